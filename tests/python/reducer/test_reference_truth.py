"""The full-order reference against the truth on models written the way commercial codes write them.

Free-free plates with (uz, rx, ry) nodes and lumped translational masses, some offset from their nodes, so that M is
singular far beyond its zero diagonal (bc_models.lumped_plate), exported as long-field DMIG* punches and read back by
kryflex's Nastran reader (reference_truth_probe.py): 45 dofs (dense reference path) and 630 dofs (sparse path), each
also through the other path; and a 192-dof stick aircraft (bc_models.lumped_aircraft) whose inputs act on M's null
space, so that its response holds a static part no mode carries. Each reduces as exported; its reference (reducer.frf(c, 'full')) agrees with an
independent dense SciPy response (M's null space condensed here with numpy's eigh, every mode by scipy.linalg.eigh)
to 1e-6 of each pair's peak; the chosen model meets its target against that SciPy response; the direct-solve check
reports a disagreement below 1e-6; and a reference deliberately left incomplete (the sparse path with 2 modes) fails
the check with exit 3 naming the frequency and the angle. Serially and on 2 ranks (which must agree).
"""
import os
import re
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
PROBE = os.path.join(SUPPORT, "reference_truth_probe.py")
ENV = dict(run_env.ENV, PYTHONPATH=run_env.PACKAGE)
TIMEOUT = 240
PAIR_FLOOR = 1e-4          # KF_FRF_PAIR_FLOOR: a pair's peak below this fraction of the largest is measured against it
RIGID = 3                  # a free plate out of its plane: uz, rx, ry
SPARSE, DENSE = ["-kf_verify_dense_max_dofs", "0"], ["-kf_verify_dense_max_dofs", "1000"]
# (size, extra options): each size through its own path and through the other one
CASES = {"small-dense": ("small", []), "small-sparse": ("small", SPARSE),
         "large-sparse": ("large", []), "large-dense": ("large", DENSE), "aircraft-dense": ("aircraft", [])}
NRIGID = {"small": RIGID, "large": RIGID, "aircraft": 6}


def run(size, out, ranks, options=()):
    cmd = [sys.executable, PROBE, size, str(out), *options]
    if ranks > 1:
        cmd = ["mpiexec", "-n", str(ranks)] + cmd
    return subprocess.run(cmd, env=ENV, capture_output=True, text=True, timeout=TIMEOUT)


def scipy_modes(M, K, static=False):
    """Every finite mode of (K, M) with M singular: M = U diag(mu) U^T, the null directions (mu <= 1e-8 max mu)
    condensed statically, the condensed pencil by scipy.linalg.eigh; modes expanded to every dof, M-normalized.
    static: also Z K_zz^-1 Z^T, the flexibility of M's null space that no mode carries (a load there moves it
    statically at every frequency)."""
    mu, U = np.linalg.eigh(0.5 * (M + M.T))
    null = mu <= 1e-8 * mu.max()
    Z, Y = U[:, null], U[:, ~null]
    T = Y - Z @ np.linalg.solve(Z.T @ K @ Z, Z.T @ K @ Y)
    Kc, Mc = T.T @ K @ T, T.T @ M @ T
    lam, V = sl.eigh(0.5 * (Kc + Kc.T), 0.5 * (Mc + Mc.T))
    if static:
        return lam, T @ V, int(null.sum()), Z @ np.linalg.solve(Z.T @ K @ Z, Z.T)
    return lam, T @ V, int(null.sum())


def io_matrices(size):
    """G (n x a) and H (t x n) of the model's scene over the dofs as read back (node by node, components ascending)."""
    sys.path.insert(0, SUPPORT)
    import bc_models
    import reference_truth_probe as probe
    _, _, G, H = bc_models.layout_reference(probe.model_spec(size))
    return G, H


def scipy_frf(M, K, G, H, f_hz, zeta, nrigid=RIGID):
    """The damped response of the scene's uniform modal damping: rigid modes 1/(-w^2), flexible 1/(lam - w^2 + 2 i
    zeta sqrt(lam) w), plus the static flexibility of M's null space: t x a per frequency."""
    lam, phi, _, S = scipy_modes(M, K, static=True)
    rigid = np.arange(len(lam)) < nrigid
    hp, pg = H @ phi, phi.T @ G
    out = []
    for w in 2 * np.pi * np.asarray(f_hz):
        d = np.where(rigid, -w * w, lam - w * w + 2j * zeta * np.sqrt(np.abs(lam)) * w)
        out.append((hp / d) @ pg + H @ S @ G)
    return np.array(out), lam


