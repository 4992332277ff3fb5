//! The examples' plots as PNG files: plotters draws into an RGB buffer
//! (`BitMapBackend::with_buffer`), the `png` crate writes it. Text is drawn in
//! the DejaVu Sans shipped in `assets/fonts/` (plotters' pure-Rust `ab_glyph`
//! renderer): no system font library or font is needed.

use std::error::Error;
use std::path::Path;

/// Registers the shipped DejaVu Sans as plotters' `"sans-serif"` (call once,
/// before drawing any text).
pub fn register_font() -> Result<(), Box<dyn Error>> {
    static DEJAVU_SANS: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");
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
