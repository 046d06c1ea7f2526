"""Independent dense reference for kryflex, built the paper's way from a scene file alone.

Reads the scene YAML and the body files (Matrix Market with scipy, PETSc binary with petsc4py), builds the
interface constraint matrix C(alpha), takes its null space P by SVD (paper eq. 21-22) and forms
M_S = P^T M P, K_S = P^T K P, G_S = P^T G, H_S = H P (eq. 3-4).  Moments and frequency responses come from
a full dense eigendecomposition.  Nothing here calls kryflex: it is the yardstick the library is checked
against, so it is written to be short and plainly right, not fast (dense, for scenes up to a few thousand
dofs).

    scene = load_scene("meshes/galileo/galileo.yaml")
    Ms, Ks, Gs, Hs = assemble(scene, 30.0)          # angles in degrees, one per revolute joint
    L = moments(Ms, Ks, Gs, Hs, 10)                 # (10, t, a)
"""
import os
from dataclasses import dataclass

import numpy as np
import scipy.io
import scipy.linalg as sl
import scipy.sparse as sp
import yaml

DOF_INDEX = {"ux": 0, "uy": 1, "uz": 2, "rx": 3, "ry": 4, "rz": 5}
RIGID_RTOL = 1e-12   # eigenvalues below RIGID_RTOL * max eigenvalue are rigid-body / mechanism modes


@dataclass
class Body:
    name: str
    M: sp.csr_matrix
    K: sp.csr_matrix
    first_dof: dict      # node id -> index of its first dof
    ndof: dict           # node id -> 3 or 6
    interfaces: dict     # interface name -> node id

    @property
    def n(self):
        return self.K.shape[0]

    def dof(self, node, component):
        node = int(node)
        if node not in self.first_dof:
            raise KeyError(f"body {self.name!r} has no node {node}")
        if component >= self.ndof[node]:
            raise KeyError(f"body {self.name!r}: node {node} has {self.ndof[node]} dofs, no component {component}")
        return self.first_dof[node] + component


@dataclass
class Scene:
    path: str
    bodies: list         # [Body], in file order
    joints: list         # [dict], in file order
    inputs: list         # [(name, [term dict])]
    outputs: list
    raw: dict            # the YAML as read
    here: str            # the scene file's folder: body file paths are relative to it

    def body_index(self, name):
        for i, b in enumerate(self.bodies):
            if b.name == name:
                return i
        raise KeyError(f"scene {self.path}: no body named {name!r}")

    @property
    def offsets(self):
        return np.concatenate([[0], np.cumsum([b.n for b in self.bodies])]).astype(int)

    @property
    def nrevolute(self):
        return sum(1 for j in self.joints if j["type"] == "revolute")


# ------------------------------------------------------------------ reading

def read_matrix(path):
    """Sparse matrix from Matrix Market (.mtx) or PETSc binary (anything else)."""
    if path.endswith(".mtx"):
        return sp.csr_matrix(scipy.io.mmread(path))
    from petsc4py import PETSc
    viewer = PETSc.Viewer().createBinary(path, "r", comm=PETSc.COMM_SELF)
    mat = PETSc.Mat().create(comm=PETSc.COMM_SELF)
    mat.setType("seqaij")
    mat.load(viewer)
    indptr, indices, data = mat.getValuesCSR()
    shape = mat.getSize()
    mat.destroy()
    viewer.destroy()
    return sp.csr_matrix((data, indices, indptr), shape=shape)


def read_vector(path, n):
    if path.endswith(".mtx"):
        v = scipy.io.mmread(path)
        v = np.asarray(v.todense() if sp.issparse(v) else v).ravel()
    else:
        from petsc4py import PETSc
        viewer = PETSc.Viewer().createBinary(path, "r", comm=PETSc.COMM_SELF)
        vec = PETSc.Vec().create(comm=PETSc.COMM_SELF)
        vec.load(viewer)
        v = vec.getArray().copy()
        vec.destroy()
        viewer.destroy()
    if v.size != n:
        raise ValueError(f"{path}: vector has {v.size} entries, the body has {n} dofs")
    return v


