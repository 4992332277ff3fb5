//! Drops the desk lamp (`assets/lamp.urdf`, floating base) from 0.5 m above a
//! table (`assets/table.urdf`, welded to the world, its top 0.75 m up), tilted
//! 10° about x: the scene `assets/lamp_on_table.json`, exactly as
//! `urdyn simulate --scene assets/lamp_on_table.json --duration 3 --out target/lamp_on_table.csv`,
//! then plots the lamp's base height, the energy and the contact count against time.
//!
//! `cargo run --release --example lamp_on_table [OUT_DIR]` writes
//! `OUT_DIR/lamp_on_table.csv`, `OUT_DIR/lamp_on_table.png` and the 3D replay
//! page `OUT_DIR/lamp_on_table.html` (OUT_DIR defaults to `target`).

use urdyn_example_plot as png_out;

use std::path::PathBuf;
use urdyn_example_plot::plotters::style::colors::{BLACK, BLUE, RED};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let out_dir = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("target"));
    std::fs::create_dir_all(&out_dir)?;
    let csv = out_dir.join("lamp_on_table.csv");
    let args = urdyn::cli::simulate::SimulateArgs {
        duration: 3.0,
        dt: Some(1e-3),
        out: Some(csv.clone()),
        html: Some(out_dir.join("lamp_on_table.html")),
        ..urdyn::cli::simulate::SimulateArgs::scene(root.join("assets/lamp_on_table.json"))
    };
    let summary = urdyn::cli::simulate::run(&args)?;
    eprintln!("{summary}");

    // read the trajectory back and plot it
    let cols = png_out::read_columns(&csv, &["t", "q:lamp/base_z", "energy", "contacts"])?;
    let png = out_dir.join("lamp_on_table.png");
    let panel = |title, ylabel, ys, color, count| png_out::Panel {
        title,
        ylabel,
        ys,
        color,
        count,
    };
    png_out::plot_panels(
        &png,
        &cols[0],
        3.0,
        &[
            panel(
                "lamp base height (table top at 0.75 m)",
                "base height z (m)",
                &cols[1],
                BLUE,
                false,
            ),
            panel(
                "energy (kinetic + potential)",
                "energy E (J)",
                &cols[2],
                RED,
                false,
            ),
            panel(
                "active contact points",
                "contacts (count)",
                &cols[3],
                BLACK,
                true,
            ),
        ],
    )?;
    println!(
        "wrote {}, {} and {}",
        csv.display(),
        png.display(),
        out_dir.join("lamp_on_table.html").display()
    );
    Ok(())
}
