"""The report's figures drawn by helper processes beside this one.

Drawing the PNGs (matplotlib's Agg) is most of the report's time and the run is single-threaded by then: where a
second core is free (the load average of the last minute at least 0.9 below the cores this process may use, and at
least two of them), helper processes draw the figures (by their indices in figures.figure_jobs) while this one
writes summary.json, report.md and the model file, and draws what the helpers' share leaves.

A helper is a fresh interpreter (not a fork: the process holds MPI, PETSc and MUMPS state that a child must not
inherit); it imports only NumPy, matplotlib and kryflex.report (no compiled kryflex code, no PETSc, no MPI), draws
one small figure to load its fonts, then waits for its work: the summary and its share on its standard input; it
writes the PNG bytes to its standard output. kryflex reduce starts its helpers when the run starts
(start_helpers), so their start-up (about half a second of a core each) overlaps the reduction instead of
delaying the report; it also tells them the scene's band and configurations, from which they build, on placeholder
data while the reduction runs, the figures that need only those (plots.prepared_figures: the frequency axes' ticks and
the Bode figure's fixed layer, most of what those figures cost when drawn first): each the Bode figure, one the
overview and the other the importance figure (PREPARED_ROLES), and the figures of those kinds go to the helper that
prepared them. write_report without them starts one when it is called, where a core is free (the load average of
the last minute at least 0.9 below the cores this process may use). A helper's figures are the very bytes this
process would draw (the same code on the same data). If a helper cannot start or fails, this process draws its
figures: the report is the same, only slower. A helper whose parent ends reads the end of its input and exits.

kryflex reduce starts its helpers whenever the cores this process may use outnumber the run's ranks, whatever the
load average: a rule on the load average made the report's time depend on the minute before the run (its own
previous run counts in it), and the helpers take little CPU that this process would not spend drawing (their start
and the prepared figures, during the reduction). KRYFLEX_REPORT_HELPER=0 turns the helpers off (every figure drawn
here); =1 starts them whatever the cores.
"""
import os
import pickle
import subprocess
import sys
import threading

from .figures import figure_jobs

# weights in figures.figure_jobs' units (about one Bode plot's drawing, 25 ms on an idle core): a helper started by
# the report itself (an interpreter importing NumPy and matplotlib, about half a second) gets that much less work;
# this process's own share of the report besides the figures (summary.json, report.md), and its import of matplotlib
# when it has not drawn a figure yet, count against it the same way
HELPER_START_WEIGHT = 20.0
MAIN_WRITE_WEIGHT = 6.0
MAIN_IMPORT_WEIGHT = 16.0
HELPER_MIN_WEIGHT = 20.0     # no helper for a lighter report: its start would cost more than it saves
HELPERS_AHEAD = 2            # helpers started ahead of the report (start_helpers)
# what each helper started ahead prepares (plots.prepared_figures' kinds), in turn: both the Bode figure of the pairs
# (each draws Bode plots), one the overview and the other the importance figures, which helper_shares then gives to it
PREPARED_ROLES = (("bode_pairs", "overview"), ("bode_pairs", "importance"))

_ahead = []                  # the helpers start_helpers started, waiting for their work


def _idle_cores():
    """(the cores this process may run on, those less the load average of the last minute: this process counts in
    it)."""
    try:
        cpus = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        cpus = os.cpu_count() or 1
    try:
        return cpus, cpus - os.getloadavg()[0]
    except OSError:
        return cpus, cpus - 1.0


def _wanted():
    """'off', 'on' (KRYFLEX_REPORT_HELPER=1: whatever the load) or 'auto'."""
    wanted = os.environ.get("KRYFLEX_REPORT_HELPER", "auto").strip().lower()
    return "off" if wanted in ("0", "no", "false", "off") else "on" if wanted in ("1", "yes", "true", "on") else "auto"


def _core_free():
    wanted = _wanted()
    if wanted != "auto":
        return wanted == "on"
    cpus, idle = _idle_cores()
    return cpus >= 2 and idle >= 0.9


def _package_root():
    return os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


