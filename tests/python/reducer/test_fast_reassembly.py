"""The allocation-free reassembly (KFReassembly; ReducedModel.at() runs on it) against the C system of
KFReducedModelReassemble (CReducedModel.reassemble, the path every other caller takes) and against a NumPy
reassembly written here from the stored reduced bodies (the constraint matrix of eq. 20, its null space by SVD,
the bodies projected on it, eq. 21-24).

Scenes: Galileo with a non-proportional damping matrix on each body plus Rayleigh damping (one revolute joint),
and a random 3-body frame scene with two skew revolute joints; at the angles of interest and at angles far from
them. The NumPy comparison is on what does not depend on the null-space basis chosen: generalized eigenvalues and
the damped transfer function H (K - w^2 M + i w C)^-1 G. A 2-rank run must give what 1 rank gives.
"""
import os
import subprocess
import sys

import numpy as np
import pytest
import scipy.linalg as sl
import yaml

import kryflex
from kryflex import _core

HERE = os.path.dirname(os.path.abspath(__file__))
SUPPORT = os.path.join(os.path.dirname(HERE), "support")   # the helpers (tests/python/support)
sys.path.insert(0, SUPPORT)
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
ROOT = run_env.ROOT
GALILEO = os.path.join(ROOT, "meshes", "galileo", "galileo.yaml")
sys.path.insert(0, os.path.join(ROOT, "meshes"))
import frames  # noqa: E402
import reference as ref  # noqa: E402

ENV = dict(run_env.ENV, PYTHONPATH=run_env.PACKAGE)
RAYLEIGH = {"alpha": 0.02, "beta": 2e-5}

pytestmark = pytest.mark.usefixtures("quiet_library")   # tests/python/conftest.py


def galileo_damped_spec():
    """Galileo as a dict scene with per body a symmetric semi-definite, non-proportional damping matrix (a little
    stiffness-proportional damping plus a random rank-3 part) and Rayleigh damping on top."""
    with open(GALILEO) as f:
        spec = yaml.safe_load(f)
    base = os.path.dirname(GALILEO)
    dense = ref.load_scene(GALILEO)
    rng = np.random.default_rng(3)
    for b, body in zip(spec["bodies"].values(), dense.bodies):
        for k in ("mass", "stiffness", "nodes"):
            b[k] = os.path.join(base, b[k])
        A = rng.standard_normal((body.n, 3))
        C = 1e-3 * body.K.toarray() + 0.2 * (A @ A.T) * np.abs(body.M.diagonal()).mean()
        b["damping"] = 0.5 * (C + C.T)
    spec.pop("reduction")
    spec["angles"] = [0.0, 30.0]
    spec["damping"] = {"modal": 0.0, "rayleigh": RAYLEIGH}
    return spec


@pytest.fixture(scope="module")
def galileo_damped():
    scene = kryflex.scene_from_dict(galileo_damped_spec())
    model = kryflex.Reducer(scene, quiet=True).reduce().model
    return model, [[0.0], [30.0], [7.5], [-135.0], [359.0]]


@pytest.fixture(scope="module")
def frames_two_joints(tmp_path_factory):
    path = frames.write_random_scene(str(tmp_path_factory.mktemp("frames2")), 240, nbodies=3, ninputs=3,
                                     noutputs=2, seed=1)
    scene = kryflex.load_scene(path)
    assert len(scene.revolute) == 2
    model = kryflex.reduce(scene, quiet=True).model
    return model, [list(c) for c in scene.configurations] + [[10.0, 250.0], [-30.0, 95.0], [333.0, 17.0]]


@pytest.fixture(scope="module", params=["galileo_damped", "frames_two_joints"])
def case(request):
    return request.getfixturevalue(request.param)


# ================================================================================================ NumPy reference

