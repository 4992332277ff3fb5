"""urdyn.Scene (python.md §"Scenes"): the scene's Model and its names, the
start, Simulation(scene) equal to rollout(scene) bit for bit, pickling, errors."""

import json
import pickle
from pathlib import Path

import numpy as np
import pytest

import urdyn

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "assets" / "lamp_on_table.json"


def test_scene_model_names_and_start():
    s = urdyn.Scene.from_file(SCENE)
    m = s.model
    assert s.model_names == ["table", "lamp"]
    assert m.nq == 10 and m.nv == 9
    assert "lamp/elbow" in m.dof_names
    assert "table/top" in m.link_names and "lamp/shade" in m.link_names
    q0 = s.q0
    assert np.allclose(q0[:3], [0.6, 0.0, 1.25])


def test_simulation_of_a_scene_equals_its_rollout_and_pickles():
    s = urdyn.Scene.from_file(SCENE)
    sim = urdyn.Simulation(s, dt=1e-3)
    assert np.array_equal(sim.q, s.q0)
    sim.step(n=50)
    q, v = urdyn.rollout(s, s.q0[None, :], s.v0[None, :], nstep=50, dt=1e-3)
    assert np.array_equal(q[0, -1], sim.q) and np.array_equal(v[0, -1], sim.v)
    s2 = pickle.loads(pickle.dumps(s))
    assert np.array_equal(s2.q0, s.q0)
    m2 = pickle.loads(pickle.dumps(s.model))
    assert m2.dof_names == s.model.dof_names


def test_bad_scenes_raise_one_line():
    text = json.dumps({"models": [{"name": "a/b", "urdf": "lamp.urdf"}]})
    with pytest.raises(ValueError, match=r"models\[0\]\.name"):
        urdyn.Scene.from_json(text, base_dir=ROOT / "assets")
    with pytest.raises(FileNotFoundError, match="nothere.urdf"):
        urdyn.Scene.from_json(json.dumps({"models": [{"name": "a", "urdf": "nothere.urdf"}]}))
    with pytest.raises(FileNotFoundError):
        urdyn.Scene.from_file(ROOT / "nothere.json")
