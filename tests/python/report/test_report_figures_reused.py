"""The report's Bode plots drawn on one reused figure (plots.bode_pngs) are the very PNGs a new figure per pair gives
(plots.bode_figure): the speed-up changes no pixel. Responses of a small damped modal model computed here, with a
pair identically zero and pairs whose magnitudes differ by decades (the y-limits must follow)."""
import numpy as np
import pytest

from kryflex.report import plots


def responses():
    f = np.geomspace(0.1, 30.0, 300)
    w = 2 * np.pi * f
    fn = np.array([0.8, 3.1, 7.7, 19.0])
    rng = np.random.default_rng(4)
    out = []
    for scale in (1.0, 1e-4, 1e3):
        r = scale * rng.standard_normal(fn.size)
        full = sum(ri / ((2 * np.pi * fi) ** 2 - w ** 2 + 2j * 0.01 * 2 * np.pi * fi * w) for ri, fi in zip(r, fn))
        out.append((full, full * (1 + 1e-3 * rng.standard_normal()), "pair %g" % scale))
    out.insert(1, (np.zeros_like(f, dtype=complex), np.zeros_like(f, dtype=complex), "zero pair"))
    return f, out


def test_reused_figure_gives_the_same_pngs():
    f, pairs = responses()
    reused = list(plots.bode_pngs(f, pairs))
    fresh = [plots.figure_png_bytes(plots.bode_figure(f, full, red, title)) for full, red, title in pairs]
    assert len(reused) == len(pairs)
    assert [a == b for a, b in zip(reused, fresh)] == [True] * len(pairs)
    assert len(set(fresh)) == len(fresh)     # the pairs' plots do differ: the comparison is not vacuous


def test_one_figure_across_frequency_grids_gives_the_same_pngs():
    """Configurations' grids differ (points across each one's resonances) but span the same band: one figure serves
    them all, its curves' frequencies replaced; a grid over another band gets a figure of its own."""
    f, pairs = responses()
    g = np.sort(np.concatenate([f[::2], [0.79, 0.81, 3.09, 3.11]]))      # the same band, other points
    h = np.geomspace(0.5, 12.0, 200)                                        # another band
    items = [(f, full, red, title) for full, red, title in pairs]
    items += [(g, np.interp(g, f, full.real) + 1j * np.interp(g, f, full.imag),
               np.interp(g, f, red.real) + 1j * np.interp(g, f, red.imag), "g " + title) for full, red, title in pairs]
    items += [(h, np.interp(h, f, full.real) + 0j, np.interp(h, f, red.real) + 0j, "h " + title)
              for full, red, title in pairs[:2]]
    reused = list(plots.bode_pngs_on_grids(items))
    fresh = [plots.figure_png_bytes(plots.bode_figure(*item)) for item in items]
    assert len(reused) == len(items)
    assert [a == b for a, b in zip(reused, fresh)] == [True] * len(items)
    assert len(set(fresh)) == len(fresh)


def test_png_encoding_keeps_savefigs_pixels():
    """plots' own PNG encoder (one PNG filter, zlib) gives the pixels and resolution matplotlib's savefig (Pillow)
    gives for the same figure, on every kind of the report's figures."""
    import io

    from PIL import Image

    f, pairs = responses()
    full, red, title = pairs[0]
    figures = [lambda: plots.bode_figure(f, full, red, title),
               lambda: plots.bode_overview_figure([("a", f, full, red), ("b", f, red, full)], "overview"),
               lambda: plots.importance_figure([0.5, 3.1, 40.0], [1.0, 0.2, 1e-3], [True, True, False], "importance",
                                               threshold=0.01, band_hz=[0.1, 30.0]),
               lambda: plots.frf_error_figure([("a", f, plots.frf_hinf_error_curve(full, red))], 0.05)]
    for make in figures:
        ours = Image.open(io.BytesIO(plots.figure_png_bytes(make())))
        buffer = io.BytesIO()
        make().savefig(buffer, format="png", dpi=plots.DPI)
        theirs = Image.open(io.BytesIO(buffer.getvalue()))
        assert ours.mode == theirs.mode == "RGBA" and ours.size == theirs.size
        assert np.array_equal(np.asarray(ours), np.asarray(theirs))
        assert np.allclose(ours.info["dpi"], theirs.info["dpi"]) and ours.info["Software"] == theirs.info["Software"]


