"""Control from Python (python.md "Control", "Sensors"): servos, sensors,
transition Jacobians and linearize against per-state calls, bad input."""

from pathlib import Path

import numpy as np
import pytest

import urdyn

ROOT = Path(__file__).resolve().parents[2]
QUAD = ROOT / "tests" / "urdf" / "quadruped.urdf"
UR5 = ROOT / "assets" / "robots" / "ur5.urdf"


def standing():
    model = urdyn.Model.from_urdf(str(QUAD), floating_base=True)
    sim = urdyn.Simulation(model)
    q = model.neutral()
    for k, name in enumerate(model.dof_names):
        q[7 + k] = 0.6 if name.endswith("hip") else -1.2
    q[2] = 0.4 * np.cos(0.6) + 0.021
    sim.set_gains(60.0, 3.0)
    sim.set_targets(q)
    sim.set_state(q, np.zeros(model.nv))
    sim.step(n=3000)
    return model, sim


def test_servo_holds_and_gains_persist():
    model, sim = standing()
    q = sim.q
    assert abs(q[2] - (0.4 * np.cos(0.6) + 0.02)) < 0.02
    # gains and targets persist across set_state: the same run again
    sim.set_state(q, np.zeros(model.nv))
    sim.step(n=10)
    assert np.all(np.isfinite(sim.q))


def test_gains_zero_are_bit_identical():
    model = urdyn.Model.from_urdf(str(UR5))
    a = urdyn.Simulation(model, ground=None, integrator="euler")
    b = urdyn.Simulation(model, ground=None, integrator="euler")
    b.set_gains(0.0, np.zeros(model.nv))
    b.set_targets(np.ones(model.nq), np.ones(model.nv))
    q = np.linspace(-1, 1, model.nq)
    for s in (a, b):
        s.set_state(q, np.zeros(model.nv))
        s.step(tau=np.ones(model.nv), n=200)
    assert np.array_equal(a.q, b.q) and np.array_equal(a.v, b.v)


def test_sensors_at_rest():
    model, sim = standing()
    total = sum(sim.contact_wrench(f"{leg}_foot")[0] for leg in ("fl", "fr", "hl", "hr"))
    weight = model.total_mass * 9.81
    assert abs(total[2] - weight) < 1e-6 * weight
    gyro, acc = sim.imu("torso")
    assert np.linalg.norm(gyro) < 1e-4  # the servoed stance sways slowly
    assert abs(np.linalg.norm(acc) - 9.81) < 0.05
    force, torque = sim.joint_wrench("fl_knee")
    assert force.shape == (3,) and torque.shape == (3,)
    f, t = sim.contact_wrench("torso")
    assert np.all(f == 0) and np.all(t == 0)


def test_transition_jacobians_and_linearize():
    model, sim = standing()
    nv = model.nv
    q0, v0 = sim.q, sim.v
    A, B = sim.transition_jacobians()
    assert A.shape == (2 * nv, 2 * nv) and B.shape == (2 * nv, nv)
    assert np.all(np.isfinite(A)) and np.all(B[:, :6] == 0)
    # (against finite differences on an arm: the default contact solve stops at
    # 1e-6 m/s, which finite differences of 1e-6 would see; tests/step_jacobians.rs
    # compares the contact cases with a converged solve)
    arm = urdyn.Model.from_urdf(str(UR5))
    s = urdyn.Simulation(arm, ground=None, integrator="euler")
    s.set_state(np.linspace(-1, 1, arm.nq), np.linspace(1, -1, arm.nv))
    s.set_gains(50.0, 2.0)
    s.set_targets(np.zeros(arm.nq))
    for integ in ("euler", "rk4", None):
        s = urdyn.Simulation(arm, ground=None, integrator=integ)
        s.set_state(np.linspace(-1, 1, arm.nq), np.linspace(1, -1, arm.nv))
        s.set_gains(50.0, 2.0)
        s.set_targets(np.zeros(arm.nq))
        Aa, Ba = s.transition_jacobians(np.ones(arm.nv))
        Ac, Bc = s.transition_jacobians(np.ones(arm.nv), method="central")
        assert np.linalg.norm(Aa - Ac) / np.linalg.norm(Ac) < 1e-5
        assert np.linalg.norm(Ba - Bc) / np.linalg.norm(Bc) < 1e-5
    # the call changed nothing
    assert np.array_equal(sim.q, q0) and np.array_equal(sim.v, v0)
    # linearize along a short trajectory equals the per-state calls
    qs, vs = [], []
    # (5 states on 2 threads: runs of 3 and 2, one workspace each)
    for _ in range(5):
        qs.append(sim.q)
        vs.append(sim.v)
        sim.step(n=3)
    qs, vs = np.array(qs), np.array(vs)
    taus = np.zeros((5, nv))
    taus[:, 6:] = 0.05
    As, Bs = urdyn.linearize(sim, qs, vs, taus, threads=2)
    assert As.shape == (5, 2 * nv, 2 * nv) and Bs.shape == (5, 2 * nv, nv)
    for t in range(5):
        sim.set_state(qs[t], vs[t])
        A, B = sim.transition_jacobians(taus[t])
        assert np.array_equal(As[t], A) and np.array_equal(Bs[t], B)


def test_bad_input_is_value_error():
    model = urdyn.Model.from_urdf(str(UR5))
    sim = urdyn.Simulation(model, ground=None)
    with pytest.raises(ValueError, match="kp"):
        sim.set_gains(-1.0, 0.0)
    with pytest.raises(ValueError, match="kd"):
        sim.set_gains(0.0, [0, 0, float("nan"), 0, 0, 0])
    with pytest.raises(ValueError, match="q_ref"):
        sim.set_targets(np.zeros(3))
    with pytest.raises(ValueError, match="method"):
        sim.transition_jacobians(method="backward")
    with pytest.raises(ValueError, match="tau"):
        sim.transition_jacobians(np.zeros(2))
    with pytest.raises(ValueError, match="nearest"):
        sim.imu("wrist_3_lnk")
    with pytest.raises(ValueError):
        sim.joint_wrench("nope")
    quad = urdyn.Model.from_urdf(str(QUAD), floating_base=True)
    qs = urdyn.Simulation(quad)
    kp = np.zeros(quad.nv)
    kp[0] = 1.0
    with pytest.raises(ValueError, match="floating-base"):
        qs.set_gains(kp, 0.0)
    with pytest.raises(ValueError, match="shape"):
        urdyn.linearize(qs, np.zeros((2, quad.nq)), np.zeros((3, quad.nv)), np.zeros((2, quad.nv)))
