"""Every scene rule, in process: a bad value anywhere is refused with kryflex.SceneError before any matrix is loaded.

Each case edits a copy of meshes/galileo (the spec, the scene text or one of its small files) and asserts that
load_scene raises SceneError whose message names the key path, the offending value and the fix, and that no body
matrix was loaded on the way (the whole scene is checked first). The good cases check that what valid scenes write
still loads. The rules live in python/kryflex/io/scene_schema.py and io/yaml_load.py.
"""
import copy
import os
import re
import shutil
import time

import numpy as np
import pytest
import yaml

import kryflex
from kryflex import _core
from kryflex.io import scene_schema, yaml_load

pytestmark = pytest.mark.fast   # the fast tier (tests/README.md)

HERE = os.path.dirname(os.path.abspath(__file__))
GALILEO_DIR = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(HERE))), "meshes", "galileo")
with open(os.path.join(GALILEO_DIR, "galileo.yaml")) as _f:
    GALILEO_TEXT = _f.read()
GALILEO = yaml.safe_load(GALILEO_TEXT)


@pytest.fixture(scope="module")
def folder(tmp_path_factory, quiet_library):
    d = str(tmp_path_factory.mktemp("scenes") / "galileo")
    shutil.copytree(GALILEO_DIR, d)
    return d


@pytest.fixture
def loads(monkeypatch):
    """Counts the body matrices loaded."""
    calls = []
    real = _core.load_matrix
    monkeypatch.setattr(_core, "load_matrix", lambda *a, **k: calls.append(a[0]) or real(*a, **k))
    return calls


# ------------------------------------------------------------------ edits

def at(path, value):
    """Sets spec[a][b]... (a dotted path; missing mappings are created); value None deletes the entry."""
    def edit(spec, d):
        keys = path.split(".")
        node = spec
        for k in keys[:-1]:
            node = node.setdefault(k, {})
        if value is None:
            del node[keys[-1]]
        else:
            node[keys[-1]] = value
    return edit


def rename(section, old, new):
    def edit(spec, d):
        spec[section] = {(new if k == old else k): v for k, v in spec[section].items()}
    return edit


def text(replace_old, replace_new):
    """The scene's text with one replacement."""
    def edit(spec, d):
        assert GALILEO_TEXT.count(replace_old) == 1, replace_old
        return GALILEO_TEXT.replace(replace_old, replace_new)
    return edit


def raw(data):
    return lambda spec, d: data


def nodes_file(body, content, name):
    """A nodes file (content: its text) for body."""
    def edit(spec, d):
        with open(os.path.join(d, name), "w") as f:
            f.write(content)
        spec["bodies"][body]["nodes"] = name
    return edit


def vector_term(content, name, **extra):
    """Output pointA_ry read by a vector file over the stator's 12 dofs."""
    def edit(spec, d):
        with open(os.path.join(d, name), "w") as f:
            f.write(content)
        spec["outputs"]["pointA_ry"] = [dict({"body": "stator", "vector": name}, **extra)]
    return edit


def spare_body(spec, d, joint=None):
    spec["bodies"]["spare"] = {"mass": "stator_M.mtx", "stiffness": "stator_K.mtx", "nodes": "stator_nodes.txt",
                               "interfaces": {"bearing": 1}}
    if joint:
        spec["joints"]["second"] = joint


def both(*edits):
    def edit(spec, d):
        out = None
        for e in edits:
            out = e(spec, d) or out
        return out
    return edit


STATOR_NODES = "# id x y z ndof\n1 0 0 0 6\n2 0 0 -1.7 6\n"
BOMB = "lol: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
    "l%d: &%s [%s]\n" % (i, chr(ord("a") + i), ", ".join(["*" + chr(ord("a") + i - 1)] * 9)) for i in range(1, 9))
ROT30 = [[0.8660254, -0.5, 0], [0.5, 0.8660254, 0], [0, 0, 1]]    # 7 digits: orthonormal to ~1e-8 only

