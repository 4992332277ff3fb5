//! Scenes (`../shared/spec/scene.md`): several URDF models, static obstacles
//! and an optional ground in one simulation. Import layer, beside
//! [`crate::urdf`]: a SCENE.json (or a [`SceneSpec`] built in code) is checked
//! key by key, its URDFs and SRDFs loaded, and the models joined into one
//! [`Model`] (a forest: one tree per model, names `MODEL/NAME`, q and v each
//! model in file order); obstacles become collision geometry on the world
//! (body 0). What the simulation needs besides (ground, friction, the starting
//! state, the pairs that never touch) is kept on the [`Scene`].

mod file;
mod forest;
pub mod srdf;

pub use file::{
    BaseSpec, GroundSpec, HeightFieldSpec, InitialBaseSpec, InitialSpec, ModelSpec, ObstacleSpec,
    RoundSpec, SceneSpec,
};
pub use forest::{forest, Part};

use crate::model::{nearest, CollisionGeom, Model, Shape, OBSTACLE};
use crate::spatial::{quat_to_matrix, Se3};
use crate::urdf::{load_file, resolve_mesh_path, LoadOptions};
use nalgebra::{DVector, Vector3};
use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// A bad scene: one line naming the scene file, the key path and what is wrong.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}: {key}: {message}")]
pub struct SceneError {
    /// The scene file (as given).
    pub file: String,
    /// The key path in it (`models[1].urdf`, `obstacles[0] (step)`).
    pub key: String,
    /// What is wrong.
    pub message: String,
    /// The path of a file that does not exist, when that is what is wrong.
    pub missing: Option<PathBuf>,
}

impl SceneError {
    fn new(file: &str, key: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            file: file.into(),
            key: key.into(),
            message: message.into(),
            missing: None,
        }
    }
}

/// The ground plane of a scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ground {
    /// Height of the plane z = height (m).
    pub height: f64,
    /// Its side's friction coefficient.
    pub friction: f64,
    /// Torsional friction coefficient (m), if the scene sets one
    /// (docs/theory.md §"Torsional and rolling friction").
    pub torsion: Option<f64>,
    /// Rolling friction coefficient (m), if the scene sets one.
    pub rolling: Option<f64>,
}

/// One model of a loaded scene.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneModel {
    /// Its name (the prefix of its names).
    pub name: String,
    /// The URDF file (resolved against the scene file's folder).
    pub urdf: PathBuf,
    /// Whether its root is on a free joint.
    pub floating: bool,
    /// `world_M_root` at the start.
    pub pose: Se3<f64>,
    /// Its links' friction coefficient.
    pub friction: f64,
    /// Contact between two of its links.
    pub self_collision: bool,
    /// Its SRDF's `<disable_collisions>` pairs that name two of its links
    /// (`MODEL/LINK` names).
    pub disabled: Vec<(String, String)>,
}

/// A static obstacle of a loaded scene (also a body-0 collision geometry of
/// [`Scene::model`] named as the obstacle).
#[derive(Debug, Clone, PartialEq)]
pub struct Obstacle {
    /// Its name.
    pub name: String,
    /// Its shape (a mesh's filename resolved against the scene file's folder).
    pub shape: Shape,
    /// `world_M_obstacle`.
    pub placement: Se3<f64>,
    /// Its friction coefficient.
    pub friction: f64,
}

/// A scene, loaded: the one [`Model`] of all its models, the obstacles (on the
/// world body), the ground, and the starting state.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The document as read (or built).
    pub spec: SceneSpec,
    /// The scene file's name in messages.
    pub file: String,
    /// The folder its relative paths are resolved against.
    pub base_dir: PathBuf,
    /// Every model as one forest (names `MODEL/NAME`), obstacles as world geometry.
    pub model: Model,
    /// The models in file order.
    pub models: Vec<SceneModel>,
    /// The obstacles in file order.
    pub obstacles: Vec<Obstacle>,
    /// The ground plane, if any.
    pub ground: Option<Ground>,
    /// Link pairs never in contact (`exclude`): `MODEL/LINK` or obstacle names.
    pub exclude: Vec<(String, String)>,
    /// The starting configuration (poses, `pose`, `initial`).
    pub q0: DVector<f64>,
    /// The starting velocity.
    pub v0: DVector<f64>,
    /// Constant generalized forces (`initial.tau`, `initial.base.force/torque`).
    pub tau0: DVector<f64>,
    /// What loaded but deserves a line (SRDF names the URDF lacks, ...).
    pub warnings: Vec<String>,
    /// The loop constraints (`"constraints"`), built against `model`; give
    /// them to [`crate::sim::Simulation::set_constraints`] after its start state.
    pub constraints: crate::model::Constraints,
}

