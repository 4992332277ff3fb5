#!/usr/bin/env python3
"""urdyn against MuJoCo on MuJoCo's own models (issue 29, "Must show", 2nd bullet).

Usage:
    python benches/mjcf_compare.py [--urdyn target/release/urdyn] [--models NAME,...]
        [--repeats 3] [--duration 3] [--no-dynamics] [--pinocchio PATH]
        [--md benches/mjcf_results.md] [--json benches/mjcf_results.json] [--base OTHER_URDYN]

--base: an A/B of two urdyn binaries: OTHER_URDYN is timed in the same rounds as --urdyn
(just before it in each round), and the markdown gets a table of both beside MuJoCo.

The models are the committed, unmodified copies in tests/fixtures/mjcf (Gymnasium 1.4.0's
envs/mujoco/assets, dm_control 1.0.50's suite; names below are DIR/STEM).

Simulation (each model, identical in both engines)
--------------------------------------------------
The file as it is: dt = the file's <option timestep>, its gravity, its ground planes, its
contact filter; zero controls; the start is the default pose qpos0 with zero velocity (the
bodies are dropped from where the file puts them); --duration (3 s) of simulated time.

urdyn: `urdyn simulate MODEL.xml --no-sleep --integrator euler --duration T --every 1000000000
--out CSV` (its
default integrator with contact, named so that a model without contact also steps at the
file's dt instead of taking dop853's adaptive steps: velocity-level rigid contact with exact
Coulomb friction). steps/s =
steps / wall seconds of the stepping loop (no parsing, no process start), from the summary
line urdyn prints on stderr: its real-time factor × steps / duration (4 significant digits,
where the printed wall time has 0.1 ms steps). The timed runs write only the final state
(--every larger than the run: no per-step energy, CSV formatting or writer thread), as
MuJoCo's timed loop records nothing; the metrics below come from one extra untimed urdyn
run with --every 1 (its steps/s, recording every step, is kept in the JSON as
urdyn_record_sps).

MuJoCo 4.0: mujoco.MjModel.from_xml_path on the same file, sleeping off (mjENBL_SLEEP
cleared: every body awake), ctrl = 0, mj_resetData (qpos0); once with mjINT_EULER and once
with mjINT_IMPLICITFAST (whatever the file's <option integrator> says); perf_counter around a
Python loop of mj_step in this process; the faster one is the table's. Everything else is the
file's (soft contact with its solref/solimp, its solver and cone).

Metrics (urdyn: from its CSV, every step; MuJoCo: an extra untimed run with the faster
integrator, recording every step):
- lands: time of the first state with a contact ("–" when none in the run: the model
  never touches anything, e.g. a swimmer in a plane-free world);
- finite: every q and v finite to the end;
- end |v|max: the largest |v| component at the end (m/s or rad/s; urdyn's free-joint
  velocity is in the body frame, MuJoCo's linear part in the world frame: same magnitude
  per component set only when summed, so this is an indicator); "rest" when < 0.05;
- max pen.: deepest penetration over the run in mm (urdyn: max of the CSV's `penetration`;
  MuJoCo: max over contacts of -dist after each step).

Timing: --repeats rounds (default 5); a round runs urdyn, then MuJoCo Euler, then MuJoCo
implicitfast, back to back; the table gives each engine's best steps/s over the rounds (the
machine is shared: the best round is the least disturbed one, for both engines alike; the
JSON keeps every round). Ratio = urdyn /
MuJoCo (> 1: urdyn faster).

Dynamics alone (unless --no-dynamics): `urdyn bench MODEL.xml --algo rnea --algo aba --json`
against Pinocchio 4.1.0 C++ (`/work/shared/tools/pinocchio-bench/run MODEL.xml --algo rnea
--algo aba --json`, pinocchio::mjcf::buildModel; it composes a body's several joints into
one composite joint) on Gymnasium's ant, humanoid, half_cheetah, hopper and walker2d, back to
back: median ns per call, ratio = urdyn / Pinocchio (< 1: urdyn faster; target <= 0.5).
"""
import argparse
import csv
import datetime
import json
import math
import os
import platform
import re
import subprocess
import sys
import tempfile
import time

