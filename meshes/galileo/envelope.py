#!/usr/bin/python3
"""The least deviation from Tables 1 and 4 that the bounds force over the whole physical envelope of a
Galileo-class spacecraft: a rigorous bound over a continuum of masses, not a grid.

    nice -n 15 /usr/bin/python3 meshes/galileo/envelope.py     # -> envelope.json, and the bound as Markdown
    nice -n 15 /usr/bin/python3 meshes/galileo/envelope.py --hub-min 600 450 225 --out /tmp/e.json   # lighter hubs

The envelope (ENVELOPE, README.md "The physical envelope" gives the sources) is a range for every lumped mass and
inertia of the model: the stator's bearing node and point A, the rotor's hub and five tips. Each of the three
bounds (implied.py's clamped floors, topmodes.py's rotor-mode floors, sumrule.py's trace bound) is monotone in
every mass and inertia, in a direction that is proved once:

  - clamped floors: mu_k = 1 / (1 + eig(M_rest X M_interface^-1 X^T)) rise as an interface node (the bearing
    node; the hub) gets heavier (M_interface^-1 falls in the Loewner order) and fall as the rest (point A; the tips)
    gets heavier; the floors are increasing in every mu_k. Least favourable corner: interface nodes at their
    lightest, the rest at its heaviest.
  - rotor-mode floors: tau = lambda_max(C_h^T M_b C_h, M_r) rises with the bearing node's masses and falls with
    the rotor's (lumped masses: only the hub's enter), and the floors fall as tau rises. Least favourable: bearing
    node heaviest, hub lightest.
  - trace bound: the stator's term rises as the bearing node gets lighter and the hub heavier, the rotor's term
    the other way round (sumrule.pair_bound); the least deviation falls as the bound rises. Least favourable: each
    term at its own corner.

So a box ("cell") of masses has, for each bound, a corner where the bound is weakest, and the bound there holds
for every model in the cell whatever the mode shapes. A cell's claim is the largest of the three at 0 and 60 deg;
the envelope's least forced deviation is at least the smallest claim over cells that cover it. The cells are
refined by branch and bound (the cell with the smallest claim is halved along its widest side, in log scale) on
the six coordinates that the bounds trade against each other: the bearing node's mass and tilt inertias Jxx, Jyy,
the hub's mass and tilt inertias. The spin inertias Jzz (not tied by the bearing) enter only the clamped floors,
the rest (point A, the tips) too: they sit at their least favourable ends in every cell. The smallest claim is a
proof (a lower bound on the least deviation over the envelope); the smallest bound at a cell's centre (the three
bounds at one set of masses) is how far the bounds could ever go (an upper bound on what they prove).
"""
import argparse
import heapq
import json
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import generate as g  # noqa: E402
import fit  # noqa: E402
import implied  # noqa: E402
import sumrule  # noqa: E402
import topmodes  # noqa: E402

R_SPACECRAFT = 2.3      # m: half the orbiter's 4.6 m diameter with the antenna deployed (NSSDC 1989-084B)
# Radii of gyration (m) of the two 6-dof nodes about each axis: the bearing node from a race's 0.1 m to the
# spacecraft's half-width; the hub (the spun main body, its centre of mass above the bearing) from 0.5 m
GYRATION = {"bearing node": (0.1, R_SPACECRAFT), "hub": (0.5, R_SPACECRAFT)}
AXIS_RATIO = 2.0        # Jxx / Jyy of either node within [1/2, 2]: both nearly axisymmetric about the spin axis
HUB_MIN_KG = 600.0      # the spun main body carrying the propellant (README.md "The physical envelope")
# Every lumped mass (kg) and inertia (kg m^2) of the envelope: (least, most); the inertias of the bearing node and
# the hub are held by GYRATION and AXIS_RATIO instead.
ENVELOPE = {
    "bearing node mass": (2.0, 420.0),
    "point A mass": (331.0, 1400.0),
    "point A Jxx": (None, 16252.0), "point A Jyy": (None, 7406.0), "point A Jzz": (None, 7406.0),
    "hub mass": (HUB_MIN_KG, 1800.0),
    "magnetometer_boom_tip mass": (8.0, 32.0), "rtg1 mass": (28.0, 120.0), "rtg2 mass": (28.0, 112.0),
    "high_gain_antenna mass": (26.0, 104.0), "lower_module mass": (90.0, 360.0),
}
SLACK = 1e-9
COORDS = ("bearing node mass", "bearing node Jxx", "bearing node Jyy", "hub mass", "hub Jxx", "hub Jyy")


