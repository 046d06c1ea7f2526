"""Figures of the verification report: Bode overlays, Krylov mode importance, moment ratios, FRF error.

Every ``*_figure`` function draws one matplotlib Figure from plain NumPy data and returns it; it does not
touch the disk. ``save_figure`` writes a figure atomically (temporary name in the same folder, then
os.replace); ``figure_png_bytes`` renders it in memory, for callers that stage several files together
(see report.py).

Figures are built on matplotlib's Agg canvas directly, never through pyplot, so this module neither needs
a display nor changes the process-wide backend of a program that imports it.

This module depends only on NumPy and matplotlib (no other kryflex module), so the report can be produced
on a machine without the compiled extension. matplotlib is imported when the first figure is drawn, not with this
module: the report's text and the data helpers below (which the reducer's summary and report.md use) do not need it,
and importing it costs a run that draws no plot (verify.full_order: false) about half a second.
"""

import struct
import zlib

import numpy as np

from ..io.files import atomic_path

FULL_STYLE = {"color": "tab:blue", "linewidth": 1.6, "label": "full order"}
REDUCED_STYLE = {"color": "tab:red", "linewidth": 1.2, "linestyle": "--", "label": "reduced (Krylov)"}
DPI = 110
# zlib level of the PNGs: 1 encodes several times faster than 6, files ~20 % larger
PNG_COMPRESS_LEVEL = 1
# the Bode figure's margins (fractions of 7 x 5.6 in), fixed: tight_layout lays it out by drawing it once more, and
# drawing is most of the report's time; these fit a one-line title and tick labels of up to 5 characters
BODE_MARGINS = dict(left=0.12, right=0.97, top=0.93, bottom=0.09, hspace=0.08)
# the same for the one-axes figures (importance 7 x 4 in, moment ratios and FRF error 7 x 4.4 in): tight_layout was a
# fifth of a 57k-dof run's report (seven figures, each drawn twice)
SINGLE_MARGINS = dict(left=0.11, right=0.97, top=0.91, bottom=0.12)
# the overview's margins and gaps between panels in inches (its size grows with the panels), fixed for the same
# reason: tight_layout drew its every panel's ticks once more, two fifths of the figure's time; these are what
# tight_layout gave for a one-line suptitle, panel titles, small axis labels and tick labels of up to 5 characters
OVERVIEW_INCHES = dict(left=0.82, right=0.15, top=0.65, bottom=0.58, wgap=0.81, hgap=0.77)

# Values of |ratio - 1| below this are drawn on the floor of the log axis: a ratio that is exactly 1
# (difference 0) cannot be shown on a log scale otherwise.
RATIO_FLOOR = 1e-16


# ----------------------------------------------------------------------------------------------- data helpers

def frf_arrays(frf_entry):
    """(freq_hz [nf], full [nf,t,a] complex, reduced [nf,t,a] complex) from one summary["frf"][label] block; the
    reduced response is the chosen model's ("chosen_re"/"chosen_im" when the reducer chose the multi-angle model,
    else the single-angle model's "reduced_re"/"reduced_im")."""
    freq = np.asarray(frf_entry["freq_hz"], dtype=float)
    full = np.asarray(frf_entry["full_re"], dtype=float) + 1j * np.asarray(frf_entry["full_im"], dtype=float)
    which = "chosen" if "chosen_re" in frf_entry else "reduced"
    reduced = (np.asarray(frf_entry[which + "_re"], dtype=float)
               + 1j * np.asarray(frf_entry[which + "_im"], dtype=float))
    return freq, full, reduced


# a pair whose peak is below this fraction of the largest pair's peak is measured against this fraction of it
PAIR_PEAK_FLOOR = 1e-6


def frf_hinf_error_curve(full, reduced, rigid=None):
    """The integrand of the relative H-infinity error per input/output pair (the one accuracy measure,
    src/measure/frf_error.c): at each frequency, max over pairs of |Tf_ij(w) - Tr_ij(w)| / peak_ij, with
    peak_ij = max_w |Tf_ij - rigid_ij| (the elastic response's peak; the total's when rigid is None; at least
    PAIR_PEAK_FLOOR x the largest pair's peak). Its maximum over the band is the error the verdict is on.
    full, reduced, rigid: [nf, t, a] (or [nf])."""
    full = np.asarray(full)
    reduced = np.asarray(reduced)
    part = full if rigid is None else full - np.asarray(rigid).reshape(full.shape)
    if full.ndim == 1:
        full, reduced, part = full[:, None, None], reduced[:, None, None], part[:, None, None]
    peak = np.max(np.abs(part), axis=0) if full.shape[0] else np.zeros(full.shape[1:])
    largest = float(np.max(peak)) if peak.size else 0.0
    peak = np.maximum(peak, PAIR_PEAK_FLOOR * largest)
    diff = np.abs(full - reduced)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(peak > 0, diff / np.where(peak > 0, peak, 1.0), np.where(diff > 0, np.inf, 0.0))
    return ratio.reshape(ratio.shape[0], -1).max(axis=1)


