//! Torsional and rolling friction of a contact (docs/theory.md §"Torsional
//! and rolling friction"): MuJoCo's `condim` 4 and 6 (`friction="slide
//! torsion roll"`) as rows of the same impulse solve as the rest.
//!
//! A contact point is a patch shrunk to a point; the patch's extent resists
//! spinning about the normal and rolling about a tangent. Where a shape
//! pair touches at three or more points the points' own Coulomb rows already
//! resist both (their lever arms are the patch), so the rows here are added
//! only where the pair has fewer points touching (a gap within the contact
//! slop; points found within the detection margin but apart carry no force
//! and make no patch), at those points:
//! - one point (a sphere, a disc on its rim, a corner): a torsion row
//!   `n·(ω_a − ω_b)` with |λ_τ| ≤ μ_τ λₙ, and a rolling pair
//!   `(t₁, t₂)·(ω_a − ω_b)` with ‖λ_r‖ ≤ μ_r λₙ;
//! - two points (a cylinder on its side, an edge): the rolling pair only
//!   (the two points' tangent rows already resist spin about the normal).
//!
//! Each is a [`RowKind::Tangent`] pair whose cone is a disc of radius μ λₙ
//! around the contact's normal row (the torsion's partner row is empty: a
//! one-dimensional cone), solved by the same projected Gauss–Seidel as the
//! Coulomb pair, so every update is a projection onto a convex set that only
//! removes energy. The rows come after every contact triple (a contact's
//! triple stays at rows 3c..3c+3), before the joint rows; their warm starts
//! are read back from the rows at the next assembly, by contact slot.

use super::{RowKind, Rows};
use crate::contact::{tangents, ContactPoint};
use crate::model::Model;
use crate::spatial::{Force, Motion};
use nalgebra::Vector3;

/// Which extra pair a row starts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Which {
    Roll,
    Torsion,
}

/// The extra rows' bookkeeping (sized at construction: nothing allocated in a step).
#[derive(Clone, Debug)]
pub(crate) struct Spin {
    /// Torsional friction coefficient μ_τ (m): |torque about n| ≤ μ_τ fₙ.
    pub torsion: f64,
    /// Rolling friction coefficient μ_r (m): ‖rolling torque‖ ≤ μ_r fₙ.
    pub rolling: f64,
    /// A point touches when its gap is at most this (m): the contact slop.
    pub touch: f64,
    /// Per contact slot: (roll₁, roll₂, torsion) impulses of the step stamped.
    warm: Vec<([f64; 3], u64)>,
    /// The assembly count (warm starts of an older stamp are stale).
    epoch: u64,
    /// This assembly's pairs: (first row, contact triple index, slot, which).
    pairs: Vec<(usize, usize, usize, Which)>,
}

impl Spin {
    /// Room for `max_points` contact points and `nslots` slots.
    pub fn new(max_points: usize, nslots: usize) -> Self {
        Self {
            torsion: 0.0,
            rolling: 0.0,
            touch: 1e-4,
            warm: vec![([0.0; 3], 0); nslots],
            epoch: 1,
            pairs: Vec::with_capacity(2 * max_points),
        }
    }

    /// Rows each contact point may add at most (for the row capacity).
    pub const MAX_ROWS_PER_POINT: usize = 4;

    /// Whether the rows are on.
    pub fn on(&self) -> bool {
        self.torsion > 0.0 || self.rolling > 0.0
    }

    /// Forgets the warm starts.
    pub fn reset(&mut self) {
        self.epoch += 2;
        self.pairs.clear();
    }

    /// Reads the last solve's impulses of the extra rows into the warm starts
    /// (before the rows are cleared).
    pub fn save(&mut self, rows: &Rows) {
        self.epoch += 1;
        for &(r, _, slot, which) in &self.pairs {
            let Some(w) = self.warm.get_mut(slot) else {
                continue;
            };
            if w.1 != self.epoch {
                *w = ([0.0; 3], self.epoch);
            }
            match which {
                Which::Roll => {
                    w.0[0] = rows.lambda[r];
                    w.0[1] = rows.lambda[r + 1];
                }
                Which::Torsion => w.0[2] = rows.lambda[r],
            }
        }
        self.pairs.clear();
    }

