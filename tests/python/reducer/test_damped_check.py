"""The direct check of the full-order reference under the damping in use (src/verify/damped_check.c).

At a few frequencies per angle kryflex solves the full system directly and compares its reference with it. With
Rayleigh, structural damping or the bodies' damping matrices that solve is the real 2 x 2 block form of the complex
system (MUMPS LU); modal ratios, defined by the reference's own modes, are taken out of both sides. Checked here on
Galileo against dense_truth (SciPy, the damped system solved densely, its rigid modes from the node files, nothing
from kryflex): the
check's truth equals the dense damped solve of the same damping, the reference agrees with it within the check's
tolerance, a tolerance below the disagreement fails the run with exit 3 naming frequency, angle and pair, and 2 ranks
give the serial truth.
"""
import os
import subprocess
import sys

import numpy as np
import pytest

import kryflex

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import test_damping as td  # noqa: E402
from rank_runs import results_on_ranks  # noqa: E402

pytestmark = pytest.mark.usefixtures("quiet_library")

CASES = {
    # name: (scene damping, body matrices)
    "matrix_modal": ({"modal": 0.002}, True),
    "matrix_only": ({"modal": 0.0}, True),
    "rayleigh": ({"modal": 0.0, "rayleigh": {"alpha": 0.02, "beta": 2e-5}}, False),
    "structural_modal": ({"modal": 0.003, "structural": 0.01}, False),
}


def without_ratios(damping):
    """The damping the direct solves use: the scene's without its modal ratios."""
    return {k: v for k, v in damping.items() if k != "modal"}


def dense_truth(angles, freqs_hz, damping, matrices):
    """(K' (1 + i g) - w^2 M + i w (C + alpha M + beta K'))^-1 solved densely, K' = P^T K_S P with
    P = I - Phi_r Phi_r^T M_S: the rigid modes from geometry (reference.geometric_rigid_modes) made K_S's exact null
    space, as in kryflex's model (the .mtx files' rounded K_S gives them a little energy); no modal ratios."""
    scene = td.ref.load_scene(td.GALILEO)
    Ms, Ks, Gs, Hs = td.ref.assemble(scene, angles)
    R = td.ref.geometric_rigid_modes(scene, angles)
    R = R @ np.linalg.inv(np.linalg.cholesky(R.T @ Ms @ R)).T
    P = np.eye(len(Ms)) - R @ R.T @ Ms
    Ks = P.T @ Ks @ P
    C = np.zeros_like(Ms)
    if matrices is not None:
        Pc = td.ref.null_space_svd(td.ref.constraint_matrix(scene, angles))
        C = Pc.T @ td.sp.block_diag(matrices).toarray() @ Pc
    ray = damping.get("rayleigh", {})
    C = C + ray.get("alpha", 0.0) * Ms + ray.get("beta", 0.0) * Ks
    Kc = Ks * (1 + 1j * damping.get("structural", 0.0))
    return np.array([Hs @ np.linalg.solve(Kc - w**2 * Ms + 1j * w * C, Gs) for w in 2 * np.pi * np.asarray(freqs_hz)])


def check_sides(reducer, c):
    """(frequencies Hz, truth, reference) of the direct check at configuration c, (nchk, t, a) complex."""
    f = np.ravel(reducer.result(c, "reference_check_frequencies_hz"))
    side = lambda name: (reducer.result(c, name + "_re") + 1j * reducer.result(c, name + "_im")).transpose(2, 0, 1)  # noqa: E731
    return f, side("reference_check_truth"), side("reference_check_reference")


