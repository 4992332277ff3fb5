//! The replay page of a scene (scene.md "Names and output"): every model's
//! visual geometry (links `MODEL/LINK`), every obstacle on the world body, the
//! height field as a triangulated surface.

use super::{
    read_trajectory, write_page, Geometry, PageSummary, Recorder, ViewError, Visual, VisualShape,
    MAX_MESH_TRIANGLES, MAX_PAGE_TRIANGLES,
};
use crate::mesh::{load_mesh, TriMesh};
use crate::model::Shape;
use crate::scene::{HeightFieldSpec, Scene};
use nalgebra::Vector3;
use std::path::PathBuf;

/// The colour of obstacles (stone grey).
const OBSTACLE_RGBA: [f64; 4] = [0.55, 0.52, 0.48, 1.0];

/// `urdyn view --scene SCENE.json TRAJ.csv --out PAGE.html`'s options.
#[derive(Clone, Debug)]
pub struct SceneViewArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// The trajectory CSV that `simulate --scene ... --out` wrote.
    pub traj: PathBuf,
    /// Roots for `package://NAME/...` mesh paths.
    pub package_path: Vec<PathBuf>,
    /// The page to write (atomically).
    pub out: PathBuf,
}

/// Runs `urdyn view --scene`: reads the scene and the CSV, writes the page
/// atomically (a bad input leaves no page).
pub fn run_scene(args: &SceneViewArgs) -> Result<PageSummary, ViewError> {
    let scene = Scene::from_file(&args.scene, &args.package_path)
        .map_err(|e| ViewError::Geometry(e.to_string()))?;
    let mut geometry = Geometry::load_scene(&scene, &args.package_path)?;
    // the loop constraints, their held world anchors where the start puts them
    let mut loops = scene.constraints.clone();
    let mut data = crate::model::Data::new(&scene.model);
    crate::dynamics::forward_kinematics_pass(&scene.model, &mut data, &scene.q0);
    loops.place_holds(&data);
    geometry.set_loops(&loops);
    let csv_name = args.traj.display().to_string();
    let text = std::fs::read(&args.traj)
        .map_err(|e| ViewError::Csv(format!("{csv_name}: cannot read: {e}")))?;
    let text = String::from_utf8(text)
        .map_err(|_| ViewError::Csv(format!("{csv_name}: not UTF-8 text")))?;
    let rows = read_trajectory(&text, &csv_name, &scene.model)?;
    let mut recorder = Recorder::new(&scene.model, rows.duration(), false);
    let last = rows.times.len().saturating_sub(1);
    for (k, t) in rows.times.iter().enumerate() {
        let plot = [rows.energy[k], rows.contacts[k], rows.penetration[k]];
        recorder.offer(*t, &rows.q[k], plot, &[], k == last);
    }
    write_page(
        &args.out,
        &scene.model,
        &geometry,
        &recorder,
        scene.ground.map(|g| g.height),
    )
}

impl Geometry {
    /// The drawn geometry of a scene: each model's URDF visuals (as
    /// [`Geometry::load`], links `MODEL/LINK`) and every obstacle.
    pub fn load_scene(scene: &Scene, package_paths: &[PathBuf]) -> Result<Self, ViewError> {
        let mut all = Geometry::default();
        for m in &scene.models {
            let g = if m.mjcf {
                mjcf_model_geometry(scene, m)?
            } else {
                Geometry::load_prefixed(
                    &scene.model,
                    &m.urdf,
                    &format!("{}/", m.name),
                    package_paths,
                )?
            };
            all.append(g);
        }
        for o in &scene.obstacles {
            let shape = match &o.shape {
                Shape::Box { size } => VisualShape::Box(*size),
                &Shape::Cylinder { radius, length } => VisualShape::Cylinder { radius, length },
                &Shape::Capsule { radius, length } => VisualShape::Capsule { radius, length },
                &Shape::Sphere { radius } => VisualShape::Sphere { radius },
                Shape::Mesh { filename, scale } => {
                    let m = load_mesh(std::path::Path::new(filename), *scale).map_err(|e| {
                        ViewError::Geometry(format!("{}: obstacle \"{}\": {e}", scene.file, o.name))
                    })?;
                    all.meshes.push(m);
                    VisualShape::Mesh(all.meshes.len() - 1)
                }
                Shape::HeightField { heights, size } => {
                    all.meshes.push(height_field_mesh(&HeightFieldSpec {
                        heights: heights.clone(),
                        size: *size,
                    }));
                    VisualShape::Mesh(all.meshes.len() - 1)
                }
            };
            all.visuals.push(Visual {
                link: o.name.clone(),
                body: 0,
                placement: o.placement,
                shape,
                rgba: OBSTACLE_RGBA,
            });
        }
        all.simplify_to(MAX_MESH_TRIANGLES, MAX_PAGE_TRIANGLES);
        Ok(all)
    }

