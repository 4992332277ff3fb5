//! A large hull's ground patch, found on its vertex graph: the lowest vertex
//! by descent, the band of vertices near it by a graph search (reused while
//! the patch rests), and the reduced patch chosen from the band.
//!
//! The band's and its rim's vertices are copied, in search order, into
//! contiguous coordinate arrays when the band is searched (rarely: a resting
//! patch keeps its band), so that the test that the band still holds (a
//! height a vertex) and the band's world points run in vector lanes without
//! gathers; each band vertex's world point is computed once a detection and
//! read by every criterion, pick and kept point after it. Every value is the
//! same operations on the same numbers as one vertex at a time (the same
//! bits): a solo12 foot is a 672-vertex hull with ~40 vertices in its band
//! and ~25 on its rim, and done a vertex at a time through the graph's
//! indices these were a seventh of a servo rollout's step.

use super::reduce::{band_best, HOLD_DEEPEST, HOLD_EXTREME, MAX_DIRS};
use super::{GroundContact, GroundShape, BAND};
use crate::contact::ContactPoint;
use crate::spatial::ops::madd;
use crate::spatial::Se3;
use nalgebra::Vector3;

/// Coordinates of points, one array a coordinate.
#[derive(Clone, Debug, Default)]
pub(super) struct Soa {
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    pub z: Vec<f64>,
}

impl Soa {
    pub fn zeros(n: usize) -> Self {
        Self {
            x: vec![0.0; n],
            y: vec![0.0; n],
            z: vec![0.0; n],
        }
    }
    #[inline(always)]
    fn put(&mut self, i: usize, v: &Vector3<f64>) {
        self.x[i] = v.x;
        self.y[i] = v.y;
        self.z[i] = v.z;
    }
    #[inline(always)]
    fn get(&self, i: usize) -> Vector3<f64> {
        Vector3::new(self.x[i], self.y[i], self.z[i])
    }
}

/// How many of the points `a..b` of `c` have a height
/// `r₀x + r₁y + r₂z + tz` (in that order: [`GroundContact::hull_patch`]'s
/// `height`) at most `band`: one vector loop, no early exit.
#[inline(always)]
fn count_within(c: &Soa, a: usize, b: usize, r: [f64; 3], tz: f64, band: f64) -> usize {
    let (Some(xs), Some(ys), Some(zs)) = (c.x.get(a..b), c.y.get(a..b), c.z.get(a..b)) else {
        return 0;
    };
    let mut n = 0;
    for ((x, y), z) in xs.iter().zip(ys).zip(zs) {
        n += usize::from(r[0] * x + r[1] * y + r[2] * z + tz <= band);
    }
    n
}

