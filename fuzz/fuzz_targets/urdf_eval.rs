//! URDF text → Model → `inspect` report → `eval` of a random state.
//! The first 8 bytes seed the state and pick fixed or floating base; the rest is
//! the URDF. Any panic is a crash; errors are fine.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::collections::BTreeMap;
use urdyn::cli::state::{BaseState, JointValue, State, StatesFile};

fn next(s: &mut u64) -> f64 {
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    // Mostly moderate numbers, sometimes large ones.
    let u = (*s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0;
    if *s % 16 == 0 {
        u * 1e6
    } else {
        u * 3.0
    }
}

fuzz_target!(|data: &[u8]| {
    if data.len() < 8 {
        return;
    }
    let mut seed = u64::from_le_bytes(data[..8].try_into().unwrap()) | 1;
    let floating_base = seed & 2 != 0;
    let text = String::from_utf8_lossy(&data[8..]);
    let Ok(model) = urdyn::load_str(&text, "fuzz.urdf", urdyn::LoadOptions { floating_base })
    else {
        return;
    };
    let _ = urdyn::cli::inspect::report(&model, &[]);
    if model.nv > 64 {
        return;
    }
    let mut maps: Vec<BTreeMap<String, JointValue>> = vec![BTreeMap::new(); 4];
    for name in model.dof_names() {
        for m in maps.iter_mut() {
            m.insert(name.to_string(), JointValue::Scalar(next(&mut seed)));
        }
    }
    let mut quat = [next(&mut seed), next(&mut seed), next(&mut seed), next(&mut seed)];
    let n = quat.iter().map(|x| x * x).sum::<f64>().sqrt();
    if n > 0.0 {
        quat.iter_mut().for_each(|x| *x /= n);
    }
    let mut v3 = || Some([next(&mut seed), next(&mut seed), next(&mut seed)]);
    let base = BaseState {
        position: v3(),
        orientation_xyzw: Some(quat),
        linear_velocity: v3(),
        angular_velocity: v3(),
        linear_acceleration: v3(),
        angular_acceleration: v3(),
        force: v3(),
        torque: v3(),
    };
    let states = StatesFile {
        gravity: Some([0.0, 0.0, -9.81]),
        states: vec![State {
            tau: maps.pop(),
            a: maps.pop(),
            v: maps.pop(),
            q: maps.pop(),
            base: Some(base),
            ..State::default()
        }],
        constraints: None,
    };
    let _ = urdyn::cli::eval::evaluate_json(&model, &states, "fuzz.urdf", "fuzz.json");
});
