"""`kryflex study` (issue 11, items 4-6) as a user runs it: build/kryflex in a subprocess on the Galileo scene with a
small --cmax, its CSV checked against an independent dense SciPy reference (tests/python/reference.py), its charts,
the growth of the fixed-c Krylov models with c, and the same errors on 2 MPI ranks."""
import csv
import os
import subprocess
import sys

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
KRYFLEX = os.path.join(ROOT, "build", "kryflex")
GALILEO = os.path.join(ROOT, "meshes", "galileo", "galileo.yaml")
sys.path.insert(0, HERE)
import reference as ref  # noqa: E402

ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OPENBLAS_NUM_THREADS="1",
           OMPI_MCA_rmaps_base_oversubscribe="1", MPLBACKEND="Agg")
PNG = b"\x89PNG\r\n\x1a\n"
CMAX = 4
METHODS = "krylov-single,krylov-multi,eigen-static,kryflex"

pytestmark = pytest.mark.skipif(not os.path.exists(KRYFLEX), reason="build/kryflex not built (cmake --build build)")


def study(out, ranks=1):
    cmd = [KRYFLEX, "study", GALILEO, "-o", str(out), "--cmax", str(CMAX), "--methods", METHODS, "-quiet"]
    if ranks > 1:
        cmd = ["mpiexec", "-n", str(ranks)] + cmd
    proc = subprocess.run(cmd, env=ENV, capture_output=True, text=True, timeout=240)
    assert proc.returncode == 0, "exit %d\n%s\n%s" % (proc.returncode, proc.stdout, proc.stderr)
    with open(os.path.join(out, "study.csv"), newline="") as f:
        return list(csv.DictReader(f))


@pytest.fixture(scope="module")
def serial(tmp_path_factory):
    out = tmp_path_factory.mktemp("study1")
    return out, study(out)


@pytest.fixture(scope="module")
def two_ranks(tmp_path_factory):
    out = tmp_path_factory.mktemp("study2")
    return out, study(out, ranks=2)


def row(rows, method, parameter):
    [r] = [r for r in rows if r["method"] == method and r["parameter"] == str(parameter)]
    return r


def test_every_method_and_one_chosen_point(serial):
    _, rows = serial
    methods = [r["method"] for r in rows]
    assert methods.count("krylov-single") == CMAX and methods.count("krylov-multi") == CMAX
    assert methods.count("eigen-static") > 3
    chosen = [r for r in rows if r["chosen"] == "1"]
    assert [r["method"] for r in chosen] == ["kryflex"]
    assert float(chosen[0]["error_hinf"]) <= 0.05          # Galileo's accuracy, measured by the study itself


def test_sizes_grow_with_c(serial):
    _, rows = serial
    sizes = [int(row(rows, "krylov-single", c)["size_dofs"]) for c in range(1, CMAX + 1)]
    systems = [int(row(rows, "krylov-single", c)["system_dofs"]) for c in range(1, CMAX + 1)]
    assert all(b > a for a, b in zip(sizes, sizes[1:])), sizes
    assert all(b > a for a, b in zip(systems, systems[1:])), systems


@pytest.mark.parametrize("method,parameter,opts", [
    ("krylov-single", 3, dict(search=False, moments=3, output_blocks=1, method="single-angle", keep_threshold=0.0)),
    ("krylov-multi", 3, dict(search=False, moments=3, output_blocks=1, method="multi-angle", keep_threshold=0.0)),
])
def test_errors_match_dense_reference(serial, quiet_library, method, parameter, opts):
    """The CSV's error of a run against the relative H-inf error computed here with SciPy alone: the full response
    of the dense assembled system (reference.assemble + modal_frf) and the reduced response of the same model's
    reassembled matrices (modal_frf on M, K, B, C), on the study's reference grid, worst over the angles."""
    import kryflex
    from kryflex.io.scene import load_scene
    _, rows = serial
    r = row(rows, method, parameter)
    scene = load_scene(GALILEO)
    dense = ref.load_scene(GALILEO)
    grid = kryflex.Reducer(scene, quiet=True, verify=True, search=False, keep_threshold=0.0, static_correction=False)
    grid.reduce()
    model = kryflex.Reducer(scene, quiet=True, verify=False, **opts).reduce().model
    errors, sizes = [], []
    for c, angles in enumerate(grid.configurations):
        w = 2 * np.pi * grid.result(c, "frf_frequencies_hz").ravel()
        Tf = ref.modal_frf(*ref.assemble(dense, angles), w, scene.damping)
        s = model.at(angles)
        sizes.append(s.dofs)
        Tr = ref.modal_frf(s.M, s.K, s.B, s.C, w, scene.damping)
        pair = np.abs(Tf - Tr).max(axis=0) / np.abs(Tf).max(axis=0)
        errors.append(pair.max())
    assert int(r["system_dofs"]) == max(sizes)
    assert int(r["size_dofs"]) == sum(model.sizes)
    expected = max(errors)
    assert expected > 1e-4          # a row whose error is the model's, not the reference's (~2e-6 on Galileo)
    # the study's reference is the C verification (truncated modes + static residual): ~2e-6 of the peak
    assert abs(float(r["error_hinf"]) - expected) <= 5e-6 + 1e-3 * expected, (r["error_hinf"], expected)


