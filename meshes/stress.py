#!/usr/bin/python3
"""Stress scenes for the failure study (issue 11, item 5): small variants of the Galileo model, each reducible in
seconds, each built to break one assumption a reduction method makes.

    /usr/bin/python3 meshes/stress.py --out DIR            # writes DIR/<name>/scene.yaml for every scene
    /usr/bin/python3 meshes/stress.py --out DIR --list     # the names and what each stresses

| name | what it stresses |
|---|---|
| many-moments | the Galileo scene as it is; the study sweeps c up to 60 (rigid content in the Arnoldi vectors) |
| repeated | a 90-degree-symmetric stator and rotor (four identical booms, EIy = EIz): repeated frequency pairs |
| spread-1e5 | the rotor 1e5 times stiffer than the Galileo rotor: stiffness spread between bodies |
| spread-1e-5 | the rotor 1e5 times softer: its modes drop to the bottom of the band |
| light-mass | the rotor 1e6 times lighter: a nearly singular mass matrix of the system |
| damping-light | modal damping 1e-4: sharp peaks |
| damping-heavy | modal damping 0.2: the band is dominated by off-resonance response |
| far-angle | single-angle model expanded at 0 degrees, used at 90 and 180 degrees |
| mimo-8x8 | 8 inputs and 8 outputs over both bodies |

Each scene has its own folder (body files written with frames.py's writers from galileo/generate.py's builders,
so a scaled body is written, not referenced): a scene is loaded with kryflex like any other.

API: write_stress_scenes(out_dir, names=None) -> {name: scene path}.
"""
import argparse
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "galileo"))
import frames  # noqa: E402  (the writers)
import generate as galileo  # noqa: E402  (the Galileo builders and design tables)

GALILEO_IO = """\
inputs:
  bearing_torque:
    - {body: stator, node: 1, dof: rz, weight: 1.0}
    - {body: rotor, node: 101, dof: rz, weight: -1.0}
outputs:
  pointA_ry: [{body: stator, node: 2, dof: ry}]
"""

# (node, dof) pairs of the 8 x 8 scene: inputs on the rotor's tips and the stator's point A, outputs on the other
# dofs (disjoint from the inputs: no collocated pair whose response is dominated by the static term)
MIMO_INPUTS = [("rotor", 102, "uy"), ("rotor", 103, "uz"), ("rotor", 104, "ux"), ("rotor", 105, "ux"),
               ("rotor", 106, "uy"), ("stator", 2, "ux"), ("stator", 2, "rz"), ("rotor", 101, "rz")]
MIMO_OUTPUTS = [("stator", 2, "ry"), ("stator", 2, "uy"), ("stator", 1, "rx"), ("rotor", 102, "uz"),
                ("rotor", 103, "ux"), ("rotor", 104, "uy"), ("rotor", 105, "uy"), ("rotor", 106, "ux")]

SCENES = {
    "many-moments": "the Galileo scene unchanged; swept to c = 60",
    "repeated": "90-degree-symmetric stator and rotor (four identical booms): repeated frequencies",
    "spread-1e5": "rotor stiffness x 1e5",
    "spread-1e-5": "rotor stiffness x 1e-5",
    "light-mass": "rotor mass x 1e-6 (nearly singular mass)",
    "damping-light": "damping 1e-4",
    "damping-heavy": "damping 0.2",
    "far-angle": "single-angle basis expanded at 0 deg, used at 90 and 180 deg",
    "mimo-8x8": "8 inputs x 8 outputs",
}


def _symmetric_bodies():
    """A stator whose lateral inertias and bending stiffnesses are equal about x and y, and a rotor with four
    identical booms at 90 degrees (EIy = EIz): the system is invariant under a quarter turn about z, so its
    lateral modes come in exactly repeated pairs at every clock angle."""
    nodes = [(1, "bearing", (0.0, 0.0, 0.0), 420.0, np.diag([1000.0, 1000.0, 260.0])),
             (2, "A", (0.0, 0.0, -1.7), 640.0, np.diag([4000.0, 4000.0, 300.0]))]
    beam = dict(galileo.STATOR_BEAM, EIz=galileo.STATOR_BEAM["EIy"])
    Ms, Ks, ts = galileo.build_stator(nodes, beam)
    hub = (101, "hub", (0.0, 0.0, 0.0), 900.0, np.diag([760.0, 760.0, 1100.0]))
    booms = [(102 + k, "boom%d" % (k + 1), (4.0 * np.cos(k * np.pi / 2), 4.0 * np.sin(k * np.pi / 2), 0.3), 40.0,
              5.0e7, 4.0e5, 4.0e5) for k in range(4)]
    Mr, Kr, tr = galileo.build_rotor(hub, booms)
    return (Ms, Ks, ts, [n[1] for n in nodes]), (Mr, Kr, tr, [b[1] for b in [hub] + booms])


