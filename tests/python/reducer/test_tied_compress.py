"""Compression of a tied model (-kf_compress with -kf_shared_directions true or auto; KFReducerCompress_Private with
tied, src/project/body_compress.c KFTiedCompressDirections / KFReducedModelCompressTied): the model's stacked body
coordinates ordered by one SVD of its whole elastic response at every angle of interest and midpoint (the bodies' rigid
motions and the static responses kept exactly), the fewest leading directions meeting the target by bisection, the
bodies tied to them.

Galileo (2 bodies, its 6 angles of interest) at 1e-3, tied (-kf_shared_directions true) with compression off and on,
checked against an independent dense NumPy/SciPy reference:
(a) the compressed model has fewer system dofs (measured 21 against 24), records its sizes (body dofs less its ties)
    and says it is tied, in the summary and as the search table's last row;
(b) its elastic error over every angle and midpoint meets the target by the dense measure;
(c) its static moment L^0 is the uncompressed model's at every angle and midpoint (the rounding floor) and so the full
    order's;
(d) it is the Galerkin projection of the full order on its tied subspace (maps, joint constraints and ties alone);
(e) under auto it competes by system dofs: never more than the body-wise compression alone (-kf_shared_directions
    false);
(f) 2 MPI ranks choose the same model.
"""
import os
import sys

import numpy as np
import pytest
import scipy.linalg as sl

import kryflex

HERE = os.path.dirname(os.path.abspath(__file__))
SUPPORT = os.path.join(os.path.dirname(HERE), "support")
sys.path.insert(0, SUPPORT)
sys.path.insert(0, HERE)
import accuracy_scenes as acc  # noqa: E402
import elastic_measure as em  # noqa: E402
import galileo_pairs as gp  # noqa: E402
import reference as ref  # noqa: E402
from galileo_pairs import GALILEO  # noqa: E402
from test_shared_directions import tied_subspace  # noqa: E402  (the subspace from maps, constraints and ties)

TARGET = 1e-3
STATIC_SAME = 2e-10   # L^0 compressed against uncompressed (relative): Galerkin keeps it (the static responses are in
                      # the tied span); the rest is the rounding of Galileo's stiff reduced K (test_compress.py), here
                      # at most eps (f_max / f_min)^2 (gp.static_rounding, 7.7e-9 .. 9e-9), measured 2.1e-10 at most
SAME_EIG = 1e-9       # reassembled eigenvalues against NumPy's projection on the tied subspace, relative to the largest
SAME_FREQ = 1e-8      # 1 against 2 ranks: the reassembled frequencies (relative)

pytestmark = pytest.mark.usefixtures("quiet_library")


def reduce(**keyword):
    r = kryflex.Reducer(kryflex.load_scene(GALILEO), quiet=True, accuracy=TARGET, **keyword)
    return r.reduce(), r


@pytest.fixture(scope="module")
def runs():
    return {c: reduce(shared_directions=True, compress=c)[0] for c in (False, True)}


dense = gp.dense_fixture("tied_compress_dense")


def test_tied_model_is_compressed_and_recorded(runs):
    plain, comp = runs[False], runs[True]
    configurations, _, _ = gp.galileo_settings()
    n0, n1 = em.system_dofs(plain.model, configurations), em.system_dofs(comp.model, configurations)
    ch = comp.summary.chosen
    ties = comp.model.ties.shape[0]
    print("system dofs %d -> %d; bodies %s -> %s, %d ties; recorded %s -> %s" % (n0, n1, plain.model.sizes,
          comp.model.sizes, ties, ch.compressed_from_dofs, ch.compressed_to_dofs))
    assert n1 < n0
    assert ch.compressed_tied is True
    assert ch.compressed_to_dofs == sum(comp.model.sizes) - ties < ch.compressed_from_dofs
    plain_ties = 0 if plain.model.ties is None else plain.model.ties.shape[0]
    assert ch.compressed_from_dofs == sum(plain.model.sizes) - plain_ties
    assert comp.summary.verdict.target_met and ch.static_exact
    assert plain.summary.chosen.compressed_from_dofs is None
    # its row of the search table, after the search's
    row = comp.summary.search[-1]
    assert (row.variant, row.reduced_dofs, row.max_system_dofs) == ("compressed, tied across the bodies",
                                                                    ch.compressed_to_dofs, n1)
    assert row.error == pytest.approx(comp.summary.verdict.error_max, rel=1e-6)


