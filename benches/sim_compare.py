#!/usr/bin/env python3
"""Drop the same robots in urdyn and in MuJoCo, in one run, and compare speed and contact.

Usage (benches/sim_compare.sh makes the venv and calls this):
    python benches/sim_compare.py [--robots solo12,go2,...] [--share DIR] [--urdyn BIN]
        [--repeats 3] [--duration 3] [--dt 0.001] [--above-ground 0.3]
        [--integrators euler,implicitfast] [--md benches/sim_results.md]
        [--json benches/sim_results.json] [--png benches/sim_results.png]

--robots takes names of the built-in list (ROBOTS below) or URDF paths below
example-robot-data's robots/ folder (name = file stem), comma separated or repeated.
--share is the folder holding example-robot-data/ (default: <site-packages>/cmeel.prefix/share
of this Python, as installed by `pip install example-robot-data`).

The scene, identical in both simulators
---------------------------------------
Floating base (identity orientation, x = y = 0); every joint at 0, except a revolute or
prismatic joint whose limits exclude 0, which starts mid-range (benches/robots_sweep.py's
start_pose; mimic joints are not degrees of freedom); the base lifted so that the lowest
point of the collision geometry is --above-ground (0.3 m) above the ground plane z = 0;
dt = 1 ms; 3 s; gravity (0, 0, -9.81); friction 1; self-collision off (only robot-ground
pairs); no actuators, no control: the robot falls, lands and collapses passively.

urdyn: `urdyn simulate URDF --floating-base --above-ground H --duration T --dt DT
--package-path SHARE --package-path SHARE/example-robot-data/robots [--initial START.json]
--out CSV` with its default integrator (self-collision does not exist in urdyn, friction
1 and gravity are its defaults). steps/s = steps / wall seconds of the summary line urdyn
prints on stderr (the stepping loop only: no URDF parsing, no process start). The CSV
(every step) gives the metrics below.

MuJoCo: the URDF through MuJoCo's own URDF importer (mujoco.MjSpec.from_string), after
these edits of the XML: `package://` and relative mesh paths rewritten to absolute files,
<visual> elements removed (what compiler discardvisual does, and it keeps MuJoCo from
opening visual meshes it cannot read, such as DAE), and a <mujoco><compiler
strippath="false" discardvisual="true" fusestatic="true" balanceinertia="true"
inertiafromgeom="false"/></mujoco> element (absolute mesh paths kept; links welded by
fixed joints fused into their parent body, as urdyn merges them; inertias that violate
the triangle inequality made admissible instead of refused; no inertia invented from
geometry for links without <inertial>). Then, on the spec: a free joint on the root body,
a plane geom in the world body, contype=1 conaffinity=0 on every robot geom and
contype=0 conaffinity=1 on the floor (only robot-floor pairs can collide), sliding
friction 1 on all geoms (condim 3: torsional and rolling friction unused), an equality
constraint per <mimic> on a revolute or prismatic joint (MuJoCo's URDF importer ignores
<mimic>), timestep, gravity; everything else at MuJoCo's defaults (Newton solver,
pyramidal cone, soft contacts solref 0.02 1, solimp 0.9 0.95 0.001, margin 0). A link
inertia MuJoCo refuses as not positive definite is replaced by its diagonal, with a note
in the table (anymal's `hatch`); a robot MuJoCo still refuses gets a row with the error.
The start: qpos as above, the base lifted so that the lowest vertex of the collision
meshes (or the lowest point of a box, sphere, cylinder or capsule) is H above the floor.
Each listed integrator is timed (perf_counter around a Python loop of mj_step calls, in
this process, on a fresh MjData); the faster one is reported, the other one is in the
JSON.

Timing: each robot in --repeats rounds (default 3); a round runs urdyn, then MuJoCo with
each integrator, back to back; the table gives the median over rounds of steps/s. The
ratio is urdyn/MuJoCo of those medians (>1: urdyn faster).

Metrics, from urdyn's CSV and from an extra, untimed MuJoCo run that records every step:
- first contact: time of the first state with a contact (urdyn: first row with
  contacts > 0; MuJoCo: d.time - dt of the first step whose collision pass, run on the
  state at the start of the step, found a contact); a free fall from H gives sqrt(2H/g);
- rest: the first time after which the base's linear speed (urdyn: |v:base_v*|; MuJoCo:
  |qvel[0:3]|, both the speed of the root link's origin) stays below 0.05 m/s to the end;
  "never" when the last state is not at rest;
- rest penetration: at the end (urdyn: last row's `penetration`; MuJoCo: max over contacts
  of -dist after mj_forward on the final state);
- contacts at rest: urdyn's `contacts` column, MuJoCo's d.ncon, at the end (the two count
  differently: MuJoCo makes up to 4 points per box against a plane and more per mesh, urdyn
  keeps at most 9 points per shape, within a 5 mm margin);
- max penetration over the run, MuJoCo warnings (d.warning), urdyn's stderr warnings.
"""
import argparse
import csv
import datetime
import json
import math
import os
import platform
import re
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
from robots_sweep import SUMMARY, start_pose  # noqa: E402

