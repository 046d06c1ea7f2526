#!/usr/bin/python3
"""Which entries of Lee's Tables 1, 4 and 5 the bounds exclude, entry by entry, for each mass layout: written to
tables_bounds.json, which the report's section "The paper's example, side by side" reads (kryflex/paper.py).

    /usr/bin/python3 meshes/galileo/tables.py            # -> meshes/galileo/tables_bounds.json, and a summary

For every layout (fit.LAYOUTS) with every mass and inertia within fit.PHYS_BAND of it:
  - Tables 1 and 4, mode by mode: implied.py's clamped floors (Cauchy interlacing with both bearing nodes held,
    multiplicative Weyl): the least deviation of each mode from the paper at 0 and 60 deg;
  - Tables 1 and 4, modes 14-28: topmodes.py's rotor-mode floors (the rotor's highest modes extended by the
    bearing node following the hub, Courant-Fischer): the least deviation of each mode at 0 and 60 deg;
  - Tables 1 and 4 as a column: sumrule.py's trace bound: the least uniform deviation of modes 18-28 (the modes
    above the band carry what the bound leaves short);
  - Table 5 at 0 and 60 deg (the angles whose frequencies the paper gives): the least sum over modes of |r_i|
    (r_i the product of mode i's output and input participations) with which L^k = sum_i r_i / lambda_i^(k+1) meets
    every entry of the column (within 5 % and of the paper's sign; a printed 0 below half its last digit) at the
    paper's frequencies: a linear program. By Cauchy-Schwarz sum |r_i| <= sqrt(h^T M^-1 h g^T M^-1 g) (the
    system's modal sum of u u^T is at most M^-1), h the output (ry at point A), g the input (the bearing torque):
    the cap is smallest with those nodes' inertias heaviest (x band). Table 5 is excluded for a layout when the
    cap is below the least sum.
the same floors and trace bound at the committed model's own masses (fit.json), family.py's closest layouts,
envelope.py's least deviation over the physical envelope (read from envelope.json) with Table 5's cap there, and
the model-independent
interlacing checks (sumrule.interlacing). Figures are the scripts' own; nothing here is
typed in by hand.
"""
import json
import os
import sys

import numpy as np
from scipy.optimize import linprog

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import generate as g  # noqa: E402
import fit  # noqa: E402
import implied  # noqa: E402
import sumrule  # noqa: E402
import topmodes  # noqa: E402
import family  # noqa: E402
import envelope  # noqa: E402

OUT = os.path.join(HERE, "tables_bounds.json")
ANGLES = (0.0, 60.0)
R_UNIT = 1e-9               # residues r_i in rad / (N m s^2): Table 5's L^9 at 60 deg needs r_1 ~ 9e-9


def paper_hz(alpha):
    return np.array(g.PAPER_SYSTEM_HZ if alpha == 0 else fit.SYSTEM_60_HZ)


def least_residue_sum(alpha):
    """The least sum |r_i| that meets Table 5's column at alpha with the paper's frequencies (HiGHS LP in r and
    t >= |r|), and the residues that reach it."""
    lam = (2 * np.pi * paper_hz(alpha)) ** 2
    j = fit.ANGLES.index(alpha)
    rows, rhs = [], []
    for k in range(fit.MOMENTS.shape[0]):
        a, L, half = lam ** -(k + 1.0), fit.MOMENTS[k, j], fit.MOMENT_FLOOR[k, j]
        scale = max(abs(L), half)
        if abs(L) <= half:
            rows += [a / scale, -a / scale]
            rhs += [half / scale, half / scale]
        else:
            s = np.sign(L)
            rows += [s * a / scale, -s * a / scale]
            rhs += [(1 + fit.MOMENT_TOL) * abs(L) / scale, -(1 - fit.MOMENT_TOL) * abs(L) / scale]
    # in units of R_UNIT, so that HiGHS's absolute feasibility tolerance (1e-7) is small beside the residues
    n, A = len(lam), np.array(rows) * R_UNIT
    I = np.eye(n)
    res = linprog(np.r_[np.zeros(n), np.ones(n)],
                  A_ub=np.vstack([np.hstack([A, 0 * A]), np.hstack([I, -I]), np.hstack([-I, -I])]),
                  b_ub=np.r_[rhs, np.zeros(2 * n)], bounds=[(None, None)] * n + [(0, None)] * n, method="highs")
    if res.status != 0:
        return None, None
    return float(res.fun) * R_UNIT, res.x[:n] * R_UNIT


def residue_cap(layout, band):
    """The least, over the band around the layout, of sqrt(h^T M^-1 h g^T M^-1 g): point A's Jyy, the bearing
    node's and the hub's Jzz at band x the layout (lumped, diagonal masses)."""
    Ms, _, Mr, _ = g.fitted_masses(fit.layout_center(layout) + np.log(band))
    return float(np.sqrt(1.0 / Ms[10, 10] * (1.0 / Ms[5, 5] + 1.0 / Mr[5, 5])))


def layout_account(layout, band, table5):
    floors = implied.frequency_floors(band, layout)
    out = {"frequency_floor_least_deviation": {}, "rotor_mode_floor_least_deviation": {},
           "trace_least_deviation_above_band": {}}
    for a in ANGLES:
        out["frequency_floor_least_deviation"][f"{a:g}"] = [float(max(v, 0.0)) for v in floors / paper_hz(a) - 1]
        out["rotor_mode_floor_least_deviation"][f"{a:g}"] = [
            float(v) for v in topmodes.least_deviation(a, topmodes.box_tau(a, layout, band))]
        out["trace_least_deviation_above_band"][f"{a:g}"] = float(
            sumrule.least_deviation_above(a, sumrule.box_bound(a, layout, band)))
    cap = residue_cap(layout, band)
    out["table5_residue_cap"] = cap
    out["table5_excluded"] = {f"{a:g}": bool(table5[f"{a:g}"] is not None and cap < table5[f"{a:g}"])
                              for a in ANGLES}
    return out


