//! `urdyn eval` (eval-contract.md): every dynamics quantity of a batch of states,
//! as one JSON document.

use crate::cli::state::{StateError, StateVectors, StatesFile};
use crate::dynamics::{self, DynamicsError, Reference};
use crate::model::{Data, Model};
use crate::spatial::{Force, Motion};
use nalgebra::{DMatrix, Vector3};
use serde_json::{json, Map, Value};

/// Why an evaluation failed: names the file and the key or joint.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EvalError {
    #[error(transparent)]
    /// The states file is bad (names the file and the key).
    State(#[from] StateError),
    #[error("{file}: {message}")]
    /// The dynamics has no answer (a massless joint, a singular H, an overflow).
    Dynamics {
        /// The file to blame (the URDF or the states file).
        file: String,
        /// What went wrong, with the state's index.
        message: String,
    },
}

fn vec3(x: &nalgebra::DVector<f64>, at: usize) -> Value {
    json!([x[at], x[at + 1], x[at + 2]])
}

fn v3(x: &Vector3<f64>) -> Value {
    json!([x.x, x.y, x.z])
}

/// A matrix as a list of rows.
fn matrix(m: &DMatrix<f64>) -> Vec<Value> {
    (0..m.nrows())
        .map(|r| Value::from(m.row(r).iter().copied().collect::<Vec<f64>>()))
        .collect()
}

fn motion(m: &Motion<f64>) -> Value {
    json!({"linear": v3(&m.lin), "angular": v3(&m.ang)})
}

/// A state's kinematic outputs (eval-contract.md "Frames, external forces, centre
/// of mass, momentum and energy"), as JSON, and whether every number is finite.
struct Kinematics {
    frames: Option<Value>,
    com: Value,
    momentum: Value,
    energy: Value,
    finite: bool,
}

/// The frames a state asked for, its centre of mass, momentum and energies, all by
/// the library's kinematics (model gravity already the file's).
fn kinematics(
    model: &Model,
    data: &mut Data,
    sv: &StateVectors,
) -> Result<Kinematics, DynamicsError> {
    let mut kin = kinematics_v2(model, data, sv)?;
    // contract v3: each frame's J̇ (world-aligned), after every v2 quantity
    if let (true, Some(Value::Object(frames))) = (sv.derivatives, kin.frames.as_mut()) {
        let mut jd = DMatrix::zeros(6, model.nv);
        for &f in &sv.frames {
            dynamics::frame_jacobian_time_variation(
                model,
                data,
                &sv.q,
                &sv.v,
                f,
                Reference::WorldAligned,
                &mut jd,
            )?;
            kin.finite &= jd.iter().all(|x| x.is_finite());
            if let Some(Value::Object(o)) = frames.get_mut(&model.frames[f.0].name) {
                o.insert("jacobian_dot".into(), Value::Array(matrix(&jd)));
            }
        }
    }
    Ok(kin)
}

