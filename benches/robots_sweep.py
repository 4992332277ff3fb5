#!/usr/bin/env python3
"""Simulate every URDF of example-robot-data with `urdyn simulate` and tabulate the runs.

Usage:
    python3 benches/robots_sweep.py ERD_DIR [--urdyn target/release/urdyn] [--jobs 2]
        [--timeout 300] [--only NAME]... [--integrator NAME] [--out docs/robots.md]
        [--json OUT.json] [--above-ground 0.3] [--lift-base Z] [--loader robots_loader.py]

ERD_DIR is example-robot-data's share folder (the one holding `robots/`), e.g.
/work/venv/lib/python3.11/site-packages/cmeel.prefix/share/example-robot-data; its parent
or its `robots/` folder are accepted too. Every `*.urdf` below `robots/` is run. Its meshes
are found through `--package-path SHARE --package-path SHARE/example-robot-data/robots`
(the URDFs use both `package://example-robot-data/robots/...` and `package://NAME/...`).
Python 3 standard library only.

Floating or fixed root
----------------------
The source of truth is the `free_flyer` flag of example-robot-data's own Python loaders
(python/example_robot_data/robots_loader.py, Gepetto/example-robot-data, branch devel at
8d470d2, 2025-05-06), mapped to the URDF file each loader opens (`path/urdf_subpath/
urdf_filename`, class inheritance followed): LOADER_FREE_FLYER below. `--loader FILE`
re-derives that table from another copy of robots_loader.py (parsed with `ast`, not run).
URDFs that no loader opens get the explicit EXTRA_FREE_FLYER table, by the rule: legged
robots, humanoids, flying robots and mobile bases float; arms, hands, fingers, pendulums
and grippers are fixed. Where the loader and that rule disagree the loader wins: the
Tiago loaders (mobile manipulators) and the Alex loaders (upper-body humanoid) are
fixed-base, PR2 floats. A URDF in neither table is guessed from its name by the same
rule and marked "guessed" in the notes.

Runs
----
- floating: `urdyn simulate URDF --floating-base --above-ground H --duration 5 --out CSV`
  (H = --above-ground, 0.3 m by default);
- fixed: `urdyn simulate URDF --no-ground --duration 3 --out CSV`;
plus `--package-path` (above), `--integrator` if given, and `--initial STATE.json` when
the start needs it. The start: every joint at 0, except a revolute/prismatic joint whose
`<limit lower upper>` excludes 0, which starts at the middle of its limits (continuous,
floating, planar and fixed joints, and joints with a `<mimic>` child, are skipped). Only
the degrees of freedom that urdyn reports (`urdyn eval URDF --states {"states": []}`
gives `dof_names`) are written into `{"q": {...}}`.
If the binary does not know `--above-ground`, floating rows are not run and say
"needs --above-ground", unless `--lift-base Z` is given: then floating robots start
from their start pose with the base at z = Z (`"base": {"position": [0, 0, Z]}`) and no
`--above-ground`, and the first-contact check is not applied (the fall height is unknown).

With `--self-collision` every run is a one-model scene (`urdyn simulate --scene`,
scene.md) instead: the same URDF, start and duration, `"self_collision": true`, and the
robot's SRDF when example-robot-data ships one (`<pkg>/srdf/*.srdf`: the one file, else
the one whose stem the URDF's stem starts with, longest first; its
`<disable_collisions>` pairs excluded). A floating robot starts where
`--above-ground H` puts it (read off a 1 ms run of the plain command), on a ground at
z = 0; a fixed one has no ground. Links of the robot that overlap at the start are left
out by urdyn (scene.md "Who touches whom"; listed in its warnings). The contact-time
check becomes "first contact no later than sqrt(2H/|g|) + 0.03 s" (a link may touch
another one before the ground).

Load status: `urdyn inspect` and `urdyn eval` (empty state list) must both succeed; a
URDF for which either fails (unparsable, no forward dynamics, ...) goes to the "does not
load" list with the error's first line and is not simulated.

Per run (the CSV, written every step, is stream-parsed and deleted):
- exit status (or "timeout" after --timeout s, a failure), finite (no non-finite error,
  every CSV value finite);
- energy rise: max over rows of E(t) - E(0), J, and relative to max(|E(0)|, 1 J);
- first contact: t of the first row with contacts > 0;
- rest: floating, the first t after which the base linear speed sqrt(vx²+vy²+vz²) (from
  v:base_vx, v:base_vy, v:base_vz) stays below 0.05 m/s to the end; fixed, the first t
  after which every |v:joint| < 0.05 stays; "never" when the last row is not at rest;
- deepest penetration (max of the penetration column); steps/s (steps / wall seconds of
  the summary line on stderr; runs share the machine with --jobs-1 others);
  max base linear speed; max |joint speed|.
- pass: exit 0, finite, energy rise <= 1e-3*|E0| + 1e-3 J and, for floating robots that
  touch the ground, first contact within 0.03 s of sqrt(2H/|g|) (0.247 s for a 0.3 m
  fall) and at rest by the end (rest is not "never"), and, when every velocity
  coordinate (base linear and angular, joints) has stayed below SLEEP_SPEED (1e-3, scene.md's
  default sleep_velocity) from at least SLEEP_MARGIN (1 s) before the end, asleep by the end
  (scene.md: an island whose every point moves slower than sleep_velocity for sleep_time,
  0.5 s, sleeps; its velocities then read exactly 0). A robot at rest by the 0.05 rule but
  still moving faster than that (a free wrist spinning down, a damped arm decaying) is
  honestly awake: the end motion column and the note say so.
- end motion: the largest |velocity coordinate| over the last SLEEP_MARGIN seconds.
- asleep: the first t after which the CSV's `awake` column stays 0 to the end; "never"
  when the last row has an awake model.

Output: `--out` (docs/robots.md): header (command line, date, urdyn commit, cores; `--title`,
`--note` add a title and a paragraph), the table (floating first, then by name; the note
column gives the failed checks, a start in the ground, a floating URDF without any
<collision>, urdyn's error and warnings), the worst rows, the "does not load" list.
`--json` dumps the raw per-robot results (the exact commands included).
A timeout (of inspect, eval or simulate; --timeout each) is a failed row, not a load error.
"""
import argparse
import ast
import concurrent.futures
import csv
import datetime
import json
import math
import os
import re
import shlex
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
G = 9.81
REST_SPEED = 0.05  # m/s (base) or rad/s, m/s (joints)
SLEEP_MARGIN = 1.0  # s: quiet this long before the end => must be asleep
SLEEP_SPEED = 1e-3  # scene.md's default sleep_velocity, applied to every velocity coordinate
CONTACT_TOL = 0.03  # s

