"""Band-aware, cluster-invariant mode importance (KFDenseModeImportanceBand) and the Hankel singular values of the
damped modal system (KFModalHankelSingularValues), against references computed here with NumPy/SciPy only:

- importance: the cluster's response ||R||_2 / |lambda_C - w^2 + 2 i zeta sqrt(lambda_C) w| maximized by brute force
  over 20001 frequencies in the band (no closed-form peak), clusters found by a loop of its own;
- cluster invariance: a random orthogonal rotation inside an exactly repeated eigenvalue leaves every importance
  unchanged (while the per-mode measures change, so the rotation is not a no-op);
- Hankel singular values: sqrt(eig(Wc Wo)) of the full 2n x 2n first-order system, Gramians by
  scipy.linalg.solve_continuous_lyapunov; and the lower bound they give: a balanced truncation of order r (built
  here with SciPy) has H-infinity error >= hsv[r] (and <= 2 sum_{k>=r} hsv[k], which checks the truncation and the
  frequency grid that measures it).

Run (from the repository root): PYTHONPATH=python .venv/bin/python -m pytest -q tests/python/reducer/test_importance_hankel.py
"""
import numpy as np
import pytest
import scipy.linalg as sl

from kryflex import _core

pytestmark = pytest.mark.fast   # the fast tier (tests/README.md)

TWO_PI = 2 * np.pi


# ------------------------------------------------------------------------------------------------ references

def orthogonal(rng, n):
    q, r = np.linalg.qr(rng.standard_normal((n, n)))
    return q * np.sign(np.diag(r))


def modal_problem(rng, freqs_hz, nrigid, a, t):
    """lambda (rigid first, then the given frequencies), Phi orthogonal (M = I), G (n x a), H (t x n)."""
    lam = np.concatenate([np.zeros(nrigid), (TWO_PI * np.asarray(freqs_hz)) ** 2])
    n = lam.size
    return lam, orthogonal(rng, n), rng.standard_normal((n, a)), rng.standard_normal((t, n))


def clusters_reference(lam, cluster_rtol, rigid_tol):
    """Lists of mode indices, ascending in frequency: chain rule w_k - w_(k-1) <= cluster_rtol w_k."""
    lmax = lam.max()
    flex = [i for i in np.argsort(lam, kind="stable") if lam[i] > 0 and lam[i] > rigid_tol * lmax]
    out = []
    for i in flex:
        w = np.sqrt(lam[i])
        if out and w - np.sqrt(lam[out[-1][-1]]) <= cluster_rtol * w:
            out[-1].append(i)
        else:
            out.append([i])
    return out


def importance_brute_force(lam, Phi, G, H, zeta, band_hz, cluster_rtol=1e-3, rigid_tol=1e-8, npoints=20001):
    w = np.linspace(TWO_PI * band_hz[0], TWO_PI * band_hz[1], npoints)
    imp, ids = np.zeros(lam.size), -np.ones(lam.size, dtype=int)
    for c, modes in enumerate(clusters_reference(lam, cluster_rtol, rigid_tol)):
        R = (H @ Phi[:, modes]) @ (Phi[:, modes].T @ G)
        lc = lam[modes].mean()
        peak = np.max(np.linalg.norm(R, 2) / np.abs(lc - w ** 2 + 2j * zeta * np.sqrt(lc) * w))
        imp[modes], ids[modes] = peak, c
    return imp / imp.max(), ids


def modal_state_space(w2, HPhi, PhiG, zeta):
    """States (q_k, qdot_k) per mode."""
    n = w2.size
    A, B, C = np.zeros((2 * n, 2 * n)), np.zeros((2 * n, PhiG.shape[1])), np.zeros((HPhi.shape[0], 2 * n))
    for k in range(n):
        A[2 * k, 2 * k + 1] = 1
        A[2 * k + 1, 2 * k] = -w2[k]
        A[2 * k + 1, 2 * k + 1] = -2 * zeta * np.sqrt(w2[k])
        B[2 * k + 1] = PhiG[k]
        C[:, 2 * k] = HPhi[:, k]
    return A, B, C


def gramians(A, B, C):
    return sl.solve_continuous_lyapunov(A, -B @ B.T), sl.solve_continuous_lyapunov(A.T, -C.T @ C)


def psd_factor(W):
    s, U = np.linalg.eigh((W + W.T) / 2)
    return U * np.sqrt(np.clip(s, 0, None))


