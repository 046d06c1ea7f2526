"""The sparse reference's eigensolve seeded by the modes of the two references nearest in angle
(src/verify/seeded_eigen.c: Rayleigh-Ritz of K+ M on them, block solves, the count certified by Krylov-Schur deflated
by them). A free-free frame with two revolute joints at 4 angles 6 deg apart (the third and fourth references are
seeded, and the midpoints after them), forced through the sparse path, as built and with its rotations made massless (M singular): the seeded
frequencies against dense SciPy and against the eigensolve from scratch (-kf_verify_seeded 0), the reference's
response against the one from scratch; serially and on 2 ranks."""
import os
import subprocess
import sys

import numpy as np
import pytest
import scipy.io as sio
import scipy.sparse as sp
import yaml
from petsc4py import PETSc

import kryflex

HERE = os.path.dirname(os.path.abspath(__file__))
SUPPORT = os.path.join(os.path.dirname(HERE), "support")
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(HERE)))
sys.path.insert(0, HERE)
sys.path.insert(0, SUPPORT)
sys.path.insert(0, os.path.join(ROOT, "meshes"))
import frames  # noqa: E402
import reference as ref  # noqa: E402
from test_sparse_eigensolve import ENV, PROBE, dense_flexible_frequencies  # noqa: E402

pytestmark = [pytest.mark.fast, pytest.mark.usefixtures("quiet_library")]


def frame(tmp, massless):
    """The frame's scene path; massless: every node's rotational rows and columns of M zeroed (a lumped-mass model)."""
    path = frames.write_random_scene(str(tmp), 360, nbodies=3, ninputs=2, noutputs=2, seed=5, nangles=4)
    with open(path) as f:
        spec = yaml.safe_load(f)
    # angles 6 deg apart: the frame's modes move little between neighbours, as a fine angle grid's do
    spec["angles"] = [[6.0 * i, -6.0 * i] for i in range(4)]
    with open(path, "w") as f:
        yaml.safe_dump(spec, f)
    if massless:
        for b in range(3):
            f = os.path.join(str(tmp), "body%d_M.mtx" % b)
            M = sio.mmread(f).toarray()
            rot = np.array([i for i in range(M.shape[0]) if i % 6 >= 3])
            M[rot, :] = 0
            M[:, rot] = 0
            sio.mmwrite(f, sp.csr_matrix(M), symmetry="symmetric")
    return path


def reduce_sparse(path, **options):
    opts = PETSc.Options()
    values = dict(kf_verify_dense_max_dofs=0, **options)
    for k, v in values.items():
        opts.setValue(k, v)
    try:
        reducer = kryflex.Reducer(kryflex.load_scene(path), quiet=True, search=False)
        reducer.reduce()
    finally:
        for k in values:
            opts.delValue(k)
    return reducer


def seeded_count(reducer):
    if "reference_eigensolves_seeded" not in reducer.result_names(-1):
        return 0
    return int(np.ravel(reducer.result(-1, "reference_eigensolves_seeded"))[0])


@pytest.mark.parametrize("massless", [False, True], ids=["free", "massless"])
def test_seeded_against_dense_and_from_scratch(tmp_path, massless):
    path = frame(tmp_path, massless)
    # the frame's Ritz pairs gain a factor of 15 to 20 a block step (the 57k solid's 30 to 60): 8 steps, not the
    # default's 3, so that every reference after the second is seeded
    seeded, plain = reduce_sparse(path, kf_verify_seed_steps=8), reduce_sparse(path, kf_verify_seeded=0)
    assert seeded_count(plain) == 0
    assert seeded_count(seeded) >= 4, seeded_count(seeded)     # the 3rd and 4th angles, two of the midpoints
    dense = ref.load_scene(path)
    for c, angles in enumerate(seeded.configurations):
        fs, fp = np.ravel(seeded.result(c, "full_frequencies_hz")), np.ravel(plain.result(c, "full_frequencies_hz"))
        f_dense = dense_flexible_frequencies(*ref.assemble(dense, angles)[:2])
        Ts, Tp = seeded.frf(c, "full"), plain.frf(c, "full")
        d_plain, d_dense = np.abs(fs / fp - 1).max(), np.abs(fs / f_dense[:fs.size] - 1).max()
        d_frf = np.abs(Ts - Tp).max() / np.abs(Tp).max()
        print("configuration %d: %d modes; seeded vs from scratch %.1e, vs dense SciPy %.1e; reference response "
              "%.1e of the peak" % (c, fs.size, d_plain, d_dense, d_frf))
        assert fs.size == fp.size > 0
        assert d_plain <= 1e-9 and d_dense <= 1e-8
        assert d_frf <= 1e-7
    e_s, e_p = float(np.ravel(seeded.result(-1, "error_max"))[0]), float(np.ravel(plain.result(-1, "error_max"))[0])
    assert e_s == pytest.approx(e_p, rel=1e-6)


@pytest.mark.mpi
def test_seeded_two_ranks_agree_with_one(tmp_path):
    path = frame(tmp_path, False)
    serial = reduce_sparse(path, kf_verify_seed_steps=8)
    assert seeded_count(serial) >= 4
    out = tmp_path / "two.npz"
    p = subprocess.run(["mpiexec", "-n", "2", sys.executable, PROBE, path, str(out), "-kf_verify_seed_steps", "8"],
                       env=ENV, capture_output=True, text=True, timeout=240)
    assert p.returncode == 0, p.stdout + p.stderr[-3000:]
    two = np.load(out)
    for c in range(len(serial.configurations)):
        f1, f2 = np.ravel(serial.result(c, "full_frequencies_hz")), two["f%d" % c]
        T1, T2 = serial.frf(c, "full"), two["T%d" % c]
        print("configuration %d: 2 ranks vs 1: frequencies %.1e, reference response %.1e of the peak"
              % (c, np.abs(f2 / f1 - 1).max(), np.abs(T2 - T1).max() / np.abs(T1).max()))
        assert f1.size == f2.size > 0 and np.allclose(f2, f1, rtol=1e-9, atol=0)
        assert np.abs(T2 - T1).max() <= 1e-8 * np.abs(T1).max()