# free_flyer of example-robot-data's loaders (robots_loader.py, devel 8d470d2), keyed by
# the URDF path below robots/.
LOADER_FREE_FLYER = {
    "a1_description/urdf/a1.urdf": True,
    "alex_description/urdf/alex_nub_hands.urdf": False,
    "alex_description/urdf/alex_psyonic_hands.urdf": False,
    "alex_description/urdf/alex_sake_hands.urdf": False,
    "allegro_hand_description/urdf/allegro_left_hand.urdf": False,
    "allegro_hand_description/urdf/allegro_right_hand.urdf": False,
    "anymal_b_simple_description/robots/anymal-kinova.urdf": True,
    "anymal_b_simple_description/robots/anymal.urdf": True,
    "anymal_c_simple_description/urdf/anymal.urdf": True,
    "asr_twodof_description/urdf/TwoDofs.urdf": False,
    "b1_description/urdf/b1-z1.urdf": True,
    "b1_description/urdf/b1.urdf": True,
    "baxter_description/urdf/baxter.urdf": False,
    "bluevolta_description/urdf/bluevolta_bravo7_gripper.urdf": True,
    "bluevolta_description/urdf/bluevolta_bravo7_no_ee.urdf": True,
    "bolt_description/robots/bolt.urdf": True,
    "borinot_description/urdf/borinot_flying_arm_2.urdf": True,
    "bravo7_description/urdf/bravo7_gripper.urdf": False,
    "bravo7_description/urdf/bravo7_no_ee.urdf": False,
    "double_pendulum_description/urdf/double_pendulum.urdf": False,
    "double_pendulum_description/urdf/double_pendulum_continuous.urdf": False,
    "double_pendulum_description/urdf/double_pendulum_simple.urdf": False,
    "falcon_description/urdf/falcon_bravo7_gripper.urdf": True,
    "falcon_description/urdf/falcon_bravo7_no_ee.urdf": True,
    "finger_edu_description/robots/finger_edu.urdf": False,
    "go1_description/urdf/go1.urdf": True,
    "go2_description/urdf/go2.urdf": True,
    "hector_description/robots/quadrotor_base.urdf": True,
    "hextilt_description/urdf/hextilt_flying_arm_5.urdf": True,
    "hyq_description/robots/hyq_no_sensors.urdf": True,
    "icub_description/robots/icub.urdf": True,
    "icub_description/robots/icub_reduced.urdf": True,
    "iris_description/robots/iris_simple.urdf": True,
    "kinova_description/robots/kinova.urdf": False,
    "laikago_description/urdf/laikago.urdf": True,
    "panda_description/urdf/panda.urdf": False,
    "panda_description/urdf/panda_collision.urdf": False,
    "pr2_description/urdf/pr2.urdf": True,
    "quadruped_description/urdf/quadruped.urdf": True,
    "romeo_description/urdf/romeo.urdf": True,
    "simple_humanoid_description/urdf/simple_humanoid.urdf": True,
    "simple_humanoid_description/urdf/simple_humanoid_classical.urdf": True,
    "solo_description/robots/solo.urdf": True,
    "solo_description/robots/solo12.urdf": True,
    "talos_data/robots/talos_full_v2.urdf": True,
    "talos_data/robots/talos_full_v2_box.urdf": True,
    "talos_data/robots/talos_left_arm.urdf": False,
    "talos_data/robots/talos_reduced.urdf": True,
    "talos_data/robots/talos_reduced_box.urdf": True,
    "tiago_description/robots/tiago.urdf": False,
    "tiago_description/robots/tiago_dual.urdf": False,
    "tiago_description/robots/tiago_no_hand.urdf": False,
    "tiago_pro_description/robots/tiago_pro.urdf": False,
    "ur_description/urdf/ur10_joint_limited_robot.urdf": False,
    "ur_description/urdf/ur10_robot.urdf": False,
    "ur_description/urdf/ur3_gripper.urdf": False,
    "ur_description/urdf/ur3_joint_limited_robot.urdf": False,
    "ur_description/urdf/ur3_robot.urdf": False,
    "ur_description/urdf/ur5_gripper.urdf": False,
    "ur_description/urdf/ur5_joint_limited_robot.urdf": False,
    "ur_description/urdf/ur5_robot.urdf": False,
    "z1_description/urdf/z1.urdf": False,
}

