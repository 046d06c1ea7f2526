#!/usr/bin/python3
"""Random free-free 3-D beam-frame bodies and articulated test scenes for kryflex.

A body is a lattice of 6-dof nodes joined by Euler-Bernoulli beams (edges of a
slightly jittered box lattice plus face diagonals), so it is rigidly connected:
exactly 6 zero-frequency modes, no mechanisms.  Everything is vectorized over
elements, so a 100,000-dof body takes a few seconds.

Also the beam element itself (stiffness, consistent mass, static condensation
of a pinned end), shared with meshes/galileo/generate.py.

CLI:
    /usr/bin/python3 meshes/frames.py --dofs 3000 --bodies 3 --seed 1 --out out/frames3k

API:
    write_random_scene(out_dir, total_dofs, nbodies=3, ninputs=3, noutputs=2,
                       seed=0, fixed_joint=False, fmt="auto") -> scene_path
    random_frame_body(ndofs, rng) -> FrameBody
"""
import argparse
import os
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

DOF_NAMES = ("ux", "uy", "uz", "rx", "ry", "rz")

# Bodies larger than this are written as PETSc binary (Matrix Market text gets slow and big).
MTX_MAX_DOFS = 30000


# ----------------------------------------------------------------------------- beam element

def beam_frames(x1, x2, ref=None):
    """Rotation matrices (ne, 3, 3) whose rows are the local x, y, z axes in global coordinates.

    Local x runs from node 1 to node 2.  Local y is perpendicular to x and to `ref`
    (default: global z, or global x for beams nearly parallel to z), local z = x cross y.
    """
    x1 = np.atleast_2d(np.asarray(x1, float))
    x2 = np.atleast_2d(np.asarray(x2, float))
    d = x2 - x1
    length = np.linalg.norm(d, axis=1)
    if np.any(length <= 0):
        raise ValueError("beam_frames: a beam has zero length (coincident end nodes); move one node")
    ex = d / length[:, None]
    if ref is None:
        ref = np.tile([0.0, 0.0, 1.0], (len(ex), 1))
        steep = np.abs(ex[:, 2]) > 0.9
        ref[steep] = [1.0, 0.0, 0.0]
    ref = np.broadcast_to(np.asarray(ref, float), ex.shape)
    ey = np.cross(ref, ex)
    ny = np.linalg.norm(ey, axis=1)
    if np.any(ny < 1e-8):
        raise ValueError("beam_frames: orientation vector parallel to a beam axis; pass another ref")
    ey /= ny[:, None]
    ez = np.cross(ex, ey)
    return np.stack([ex, ey, ez], axis=1), length


def beam_local_stiffness(L, EA, GJ, EIy, EIz):
    """Euler-Bernoulli 3-D beam stiffness in local axes, (ne, 12, 12); dofs u v w rx ry rz per node."""
    L, EA, GJ, EIy, EIz = np.broadcast_arrays(*(np.atleast_1d(np.asarray(v, float)) for v in (L, EA, GJ, EIy, EIz)))
    k = np.zeros((len(L), 12, 12))
    _put2(k, (0, 6), EA / L)
    _put2(k, (3, 9), GJ / L)
    # bending in the local x-y plane (v, rz): v' = +rz
    _put4(k, (1, 5, 7, 11), EIz / L**3, _bend_k(L, +1))
    # bending in the local x-z plane (w, ry): w' = -ry, hence the sign flips
    _put4(k, (2, 4, 8, 10), EIy / L**3, _bend_k(L, -1))
    return k


def beam_local_mass(L, m, polar_r2):
    """Consistent beam mass in local axes, (ne, 12, 12): m = rho A L, polar_r2 = (Iy + Iz) / A."""
    L, m, polar_r2 = np.broadcast_arrays(*(np.atleast_1d(np.asarray(v, float)) for v in (L, m, polar_r2)))
    mm = np.zeros((len(L), 12, 12))
    _put2(mm, (0, 6), m / 6.0, diag=2.0, off=1.0)
    _put2(mm, (3, 9), m * polar_r2 / 6.0, diag=2.0, off=1.0)
    _put4(mm, (1, 5, 7, 11), m / 420.0, _bend_m(L, +1))
    _put4(mm, (2, 4, 8, 10), m / 420.0, _bend_m(L, -1))
    return mm


