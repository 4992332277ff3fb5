"""Batched PD-target rollouts: urdyn.rollout with servos (kp, kd, q_ref per environment)
against mujoco.rollout with position actuators, on solo12, in one run.

64 environments of solo12 (floating base, ground plane, dt = 1 ms, semi-implicit Euler on
both sides) starting in a standing stance with the feet 3 cm up, each with its own joint
targets (the stance plus a per-environment offset of up to ±0.2 rad), kp = 5 N·m/rad and kd = 0.1 N·m·s/rad on every joint, 1000 steps,
2 threads. MuJoCo's model is the same URDF through its importer (benches/sim_compare.py's
build_mujoco: floor, friction 1, no self-collision) with one position actuator per joint
(gain kp, bias -kp q - kd v, the targets as controls); urdyn's is the URDF with its
default contact (self-collision included). The two are timed in --rounds interleaved rounds (each
round one call of each, the order alternating), so that a burst of other work on the
machine hits both sides alike; each round prints steps/s of each (wall time, and the
process's CPU time split into user and system) and the round's ratios, and the end the
median and best round, and each side's fastest round with their ratio (min/min: the
fastest time over the fastest time, as benches/derivatives_ab.py --min; on a machine with
fast and slow spells the fairest single figure beside the median of per-round ratios). Checks that one urdyn environment equals a Simulation with the
same gains and targets stepped alone, bit for bit.

    /work/venv/bin/python benches/servo_rollout.py    # needs mujoco and urdyn installed
"""

import argparse
import os
import resource
import statistics
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mujoco  # noqa: E402
from mujoco import rollout as mj_rollout  # noqa: E402
from sim_compare import mujoco_xml  # noqa: E402

import urdyn  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
URDF = os.path.join(ROOT, "assets", "robots", "solo12.urdf")
KP, KD = 5.0, 0.1


