//! The simulation's contact and constraint state as seen from outside: the
//! contact points and forces of the last step, the links they touch (both sides
//! of a pair), the pairs dropped at the start, and the constraints a start state
//! violates (with the lift of a floating base above the ground).

use super::{limit_excess, ContactForce, SimError, Simulation};
use crate::contact::{ContactPoint, DroppedPair, NO_GEOM};
use crate::dynamics::forward_kinematics_pass as forward_kinematics;
use crate::spatial::Force;

/// A constraint the current state violates (see [`Simulation::start_violations`]).
#[derive(Clone, Debug, PartialEq)]
pub enum Violation {
    /// A link's collision geometry is `depth` m inside the ground.
    Ground {
        /// The URDF link.
        link: String,
        /// Its deepest point's penetration (m, positive).
        depth: f64,
    },
    /// Two shapes of different bodies (a body and an obstacle, two models,
    /// two links of one model that overlap by at most 1 mm) overlap by `depth` m.
    Overlap {
        /// One side's link.
        a: String,
        /// The other side's link (an obstacle: its name).
        b: String,
        /// The deepest overlap (m, positive).
        depth: f64,
    },
    /// A joint is `amount` outside its limits [lower, upper] (at `q`).
    Limit {
        /// The URDF joint.
        joint: String,
        /// Its position (rad or m).
        q: f64,
        /// Lower limit (rad or m; −∞ when the URDF gives none).
        lower: f64,
        /// Upper limit (rad or m; +∞ when the URDF gives none).
        upper: f64,
        /// How far outside the limits `q` lies (rad or m, positive).
        amount: f64,
    },
}

impl std::fmt::Display for Violation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Violation::Overlap { a, b, depth } => write!(
                f,
                "links \"{a}\" and \"{b}\" start {depth:.4} m inside each other (pushed apart at a capped speed)"
            ),
            Violation::Ground { link, depth } => write!(
                f,
                "link \"{link}\" starts {depth:.4} m inside the ground (pushed out at a capped speed)"
            ),
            Violation::Limit {
                joint,
                q,
                lower,
                upper,
                amount,
            } => write!(
                f,
                "joint \"{joint}\" starts {amount:.4} outside its limit [{lower}, {upper}] (q = {q}; brought back at a capped speed)"
            ),
        }
    }
}

impl Simulation {
    /// Moves a floating base vertically so that the lowest point of the
    /// collision geometry is `height` above the ground. Returns `false` (and
    /// moves nothing) without a floating base, a ground or collision geometry.
    pub fn lift_above_ground(&mut self, height: f64) -> Result<bool, SimError> {
        if !height.is_finite() {
            return Err(SimError::Invalid(format!(
                "--above-ground must be a finite number (got {height})"
            )));
        }
        let low = self.lowest_point();
        let ground = match self.contact.as_ref().and_then(|c| c.ground_height()) {
            Some(g) => g,
            None => return Ok(false),
        };
        if !self.model.floating_base || !low.is_finite() {
            return Ok(false);
        }
        let (mut q, v) = (self.q.clone(), self.v.clone());
        q[2] += ground + height - low;
        self.set_state(&q, &v)?;
        Ok(true)
    }

    /// The constraints the current state violates: links deeper in the ground
    /// than the contact margin (one entry per link, its deepest point) and
    /// joints outside their limits. The simulation recovers from them gently
    /// (the position pass, at most `contact.max_push_speed` and
    /// `limit_push_speed`).
    pub fn start_violations(&self) -> Vec<Violation> {
        let mut out = Vec::new();
        if self.contact.is_some() {
            let margin = self.opts.contact.margin;
            for p in &self.points {
                if -p.gap <= margin {
                    continue;
                }
                let link = self.geom_link(p.geom);
                if p.other_geom != NO_GEOM {
                    let other = self.geom_link(p.other_geom);
                    match out.iter_mut().find(|v: &&mut Violation| {
                        matches!(v, Violation::Overlap { a, b, .. } if a == link && b == other)
                    }) {
                        Some(Violation::Overlap { depth, .. }) => *depth = depth.max(-p.gap),
                        _ => out.push(Violation::Overlap {
                            a: link.to_string(),
                            b: other.to_string(),
                            depth: -p.gap,
                        }),
                    }
                    continue;
                }
                match out.iter_mut().find(
                    |v: &&mut Violation| matches!(v, Violation::Ground { link: l, .. } if l == link),
                ) {
                    Some(Violation::Ground { depth, .. }) => *depth = depth.max(-p.gap),
                    _ => out.push(Violation::Ground {
                        link: link.to_string(),
                        depth: -p.gap,
                    }),
                }
            }
        }
        if self.opts.joint_dynamics {
            for (d, iq, _) in self.model.dof_indices() {
                let info = &self.model.dofs[d];
                if info.continuous {
                    continue;
                }
                let q = self.q[iq];
                let (lower, upper, amount) = limit_excess(info, q);
                if amount > 1e-9 {
                    out.push(Violation::Limit {
                        joint: info.name.clone(),
                        q,
                        lower,
                        upper,
                        amount,
                    });
                }
            }
        }
        out
    }

