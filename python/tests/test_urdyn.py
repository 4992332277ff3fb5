"""The Python package against the committed Pinocchio fixtures (the same
figures as the Rust tests), rollouts against Simulation stepped alone, errors,
pickling and the GIL."""

import json
import pickle
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import urdyn

ROOT = Path(__file__).resolve().parents[2]
FIXTURES = ROOT / "tests" / "fixtures"
CASES = sorted(
    p.name for p in FIXTURES.iterdir() if (p / "meta.json").exists() and (p / "expected.json").exists()
)
LAMP = ROOT / "assets" / "lamp.urdf"
UR5 = ROOT / "assets" / "robots" / "ur5.urdf"


def rel(got, want):
    got, want = np.asarray(got, float), np.asarray(want, float)
    assert got.shape == want.shape
    return float(np.max(np.abs(got - want), initial=0.0) / max(1.0, np.max(np.abs(want), initial=0.0)))


def vectors(model, state):
    """The contract's state object as engine-order q, v, a, tau."""
    fb = model.floating_base
    names = model.dof_names
    o = 6 if fb else 0
    q = model.neutral()
    v, a, tau = (np.zeros(model.nv) for _ in range(3))
    for vec, key, off in ((q, "q", 7 if fb else 0), (v, "v", o), (a, "a", o), (tau, "tau", o)):
        for name, x in state.get(key, {}).items():
            vec[off + names.index(name)] = x
    b = state.get("base", {}) if fb else {}
    if fb:
        q[0:3] = b.get("position", [0, 0, 0])
        quat = np.asarray(b.get("orientation_xyzw", [0, 0, 0, 1]), float)
        q[3:7] = quat / np.linalg.norm(quat)
        v[0:3] = b.get("linear_velocity", [0, 0, 0])
        v[3:6] = b.get("angular_velocity", [0, 0, 0])
        a[0:3] = b.get("linear_acceleration", [0, 0, 0])
        a[3:6] = b.get("angular_acceleration", [0, 0, 0])
        tau[0:3] = b.get("force", [0, 0, 0])
        tau[3:6] = b.get("torque", [0, 0, 0])
    return q, v, a, tau


def by_name(model, values, base=None):
    """Engine-order vector of a contract dict (and the base's 6 first)."""
    out = [values[n] for n in model.dof_names]
    return np.array(list(base or []) + out, float)


