//! The tests of `src/cli/output.rs`, formerly its `#[cfg(test)]` module (tests/unit/mod.rs).
#![cfg(unix)]

use std::os::unix::fs::symlink;
use std::path::Path;
use urdyn::cli::output::write_atomic;

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
