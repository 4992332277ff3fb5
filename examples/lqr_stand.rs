//! An LQR built from urdyn's transition Jacobians holds a quadruped standing
//! against a push (docs/theory.md §"Transition Jacobians").
//!
//! The quadruped of `tests/urdf/quadruped.urdf` stands on its four sphere feet
//! under soft joint servos (kp 60, kd 3, part of the plant). At the standing
//! state x* the analytic A = ∂x'/∂x and B = ∂x'/∂τ of one 1 ms step are taken.
//! With the feet sticking, the feet's positions are uncontrollable modes
//! (eigenvalue 1: no torque moves a stuck foot), so the LQR is designed on the
//! complement: x = T z with T = diag(N, N), N an orthonormal basis of the null
//! space of the feet's contact Jacobian J_c, A_r = Tᵀ A T, B_r = Tᵀ B, the
//! discrete Riccati equation iterated to its fixed point, u = −K_r Tᵀ δx.
//! The base is then pushed to 0.5 m/s forward, with the joint rates that keep
//! the feet where they stand (J_c δv = 0: a push that slid the feet could not
//! be undone), and the controller brings it back.
//! Only the joints are actuated: the design takes B's joint columns (B's
//! base-wrench columns would be a force nobody applies).
//! Run: `cargo run --release --example lqr_stand [OUT_DIR]` (exit 1 if the base
//! does not come back within 1 cm); writes the replay page `OUT_DIR/lqr_stand.html`
//! (OUT_DIR defaults to `target`). Measured: back within 4.6 mm (farthest 25 mm), its
//! velocity below 1e-5 after 1.5 s; Q = 10·I, R = 1·I (env LQR_Q, LQR_R,
//! LQR_PUSH change them; LQR_R=1e12, the servos alone: 4.7 mm).
//! `LQR_SERVOS=0` switches the servos off once it stands and keeps their static
//! torques τ* as a feed-forward: the stance is then open-loop unstable (spectral
//! radius 1.0097 on the complement) and the LQR alone holds it, back within
//! 0.04 mm after pushes up to 0.2 m/s (farthest 9.2 mm); from 0.3 m/s it falls
//! (the linear design does not hold the feet on the ground that far out).

use nalgebra::{DMatrix, DVector, Vector3};
use std::path::PathBuf;
use urdyn::cli::view::{write_page, Geometry, Recorder};
use urdyn::dynamics_f64::{self as dynamics, Reference};
use urdyn::model::configuration::difference;
use urdyn::sim::{JacobianMethod, SimOptions, Simulation};
use urdyn::{Data, LoadOptions};