import numpy as np  # noqa: E402
import mujoco  # noqa: E402

ROBOTS = {
    "solo12": "solo_description/robots/solo12.urdf",
    "talos_reduced": "talos_data/robots/talos_reduced.urdf",
    "g1": "g1_description/urdf/g1_29dof_rev_1_0.urdf",
    "go2": "go2_description/urdf/go2.urdf",
    "a1": "a1_description/urdf/a1.urdf",
    "anymal": "anymal_c_simple_description/urdf/anymal.urdf",
    # beyond the four: every other legged robot and humanoid of
    # example-robot-data that MuJoCo's URDF importer compiles
    "solo8": "solo_description/robots/solo.urdf",
    "bolt": "bolt_description/robots/bolt.urdf",
    "laikago": "laikago_description/urdf/laikago.urdf",
    "quadruped": "quadruped_description/urdf/quadruped.urdf",
    "b1": "b1_description/urdf/b1.urdf",
    "go1": "go1_description/urdf/go1.urdf",
    "anymal_b": "anymal_b_simple_description/robots/anymal.urdf",
    "g1_hands": "g1_description/urdf/g1_29dof_with_hand_rev_1_0.urdf",
}
REST_SPEED = 0.05  # m/s
G = 9.81
MJ_INTEGRATORS = {"euler": mujoco.mjtIntegrator.mjINT_EULER,
                  "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
                  "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT,
                  "rk4": mujoco.mjtIntegrator.mjINT_RK4}
TRACE_EVERY = 10  # ms: base height samples kept for the plot and the JSON


def find_share(arg):
    if arg:
        cands = [arg]
    else:
        cands = [os.path.join(sysconfig.get_paths()[k], "cmeel.prefix", "share")
                 for k in ("purelib", "platlib")]
    for c in cands:
        c = os.path.abspath(c)
        if os.path.isdir(os.path.join(c, "example-robot-data", "robots")):
            return c
        if os.path.basename(c) == "example-robot-data" and os.path.isdir(os.path.join(c, "robots")):
            return os.path.dirname(c)
    sys.exit("sim_compare: no example-robot-data/robots below %s (pip install example-robot-data, "
             "or --share DIR)" % " or ".join(cands))


# ---------------------------------------------------------------------------- MuJoCo

def resolve_mesh(fn, urdf_dir, roots):
    if fn.startswith("package://"):
        rest = fn[len("package://"):]
        for r in roots:
            p = os.path.join(r, rest)
            if os.path.exists(p):
                return p
        raise FileNotFoundError("mesh %s not found below %s" % (fn, ", ".join(roots)))
    if fn.startswith("file://"):
        fn = fn[len("file://"):]
    return fn if os.path.isabs(fn) else os.path.normpath(os.path.join(urdf_dir, fn))


def mujoco_xml(urdf, roots, diag_links=()):
    """The URDF text MuJoCo's importer gets (see the docstring)."""
    root = ET.parse(urdf).getroot()
    for link in root.iter("link"):
        for v in link.findall("visual"):
            link.remove(v)
        if link.get("name") in diag_links:
            inertia = link.find("inertial/inertia")
            for k in ("ixy", "ixz", "iyz"):
                inertia.set(k, "0")
    for m in root.iter("mesh"):
        m.set("filename", resolve_mesh(m.get("filename"), os.path.dirname(urdf), roots))
    for old in root.findall("mujoco"):
        root.remove(old)
    mj = ET.SubElement(root, "mujoco")
    ET.SubElement(mj, "compiler", strippath="false", discardvisual="true", fusestatic="true",
                  balanceinertia="true", inertiafromgeom="false")
    return ET.tostring(root, encoding="unicode")