def balanced_truncation(A, B, C, r):
    """Square-root balanced truncation of order r."""
    Wc, Wo = gramians(A, B, C)
    Lc, Lo = psd_factor(Wc), psd_factor(Wo)
    U, s, Vt = np.linalg.svd(Lo.T @ Lc)
    T = Lc @ Vt[:r].T / np.sqrt(s[:r])
    Ti = (U[:, :r] / np.sqrt(s[:r])).T @ Lo.T
    return Ti @ A @ T, Ti @ B, C @ T


def hinf_error_on_grid(sys_full, sys_red, w2, zeta):
    """max over w of sigma_max(T_full(iw) - T_red(iw)) on a grid dense around every resonance (peaks are
    ~zeta w wide) plus a log grid from far below to far above the modes, and w = 0."""
    wk = np.sqrt(w2)
    grid = [np.array([0.0]), np.geomspace(wk.min() / 100, wk.max() * 100, 4000)]
    grid += [w * (1 + zeta * np.linspace(-8, 8, 801)) for w in wk]
    grid = np.concatenate(grid)
    err = 0.0
    for w in grid:
        E = np.zeros((sys_full[2].shape[0], sys_full[1].shape[1]), dtype=complex)
        for sign, (A, B, C) in ((1, sys_full), (-1, sys_red)):
            E += sign * (C @ np.linalg.solve(1j * w * np.eye(A.shape[0]) - A, B))
        err = max(err, np.linalg.norm(E, 2))
    return err


# ------------------------------------------------------------------------------------------------ importance

def test_importance_band_matches_brute_force():
    """Rigid modes, a close pair within cluster_rtol, modes below, inside and above the band; two damping ratios
    (one above 1/sqrt(2), where the peak of every cluster is at the lower band edge)."""
    rng = np.random.default_rng(11)
    freqs = [0.6, 3.0, 4.0, 4.002, 7.5, 12.0, 25.0, 60.0]  # band [2, 10] Hz: 0.6 below, 12+ above, 4/4.002 a cluster
    lam, Phi, G, H = modal_problem(rng, freqs, 2, 2, 3)
    for zeta in (0.02, 0.8):
        imp, ids = _core.mode_importance_band(lam, Phi, G, H, zeta, (2.0, 10.0), cluster_rtol=1e-3)
        ref_imp, ref_ids = importance_brute_force(lam, Phi, G, H, zeta, (2.0, 10.0), cluster_rtol=1e-3)
        np.testing.assert_array_equal(ids, ref_ids)
        assert list(ids) == [-1, -1, 0, 1, 2, 2, 3, 4, 5, 6]
        np.testing.assert_allclose(imp, ref_imp, rtol=1e-3, atol=0)
        assert imp.max() == 1.0 and imp[:2].tolist() == [0.0, 0.0]


def test_importance_band_zero_damping_floor():
    """zeta = 0: finite importances (the documented 1e-6 floor), in-band clusters above every out-of-band one."""
    rng = np.random.default_rng(5)
    lam, Phi, G, H = modal_problem(rng, [1.0, 3.0, 5.0, 20.0, 40.0], 1, 2, 2)
    imp, ids = _core.mode_importance_band(lam, Phi, G, H, 0.0, (2.0, 10.0))
    assert np.all(np.isfinite(imp)) and imp[0] == 0 and ids[0] == -1
    assert min(imp[2], imp[3]) > 1e3 * max(imp[1], imp[4], imp[5])


def test_importance_band_cluster_invariance():
    """An exactly repeated eigenvalue (a symmetric structure's pair) has no preferred basis: rotating it by a random
    orthogonal matrix must leave every importance unchanged; the per-mode Hinf measure does change."""
    rng = np.random.default_rng(7)
    lam, Phi, G, H = modal_problem(rng, [2.0, 5.0, 5.0, 5.0, 8.0, 30.0], 1, 3, 2)
    Q = orthogonal(rng, 3)
    Phi2 = Phi.copy()
    Phi2[:, 2:5] = Phi[:, 2:5] @ Q
    band = (1.0, 12.0)
    imp1, ids1 = _core.mode_importance_band(lam, Phi, G, H, 0.02, band)
    imp2, ids2 = _core.mode_importance_band(lam, Phi2, G, H, 0.02, band)
    np.testing.assert_array_equal(ids1, ids2)
    assert ids1[2] == ids1[3] == ids1[4] and imp1[2] == imp1[3] == imp1[4]
    np.testing.assert_allclose(imp2, imp1, rtol=1e-12, atol=1e-15)
    h1 = _core.mode_importance(lam, Phi, G, H, 0.02, "hinf")
    h2 = _core.mode_importance(lam, Phi2, G, H, 0.02, "hinf")
    assert np.max(np.abs(h1[2:5] - h2[2:5])) > 1e-3


