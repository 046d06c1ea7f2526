"""CSystem.eigen_modes asked for more modes than the system has (nev = its dofs, beyond the flexible modes' count)
returns the flexible modes that exist, the same as when asked for exactly that count, checked against a dense SciPy
solve of the gathered pencil: Galileo (28 dofs, 7 rigid and mechanism modes), serially and on 2 ranks."""
import os
import sys

import numpy as np
import pytest
import scipy.linalg as sl

HERE = os.path.dirname(os.path.abspath(__file__))
SUPPORT = os.path.join(os.path.dirname(HERE), "support")
sys.path.insert(0, SUPPORT)
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
ROOT = run_env.ROOT
PROBE = os.path.join(SUPPORT, "eigen_modes_probe.py")
GALILEO = os.path.join(ROOT, "meshes", "galileo", "galileo.yaml")
ENV = dict(run_env.ENV, PYTHONPATH=run_env.PACKAGE)
from rank_runs import probe_on_ranks  # noqa: E402


@pytest.mark.parametrize("ranks", [1, pytest.param(2, marks=pytest.mark.mpi)])
def test_more_modes_than_exist(ranks, tmp_path):
    probe_on_ranks([sys.executable, PROBE, GALILEO, str(tmp_path / "p.npz")], ranks, ENV, timeout=120)
    d = np.load(tmp_path / "p.npz")
    K, M = d["K"], d["M"]
    n, nflex = K.shape[0], len(d["w2_all"])
    lam = sl.eigh(0.5 * (K + K.T), 0.5 * (M + M.T), eigvals_only=True)
    assert nflex == n - int(d["nrigid"]) and nflex < n
    assert d["modes_all"].shape == (n, nflex)
    np.testing.assert_array_equal(d["w2_all"], d["w2_count"])
    np.testing.assert_array_equal(d["modes_all"], d["modes_count"])
    # the flexible eigenvalues: SciPy knows them to eps of the largest
    np.testing.assert_allclose(d["w2_all"], lam[n - nflex:], rtol=0, atol=1e-10 * lam.max())
    X = d["modes_all"]
    np.testing.assert_allclose(X.T @ M @ X, np.eye(nflex), atol=1e-10)
    R = K @ X - M @ X * d["w2_all"]
    assert np.abs(R).max() <= 1e-9 * np.abs(K).max()
