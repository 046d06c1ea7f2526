#!/usr/bin/python3
"""Large 3-D solid FE bodies for kryflex: a bus and a three-boom rotor on a spin bearing.

    /usr/bin/python3 meshes/solid/generate.py --refine 1 -o OUTDIR
    mpiexec -n 2 /usr/bin/python3 meshes/solid/generate.py --refine 6 -o OUTDIR

writes, per body, <body>_K.petsc and <body>_M.petsc (PETSc binary, assembled in
parallel), <body>_nodes.txt (solid 3-dof nodes, then the 6-dof RBE2 nodes),
and spacecraft.yaml, the kryflex scene. Geometry: solid_spacecraft.py;
meshing: solid_grid.py; element: solid_hex8.py; assembly and RBE2
elimination: solid_assembly.py. Dofs per refinement: README.md.

Python: write_spacecraft(out_dir, refine=..., comm=PETSc.COMM_WORLD) -> scene path.
"""
import argparse
import os
import sys
import time
from pathlib import Path

_HERE = Path(__file__).resolve().parent
if str(_HERE) not in sys.path:          # siblings import each other as top-level modules
    sys.path.insert(0, str(_HERE))

import numpy as np                      # noqa: E402
import yaml                             # noqa: E402
from petsc4py import PETSc              # noqa: E402

import solid_assembly                   # noqa: E402
import solid_grid                       # noqa: E402
import solid_spacecraft                 # noqa: E402

# From the convergence study in README.md: at refine 2 (82k dofs) every
# in-band system frequency is within 2.5 % of its converged value.
DEFAULT_REFINE = 2.0
# Scene band (Hz): about 3x the first flexible system frequency (4.7-5.1 Hz
# with the spin angle, README.md); holds the first seven flexible modes.
BAND_HZ = [0.01, 15.0]


def build_bodies(refine=DEFAULT_REFINE):
    """Meshes of the pair: {'bus': GridBody, 'rotor': GridBody}."""
    return {s.name: solid_grid.build_grid(s, refine) for s in (solid_spacecraft.bus_spec(), solid_spacecraft.rotor_spec())}


def node_ids(body):
    """File ids of the RBE2 nodes by patch name (solid nodes are 1..n_solid in file order; these follow)."""
    return {r.name: body.n_solid + 1 + q for q, r in enumerate(body.rbe2)}


def write_nodes(body, path, refine):
    xyz = body.solid_coords()
    ids = np.arange(1, body.n_solid + 1)
    rbe2 = node_ids(body)
    with open(path, "w") as f:
        f.write(f"# kryflex nodes: body '{body.spec.name}', meshes/solid/generate.py --refine {refine:g}\n")
        f.write(f"# {body.n_solid} solid hex8 nodes (ux uy uz), then {body.n_rbe2} RBE2 nodes (ux uy uz rx ry rz) "
                "tied rigidly to their surface patch: " + ", ".join(f"{k} = {v}" for k, v in rbe2.items()) + "\n")
        f.write(f"# E = {body.spec.E:g} Pa, nu = {body.spec.nu:g}, rho = {body.spec.rho:g} kg/m^3, "
                f"{body.n_elements} elements, {body.n_dofs} dofs\n")
        f.write("# id x y z ndof\n")
        rows = np.column_stack([ids, xyz])
        f.write("".join(f"{int(i)} {x:.15g} {y:.15g} {z:.15g} 3\n" for i, x, y, z in rows))
        for r in body.rbe2:
            x, y, z = r.centroid
            f.write(f"{rbe2[r.name]} {x:.15g} {y:.15g} {z:.15g} 6\n")


def write_matrix(mat, path, comm):
    viewer = PETSc.Viewer().createBinary(str(path), "w", comm=comm)
    mat.view(viewer)
    viewer.destroy()
    comm.barrier()
    if comm.getRank() == 0 and os.path.exists(f"{path}.info"):
        os.remove(f"{path}.info")       # only holds load options we do not use


def write_body(body, out_dir, comm, lumped=False, log=None):
    """Assemble and write K, M (one at a time, to bound memory) and the nodes file. Returns file names."""
    name = body.spec.name
    files = {"mass": f"{name}_M.petsc", "stiffness": f"{name}_K.petsc", "nodes": f"{name}_nodes.txt"}
    if comm.getRank() == 0:
        write_nodes(body, Path(out_dir) / files["nodes"], body.refine)
    for kind in ("stiffness", "mass"):
        t0 = time.perf_counter()
        mat = solid_assembly.assemble(body, kind, comm, lumped=lumped)
        t1 = time.perf_counter()
        nnz = int(mat.getInfo(PETSc.Mat.InfoType.GLOBAL_SUM)["nz_used"])
        write_matrix(mat, Path(out_dir) / files[kind], comm)
        mat.destroy()
        if log:
            log(f"  {name} {kind}: nnz {nnz}, assembled in {t1 - t0:.2f} s, written in {time.perf_counter() - t1:.2f} s")
    return files


