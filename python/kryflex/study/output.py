"""The study's files: study.csv (one row per run), accuracy_vs_size.png and accuracy_vs_time.png (log error, one curve
per method, kryflex's choice marked, the scene's accuracy and the Hankel limit as lines), study.md (the table and
what it shows). Figures on matplotlib's Agg canvas (no pyplot), as report/plots.py does."""
import csv
import math

import numpy as np

from .sweep import CSV_FIELDS, LABELS, METHODS

STYLES = {"krylov-single": ("tab:blue", "o", "-"), "krylov-multi": ("tab:green", "s", "-"),
          "krylov-paper": ("tab:purple", "v", ":"), "krylov-search": ("tab:cyan", "D", "-"),
          "krylov-points": ("tab:olive", "P", "-"), "eigen-static": ("tab:orange", "^", "--"),
          "eigen-plain": ("tab:brown", "D", "--"), "krylov-raw": ("tab:gray", "x", "-."),
          "kryflex": ("tab:red", "*", "")}
FLOOR = 1e-16        # an exact (zero) error drawn on the floor of the log axis


def _fmt(value, digits=17):
    """Numbers with every digit (the errors are compared across runs and rank counts), times with 4."""
    if isinstance(value, float):
        return "" if math.isnan(value) else "%.*g" % (digits, value)
    return str(value)


def write_csv(rows, path):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=CSV_FIELDS)
        w.writeheader()
        for row in rows:
            w.writerow({k: _fmt(row.get(k, ""), 4 if k == "seconds" else 17) for k in CSV_FIELDS})


def read_csv(path):
    """The rows of a study.csv, numbers as floats (NaN where empty)."""
    out = []
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            for k in ("size_dofs", "system_dofs", "error_hinf", "error_pointwise", "seconds", "min_frequency_ratio",
                      "moment_error", "gram_condition", "flexible_dofs"):
                row[k] = float(row[k]) if row.get(k) not in (None, "") else math.nan
            row["chosen"] = int(row["chosen"] or 0)
            row["exit_code"] = int(row["exit_code"] or 0)
            out.append(row)
    return out


def _measured(rows):
    return [r for r in rows if isinstance(r["error_hinf"], float) and not math.isnan(r["error_hinf"])]


