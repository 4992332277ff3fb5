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
use crate::dynamics::forward_kinematics;
use crate::mesh::{load_mesh_colored, Rgba, TriMesh};
use crate::model::{Data, Shape};
use crate::spatial::Se3;
use crate::{LoadOptions, Model};
use nalgebra::{DVector, Matrix3, Rotation3, UnitQuaternion, Vector3};
use serde_json::{json, Value};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

pub mod mjcf;
mod scene;
mod visuals;

pub use scene::{run_scene, LoopMark, SceneViewArgs};

const PAGE_HTML: &str = include_str!("page.html");
const VIEWER_JS: &str = include_str!("viewer.js");
const VIEWER_CSS: &str = include_str!("viewer.css");

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

/// The rows of a trajectory CSV: times, configurations and the plotted columns
/// (NaN where the CSV has no such column).
#[derive(Clone, Debug, Default)]
pub struct TrajectoryRows {
    /// `t` of every row, as written.
    pub times: Vec<f64>,
    /// q of every row (engine order; a floating base's quaternion normalised).
    pub q: Vec<DVector<f64>>,
    /// `energy` per row.
    pub energy: Vec<f64>,
    /// `contacts` per row.
    pub contacts: Vec<f64>,
    /// `penetration` per row.
    pub penetration: Vec<f64>,
}

impl TrajectoryRows {
    /// Last time minus first time (0 for fewer than two rows).
    pub fn duration(&self) -> f64 {
        match (self.times.first(), self.times.last()) {
            (Some(a), Some(b)) => b - a,
            _ => 0.0,
        }
    }
}

/// Reads a trajectory CSV (cli.md's format) for `model`: a `t` column and a
/// `q:NAME` column for every coordinate of the model, in any order; other columns
/// are read if they are `energy`, `contacts`, `penetration` and otherwise ignored.
/// Every error names `file` and the column or row (rows counted from 1 after the
/// header, lines from 1).
pub fn read_trajectory(text: &str, file: &str, model: &Model) -> Result<TrajectoryRows, ViewError> {
    let bad = |m: String| ViewError::Csv(format!("{file}: {m}"));
    let mut lines = text.lines().enumerate();
    let header: Vec<&str> = match lines.next() {
        Some((_, h)) if !h.trim().is_empty() => h.split(',').map(str::trim).collect(),
        _ => return Err(bad("empty file (no header row)".into())),
    };
    let col = |name: &str| header.iter().position(|h| *h == name);
    let (q_names, _) = crate::sim::column_names(model);
    let t_col = col("t").ok_or_else(|| bad("no \"t\" column in the header".into()))?;
    let mut q_cols = Vec::with_capacity(q_names.len());
    for n in &q_names {
        q_cols.push(col(n).ok_or_else(|| {
            bad(format!(
                "no \"{n}\" column: the trajectory does not fit this URDF{}",
                if model.floating_base {
                    " (with --floating-base)"
                } else {
                    ""
                }
            ))
        })?);
    }
    // A q column for a joint the model does not have: the CSV is another robot's.
    if let Some(extra) = header
        .iter()
        .find(|h| h.starts_with("q:") && !q_names.iter().any(|n| n == *h))
    {
        return Err(bad(format!(
            "column \"{extra}\" names no degree of freedom of this URDF{}",
            if extra.starts_with("q:base_") && !model.floating_base {
                " (simulated with --floating-base?)"
            } else {
                ""
            }
        )));
    }
    let plot_cols = [col("energy"), col("contacts"), col("penetration")];
    let mut rows = TrajectoryRows::default();
    for (row, (line_no, line)) in lines.enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let at = format!("row {} (line {})", row + 1, line_no + 1);
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        if cells.len() != header.len() {
            return Err(bad(format!(
                "{at} has {} cells, the header {} columns (a truncated row?)",
                cells.len(),
                header.len()
            )));
        }
        let num = |c: usize| -> Result<f64, ViewError> {
            let cell = cells.get(c).copied().unwrap_or("");
            let name = header.get(c).copied().unwrap_or("?");
            match cell.parse::<f64>() {
                Ok(x) if x.is_finite() => Ok(x),
                _ => Err(bad(format!(
                    "{at}, column \"{name}\": \"{}\" is not a finite number",
                    cell.chars().take(40).collect::<String>()
                ))),
            }
        };
        let t = num(t_col)?;
        if let Some(&prev) = rows.times.last() {
            if t < prev {
                return Err(bad(format!(
                    "{at}, column \"t\": time {t} goes back (the previous row has {prev})"
                )));
            }
        }
        let mut q = DVector::zeros(model.nq);
        for (k, &c) in q_cols.iter().enumerate() {
            q[k] = num(c)?;
        }
        for f in &model.free_joints {
            let i = f.iq + 3;
            let n = (q[i] * q[i] + q[i + 1] * q[i + 1] + q[i + 2] * q[i + 2] + q[i + 3] * q[i + 3])
                .sqrt();
            if (n - 1.0).abs() > 1e-3 {
                return Err(bad(format!(
                    "{at}, columns \"q:{0}_qx\"..\"q:{0}_qw\": the quaternion's norm is {n}, not 1",
                    f.name
                )));
            }
            for k in i..i + 4 {
                q[k] /= n;
            }
        }
        // spherical and floating joints inside the tree: their quaternions as written
        crate::model::configuration::normalize_quats(model, &mut q);
        let mut plot = [f64::NAN; 3];
        for (p, c) in plot.iter_mut().zip(plot_cols) {
            if let Some(c) = c {
                *p = num(c)?;
            }
        }
        rows.times.push(t);
        rows.q.push(q);
        rows.energy.push(plot[0]);
        rows.contacts.push(plot[1]);
        rows.penetration.push(plot[2]);
    }
    if rows.times.is_empty() {
        return Err(bad("no data rows after the header".into()));
    }
    Ok(rows)
}