# id -> (edit, what the message must contain, the fix (a regex))
CASES = {
    # ---- YAML itself
    "yaml_duplicate_top_key": (text("damping: 0.0025", "damping: 0.0025\ndamping: 0.003"),
                               ["'damping' appears twice (lines 27 and 28)"], r"keep one"),
    "yaml_duplicate_body": (text("  rotor:\n", "  stator:\n"), ["'stator' appears twice"], r"keep one"),
    "yaml_duplicate_nested_key": (text("output_blocks: 1,", "output_blocks: 1, moments: 3,"),
                                  ["'moments' appears twice (line 29, columns"], r"keep one"),
    "yaml_alias_bomb": (raw(BOMB), ["aliases", "expand to more than 100000"], r"write the entries out"),
    "yaml_alias_loop": (raw("bodies: &b [1, *b]\n"), ["*b", "loop"], r"write the entry out"),
    "yaml_too_deep": (raw("angles: " + "[" * 40 + "]" * 40 + "\n"), ["line 1", "deeper than 32"], r"remove the extra nesting"),
    "yaml_not_utf8": (raw(b"name: gal\xe9leo\n"), ["not UTF-8 text at byte 9"], r"save the scene as UTF-8"),
    "yaml_syntax": (text("angles: [0, 15, 30, 45, 60, 72]", "angles: [0, 15, 30\n  oops: : ]"),
                    ["not valid YAML at line 26, column"], r"fix the syntax"),
    "yaml_too_large": (raw("# padding\n" * 110000), ["1100000 bytes", "1048576"], r"their own files"),
    "yaml_empty": (raw(""), ["an empty file"], r"write the scene as a YAML mapping with bodies"),
    "yaml_list": (raw("- 1\n- 2\n"), ["[1, 2]"], r"write the scene as a YAML mapping with bodies"),
    # ---- top level
    "top_unknown_key": (text("damping: 0.0025", "dampng: 0.0025"), ["'dampng'"], r"did you mean 'damping'"),
    "top_bodies_missing": (at("bodies", None), ["bodies", "missing"], r"give at least one"),
    "top_inputs_empty": (at("inputs", {}), ["inputs", "missing or empty"], r"give at least one"),
    "top_name_list": (at("name", ["a"]), ["name", "['a']"], r"give it as text"),
    "top_name_newline": (at("name", "gal\nileo"), ["name", "'gal\\nileo'"], r"printable characters"),
    "top_description": (at("description", 3), ["description", "3"], r"as text"),
    # ---- band, damping, accuracy
    "damping_high": (at("damping", 1.5), ["damping", "1.5", "outside [0, 1)"], r"give the modal damping ratio in \[0, 1\)"),
    "damping_negative": (at("damping", -0.01), ["damping", "-0.01 is outside"], r"give the modal damping ratio in \[0, 1\)"),
    "damping_text": (at("damping", "low"), ["damping", "'low'", "not a number"], r"give the modal damping ratio in \[0, 1\)"),
    "damping_nan": (text("damping: 0.0025", "damping: .nan"), ["damping", "nan"], r"give the modal damping ratio in \[0, 1\)"),
    "damping_bool": (at("damping", True), ["damping", "True", "not a number"], r"\[0, 1\)"),
    "accuracy_one": (at("accuracy", 1.0), ["accuracy", "1.0", "(0, 1)"], r"target relative error"),
    "accuracy_negative": (at("accuracy", -0.1), ["accuracy", "-0.1"], r"give the target"),
    "band_reversed": (at("band", [10, 1]), ["band", "[10.0, 1.0]", "not below"], r"0 < f_low < f_high"),
    "band_zero": (at("band", [0, 10]), ["band", "0 is outside"], r"0 < f_low < f_high"),
    "band_one_value": (at("band", [1]), ["band", "[1]"], r"\[f_low, f_high\]"),
    "band_text": (at("band", "wide"), ["band", "'wide'"], r"\[f_low, f_high\]"),
    "band_infinite": (text("band: [0.01, 10.0]", "band: [0.01, .inf]"), ["band", "inf"], r"0 < f_low < f_high"),
    # ---- reduction
    "moments_zero": (at("reduction.moments", 0), ["reduction.moments", "0", "[1, 200]"], r"give an integer in"),
    "moments_huge": (at("reduction.moments", 201), ["reduction.moments", "201"], r"give an integer in \[1, 200\]"),
    "moments_fraction": (at("reduction.moments", 10.5), ["reduction.moments", "10.5", "not an integer"],
                         r"give an integer"),
    "moments_bool": (at("reduction.moments", True), ["reduction.moments", "True"], r"give an integer"),
    "output_blocks_negative": (at("reduction.output_blocks", -1), ["reduction.output_blocks", "-1"], r">= 0"),
    "output_blocks_too_many": (at("reduction.output_blocks", 10), ["reduction.output_blocks", "10", "moments (10)"],
                               r"fewer output blocks than moments"),
    "keep_threshold_zero": (at("reduction.keep_threshold", 0), ["reduction.keep_threshold", "0", "(0, 1]"],
                            r"give a value in \(0, 1\]"),
    "keep_threshold_high": (at("reduction.keep_threshold", 1.5), ["reduction.keep_threshold", "1.5"], r"\(0, 1\]"),
    "deflation_tol_one": (at("reduction.deflation_tol", 1), ["reduction.deflation_tol", "1 is outside (0, 1)"],
                          r"tolerances are relative"),
    "body_tol_zero": (at("reduction.body_tol", 0.0), ["reduction.body_tol", "0.0"], r"give a value in \(0, 1\)"),
    "reassembly_rtol_negative": (at("reduction.reassembly_rtol", -1e-9), ["reduction.reassembly_rtol", "-1e-09"],
                                 r"\(0, 1\)"),
    "shift_negative": (at("reduction.shift", -1), ["reduction.shift", "-1", "[0, inf)"], r"shift >= 0"),
    "eigen_cover_low": (at("reduction.eigen_cover", 0.5), ["reduction.eigen_cover", "0.5"], r"multiple >= 1"),
    "importance_unknown": (at("reduction.importance", "h3"), ["reduction.importance", "'h3'"], r"h2, hinf, static"),
    "basis_unknown": (at("reduction.basis", "modal"), ["reduction.basis", "'modal'"], r"krylov, eigen"),
    "method_unknown": (at("reduction.method", "multi"), ["reduction.method", "'multi'"],
                       r"single-angle, multi-angle"),
    "reduction_angle_999": (at("reduction.reduction_angle", 999), ["reduction.reduction_angle", "999"],
                            r"\[-360, 360\]"),
    "reduction_angle_text": (at("reduction.reduction_angle", "best"), ["reduction.reduction_angle", "'best'"],
                             r"give auto or an angle"),
    "reduction_angle_two": (at("reduction.reduction_angle", [10, 20]), ["reduction.reduction_angle", "[10, 20]",
                                                                         "1 revolute joint"], r"give 1 angle"),
    "reduction_angles_repeated": (at("reduction.reduction_angles", [0, 30, 0]),
                                  ["reduction.reduction_angles", "0", "appears twice"], r"each configuration once"),
    "reduction_angles_range": (at("reduction.reduction_angles", [400]), ["reduction.reduction_angles[0]", "400"],
                               r"\[-360, 360\]"),
    "reduction_angles_empty": (at("reduction.reduction_angles", []), ["reduction.reduction_angles", "empty"],
                               r"at least one configuration"),
    "save_maps_maybe": (at("reduction.save_maps", "maybe"), ["reduction.save_maps", "'maybe'"],
                        r"auto, true or false"),
    "static_correction_maybe": (at("reduction.static_correction", "maybe"),
                                ["reduction.static_correction", "'maybe'", "not a boolean"], r"true or false"),
    "static_correction_int": (at("reduction.static_correction", 1), ["reduction.static_correction", "1"],
                              r"true or false"),
    "reduction_unknown_key": (at("reduction.moment", 3), ["reduction", "'moment'"], r"did you mean 'moments'"),
    "reduction_not_mapping": (at("reduction", 5), ["reduction", "5"], r"is not a mapping; give a mapping of"),
    # ---- verify
    "verify_modes_zero": (at("verify.modes", 0), ["verify.modes", "0"], r"auto or a positive integer"),
    "verify_modes_text": (at("verify.modes", "many"), ["verify.modes", "'many'"], r"auto or a positive integer"),
    "frequency_points_one": (at("verify.frequency_points", 1), ["verify.frequency_points", "1"],
                             r"\[2, 100000\]"),
    "frequency_points_huge": (at("verify.frequency_points", 200000), ["verify.frequency_points", "200000"],
                              r"\[2, 100000\]"),
    "full_order_maybe": (at("verify.full_order", "maybe"), ["verify.full_order", "'maybe'"], r"true or false"),
    "frf_floor_positive": (at("verify.frf_floor_db", 10), ["verify.frf_floor_db", "10"], r"negative"),
    "verify_unknown_key": (at("verify.mode", 3), ["verify", "'mode'"], r"did you mean 'modes'"),
    # ---- angles of interest
    "angles_repeated": (at("angles", [30, 30]), ["angles", "30", "appears twice"], r"each configuration once"),
    "angles_999": (at("angles", [0, 999]), ["angles[1]", "999"], r"\[-360, 360\]"),
    "angles_text": (at("angles", ["a"]), ["angles[0]", "'a'"], r"in degrees"),
    "angles_two_per_config": (at("angles", [[0, 10]]), ["angles[0]", "[0, 10]", "1 revolute joint"],
                              r"give 1 angle"),
    "angles_missing": (at("angles", None), ["angles", "missing"], r"e\.g\. angles: \[0, 30, 60\]"),
    "angles_nan": (text("angles: [0, 15, 30, 45, 60, 72]", "angles: [0, .nan]"), ["angles[1]", "nan"],
                   r"in degrees"),
    "angles_unknown_joint": (at("angles", [{"spin": 10}]), ["angles[0]", "spin"],
                             r"one angle per revolute joint \(spin_bearing\)"),
    "angles_empty": (at("angles", []), ["angles", "empty"], r"give at least one configuration"),
    # ---- names
    "name_space": (rename("bodies", "rotor", "ro tor"), ["bodies", "'ro tor'"], r"ASCII letters"),
    "name_slash": (rename("bodies", "rotor", "a/b"), ["bodies", "'a/b'"], r"ASCII letters, digits"),
    "name_dot": (rename("bodies", "rotor", ".rotor"), ["bodies", "'.rotor'"], r"not starting with '\.'"),
    "name_long": (rename("bodies", "rotor", "r" * 64), ["bodies", "'rrrr"], r"1 to 63"),
    "name_non_ascii": (rename("bodies", "rotor", "r\u00f6tor"), ["bodies", "'r\u00f6tor'"], r"ASCII"),
    "name_interface": (at("bodies.rotor.interfaces", {"bear ing": 101}), ["bodies.rotor.interfaces",
                                                                          "'bear ing'"], r"ASCII letters"),
    "name_input_nul": (rename("inputs", "bearing_torque", "torque\0"), ["inputs", "'torque\\x00'"], r"ASCII"),
    "name_output_slash": (rename("outputs", "pointA_ry", "A/ry"), ["outputs", "'A/ry'"], r"HDF5 group names"),
    "name_joint_space": (rename("joints", "spin_bearing", "spin bearing"), ["joints", "'spin bearing'"],
                         r"ASCII letters"),
    "name_output_twice": (lambda s, d: s["outputs"].update({1: s["outputs"]["pointA_ry"],
                                                            "1": s["outputs"]["pointA_ry"]}),
                          ["outputs.1", "used twice"], r"unique name"),
    # ---- node ids and nodes
    "node_id_huge_interface": (at("bodies.rotor.interfaces.bearing", 3000000000),
                               ["bodies.rotor.interfaces.bearing", "3000000000", "exceeds 2147483647"],
                               r"renumber the nodes"),
    "node_id_negative_term": (lambda s, d: s["inputs"]["bearing_torque"][0].update(node=-1),
                              ["inputs.bearing_torque[0].node", "-1"], r"give the node id as an integer in \[0, 2147483647\]"),
    "node_id_text": (lambda s, d: s["inputs"]["bearing_torque"][0].update(node="one"),
                     ["inputs.bearing_torque[0].node", "'one'", "not an integer"], r"give the node id as an integer"),
    "node_id_fraction": (lambda s, d: s["outputs"]["pointA_ry"][0].update(node=1.5),
                         ["outputs.pointA_ry[0].node", "1.5"], r"give the node id as an integer"),
    "inline_nodes_duplicate": (at("bodies.stator.nodes", [[1, 0, 0, 0, 6], [1, 0, 0, -1.7, 6]]),
                               ["bodies.stator.nodes[1]", "node id 1 appears twice"], r"give each node once"),
    "inline_nodes_ndof": (at("bodies.stator.nodes", [[1, 0, 0, 0, 6], [2, 0, 0, -1.7, 4]]),
                          ["bodies.stator.nodes[1]", "ndof 4"], r"give 6 .* or 3"),
    "inline_nodes_nan": (at("bodies.stator.nodes", [[1, 0, 0, 0, 6], [2, 0, float("nan"), -1.7, 6]]),
                         ["bodies.stator.nodes[1]", "nan"], r"finite numbers"),
    "inline_nodes_short": (at("bodies.stator.nodes", [[1, 0, 0, 0, 6], [2, 0, 0, 6]]),
                           ["bodies.stator.nodes[1]", "[2, 0, 0, 6]"], r"five numbers per node"),
    "inline_nodes_huge_id": (at("bodies.stator.nodes", [[1, 0, 0, 0, 6], [2 ** 32, 0, 0, 0, 6]]),
                             ["bodies.stator.nodes[1]", "4294967296"], r"renumber the nodes"),
    "nodes_file_fields": (nodes_file("stator", "1 0 0 0 6\n2 0 0 6\n", "n1.txt"),
                          ["bodies.stator.nodes", "n1.txt line 2", "'2 0 0 6'"], r"five numbers per line"),
    "nodes_file_huge_id": (nodes_file("stator", "# x\n1 0 0 0 6\n3000000000 0 0 -1.7 6\n", "n2.txt"),
                           ["bodies.stator.nodes (n2.txt line 3)", "3000000000 exceeds 2147483647"],
                           r"renumber the nodes"),
    "nodes_file_duplicate": (nodes_file("stator", "1 0 0 0 6\n\n1 0 0 -1.7 6\n", "n3.txt"),
                             ["bodies.stator.nodes (n3.txt line 3)", "node id 1 appears twice (n3.txt line 1 and n3.txt line 3)"], r"each node once"),
    "nodes_file_text": (nodes_file("stator", "1 0 0 0 6\n2 0 zero -1.7 6\n", "n4.txt"),
                        ["n4.txt line 2", "'2 0 zero -1.7 6'", "not numbers"], r"give 'id x y z ndof'"),
    "nodes_file_ndof": (nodes_file("stator", "1 0 0 0 6\n2 0 0 -1.7 5\n", "n5.txt"),
                        ["n5.txt line 2", "ndof 5"], r"give 6"),
    "nodes_file_nan": (nodes_file("stator", "1 0 0 0 6\n2 nan 0 -1.7 6\n", "n6.txt"),
                       ["n6.txt line 2", "nan is not a finite number"], r"finite numbers"),
    "nodes_file_missing": (at("bodies.rotor.nodes", "nowhere.txt"), ["bodies.rotor.nodes", "'nowhere.txt'",
                                                                     "not found"], r"fix the path"),
    "nodes_file_empty": (nodes_file("stator", "# nothing\n", "n7.txt"), ["bodies.stator.nodes", "n7.txt",
                                                                        "no nodes"], r"'id x y z ndof' per line"),
    # ---- joints
    "joint_type": (at("joints.spin_bearing.type", "hinge"), ["joints.spin_bearing.type", "'hinge'"],
                   r"revolute, fixed"),
    "joint_axis_zero": (at("joints.spin_bearing.axis", [0, 0, 0]), ["joints.spin_bearing.axis", "[0, 0, 0]",
                                                                   "is zero"], r"a direction such as"),
    "joint_axis_short": (at("joints.spin_bearing.axis", [0, 1]), ["joints.spin_bearing.axis", "[0, 1]"],
                         r"\[x, y, z\]"),
    "joint_axis_text": (at("joints.spin_bearing.axis", "z"), ["joints.spin_bearing.axis", "'z'"], r"\[x, y, z\]"),
    "joint_orientation_text": (at("joints.spin_bearing.orientation", "identity"),
                               ["joints.spin_bearing.orientation", "'identity'", "not a 3x3 matrix"],
                               r"3x3 rotation matrix as rows"),
    "joint_orientation_2x2": (at("joints.spin_bearing.orientation", [[1, 0], [0, 1]]),
                              ["joints.spin_bearing.orientation", "[[1, 0], [0, 1]]"], r"3x3 rotation matrix"),
    "joint_orientation_scaled": (at("joints.spin_bearing.orientation", [[2, 0, 0], [0, 1, 0], [0, 0, 1]]),
                                 ["joints.spin_bearing.orientation", "not a rotation", "error 3"],
                                 r"orthonormal to 1e-06 with det \+1"),
    "joint_orientation_reflection": (at("joints.spin_bearing.orientation", [[1, 0, 0], [0, 1, 0], [0, 0, -1]]),
                                     ["joints.spin_bearing.orientation", "det -1"], r"det \+1"),
    "joint_orientation_text_entry": (at("joints.spin_bearing.orientation", [[1, 0, 0], [0, 1, 0], [0, 0, "a"]]),
                                     ["joints.spin_bearing.orientation", "'a'"], r"3x3 rotation matrix"),
    "joint_parent_unknown": (at("joints.spin_bearing.parent", "statr"), ["joints.spin_bearing.parent", "'statr'"],
                             r"bodies: stator, rotor"),
    "joint_interface_unknown": (at("joints.spin_bearing.child_interface", "hub"),
                                ["joints.spin_bearing.child_interface", "'hub'"], r"declare it under bodies\.rotor"),
    "joint_missing_child": (at("joints.spin_bearing.child", None), ["joints.spin_bearing", "'child' is missing"],
                            r"give it"),
    "joint_unknown_key": (at("joints.spin_bearing.axes", [0, 0, 1]), ["joints.spin_bearing", "'axes'"],
                          r"did you mean 'axis'"),
    "joint_to_itself": (at("joints.spin_bearing.child", "stator"), ["joints.spin_bearing", "stator"],
                        r"two different bodies"),
    "joint_loop": (at("joints.back", {"parent": "rotor", "parent_interface": "bearing", "child": "stator",
                                      "child_interface": "bearing"}), ["joints", "loop"], r"needs a tree"),
    "joint_child_twice": (lambda s, d: spare_body(s, d, {"parent": "spare", "parent_interface": "bearing",
                                                         "child": "rotor", "child_interface": "bearing"}),
                          ["joints.second", "'rotor' is the child of two joints"], r"make one of them its parent"),
    "body_unreached": (spare_body, ["bodies.spare", "not attached"], r"add a joint"),
    # ---- inputs and outputs
    "term_dof": (lambda s, d: s["outputs"]["pointA_ry"][0].update(dof="rw"), ["outputs.pointA_ry[0].dof", "'rw'"],
                 r"ux, uy, uz, rx, ry, rz"),
    "term_weight_text": (lambda s, d: s["inputs"]["bearing_torque"][1].update(weight="heavy"),
                         ["inputs.bearing_torque[1].weight", "'heavy'", "not a number"], r"finite number"),
    "term_weight_inf": (lambda s, d: s["inputs"]["bearing_torque"][1].update(weight=float("inf")),
                        ["inputs.bearing_torque[1].weight", "inf"], r"finite number"),
    "term_body": (lambda s, d: s["inputs"]["bearing_torque"][1].update(body="rotr"),
                  ["inputs.bearing_torque[1].body", "'rotr'"], r"bodies: stator, rotor"),
    "term_node_and_vector": (lambda s, d: s["inputs"]["bearing_torque"][1].update(vector="v.txt"),
                             ["inputs.bearing_torque[1]", "both a vector and node/dof"], r"not both"),
    "term_no_dof": (lambda s, d: s["inputs"]["bearing_torque"][1].pop("dof") and None,
                    ["inputs.bearing_torque[1]", "missing"], r"give node and dof"),
    "term_unknown_key": (lambda s, d: s["inputs"]["bearing_torque"][1].update(wieght=1),
                         ["inputs.bearing_torque[1]", "'wieght'"], r"did you mean 'weight'"),
    "term_not_list": (at("outputs.pointA_ry", "A"), ["outputs.pointA_ry", "'A'"], r"list of .* terms"),
    "term_node_absent": (lambda s, d: s["outputs"]["pointA_ry"][0].update(node=999),
                         ["outputs.pointA_ry[0].node", "no node 999"], r"use one of its node ids"),
    "term_rotation_on_3dof": (lambda s, d: s["outputs"]["pointA_ry"][0].update(body="rotor", node=102),
                              ["outputs.pointA_ry[0].dof", "node 102", "3 dofs", "'ry'"], r"need a 6-dof node"),
    "interface_node_absent": (at("bodies.rotor.interfaces.bearing", 107), ["bodies.rotor.interfaces.bearing", "107"],
                              r"use one of its node ids"),
    "interface_3dof_node": (at("bodies.rotor.interfaces.bearing", 102), ["bodies.rotor.interfaces.bearing", "102"],
                            r"need 6"),
    # ---- files
    "mass_missing_last_body": (at("bodies.rotor.mass", "gone_M.mtx"), ["bodies.rotor.mass", "'gone_M.mtx'",
                                                                       "not found"], r"fix the path"),
    "stiffness_is_folder": (at("bodies.rotor.stiffness", "."), ["bodies.rotor.stiffness", "a folder, not a file"],
                            r"give the path of the matrix file itself"),
    "mass_not_text": (at("bodies.rotor.mass", 5), ["bodies.rotor.mass", "5"], r"relative to the scene file"),
    "vector_missing": (lambda s, d: s["outputs"].update(pointA_ry=[{"body": "stator", "vector": "none.txt"}]),
                       ["outputs.pointA_ry[0].vector", "'none.txt'", "not found"], r"fix the path"),
    "vector_length": (vector_term("1 2 3\n", "v1.txt"), ["outputs.pointA_ry[0].vector", "3 entries",
                                                         "'stator' has 12 dofs"], r"one entry per dof"),
    "vector_nan": (vector_term("0 0 0\n0 nan 0\n", "v2.txt"), ["outputs.pointA_ry[0].vector", "v2.txt line 2",
                                                               "'nan'"], r"finite numbers"),
    "vector_text": (vector_term("0 0 0\n# c\n0 x 0\n", "v3.txt"), ["outputs.pointA_ry[0].vector", "v3.txt line 3",
                                                                   "'x'"], r"one number per dof"),
}

