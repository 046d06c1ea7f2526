"""The physical slewing check (the reduced bodies in Exudyn) on the small solid scene (meshes/solid --refine 0.25, 1,308 dofs; the reduction of test_export.py):
a torque-driven slew of the REDUCED bodies in Exudyn's nonlinear floating-frame formulation (kryflex.export.exudyn:
ObjectFFRFreducedOrder per body, GenericJoint, the bearing torque as input) against kryflex's own integrator of the
FULL-order bodies (and of the reduced ones) along the angle history Exudyn produced (slew/exudyn_check.py:
ffrf_comparison). The errors are the study's, of the elastic outputs (rigid-body and mechanism modes at alpha(t) taken
out), relative to the full model's peak.

What may differ, and by how much:
- the reduction (reduced_vs_full: the same linear time-varying equations, full against reduced bodies);
- the terms the linear time-varying model leaves out and Exudyn keeps: centrifugal and Coriolis loads of the turning
  body, finite rotations, the export's four second-order inertia terms (set to zero, quadratic in the deflection).
  For a rest-to-rest cycloidal slew of amplitude A (radians) the centrifugal load per unit radius, alpha'^2 <= (2A/T)^2,
  against the drive's tangential one, alpha'' <= 2 pi A / T^2, is 2A/pi whatever the duration T: the neglected terms'
  share grows with the amplitude, not with the rate. Their effect on the outputs is that ratio times how strongly the
  outputs respond to radial against tangential loads (measured 1.1 to 2: NONLINEAR_FACTOR bounds it).
So the slow slew is run at a small amplitude (0.01 deg: 2A/pi = 1.1e-4) where Exudyn must agree with the full model
to the reduction's error plus that share; at 1 deg the Exudyn-vs-linear difference must be the neglected terms' share
(it scales with A, so an error of the export or of the state mapping, which would not, is excluded).
Measured (benchmarks/slew-exudyn/bench-slew-exudyn): 0.01 deg, 20 P1: Exudyn vs full 3.6e-4, reduced vs full 1.7e-4, Exudyn vs
reduced 2.2e-4; 0.5 P1: reduced vs full 8.8e-4. 1 deg: Exudyn vs reduced 0.012 to 0.020 (2A/pi = 0.011)."""
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "support"))
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
from run_env import run  # noqa: E402  (in run_env.COMMAND_ENV: oversubscribed, for mpiexec -n 2 on a small machine)
ROOT = run_env.ROOT
KRYFLEX = run_env.KRYFLEX
NONLINEAR_FACTOR = 3.0    # outputs' response to the neglected (radial) loads against the drive's, per unit load ratio

exudyn = pytest.importorskip("exudyn", reason="Exudyn comes with the project's .venv (scripts/setup)")



@pytest.fixture(scope="module")
def solid(tmp_path_factory, quiet_library):
    import kryflex
    out = tmp_path_factory.mktemp("solid")
    r = run([sys.executable, os.path.join(ROOT, "meshes", "solid", "generate.py"), "--refine", "0.25", "-o", str(out)])
    assert r.returncode == 0, r.stderr
    r = run([KRYFLEX, "reduce", str(out / "spacecraft.yaml"), "-o", str(out / "red"), "-quiet",
             "-scene.reduction.method", "multi-angle", "-kf_search", "0", "-kf_verify", "0"])
    assert r.returncode == 0, r.stdout + r.stderr
    path = str(out / "spacecraft.yaml")
    return kryflex.load_scene(path), kryflex.ReducedModel.load(str(out / "red" / "reduced.h5")), path


def _study(solid, amplitude_deg):
    from kryflex.slew.study import SlewStudy
    scene, model, _ = solid
    return SlewStudy(scene, model, amplitude_deg=amplitude_deg, inputs=["bearing_torque"])


def _share(r):
    """2A/pi of the turn Exudyn made: the neglected centrifugal load against the drive's tangential one."""
    return 2 * np.radians(r["turn_deg"]) / np.pi