/// Chooses which rows a page shows: the first, then the first row at or after
/// each multiple of the frame interval from it (and, by the caller, the last).
#[derive(Clone, Debug)]
pub struct FrameSampler {
    interval: f64,
    start: Option<f64>,
    next: f64,
}

impl FrameSampler {
    /// A sampler for a run of `duration` seconds whose frames cost
    /// `bytes_per_frame` each: [`FRAME_RATE`] frames a second, fewer when the
    /// poses would pass [`MAX_POSE_BYTES`].
    pub fn new(duration: f64, bytes_per_frame: usize) -> Self {
        let max_frames = (MAX_POSE_BYTES / bytes_per_frame.max(1)).max(2) as f64;
        let interval = (1.0 / FRAME_RATE).max(duration.max(0.0) / (max_frames - 1.0));
        Self {
            interval,
            start: None,
            next: f64::NEG_INFINITY,
        }
    }
    /// Whether the row at time `t` is shown (rows come in time order).
    pub fn take(&mut self, t: f64) -> bool {
        // (a tolerance of a millionth of the interval for times like 0.1 + 0.2)
        let eps = self.interval * 1e-6;
        let start = *self.start.get_or_insert(t);
        if t < self.next - eps {
            return false;
        }
        let k = ((t - start + eps) / self.interval).floor() + 1.0;
        self.next = start + k * self.interval;
        true
    }
}

/// A contact point and the force on the link there (world frame), for the page.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactArrow {
    /// The point (m).
    pub point: [f64; 3],
    /// The force (N).
    pub force: [f64; 3],
}

/// Collects a page's frames: offered rows (time, q, plotted values, contacts)
/// are kept as [`FrameSampler`] says, and the body poses of kept rows computed by
/// forward kinematics.
#[derive(Clone, Debug)]
pub struct Recorder {
    sampler: FrameSampler,
    model: Model,
    data: Data,
    nmoving: usize,
    /// Whether contacts are recorded (`simulate --html`).
    pub with_contacts: bool,
    /// Times of the kept rows.
    pub times: Vec<f64>,
    /// Per kept row and moving body (1..nbodies): position.
    pub positions: Vec<f64>,
    /// Per kept row and moving body: rotation as a quaternion (x, y, z, w).
    pub rotations: Vec<f32>,
    /// Per kept row: energy, contact count, penetration (NaN if unknown).
    pub plot: Vec<[f64; 3]>,
    /// Contact arrows of all kept rows; row k's are `arrows[offsets[k]..offsets[k + 1]]`.
    pub arrows: Vec<ContactArrow>,
    /// Start of each kept row's arrows (one more entry than rows).
    pub offsets: Vec<usize>,
}

impl Recorder {
    /// A recorder for a run of `duration` seconds of `model`.
    pub fn new(model: &Model, duration: f64, with_contacts: bool) -> Self {
        let nmoving = model.nbodies.saturating_sub(1);
        let sampler = FrameSampler::new(duration, nmoving * 40);
        // the frames the sampler will keep (and the last), allocated here
        // rather than grown while the simulation runs
        let est = duration.max(0.0) / sampler.interval;
        let frames = if est.is_finite() {
            est.min(1e5) as usize + 3
        } else {
            2
        };
        let mut offsets = Vec::with_capacity(frames + 1);
        offsets.push(0);
        Self {
            sampler,
            model: model.clone(),
            data: Data::new(model),
            nmoving,
            with_contacts,
            times: Vec::with_capacity(frames),
            positions: Vec::with_capacity(frames * 3 * nmoving),
            rotations: Vec::with_capacity(frames * 4 * nmoving),
            plot: Vec::with_capacity(frames),
            arrows: Vec::with_capacity(if with_contacts { frames * 4 } else { 0 }),
            offsets,
        }
    }

