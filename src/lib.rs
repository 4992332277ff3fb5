//! urdyn: URDF-driven rigid multibody dynamics in Featherstone's spatial-vector
//! notation. Data flows one way: [`spatial`] ← [`model`] ← [`urdf`];
//! [`dynamics`] (on [`model`]) ← [`contact`] ← [`sim`] ← tools (the `cli` module,
//! behind the default `cli` feature).
#[cfg(feature = "cli")]
pub mod cli;
pub mod contact;
pub mod dynamics;
pub mod model;
pub mod sim;
pub mod spatial;
pub mod urdf;

pub use model::{Data, Model};
/// The nalgebra this crate is built with (its vectors and matrices are in the API):
/// `urdyn::nalgebra::DVector` always matches.
pub use nalgebra;
pub use urdf::{load_file, load_str, LoadOptions, UrdfError};

/// The README's Rust examples, compiled and run by `cargo test` (doctests).
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
