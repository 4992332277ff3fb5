//! Output files (`simulate --out`, `eval --output`): never half written, and no
//! special file is ever replaced.
//!
//! [`write_atomic`] looks at what the path names before writing:
//! - a **new path or a regular file**: the output goes to a temporary file in the
//!   same folder (created exclusively, never following a link), which is flushed,
//!   synced and renamed over the path only on success. A replaced file keeps its
//!   permission bits. On any error the temporary file is removed: nothing appears
//!   and an existing file is left as it was.
//! - a **symbolic link** (or a chain of them): written *through*. The chain is
//!   followed to its final target; when that is a regular file or does not exist
//!   yet, the temporary file goes to the target's folder and is renamed onto the
//!   target, so the link stays a link and the target gets the output (with the
//!   same all-or-nothing guarantee). When it is another kind of file, that file is
//!   treated as below. A chain that loops or is longer than 40 links is an error.
//! - a **FIFO, character or block device, or any other non-regular file**: opened
//!   for writing (no truncation, no temporary file, no rename) and streamed into
//!   directly, as a shell redirection would. Opening a FIFO waits for a reader.
//!   What was written before an error has been written: a stream cannot be
//!   taken back.
//! - a **directory** (also through a link): an error naming the path.
//!
//! An output naming one of the command's inputs, or its other output, is refused
//! before anything runs ([`not_an_input`]).
//!
//! Every error is one line naming the path as given.

use std::fs::{File, OpenOptions};
use std::io::{ErrorKind, Write};
use std::path::{Path, PathBuf};

/// Symbolic links followed before giving up (Linux's own limit).
const MAX_LINKS: usize = 40;

/// What the output path resolves to.
enum Target {
    /// A regular file or a path that does not exist yet (the resolved path):
    /// temporary file plus rename.
    Replace {
        path: PathBuf,
        existing: Option<std::fs::Permissions>,
    },
    /// A FIFO, device or other special file (the resolved path): written in place.
    Stream(PathBuf),
}

/// Follows `path` through any chain of symbolic links and classifies the end.
fn resolve(path: &Path, name: &str) -> Result<Target, String> {
    let mut p = path.to_path_buf();
    for _ in 0..=MAX_LINKS {
        let md = match std::fs::symlink_metadata(&p) {
            Ok(md) => md,
            Err(e) if e.kind() == ErrorKind::NotFound => {
                if p.file_name().is_none() {
                    return Err(format!("{name}: not a file path"));
                }
                return Ok(Target::Replace {
                    path: p,
                    existing: None,
                });
            }
            Err(e) => return Err(format!("{name}: cannot write: {e}")),
        };
        let ft = md.file_type();
        if ft.is_symlink() {
            let link = std::fs::read_link(&p)
                .map_err(|e| format!("{name}: cannot follow the symbolic link: {e}"))?;
            // a relative target is relative to the link's folder (joined, not
            // normalised: the system resolves any `..` against the real folder)
            p = if link.is_absolute() {
                link
            } else {
                match p.parent() {
                    Some(d) if !d.as_os_str().is_empty() => d.join(link),
                    _ => link,
                }
            };
            continue;
        }
        if ft.is_dir() {
            return Err(format!("{name}: is a directory"));
        }
        if ft.is_file() {
            if p.file_name().is_none() {
                return Err(format!("{name}: not a file path"));
            }
            return Ok(Target::Replace {
                path: p,
                existing: Some(md.permissions()),
            });
        }
        return Ok(Target::Stream(p));
    }
    Err(format!(
        "{name}: too many levels of symbolic links (more than {MAX_LINKS})"
    ))
}

/// Creates a fresh temporary file next to `target` (exclusively: an existing
/// file or link of that name is never opened or followed).
fn create_temp(target: &Path, name: &str) -> Result<(PathBuf, File), String> {
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let file_name = target
        .file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let pid = std::process::id();
    let mut last = None;
    for k in 0..100u32 {
        let tmp = dir.join(format!(".{file_name}.{pid}.{k}.tmp"));
        match OpenOptions::new().write(true).create_new(true).open(&tmp) {
            Ok(f) => return Ok((tmp, f)),
            Err(e) if e.kind() == ErrorKind::AlreadyExists => last = Some(e),
            Err(e) => return Err(format!("{name}: cannot write: {e}")),
        }
    }
    let e = last.map(|e| e.to_string()).unwrap_or_default();
    Err(format!(
        "{name}: cannot write: no free temporary file name ({e})"
    ))
}

/// Writes the output `fill` produces to `path`: atomically (temporary file and
/// rename) for a new path or a regular file, through a symbolic link onto its
/// target, streamed in place into a FIFO or device, never into a directory (see
/// the module documentation). On an error with a new path or regular file the
/// temporary file is removed and nothing appears.
pub fn write_atomic<F>(path: &Path, fill: F) -> Result<(), String>
where
    F: FnOnce(&mut (dyn Write + Send)) -> Result<(), String>,
{
    let name = path.display().to_string();
    let io = |e: std::io::Error| format!("{name}: cannot write: {e}");
    match resolve(path, &name)? {
        Target::Stream(p) => {
            let f = OpenOptions::new().write(true).open(&p).map_err(io)?;
            let mut w = std::io::BufWriter::with_capacity(1 << 16, f);
            fill(&mut w)?;
            w.flush().map_err(io)?;
            Ok(())
        }
        Target::Replace {
            path: target,
            existing,
        } => {
            let (tmp, f) = create_temp(&target, &name)?;
            let result = (|| {
                if let Some(perm) = existing {
                    f.set_permissions(perm).map_err(io)?;
                }
                let mut w = std::io::BufWriter::with_capacity(1 << 20, f);
                fill(&mut w)?;
                w.flush().map_err(io)?;
                let f = w.into_inner().map_err(|e| io(e.into_error()))?;
                f.sync_all().map_err(io)?;
                drop(f);
                std::fs::rename(&tmp, &target).map_err(io)
            })();
            if result.is_err() {
                let _ = std::fs::remove_file(&tmp);
            }
            result
        }
    }
}

/// `a` and `b` name one file: both exist and resolve (through symbolic links)
/// to one path, or neither exists and their folders resolve to one with the
/// same file name.
pub fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(x), Ok(y)) => x == y,
        (Err(_), Err(_)) => {
            let key = |p: &Path| {
                let dir = match p.parent() {
                    Some(d) if !d.as_os_str().is_empty() => d,
                    _ => Path::new("."),
                };
                Some((std::fs::canonicalize(dir).ok()?, p.file_name()?.to_owned()))
            };
            key(a).is_some_and(|k| key(b) == Some(k))
        }
        _ => false,
    }
}

/// Refuses an output `out` (given as option `opt`) that names one of the
/// command's inputs (`inputs`: the option or argument naming it, and its
/// path) or another output: `urdyn simulate --scene s.json --out s.json`
/// replaced the scene with the trajectory. A FIFO or device (`/dev/null`) is
/// streamed into, never replaced: any may share it.
pub fn not_an_input(out: &Path, opt: &str, inputs: &[(&str, &Path)]) -> Result<(), String> {
    if std::fs::metadata(out).is_ok_and(|m| !m.is_file() && !m.is_dir()) {
        return Ok(());
    }
    match inputs.iter().find(|(_, p)| same_file(out, p)) {
        Some((what, p)) => Err(format!(
            "{opt} {}: names the same file as {what} {} (not overwritten)",
            out.display(),
            p.display()
        )),
        None => Ok(()),
    }
}
