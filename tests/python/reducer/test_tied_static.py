"""Tied models (-kf_shared_directions) under -kf_static_exact false (src/reducer/search.c, KFTriesNoStatic): a tied
model is not compressed, so the search itself tries each cluster bisection again without the static correction of the
dropped clusters; L^0 is then measured, not exact.

Galileo at one angle (0 deg), elastic target 1e-3, the scene's own damping, checked against an independent dense
NumPy/SciPy reference (accuracy_scenes.DenseReference: eigh of the assembled full order):
(a) with static_exact false the tied model has fewer system dofs than with true (measured 16 against 17 under the
    scene's modal damping; under the peers bench's C = beta K 9 against 10, benchmarks/peers/README.md), and meets the
    target on the dense elastic measure;
(b) it is the Galerkin projection of the full order on its tied subspace (maps, joint constraints and ties alone):
    eigenvalues and transfer function against NumPy's projection;
(c) its summary says L^0 is not kept, with the L^0 error the dense reference gives; with true L^0 stays exact (to the
    dense reference's floor, 1e-7);
(d) 2 MPI ranks choose the same model.
"""
import os
import subprocess
import sys

import numpy as np
import pytest
import scipy.linalg as sl

import kryflex

HERE = os.path.dirname(os.path.abspath(__file__))
SUPPORT = os.path.join(os.path.dirname(HERE), "support")
sys.path.insert(0, SUPPORT)
import accuracy_scenes as acc  # noqa: E402
import elastic_measure as em  # noqa: E402
import reference as ref  # noqa: E402

PROBE = os.path.join(SUPPORT, "mpi_reducer_probe.py")
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
ENV = dict(run_env.ENV, PYTHONPATH=run_env.PYTHONPATH)
TARGET = 1e-3
ANGLE = 0.0
SAME_EIG = 1e-9       # model against the NumPy Galerkin projection: eigenvalues relative to the largest
SAME_FRF = 1e-8       # transfer function relative to its largest entry
STATIC = 1e-7         # L^0 exact with static_exact true, against the dense eigh modal sum (its floor on Galileo ~2e-8,
                      # test_static_exact.py; 3.0e-8 measured)
DENSE_L0 = 1e-7       # the dense eigh modal sum's own floor on Galileo (test_static_exact.py)

pytestmark = pytest.mark.usefixtures("quiet_library")


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    return acc.write_variant(acc.GALILEO, str(tmp_path_factory.mktemp("galileo") / "one.yaml"), accuracy=TARGET,
                             angles=[[ANGLE]])


@pytest.fixture(scope="module")
def runs(scene):
    return {se: kryflex.reduce(kryflex.load_scene(scene), quiet=True, shared_directions=True, static_exact=se)
            for se in (True, False)}


@pytest.fixture(scope="module")
def dense(scene, tmp_path_factory):
    return acc.DenseReference(scene, str(tmp_path_factory.mktemp("dense")))


def dense_L0(full):
    f = ~full.rigid
    return (full.hp[:, f] / full.lam[f]) @ full.pg[f]


def test_smaller_without_the_static_promise_and_meets_the_target(runs, dense):
    raw = dense.scene.raw
    n = {se: em.system_dofs(r.model, [[ANGLE]]) for se, r in runs.items()}
    el = {se: em.errors(r.model, dense, [[ANGLE]], raw["band"], float(raw["damping"]))[0] for se, r in runs.items()}
    print("Galileo at %g deg, %g, tied: system dofs %s, dense elastic errors %s" % (ANGLE, TARGET, n, el))
    assert n[False] < n[True]                  # measured 16 against 17
    for se, r in runs.items():
        assert r.model.ties is not None and r.summary.verdict.target_met
        assert el[se] <= TARGET


def test_galerkin_on_the_tied_subspace(runs, scene):
    s = ref.load_scene(scene)
    Ms, Ks, Gs, Hs = ref.assemble(s, [ANGLE])
    model = runs[False].model
    Q = sl.block_diag(*model.maps)
    C = ref.constraint_matrix(s, [ANGLE])
    V = ref.null_space_svd(C).T @ (Q @ ref.null_space_svd(np.vstack([C @ Q, model.ties]), rtol=1e-9))
    Mr, Kr = V.T @ Ms @ V, V.T @ Ks @ V
    rs = model.at([ANGLE], trimmed=False)
    assert rs.dofs == V.shape[1]
    lam_ref = sl.eigh(Kr, Mr, eigvals_only=True)
    err = np.max(np.abs(np.sort(rs.eigenvalues) - lam_ref)) / lam_ref.max()
    w = 2 * np.pi * np.array([0.5, 2.3, 7.7])  # between resonances, where the rigid 1/w^2 part does not dominate
    T_ref = np.array([Hs @ V @ np.linalg.solve(Kr - x * x * Mr, V.T @ Gs) for x in w])
    T = np.array([rs.C @ np.linalg.solve(rs.K - x * x * rs.M, rs.B) for x in w])
    ferr = np.max(np.abs(T - T_ref)) / np.max(np.abs(T_ref))
    print("%d dofs: eigenvalues %.2e, FRF %.2e from the NumPy projection" % (rs.dofs, err, ferr))
    assert err <= SAME_EIG and ferr <= SAME_FRF


def test_the_static_moment_is_reported_as_measured(runs, dense):
    L0f = dense_L0(dense.at([ANGLE]))
    err = {se: float(np.linalg.norm(r.model.at([ANGLE]).moments(1)[0] - L0f) / np.linalg.norm(L0f))
           for se, r in runs.items()}
    ch = runs[False].summary.chosen
    reported = max(v for v in ch.static_moment_error.values() if v is not None)
    print("L0 error against the dense reference: %s; reported without the promise %.3e" % (err, reported))
    assert err[True] <= STATIC and runs[True].summary.chosen.static_exact is True
    assert ch.static_exact is False and runs[False].model.settings.get("static_exact", True) is False
    assert err[False] > STATIC                                  # measured 1.2e-3
    assert abs(reported - err[False]) <= 1e-6 * err[False] + DENSE_L0


@pytest.mark.mpi
def test_two_ranks_choose_the_same_model(runs, scene, tmp_path):
    path = str(tmp_path / "m.h5")
    subprocess.run(["mpiexec", "-n", "2", sys.executable, PROBE, scene, path, str(tmp_path / "s.json"),
                    "-kf_shared_directions", "true", "-kf_static_exact", "false"], env=ENV, check=True, timeout=600,
                   capture_output=True)
    two, one = kryflex.ReducedModel.load(path), runs[False].model
    assert two.sizes == one.sizes and two.ties is not None and two.ties.shape == one.ties.shape
    assert np.allclose(one.at([ANGLE]).frequencies_hz, two.at([ANGLE]).frequencies_hz, rtol=1e-8, atol=0)
