//! STATES.json text → parse → to_vectors → eval, on the corpus's mimic robot with
//! a fixed and a floating base. Any panic is a crash; errors are fine.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::sync::OnceLock;

const URDF: &str = include_str!("../../tests/bad/ok.urdf");

fn models() -> &'static [urdyn::Model; 2] {
    static M: OnceLock<[urdyn::Model; 2]> = OnceLock::new();
    M.get_or_init(|| {
        let load = |floating_base| {
            urdyn::load_str(URDF, "ok.urdf", urdyn::LoadOptions { floating_base })
                .expect("the fuzz model loads")
        };
        [load(false), load(true)]
    })
}

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let _ = urdyn::cli::state::parse_state(text, "state.json");
    let Ok(states) = urdyn::cli::state::parse_states(text, "states.json") else {
        return;
    };
    for model in models() {
        for (i, s) in states.states.iter().enumerate() {
            let _ = s.to_vectors(model, "states.json", &format!("states[{i}]"));
        }
        let _ = urdyn::cli::eval::evaluate_json(model, &states, "ok.urdf", "states.json");
    }
});
