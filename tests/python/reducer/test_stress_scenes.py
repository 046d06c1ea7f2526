"""The stress scenes of meshes/stress.py (small two-body variants of Galileo, 28 system dofs) under the elastic measure.

Every variant at accuracy 1e-2 and 1e-3, measured against the full order (the default) and estimated (verify false):
- the measured error agrees with an independent dense NumPy elastic error (tests/python/support: reference.py's
  assembly and geometric rigid modes, elastic_measure.py's measure) at the angles of interest and the midpoints, on a
  grid with points across every full-order and reduced resonance, and the verdict (target met, exit 0; else exit 6)
  follows it;
- an estimated pass is a true pass: the estimated model's dense elastic error meets the target (no false pass).
The dense modes here are solved on the M-orthogonal complement of the geometric rigid modes: on spread-1e-5 (a rotor
1e-5 as stiff) the first flexible eigenvalue is 7e-14 of the largest, and an eigensolve of the whole pencil mixes 1e-3
of a rigid mode into it. kryflex's dense reference solves them there too and refines each eigenvalue to its own
accuracy (src/verify/eigen.c, KFSystemEigenRefine). Light-mass (a rotor 1e-6 as heavy) has masses 2e-9 of the
largest that are the rotor's own, not a null space of M.
"""
import os
import subprocess
import sys

import numpy as np
import pytest
import scipy.linalg as sl

import accuracy_scenes as acc
import elastic_measure as em
import reference as ref

import run_env  # support/run_env.py: the repository's paths, the subprocesses' environment
from rank_runs import results_on_ranks
ROOT = run_env.ROOT
VARIANTS = ["damping-heavy", "damping-light", "far-angle", "light-mass", "many-moments", "mimo-8x8", "repeated",
            "spread-1e-5", "spread-1e5"]
ACCURACIES = [1e-2, 1e-3]
AGREE_RTOL = 0.02     # kryflex's measured error against the dense NumPy one (different grids, same measure)
# below this the two errors cannot be told apart: kryflex's full-order reference is held to 1e-6 of a pair's peak
# against direct solves (its reference check), and the error is a difference of two responses over that peak.
# Measured: repeated at 1e-3, 5.7e-6 against the dense 4.2e-6 on an AMD EPYC (2026-12-01; within 1e-6 before)
REFERENCE_FLOOR = 2e-6


@pytest.fixture(scope="module")
def scenes(tmp_path_factory):
    # written by its own process: meshes/stress.py imports Galileo's generate.py (see test_full_reference.py)
    out = str(tmp_path_factory.mktemp("stress_scenes"))
    subprocess.run([sys.executable, os.path.join(ROOT, "meshes", "stress.py"), "--out", out], check=True,
                   capture_output=True, timeout=120)
    return {v: os.path.join(out, v, "scene.yaml") for v in VARIANTS}


class DeflatedDense:
    """The dense full-order modes of a scene per configuration: the geometric rigid modes, M-orthonormalized, and the
    flexible modes of the pencil restricted to their M-orthogonal complement (SciPy, nothing from kryflex)."""

    def __init__(self, path):
        self.scene = ref.load_scene(path)
        self._memo = {}

    def at(self, angles):
        key = tuple(float(a) for a in angles)
        if key not in self._memo:
            Ms, Ks, Gs, Hs = (np.asarray(x.todense()) if hasattr(x, "todense") else np.asarray(x)
                              for x in ref.assemble(self.scene, list(key)))
            R = ref.geometric_rigid_modes(self.scene, list(key))
            Q = R @ np.linalg.inv(sl.cholesky(R.T @ Ms @ R))
            Z = sl.null_space((Ms @ Q).T)
            lam, Y = sl.eigh(Z.T @ Ks @ Z, Z.T @ Ms @ Z)
            phi = np.hstack([Q, Z @ Y])
            rigid = np.arange(phi.shape[1]) < Q.shape[1]
            self._memo[key] = acc.ModalData(np.concatenate([np.zeros(Q.shape[1]), lam]), rigid, Hs @ phi,
                                            phi.T @ Gs)
        return self._memo[key]


_dense = {}


