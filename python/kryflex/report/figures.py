"""The report's figures: their file names and their PNG bytes."""
import numpy as np

from . import plots
from .context import _Context
from .formatting import MAX_PAIRS_PER_FIGURE, RATIO_EXACT_TOL, safe_name
from .paper import paper_figures


def plot_file_names(summary, pair_plots=False):
    """{"bode_pairs": {label: file}, "bode": {(label, (o, i)): file}, "importance": {label: file}} with file-name-safe,
    distinct names: the Bode plots of a configuration in one figure (a cell per input/output pair, "bode_pairs") when it
    has at most MAX_PAIRS_PER_FIGURE pairs, else a figure per pair ("bode"); pair_plots: a figure per pair too."""
    c = _Context(summary)
    used = set()

    def unique(name):
        stem, candidate, n = name[:-4], name, 2
        while candidate in used:
            candidate, n = f"{stem}_{n}.png", n + 1
        used.add(candidate)
        return candidate

    names = {"bode_pairs": {}, "bode": {}, "importance": {}}
    together = len(c.entries) <= MAX_PAIRS_PER_FIGURE
    for label in c.labels:
        unit = "" if c.no_joint(label) else "deg"   # bode_15deg_..., bode_structure_... without revolute joints
        if together:
            names["bode_pairs"][label] = unique(f"bode_{safe_name(label)}{unit}.png")
        for (o, i) in (c.entries if pair_plots or not together else ()):
            names["bode"][(label, (o, i))] = unique(
                f"bode_{safe_name(label)}{unit}_{safe_name(c.outputs[o])}_{safe_name(c.inputs[i])}.png")
        names["importance"][label] = unique(f"importance_{safe_name(label)}{unit}.png")
    return names


def _render_plots(summary, plot_names):
    """Yield (file name, PNG bytes) for every figure of the report (summary: a Summary or its JSON dict)."""
    for _, job, _ in figure_jobs(summary, plot_names):
        yield from job()


def figure_jobs(summary, plot_names, prepared=None):
    """The report's figures as [(weight, job, kind)]: job() yields (file name, PNG bytes) of one or more figures, kind
    names them as plots.prepared_figures does ("bode", "overview", "importance"; "moments", "frf_error", "paper"), weight is
    about its drawing time in units of one Bode plot drawn over its figure's fixed layer (plots._FixedLayer: about
    25 ms for 450 frequencies on an idle core), as a helper draws them with its figures prepared (the Bode, overview
    and importance figures: plots.prepared_figures, given as prepared, the reuse dict the jobs then draw on; without
    it the first Bode plot and the overview cost about 5 units more each). The same list, in the same order, for the same summary: the figures can be shared among
    processes by their indices (report/helper.py)."""
    c = _Context(summary)
    s = c.summary
    threshold = s.settings.keep_threshold if s.settings is not None else None
    arrays = {label: (np.asarray(s.frf[label].freq_hz, float), s.frf[label].full(), s.frf[label].chosen())
              for label in c.labels}
    jobs = []
    # the Bode and importance figures left by one share for the next: a process that draws both shares (no helper, or
    # a helper's failure) builds each figure once
    reuse = {} if prepared is None else prepared

    def bode(labels):       # the configurations' pairs on one reused figure (plots.bode_pngs_on_grids)
        items, names = [], []
        for label in labels:
            freq, full, red = arrays[label]
            for (o, i) in c.entries:
                items.append((freq, full[:, o, i], red[:, o, i],
                              f"{c.angle(label)}{c.g_mark(label)}: {c.entry_name((o, i))}, {c.model_name}"))
                names.append(plot_names["bode"][(label, (o, i))])
        yield from zip(names, plots.bode_pngs_on_grids(items, reuse=reuse))
    # two jobs (a share for each process of report/helper.py), each configuration's pairs in one of them; a process's
    # first figure draws the fixed layer too, unless prepared
    halves = [c.labels[:(len(c.labels) + 1) // 2], c.labels[(len(c.labels) + 1) // 2:]]
    if plot_names["bode"]:
        jobs += [(float(len(part) * len(c.entries)), lambda part=part: bode(part), "bode") for part in halves if part]

    def bode_pairs(labels):     # a figure per configuration, its pairs as cells, on one reused figure
        items = []
        for label in labels:
            freq, full, red = arrays[label]
            items.append((freq, [(full[:, o, i], red[:, o, i], c.entry_name((o, i))) for (o, i) in c.entries],
                          f"{c.angle(label)}{c.g_mark(label)}: full vs reduced ({c.model_name})"))
        yield from zip([plot_names["bode_pairs"][label] for label in labels], plots.bode_pairs_pngs(items, reuse=reuse))
    # a figure of six cells draws in about the time of 2.5 Bode plots (its y axes: 0.4 Bode plot each)
    if plot_names["bode_pairs"]:
        jobs += [(0.45 * len(part) * len(c.entries), lambda part=part: bode_pairs(part), "bode_pairs")
                 for part in halves if part]

    def overview():
        o, i = c.dominant_entry
        panels = [(c.short_angle(l), arrays[l][0], arrays[l][1][:, o, i], arrays[l][2][:, o, i]) for l in c.labels]
        yield "bode_overview.png", plots.bode_overview_png(
            panels, f"{s.scene}: full vs reduced ({c.model_name}), {c.entry_name((o, i))}", reuse=reuse)
    jobs.append((1.0 + 0.8 * len(c.labels), overview, "overview"))

    def importance(labels):     # the configurations' figures on one reused figure (plots.importance_pngs)
        items = [(s.krylov[label].frequency_hz, s.krylov[label].importance, s.krylov[label].kept,
                  f"Krylov mode importance, {c.angle(label)}{c.g_mark(label)}", threshold, s.band_hz)
                 for label in labels]
        yield from zip([plot_names["importance"][label] for label in labels], plots.importance_pngs(items, reuse=reuse))
    # in two jobs as the Bode plots; a process's first figure builds its ticks, unless prepared
    jobs += [(1.5 + 2.2 * len(part), lambda part=part: importance(part), "importance") for part in halves if part]

    def moments():
        series = [(f"single, {c.short_angle(l)}", s.reduced.moment_ratios[l], False) for l in c.labels]
        multi = (s.multi_angle.moment_ratios if s.multi_angle is not None else None) or {}
        series += [(f"multi, {c.short_angle(l)}", multi[l], True) for l in c.labels if l in multi]
        yield "moment_ratios.png", plots.figure_png_bytes(plots.moment_ratio_figure(series, RATIO_EXACT_TOL))
    jobs.append((4.0, moments, "moments"))

    def rigid(label):       # the elastic measure's rigid part of the full response, when the summary has it
        f = s.frf[label]
        return None if f.full_rigid_re is None else f._complex(f.full_rigid_re, f.full_rigid_im)

    def frf_error():
        curves = [(c.short_angle(l), arrays[l][0], plots.frf_hinf_error_curve(arrays[l][1], arrays[l][2], rigid(l)))
                  for l in c.labels]
        yield "frf_error.png", plots.figure_png_bytes(plots.frf_error_figure(
            curves, s.accuracy, f"Relative {s.verdict.accuracy_measure or 'total'}-response error of the chosen model "
                                f"({c.model_name})"))
    jobs.append((4.0, frf_error, "frf_error"))
    paper = (c.s.get("paper") or {}).get("frf")
    if paper:
        jobs.append((1.0 + 2.0 * len(paper), lambda: paper_figures(c.s), "paper"))      # an overview of its angles
    return jobs
