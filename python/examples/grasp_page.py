"""A grasp and lift from Python, recorded as a replay page: a two-finger gripper on a
vertical slide closes on a 0.1 m cube resting on the ground (servoed fingers), lifts it
0.2 m, and `sim.write_html` writes the page (open it in a browser;
tests/browser/view_check.py page PAGE checks it draws and moves).

    python python/examples/grasp_page.py [OUT.html]     # default target/grasp.html

Prints the cube's height gained and how far it slipped down the fingers."""

import json
import sys
import tempfile
from pathlib import Path

import numpy as np

import urdyn

ROOT = Path(__file__).resolve().parents[2]

CUBE = """<robot name="cube"><link name="box">
 <inertial><mass value="0.2"/><inertia ixx="3.3e-4" iyy="3.3e-4" izz="3.3e-4" ixy="0" ixz="0" iyz="0"/></inertial>
 <visual><geometry><box size="0.1 0.1 0.1"/></geometry></visual>
 <collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link></robot>"""

FINGER = """<link name="{name}"><inertial><mass value="0.1"/>
  <inertia ixx="1e-4" iyy="1e-4" izz="1e-4" ixy="0" ixz="0" iyz="0"/></inertial>
  <visual><geometry><box size="0.04 0.02 0.08"/></geometry></visual>
  <collision><geometry><box size="0.04 0.02 0.08"/></geometry></collision></link>"""

GRIPPER = f"""<robot name="gripper">
 <link name="mount"/>
 <link name="palm"><inertial><mass value="0.5"/><inertia ixx="1e-3" iyy="1e-3" izz="1e-3" ixy="0" ixz="0" iyz="0"/></inertial>
  <visual><origin xyz="0 0 0.06"/><geometry><box size="0.05 0.2 0.02"/></geometry></visual></link>
 {FINGER.format(name="left")}
 {FINGER.format(name="right")}
 <joint name="lift" type="prismatic"><parent link="mount"/><child link="palm"/>
  <axis xyz="0 0 1"/><limit lower="-0.01" upper="0.3" effort="200" velocity="1"/></joint>
 <joint name="left_slide" type="prismatic"><parent link="palm"/><child link="left"/>
  <origin xyz="0 0.065 0"/><axis xyz="0 -1 0"/><limit lower="-0.03" upper="0.05" effort="50" velocity="1"/></joint>
 <joint name="right_slide" type="prismatic"><parent link="palm"/><child link="right"/>
  <origin xyz="0 -0.065 0"/><axis xyz="0 1 0"/><limit lower="-0.03" upper="0.05" effort="50" velocity="1"/></joint>
</robot>"""


def main(out):
    tmp = Path(tempfile.mkdtemp(prefix="urdyn-grasp-"))
    (tmp / "cube.urdf").write_text(CUBE)
    (tmp / "gripper.urdf").write_text(GRIPPER)
    (tmp / "scene.json").write_text(json.dumps({
        "ground": {"height": 0.0, "friction": 1.0},
        "models": [
            {"name": "cube", "urdf": "cube.urdf", "base": "floating", "position": [0, 0, 0.05]},
            {"name": "gripper", "urdf": "gripper.urdf", "base": "fixed", "position": [0, 0, 0.05]},
        ],
    }))
    scene = urdyn.Scene.from_file(tmp / "scene.json")
    m = scene.model
    sim = urdyn.Simulation(scene)
    lift, left, right = (m.joint_q_slice(f"gripper/{j}") for j in ("lift", "left_slide", "right_slide"))
    kp = np.zeros(m.nv)
    kp[m.model_v_slice("gripper")] = [3000.0, 500.0, 500.0]
    sim.set_gains(kp, 0.05 * kp)
    q_ref = scene.q0.copy()
    sim.record(True)
    z0 = sim.q[2]
    for k in range(1500):
        t = k * 1e-3
        q_ref[left] = q_ref[right] = min(t / 0.2, 1.0) * 0.02  # close, 1 cm past contact
        q_ref[lift] = 0.2 * min(max((t - 0.3) / 0.9, 0.0), 1.0)  # then lift 0.2 m
        sim.set_targets(q_ref)
        sim.step()
        if k == 299:  # gripped, before the lift: the cube's height relative to the fingers
            held = sim.q[2] - sim.q[lift][0]
    sim.record(False)
    frames = sim.write_html(out)
    gained = sim.q[2] - z0
    slip = held - (sim.q[2] - sim.q[lift][0])
    print(f"cube lifted {gained * 1000:.1f} mm (gripper {sim.q[lift][0] * 1000:.1f} mm), slipped "
          f"{slip * 1000:.3f} mm down the fingers; {len(sim.contacts())} contact points; wrote {out} "
          f"({frames} frames)")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "target" / "grasp.html")
