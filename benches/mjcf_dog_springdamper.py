"""dm_control dog with MuJoCo's springdamper resolved by hand (round 6 diagnosis).

urdyn reads `<joint springdamper>` but ignores it (the tail's 21 caudal joints get no
stiffness or damping). This writes tests/fixtures/mjcf/dm_control/dog_sdtmp.xml (next to
dog.xml for its mesh paths; delete it afterwards): dog.xml with springdamper removed and
every Ca_* joint given MuJoCo 4.0's compiled jnt_stiffness / dof_damping. Then:
  ./target/release/urdyn simulate tests/fixtures/mjcf/dm_control/dog_sdtmp.xml \
      --no-sleep --integrator euler --duration 3 --every 1000000000
Run from the repository root with /work/venv/bin/python.
"""
import mujoco, re
src = 'tests/fixtures/mjcf/dm_control/dog.xml'
m = mujoco.MjModel.from_xml_path(src)
x = open(src).read().replace('<joint group="3" springdamper="0.001 50"/>', '<joint group="3"/>')
n = 0
for j in range(m.njnt):
    nm = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j)
    if nm and nm.startswith('Ca_'):
        k, b = m.jnt_stiffness[j], m.dof_damping[m.jnt_dofadr[j]]
        x, c = re.subn(r'<joint name="%s" ' % nm, '<joint name="%s" stiffness="%.17g" damping="%.17g" ' % (nm, k, b), x)
        n += c
print('joints given exact values:', n)
open('tests/fixtures/mjcf/dm_control/dog_sdtmp.xml', 'w').write(x)
m2 = mujoco.MjModel.from_xml_path('tests/fixtures/mjcf/dm_control/dog_sdtmp.xml')
import numpy as np
print('max |stiffness diff|', np.abs(m2.jnt_stiffness - m.jnt_stiffness).max(), 'damping', np.abs(m2.dof_damping - m.dof_damping).max())
