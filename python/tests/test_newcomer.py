"""A newcomer's first hour from Python (issue 20): a base quaternion off unit norm
refused by every function taking q, a missing file raised as FileNotFoundError, a
missing collision mesh explained in Python's terms, and a Pinocchio user's vectors
used as they are (the same degrees of freedom in the same order; continuous joints
through from_pinocchio_q / to_pinocchio_q), checked against Pinocchio itself when
it is installed."""

import math
import re
from pathlib import Path

import numpy as np
import pytest

import urdyn

ROOT = Path(__file__).resolve().parents[2]
LAMP = ROOT / "assets" / "lamp.urdf"
SOLO = ROOT / "assets" / "robots" / "solo12.urdf"
TIAGO = ROOT / "assets" / "robots" / "tiago.urdf"
MISSING_MESH = ROOT / "tests" / "bad" / "sim_missing_mesh.urdf"

try:
    import pinocchio as pin
except ImportError:  # the Pinocchio comparisons are skipped
    pin = None


def _erd_robots():
    """example-robot-data's URDFs, from its pip package (cmeel's prefix in
    site-packages) if installed."""
    import site

    for sp in site.getsitepackages():
        d = Path(sp) / "cmeel.prefix" / "share" / "example-robot-data" / "robots"
        if d.is_dir():
            return sorted(d.glob("*/*/*.urdf"))
    return []


ERD = _erd_robots()


def unit_base_q(model, rng):
    """A configuration with a random unit base quaternion."""
    q = model.neutral()
    q[7:] = rng.uniform(-1, 1, model.nq - 7)
    quat = rng.normal(size=4)
    q[3:7] = quat / np.linalg.norm(quat)
    q[0:3] = rng.uniform(-1, 1, 3)
    return q


# ---------------------------------------------------------------------------
# a base quaternion off unit norm: ValueError from every function taking q


def _q_takers(model):
    """(name, call(q)) for every function and method of the package taking q."""
    data = model.create_data()
    nv = model.nv
    v, a = np.full(nv, 0.1), np.full(nv, 0.2)
    link = model.link_names[-1]
    calls = [
        ("rnea", lambda q: urdyn.rnea(model, data, q, v, a)),
        ("nonlinear_effects", lambda q: urdyn.nonlinear_effects(model, data, q, v)),
        ("crba", lambda q: urdyn.crba(model, data, q)),
        ("aba", lambda q: urdyn.aba(model, data, q, v, a)),
        ("forward_dynamics", lambda q: urdyn.forward_dynamics(model, data, q, v, a)),
        ("forward_dynamics_rnea", lambda q: urdyn.forward_dynamics_rnea(model, data, q, v, a)),
        ("frame_placement", lambda q: urdyn.frame_placement(model, data, q, link)),
        ("frame_jacobian", lambda q: urdyn.frame_jacobian(model, data, q, link)),
        ("frame_velocity", lambda q: urdyn.frame_velocity(model, data, q, v, link)),
        ("center_of_mass", lambda q: urdyn.center_of_mass(model, data, q)),
        ("center_of_mass_jacobian", lambda q: urdyn.center_of_mass_jacobian(model, data, q)),
        ("centroidal_momentum", lambda q: urdyn.centroidal_momentum(model, data, q, v)),
        ("kinetic_energy", lambda q: urdyn.kinetic_energy(model, data, q, v)),
        ("potential_energy", lambda q: urdyn.potential_energy(model, data, q)),
        ("to_pinocchio_q", lambda q: urdyn.to_pinocchio_q(model, q)),
        ("from_pinocchio_q", lambda q: urdyn.from_pinocchio_q(model, urdyn.to_pinocchio_q(model, q))),
        ("Simulation.set_state", lambda q: urdyn.Simulation(model, ground=None).set_state(q, v)),
        ("rollout", lambda q: urdyn.rollout(model, q[None, :], v[None, :], nstep=1, ground=None)),
    ]
    # functions other parts of the package add (python.md): checked when present
    optional = {
        "rnea_derivatives": lambda f: (lambda q: f(model, data, q, v, a)),
        "aba_derivatives": lambda f: (lambda q: f(model, data, q, v, a)),
        "frame_jacobian_time_variation": lambda f: (lambda q: f(model, data, q, v, link)),
        "integrate": lambda f: (lambda q: f(model, q, v)),
        "difference": lambda f: (lambda q: f(model, q, model.neutral())),
    }
    for name, make in optional.items():
        if hasattr(urdyn, name):
            calls.append((name, make(getattr(urdyn, name))))
    return calls