impl GroundContact {
    /// Appends the patch of hull `s` (shape `si`, placed at `o_m_g`, with a
    /// vertex graph) to `out`: nothing when its lowest vertex is above
    /// `margin`; at most `maxp` picks and `maxp` points kept from last step
    /// (see [`GroundContact::detect`]).
    pub(super) fn hull_patch(
        &mut self,
        si: usize,
        s: &GroundShape,
        o_m_g: &Se3<f64>,
        margin: f64,
        maxp: usize,
        out: &mut Vec<ContactPoint>,
    ) {
        let ground = self.ground;
        let r = &o_m_g.rot;
        let (rx, ry, rz) = (r[(2, 0)], r[(2, 1)], r[(2, 2)]);
        let tz = o_m_g.trans.z - ground;
        let height = |v: &Vector3<f64>| rx * v.x + ry * v.y + rz * v.z + tz;
        let base = self.slot_offset[si];
        // descend the vertex graph from the last lowest vertex (a vertex of a
        // convex polytope with no lower neighbour is the lowest), then collect
        // the vertices within the margin, a connected set on the graph
        let nbrs = |k: usize| {
            let (a, b) = (s.adj_start[k] as usize, s.adj_start[k + 1] as usize);
            &s.adj[a..b]
        };
        let mut k = self.last_low[si].min(s.verts.len() - 1);
        let mut zk = height(&s.verts[k]);
        loop {
            let mut best = None;
            for &j in nbrs(k) {
                let zj = height(&s.verts[j as usize]);
                if zj < zk {
                    zk = zj;
                    best = Some(j as usize);
                }
            }
            match best {
                Some(j) => k = j,
                None => break,
            }
        }
        self.last_low[si] = k;
        if zk > margin {
            return;
        }
        // the band the patch is chosen from: within BAND of the lowest vertex
        // (a face lying flat on the ground is all inside it; the vertices
        // further up a rounded edge are not needed to span the patch)
        let band = margin.min(zk + BAND);
        let verts = &s.verts[..];
        let order = &mut self.band_order[base..base + verts.len()];
        // last step's band (in its search order) and its rim (the vertices
        // next to it outside it): from the same lowest vertex, the band is the
        // same set, searched in the same order, when every band vertex is
        // still in it and no rim vertex is (a height a vertex, no graph walk:
        // a patch at rest)
        let (bl, rl) = (self.band_len[si], self.rim_len[si]);
        let rz3 = [rx, ry, rz];
        let same = bl > 0
            && order[0] as usize == k
            && count_within(&self.band_xyz, base + 1, base + bl, rz3, tz, band) == bl - 1
            && count_within(&self.rim_xyz, base, base + rl, rz3, tz, band) == 0;
        if !same {
            // the band's vertices by a search from the lowest; a vertex is
            // marked when its height is first taken (one height a vertex, in
            // or out of the band), the band's stamped with this search's
            // generation and given its place in the search order
            self.generation = self.generation.wrapping_add(1).max(1);
            let stamp = self.generation;
            let visited = &mut self.visited[base..base + verts.len()];
            let in_band = &mut self.in_band[base..base + verts.len()];
            let place = &mut self.band_place[base..base + verts.len()];
            let (bxyz, rxyz) = (&mut self.band_xyz, &mut self.rim_xyz);
            let stack = &mut self.stack;
            stack.clear();
            stack.push(k as u32);
            visited[k] = stamp;
            let (mut bl, mut rl) = (0, 0);
            while let Some(i) = stack.pop() {
                order[bl] = i;
                place[i as usize] = bl as u32;
                bxyz.put(base + bl, &verts[i as usize]);
                bl += 1;
                in_band[i as usize] = stamp;
                for &j in nbrs(i as usize) {
                    let j = j as usize;
                    if visited[j] != stamp {
                        visited[j] = stamp;
                        if height(&verts[j]) <= band {
                            stack.push(j as u32);
                        } else {
                            rxyz.put(base + rl, &verts[j]);
                            rl += 1;
                        }
                    }
                }
            }
            self.band_len[si] = bl;
            self.rim_len[si] = rl;
            self.band_gen[si] = stamp;
        }
        let cand = &order[..self.band_len[si]];
        // each band vertex's world point, once (see the module doc); its
        // criteria (`reduce`: −φ, cᵢ·x + sᵢ·y) and their maxima: no
        // ContactPoint until chosen
        let nb = cand.len();
        {
            // `o_m_g.act_point` (`add_mat_vec`: the same fused products) of
            // each band vertex, from its copy in search order
            let (r, t) = (&o_m_g.rot, &o_m_g.trans);
            let b = &self.band_xyz;
            let (bx, by, bz) = (
                &b.x[base..base + nb],
                &b.y[base..base + nb],
                &b.z[base..base + nb],
            );
            let p = &mut self.band_pts;
            let (px, py, pz) = (&mut p.x[..nb], &mut p.y[..nb], &mut p.z[..nb]);
            let row = |i: usize, x: f64, y: f64, z: f64, c: f64| {
                madd(r[(i, 2)], z, madd(r[(i, 1)], y, madd(r[(i, 0)], x, c)))
            };
            for j in 0..nb {
                px[j] = row(0, bx[j], by[j], bz[j], t.x);
                py[j] = row(1, bx[j], by[j], bz[j], t.y);
                pz[j] = row(2, bx[j], by[j], bz[j], t.z);
            }
        }
        let pts = &self.band_pts;
        let dirs = maxp.saturating_sub(1).clamp(1, MAX_DIRS);
        let dir = &self.reduce_dirs;
        let key = |p: &Vector3<f64>, q: usize| -> f64 {
            if q == 0 {
                -(p.z - ground)
            } else {
                let (c, sn) = dir[q - 1];
                c * p.x + sn * p.y
            }
        };
        let point = |k: usize, p: Vector3<f64>| s.contact_at(si, base + k, p, ground);
        if cand.len() <= maxp {
            out.extend(
                cand.iter()
                    .enumerate()
                    .map(|(t, &i)| point(i as usize, pts.get(t))),
            );
            return;
        }
        let best = match dirs {
            3 => band_best::<3>(pts, nb, ground, dir),
            _ => band_best::<0>(pts, nb, ground, dir),
        };
        // a band vertex's place in `cand` / `pts`
        let stamp = self.band_gen[si];
        let (in_band, place) = (&self.in_band, &self.band_place);
        let at = |slot: usize| -> Option<usize> {
            (in_band.get(slot) == Some(&stamp)).then(|| place[slot] as usize)
        };
        // each criterion's choice as `reduce`'s: a point kept last step (this
        // shape's, at most maxp, looked at directly) within its hold of the
        // best, the lowest slot; else the lowest slot within 1e-6 of the best
        // (a scan of the band, only then)
        let (pa, pb, pc) = self.prev_range[si];
        let kept = &self.prev_list[pa..pb];
        let kept_all = &self.prev_list[pa..pc];
        let start = out.len();
        // the kept picks still in the band (slot, place, world point), looked
        // up once for every criterion (at most one pick a criterion: `dirs + 1`
        // ≤ MAX_DIRS + 1 of them; beyond, looked up per criterion)
        let mut kin = [(0usize, 0usize, Vector3::zeros()); MAX_DIRS + 1];
        let mut nk = 0;
        let cached = kept.len() <= kin.len();
        if cached {
            for &slot in kept {
                if let Some(t) = at(slot) {
                    kin[nk] = (slot, t, pts.get(t));
                    nk += 1;
                }
            }
        }
        for (q, &bq) in best.iter().enumerate().take(dirs + 1) {
            let hold = if q == 0 { HOLD_DEEPEST } else { HOLD_EXTREME };
            let (mut ch, mut tch) = (usize::MAX, 0);
            if cached {
                for &(slot, t, p) in &kin[..nk] {
                    if slot < ch && key(&p, q) >= bq - hold {
                        (ch, tch) = (slot, t);
                    }
                }
            } else {
                for &slot in kept {
                    if slot < ch {
                        if let Some(t) = at(slot) {
                            if key(&pts.get(t), q) >= bq - hold {
                                (ch, tch) = (slot, t);
                            }
                        }
                    }
                }
            }
            // the choice's place in the band
            let t = if ch != usize::MAX {
                tch
            } else {
                let (mut kmin, mut tmin) = (usize::MAX, 0);
                for (t, &i) in cand.iter().enumerate() {
                    let i = i as usize;
                    if i < kmin && key(&pts.get(t), q) >= bq - 1e-6 {
                        (kmin, tmin) = (i, t);
                    }
                }
                tmin
            };
            if out.len() - start >= maxp {
                break;
            }
            let k = cand[t] as usize;
            if !out[start..].iter().any(|p| p.slot == base + k) {
                out.push(point(k, pts.get(t)));
            }
        }
        // a point kept last step and still in the ground that no criterion
        // picked stays in the patch beside the picks (never in place of one:
        // a pick above the ground may be the point about to be hit), at most
        // maxp of them: a point that carries the body does not lose its row
        // because another became the deepest or an extreme (docs/theory.md
        // §"Contact geometry"; borinot's rocking, docs/robots.md)
        self.picks[si] = out.len() - start;
        let mut extra = 0;
        for &slot in kept_all {
            if extra >= maxp {
                break;
            }
            if out[start..].iter().any(|p| p.slot == slot) {
                continue;
            }
            let k = slot - base;
            let p = match at(slot) {
                Some(t) => point(k, pts.get(t)),
                None => point(k, o_m_g.act_point(&verts[k])),
            };
            if p.gap < 0.0 {
                out.push(p);
                extra += 1;
            }
        }
    }
}