def mimics(urdf):
    """(joint, leader, multiplier, offset) for every revolute/prismatic joint with <mimic>."""
    out = []
    for j in ET.parse(urdf).getroot().iter("joint"):
        mm = j.find("mimic")
        if mm is not None and j.get("type") in ("revolute", "prismatic", "continuous"):
            out.append((j.get("name"), mm.get("joint"), float(mm.get("multiplier", 1.0)),
                        float(mm.get("offset", 0.0))))
    return out


def build_mujoco(urdf, roots, args):
    """(model, notes). Raises on a robot MuJoCo refuses."""
    notes = []
    diag = []
    while True:
        spec = mujoco.MjSpec.from_string(mujoco_xml(urdf, roots, diag))
        tops = list(spec.worldbody.bodies)
        if len(tops) != 1:
            raise ValueError("%d bodies under the world, expected one root link" % len(tops))
        base = tops[0]
        if list(base.joints):
            raise ValueError("the root link %s already has a joint" % base.name)
        base.add_freejoint()
        for g in spec.geoms:
            g.contype, g.conaffinity = 1, 0
            g.friction = [1.0, 0.005, 0.0001]
        spec.worldbody.add_geom(name="sim_compare_floor", type=mujoco.mjtGeom.mjGEOM_PLANE,
                                size=[0, 0, 1], contype=0, conaffinity=1,
                                friction=[1.0, 0.005, 0.0001])
        names = {j.name for j in spec.joints}
        for j, leader, mul, off in mimics(urdf):
            if j in names and leader in names:
                spec.add_equality(type=mujoco.mjtEq.mjEQ_JOINT, name1=j, name2=leader,
                                  data=[off, mul, 0, 0, 0] + [0] * 6)
        spec.option.timestep = args.dt
        spec.option.gravity = [0, 0, -G]
        try:
            model = spec.compile()
        except ValueError as e:
            mt = re.search(r"inertia must have positive eigenvalues.*?Element name '([^']+)'", str(e),
                           re.S)
            if mt and mt.group(1) not in diag:
                diag.append(mt.group(1))
                notes.append("MuJoCo refuses link %s's inertia (not positive definite): "
                             "replaced by its diagonal for MuJoCo" % mt.group(1))
                continue
            raise
        return model, notes, len(mimics(urdf))


def lowest_point(m, d):
    """Lowest z of the robot's collision geometry (the floor excluded)."""
    low = math.inf
    for g in range(m.ngeom):
        if m.geom_type[g] == mujoco.mjtGeom.mjGEOM_PLANE:
            continue
        p, R = d.geom_xpos[g], d.geom_xmat[g].reshape(3, 3)
        s, t = m.geom_size[g], mujoco.mjtGeom(int(m.geom_type[g]))
        if t == mujoco.mjtGeom.mjGEOM_MESH:
            mid = m.geom_dataid[g]
            a, n = m.mesh_vertadr[mid], m.mesh_vertnum[mid]
            z = p[2] + m.mesh_vert[a:a + n] @ R[2]
            low = min(low, float(z.min()))
        elif t == mujoco.mjtGeom.mjGEOM_SPHERE:
            low = min(low, p[2] - s[0])
        elif t == mujoco.mjtGeom.mjGEOM_BOX:
            low = min(low, p[2] - float(np.abs(R[2]) @ s[:3]))
        elif t in (mujoco.mjtGeom.mjGEOM_CYLINDER, mujoco.mjtGeom.mjGEOM_CAPSULE):
            az = abs(R[2, 2])
            rad = s[0] * math.sqrt(max(0.0, 1 - az * az))
            low = min(low, p[2] - az * s[1] - (s[0] if t == mujoco.mjtGeom.mjGEOM_CAPSULE else rad))
        elif t == mujoco.mjtGeom.mjGEOM_ELLIPSOID:
            low = min(low, p[2] - float(np.linalg.norm(R[2] * s[:3])))
        else:
            raise ValueError("geom type %s not handled" % t.name)
    return low


def mujoco_start(m, q, urdf, H):
    """qpos of the start (see the docstring)."""
    d = mujoco.MjData(m)
    qpos = m.qpos0.copy()
    qpos[0:7] = [0, 0, 0, 1, 0, 0, 0]
    for name, val in q.items():
        jid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)
        if jid >= 0:
            qpos[m.jnt_qposadr[jid]] = val
    for j, leader, mul, off in mimics(urdf):
        a = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, j)
        b = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, leader)
        if a >= 0 and b >= 0:
            qpos[m.jnt_qposadr[a]] = off + mul * qpos[m.jnt_qposadr[b]]
    d.qpos[:] = qpos
    mujoco.mj_kinematics(m, d)
    qpos[2] += H - lowest_point(m, d)
    return qpos


