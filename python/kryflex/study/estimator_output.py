"""The estimator check's files (estimator.py): estimator.csv (one row per candidate both searches tried),
estimate_vs_truth.png (log-log scatter of the estimated against the true error, y = x, the scene's accuracy on both
axes, the chosen models marked) and its section of study.md. Figures on matplotlib's Agg canvas, as output.py."""
import csv
import math

import numpy as np

from .estimator import DECISION_BAND, FIELDS, describe
from .output import FLOOR, _fmt, _g

CSV_NAME, FIGURE_NAME = "estimator.csv", "estimate_vs_truth.png"
FAMILY_STYLE = {"single-angle": ("tab:blue", "o"), "multi-angle": ("tab:green", "s")}


def write_csv(rows, path):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=FIELDS)
        w.writeheader()
        for row in rows:
            w.writerow({k: _fmt(row[k]) for k in FIELDS})


def read_csv(path):
    """The rows of an estimator.csv: errors and ratio as floats, counts and flags as ints."""
    out = []
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            for k in ("true_error", "estimated_error", "ratio"):
                row[k] = float(row[k]) if row[k] != "" else math.nan
            for k in ("moments", "kept_clusters", "expansion_angles", "reduced_dofs", "system_dofs",
                      "true_lower_bound", "estimate_lower_bound", "chosen_full_order", "chosen_estimator"):
                row[k] = int(row[k])
            out.append(row)
    return out