def pair_distance(T, exact):
    peak = np.abs(exact).max(axis=0)
    return float((np.abs(T - exact).max(axis=0) / np.maximum(peak, PAIR_FLOOR * peak.max())).max())


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("truth")
    return tmp, {}


def result(runs, case, ranks):
    tmp, done = runs
    if (case, ranks) not in done:
        size, options = CASES[case]
        out = tmp / ("%s_%d.npz" % (case, ranks))
        p = run(size, out, ranks, options)
        assert p.returncode == 0, "%s on %d ranks:\n%s\n%s" % (case, ranks, p.stdout, p.stderr[-3000:])
        done[case, ranks] = dict(np.load(out))
    return done[case, ranks]


@pytest.mark.parametrize("size", ["small", "large", "aircraft"])
def test_exported_mass_is_singular_beyond_its_zero_diagonal(runs, size):
    """The premise: the mass as read back from the punch has a null space larger than its zero diagonal."""
    r = result(runs, size + ("-sparse" if size == "large" else "-dense"), 1)
    M = r["M"]
    zero_diag = int(np.count_nonzero(np.diag(M) == 0))
    _, _, nnull = scipy_modes(M, r["K"])
    print("%s model: %d dofs, %d zero-diagonal dofs, null space of M %d" % (size, len(M), zero_diag, nnull))
    assert nnull > zero_diag > 0
    assert len(M) > 600 if size == "large" else len(M) < 600


@pytest.mark.parametrize("ranks", [1, pytest.param(2, marks=pytest.mark.mpi)])
@pytest.mark.parametrize("case", list(CASES))
def test_reference_agrees_with_dense_scipy_and_target_met(runs, case, ranks):
    size = CASES[case][0]
    r = result(runs, case, ranks)
    G, H = io_matrices(size)
    exact, lam = scipy_frf(r["M"], r["K"], G, H, r["f"], float(r["zeta"]), NRIGID[size])
    nr = NRIGID[size]
    assert np.all(np.abs(lam[:nr]) < 1e-6 * (2 * np.pi * r["band"][0]) ** 2) and lam[nr] > (2 * np.pi * r["band"][0]) ** 2
    ref = pair_distance(r["Tfull"], exact)
    red = pair_distance(r["Tred"], exact)
    print("%s, %d rank(s): reference vs dense SciPy %.2e, direct-solve check %.2e, reduced model %.2e (kryflex says "
          "%.2e, target %g)" % (case, ranks, ref, float(r["check"]), red, float(r["error_max"]), float(r["accuracy"])))
    assert ref <= 1e-6
    assert float(r["check"]) <= 1e-6
    assert bool(r["target_met"])
    assert red <= float(r["accuracy"])


def test_scipy_response_is_the_direct_solve():
    """The test's own reference: the condensed modal sum, undamped, equals a direct dense solve of (K - w^2 M) x = G
    off resonance (so the modal route above is not checked against itself)."""
    sys.path.insert(0, SUPPORT)
    import bc_models
    spec = bc_models.lumped_plate()
    M, K, G, H = bc_models.layout_reference(spec)
    lam, phi, _ = scipy_modes(M, K)
    f = np.sqrt(np.abs(lam[RIGID:RIGID + 4])) / (2 * np.pi)
    for fw in np.sqrt(f[:-1] * f[1:]):              # between resonances
        w = 2 * np.pi * fw
        direct = H @ np.linalg.solve(K - w * w * M, G)
        d = np.where(np.arange(len(lam)) < RIGID, -w * w, lam - w * w)
        modal = ((H @ phi) / d) @ (phi.T @ G)
        assert np.abs(modal - direct).max() <= 1e-9 * np.abs(direct).max()


@pytest.mark.mpi
@pytest.mark.parametrize("case", ["small-sparse", "large-sparse", "aircraft-dense"])
def test_two_ranks_agree_with_one(runs, case):
    one, two = result(runs, case, 1), result(runs, case, 2)
    assert np.allclose(one["f"], two["f"], rtol=1e-12)
    peak = np.abs(one["Tfull"]).max()
    assert np.abs(one["Tfull"] - two["Tfull"]).max() <= 1e-8 * peak


