"""The Panda grasps a cube and lifts it, recorded as a replay page from Python: the
committed assets/robots/panda.urdf (its meshes in assets/robots/example-robot-data) and a
4 cm cube on the ground, in one scene; the arm's seven joints and the fingers on servos
(gravity held by a feed-forward of the servo targets' RNEA), the targets along joint-space
segments found by a small damped least-squares IK on `frame_placement`/`frame_jacobian`:
above the cube, down around it, close the fingers, lift 0.15 m. `sim.write_html` writes
the page (tests/browser/view_check.py page PAGE checks it draws and moves).

    python python/examples/panda_grasp.py [OUT.html]     # default target/panda_grasp.html

Prints the cube's height gained and how far it slipped in the fingers."""

import json
import sys
import tempfile
from pathlib import Path

import numpy as np

import urdyn

ROOT = Path(__file__).resolve().parents[2]
PANDA = ROOT / "assets" / "robots" / "panda.urdf"
SIDE = 0.04
CUBE = f"""<robot name="cube"><link name="box">
 <inertial><mass value="0.1"/><inertia ixx="2.7e-5" iyy="2.7e-5" izz="2.7e-5" ixy="0" ixz="0" iyz="0"/></inertial>
 <visual><geometry><box size="{SIDE} {SIDE} {SIDE}"/></geometry></visual>
 <collision><geometry><box size="{SIDE} {SIDE} {SIDE}"/></geometry></collision></link></robot>"""
AT = np.array([0.5, 0.0, SIDE / 2])  # the cube's centre
READY = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])


def ik(arm, data, q, target, iters=200):
    """Arm joints with the TCP at `target`, pointing down (hand z along world −z,
    fingers closing along world y), by damped least squares from q."""
    q = q.copy()
    want = np.diag([1.0, -1.0, -1.0])  # x forward, z down
    for _ in range(iters):
        m = urdyn.frame_placement(arm, data, q, "panda_hand_tcp")
        R, p = m[:3, :3], m[:3, 3]
        e_rot = 0.5 * sum(np.cross(R[:, k], want[:, k]) for k in range(3))
        e = np.concatenate([target - p, e_rot])
        if np.linalg.norm(e) < 1e-9:
            break
        J = urdyn.frame_jacobian(arm, data, q, "panda_hand_tcp", reference="world_aligned")
        dq = J.T @ np.linalg.solve(J @ J.T + 1e-6 * np.eye(6), e)
        q[:7] += dq[:7]
    return q


def main(out):
    arm = urdyn.Model.from_urdf(PANDA)
    data = arm.create_data()
    q = np.concatenate([READY, [0.04]])
    above = ik(arm, data, q, AT + [0, 0, 0.12])
    grasp = ik(arm, data, above, AT)
    lifted = ik(arm, data, grasp, AT + [0, 0, 0.15])

    tmp = Path(tempfile.mkdtemp(prefix="urdyn-panda-"))
    (tmp / "cube.urdf").write_text(CUBE)
    (tmp / "scene.json").write_text(json.dumps({
        "ground": {"height": 0.0, "friction": 1.0},
        "models": [
            {"name": "cube", "urdf": "cube.urdf", "base": "floating", "position": AT.tolist()},
            {"name": "panda", "urdf": str(PANDA), "base": "fixed", "self_collision": False,
             "initial": {"q": dict(zip(arm.q_names, above.tolist()))}},
        ],
    }))
    scene = urdyn.Scene.from_file(tmp / "scene.json")
    m = scene.model
    sim = urdyn.Simulation(scene)
    qs, vs = m.model_q_slice("panda"), m.model_v_slice("panda")
    kp = np.zeros(m.nv)
    kp[vs] = [2000.0] * 4 + [300.0] * 3 + [1000.0]
    sim.set_gains(kp, 0.05 * kp)
    q_ref = sim.q.copy()
    sim.record(True)
    z0 = sim.q[2]
    steps = 2200
    for k in range(steps):
        t = k * 1e-3
        s = lambda a, b: min(max((t - a) / (b - a), 0.0), 1.0)  # noqa: E731
        s = {"down": s(0.0, 0.6), "close": s(0.7, 1.0), "lift": s(1.1, 1.9)}
        s = {n: 3 * x * x - 2 * x ** 3 for n, x in s.items()}  # smooth steps
        arm_q = above + s["down"] * (grasp - above) + s["lift"] * (lifted - grasp)
        arm_q[7] = 0.04 + s["close"] * (SIDE / 2 - 0.01 - 0.04)  # 1 cm past the faces
        q_ref[qs] = arm_q
        sim.set_targets(q_ref)
        # gravity at the targets as a feed-forward (the servos then only track)
        tau = np.zeros(m.nv)
        tau[vs] = urdyn.rnea(arm, data, arm_q, np.zeros(8), np.zeros(8))
        sim.step(tau)
        if k == 1099:  # gripped, before the lift
            held = sim.q[2] - urdyn.frame_placement(arm, data, sim.q[qs], "panda_hand_tcp")[2, 3]
    sim.record(False)
    frames = sim.write_html(out)
    gained = sim.q[2] - z0
    slip = held - (sim.q[2] - urdyn.frame_placement(arm, data, sim.q[qs], "panda_hand_tcp")[2, 3])
    print(f"cube lifted {gained * 1000:.1f} mm (target 150), slipped {slip * 1000:.3f} mm in the "
          f"fingers; {len(sim.contacts())} contact points; wrote {out} ({frames} frames)")
    return gained, slip


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "target" / "panda_grasp.html")
