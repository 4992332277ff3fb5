//! A scene file's loading (scene.md): every key checked, the URDFs and SRDFs
//! loaded, the models joined into one forest [`Model`]; the obstacles in
//! [`super::obstacles`].

use super::file::{BaseSpec, SceneSpec};
use super::forest::{forest, Part};
use super::{read_text, srdf, Ground, Scene, SceneError, SceneModel};
use crate::model::{nearest, CollisionGeom, Model, Shape, OBSTACLE};
use crate::spatial::{quat_to_matrix, Se3};
use crate::urdf::{load_file, resolve_mesh_path, LoadOptions};
use nalgebra::{DVector, Vector3};
use std::collections::HashSet;
use std::path::{Path, PathBuf};

pub(super) struct Loader<'a> {
    pub(super) file: &'a str,
    pub(super) base_dir: &'a Path,
    pub(super) package_paths: &'a [PathBuf],
}

impl Loader<'_> {
    pub(super) fn err(&self, key: impl Into<String>, message: impl Into<String>) -> SceneError {
        SceneError::new(self.file, key, message)
    }

    pub(super) fn finite(&self, key: &str, xs: &[f64]) -> Result<(), SceneError> {
        match xs.iter().find(|x| !x.is_finite()) {
            Some(x) => Err(self.err(key, format!("non-finite number {x}"))),
            None => Ok(()),
        }
    }

    pub(super) fn positive(&self, key: &str, xs: &[f64], what: &str) -> Result<(), SceneError> {
        self.finite(key, xs)?;
        match xs.iter().find(|&&x| x <= 0.0) {
            Some(x) => Err(self.err(key, format!("{what} must be positive (got {x})"))),
            None => Ok(()),
        }
    }

    pub(super) fn friction(&self, key: &str, mu: Option<f64>) -> Result<f64, SceneError> {
        let mu = mu.unwrap_or(1.0);
        if !(mu.is_finite() && mu >= 0.0) {
            return Err(self.err(
                key,
                format!("friction must be a non-negative number (got {mu})"),
            ));
        }
        Ok(mu)
    }

    pub(super) fn pose(
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
    pub(super) fn quaternion(
        &self,
        key: &str,
        o: Option<[f64; 4]>,
    ) -> Result<[f64; 4], SceneError> {
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
    pub(super) fn existing(&self, key: &str, name: &str) -> Result<PathBuf, SceneError> {
        let p = Path::new(name);
        let path = if p.is_absolute() {
            p.to_path_buf()
        } else {
            self.base_dir.join(p)
        };
        if path.is_dir() {
            return Err(self.err(key, format!("\"{name}\" is a directory, not a file")));
        }
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

    pub(super) fn name(
        &self,
        key: &str,
        name: &str,
        seen: &mut HashSet<String>,
    ) -> Result<(), SceneError> {
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

    pub(super) fn load(&self, spec: SceneSpec) -> Result<Scene, SceneError> {
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
        let mut grounds = super::mjcf::Grounds { planes: Vec::new() };
        // (first collision in the forest, the file's own frictions) of each
        // MJCF model without a "friction": its geoms keep theirs
        let mut own_friction: Vec<(usize, Vec<f64>)> = Vec::new();
        let mut ncollisions = 0usize;
        for (i, m) in spec.models.iter().enumerate() {
            let key = format!("models[{i}]");
            let pose = self.pose(&key, m.position, m.orientation_xyzw)?;
            let (model, urdf, floating) = match (&m.urdf, &m.mjcf) {
                (Some(u), None) => {
                    let urdf = self.existing(&format!("{key}.urdf"), u)?;
                    let floating = m.base == Some(BaseSpec::Floating);
                    let mut model = load_file(
                        &urdf,
                        LoadOptions {
                            floating_base: floating,
                        },
                    )
                    .map_err(|e| self.err(format!("{key}.urdf"), e.to_string()))?;
                    for c in &mut model.collisions {
                        if let Shape::Mesh { filename, .. } = &mut c.shape {
                            if let Some(p) =
                                resolve_mesh_path(filename, Some(&urdf), self.package_paths)
                            {
                                *filename = p.display().to_string();
                            }
                        }
                    }
                    (model, urdf, floating)
                }
                (None, Some(x)) => {
                    let mm = self.mjcf_model(&key, m, x, &pose, &mut warnings)?;
                    if let Some((h, mu)) = mm.ground {
                        grounds.planes.push((i, h, mu));
                    }
                    if m.friction.is_none() {
                        let mus = mm.model.collisions.iter().map(|c| c.friction).collect();
                        own_friction.push((ncollisions, mus));
                    }
                    (mm.model, mm.path, false)
                }
                (u, _) => {
                    return Err(self.err(
                        &key,
                        format!(
                            "a model needs exactly one of \"urdf\" and \"mjcf\" (got {})",
                            if u.is_some() { "both" } else { "neither" }
                        ),
                    ))
                }
            };
            ncollisions += model.collisions.len();
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
                        m.urdf.as_deref().unwrap_or_default(),
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
                mjcf: m.mjcf.is_some(),
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
        for (at, mus) in own_friction {
            for (c, mu) in model.collisions[at..].iter_mut().zip(mus) {
                c.friction = mu;
            }
        }
        let ground = self.merge_grounds(ground, &grounds, &mut warnings)?;

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
            let tree = part_tree(&model, &m.name);
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
                // an MJCF model's free roots are placed by its pose (no
                // "base" beside "mjcf": the pose is final here)
                let o = orientation;
                let pose = Se3::new(
                    quat_to_matrix(o[0], o[1], o[2], o[3]),
                    Vector3::from(position),
                );
                let world_pose = models[i].mjcf.then_some(&pose);
                for (map, which) in maps {
                    for (joint, x) in map.iter().flat_map(|m| m.iter()) {
                        let k = format!("{key}.initial.{which}.{joint}");
                        let full = format!("{pre}{joint}");
                        if model.q_index(&full).is_err() || model.v_index(&full).is_err() {
                            let own: Vec<&str> = model.dofs[tree.dofs.clone()]
                                .iter()
                                .map(|d| &d.name[pre.len()..])
                                .collect();
                            let near = nearest(joint, own.iter().copied())
                                .map(|n| format!("; nearest: \"{n}\""))
                                .unwrap_or_default();
                            return Err(self.err(
                                k,
                                format!("unknown joint \"{joint}\" (not a movable, non-mimic joint of {}{near})", m.urdf.as_deref().or(m.mjcf.as_deref()).unwrap_or_default()),
                            ));
                        };
                        let (at, vals) =
                            self.initial_joint(&k, &model, &full, which, x, world_pose)?;
                        if let Some(f) = tree.free.map(|f| &model.free_joints[f]) {
                            if at == if which == "q" { f.iq } else { f.iv } {
                                return Err(self.err(k, "the floating base: its pose and velocities are \"initial.base\"'s"));
                            }
                        }
                        let dst = match which {
                            "q" => &mut q0,
                            "v" => &mut v0,
                            _ => &mut tau0,
                        };
                        dst.rows_mut(at, vals.len()).copy_from_slice(&vals);
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

    /// The `MODEL/LINK` or obstacle names one side of an `exclude` pair stands for.
    pub(super) fn side(
        &self,
        key: &str,
        name: &str,
        model: &Model,
        spec: &SceneSpec,
    ) -> Result<Vec<String>, SceneError> {
        if spec.obstacles.iter().any(|o| o.name == name) {
            return Ok(vec![name.to_string()]);
        }
        if model.trees.iter().any(|t| t.name == name) {
            let t = part_tree(model, name);
            return Ok(model.frames[t.frames]
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

/// The one tree of the scene model `name`, or the span of its trees (an MJCF
/// world of several, contiguous; `free` the first's).
pub(super) fn part_tree(model: &Model, name: &str) -> crate::model::Tree {
    let mut ts = model.trees.iter().filter(|t| t.name == name);
    let Some(first) = ts.next() else {
        let mut t = crate::model::Tree::whole(1, 0, 0, 0, 0, false);
        t.name = name.to_string();
        return t;
    };
    let mut t = first.clone();
    for u in ts {
        t.bodies.end = u.bodies.end;
        t.frames.end = u.frames.end;
        t.dofs.end = u.dofs.end;
        t.q.end = u.q.end;
        t.v.end = u.v.end;
    }
    t
}
