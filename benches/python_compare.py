#!/usr/bin/env python3
"""urdyn from Python against Pinocchio and MuJoCo from Python, in one run.

Usage (benches/python_compare.sh makes the venv, installs ./python and calls this):
    python benches/python_compare.py [--share DIR] [--repeats 5] [--threads 2]
        [--md benches/python_results.md] [--json benches/python_results.json]

1. Per call, overhead included on both sides (a Python loop of N calls, best of
   --repeats): `urdyn.rnea` / `urdyn.aba` against `pin.rnea` / `pin.aba` on ur5 (fixed
   base) and talos_reduced (free base), same q, v, a/tau arrays (float64, contiguous).
2. Batched rollouts, semi-implicit Euler at dt = 1 ms on both sides, B = 32 runs of
   1000 steps, --threads threads (urdyn.rollout(threads=2); mujoco.rollout with 2 MjData):
   - ur5, fixed base, no contact, gravity, from random joint angles in [-π, π] (seed 0),
     at rest; MuJoCo with its contact pass disabled (no floor exists anyway);
   - go2 dropped on the ground: floating base, joints at 0 or mid-range where 0 is outside
     their limits, the lowest collision point 0.3 m above the ground (the start of
     benches/sim_compare.py, computed in MuJoCo and given to both engines), 1000 steps.
   MuJoCo gets the URDF through its own importer, as benches/sim_compare.py builds it
   (free joint, floor, robot-floor pairs only, friction 1, Newton solver, pyramidal cone).
   steps/s = B·1000 / wall seconds of the rollout call (best of --repeats).
   Each urdyn batch is also checked, bit for bit, against one `urdyn.Simulation` stepped
   alone from the same start.
"""

import argparse
import datetime
import json
import math
import os
import platform
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import numpy as np  # noqa: E402
import mujoco  # noqa: E402
from mujoco import rollout as mj_rollout  # noqa: E402
import pinocchio as pin  # noqa: E402

import urdyn  # noqa: E402
from robots_sweep import start_pose  # noqa: E402
from sim_compare import build_mujoco, find_share, mujoco_start, mujoco_xml  # noqa: E402

ROOT = os.path.dirname(HERE)


def best_time(f, repeats):
    best = math.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        f()
        best = min(best, time.perf_counter() - t0)
    return best


def per_call(repeats):
    rows = []
    for name, rel, fb in (("ur5", "assets/robots/ur5.urdf", False),
                          ("talos_reduced", "assets/robots/talos_reduced.urdf", True)):
        path = os.path.join(ROOT, rel)
        pm = pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer()) if fb else pin.buildModelFromUrdf(path)
        pd = pm.createData()
        um = urdyn.Model.from_urdf(path, floating_base=fb)
        ud = um.create_data()
        assert (um.nq, um.nv) == (pm.nq, pm.nv), name
        rng = np.random.default_rng(0)
        q = um.neutral()
        q[7 if fb else 0:] = rng.uniform(-1, 1, um.nq - (7 if fb else 0))
        v, a = rng.normal(size=um.nv), rng.normal(size=um.nv)
        # Pinocchio's q: same joint values by name, same base pose
        pq = pin.neutral(pm)
        off = 7 if fb else 0
        for i, jn in enumerate(um.dof_names):
            jid = pm.getJointId(jn)
            pq[pm.joints[jid].idx_q] = q[off + i]
        n = 20000
        for fn, pf, uf in (("rnea", lambda: pin.rnea(pm, pd, pq, v, a), lambda: urdyn.rnea(um, ud, q, v, a)),
                           ("aba", lambda: pin.aba(pm, pd, pq, v, a), lambda: urdyn.aba(um, ud, q, v, a))):
            def loop(f):
                return lambda: [f() for _ in range(n)]
            tp = best_time(loop(pf), repeats) / n
            tu = best_time(loop(uf), repeats) / n
            rows.append({"robot": name, "function": fn, "pinocchio_ns": tp * 1e9, "urdyn_ns": tu * 1e9,
                         "ratio": tu / tp})
            print(f"{name:14s} {fn:5s} pin {tp*1e9:7.0f} ns  urdyn {tu*1e9:7.0f} ns  ratio {tu/tp:.2f}", flush=True)
    return rows


class Args:
    dt = 1e-3


def mj_rollout_rate(m, qpos0, threads, nstep, repeats):
    """MuJoCo rollouts from the rows of qpos0 (B x nq, at rest), steps/s."""
    m.opt.integrator = mujoco.mjtIntegrator.mjINT_EULER
    d = mujoco.MjData(m)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    nstate = mujoco.mj_stateSize(m, spec)
    init = np.zeros((len(qpos0), nstate))
    for b, qp in enumerate(qpos0):
        mujoco.mj_resetData(m, d)
        d.qpos[:] = qp
        mujoco.mj_forward(m, d)
        mujoco.mj_getState(m, d, init[b], spec)
    datas = [mujoco.MjData(m) for _ in range(threads)]
    mj_rollout.rollout(m, datas, init, nstep=nstep)  # warm up (thread pool, pages)
    wall = best_time(lambda: mj_rollout.rollout(m, datas, init, nstep=nstep), repeats)
    return len(qpos0) * nstep / wall


def urdyn_rollout_rate(um, q0, v0, threads, nstep, repeats, ground):
    urdyn.rollout(um, q0[:2], v0[:2], nstep=10, threads=threads, ground=ground, integrator="euler")
    Q = None

    def run():
        nonlocal Q
        Q, _ = urdyn.rollout(um, q0, v0, nstep=nstep, threads=threads, ground=ground, integrator="euler")
    wall = best_time(run, repeats)
    # bit for bit against one Simulation stepped alone
    sim = urdyn.Simulation(um, ground=ground, integrator="euler")
    sim.set_state(q0[-1], v0[-1])
    sim.step(n=nstep)
    same = bool(np.array_equal(Q[-1, -1], sim.q))
    return len(q0) * nstep / wall, same