def stick_values():
    """generate.py's stick masses and inertias by MASS_PARAMETERS name (what a log factor of 0 means)."""
    Ms, _, Mr, _ = g._stick_masses()
    return {name: (Ms if body == "stator" else Mr)[dofs[0], dofs[0]] for body, dofs, name in g.MASS_PARAMETERS}


STICK = stick_values()


def envelope_box(hub_min=HUB_MIN_KG):
    """The six coordinates' ranges (log of kg, kg m^2) that cover the envelope."""
    mb, mh = ENVELOPE["bearing node mass"], (hub_min, ENVELOPE["hub mass"][1])
    (kb0, kb1), (kh0, kh1) = GYRATION["bearing node"], GYRATION["hub"]
    jb, jh = (mb[0] * kb0 ** 2, mb[1] * kb1 ** 2), (mh[0] * kh0 ** 2, mh[1] * kh1 ** 2)
    return np.log([mb, jb, jb, mh, jh, jh]).T


def inside(lo, hi, hub_min=HUB_MIN_KG):
    """Whether the cell [lo, hi] (log coordinates) may meet the envelope (False only when it provably does not:
    some tilt inertia out of reach of the node's masses and radii of gyration, or the two out of AXIS_RATIO)."""
    lo, hi = np.exp(lo) * (1 - SLACK), np.exp(hi) * (1 + SLACK)     # round-off never drops a cell
    if hi[3] < hub_min or lo[3] > ENVELOPE["hub mass"][1]:
        return False
    for m, jx, jy, (k0, k1) in ((0, 1, 2, GYRATION["bearing node"]), (3, 4, 5, GYRATION["hub"])):
        if max(lo[jx], lo[jy]) > hi[m] * k1 ** 2 or min(hi[jx], hi[jy]) < lo[m] * k0 ** 2:
            return False
        if lo[jx] > AXIS_RATIO * hi[jy] or lo[jy] > AXIS_RATIO * hi[jx]:
            return False
    return True


def holds(values, hub_min=HUB_MIN_KG):
    """Whether one set of masses (name -> kg or kg m^2; names not given: generate.py's) is inside the envelope;
    the reasons it is not."""
    v = dict(STICK, **values)
    out = []
    for name, (least, most) in ENVELOPE.items():
        least = hub_min if name == "hub mass" else least
        if (least is not None and v[name] < least) or v[name] > most:
            out.append(f"{name} {v[name]:.4g} outside {least:g}-{most:g}" if least is not None
                       else f"{name} {v[name]:.4g} above {most:g}")
    for node, (kmin, kmax) in GYRATION.items():
        for axis in ("Jxx", "Jyy", "Jzz"):
            k = np.sqrt(v[f"{node} {axis}"] / v[f"{node} mass"])
            if not kmin <= k <= kmax:
                out.append(f"{node} {axis}: radius of gyration {k:.2f} m outside {kmin:g}-{kmax:g} m")
        ratio = v[f"{node} Jxx"] / v[f"{node} Jyy"]
        if not 1 / AXIS_RATIO <= ratio <= AXIS_RATIO:
            out.append(f"{node} Jxx / Jyy {ratio:.3g} outside 1/{AXIS_RATIO:g}-{AXIS_RATIO:g}")
    return not out, out


def _params(values):
    """generate.MASS_PARAMETERS log factors for the values (name -> kg or kg m^2; the rest generate.py's)."""
    return np.array([np.log(values.get(name, STICK[name]) / STICK[name]) for _, _, name in g.MASS_PARAMETERS])


def _node(prefix, m, jxx, jyy, jzz):
    return {f"{prefix} mass": m, f"{prefix} Jxx": jxx, f"{prefix} Jyy": jyy, f"{prefix} Jzz": jzz}


def _rest_heaviest():
    """Point A and the tips at their heaviest: the clamped floors' least favourable corner."""
    return {name: most for name, (_, most) in ENVELOPE.items() if not name.startswith(("bearing", "hub"))}


def corners(lo, hi):
    """Each bound's least favourable masses in the cell [lo, hi]: {"clamped", "tau", "trace stator", "trace
    rotor"} -> MASS_PARAMETERS log factors."""
    a, b = np.exp(lo), np.exp(hi)
    (kb0, kb1), (kh0, kh1) = GYRATION["bearing node"], GYRATION["hub"]
    light_b = _node("bearing node", a[0], a[1], a[2], a[0] * kb0 ** 2)
    heavy_b = _node("bearing node", b[0], b[1], b[2], b[0] * kb1 ** 2)
    light_h = _node("hub", a[3], a[4], a[5], a[3] * kh0 ** 2)
    heavy_h = _node("hub", b[3], b[4], b[5], b[3] * kh1 ** 2)
    return {"clamped": _params(dict(_rest_heaviest(), **light_b, **light_h)),
            "tau": _params(dict(heavy_b, **light_h)),
            "trace stator": _params(dict(light_b, **heavy_h)),
            "trace rotor": _params(dict(heavy_b, **light_h))}


