#!/usr/bin/env python3
"""Writes the mesh files that the URDFs of this folder name, under
`example-robot-data/robots/...` beside them, so that their `package://example-robot-data/...`
paths resolve with no download (src/mesh/paths.rs: the URDF's folder is a package root).

    make_meshes.py SHARE   # SHARE holds example-robot-data/robots/... (cmeel.prefix/share)

Needs numpy and fast-simplification (pip). What is written, per file:
- a file that a `<collision>` names is copied byte for byte (the contact shape is the
  convex hull of its vertices: unchanged), except kinova's (used for benchmarks only,
  never for contact in this repository; its meshes serve visual and collision at once and
  are 6.5 MB), which are simplified as visual ones;
- a file that only `<visual>`s name is simplified (quadric edge collapse, Garland and
  Heckbert, through fast-simplification) so that each robot's visual meshes have at most
  BUDGET triangles together (every file kept whole up to a common limit, larger ones
  reduced to it), and written in the format its name says: binary STL, or a minimal
  COLLADA document in metres with one `<triangles>` per material and the material's
  diffuse colour (the DAE's own colours, which the replay page draws).
Deterministic for the same inputs and package versions.
"""
import os
import shutil
import struct
import sys
import xml.etree.ElementTree as ET

import fast_simplification
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
PREFIX = "package://"
# Triangles of a robot's simplified visual meshes together.
BUDGET = 6000
# No file is reduced below this many triangles.
FLOOR = 150
# Files simplified although a <collision> names them (see the module doc).
SIMPLIFY_COLLISION = ("kinova_description",)


def urdf_meshes(path):
    """{filename: set of "visual"/"collision"} of a URDF's mesh elements."""
    use = {}
    for link in ET.parse(path).getroot().iter("link"):
        for kind in ("visual", "collision"):
            for el in link.iter(kind):
                for m in el.iter("mesh"):
                    use.setdefault(m.get("filename"), set()).add(kind)
    return use


def read_stl(path):
    """[(positions (n, 3), triangles (m, 3), None)] of a binary or ASCII STL."""
    data = open(path, "rb").read()
    tri = None
    if len(data) >= 84:
        n = struct.unpack_from("<I", data, 80)[0]
        if 84 + 50 * n == len(data):
            rec = np.frombuffer(data, dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")]),
                                count=n, offset=84)
            tri = rec["v"].astype(np.float64)
    if tri is None:
        pts = [list(map(float, line.split()[1:4])) for line in data.decode("latin-1").splitlines()
               if line.strip().startswith("vertex")]
        tri = np.array(pts, dtype=np.float64).reshape(-1, 3, 3)
    flat = tri.reshape(-1, 3)
    verts, inv = np.unique(flat, axis=0, return_inverse=True)
    return [(verts, inv.reshape(-1, 3).astype(np.int64), None)]


def _local(tag):
    return tag.rsplit("}", 1)[-1]


def _floats(text):
    return np.array((text or "").split(), dtype=np.float64)


def _transform(node):
    """The product of a <node>'s transform elements, in document order."""
    m = np.eye(4)
    for el in node:
        tag, v = _local(el.tag), _floats(el.text)
        if tag == "matrix":
            t = v.reshape(4, 4)
        elif tag == "translate":
            t = np.eye(4)
            t[:3, 3] = v
        elif tag == "scale":
            t = np.diag([v[0], v[1], v[2], 1.0])
        elif tag == "rotate":
            axis, a = v[:3] / np.linalg.norm(v[:3]), np.radians(v[3])
            k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
            t = np.eye(4)
            t[:3, :3] = np.eye(3) + np.sin(a) * k + (1 - np.cos(a)) * k @ k
        else:
            continue
        m = m @ t
    return m


