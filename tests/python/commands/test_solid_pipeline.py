"""Large-body pipeline at small size, end to end: solid mesh -> bodies -> reduction -> verification, serial and
2 ranks, for the Krylov basis and the eigenvector baseline; and the scaling benchmark's machinery."""
import json
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "support"))
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
from run_env import run  # noqa: E402  (in run_env.COMMAND_ENV: oversubscribed, for mpiexec -n 2 on a small machine)
ROOT = run_env.ROOT
KRYFLEX = run_env.KRYFLEX
REFINE = "0.5"   # 2,760 dofs: a real 3-D solid pair with RBE2 spiders, seconds to reduce



@pytest.fixture(scope="module")
def solid(tmp_path_factory):
    """The bus/rotor pair written by 2 ranks (the generator assembles in parallel)."""
    out = tmp_path_factory.mktemp("solid")
    r = run(["mpiexec", "-n", "2", sys.executable, os.path.join(ROOT, "meshes", "solid", "generate.py"),
             "--refine", REFINE, "-o", str(out)])
    assert r.returncode == 0, r.stderr
    return os.path.join(out, "spacecraft.yaml")


def reduce(scene, out, nranks, *options, code=0):
    r = run(run_env.on_ranks(nranks, [KRYFLEX, "reduce", scene, "-o", str(out), "-quiet", *options]))
    assert r.returncode == code, r.stdout + r.stderr
    return json.load(open(os.path.join(out, "summary.json")))


# the multi-angle method with its whole basis (the fixed recipe: the search would keep only what the target needs, and
# then the moments are no longer exact)
MULTI_RECIPE = ("-scene.reduction.method", "multi-angle", "-kf_search", "0")


@pytest.fixture(scope="module")
def krylov_serial(solid, tmp_path_factory):
    return reduce(solid, tmp_path_factory.mktemp("k1"), 1, *MULTI_RECIPE)


@pytest.mark.mpi
def test_solid_scene_reduces_and_verifies(krylov_serial):
    s = krylov_serial
    assert s["full"]["rigid_modes"] == 7
    # the multi-angle model matches every moment at every angle of interest (normwise, block moments)
    for lab in s["angle_labels"]:
        errs = [e for e in s["multi_angle"]["moment_error"][lab] if e is not None]
        assert errs and max(errs) <= 1e-8, (lab, errs)
    # and its frequency response over the band follows the full order's closely
    for lab, err in s["multi_angle"]["frf_max_rel_error"].items():
        assert err <= 1e-3, (lab, err)
    # the single-angle model's static gain at alpha_G
    assert s["reduced"]["static_gain_error"][s["reduction_label"]] <= 1e-9


@pytest.mark.mpi
def test_two_ranks_equal_serial(solid, krylov_serial, tmp_path):
    s2 = reduce(solid, tmp_path, 2, *MULTI_RECIPE)
    for lab in krylov_serial["angle_labels"]:
        f1 = np.array(krylov_serial["reduced"]["frequencies_hz"][lab][:10])
        f2 = np.array(s2["reduced"]["frequencies_hz"][lab][:10])
        assert np.allclose(f1, f2, rtol=1e-7), lab
        L1 = np.array(krylov_serial["full"]["moments"][lab])
        L2 = np.array(s2["full"]["moments"][lab])
        assert np.linalg.norm(L1 - L2) <= 1e-8 * np.linalg.norm(L1), lab
    assert s2["reduced"]["dofs_per_body"] == krylov_serial["reduced"]["dofs_per_body"]


@pytest.mark.mpi
def test_eigenvector_baseline_runs_through_the_same_pipeline(solid, krylov_serial, tmp_path):
    # the baseline's fixed recipe (keep threshold 0.05) keeps 3 modes: it meets the scene's 0.05 on the total
    # response (3e-3 measured), and misses it on the elastic one (2.19 measured, 2026-11-29): exit 6, said so
    st = reduce(solid, tmp_path / "total", 1, "-scene.reduction.basis", "eigen", "-scene.reduction.eigen_cover", "2",
                "-kf_accuracy_measure", "total")
    assert st["accuracy_measure"] == "total"
    assert st["target_met"] is True and st["error_max"] <= st["accuracy"]
    for err in st["frf"].values():
        assert err["max_rel_error"] < 0.5
    se = reduce(solid, tmp_path / "elastic", 1, "-scene.reduction.basis", "eigen", "-scene.reduction.eigen_cover", "2",
                code=6)
    assert se["accuracy_measure"] == "elastic"
    assert se["target_met"] is False and se["error_max"] > se["accuracy"]
    assert se["settings"]["basis"] == "eigen"
    # the baseline's modes are exact full-order modes: its kept modes reproduce the full frequencies
    lab = se["reduction_label"]
    full = np.array(se["full"]["frequencies_hz"][lab])
    krylov_modes = np.array(se["krylov"][lab]["frequency_hz"])
    n = min(len(full), len(krylov_modes))
    assert np.allclose(krylov_modes[:n], full[:n], rtol=1e-8)
    # static correction keeps the static gain at alpha_G, as with the Krylov basis
    assert se["reduced"]["static_gain_error"][lab] <= 1e-9
    # same selection, projection and reassembly as the Krylov basis: the same model under either measure
    assert se["reduced"]["dofs_per_body"] == st["reduced"]["dofs_per_body"]


def test_bench_scaling_quick_writes_csv_and_charts(tmp_path):
    """The benchmark's own machinery on the smallest sizes (its figures are measured by running it, not here)."""
    r = run([sys.executable, os.path.join(ROOT, "benchmarks", "scaling", "bench-scaling"), "--sizes", "2k", "--ranks", "1,2",
             "--baseline", "2k", "--tradeoff", "none", "--out", str(tmp_path)])
    assert r.returncode == 0, r.stdout + r.stderr
    rows = list(__import__("csv").DictReader(open(tmp_path / "bench-scaling.csv")))
    assert {(row["method"], row["ranks"]) for row in rows} == {("krylov", "1"), ("krylov", "2"), ("eigen", "1"), ("eigen", "2")}
    for row in rows:
        assert float(row["frf_error"]) < 1e-2 and float(row["t_factor"]) > 0 and float(row["peak_mb_max"]) > 0
    for chart in ("time_vs_dofs.png", "accuracy_vs_time.png", "speedup.png"):
        assert open(tmp_path / chart, "rb").read(8) == b"\x89PNG\r\n\x1a\n"
    assert "targets (measured side by side in this run)" in r.stdout