import numpy as np
import mujoco

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FIX = os.path.join(REPO, "tests", "fixtures", "mjcf")
MODELS = [
    "gymnasium/humanoid", "gymnasium/ant", "dm_control/quadruped", "dm_control/humanoid_CMU",
    "gymnasium/humanoidstandup", "gymnasium/half_cheetah", "gymnasium/hopper",
    "gymnasium/walker2d", "gymnasium/walker2d_v5", "gymnasium/swimmer",
    "dm_control/humanoid", "dm_control/cheetah", "dm_control/walker", "dm_control/hopper",
    "dm_control/swimmer", "dm_control/fish", "dm_control/ball_in_cup", "dm_control/finger",
    "dm_control/point_mass", "dm_control/stacker", "dm_control/dog",
]
TWO_X = {"gymnasium/humanoid", "gymnasium/ant", "dm_control/quadruped", "dm_control/humanoid_CMU"}
DYN_MODELS = ["gymnasium/ant", "gymnasium/humanoid", "gymnasium/half_cheetah",
              "gymnasium/hopper", "gymnasium/walker2d"]
PINOCCHIO = "/work/shared/tools/pinocchio-bench/run"
REST = 0.05
NOTES = (
    "`perf record --call-graph dwarf` on 15 runs of `urdyn simulate MODEL.xml --no-sleep "
    "--integrator euler --duration 3 --every 1000000000` (2026-12-03, share of the stepping "
    "loop, children included): Gymnasium's humanoid: the constraint solve 45 % (PGS sweeps "
    "32 %, 17 % self; the subspace step 10 %), the free velocity 22 % (CRBA 10 %, the mass "
    "factor 5 %, bias 7 %), pair contact detection 15 % (parry's manifolds 9 %), solver row "
    "forming 14 %, island grouping 4 %. humanoid_CMU (nv 62, self time): LTDL 18 %, PGS 11 %, "
    "row forming 9 %, CRBA 7 %, assembly 5 %, LTDL solves 4 %, subspace step 3 %, bias 3 %, "
    "pairs 3 %. No MJCF-specific code (importer, actuators as servos, tendons) appears in the "
    "step: the cost is in the solver (src/sim/solver: PGS, subspace, forming), the contact "
    "pipeline (src/contact) and the mass factor (src/dynamics/ltdl.rs, src/sim/factor.rs). "
    "Recording every step (--every 1: energy per step, CSV formatting on a writer thread "
    "sharing the 2 cores) cost humanoid and humanoid_CMU 18 %, ant 10 %, dm_control's "
    "swimmer 63 % of the stepping loop's rate, which the timed runs now leave out (MuJoCo's "
    "timed loop records nothing either). The timings move by up to 2x between runs on this "
    "shared machine.")
ABA_NOTES = (
    "urdyn gives each MJCF joint its own body (a body's several joints become a chain of "
    "massless bodies, each about its own anchor, exactly MuJoCo's composition), so ABA does "
    "one articulated-inertia step per joint; Pinocchio composes a body's joints into one "
    "composite joint and does one step per MJCF body. Bodies in the two passes (urdyn / "
    "Pinocchio): ant 9 / 9 (no body with several joints), half_cheetah 9 / 7, walker2d 9 / 7, "
    "hopper 6 / 4, humanoid 18 / 11: the models with the largest share of their degrees of "
    "freedom in multi-joint bodies (hopper: 3 of 6, its root slide-slide-hinge; humanoid: "
    "12 of 23) have urdyn's worst aba ratios. Armature is not the cause: urdyn's `aba` "
    "pass has no armature term (eval and the simulation factor H + A where a model has "
    "armature), Pinocchio's adds it to each joint's scalar D at no extra cost. A composite "
    "joint in urdyn's ABA (src/dynamics/aba*, another room) would remove the massless "
    "bodies' steps.")
