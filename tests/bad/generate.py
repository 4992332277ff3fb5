# Regenerates the hand-made files of this corpus (python3 tests/bad/generate.py).
import os, json
D = os.path.dirname(os.path.abspath(__file__))  # tests/bad
def inertial(m="1", ixx="0.1", iyy="0.1", izz="0.1", ixy="0", ixz="0", iyz="0", origin=""):
    return f'<inertial>{origin}<mass value="{m}"/><inertia ixx="{ixx}" ixy="{ixy}" ixz="{ixz}" iyy="{iyy}" iyz="{iyz}" izz="{izz}"/></inertial>'
def link(name, inert=None):
    return f'  <link name="{name}">{inertial() if inert is None else inert}</link>\n'
def joint(name, parent, child, t="revolute", axis="0 0 1", limit='<limit lower="-1" upper="1" effort="10" velocity="5"/>', origin='<origin xyz="0 0 0.5" rpy="0 0 0"/>', extra=""):
    ax = f'<axis xyz="{axis}"/>' if axis is not None else ""
    return f'  <joint name="{name}" type="{t}"><parent link="{parent}"/><child link="{child}"/>{origin}{ax}{limit or ""}{extra}</joint>\n'
def robot(body, name="bad", attrs=""):
    return f'<?xml version="1.0"?>\n<robot name="{name}"{attrs}>\n{body}</robot>\n'
files = {}
chain = link("base") + link("l1") + link("l2") + joint("j1","base","l1") + joint("j2","l1","l2")
files["ok.urdf"] = robot(link("base") + link("l1") + link("l2") + link("l3") + joint("j1","base","l1") + joint("j2","l1","l2")
    + joint("j3","l1","l3", extra='<mimic joint="j1" multiplier="2" offset="0.1"/>'), "ok")
