//! Zero heap allocation per call in the hot path, proven with a counting global
//! allocator (`common/counting_alloc.rs`: per thread, so that the other tests of the
//! binary may allocate while a count is taken).

use std::path::PathBuf;
use urdyn::cli::bench::random_states;
use urdyn::dynamics;
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
    ] {
        let model = urdyn::load_file(root.join(file), LoadOptions { floating_base }).unwrap();
        let mut data = Data::new(&model);
        let states = random_states(&model, 2, 1);
        let fext = vec![urdyn::spatial::Force::zero(); model.nbodies];
        for s in &states {
            let (q, v, a, tau) = (&s.q, &s.v, &s.a, &s.tau);
            let checks: [(&str, usize); 12] = [
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
            ];
            for (name, n) in checks {
                assert_eq!(n, 0, "{file}: {name} allocated {n} times");
            }
        }
        eprintln!("{file}: 0 allocations in rnea, bias, crba, ltdl, aba, fd, fd-crba, fd-rnea, fk");
    }
}
