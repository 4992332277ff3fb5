//! `urdyn simulate` when the start or the run goes wrong (cli.md): a warning
//! naming the link or joint for a start that violates the ground or a limit,
//! gentle recovery, `--above-ground`, every integrator with contact landing on
//! `--duration` without adding energy, and a diverging run that exits non-zero.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn simulate(args: &[&str], out: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_urdyn"))
        .arg("simulate")
        .args(args)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

use crate::common::csv::read_csv;

fn col(h: &[String], n: &str) -> usize {
    h.iter()
        .position(|x| x == n)
        .unwrap_or_else(|| panic!("no column {n}"))
}

fn legged() -> String {
    root()
        .join("tests/urdf/legged_box.urdf")
        .display()
        .to_string()
}

#[test]
fn diverging_run_exits_non_zero_with_the_error_and_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("T.csv");
    let urdf = root().join("tests/urdf/stiff_pendulum.urdf");
    let init = dir.path().join("init.json");
    std::fs::write(&init, r#"{"q": {"j": 0.5}}"#).unwrap();
    let o = simulate(
        &[
            urdf.to_str().unwrap(),
            "--integrator",
            "rk4",
            "--dt",
            "0.2",
            "--duration",
            "100",
            "--initial",
            init.to_str().unwrap(),
        ],
        &out,
    );
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "a diverging run exited 0: {stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("stiff_pendulum.urdf") && stderr.contains("diverging"),
        "{stderr}"
    );
    assert!(stderr.contains("v:j"), "names the quantity: {stderr}");
    assert!(!out.exists(), "a failed run left its trajectory");
    assert!(o.stdout.is_empty());
}

#[test]
fn start_outside_limits_warns_and_recovers_gently() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("T.csv");
    let o = simulate(
        &[
            &legged(),
            "--floating-base",
            "--no-ground",
            "--duration",
            "2",
        ],
        &out,
    );
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    let warnings: Vec<_> = stderr.lines().filter(|l| l.contains("limit")).collect();
    assert_eq!(warnings.len(), 2, "{stderr}");
    assert!(warnings
        .iter()
        .any(|l| l.contains("\"front_calf_joint\"") && l.contains("0.89")));
    assert!(warnings.iter().any(|l| l.contains("\"rear_calf_joint\"")));
    let (h, rows) = read_csv(&out);
    let (qf, vf) = (col(&h, "q:front_calf_joint"), col(&h, "v:front_calf_joint"));
    let vmax = rows.iter().map(|r| r[vf].abs()).fold(0.0, f64::max);
    assert!(vmax < 20.0, "joint speed {vmax} rad/s");
    let q_end = rows.last().unwrap()[qf];
    assert!(
        (-2.82 - 1e-3..=-0.89 + 1e-3).contains(&q_end),
        "q = {q_end}"
    );
}

#[test]
fn start_in_the_ground_warns_and_is_not_thrown() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("T.csv");
    let init = dir.path().join("init.json");
    // the body 0.1 m into the ground, the calves inside their limits
    std::fs::write(
        &init,
        r#"{"q": {"front_calf_joint": -1.2, "rear_calf_joint": -1.2},
            "base": {"position": [0, 0, -0.1], "orientation_xyzw": [0, 0, 0, 1]}}"#,
    )
    .unwrap();
    let o = simulate(
        &[
            &legged(),
            "--floating-base",
            "--duration",
            "3",
            "--initial",
            init.to_str().unwrap(),
        ],
        &out,
    );
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    let warnings: Vec<_> = stderr.lines().filter(|l| l.contains("ground")).collect();
    assert_eq!(warnings.len(), 1, "{stderr}");
    assert!(warnings[0].contains("inside the ground") && warnings[0].contains("m "));
    let (h, rows) = read_csv(&out);
    let ib: Vec<_> = ["v:base_vx", "v:base_vy", "v:base_vz"]
        .iter()
        .map(|n| col(&h, n))
        .collect();
    let speed = rows
        .iter()
        .map(|r| ib.iter().map(|&i| r[i] * r[i]).sum::<f64>().sqrt())
        .fold(0.0, f64::max);
    assert!(speed < 1.0, "base thrown at {speed} m/s");
    let pen = col(&h, "penetration");
    assert!(rows.last().unwrap()[pen] < 1e-3);
}

#[test]
fn above_ground_lifts_the_lowest_point() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("T.csv");
    let init = dir.path().join("init.json");
    std::fs::write(
        &init,
        r#"{"q": {"front_calf_joint": -1.2, "rear_calf_joint": -1.2}}"#,
    )
    .unwrap();
    let o = simulate(
        &[
            &legged(),
            "--floating-base",
            "--duration",
            "0.4",
            "--initial",
            init.to_str().unwrap(),
            "--above-ground",
            "0.3",
        ],
        &out,
    );
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "no warning expected: {stderr}");
    let (h, rows) = read_csv(&out);
    let (c, t) = (col(&h, "contacts"), col(&h, "t"));
    // a 0.3 m fall takes sqrt(2·0.3/9.81) = 0.247 s; the 5 mm margin sees it 2 ms early
    let first = rows.iter().find(|r| r[c] > 0.0).map(|r| r[t]).unwrap();
    assert!((first - 0.247).abs() < 0.006, "first contact at {first} s");
    // without collision geometry: a warning, nothing moved
    let bare = dir.path().join("bare.urdf");
    std::fs::write(
        &bare,
        r#"<robot name="bare"><link name="b"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link></robot>"#,
    )
    .unwrap();
    let o = simulate(
        &[
            bare.to_str().unwrap(),
            "--floating-base",
            "--duration",
            "0.01",
            "--above-ground",
            "0.3",
        ],
        &out,
    );
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(
        stderr
            .lines()
            .any(|l| l.contains("warning") && l.contains("--above-ground")),
        "{stderr}"
    );
}

#[test]
fn every_integrator_with_contact_lands_on_duration_without_energy_gain() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("T.csv");
    let init = dir.path().join("init.json");
    std::fs::write(
        &init,
        r#"{"q": {"front_calf_joint": -1.0, "rear_calf_joint": -2.0},
            "base": {"position": [0, 0, 0.5], "orientation_xyzw": [0.1, 0.05, 0, 0.9937]}}"#,
    )
    .unwrap();
    for integ in ["euler", "rk4", "dop853"] {
        let o = simulate(
            &[
                &legged(),
                "--floating-base",
                "--duration",
                "1.2345",
                "--integrator",
                integ,
                "--initial",
                init.to_str().unwrap(),
            ],
            &out,
        );
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{integ}: {stderr}");
        let (h, rows) = read_csv(&out);
        let (t, e) = (col(&h, "t"), col(&h, "energy"));
        assert_eq!(rows.last().unwrap()[t], 1.2345, "{integ}");
        // no sliver: every step at least a tenth of dt
        for w in rows.windows(2) {
            assert!(
                w[1][t] - w[0][t] > 1e-4,
                "{integ}: step {} at {}",
                w[1][t] - w[0][t],
                w[0][t]
            );
        }
        let e0 = rows[0][e];
        let emax = rows.iter().map(|r| r[e]).fold(f64::MIN, f64::max);
        assert!(
            emax <= e0 + 1e-3 * e0.abs() + 1e-3,
            "{integ}: energy {e0} -> max {emax}"
        );
    }
}
