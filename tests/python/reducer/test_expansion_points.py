"""Expansion points inside the band (src/reducer/shifts.c, -kf_max_factorizations): Krylov blocks of
(K - sigma M)^-1 M at points the search chooses, checked against an independent dense NumPy/SciPy reference.

Scenes: the 2,760-dof solid spacecraft (meshes/solid, refine 0.5) at one angle (90 deg, band 0.01-15 Hz,
zeta 0.25 %), and Galileo (meshes/galileo, its six angles). The elastic error (tests/python/elastic_measure.py) is
the total response's error divided by each pair's elastic peak, on a grid with points across every full-order and
reduced resonance.
"""
import os
import subprocess
import sys

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
SUPPORT = os.path.join(os.path.dirname(HERE), "support")   # the helpers (tests/python/support)
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(HERE)))
sys.path.insert(0, SUPPORT)
import accuracy_scenes as acc  # noqa: E402
import elastic_measure as em  # noqa: E402
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
from rank_runs import results_on_ranks  # noqa: E402

SOLID_ANGLES = [[90.0]]
SOLID_BAND = [0.01, 15.0]
ZETA = 0.0025
MAXF = 4                     # factorizations the search may spend on points
# L^0 of a model with points: the blocks at zero are in it, so it stays exact. Against the dense reference (one eigh
# of the 2,755-dof system) every model of this solid, with or without points, at 24 or 31 dofs, measured 1.39e-10
# on one machine and 1.53e-9 on an AMD EPYC one: that is the reference's own floor on this scene (its eigh's
# rounding), so the bound is the moment-only model's distance to the same reference, with room (STATIC_FLOOR), and,
# more tightly, the model with points must give the moment-only model's L^0 to 1e-11.
STATIC_FLOOR = 1.5
STATIC_SAME = 1e-11


@pytest.fixture(scope="module")
def solid(tmp_path_factory):
    work = str(tmp_path_factory.mktemp("expansion_solid"))
    base = acc.solid_base(os.path.join(work, "solid"))
    path = acc.write_variant(base, os.path.join(work, "one.yaml"), angles=SOLID_ANGLES, band=SOLID_BAND,
                             reduction=None)
    return path, acc.DenseReference(path, os.path.join(work, "dense"))


@pytest.fixture(scope="module")
def galileo(tmp_path_factory):
    work = str(tmp_path_factory.mktemp("expansion_galileo"))
    spec = acc.galileo_spec()
    path = acc.write_variant(spec.base, os.path.join(work, "galileo.yaml"), reduction=None)
    return path, acc.DenseReference(path, os.path.join(work, "dense")), spec.configurations


def reduce(path, **options):
    import kryflex
    return kryflex.reduce(kryflex.load_scene(path), quiet=True, **options)


def static_error(model, dense, angles):
    """|L0_red - L0_full| / |L0_full| with L0_full = sum over flexible modes H phi phi^T G / lambda (dense)."""
    full = dense.at(angles)
    f = ~full.rigid
    L0 = (full.hp[:, f] / full.lam[f]) @ full.pg[f]
    L0r = model.at(angles).moments(1)[0]
    return float(np.linalg.norm(L0r - L0) / np.linalg.norm(L0))


