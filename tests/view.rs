//! `urdyn view` and `urdyn simulate --html` (issue 15): the page is one
//! self-contained file whose frames are rows of the CSV and whose base poses are
//! the CSV's; a CSV that does not fit the URDF is one line naming the CSV and the
//! column or row, a non-zero exit and no page. (The page running in a browser is
//! checked by tests/browser/view_check.py, which `.ci/run` runs.)

use crate::common::csv::read_csv;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn urdyn(args: &[&std::ffi::OsStr]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_urdyn"))
        .args(args)
        .output()
        .unwrap()
}

fn lamp() -> PathBuf {
    root().join("assets/lamp.urdf")
}

/// Simulates the lamp drop for `duration` s into `dir/lamp.csv` and `dir/sim.html`.
fn simulate_lamp(dir: &Path, duration: &str) -> (PathBuf, PathBuf) {
    let (csv, html) = (dir.join("lamp.csv"), dir.join("sim.html"));
    let o = Command::new(env!("CARGO_BIN_EXE_urdyn"))
        .arg("simulate")
        .arg(lamp())
        .args(["--floating-base", "--duration", duration, "--initial"])
        .arg(root().join("assets/lamp_initial.json"))
        .arg("--out")
        .arg(&csv)
        .arg("--html")
        .arg(&html)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    (csv, html)
}

/// The page's embedded data object.
fn page_data(html: &str) -> serde_json::Value {
    let start_tag = r#"<script id="urdyn-data" type="application/json">"#;
    let start = html.find(start_tag).expect("data script") + start_tag.len();
    let len = html[start..].find("</script>").expect("end of data");
    serde_json::from_str(&html[start..start + len]).unwrap()
}

/// Standard base64 decoding (written here independently of the page writer).
fn unbase64(s: &str) -> Vec<u8> {
    let val = |c: u8| -> u32 {
        match c {
            b'A'..=b'Z' => (c - b'A') as u32,
            b'a'..=b'z' => (c - b'a') as u32 + 26,
            b'0'..=b'9' => (c - b'0') as u32 + 52,
            b'+' => 62,
            b'/' => 63,
            _ => panic!("not base64: {c}"),
        }
    };
    let mut out = Vec::new();
    for chunk in s.as_bytes().chunks(4) {
        let pad = chunk.iter().filter(|&&c| c == b'=').count();
        let n = chunk
            .iter()
            .map(|&c| if c == b'=' { 0 } else { val(c) })
            .fold(0u32, |n, v| (n << 6) | v);
        let bytes = [(n >> 16) as u8, (n >> 8) as u8, n as u8];
        out.extend_from_slice(&bytes[..3 - pad]);
    }
    out
}

/// The page's `times`, read from the page's text with Rust's exact float parser
/// (serde_json's default one may be off by an ulp).
fn times_of(html: &str) -> Vec<f64> {
    let start = html.find("\"times\":[").expect("times") + "\"times\":[".len();
    let len = html[start..].find(']').unwrap();
    html[start..start + len]
        .split(',')
        .map(|t| t.parse::<f64>().unwrap())
        .collect()
}

