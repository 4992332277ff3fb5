"""Reference motion of assets/four_bar.urdf released from rest under gravity, by an
integration independent of urdyn: minimal coordinates (the crank angle theta), the
loop closed in closed form, Lagrange's equation in theta, scipy's DOP853 at rtol 1e-12.

Planar coordinates (x, w) with w = -z: a rotation by a about +y is counter-clockwise
in (x, w), e(a) = (cos a, sin a); gravity (0, 0, -g) points along +w. Angles:
phi1 = q_crank, phi2 = q_crank + q_coupler, phi3 = q_rocker. Loop:
l1 e(phi1) + l2 e(phi2) = (d, 0) + l3 e(phi3). Each link's centre of mass lies on
its axis at r_k (the URDF's inertial origin), its inertia about +y at the centre is
iyy_k. With s = dphi/dtheta and s' = d2phi/dtheta2 (implicit differentiation of the
loop), c_k' = dc_k/dtheta, c_k'' likewise:
    m(theta) = sum m_k |c_k'|^2 + I_k s_k^2,
    m(theta) theta'' + theta'^2 sum (m_k c_k'.c_k'' + I_k s_k s_k') + V'(theta) = 0,
    V = -g sum m_k c_k,w.
Writes tests/fixtures/four_bar_reference.json: theta0, the joints' angles
q = (crank, coupler, rocker) at t = 0.5, 1, 1.5, 2 s, the energy.
Run: /work/venv/bin/python tests/oracle/four_bar_reference.py
"""
import json
import math
import os
import xml.etree.ElementTree as ET

import numpy as np
from scipy.integrate import solve_ivp

ROOT = os.path.join(os.path.dirname(__file__), "..", "..")
THETA0 = -1.0  # the crank's start angle (rad), at rest; the loop's upper branch (z > 0)
G = 9.81
TIMES = [0.5, 1.0, 1.5, 2.0]

urdf = ET.parse(os.path.join(ROOT, "assets", "four_bar.urdf")).getroot()


def xyz(el):
    return [float(x) for x in el.get("xyz").split()]


links = {}
for link in urdf.findall("link"):
    i = link.find("inertial")
    links[link.get("name")] = dict(
        m=float(i.find("mass").get("value")),
        r=xyz(i.find("origin")),
        iyy=float(i.find("inertia").get("iyy")),
    )
joints = {j.get("name"): xyz(j.find("origin")) for j in urdf.findall("joint")}
for j in urdf.findall("joint"):
    assert [float(a) for a in j.find("axis").get("xyz").split()] == [0, 1, 0]
cons = json.load(open(os.path.join(ROOT, "assets", "four_bar_constraints.json")))[0]
L1 = joints["coupler_joint"][0]
D = joints["rocker_joint"][0]
L2 = cons["point1"][0]
L3 = cons["point2"][0]
for name in ("crank", "coupler", "rocker"):
    assert links[name]["r"][1] == 0 and links[name]["r"][2] == 0, "centre off the bar's axis"
m = [links[n]["m"] for n in ("crank", "coupler", "rocker")]
r = [links[n]["r"][0] for n in ("crank", "coupler", "rocker")]
inertia = [links[n]["iyy"] for n in ("crank", "coupler", "rocker")]


def e(a):
    return np.array([math.cos(a), math.sin(a)])


def de(a):
    return np.array([-math.sin(a), math.cos(a)])


def angles(theta):
    """phi1..3 in closed form: circle-circle intersection, branch w < 0 (z > 0)."""
    a = L1 * e(theta)
    b0 = np.array([D, 0.0])
    dv = b0 - a
    dist = np.linalg.norm(dv)
    # B at distance L2 from a, L3 from b0
    x = (L2**2 - L3**2 + dist**2) / (2 * dist)
    h = math.sqrt(L2**2 - x**2)
    u = dv / dist
    n = np.array([-u[1], u[0]])
    cands = [a + x * u + h * n, a + x * u - h * n]
    b = min(cands, key=lambda p: p[1])  # w < 0: above the ground line
    phi2 = math.atan2(*(b - a)[::-1])
    phi3 = math.atan2(*(b - b0)[::-1])
    return theta, phi2, phi3


