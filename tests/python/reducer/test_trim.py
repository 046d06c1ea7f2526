"""Trimming (reduction.max_frequency, docs/guide/trimming.md): reduced-system modes above the limit out of the
dynamics, their static share kept as a feedthrough.

On Galileo (meshes/galileo) and the solid spacecraft (meshes/solid, refine 0.5), each reduced twice with
max_frequency: 3 (3x the band's top): by the paper's fixed recipe (search: false), whose models keep static-correction
modes at hundreds of Hz, and by the accuracy search. Checked against an independent dense reference (SciPy, the
scene files read by reference.py; accuracy_scenes.py's measure, not kryflex's):

* the accuracy target is met at every angle of interest and every midpoint (the total response; the elastic one by
  the search, and the fixed recipe's verdict is the independent elastic measure's);
* the highest frequency left in the dynamics is at most 3x the band's top;
* the static moment L^0 is the untrimmed model's to 1e-10 (the same bodies reassembled with trimming off), and the
  static gain (the reduced L^0 against the dense one) is what it was untrimmed;
* the feedthrough is sum over the trimmed modes of H phi phi^T G / lambda, from a SciPy eigensolve of the untrimmed
  reduced system;
* 2 MPI ranks give the serial model's trimmed systems.

Run: PYTHONPATH=python .venv/bin/python -m pytest -q tests/python/test_trim.py
"""
import os
import subprocess
import sys

import numpy as np
import pytest
import scipy.linalg as sl
import yaml

HERE = os.path.dirname(os.path.abspath(__file__))
SUPPORT = os.path.join(os.path.dirname(HERE), "support")   # the helpers (tests/python/support)
sys.path.insert(0, SUPPORT)
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
import accuracy_scenes as acc  # noqa: E402
import elastic_measure as em  # noqa: E402

KRYFLEX = run_env.KRYFLEX
ENV = dict(run_env.ENV, PYTHONPATH=run_env.PACKAGE, MPLBACKEND="Agg")
LIMIT = 3.0
RECIPES = ("paper", "search")


def recipe(spec, name):
    """paper: the scene file's own fixed recipe (its reduction section, search off); search: the contract's."""
    if name == "paper":
        with open(spec.base) as f:
            return dict(yaml.safe_load(f).get("reduction") or {}, search=False, max_frequency=LIMIT)
    return dict(acc.CONTRACT_REDUCTION, max_frequency=LIMIT)


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    return str(tmp_path_factory.mktemp("trim"))


@pytest.fixture(scope="module", params=["galileo", "solid"])
def case(request, workdir):
    spec = acc.galileo_spec() if request.param == "galileo" else acc.solid_spec(os.path.join(workdir, "solid"))
    dense = acc.DenseReference(spec.base, os.path.join(workdir, "dense"))
    return spec, dense


def reduce(spec, path, reduction):
    import kryflex
    scene_path = spec.variant(path, accuracy=0.05, reduction=reduction)
    scene = kryflex.load_scene(scene_path)
    return scene_path, scene, kryflex.Reducer(scene, quiet=True).reduce()


def untrimmed(model):
    """The same reduced bodies reassembled with trimming off (the model's setting is what reassembly reads)."""
    import kryflex
    copy = kryflex.ReducedModel.load(model._trim_path)
    copy.set_setting("max_frequency_hz", "0")
    return copy


@pytest.fixture(scope="module", params=RECIPES)
def reduced(request, case, workdir):
    spec, dense = case
    tag = "%s_%s" % (spec.name, request.param)
    scene_path, scene, result = reduce(spec, os.path.join(workdir, tag + ".yaml"), recipe(spec, request.param))
    model = result.model
    model._trim_path = os.path.join(workdir, tag + ".h5")
    model.save(model._trim_path)
    return dict(spec=spec, dense=dense, scene=scene, scene_path=scene_path, result=result, model=model, tag=tag)


def test_accuracy_met_everywhere(reduced):
    spec, dense, scene, model = reduced["spec"], reduced["dense"], reduced["scene"], reduced["model"]
    checks = acc.evaluate_model(model, dense, spec.configurations, scene.band, scene.damping,
                                scene.verify["frequency_points"])
    assert len(checks) == 2 * len(spec.configurations) - 1
    bad = [c for c in checks if not c.error <= scene.accuracy]
    assert not bad, "%s: accuracy %g missed:\n%s" % (reduced["tag"], scene.accuracy, acc.describe(bad))
    # kryflex's verdict is on its default measure, the elastic response: measured here independently too
    elastic, _ = em.errors(model, dense, spec.configurations, scene.band, scene.damping)
    met = reduced["result"].summary.verdict.target_met
    if reduced["tag"].endswith("search"):
        assert met is True and elastic <= scene.accuracy, "%s: elastic error %g" % (reduced["tag"], elastic)
    else:   # the paper's fixed recipe is not searched: its verdict must be the independent measure's
        assert met is (elastic <= scene.accuracy), "%s: target_met %s, elastic error %g" % (reduced["tag"], met,
                                                                                          elastic)


