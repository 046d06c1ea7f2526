"""The model check's symmetry defect ||A - A^T||_F / ||A||_F (kryflex.check._asymmetry) against NumPy's, on AIJ and
dense matrices: an exactly symmetric one (0, found by MatIsSymmetric without forming A - A^T), entries whose partner
differs by round-off and by more, and an entry without a partner (a pattern that is not symmetric)."""
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "support"))
from reference import petsc_matrix  # noqa: E402

import kryflex  # noqa: E402
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)


def symmetric(n=18, seed=3):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n)) * (rng.random((n, n)) < 0.3)
    return A + A.T + n * np.eye(n)


def cases():
    S = symmetric()
    off = S.copy()
    i, j = np.argwhere(np.triu(S, 1) != 0)[0]
    off[i, j] *= 1 + 1e-13
    big = S.copy()
    big[5, 11] += 0.5
    lone = S.copy()
    lone[3, 14], lone[14, 3] = 0.7, 0.0
    return {"symmetric": S, "round-off": off, "partner differs": big, "no partner": lone}


@pytest.mark.fast
@pytest.mark.parametrize("name", list(cases()))
@pytest.mark.parametrize("dense", [False, True])
def test_asymmetry_matches_numpy(name, dense):
    kryflex.init()
    from kryflex.check import _asymmetry
    A = cases()[name]
    want = np.linalg.norm(A - A.T) / np.linalg.norm(A)
    got = _asymmetry(petsc_matrix(A, dense=dense))
    if name == "symmetric":
        assert want == 0.0 and got == 0.0
    else:
        assert want > 0 and got == pytest.approx(want, rel=1e-10)


def main():
    """Under mpiexec: each case's measure on rank 0's standard output, one line 'name value'."""
    kryflex.init()
    from petsc4py import PETSc
    from kryflex.check import _asymmetry
    for name, A in cases().items():
        got = _asymmetry(petsc_matrix(A))
        if PETSc.COMM_WORLD.getRank() == 0:
            print(name, repr(got), flush=True)


@pytest.mark.mpi
def test_asymmetry_matches_numpy_two_ranks():
    import subprocess
    env = dict(run_env.ENV, PYTHONPATH=run_env.PACKAGE)
    p = subprocess.run(["mpiexec", "-n", "2", sys.executable, os.path.abspath(__file__)], env=env, capture_output=True,
                       text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    got = {line.rsplit(" ", 1)[0]: float(line.rsplit(" ", 1)[1]) for line in p.stdout.splitlines() if line.strip()}
    for name, A in cases().items():
        want = np.linalg.norm(A - A.T) / np.linalg.norm(A)
        assert got[name] == pytest.approx(want, rel=1e-10, abs=0.0), name


if __name__ == "__main__":
    main()
