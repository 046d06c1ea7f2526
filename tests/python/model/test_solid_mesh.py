"""Checks of meshes/solid: hex8 element, grid assembly with RBE2 elimination, written bodies and scene.

Everything runs on the coarsest mesh (refine TINY, ~1,300 dofs for the pair),
so dense NumPy references are affordable and the whole file takes seconds.
"""
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla
import yaml

REPO = Path(__file__).resolve().parents[3]
SOLID = REPO / "meshes" / "solid"
sys.path.insert(0, str(SOLID))

PETSc = pytest.importorskip("petsc4py.PETSc")

import generate          # noqa: E402
import solid_assembly    # noqa: E402
import solid_grid        # noqa: E402
import solid_hex8        # noqa: E402
import solid_spacecraft  # noqa: E402
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "support"))
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)

TINY = 0.25
E, NU, RHO = 70e9, 0.33, 2700.0


# ---------------------------------------------------------------- independent references

def elasticity_tensor(E, nu):
    """C_ijkl = lam d_ij d_kl + mu (d_ik d_jl + d_il d_jk), no Voigt notation."""
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    d = np.eye(3)
    return (lam * np.einsum("ij,kl->ijkl", d, d)
            + mu * (np.einsum("ik,jl->ijkl", d, d) + np.einsum("il,jk->ijkl", d, d)))


def reference_hex8(coords, E, nu, rho):
    """Plain-loop hex8: K[a i, b k] = sum_gp dN_a/dx_j C_ijkl dN_b/dx_l |J|; M = rho sum N_a N_b |J| (x I3).
    Node a sits at reference corner (+-1, +-1, +-1) with x varying fastest, as in solid_hex8."""
    C = elasticity_tensor(E, nu)
    corners = [(sx, sy, sz) for sz in (-1, 1) for sy in (-1, 1) for sx in (-1, 1)]
    g = 1 / np.sqrt(3)
    K, M = np.zeros((24, 24)), np.zeros((24, 24))
    for xi in (-g, g):
        for eta in (-g, g):
            for zeta in (-g, g):
                N = np.array([(1 + sx * xi) * (1 + sy * eta) * (1 + sz * zeta) / 8 for sx, sy, sz in corners])
                dN = np.array([[sx * (1 + sy * eta) * (1 + sz * zeta) / 8,
                                sy * (1 + sx * xi) * (1 + sz * zeta) / 8,
                                sz * (1 + sx * xi) * (1 + sy * eta) / 8] for sx, sy, sz in corners])
                J = np.zeros((3, 3))
                for a in range(8):
                    J += np.outer(dN[a], coords[a])
                detJ = np.linalg.det(J)
                dNx = dN @ np.linalg.inv(J).T
                for a in range(8):
                    for b in range(8):
                        M[3 * a:3 * a + 3, 3 * b:3 * b + 3] += rho * N[a] * N[b] * detJ * np.eye(3)
                        for i in range(3):
                            for k in range(3):
                                K[3 * a + i, 3 * b + k] += detJ * sum(dNx[a, j] * C[i, j, k, l] * dNx[b, l]
                                                                     for j in range(3) for l in range(3))
    return K, M


def shapes():
    """A box and a parallelepiped (an affine map of the box: trilinear elements are exact there),
    plus a general distorted hex for the element comparison only."""
    box = solid_hex8.box_coords((0.3, 0.2, 0.5))
    A = np.array([[1.0, 0.2, 0.1], [0.0, 0.9, 0.3], [0.1, 0.0, 1.1]])
    pped = box @ A.T + np.array([0.4, -0.2, 1.0])
    rng = np.random.default_rng(7)
    distorted = box + 0.03 * rng.standard_normal(box.shape)
    return {"box": (box, 0.3 * 0.2 * 0.5), "parallelepiped": (pped, 0.3 * 0.2 * 0.5 * np.linalg.det(A)),
            "distorted": (distorted, None)}


def rigid_modes(xyz, ndof):
    """6 rigid-body modes over nodes with 3 or 6 dofs: u = t + theta x x, rotations = theta."""
    cols = []
    for k in range(6):
        t, th = np.zeros(3), np.zeros(3)
        (t if k < 3 else th)[k % 3] = 1.0
        v = []
        for x, n in zip(xyz, ndof):
            v.extend(t + np.cross(th, x))
            if n == 6:
                v.extend(th)
        cols.append(v)
    return np.array(cols).T


def load_petsc(path):
    viewer = PETSc.Viewer().createBinary(str(path), "r", comm=PETSc.COMM_SELF)
    A = PETSc.Mat().create(PETSc.COMM_SELF)
    A.setType("aij")
    A.load(viewer)
    viewer.destroy()
    return A


def dense(A):
    return A.convert("dense").getDenseArray().copy()


def read_nodes(path):
    data = np.loadtxt(path, comments="#", ndmin=2)
    return data[:, 0].astype(int), data[:, 1:4], data[:, 4].astype(int)


