#!/usr/bin/env python3
"""Reference dynamics for `urdyn eval`, computed with Pinocchio (the outside oracle).

For every fixture in FIXTURES this writes, under tests/fixtures/<name>/:
  states.json    an `urdyn eval` input (see shared/spec/eval-contract.md)
  expected.json  the `urdyn eval` output that input must produce
  meta.json      {"urdf": <repo-relative URDF path>, "floating_base": bool, "cond_H_max": float}

Run through tests/oracle/run.sh, which sets up the pinned environment. The fixtures are
deterministic (fixed seeds), so re-running only changes them if the robots, the state
recipe or the library versions change.

Conventions and checks (details in tests/oracle/README.md):
- Pinocchio's own mimic support is not used: every mimic joint is built as an
  independent joint (buildModelFromUrdf's mimic=False, the default) and the system is
  reduced here with the Jacobian G of all joint coordinates w.r.t. the degrees of freedom.
- Pinocchio and yourdfpy are both fed a temporary copy of the URDF with normalised axes
  and no <mimic> tags; yourdfpy's link poses must agree with Pinocchio's to 1e-10.
- Without mimic joints, forward dynamics from solve(H, tau - C) must agree with ABA.
"""

import copy
import json
import math
import os
import shutil
import sys
import sysconfig
import tempfile
import xml.etree.ElementTree as ET
import zlib
from pathlib import Path

import logging

import numpy as np
import pinocchio as pin
import yourdfpy

ROOT = Path(__file__).resolve().parents[2]
FIXTURE_DIR = ROOT / "tests" / "fixtures"
ERD_VERSION = "6.0.0"
ERD = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share" / "example-robot-data" / "robots"

# name in assets/robots/ -> path inside example-robot-data's robots/ directory
ROBOT_SOURCES = {
    "ur5": "ur_description/urdf/ur5_robot.urdf",
    "panda": "panda_description/urdf/panda.urdf",
    "solo12": "solo_description/robots/solo12.urdf",
    "talos_reduced": "talos_data/robots/talos_reduced.urdf",
    "anymal": "anymal_b_simple_description/robots/anymal.urdf",
    "icub_reduced": "icub_description/robots/icub_reduced.urdf",
    "tiago": "tiago_description/robots/tiago.urdf",
}

G_DOWN = [0.0, 0.0, -9.81]
G_TILT = [0.3, -0.2, -9.81]
G_TILT2 = [-0.5, 0.4, -9.7]
G_SEED = [0.0, -9.81, 0.0]  # the seed's planar examples: gravity along -y

# (fixture name, repo-relative URDF, floating base, gravity; None = leave the key out)
FIXTURES = [
    ("ur5", "assets/robots/ur5.urdf", False, None),
    ("ur5_floating", "assets/robots/ur5.urdf", True, G_TILT),
    ("panda", "assets/robots/panda.urdf", False, G_TILT),
    ("solo12", "assets/robots/solo12.urdf", True, G_DOWN),
    ("talos_reduced", "assets/robots/talos_reduced.urdf", True, G_DOWN),
    ("anymal", "assets/robots/anymal.urdf", True, G_TILT2),
    # <texture> without filename in its visuals, near-zero indefinite inertias
    ("icub_reduced", "assets/robots/icub_reduced.urdf", True, G_DOWN),
    # two 1e-6 kg antennas with slightly indefinite inertias (loaded as written)
    ("tiago", "assets/robots/tiago.urdf", False, G_TILT),
    ("double_pendulum", "tests/urdf/double_pendulum.urdf", False, None),
    ("fixed_chain", "tests/urdf/fixed_chain.urdf", False, G_TILT),
    ("fixed_chain_floating", "tests/urdf/fixed_chain.urdf", True, G_DOWN),
    ("prismatic_continuous", "tests/urdf/prismatic_continuous.urdf", False, G_TILT2),
    ("mimic", "tests/urdf/mimic.urdf", False, G_TILT),
    ("unnormalized_axis", "tests/urdf/unnormalized_axis.urdf", False, G_DOWN),
    ("particle", "assets/particle.urdf", False, G_SEED),
    ("planar_lamp", "assets/planar_lamp.urdf", False, G_SEED),
    ("planar_lamp_floating", "assets/planar_lamp.urdf", True, G_SEED),
]

# Large robots keep few states (the fixture JSON stays small): these indices of
# make_states' list (the zero state, a random one with every key, the fast one).
FEW_STATES = {"icub_reduced": [0, 1, 4], "tiago": [0, 1, 4]}

