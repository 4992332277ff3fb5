//! `urdyn bench` (cli.md): times each dynamics algorithm on random states of a
//! model, single-threaded, the way the Pinocchio bench does (shared/tools/
//! pinocchio-bench): a fixed-seed pool of states, a warm-up, then samples that each
//! time a batch of calls (sized to about 50 µs) cycling over the pool; the per-call
//! time of a sample is batch time / batch size; outputs go through `black_box`.

use crate::dynamics::{self, ConstraintData};
use crate::model::{Constraints, Data, JointKind, Model};
use nalgebra::DVector;
use serde_json::{json, Map, Value};
use std::hint::black_box;
use std::time::{Duration, Instant};

/// One timed algorithm.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Algo {
    /// `rnea`: inverse dynamics τ = ID(q, v, a) ([`dynamics::rnea`]).
    Rnea,
    /// `bias`: C(q, v) = ID(q, v, 0) ([`dynamics::bias`]).
    Bias,
    /// `crba`: the upper triangle of H(q) ([`dynamics::crba_upper`], Pinocchio's work).
    Crba,
    /// `aba`: forward dynamics by the articulated-body algorithm ([`dynamics::aba`]).
    Aba,
    /// `fd-rnea`: forward dynamics by nv + 1 inverse dynamics calls
    /// ([`dynamics::forward_dynamics_rnea`]).
    FdRnea,
    /// CRBA + RNEA bias + LTDL (dense Cholesky with mimic joints).
    FdCrba,
    /// `fd`: the engine's forward dynamics, by the model's chosen method
    /// ([`dynamics::forward_dynamics`]).
    Fd,
    /// `fk`: forward kinematics of every body and frame.
    Fk,
    /// `rnea-derivatives`: ∂τ/∂q, ∂τ/∂v (and H) ([`dynamics::rnea_derivatives`]).
    RneaDerivatives,
    /// `aba-derivatives`: ∂q̈/∂q, ∂q̈/∂v, H⁻¹ ([`dynamics::aba_derivatives`]).
    AbaDerivatives,
    /// `jacobians`: every body's world Jacobian ([`dynamics::joint_jacobians`],
    /// Pinocchio's `computeJointJacobians`).
    Jacobians,
    /// `constraint-dynamics`: q̈ and λ under the loop constraints
    /// ([`dynamics::constraint_dynamics`]; needs constraints, cli.md `--hold`).
    ConstraintDynamics,
    /// `constraint-dynamics-derivatives`: the constrained q̈ and its derivatives
    /// together ([`dynamics::constraint_dynamics_derivatives`]).
    ConstraintDynamicsDerivatives,
}

impl Algo {
    /// Every algorithm, in the order `bench` times and prints them.
    pub const ALL: [Algo; 11] = [
        Algo::Rnea,
        Algo::Bias,
        Algo::Crba,
        Algo::Aba,
        Algo::FdRnea,
        Algo::FdCrba,
        Algo::Fd,
        Algo::Fk,
        Algo::RneaDerivatives,
        Algo::AbaDerivatives,
        Algo::Jacobians,
    ];
    /// The algorithms that need constraints (timed by default when some are given).
    pub const CONSTRAINED: [Algo; 2] = [
        Algo::ConstraintDynamics,
        Algo::ConstraintDynamicsDerivatives,
    ];
    /// The command-line name (`--algo`, and the key in `--json`).
    pub fn name(self) -> &'static str {
        match self {
            Algo::Rnea => "rnea",
            Algo::Bias => "bias",
            Algo::Crba => "crba",
            Algo::Aba => "aba",
            Algo::FdRnea => "fd-rnea",
            Algo::FdCrba => "fd-crba",
            Algo::Fd => "fd",
            Algo::Fk => "fk",
            Algo::RneaDerivatives => "rnea-derivatives",
            Algo::AbaDerivatives => "aba-derivatives",
            Algo::Jacobians => "jacobians",
            Algo::ConstraintDynamics => "constraint-dynamics",
            Algo::ConstraintDynamicsDerivatives => "constraint-dynamics-derivatives",
        }
    }
    /// The algorithm of a command-line name; `None` for an unknown name.
    pub fn from_name(s: &str) -> Option<Algo> {
        Algo::ALL
            .into_iter()
            .chain(Algo::CONSTRAINED)
            .find(|a| a.name() == s)
    }
}