SUMMARY = re.compile(r"urdyn simulate: (\d+) steps \((\w+)\) in ([0-9.eE+-]+) s wall, "
                     r"real-time factor ([0-9.eE+-]+)")


def path_of(name):
    return os.path.join(FIX, name + ".xml")


# ---------------------------------------------------------------------------- MuJoCo

def load_mujoco(name):
    m = mujoco.MjModel.from_xml_path(path_of(name))
    m.opt.enableflags &= ~int(mujoco.mjtEnableBit.mjENBL_SLEEP)
    return m


def fresh(m, integ):
    m.opt.integrator = int(integ)
    d = mujoco.MjData(m)
    mujoco.mj_resetData(m, d)
    d.ctrl[:] = 0.0
    return d


def time_mujoco(m, integ, steps):
    d = fresh(m, integ)
    step = mujoco.mj_step
    t0 = time.perf_counter()
    for _ in range(steps):
        step(m, d)
    return steps / (time.perf_counter() - t0)


def mujoco_metrics(m, integ, steps):
    d = fresh(m, integ)
    first, pen = None, 0.0
    for _ in range(steps):
        mujoco.mj_step(m, d)
        if d.ncon:
            if first is None:
                first = d.time - m.opt.timestep
            pen = max(pen, max(-float(d.contact[i].dist) for i in range(d.ncon)))
    finite = bool(np.all(np.isfinite(d.qpos)) and np.all(np.isfinite(d.qvel)))
    vmax = float(np.max(np.abs(d.qvel))) if m.nv else 0.0
    return {"lands": first, "finite": finite, "vmax_end": vmax, "max_pen": pen}


# ---------------------------------------------------------------------------- urdyn

def run_urdyn(urdyn, name, duration, out, record=False):
    # timed rounds write the final state only (--every larger than the run), as
    # MuJoCo's timed loop records nothing; the metrics come from one extra
    # untimed run that writes every step (record=True), as MuJoCo's do
    every = "1" if record else str(10**9)
    cmd = [urdyn, "simulate", path_of(name), "--no-sleep", "--integrator", "euler",
           "--duration", str(duration), "--every", every, "--out", out]
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    lines = [ln.strip() for ln in p.stderr.splitlines() if ln.strip()]
    summ = [ln for ln in lines if SUMMARY.search(ln)]
    res = {"exit": p.returncode, "warnings": [ln for ln in lines if ln not in summ],
           "command": " ".join(os.path.relpath(c, REPO) if os.path.isabs(c) else c for c in cmd)}
    if summ:
        mt = SUMMARY.search(summ[-1])
        res.update(steps=int(mt.group(1)), integrator=mt.group(2), wall=float(mt.group(3)))
        # the real-time factor (4 significant digits) is finer than the wall time
        # (0.1 ms steps on runs of a few ms): steps/s = factor · steps / duration
        res["steps_per_s"] = float(mt.group(4)) * res["steps"] / duration
    return res


def urdyn_metrics(csv_path):
    with open(csv_path, newline="") as fh:
        rd = csv.reader(fh)
        head = next(rd)
        col = {h: i for i, h in enumerate(head)}
        iv = [i for h, i in col.items() if h.startswith("v:")]
        iqv = [i for h, i in col.items() if h.startswith("q:") or h.startswith("v:")]
        ic, ip, it = col["contacts"], col["penetration"], col["t"]
        first, pen, last = None, 0.0, None
        for row in rd:
            if first is None and int(float(row[ic])) > 0:
                first = float(row[it])
            pen = max(pen, float(row[ip]))
            last = row
    finite = all(math.isfinite(float(last[i])) for i in iqv)
    vmax = max((abs(float(last[i])) for i in iv), default=0.0)
    return {"lands": first, "finite": finite, "vmax_end": vmax, "max_pen": pen}


