#!/usr/bin/env python3
"""Fixtures for loop constraints (mechanisms.md §"Loop constraints").

Run: /work/venv/bin/python tests/oracle/make_constraint_fixtures.py
Writes tests/fixtures/constraints/NAME.json, read by tests/constraint_dynamics.rs.

Truth, independently of urdyn:
- q̈, J_cᵀλ (and λ when J_c has full row rank): our own numpy KKT on Pinocchio's
  H (crba), C (nle), frame Jacobians (LOCAL_WORLD_ALIGNED) and classical
  accelerations of added operational frames; λ least norm by the pseudo-inverse.
  Checked against pin.constraintDynamics (RigidConstraintModel CONTACT_3D /
  CONTACT_6D, LOCAL_WORLD_ALIGNED) at every state for point rows and at states
  satisfied at position and velocity level for frame rows (mechanisms.md:
  Pinocchio's 6-D rows use spatial accelerations elsewhere); μ > 0 on redundant
  rows (its proximal solver needs it).
- derivatives: Richardson-extrapolated central differences of that KKT q̈ along
  pin.integrate (tangent space), world anchors held fixed; checked against
  pin.computeConstraintDynamicsDerivatives where its convention is the
  contract's (point rows; 6-D rows at satisfied states, fixed base).
"""
import json
import os
import sys

import numpy as np
import pinocchio as pin

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
OUT = os.path.join(ROOT, "tests", "fixtures", "constraints")
LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
rng = np.random.default_rng(7)


def load(path, floating):
    full = os.path.join(ROOT, path)
    if floating:
        return pin.buildModelFromUrdf(full, pin.JointModelFreeFlyer())
    return pin.buildModelFromUrdf(full)


def quat_to_rot(q):
    x, y, z, w = q
    return pin.Quaternion(w, x, y, z).normalized().toRotationMatrix()


