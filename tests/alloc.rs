//! Zero heap allocation per call in the hot path, proven with a counting global
//! allocator (`common/counting_alloc.rs`: per thread, so that the other tests of the
//! binary may allocate while a count is taken).

use std::path::PathBuf;
use urdyn::cli::bench::random_states;
use urdyn::dynamics_f64 as dynamics;
use urdyn::{Data, LoadOptions};

use crate::common::counting_alloc::{allocations, measure_this_thread};

fn count(f: impl FnOnce()) -> usize {
    let before = allocations();
    f();
    allocations() - before
}

#[test]
fn hot_path_does_not_allocate() {
    measure_this_thread();
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    for (file, floating_base) in [
        ("assets/robots/ur5.urdf", false),
        ("assets/robots/solo12.urdf", true),
        ("assets/robots/panda.urdf", false),
        ("assets/synthetic/tree_5.urdf", false),
        // a long chain: aba_derivatives' low-rank products
        ("assets/synthetic/chain_100.urdf", false),
    ] {
        let model = urdyn::load_file(root.join(file), LoadOptions { floating_base }).unwrap();
        let mut data = Data::new(&model);
        let states = random_states(&model, 2, 1);
        let fext = vec![urdyn::spatial::Force::zero(); model.nbodies];
        for s in &states {
            let (q, v, a, tau) = (&s.q, &s.v, &s.a, &s.tau);
            let wrenches = [dynamics::LinkWrench {
                frame: urdyn::model::FrameId(model.frames.len() - 1),
                force: nalgebra::Vector3::new(1.0, -2.0, 0.5),
                torque: nalgebra::Vector3::new(0.1, 0.2, -0.3),
            }];
            let mut jd = nalgebra::DMatrix::zeros(6, model.nv);
            let checks: [(&str, usize); 18] = [
                (
                    "rnea",
                    count(|| {
                        dynamics::rnea(&model, &mut data, q, v, a, None).unwrap();
                    }),
                ),
                (
                    "rnea+fext",
                    count(|| {
                        dynamics::rnea(&model, &mut data, q, v, a, Some(&fext)).unwrap();
                    }),
                ),
                (
                    "bias",
                    count(|| {
                        dynamics::bias(&model, &mut data, q, v, None).unwrap();
                    }),
                ),
                (
                    "crba",
                    count(|| {
                        dynamics::crba(&model, &mut data, q).unwrap();
                    }),
                ),
                (
                    "mass_matrix",
                    count(|| {
                        dynamics::mass_matrix(&model, &mut data, q).unwrap();
                    }),
                ),
                (
                    "ltdl+solve",
                    count(|| {
                        if !model.has_mimic {
                            let (h, u, x) = (&data.h, &mut data.chol, &mut data.qdd);
                            dynamics::ltdl::ltdl(h, &model.dof_parent, u).unwrap();
                            dynamics::ltdl::ltdl_solve(u, &model.dof_parent, x);
                        }
                    }),
                ),
                (
                    "aba",
                    count(|| {
                        let r = dynamics::aba(&model, &mut data, q, v, tau, None);
                        assert_eq!(r.is_ok(), !model.has_mimic);
                    }),
                ),
                (
                    "aba+fext",
                    count(|| {
                        if !model.has_mimic {
                            dynamics::aba(&model, &mut data, q, v, tau, Some(&fext)).unwrap();
                        }
                    }),
                ),
                (
                    "fd",
                    count(|| {
                        dynamics::forward_dynamics(&model, &mut data, q, v, tau, None).unwrap();
                    }),
                ),
                (
                    "fd-crba",
                    count(|| {
                        dynamics::forward_dynamics_crba(&model, &mut data, q, v, tau, None)
                            .unwrap();
                    }),
                ),
                (
                    "fd-rnea",
                    count(|| {
                        dynamics::forward_dynamics_rnea(&model, &mut data, q, v, tau, None)
                            .unwrap();
                    }),
                ),
                (
                    "fk",
                    count(|| {
                        dynamics::forward_kinematics(&model, &mut data, q).unwrap();
                        dynamics::update_frames(&model, &mut data);
                    }),
                ),
                (
                    "rnea_derivatives",
                    count(|| {
                        dynamics::rnea_derivatives(&model, &mut data, q, v, a, None).unwrap();
                    }),
                ),
                (
                    "rnea_derivatives+fext",
                    count(|| {
                        dynamics::rnea_derivatives(&model, &mut data, q, v, a, Some(&wrenches))
                            .unwrap();
                    }),
                ),
                (
                    "aba_derivatives",
                    count(|| {
                        dynamics::aba_derivatives(&model, &mut data, q, v, tau, None).unwrap();
                    }),
                ),
                (
                    "aba_derivatives+fext",
                    count(|| {
                        dynamics::aba_derivatives(&model, &mut data, q, v, tau, Some(&wrenches))
                            .unwrap();
                    }),
                ),
                (
                    "frame_jacobian_time_variation",
                    count(|| {
                        let f = urdyn::model::FrameId(model.frames.len() - 1);
                        let r = dynamics::Reference::Local;
                        dynamics::frame_jacobian_time_variation(
                            &model, &mut data, q, v, f, r, &mut jd,
                        )
                        .unwrap();
                    }),
                ),
                (
                    "joint_jacobians",
                    count(|| {
                        dynamics::joint_jacobians(&model, &mut data, q).unwrap();
                    }),
                ),
            ];
            for (name, n) in checks {
                assert_eq!(n, 0, "{file}: {name} allocated {n} times");
            }
        }
        eprintln!("{file}: 0 allocations in rnea, bias, crba, ltdl, aba, fd, fd-crba, fd-rnea, fk, the derivatives, joint Jacobians");
    }
}