def test_points_factored_inside_the_band_static_moment_exact(solid):
    """A model with points (the family forced, so that it is the one measured): its points lie in the band, their
    factorizations are reported and within the cap, L^0 is exact, and its elastic error is measured independently."""
    path, dense = solid
    red = reduce(path, accuracy=1e-4, max_factorizations=MAXF, shift_family_only=True)
    c = red.summary.chosen
    points = c.expansion_points_hz
    print("points %s Hz, %d factorizations, spent %d" % (points, c.expansion_point_factorizations,
                                                       red.summary.expansion_point_search.factorizations_spent))
    assert points, "the forced family chose no point"
    assert all(SOLID_BAND[0] < f < SOLID_BAND[1] * 1.01 for f in points)
    assert c.expansion_point_factorizations == len(points)          # one angle: one factorization per point
    assert 0 < red.summary.expansion_point_search.factorizations_spent <= MAXF
    rows = red.summary.expansion_point_search.rows
    assert rows and all(r.factorizations_spent <= MAXF for r in rows)
    err = static_error(red.model, dense, SOLID_ANGLES[0])
    el, tot = em.errors(red.model, dense, SOLID_ANGLES, SOLID_BAND, ZETA)
    L0p = red.model.at(SOLID_ANGLES[0]).moments(1)[0]
    L0m = reduce(path, accuracy=1e-4).model.at(SOLID_ANGLES[0]).moments(1)[0]
    same = float(np.linalg.norm(L0p - L0m) / np.linalg.norm(L0m))
    print("L0 relative error %.2e (against the moment-only model's %.2e); elastic %.2e, total %.2e, kryflex's %.2e"
          % (err, same, el, tot, c.worst_error))
    floor = static_error(reduce(path, accuracy=1e-4).model, dense, SOLID_ANGLES[0])
    assert err <= STATIC_FLOOR * floor
    assert same <= STATIC_SAME
    # the model kryflex measured is the one the dense reference measures: its verdict holds (to the grids' 5 %) on
    # the independent measure of the same kind (total here; elastic where kryflex's search measures it)
    measure = red.summary.verdict.accuracy_measure or "total"
    assert (el if measure == "elastic" else tot) <= 1e-4 * 1.05


def test_a_point_at_the_largest_error_lowers_it(solid):
    """The greedy step: 1 moment at zero, then a point at the frequency of its largest error; the model with the point
    is more accurate by kryflex's own measure (the search table's first rows are those two models)."""
    path, dense = solid
    red = reduce(path, accuracy=1e-9, max_factorizations=1, shift_family_only=True)
    rows = red.summary.expansion_point_search.rows
    first = [r for r in rows if r.moments == 1]
    print(first)
    assert first[0].points == 0 and first[1].points == 1
    assert first[1].error < first[0].error
    assert red.summary.expansion_point_search.factorizations_spent == 1


def test_no_budget_is_the_moment_only_model(solid):
    """-kf_max_factorizations 0 (the default) is today's search: no point, the same model."""
    path, dense = solid
    a = reduce(path, accuracy=1e-3)
    b = reduce(path, accuracy=1e-3, max_factorizations=0)
    assert a.summary.chosen.expansion_points_hz == [] == b.summary.chosen.expansion_points_hz
    assert a.summary.chosen.dofs == b.summary.chosen.dofs
    M1, M2 = a.model.at([90.0]).M, b.model.at([90.0]).M
    np.testing.assert_allclose(M1, M2, rtol=0, atol=1e-12 * np.abs(M1).max())


def _elastic_measure_default():
    """Whether kryflex's own search measures the elastic response (the elastic-accuracy work): until it does, the
    search is driven by the total response and cannot target an elastic error."""
    try:
        from kryflex.report import summary
        return hasattr(summary, "accuracy_measure")
    except ImportError:
        return False


@pytest.mark.slow
@pytest.mark.parametrize("target", [1e-2, 1e-3, 1e-4])
def test_elastic_target_no_more_dofs_than_moment_only_solid(solid, target):
    """At each elastic target, the model the search chooses with points meets it (dense measure) with no more
    second-order dofs than the moment-only model."""
    if not _elastic_measure_default():
        pytest.skip("kryflex's search measures the total response here; the elastic measure is another branch's")
    path, dense = solid
    mo = reduce(path, accuracy=target)
    sh = reduce(path, accuracy=target, max_factorizations=MAXF)
    rows = []
    for name, red in (("moment-only", mo), ("points", sh)):
        el, tot = em.errors(red.model, dense, SOLID_ANGLES, SOLID_BAND, ZETA)
        dofs = em.system_dofs(red.model, SOLID_ANGLES)
        rows.append((name, dofs, el, red.summary.chosen.expansion_points_hz))
        print("solid %g %s: %d dofs, elastic %.2e, total %.2e, points %s" % (target, name, dofs, el, tot, rows[-1][3]))
    assert rows[1][2] <= target * 1.05
    assert rows[1][1] <= rows[0][1]
    assert static_error(sh.model, dense, SOLID_ANGLES[0]) <= STATIC_FLOOR * static_error(mo.model, dense, SOLID_ANGLES[0])