def read_dae(path):
    """[(positions, triangles, rgba or None)] of a COLLADA file as urdyn reads it
    (src/mesh/): the visual scene walked, node transforms multiplied in
    document order, <unit meter> applied, <triangles>/<polylist>/<polygons> fanned, each
    primitive's colour the diffuse <color> of the material its symbol is bound to."""
    root = ET.parse(path).getroot()
    by_id = {el.get("id"): el for el in root.iter() if el.get("id")}
    unit = 1.0
    for asset in root:
        if _local(asset.tag) == "asset":
            for u in asset:
                if _local(u.tag) == "unit" and u.get("meter"):
                    unit = float(u.get("meter"))

    def colour(material_id):
        mat = by_id.get(material_id)
        if mat is None:
            return None
        for ie in mat.iter():
            if _local(ie.tag) == "instance_effect":
                eff = by_id.get(ie.get("url", "").lstrip("#"))
                for d in (eff.iter() if eff is not None else []):
                    if _local(d.tag) == "diffuse":
                        for c in d:
                            if _local(c.tag) == "color":
                                v = _floats(c.text)
                                return tuple(np.clip(np.r_[v[:3], v[3:4] if len(v) > 3 else [1.0]], 0, 1))
        return None

    def geometry_parts(geom, world, bind):
        mesh = next((m for m in geom if _local(m.tag) == "mesh"), None)
        if mesh is None:
            return []
        verts_src = {}
        for v in mesh:
            if _local(v.tag) == "vertices":
                for i in v:
                    if _local(i.tag) == "input" and i.get("semantic") == "POSITION":
                        verts_src[v.get("id")] = i.get("source").lstrip("#")
        parts = []
        for prim in mesh:
            kind = _local(prim.tag)
            if kind not in ("triangles", "polylist", "polygons"):
                continue
            stride, voff, vsrc = 1, None, None
            for i in prim:
                if _local(i.tag) == "input":
                    off = int(i.get("offset", 0))
                    stride = max(stride, off + 1)
                    if i.get("semantic") == "VERTEX":
                        voff, vsrc = off, i.get("source").lstrip("#")
            if voff is None:
                continue
            src = by_id[verts_src.get(vsrc, vsrc)]
            arr = next(a for a in src.iter() if _local(a.tag) == "float_array")
            pos = _floats(arr.text).reshape(-1, 3)
            ps = [np.array((p.text or "").split(), dtype=np.int64) for p in prim if _local(p.tag) == "p"]
            tris = []
            if kind == "triangles":
                idx = np.concatenate(ps) if ps else np.zeros(0, np.int64)
                tris = idx.reshape(-1, stride)[:, voff].reshape(-1, 3).tolist()
            else:
                if kind == "polylist":
                    vc = next((_floats(c.text).astype(int) for c in prim if _local(c.tag) == "vcount"), [])
                    idx = np.concatenate(ps).reshape(-1, stride)[:, voff]
                    polys, at = [], 0
                    for n in vc:
                        polys.append(idx[at:at + n])
                        at += n
                else:
                    polys = [p.reshape(-1, stride)[:, voff] for p in ps]
                for poly in polys:
                    for k in range(1, len(poly) - 1):
                        tris.append([poly[0], poly[k], poly[k + 1]])
            if not tris:
                continue
            t = np.array(tris, dtype=np.int64)
            used = np.unique(t)
            remap = np.full(len(pos), -1, dtype=np.int64)
            remap[used] = np.arange(len(used))
            p4 = np.c_[pos[used], np.ones(len(used))] @ world.T
            sym = prim.get("material")
            parts.append((p4[:, :3] * unit, remap[t], colour(bind.get(sym, sym)) if sym else None))
        return parts

    scene = None
    for s in root.iter():
        if _local(s.tag) == "instance_visual_scene":
            scene = by_id.get(s.get("url", "").lstrip("#"))
    if scene is None:
        scene = next((s for s in root.iter() if _local(s.tag) == "visual_scene"), None)
    parts = []

    def walk(node, parent):
        world = parent @ _transform(node)
        for el in node:
            tag = _local(el.tag)
            if tag == "instance_geometry":
                bind = {im.get("symbol"): im.get("target", "").lstrip("#")
                        for im in el.iter() if _local(im.tag) == "instance_material"}
                parts.extend(geometry_parts(by_id[el.get("url").lstrip("#")], world, bind))
        for el in node:
            if _local(el.tag) == "node":
                walk(el, world)
        for el in node:
            if _local(el.tag) == "instance_node":
                walk(by_id[el.get("url").lstrip("#")], world)

    for n in (scene if scene is not None else []):
        if _local(n.tag) == "node":
            walk(n, np.eye(4))
    if not parts:
        raise SystemExit(f"{path}: no placed geometry (not handled by this script)")
    return parts