# URDFs that no loader opens (example-robot-data 6.0.0), by the rule of the docstring.
EXTRA_FREE_FLYER = {
    "alexander_description/urdf/alexander_v1.lowerBodyOnly.urdf": True,  # humanoid legs
    "centauro_description/urdf/centauro.urdf": True,  # legged (four legs, torso, arms)
    "g1_description/urdf/g1_29dof_rev_1_0.urdf": True,  # humanoid
    "g1_description/urdf/g1_29dof_with_hand_rev_1_0.urdf": True,  # humanoid
    "human_description/robots/human.urdf": True,  # human body model
    "iris_description/robots/iris.urdf": True,  # quadrotor
    "romeo_description/urdf/romeo_laas_small.urdf": True,  # humanoid
    "romeo_description/urdf/romeo_small.urdf": True,  # humanoid
    "talos_data/robots/talos_reduced_corrected.urdf": True,  # humanoid
    "so_arm_description/urdf/so100.urdf": False,  # arm
    "so_arm_description/urdf/so101.urdf": False,  # arm
    "ur_description/urdf/ur3.urdf": False,  # arm
    "xarm_description/urdf/xarm7.urdf": False,  # arm
}

FLOAT_WORDS = ("quadrotor", "hextilt", "borinot", "iris", "hector", "humanoid", "legged",
               "anymal", "solo", "bolt", "talos", "g1", "go1", "go2", "a1", "b1", "hyq",
               "laikago", "icub", "romeo", "human", "pr2", "quadruped", "cassie")


def loader_table(path):
    """free_flyer per URDF path from a robots_loader.py, by reading its class attributes."""
    tree = ast.parse(open(path).read())
    classes = {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            attrs = {}
            for s in node.body:
                if (isinstance(s, ast.Assign) and len(s.targets) == 1
                        and isinstance(s.targets[0], ast.Name)):
                    try:
                        attrs[s.targets[0].id] = ast.literal_eval(s.value)
                    except ValueError:
                        pass
            classes[node.name] = ([b.id for b in node.bases if isinstance(b, ast.Name)], attrs)

    def get(cls, key):
        bases, attrs = classes[cls]
        if key in attrs:
            return attrs[key]
        for b in bases:
            if b in classes:
                v = get(b, key)
                if v is not None:
                    return v
        return None

    out = {}
    for cls in classes:
        fn = get(cls, "urdf_filename")
        if fn and get(cls, "path"):
            out["/".join((get(cls, "path"), get(cls, "urdf_subpath") or "robots", fn))] = bool(
                get(cls, "free_flyer"))
    return out


def decide_floating(rel, table):
    if rel in table:
        return table[rel], "loader"
    if rel in EXTRA_FREE_FLYER:
        return EXTRA_FREE_FLYER[rel], "table"
    low = rel.lower()
    return any(re.search(r"(^|[^a-z])" + w, low) for w in FLOAT_WORDS), "guessed"


def start_pose(urdf):
    """{joint: value} for the joints whose limits exclude 0 (middle of the limits)."""
    root = ET.parse(urdf).getroot()
    q = {}
    for j in root.iter("joint"):
        if j.get("type") not in ("revolute", "prismatic") or j.find("mimic") is not None:
            continue
        lim = j.find("limit")
        if lim is None:
            continue
        lo, hi = float(lim.get("lower", 0.0)), float(lim.get("upper", 0.0))
        if lo <= hi and not (lo <= 0.0 <= hi):
            q[j.get("name")] = 0.5 * (lo + hi)
    return q


def first_line(text):
    for line in text.splitlines():
        if line.strip():
            return line.strip()
    return ""


def run(cmd, timeout):
    t0 = time.time()
    try:
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                           timeout=timeout)
        return p.returncode, p.stdout, p.stderr, time.time() - t0
    except subprocess.TimeoutExpired as e:
        err = e.stderr.decode(errors="replace") if isinstance(e.stderr, bytes) else (e.stderr or "")
        return "timeout", "", err, time.time() - t0