def _galileo_bodies():
    Ms, Ks, ts = galileo.build_stator()
    Mr, Kr, tr = galileo.build_rotor()
    return ((Ms, Ks, ts, [n[1] for n in galileo.STATOR_NODES]),
            (Mr, Kr, tr, [galileo.ROTOR_HUB[1]] + [a[1] for a in galileo.ROTOR_APPENDAGES]))


def _write_body(folder, name, body, note):
    M, K, table, names = body
    frames.write_mtx_symmetric(os.path.join(folder, "%s_M.mtx" % name), M, note)
    frames.write_mtx_symmetric(os.path.join(folder, "%s_K.mtx" % name), K, note)
    ids = [i for i, _, _ in table]
    frames.write_nodes(os.path.join(folder, "%s_nodes.txt" % name), ids, [x for _, x, _ in table],
                       [d for _, _, d in table], note + "\nnodes: " + ", ".join("%s %s" % (i, n) for i, n in zip(ids, names)))


def _terms(items, prefix):
    return "".join("  %s%d_%s_%d_%s: [{body: %s, node: %d, dof: %s}]\n" % (prefix, k + 1, b, n, d, b, n, d)
                   for k, (b, n, d) in enumerate(items))


def scene_text(name, io=GALILEO_IO, angles=(0, 15, 30, 45, 60, 72), damping=0.0025, extra=""):
    return """\
# stress scene '{name}' ({what}); generated by meshes/stress.py
name: stress-{name}
bodies:
  stator: {{mass: stator_M.mtx, stiffness: stator_K.mtx, nodes: stator_nodes.txt, interfaces: {{bearing: 1}}}}
  rotor: {{mass: rotor_M.mtx, stiffness: rotor_K.mtx, nodes: rotor_nodes.txt, interfaces: {{bearing: 101}}}}
joints:
  spin_bearing: {{type: revolute, parent: stator, parent_interface: bearing, child: rotor, child_interface: bearing, axis: [0, 0, 1]}}
{io}angles: [{angles}]
band: [0.01, 10.0]
damping: {damping}
accuracy: 0.001
{extra}""".format(name=name, what=SCENES[name], io=io, angles=", ".join("%g" % a for a in angles), damping=damping,
                  extra=extra)


def write_stress_scene(out_dir, name):
    """Writes one stress scene into out_dir/name; returns its scene.yaml path."""
    if name not in SCENES:
        raise ValueError("unknown stress scene %r: one of %s" % (name, ", ".join(SCENES)))
    folder = os.path.join(out_dir, name)
    os.makedirs(folder, exist_ok=True)
    stator, rotor = _symmetric_bodies() if name == "repeated" else _galileo_bodies()
    Mr, Kr, tr, nr = rotor
    if name == "spread-1e5":
        Kr = Kr * 1e5
    elif name == "spread-1e-5":
        Kr = Kr * 1e-5
    elif name == "light-mass":
        Mr = Mr * 1e-6
    note = "stress scene %s (%s); generated by meshes/stress.py" % (name, SCENES[name])
    _write_body(folder, "stator", stator, note)
    _write_body(folder, "rotor", (Mr, Kr, tr, nr), note)
    kwargs = {}
    if name == "repeated":
        # inputs and outputs off the symmetry axis: the bearing torque alone would excite only torsion
        kwargs["io"] = "inputs:\n" + _terms([("rotor", 102, "ux"), ("stator", 2, "uy")], "in") + \
                       "outputs:\n" + _terms([("rotor", 103, "ux"), ("stator", 2, "rx")], "out")
    elif name == "damping-light":
        kwargs["damping"] = 1e-4
    elif name == "damping-heavy":
        kwargs["damping"] = 0.2
    elif name == "far-angle":
        kwargs["angles"] = (0, 90, 180)
        kwargs["extra"] = "reduction: {reduction_angle: 0}\n"
    elif name == "mimo-8x8":
        kwargs["io"] = "inputs:\n" + _terms(MIMO_INPUTS, "in") + "outputs:\n" + _terms(MIMO_OUTPUTS, "out")
    path = os.path.join(folder, "scene.yaml")
    with open(path, "w") as f:
        f.write(scene_text(name, **kwargs))
    return path


def write_stress_scenes(out_dir, names=None):
    return {name: write_stress_scene(out_dir, name) for name in (names or SCENES)}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="folder for the scenes (one subfolder per scene)")
    ap.add_argument("--names", help="comma list of scenes (default: all)")
    ap.add_argument("--list", action="store_true", help="list the scenes and exit")
    args = ap.parse_args()
    if args.list:
        for name, what in SCENES.items():
            print("%-14s %s" % (name, what))
        return
    for name, path in write_stress_scenes(args.out, args.names.split(",") if args.names else None).items():
        print("%s %s" % (name, path))


if __name__ == "__main__":
    main()
