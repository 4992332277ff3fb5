#!/usr/bin/env python3
"""Run the same scenes (scene.md files) in urdyn and in MuJoCo 4.0, in one run: steps/s and penetration.

Usage (benches/scene_compare.sh calls this with /work/venv's or another venv's Python):
    python benches/scene_compare.py --urdyn BIN [--scenes a,b] [--repeats 3] [--duration 3]
        [--dt 0.001] [--md benches/scene_results.md] [--json FILE]

The scenes are benches/scenes/*.json, in scene.md's format; the string "{erd}" in a path
stands for example-robot-data's robots/ folder (found in this Python's site-packages, or
--share). The script writes resolved copies (absolute paths) to a temporary folder and
hands those to both engines.

MuJoCo's scene is built from the same file with mujoco.MjSpec:
- every model: its URDF through MuJoCo's own URDF importer (MjSpec.from_string, the XML
  edited as in benches/sim_compare.py: package:// paths made absolute, <visual> removed,
  discardvisual, balanceinertia, no inertia from geometry), a free joint on the root body
  when "base" is "floating", then attached (spec.attach, prefix "MODEL/") at a frame of the
  world body at the model's position/orientation; fusestatic is off so that a fixed model's
  root stays a body of its own (MuJoCo skips pairs within one weld group and parent-child
  pairs, the same filter as scene.md "Who touches whom" 1-2; with fusestatic on, the root
  would merge into the world body and its first moving links would collide with it);
- obstacles as world geoms (box, sphere, cylinder, capsule; a height field as an mjsHField
  whose elevation is the grid normalised to [0, 1] and scaled to its range, the geom lowered
  to the grid's minimum); the ground a plane; friction: sliding coefficient of each side
  (MuJoCo takes the larger, as scene.md), condim 3;
- exclusions: SRDF <disable_collisions>, the "exclude" list, self_collision false (all
  body pairs of the model), and the self pairs overlapping by more than 1 mm at the start
  (found with mj_forward at the start state, as urdyn drops them, scene.md rule 4);
- start: the SRDF pose, then "initial" (q, base position/orientation/velocities);
- everything else at MuJoCo's defaults (Newton solver, pyramidal cone, solref 0.02 1,
  solimp 0.9 0.95 0.001, margin 0); dt and gravity from the file / --dt.
Euler and implicitfast are both timed (perf_counter around a Python loop of mj_step on a
fresh MjData); the faster is reported.

urdyn: `urdyn simulate --scene FILE --duration T --dt DT --package-path ... --no-sleep --every 1000000000
--out /dev/null` (awake against awake; --every larger than the run: no per-step CSV formatting, as
MuJoCo's timed loop records nothing); steps/s = steps / wall seconds of its stderr summary line (the
stepping loop only). Its metrics (penetration, at rest, contacts) come from one extra untimed run
writing every step (`--out CSV`).

Per repeat: urdyn, then MuJoCo euler, then implicitfast; the table gives medians.
Penetration: deepest over t >= --settle (0.5 s: after landing) and at the end; urdyn: the
CSV's `penetration` column; MuJoCo: max over contacts of -dist (an extra untimed run).
At rest: every velocity coordinate below 0.05 (m/s or rad/s) at the end.
"""
import argparse
import copy
import csv
import datetime
import json
import math
import os
import shlex
import statistics
import subprocess
import sys
import sysconfig
import tempfile
import time
import xml.etree.ElementTree as ET

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
sys.path.insert(0, HERE)
from sim_compare import mujoco_xml, machine, commit  # noqa: E402
from robots_sweep import SUMMARY  # noqa: E402

import numpy as np  # noqa: E402
import mujoco  # noqa: E402

SCENES = ["lamp_on_table", "box_stack", "ball_ramp", "solo12_slope", "solo12_step",
          "ur5_limp", "talos_fall", "two_solo12"]
