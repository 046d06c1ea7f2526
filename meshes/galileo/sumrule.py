#!/usr/bin/python3
"""The trace (sum-rule) bound: how far joining the bodies can lower the sum of the system's squared frequencies,
from the interface masses alone, whatever the mode shapes; and the interlacing checks between Table 1's
components, its system column and Table 4's 60 deg column.

    /usr/bin/python3 meshes/galileo/sumrule.py           # the bounds, as Markdown (README.md quotes them)

The system at angle alpha is the free-free pair (stator + rotor, 33 dofs, 12 rigid modes) restricted to the
5 bearing ties C u = 0 (fit.constraint_matrix). In mass-weighted coordinates (A = M^-1/2 K M^-1/2) its eigenvalues
are those of A compressed to the complement of B = M^-1/2 C^T, so their sum is trace(A) less the trace of A on
range(B):

    sum lambda(pair) - sum lambda(system) = D = trace(W^-1 C M^-1 K M^-1 C^T),   W = C M^-1 C^T.

sum lambda(pair) is Table 1's component column (exactly: the model's stiffness is built from it), so D is fixed by
Table 1 (or Table 4) for any model that meets it. For a body, M^-1 K M^-1 = Phi Lambda Phi^T (Phi its
M-orthonormal flexible modes) and the modes' interface participations sum to P = C_b (M^-1 - R (R^T M R)^-1 R^T)
C_b^T (the rigid part removed; P <= C_b M^-1 C_b^T). So D is the stator's sum_i lambda_i w_i plus the rotor's, with
w_i = phi_i^T C_b^T W^-1 C_b phi_i, and by von Neumann's trace inequality and Cauchy interlacing

    D <= sum_k lambda_k(stator, descending) nu_k(stator) + sum_k lambda_k(rotor, descending) nu_k(rotor),

nu_k the eigenvalues (descending, 5 of them) of W^-1/2 P W^-1/2: mode shapes cannot put more of the bodies' top
frequencies into the ties than the interface masses let them. With P relaxed to C_b M^-1 C_b^T the stator's nu
are those of (I + A_s^-1 A_r)^-1 (A = C_b M^-1 C_b^T of each side), largest with its bearing node light and the
hub heavy; the rotor's the other way round. Over a band of factors on every mass and inertia of a layout the bound
is therefore at most the stator's term at one corner plus the rotor's at the other (box_bound): only the two
interface nodes enter. If Table 1's D exceeds it, no model of the topology with those masses meets Table 1: its
system frequencies' squares sum to at least sum lambda(pair) - bound, and the least uniform relative deviation
from the paper is sqrt(that / the paper's sum) - 1.

Interlacing (model-independent): the system is the pair with 5 constraints, so lambda_j(pair) <= lambda_j(system)
<= lambda_(j+5)(pair), i.e. the k-th flexible system frequency lies between the components' (k-5)-th and k-th; and
the systems at 0 and 60 deg share the 24-dof subspace where both sets of ties hold (4 constraints more on either:
the bearing's lateral and tilt motion held), so lambda_j(60) <= lambda_(j+4)(0) and lambda_j(0) <= lambda_(j+4)(60).
"""
import os
import sys

import numpy as np
import scipy.linalg as sl

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import generate as g  # noqa: E402
import fit  # noqa: E402

TWO_PI2 = (2 * np.pi) ** 2
INTERFACE = {"stator": ("bearing node mass", "bearing node Jxx", "bearing node Jyy", "bearing node Jzz"),
             "rotor": ("hub mass", "hub Jxx", "hub Jyy", "hub Jzz")}


def component_lambdas():
    """Table 1's flexible component eigenvalues (rad^2/s^2): (stator, rotor)."""
    return TWO_PI2 * np.square(g.PAPER_STATOR_HZ), TWO_PI2 * np.square(g.PAPER_ROTOR_HZ)


def _split(alpha, Ms, Mr):
    C = fit.constraint_matrix(alpha, Ms.shape[0], Mr.shape[0])
    return C, C[:, :Ms.shape[0]], C[:, Ms.shape[0]:]


