"""kryflex.Reducer, the Python face of the C reducer (KFReducer): the same model as the kryflex command (1 and 2
ranks), a summary that holds the reducer's own results, its named results, -kf_ options over the scene, the
command's -help, the C example's model, and an import of kryflex without side effects.

Two scenes: the Galileo-like model (meshes/galileo) and a generated 3-body frame scene (meshes/frames.py, 3 inputs,
2 outputs, 2 skew revolute joints). Models are compared by their reassembled matrices (M, K, B, C) at angles of
interest and at angles the reduction never saw, to SAME relative (the same computation on the same ranks)."""
import gc
import json
import os
import subprocess
import sys

import numpy as np
import pytest
import yaml

import kryflex

HERE = os.path.dirname(os.path.abspath(__file__))
SUPPORT = os.path.join(os.path.dirname(HERE), "support")   # the helpers (tests/python/support)
sys.path.insert(0, SUPPORT)
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
ROOT = run_env.ROOT
GALILEO = os.path.join(ROOT, "meshes", "galileo", "galileo.yaml")
KRYFLEX_CMD = run_env.KRYFLEX
EXAMPLE = os.path.join(ROOT, "build", "examples", "reduce_galileo")
PROBE = os.path.join(SUPPORT, "mpi_reducer_probe.py")
PYTHON = run_env.PYTHON
sys.path.insert(0, os.path.join(ROOT, "meshes"))
import frames  # noqa: E402

SAME = 1e-12
ENV = dict(run_env.ENV, PYTHONPATH=run_env.PYTHONPATH)
FRAMES_ANGLES = [[0.0, 0.0], [45.0, 120.0], [210.0, 330.0]]
OTHER_ANGLES = {"galileo": [[7.5], [100.0]], "frames": [[10.0, 250.0], [-30.0, 95.0]]}

# what every configuration of interest records, and what the whole solve records (docs/guide/results.md, Results of a reduction)
PER_CONFIG = {"full_moments", "krylov_frequencies_hz", "krylov_importance", "krylov_kept", "krylov_deflations",
              "gram_condition_raw", "held_dofs", "rigid_residual", "reduced_dofs", "reduced_frequencies_hz",
              "reduced_moments", "moment_ratios", "moment_error", "static_gain_error", "reassembly_rank",
              "reassembly_sigma_ratio", "reassembly_seconds"}
VERIFIED = {"full_frequencies_hz", "frf_frequencies_hz", "frf_full_re", "frf_full_im", "frf_reduced_re",
            "frf_reduced_im", "frf_error", "dominant_modes", "dominant_frequency_error"}
MULTI = {"multi_reduced_dofs", "multi_moment_ratios", "multi_moment_error"}
WHOLE = {"reduction_angles", "reduction_config", "kept_modes", "static_correction_modes", "full_system_dofs",
         "rigid_modes", "reduced_dofs_per_body", "time_assembly", "time_factorization", "time_basis", "time_modes",
         "time_moments", "time_projection", "time_verification"}

pytestmark = pytest.mark.usefixtures("quiet_library")   # tests/python/conftest.py


def run(cmd, timeout=300):
    proc = subprocess.run([str(c) for c in cmd], env=ENV, capture_output=True, text=True, timeout=timeout)
    assert proc.returncode == 0, "exit %d: %s\n%s\n%s" % (proc.returncode, " ".join(map(str, cmd)), proc.stdout,
                                                         proc.stderr)
    return proc


def mpi(ranks):
    return ["mpiexec", "-n", str(ranks)] if ranks > 1 else []


def assert_same_model(m1, m2, angles, what):
    """The same reduced bodies: equal sizes and settings, and the same reassembled M, K, B, C at every angle."""
    assert m1.sizes == m2.sizes, what
    assert m1.settings == m2.settings, what
    for a in angles:
        s1, s2 = m1.at(a), m2.at(a)
        for name in ("M", "K", "B", "C"):
            x1, x2 = getattr(s1, name), getattr(s2, name)
            assert x1.shape == x2.shape, (what, a, name)
            err = np.linalg.norm(x1 - x2) / np.linalg.norm(x1)
            assert err <= SAME, "%s at %s deg: %s differs by %.2e relative" % (what, a, name, err)