def test_highest_frequency_and_step(reduced):
    spec, scene, model = reduced["spec"], reduced["scene"], reduced["model"]
    limit = LIMIT * scene.band[1]
    assert float(model.settings["max_frequency_hz"]) == pytest.approx(limit, rel=1e-12)
    trim = reduced["result"].summary.reduced.trimming
    trimmed = 0
    for angles, _ in acc.with_midpoints(spec.configurations):
        system = model.at(angles)
        lam = np.sort(sl.eigh(system.K, system.M, eigvals_only=True))   # the dynamics the system holds
        top = np.sqrt(lam.max()) / (2 * np.pi)
        assert top <= limit * (1 + 1e-9), "%s at %s: %g Hz left above %g Hz" % (reduced["tag"], angles, top, limit)
        assert system.top_frequency_hz == pytest.approx(top, rel=1e-8)
        assert system.explicit_step_s == pytest.approx(1 / (np.pi * top), rel=1e-8)
        full = untrimmed(model).at(angles)
        assert system.trimmed == int(np.sum(full.frequencies_hz > limit))
        assert system.untrimmed_top_hz == pytest.approx(full.frequencies_hz.max(), rel=1e-12)
        trimmed += system.trimmed
    for label in trim.top_frequency_hz:
        assert trim.top_frequency_hz[label] <= limit
    if reduced["tag"].endswith("paper"):
        # the fixed recipe keeps static-correction modes far above the band: this is where trimming has work to do
        assert trimmed > 0


def test_static_moment_exact_and_feedthrough(reduced):
    spec, dense, model = reduced["spec"], reduced["dense"], reduced["model"]
    plain = untrimmed(model)
    for angles, _ in acc.with_midpoints(spec.configurations):
        system, full = model.at(angles), plain.at(angles)
        L0, L0_untrimmed = system.moments(1)[0], full.moments(1)[0]
        scale = np.abs(L0_untrimmed).max()
        assert np.abs(L0 - L0_untrimmed).max() <= 1e-10 * scale, (reduced["tag"], angles)
        # the static gain against the dense full order: trimming changes nothing in it (the untrimmed models' own
        # error against it is the reduction's: measured 5e-6 to 2e-2 over these models, angles and midpoints)
        d = dense.at(angles)
        flex = ~d.rigid
        L0_dense = (d.hp[:, flex] / d.lam[flex]) @ d.pg[flex]
        gain_error = np.abs(L0 - L0_dense).max() / np.abs(L0_dense).max()
        gain_error_untrimmed = np.abs(L0_untrimmed - L0_dense).max() / np.abs(L0_dense).max()
        assert gain_error <= gain_error_untrimmed + 1e-10
        # the feedthrough from the untrimmed system's own modes (SciPy)
        lam, phi = sl.eigh(full.K, full.M)
        high = np.sqrt(np.clip(lam, 0, None)) / (2 * np.pi) > system.max_frequency_hz
        D = ((full.C @ phi[:, high]) / lam[high]) @ (phi[:, high].T @ full.B)
        if system.trimmed:
            assert np.abs(system.feedthrough - D).max() <= 1e-8 * scale + 1e-6 * np.abs(D).max()
        else:
            assert system.feedthrough is None and not high.any()


def test_trimmed_response_keeps_static_part(reduced):
    """At the band's bottom the response is its static part: the trimmed one equals the untrimmed one there (the
    feedthrough carries the trimmed modes' share), while without the feedthrough it would not."""
    spec, scene, model = reduced["spec"], reduced["scene"], reduced["model"]
    plain = untrimmed(model)
    for angles in spec.configurations:
        system, full = model.at(angles), plain.at(angles)
        if not system.trimmed:
            continue
        f = np.array([scene.band[1]])
        T, Tu = system.frf(f, damping=0.0), full.frf(f, damping=0.0)
        assert np.abs(T - Tu).max() <= 1e-3 * np.abs(Tu).max()