def to_global(local, frames):
    """T^T A T for every element, T = blockdiag(R, R, R, R) (R rows = local axes)."""
    ne = len(frames)
    t = np.zeros((ne, 12, 12))
    for b in range(4):
        t[:, 3 * b:3 * b + 3, 3 * b:3 * b + 3] = frames
    return np.einsum("eji,ejk,ekl->eil", t, local, t, optimize=True)


def condense(k, drop):
    """Static condensation of the dofs `drop` out of element matrices k (ne, n, n): K_aa - K_ab K_bb^-1 K_ba.

    Used where a beam ends at a 3-dof node: its end rotations are free (pinned end), not held.
    """
    n = k.shape[-1]
    keep = np.setdiff1d(np.arange(n), drop)
    kaa = k[:, keep][:, :, keep]
    kab = k[:, keep][:, :, drop]
    kbb = k[:, drop][:, :, drop]
    return kaa - kab @ np.linalg.solve(kbb, np.swapaxes(kab, 1, 2))


def assemble(elem, elem_dofs, n):
    """Sum element matrices (ne, p, p) into an n x n CSR matrix; elem_dofs (ne, p) global dof numbers."""
    p = elem_dofs.shape[1]
    rows = np.repeat(elem_dofs, p, axis=1).ravel()
    cols = np.tile(elem_dofs, (1, p)).ravel()
    a = sp.csr_matrix((elem.ravel(), (rows, cols)), shape=(n, n))
    a.sum_duplicates()
    return 0.5 * (a + a.T).tocsr()   # exact symmetry, whatever the element round-off


def _bend_k(L, s):
    z = np.zeros_like(L)
    return np.array([[12 + z, s * 6 * L, -12 + z, s * 6 * L],
                     [s * 6 * L, 4 * L**2, -s * 6 * L, 2 * L**2],
                     [-12 + z, -s * 6 * L, 12 + z, -s * 6 * L],
                     [s * 6 * L, 2 * L**2, -s * 6 * L, 4 * L**2]])


def _bend_m(L, s):
    z = np.zeros_like(L)
    return np.array([[156 + z, s * 22 * L, 54 + z, -s * 13 * L],
                     [s * 22 * L, 4 * L**2, s * 13 * L, -3 * L**2],
                     [54 + z, s * 13 * L, 156 + z, -s * 22 * L],
                     [-s * 13 * L, -3 * L**2, -s * 22 * L, 4 * L**2]])


def _put2(a, idx, scale, diag=1.0, off=-1.0):
    i, j = idx
    a[:, i, i] += diag * scale
    a[:, j, j] += diag * scale
    a[:, i, j] += off * scale
    a[:, j, i] += off * scale


def _put4(a, idx, scale, block):
    for r, i in enumerate(idx):
        for c, j in enumerate(idx):
            a[:, i, j] += scale * block[r, c]


# ----------------------------------------------------------------------------- lattice body

@dataclass
class FrameBody:
    xyz: np.ndarray            # (nnodes, 3)
    M: sp.csr_matrix
    K: sp.csr_matrix
    shape: tuple               # lattice (nx, ny, nz); the last level may be partial
    ids: np.ndarray = field(default=None)   # node ids written to the nodes file (1-based)

    @property
    def ndofs(self):
        return self.K.shape[0]


