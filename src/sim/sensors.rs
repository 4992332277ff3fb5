//! Sensors read after a step (docs/theory.md §"Sensors"): a link's IMU
//! (gyro and proper acceleration in the link frame), the wrench a joint
//! transmits, the contact wrench on a link.
//!
//! The step's start state (q₀, v₀) and length h are kept by the step
//! ([`Sensors::begin`]); every reading is computed on demand from them, the
//! end state and the step's contact forces, in a scratch workspace of its own.

use crate::dynamics::{
    forward_kinematics, forward_kinematics_second_order, frame_placement, frame_velocity, rnea,
    Reference,
};
use crate::model::{Data, Model};
use crate::sim::{SimError, Simulation};
use nalgebra::{DVector, Vector3};

/// The last step's start state and length, and a workspace for the readings.
#[derive(Clone, Debug)]
pub(crate) struct Sensors {
    q0: DVector<f64>,
    v0: DVector<f64>,
    /// The last step's length (0: no step yet).
    h: f64,
    data: Option<Box<Data>>,
}

impl Sensors {
    /// No step yet, for a model of `nq`, `nv` coordinates.
    pub fn new(nq: usize, nv: usize) -> Self {
        Self {
            q0: DVector::zeros(nq),
            v0: DVector::zeros(nv),
            h: 0.0,
            data: None,
        }
    }
    /// A step begins from (q, v).
    #[inline]
    pub fn begin(&mut self, q: &DVector<f64>, v: &DVector<f64>) {
        self.q0.copy_from(q);
        self.v0.copy_from(v);
    }
    /// The step just taken was `h` long.
    #[inline]
    pub fn end(&mut self, h: f64) {
        self.h = h;
    }
    /// A new state was set: no step to read from.
    pub fn forget(&mut self) {
        self.h = 0.0;
    }
}

fn name_error(e: impl std::fmt::Display) -> SimError {
    SimError::Invalid(e.to_string())
}

impl Simulation {
    /// The IMU of URDF link `link` after the last step: (gyro, accel), both in
    /// the link's coordinates. `gyro` is the link's angular velocity at the
    /// step's end; `accel` what an accelerometer at the link origin reads,
    /// (v_w(end) − v_w(start))/h − g with v_w the origin's world velocity,
    /// rotated into the link at the step's end (at rest: +g upward; falling
    /// freely: 0). Before any step (or right after `set_state`) the velocity
    /// change is taken as 0. An unknown link is an error naming the nearest.
    pub fn imu(&mut self, link: &str) -> Result<(Vector3<f64>, Vector3<f64>), SimError> {
        let frame = self.model.frame_id(link).map_err(name_error)?;
        let model = &self.model;
        let s = &mut self.sensors;
        let data = s.data.get_or_insert_with(|| Box::new(Data::new(model)));
        let a0 = DVector::zeros(model.nv);
        // v_w(start)
        forward_kinematics_second_order(model, data, &s.q0, &s.v0, &a0)?;
        let v_start = frame_velocity(model, data, frame, Reference::WorldAligned)?.lin;
        // v_w(end), ω(end) in the link, the link's rotation at the end
        forward_kinematics_second_order(model, data, &self.q, &self.v, &a0)?;
        let v_end = frame_velocity(model, data, frame, Reference::WorldAligned)?.lin;
        let gyro = frame_velocity(model, data, frame, Reference::Local)?.ang;
        let rot = frame_placement(model, data, frame)?.rot;
        // proper acceleration: a_w − g, in the link's axes
        let dv = if s.h > 0.0 {
            (v_end - v_start) / s.h
        } else {
            Vector3::zeros()
        };
        let accel = rot.transpose() * (dv - model.gravity);
        Ok((gyro, accel))
    }

