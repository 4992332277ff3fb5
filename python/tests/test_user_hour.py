"""The Python user's hour (issue 31; python.md §"Introspection, contacts, batched
control, pictures"): contacts with their true normals, both sides and depths; model
introspection equal to Pinocchio's (committed fixtures of make_introspection_fixtures.py);
rollout with servos bit for bit a Simulation; pictures; the edges (errors naming the
argument, reset, set_state(time=), penetration, applied_torques)."""

import csv
import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

import urdyn

ROOT = Path(__file__).resolve().parents[2]
FIX = json.loads((Path(__file__).parent / "fixtures" / "introspection.json").read_text())
UR5 = ROOT / "assets" / "robots" / "ur5.urdf"
SOLO = ROOT / "assets" / "robots" / "solo12.urdf"
URDYN = ROOT / "target" / "release" / "urdyn"

CUBE = """<robot name="cube"><link name="box">
 <inertial><mass value="1"/><inertia ixx="0.001667" iyy="0.001667" izz="0.001667" ixy="0" ixz="0" iyz="0"/></inertial>
 <collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link></robot>"""

# two fingers sliding along y toward the middle (q > 0: inward)
GRIPPER = """<robot name="gripper">
 <link name="palm"/>
 <link name="left"><inertial><mass value="0.1"/><inertia ixx="1e-4" iyy="1e-4" izz="1e-4" ixy="0" ixz="0" iyz="0"/></inertial>
  <collision><geometry><box size="0.1 0.02 0.1"/></geometry></collision></link>
 <link name="right"><inertial><mass value="0.1"/><inertia ixx="1e-4" iyy="1e-4" izz="1e-4" ixy="0" ixz="0" iyz="0"/></inertial>
  <collision><geometry><box size="0.1 0.02 0.1"/></geometry></collision></link>
 <joint name="left_slide" type="prismatic"><parent link="palm"/><child link="left"/>
  <origin xyz="0 0.065 0"/><axis xyz="0 -1 0"/><limit lower="-0.05" upper="0.05" effort="50" velocity="1"/></joint>
 <joint name="right_slide" type="prismatic"><parent link="palm"/><child link="right"/>
  <origin xyz="0 -0.065 0"/><axis xyz="0 1 0"/><limit lower="-0.05" upper="0.05" effort="50" velocity="1"/></joint>
</robot>"""


def write_scene(tmp_path, scene):
    (tmp_path / "cube.urdf").write_text(CUBE)
    (tmp_path / "gripper.urdf").write_text(GRIPPER)
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(scene))
    return path


def wall_scene(tmp_path):
    """A cube pushed by gravity along -x against a wall whose face is x = 0 (no ground)."""
    return write_scene(tmp_path, {
        "gravity": [-9.81, 0, 0],
        "models": [{"name": "cube", "urdf": "cube.urdf", "base": "floating", "position": [0.05, 0, 1]}],
        "obstacles": [{"name": "wall", "box": [0.2, 1, 1], "position": [-0.1, 0, 1]}],
    })


def grip_scene(tmp_path):
    """A cube squeezed between two servoed fingers (no gravity, no ground)."""
    return write_scene(tmp_path, {
        "gravity": [0, 0, 0],
        "models": [
            {"name": "cube", "urdf": "cube.urdf", "base": "floating", "position": [0, 0, 0]},
            {"name": "gripper", "urdf": "gripper.urdf", "base": "fixed"},
        ],
    })


# ---------------------------------------------------------------------------
# contacts (defect 1: every normal was [0, 0, 1], no other side, no depth)


def test_cube_on_a_wall_reports_the_walls_normal_other_and_the_csv_penetration(tmp_path):
    path = wall_scene(tmp_path)
    sim = urdyn.Simulation(urdyn.Scene.from_file(path))
    sim.step(n=300)
    cs = sim.contacts()
    assert cs, "the cube touches the wall"
    for c in cs:
        assert c["link"] == "cube/box" and c["other"] == "wall"
        assert np.abs(c["normal"] - [1.0, 0.0, 0.0]).max() < 1e-9, c["normal"]
        assert abs(c["point"][0]) < 2e-3
    forces = sim.contact_forces()
    assert forces and all(np.abs(f["normal"] - [1, 0, 0]).max() < 1e-9 for f in forces)
    # the wall carries the cube's weight along x
    total = sum(f["force"] for f in forces)
    assert abs(total[0] - 9.81) < 0.05 * 9.81, total
    deepest = max(c["depth"] for c in cs)
    assert deepest == sim.penetration
    if URDYN.exists():  # the CLI's CSV of the same run: the same penetration
        out = tmp_path / "run.csv"
        subprocess.run([str(URDYN), "simulate", "--scene", str(path), "--duration", "0.3",
                        "--out", str(out)], check=True, capture_output=True)
        rows = list(csv.DictReader(out.open()))
        assert abs(float(rows[-1]["penetration"]) - deepest) <= 1e-9 * max(1.0, abs(deepest))