    /// Appends the extra rows of the contacts just assembled (triple c at rows
    /// 3c.., point `points[row_point[c]]`); `sw`: each body's world-frame
    /// motion subspace columns; `jd`: a zeroed scratch of 3·nv (left zeroed).
    pub fn push(
        &mut self,
        rows: &mut Rows,
        model: &Model,
        sw: &[[Motion; 6]],
        points: &[ContactPoint],
        row_point: &[usize],
        jd: &mut [f64],
    ) -> usize {
        if !self.on() {
            return 0;
        }
        let nv = rows.nv;
        let same = |a: &ContactPoint, b: &ContactPoint| {
            a.geom == b.geom
                && a.other_geom == b.other_geom
                && a.body == b.body
                && a.other == b.other
        };
        let mut added = 0;
        let mut c = 0;
        while c < row_point.len() {
            // the run of consecutive points of one shape pair
            let mut e = c + 1;
            while e < row_point.len() {
                match (points.get(row_point[c]), points.get(row_point[e])) {
                    (Some(a), Some(b)) if same(a, b) => e += 1,
                    _ => break,
                }
            }
            // the points that touch (a gap within `touch`): the patch
            let touching = |k: usize| {
                points
                    .get(row_point[k])
                    .is_some_and(|p| p.gap <= self.touch)
            };
            let count = (c..e).filter(|&k| touching(k)).count();
            for k in c..e {
                let Some(pt) = points.get(row_point[k]) else {
                    continue;
                };
                if !touching(k) {
                    continue;
                }
                let warm = match self.warm.get(pt.slot) {
                    Some(w) if !pt.fresh && w.1 == self.epoch => w.0,
                    _ => [0.0; 3],
                };
                let rn = 3 * k;
                let path = rows.path[rn];
                let (t1, t2) = tangents(&pt.normal);
                let mut wanted: [(Which, f64); 2] = [(Which::Roll, 0.0), (Which::Torsion, 0.0)];
                if count <= 2 {
                    wanted[0].1 = self.rolling;
                }
                if count == 1 {
                    wanted[1].1 = self.torsion;
                }
                for (which, mu) in wanted {
                    if !(mu > 0.0) || rows.n + 2 > rows.capacity() {
                        continue;
                    }
                    let tangent = RowKind::Tangent { normal: rn, mu };
                    let (w1, w2) = match which {
                        Which::Roll => (warm[0], warm[1]),
                        Which::Torsion => (warm[2], 0.0),
                    };
                    let Some(r) = rows.push(tangent, 0.0, w1, path) else {
                        continue;
                    };
                    if rows.push(RowKind::Tangent2, 0.0, w2, path).is_none() {
                        rows.pop(1);
                        continue;
                    }
                    // the relative angular velocity along the rows' axes
                    let axes = match which {
                        Which::Roll => [t1, t2],
                        Which::Torsion => [pt.normal, Vector3::zeros()],
                    };
                    for (start, sign) in [(pt.body, 1.0), (pt.other, -1.0)] {
                        let mut b = start;
                        while b != 0 {
                            let j = &model.joints[b];
                            for col in 0..j.nv().min(6) {
                                let w = sw[b][col].ang * sign;
                                let d = j.iv + col;
                                if d < nv {
                                    jd[d] += axes[0].dot(&w);
                                    jd[nv + d] += axes[1].dot(&w);
                                }
                            }
                            b = model.parent[b];
                        }
                    }
                    let (j0, rest) = jd.split_at_mut(nv);
                    rows.gather(r, j0);
                    rows.gather(r + 1, &mut rest[..nv]);
                    self.pairs.push((r, k, pt.slot, which));
                    added += 2;
                }
            }
            c = e;
        }
        added
    }

    /// Adds the extra rows' torques (λ/Δt about their axes) to the bodies'
    /// contact wrenches `fext` (world frame).
    pub fn add_torques(
        &self,
        rows: &Rows,
        points: &[ContactPoint],
        row_point: &[usize],
        fext: &mut [Force],
        h: f64,
    ) {
        for &(r, c, _, which) in &self.pairs {
            let Some(pt) = row_point.get(c).and_then(|&pi| points.get(pi)) else {
                continue;
            };
            let (t1, t2) = tangents(&pt.normal);
            let torque = match which {
                Which::Roll => t1 * rows.lambda[r] + t2 * rows.lambda[r + 1],
                Which::Torsion => pt.normal * rows.lambda[r],
            } / h;
            if let Some(f) = fext.get_mut(pt.body) {
                f.ang += torque;
            }
            if pt.other != 0 {
                if let Some(f) = fext.get_mut(pt.other) {
                    f.ang -= torque;
                }
            }
        }
    }
}
