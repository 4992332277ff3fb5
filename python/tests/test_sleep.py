"""Sleep and threads from Python (python.md §"Mechanisms, MJCF and large
scenes", scene.md §"Large scenes"): a box at rest on the ground falls asleep
(awake 0) within the sleep time, sleep=False keeps it awake, a scene model's
own "sleep": false and a driven model never sleep, wake() wakes, and rollout
equals Simulation bit for bit with sleep on and island threads."""

import json
from pathlib import Path

import numpy as np
import pytest

import urdyn

ROOT = Path(__file__).resolve().parents[2]


def one_box(extra_model="", extra_scene=""):
    text = (
        '{"ground": {"height": 0.0}, %s "models": [{"name": "m", "urdf": "tests/urdf/crate_box.urdf", '
        '"base": "floating", "position": [0, 0, 0.1] %s}]}' % (extra_scene, extra_model)
    )
    return urdyn.Scene.from_json(text, base_dir=ROOT)


def run(sim, t):
    n = int(round(t / 1e-3))
    sim.step(n=n)
    return sim


def test_a_resting_box_sleeps_and_sleep_false_keeps_it_awake():
    s = one_box()
    sim = run(urdyn.Simulation(s), 1.5)
    assert sim.awake == 0 and sim.sleeping("m") is True
    # asleep: its velocity is exactly zero
    assert np.all(sim.v == 0.0)
    awake = run(urdyn.Simulation(s, sleep=False), 1.5)
    assert awake.awake == 1 and awake.sleeping("m") is False
    # the sleeping run ends where the awake one does (within a millimetre)
    assert np.max(np.abs(sim.q[:3] - awake.q[:3])) < 1e-3
    sim.wake()
    assert sim.awake == 1 and sim.sleeping("m") is False
    with pytest.raises(ValueError, match="nope"):
        sim.sleeping("nope")


def test_the_scene_decides_when_the_call_does_not():
    s = one_box(extra_scene='"sleep": false,')
    assert run(urdyn.Simulation(s), 1.5).awake == 1
    assert run(urdyn.Simulation(s, sleep=True), 1.5).awake == 0
    own = one_box(extra_model=', "sleep": false')
    assert run(urdyn.Simulation(own), 1.5).awake == 1


def test_a_model_alone_sleeps_by_default():
    m = urdyn.Model.from_urdf(ROOT / "tests" / "urdf" / "crate_box.urdf", floating_base=True)
    q0 = one_box().q0
    sim = urdyn.Simulation(m)
    sim.set_state(q0, np.zeros(m.nv))
    run(sim, 1.5)
    assert sim.awake == 0 and sim.sleeping(m.models[0]) is True
    # setting a state wakes it; stepping with zero torques does not keep it awake
    sim.set_state(sim.q, sim.v)
    assert sim.awake == 1 and sim.sleeping(m.models[0]) is False
    run(sim, 1.0)
    assert sim.awake == 0


@pytest.mark.parametrize("threads", [None, 2])
def test_rollout_equals_simulation_bit_for_bit_with_sleep_on(threads):
    s = one_box()
    nstep = 1200
    q0 = np.array(s.q0)[None, :].repeat(2, axis=0)
    q0[1, 2] += 0.05  # dropped from 5 cm higher
    v0 = np.zeros((2, s.model.nv))
    qs, vs = urdyn.rollout(s, q0, v0, nstep=nstep, sleep=True, threads=threads)
    for b in range(2):
        sim = urdyn.Simulation(s, sleep=True, threads=threads)
        sim.set_state(q0[b], v0[b])
        sim.step(n=nstep)
        assert np.array_equal(sim.q, qs[b, -1]) and np.array_equal(sim.v, vs[b, -1])
    # sleep changes the result (the run is not the awake one bit for bit) but
    # both rest at the same place
    qa, _ = urdyn.rollout(s, q0, v0, nstep=nstep, sleep=False)
    assert not np.array_equal(qa[:, -1], qs[:, -1])
    assert np.max(np.abs(qa[:, -1, :3] - qs[:, -1, :3])) < 1e-3
    with pytest.raises(ValueError, match="threads"):
        urdyn.Simulation(s, threads=-1)
