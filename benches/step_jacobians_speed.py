#!/usr/bin/env python3
"""The transition Jacobians of one step: urdyn (analytic, forward, central) against
MuJoCo's mjd_transitionFD (forward differences), single thread, one run.

Usage: python benches/step_jacobians_speed.py [--share DIR] [--md benches/step_jacobians.md]

- ur5, fixed base, no contact, semi-implicit Euler at dt = 1 ms on both sides, random
  joint angles (seed 0), at rest; MuJoCo with its contact pass disabled.
- solo12 (example-robot-data, its collision meshes) standing on a floor under joint servos
  (kp 5 N·m/rad, kd 0.1 N·m·s/rad, the SRDF's "standing" pose) for 1 s, dt = 1 ms: urdyn's
  default (time stepping) against MuJoCo's Euler with a plane floor and 12 position
  actuators of the same gains, at tolerance 0 and one solver iteration (as MuJoCo's
  documentation advises for mjd_transitionFD); each its own resting state.
- the quadruped of tests/urdf/quadruped.urdf standing on the ground under servos (urdyn only).
- linearize: A and B along 200 states of solo12's standing run, on 2 threads, against a
  loop of mjd_transitionFD over MuJoCo's 200 states (one thread).
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
from sim_compare import find_share, lowest_point, mujoco_xml  # noqa: E402

SOLO12 = "solo_description/robots/solo12.urdf"
# the SRDF's "standing" group state
SOLO12_STAND = {"FL_HAA": 0.1, "FL_HFE": 0.8, "FL_KFE": -1.6, "HL_HAA": 0.1, "HL_HFE": -0.8,
                "HL_KFE": 1.6, "FR_HAA": -0.1, "FR_HFE": 0.8, "FR_KFE": -1.6, "HR_HAA": -0.1,
                "HR_HFE": -0.8, "HR_KFE": 1.6}
KP, KD = 5.0, 0.1


def per_call(f, n):
    best = math.inf
    for _ in range(5):
        t0 = time.perf_counter()
        for _ in range(n):
            f()
        best = min(best, (time.perf_counter() - t0) / n)
    return best * 1e6


def mujoco_fd(m, d):
    A = np.zeros((2 * m.nv, 2 * m.nv))
    B = np.zeros((2 * m.nv, m.nu)) if m.nu else None
    return lambda: mujoco.mjd_transitionFD(m, d, 1e-6, 0, A, B, None, None)


def ur5(rows, roots):
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
    mj = per_call(mujoco_fd(m, d), 500)
    sim = urdyn.Simulation(um, ground=None, integrator="euler")
    sim.set_state(q0, np.zeros(um.nv))
    tau = np.zeros(um.nv)
    t = {k: per_call(lambda k=k: sim.transition_jacobians(tau, method=k), 500)
         for k in ("analytic", "forward", "central")}
    rows.append(("ur5, no contact", mj, t, ""))


def solo12_mujoco(share, roots):
    path = os.path.join(share, "example-robot-data", "robots", SOLO12)
    spec = mujoco.MjSpec.from_string(mujoco_xml(path, roots))
    base = list(spec.worldbody.bodies)[0]
    base.add_freejoint()
    for g in spec.geoms:
        g.contype, g.conaffinity = 1, 0
    spec.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 1],
                            contype=0, conaffinity=1)
    for name in SOLO12_STAND:
        a = spec.add_actuator(name=name, target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        a.set_to_position(kp=KP, kv=KD)
    spec.option.timestep = 1e-3
    spec.option.gravity = [0, 0, -9.81]
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    m = spec.compile()
    d = mujoco.MjData(m)
    d.qpos[:7] = [0, 0, 0, 1, 0, 0, 0]
    for i, name in enumerate(SOLO12_STAND):
        jid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)
        d.qpos[m.jnt_qposadr[jid]] = SOLO12_STAND[name]
        d.ctrl[i] = SOLO12_STAND[name]
    mujoco.mj_kinematics(m, d)
    d.qpos[2] += 1e-3 - lowest_point(m, d)
    mujoco.mj_forward(m, d)
    for _ in range(1000):
        mujoco.mj_step(m, d)
    # as mjd_transitionFD's documentation advises: a fixed number of solver iterations
    m.opt.tolerance = 0
    m.opt.iterations = 1
    states = []
    for _ in range(200):
        mujoco.mj_step(m, d)
        states.append((d.qpos.copy(), d.qvel.copy()))
    return m, d, states


def solo12_urdyn(share, roots):
    path = os.path.join(share, "example-robot-data", "robots", SOLO12)
    um = urdyn.Model.from_urdf(path, floating_base=True)
    sim = urdyn.Simulation(um, package_dirs=roots)
    q = um.neutral()
    for k, name in enumerate(um.dof_names):
        q[7 + k] = SOLO12_STAND[name]
    sim.set_gains(KP, KD)
    sim.set_targets(q)
    sim.set_state(q, np.zeros(um.nv))
    # feet 1 mm above the floor
    low = min(c["point"][2] for c in sim.contact_forces()) if sim.contact_forces() else None
    if low is None:
        sim.step()
        low = min(c["point"][2] for c in sim.contact_forces())
    q[2] += 1e-3 - low
    sim.set_state(q, np.zeros(um.nv))
    sim.step(n=1000)
    Q, V = [], []
    for _ in range(200):
        sim.step()
        Q.append(sim.q)
        V.append(sim.v)
    return sim, np.array(Q), np.array(V)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--share")
    ap.add_argument("--md", default=os.path.join(HERE, "step_jacobians.md"))
    args = ap.parse_args()
    share = find_share(args.share)
    roots = [share, os.path.join(share, "example-robot-data", "robots")]
    rows = []
    ur5(rows, roots)
    # solo12 standing
    m, d, mstates = solo12_mujoco(share, roots)
    mj = per_call(mujoco_fd(m, d), 20)
    sim, Q, V = solo12_urdyn(share, roots)
    nv = sim.model.nv if hasattr(sim, "model") else Q.shape[1] - 1
    tau = np.zeros(V.shape[1])
    t = {k: per_call(lambda k=k: sim.transition_jacobians(tau, method=k), 20 if k == "analytic" else 5)
         for k in ("analytic", "forward", "central")}
    rows.append(("solo12 standing (meshes, servos)", mj, t,
                 f"urdyn {len(sim.contact_forces())} contact points, MuJoCo {d.ncon} contacts"))
    # linearize over 200 states on 2 threads against a loop of mjd_transitionFD
    T = np.zeros_like(V)
    lin2 = per_call(lambda: urdyn.linearize(sim, Q, V, T, threads=2), 1)
    lin1 = per_call(lambda: urdyn.linearize(sim, Q, V, T, threads=1), 1)
    fd = mujoco_fd(m, d)

    def mj_loop():
        for qp, qv in mstates:
            d.qpos[:] = qp
            d.qvel[:] = qv
            fd()
    mjl = per_call(mj_loop, 1)
    # the quadruped of the tests standing
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
    t = {k: per_call(lambda k=k: qs.transition_jacobians(tau, method=k), 100)
         for k in ("analytic", "forward", "central")}
    rows.append(("quadruped of the tests standing (4 sphere feet, servos)", None, t, "urdyn only"))
    lines = ["# Transition Jacobians of one step: urdyn against MuJoCo's mjd_transitionFD", "",
             "`python benches/step_jacobians_speed.py` (one run, this machine, shared by other jobs;",
             "µs per call, best of 5 rounds, one thread). MuJoCo: `mjd_transitionFD(eps=1e-6,",
             "centered=0)`, A and B; solo12 at tolerance 0 and one solver iteration.", "",
             "| robot | MuJoCo FD | urdyn analytic | analytic / MuJoCo | urdyn forward | urdyn central | notes |",
             "| --- | --- | --- | --- | --- | --- | --- |"]
    for name, mj, t, note in rows:
        mjs = f"{mj:.1f}" if mj else "–"
        ratio = f"**{t['analytic'] / mj:.2f}**" if mj else "–"
        lines.append(f"| {name} | {mjs} | {t['analytic']:.1f} | {ratio} | {t['forward']:.1f} | "
                     f"{t['central']:.1f} | {note} |")
    lines += ["", f"`urdyn.linearize` over 200 states of solo12 standing (analytic): {lin2 / 1e3:.2f} ms on "
              f"2 threads ({lin1 / 1e3:.2f} ms on 1), against {mjl / 1e3:.1f} ms for a loop of "
              f"mjd_transitionFD over MuJoCo's 200 states: **{lin2 / mjl:.3f}**.", ""]
    text = "\n".join(lines)
    print(text)
    with open(args.md, "w") as f:
        f.write(text)


if __name__ == "__main__":
    main()