    /// The wrench (force, torque) the parent side of URDF joint `joint`
    /// exerts on its child link in the last step (constraint, actuation,
    /// damping, friction and limits together), at the child link's origin, in
    /// its coordinates: the inverse dynamics' internal force of the joint at
    /// the step's start state with the step's acceleration and contact forces.
    /// Before any step the acceleration is taken as 0. An unknown joint (or a
    /// fixed one, merged away) is an error naming the nearest movable joint.
    pub fn joint_wrench(&mut self, joint: &str) -> Result<(Vector3<f64>, Vector3<f64>), SimError> {
        let id = self.model.joint_id(joint).map_err(name_error)?;
        let body = id.0;
        let child = self
            .model
            .frame_id(&self.model.body_link_names[body])
            .map_err(name_error)?;
        let model = &self.model;
        let s = &mut self.sensors;
        let data = s.data.get_or_insert_with(|| Box::new(Data::new(model)));
        // the step's generalized acceleration (body-frame spatial for a free base)
        let a = step_acceleration(model, &s.v0, &self.v, s.h);
        let (q, v) = if s.h > 0.0 {
            (&s.q0, &s.v0)
        } else {
            (&self.q, &self.v)
        };
        let fext = self.sleep.body_forces(self.cons.body_forces());
        rnea(model, data, q, v, &a, Some(fext))?;
        // body frame → the child link's frame (bMf)
        let f = model.frames[child.0].placement.inv_act_force(&data.f[body]);
        Ok((f.lin, f.ang))
    }

    /// The total contact force on URDF link `link` in the last step and its
    /// torque about the link's origin, world coordinates (zero where it touched
    /// nothing). Each contact counts toward the link whose collision shape
    /// touched ([`Simulation::contact_link`]). An unknown link is an error.
    pub fn contact_wrench(&mut self, link: &str) -> Result<(Vector3<f64>, Vector3<f64>), SimError> {
        let frame = self.model.frame_id(link).map_err(name_error)?;
        let (mut force, mut moment) = (Vector3::zeros(), Vector3::zeros());
        if !self
            .link_contact_forces()
            .any(|(l, f)| l == link && f.force != Vector3::zeros())
        {
            return Ok((force, moment));
        }
        // the link origin where the forces acted (the step's start)
        let model = &self.model;
        let s = &mut self.sensors;
        let data = s.data.get_or_insert_with(|| Box::new(Data::new(model)));
        let q = if s.h > 0.0 { &s.q0 } else { &self.q };
        forward_kinematics(model, data, q)?;
        let o = frame_placement(model, data, frame)?.trans;
        for (l, f) in self.link_contact_forces() {
            if l == link {
                // τ = (p − o) × f
                force += f.force;
                moment += (f.point.point - o).cross(&f.force);
            }
        }
        Ok((force, moment))
    }
}

/// The generalized acceleration of a step from (q₀, v₀) to (q₁, v₁) of length h:
/// (v₁ − v₀)/h on the joints; each free joint's body-frame spatial acceleration,
/// its linear velocity taken back into the start frame, exp(h ω₁) v₁, and the
/// frame's own rate ω₀ × v₀ removed (the semi-implicit step's, `euler.rs`).
fn step_acceleration(model: &Model, v0: &DVector<f64>, v1: &DVector<f64>, h: f64) -> DVector<f64> {
    let mut a = DVector::zeros(model.nv);
    if h <= 0.0 {
        return a;
    }
    a.copy_from(v1);
    a -= v0;
    a /= h;
    for f in &model.free_joints {
        let i = f.iv;
        let w1 = Vector3::new(v1[i + 3], v1[i + 4], v1[i + 5]);
        let w0 = Vector3::new(v0[i + 3], v0[i + 4], v0[i + 5]);
        let l0 = Vector3::new(v0[i], v0[i + 1], v0[i + 2]);
        let l1 = Vector3::new(v1[i], v1[i + 1], v1[i + 2]);
        let th = (w1 * h).norm();
        let l1s = if th > 0.0 {
            crate::spatial::axis_angle(&(w1 * h / th), th) * l1
        } else {
            l1
        };
        let al = (l1s - l0) / h - w0.cross(&l0);
        a[i] = al.x;
        a[i + 1] = al.y;
        a[i + 2] = al.z;
    }
    a
}