def fresh(m, qpos, integ):
    m.opt.integrator = MJ_INTEGRATORS[integ]
    d = mujoco.MjData(m)
    d.qpos[:] = qpos
    mujoco.mj_forward(m, d)
    return d


def time_mujoco(m, qpos, integ, steps):
    d = fresh(m, qpos, integ)
    step = mujoco.mj_step
    t0 = time.perf_counter()
    for _ in range(steps):
        step(m, d)
    wall = time.perf_counter() - t0
    return steps / wall, wall


def contact_depth(d):
    return max((-float(d.contact[i].dist) for i in range(d.ncon)), default=0.0)


def run_mujoco_metrics(m, qpos, integ, steps, dt):
    d = fresh(m, qpos, integ)
    first = None
    moving_since = 0.0  # the state at t = 0 is at rest
    max_pen = 0.0
    trace = [(0.0, float(d.qpos[2]))]
    for k in range(1, steps + 1):
        mujoco.mj_step(m, d)
        if d.ncon and first is None:
            first = d.time - dt
        if d.ncon:
            max_pen = max(max_pen, contact_depth(d))
        speed = float(np.linalg.norm(d.qvel[0:3]))
        if speed < REST_SPEED:
            if moving_since is None:
                moving_since = d.time
        else:
            moving_since = None
        if k % TRACE_EVERY == 0 or k == steps:
            trace.append((round(d.time, 6), float(d.qpos[2])))
    mujoco.mj_forward(m, d)  # contacts of the final state
    warnings = {mujoco.mjtWarning(i).name: int(d.warning[i].number)
                for i in range(len(d.warning)) if d.warning[i].number}
    pen = contact_depth(d)
    return {"first_contact": first, "rest": moving_since, "rest_penetration": pen,
            "max_penetration": max(max_pen, pen), "contacts_end": int(d.ncon),
            "base_z_start": float(qpos[2]), "base_z_end": float(d.qpos[2]),
            "finite": bool(np.all(np.isfinite(d.qpos))), "warnings": warnings, "trace": trace}


# ---------------------------------------------------------------------------- urdyn

