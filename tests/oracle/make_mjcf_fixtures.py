"""MuJoCo 4.0's numbers for urdyn's MJCF import (tests/mjcf_oracle.rs).

For every model under tests/fixtures/mjcf/{gymnasium,dm_control,synthetic}/*.xml that
MuJoCo compiles: per body its compiled mass, centre of mass and inertia about it in the
body frame (body_mass, body_ipos, body_iquat·diag(body_inertia)·body_iquatᵀ), and
at 5 random states, in urdyn's coordinates (mjcf.md §"In `eval`"): the mass matrix
with armature H = Tᵀ qM T, bias = Tᵀ (qfrc_bias + qM Ṫ v), tau = Tᵀ (mj_rne(qacc) +
armature·qacc) with qacc = T a + Ṫ v (mj_rne leaves armature out; MuJoCo's qM has it),
qdd for an independent random tau_in (mj_forward with qfrc_applied = T⁻ᵀ tau_in,
constraints, passive forces and actuation off), and every body's pose
(xpos, xmat). T maps urdyn's v to MuJoCo's qvel: R on a free joint's linear block
(urdyn's free-joint linear velocity is body-frame, MuJoCo's world-frame),
identity elsewhere; Ṫ = R [ω]× there.

Run: /work/venv/bin/python tests/oracle/make_mjcf_fixtures.py
Writes tests/fixtures/mjcf/oracle/<suite>_<model>.json.
"""

import glob
import json
import os

import mujoco
import numpy as np

ROOT = os.path.join(os.path.dirname(__file__), "..", "fixtures", "mjcf")
OUT = os.path.join(ROOT, "oracle")
NSTATES = 5


def name(m, kind, i, prefix):
    n = mujoco.mj_id2name(m, kind, i)
    return n if n else f"{prefix}_{i}"


def skew(w):
    return np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])


def quat_mat(q):
    r = np.zeros(9)
    mujoco.mju_quat2Mat(r, q)
    return r.reshape(3, 3)


def disable_all_but_dynamics(m):
    flags = 0
    for f in ["CONSTRAINT", "PASSIVE", "SPRING", "DAMPER", "ACTUATION", "CONTACT", "LIMIT",
              "EQUALITY", "FRICTIONLOSS"]:
        bit = getattr(mujoco.mjtDisableBit, "mjDSBL_" + f, None)
        if bit is not None:
            flags |= int(bit)
    m.opt.disableflags |= flags
    m.opt.density = 0.0
    m.opt.viscosity = 0.0


def fixture(path, rng):
    m = mujoco.MjModel.from_xml_path(path)
    d = mujoco.MjData(m)
    bodies = {}
    for b in range(1, m.nbody):
        r = quat_mat(m.body_iquat[b])
        inertia = r @ np.diag(m.body_inertia[b]) @ r.T
        bodies[name(m, mujoco.mjtObj.mjOBJ_BODY, b, "body")] = {
            "mass": float(m.body_mass[b]),
            "com": m.body_ipos[b].tolist(),
            "inertia": inertia.tolist(),
        }
    frees = [(m.jnt_qposadr[j], m.jnt_dofadr[j]) for j in range(m.njnt)
             if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE]
    balls = [m.jnt_qposadr[j] for j in range(m.njnt)
             if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_BALL]
    disable_all_but_dynamics(m)
    states = []
    for _ in range(NSTATES):
        qpos = m.qpos0.copy()
        qpos += rng.uniform(-1, 1, m.nq)
        for qa in [qa + 3 for qa, _ in frees] + balls:
            q = rng.normal(size=4)
            qpos[qa:qa + 4] = q / np.linalg.norm(q)
        qvel = rng.uniform(-1, 1, m.nv)
        a = rng.uniform(-1, 1, m.nv)
        tau_in = rng.uniform(-1, 1, m.nv)
        T = np.eye(m.nv)
        Td = np.zeros((m.nv, m.nv))
        q_u = qpos.copy()
        for qa, da in frees:
            R = quat_mat(qpos[qa + 3:qa + 7])
            T[da:da + 3, da:da + 3] = R
            Td[da:da + 3, da:da + 3] = R @ skew(qvel[da + 3:da + 6])
        for qa in [qa + 3 for qa, _ in frees] + balls:  # w-first to w-last
            q_u[qa:qa + 3] = qpos[qa + 1:qa + 4]
            q_u[qa + 3] = qpos[qa]
        v = np.linalg.solve(T, qvel)
        d.qpos[:] = qpos
        d.qvel[:] = qvel
        d.qfrc_applied[:] = 0
        d.ctrl[:] = 0
        mujoco.mj_forward(m, d)
        qM = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, qM)
        H = T.T @ qM @ T
        bias = T.T @ (d.qfrc_bias + qM @ Td @ v)
        poses = {}
        for b in range(1, m.nbody):
            poses[name(m, mujoco.mjtObj.mjOBJ_BODY, b, "body")] = (
                d.xpos[b].tolist() + d.xmat[b].tolist())
        qacc = T @ a + Td @ v
        d.qacc[:] = qacc
        rne = np.zeros(m.nv)
        mujoco.mj_rne(m, d, 1, rne)
        tau = T.T @ (rne + m.dof_armature * qacc)
        # forward dynamics for tau_in: MuJoCo's generalized force f with Tᵀ f = tau_in
        d.qfrc_applied[:] = np.linalg.solve(T.T, tau_in)
        mujoco.mj_forward(m, d)
        qdd = np.linalg.solve(T, d.qacc - Td @ v)
        states.append({
            "q": q_u.tolist(), "v": v.tolist(), "a": a.tolist(), "tau_in": tau_in.tolist(),
            "mass_matrix": H.tolist(), "bias": bias.tolist(), "tau": tau.tolist(),
            "qdd": qdd.tolist(), "poses": poses,
        })
    return {
        "nq": int(m.nq), "nv": int(m.nv),
        "gravity": m.opt.gravity.tolist(),
        "bodies": bodies, "states": states,
    }


def main():
    os.makedirs(OUT, exist_ok=True)
    rng = np.random.default_rng(29)
    made = []
    for suite in ["gymnasium", "dm_control", "synthetic"]:
        for path in sorted(glob.glob(os.path.join(ROOT, suite, "*.xml"))):
            stem = os.path.splitext(os.path.basename(path))[0]
            try:
                fx = fixture(path, rng)
            except ValueError as e:  # MuJoCo does not compile it
                print(f"skip {suite}/{stem}: {e}")
                continue
            fx["model"] = f"{suite}/{stem}.xml"
            with open(os.path.join(OUT, f"{suite}_{stem}.json"), "w") as f:
                json.dump(fx, f, separators=(",", ":"))
            made.append(fx["model"])
    print(f"{len(made)} fixtures:", " ".join(made))


if __name__ == "__main__":
    main()