class Sys:
    """A Pinocchio model and the contract's constraints on it."""

    def __init__(self, path, floating, constraints):
        self.path, self.floating = path, floating
        self.model = load(path, floating)
        self.cons = constraints
        self.sides = []  # per constraint: (frame id 1, frame id 2 or None) as added op frames
        m = self.model
        for k, c in enumerate(constraints):
            if c["kind"] == "joint":
                j1 = m.getJointId(c["joint1"])
                j2 = m.getJointId(c["joint2"]) if "joint2" in c else None
                self.sides.append(("joint", m.joints[j1].idx_v, m.joints[j1].idx_q,
                                   None if j2 is None else (m.joints[j2].idx_v, m.joints[j2].idx_q)))
                continue
            fids = []
            for s in ("1", "2"):
                link = c.get("link" + s)
                if c["kind"] == "point":
                    local = pin.SE3(np.eye(3), np.array(c.get("point" + s, [0, 0, 0]), float))
                else:
                    fr = c.get("frame" + s, {})
                    local = pin.SE3(quat_to_rot(fr.get("orientation_xyzw", [0, 0, 0, 1])),
                                    np.array(fr.get("position", [0, 0, 0]), float))
                if link is None or link == "world":
                    fids.append(("world", local))
                    continue
                fid = m.getFrameId(link)
                f = m.frames[fid]
                placement = f.placement * local
                new = pin.Frame(f"c{k}_{s}", f.parentJoint, fid, placement, pin.FrameType.OP_FRAME)
                fids.append(("frame", m.addFrame(new)))
            self.sides.append((c["kind"], fids))
        self.data = m.createData()

    # ------------------------------------------------------------ rows
    def rows(self, q, v, anchors):
        """J_c, γ_c (classical accelerations at q̈ = 0), violation per constraint."""
        m, d = self.model, self.data
        pin.forwardKinematics(m, d, q, v, np.zeros(m.nv))
        pin.computeJointJacobians(m, d, q)
        pin.updateFramePlacements(m, d)
        J, g, viol = [], [], []
        for k, side in enumerate(self.sides):
            if side[0] == "joint":
                _, v1, q1, second = side
                c = self.cons[k]
                row = np.zeros(m.nv)
                row[v1] = 1.0
                r = q[q1] - c.get("offset", 0.0)
                if second is not None:
                    row[second[0]] -= c.get("ratio", 1.0)
                    r -= c.get("ratio", 1.0) * q[second[1]]
                J.append(row[None, :])
                g.append(np.zeros(1))
                viol.append(r)
                continue
            kind, fids = side
            nr = 3 if kind == "point" else 6
            Js, gs, Ms = [], [], []
            for which, (t, x) in enumerate(fids):
                if t == "world":
                    Js.append(np.zeros((6, m.nv)))
                    gs.append(np.zeros(6))
                    Ms.append(anchors[k] if anchors.get(k) is not None else x)
                    continue
                Js.append(pin.getFrameJacobian(m, d, x, LWA))
                a = pin.getFrameClassicalAcceleration(m, d, x, LWA)
                gs.append(np.concatenate([a.linear, a.angular]))
                Ms.append(d.oMf[x])
            J.append((Js[0] - Js[1])[:nr])
            g.append((gs[0] - gs[1])[:nr])
            dist = np.linalg.norm(Ms[0].translation - Ms[1].translation)
            if kind == "point":
                viol.append(dist)
            else:
                ang = np.linalg.norm(pin.log3(Ms[0].rotation @ Ms[1].rotation.T))
                viol.append(max(dist, ang))
        return np.vstack(J), np.concatenate(g), viol

    def anchors_at(self, q):
        """World sides left out: where side 1 is at q (a hold)."""
        m, d = self.model, self.data
        pin.framesForwardKinematics(m, d, q)
        out = {}
        for k, side in enumerate(self.sides):
            if side[0] == "joint":
                continue
            (t1, x1), (t2, x2) = side[1]
            c = self.cons[k]
            key2 = "point2" if c["kind"] == "point" else "frame2"
            if t2 == "world" and key2 not in c:
                out[k] = d.oMf[x1].copy()
        return out

    # ------------------------------------------------------------ KKT
    def kkt(self, q, v, tau, anchors):
        m, d = self.model, self.data
        H = pin.crba(m, d, q)
        H = np.triu(H) + np.triu(H, 1).T
        C = pin.nle(m, d, q, v)
        J, g, viol = self.rows(q, v, anchors)
        Hi = np.linalg.inv(H)
        qdd0 = Hi @ (tau - C)
        Y = Hi @ J.T
        K = J @ Y
        r = -g - J @ qdd0
        lam = np.linalg.pinv(K, rcond=1e-10, hermitian=True) @ r
        res = K @ lam - r
        assert np.abs(res).max() < 1e-7 * (np.abs(r).max() + np.abs(g).max() + 1e-300), res
        qdd = qdd0 + Y @ lam
        full = np.linalg.matrix_rank(J, tol=1e-9 * max(1.0, np.abs(J).max())) == J.shape[0]
        return qdd, J.T @ lam, lam, full, viol, J

    # ------------------------------------------------------------ Pinocchio
    def pin_models(self, anchors):
        m = self.model
        out = []
        for k, side in enumerate(self.sides):
            if side[0] == "joint":
                return None
            kind, fids = side
            ct = pin.ContactType.CONTACT_3D if kind == "point" else pin.ContactType.CONTACT_6D
            pl = []
            for t, x in fids:
                if t == "world":
                    pl.append((0, anchors[k] if anchors.get(k) is not None else x))
                else:
                    f = m.frames[x]
                    pl.append((f.parentJoint, f.placement))
            out.append(pin.RigidConstraintModel(ct, m, pl[0][0], pl[0][1], pl[1][0], pl[1][1], LWA))
        return out

    def pinocchio(self, q, v, tau, anchors, mu):
        cms = self.pin_models(anchors)
        if cms is None:
            return None
        m = self.model
        d = m.createData()
        cml = pin.StdVec_RigidConstraintModel()
        for c in cms:
            cml.append(c)
        cms = cml
        cds = pin.StdVec_RigidConstraintData()
        for c in cms:
            cds.append(c.createData())
        pin.initConstraintDynamics(m, d, cms, cds)
        prox = pin.ProximalSettings(1e-14, mu, 200)
        qdd = pin.constraintDynamics(m, d, q, v, tau, cms, cds, prox)
        derivs = pin.computeConstraintDynamicsDerivatives(m, d, cms, cds, prox)
        return qdd.copy(), [x.copy() for x in derivs[:3]]

    # ------------------------------------------------------------ FD
    def fd(self, q, v, tau, anchors):
        """Richardson-extrapolated central differences of the KKT q̈."""
        m = self.model
        f = lambda qq, vv, tt: self.kkt(qq, vv, tt, anchors)[0]
        out = []
        for wrt in ("q", "v", "tau"):
            D = np.zeros((m.nv, m.nv))
            for k in range(m.nv):
                def at(eps):
                    e = np.zeros(m.nv)
                    e[k] = eps
                    if wrt == "q":
                        return f(pin.integrate(m, q, e), v, tau)
                    if wrt == "v":
                        return f(q, v + e, tau)
                    return f(q, v, tau + e)
                h = 1e-3
                d1 = (at(h) - at(-h)) / (2 * h)
                d2 = (at(h / 2) - at(-h / 2)) / h
                d4 = (at(h / 4) - at(-h / 4)) / (h / 2)
                r1 = (4 * d2 - d1) / 3
                r2 = (4 * d4 - d2) / 3
                D[:, k] = (16 * r2 - r1) / 15
            out.append(D)
        return out

    # ------------------------------------------------------------ states
    def random_q(self):
        m = self.model
        q = pin.randomConfiguration(m, -np.ones(m.nq) * 1.0, np.ones(m.nq) * 1.0)
        if self.floating:
            q[:3] = rng.uniform(-0.3, 0.3, 3)
        return q

    def satisfied_q(self, q0, anchors):
        """Gauss–Newton on the position error from q0 (point rows: positions)."""
        m = self.model
        q = q0.copy()
        for _ in range(100):
            err = []
            pin.framesForwardKinematics(m, self.data, q)
            for k, side in enumerate(self.sides):
                kind, fids = side
                Ms = [anchors.get(k, x) if t == "world" else self.data.oMf[x] for t, x in fids]
                err.append((Ms[0].translation - Ms[1].translation))
                if kind == "frame":
                    err.append(pin.log3(Ms[0].rotation @ Ms[1].rotation.T))
            e = np.concatenate(err)
            if np.abs(e).max() < 1e-14:
                break
            J, _, _ = self.rows(q, np.zeros(m.nv), anchors)
            q = pin.integrate(m, q, -np.linalg.pinv(J) @ e)
        return q