# -scene.<path> options: (options, mentions, fix)
OVERRIDES = {
    "override_unknown_reduction_key": ({"scene.reduction.momnets": "12"},
                                       ["option -scene.reduction.momnets", "'momnets'"], r"did you mean 'moments'"),
    "override_unknown_top_key": ({"scene.dampng": "0.1"}, ["option -scene.dampng"], r"did you mean 'damping'"),
    "override_bad_value": ({"scene.damping": "2"}, ["damping", "2 is outside [0, 1)"], r"give the modal damping ratio in \[0, 1\)"),
    "override_repeated_angles": ({"scene.angles": "30,30"}, ["angles", "30", "appears twice"],
                                 r"each configuration once"),
    "override_unknown_body": ({"scene.bodies.rotr.mass": "x.mtx"}, ["option -scene.bodies.rotr.mass", "'rotr'"],
                              r"did you mean 'rotor'"),
    "override_unknown_body_key": ({"scene.bodies.rotor.mas": "x.mtx"}, ["option -scene.bodies.rotor.mas"],
                                  r"did you mean 'mass'"),
    "override_below_scalar": ({"scene.damping.x": "1"}, ["option -scene.damping.x"], r"give -scene.damping VALUE"),
    "override_verify_modes": ({"scene.verify.modes": "0"}, ["verify.modes", "0"], r"auto or a positive integer"),
    "override_bad_yaml": ({"scene.reduction.moments": "[1"}, ["option -scene.reduction.moments", "not valid YAML"],
                          r"fix the syntax"),
}


