// src/lib.rs's first example verbatim, inside `main` (tests/doc_examples.rs checks
// that it is): edit both.
pub fn main() -> Result<(), Box<dyn std::error::Error>> {
    use urdyn::nalgebra::DVector;
    use urdyn::{dynamics, Data, LoadOptions};

    let model = urdyn::load_file("assets/robots/ur5.urdf", LoadOptions::default())?;
    let mut data = Data::new(&model); // preallocated workspace, reused by every call
    let q = DVector::from_fn(model.nq, |k, _| 0.2 * k as f64); // rad
    let v = DVector::from_element(model.nv, 0.5); // rad/s
    let a = DVector::from_fn(model.nv, |k, _| 1.0 - 0.3 * k as f64); // rad/s²
    let tau = dynamics::rnea(&model, &mut data, &q, &v, &a, None)?.clone(); // a wrong-length vector is an Err
    let qdd = dynamics::forward_dynamics(&model, &mut data, &q, &v, &tau, None)?;
    assert!((qdd - &a).amax() < 1e-9); // the round trip gives a back
    Ok(())
}