def nan_to_none(a):
    a = np.asarray(a, dtype=float)
    if a.ndim == 0:
        return None if np.isnan(a) else float(a)
    return [nan_to_none(x) for x in a]


# ================================================================================================ fixtures

@pytest.fixture(scope="module")
def frames_scene(tmp_path_factory):
    """A random 3-body frame scene (3 inputs, 2 outputs, 2 skew revolute joints) with chosen angles."""
    folder = str(tmp_path_factory.mktemp("frames"))
    path = frames.write_random_scene(folder, 240, nbodies=3, ninputs=3, noutputs=2, seed=1)
    with open(path) as f:
        spec = yaml.safe_load(f)
    spec["angles"] = FRAMES_ANGLES
    with open(path, "w") as f:
        yaml.safe_dump(spec, f, sort_keys=False)
    return path


@pytest.fixture(scope="module")
def scenes(frames_scene):
    return {"galileo": GALILEO, "frames": frames_scene}


class Solved:
    """A scene reduced in this process by kryflex.Reducer: the reducer (its results) and the Reduction."""

    def __init__(self, path):
        self.path = path
        self.scene = kryflex.load_scene(path)
        self.reducer = kryflex.Reducer(self.scene, quiet=True)
        self.reduction = self.reducer.reduce()
        self.summary = self.reduction.summary
        self.labels = [self.scene.label(c) for c in self.scene.configurations]


@pytest.fixture(scope="module")
def solved(scenes):
    cache = {}

    def get(name):
        if name not in cache:
            cache[name] = Solved(scenes[name])
        return cache[name]
    return get


# ================================================================================================ Reducer = kryflex reduce

@pytest.mark.mpi
@pytest.mark.parametrize("ranks", [1, 2])
@pytest.mark.parametrize("name", ["galileo", "frames"])
def test_reducer_model_equals_the_command_model(name, ranks, scenes, solved, tmp_path):
    """kryflex.Reducer and `kryflex reduce` make the same reduced model, serially and on 2 ranks (the Python face on
    the same ranks as the command: probe script under mpiexec)."""
    path = scenes[name]
    out = tmp_path / "cli"
    run(mpi(ranks) + [KRYFLEX_CMD, "reduce", path, "-o", out, "-quiet"])
    cli_model = kryflex.ReducedModel.load(str(out / "reduced.h5"))
    with open(out / "summary.json") as f:
        cli_summary = json.load(f)
    if ranks == 1:
        mine = solved(name)
        model, summary = mine.reduction.model, mine.summary.to_json()
    else:
        h5, js = tmp_path / "probe.h5", tmp_path / "probe.json"
        run(mpi(ranks) + [PYTHON, PROBE, path, h5, js, "-kf_quiet"])
        model = kryflex.ReducedModel.load(str(h5))
        with open(js) as f:
            summary = json.load(f)
    scene = solved(name).scene
    angles = [list(c) for c in scene.configurations] + OTHER_ANGLES[name]
    assert_same_model(model, cli_model, angles, "%s, %d rank(s)" % (name, ranks))
    # the same reduction: alpha_G, kept modes, sizes (timings and the scene file's path aside)
    for key in ("reduction_label", "kept_modes", "static_correction_modes", "settings", "angle_labels"):
        assert summary[key] == cli_summary[key], key
    assert summary["reduced"]["system_dofs"] == cli_summary["reduced"]["system_dofs"]


# ================================================================================================ results and summary

def test_result_names(solved):
    s = solved("galileo")
    nconfig = len(s.labels)
    for c in range(nconfig):
        names = set(s.reducer.result_names(c))
        assert PER_CONFIG | VERIFIED | MULTI <= names, sorted(PER_CONFIG | VERIFIED | MULTI - names)
    whole = set(s.reducer.result_names(-1))
    assert WHOLE | {"multi_dofs_per_body", "multi_reduction_angles"} <= whole, sorted(WHOLE - whole)
    with pytest.raises(kryflex.Error, match="no result 'no_such_result'"):
        s.reducer.result(0, "no_such_result")
    with pytest.raises(kryflex.Error):
        s.reducer.result(nconfig, "reduced_dofs")


