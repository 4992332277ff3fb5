//! The command line's tool layer: what the `urdyn` binary does with the engine
//! (states files, the `eval` contract, `inspect`, `simulate`, `bench`, the replay
//! page of `view`, output files).
//!
//! Not part of the engine: nothing in [`crate::spatial`], [`crate::model`],
//! [`crate::urdf`], [`crate::dynamics`], [`crate::contact`] or [`crate::sim`] imports
//! it, and it is compiled only with the `cli` feature (on by default; a library user
//! who wants the engine alone builds with `default-features = false`).
pub mod bench;
pub mod eval;
pub mod eval_constrained;
pub mod inspect;
pub mod output;
pub mod simulate;
mod simulate_mjcf;
pub mod state;
pub mod view;
