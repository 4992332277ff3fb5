"""A scene's ground keys "torsion" and "rolling" (scene.md; the library's
ContactParams::{torsion, rolling}) reach Python's Simulation and rollout as they reach
`urdyn simulate --scene`: a Luxo drop, whose feet land on a ground with torsional and
rolling friction, steps bit for bit as the CLI's CSV, contacts included."""

import csv
import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

import urdyn

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "assets" / "luxo_drop.json"
STEPS = 400  # the lamp lands near step 230; the last CSV row (t = duration) lands on it


def urdyn_bin():
    for p in (ROOT / "target" / "release" / "urdyn", ROOT / "target" / "debug" / "urdyn"):
        if p.exists():
            return p
    return None


def cli_run(exe, scene, tmp_path):
    out = tmp_path / "run.csv"
    subprocess.run([str(exe), "simulate", "--scene", str(scene), "--duration", "0.45",
                    "--out", str(out)], check=True, capture_output=True, text=True)
    rows = list(csv.reader(out.open()))
    head = rows[0]
    data = np.array([[float(x) for x in r] for r in rows[1:]])
    qc = [i for i, n in enumerate(head) if n.startswith("q:")]
    vc = [i for i, n in enumerate(head) if n.startswith("v:")]
    return data[:, qc], data[:, vc], data[:, head.index("penetration")]


def test_luxo_scene_with_torsion_and_rolling_steps_as_the_cli(tmp_path):
    exe = urdyn_bin()
    if exe is None:
        pytest.skip("no urdyn binary (cargo build --release)")
    spec = json.loads(SCENE.read_text())
    assert spec["ground"]["torsion"] > 0 and spec["ground"]["rolling"] > 0
    q_cli, v_cli, pen_cli = cli_run(exe, SCENE, tmp_path)
    scene = urdyn.Scene.from_file(SCENE)
    sim = urdyn.Simulation(scene, dt=1e-3)
    assert np.array_equal(sim.q, q_cli[0]) and np.array_equal(sim.v, v_cli[0])
    touched = 0
    for k in range(1, STEPS + 1):
        sim.step()
        assert np.array_equal(sim.q, q_cli[k]), k
        assert np.array_equal(sim.v, v_cli[k]), k
        assert sim.penetration == pen_cli[k], k
        touched += pen_cli[k] > 0
    assert touched > 100  # the comparison covers the contact, not only the fall
    # rollout of the scene: the same numbers
    q, v = urdyn.rollout(scene, scene.q0[None, :], scene.v0[None, :], nstep=STEPS, dt=1e-3)
    assert np.array_equal(q[0], q_cli[: STEPS + 1]) and np.array_equal(v[0], v_cli[: STEPS + 1])

    # the keys matter here: the same scene without them goes elsewhere, by centimetres
    for key in ("torsion", "rolling"):
        del spec["ground"][key]
    plain = urdyn.Scene.from_json(json.dumps(spec), base_dir=str(SCENE.parent))
    sp = urdyn.Simulation(plain, dt=1e-3)
    sp.step(n=STEPS)
    assert np.abs(sp.q - q_cli[STEPS]).max() > 1e-3