@pytest.mark.mpi
@pytest.mark.slow
def test_two_ranks_agree(reduced, tmp_path):
    """mpiexec -n 2 kryflex reduce with -kf_max_frequency 3 gives the serial model's trimmed systems."""
    import kryflex
    if not reduced["tag"].endswith("paper"):
        pytest.skip("one recipe on 2 ranks is enough (the search's is covered by the serial tests)")
    out = str(tmp_path / "out")
    run = subprocess.run(["mpiexec", "-n", "2", KRYFLEX, "reduce", reduced["scene_path"], "-o", out], env=ENV,
                         capture_output=True, text=True, timeout=600)
    # the fixed recipe's verdict on the elastic measure is the serial run's: exit 0 when met, 6 when missed
    assert run.returncode == (0 if reduced["result"].summary.verdict.target_met else 6), run.stderr[-3000:]
    assert "highest reduced frequency" in run.stdout and "trimmed" in run.stdout
    par = kryflex.ReducedModel.load(os.path.join(out, "reduced.h5"))
    assert par.settings["max_frequency_hz"] == reduced["model"].settings["max_frequency_hz"]
    for angles, _ in acc.with_midpoints(reduced["spec"].configurations):
        a, b = reduced["model"].at(angles), par.at(angles)
        assert a.trimmed == b.trimmed
        np.testing.assert_allclose(b.frequencies_hz, a.frequencies_hz, rtol=1e-8)
        np.testing.assert_allclose(b.moments(3), a.moments(3), rtol=1e-7, atol=1e-10 * np.abs(a.moments(1)).max())


def test_bad_max_frequency(tmp_path):
    """A bad limit: exit 2 naming the key and the fix, no traceback."""
    path = acc.write_variant(acc.GALILEO, str(tmp_path / "bad.yaml"), reduction={"max_frequency": "3 kHz"})
    run = subprocess.run([KRYFLEX, "reduce", path, "-o", str(tmp_path / "out")], env=ENV, capture_output=True,
                         text=True, timeout=120)
    assert run.returncode == 2, run.stdout + run.stderr
    assert "max_frequency" in run.stderr and "40 Hz" in run.stderr and "Traceback" not in run.stderr
    run = subprocess.run([KRYFLEX, "reduce", acc.GALILEO, "-o", str(tmp_path / "out2"), "-kf_max_frequency", "0.5"],
                         env=ENV, capture_output=True, text=True, timeout=120)
    assert run.returncode == 2, run.stdout + run.stderr
    assert "max_frequency" in run.stderr and "Traceback" not in run.stderr


@pytest.fixture(scope="module")
def galileo_paper(workdir):
    spec = acc.galileo_spec()
    _, scene, result = reduce(spec, os.path.join(workdir, "galileo_paper_slew.yaml"), recipe(spec, "paper"))
    return scene, result.model


def test_bodies_with_trimmed_mass_give_the_trimmed_system(galileo_paper):
    """The slew's trimmed bodies (slew/trimmed.py: the trimmed modes' mass taken out in body coordinates) restricted to
    the ties by SciPy's null space: their finite frequencies are the C trimmed system's, at angles off the expansion
    angle too."""
    from kryflex.slew.bodies import SlewBodies
    from kryflex.slew.trimmed import TrimmedMass
    scene, model = galileo_paper
    bodies = SlewBodies.from_model(model)
    mass = TrimmedMass(bodies, float(model.settings["max_frequency_hz"]))
    for angles in ([0.0], [37.5], [72.0]):
        rad = np.radians(angles)
        N = sl.null_space(bodies.ties(rad))
        Kr, Mr = N.T @ bodies.K.toarray() @ N, N.T @ mass.at(rad) @ N
        lam = sl.eig(Kr, Mr, right=False)
        lam = np.sort(lam[np.isfinite(lam)].real)
        f = np.sqrt(np.clip(lam, 0, None)) / (2 * np.pi)
        expected = model.at(angles).frequencies_hz
        # the trimmed mass is singular: its infinite eigenvalues can leave QZ finite at rounding (4.1e9 Hz on an AMD
        # EPYC machine, against 12.3 Hz for the highest mode); none is a mode
        flexible = f[(f > 0.5 * expected[0]) & (f < 1e6 * expected[-1])]
        np.testing.assert_allclose(flexible, expected, rtol=1e-6)