def dense_error(path, model):
    """The model's elastic error by the dense NumPy measure, max over the angles of interest and the midpoints."""
    if path not in _dense:
        _dense[path] = DeflatedDense(path)
    raw = _dense[path].scene.raw
    configurations = [[float(a)] for a in raw["angles"]]
    return em.errors(model, _dense[path], configurations, raw["band"], float(raw["damping"]))[0]


def reduce(path, accuracy, verify):
    import kryflex
    return kryflex.reduce(kryflex.load_scene(path), quiet=True, accuracy=accuracy, verify=verify)


# Measured and dense errors that differ by more than AGREE_RTOL, on 2026-11-30 (the verdicts agree):
# damping-light (zeta 1e-4) 1.36e-4 against 1.30e-4; light-mass at 1e-3, whose elastic error is measured against the
# rounding floor (the two references differ by 3e-10 of the pair's total peak there, 3e-4 of the floor). At 1e-2 the
# model chosen since the Krylov basis keeps the light rotor's columns (6.97e-3) is far enough above that to agree.
# spread-1e-5 agrees since kryflex's dense reference refines its eigenvalues (4.83e-4 against 4.82e-4; before, its
# reference was 5.5e-6 of the peak off the direct solves and the run exited 3). damping-light at 1e-3 agrees under the
# shared-directions default auto (measured 4.935258e-4 against dense 4.935256e-4; the split model of -kf_shared_directions
# false still differs as above).
UNEXPLAINED = {("light-mass", 1e-3)}


@pytest.mark.parametrize("accuracy", ACCURACIES)
@pytest.mark.parametrize("variant", VARIANTS)
def test_measured_error_is_the_dense_one(scenes, variant, accuracy, quiet_library, request):
    path = scenes[variant]
    measured = reduce(path, accuracy, True)
    s = measured.summary.verdict
    truth = dense_error(path, measured.model)
    print(variant, accuracy, "measured", s.error_max, "dense", truth)
    assert not s.error_estimated
    assert s.target_met == (s.error_max <= accuracy)
    if abs(truth - accuracy) > AGREE_RTOL * accuracy:     # the verdict is the dense one's
        assert s.target_met == (truth <= accuracy)
    if (variant, accuracy) in UNEXPLAINED:
        request.applymarker(pytest.mark.xfail(strict=True, reason="measured and dense errors differ (see above)"))
    assert abs(s.error_max - truth) <= AGREE_RTOL * truth + max(1e-3 * accuracy, REFERENCE_FLOOR)


@pytest.mark.parametrize("accuracy", ACCURACIES)
@pytest.mark.parametrize("variant", VARIANTS)
def test_no_estimate_passes_falsely(scenes, variant, accuracy, quiet_library):
    path = scenes[variant]
    estimated = reduce(path, accuracy, False)
    e = estimated.summary.verdict
    truth = dense_error(path, estimated.model)
    print(variant, accuracy, "estimated", e.error_max, "dense", truth)
    assert e.error_estimated
    if e.target_met:
        assert truth <= (1 + AGREE_RTOL) * accuracy, "a false pass: estimated %.3g, dense %.3g" % (e.error_max, truth)


@pytest.mark.parametrize("variant, code", [("light-mass", 0), ("spread-1e-5", 0)])
def test_exit_codes(scenes, variant, code, tmp_path):
    """The command's exit code on the two variants that broke: light-mass meets 1e-3 (its elastic response, 5e-8 of
    the total, measured against the rounding floor; the rotor's masses are not a null space of M); spread-1e-5's
    reference agrees with the direct solves (its flexible modes on the rigid modes' complement, refined)."""
    run = subprocess.run([os.path.join(ROOT, "build", "kryflex"), "reduce", scenes[variant], "-o",
                          str(tmp_path / "out"), "-scene.accuracy", "1e-3", "-quiet"], capture_output=True, text=True,
                         timeout=300, env=dict(os.environ, OPENBLAS_NUM_THREADS="1"))
    assert run.returncode == code, run.stdout[-1500:] + run.stderr[-1500:]
    assert "Traceback" not in run.stderr


