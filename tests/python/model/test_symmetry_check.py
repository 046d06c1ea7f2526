"""The symmetry check of body matrices (KFMatCheckSymmetric, src/body/load.c) against NumPy.

The check measures ||A - A^T||_F / ||A||_F in one pass over A's entries (no transpose built): each entry against its
transposed partner, an entry without a partner (above or below the diagonal) counted for both positions it fills in
A - A^T, and on several ranks the couplings between ranks against their transpose.  Its refusal message prints the
measured ratio; here that figure is compared with the ratio NumPy computes from the dense matrix, for an entry whose
partner differs, entries without a partner, and both across the ranks' boundary (2 ranks); a symmetric matrix with a
rounding-level difference passes, and only an exactly symmetric one is recorded as such (the model check reads that
instead of comparing the matrix with its transpose again).

    mpiexec -n 2 python tests/python/model/test_symmetry_check.py CASE   (the 2-rank half: prints the ratio or "ok")
"""
import os
import re
import subprocess
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "support"))
from reference import petsc_matrix  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
ROOT = run_env.ROOT
MPI_ENV = dict(run_env.ENV, PYTHONPATH=run_env.PACKAGE)
N = 24  # 4 nodes of 6 dofs: on 2 ranks, rows 0-11 and 12-23


def stiffness(case):
    """A dense SPD matrix (a few structural zeros), made asymmetric as the case says."""
    rng = np.random.default_rng(7)
    A = rng.standard_normal((N, N))
    K = A @ A.T
    K[3, 20] = K[20, 3] = 0.0       # structural zeros: (3, 20) is where a partnerless entry goes
    K[5, 7] = K[7, 5] = 0.0
    K[22, 23] = K[23, 22] = 0.0
    if case == "value":             # a partner with another value, both rows on one rank
        K[2, 9] += 1e-4
    elif case == "partnerless":     # an entry whose transposed position is empty, one rank
        K[5, 7] = 3e-4
    elif case == "partnerless_lower":  # below the diagonal: one stepped over, one in the last row left at the end
        K[7, 5] = 3e-4
        K[23, 22] = 2e-4
    elif case == "value_across":    # across the ranks' boundary (row 1 on rank 0, column 18 on rank 1)
        K[1, 18] += 2e-4
    elif case == "partnerless_across":
        K[3, 20] = 5e-4
    elif case == "all":
        K[2, 9] += 1e-4
        K[5, 7] = 3e-4
        K[1, 18] += 2e-4
        K[3, 20] = 5e-4
        K[7, 5] = 1e-4
        K[23, 22] = 2e-4
    elif case == "rounding":        # 1e-14 relative: symmetric as far as the check is concerned
        K[1, 18] *= 1 + 1e-14
    return K


def measured_ratio(case, exact=None):
    """The ratio the check reports (None when it accepts the matrix); exact: a list given the set-up's (M, K) found
    exactly symmetric, when it accepts."""
    from kryflex import _core
    s = _core.CScene()
    b = s.add_body("plate", petsc_matrix(np.eye(N)), petsc_matrix(stiffness(case)), [1, 2, 3, 4],
                   np.arange(12.0).reshape(4, 3),
                   [6, 6, 6, 6])
    s.set_num_io(1, 1)
    s.add_input_load(0, b, 1, 0)
    s.add_output_reading(0, b, 4, 0)
    try:
        s.setup()
    except _core.Error as e:
        found = re.search(r"stiffness matrix K of body 'plate' is not symmetric: \|\|A - A\^T\|\| / \|\|A\|\| = (\S+) ",
                          str(e))
        assert found, str(e)
        return float(found.group(1))
    if exact is not None:
        exact.extend(s.body_symmetric(b))
    return None


def numpy_ratio(case):
    K = stiffness(case)
    return np.linalg.norm(K - K.T) / np.linalg.norm(K)


ASYMMETRIC = ["value", "partnerless", "partnerless_lower", "value_across", "partnerless_across", "all"]


