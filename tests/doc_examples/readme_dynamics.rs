// The README's example verbatim (tests/doc_examples.rs checks that it is): edit both.
use urdyn::nalgebra::DVector; // urdyn re-exports the nalgebra it is built with
use urdyn::{dynamics, Data, LoadOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let model = urdyn::load_file("assets/robots/ur5.urdf", LoadOptions::default())?;
    let mut data = Data::new(&model); // preallocated workspace
    let q = model.neutral();
    let v = DVector::zeros(model.nv);
    let a = DVector::zeros(model.nv);
    let tau = dynamics::rnea(&model, &mut data, &q, &v, &a, None)?.clone(); // gravity torques
    let qdd = dynamics::forward_dynamics(&model, &mut data, &q, &v, &tau, None)?;
    assert!(qdd.amax() < 1e-9); // holding the gravity torques: no acceleration
    dynamics::forward_kinematics(&model, &mut data, &q)?; // a wrong-length q is an error
    dynamics::update_frames(&model, &mut data); // data.o_m_f[k]: world pose of model.frames[k]
    Ok(())
}
