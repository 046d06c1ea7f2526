"""Verification report of one reduction: summary.json, report.md (laid out like the paper's study) and plots.

    paths = write_report(summary, out_dir)

writes into out_dir (created if needed):
  summary.json                                   every number, exactly as given
  report.md                                      tables in the order of the paper's Tables 1-6 and Fig. 3
  bode_<angle>deg_<output>_<input>.png           full vs reduced, one per configuration and I/O pair
  bode_overview.png                              magnitudes at every configuration (dominant I/O pair)
  importance_<angle>deg.png                      normalized importance of the Krylov modes, kept ones marked
  moment_ratios.png                              |L_full/L_reduced - 1| against k
  frf_error.png                                  pointwise relative FRF error against frequency
and returns the written paths. Everything is validated and rendered first, into temporary files; only when
all succeeded are they renamed into place (os.replace). A failure raises ReportError (or the plotting error),
removes the temporary files and leaves any earlier report in out_dir untouched.

The summary schema is in schema.py. This package depends only on the standard library, NumPy and matplotlib
(no compiled kryflex code).
"""
import json
import os

from ..io.files import commit, temporary_beside
from .figures import _render_plots, plot_file_names
from .schema import _check_json_types, validate_summary
from .sections import render_markdown


class _StagedFiles:
    """Files written under temporary names in out_dir and renamed into place together by commit().

    Until commit() nothing visible changes in out_dir; abort() removes the temporary files, so a failure
    never leaves a partial or mixed old/new report behind."""

    def __init__(self, out_dir):
        self.out_dir = out_dir
        self.staged = []

    def add(self, name, data):
        final = os.path.join(self.out_dir, name)
        tmp = temporary_beside(final)
        self.staged.append((tmp, final))
        with open(tmp, "wb") as handle:
            handle.write(data)

    def commit(self):
        written = []
        for tmp, final in self.staged:
            commit(tmp, final)
            written.append(final)
        self.staged = []
        return written

    def abort(self):
        for tmp, _ in self.staged:
            if os.path.exists(tmp):
                os.unlink(tmp)
        self.staged = []


def write_report(summary, out_dir, between=None):
    """Write summary.json, report.md and the PNG plots into out_dir; return the written paths.

    Raises ReportError (a ValueError) naming the offending key when the summary is incomplete or not plain JSON;
    on any failure no file of this report is left in out_dir (earlier files there are untouched). between: called
    after each plot (the command stops there when it was interrupted: rendering the plots is the long part).
    """
    validate_summary(summary)
    text_json = json.dumps(summary, indent=1, allow_nan=False) + "\n"
    plot_names = plot_file_names(summary)
    markdown = render_markdown(summary, plot_names)
    os.makedirs(out_dir, exist_ok=True)
    staging = _StagedFiles(out_dir)
    try:
        for name, data in _render_plots(summary, plot_names):
            staging.add(name, data)
            if between is not None:
                between()
        staging.add("summary.json", text_json.encode("utf-8"))
        staging.add("report.md", markdown.encode("utf-8"))
        return staging.commit()
    except BaseException:
        staging.abort()
        raise


def write_unverified(summary, out_dir):
    """When the full-order verification was skipped (verify.full_order: false): summary.json and a short report.md
    with what is known without the full order (sizes, alpha_G, kept modes, full-order moments). Same guarantees as
    write_report."""
    _check_json_types(summary, ())
    lines = [f"# kryflex reduction: {summary.get('scene', '?')}", "",
             "The full-order verification was skipped (`verify.full_order: false`): no frequency-response or",
             "frequency comparison. Reduced body sizes: " + ", ".join(
                 f"{b} {v}" for b, v in (summary.get("reduced", {}).get("dofs_per_body") or {}).items()) + ".",
             f"Reduction angle α_G: {summary.get('reduction_label')} deg; kept Krylov modes: {summary.get('kept_modes')}.", ""]
    ratios = summary.get("reduced", {}).get("moment_ratios") or {}
    if ratios:
        lines += ["| angle (deg) | max abs(L_full/L_reduced - 1) |", "| :--- | ---: |"]
        for label, r in ratios.items():
            devs = [abs(x - 1) for k in r for row in k for x in row if x is not None]
            lines.append(f"| {label} | {max(devs) if devs else 0:.3e} |")
    os.makedirs(out_dir, exist_ok=True)
    staging = _StagedFiles(out_dir)
    try:
        staging.add("summary.json", (json.dumps(summary, indent=1, allow_nan=False) + "\n").encode("utf-8"))
        staging.add("report.md", ("\n".join(lines) + "\n").encode("utf-8"))
        return staging.commit()
    except BaseException:
        staging.abort()
        raise
