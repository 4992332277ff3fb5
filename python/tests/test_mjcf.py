"""MJCF from Python (mjcf.md §"Entry points"): Model.from_mjcf /
from_mjcf_string / from_file against MuJoCo 4.0's numbers (the committed
fixtures tests/fixtures/mjcf/oracle/, tests/oracle/make_mjcf_fixtures.py): H with
the joints' armature (MuJoCo's qM), the bias, inverse and forward dynamics; the
MuJoCo state converters against their closed forms."""

import json
import pickle
from pathlib import Path

import numpy as np
import pytest

import urdyn

ROOT = Path(__file__).resolve().parents[2]
MJ = ROOT / "tests" / "fixtures" / "mjcf"


def fixture(name):
    f = json.loads((MJ / "oracle" / f"{name}.json").read_text())
    return f, MJ / f["model"]


def close(got, want, tol=1e-10):
    got, want = np.asarray(got), np.asarray(want)
    assert got.shape == want.shape
    scale = max(1.0, np.max(np.abs(want)))
    err = np.max(np.abs(got - want)) / scale
    assert err < tol, err


@pytest.mark.parametrize(
    "name", ["gymnasium_ant", "dm_control_humanoid", "dm_control_cartpole", "dm_control_acrobot"]
)
def test_mjcf_dynamics_matches_mujoco(name):
    f, path = fixture(name)
    m = urdyn.Model.from_mjcf(path)
    assert (m.nq, m.nv) == (f["nq"], f["nv"])
    d = m.create_data()
    for s in f["states"]:
        close(urdyn.crba(m, d, s["q"]), s["mass_matrix"])
        close(urdyn.nonlinear_effects(m, d, s["q"], s["v"]), s["bias"])
        close(urdyn.rnea(m, d, s["q"], s["v"], s["a"]), s["tau"])
        close(urdyn.forward_dynamics(m, d, s["q"], s["v"], s["tau_in"]), s["qdd"])


def test_ant_armature_is_in_the_mass_matrix():
    f, path = fixture("gymnasium_ant")
    m = urdyn.Model.from_mjcf(path)
    arm = m.armature
    assert np.max(arm) == 1.0  # the ant's leg joints
    d = m.create_data()
    s = f["states"][0]
    # without the armature, H would differ from MuJoCo's qM by exactly A
    h = urdyn.crba(m, d, s["q"])
    close(h - np.diag(arm), np.asarray(s["mass_matrix"]) - np.diag(arm))
    assert np.max(np.abs(np.diag(h) - np.diag(s["mass_matrix"]))) < 1e-10


def test_from_file_string_and_pickle_agree():
    f, path = fixture("dm_control_cartpole")
    a = urdyn.Model.from_mjcf(path)
    b = urdyn.Model.from_file(path)
    c = urdyn.Model.from_mjcf_string(path.read_text(), base_dir=path.parent)
    e = pickle.loads(pickle.dumps(a))
    s = f["states"][1]
    h = [urdyn.crba(m, m.create_data(), s["q"]) for m in (a, b, c, e)]
    for x in h[1:]:
        assert np.array_equal(x, h[0])
    assert a.q_names == e.q_names
    # a URDF through from_file is from_urdf
    u = urdyn.Model.from_file(ROOT / "tests" / "urdf" / "double_pendulum.urdf")
    assert u.nq == 2
    with pytest.raises(ValueError, match="floating"):
        urdyn.Model.from_file(path, floating_base=True)


def test_bad_mjcf_is_a_value_error_and_missing_file_not_found():
    with pytest.raises(ValueError, match="joint"):
        urdyn.Model.from_mjcf_string(
            '<mujoco><worldbody><body><joint type="bogus"/><geom size="1"/></body></worldbody></mujoco>'
        )
    with pytest.raises(FileNotFoundError):
        urdyn.Model.from_mjcf(MJ / "no_such_file.xml")


def quat_wxyz_to_matrix(w, x, y, z):
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def test_mujoco_state_converters_closed_form():
    f, path = fixture("dm_control_humanoid")
    m = urdyn.Model.from_mjcf(path)
    s = f["states"][0]
    q, v = np.array(s["q"]), np.array(s["v"])
    qpos = urdyn.to_mujoco_qpos(m, q)
    # the free joint's quaternion w-first in MuJoCo, the rest as is
    assert np.array_equal(qpos[:3], q[:3])
    assert np.array_equal(qpos[3:7], [q[6], q[3], q[4], q[5]])
    assert np.array_equal(qpos[7:], q[7:])
    qvel = urdyn.to_mujoco_qvel(m, q, v)
    r = quat_wxyz_to_matrix(*qpos[3:7])
    close(qvel[:3], r @ v[:3], 1e-14)
    assert np.array_equal(qvel[3:], v[3:])
    assert np.allclose(urdyn.from_mujoco_qpos(m, qpos), q, rtol=0, atol=1e-15)
    assert np.allclose(urdyn.from_mujoco_qvel(m, qpos, qvel), v, rtol=0, atol=1e-14)
    with pytest.raises(ValueError, match="qpos"):
        urdyn.from_mujoco_qpos(m, np.zeros(m.nq + 1))