@pytest.mark.parametrize("ranks", [1, pytest.param(2, marks=pytest.mark.mpi)])
def test_incomplete_reference_is_caught(tmp_path, ranks):
    """The sparse path with 2 modes of a plate with 13 in its band: the residual of the rest is quasi-static, wrong at
    the band's resonances. The direct solves catch it: exit 3, the frequency and the configuration named (the structure:
    this scene has no revolute joint), nothing written."""
    out = tmp_path / "bad.npz"
    p = run("large", out, ranks, SPARSE + ["-kf_verify_modes", "2"])
    assert p.returncode == 3, p.stdout + p.stderr[-2000:]
    assert "disagrees with a direct solve of the full system at" in p.stdout
    assert " Hz by " in p.stdout and "the full-order reference of the structure disagrees" in p.stdout
    assert " deg" not in p.stdout
    assert "Traceback" not in p.stderr
    assert not out.exists()


GALILEO = os.path.join(ROOT, "meshes", "galileo", "galileo.yaml")
KRYFLEX = [sys.executable, "-m", "kryflex"]


def test_inexact_block_solves_are_said_under_quiet(tmp_path):
    """A refinement threshold no solve can reach (-kf_refine_rtol 1e-14): every block is escalated and stays above;
    summary.json counts them, the report's notes and the verdict line say so under -quiet, and the verdict is the
    checked reference's (exit 0: the model is measured against a reference the direct solves confirm)."""
    import json
    out = tmp_path / "out"
    p = subprocess.run(KRYFLEX + ["reduce", GALILEO, "-o", str(out), "-quiet", "-kf_refine_rtol", "1e-14"], env=ENV,
                       capture_output=True, text=True, timeout=TIMEOUT)
    assert p.returncode == 0, p.stdout + p.stderr[-2000:]
    s = json.loads((out / "summary.json").read_text())
    perf = s["performance"]
    assert perf["blocks_unconverged"] > 0 and perf["blocks_escalated"] >= perf["blocks_unconverged"]
    assert perf["residual_final_max"] > 1e-14
    assert any("block solves stayed above -kf_refine_rtol" in n for n in s["notes"])
    assert "block solves stayed above -kf_refine_rtol after refinement and escalation" in p.stderr
    last = p.stdout.strip().splitlines()[-1]
    assert "block solves inexact" in last and "measured against the full order" in last
    assert s["reference_check"]["error"] <= 1e-6
    assert "checked against solves of the full system" in (out / "report.md").read_text()


def test_reference_check_in_summary_and_report(tmp_path):
    import json
    out = tmp_path / "out"
    p = subprocess.run(KRYFLEX + ["reduce", GALILEO, "-o", str(out)], env=ENV, capture_output=True,
                       text=True, timeout=TIMEOUT)
    assert p.returncode == 0, p.stdout + p.stderr[-2000:]
    s = json.loads((out / "summary.json").read_text())
    check = s["reference_check"]
    assert 0 <= check["error"] <= check["rtol"] == 1e-6
    assert set(check["per_angle"]) == set(s["angle_labels"])
    # the whole check is the worst of every configuration checked, midpoints included (their progress lines)
    assert max(v["error"] for v in check["per_angle"].values()) <= check["error"]
    worst = [float(m) for m in re.findall(r"worst disagreement (\S+) of the pair's peak", p.stdout)]
    assert len(worst) == len(s["angle_labels"]) + len(s["midpoints"])
    assert abs(max(worst) - check["error"]) <= 5e-3 * check["error"]
    assert "block solves inexact" not in p.stdout


@pytest.mark.parametrize("option, value", [("-kf_verify_check_rtol", "2"), ("-kf_verify_check_points", "-1")])
def test_bad_check_options_are_named(tmp_path, option, value):
    p = subprocess.run(KRYFLEX + ["reduce", GALILEO, "-o", str(tmp_path / "out"), "-quiet", option, value], env=ENV,
                       capture_output=True, text=True, timeout=TIMEOUT)
    assert p.returncode == 2, p.stdout + p.stderr
    assert option in p.stdout + p.stderr and "Traceback" not in p.stderr
    assert not (tmp_path / "out").exists()