def urdyn_dofs(urdyn, urdf, tmp):
    empty = os.path.join(tmp, "empty.json")
    with open(empty, "w") as fh:
        json.dump({"states": []}, fh)
    p = subprocess.run([urdyn, "eval", urdf, "--floating-base", "--states", empty],
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if p.returncode != 0:
        raise RuntimeError(p.stderr.strip().splitlines()[-1] if p.stderr.strip() else "eval failed")
    return json.loads(p.stdout)["dof_names"]


def run_urdyn(cmd):
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    lines = [ln.strip() for ln in p.stderr.splitlines() if ln.strip()]
    summ = [ln for ln in lines if SUMMARY.search(ln)]
    out = {"exit": p.returncode, "stderr_other": [ln for ln in lines if ln not in summ]}
    if summ:
        mt = SUMMARY.search(summ[-1])
        out.update(steps=int(mt.group(1)), integrator=mt.group(2), wall=float(mt.group(3)),
                   summary=summ[-1])
        out["steps_per_s"] = out["steps"] / out["wall"] if out["wall"] > 0 else None
    return out


def parse_urdyn_csv(path):
    with open(path, newline="") as fh:
        rd = csv.reader(fh)
        head = next(rd)
        col = {h: i for i, h in enumerate(head)}
        ib = [col["v:base_vx"], col["v:base_vy"], col["v:base_vz"]]
        ic, ip, iz = col["contacts"], col["penetration"], col["q:base_z"]
        first, moving_since, max_pen, trace, finite = None, None, 0.0, [], True
        last = None
        for k, row in enumerate(rd):
            vals = [float(x) for x in row]
            if not all(math.isfinite(x) for x in vals):
                finite = False
            t = vals[0]
            if first is None and vals[ic] > 0:
                first = t
            max_pen = max(max_pen, vals[ip])
            if math.sqrt(sum(vals[i] ** 2 for i in ib)) < REST_SPEED:
                if moving_since is None:
                    moving_since = t
            else:
                moving_since = None
            if k % TRACE_EVERY == 0:
                trace.append((t, vals[iz]))
            if k == 0:
                z0 = vals[iz]
            last = vals
    if trace[-1][0] != last[0]:
        trace.append((last[0], last[iz]))
    return {"first_contact": first, "rest": moving_since, "rest_penetration": last[ip],
            "max_penetration": max_pen, "contacts_end": int(last[ic]), "base_z_start": z0,
            "base_z_end": last[iz], "finite": finite, "t_end": last[0], "trace": trace}


# ---------------------------------------------------------------------------- one robot

def bench_robot(name, rel, args, tmp):
    urdf = os.path.join(args.robots_dir, rel)
    r = {"robot": name, "urdf": rel, "notes": []}
    steps = int(round(args.duration / args.dt))
    # the start
    q = start_pose(urdf)
    try:
        dofs = urdyn_dofs(args.urdyn, urdf, tmp)
    except RuntimeError as e:
        r["urdyn_error"] = str(e)
        dofs = None
    if dofs is not None:
        r["dof"] = len(dofs)
        q = {k: v for k, v in q.items() if k in dofs}
    r["start_q"] = q
    # MuJoCo model
    try:
        t0 = time.perf_counter()
        m, notes, nmimic = build_mujoco(urdf, args.roots, args)
        r["mujoco_compile_s"] = time.perf_counter() - t0
        r["notes"] += notes
        r["mujoco_nv"], r["mujoco_nbody"], r["mujoco_ngeom"] = m.nv, m.nbody, m.ngeom
        r["mujoco_geom_types"] = sorted({mujoco.mjtGeom(int(t)).name[7:].lower()
                                         for t in m.geom_type} - {"plane"})
        r["mujoco_mass"] = float(m.body_mass.sum())
        qpos = mujoco_start(m, q, urdf, args.above_ground)
    except Exception as e:  # a robot MuJoCo refuses
        r["mujoco_error"] = "%s" % (str(e).strip().replace("\n", " ") or repr(e))
        m = None
    # urdyn command
    init = os.path.join(tmp, name + "_initial.json")
    with open(init, "w") as fh:
        json.dump({"q": q} if q else {}, fh)
    trj = os.path.join(tmp, name + ".csv")
    cmd = [args.urdyn, "simulate", urdf, "--floating-base", "--above-ground", repr(args.above_ground),
           "--duration", repr(args.duration), "--dt", repr(args.dt)]
    for p in args.roots:
        cmd += ["--package-path", p]
    cmd += ["--initial", init, "--out", trj]
    r["urdyn_command"] = " ".join(shlex.quote(c) for c in cmd)
    urdyn_runs, mj_runs = [], {k: [] for k in args.integrators}
    for rep in range(args.repeats):
        if "urdyn_error" not in r:
            u = run_urdyn(cmd)
            urdyn_runs.append(u)
            if u["exit"] != 0:
                r["urdyn_error"] = (u["stderr_other"] or ["exit %s" % u["exit"]])[-1]
        if m is not None:
            for integ in args.integrators:
                sps, wall = time_mujoco(m, qpos, integ, steps)
                mj_runs[integ].append(sps)
        print("  %s round %d: urdyn %s, MuJoCo %s" % (
            name, rep + 1, "%.0f" % urdyn_runs[-1]["steps_per_s"] if urdyn_runs and
            urdyn_runs[-1].get("steps_per_s") else "–",
            ", ".join("%s %.0f" % (k, v[-1]) for k, v in mj_runs.items() if v) or "–"),
            file=sys.stderr)
    # urdyn results
    if urdyn_runs and "urdyn_error" not in r:
        sps = [u["steps_per_s"] for u in urdyn_runs]
        r["urdyn"] = {"steps_per_s": statistics.median(sps), "runs_steps_per_s": sps,
                      "integrator": urdyn_runs[-1]["integrator"], "steps": urdyn_runs[-1]["steps"],
                      "summary": urdyn_runs[-1]["summary"]}
        r["urdyn"].update(parse_urdyn_csv(trj))
        warn = sorted(set(w for u in urdyn_runs for w in u["stderr_other"]))
        if warn:
            r["urdyn"]["warnings"] = warn
    # MuJoCo results
    if m is not None:
        r["mujoco"] = {}
        for integ in args.integrators:
            res = {"steps_per_s": statistics.median(mj_runs[integ]), "runs_steps_per_s": mj_runs[integ]}
            res.update(run_mujoco_metrics(m, qpos, integ, steps, args.dt))
            r["mujoco"][integ] = res
        best = max(args.integrators, key=lambda k: r["mujoco"][k]["steps_per_s"])
        r["mujoco_best"] = best
    if "urdyn" in r and "mujoco" in r:
        r["ratio"] = r["urdyn"]["steps_per_s"] / r["mujoco"][r["mujoco_best"]]["steps_per_s"]
        dz = r["urdyn"]["base_z_start"] - r["mujoco"][r["mujoco_best"]]["base_z_start"]
        r["start_base_z_diff"] = dz
        if abs(dz) > 1e-3:
            r["notes"].append("start base z differs by %.1f mm (lowest collision point computed "
                              "differently)" % (1e3 * dz))
    return r


# ---------------------------------------------------------------------------- output

def fmt(x, spec="%.3g", none="–"):
    if x is None:
        return none
    return spec % x


def machine():
    cpu = platform.processor() or ""
    try:
        with open("/proc/cpuinfo") as fh:
            cpu = next((ln.split(":", 1)[1].strip() for ln in fh if ln.startswith("model name")), cpu)
    except OSError:
        pass
    return "%s, %d cores, %s %s, Python %s" % (cpu or "unknown CPU", os.cpu_count(), platform.system(),
                                               platform.release(), platform.python_version())


def commit():
    try:
        c = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=REPO, text=True,
                           stdout=subprocess.PIPE, stderr=subprocess.DEVNULL).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no", "--", "src",
                                "Cargo.toml", "Cargo.lock"], cwd=REPO, text=True,
                               stdout=subprocess.PIPE, stderr=subprocess.DEVNULL).stdout.strip()
        return c + (" (with uncommitted changes in src/)" if dirty else "") if c else "unknown"
    except OSError:
        return "unknown"


