#!/usr/bin/env python3
"""Reference derivatives of the dynamics for `urdyn eval` contract version 3, computed with
Pinocchio (the outside oracle).

For every fixture of make_fixtures.FIXTURES this writes, under tests/fixtures/<name>/:
  deriv_states.json    an `urdyn eval` input whose states all ask for "derivatives" and
                       for a few "frames", some with "fext" (floating ones with base
                       velocities and wrench)
  deriv_expected.json  the `urdyn eval` output for it: every v2 field (as make_fixtures
                       computes them) plus "derivatives" {dtau_dq, dtau_dv, dqdd_dq,
                       dqdd_dv, dqdd_dtau} and each frame's "jacobian_dot"
  deriv_meta.json      per state: cond(H), the relative disagreement of the two routes to
                       the forward-dynamics derivatives (null for mimic models), and the
                       worst relative errors against finite differences

Run through tests/oracle/run.sh (after make_fixtures.py). Deterministic: fixed seeds.

How (details and the reasons in tests/oracle/README.md §"Derivative fixtures"):
- the full, mimic-free model of make_fixtures.Robot, reduced by its G;
- dtau/dq, dtau/dv: pin.computeRNEADerivatives without fext, plus the derivative of the
  external wrenches' part -Σ J0ᵀ F0 computed here with the wrenches held fixed in world
  axes at the moving link origin (the contract). Pinocchio's fext variant holds them fixed
  in the joint frames: the script checks that Pinocchio's fext variant minus its fext-free
  one equals this script's formula for joint-frame-fixed wrenches (so both formulas are
  tied to Pinocchio), then swaps one for the other;
- dqdd/dq, dqdd/dv, dqdd/dtau: pin.computeABADerivatives (fext in joint frames) corrected
  by -H⁻¹ (world-fixed − joint-fixed) for models without mimic joints, checked against
  -H⁻¹ ∂τ/∂x at a = qdd; for mimic models that reduced formula itself (H = Gᵀ M G);
- jacobian_dot: computeJointJacobiansTimeVariation + getFrameJacobianTimeVariation
  (LOCAL_WORLD_ALIGNED) of the full model, times G; checked J a + J̇ v = the classical
  acceleration.
- Every matrix is checked against 5-point central finite differences of the contract's
  own functions (pin.rnea / solve(H, ·) with the wrenches re-expressed at each perturbed
  configuration; q moved by pin.integrate along G e_k); the worst error is printed.
"""

import json
import math
import sys
import tempfile
import zlib
from pathlib import Path

import numpy as np
import pinocchio as pin

sys.path.insert(0, str(Path(__file__).resolve().parent))
import make_fixtures as mf  # noqa: E402

# large robots: fewer states (the JSON stays small)
FEW_STATES = {"icub_reduced": [1, 3], "tiago": [1, 3], "talos_reduced": [1, 3]}
FD_STEP = 1e-3  # 5-point stencil: truncation ~ h^4, rounding ~ eps/h
FD_TOL = 1e-7  # relative to max(1, max|analytic|)
ROUTE_TOL = 1e-9  # ABA-derivative routes, relative, times cond(H) / 1e4 when larger


# --------------------------------------------------------------------------- states