    /// Offers a row; it is kept if the sampler takes it or `last` is set (the
    /// run's final row).
    pub fn offer(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        plot: [f64; 3],
        arrows: &[ContactArrow],
        last: bool,
    ) {
        self.offer_with(t, q, plot, last, |out| out.extend_from_slice(arrows))
    }

    /// As [`Recorder::offer`], the contact arrows pushed by `arrows` only if the
    /// row is kept (they cost nothing otherwise).
    pub fn offer_with(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        plot: [f64; 3],
        last: bool,
        arrows: impl FnOnce(&mut Vec<ContactArrow>),
    ) {
        let taken = self.sampler.take(t);
        if !(taken || (last && self.times.last() != Some(&t))) {
            return;
        }
        self.keep(t, q, plot);
        if self.with_contacts {
            arrows(&mut self.arrows);
        }
        self.offsets.push(self.arrows.len());
    }

    fn keep(&mut self, t: f64, q: &DVector<f64>, plot: [f64; 3]) {
        // q is nq long (the CSV reader and the simulation size it): the size
        // check cannot fail, and a frame without poses is never kept
        if forward_kinematics(&self.model, &mut self.data, q).is_err() {
            return;
        }
        for m in self.data.o_m_i.iter().skip(1).take(self.nmoving) {
            self.positions.extend_from_slice(m.trans.as_slice());
            let r = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(m.rot));
            let c = r.coords;
            self.rotations
                .extend_from_slice(&[c.x as f32, c.y as f32, c.z as f32, c.w as f32]);
        }
        self.times.push(t);
        self.plot.push(plot);
    }
}

/// The shape of a visual, as the page draws it.
#[derive(Clone, Debug, PartialEq)]
pub enum VisualShape {
    /// Index into [`Geometry::meshes`].
    Mesh(usize),
    /// Full extents along x, y, z.
    Box([f64; 3]),
    /// Along z, centred.
    Cylinder {
        /// Radius (m).
        radius: f64,
        /// Length (m).
        length: f64,
    },
    /// A cylinder with hemispherical caps, along z, centred.
    Capsule {
        /// Radius (m).
        radius: f64,
        /// Length of the cylindrical part (m).
        length: f64,
    },
    /// Centred sphere.
    Sphere {
        /// Radius (m).
        radius: f64,
    },
    /// Centred ellipsoid (an MJCF geom).
    Ellipsoid {
        /// Semi-axes along x, y, z (m).
        radii: [f64; 3],
    },
}

/// One drawn piece of a link: its shape, its placement on its body and its colour.
#[derive(Clone, Debug, PartialEq)]
pub struct Visual {
    /// The URDF link it belongs to.
    pub link: String,
    /// The body that carries it (index into the model's bodies; 0 is the world).
    pub body: usize,
    /// `body_M_visual`.
    pub placement: Se3,
    /// What is drawn.
    pub shape: VisualShape,
    /// Red, green, blue, alpha in 0..1.
    pub rgba: [f64; 4],
}

/// The robot's drawn geometry: distinct meshes (simplified) and the visuals that
/// place them and the primitive shapes.
#[derive(Clone, Debug, Default)]
pub struct Geometry {
    /// Distinct (file, scale) meshes, simplified where they were too large.
    pub meshes: Vec<TriMesh>,
    /// Per mesh, the colour of each triangle where its file gives one (DAE
    /// materials; empty or `None` where it does not: the visual's colour).
    pub mesh_colors: Vec<Vec<Option<Rgba>>>,
    /// How many of `meshes` were simplified.
    pub simplified: usize,
    /// Every drawn piece.
    pub visuals: Vec<Visual>,
    /// Visual elements left out (malformed), one line each, naming the URDF and link.
    pub warnings: Vec<String>,
    /// The loop constraints drawn (mechanisms.md): a line between each
    /// `point`/`frame` constraint's two anchor points.
    pub loops: Vec<LoopMark>,
}

/// The colour of a visual without a material, and of collision geometry.
const DEFAULT_RGBA: [f64; 4] = [0.72, 0.74, 0.78, 1.0];
/// The side (m) of the box drawn for a link whose visual mesh is missing and
/// that has no collision geometry.
pub const PLACEHOLDER_BOX: f64 = 0.05;
/// The colour of that box (a translucent red: "something is missing here").
const PLACEHOLDER_RGBA: [f64; 4] = [0.9, 0.25, 0.2, 0.6];

impl Geometry {
    /// Reads the URDF's visual geometry (its collision geometry for a link
    /// without visuals) and every mesh it names. A visual mesh file that is not
    /// found is a warning (naming the URDF, the link and the file), and the link
    /// is drawn as its collision geometry, or as a [`PLACEHOLDER_BOX`] without any;
    /// a collision mesh drawn that is not found, or a mesh that cannot be read, is
    /// an error naming the URDF, the link and the mesh file.
    pub fn load(model: &Model, urdf: &Path, package_paths: &[PathBuf]) -> Result<Self, ViewError> {
        Self::load_prefixed(model, urdf, "", package_paths)
    }