def fnum(x):
    try:
        return float(x)
    except ValueError:
        return float("nan")


def parse_csv(path, floating):
    """Stream the trajectory once; returns the metrics (None when there is no CSV)."""
    if not os.path.exists(path):
        return None
    m = {"rows": 0, "finite_csv": True, "E0": None, "rise": -math.inf, "first_contact": None,
         "rest": None, "max_pen": 0.0, "max_base_speed": None, "max_joint_speed": 0.0,
         "asleep": None}
    with open(path, newline="") as fh:
        rd = csv.reader(fh)
        head = next(rd, None)
        if head is None:
            return None
        # a one-model scene's columns are q:MODEL/NAME, v:MODEL/NAME
        head = [re.sub(r"^([qv]):[^/]+/", r"\1:", h) for h in head]
        col = {h: i for i, h in enumerate(head)}
        ie, ic, ip = col["energy"], col["contacts"], col["penetration"]
        base = [col[k] for k in ("v:base_vx", "v:base_vy", "v:base_vz")] if floating else None
        joints = [i for h, i in col.items() if h.startswith("v:") and not h.startswith("v:base_")]
        moving_since = None  # t of the first row of the current at-rest stretch
        ia = col.get("awake")
        asleep_since = None  # t of the first row of the current all-asleep stretch
        all_still_since = None  # ... of every velocity coordinate below SLEEP_SPEED
        motion = []  # (t, largest |velocity coordinate|) a row, for the end motion
        for row in rd:
            vals = [fnum(x) for x in row]
            if not all(math.isfinite(x) for x in vals):
                m["finite_csv"] = False
            t, e = vals[0], vals[ie]
            m["rows"] += 1
            if m["E0"] is None:
                m["E0"], m["pen0"] = e, vals[ip]
            m["rise"] = max(m["rise"], e - m["E0"])
            if m["first_contact"] is None and vals[ic] > 0:
                m["first_contact"] = t
            m["max_pen"] = max(m["max_pen"], vals[ip])
            js = max((abs(vals[i]) for i in joints), default=0.0)
            m["max_joint_speed"] = max(m["max_joint_speed"], js)
            if floating:
                bs = math.sqrt(sum(vals[i] ** 2 for i in base))
                m["max_base_speed"] = max(m["max_base_speed"] or 0.0, bs)
                still = bs < REST_SPEED
            else:
                still = js < REST_SPEED
            if still:
                if moving_since is None:
                    moving_since = t
            else:
                moving_since = None
            vmax = max((abs(vals[i]) for i in (base or []) + joints), default=0.0)
            if floating:
                vmax = max([vmax] + [abs(vals[col[k]]) for k in ("v:base_wx", "v:base_wy", "v:base_wz") if k in col])
            motion.append((t, vmax))
            if vmax < SLEEP_SPEED:
                if all_still_since is None:
                    all_still_since = t
            else:
                all_still_since = None
            if ia is not None and vals[ia] == 0:
                if asleep_since is None:
                    asleep_since = t
            else:
                asleep_since = None
        m["rest"] = moving_since
        m["asleep"] = asleep_since
        m["all_still"] = all_still_since
        m["t_end"] = t if m["rows"] else None
        if m["rows"]:
            m["end_motion"] = max(v for (tt, v) in motion if tt >= t - SLEEP_MARGIN)
    return m


def find_srdf(urdf):
    """The SRDF example-robot-data ships beside `urdf` (`<pkg>/srdf/`), or None."""
    pkg = os.path.dirname(os.path.dirname(urdf))
    d = os.path.join(pkg, "srdf")
    if not os.path.isdir(d):
        return None
    files = sorted(f for f in os.listdir(d) if f.endswith(".srdf"))
    if len(files) == 1:
        return os.path.join(d, files[0])
    stem = os.path.splitext(os.path.basename(urdf))[0]
    match = [f for f in files if stem.startswith(os.path.splitext(f)[0])]
    match.sort(key=len, reverse=True)
    return os.path.join(d, match[0]) if match else None


def scene_command(plain, urdf, floating, state, tmp, args, r):
    """The one-model scene run (`--self-collision`) of the plain command `plain`
    (which ends before --package-path and --out): the start pose read off a 1 ms run
    of it. None (with r["error"] set) when that run fails."""
    pk = []
    for d in args.package_paths:
        pk += ["--package-path", d]
    model = {"name": "r", "urdf": urdf, "base": "floating" if floating else "fixed",
             "self_collision": True}
    srdf = find_srdf(urdf)
    if srdf:
        model["srdf"] = srdf
        r["srdf"] = os.path.relpath(srdf, os.path.dirname(os.path.dirname(os.path.dirname(urdf))))
    if state.get("q"):
        model["initial"] = {"q": state["q"]}
    if floating:
        probe = os.path.join(tmp, "start.csv")
        cmd = [c for c in plain]
        k = cmd.index("--duration")
        cmd[k + 1] = "0.001"
        rc, _, err, _ = run(cmd + pk + ["--out", probe], args.timeout)
        if rc != 0 or not os.path.exists(probe):
            r["error"] = "start pose: " + (first_line(err) or "exit %s" % rc)
            r["exit"] = rc
            return None
        with open(probe, newline="") as fh:
            rd = csv.reader(fh)
            head = next(rd)
            row = [float(x) for x in next(rd)]
        col = {h: i for i, h in enumerate(head)}
        model["position"] = [row[col["q:base_" + a]] for a in "xyz"]
        model["orientation_xyzw"] = [row[col["q:base_q" + a]] for a in "xyzw"]
    scene = {"models": [model]}
    if floating:
        scene["ground"] = {"height": 0.0}
    path = os.path.join(tmp, "scene.json")
    with open(path, "w") as fh:
        json.dump(scene, fh)
    cmd = [args.urdyn, "simulate", "--scene", path, "--duration", "5" if floating else "3"]
    if args.integrator:
        cmd += ["--integrator", args.integrator]
    return cmd