def test_result_shapes(solved):
    s = solved("frames")
    t, a = len(s.scene.output_names), len(s.scene.input_names)
    nmom = int(s.reduction.model.settings["moments"])
    nrev = len(s.scene.revolute)
    for c in range(len(s.labels)):
        assert s.reducer.result(c, "full_moments").shape == (t, a, nmom)
        assert s.reducer.moments(c, "full_moments").shape == (nmom, t, a)
        nw = s.reducer.result(c, "frf_frequencies_hz").shape[0]
        assert s.reducer.result(c, "frf_full_re").shape == (t, a, nw)
        assert s.reducer.frf(c, "reduced").shape == (nw, t, a)
        nk = s.reducer.result(c, "krylov_frequencies_hz").shape[0]
        assert s.reducer.result(c, "krylov_kept").shape == (nk,)
    assert s.reducer.result(-1, "reduction_angles").shape[0] == nrev
    assert s.reducer.result(-1, "reduced_dofs_per_body").shape == (len(s.scene.body_names),)


@pytest.mark.parametrize("name", ["galileo", "frames"])
def test_summary_holds_the_reducer_results(name, solved):
    """Every number of the typed summary is one of the reducer's results, as recorded (NaN -> None)."""
    s = solved(name)
    r, summary, labels = s.reducer, s.summary, s.labels
    from kryflex.report import validate_summary
    from kryflex.results import Summary
    assert isinstance(summary, Summary)
    validate_summary(summary.to_json())
    assert Summary.from_json(summary.to_json()).to_json() == summary.to_json()
    assert summary.angle_labels == labels
    assert summary.angles_deg == s.scene.configurations
    index_g = int(r.result(-1, "reduction_config")[0])
    assert index_g >= 0 and summary.reduction_label == labels[index_g]
    np.testing.assert_allclose(np.degrees(r.result(-1, "reduction_angles")[:, 0]), s.scene.configurations[index_g],
                               rtol=1e-14, atol=1e-12)
    assert summary.kept_modes == [int(k) for k in r.result(-1, "kept_modes")]
    assert summary.static_correction_modes == int(r.result(-1, "static_correction_modes")[0])
    full, reduced = summary.full, summary.reduced
    assert full.system_dofs == int(r.result(-1, "full_system_dofs")[0])
    assert full.rigid_modes == int(r.result(-1, "rigid_modes")[0]) == 6 + len(s.scene.revolute)
    assert list(reduced.dofs_per_body.values()) == [int(v) for v in r.result(-1, "reduced_dofs_per_body")]
    assert list(reduced.dofs_per_body.values()) == s.reduction.single_angle_model.sizes
    assert summary.reduction_rule == r.rule and summary.notes == r.notes
    for c, lab in enumerate(labels):
        assert full.moments[lab] == nan_to_none(r.moments(c, "full_moments"))
        assert reduced.moments[lab] == nan_to_none(r.moments(c, "reduced_moments"))
        assert reduced.moment_ratios[lab] == nan_to_none(r.moments(c, "moment_ratios"))
        assert reduced.moment_error[lab] == nan_to_none(r.result(c, "moment_error"))
        assert reduced.frequencies_hz[lab] == nan_to_none(r.result(c, "reduced_frequencies_hz"))
        assert reduced.system_dofs[lab] == int(r.result(c, "reduced_dofs")[0])
        assert reduced.static_gain_error[lab] == float(r.result(c, "static_gain_error")[0])
        assert reduced.reassembly_rank[lab] == int(r.result(c, "reassembly_rank")[0])
        assert reduced.reassembly_sigma_ratio[lab] == float(r.result(c, "reassembly_sigma_ratio")[0])
        kr = summary.krylov[lab]
        assert kr.frequency_hz == nan_to_none(r.result(c, "krylov_frequencies_hz"))
        assert kr.importance == nan_to_none(r.result(c, "krylov_importance"))
        assert kr.kept == [bool(k) for k in r.result(c, "krylov_kept")]
        assert kr.deflations == int(r.result(c, "krylov_deflations")[0])
        assert kr.gram_condition_raw == nan_to_none(r.result(c, "gram_condition_raw")[0])
        assert full.frequencies_hz[lab] == nan_to_none(r.result(c, "full_frequencies_hz"))
        frf = summary.frf[lab]
        assert frf.freq_hz == nan_to_none(r.result(c, "frf_frequencies_hz"))
        for which in ("full", "reduced"):
            T = r.frf(c, which)
            assert getattr(frf, which + "_re") == nan_to_none(T.real)
            assert getattr(frf, which + "_im") == nan_to_none(T.imag)
        assert frf.frf_error == frf.max_rel_error == float(r.result(c, "frf_error")[0])
        assert summary.dominant_modes[lab] == [int(i) for i in r.result(c, "dominant_modes")]
        assert summary.dominant_freq_error[lab] == nan_to_none(r.result(c, "dominant_frequency_error"))
        # the C measures give the summary's errors again from its own arrays (one definition of each measure)
        hinf, pointwise = kryflex._core.frf_errors(frf.full(), frf.reduced(), float(s.scene.verify["frf_floor_db"]),
                                                   rigid=r.full_rigid(c))
        # the reducer adds points across the model's own resonances and refines the worst pair's maximum between
        # points: never below the grid's value
        assert hinf <= frf.frf_error <= hinf * 1.5 + 1e-15
    multi = summary.multi_angle
    assert list(multi.dofs_per_body.values()) == [int(v) for v in r.result(-1, "multi_dofs_per_body")]
    assert list(multi.dofs_per_body.values()) == s.reduction.multi_angle_model.sizes
    for c, lab in enumerate(labels):
        assert multi.system_dofs[lab] == int(r.result(c, "multi_reduced_dofs")[0])
        assert multi.moment_ratios[lab] == nan_to_none(r.moments(c, "multi_moment_ratios"))
        assert multi.moment_error[lab] == nan_to_none(r.result(c, "multi_moment_error"))
        assert multi.frf_error[lab] == multi.frf_max_rel_error[lab] == float(r.result(c, "multi_frf_error")[0])
    # the verdict and the chosen model: the reducer's
    assert summary.verdict.target_met is bool(r.result(-1, "target_met")[0])
    assert summary.verdict.error_max == float(r.result(-1, "error_max")[0])
    assert summary.verdict.chosen_method == ("single-angle", "multi-angle")[int(r.result(-1, "chosen_method")[0])]
    assert summary.chosen.dofs == sum(s.reduction.model.sizes)
    # timings: the reducer's stages that took time, under the report's names
    names = {"time_assembly": "assembly", "time_factorization": "factorization", "time_basis": "krylov",
             "time_modes": "krylov modes", "time_moments": "moments", "time_projection": "projection",
             "time_verification": "verification eigensolve", "time_other": "other"}
    expected = {names[k]: float(r.result(-1, k)[0]) for k in names if float(r.result(-1, k)[0]) > 0}
    assert summary.timings_s == expected and "assembly" in expected and "verification eigensolve" in expected
    assert summary.performance.whole_s == float(r.result(-1, "time_whole")[0])