def triangle_limit(counts, total):
    """The largest L with sum(min(n, L)) <= total (water filling)."""
    counts = sorted(counts)
    if sum(counts) <= total:
        return max(counts, default=0)
    left = total
    for k, n in enumerate(counts):
        rest = len(counts) - k
        if n * rest > left:
            return max(left // rest, FLOOR)
        left -= n
    return max(counts)


def weld(v, t):
    """The mesh with coincident vertices (to 1e-6 m) merged, so that edges are shared."""
    key = np.round(v / 1e-6).astype(np.int64)
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    t = inv.reshape(-1)[t]
    keep = (t[:, 0] != t[:, 1]) & (t[:, 1] != t[:, 2]) & (t[:, 0] != t[:, 2])
    return v[first], t[keep]


def cluster(v, t, want):
    """Vertex clustering on ever coarser grids until at most `want` triangles remain
    (each cell's vertices merged into their mean; collapsed and repeated triangles
    dropped), as the replay page simplifies (src/cli/view/mod.rs)."""
    lo, size = v.min(axis=0), np.ptp(v, axis=0).max()
    cells = np.sqrt(want) * 1.5
    while True:
        key = np.floor((v - lo) / (size / cells)).astype(np.int64)
        _, inv = np.unique(key, axis=0, return_inverse=True)
        inv = inv.reshape(-1)
        n = inv.max() + 1
        mean = np.zeros((n, 3))
        np.add.at(mean, inv, v)
        mean /= np.bincount(inv, minlength=n)[:, None]
        t2 = inv[t]
        keep = (t2[:, 0] != t2[:, 1]) & (t2[:, 1] != t2[:, 2]) & (t2[:, 0] != t2[:, 2])
        t2 = t2[keep]
        _, first = np.unique(np.sort(t2, axis=1), axis=0, return_index=True)
        t2 = t2[np.sort(first)]
        if len(t2) <= want or cells < 2:
            used = np.unique(t2)
            remap = np.full(n, -1, dtype=np.int64)
            remap[used] = np.arange(len(used))
            return mean[used], remap[t2]
        cells *= 0.85


def simplify(parts, limit):
    """The parts with at most `limit` triangles together (each reduced alike)."""
    total = sum(len(t) for _, t, _ in parts)
    if total <= limit:
        return parts
    out = []
    for v, t, c in parts:
        v, t = weld(v, t)
        want = max(4, int(round(len(t) * limit / total)))
        if len(t) > want:
            v2, t2 = fast_simplification.simplify(v.astype(np.float32), t.astype(np.int32),
                                                  target_reduction=1.0 - want / len(t))
            v, t = np.asarray(v2, dtype=np.float64), np.asarray(t2, dtype=np.int64)
        # where edge collapse stops early (edges it may not collapse), vertex clustering
        if len(t) > 1.3 * want:
            v, t = cluster(v, t, want)
        if len(t):
            out.append((v, t, c))
    return out


def write_stl(path, parts):
    tris = np.concatenate([v[t] for v, t, _ in parts]).astype(np.float32)
    normals = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    n = np.linalg.norm(normals, axis=1, keepdims=True)
    normals = np.where(n > 0, normals / np.where(n > 0, n, 1), 0).astype(np.float32)
    rec = np.zeros(len(tris), dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")]))
    rec["n"], rec["v"] = normals, tris
    with open(path, "wb") as f:
        f.write(b"urdyn: simplified from example-robot-data".ljust(80, b" "))
        f.write(struct.pack("<I", len(tris)))
        f.write(rec.tobytes())


def fmt(xs):
    return " ".join("%.6g" % x for x in xs)


def write_dae(path, parts):
    effects, materials, prims, binds = [], [], [], []
    colours = []
    for _, _, c in parts:
        if c is not None and c not in colours:
            colours.append(c)
    for k, c in enumerate(colours):
        effects.append(f'<effect id="e{k}"><profile_COMMON><technique sid="common"><lambert>'
                       f'<diffuse><color>{fmt(c)}</color></diffuse></lambert></technique>'
                       f'</profile_COMMON></effect>')
        materials.append(f'<material id="m{k}"><instance_effect url="#e{k}"/></material>')
        binds.append(f'<instance_material symbol="m{k}" target="#m{k}"/>')
    verts = np.concatenate([v for v, _, _ in parts])
    base = np.cumsum([0] + [len(v) for v, _, _ in parts])
    for (v, t, c), b in zip(parts, base):
        mat = f' material="m{colours.index(c)}"' if c is not None else ""
        prims.append(f'<triangles{mat} count="{len(t)}"><input semantic="VERTEX" source="#v" offset="0"/>'
                     f'<p>{" ".join(map(str, (t + b).ravel().tolist()))}</p></triangles>')
    bind = (f'<bind_material><technique_common>{"".join(binds)}</technique_common></bind_material>'
            if binds else "")
    text = f'''<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
<asset><contributor><comments>urdyn: simplified from example-robot-data</comments></contributor><unit meter="1"/><up_axis>Z_UP</up_axis></asset>
<library_effects>{"".join(effects)}</library_effects>
<library_materials>{"".join(materials)}</library_materials>
<library_geometries><geometry id="g"><mesh>
<source id="p"><float_array id="pa" count="{verts.size}">{fmt(verts.ravel())}</float_array>
<technique_common><accessor source="#pa" count="{len(verts)}" stride="3"><param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/></accessor></technique_common></source>
<vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
{"".join(prims)}
</mesh></geometry></library_geometries>
<library_visual_scenes><visual_scene id="s"><node id="n"><instance_geometry url="#g">{bind}</instance_geometry></node></visual_scene></library_visual_scenes>
<scene><instance_visual_scene url="#s"/></scene>
</COLLADA>
'''
    with open(path, "w") as f:
        f.write(text)


def main():
    share = sys.argv[1]
    for urdf in sorted(f for f in os.listdir(HERE) if f.endswith(".urdf")):
        use = urdf_meshes(os.path.join(HERE, urdf))
        simplified = {}
        for fn, kinds in sorted(use.items()):
            rel = fn[len(PREFIX):]
            src, dst = os.path.join(share, rel), os.path.join(HERE, rel)
            os.makedirs(os.path.dirname(dst), exist_ok=True)
            if "collision" in kinds and not any(s in rel for s in SIMPLIFY_COLLISION):
                shutil.copyfile(src, dst)
                continue
            ext = os.path.splitext(rel)[1].lower()
            simplified[rel] = (src, dst, ext, read_stl(src) if ext == ".stl" else read_dae(src))
        counts = [sum(len(t) for _, t, _ in p) for *_, p in simplified.values()]
        limit = triangle_limit(counts, BUDGET)
        before = after = 0
        for rel, (src, dst, ext, parts) in sorted(simplified.items()):
            small = simplify(parts, limit)
            before += sum(len(t) for _, t, _ in parts)
            after += sum(len(t) for _, t, _ in small)
            (write_stl if ext == ".stl" else write_dae)(dst, small)
        print(f"{urdf}: {len(use)} files, {len(simplified)} simplified ({before} -> {after} triangles)")


if __name__ == "__main__":
    main()