def make_deriv_states(name, robot):
    """Four states (see README): 0 random, no fext; 1 fast, wrenches on a random link, the
    last link and the root; 2 no velocity key, some joints left out, a torque-only and a
    force-only wrench; 3 random, base far from the origin, a wrench on the last link."""
    rng = np.random.default_rng(zlib.crc32(name.encode()) ^ 0xD371)
    dofs, joints, links, root = robot.dofs, robot.joints, robot.links, robot.root_link

    def q_sample(n):
        j = joints[n]
        lo, hi = j["lower"], j["upper"]
        if j["type"] == "continuous" or lo is None or hi is None or not lo < hi:
            lo, hi = -math.pi, math.pi
        return float(rng.uniform(lo, hi))

    vec = lambda n, s=1.0: [float(x) for x in rng.uniform(-s, s, n)]
    pick = lambda: links[int(rng.integers(len(links)))]

    def jmap(f, drop=0.0):
        out = {}
        for n in dofs:
            val = f(n)
            if drop and rng.random() < drop:
                continue
            out[n] = val
        return out

    u = lambda s=1.0: (lambda n: float(rng.uniform(-s, s)))

    def base(vs=1.0, quat_scale=1.0, pos_scale=1.0):
        return {
            "position": vec(3, pos_scale),
            "orientation_xyzw": [float(x) * quat_scale for x in mf.rand_unit_quat(rng)],
            "linear_velocity": vec(3, vs),
            "angular_velocity": vec(3, vs),
            "linear_acceleration": vec(3),
            "angular_acceleration": vec(3),
            "force": vec(3, 5.0),
            "torque": vec(3, 2.0),
        }

    floating = robot.floating
    states = []
    s = {"q": jmap(q_sample), "v": jmap(u()), "a": jmap(u()), "tau": jmap(u())}
    if floating:
        s["base"] = base()
    s["frames"] = list(dict.fromkeys([root, links[-1], pick()]))
    states.append(s)

    s = {"q": jmap(q_sample), "v": jmap(u(5.0)), "a": jmap(u()), "tau": jmap(u())}
    if floating:
        s["base"] = base(vs=5.0, quat_scale=1.0004)
    l1 = pick()
    s["fext"] = {l1: {"force": vec(3, 5.0), "torque": vec(3, 2.0)},
                 links[-1]: {"force": vec(3, 5.0)},
                 root: {"force": vec(3, 10.0), "torque": vec(3, 3.0)}}
    s["frames"] = list(dict.fromkeys([l1, links[-1], pick()]))
    states.append(s)

    s = {"q": jmap(q_sample, 0.3), "a": jmap(u(), 0.3), "tau": jmap(u(), 0.3)}
    if floating:
        b = base()
        s["base"] = {k: b[k] for k in ("position", "orientation_xyzw", "force")}
    l1, l2 = pick(), pick()
    s["fext"] = {l1: {"torque": vec(3, 3.0)}}
    s["fext"][l2] = {"force": vec(3, 5.0)}
    s["frames"] = list(dict.fromkeys([l2, pick()]))
    states.append(s)

    s = {"q": jmap(q_sample), "v": jmap(u(2.0)), "a": jmap(u(3.0)), "tau": jmap(u(3.0))}
    if floating:
        s["base"] = base(pos_scale=20.0)
    s["fext"] = {links[-1]: {"force": vec(3, 10.0), "torque": vec(3, 2.0)}}
    s["frames"] = list(dict.fromkeys([links[-1], root, pick()]))
    states.append(s)

    for s in states:
        s["derivatives"] = True
    if name in FEW_STATES:
        states = [states[i] for i in FEW_STATES[name]]
    return states


# --------------------------------------------------------------------------- helpers


def motion_cross(a, b):
    """[v1; w1] × [v2; w2] = [w1×v2 + v1×w2; w1×w2] (Pinocchio's linear-first order)."""
    return np.concatenate([np.cross(a[3:], b[:3]) + np.cross(a[:3], b[3:]), np.cross(a[3:], b[3:])])


def force_cross(a, f):
    """[v; w] ×* [f; n] = [w×f; w×n + v×f]."""
    return np.concatenate([np.cross(a[3:], f[:3]), np.cross(a[3:], f[3:]) + np.cross(a[:3], f[:3])])


