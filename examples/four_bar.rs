//! A passive planar four-bar (assets/four_bar.urdf: crank, coupler, rocker as a
//! tree of three revolute joints, the loop closed by the `point` constraint of
//! assets/four_bar_constraints.json) released at rest under gravity, integrated
//! with urdyn's `constraint_dynamics` by RK4 at h = 0.1 ms plus a projection
//! onto the constraint manifold (examples/common/constrained.rs).
//!
//! Run: `cargo run --release --example four_bar [OUT_DIR]`; writes
//! `OUT_DIR/four_bar.csv` (t, q of the three joints, energy, violation) and
//! `OUT_DIR/four_bar.png` (crank angle, violation, energy), OUT_DIR defaults to
//! `target`. tests/mechanism_examples/four_bar.rs checks the same run against an independent
//! minimal-coordinate integration (tests/fixtures/four_bar_reference.json).

#[path = "common/constrained.rs"]
mod constrained;
#[path = "common/four_bar_setup.rs"]
mod four_bar_setup;
use urdyn_example_plot as png_out;

use std::error::Error;
use std::io::Write;
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn Error>> {
    let out_dir = PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "target".into()));
    std::fs::create_dir_all(&out_dir)?;
    let t_end = 2.0;
    let start = std::time::Instant::now();
    let samples = four_bar_setup::run(1e-4, t_end, 10);
    let wall = start.elapsed().as_secs_f64();
    let csv = out_dir.join("four_bar.csv");
    let mut f = std::io::BufWriter::new(std::fs::File::create(&csv)?);
    writeln!(
        f,
        "t,q:crank_joint,q:coupler_joint,q:rocker_joint,energy,violation"
    )?;
    for s in &samples {
        writeln!(
            f,
            "{},{},{},{},{},{}",
            s.t, s.q[0], s.q[1], s.q[2], s.energy, s.violation
        )?;
    }
    drop(f);
    let e0 = samples[0].energy;
    let drift = samples
        .iter()
        .map(|s| (s.energy - e0).abs())
        .fold(0.0, f64::max);
    let viol = samples.iter().map(|s| s.violation).fold(0.0, f64::max);
    let t: Vec<f64> = samples.iter().map(|s| s.t).collect();
    let crank: Vec<f64> = samples.iter().map(|s| s.q[0]).collect();
    let violation: Vec<f64> = samples.iter().map(|s| s.violation * 1e15).collect();
    let energy: Vec<f64> = samples.iter().map(|s| (s.energy - e0) * 1e12).collect();
    let panel = |title, ylabel, ys, color| png_out::Panel {
        title,
        ylabel,
        ys,
        color,
        count: false,
    };
    let png = out_dir.join("four_bar.png");
    png_out::plot_panels(
        &png,
        &t,
        t_end,
        &[
            panel(
                "crank angle",
                "q crank (rad)",
                &crank,
                urdyn_example_plot::plotters::style::RGBColor(200, 40, 30),
            ),
            panel(
                "loop violation |p1 - p2| (1e-15 m = fm)",
                "fm",
                &violation,
                urdyn_example_plot::plotters::style::RGBColor(30, 90, 200),
            ),
            panel(
                "energy - E0 (1e-12 J = pJ; E0 = 1.286 J)",
                "pJ",
                &energy,
                urdyn_example_plot::plotters::style::RGBColor(30, 150, 60),
            ),
        ],
    )?;
    for s in samples
        .iter()
        .filter(|s| (s.t * 2.0 - (s.t * 2.0).round()).abs() < 1e-9 && s.t > 0.0)
    {
        println!("t = {:.1} s: crank {:.9} rad", s.t, s.q[0]);
    }
    println!(
        "four_bar: {} steps in {wall:.2} s, energy E0 = {e0:.12} J, largest |E - E0| = {drift:.2e} J, largest violation {viol:.2e} m; wrote {} and {}",
        (t_end / 1e-4).round(),
        csv.display(),
        png.display()
    );
    Ok(())
}
