//! solo12 standing with its four feet held by `point` constraints
//! (`constraint_dynamics` as the contact model), swaying its base sideways
//! (2 cm, 0.5 Hz) and bobbing it (1.5 cm, 1 Hz) under a computed-torque
//! controller through the constrained dynamics: torques on the twelve joints
//! only, the base unactuated, the feet's forces the least-norm ones that carry
//! the base (examples/common/quadruped_setup.rs). Integrated by RK4 at 1 ms with
//! projection onto the held feet (examples/common/constrained.rs).
//!
//! Run: `cargo run --release --example quadruped_held [OUT_DIR]`; writes
//! `OUT_DIR/quadruped_held.csv` and `OUT_DIR/quadruped_held.png` (base height
//! and sway against the reference, tracking error, the feet's normal forces),
//! OUT_DIR defaults to `target`. tests/mechanism_examples/quadruped_held.rs checks the tracking and
//! the weight carried at rest.

#[path = "common/constrained.rs"]
mod constrained;
use urdyn_example_plot as png_out;
#[path = "common/quadruped_setup.rs"]
mod quadruped_setup;

use std::error::Error;
use std::io::Write;
use std::path::PathBuf;
use urdyn_example_plot::plotters::style::RGBColor;

fn main() -> Result<(), Box<dyn Error>> {
    let out_dir = PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "target".into()));
    std::fs::create_dir_all(&out_dir)?;
    let (t_end, h) = (3.0, 1e-3);
    let start = std::time::Instant::now();
    let s = quadruped_setup::run(h, t_end, 5);
    let wall = start.elapsed().as_secs_f64();
    let csv = out_dir.join("quadruped_held.csv");
    let mut f = std::io::BufWriter::new(std::fs::File::create(&csv)?);
    writeln!(
        f,
        "t,base_z,base_z_ref,base_y,base_y_ref,error,fz_FL,fz_FR,fz_HL,fz_HR,tau_max,violation"
    )?;
    for x in &s {
        writeln!(
            f,
            "{},{},{},{},{},{},{},{},{},{},{},{}",
            x.t,
            x.z.0,
            x.z.1,
            x.y.0,
            x.y.1,
            x.error,
            x.normal[0],
            x.normal[1],
            x.normal[2],
            x.normal[3],
            x.tau_max,
            x.violation
        )?;
    }
    drop(f);
    let t: Vec<f64> = s.iter().map(|x| x.t).collect();
    let z: Vec<f64> = s.iter().map(|x| x.z.0 * 1e3).collect();
    let y: Vec<f64> = s.iter().map(|x| x.y.0 * 1e3).collect();
    let err: Vec<f64> = s.iter().map(|x| x.error.max(1e-16).log10()).collect();
    let fmin: Vec<f64> = s
        .iter()
        .map(|x| x.normal.iter().cloned().fold(f64::INFINITY, f64::min))
        .collect();
    let fsum: Vec<f64> = s.iter().map(|x| x.normal.iter().sum()).collect();
    let panel = |title, ylabel, ys, color| png_out::Panel {
        title,
        ylabel,
        ys,
        color,
        count: false,
    };
    let png = out_dir.join("quadruped_held.png");
    png_out::plot_panels(
        &png,
        &t,
        t_end,
        &[
            panel(
                "base height z (tracks 1.5 cm at 1 Hz)",
                "mm",
                &z,
                RGBColor(200, 40, 30),
            ),
            panel(
                "base sway y (tracks 2 cm at 0.5 Hz)",
                "mm",
                &y,
                RGBColor(30, 90, 200),
            ),
            panel(
                "tracking error log10 |p - p_ref| (m)",
                "log10 m",
                &err,
                RGBColor(120, 60, 160),
            ),
            panel(
                "smallest foot normal force (N)",
                "N",
                &fmin,
                RGBColor(30, 150, 60),
            ),
            panel(
                "sum of the feet's normal forces (N)",
                "N",
                &fsum,
                RGBColor(90, 90, 90),
            ),
        ],
    )?;
    let late = s
        .iter()
        .filter(|x| x.t >= 1.0)
        .map(|x| x.error)
        .fold(0.0, f64::max);
    let first = s.iter().map(|x| x.error).fold(0.0, f64::max);
    let fmin_all = fmin.iter().cloned().fold(f64::INFINITY, f64::min);
    let tau_max = s.iter().map(|x| x.tau_max).fold(0.0, f64::max);
    let viol = s.iter().map(|x| x.violation).fold(0.0, f64::max);
    println!(
        "quadruped_held: {:.0} steps in {wall:.2} s; tracking error at most {first:.2e} m (catching up), {late:.2e} m after 1 s; feet normal forces >= {fmin_all:.3} N (weight {:.4} N); |tau| <= {tau_max:.3} N m; feet violation <= {viol:.1e} m; wrote {} and {}",
        t_end / h,
        quadruped_setup::setup().0.model.total_mass() * 9.81,
        csv.display(),
        png.display()
    );
    Ok(())
}