def test_measures_of_the_binding_are_the_reducers(solved):
    """_core.frequency_grid, moment_errors, frf_errors (src/measure, the C reducer's own measures) give back the
    reducer's results from its arrays: the one definition of each measure, reachable from Python."""
    from kryflex import _core
    s = solved("frames")
    r, scene = s.reducer, s.scene
    settings = s.reduction.model.settings
    Lall = np.array([r.moments(c, "full_moments") for c in range(len(s.labels))])
    for c in range(len(s.labels)):
        grid = _core.frequency_grid(settings["band_hz"], r.result(c, "full_frequencies_hz"), settings["damping"],
                                    int(scene.verify["frequency_points"]))
        np.testing.assert_array_equal(grid, r.result(c, "frf_frequencies_hz"))
        errors, ratios = _core.moment_errors(Lall, c, r.moments(c, "reduced_moments"))
        np.testing.assert_array_equal(errors, r.result(c, "moment_error"))
        np.testing.assert_array_equal(ratios, r.moments(c, "moment_ratios"))
        hinf, pointwise = _core.frf_errors(r.frf(c, "full"), r.frf(c, "reduced"), float(scene.verify["frf_floor_db"]),
                                           rigid=r.full_rigid(c))
        # the reducer's grid has points across the model's own resonances too: never below the stored grid's value
        assert pointwise <= float(r.result(c, "frf_pointwise_error")[0]) * (1 + 1e-12)
        assert hinf <= float(r.result(c, "frf_error")[0]) <= hinf * 1.5 + 1e-15
    lam = np.array([1e-12, 2e-12, 1.0, 4.0])
    assert _core.rigid_tolerance(lam, 2) == pytest.approx(np.sqrt(2e-12 * 1.0) / 4.0)
    with pytest.raises(ValueError):
        _core.frf_errors(np.zeros((3, 2, 1)), np.zeros((3, 1, 2)))


