//! Drops the balanced-arm desk lamp with its two parallelogram arms
//! (assets/luxo.urdf, the loops closed by two `point` constraints) from 0.3 m,
//! tilted 10° about x, onto a table (assets/table.urdf, its top 0.75 m up): the scene `assets/luxo_on_table.json`, exactly as
//! `urdyn simulate --scene assets/luxo_on_table.json --duration 8 --out target/luxo_on_table.csv --html target/luxo_on_table.html`,
//! then plots the lamp's base height, the energy, the loops' largest violation and
//! the contact count against time (docs/mechanisms_examples.md gives the numbers).
//!
//! `cargo run --release --example luxo_on_table [OUT_DIR]` writes `OUT_DIR/luxo_on_table.csv`,
//! `OUT_DIR/luxo_on_table.png` and the replay page `OUT_DIR/luxo_on_table.html`, which draws
//! the loop constraints (OUT_DIR defaults to `target`).

#[path = "common/luxo_run.rs"]
mod luxo_run;
use urdyn_example_plot as png_out;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let summary = luxo_run::run(
        "assets/luxo_on_table.json",
        "luxo_on_table",
        "lamp base height (table top at 0.75 m)",
    )?;
    eprintln!("{summary}");
    Ok(())
}
