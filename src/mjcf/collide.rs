//! Who touches whom in an MJCF world, as MuJoCo decides it (mjcf.md §"What
//! the file becomes"): a geom pair touches when either's `contype` ANDs the
//! other's `conaffinity`, the two bodies are not welded together, neither is
//! the other's (weld) parent unless that parent is the world, and no
//! `<contact><exclude>` names the pair. urdyn's pair filter works per pair of
//! links (here: MJCF bodies), so a body pair none of whose geom pairs may touch
//! becomes an excluded link pair; a body pair where some geom pairs touch and
//! others not keeps all (a report line says so). The world's upward-facing
//! `plane` is the ground; other planes are reported as not modelled.

use super::compile::{MjGeom, MjGeomType, World};

/// The ground an MJCF world's planes give: height and the plane's sliding
/// friction, plus report lines.
#[derive(Clone, Debug, PartialEq)]
pub struct Ground {
    /// z of the plane (m).
    pub height: f64,
    /// The plane's sliding friction (a pair takes the larger side, as MuJoCo).
    pub friction: f64,
    /// The plane's `contype` and `conaffinity`.
    pub bits: (i64, i64),
}

fn bits_touch(a: &MjGeom, b: &MjGeom) -> bool {
    (a.contype & b.conaffinity) != 0 || (b.contype & a.conaffinity) != 0
}

/// The world's ground from its planes (the highest upward-facing plane welded
/// to the world), with a report line per plane that is not it.
pub fn ground(world: &World) -> (Option<Ground>, Vec<String>) {
    let mut warnings = Vec::new();
    let mut best: Option<Ground> = None;
    if world.contact_disabled {
        return (None, warnings);
    }
    for g in world.geoms.iter().filter(|g| g.kind == MjGeomType::Plane) {
        if g.contype == 0 && g.conaffinity == 0 {
            continue;
        }
        let (p, q) = world_pose(world, g);
        let n = q * nalgebra::Vector3::z();
        let welded = chain(world, g.body).all(|b| world.bodies[b].joints.is_empty());
        if !welded || n.z < 1.0 - 1e-9 {
            warnings.push(format!(
                "geom \"{}\": a plane that {} is not modelled (only an upward-facing plane welded to the world: the ground)",
                g.name,
                if welded { "does not face up" } else { "moves" }
            ));
            continue;
        }
        if let Some(b) = &best {
            warnings.push(format!(
                "geom \"{}\": a second ground plane; the higher one is the ground",
                g.name
            ));
            if b.height >= p.z {
                continue;
            }
        }
        best = Some(Ground {
            height: p.z,
            friction: g.friction[0],
            bits: (g.contype, g.conaffinity),
        });
    }
    (best, warnings)
}

/// The MJCF bodies from `b` up to (not including) the world.
fn chain(world: &World, mut b: usize) -> impl Iterator<Item = usize> + '_ {
    std::iter::from_fn(move || {
        if b == 0 {
            return None;
        }
        let out = b;
        b = world.bodies[b].parent;
        Some(out)
    })
}

/// A geom's pose in the world at the bodies' defined poses.
fn world_pose(
    world: &World,
    g: &MjGeom,
) -> (nalgebra::Vector3<f64>, nalgebra::UnitQuaternion<f64>) {
    let (mut p, mut q) = (g.pos, g.quat);
    for b in chain(world, g.body) {
        let body = &world.bodies[b];
        p = body.pos + body.quat * p;
        q = body.quat * q;
    }
    (p, q)
}

/// The MJCF body pairs (by name) that never touch, and report lines. `weld[b]`
/// is the urdyn body MJCF body `b` moves with (0: welded to the world),
/// `colliding[k]` whether geom `k` became a collision shape.
pub(super) fn excluded_pairs(
    world: &World,
    weld: &[usize],
    colliding: &[bool],
    ground: Option<&Ground>,
) -> (Vec<(String, String)>, Vec<String>) {
    let nb = world.bodies.len();
    // MuJoCo's weld parent: the weld body of the parent of the topmost body of a weld
    let mut weld_parent = vec![0usize; nb];
    for b in 1..nb {
        let p = world.bodies[b].parent;
        if weld[b] != weld[p] {
            weld_parent[b] = weld[p];
        } else {
            weld_parent[b] = weld_parent[p];
        }
    }
    let mut geoms_of: Vec<Vec<&MjGeom>> = vec![Vec::new(); nb];
    for (k, g) in world.geoms.iter().enumerate() {
        if colliding[k] {
            geoms_of[g.body].push(g);
        }
    }
    let bodies: Vec<usize> = (0..nb).filter(|&b| !geoms_of[b].is_empty()).collect();
    let mut out = Vec::new();
    let mut mixed = 0usize;
    for (i, &a) in bodies.iter().enumerate() {
        for &b in &bodies[i + 1..] {
            let (wa, wb) = (weld[a], weld[b]);
            if wa == wb {
                continue; // urdyn's own rule: one body
            }
            let parent_child = wa != 0 && wb != 0 && (wa == weld_parent[b] || wb == weld_parent[a]);
            let listed = world
                .excludes
                .iter()
                .any(|&(x, y)| (x == a && y == b) || (x == b && y == a));
            let pairs = geoms_of[a]
                .iter()
                .flat_map(|ga| geoms_of[b].iter().map(move |gb| bits_touch(ga, gb)));
            let (mut any, mut all) = (false, true);
            for t in pairs {
                any |= t;
                all &= t;
            }
            if parent_child || listed || !any {
                out.push((world.bodies[a].name.clone(), world.bodies[b].name.clone()));
            } else if !all {
                mixed += 1;
            }
        }
    }
    let mut warnings = Vec::new();
    if mixed > 0 {
        warnings.push(format!(
            "{mixed} body pair(s) where contype/conaffinity let some geom pairs touch and not others: all of their geoms touch"
        ));
    }
    if let Some(gr) = ground {
        let plane = MjGeom {
            contype: gr.bits.0,
            conaffinity: gr.bits.1,
            ..world.geoms[0].clone()
        };
        let off = world
            .geoms
            .iter()
            .enumerate()
            .filter(|(k, g)| colliding[*k] && weld[g.body] != 0 && !bits_touch(g, &plane))
            .count();
        if off > 0 {
            warnings.push(format!(
                "{off} moving geom(s) whose contype/conaffinity exclude the ground plane: they touch the ground all the same"
            ));
        }
    }
    (out, warnings)
}
