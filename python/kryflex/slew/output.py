"""The slewing study's files: slew.csv (one row per slew duration), slew.md (the table, the adequacy limit and the
step check) and slew.png (error against peak slew rate, log-log, the scene's accuracy as a line), plus the time
histories of the slowest and the fastest slew (slew_histories.png), and slew.json (the rows without the histories,
the limit, the settings). A held profile (a step or pulse of force on a structure at rest, profiles.HELD) writes the
same files with the input's rise time or pulse length in place of the slew rate."""
import csv
import json

import numpy as np

COLUMNS = ("duration_s", "periods", "peak_rate_deg_s", "step_s", "error", "elastic_error", "total_error", "full_seconds",
           "reduced_seconds")


def write_csv(rows, path, output_names):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(list(COLUMNS) + ["error_%s" % n for n in output_names])
        for r in rows:
            w.writerow(["%.6g" % r[c] for c in COLUMNS] + ["%.6g" % e for e in r["errors"]])


def write_chart(rows, path, title, accuracy, limit, frf_error=None, baseline=None, measure="elastic"):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    held = rows[0]["peak_rate_deg_s"] == 0
    # a held profile has no rate: its runs go by the input's duration T / P1, shortest (hardest) to the right
    rate = np.array([r["periods"] if held else r["peak_rate_deg_s"] for r in rows])
    err = np.array([r["elastic_error"] for r in rows])
    tot = np.array([r["total_error"] for r in rows])
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    ax.loglog(rate, err, "o-", label="elastic output (rigid modes removed)")
    ax.loglog(rate, tot, "s--", alpha=0.6, label="total output")
    ax.axhline(accuracy, color="r", lw=1, label="scene accuracy %g" % accuracy)
    if frf_error is not None and frf_error > 0:
        ax.axhline(frf_error, color="g", lw=1, ls=":", label="frequency-domain %s error %.3g" % (measure, frf_error))
    if baseline is not None:
        ax.axhline(baseline["error"], color="m", lw=1, ls="-.",
                   label="no slew (angle held), same torque: %.3g" % baseline["error"])
    if limit is not None:
        x = limit["periods"] if held else limit["peak_rate_deg_s"]
        ax.axvline(x, color="k", lw=1, ls=":", label=("not adequate from T = %.3g P1" if held else
                                                      "not adequate from %.3g deg/s") % x)
    if held:
        ax.invert_xaxis()
    ax.set_xlabel("input rise time or pulse length T / P1" if held else "peak slew rate (deg/s)")
    ax.set_ylabel("relative max-norm error of the output history")
    ax.set_title(title, fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def write_histories(rows, path, title, output_names):
    """The elastic output histories (full and reduced) of the slowest and the fastest slew."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    picks = [rows[0], rows[-1]]
    fig, axes = plt.subplots(len(picks), 1, figsize=(6.4, 5.6))
    for ax, r in zip(axes, picks):
        tf, _, ef = r["full"]
        tr, _, er = r["reduced"]
        ax.plot(tf, ef[:, 0], label="full (%s)" % output_names[0])
        ax.plot(tr, er[:, 0], "--", label="reduced")
        ax.axvline(r["duration_s"], color="k", lw=0.8, ls=":")
        ax.set_title(("input of %.3g s: error %.3g" % (r["duration_s"], r["error"])) if r["peak_rate_deg_s"] == 0 else
                     "slew %.3g s (peak %.3g deg/s): error %.3g" % (r["duration_s"], r["peak_rate_deg_s"], r["error"]),
                     fontsize=9)
        ax.set_xlabel("t (s)")
        ax.legend(fontsize=8)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def write_json(rows, path, study, limit, check, frf_error, baseline=None):
    """The study's figures (no histories) for scripts."""
    s = study
    strip = lambda r: None if r is None else {k: v for k, v in r.items() if k not in ("full", "reduced")}
    data = dict(scene=s.scene.name, profile=s.kind, held=s.held, inputs=s.inputs, force=s.force if s.held else None,
                angles_deg=None if s.jointfree else np.atleast_1d(s.alpha0_deg).tolist(),
                amplitude_deg=None if s.held else np.atleast_1d(s.amplitude_deg).tolist(),
                full_dofs=s.full.dofs, reduced_dofs=s.reduced.dofs, f1_hz=s.f1, P1_s=s.P1, damping=s.zeta,
                accuracy=s.accuracy, adequate=limit is None, limit=strip(limit), frf_error=frf_error,
                baseline=strip(baseline), step_check=check, rows=[strip(r) for r in rows])
    with open(path, "w") as f:
        json.dump(data, f, indent=1)


def _where(s):
    """Where the study runs: the structure (no revolute joint) or the angles."""
    return "of the structure" if s.jointfree else "at %s deg" % _deg(s.alpha0_deg)


def markdown(rows, study, limit, check, frf_error, exudyn=None, baseline=None, ffrf=None, measure="elastic"):
    s = study
    damping = ("damping ratio %.3g: the frequency domain's damping model on each model's own modes" % s.zeta if s.held
               else "damping ratio %.3g: with the angle held the frequency domain's damping model on each model's own "
               "modes, while slewing stiffness-proportional at f1" % s.zeta)
    if s.held:
        what = ("a %s of force %g on %s (rise time or pulse length T swept), %s" % (
            s.kind, s.force, ", ".join(s.inputs), "no joint" if s.jointfree else "angles held %s" % _where(s)))
        lines = ["# Time response at rest: %s" % s.scene.name, "",
                 "Full order %d dofs, reduced %d dofs; %s; first flexible frequency %.4g Hz (P1 %.4g s); %s; "
                 "accuracy %g." % (s.full.dofs, s.reduced.dofs, what, s.f1, s.P1, damping, s.accuracy), ""]
    else:
        lines = ["# Slewing study: %s" % s.scene.name, "",
                 "Full order %d dofs, reduced %d dofs; profile %s from %s deg by %s deg; first flexible frequency "
                 "%.4g Hz (P1 %.4g s); %s; drive on %s; accuracy %g."
                 % (s.full.dofs, s.reduced.dofs, s.kind, _deg(s.alpha0_deg), _deg(s.amplitude_deg), s.f1, s.P1,
                    damping, ", ".join(s.inputs), s.accuracy), ""]
    lines += ["Note: %s." % n for n in getattr(s, "notes", [])]
    step, step_untrimmed = s.explicit_step
    if s.trim_hz > 0:
        lines += ["Trimmed reduced model (reduction.max_frequency, %.4g Hz): highest frequency %s %.4g Hz "
                  "(untrimmed %.4g Hz), stable explicit step 2/omega_max %.3g s (untrimmed %.3g s); integrated with "
                  "the trimmed modes' mass taken out at every angle (kryflex/slew/trimmed.py)."
                  % (s.trim_hz, _where(s), s.top_hz, s.untrimmed_top_hz, step, step_untrimmed), ""]
    else:
        lines += ["Reduced model untrimmed: highest frequency %s %.4g Hz, stable explicit step 2/omega_max %.3g s "
                  "(reduction.max_frequency trims it)." % (_where(s), s.top_hz, step), ""]
    if frf_error is not None:
        lines += ["Frequency-domain error of the reduced model (the reduction's verification: relative H-inf error "
                  "of the %s response per input/output pair, max over the angles of interest): %.3g."
                  % (measure, frf_error), ""]
    if baseline is not None:
        lines += ["No slew (the slowest slew's torque with the angle held at %s deg): error %.3g (elastic %.3g, total "
                  "%.3g): the reduced model's time-domain error at a fixed angle." % (
                      _deg(s.alpha0_deg), baseline["error"], baseline["elastic_error"], baseline["total_error"]), ""]
    lines += _table(rows, s.held)
    if s.held:
        lines.append("The reduced model stays adequate (error <= %g) for every input down to T = %.3g P1."
                     % (s.accuracy, min(r["periods"] for r in rows)) if limit is None else
                     "The reduced model stops being adequate (error > %g) for an input of %.3g s = %.3g P1."
                     % (s.accuracy, limit["duration_s"], limit["periods"]))
    elif limit is None:
        lines.append("The reduced model stays adequate (error <= %g) at every rate up to %.4g deg/s."
                     % (s.accuracy, max(r["peak_rate_deg_s"] for r in rows)))
    else:
        lines.append("The reduced model stops being adequate (error > %g) at a peak slew rate of %.4g deg/s "
                     "(slew of %.3g s = %.3g P1)." % (s.accuracy, limit["peak_rate_deg_s"], limit["duration_s"],
                                                       limit["periods"]))
    if check is not None:
        lines += ["", "Step check (fastest run, step %.3g s and half of it): error %.4g and %.4g; the full model's "
                  "elastic output changes by %.2g of its peak." % (check["step_s"], check["error"],
                                                                   check["error_half_step"], check["output_change"])]
    if exudyn is not None:
        lines += ["", "Exudyn check (the full model's fastest run by Exudyn's generalized-alpha solver on the same "
                  "equations, step %.3g s): relative difference from this integrator %.2g." % (exudyn["step_s"],
                                                                                               exudyn["difference"])]
    if ffrf:
        lines += ["", "Reduced bodies in Exudyn's floating-frame formulation (nonlinear, undamped, driven by the slew's "
                  "torque) against this integrator along Exudyn's angle history, elastic-output errors "
                  "(2A/pi: the share of the centrifugal loads the linear model neglects):", "",
                  "| T / P1 | turn (deg) | peak rate (deg/s) | Exudyn reduced vs full | reduced vs full | "
                  "Exudyn vs reduced | 2A/pi |", "|---:|---:|---:|---:|---:|---:|---:|"]
        lines += ["| %.3g | %.4g | %.4g | %.3g | %.3g | %.3g | %.3g |" % (
            r["periods"], r["turn_deg"], r["peak_rate_deg_s"], r["exudyn_vs_full"], r["reduced_vs_full"],
            r["exudyn_vs_reduced"], 2 * np.radians(r["turn_deg"]) / np.pi) for r in ffrf]
    lines += ["", "error: max(elastic, total), each the largest over outputs of max_t |y_full - y_red| / max_t |y_full|; "
              "elastic: of the outputs of the elastic parts (rigid-body and mechanism modes taken out M-orthogonally"
              "%s); total: of the outputs themselves." % ("" if s.jointfree else " at alpha(t)")]
    lines += ["", "Chart: slew.png; histories of the slowest and the fastest %s: slew_histories.png; figures: "
              "slew.json." % ("input" if s.held else "slew"), ""]
    return "\n".join(lines)


def _table(rows, held):
    if held:
        head = ["| input duration T (s) | T / P1 | step (s) | error | elastic | total | full (s) | reduced (s) |",
                "|---:|---:|---:|---:|---:|---:|---:|---:|"]
        return head + ["| %.4g | %.3g | %.3g | %.3g | %.3g | %.3g | %.1f | %.1f |" % (
            r["duration_s"], r["periods"], r["step_s"], r["error"], r["elastic_error"], r["total_error"],
            r["full_seconds"], r["reduced_seconds"]) for r in rows] + [""]
    head = ["| slew duration (s) | T / P1 | peak rate (deg/s) | step (s) | error | elastic | total | "
            "full (s) | reduced (s) |", "|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    return head + ["| %.4g | %.3g | %.4g | %.3g | %.3g | %.3g | %.3g | %.1f | %.1f |" % (
        r["duration_s"], r["periods"], r["peak_rate_deg_s"], r["step_s"], r["error"], r["elastic_error"],
        r["total_error"], r["full_seconds"], r["reduced_seconds"]) for r in rows] + [""]


def _deg(a):
    return ", ".join("%g" % x for x in np.atleast_1d(a))