def test_reused_importance_figure_gives_the_same_pngs():
    """The importance figures of several configurations drawn on one figure (plots.importance_pngs) are the PNGs a new
    figure per configuration gives: modes over other decades (the x limits follow), with and without a threshold,
    none kept, and one on a linear axis (a zero frequency) in between."""
    items = [([0.05, 0.9, 3.0, 45.0, 700.0], [1.0, 0.3, 0.02, 1e-4, 0.5], [True, True, False, False, True],
              "first", 0.01, [0.1, 30.0]),
             ([2.0, 8.0, 3000.0], [0.2, 1.0, 0.9], [False, True, True], "second", None, [1.0, 10.0]),
             ([0.0, 2.0, 5.0], [1.0, 0.5, 0.1], [True, False, False], "linear", 0.01, None),
             ([0.3, 0.4], [0.7, 1.2], [False, False], "none kept", 0.5, [0.2, 0.5])]
    reused = list(plots.importance_pngs(items))
    fresh = [plots.figure_png_bytes(plots.importance_figure(*item)) for item in items]
    assert len(reused) == len(items)
    assert [a == b for a, b in zip(reused, fresh)] == [True] * len(items)
    assert len(set(fresh)) == len(fresh)


def test_figures_reused_across_calls_give_the_same_pngs():
    """figures.figure_jobs draws a process's two shares of Bode and importance figures on the figure the first share
    left (reuse=): the PNGs are those of a new figure per plot."""
    f, pairs = responses()
    items = [(f, full, red, title) for full, red, title in pairs]
    kept = {}
    reused = list(plots.bode_pngs_on_grids(items[:2], reuse=kept)) + list(plots.bode_pngs_on_grids(items[2:], reuse=kept))
    assert "bode" in kept
    fresh = [plots.figure_png_bytes(plots.bode_figure(*item)) for item in items]
    assert [a == b for a, b in zip(reused, fresh)] == [True] * len(items)
    imp = [([0.05, 0.9, 3.0, 45.0], [1.0, 0.3, 0.02, 1e-4], [True, True, False, False], "first", 0.01, [0.1, 30.0]),
           ([2.0, 8.0, 3000.0], [0.2, 1.0, 0.9], [False, True, True], "second", None, [1.0, 10.0])]
    kept = {}
    reused = list(plots.importance_pngs(imp[:1], reuse=kept)) + list(plots.importance_pngs(imp[1:], reuse=kept))
    assert "importance" in kept
    fresh = [plots.figure_png_bytes(plots.importance_figure(*item)) for item in imp]
    assert [a == b for a, b in zip(reused, fresh)] == [True] * len(imp)


@pytest.mark.parametrize("npanels", [1, 2, 4, 7])
def test_overview_margins_hold_its_labels(npanels):
    """The overview's fixed margins (no tight_layout) keep every panel's tick labels, axis labels and title inside the
    figure and clear of the other panels and of the suptitle, with five-character tick labels (-1000 dB)."""
    f, pairs = responses()
    full = pairs[0][0] * 1e-50 / np.abs(pairs[0][0]).max()          # magnitudes down to about -1000 dB
    panels = [("%d°" % (30 * k), f, full, full * 1.01) for k in range(npanels)]
    fig = plots.bode_overview_figure(panels, "a scene's name: full vs reduced (single-angle model), out <- in")
    fig.set_dpi(plots.DPI)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    page = fig.bbox
    boxes = [ax.get_tightbbox(renderer) for ax in fig.axes if ax.get_visible()]
    title = fig._suptitle.get_window_extent(renderer)
    assert len(boxes) == npanels
    assert any(len(t.get_text()) >= 5 for t in fig.axes[0].get_yticklabels())    # the widest labels are drawn
    for k, box in enumerate(boxes):
        assert page.x0 <= box.x0 and box.x1 <= page.x1 and page.y0 <= box.y0 and box.y1 <= page.y1
        assert not box.overlaps(title)
        assert not any(box.overlaps(other) for other in boxes[k + 1:])