def test_importance_band_argument_errors():
    rng = np.random.default_rng(3)
    lam, Phi, G, H = modal_problem(rng, [1.0, 2.0], 0, 1, 1)
    with pytest.raises(ValueError, match="band_hz"):
        _core.mode_importance_band(lam, Phi, G, H, 0.01, (5.0, 1.0))
    with pytest.raises(ValueError, match="damping"):
        _core.mode_importance_band(lam, Phi, G, H, -0.01, (0.0, 1.0))
    with pytest.raises(ValueError, match="cluster_rtol"):
        _core.mode_importance_band(lam, Phi, G, H, 0.01, (0.0, 1.0), cluster_rtol=1.5)
    with pytest.raises(ValueError, match="inconsistent sizes"):
        _core.mode_importance_band(lam, Phi, G[:1], H, 0.01, (0.0, 1.0))
    with pytest.raises(ValueError, match="mode_importance_band"):
        _core.mode_importance(lam, Phi, G, H, 0.01, "band")
    imp, ids = _core.mode_importance_band(np.zeros(0), np.zeros((0, 0)), np.zeros((0, 2)), np.zeros((1, 0)), 0.01, (0, 1))
    assert imp.size == 0 and ids.size == 0


# ------------------------------------------------------------------------------------------------ Hankel

def random_modal_system(seed, n=12, a=2, t=3):
    rng = np.random.default_rng(seed)
    w2 = np.sort(TWO_PI * rng.uniform(0.5, 40.0, n)) ** 2
    return w2, rng.standard_normal((t, n)), rng.standard_normal((n, a))


@pytest.mark.parametrize("zeta", [0.01, 0.2])
def test_hankel_singular_values_match_lyapunov(zeta):
    w2, HPhi, PhiG = random_modal_system(21)
    hsv = _core.modal_hankel_singular_values(w2, HPhi, PhiG, zeta)
    Wc, Wo = gramians(*modal_state_space(w2, HPhi, PhiG, zeta))
    ref = np.sort(np.sqrt(np.abs(np.linalg.eigvals(Wc @ Wo).real)))[::-1]
    assert hsv.shape == (2 * w2.size,) and np.all(np.diff(hsv) <= 0)
    np.testing.assert_allclose(hsv, ref, rtol=0, atol=1e-8 * ref[0])


@pytest.mark.parametrize("zeta", [0.01, 0.2])
def test_hankel_lower_bound_of_balanced_truncation(zeta):
    """hsv[r] <= ||T - T_r||_inf <= 2 sum_{k >= r} hsv[k] for the order-r balanced truncation."""
    w2, HPhi, PhiG = random_modal_system(21)
    hsv = _core.modal_hankel_singular_values(w2, HPhi, PhiG, zeta)
    full = modal_state_space(w2, HPhi, PhiG, zeta)
    for r in (4, 9):
        err = hinf_error_on_grid(full, balanced_truncation(*full, r), w2, zeta)
        assert hsv[r] <= err <= 2 * hsv[r:].sum() * (1 + 1e-9), (r, hsv[r], err, 2 * hsv[r:].sum())


def test_hankel_argument_errors():
    w2, HPhi, PhiG = random_modal_system(2, n=3)
    with pytest.raises(ValueError, match="damping"):
        _core.modal_hankel_singular_values(w2, HPhi, PhiG, 0.0)
    with pytest.raises(ValueError, match="flexible"):
        _core.modal_hankel_singular_values(np.r_[0.0, w2[1:]], HPhi, PhiG, 0.01)
    with pytest.raises(ValueError, match="inconsistent sizes"):
        _core.modal_hankel_singular_values(w2, HPhi[:, :2], PhiG, 0.01)
    assert _core.modal_hankel_singular_values(np.zeros(0), np.zeros((2, 0)), np.zeros((0, 2)), 0.1).size == 0
