"""Bad scene files: keys, types, ranges, enumerations, names, angles, joints, YAML abuse, -scene.<path> overrides.

Every case is refused with exit 2 by `kryflex info` (fast: it fails before any reduction) or, where the output
folder matters, by `kryflex reduce`; kryflex.load_scene raises kryflex.SceneError with the same content. The message
names the scene file and the entry path, the offending value, and the fix.
"""
from .edits import (alias_bomb, deep_nesting, huge_scene, make_folder, non_utf8_scene, rename_body,
                    rename_interface, rename_io, rename_joint, set_key, spec_edit, text, write)
from .harness import DID_YOU_MEAN, EXIT_INPUT, FIX, Case

REDUCE = ("reduce", "{scene}", "-o", "{out}", "-quiet")


def S(name, prepare, mentions, fix=FIX, argv=("info", "{scene}"), **kw):
    """A scene case: the message also names the scene file."""
    return Case("scene", name, prepare, argv=argv, code=EXIT_INPUT, mentions=("galileo.yaml",) + tuple(mentions),
                fix=fix, api="scene", **kw)


def R(name, prepare, mentions, fix=FIX, out="absent", **kw):
    """A scene case run through `kryflex reduce -o OUT`: nothing may be written."""
    return S(name, prepare, mentions, fix, argv=REDUCE, out=out, **kw)


def override(name, options, mentions, fix=FIX, out="absent", command="reduce"):
    """A -scene.<path> VALUE option on the command line of a good scene."""
    argv = (REDUCE if command == "reduce" else ("info", "{scene}")) + tuple(options)
    return S(name, None, mentions, fix, argv=argv, out=out if command == "reduce" else "none")


RANGE = r"(\(|\[)\s*0|between|range|positive|greater|at least|> ?0|must|give|use"
# a bad name: the fix is to rename it, or the rule a name must follow ("use 1 to 63 ASCII letters, ...")
NAME_FIX = r"rename|\buse 1 to \d+ ASCII"
IN_0_1 = r"\(0, 1\]|\(0,1\]|between 0 and 1|in \(0|0 < |give a value"

