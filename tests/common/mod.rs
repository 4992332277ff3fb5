//! Helpers shared by the test modules (`use crate::common::...`).

pub mod counting_alloc;
pub mod csv;
pub mod dd;
pub mod lcg;