def read_coordinates(path):
    """Node ids -> (x, y, z), in file order."""
    xyz = {}
    with open(path) as f:
        for line in f:
            line = line.split("#", 1)[0].split()
            if line:
                xyz[int(line[0])] = np.array([float(v) for v in line[1:4]])
    return xyz


def read_nodes(path):
    """Node ids -> (first dof, ndof), dofs numbered node by node in file order."""
    first, ndof, nxt = {}, {}, 0
    with open(path) as f:
        for line in f:
            line = line.split("#", 1)[0].split()
            if not line:
                continue
            node, d = int(line[0]), int(line[4])
            first[node], ndof[node] = nxt, d
            nxt += d
    return first, ndof


def load_scene(path):
    with open(path) as f:
        raw = yaml.safe_load(f)
    here = os.path.dirname(os.path.abspath(path))
    bodies = []
    for name, spec in raw["bodies"].items():
        M = read_matrix(os.path.join(here, spec["mass"]))
        K = read_matrix(os.path.join(here, spec["stiffness"]))
        first, ndof = read_nodes(os.path.join(here, spec["nodes"]))
        if M.shape != K.shape or K.shape[0] != sum(ndof.values()):
            raise ValueError(f"body {name}: M {M.shape}, K {K.shape}, nodes give {sum(ndof.values())} dofs")
        bodies.append(Body(name, M, K, first, ndof, {k: int(v) for k, v in spec.get("interfaces", {}).items()}))
    joints = [dict(j, name=n) for n, j in raw.get("joints", {}).items()]
    as_terms = lambda v: v if isinstance(v, list) else [v]   # noqa: E731
    scene = Scene(path, bodies, joints,
                  [(n, as_terms(v)) for n, v in raw.get("inputs", {}).items()],
                  [(n, as_terms(v)) for n, v in raw.get("outputs", {}).items()], raw, here)
    return scene


def configurations(scene):
    """The scene's angles as a list of configurations, each a list of one angle (degrees) per revolute joint."""
    angles = scene.raw.get("angles", [0.0])
    return [list(np.atleast_1d(a).astype(float)) for a in angles]


# ------------------------------------------------------------------ assembly (eq. 2-4, 20-22)

def rotation(axis, alpha, R0=None):
    """Rot(axis, alpha) R0 by Rodrigues' formula (alpha in radians)."""
    a = np.asarray(axis, float)
    a = a / np.linalg.norm(a)
    S = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    R = np.eye(3) + np.sin(alpha) * S + (1 - np.cos(alpha)) * S @ S
    return R if R0 is None else R @ np.asarray(R0, float)


def interface_dofs(body, name):
    node = body.interfaces[name]
    if body.ndof[node] != 6:
        raise ValueError(f"body {body.name!r}: interface {name!r} is node {node} with {body.ndof[node]} dofs; "
                         "interface nodes need 6")
    return body.first_dof[node] + np.arange(6)


def constraint_matrix(scene, angles_deg):
    """C(alpha): rows u_p - R u_c = 0, and (theta_p - R theta_c) = 0 across the axis (revolute) or fully (fixed)."""
    angles = np.atleast_1d(np.asarray(angles_deg, float))
    if angles.size != scene.nrevolute:
        raise ValueError(f"{scene.nrevolute} revolute joints but {angles.size} angles given")
    off = scene.offsets
    rows, r = [], 0
    for j in scene.joints:
        p, c = scene.body_index(j["parent"]), scene.body_index(j["child"])
        bp, bc = scene.bodies[p], scene.bodies[c]
        dp = off[p] + interface_dofs(bp, j["parent_interface"])
        dc = off[c] + interface_dofs(bc, j["child_interface"])
        if j["type"] == "revolute":
            axis = np.asarray(j["axis"], float)
            axis /= np.linalg.norm(axis)
            R = rotation(axis, np.radians(angles[r]), j.get("orientation"))
            r += 1
            across = sl.null_space(axis[None, :]).T       # two unit vectors perpendicular to the axis
        elif j["type"] == "fixed":
            R = np.asarray(j.get("orientation", np.eye(3)), float)
            across = np.eye(3)
        else:
            raise ValueError(f"joint {j['name']}: unknown type {j['type']!r}")
        for proj, k in ((np.eye(3), 0), (across, 3)):      # translations, then rotations
            block = np.zeros((len(proj), off[-1]))
            block[:, dp[k:k + 3]] = proj
            block[:, dc[k:k + 3]] = -proj @ R
            rows.append(block)
    return np.vstack(rows) if rows else np.zeros((0, off[-1]))


