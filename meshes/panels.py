#!/usr/bin/python3
"""A modally dense, articulated spacecraft scene of any size (a few thousand to 2M+ dofs): bus, two solar arrays, boom.

The way large structures are: a compact bus, two large thin solar-array panels on revolute joints (the solar-array
drives, both at one angle: they track the sun together), and a long boom (a square truss) on a fixed joint. The
panels are flat beam lattices (meshes/frames.py's beam element, reused), so they factor with 2-D-like fill and a
2M-dof scene fits one 24 GiB machine; the bus is a frames.py box-lattice body.

The physics does not depend on the mesh: the panels are sized as 10 m x 3 m honeycomb plates (bending stiffness D,
areal mass mu, membrane stiffness) whose beams stand for strips of the lattice spacing, so refining the lattice
converges the same structure and the band [0.01, BAND_TOP_HZ] Hz holds 100-200 flexible modes at every size (a
plate has about A / 2 sqrt(mu / D) modes per Hz). Outputs read accelerations at the array tips and the boom tip (an
accelerometer: every mode in the band counts about equally, not just the lowest ones) and the bus rotation.

CLI:
    /usr/bin/python3 meshes/panels.py --dofs 200000 --out out/panels200k

API:
    write_panel_scene(out_dir, total_dofs, seed=0, fmt="auto", nangles=2) -> scene_path
    panel_body(nx, ny, width, span) -> frames.FrameBody    (flat lattice in the x-y plane, span along y)
    boom_body(nseg, length, side) -> frames.FrameBody      (2 x 2 truss along -z)
"""
import argparse
import os
import sys

import numpy as np
import scipy.sparse as sp

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import frames  # noqa: E402

BAND_TOP_HZ = 30.0
PANEL_SPAN, PANEL_WIDTH = 10.0, 3.0      # m, one solar-array wing
PANEL_D = 200.0          # N m: bending stiffness of the honeycomb panel (per unit width)
PANEL_MU = 2.0           # kg / m^2
PANEL_EM = 2.0e7         # N / m: membrane stiffness (face sheets E t)
BOOM_LENGTH, BOOM_SIDE = 12.0, 0.3
BUS_SIDE = 2.0
CHUNK = 200000           # elements per assembly chunk: bounds the (ne, 12, 12) temporaries at 2M dofs


def _assemble_beams(xyz, edges, EA, GJ, EIy, EIz, m, polar_r2):
    """K and consistent M of 6-dof beams `edges` over nodes `xyz`, in chunks (frames.py's element)."""
    n = 6 * len(xyz)
    K = sp.csr_matrix((n, n))
    M = sp.csr_matrix((n, n))
    for s in range(0, len(edges), CHUNK):
        e = edges[s:s + CHUNK]
        sl = slice(s, s + len(e))
        fr, L = frames.beam_frames(xyz[e[:, 0]], xyz[e[:, 1]])
        dofs = np.concatenate([6 * e[:, :1] + np.arange(6), 6 * e[:, 1:] + np.arange(6)], axis=1)
        K = K + frames.assemble(frames.to_global(frames.beam_local_stiffness(L, EA[sl], GJ[sl], EIy[sl], EIz[sl]), fr),
                                dofs, n)
        M = M + frames.assemble(frames.to_global(frames.beam_local_mass(L, m[sl] * L, polar_r2[sl]), fr), dofs, n)
    return M.tocsr(), K.tocsr()


