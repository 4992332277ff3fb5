//! URDF import: **parse** (quick-xml into urdf-rs's data model, [`types`], behind an
//! entity guard) → **validate** (names,
//! tree, numbers, inertias, mimic relations) → **lower** (bodies merged through
//! fixed joints into a flat, parent-before-child [`Model`]), with an
//! [`ImportReport`](crate::model::ImportReport) of what was merged, ignored or
//! suspicious.

mod lower;
mod parse;
pub mod types;
mod validate;

pub use crate::mesh::resolve_mesh_path;

use crate::model::Model;
use std::path::Path;

/// How to attach the URDF's root link to the world.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// Give the root link a free 6-DoF joint (unit quaternion) instead of welding it.
    pub floating_base: bool,
}

/// An import error: names the file and, where there is one, the offending element.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}: {}{message}", element.as_ref().map(|e| format!("{e}: ")).unwrap_or_default())]
pub struct UrdfError {
    /// The file (as given to the loader).
    pub file: String,
    /// The offending element (`joint "j1" <limit>`), where there is one.
    pub element: Option<String>,
    /// What is wrong.
    pub message: String,
}

impl UrdfError {
    pub(crate) fn new(file: &str, element: Option<String>, message: impl Into<String>) -> Self {
        Self {
            file: file.to_string(),
            element,
            message: message.into(),
        }
    }
}

/// Reads and imports a URDF file. Mesh files are not opened.
pub fn load_file(path: impl AsRef<Path>, options: LoadOptions) -> Result<Model, UrdfError> {
    let path = path.as_ref();
    let name = path.display().to_string();
    let meta = std::fs::metadata(path)
        .map_err(|e| UrdfError::new(&name, None, format!("cannot read file: {e}")))?;
    if meta.is_dir() {
        return Err(UrdfError::new(
            &name,
            None,
            "is a directory, not a URDF file",
        ));
    }
    let bytes = std::fs::read(path)
        .map_err(|e| UrdfError::new(&name, None, format!("cannot read file: {e}")))?;
    let text =
        String::from_utf8(bytes).map_err(|_| UrdfError::new(&name, None, "not UTF-8 text"))?;
    let mut model = load_str(&text, &name, options)?;
    model.source = Some(path.to_path_buf());
    Ok(model)
}

/// Imports URDF text; `file` is the name used in error messages.
pub fn load_str(text: &str, file: &str, options: LoadOptions) -> Result<Model, UrdfError> {
    let parsed = parse::parse(text, file)?;
    let checked = validate::validate(&parsed, file)?;
    lower::lower(&parsed, &checked, file, options)
}

/// The URDF text's links and joints as read (checked, not validated or lowered):
/// each link's own `<inertial>`, as the Python package's introspection reports it.
pub fn read_robot(text: &str, file: &str) -> Result<types::Robot, UrdfError> {
    parse::parse(text, file).map(|p| p.robot)
}
