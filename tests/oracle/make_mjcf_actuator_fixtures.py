"""MuJoCo's trajectories of actuated models for tests/mjcf_actuators.rs
(issue 29, "Actuators right"): dm_control's acrobot, cartpole, reacher and
pendulum, Gymnasium's reacher and pusher, and urdyn's actuator_kinds.xml
(position, velocity, motor, affine general, gears, ctrl and force ranges),
dm_control's point_mass (motors on fixed tendons) and urdyn's tendon_kinds.xml
(fixed tendons: springs, dampers, a range, actuators pulling them),
contact off, from qpos0 at rest (a limited hinge or slide within 0.1 of
a limit at qpos0 starts at its range's middle instead: Gymnasium's pusher's elbow
and wrist), driven 2 s by piecewise-constant random
controls (a new row every 0.1 s) small enough that every limited joint stays
at least 0.05 (rad or m) inside its range. MuJoCo's RK4 at dt = 1e-5 (its
error ~ dt^4, far below the test's 1e-5); qpos and qvel every 0.5 s.
Writes tests/fixtures/mjcf/actuators/mujoco_actuated.json.
Run: /work/venv/bin/python tests/oracle/make_mjcf_actuator_fixtures.py (MuJoCo 4.0)."""
import json
import pathlib

import mujoco
import numpy as np

root = pathlib.Path(__file__).resolve().parents[2]
fx = root / "tests/fixtures/mjcf"
MODELS = [
    "dm_control/acrobot.xml",
    "dm_control/cartpole.xml",
    "dm_control/reacher.xml",
    "dm_control/pendulum.xml",
    "gymnasium/reacher.xml",
    "gymnasium/pusher.xml",
    "actuators/actuator_kinds.xml",
    "dm_control/point_mass.xml",
    "actuators/tendon_kinds.xml",
]
DT, T, HOLD, EVERY = 1e-5, 2.0, 0.1, 0.5
MARGIN = 0.05


def start(m):
    q = m.qpos0.copy()
    for j in range(m.njnt):
        if m.jnt_limited[j] and int(m.jnt_type[j]) in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE)):
            a = m.jnt_qposadr[j]
            lo, hi = m.jnt_range[j]
            if min(q[a] - lo, hi - q[a]) < 0.1:
                q[a] = 0.5 * (lo + hi)
    return q


def run(m, rows):
    d = mujoco.MjData(m)
    mujoco.mj_resetData(m, d)
    d.qpos[:] = start(m)
    hold = round(HOLD / DT)
    every = round(EVERY / DT)
    n = round(T / DT)
    lo = m.jnt_range[:, 0]
    hi = m.jnt_range[:, 1]
    limited = m.jnt_limited.astype(bool)
    qadr = m.jnt_qposadr
    worst = np.inf
    samples = []
    for k in range(n + 1):
        if k % every == 0:
            samples.append({"t": k * DT, "qpos": list(d.qpos), "qvel": list(d.qvel)})
        if k % hold == 0 and k < n:
            d.ctrl[:] = rows[k // hold]
        q = d.qpos[qadr]
        if limited.any():
            worst = min(worst, np.min(np.minimum(q - lo, hi - q)[limited]))
        if k < n:
            mujoco.mj_step(m, d)
    return samples, worst


out = {"mujoco": mujoco.__version__, "integrator": "RK4", "dt": DT, "hold": HOLD, "models": []}
rng = np.random.default_rng(29)
for rel in MODELS:
    m = mujoco.MjModel.from_xml_path(str(fx / rel))
    m.opt.timestep = DT
    m.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
    nrows = round(T / HOLD)
    base = rng.uniform(-1.0, 1.0, size=(nrows, m.nu))
    span = np.where(m.actuator_ctrllimited.astype(bool),
                    np.maximum(np.abs(m.actuator_ctrlrange[:, 0]), np.abs(m.actuator_ctrlrange[:, 1])),
                    1.0)
    # actuator_kinds: its first actuator is driven past its ctrlrange (clamped)
    over = np.ones(m.nu)
    if rel.startswith("actuators/"):
        over[0] = 4.0
    scale = 0.5
    for _ in range(20):
        rows = base * span * over * scale
        samples, worst = run(m, rows)
        if worst >= MARGIN:
            break
        scale *= 0.7
    else:
        raise SystemExit(f"{rel}: no control scale keeps the joints off their limits")
    print(f"{rel}: nu {m.nu}, control scale {scale:.4f}, closest to a limit {worst:.4f}, "
          f"end qpos {np.round(samples[-1]['qpos'], 4)}")
    names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_ACTUATOR, i) or f"actuator_{i}" for i in range(m.nu)]
    out["models"].append({
        "file": rel,
        "actuators": names,
        "controls": [[i * HOLD] + list(r) for i, r in enumerate(rows)],
        "closest_to_limit": None if np.isinf(worst) else worst,
        "samples": samples,
    })
dst = fx / "actuators/mujoco_actuated.json"
dst.write_text(json.dumps(out, indent=1) + "\n")
print(dst)
