//! Criterion benches of every algorithm on ur5, solo12 (floating), panda (mimic) and
//! the synthetic chains/tree: `cargo bench --features bench --bench dynamics [-- FILTER]`.
//! (`urdyn bench` and benches/compare.sh give the Pinocchio comparison.)
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use std::hint::black_box;
use std::path::PathBuf;
use urdyn::cli::bench::random_states;
use urdyn::{dynamics, Data, LoadOptions};

fn robots() -> Vec<(&'static str, &'static str, bool)> {
    vec![
        ("ur5", "assets/robots/ur5.urdf", false),
        ("solo12", "assets/robots/solo12.urdf", true),
        ("panda", "assets/robots/panda.urdf", false),
        ("chain_20", "assets/synthetic/chain_20.urdf", false),
        ("chain_100", "assets/synthetic/chain_100.urdf", false),
        ("tree_6", "assets/synthetic/tree_6.urdf", false),
    ]
}

fn bench(c: &mut Criterion) {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    for (name, file, floating_base) in robots() {
        let Ok(model) = urdyn::load_file(root.join(file), LoadOptions { floating_base }) else {
            continue;
        };
        let mut data = Data::new(&model);
        let states = random_states(&model, 16, 3);
        let mut g = c.benchmark_group(name);
        let mut k = 0usize;
        let mut next = || {
            k = (k + 1) % states.len();
            &states[k]
        };
        g.bench_function(BenchmarkId::from_parameter("rnea"), |b| {
            b.iter(|| {
                let s = next();
                black_box(dynamics::rnea(&model, &mut data, &s.q, &s.v, &s.a, None).map(|x| x[0]))
            })
        });
        g.bench_function(BenchmarkId::from_parameter("crba"), |b| {
            b.iter(|| black_box(dynamics::crba(&model, &mut data, &next().q).map(|h| h[(0, 0)])))
        });
        if !model.has_mimic {
            g.bench_function(BenchmarkId::from_parameter("aba"), |b| {
                b.iter(|| {
                    let s = next();
                    black_box(
                        dynamics::aba(&model, &mut data, &s.q, &s.v, &s.tau, None).map(|x| x[0]),
                    )
                })
            });
        }
        g.bench_function(BenchmarkId::from_parameter("fd-crba"), |b| {
            b.iter(|| {
                let s = next();
                black_box(
                    dynamics::forward_dynamics_crba(&model, &mut data, &s.q, &s.v, &s.tau, None)
                        .map(|x| x[0]),
                )
            })
        });
        g.bench_function(BenchmarkId::from_parameter("fd"), |b| {
            b.iter(|| {
                let s = next();
                black_box(
                    dynamics::forward_dynamics(&model, &mut data, &s.q, &s.v, &s.tau, None)
                        .map(|x| x[0]),
                )
            })
        });
        g.bench_function(BenchmarkId::from_parameter("fk"), |b| {
            b.iter(|| {
                black_box(dynamics::forward_kinematics(&model, &mut data, &next().q).is_ok());
                dynamics::update_frames(&model, &mut data);
                black_box(data.o_m_f.len())
            })
        });
        g.finish();
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).warm_up_time(std::time::Duration::from_millis(200)).measurement_time(std::time::Duration::from_millis(600));
    targets = bench
}
criterion_main!(benches);