def test_a_gripped_cube_reports_both_fingers_with_opposite_normals(tmp_path):
    scene = urdyn.Scene.from_file(grip_scene(tmp_path))
    sim = urdyn.Simulation(scene)
    m = scene.model
    kp = np.zeros(m.nv)
    kp[m.joint_v_slice("gripper/left_slide")] = 200.0
    kp[m.joint_v_slice("gripper/right_slide")] = 200.0
    sim.set_gains(kp, kp * 0.1)
    q_ref = sim.q.copy()
    q_ref[m.joint_q_slice("gripper/left_slide")] = 0.02
    q_ref[m.joint_q_slice("gripper/right_slide")] = 0.02
    sim.set_targets(q_ref)
    sim.step(n=400)
    cs = sim.contacts()
    sides = {c["other"] for c in cs}
    assert sides == {"gripper/left", "gripper/right"}, sides
    for c in cs:
        # the cube's model comes first in the scene: it is `link`
        assert c["link"] == "cube/box"
        want = [0, -1, 0] if c["other"] == "gripper/left" else [0, 1, 0]
        assert np.abs(c["normal"] - want).max() < 1e-9, (c["other"], c["normal"])
        # the force on the cube pushes it away from that finger
        assert np.dot(c["force"], want) >= 0
    assert max(c["depth"] for c in cs) == sim.penetration > 0


# ---------------------------------------------------------------------------
# introspection against Pinocchio (committed fixtures)


def _inf(x):
    return float(x) if not isinstance(x, str) else (np.inf if x == "inf" else -np.inf)


@pytest.mark.parametrize("name", sorted(FIX))
def test_introspection_equals_pinocchio(name):
    f = FIX[name]
    model = urdyn.Model.from_urdf(ROOT / f["urdf"], floating_base=f["floating"])
    assert model.models == ["robot"]
    assert model.model_q_slice("robot") == slice(0, model.nq)  # step None, as Python's
    assert model.model_v_slice("robot") == slice(0, model.nv)
    lower, upper = model.lower_limits, model.upper_limits
    effort, velocity = model.effort_limits, model.velocity_limits
    assert lower.shape == (model.nq,) and effort.shape == (model.nv,)
    np.testing.assert_array_equal(model.armature, np.zeros(model.nv))
    for joint, j in f["joints"].items():
        if j["shortname"] == "JointModelMimic":
            with pytest.raises(ValueError, match="mimic"):
                model.joint_q_slice(joint)
            continue
        sq, sv = model.joint_q_slice(joint), model.joint_v_slice(joint)
        assert sv == slice(j["idx_v"], j["idx_v"] + j["nv"]), joint
        if j["shortname"] in ("JointModelRUBX", "JointModelRUBY", "JointModelRUBZ", "JointModelRevoluteUnboundedUnaligned"):
            # continuous: one q entry here, two (cos, sin) in Pinocchio; no limits
            assert sq.stop - sq.start == 1
            assert lower[sq][0] == -np.inf and upper[sq][0] == np.inf
        elif joint == "base":
            assert sq == slice(0, 7) and sv == slice(0, 6)
            assert np.all(lower[sq] == -np.inf) and np.all(upper[sq] == np.inf)
            assert np.all(effort[sv] == np.inf)
        else:
            assert sq.stop - sq.start == j["nq"] == 1, joint
            pq = j["idx_q"]
            assert lower[sq][0] == _inf(f["lower"][pq]) and upper[sq][0] == _inf(f["upper"][pq]), joint
        if joint != "base":
            pv = j["idx_v"]
            for ours, key in [(effort, "effort"), (velocity, "velocity"), (model.damping, "damping"),
                              (model.friction, "friction")]:
                assert ours[sv][0] == _inf(f[key][pv]), (joint, key, ours[sv][0], f[key][pv])
    for link, l in f["links"].items():
        assert abs(model.link_mass(link) - l["mass"]) <= 1e-12 * max(1, l["mass"]), link
        com, inertia = model.link_inertia(link)
        if l["mass"] > 0:
            np.testing.assert_allclose(com, l["com"], atol=1e-12, err_msg=link)
        np.testing.assert_allclose(inertia, l["inertia"], atol=1e-12, err_msg=link)