fn read_text(path: &Path) -> Result<String, std::io::Error> {
    let bytes = std::fs::read(path)?;
    String::from_utf8(bytes)
        .map_err(|_| std::io::Error::new(std::io::ErrorKind::InvalidData, "not UTF-8 text"))
}

impl Scene {
    /// Reads and loads a SCENE.json; relative paths are taken against its folder,
    /// `package://` meshes against `package_paths` as in cli.md.
    pub fn from_file(
        path: impl AsRef<Path>,
        package_paths: &[PathBuf],
    ) -> Result<Self, SceneError> {
        let path = path.as_ref();
        let name = path.display().to_string();
        if path.is_dir() {
            return Err(SceneError::new(
                &name,
                "(file)",
                "is a directory, not a scene file",
            ));
        }
        let text = read_text(path).map_err(|e| {
            let mut err = SceneError::new(&name, "(file)", format!("cannot read: {e}"));
            if e.kind() == std::io::ErrorKind::NotFound {
                err.message = format!("file \"{name}\" not found");
                err.missing = Some(path.to_path_buf());
            }
            err
        })?;
        let dir = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        Self::from_json(&text, &name, &dir, package_paths)
    }

    /// Loads SCENE.json text; `file` names it in messages, `base_dir` resolves
    /// its relative paths.
    pub fn from_json(
        text: &str,
        file: &str,
        base_dir: &Path,
        package_paths: &[PathBuf],
    ) -> Result<Self, SceneError> {
        let spec = file::parse_spec(text).map_err(|(k, m)| SceneError::new(file, k, m))?;
        Self::from_spec(spec, file, base_dir, package_paths)
    }

    /// Loads a scene built in code (the same checks as a file's).
    pub fn from_spec(
        spec: SceneSpec,
        file: &str,
        base_dir: &Path,
        package_paths: &[PathBuf],
    ) -> Result<Self, SceneError> {
        Loader {
            file,
            base_dir,
            package_paths,
        }
        .load(spec)
    }
}

struct Loader<'a> {
    file: &'a str,
    base_dir: &'a Path,
    package_paths: &'a [PathBuf],
}

