"""The verification's direct check solved body-wise (src/verify/direct_check.c).

With -kf_verify_check_method direct (the iterative check, the default, factors nothing: test_refined_check.py), the
check frequencies are common to every angle of interest and midpoint; undamped (or modal ratios only) on a
free-free jointed scene, each frequency's K_b - w^2 M_b is factored once per body and every angle's jointed system is
solved from those factors with its own small interface problem (src/solve/impls/bodywise). Checked here against
independent dense solves (NumPy/SciPy, nothing from kryflex's numerics):

- Galileo (2 bodies, free-free, modal ratios): the check's truth equals the dense solve (rigid part exact, flexible
  part on the M-orthogonal complement of the geometric rigid modes) at every angle, to 1e-10 of the pair's peak, and equals
  the whole-system factorization's truth (-kf_verify_check_bodywise false); 3 x 2 body factorizations in place of
  3 x 3 whole-system ones;
- Galileo with its rotor clamped (modal ratios): the body-wise solve does not take clamps, the whole system is
  factored per point and frequency as before, and its truth is the dense solve's to 1e-10;
- Galileo with Rayleigh damping: the 2 x 2 block form at the common frequencies (test_damped_check.py checks its
  truth against dense solves);
- a reference left incomplete (the sparse path with 2 modes) fails with exit 3 naming the frequency and the angle,
  serially and on 2 ranks; 2 ranks give the serial truth and verdict.
"""
import os
import subprocess
import sys

import numpy as np
import pytest
import scipy.linalg as sl

import kryflex

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import test_damping as td  # noqa: E402
import test_damped_check as tdc  # noqa: E402
from rank_runs import results_on_ranks  # noqa: E402

pytestmark = pytest.mark.usefixtures("quiet_library")
EXIT_NOT_CONVERGED = 3
PAIR_FLOOR = 1e-4   # KF_FRF_PAIR_FLOOR


def reduce(spec, **options):
    """The check by factorizations (the iterative one, the default, factors nothing: test_refined_check.py)."""
    options.setdefault("verify_check_method", "direct")
    reducer = kryflex.Reducer(kryflex.scene_from_dict(spec), quiet=True, **options)
    reducer.reduce()
    return reducer


def scalar(reducer, name, c=-1):
    return float(np.ravel(reducer.result(c, name))[0])


def pair_scale(reducer, c):
    peak = np.abs(reducer.frf(c, "full")).max(axis=0)
    return np.maximum(peak, PAIR_FLOOR * peak.max())


def dense_truth(Ms, Ks, Gs, Hs, R, freqs_hz):
    """The truth as kryflex defines the model, solved densely without its cancellation: the rigid part exact,
    -H R R^T G / w^2 (R the rigid modes, M-orthonormalized here), and the flexible part H Q (Q^T K Q - w^2 Q^T M Q)^-1
    Q^T G on a basis Q of the M-orthogonal complement of R (SVD null space of R^T M): it equals
    H P (K' - w^2 M)^-1 P^T G with P = I - R R^T M, K' = P^T K P, without the near-singular rigid directions."""
    R = R @ np.linalg.inv(np.linalg.cholesky(R.T @ Ms @ R)).T
    Q = sl.null_space((Ms @ R).T)
    Kq, Mq, Gq, Hq = Q.T @ Ks @ Q, Q.T @ Ms @ Q, Q.T @ Gs, Hs @ Q
    HR, RG = Hs @ R, R.T @ Gs
    return np.array([Hq @ np.linalg.solve(Kq - w**2 * Mq, Gq) - HR @ RG / w**2 for w in 2 * np.pi * np.asarray(freqs_hz)])


CLAMPS = {"rotor": [{"node": n, "dofs": "123"} for n in (103, 104, 105)]}   # the rotor held at 3 points


