//! A scene's obstacles (scene.md §"Obstacles"): boxes, spheres, cylinders,
//! capsules, meshes and height fields, checked and made collision geometry on
//! the world.

use super::file::{HeightFieldSpec, ObstacleSpec};
use super::load::Loader;
use super::{Obstacle, SceneError};
use crate::model::Shape;

impl Loader<'_> {
    pub(super) fn obstacle(&self, i: usize, o: &ObstacleSpec) -> Result<Obstacle, SceneError> {
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

    pub(super) fn height_field(&self, key: &str, h: &HeightFieldSpec) -> Result<Shape, SceneError> {
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
}

/// The height field obstacle's shape.
fn height_field_shape(h: &HeightFieldSpec) -> Shape {
    Shape::HeightField {
        heights: h.heights.clone(),
        size: h.size,
    }
}