impl Loader<'_> {
    fn err(&self, key: impl Into<String>, message: impl Into<String>) -> SceneError {
        SceneError::new(self.file, key, message)
    }

    fn finite(&self, key: &str, xs: &[f64]) -> Result<(), SceneError> {
        match xs.iter().find(|x| !x.is_finite()) {
            Some(x) => Err(self.err(key, format!("non-finite number {x}"))),
            None => Ok(()),
        }
    }

    fn positive(&self, key: &str, xs: &[f64], what: &str) -> Result<(), SceneError> {
        self.finite(key, xs)?;
        match xs.iter().find(|&&x| x <= 0.0) {
            Some(x) => Err(self.err(key, format!("{what} must be positive (got {x})"))),
            None => Ok(()),
        }
    }

    fn friction(&self, key: &str, mu: Option<f64>) -> Result<f64, SceneError> {
        let mu = mu.unwrap_or(1.0);
        if !(mu.is_finite() && mu >= 0.0) {
            return Err(self.err(
                key,
                format!("friction must be a non-negative number (got {mu})"),
            ));
        }
        Ok(mu)
    }

    fn pose(
        &self,
        key: &str,
        position: Option<[f64; 3]>,
        orientation: Option<[f64; 4]>,
    ) -> Result<Se3<f64>, SceneError> {
        let p = position.unwrap_or([0.0; 3]);
        self.finite(&format!("{key}.position"), &p)?;
        let o = self.quaternion(&format!("{key}.orientation_xyzw"), orientation)?;
        Ok(Se3::new(
            quat_to_matrix(o[0], o[1], o[2], o[3]),
            Vector3::from(p),
        ))
    }

    /// A unit quaternion (x, y, z, w) normalised, or an error if further than
    /// 1e-3 from unit norm.
    fn quaternion(&self, key: &str, o: Option<[f64; 4]>) -> Result<[f64; 4], SceneError> {
        let o = o.unwrap_or([0.0, 0.0, 0.0, 1.0]);
        self.finite(key, &o)?;
        let n = o.iter().map(|x| x * x).sum::<f64>().sqrt();
        if (n - 1.0).abs() > 1e-3 {
            return Err(self.err(
                key,
                format!(
                    "not a unit quaternion: [{}, {}, {}, {}] has norm {n}",
                    o[0], o[1], o[2], o[3]
                ),
            ));
        }
        Ok([o[0] / n, o[1] / n, o[2] / n, o[3] / n])
    }

    /// A file named in the scene, resolved against the scene's folder; an error
    /// naming the key and the path when it does not exist.
    fn existing(&self, key: &str, name: &str) -> Result<PathBuf, SceneError> {
        let p = Path::new(name);
        let path = if p.is_absolute() {
            p.to_path_buf()
        } else {
            self.base_dir.join(p)
        };
        if !path.is_file() {
            let mut e = self.err(key, format!("file \"{name}\" not found"));
            if path.as_path() != p {
                e.message = format!("file \"{name}\" not found ({})", path.display());
            }
            e.missing = Some(path);
            return Err(e);
        }
        Ok(path)
    }

    fn name(&self, key: &str, name: &str, seen: &mut HashSet<String>) -> Result<(), SceneError> {
        if name.is_empty() {
            return Err(self.err(key, "empty name"));
        }
        if name.contains('/') {
            return Err(self.err(key, format!("name \"{name}\" contains '/'")));
        }
        if name.trim() != name || name.chars().any(char::is_control) {
            return Err(self.err(
                key,
                format!(
                    "name \"{}\" has spaces at an end or control characters",
                    name.escape_default()
                ),
            ));
        }
        if !seen.insert(name.to_string()) {
            return Err(self.err(key, format!("duplicate name \"{name}\"")));
        }
        Ok(())
    }

    fn load(&self, spec: SceneSpec) -> Result<Scene, SceneError> {
        let gravity = spec.gravity.unwrap_or([0.0, 0.0, -9.81]);
        self.finite("gravity", &gravity)?;
        let ground = match &spec.ground {
            None => None,
            Some(g) => {
                let height = g.height.unwrap_or(0.0);
                self.finite("ground.height", &[height])?;
                let spin = |key: &str, x: Option<f64>| match x {
                    Some(x) => self.friction(key, Some(x)).map(Some),
                    None => Ok(None),
                };
                Some(Ground {
                    height,
                    friction: self.friction("ground.friction", g.friction)?,
                    torsion: spin("ground.torsion", g.torsion)?,
                    rolling: spin("ground.rolling", g.rolling)?,
                })
            }
        };
        if spec.models.is_empty() {
            return Err(self.err("models", "a scene needs at least one model"));
        }
        let mut names = HashSet::new();
        for (i, m) in spec.models.iter().enumerate() {
            self.name(&format!("models[{i}].name"), &m.name, &mut names)?;
        }
        for (i, o) in spec.obstacles.iter().enumerate() {
            self.name(&format!("obstacles[{i}].name"), &o.name, &mut names)?;
        }

        // the models, each loaded alone, then joined
        let mut parts = Vec::new();
        let mut models = Vec::new();
        let mut srdfs = Vec::new();
        let mut warnings = Vec::new();
        for (i, m) in spec.models.iter().enumerate() {
            let key = format!("models[{i}]");
            let pose = self.pose(&key, m.position, m.orientation_xyzw)?;
            let urdf = self.existing(&format!("{key}.urdf"), &m.urdf)?;
            let floating = m.base == BaseSpec::Floating;
            let mut model = load_file(
                &urdf,
                LoadOptions {
                    floating_base: floating,
                },
            )
            .map_err(|e| self.err(format!("{key}.urdf"), e.to_string()))?;
            for c in &mut model.collisions {
                if let Shape::Mesh { filename, .. } = &mut c.shape {
                    if let Some(p) = resolve_mesh_path(filename, Some(&urdf), self.package_paths) {
                        *filename = p.display().to_string();
                    }
                }
            }
            let srdf = match &m.srdf {
                None => None,
                Some(s) => {
                    let k = format!("{key}.srdf");
                    let path = self.existing(&k, s)?;
                    let text = read_text(&path)
                        .map_err(|e| self.err(&k, format!("{s}: cannot read: {e}")))?;
                    Some(srdf::parse_srdf(&text).map_err(|e| self.err(&k, format!("{s}: {e}")))?)
                }
            };
            if m.pose.is_some() && srdf.is_none() {
                return Err(self.err(
                    format!("{key}.pose"),
                    "a pose is a <group_state> of the model's SRDF: the model has no \"srdf\"",
                ));
            }
            if let (Some(p), Some(s)) = (&m.pose, &srdf) {
                if s.pose(p).is_none() {
                    let known: Vec<&str> = s.poses.iter().map(|(n, _)| n.as_str()).collect();
                    let near = nearest(p, known.iter().copied())
                        .map(|n| format!("; nearest: \"{n}\""))
                        .unwrap_or_default();
                    return Err(self.err(
                        format!("{key}.pose"),
                        format!(
                            "unknown pose \"{p}\" (not a <group_state> of {}{near})",
                            m.srdf.as_deref().unwrap_or_default()
                        ),
                    ));
                }
            }
            // SRDF pairs and pose joints that name nothing of this URDF: one warning
            let mut disabled = Vec::new();
            if let Some(s) = &srdf {
                let mut unknown: Vec<String> = Vec::new();
                let links: HashSet<&str> = model.frames.iter().map(|f| f.name.as_str()).collect();
                for (a, b) in &s.disabled {
                    let mut ok = true;
                    for l in [a, b] {
                        if !links.contains(l.as_str()) {
                            ok = false;
                            if !unknown.contains(&format!("link \"{l}\"")) {
                                unknown.push(format!("link \"{l}\""));
                            }
                        }
                    }
                    if ok {
                        disabled.push((format!("{}/{a}", m.name), format!("{}/{b}", m.name)));
                    }
                }
                if let Some(p) = m.pose.as_deref().and_then(|p| s.pose(p)) {
                    for (j, _) in p {
                        if !model.body_joint_names.iter().any(|n| n == j)
                            && j != "root_joint"
                            && !unknown.contains(&format!("joint \"{j}\""))
                        {
                            unknown.push(format!("joint \"{j}\""));
                        }
                    }
                }
                if !unknown.is_empty() {
                    let shown: Vec<&str> = unknown.iter().take(6).map(String::as_str).collect();
                    warnings.push(format!(
                        "{}: {key}.srdf: {} names {} {} that {} lacks (ignored): {}{}",
                        self.file,
                        m.srdf.as_deref().unwrap_or_default(),
                        unknown.len(),
                        if unknown.len() == 1 {
                            "element"
                        } else {
                            "elements"
                        },
                        m.urdf,
                        shown.join(", "),
                        if unknown.len() > shown.len() {
                            ", ..."
                        } else {
                            ""
                        }
                    ));
                }
            }
            srdfs.push(srdf);
            models.push(SceneModel {
                name: m.name.clone(),
                urdf,
                floating,
                pose,
                friction: self.friction(&format!("{key}.friction"), m.friction)?,
                self_collision: m.self_collision.unwrap_or(true),
                disabled,
            });
            parts.push(Part {
                name: m.name.clone(),
                model,
                pose,
                friction: models[i].friction,
                self_collision: models[i].self_collision,
            });
        }
        // the forest is named after its file (`lamp_on_table` for lamp_on_table.json)
        let name = Path::new(self.file)
            .file_stem()
            .and_then(|s| s.to_str())
            .filter(|s| !s.is_empty())
            .unwrap_or("scene");
        let mut model = forest(name, parts, Vector3::from(gravity));

        // obstacles: collision geometry on the world body
        let mut obstacles = Vec::new();
        for (i, o) in spec.obstacles.iter().enumerate() {
            let obstacle = self.obstacle(i, o)?;
            model.collisions.push(CollisionGeom {
                link: obstacle.name.clone(),
                body: 0,
                placement: obstacle.placement,
                trimesh: matches!(obstacle.shape, Shape::Mesh { .. }),
                shape: obstacle.shape.clone(),
                friction: obstacle.friction,
                model: OBSTACLE,
            });
            obstacles.push(obstacle);
        }

        // exclude: MODEL/LINK, MODEL or an obstacle on each side
        let mut exclude = Vec::new();
        for (i, pair) in spec.exclude.iter().enumerate() {
            let mut sides = Vec::new();
            for (s, name) in pair.iter().enumerate() {
                sides.push(self.side(&format!("exclude[{i}][{s}]"), name, &model, &spec)?);
            }
            for a in &sides[0] {
                for b in &sides[1] {
                    exclude.push((a.clone(), b.clone()));
                }
            }
        }

        // never in contact: the SRDFs' pairs, then `exclude`
        for sm in &models {
            model
                .collision_filter
                .excluded
                .extend(sm.disabled.iter().cloned());
        }
        model
            .collision_filter
            .excluded
            .extend(exclude.iter().cloned());

        // the starting state
        let mut q0 = model.neutral();
        let mut v0 = DVector::zeros(model.nv);
        let mut tau0 = DVector::zeros(model.nv);
        for (i, m) in spec.models.iter().enumerate() {
            let key = format!("models[{i}]");
            let tree = model.trees[i].clone();
            let pre = tree.prefix();
            let mut position = m.position.unwrap_or([0.0; 3]);
            let mut orientation =
                self.quaternion(&format!("{key}.orientation_xyzw"), m.orientation_xyzw)?;
            if let (Some(p), Some(s)) = (&m.pose, &srdfs[i]) {
                for (j, vals) in s.pose(p).unwrap_or_default() {
                    let full = format!("{pre}{j}");
                    let scalar = model
                        .dofs
                        .iter()
                        .any(|d| d.name == full && d.kind.nv() == 1);
                    if let (Ok(iq), [x], true) = (model.q_index(&full), vals.as_slice(), scalar) {
                        q0[iq] = *x;
                    }
                }
            }
            if let Some(init) = &m.initial {
                let maps = [(&init.q, "q"), (&init.v, "v"), (&init.tau, "tau")];
                for (map, which) in maps {
                    for (joint, &x) in map.iter().flat_map(|m| m.iter()) {
                        let k = format!("{key}.initial.{which}.{joint}");
                        let full = format!("{pre}{joint}");
                        let (Ok(iq), Ok(iv)) = (model.q_index(&full), model.v_index(&full)) else {
                            let own: Vec<&str> = model.dofs[tree.dofs.clone()]
                                .iter()
                                .map(|d| &d.name[pre.len()..])
                                .collect();
                            let near = nearest(joint, own.iter().copied())
                                .map(|n| format!("; nearest: \"{n}\""))
                                .unwrap_or_default();
                            return Err(self.err(
                                k,
                                format!("unknown joint \"{joint}\" (not a movable, non-mimic joint of {}{near})", m.urdf),
                            ));
                        };
                        self.finite(&k, &[x])?;
                        if let Some(d) = model
                            .dofs
                            .iter()
                            .find(|d| d.name == full && d.kind.nv() != 1)
                        {
                            return Err(self.err(
                                k,
                                format!(
                                    "joint \"{joint}\" is {}: a scene's initial state sets 1-DoF joints only",
                                    d.kind.name()
                                ),
                            ));
                        }
                        match which {
                            "q" => q0[iq] = x,
                            "v" => v0[iv] = x,
                            _ => tau0[iv] = x,
                        }
                    }
                }
                if let Some(b) = &init.base {
                    let bk = format!("{key}.initial.base");
                    let Some(f) = tree.free.map(|f| model.free_joints[f].clone()) else {
                        return Err(self.err(
                            bk,
                            format!("model \"{}\" has a fixed base (\"base\": \"floating\" gives it one)", m.name),
                        ));
                    };
                    if let Some(p) = b.position {
                        self.finite(&format!("{bk}.position"), &p)?;
                        position = p;
                    }
                    if let Some(o) = b.orientation_xyzw {
                        orientation =
                            self.quaternion(&format!("{bk}.orientation_xyzw"), Some(o))?;
                    }
                    let vecs = [
                        (&b.linear_velocity, "linear_velocity", 0),
                        (&b.angular_velocity, "angular_velocity", 3),
                    ];
                    for (x, field, at) in vecs {
                        if let Some(x) = x {
                            self.finite(&format!("{bk}.{field}"), x)?;
                            v0.rows_mut(f.iv + at, 3).copy_from_slice(x);
                        }
                    }
                    for (x, field, at) in [(&b.force, "force", 0), (&b.torque, "torque", 3)] {
                        if let Some(x) = x {
                            self.finite(&format!("{bk}.{field}"), x)?;
                            tau0.rows_mut(f.iv + at, 3).copy_from_slice(x);
                        }
                    }
                }
            }
            if let Some(f) = tree.free.map(|f| &model.free_joints[f]) {
                q0.rows_mut(f.iq, 3).copy_from_slice(&position);
                q0.rows_mut(f.iq + 3, 4).copy_from_slice(&orientation);
                let o = orientation;
                models[i].pose = Se3::new(
                    quat_to_matrix(o[0], o[1], o[2], o[3]),
                    Vector3::from(position),
                );
            }
        }
        // loop constraints against the forest (`MODEL/NAME`); held world
        // anchors are placed by the simulation at its start
        let constraints = crate::model::Constraints::from_json(&model, &spec.constraints)
            .map_err(|e| self.err(format!("constraints[{}].{}", e.index, e.key), e.message))?;
        Ok(Scene {
            constraints,
            spec,
            file: self.file.to_string(),
            base_dir: self.base_dir.to_path_buf(),
            model,
            models,
            obstacles,
            ground,
            exclude,
            q0,
            v0,
            tau0,
            warnings,
        })
    }

    fn obstacle(&self, i: usize, o: &ObstacleSpec) -> Result<Obstacle, SceneError> {
        let key = format!("obstacles[{i}]");
        let named = format!("{key} ({})", o.name);
        let keys = o.shape_keys();
        match keys.len() {
            0 => {
                return Err(self.err(
                    named,
                    "no shape key (one of box, sphere, cylinder, capsule, mesh, heightfield)",
                ))
            }
            1 => {}
            _ => return Err(self.err(named, format!("two shape keys {}", keys.join(", ")))),
        }
        if o.scale.is_some() && o.mesh.is_none() {
            return Err(self.err(format!("{key}.scale"), "a scale is for a mesh only"));
        }
        let shape = if let Some(b) = o.box_ {
            self.positive(&format!("{key}.box"), &b, "edge lengths")?;
            Shape::Box { size: b }
        } else if let Some(r) = o.sphere {
            self.positive(&format!("{key}.sphere"), &[r], "the radius")?;
            Shape::Sphere { radius: r }
        } else if let Some(c) = o.cylinder {
            self.positive(&format!("{key}.cylinder.radius"), &[c.radius], "the radius")?;
            self.positive(&format!("{key}.cylinder.length"), &[c.length], "the length")?;
            Shape::Cylinder {
                radius: c.radius,
                length: c.length,
            }
        } else if let Some(c) = o.capsule {
            self.positive(&format!("{key}.capsule.radius"), &[c.radius], "the radius")?;
            self.finite(&format!("{key}.capsule.length"), &[c.length])?;
            if c.length < 0.0 {
                return Err(self.err(
                    format!("{key}.capsule.length"),
                    format!("the length must not be negative (got {})", c.length),
                ));
            }
            Shape::Capsule {
                radius: c.radius,
                length: c.length,
            }
        } else if let Some(m) = &o.mesh {
            let path = self.existing(&format!("{key}.mesh"), m)?;
            let scale = o.scale.unwrap_or([1.0; 3]);
            self.finite(&format!("{key}.scale"), &scale)?;
            if scale.iter().any(|&s| s == 0.0) {
                return Err(self.err(format!("{key}.scale"), "a scale of 0 flattens the mesh"));
            }
            Shape::Mesh {
                filename: path.display().to_string(),
                scale,
            }
        } else if let Some(h) = &o.heightfield {
            self.height_field(&key, h)?
        } else {
            // (the count of shape keys above is exactly one)
            return Err(self.err(
                key.clone(),
                "no shape key (one of box, sphere, cylinder, capsule, mesh, heightfield)",
            ));
        };
        Ok(Obstacle {
            name: o.name.clone(),
            shape,
            placement: self.pose(&key, o.position, o.orientation_xyzw)?,
            friction: self.friction(&format!("{key}.friction"), o.friction)?,
        })
    }

    fn height_field(&self, key: &str, h: &HeightFieldSpec) -> Result<Shape, SceneError> {
        let hk = format!("{key}.heightfield.heights");
        if h.heights.is_empty() || h.heights.iter().all(Vec::is_empty) {
            return Err(self.err(hk, "empty height grid"));
        }
        let cols = h.heights[0].len();
        for (r, row) in h.heights.iter().enumerate() {
            if row.len() != cols {
                return Err(self.err(
                    format!("{hk}[{r}]"),
                    format!(
                        "ragged height grid: row {r} has {} heights, row 0 has {cols}",
                        row.len()
                    ),
                ));
            }
            for (c, x) in row.iter().enumerate() {
                self.finite(&format!("{hk}[{r}][{c}]"), &[*x])?;
            }
        }
        if h.heights.len() < 2 || cols < 2 {
            return Err(self.err(
                hk,
                format!(
                    "a height grid needs at least 2 rows of at least 2 heights (got {} x {cols})",
                    h.heights.len()
                ),
            ));
        }
        self.positive(&format!("{key}.heightfield.size"), &h.size, "the extents")?;
        Ok(height_field_shape(h))
    }

    /// The `MODEL/LINK` or obstacle names one side of an `exclude` pair stands for.
    fn side(
        &self,
        key: &str,
        name: &str,
        model: &Model,
        spec: &SceneSpec,
    ) -> Result<Vec<String>, SceneError> {
        if spec.obstacles.iter().any(|o| o.name == name) {
            return Ok(vec![name.to_string()]);
        }
        if let Some(t) = model.trees.iter().find(|t| t.name == name) {
            return Ok(model.frames[t.frames.clone()]
                .iter()
                .map(|f| f.name.clone())
                .collect());
        }
        if model.frames.iter().any(|f| f.name == name) {
            return Ok(vec![name.to_string()]);
        }
        let known = model
            .frames
            .iter()
            .map(|f| f.name.as_str())
            .chain(model.trees.iter().map(|t| t.name.as_str()))
            .chain(spec.obstacles.iter().map(|o| o.name.as_str()));
        let near = nearest(name, known)
            .map(|n| format!("; nearest: \"{n}\""))
            .unwrap_or_default();
        let what = match name.split_once('/') {
            Some((m, _)) if model.trees.iter().any(|t| t.name == m) => {
                format!("unknown link \"{name}\" (model \"{m}\" has no such link{near})")
            }
            Some((m, _)) => format!("unknown model \"{m}\" in \"{name}\"{near}"),
            None => format!("unknown model or obstacle \"{name}\"{near}"),
        };
        Err(self.err(key, what))
    }
}

/// The height field obstacle's shape.
fn height_field_shape(h: &HeightFieldSpec) -> Shape {
    Shape::HeightField {
        heights: h.heights.clone(),
        size: h.size,
    }
}