def figure(rows, scene_name, accuracy):
    """Estimated against true error per candidate, log-log. Open markers: a value the search stopped measuring
    once it exceeded the accuracy (a lower bound). The quadrant of the false passes (estimate meets the accuracy,
    truth does not) shaded."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    fig = Figure(figsize=(6.5, 6.0))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    t = np.array([r["true_error"] for r in rows], float)
    e = np.array([r["estimated_error"] for r in rows], float)
    finite = np.isfinite(t) & np.isfinite(e)
    shown = np.concatenate([np.maximum(t[finite], FLOOR), np.maximum(e[finite], FLOOR), [accuracy]])
    lo, hi = shown.min() / 3.0, shown.max() * 3.0
    ax.fill_between([accuracy, hi], lo, accuracy, color="tab:red", alpha=0.08, linewidth=0,
                    label="false pass (estimate meets, truth misses)")
    ax.plot([lo, hi], [lo, hi], color="k", linewidth=0.8, label="estimate = truth")
    ax.axhline(accuracy, color="k", linestyle=":", linewidth=1.0, label="scene accuracy %g" % accuracy)
    ax.axvline(accuracy, color="k", linestyle=":", linewidth=1.0)
    for family, (color, marker) in FAMILY_STYLE.items():
        for bound in (False, True):
            mine = [i for i, r in enumerate(rows) if r["family"] == family and finite[i]
                    and bool(r["true_lower_bound"] or r["estimate_lower_bound"]) == bound]
            if not mine:
                continue
            ax.plot(np.maximum(t[mine], FLOOR), np.maximum(e[mine], FLOOR), linestyle="", marker=marker, markersize=6,
                    color=color, markerfacecolor="none" if bound else color, alpha=0.8,
                    label="%s%s (%d)" % (family, ", a value is a lower bound" if bound else "", len(mine)))
    # the two choices are often the same candidate: a star inside a ring keeps both visible
    for flag, label, style in (("chosen_full_order", "chosen with the full order",
                                dict(marker="*", markersize=14, color="tab:red", markeredgecolor="k")),
                               ("chosen_estimator", "chosen with the estimator",
                                dict(marker="o", markersize=20, markerfacecolor="none", markeredgecolor="tab:orange",
                                     markeredgewidth=2.0))):
        mine = [i for i, r in enumerate(rows) if r[flag] and finite[i]]
        if mine:
            ax.plot(np.maximum(t[mine], FLOOR), np.maximum(e[mine], FLOOR), linestyle="", label=label, zorder=5,
                    **style)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlim(lo, hi)
    ax.set_ylim(lo, hi)
    ax.set_xlabel("true error (against the full order)")
    ax.set_ylabel("estimated error (against the richest candidate)")
    ax.set_title("%s: the search's error estimate against the truth, per candidate" % scene_name, fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    return fig


def write_figure(rows, path, scene_name, accuracy):
    figure(rows, scene_name, accuracy).savefig(path, dpi=110)
    return path


def markdown(check, failure=None):
    """The study.md section: what was compared, the figures, the chosen models (lines, no trailing blank)."""
    lines = ["## The error estimator against the truth", ""]
    if check is None:
        return lines + ["Not made: %s." % failure.rstrip(".")]
    s = check.summary()
    acc = s["accuracy"]
    lines += ["The accuracy search run twice on this scene: every candidate's error measured against the full order "
              "(verify.full_order on, %s s) and estimated against the richest candidate (off, %s s), the two search "
              "tables joined on the candidate (family, moments, kept clusters, expansion angles, alpha_G or first "
              "expansion angle). %s. Every joined candidate in estimator.csv, the scatter in estimate_vs_truth.png."
              % (_g(s["full_seconds"]), _g(s["estimator_seconds"]), _counts(s)), ""]
    if s["exact"]:
        lines.append("- Ratio estimate / true over the %d candidates whose two errors are exact: median %s, from %s "
                     "to %s; the farthest from 1: %s." % (s["exact"], _g(s["median_ratio"]), _g(s["min_ratio"]),
                                                         _g(s["max_ratio"]), _worst(s["worst"])))
    else:
        lines.append("- No candidate has both errors exact: no ratio estimate / true.")
    lines.append("- Where pass or fail is decided (true error >= accuracy / %g = %s): %s." % (
        DECISION_BAND, _g(acc / DECISION_BAND), "%d candidates, median ratio %s, the farthest from 1: %s" % (
            s["near"], _g(s["near_median_ratio"]), _worst(s["near_worst"])) if s["near"] else "no candidate"))
    lines.append("- The lowest true error of any candidate is %s: near it the true error may be the full-order "
                 "reference's own floor (its truncated modal sum) rather than the model's." % _g(s["lowest_true"]))
    for rows, what in ((s["false_passes"], "False passes (the estimate meets %g, the true error does not)" % acc),
                       (s["false_fails"], "False fails (the estimate misses %g, the true error meets it)" % acc)):
        lines.append("- %s: %d of %d%s." % (what, len(rows), s["joined"], ": " + "; ".join(
            _row(r) for r in rows[:6]) + (" ..." if len(rows) > 6 else "") if rows else ""))
    if s["only_full"] or s["only_estimator"]:
        lines.append("- %d candidates only in the full-order search, %d only in the estimator's: the searches took "
                     "different paths where a pass or fail, or the best single-angle model, differed%s." % (
                         s["only_full"], s["only_estimator"], "" if not s["multi_starts"] else
                         " (the multi-angle search started from %s deg with the full order, from %s deg with the "
                         "estimator)" % (_list(s["multi_starts"]["full"]), _list(s["multi_starts"]["estimator"]))))
    for name, what in (("full", "With the full order"), ("estimator", "With the estimator")):
        c = s["chosen_" + name]
        row = c["row"]
        if row is not None:
            truth = "; its true error %s, estimate %s (%s)" % (
                _bounded(row["true_error"], row["true_lower_bound"]),
                _bounded(row["estimated_error"], row["estimate_lower_bound"]), row["verdict"])
        else:       # the other search never tried it: its truth where the full order is known
            truth = "; the other search did not try it; its true error at the angles of interest (no midpoints): %s" % (
                "n/a" if c["at_angles"] is None else "%s (%s %g)" % (
                    _g(c["at_angles"]), "meets" if c["at_angles"] <= acc else "misses", acc))
        lines.append("- %s the search chose %s; error_max %s, target %s%s." % (
            what, c["candidate"] or "a model no table column matches", _g(c["error_max"]),
            {1.0: "met", 0.0: "missed"}.get(c["target_met"], "n/a"), truth))
    if check.notes:
        lines += [""] + ["- %s" % n for n in check.notes]
    return lines


def console(check, failure=None):
    """One line of the figures for the terminal."""
    if check is None:
        return "estimator check not made: %s" % failure
    s = check.summary()
    return ("estimator vs truth: %d candidates (%d exact), ratio estimate/true median %s, farthest from 1 %s (near "
            "the accuracy: median %s, farthest %s); false passes %d, false fails %d; chosen error_max %s (full "
            "order), %s (estimated)" % (s["joined"], s["exact"], _g(s["median_ratio"]), _g(_worst_ratio(s["worst"])),
                                        _g(s["near_median_ratio"]), _g(_worst_ratio(s["near_worst"])),
                                        len(s["false_passes"]), len(s["false_fails"]),
                                        _g(s["chosen_full"]["error_max"]), _g(s["chosen_estimator"]["error_max"])))


def _counts(s):
    out = "%d candidates in both searches (of %d in the full-order one, %d in the estimator one)" % (
        s["joined"], s["full_candidates"], s["estimator_candidates"])
    if s["lower_bounds"]:
        out += "; %d of them with an error that is only a lower bound (the search stops measuring a candidate " \
               "once its error exceeds the accuracy): drawn open, left out of the ratios" % s["lower_bounds"]
    return out


def _bounded(value, lower_bound):
    return (">= " if lower_bound else "") + _g(value)


def _list(labels):
    return " / ".join(labels) or "none"


def _worst_ratio(row):
    return math.nan if row is None else row["ratio"]


def _worst(row):
    return "n/a" if row is None else "%s (%s)" % (_g(row["ratio"]), _row(row))


def _row(r):
    return "%s: true %s, estimate %s" % (
        describe(r["family"], r["moments"], r["kept_clusters"], r["expansion_angles"], r["start_deg"])
        + ("" if r.get("variant", "split") == "split" else ", " + r["variant"]),
        _bounded(r["true_error"], r["true_lower_bound"]), _bounded(r["estimated_error"], r["estimate_lower_bound"]))
