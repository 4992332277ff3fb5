#![allow(dead_code)] // each of the two test binaries uses its own part of the helpers
//! Helpers shared by the test modules (`use crate::common::...`).

pub mod counting_alloc;
pub mod csv;
pub mod dd;
pub mod lcg;
pub mod refusal;