files["not_xml.urdf"] = "this is not XML at all { \"robot\": 1 }\n"
files["binary.urdf"] = None  # written below
files["truncated.urdf"] = robot(chain)[:-60]
files["no_robot.urdf"] = '<?xml version="1.0"?>\n<model name="m">\n' + link("base") + '</model>\n'
files["missing_parent.urdf"] = robot(link("base") + link("l1") + joint("j1","nowhere","l1"))
files["missing_child.urdf"] = robot(link("base") + link("l1") + joint("j1","base","l1") + joint("j2","l1","ghost"))
files["two_roots.urdf"] = robot(link("base") + link("l1") + link("island") + joint("j1","base","l1"))
files["cycle.urdf"] = robot(link("base") + link("a") + link("b") + joint("j0","base","a") + joint("jab","a","b") + joint("jba","b","a"))
files["cycle_no_root.urdf"] = robot(link("a") + link("b") + link("c") + joint("jab","a","b") + joint("jbc","b","c") + joint("jca","c","a"))
files["two_parents.urdf"] = robot(link("base") + link("l1") + link("l2") + joint("j1","base","l1") + joint("j2","base","l2") + joint("j3","l1","l2"))
files["self_parent.urdf"] = robot(link("base") + link("l1") + joint("j1","base","l1") + joint("jself","l1","l1"))
files["dup_link.urdf"] = robot(link("base") + link("l1") + link("l1") + joint("j1","base","l1"))
files["dup_joint.urdf"] = robot(link("base") + link("l1") + link("l2") + joint("j1","base","l1") + joint("j1","l1","l2"))
files["mimic_missing_leader.urdf"] = robot(chain.replace('<limit lower="-1" upper="1" effort="10" velocity="5"/></joint>\n  <joint name="j2"', '<limit lower="-1" upper="1" effort="10" velocity="5"/></joint>\n  <joint name="j2"') .replace('</joint>\n</', '</joint>\n</') [:0] + link("base") + link("l1") + link("l2") + joint("j1","base","l1") + joint("j2","l1","l2", extra='<mimic joint="ghost"/>'))
files["mimic_fixed_leader.urdf"] = robot(link("base") + link("l1") + link("l2") + joint("jf","base","l1", t="fixed", limit=None) + joint("j2","l1","l2", extra='<mimic joint="jf"/>'))
files["mimic_cycle.urdf"] = robot(link("base") + link("l1") + link("l2") + link("l3") + joint("j1","base","l1") + joint("ma","l1","l2", extra='<mimic joint="mb"/>') + joint("mb","l1","l3", extra='<mimic joint="ma"/>'))
files["mimic_self.urdf"] = robot(link("base") + link("l1") + link("l2") + joint("j1","base","l1") + joint("ms","l1","l2", extra='<mimic joint="ms"/>'))
files["negative_mass.urdf"] = robot(link("base") + link("l1", inertial(m="-2")) + joint("j1","base","l1"))
files["nan_mass.urdf"] = robot(link("base") + link("l1", inertial(m="NaN")) + joint("j1","base","l1"))
files["inf_mass.urdf"] = robot(link("base") + link("l1", inertial(m="inf")) + joint("j1","base","l1"))
files["nonnumeric_mass.urdf"] = robot(link("base") + link("l1", inertial(m="heavy")) + joint("j1","base","l1"))
files["indefinite_inertia.urdf"] = robot(link("base") + link("l1", inertial(ixx="0.1", iyy="0.1", izz="-0.05")) + joint("j1","base","l1"))
files["indefinite_offdiag.urdf"] = robot(link("base") + link("l1", inertial(ixx="0.1", iyy="0.1", izz="0.1", ixy="0.5")) + joint("j1","base","l1"))
files["nan_inertia.urdf"] = robot(link("base") + link("l1", inertial(iyz="nan")) + joint("j1","base","l1"))
files["inf_inertial_origin.urdf"] = robot(link("base") + link("l1", inertial(origin='<origin xyz="0 inf 0" rpy="0 0 0"/>')) + joint("j1","base","l1"))
files["nan_joint_origin.urdf"] = robot(link("base") + link("l1") + joint("j1","base","l1", origin='<origin xyz="0 0 0.5" rpy="0 NaN 0"/>'))
files["inf_joint_origin.urdf"] = robot(link("base") + link("l1") + joint("j1","base","l1", origin='<origin xyz="-inf 0 0.5"/>'))
files["nan_axis.urdf"] = robot(link("base") + link("l1") + joint("j1","base","l1", axis="0 nan 1"))
files["inf_axis.urdf"] = robot(link("base") + link("l1") + joint("j1","base","l1", axis="0 0 inf"))
files["zero_axis.urdf"] = robot(link("base") + link("l1") + joint("j1","base","l1", axis="0 0 0"))
files["nan_limit.urdf"] = robot(link("base") + link("l1") + joint("j1","base","l1", limit='<limit lower="NaN" upper="1" effort="10" velocity="5"/>'))
files["inf_limit_effort.urdf"] = robot(link("base") + link("l1") + joint("j1","base","l1", limit='<limit lower="-1" upper="1" effort="inf" velocity="nan"/>'))
files["reversed_limit.urdf"] = robot(link("base") + link("l1") + joint("j1","base","l1", limit='<limit lower="1" upper="-1" effort="10" velocity="5"/>'))
files["nan_mimic_multiplier.urdf"] = robot(link("base") + link("l1") + link("l2") + joint("j1","base","l1") + joint("j2","l1","l2", extra='<mimic joint="j1" multiplier="nan"/>'))
files["unknown_joint_type.urdf"] = robot(link("base") + link("l1") + joint("j1","base","l1", t="hinge"))
files["mimic_spherical.urdf"] = robot(link("base") + link("l1") + link("l2") + joint("j1","base","l1", t="spherical", limit=None) + joint("j2","l1","l2", t="spherical", limit=None, extra='<mimic joint="j1"/>'))
files["mimic_spherical_leader.urdf"] = robot(link("base") + link("l1") + link("l2") + joint("j1","base","l1", t="spherical", limit=None) + joint("j2","l1","l2", extra='<mimic joint="j1"/>'))
files["nonnumeric_origin.urdf"] = robot(link("base") + link("l1") + joint("j1","base","l1", origin='<origin xyz="0 zero 0.5"/>'))
files["short_origin.urdf"] = robot(link("base") + link("l1") + joint("j1","base","l1", origin='<origin xyz="0 0.5"/>'))
files["joint_no_type.urdf"] = robot(link("base") + link("l1") + '  <joint name="j1"><parent link="base"/><child link="l1"/></joint>\n')
files["joint_no_child.urdf"] = robot(link("base") + link("l1") + '  <joint name="j1" type="revolute"><parent link="base"/><axis xyz="0 0 1"/></joint>\n')
files["link_no_name.urdf"] = robot(link("base") + '  <link/>\n')
files["empty.urdf"] = ""
files["whitespace.urdf"] = "  \n\t\n"
files["no_links.urdf"] = robot("")
files["entity_bomb.urdf"] = '<?xml version="1.0"?>\n<!DOCTYPE robot [\n  <!ENTITY a "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa">\n' + "".join(f'  <!ENTITY {chr(98+i)} "{("&"+chr(97+i)+";")*10}">\n' for i in range(9)) + ']>\n<robot name="&j;">\n' + link("base") + '</robot>\n'
files["external_entity.urdf"] = '<?xml version="1.0"?>\n<!DOCTYPE robot [\n  <!ENTITY x SYSTEM "file:///etc/passwd">\n]>\n<robot name="&x;">\n' + link("base") + '</robot>\n'
files["doctype_only.urdf"] = '<?xml version="1.0"?>\n<!DOCTYPE robot SYSTEM "http://example.invalid/robot.dtd">\n<robot name="r">\n' + link("base") + '</robot>\n'
files["undeclared_entity.urdf"] = '<?xml version="1.0"?>\n<robot name="&x;">\n' + link("base") + '</robot>\n'
coll = lambda fn: f'<collision><geometry><mesh filename="{fn}"/></geometry></collision>'
files["mesh_dotdot.urdf"] = robot(link("base") + f'  <link name="l1">{inertial()}{coll("../../../../../../../etc/shadow")}{coll("package://../../etc/passwd")}</link>\n' + joint("j1","base","l1"))
files["semidefinite_inertia.urdf"] = robot(link("base") + link("l1", inertial(ixx="0", iyy="0", izz="0", origin='<origin xyz="0.3 0 0"/>')) + link("l2", inertial(ixx="0.1", iyy="0.1", izz="0")) + joint("j1","base","l1") + joint("j2","l1","l2", axis="1 0 0"))
files["quadruped_base_1e-6.urdf"] = robot(link("base", inertial(m="5", ixx="1e-6", iyy="1e-6", izz="1e-6", ixy="1e-6", ixz="1e-6", iyz="1e-6")) + link("l1") + joint("j1","base","l1"))
files["triangle_inequality.urdf"] = robot(link("base") + link("l1", inertial(ixx="0.01", iyy="0.01", izz="0.5")) + joint("j1","base","l1"))
# What urdyn does not know, or what no dynamics reads, is a warning, never an error.
files["unknown_attribute.urdf"] = robot(link("base") + link("l1") + link("l2")
    + joint("j1","base","l1", limit='<limit lowr="-1.5" upper="1" effort="10" velocity="5"/>')
    + joint("j2","l1","l2", limit='<limit lowr="-1" upper="1" effort="10" velocity="5"/>', extra='<spring stiffness="3"/>'))
