//! `urdyn view` and `urdyn simulate --html` (cli.md): one self-contained HTML page
//! that replays a trajectory in 3D.
//!
//! The page carries everything it draws, so it opens from disk with no network:
//! - the robot's geometry, from the URDF's `<visual>` elements (the `<collision>`
//!   elements of a link without any): meshes read by [`crate::mesh::load_mesh`],
//!   simplified by vertex clustering past [`MAX_MESH_TRIANGLES`] triangles and
//!   quantised to 16 bits a coordinate; boxes, cylinders, capsules and spheres as
//!   their dimensions (the page builds them); the URDF's material colours;
//! - the trajectory as the world pose of every moving body per shown frame (the
//!   engine's [`forward_kinematics`]), every URDF link as a body and placement, the
//!   frames being rows of the trajectory subsampled by [`FrameSampler`] (at most
//!   [`FRAME_RATE`] a simulated second, the first and last rows kept);
//! - energy, contact count and penetration per frame for the plot, and with
//!   `simulate --html` the contact points and forces;
//! - the page's own WebGL2 renderer (`viewer.js`, `viewer.css`, `page.html` next
//!   to this file, included at compile time; no third-party code).
//!
//! The page sets `window.urdynViewer` (cli.md) once it has drawn its first frame.

use crate::cli::output::write_atomic;
use crate::{LoadOptions, Model};
use std::path::{Path, PathBuf};

pub(crate) mod geometry;
pub mod mjcf;
pub(crate) mod page;
pub(crate) mod scene;
mod trajectory;
pub(crate) mod visuals;

pub(crate) use geometry::PLACEHOLDER_RGBA;
pub use geometry::{simplify, simplify_keeping, Geometry, Visual, VisualShape, PLACEHOLDER_BOX};
pub use page::page_html;
pub use scene::{run_scene, LoopMark, SceneViewArgs};
pub use trajectory::{read_trajectory, ContactArrow, FrameSampler, Recorder, TrajectoryRows};

/// Most frames a simulated second the page shows (a browser plays 60 smoothly).
pub const FRAME_RATE: f64 = 60.0;
/// Most bytes of body poses a page carries (longer runs are shown at a lower rate).
pub const MAX_POSE_BYTES: usize = 12 << 20;
/// Meshes with more triangles than this are simplified (vertex clustering).
pub const MAX_MESH_TRIANGLES: usize = 20_000;
/// The triangle budget of a whole page (about 12 bytes a triangle once
/// quantised and in base64: 1.8 MB): past it, the largest meshes are simplified
/// to a common limit ([`Geometry::simplify_to`]).
pub const MAX_PAGE_TRIANGLES: usize = 150_000;

/// `urdyn view`'s options (cli.md).
#[derive(Clone, Debug)]
pub struct ViewArgs {
    /// The URDF file.
    pub urdf: PathBuf,
    /// The trajectory CSV that `simulate --out` wrote.
    pub traj: PathBuf,
    /// The root link has a free 6-DoF joint (as when simulated).
    pub floating_base: bool,
    /// Roots for `package://NAME/...` mesh paths.
    pub package_path: Vec<PathBuf>,
    /// The page to write (atomically).
    pub out: PathBuf,
}

/// What a written page holds.
#[derive(Clone, Debug, PartialEq)]
pub struct PageSummary {
    /// Frames shown.
    pub frames: usize,
    /// Distinct meshes embedded.
    pub meshes: usize,
    /// Triangles of the embedded meshes (after simplification).
    pub triangles: usize,
    /// Meshes that were simplified.
    pub simplified: usize,
    /// Size of the page in bytes.
    pub bytes: usize,
    /// Visual elements left out (malformed), one line each.
    pub warnings: Vec<String>,
}

impl std::fmt::Display for PageSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "view: {} frames, {} meshes ({} triangles, {} simplified), {:.2} MB",
            self.frames,
            self.meshes,
            self.triangles,
            self.simplified,
            self.bytes as f64 / 1e6
        )
    }
}

/// Why no page was written: one line naming the file and the element, column or row.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    /// The URDF could not be imported.
    #[error(transparent)]
    Urdf(#[from] crate::UrdfError),
    /// The URDF's visual geometry (a mesh file, a shape) could not be read.
    #[error("{0}")]
    Geometry(String),
    /// The trajectory CSV does not fit the URDF or is malformed.
    #[error("{0}")]
    Csv(String),
    /// The page could not be written.
    #[error("{0}")]
    Output(String),
}

/// Runs `urdyn view`: reads the URDF and the CSV, writes the page atomically (a
/// bad input leaves no page).
pub fn run(args: &ViewArgs) -> Result<PageSummary, ViewError> {
    let is_mjcf = crate::load::file_format(&args.urdf) == crate::load::Format::Mjcf;
    if is_mjcf && args.floating_base {
        return Err(ViewError::Geometry(format!(
            "{}: --floating-base does not apply to an MJCF file (the file says which joints are free)",
            args.urdf.display()
        )));
    }
    let (model, geometry, ground) = if is_mjcf {
        // the file's whole world, every geom in its colour (view/mjcf.rs)
        let (model, world) = crate::mjcf::load_file_with_world(&args.urdf)
            .map_err(|e| ViewError::Geometry(e.to_string()))?;
        let g = mjcf::geometry(&model, &world, &args.urdf.display().to_string());
        let ground = crate::mjcf::ground_of(&world).map(|g| g.height);
        (model, g, ground)
    } else {
        let model = crate::load_file(
            &args.urdf,
            LoadOptions {
                floating_base: args.floating_base,
            },
        )?;
        let geometry = Geometry::load(&model, &args.urdf, &args.package_path)?;
        (model, geometry, Some(0.0))
    };
    let csv_name = args.traj.display().to_string();
    let text = std::fs::read(&args.traj)
        .map_err(|e| ViewError::Csv(format!("{csv_name}: cannot read: {e}")))?;
    let text = String::from_utf8(text)
        .map_err(|_| ViewError::Csv(format!("{csv_name}: not UTF-8 text")))?;
    let rows = read_trajectory(&text, &csv_name, &model)?;
    let mut recorder = Recorder::new(&model, rows.duration(), false);
    let last = rows.times.len().saturating_sub(1);
    for (k, t) in rows.times.iter().enumerate() {
        let plot = [rows.energy[k], rows.contacts[k], rows.penetration[k]];
        recorder.offer(*t, &rows.q[k], plot, &[], k == last);
    }
    write_page(&args.out, &model, &geometry, &recorder, ground)
}

/// Writes the page for `recorder`'s frames atomically to `out`.
pub fn write_page(
    out: &Path,
    model: &Model,
    geometry: &Geometry,
    recorder: &Recorder,
    ground: Option<f64>,
) -> Result<PageSummary, ViewError> {
    let html = page_html(model, geometry, recorder, ground);
    write_atomic(out, |w| {
        w.write_all(html.as_bytes())
            .map_err(|e| format!("{}: cannot write: {e}", out.display()))
    })
    .map_err(ViewError::Output)?;
    Ok(PageSummary {
        frames: recorder.times.len(),
        meshes: geometry.meshes.len(),
        triangles: geometry.meshes.iter().map(|m| m.triangles.len()).sum(),
        simplified: geometry.simplified,
        bytes: html.len(),
        warnings: geometry.warnings.clone(),
    })
}
