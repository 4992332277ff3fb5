//! Output paths of `simulate --out` and `eval --output` (issue 11): symbolic links
//! are written through and kept, FIFOs are streamed into and stay FIFOs, failed runs
//! leave nothing, and negative numbers reach the option checks (one line naming the
//! option, not a parser complaint about an unexpected argument).
#![cfg(unix)]

use std::os::unix::fs::{symlink, FileTypeExt};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::Duration;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn urdyn() -> Command {
    Command::new(env!("CARGO_BIN_EXE_urdyn"))
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// `simulate` of the lamp for 50 ms, writing to `out`, with extra arguments.
fn lamp(out: &Path, extra: &[&str]) -> Output {
    urdyn()
        .arg("simulate")
        .arg(root().join("assets/lamp.urdf"))
        .args(["--floating-base", "--duration", "0.05", "--initial"])
        .arg(root().join("assets/lamp_initial.json"))
        .args(extra)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

fn is_symlink(p: &Path) -> bool {
    std::fs::symlink_metadata(p)
        .map(|m| m.file_type().is_symlink())
        .unwrap_or(false)
}

/// A CSV as simulate writes it for the lamp: header, then rows up to t = 0.05.
fn check_lamp_csv(text: &str) {
    let mut lines = text.lines();
    let header = lines.next().unwrap_or_default();
    assert!(header.starts_with("t,"), "header: {header}");
    assert!(
        header.ends_with(",energy,contacts,penetration,awake"),
        "{header}"
    );
    let width = header.split(',').count();
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), 51, "rows at 0, 1, ..., 50 ms");
    for r in &rows {
        assert_eq!(r.split(',').count(), width, "{r}");
    }
    let t_last: f64 = rows
        .last()
        .and_then(|r| r.split(',').next())
        .unwrap()
        .parse()
        .unwrap();
    assert_eq!(t_last, 0.05);
}

/// (a) `--out LINK`: the link is kept, its target gets the CSV — whether the
/// target exists yet or not, and for a relative link into another folder.
#[test]
fn simulate_writes_through_a_symlink() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("target.csv");
    let link = dir.path().join("LINK");
    symlink(&target, &link).unwrap();
    // target absent: created through the link
    let o = lamp(&link, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(is_symlink(&link), "LINK was replaced");
    check_lamp_csv(&std::fs::read_to_string(&target).unwrap());
    // target present: replaced whole, link still a link
    std::fs::write(&target, "previous").unwrap();
    let o = lamp(&link, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(is_symlink(&link));
    check_lamp_csv(&std::fs::read_to_string(&target).unwrap());
    assert_eq!(names(dir.path()), vec!["LINK", "target.csv"]);

    // a relative chain: a -> b -> sub/t.csv; the temporary file is made in sub/
    let sub = dir.path().join("sub");
    std::fs::create_dir(&sub).unwrap();
    symlink("sub/t.csv", dir.path().join("b")).unwrap();
    symlink("b", dir.path().join("a")).unwrap();
    let o = lamp(&dir.path().join("a"), &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(is_symlink(&dir.path().join("a")) && is_symlink(&dir.path().join("b")));
    check_lamp_csv(&std::fs::read_to_string(sub.join("t.csv")).unwrap());
    assert_eq!(names(&sub), vec!["t.csv"]);
}

/// A link to a directory is an error naming the path given; nothing changes.
#[test]
fn a_link_to_a_directory_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let sub = dir.path().join("sub");
    std::fs::create_dir(&sub).unwrap();
    let link = dir.path().join("LD");
    symlink(&sub, &link).unwrap();
    let o = lamp(&link, &[]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("LD") && err.contains("directory"), "{err}");
    assert!(is_symlink(&link));
    assert!(names(&sub).is_empty());
}

/// (b) `--out FIFO`: streamed into while a reader reads; the FIFO stays a FIFO.
#[test]
fn simulate_streams_into_a_fifo() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("pipe.csv");
    match Command::new("mkfifo").arg(&fifo).status() {
        Ok(s) if s.success() => {}
        other => {
            eprintln!("skipped: mkfifo is not available ({other:?})");
            return;
        }
    }
    let (tx, rx) = std::sync::mpsc::channel();
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || {
            let text = std::fs::read_to_string(&fifo);
            let _ = tx.send(text.map_err(|e| e.to_string()));
        })
    };
    let o = lamp(&fifo, &[]);
    // If the run failed before opening the FIFO, the reader would wait forever
    // for a writer: open and close it read-write (never blocks on Linux) until the
    // reader is done.
    let mut got = None;
    for _ in 0..600 {
        match rx.recv_timeout(Duration::from_millis(100)) {
            Ok(r) => {
                got = Some(r);
                break;
            }
            Err(_) => {
                let _ = std::fs::OpenOptions::new()
                    .read(true)
                    .write(true)
                    .open(&fifo);
            }
        }
    }
    reader.join().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let text = got.expect("the reader finished").unwrap();
    check_lamp_csv(&text);
    let ft = std::fs::symlink_metadata(&fifo).unwrap().file_type();
    assert!(ft.is_fifo(), "the FIFO was replaced: {ft:?}");
    assert_eq!(names(dir.path()), vec!["pipe.csv"]);
}