def write_case(folder, case, edit):
    spec = copy.deepcopy(GALILEO)
    out = edit(spec, folder)
    path = os.path.join(folder, case + ".yaml")
    if out is None:
        out = yaml.safe_dump(spec, sort_keys=False, allow_unicode=True)
    with open(path, "wb") as f:
        f.write(out if isinstance(out, bytes) else out.encode())
    return path


def check_message(msg, mentions, fix):
    assert "\n" not in msg.rstrip() or "gal\\nileo" in msg, f"one line: {msg!r}"
    assert len(msg) < 600, f"short: {len(msg)} characters"
    for m in mentions:
        assert m in msg, f"the message should name {m!r}: {msg!r}"
    assert re.search(fix, msg), f"the message should say what to do ({fix!r}): {msg!r}"


@pytest.mark.parametrize("case", sorted(CASES))
def test_refused(folder, loads, case):
    edit, mentions, fix = CASES[case]
    path = write_case(folder, case, edit)
    start = time.perf_counter()
    with pytest.raises(kryflex.SceneError) as err:
        kryflex.load_scene(path, overrides=False)
    elapsed = time.perf_counter() - start
    msg = str(err.value)
    print(f"{case}: {msg}")
    assert msg.startswith(case + ".yaml: "), f"the message should start with the scene file: {msg!r}"
    check_message(msg, mentions, fix)
    assert not loads, f"{case}: matrices loaded before the scene was refused: {loads}"
    assert elapsed < 1.0, f"{case}: refused after {elapsed:.2f} s"


