//! Drops the desk lamp (`assets/lamp.urdf`, floating base) from 0.5 m with a 10°
//! tilt about x onto the ground, exactly as
//! `urdyn simulate assets/lamp.urdf --floating-base --duration 3 --initial assets/lamp_initial.json --out lamp_drop.csv`,
//! then plots base height, energy and contact count against time.
//!
//! `cargo run --release --example lamp_drop [OUT_DIR]` writes `OUT_DIR/lamp_drop.csv`,
//! `OUT_DIR/lamp_drop.png` and the 3D replay page `OUT_DIR/lamp_drop.html` (as
//! `simulate --html` writes it; OUT_DIR defaults to `target`).

#[path = "common/png_out.rs"]
mod png_out;

use plotters::prelude::*;
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let out_dir = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("target"));
    std::fs::create_dir_all(&out_dir)?;
    let csv = out_dir.join("lamp_drop.csv");
    let args = urdyn::cli::simulate::SimulateArgs {
        urdf: root.join("assets/lamp.urdf"),
        scene: None,
        floating_base: true,
        duration: 3.0,
        dt: 1e-3,
        integrator: None,
        tol: 1e-6,
        initial: Some(root.join("assets/lamp_initial.json")),
        armature: 0.0,
        above_ground: None,
        ground: None,
        no_ground: false,
        gravity: None,
        friction: 1.0,
        package_path: vec![],
        out: Some(csv.clone()),
        html: Some(out_dir.join("lamp_drop.html")),
        every: 1,
        progress: false,
    };
    let summary = urdyn::cli::simulate::run(&args)?;
    eprintln!("{summary}");

    // read the trajectory back
    let text = std::fs::read_to_string(&csv)?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or_default().split(',').collect();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .ok_or(format!("no column {name}"))
    };
    let (ct, cz, ce, cc) = (
        col("t")?,
        col("q:base_z")?,
        col("energy")?,
        col("contacts")?,
    );
    let mut t = Vec::new();
    let mut z = Vec::new();
    let mut e = Vec::new();
    let mut c = Vec::new();
    for l in lines {
        let f: Vec<f64> = l
            .split(',')
            .map(|x| x.parse().unwrap_or(f64::NAN))
            .collect();
        t.push(f[ct]);
        z.push(f[cz]);
        e.push(f[ce]);
        c.push(f[cc]);
    }
    let png = out_dir.join("lamp_drop.png");
    let mut rgb = vec![0u8; 1000 * 900 * 3];
    png_out::register_font()?;
    {
        let area = BitMapBackend::with_buffer(&mut rgb, (1000, 900)).into_drawing_area();
        area.fill(&WHITE)?;
        let panels = area.split_evenly((3, 1));
        // base height and energy: real-valued axes; the contact count: integer ticks
        let series: [(&str, &str, &Vec<f64>, RGBColor); 2] = [
            ("base height", "base height z (m)", &z, BLUE),
            ("energy (kinetic + potential)", "energy E (J)", &e, RED),
        ];
        for (panel, (title, ylabel, ys, color)) in panels.iter().zip(series.iter()) {
            let (lo, hi) = ys
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &y| {
                    (a.min(y), b.max(y))
                });
            let pad = ((hi - lo) * 0.08).max(1e-3);
            let mut chart = ChartBuilder::on(panel)
                .caption(*title, ("sans-serif", 20))
                .margin(10)
                .x_label_area_size(40)
                .y_label_area_size(70)
                .build_cartesian_2d(0.0..3.0, (lo - pad)..(hi + pad))?;
            chart
                .configure_mesh()
                .x_desc("time t (s)")
                .y_desc(*ylabel)
                .axis_desc_style(("sans-serif", 16))
                .label_style(("sans-serif", 13))
                .draw()?;
            chart.draw_series(LineSeries::new(
                t.iter().copied().zip(ys.iter().copied()),
                color,
            ))?;
        }
        let cmax = c.iter().copied().fold(0.0, f64::max).max(1.0).ceil();
        let mut chart = ChartBuilder::on(&panels[2])
            .caption("active contact points", ("sans-serif", 20))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..3.0, -0.3..cmax + 0.3)?;
        chart
            .configure_mesh()
            .x_desc("time t (s)")
            .y_desc("contacts (count)")
            .axis_desc_style(("sans-serif", 16))
            .label_style(("sans-serif", 13))
            // at most cmax + 1 labels: a step of at least 1, and only integers shown
            .y_labels((cmax as usize + 1).min(6))
            .y_label_formatter(&|y| {
                if (y - y.round()).abs() < 1e-9 {
                    format!("{y:.0}")
                } else {
                    String::new()
                }
            })
            .draw()?;
        chart.draw_series(LineSeries::new(
            t.iter().copied().zip(c.iter().copied()),
            BLACK,
        ))?;
        area.present()?;
    }
    png_out::write_png(&png, &rgb, (1000, 900))?;
    println!(
        "wrote {}, {} and {}",
        csv.display(),
        png.display(),
        out_dir.join("lamp_drop.html").display()
    );
    Ok(())
}
