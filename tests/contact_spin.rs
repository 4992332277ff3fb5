//! Torsional and rolling friction (src/sim/constraints/spin.rs, docs/theory.md
//! §"Torsional and rolling friction"). Truth from outside: the closed form of
//! a body rolling without slip against a rolling-resistance torque μ_r·N, and
//! of one spinning on a point against a torsional torque μ_τ·N.
//!
//! Rolling, forward speed v, radius R, mass m, inertia I about the rolling axis:
//! m v̇ = F (the contact's friction), I ω̇ = −F R − μ_r m g, ω = v/R, so
//! v̇ = −μ_r m g R / (I + m R²): a constant deceleration a, the body stops
//! after v₀/a having travelled v₀²/(2a).

use nalgebra::DVector;
use urdyn::contact::ContactParams;
use urdyn::sim::{SimOptions, Simulation};
use urdyn::{load_str, LoadOptions};

const FLOAT: LoadOptions = LoadOptions {
    floating_base: true,
};
const G: f64 = 9.81;

/// A solid body of mass `m` whose collision shape is `shape` (its axis of
/// symmetry along y for a cylinder), inertia `(i_xz, i_y)`.
fn body(shape: &str, m: f64, i_xz: f64, i_y: f64) -> urdyn::model::Model {
    let urdf = format!(
        r#"<robot name="roller"><link name="roller">
<inertial><mass value="{m}"/><inertia ixx="{i_xz}" iyy="{i_y}" izz="{i_xz}" ixy="0" ixz="0" iyz="0"/></inertial>
<collision><origin xyz="0 0 0" rpy="1.5707963267948966 0 0"/><geometry>{shape}</geometry></collision>
</link></robot>"#
    );
    load_str(&urdf, "roller.urdf", FLOAT).unwrap()
}

fn sim_with(model: urdyn::model::Model, torsion: f64, rolling: f64) -> Simulation {
    let opts = SimOptions {
        dt: 1e-3,
        ground: Some(0.0),
        contact: ContactParams {
            friction: 1.0,
            torsion,
            rolling,
            ..Default::default()
        },
        sleep: false,
        ..Default::default()
    };
    Simulation::new(model, opts).unwrap()
}

/// Rolls the body (radius `r`, resting on the ground) forward along x at
/// `v0` for `t` seconds; returns the distance travelled along x.
fn roll(sim: &mut Simulation, r: f64, v0: f64, t: f64) -> f64 {
    let mut q = sim.q().clone();
    q[2] = r;
    let mut v = DVector::zeros(6);
    // body-frame twist at the identity orientation: v along x, ω about y
    v[0] = v0;
    v[4] = v0 / r;
    sim.set_state(&q, &v).unwrap();
    let x0 = sim.q()[0];
    while sim.time() < t - 1e-9 {
        sim.step().unwrap();
    }
    sim.q()[0] - x0
}

#[test]
fn rolling_friction_slows_a_ball_at_the_closed_form_rate() {
    let (m, r, v0, mu_r) = (2.0, 0.1, 1.0, 0.01);
    // a solid ball (I = 2/5 m R²) rolling at 1 m/s (a cylinder on its side
    // touches at its two exact rim points and, as it turns, at the rim's
    // sampled vertices passing the bottom (src/contact/ground): it knocks
    // from vertex to vertex, and no closed form holds)
    let cases = [(
        "ball",
        format!(r#"<sphere radius="{r}"/>"#),
        0.4 * m * r * r,
        0.4 * m * r * r,
    )];
    for (name, shape, i_xz, i_y) in cases {
        let a = mu_r * m * G * r / (i_y + m * r * r);
        let t_stop = v0 / a;
        // halfway to the stop: x = v₀t − ½at²; and at rest: v₀²/(2a)
        let mut sim = sim_with(body(&shape, m, i_xz, i_y), 0.005, mu_r);
        let th = 0.5 * t_stop;
        let x_half = roll(&mut sim, r, v0, th);
        let want_half = v0 * th - 0.5 * a * th * th;
        let mut sim = sim_with(body(&shape, m, i_xz, i_y), 0.005, mu_r);
        let x_end = roll(&mut sim, r, v0, t_stop + 0.5);
        let want_end = v0 * v0 / (2.0 * a);
        let speed = sim.v().rows(0, 3).norm();
        eprintln!(
            "{name}: a = {a:.4} m/s², stop at {t_stop:.3} s; x({th:.3}) = {x_half:.5} (closed form {want_half:.5}), \
             x at rest = {x_end:.5} ({want_end:.5}), final speed {speed:.2e}"
        );
        assert!(
            (x_half - want_half).abs() < 5e-3 * want_half,
            "{name}: {x_half} vs {want_half}"
        );
        assert!(
            (x_end - want_end).abs() < 5e-3 * want_end,
            "{name}: {x_end} vs {want_end}"
        );
        assert!(speed < 1e-6, "{name} still moving at {speed}");
    }
}

#[test]
fn without_rolling_friction_a_ball_keeps_rolling() {
    let (m, r, v0) = (2.0, 0.1, 1.0);
    for (name, shape, i_xz, i_y) in [(
        "ball",
        format!(r#"<sphere radius="{r}"/>"#),
        0.4 * m * r * r,
        0.4 * m * r * r,
    )] {
        let mut sim = sim_with(body(&shape, m, i_xz, i_y), 0.0, 0.0);
        let x = roll(&mut sim, r, v0, 2.0);
        eprintln!(
            "{name} without rolling friction: x(2 s) = {x:.6} (v₀t = {:.6})",
            2.0 * v0
        );
        assert!((x - 2.0 * v0).abs() < 1e-3 * 2.0 * v0, "{name}: {x}");
    }
}

/// A ball spinning about the vertical at ω₀ on one point: the torsional
/// torque μ_τ m g stops it at the rate I ω̇ = −μ_τ m g (I = 2/5 m R²), and
/// without torsion it keeps spinning.
#[test]
fn torsional_friction_stops_a_spinning_ball_at_the_closed_form_rate() {
    let (m, r, w0, mu_t) = (2.0, 0.1, 5.0, 0.005);
    let i = 0.4 * m * r * r;
    let alpha = mu_t * m * G / i;
    for (torsion, want) in [(mu_t, w0 - alpha * 0.1), (0.0, w0)] {
        let shape = format!(r#"<sphere radius="{r}"/>"#);
        let mut sim = sim_with(body(&shape, m, i, i), torsion, 1e-4);
        let mut q = sim.q().clone();
        q[2] = r;
        let mut v = DVector::zeros(6);
        v[5] = w0;
        sim.set_state(&q, &v).unwrap();
        while sim.time() < 0.1 - 1e-9 {
            sim.step().unwrap();
        }
        let w = sim.v()[5];
        eprintln!("torsion {torsion}: ω(0.1 s) = {w:.6} (closed form {want:.6})");
        assert!((w - want).abs() < 1e-3 * w0, "{w} vs {want}");
    }
}