@pytest.mark.parametrize("norm", [0.0, 2.0, 1.0 + 2e-3, 1.0 - 2e-3])
def test_base_quaternion_off_unit_norm_is_refused_everywhere(norm):
    model = urdyn.Model.from_urdf(SOLO, floating_base=True)
    q = unit_base_q(model, np.random.default_rng(1))
    q[3:7] *= norm
    for name, call in _q_takers(model):
        with pytest.raises(ValueError, match=r"q\S*\[3:7\].*not a unit quaternion \(norm ") as err:
            call(q)
        msg = str(err.value)
        assert "\n" not in msg, (name, msg)
        # the norm the message reports is the one given
        reported = float(re.search(r"norm ([^)]+)\)", msg).group(1))
        assert abs(reported - norm) < 1e-12, (name, msg)


def test_base_quaternion_within_tolerance_is_normalised():
    """Within 1e-3 of unit norm the engine normalises (as the CLI does): the
    results equal those of the normalised q."""
    model = urdyn.Model.from_urdf(SOLO, floating_base=True)
    data = model.create_data()
    rng = np.random.default_rng(2)
    q = unit_base_q(model, rng)
    v, a = rng.uniform(-1, 1, model.nv), rng.uniform(-1, 1, model.nv)
    q_off = q.copy()
    q_off[3:7] *= 1.0 + 5e-4
    np.testing.assert_allclose(
        urdyn.rnea(model, data, q_off, v, a), urdyn.rnea(model, data, q, v, a), rtol=1e-12, atol=1e-12
    )
    np.testing.assert_allclose(urdyn.crba(model, data, q_off), urdyn.crba(model, data, q), rtol=1e-12, atol=1e-12)


def test_rollout_names_the_batch_row_of_a_bad_quaternion():
    model = urdyn.Model.from_urdf(LAMP, floating_base=True)
    q0 = np.tile(model.neutral(), (3, 1))
    q0[2, 3:7] = [0.0, 0.0, 0.0, 0.0]
    v0 = np.zeros((3, model.nv))
    with pytest.raises(ValueError, match=r"q0\[2\]\[3:7\].*not a unit quaternion \(norm 0"):
        urdyn.rollout(model, q0, v0, nstep=1)


def test_fixed_base_q_has_no_quaternion_check():
    """A fixed-base model's q is joint angles only: any finite value is taken."""
    model = urdyn.Model.from_urdf(ROOT / "assets" / "robots" / "ur5.urdf")
    data = model.create_data()
    q = np.zeros(model.nq)
    urdyn.rnea(model, data, q, np.zeros(model.nv), np.zeros(model.nv))


# ---------------------------------------------------------------------------
# missing files and meshes


def test_missing_urdf_raises_file_not_found_naming_the_path(tmp_path):
    path = tmp_path / "no_such_robot.urdf"
    with pytest.raises(FileNotFoundError) as err:
        urdyn.Model.from_urdf(path)
    assert str(path) in str(err.value)
    assert not isinstance(err.value, ValueError)
    with pytest.raises(FileNotFoundError, match="no_such_robot.urdf"):
        urdyn.Model.from_urdf(str(path), floating_base=True)


def test_a_directory_or_bad_urdf_stays_a_value_error(tmp_path):
    with pytest.raises(ValueError, match="directory"):
        urdyn.Model.from_urdf(tmp_path)
    bad = tmp_path / "bad.urdf"
    bad.write_text("<robot name='x'><link name='a'/><joint name='j' type='revolute'/></robot>")
    with pytest.raises(ValueError, match="bad.urdf"):
        urdyn.Model.from_urdf(bad)


def test_missing_collision_mesh_speaks_python():
    model = urdyn.Model.from_urdf(MISSING_MESH, floating_base=True)
    with pytest.raises(FileNotFoundError) as err:
        urdyn.Simulation(model)
    msg = str(err.value)
    assert "foot_missing.stl" in msg and "sim_missing_mesh.urdf" in msg, msg
    assert "package_dirs=" in msg and "ground=None" in msg, msg
    assert "--package-path" not in msg and "--no-ground" not in msg, msg
    assert "\n" not in msg
    with pytest.raises(FileNotFoundError, match="ground=None"):
        urdyn.rollout(model, model.neutral()[None, :], np.zeros((1, model.nv)), nstep=1)
    # the two ways out the message names both work
    urdyn.Simulation(model, ground=None).step(n=2)
    urdyn.Simulation(model, package_dirs=[str(MISSING_MESH.parent)], ground=None)


