"""The slewing study (python/kryflex/slew, `kryflex slew`): the ties D(alpha) against C's reassembly and the dense
reference, the Newmark integrator against the exact solution (SciPy expm) of the assembled system at a fixed
angle, second-order convergence in the step, the same histories as Exudyn's solver under a slew, the reduced model's
error small at a slow slew and growing with the rate, and the command's files and refusals."""
import csv
import os
import subprocess
import sys

import numpy as np
import pytest
import scipy.linalg as sl

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


@pytest.fixture(scope="module")
def galileo(quiet_library):
    import kryflex
    scene = kryflex.load_scene(GALILEO)
    model = kryflex.Reducer(scene, quiet=True).reduce().model
    return scene, model


def _flexible_hz(N, M, K, nrigid):
    """The flexible frequencies of the system on the null space N: all but the nrigid lowest eigenvalues (a relative
    threshold would also drop a soft mode, such as Galileo's 0.11 Hz one beside kHz static-correction modes)."""
    lam = sl.eigh(N.T @ K @ N, N.T @ M @ N, eigvals_only=True)
    return np.sqrt(np.maximum(lam[nrigid:], 0.0)) / (2 * np.pi)


def test_ties_give_the_reassembled_systems(galileo):
    """The null space of D(alpha) = T(alpha) I: the full bodies give the dense reference's frequencies, the reduced
    bodies C's reassembled ones (the same ties as KFReassemble), at angles off the reduction angle."""
    from kryflex.slew.bodies import SlewBodies
    scene, model = galileo
    full, red = SlewBodies.from_scene(scene), SlewBodies.from_model(model)
    dense = ref.load_scene(GALILEO)
    for angle in (0.0, 37.0, 250.0):
        Ms, Ks, _, _ = ref.assemble(dense, angle)
        f_ref = _flexible_hz(np.eye(Ms.shape[0]), Ms, Ks, model.nrigid)
        Nf = sl.null_space(full.ties(np.radians([angle])))
        f_full = _flexible_hz(Nf, full.M.toarray(), full.K.toarray(), model.nrigid)
        assert np.allclose(f_full, f_ref, rtol=1e-8)
        Nr = sl.null_space(red.ties(np.radians([angle])))
        f_red = _flexible_hz(Nr, red.M.toarray(), red.K.toarray(), model.nrigid)
        f_c = model.at([angle]).frequencies_hz
        assert np.allclose(f_red, f_c[:len(f_red)], rtol=1e-8)
        # rigid-body and mechanism modes: as many as C counts, and tied
        Phi = np.asarray(full.rigid_modes(np.radians([angle])))
        assert Phi.shape[1] == model.nrigid == 7
        assert np.abs(full.ties(np.radians([angle])) @ Phi).max() < 1e-10 * np.abs(Phi).max()


def _dense_solution(scene_path, angle, beta, duration, t):
    """y(t) of the assembled system at a fixed angle (reference.py, null-space coordinates), damping beta K_S, all
    inputs driven by the slew torque sin(2 pi t / duration) on [0, duration]: exact, by the matrix exponential of
    the state-space system augmented with the oscillator that generates the sine (SciPy expm), stepped sample to
    sample. t: equally spaced from 0."""
    dense = ref.load_scene(scene_path)
    Ms, Ks, Gs, Hs = ref.assemble(dense, angle)
    n = Ms.shape[0]
    Minv = np.linalg.inv(Ms)
    w = 2 * np.pi / duration
    A = np.zeros((2 * n + 2, 2 * n + 2))
    A[:n, n:2 * n] = np.eye(n)
    A[n:2 * n, :n] = -Minv @ Ks
    A[n:2 * n, n:2 * n] = -beta * Minv @ Ks
    A[n:2 * n, 2 * n] = Minv @ Gs.sum(axis=1)          # forced by s = sin(w t)
    A[2 * n, 2 * n + 1], A[2 * n + 1, 2 * n] = w, -w   # s' = w c, c' = -w s
    dt = t[1] - t[0]
    step = sl.expm(A * dt)
    x = np.zeros(2 * n + 2)
    x[2 * n + 1] = 1.0
    ys = []
    for tk in t:
        if tk >= duration - 1e-12:
            x[2 * n:] = 0.0                             # the torque ends with the slew (sin(w T) = 0)
        ys.append(Hs @ x[:n])
        x = step @ x
    return np.array(ys)


