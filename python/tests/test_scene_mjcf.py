"""`urdyn.Scene.from_mjcf(path)` (mjcf.md §"Entry points"): an MJCF file's whole
world as a scene — one model named after the file's stem, names STEM/NAME, its
floor plane the ground, its free joint's q the file's world pose; the same
state and link names as `Model.from_mjcf` with the prefix; pickles."""

import pickle
from pathlib import Path

import numpy as np

import urdyn

ROOT = Path(__file__).resolve().parents[2]
ANT = ROOT / "tests" / "fixtures" / "mjcf" / "gymnasium" / "ant.xml"


def test_scene_from_mjcf_is_the_files_world():
    s = urdyn.Scene.from_mjcf(ANT)
    m = urdyn.Model.from_mjcf(ANT)
    assert s.model_names == ["ant"]
    assert s.ground == 0.0  # the floor plane at z = 0
    assert s.model.link_names == ["ant/" + n for n in m.link_names]
    assert s.model.dof_names == ["ant/" + n for n in m.dof_names]
    # the torso's free joint starts at the file's pose (0, 0, 0.75)
    q0 = np.asarray(s.q0)
    assert q0.shape == (15,)
    np.testing.assert_array_equal(q0[:7], [0, 0, 0.75, 0, 0, 0, 1])
    np.testing.assert_array_equal(np.asarray(s.v0), np.zeros(14))
    # pickles as its text and folder
    t = pickle.loads(pickle.dumps(s))
    np.testing.assert_array_equal(np.asarray(t.q0), q0)
    assert t.model_names == ["ant"]


def test_scene_from_mjcf_of_a_missing_file_names_it():
    try:
        urdyn.Scene.from_mjcf(ANT.with_name("no_such.xml"))
    except FileNotFoundError as e:
        assert "no_such.xml" in str(e)
    else:
        raise AssertionError("a missing file loaded")


def test_scene_model_link_inertias_of_an_mjcf_model_are_the_files():
    # Scene.from_mjcf(ant).model: each MODEL/BODY's own inertial as
    # Model.from_mjcf gives it (its own frame: the scene's pose does not move it)
    s = urdyn.Scene.from_mjcf(ANT)
    m = urdyn.Model.from_mjcf(ANT)
    for link in m.link_names:
        c0, i0 = m.link_inertia(link)
        c, i = s.model.link_inertia("ant/" + link)
        np.testing.assert_array_equal(np.asarray(c), np.asarray(c0))
        np.testing.assert_array_equal(np.asarray(i), np.asarray(i0))
    # the torso: a sphere of radius 0.25 at density 5 (ant.xml's default)
    c, i = s.model.link_inertia("ant/torso")
    mass = 5.0 * 4.0 / 3.0 * np.pi * 0.25**3
    np.testing.assert_allclose(np.diag(np.asarray(i)), [0.4 * mass * 0.25**2] * 3, rtol=1e-12)