@pytest.mark.parametrize("case", ASYMMETRIC)
def test_ratio_matches_numpy_serial(case):
    # the message prints %g: 6 significant digits
    assert measured_ratio(case) == pytest.approx(numpy_ratio(case), rel=1e-5)


def test_symmetric_within_tolerance_passes():
    assert 0 < numpy_ratio("rounding") < 1e-10
    exact = []
    assert measured_ratio("rounding", exact) is None
    # accepted, but not exactly symmetric: the model check then measures the defect itself (kryflex.check._asymmetry)
    assert exact == [True, False]


def test_exactly_symmetric_found_at_setup():
    K = stiffness("none")
    assert np.array_equal(K, K.T)
    exact = []
    assert measured_ratio("none", exact) is None
    assert exact == [True, True]


def mass_like(K):
    """A mass matrix with K's nonzero pattern (a body's consistent M and K): symmetric where the pattern is."""
    return np.where(K != 0, 1.0 + 0.5 * (np.abs(K) + np.abs(K.T)), 0.0)


@pytest.mark.parametrize("case", ASYMMETRIC + ["rounding", "none"])
def test_mass_and_stiffness_of_one_pattern_walked_together(case):
    """M and K of the same nonzero pattern are measured in one walk (KFMatCheckSymmetricPairExact): each verdict is
    the one NumPy's ratios give, M judged first (its message names M, then K's names K), and where both pass the
    exact flags say which is exactly symmetric."""
    from kryflex import _core
    K = stiffness(case)
    M = mass_like(K)
    s = _core.CScene()
    b = s.add_body("plate", petsc_matrix(M), petsc_matrix(K), [1, 2, 3, 4], np.arange(12.0).reshape(4, 3), [6, 6, 6, 6])
    s.set_num_io(1, 1)
    s.add_input_load(0, b, 1, 0)
    s.add_output_reading(0, b, 4, 0)
    ratios = {key: np.linalg.norm(A - A.T) / np.linalg.norm(A) for key, A in (("M", M), ("K", K))}
    bad = [key for key in ("M", "K") if ratios[key] > 1e-10]
    if bad:
        with pytest.raises(_core.Error) as e:
            s.setup()
        what = "mass matrix M" if bad[0] == "M" else "stiffness matrix K"
        found = re.search(r"%s of body 'plate' is not symmetric: \|\|A - A\^T\|\| / \|\|A\|\| = (\S+) " % what, str(e.value))
        assert found, str(e.value)
        assert float(found.group(1)) == pytest.approx(ratios[bad[0]], rel=1e-5)
    else:
        s.setup()
        assert list(s.body_symmetric(b)) == [ratios["M"] == 0, ratios["K"] == 0]


@pytest.mark.mpi
@pytest.mark.parametrize("case", ASYMMETRIC + ["rounding", "none"])
def test_ratio_matches_numpy_two_ranks(case):
    out = subprocess.run(["mpiexec", "-n", "2", sys.executable, os.path.abspath(__file__), case], env=MPI_ENV,
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    lines = [ln for ln in out.stdout.split("\n") if ln.startswith("ratio ")]
    assert len(lines) == 2, out.stdout        # both ranks answer, with the same verdict
    values = {ln.split(None, 1)[1] for ln in lines}
    assert len(values) == 1, lines
    got = values.pop()
    if case in ("rounding", "none"):
        # accepted; K exactly symmetric only without the rounding-level difference across the ranks' boundary
        assert got == "ok %s" % ("exact" if case == "none" else "inexact")
    else:
        assert float(got) == pytest.approx(numpy_ratio(case), rel=1e-5)


if __name__ == "__main__":
    sys.path.insert(0, os.path.join(ROOT, "python"))
    import petsc4py
    petsc4py.init(sys.argv[:1])
    exact = []
    r = measured_ratio(sys.argv[1], exact)
    verdict = "ok %s" % ("exact" if exact == [True, True] else "inexact")
    sys.stdout.write("ratio %s\n" % (verdict if r is None else repr(r)))  # one write per rank: lines stay whole
    sys.stdout.flush()