    /// As [`Geometry::load`] for the URDF of one model of a scene, whose links
    /// are `PREFIX` + the URDF's link name in `model`.
    pub fn load_prefixed(
        model: &Model,
        urdf: &Path,
        prefix: &str,
        package_paths: &[PathBuf],
    ) -> Result<Self, ViewError> {
        let name = urdf.display().to_string();
        let text = std::fs::read_to_string(urdf)
            .map_err(|e| ViewError::Geometry(format!("{name}: cannot read: {e}")))?;
        let drawables =
            visuals::read(&text).map_err(|e| ViewError::Geometry(format!("{name}: {e}")))?;
        let mut geometry = Geometry {
            warnings: drawables
                .warnings
                .iter()
                .map(|w| format!("{name}: {w}"))
                .collect(),
            ..Geometry::default()
        };
        let mut mesh_index: HashMap<(PathBuf, [u64; 3]), usize> = HashMap::new();
        let resolve =
            |filename: &str| crate::contact::resolve_mesh_path(filename, Some(urdf), package_paths);
        for link in &drawables.links {
            let Some(frame) = model
                .frame_index(&format!("{prefix}{}", link.name))
                .and_then(|k| model.frames.get(k))
            else {
                continue;
            };
            // The pieces drawn: the visuals whose files exist; for any that is
            // missing, the collision geometry (once) or a placeholder box.
            let mut drawn: Vec<(&str, &visuals::Piece)> = Vec::new();
            let mut missing = Vec::new();
            if link.visuals.is_empty() {
                drawn.extend(link.collisions.iter().map(|p| ("collision", p)));
            } else {
                for piece in &link.visuals {
                    match &piece.shape {
                        Shape::Mesh { filename, .. } if resolve(filename).is_none() => {
                            missing.push(filename.as_str());
                        }
                        _ => drawn.push(("visual", piece)),
                    }
                }
            }
            if !missing.is_empty() {
                let instead = if link.collisions.is_empty() {
                    "a placeholder box is drawn"
                } else {
                    "its collision geometry is drawn"
                };
                for filename in &missing {
                    geometry.warnings.push(format!(
                        "{name}: link \"{}\": <visual> mesh file \"{filename}\" not found \
                         (a package:// path needs --package-path DIR): {instead}",
                        link.name
                    ));
                }
                drawn.extend(link.collisions.iter().map(|p| ("collision", p)));
            }
            let placeholder =
                (!missing.is_empty() && link.collisions.is_empty()).then(|| visuals::Piece {
                    rot: Matrix3::identity(),
                    xyz: Vector3::zeros(),
                    shape: Shape::Box {
                        size: [PLACEHOLDER_BOX; 3],
                    },
                    material: None,
                    color: Some(PLACEHOLDER_RGBA),
                });
            drawn.extend(placeholder.iter().map(|p| ("visual", p)));
            for (element, piece) in drawn {
                let at = || format!("{name}: link \"{}\": <{element}>", link.name);
                let placement = frame.placement.compose(&Se3::new(piece.rot, piece.xyz));
                let shape = match &piece.shape {
                    Shape::Box { size } => VisualShape::Box(*size),
                    &Shape::Cylinder { radius, length } => VisualShape::Cylinder { radius, length },
                    &Shape::Capsule { radius, length } => VisualShape::Capsule { radius, length },
                    &Shape::Sphere { radius } => VisualShape::Sphere { radius },
                    Shape::Mesh { filename, scale } => {
                        let path = resolve(filename).ok_or_else(|| {
                            ViewError::Geometry(format!(
                                "{}: mesh file \"{filename}\" not found (a package:// path needs --package-path DIR)",
                                at()
                            ))
                        })?;
                        let key = (path.clone(), scale.map(f64::to_bits));
                        let k = match mesh_index.get(&key) {
                            Some(&k) => k,
                            None => {
                                let (m, colors) = load_mesh_colored(&path, *scale)
                                    .map_err(|e| ViewError::Geometry(format!("{}: {e}", at())))?;
                                geometry.meshes.push(m);
                                geometry.mesh_colors.push(colors);
                                mesh_index.insert(key, geometry.meshes.len() - 1);
                                geometry.meshes.len() - 1
                            }
                        };
                        VisualShape::Mesh(k)
                    }
                    // a URDF has none (a scene's terrain is drawn by the scene's page)
                    Shape::HeightField { .. } => continue,
                };
                let rgba = piece
                    .color
                    .or_else(|| {
                        piece
                            .material
                            .as_ref()
                            .and_then(|m| drawables.materials.get(m).copied())
                    })
                    .map(|c| c.map(|x| x.clamp(0.0, 1.0)))
                    .unwrap_or(DEFAULT_RGBA);
                geometry.visuals.push(Visual {
                    link: format!("{prefix}{}", link.name),
                    body: frame.body,
                    placement,
                    shape,
                    rgba,
                });
            }
        }
        geometry.simplify_to(MAX_MESH_TRIANGLES, MAX_PAGE_TRIANGLES);
        Ok(geometry)
    }

