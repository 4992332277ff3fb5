"""MuJoCo's trajectory of tests/fixtures/mjcf/sim/double_pendulum_passive.xml
(damping, springs with springref, armature; no contact) from its keyframe
"swing": RK4 at dt = 1e-5 (the integration error is far below the test's
tolerance: RK4's error ~ (dt)^4), sampled every 0.25 s for 2 s.
Writes tests/fixtures/mjcf/sim/mujoco_double_pendulum_passive.json.
Run: /work/venv/bin/python tests/oracle/make_mjcf_sim_fixture.py (MuJoCo 4.0)."""
import json
import pathlib

import mujoco

root = pathlib.Path(__file__).resolve().parents[2]
xml = root / "tests/fixtures/mjcf/sim/double_pendulum_passive.xml"
m = mujoco.MjModel.from_xml_path(str(xml))
m.opt.timestep = 1e-5
m.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
d = mujoco.MjData(m)
mujoco.mj_resetDataKeyframe(m, d, 0)
samples = []
every = 25000
for k in range(0, 200001):
    if k % every == 0:
        samples.append({"t": k * 1e-5, "qpos": list(d.qpos), "qvel": list(d.qvel)})
    if k < 200000:
        mujoco.mj_step(m, d)
out = {
    "mujoco": mujoco.__version__,
    "model": "tests/fixtures/mjcf/sim/double_pendulum_passive.xml",
    "key": "swing",
    "integrator": "RK4",
    "dt": 1e-5,
    "samples": samples,
}
dst = root / "tests/fixtures/mjcf/sim/mujoco_double_pendulum_passive.json"
dst.write_text(json.dumps(out, indent=1) + "\n")
print(dst, samples[-1])
