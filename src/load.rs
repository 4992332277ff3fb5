//! One entry for every command that reads a robot file: the format is decided
//! here, once (mjcf.md: a file whose root element is `<mujoco>` is MJCF whatever
//! its extension; anything else is URDF).

use crate::mjcf::{self, MjcfError};
use crate::model::Model;
use crate::urdf::{self, LoadOptions, UrdfError};
use std::path::Path;

/// A robot file's format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// URDF (`<robot>`).
    Urdf,
    /// MuJoCo's MJCF (`<mujoco>`).
    Mjcf,
}

/// The format of the file at `path` (URDF unless its root element is `<mujoco>`;
/// an unreadable file is URDF, whose loader then names the problem).
pub fn file_format(path: &Path) -> Format {
    if mjcf::is_mjcf_file(path) {
        Format::Mjcf
    } else {
        Format::Urdf
    }
}

/// Why a robot file did not load.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LoadError {
    /// A URDF error (names the file and element).
    #[error(transparent)]
    Urdf(#[from] UrdfError),
    /// An MJCF error (names the file, element and attribute).
    #[error(transparent)]
    Mjcf(#[from] MjcfError),
    /// `--floating-base` given beside an MJCF file.
    #[error(
        "{0}: --floating-base does not apply to an MJCF file: the file says which joints are free"
    )]
    FloatingBaseWithMjcf(String),
}

/// Loads a URDF or MJCF file (the format from its content); `options` are the
/// URDF's (`floating_base` beside an MJCF file is an error).
pub fn load_model(path: impl AsRef<Path>, options: LoadOptions) -> Result<Model, LoadError> {
    let path = path.as_ref();
    match file_format(path) {
        Format::Mjcf if options.floating_base => {
            Err(LoadError::FloatingBaseWithMjcf(path.display().to_string()))
        }
        Format::Mjcf => Ok(mjcf::load_file(path)?),
        Format::Urdf => Ok(urdf::load_file(path, options)?),
    }
}
