//! Mesh paths of a URDF (`package://`, `file://`, relative), resolved without ROS.

use std::path::{Path, PathBuf};

/// Resolves a URDF mesh `filename` to an existing file, without ROS:
/// `package://NAME/rest` is looked up as `ROOT/NAME/rest` (and `ROOT/rest` when ROOT
/// is itself the package) for each root in `package_paths`, `ROS_PACKAGE_PATH`, and
/// the URDF's folder and its ancestors; `file://` and plain paths are taken relative
/// to the URDF's folder. Returns `None` when nothing exists.
pub fn resolve_mesh_path(
    filename: &str,
    urdf: Option<&Path>,
    package_paths: &[PathBuf],
) -> Option<PathBuf> {
    let urdf_dir = urdf.and_then(|p| p.parent()).map(|p| {
        if p.as_os_str().is_empty() {
            Path::new(".")
        } else {
            p
        }
    });
    if let Some(rest) = filename.strip_prefix("package://") {
        let (pkg, tail) = rest.split_once('/')?;
        let mut roots: Vec<PathBuf> = package_paths.to_vec();
        if let Ok(env) = std::env::var("ROS_PACKAGE_PATH") {
            roots.extend(std::env::split_paths(&env));
        }
        if let Some(d) = urdf_dir {
            roots.extend(d.ancestors().map(Path::to_path_buf));
        }
        for r in roots {
            for cand in [
                r.join(pkg).join(tail),
                if r.ends_with(pkg) {
                    r.join(tail)
                } else {
                    PathBuf::new()
                },
            ] {
                if !cand.as_os_str().is_empty() && cand.is_file() {
                    return Some(cand);
                }
            }
        }
        return None;
    }
    let plain = filename.strip_prefix("file://").unwrap_or(filename);
    let p = Path::new(plain);
    let cand = if p.is_absolute() {
        p.to_path_buf()
    } else {
        urdf_dir.unwrap_or(Path::new(".")).join(p)
    };
    cand.is_file().then_some(cand)
}
