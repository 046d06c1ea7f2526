#!/usr/bin/python3
"""What Lee's tables imply for any 28-dof model of the paper's topology, independently of a fit.

    /usr/bin/python3 meshes/galileo/implied.py            # both analyses, as Markdown (README.md quotes them)

1. How many system modes a mass layout allows below a frequency (Table 1's system column needs ten flexible
   modes at or below 9.2953 Hz, from components with six). Holding both bodies' bearing nodes still is 7 more
   constraints on the 28-dof system (the 5 shared dofs, and rz of each side); what is left is the stator with its
   bearing clamped beside the rotor with its hub clamped. By Cauchy interlacing, lambda_k(system) <= lambda_k(clamped)
   <= lambda_(k+7)(system), so the system has at most N_c(f) flexible modes below f, N_c(f) the clamped bodies'
   count. Each body is an interface node (bearing or hub) and the rest (point A; the five tips): its stiffness
   depends only on the rest's motion relative to the interface's rigid motion, d = u_rest - X u_interface, so the
   free-free flexible eigenvalues are those of (k, S) with S = (M_rest^-1 + X M_interface^-1 X^T)^-1 (the interface's
   motion eliminated), the clamped ones those of (k, M_rest): the eigenvalues of a product of two positive
   semi-definite matrices, one with the free-free eigenvalues, one with mu_k = eig(S, M_rest) =
   1 / (1 + eig(M_rest X M_interface^-1 X^T)). By the multiplicative Weyl inequality the j-th clamped eigenvalue is
   at least lambda_i(free) mu_k whenever i + k - 1 = j. So Table 1's component frequencies and the masses alone
   bound the count: whatever the mode shapes (the fit's other 120 unknowns). Each mu_k falls as the rest gets
   heavier and the interface lighter, so over a band of factors on every mass and inertia the lowest are at the
   corner (interface masses / band, the rest's x band).
2. What Table 5 says about the lowest mode the input and output see: for large k, L^k ~ r1 / lambda1^(k+1), so
   lambda1 = L^8 / L^9 and r1 = L^9 lambda1^10 at each angle.
"""
import os
import sys

import numpy as np
import scipy.linalg as sl

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import generate as g  # noqa: E402
import fit  # noqa: E402

BAND_TOP = max(g.PAPER_SYSTEM_HZ[:fit.LOW])   # 9.2953 Hz: Table 1's tenth flexible system mode


def clamped_ratios(M, table, band):
    """mu_1 <= mu_2 <= ...: the eigenvalues of (S, M_rest) for the body (M, table) with every lumped mass and inertia
    at the corner of the band that makes each smallest (interface node / band, the rest x band: each eigenvalue of
    M_rest X M_interface^-1 X^T grows with M_rest and falls with M_interface)."""
    R = g.rigid_modes(table)
    X = R[6:] @ np.linalg.inv(R[:6])          # the rest's rigid motion when the interface node moves
    Mi, Mo = M[:6, :6] / band, M[6:, 6:] * band
    nu = sl.eigh(X @ np.linalg.solve(Mi, X.T), np.linalg.inv(Mo), eigvals_only=True)
    return np.sort(1.0 / (1.0 + np.maximum(nu, 0.0)))


def clamped_floors(freqs_hz, mu):
    """Lower bounds on the clamped body's frequencies, ascending: f_j >= max over i + k - 1 = j of f_i sqrt(mu_k)
    (the clamped eigenvalues are those of a product of two positive semi-definite matrices with the free-free
    eigenvalues and the mu; for such a product lambda_(i+k-1) >= lambda_i mu_k, the multiplicative Weyl
    inequality)."""
    f = np.asarray(freqs_hz, float)
    n = len(f)
    return np.array([max(f[i] * np.sqrt(mu[j - i]) for i in range(j + 1)) for j in range(n)])


def mode_count_bound(band, top=BAND_TOP, layout="stick"):
    """(bound on the system's flexible modes at or below top, stator floors Hz, rotor floors Hz): the clamped
    floors of Table 1's component frequencies at the band's worst corner around the layout (fit.LAYOUTS)."""
    Ms, ts, Mr, tr = g.fitted_masses(fit.layout_center(layout))
    fs = clamped_floors(g.PAPER_STATOR_HZ, clamped_ratios(Ms, ts, band))
    fr = clamped_floors(g.PAPER_ROTOR_HZ, clamped_ratios(Mr, tr, band))
    return int((fs <= top).sum() + (fr <= top).sum()), fs, fr