def numpy_reassemble(model, angles_deg, rtol=1e-9):
    """(M, K, C, G, H) of the reassembled system by NumPy: D of eq. (20) from the bodies' interface rows (and the
    model's coordinate ties, if it has them), its null space by SVD, blkdiag of the bodies projected on it; C: the bodies' damping plus the model's Rayleigh terms."""
    sizes = model.sizes
    off = np.concatenate([[0], np.cumsum(sizes)]).astype(int)
    rows, irev = [], 0
    for j in model.joints:
        p, c = j["parent"], j["child"]
        Ip = model.bodies[p]["iface"][6 * j["parent_interface"]:6 * j["parent_interface"] + 6]
        Ic = model.bodies[c]["iface"][6 * j["child_interface"]:6 * j["child_interface"] + 6]
        if j["type"] == "revolute":
            axis = np.asarray(j["axis"], float) / np.linalg.norm(j["axis"])
            R = ref.rotation(axis, np.radians(angles_deg[irev]), j.get("R0"))
            irev += 1
            across = sl.null_space(axis[None, :]).T
        else:
            R = np.asarray(j["R0"], float)
            across = np.eye(3)
        for proj, k in ((np.eye(3), 0), (across, 3)):
            block = np.zeros((len(proj), off[-1]))
            block[:, off[p]:off[p + 1]] = proj @ Ip[k:k + 3]
            block[:, off[c]:off[c + 1]] = -proj @ R @ Ic[k:k + 3]
            rows.append(block)
    if model.ties is not None:      # a model of shared directions: its coordinate ties appended to the joints'
        rows.append(model.ties)
    D = np.vstack(rows)
    _, s, vt = np.linalg.svd(D)
    N = vt[int(np.sum(s > rtol * s[0])):].T
    M = N.T @ sl.block_diag(*[b["M"] for b in model.bodies]) @ N
    K = N.T @ sl.block_diag(*[b["K"] for b in model.bodies]) @ N
    Cb = sl.block_diag(*[b.get("damping_matrix", np.zeros_like(b["M"])) for b in model.bodies])
    ray = model.damping()["rayleigh"]
    C = N.T @ Cb @ N + ray["alpha"] * M + ray["beta"] * K
    G = N.T @ np.vstack([b["G"] for b in model.bodies])
    H = np.hstack([b["H"] for b in model.bodies]) @ N
    return M, K, C, G, H


def damped_transfer(M, K, C, G, H, w):
    return H @ np.linalg.solve(K - w ** 2 * M + 1j * w * C, G)


# ================================================================================================ tests

def test_fast_path_equals_the_c_system(case):
    """at() (KFReassemblyApply's closed form, KFReassemblyEig) gives KFReducedModelReassemble's system in another
    basis of the same null space: the same eigenvalues, frequencies, rank, rigid count and damped transfer function.
    (The arrays themselves: test_closed_form_reassembly, where the SVD path is compared array for array.)"""
    model, angles_list = case
    for angles in angles_list:
        fast = model.at(angles)
        old = model.reassemble(np.radians(angles))
        M, K, G, H = old.matrices()
        lam, Phi, nrigid, Phir = old.modes()
        rank, ratio = old.reassembly_info()
        Cd, damping_model = old.damping()
        assert fast.M.shape == M.shape and fast.rigid_modes.shape == Phir.shape
        np.testing.assert_allclose(fast.eigenvalues, lam, rtol=0, atol=1e-12 * np.abs(lam).max())
        np.testing.assert_allclose(fast.frequencies_hz, old.frequencies_hz(), rtol=1e-9)
        # M-orthonormal modes that diagonalize K, in the fast path's own basis
        np.testing.assert_allclose(fast.modes.T @ fast.M @ fast.modes, np.eye(len(lam)), atol=1e-9)
        assert (fast.constraint_rank, fast.sigma_ratio) == (rank, ratio)
        assert fast.damping_model == damping_model
        assert (fast.damping_matrix is None) == (Cd is None)
        Cf = fast.damping_matrix if Cd is not None else np.zeros_like(fast.M)
        Co = Cd if Cd is not None else np.zeros_like(M)
        for f in (0.05, 0.7, 3.3, 12.0):
            w = 2 * np.pi * f
            Tf, To = damped_transfer(fast.M, fast.K, Cf, fast.B, fast.C, w), damped_transfer(M, K, Co, G, H, w)
            cond = np.linalg.cond(K - w ** 2 * M + 1j * w * Co)
            assert np.abs(Tf - To).max() <= max(1e-12, 1e3 * np.finfo(float).eps * cond) * np.abs(To).max(), f


def test_fast_path_against_numpy(case):
    """Eigenvalues and the damped transfer function at frequencies across the band against the NumPy reassembly."""
    model, angles_list = case
    for angles in angles_list:
        s = model.at(angles)
        M, K, C, G, H = numpy_reassemble(model, angles)
        assert s.M.shape == M.shape
        # the flexible eigenvalues (the rigid ones are zeros to rounding on either side)
        lam = sl.eigh(K, M, eigvals_only=True)
        nr = s.rigid_modes.shape[1]
        np.testing.assert_allclose(s.eigenvalues[nr:], lam[nr:], rtol=1e-8)
        Cd = s.damping_matrix if s.damping_matrix is not None else np.zeros_like(s.M)
        for f in (0.05, 0.7, 3.3, 12.0):
            w = 2 * np.pi * f
            Tf = damped_transfer(s.M, s.K, Cd, s.B, s.C, w)
            Tn = damped_transfer(M, K, C, G, H, w)
            assert np.abs(Tf - Tn).max() <= 1e-8 * np.abs(Tn).max()
        # the modes are M-orthonormal and diagonalize K
        Phi = s.modes
        np.testing.assert_allclose(Phi.T @ s.M @ Phi, np.eye(len(lam)), atol=1e-9)