/// The v2 part of [`kinematics`].
fn kinematics_v2(
    model: &Model,
    data: &mut Data,
    sv: &StateVectors,
) -> Result<Kinematics, DynamicsError> {
    let mut finite = true;
    let mut fin = |xs: &[f64]| finite &= xs.iter().all(|x| x.is_finite());
    dynamics::forward_kinematics_second_order(model, data, &sv.q, &sv.v, &sv.a)?;
    let mut frames = None;
    if !sv.frames.is_empty() {
        let mut out = Map::new();
        let mut j = DMatrix::zeros(6, model.nv);
        let mut jl = DMatrix::zeros(6, model.nv);
        for &f in &sv.frames {
            dynamics::frame_jacobian(model, data, f, Reference::WorldAligned, &mut j)?;
            dynamics::frame_jacobian(model, data, f, Reference::Local, &mut jl)?;
            let vel = dynamics::frame_velocity(model, data, f, Reference::WorldAligned)?;
            let acc =
                dynamics::frame_classical_acceleration(model, data, f, Reference::WorldAligned)?;
            fin(j.as_slice());
            fin(jl.as_slice());
            fin(vel.to_vector().as_slice());
            fin(acc.to_vector().as_slice());
            out.insert(
                model.frames[f.0].name.clone(),
                json!({"jacobian": matrix(&j), "jacobian_local": matrix(&jl),
                       "velocity": motion(&vel), "acceleration": motion(&acc)}),
            );
        }
        frames = Some(Value::Object(out));
    }
    let c = dynamics::center_of_mass(model, data);
    let cd = dynamics::center_of_mass_velocity(model, data);
    let mut jc = DMatrix::zeros(3, model.nv);
    dynamics::center_of_mass_jacobian(model, data, &mut jc)?;
    let pe = dynamics::potential_energy(model, data);
    let ke = dynamics::kinetic_energy(model, data, &sv.q, &sv.v)?;
    let (k_g, l) = dynamics::centroidal_momentum(model, data, &sv.q, &sv.v)?;
    for x in [&c, &cd, &k_g, &l] {
        fin(x.as_slice());
    }
    fin(jc.as_slice());
    fin(&[ke, pe]);
    Ok(Kinematics {
        frames,
        com: json!({"position": v3(&c), "velocity": v3(&cd), "jacobian": matrix(&jc)}),
        momentum: json!({"linear": v3(&l), "angular": v3(&k_g)}),
        energy: json!({"kinetic": ke, "potential": pe}),
        finite,
    })
}

/// A state's derivatives (eval-contract.md §"Derivatives (version 3)") as JSON, and
/// whether every number is finite.
fn derivatives(
    model: &Model,
    data: &mut Data,
    sv: &StateVectors,
) -> Result<(Value, bool), DynamicsError> {
    let wrenches: Vec<dynamics::LinkWrench> = sv
        .fext
        .iter()
        .map(|&(frame, force, torque)| dynamics::LinkWrench {
            frame,
            force,
            torque,
        })
        .collect();
    let w = (!wrenches.is_empty()).then_some(wrenches.as_slice());
    dynamics::rnea_derivatives(model, data, &sv.q, &sv.v, &sv.a, w)?;
    let (dq, dv) = (data.dtau_dq.clone(), data.dtau_dv.clone());
    dynamics::aba_derivatives(model, data, &sv.q, &sv.v, &sv.tau, w)?;
    let mats = [&dq, &dv, &data.dqdd_dq, &data.dqdd_dv, &data.minv];
    let finite = mats.iter().all(|m| m.iter().all(|x| x.is_finite()));
    let out = json!({
        "dtau_dq": matrix(&dq), "dtau_dv": matrix(&dv),
        "dqdd_dq": matrix(&data.dqdd_dq), "dqdd_dv": matrix(&data.dqdd_dv),
        "dqdd_dtau": matrix(&data.minv),
    });
    Ok((out, finite))
}

/// The most degrees of freedom `eval` answers: its output holds the dense nv×nv
/// mass matrix of every state (2048² numbers is about 90 MB of JSON a state).
pub const MAX_EVAL_DOF: usize = 2048;

/// Evaluates every state of `states` on `model` (whose gravity is replaced by the
/// file's). `urdf_file` and `states_file` name the inputs in errors.
pub fn evaluate(
    model: &Model,
    states: &StatesFile,
    urdf_file: &str,
    states_file: &str,
) -> Result<Value, EvalError> {
    let mut results = Vec::with_capacity(states.states.len());
    let names = evaluate_each(model, states, urdf_file, states_file, |r| {
        results.push(r);
    })?;
    Ok(
        json!({"dof_names": names, "q_names": model.q_names(), "v_names": model.v_names(),
        "results": results}),
    )
}