MOVABLE = ("revolute", "continuous", "prismatic")
POSE_TOL = 1e-10
ABA_TOL = 1e-10


# --------------------------------------------------------------------------- assets


def copy_robot_assets():
    """Copy the example-robot-data URDFs (verbatim) and the package licence."""
    if not ERD.is_dir():
        sys.exit(f"example-robot-data not found at {ERD}")
    out = ROOT / "assets" / "robots"
    out.mkdir(parents=True, exist_ok=True)
    for name, rel in ROBOT_SOURCES.items():
        src = ERD / rel
        dst = out / f"{name}.urdf"
        if not dst.exists() or dst.read_bytes() != src.read_bytes():
            shutil.copyfile(src, dst)
    dist = Path(sysconfig.get_paths()["purelib"]) / f"example_robot_data-{ERD_VERSION}.dist-info"
    lic = dist / "licenses" / "LICENSE"
    dst = out / "LICENSE-example-robot-data"
    if not dst.exists() or dst.read_bytes() != lic.read_bytes():
        shutil.copyfile(lic, dst)
    # panda_description carries its own licence file (Apache-2.0)
    plic = ERD / "panda_description" / "LICENSE"
    dst = out / "LICENSE-panda_description"
    if not dst.exists() or dst.read_bytes() != plic.read_bytes():
        shutil.copyfile(plic, dst)


# --------------------------------------------------------------------------- URDF


def parse_urdf(path):
    tree = ET.parse(path)
    robot = tree.getroot()
    links = [l.get("name") for l in robot.findall("link")]
    joints = {}
    for j in robot.findall("joint"):
        info = {"type": j.get("type"), "parent": j.find("parent").get("link"),
                "child": j.find("child").get("link"), "mimic": None,
                "lower": None, "upper": None}
        lim = j.find("limit")
        if lim is not None:
            if lim.get("lower") is not None:
                info["lower"] = float(lim.get("lower"))
            if lim.get("upper") is not None:
                info["upper"] = float(lim.get("upper"))
        mim = j.find("mimic")
        if mim is not None and info["type"] in MOVABLE:  # a <mimic> on a fixed joint is ignored
            info["mimic"] = (mim.get("joint"), float(mim.get("multiplier", 1.0)),
                             float(mim.get("offset", 0.0)))
        joints[j.get("name")] = info
    children = {j["child"] for j in joints.values()}
    roots = [l for l in links if l not in children]
    assert len(roots) == 1, f"{path}: roots {roots}"
    return tree, links, joints, roots[0]


def resolve_mimic(joints):
    """joint name -> (leader DoF, multiplier, offset) with mimic chains composed."""
    out = {}

    def resolve(name, seen):
        if name in out:
            return out[name]
        j = joints[name]
        if j["mimic"] is None:
            return (name, 1.0, 0.0)
        leader, m, o = j["mimic"]
        assert leader not in seen, f"mimic cycle through {name}"
        assert leader in joints and joints[leader]["type"] in MOVABLE, f"bad leader for {name}"
        root, m2, o2 = resolve(leader, seen | {name})
        r = (root, m * m2, m * o2 + o)
        out[name] = r
        return r

    for n, j in joints.items():
        if j["type"] in MOVABLE and j["mimic"] is not None:
            resolve(n, {n})
    return out


def oracle_copy(tree, dst, keep_mimic=None):
    """A copy with normalised joint axes and no <mimic> tags; with keep_mimic (the output
    of resolve_mimic) the movable joints' <mimic> tags are kept, chains flattened to point
    at the ultimate leader (yourdfpy does not follow mimic chains)."""
    t = copy.deepcopy(tree)
    for j in t.getroot().findall("joint"):
        ax = j.find("axis")
        if ax is not None and j.get("type") in MOVABLE:
            a = np.array([float(x) for x in ax.get("xyz").split()])
            n = np.linalg.norm(a)
            assert n > 0, "zero axis"
            if abs(n - 1.0) > 0.0:
                ax.set("xyz", " ".join(repr(float(x)) for x in a / n))
        for m in j.findall("mimic"):
            if keep_mimic is None:
                j.remove(m)
            elif j.get("name") in keep_mimic:
                leader, mult, off = keep_mimic[j.get("name")]
                m.set("joint", leader)
                m.set("multiplier", repr(mult))
                m.set("offset", repr(off))
    t.write(dst)


# --------------------------------------------------------------------------- states


def rand_unit_quat(rng):
    while True:
        q = rng.normal(size=4)
        n = np.linalg.norm(q)
        if n > 1e-3:
            return q / n


