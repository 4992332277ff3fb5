//! The library's unit tests: formerly `#[cfg(test)]` modules in `src/` (each file
//! names its source), now modules of this binary, so that `cargo test --release`
//! compiles the library once, not a second time as a test harness (Cargo.toml's
//! `[lib] test = false`). The internals they exercise come from the hidden
//! `urdyn::testing` (src/testing.rs); a new test of an internal goes here.

mod cli_output;
mod contact_apart;
mod contact_ball;
mod contact_box_corner;
mod contact_boxes;
mod contact_broad;
mod contact_climb_step;
mod contact_cylinder;
mod contact_cylinder_apart;
mod contact_cylinder_pfm;
mod contact_cylinder_rim;
mod contact_cylinder_side;
mod contact_face;
mod contact_hull;
mod contact_narrow;
mod contact_prim;
mod contact_travel;
mod factor_zeros;
mod mesh_cache;
mod mesh_dae;
mod mesh_inertia;
mod piles_chain6;
mod scene_srdf;
mod sim_add_body;
mod sim_build;
mod sim_dense;
mod sim_factor;
mod sim_parallel;
mod sleep_doze;
mod sleep_doze_energy;
mod spatial;
mod step_position_warm;
mod view_geometry;
mod view_page;
mod view_scene;
mod view_trajectory;
mod view_visuals;

use parry3d_f64::math::Vector as PVec;
use urdyn::testing::contact::{reduce_pair, ContactPoint, Raw, TestHull};

/// What `narrow::reduce_pair` keeps of one pair's raw points (4 at most), as
/// the points of bodies 1 and 2 (contact_box_corner.rs, contact_face.rs).
pub(crate) fn reduce4(raw: &[Raw]) -> Vec<ContactPoint> {
    let mut out = Vec::new();
    reduce_pair(raw, 4, &mut out, &|r| ContactPoint {
        shape: 0,
        slot: 0,
        body: 1,
        point: r.point,
        gap: r.gap,
        geom: 0,
        other: 2,
        other_geom: 0,
        normal: r.normal,
        friction: 1.0,
        fresh: true,
        key: r.key,
    });
    out
}

/// A superellipsoid's hull of 266 points (`|x/a|^(2/p) + ... = 1` sampled on
/// a 24 × 11 grid plus the poles): the climbing kind of hull, many vertices.
pub(crate) fn superellipsoid(half: [f64; 3], power: f64) -> TestHull {
    let mut pts = Vec::new();
    for i in 0..24 {
        for j in 1..12 {
            let (th, ph) = (
                std::f64::consts::TAU * i as f64 / 24.0,
                std::f64::consts::PI * j as f64 / 12.0,
            );
            let f = |c: f64| c.signum() * c.abs().powf(power);
            pts.push(PVec::new(
                half[0] * f(ph.sin() * th.cos()),
                half[1] * f(ph.sin() * th.sin()),
                half[2] * f(ph.cos()),
            ));
        }
    }
    pts.push(PVec::new(0.0, 0.0, half[2]));
    pts.push(PVec::new(0.0, 0.0, -half[2]));
    match TestHull::of_points(&pts) {
        Some(Ok(h)) => h,
        _ => panic!("a large hull"),
    }
}