def model_account(path=g.FIT_FILE):
    """The same bounds at one model's own masses (the committed fit.json by default: masses free, so the layouts'
    bands do not hold it): per-mode clamped floors and the trace bound's least deviation above the band."""
    Ms, ts, Mr, tr = g.fitted_masses(g.load_fit(path)[:len(g.MASS_PARAMETERS)])
    floors = np.sort(np.r_[implied.clamped_floors(g.PAPER_STATOR_HZ, implied.clamped_ratios(Ms, ts, 1.0)),
                           implied.clamped_floors(g.PAPER_ROTOR_HZ, implied.clamped_ratios(Mr, tr, 1.0))])
    params = g.load_fit(path)[:len(g.MASS_PARAMETERS)]
    return {"file": os.path.basename(path),
            "frequency_floor_least_deviation": {f"{a:g}": [float(max(v, 0.0)) for v in floors / paper_hz(a) - 1]
                                                for a in ANGLES},
            "rotor_mode_floor_least_deviation": {f"{a:g}": [float(v) for v in topmodes.least_deviation(
                a, topmodes.tau(a, Ms, Mr))] for a in ANGLES},
            "trace_least_deviation_above_band": {f"{a:g}": float(sumrule.least_deviation_above(
                a, sumrule.masses_bound(a, params))) for a in ANGLES}}


FAMILY_HUBS = (1.0, 0.25)    # the hub as laid out, and a quarter of it (family.py prints every HUB_SCALES)


def family_account():
    """family.py's grid: per hub scale, the closest any bearing node of the despun family comes to Tables 1 and 4,
    among nodes no wider than family.R_GYRATION and among the wider ones."""
    out = {"radius_of_gyration_m": family.R_GYRATION, "masses_kg": list(family.MASSES),
           "inertias_kg_m2": list(family.INERTIAS), "hub_scales": {}}
    for hub in FAMILY_HUBS:
        out["hub_scales"][f"{hub:g}"] = {
            "closest_ring" if ring else "closest_wider": {"least_deviation": float(dev), "mass_kg": float(m),
                                                          "inertia_kg_m2": float(J), "bound": name}
            for ring, (dev, m, J, name) in family.closest(hub).items()}
    return out


def envelope_account(table5):
    """envelope.py's account (envelope.json: its branch and bound takes minutes, so it is read, not re-run) with
    Table 5's residue cap over the envelope against the least sums."""
    with open(envelope.OUT) as f:
        acc = json.load(f)
    return dict(acc, table5=envelope.table5_account(table5))


def account():
    table5 = {f"{a:g}": least_residue_sum(a)[0] for a in ANGLES}
    checks = sumrule.interlacing()
    return {
        "about": "which entries of Lee's Tables 1, 4 and 5 the bounds exclude, per mass layout (every mass and "
                 "inertia within mass_band of it); written by meshes/galileo/tables.py",
        "command": "meshes/galileo/tables.py",
        "mass_band": fit.PHYS_BAND,
        "rotor_mode_tau_needed": topmodes.tau_needed(0.0),
        "frequency_tolerance": fit.FREQ_TOL,
        "moment_tolerance": fit.MOMENT_TOL,
        "first_mode_above_band": 8 + fit.LOW,
        "interlacing": {"checks": len(checks), "failed": [f"{w}: mode {m}" for w, m, *_, ok in checks if not ok]},
        "table5_least_residue_sum": table5,
        "layouts": {name: layout_account(name, fit.PHYS_BAND, table5) for name in sorted(fit.LAYOUTS)},
        "committed_model": model_account(),
        "family": family_account(),
        "envelope": envelope_account(table5),
    }


def main():
    acc = account()
    with open(OUT, "w") as f:
        json.dump(acc, f, indent=1)
        f.write("\n")
    tol = acc["frequency_tolerance"]
    print(f"interlacing: {acc['interlacing']['checks']} checks, failed: {acc['interlacing']['failed'] or 'none'}")
    print(f"Table 5, least sum |r_i| at the paper's frequencies: {acc['table5_least_residue_sum']}\n")
    print("| layout (band 2) | modes the floors (clamped, rotor-mode) keep out of 0.5 %, 0° / 60° "
          "| modes 18-28 (trace bound), 0° / 60° | Table 5: cap on sum r_i |")
    print("|---|---|---|---|")
    for name, lay in acc["layouts"].items():
        fl = {a: np.maximum(lay["frequency_floor_least_deviation"][a],
                            lay["rotor_mode_floor_least_deviation"][a]) for a in ("0", "60")}
        cells = ["; ".join(f"{m + 8} (+{100 * v:.1f} %)" for m, v in enumerate(fl[a]) if v > tol) or "none"
                 for a in ("0", "60")]
        tr = lay["trace_least_deviation_above_band"]
        trace = " / ".join(f"{100 * tr[a]:.2f} %" if tr[a] > tol else "allowed" for a in ("0", "60"))
        print(f"| {name} | {cells[0]} / {cells[1]} | {trace} | {lay['table5_residue_cap']:.3g} |")
    print(f"\nwrote {OUT}")


if __name__ == "__main__":
    main()