@pytest.fixture
def options():
    from petsc4py import PETSc
    opts, names = PETSc.Options(), []

    def set_(values):
        for k, v in values.items():
            opts.setValue(k, v)
            names.append(k)
    yield set_
    for k in names:
        opts.delValue(k)


@pytest.mark.parametrize("case", sorted(OVERRIDES))
def test_override_refused(folder, loads, options, case):
    values, mentions, fix = OVERRIDES[case]
    path = write_case(folder, case, lambda s, d: None)
    options(values)
    with pytest.raises(kryflex.SceneError) as err:
        kryflex.load_scene(path)
    msg = str(err.value)
    print(f"{case}: {msg}")
    check_message(msg, mentions, fix)
    assert not loads


def test_override_applied(folder, options):
    path = write_case(folder, "override_ok", lambda s, d: None)
    options({"scene.reduction.moments": "12", "scene.angles": "0,30", "scene.reduction.static_correction": "no"})
    scene = kryflex.load_scene(path)
    assert scene.reduction["moments"] == 12 and scene.configurations == [[0.0], [30.0]]
    assert scene.reduction["static_correction"] is False


def test_override_exponent_without_dot(folder, options):
    path = write_case(folder, "override_exponent", lambda s, d: None)
    options({"scene.accuracy": "1e-12", "scene.reduction.deflation_tol": "1E-9"})
    scene = kryflex.load_scene(path)
    assert scene.accuracy == 1e-12 and scene.reduction["deflation_tol"] == 1e-9


