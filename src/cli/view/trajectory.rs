//! The trajectory a page replays: the CSV reader, the frame sampler and the
//! recorder that keeps the shown frames' body poses.

use super::{ViewError, FRAME_RATE, MAX_POSE_BYTES};
use crate::dynamics::forward_kinematics;
use crate::model::Data;
use crate::Model;
use nalgebra::{DVector, Rotation3, UnitQuaternion};

/// The rows of a trajectory CSV: times, configurations and the plotted columns
/// (NaN where the CSV has no such column).
#[derive(Clone, Debug, Default)]
pub struct TrajectoryRows {
    /// `t` of every row, as written.
    pub times: Vec<f64>,
    /// q of every row (engine order; a floating base's quaternion normalised).
    pub q: Vec<DVector<f64>>,
    /// `energy` per row.
    pub energy: Vec<f64>,
    /// `contacts` per row.
    pub contacts: Vec<f64>,
    /// `penetration` per row.
    pub penetration: Vec<f64>,
}

impl TrajectoryRows {
    /// Last time minus first time (0 for fewer than two rows).
    pub fn duration(&self) -> f64 {
        match (self.times.first(), self.times.last()) {
            (Some(a), Some(b)) => b - a,
            _ => 0.0,
        }
    }
}

/// Reads a trajectory CSV (cli.md's format) for `model`: a `t` column and a
/// `q:NAME` column for every coordinate of the model, in any order; other columns
/// are read if they are `energy`, `contacts`, `penetration` and otherwise ignored.
/// Every error names `file` and the column or row (rows counted from 1 after the
/// header, lines from 1).
pub fn read_trajectory(text: &str, file: &str, model: &Model) -> Result<TrajectoryRows, ViewError> {
    let bad = |m: String| ViewError::Csv(format!("{file}: {m}"));
    let mut lines = text.lines().enumerate();
    let header: Vec<&str> = match lines.next() {
        Some((_, h)) if !h.trim().is_empty() => h.split(',').map(str::trim).collect(),
        _ => return Err(bad("empty file (no header row)".into())),
    };
    let col = |name: &str| header.iter().position(|h| *h == name);
    let (q_names, _) = crate::sim::column_names(model);
    let t_col = col("t").ok_or_else(|| bad("no \"t\" column in the header".into()))?;
    let mut q_cols = Vec::with_capacity(q_names.len());
    for n in &q_names {
        q_cols.push(col(n).ok_or_else(|| {
            bad(format!(
                "no \"{n}\" column: the trajectory does not fit this URDF{}",
                if model.floating_base {
                    " (with --floating-base)"
                } else {
                    ""
                }
            ))
        })?);
    }
    // A q column for a joint the model does not have: the CSV is another robot's.
    if let Some(extra) = header
        .iter()
        .find(|h| h.starts_with("q:") && !q_names.iter().any(|n| n == *h))
    {
        return Err(bad(format!(
            "column \"{extra}\" names no degree of freedom of this URDF{}",
            if extra.starts_with("q:base_") && !model.floating_base {
                " (simulated with --floating-base?)"
            } else {
                ""
            }
        )));
    }
    let plot_cols = [col("energy"), col("contacts"), col("penetration")];
    let mut rows = TrajectoryRows::default();
    for (row, (line_no, line)) in lines.enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let at = format!("row {} (line {})", row + 1, line_no + 1);
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        if cells.len() != header.len() {
            return Err(bad(format!(
                "{at} has {} cells, the header {} columns (a truncated row?)",
                cells.len(),
                header.len()
            )));
        }
        let num = |c: usize| -> Result<f64, ViewError> {
            let cell = cells.get(c).copied().unwrap_or("");
            let name = header.get(c).copied().unwrap_or("?");
            match cell.parse::<f64>() {
                Ok(x) if x.is_finite() => Ok(x),
                _ => Err(bad(format!(
                    "{at}, column \"{name}\": \"{}\" is not a finite number",
                    cell.chars().take(40).collect::<String>()
                ))),
            }
        };
        let t = num(t_col)?;
        if let Some(&prev) = rows.times.last() {
            if t < prev {
                return Err(bad(format!(
                    "{at}, column \"t\": time {t} goes back (the previous row has {prev})"
                )));
            }
        }
        let mut q = DVector::zeros(model.nq);
        for (k, &c) in q_cols.iter().enumerate() {
            q[k] = num(c)?;
        }
        for f in &model.free_joints {
            let i = f.iq + 3;
            let n = (q[i] * q[i] + q[i + 1] * q[i + 1] + q[i + 2] * q[i + 2] + q[i + 3] * q[i + 3])
                .sqrt();
            if (n - 1.0).abs() > 1e-3 {
                return Err(bad(format!(
                    "{at}, columns \"q:{0}_qx\"..\"q:{0}_qw\": the quaternion's norm is {n}, not 1",
                    f.name
                )));
            }
            for k in i..i + 4 {
                q[k] /= n;
            }
        }
        // spherical and floating joints inside the tree: their quaternions as written
        crate::model::configuration::normalize_quats(model, &mut q);
        let mut plot = [f64::NAN; 3];
        for (p, c) in plot.iter_mut().zip(plot_cols) {
            if let Some(c) = c {
                *p = num(c)?;
            }
        }
        rows.times.push(t);
        rows.q.push(q);
        rows.energy.push(plot[0]);
        rows.contacts.push(plot[1]);
        rows.penetration.push(plot[2]);
    }
    if rows.times.is_empty() {
        return Err(bad("no data rows after the header".into()));
    }
    Ok(rows)
}