/// Why a benchmark could not run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BenchError {
    /// An `--algo` name that is not one of [`Algo::ALL`] (the name given).
    #[error("unknown algorithm \"{0}\" (known: rnea, bias, crba, aba, fd-rnea, fd-crba, fd, fk, rnea-derivatives, aba-derivatives, jacobians, constraint-dynamics, constraint-dynamics-derivatives)")]
    UnknownAlgo(String),
    /// `--samples 0`.
    #[error("--samples must be at least 1")]
    NoSamples,
    /// A dynamics call failed on a benchmark state.
    #[error("{algo}: {message}")]
    Dynamics {
        /// The algorithm's command-line name.
        algo: &'static str,
        /// The dynamics error, as text.
        message: String,
    },
}

/// Median and minimum nanoseconds per call over the samples.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Timing {
    /// Median time per call over the samples (ns).
    pub median_ns: f64,
    /// Fastest sample's time per call (ns).
    pub min_ns: f64,
    /// Samples taken (fewer than asked when the budget ran out, never below 5).
    pub samples: usize,
    /// Calls per sample (a batch of about 50 µs).
    pub batch: usize,
}

/// SplitMix64: a small, fixed-seed generator (reproducible states, no dependency).
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    /// A generator starting from `seed` (the same seed gives the same sequence).
    pub fn new(seed: u64) -> Self {
        Rng(seed)
    }
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
}

/// A state: configuration, velocity, acceleration and generalized force.
#[derive(Clone, Debug)]
pub struct State {
    /// Configuration (nq).
    pub q: DVector<f64>,
    /// Velocity (nv).
    pub v: DVector<f64>,
    /// Acceleration (nv).
    pub a: DVector<f64>,
    /// Generalized force (nv; N·m or N per joint).
    pub tau: DVector<f64>,
}

/// A random state: joint q uniform within the joint limits (or [−π, π] when they
/// are missing, infinite or wider than that), a free base at a position in
/// [−1, 1]³ with a uniform unit quaternion (Shoemake); v, a, τ uniform in [−1, 1].
pub fn random_state(model: &Model, rng: &mut Rng) -> State {
    use std::f64::consts::PI;
    let mut q = model.neutral();
    if model.floating_base {
        for k in 0..3 {
            q[k] = rng.uniform(-1.0, 1.0);
        }
        let (u1, u2, u3) = (rng.unit(), rng.unit() * 2.0 * PI, rng.unit() * 2.0 * PI);
        let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
        q[3] = a * u2.sin();
        q[4] = a * u2.cos();
        q[5] = b * u3.sin();
        q[6] = b * u3.cos();
    }
    // joints of several degrees of freedom: a uniform rotation (and a position
    // in [−1, 1]³ for a floating joint), a planar joint's x, y in [−1, 1], θ in [−π, π]
    for d in &model.dofs {
        let iq = d.iq;
        let mut quat = |q: &mut DVector<f64>, at: usize| {
            let (u1, u2, u3) = (rng.unit(), rng.unit() * 2.0 * PI, rng.unit() * 2.0 * PI);
            let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
            q[at] = a * u2.sin();
            q[at + 1] = a * u2.cos();
            q[at + 2] = b * u3.sin();
            q[at + 3] = b * u3.cos();
        };
        match d.kind {
            JointKind::Spherical => quat(&mut q, iq),
            JointKind::Free => {
                quat(&mut q, iq + 3);
                for k in 0..3 {
                    q[iq + k] = rng.uniform(-1.0, 1.0);
                }
            }
            JointKind::Planar => {
                q[iq] = rng.uniform(-1.0, 1.0);
                q[iq + 1] = rng.uniform(-1.0, 1.0);
                q[iq + 2] = rng.uniform(-PI, PI);
            }
            _ => {
                let (lo, hi) = match (d.limits.lower, d.limits.upper) {
                    (Some(l), Some(u)) if l < u && l >= -PI && u <= PI => (l, u),
                    _ => (-PI, PI),
                };
                q[iq] = rng.uniform(lo, hi);
            }
        }
    }
    let mut vec = |n: usize| DVector::from_fn(n, |_, _| rng.uniform(-1.0, 1.0));
    let v = vec(model.nv);
    let a = vec(model.nv);
    let tau = vec(model.nv);
    State { q, v, a, tau }
}

/// A pool of `n` random states from a fixed seed.
pub fn random_states(model: &Model, n: usize, seed: u64) -> Vec<State> {
    let mut rng = Rng::new(seed);
    (0..n).map(|_| random_state(model, &mut rng)).collect()
}

/// What to time and how long.
#[derive(Clone, Debug)]
pub struct BenchOptions {
    /// The algorithms to time, in this order (default: [`Algo::ALL`]).
    pub algos: Vec<Algo>,
    /// Samples per algorithm (lowered for slow calls by `budget`, never below 5).
    pub samples: usize,
    /// Soft time limit per algorithm.
    pub budget: Duration,
    /// The loop constraints of the constrained algorithms, as the contract's
    /// JSON objects (mechanisms.md); world anchors left out are placed where
    /// their link is in the first sampled state.
    pub constraints: Vec<Value>,
}