def deficit(alpha, bodies):
    """D = trace(W^-1 C M^-1 K M^-1 C^T) of a model ((Ms, Ks, ts), (Mr, Kr, tr)): sum lambda(pair) less
    sum lambda(system)."""
    (Ms, Ks, _), (Mr, Kr, _) = bodies
    C, Cs, Cr = _split(alpha, Ms, Mr)
    W = Cs @ np.linalg.solve(Ms, Cs.T) + Cr @ np.linalg.solve(Mr, Cr.T)
    Ys, Yr = np.linalg.solve(Ms, Cs.T), np.linalg.solve(Mr, Cr.T)
    G = Ys.T @ Ks @ Ys + Yr.T @ Kr @ Yr
    return float(np.trace(np.linalg.solve(W, G)))


def _participation(M, table, Cb, rigid):
    """C_b (M^-1 - rigid part) C_b^T: the flexible modes' summed interface participation (rigid=False: its upper
    bound C_b M^-1 C_b^T)."""
    Y = np.linalg.solve(M, Cb.T)
    P = Cb @ Y
    if rigid:
        R = g.rigid_modes(table)
        Z = Cb @ R
        P = P - Z @ np.linalg.solve(R.T @ M @ R, Z.T)
    return 0.5 * (P + P.T)


def _weights(W, P):
    """nu: eigenvalues of W^-1/2 P W^-1/2, descending."""
    return np.sort(np.maximum(sl.eigh(P, W, eigvals_only=True), 0.0))[::-1]


def _top_sum(lam, nu):
    lam = np.sort(lam)[::-1]
    n = min(len(lam), len(nu))
    return float(lam[:n] @ nu[:n])


def masses_bound(alpha, mass_params, rigid=True):
    """The bound on D for one set of masses (generate.MASS_PARAMETERS log factors), whatever the mode shapes."""
    Ms, ts, Mr, tr = g.fitted_masses(mass_params)
    _, Cs, Cr = _split(alpha, Ms, Mr)
    Ps, Pr = _participation(Ms, ts, Cs, rigid), _participation(Mr, tr, Cr, rigid)
    W = Cs @ np.linalg.solve(Ms, Cs.T) + Cr @ np.linalg.solve(Mr, Cr.T)
    ls, lr = component_lambdas()
    return _top_sum(ls, _weights(W, Ps)) + _top_sum(lr, _weights(W, Pr))


def _corner(center, band, light):
    """The layout's log factors with the interface node of body `light` at 1/band and the other's at x band."""
    p = np.array(center, float)
    for i, (_, _, name) in enumerate(g.MASS_PARAMETERS):
        if name in INTERFACE[light]:
            p[i] -= np.log(band)
        elif any(name in names for names in INTERFACE.values()):
            p[i] += np.log(band)
    return p


def pair_bound(alpha, stator_term, rotor_term):
    """The bound on D with the stator's term (P relaxed) at the masses stator_term and the rotor's at rotor_term
    (generate.MASS_PARAMETERS log factors). The stator's term grows as its bearing node gets lighter and the hub
    heavier (its nu are those of (I + A_s^-1 A_r)^-1, A = C_b M^-1 C_b^T of each side), the rotor's the other way
    round, and nothing else enters: so over any box of masses the bound at its two corners (stator_term: bearing
    node lightest, hub heaviest; rotor_term: the opposite) holds for every model in the box."""
    ls, lr = component_lambdas()
    total = 0.0
    for light, lam, p in (("stator", ls, stator_term), ("rotor", lr, rotor_term)):
        Ms, ts, Mr, tr = g.fitted_masses(p)
        _, Cs, Cr = _split(alpha, Ms, Mr)
        As, Ar = Cs @ np.linalg.solve(Ms, Cs.T), Cr @ np.linalg.solve(Mr, Cr.T)
        total += _top_sum(lam, _weights(As + Ar, As if light == "stator" else Ar))
    return total


def box_bound(alpha, layout, band):
    """The bound on D over every mass and inertia within a factor band of the layout: the stator's term (P
    relaxed) at the corner where its bearing node is lightest and the hub heaviest, plus the rotor's at the other."""
    center = fit.layout_center(layout)
    return pair_bound(alpha, _corner(center, band, "stator"), _corner(center, band, "rotor"))


def paper_deficit(alpha):
    """D that Table 1 (0 deg) or Table 4 (60 deg) needs: sum lambda(pair) - sum lambda(paper's system)."""
    ls, lr = component_lambdas()
    sys_hz = g.PAPER_SYSTEM_HZ if alpha == 0 else fit.SYSTEM_60_HZ
    return float(ls.sum() + lr.sum() - TWO_PI2 * np.square(sys_hz).sum())


