//! `eval`'s loop constraints (mechanisms.md §"In `eval` (version 4)"): the
//! top-level `"constraints"` list and each result's `"constrained"` block.

use crate::cli::state::{StateError, StateVectors};
use crate::dynamics::{self, ConstraintData, LinkWrench};
use crate::model::{ConstraintKind, Constraints, Data, Model};
use crate::spatial::Force;
use nalgebra::{DMatrix, DVector};
use serde_json::{json, Map, Value};

/// The model's own active constraints (MJCF `<equality>`, mjcf.md §"In
/// `eval`") followed by the file's, checked against the model (`None` when
/// there are none).
pub fn parse(
    model: &Model,
    constraints: Option<&Value>,
    file: &str,
) -> Result<Option<Constraints>, StateError> {
    let own: Vec<_> = model
        .equalities
        .items
        .iter()
        .zip(model.equality_active.iter().chain(std::iter::repeat(&true)))
        .filter(|(_, on)| **on)
        .map(|(c, _)| c.clone())
        .collect();
    let Some(v) = constraints else {
        return Ok((!own.is_empty()).then_some(Constraints { items: own }));
    };
    let mut set = Constraints::from_value(model, v).map_err(|e| StateError {
        file: file.to_string(),
        key: if e.key.is_empty() {
            "constraints".into()
        } else {
            format!("constraints[{}].{}", e.index, e.key)
        },
        message: e.message,
    })?;
    if let Some((k, c)) = set
        .items
        .iter()
        .enumerate()
        .find(|(_, c)| own.iter().any(|o| o.name == c.name))
    {
        return Err(StateError {
            file: file.to_string(),
            key: format!("constraints[{k}].name"),
            message: format!(
                "\"{}\" is the name of one of the model's equalities",
                c.name
            ),
        });
    }
    let mut items = own;
    items.append(&mut set.items);
    Ok(Some(Constraints { items }))
}

fn rows(m: &DMatrix<f64>) -> Value {
    Value::Array(
        (0..m.nrows())
            .map(|r| Value::from((0..m.ncols()).map(|c| m[(r, c)]).collect::<Vec<_>>()))
            .collect(),
    )
}

/// A state's `"constrained"` block and whether every number is finite; the
/// error is the message (the caller names the state).
pub fn block(
    model: &Model,
    data: &mut Data,
    constraints: &Constraints,
    sv: &StateVectors,
    fext: Option<&[Force<f64>]>,
) -> Result<(Value, bool), String> {
    let mut c = constraints.clone();
    if c.has_holds() {
        dynamics::forward_kinematics(model, data, &sv.q).map_err(|e| e.to_string())?;
        c.place_holds(data);
    }
    let mut cd = ConstraintData::new(model, &c);
    dynamics::constraint_dynamics(model, data, &mut cd, &c, &sv.q, &sv.v, &sv.tau, fext)
        .map_err(|e| e.to_string())?;
    let mut viol = vec![0.0; c.items.len()];
    dynamics::constraint_violation(model, data, &c, &sv.q, &mut viol).map_err(|e| e.to_string())?;
    let by_name = |x: &DVector<f64>| super::eval::joint_values(model, x);
    let mut forces = Map::new();
    let mut violation = Map::new();
    let mut row = 0;
    for (con, e) in c.items.iter().zip(&viol) {
        let l = |i: usize| cd.lambda[row + i];
        let f = match con.kind {
            ConstraintKind::Point => json!({"force": [l(0), l(1), l(2)]}),
            ConstraintKind::Frame => {
                json!({"force": [l(0), l(1), l(2)], "torque": [l(3), l(4), l(5)]})
            }
            ConstraintKind::Joint { prismatic, .. } => {
                if prismatic {
                    json!({"force": l(0)})
                } else {
                    json!({"torque": l(0)})
                }
            }
        };
        forces.insert(con.name.clone(), f);
        violation.insert(con.name.clone(), json!(e));
        row += con.rows();
    }
    let mut out = Map::new();
    out.insert("qdd".into(), by_name(&cd.qdd));
    out.insert("generalized_force".into(), by_name(&cd.generalized_force));
    out.insert("constraint_forces".into(), Value::Object(forces));
    out.insert("violation".into(), Value::Object(violation));
    if model.floating_base {
        let (a, g) = (&cd.qdd, &cd.generalized_force);
        out.insert(
            "base".into(),
            json!({
                "linear_acceleration": [a[0], a[1], a[2]],
                "angular_acceleration": [a[3], a[4], a[5]],
                "force": [g[0], g[1], g[2]], "torque": [g[3], g[4], g[5]],
            }),
        );
    }
    let mut finite = [&cd.qdd, &cd.generalized_force, &cd.lambda]
        .iter()
        .all(|x| x.iter().all(|v| v.is_finite()));
    if sv.derivatives {
        let w: Vec<LinkWrench> = sv
            .fext
            .iter()
            .map(|&(frame, force, torque)| LinkWrench {
                frame,
                force,
                torque,
            })
            .collect();
        let w = (!w.is_empty()).then_some(w.as_slice());
        dynamics::constraint_dynamics_derivatives(
            model, data, &mut cd, &c, &sv.q, &sv.v, &sv.tau, w,
        )
        .map_err(|e| e.to_string())?;
        let mats = [&cd.dqdd_dq, &cd.dqdd_dv, &cd.dqdd_dtau];
        finite &= mats.iter().all(|m| m.iter().all(|x| x.is_finite()));
        out.insert("dqdd_dq".into(), rows(&cd.dqdd_dq));
        out.insert("dqdd_dv".into(), rows(&cd.dqdd_dv));
        out.insert("dqdd_dtau".into(), rows(&cd.dqdd_dtau));
    }
    Ok((Value::Object(out), finite))
}