def per_mode(lo, hi):
    """{angle: per mode 8-28, the least deviation above the paper's that the clamped or the rotor-mode floors force
    on that mode alone over the cell [lo, hi] (0: none), and the bound}: each floor at its own weakest corner."""
    c = corners(lo, hi)
    Ms, ts, Mr, tr = g.fitted_masses(c["clamped"])
    floors = np.sort(np.r_[implied.clamped_floors(g.PAPER_STATOR_HZ, implied.clamped_ratios(Ms, ts, 1.0)),
                           implied.clamped_floors(g.PAPER_ROTOR_HZ, implied.clamped_ratios(Mr, tr, 1.0))])
    Ms, _, Mr, _ = g.fitted_masses(c["tau"])
    out = {}
    for alpha, paper in ((0.0, g.PAPER_SYSTEM_HZ), (60.0, fit.SYSTEM_60_HZ)):
        clamped = np.maximum(floors / np.asarray(paper) - 1.0, 0.0)
        rotor = topmodes.least_deviation(alpha, topmodes.tau(alpha, Ms, Mr))
        out[f"{alpha:g}"] = [[float(max(x, y)), "clamped" if x >= y else "rotor modes"] for x, y in zip(clamped, rotor)]
    return out


def claim(lo, hi):
    """(the largest least deviation of Tables 1 and 4 that the three bounds force on every model in the cell,
    the bound that forces it)."""
    c = corners(lo, hi)
    Ms, ts, Mr, tr = g.fitted_masses(c["clamped"])
    floors = np.sort(np.r_[implied.clamped_floors(g.PAPER_STATOR_HZ, implied.clamped_ratios(Ms, ts, 1.0)),
                           implied.clamped_floors(g.PAPER_ROTOR_HZ, implied.clamped_ratios(Mr, tr, 1.0))])
    Ms, _, Mr, _ = g.fitted_masses(c["tau"])
    out = []
    for alpha, paper in ((0.0, g.PAPER_SYSTEM_HZ), (60.0, fit.SYSTEM_60_HZ)):
        out.append((float(np.max(floors / np.asarray(paper) - 1.0)), "clamped"))
        out.append((float(np.max(topmodes.least_deviation(alpha, topmodes.tau(alpha, Ms, Mr)))), "rotor modes"))
        bound = sumrule.pair_bound(alpha, c["trace stator"], c["trace rotor"])
        out.append((sumrule.least_deviation_above(alpha, bound), "trace"))
    dev, name = max(out)
    return (max(dev, 0.0), name if dev > 0 else "none")


def branch_and_bound(cells=3000, hub_min=HUB_MIN_KG):
    """Refine the envelope's cover until `cells` cells were evaluated. Returns (proved, at most, the cell with the
    smallest claim (lo, hi, claim, bound), the centre with the smallest bound (lo, claim, bound), cells kept)."""
    lo, hi = envelope_box(hub_min)
    heap, count, best_point = [], 0, (np.inf, None, None)

    def push(lo, hi):
        nonlocal count, best_point
        if not inside(lo, hi, hub_min):
            return
        dev, name = claim(lo, hi)
        mid = 0.5 * (lo + hi)
        count += 1
        if inside(mid, mid, hub_min):
            pdev, pname = claim(mid, mid)
            count += 1
            best_point = min(best_point, (pdev, tuple(mid), pname))
        heapq.heappush(heap, (dev, count, lo, hi, name))

    push(lo, hi)
    while count < cells and heap:
        dev, _, lo, hi, name = heapq.heappop(heap)
        k = int(np.argmax(hi - lo))
        cut = 0.5 * (lo[k] + hi[k])
        for a, b in ((lo[k], cut), (cut, hi[k])):
            l2, h2 = lo.copy(), hi.copy()
            l2[k], h2[k] = a, b
            push(l2, h2)
    dev, _, lo, hi, name = heap[0]
    return dev, best_point[0], (lo, hi, dev, name), best_point, len(heap)


def _fmt_cell(lo, hi):
    a, b = np.exp(lo), np.exp(hi)
    return ", ".join(f"{n} {x:.3g}-{y:.3g}" for n, x, y in zip(COORDS, a, b))