CASES = [
    # ------------------------------------------------------------------ types
    R("damping_not_a_number", text("damping: 0.0025", "damping: low"), ["damping", "low"]),          # existing
    S("damping_bool", text("damping: 0.0025", "damping: true"), ["damping", "re:true|True"]),
    S("damping_list", text("damping: 0.0025", "damping: [0.0025]"), ["damping", "0.0025"]),
    S("damping_null", text("damping: 0.0025", "damping:"), ["damping", "re:None|null|empty|missing"]),
    S("accuracy_string", text("accuracy: 0.05", "accuracy: tight"), ["accuracy", "tight"]),
    S("moments_float", set_key("reduction.moments", 10.5), ["reduction.moments", "10.5"]),
    S("moments_string", set_key("reduction.moments", "ten"), ["reduction.moments", "ten"]),
    S("paper_unknown", set_key("paper", "smith"), ["paper", "smith", "lee"]),
    S("paper_not_a_string", set_key("paper", 3), ["paper", "3"]),
    S("band_string", text("band: [0.01, 10.0]", "band: 0.01-10"), ["band", "0.01-10"]),
    S("band_element_string", text("band: [0.01, 10.0]", "band: [0.01, ten]"), ["band", "ten"]),
    S("weight_not_a_number", text("weight: -1.0", "weight: heavy"), ["inputs.bearing_torque[1]", "heavy"]),  # existing
    S("node_id_not_a_number", text("{body: stator, node: 1, dof: rz", "{body: stator, node: one, dof: rz"),
      ["inputs.bearing_torque[0]", "one"]),                                                          # existing
    S("static_correction_not_bool", set_key("reduction.static_correction", "maybe"),
      ["reduction.static_correction", "maybe"]),
    S("bodies_not_a_mapping", spec_edit(lambda s: s.__setitem__("bodies", ["stator", "rotor"])), ["bodies"]),
    S("scene_not_a_mapping", write("galileo.yaml", "- stator\n- rotor\n"), []),
    S("scene_empty", write("galileo.yaml", ""), []),
    # ------------------------------------------------------------------ ranges
    S("damping_negative", text("damping: 0.0025", "damping: -0.01"), ["damping", "-0.01"]),
    S("damping_one", text("damping: 0.0025", "damping: 1.0"), ["damping", "re:\\b1(\\.0*)?\\b"]),
    S("damping_inf", text("damping: 0.0025", "damping: .inf"), ["damping", "inf"]),
    S("accuracy_negative", text("accuracy: 0.05", "accuracy: -0.05"), ["accuracy", "-0.05"]),
    S("accuracy_zero", text("accuracy: 0.05", "accuracy: 0"), ["accuracy", "0"]),
    S("accuracy_nan", text("accuracy: 0.05", "accuracy: .nan"), ["accuracy", "nan"]),
    S("band_reversed", text("band: [0.01, 10.0]", "band: [10.0, 0.01]"), ["band", "10", "0.01"]),
    S("band_equal", text("band: [0.01, 10.0]", "band: [1.0, 1.0]"), ["band", "1"]),
    S("band_negative", text("band: [0.01, 10.0]", "band: [-1.0, 10.0]"), ["band", "-1"]),
    S("band_three_values", text("band: [0.01, 10.0]", "band: [0.01, 1.0, 10.0]"), ["band", "0.01, 1.0, 10.0"]),
    S("moments_zero", set_key("reduction.moments", 0), ["reduction.moments", "0"]),
    S("moments_negative", set_key("reduction.moments", -3), ["reduction.moments", "-3"]),
    S("output_blocks_negative", set_key("reduction.output_blocks", -1), ["reduction.output_blocks", "-1"]),
    S("output_blocks_not_below_moments", set_key("reduction.output_blocks", 10), ["output_blocks", "10"]),
    R("keep_threshold_1.5", set_key("reduction.keep_threshold", 1.5), ["reduction.keep_threshold", "1.5"],
      fix=IN_0_1, out="earlier"),
    S("keep_threshold_zero", set_key("reduction.keep_threshold", 0), ["reduction.keep_threshold", "0"], fix=IN_0_1),
    S("keep_threshold_negative", set_key("reduction.keep_threshold", -0.1), ["reduction.keep_threshold", "-0.1"]),
    S("reduction_angle_999", set_key("reduction.reduction_angle", 999), ["reduction.reduction_angle", "999"]),
    S("reduction_angle_string", set_key("reduction.reduction_angle", "zero"), ["reduction.reduction_angle", "zero"]),
    S("reduction_angles_out_of_range", set_key("reduction.reduction_angles", [0, 400]),
      ["reduction.reduction_angles", "400"]),
    S("deflation_tol_negative", set_key("reduction.deflation_tol", -1e-10), ["reduction.deflation_tol", "-1e-10"]),
    S("shift_negative", set_key("reduction.shift", -1.0), ["reduction.shift", "-1"]),
    S("eigen_cover_zero", set_key("reduction.eigen_cover", 0), ["reduction.eigen_cover", "0"]),
    # ------------------------------------------------------------------ enumerations
    S("importance_h3", set_key("reduction.importance", "h3"), ["reduction.importance", "h3", "h2"]),
    S("method_misspelt", set_key("reduction.method", "multiangle"), ["reduction.method", "multiangle", "multi-angle"]),
    S("basis_misspelt", set_key("reduction.basis", "krylof"), ["reduction.basis", "krylof", "krylov"]),
    S("save_maps_bad", set_key("reduction.save_maps", "sometimes"), ["reduction.save_maps", "sometimes"]),
    S("joint_type_prismatic", text("type: revolute", "type: prismatic"), ["joints.spin_bearing.type", "prismatic"]),
    S("dof_misspelt", text("dof: ry}", "dof: ryy}"), ["outputs.pointA_ry[0]", "ryy"]),
    # ------------------------------------------------------------------ unknown keys, did you mean
    S("misspelt_key", text("damping: 0.0025", "dampng: 0.0025"), ["dampng", "damping"], fix=DID_YOU_MEAN),  # existing
    S("unknown_reduction_key", set_key("reduction.momnets", 12), ["reduction", "momnets", "moments"], fix=DID_YOU_MEAN),
    S("unknown_body_key", text("stiffness: rotor_K.mtx", "stifness: rotor_K.mtx"), ["bodies.rotor", "stifness",
                                                                                      "stiffness"], fix=DID_YOU_MEAN),
    S("unknown_joint_key", text("axis: [0, 0, 1]", "axsi: [0, 0, 1]"), ["joints.spin_bearing", "axsi", "axis"],
      fix=DID_YOU_MEAN),
    S("unknown_term_key", text("weight: -1.0", "wieght: -1.0"), ["inputs.bearing_torque[1]", "wieght", "weight"],
      fix=DID_YOU_MEAN),
    S("unknown_verify_key", set_key("verify.mdoes", 20), ["verify", "mdoes", "modes"], fix=DID_YOU_MEAN),
    # ------------------------------------------------------------------ duplicate YAML keys (PyYAML keeps the last)
    S("duplicate_top_key", text("damping: 0.0025", "damping: 0.0025\ndamping: 0.01"), ["damping", "re:duplicate|twice"]),
    S("duplicate_body_key", text("mass: rotor_M.mtx", "mass: rotor_M.mtx\n    mass: stator_M.mtx"),
      ["bodies.rotor", "mass", "re:duplicate|twice"]),
    S("duplicate_body_name", text("  rotor:\n", "  stator:\n    mass: stator_M.mtx\n    stiffness: stator_K.mtx\n"
                                  "    nodes: stator_nodes.txt\n    interfaces: {bearing: 1}\n  rotor:\n"),
      ["stator", "re:duplicate|twice"]),
    S("duplicate_interface_name", text("interfaces: {bearing: 101}", "interfaces: {bearing: 101, bearing: 102}"),
      ["bodies.rotor.interfaces", "bearing", "re:duplicate|twice"]),
    # ------------------------------------------------------------------ names: '/', spaces, non-ASCII
    R("body_name_slash", rename_body("rotor", "rot/or"), ["rot/or"], fix=NAME_FIX),
    S("body_name_space", rename_body("rotor", "my rotor"), ["my rotor"], fix=NAME_FIX),
    S("body_name_non_ascii", rename_body("rotor", "rötor"), ["rötor"], fix=NAME_FIX),
    S("joint_name_slash", rename_joint("spin_bearing", "spin/bearing"), ["spin/bearing"], fix=NAME_FIX),
    S("input_name_space", rename_io("inputs", "bearing_torque", "bearing torque"), ["bearing torque"], fix=NAME_FIX),
    S("output_name_non_ascii", rename_io("outputs", "pointA_ry", "pointÅ_ry"), ["pointÅ_ry"], fix=NAME_FIX),
    S("interface_name_slash", rename_interface("rotor", "bearing", "bear/ing"), ["bear/ing"], fix=NAME_FIX),
    # ------------------------------------------------------------------ angles
    S("empty_angles", text("angles: [0, 15, 30, 45, 60, 72]", "angles: []"), ["angles"],
      fix=r"give at least one configuration"),                                                       # existing
    S("angles_missing", text("angles: [0, 15, 30, 45, 60, 72]\n", ""), ["angles"]),
    S("angles_duplicate", text("angles: [0, 15, 30, 45, 60, 72]", "angles: [0, 15, 30, 30, 60, 72]"),
      ["angles", "30", "re:duplicate|twice|more than once"]),
    S("angles_out_of_range", text("angles: [0, 15, 30, 45, 60, 72]", "angles: [0, 15, 1000]"), ["angles", "1000"]),
    S("angles_wrong_count", text("angles: [0, 15, 30, 45, 60, 72]", "angles: [[0, 10], [15, 20]]"),
      ["angles[0]", "re:1 revolute|one revolute"]),
    S("angles_not_numbers", text("angles: [0, 15, 30, 45, 60, 72]", "angles: [0, fifteen]"), ["angles", "fifteen"]),
    S("angles_nan", text("angles: [0, 15, 30, 45, 60, 72]", "angles: [0, .nan]"), ["angles", "nan"]),
    S("angles_unknown_joint", text("angles: [0, 15, 30, 45, 60, 72]", "angles: [{spin_bearng: 0}]"),
      ["angles[0]", "spin_bearng", "spin_bearing"]),
    # ------------------------------------------------------------------ joints, interfaces, nodes
    S("joint_unknown_body", text("child: rotor,", "child: rotr,"), ["joints.spin_bearing.child", "rotr"],
      fix=r"bodies: stator, rotor|did you mean 'rotor'"),                                            # existing
    S("joint_unknown_parent", text("parent: stator,", "parent: statr,"), ["joints.spin_bearing.parent", "statr"]),
    S("joint_to_itself", text("child: rotor, child_interface: bearing", "child: stator, child_interface: bearing"),
      ["joints.spin_bearing", "stator"], fix=r"two different bodies"),                               # existing
    S("joint_unknown_interface", text("parent_interface: bearing", "parent_interface: baring"),
      ["joints.spin_bearing.parent_interface", "baring"], fix=r"declare|did you mean"),
    S("missing_interface_node", text("interfaces: {bearing: 101}", "interfaces: {bearing: 107}"),
      ["bodies.rotor.interfaces.bearing", "107"], fix=r"use one of its node ids"),                  # existing
    S("interface_without_rotations", text("interfaces: {bearing: 101}", "interfaces: {bearing: 102}"),
      ["bodies.rotor.interfaces.bearing", "102"], fix=r"need 6"),                                    # existing
    S("unreached_body", text("  rotor:\n", "  spare:\n    mass: stator_M.mtx\n    stiffness: stator_K.mtx\n"
                             "    nodes: stator_nodes.txt\n    interfaces: {bearing: 1}\n  rotor:\n"),
      ["spare"], fix=r"add a joint"),                                                                # existing
    S("interface_node_2pow31", text("interfaces: {bearing: 101}", "interfaces: {bearing: 2147483648}"),
      ["bodies.rotor.interfaces.bearing", "2147483648"]),
    S("input_node_2pow31", text("{body: rotor, node: 101,", "{body: rotor, node: 2147483648,"),
      ["inputs.bearing_torque[1]", "2147483648"]),
    S("input_node_missing", text("{body: rotor, node: 101,", "{body: rotor, node: 999,"),
      ["inputs.bearing_torque[1]", "999"]),
    S("input_unknown_body", text("{body: rotor, node: 101,", "{body: rotr, node: 101,"),
      ["inputs.bearing_torque[1].body", "rotr"]),
    S("input_empty", text("  bearing_torque:\n    - {body: stator, node: 1, dof: rz, weight: 1.0}\n"
                          "    - {body: rotor, node: 101, dof: rz, weight: -1.0}", "  bearing_torque: []"),
      ["inputs.bearing_torque"]),
    S("weight_nan", text("weight: -1.0", "weight: .nan"), ["inputs.bearing_torque[1]", "nan"]),
    S("orientation_string", text("axis: [0, 0, 1]}", "axis: [0, 0, 1], orientation: upside-down}"),
      ["joints.spin_bearing.orientation", "upside-down"]),
    S("orientation_not_rotation", text("axis: [0, 0, 1]}", "axis: [0, 0, 1], orientation: [[1, 0, 0], [0, 1, 0], [0, 0, 2]]}"),
      ["joints.spin_bearing.orientation", "re:rotation|orthonormal|orthogonal"]),
    S("orientation_reflection", text("axis: [0, 0, 1]}", "axis: [0, 0, 1], orientation: [[1, 0, 0], [0, 1, 0], [0, 0, -1]]}"),
      ["joints.spin_bearing.orientation", "re:det|reflection|rotation"]),
    S("orientation_wrong_shape", text("axis: [0, 0, 1]}", "axis: [0, 0, 1], orientation: [[1, 0, 0], [0, 1, 0]]}"),
      ["joints.spin_bearing.orientation", "re:3 ?x ?3"]),
    S("axis_zero", text("axis: [0, 0, 1]", "axis: [0, 0, 0]"), ["joints.spin_bearing.axis", "re:zero|0, 0, 0"]),
    S("axis_two_components", text("axis: [0, 0, 1]", "axis: [0, 1]"), ["joints.spin_bearing.axis", "re:\\[0, 1\\]"]),
    S("axis_string", text("axis: [0, 0, 1]", "axis: z"), ["joints.spin_bearing.axis", "z"]),
    # ------------------------------------------------------------------ verify.*
    S("verify_modes_negative", set_key("verify.modes", -5), ["verify.modes", "-5"]),
    S("verify_frequency_points_zero", set_key("verify.frequency_points", 0), ["verify.frequency_points", "0"]),
    S("verify_full_order_string", set_key("verify.full_order", "yes please"), ["verify.full_order", "yes please"]),
    S("verify_frf_floor_positive", set_key("verify.frf_floor_db", 10), ["verify.frf_floor_db", "10"]),
    # ------------------------------------------------------------------ the file itself
    S("invalid_yaml", text("angles: [0, 15, 30, 45, 60, 72]", "angles: [0, 15, 30\n  oops: : ]"),
      ["line "], fix=r"not valid YAML"),                                                             # existing
    S("yaml_alias_bomb", alias_bomb(), ["re:alias|anchor"]),
    S("yaml_too_deep", deep_nesting(40), ["re:deep|nest|level"]),
    S("non_utf8", non_utf8_scene, ["re:UTF-?8"]),
    S("huge_file", huge_scene(), ["re:large|size|MB|MiB|bytes"], timeout=30),
    Case("scene", "scene_missing", None, argv=("info", "{dir}/nothere.yaml"), code=EXIT_INPUT,
         mentions=("nothere.yaml", "not found"), fix=FIX),
    Case("scene", "scene_is_a_folder", make_folder("folder.yaml"), argv=("info", "{dir}/folder.yaml"), code=EXIT_INPUT,
         mentions=("folder.yaml", "re:folder|directory"), fix=FIX),
    # ------------------------------------------------------------------ -scene.<path> overrides
    override("override_damping_not_a_number", ["-scene.damping", "abc"], ["damping", "abc"]),
    override("override_keep_threshold_1.5", ["-scene.reduction.keep_threshold", "1.5"],
             ["reduction.keep_threshold", "1.5"], fix=IN_0_1, out="earlier"),
    override("override_unknown_path", ["-scene.bodiez.x", "1"], ["-scene.bodiez.x", "bodiez"], command="info"),
    override("override_misspelt_key", ["-scene.reduction.momentz", "6"], ["momentz", "moments"], fix=DID_YOU_MEAN,
             command="info"),
    override("override_no_value", ["-scene.angles"], ["-scene.angles"], command="info"),
    override("override_angle_not_a_number", ["-scene.angles", "0,abc"], ["angles", "abc"], command="info"),
    override("override_band_reversed", ["-scene.band", "10,0.01"], ["band", "10"], command="info"),
    override("override_into_a_number", ["-scene.damping.x", "1"], ["-scene.damping.x", "damping"], command="info"),
]