INTEGRATORS = {"euler": mujoco.mjtIntegrator.mjINT_EULER,
               "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST}
REST = 0.05
G = mujoco.mjtGeom


def find_share(arg):
    cands = [arg] if arg else [os.path.join(sysconfig.get_paths()[k], "cmeel.prefix", "share")
                               for k in ("purelib", "platlib")]
    for c in cands:
        if os.path.isdir(os.path.join(c, "example-robot-data", "robots")):
            return os.path.abspath(c)
    sys.exit("scene_compare: no example-robot-data/robots below %s" % " or ".join(cands))


def resolve_scene(path, robots, out_dir):
    """The scene with absolute paths, written to out_dir; returns (dict, new path)."""
    with open(path) as fh:
        sc = json.load(fh)
    base = os.path.dirname(os.path.abspath(path))

    def fix(p):
        p = p.replace("{erd}", robots)
        return p if os.path.isabs(p) else os.path.normpath(os.path.join(base, p))
    for m in sc["models"]:
        for k in ("urdf", "srdf"):
            if k in m:
                m[k] = fix(m[k])
    for o in sc.get("obstacles", []):
        if "mesh" in o:
            o["mesh"] = fix(o["mesh"])
    new = os.path.join(out_dir, os.path.basename(path))
    with open(new, "w") as fh:
        json.dump(sc, fh, indent=1)
    return sc, new


# ---------------------------------------------------------------------------- MuJoCo

def urdf_bodies(urdf):
    """link -> its MuJoCo body name (fusestatic off: every link is a body of its own)."""
    root = ET.parse(urdf).getroot()
    return {lk.get("name"): lk.get("name") for lk in root.findall("link")}


def srdf_info(path):
    root = ET.parse(path).getroot()
    pairs = [(d.get("link1"), d.get("link2")) for d in root.iter("disable_collisions")]
    poses = {}
    for gs in root.iter("group_state"):
        poses[gs.get("name")] = {j.get("name"): [float(x) for x in j.get("value").split()]
                                 for j in gs.iter("joint")}
    return pairs, poses


def quat_wxyz(xyzw):
    x, y, z, w = xyzw
    return [w, x, y, z]


def build_mujoco(sc, roots, dt, extra_excludes=()):
    spec = mujoco.MjSpec()
    spec.compiler.fusestatic = False
    spec.option.timestep = dt
    spec.option.gravity = sc.get("gravity", [0, 0, -9.81])
    world_geoms = []
    gr = sc.get("ground")
    if gr is not None:
        g = spec.worldbody.add_geom(name="ground", type=G.mjGEOM_PLANE, size=[0, 0, 1],
                                    pos=[0, 0, gr.get("height", 0.0)],
                                    friction=[gr.get("friction", 1.0), 0.005, 0.0001])
    for k, o in enumerate(sc.get("obstacles", [])):
        kw = dict(name=o["name"], pos=o.get("position", [0, 0, 0]),
                  quat=quat_wxyz(o.get("orientation_xyzw", [0, 0, 0, 1])),
                  friction=[o.get("friction", 1.0), 0.005, 0.0001])
        if "box" in o:
            spec.worldbody.add_geom(type=G.mjGEOM_BOX, size=[x / 2 for x in o["box"]], **kw)
        elif "sphere" in o:
            spec.worldbody.add_geom(type=G.mjGEOM_SPHERE, size=[o["sphere"], 0, 0], **kw)
        elif "cylinder" in o or "capsule" in o:
            c = o.get("cylinder") or o.get("capsule")
            t = G.mjGEOM_CYLINDER if "cylinder" in o else G.mjGEOM_CAPSULE
            spec.worldbody.add_geom(type=t, size=[c["radius"], c["length"] / 2, 0], **kw)
        elif "heightfield" in o:
            h = np.array(o["heightfield"]["heights"], dtype=float)
            sx, sy = o["heightfield"]["size"]
            lo, hi = float(h.min()), float(h.max())
            rng = max(hi - lo, 1e-6)
            hf = spec.add_hfield(name=o["name"] + "_hf", nrow=h.shape[0], ncol=h.shape[1],
                                 size=[sx / 2, sy / 2, rng, 0.1],
                                 userdata=((h - lo) / rng).ravel().tolist())
            kw["pos"] = list(np.array(kw["pos"]) + np.array([0, 0, lo]))
            spec.worldbody.add_geom(type=G.mjGEOM_HFIELD, hfieldname=hf.name, **kw)
        else:
            raise ValueError("obstacle %s: shape not handled here" % o["name"])
    starts = []
    excludes = list(extra_excludes)
    for m in sc["models"]:
        name = m["name"]
        child = mujoco.MjSpec.from_string(mujoco_xml(m["urdf"], roots))
        child.compiler.fusestatic = False
        top = list(child.worldbody.bodies)[0]
        floating = m["base"] == "floating"
        if floating:
            top.add_freejoint(name="base")
        for g in child.geoms:
            g.friction = [m.get("friction", 1.0), 0.005, 0.0001]
        frame = spec.worldbody.add_frame(pos=m.get("position", [0, 0, 0]),
                                         quat=quat_wxyz(m.get("orientation_xyzw", [0, 0, 0, 1])))
        spec.attach(child, prefix=name + "/", frame=frame)
        body_of = urdf_bodies(m["urdf"])
        q = {}
        if "srdf" in m:
            pairs, poses = srdf_info(m["srdf"])
            for a, b in pairs:
                if a in body_of and b in body_of and body_of[a] != body_of[b]:
                    excludes.append((name + "/" + body_of[a], name + "/" + body_of[b]))
            if "pose" in m:
                q.update({j: v[0] for j, v in poses[m["pose"]].items() if len(v) == 1})
        if not m.get("self_collision", True):
            bs = sorted(set(body_of.values()))
            excludes += [(name + "/" + a, name + "/" + b) for i, a in enumerate(bs) for b in bs[i + 1:]]
        init = m.get("initial", {})
        q.update(init.get("q", {}))
        starts.append((name, floating, q, init.get("base", {}), m))
    for side in sc.get("exclude", []):
        a, b = side
        if "/" in a and "/" in b:
            excludes.append((a, b))
    seen = set()
    bodies = {b.name for b in spec.bodies}  # a URDF link "world" is MuJoCo's world body
    for a, b in excludes:
        if (a, b) in seen or (b, a) in seen or a not in bodies or b not in bodies:
            continue
        seen.add((a, b))
        spec.add_exclude(bodyname1=a, bodyname2=b)
    model = spec.compile()
    qpos, qvel = model.qpos0.copy(), np.zeros(model.nv)
    for name, floating, q, base, m in starts:
        for j, v in q.items():
            jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name + "/" + j)
            if jid >= 0 and model.jnt_type[jid] in (2, 3):  # slide, hinge
                qpos[model.jnt_qposadr[jid]] = v
        if floating:
            jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name + "/base")
            a, dv = model.jnt_qposadr[jid], model.jnt_dofadr[jid]
            if "position" in base:
                qpos[a:a + 3] = base["position"]
            if "orientation_xyzw" in base:
                qpos[a + 3:a + 7] = quat_wxyz(base["orientation_xyzw"])
            # (these scenes start at rest: only a linear velocity is carried over, as
            # MuJoCo's free joint takes it, in the world frame)
            if "linear_velocity" in base:
                qvel[dv:dv + 3] = base["linear_velocity"]
    return model, qpos, qvel, excludes


