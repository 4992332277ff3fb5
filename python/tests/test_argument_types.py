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


def test_wrong_types_of_names_and_paths_are_value_errors_naming_the_argument():
    """The strings and paths: a link, a reference frame, a method, an integrator, a
    joint or model name, a file, a package folder (pyo3's own conversion raised a
    TypeError for each)."""
    model = urdyn.Model.from_urdf(UR5)
    data = model.create_data()
    sim = urdyn.Simulation(model)
    q, z = model.neutral(), np.zeros(model.nv)
    q0, v0 = q[None, :], z[None, :]
    link = "tool0"
    cases = [
        (lambda: urdyn.frame_placement(model, data, q, 5), "link must be a string"),
        (lambda: urdyn.frame_jacobian(model, data, q, None), "link must be a string"),
        (lambda: urdyn.frame_jacobian(model, data, q, link, reference=0), "reference must be a string"),
        (lambda: urdyn.frame_velocity(model, data, q, z, link, 1.0), "reference must be a string"),
        (lambda: urdyn.frame_jacobian_time_variation(model, data, q, z, b"tool0"), "link must be a string"),
        (lambda: model.joint_q_slice(3), "name must be a string"),
        (lambda: model.model_v_slice(None), "name must be a string"),
        (lambda: model.link_mass(["tool0"]), "link must be a string"),
        (lambda: model.link_inertia(7), "link must be a string"),
        (lambda: urdyn.Model.from_urdf(42), "path must be a path"),
        (lambda: urdyn.Model.from_urdf(UR5, package_dirs="/opt/ros"), "package_dirs must be a list of paths"),
        (lambda: urdyn.Model.from_urdf(UR5, package_dirs=[1]), "package_dirs"),
        (lambda: urdyn.Model.from_mjcf(3.5), "path must be a path"),
        (lambda: urdyn.Model.from_urdf_string(b"<robot/>"), "xml must be a string"),
        (lambda: urdyn.Scene.from_file(None), "path must be a path"),
        (lambda: urdyn.Simulation(model, integrator=4), "integrator must be a string"),
        (lambda: urdyn.rollout(model, q0, v0, nstep=1, integrator=["rk4"]), "integrator must be a string"),
        (lambda: sim.transition_jacobians(method=1), "method must be a string"),
        (lambda: urdyn.linearize(sim, q0, v0, v0, method=None), "method must be a string"),
        (lambda: sim.imu(0), "link must be a string"),
        (lambda: sim.sleeping(0), "model_name must be a string"),
        (lambda: sim.write_html(12), "path must be a path"),
        (lambda: urdyn.write_html(12, model, q0), "path must be a path"),
    ]
    for call, message in cases:
        with pytest.raises(ValueError, match="^" + message):
            call()
    # the right types still pass: str, pathlib paths, None where allowed
    urdyn.frame_placement(model, data, q, link)
    urdyn.frame_jacobian(model, data, q, link, reference="local")
    urdyn.Model.from_urdf(str(UR5), package_dirs=[ROOT])
    urdyn.Simulation(model, integrator=None)
    sim.transition_jacobians(method="analytic")


def test_threads_beyond_the_librarys_bound_is_a_value_error_not_a_crash():
    # rollout and linearize start their pool before any simulation checks its
    # options: 100000 threads aborted the process (stack guards not mapped)
    model = urdyn.Model.from_urdf(UR5)
    q0, v0 = model.neutral()[None, :], np.zeros((1, model.nv))
    with pytest.raises(ValueError, match="^threads must be at most 1024 \\(got 100000\\)"):
        urdyn.rollout(model, q0, v0, nstep=1, threads=100000)
    with pytest.raises(ValueError, match="^threads must be at most 1024"):
        urdyn.Simulation(model, threads=5000)
    q, v = urdyn.rollout(model, q0, v0, nstep=1, threads=1024)
    assert q.shape == (1, 2, model.nq)