@pytest.mark.parametrize("case", CASES)
def test_fixtures_agree_with_pinocchio(case):
    meta = json.loads((FIXTURES / case / "meta.json").read_text())
    states = json.loads((FIXTURES / case / "states.json").read_text())
    expected = json.loads((FIXTURES / case / "expected.json").read_text())
    model = urdyn.Model.from_urdf(ROOT / meta["urdf"], floating_base=meta["floating_base"])
    data = model.create_data()
    fb = model.floating_base
    order = expected["dof_names"]
    # engine index of each expected row (the base's 6 first)
    perm = ([0, 1, 2, 3, 4, 5] if fb else []) + [
        (6 if fb else 0) + model.dof_names.index(n) for n in order
    ]
    worst = 0.0
    for k, (state, want) in enumerate(zip(states["states"], expected["results"])):
        g = state.get("gravity", states.get("gravity", [0, 0, -9.81]))
        model.gravity = g
        q, v, a, tau = vectors(model, state)
        # contract v2: the state's external wrenches enter every dynamics quantity
        fx = {
            link: (w.get("force", [0.0] * 3), w.get("torque", [0.0] * 3))
            for link, w in state.get("fext", {}).items()
        } or None
        wb = want.get("base", {})
        base = lambda *keys: [x for key in keys for x in wb[key]] if fb else None  # noqa: E731
        errs = {
            "tau": rel(urdyn.rnea(model, data, q, v, a, fx), by_name(model, want["tau"], base("force", "torque"))),
            "bias": rel(
                urdyn.nonlinear_effects(model, data, q, v, fx),
                by_name(model, want["bias"], base("bias_force", "bias_torque")),
            ),
            "qdd": rel(
                urdyn.forward_dynamics(model, data, q, v, tau, fx),
                by_name(model, want["qdd"], base("linear_acceleration", "angular_acceleration")),
            ),
            "H": rel(urdyn.crba(model, data, q)[np.ix_(perm, perm)], want["mass_matrix"]),
        }
        if fx is None:  # forward_dynamics_rnea takes no external wrenches
            errs["qdd_rnea"] = rel(
                urdyn.forward_dynamics_rnea(model, data, q, v, tau),
                by_name(model, want["qdd"], base("linear_acceleration", "angular_acceleration")),
            )
        if not meta.get("has_mimic", case in ("mimic", "panda")):
            errs["qdd_aba"] = rel(
                urdyn.aba(model, data, q, v, tau, fx),
                by_name(model, want["qdd"], base("linear_acceleration", "angular_acceleration")),
            )
        for link, pose in want["link_poses"].items():
            m = urdyn.frame_placement(model, data, q, link)
            errs[f"pose {link}"] = max(rel(m[:3, 3], pose["position"]), rel(m[:3, :3], pose["rotation"]))
        # contract v2 kinematics (columns in the expected order: perm)
        for link, fw in want.get("frames", {}).items():
            for ref, key in (("world_aligned", "jacobian"), ("local", "jacobian_local")):
                J = urdyn.frame_jacobian(model, data, q, link, reference=ref)
                errs[f"{key} {link}"] = rel(J[:, perm], fw[key])
            vel = urdyn.frame_velocity(model, data, q, v, link)
            errs[f"velocity {link}"] = rel(vel, fw["velocity"]["linear"] + fw["velocity"]["angular"])
        errs["com"] = rel(urdyn.center_of_mass(model, data, q), want["com"]["position"])
        errs["com_jacobian"] = rel(urdyn.center_of_mass_jacobian(model, data, q)[:, perm], want["com"]["jacobian"])
        hg = urdyn.centroidal_momentum(model, data, q, v)
        errs["momentum"] = rel(hg, want["momentum"]["linear"] + want["momentum"]["angular"])
        errs["kinetic"] = rel([urdyn.kinetic_energy(model, data, q, v)], [want["energy"]["kinetic"]])
        errs["potential"] = rel([urdyn.potential_energy(model, data, q)], [want["energy"]["potential"]])
        what, e = max(errs.items(), key=lambda kv: kv[1])
        assert e <= 1e-12, f"{case} state {k}: {what} off by {e:.2e}"
        worst = max(worst, e)
    print(f"{case}: worst relative error {worst:.1e}")


def test_fd_of_id_with_fext_is_identity():
    model = urdyn.Model.from_urdf(UR5, floating_base=True)
    data = model.create_data()
    rng = np.random.default_rng(1)
    q = model.neutral()
    q[7:] = rng.uniform(-1, 1, model.nv - 6)
    quat = rng.normal(size=4)
    q[3:7] = quat / np.linalg.norm(quat)
    v, a = rng.normal(size=model.nv), rng.normal(size=model.nv)
    fext = {"wrist_3_link": ([1.0, -2.0, 3.0], [0.1, 0.2, -0.3]), "base_link": ([0, 0, 5.0], [0, 0, 0])}
    tau = urdyn.rnea(model, data, q, v, a, fext)
    assert not np.allclose(tau, urdyn.rnea(model, data, q, v, a))
    for fd in (urdyn.aba, urdyn.forward_dynamics):
        np.testing.assert_allclose(fd(model, data, q, v, tau, fext), a, atol=1e-9)


BOX = """<robot name="box"><link name="b"><inertial><origin xyz="0 0 0"/><mass value="2"/>
<inertia ixx="0.1" iyy="0.2" izz="0.3" ixy="0" ixz="0" iyz="0"/></inertial></link></robot>"""