def galileo_truth(angles, freqs_hz, clamps=None):
    """Galileo assembled by tests/python/support/reference.py (its clamps as constraint rows here), its rigid and
    mechanism modes from geometry: the bodies' rigid modes that satisfy every constraint."""
    scene = td.ref.load_scene(td.GALILEO)
    rows = [td.ref.constraint_matrix(scene, angles)]
    for name, clamps_b in (clamps or {}).items():
        b = scene.body_index(name)
        for c in clamps_b:
            for k in c["dofs"]:
                row = np.zeros(scene.offsets[-1])
                row[scene.offsets[b] + scene.bodies[b].dof(c["node"], int(k) - 1)] = 1.0
                rows.append(row[None, :])
    C = np.vstack(rows)
    P = td.ref.null_space_svd(C)
    M = td.sp.block_diag([b.M for b in scene.bodies]).toarray()
    K = td.sp.block_diag([b.K for b in scene.bodies]).toarray()
    G, H = td.ref.body_io(scene)
    B = sl.block_diag(*[td.ref.body_rigid_modes(scene, b) for b in range(len(scene.bodies))])
    R = P.T @ (B @ sl.null_space(C @ B))
    Ms, Ks = P.T @ M @ P, P.T @ K @ P
    return dense_truth(0.5 * (Ms + Ms.T), 0.5 * (Ks + Ks.T), P.T @ G, H @ P, R, freqs_hz)


@pytest.mark.fast
def test_bodywise_truth_is_the_dense_solve():
    """Galileo with modal ratios: the body-wise truth is the dense undamped solve, and the whole-system truth."""
    spec = td.galileo_spec({"modal": 0.002})
    bodywise, whole = reduce(spec), reduce(spec, verify_check_bodywise=False)
    nconf, npts, nbodies = len(bodywise.configurations), 3, 2
    npoints = 2 * nconf - 1                                   # the angles of interest and the midpoints
    assert scalar(bodywise, "reference_check_factorizations") == npts * nbodies
    assert scalar(whole, "reference_check_factorizations") == npts * npoints
    first = None
    for c, angles in enumerate(bodywise.configurations):
        f, truth, reference = tdc.check_sides(bodywise, c)
        f_whole, truth_whole, _ = tdc.check_sides(whole, c)
        first = f if first is None else first
        assert len(f) == npts and np.array_equal(f, first)     # one set of frequencies for every angle
        assert np.array_equal(f, f_whole)
        dense = galileo_truth(angles, f)
        scale = pair_scale(bodywise, c)
        agree = float((np.abs(truth - dense) / scale).max())
        same = float((np.abs(truth - truth_whole) / scale).max())
        print("%s deg at %s Hz: body-wise vs dense %.2e, vs whole-system %.2e, reference %.2e" % (
            angles, np.round(f, 4), agree, same, scalar(bodywise, "reference_check_error", c)))
        assert np.abs(truth.imag).max() == 0                   # undamped: the ratios are out of both sides
        assert agree <= 1e-10
        assert same <= 1e-10
        assert scalar(bodywise, "reference_check_error", c) <= 1e-6
    assert scalar(bodywise, "reference_check_residual") <= 1e-13   # the backward error taken without a fallback


@pytest.mark.fast
def test_clamped_scene_keeps_the_whole_system_solve():
    """Galileo's rotor clamped (the stator's rotation about the bearing its one mechanism): the body-wise solve does
    not take clamps, so every point's system is factored per frequency (as before); the truth is the dense solve's."""
    spec = td.galileo_spec({"modal": 0.002})
    for name, clamps_b in CLAMPS.items():
        spec["bodies"][name]["constraints"] = clamps_b
    reducer = reduce(spec)
    nconf = len(reducer.configurations)
    assert scalar(reducer, "reference_check_factorizations") == 3 * (2 * nconf - 1)
    for c, angles in enumerate(reducer.configurations):
        f, truth, _ = tdc.check_sides(reducer, c)
        dense = galileo_truth(angles, f, CLAMPS)
        agree = float((np.abs(truth - dense) / pair_scale(reducer, c)).max())
        print("%s deg: whole-system vs dense %.2e" % (angles, agree))
        assert agree <= 1e-10
        assert scalar(reducer, "reference_check_error", c) <= 1e-6


