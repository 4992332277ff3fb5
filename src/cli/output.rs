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

#[cfg(all(test, unix))]
mod tests {
    use super::*;
    use std::os::unix::fs::symlink;

    fn put(path: &Path, text: &str) -> Result<(), String> {
        write_atomic(path, |w| {
            w.write_all(text.as_bytes()).map_err(|e| e.to_string())
        })
    }

    fn entries(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn new_and_regular_files_are_replaced_whole() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("a.txt");
        put(&p, "one").unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "one");
        put(&p, "two").unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "two");
        let e = write_atomic(&p, |w| {
            w.write_all(b"half").unwrap();
            Err("boom".into())
        });
        assert_eq!(e, Err("boom".into()));
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "two");
        assert_eq!(entries(d.path()), vec!["a.txt"]);
    }

    #[test]
    fn permissions_of_a_replaced_file_are_kept() {
        use std::os::unix::fs::PermissionsExt;
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("a.txt");
        std::fs::write(&p, "x").unwrap();
        std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o640)).unwrap();
        put(&p, "y").unwrap();
        let mode = std::fs::metadata(&p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode, 0o640);
    }

    #[test]
    fn links_are_written_through_and_kept() {
        let d = tempfile::tempdir().unwrap();
        let sub = d.path().join("sub");
        std::fs::create_dir(&sub).unwrap();
        // relative chain: l1 -> l2 -> sub/t.txt (t.txt absent at first)
        symlink("sub/t.txt", d.path().join("l2")).unwrap();
        symlink("l2", d.path().join("l1")).unwrap();
        let l1 = d.path().join("l1");
        put(&l1, "first").unwrap();
        put(&l1, "second").unwrap();
        assert!(std::fs::symlink_metadata(&l1)
            .unwrap()
            .file_type()
            .is_symlink());
        assert!(std::fs::symlink_metadata(d.path().join("l2"))
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(
            std::fs::read_to_string(sub.join("t.txt")).unwrap(),
            "second"
        );
        assert_eq!(entries(&sub), vec!["t.txt"]);
        // a failure leaves the target as it was, and no temporary file
        assert!(write_atomic(&l1, |_| Err("boom".into())).is_err());
        assert_eq!(
            std::fs::read_to_string(sub.join("t.txt")).unwrap(),
            "second"
        );
        assert_eq!(entries(&sub), vec!["t.txt"]);
        assert_eq!(entries(d.path()), vec!["l1", "l2", "sub"]);
    }

    #[test]
    fn directories_and_loops_are_errors() {
        let d = tempfile::tempdir().unwrap();
        let e = put(d.path(), "x").unwrap_err();
        assert!(e.contains("is a directory"), "{e}");
        let l = d.path().join("ld");
        symlink(d.path(), &l).unwrap();
        let e = put(&l, "x").unwrap_err();
        assert!(e.contains("is a directory") && e.contains("ld"), "{e}");
        let (a, b) = (d.path().join("a"), d.path().join("b"));
        symlink(&b, &a).unwrap();
        symlink(&a, &b).unwrap();
        let e = put(&a, "x").unwrap_err();
        assert!(e.contains("symbolic links"), "{e}");
        assert_eq!(e.lines().count(), 1);
    }

    #[test]
    fn a_missing_folder_is_an_error_and_creates_nothing() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("no/such/dir/x.csv");
        let e = put(&p, "x").unwrap_err();
        assert!(e.contains("x.csv") && e.contains("cannot write"), "{e}");
        assert_eq!(entries(d.path()), Vec::<String>::new());
    }
}