def test_compressed_tied_model_meets_the_target_independently(runs, dense):
    configurations, band, zeta = gp.galileo_settings()
    el, _ = em.errors(runs[True].model, dense, configurations, band, zeta)
    print("elastic error %.3g (dense measure); kryflex's %.3g" % (el, runs[True].summary.verdict.error_max))
    assert el <= TARGET * 1.05      # the grids differ (kryflex's and this one's): 5 %


def test_static_moment_stays_exact_everywhere(runs, dense):
    configurations, _, _ = gp.galileo_settings()
    for angles, _ in acc.with_midpoints(configurations):
        L0c, L0p, L0f, same = gp.static_moments(runs[True].model, runs[False].model, dense, angles)
        err, err0 = (np.linalg.norm(L - L0f) / np.linalg.norm(L0f) for L in (L0c, L0p))
        print(angles, "L0 against the uncompressed model %.2e; against the dense full order %.2e (uncompressed %.2e)"
              % (same, err, err0))
        floor = max(STATIC_SAME, gp.static_rounding(runs[False].model, angles))
        assert same <= floor
        assert err <= err0 + floor


@pytest.mark.parametrize("angle", [0.0, 25.0])
def test_galerkin_on_the_tied_subspace(runs, angle):
    s = ref.load_scene(GALILEO)
    Ms, Ks, _, _ = ref.assemble(s, [angle])
    model = runs[True].model
    V = tied_subspace(s, model, angle)
    lam_ref = sl.eigh(V.T @ Ks @ V, V.T @ Ms @ V, eigvals_only=True)
    rs = model.at([angle], trimmed=False)
    assert rs.dofs == V.shape[1]
    err = np.max(np.abs(np.sort(rs.eigenvalues) - lam_ref)) / lam_ref.max()
    print("angle %g: %d dofs, eigenvalues %.2e from the NumPy projection" % (angle, rs.dofs, err))
    assert err <= SAME_EIG


def test_auto_is_never_larger_than_body_wise():
    configurations, _, _ = gp.galileo_settings()
    auto, r = reduce()                                   # the default: auto, compression on
    split, _ = reduce(shared_directions=False)
    na, ns = em.system_dofs(auto.model, configurations), em.system_dofs(split.model, configurations)
    print("auto %d system dofs (tied compression kept: %s), body-wise %d; compression %.2f s"
          % (na, auto.summary.chosen.compressed_tied, ns, float(np.ravel(r.result(-1, "time_compress"))[0])))
    assert na <= ns
    assert auto.summary.verdict.target_met


@pytest.mark.mpi
def test_two_ranks_choose_the_same_compressed_tied_model(runs, tmp_path):
    two = gp.on_two_ranks(GALILEO, tmp_path, "-kf_shared_directions", "true", "-kf_compress", "true",
                          "-kf_accuracy", str(TARGET))
    one = runs[True].model
    assert two.sizes == one.sizes and two.ties.shape == one.ties.shape
    configurations, band, _ = gp.galileo_settings()
    for angles in configurations:
        f1, f2 = one.at(angles).frequencies_hz, two.at(angles).frequencies_hz
        assert f1.shape == f2.shape
        inband = f1 <= band[1]
        np.testing.assert_allclose(f2[inband], f1[inband], rtol=SAME_FREQ)
        L1, L2 = one.at(angles).moments(1)[0], two.at(angles).moments(1)[0]
        assert np.linalg.norm(L1 - L2) <= gp.static_rounding(one, angles) * np.linalg.norm(L1)
