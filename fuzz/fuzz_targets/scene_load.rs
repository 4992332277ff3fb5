//! SCENE.json text → parse, check, load its URDFs and SRDFs (relative to
//! `assets/`), join the forest, then the dynamics at its starting state. Any
//! panic is a crash; errors are fine.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let dir = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../assets"));
    let Ok(scene) = urdyn::Scene::from_json(text, "fuzz.json", dir, &[]) else {
        return;
    };
    let m = &scene.model;
    let _ = urdyn::sim::column_names(m);
    let mut data = urdyn::Data::new(m);
    let _ = urdyn::dynamics::rnea(m, &mut data, &scene.q0, &scene.v0, &scene.tau0, None);
    let _ = urdyn::dynamics::forward_dynamics(m, &mut data, &scene.q0, &scene.v0, &scene.tau0, None);
});