SUMMARY = re.compile(r"(\d+) steps (?:\((\S+)\) )?in ([0-9.eE+-]+) s wall")


def sweep_one(job, args, have_above_ground):
    rel, urdf, floating, how = job["rel"], job["urdf"], job["floating"], job["how"]
    r = {"robot": job["name"], "urdf": rel, "path": urdf, "floating": floating, "base_rule": how,
         "loads": True, "load_error": None, "exit": None, "finite": None, "note": ""}
    pk = []
    for d in args.package_paths:
        pk += ["--package-path", d]
    with tempfile.TemporaryDirectory(prefix="sweep_", dir=args.tmpdir) as tmp:
        empty = os.path.join(tmp, "empty.json")
        with open(empty, "w") as fh:
            json.dump({"states": []}, fh)
        fb = ["--floating-base"] if floating else []
        # the URDF loads when both inspect and eval (an empty batch) accept it
        for what, cmd in (("inspect", [args.urdyn, "inspect", urdf] + fb + pk),
                          ("eval", [args.urdyn, "eval", urdf, "--states", empty] + fb)):
            rc, out, err, _ = run(cmd, args.timeout)
            if rc == "timeout":
                r.update(exit="timeout", finite=None, error="%s: timeout after %g s" % (what, args.timeout),
                         **{"pass": False, "fail_reasons": ["timeout"]})
                return r
            if rc != 0:
                r.update(loads=False, load_error=first_line(err) or "%s: %s" % (what, rc))
                return r
        dofs = json.loads(out)["dof_names"]
        r["dofs"] = len(dofs)
        try:
            q = start_pose(urdf)
        except ET.ParseError as e:
            r.update(loads=False, load_error="xml.etree: %s" % e)
            return r
        r["collision_elements"] = len(list(ET.parse(urdf).getroot().iter("collision")))
        q = {k: v for k, v in q.items() if k in dofs}
        r["start_q"] = q
        state = {}
        if q:
            state["q"] = q
        cmd = [args.urdyn, "simulate", urdf]
        if floating:
            cmd += ["--floating-base", "--duration", "5"]
            if have_above_ground:
                cmd += ["--above-ground", repr(args.above_ground)]
            elif args.lift_base is not None:
                state["base"] = {"position": [0.0, 0.0, args.lift_base]}
            else:
                r["note"] = "needs --above-ground"
                return r
        else:
            cmd += ["--no-ground", "--duration", "3"]
        if state:
            init = os.path.join(tmp, "initial.json")
            with open(init, "w") as fh:
                json.dump(state, fh)
            cmd += ["--initial", init]
        if args.integrator:
            cmd += ["--integrator", args.integrator]
        trj = os.path.join(tmp, "traj.csv")
        if args.self_collision:
            cmd = scene_command(cmd, urdf, floating, state, tmp, args, r)
            if cmd is None:
                return r
        cmd += pk + ["--out", trj]
        r["command"] = " ".join(shlex.quote(c) for c in cmd)
        rc, out, err, wall = run(cmd, args.timeout)
        r["exit"] = rc
        r["wall_s"] = round(wall, 3)
        lines = [ln.strip() for ln in err.splitlines() if ln.strip()]
        summ = [ln for ln in lines if SUMMARY.search(ln)]
        others = [ln for ln in lines if ln not in summ]
        if "unexpected argument '--above-ground'" in err:
            r["note"] = "needs --above-ground"
            r["exit"] = None
            return r
        if rc == "timeout":
            r["error"] = "timeout after %g s" % args.timeout
        elif rc != 0:
            r["error"] = others[-1] if others else "exit %s" % rc
        r["warnings"] = [ln for ln in others if ln != r.get("error")]
        if summ:
            mt = SUMMARY.search(summ[-1])
            r["steps"], r["integrator"], r["wall_sim_s"] = int(mt.group(1)), mt.group(2), float(mt.group(3))
            r["steps_per_s"] = r["steps"] / r["wall_sim_s"] if r["wall_sim_s"] > 0 else None
            r["summary"] = summ[-1]
        m = parse_csv(trj, floating)
        nonfinite_err = "non-finite" in err or "NaN" in err
        if m is not None:
            r.update(m)
            r["rise_rel"] = m["rise"] / max(abs(m["E0"]), 1.0)
            r["finite"] = m["finite_csv"] and not nonfinite_err
        else:
            r["finite"] = False if nonfinite_err else (None if rc != 0 else True)
    # acceptance
    ok = r["exit"] == 0 and r["finite"] is True and r.get("E0") is not None
    why = []
    if r["exit"] != 0:
        why.append("timeout" if r["exit"] == "timeout" else "exit %s" % r["exit"])
    if r["finite"] is False:
        why.append("non-finite")
    if r.get("E0") is not None and r["rise"] > 1e-3 * abs(r["E0"]) + 1e-3:
        ok = False
        why.append("energy")
    if floating and r.get("first_contact") is not None:
        if have_above_ground:
            expect = math.sqrt(2 * args.above_ground / G)
            r["contact_expected"] = expect
            early = args.self_collision and r["first_contact"] < expect
            if abs(r["first_contact"] - expect) > CONTACT_TOL and not early:
                ok = False
                why.append("contact time")
        if r.get("rest") is None:
            ok = False
            why.append("not at rest")
        elif (r.get("t_end") is not None and r.get("all_still") is not None
              and r["all_still"] <= r["t_end"] - SLEEP_MARGIN and r.get("asleep") is None):
            ok = False
            why.append("still but awake")
    r["pass"] = ok
    r["fail_reasons"] = why
    return r


