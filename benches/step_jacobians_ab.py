#!/usr/bin/env python3
"""ur5 step Jacobians, before/after in ONE process: MuJoCo's mjd_transitionFD and two builds
of the urdyn package (each a folder holding urdyn/__init__.py and urdyn/_urdyn.abi3.so, e.g.
the extension of `cargo build --release -p urdyn-python` copied there), alternated in
batches (500 urdyn calls, 100 MuJoCo calls) for ROUNDS rounds; min and median µs per call
over the batches, and the ratios. Same setting as benches/step_jacobians_speed.py (ur5,
no contact, Euler at 1 ms, random angles of seed 0, at rest, tau = 0).

Usage: python benches/step_jacobians_ab.py BEFORE_DIR AFTER_DIR [ROUNDS]
"""
import importlib.util, math, os, sys, time
import numpy as np, mujoco
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
def load(name, folder):
    spec = importlib.util.spec_from_file_location(name, os.path.join(folder, "urdyn", "__init__.py"),
                                                  submodule_search_locations=[os.path.join(folder, "urdyn")])
    mod = importlib.util.module_from_spec(spec); sys.modules[name] = mod; spec.loader.exec_module(mod)
    return mod
mods = {"before": load("urdyn_before", sys.argv[1]), "after": load("urdyn", sys.argv[2])}
from sim_compare import find_share, mujoco_xml
share = find_share(None)
roots = [share, os.path.join(share, "example-robot-data", "robots")]
path = os.path.join(os.path.dirname(HERE), "assets/robots/ur5.urdf")
spec = mujoco.MjSpec.from_string(mujoco_xml(path, roots))
spec.option.timestep = 1e-3; spec.option.gravity = [0, 0, -9.81]
spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
m = spec.compile(); d = mujoco.MjData(m)
fs = {}
for k, u in mods.items():
    um = u.Model.from_urdf(path)
    q0 = np.random.default_rng(0).uniform(-math.pi, math.pi, um.nq)
    if k == "before":
        for i, jn in enumerate(um.dof_names):
            jid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, jn)
            d.qpos[m.jnt_qposadr[jid]] = q0[i]
        mujoco.mj_forward(m, d)
    sim = u.Simulation(um, ground=None, integrator="euler")
    sim.set_state(q0, np.zeros(um.nv))
    tau = np.zeros(um.nv)
    fs[k] = (lambda sim=sim, tau=tau: sim.transition_jacobians(tau, method="analytic"))
A = np.zeros((2 * m.nv, 2 * m.nv)); B = np.zeros((2 * m.nv, m.nu)) if m.nu else None
fs["mujoco"] = lambda: mujoco.mjd_transitionFD(m, d, 1e-6, 0, A, B, None, None)
a1, _ = fs["before"](); a2, _ = fs["after"](); assert np.array_equal(a1, a2) and a2.flags["C_CONTIGUOUS"]
rounds = int(sys.argv[3]) if len(sys.argv) > 3 else 100
res = {k: [] for k in fs}
for r in range(rounds):
    for k, f in fs.items():
        n = 100 if k == "mujoco" else 500
        t0 = time.perf_counter()
        for _ in range(n): f()
        res[k].append((time.perf_counter() - t0) / n * 1e6)
st = {k: (min(v), float(np.median(v))) for k, v in res.items()}
for k, (mn, md) in st.items(): print(f"{k:7s} min {mn:6.2f} median {md:6.2f} us")
for k in [k for k in mods]:
    print(f"{k}/mujoco: min/min {st[k][0] / st['mujoco'][0]:.3f}  median/median {st[k][1] / st['mujoco'][1]:.3f}")
pr = [n / o for n, o in zip(res["after"], res["before"])]
print(f"after/before per round: median {np.median(pr):.3f}; min/min {st['after'][0] / st['before'][0]:.3f}")
print("load", open("/proc/loadavg").read().split()[:3])
