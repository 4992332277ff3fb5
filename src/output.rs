//! Output files are never half written: they go to a temporary file in the same
//! folder, renamed over the target only on success.

use std::io::Write;
use std::path::{Path, PathBuf};

/// Writes `path` atomically by streaming into a temporary sibling with `fill`,
/// then renaming. On any error the temporary file is removed and nothing appears.
pub fn write_atomic<F>(path: &Path, fill: F) -> Result<(), String>
where
    F: FnOnce(&mut (dyn Write + Send)) -> Result<(), String>,
{
    let name = path.display().to_string();
    if path.is_dir() {
        return Err(format!("{name}: is a directory"));
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let file_name = path
        .file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let tmp = dir.join(format!(".{file_name}.{}.tmp", std::process::id()));
    let result = (|| {
        let f = std::fs::File::create(&tmp).map_err(|e| format!("{name}: cannot write: {e}"))?;
        let mut w = std::io::BufWriter::with_capacity(1 << 20, f);
        fill(&mut w)?;
        w.flush()
            .map_err(|e| format!("{name}: cannot write: {e}"))?;
        let f = w
            .into_inner()
            .map_err(|e| format!("{name}: cannot write: {e}"))?;
        f.sync_all()
            .map_err(|e| format!("{name}: cannot write: {e}"))?;
        std::fs::rename(&tmp, path).map_err(|e| format!("{name}: cannot write: {e}"))
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}