def null_space_svd(C, rtol=1e-10):
    """Orthonormal basis of the null space of C from its SVD (paper eq. 21-22)."""
    n = C.shape[1]
    if C.shape[0] == 0:
        return np.eye(n)
    _, s, vt = np.linalg.svd(C, full_matrices=True)
    rank = int(np.sum(s > rtol * s[0]))
    return vt[rank:].T


def body_io(scene):
    """Stacked input matrix G (N x a) and output matrix H (t x N) over all bodies."""
    off, N = scene.offsets, scene.offsets[-1]

    def fill(terms, out):
        for term in terms:
            b = scene.body_index(term["body"])
            body = scene.bodies[b]
            if "vector" in term:
                out[off[b]:off[b + 1]] += term.get("weight", 1.0) * read_vector(
                    os.path.join(scene.here, term["vector"]), body.n)
            else:
                out[off[b] + body.dof(term["node"], DOF_INDEX[term["dof"]])] += term.get("weight", 1.0)

    G = np.zeros((N, len(scene.inputs)))
    H = np.zeros((len(scene.outputs), N))
    for i, (_, terms) in enumerate(scene.inputs):
        fill(terms, G[:, i])
    for o, (_, terms) in enumerate(scene.outputs):
        fill(terms, H[o])
    return G, H


def assemble(scene, angles_deg):
    """Full-order system at one configuration: (Ms, Ks, Gs, Hs), dense."""
    M = sp.block_diag([b.M for b in scene.bodies]).tocsr()
    K = sp.block_diag([b.K for b in scene.bodies]).tocsr()
    G, H = body_io(scene)
    P = null_space_svd(constraint_matrix(scene, angles_deg))
    Ms, Ks = P.T @ (M @ P), P.T @ (K @ P)
    return 0.5 * (Ms + Ms.T), 0.5 * (Ks + Ks.T), P.T @ G, H @ P


def body_rigid_modes(scene, b):
    """The 6 rigid-body modes of body b from its node coordinates alone (n_b x 6): a node's translations
    t + theta x x, its rotations (6-dof nodes) theta."""
    body = scene.bodies[b]
    xyz = read_coordinates(os.path.join(scene.here, scene.raw["bodies"][body.name]["nodes"]))
    R = np.zeros((body.n, 6))
    for node, k0 in body.first_dof.items():
        for d in range(3):
            e = np.zeros(3)
            e[d] = 1.0
            R[k0 + d, d] = 1.0
            R[k0 + d, 3:] = np.cross(xyz[node], e)     # (theta x x)_d = theta . (x x e_d)
        if body.ndof[node] == 6:
            R[k0 + 3:k0 + 6, 3:] = np.eye(3)
        elif body.ndof[node] != 3:
            raise ValueError(f"body {body.name!r}: node {node} has {body.ndof[node]} dofs; rigid modes need 3 or 6")
    return R


def geometric_rigid_modes(scene, angles_deg):
    """The system's rigid-body and mechanism modes from geometry and joints alone, in the coordinates of assemble()
    (N_s x r): the combinations of the bodies' rigid modes that satisfy C(alpha), mapped by P^T. Exact where the
    null space of K_S from an eigensolver is only known to eps lam_max / lam_1 (on a 2,755-dof solid 2e-9 rad, which
    at 0.01 Hz is 3e-4 of the elastic peak next to a rigid response 670 times that peak)."""
    B = sl.block_diag(*[body_rigid_modes(scene, b) for b in range(len(scene.bodies))])
    C = constraint_matrix(scene, angles_deg)
    c = sl.null_space(C @ B) if C.shape[0] else np.eye(B.shape[1])
    return null_space_svd(C).T @ (B @ c)


# ------------------------------------------------------------------ analysis

def eigenvalues(Ms, Ks):
    """Generalized eigenvalues of (K, M), ascending (omega^2)."""
    return sl.eigh(Ks, Ms, eigvals_only=True)


