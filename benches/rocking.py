#!/usr/bin/env python3
"""Housner's rocking block in MuJoCo: the column of tests/rocking.rs, its per-impact ratios.

Usage:
    /work/venv/bin/python benches/rocking.py [--theta 0.05,0.15] [--duration 1.5] [--integrator euler]

The scenes of tests/rocking.rs (the box piles' two-box column, 0.1 m cubes of 1 kg, μ 0.8; the
column as one 0.1 x 0.1 x 0.2 m box; one cube), tilted by θ₀ about the y axis through a bottom
edge and released at rest, built by benches/scene_compare.build_mujoco as the piles are (condim 3,
MuJoCo's default solref/solimp, dt 1 ms); also the column tilted about two horizontal axes off
the faces' (the 3D wobble). Each impact (a sign change of the tilt θ): the swing's top |θ| before
and after, the ratio of the rocking energies they mean (gR(cos(α - θ) - cos α): the soft contact's
impact lasts ~10 ms and sinks the column, so the energy a few steps off the impact is not the
swing's), r = its square root against Housner's (r = 1 - 1.5 sin²α, α = atan(b/h)), the time since
the last impact, and when the column comes to rest (the last step with |θ̇| >= 0.1 rad/s). urdyn's side: `cargo test --release
--test integration rocking::report -- --ignored --nocapture`.
--cone elliptic: MuJoCo's elliptic (Coulomb's disc) cone, urdyn's PGS cone; --pile N: the box pile
of benches/scenes/pile_boxes_N.json instead, the boxes moving every 0.1 s (sleep off).
"""
import argparse
import json
import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
sys.path.insert(0, HERE)
from scene_compare import build_mujoco  # noqa: E402

import mujoco  # noqa: E402

G = 9.81
CUBE = os.path.join(REPO, "benches", "pile", "box.urdf")
TALL = os.path.join(REPO, "tests", "urdf", "column_box.urdf")
COLUMNS = {
    # name: ([(urdf, centre z, half extents)], b, h, mass)
    "two cubes": ([(CUBE, 0.05, (0.05, 0.05, 0.05)), (CUBE, 0.15, (0.05, 0.05, 0.05))], 0.05, 0.1, 2.0),
    "one tall box": ([(TALL, 0.1, (0.05, 0.05, 0.1))], 0.05, 0.1, 2.0),
    "one cube": ([(CUBE, 0.05, (0.05, 0.05, 0.05))], 0.05, 0.05, 1.0),
}


def rot(u, t):
    """Rodrigues: the rotation by t about the unit axis u."""
    k = np.array([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]])
    return np.eye(3) + math.sin(t) * k + (1 - math.cos(t)) * k @ k


def scene(boxes, u, theta0):
    r = rot(u, theta0)
    lowest = min((r @ np.array([sx * e[0], sy * e[1], z + sz * e[2]]))[2]
                 for _, z, e in boxes for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1))
    qx = [u[0] * math.sin(theta0 / 2), u[1] * math.sin(theta0 / 2), u[2] * math.sin(theta0 / 2),
          math.cos(theta0 / 2)]
    models = []
    for i, (urdf, z, _) in enumerate(boxes):
        c = r @ np.array([0.0, 0.0, z]) - np.array([0.0, 0.0, lowest])
        models.append({"name": "b%d" % i, "urdf": urdf, "base": "floating", "friction": 0.8,
                       "position": c.tolist(), "orientation_xyzw": qx})
    return {"ground": {"height": 0.0, "friction": 0.8}, "sleep": False, "models": models}


def tune(model, solref, cone):
    if solref is not None:
        model.geom_solref[:, 0] = solref
    if cone == "elliptic":
        model.opt.cone = mujoco.mjtCone.mjCONE_ELLIPTIC


def run(name, u, theta0, duration, integ, solref=None, cone="pyramidal"):
    boxes, b, h, mass = COLUMNS[name]
    model, qpos, qvel, _ = build_mujoco(scene(boxes, u, theta0), [], 0.001)
    tune(model, solref, cone)
    perp = np.cross(u, [0.0, 0.0, 1.0])
    model.opt.integrator = {"euler": mujoco.mjtIntegrator.mjINT_EULER,
                            "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST}[integ]
    d = mujoco.MjData(model)
    d.qpos[:], d.qvel[:] = qpos, qvel
    bodies = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "b%d/box" % i) for i in range(len(boxes))]
    rec = []
    rest_pe = G * h * mass
    for step in range(int(round(duration / 0.001))):
        mujoco.mj_step(model, d)
        e = 0.0
        for k, bid in enumerate(bodies):
            m = model.body_mass[bid]
            inertia = model.body_inertia[bid]
            v = d.qvel[6 * k:6 * k + 3]
            w = d.qvel[6 * k + 3:6 * k + 6]  # body frame
            e += 0.5 * m * v @ v + 0.5 * inertia @ (w * w) + m * G * d.xipos[bid][2]
        rmat = d.xmat[bodies[0]].reshape(3, 3)
        zb = rmat[:, 2]
        w_world = rmat @ d.qvel[3:6]
        rec.append((d.time, math.atan2(zb @ perp, zb[2]), w_world @ u, (e - rest_pe) / mass,
                    d.xpos[bodies[0]][2]))
    return rec


