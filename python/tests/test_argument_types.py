"""python.md §"Introspection, contacts, batched control, pictures": "A wrong type
raises ValueError naming the argument" — the numbers and flags a user types by hand
(dt, time, eps, seed, sleep, record's flag, floating_base), which pyo3's own
conversion answered with a TypeError (or an OverflowError for seed=-1)."""

import numpy as np
import pytest

import urdyn
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
UR5 = ROOT / "assets" / "robots" / "ur5.urdf"


def test_wrong_types_of_numbers_and_flags_are_value_errors_naming_the_argument():
    model = urdyn.Model.from_urdf(UR5)
    sim = urdyn.Simulation(model)
    q, z = model.neutral(), np.zeros(model.nv)
    q0, v0 = q[None, :], z[None, :]
    cases = [
        (lambda: urdyn.Simulation(model, dt="a"), "dt must be a number"),
        (lambda: urdyn.Simulation(model, dt=True), "dt must be a number"),
        (lambda: urdyn.Simulation(model, sleep="no"), "sleep must be True or False"),
        (lambda: urdyn.Simulation(model, sleep=1), "sleep must be True or False"),
        (lambda: urdyn.rollout(model, q0, v0, nstep=1, dt="a"), "dt must be a number"),
        (lambda: urdyn.rollout(model, q0, v0, nstep=1, sleep="x"), "sleep must be True or False"),
        (lambda: sim.set_state(q, z, time="a"), "time must be a number"),
        (lambda: sim.record("yes"), "on must be True or False"),
        (lambda: sim.transition_jacobians(eps="a"), "eps must be a number"),
        (lambda: urdyn.linearize(sim, q0, v0, v0, eps=[1e-6]), "eps must be a number"),
        (lambda: urdyn.random_configuration(model, seed=-1), "seed must be a whole number"),
        (lambda: urdyn.random_configuration(model, seed=1.5), "seed must be a whole number"),
        (lambda: urdyn.Model.from_urdf(UR5, floating_base="yes"), "floating_base must be True or False"),
        (lambda: urdyn.Model.from_urdf_string(UR5.read_text(), floating_base=2), "floating_base must be True or False"),
    ]
    for call, message in cases:
        with pytest.raises(ValueError, match="^" + message):
            call()
    # the right types still pass, numpy's included
    urdyn.Simulation(model, dt=np.float64(2e-3), sleep=np.bool_(False))
    sim.set_state(q, z, time=1)
    assert sim.time == 1.0
    a = urdyn.random_configuration(model, seed=np.int64(7))
    assert np.array_equal(a, urdyn.random_configuration(model, seed=7))
    assert urdyn.Model.from_urdf(UR5, floating_base=np.bool_(True)).nq == model.nq + 7