def frf_relative_error(full, reduced):
    """Pointwise relative FRF error ||H_full(f) - H_red(f)||_F / ||H_full(f)||_F over the I/O matrix.

    full, reduced: arrays [nf, t, a] (or [nf]). A frequency where the full response is exactly zero gives inf
    unless the reduced one is zero too (then 0), so the caller sees the problem rather than a silent 0.
    """
    full = np.asarray(full)
    reduced = np.asarray(reduced)
    axes = tuple(range(1, full.ndim))
    diff = np.sqrt(np.sum(np.abs(full - reduced) ** 2, axis=axes)) if axes else np.abs(full - reduced)
    ref = np.sqrt(np.sum(np.abs(full) ** 2, axis=axes)) if axes else np.abs(full)
    with np.errstate(divide="ignore", invalid="ignore"):
        err = np.where(ref > 0, diff / np.where(ref > 0, ref, 1.0), np.where(diff > 0, np.inf, 0.0))
    return err


def magnitude_db(h):
    """20 log10 |h|; NaN (a gap in the curve) where h is exactly zero, e.g. an output the input cannot reach."""
    mag = np.abs(np.asarray(h))
    with np.errstate(divide="ignore"):
        return np.where(mag > 0, 20.0 * np.log10(np.where(mag > 0, mag, 1.0)), np.nan)


def phase_deg(h, reference_deg=None):
    """Unwrapped phase in degrees, shifted by a multiple of 360 so that its first point lies within 180 degrees
    of reference_deg (default 0). Unwrapping avoids the vertical +-180 jumps of a wrapped phase."""
    h = np.asarray(h)
    ph = np.degrees(np.unwrap(np.angle(h)))
    ref = 0.0 if reference_deg is None or not np.isfinite(reference_deg) else reference_deg
    if ph.size:
        ph = ph - 360.0 * np.round((ph[0] - ref) / 360.0)
    return np.where(h != 0, ph, np.nan)


def phase_pair_deg(full, reduced):
    """(full, reduced) phases in degrees, drawn consistently: both unwrapped (numpy.unwrap), the full curve's first
    point within 180 degrees of 0, then the reduced curve moved by a multiple of 360 at EVERY frequency to lie within
    180 degrees of the full one.

    Aligning at the first frequency only is not enough: across a lightly damped notch the phase jumps by nearly
    180 degrees between two grid points, and unwrap may read the jump as +180 for one curve and -180 for the other
    (a zero pair just left or just right of the axis). The two responses then agree to 1e-5 while their unwrapped
    phases differ by 360 degrees for the rest of the band (the Galileo scene at 30 deg). Moving the reduced curve
    point by point keeps the drawn difference equal to the true phase difference, wrapped to (-180, 180]."""
    ph_full = phase_deg(full)
    ph_red = phase_deg(reduced, ph_full[0] if ph_full.size else None)
    both = np.isfinite(ph_full) & np.isfinite(ph_red)
    ph_red = np.where(both, ph_red - 360.0 * np.round((ph_red - np.where(both, ph_full, 0.0)) / 360.0), ph_red)
    return ph_full, ph_red


def _frequency_axis(ax, freq, set_limits=True):
    """Log frequency axis over the data; under about two decades, label 2x and 5x ticks too, in plain numbers,
    so a narrow band is not left with a single '10^0' label."""
    freq = np.asarray(freq, dtype=float)
    if not freq.size:
        return
    low, high = float(freq.min()), float(freq.max())
    if set_limits:
        ax.set_xlim(low, high)
    else:
        low, high = ax.get_xlim()
    ticker = _ticker()
    plain = ticker.FuncFormatter(lambda x, _: f"{x:g}")
    ax.xaxis.set_major_formatter(plain)
    if high > 0 and low > 0 and np.log10(high / low) < 2.2:
        ax.xaxis.set_minor_locator(ticker.LogLocator(base=10.0, subs=(2.0, 5.0)))
        ax.xaxis.set_minor_formatter(plain)


def _note_zero_response(ax, *curves):
    """Say so on the axes when every curve is identically zero (nothing would be drawn on a dB scale)."""
    if all(not np.any(np.asarray(c) != 0) for c in curves):
        ax.text(0.5, 0.5, "response identically zero", transform=ax.transAxes, ha="center", va="center",
                color="0.4")
        ax.set_yticks([])


# ----------------------------------------------------------------------------------------------- figures