def write_md(path, results, meta, plot_note):
    L = ["# Dropping robots in urdyn and MuJoCo", "",
         "Made by `%s` on %s (%.0f s wall): urdyn commit %s, MuJoCo %s, %s. "
         "The script's docstring defines the scene and every column." % (
             meta["command"], meta["date"], meta["wall_s"], meta["commit"], meta["mujoco_version"],
             meta["machine"]), "",
         "Scene: floating base, joints at 0 (mid-range where 0 is outside the limits), lowest "
         "collision point %g m above the ground, dt = %g s, %g s, gravity −9.81 z, friction 1, "
         "no self-collision, no control. steps/s: median of %d rounds (urdyn and MuJoCo back to "
         "back in each round); urdyn: its summary line's steps / wall seconds of the stepping loop; "
         "MuJoCo: perf_counter around the mj_step loop in this process, the faster of %s. "
         "Ratio = urdyn / MuJoCo (> 1: urdyn faster). Rest: first time after which the base "
         "speed stays < %g m/s. Free fall from %g m: first contact at %.3f s. The robots are "
         "passive: they land and fold under gravity, and where they fold is sensitive (a leg may "
         "splay one way or the other), so end poses may differ between the two engines." % (
             meta["above_ground"], meta["dt"], meta["duration"], meta["repeats"],
             " and ".join(meta["integrators"]), REST_SPEED, meta["above_ground"],
             math.sqrt(2 * meta["above_ground"] / G)), "",
         "| robot | DoF | urdyn steps/s | MuJoCo steps/s (integrator) | ratio | rest pen. urdyn / MuJoCo (mm) "
         "| rest at (s) urdyn / MuJoCo | first contact (s) urdyn / MuJoCo | contacts at rest urdyn / MuJoCo "
         "| max pen. urdyn / MuJoCo (mm) | base z start → end (m) urdyn / MuJoCo |",
         "|---|---|---|---|---|---|---|---|---|---|---|"]
    notes = []
    for r in results:
        u = r.get("urdyn") or {}
        mj = (r.get("mujoco") or {}).get(r.get("mujoco_best")) or {}

        def rest(x, have):
            return fmt(x, "%.3f") if x is not None else ("never" if have else "–")

        mjs = "–"
        if mj:
            mjs = "%.0f (%s)" % (mj["steps_per_s"], r["mujoco_best"])
            other = [k for k in r["mujoco"] if k != r["mujoco_best"]]
            if other:
                mjs += "; " + ", ".join("%s %.0f" % (k, r["mujoco"][k]["steps_per_s"]) for k in other)
        L.append("| %s | %s | %s | %s | %s | %s / %s | %s / %s | %s / %s | %s / %s | %s / %s | %s |" % (
            r["robot"], r.get("dof", "–"),
            fmt(u.get("steps_per_s"), "%.0f") + (" (%s)" % u["integrator"] if u.get("integrator") else ""),
            mjs, fmt(r.get("ratio"), "%.2f"),
            fmt(1e3 * u["rest_penetration"] if u else None, "%.2f"),
            fmt(1e3 * mj["rest_penetration"] if mj else None, "%.2f"),
            rest(u.get("rest"), bool(u)), rest(mj.get("rest"), bool(mj)),
            fmt(u.get("first_contact"), "%.3f"), fmt(mj.get("first_contact"), "%.3f"),
            fmt(u.get("contacts_end"), "%d"), fmt(mj.get("contacts_end"), "%d"),
            fmt(1e3 * u["max_penetration"] if u else None, "%.2f"),
            fmt(1e3 * mj["max_penetration"] if mj else None, "%.2f"),
            " / ".join("%.3f → %.3f" % (x["base_z_start"], x["base_z_end"]) if x else "–" for x in (u, mj))))
        n = list(r["notes"])
        if r.get("mujoco_error"):
            n.append("MuJoCo refuses it: " + r["mujoco_error"])
        if r.get("urdyn_error"):
            n.append("urdyn fails: " + r["urdyn_error"])
        for w in u.get("warnings", []):
            n.append("urdyn: " + w)
        for integ, res in (r.get("mujoco") or {}).items():
            if res["warnings"]:
                n.append("MuJoCo %s warnings: %s" % (integ, ", ".join(
                    "%s ×%d" % kv for kv in res["warnings"].items())))
            if not res["finite"]:
                n.append("MuJoCo %s: non-finite state" % integ)
        if u and not u.get("finite", True):
            n.append("urdyn: non-finite values in the CSV")
        if r.get("mujoco_nv") is not None and r.get("dof") is not None and r["mujoco_nv"] != r["dof"] + 6:
            n.append("MuJoCo has nv = %d, urdyn %d + 6" % (r["mujoco_nv"], r["dof"]))
        if n:
            notes.append("- %s: %s." % (r["robot"], "; ".join(x.rstrip(".") for x in n)))
    L += ["", "Both collide a mesh through the convex hull of its vertices. Contact models differ: "
          "urdyn's is hard (velocity-level complementarity, penetration removed by a position pass), "
          "MuJoCo's soft (default solref 0.02 s: the landing sinks centimetres in before it is pushed "
          "out), hence the max. penetration column. Collision geometry per robot (MuJoCo's names): " + "; ".join(
              "%s %s" % (r["robot"], ", ".join(r.get("mujoco_geom_types", []))) for r in results
              if r.get("mujoco_geom_types")) + "."]
    L += ["", "## Notes", ""] + (notes or ["none"])
    L += ["", plot_note]
    with open(path, "w") as fh:
        fh.write("\n".join(L) + "\n")