def make_states(name, dofs, joints, floating):
    rng = np.random.default_rng(zlib.crc32(name.encode()) ^ 0x5EED)

    def q_sample(n):
        j = joints[n]
        lo, hi = j["lower"], j["upper"]
        if j["type"] == "continuous" or lo is None or hi is None or not lo < hi:
            lo, hi = -math.pi, math.pi
        return float(rng.uniform(lo, hi))

    def vec(n, s=1.0):
        return [float(x) for x in rng.uniform(-s, s, n)]

    def jmap(f, drop=0.0):
        out = {}
        for n in dofs:
            val = f(n)
            if drop and rng.random() < drop:
                continue
            out[n] = val
        return out

    def base_full(vs=1.0, quat_scale=1.0, pos_scale=1.0):
        return {
            "position": [float(x) for x in rng.uniform(-pos_scale, pos_scale, 3)],
            "orientation_xyzw": [float(x) * quat_scale for x in rand_unit_quat(rng)],
            "linear_velocity": vec(3, vs),
            "angular_velocity": vec(3, vs),
            "linear_acceleration": vec(3),
            "angular_acceleration": vec(3),
            "force": vec(3, 5.0),
            "torque": vec(3, 2.0),
        }

    u = lambda s=1.0: (lambda n: float(rng.uniform(-s, s)))
    states = []
    # 0: the zero state, everything left out (defaults)
    states.append({})
    # 1: random, every key given
    s = {"q": jmap(q_sample), "v": jmap(u()), "a": jmap(u()), "tau": jmap(u())}
    if floating:
        s["base"] = base_full()
    states.append(s)
    # 2: random, some joints left out of each map
    s = {"q": jmap(q_sample, 0.3), "v": jmap(u(), 0.3), "a": jmap(u(), 0.3), "tau": jmap(u(), 0.3)}
    if floating:
        s["base"] = base_full()
    states.append(s)
    # 3: no "a" map at all, partial base object
    s = {"q": jmap(q_sample), "v": jmap(u()), "tau": jmap(u(), 0.5)}
    if floating:
        b = base_full()
        s["base"] = {k: b[k] for k in ("position", "orientation_xyzw", "linear_velocity", "force")}
    states.append(s)
    # 4: fast: joint and base velocities in [-10, 10]; a quaternion 4e-4 off unit norm
    s = {"q": jmap(q_sample), "v": jmap(u(10.0)), "a": jmap(u()), "tau": jmap(u())}
    if floating:
        s["base"] = base_full(vs=10.0, quat_scale=1.0004)
    states.append(s)
    # 5: bigger accelerations and torques, base far from the origin
    s = {"q": jmap(q_sample), "v": jmap(u()), "a": jmap(u(5.0)), "tau": jmap(u(5.0))}
    if floating:
        s["base"] = base_full(pos_scale=20.0)
    states.append(s)
    return states


# --------------------------------------------------------------------------- dynamics