def model_of_body(m, b):
    n = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b) or ""
    return n.split("/")[0] if "/" in n else None


def start_overlaps(model, qpos, qvel):
    """Self pairs (same model) overlapping by more than 1 mm at the start."""
    d = mujoco.MjData(model)
    d.qpos[:], d.qvel[:] = qpos, qvel
    mujoco.mj_forward(model, d)
    out = []
    for i in range(d.ncon):
        c = d.contact[i]
        b1, b2 = model.geom_bodyid[c.geom1], model.geom_bodyid[c.geom2]
        m1, m2 = model_of_body(model, b1), model_of_body(model, b2)
        if m1 is not None and m1 == m2 and c.dist < -1e-3:
            out.append((mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b1),
                        mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b2), -float(c.dist)))
    return out


def dedupe(over):
    """{(body, body): deepest} of the start overlaps."""
    out = {}
    for a, b, dd in over:
        out[(a, b)] = max(out.get((a, b), 0.0), dd)
    return out


def fresh(model, qpos, qvel, integ):
    model.opt.integrator = INTEGRATORS[integ]
    d = mujoco.MjData(model)
    d.qpos[:], d.qvel[:] = qpos, qvel
    mujoco.mj_forward(model, d)
    return d


def time_mujoco(model, qpos, qvel, integ, steps):
    d = fresh(model, qpos, qvel, integ)
    step = mujoco.mj_step
    t0 = time.perf_counter()
    for _ in range(steps):
        step(model, d)
    sps = steps / (time.perf_counter() - t0)
    time_mujoco.unstable = int(d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number)
    return sps


