"""The report's figures drawn by two processes: this one and a helper Python started for them.

Drawing the PNGs (matplotlib's Agg) is most of the report's time, about 0.1 s of one core per figure, and the run
is single-threaded by then: where a second core is free (the load average of the last minute at least 0.9 below the
cores this process may use), a helper process draws part of the figures (by
their indices in figures.figure_jobs) while this one draws the rest. The helper is a fresh interpreter (not a fork:
the process holds MPI, PETSc and MUMPS state that a child must not inherit); it imports only NumPy, matplotlib and
kryflex.report (no compiled kryflex code, no PETSc, no MPI), reads the summary from its standard input and writes the
PNG bytes to its standard output. Its figures are the very bytes this process would draw (the same code on the same
data). If it cannot start or fails, this process draws its figures too: the report is the same, only slower.

KRYFLEX_REPORT_HELPER=0 turns the helper off (every figure drawn here); =1 starts it whatever the load.
"""
import os
import pickle
import subprocess
import sys
import threading

from .figures import figure_jobs

# the helper's start (an interpreter importing NumPy and matplotlib, about 0.5 s of a core), in Bode-plot units: it
# gets that much less work, and no helper is started for a report lighter than HELPER_MIN_WEIGHT
HELPER_START_WEIGHT = 5.0
HELPER_MIN_WEIGHT = 12.0


def _idle_cores():
    """The cores this process may run on less the load average of the last minute (this process counts in it)."""
    try:
        cpus = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        cpus = os.cpu_count() or 1
    try:
        return cpus - os.getloadavg()[0]
    except OSError:
        return cpus - 1.0


def helper_share(jobs):
    """The indices of the jobs the helper draws (an empty set: no helper), about half the weight less its start-up:
    the heaviest jobs first to whichever side is lighter."""
    wanted = os.environ.get("KRYFLEX_REPORT_HELPER", "auto").strip().lower()
    if wanted in ("0", "no", "false", "off"):
        return set()
    total = sum(w for w, _ in jobs)
    if total < HELPER_MIN_WEIGHT or (wanted != "1" and _idle_cores() < 0.9):   # no core free: only its start added
        return set()
    here, there, share = 0.0, HELPER_START_WEIGHT, set()
    for k in sorted(range(len(jobs)), key=lambda k: -jobs[k][0]):
        if there < here:
            share.add(k)
            there += jobs[k][0]
        else:
            here += jobs[k][0]
    return share


def _package_root():
    return os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


class _Helper:
    """The helper process drawing the jobs of share; result() is its [(name, bytes)], None if it failed."""

    def __init__(self, summary, plot_names, share):
        env = dict(os.environ, KRYFLEX_MUMPS="plain")
        env["PYTHONPATH"] = _package_root() + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
        self.proc = subprocess.Popen([sys.executable, "-c", "from kryflex.report.helper import main; main()"],
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                                     env=env, start_new_session=True)   # a terminal's Ctrl-C is for the run: it
                                                                         # stops the helper (stop() below)
        data = pickle.dumps((summary, plot_names, sorted(share)), protocol=pickle.HIGHEST_PROTOCOL)
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
        self.proc.stdout.close()


def render_plots(summary, plot_names, between=None):
    """Yield (file name, PNG bytes) of every figure of the report, as figures._render_plots, a share of them drawn by
    a helper process where a second core is free. between() is called after each figure drawn here (the command
    stops there when it was interrupted; the helper is then stopped)."""
    jobs = figure_jobs(summary, plot_names)
    share = helper_share(jobs)
    helper = None
    if share:
        try:
            helper = _Helper(summary, plot_names, share)
        except OSError:
            share = set()
    try:
        for k, (_, job) in enumerate(jobs):
            if k in share:
                continue
            for item in job():
                yield item
                if between is not None:
                    between()
        got = helper.result() if helper is not None else None
        if got is not None:
            yield from got
            return
        for k in sorted(share):         # the helper failed: its figures drawn here
            for item in jobs[k][1]():
                yield item
                if between is not None:
                    between()
    finally:
        if helper is not None:
            helper.stop()


def main():
    """The helper: (summary, plot names, job indices) pickled on standard input; [(name, PNG bytes)] pickled on
    standard output."""
    summary, plot_names, share = pickle.load(sys.stdin.buffer)
    jobs = figure_jobs(summary, plot_names)
    out = [item for k in share for item in jobs[k][1]()]
    sys.stdout.buffer.write(pickle.dumps(out, protocol=pickle.HIGHEST_PROTOCOL))
    sys.stdout.buffer.flush()
