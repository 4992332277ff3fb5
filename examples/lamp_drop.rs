//! Drops the desk lamp (`assets/lamp.urdf`, floating base) from 0.5 m with a 10°
//! tilt about x onto the ground, exactly as
//! `urdyn simulate assets/lamp.urdf --floating-base --duration 3 --initial assets/lamp_initial.json --out lamp_drop.csv`,
//! then plots base height, energy and contact count against time.
//!
//! `cargo run --release --example lamp_drop [OUT_DIR]` writes `OUT_DIR/lamp_drop.csv`,
//! `OUT_DIR/lamp_drop.png` and the 3D replay page `OUT_DIR/lamp_drop.html` (as
//! `simulate --html` writes it; OUT_DIR defaults to `target`).

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
    let csv = out_dir.join("lamp_drop.csv");
    let args = urdyn::cli::simulate::SimulateArgs {
        floating_base: true,
        duration: 3.0,
        dt: Some(1e-3),
        initial: Some(root.join("assets/lamp_initial.json")),
        out: Some(csv.clone()),
        html: Some(out_dir.join("lamp_drop.html")),
        ..urdyn::cli::simulate::SimulateArgs::new(root.join("assets/lamp.urdf"))
    };
    let summary = urdyn::cli::simulate::run(&args)?;
    eprintln!("{summary}");

    // read the trajectory back and plot it
    let cols = png_out::read_columns(&csv, &["t", "q:base_z", "energy", "contacts"])?;
    let png = out_dir.join("lamp_drop.png");
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
            panel("base height", "base height z (m)", &cols[1], BLUE, false),
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
        out_dir.join("lamp_drop.html").display()
    );
    Ok(())
}