# ------------------------------------------------------------------ what valid scenes write still loads

def test_galileo_unchanged(loads):
    scene = kryflex.load_scene(os.path.join(GALILEO_DIR, "galileo.yaml"), overrides=False)
    assert scene.name == "galileo" and scene.body_names == ["stator", "rotor"] and scene.body_dofs == [12, 21]
    assert scene.interfaces == [["bearing"], ["bearing"]] and scene.revolute == ["spin_bearing"]
    assert scene.joints == [dict(name="spin_bearing", type="revolute", parent=0, child=1, parent_interface=0,
                                 child_interface=0, axis=[0.0, 0.0, 1.0], R0=None)]
    assert scene.input_names == ["bearing_torque"] and scene.output_names == ["pointA_ry"]
    assert scene.configurations == [[0.0], [15.0], [30.0], [45.0], [60.0], [72.0]]
    assert scene.band == [0.01, 10.0] and scene.damping == 0.0025 and scene.accuracy == 0.05
    # the defaults, but for the paper's c = 10, H2 importance and keep threshold 0.1, which the scene file states
    assert scene.reduction == dict(scene_schema.REDUCTION_DEFAULTS, moments=10, importance="h2", keep_threshold=0.1)
    assert scene.paper == "lee"
    assert scene.verify == dict(scene_schema.VERIFY_DEFAULTS)
    assert scene.info["system_dofs"] == 28 and len(loads) == 4
    ids, xyz, ndof = scene.body_nodes[1]
    assert ids.dtype == np.int32 and ids.tolist() == [101, 102, 103, 104, 105, 106] and ndof.sum() == 21


