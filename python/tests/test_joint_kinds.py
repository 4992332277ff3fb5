"""Joint kinds in the Pinocchio converters and quaternion checks
(mechanisms.md): a planar joint's (x, y, θ) is Pinocchio's (x, y, cos θ,
sin θ); spherical and inner floating joints' quaternions are normalised (within
1e-3 of unit norm) or refused, naming their own entries of q. The model is the
joint-kind fixture's (tests/fixtures/joints/mech.urdf, its q from Pinocchio)."""

import json
from pathlib import Path

import numpy as np
import pytest

import urdyn

ROOT = Path(__file__).resolve().parents[2]
FIX = ROOT / "tests" / "fixtures" / "joints"


def mech():
    f = json.loads((FIX / "mech.json").read_text())
    return f, urdyn.Model.from_urdf(FIX / "mech.urdf")


def test_planar_in_to_and_from_pinocchio_q():
    f, m = mech()
    q = np.array(f["states"][1]["q"])
    qp = urdyn.to_pinocchio_q(m, q)
    # two planar joints gain one coordinate each; no continuous joints here
    assert qp.shape == (m.nq + 2,)
    # walk the joints in order: Pinocchio's layout by hand
    k = 0
    for name in f["joint_names"]:
        sl = m.joint_q_slice(name)
        x = q[sl]
        if name in ("c_plane", "g_tilt"):
            want = [x[0], x[1], np.cos(x[2]), np.sin(x[2])]
        else:
            want = list(x)
        # (quaternions renormalised: equal to the last bits)
        assert np.allclose(qp[k : k + len(want)], want, rtol=0, atol=1e-15), name
        k += len(want)
    assert k == len(qp)
    back = urdyn.from_pinocchio_q(m, qp)
    assert np.allclose(back, q, rtol=0, atol=1e-15)
    # a (0, 0) planar pair names the joint
    bad = qp.copy()
    i = m.joint_q_slice("c_plane").start
    bad[i + 2 : i + 4] = 0.0
    with pytest.raises(ValueError, match="c_plane"):
        urdyn.from_pinocchio_q(m, bad)


def test_spherical_and_inner_floating_quaternions_are_normalised_or_refused():
    f, m = mech()
    q = np.array(f["states"][1]["q"])
    d = m.create_data()
    tau = urdyn.rnea(m, d, q, np.zeros(m.nv), np.zeros(m.nv))
    for name, off in (("a_shoulder", 0), ("f_wrist", 0), ("d_loose", 3)):
        at = m.joint_q_slice(name).start + off
        scaled = q.copy()
        scaled[at : at + 4] *= 1.0005  # within the tolerance: normalised
        assert np.allclose(urdyn.rnea(m, d, scaled, np.zeros(m.nv), np.zeros(m.nv)), tau, atol=1e-12)
        off_unit = q.copy()
        off_unit[at : at + 4] *= 1.1
        with pytest.raises(ValueError, match=rf"q\[{at}:{at + 4}\].*not a unit quaternion"):
            urdyn.rnea(m, d, off_unit, np.zeros(m.nv), np.zeros(m.nv))