# ---------------------------------------------------------------------------
# Pinocchio's q: continuous joints as (cos, sin)


def continuous_joints(path):
    """The names of the URDF's continuous joints, read from its text."""
    import xml.etree.ElementTree as ET

    return {j.get("name") for j in ET.parse(path).getroot().iter("joint") if j.get("type") == "continuous"}


@pytest.mark.parametrize("floating", [False, True])
def test_pinocchio_q_round_trip(floating):
    model = urdyn.Model.from_urdf(TIAGO, floating_base=floating)
    cont = continuous_joints(TIAGO)
    assert len(cont) >= 2  # the wheels
    rng = np.random.default_rng(4)
    q = unit_base_q(model, rng) if floating else rng.uniform(-3, 3, model.nq)
    qp = urdyn.to_pinocchio_q(model, q)
    base = 7 if floating else 0
    # the expected layout, built from the URDF's joint types: the base as it is,
    # then per degree of freedom its coordinate, or (cos, sin) for a continuous one
    want = list(q[:base])
    for name, x in zip(model.dof_names, q[base:]):
        want += [math.cos(x), math.sin(x)] if name in cont else [x]
    assert qp.shape == (model.nq + len(cont),)
    np.testing.assert_allclose(qp, want, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(qp[:base], q[:base])
    back = urdyn.from_pinocchio_q(model, qp)
    assert back.shape == q.shape
    # continuous angles come back wrapped into (-pi, pi], the rest exactly
    for i, name in enumerate(model.dof_names):
        if name in cont:
            assert -math.pi < back[base + i] <= math.pi
            assert abs(math.remainder(back[base + i] - q[base + i], 2 * math.pi)) < 1e-14
        else:
            assert back[base + i] == q[base + i]
    np.testing.assert_array_equal(back[:base], q[:base])
    np.testing.assert_allclose(urdyn.to_pinocchio_q(model, back), qp, rtol=0, atol=1e-15)


def test_pinocchio_q_without_continuous_joints_is_q():
    model = urdyn.Model.from_urdf(SOLO, floating_base=True)
    q = unit_base_q(model, np.random.default_rng(5))
    np.testing.assert_array_equal(urdyn.to_pinocchio_q(model, q), q)
    np.testing.assert_array_equal(urdyn.from_pinocchio_q(model, q), q)


def test_pinocchio_q_errors():
    model = urdyn.Model.from_urdf(TIAGO)
    qp = urdyn.to_pinocchio_q(model, model.neutral())
    with pytest.raises(ValueError, match="q_pin has"):
        urdyn.from_pinocchio_q(model, qp[:-1])
    with pytest.raises(ValueError, match=r"q has \d+ entries"):
        urdyn.to_pinocchio_q(model, qp)
    # a (0, 0) pair: find the first continuous pair (cos 0, sin 0) = (1, 0)
    k = int(np.flatnonzero(qp == 1.0)[0])
    bad = qp.copy()
    bad[k] = 0.0
    with pytest.raises(ValueError, match=r"q_pin\[\d+:\d+\].*continuous joint .*\(0, 0\)"):
        urdyn.from_pinocchio_q(model, bad)
    bad[k] = np.nan
    with pytest.raises(ValueError, match="not a finite number"):
        urdyn.from_pinocchio_q(model, bad)


# ---------------------------------------------------------------------------
# against Pinocchio: the same order, the same numbers, no reordering


def _pinocchio_model(path, floating):
    root = [pin.JointModelFreeFlyer()] if floating else []
    return pin.buildModelFromUrdf(str(path), *root, mimic=True)


def _pinocchio_dof_names(pm):
    """Pinocchio's joint names in its order, the root joint and mimic joints
    (nv = 0 with mimic=True) left out."""
    return [pm.names[i] for i in range(1, pm.njoints) if pm.joints[i].nv > 0 and pm.names[i] != "root_joint"]


def compare_with_pinocchio(path, floating, seed=0):
    """dof_names and nq/nv as Pinocchio's; rnea and crba at a random Pinocchio
    state equal to Pinocchio's with no reordering. Returns the worst relative
    error."""
    model = urdyn.Model.from_urdf(path, floating_base=floating)
    pm = _pinocchio_model(path, floating)
    assert model.dof_names == _pinocchio_dof_names(pm), path
    assert model.nv == pm.nv, path
    assert len(urdyn.to_pinocchio_q(model, model.neutral())) == pm.nq, path
    rng = np.random.default_rng(seed)
    # a random Pinocchio configuration: its neutral moved along a random tangent
    q_pin = pin.integrate(pm, pin.neutral(pm), rng.uniform(-1, 1, pm.nv))
    v, a = rng.uniform(-1, 1, pm.nv), rng.uniform(-1, 1, pm.nv)
    pd = pm.createData()
    tau_pin = pin.rnea(pm, pd, q_pin, v, a)
    H_pin = pin.crba(pm, pd, q_pin)
    H_pin = np.triu(H_pin) + np.triu(H_pin, 1).T
    data = model.create_data()
    q = urdyn.from_pinocchio_q(model, q_pin)
    tau = urdyn.rnea(model, data, q, v, a)
    H = urdyn.crba(model, data, q)
    np.testing.assert_allclose(urdyn.to_pinocchio_q(model, q), q_pin, rtol=0, atol=1e-14)
    err = 0.0
    for got, want in ((tau, tau_pin), (H, H_pin)):
        e = np.max(np.abs(got - want), initial=0.0) / max(1.0, np.max(np.abs(want), initial=0.0))
        err = max(err, float(e))
    assert err < 1e-10, (path, floating, err)
    return err


needs_pinocchio = pytest.mark.skipif(pin is None, reason="pinocchio is not installed")


@needs_pinocchio
@pytest.mark.parametrize("path", sorted((ROOT / "assets" / "robots").glob("*.urdf")), ids=lambda p: p.stem)
@pytest.mark.parametrize("floating", [False, True])
def test_repository_robots_against_pinocchio(path, floating):
    compare_with_pinocchio(path, floating)


# robots whose order or joints are the interesting cases: siblings out of
# byte-wise order (allegro, baxter, pr2, tiago), continuous joints (tiago, pr2,
# kinova, the continuous pendulum), mimic joints (panda, pr2, baxter)
INTERESTING = [
    "allegro_left_hand.urdf",
    "allegro_right_hand.urdf",
    "baxter.urdf",
    "pr2.urdf",
    "tiago.urdf",
    "tiago_dual.urdf",
    "tiago_no_hand.urdf",
    "kinova.urdf",
    "double_pendulum_continuous.urdf",
    "talos_reduced.urdf",
    "panda.urdf",
]


@needs_pinocchio
@pytest.mark.skipif(not ERD, reason="example-robot-data is not installed")
@pytest.mark.parametrize("name", INTERESTING)
def test_example_robot_data_against_pinocchio(name):
    paths = [p for p in ERD if p.name == name]
    assert paths, f"{name} not in example-robot-data"
    for p in paths:
        for floating in (False, True):
            compare_with_pinocchio(p, floating)


def mimic_joints(path):
    """The names of the URDF's joints with a <mimic> element, read from its text."""
    import xml.etree.ElementTree as ET

    return {j.get("name") for j in ET.parse(path).getroot().iter("joint") if j.find("mimic") is not None}


@needs_pinocchio
@pytest.mark.skipif(not ERD, reason="example-robot-data is not installed")
def test_every_example_robot_data_robot_against_pinocchio():
    """Every URDF of example-robot-data that both load: the same dof_names, and
    rnea/crba at a Pinocchio state equal to Pinocchio's, fixed and floating.
    Where Pinocchio refuses mimic=True (a mimic joint whose leader it places
    elsewhere in the tree), its mimic=False model still gives the order: its
    joint names without the mimic joints are dof_names."""
    compared, names_only, skipped = [], [], []
    for p in ERD:
        try:
            urdyn.Model.from_urdf(p)
        except ValueError as e:
            skipped.append((p.name, str(e)[:100]))
            continue
        try:
            _pinocchio_model(p, False)
        except (ValueError, RuntimeError):
            pm = pin.buildModelFromUrdf(str(p))
            mimic = mimic_joints(p)
            pin_names = [n for n in _pinocchio_dof_names(pm) if n not in mimic]
            assert urdyn.Model.from_urdf(p).dof_names == pin_names, p
            names_only.append(p.name)
            continue
        for floating in (False, True):
            compare_with_pinocchio(p, floating)
        compared.append(p.name)
    print(f"\ncompared {len(compared)} robots, names only {names_only}, skipped {skipped}")
    assert len(compared) >= 60, (len(compared), skipped)
