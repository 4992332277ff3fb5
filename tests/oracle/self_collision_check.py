#!/usr/bin/env python3
"""How deep does a robot falling limp with self-collision sink into itself in urdyn,
measured by another engine's geometry (coal, through Pinocchio)?

For each scene (one model each, scene.md files):
- runs `urdyn simulate --scene FILE --duration T --out CSV` (urdyn's trajectory);
- builds the same robot in Pinocchio (`buildModelFromUrdf`, a free flyer for a floating
  base) with its collision geometry (`buildGeomFromUrdf(COLLISION)`), every mesh made
  its convex hull (scipy's Qhull, as a coal.Convex: urdyn collides a link mesh as its
  convex hull too), boxes, cylinders and spheres as they are;
- takes every pair of collision objects as scene.md "Who touches whom" does: not two
  objects of one joint's body, not a body and its parent joint's body, not an SRDF
  `<disable_collisions>` pair (`removeCollisionPairs`), not a pair overlapping by more
  than 1 mm at the start (coal's distance at the CSV's first row);
- at every `--every`-th row of the CSV (q by column name, q:MODEL/JOINT, the base as
  q:MODEL/base_x … base_qw), `computeDistances` on all those pairs: the deepest
  penetration (−distance) over the run, with its pair and time.
Writes docs/self_collision_check.md (or --output).

    python tests/oracle/self_collision_check.py --urdyn target/release/urdyn [--duration 3]

The scenes: benches/scenes/ur5_limp.json (ur5 welded 1 m up, falling limp from a folded
pose with its SRDF), tests/oracle/scenes/ur5_fold.json (the same, folded tighter: the
wrist falls onto the upper arm) and examples/scenes/talos_limp.json (talos_reduced falling limp from
half_sitting, self-collision on), paths "{erd}" resolved to example-robot-data's robots/.
"""

import argparse
import csv
import datetime
import json
import os
import subprocess
import sys
import sysconfig
import tempfile
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin
from scipy.spatial import ConvexHull

ROOT = Path(__file__).resolve().parents[2]
SCENES = ["benches/scenes/ur5_limp.json", "tests/oracle/scenes/ur5_fold.json",
          "examples/scenes/talos_limp.json"]
START_OVERLAP = 1e-3


def erd_robots(share):
    if share:
        return Path(share)
    return Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix/share/example-robot-data/robots"


def resolve(scene_path, erd, tmp):
    """The scene with absolute paths ("{erd}" and paths relative to the file)."""
    text = Path(scene_path).read_text().replace("{erd}", str(erd))
    spec = json.loads(text)
    base = Path(scene_path).resolve().parent
    for m in spec["models"]:
        for k in ("urdf", "srdf"):
            if k in m and not os.path.isabs(m[k]):
                m[k] = str((base / m[k]).resolve())
    out = Path(tmp) / Path(scene_path).name
    out.write_text(json.dumps(spec))
    return out, spec


def convex_hull(bvh):
    """A coal mesh's convex hull as a coal.Convex (scipy's Qhull: the pip build of coal
    has no Qhull of its own, and `buildConvexRepresentation` keeps the mesh's own,
    possibly non-convex, triangles, on which GJK's support search is wrong)."""
    pts = np.array([np.array(bvh.vertex(i)) for i in range(bvh.num_vertices)])
    hull = ConvexHull(pts)
    index = {int(k): i for i, k in enumerate(hull.vertices)}
    vs = coal.StdVec_Vec3s()
    for k in hull.vertices:
        vs.append(pts[k])
    ts = coal.StdVec_Triangle()
    for a, b, c in hull.simplices:
        ts.append(coal.Triangle(index[int(a)], index[int(b)], index[int(c)]))
    return coal.Convex(vs, ts)


def pin_robot(m, erd):
    urdf = m["urdf"]
    floating = m.get("base") == "floating"
    model = (pin.buildModelFromUrdf(urdf, pin.JointModelFreeFlyer()) if floating
             else pin.buildModelFromUrdf(urdf))
    dirs = [str(erd.parent.parent), str(erd.parent), str(erd), str(ROOT / "assets/robots/example-robot-data/robots"),
            str(ROOT / "assets/robots"), str(Path(urdf).parent)]
    geom = pin.buildGeomFromUrdf(model, urdf, pin.COLLISION, package_dirs=dirs)
    for g in geom.geometryObjects:
        if type(g.geometry).__name__.startswith("BVH"):
            g.geometry = convex_hull(g.geometry)
    geom.addAllCollisionPairs()
    if "srdf" in m:
        pin.removeCollisionPairs(model, geom, m["srdf"])
    # scene.md: not one body, not a body and its parent body
    keep = []
    for k, cp in enumerate(geom.collisionPairs):
        ja = geom.geometryObjects[cp.first].parentJoint
        jb = geom.geometryObjects[cp.second].parentJoint
        if ja == jb or model.parents[ja] == jb or model.parents[jb] == ja:
            continue
        keep.append((cp.first, cp.second))
    geom.removeAllCollisionPairs()
    for a, b in keep:
        geom.addCollisionPair(pin.CollisionPair(a, b))
    return model, geom, floating