def rigid_count(Ms, Ks, rtol=RIGID_RTOL):
    lam = eigenvalues(Ms, Ks)
    return int(np.sum(np.abs(lam) <= rtol * np.abs(lam).max()))


def _modes(Ms, Ks, rtol):
    lam, phi = sl.eigh(Ks, Ms)                       # phi^T M phi = I
    rigid = np.abs(lam) <= rtol * np.abs(lam).max()
    return lam, phi, rigid


def transfer(Ms, Ks, Gs, Hs, omegas):
    """Undamped T(w) = H (K - w^2 M)^-1 G at each w (rad/s, nonzero): array (nw, t, a)."""
    return np.array([Hs @ np.linalg.solve(Ks - w**2 * Ms, Gs) for w in np.atleast_1d(omegas)])


def moments(Ms, Ks, Gs, Hs, nmom, rtol=RIGID_RTOL):
    """L^k = sum over flexible modes H phi phi^T G / lambda^(k+1), k = 0..nmom-1: array (nmom, t, a)."""
    lam, phi, rigid = _modes(Ms, Ks, rtol)
    hp, pg, lf = Hs @ phi[:, ~rigid], phi[:, ~rigid].T @ Gs, lam[~rigid]
    return np.array([(hp * (1.0 / lf) ** (k + 1)) @ pg for k in range(nmom)])


def static_moment(Ms, Ks, Gs, Hs, R, steps=2):
    """L^0 = H K+ G on the flexible subspace (R^T M x = 0; R: the rigid-body and mechanism modes, any basis), dense,
    without an eigensolve: (K + M R R^T M) x = G - M R R^T G with R M-orthonormalized, solved in double and refined
    (steps) with its residual in long double. The modal sum of moments() loses digits over the stiff modes (Galileo:
    2e-8); this keeps what the assembly's own rounding leaves (Galileo's and the solid's ties eliminated by a pivoted QR
    or an SVD null space give L^0 1.2e-11 and 3.6e-12 apart)."""
    Ms, Ks = np.asarray(Ms, dtype=float), np.asarray(Ks, dtype=float)
    R = R @ np.linalg.inv(np.linalg.cholesky(R.T @ Ms @ R)).T
    MR = Ms @ R
    Ge = Gs - MR @ (R.T @ Gs)
    A = Ks + MR @ MR.T
    lu = sl.lu_factor(A)
    ld = np.longdouble
    A_ld, Ge_ld, MR_ld = Ks.astype(ld), Ge.astype(ld), MR.astype(ld)
    A_ld += MR_ld @ MR_ld.T
    x = sl.lu_solve(lu, Ge)
    for _ in range(steps):
        x = x + sl.lu_solve(lu, (Ge_ld - A_ld @ x.astype(ld)).astype(float))
    return Hs @ (x - R @ (MR.T @ x))


def modal_frf(Ms, Ks, Gs, Hs, omegas, zeta, rtol=RIGID_RTOL):
    """T(w) = sum_i H phi_i phi_i^T G / (lambda_i - w^2 + 2 i zeta sqrt(lambda_i) w), rigid modes 1/(-w^2)."""
    lam, phi, rigid = _modes(Ms, Ks, rtol)
    lam = np.where(rigid, 0.0, lam)
    hp, pg = Hs @ phi, phi.T @ Gs
    out = []
    for w in np.atleast_1d(omegas):
        d = lam - w**2 + 2j * zeta * np.sqrt(lam) * w
        out.append((hp / d) @ pg)
    return np.array(out)


def petsc_matrix(D, dense=False):
    """The dense array D as a distributed PETSc matrix (AIJ holding D's nonzeros only, or dense), each rank setting its
    own rows: the tests' way to hand a small hand-made body to the library."""
    from petsc4py import PETSc
    n = D.shape[0]
    if dense:
        m = PETSc.Mat().createDense([n, n])
        m.setUp()
    else:
        m = PETSc.Mat().createAIJ([n, n], nnz=n)
    r0, r1 = m.getOwnershipRange()
    for i in range(r0, r1):
        cols = np.nonzero(D[i])[0].astype(PETSc.IntType)
        m.setValues([i], cols, D[i, cols])
    m.assemble()
    return m