def lattice_shape(nnodes):
    """A compact (nx, ny, nz) lattice holding nnodes nodes, nz >= nx, ny: roughly 1 x 1 x 2.5 towers.

    Compact keeps K well conditioned (a long thin chain would have a tiny first frequency).
    """
    if nnodes < 2:
        raise ValueError("a frame body needs at least 2 nodes (12 dofs)")
    side = max(1, int(round((nnodes / 2.5) ** (1.0 / 3.0))))
    nx = ny = side
    nz = -(-nnodes // (nx * ny))
    return nx, ny, nz


def lattice_edges(shape, nnodes):
    """Beam connectivity of the first nnodes nodes of an (nx, ny, nz) lattice numbered x fastest.

    Edges along x, y, z plus one diagonal in each x-z and y-z face: a rigidly connected frame.
    """
    nx, ny, nz = shape
    idx = np.arange(nx * ny * nz).reshape(nz, ny, nx)   # idx[k, j, i]
    pairs = []
    for a, b in ((idx[:, :, :-1], idx[:, :, 1:]),      # x
                 (idx[:, :-1, :], idx[:, 1:, :]),      # y
                 (idx[:-1, :, :], idx[1:, :, :]),      # z
                 (idx[:-1, :, :-1], idx[1:, :, 1:]),   # x-z diagonal
                 (idx[:-1, :-1, :], idx[1:, 1:, :])):  # y-z diagonal
        pairs.append(np.stack([a.ravel(), b.ravel()], axis=1))
    e = np.concatenate(pairs)
    return e[(e[:, 0] < nnodes) & (e[:, 1] < nnodes)]


def random_frame_body(ndofs, rng, spacing=1.0, jitter=0.15):
    """A free-free lattice frame with ceil(ndofs / 6) nodes: jittered geometry, random tube sections.

    Aluminium-like material; section properties vary by +-30 % per beam so no two bodies are alike,
    but stay within one order of magnitude so K and M are well conditioned.
    """
    nnodes = max(2, -(-int(ndofs) // 6))
    shape = lattice_shape(nnodes)
    nx, ny, nz = shape
    k, j, i = np.meshgrid(np.arange(nz), np.arange(ny), np.arange(nx), indexing="ij")
    grid = np.stack([i.ravel(), j.ravel(), k.ravel()], axis=1)[:nnodes].astype(float)
    h = spacing * rng.uniform(0.8, 1.2, size=3)
    xyz = grid * h + rng.uniform(-jitter, jitter, size=(nnodes, 3)) * h
    edges = lattice_edges(shape, nnodes)
    ne = len(edges)

    E, G, rho = 70e9, 27e9, 2700.0
    radius = 0.03 * rng.uniform(0.7, 1.3, size=ne)
    wall = 0.2 * radius
    area = np.pi * (radius**2 - (radius - wall) ** 2)
    inertia = 0.25 * np.pi * (radius**4 - (radius - wall) ** 4)
    aniso = rng.uniform(0.8, 1.25, size=ne)                # slightly elliptic tubes
    EIy, EIz, GJ = E * inertia * aniso, E * inertia / aniso, G * 2 * inertia

    frames, L = beam_frames(xyz[edges[:, 0]], xyz[edges[:, 1]])
    dofs = np.concatenate([6 * edges[:, :1] + np.arange(6), 6 * edges[:, 1:] + np.arange(6)], axis=1)
    n = 6 * nnodes
    K = assemble(to_global(beam_local_stiffness(L, E * area, GJ, EIy, EIz), frames), dofs, n)

    # Mass: half consistent, half lumped (translational mass plus a small rotary inertia),
    # "consistent-ish" and positive definite even where a node has a single beam.
    m = rho * area * L
    polar_r2 = 2 * inertia / area
    Mc = assemble(to_global(beam_local_mass(L, m, polar_r2), frames), dofs, n)
    lumped = np.zeros((nnodes, 6))
    rot = m * (L**2 / 12.0 + polar_r2) / 2.0
    for end in (0, 1):
        np.add.at(lumped[:, :3], edges[:, end], (m / 2.0)[:, None])
        np.add.at(lumped[:, 3:], edges[:, end], (rot / 2.0)[:, None])
    M = (0.5 * Mc + 0.5 * sp.diags(lumped.ravel())).tocsr()
    return FrameBody(xyz=xyz, M=M, K=K, shape=shape, ids=np.arange(1, nnodes + 1))


# ----------------------------------------------------------------------------- writers

def write_mtx_symmetric(path, a, comment=""):
    """Matrix Market 'coordinate real symmetric' (lower triangle, 1-based), 17 significant digits."""
    low = sp.tril(sp.csr_matrix(a)).tocoo()
    with open(path, "w") as f:
        f.write("%%MatrixMarket matrix coordinate real symmetric\n")
        for line in comment.splitlines():
            f.write("% " + line + "\n")
        f.write(f"{a.shape[0]} {a.shape[1]} {low.nnz}\n")
        data = np.column_stack([low.row + 1, low.col + 1, low.data])
        np.savetxt(f, data, fmt=["%d", "%d", "%.17g"])


def write_petsc_binary(path, a):
    """PETSc binary AIJ matrix (read back with MatLoad / KFMatLoadFile)."""
    from petsc4py import PETSc
    a = sp.csr_matrix(a)
    a.sort_indices()
    mat = PETSc.Mat().createAIJ(size=a.shape, csr=(a.indptr.astype(PETSc.IntType), a.indices.astype(PETSc.IntType), a.data),
                                comm=PETSc.COMM_SELF)
    mat.assemble()
    viewer = PETSc.Viewer().createBinary(path, "w", comm=PETSc.COMM_SELF)
    mat.view(viewer)
    viewer.destroy()
    mat.destroy()
    info = path + ".info"          # PETSc writes an options file beside the matrix; it is not needed
    if os.path.exists(info):
        os.remove(info)


def write_nodes(path, ids, xyz, ndof, comment=""):
    with open(path, "w") as f:
        for line in comment.splitlines():
            f.write("# " + line + "\n")
        f.write("# id x y z ndof\n")
        for i, (x, y, z), d in zip(ids, xyz, ndof):
            f.write(f"{int(i)} {x:.17g} {y:.17g} {z:.17g} {int(d)}\n")


def write_matrix(out_dir, stem, a, fmt, comment=""):
    """Writes stem.mtx or stem.petsc; returns the file name (relative to out_dir)."""
    if fmt == "auto":
        fmt = "mtx" if a.shape[0] <= MTX_MAX_DOFS else "petsc"
    if fmt == "mtx":
        name = stem + ".mtx"
        write_mtx_symmetric(os.path.join(out_dir, name), a, comment)
    elif fmt == "petsc":
        name = stem + ".petsc"
        write_petsc_binary(os.path.join(out_dir, name), a)
    else:
        raise ValueError(f"unknown matrix format {fmt!r}: use 'mtx', 'petsc' or 'auto'")
    return name


# ----------------------------------------------------------------------------- scenes

def random_axis(rng):
    """A random unit vector with every component at least 0.2 in size: never near a coordinate axis."""
    while True:
        v = rng.normal(size=3)
        v /= np.linalg.norm(v)
        if np.all(np.abs(v) > 0.2):
            return v


def split_dofs(total_dofs, nbodies, rng):
    """Body sizes (multiples of 6, at least 12) adding up to about total_dofs, unequal on purpose."""
    weights = rng.uniform(0.6, 1.4, size=nbodies)
    sizes = np.maximum(12, 6 * np.round(total_dofs * weights / weights.sum() / 6.0)).astype(int)
    return [int(s) for s in sizes]


def write_random_scene(out_dir, total_dofs, nbodies=3, ninputs=3, noutputs=2, seed=0, fixed_joint=False,
                       fmt="auto", nangles=3):
    """Writes nbodies random frame bodies and a scene YAML joining them in a random tree.

    fmt: 'mtx', 'petsc' or 'auto' (Matrix Market unless a body exceeds MTX_MAX_DOFS dofs).
    Joints are revolute about random non-axis-aligned axes; with fixed_joint=True the last joint is fixed
    (with a random R0 orientation).  Inputs are point forces/moments in random directions, outputs
    weighted readings, spread over different bodies.  `angles` lists nangles configurations, each a list
    with one angle (degrees) per revolute joint in joint order.  Returns the scene file path.
    """
    import yaml

    if nbodies < 1:
        raise ValueError("nbodies must be at least 1")
    rng = np.random.default_rng(seed)
    os.makedirs(out_dir, exist_ok=True)
    names = [f"body{b}" for b in range(nbodies)]
    sizes = split_dofs(total_dofs, nbodies, rng)
    bodies = [random_frame_body(n, rng) for n in sizes]
    if fmt == "auto":   # one format per scene: PETSc binary as soon as one body is too big for text
        fmt = "mtx" if max(sizes) <= MTX_MAX_DOFS else "petsc"
    parents = [None] + [int(rng.integers(0, b)) for b in range(1, nbodies)]

    # Interface nodes: a child hangs from a node near the top of its parent by a node near its own bottom.
    interfaces = {b: {} for b in range(nbodies)}
    joints = {}
    for c in range(1, nbodies):
        p = parents[c]
        jname = f"joint{c}"
        top = np.argsort(-bodies[p].xyz[:, 2])[: max(1, len(bodies[p].xyz) // 4)]
        bottom = np.argsort(bodies[c].xyz[:, 2])[: max(1, len(bodies[c].xyz) // 4)]
        interfaces[p][f"to_{names[c]}"] = int(bodies[p].ids[rng.choice(top)])
        interfaces[c]["base"] = int(bodies[c].ids[rng.choice(bottom)])
        joint = {"type": "revolute", "parent": names[p], "parent_interface": f"to_{names[c]}",
                 "child": names[c], "child_interface": "base", "axis": [float(v) for v in random_axis(rng)]}
        if fixed_joint and c == nbodies - 1 and nbodies > 1:
            joint = {k: v for k, v in joint.items() if k != "axis"}
            joint["type"] = "fixed"
            joint["orientation"] = [[float(v) for v in row] for row in random_rotation(rng)]
        joints[jname] = joint

    scene_bodies = {}
    for b, body in enumerate(bodies):
        note = f"random frame body {names[b]}: {body.ndofs} dofs, lattice {body.shape}, seed {seed}"
        scene_bodies[names[b]] = {
            "mass": write_matrix(out_dir, f"{names[b]}_M", body.M, fmt, note),
            "stiffness": write_matrix(out_dir, f"{names[b]}_K", body.K, fmt, note),
            "nodes": f"{names[b]}_nodes.txt",
            "interfaces": interfaces[b],
        }
        write_nodes(os.path.join(out_dir, f"{names[b]}_nodes.txt"), body.ids, body.xyz,
                    np.full(len(body.ids), 6), note)

    def point_terms(b, kind):
        body = bodies[b]
        node = int(body.ids[rng.integers(len(body.ids))])
        direction = rng.normal(size=3)
        direction /= np.linalg.norm(direction)
        names3 = DOF_NAMES[3:] if kind == "rotation" else DOF_NAMES[:3]
        return [{"body": names[b], "node": node, "dof": d, "weight": float(w)} for d, w in zip(names3, direction)]

    inputs = {f"in{i}": point_terms(i % nbodies, "rotation" if i % 2 else "translation") for i in range(ninputs)}
    outputs = {f"out{o}": point_terms((o + 1) % nbodies, "rotation" if o % 2 else "translation")
               for o in range(noutputs)}

    nrev = sum(1 for j in joints.values() if j["type"] == "revolute")
    angles = [[float(a) for a in rng.choice(np.arange(0, 360, 15), size=nrev)] for _ in range(nangles)]
    angles[0] = [0.0] * nrev
    scene = {
        "name": os.path.basename(os.path.normpath(out_dir)) or "frames",
        "bodies": scene_bodies,
        "joints": joints,
        "inputs": inputs,
        "outputs": outputs,
        "angles": angles,
        "band": [0.01, 10.0],
        "damping": 0.0025,
        "accuracy": 0.05,
        "reduction": {"moments": 10, "output_blocks": 1, "importance": "h2", "keep_threshold": 0.05,
                      "reduction_angle": "auto"},
    }
    path = os.path.join(out_dir, "scene.yaml")
    with open(path, "w") as f:
        f.write(f"# generated by meshes/frames.py: total_dofs={total_dofs} nbodies={nbodies} seed={seed}\n")
        yaml.safe_dump(scene, f, sort_keys=False, default_flow_style=None, width=120)
    return path


def random_rotation(rng):
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    return q


def main():
    ap = argparse.ArgumentParser(description="Write random free-free beam-frame bodies and a scene joining them.")
    ap.add_argument("--dofs", type=int, required=True, help="total dofs over all bodies (approximate)")
    ap.add_argument("--bodies", type=int, default=3)
    ap.add_argument("--inputs", type=int, default=3)
    ap.add_argument("--outputs", type=int, default=2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--fixed-joint", action="store_true", help="make the last joint fixed instead of revolute")
    ap.add_argument("--format", default="auto", choices=["auto", "mtx", "petsc"],
                    help=f"matrix files; auto = .mtx up to {MTX_MAX_DOFS} dofs per body, PETSc binary above")
    ap.add_argument("--out", required=True, help="output directory")
    args = ap.parse_args()
    path = write_random_scene(args.out, args.dofs, args.bodies, args.inputs, args.outputs, args.seed,
                              args.fixed_joint, args.format)
    print(path)


if __name__ == "__main__":
    main()