def plot(path, results):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return None
    have = [r for r in results if r.get("urdyn") or r.get("mujoco")]
    fig = plt.figure(figsize=(12, 4 + 2.2 * math.ceil(len(have) / 3)))
    gs = fig.add_gridspec(1 + math.ceil(len(have) / 3), 3, height_ratios=[1.6] + [1] * math.ceil(len(have) / 3))
    ax = fig.add_subplot(gs[0, :])
    x = np.arange(len(have))
    us = [(r.get("urdyn") or {}).get("steps_per_s") or 0 for r in have]
    ms = [r["mujoco"][r["mujoco_best"]]["steps_per_s"] if r.get("mujoco") else 0 for r in have]
    ax.bar(x - 0.2, us, 0.4, label="urdyn")
    ax.bar(x + 0.2, ms, 0.4, label="MuJoCo (faster integrator)")
    ax.set_xticks(x, [r["robot"] for r in have])
    ax.set_ylabel("steps/s (dt = 1 ms)")
    ax.set_yscale("log")
    ax.legend()
    ax.set_title("Drop test, %s" % datetime.date.today().isoformat())
    for i, r in enumerate(have):
        a = fig.add_subplot(gs[1 + i // 3, i % 3])
        if r.get("urdyn"):
            t, z = zip(*r["urdyn"]["trace"])
            a.plot(t, z, label="urdyn")
        if r.get("mujoco"):
            t, z = zip(*r["mujoco"][r["mujoco_best"]]["trace"])
            a.plot(t, z, "--", label="MuJoCo (faster integrator)")
        a.set_title(r["robot"], fontsize=9)
        a.set_xlabel("t (s)", fontsize=8)
        a.set_ylabel("base z (m)", fontsize=8)
        a.tick_params(labelsize=7)
        if i == 0:
            a.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    return path


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--robots", action="append", default=[],
                    help="names of the built-in list or URDF paths below robots/ (comma separated, repeatable)")
    ap.add_argument("--share", help="the folder holding example-robot-data/")
    ap.add_argument("--urdyn", default=os.path.join(REPO, "target", "release", "urdyn"))
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--duration", type=float, default=3.0)
    ap.add_argument("--dt", type=float, default=0.001)
    ap.add_argument("--above-ground", type=float, default=0.3)
    ap.add_argument("--integrators", default="euler,implicitfast",
                    help="MuJoCo integrators to time; the faster is reported")
    ap.add_argument("--md", default=os.path.join(HERE, "sim_results.md"))
    ap.add_argument("--json", default=os.path.join(HERE, "sim_results.json"))
    ap.add_argument("--png", default=os.path.join(HERE, "sim_results.png"))
    args = ap.parse_args()
    args.integrators = [s.strip() for s in args.integrators.split(",") if s.strip()]
    for k in args.integrators:
        if k not in MJ_INTEGRATORS:
            sys.exit("sim_compare: unknown MuJoCo integrator %s (%s)" % (k, ", ".join(MJ_INTEGRATORS)))
    share = find_share(args.share)
    args.robots_dir = os.path.join(share, "example-robot-data", "robots")
    args.roots = [share, args.robots_dir]
    if not os.access(args.urdyn, os.X_OK):
        sys.exit("sim_compare: %s is not an executable (cargo build --release)" % args.urdyn)
    wanted = [s.strip() for a in args.robots for s in a.split(",") if s.strip()] or list(ROBOTS)
    jobs = []
    for w in wanted:
        rel = ROBOTS.get(w, w)
        if not os.path.exists(os.path.join(args.robots_dir, rel)):
            sys.exit("sim_compare: %s: no such robot name or URDF below %s" % (w, args.robots_dir))
        jobs.append((w if w in ROBOTS else os.path.splitext(os.path.basename(w))[0], rel))

    started = time.time()
    date = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    results = []
    with tempfile.TemporaryDirectory(prefix="sim_compare_") as tmp:
        for name, rel in jobs:
            print("%s (%s)" % (name, rel), file=sys.stderr)
            results.append(bench_robot(name, rel, args, tmp))
    argv = ["python", os.path.relpath(os.path.abspath(__file__), REPO)] + sys.argv[1:]
    meta = {"command": " ".join(shlex.quote(a) for a in argv), "date": date,
            "wall_s": time.time() - started, "commit": commit(), "machine": machine(),
            "mujoco_version": mujoco.__version__, "numpy_version": np.__version__,
            "urdyn": args.urdyn, "share": share, "above_ground": args.above_ground, "dt": args.dt,
            "duration": args.duration, "repeats": args.repeats, "integrators": args.integrators,
            "rest_speed": REST_SPEED}
    png = plot(args.png, results) if args.png else None
    plot_note = ("![steps/s and base height](%s)" % os.path.relpath(png, os.path.dirname(os.path.abspath(args.md)))
                 if png else "No plot: matplotlib is not installed in this Python (%s)." % sys.executable)
    write_md(args.md, results, meta, plot_note)
    for r in results:  # traces as two short columns, rounded
        for res in [r.get("urdyn")] + list((r.get("mujoco") or {}).values()):
            if res and "trace" in res:
                res["trace"] = {"t": [round(t, 4) for t, _ in res["trace"]],
                                "base_z": [round(z, 5) for _, z in res["trace"]]}
    text = json.dumps({"meta": meta, "results": results}, indent=1)
    text = re.sub(r"\[\s*([-0-9.eE,\s]+?)\s*\]",  # numeric lists on one line
                  lambda mt: "[" + ", ".join(mt.group(1).replace(",", " ").split()) + "]", text)
    with open(args.json, "w") as fh:
        fh.write(text + "\n")
    print("wrote %s, %s%s" % (args.md, args.json, ", " + png if png else " (no plot: no matplotlib)"),
          file=sys.stderr)


if __name__ == "__main__":
    main()
