"""The estimated verdict certified by the mode count (-kf_verify auto, src/reducer/certify.c): from
-kf_verify_certified_min_dofs system dofs on (lowered to 0 here) the search's error is estimated against the richest
candidate, and certified by the full order's flexible modes below -kf_verify_certified_cover x the band's top
(Sylvester's inertia) equal to the richest candidate's at every angle of interest and midpoint; else measured. Checked:
Galileo and the solid at refine 0.5 certified, the counts equal to a dense SciPy count of the assembled full order
at every configuration, the error the plain estimator's bit for bit; a cut above the richest candidate's reach (the
solid, 20 x the band's top) fails the certificate and gives the measured verdict of -kf_verify true; below the
threshold auto is -kf_verify true bit for bit; 2 ranks agree with 1; bad values are clear errors."""
import functools
import json
import os
import subprocess
import sys

import numpy as np
import pytest

import kryflex
from kryflex import _core

HERE = os.path.dirname(os.path.abspath(__file__))
SUPPORT = os.path.join(os.path.dirname(HERE), "support")
sys.path.insert(0, SUPPORT)
sys.path.insert(0, HERE)
import accuracy_scenes  # noqa: E402
from test_mode_count import ENV, ROOT, dense, reference_frequencies  # noqa: E402

pytestmark = [pytest.mark.usefixtures("quiet_library")]

CERTIFIED = dict(verify="auto", verify_certified_min_dofs=0)


def reduce(path, **options):
    return kryflex.reduce(kryflex.load_scene(path), quiet=True, **options).summary


@pytest.fixture(scope="module")
def solid(tmp_path_factory):
    return accuracy_scenes.solid_base(str(tmp_path_factory.mktemp("solid_certified")))


def evaluation_angles(scene):
    """The angles of interest (degrees, one joint), then the midpoints between consecutive ones: the certificate's
    configurations, in its order."""
    a = [float(np.ravel(c)[0]) for c in scene.configurations]
    return a + [0.5 * (x + y) for x, y in zip(a, a[1:])]


@functools.lru_cache(maxsize=None)
def scipy_frequencies(path, angle):
    """The full order's flexible frequencies (Hz) at one configuration, by dense SciPy eigenvalues (kept: several tests
    count on the same scene, and at 2,760 dofs each configuration is seconds)."""
    scene = kryflex.load_scene(path)
    system = _core.CSystem(scene.cscene)      # one per configuration: its matrices are taken as they are
    system.set_angles(np.radians([angle]))
    Ms, Ks, _, _ = system.matrices()
    f, _ = reference_frequencies(dense(Ms), dense(Ks))
    return f


def scipy_counts(path, below_hz, which=None):
    """The full order's flexible modes below below_hz at the configurations which (indices into evaluation_angles,
    None: all)."""
    angles = evaluation_angles(kryflex.load_scene(path))
    return [int(np.sum(scipy_frequencies(path, float(angle)) < below_hz))
            for angle in (angles if which is None else [angles[k] for k in which])]


@pytest.mark.parametrize("name", ["galileo", "solid"])
def test_certified_counts_are_scipys_and_the_error_is_the_estimators(name, solid):
    path = accuracy_scenes.GALILEO if name == "galileo" else solid
    cert = reduce(path, **CERTIFIED)
    plain = reduce(path, verify=False)
    v = cert.verdict
    assert v.verdict_kind == "certified" and v.error_estimated
    c = v.certificate
    assert c["certified"] and c["full_counts"] == c["rich_counts"]
    band = kryflex.load_scene(path).band
    assert c["below_hz"] == pytest.approx(1.5 * band[1], rel=1e-12)
    # the solid's dense eigenvalues cost seconds each: an angle of interest and a midpoint
    which = None if name == "galileo" else [1, len(c["full_counts"]) - 1]
    picked = c["full_counts"] if which is None else [c["full_counts"][k] for k in which]
    assert picked == scipy_counts(path, c["below_hz"], which) and min(c["full_counts"]) > 0
    # the certificate only adds counts: the estimator's search, model and error unchanged
    assert plain.verdict.verdict_kind == "estimated" and plain.verdict.certificate is None
    assert v.error_max == plain.verdict.error_max
    assert cert.chosen.dofs == plain.chosen.dofs
    assert cert.performance.certificate_count_s > 0


@pytest.fixture(scope="module")
def fallback(solid):
    """The solid counted to 20 x the band's top (the certificate fails), and its -kf_verify true run, on 1 rank."""
    return reduce(solid, verify_certified_cover=20, **CERTIFIED), reduce(solid, verify=True)