    /// Simplifies the meshes so that none has more than `per_mesh` triangles and
    /// all of them together at most `total`: every mesh is kept whole up to a
    /// common limit L (the largest with Σ min(nᵢ, L) ≤ total, at most
    /// `per_mesh`), larger ones are simplified to L.
    pub fn simplify_to(&mut self, per_mesh: usize, total: usize) {
        let limit = triangle_limit(
            &self
                .meshes
                .iter()
                .map(|m| m.triangles.len())
                .collect::<Vec<_>>(),
            per_mesh,
            total,
        );
        self.mesh_colors.resize(self.meshes.len(), Vec::new());
        for (m, colors) in self.meshes.iter_mut().zip(self.mesh_colors.iter_mut()) {
            if m.triangles.len() > limit {
                let (s, kept) = simplify_keeping(m, limit);
                if !colors.is_empty() {
                    *colors = kept
                        .iter()
                        .map(|&k| colors.get(k).copied().flatten())
                        .collect();
                }
                *m = s;
                self.simplified += 1;
            }
        }
    }
}

/// The largest L ≤ `per_mesh` with Σ min(nᵢ, L) ≤ `total` for triangle counts
/// `counts` (water filling; at least 12, a box's worth, for a tiny `total`).
fn triangle_limit(counts: &[usize], per_mesh: usize, total: usize) -> usize {
    let mut sorted: Vec<usize> = counts.iter().map(|&n| n.min(per_mesh)).collect();
    sorted.sort_unstable();
    if sorted.iter().sum::<usize>() <= total {
        return per_mesh;
    }
    // meshes below the level keep their count; the level is shared by the rest
    let mut left = total;
    for (k, &n) in sorted.iter().enumerate() {
        let rest = sorted.len() - k;
        if n * rest > left {
            return (left / rest).max(12);
        }
        left -= n;
    }
    per_mesh
}

/// The mesh's bounding box (lower corner, upper corner).
fn bounds(m: &TriMesh) -> (Vector3<f64>, Vector3<f64>) {
    let mut lo = Vector3::repeat(f64::INFINITY);
    let mut hi = Vector3::repeat(f64::NEG_INFINITY);
    for v in &m.vertices {
        lo = lo.inf(v);
        hi = hi.sup(v);
    }
    if m.vertices.is_empty() {
        (Vector3::zeros(), Vector3::zeros())
    } else {
        (lo, hi)
    }
}

/// Vertex clustering: the mesh on ever coarser grids until it has at most
/// `max_triangles` triangles (each cell's vertices merged into their mean,
/// collapsed and repeated triangles dropped).
pub fn simplify(m: &TriMesh, max_triangles: usize) -> TriMesh {
    simplify_keeping(m, max_triangles).0
}

/// [`simplify`], and for each triangle of the result the index of the input
/// triangle it comes from.
pub fn simplify_keeping(m: &TriMesh, max_triangles: usize) -> (TriMesh, Vec<usize>) {
    let (lo, hi) = bounds(m);
    let size = (hi - lo).max();
    if m.triangles.len() <= max_triangles || size <= 0.0 {
        return (m.clone(), (0..m.triangles.len()).collect());
    }
    let mut cells = (max_triangles as f64).sqrt() * 1.5;
    loop {
        let out = cluster(m, lo, size / cells);
        if out.0.triangles.len() <= max_triangles || cells < 2.0 {
            return out;
        }
        cells *= 0.8;
    }
}

/// One vertex-clustering pass with cubic cells of side `h` from `lo`: the mesh
/// and the input triangle each output triangle comes from.
fn cluster(m: &TriMesh, lo: Vector3<f64>, h: f64) -> (TriMesh, Vec<usize>) {
    let mut cell_of: HashMap<[i64; 3], u32> = HashMap::new();
    let mut sums: Vec<(Vector3<f64>, f64)> = Vec::new();
    let remap: Vec<u32> = m
        .vertices
        .iter()
        .map(|v| {
            let c = ((v - lo) / h).map(|x| x.floor() as i64);
            let next = sums.len() as u32;
            let k = *cell_of.entry([c.x, c.y, c.z]).or_insert(next);
            if k == next {
                sums.push((Vector3::zeros(), 0.0));
            }
            if let Some(s) = sums.get_mut(k as usize) {
                s.0 += v;
                s.1 += 1.0;
            }
            k
        })
        .collect();
    let mut seen = std::collections::HashSet::new();
    let mut triangles = Vec::new();
    let mut kept = Vec::new();
    for (k, t) in m.triangles.iter().enumerate() {
        let [a, b, c] = t.map(|i| remap.get(i as usize).copied().unwrap_or(0));
        if a == b || b == c || a == c {
            continue;
        }
        let mut key = [a, b, c];
        key.sort_unstable();
        if seen.insert(key) {
            triangles.push([a, b, c]);
            kept.push(k);
        }
    }
    let mesh = TriMesh {
        vertices: sums.into_iter().map(|(s, n)| s / n).collect(),
        triangles,
    };
    (mesh, kept)
}