/// As [`evaluate`], serialised to the JSON text of the contract (one line, no
/// trailing newline). Each state's result is serialised as soon as it is computed,
/// so memory holds text, not a tree of JSON values.
pub fn evaluate_json(
    model: &Model,
    states: &StatesFile,
    urdf_file: &str,
    states_file: &str,
) -> Result<String, EvalError> {
    let mut body = String::new();
    let names = evaluate_each(model, states, urdf_file, states_file, |r| {
        if !body.is_empty() {
            body.push(',');
        }
        body.push_str(&r.to_string());
    })?;
    // Key order as serde_json writes the object of `evaluate` (sorted).
    Ok(format!(
        "{{\"dof_names\":{},\"q_names\":{},\"results\":[{body}],\"v_names\":{}}}",
        Value::from(names),
        Value::from(model.q_names()),
        Value::from(model.v_names())
    ))
}

/// Computes each state's result object and hands it to `sink`; returns the DoF names.
fn evaluate_each(
    model: &Model,
    states: &StatesFile,
    urdf_file: &str,
    states_file: &str,
    mut sink: impl FnMut(Value),
) -> Result<Vec<String>, EvalError> {
    if model.nv > MAX_EVAL_DOF {
        return Err(EvalError::Dynamics {
            file: urdf_file.to_string(),
            message: format!(
                "the robot has {} velocity degrees of freedom; eval writes the dense mass matrix and answers at most {MAX_EVAL_DOF}",
                model.nv
            ),
        });
    }
    let mut model = model.clone();
    if let Some(g) = states.gravity {
        model.gravity = nalgebra::Vector3::from(g);
    }
    if let Err(e) = dynamics::check_massless(&model) {
        return Err(EvalError::Dynamics {
            file: urdf_file.to_string(),
            message: e.to_string(),
        });
    }
    // Every state is checked before any dynamics is computed.
    let mut vectors = Vec::with_capacity(states.states.len());
    for (i, state) in states.states.iter().enumerate() {
        vectors.push(state.to_vectors(&model, states_file, &format!("states[{i}]"))?);
    }
    let constraints = crate::cli::eval_constrained::parse(&model, states.constraints.as_ref(), states_file)?;
    let mut data = Data::new(&model);
    let names = model.dof_names();
    let mut fext = vec![Force::zero(); model.nbodies];
    for (i, sv) in vectors.iter().enumerate() {
        let key = format!("states[{i}]");
        let dyn_err = |e: DynamicsError| EvalError::Dynamics {
            file: states_file.to_string(),
            message: format!("{key}: {e}"),
        };
        // the external wrenches, by link, onto their bodies at this q
        dynamics::forward_kinematics(&model, &mut data, &sv.q).map_err(dyn_err)?;
        fext.fill(Force::zero());
        for (link, f, t) in &sv.fext {
            dynamics::add_link_wrench(&model, &data, *link, f, t, &mut fext).map_err(dyn_err)?;
        }
        let fx = (!sv.fext.is_empty()).then_some(fext.as_slice());
        let tau = dynamics::rnea(&model, &mut data, &sv.q, &sv.v, &sv.a, fx)
            .map_err(dyn_err)?
            .clone();
        let bias = dynamics::bias(&model, &mut data, &sv.q, &sv.v, fx)
            .map_err(dyn_err)?
            .clone();
        let h = dynamics::mass_matrix(&model, &mut data, &sv.q)
            .map_err(dyn_err)?
            .clone();
        // The contract's singularity test is on H itself (a pivot at most 64 ε of its
        // diagonal), whichever algorithm the engine's fd then uses.
        if let Err(k) = dynamics::linalg::cholesky(&h, &mut data.chol) {
            return Err(dyn_err(DynamicsError::Singular(k)));
        }
        let qdd = dynamics::forward_dynamics(&model, &mut data, &sv.q, &sv.v, &sv.tau, fx)
            .map_err(dyn_err)?
            .clone();
        let kin = kinematics(&model, &mut data, sv).map_err(dyn_err)?;
        let constrained = match &constraints {
            Some(c) => Some(
                crate::cli::eval_constrained::block(&model, &mut data, c, sv, fx).map_err(|m| {
                    EvalError::Dynamics {
                        file: states_file.to_string(),
                        message: format!("{key}: {m}"),
                    }
                })?,
            ),
            None => None,
        };
        let deriv = if sv.derivatives {
            Some(derivatives(&model, &mut data, sv).map_err(dyn_err)?)
        } else {
            None
        };
        // Finite inputs can still overflow (a mass of 1e300, a speed of 1e200):
        // an answer with infinities or NaN (JSON null) is an error, not output.
        let finite = |x: &nalgebra::DVector<f64>| x.iter().all(|v| v.is_finite());
        for (what, ok) in [
            ("tau", finite(&tau)),
            ("bias", finite(&bias)),
            ("qdd", finite(&qdd)),
            ("mass_matrix", h.iter().all(|v| v.is_finite())),
            ("a frame, centre of mass, momentum or energy", kin.finite),
            ("a derivative", deriv.as_ref().is_none_or(|d| d.1)),
            ("the constrained block", constrained.as_ref().is_none_or(|c| c.1)),
        ] {
            if !ok {
                return Err(EvalError::Dynamics {
                    file: states_file.to_string(),
                    message: format!("{key}: {what} is not finite (the numbers overflow)"),
                });
            }
        }
        dynamics::forward_kinematics(&model, &mut data, &sv.q).map_err(dyn_err)?;
        dynamics::update_frames(&model, &mut data);
        if let Some(f) = data.o_m_f.iter().position(|m| {
            !(m.rot.iter().all(|x| x.is_finite()) && m.trans.iter().all(|x| x.is_finite()))
        }) {
            return Err(EvalError::Dynamics {
                file: states_file.to_string(),
                message: format!(
                    "{key}: the pose of link \"{}\" is not finite (the numbers overflow)",
                    model.frames.get(f).map_or("?", |fr| fr.name.as_str())
                ),
            });
        }

        // a joint of several degrees of freedom gives an array (mechanisms.md)
        let by_name = |x: &nalgebra::DVector<f64>| -> Value {
            let mut m = Map::new();
            for d in &model.dofs {
                let n = d.kind.nv();
                let val = if n == 1 {
                    json!(x[d.iv])
                } else {
                    json!(x.as_slice()[d.iv..d.iv + n])
                };
                m.insert(d.name.clone(), val);
            }
            Value::Object(m)
        };
        let rows = matrix(&h);
        let mut poses = Map::new();
        for (k, f) in model.frames.iter().enumerate() {
            let m = &data.o_m_f[k];
            let rot: Vec<Value> = (0..3)
                .map(|r| json!([m.rot[(r, 0)], m.rot[(r, 1)], m.rot[(r, 2)]]))
                .collect();
            poses.insert(
                f.name.clone(),
                json!({"position": [m.trans.x, m.trans.y, m.trans.z], "rotation": rot}),
            );
        }
        let mut r = Map::new();
        r.insert("tau".into(), by_name(&tau));
        r.insert("qdd".into(), by_name(&qdd));
        r.insert("bias".into(), by_name(&bias));
        r.insert("mass_matrix".into(), Value::Array(rows));
        r.insert("link_poses".into(), Value::Object(poses));
        if let Some(frames) = kin.frames {
            r.insert("frames".into(), frames);
        }
        if let Some((d, _)) = deriv {
            r.insert("derivatives".into(), d);
        }
        if let Some((c, _)) = constrained {
            r.insert("constrained".into(), c);
        }
        r.insert("com".into(), kin.com);
        r.insert("momentum".into(), kin.momentum);
        r.insert("energy".into(), kin.energy);
        if model.floating_base {
            r.insert(
                "base".into(),
                json!({
                    "force": vec3(&tau, 0), "torque": vec3(&tau, 3),
                    "bias_force": vec3(&bias, 0), "bias_torque": vec3(&bias, 3),
                    "linear_acceleration": vec3(&qdd, 0), "angular_acceleration": vec3(&qdd, 3),
                }),
            );
        }
        sink(Value::Object(r));
    }
    Ok(names.iter().map(|n| n.to_string()).collect())
}
