"""`kryflex study` as a user runs it: build/kryflex in a subprocess on the Galileo scene with a
small --cmax, its CSV checked against an independent dense SciPy reference (tests/python/support/reference.py), its charts,
the growth of the fixed-c Krylov models with c, and the same errors on 2 MPI ranks."""
import csv
import os
import subprocess
import sys

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
SUPPORT = os.path.join(os.path.dirname(HERE), "support")   # the helpers (tests/python/support)
sys.path.insert(0, SUPPORT)
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
ROOT = run_env.ROOT
KRYFLEX = run_env.KRYFLEX
GALILEO = os.path.join(ROOT, "meshes", "galileo", "galileo.yaml")
import reference as ref  # noqa: E402

ENV = dict(run_env.ENV, MPLBACKEND="Agg")
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
        Ms, Ks, Gs, Hs = ref.assemble(dense, angles)
        Tf = ref.modal_frf(Ms, Ks, Gs, Hs, w, scene.damping)
        # the scene's measure (elastic by default): the rigid part, from the dense zero-eigenvalue modes, taken out
        _, phi, rigid = ref._modes(Ms, Ks, ref.RIGID_RTOL)
        Tg = -((Hs @ phi[:, rigid]) @ (phi[:, rigid].T @ Gs))[None] / (w**2)[:, None, None]
        s = model.at(angles)
        sizes.append(s.dofs)
        Tr = ref.modal_frf(s.M, s.K, s.B, s.C, w, scene.damping)
        peak = np.abs(Tf - Tg).max(axis=0)
        pair = np.abs(Tf - Tr).max(axis=0) / np.maximum(peak, 1e-4 * peak.max())
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


@pytest.mark.mpi
def test_two_ranks_same_errors(serial, two_ranks):
    """The same runs, sizes and errors on 2 ranks: the H-inf error to 1e-5 relative where it is the model's, to 1e-6
    absolute where it is the reference's floor; the pointwise error (divided by down to 1e-3 of a pair's peak in
    notches) to 1e-3 relative where it is the model's, to 1e-5 absolute where it is the reference's floor (the
    full-order reference repeats to ~3e-6 only, SLEPc's start vectors carrying on between solves, and the pointwise
    measure divides that noise by less than the peak: on Debian's current packages eigen-static at 8 modes reads 3.2e-6
    on 1 rank and 1.8e-6 on 2). Since the dense reference refines its eigenvalues (2026-11-30) the references agree
    to 2.4e-11 of the peak and the errors to 4.4e-8 (eigen-static at 4 modes, 1.2e-7 against 1.7e-7). Not 1e-8:
    the reduced models' responses differ by up to 1.3e-7 (relative) between 1 and 2 ranks on Galileo (the strict test
    below)."""
    relative, absolute = _rank_differences(serial[1], two_ranks[1], "error_hinf")
    assert relative[0] <= 1e-5 and absolute[0] <= 1e-6, (relative, absolute)
    relative, absolute = _rank_differences(serial[1], two_ranks[1], "error_pointwise")
    assert relative[0] <= 1e-3 and absolute[0] <= 1e-5, (relative, absolute)


@pytest.mark.mpi
@pytest.mark.xfail(strict=True, reason="the reduced models' responses differ by up to 1.3e-7 relative between 1 and "
                   "2 ranks on Galileo (the references agree to 2.4e-11 of the peak), so the errors agree to ~4e-8, "
                   "not 1e-8")
def test_two_ranks_same_errors_to_1e8(serial, two_ranks):
    relative, absolute = _rank_differences(serial[1], two_ranks[1], "error_hinf")
    assert relative[0] <= 1e-8 and absolute[0] <= 1e-8 * 2e-6, (relative, absolute)


