//! urdyn: URDF-driven rigid multibody dynamics in Featherstone's spatial-vector
//! notation. Data flows one way: [`urdf`] → [`model`] → [`dynamics`] → tools
//! ([`eval`], [`inspect`]).
pub mod bench;
pub mod contact;
pub mod dynamics;
pub mod eval;
pub mod inspect;
pub mod model;
pub mod output;
pub mod sim;
pub mod simulate;
pub mod spatial;
pub mod state;
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