def case(name, path, floating, constraints, nrandom, satisfied=0, pin_check=True, mu=0.0,
         fixed_states=()):
    s = Sys(path, floating, constraints)
    m = s.model
    states = []
    qs = [(np.array(q), True) for q in fixed_states]
    for i in range(satisfied):
        q = s.satisfied_q(s.random_q() * 0.3 + pin.neutral(m) * 0.7 if not floating else pin.neutral(m), {})
        qs.append((q, True))
    for i in range(nrandom):
        qs.append((s.random_q(), False))
    worst_pin = 0.0
    worst_pin_d = 0.0
    for q, sat in qs:
        anchors = s.anchors_at(q)
        J, _, _ = s.rows(q, np.zeros(m.nv), anchors)
        v = rng.uniform(-1, 1, m.nv)
        if sat:
            # a velocity that satisfies the rows: projected on J's null space
            v = v - np.linalg.pinv(J) @ (J @ v)
        tau = rng.uniform(-2, 2, m.nv)
        qdd, gf, lam, full, viol, _ = s.kkt(q, v, tau, anchors)
        dq, dv, dt = s.fd(q, v, tau, anchors)
        st = {"q": q.tolist(), "v": v.tolist(), "tau": tau.tolist(), "satisfied": sat,
              "qdd": qdd.tolist(), "generalized_force": gf.tolist(),
              "lambda": lam.tolist() if full else None, "violation": [float(x) for x in viol],
              "dqdd_dq": dq.tolist(), "dqdd_dv": dv.tolist(), "dqdd_dtau": dt.tolist(),
              "anchors": {str(k): {"position": a.translation.tolist(),
                                   "rotation": a.rotation.tolist()} for k, a in anchors.items()}}
        all_point = all(c["kind"] == "point" for c in constraints)
        if pin_check and (all_point or sat):
            r = s.pinocchio(q, v, tau, anchors, mu)
            if r is not None:
                pqdd, pd = r
                e = np.abs(pqdd - qdd).max() / (1 + np.abs(qdd).max())
                worst_pin = max(worst_pin, e)
                assert e < 1e-8, (name, e)
                st["pinocchio_qdd"] = pqdd.tolist()
                if mu == 0.0:
                    de = max(np.abs(a - b).max() / (1 + np.abs(b).max()) for a, b in zip(pd, (dq, dv, dt)))
                    worst_pin_d = max(worst_pin_d, de)
                    st["pinocchio_derivatives_rel_err"] = float(de)
        states.append(st)
    fix = {"robot": path, "floating_base": floating, "gravity": [0, 0, -9.81],
           "constraints": constraints, "states": states}
    os.makedirs(OUT, exist_ok=True)
    with open(os.path.join(OUT, name + ".json"), "w") as fh:
        json.dump(fix, fh)
    print(f"{name}: nv={m.nv} rows={sum(3 if c['kind']=='point' else 6 if c['kind']=='frame' else 1 for c in constraints)} "
          f"states={len(states)} pinocchio qdd rel err {worst_pin:.2e}, derivatives {worst_pin_d:.2e}")