def mujoco_metrics(model, qpos, qvel, integ, steps, settle):
    d = fresh(model, qpos, qvel, integ)
    pen, ncon = 0.0, []
    for _ in range(steps):
        mujoco.mj_step(model, d)
        if d.time >= settle - 1e-9 and d.ncon:
            pen = max(pen, max(-float(d.contact[i].dist) for i in range(d.ncon)))
        ncon.append(d.ncon)
    mujoco.mj_forward(model, d)
    end = max((-float(d.contact[i].dist) for i in range(d.ncon)), default=0.0)
    return {"pen_after_landing": max(pen, end), "pen_end": end, "max_v_end": float(np.abs(d.qvel).max()),
            "contacts_mean": float(np.mean(ncon)), "contacts_end": int(d.ncon),
            "finite": bool(np.all(np.isfinite(d.qpos))),
            "warnings": {mujoco.mjtWarning(i).name: int(d.warning[i].number)
                         for i in range(len(d.warning)) if d.warning[i].number}}


# ---------------------------------------------------------------------------- urdyn

def run_urdyn(cmd):
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    lines = [ln.strip() for ln in p.stderr.splitlines() if ln.strip()]
    summ = [ln for ln in lines if SUMMARY.search(ln)]
    out = {"exit": p.returncode, "stderr_other": [ln for ln in lines if ln not in summ]}
    if summ:
        mt = SUMMARY.search(summ[-1])
        out.update(steps=int(mt.group(1)), integrator=mt.group(2), wall=float(mt.group(3)),
                   summary=summ[-1], steps_per_s=int(mt.group(1)) / float(mt.group(3)))
    return out


def urdyn_metrics(path, settle):
    with open(path, newline="") as fh:
        rd = csv.reader(fh)
        head = next(rd)
        ip, ic = head.index("penetration"), head.index("contacts")
        iv = [i for i, h in enumerate(head) if h.startswith("v:")]
        pen, last, ncon = 0.0, None, []
        for row in rd:
            vals = [float(x) for x in row]
            if vals[0] >= settle - 1e-9:
                pen = max(pen, vals[ip])
            ncon.append(vals[ic])
            last = vals
    return {"pen_after_landing": pen, "pen_end": last[ip],
            "max_v_end": max(abs(last[i]) for i in iv), "contacts_mean": float(np.mean(ncon)),
            "contacts_end": int(last[ic]),
            "finite": all(math.isfinite(x) for x in last)}


# ---------------------------------------------------------------------------- one scene