def test_fext_is_a_wrench_at_the_link_origin():
    # one free body with its centre of mass at the link origin, turned: a force
    # there accelerates it by f/m (world) and does not turn it; a pure couple τ
    # turns it by I⁻¹ τ (body frame)
    model = urdyn.Model.from_urdf_string(BOX, floating_base=True)
    model.gravity = [0, 0, 0]
    data = model.create_data()
    q, v, tau = model.neutral(), np.zeros(6), np.zeros(6)
    q[:3] = [1.0, -2.0, 0.5]
    q[3:7] = [0, 0, np.sin(0.25), np.cos(0.25)]  # 0.5 rad about z
    R = urdyn.frame_placement(model, data, q, "b")[:3, :3]
    f = np.array([2.0, 1.0, -4.0])
    qdd = urdyn.forward_dynamics(model, data, q, v, tau, {"b": (f, [0, 0, 0])})
    np.testing.assert_allclose(R @ qdd[:3], f / 2.0, atol=1e-12)
    np.testing.assert_allclose(qdd[3:], 0, atol=1e-12)
    t = np.array([0.3, -0.2, 0.6])
    qdd = urdyn.forward_dynamics(model, data, q, v, tau, {"b": ([0, 0, 0], t)})
    np.testing.assert_allclose(qdd[3:], (R.T @ t) / [0.1, 0.2, 0.3], atol=1e-12)
    np.testing.assert_allclose(qdd[:3], 0, atol=1e-12)


