#!/usr/bin/env python3
"""Piles dropped into a bin (benches/pile_gen.py) in urdyn and in MuJoCo 4.0, in one run: steps/s.

Usage:
    /work/venv/bin/python benches/pile_compare.py --urdyn BIN [--kinds boxes,mixed]
        [--sizes 16,64,256,1024] [--duration 4] [--duration-1024 2] [--md benches/pile_results.md]
        [--settled 256] [--repeats 3] [--threads 2]

Each scene (benches/scenes/pile_KIND_N.json) is run
- by urdyn: `urdyn simulate --scene FILE --duration T --dt 0.001 --every 1000000000 --out /dev/null`
  with sleep (the default) and with `--no-sleep`; steps/s from its summary line (the stepping loop
  only; --every larger than the run: no CSV row formatted per step, as MuJoCo's loop records
  nothing; the summary's mean awake count is over every step all the same);
- by MuJoCo 4.0: the same file built with mujoco.MjSpec exactly as benches/scene_compare.py builds
  its scenes (build_mujoco), dt 1 ms, islands on (MuJoCo's default), for each of Euler and
  implicitfast with sleep off and on (mjENBL_SLEEP); perf_counter around a Python loop of mj_step.
The ratio is urdyn's faster run (sleep on, its default) over MuJoCo's fastest of the four.
--threads N adds urdyn with `--threads N` (sleep on) as a column of its own and its ratio beside
the headline's, which stays one thread's (MuJoCo's `mj_step` runs on one thread by default). That
ratio is against the faster of MuJoCo's one-thread best and its best with its own thread pool of N
workers (`mujoco.mju_threadpool(d, N)`: collision and the islands' solve in parallel), the four
configurations again.
--elliptic adds MuJoCo's four configurations with its elliptic friction cone (`opt.cone =
mjCONE_ELLIPTIC`: Coulomb's disc, the friction law urdyn solves; MuJoCo's default, used above, is a
pyramid, which ends a box's 3D wobble sooner: round 34's rock room, benches/rocking.py), its best
and urdyn's ratio to it as columns of their own; the headline ratio is unchanged.
Growth: the step time ratio from 64 to 1024 objects (≤ 16: no faster than linear); beside it
the same ratio per awake object (step time over the run's mean awake count), and the ratio at equal
durations (the 64 pile run again over the 1024 pile's 2 s, both engines; --no-equal-growth skips it).

--settled N: the N-box pile's steps/s falling against settled, urdyn with sleep on, by
`examples/pile_settled.rs` (500 steps from the drop, and 2000 steps from the state the run reaches
at 4 s, each timed in one process from a clone of the simulation: built first with
`cargo build --release --features tools --example pile_settled`, or given by --pile-settled BIN).
Without that binary, the difference of a 4.5 s and a 4 s CLI run (a bound once an all-asleep step
costs less than the timer resolves).
"""
import argparse
import datetime
import os
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from scene_compare import resolve_scene, build_mujoco, run_urdyn, find_share, uptime  # noqa: E402
from sim_compare import machine, commit  # noqa: E402

import mujoco  # noqa: E402

