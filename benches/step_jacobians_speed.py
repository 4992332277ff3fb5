#!/usr/bin/env python3
"""The transition Jacobians of one step: urdyn (analytic, forward, central) against
MuJoCo's mjd_transitionFD (forward differences), single thread, one run.

Usage: python benches/step_jacobians_speed.py [--share DIR] [--md benches/step_jacobians.md]

- ur5, fixed base, no contact, semi-implicit Euler at dt = 1 ms on both sides, random
  joint angles (seed 0), at rest; MuJoCo with its contact pass disabled.
- the quadruped of tests/urdf/quadruped.urdf standing on the ground under servos
  (urdyn only: its sphere feet in MuJoCo would need a scene of their own).
Each figure is the best of 5 rounds of the mean over N calls (µs per call).
"""

import argparse
import math
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
ROOT = os.path.dirname(HERE)

import numpy as np  # noqa: E402
import mujoco  # noqa: E402

import urdyn  # noqa: E402
from sim_compare import find_share, mujoco_xml  # noqa: E402


def per_call(f, n):
    best = math.inf
    for _ in range(5):
        t0 = time.perf_counter()
        for _ in range(n):
            f()
        best = min(best, (time.perf_counter() - t0) / n)
    return best * 1e6


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--share")
    ap.add_argument("--md", default=os.path.join(HERE, "step_jacobians.md"))
    args = ap.parse_args()
    share = find_share(args.share)
    roots = [share, os.path.join(share, "example-robot-data", "robots")]
    rows = []
    # ur5: MuJoCo
    path = os.path.join(ROOT, "assets/robots/ur5.urdf")
    spec = mujoco.MjSpec.from_string(mujoco_xml(path, roots))
    spec.option.timestep = 1e-3
    spec.option.gravity = [0, 0, -9.81]
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
    m = spec.compile()
    d = mujoco.MjData(m)
    um = urdyn.Model.from_urdf(path)
    rng = np.random.default_rng(0)
    q0 = rng.uniform(-math.pi, math.pi, um.nq)
    for i, jn in enumerate(um.dof_names):
        jid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, jn)
        d.qpos[m.jnt_qposadr[jid]] = q0[i]
    mujoco.mj_forward(m, d)
    A = np.zeros((2 * m.nv, 2 * m.nv))
    B = np.zeros((2 * m.nv, m.nu)) if m.nu else None
    mj = per_call(lambda: mujoco.mjd_transitionFD(m, d, 1e-6, 0, A, B, None, None), 200)
    sim = urdyn.Simulation(um, ground=None, integrator="euler")
    sim.set_state(q0, np.zeros(um.nv))
    tau = np.zeros(um.nv)
    t = {k: per_call(lambda k=k: sim.transition_jacobians(tau, method=k), 200)
         for k in ("analytic", "forward", "central")}
    rows.append(("ur5, no contact", mj, t))
    # the quadruped standing
    qm = urdyn.Model.from_urdf(os.path.join(ROOT, "tests/urdf/quadruped.urdf"), floating_base=True)
    qs = urdyn.Simulation(qm)
    q = qm.neutral()
    for k, name in enumerate(qm.dof_names):
        q[7 + k] = 0.6 if name.endswith("hip") else -1.2
    q[2] = 0.4 * math.cos(0.6) + 0.021
    qs.set_gains(60.0, 3.0)
    qs.set_targets(q)
    qs.set_state(q, np.zeros(qm.nv))
    qs.step(n=2000)
    tau = np.zeros(qm.nv)
    t = {k: per_call(lambda k=k: qs.transition_jacobians(tau, method=k), 50)
         for k in ("analytic", "forward", "central")}
    rows.append(("quadruped standing (4 contacts, servos)", None, t))
    # linearize over 200 states on 2 threads against a loop of the analytic call
    Q = np.tile(qs.q, (200, 1))
    V = np.tile(qs.v, (200, 1))
    T = np.zeros((200, qm.nv))
    lin2 = per_call(lambda: urdyn.linearize(qs, Q, V, T, threads=2), 2)
    lin1 = per_call(lambda: urdyn.linearize(qs, Q, V, T, threads=1), 2)
    lines = ["# Transition Jacobians of one step: urdyn against MuJoCo's mjd_transitionFD", "",
             "`python benches/step_jacobians_speed.py` (one run, this machine, shared by other jobs;",
             "µs per call, best of 5 rounds). MuJoCo: `mjd_transitionFD(eps=1e-6, centered=0)`.", "",
             "| robot | MuJoCo FD | urdyn analytic | urdyn forward | urdyn central |",
             "| --- | --- | --- | --- | --- |"]
    for name, mj, t in rows:
        mjs = f"{mj:.1f}" if mj else "–"
        lines.append(f"| {name} | {mjs} | {t['analytic']:.1f} | {t['forward']:.1f} | {t['central']:.1f} |")
    lines += ["", f"`urdyn.linearize` over 200 standing states (analytic): {lin1/1e3:.1f} ms on 1 thread, "
              f"{lin2/1e3:.1f} ms on 2 threads.", ""]
    text = "\n".join(lines)
    print(text)
    with open(args.md, "w") as f:
        f.write(text)


if __name__ == "__main__":
    main()