def report(name, theta0, duration, integ, axis=(0.0, 1.0, 0.0), solref=None, cone="pyramidal"):
    boxes, b, h, mass = COLUMNS[name]
    alpha = math.atan(b / h)
    big_r = math.hypot(b, h)
    hr = 1.0 - 1.5 * math.sin(alpha) ** 2
    u = np.array(axis) / np.linalg.norm(axis)
    rec = run(name, u, theta0, duration, integ, solref, cone)

    def swing_energy(top):  # the rocking energy (J/kg) of a swing reaching |θ| = top
        return G * big_r * (math.cos(alpha - top) - math.cos(alpha))

    print("== MuJoCo %s, %s cone, solref timeconst %s, %s, axis %s: θ₀ %.3f, Housner r %.4f (energy %.4f)"
          % (integ, cone, solref or "0.02 (default)", name, tuple(round(float(x), 3) for x in u),
             theta0, hr, hr * hr))
    imp = [k for k in range(1, len(rec)) if rec[k][1] * rec[k - 1][1] < 0.0]
    prev, top_before = 0.0, theta0
    for n, k in enumerate(imp[:12]):
        nxt = imp[n + 1] if n + 1 < len(imp) else len(rec)
        top_after = max(abs(r[1]) for r in rec[k:nxt])
        e0 = swing_energy(top_before)
        er = swing_energy(top_after) / e0 if e0 > 0 else float("nan")
        print("impact %2d t %.4f dt %.4f swing tops %.5f -> %.5f energy ratio %.4f r %.4f (%.3f of Housner's)"
              % (n, rec[k][0], rec[k][0] - prev, top_before, top_after, er, math.sqrt(er),
                 math.sqrt(er) / hr))
        prev, top_before = rec[k][0], top_after
    tops, lo = [], 0
    for k in imp + [len(rec)]:
        if k > lo:
            tops.append(max(rec[lo:k], key=lambda r: abs(r[1]))[3])
        lo = k
    print("swing tops' energy (J/kg): " + " ".join("%.2e" % e for e in tops[:10]))
    moving = [r[0] for r in rec if abs(r[2]) >= 0.1]
    zmin = min(r[4] for r in rec)
    print("impacts %d ; last |θ̇| >= 0.1 at %s s ; bottom body's lowest centre z %.5f m"
          % (len(imp), "%.3f" % moving[-1] if moving else "-", zmin))


def pile(n, duration, integ, solref, cone):
    """The box pile of benches/scenes/pile_boxes_N.json: boxes moving (|v| > 1 cm/s or |ω| > 0.1
    rad/s) every 0.1 s, sleep off, and when the last one stops."""
    path = os.path.join(REPO, "benches", "scenes", "pile_boxes_%d.json" % n)
    with open(path) as fh:
        sc = json.load(fh)
    for m in sc["models"]:
        m["urdf"] = os.path.normpath(os.path.join(os.path.dirname(path), m["urdf"]))
    model, qpos, qvel, _ = build_mujoco(sc, [], 0.001)
    model.opt.integrator = {"euler": mujoco.mjtIntegrator.mjINT_EULER,
                            "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST}[integ]
    tune(model, solref, cone)
    d = mujoco.MjData(model)
    d.qpos[:], d.qvel[:] = qpos, qvel
    row, last = [], 0.0
    for step in range(1, int(round(duration / 0.001)) + 1):
        mujoco.mj_step(model, d)
        v = d.qvel.reshape(-1, 6)
        mv = int(np.sum((np.linalg.norm(v[:, :3], axis=1) > 0.01) | (np.linalg.norm(v[:, 3:], axis=1) > 0.1)))
        if mv:
            last = d.time
        if step % 100 == 0:
            row.append(mv)
    print("boxes %d, MuJoCo %s, %s cone, solref %s: moving every 0.1 s %s; the last at %.3f s"
          % (n, integ, cone, solref or "0.02 (default)", row, last))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--theta", default="0.05,0.15")
    ap.add_argument("--duration", type=float, default=1.5)
    ap.add_argument("--integrator", default="euler")
    ap.add_argument("--solref", type=float, default=None,
                    help="every geom's solref time constant (s; MuJoCo's default 0.02)")
    ap.add_argument("--cone", default="pyramidal", help="pyramidal (MuJoCo's default) or elliptic")
    ap.add_argument("--pile", type=int, default=0,
                    help="N: the box pile of N instead (moving boxes every 0.1 s, sleep off)")
    args = ap.parse_args()
    sr, cone = args.solref, args.cone
    if args.pile:
        pile(args.pile, args.duration, args.integrator, sr, cone)
        return
    for th in [float(x) for x in args.theta.split(",")]:
        for name in ("two cubes", "one tall box"):
            report(name, th, args.duration, args.integrator, solref=sr, cone=cone)
    report("one cube", max(float(x) for x in args.theta.split(",")), 1.0, args.integrator,
           solref=sr, cone=cone)
    report("two cubes", 0.1, args.duration, args.integrator, (1.0, 1.0, 0.0), sr, cone)
    report("two cubes", 0.1, args.duration, args.integrator, (0.9, 0.3, 0.0), sr, cone)


if __name__ == "__main__":
    main()