def _new_figure(figsize):
    """An empty matplotlib Figure on its own Agg canvas (never pyplot: no display, the process's backend untouched)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    fig = Figure(figsize=figsize)
    FigureCanvasAgg(fig)
    return fig


def _ticker():
    from matplotlib import ticker
    return ticker


def _set_title(ax, title, **kwargs):
    """The axes' title at its fixed height (y = 1, rcParams' default): matplotlib otherwise places it on every draw by
    measuring the y axis's tick labels (a second tick layout per drawing) to move it above an x axis on top or an
    offset text, which these figures do not have (their y axes are dB, degrees, importance or log scales)."""
    ax.set_title(title, y=1.0, **kwargs)

def bode_figure(freq_hz, full, reduced, title):
    """Magnitude (dB) and phase (deg) against frequency (Hz, log axis), full and reduced overlaid.

    full, reduced: complex arrays [nf] for one (output, input) pair.
    """
    freq = np.asarray(freq_hz, dtype=float)
    fig = _new_figure(figsize=(7.0, 5.6))
    ax_mag, ax_ph = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [3, 2]})
    ax_mag.semilogx(freq, magnitude_db(full), **FULL_STYLE)
    ax_mag.semilogx(freq, magnitude_db(reduced), **REDUCED_STYLE)
    ax_mag.set_ylabel("magnitude (dB)")
    _set_title(ax_mag, title)
    ax_mag.legend(loc="best", fontsize="small")
    _note_zero_response(ax_mag, full, reduced)
    ph_full, ph_red = phase_pair_deg(full, reduced)
    ax_ph.semilogx(freq, ph_full, **FULL_STYLE)
    ax_ph.semilogx(freq, ph_red, **REDUCED_STYLE)
    ax_ph.set_ylabel("phase (deg)")
    ax_ph.set_xlabel("frequency (Hz)")
    for ax in (ax_mag, ax_ph):
        ax.grid(True, which="both", alpha=0.3)
    _frequency_axis(ax_ph, freq)
    fig.subplots_adjust(**BODE_MARGINS)
    return fig


def bode_pngs(freq_hz, pairs, dpi=DPI):
    """PNG bytes of bode_figure(freq_hz, full, reduced, title) for each (full, reduced, title) of pairs, in order, drawn
    on one figure whose curves, title and y-limits are replaced between pairs: the same pixels as a new figure per
    pair, without building the axes and their ticks again (most of a figure's drawing time). A pair whose response is
    identically zero gets a figure of its own (bode_figure notes it on the axes)."""
    return bode_pngs_on_grids([(freq_hz, full, reduced, title) for full, reduced, title in pairs], dpi)


def bode_pngs_on_grids(items, dpi=DPI, reuse=None):
    """bode_pngs for (freq_hz, full, reduced, title) items whose frequency grids may differ (one per configuration):
    one figure for all whose grids span the same band (the curves' frequencies replaced too), a new one where the
    band differs (its axis limits and ticks are laid out for it). The figure's fixed layer (_FixedLayer: the frequency
    axes, their grid and labels) is drawn once per band. reuse: a dict kept between calls (figures.figure_jobs: the
    two shares of one process) in which the last figure is left for the next call to draw on."""
    reuse = {} if reuse is None else reuse
    fig, span, layer = reuse.get("bode", (None, None, None))
    for freq_hz, full, reduced, title in items:
        freq = np.asarray(freq_hz, dtype=float)
        if all(not np.any(np.asarray(c) != 0) for c in (full, reduced)):
            yield figure_png_bytes(bode_figure(freq, full, reduced, title), dpi)
            continue
        this = (float(freq.min()), float(freq.max())) if freq.size else None
        if fig is None or this != span:
            fig, span = bode_figure(freq, full, reduced, title), this
            layer = _FixedLayer(fig, dpi, [ax.xaxis for ax in fig.axes])
        else:
            ax_mag, ax_ph = fig.axes
            for line, y in zip(ax_mag.lines, (magnitude_db(full), magnitude_db(reduced))):
                line.set_data(freq, y)
            for line, y in zip(ax_ph.lines, phase_pair_deg(full, reduced)):
                line.set_data(freq, y)
            _set_title(ax_mag, title)
            for ax in (ax_mag, ax_ph):
                ax.relim()
                ax.autoscale_view(scalex=False)
        reuse["bode"] = (fig, span, layer)
        yield layer.png_bytes()


class _FixedLayer:
    """A figure drawn as two layers: the fixed one (the figure's and axes' backgrounds and the artists given, e.g. a
    shared frequency axis with its grid, ticks and labels: most of a drawing's time) rendered once and kept as pixels;
    the rest (y axes, curves, spines, titles, legends) drawn over a copy of those pixels for each PNG. The PNGs are
    byte for byte what figure_png_bytes gives: the same artists drawn in the same order on the same pixels, provided
    an axes' changing artists never reach into a later axes' rectangle (true of figures whose axes do not overlap)."""

    def __init__(self, fig, dpi, fixed, after=()):
        fig.set_dpi(dpi)       # what savefig(dpi=) does for the time of its drawing
        self.fig = fig
        keep = set(map(id, fixed))
        # each axes' changing artists in its drawing order (Axes.draw: its children but the patch, by zorder)
        self.moving = [(ax, sorted((a for a in ax.get_children() if a is not ax.patch and id(a) not in keep),
                                   key=lambda a: a.get_zorder())) for ax in fig.axes]
        # the figure's own changing artists (e.g. its suptitle), which Figure.draw draws after the axes (zorder above 0)
        self.after = list(after)
        for _, artists in self.moving + [(None, self.after)]:
            for a in artists:
                a.set_animated(True)           # left out of canvas.draw(): the fixed layer alone
        fig.canvas.draw()
        self.background = fig.canvas.copy_from_bbox(fig.bbox)

    def png_bytes(self):
        canvas = self.fig.canvas
        canvas.restore_region(self.background)
        renderer = canvas.get_renderer()
        for ax, artists in self.moving:
            ax.apply_aspect()
            for a in artists:
                if a.get_visible():
                    a.draw(renderer)
        for a in self.after:
            if a.get_visible():
                a.draw(renderer)
        return _encode_png(canvas, self.fig.dpi)


# the per-configuration Bode figure's cell (one input/output pair: magnitude over phase) in inches, and its margins and
# gaps in inches (fixed, as the overview's: these fit a one-line suptitle, panel titles, tick labels of up to 5
# characters, the y labels of the left column and the legend under the cells)
PAIRS_CELL = (4.2, 3.6)
PAIRS_INCHES = dict(left=0.8, right=0.15, top=0.75, bottom=0.8, wgap=0.6, hgap=0.75)
PAIRS_MIN_WIDTH = 7.0       # a figure of one cell as wide as a Bode plot, for its suptitle
PAIRS_COLUMNS = 3


def bode_pairs_figure(freq_hz, pairs, suptitle):
    """Every input/output pair of one configuration on one figure: a cell per pair (its title), magnitude (dB) over
    phase (deg) against frequency (Hz, log axis, the same for every cell), full and reduced overlaid, one legend.

    pairs: [(full [nf], reduced [nf], title), ...] complex responses; what bode_figure draws for each pair."""
    freq = np.asarray(freq_hz, dtype=float)
    n = max(len(pairs), 1)
    ncols = min(PAIRS_COLUMNS, n)
    nrows = (n + ncols - 1) // ncols
    m = PAIRS_INCHES
    cell_w = max(PAIRS_CELL[0], (PAIRS_MIN_WIDTH - m["left"] - m["right"] - (ncols - 1) * m["wgap"]) / ncols)
    cell_h = PAIRS_CELL[1]
    width = cell_w * ncols + m["left"] + m["right"] + (ncols - 1) * m["wgap"]
    height = cell_h * nrows + m["top"] + m["bottom"] + (nrows - 1) * m["hgap"]
    fig = _new_figure(figsize=(width, height))
    for k in range(n):
        row, col = divmod(k, ncols)
        x0 = (m["left"] + col * (cell_w + m["wgap"])) / width
        top = height - m["top"] - row * (cell_h + m["hgap"])
        mag_h, gap = 0.58 * cell_h, 0.06 * cell_h
        ax_mag = fig.add_axes([x0, (top - mag_h) / height, cell_w / width, mag_h / height])
        ax_ph = fig.add_axes([x0, (top - cell_h) / height, cell_w / width, (cell_h - mag_h - gap) / height],
                             sharex=ax_mag)
        ax_mag.tick_params(labelbottom=False)
        if col == 0:        # at a fixed place (set_ylabel would place them by measuring every tick label)
            for ax, text in ((ax_mag, "magnitude (dB)"), (ax_ph, "phase (deg)")):
                box = ax.get_position()
                fig.text(0.22 / width, (box.y0 + box.y1) / 2, text, rotation=90, ha="center", va="center",
                         fontsize="small")
        if row == nrows - 1 or k + ncols >= n:
            ax_ph.set_xlabel("frequency (Hz)", fontsize="small")
        for ax in (ax_mag, ax_ph):
            ax.tick_params(labelsize="small")
            ax.grid(True, which="both", alpha=0.3)
            # four or five ticks on a cell's y axes (the y axes are drawn for every figure: most of its time)
            ax.yaxis.set_major_locator(_ticker().MaxNLocator(nbins=4, steps=[1, 2, 2.5, 5, 10]))
            # their labels are the figure's texts above: the axis's own (empty) label is not placed (matplotlib
            # places it on every drawing by measuring the tick labels of the axis and of its siblings)
            ax.yaxis._update_label_position = lambda renderer: None
        if k < len(pairs):
            full, reduced, title = pairs[k]
            _set_title(ax_mag, title, fontsize="medium")
            ax_mag.semilogx(freq, magnitude_db(full), **FULL_STYLE)
            ax_mag.semilogx(freq, magnitude_db(reduced), **REDUCED_STYLE)
            ph_full, ph_red = phase_pair_deg(full, reduced)
            ax_ph.semilogx(freq, ph_full, **FULL_STYLE)
            ax_ph.semilogx(freq, ph_red, **REDUCED_STYLE)
            _note_zero_response(ax_mag, full, reduced)
        _frequency_axis(ax_ph, freq)
        # minor ticks and grid lines at 2 and 5 only, as _frequency_axis sets them under two decades (wider, unlabelled
        # as the default ones are): the default eight per decade, on twelve axes, were most of a new figure's time
        ax_ph.xaxis.set_minor_locator(_ticker().LogLocator(base=10.0, subs=(2.0, 5.0)))
    # one legend under the cells (the same two entries for every cell), drawn once with the frequency axes
    if pairs:
        fig.legend(handles=fig.axes[0].lines, loc="lower center", bbox_to_anchor=(0.5, 0.0), ncol=2,
                   fontsize="small", frameon=False)
    fig.suptitle(suptitle, x=m["left"] / width, ha="left")
    return fig


def bode_pairs_pngs(items, dpi=DPI, reuse=None):
    """PNG bytes of bode_pairs_figure(freq_hz, pairs, suptitle) for each (freq_hz, pairs, suptitle) of items, drawn on
    one figure for all items of the same band and pair titles: their curves, y-limits and suptitle replaced, the
    fixed layer (_FixedLayer: the frequency axes, the cells' titles and y labels, the legend) drawn once. The same
    pixels as a new figure per item. An item with a pair whose response is identically zero gets a figure of its own
    (noted on its panel). reuse: as bode_pngs_on_grids'."""
    reuse = {} if reuse is None else reuse
    fig, key, layer = reuse.get("bode_pairs", (None, None, None))
    for freq_hz, pairs, suptitle in items:
        freq = np.asarray(freq_hz, dtype=float)
        if any(all(not np.any(np.asarray(c) != 0) for c in (full, red)) for full, red, _ in pairs):
            yield figure_png_bytes(bode_pairs_figure(freq, pairs, suptitle), dpi)
            continue
        this = ((float(freq.min()), float(freq.max())) if freq.size else None, tuple(t for _, _, t in pairs))
        if fig is None or this != key:
            fig, key = bode_pairs_figure(freq, pairs, suptitle), this
            layer = _FixedLayer(fig, dpi, [ax.xaxis for ax in fig.axes] + [ax.title for ax in fig.axes],
                                after=[fig._suptitle])
        else:
            axes = fig.axes
            for k, (full, reduced, _) in enumerate(pairs):
                ax_mag, ax_ph = axes[2 * k], axes[2 * k + 1]
                for line, y in zip(ax_mag.lines, (magnitude_db(full), magnitude_db(reduced))):
                    line.set_data(freq, y)
                for line, y in zip(ax_ph.lines, phase_pair_deg(full, reduced)):
                    line.set_data(freq, y)
                for ax in (ax_mag, ax_ph):
                    ax.relim()
                    ax.autoscale_view(scalex=False)
            fig.suptitle(suptitle, x=PAIRS_INCHES["left"] / fig.get_figwidth(), ha="left")
        reuse["bode_pairs"] = (fig, key, layer)
        yield layer.png_bytes()


def bode_overview_figure(panels, suptitle):
    """Magnitudes only, one panel per configuration: panels = [(title, freq_hz, full [nf], reduced [nf]), ...]."""
    n = max(len(panels), 1)
    ncols = min(3, n)
    nrows = (n + ncols - 1) // ncols
    fig = _new_figure(figsize=(4.2 * ncols, 3.2 * nrows + 0.6))
    axes = np.atleast_1d(fig.subplots(nrows, ncols, squeeze=False)).ravel()
    for ax, (title, freq, full, reduced) in zip(axes, panels):
        ax.semilogx(freq, magnitude_db(full), **FULL_STYLE)
        ax.semilogx(freq, magnitude_db(reduced), **REDUCED_STYLE)
        _set_title(ax, title, fontsize="medium")
        ax.grid(True, which="both", alpha=0.3)
        ax.set_xlabel("frequency (Hz)", fontsize="small")
        ax.set_ylabel("magnitude (dB)", fontsize="small")
        _note_zero_response(ax, full, reduced)
        _frequency_axis(ax, freq)
    for ax in axes[len(panels):]:
        ax.set_visible(False)
    if panels:
        axes[0].legend(loc="best", fontsize="x-small")
    fig.suptitle(suptitle)
    fig.subplots_adjust(**_overview_margins(ncols, nrows, *fig.get_size_inches()))
    return fig


def bode_overview_png(panels, suptitle, dpi=DPI, reuse=None):
    """PNG bytes of bode_overview_figure(panels, suptitle), drawn on the overview left in reuse (a dict, as
    bode_pngs_on_grids') when it has as many panels over the same bands: its curves, titles and y-limits replaced, its
    frequency axes' ticks (some 60 to 70 per panel on a log axis, most of a new overview's drawing time) kept. The same
    pixels as a new figure (the Bode plots' reuse, panel by panel). A panel whose response is identically zero gets a
    new figure (bode_overview_figure notes it on the axes)."""
    reuse = {} if reuse is None else reuse
    spans = [(float(np.min(freq)), float(np.max(freq))) if np.size(freq) else None for _, freq, _, _ in panels]
    fig, key = reuse.get("overview", (None, None))
    if (fig is None or key != spans
            or any(all(not np.any(np.asarray(c) != 0) for c in (full, red)) for _, _, full, red in panels)):
        fig = bode_overview_figure(panels, suptitle)
    else:
        for ax, (title, freq, full, reduced) in zip(fig.axes, panels):
            for line, y in zip(ax.lines, (magnitude_db(full), magnitude_db(reduced))):
                line.set_data(np.asarray(freq, dtype=float), y)
            _set_title(ax, title, fontsize="medium")
            ax.relim()
            ax.autoscale_view(scalex=False)
        fig.suptitle(suptitle)
    reuse["overview"] = (fig, spans)
    return figure_png_bytes(fig, dpi)


PREPARED_KINDS = ("bode_pairs", "bode", "overview", "importance")


def prepared_figures(band_hz, configurations, kinds=PREPARED_KINDS, points=449, dpi=DPI, pairs=()):
    """A reuse dict (bode_pairs_pngs, bode_pngs_on_grids, bode_overview_png, importance_pngs) holding, of kinds, a
    figure of the input/output pairs named in pairs (when given), a Bode figure, an overview of `configurations` panels
    over band_hz and an importance figure, each drawn once on placeholder data: their
    frequency axes' ticks built (the importance axis's over seven decades from the band's bottom, more than the Krylov
    modes usually span, so that their figures find their ticks made), the Bode figure's fixed layer rendered, the
    fonts loaded, before the report's data exist (report/helper.py draws them while the reduction runs). A figure
    whose band or panel count turns out different is simply made anew when used."""
    low, high = float(band_hz[0]), float(band_hz[1])
    freq = np.geomspace(low, high, points) if 0 < low < high else np.linspace(low, high, points)
    freq[0], freq[-1] = low, high                   # the spans compared when used: the band's own numbers
    corner = np.sqrt(low * high) if low > 0 else max(high, 1.0)
    curve = 1.0 / (1.0 + 1j * freq / corner)           # any response that is not zero: the curves are replaced
    reuse = {}
    if "bode_pairs" in kinds and pairs:
        for _ in bode_pairs_pngs([(freq, [(curve, 1.01 * curve, title) for title in pairs], "prepared")], dpi, reuse):
            pass
    if "bode" in kinds:
        for _ in bode_pngs_on_grids([(freq, curve, 1.01 * curve, "prepared")], dpi, reuse):
            pass
    if "overview" in kinds:
        bode_overview_png([("prepared", freq, curve, 1.01 * curve)] * max(int(configurations), 1), "prepared", dpi,
                          reuse)
    if "importance" in kinds and low > 0:
        modes = np.geomspace(low, low * 1e7, 24)
        for _ in importance_pngs([(modes, np.linspace(1.0, 0.01, modes.size), modes < high, "prepared", 0.01,
                                   [low, high])], dpi, reuse):
            pass
    return reuse


def _overview_margins(ncols, nrows, width, height):
    """subplots_adjust's fractions for OVERVIEW_INCHES on a width x height (inches) figure of nrows x ncols panels."""
    m = OVERVIEW_INCHES
    panel_w = (width - m["left"] - m["right"] - (ncols - 1) * m["wgap"]) / ncols
    panel_h = (height - m["top"] - m["bottom"] - (nrows - 1) * m["hgap"]) / nrows
    return dict(left=m["left"] / width, right=1.0 - m["right"] / width, top=1.0 - m["top"] / height,
                bottom=m["bottom"] / height, wspace=m["wgap"] / panel_w, hspace=m["hgap"] / panel_h)


def importance_figure(freq_hz, importance, kept, title, threshold=None, band_hz=None):
    """Normalized importance of each Krylov mode at its frequency; kept modes in colour, the rest in grey.

    Drawn as vertical bars on a log frequency axis (linear if a frequency is not positive), each labelled with
    its 1-based mode number so the figure can be read beside the report's importance tables.
    """
    fig = _new_figure(figsize=(7.0, 4.0))
    _draw_importance(fig.subplots(), freq_hz, importance, kept, title, threshold, band_hz)
    fig.subplots_adjust(**SINGLE_MARGINS)
    return fig


def _draw_importance(ax, freq_hz, importance, kept, title, threshold, band_hz):
    freq = np.asarray(freq_hz, dtype=float)
    imp = np.asarray(importance, dtype=float)
    kept = np.asarray(kept, dtype=bool)
    log_axis = freq.size > 0 and np.all(freq > 0)
    if log_axis:
        ax.set_xscale("log")
    if band_hz is not None and len(band_hz) == 2:
        ax.axvspan(band_hz[0], band_hz[1], color="0.92", zorder=0, label="band of interest")
    for mask, colour, label in ((kept, "tab:green", "kept"), (~kept, "0.55", "discarded")):
        if np.any(mask):
            ax.vlines(freq[mask], 0.0, imp[mask], colors=colour, linewidth=4, label=label, zorder=2)
            ax.plot(freq[mask], imp[mask], "o", color=colour, markersize=4, zorder=3)
    for number, (f, v) in enumerate(zip(freq, imp), start=1):
        ax.annotate(str(number), (f, v), textcoords="offset points", xytext=(0, 4), ha="center", fontsize=7)
    if threshold is not None:
        ax.axhline(threshold, color="tab:orange", linestyle=":", linewidth=1.2, label=f"keep threshold {threshold:g}")
    ax.set_ylim(0.0, max(1.08, float(np.max(imp)) * 1.08 if imp.size else 1.08))
    if log_axis:
        _frequency_axis(ax, freq, set_limits=False)
    ax.set_xlabel("Krylov mode frequency (Hz)")
    ax.set_ylabel("normalized importance")
    _set_title(ax, title)
    ax.grid(True, which="both", axis="x", alpha=0.3)
    ax.legend(loc="best", fontsize="small")


def importance_pngs(items, dpi=DPI, reuse=None):
    """PNG bytes of importance_figure(*item) for each item, in order, drawn on one figure whose axes are emptied and
    drawn again between items: the same pixels as a new figure per item, without building the ticks of its axes
    again (a log axis over the Krylov modes' decades has some fifty, most of a new figure's drawing time). A figure
    on a linear axis (a frequency not positive) is drawn on its own. reuse: as bode_pngs_on_grids'."""
    reuse = {} if reuse is None else reuse
    fig = reuse.get("importance")
    for item in items:
        freq = np.asarray(item[0], dtype=float)
        if not (freq.size > 0 and np.all(freq > 0)):
            yield figure_png_bytes(importance_figure(*item), dpi)
            continue
        if fig is None:
            fig = importance_figure(*item)
        else:
            ax = fig.axes[0]
            for artist in ax.lines[:] + ax.collections[:] + ax.texts[:] + ax.patches[:] + [ax.get_legend()]:
                artist.remove()
            ax.dataLim.set_points(_bbox_null())      # as a new axes': the next artists' extent alone
            ax.ignore_existing_data_limits = True
            ax.set_autoscalex_on(True)
            _draw_importance(ax, *item)
        reuse["importance"] = fig
        yield figure_png_bytes(fig, dpi)


def _bbox_null():
    from matplotlib.transforms import Bbox
    return Bbox.null().get_points()


def _worst_deviation_per_k(ratios):
    """max over I/O entries of |ratio - 1| for each k; None where every entry is undefined."""
    worst = []
    for matrix in ratios:
        values = [abs(r - 1.0) for row in matrix for r in row if r is not None]
        worst.append(max(values) if values else None)
    return worst


def moment_ratio_figure(series, threshold, title="Moment ratios L_full / L_reduced"):
    """|L_full^k / L_reduced^k - 1| (worst I/O entry) against k, one line per configuration and model.

    series: [(legend label, ratios [k][t][a] with None where undefined, dashed: bool), ...].
    A ratio of exactly 1 sits on the axis floor (RATIO_FLOOR); threshold is the exact-match tolerance line.
    """
    fig = _new_figure(figsize=(7.0, 4.4))
    ax = fig.subplots()
    markers = "osD^v<>ph*"
    for index, (label, ratios, dashed) in enumerate(series):
        worst = _worst_deviation_per_k(ratios)
        ks = [k for k, w in enumerate(worst) if w is not None]
        ys = [max(worst[k], RATIO_FLOOR) for k in ks]
        if not ks:
            continue
        ax.semilogy(ks, ys, marker=markers[index % len(markers)], linestyle="--" if dashed else "-",
                    linewidth=1.0, markersize=4, label=label)
    ax.axhline(threshold, color="k", linestyle=":", linewidth=1.0, label=f"exact-match tolerance {threshold:g}")
    ax.set_ylim(bottom=RATIO_FLOOR / 3)
    ax.xaxis.set_major_locator(_ticker().MaxNLocator(integer=True))
    ax.set_xlabel("moment index k")
    ax.set_ylabel("|L_full / L_reduced - 1|  (worst I/O entry)")
    _set_title(ax, title + f"  (floor {RATIO_FLOOR:g} = exact)", fontsize="medium")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="best", fontsize="x-small", ncol=2)
    fig.subplots_adjust(**SINGLE_MARGINS)
    return fig


def frf_error_figure(curves, accuracy, title="Relative frequency-response error of the chosen model"):
    """|Tf - Tr| / peak |Tf| (worst input/output pair, see frf_hinf_error_curve) against frequency, one curve per
    configuration: the peak of each curve is that configuration's relative H-infinity error, the verdict's measure.

    curves: [(legend label, freq_hz [nf], error [nf]), ...]; accuracy: target drawn as a horizontal line (or None).
    """
    fig = _new_figure(figsize=(7.0, 4.4))
    ax = fig.subplots()
    for label, freq, err in curves:
        err = np.asarray(err, dtype=float)
        ax.loglog(freq, np.maximum(err, RATIO_FLOOR), linewidth=1.1, label=label)
    if accuracy is not None:
        ax.axhline(accuracy, color="k", linestyle=":", linewidth=1.2, label=f"accuracy target {accuracy:g}")
    if curves:
        _frequency_axis(ax, np.concatenate([np.asarray(f, dtype=float) for _, f, _ in curves]))
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("|T_full - T_red| / max_w |T_full|  (worst pair)")
    _set_title(ax, title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="best", fontsize="x-small", ncol=2)
    fig.subplots_adjust(**SINGLE_MARGINS)
    return fig


# ----------------------------------------------------------------------------------------------- output

def figure_png_bytes(fig, dpi=DPI):
    """The figure rendered as PNG bytes (nothing written to disk): drawn at dpi on its Agg canvas (what savefig(dpi=)
    draws), then encoded by _encode_png."""
    fig.set_dpi(dpi)
    fig.canvas.draw()
    return _encode_png(fig.canvas, dpi)


def _encode_png(canvas, dpi):
    """The canvas's pixels as it holds them (not drawn again), encoded as PNG: 8-bit RGBA, every row filtered by
    PNG's "Up" filter (its difference from the row above, vectorized) and compressed by zlib at level 1. Pillow,
    which savefig uses, tries all five filters on every row (most of a figure's encoding time, 4x this one's) for
    files about 2 % smaller; the pixels are the same. The image's resolution (pHYs) and the software that drew it
    (tEXt) are recorded as matplotlib records them."""
    import matplotlib
    rgba = np.asarray(canvas.buffer_rgba())
    height, width = rgba.shape[:2]
    rows = rgba.reshape(height, width * 4)
    filtered = np.empty((height, width * 4 + 1), dtype=np.uint8)
    filtered[:, 0] = 2                          # the filter type of each row: Up
    filtered[0, 1:] = rows[0]                   # the row above the first is zero
    np.subtract(rows[1:], rows[:-1], out=filtered[1:, 1:])      # modulo 256, as PNG's filters are
    per_metre = int(dpi / 0.0254 + 0.5)
    software = "Matplotlib version%s, https://matplotlib.org/" % matplotlib.__version__

    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data))
    return b"".join((b"\x89PNG\r\n\x1a\n",
                     chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)),
                     chunk(b"pHYs", struct.pack(">IIB", per_metre, per_metre, 1)),
                     chunk(b"tEXt", b"Software\x00" + software.encode("latin-1")),
                     chunk(b"IDAT", zlib.compress(filtered.tobytes(), PNG_COMPRESS_LEVEL)),
                     chunk(b"IEND", b"")))


def save_figure(fig, path, dpi=DPI):
    """Write the figure as PNG at path atomically: rendered in memory, written under a temporary name in the
    same folder, then renamed, so a failure never leaves a truncated image at path."""
    data = figure_png_bytes(fig, dpi)
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as handle:
            handle.write(data)
    return path