def test_unknown_method_refused(tmp_path):
    proc = subprocess.run([KRYFLEX, "study", GALILEO, "-o", str(tmp_path / "o"), "--methods", "krylov,eigen-static"],
                          env=ENV, capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2
    assert "--methods krylov" in proc.stderr and "krylov-single" in proc.stderr
    assert not os.path.exists(tmp_path / "o")


# ---------------------------------------------------------------------------------------------- the estimator check

@pytest.fixture(scope="module")
def estimator_study(tmp_path_factory):
    """`kryflex study` on Galileo with only the kryflex run swept: the estimator check is part of the study."""
    out = tmp_path_factory.mktemp("estimator")
    # the total measure: under the elastic one Galileo's search has no candidate in the decision band (its errors
    # jump from 0.0035 to 0.057 around the 0.05 target, measured 2026-11-29), where the estimator's figures are made
    proc = subprocess.run([KRYFLEX, "study", GALILEO, "-o", str(out), "--methods", "kryflex", "-quiet",
                           "-kf_accuracy_measure", "total"], env=ENV,
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, "exit %d\n%s\n%s" % (proc.returncode, proc.stdout, proc.stderr)
    from kryflex.study.estimator_output import read_csv
    with open(os.path.join(out, "study.md")) as f:
        md = f.read()
    return out, read_csv(os.path.join(out, "estimator.csv")), md


@pytest.fixture(scope="module")
def galileo_searches(quiet_library):
    """Galileo's accuracy search made here (the total measure, as estimator_study), apart from the study:
    verify.full_order on and off, with alpha_G auto
    (the scene's) and named at each angle of interest in turn (a named alpha_G gives that angle's single-angle rows
    alone: which rows of the auto search belong to which alpha_G, told without the study's reading of the table)."""
    import kryflex
    from kryflex.io.scene import load_scene
    scene = load_scene(GALILEO)
    runs = {}
    for verify in (True, False):
        r = kryflex.Reducer(scene, quiet=True, search=True, verify=verify, accuracy_measure="total")
        reduction = r.reduce()
        runs[verify, "auto"] = (r, reduction)
        for angles in scene.configurations:
            named = kryflex.Reducer(scene, quiet=True, search=True, verify=verify, reduction_angle=angles[0],
                                    accuracy_measure="total")
            named.reduce()
            runs[verify, angles[0]] = (named, None)
    return scene, runs


def _table(reducer):
    return np.asarray(reducer.result(-1, "search_table"), float)


# the search table's rows that name a candidate: all but its error (row 6), the variant (row 7) included: under the
# default -kf_shared_directions auto the table holds a split and a tied pass over the same candidates
NAMING = [0, 1, 2, 3, 4, 5, 7]
VARIANT_CODES = {"split": 0, "tied": 1, "tied, no static correction": 2}


def _columns(rows, error):
    """The estimator.csv rows as search-table columns (family, c, kept, expansion angles, dofs, system dofs, error,
    variant)."""
    return np.array([[0 if r["family"] == "single-angle" else 1, r["moments"], r["kept_clusters"],
                      r["expansion_angles"], r["reduced_dofs"], r["system_dofs"], r[error],
                      VARIANT_CODES[r["variant"]]] for r in rows]).T


def test_estimator_join_matches_both_searches(estimator_study, galileo_searches):
    """Every row of estimator.csv: its true error is the full-order search's, its estimate the estimator search's,
    for the same candidate. Single-angle rows are compared with the search made with that row's alpha_G named (its
    rows alone, in order); multi-angle rows with the auto search's multi-angle columns."""
    _, rows, _ = estimator_study
    scene, runs = galileo_searches
    full, est = _table(runs[True, "auto"][0]), _table(runs[False, "auto"][0])
    assert runs[True, "auto"][0].result(-1, "error_estimated").ravel()[0] == 0
    assert runs[False, "auto"][0].result(-1, "error_estimated").ravel()[0] == 1
    # on Galileo both searches try the same candidates in the same order: every one of them is joined
    assert np.array_equal(full[NAMING], est[NAMING])
    assert len(rows) == full.shape[1]
    accuracy = float(scene.accuracy)
    for verify, error in ((True, "true_error"), (False, "estimated_error")):
        for angles in scene.configurations:
            # the row of each body's share (kept -2) is made from the best alpha_G only: not comparable by alpha_G
            mine = [r for r in rows if r["family"] == "single-angle" and r["start_deg"] == "%g" % angles[0]
                    and int(r["kept_clusters"]) != -2]
            named = _table(runs[verify, angles[0]][0])
            expected = named[:, (named[0] == 0) & (named[2] != -2)]
            got = _columns(mine, error)
            assert got.shape == expected.shape, (verify, angles, got.shape, expected.shape)
            assert np.array_equal(got[NAMING], expected[NAMING]), (verify, angles)
            # not to the last digit: the full-order reference of a second solve in one process differs by ~3e-6
            # relative (the eigensolver's random start vectors go on), and the richest candidate by its rounding
            # (a named alpha_G is visited last); the errors of a whole basis (~2e-6 true, ~3e-8 estimated) are that
            # noise: an absolute 1e-5 of the accuracy
            assert np.allclose(got[6], expected[6], rtol=2e-5, atol=1e-5 * accuracy), (verify, angles, got[6],
                                                                                      expected[6])
        table = full if verify else est
        multi = table[:, table[0] == 1]
        got = _columns([r for r in rows if r["family"] == "multi-angle"], error)
        assert got.shape == multi.shape and np.array_equal(got[NAMING], multi[NAMING]), (verify, got, multi)
        assert np.allclose(got[6], multi[6], rtol=2e-5, atol=1e-5 * accuracy), (verify, got, multi)


def test_estimator_ratios_and_false_passes(estimator_study, galileo_searches):
    """study.md's figures recomputed from the two search tables made here, paired column by column (both searches
    tried the same candidates): the ratios over the candidates whose two errors are exact (<= the accuracy: the
    search measures such a candidate at every point) and over those where pass or fail is decided (true error >=
    accuracy / 10), the false passes and false fails over all. The farthest ratio over all candidates is a whole
    basis's, at the full-order reference's noise (~2e-6, different in every process): checked against the CSV."""
    out, rows, md = estimator_study
    scene, runs = galileo_searches
    accuracy = float(scene.accuracy)
    true, est = _table(runs[True, "auto"][0])[6], _table(runs[False, "auto"][0])[6]
    exact = (true <= accuracy) & (est <= accuracy)
    ratios = est[exact] / true[exact]
    near = exact & (true >= accuracy / 10)
    near_ratios = est[near] / true[near]
    near_worst = near_ratios[np.argmax(np.abs(np.log(near_ratios)))]
    false_passes = int(np.sum((est <= accuracy) & (true > accuracy)))
    false_fails = int(np.sum((est > accuracy) & (true <= accuracy)))
    assert near.sum() >= 3, "Galileo should have candidates near its accuracy: %s" % true
    assert "## The error estimator against the truth" in md
    assert "over the %d candidates whose two errors are exact: median %.3g, from" % (exact.sum(), np.median(ratios)) \
        in md
    csv_ratios = np.array([r["ratio"] for r in rows if not r["true_lower_bound"] and not r["estimate_lower_bound"]])
    assert "the farthest from 1: %.3g (" % csv_ratios[np.argmax(np.abs(np.log(csv_ratios)))] in md
    assert "(true error >= accuracy / 10 = %g): %d candidates, median ratio %.3g, the farthest from 1: %.3g (" % (
        accuracy / 10, near.sum(), np.median(near_ratios), near_worst) in md
    assert "(the estimate meets %g, the true error does not): %d of %d" % (accuracy, false_passes, len(true)) in md
    assert "(the estimate misses %g, the true error meets it): %d of %d" % (accuracy, false_fails, len(true)) in md
    assert sum(r["verdict"] == "false pass" for r in rows) == false_passes
    # the ratio column, and the lower bounds marked: a value above the accuracy (Galileo has 11 evaluation points)
    for r, t, e in zip(rows, true, est):
        assert r["true_lower_bound"] == int(t > accuracy) and r["estimate_lower_bound"] == int(e > accuracy)
        assert r["ratio"] == pytest.approx(r["estimated_error"] / r["true_error"], rel=1e-12)
    with open(os.path.join(out, "estimate_vs_truth.png"), "rb") as f:
        assert f.read(8) == PNG


def test_estimator_chosen_model_against_dense_reference(estimator_study, galileo_searches, tmp_path):
    """The full-order search's choice: its row in estimator.csv carries the search's error_max, which a dense SciPy
    check (tests/python/support/accuracy_scenes.py: the dense full-order response, a grid 4x finer than the reducer's,
    angles of interest and midpoints) reproduces to 1 %; study.md names the same error_max for both searches'
    choices."""
    import accuracy_scenes as acs
    from accuracy_sweep import reducer_grid_points
    _, rows, md = estimator_study
    scene, runs = galileo_searches
    reducer, reduction = runs[True, "auto"]
    error_max = float(reducer.result(-1, "error_max").ravel()[0])
    [chosen] = [r for r in rows if r["chosen_full_order"]]
    assert chosen["true_error"] == pytest.approx(error_max, rel=2e-5)      # another process: reference noise
    # the search's size of a model: its bodies' dofs less its coordinate ties (a tied model, -kf_shared_directions)
    ties = reduction.model.ties
    assert chosen["reduced_dofs"] == sum(reduction.model.sizes) - (0 if ties is None else ties.shape[0])
    assert chosen["variant"] == ("split" if ties is None else "tied")
    dense = acs.DenseReference(GALILEO, str(tmp_path / "dense"))
    checks = acs.evaluate_model(reduction.model, dense, scene.configurations, scene.band, scene.damping,
                                reducer_grid_points(reducer, scene))
    assert abs(acs.worst(checks) - error_max) <= 1e-2 * acs.worst(checks), (error_max, acs.describe(checks))
    estimated_max = float(runs[False, "auto"][0].result(-1, "error_max").ravel()[0])
    assert "With the full order the search chose" in md and "error_max %.3g, target met" % error_max in md
    assert "With the estimator the search chose" in md and "error_max %.3g" % estimated_max in md


def test_no_estimator(tmp_path):
    out = tmp_path / "o"
    proc = subprocess.run([KRYFLEX, "study", GALILEO, "-o", str(out), "--methods", "kryflex", "--no-estimator",
                           "-quiet"], env=ENV, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert sorted(os.listdir(out)) == ["accuracy_vs_size.png", "accuracy_vs_time.png", "study.csv", "study.md"]
    with open(out / "study.md") as f:
        assert "estimator" not in f.read()


def test_kf_options_reach_every_run(tmp_path, quiet_library):
    """-kf_ options on the study's command line are read by every run as `kryflex reduce` reads them: -kf_accuracy
    by kryflex's run and by the study's verdict on it, -kf_keep_threshold by krylov-paper (the scene's importance rule
    unless the command line says otherwise). Against models reduced here with the same values given as keywords,
    which differ from the scene's (so the check sees whether the options arrived)."""
    import kryflex
    from kryflex.io.scene import load_scene
    out = tmp_path / "o"
    proc = subprocess.run([KRYFLEX, "study", GALILEO, "-o", str(out), "--cmax", "3", "--methods", "krylov-paper,kryflex",
                           "--no-estimator", "-quiet", "-kf_accuracy", "0.01", "-kf_keep_threshold", "0.9"], env=ENV,
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    with open(out / "study.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    scene = load_scene(GALILEO)
    assert float(scene.accuracy) != 0.01 and float(scene.reduction["keep_threshold"]) != 0.9
    paper = dict(search=False, moments=3, output_blocks=1, method="single-angle", verify=False)
    for r, given, scenes in ((row(rows, "kryflex", "default"), dict(accuracy=0.01), {}),
                             (row(rows, "krylov-paper", 3), dict(paper, keep_threshold=0.9), paper)):
        model = kryflex.Reducer(scene, quiet=True, **given).reduce().model
        assert int(r["size_dofs"]) == sum(model.sizes), (r["method"], r["size_dofs"], model.sizes)
        assert sum(kryflex.Reducer(scene, quiet=True, **scenes).reduce().model.sizes) != sum(model.sizes)
    assert "accuracy 0.01 met" in row(rows, "kryflex", "default")["note"]
    with open(out / "study.md") as f:
        assert "Scene accuracy: 0.01." in f.read()
