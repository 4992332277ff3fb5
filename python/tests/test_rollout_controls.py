"""`rollout(..., controls=)` (python.md §"Introspection, contacts, batched control,
pictures"): each batch entry equals a `Simulation` given `set_controls` before its steps
and stepped alone, bit for bit; controls on a model without actuators are a ValueError."""

from pathlib import Path

import numpy as np
import pytest

import urdyn

ROOT = Path(__file__).resolve().parents[2]
MJ = ROOT / "tests" / "fixtures" / "mjcf"


def cartpole():
    m = urdyn.Model.from_mjcf(MJ / "dm_control" / "cartpole.xml")
    return m, len(urdyn.Simulation(m).controls)


def alone(model, q0, v0, us, tau=None):
    """One Simulation: set_controls(us[k]) then step(tau[k]) for each step."""
    sim = urdyn.Simulation(model, integrator="euler")
    sim.set_state(q0, v0)
    qs = [sim.q.copy()]
    for k, u in enumerate(us):
        sim.set_controls(u)
        sim.step(None if tau is None else tau[k])
        qs.append(sim.q.copy())
    return np.array(qs), sim.v.copy()


def test_rollout_controls_equal_a_simulation_bit_for_bit():
    m, nu = cartpole()
    assert nu >= 1
    B, N = 3, 40
    rng = np.random.default_rng(1)
    q0 = np.tile(m.neutral(), (B, 1))
    q0[:, -1] += rng.uniform(-0.3, 0.3, B)
    v0 = np.zeros((B, m.nv))
    # per step controls (B, nstep, nu), and constant ones (B, nu) with torques
    per = rng.uniform(-1, 1, (B, N, nu))
    Q, V = urdyn.rollout(m, q0, v0, nstep=N, threads=2, integrator="euler", controls=per)
    const = rng.uniform(-1, 1, (B, nu))
    tau = rng.uniform(-0.1, 0.1, (B, N, m.nv))
    Qc, Vc = urdyn.rollout(m, q0, v0, tau=tau, nstep=N, threads=2, integrator="euler",
                           controls=const)
    for i in range(B):
        qs, v = alone(m, q0[i], v0[i], per[i])
        assert np.array_equal(Q[i], qs) and np.array_equal(V[i, -1], v)
        qs, v = alone(m, q0[i], v0[i], [const[i]] * N, tau[i])
        assert np.array_equal(Qc[i], qs) and np.array_equal(Vc[i, -1], v)
    # the controls move the cart (a motor): not the run without them
    Q0, _ = urdyn.rollout(m, q0, v0, nstep=N, integrator="euler")
    assert not np.array_equal(Q0, Q)


def test_rollout_controls_bad_shapes_and_no_actuators():
    m, nu = cartpole()
    q0, v0 = m.neutral()[None], np.zeros((1, m.nv))
    with pytest.raises(ValueError, match="controls"):
        urdyn.rollout(m, q0, v0, nstep=3, controls=np.zeros((1, nu + 1)))
    ur5 = urdyn.Model.from_urdf(ROOT / "assets" / "robots" / "ur5.urdf")
    with pytest.raises(ValueError, match="controls"):
        urdyn.rollout(ur5, ur5.neutral()[None], np.zeros((1, ur5.nv)), nstep=3,
                      controls=np.zeros((1, 1)))


def test_controls_for_a_model_without_actuators_say_so_whatever_their_shape():
    model = urdyn.Model.from_urdf(str(ROOT / "assets" / "robots" / "ur5.urdf"))
    q0 = np.tile(model.neutral(), (2, 1))
    v0 = np.zeros((2, model.nv))
    for u in (np.ones((2, 1)), np.ones((2, 0))):
        with pytest.raises(ValueError, match=r"^controls: the model has no actuators"):
            urdyn.rollout(model, q0, v0, nstep=1, controls=u)
    q, _ = urdyn.rollout(model, q0, v0, nstep=1, controls=None)
    assert q.shape == (2, 2, model.nq)