def q_of_row(model, floating, name, header, row):
    col = {h: i for i, h in enumerate(header)}
    q = pin.neutral(model)
    for j in range(1, model.njoints):
        jn = model.names[j]
        iq, nq = model.idx_qs[j], model.nqs[j]
        if floating and j == 1:
            for k, c in enumerate(["base_x", "base_y", "base_z", "base_qx", "base_qy", "base_qz", "base_qw"]):
                q[iq + k] = float(row[col[f"q:{name}/{c}"]])
            continue
        key = f"q:{name}/{jn}"
        if key not in col:
            continue  # a mimic joint (urdyn reduces it) or one urdyn does not move
        x = float(row[col[key]])
        if nq == 2:
            q[iq], q[iq + 1] = np.cos(x), np.sin(x)
        else:
            q[iq] = x
    return q


def check(scene_file, args, erd, tmp):
    path, spec = resolve(ROOT / scene_file, erd, tmp)
    assert len(spec["models"]) == 1, "one model per scene"
    m = spec["models"][0]
    out = Path(tmp) / (path.stem + ".csv")
    cmd = [args.urdyn, "simulate", "--scene", str(path), "--duration", repr(args.duration),
           "--out", str(out), "--package-path", str(erd.parent.parent)]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        return {"scene": scene_file, "error": p.stderr.strip().splitlines()[-1]}
    rows = list(csv.reader(open(out)))
    header, rows = rows[0], rows[1:]
    model, geom, floating = pin_robot(m, erd)
    data, gdata = model.createData(), geom.createData()

    def distances(row):
        q = q_of_row(model, floating, m["name"], header, row)
        pin.updateGeometryPlacements(model, data, geom, gdata, q)
        pin.computeDistances(geom, gdata)
        return np.array([r.min_distance for r in gdata.distanceResults])

    d0 = distances(rows[0])
    start_dropped = [k for k, d in enumerate(d0) if d < -START_OVERLAP]
    active = np.ones(len(d0), bool)
    active[start_dropped] = False
    worst, worst_t, worst_pair = 0.0, None, None
    for row in rows[:: args.every]:
        d = distances(row)
        d = np.where(active, d, np.inf)
        k = int(np.argmin(d))
        if -d[k] > worst:
            worst, worst_t = float(-d[k]), float(row[0])
            cp = geom.collisionPairs[k]
            worst_pair = (geom.geometryObjects[cp.first].name, geom.geometryObjects[cp.second].name)
    col = {h: i for i, h in enumerate(header)}
    urdyn_pen = max(float(r[col["penetration"]]) for r in rows) if "penetration" in col else None
    return {"scene": scene_file, "pairs": int(active.sum()), "start_dropped": len(start_dropped),
            "rows": len(rows[:: args.every]), "deepest": worst, "t": worst_t, "pair": worst_pair,
            "urdyn_penetration": urdyn_pen, "summary": p.stderr.strip().splitlines()[-1]}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--urdyn", default=str(ROOT / "target/release/urdyn"))
    ap.add_argument("--duration", type=float, default=3.0)
    ap.add_argument("--every", type=int, default=5, help="check every N-th CSV row")
    ap.add_argument("--share", help="example-robot-data's robots/ folder")
    ap.add_argument("--output", default=str(ROOT / "docs/self_collision_check.md"))
    args = ap.parse_args()
    erd = erd_robots(args.share)
    with tempfile.TemporaryDirectory() as tmp:
        res = [check(s, args, erd, tmp) for s in SCENES]
    lines = [
        "# Self-collision checked with coal (through Pinocchio)", "",
        f"Generated by `tests/oracle/self_collision_check.py` on "
        f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC (Pinocchio {pin.__version__}): "
        "urdyn's trajectory of each scene, its collision geometry rebuilt in Pinocchio (meshes as "
        "their convex hulls, coal.Convex), every pair scene.md lets touch (not one body, not parent and child, "
        "not an SRDF `<disable_collisions>` pair, not a pair overlapping > 1 mm at the start), "
        f"coal's distance at every {args.every}th step: the deepest penetration over "
        f"{args.duration} s.", "",
        "| scene | pairs checked | dropped at start | steps checked | deepest (mm) | at t (s) | pair | urdyn's own deepest (ground and self, mm) |",
        "|---|---:|---:|---:|---:|---:|---|---:|",
    ]
    for r in res:
        if "error" in r:
            lines.append(f"| {r['scene']} | urdyn failed: {r['error']} | | | | | | |")
            continue
        pair = " – ".join(r["pair"]) if r["pair"] else "none touching"
        t = f"{r['t']:.3f}" if r["t"] is not None else "–"
        up = f"{1e3 * r['urdyn_penetration']:.2f}" if r["urdyn_penetration"] is not None else "–"
        lines.append(f"| {r['scene']} | {r['pairs']} | {r['start_dropped']} | {r['rows']} | "
                     f"{1e3 * r['deepest']:.2f} | {t} | {pair} | {up} |")
    Path(args.output).write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    bad = [r for r in res if "error" in r or r["deepest"] > 2e-3]
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