#[test]
fn pages_hold_csv_rows_and_base_poses() {
    let dir = tempfile::tempdir().unwrap();
    let (csv, sim_html) = simulate_lamp(dir.path(), "3");
    let view_html = dir.path().join("view.html");
    let o = urdyn(&[
        "view".as_ref(),
        lamp().as_os_str(),
        csv.as_os_str(),
        "--floating-base".as_ref(),
        "--out".as_ref(),
        view_html.as_os_str(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (header, rows) = read_csv(&csv);
    let col = |n: &str| header.iter().position(|h| h == n).unwrap();
    let csv_times: Vec<f64> = rows.iter().map(|r| r[0]).collect();
    for (page, with_contacts) in [(&sim_html, true), (&view_html, false)] {
        let html = std::fs::read_to_string(page).unwrap();
        assert!(html.starts_with("<!DOCTYPE html>"));
        assert!(html.len() < 1_000_000, "{} bytes", html.len());
        for needle in ["http://", "https://", "src=", "<link", "{{"] {
            assert!(!html.contains(needle), "{page:?} contains {needle}");
        }
        let data = page_data(&html);
        // Frames: rows of the CSV, the first and last kept, 60 a second.
        let times = times_of(&html);
        assert_eq!(times.first(), csv_times.first());
        assert_eq!(times.last(), csv_times.last());
        assert_eq!(times.len(), 181, "{times:?}");
        for w in times.windows(2) {
            assert!(w[1] - w[0] > 1.0 / 60.0 - 1.5e-3 && w[1] - w[0] < 1.0 / 60.0 + 1.5e-3);
        }
        // The base (body 1) pose of each frame is its CSV row's q.
        let moving = data["moving"].as_u64().unwrap() as usize;
        assert_eq!(moving, 4);
        let pos: Vec<f64> = unbase64(data["positions"].as_str().unwrap())
            .chunks_exact(8)
            .map(|b| f64::from_le_bytes(b.try_into().unwrap()))
            .collect();
        let rot: Vec<f32> = unbase64(data["rotations"].as_str().unwrap())
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
            .collect();
        assert_eq!(pos.len(), times.len() * moving * 3);
        assert_eq!(rot.len(), times.len() * moving * 4);
        for (k, t) in times.iter().enumerate() {
            let row = &rows[csv_times.iter().position(|x| x == t).unwrap()];
            for (i, c) in ["q:base_x", "q:base_y", "q:base_z"].iter().enumerate() {
                assert!((pos[k * moving * 3 + i] - row[col(c)]).abs() < 1e-12);
            }
            let q: Vec<f64> = ["q:base_qx", "q:base_qy", "q:base_qz", "q:base_qw"]
                .iter()
                .map(|c| row[col(c)])
                .collect();
            let dot: f64 = (0..4).map(|i| q[i] * rot[k * moving * 4 + i] as f64).sum();
            assert!((dot.abs() - 1.0).abs() < 1e-6, "frame {k}: {dot}");
        }
        // Every URDF link is a frame; the lamp's 7 visuals are drawn.
        let mut links: Vec<&str> = data["links"]
            .as_array()
            .unwrap()
            .iter()
            .map(|l| l["name"].as_str().unwrap())
            .collect();
        links.sort();
        assert_eq!(links, ["base", "lower_arm", "shade", "upper_arm"]);
        assert_eq!(data["visuals"].as_array().unwrap().len(), 7);
        // Contacts only in simulate's page: offsets per frame, arrows of 6 floats.
        if with_contacts {
            let offsets = data["contactForces"]["offsets"].as_array().unwrap();
            assert_eq!(offsets.len(), times.len() + 1);
            let arrows = unbase64(data["contactForces"]["arrows"].as_str().unwrap());
            assert_eq!(
                arrows.len(),
                offsets.last().unwrap().as_u64().unwrap() as usize * 24
            );
            // The lamp stands on the ground at the end: its last frame has contacts
            // whose forces hold its weight (2.25 kg).
            let last = offsets.len() - 2;
            let (a, b) = (
                offsets[last].as_u64().unwrap() as usize,
                offsets[last + 1].as_u64().unwrap() as usize,
            );
            assert!(b > a);
            let fz: f64 = (a..b)
                .map(|i| {
                    let o = i * 24 + 20;
                    f32::from_le_bytes(arrows[o..o + 4].try_into().unwrap()) as f64
                })
                .sum();
            assert!((fz - 2.25 * 9.81).abs() < 0.05 * 2.25 * 9.81, "{fz}");
        } else {
            assert!(data["contactForces"].is_null());
        }
    }
}

/// Runs `view` on the lamp with `csv_text`, expecting one line naming the CSV and
/// each of `expect`, a non-zero exit and no page (nor temporary file) left.
fn assert_rejected(csv_text: &str, floating: bool, expect: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("traj.csv");
    std::fs::write(&csv, csv_text).unwrap();
    let page = dir.path().join("page.html");
    let lamp_path = lamp();
    let mut args: Vec<&std::ffi::OsStr> =
        vec!["view".as_ref(), lamp_path.as_os_str(), csv.as_os_str()];
    if floating {
        args.push("--floating-base".as_ref());
    }
    args.extend(["--out".as_ref(), page.as_os_str()]);
    let o = urdyn(&args);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(!o.status.success(), "accepted: {expect:?}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains(&csv.display().to_string()), "{err}");
    for e in expect {
        assert!(err.contains(e), "{err} lacks {e}");
    }
    assert!(o.stdout.is_empty());
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left, vec![std::ffi::OsString::from("traj.csv")], "{err}");
}

#[test]
fn csv_that_does_not_fit_is_one_line_and_no_page() {
    let dir = tempfile::tempdir().unwrap();
    let (csv, _) = simulate_lamp(dir.path(), "0.02");
    let good = std::fs::read_to_string(&csv).unwrap();
    // Other joint names.
    assert_rejected(
        &good.replacen("q:elbow", "q:knee", 1),
        true,
        &["\"q:elbow\""],
    );
    // A truncated last row (the file cut mid-row).
    let cut = &good[..good.trim_end().rfind(',').unwrap()];
    let last_row = good.lines().count() - 1;
    assert_rejected(cut, true, &[&format!("row {last_row} ")]);
    // A non-numeric cell, in row 3.
    let mut lines: Vec<String> = good.lines().map(String::from).collect();
    let header: Vec<String> = lines[0].split(',').map(String::from).collect();
    let k = header.iter().position(|h| *h == "q:shoulder").unwrap();
    let mut cells: Vec<String> = lines[3].split(',').map(String::from).collect();
    cells[k] = "abc".into();
    lines[3] = cells.join(",");
    assert_rejected(&lines.join("\n"), true, &["row 3", "\"q:shoulder\"", "abc"]);
    // A floating-base trajectory read without --floating-base.
    assert_rejected(&good, false, &["\"q:base_x\"", "--floating-base"]);
    // No header, no rows, a non-unit quaternion.
    assert_rejected("", true, &["empty"]);
    assert_rejected(lines[0].as_str(), true, &["no data rows"]);
    let qw = header.iter().position(|h| *h == "q:base_qw").unwrap();
    let mut cells: Vec<String> = lines[1].split(',').map(String::from).collect();
    cells[qw] = "3".into();
    lines[1] = cells.join(",");
    assert_rejected(&lines.join("\n"), true, &["row 1", "q:base_qw", "norm"]);
}

/// A one-link URDF whose link has `body` (visual and collision elements).
fn one_link(dir: &Path, body: &str) -> PathBuf {
    let urdf = dir.join("r.urdf");
    std::fs::write(
        &urdf,
        format!(
            r#"<robot name="r"><link name="a"><inertial><mass value="1"/>
<inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial>
{body}</link></robot>"#
        ),
    )
    .unwrap();
    urdf
}

/// `urdyn view URDF` of a one-row CSV into `dir/p.html`: the output and the page.
fn view_one_row(dir: &Path, urdf: &Path) -> (Output, PathBuf) {
    let csv = dir.join("t.csv");
    std::fs::write(&csv, "t,energy\n0,0\n").unwrap();
    let page = dir.join("p.html");
    let o = urdyn(&[
        "view".as_ref(),
        urdf.as_os_str(),
        csv.as_os_str(),
        "--out".as_ref(),
        page.as_os_str(),
    ]);
    (o, page)
}

#[test]
fn missing_visual_mesh_is_a_warning_and_the_collision_geometry_or_a_box_is_drawn() {
    let dir = tempfile::tempdir().unwrap();
    // No collision geometry: a placeholder box, and one warning line naming the
    // URDF, the link and the file.
    let urdf = one_link(
        dir.path(),
        r#"<visual><geometry><mesh filename="package://nowhere/foot.stl"/></geometry></visual>"#,
    );
    let (o, page) = view_one_row(dir.path(), &urdf);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let warnings: Vec<&str> = err.lines().filter(|l| l.contains("warning")).collect();
    assert_eq!(warnings.len(), 1, "{err}");
    for e in [
        urdf.display().to_string().as_str(),
        "link \"a\"",
        "package://nowhere/foot.stl",
        "not found",
        "placeholder box",
    ] {
        assert!(warnings[0].contains(e), "{err} lacks {e}");
    }
    let data = page_data(&std::fs::read_to_string(&page).unwrap());
    let visuals = data["visuals"].as_array().unwrap();
    assert_eq!(visuals.len(), 1, "{visuals:?}");
    assert_eq!(visuals[0]["link"], "a");
    assert_eq!(visuals[0]["kind"], "box");
    assert_eq!(visuals[0]["dims"], serde_json::json!([0.05, 0.05, 0.05]));
    // With collision geometry: that is drawn instead (a sphere 0.5 m up), the
    // visual box beside the missing mesh stays.
    let urdf = one_link(
        dir.path(),
        r#"<visual><geometry><mesh filename="package://nowhere/foot.stl"/></geometry></visual>
<visual><geometry><box size="1 2 3"/></geometry></visual>
<collision><origin xyz="0 0 0.5"/><geometry><sphere radius="0.2"/></geometry></collision>"#,
    );
    let (o, page) = view_one_row(dir.path(), &urdf);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("its collision geometry is drawn"), "{err}");
    let data = page_data(&std::fs::read_to_string(&page).unwrap());
    let kinds: Vec<(String, serde_json::Value, serde_json::Value)> = data["visuals"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| {
            (
                v["kind"].as_str().unwrap().to_string(),
                v["dims"].clone(),
                v["p"].clone(),
            )
        })
        .collect();
    assert_eq!(
        kinds,
        vec![
            (
                "box".into(),
                serde_json::json!([1.0, 2.0, 3.0]),
                serde_json::json!([0.0, 0.0, 0.0])
            ),
            (
                "sphere".into(),
                serde_json::json!([0.2]),
                serde_json::json!([0.0, 0.0, 0.5])
            ),
        ]
    );
    // simulate --html: the same warning, and the page is written.
    let out = dir.path().join("o.csv");
    std::fs::remove_file(&page).unwrap();
    let o = urdyn(&[
        "simulate".as_ref(),
        urdf.as_os_str(),
        "--duration".as_ref(),
        "0.01".as_ref(),
        "--out".as_ref(),
        out.as_os_str(),
        "--html".as_ref(),
        page.as_os_str(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("package://nowhere/foot.stl"), "{err}");
    assert!(page.exists() && out.exists());
}

#[test]
fn missing_collision_mesh_drawn_is_one_line_naming_it_and_no_page() {
    let dir = tempfile::tempdir().unwrap();
    // A link without visuals is drawn as its collision geometry: its mesh must exist.
    let urdf = one_link(
        dir.path(),
        r#"<collision><geometry><mesh filename="package://nowhere/foot.stl"/></geometry></collision>"#,
    );
    let (o, page) = view_one_row(dir.path(), &urdf);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    for e in [
        urdf.display().to_string().as_str(),
        "link \"a\"",
        "<collision>",
        "package://nowhere/foot.stl",
    ] {
        assert!(err.contains(e), "{err} lacks {e}");
    }
    assert!(!page.exists());
    // simulate --html reads the geometry before simulating: the same file named, no files.
    let out = dir.path().join("o.csv");
    let o = urdyn(&[
        "simulate".as_ref(),
        urdf.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
        "--html".as_ref(),
        page.as_os_str(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(err.contains("package://nowhere/foot.stl"), "{err}");
    assert!(!page.exists() && !out.exists());
}

/// Writes a binary STL of a UV sphere of radius `r` with 2·n² triangles.
fn sphere_stl(path: &Path, n: usize, r: f32) {
    let point = |i: usize, j: usize| {
        let th = std::f32::consts::PI * i as f32 / n as f32;
        let ph = 2.0 * std::f32::consts::PI * (j % n) as f32 / n as f32;
        [
            r * th.sin() * ph.cos(),
            r * th.sin() * ph.sin(),
            r * th.cos(),
        ]
    };
    let mut tris = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let (a, b, c, d) = (
                point(i, j),
                point(i, j + 1),
                point(i + 1, j),
                point(i + 1, j + 1),
            );
            tris.push([a, b, d]);
            tris.push([a, d, c]);
        }
    }
    let mut bytes = vec![0u8; 80];
    bytes.extend_from_slice(&(tris.len() as u32).to_le_bytes());
    for t in &tris {
        bytes.extend_from_slice(&[0u8; 12]);
        for p in t {
            for x in p {
                bytes.extend_from_slice(&x.to_le_bytes());
            }
        }
        bytes.extend_from_slice(&[0u8; 2]);
    }
    std::fs::write(path, bytes).unwrap();
}

#[test]
fn large_meshes_are_simplified_to_the_page_budget() {
    // Twelve distinct 80 000-triangle spheres (960 000 triangles, 48 MB of STL):
    // the page holds at most 150 000 triangles and stays under 3 MB, every mesh
    // simplified and still a sphere of radius 1 about its centre.
    let dir = tempfile::tempdir().unwrap();
    let mut body = String::new();
    for k in 0..12 {
        let stl = dir.path().join(format!("s{k}.stl"));
        sphere_stl(&stl, 200, 1.0);
        body += &format!(
            r#"<visual><origin xyz="{k} 0 0"/><geometry><mesh filename="s{k}.stl" scale="1 1 {}"/></geometry></visual>"#,
            1.0 + k as f64 * 1e-3
        );
    }
    let urdf = one_link(dir.path(), &body);
    let (o, page) = view_one_row(dir.path(), &urdf);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("12 meshes"), "{err}");
    assert!(err.contains("12 simplified"), "{err}");
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(html.len() < 3_000_000, "{} bytes", html.len());
    let data = page_data(&html);
    let mut total = 0;
    for m in data["meshes"].as_array().unwrap() {
        let wide = m["wide"].as_bool().unwrap();
        let idx = unbase64(m["i"].as_str().unwrap());
        let tris = idx.len() / if wide { 12 } else { 6 };
        total += tris;
        assert!(tris > 5_000, "{tris}");
        // dequantised vertices lie near the unit sphere (the clustering keeps
        // cluster means: inside, within a cell of the surface)
        let v = unbase64(m["v"].as_str().unwrap());
        let (min, ext) = (&m["min"], &m["ext"]);
        for c in v.chunks(6) {
            let p: Vec<f64> = (0..3)
                .map(|k| {
                    let q = u16::from_le_bytes([c[2 * k], c[2 * k + 1]]) as f64 / 65535.0;
                    min[k].as_f64().unwrap() + q * ext[k].as_f64().unwrap()
                })
                .collect();
            let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2] / 1.012f64.powi(2)).sqrt();
            assert!(r < 1.001 && r > 0.95, "{r}");
        }
    }
    assert!(total <= 150_000 && total > 60_000, "{total}");
    assert!(err.contains(&format!("{total} triangles")), "{err}");
}

/// The robots of assets/robots draw with the meshes shipped beside them: no
/// download, no warning, a small page with the DAE materials' colours.
#[test]
fn shipped_robots_draw_with_their_own_meshes() {
    let dir = tempfile::tempdir().unwrap();
    for robot in [
        "ur5",
        "panda",
        "solo12",
        "talos_reduced",
        "anymal",
        "icub_reduced",
        "tiago",
        "kinova",
    ] {
        let urdf = root().join(format!("assets/robots/{robot}.urdf"));
        // inspect: no missing mesh
        let o = Command::new(env!("CARGO_BIN_EXE_urdyn"))
            .arg("inspect")
            .arg(&urdf)
            .env_remove("ROS_PACKAGE_PATH")
            .output()
            .unwrap();
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(o.status.success(), "{robot}: {text}");
        assert!(!text.contains("not found"), "{robot}: {text}");
        // view (of a short run): every visual mesh found, the page under 1 MB
        let csv = dir.path().join(format!("{robot}.csv"));
        let o = Command::new(env!("CARGO_BIN_EXE_urdyn"))
            .arg("simulate")
            .arg(&urdf)
            .args(["--no-ground", "--duration", "0.002", "--out"])
            .arg(&csv)
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{robot}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let page = dir.path().join(format!("{robot}.html"));
        let o = urdyn(&[
            "view".as_ref(),
            urdf.as_os_str(),
            csv.as_os_str(),
            "--out".as_ref(),
            page.as_os_str(),
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{robot}: {err}");
        assert!(!err.contains("warning"), "{robot}: {err}");
        let html = std::fs::read_to_string(&page).unwrap();
        assert!(html.len() < 1_000_000, "{robot}: {} bytes", html.len());
        if robot == "ur5" {
            // its DAE visuals carry their materials' colours (base.dae: a light
            // and a dark grey), drawn per triangle group
            let data = page_data(&html);
            let mut colours = std::collections::BTreeSet::new();
            for m in data["meshes"].as_array().unwrap() {
                for g in m["groups"].as_array().into_iter().flatten() {
                    colours.insert(g[2].to_string());
                }
            }
            assert!(colours.len() >= 3, "{colours:?}");
            assert!(colours.iter().any(|c| c.contains("0.064")), "{colours:?}");
        }
    }
}

#[test]
fn simulate_html_says_where_it_wrote_the_page() {
    let dir = tempfile::tempdir().unwrap();
    let (csv, html) = (dir.path().join("lamp.csv"), dir.path().join("sim.html"));
    let o = Command::new(env!("CARGO_BIN_EXE_urdyn"))
        .arg("simulate")
        .arg(lamp())
        .args(["--floating-base", "--duration", "0.05", "--out"])
        .arg(&csv)
        .arg("--html")
        .arg(&html)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let line = err
        .lines()
        .find(|l| l.contains("replay page"))
        .unwrap_or_else(|| panic!("{err}"));
    assert!(line.contains(&html.display().to_string()), "{line}");
    let bytes = std::fs::metadata(&html).unwrap().len() as f64;
    assert!(line.contains(&format!("{:.2} MB", bytes / 1e6)), "{line}");
}