def test_integrator_matches_dense_reference_at_fixed_angle(galileo):
    """At a fixed angle (amplitude 0) the time-varying model is the assembled LTI system: the Newmark histories of
    the full bodies match the exact dense solution, with second-order convergence in the step."""
    from kryflex.slew.bodies import SlewBodies
    from kryflex.slew.integrator import Integrator
    from kryflex.slew.profiles import Profile
    scene, _ = galileo
    full = SlewBodies.from_scene(scene)
    angle, beta = 30.0, 2e-3
    profile = Profile("slew", 1.5, [0.0], [np.radians(angle)])
    errs = []
    for h in (0.01, 0.005):
        t, y, _ = Integrator(full, h, beta).run(profile, 3.0)
        y_ref = _dense_solution(GALILEO, angle, beta, 1.5, t)
        errs.append(np.abs(y - y_ref).max() / np.abs(y_ref).max())
    assert errs[1] < 5e-4                         # measured 2.0e-4 at h = 5 ms
    assert 3.0 < errs[0] / errs[1] < 5.0          # second order: halving h divides the error by ~4


@pytest.mark.parametrize("profile", ["slew", "spinup"])
def test_slewing_error_small_when_slow_and_growing_with_rate(galileo, profile):
    """The reduced model's error: below the scene's accuracy for a slow slew (or spin-up), and larger for a fast
    one; the slew moves the structure rigidly, so the total output differs from its elastic part."""
    from kryflex.slew.study import SlewStudy
    scene, model = galileo
    # the fast run well above the slow run's rounding floor (2.5e-7 to 9e-7: any change in the summation order of
    # the reduction's products moves it by that much; the fast errors do not move): a spin-up peaks at half a slew's
    # rate, so its fast run is at 0.01 P1 (error 1.5e-5; at 0.02 P1 it is 1.9e-6, within 3x of the floor)
    study = SlewStudy(scene, model, profile, periods_max=1.0, periods_min=0.02 if profile == "slew" else 0.01,
                      nrates=2, settle_periods=0.5)
    slow, fast = study.sweep()
    assert slow["peak_rate_deg_s"] < fast["peak_rate_deg_s"]
    assert slow["error"] < 0.2 * scene.accuracy
    assert fast["error"] > 3 * slow["error"]
    assert study.limit([slow]) is None
    still = study.baseline()                       # the same torque, the angle held: the fixed-angle error
    assert still["error"] < 0.2 * scene.accuracy and still["peak_rate_deg_s"] == 0.0
    assert study.limit([slow, fast]) in (None, fast)
    # the total output differs from its elastic part (the slew moves the structure rigidly), in both models alike
    _, yf, ef = slow["full"]
    assert np.abs(yf - ef).max() > 0.1 * np.abs(ef).max()


def test_profiles():
    from kryflex.slew.profiles import Profile
    t = np.linspace(0, 3, 30001)
    for kind, rate in (("slew", 2.0), ("spinup", 1.0)):
        p = Profile(kind, 2.0, [2.0], [0.5])
        a = p.angles(t)[:, 0]
        assert a[0] == 0.5
        rate_num = np.gradient(a, t)
        assert np.isclose(rate_num.max(), rate, rtol=1e-3) and np.isclose(p.peak_rate, rate)
        acc = np.gradient(rate_num, t)
        assert np.abs(acc[5:-5] - 2.0 * p.s2(t)[5:-5]).max() < 1e-3 * np.abs(acc).max()
        assert np.isclose(np.abs(p.torque(t)).max(), 1.0) and p.torque(0.0) == 0.0
    with pytest.raises(ValueError, match="unknown slew profile"):
        Profile("wobble", 1.0, [1.0], [0.0])