def talos_no_mimic():
    """talos_reduced with its gripper's mimic joints made fixed (Pinocchio's URDF
    parser would make them independent joints): the same robot for both."""
    import re
    src = open(os.path.join(ROOT, "assets/robots/talos_reduced.urdf")).read()
    names = set()
    for mj in re.finditer(r'<joint name="([^"]+)"[^>]*>(.*?)</joint>', src, re.S):
        if "<mimic" in mj.group(2):
            names.add(mj.group(1))
    def fix(mj):
        body = mj.group(0)
        if mj.group(1) in names:
            body = re.sub(r'type="[^"]+"', 'type="fixed"', body, count=1)
            body = re.sub(r"<mimic[^>]*/>", "", body)
        return body
    out = re.sub(r'<joint name="([^"]+)"[^>]*>.*?</joint>', fix, src, flags=re.S)
    path = "tests/fixtures/constraints/talos_reduced_locked_grippers.urdf"
    os.makedirs(OUT, exist_ok=True)
    open(os.path.join(ROOT, path), "w").write(out)
    return path


def main():
    planar = [{"name": "loop", "kind": "point", "link1": "coupler_link", "point1": [0.5, 0, 0],
               "link2": "rocker_link", "point2": [0.4, 0, 0]}]
    case("four_bar_planar", "tests/urdf/four_bar_planar.urdf", False, planar, 2, satisfied=1, mu=1e-9)
    case("four_bar_planar_twice", "tests/urdf/four_bar_planar.urdf", False,
         planar + [dict(planar[0], name="loop_again")], 2, satisfied=1, mu=1e-9)
    spatial = [{"name": "ball", "kind": "point", "link1": "coupler_link", "point1": [0, 0, 0.4],
                "link2": "rocker_link", "point2": [0, 0, 0.5]}]
    case("four_bar_spatial", "tests/urdf/four_bar_spatial.urdf", False, spatial, 2, satisfied=1)
    feet = [{"name": f, "kind": "point", "link1": f} for f in ("FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT")]
    case("solo12_feet", "assets/robots/solo12.urdf", True, feet, 3)
    talos = talos_no_mimic()
    # the hands welded where they are in a fixed pose q0 (which then satisfies it)
    tm = load(talos, False)
    td = tm.createData()
    q0 = pin.neutral(tm) + np.random.default_rng(3).uniform(-0.3, 0.3, tm.nq)
    pin.framesForwardKinematics(tm, td, q0)
    l1 = pin.SE3(np.eye(3), np.array([0, 0, -0.1]))
    m1 = td.oMf[tm.getFrameId("gripper_left_base_link")] * l1
    m2 = td.oMf[tm.getFrameId("gripper_right_base_link")].inverse() * m1
    qt = pin.Quaternion(m2.rotation)
    hands = [{"name": "hands", "kind": "frame", "link1": "gripper_left_base_link",
              "frame1": {"position": [0, 0, -0.1]}, "link2": "gripper_right_base_link",
              "frame2": {"position": m2.translation.tolist(),
                         "orientation_xyzw": [qt.x, qt.y, qt.z, qt.w]}}]
    case("talos_hands", talos, False, hands, 2, fixed_states=[q0])
    gear = [{"name": "gear", "kind": "joint", "joint1": "elbow_joint", "joint2": "shoulder_lift_joint",
             "ratio": -2.0, "offset": 0.1}]
    case("ur5_gear", "assets/robots/ur5.urdf", False, gear, 3, pin_check=False)


if __name__ == "__main__":
    main()