# ---------------------------------------------------------------------------- dynamics

def bench_json(cmd):
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if p.returncode != 0:
        raise RuntimeError((p.stderr.strip().splitlines() or ["exit %d" % p.returncode])[-1])
    js = json.loads(p.stdout.strip().splitlines()[-1])
    res = js.get("results", js)
    return {a: float(res[a]["median_ns"]) for a in ("rnea", "aba") if a in res}, js


def dynamics(urdyn, pinocchio, names):
    rows = []
    for name in names:
        r = {"model": name}
        try:
            r["urdyn"], js = bench_json([urdyn, "bench", path_of(name), "--algo", "rnea",
                                         "--algo", "aba", "--json"])
            r["nv"] = js.get("nv")
        except (RuntimeError, ValueError) as e:
            r["urdyn_error"] = str(e)
        try:
            r["pinocchio"], _ = bench_json([pinocchio, path_of(name), "--algo", "rnea", "--algo",
                                            "aba", "--json"])
        except (RuntimeError, ValueError, OSError) as e:
            r["pinocchio_error"] = str(e)
        print("dynamics %s: %s" % (name, r), file=sys.stderr)
        rows.append(r)
    return rows


# ---------------------------------------------------------------------------- table

def fmt_t(x):
    return "–" if x is None else "%.3f s" % x


def fmt_end(m):
    if not m["finite"]:
        return "NOT finite"
    return "rest (%.1e)" % m["vmax_end"] if m["vmax_end"] < REST else "moving (%.2g)" % m["vmax_end"]