def panel_body(nx, ny, width=PANEL_WIDTH, span=PANEL_SPAN):
    """A flat nx x ny lattice in the x-y plane (x across the width, centred; y along the span from 0), beams along x
    and y plus one diagonal per cell (in-plane shear), each standing for a strip of the spacing: out-of-plane EI =
    D h, torsion GJ = D h, membrane EA = Em h, mass mu h per unit length (a node carries mu hx hy)."""
    if nx < 2 or ny < 2:
        raise ValueError("panel_body: a panel needs at least 2 x 2 nodes")
    hx, hy = width / (nx - 1), span / (ny - 1)
    # frames.lattice_edges on an (nx, 1, ny) lattice: x edges, "z" edges (here y) and the x-"z" diagonal
    edges = frames.lattice_edges((nx, 1, ny), nx * ny)
    j, i = np.divmod(np.arange(nx * ny), nx)
    xyz = np.stack([i * hx - 0.5 * width, j * hy, np.zeros(nx * ny)], axis=1)
    d = xyz[edges[:, 1]] - xyz[edges[:, 0]]
    along_x = np.abs(d[:, 1]) < 1e-12 * span
    along_y = np.abs(d[:, 0]) < 1e-12 * width
    diag = ~(along_x | along_y)
    strip = np.where(along_x, hy, hx)                      # the strip width a beam stands for
    EA = PANEL_EM * strip
    EIy = PANEL_D * strip                                  # out of plane (local z is the plate normal)
    EIz = PANEL_EM * strip**3 / 12.0                       # in plane
    GJ = PANEL_D * strip
    mu = PANEL_MU * strip / 2.0                            # x and y beams share the areal mass
    polar_r2 = strip**2 / 12.0
    # diagonals: shear stiffness only (a tenth of the membrane), little bending, little mass
    h = np.hypot(hx, hy)
    EA = np.where(diag, 0.1 * PANEL_EM * h, EA)
    EIy = np.where(diag, 0.01 * PANEL_D * h, EIy)
    EIz = np.where(diag, 0.01 * PANEL_EM * h**3 / 12.0, EIz)
    GJ = np.where(diag, 0.01 * PANEL_D * h, GJ)
    mu = np.where(diag, 0.01 * PANEL_MU * h, mu)
    polar_r2 = np.where(diag, h**2 / 12.0, polar_r2)
    M, K = _assemble_beams(xyz, edges, EA, GJ, EIy, EIz, mu, polar_r2)
    return frames.FrameBody(xyz=xyz, M=M, K=K, shape=(nx, ny, 1), ids=np.arange(1, nx * ny + 1))


def boom_body(nseg, length=BOOM_LENGTH, side=BOOM_SIDE):
    """A 2 x 2 square truss of nseg + 1 bays along -z from z = 0 (frames.lattice_edges: edges and face diagonals),
    aluminium tubes (radius 15 mm, wall 1.5 mm)."""
    nseg = max(1, int(nseg))
    shape = (2, 2, nseg + 1)
    nn = 4 * (nseg + 1)
    edges = frames.lattice_edges(shape, nn)
    k, r = np.divmod(np.arange(nn), 4)
    jj, ii = np.divmod(r, 2)
    xyz = np.stack([(ii - 0.5) * side, (jj - 0.5) * side, -k * length / nseg], axis=1)
    E, G, rho, rad, wall = 70e9, 27e9, 2700.0, 0.015, 0.0015
    area = np.pi * (rad**2 - (rad - wall) ** 2)
    inertia = 0.25 * np.pi * (rad**4 - (rad - wall) ** 4)
    ne = len(edges)
    full = np.ones(ne)
    M, K = _assemble_beams(xyz, edges, E * area * full, G * 2 * inertia * full, E * inertia * full, E * inertia * full,
                           rho * area * full, 2 * inertia / area * full)
    return frames.FrameBody(xyz=xyz, M=M, K=K, shape=shape, ids=np.arange(1, nn + 1))


