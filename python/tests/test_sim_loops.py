"""Loops in a Python simulation (mechanisms.md §"Python"): `Simulation(model,
constraints=...)` without a scene file, `sim.constraint_forces()`,
`sim.set_constraint_active(name, on)`, `sim.constraint_violation`, a scene's
"constraints", `rollout` with loops. The numbers are checked against closed forms
(a welded rod carries its weight m·g and the moment of its weight), the contract's
bounds (a closed four-bar stays within 1e-6 and its energy never rises), and the
functional `urdyn.constraint_violation` of the same state."""

import json
import warnings
from pathlib import Path

import numpy as np
import pytest

import urdyn

ROOT = Path(__file__).resolve().parents[2]
FIX = ROOT / "tests" / "fixtures"

# a 2 kg rod along x, its centre of mass 0.25 m from its origin
ROD = """<robot name="rod">
  <link name="rod">
    <inertial><origin xyz="0.25 0 0"/><mass value="2.0"/>
      <inertia ixx="1e-3" ixy="0" ixz="0" iyy="4.2e-2" iyz="0" izz="4.2e-2"/></inertial>
  </link>
</robot>"""


def four_bar():
    f = json.loads((FIX / "constraints" / "four_bar_planar.json").read_text())
    m = urdyn.Model.from_urdf(ROOT / f["robot"])
    c = urdyn.Constraints(m, f["constraints"])
    # state 0 of the fixture closes the loop (violation 1.6e-16)
    return m, c, np.array(f["states"][0]["q"])


def test_a_welded_rod_carries_its_weight_and_its_moment():
    m = urdyn.Model.from_urdf_string(ROD, floating_base=True)
    c = urdyn.Constraints(m, [{"name": "weld", "kind": "frame", "link1": "rod"}])
    sim = urdyn.Simulation(m, ground=None, constraints=c)
    q0 = sim.q
    sim.step(n=200)
    f = sim.constraint_forces()
    assert list(f) == ["weld"]
    mg = 2.0 * 9.81
    # on link1 at its origin: f = −m g_vec, τ = −c × (m g_vec) = (0, −0.25 m g, 0)
    np.testing.assert_allclose(f["weld"]["force"], [0, 0, mg], rtol=0, atol=1e-6 * mg)
    np.testing.assert_allclose(f["weld"]["torque"], [0, -0.25 * mg, 0], rtol=0, atol=1e-6 * mg)
    assert np.max(np.abs(sim.q - q0)) < 1e-9
    assert sim.constraint_violation < 1e-9
    # the same rod with the gravity turned: the force turns with it
    m.gravity = [9.81, 0, 0]
    sim = urdyn.Simulation(m, ground=None, constraints=[{"name": "weld", "kind": "frame", "link1": "rod"}])
    sim.step(n=50)
    f = sim.constraint_forces()["weld"]
    np.testing.assert_allclose(f["force"], [-mg, 0, 0], rtol=0, atol=1e-6 * mg)
    # c × (m g x̂) = 0: the weight along the rod has no moment about its origin
    assert np.max(np.abs(f["torque"])) < 1e-6 * mg


def test_a_pinned_rod_holds_where_it_stands_after_set_state():
    # a point hold with no world point: where the rod's origin is at the start,
    # and set_state starts the run anew (the anchor placed there)
    m = urdyn.Model.from_urdf_string(ROD, floating_base=True)
    sim = urdyn.Simulation(m, ground=None, sleep=False,
                           constraints=[{"name": "pin", "kind": "point", "link1": "rod"}])
    q = m.neutral()
    q[:3] = [0.3, -0.2, 1.0]
    sim.set_state(q, np.zeros(m.nv))
    sim.step(n=300)
    d = m.create_data()
    origin = urdyn.frame_placement(m, d, sim.q, "rod")[:3, 3]
    np.testing.assert_allclose(origin, [0.3, -0.2, 1.0], atol=1e-6)
    # it swings about the pin: the centre of mass has moved down
    com = urdyn.center_of_mass(m, d, sim.q)
    assert com[2] < 1.0 - 1e-3


def test_a_closed_four_bar_stays_closed_and_its_energy_never_rises():
    m, c, q0 = four_bar()
    sim = urdyn.Simulation(m, ground=None, constraints=c)
    sim.set_state(q0, np.zeros(m.nv))
    d = m.create_data()
    e0 = sim.energy()
    scale = abs(e0) + m.total_mass * 9.81 * 1.0
    worst = 0.0
    for _ in range(200):
        sim.step(n=10)
        worst = max(worst, sim.constraint_violation)
        assert sim.energy() <= e0 + 1e-6 * scale
    assert worst < 1e-6
    # the simulation's reading is the functional measure of the same state
    assert abs(sim.constraint_violation - urdyn.constraint_violation(m, d, sim.q, c)[0]) < 1e-12
    # called, it reads the same (an attribute that may also be called)
    assert sim.constraint_violation() == float(sim.constraint_violation)
    # it moved: the crank swung under gravity
    assert abs(sim.q[0] - q0[0]) > 0.05
    f = sim.constraint_forces()["loop"]
    assert f["force"].shape == (3,) and np.linalg.norm(f["force"]) > 1e-3