files["texture_no_filename.urdf"] = robot('  <material name="grey"><color rgba="0.5 0.5 0.5 1"/><texture/></material>\n'
    + '  <link name="base">' + inertial() + '<visual><geometry><box size="1 1 1"/></geometry><material name="skin"><texture/></material></visual></link>\n'
    + '  <link name="l1">' + inertial() + '<contact><lateral_friction value="1"/></contact></link>\n' + joint("j1","base","l1")
    + '  <xacro:property name="leftover" value="1"/>\n', attrs=' version="1.0" xmlns:xacro="http://www.ros.org/wiki/xacro"')
files["malformed_visual.urdf"] = robot('  <material name="red"><color rgba="1 0 0"/></material>\n'
    + '  <link name="base">' + inertial() + '<visual><geometry><box size="1 2"/></geometry></visual><visual><geometry/></visual></link>\n'
    + link("l1") + joint("j1","base","l1")
    + '  <gazebo reference="l1"><mu1>0.2</mu1><anything at="all"><deep/></anything></gazebo>\n'
    + '  <transmission name="t1"><type>SimpleTransmission</type><joint name="j1"><hardwareInterface>x</hardwareInterface></joint></transmission>\n')
# The same defect in a <collision> (read by contact) stays an error.
files["malformed_collision.urdf"] = robot(link("base") + '  <link name="l1">' + inertial() + '<collision><geometry><box size="1 2"/></geometry></collision></link>\n' + joint("j1","base","l1"))
files["no_limit.urdf"] = robot(link("base") + link("l1") + link("l2") + joint("j1","base","l1", limit=None) + joint("j2","l1","l2", t="prismatic", limit=None))
files["massless_joint.urdf"] = robot(link("base") + link("l1") + link("tip", inertial(m="0", ixx="0", iyy="0", izz="0")) + joint("j1","base","l1") + joint("wrist","l1","tip", axis="1 0 0"))
files["massless_joint_nointertial.urdf"] = robot(link("base") + link("l1") + '  <link name="tip"/>\n' + joint("j1","base","l1") + joint("wrist","l1","tip", axis="1 0 0"))
# fifo mesh: placeholder path substituted by the test
files["mesh_fifo.urdf.in"] = robot(link("base") + f'  <link name="l1">{inertial()}{coll("@FIFO@")}{coll("file://@FIFO@")}</link>\n' + joint("j1","base","l1"))
for k, v in files.items():
    if v is None: continue
    open(os.path.join(D, k), "w").write(v)
