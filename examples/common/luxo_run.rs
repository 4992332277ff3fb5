//! The Luxo lamp examples' shared run: a scene simulated exactly as
//! `urdyn simulate --scene SCENE --duration 8 --out CSV --html PAGE`, then a PNG of
//! the lamp's base height, the energy, the loops' largest violation and the
//! contact count against time (docs/mechanisms_examples.md).

use std::path::{Path, PathBuf};
use urdyn_example_plot::plotters::style::colors::{BLACK, BLUE, RED};
use urdyn_example_plot::plotters::style::RGBColor;

/// The run's length (s).
pub const DURATION: f64 = 8.0;

/// Simulates `scene` (relative to the crate root) and writes `OUT_DIR/NAME.csv`,
/// `.png`, `.html`; returns the summary line.
pub fn run(
    scene: &str,
    name: &str,
    height_note: &str,
) -> Result<String, Box<dyn std::error::Error>> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let out_dir = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("target"));
    std::fs::create_dir_all(&out_dir)?;
    let csv = out_dir.join(format!("{name}.csv"));
    let html = out_dir.join(format!("{name}.html"));
    let args = urdyn::cli::simulate::SimulateArgs {
        urdf: PathBuf::new(),
        scene: Some(root.join(scene)),
        floating_base: false,
        duration: DURATION,
        dt: Some(1e-3),
        key: None,
        controls: None,
        integrator: None,
        tol: 1e-6,
        initial: None,
        armature: 0.0,
        above_ground: None,
        ground: None,
        no_ground: false,
        no_sleep: false,
        threads: None,
        gravity: None,
        friction: 1.0,
        package_path: vec![],
        out: Some(csv.clone()),
        html: Some(html.clone()),
        every: 1,
        progress: false,
    };
    let summary = urdyn::cli::simulate::run(&args)?;
    plot(&csv, &out_dir.join(format!("{name}.png")), height_note)?;
    println!(
        "wrote {}, {}.png and {}",
        csv.display(),
        name,
        html.display()
    );
    Ok(summary.to_string())
}

fn plot(csv: &Path, png: &Path, height_note: &str) -> Result<(), Box<dyn std::error::Error>> {
    let cols = super::png_out::read_columns(
        csv,
        &[
            "t",
            "q:luxo/base_z",
            "energy",
            "constraint_violation",
            "contacts",
        ],
    )?;
    // the violation on a log scale (decades)
    let log_viol: Vec<f64> = cols[3].iter().map(|v| v.max(1e-16).log10()).collect();
    let panel = |title, ylabel, ys, color, count| super::png_out::Panel {
        title,
        ylabel,
        ys,
        color,
        count,
    };
    super::png_out::plot_panels(
        png,
        &cols[0],
        DURATION,
        &[
            panel(height_note, "base height z (m)", &cols[1], BLUE, false),
            panel(
                "energy (kinetic + potential)",
                "energy E (J)",
                &cols[2],
                RED,
                false,
            ),
            panel(
                "largest loop violation (log10 m)",
                "log10 violation",
                &log_viol,
                RGBColor(30, 150, 60),
                false,
            ),
            panel(
                "active contact points",
                "contacts (count)",
                &cols[4],
                BLACK,
                true,
            ),
        ],
    )?;
    Ok(())
}
