"""Writes python/tests/fixtures/introspection.json: what Pinocchio says about 5 robots
(joint idx_q/nq/idx_v/nv, position/effort/velocity limits, damping, friction, and each
link's own inertia: mass, centre of mass and inertia about it, in the link frame, read
from the URDF's XML and checked to sum to Pinocchio's merged body inertias), the oracle of test_user_hour.py's introspection tests. Run with the oracle Python (Pinocchio):

    /work/venv/bin/python python/tests/make_introspection_fixtures.py

CI does not run it: the JSON is committed."""

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin

ROOT = Path(__file__).resolve().parents[2]
ROBOTS = [
    ("ur5", False),
    ("panda", False),
    ("solo12", True),
    ("tiago", True),
    ("talos_reduced", True),
]


def num(x):
    """JSON numbers; ±inf (and Pinocchio's ±max double) as strings."""
    x = float(x)
    if not np.isfinite(x) or abs(x) >= 1e300:
        return "inf" if x > 0 else "-inf"
    return x


def rpy_matrix(r, p, y):
    """URDF's rpy: R = Rz(y) Ry(p) Rx(r)."""
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def xml_inertias(path):
    """Each link's own <inertial> read from the XML: (mass, com, inertia about the com in
    the link frame = R I Rᵀ)."""
    out = {}
    for link in ET.parse(path).getroot().iter("link"):
        el = link.find("inertial")
        if el is None:
            out[link.get("name")] = (0.0, np.zeros(3), np.zeros((3, 3)))
            continue
        o = el.find("origin")
        xyz = np.array([float(x) for x in (o.get("xyz", "0 0 0") if o is not None else "0 0 0").split()])
        rpy = [float(x) for x in (o.get("rpy", "0 0 0") if o is not None else "0 0 0").split()]
        i = el.find("inertia")
        g = {k: float(i.get(k, 0)) for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
        local = np.array([[g["ixx"], g["ixy"], g["ixz"]], [g["ixy"], g["iyy"], g["iyz"]],
                          [g["ixz"], g["iyz"], g["izz"]]])
        R = rpy_matrix(*rpy)
        out[link.get("name")] = (float(el.find("mass").get("value")), xyz, R @ local @ R.T)
    return out


def check_against_pinocchio(model, links):
    """Pinocchio merges a joint's links into one body: the links' inertias, moved into
    the joint frame by Pinocchio's frame placements, sum to its model.inertias[j]."""
    worst = 0.0
    for j in range(1, model.njoints):
        total = np.zeros((6, 6))
        for f in model.frames:
            if f.type == pin.FrameType.BODY and f.parentJoint == j:
                m, c, I = links[f.name]
                total += f.placement.act(pin.Inertia(m, c, I)).matrix()
        worst = max(worst, np.abs(total - model.inertias[j].matrix()).max())
    assert worst < 1e-9, worst
    return worst


out = {}
for name, floating in ROBOTS:
    path = ROOT / "assets" / "robots" / f"{name}.urdf"
    if floating:
        model = pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer(), mimic=True)
    else:
        model = pin.buildModelFromUrdf(str(path), mimic=True)
    joints = {}
    for j in range(1, model.njoints):
        jm = model.joints[j]
        jname = "base" if (floating and j == 1) else model.names[j]
        joints[jname] = {
            "idx_q": jm.idx_q, "nq": jm.nq, "idx_v": jm.idx_v, "nv": jm.nv,
            "shortname": jm.shortname(),
        }
    own = xml_inertias(path)
    worst = check_against_pinocchio(model, own)
    print(f"{name}: the links' own inertias sum to Pinocchio's body inertias within {worst:.1e}")
    links = {k: {"mass": m, "com": list(map(float, c)), "inertia": [list(map(float, r)) for r in I]}
             for k, (m, c, I) in own.items()}
    out[name] = {
        "urdf": f"assets/robots/{name}.urdf",
        "floating": floating,
        "nq": model.nq,
        "nv": model.nv,
        "joints": joints,
        "lower": [num(x) for x in model.lowerPositionLimit],
        "upper": [num(x) for x in model.upperPositionLimit],
        "effort": [num(x) for x in model.effortLimit],
        "velocity": [num(x) for x in model.velocityLimit],
        "damping": [num(x) for x in model.damping],
        "friction": [num(x) for x in model.friction],
        "links": links,
    }
dst = ROOT / "python" / "tests" / "fixtures" / "introspection.json"
dst.write_text(json.dumps(out, indent=1) + "\n")
print(f"wrote {dst} (pinocchio {pin.__version__})")