def bench(name, args, tmp):
    sc, path = resolve_scene(os.path.join(HERE, "scenes", name + ".json"), args.robots_dir, tmp)
    steps = int(round(args.duration / args.dt))
    r = {"scene": name, "notes": []}
    model, qpos, qvel, exc = build_mujoco(sc, args.roots, args.dt)
    over = start_overlaps(model, qpos, qvel)
    if over:
        r["notes"].append("MuJoCo: %d self pairs overlapping > 1 mm at the start excluded (%s)" % (
            len(set((a, b) for a, b, _ in over)), ", ".join(
                "%s–%s %.1f mm" % (a, b, 1e3 * dd) for (a, b), dd in sorted(dedupe(over).items()))))
        model, qpos, qvel, exc = build_mujoco(sc, args.roots, args.dt, list(dedupe(over)))
    r["mujoco_model"] = {"nbody": model.nbody, "nv": model.nv, "ngeom": model.ngeom,
                         "nexclude": model.nexclude}
    csvp = os.path.join(tmp, name + ".csv")
    cmd = [args.urdyn, "simulate", "--scene", path, "--duration", repr(args.duration),
           "--dt", repr(args.dt), "--no-sleep"]
    for p in args.roots:
        cmd += ["--package-path", p]
    # timed rounds write the final state only (--every larger than the run), as MuJoCo's
    # timed loop records nothing; the metrics come from one extra untimed run writing
    # every step (as benches/mjcf_compare.py does)
    record = cmd + ["--out", csvp]
    cmd = cmd + ["--every", str(10**9), "--out", os.devnull]
    r["urdyn_command"] = " ".join(shlex.quote(c) for c in cmd)
    r["urdyn_record_command"] = " ".join(shlex.quote(c) for c in record)
    us, ms = [], {k: [] for k in INTEGRATORS}
    for rep in range(args.repeats):
        u = run_urdyn(cmd)
        if u["exit"] != 0 or "steps_per_s" not in u:
            r["urdyn_error"] = (u["stderr_other"] or ["exit %s" % u["exit"]])[-1]
        else:
            us.append(u)
        for k in INTEGRATORS:
            ms[k].append(time_mujoco(model, qpos, qvel, k, steps))
        print("  %s round %d: urdyn %s, MuJoCo %s" % (
            name, rep + 1, "%.0f" % us[-1]["steps_per_s"] if us else "–",
            ", ".join("%s %.0f" % (k, v[-1]) for k, v in ms.items())), file=sys.stderr)
    rec = run_urdyn(record) if us else {}
    if us and rec.get("exit") != 0:
        r["urdyn_error"] = (rec.get("stderr_other") or ["exit %s" % rec.get("exit")])[-1]
        us = []
    if us:
        r["urdyn"] = {"steps_per_s": statistics.median(u["steps_per_s"] for u in us),
                      "runs": [u["steps_per_s"] for u in us], "integrator": us[-1]["integrator"],
                      "summary": us[-1]["summary"],
                      "recording_steps_per_s": rec.get("steps_per_s"),
                      "warnings": sorted(set(w for u in us for w in u["stderr_other"]))}
        r["urdyn"].update(urdyn_metrics(csvp, args.settle))
    r["mujoco"] = {k: {"steps_per_s": statistics.median(v), "runs": v} for k, v in ms.items()}
    best = max(INTEGRATORS, key=lambda k: r["mujoco"][k]["steps_per_s"])
    r["mujoco_best"] = best
    r["mujoco"][best].update(mujoco_metrics(model, qpos, qvel, best, steps, args.settle))
    if "urdyn" in r:
        r["ratio"] = r["urdyn"]["steps_per_s"] / r["mujoco"][best]["steps_per_s"]
    return r


VARIANTS = [
    ("in the air, self-collision off", dict(world=False, self_collision=False)),
    ("in the air, self-collision on", dict(world=False, self_collision=True)),
    ("ground/obstacles, self-collision off", dict(world=True, self_collision=False)),
    ("ground/obstacles, self-collision off, friction 0", dict(world=True, self_collision=False,
                                                              friction=0.0)),
    ("as the scene, every model 2 m higher, 0.5 s (in the air: every pair checked, none touching)",
     "lifted"),
    ("as the scene", None),
]
LIFT, LIFTED_FOR = 2.0, 0.5  # m, s: a free fall of 1.2 m


def variant(sc, opts):
    """The scene without its ground and obstacles (world=False) and/or with every model's
    self_collision set: the time each part of the contact pipeline takes."""
    sc = copy.deepcopy(sc)
    if opts == "lifted":
        for m in sc["models"]:
            m["position"] = list(m.get("position", [0, 0, 0]))
            m["position"][2] += LIFT
            bp = m.get("initial", {}).get("base", {}).get("position")
            if bp:
                bp[2] += LIFT
    if opts is None or opts == "lifted":
        return sc
    if not opts["world"]:
        sc["ground"] = None
        sc["obstacles"] = []
    for m in sc["models"]:
        m["self_collision"] = opts["self_collision"]
    if "friction" in opts:
        for x in sc["models"] + sc.get("obstacles", []) + ([sc["ground"]] if sc.get("ground") else []):
            x["friction"] = opts["friction"]
    return sc