def least_deviation(alpha, bound):
    """The least uniform relative deviation of the system frequencies from the paper's that D <= bound forces
    (0 when the bound allows the paper's)."""
    ls, lr = component_lambdas()
    paper = TWO_PI2 * np.square(g.PAPER_SYSTEM_HZ if alpha == 0 else fit.SYSTEM_60_HZ).sum()
    least = ls.sum() + lr.sum() - bound
    return max(np.sqrt(least / paper) - 1.0, 0.0)


def least_deviation_above(alpha, bound, low=fit.LOW):
    """The same for the modes above the band alone (modes 18-28): the band's modes can take at most the
    components' lowest ten squared (interlacing), far less than the shortfall, so the rest falls on these."""
    ls, lr = component_lambdas()
    comp = np.sort(np.r_[ls, lr])
    paper = TWO_PI2 * np.square(g.PAPER_SYSTEM_HZ if alpha == 0 else fit.SYSTEM_60_HZ)
    least = comp.sum() - bound - comp[:low].sum()
    return max(np.sqrt(least / paper[low:].sum()) - 1.0, 0.0)


def least_band(alpha, layout, lo=1.0, hi=1e4):
    """The smallest band around the layout whose box bound allows Table 1's (or 4's) D (bisection on log band:
    the box grows with the band)."""
    need = paper_deficit(alpha)
    if box_bound(alpha, layout, hi) < need:
        return np.inf
    for _ in range(60):
        mid = np.sqrt(lo * hi)
        lo, hi = (mid, hi) if box_bound(alpha, layout, mid) < need else (lo, mid)
    return hi


def interlacing():
    """Model-independent checks, each a list of (what, mode, value, lower, upper, holds)."""
    comp = np.sort(np.r_[g.PAPER_STATOR_HZ, g.PAPER_ROTOR_HZ])
    rows = []
    for label, sys_hz in (("Table 1, 0°", g.PAPER_SYSTEM_HZ), ("Table 4, 60°", fit.SYSTEM_60_HZ)):
        for k, f in enumerate(sys_hz):
            lo = comp[k - 5] if k >= 5 else 0.0
            rows.append((f"{label} between the components' (k-5)-th and k-th", k + 8, f, lo, comp[k],
                         lo <= f <= comp[k]))
    for label, a, b in (("Table 4 (60°) at most Table 1's (0°) four modes up", fit.SYSTEM_60_HZ, g.PAPER_SYSTEM_HZ),
                        ("Table 1 (0°) at most Table 4's (60°) four modes up", g.PAPER_SYSTEM_HZ, fit.SYSTEM_60_HZ)):
        for k in range(len(a) - 4):
            rows.append((label, k + 8, a[k], 0.0, b[k + 4], a[k] <= b[k + 4]))
    return rows


def main():
    ls, lr = component_lambdas()
    print(f"Σ f² of Table 1's components: {(ls.sum() + lr.sum()) / TWO_PI2:.6g} Hz²; the deficit D (Hz²) Table 1 "
          f"needs at 0°: {paper_deficit(0) / TWO_PI2:.6g}, Table 4 at 60°: {paper_deficit(60) / TWO_PI2:.6g}\n")
    print("| layout | band | bound on D, 0° (Hz²) | least uniform deviation, modes 8-28, 0° / 60° | the same, "
          "modes 18-28 | least band that allows Table 1 |")
    print("|---|---|---|---|---|---|")
    for layout in sorted(fit.LAYOUTS, reverse=True):
        for band in (1, 2, 5):
            b0, b60 = box_bound(0.0, layout, band), box_bound(60.0, layout, band)
            print(f"| {layout} | {band:g} | {b0 / TWO_PI2:.4g} | {100 * least_deviation(0, b0):.2f} % / "
                  f"{100 * least_deviation(60, b60):.2f} % | {100 * least_deviation_above(0, b0):.2f} % / "
                  f"{100 * least_deviation_above(60, b60):.2f} % | {least_band(0.0, layout):.3g} |")
    print()
    rows = interlacing()
    bad = [r for r in rows if not r[-1]]
    print(f"Interlacing (model-independent): {len(rows) - len(bad)} of {len(rows)} checks hold.")
    for what, mode, f, lo, hi, _ in bad:
        print(f"- fails: {what}, mode {mode}: {f:g} Hz not in [{lo:g}, {hi:g}]")


if __name__ == "__main__":
    main()