def test_a_mode_the_richest_candidate_lacks_falls_back_to_the_measured_verdict(solid, fallback):
    """Counted to 20 x the band's top, beyond the Krylov bases' reach: the full order has modes there that the
    richest candidate lacks, so the run measures against the full order, with -kf_verify true's error."""
    cert, measured = fallback
    v = cert.verdict
    c = v.certificate
    assert not c["certified"] and v.verdict_kind == "measured" and not v.error_estimated
    assert any(f > r for f, r in zip(c["full_counts"], c["rich_counts"]))
    assert all(f >= r for f, r in zip(c["full_counts"], c["rich_counts"]))     # Poincare: never more in the model
    bad = next(k for k, (f, r) in enumerate(zip(c["full_counts"], c["rich_counts"])) if f > r)
    assert [c["full_counts"][bad]] == scipy_counts(solid, c["below_hz"], [bad])
    assert any("the certificate failed" in n for n in cert.notes)
    # the references are the full order's; their first moments by solves rather than from the visits' bases
    assert v.error_max == pytest.approx(measured.verdict.error_max, rel=1e-10)
    assert cert.chosen.dofs == measured.chosen.dofs
    for label, e in measured.chosen.frf_error.items():
        assert cert.chosen.frf_error[label] == pytest.approx(e, rel=1e-10)


def test_below_the_threshold_auto_is_the_measured_verdict_bit_for_bit():
    auto = reduce(accuracy_scenes.GALILEO)          # the default: auto, 50,000 dofs, Galileo far below
    measured = reduce(accuracy_scenes.GALILEO, verify=True)
    assert auto.verdict.verdict_kind == "measured" and auto.verdict.certificate is None
    a, m = auto.to_json(), measured.to_json()
    for d in (a, m):      # the clocks apart
        d.pop("performance", None)
        d.pop("timings_s", None)
        d["reduced"].pop("reassembly_seconds", None)
    assert a == m


def test_a_tighter_target_than_the_estimate_is_trusted_to_is_measured():
    """Below -kf_verify_certified_min_accuracy (1e-3) auto measures whatever the size: the certificate counts modes,
    it does not bound the estimate's own error (on the stress scenes damping-light and spread-1e-5 pass falsely, certified, at 1e-4)."""
    s = reduce(accuracy_scenes.GALILEO, accuracy=1e-4, **CERTIFIED)
    assert s.verdict.verdict_kind == "measured" and s.verdict.certificate is None
    assert reduce(accuracy_scenes.GALILEO, accuracy=1e-4, verify_certified_min_accuracy=1e-5,
                  **CERTIFIED).verdict.verdict_kind == "certified"


def test_two_ranks_agree_with_one(solid, tmp_path):
    serial = reduce(solid, **CERTIFIED)
    out = tmp_path / "out"
    r = subprocess.run(["mpiexec", "-n", "2", sys.executable, "-m", "kryflex", "reduce", solid, "-o", str(out),
                        "-kf_verify_certified_min_dofs", "0"], capture_output=True, text=True, timeout=600,
                       cwd=ROOT, env=ENV)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    assert "estimated, certified (" in r.stdout
    s = json.load(open(out / "summary.json"))
    assert s["verdict_kind"] == "certified"
    assert s["certificate"] == serial.verdict.certificate
    # the bases' rounding on 2 ranks moves the estimate by ~1e-9 of itself (the counts are exact integers)
    assert s["error_max"] == pytest.approx(serial.verdict.error_max, rel=1e-7)


def test_two_ranks_fall_back_as_one_rank_does(solid, fallback, tmp_path):
    """The failed certificate on 2 ranks (the bodies spread, one per rank): the same counts, the same measured verdict
    and error as 1 rank and as -kf_verify true, and the measured report's figures though no helper was started ahead
    for them (the run was planned certified)."""
    serial, measured = fallback
    out = tmp_path / "out"
    r = subprocess.run(["mpiexec", "-n", "2", sys.executable, "-m", "kryflex", "reduce", solid, "-o", str(out),
                        "-kf_verify_certified_min_dofs", "0", "-kf_verify_certified_cover", "20"],
                       capture_output=True, text=True, timeout=900, cwd=ROOT, env=ENV)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    assert "measured against the full order" in r.stdout and "Traceback" not in r.stdout + r.stderr
    s = json.load(open(out / "summary.json"))
    c = s["certificate"]
    assert s["verdict_kind"] == "measured" and not s["error_estimated"] and not c["certified"]
    assert c == serial.verdict.certificate
    assert any("the certificate failed" in n for n in s["notes"])
    # MUMPS' parallel scheduling and the bases' rounding on 2 ranks move the error by ~1e-9 of itself
    assert s["error_max"] == pytest.approx(serial.verdict.error_max, rel=1e-7)
    assert s["error_max"] == pytest.approx(measured.verdict.error_max, rel=1e-7)
    assert s["chosen"]["dofs"] == serial.chosen.dofs == measured.chosen.dofs
    assert (out / "bode_overview.png").is_file() and any(f.startswith("bode_") and f.endswith("deg.png")
                                                           for f in os.listdir(out))