pytestmark_cli = pytest.mark.skipif(not os.path.exists(KRYFLEX), reason="build/kryflex not built")


@pytestmark_cli
def test_command_writes_table_and_chart(tmp_path):
    out = tmp_path / "slew"
    proc = subprocess.run([KRYFLEX, "slew", GALILEO, "-o", str(out), "--rates", "2", "--periods-max", "0.5",
                           "--periods-min", "0.1", "--settle-periods", "0.5", "--steps-per-period", "10",
                           "--exudyn-check", "-quiet"], env=ENV, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    for name in ("slew.png", "slew_histories.png"):
        assert (out / name).read_bytes()[:8] == PNG
    with open(out / "slew.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 2 and float(rows[0]["peak_rate_deg_s"]) < float(rows[1]["peak_rate_deg_s"])
    assert all(float(r["error"]) >= float(r["elastic_error"]) for r in rows)
    md = (out / "slew.md").read_text()
    assert "| slew duration (s) |" in md and "Step check" in md and "galileo" in md and "No slew" in md
    difference = float(md.split("relative difference from this integrator ")[1].split()[0].rstrip("."))
    assert difference < 1e-6
    assert "results in" in proc.stdout


@pytestmark_cli
@pytest.mark.parametrize("args, message", [
    (["--rates", "1"], "--rates of at least 2"),
    (["--periods-min", "5", "--periods-max", "1"], "0 < --periods-min < --periods-max"),
    (["--settle-periods", "-1"], "--settle-periods must be >= 0"),
    (["--input", "thrust"], "--input thrust: give input names of scene 'galileo' (bearing_torque)"),
    (["--profile", "wobble"], "invalid choice"),
])
def test_command_refuses_bad_values(tmp_path, args, message):
    out = tmp_path / "o"
    proc = subprocess.run([KRYFLEX, "slew", GALILEO, "-o", str(out), "-quiet"] + args, env=ENV, capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert message in proc.stderr and "Traceback" not in proc.stderr
    assert not out.exists() or not any(p.name.startswith("slew") for p in out.iterdir())


@pytest.mark.mpi
@pytestmark_cli
def test_command_refuses_several_ranks(tmp_path):
    proc = subprocess.run(["mpiexec", "-n", "2", KRYFLEX, "slew", GALILEO, "-o", str(tmp_path / "o"), "-quiet"],
                          env=ENV, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert "one rank" in proc.stderr and "Traceback" not in proc.stderr


def test_integrator_agrees_with_exudyn_under_slewing(galileo):
    """Exudyn's own solver on the same time-varying equations (exudyn_check.py: a generic ODE2 object, the ties
    D(alpha(t)) as a coordinate-vector constraint with user functions; generalized-alpha with spectral radius 1, the
    trapezoidal rule, index 3, fixed step), the full Galileo bodies slewed 72 deg in 2 s: the same histories as the
    Newmark integrator at the same step (measured 7e-9 relative), and both converge to the fine-step solution."""
    pytest.importorskip("exudyn")
    from kryflex.slew.bodies import SlewBodies
    from kryflex.slew.exudyn_check import exudyn_history
    from kryflex.slew.integrator import Integrator
    from kryflex.slew.profiles import Profile
    scene, _ = galileo
    full = SlewBodies.from_scene(scene)
    profile = Profile("slew", 2.0, [np.radians(72.0)], [0.0])
    fine = 0.00125
    tf, yf, _ = Integrator(full, fine, 2e-3).run(profile, 3.0)
    to_fine = []
    for h in (0.02, 0.01):
        te, ye = exudyn_history(full, profile, 3.0, h, 2e-3)
        t, y, _ = Integrator(full, h, 2e-3).run(profile, 3.0)
        assert np.allclose(te, t)
        assert np.abs(ye - y).max() < 1e-6 * np.abs(y).max()
        to_fine.append(np.abs(ye - yf[::int(round(h / fine))]).max() / np.abs(yf).max())
    assert to_fine[1] < 1e-3 and 3.0 < to_fine[0] / to_fine[1] < 5.0     # measured 8.8e-4, 2.3e-4