    /// The deepest penetration and the largest joint-limit excess now (no
    /// allocation: the step's recovery test).
    pub(super) fn worst_violation(&self) -> (f64, f64) {
        let mut excess: f64 = 0.0;
        if self.opts.joint_dynamics {
            for (d, iq, _) in self.model.dof_indices() {
                let info = &self.model.dofs[d];
                if info.continuous {
                    continue;
                }
                excess = excess.max(limit_excess(info, self.q[iq]).2);
            }
        }
        (self.penetration(), excess)
    }

    /// Whether this simulation has ground contact.
    pub fn has_contact(&self) -> bool {
        self.contact.is_some()
    }
    /// Narrow-phase contact queries performed so far (0 for a scene with no
    /// collision geometry or no ground).
    pub fn contact_queries(&self) -> u64 {
        self.contact.as_ref().map_or(0, |c| c.queries())
    }
    /// The lowest point of the collision geometry at the current state (m; +∞
    /// without contact shapes).
    pub fn lowest_point(&mut self) -> f64 {
        forward_kinematics(&self.model, &mut self.data, &self.q);
        self.fk_valid = true;
        match &self.contact {
            Some(c) => c.lowest_point(&self.data.o_m_i),
            None => f64::INFINITY,
        }
    }
    /// Contact points at the current state (within the detection margin).
    pub fn contact_points(&self) -> &[ContactPoint] {
        &self.points
    }
    /// Deepest penetration into the ground at the current state (m, 0 if none).
    pub fn penetration(&self) -> f64 {
        let frozen = &self.sleep.frozen_points;
        self.points
            .iter()
            .chain(frozen)
            .map(|p| -p.gap)
            .fold(0.0, f64::max)
    }
    /// The contact points that carried force in the last step, with their forces.
    pub fn contact_forces(&self) -> &[ContactForce] {
        self.sleep.forces(self.cons.contact_forces())
    }
    /// The URDF link whose collision shape made a contact point (a point of
    /// [`Simulation::contact_points`] or [`ContactForce::point`]); `None` for a
    /// point this simulation did not find.
    pub fn contact_link(&self, point: &ContactPoint) -> Option<&str> {
        self.contact.as_ref()?;
        self.model
            .collisions
            .get(point.geom)
            .map(|g| g.link.as_str())
    }
    /// The link (an obstacle: its name) on the other side of a contact point;
    /// `None` on the ground.
    pub fn contact_other_link(&self, point: &ContactPoint) -> Option<&str> {
        self.model
            .collisions
            .get(point.other_geom)
            .map(|g| g.link.as_str())
    }
    /// [`Simulation::contact_forces`] named by URDF link (the link whose
    /// collision shape touched, not the merged body), on both sides: a
    /// contact between two shapes gives the force on each (the second with
    /// the point's sides swapped, its normal and force negated); the ground
    /// gives one.
    pub fn link_contact_forces(&self) -> impl Iterator<Item = (&str, ContactForce)> + '_ {
        self.contact_forces().iter().flat_map(move |f| {
            let a = (self.contact_link(&f.point).unwrap_or(""), *f);
            let b = self.contact_other_link(&f.point).map(|l| {
                let p = f.point;
                let swapped = ContactPoint {
                    body: p.other,
                    other: p.body,
                    geom: p.other_geom,
                    other_geom: p.geom,
                    normal: -p.normal,
                    ..p
                };
                (
                    l,
                    ContactForce {
                        point: swapped,
                        force: -f.force,
                    },
                )
            });
            std::iter::once(a).chain(b)
        })
    }
    /// The self pairs dropped because they overlapped at the start (scene.md
    /// "Who touches whom" rule 4), each with its warning line (`Display`).
    pub fn dropped_pairs(&self) -> &[DroppedPair] {
        self.contact.as_ref().map_or(&[], |c| &c.dropped)
    }
    /// The link of a collision geometry ("" for none).
    fn geom_link(&self, geom: usize) -> &str {
        self.model
            .collisions
            .get(geom)
            .map_or("", |g| g.link.as_str())
    }
    /// Number of contact points that carried force in the last step.
    pub fn active_contacts(&self) -> usize {
        self.contact_forces().len()
    }
    /// The ground contact wrench on each body in the last step (world frame, at
    /// the world origin; entry 0 is the world). Link names: `model.body_link_names`.
    pub fn body_contact_forces(&self) -> &[Force] {
        self.sleep.body_forces(self.cons.body_forces())
    }
}