def profile(name, args, tmp):
    """steps/s of each VARIANTS entry in both engines (median of --repeats), with urdyn's
    mean contact count."""
    base, _ = resolve_scene(os.path.join(HERE, "scenes", name + ".json"), args.robots_dir, tmp)
    rows = []
    for label, opts in VARIANTS:
        dur = LIFTED_FOR if opts == "lifted" else args.duration
        steps = int(round(dur / args.dt))
        sc = variant(base, opts)
        path = os.path.join(tmp, "%s_profile.json" % name)
        with open(path, "w") as fh:
            json.dump(sc, fh)
        model, qpos, qvel, _ = build_mujoco(sc, args.roots, args.dt)
        over = start_overlaps(model, qpos, qvel)
        if over:
            model, qpos, qvel, _ = build_mujoco(sc, args.roots, args.dt, list(dedupe(over)))
        csvp = os.path.join(tmp, name + "_profile.csv")
        # --integrator euler: without ground and obstacles urdyn's default would be dop853
        cmd = [args.urdyn, "simulate", "--scene", path, "--duration", repr(dur),
               "--dt", repr(args.dt), "--integrator", "euler", "--no-sleep"]
        for p in args.roots:
            cmd += ["--package-path", p]
        cmd += ["--out", csvp]
        us, ms, unstable = [], [], set()
        for _ in range(args.repeats):
            u = run_urdyn(cmd)
            if "steps_per_s" in u:
                us.append(u["steps_per_s"])
            best = 0.0
            for k in INTEGRATORS:
                best = max(best, time_mujoco(model, qpos, qvel, k, steps))
                if time_mujoco.unstable:
                    unstable.add(k)
            ms.append(best)
        um = urdyn_metrics(csvp, 0.0) if us else {}
        rows.append({"variant": label, "urdyn": statistics.median(us) if us else None,
                     "mujoco": statistics.median(ms), "mujoco_unstable": sorted(unstable),
                     "urdyn_contacts_mean": um.get("contacts_mean")})
        print("  profile %s / %s: urdyn %s, MuJoCo %.0f" % (name, label, rows[-1]["urdyn"], rows[-1]["mujoco"]),
              file=sys.stderr)
    return rows


def uptime():
    try:
        return subprocess.run(["uptime"], stdout=subprocess.PIPE, text=True).stdout.strip()
    except OSError:
        return "?"