def test_prepared_figures_give_the_same_pngs():
    """The Bode figure, the overview and the importance figure a helper prepares on placeholder data before the
    report's data exist (plots.prepared_figures) draw the PNGs of a new figure per plot: the prepared band and panel
    count used, a band or a panel count that differs (a new figure then), an overview with a panel identically zero,
    importance figures over fewer and more decades than prepared."""
    f, pairs = responses()
    band = (float(f[0]), float(f[-1]))
    items = [(f, full, red, title) for full, red, title in pairs]
    prepared = plots.prepared_figures(band, 3)
    assert set(prepared) == {"bode", "overview", "importance"}
    reused = list(plots.bode_pngs_on_grids(items, reuse=prepared))
    fresh = [plots.figure_png_bytes(plots.bode_figure(*item)) for item in items]
    assert [a == b for a, b in zip(reused, fresh)] == [True] * len(items)
    live = [p for p in pairs if np.any(p[0] != 0)]
    overviews = []
    for panels in ([("%d deg" % (30 * k), f, full, red) for k, (full, red, _) in enumerate(live)],   # as prepared
                   [("one", f, live[0][0], live[0][1])],                                             # fewer panels
                   [("g", f[20:], live[0][0][20:], live[0][1][20:])] * 3,                            # another band
                   [("%d" % k, f, full, red) for k, (full, red, _) in enumerate(pairs[:3])]):       # a zero panel
        ours = plots.bode_overview_png(panels, "overview: full vs reduced", reuse=prepared)
        assert ours == plots.figure_png_bytes(plots.bode_overview_figure(panels, "overview: full vs reduced"))
        overviews.append(ours)
    assert len(set(overviews)) == len(overviews)       # the comparisons are not vacuous
    imp = [([0.05, 0.9, 3.0, 45.0, 700.0], [1.0, 0.3, 0.02, 1e-4, 0.5], [True, True, False, False, True], "a", 0.01,
            [0.1, 30.0]),
           (list(np.geomspace(0.2, 4e5, 30)), list(np.linspace(1.0, 0.0, 30)), [True] * 10 + [False] * 20, "b", None,
            [0.1, 30.0])]
    reused = list(plots.importance_pngs(imp, reuse=prepared))
    fresh = [plots.figure_png_bytes(plots.importance_figure(*item)) for item in imp]
    assert [a == b for a, b in zip(reused, fresh)] == [True] * len(imp)


def pair_items():
    """Two configurations' pairs over one band (their curves' grids differ), one over another band, one with a pair
    identically zero: what plots.bode_pairs_pngs draws."""
    f, pairs = responses()
    live = [p for p in pairs if np.any(p[0] != 0)]
    g = np.sort(np.concatenate([f[::2], [0.79, 0.81, 3.09, 3.11]]))      # the same band, other points
    h = np.geomspace(0.5, 12.0, 200)                                        # another band

    def on(grid, responses_):
        return [(np.interp(grid, f, a.real) + 1j * np.interp(grid, f, a.imag),
                 np.interp(grid, f, b.real) + 1j * np.interp(grid, f, b.imag), title) for a, b, title in responses_]
    return [(f, live, "0°: full vs reduced"), (g, on(g, live[::-1]), "30°: full vs reduced"),
            (h, on(h, live), "60°: full vs reduced"), (f, pairs, "90°: full vs reduced")]


def test_reused_pairs_figure_gives_the_same_pngs():
    """The figures of every input/output pair of a configuration drawn on one figure (plots.bode_pairs_pngs: its
    frequency axes, cells' titles and legend drawn once) are the PNGs a new figure per configuration gives, across
    calls sharing it (reuse=), pairs in another order, another band and a pair identically zero."""
    items = pair_items()
    kept = {}
    reused = list(plots.bode_pairs_pngs(items[:1], reuse=kept)) + list(plots.bode_pairs_pngs(items[1:], reuse=kept))
    assert "bode_pairs" in kept
    fresh = [plots.figure_png_bytes(plots.bode_pairs_figure(*item)) for item in items]
    assert [a == b for a, b in zip(reused, fresh)] == [True] * len(items)
    assert len(set(fresh)) == len(fresh)