impl Default for BenchOptions {
    fn default() -> Self {
        Self {
            algos: Algo::ALL.to_vec(),
            samples: 300,
            budget: Duration::from_millis(1500),
            constraints: Vec::new(),
        }
    }
}

const POOL: usize = 64;
const SEED: u64 = 0x5EED_0DD5;

/// A matrix's (0, 0) entry, 0 when it is empty (a model without degrees of freedom).
fn corner(m: &nalgebra::DMatrix<f64>) -> f64 {
    m.get((0, 0)).copied().unwrap_or(0.0)
}

/// One call of `algo` on `s`; returns a number derived from the output (kept alive
/// through `black_box`).
#[inline(never)]
fn call(
    algo: Algo,
    model: &Model,
    data: &mut Data,
    cx: &mut Option<(Constraints, ConstraintData)>,
    s: &State,
) -> Result<f64, String> {
    Ok(match algo {
        Algo::ConstraintDynamics | Algo::ConstraintDynamicsDerivatives => {
            let (c, cd) = cx
                .as_mut()
                .ok_or("needs constraints: --hold, --hold6 or --weld")?;
            if algo == Algo::ConstraintDynamics {
                dynamics::constraint_dynamics(model, data, cd, c, &s.q, &s.v, &s.tau, None)
                    .map_err(|e| e.to_string())?
                    .get(0)
                    .copied()
                    .unwrap_or(0.0)
            } else {
                dynamics::constraint_dynamics_derivatives(
                    model, data, cd, c, &s.q, &s.v, &s.tau, None,
                )
                .map_err(|e| e.to_string())?;
                corner(&cd.dqdd_dq) + corner(&cd.dqdd_dv) + corner(&cd.dqdd_dtau)
            }
        }
        Algo::Rnea => dynamics::rnea(model, data, &s.q, &s.v, &s.a, None)
            .map_err(|e| e.to_string())?
            .get(0)
            .copied()
            .unwrap_or(0.0),
        Algo::Bias => dynamics::bias(model, data, &s.q, &s.v, None)
            .map_err(|e| e.to_string())?
            .get(0)
            .copied()
            .unwrap_or(0.0),
        // H's upper triangle, the work of Pinocchio's crba (mass_matrix mirrors it)
        Algo::Crba => dynamics::crba_upper(model, data, &s.q)
            .map_err(|e| e.to_string())?
            .get((0, 0))
            .copied()
            .unwrap_or(0.0),
        Algo::Aba => dynamics::aba(model, data, &s.q, &s.v, &s.tau, None)
            .map_err(|e| e.to_string())?
            .get(0)
            .copied()
            .unwrap_or(0.0),
        Algo::FdRnea => dynamics::forward_dynamics_rnea(model, data, &s.q, &s.v, &s.tau, None)
            .map_err(|e| e.to_string())?
            .get(0)
            .copied()
            .unwrap_or(0.0),
        Algo::FdCrba => dynamics::forward_dynamics_crba(model, data, &s.q, &s.v, &s.tau, None)
            .map_err(|e| e.to_string())?
            .get(0)
            .copied()
            .unwrap_or(0.0),
        Algo::Fd => dynamics::forward_dynamics(model, data, &s.q, &s.v, &s.tau, None)
            .map_err(|e| e.to_string())?
            .get(0)
            .copied()
            .unwrap_or(0.0),
        Algo::Fk => {
            dynamics::forward_kinematics(model, data, &s.q).map_err(|e| e.to_string())?;
            dynamics::update_frames(model, data);
            data.o_m_f.last().map_or(0.0, |m| m.trans.x)
        }
        Algo::RneaDerivatives => {
            dynamics::rnea_derivatives(model, data, &s.q, &s.v, &s.a, None)
                .map_err(|e| e.to_string())?;
            corner(&data.dtau_dq) + corner(&data.dtau_dv)
        }
        Algo::AbaDerivatives => {
            dynamics::aba_derivatives(model, data, &s.q, &s.v, &s.tau, None)
                .map_err(|e| e.to_string())?;
            corner(&data.dqdd_dq) + corner(&data.dqdd_dv) + corner(&data.minv)
        }
        Algo::Jacobians => dynamics::joint_jacobians(model, data, &s.q)
            .map_err(|e| e.to_string())?
            .get((0, 0))
            .copied()
            .unwrap_or(0.0),
    })
}