INTEG = {"euler": mujoco.mjtIntegrator.mjINT_EULER,
         "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST}


def time_mj(model, qpos, qvel, integ, sleep, steps, pool=0, cone=None):
    model.opt.integrator = INTEG[integ]
    # the friction cone: MuJoCo's default pyramid, or (--elliptic) the elliptic cone, Coulomb's
    # disc as urdyn solves it
    model.opt.cone = cone if cone is not None else mujoco.mjtCone.mjCONE_PYRAMIDAL
    if sleep:
        model.opt.enableflags |= int(mujoco.mjtEnableBit.mjENBL_SLEEP)
    else:
        model.opt.enableflags &= ~int(mujoco.mjtEnableBit.mjENBL_SLEEP)
    d = mujoco.MjData(model)
    if pool:
        # MuJoCo's own thread pool: collision and the islands' solve on `pool` worker threads
        mujoco.mju_threadpool(d, pool)
    d.qpos[:], d.qvel[:] = qpos, qvel
    mujoco.mj_forward(model, d)
    step = mujoco.mj_step
    t0 = time.perf_counter()
    for _ in range(steps):
        step(model, d)
    return steps / (time.perf_counter() - t0)


def urdyn(args, path, dur, extra=()):
    # --every larger than the run: the final state only, no per-step CSV formatting (MuJoCo's
    # timed loop records nothing); the summary's mean awake count covers every step
    cmd = [args.urdyn, "simulate", "--scene", path, "--duration", repr(dur), "--dt", "0.001",
           "--every", str(10**9), "--out", os.devnull] + list(extra)
    r = run_urdyn(cmd)
    if r.get("exit") != 0 or "steps_per_s" not in r:
        raise RuntimeError("urdyn failed: %s: %s" % (" ".join(cmd), r.get("stderr_other")))
    return r


def one(args, kind, n, tmp):
    sc, path = resolve_scene(os.path.join(HERE, "scenes", "pile_%s_%d.json" % (kind, n)), "", tmp)
    dur = args.duration_1024 if n >= 1024 else args.duration
    steps = int(round(dur / 0.001))
    row = {"kind": kind, "n": n, "duration": dur}
    # best of --repeats runs each (machines are shared: a single short run can lose half its speed)
    runs = [urdyn(args, path, dur) for _ in range(args.repeats)]
    ur = max(runs, key=lambda r: r["steps_per_s"])
    row["urdyn_sleep"] = ur["steps_per_s"]
    row["urdyn_awake_mean"] = ur["summary"].rsplit("mean awake", 1)[-1].strip() if "mean awake" in ur["summary"] else ""
    row["urdyn_nosleep"] = max(urdyn(args, path, dur, ["--no-sleep"])["steps_per_s"]
                               for _ in range(args.repeats)) if not args.no_nosleep else None
    if args.threads:
        row["urdyn_threads"] = max(urdyn(args, path, dur, ["--threads", str(args.threads)])["steps_per_s"]
                                   for _ in range(args.repeats))
    model, qpos, qvel, _ = build_mujoco(sc, [], 0.001)
    mj = {}
    for integ in INTEG:
        for sleep in (False, True):
            mj["%s%s" % (integ, "+sleep" if sleep else "")] = max(
                time_mj(model, qpos, qvel, integ, sleep, steps) for _ in range(args.repeats))
    row["mujoco"] = mj
    best = max(mj, key=mj.get)
    row["mujoco_best"], row["mujoco_best_cfg"] = mj[best], best
    row["ratio"] = max(row["urdyn_sleep"], row["urdyn_nosleep"] or 0) / mj[best]
    if args.elliptic:
        # like for like in the friction law: MuJoCo with the elliptic cone (Coulomb's disc, as urdyn's
        # solve); the ratio stays against MuJoCo's fastest (its default pyramid)
        ell = {}
        for integ in INTEG:
            for sleep in (False, True):
                ell["%s%s" % (integ, "+sleep" if sleep else "")] = max(
                    time_mj(model, qpos, qvel, integ, sleep, steps, cone=mujoco.mjtCone.mjCONE_ELLIPTIC)
                    for _ in range(args.repeats))
        row["mujoco_elliptic"] = ell
        ebest = max(ell, key=ell.get)
        row["mujoco_elliptic_best"], row["mujoco_elliptic_best_cfg"] = ell[ebest], ebest
        row["ratio_elliptic"] = max(row["urdyn_sleep"], row["urdyn_nosleep"] or 0) / ell[ebest]
    if args.threads:
        # against MuJoCo's fastest on one thread or with its own pool of the same size
        pool = {}
        for integ in INTEG:
            for sleep in (False, True):
                pool["%s%s" % (integ, "+sleep" if sleep else "")] = max(
                    time_mj(model, qpos, qvel, integ, sleep, steps, args.threads) for _ in range(args.repeats))
        row["mujoco_pool"] = pool
        pbest = max(pool, key=pool.get)
        row["mujoco_pool_best"], row["mujoco_pool_best_cfg"] = pool[pbest], pbest
        row["ratio_threads"] = row["urdyn_threads"] / max(mj[best], pool[pbest])
    if n == 64 and args.equal_growth and args.duration_1024 != dur:
        # the 64 pile again over the 1024 pile's duration: growth at equal durations (a 4 s run of
        # a small pile is mostly asleep or resting, a 2 s run of the large one mostly falling)
        d2, s2 = args.duration_1024, int(round(args.duration_1024 / 0.001))
        row["equal"] = {
            "duration": d2,
            "urdyn_sleep": max(urdyn(args, path, d2)["steps_per_s"] for _ in range(args.repeats)),
            "urdyn_nosleep": max(urdyn(args, path, d2, ["--no-sleep"])["steps_per_s"]
                                 for _ in range(args.repeats)),
            "mujoco_best": max(max(time_mj(model, qpos, qvel, integ, sleep, s2) for _ in range(args.repeats))
                               for integ in INTEG for sleep in (False, True))}
    print("%s %d: urdyn %.0f (no sleep %s%s), MuJoCo %.0f (%s), ratio %.2f" % (
        kind, n, row["urdyn_sleep"], row["urdyn_nosleep"] and "%.0f" % row["urdyn_nosleep"],
        ", threads %d %.0f" % (args.threads, row["urdyn_threads"]) if args.threads else "",
        mj[best], best, row["ratio"]), file=sys.stderr, flush=True)
    return row


def settled(args, n, tmp):
    """Falling against settled steps/s of urdyn's N-box pile, sleep on."""
    exe = args.pile_settled or os.path.join(os.path.dirname(HERE), "target", "release", "examples",
                                            "pile_settled")
    if os.path.isfile(exe):
        # "pile_boxes_N: falling (...) F steps/s; settled (...) S steps/s; ratio R"
        out = subprocess.run([exe, str(n), "4"], capture_output=True, text=True, timeout=600)
        if out.returncode != 0:
            raise RuntimeError("%s failed: %s" % (exe, out.stderr.strip()))
        parts = out.stdout.split(";")
        falling = float(parts[0].split()[-2])
        settled_sps = float(parts[1].split()[-2])
        return {"n": n, "falling": falling, "settled": settled_sps,
                "ratio": settled_sps / falling, "bound": False, "how": "examples/pile_settled"}
    _, path = resolve_scene(os.path.join(HERE, "scenes", "pile_boxes_%d.json" % n), "", tmp)
    a = urdyn(args, path, 0.5)
    b = urdyn(args, path, 4.0)
    c = urdyn(args, path, 4.5)
    falling = a["steps_per_s"]
    # two runs' difference: below 0.1 ms it is the timer's noise, not the 500 settled steps
    # (an all-asleep step only advances time): then a bound
    diff = c["wall"] - b["wall"]
    settled_sps = 500 / max(diff, 1e-4)
    return {"n": n, "falling": falling, "settled": settled_sps, "ratio": settled_sps / falling,
            "bound": diff < 1e-4, "how": "4.5 s run minus 4 s run"}


def write_md(path, rows, meta, st, threads=0, elliptic=False):
    el_head = " MuJoCo elliptic (best) | ratio (elliptic) |" if elliptic else ""
    th_head = " urdyn --threads %d |" % threads if threads else ""
    th_ratio = (" MuJoCo pool %d (best) | ratio (threads %d) |" % (threads, threads)) if threads else ""
    out = ["# Piles in a bin: urdyn and MuJoCo 4.0.0", "",
           "Made by `%s` on %s (%.0f s wall), urdyn commit %s, %s. Load at the start: `%s`; at the end: `%s`."
           % (meta["cmd"], meta["date"], meta["wall"], meta["commit"], meta["machine"], meta["load0"], meta["load1"]),
           "The script's docstring says how each engine gets the scene.", "",
           "dt = 0.001 s; 4 s per run (1024 objects: 2 s). urdyn: sleep on (default) and `--no-sleep`; "
           "MuJoCo: Euler and implicitfast, sleep off and on, islands on; ratio = urdyn (faster of its two) / "
           "MuJoCo's fastest.", "",
           "| pile | objects | urdyn steps/s (sleep) | urdyn --no-sleep |" + th_head + " mean awake | MuJoCo euler |"
           " euler+sleep | implicitfast | implicitfast+sleep | ratio |" + th_ratio + el_head,
           "|---|---|---|---|" + ("---|" if threads else "") + "---|---|---|---|---|---|" + ("---|---|" if threads else "")
           + ("---|---|" if elliptic else "")]
    for r in rows:
        mj = r["mujoco"]
        th = " %.0f |" % r["urdyn_threads"] if threads else ""
        thr = (" %.0f (%s) | %.2f |" % (r["mujoco_pool_best"], r["mujoco_pool_best_cfg"], r["ratio_threads"])
               if threads else "")
        el = (" %.0f (%s) | %.2f |" % (r["mujoco_elliptic_best"], r["mujoco_elliptic_best_cfg"], r["ratio_elliptic"])
              if elliptic else "")
        out.append("| %s | %d | %.0f | %s |%s %s | %.0f | %.0f | %.0f | %.0f | %.2f |%s%s" % (
            r["kind"], r["n"], r["urdyn_sleep"], "%.0f" % r["urdyn_nosleep"] if r["urdyn_nosleep"] else "-",
            th, r["urdyn_awake_mean"] or "-", mj["euler"], mj["euler+sleep"], mj["implicitfast"],
            mj["implicitfast+sleep"], r["ratio"], thr, el))
    out.append("")
    for kind in sorted({r["kind"] for r in rows}):
        by = {r["n"]: r for r in rows if r["kind"] == kind}
        if 64 in by and 1024 in by:
            g_u = by[64]["urdyn_sleep"] / by[1024]["urdyn_sleep"]
            g_un = (by[64]["urdyn_nosleep"] / by[1024]["urdyn_nosleep"]) if by[64]["urdyn_nosleep"] else float("nan")
            g_m = by[64]["mujoco_best"] / by[1024]["mujoco_best"]
            out.append("- %s, step time 1024 / 64 objects (16× the objects): urdyn %.1f× (no sleep %.1f×), MuJoCo %.1f×."
                       % (kind, g_u, g_un, g_m))
            eq = by[64].get("equal")
            if eq and by[1024]["duration"] == eq["duration"]:
                out.append("  At equal durations (%g s each): urdyn %.1f× (no sleep %.1f×), MuJoCo %.1f×."
                           % (eq["duration"], eq["urdyn_sleep"] / by[1024]["urdyn_sleep"],
                              eq["urdyn_nosleep"] / by[1024]["urdyn_nosleep"] if by[1024]["urdyn_nosleep"] else float("nan"),
                              eq["mujoco_best"] / by[1024]["mujoco_best"]))
            # the same ratio per awake object: what a step costs for each model it integrates
            # (sleep on; the larger pile stays awake through more of its run)
            a64, a1024 = by[64]["urdyn_awake_mean"], by[1024]["urdyn_awake_mean"]
            if a64 and a1024:
                c64 = 1e6 / (by[64]["urdyn_sleep"] * float(a64))
                c1024 = 1e6 / (by[1024]["urdyn_sleep"] * float(a1024))
                out.append("  Per awake object (step time / mean awake): %.2f µs at 64, %.2f µs at 1024: %.2f×."
                           % (c64, c1024, c1024 / c64))
    if st:
        ge = "≥ " if st.get("bound") else ""
        out.append("- settled %d-box pile (%s): %.0f steps/s falling, %s%.0f settled from 4 s: %s%.1f×."
                   % (st["n"], st["how"], st["falling"], ge, st["settled"], ge, st["ratio"]))
    out.append("")
    with open(path, "w") as fh:
        fh.write("\n".join(out))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--urdyn", required=True)
    ap.add_argument("--kinds", default="boxes,mixed")
    ap.add_argument("--sizes", default="16,64,256,1024")
    ap.add_argument("--duration", type=float, default=4.0)
    ap.add_argument("--duration-1024", type=float, default=2.0)
    ap.add_argument("--settled", type=int, default=0)
    ap.add_argument("--pile-settled", default=None,
                    help="examples/pile_settled binary (default target/release/examples/pile_settled)")
    ap.add_argument("--repeats", type=int, default=1, help="best of this many runs of each engine and setting")
    ap.add_argument("--threads", type=int, default=0,
                    help="also run urdyn with --threads N (sleep on), and MuJoCo with its thread pool of N: "
                         "a column and a ratio of their own")
    ap.add_argument("--elliptic", action="store_true",
                    help="also run MuJoCo with its elliptic friction cone (Coulomb's disc, urdyn's friction law; "
                         "its default is a pyramid): a column and a like-for-like ratio of their own")
    ap.add_argument("--no-nosleep", action="store_true", help="skip urdyn's --no-sleep runs")
    ap.add_argument("--no-equal-growth", dest="equal_growth", action="store_false",
                    help="skip the 64 pile's runs over the 1024 pile's duration (growth at equal durations)")
    ap.add_argument("--md", default="")
    args = ap.parse_args()
    t0 = time.time()
    load0 = uptime()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for kind in args.kinds.split(","):
            for n in [int(x) for x in args.sizes.split(",")]:
                rows.append(one(args, kind, n, tmp))
        st = settled(args, args.settled, tmp) if args.settled else None
    if st:
        print("settled %d: falling %.0f, settled %.0f steps/s (%.1fx)" % (st["n"], st["falling"], st["settled"], st["ratio"]), file=sys.stderr)
    if args.md:
        meta = {"cmd": "python benches/pile_compare.py " + " ".join(sys.argv[1:]),
                "date": datetime.datetime.utcnow().strftime("%Y-%m-%d %H:%M UTC"),
                "wall": time.time() - t0, "commit": commit(), "machine": machine(),
                "load0": load0, "load1": uptime()}
        write_md(args.md, rows, meta, st, args.threads, args.elliptic)


if __name__ == "__main__":
    main()
