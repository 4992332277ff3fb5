//! The examples' plots as PNG files: plotters draws into an RGB buffer
//! (`BitMapBackend::with_buffer`), the `png` crate writes it. Text is drawn in
//! the DejaVu Sans shipped in `assets/fonts/` (plotters' pure-Rust `ab_glyph`
//! renderer): no system font library or font is needed.
//!
//! A crate of its own (a dev-dependency of urdyn, by path), not a `#[path]` module of
//! each example: plotters' generic drawing code is compiled and optimised once here,
//! beside the library's build, instead of once in every example that plots (six of
//! them in `cargo test --release`; README §"Two commands").

pub use plotters;

use std::error::Error;
use std::path::Path;

/// Registers the shipped DejaVu Sans as plotters' `"sans-serif"` (call once,
/// before drawing any text).
pub fn register_font() -> Result<(), Box<dyn Error>> {
    static DEJAVU_SANS: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans.ttf");
    plotters::style::register_font(
        "sans-serif",
        plotters::style::FontStyle::Normal,
        DEJAVU_SANS,
    )
    .map_err(|_| "assets/fonts/DejaVuSans.ttf: not a font plotters can read".into())
}

/// Writes the 8-bit RGB pixels `rgb` (`size.0 × size.1`, row by row) to `path` as
/// a PNG: first into `path` + `.tmp`, then renamed over it, so that a failed write
/// leaves no half-written picture.
pub fn write_png(path: &Path, rgb: &[u8], size: (u32, u32)) -> Result<(), Box<dyn Error>> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = std::path::PathBuf::from(tmp);
    let result = (|| -> Result<(), Box<dyn Error>> {
        let file = std::io::BufWriter::new(std::fs::File::create(&tmp)?);
        let mut enc = png::Encoder::new(file, size.0, size.1);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header()?;
        writer.write_image_data(rgb)?;
        writer.finish()?;
        Ok(())
    })();
    match result {
        Ok(()) => Ok(std::fs::rename(&tmp, path)?),
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(e)
        }
    }
}

/// The columns `names` of the CSV trajectory `csv` (as `urdyn simulate --out`
/// writes it), each a vector of its rows' values.
pub fn read_columns(csv: &Path, names: &[&str]) -> Result<Vec<Vec<f64>>, Box<dyn Error>> {
    let text = std::fs::read_to_string(csv)?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or_default().split(',').collect();
    let index = names
        .iter()
        .map(|name| {
            header
                .iter()
                .position(|h| h == name)
                .ok_or_else(|| format!("{}: no column {name}", csv.display()))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let mut cols = vec![Vec::new(); names.len()];
    for l in lines {
        let f: Vec<&str> = l.split(',').collect();
        for (col, &k) in cols.iter_mut().zip(&index) {
            col.push(f.get(k).and_then(|x| x.parse().ok()).unwrap_or(f64::NAN));
        }
    }
    Ok(cols)
}

/// One panel of [`plot_panels`]: its title, its y axis label (with units), its
/// values, its colour, and whether they are a count (integer ticks from 0).
pub struct Panel<'a> {
    pub title: &'a str,
    pub ylabel: &'a str,
    pub ys: &'a [f64],
    pub color: plotters::style::RGBColor,
    pub count: bool,
}

/// Plots `panels` one above the other against the time `t` (s, 0 to `t_end`),
/// 1000 px wide and 300 px a panel, into the PNG `png`.
pub fn plot_panels(
    png: &Path,
    t: &[f64],
    t_end: f64,
    panels: &[Panel],
) -> Result<(), Box<dyn Error>> {
    use plotters::prelude::*;
    let size = (1000u32, 300 * panels.len() as u32);
    let mut rgb = vec![0u8; (size.0 * size.1 * 3) as usize];
    register_font()?;
    {
        let area = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
        area.fill(&WHITE)?;
        for (region, p) in area.split_evenly((panels.len(), 1)).iter().zip(panels) {
            let (lo, hi) =
                p.ys.iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &y| {
                        (a.min(y), b.max(y))
                    });
            // a count: from 0, integer ticks only; a value: its range padded by 8 %
            let (lo, hi, pad) = if p.count {
                (0.0, hi.max(1.0).ceil(), 0.3)
            } else {
                (lo, hi, ((hi - lo) * 0.08).max(1e-3))
            };
            let mut chart = ChartBuilder::on(region)
                .caption(p.title, ("sans-serif", 20))
                .margin(10)
                .x_label_area_size(40)
                .y_label_area_size(70)
                .build_cartesian_2d(0.0..t_end, (lo - pad)..(hi + pad))?;
            let integer = |y: &f64| {
                if (y - y.round()).abs() < 1e-9 {
                    format!("{y:.0}")
                } else {
                    String::new()
                }
            };
            let mut mesh = chart.configure_mesh();
            mesh.x_desc("time t (s)")
                .y_desc(p.ylabel)
                .axis_desc_style(("sans-serif", 16))
                .label_style(("sans-serif", 13));
            if p.count {
                mesh.y_labels((hi as usize + 1).min(6))
                    .y_label_formatter(&integer);
            }
            mesh.draw()?;
            chart.draw_series(LineSeries::new(
                t.iter().copied().zip(p.ys.iter().copied()),
                p.color,
            ))?;
        }
        area.present()?;
    }
    write_png(png, &rgb, size)
}
