"""MuJoCo 4.0's kinematics for urdyn's MJCF equality constraints (tests/mjcf_equality.rs).

For tests/fixtures/mjcf/equality/equalities.xml: at 5 random states (q, v, tau
random; the constraints violated), the constrained forward dynamics of mechanisms.md
(classical accelerations: H q̈ + bias = tau + J_cᵀ λ, J_c q̈ + γ_c = 0) solved as one
KKT system (least squares: the planar four-bar's connect has an identically zero row)
on MuJoCo's own kinematics: H from mj_fullM, bias from qfrc_bias, each point's J and
J̇ from mj_jac / mj_jacDot at the compiled anchors (eq_data: body1's point data[3:6]
for a weld, data[0:3] for a connect; body2's data[0:3] for a weld, data[3:6] for a
connect), angular rows from the bodies' rotational J and J̇, a joint row
e₁ − a₁ e₂. Active equalities only (eq_active0). Everything in urdyn's coordinates
(mjcf.md §"In `eval`": T = R on a free joint's linear block, qacc = T a + Ṫ v):
H = Tᵀ qM T, bias = Tᵀ (qfrc_bias + qM Ṫ v), J_u = J T, γ_u = γ + J Ṫ v.
Also MuJoCo's compiled eq_data per equality (the anchors urdyn must compute).

Run: /work/venv/bin/python tests/oracle/make_mjcf_equality_fixtures.py
Writes tests/fixtures/mjcf/oracle_equality/equalities.json.
"""

import json
import os

import mujoco
import numpy as np

ROOT = os.path.join(os.path.dirname(__file__), "..", "fixtures", "mjcf")
MODEL = "equality/equalities.xml"
OUT = os.path.join(ROOT, "oracle_equality")


def skew(w):
    return np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])


def quat_mat(q):
    r = np.zeros(9)
    mujoco.mju_quat2Mat(r, q)
    return r.reshape(3, 3)


def point_jac(m, d, body, local):
    """World point of `local` on `body`, its J (3×nv) and J̇ (3×nv); angular J, J̇."""
    R = d.xmat[body].reshape(3, 3)
    p = d.xpos[body] + R @ local
    jp, jr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
    mujoco.mj_jac(m, d, jp, jr, p, body)
    jpd, jrd = np.zeros((3, m.nv)), np.zeros((3, m.nv))
    mujoco.mj_jacDot(m, d, jpd, jrd, p, body)
    return jp, jpd, jr, jrd


def main():
    m = mujoco.MjModel.from_xml_path(os.path.join(ROOT, MODEL))
    d = mujoco.MjData(m)
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    rng = np.random.default_rng(2929)
    frees = [(m.jnt_qposadr[j], m.jnt_dofadr[j]) for j in range(m.njnt)
             if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE]
    balls = [m.jnt_qposadr[j] for j in range(m.njnt)
             if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_BALL]
    eqs = [i for i in range(m.neq) if m.eq_active0[i]]
    states = []
    for _ in range(5):
        qpos = m.qpos0 + rng.uniform(-0.5, 0.5, m.nq)
        for qa in [qa + 3 for qa, _ in frees] + balls:
            q = rng.normal(size=4)
            qpos[qa:qa + 4] = q / np.linalg.norm(q)
        qvel = rng.uniform(-1, 1, m.nv)
        tau_u = rng.uniform(-1, 1, m.nv)
        T, Td = np.eye(m.nv), np.zeros((m.nv, m.nv))
        q_u = qpos.copy()
        for qa, da in frees:
            R = quat_mat(qpos[qa + 3:qa + 7])
            T[da:da + 3, da:da + 3] = R
            Td[da:da + 3, da:da + 3] = R @ skew(qvel[da + 3:da + 6])
        for qa in [qa + 3 for qa, _ in frees] + balls:
            q_u[qa:qa + 3] = qpos[qa + 1:qa + 4]
            q_u[qa + 3] = qpos[qa]
        v = np.linalg.solve(T, qvel)
        d.qpos[:], d.qvel[:] = qpos, qvel
        mujoco.mj_forward(m, d)
        qM = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, qM)
        rows, gam, sizes = [], [], []
        for i in eqs:
            t, b1, b2, D = m.eq_type[i], m.eq_obj1id[i], m.eq_obj2id[i], m.eq_data[i]
            if t == mujoco.mjtEq.mjEQ_CONNECT:
                j1, j1d, _, _ = point_jac(m, d, b1, D[0:3])
                j2, j2d, _, _ = point_jac(m, d, b2, D[3:6])
                rows.append(j1 - j2)
                gam.append((j1d - j2d) @ qvel)
                sizes.append(3)
            elif t == mujoco.mjtEq.mjEQ_WELD:
                j1, j1d, r1, r1d = point_jac(m, d, b1, D[3:6])
                j2, j2d, r2, r2d = point_jac(m, d, b2, D[0:3])
                rows += [j1 - j2, r1 - r2]
                gam += [(j1d - j2d) @ qvel, (r1d - r2d) @ qvel]
                sizes.append(6)
            elif t == mujoco.mjtEq.mjEQ_JOINT:
                r = np.zeros((1, m.nv))
                r[0, m.jnt_dofadr[b1]] = 1.0
                if b2 >= 0:
                    r[0, m.jnt_dofadr[b2]] -= D[1]
                rows.append(r)
                gam.append(np.zeros(1))
                sizes.append(1)
            else:
                raise ValueError("unexpected equality type %d" % t)
        J = np.vstack(rows) @ T
        g = np.concatenate(gam) + np.vstack(rows) @ Td @ v
        H = T.T @ qM @ T
        bias = T.T @ (d.qfrc_bias + qM @ Td @ v)
        n, k = m.nv, J.shape[0]
        K = np.block([[H, -J.T], [J, np.zeros((k, k))]])
        rhs = np.concatenate([tau_u - bias, -g])
        sol = np.linalg.lstsq(K, rhs, rcond=None)[0]
        qdd, lam = sol[:n], sol[n:]
        res = K @ sol - rhs
        assert np.max(np.abs(res)) < 1e-10, res
        states.append({"q": q_u.tolist(), "v": v.tolist(), "tau": tau_u.tolist(),
                       "qdd": qdd.tolist(), "generalized_force": (J.T @ lam).tolist()})
    eq_data = {m.equality(i).name: m.eq_data[i][:10].tolist() for i in range(m.neq)}
    os.makedirs(OUT, exist_ok=True)
    fx = {"model": MODEL, "nq": int(m.nq), "nv": int(m.nv),
          "active": [m.equality(i).name for i in eqs], "eq_data": eq_data, "states": states}
    with open(os.path.join(OUT, "equalities.json"), "w") as f:
        json.dump(fx, f, indent=1)
    print("wrote", os.path.join(OUT, "equalities.json"))


if __name__ == "__main__":
    main()