TWO_RANKS = """
import json, sys
import kryflex
red = kryflex.reduce(kryflex.load_scene(sys.argv[1]), quiet=True, accuracy=1e-3)
from mpi4py import MPI
if MPI.COMM_WORLD.rank == 0:
    s = red.summary
    print("RESULT " + json.dumps({"error": s.verdict.error_max, "met": bool(s.verdict.target_met),
                                  "dofs": s.search[s.search_chosen].reduced_dofs,
                                  "angles": red.model.settings["reduction_angles_deg"], "sizes": list(red.model.sizes)}))
"""


@pytest.mark.mpi
@pytest.mark.parametrize("variant", ["light-mass", "spread-1e-5"])
def test_two_ranks_agree_with_one(scenes, variant, tmp_path):
    res = dict(zip((1, 2), results_on_ranks(TWO_RANKS, tmp_path, dict(run_env.ENV, PYTHONPATH=run_env.PACKAGE),
                                            args=[scenes[variant]])))
    assert res[1]["met"] == res[2]["met"]
    # the same model: on light-mass two 10-dof candidates (alpha_G 0 and 15 deg) meet 1e-3 with errors of a few 1e-5
    # that rounding reorders between 1 and 2 ranks; errors of one size within 10 % of the target of each other are a
    # tie, kept by the first candidate in search order (src/reducer/search.c)
    assert res[1]["dofs"] == res[2]["dofs"]
    assert res[1]["angles"] == res[2]["angles"] and res[1]["sizes"] == res[2]["sizes"]
    if variant == "light-mass":
        # the same model measured against its rounding floor: its error moves with the ranks' rounding
        assert max(res[1]["error"], res[2]["error"]) <= 0.1 * 1e-3
    else:
        np.testing.assert_allclose(res[2]["error"], res[1]["error"], rtol=AGREE_RTOL)


def numpy_floors(frf, measure, outputs, inputs):
    """The pairs of one configuration the error measure floors, recomputed with NumPy from the summary's responses:
    largest_pair, the measured peak below 1e-4 of the largest pair's; own_total, the elastic peak (so raised) still
    below 1e-6 of the pair's own total peak; as [output, input] names."""
    full = np.array(frf["full_re"]) + 1j * np.array(frf["full_im"])
    rigid = np.array(frf["full_rigid_re"]) + 1j * np.array(frf["full_rigid_im"]) if measure == "elastic" else 0
    peak = np.abs(full - rigid).max(axis=0)
    largest = peak < 1e-4 * peak.max()
    own = np.maximum(peak, 1e-4 * peak.max()) < 1e-6 * np.abs(full).max(axis=0) if measure == "elastic" \
        else np.zeros_like(largest)
    names = lambda mask: [[outputs[i], inputs[j]] for i, j in zip(*np.nonzero(mask))]
    return {"largest_pair": names(largest & ~own), "own_total": names(own)}


@pytest.mark.mpi
@pytest.mark.parametrize("ranks", [1, 2])
@pytest.mark.parametrize("variant, kind", [("mimo-8x8", "largest_pair"), ("light-mass", "own_total")])
def test_floored_pairs_are_those_numpy_finds(scenes, variant, kind, ranks, tmp_path):
    """summary.json's floored_pairs per angle of interest against NumPy's floors of the responses the summary holds:
    mimo-8x8 has pairs whose elastic peak is below 1e-4 of the largest pair's, light-mass an elastic response 5e-8 of
    its total (below 1e-6 of its own total peak); the report names them."""
    import json
    cmd = [os.path.join(ROOT, "build", "kryflex"), "reduce", scenes[variant], "-o", str(tmp_path / "out"), "-quiet"]
    if ranks > 1:
        cmd = ["mpiexec", "-n", str(ranks)] + cmd
    env = run_env.ENV
    run = subprocess.run(cmd, capture_output=True, text=True, timeout=300, env=env)
    assert run.returncode == 0, run.stdout[-1500:] + run.stderr[-1500:]
    with open(tmp_path / "out" / "summary.json", encoding="utf-8") as f:
        data = json.load(f)
    floored = data["floored_pairs"]
    assert sorted(floored) == sorted(data["frf"])
    for label, frf in data["frf"].items():
        mine = numpy_floors(frf, data["accuracy_measure"], data["outputs"], data["inputs"])
        assert floored[label] == mine, (label, floored[label], mine)
        assert mine[kind], (label, mine)
    report = (tmp_path / "out" / "report.md").read_text(encoding="utf-8")
    assert "measured against a floor" in report