def test_scene_model_slices_and_names(tmp_path):
    m = urdyn.Scene.from_file(grip_scene(tmp_path)).model
    assert m.models == ["cube", "gripper"]
    assert m.model_q_slice("cube") == slice(0, 7) and m.model_v_slice("cube") == slice(0, 6)
    assert m.model_q_slice("gripper") == slice(7, 9) and m.model_v_slice("gripper") == slice(6, 8)
    assert m.joint_q_slice("cube/base") == slice(0, 7)
    assert m.q_names[:3] == ["cube/base_x", "cube/base_y", "cube/base_z"] and len(m.q_names) == m.nq
    assert m.v_names[m.joint_v_slice("gripper/left_slide")] == ["gripper/left_slide"]
    assert m.joint_q_slice("gripper/right_slide") == slice(8, 9)
    assert m.link_mass("gripper/left") == 0.1 and m.link_mass("gripper/palm") == 0.0
    with pytest.raises(ValueError, match="unknown joint"):
        m.joint_q_slice("left_slide")
    with pytest.raises(ValueError, match="unknown model"):
        m.model_q_slice("table")


# ---------------------------------------------------------------------------
# rollout with servos: each run a Simulation stepped alone, bit for bit


def test_rollout_with_servos_equals_simulations():
    solo = urdyn.Model.from_urdf(SOLO, floating_base=True)
    b, nstep, nv, nq = 4, 60, solo.nv, solo.nq
    rng = np.random.default_rng(3)
    q0 = np.tile(solo.neutral(), (b, 1))
    q0[:, 2] = 0.35
    v0 = np.zeros((b, nv))
    kp = np.zeros((b, nv))
    kp[:, 6:] = rng.uniform(2, 6, (b, nv - 6))
    kd = np.zeros((b, nv))
    kd[:, 6:] = 0.1
    q_ref = np.tile(solo.neutral(), (b, nstep, 1))
    q_ref[:, :, 7:] += rng.uniform(-0.5, 0.5, (b, 1, nq - 7)) * np.linspace(0, 1, nstep)[None, :, None]
    v_ref = rng.uniform(-0.1, 0.1, (b, nv))
    v_ref[:, :6] = 0
    q, v = urdyn.rollout(solo, q0, v0, nstep=nstep, threads=2, kp=kp, kd=kd, q_ref=q_ref, v_ref=v_ref)
    for i in range(b):
        sim = urdyn.Simulation(solo)
        sim.set_state(q0[i], v0[i])
        sim.set_gains(kp[i], kd[i])
        for k in range(nstep):
            sim.set_targets(q_ref[i, k], v_ref[i])
            sim.step()
        assert np.array_equal(sim.q, q[i, -1]) and np.array_equal(sim.v, v[i, -1]), i
    # constant targets (B, nq) and shared gains (nv,)
    q2, _ = urdyn.rollout(solo, q0, v0, nstep=20, kp=kp[0], kd=kd[0], q_ref=q_ref[:, -1])
    sim = urdyn.Simulation(solo)
    sim.set_state(q0[1], v0[1])
    sim.set_gains(kp[0], kd[0])
    sim.set_targets(q_ref[1, -1])
    sim.step(n=20)
    assert np.array_equal(sim.q, q2[1, -1])
    with pytest.raises(ValueError, match="q_ref has shape"):
        urdyn.rollout(solo, q0, v0, nstep=5, q_ref=np.zeros((b, 3)))


# ---------------------------------------------------------------------------
# edges (defect 5)


def test_scene_quaternion_error_names_its_own_entries(tmp_path):
    path = write_scene(tmp_path, {
        "models": [
            {"name": "a", "urdf": "cube.urdf", "base": "floating", "position": [0, 0, 1]},
            {"name": "b", "urdf": "cube.urdf", "base": "floating", "position": [1, 0, 1]},
        ],
    })
    scene = urdyn.Scene.from_file(path)
    sim = urdyn.Simulation(scene)
    q = scene.q0.copy()
    s = scene.model.model_q_slice("b")
    q[s.start + 3:s.start + 7] = [0, 0, 0, 2]
    with pytest.raises(ValueError, match=rf"q\[{s.start + 3}:{s.start + 7}\].*not a unit quaternion"):
        sim.set_state(q, np.zeros(scene.model.nv))
    data = scene.model.create_data()
    with pytest.raises(ValueError, match=rf"q\[{s.start + 3}:{s.start + 7}\]"):
        urdyn.crba(scene.model, data, q)