@pytest.mark.parametrize("options, plan", [
    (dict(verify=True), (True, False)),
    (dict(verify=False), (False, False)),
    (dict(verify="auto"), (True, False)),                      # Galileo: far below 50,000 system dofs
    (CERTIFIED, (False, True)),
    (dict(CERTIFIED, accuracy=1e-4), (True, False)),           # tighter than -kf_verify_certified_min_accuracy
])
def test_the_plan_is_the_verdict_the_solve_gives(options, plan):
    """Reducer.verification_plan() (what kryflex reduce starts the report's helpers by) before the solve, against the
    verdict the solve then gives"""
    r = kryflex.Reducer(kryflex.load_scene(accuracy_scenes.GALILEO), quiet=True, **options)
    r.setup()
    assert r.verification_plan() == plan
    kind = r.reduce().summary.verdict.verdict_kind
    assert kind == ("measured" if plan[0] else "certified" if plan[1] else "estimated")


@pytest.mark.parametrize("args, says", [
    (["-kf_verify", "sometimes"], "-kf_verify sometimes: give auto, true or false"),
    (["-kf_verify_certified_min_dofs", "-3"], "-kf_verify_certified_min_dofs"),
    (["-kf_verify_certified_cover", "0.5"], "-kf_verify_certified_cover"),
])
def test_bad_values_are_clear_errors(args, says, tmp_path):
    r = subprocess.run([sys.executable, "-m", "kryflex", "reduce", accuracy_scenes.GALILEO, "-o",
                        str(tmp_path / "out")] + args, capture_output=True, text=True, timeout=300, cwd=ROOT, env=ENV)
    assert r.returncode == 2, r.stdout[-2000:] + r.stderr[-2000:]
    assert says in r.stderr and "Traceback" not in r.stderr + r.stdout


def test_bad_scene_value_is_a_clear_error(tmp_path):
    r = subprocess.run([sys.executable, "-m", "kryflex", "reduce", accuracy_scenes.GALILEO, "-o", str(tmp_path / "out"),
                        "-scene.verify.full_order", "sometimes"], capture_output=True, text=True, timeout=300,
                       cwd=ROOT, env=ENV)
    assert r.returncode == 2, r.stdout[-2000:] + r.stderr[-2000:]
    assert "verify.full_order" in r.stderr and "sometimes" in r.stderr and "Traceback" not in r.stderr


def test_a_certified_estimate_that_misses_the_target_is_exit_6(tmp_path):
    r = subprocess.run([sys.executable, "-m", "kryflex", "reduce", accuracy_scenes.GALILEO, "-o", str(tmp_path / "out"),
                        "-kf_verify_certified_min_dofs", "0", "-scene.accuracy", "1e-9",
                        "-kf_verify_certified_min_accuracy", "1e-12", "-quiet"], capture_output=True, text=True,
                       timeout=300, cwd=ROOT, env=ENV)
    assert r.returncode == 6, r.stdout[-2000:] + r.stderr[-2000:]
    assert "estimated, certified (" in r.stdout and "target missed" in r.stderr
    s = json.load(open(tmp_path / "out" / "summary.json"))
    assert s["verdict_kind"] == "certified" and s["target_met"] is False


@pytest.mark.parametrize("ranks", [1, 2])
def test_count_on_the_reductions_analyses(solid, tmp_path, ranks):
    """With the body-wise reduction (forced below its 20,000-dof threshold) the count in-process factors each body's shifted
    interior on the MUMPS analysis the reduction made for it: two analyses in the run, not four (the progress lines),
    and the same counts as a dense SciPy count at every configuration, 1 and 2 ranks (the bodies spread)."""
    out = tmp_path / "out"
    r = subprocess.run(["mpiexec", "-n", str(ranks), sys.executable, "-m", "kryflex", "reduce", solid, "-o", str(out),
                        "-kf_verify_certified_min_dofs", "0", "-kf_flex_solver", "bodywise"],
                       capture_output=True, text=True, timeout=600, cwd=ROOT,
                       env=dict(ENV, KRYFLEX_COUNT_HELPER="0"))     # the count in this process, on its analyses
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    assert r.stdout.count("MUMPS analysis:") == 2
    assert "K - w^2 M at" in r.stdout
    c = json.load(open(out / "summary.json"))["certificate"]
    assert c["certified"]
    assert c["full_counts"] == scipy_counts(solid, c["below_hz"]) and min(c["full_counts"]) > 0