GOOD = {
    "yes_no_booleans": (text("reduction_angle: auto}", "reduction_angle: auto, static_correction: no, "
                             "save_maps: yes}\nverify: {full_order: off, modes: 20}"),
                        lambda s: (s.reduction["static_correction"], s.reduction["save_maps"],
                                   s.verify["full_order"], s.verify["modes"]) == (False, True, False, 20)),
    "integral_float_moments": (at("reduction.moments", 12.0), lambda s: s.reduction["moments"] == 12),
    "reduction_angle_number": (at("reduction.reduction_angle", 30), lambda s: s.reduction["reduction_angle"] == [30.0]),
    "reduction_angle_list": (at("reduction.reduction_angle", [-360]),
                             lambda s: s.reduction["reduction_angle"] == [-360.0]),
    "reduction_angles": (both(at("reduction.reduction_angles", [0, 45, 360]), at("reduction.method", "multi-angle")),
                         lambda s: s.reduction["reduction_angles"] == [[0.0], [45.0], [360.0]]),
    "angles_as_joint_maps": (at("angles", [{"spin_bearing": 10}, {"spin_bearing": -10}]),
                             lambda s: s.configurations == [[10.0], [-10.0]]),
    "angles_scalar": (at("angles", 30), lambda s: s.configurations == [[30.0]]),
    "orientation_7_digits": (at("joints.spin_bearing.orientation", ROT30),
                             lambda s: np.abs(np.array(s.joints[0]["R0"]) - ROT30).max() < 1e-6),
    "orientation_identity_kept": (at("joints.spin_bearing.orientation", [[1, 0, 0], [0, 1, 0], [0, 0, 1]]),
                                  lambda s: s.joints[0]["R0"] == [[1, 0, 0], [0, 1, 0], [0, 0, 1]]),
    "merge_keys": (text("reduction: {", "defaults: &d {moments: 8}\nreduction: {<<: *d, "),
                   None),
    "utf8_bom_and_comment": (raw(("\ufeff# Galil\u00e9o\n" + GALILEO_TEXT).encode()), lambda s: s.name == "galileo"),
    "name_characters": (rename("joints", "spin_bearing", "Spin-2.b+c_"), lambda s: s.revolute == ["Spin-2.b+c_"]),
    "name_63_characters": (rename("outputs", "pointA_ry", "o" * 63), lambda s: s.output_names == ["o" * 63]),
    "vector_term_weighted": (vector_term("0 0 0 0 0 0\n0 0 0 0 1 0\n", "v_ok.txt", weight=2.0),
                             lambda s: s.output_names == ["pointA_ry"]),
    "fixed_joint": (at("joints.spin_bearing.type", "fixed"), None),
    # YAML 1.1 reads 1e-12 (no dot) as text: the scene loader reads it as the number everybody means
    "exponent_without_dot": (text("accuracy: 0.05", "accuracy: 1e-12"), lambda s: s.accuracy == 1e-12),
}