open(os.path.join(D, "binary.urdf"), "wb").write(b"\x89PNG\r\n\x1a\n\x00\x00\xff\xfe<robot>")
S = {}
S["states_ok.json"] = {"states": [{"q": {"j1": 0.3, "j2": -0.2}, "v": {"j1": 1.0}, "a": {"j2": 0.5}, "tau": {"j1": 0.1}}, {}]}
S["states_empty.json"] = {"states": []}
S["states_wrong_type.json"] = {"states": [{"q": {"j1": "0.3"}}]}
S["states_wrong_type_map.json"] = {"states": [{"q": [0.3, 0.2]}]}
S["states_states_not_list.json"] = {"states": {"q": {}}}
S["states_unknown_joint.json"] = {"states": [{}, {"v": {"elbow": 1.0}}]}
S["states_mimic_key.json"] = {"states": [{"q": {"j3": 0.5}}]}
S["states_fixed_key.json"] = None
S["states_quat_nonunit.json"] = {"states": [{"base": {"orientation_xyzw": [0, 0, 0, 2]}}]}
S["states_quat_zero.json"] = {"states": [{"base": {"orientation_xyzw": [0, 0, 0, 0]}}]}
S["states_short_position.json"] = {"states": [{"base": {"position": [0, 0]}}]}
S["states_long_gravity.json"] = {"gravity": [0, 0, -9.81, 0], "states": []}
S["states_missing_states.json"] = {"gravity": [0, 0, -9.81]}
S["states_misspelt_top.json"] = {"gravty": [0, 0, -9.81], "states": []}
S["states_misspelt_state.json"] = {"states": [{"qq": {"j1": 0.1}}]}
S["states_misspelt_base.json"] = {"states": [{"base": {"positon": [0, 0, 1]}}]}
S["states_top_not_object.json"] = [1, 2, 3]
for k, v in S.items():
    if v is None: continue
    open(os.path.join(D, k), "w").write(json.dumps(v, indent=1) + "\n")