def test_slew_uses_the_trimmed_model(galileo_paper):
    """kryflex slew's study integrates a trimmed model trimmed (its reduced bodies' trimmed mass at every angle of the
    slew) and meets the scene's accuracy against the full order, like the untrimmed one."""
    from kryflex.slew.study import SlewStudy
    from kryflex.slew.trimmed import TrimmedIntegrator
    scene, model = galileo_paper
    study = SlewStudy(scene, model, nrates=2)
    assert isinstance(study.integrator(study.reduced, 1e-3), TrimmedIntegrator)
    assert study.top_hz <= LIMIT * scene.band[1] < study.untrimmed_top_hz
    row = study.run(4.0)
    assert row["error"] <= scene.accuracy, row["error"]


def test_export_carries_the_trimmed_systems(galileo_paper, tmp_path):
    """The neutral file holds the trimmed fixed-angle systems (M, K, B, C, D) beside the untrimmed floating-frame
    bodies, and reads them back."""
    from kryflex.export import from_model
    from kryflex.export.neutral import read_neutral, write_neutral
    _, model = galileo_paper
    data = from_model(model, [[0.0], [60.0]])
    assert data.max_frequency_hz == pytest.approx(LIMIT * 10.0)
    back = read_neutral(write_neutral(data, str(tmp_path / "x.npz")))
    assert len(back.systems) == 2
    for angles, sysd in zip(([0.0], [60.0]), back.systems):
        s = model.at(angles)
        np.testing.assert_allclose(sysd["frequencies_hz"], s.frequencies_hz, rtol=1e-12)
        np.testing.assert_allclose(sysd["D"], s.feedthrough, rtol=1e-12)
        assert sysd["frequencies_hz"].max() <= back.max_frequency_hz


@pytest.mark.parametrize("value, text", [(3, "3"), (3.5, "3.5"), ("3x", "3"), ("40 Hz", "40 Hz"), ("40hz", "40 Hz"),
                                         (None, None), ("none", None), (0, None)])
def test_scene_key_forms(value, text):
    from kryflex.io.scene_schema import _max_frequency
    assert _max_frequency("scene.yaml", "reduction.max_frequency", value) == text


@pytest.mark.parametrize("value", [True, 0.5, "0.5", "3 kHz", "-2", "fast", float("nan")])
def test_scene_key_refused(value):
    from kryflex.io.scene_schema import SceneError, _max_frequency
    with pytest.raises(SceneError, match="reduction.max_frequency.*40 Hz"):
        _max_frequency("scene.yaml", "reduction.max_frequency", value)


def test_damping_matrix_and_output_quantities(workdir):
    """Galileo's fixed recipe with Rayleigh damping (a damping matrix in the reduced system) and velocity and
    acceleration outputs beside the displacement one, trimmed at 3x: the trimmed response (the kept modes' projected
    damping, the feedthrough times i w and -w^2) stays within 1e-3 of the untrimmed model's over the band, and the
    static moment is unchanged."""
    import kryflex
    spec = acc.galileo_spec()
    with open(spec.base) as f:
        raw = yaml.safe_load(f)
    point = raw["outputs"]["pointA_ry"][0]
    path = acc.write_variant(spec.base, os.path.join(workdir, "galileo_damped.yaml"),
                             reduction=recipe(spec, "paper"), damping={"rayleigh": {"alpha": 0.01, "beta": 1e-5}})
    with open(path) as f:
        raw = yaml.safe_load(f)
    raw["outputs"]["pointA_vel"] = [dict(point, quantity="velocity")]
    raw["outputs"]["pointA_acc"] = [dict(point, quantity="acceleration")]
    with open(path, "w") as f:
        yaml.safe_dump(raw, f, sort_keys=False)
    scene = kryflex.load_scene(path)
    model = kryflex.Reducer(scene, quiet=True).reduce().model
    model._trim_path = os.path.join(workdir, "galileo_damped.h5")
    model.save(model._trim_path)
    plain = untrimmed(model)
    f = np.geomspace(scene.band[0], scene.band[1], 400)
    for angles in ([0.0], [45.0], [72.0]):
        s, u = model.at(angles), plain.at(angles)
        assert s.trimmed > 0 and s.damping_matrix is not None
        T, Tu = s.frf(f), u.frf(f)
        err = np.abs(T - Tu).max(axis=0) / np.abs(Tu).max(axis=0)
        # measured: up to 9e-6 (acceleration output, 72 deg): the trimmed modes' dynamic share at 10 Hz
        assert err.max() <= 1e-3, (angles, err)
        L0, L0u = s.moments(1)[0], u.moments(1)[0]
        assert np.abs(L0 - L0u).max() <= 1e-10 * np.abs(L0u).max()