/// (c) negative (and other bad) numbers are answered by one line naming the option.
#[test]
fn negative_numbers_are_named_by_option() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t.csv");
    let cases: &[(&[&str], &str)] = &[
        (&["--duration", "-1"], "--duration"),
        (&["--dt", "-0.001"], "--dt"),
        (&["--friction", "-1"], "--friction"),
        (&["--every", "-1"], "--every"),
        (&["--tol", "-1"], "--tol"),
        (&["--armature", "-1"], "--armature"),
        (&["--duration", "-inf"], "--duration"),
        (&["--dt", "-1e-3"], "--dt"),
        (&["--armature", "nan"], "--armature"),
        (&["--armature", "inf"], "--armature"),
        (&["--above-ground", "nan"], "--above-ground"),
        (&["--above-ground", "-inf"], "--above-ground"),
        (&["--ground", "-inf"], "--ground"),
        (&["--gravity", "-nan,0,0"], "--gravity"),
        (&["--every", "-x"], "--every"),
    ];
    for (args, opt) in cases {
        let o = lamp(&out, args);
        let err = stderr(&o);
        assert!(!o.status.success(), "{args:?} accepted: {err}");
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains(opt), "{args:?}: {err}");
        assert!(!err.contains("unexpected argument"), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert!(o.stdout.is_empty());
        assert!(names(dir.path()).is_empty(), "{args:?} left a file");
    }
    // negative values that are fine are accepted
    for args in [
        &["--ground", "-0.25"][..],
        &["--gravity", "0,0,-1.62"][..],
        &["--above-ground", "-0.01"][..],
    ] {
        let o = lamp(&out, args);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
        check_lamp_csv(&std::fs::read_to_string(&out).unwrap());
    }
    // bench: --samples -1 names --samples
    let o = urdyn()
        .arg("bench")
        .arg(root().join("assets/lamp.urdf"))
        .args(["--samples", "-1"])
        .output()
        .unwrap();
    let err = stderr(&o);
    assert!(!o.status.success());
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("--samples") && !err.contains("unexpected"),
        "{err}"
    );
}

/// `--above-ground` without `--floating-base`: one line naming both.
#[test]
fn above_ground_needs_a_floating_base() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t.csv");
    let o = urdyn()
        .arg("simulate")
        .arg(root().join("assets/lamp.urdf"))
        .args(["--duration", "0.01", "--above-ground", "0.1", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let err = stderr(&o);
    assert!(!o.status.success());
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("--above-ground") && err.contains("--floating-base"),
        "{err}"
    );
    assert!(names(dir.path()).is_empty());
}

/// (d) `eval --output LINK`: the link is kept, its target holds what stdout gets.
#[test]
fn eval_writes_through_a_symlink() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("target.json");
    let link = dir.path().join("LINK");
    symlink("target.json", &link).unwrap();
    let eval = |output: Option<&Path>| {
        let mut c = urdyn();
        c.arg("eval")
            .arg(root().join("assets/robots/ur5.urdf"))
            .arg("--states")
            .arg(root().join("tests/fixtures/ur5/states.json"));
        if let Some(p) = output {
            c.arg("--output").arg(p);
        }
        c.output().unwrap()
    };
    let o = eval(Some(&link));
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(o.stdout.is_empty());
    assert!(is_symlink(&link), "LINK was replaced");
    let written = std::fs::read(&target).unwrap();
    let expected = eval(None);
    assert!(expected.status.success());
    assert_eq!(written, expected.stdout);
    // again, over the existing target
    std::fs::write(&target, "previous").unwrap();
    let o = eval(Some(&link));
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(is_symlink(&link));
    assert_eq!(std::fs::read(&target).unwrap(), expected.stdout);
    assert_eq!(names(dir.path()), vec!["LINK", "target.json"]);
}

/// (e) a failed run leaves no file: not at a new path, not behind a dangling
/// link (the link stays, its target is not created), and an existing target is
/// left as it was.
#[test]
fn a_failed_run_leaves_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let init = dir.path().join("bad_initial.json");
    std::fs::write(&init, r#"{"base": {"positon": [0, 0, 1]}}"#).unwrap();
    let run = |out: &Path| {
        urdyn()
            .arg("simulate")
            .arg(root().join("assets/lamp.urdf"))
            .args(["--floating-base", "--duration", "0.05", "--initial"])
            .arg(&init)
            .arg("--out")
            .arg(out)
            .output()
            .unwrap()
    };
    let check = |o: &Output| {
        let err = stderr(o);
        assert!(!o.status.success());
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(
            err.contains("bad_initial.json") && err.contains("positon"),
            "{err}"
        );
        assert!(o.stdout.is_empty());
    };
    let new = dir.path().join("new.csv");
    check(&run(&new));
    assert_eq!(names(dir.path()), vec!["bad_initial.json"]);

    let link = dir.path().join("LINK");
    symlink("target.csv", &link).unwrap();
    check(&run(&link));
    assert!(is_symlink(&link));
    assert_eq!(names(dir.path()), vec!["LINK", "bad_initial.json"]);

    std::fs::write(dir.path().join("target.csv"), "previous").unwrap();
    check(&run(&link));
    assert_eq!(
        std::fs::read_to_string(dir.path().join("target.csv")).unwrap(),
        "previous"
    );
    assert_eq!(
        names(dir.path()),
        vec!["LINK", "bad_initial.json", "target.csv"]
    );
}