    /// Takes `other`'s meshes and visuals (its mesh indices moved past ours).
    fn append(&mut self, other: Geometry) {
        let off = self.meshes.len();
        self.meshes.extend(other.meshes);
        self.simplified += other.simplified;
        self.warnings.extend(other.warnings);
        self.visuals.extend(other.visuals.into_iter().map(|mut v| {
            if let VisualShape::Mesh(k) = &mut v.shape {
                *k += off;
            }
            v
        }));
    }
}

/// An MJCF model of a scene drawn as `urdyn view FILE.xml` draws the file
/// (view/mjcf.rs), its bodies moved to the scene's (the forest keeps a part's
/// bodies contiguous from its first tree's first body), its links `MODEL/LINK`,
/// the file's world geoms placed by the model's pose.
fn mjcf_model_geometry(scene: &Scene, m: &crate::scene::SceneModel) -> Result<Geometry, ViewError> {
    let name = m.urdf.display().to_string();
    let (alone, world) = crate::mjcf::load_file_with_world(&m.urdf)
        .map_err(|e| ViewError::Geometry(format!("{}: {name}: {e}", scene.file)))?;
    let mut g = super::mjcf::geometry(&alone, &world, &name);
    let b0 = scene
        .model
        .trees
        .iter()
        .find(|t| t.name == m.name)
        .map_or(1, |t| t.bodies.start);
    for v in &mut g.visuals {
        v.link = format!("{}/{}", m.name, v.link);
        if v.body == 0 {
            v.placement = m.pose.compose(&v.placement);
        } else {
            v.body += b0 - 1;
        }
    }
    Ok(g)
}

/// The height field's surface: one vertex a grid point (rows along y from −y,
/// each along x from −x, centred on the frame), two triangles a cell, facing up.
pub fn height_field_mesh(h: &HeightFieldSpec) -> TriMesh {
    let (nr, nc) = (h.heights.len(), h.heights.first().map_or(0, Vec::len));
    let mut m = TriMesh::default();
    if nr < 2 || nc < 2 {
        return m;
    }
    let (sx, sy) = (h.size[0], h.size[1]);
    for (r, row) in h.heights.iter().enumerate() {
        for (c, &z) in row.iter().enumerate() {
            // x, y = −s/2 + index · s / (n − 1)
            let x = -0.5 * sx + c as f64 * sx / (nc - 1) as f64;
            let y = -0.5 * sy + r as f64 * sy / (nr - 1) as f64;
            m.vertices.push(Vector3::new(x, y, z));
        }
    }
    for r in 0..nr - 1 {
        for c in 0..nc - 1 {
            let a = (r * nc + c) as u32;
            let (b, d, e) = (a + 1, a + nc as u32, a + nc as u32 + 1);
            m.triangles.push([a, b, e]);
            m.triangles.push([a, e, d]);
        }
    }
    m
}

/// A loop constraint as the page draws it: its two anchor points, each fixed
/// in a body (body 0: the world, the point in world coordinates).
#[derive(Clone, Debug, PartialEq)]
pub struct LoopMark {
    /// The constraint's name.
    pub name: String,
    /// Side 1's body and its anchor point in that body's frame.
    pub body1: usize,
    /// Side 1's anchor point (m, body frame).
    pub point1: [f64; 3],
    /// Side 2's body (0: the world).
    pub body2: usize,
    /// Side 2's anchor point (m, body frame, or world for the world).
    pub point2: [f64; 3],
}

impl Geometry {
    /// Draws the `point` and `frame` constraints of `set` (its held world
    /// anchors placed: a simulation's set, or one placed at the start state);
    /// `joint` constraints have no anchor points and are not drawn.
    pub fn set_loops(&mut self, set: &crate::model::Constraints) {
        self.loops = set
            .items
            .iter()
            .filter(|c| !matches!(c.kind, crate::model::ConstraintKind::Joint { .. }))
            .map(|c| {
                let p = |t: &nalgebra::Vector3<f64>| [t.x, t.y, t.z];
                LoopMark {
                    name: c.name.clone(),
                    body1: c.a.body,
                    point1: p(&c.a.local.trans),
                    body2: c.b.body,
                    point2: p(&c.b.local.trans),
                }
            })
            .collect();
    }
}