class Deriv:
    """The derivative oracle around a make_fixtures.Robot."""

    def __init__(self, robot):
        self.r = robot
        m = robot.model
        self.d = m.createData()
        self.dk = m.createData()  # kinematics only
        # joint owning each tangent column, and each joint's ancestors (itself included)
        self.col_joint = np.zeros(m.nv, dtype=int)
        for i in range(1, m.njoints):
            jm = m.joints[i]
            self.col_joint[jm.idx_v:jm.idx_v + jm.nv] = i
        self.anc = {}
        for i in range(m.njoints):
            s, k = set(), i
            while k > 0:
                s.add(k)
                k = m.parents[k]
            self.anc[i] = s
        # A[k, j]: column k's joint is an ancestor of (or is) column j's joint
        self.A = np.array([[self.col_joint[k] in self.anc[self.col_joint[j]] for j in range(m.nv)]
                           for k in range(m.nv)])

    # ---- the state as Pinocchio vectors (as make_fixtures.Robot.evaluate builds them)
    def vectors(self, state):
        r, m = self.r, self.r.model
        q, v, a = pin.neutral(m), np.zeros(m.nv), np.zeros(m.nv)
        tau_in = np.zeros(r.nv_red)
        pos, quat, b = r.base_pose(state)
        if r.floating:
            q[0:3], q[3:7] = pos, quat
            v[0:3] = b.get("linear_velocity", [0.0] * 3)
            v[3:6] = b.get("angular_velocity", [0.0] * 3)
            a[0:3] = b.get("linear_acceleration", [0.0] * 3)
            a[3:6] = b.get("angular_acceleration", [0.0] * 3)
            tau_in[0:3] = b.get("force", [0.0] * 3)
            tau_in[3:6] = b.get("torque", [0.0] * 3)
        full = r.full_values(state)
        for name, iq, iv, nq in r.pjoints:
            qq, vv, aa = full[name]
            if nq == 2:
                q[iq], q[iq + 1] = math.cos(qq), math.sin(qq)
            else:
                q[iq] = qq
            v[iv], a[iv] = vv, aa
        nb = 6 if r.floating else 0
        for k, n in enumerate(r.dofs):
            tau_in[nb + k] = state.get("tau", {}).get(n, 0.0)
        return q, v, a, tau_in

    def wrenches(self, state):
        """[(joint id, frame id, force, torque)] in world axes, links on the universe dropped."""
        m = self.r.model
        out = []
        for link, w in state.get("fext", {}).items():
            fid = m.getFrameId(link, pin.BODY)
            jid = m.frames[fid].parentJoint
            if jid == 0:
                continue  # welded to the world: no effect
            out.append((jid, fid, np.array(w.get("force", [0.0] * 3), dtype=float),
                        np.array(w.get("torque", [0.0] * 3), dtype=float)))
        return out

    def fext_local(self, q, ws):
        """The world wrenches at configuration q as Pinocchio's joint-frame fext."""
        m, d = self.r.model, self.dk
        pin.framesForwardKinematics(m, d, q)
        fext = pin.StdVec_Force()
        for _ in range(m.njoints):
            fext.append(pin.Force.Zero())
        for jid, fid, f, t in ws:
            p = d.oMf[fid].translation
            fext[jid] = fext[jid] + d.oMi[jid].actInv(pin.Force(f, t + np.cross(p, f)))
        return fext

    # ---- the contract's functions (full model; reduced by G by the callers)
    def tau_full(self, q, v, a, ws):
        return pin.rnea(self.r.model, self.dk, q, v, a, self.fext_local(q, ws)).copy()

    def H_red(self, q):
        M = pin.crba(self.r.model, self.dk, q).copy()
        M = np.triu(M) + np.triu(M, 1).T
        return self.r.G.T @ M @ self.r.G

    def qdd_red(self, q, v, tau_in, ws):
        G = self.r.G
        bias = G.T @ self.tau_full(q, v, np.zeros(self.r.model.nv), ws)
        return np.linalg.solve(self.H_red(q), tau_in - bias)

    # ---- the external wrenches' part of dtau/dq, analytic
    def ext_dq(self, q, ws):
        """d/dq of -Σ J0ᵀ F0 (full model): F0 = [f; τ + p × f] the world wrench at the world
        origin. World-fixed (the contract): dF0/dq_k = [0; ∂p/∂q_k × f]. Joint-fixed
        (Pinocchio's fext): dF0/dq_k = S_k ×* F0. In both, ∂S_j/∂q_k = S_k × S_j when k's
        joint is j's or an ancestor of it."""
        m, d = self.r.model, self.dk
        nv = m.nv
        pin.computeJointJacobians(m, d, q)
        pin.updateFramePlacements(m, d)
        S = d.J.copy()  # world spatial axes, 6 × nv
        world, local = np.zeros((nv, nv)), np.zeros((nv, nv))
        for jid, fid, f, t in ws:
            p = d.oMf[fid].translation.copy()
            F0 = np.concatenate([f, t + np.cross(p, f)])
            Jf = pin.getFrameJacobian(m, d, fid, pin.LOCAL_WORLD_ALIGNED)
            sup = [c for c in range(nv) if self.col_joint[c] in self.anc[jid]]
            for k in sup:
                dF_world = np.concatenate([np.zeros(3), np.cross(Jf[:3, k], f)])
                dF_local = force_cross(S[:, k], F0)
                for j in sup:
                    t1 = -motion_cross(S[:, k], S[:, j]) @ F0 if self.A[k, j] else 0.0
                    world[j, k] += t1 - S[:, j] @ dF_world
                    local[j, k] += t1 - S[:, j] @ dF_local
        return world, local

    # ---- the fixture values
    def derivatives(self, state):
        r, m, d, G = self.r, self.r.model, self.d, self.r.G
        q, v, a, tau_in = self.vectors(state)
        ws = self.wrenches(state)
        fl = self.fext_local(q, ws)
        zero_f = self.fext_local(q, [])
        ext_w, ext_l = self.ext_dq(q, ws)

        # RNEA derivatives at (q, v, a): Pinocchio without fext + the world-fixed part
        dq0, dv0, _ = (x.copy() for x in pin.computeRNEADerivatives(m, d, q, v, a))
        dqp, dvp, _ = (x.copy() for x in pin.computeRNEADerivatives(m, d, q, v, a, fl))
        sc = max(1.0, float(np.max(np.abs(dqp))))
        tie = float(np.max(np.abs((dqp - dq0) - ext_l))) / sc
        assert tie < 1e-11, f"joint-fixed fext formula vs Pinocchio: {tie}"
        assert np.max(np.abs(dvp - dv0)) <= 1e-12 * max(1.0, float(np.max(np.abs(dv0))))
        dtau_dq = G.T @ (dq0 + ext_w) @ G
        dtau_dv = G.T @ dv0 @ G

        # forward dynamics: qdd, then its derivatives
        H = self.H_red(q)
        Hinv = np.linalg.inv(H)
        Hinv = 0.5 * (Hinv + Hinv.T)
        qdd = self.qdd_red(q, v, tau_in, ws)
        qdd_full = G @ qdd
        dqa, dva, _ = (x.copy() for x in pin.computeRNEADerivatives(m, d, q, v, qdd_full))
        dqdd_dq_a = -Hinv @ (G.T @ (dqa + ext_w) @ G)
        dqdd_dv_a = -Hinv @ (G.T @ dva @ G)
        cond = float(np.linalg.cond(H))
        route = None
        if not r.reduced:
            ddq_dq, ddq_dv, Minv = (x.copy() for x in pin.computeABADerivatives(m, d, q, v, tau_in, fl))
            Minv = np.triu(Minv) + np.triu(Minv, 1).T
            qdd_aba = pin.aba(m, d, q, v, tau_in, fl)
            dqdd_dq = ddq_dq - Minv @ (ext_w - ext_l)
            dqdd_dv, dqdd_dtau = ddq_dv, Minv
            tol = ROUTE_TOL * max(1.0, cond / 1e4)
            route = 0.0
            for x, y in ((dqdd_dq, dqdd_dq_a), (dqdd_dv, dqdd_dv_a), (Minv, Hinv), (qdd_aba, qdd)):
                e = float(np.max(np.abs(x - y))) / max(1.0, float(np.max(np.abs(y))))
                route = max(route, e)
            assert route < tol, f"ABA derivatives: two routes differ by {route} (tol {tol})"
        else:
            dqdd_dq, dqdd_dv, dqdd_dtau = dqdd_dq_a, dqdd_dv_a, Hinv

        # frames' J̇ (world-aligned), full model times G
        pin.computeJointJacobiansTimeVariation(m, d, q, v)
        pin.updateFramePlacements(m, d)
        jdots = {}
        for link in state.get("frames", []):
            fid = m.getFrameId(link, pin.BODY)
            jdots[link] = pin.getFrameJacobianTimeVariation(m, d, fid, pin.LOCAL_WORLD_ALIGNED).copy() @ G
        out = {"dtau_dq": dtau_dq, "dtau_dv": dtau_dv, "dqdd_dq": dqdd_dq, "dqdd_dv": dqdd_dv,
               "dqdd_dtau": dqdd_dtau}
        return out, jdots, (q, v, a, tau_in, ws, qdd), cond, route

    # ---- finite-difference checks
    def fd_check(self, out, jdots, vecs, result):
        """Worst error of each matrix against 5-point central differences, relative to
        max(1, max|analytic|)."""
        r, m, G = self.r, self.r.model, self.r.G
        q, v, a, tau_in, ws, qdd = vecs
        h = FD_STEP

        def stencil(f):
            return (f(-2 * h) - 8 * f(-h) + 8 * f(h) - f(2 * h)) / (12 * h)

        def col_q(fun, k):
            dq = G[:, k]
            return stencil(lambda e: fun(pin.integrate(m, q, e * dq), v))

        def col_v(fun, k):
            dv = G[:, k]
            return stencil(lambda e: fun(q, v + e * dv))

        tau_r = lambda qq, vv: G.T @ self.tau_full(qq, vv, a, ws)
        qdd_r = lambda qq, vv: self.qdd_red(qq, vv, tau_in, ws)
        n = r.nv_red
        fd = {
            "dtau_dq": np.column_stack([col_q(tau_r, k) for k in range(n)]),
            "dtau_dv": np.column_stack([col_v(tau_r, k) for k in range(n)]),
            "dqdd_dq": np.column_stack([col_q(qdd_r, k) for k in range(n)]),
            "dqdd_dv": np.column_stack([col_v(qdd_r, k) for k in range(n)]),
        }
        errs = {}
        for key, F in fd.items():
            A = out[key]
            errs[key] = float(np.max(np.abs(F - A))) / max(1.0, float(np.max(np.abs(A))))
        H = self.H_red(q)
        errs["dqdd_dtau"] = float(np.max(np.abs(out["dqdd_dtau"] @ H - np.eye(n))))
        # J̇ against d/dε J(q ⊕ ε v) and the classical acceleration J a + J̇ v
        vr = np.linalg.lstsq(G, v, rcond=None)[0]
        ar = np.linalg.lstsq(G, a, rcond=None)[0]
        dk = self.dk
        ej, ea = 0.0, 0.0
        for link, Jd in jdots.items():
            fid = m.getFrameId(link, pin.BODY)

            def J_at(e):
                qq = pin.integrate(m, q, e * v)
                pin.computeJointJacobians(m, dk, qq)
                pin.updateFramePlacements(m, dk)
                return pin.getFrameJacobian(m, dk, fid, pin.LOCAL_WORLD_ALIGNED) @ G

            F = stencil(J_at)
            ej = max(ej, float(np.max(np.abs(F - Jd))) / max(1.0, float(np.max(np.abs(Jd)))))
            fr = result["frames"][link]
            J = np.array(fr["jacobian"])
            acc = np.concatenate([fr["acceleration"]["linear"], fr["acceleration"]["angular"]])
            ea = max(ea, float(np.max(np.abs(J @ ar + Jd @ vr - acc))) / max(1.0, float(np.max(np.abs(acc)))))
        errs["jacobian_dot"] = ej
        errs["J a + Jdot v"] = ea
        return errs