def write_md(path, rows, dyn, meta):
    L = ["# urdyn and MuJoCo on MuJoCo's own models", "",
         "Made by `%s` on %s (%.0f s wall): urdyn commit %s, MuJoCo %s, %s; machine load "
         "average at the start %s (2 cores shared with other jobs: compare the ratios, "
         "measured back to back, not absolute rates). benches/mjcf_compare.py's docstring "
         "defines every column." % (meta["command"], meta["date"], meta["wall_s"], meta["commit"],
                                    meta["mujoco"], meta["machine"], meta["load"]), "",
         "Each model as its file defines it (dt = its timestep, its gravity, planes and contact "
         "filter), zero controls, dropped from the default pose qpos0, %g s. urdyn `simulate "
         "--no-sleep` (euler, rigid contact), timed without per-step recording (final state "
         "only; the metrics from an extra untimed run writing every step); MuJoCo with every "
         "body awake, the faster of Euler and implicitfast, timed in process. steps/s: best of %d rounds. Ratio = urdyn / "
         "MuJoCo (target: ≥ 2 on the four marked *, ≥ 1 elsewhere). lands: first contact; "
         "end: largest |v| component at the end (rest: < %g); pen.: deepest penetration over "
         "the run." % (meta["duration"], meta["repeats"], REST), "",
         "| model | nv | dt | urdyn steps/s | MuJoCo steps/s (integrator) | ratio | lands urdyn / MuJoCo "
         "| end urdyn / MuJoCo | max pen. urdyn / MuJoCo (mm) |",
         "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        star = " *" if r["model"] in TWO_X else ""
        if "error" in r:
            L.append("| %s%s | | | %s | | | | | |" % (r["model"], star, r["error"]))
            continue
        u, mj = r["urdyn_metrics"], r["mujoco_metrics"]
        L.append("| %s%s | %d | %g | %.0f | %.0f (%s) | **%.2f** | %s / %s | %s / %s | %.3f / %.3f |" % (
            r["model"], star, r["nv"], r["dt"], r["urdyn_sps"], r["mujoco_sps"], r["mujoco_integrator"],
            r["ratio"], fmt_t(u["lands"]), fmt_t(mj["lands"]), fmt_end(u), fmt_end(mj),
            1e3 * u["max_pen"], 1e3 * mj["max_pen"]))
    ab = [r for r in rows if "base_sps" in r]
    if ab:
        L += ["", "A/B: `%s` (base) timed in the same rounds, just before `--urdyn`:" % meta["base"], "",
              "| model | base steps/s (ratio) | this steps/s (ratio) | max pen. base / this (mm) "
              "| end base / this |", "|---|---|---|---|---|"]
        for r in ab:
            bm = r.get("base_metrics", {})
            L.append("| %s | %.0f (%.2f) | %.0f (%.2f) | %s / %.3f | %s / %s |" % (
                r["model"], r["base_sps"], r["base_ratio"], r["urdyn_sps"], r["ratio"],
                "%.3f" % (1e3 * bm["max_pen"]) if bm else "–", 1e3 * r["urdyn_metrics"]["max_pen"],
                fmt_end(bm) if bm else "–", fmt_end(r["urdyn_metrics"])))
    warn = [(r["model"], w) for r in rows for w in r.get("urdyn_warnings", [])]
    if warn:
        L += ["", "urdyn's warnings (import report and start state):", ""]
        L += ["- %s: %s" % (m, w.split(": ", 1)[-1]) for m, w in warn]
    if dyn:
        L += ["", "## Dynamics alone", "",
              "`urdyn bench MODEL.xml --algo rnea --algo aba` against Pinocchio 4.1.0 C++ "
              "(`pinocchio-bench/run MODEL.xml`, -march=native), back to back, median ns per call "
              "on random states; ratio = urdyn / Pinocchio (target ≤ 0.5).", "",
              "| model | nv | rnea urdyn / Pinocchio (ns) | ratio | aba urdyn / Pinocchio (ns) | ratio |",
              "|---|---|---|---|---|---|"]
        for r in dyn:
            if "urdyn" not in r or "pinocchio" not in r:
                L.append("| %s | | %s | | | |" % (r["model"], r.get("urdyn_error") or r.get("pinocchio_error")))
                continue
            u, p = r["urdyn"], r["pinocchio"]
            L.append("| %s | %s | %.0f / %.0f | **%.2f** | %.0f / %.0f | **%.2f** |" % (
                r["model"], r.get("nv", ""), u["rnea"], p["rnea"], u["rnea"] / p["rnea"],
                u["aba"], p["aba"], u["aba"] / p["aba"]))
    L += ["", "## Where urdyn's time goes (perf, 2026-12-03)", "", NOTES]
    if dyn:
        L += ["", "## Why aba is nearer 0.5 on some MJCF models", "", ABA_NOTES]
    with open(path, "w") as fh:
        fh.write("\n".join(L) + "\n")


def machine():
    cpu = "unknown CPU"
    try:
        with open("/proc/cpuinfo") as fh:
            cpu = next((ln.split(":", 1)[1].strip() for ln in fh if ln.startswith("model name")), cpu)
    except OSError:
        pass
    return "%s, %d cores, Python %s" % (cpu, os.cpu_count(), platform.python_version())


def commit():
    p = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=REPO, text=True,
                       stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
    return p.stdout.strip() or "unknown"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--urdyn", default=os.path.join(REPO, "target", "release", "urdyn"))
    ap.add_argument("--models", action="append")
    # A/B: another urdyn binary timed in the same rounds (its run first in each
    # round, then --urdyn's, then MuJoCo's two), reported beside --urdyn's
    ap.add_argument("--base")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--duration", type=float, default=3.0)
    ap.add_argument("--no-dynamics", action="store_true")
    ap.add_argument("--pinocchio", default=PINOCCHIO)
    ap.add_argument("--md", default=os.path.join(REPO, "benches", "mjcf_results.md"))
    ap.add_argument("--json", default=os.path.join(REPO, "benches", "mjcf_results.json"))
    args = ap.parse_args()
    names = [n for a in args.models for n in a.split(",") if n] if args.models else MODELS
    started = time.time()
    load = os.getloadavg()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            r = {"model": name}
            try:
                m = load_mujoco(name)
            except Exception as e:  # MuJoCo refuses the file: a row with its message
                r["error"] = "MuJoCo: %s" % str(e).splitlines()[0]
                rows.append(r)
                continue
            dt = float(m.opt.timestep)
            steps = int(round(args.duration / dt))
            r.update(nv=int(m.nv), dt=dt, steps=steps)
            csvp = os.path.join(tmp, name.replace("/", "_") + ".csv")
            us, bs, mjs = [], [], {"EULER": [], "IMPLICITFAST": []}
            for _ in range(args.repeats):
                if args.base:
                    b = run_urdyn(args.base, name, args.duration, csvp)
                    if b.get("steps_per_s"):
                        bs.append(b["steps_per_s"])
                u = run_urdyn(args.urdyn, name, args.duration, csvp)
                if u["exit"] != 0 or not u.get("steps_per_s"):
                    r["error"] = "urdyn: %s" % ((u["warnings"] or ["exit %d" % u["exit"]])[-1])
                    break
                us.append(u["steps_per_s"])
                for integ in mjs:
                    mjs[integ].append(time_mujoco(m, getattr(mujoco.mjtIntegrator, "mjINT_" + integ), steps))
            if "error" in r:
                rows.append(r)
                print("%s: %s" % (name, r["error"]), file=sys.stderr)
                continue
            med = {k: max(v) for k, v in mjs.items()}
            best = max(med, key=med.get)
            r.update(urdyn_sps=max(us), urdyn_all=us, mujoco_all=mjs,
                     mujoco_sps=med[best], mujoco_integrator=best.lower(),
                     urdyn_command=u["command"], urdyn_warnings=u["warnings"])
            r["ratio"] = r["urdyn_sps"] / r["mujoco_sps"]
            if bs:
                r.update(base_sps=max(bs), base_all=bs, base_ratio=max(bs) / r["mujoco_sps"])
                brec = run_urdyn(args.base, name, args.duration, csvp, record=True)
                if brec["exit"] == 0:
                    r["base_metrics"] = urdyn_metrics(csvp)
            rec = run_urdyn(args.urdyn, name, args.duration, csvp, record=True)
            r["urdyn_record_sps"] = rec.get("steps_per_s")
            r["urdyn_metrics"] = urdyn_metrics(csvp)
            r["mujoco_metrics"] = mujoco_metrics(m, getattr(mujoco.mjtIntegrator, "mjINT_" + best), steps)
            print("%s: urdyn %.0f, MuJoCo %.0f (%s), ratio %.2f%s; urdyn %s, MuJoCo %s" % (
                name, r["urdyn_sps"], r["mujoco_sps"], best, r["ratio"],
                " (base %.0f, %.2f)" % (r["base_sps"], r["base_ratio"]) if bs else "",
                r["urdyn_metrics"], r["mujoco_metrics"]), file=sys.stderr)
            rows.append(r)
    dyn = [] if args.no_dynamics else dynamics(args.urdyn, args.pinocchio, DYN_MODELS)
    meta = {"command": "python benches/mjcf_compare.py " + " ".join(sys.argv[1:]),
            "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
            "wall_s": time.time() - started, "commit": commit(), "mujoco": mujoco.__version__,
            "machine": machine(), "load": "%.1f" % load[0], "duration": args.duration,
            "repeats": args.repeats, "base": args.base}
    write_md(args.md, rows, dyn, meta)
    with open(args.json, "w") as fh:
        json.dump({"meta": meta, "simulation": rows, "dynamics": dyn}, fh, indent=1)
    print("wrote %s and %s" % (args.md, args.json), file=sys.stderr)


if __name__ == "__main__":
    main()