class Robot:
    def __init__(self, urdf_rel, floating, tmpdir):
        self.urdf_rel = urdf_rel
        self.floating = floating
        path = ROOT / urdf_rel
        self.tree, self.links, self.joints, self.root_link = parse_urdf(path)
        self.mimic = resolve_mimic(self.joints)
        stem = Path(urdf_rel).stem
        self.clean = os.path.join(tmpdir, f"{stem}_oracle.urdf")
        oracle_copy(self.tree, self.clean)
        if floating:
            self.model = pin.buildModelFromUrdf(self.clean, pin.JointModelFreeFlyer())
        else:
            self.model = pin.buildModelFromUrdf(self.clean)
        self.data = self.model.createData()
        m = self.model
        first = 2 if floating else 1
        if floating:
            assert m.joints[1].shortname() == "JointModelFreeFlyer"
        # Pinocchio joints (tree order) that are URDF movable joints
        self.pjoints = []
        for i in range(first, m.njoints):
            name = m.names[i]
            jm = m.joints[i]
            assert name in self.joints and self.joints[name]["type"] in MOVABLE, name
            assert jm.nv == 1 and jm.nq in (1, 2), (name, jm.shortname())
            cont = self.joints[name]["type"] == "continuous"
            assert (jm.nq == 2) == cont, (name, jm.shortname())
            self.pjoints.append((name, jm.idx_q, jm.idx_v, jm.nq))
        movable = {n for n, j in self.joints.items() if j["type"] in MOVABLE}
        assert movable == {p[0] for p in self.pjoints}, "joint sets differ"
        self.dofs = [p[0] for p in self.pjoints if p[0] not in self.mimic]
        nb = 6 if floating else 0
        self.nv_red = nb + len(self.dofs)
        col = {n: nb + k for k, n in enumerate(self.dofs)}
        G = np.zeros((m.nv, self.nv_red))
        for k in range(nb):
            G[k, k] = 1.0
        self.offset = {}
        for name, _, iv, _ in self.pjoints:
            leader, mult, off = self.mimic.get(name, (name, 1.0, 0.0))
            G[iv, col[leader]] = mult
        self.G = G
        self.reduced = bool(self.mimic)
        # every link must have a BODY frame
        for l in self.links:
            assert m.existFrame(l, pin.BODY), f"no BODY frame for link {l}"
        # yourdfpy on the same normalised, mimic-free copy
        self.ydf = yourdfpy.URDF.load(self.clean, build_scene_graph=True, load_meshes=False,
                                      load_collision_meshes=False)
        assert self.ydf.base_link == self.root_link

    def full_values(self, state):
        """URDF joint name -> (q, v, a) for every movable joint, mimic joints included."""
        qm, vm, am = (state.get(k, {}) for k in ("q", "v", "a"))
        out = {}
        for name, _, _, _ in self.pjoints:
            leader, mult, off = self.mimic.get(name, (name, 1.0, 0.0))
            out[name] = (mult * qm.get(leader, 0.0) + off, mult * vm.get(leader, 0.0),
                         mult * am.get(leader, 0.0))
        return out

    def base_pose(self, state):
        b = state.get("base", {}) if self.floating else {}
        pos = np.array(b.get("position", [0.0, 0.0, 0.0]))
        quat = np.array(b.get("orientation_xyzw", [0.0, 0.0, 0.0, 1.0]))
        nq = np.linalg.norm(quat)
        assert abs(nq - 1.0) <= 1e-3
        quat = quat / nq
        return pos, quat, b

    def evaluate(self, state, gravity):
        m, d = self.model, self.data
        m.gravity.linear = np.array(gravity, dtype=float)
        q = pin.neutral(m)
        v = np.zeros(m.nv)
        a = np.zeros(m.nv)
        tau_in = np.zeros(self.nv_red)
        pos, quat, b = self.base_pose(state)
        if self.floating:
            q[0:3] = pos
            q[3:7] = quat  # Pinocchio's free flyer quaternion is (x, y, z, w)
            v[0:3] = b.get("linear_velocity", [0.0] * 3)
            v[3:6] = b.get("angular_velocity", [0.0] * 3)
            a[0:3] = b.get("linear_acceleration", [0.0] * 3)
            a[3:6] = b.get("angular_acceleration", [0.0] * 3)
            tau_in[0:3] = b.get("force", [0.0] * 3)
            tau_in[3:6] = b.get("torque", [0.0] * 3)
        full = self.full_values(state)
        for name, iq, iv, nq in self.pjoints:
            qq, vv, aa = full[name]
            if nq == 2:
                q[iq], q[iq + 1] = math.cos(qq), math.sin(qq)
            else:
                q[iq] = qq
            v[iv] = vv
            a[iv] = aa
        nb = 6 if self.floating else 0
        taum = state.get("tau", {})
        for k, n in enumerate(self.dofs):
            tau_in[nb + k] = taum.get(n, 0.0)
        G = self.G
        # the reduced velocities/accelerations must reproduce the full ones
        v_red = np.concatenate([v[:nb], [state.get("v", {}).get(n, 0.0) for n in self.dofs]])
        a_red = np.concatenate([a[:nb], [state.get("a", {}).get(n, 0.0) for n in self.dofs]])
        assert np.allclose(G @ v_red, v, rtol=0, atol=1e-14)
        assert np.allclose(G @ a_red, a, rtol=0, atol=1e-14)

        rnea = pin.rnea(m, d, q, v, a).copy()
        nle = pin.nonLinearEffects(m, d, q, v).copy()
        M = pin.crba(m, d, q).copy()
        M = np.triu(M) + np.triu(M, 1).T
        H = G.T @ M @ G
        tau = G.T @ rnea
        bias = G.T @ nle
        qdd = np.linalg.solve(H, tau_in - bias)
        scale = max(1.0, float(np.max(np.abs(tau))))
        assert np.max(np.abs(H @ a_red + bias - tau)) < 1e-9 * scale, "tau != H a + C"
        aba_err = None
        if not self.reduced:
            qdd_aba = pin.aba(m, d, q, v, tau_in).copy()
            aba_err = float(np.max(np.abs(qdd_aba - qdd)) / max(1.0, float(np.max(np.abs(qdd)))))
            assert aba_err < ABA_TOL, f"ABA disagrees with solve(H): {aba_err}"
        cond = float(np.linalg.cond(H))

        pin.framesForwardKinematics(m, d, q)
        poses = {}
        for l in self.links:
            T = d.oMf[m.getFrameId(l, pin.BODY)]
            poses[l] = T.homogeneous.copy()
        if self.floating:
            Tr = poses[self.root_link]
            assert np.allclose(Tr[:3, 3], pos, atol=1e-12)
            assert np.allclose(Tr[:3, :3], pin.Quaternion(quat[3], *quat[:3]).toRotationMatrix(), atol=1e-12)
        # yourdfpy cross-check of every link pose
        T_base = np.eye(4)
        T_base[:3, :3] = pin.Quaternion(quat[3], *quat[:3]).toRotationMatrix()
        T_base[:3, 3] = pos
        cfg = np.array([full[n][0] for n in self.ydf.actuated_joint_names])
        self.ydf.update_cfg(cfg)
        pose_err = 0.0
        for l in self.links:
            Ty = T_base @ self.ydf.get_transform(l)
            pose_err = max(pose_err, float(np.max(np.abs(Ty - poses[l]))))
        assert pose_err < POSE_TOL, f"yourdfpy link poses disagree: {pose_err}"

        fl = lambda x: [float(y) for y in x]
        res = {
            "tau": {n: float(tau[nb + k]) for k, n in enumerate(self.dofs)},
            "qdd": {n: float(qdd[nb + k]) for k, n in enumerate(self.dofs)},
            "bias": {n: float(bias[nb + k]) for k, n in enumerate(self.dofs)},
            "mass_matrix": [fl(r) for r in H],
            "link_poses": {l: {"position": fl(T[:3, 3]), "rotation": [fl(r) for r in T[:3, :3]]}
                           for l, T in poses.items()},
        }
        if self.floating:
            res["base"] = {
                "force": fl(tau[0:3]), "torque": fl(tau[3:6]),
                "bias_force": fl(bias[0:3]), "bias_torque": fl(bias[3:6]),
                "linear_acceleration": fl(qdd[0:3]), "angular_acceleration": fl(qdd[3:6]),
            }
        return res, cond, pose_err, aba_err