def test_reduction_models(solved):
    s = solved("galileo")
    red = s.reduction
    assert red.model is red.single_angle_model and red.multi_angle_model is not None
    assert red.model.settings["method"] == "single-angle" and red.multi_angle_model.settings["method"] == "multi-angle"
    assert not hasattr(red, "multi_model")
    assert s.reducer.reduce() is red          # solved once


def test_models_outlive_the_reducer(scenes):
    scene = kryflex.load_scene(scenes["frames"])
    reducer = kryflex.Reducer(scene, quiet=True)
    reduction = reducer.reduce()
    model = reduction.model
    K = model.at(FRAMES_ANGLES[1]).K
    del reducer, reduction, scene
    gc.collect()
    np.testing.assert_array_equal(model.at(FRAMES_ANGLES[1]).K, K)


def test_one_call_reduce_is_the_reducer(scenes, solved):
    scene = kryflex.load_scene(scenes["frames"])
    reduction = kryflex.reduce(scene, quiet=True)
    assert isinstance(reduction, kryflex.Reduction)
    mine = solved("frames").reduction
    assert_same_model(reduction.model, mine.model, FRAMES_ANGLES, "kryflex.reduce")
    assert reduction.summary.kept_modes == mine.summary.kept_modes


def test_kf_options_override_the_scene(scenes):
    """The scene's keys are set on the reducer first, then its -kf_ options: command-line options win, and the
    summary describes what the reducer did (its angles of interest, moments, method, damping)."""
    from petsc4py import PETSc
    opts = PETSc.Options()
    scene = kryflex.load_scene(scenes["frames"])
    assert int(scene.reduction["moments"]) == 10
    given = {"kf_moments": 6, "kf_method": "multi-angle", "kf_verify": False, "kf_angles": "45,120,0,0",
             "kf_damping": 0.01}
    for key, value in given.items():
        opts.setValue(key, value)
    try:
        reducer = kryflex.Reducer(scene, quiet=True)
    finally:
        for key in given:
            opts.delValue(key)
    reduction = reducer.reduce()
    summary = reduction.summary
    assert reduction.model.settings["moments"] == 6 and reduction.model.settings["method"] == "multi-angle"
    assert reduction.model is reduction.multi_angle_model
    # verification off: the search measures against its estimator, and the summary says so
    assert summary.settings.moments == 6 and summary.damping == 0.01 and summary.verdict.error_estimated is True
    assert summary.angle_labels == ["45_120", "0_0"] and summary.angles_deg == [[45.0, 120.0], [0.0, 0.0]]
    assert len(summary.full.moments["0_0"]) == 6
    assert reducer.result(-1, "error_estimated")[0] == 1     # the errors recorded are the estimator's
    with pytest.raises(kryflex.Error):
        reducer.result(2, "reduced_dofs")      # two angles of interest, not the scene's three


def test_keyword_options_set_this_reducer_only(scenes):
    """Reducer(scene, **options) takes -kf_ options by name (moments=6, method="multi-angle", verify=False,
    damping=0.01): they reach the C reducer and are gone from PETSc's options afterwards."""
    from petsc4py import PETSc
    scene = kryflex.load_scene(scenes["frames"])
    reducer = kryflex.Reducer(scene, quiet=True, moments=6, method="multi-angle", verify=False, damping=0.01)
    opts = PETSc.Options()
    assert not any(opts.hasName(n) for n in ("kf_moments", "kf_method", "kf_verify", "kf_damping"))
    reduction = reducer.reduce()
    assert reduction.model.settings["moments"] == 6 and reduction.model.settings["method"] == "multi-angle"
    assert reduction.model.settings["damping"] == 0.01
    assert reducer.result(-1, "error_estimated")[0] == 1


def test_quiet_silences_the_progress_lines_for_the_call_only(scenes, capfd):
    from petsc4py import PETSc
    opts = PETSc.Options()
    was = opts.hasName("kf_quiet")
    if was:
        opts.delValue("kf_quiet")
    try:
        capfd.readouterr()
        scene = kryflex.load_scene(scenes["frames"], quiet=True)      # loading the body files: silent too
        kryflex.Reducer(scene, quiet=True).reduce()
        assert "[kryflex" not in capfd.readouterr().out
        assert not opts.hasName("kf_quiet")
        scene.verify["full_order"] = False
        kryflex.Reducer(scene).reduce()
        assert "[kryflex" in capfd.readouterr().out
        kryflex.load_scene(scenes["frames"])
        assert "loaded stiffness of body" in capfd.readouterr().out
    finally:
        if was:
            opts.setValue("kf_quiet", True)


