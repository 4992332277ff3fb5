// The README's example verbatim (tests/doc_examples.rs checks that it is): edit both.
use urdyn::dynamics::{self, Reference};
use urdyn::model::configuration::{difference, integrate, random_configuration};
use urdyn::nalgebra::{DMatrix, DVector, Vector3};
use urdyn::spatial::Force;
use urdyn::{Data, LoadOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let model = urdyn::load_file("assets/robots/solo12.urdf", LoadOptions { floating_base: true })?;
    let mut data = Data::new(&model);
    let q = random_configuration(&model, 7); // inside the joint limits
    let v = difference(&model, &model.neutral(), &q)?; // q = neutral ⊕ v
    let back = integrate(&model, &model.neutral(), &v)?; // q up to the quaternion's sign
    assert!(difference(&model, &q, &back)?.amax() < 1e-12);
    let a = DVector::zeros(model.nv);
    let foot = model.frame_id("FL_FOOT")?; // a link welded by a fixed joint
    let knee = model.joint_id("FL_KFE")?;
    let _knee_v = model.joint_v_range(knee)?; // its columns in v, H and J
    dynamics::forward_kinematics_second_order(&model, &mut data, &q, &v, &a)?;
    let mut j = DMatrix::zeros(6, model.nv);
    dynamics::frame_jacobian(&model, &data, foot, Reference::WorldAligned, &mut j)?;
    let vel = dynamics::frame_velocity(&model, &data, foot, Reference::WorldAligned)?;
    assert!(((&j * &v).rows(0, 3) - vel.lin).amax() < 1e-12);
    let mut jc = DMatrix::zeros(3, model.nv);
    dynamics::center_of_mass_jacobian(&model, &data, &mut jc)?;
    let com = dynamics::center_of_mass(&model, &data);
    // push the foot up with 10 N: the wrench on its body, then inverse dynamics
    let mut fext = vec![Force::zero(); model.nbodies];
    dynamics::add_link_wrench(&model, &data, foot, &Vector3::new(0.0, 0.0, 10.0), &Vector3::zeros(), &mut fext)?;
    let tau = dynamics::rnea(&model, &mut data, &q, &v, &a, Some(&fext))?;
    println!("com {com:?}, base force {:?}", tau.rows(0, 3));
    Ok(())
}