def test_rayleigh_takes_the_block_form_at_common_frequencies():
    """Rayleigh damping: the 2 x 2 block form per point and frequency (its truth: test_damped_check.py), the same
    frequencies at every angle, the verdict given."""
    reducer = reduce(td.galileo_spec({"modal": 0.0, "rayleigh": {"alpha": 0.02, "beta": 2e-5}}))
    freqs = [tdc.check_sides(reducer, c)[0] for c in range(len(reducer.configurations))]
    assert all(np.array_equal(f, freqs[0]) for f in freqs)
    assert scalar(reducer, "reference_check_factorizations") == 3 * (2 * len(freqs) - 1)
    for c in range(len(freqs)):
        _, truth, _ = tdc.check_sides(reducer, c)
        assert np.abs(truth.imag).max() > 1e-6 * np.abs(truth).max()
        assert scalar(reducer, "reference_check_error", c) <= 1e-6


@pytest.mark.skipif(not os.path.exists(td.KRYFLEX), reason="build/kryflex not built")
@pytest.mark.parametrize("ranks", [1, pytest.param(2, marks=pytest.mark.mpi)])
def test_incomplete_reference_is_exit_3(tmp_path, ranks):
    """Galileo's reference on the sparse path with 2 modes, checked body-wise: exit 3, one message naming the
    frequency and the angle, no traceback, on every rank."""
    cmd = [td.KRYFLEX, "reduce", td.GALILEO, "-o", str(tmp_path / "out"), "-quiet", "-kf_verify_dense_max_dofs", "0",
           "-kf_verify_modes", "2"]
    if ranks > 1:
        cmd = ["mpiexec", "-n", str(ranks)] + cmd
    p = subprocess.run(cmd, env=td.ENV, capture_output=True, text=True, timeout=300)
    print(p.returncode, p.stderr[-1500:])
    assert p.returncode == EXIT_NOT_CONVERGED
    assert "Traceback" not in p.stderr
    assert "disagrees with a direct solve" in p.stderr and " Hz " in p.stderr and "deg" in p.stderr


TWO_RANKS = r"""
import json, sys
sys.path.insert(0, %(here)r)
import numpy as np, kryflex
import test_damping as td
r = kryflex.Reducer(kryflex.scene_from_dict(td.galileo_spec({"modal": 0.002})), quiet=True,
                    verify_check_method="direct")
r.reduce()
T = np.concatenate([np.ravel(r.result(c, "reference_check_truth_re")) for c in range(r.nconfig)])
e = [float(np.ravel(r.result(c, "reference_check_error"))[0]) for c in range(r.nconfig)]
n = float(np.ravel(r.result(-1, "reference_check_factorizations"))[0])
from mpi4py import MPI
if MPI.COMM_WORLD.rank == 0:
    print("RESULT " + json.dumps({"truth": T.tolist(), "error": e, "factorizations": n}))
"""


@pytest.mark.mpi
def test_two_ranks_same_truth_and_verdict(tmp_path):
    """2 ranks (each body factored on its own rank): the body-wise truth and the verdict as on 1 rank."""
    results = results_on_ranks(TWO_RANKS % {"here": HERE}, tmp_path, td.ENV)
    one, two = (np.array(r["truth"]) for r in results)
    print("2 ranks vs 1: truth %.2e, errors %s %s" % (np.abs(one - two).max() / np.abs(one).max(),
                                                     results[0]["error"], results[1]["error"]))
    assert results[0]["factorizations"] == results[1]["factorizations"] == 6
    assert np.abs(one - two).max() <= 1e-10 * np.abs(one).max()
    assert max(results[1]["error"]) <= 1e-6 and max(results[0]["error"]) <= 1e-6