def write_md(path, results, meta):
    L = ["# Scenes in urdyn and MuJoCo %s" % meta["mujoco_version"], "",
         "Made by `%s` on %s (%.0f s wall), urdyn commit %s, %s. Load at the start: `%s`; at the end: "
         "`%s`. The script's docstring says how each engine gets the scene." % (
             meta["command"], meta["date"], meta["wall_s"], meta["commit"], meta["machine"],
             meta["load_start"], meta["load_end"]), "",
         "dt = %g s, %g s per run, median of %d rounds (urdyn, then MuJoCo Euler, then implicitfast, "
         "back to back); MuJoCo: the faster integrator, default solver settings; URDF models loaded with "
         "MjSpec.from_string (MuJoCo's URDF importer) and attached. Penetration: deepest from t = %g s "
         "(after landing) to the end. At rest: every velocity coordinate < %g at the end. "
         "Ratio = urdyn / MuJoCo (≥ 1: urdyn as fast or faster)." % (
             meta["dt"], meta["duration"], meta["repeats"], meta["settle"], REST), "",
         "| scene | urdyn steps/s | MuJoCo steps/s (integrator) | ratio | pen. urdyn / MuJoCo (mm) "
         "| at rest urdyn / MuJoCo | mean contacts urdyn / MuJoCo |",
         "|---|---|---|---|---|---|---|"]
    notes = []
    for r in results:
        u = r.get("urdyn") or {}
        best = r["mujoco_best"]
        mj = r["mujoco"][best]
        other = [k for k in INTEGRATORS if k != best][0]
        L.append("| %s | %s | %.0f (%s; %s %.0f) | %s | %s / %.2f | %s / %s | %s / %.1f |" % (
            r["scene"], "%.0f" % u["steps_per_s"] if u else "fails",
            mj["steps_per_s"], best, other, r["mujoco"][other]["steps_per_s"],
            "%.2f" % r["ratio"] if "ratio" in r else "–",
            "%.2f" % (1e3 * u["pen_after_landing"]) if u else "–", 1e3 * mj["pen_after_landing"],
            ("yes" if u["max_v_end"] < REST else "no (%.2g)" % u["max_v_end"]) if u else "–",
            "yes" if mj["max_v_end"] < REST else "no (%.2g)" % mj["max_v_end"],
            "%.1f" % u["contacts_mean"] if u else "–", mj["contacts_mean"]))
        n = list(r["notes"])
        if r.get("urdyn_error"):
            n.append("urdyn fails: " + r["urdyn_error"])
        for w in u.get("warnings", []):
            n.append("urdyn: " + w)
        if mj.get("warnings"):
            n.append("MuJoCo warnings: " + ", ".join("%s ×%d" % kv for kv in mj["warnings"].items()))
        if n:
            notes.append("- %s: %s." % (r["scene"], "; ".join(x.rstrip(".") for x in n)))
    L += ["", "## Notes", ""] + (notes or ["none"])
    prof = [r for r in results if r.get("profile")]
    if prof:
        L += ["", "## Where urdyn's time goes (scenes where it is slower)", "",
              "Each scene rerun (same repeats, median) without its ground and obstacles and/or with "
              "self-collision off for every model, or lifted 2 m for 0.5 s (every pair checked, none "
              "touching), or frictionless (one row per contact point instead of three: the share of the "
              "solve), all with urdyn's euler integrator: steps/s and µs per step (1e6 / steps/s). "
              "The difference between two rows is the cost of the part switched on.", "",
              "| scene | variant | urdyn steps/s (µs/step) | MuJoCo steps/s (µs/step) | urdyn mean contacts |",
              "|---|---|---|---|---|"]
        for r in prof:
            for p in r["profile"]:
                L.append("| %s | %s | %s | %.0f (%.0f)%s | %s |" % (
                    r["scene"], p["variant"],
                    "%.0f (%.0f)" % (p["urdyn"], 1e6 / p["urdyn"]) if p["urdyn"] else "fails",
                    p["mujoco"], 1e6 / p["mujoco"],
                    " unstable with %s (MuJoCo reset the state)" % ", ".join(p["mujoco_unstable"])
                    if p["mujoco_unstable"] else "",
                    "%.1f" % p["urdyn_contacts_mean"] if p["urdyn_contacts_mean"] is not None else "–"))
    # the hand-written "## Findings" section of the previous file is kept
    try:
        with open(path) as fh:
            old = fh.read()
        if "\n## Findings" in old:
            L += ["", "## Findings" + old.split("\n## Findings", 1)[1].rstrip("\n")]
    except OSError:
        pass
    with open(path, "w") as fh:
        fh.write("\n".join(L) + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--urdyn", required=True)
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--share")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--duration", type=float, default=3.0)
    ap.add_argument("--dt", type=float, default=0.001)
    ap.add_argument("--settle", type=float, default=0.5)
    ap.add_argument("--profile", action="store_true",
                    help="for every scene where urdyn is slower, time its variants (VARIANTS)")
    ap.add_argument("--md", default=os.path.join(HERE, "scene_results.md"))
    ap.add_argument("--json", default="", help="also write every number as JSON here")
    args = ap.parse_args()
    share = find_share(args.share)
    args.robots_dir = os.path.join(share, "example-robot-data", "robots")
    args.roots = [share, args.robots_dir]
    args.md, args.urdyn = os.path.abspath(args.md), os.path.abspath(args.urdyn)
    if args.json:
        args.json = os.path.abspath(args.json)
    load_start = uptime()
    started = time.time()
    date = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    results = []
    with tempfile.TemporaryDirectory(prefix="scene_compare_") as tmp:
        os.chdir(tmp)  # MuJoCo's MUJOCO_LOG.TXT lands there
        for name in [s for s in args.scenes.split(",") if s]:
            print(name, file=sys.stderr)
            results.append(bench(name, args, tmp))
            if args.profile and results[-1].get("ratio", 0) < 1:
                results[-1]["profile"] = profile(name, args, tmp)
    os.chdir(REPO)
    meta = {"command": " ".join(["python", "benches/scene_compare.py"] + [shlex.quote(a) for a in sys.argv[1:]]),
            "date": date, "wall_s": time.time() - started, "commit": commit(), "machine": machine(),
            "mujoco_version": mujoco.__version__, "load_start": load_start, "load_end": uptime(),
            "dt": args.dt, "duration": args.duration, "repeats": args.repeats, "settle": args.settle}
    write_md(args.md, results, meta)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"meta": meta, "results": results}, fh, indent=1)
    print("wrote %s" % args.md, file=sys.stderr)


if __name__ == "__main__":
    main()