def test_switching_a_loop_off_lets_it_open_and_on_closes_it_again():
    m, c, q0 = four_bar()
    sim = urdyn.Simulation(m, ground=None, sleep=False, constraints=c)
    sim.set_state(q0, np.zeros(m.nv))
    d = m.create_data()
    sim.set_constraint_active("loop", False)
    sim.step(n=300)
    opened = urdyn.constraint_violation(m, d, sim.q, c)[0]
    assert opened > 1e-2
    # over the active constraints only: none
    assert sim.constraint_violation == 0.0
    assert np.all(sim.constraint_forces()["loop"]["force"] == 0.0)
    # off survives set_state and reset
    sim.set_state(q0, np.zeros(m.nv))
    sim.step(n=100)
    assert urdyn.constraint_violation(m, d, sim.q, c)[0] > 1e-3
    sim.set_constraint_active("loop", True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim.step(n=600)
    assert urdyn.constraint_violation(m, d, sim.q, c)[0] < 1e-6
    assert sim.constraint_violation < 1e-6


def test_a_violated_start_warns_naming_the_constraint():
    m, c, q0 = four_bar()
    sim = urdyn.Simulation(m, ground=None, constraints=c)
    q = q0.copy()
    q[0] += 0.05
    sim.set_state(q, np.zeros(m.nv))
    with pytest.warns(RuntimeWarning, match=r'constraint "loop".*violated'):
        sim.step()
    # once
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sim.step(n=500)
    assert sim.constraint_violation < 1e-6


def test_a_scene_with_constraints_runs_them_and_rollout_equals_it():
    scene = urdyn.Scene.from_file(FIX / "loops" / "scene.json")
    sim = urdyn.Simulation(scene)
    assert list(sim.constraint_forces()) == ["loop"]
    e0 = sim.energy()
    nstep = 300
    qs = [sim.q]
    for _ in range(nstep):
        sim.step()
        qs.append(sim.q)
        assert sim.constraint_violation < 1e-6
    assert sim.energy() <= e0 + 1e-6 * (abs(e0) + scene.model.total_mass * 9.81)
    q, v = urdyn.rollout(scene, scene.q0[None, :], scene.v0[None, :], nstep=nstep)
    assert np.array_equal(q[0], np.array(qs))


def test_rollout_with_constraints_equals_a_simulation_bit_for_bit():
    m, c, q0 = four_bar()
    b, nstep = 3, 200
    q0s = np.stack([q0] * b)
    v0s = np.zeros((b, m.nv))
    v0s[1, 0] = 0.5  # not along the loop: the first step corrects it
    q, v = urdyn.rollout(m, q0s, v0s, nstep=nstep, ground=None, constraints=c, threads=2)
    for i in range(b):
        sim = urdyn.Simulation(m, ground=None, constraints=c)
        sim.set_state(q0s[i], v0s[i])
        for k in range(nstep):
            sim.step()
        assert np.array_equal(sim.q, q[i, -1]) and np.array_equal(sim.v, v[i, -1]), i
    d = m.create_data()
    assert urdyn.constraint_violation(m, d, q[0, -1], c)[0] < 1e-6


def test_reset_replays_a_run_with_loops_bit_for_bit():
    # a scene's start closes the loop; reset returns to it, the switch stays
    scene = urdyn.Scene.from_file(FIX / "loops" / "scene.json")
    sim = urdyn.Simulation(scene)
    sim.step(n=100)
    first = sim.q
    sim.reset()
    sim.step(n=100)
    assert np.array_equal(sim.q, first)
    sim.reset()
    sim.set_constraint_active("loop", False)
    sim.step(n=100)
    off = sim.q
    sim.reset()
    sim.step(n=100)
    assert np.array_equal(sim.q, off) and not np.array_equal(off, first)


def test_bad_loop_arguments_are_value_errors_naming_the_argument():
    m, c, q0 = four_bar()
    with pytest.raises(ValueError, match="constraints"):
        urdyn.Simulation(m, constraints=5)
    with pytest.raises(ValueError, match=r"constraints\[0\]\.link1"):
        urdyn.Simulation(m, constraints=[{"kind": "point", "link1": "nope", "link2": "rocker_link"}])
    other = urdyn.Model.from_urdf_string(ROD, floating_base=True)
    with pytest.raises(ValueError, match="constraints: made for another model"):
        urdyn.Simulation(other, constraints=c)
    scene = urdyn.Scene.from_file(FIX / "loops" / "scene.json")
    with pytest.raises(ValueError, match="constraints= does not apply beside a scene"):
        urdyn.Simulation(scene, constraints=[])
    with pytest.raises(ValueError, match="constraints= does not apply beside a scene"):
        urdyn.rollout(scene, scene.q0[None, :], scene.v0[None, :], nstep=1, constraints=[])
    sim = urdyn.Simulation(m, ground=None, constraints=c)
    with pytest.raises(ValueError, match=r'name: no constraint named "lop" \(nearest: "loop"\)'):
        sim.set_constraint_active("lop", False)
    with pytest.raises(ValueError, match="name: expected a constraint's name"):
        sim.set_constraint_active(3, False)
    with pytest.raises(ValueError, match="on: expected True or False"):
        sim.set_constraint_active("loop", "no")
    with pytest.raises(ValueError, match="on: expected True or False"):
        sim.set_constraint_active("loop", 0)
    sim.set_constraint_active("loop", np.bool_(False))
    # no loops: nothing to switch, violation 0, no forces
    plain = urdyn.Simulation(m, ground=None)
    assert plain.constraint_violation == 0.0 and plain.constraint_forces() == {}
    with pytest.raises(ValueError, match="name: no constraint named"):
        plain.set_constraint_active("loop", True)