@pytest.fixture(scope="module")
def tiny_scene(tmp_path_factory):
    out = tmp_path_factory.mktemp("solid_tiny")
    scene = generate.write_spacecraft(out, refine=TINY, comm=PETSc.COMM_SELF)
    return Path(scene)


# ---------------------------------------------------------------- element

@pytest.mark.parametrize("shape", ["box", "parallelepiped", "distorted"])
def test_hex8_matches_plain_loop_reference(shape):
    coords, _ = shapes()[shape]
    K, M = solid_hex8.element_matrices(coords, E, NU, RHO)
    Kr, Mr = reference_hex8(coords, E, NU, RHO)
    assert np.abs(K - Kr).max() <= 1e-12 * np.abs(Kr).max()
    assert np.abs(M - Mr).max() <= 1e-12 * np.abs(Mr).max()
    assert np.array_equal(K, K.T) and np.array_equal(M, M.T)


@pytest.mark.parametrize("shape", ["box", "parallelepiped"])
def test_hex8_patch_test_uniform_strain_energy(shape):
    """u = G x gives the uniform strain eps = sym(G): energy 1/2 u.K.u must be V/2 eps:C:eps exactly,
    and the skew part of G (a rotation) must cost nothing."""
    coords, volume = shapes()[shape]
    K, _ = solid_hex8.element_matrices(coords, E, NU, RHO)
    C = elasticity_tensor(E, NU)
    rng = np.random.default_rng(3)
    for _ in range(5):
        G = rng.standard_normal((3, 3)) * 1e-3
        u = (coords @ G.T).ravel()
        eps = 0.5 * (G + G.T)
        exact = 0.5 * volume * np.einsum("ij,ijkl,kl->", eps, C, eps)
        assert 0.5 * u @ K @ u == pytest.approx(exact, rel=1e-12)
        W = 0.5 * (G - G.T)
        w = (coords @ W.T).ravel()
        assert abs(w @ K @ w) <= 1e-12 * np.abs(K).max() * (w @ w)
    R = rigid_modes(coords, [3] * 8)
    assert np.abs(K @ R).max() <= 1e-12 * np.abs(K).max() * np.abs(R).max()
    assert np.linalg.matrix_rank(K, tol=1e-9 * np.abs(K).max()) == 24 - 6


def test_hex8_mass_totals_and_lumping():
    coords, volume = shapes()["parallelepiped"]
    _, M = solid_hex8.element_matrices(coords, E, NU, RHO)
    for d in range(3):
        assert M[d::3, d::3].sum() == pytest.approx(RHO * volume, rel=1e-13)
    assert np.all(np.linalg.eigvalsh(M) > 0)
    box, vbox = shapes()["box"]
    L = solid_hex8.lump(solid_hex8.element_matrices(box, E, NU, RHO)[1])
    assert np.allclose(np.diag(L), RHO * vbox / 8, rtol=1e-13)
    assert np.count_nonzero(L - np.diag(np.diag(L))) == 0


# ---------------------------------------------------------------- assembly and RBE2 elimination

def dense_reference(body, lumped=False):
    """Element-by-element scatter into all nodes' dofs, then K' = T^T K T with T built from coordinates."""
    xyz = body.coords()
    n = len(xyz)
    K = np.zeros((3 * n, 3 * n))
    M = np.zeros((3 * n, 3 * n))
    for e in np.argwhere(body.cell_type >= 0):
        nodes = [body.node_number[e[0] + a, e[1] + b, e[2] + c] for c in (0, 1) for b in (0, 1) for a in (0, 1)]
        ke, me = solid_hex8.element_matrices(xyz[nodes], body.spec.E, body.spec.nu, body.spec.rho)
        if lumped:
            me = np.diag(me.sum(axis=1))
        d = (3 * np.array(nodes)[:, None] + np.arange(3)).ravel()
        K[np.ix_(d, d)] += ke
        M[np.ix_(d, d)] += me
    surface = {int(s): q for q, r in enumerate(body.rbe2) for s in r.surface}
    solid = [k for k in range(n) if k not in surface]
    ns = len(solid)
    T = np.zeros((3 * n, 3 * ns + 6 * len(body.rbe2)))
    for j, k in enumerate(solid):
        T[3 * k:3 * k + 3, 3 * j:3 * j + 3] = np.eye(3)
    for k, q in surface.items():
        c0 = 3 * ns + 6 * q
        T[3 * k:3 * k + 3, c0:c0 + 3] = np.eye(3)
        r = xyz[k] - body.rbe2[q].centroid
        for a in range(3):   # column of theta_a: e_a x r
            T[3 * k:3 * k + 3, c0 + 3 + a] = np.cross(np.eye(3)[a], r)
    Mr = T.T @ M @ T
    for q, r in enumerate(body.rbe2):
        c0 = 3 * ns + 6 * q
        Mr[c0:c0 + 3, c0:c0 + 3] += r.point_mass * np.eye(3)
    return T.T @ K @ T, Mr


