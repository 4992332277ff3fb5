//! Reads mesh file paths (one a line) on standard input and prints, for each, one
//! JSON line: `{"file", "urdyn": {"min", "max", "n"} | {"error"}, "mesh_loader": ...}`,
//! the axis-aligned bounding box of the vertices each reader returns (urdyn's
//! `mesh::load_vertices`, mesh-loader's `Loader::load`, every mesh of the
//! scene) and their number.
use serde_json::{json, Value};
use std::io::BufRead;
use std::path::Path;

fn bbox(points: impl Iterator<Item = [f64; 3]>) -> Value {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    let mut n = 0usize;
    for p in points {
        n += 1;
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    if n == 0 {
        return json!({"error": "no vertices"});
    }
    json!({"min": lo, "max": hi, "n": n})
}

fn main() {
    let loader = mesh_loader::Loader::default();
    for line in std::io::stdin().lock().lines() {
        let Ok(file) = line else { break };
        let path = Path::new(file.trim());
        let ours = match urdyn::mesh::load_vertices(path, [1.0; 3]) {
            Ok(v) => bbox(v.iter().map(|p| [p.x, p.y, p.z])),
            Err(e) => json!({"error": e.to_string()}),
        };
        let theirs = match std::panic::catch_unwind(|| loader.load(path)) {
            Ok(Ok(scene)) => bbox(scene.meshes.iter().flat_map(|m| {
                m.vertices
                    .iter()
                    .map(|v| [v[0] as f64, v[1] as f64, v[2] as f64])
            })),
            Ok(Err(e)) => json!({"error": e.to_string()}),
            Err(_) => json!({"error": "panicked"}),
        };
        println!(
            "{}",
            json!({"file": file.trim(), "urdyn": ours, "mesh_loader": theirs})
        );
    }
}