/// Times one algorithm. Models with no degree of freedom time as usual.
pub fn time_algo(model: &Model, algo: Algo, opts: &BenchOptions) -> Result<Timing, BenchError> {
    if opts.samples == 0 {
        return Err(BenchError::NoSamples);
    }
    let states = random_states(model, POOL, SEED);
    let mut data = Data::new(model);
    let err = |m: String| BenchError::Dynamics {
        algo: algo.name(),
        message: m,
    };
    let mut cx = if Algo::CONSTRAINED.contains(&algo) && !opts.constraints.is_empty() {
        let mut c =
            Constraints::from_json(model, &opts.constraints).map_err(|e| BenchError::Dynamics {
                algo: algo.name(),
                message: e.to_string(),
            })?;
        if let Some(s0) = states.first() {
            dynamics::forward_kinematics(model, &mut data, &s0.q)
                .map_err(|e| err(e.to_string()))?;
            c.place_holds(&data);
        }
        let cd = ConstraintData::new(model, &c);
        Some((c, cd))
    } else {
        None
    };
    let nstates = states.len();
    // Warm-up (at least 20 ms) and a first estimate of the per-call time.
    let start = Instant::now();
    let mut calls = 0usize;
    while start.elapsed() < Duration::from_millis(20) || calls < 3 {
        black_box(
            call(
                algo,
                model,
                &mut data,
                &mut cx,
                black_box(&states[calls % nstates]),
            )
            .map_err(err)?,
        );
        calls += 1;
    }
    let per_call = start.elapsed().as_secs_f64() / calls as f64;
    let batch = ((50e-6 / per_call).round() as usize).max(1);
    let sample_time = per_call * batch as f64;
    let samples = if sample_time * opts.samples as f64 > opts.budget.as_secs_f64() {
        ((opts.budget.as_secs_f64() / sample_time) as usize)
            .clamp(5.min(opts.samples), opts.samples)
    } else {
        opts.samples
    };
    let mut per = Vec::with_capacity(samples);
    let mut k = 0usize;
    for _ in 0..samples {
        let t0 = Instant::now();
        for _ in 0..batch {
            let s = black_box(&states[k]);
            k += 1;
            if k == nstates {
                k = 0;
            }
            black_box(call(algo, model, &mut data, &mut cx, s).map_err(err)?);
        }
        per.push(t0.elapsed().as_nanos() as f64 / batch as f64);
    }
    per.sort_by(f64::total_cmp);
    let median_ns = if per.len() % 2 == 1 {
        per[per.len() / 2]
    } else {
        0.5 * (per[per.len() / 2 - 1] + per[per.len() / 2])
    };
    Ok(Timing {
        median_ns,
        min_ns: per[0],
        samples,
        batch,
    })
}

/// Times every requested algorithm. An algorithm that cannot run on this model
/// (`aba` on a mimic model) is left out with a note in the returned list.
pub fn run(
    model: &Model,
    opts: &BenchOptions,
) -> Result<(Vec<(Algo, Timing)>, Vec<String>), BenchError> {
    let mut out = Vec::new();
    let mut notes = Vec::new();
    for &algo in &opts.algos {
        if algo == Algo::Aba && model.has_mimic {
            notes.push("aba skipped: the model has mimic joints (fd uses CRBA)".to_string());
            continue;
        }
        out.push((algo, time_algo(model, algo, opts)?));
    }
    Ok((out, notes))
}

/// The `--json` object of cli.md.
pub fn to_json(model: &Model, results: &[(Algo, Timing)]) -> Value {
    let mut r = Map::new();
    for (a, t) in results {
        r.insert(
            a.name().to_string(),
            json!({"median_ns": t.median_ns, "min_ns": t.min_ns}),
        );
    }
    json!({"robot": model.name, "nq": model.nq, "nv": model.nv, "results": r})
}

/// A table for people.
pub fn to_table(model: &Model, results: &[(Algo, Timing)]) -> String {
    // the name column as wide as the longest name shown (at least 16)
    let w = results
        .iter()
        .map(|(a, _)| a.name().len())
        .max()
        .unwrap_or(0)
        .max(16);
    let mut s = format!(
        "{}: nq {}, nv {}, {} bodies, fd method {:?}\n{:<w$} {:>12} {:>12} {:>8} {:>7}\n",
        model.name,
        model.nq,
        model.nv,
        model.nbodies - 1,
        model.topology.fd_method,
        "algo",
        "median ns",
        "min ns",
        "samples",
        "batch"
    );
    for (a, t) in results {
        s.push_str(&format!(
            "{:<w$} {:>12.1} {:>12.1} {:>8} {:>7}\n",
            a.name(),
            t.median_ns,
            t.min_ns,
            t.samples,
            t.batch
        ));
    }
    s
}