def split(total_dofs):
    """Lattice sizes for about total_dofs: bus ~3 % (at most 60,000 dofs), boom ~3 %, the rest two equal panels of
    aspect span / width. Returns (bus_dofs, boom_segments, (nx, ny))."""
    total_dofs = int(total_dofs)
    if total_dofs < 1000:
        raise ValueError("--dofs %d is too small for a bus, two wings and a boom: give at least 1000" % total_dofs)
    bus = int(min(60000, max(300, 0.03 * total_dofs)))
    nseg = max(8, int(0.03 * total_dofs / 24))
    panel_nodes = (total_dofs - bus - 24 * (nseg + 1)) / 12.0
    nx = max(3, int(round(np.sqrt(panel_nodes * PANEL_WIDTH / PANEL_SPAN))))
    ny = max(4, int(round(panel_nodes / nx)))
    return bus, nseg, (nx, ny)


def write_panel_scene(out_dir, total_dofs, seed=0, fmt="auto", nangles=2):
    """Writes the bus, the two wings and the boom and a scene YAML joining them; returns the scene file's path.

    Joints: wing_pos / wing_neg revolute about the y axis (the solar-array drives, the span direction) between the
    bus's +y / -y face centre and the wing's root (middle of its inner edge); boom fixed under the bus. angles: the
    two drives at one angle, nangles configurations (0, 45, ... degrees). fmt as in frames.py (auto: PETSc binary
    above frames.MTX_MAX_DOFS dofs per body).
    """
    import yaml

    bus_dofs, nseg, (nx, ny) = split(total_dofs)     # checks total_dofs before anything is written
    rng = np.random.default_rng(seed)
    os.makedirs(out_dir, exist_ok=True)
    bus = frames.random_frame_body(bus_dofs, rng, spacing=BUS_SIDE / max(1.0, (bus_dofs / 6 / 2.5) ** (1 / 3)))
    bus.xyz -= bus.xyz.mean(axis=0)
    wing = panel_body(nx, ny)
    boom = boom_body(nseg)
    bodies = {"bus": bus, "wing_pos": wing, "wing_neg": wing, "boom": boom}
    if fmt == "auto":
        fmt = "mtx" if max(b.ndofs for b in bodies.values()) <= frames.MTX_MAX_DOFS else "petsc"

    def nearest(body, point):
        return int(body.ids[np.argmin(np.linalg.norm(body.xyz - point, axis=1))])

    top = bus.xyz.max(axis=0)
    low = bus.xyz.min(axis=0)
    root = nearest(wing, [0.0, 0.0, 0.0])                       # middle of the inner edge
    tip = nearest(wing, [0.5 * PANEL_WIDTH, PANEL_SPAN, 0.0])   # an outer corner
    interfaces = {
        "bus": {"to_wing_pos": nearest(bus, [0.0, top[1], 0.0]), "to_wing_neg": nearest(bus, [0.0, low[1], 0.0]),
                "to_boom": nearest(bus, [0.0, 0.0, low[2]])},
        "wing_pos": {"root": root}, "wing_neg": {"root": root},
        "boom": {"base": nearest(boom, [0.0, 0.0, 0.0])},
    }
    # the -y wing is the +y one turned half a turn about z (its span runs along -y)
    half_turn = [[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]]
    joints = {
        "wing_pos": {"type": "revolute", "parent": "bus", "parent_interface": "to_wing_pos", "child": "wing_pos",
                     "child_interface": "root", "axis": [0.0, 1.0, 0.0]},
        "wing_neg": {"type": "revolute", "parent": "bus", "parent_interface": "to_wing_neg", "child": "wing_neg",
                     "child_interface": "root", "axis": [0.0, -1.0, 0.0], "orientation": half_turn},
        "boom": {"type": "fixed", "parent": "bus", "parent_interface": "to_boom", "child": "boom",
                 "child_interface": "base"},
    }
    scene_bodies = {}
    written = {}
    for name, body in bodies.items():
        note = "meshes/panels.py %s: %d dofs, lattice %s, total_dofs %d" % (name, body.ndofs, body.shape, total_dofs)
        if id(body) in written:      # the two wings share their files
            files = written[id(body)]
        else:
            files = {"mass": frames.write_matrix(out_dir, name + "_M", body.M, fmt, note),
                     "stiffness": frames.write_matrix(out_dir, name + "_K", body.K, fmt, note),
                     "nodes": name + "_nodes.txt"}
            frames.write_nodes(os.path.join(out_dir, name + "_nodes.txt"), body.ids, body.xyz,
                               np.full(len(body.ids), 6), note)
            written[id(body)] = files
        scene_bodies[name] = dict(files, interfaces=interfaces[name])

    boom_tip = nearest(boom, [0.5 * BOOM_SIDE, 0.5 * BOOM_SIDE, -BOOM_LENGTH])
    bus_node = interfaces["bus"]["to_boom"]
    inputs = {
        # attitude control torque on the bus, about a skew axis
        "bus_torque": [{"body": "bus", "node": bus_node, "dof": d, "weight": w}
                       for d, w in zip(("rx", "ry", "rz"), (0.6, 0.48, 0.64))],
        # a disturbance force at the +y wing's outer corner (out of plane, a little in plane)
        "wing_force": [{"body": "wing_pos", "node": tip, "dof": "uz", "weight": 1.0},
                       {"body": "wing_pos", "node": tip, "dof": "ux", "weight": 0.2}],
    }
    outputs = {
        "bus_pointing": [{"body": "bus", "node": bus_node, "dof": d, "weight": w}
                         for d, w in zip(("rx", "ry", "rz"), (0.48, -0.6, 0.64))],
        "wing_tip_acc": [{"body": "wing_neg", "node": tip, "dof": "uz", "weight": 1.0, "quantity": "acceleration"}],
        "boom_tip_acc": [{"body": "boom", "node": boom_tip, "dof": d, "weight": w, "quantity": "acceleration"}
                         for d, w in zip(("ux", "uy"), (0.8, 0.6))],
    }
    angles = [[45.0 * k, 45.0 * k] for k in range(nangles)]
    scene = {
        "name": os.path.basename(os.path.normpath(out_dir)) or "panels",
        "bodies": scene_bodies,
        "joints": joints,
        "inputs": inputs,
        "outputs": outputs,
        "angles": angles,
        "band": [0.01, BAND_TOP_HZ],
        "damping": 0.005,
        "accuracy": 0.05,
        "reduction": {"moments": "auto", "moments_max": 100, "importance": "h2", "keep_threshold": 0.05},
    }
    path = os.path.join(out_dir, "scene.yaml")
    with open(path, "w") as f:
        f.write("# generated by meshes/panels.py: total_dofs=%d seed=%d; bus %d, wings 2 x %d (%d x %d), boom %d dofs\n"
                % (total_dofs, seed, bus.ndofs, wing.ndofs, nx, ny, boom.ndofs))
        yaml.safe_dump(scene, f, sort_keys=False, default_flow_style=None, width=120)
    return path


def main():
    ap = argparse.ArgumentParser(description="Write a modally dense spacecraft scene: bus, two solar-array wings on "
                                             "revolute drives, a boom.")
    ap.add_argument("--dofs", type=int, required=True, help="total dofs over all bodies (approximate)")
    ap.add_argument("--seed", type=int, default=0, help="the bus lattice's jitter")
    ap.add_argument("--angles", type=int, default=2, help="configurations (both drives at 0, 45, ... degrees)")
    ap.add_argument("--format", default="auto", choices=["auto", "mtx", "petsc"],
                    help="matrix files; auto = .mtx up to %d dofs per body, PETSc binary above" % frames.MTX_MAX_DOFS)
    ap.add_argument("--out", required=True, help="output directory")
    args = ap.parse_args()
    if args.angles < 1:
        ap.error("--angles %d: give at least 1 configuration" % args.angles)
    try:
        split(args.dofs)
    except ValueError as e:
        ap.error(str(e))          # exit 2, one line, before anything is written
    print(write_panel_scene(args.out, args.dofs, args.seed, args.format, args.angles))


if __name__ == "__main__":
    main()