def test_prepared_pairs_figure_gives_the_same_pngs():
    """The pairs' figure a helper prepares from the scene's band and pair names (plots.prepared_figures) draws the
    PNGs of a new figure: for those pairs, and for others (a new figure then)."""
    items = pair_items()
    f = items[0][0]
    prepared = plots.prepared_figures((float(f[0]), float(f[-1])), 4, kinds=("bode_pairs",),
                                      pairs=[title for _, _, title in items[0][1]])
    assert set(prepared) == {"bode_pairs"}
    reused = list(plots.bode_pairs_pngs(items, reuse=prepared))
    fresh = [plots.figure_png_bytes(plots.bode_pairs_figure(*item)) for item in items]
    assert [a == b for a, b in zip(reused, fresh)] == [True] * len(items)


def test_pairs_figure_draws_what_the_figure_per_pair_draws():
    """Each cell of the pairs' figure holds the curves of that pair's own Bode figure (plots.bode_figure): the same
    frequencies, magnitudes and phases, full and reduced, the same axis limits and the pair's title."""
    f, pairs, _ = pair_items()[3]
    fig = plots.bode_pairs_figure(f, pairs, "every pair")
    assert len(fig.axes) == 2 * len(pairs)
    for k, (full, red, title) in enumerate(pairs):
        single = plots.bode_figure(f, full, red, title)
        for ours, theirs in zip(fig.axes[2 * k:2 * k + 2], single.axes):
            assert len(ours.lines) == len(theirs.lines) == 2
            for a, b in zip(ours.lines, theirs.lines):
                assert np.array_equal(a.get_xdata(), b.get_xdata())
                assert np.array_equal(a.get_ydata(), b.get_ydata(), equal_nan=True)
                assert (a.get_color(), a.get_linestyle(), a.get_label()) == (b.get_color(), b.get_linestyle(),
                                                                            b.get_label())
            assert ours.get_xlim() == theirs.get_xlim()
        assert fig.axes[2 * k].get_title() == title
    assert [t.get_text() for t in fig.legends[0].get_texts()] == ["full order", "reduced (Krylov)"]


@pytest.mark.parametrize("npairs", [1, 2, 4, 6, 12])
def test_pairs_figure_margins_hold_its_labels(npairs):
    """The pairs' figure's fixed margins keep every cell's tick labels and title inside the figure and clear of the
    other cells, of the y labels, the suptitle and the legend, with five-character tick labels (-1000 dB)."""
    f, pairs = responses()
    full = pairs[0][0] * 1e-50 / np.abs(pairs[0][0]).max()          # magnitudes down to about -1000 dB
    fig = plots.bode_pairs_figure(f, [(full, full * 1.01, "output%d ← input" % k) for k in range(npairs)],
                                  "a scene's name: full vs reduced (single-angle model)")
    fig.set_dpi(plots.DPI)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    page = fig.bbox
    boxes = [ax.get_tightbbox(renderer) for ax in fig.axes]
    cells = [boxes[k].union([boxes[k], boxes[k + 1]]) for k in range(0, 2 * npairs, 2)]
    others = [fig._suptitle.get_window_extent(renderer), fig.legends[0].get_window_extent(renderer)]
    labels = [t for t in fig.texts if t is not fig._suptitle]
    others += [t.get_window_extent(renderer) for t in labels]
    assert len(labels) == 2 * ((npairs + 2) // 3)      # the y labels of the left column's cells
    assert page.x0 <= others[0].x0 and others[0].x1 <= page.x1 and others[1].x1 <= page.x1
    assert any(len(t.get_text()) >= 5 for t in fig.axes[0].get_yticklabels())    # the widest labels are drawn
    for k, box in enumerate(cells):
        assert page.x0 <= box.x0 and box.x1 <= page.x1 and page.y0 <= box.y0 and box.y1 <= page.y1
        assert not any(box.overlaps(other) for other in others + cells[k + 1:])
    assert not others[0].overlaps(others[1])