def test_jacobians_agree_with_finite_differences():
    model = urdyn.Model.from_urdf(UR5, floating_base=True)
    data = model.create_data()
    rng = np.random.default_rng(2)
    q = model.neutral()
    q[7:] = rng.uniform(-1, 1, model.nv - 6)
    v = rng.normal(size=model.nv)
    link = "wrist_3_link"
    h = 1e-6

    def integrate(q, dv):
        # the base moves in its body frame: position += R dv_lin, R = R exp(dv_ang)
        from numpy.linalg import norm

        qn = q.copy()
        x, y, z, w = q[3:7]
        r = np.array(
            [
                [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
            ]
        )
        qn[0:3] = q[0:3] + r @ dv[0:3]
        th = norm(dv[3:6])
        if th > 0:
            ax = dv[3:6] / th
            dq = np.r_[ax * np.sin(th / 2), np.cos(th / 2)]
            # q ⊗ dq (xyzw)
            x2, y2, z2, w2 = dq
            qn[3:7] = [
                w * x2 + x * w2 + y * z2 - z * y2,
                w * y2 - x * z2 + y * w2 + z * x2,
                w * z2 + x * y2 - y * x2 + z * w2,
                w * w2 - x * x2 - y * y2 - z * z2,
            ]
        qn[7:] = q[7:] + dv[6:]
        return qn

    p0 = urdyn.frame_placement(model, data, q, link)
    p1 = urdyn.frame_placement(model, data, integrate(q, h * v), link)
    lin_fd = (p1[:3, 3] - p0[:3, 3]) / h
    J = urdyn.frame_jacobian(model, data, q, link)
    np.testing.assert_allclose(J[:3] @ v, lin_fd, atol=1e-5)
    c0 = urdyn.center_of_mass(model, data, q)
    c1 = urdyn.center_of_mass(model, data, integrate(q, h * v))
    np.testing.assert_allclose(urdyn.center_of_mass_jacobian(model, data, q) @ v, (c1 - c0) / h, atol=1e-5)
    # local = Rᵀ world-aligned, velocity = J v
    Jl = urdyn.frame_jacobian(model, data, q, link, reference="local")
    R = p0[:3, :3]
    np.testing.assert_allclose(Jl[:3], R.T @ J[:3], atol=1e-12)
    np.testing.assert_allclose(urdyn.frame_velocity(model, data, q, v, link), J @ v, atol=1e-12)
    # momentum: linear = M ċ; energy = ½ vᵀ H v
    hg = urdyn.centroidal_momentum(model, data, q, v)
    np.testing.assert_allclose(hg[:3], model.total_mass * (c1 - c0) / h, atol=1e-4)
    H = urdyn.crba(model, data, q)
    assert abs(urdyn.kinetic_energy(model, data, q, v) - 0.5 * v @ H @ v) < 1e-10


def lamp_start(model):
    q = model.neutral()
    q[2] = 0.3
    return q, np.zeros(model.nv)


@pytest.mark.parametrize("integrator", [None, "rk4", "dop853"])
def test_rollout_equals_simulation_bit_for_bit(integrator):
    model = urdyn.Model.from_urdf(LAMP, floating_base=True)
    q, v = lamp_start(model)
    rng = np.random.default_rng(3)
    B, n = 5, 300
    q0 = np.tile(q, (B, 1))
    q0[:, 2] += rng.uniform(0, 0.2, B)
    v0 = rng.normal(scale=0.3, size=(B, model.nv))
    tau = rng.normal(scale=0.05, size=(B, model.nv))
    Q, V = urdyn.rollout(model, q0, v0, tau=tau, nstep=n, threads=2, integrator=integrator)
    assert Q.shape == (B, n + 1, model.nq) and V.shape == (B, n + 1, model.nv)
    for b in (0, B - 1):
        sim = urdyn.Simulation(model, integrator=integrator)
        sim.set_state(q0[b], v0[b])
        for k in range(n):
            sim.step(tau[b])
            assert np.array_equal(Q[b, k + 1], sim.q) and np.array_equal(V[b, k + 1], sim.v), (b, k)
    # threads do not change results
    Q1, _ = urdyn.rollout(model, q0, v0, tau=tau, nstep=n, threads=1, integrator=integrator)
    assert np.array_equal(Q, Q1)


def test_rollout_per_step_torques_and_no_ground():
    model = urdyn.Model.from_urdf(UR5)
    B, n = 3, 50
    q0 = np.zeros((B, model.nq))
    v0 = np.zeros((B, model.nv))
    tau = np.zeros((B, n, model.nv))
    tau[:, :, 0] = 1.0
    Q, V = urdyn.rollout(model, q0, v0, tau=tau, nstep=n, ground=None)
    sim = urdyn.Simulation(model, ground=None)
    sim.set_state(q0[1], v0[1])
    for k in range(n):
        sim.step(tau[1, k])
    assert np.array_equal(Q[1, -1], sim.q)
    assert V[0, -1, 0] > 0  # the torque turned the first joint


def test_pickle_round_trip():
    model = urdyn.Model.from_urdf(UR5, floating_base=True)
    model.gravity = [0.1, 0.0, -9.0]
    m2 = pickle.loads(pickle.dumps(model))
    assert (m2.nq, m2.nv, m2.dof_names, m2.link_names) == (model.nq, model.nv, model.dof_names, model.link_names)
    np.testing.assert_array_equal(m2.gravity, model.gravity)
    d1, d2 = model.create_data(), m2.create_data()
    q = model.neutral()
    v = np.linspace(-1, 1, model.nv)
    assert np.array_equal(urdyn.rnea(model, d1, q, v, v), urdyn.rnea(m2, d2, q, v, v))


def test_bad_inputs_are_value_errors():
    model = urdyn.Model.from_urdf(UR5)
    data = model.create_data()
    q, v = model.neutral(), np.zeros(model.nv)
    cases = [
        (lambda: urdyn.rnea(model, data, q[:-1], v, v), "q has 5 entries"),
        (lambda: urdyn.rnea(model, data, np.r_[q, 0.0], v, v), "q has 7 entries"),
        (lambda: urdyn.rnea(model, data, q, v, np.r_[v[:-1], np.nan]), "not a finite"),
        (lambda: urdyn.rnea(model, data, q, v, v, {"nolink": ([0, 0, 0], [0, 0, 0])}), "unknown link"),
        (lambda: urdyn.rnea(model, data, q, v, v, {"wrist_3_link": ([0, 0, 0, 0], [0, 0, 0])}), "force"),
        (lambda: urdyn.frame_jacobian(model, data, q, "wrist_3_lnk"), "nearest: \"wrist_3_link\""),
        (lambda: urdyn.frame_jacobian(model, data, q, "wrist_3_link", reference="global"), "reference"),
        (lambda: urdyn.crba(model, urdyn.Model.from_urdf(LAMP).create_data(), q), "another model"),
        # (a URDF that does not exist: FileNotFoundError, test_newcomer.py)
        (lambda: urdyn.Model.from_urdf_string("<robot name='x'><link name='a'></robot>"), "<string>"),
        (lambda: urdyn.Simulation(model, dt=-1.0), "dt"),
        (lambda: urdyn.Simulation(model, integrator="leapfrog"), "integrator"),
        (lambda: urdyn.rollout(model, np.zeros((2, 5)), np.zeros((2, 6))), "q0 has shape"),
        (lambda: urdyn.rollout(model, np.zeros((2, 6)), np.zeros((2, 6)), tau=np.zeros((2, 3))), "tau has shape"),
        (lambda: urdyn.rollout(model, np.zeros((2, 6)), np.zeros((2, 6)), threads=0), "threads"),
    ]
    for call, words in cases:
        with pytest.raises(ValueError, match=None) as err:
            call()
        assert words in str(err.value), (words, str(err.value))
        assert "\n" not in str(err.value)
    lamp = urdyn.Model.from_urdf(LAMP, floating_base=True)
    with pytest.raises(ValueError):
        urdyn.aba(lamp, lamp.create_data(), lamp.neutral(), [0] * 8, np.zeros(lamp.nv))
    mimic = urdyn.Model.from_urdf(ROOT / "tests" / "urdf" / "mimic.urdf")
    with pytest.raises(ValueError, match="mimic"):
        urdyn.aba(mimic, mimic.create_data(), mimic.neutral(), np.zeros(mimic.nv), np.zeros(mimic.nv))


def test_diverging_rollout_raises_with_partial_results():
    # a passive pendulum with a step far past RK4's stability: the energy guard stops it
    model = urdyn.Model.from_urdf(ROOT / "tests" / "urdf" / "double_pendulum.urdf")
    q0 = np.array([[0.1, 0.0], [1.5, 1.0]])[:, : model.nq]
    v0 = np.zeros((2, model.nv))
    with pytest.raises(urdyn.SimulationError) as err:
        urdyn.rollout(model, q0, v0, nstep=400, dt=0.2, integrator="rk4", ground=None)
    e = err.value
    assert e.q.shape == (2, 401, model.nq) and e.index in (0, 1)
    assert np.isfinite(e.q[e.index, 0]).all() and np.isnan(e.q[e.index, -1]).all()


def test_gil_is_released_during_a_rollout():
    model = urdyn.Model.from_urdf(UR5)
    B = 16
    q0 = np.random.default_rng(4).uniform(-1, 1, (B, model.nq))
    v0 = np.zeros((B, model.nv))
    ticks = []
    done = threading.Event()

    def tick():
        while not done.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    t = threading.Thread(target=tick)
    t.start()
    start = time.perf_counter()
    urdyn.rollout(model, q0, v0, nstep=4000, threads=1, ground=None)
    end = time.perf_counter()
    done.set()
    t.join()
    during = [x for x in ticks if start < x < end]
    assert end - start > 0.05, "rollout too short to tell"
    assert len(during) >= 5, f"the other thread ran {len(during)} times in {end - start:.3f} s"


def test_ray_example_equals_local_rollout():
    ray = pytest.importorskip("ray", reason="ray not installed (pip install ray)")
    import importlib.util

    spec = importlib.util.spec_from_file_location("ray_rollouts", ROOT / "python" / "examples" / "ray_rollouts.py")
    ex = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(ex)
    ray.init(num_cpus=2, include_dashboard=False, ignore_reinit_error=True)
    try:
        model = urdyn.Model.from_urdf(UR5)
        q0, v0 = ex.initial_states(model, 6)
        q, v = ex.rollouts_on_ray(model, q0, v0, nstep=200, batches=2, ground=None)
        lq, lv = urdyn.rollout(model, q0, v0, nstep=200, ground=None)
        assert np.array_equal(q, lq) and np.array_equal(v, lv)
    finally:
        ray.shutdown()


def test_readme_python_blocks_run(monkeypatch):
    text = (ROOT / "README.md").read_text()
    blocks = [b.split("```", 1)[0] for b in text.split("```python\n")[1:]]
    assert len(blocks) >= 2
    monkeypatch.chdir(ROOT)
    for code in blocks:
        exec(compile(code, "README.md", "exec"), {})
