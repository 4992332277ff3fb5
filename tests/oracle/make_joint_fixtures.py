#!/usr/bin/env python3
"""Fixtures for the joint kinds of mechanisms.md (spherical, planar, floating
anywhere in the tree) against Pinocchio 4.1, built by `addJoint` with
JointModelSpherical / JointModelPlanar / JointModelFreeFlyer mixed with revolute
and prismatic joints. Each robot is one description that writes both the URDF
(tests/fixtures/joints/NAME.urdf) and the pin.Model, so the two agree by
construction (Pinocchio's URDF parser, urdfdom, does not know `spherical`).

Writes tests/fixtures/joints/NAME.json: per state q (urdyn's layout: a planar
joint's [x, y, θ]), v, a, tau and Pinocchio's RNEA, CRBA (H), ABA, bias,
frame Jacobians (LOCAL_WORLD_ALIGNED, LOCAL) and their time variation, centre of
mass (position, velocity, Jacobian), centroidal momentum, energies, RNEA and ABA
derivatives (tangent space), integrate / difference and their Jacobians.

Run: /work/venv/bin/python tests/oracle/make_joint_fixtures.py
"""
import json
import math
import pathlib

import numpy as np
import pinocchio as pin

OUT = pathlib.Path(__file__).resolve().parents[1] / "fixtures" / "joints"

