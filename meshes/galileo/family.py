#!/usr/bin/python3
"""The bounds over a family of despun layouts: how close to Tables 1 and 4 any of them can come.

    /usr/bin/python3 meshes/galileo/family.py            # the grid, as Markdown (README.md quotes it)

The stator's bearing node is given a mass m and tilt inertias J (Jxx = Jyy = Jzz = J), point A the rest of the
despun section's 1060 kg (at least 100 kg), the rotor generate.py's layout with the hub's mass and inertias times
a scale h (HUB_SCALES; 1: the layout's 900 kg); every mass and inertia within a factor fit.PHYS_BAND of that. For
each (m, J) the three bounds, each valid for any mode shapes: implied.py's clamped floors (want the bearing node
light against point A), topmodes.py's rotor-mode floors (want it as heavy as the hub) and sumrule.py's trace bound.
A cell is the largest least deviation of Tables 1 and 4 (modes 8-28, 0 and 60 deg) that they force, and which
bound forces it ("none": no bound excludes the layout). The grid samples the family; between its points nothing
is claimed. A node's radius of gyration sqrt(J / m) above R_GYRATION (a ring wider than the spacecraft's bus) is
marked: such a node is not a bearing assembly (the committed fit's bearing node, 8.4 kg with 540-1870 kg m^2, is
one of them).
"""
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

DESPUN_KG = 1060.0
R_GYRATION = 2.0            # m: the widest a despun bearing assembly's ring could be on a 2 m-class bus
MASSES = (2.5, 5, 10, 20, 40, 80, 160, 320, 640, 960)
INERTIAS = tuple(2.0 ** k for k in range(13))      # 1 .. 4096 kg m^2
HUB_SCALES = (0.25, 0.5, 1.0, 2.0)


def layout(m, J, hub=1.0):
    """fit.LAYOUTS-style log factors on generate.py's stick masses for a bearing node of m kg and J kg m^2 and the
    hub's masses times hub."""
    out = {"bearing node mass": np.log(m / 420.0), "bearing node Jxx": np.log(J / 600.0),
           "bearing node Jyy": np.log(J / 1500.0), "bearing node Jzz": np.log(J / 260.0),
           "point A mass": np.log(max(DESPUN_KG - m, 100.0) / 640.0)}
    return dict(out, **{name: np.log(hub) for name in ("hub mass", "hub Jxx", "hub Jyy", "hub Jzz")})


def least_deviation(m, J, hub=1.0, band=fit.PHYS_BAND):
    """(the largest least deviation the three bounds force on Tables 1 and 4, the bound's name)."""
    name = f"bearing {m:g} kg, {J:g} kg m^2, hub x {hub:g}"
    fit.LAYOUTS[name] = layout(m, J, hub)
    try:
        out = []
        for a, paper in ((0.0, g.PAPER_SYSTEM_HZ), (60.0, fit.SYSTEM_60_HZ)):
            out.append((float(np.max(implied.least_deviation(band, paper, name))), "clamped"))
            out.append((float(np.max(topmodes.least_deviation(a, topmodes.box_tau(a, name, band)))), "rotor modes"))
            out.append((sumrule.least_deviation_above(a, sumrule.box_bound(a, name, band)), "trace"))
        dev, bound = max(out)
        return (dev, bound) if dev > 0 else (0.0, "none")
    finally:
        del fit.LAYOUTS[name]


def closest(hub=1.0):
    """{True: (deviation, m, J, bound) of the grid's closest layout with a radius of gyration at most R_GYRATION,
    False: the same among the wider ones}, for the hub's masses times hub."""
    least = {True: (np.inf, None, None, None), False: (np.inf, None, None, None)}
    for m in MASSES:
        for J in INERTIAS:
            dev, name = least_deviation(m, J, hub)
            ring = bool(np.sqrt(J / m) <= R_GYRATION)
            least[ring] = min(least[ring], (dev, m, J, name))
    return least


def main():
    print("| bearing node (kg) \\ J (kg m²) | " + " | ".join(f"{J:g}" for J in INERTIAS) + " |")
    print("|---" * (len(INERTIAS) + 1) + "|")
    least = {True: (np.inf, None), False: (np.inf, None)}
    for m in MASSES:
        cells = []
        for J in INERTIAS:
            dev, name = least_deviation(m, J)
            ring = np.sqrt(J / m) <= R_GYRATION
            least[ring] = min(least[ring], (dev, (m, J, name)))
            cells.append(f"{100 * dev:.1f} % ({name})" + ("" if ring else " *"))
        print(f"| {m:g} | " + " | ".join(cells) + " |")
    print(f"\n*: radius of gyration sqrt(J / m) above {R_GYRATION:g} m")
    for ring, what in ((True, f"radius of gyration at most {R_GYRATION:g} m"), (False, "wider (*)")):
        dev, (m, J, name) = least[ring]
        print(f"closest, {what}: {100 * dev:.2f} % at a {m:g} kg, {J:g} kg m² bearing node ({name})")
    print(f"\n| hub (x the layout's 900 kg) | closest, radius of gyration at most {R_GYRATION:g} m | closest, wider |")
    print("|---|---|---|")
    for hub in HUB_SCALES:
        c = closest(hub)
        print(f"| {hub:g} | " + " | ".join(f"{100 * c[r][0]:.1f} % ({c[r][1]:g} kg, {c[r][2]:g} kg m², {c[r][3]})"
                                         for r in (True, False)) + " |")


if __name__ == "__main__":
    main()
