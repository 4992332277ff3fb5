//! MJCF text → parse (entity guard, includes under tests/fixtures/mjcf), compile
//! (defaults, frames, orientations, mass properties from geoms, meshes), lower into
//! a `Model`, then the dynamics at its `qpos0` and the MJCF world's simulation
//! options. Any panic is a crash; errors are fine.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let dir = std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/fixtures/mjcf/dm_control"
    ));
    let Ok(m) = urdyn::mjcf::load_str(text, "fuzz.xml", dir) else {
        return;
    };
    let q = m.neutral();
    let v = urdyn::nalgebra::DVector::zeros(m.nv);
    let tau = urdyn::nalgebra::DVector::zeros(m.nv);
    let mut data = urdyn::Data::new(&m);
    let _ = urdyn::dynamics::rnea(&m, &mut data, &q, &v, &tau, None);
    let _ = urdyn::dynamics::forward_dynamics(&m, &mut data, &q, &v, &tau, None);
    let _ = urdyn::sim::column_names(&m);
});