def accuracy_figure(rows, x, xlabel, title, accuracy, limit=None):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    fig = Figure(figsize=(7.5, 5.0))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    rows = _measured(rows)
    for method in METHODS:
        mine = [r for r in rows if r["method"] == method and not (isinstance(r[x], float) and math.isnan(r[x]))]
        if not mine:
            continue
        color, marker, line = STYLES[method]
        if x != "seconds":      # a size sweep need not grow monotonically with its parameter: drawn by size
            mine = sorted(mine, key=lambda r: (float(r[x]), r["error_hinf"]))
        xs = np.array([float(r[x]) for r in mine])
        ys = np.maximum([r["error_hinf"] for r in mine], FLOOR)
        if method == "kryflex":
            ax.plot(xs, ys, linestyle="", marker=marker, markersize=16, color=color, markeredgecolor="k",
                    label=LABELS[method], zorder=5)
            continue
        if x == "seconds":       # times are not monotone in the parameter: points, joined in parameter order
            ax.plot(xs, ys, linestyle=line or "-", linewidth=0.6, marker=marker, markersize=4, color=color,
                    label=LABELS[method], alpha=0.85)
        else:
            ax.plot(xs, ys, linestyle=line or "-", linewidth=1.0, marker=marker, markersize=4, color=color,
                    label=LABELS[method], alpha=0.85)
    ax.axhline(accuracy, color="k", linewidth=1.0, linestyle=":", label="scene accuracy %g" % accuracy)
    if limit is not None and x == "system_dofs":
        ys = np.maximum(limit["error"], FLOOR)
        ax.step(limit["dofs"], ys, where="post", color="k", linewidth=1.6, label="Hankel limit (no model of this "
                "size does better)")
    ax.set_yscale("log")
    if x == "seconds":
        ax.set_xscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("relative H-inf FRF error per pair (worst angle)")
    ax.set_title(title, fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    fig.tight_layout()
    return fig


def write_figures(rows, folder, scene_name, accuracy, limit=None):
    import os
    paths = []
    for name, x, xlabel in (("accuracy_vs_size.png", "system_dofs", "reassembled system dofs (max over angles)"),
                            ("accuracy_vs_time.png", "seconds", "reduction wall time (s)")):
        fig = accuracy_figure(rows, x, xlabel, "%s: error against %s" % (scene_name, "size" if x != "seconds"
                                                                             else "reduction time"), accuracy, limit)
        path = os.path.join(folder, name)
        fig.savefig(path, dpi=110)
        paths.append(path)
    return paths


def best_rows(rows, accuracy):
    """Per method: (best error row, smallest row meeting the accuracy or None)."""
    out = {}
    for method in METHODS:
        mine = [r for r in _measured(rows) if r["method"] == method]
        if not mine:
            continue
        best = min(mine, key=lambda r: (r["error_hinf"], float(r["system_dofs"] or 0)))
        meet = [r for r in mine if r["error_hinf"] <= accuracy]
        smallest = min(meet, key=lambda r: (float(r["system_dofs"]), r["seconds"])) if meet else None
        out[method] = (best, smallest)
    return out


def markdown(rows, scene_name, accuracy, study, limit=None, sections=()):
    """study.md: the summary per method, what it shows, further sections (lists of lines: the estimator check's),
    and the whole table."""
    lines = ["# Speed-accuracy study: %s" % scene_name, "",
             "Reference: the full-order verification of the C reducer (%d system dofs, %d rigid/mechanism modes), "
             "%s, on its frequency grid (%d points%s). Error: %s; %s. Scene accuracy: %g."
             % (study.full_dofs, study.nrigid,
                "at the angles of interest %s deg" % ", ".join(" ".join("%g" % a for a in ang) for ang in study.angles)
                if any(len(ang) for ang in study.angles) else "of the structure (no revolute joint)",
                len(study.grids[0]), " at the first angle" if any(len(ang) for ang in study.angles) else "",
                study.error_measure, "a run's error is the worst over the angles of interest"
                if any(len(ang) for ang in study.angles) else "a run's error is the structure's", accuracy), ""]
    lines += ["| method | best error | at system dofs | smallest meeting %g | its error | its time (s) |" % accuracy,
              "|---|---|---|---|---|---|"]
    for method, (best, small) in best_rows(rows, accuracy).items():
        lines.append("| %s | %s | %s | %s | %s | %s |" % (
            LABELS[method], _g(best["error_hinf"]), _i(best["system_dofs"]),
            _i(small["system_dofs"]) if small else "none", _g(small["error_hinf"]) if small else "",
            _g(small["seconds"]) if small else ""))
    lines.append("")
    lines += ["## What it shows", ""] + observations(rows, accuracy, study, limit) + [""]
    for section in sections:
        lines += list(section) + [""]
    lines += ["## Every run", "", "| " + " | ".join(CSV_FIELDS[:12] + ("exit_code", "failure")) + " |",
              "|" + "---|" * 14]
    for r in rows:
        lines.append("| " + " | ".join(_fmt(r.get(k, ""), 4) for k in CSV_FIELDS[:12] + ("exit_code", "failure")) + " |")
    notes = sorted({r["note"] for r in rows if r.get("note")})
    if notes or study.notes:
        lines += ["", "Notes:", ""] + ["- %s" % n for n in list(study.notes) + notes]
    return "\n".join(lines) + "\n"


def observations(rows, accuracy, study, limit):
    """Plain statements read off the rows (no judgement beyond the numbers)."""
    out = []
    chosen = [r for r in rows if r["method"] == "kryflex"]
    best = best_rows(rows, accuracy)
    if chosen:
        c = chosen[0]
        out.append("- kryflex's choice: %s system dofs (%s body dofs), error %s, %s s; exit code %s (%s)."
                   % (_i(c["system_dofs"]), _i(c["size_dofs"]), _g(c["error_hinf"]), _g(c["seconds"]),
                      c["exit_code"], c.get("note") or c.get("failure") or ""))
        smallest = [s for m, (b, s) in best.items() if s is not None and m != "kryflex"]
        if smallest and not math.isnan(c["error_hinf"]):
            s = min(smallest, key=lambda r: float(r["system_dofs"]))
            out.append("- The smallest model of the sweeps meeting %g: %s with parameter %s, %s system dofs "
                       "(error %s): kryflex's choice is %.2fx its size."
                       % (accuracy, LABELS[s["method"]], s["parameter"], _i(s["system_dofs"]), _g(s["error_hinf"]),
                          float(c["system_dofs"]) / float(s["system_dofs"])))
    failed = [r for r in rows if r.get("failure")]
    if failed:
        kinds = {}
        for r in failed:
            for f in str(r["failure"]).split("; "):
                kinds.setdefault(f.split(" (")[0].split(":")[0], []).append("%s %s" % (r["method"], r["parameter"]))
        for kind, where in kinds.items():
            out.append("- %s: %d run(s): %s%s" % (kind, len(where), ", ".join(where[:8]),
                                                  " ..." if len(where) > 8 else ""))
    floor = min((r["error_hinf"] for r in _measured(rows) if r["error_hinf"] > 0), default=math.nan)
    if not math.isnan(floor):
        out.append("- The lowest error any run reached is %s: below about that level the errors measure the "
                   "reference (the verification's truncated modal sum and static residual), not the model." % _g(floor))
    if limit is None:
        out.append("- Hankel limit: not drawn; the C library does not give Hankel singular values yet.")
    else:
        k = np.nonzero(limit["error"] <= accuracy)[0]
        out.append("- Hankel limit (%s): %s flexible second-order dofs (%s system dofs) are the fewest any model "
                   "needs for %g." % (limit["source"], _i(limit["flexible"][k[0]]) if len(k) else "more than %d"
                                      % len(limit["error"]), _i(limit["dofs"][k[0]]) if len(k) else "?", accuracy))
    return out


def _g(x):
    try:
        x = float(x)
    except (TypeError, ValueError):
        return str(x)
    return "n/a" if math.isnan(x) else "%.3g" % x


def _i(x):
    try:
        return "%d" % int(float(x))
    except (TypeError, ValueError):
        return str(x)