/// The standing servos' gains (N·m/rad, N·m·s/rad), the same on every joint.
const KP: f64 = 60.0;
const KD: f64 = 3.0;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let model = urdyn::load_file(
        root.join("tests/urdf/quadruped.urdf"),
        LoadOptions {
            floating_base: true,
        },
    )?;
    let n = model.nv;
    let mut sim = Simulation::new(model.clone(), SimOptions::default())?;
    // stand: the joints at (0.6, −1.2), the feet on the ground, settled 2 s
    let mut q = sim.q().clone();
    for (k, d) in model.dofs.iter().enumerate() {
        q[7 + k] = if d.name.ends_with("hip") { 0.6 } else { -1.2 };
    }
    q[2] = 0.4 * 0.6f64.cos() + 0.021;
    sim.set_gains_uniform(KP, KD)?;
    sim.set_targets(&q, None)?;
    sim.set_state(&q, &DVector::zeros(n))?;
    for _ in 0..2000 {
        sim.step()?;
    }
    let (qs, vs) = (sim.q().clone(), sim.v().clone());
    println!(
        "standing: base at z = {:.4} m, |v| = {:.1e}, {} contacts",
        qs[2],
        vs.norm(),
        sim.active_contacts()
    );
    // LQR_SERVOS=0: the servos off, their static torques τ* at the stance
    // kept as a feed-forward, and the LQR alone holds it (around τ*)
    let keep_servos = std::env::var("LQR_SERVOS").map_or(true, |s| s != "0");
    let mut tau0 = DVector::zeros(n);
    if !keep_servos {
        for k in 0..n - 6 {
            tau0[6 + k] = KP * (q[7 + k] - qs[7 + k]) - KD * vs[6 + k];
        }
        sim.set_gains_uniform(0.0, 0.0)?;
        sim.set_state(&qs, &vs)?;
    }
    // the step's Jacobians at the standing state
    let j = sim.transition_jacobians(&tau0, JacobianMethod::Analytic, 1e-6)?;
    // the feet's contact-point Jacobian (sphere feet: the point r below the centre)
    let mut data = Data::new(&model);
    dynamics::forward_kinematics(&model, &mut data, &qs)?;
    let feet = ["fl_foot", "fr_foot", "hl_foot", "hr_foot"];
    let mut jc = DMatrix::zeros(3 * feet.len(), n);
    let mut jf = DMatrix::zeros(6, n);
    for (i, f) in feet.iter().enumerate() {
        dynamics::frame_jacobian(
            &model,
            &data,
            model.frame_id(f)?,
            Reference::WorldAligned,
            &mut jf,
        )?;
        let r = Vector3::new(0.0, 0.0, 0.02);
        for c in 0..n {
            let w = Vector3::new(jf[(3, c)], jf[(4, c)], jf[(5, c)]);
            let v = Vector3::new(jf[(0, c)], jf[(1, c)], jf[(2, c)]) + r.cross(&w);
            for a in 0..3 {
                jc[(3 * i + a, c)] = v[a];
            }
        }
    }
    // N: the null space of J_c (right singular vectors past its rank)
    let svd = jc.clone().svd(false, true);
    let vt = svd.v_t.ok_or("svd")?;
    let smax = svd.singular_values.max();
    let rank = svd
        .singular_values
        .iter()
        .filter(|&&s| s > 1e-9 * smax)
        .count();
    let mut order: Vec<usize> = (0..svd.singular_values.len()).collect();
    order.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
    let mut basis: Vec<DVector<f64>> = order[..rank]
        .iter()
        .map(|&i| vt.row(i).transpose())
        .collect();
    // complete the row space to R^n, then keep the orthogonal complement
    let mut null = Vec::new();
    for k in 0..n {
        let mut e = DVector::zeros(n);
        e[k] = 1.0;
        for b in basis.iter().chain(null.iter()) {
            let d = e.dot(b);
            e.axpy(-d, b, 1.0);
        }
        if e.norm() > 1e-6 {
            let e = e.normalize();
            null.push(e);
        }
    }
    basis.clear();
    let k = null.len();
    let nn = DMatrix::from_columns(&null);
    let mut t = DMatrix::zeros(2 * n, 2 * k);
    t.view_mut((0, 0), (n, k)).copy_from(&nn);
    t.view_mut((n, k), (n, k)).copy_from(&nn);
    let ar = t.transpose() * &j.a * &t;
    // only the joints are actuated: B's base-wrench columns are left out
    let br = t.transpose() * j.b.columns(6, n - 6);
    println!(
        "J_c rank {rank}: LQR on {} of {} state dimensions",
        2 * k,
        2 * n
    );
    // discrete Riccati: P = Q + AᵀPA − AᵀPB (R + BᵀPB)⁻¹ BᵀPA
    let env = |k: &str, d: f64| {
        std::env::var(k)
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(d)
    };
    let qw = DMatrix::<f64>::identity(2 * k, 2 * k) * env("LQR_Q", 10.0);
    let rw = DMatrix::<f64>::identity(n - 6, n - 6) * env("LQR_R", 1.0);
    let mut p = qw.clone();
    let mut kr = DMatrix::zeros(n - 6, 2 * k);
    for it in 0..20000 {
        let s = &rw + br.transpose() * &p * &br;
        kr = s
            .lu()
            .solve(&(br.transpose() * &p * &ar))
            .ok_or("singular R + BᵀPB")?;
        let pn = &qw + ar.transpose() * &p * &ar - ar.transpose() * &p * &br * &kr;
        let change = (&pn - &p).norm() / pn.norm();
        p = pn;
        if change < 1e-12 {
            println!("Riccati converged in {it} iterations");
            break;
        }
    }
    let radius = |m: &DMatrix<f64>| {
        m.complex_eigenvalues()
            .iter()
            .map(|e| e.norm())
            .fold(0.0, f64::max)
    };
    let open_rho = radius(&ar);
    println!("open-loop spectral radius on the complement: {open_rho:.6}");
    let rho = radius(&(&ar - &br * &kr));
    println!("closed-loop spectral radius on the complement: {rho:.6}");
    // the push: base 0.5 m/s forward, joint rates keeping the feet in place
    let mut v = DVector::zeros(n);
    v[0] = env("LQR_PUSH", 0.5);
    let jb = jc.columns(0, 6).into_owned();
    let jj = jc.columns(6, n - 6).into_owned();
    let rhs = -(&jb * v.rows(0, 6));
    let qd = jj.svd(true, true).solve(&rhs, 1e-12)?;
    v.rows_mut(6, n - 6).copy_from(&qd);
    println!(
        "push: base 0.5 m/s, feet velocity residual {:.1e} m/s",
        (&jc * &v).norm()
    );
    sim.set_state(&qs, &v)?;
    // the replay page of the push and the recovery (3 s)
    let mut rec = Recorder::new(&model, 3.0, true);
    rec.offer(
        0.0,
        sim.q(),
        [
            sim.energy(),
            sim.active_contacts() as f64,
            sim.penetration(),
        ],
        &[],
        false,
    );
    let mut worst: f64 = 0.0;
    println!("   t (s)   base offset (mm)   |v| (m/s or rad/s)");
    for step in 1..=3000 {
        let dq = difference(&model, &qs, sim.q())?;
        let mut dx = DVector::zeros(2 * n);
        dx.rows_mut(0, n).copy_from(&dq);
        dx.rows_mut(n, n).copy_from(&(sim.v() - &vs));
        let u = -(&kr * (t.transpose() * dx));
        let mut tau = tau0.clone();
        tau.rows_mut(6, n - 6).axpy(1.0, &u, 1.0);
        sim.set_torques(&tau)?;
        sim.step()?;
        let plot = [
            sim.energy(),
            sim.active_contacts() as f64,
            sim.penetration(),
        ];
        rec.offer(step as f64 * 1e-3, sim.q(), plot, &[], step == 3000);
        let off = (sim.q().rows(0, 3) - qs.rows(0, 3)).norm();
        worst = worst.max(off);
        if step % 250 == 0 {
            println!(
                "{:8.3}   {:16.2}   {:.2e}",
                sim.time() - 2.0,
                1e3 * off,
                sim.v().norm()
            );
        }
    }
    let off = (sim.q().rows(0, 3) - qs.rows(0, 3)).norm();
    println!(
        "after 3 s: base {:.2} mm from where it stood (farthest {:.1} mm), {} contacts",
        1e3 * off,
        1e3 * worst,
        sim.active_contacts()
    );
    let out_dir = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("target"));
    std::fs::create_dir_all(&out_dir)?;
    let page = out_dir.join("lqr_stand.html");
    let geometry = Geometry::load(&model, &root.join("tests/urdf/quadruped.urdf"), &[])?;
    let summary = write_page(&page, &model, &geometry, &rec, Some(0.0))?;
    println!(
        "wrote {} ({} frames): the push and the recovery in 3D",
        page.display(),
        summary.frames
    );
    if off > 0.01 {
        eprintln!("the base did not come back within 1 cm");
        std::process::exit(1);
    }
    Ok(())
}
