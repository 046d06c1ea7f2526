"""Verification report of one reduction: summary.json, report.md (laid out like the paper's study) and plots.

    paths = write_report(summary, out_dir)

writes into out_dir (created if needed):
  summary.json                                   every number, exactly as given
  report.md                                      tables in the order of the paper's Tables 1-6 and Fig. 3
  bode_<angle>deg.png                            full vs reduced, one per configuration, every I/O pair a cell
                                                 (bode_structure.png without revolute joints)
  bode_<angle>deg_<output>_<input>.png           the same, one per configuration and I/O pair: with pair_plots,
                                                 or instead of the above for more than 12 pairs
  bode_overview.png                              magnitudes at every configuration (dominant I/O pair)
  importance_<angle>deg.png                      normalized importance of the Krylov modes, kept ones marked
                                                 (importance_structure.png without revolute joints)
  moment_ratios.png                              |L_full/L_reduced - 1| against k
  frf_error.png                                  pointwise relative FRF error against frequency
and returns the written paths. Everything is validated first, then rendered into a hidden staging folder inside
out_dir; only when all succeeded are the files moved into place together (io.files.Staging). A failure raises
ReportError (or the plotting error), removes the staging folder and leaves any earlier report in out_dir untouched.

The summary is a kryflex.results.Summary (or its JSON dict); summary.json is its to_json(). This package depends
only on the standard library, NumPy and matplotlib (no compiled kryflex code).
"""
import os

from ..io.files import Staging
from ..io.scene_schema import NO_JOINT_LABEL
from .figures import plot_file_names
from .helper import PlotRendering
from .schema import _check_json_types, validate_summary
from .context import _Context, as_summary
from .sections import _section_accuracy, _section_choice, render_markdown


def _write_together(out_dir, files):
    """Writes (name, bytes) pairs into a staging folder of out_dir (io.files.Staging) and moves them into place
    together; returns their paths. On any failure, or an exception raised between files, nothing of them is left
    and out_dir's earlier files are as they were."""
    os.makedirs(out_dir, exist_ok=True)
    staging = Staging(out_dir)
    staging.create()
    try:
        for name, data in files:
            with open(staging.file(name), "wb") as handle:
                handle.write(data)
        return staging.commit()
    finally:
        staging.discard()


class PendingReport:
    """A report begun (begin_report): its summary validated, its figures' shares sent to the helper processes that
    draw them meanwhile, summary.json and report.md written into its staging folder. finish() draws what is left
    here, writes the figures and moves every file into out_dir together (returning their paths); stop() abandons it
    (the helpers stopped, the staging folder removed, out_dir as it was)."""

    def __init__(self, summary, out_dir, between, pair_plots=False):
        if not isinstance(summary, dict):
            summary = as_summary(summary).to_json()
        validate_summary(summary)
        summary = as_summary(summary)
        self.between, self.staging = between, None
        plot_names = plot_file_names(summary, pair_plots)
        # the helpers first, so that they draw while the text below is written and the caller writes its files
        self.rendering = PlotRendering(summary, plot_names).start()
        try:
            os.makedirs(out_dir, exist_ok=True)
            self.staging = Staging(out_dir)
            self.staging.create()
            self._write("summary.json", summary.dumps().encode("utf-8"))
            self._write("report.md", render_markdown(summary, plot_names).encode("utf-8"))
        except BaseException:
            self.stop()
            raise

    def _write(self, name, data):
        with open(self.staging.file(name), "wb") as handle:
            handle.write(data)

    def finish(self):
        try:
            for name, data in self.rendering.items(self.between):
                self._write(name, data)
            return self.staging.commit()
        finally:
            self.stop()

    def stop(self):
        self.rendering.stop()
        if self.staging is not None:
            self.staging.discard()


def begin_report(summary, out_dir, between=None, pair_plots=False):
    """write_report in two steps, so that the caller can write its own files while the figures are drawn: returns a
    PendingReport whose finish() writes the report (stop() abandons it). Raises as write_report."""
    return PendingReport(summary, out_dir, between, pair_plots)


def write_report(summary, out_dir, between=None, pair_plots=False):
    """Write summary.json, report.md and the PNG plots into out_dir; return the written paths.

    Raises ReportError (a ValueError) naming the offending key when the summary is incomplete or not plain JSON;
    on any failure no file of this report is left in out_dir (earlier files there are untouched). between: called
    after each plot drawn in this process (the command stops there when it was interrupted: rendering the plots is
    the long part). The figures are shared with helper processes where cores are free (report/helper.py).
    pair_plots: a Bode figure per input/output pair too (bode_<angle>deg_<output>_<input>.png), besides the one per
    configuration.
    """
    return begin_report(summary, out_dir, between, pair_plots).finish()


def write_unverified(summary, out_dir):
    """When the full-order verification was skipped (verify.full_order: false): summary.json and a short report.md
    with what is known without the full order (sizes, alpha_G, kept modes, the estimated error of the chosen model
    and the search, full-order moments). Same guarantees as write_report."""
    typed = as_summary(summary)
    summary = typed.to_json()
    _check_json_types(summary, ())
    lines = [f"# kryflex reduction: {summary.get('scene', '?')}", "",
             "The full-order verification was skipped (`verify.full_order: false`): no frequency-response or",
             "frequency comparison against the full order; errors below are estimated. Single-angle model: body sizes "
             + ", ".join(f"{b} {v}" for b, v in (summary.get("reduced", {}).get("dofs_per_body") or {}).items()) + ",",
             ("one configuration (no revolute joint)" if summary.get("reduction_label") == NO_JOINT_LABEL
              else f"reduction angle α_G {summary.get('reduction_label')} deg")
             + f", kept Krylov modes {summary.get('kept_modes')}.", ""]
    try:
        c = _Context(summary)
    except (KeyError, TypeError, ValueError, IndexError):      # a summary too sparse for the sections below
        c = None
    if c is not None:
        # the verdict on the chosen model: its error estimated (the a-posteriori estimator) when the reducer gave one
        lines += _section_accuracy(c) + _section_choice(c)
    ratios = summary.get("reduced", {}).get("moment_ratios") or {}
    if ratios:
        lines += ["| angle (deg) | max abs(L_full/L_reduced - 1) |", "| :--- | ---: |"]
        for label, r in ratios.items():
            devs = [abs(x - 1) for k in r for row in k for x in row if x is not None]
            lines.append(f"| {label} | {max(devs) if devs else 0:.3e} |")
    return _write_together(out_dir, [
        ("summary.json", typed.dumps().encode("utf-8")),
        ("report.md", ("\n".join(lines) + "\n").encode("utf-8"))])