# --------------------------------------------------------------------------- main


def main():
    import logging
    logging.getLogger("yourdfpy").setLevel(logging.ERROR)
    print(f"pinocchio {pin.__version__}, numpy {np.__version__}")
    rows = lambda M: [[float(x) for x in r] for r in M]
    keys = ["dtau_dq", "dtau_dv", "dqdd_dq", "dqdd_dv", "dqdd_dtau", "jacobian_dot", "J a + Jdot v"]
    print(f"{'fixture':22s} {'nv':>3s} {'#st':>3s} {'cond(H)':>9s} {'routes':>8s}  worst vs finite differences: "
          + ", ".join(keys))
    worst_all = 0.0
    with tempfile.TemporaryDirectory() as tmp:
        for name, urdf_rel, floating, gravity in mf.FIXTURES:
            robot = mf.Robot(urdf_rel, floating, tmp)
            oracle = Deriv(robot)
            states = make_deriv_states(name, robot)
            # the states as urdyn reads them (JSON round trip: the same doubles)
            states = json.loads(json.dumps(states))
            g = gravity if gravity is not None else mf.G_DOWN
            results, errs, conds, routes = [], {k: 0.0 for k in keys}, [], []
            per_state = []
            for st in states:
                res, _, _, _ = robot.evaluate(st, g)
                out, jdots, vecs, cond, route = oracle.derivatives(st)
                # evaluate() set the model's gravity; derivatives() and the checks use it
                e = oracle.fd_check(out, jdots, vecs, res)
                for k in keys:
                    errs[k] = max(errs[k], e[k])
                conds.append(cond)
                if route is not None:
                    routes.append(route)
                per_state.append({"cond_H": cond, "aba_routes": route,
                                  "fd": {k: e[k] for k in keys}})
                res["derivatives"] = {k: rows(M) for k, M in out.items()}
                for link, Jd in jdots.items():
                    res["frames"][link]["jacobian_dot"] = rows(Jd)
                results.append(res)
            worst = max(errs[k] for k in keys[:4] + keys[5:6])
            assert worst < FD_TOL, f"{name}: finite differences disagree: {errs}"
            assert errs["dqdd_dtau"] < 1e-9 * max(1.0, max(conds) / 1e4), errs
            assert errs["J a + Jdot v"] < 1e-11, errs
            worst_all = max(worst_all, worst)
            inp = {"states": states} if gravity is None else {"gravity": gravity, "states": states}
            out_dir = mf.FIXTURE_DIR / name
            mf.dump(out_dir / "deriv_states.json", inp)
            mf.dump(out_dir / "deriv_expected.json", {"dof_names": robot.dofs, "results": results})
            mf.dump(out_dir / "deriv_meta.json", {"urdf": urdf_rel, "floating_base": floating,
                                                  "states": per_state})
            rt = f"{max(routes):.1e}" if routes else "reduced"
            print(f"{name:22s} {robot.nv_red:3d} {len(states):3d} {max(conds):9.2e} {rt:>8s}  "
                  + "  ".join(f"{errs[k]:.1e}" for k in keys))
    print(f"worst relative error against finite differences over every fixture: {worst_all:.1e}")


if __name__ == "__main__":
    main()