def rollouts(share, threads, repeats):
    rows = []
    B, nstep = 32, 1000
    roots = [share, os.path.join(share, "example-robot-data", "robots")]
    # ur5: fixed base, no contact
    path = os.path.join(ROOT, "assets/robots/ur5.urdf")
    spec = mujoco.MjSpec.from_string(mujoco_xml(path, roots))
    spec.option.timestep = 1e-3
    spec.option.gravity = [0, 0, -9.81]
    spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
    m = spec.compile()
    um = urdyn.Model.from_urdf(path)
    rng = np.random.default_rng(0)
    q0 = rng.uniform(-math.pi, math.pi, (B, um.nq))
    v0 = np.zeros((B, um.nv))
    qpos = np.zeros((B, m.nq))
    for i, jn in enumerate(um.dof_names):
        jid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, jn)
        qpos[:, m.jnt_qposadr[jid]] = q0[:, i]
    mj = mj_rollout_rate(m, qpos, threads, nstep, repeats)
    ur, same = urdyn_rollout_rate(um, q0, v0, threads, nstep, repeats, None)
    rows.append({"robot": "ur5", "scene": "fixed base, no contact", "mujoco_steps_s": mj,
                 "urdyn_steps_s": ur, "ratio": ur / mj, "bit_identical": same})
    print(f"ur5 rollout: MuJoCo {mj:,.0f} steps/s, urdyn {ur:,.0f} steps/s, ratio {ur/mj:.2f}, "
          f"bit-identical {same}", flush=True)
    # go2 dropped on the ground
    path = os.path.join(share, "example-robot-data/robots/go2_description/urdf/go2.urdf")
    m, _, _ = build_mujoco(path, roots, Args)
    qpos0 = mujoco_start(m, start_pose(path), path, 0.3)
    um = urdyn.Model.from_urdf(path, floating_base=True, package_dirs=roots)
    q = um.neutral()
    q[0:3] = qpos0[0:3]
    w, x, y, z = qpos0[3:7]
    q[3:7] = [x, y, z, w]
    for i, jn in enumerate(um.dof_names):
        jid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, jn)
        q[7 + i] = qpos0[m.jnt_qposadr[jid]]
    q0 = np.tile(q, (B, 1))
    v0 = np.zeros((B, um.nv))
    mj = mj_rollout_rate(m, np.tile(qpos0, (B, 1)), threads, nstep, repeats)
    ur, same = urdyn_rollout_rate(um, q0, v0, threads, nstep, repeats, 0.0)
    rows.append({"robot": "go2", "scene": "dropped 0.3 m onto the ground", "mujoco_steps_s": mj,
                 "urdyn_steps_s": ur, "ratio": ur / mj, "bit_identical": same})
    print(f"go2 rollout: MuJoCo {mj:,.0f} steps/s, urdyn {ur:,.0f} steps/s, ratio {ur/mj:.2f}, "
          f"bit-identical {same}", flush=True)
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--share", default=None)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--md", default=os.path.join(HERE, "python_results.md"))
    ap.add_argument("--json", default=os.path.join(HERE, "python_results.json"))
    args = ap.parse_args()
    share = find_share(args.share)
    calls = per_call(args.repeats)
    rolls = rollouts(share, args.threads, args.repeats)
    meta = {"date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "machine": f"{platform.machine()}, {os.cpu_count()} cores, {platform.python_version()}",
            "pinocchio": pin.__version__, "mujoco": mujoco.__version__, "threads": args.threads,
            "load_average": os.getloadavg()}
    with open(args.json, "w") as f:
        json.dump({"meta": meta, "per_call": calls, "rollout": rolls}, f, indent=1)
    lines = [
        "# urdyn from Python against Pinocchio and MuJoCo (benches/python_compare.py)",
        "",
        f"Measured {meta['date']} on {meta['machine']} (load average {meta['load_average'][0]:.1f}); "
        f"Pinocchio {meta['pinocchio']}, MuJoCo {meta['mujoco']}. Scenes and timing: the script's docstring.",
        "",
        "## Per call from Python (overhead included on both sides)",
        "",
        "| robot | function | Pinocchio (ns) | urdyn (ns) | urdyn / Pinocchio |",
        "|---|---|---|---|---|",
    ]
    for r in calls:
        lines.append(f"| {r['robot']} | {r['function']} | {r['pinocchio_ns']:.0f} | {r['urdyn_ns']:.0f} | "
                     f"{r['ratio']:.2f} |")
    lines += [
        "",
        f"## Batched rollouts: 32 × 1000 steps, semi-implicit Euler, dt = 1 ms, {args.threads} threads",
        "",
        "| robot | scene | mujoco.rollout (steps/s) | urdyn.rollout (steps/s) | urdyn / MuJoCo | "
        "bit-identical to Simulation |",
        "|---|---|---|---|---|---|",
    ]
    for r in rolls:
        lines.append(f"| {r['robot']} | {r['scene']} | {r['mujoco_steps_s']:,.0f} | {r['urdyn_steps_s']:,.0f} | "
                     f"{r['ratio']:.2f} | {'yes' if r['bit_identical'] else 'NO'} |")
    with open(args.md, "w") as f:
        f.write("\n".join(lines) + "\n")
    print("wrote", args.md, "and", args.json)


if __name__ == "__main__":
    main()