def timed(f):
    """(wall seconds, user CPU seconds, system CPU seconds) of this process for one call."""
    r0, t0 = resource.getrusage(resource.RUSAGE_SELF), time.perf_counter()
    f()
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_SELF)
    return wall, r1.ru_utime - r0.ru_utime, r1.ru_stime - r0.ru_stime


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--batch", type=int, default=64)
    ap.add_argument("--nstep", type=int, default=1000)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--rounds", type=int, default=5)
    args = ap.parse_args()
    B, N = args.batch, args.nstep
    rng = np.random.default_rng(0)

    um = urdyn.Model.from_urdf(URDF, floating_base=True)
    nq, nv, nj = um.nq, um.nv, um.nv - 6
    # the stance (hips 0, thighs ±0.8, knees ∓1.6; front legs first), the feet 3 cm up
    stance = um.neutral()
    for k, name in enumerate(um.dof_names):
        front = name.startswith("F")
        stance[7 + k] = 0.0 if name.endswith("HAA") else (
            (0.8 if front else -0.8) if name.endswith("HFE") else (-1.6 if front else 1.6))
    data = um.create_data()
    feet = [n for n in um.link_names if n.endswith("FOOT")]
    stance[2] = -min(urdyn.frame_placement(um, data, stance, f)[2, 3] for f in feet) + 0.03
    q0 = np.tile(stance, (B, 1))
    v0 = np.zeros((B, nv))
    q_ref = np.tile(stance, (B, 1))
    q_ref[:, 7:] += rng.uniform(-0.2, 0.2, (B, nj))
    kp = np.zeros(nv)
    kp[6:] = KP
    kd = np.zeros(nv)
    kd[6:] = KD

    def run_urdyn():
        return urdyn.rollout(um, q0, v0, nstep=N, threads=args.threads, integrator="euler",
                             kp=kp, kd=kd, q_ref=q_ref)

    urdyn.rollout(um, q0[:2], v0[:2], nstep=10, threads=args.threads, integrator="euler",
                  kp=kp, kd=kd, q_ref=q_ref[:2])
    Q, V = run_urdyn()
    sim = urdyn.Simulation(um, integrator="euler")
    sim.set_state(q0[5], v0[5])
    sim.set_gains(kp, kd)
    sim.set_targets(q_ref[5])
    sim.step(n=N)
    same = bool(np.array_equal(sim.q, Q[5, -1]) and np.array_equal(sim.v, V[5, -1]))
    del Q, V

    ma = mujoco_model()
    nu = ma.nu
    assert nu == nj, (nu, nj)
    qpos0 = np.tile(ma.qpos0, (B, 1))
    qpos0[:, :7] = q0[:, :7][:, [0, 1, 2, 6, 3, 4, 5]]  # MuJoCo's quaternion is w, x, y, z
    init = np.concatenate([np.zeros((B, 1)), qpos0, np.zeros((B, ma.nv))], axis=1)
    ctrl = np.repeat(q_ref[:, None, 7:], N, axis=1)
    datas = [mujoco.MjData(ma) for _ in range(args.threads)]
    mj_rollout.rollout(ma, datas, init[:2], ctrl[:2, :10], nstep=10)

    def run_mujoco():
        return mj_rollout.rollout(ma, datas, init, ctrl, nstep=N)

    print(f"solo12, {B} environments x {N} steps, per-environment targets, {args.threads} "
          f"threads, {args.rounds} interleaved rounds (steps/s; CPU = user + system):")
    print("  round | mujoco wall    CPU (sys)       | urdyn wall     CPU (sys)       "
          "| ratio wall  CPU")
    ratios = []
    for r in range(args.rounds):
        pair = [("mj", run_mujoco), ("ur", run_urdyn)]
        if r % 2:
            pair.reverse()
        t = {name: timed(f) for name, f in pair}
        (w_mj, u_mj, s_mj), (w_ur, u_ur, s_ur) = t["mj"], t["ur"]
        c_mj, c_ur = u_mj + s_mj, u_ur + s_ur
        ratios.append((w_mj / w_ur, c_mj / c_ur, B * N / w_mj, B * N / w_ur))
        print(f"  {r:5d} | {B * N / w_mj:9,.0f} {B * N / c_mj:9,.0f} ({s_mj:.3f}s) "
              f"| {B * N / w_ur:9,.0f} {B * N / c_ur:9,.0f} ({s_ur:.3f}s) "
              f"| {w_mj / w_ur:5.2f} {c_mj / c_ur:5.2f}")
    med = [statistics.median(x[k] for x in ratios) for k in range(4)]
    # each side's fastest round (the machine's quietest moment for it) and their ratio
    fast_mj, fast_ur = max(x[2] for x in ratios), max(x[3] for x in ratios)
    print(f"  median: mujoco.rollout {med[2]:,.0f} steps/s, urdyn.rollout {med[3]:,.0f} steps/s, "
          f"ratio wall {med[0]:.2f}, CPU {med[1]:.2f}; best round's wall ratio "
          f"{max(x[0] for x in ratios):.2f}, worst {min(x[0] for x in ratios):.2f}\n"
          f"  fastest round: mujoco.rollout {fast_mj:,.0f} steps/s, urdyn.rollout "
          f"{fast_ur:,.0f} steps/s, min/min wall ratio {fast_ur / fast_mj:.2f}\n"
          f"  urdyn environment 5 == a Simulation with the same gains and targets, bit for bit: {same}")


def mujoco_model():
    """solo12 as benches/sim_compare.py's build_mujoco makes it (the URDF through MuJoCo's
    importer, a free joint, a floor, friction 1, no self-collision, dt = 1 ms), with a
    position actuator (kp, kd) on every hinge joint, semi-implicit Euler."""
    spec = mujoco.MjSpec.from_string(mujoco_xml(URDF, [os.path.dirname(URDF)]))
    base = list(spec.worldbody.bodies)[0]
    base.add_freejoint()
    for g in spec.geoms:
        g.contype, g.conaffinity = 1, 0
        g.friction = [1.0, 0.005, 0.0001]
    spec.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 1],
                            contype=0, conaffinity=1, friction=[1.0, 0.005, 0.0001])
    for j in spec.joints:
        if j.type == mujoco.mjtJoint.mjJNT_HINGE:
            spec.add_actuator(name=f"pos_{j.name}", target=j.name,
                              trntype=mujoco.mjtTrn.mjTRN_JOINT,
                              gaintype=mujoco.mjtGain.mjGAIN_FIXED,
                              biastype=mujoco.mjtBias.mjBIAS_AFFINE,
                              gainprm=[KP] + [0] * 9, biasprm=[0, -KP, -KD] + [0] * 7)
    spec.option.timestep = 1e-3
    spec.option.gravity = [0, 0, -9.81]
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    return spec.compile()


if __name__ == "__main__":
    main()
