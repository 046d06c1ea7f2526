"""The full-order moments at an angle of interest taken from its own Krylov basis (src/reducer/full_moments.c).

With verification on, the moments L^k = H (K+ M)^k K+ G at each angle of interest (the reference's residual takes
L^0 and L^1, the moment checks all of them) but L^0 come from the projected pencil of that angle's undeflated Krylov
basis, which matches the full order's first moments exactly (Galerkin), instead of one block solve per moment; L^0 is
solved either way (test_static_moment_reference.py); -kf_full_moments asks for the solves. Checked on Galileo with the sparse reference path (which uses L^0 and L^1):

- the basis's moments are the solved ones to 1e-8 (every moment the search builds), and both are the dense NumPy
  moments of tests/python/support/reference.py (assembled from the files) to 1e-6;
- the same model and error, the same reference check, fewer columns through the factor;
- the same with the rotor clamped and with Rayleigh damping; a deflated basis (24 moments of the 33-dof Galileo) takes
  the solves, with the same result;
- 2 ranks give the serial moments and error.
"""
import os
import sys

import numpy as np
import pytest

import kryflex

HERE = os.path.dirname(os.path.abspath(__file__))
SUPPORT = os.path.join(os.path.dirname(HERE), "support")
sys.path.insert(0, SUPPORT)
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
ROOT = run_env.ROOT
GALILEO = os.path.join(ROOT, "meshes", "galileo", "galileo.yaml")
ENV = dict(run_env.ENV, MPLBACKEND="Agg")
import reference as ref  # noqa: E402
from rank_runs import results_on_ranks  # noqa: E402

pytestmark = pytest.mark.usefixtures("quiet_library")

SAME_RTOL = 1e-8     # basis against solves: both carry the block solves' error (Galileo: 1e-10 to 1e-9 measured)
DENSE_RTOL = 1e-6    # against the dense NumPy moments of another assembly (2e-8 to 5e-8 measured, either way)


def scalar(reducer, name, config=-1):
    return float(np.ravel(reducer.result(config, name))[0])


def reduce(**opts):
    scene = kryflex.load_scene(GALILEO)
    reducer = kryflex.Reducer(scene, quiet=True, verify_dense_max_dofs=0, **opts)
    reducer.reduce()
    return scene, reducer


@pytest.fixture(scope="module")
def runs():
    return {"basis": reduce(), "solved": reduce(full_moments=True)}


def rel(a, b):
    return np.linalg.norm(a - b) / np.linalg.norm(b)


@pytest.mark.fast
def test_basis_moments_are_the_solved_and_dense_ones(runs):
    scene, rb = runs["basis"]
    _, rs = runs["solved"]
    rscene = ref.load_scene(GALILEO)
    for c, angles in enumerate(scene.configurations):
        Lb, Ls = rb.moments(c, "full_moments"), rs.moments(c, "full_moments")
        assert Lb.shape == Ls.shape and Lb.shape[0] >= 2
        Ms, Ks, Gs, Hs = ref.assemble(rscene, angles)
        Lr = ref.moments(Ms, Ks, Gs, Hs, Lb.shape[0])
        for k in range(Lb.shape[0]):
            print(c, k, "basis vs solved %.1e, basis vs dense %.1e, solved vs dense %.1e" % (
                rel(Lb[k], Ls[k]), rel(Lb[k], Lr[k]), rel(Ls[k], Lr[k])))
            assert rel(Lb[k], Ls[k]) <= SAME_RTOL, (c, k)
            assert rel(Lb[k], Lr[k]) <= DENSE_RTOL, (c, k)


@pytest.mark.fast
def test_same_verdict_fewer_solves(runs):
    _, rb = runs["basis"]
    _, rs = runs["solved"]
    # errors are fractions of a pair's peak; the two references differ by the moments' solve error (~1e-10 of them)
    assert scalar(rb, "error_max") == pytest.approx(scalar(rs, "error_max"), abs=1e-9)
    assert scalar(rb, "reference_check_error") <= 1e-9 and scalar(rs, "reference_check_error") <= 1e-9
    assert scalar(rb, "reference_check_fallbacks") == scalar(rs, "reference_check_fallbacks") == 0
    # every block of the moments at the angles of interest but L^0's is gone (L^0 and K+ G, the reference check's
    # first step, are solved either way): nfull - 1 blocks of a columns per angle, each refined by one step (-kf_refine
    # 1) as every reference solve is; the midpoints solve theirs in both runs
    nfull, _, a = rb.moments(0, "full_moments").shape
    saved = scalar(rs, "solve_columns") - scalar(rb, "solve_columns")
    assert saved == len(rb.configurations) * 2 * (nfull - 1) * a, saved