class _Helper:
    """One helper process: started at once (it imports and warms up, then waits); send() gives it its share,
    result() is its [(name, bytes)], None if it failed."""

    def __init__(self, start_weight, prepare=None):
        self.start_weight = start_weight       # what its start still costs when it is given work (figures' units)
        self.prepared = set(prepare.get("kinds", ())) if prepare is not None else set()   # the kinds it prepares
        env = dict(os.environ, KRYFLEX_MUMPS="plain")
        env["PYTHONPATH"] = _package_root() + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
        self.proc = subprocess.Popen([sys.executable, "-c", "from kryflex.report.helper import main; main()"],
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                                     env=env, start_new_session=True)   # a terminal's Ctrl-C is for the run: it
                                                                         # stops the helper (stop() below)
        self.writer = None
        if prepare is not None:
            # a few hundred bytes: the pipe takes them at once, the helper reads them after its warm-up
            try:
                self.proc.stdin.write(pickle.dumps(("prepare", prepare), protocol=pickle.HIGHEST_PROTOCOL))
                self.proc.stdin.flush()
            except OSError:     # the helper died: result() says so
                pass

    def send(self, data):
        # written by a thread: the pipe holds less than the summary, and the helper reads it only once started
        self.writer = threading.Thread(target=self._write, args=(data,), daemon=True)
        self.writer.start()

    def _write(self, data):
        try:
            self.proc.stdin.write(data)
            self.proc.stdin.close()
        except OSError:       # the helper died: result() says so
            pass

    def result(self):
        try:
            out = self.proc.stdout.read()
        except OSError:
            return None
        if self.writer is not None:
            self.writer.join()
        if self.proc.wait() != 0:
            return None
        try:
            return pickle.loads(out)
        except Exception:  # noqa: BLE001 - a truncated or foreign output: the figures are drawn here instead
            return None

    def stop(self):
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()
        for pipe in (self.proc.stdin, self.proc.stdout):
            try:
                pipe.close()
            except OSError:
                pass


def start_helpers(ranks=1, prepare=None):
    """Start the report's helpers now (kryflex reduce, as the run starts), when the cores this process may use
    outnumber the run's ranks (or KRYFLEX_REPORT_HELPER=1): they load NumPy and matplotlib while the reduction runs
    and wait for the figures. prepare: {"band_hz": [low, high], "configurations": n, "pairs": [pair names]}, the
    scene's, from which each helper prepares its figures of PREPARED_ROLES meanwhile (plots.prepared_figures; without
    pairs, the report's Bode plots are a figure per pair: the Bode figure instead of the pairs' figure). Returns how
    many were started."""
    stop_helpers()
    wanted = _wanted()
    if wanted == "on" or (wanted == "auto" and _idle_cores()[0] > ranks):
        for k in range(HELPERS_AHEAD):
            role = PREPARED_ROLES[k % len(PREPARED_ROLES)]
            if prepare is not None and not prepare.get("pairs"):
                role = tuple("bode" if kind == "bode_pairs" else kind for kind in role)
            spec = None if prepare is None else dict(prepare, kinds=role)
            try:
                _ahead.append(_Helper(start_weight=0.0, prepare=spec))
            except OSError:
                break
    return len(_ahead)


def stop_helpers():
    """Stop the helpers start_helpers started and no report took (a run that failed or wrote no figures)."""
    while _ahead:
        _ahead.pop().stop()


def _take_helpers():
    """The helpers started ahead, else one started now where a core is free."""
    if _ahead:
        taken, dead = [h for h in _ahead if h.proc.poll() is None], [h for h in _ahead if h.proc.poll() is not None]
        _ahead.clear()
        for h in dead:
            h.stop()
        return taken
    if _wanted() != "off" and _core_free():
        try:
            return [_Helper(start_weight=HELPER_START_WEIGHT)]
        except OSError:
            return []
    return []


def helper_shares(jobs, helpers):
    """The indices of the jobs each helper draws ([set] per helper; the rest are this process's): the heaviest jobs
    first to whichever process has the least so far, this process starting with its writing (and its import of
    matplotlib when it has drawn nothing yet), each helper with what its start still costs; a job of a kind some
    helpers prepared (their prepared set, start_helpers) to the least loaded of those. With a helper per core this
    process draws nothing (it writes the rest meanwhile). No helper for a report lighter than HELPER_MIN_WEIGHT."""
    total = sum(w for w, _, _ in jobs)
    if not helpers or total < HELPER_MIN_WEIGHT:
        return [set() for _ in helpers]
    if len(helpers) >= _idle_cores()[0]:
        loads = [float("inf")]
    else:
        loads = [MAIN_WRITE_WEIGHT + (0.0 if "matplotlib.backends.backend_agg" in sys.modules else MAIN_IMPORT_WEIGHT)]
    loads += [h.start_weight for h in helpers]
    shares = [set() for _ in helpers]
    for k in sorted(range(len(jobs)), key=lambda k: -jobs[k][0]):
        ready = [p + 1 for p, h in enumerate(helpers) if jobs[k][2] in getattr(h, "prepared", ())]
        who = min(ready or range(len(loads)), key=lambda p: (loads[p], -p))      # a tie to a helper
        loads[who] += jobs[k][0]
        if who:
            shares[who - 1].add(k)
    return shares


