//! Drops the balanced-arm desk lamp with its two parallelogram arms
//! (assets/luxo.urdf, the loops closed by two `point` constraints) from 0.3 m,
//! tilted 10° about x, onto the ground: the scene `assets/luxo_drop.json`, exactly as
//! `urdyn simulate --scene assets/luxo_drop.json --duration 8 --out target/luxo_drop.csv --html target/luxo_drop.html`,
//! then plots the lamp's base height, the energy, the loops' largest violation and
//! the contact count against time (docs/mechanisms_examples.md gives the numbers).
//!
//! `cargo run --release --example luxo_drop [OUT_DIR]` writes `OUT_DIR/luxo_drop.csv`,
//! `OUT_DIR/luxo_drop.png` and the replay page `OUT_DIR/luxo_drop.html`, which draws
//! the loop constraints (OUT_DIR defaults to `target`).

#[path = "common/luxo_run.rs"]
mod luxo_run;
use urdyn_example_plot as png_out;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let summary = luxo_run::run(
        "assets/luxo_drop.json",
        "luxo_drop",
        "lamp base height (ground at 0 m)",
    )?;
    eprintln!("{summary}");
    Ok(())
}