def test_damping_matrix_and_rayleigh(galileo_damped):
    """The damped model's reassembled damping matrix holds the bodies' matrices and alpha M + beta K."""
    model, angles_list = galileo_damped
    assert model.damping()["rayleigh"] == RAYLEIGH
    assert all("damping_matrix" in b for b in model.bodies)
    s = model.at(angles_list[3])
    M, K, C, G, H = numpy_reassemble(model, angles_list[3])
    Tn = damped_transfer(M, K, C, G, H, 2 * np.pi * 1.0)
    Tf = damped_transfer(s.M, s.K, s.damping_matrix, s.B, s.C, 2 * np.pi * 1.0)
    assert np.abs(Tf - Tn).max() <= 1e-8 * np.abs(Tn).max()
    # without its damping matrix the response differs: the check above is not vacuous
    T0 = damped_transfer(s.M, s.K, 0 * s.damping_matrix, s.B, s.C, 2 * np.pi * 1.0)
    assert np.abs(T0 - Tn).max() > 1e-3 * np.abs(Tn).max()


def test_modes_are_lazy_and_frf_works(galileo_damped):
    model, angles_list = galileo_damped
    s = model.at(angles_list[2])
    assert s._eigen is None and s._handle is None
    f = np.geomspace(0.05, 10, 40)
    T = s.frf(f)
    assert T.shape == (len(f), s.C.shape[0], s.B.shape[1]) and np.all(np.isfinite(T))
    assert len(s.frequencies_hz) == s.dofs - s.rigid_modes.shape[1]


def test_changed_damping_is_seen(galileo_damped):
    """The workspace at() keeps is made again when the model's damping changes."""
    model, angles_list = galileo_damped
    before = model.at(angles_list[0]).damping_matrix.copy()
    d = model.damping()
    try:
        model.set_damping(dict(d, rayleigh={"alpha": 0.0, "beta": 0.0}))
        after = model.at(angles_list[0])
        fresh = _core.CReassembly(model).apply(np.radians(angles_list[0]))[2]    # a workspace of the new damping
        np.testing.assert_allclose(after.damping_matrix, fresh, rtol=1e-13, atol=0)
        assert np.abs(after.damping_matrix - before).max() > 1e-6 * np.abs(before).max()
    finally:
        model.set_damping(d)


def test_bad_angles(frames_two_joints):
    model, _ = frames_two_joints
    with pytest.raises(ValueError, match="2 revolute joint"):
        model.at([10.0])
    with pytest.raises(ValueError, match="finite"):
        model.at([np.nan, 1.0])
    r = _core.CReassembly(model)
    with pytest.raises(ValueError, match="eig takes"):
        r.eig(np.eye(3), np.eye(4))


TWO_RANKS = r"""
import sys, numpy as np, kryflex
from mpi4py import MPI
scene = kryflex.load_scene(sys.argv[1])
model = kryflex.reduce(scene, quiet=True).model
out = {}
for i, a in enumerate(([0.0, 0.0], [10.0, 250.0], [-30.0, 95.0])):
    s = model.at(a)
    out["M%d" % i], out["K%d" % i], out["B%d" % i], out["lam%d" % i] = s.M, s.K, s.B, s.eigenvalues
    model.save(sys.argv[2] + ".h5") if i == 0 else None
rows = MPI.COMM_WORLD.gather(out["K1"], root=0)
if MPI.COMM_WORLD.rank == 0:
    assert all(np.array_equal(r, rows[0]) for r in rows), "ranks differ"
    np.savez(sys.argv[2], **out)
"""


@pytest.mark.mpi
def test_two_ranks_agree_with_one(tmp_path):
    """A model reduced on 2 ranks, reassembled on each: the ranks agree, and the reassembly of the same model on
    1 rank (loaded from its file) is the same."""
    path = frames.write_random_scene(str(tmp_path), 240, nbodies=3, ninputs=3, noutputs=2, seed=1)
    script = tmp_path / "two.py"
    script.write_text(TWO_RANKS)
    out = str(tmp_path / "two")
    r = subprocess.run(["mpiexec", "-n", "2", sys.executable, str(script), path, out], env=ENV,
                       capture_output=True, text=True, timeout=240)
    assert r.returncode == 0, r.stderr[-3000:]
    got = np.load(out + ".npz")
    model = kryflex.ReducedModel.load(out + ".h5")
    for i, a in enumerate(([0.0, 0.0], [10.0, 250.0], [-30.0, 95.0])):
        s = model.at(a)
        np.testing.assert_array_equal(s.M, got["M%d" % i])
        np.testing.assert_array_equal(s.K, got["K%d" % i])
        np.testing.assert_array_equal(s.B, got["B%d" % i])
        np.testing.assert_allclose(s.eigenvalues, got["lam%d" % i], rtol=1e-12, atol=1e-12 * got["lam%d" % i].max())