@pytest.mark.parametrize("method", ["iterative", "direct"])
@pytest.mark.parametrize("case", sorted(CASES))
def test_check_solves_the_damped_system(case, method):
    """The check's truth is the dense damped solve (without modal ratios) to 1e-7 of the pair's peak, and the
    reference agrees with it to the check's 1e-6, at every angle; by either method (the iterative one takes Rayleigh
    and structural damping, the bodies' damping matrices go to the 2 x 2 block form: refined_check.c)."""
    damping, with_matrices = CASES[case]
    mats = td.damping_matrices() if with_matrices else None
    reducer = kryflex.Reducer(kryflex.scene_from_dict(td.galileo_spec(damping, mats)), quiet=True,
                              verify_check_method=method)
    reducer.reduce()
    iterated = float(np.ravel(reducer.result(-1, "reference_check_iterative_points"))[0])
    assert iterated == (2 * len(reducer.configurations) - 1 if method == "iterative" and not with_matrices else 0)
    for c, angles in enumerate(reducer.configurations):
        f, truth, reference = check_sides(reducer, c)
        assert len(f) >= 2
        dense = dense_truth(angles, f, without_ratios(damping), mats)
        peak = np.abs(reducer.frf(c, "full")).max(axis=0)
        scale = np.maximum(peak, 1e-4 * peak.max())
        agree = float((np.abs(truth - dense) / scale).max())
        check = float((np.abs(reference - truth) / scale).max())
        reported = float(np.ravel(reducer.result(c, "reference_check_error"))[0])
        print("%s %s: truth vs dense %.2e, reference vs truth %.2e (reported %.2e)" % (case, angles, agree, check,
                                                                                      reported))
        assert agree <= 1e-7      # a tenth of the check's tolerance: dense double solves near the band's bottom
        assert np.abs(truth.imag).max() > 1e-6 * np.abs(truth).max() or not without_ratios(damping)
        assert check == pytest.approx(reported, rel=1e-6, abs=1e-15)
        assert reported <= 1e-6


@pytest.mark.skipif(not os.path.exists(td.KRYFLEX), reason="build/kryflex not built")
def test_disagreement_is_exit_3(tmp_path):
    """A tolerance below the damped check's disagreement: exit 3, one message naming the frequency, the angle and the
    pair, no traceback, no verdict."""
    mats = td.damping_matrices()
    path = td.write_scene_files(str(tmp_path / "scene"), td.galileo_spec({"modal": 0.002}, mats), mats)
    out = tmp_path / "out"
    p = subprocess.run([td.KRYFLEX, "reduce", path, "-o", str(out), "-quiet", "-kf_verify_check_rtol", "1e-15"],
                       env=td.ENV, capture_output=True, text=True, timeout=300)
    print(p.returncode, p.stderr[-1500:])
    assert p.returncode == 3
    assert "Traceback" not in p.stderr
    msg = p.stderr
    assert "disagrees with a direct solve" in msg and "Hz" in msg and "deg" in msg and "output" in msg and "input" in msg


TWO_RANKS = r"""
import json, sys
sys.path.insert(0, %(here)r)
import numpy as np, kryflex
import test_damping as td
mats = td.damping_matrices()
r = kryflex.Reducer(kryflex.scene_from_dict(td.galileo_spec({"modal": 0.002, "rayleigh": {"alpha": 0.01}}, mats)),
                    quiet=True)
r.reduce()
T = np.concatenate([np.ravel(r.result(c, "reference_check_truth_" + p)) for c in range(r.nconfig) for p in ("re", "im")])
e = [float(np.ravel(r.result(c, "reference_check_error"))[0]) for c in range(r.nconfig)]
from mpi4py import MPI
if MPI.COMM_WORLD.rank == 0:
    print("RESULT " + json.dumps({"truth": T.tolist(), "error": e}))
"""


@pytest.mark.mpi
def test_two_ranks_same_truth(tmp_path):
    """Damping matrices, modal ratios and Rayleigh on 2 ranks: the check's truth and its disagreement as on 1 rank."""
    results = results_on_ranks(TWO_RANKS % {"here": HERE}, tmp_path, td.ENV)
    one, two = (np.array(r["truth"]) for r in results)
    print("2 ranks vs 1: truth %.2e, errors %s %s" % (np.abs(one - two).max() / np.abs(one).max(),
                                                     results[0]["error"], results[1]["error"]))
    assert np.abs(one - two).max() <= 1e-7 * np.abs(one).max()    # MUMPS orderings differ; the band bottom is ill-conditioned
    assert max(results[1]["error"]) <= 1e-6