def test_files(serial):
    out, _ = serial
    for name in ("accuracy_vs_size.png", "accuracy_vs_time.png"):
        with open(os.path.join(out, name), "rb") as f:
            assert f.read(8) == PNG
    with open(os.path.join(out, "study.md")) as f:
        text = f.read()
    assert "kryflex's choice" in text and "| krylov-single | 1 |" in text
    assert not [f for f in os.listdir(out) if f.startswith(".kryflex-")]


def _rank_differences(one, two, key):
    """(worst relative difference of error column key between the serial and the 2-rank CSV over the runs whose
    error is the model's (> 1e-3), worst absolute difference over the others, whose error is the reference's floor
    ~2e-6), each with its row."""
    assert [(r["method"], r["parameter"]) for r in one] == [(r["method"], r["parameter"]) for r in two]
    relative, absolute = (0.0, None), (0.0, None)
    for a, b in zip(one, two):
        assert (a["size_dofs"], a["system_dofs"]) == (b["size_dofs"], b["system_dofs"]), (a, b)
        x, y = float(a[key]), float(b[key])
        where = (a["method"], a["parameter"], x, y)
        if x > 1e-3:
            relative = max(relative, (abs(x - y) / x, where), key=lambda d: d[0])
        else:
            absolute = max(absolute, (abs(x - y), where), key=lambda d: d[0])
    return relative, absolute


def test_two_ranks_same_errors(serial, two_ranks):
    """The same runs, sizes and errors on 2 ranks: the H-inf error to 1e-5 relative where it is the model's, to 1e-6
    absolute where it is the reference's floor; the pointwise error (divided by down to 1e-3 of a pair's peak in
    notches) to 1e-3. Not 1e-8: the C reducer's own full-order reference and reduced responses differ by ~5e-7
    (relative) between 1 and 2 ranks on Galileo (the strict test below)."""
    relative, absolute = _rank_differences(serial[1], two_ranks[1], "error_hinf")
    assert relative[0] <= 1e-5 and absolute[0] <= 1e-6, (relative, absolute)
    relative, absolute = _rank_differences(serial[1], two_ranks[1], "error_pointwise")
    assert relative[0] <= 1e-3 and absolute[0] <= 1e-6, (relative, absolute)


@pytest.mark.xfail(strict=True, reason="the C reducer's verification response (frf_full) and the reduced models' "
                   "responses differ by ~5e-7 relative between 1 and 2 ranks on Galileo, so the errors agree to "
                   "~1e-6, not 1e-8")
def test_two_ranks_same_errors_to_1e8(serial, two_ranks):
    relative, absolute = _rank_differences(serial[1], two_ranks[1], "error_hinf")
    assert relative[0] <= 1e-8 and absolute[0] <= 1e-8 * 2e-6, (relative, absolute)


def test_unknown_method_refused(tmp_path):
    proc = subprocess.run([KRYFLEX, "study", GALILEO, "-o", str(tmp_path / "o"), "--methods", "krylov,eigen-static"],
                          env=ENV, capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2
    assert "--methods krylov" in proc.stderr and "krylov-single" in proc.stderr
    assert not os.path.exists(tmp_path / "o")