raw = {
 "states_not_json.json": "{ states: [ {q: 1} ] ",
 "states_empty.txt": "",
 "states_nan.json": '{"states": [{"q": {"j1": NaN}}]}\n',
 "states_inf_literal.json": '{"states": [{"v": {"j1": Infinity}}]}\n',
 "states_huge.json": '{"states": [{"a": {"j1": 1e999}}]}\n',
 "states_gravity_huge.json": '{"gravity": [0, 0, -1e400], "states": []}\n',
 "states_trailing.json": '{"states": []} {"states": []}\n',
 "states_duplicate_key.json": '{"states": [], "states": []}\n',
}
for k, v in raw.items():
    open(os.path.join(D, k), "w").write(v)
# A model whose H is singular only at some configurations: a point mass that lies
# on j1's axis when j2 = 0.
open(os.path.join(D, "singular_at_zero.urdf"), "w").write(robot(
    '  <link name="base"/>\n  <link name="l1"/>\n'
    + link("l2", inertial(ixx="0", iyy="0", izz="0", origin='<origin xyz="0 0 0.3"/>'))
    + joint("j1", "base", "l1", origin="") + joint("j2", "l1", "l2", axis="1 0 0", origin="")))
for k, v in {
    "states_state_as_array.json": '{"states": [[{"j1": 1.0}]]}\n',
    "states_base_as_array.json": '{"states": [{"base": [[0, 0, 1]]}]}\n',
    "states_base_huge.json": '{"states": [{"base": {"position": [0, 0, 1e999]}}]}\n',
    "states_singular_second.json": '{"states": [{"q": {"j2": 0.5}}, {"q": {"j2": 0.0}}]}\n',
    "states_tau_null.json": '{"states": [{"tau": {"j1": null}}]}\n',
    "states_one.json": '{"states": [{}]}\n',
}.items():
    open(os.path.join(D, k), "w").write(v)
# Joints of several degrees of freedom (mechanisms.md "In `eval` (version 4)"):
# a spherical "ball", a planar "slide", a floating "mount" and a revolute "hinge".
open(os.path.join(D, "joints_ok.urdf"), "w").write(robot(
    link("base") + link("l1") + link("l2") + link("l3") + link("l4")
    + joint("ball", "base", "l1", t="spherical", axis=None, limit=None)
    + joint("hinge", "l1", "l2", axis="1 0 0")
    + joint("mount", "l2", "l3", t="floating", axis=None, limit=None)
    + joint("slide", "l3", "l4", t="planar", axis=None, limit=None), "joints_ok"))
for k, v in {
    "states_joints_ok.json": {"states": [{"q": {"ball": [0, 0, 0.6, 0.8], "hinge": 0.3, "mount": [0.1, 0, 0.2, 0, 0, 0, 1.0005], "slide": [0.1, 0.2, 0.3]},
                                           "v": {"ball": [0.1, 0.2, 0.3], "slide": [1, 0, 0.5]}, "tau": {"mount": [0, 0, 1, 0, 0, 0]}, "derivatives": True}, {}]},
    "states_joint_number_for_array.json": {"states": [{"q": {"ball": 0.3}}]},
    "states_joint_wrong_length.json": {"states": [{"q": {"slide": [0.1, 0.2]}}]},
    "states_joint_v_wrong_length.json": {"states": [{"v": {"mount": [0.1, 0.2, 0.3]}}]},
    "states_joint_quat_nonunit.json": {"states": [{"q": {"ball": [0, 0, 0, 0.9]}}]},
    "states_joint_mount_quat_nonunit.json": {"states": [{"q": {"mount": [0, 0, 0, 0, 0, 0, 2]}}]},
    "states_joint_array_for_number.json": {"states": [{"v": {"hinge": [1, 2]}}]},
    "states_joint_string_in_array.json": {"states": [{"a": {"ball": [1, "x", 2]}}]},
}.items():
    open(os.path.join(D, k), "w").write(json.dumps(v, indent=1) + "\n")
open(os.path.join(D, "states_joint_nonfinite.json"), "w").write('{"states": [{"tau": {"slide": [0, 1e999, 0]}}]}\n')