def frequency_floors(band, layout="stick"):
    """Sorted lower bounds (Hz) on the system's flexible frequencies 1..21 (modes 8-28) at any angle, for every
    mass and inertia within the band around the layout: the j-th lowest of both bodies' clamped floors."""
    _, fs, fr = mode_count_bound(band, layout=layout)
    return np.sort(np.r_[fs, fr])


def least_deviation(band, paper_hz, layout="stick"):
    """Per mode, the least relative deviation below (negative: none) that the floors force: floor / paper - 1."""
    return frequency_floors(band, layout) / np.asarray(paper_hz) - 1


def least_band(need=fit.LOW, top=BAND_TOP, layout="stick"):
    """The smallest band (factor on every mass and inertia of the layout) whose bound allows need modes at or
    below top (bisection on log band; the bound's count rises with the band)."""
    lo, hi = 1.0, 1e3
    for _ in range(60):
        mid = np.sqrt(lo * hi)
        lo, hi = (lo, mid) if mode_count_bound(mid, top, layout)[0] >= need else (mid, hi)
    return hi


def table5_lowest_mode():
    """Rows (angle, lambda1, f1 Hz, r1, r1/lambda1 over L^0, r1/lambda1^2 over L^1) from Table 5's L^8, L^9."""
    rows = []
    for j, a in enumerate(fit.ANGLES):
        L = fit.MOMENTS[:, j]
        if abs(L[9]) <= fit.MOMENT_FLOOR[9, j]:
            rows.append((a, None, None, None, None, None))
            continue
        lam = L[8] / L[9]
        r = L[9] * lam ** 10
        rows.append((a, lam, np.sqrt(lam) / (2 * np.pi), r, r / lam / L[0], r / lam ** 2 / L[1]))
    return rows


def main():
    print(f"Modes at or below {BAND_TOP} Hz that a layout allows (Table 1 needs {fit.LOW}):\n")
    print("| layout | band | bound | stator's clamped floors (Hz) | rotor's, above its sixth (Hz) |")
    print("|---|---|---|---|---|")
    for layout in sorted(fit.LAYOUTS, reverse=True):
        for band in (1, 1.5, 2, 3, 4, 5, 10):
            n, fs, fr = mode_count_bound(band, layout=layout)
            print(f"| {layout} | {band:g} | {n} | " + ", ".join(f"{v:.3g}" for v in fs) + " | "
                  + ", ".join(f"{v:.3g}" for v in fr[6:9]) + ", ... |")
    print()
    for layout in sorted(fit.LAYOUTS, reverse=True):
        print(f"least band that allows {fit.LOW}, layout {layout}: {least_band(layout=layout):.3f}")
    print()
    print("Least deviation any mode shapes reach, per mode (modes whose floor is below the paper's: none):\n")
    print(f"| layout | mode | Table 1, 0° (Hz) | Table 4, 60° (Hz) | floor, band {fit.PHYS_BAND:g} (Hz) | "
          "least deviation 0° / 60° |")
    print("|---|---|---|---|---|---|")
    for layout in sorted(fit.LAYOUTS, reverse=True):
        fl = frequency_floors(fit.PHYS_BAND, layout)
        rows = [j for j, (a, b) in enumerate(zip(g.PAPER_SYSTEM_HZ, fit.SYSTEM_60_HZ)) if fl[j] > min(a, b)]
        for j in rows:
            a, b = g.PAPER_SYSTEM_HZ[j], fit.SYSTEM_60_HZ[j]
            print(f"| {layout} | {j + 8} | {a:g} | {b:g} | {fl[j]:.4g} | {100 * max(fl[j] / a - 1, 0):+.1f} % / "
                  f"{100 * max(fl[j] / b - 1, 0):+.1f} % |")
        if not rows:
            print(f"| {layout} | none | | | | |")
    print()
    print("| α | λ₁ = L⁸/L⁹ (rad²/s²) | f₁ (Hz) | r₁ = L⁹ λ₁¹⁰ | mode 1's share of L⁰ | of L¹ |")
    print("|---|---|---|---|---|---|")
    for a, lam, f, r, s0, s1 in table5_lowest_mode():
        if lam is None:
            lam1 = (2 * np.pi * g.PAPER_SYSTEM_HZ[0]) ** 2      # Table 1's first mode at 0 deg
            print(f"| {a:g}° | - | ({g.PAPER_SYSTEM_HZ[0]}, Table 1) | below {fit.MOMENT_FLOOR[9, 0] * lam1 ** 10:.2g} "
                  "| - | - |")
        else:
            print(f"| {a:g}° | {lam:.5f} | {f:.5f} | {r:.4e} | {s0:+.3f} | {s1:+.4f} |")


if __name__ == "__main__":
    main()
