//! MJCF import against MuJoCo 4.0 (fixtures by tests/oracle/make_mjcf_fixtures.py):
//! per body mass, centre of mass and inertia within 1e-10; at 5 random states H with
//! armature, bias, tau, qdd within 1e-10 relative and every body's pose within
//! 1e-12, on every Gymnasium and dm_control model MuJoCo compiles (dog.xml's bodies
//! take their mass from its bone meshes).

use nalgebra::{DMatrix, DVector};
use serde_json::Value;
use std::path::Path;
use urdyn::dynamics_f64 as dynamics;

fn dir() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/mjcf")
}

fn vecf(v: &Value) -> Vec<f64> {
    v.as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

fn close(what: &str, got: &[f64], want: &[f64], tol: f64) -> Result<(), String> {
    if got.len() != want.len() {
        return Err(format!(
            "{what}: {} entries, MuJoCo {}",
            got.len(),
            want.len()
        ));
    }
    let scale = want.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    for (k, (g, w)) in got.iter().zip(want).enumerate() {
        if (g - w).abs() > tol * scale || g.is_nan() {
            return Err(format!(
                "{what}[{k}]: urdyn {g}, MuJoCo {w} (scale {scale})"
            ));
        }
    }
    Ok(())
}

/// Every check of one fixture; the first failure's description.
fn check(fixture: &Path) -> Result<usize, String> {
    let fx: Value = serde_json::from_str(&std::fs::read_to_string(fixture).unwrap()).unwrap();
    let file = dir().join(fx["model"].as_str().unwrap());
    let model = urdyn::mjcf::load_file(&file).map_err(|e| e.to_string())?;
    if model.nq != fx["nq"].as_u64().unwrap() as usize
        || model.nv != fx["nv"].as_u64().unwrap() as usize
    {
        return Err(format!(
            "nq, nv = {}, {}; MuJoCo {}, {}",
            model.nq, model.nv, fx["nq"], fx["nv"]
        ));
    }
    let mut checks = 0;
    for (name, b) in fx["bodies"].as_object().unwrap() {
        let own = model
            .report
            .bodies
            .iter()
            .find(|l| &l.name == name)
            .ok_or_else(|| format!("body {name} missing"))?;
        close(
            &format!("{name} mass"),
            &[own.mass],
            &[b["mass"].as_f64().unwrap()],
            1e-10,
        )?;
        close(
            &format!("{name} com"),
            own.com.as_slice(),
            &vecf(&b["com"]),
            1e-10,
        )?;
        let want: Vec<f64> = b["inertia"]
            .as_array()
            .unwrap()
            .iter()
            .flat_map(vecf)
            .collect();
        let got: Vec<f64> = (0..3)
            .flat_map(|r| (0..3).map(move |c| (r, c)))
            .map(|(r, c)| own.inertia[(r, c)])
            .collect();
        close(&format!("{name} inertia"), &got, &want, 1e-10)?;
        checks += 1;
    }
    let arm = model.armature().unwrap_or_else(|| DVector::zeros(model.nv));
    let mut data = urdyn::Data::new(&model);
    for (i, s) in fx["states"].as_array().unwrap().iter().enumerate() {
        let q = DVector::from_vec(vecf(&s["q"]));
        let v = DVector::from_vec(vecf(&s["v"]));
        let a = DVector::from_vec(vecf(&s["a"]));
        let tau_in = DVector::from_vec(vecf(&s["tau_in"]));
        let mut h = dynamics::mass_matrix(&model, &mut data, &q)
            .map_err(|e| e.to_string())?
            .clone();
        for k in 0..model.nv {
            h[(k, k)] += arm[k];
        }
        let want_h: Vec<f64> = s["mass_matrix"]
            .as_array()
            .unwrap()
            .iter()
            .flat_map(vecf)
            .collect();
        let got_h: Vec<f64> = h.transpose().iter().copied().collect();
        close(&format!("state {i} H"), &got_h, &want_h, 1e-10)?;
        let bias = dynamics::bias(&model, &mut data, &q, &v, None)
            .map_err(|e| e.to_string())?
            .clone();
        close(
            &format!("state {i} bias"),
            bias.as_slice(),
            &vecf(&s["bias"]),
            1e-10,
        )?;
        let tau = dynamics::rnea(&model, &mut data, &q, &v, &a, None)
            .map_err(|e| e.to_string())?
            .clone()
            + arm.component_mul(&a);
        close(
            &format!("state {i} tau"),
            tau.as_slice(),
            &vecf(&s["tau"]),
            1e-10,
        )?;
        let mut l = DMatrix::zeros(model.nv, model.nv);
        dynamics::linalg::cholesky(&h, &mut l).map_err(|k| format!("H singular at {k}"))?;
        let mut qdd = &tau_in - &bias;
        dynamics::linalg::cholesky_solve(&l, &mut qdd);
        close(
            &format!("state {i} qdd"),
            qdd.as_slice(),
            &vecf(&s["qdd"]),
            1e-10,
        )?;
        dynamics::forward_kinematics(&model, &mut data, &q).map_err(|e| e.to_string())?;
        dynamics::update_frames(&model, &mut data);
        for (name, p) in s["poses"].as_object().unwrap() {
            let f = model
                .frame_index(name)
                .ok_or_else(|| format!("no frame {name}"))?;
            let m = &data.o_m_f[f];
            let mut got = m.trans.as_slice().to_vec();
            for r in 0..3 {
                for c in 0..3 {
                    got.push(m.rot[(r, c)]);
                }
            }
            let want = vecf(p);
            for (k, (g, w)) in got.iter().zip(&want).enumerate() {
                if (g - w).abs() > 1e-12 || g.is_nan() {
                    return Err(format!(
                        "state {i} pose of {name}[{k}]: urdyn {g}, MuJoCo {w}"
                    ));
                }
            }
        }
        checks += 1;
    }
    Ok(checks)
}

#[test]
fn mjcf_models_match_mujoco() {
    let mut fixtures: Vec<_> = std::fs::read_dir(dir().join("oracle"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    fixtures.sort();
    assert!(fixtures.len() >= 32, "fixtures missing: {}", fixtures.len());
    let mut bad = Vec::new();
    for f in &fixtures {
        let stem = f.file_stem().unwrap().to_string_lossy().to_string();
        match check(f) {
            Ok(n) => eprintln!("{stem}: {n} checks pass"),
            Err(e) => bad.push(format!("{stem}: {e}")),
        }
    }
    assert!(
        bad.is_empty(),
        "{} of {} models differ from MuJoCo:\n{}",
        bad.len(),
        fixtures.len(),
        bad.join("\n")
    );
}

/// The comparison sees what it checks: Gymnasium's ant without its armature (1.0 on
/// each leg joint) differs from MuJoCo's H, and a capsule's mass moved by 1e-9
/// relative differs from MuJoCo's body mass.
#[test]
fn mjcf_comparison_sees_a_difference() {
    let fx: Value = serde_json::from_str(
        &std::fs::read_to_string(dir().join("oracle/gymnasium_ant.json")).unwrap(),
    )
    .unwrap();
    let model = urdyn::mjcf::load_file(dir().join("gymnasium/ant.xml")).unwrap();
    let mut data = urdyn::Data::new(&model);
    let s = &fx["states"][0];
    let q = DVector::from_vec(vecf(&s["q"]));
    let h = dynamics::mass_matrix(&model, &mut data, &q)
        .unwrap()
        .clone();
    let want: Vec<f64> = s["mass_matrix"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(vecf)
        .collect();
    let got: Vec<f64> = h.transpose().iter().copied().collect();
    assert!(close("H", &got, &want, 1e-10).is_err());
    let torso = model
        .report
        .bodies
        .iter()
        .find(|b| b.name == "torso")
        .unwrap();
    let m = fx["bodies"]["torso"]["mass"].as_f64().unwrap();
    assert!(close("mass", &[torso.mass], &[m], 1e-10).is_ok());
    assert!(close("mass", &[torso.mass * (1.0 + 1e-9)], &[m], 1e-10).is_err());
}

/// `<joint springdamper="τ ζ">` (dm_control dog's 21 tail joints): stiffness and
/// damping as MuJoCo 4.0.0 compiles them (`m.jnt_stiffness`, `m.dof_damping` printed
/// by `mujoco.MjModel.from_xml_path(dog.xml)`, 2026-12-03); urdyn read the attribute
/// and left both 0 before.
#[test]
fn mjcf_springdamper_matches_mujocos_compiled_stiffness_and_damping() {
    let model = urdyn::mjcf::load_file(dir().join("dm_control/dog.xml")).expect("dog.xml");
    let want = [
        ("Ca_1_extend", 0.0806406488611183, 0.4032032443055914),
        ("Ca_10_bend", 0.04962579130133998, 0.24812895650669986),
        ("Ca_15_extend", 0.04544200341892538, 0.22721001709462688),
        ("Ca_19_extend", 0.04063014961672653, 0.20315074808363262),
    ];
    for (name, k, b) in want {
        let d = model
            .dofs
            .iter()
            .find(|d| d.name == name)
            .unwrap_or_else(|| panic!("no dof {name}"));
        assert!(
            (d.stiffness - k).abs() <= 1e-9 * k && (d.damping - b).abs() <= 1e-9 * b,
            "{name}: stiffness {} damping {}, MuJoCo {k} {b}",
            d.stiffness,
            d.damping
        );
    }
}

/// The closed form on one hinge fixed to the world: m = I_axis + armature, so
/// k = m / (τ² ζ²), b = 2 m / τ (a sphere of mass 2, radius 0.1 at 0.3 from the
/// axis: I = 2·(0.4·0.01 + 0.09) = 0.188; armature 0.012 gives m = 0.2).
#[test]
fn mjcf_springdamper_on_a_pendulum_is_the_closed_form() {
    let xml = r#"<mujoco><worldbody><body>
        <joint name="h" type="hinge" axis="0 1 0" armature="0.012" stiffness="7" damping="9" springdamper="0.02 0.5"/>
        <geom type="sphere" size="0.1" pos="0.3 0 0" mass="2"/>
      </body></worldbody></mujoco>"#;
    let model = urdyn::mjcf::load_str(xml, "pend.xml", Path::new(".")).expect("pendulum");
    let d = &model.dofs[0];
    let m = 2.0 * (0.4 * 0.01 + 0.09) + 0.012;
    let (k, b) = (m / (0.02f64.powi(2) * 0.25), 2.0 * m / 0.02);
    assert!(
        (d.stiffness - k).abs() <= 1e-12 * k,
        "{} vs {k}",
        d.stiffness
    );
    assert!((d.damping - b).abs() <= 1e-12 * b, "{} vs {b}", d.damping);
}
