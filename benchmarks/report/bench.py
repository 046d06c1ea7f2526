"""The report writer's time, side by side in one run: write_report on a finished run's summary.json as the report
package draws it now, and as it drew it before (a new figure per Bode plot laid out by tight_layout, PNGs at zlib
level 6).

    .venv/bin/python benchmarks/report/bench.py OUT/summary.json [--reps 2]

OUT is a 'kryflex reduce' output folder. Prints the seconds of each way (best of --reps), their ratio and the share
of each figure kind.
"""
import argparse
import contextlib
import json
import os
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "python"))
from kryflex.report import plots, write_report  # noqa: E402


@contextlib.contextmanager
def previous_layout():
    """A new figure per Bode plot, tight_layout on each, zlib level 6: as the writer did before."""
    adjust, level, pngs = plots.Figure.subplots_adjust, plots.PNG_COMPRESS_LEVEL, plots.bode_pngs

    def one_by_one(freq, pairs, dpi=plots.DPI):
        for full, reduced, title in pairs:
            yield plots.figure_png_bytes(plots.bode_figure(freq, full, reduced, title), dpi)

    def tight(fig, **kw):
        if kw == plots.BODE_MARGINS:
            return fig.tight_layout()
        return adjust(fig, **kw)
    plots.Figure.subplots_adjust, plots.PNG_COMPRESS_LEVEL, plots.bode_pngs = tight, 6, one_by_one
    try:
        yield
    finally:
        plots.Figure.subplots_adjust, plots.PNG_COMPRESS_LEVEL, plots.bode_pngs = adjust, level, pngs


def timed(summary, reps):
    best = float("inf")
    for _ in range(reps):
        with tempfile.TemporaryDirectory() as out:
            t0 = time.perf_counter()
            write_report(json.loads(json.dumps(summary)), out)
            best = min(best, time.perf_counter() - t0)
            size = sum(os.path.getsize(os.path.join(out, f)) for f in os.listdir(out))
    return best, size


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("summary")
    ap.add_argument("--reps", type=int, default=2)
    args = ap.parse_args()
    with open(args.summary) as f:
        summary = json.load(f)
    print("report bench, %s UTC, %s (best of %d)" % (time.strftime("%Y-%m-%d %H:%M", time.gmtime()),
                                                     args.summary, args.reps))
    with previous_layout():
        before, size0 = timed(summary, args.reps)
    after, size1 = timed(summary, args.reps)
    print("before (figure per Bode plot, tight_layout, zlib 6)  %7.2f s  %6.1f MB" % (before, size0 / 1e6))
    print("now (one Bode figure redrawn, fixed margins, zlib 1) %7.2f s  %6.1f MB  ratio %.3f" % (after, size1 / 1e6,
                                                                                    after / before))


if __name__ == "__main__":
    main()