@pytest.mark.parametrize("spec", [solid_spacecraft.bus_spec, solid_spacecraft.rotor_spec], ids=["bus", "rotor"])
@pytest.mark.parametrize("lumped", [False, True], ids=["consistent", "lumped"])
def test_assembly_matches_dense_scatter_with_rbe2(spec, lumped):
    body = solid_grid.build_grid(spec(), TINY)
    K = dense(solid_assembly.assemble(body, "stiffness", PETSc.COMM_SELF))
    M = dense(solid_assembly.assemble(body, "mass", PETSc.COMM_SELF, lumped=lumped))
    Kr, Mr = dense_reference(body, lumped)
    assert np.abs(K - Kr).max() <= 1e-12 * np.abs(Kr).max()
    assert np.abs(M - Mr).max() <= 1e-12 * np.abs(Mr).max()
    assert np.array_equal(K, K.T) and np.array_equal(M, M.T)   # bitwise, by construction


def test_patch_on_interior_plane_is_rejected():
    spec = solid_spacecraft.bus_spec()
    spec.patches[0] = solid_grid.Rbe2Patch("bad", axis=2, plane=-0.6, lo=(-0.3, -0.3, 0), hi=(0.3, 0.3, 0))
    with pytest.raises(ValueError, match="outer face"):
        solid_grid.build_grid(spec, TINY)


# ---------------------------------------------------------------- written bodies and scene

def test_bodies_are_free_free_with_spd_mass(tiny_scene):
    scene = yaml.safe_load(tiny_scene.read_text())
    for name, b in scene["bodies"].items():
        K = dense(load_petsc(tiny_scene.parent / b["stiffness"]))
        M = dense(load_petsc(tiny_scene.parent / b["mass"]))
        np.linalg.cholesky(M)                                  # SPD, or this raises
        lam = sla.eigh(K, M, eigvals_only=True)
        tol = 1e-10 * lam[-1]
        assert np.count_nonzero(np.abs(lam) < tol) == 6, f"{name}: {lam[:8]}"
        assert lam[6] > 1e6 * np.abs(lam[:6]).max(), f"{name}: no clear gap after the rigid modes {lam[:8]}"


def test_rbe2_keeps_rigid_motion_and_total_mass(tiny_scene):
    scene = yaml.safe_load(tiny_scene.read_text())
    for name, b in scene["bodies"].items():
        ids, xyz, ndof = read_nodes(tiny_scene.parent / b["nodes"])
        K = dense(load_petsc(tiny_scene.parent / b["stiffness"]))
        M = dense(load_petsc(tiny_scene.parent / b["mass"]))
        assert K.shape[0] == ndof.sum()
        R = rigid_modes(xyz, ndof)
        assert np.abs(K @ R).max() <= 1e-12 * np.abs(K).max() * np.abs(R).max()
        spec = {"bus": solid_spacecraft.bus_spec, "rotor": solid_spacecraft.rotor_spec}[name]()
        mass = spec.rho * sum(np.prod(np.subtract(bl.hi, bl.lo)) for bl in spec.blocks) \
            + sum(p.point_mass for p in spec.patches)
        assert np.allclose((R.T @ M @ R)[:3, :3], mass * np.eye(3), rtol=1e-12, atol=1e-12 * mass)


def test_scene_refers_to_existing_six_dof_nodes(tiny_scene):
    scene = yaml.safe_load(tiny_scene.read_text())
    nodes = {}
    for name, b in scene["bodies"].items():
        for key in ("mass", "stiffness", "nodes"):
            assert (tiny_scene.parent / b[key]).is_file()
        ids, _, ndof = read_nodes(tiny_scene.parent / b["nodes"])
        nodes[name] = dict(zip(ids, ndof))
        six = np.nonzero(ndof == 6)[0]
        assert np.array_equal(six, np.arange(len(ids) - len(six), len(ids))), "6-dof nodes must come last"
        for iface in b["interfaces"].values():
            assert nodes[name][iface] == 6
    for terms in list(scene["inputs"].values()) + list(scene["outputs"].values()):
        for t in terms:
            need = 6 if t["dof"].startswith("r") else 3
            assert nodes[t["body"]][t["node"]] >= need, t
    assert scene["angles"] == [0, 30, 60, 90] and scene["damping"] == 0.0025
    assert scene["reduction"]["moments"] == 10


@pytest.mark.mpi
@pytest.mark.skipif(shutil.which("mpiexec") is None, reason="mpiexec not installed")
def test_two_ranks_write_the_same_matrices(tiny_scene, tmp_path):
    env = run_env.ENV
    run = subprocess.run(["mpiexec", "-n", "2", sys.executable, str(SOLID / "generate.py"),
                          "--refine", str(TINY), "-o", str(tmp_path)],
                         env=env, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    assert "2 rank(s)" in run.stdout
    serial = tiny_scene.parent
    for f in sorted(p.name for p in serial.iterdir()):
        if f.endswith(".petsc"):
            a, b = load_petsc(serial / f), load_petsc(tmp_path / f)
            for x, y in zip(a.getValuesCSR(), b.getValuesCSR()):
                assert np.array_equal(x, y), f
        else:
            assert (serial / f).read_text() == (tmp_path / f).read_text(), f
