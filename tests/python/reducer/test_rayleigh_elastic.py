"""The reported elastic error under stiffness-proportional Rayleigh damping (C = beta K, the scene's rayleigh key),
checked against an independent dense reference: the case of benchmarks/peers, where kryflex at 1e-4 seemed to pass
falsely (reported <= 1e-4, measured 2.0e-4).

The cause was the bench's yardstick, not kryflex: its rigid-body and mechanism modes came from an eigensolver, whose
null space of K is only known to eps lam_max / lam_1, and at the band's bottom the rigid response is up to 1e5 times
a pair's elastic peak. With the geometric rigid modes Q (node coordinates and joints: reference.geometric_rigid_modes)
and C Q = 0, the split T(w) = He Z(w)^-1 Ge - H Q Q^T G / w^2 (Ge = G - M Q Q^T G, He = H - H Q Q^T M, Z = K (1 + i w
beta) - w^2 M) is exact, and the measured error is kryflex's reported one (2.16e-5 against 2.16e-5 on the 2,760-dof
solid; the bench now takes these modes).

Here on Galileo (dense, 28 dofs; beta = 2 zeta / omega_1 with zeta = 0.25 %, as the bench) at 1e-2, 1e-3 and 1e-4:
`kryflex reduce` (1 rank; 1e-3 also on 2), then the model it wrote against the dense split at every angle of
interest and every midpoint, on a grid 4x finer than kryflex's plus 29 points across every full-order resonance (at
the first mode's ratio and at the mode's own, beta w_k / 2) and every resonance of the reduced model. Exit 0 must
mean the measured error meets the target (no false pass), exit 6 that it does not; the reported error within 10 % of
the measured one either way.
"""
import json
import os
import subprocess
import sys

import numpy as np
import pytest
import scipy.linalg as sl
import yaml

import kryflex

HERE = os.path.dirname(os.path.abspath(__file__))
SUPPORT = os.path.join(os.path.dirname(HERE), "support")
sys.path.insert(0, SUPPORT)
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
import accuracy_scenes as acs  # noqa: E402
import reference as ref  # noqa: E402

KRYFLEX = run_env.KRYFLEX
ENV = dict(run_env.ENV, MPLBACKEND="Agg", PYTHONPATH=run_env.PYTHONPATH)
ZETA = 0.0025

pytestmark = pytest.mark.skipif(not os.path.exists(KRYFLEX), reason="build/kryflex not built")


class DenseSplit:
    """Galileo's dense full order at one configuration with C = beta K, split exactly on the geometric rigid modes."""

    def __init__(self, scene, angles, beta):
        Ms, Ks, Gs, Hs = ref.assemble(scene, angles)
        R = ref.geometric_rigid_modes(scene, angles)
        Q = R @ np.linalg.inv(sl.cholesky(R.T @ Ms @ R))
        assert np.abs(Ks @ Q).max() <= 1e-12 * np.abs(Ks).max() * np.abs(Q).max()
        self.M, self.K, self.beta = Ms, Ks, beta
        self.Ge, self.He = Gs - Ms @ Q @ (Q.T @ Gs), Hs - (Hs @ Q) @ (Q.T @ Ms)
        self.rigid = Hs @ Q @ (Q.T @ Gs)
        lam = sl.eigh(Ks, Ms, eigvals_only=True)
        self.flexible_hz = np.sqrt(lam[Q.shape[1]:]) / (2 * np.pi)

    def elastic(self, f_hz):
        return np.array([self.He @ np.linalg.solve(self.K * (1 + 1j * w * self.beta) - w**2 * self.M, self.Ge)
                         for w in 2 * np.pi * np.asarray(f_hz)])

    def rigid_part(self, f_hz):
        return -self.rigid[None] / ((2 * np.pi * np.asarray(f_hz)) ** 2)[:, None, None]


@pytest.fixture(scope="module")
def setting(tmp_path_factory):
    """The scene's dense reader, beta, and a folder."""
    scene = ref.load_scene(acs.GALILEO)
    first = DenseSplit(scene, [0.0], 0.0).flexible_hz[0]
    return scene, 2 * ZETA / (2 * np.pi * first), str(tmp_path_factory.mktemp("rayleigh"))


def reduce(setting, target, nranks):
    scene, beta, folder = setting
    tag = "rayleigh_%g_%d" % (target, nranks)
    path = acs.write_variant(acs.GALILEO, os.path.join(folder, tag + ".yaml"), accuracy=target,
                             damping={"modal": 0.0, "rayleigh": {"alpha": 0.0, "beta": float(beta)}})
    out = os.path.join(folder, "out_" + tag)
    cmd = [KRYFLEX, "reduce", path, "-o", out, "-kf_quiet"]
    if nranks > 1:
        cmd = ["mpiexec", "-n", str(nranks)] + cmd
    p = subprocess.run(cmd, env=ENV, capture_output=True, text=True, timeout=600)
    assert p.returncode in (0, 6), "exit %d\n%s\n%s" % (p.returncode, p.stdout[-2000:], p.stderr[-2000:])
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    return p, summary, kryflex.ReducedModel.load(os.path.join(out, "reduced.h5"))


def measured(setting, summary, model):
    """[(angles, elastic error)] at every angle of interest and midpoint."""
    scene, beta, _ = setting
    n_log = max(len(v["freq_hz"]) for v in summary["frf"].values())
    band = scene.raw["band"]
    rows = []
    for angles, _ in acs.with_midpoints([[float(a)] for a in scene.raw["angles"]]):
        full, system = DenseSplit(scene, angles, beta), model.at(angles)
        own = [acs.check_grid(band, 1, [fr], beta * np.pi * fr) for fr in full.flexible_hz]   # zeta_k = beta w_k / 2
        f = np.union1d(acs.check_grid(band, n_log, np.concatenate([full.flexible_hz, system.frequencies_hz]), ZETA),
                       np.concatenate(own))
        Tel = full.elastic(f)
        Tf = Tel + full.rigid_part(f)
        peak = np.abs(Tel).max(axis=0)
        e = np.abs(Tf - system.frf(f)).max(axis=0) / np.maximum(peak, acs.PAIR_FLOOR * peak.max())
        rows.append((angles, float(e.max())))
    return rows


def check(setting, target, nranks=1):
    p, s, model = reduce(setting, target, nranks)
    rows = measured(setting, s, model)
    worst = max(e for _, e in rows)
    what = "target %g on %d rank(s): exit %d, sizes %s, reported %.4g, measured %.4g\n%s" % (
        target, nranks, p.returncode, list(model.sizes), s["error_max"], worst,
        "\n".join("  %-8s %.3e" % (a, e) for a, e in rows))
    print(what)
    assert s["accuracy_measure"] == "elastic", what
    assert (p.returncode == 0) == bool(s["target_met"]) == (s["error_max"] <= target), what
    if p.returncode == 0:
        assert worst <= target, "false pass: " + what
    assert abs(s["error_max"] - worst) <= 0.10 * worst, what
    return s, model


@pytest.mark.slow
@pytest.mark.parametrize("target", [1e-2, 1e-3, 1e-4])
def test_rayleigh_reported_is_measured(setting, target):
    check(setting, target)


@pytest.mark.slow
@pytest.mark.mpi
def test_rayleigh_two_ranks(setting):
    s1, m1 = check(setting, 1e-3)
    s2, m2 = check(setting, 1e-3, nranks=2)
    assert list(m1.sizes) == list(m2.sizes)
    assert s2["error_max"] == pytest.approx(s1["error_max"], rel=1e-3)