def fmt(x, spec="%.3g", none="–"):
    if x is None:
        return none
    if isinstance(x, float) and not math.isfinite(x):
        return str(x)
    return spec % x


def write_md(path, results, header):
    ran = [r for r in results if r["loads"]]
    dead = [r for r in results if not r["loads"]]
    ran.sort(key=lambda r: (not r["floating"], r["robot"]))
    L = list(header)
    L += ["", "| robot | base | DoF | exit | finite | E0 (J) | energy rise (J) | rise rel. "
          "| first contact (s) | rest (s) | asleep (s) | end motion | max pen. (mm) | steps/s, integrator "
          "| max base v (m/s) | max joint v | pass | note |",
          "|" + "---|" * 18]
    for r in ran:
        note = r["note"] or r.get("error") or ""
        if r["floating"] and r.get("collision_elements") == 0:
            note = ("no <collision> in the URDF: never lands; " + note).strip("; ")
        if r.get("pen0"):
            note = ("starts %.1f mm in the ground; " % (1e3 * r["pen0"]) + note).strip("; ")
        for w in r.get("warnings") or []:
            note = (note + "; " + w).strip("; ")
        if r["base_rule"] == "guessed":
            note = ("base guessed; " + note).strip("; ")
        if r.get("srdf"):
            note = ("SRDF %s; " % r["srdf"] + note).strip("; ")
        if r.get("fail_reasons") and not r["pass"]:
            note = (", ".join(r["fail_reasons"]) + ("; " + note if note else ""))
        em = r.get("end_motion")
        if (r["floating"] and r.get("rest") is not None and r.get("asleep") is None
                and em is not None and em >= SLEEP_SPEED):
            note = ("at rest by %g but moving %.1e in the last %g s: awake (sleep_velocity %g)"
                    % (REST_SPEED, em, SLEEP_MARGIN, SLEEP_SPEED) + ("; " + note if note else ""))
        rest = r.get("rest")
        if r.get("E0") is not None and rest is None:
            rest_s = "never"
        else:
            rest_s = fmt(rest, "%.3f")
        asleep_s = "never" if r.get("E0") is not None and r.get("asleep") is None else fmt(r.get("asleep"), "%.3f")
        L.append("| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (
            r["robot"], "float" if r["floating"] else "fixed", r.get("dofs", "–"),
            r["exit"] if r["exit"] is not None else "–",
            {True: "yes", False: "**no**", None: "–"}[r["finite"]],
            fmt(r.get("E0"), "%.4g"), fmt(r.get("rise"), "%.2e"), fmt(r.get("rise_rel"), "%.1e"),
            fmt(r.get("first_contact"), "%.3f"), rest_s, asleep_s,
            fmt(em if r.get("E0") is not None else None, "%.1e"),
            fmt(None if r.get("E0") is None else 1e3 * r["max_pen"], "%.2f"),
            fmt(r.get("steps_per_s"), "%.0f") + (" " + r["integrator"] if r.get("integrator") else ""),
            fmt(r.get("max_base_speed"), "%.2f"),
            fmt(r.get("max_joint_speed") if r.get("E0") is not None else None, "%.3g"),
            "" if r["exit"] is None and r["note"] else ("yes" if r.get("pass") else "**no**"),
            note.replace("|", "\\|")))
    L += ["", "## Worst rows", ""]
    have = [r for r in ran if r.get("E0") is not None]

    def top(title, key, fmt_row, rev=True, n=8):
        rows = sorted((r for r in have if key(r) is not None), key=key, reverse=rev)[:n]
        L.append("- %s: %s" % (title, "; ".join(fmt_row(r) for r in rows) or "none"))

    top("largest energy rise (relative)", lambda r: r["rise_rel"],
        lambda r: "%s %.2e J (%.1e)" % (r["robot"], r["rise"], r["rise_rel"]))
    never = [r["robot"] for r in have if r["floating"] and r["rest"] is None]
    L.append("- floating robots never at rest: %s" % (", ".join(never) or "none"))
    top("slowest to rest", lambda r: r["rest"],
        lambda r: "%s %.3f s" % (r["robot"], r["rest"]))
    top("deepest penetration", lambda r: r["max_pen"],
        lambda r: "%s %.2f mm" % (r["robot"], 1e3 * r["max_pen"]))
    top("lowest steps/s", lambda r: r.get("steps_per_s"),
        lambda r: "%s %.0f (%s)" % (r["robot"], r["steps_per_s"], r.get("integrator")), rev=False)
    failed = [r for r in ran if r["exit"] not in (0, None)]
    L.append("- runs that failed: %s" % ("; ".join(
        "%s (%s)" % (r["robot"], r.get("error", "")) for r in failed) or "none"))
    L += ["", "## Does not load", ""]
    if dead:
        L += ["| URDF | error |", "|---|---|"]
        for r in sorted(dead, key=lambda r: r["robot"]):
            err = r["load_error"]
            for pre in ("urdyn: %s: " % r["path"], "urdyn: "):  # the path is in the first column
                if err.startswith(pre):
                    err = err[len(pre):]
                    break
            L.append("| %s | %s |" % (r["urdf"], err.replace("|", "\\|")))
    else:
        L.append("none")
    with open(path, "w") as fh:
        fh.write("\n".join(L) + "\n")