def particle_check(results, states):
    """The seed's section 3.1 closed form: Q_x = m qdd_x, Q_y = m (qdd_y + g), m = 2."""
    for st, r in zip(states, results):
        ax = st.get("a", {}).get("x", 0.0)
        ay = st.get("a", {}).get("y", 0.0)
        assert abs(r["tau"]["x"] - 2.0 * ax) < 1e-12
        assert abs(r["tau"]["y"] - 2.0 * (ay + 9.81)) < 1e-12
        assert abs(r["bias"]["y"] - 2.0 * 9.81) < 1e-12 and abs(r["bias"]["x"]) < 1e-12


def mimic_yourdfpy_check(robot, states):
    """yourdfpy's own mimic handling (chains flattened, the <mimic> on fixed joints left in)
    against the G mapping: the worst link-pose difference."""
    tmp = robot.clean.replace("_oracle.urdf", "_oracle_mimic.urdf")
    oracle_copy(robot.tree, tmp, keep_mimic=robot.mimic)
    try:
        y = yourdfpy.URDF.load(tmp, build_scene_graph=True, load_meshes=False,
                               load_collision_meshes=False)
        worst = 0.0
        for st in states:
            cfg = np.array([st.get("q", {}).get(n, 0.0) for n in y.actuated_joint_names])
            y.update_cfg(cfg)
            full = robot.full_values(st)
            y2 = robot.ydf
            y2.update_cfg(np.array([full[n][0] for n in y2.actuated_joint_names]))
            for l in robot.links:
                worst = max(worst, float(np.max(np.abs(y.get_transform(l) - y2.get_transform(l)))))
        return f"{worst:.1e}"
    except Exception as e:  # noqa: BLE001 - informational only
        return f"n/a ({type(e).__name__}: {e})"