@pytest.mark.parametrize("case", sorted(GOOD))
def test_good(folder, case):
    edit, check = GOOD[case]
    if case == "merge_keys":     # 'defaults' is no scene key: merge keys work, unknown keys are still refused
        path = write_case(folder, case, edit)
        with pytest.raises(kryflex.SceneError, match="unknown key 'defaults'"):
            kryflex.load_scene(path, overrides=False)
        return
    if case == "fixed_joint":    # a fixed joint leaves no revolute joint: no angles then
        edit = both(edit, at("angles", None))
    scene = kryflex.load_scene(write_case(folder, case, edit), overrides=False)
    assert check is None or check(scene), case


def test_alias_bomb_is_quick():
    start = time.perf_counter()
    with pytest.raises(yaml_load.YAMLInputError, match="expand to more than"):
        yaml_load.load_text(BOMB + "l9: &j [" + ", ".join(["*i"] * 9) + "]\n")
    assert time.perf_counter() - start < 0.5


def test_node_id_limit():
    ids, _, _ = scene_schema.node_table("s.yaml", "bodies.b.nodes", [[2 ** 31 - 1, 0, 0, 0, 6], [0, 1, 0, 0, 3]])
    assert ids.dtype == np.int32 and ids.tolist() == [2 ** 31 - 1, 0]


def test_scene_path_not_a_file(tmp_path):
    with pytest.raises(kryflex.SceneError, match=r"is a folder, not a file .*give the path of the scene's \.yaml file"):
        kryflex.load_scene(str(tmp_path))
    with pytest.raises(kryflex.SceneError, match=r"nothere\.yaml: scene file not found .*fix the path"):
        kryflex.load_scene(str(tmp_path / "nothere.yaml"))


def test_scene_from_dict_same_rules():
    spec = copy.deepcopy(GALILEO)
    spec["angles"] = [30, 30]
    with pytest.raises(kryflex.SceneError, match=r"^scene.yaml: angles: configuration 30 appears twice"):
        kryflex.scene_from_dict(spec, base=GALILEO_DIR)


NODE_TEXTS = {
    "plain": b"# id x y z ndof\n1 0 0 0 6\n2 0.5 -1e-3 1.7 3\n  3 1. .25 -0 3  # tip\n% a comment\n\n4 1e2 2 3 6\n",
    "crlf": b"1 0 0 0 6\r\n2 0 0 -1.7 3\r\n",
    "lone_cr": b"1 0 0 0 6\r2 0 0 -1.7 3\r",
    "form_feed": b"1 0 0\x0c0 6\n",
    "integral_float_id": b"1.0 0 0 0 6\n",
    "integral_float_ndof": b"1 0 0 0 6.0\n",
    "underscores": b"1_0 0 0 0 6\n2 1_0.5 0 0 3\n",
    "signs": b"+1 +0.5 -2 3 +6\n",
    "layouts": b"1 0 0 0 c345\n2 0 0 1 s\n3 0 0 2 6\n",
    "latin1_comment": "1 0 0 0 6  # gal\xe9e\n".encode("latin-1"),
    "utf8_comment": "1 0 0 0 6  # gal\xe9e\n2 0 0 1 3\n".encode("utf-8"),
    "nbsp": "1\xa00 0 0 6\n".encode("utf-8"),
    "arabic_digit": "1 \u0661 0 0 6\n".encode("utf-8"),
    "nan": b"1 nan 0 0 6\n",
    "infinity": b"1 0 Infinity 0 6\n",
    "negative_id": b"-1 0 0 0 6\n",
    "huge_id": b"1 0 0 0 6\n99999999999999999999 0 0 0 6\n",
    "duplicate": b"1 0 0 0 6\n1 0 0 1 6\n",
    "columns": b"1 0 0 0 6 7\n",
    "comments_only": b"# nothing\n% here\n",
    "empty": b"",
}


@pytest.mark.parametrize("case", sorted(NODE_TEXTS))
def test_nodes_files_read_as_line_by_line(case, tmp_path, monkeypatch):
    """A nodes file read by NumPy's C reader gives what the line-by-line reader gives, table or message, on every
    kind of text (where the C reader might differ it leaves the file to the line-by-line reader)."""
    from kryflex.io import scene as scene_io
    (tmp_path / "n.txt").write_bytes(NODE_TEXTS[case])

    def read():
        try:
            t = scene_io._read_nodes("s.yaml", "bodies.b.nodes", "n.txt", str(tmp_path))
        except kryflex.SceneError as e:
            return str(e)
        return [a.tolist() for a in (t[0], t[1], t[2], t.comps)] + [a.dtype.str for a in (t[0], t[1], t[2], t.comps)]
    fast = read()
    if case in ("plain", "crlf", "signs", "utf8_comment", "nbsp"):     # these the C reader reads
        assert isinstance(fast, list) and scene_io._node_file_rows(str(tmp_path / "n.txt")) is not None, case
    monkeypatch.setattr(scene_io, "_node_file_rows", lambda path: None)
    assert repr(fast) == repr(read()), case
