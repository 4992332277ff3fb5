use super::linalg::{cholesky, cholesky_solve};
use super::rnea::rnea_impl;
use super::DynamicsError;
use crate::model::{Data, Model};
use crate::spatial::{Force, Scalar};
use nalgebra::DVector;

/// H(q) column by column from n inverse-dynamics calls (docs/theory.md
/// §"Forward dynamics by inverse dynamics"), written to `data.h`. Each column is
/// ID(q, 0, δᵢ) with gravity off: the same n calls as the course note's
/// `ID(q, q̇, δᵢ) − C`, without its cancellation when C is large.
pub fn mass_matrix_rnea<T: Scalar>(
    model: &Model<T>,
    data: &mut Data<T>,
    q: &DVector<T>,
) -> Result<(), DynamicsError> {
    super::check_sizes(model, q, &[], None)?;
    let nv = model.nv;
    let mut delta = std::mem::replace(&mut data.tmp_a, DVector::zeros(0));
    delta.as_mut_slice().fill(T::zero());
    for i in 0..nv {
        delta[i] = T::one();
        rnea_impl(model, data, q, None, Some(&delta), false, None);
        delta[i] = T::zero();
        data.h.set_column(i, &data.tau);
    }
    data.tmp_a = delta;
    Ok(())
}

/// The course note's forward dynamics (docs/theory.md §"Forward dynamics by inverse dynamics"),
/// kept as the reference method: C from one inverse-dynamics call, H from n more,
/// then a Cholesky solve of `H q̈ = Q − C`. The result is written to
/// `data.qdd` (also `data.bias`, `data.h`).
pub fn forward_dynamics_rnea<'d, T: Scalar>(
    model: &Model<T>,
    data: &'d mut Data<T>,
    q: &DVector<T>,
    v: &DVector<T>,
    tau: &DVector<T>,
    fext: Option<&[Force<T>]>,
) -> Result<&'d DVector<T>, DynamicsError> {
    super::check_sizes(model, q, &[("v", v), ("tau", tau)], fext)?;
    super::check_massless(model)?;
    rnea_impl(model, data, q, Some(v), None, true, fext);
    data.bias.copy_from(&data.tau);
    mass_matrix_rnea(model, data, q)?;
    cholesky(&data.h, &mut data.chol).map_err(DynamicsError::Singular)?;
    data.qdd.copy_from(tau);
    data.qdd -= &data.bias;
    cholesky_solve(&data.chol, &mut data.qdd);
    Ok(&data.qdd)
}
