"""Loop constraints from Python (mechanisms.md §"Python"): urdyn.Constraints,
constraint_dynamics, its derivatives, constraint_jacobian and
constraint_violation against the committed Pinocchio fixtures
(tests/fixtures/constraints/, tests/oracle/make_constraint_fixtures.py) and
identities (J_c q̈ + γ = 0 through finite differences of the violation)."""

import json
from pathlib import Path

import numpy as np
import pytest

import urdyn

ROOT = Path(__file__).resolve().parents[2]
FIX = ROOT / "tests" / "fixtures" / "constraints"


def load(name):
    f = json.loads((FIX / f"{name}.json").read_text())
    m = urdyn.Model.from_urdf(ROOT / f["robot"], floating_base=f["floating_base"])
    m.gravity = f["gravity"]
    return f, m, urdyn.Constraints(m, f["constraints"])


def rel(got, want):
    got, want = np.asarray(got), np.asarray(want)
    return np.max(np.abs(got - want)) / max(1.0, np.max(np.abs(want)))


@pytest.mark.parametrize("name", ["four_bar_planar", "four_bar_spatial", "ur5_gear", "solo12_feet"])
def test_constraint_dynamics_matches_pinocchio(name):
    f, m, c = load(name)
    d = m.create_data()
    for i, st in enumerate(f["states"]):
        qdd, lam = urdyn.constraint_dynamics(m, d, st["q"], st["v"], st["tau"], c)
        assert qdd.shape == (m.nv,) and lam.shape == (c.rows,)
        assert rel(qdd, st["qdd"]) < 1e-10, (name, i)
        if st.get("lambda") is not None:
            assert rel(lam, st["lambda"]) < 1e-10, (name, i)
        # J_cᵀ λ is the generalized constraint force
        jc = urdyn.constraint_jacobian(m, d, st["q"], c)
        assert jc.shape == (c.rows, m.nv)
        assert rel(jc.T @ lam, st["generalized_force"]) < 1e-9, (name, i)
        viol = urdyn.constraint_violation(m, d, st["q"], c)
        assert viol.shape == (len(c),)
        assert np.allclose(viol, st["violation"], atol=1e-10), (name, i)


@pytest.mark.parametrize("name", ["four_bar_spatial", "ur5_gear"])
def test_constraint_derivatives_match_the_fixture(name):
    f, m, c = load(name)
    d = m.create_data()
    for i, st in enumerate(f["states"][:3]):
        dq, dv, dtau = urdyn.constraint_dynamics_derivatives(m, d, st["q"], st["v"], st["tau"], c)
        for got, key in ((dq, "dqdd_dq"), (dv, "dqdd_dv"), (dtau, "dqdd_dtau")):
            assert got.shape == (m.nv, m.nv)
            assert rel(got, st[key]) < 1e-7, (name, i, key)


def test_dqdd_dtau_is_a_projection_of_the_inverse_mass_matrix():
    # ∂q̈/∂τ = H⁻¹ − Y K⁺ Yᵀ annihilates J_cᵀ: J_c ∂q̈/∂τ = 0
    f, m, c = load("four_bar_spatial")
    d = m.create_data()
    st = f["states"][0]
    _, _, dtau = urdyn.constraint_dynamics_derivatives(m, d, st["q"], st["v"], st["tau"], c)
    jc = urdyn.constraint_jacobian(m, d, st["q"], c)
    assert np.max(np.abs(jc @ dtau)) < 1e-9
    assert np.max(np.abs(dtau)) > 1e-3


def test_point_violation_is_the_distance():
    # an unsatisfied loop: the violation changes with q, and J_c is its gradient
    f, m, c = load("four_bar_spatial")
    d = m.create_data()
    q = np.array(f["states"][0]["q"]) + 0.05
    jc = urdyn.constraint_jacobian(m, d, q, c)
    e0 = urdyn.constraint_violation(m, d, q, c)[0]
    assert e0 > 1e-4
    # a point constraint's violation is |p1 − p2| and its rows are d(p1 − p2)/dq
    # (no base: v = q̇): |p1 − p2| changes by (p1 − p2)/|p1 − p2| · J_c dq
    h = 1e-6
    for k in range(m.nv):
        dq = np.zeros(m.nv)
        dq[k] = h
        ep = urdyn.constraint_violation(m, d, q + dq, c)[0]
        em = urdyn.constraint_violation(m, d, q - dq, c)[0]
        slope = (ep - em) / (2 * h)
        assert abs(slope) <= np.linalg.norm(jc[:, k]) + 1e-6


def test_fext_changes_qdd_as_a_generalized_force():
    f, m, c = load("four_bar_spatial")
    d = m.create_data()
    st = f["states"][0]
    link = f["constraints"][0]["link1"]
    qdd0, _ = urdyn.constraint_dynamics(m, d, st["q"], st["v"], st["tau"], c)
    qdd1, _ = urdyn.constraint_dynamics(
        m, d, st["q"], st["v"], st["tau"], c, fext={link: ([0, 0, 0], [0, 0, 0])}
    )
    assert np.array_equal(qdd0, qdd1)
    qdd2, _ = urdyn.constraint_dynamics(
        m, d, st["q"], st["v"], st["tau"], c, fext={link: ([1.0, 2.0, 3.0], [0, 0, 0])}
    )
    assert np.max(np.abs(qdd2 - qdd0)) > 1e-6


def test_bad_constraints_are_value_errors_naming_the_key():
    _, m, _ = load("four_bar_spatial")
    with pytest.raises(ValueError, match=r"constraints\[0\]\.link1"):
        urdyn.Constraints(m, [{"name": "x", "kind": "point", "link1": "nope", "link2": "rocker_link"}])
    with pytest.raises(ValueError, match=r"constraints\[1\]\.name"):
        ok = {"name": "a", "kind": "point", "link1": "coupler_link", "link2": "rocker_link"}
        urdyn.Constraints(m, [ok, dict(ok)])
    f, m, c = load("four_bar_spatial")
    d = m.create_data()
    with pytest.raises(ValueError, match="tau"):
        urdyn.constraint_dynamics(m, d, np.zeros(m.nq), np.zeros(m.nv), np.zeros(m.nv + 1), c)
    # constraints made for another model
    _, m2, c2 = load("ur5_gear")
    with pytest.raises(ValueError, match="another model"):
        urdyn.constraint_violation(m, d, np.zeros(m.nq), c2)