# joints: (name, type, parent link, child link, xyz, rpy, axis)
# links: name -> (mass, com, [ixx, ixy, ixz, iyy, iyz, izz])
MECH = {
    "links": {
        "base": (2.0, [0.01, -0.02, 0.05], [0.02, 0.001, -0.002, 0.03, 0.0015, 0.025]),
        "upper": (1.2, [0.1, 0.02, -0.03], [0.01, 0.0005, 0.0, 0.012, -0.001, 0.008]),
        "slider": (0.7, [0.0, 0.05, 0.02], [0.004, 0.0, 0.0003, 0.005, 0.0, 0.006]),
        "table": (1.5, [0.03, -0.01, 0.02], [0.02, 0.002, 0.0, 0.025, 0.0, 0.03]),
        "puck": (0.4, [0.02, 0.01, -0.01], [0.002, 0.0001, 0.0, 0.0025, 0.0002, 0.003]),
        "camera": (0.3, [-0.01, 0.02, 0.04], [0.001, 0.0, 0.0001, 0.0012, 0.0, 0.0009]),
        "ball": (0.9, [0.05, 0.0, 0.1], [0.006, 0.0003, 0.0, 0.005, 0.0004, 0.004]),
        "tilted": (0.6, [0.02, 0.03, 0.0], [0.003, 0.0, 0.0002, 0.004, 0.0, 0.002]),
        "tip": (0.25, [0.0, 0.0, 0.05], [0.0008, 0.0, 0.0, 0.0009, 0.0, 0.0005]),
    },
    "joints": [
        ("a_shoulder", "spherical", "base", "upper", [0.1, 0.0, 0.3], [0.1, -0.2, 0.3], None),
        ("b_slide", "prismatic", "upper", "slider", [0.2, 0.05, 0.0], [0.0, 0.3, 0.0], [0.6, 0.8, 0.0]),
        ("c_plane", "planar", "slider", "table", [0.0, 0.1, 0.05], [0.2, 0.0, -0.1], None),
        ("d_loose", "floating", "table", "puck", [0.05, 0.0, 0.1], [0.0, 0.0, 0.4], None),
        ("e_cam", "revolute", "puck", "camera", [0.0, 0.03, 0.02], [0.0, 0.0, 0.0], [1.0, 0.0, 0.0]),
        ("f_wrist", "spherical", "base", "ball", [-0.1, 0.05, 0.2], [0.0, 0.0, 0.0], None),
        ("g_tilt", "planar", "ball", "tilted", [0.0, 0.0, 0.15], [0.3, 0.1, 0.0], [0.0, 0.6, 0.8]),
        ("h_tip", "revolute", "tilted", "tip", [0.1, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
    ],
    "root": "base",
}


def rpy_matrix(r, p, y):
    return pin.rpy.rpyToMatrix(r, p, y)


def plane_rotation(a):
    """The smallest rotation taking z onto a (a half turn about x for −z)."""
    a = np.asarray(a, float)
    a = a / np.linalg.norm(a)
    z = np.array([0.0, 0.0, 1.0])
    if np.allclose(a, z, atol=0, rtol=0):
        return np.eye(3)
    c = float(z @ a)
    if c <= -1 + 1e-12:
        return np.diag([1.0, -1.0, -1.0])
    axis = np.cross(z, a)
    axis /= np.linalg.norm(axis)
    return pin.exp3(axis * math.acos(max(-1.0, min(1.0, c))))


def fmt(x):
    return " ".join(repr(float(v)) for v in x)


def write_urdf(name, d, path):
    lines = [f'<robot name="{name}">']
    for ln, (m, com, i) in d["links"].items():
        lines.append(
            f'  <link name="{ln}"><inertial><origin xyz="{fmt(com)}" rpy="0 0 0"/>'
            f'<mass value="{m!r}"/><inertia ixx="{i[0]!r}" ixy="{i[1]!r}" ixz="{i[2]!r}" '
            f'iyy="{i[3]!r}" iyz="{i[4]!r}" izz="{i[5]!r}"/></inertial></link>'
        )
    for jn, t, par, ch, xyz, rpy, axis in d["joints"]:
        ax = f'<axis xyz="{fmt(axis)}"/>' if axis is not None else ""
        lim = '<limit lower="-2" upper="2" effort="50" velocity="5"/>' if t in ("revolute", "prismatic") else ""
        lines.append(
            f'  <joint name="{jn}" type="{t}"><parent link="{par}"/><child link="{ch}"/>'
            f'<origin xyz="{fmt(xyz)}" rpy="{fmt(rpy)}"/>{ax}{lim}</joint>'
        )
    lines.append("</robot>")
    path.write_text("\n".join(lines) + "\n")


def build(d, floating):
    """pin.Model by addJoint, in urdyn's (and Pinocchio's URDF) order: depth-first,
    children by joint name. Returns the model and per joint its q kind."""
    model = pin.Model()
    links = d["links"]
    children = {}
    for j in d["joints"]:
        children.setdefault(j[2], []).append(j)
    root = d["root"]
    # link -> (joint id, body_M_link)
    where = {}

    def inertia(ln):
        m, com, i = links[ln]
        I = np.array([[i[0], i[1], i[2]], [i[1], i[3], i[4]], [i[2], i[4], i[5]]])
        return pin.Inertia(m, np.array(com, float), I)

    if floating:
        jid = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "root_joint")
        model.appendBodyToJoint(jid, inertia(root), pin.SE3.Identity())
        where[root] = (jid, pin.SE3.Identity())
    else:
        where[root] = (0, pin.SE3.Identity())
    fid = model.addFrame(pin.Frame(root, where[root][0], 0, where[root][1], pin.FrameType.BODY))
    kinds = []
    stack = [root]
    order = []
    while stack:
        ln = stack.pop()
        order.append(ln)
        for j in sorted(children.get(ln, []), key=lambda j: j[0].encode())[::-1]:
            stack.append(j[3])
    for ln in order:
        if ln == root:
            continue
        jn, t, par, ch, xyz, rpy, axis = next(j for j in d["joints"] if j[3] == ln)
        pj, b_m_par = where[par]
        origin = b_m_par * pin.SE3(rpy_matrix(*rpy), np.array(xyz, float))
        b_m_link = pin.SE3.Identity()
        if t == "revolute":
            jm = pin.JointModelRevoluteUnaligned(np.array(axis, float) / np.linalg.norm(axis))
        elif t == "prismatic":
            jm = pin.JointModelPrismaticUnaligned(np.array(axis, float) / np.linalg.norm(axis))
        elif t == "spherical":
            jm = pin.JointModelSpherical()
        elif t == "floating":
            jm = pin.JointModelFreeFlyer()
        elif t == "planar":
            jm = pin.JointModelPlanar()
            ra = plane_rotation(axis if axis is not None else [0, 0, 1])
            origin = origin * pin.SE3(ra, np.zeros(3))
            b_m_link = pin.SE3(ra.T, np.zeros(3))
        jid = model.addJoint(pj, jm, origin, jn)
        model.appendBodyToJoint(jid, b_m_link.act(inertia(ln)), pin.SE3.Identity())
        model.addFrame(pin.Frame(ln, jid, 0, b_m_link, pin.FrameType.BODY))
        where[ln] = (jid, b_m_link)
        kinds.append((jn, t))
    return model, kinds


def to_pin_q(model, q):
    """urdyn's q (planar [x, y, θ]) to Pinocchio's (planar [x, y, cos θ, sin θ])."""
    out = []
    k = 0
    for j in model.joints[1:]:
        if j.shortname() == "JointModelPlanar":
            x, y, th = q[k:k + 3]
            out += [x, y, math.cos(th), math.sin(th)]
            k += 3
        else:
            out += list(q[k:k + j.nq])
            k += j.nq
    return np.array(out)


def from_pin_q(model, qp):
    out = []
    for j in model.joints[1:]:
        s = qp[j.idx_q:j.idx_q + j.nq]
        if j.shortname() == "JointModelPlanar":
            out += [s[0], s[1], math.atan2(s[3], s[2])]
        else:
            out += list(s)
    return np.array(out)


def random_q(model, rng):
    out = []
    for j in model.joints[1:]:
        n = j.shortname()
        if n in ("JointModelSpherical", "JointModelFreeFlyer"):
            if n == "JointModelFreeFlyer":
                out += list(rng.uniform(-0.5, 0.5, 3))
            quat = rng.normal(size=4)
            quat /= np.linalg.norm(quat)
            out += list(quat)
        elif n == "JointModelPlanar":
            out += list(rng.uniform(-0.5, 0.5, 2)) + [rng.uniform(-2.5, 2.5)]
        else:
            out += [rng.uniform(-1.5, 1.5)]
    return np.array(out)


def L(x):
    return np.asarray(x).tolist()


def state_results(model, frames, q, v, a, tau, v2):
    data = model.createData()
    qp = to_pin_q(model, q)
    r = {}
    r["tau"] = L(pin.rnea(model, data, qp, v, a))
    H = pin.crba(model, data, qp)
    H = np.triu(H) + np.triu(H, 1).T
    r["H"] = L(H)
    r["qdd"] = L(pin.aba(model, data, qp, v, tau))
    r["bias"] = L(pin.nonLinearEffects(model, data, qp, v))
    pin.computeJointJacobians(model, data, qp)
    pin.updateFramePlacements(model, data)
    pin.computeJointJacobiansTimeVariation(model, data, qp, v)
    jac = {}
    for f in frames:
        fid = model.getFrameId(f)
        jac[f] = {
            "world_aligned": L(pin.getFrameJacobian(model, data, fid, pin.LOCAL_WORLD_ALIGNED)),
            "local": L(pin.getFrameJacobian(model, data, fid, pin.LOCAL)),
            "dot_world_aligned": L(pin.getFrameJacobianTimeVariation(model, data, fid, pin.LOCAL_WORLD_ALIGNED)),
            "dot_local": L(pin.getFrameJacobianTimeVariation(model, data, fid, pin.LOCAL)),
            "placement": L(data.oMf[fid].homogeneous),
        }
    r["frames"] = jac
    pin.centerOfMass(model, data, qp, v)
    r["com"] = L(data.com[0])
    r["com_velocity"] = L(data.vcom[0])
    r["com_jacobian"] = L(pin.jacobianCenterOfMass(model, data, qp))
    pin.computeCentroidalMomentum(model, data, qp, v)
    hg = data.hg
    r["momentum_angular"] = L(hg.angular)
    r["momentum_linear"] = L(hg.linear)
    r["kinetic"] = float(pin.computeKineticEnergy(model, data, qp, v))
    r["potential"] = float(pin.computePotentialEnergy(model, data, qp))
    dq, dv, _ = pin.computeRNEADerivatives(model, data, qp, v, a)
    r["dtau_dq"] = L(dq)
    r["dtau_dv"] = L(dv)
    ddq, ddv, minv = pin.computeABADerivatives(model, data, qp, v, tau)
    r["dqdd_dq"] = L(ddq)
    r["dqdd_dv"] = L(ddv)
    minv = np.triu(minv) + np.triu(minv, 1).T
    r["minv"] = L(minv)
    q1p = pin.integrate(model, qp, v2)
    r["integrate"] = L(from_pin_q(model, q1p))
    r["difference"] = L(pin.difference(model, qp, q1p))
    r["dintegrate_dq"] = L(pin.dIntegrate(model, qp, v2, pin.ARG0))
    r["dintegrate_dv"] = L(pin.dIntegrate(model, qp, v2, pin.ARG1))
    r["ddifference_dq0"] = L(pin.dDifference(model, qp, q1p, pin.ARG0))
    r["ddifference_dq1"] = L(pin.dDifference(model, qp, q1p, pin.ARG1))
    return r


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    urdf = OUT / "mech.urdf"
    write_urdf("mech", MECH, urdf)
    for floating in (False, True):
        name = "mech_floating" if floating else "mech"
        model, kinds = build(MECH, floating)
        rng = np.random.default_rng(7 if floating else 3)
        frames = ["camera", "tip", "table", "tilted"]
        states = []
        for s in range(4):
            q = random_q(model, rng)
            if s == 0:
                q = from_pin_q(model, pin.neutral(model))
            v = rng.uniform(-1.5, 1.5, model.nv)
            a = rng.uniform(-2, 2, model.nv)
            tau = rng.uniform(-3, 3, model.nv)
            v2 = rng.uniform(-0.8, 0.8, model.nv)
            if s == 0:
                v[:] = 0
            # the planar angle after integrate stays in (−π, π) (no wrap to compare)
            states.append({
                "q": L(q), "v": L(v), "a": L(a), "tau": L(tau), "v2": L(v2),
                "expected": state_results(model, frames, q, v, a, tau, v2),
            })
        out = {
            "urdf": "tests/fixtures/joints/mech.urdf",
            "floating_base": floating,
            "nq": int(sum(3 if j.shortname() == "JointModelPlanar" else j.nq for j in model.joints[1:])),
            "nv": int(model.nv),
            "joint_names": [str(n) for n in model.names[1:]],
            "frames": frames,
            "gravity": L(model.gravity.linear),
            "states": states,
        }
        (OUT / f"{name}.json").write_text(json.dumps(out, indent=None) + "\n")
        print(name, "nq", out["nq"], "nv", model.nv, "joints", out["joint_names"])


if __name__ == "__main__":
    main()