def pin_mimic_check(robot, states, results, gravity):
    """Pinocchio's native mimic joints (mimic=True, chains flattened) against the G
    reduction: worst difference of tau, bias and H over the states (informational)."""
    tmp = robot.clean.replace("_oracle.urdf", "_oracle_mimic.urdf")
    oracle_copy(robot.tree, tmp, keep_mimic=robot.mimic)
    try:
        if robot.floating:
            m = pin.buildModelFromUrdf(tmp, pin.JointModelFreeFlyer(), mimic=True)
        else:
            m = pin.buildModelFromUrdf(tmp, mimic=True)
        d = m.createData()
        m.gravity.linear = np.array(gravity, dtype=float)
        ids = [m.getJointId(n) for n in robot.dofs]
        assert m.nv == len(ids), "nv"
        iv = [m.joints[i].idx_v for i in ids]
        worst = 0.0
        for st, r in zip(states, results):
            q, v, a = pin.neutral(m), np.zeros(m.nv), np.zeros(m.nv)
            for n, i in zip(robot.dofs, ids):
                j = m.joints[i]
                val = st.get("q", {}).get(n, 0.0)
                if j.nq == 2:
                    q[j.idx_q], q[j.idx_q + 1] = math.cos(val), math.sin(val)
                else:
                    q[j.idx_q] = val
                v[j.idx_v] = st.get("v", {}).get(n, 0.0)
                a[j.idx_v] = st.get("a", {}).get(n, 0.0)
            tau = pin.rnea(m, d, q, v, a)
            nle = pin.nonLinearEffects(m, d, q, v)
            M = pin.crba(m, d, q)
            M = np.triu(M) + np.triu(M, 1).T
            H = np.array(r["mass_matrix"])
            for k, n in enumerate(robot.dofs):
                worst = max(worst, abs(tau[iv[k]] - r["tau"][n]), abs(nle[iv[k]] - r["bias"][n]))
            worst = max(worst, float(np.max(np.abs(M[np.ix_(iv, iv)] - H))))
        return f"{worst:.1e}"
    except Exception as e:  # noqa: BLE001 - informational only
        return f"n/a ({type(e).__name__}: {str(e)[:60]})"


# --------------------------------------------------------------------------- main


def dump(path, obj):
    with open(path, "w") as f:
        json.dump(obj, f, indent=1)
        f.write("\n")


def main():
    logging.getLogger("yourdfpy").setLevel(logging.ERROR)
    print(f"pinocchio {pin.__version__}, yourdfpy {getattr(yourdfpy, '__version__', '?')}, numpy {np.__version__}")
    copy_robot_assets()
    FIXTURE_DIR.mkdir(parents=True, exist_ok=True)
    print(f"{'fixture':22s} {'nq':>3s} {'nv':>3s} {'red':>3s} {'#st':>3s} {'cond(H) max':>11s} "
          f"{'ydf pose':>8s} {'aba':>8s}  extra")
    with tempfile.TemporaryDirectory() as tmp:
        for name, urdf_rel, floating, gravity in FIXTURES:
            robot = Robot(urdf_rel, floating, tmp)
            states = make_states(name, robot.dofs, robot.joints, floating)
            if name in FEW_STATES:
                states = [states[i] for i in FEW_STATES[name]]
            g = gravity if gravity is not None else G_DOWN
            results, conds, perrs, aerrs = [], [], [], []
            for st in states:
                r, c, pe, ae = robot.evaluate(st, g)
                results.append(r)
                conds.append(c)
                perrs.append(pe)
                if ae is not None:
                    aerrs.append(ae)
            extra = ""
            if name == "particle":
                particle_check(results, states)
                extra = "seed 3.1 closed form ok"
            if robot.reduced and not floating:
                extra = ("ydf-mimic vs G: " + mimic_yourdfpy_check(robot, states)
                         + "; pin mimic=True vs G: " + pin_mimic_check(robot, states, results, g))
            inp = {"states": states}
            if gravity is not None:
                inp = {"gravity": gravity, "states": states}
            out_dir = FIXTURE_DIR / name
            out_dir.mkdir(parents=True, exist_ok=True)
            dump(out_dir / "states.json", inp)
            dump(out_dir / "expected.json", {"dof_names": robot.dofs, "results": results})
            dump(out_dir / "meta.json", {"urdf": urdf_rel, "floating_base": floating,
                                         "cond_H_max": max(conds)})
            aba = f"{max(aerrs):.1e}" if aerrs else "reduced"
            print(f"{name:22s} {robot.model.nq:3d} {robot.model.nv:3d} {robot.nv_red:3d} "
                  f"{len(states):3d} {max(conds):11.3e} {max(perrs):8.1e} {aba:>8s}  {extra}")


if __name__ == "__main__":
    main()