def clean(x):
    """JSON-safe copy: non-finite floats become null."""
    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if isinstance(x, dict):
        return {k: clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [clean(v) for v in x]
    return x


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("erd", help="example-robot-data folder (holding robots/)")
    ap.add_argument("--urdyn", default=os.path.join(REPO, "target", "release", "urdyn"))
    ap.add_argument("--jobs", type=int, default=2, help="parallel runs (default 2)")
    ap.add_argument("--timeout", type=float, default=300.0, help="seconds per command")
    ap.add_argument("--only", action="append", default=[], help="substring of the URDF path (repeatable)")
    ap.add_argument("--integrator", help="passed to urdyn simulate")
    ap.add_argument("--out", default=os.path.join(REPO, "docs", "robots.md"))
    ap.add_argument("--json", help="dump the raw results here")
    ap.add_argument("--above-ground", type=float, default=0.3, help="drop height of floating robots (m)")
    ap.add_argument("--lift-base", type=float, default=None,
                    help="only for a binary without --above-ground: start floating robots with the base at this z")
    ap.add_argument("--loader", help="a robots_loader.py to take the free_flyer flags from")
    ap.add_argument("--self-collision", action="store_true",
                    help="run each robot as a one-model scene with self-collision (and its SRDF)")
    ap.add_argument("--tmpdir", default=None, help="where the CSVs go while parsed")
    ap.add_argument("--title", default="Robots sweep: example-robot-data through `urdyn simulate`")
    ap.add_argument("--note", help="a paragraph put under the title")
    args = ap.parse_args()

    erd = os.path.abspath(args.erd)
    if os.path.basename(erd) == "robots":
        erd = os.path.dirname(erd)
    elif not os.path.isdir(os.path.join(erd, "robots")) and os.path.isdir(
            os.path.join(erd, "example-robot-data", "robots")):
        erd = os.path.join(erd, "example-robot-data")
    robots = os.path.join(erd, "robots")
    if not os.path.isdir(robots):
        sys.exit("robots_sweep: no robots/ folder under %s" % args.erd)
    args.package_paths = [os.path.dirname(erd), robots]
    if not os.access(args.urdyn, os.X_OK):
        sys.exit("robots_sweep: %s is not an executable (cargo build --release)" % args.urdyn)

    table = loader_table(args.loader) if args.loader else LOADER_FREE_FLYER
    helptext = subprocess.run([args.urdyn, "simulate", "--help"], stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, text=True).stdout
    have_above_ground = "--above-ground" in helptext

    jobs = []
    for dirpath, _, files in os.walk(robots):
        for f in files:
            if not f.endswith(".urdf"):
                continue
            urdf = os.path.join(dirpath, f)
            rel = os.path.relpath(urdf, robots).replace(os.sep, "/")
            if args.only and not any(s in rel for s in args.only):
                continue
            floating, how = decide_floating(rel, table)
            pkg = rel.split("/")[0].replace("_description", "")
            jobs.append({"rel": rel, "urdf": urdf, "floating": floating, "how": how,
                         "name": "%s/%s" % (pkg, f[:-5])})
    jobs.sort(key=lambda j: j["rel"])
    if not jobs:
        sys.exit("robots_sweep: no URDF matched")

    started = datetime.datetime.now(datetime.timezone.utc)
    results = []
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, args.jobs)) as ex:
        futs = {ex.submit(sweep_one, j, args, have_above_ground): j for j in jobs}
        for fut in concurrent.futures.as_completed(futs):
            j = futs[fut]
            try:
                r = fut.result()
            except Exception as e:  # a bug here must not lose the other rows
                r = {"robot": j["name"], "urdf": j["rel"], "floating": j["floating"],
                     "base_rule": j["how"], "loads": True, "load_error": None, "exit": None,
                     "finite": None, "note": "sweep error: %r" % e}
            results.append(r)
            status = ("does not load" if not r["loads"] else r["note"] or
                      ("pass" if r.get("pass") else "FAIL " + ",".join(r.get("fail_reasons", []))))
            print("[%d/%d] %s: %s" % (len(results), len(jobs), r["robot"], status), file=sys.stderr)
    done = datetime.datetime.now(datetime.timezone.utc)

    try:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=REPO, text=True,
                                stdout=subprocess.PIPE, stderr=subprocess.DEVNULL).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=REPO,
                               text=True, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL).stdout.strip()
        if dirty:
            commit += " (with uncommitted changes)"
    except OSError:
        commit = "unknown"
    cpu = ""
    try:
        with open("/proc/cpuinfo") as fh:
            cpu = next((ln.split(":", 1)[1].strip() for ln in fh if ln.startswith("model name")), "")
    except OSError:
        pass
    argv = ["python3", os.path.relpath(os.path.abspath(__file__), REPO)] + sys.argv[1:]
    shown = list(argv)  # the command line of the header, with --note's text left out
    for i, a in enumerate(shown):
        if a == "--note" and i + 1 < len(shown):
            shown[i + 1] = "..."
        elif a.startswith("--note="):
            shown[i] = "--note=..."
    n_load = sum(r["loads"] for r in results)
    ran = [r for r in results if r["loads"] and r["exit"] is not None]
    header = [
        "# " + args.title, "",
    ] + ([args.note, ""] if args.note else []) + [
        "Made by `%s` (`benches/robots_sweep.py`; its docstring defines every column and the "
        "acceptance) on %s (%.0f s wall), urdyn commit %s, %s cores%s, %d parallel runs." % (
            " ".join(shlex.quote(a) for a in shown), started.strftime("%Y-%m-%d %H:%M UTC"),
            (done - started).total_seconds(), commit, os.cpu_count(),
            " (%s)" % cpu if cpu else "", args.jobs),
        "",
        "Floating robots: `--floating-base --duration 5` %s; fixed robots: `--no-ground --duration 3`; "
        "start at joint 0 or mid-limits where 0 is outside them; integrator: %s." % (
            "`--above-ground %g`" % args.above_ground if have_above_ground else
            ("no `--above-ground` (this binary lacks it): base started at z = %g m" % args.lift_base
             if args.lift_base is not None else "not run (this binary lacks `--above-ground`)"),
            args.integrator or "urdyn's default"),
        "",
        "%d URDFs, %d load, %d simulated, %d pass. Rest threshold %g m/s (base) or per joint; "
        "pass = exit 0, finite, energy rise <= 1e-3·|E0| + 1e-3 J%s." % (
            len(results), n_load, len(ran), sum(1 for r in ran if r.get("pass")), REST_SPEED,
            ", and for floating robots that touch the ground: first contact within %g s of %.3f s "
            "and at rest by the end, and asleep by the end when every velocity coordinate is below %g "
            "(the default sleep_velocity) from %g s before it" % (
                CONTACT_TOL, math.sqrt(2 * args.above_ground / G), SLEEP_SPEED, SLEEP_MARGIN)
            if have_above_ground else
            ", and for floating robots that touch the ground: at rest by the end (no contact-time "
            "check without `--above-ground`)"),
        "",
        "Columns: energy rise = max over rows of E(t) − E(0); rise rel. = rise / max(|E0|, 1 J); "
        "first contact = first row with contacts > 0; rest = first t after which the base speed "
        "(floating) or every joint speed (fixed) stays below %g; asleep = first t after which the "
        "`awake` column stays 0 (every model asleep); end motion = the largest |velocity coordinate| "
        "in the last %g s; max pen. = deepest penetration; "
        "steps/s = steps / wall seconds of urdyn's summary line (an adaptive integrator takes fewer, "
        "longer steps: compare within one integrator); max joint v in rad/s or m/s. A failed run leaves no "
        "CSV (urdyn writes it atomically), hence the dashes." % (REST_SPEED, SLEEP_MARGIN),
    ]
    if args.out:
        os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
        write_md(args.out, results, header)
        print("wrote %s" % args.out, file=sys.stderr)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"argv": argv, "started": started.isoformat(), "commit": commit,
                       "cores": os.cpu_count(), "above_ground_supported": have_above_ground,
                       "results": clean(sorted(results, key=lambda r: r["robot"]))}, fh, indent=1)
        print("wrote %s" % args.json, file=sys.stderr)


if __name__ == "__main__":
    main()
