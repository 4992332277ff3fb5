//! The stress tests (`stress.rs`: double-double references, 1000-link chains, huge
//! and tiny numbers): the test binary `integration-stress`, compiled side by side with
//! `integration` (`tests/main.rs`, which says how the files are organised). Alone:
//! `cargo test --release --test integration-stress`.

mod common;

mod stress;