/// Standard base64 (with padding) of `bytes`.
fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for c in bytes.chunks(3) {
        let b = [
            c[0],
            c.get(1).copied().unwrap_or(0),
            c.get(2).copied().unwrap_or(0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= c.len() {
                out.push(A[((n >> (18 - 6 * k)) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// A rotation matrix row-major (nalgebra stores column-major: the transpose's storage).
fn rows9(r: &Matrix3<f64>) -> Vec<f64> {
    r.transpose().as_slice().to_vec()
}

/// The mesh quantised: 16 bits a coordinate over its bounding box, indices as
/// 16 bits when they fit (else 32). With triangle colours (`colors`, one a
/// triangle, or empty), the triangles are ordered by colour and `groups` lists
/// `[first index, index count, rgba or null]` per colour (null: the visual's).
fn mesh_json(m: &TriMesh, colors: &[Option<Rgba>]) -> Value {
    let (lo, hi) = bounds(m);
    let ext = (hi - lo).map(|e| if e > 0.0 { e } else { 1.0 });
    let mut v = Vec::with_capacity(m.vertices.len() * 6);
    for p in &m.vertices {
        for k in 0..3 {
            let q = ((p[k] - lo[k]) / ext[k] * 65535.0)
                .round()
                .clamp(0.0, 65535.0) as u16;
            v.extend_from_slice(&q.to_le_bytes());
        }
    }
    // colour groups in order of first appearance
    let key = |c: &Option<Rgba>| c.map(|c| c.map(f64::to_bits));
    let mut group_of: HashMap<Option<[u64; 4]>, usize> = HashMap::new();
    let mut palette: Vec<Option<Rgba>> = Vec::new();
    let mut members: Vec<Vec<usize>> = Vec::new();
    let colored = colors.iter().any(Option::is_some);
    for t in 0..m.triangles.len() {
        let c = if colored {
            colors.get(t).copied().flatten()
        } else {
            None
        };
        let g = *group_of.entry(key(&c)).or_insert_with(|| {
            palette.push(c);
            members.push(Vec::new());
            palette.len() - 1
        });
        if let Some(list) = members.get_mut(g) {
            list.push(t);
        }
    }
    let wide = m.vertices.len() > 65536;
    let mut i = Vec::with_capacity(m.triangles.len() * if wide { 12 } else { 6 });
    let mut groups = Vec::new();
    let mut first = 0;
    for (c, list) in palette.iter().zip(&members) {
        for t in list.iter().filter_map(|&t| m.triangles.get(t)) {
            for &k in t {
                if wide {
                    i.extend_from_slice(&k.to_le_bytes());
                } else {
                    i.extend_from_slice(&(k as u16).to_le_bytes());
                }
            }
        }
        groups.push(json!([first, 3 * list.len(), c]));
        first += 3 * list.len();
    }
    let mut out = json!({
        "min": [lo.x, lo.y, lo.z],
        "ext": [ext.x, ext.y, ext.z],
        "v": base64(&v),
        "i": base64(&i),
        "wide": wide,
    });
    if colored {
        out["groups"] = Value::Array(groups);
    }
    out
}

/// The page's data (one JSON object the viewer reads).
fn page_data(model: &Model, geometry: &Geometry, rec: &Recorder, ground: Option<f64>) -> Value {
    let links: Vec<Value> = model
        .frames
        .iter()
        .map(|f| {
            json!({"name": f.name, "body": f.body,
                   "p": f.placement.trans.as_slice(), "R": rows9(&f.placement.rot)})
        })
        .collect();
    let visuals: Vec<Value> = geometry
        .visuals
        .iter()
        .map(|v| {
            let (kind, dims, mesh) = match &v.shape {
                VisualShape::Mesh(k) => ("mesh", vec![], Some(*k)),
                VisualShape::Box(s) => ("box", s.to_vec(), None),
                VisualShape::Cylinder { radius, length } => {
                    ("cylinder", vec![*radius, *length], None)
                }
                VisualShape::Capsule { radius, length } => {
                    ("capsule", vec![*radius, *length], None)
                }
                VisualShape::Sphere { radius } => ("sphere", vec![*radius], None),
                VisualShape::Ellipsoid { radii } => ("ellipsoid", radii.to_vec(), None),
            };
            json!({"link": v.link, "body": v.body, "p": v.placement.trans.as_slice(),
                   "R": rows9(&v.placement.rot), "kind": kind, "dims": dims,
                   "mesh": mesh, "rgba": v.rgba})
        })
        .collect();
    let f64s: Vec<u8> = rec.positions.iter().flat_map(|x| x.to_le_bytes()).collect();
    let f32s: Vec<u8> = rec.rotations.iter().flat_map(|x| x.to_le_bytes()).collect();
    let series = |k: usize| -> Vec<Option<f64>> {
        rec.plot
            .iter()
            .map(|p| Some(p[k]).filter(|x| x.is_finite()))
            .collect()
    };
    let contacts = if rec.with_contacts {
        let arrows: Vec<u8> = rec
            .arrows
            .iter()
            .flat_map(|a| a.point.iter().chain(a.force.iter()).map(|&x| x as f32))
            .flat_map(f32::to_le_bytes)
            .collect();
        json!({"arrows": base64(&arrows), "offsets": rec.offsets})
    } else {
        Value::Null
    };
    json!({
        "robot": model.name,
        "ground": ground,
        "moving": rec.nmoving,
        "links": links,
        "visuals": visuals,
        "meshes": geometry
            .meshes
            .iter()
            .enumerate()
            .map(|(k, m)| mesh_json(m, geometry.mesh_colors.get(k).map(Vec::as_slice).unwrap_or_default()))
            .collect::<Vec<_>>(),
        "times": rec.times,
        "positions": base64(&f64s),
        "rotations": base64(&f32s),
        "energy": series(0),
        "contacts": series(1),
        "penetration": series(2),
        "contactForces": contacts,
        "loops": geometry.loops.iter().map(|l| json!({"name": l.name, "body1": l.body1,
            "p1": l.point1, "body2": l.body2, "p2": l.point2})).collect::<Vec<_>>(),
    })
}

/// Text safe inside HTML element content and attributes.
fn html_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The whole page: the template with its style, script and data inlined.
pub fn page_html(
    model: &Model,
    geometry: &Geometry,
    rec: &Recorder,
    ground: Option<f64>,
) -> String {
    // JSON inside <script>: "</" only occurs in strings, where "<\/" means the same.
    let data = page_data(model, geometry, rec, ground)
        .to_string()
        .replace("</", "<\\/");
    let mut out = String::with_capacity(PAGE_HTML.len() + VIEWER_JS.len() + data.len() + 1024);
    let template = PAGE_HTML.replace("{{TITLE}}", &html_escape(&model.name));
    let mut rest = template.as_str();
    for (marker, text) in [
        ("{{CSS}}", VIEWER_CSS.to_string()),
        ("{{DATA}}", data),
        ("{{JS}}", VIEWER_JS.to_string()),
    ] {
        if let Some((head, tail)) = rest.split_once(marker) {
            out.push_str(head);
            out.push_str(&text);
            rest = tail;
        }
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_matches_the_rfc_vectors() {
        // RFC 4648 §10.
        for (raw, enc) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(raw.as_bytes()), enc);
        }
        assert_eq!(base64(&[0xfb, 0xff]), "+/8=");
    }

    #[test]
    fn sampler_keeps_one_row_a_frame_interval() {
        // Rows every millisecond for 1 s: the first row at or after each 1/60 s.
        let mut s = FrameSampler::new(1.0, 100);
        let kept: Vec<usize> = (0..=1000).filter(|&k| s.take(k as f64 * 1e-3)).collect();
        let want: Vec<usize> = (0..=60)
            .map(|j| (j as f64 * 1000.0 / 60.0 - 1e-9).ceil() as usize)
            .collect();
        assert_eq!(kept, want);
        // A long run at 1 kB a frame: the poses stay within MAX_POSE_BYTES.
        let mut s = FrameSampler::new(1e4, 1000);
        let n = (0..=1_000_000).filter(|&k| s.take(k as f64 * 1e-2)).count();
        assert!(
            n * 1000 <= MAX_POSE_BYTES && n * 1000 > MAX_POSE_BYTES * 9 / 10,
            "{n}"
        );
    }

    /// A UV sphere of radius 1 with about 2·n² triangles.
    fn sphere(n: usize) -> TriMesh {
        let mut m = TriMesh::default();
        for i in 0..=n {
            let th = std::f64::consts::PI * i as f64 / n as f64;
            for j in 0..n {
                let ph = 2.0 * std::f64::consts::PI * j as f64 / n as f64;
                m.vertices.push(Vector3::new(
                    th.sin() * ph.cos(),
                    th.sin() * ph.sin(),
                    th.cos(),
                ));
            }
        }
        for i in 0..n {
            for j in 0..n {
                let (a, b) = ((i * n + j) as u32, (i * n + (j + 1) % n) as u32);
                let (c, d) = (a + n as u32, b + n as u32);
                m.triangles.push([a, b, d]);
                m.triangles.push([a, d, c]);
            }
        }
        m
    }

    #[test]
    fn triangle_limit_fills_the_budget_from_below() {
        // Under the budget: the per-mesh cap.
        assert_eq!(triangle_limit(&[10, 20, 30], 100, 1000), 100);
        // 10 and 20 kept whole; the other two share 120 - 30 = 90: L = 45,
        // and Σ min(n, 45) = 10 + 20 + 45 + 45 = 120.
        assert_eq!(triangle_limit(&[500, 10, 20, 80], 1000, 120), 45);
        // The cap first: 60 000 counts as 20 000.
        assert_eq!(triangle_limit(&[60_000, 100], 20_000, 20_100), 20_000);
        // A tiny budget still leaves a box's worth.
        assert_eq!(triangle_limit(&[1000, 1000], 1000, 4), 12);
        // Brute force: the largest L with Σ min(nᵢ, L) ≤ total.
        let counts = [3, 900, 77, 4000, 1200, 50];
        for total in [100, 1000, 3000, 6000] {
            let best = (0..=4000)
                .filter(|&l| counts.iter().map(|&n: &usize| n.min(l)).sum::<usize>() <= total)
                .max()
                .unwrap();
            assert_eq!(
                triangle_limit(&counts, 4000, total),
                best.max(12),
                "{total}"
            );
        }
    }

    #[test]
    fn simplify_stays_under_the_limit_and_on_the_shape() {
        let m = sphere(200);
        assert!(m.triangles.len() > 70_000);
        let s = simplify(&m, 5_000);
        assert!(
            s.triangles.len() <= 5_000 && s.triangles.len() > 1_000,
            "{}",
            s.triangles.len()
        );
        // Cluster means lie inside the sphere, near its surface; the bounding box
        // is nearly kept; every index is valid.
        for v in &s.vertices {
            assert!(v.norm() <= 1.0 + 1e-12 && v.norm() > 0.9, "{}", v.norm());
        }
        let (lo, hi) = bounds(&s);
        assert!((hi - lo).iter().all(|e| *e > 1.9), "{lo} {hi}");
        assert!(s
            .triangles
            .iter()
            .flatten()
            .all(|&i| (i as usize) < s.vertices.len()));
        // A mesh under the limit is kept as it is.
        assert_eq!(simplify(&m, 100_000), m);
    }

    #[test]
    fn collision_geometry_where_a_link_has_no_visual_and_material_colours() {
        let dir = tempfile::tempdir().unwrap();
        let urdf = dir.path().join("r.urdf");
        std::fs::write(
            &urdf,
            r#"<robot name="r">
<material name="red"><color rgba="1 0 0 1"/></material>
<link name="a"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial>
<collision><origin xyz="0 0 1"/><geometry><box size="1 2 3"/></geometry></collision></link>
<joint name="j" type="revolute"><parent link="a"/><child link="b"/><origin xyz="1 0 0"/><axis xyz="0 0 1"/>
<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
<link name="b"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial>
<visual><origin xyz="0 0.5 0"/><geometry><sphere radius="0.25"/></geometry><material name="red"/></visual>
<visual><geometry><cylinder radius="0.1" length="2"/></geometry><material name="x"><color rgba="0 0 1 0.5"/></material></visual>
<collision><geometry><sphere radius="9"/></geometry></collision></link>
<joint name="f" type="fixed"><parent link="b"/><child link="c"/><origin xyz="0 0 2"/></joint>
<link name="c"><visual><geometry><box size="1 1 1"/></geometry></visual></link>
</robot>"#,
        )
        .unwrap();
        let model = crate::load_file(&urdf, LoadOptions::default()).unwrap();
        let g = Geometry::load(&model, &urdf, &[]).unwrap();
        let v: Vec<_> = g
            .visuals
            .iter()
            .map(|v| (v.link.as_str(), v.shape.clone(), v.rgba, v.placement.trans))
            .collect();
        assert_eq!(v.len(), 4, "{v:?}");
        assert_eq!(v[0].0, "a");
        assert_eq!(v[0].1, VisualShape::Box([1.0, 2.0, 3.0]));
        assert_eq!(v[0].2, DEFAULT_RGBA);
        assert_eq!(v[1].1, VisualShape::Sphere { radius: 0.25 });
        assert_eq!(v[1].2, [1.0, 0.0, 0.0, 1.0]);
        assert_eq!(v[2].2, [0.0, 0.0, 1.0, 0.5]);
        // c is welded to b: its box sits on b's body, 2 m up.
        assert_eq!(v[3].0, "c");
        let body_b = model.frames[model.frame_index("b").unwrap()].body;
        assert_eq!(g.visuals[3].body, body_b);
        assert!((v[3].3 - Vector3::new(0.0, 0.0, 2.0)).norm() < 1e-12);
        assert!((v[1].3 - Vector3::new(0.0, 0.5, 0.0)).norm() < 1e-12);
    }
}
