//! Profiling driver: `cargo run --release --features tools --example profile -- ROBOT.urdf [--floating-base] ALGO N`
//! calls one algorithm N times on a fixed pool of random states (for callgrind,
//! whose instruction counts are stable on a shared, noisy machine).
use std::hint::black_box;
use urdyn::cli::bench::random_states;
use urdyn::{dynamics_f64 as dynamics, Data, LoadOptions};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let floating_base = args.iter().any(|a| a == "--floating-base");
    let rest: Vec<&String> = args.iter().filter(|a| !a.starts_with("--")).collect();
    let (Some(file), Some(algo), Some(n)) = (rest.first(), rest.get(1), rest.get(2)) else {
        eprintln!("usage: profile ROBOT.urdf [--floating-base] ALGO N");
        std::process::exit(2);
    };
    let n: usize = n.parse().unwrap_or(1000);
    let model = match urdyn::load_file(file.as_str(), LoadOptions { floating_base }) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(1);
        }
    };
    let mut data = Data::new(&model);
    let states = random_states(&model, 16, 7);
    for k in 0..n {
        let s = &states[k % states.len()];
        match algo.as_str() {
            "rnea" => {
                black_box(dynamics::rnea(&model, &mut data, &s.q, &s.v, &s.a, None).ok());
            }
            "crba" => {
                black_box(dynamics::crba(&model, &mut data, &s.q).ok());
            }
            "aba" => {
                black_box(dynamics::aba(&model, &mut data, &s.q, &s.v, &s.tau, None).ok());
            }
            "fd" => {
                black_box(
                    dynamics::forward_dynamics(&model, &mut data, &s.q, &s.v, &s.tau, None).ok(),
                );
            }
            "fdcrba" => {
                black_box(
                    dynamics::forward_dynamics_crba(&model, &mut data, &s.q, &s.v, &s.tau, None)
                        .ok(),
                );
            }
            "fk" => {
                black_box(dynamics::forward_kinematics(&model, &mut data, &s.q).is_ok());
                dynamics::update_frames(&model, &mut data);
                black_box(&data.o_m_f);
            }
            _ => {
                eprintln!("unknown algo");
                std::process::exit(2);
            }
        }
    }
}
