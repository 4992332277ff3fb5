"""Batched PD-target rollouts: urdyn.rollout with servos (kp, kd, q_ref per environment)
against mujoco.rollout with position actuators, on solo12, in one run.

64 environments of solo12 (floating base, ground plane, dt = 1 ms, semi-implicit Euler on
both sides), each with its own joint targets (the neutral stance plus a per-environment
offset of up to ±0.3 rad), kp = 5 N·m/rad and kd = 0.1 N·m·s/rad on every joint, 1000 steps,
2 threads. MuJoCo's model is the same URDF through its importer (benches/sim_compare.py's
build_mujoco: floor, friction 1, no self-collision) with one position actuator per joint
(gain kp, bias -kp q - kd v, the targets as controls); urdyn's is the URDF with its
default contact (self-collision included). Prints steps/s of each (best of --repeats
calls) and the ratio, and checks that one urdyn environment equals a Simulation with
the same gains and targets stepped alone, bit for bit.

    /work/venv/bin/python benches/servo_rollout.py    # needs mujoco and urdyn installed
"""

import argparse
import os
import sys
import time
from types import SimpleNamespace

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mujoco  # noqa: E402
from mujoco import rollout as mj_rollout  # noqa: E402
from sim_compare import build_mujoco  # noqa: E402

import urdyn  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
URDF = os.path.join(ROOT, "assets", "robots", "solo12.urdf")
KP, KD = 5.0, 0.1


def best(f, repeats):
    t = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        f()
        t.append(time.perf_counter() - t0)
    return min(t)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--batch", type=int, default=64)
    ap.add_argument("--nstep", type=int, default=1000)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    B, N = args.batch, args.nstep
    rng = np.random.default_rng(0)

    um = urdyn.Model.from_urdf(URDF, floating_base=True)
    nq, nv, nj = um.nq, um.nv, um.nv - 6
    q0 = np.tile(um.neutral(), (B, 1))
    q0[:, 2] = 0.4
    v0 = np.zeros((B, nv))
    q_ref = np.tile(um.neutral(), (B, 1))
    q_ref[:, 7:] += rng.uniform(-0.3, 0.3, (B, nj))
    kp = np.zeros(nv)
    kp[6:] = KP
    kd = np.zeros(nv)
    kd[6:] = KD

    def run_urdyn():
        return urdyn.rollout(um, q0, v0, nstep=N, threads=args.threads, integrator="euler",
                             kp=kp, kd=kd, q_ref=q_ref)

    urdyn.rollout(um, q0[:2], v0[:2], nstep=10, threads=args.threads, integrator="euler",
                  kp=kp, kd=kd, q_ref=q_ref[:2])
    t_ur = best(run_urdyn, args.repeats)
    Q, V = run_urdyn()
    sim = urdyn.Simulation(um, integrator="euler")
    sim.set_state(q0[5], v0[5])
    sim.set_gains(kp, kd)
    sim.set_targets(q_ref[5])
    sim.step(n=N)
    same = bool(np.array_equal(sim.q, Q[5, -1]) and np.array_equal(sim.v, V[5, -1]))

    m, _, _ = build_mujoco(URDF, [os.path.dirname(URDF)], SimpleNamespace(dt=1e-3))
    ma = _with_position_actuators(m)
    nu = ma.nu
    assert nu == nj, (nu, nj)
    qpos0 = np.tile(ma.qpos0, (B, 1))
    qpos0[:, :7] = q0[:, :7][:, [0, 1, 2, 6, 3, 4, 5]]  # MuJoCo's quaternion is w, x, y, z
    init = np.concatenate([np.zeros((B, 1)), qpos0, np.zeros((B, ma.nv))], axis=1)
    ctrl = np.repeat(q_ref[:, None, 7:], N, axis=1)
    datas = [mujoco.MjData(ma) for _ in range(args.threads)]
    mj_rollout.rollout(ma, datas, init[:2], ctrl[:2, :10], nstep=10)
    t_mj = best(lambda: mj_rollout.rollout(ma, datas, init, ctrl, nstep=N), args.repeats)
    r_ur, r_mj = B * N / t_ur, B * N / t_mj
    print(f"solo12, {B} environments x {N} steps, per-environment targets, {args.threads} threads: "
          f"mujoco.rollout {r_mj:,.0f} steps/s, urdyn.rollout {r_ur:,.0f} steps/s, "
          f"ratio {r_ur / r_mj:.2f}; urdyn env 5 == Simulation bit for bit: {same}")


def _with_position_actuators(m):
    """m recompiled with a position actuator (kp, kd) on every hinge joint, Euler."""
    path = os.path.join(ROOT, "target", "servo_rollout_solo12.xml")
    mujoco.mj_saveLastXML(path, m)
    spec = mujoco.MjSpec.from_file(path)
    for j in spec.joints:
        if j.type == mujoco.mjtJoint.mjJNT_HINGE:
            spec.add_actuator(name=f"pos_{j.name}", target=j.name,
                              trntype=mujoco.mjtTrn.mjTRN_JOINT,
                              gaintype=mujoco.mjtGain.mjGAIN_FIXED,
                              biastype=mujoco.mjtBias.mjBIAS_AFFINE,
                              gainprm=[KP] + [0] * 9, biasprm=[0, -KP, -KD] + [0] * 7)
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    return spec.compile()


if __name__ == "__main__":
    main()