def test_bad_settings_are_errors_not_crashes(scenes):
    scene = kryflex.load_scene(scenes["frames"])
    r = kryflex._core.CReducer()
    with pytest.raises(ValueError, match="set the scene first"):
        r.set_angles([[0.0, 0.0]])
    with pytest.raises(ValueError, match="reducer type"):
        r.set_type("lanczos")
    r.set_scene(scene.cscene)
    with pytest.raises(ValueError, match="one row of 2 angle"):
        r.set_angles([[0.0]])
    with pytest.raises(ValueError, match="finite"):
        r.set_angles([[0.0, np.nan]])
    with pytest.raises(kryflex.Error, match="moments"):
        r.set_moments(2, 2)
    with pytest.raises(kryflex.Error, match="damping"):
        r.set_damping(1.5)
    with pytest.raises(kryflex.Error, match="KFReducerSolve"):
        r.models()
    with pytest.raises(TypeError):
        r.models(dict)


# ================================================================================================ the command

@pytest.mark.parametrize("flag", ["-help", "--help", "-h"])
def test_reduce_help_lists_the_reducer_options(flag):
    proc = run([KRYFLEX_CMD, "reduce", flag], timeout=60)
    out = proc.stdout
    assert "usage: kryflex reduce" in out and "-scene." in out
    for option, default in (("-kf_reducer_type", "krylov"), ("-kf_moments", "auto"), ("-kf_band", "0.01"),
                            ("-kf_damping", "0.0025"), ("-kf_keep_threshold", "0.05"), ("-kf_method", "auto"),
                            ("-kf_verify", "auto"), ("-kf_quiet", None)):
        lines = [line for line in out.splitlines() if line.strip().startswith((option + " ", option + ":"))]
        assert lines, "%s is not listed by kryflex reduce %s:\n%s" % (option, flag, out)
        assert default is None or default in lines[0], (option, lines[0])
    assert out.count("-kf_moments <") == 1
    assert proc.stderr.strip() == ""


@pytest.mark.mpi
def test_reduce_help_under_mpi_prints_once():
    out = run(mpi(2) + [KRYFLEX_CMD, "reduce", "-help"], timeout=60).stdout
    assert out.count("usage: kryflex reduce") == 1 and out.count("-kf_moments <") == 1


# ================================================================================================ the C example

@pytest.mark.skipif(not os.path.exists(EXAMPLE), reason="build/examples/reduce_galileo not built")
def test_c_example_writes_the_command_model(tmp_path, solved):
    """examples/reduce_galileo.c (the C API alone) writes the same reduced model as `kryflex reduce`."""
    out = tmp_path / "cli"
    run([KRYFLEX_CMD, "reduce", GALILEO, "-o", out, "-quiet"])
    h5 = tmp_path / "example.h5"
    run([EXAMPLE, "-mesh_dir", os.path.dirname(GALILEO), "-o", h5, "-kf_quiet"], timeout=300)
    angles = [list(c) for c in solved("galileo").scene.configurations] + OTHER_ANGLES["galileo"]
    assert_same_model(kryflex.ReducedModel.load(str(h5)), kryflex.ReducedModel.load(str(out / "reduced.h5")), angles,
                      "examples/reduce_galileo")


# ================================================================================================ import

def test_import_has_no_side_effects():
    code = ("import sys, kryflex\n"
            "assert 'petsc4py.PETSc' not in sys.modules and 'kryflex._core' not in sys.modules, sorted(sys.modules)\n"
            "import petsc4py\n"
            "print('ok')\n")
    proc = run([PYTHON, "-c", code], timeout=60)
    assert proc.stdout.strip() == "ok"
    code = ("import kryflex\n"
            "kryflex.Reducer\n"
            "from petsc4py import PETSc\n"
            "print(PETSc.Sys.isInitialized())\n")
    assert run([PYTHON, "-c", code], timeout=60).stdout.strip() == "True"