def scene_dict(bodies, files, refine, lumped):
    bus, rotor = bodies["bus"], bodies["rotor"]
    bus_ids, rotor_ids = node_ids(bus), node_ids(rotor)
    corner = bus.nearest_solid_node(bus.spec.points["corner"]) + 1
    body_entry = lambda b, ids: {"mass": files[b]["mass"], "stiffness": files[b]["stiffness"],
                                 "nodes": files[b]["nodes"], "interfaces": {"bearing": ids["bearing"]}}
    return {
        "name": f"spacecraft_solid_r{refine:g}" + ("_lumped" if lumped else ""),
        "bodies": {"bus": body_entry("bus", bus_ids), "rotor": body_entry("rotor", rotor_ids)},
        "joints": {"spin_bearing": {"type": "revolute", "parent": "bus", "parent_interface": "bearing",
                                    "child": "rotor", "child_interface": "bearing", "axis": [0, 0, 1]}},
        "inputs": {
            "bearing_torque": [{"body": "bus", "node": bus_ids["bearing"], "dof": "rz", "weight": 1.0},
                               {"body": "rotor", "node": rotor_ids["bearing"], "dof": "rz", "weight": -1.0}],
            "tip_force": [{"body": "rotor", "node": rotor_ids["tip"], "dof": "uz", "weight": 1.0}],
        },
        "outputs": {
            "pointA_ry": [{"body": "bus", "node": bus_ids["pointA"], "dof": "ry"}],
            "pointA_rx": [{"body": "bus", "node": bus_ids["pointA"], "dof": "rx"}],
            "corner_uy": [{"body": "bus", "node": corner, "dof": "uy"}],
        },
        "angles": [0, 30, 60, 90],
        "band": list(BAND_HZ),
        "damping": 0.0025,
        "accuracy": 0.05,
        "reduction": {"moments": 10, "output_blocks": 1, "importance": "h2", "keep_threshold": 0.05,
                      "reduction_angle": "auto"},
    }


def write_spacecraft(out_dir, refine=DEFAULT_REFINE, comm=None, lumped=False, log=None):
    """Generate the bus/rotor pair at refinement `refine` into out_dir; returns the scene file path.

    Collective over comm (default PETSc.COMM_WORLD): every rank meshes the (cheap)
    geometry, assembles its rows of K and M, and writes through PETSc's binary viewer."""
    comm = comm or PETSc.COMM_WORLD
    out_dir = Path(out_dir)
    if comm.getRank() == 0:
        out_dir.mkdir(parents=True, exist_ok=True)
    comm.barrier()
    bodies = build_bodies(refine)
    files = {}
    for name, body in bodies.items():
        if log:
            log(f"{name}: {body.n_dofs} dofs ({body.n_solid} solid nodes + {body.n_rbe2} RBE2 nodes), "
                f"{body.n_elements} elements")
        files[name] = write_body(body, out_dir, comm, lumped, log)
    scene = out_dir / "spacecraft.yaml"
    if comm.getRank() == 0:
        header = (f"# Generated by meshes/solid/generate.py --refine {refine:g}"
                  f"{' --lumped-mass' if lumped else ''}: bus + three-boom rotor, hex8 solids,\n"
                  f"# RBE2 interface nodes; total {sum(b.n_dofs for b in bodies.values())} dofs. See meshes/solid/README.md.\n")
        with open(scene, "w") as f:
            f.write(header)
            yaml.safe_dump(scene_dict(bodies, files, refine, lumped), f, sort_keys=False, default_flow_style=None)
    comm.barrier()
    return str(scene)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--refine", type=float, default=DEFAULT_REFINE,
                   help=f"mesh refinement: element sizes / refine; pair dofs 13,518 at 1, 82,140 at 2, "
                        f"1,055,010 at 5 (README.md); default {DEFAULT_REFINE:g}")
    p.add_argument("-o", "--output", required=True, help="output directory (created)")
    p.add_argument("--lumped-mass", action="store_true", help="row-sum lumped instead of consistent mass")
    args = p.parse_args(argv)
    comm = PETSc.COMM_WORLD
    say = (lambda s: print(s, flush=True)) if comm.getRank() == 0 else None
    t0 = time.perf_counter()
    scene = write_spacecraft(args.output, args.refine, comm, args.lumped_mass, log=say)
    if say:
        say(f"scene {scene}; {comm.getSize()} rank(s), elapsed {time.perf_counter() - t0:.2f} s")


if __name__ == "__main__":
    main()