class PlotRendering:
    """The report's figures being drawn: started (start()) with the helpers' shares sent to them, so that they draw
    while this process writes the rest; items() then yields every (file name, PNG bytes), this process's share drawn
    as it goes (between() after each), then the helpers' (a failed helper's drawn here)."""

    def __init__(self, summary, plot_names):
        self.summary, self.plot_names = summary, plot_names
        self.jobs = figure_jobs(summary, plot_names)
        self.helpers, self.shares = [], []

    def start(self):
        helpers = _take_helpers()
        shares = helper_shares(self.jobs, helpers)
        data = None
        for h, share in zip(helpers, shares):
            if not share:
                h.stop()
                continue
            if data is None:
                data = pickle.dumps((self.summary, self.plot_names), protocol=pickle.HIGHEST_PROTOCOL)
            h.send(pickle.dumps(sorted(share), protocol=pickle.HIGHEST_PROTOCOL) + data)
            self.helpers.append(h)
            self.shares.append(share)
        return self

    def _draw(self, indices, between):
        for k in indices:
            for item in self.jobs[k][1]():
                yield item
                if between is not None:
                    between()

    def items(self, between=None):
        theirs = set().union(*self.shares) if self.shares else set()
        try:
            yield from self._draw([k for k in range(len(self.jobs)) if k not in theirs], between)
            for h, share in zip(self.helpers, self.shares):
                got = h.result()
                if got is None:
                    yield from self._draw(sorted(share), between)
                    continue
                yield from got
                if between is not None:
                    between()
        finally:
            self.stop()

    def stop(self):
        for h in self.helpers:
            h.stop()
        self.helpers = []


def render_plots(summary, plot_names, between=None):
    """Yield (file name, PNG bytes) of every figure of the report, as figures._render_plots, shares of them drawn by
    helper processes where a core is free. between() is called after each figure drawn here (the command stops there
    when it was interrupted; the helpers are then stopped)."""
    yield from PlotRendering(summary, plot_names).start().items(between)


def _warm_up():
    """Load matplotlib's Agg canvas and its font (the first text drawn reads it) before any work arrives."""
    from . import plots
    fig = plots._new_figure(figsize=(1.0, 1.0))
    ax = fig.subplots()
    ax.set_xscale("log")
    ax.set_title("0")
    fig.canvas.draw()


def _prepared(spec):
    """plots.prepared_figures for the spec start_helpers sent, None if it cannot be used (the figures are then made
    when drawn, as without it)."""
    from . import plots
    try:
        return plots.prepared_figures(spec["band_hz"], spec["configurations"], spec.get("kinds", plots.PREPARED_KINDS),
                                      pairs=spec.get("pairs", ()))
    except Exception:  # noqa: BLE001 - a preparation only: the figures are drawn the same without it
        return None


def main():
    """The helper: loads what it draws with, then reads on standard input, pickled: optionally ("prepare", spec) (the
    figures it prepares before its work), its job indices and (summary, plot names); writes [(name, PNG bytes)]
    pickled on standard output."""
    _warm_up()
    prepared = None
    try:
        share = pickle.load(sys.stdin.buffer)
        if isinstance(share, tuple) and share and share[0] == "prepare":
            prepared = _prepared(share[1])
            share = pickle.load(sys.stdin.buffer)
        summary, plot_names = pickle.load(sys.stdin.buffer)
    except EOFError:         # the run ended (failed, or drew no figures) before sending work
        sys.exit(0)
    jobs = figure_jobs(summary, plot_names, prepared)
    out = [item for k in share for item in jobs[k][1]()]
    sys.stdout.buffer.write(pickle.dumps(out, protocol=pickle.HIGHEST_PROTOCOL))
    sys.stdout.buffer.flush()