@pytest.mark.slow
@pytest.mark.parametrize("target", [1e-2, 1e-3])
def test_elastic_target_no_more_dofs_than_moment_only_galileo(galileo, target):
    """The same on Galileo at its six angles and their midpoints (the points at every expansion angle)."""
    if not _elastic_measure_default():
        pytest.skip("kryflex's search measures the total response here; the elastic measure is another branch's")
    path, dense, configs = galileo
    mo = reduce(path, accuracy=target)
    sh = reduce(path, accuracy=target, max_factorizations=2 * MAXF)
    out = []
    for name, red in (("moment-only", mo), ("points", sh)):
        el, tot = em.errors(red.model, dense, configs, [0.01, 10.0], ZETA)
        out.append((em.system_dofs(red.model, configs), el))
        print("galileo %g %s: %d dofs, elastic %.2e, total %.2e, points %s" % (
            target, name, out[-1][0], el, tot, red.summary.chosen.expansion_points_hz))
    assert out[1][1] <= target * 1.05
    assert out[1][0] <= out[0][0]


def test_bad_budget_exits_2_naming_the_option(solid, tmp_path):
    path, _ = solid
    for opt, val in (("-kf_max_factorizations", "-1"), ("-kf_shift_blocks", "0")):
        run = subprocess.run([os.path.join(ROOT, "build", "kryflex"), "reduce", path, "-o", str(tmp_path / "out"),
                              opt, val], capture_output=True, text=True, timeout=120)
        print(run.returncode, run.stderr[-400:])
        assert run.returncode == 2
        assert opt in run.stderr and "Traceback" not in run.stderr


TWO_RANKS = r"""
import json, sys
import kryflex
red = kryflex.reduce(kryflex.load_scene(sys.argv[1]), quiet=True, accuracy=1e-4, max_factorizations=4,
                     shift_family_only=True)
from mpi4py import MPI
if MPI.COMM_WORLD.rank == 0:
    c = red.summary.chosen
    print("RESULT " + json.dumps({"dofs": c.dofs, "points": c.expansion_points_hz, "moments": c.moments,
                                  "rows": [(r.moments, r.points, r.reduced_dofs)
                                           for r in red.summary.expansion_point_search.rows]}))
"""


@pytest.mark.mpi
def test_one_and_two_ranks_choose_the_same_model(solid, tmp_path):
    path, _ = solid
    res = dict(zip((1, 2), results_on_ranks(TWO_RANKS, tmp_path, dict(run_env.ENV, PYTHONPATH=run_env.PACKAGE),
                                            args=[path])))
    print(res)
    assert res[1]["dofs"] == res[2]["dofs"] and res[1]["moments"] == res[2]["moments"]
    assert res[1]["rows"] == res[2]["rows"]
    np.testing.assert_allclose(res[1]["points"], res[2]["points"], rtol=1e-9)


def test_multi_angle_points_at_every_expansion_angle(galileo):
    """The multi-angle method combines points and angles: each point is factored at every expansion angle of the
    model, and L^0 at each of those angles is as accurate as the moment-only multi-angle model's (dense reference).
    That model is not exact there: its bases at two angles share one body projection, deflated at the body
    tolerance, and it measured 2.3e-8 and 1.9e-8 at 0 and 72 deg on 2026-11-29."""
    path, dense, configs = galileo
    red = reduce(path, accuracy=1e-3, method="multi-angle", max_factorizations=12, shift_family_only=True)
    c = red.summary.chosen
    angles = c.expansion_angles_deg
    print("points %s Hz at angles %s, %d factorizations, %d dofs" % (c.expansion_points_hz, angles,
                                                                    c.expansion_point_factorizations, c.dofs))
    assert c.method == "multi-angle" and c.expansion_points_hz
    distinct = {tuple(a) for a in angles}
    assert len(distinct) >= 2
    assert c.expansion_point_factorizations == len(c.expansion_points_hz) * len(distinct)
    base = reduce(path, accuracy=1e-3, method="multi-angle")
    assert base.summary.chosen.expansion_points_hz == []
    for a in sorted(distinct):
        err, err0 = static_error(red.model, dense, list(a)), static_error(base.model, dense, list(a))
        print("L0 at %s deg: %.2e (moment-only multi-angle model %.2e)" % (a, err, err0))
        assert err <= 1.1 * err0 + 1e-12