/// Chooses which rows a page shows: the first, then the first row at or after
/// each multiple of the frame interval from it (and, by the caller, the last).
#[derive(Clone, Debug)]
pub struct FrameSampler {
    interval: f64,
    start: Option<f64>,
    next: f64,
}

impl FrameSampler {
    /// A sampler for a run of `duration` seconds whose frames cost
    /// `bytes_per_frame` each: [`FRAME_RATE`] frames a second, fewer when the
    /// poses would pass [`MAX_POSE_BYTES`].
    pub fn new(duration: f64, bytes_per_frame: usize) -> Self {
        let max_frames = (MAX_POSE_BYTES / bytes_per_frame.max(1)).max(2) as f64;
        let interval = (1.0 / FRAME_RATE).max(duration.max(0.0) / (max_frames - 1.0));
        Self {
            interval,
            start: None,
            next: f64::NEG_INFINITY,
        }
    }
    /// Whether the row at time `t` is shown (rows come in time order).
    pub fn take(&mut self, t: f64) -> bool {
        // (a tolerance of a millionth of the interval for times like 0.1 + 0.2)
        let eps = self.interval * 1e-6;
        let start = *self.start.get_or_insert(t);
        if t < self.next - eps {
            return false;
        }
        let k = ((t - start + eps) / self.interval).floor() + 1.0;
        self.next = start + k * self.interval;
        true
    }
}

/// A contact point and the force on the link there (world frame), for the page.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactArrow {
    /// The point (m).
    pub point: [f64; 3],
    /// The force (N).
    pub force: [f64; 3],
}

/// Collects a page's frames: offered rows (time, q, plotted values, contacts)
/// are kept as [`FrameSampler`] says, and the body poses of kept rows computed by
/// forward kinematics.
#[derive(Clone, Debug)]
pub struct Recorder {
    sampler: FrameSampler,
    model: Model,
    data: Data,
    pub(super) nmoving: usize,
    /// Whether contacts are recorded (`simulate --html`).
    pub with_contacts: bool,
    /// Times of the kept rows.
    pub times: Vec<f64>,
    /// Per kept row and moving body (1..nbodies): position.
    pub positions: Vec<f64>,
    /// Per kept row and moving body: rotation as a quaternion (x, y, z, w).
    pub rotations: Vec<f32>,
    /// Per kept row: energy, contact count, penetration (NaN if unknown).
    pub plot: Vec<[f64; 3]>,
    /// Contact arrows of all kept rows; row k's are `arrows[offsets[k]..offsets[k + 1]]`.
    pub arrows: Vec<ContactArrow>,
    /// Start of each kept row's arrows (one more entry than rows).
    pub offsets: Vec<usize>,
}

impl Recorder {
    /// A recorder for a run of `duration` seconds of `model`.
    pub fn new(model: &Model, duration: f64, with_contacts: bool) -> Self {
        let nmoving = model.nbodies.saturating_sub(1);
        let sampler = FrameSampler::new(duration, nmoving * 40);
        // the frames the sampler will keep (and the last), allocated here
        // rather than grown while the simulation runs
        let est = duration.max(0.0) / sampler.interval;
        let frames = if est.is_finite() {
            est.min(1e5) as usize + 3
        } else {
            2
        };
        let mut offsets = Vec::with_capacity(frames + 1);
        offsets.push(0);
        Self {
            sampler,
            model: model.clone(),
            data: Data::new(model),
            nmoving,
            with_contacts,
            times: Vec::with_capacity(frames),
            positions: Vec::with_capacity(frames * 3 * nmoving),
            rotations: Vec::with_capacity(frames * 4 * nmoving),
            plot: Vec::with_capacity(frames),
            arrows: Vec::with_capacity(if with_contacts { frames * 4 } else { 0 }),
            offsets,
        }
    }

    /// Offers a row; it is kept if the sampler takes it or `last` is set (the
    /// run's final row).
    pub fn offer(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        plot: [f64; 3],
        arrows: &[ContactArrow],
        last: bool,
    ) {
        self.offer_with(t, q, plot, last, |out| out.extend_from_slice(arrows))
    }

    /// As [`Recorder::offer`], the contact arrows pushed by `arrows` only if the
    /// row is kept (they cost nothing otherwise).
    pub fn offer_with(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        plot: [f64; 3],
        last: bool,
        arrows: impl FnOnce(&mut Vec<ContactArrow>),
    ) {
        let taken = self.sampler.take(t);
        if !(taken || (last && self.times.last() != Some(&t))) {
            return;
        }
        self.keep(t, q, plot);
        if self.with_contacts {
            arrows(&mut self.arrows);
        }
        self.offsets.push(self.arrows.len());
    }

    fn keep(&mut self, t: f64, q: &DVector<f64>, plot: [f64; 3]) {
        // q is nq long (the CSV reader and the simulation size it): the size
        // check cannot fail, and a frame without poses is never kept
        if forward_kinematics(&self.model, &mut self.data, q).is_err() {
            return;
        }
        for m in self.data.o_m_i.iter().skip(1).take(self.nmoving) {
            self.positions.extend_from_slice(m.trans.as_slice());
            let r = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(m.rot));
            let c = r.coords;
            self.rotations
                .extend_from_slice(&[c.x as f32, c.y as f32, c.z as f32, c.w as f32]);
        }
        self.times.push(t);
        self.plot.push(plot);
    }
}
