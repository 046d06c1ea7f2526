"""kryflex's dense verification eigensolve (M definite, rigid modes known) against an extended-precision one (mpmath,
40 digits) of the same K_S and M_S: each of the lowest flexible eigenvalues to 1e-12 of itself and each mode's
participation (H phi)(phi^T G) to 1e-8 of the largest (7e-9 measured on spread-1e-5, 2026-11-30), on Galileo (first flexible eigenvalue 3e-9 of the largest) and
the spread-1e-5 stress scene (7e-14 of it), serially and on 2 ranks (which number the system's dofs differently). A
Householder eigensolve of the pencil knows those eigenvalues to eps lam_max only: Galileo's first to 2e-8 of itself,
which moved a reference near that resonance by 4e-6 of the peak between 1 and 2 ranks."""
import os
import subprocess
import sys

import mpmath as mp
import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
SUPPORT = os.path.join(os.path.dirname(HERE), "support")
sys.path.insert(0, SUPPORT)
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
ROOT = run_env.ROOT
PROBE = os.path.join(SUPPORT, "dense_relative_probe.py")
GALILEO = os.path.join(ROOT, "meshes", "galileo", "galileo.yaml")
ENV = dict(run_env.ENV, PYTHONPATH=run_env.PACKAGE)
from rank_runs import probe_on_ranks  # noqa: E402
LOWEST = 6


@pytest.fixture(scope="module")
def scenes(tmp_path_factory):
    out = str(tmp_path_factory.mktemp("stress_scenes"))
    subprocess.run([sys.executable, os.path.join(ROOT, "meshes", "stress.py"), "--out", out], check=True,
                   capture_output=True, timeout=120)
    return {"galileo": GALILEO, "spread-1e-5": os.path.join(out, "spread-1e-5", "scene.yaml")}


def probe(path, out, ranks):
    probe_on_ranks([sys.executable, PROBE, path, str(out)], ranks, ENV, timeout=120)
    return np.load(out)


def extended(K, M, G, H, nrigid):
    """The flexible eigenvalues (ascending) and participations of (K, M) in 40-digit arithmetic: M = L L^T,
    L^-1 K L^-T's eigenpairs; the nrigid smallest eigenvalues are the rigid modes'."""
    mp.mp.dps = 40
    L = mp.cholesky(mp.matrix(K.shape[0], K.shape[0]) + mp.matrix(M.tolist()))
    Li = mp.inverse(L)
    A = Li * mp.matrix(K.tolist()) * Li.T
    A = (A + A.T) / 2
    E, Q = mp.eigsy(A)
    order = sorted(range(len(E)), key=lambda i: E[i])[nrigid:]
    X = Li.T * Q
    lam = np.array([float(E[i]) for i in order])
    part = []
    for i in order:
        x = X[:, i]
        part.append(float((mp.matrix(H.tolist()) * x)[0] * (x.T * mp.matrix(G.tolist()))[0]))
    return lam, np.array(part)


@pytest.mark.parametrize("ranks", [1, pytest.param(2, marks=pytest.mark.mpi)])
@pytest.mark.parametrize("name", ["galileo", "spread-1e-5"])
def test_lowest_modes_to_their_own_accuracy(scenes, name, ranks, tmp_path):
    d = probe(scenes[name], tmp_path / "p.npz", ranks)
    n = d["K"].shape[0]
    nflex = len(d["w2"])
    lam, part = extended(d["K"], d["M"], d["G"][:, :1], d["H"][:1, :], n - nflex)
    got = d["w2"][:LOWEST]
    np.testing.assert_allclose(got, lam[:LOWEST], rtol=1e-12, atol=0)
    mine = d["HPhi"][0, :] * d["PhiG"][:, 0]
    assert np.abs(mine[:LOWEST] - part[:LOWEST]).max() <= 1e-8 * np.abs(part).max(), (mine[:LOWEST], part[:LOWEST])
