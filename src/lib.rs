#![warn(missing_docs)]
//! urdyn: URDF-driven rigid multibody dynamics in Featherstone's spatial-vector
//! notation. Data flows one way: [`spatial`] ← [`model`] ← [`urdf`];
//! [`dynamics`] (on [`model`]) ← [`contact`] ← [`sim`] ← tools (the `cli` module,
//! behind the default `cli` feature).
//!
//! # Getting started
//!
//! Inverse dynamics then forward dynamics of the UR5 (fixed base, nq = nv = 6):
//! [`dynamics::rnea`] gives the joint torques τ = H(q) a + C(q, v) (N·m) that
//! produce an acceleration, [`dynamics::forward_dynamics`] the acceleration those
//! torques produce (docs/theory.md §"Equation of motion"). (This example is
//! compiled and run by `cargo test` in the integration tests, tests/doc_examples.rs,
//! rather than as a doctest: rustdoc would instantiate the generic dynamics again,
//! unoptimised, for it alone.)
//!
//! ```ignore
//! use urdyn::nalgebra::DVector;
//! use urdyn::{dynamics, Data, LoadOptions};
//!
//! let model = urdyn::load_file("assets/robots/ur5.urdf", LoadOptions::default())?;
//! let mut data = Data::new(&model); // preallocated workspace, reused by every call
//! let q = DVector::from_fn(model.nq, |k, _| 0.2 * k as f64); // rad
//! let v = DVector::from_element(model.nv, 0.5); // rad/s
//! let a = DVector::from_fn(model.nv, |k, _| 1.0 - 0.3 * k as f64); // rad/s²
//! let tau = dynamics::rnea(&model, &mut data, &q, &v, &a, None)?.clone(); // a wrong-length vector is an Err
//! let qdd = dynamics::forward_dynamics(&model, &mut data, &q, &v, &tau, None)?;
//! assert!((qdd - &a).amax() < 1e-9); // the round trip gives a back
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! A [`sim::Simulation`] of the desk lamp on a floating base (nq = 7 + 3,
//! nv = 6 + 3), dropped onto the ground at z = 0 while a PD controller holds its
//! three joints at their starting angles; the program steps it itself, 0.5 s:
//!
//! ```
//! use urdyn::sim::{SimOptions, Simulation};
//! use urdyn::LoadOptions;
//!
//! let model = urdyn::load_file("assets/lamp.urdf", LoadOptions { floating_base: true })?;
//! let mut sim = Simulation::new(model, SimOptions::default())?; // dt = 1 ms, ground contact on
//! sim.lift_above_ground(0.05)?; // the lowest collision point 5 cm above the ground
//! let (qo, vo) = (sim.model.joint_q_offset(), sim.model.joint_v_offset()); // 7, 6
//! let target = sim.q().clone();
//! while sim.time() < 0.5 {
//!     let (q, v) = (sim.q().clone(), sim.v().clone());
//!     for k in 0..sim.model.dofs.len() {
//!         let (e, ed) = (q[qo + k] - target[qo + k], v[vo + k]);
//!         sim.torques_mut()[vo + k] = -20.0 * e - 0.5 * ed; // N·m, clamped to the URDF effort
//!     }
//!     sim.step()?; // a non-finite state is an Err, never a silent blow-up
//! }
//! assert!(sim.active_contacts() > 0); // landed
//! for f in sim.contact_forces() {
//!     println!("{:?} N at {:?} m", f.force, f.point.point); // world frame
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#[cfg(feature = "cli")]
pub mod cli;
pub mod contact;
pub mod dynamics;
#[doc(hidden)]
pub mod dynamics_f64;
pub mod load;
pub mod mesh;
pub mod mjcf;
pub mod model;
pub mod scene;
pub mod sim;
pub mod spatial;
#[doc(hidden)]
pub mod testing;
pub mod urdf;

pub use load::{load_model, LoadError};
pub use model::{Data, Model};
/// The nalgebra this crate is built with (its vectors and matrices are in the API):
/// `urdyn::nalgebra::DVector` always matches.
pub use nalgebra;
pub use scene::{Scene, SceneError};
pub use urdf::{load_file, load_str, LoadOptions, UrdfError};
