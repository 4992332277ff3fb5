"""The derivative and configuration functions (python.md §"Configurations",
§"Derivatives"): the same numbers as `urdyn eval` contract v3 on the fixture
states; integrate/difference equal Pinocchio's (skipped without pinocchio)."""

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

import urdyn

ROOT = Path(__file__).resolve().parents[2]
FIXTURES = ROOT / "tests" / "fixtures"
CASES = sorted(p.name for p in FIXTURES.iterdir() if (p / "deriv_states.json").exists() and (p / "deriv_meta.json").exists())


def rel(got, want):
    got, want = np.asarray(got, float), np.asarray(want, float)
    assert got.shape == want.shape
    return float(np.max(np.abs(got - want), initial=0.0) / max(1.0, np.max(np.abs(want), initial=0.0)))


def vectors(model, state):
    fb = model.floating_base
    names = model.dof_names
    o = 6 if fb else 0
    q = model.neutral()
    v, a, tau = (np.zeros(model.nv) for _ in range(3))
    for vec, key, off in ((q, "q", 7 if fb else 0), (v, "v", o), (a, "a", o), (tau, "tau", o)):
        for name, x in state.get(key, {}).items():
            vec[off + names.index(name)] = x
    b = state.get("base", {}) if fb else {}
    if fb:
        q[0:3] = b.get("position", [0, 0, 0])
        quat = np.asarray(b.get("orientation_xyzw", [0, 0, 0, 1]), float)
        q[3:7] = quat / np.linalg.norm(quat)
        v[0:3] = b.get("linear_velocity", [0, 0, 0])
        v[3:6] = b.get("angular_velocity", [0, 0, 0])
        a[0:3] = b.get("linear_acceleration", [0, 0, 0])
        a[3:6] = b.get("angular_acceleration", [0, 0, 0])
        tau[0:3] = b.get("force", [0, 0, 0])
        tau[3:6] = b.get("torque", [0, 0, 0])
    fext = {k: (w.get("force", [0, 0, 0]), w.get("torque", [0, 0, 0])) for k, w in state.get("fext", {}).items()}
    return q, v, a, tau, fext


def urdyn_bin():
    for p in (ROOT / "target" / "release" / "urdyn", ROOT / "target" / "debug" / "urdyn"):
        if p.exists():
            return p
    return None


@pytest.mark.parametrize("case", CASES)
def test_derivatives_equal_eval(case, tmp_path):
    exe = urdyn_bin()
    if exe is None:
        pytest.skip("no urdyn binary (cargo build --release --bin urdyn)")
    meta = json.loads((FIXTURES / case / "deriv_meta.json").read_text())
    states_file = FIXTURES / case / "deriv_states.json"
    urdf = ROOT / meta["urdf"]
    fb = meta["floating_base"]
    cmd = [str(exe), "eval", str(urdf), "--states", str(states_file)] + (["--floating-base"] if fb else [])
    out = json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout)
    model = urdyn.Model.from_urdf(urdf, floating_base=fb)
    states = json.loads(states_file.read_text())
    if "gravity" in states:
        model.gravity = states["gravity"]
    data = model.create_data()
    for st, res in zip(states["states"], out["results"]):
        q, v, a, tau, fext = vectors(model, st)
        d = res["derivatives"]
        dq, dv, m = urdyn.rnea_derivatives(model, data, q, v, a, fext or None)
        # The wheel is built without the repository's target-cpu=native (pip builds
        # it in a copy), the binary with it: fused multiply-adds round differently,
        # and an ill-conditioned H (icub: cond 5e5) amplifies that in the dqdd_*.
        assert rel(dq, d["dtau_dq"]) < 1e-12 and rel(dv, d["dtau_dv"]) < 1e-12
        assert rel(m, res["mass_matrix"]) < 1e-12
        fq, fv, minv = urdyn.aba_derivatives(model, data, q, v, tau, fext or None)
        assert rel(fq, d["dqdd_dq"]) < 1e-9 and rel(fv, d["dqdd_dv"]) < 1e-9
        assert rel(minv, d["dqdd_dtau"]) < 1e-9
        np.testing.assert_allclose(minv, minv.T, atol=1e-9 * np.abs(minv).max())
        for link, fr in res.get("frames", {}).items():
            jd = urdyn.frame_jacobian_time_variation(model, data, q, v, link)
            assert rel(jd, fr["jacobian_dot"]) < 1e-12
            jdl = urdyn.frame_jacobian_time_variation(model, data, q, v, link, reference="local")
            assert jdl.shape == (6, model.nv)


def test_integrate_difference_and_random_configuration():
    model = urdyn.Model.from_urdf(ROOT / "assets" / "robots" / "solo12.urdf", floating_base=True)
    q0 = urdyn.random_configuration(model, seed=3)
    q1 = urdyn.random_configuration(model, seed=4)
    assert abs(np.linalg.norm(q0[3:7]) - 1) < 1e-14
    assert not np.allclose(q0, q1)
    dq = urdyn.difference(model, q0, q1)
    back = urdyn.integrate(model, q0, dq)
    same = np.allclose(back[3:7], q1[3:7], atol=1e-12) or np.allclose(back[3:7], -q1[3:7], atol=1e-12)
    assert same and np.allclose(back[:3], q1[:3], atol=1e-12) and np.allclose(back[7:], q1[7:], atol=1e-12)
    with pytest.raises(ValueError, match="dq"):
        urdyn.integrate(model, q0, np.zeros(3))
    with pytest.raises(ValueError, match="link"):
        urdyn.frame_jacobian_time_variation(model, model.create_data(), q0, np.zeros(model.nv), "no_such_link")
    with pytest.raises(ValueError, match="fext"):
        urdyn.rnea_derivatives(model, model.create_data(), q0, np.zeros(model.nv), np.zeros(model.nv), {"nope": ([0, 0, 0], [0, 0, 0])})


def test_integrate_and_difference_equal_pinocchio():
    pin = pytest.importorskip("pinocchio")
    for path, fb in (("assets/robots/solo12.urdf", True), ("assets/robots/ur5.urdf", False)):
        urdf = str(ROOT / path)
        model = urdyn.Model.from_urdf(urdf, floating_base=fb)
        pm = pin.buildModelFromUrdf(urdf, pin.JointModelFreeFlyer()) if fb else pin.buildModelFromUrdf(urdf)
        assert [pm.names[i] for i in range(2 if fb else 1, pm.njoints)] == model.dof_names
        rng = np.random.default_rng(7)
        for seed in range(10):
            q0 = urdyn.random_configuration(model, seed=seed)
            q1 = urdyn.random_configuration(model, seed=seed + 20)
            dq = rng.uniform(-2, 2, model.nv)
            got = urdyn.integrate(model, q0, dq)
            want = pin.integrate(pm, q0, dq)
            assert rel(got, want) < 1e-13, (path, seed)
            got_d = urdyn.difference(model, q0, q1)
            want_d = pin.difference(pm, q0, q1)
            assert rel(got_d, want_d) < 1e-12, (path, seed)