def rates(phi):
    """s = dphi/dtheta, s' = d2phi/dtheta2 by implicit differentiation of the loop."""
    p1, p2, p3 = phi
    A = np.column_stack([L2 * de(p2), -L3 * de(p3)])
    s23 = np.linalg.solve(A, -L1 * de(p1))
    s = np.array([1.0, *s23])
    # derivative of L1 de(p1) s1 + L2 de(p2) s2 - L3 de(p3) s3 = 0, de' = -e
    rhs = L1 * e(p1) * s[0] ** 2 + L2 * e(p2) * s[1] ** 2 - L3 * e(p3) * s[2] ** 2
    ds23 = np.linalg.solve(A, rhs)
    return s, np.array([0.0, *ds23])


def coms(phi, s, ds):
    p1, p2, p3 = phi
    c = [r[0] * e(p1), L1 * e(p1) + r[1] * e(p2), np.array([D, 0.0]) + r[2] * e(p3)]
    dc = [r[0] * de(p1) * s[0], L1 * de(p1) * s[0] + r[1] * de(p2) * s[1], r[2] * de(p3) * s[2]]
    ddc = [
        r[0] * (-e(p1) * s[0] ** 2 + de(p1) * ds[0]),
        L1 * (-e(p1) * s[0] ** 2 + de(p1) * ds[0]) + r[1] * (-e(p2) * s[1] ** 2 + de(p2) * ds[1]),
        r[2] * (-e(p3) * s[2] ** 2 + de(p3) * ds[2]),
    ]
    return c, dc, ddc


def rhs(_t, y):
    theta, om = y
    phi = angles(theta)
    s, ds = rates(phi)
    c, dc, ddc = coms(phi, s, ds)
    mass = sum(m[k] * dc[k] @ dc[k] + inertia[k] * s[k] ** 2 for k in range(3))
    half_dm = sum(m[k] * dc[k] @ ddc[k] + inertia[k] * s[k] * ds[k] for k in range(3))
    dV = -G * sum(m[k] * dc[k][1] for k in range(3))
    return [om, -(half_dm * om**2 + dV) / mass]


def energy(theta, om):
    phi = angles(theta)
    s, ds = rates(phi)
    c, dc, _ = coms(phi, s, ds)
    mass = sum(m[k] * dc[k] @ dc[k] + inertia[k] * s[k] ** 2 for k in range(3))
    V = -G * sum(m[k] * c[k][1] for k in range(3))
    return 0.5 * mass * om**2 + V


sol = solve_ivp(rhs, (0, TIMES[-1]), [THETA0, 0.0], method="DOP853", rtol=1e-12, atol=1e-12,
                dense_output=True)
assert sol.success
# a second run at rtol 1e-13 bounds the reference's own error
sol2 = solve_ivp(rhs, (0, TIMES[-1]), [THETA0, 0.0], method="DOP853", rtol=1e-13, atol=1e-13,
                 dense_output=True)
out = dict(source="tests/oracle/four_bar_reference.py (scipy DOP853, rtol 1e-12, minimal coordinates)",
           theta0=THETA0, gravity=G, times=TIMES, q=[], qdot_crank=[], energy=[],
           start_q=[], self_check=0.0)
p0 = angles(THETA0)
out["start_q"] = [p0[0], p0[1] - p0[0], p0[2]]
out["energy0"] = energy(THETA0, 0.0)
for t in TIMES:
    th, om = sol.sol(t)
    th2, _ = sol2.sol(t)
    out["self_check"] = max(out["self_check"], abs(th - th2))
    p = angles(th)
    out["q"].append([p[0], p[1] - p[0], p[2]])
    out["qdot_crank"].append(om)
    out["energy"].append(energy(th, om))
path = os.path.join(ROOT, "tests", "fixtures", "four_bar_reference.json")
json.dump(out, open(path, "w"), indent=1)
print(json.dumps(out, indent=1))
