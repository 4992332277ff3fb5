//! Mesh paths: resolved by the import layer ([`crate::urdf::resolve_mesh_path`]).
pub use crate::urdf::resolve_mesh_path;