def test_reduced_bodies_in_exudyn_follow_the_full_model(solid):
    """Slow slew (20 P1) and a faster one (0.5 P1) of 0.01 deg: Exudyn's reduced bodies agree with the full model's
    history to the reduction's error on that history plus the neglected terms' share; the reduction's error grows with
    the rate, and so does the Exudyn-vs-full one."""
    from kryflex.slew.exudyn_check import ffrf_comparison
    study = _study(solid, 0.01)
    slow, fast = ffrf_comparison(study, 20.0), ffrf_comparison(study, 0.5)
    for r in (slow, fast):
        assert r["turn_deg"] == pytest.approx(0.01, rel=0.2)          # the torque scale turned the joint as meant
    # the frames' references follow the joint's turn: what is left of the rotor frame's rotation is elastic, far
    # below the turn (1.7e-4 rad) in the slow slew
    assert slow["frame_offset"] < 1e-2 * np.radians(slow["turn_deg"])
    tol = slow["reduced_vs_full"] + NONLINEAR_FACTOR * _share(slow)
    assert slow["exudyn_vs_full"] <= tol, (slow["exudyn_vs_full"], tol)
    assert slow["exudyn_vs_full"] < 1e-3
    assert fast["reduced_vs_full"] > 2 * slow["reduced_vs_full"]
    assert fast["exudyn_vs_full"] > slow["exudyn_vs_full"]
    # the histories are not trivially small: the outputs move by the drive's elastic response
    assert np.abs(slow["full"]).max() > 0 and np.abs(slow["exudyn"]).max() > 0.9 * np.abs(slow["full"]).max()


def test_exudyn_adds_the_neglected_terms_in_proportion_to_the_amplitude(solid):
    """The same duration (5 P1) at 0.01 and 1 deg: the reduction's error stays (the equations are linear in the
    torque), the Exudyn-vs-linear difference is the neglected terms' share 2A/pi (within NONLINEAR_FACTOR) and grows
    with the amplitude (x100: by more than 30), so it is the physics the linear time-varying model leaves out."""
    from kryflex.slew.exudyn_check import ffrf_comparison
    small = ffrf_comparison(_study(solid, 0.01), 5.0)
    large = ffrf_comparison(_study(solid, 1.0), 5.0)
    assert large["reduced_vs_full"] == pytest.approx(small["reduced_vs_full"], rel=0.1)
    share = _share(large)
    assert share / NONLINEAR_FACTOR <= large["exudyn_vs_reduced"] <= NONLINEAR_FACTOR * share
    assert large["exudyn_vs_reduced"] > 30 * small["exudyn_vs_reduced"]


def test_command_reports_the_exudyn_comparison(solid, tmp_path):
    """kryflex slew --exudyn-ffrf: slew.md holds the table (the slowest and the middle slew); the command reduces the
    scene as `kryflex reduce` does (its own, smaller model), and the Exudyn-vs-linear column is the neglected terms'
    share 2A/pi again (within NONLINEAR_FACTOR)."""
    out = tmp_path / "slew"
    r = run([sys.executable, "-m", "kryflex", "slew", solid[2], "-o", str(out), "--input", "bearing_torque",
             "--rates", "2", "--periods-max", "20", "--periods-min", "2", "--amplitude", "1", "--no-step-check",
             "--exudyn-ffrf", "-quiet"])
    assert r.returncode == 0, r.stdout + r.stderr
    text = (out / "slew.md").read_text()
    assert "Reduced bodies in Exudyn's floating-frame formulation" in text
    rows = [line.split("|")[1:-1] for line in text.splitlines() if line.startswith("| 20 |") or line.startswith("| 2 |")]
    rows = [[float(x) for x in row] for row in rows if len(row) == 7]
    assert [row[0] for row in rows] == [20.0, 2.0]
    for row in rows:
        share = row[6]
        assert share == pytest.approx(2 * np.radians(row[1]) / np.pi, rel=1e-2)
        assert share / NONLINEAR_FACTOR <= row[5] <= NONLINEAR_FACTOR * share
