"""An independent dense measure of a reduced model's elastic error (helpers only, no tests).

The elastic response of a pair is the total response minus its rigid-body and mechanism part, which both models hold
exactly (the geometric rigid modes): per input/output pair, the error is max_w |T_full - T_red| divided by the peak of
T_full - T_full,rigid over the band (a pair whose elastic peak is below PAIR_FLOOR x the largest pair's is measured
against that floor, and none against less than ELASTIC_FLOOR x its own total peak, the rigid part's rounding). The full order comes from tests/python/reference.py and accuracy_scenes.DenseReference (SciPy,
one dense generalized eigendecomposition per configuration), nothing from kryflex; the reduced model only gives its
frequency response. The grid has points across every full-order resonance in the band and every reduced-model
resonance (fr (1 + zeta [-2, 2]), 29 points each), so a missed or shifted peak cannot fall between grid points.

Used by test_expansion_points.py and benchmarks/expansion_points/bench.py.
"""
import numpy as np

import accuracy_scenes as acc

PAIR_FLOOR = 1e-4
ELASTIC_FLOOR = 1e-6      # an elastic peak below this fraction of the pair's total peak is rounding (KF_FRF_ELASTIC_FLOOR)


def rigid_response(full, freqs_hz):
    """The rigid-body and mechanism part of the full-order response: sum over rigid modes hp pg / (-w^2)."""
    w = 2 * np.pi * np.asarray(freqs_hz, float)
    hp, pg = full.hp[:, full.rigid], full.pg[full.rigid]
    return -np.einsum("tr,ra->ta", hp, pg)[None] / (w**2)[:, None, None]


def errors_at(model, dense, angles, band_hz, zeta, n_log=200):
    """(elastic, total) errors of a kryflex ReducedModel at one configuration: the max over pairs."""
    full = dense.at(angles)
    system = model.at(angles)
    lam = np.asarray(system.eigenvalues, float)
    f_red = np.sqrt(np.clip(lam, 0, None)) / (2 * np.pi)
    resonances = np.concatenate([full.flexible_hz, f_red[f_red > 0]])
    f = acc.check_grid(band_hz, n_log, resonances, zeta)
    Tf = full.frf(f, zeta)
    Tr = system.frf(f)
    diff = np.abs(Tf - Tr).max(axis=0)
    el_peak = np.abs(Tf - rigid_response(full, f)).max(axis=0)
    tot_peak = np.abs(Tf).max(axis=0)
    elastic = diff / np.maximum(np.maximum(el_peak, PAIR_FLOOR * el_peak.max()), ELASTIC_FLOOR * tot_peak)
    total = diff / np.maximum(tot_peak, PAIR_FLOOR * tot_peak.max())
    return float(elastic.max()), float(total.max())


def errors(model, dense, configurations, band_hz, zeta, n_log=200):
    """(elastic, total) errors, max over the configurations of interest and the midpoints between them."""
    el, tot = 0.0, 0.0
    for angles, _ in acc.with_midpoints(configurations):
        e, t = errors_at(model, dense, angles, band_hz, zeta, n_log)
        el, tot = max(el, e), max(tot, t)
    return el, tot


def system_dofs(model, configurations):
    """Second-order dofs of the reassembled system (rigid modes included), the largest over the configurations."""
    return max(int(model.at(a).dofs) for a, _ in acc.with_midpoints(configurations))