@pytest.mark.fast
@pytest.mark.parametrize("case, moments", [("clamped", 10), ("rayleigh", 10), ("clamped", None)])
def test_basis_moments_clamped_damped_deflated(case, moments):
    """The rotor clamped (held dofs), or Rayleigh damping (the undamped moments still: the basis is the plain
    recurrence), with Galileo's 10 moments: the basis's moments are the solved ones, the same error and check, fewer
    columns solved. With the search's default 24 moments the 33-dof Galileo's Krylov space is exhausted and its basis
    deflated: the moments are then solved for (the same columns as -kf_full_moments), and the same."""
    sys.path.insert(0, HERE)
    import test_damping as td
    import test_direct_check_bodywise as tdb
    spec = td.galileo_spec({"modal": 0.002} if case == "clamped" else
                           {"modal": 0.0, "rayleigh": {"alpha": 0.02, "beta": 2e-5}})
    if case == "clamped":
        for name, clamps_b in tdb.CLAMPS.items():
            spec["bodies"][name]["constraints"] = clamps_b
    if moments:
        spec["reduction"] = {"moments_max": moments}
    runs = {}
    for way, opts in (("basis", {}), ("solved", {"full_moments": True})):
        r = kryflex.Reducer(kryflex.scene_from_dict(spec), quiet=True, verify_dense_max_dofs=0, **opts)
        r.reduce()
        runs[way] = r
    rb, rs = runs["basis"], runs["solved"]
    deflated = sum(scalar(rb, "krylov_deflations", c) for c in range(len(rb.configurations)))
    for c in range(len(rb.configurations)):
        Lb, Ls = rb.moments(c, "full_moments"), rs.moments(c, "full_moments")
        worst = max(rel(Lb[k], Ls[k]) for k in range(Lb.shape[0]))
        print(case, moments, c, "basis vs solved, worst of %d moments %.1e, deflated %d" % (Lb.shape[0], worst, deflated))
        assert worst <= SAME_RTOL, c
    # errors are fractions of a pair's peak; the two references differ by the moments' solve error (~1e-10 of them)
    assert scalar(rb, "error_max") == pytest.approx(scalar(rs, "error_max"), abs=1e-9)
    assert scalar(rb, "reference_check_error") <= 1e-9 and scalar(rb, "reference_check_fallbacks") == 0
    if moments:
        assert deflated == 0 and scalar(rb, "solve_columns") < scalar(rs, "solve_columns")
    else:
        assert deflated > 0 and scalar(rb, "solve_columns") == scalar(rs, "solve_columns")


TWO_RANKS = r"""
import json, numpy as np, kryflex
r = kryflex.Reducer(kryflex.load_scene(%(galileo)r), quiet=True, verify_dense_max_dofs=0)
r.reduce()
L = np.concatenate([np.ravel(r.moments(c, "full_moments")) for c in range(len(r.configurations))])
from mpi4py import MPI
if MPI.COMM_WORLD.rank == 0:
    print("RESULT " + json.dumps({"L": L.tolist(), "error": float(np.ravel(r.result(-1, "error_max"))[0])}))
"""


@pytest.mark.mpi
def test_two_ranks_same_moments(tmp_path):
    results = results_on_ranks(TWO_RANKS % {"galileo": GALILEO}, tmp_path, ENV)
    one, two = (np.array(r["L"]) for r in results)
    print("2 ranks vs 1: moments %.2e" % (np.abs(one - two).max() / np.abs(one).max()))
    assert np.abs(one - two).max() <= SAME_RTOL * np.abs(one).max()
    assert results[1]["error"] == pytest.approx(results[0]["error"], rel=1e-6)