def test_negative_counts_and_wrong_types_name_the_argument():
    model = urdyn.Model.from_urdf(UR5)
    sim = urdyn.Simulation(model)
    q0, v0 = model.neutral()[None, :], np.zeros((1, model.nv))
    for call, arg in [
        (lambda: sim.step(n=-1), "n"),
        (lambda: sim.step(n=2.5), "n"),
        (lambda: sim.step(n="3"), "n"),
        (lambda: urdyn.rollout(model, q0, v0, nstep=-5), "nstep"),
        (lambda: urdyn.rollout(model, q0, v0, nstep=1.5), "nstep"),
        (lambda: urdyn.rollout(model, q0, v0, nstep=1, threads=0), "threads"),
        (lambda: urdyn.rollout(model, q0, v0, nstep=1, threads=-2), "threads"),
        (lambda: urdyn.linearize(sim, q0, v0, v0, threads=-1), "threads"),
        (lambda: urdyn.linearize(sim, q0, v0, v0, threads=1.0), "threads"),
    ]:
        with pytest.raises(ValueError, match=rf"^{arg} must be a whole number"):
            call()
    sim.step(n=0)
    assert sim.time == 0.0


def test_keywords_a_scene_decides_are_refused(tmp_path):
    scene = urdyn.Scene.from_file(wall_scene(tmp_path))
    q0, v0 = scene.q0[None, :], scene.v0[None, :]
    for kw in [{"ground": 0.5}, {"friction": 0.1}, {"ground": 0.0}, {"friction": 1.0}, {"ground": None}]:
        key = next(iter(kw))
        with pytest.raises(ValueError, match=rf"^{key}= does not apply beside a scene"):
            urdyn.Simulation(scene, **kw)
        with pytest.raises(ValueError, match=rf"^{key}= does not apply beside a scene"):
            urdyn.rollout(scene, q0, v0, nstep=1, **kw)
    # a model still takes them
    model = urdyn.Model.from_urdf(UR5)
    urdyn.Simulation(model, ground=None, friction=0.5)
    with pytest.raises(ValueError, match="ground must be a number"):
        urdyn.Simulation(model, ground="high")


def test_applied_torques_show_the_effort_clamp():
    model = urdyn.Model.from_urdf(UR5)
    sim = urdyn.Simulation(model, ground=None)
    tau = np.zeros(model.nv)
    k = model.joint_v_slice("wrist_3_joint").start
    tau[k] = 1000.0
    sim.step(tau)
    applied = sim.applied_torques
    assert applied[k] == model.effort_limits[k] < 1000.0
    sim2 = urdyn.Simulation(model, ground=None)
    tau2 = tau.copy()
    tau2[k] = model.effort_limits[k]
    sim2.step(tau2)
    assert np.array_equal(sim.q, sim2.q)
    assert sim.penetration == 0.0


def test_reset_replays_and_set_state_takes_a_time():
    solo = urdyn.Model.from_urdf(SOLO, floating_base=True)
    sim = urdyn.Simulation(solo)
    q0 = solo.neutral()
    q0[2] = 0.3
    sim.set_state(q0, np.zeros(solo.nv), time=0.0)
    sim.set_gains(3.0, 0.1)
    sim.set_targets(q0)
    sim.step(n=150)
    first = sim.q.copy()
    sim.reset()
    assert sim.time == 0.0 and np.array_equal(sim.q, solo.neutral())
    sim.set_state(q0, np.zeros(solo.nv))
    sim.step(n=150)
    assert np.array_equal(sim.q, first)
    sim.set_state(q0, np.zeros(solo.nv), time=2.5)
    assert sim.time == 2.5
    sim.set_state(q0, np.zeros(solo.nv))
    assert sim.time == 2.5


# ---------------------------------------------------------------------------
# pictures


def test_write_html_from_a_trajectory_and_a_recording(tmp_path):
    model = urdyn.Model.from_urdf(UR5)
    qs = np.tile(model.neutral(), (50, 1))
    qs[:, 0] = np.linspace(0, 1, 50)
    page = tmp_path / "traj.html"
    frames = urdyn.write_html(page, model, qs, dt=0.02)
    assert frames >= 2 and "<html" in page.read_text()[:2000].lower()
    with pytest.raises(ValueError, match="not both"):
        urdyn.write_html(page, model, qs, t=np.arange(50.0), dt=0.1)
    scene = urdyn.Scene.from_file(wall_scene(tmp_path))
    sim = urdyn.Simulation(scene)
    with pytest.raises(ValueError, match="nothing recorded"):
        sim.write_html(tmp_path / "x.html")
    sim.record(True)
    sim.step(n=100)
    sim.record(False)
    sim.step(n=10)
    rec = tmp_path / "rec.html"
    assert sim.write_html(rec) >= 2
    assert "wall" in rec.read_text()