def residue_cap():
    """The least, over the envelope, of sqrt(h^T M^-1 h g^T M^-1 g) (tables.py: a model's sum |r_i| is at most
    this): point A's Jyy, the bearing node's and the hub's Jzz at their largest."""
    jzz_b = ENVELOPE["bearing node mass"][1] * GYRATION["bearing node"][1] ** 2
    jzz_h = ENVELOPE["hub mass"][1] * GYRATION["hub"][1] ** 2
    return float(np.sqrt(1.0 / ENVELOPE["point A Jyy"][1] * (1.0 / jzz_b + 1.0 / jzz_h)))


def table5_account(least_sums):
    """Table 5 against the envelope: the residue cap against the least sum |r_i| that meets each column
    (tables.py's LP, {angle: sum}), and the static condition |L^0| <= cap / lambda_1 (lambda_1 the lowest flexible
    eigenvalue, Table 1's or 4's first mode)."""
    cap = residue_cap()
    out = {"residue_cap": cap, "least_residue_sum": least_sums, "excluded": {}, "static_cap_over_L0": {}}
    for a, least in least_sums.items():
        lam1 = (2 * np.pi * (g.PAPER_SYSTEM_HZ if float(a) == 0 else fit.SYSTEM_60_HZ)[0]) ** 2
        out["excluded"][a] = bool(least is not None and cap < least)
        out["static_cap_over_L0"][a] = float(cap / lam1 / abs(fit.MOMENTS[0, fit.ANGLES.index(float(a))]))
    return out


def account(cells, hub_mins):
    """The envelope, its least forced deviation for each least hub mass, and where the open layouts lie."""
    rows = []
    for hub_min in hub_mins:
        proved, best, (lo, hi, _, name), point, kept = branch_and_bound(cells, hub_min)
        rows.append({"hub_min_kg": hub_min, "proved": float(proved), "bound": name, "at_best": float(best),
                     "at_best_bound": point[2], "at_best_masses": dict(zip(COORDS, np.exp(point[1]).tolist())),
                     "weakest_cell": {n: [float(x), float(y)] for n, x, y in zip(COORDS, np.exp(lo), np.exp(hi))},
                     "cells_evaluated": cells, "cells_kept": kept})
    box = envelope_box(HUB_MIN_KG)
    outside = {}
    for label, values in (("light-hub", {n: STICK[n] * np.exp(q) for n, q in fit.LAYOUTS["light-hub"].items()}),
                          ("committed fit", {n: STICK[n] * np.exp(q) for (_, _, n), q in
                                             zip(g.MASS_PARAMETERS, g.load_fit()[:len(g.MASS_PARAMETERS)])})):
        outside[label] = holds(values)[1]
    return {"ranges": {n: list(r) for n, r in ENVELOPE.items()}, "hub_min_kg": HUB_MIN_KG,
            "gyration_m": {n: list(k) for n, k in GYRATION.items()}, "axis_ratio": AXIS_RATIO,
            "rows": rows, "outside": outside, "per_mode": per_mode(box[0], box[1])}


OUT = os.path.join(HERE, "envelope.json")


def main():
    global AXIS_RATIO
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cells", type=int, default=4000, help="bound evaluations of the branch and bound")
    ap.add_argument("--hub-min", type=float, nargs="+", default=[HUB_MIN_KG, 450.0],
                    help="the hub's least mass (kg); the first is the envelope's, the others show what a lighter "
                         "hub allows")
    ap.add_argument("--axis-ratio", type=float, default=AXIS_RATIO,
                    help="the largest Jxx/Jyy of the bearing node and of the hub (a wider envelope: a sensitivity)")
    ap.add_argument("--out", default=OUT, help="the account as JSON (tables.py and the report read it)")
    args = ap.parse_args()
    AXIS_RATIO = args.axis_ratio
    acc = account(args.cells, args.hub_min)
    with open(args.out, "w") as f:
        json.dump(acc, f, indent=1)
        f.write("\n")
    print("| hub at least (kg) | proved: least deviation over the envelope | the bounds reach at best "
          "| the weakest cell (kg, kg m²) |")
    print("|---|---|---|---|")
    for r in acc["rows"]:
        cell = ", ".join(f"{n} {x:.3g}-{y:.3g}" for n, (x, y) in r["weakest_cell"].items())
        print(f"| {r['hub_min_kg']:g} | {100 * r['proved']:.2f} % ({r['bound']}) | {100 * r['at_best']:.2f} % "
              f"({r['at_best_bound']}) | {cell} |")
    print()
    for label, why in acc["outside"].items():
        print(f"- {label}: " + ("inside the envelope" if not why else "outside: " + "; ".join(why)))
    print(f"\nTable 5: the residue cap over the envelope is at least {residue_cap():.3g}; wrote {args.out}")


if __name__ == "__main__":
    main()
