"""The certificate's mode count in a helper process beside the reduction.

The full order's count (src/reducer/certify.c) depends only on the scene, the cut and the configurations, not on the
reduction, and the reduction is single-threaded on one process: where a core is free, kryflex reduce starts a helper
that counts on it while the reduction runs, and the solve takes its counts at the count instead of factoring there.

The helper is a fresh interpreter (never a fork: this process holds MPI, PETSc and MUMPS state); it sees none of the
launcher's MPI environment (an MPI singleton of its own), loads the same scene with this process's PETSc options, and
counts by the same C code (KFReducerCertifyCountWrite, on factors of its own), writing the counts to a pipe whose read
end the solve reads with poll() (KFReducerSetCountSource). A helper that fails, dies, writes something else or is
slow leaves the solve to count in-process, as without it, with a progress line saying so. It dies with this process
(PR_SET_PDEATHSIG) and is reaped by stop(); its output and errors go to count_helper.log in the staging folder, kept in
the results only when it failed.

Started when the run is on one process, its verification plan tries the certificate, and the cores this process may
use outnumber the run's ranks (the report helpers' rule, report/helper.py). KRYFLEX_COUNT_HELPER=0 turns it off
(counted in-process); =1 starts it whatever the cores.
"""
import os
import signal
import subprocess
import sys

LOG_NAME = "count_helper.log"
# what the helper runs: an attribute, so that a test can give it a helper that fails
CHILD_CODE = "from kryflex.count_helper import main; main()"
# the launchers' variables (Open MPI, PMIx, PRRTE): the helper is an MPI singleton, not a rank of this run
MPI_PREFIXES = ("OMPI_", "PMIX_", "PRTE_", "OPAL_")
# options the helper does not take: this process's outputs, its help
DROPPED_OPTIONS = ("help", "log_view", "kf_reducer_view", "kf_model_view", "options_view", "options_left")


def wanted(ranks):
    """Whether to start the helper for a run on ranks processes (KRYFLEX_COUNT_HELPER=0/1 or the free cores)."""
    from .report.helper import _idle_cores
    if ranks != 1:
        return False
    value = os.environ.get("KRYFLEX_COUNT_HELPER", "auto").strip().lower()
    if value in ("0", "no", "false", "off"):
        return False
    if value in ("1", "yes", "true", "on"):
        return True
    return _idle_cores()[0] > ranks


def child_environment():
    """This process's environment without the MPI launcher's variables (but Open MPI's permission to run as root), with
    kryflex on the path."""
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(MPI_PREFIXES) or k.startswith("OMPI_ALLOW_RUN_AS_ROOT")}
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    env["PYTHONPATH"] = root + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    return env


def petsc_arguments():
    """This process's PETSc options as a command line (the -kf_ and -scene. options among them)."""
    from petsc4py import PETSc
    out = []
    for name, value in sorted(PETSc.Options().getAll().items()):
        if name in DROPPED_OPTIONS:
            continue
        out.append("-" + name)
        if value not in (None, ""):
            out.append(str(value))
    return out


class CountHelper:
    """The helper process counting for a reducer (set up, on one process): started at once, its pipe handed to the
    reducer; stop() ends and reaps it (a helper still counting is killed), and returns its peak resident memory (MB)."""

    def __init__(self, reducer, scene_path, folder):
        self.log = os.path.join(folder, LOG_NAME)
        self.peak_rss_mb = None
        read, write = os.pipe()
        try:
            with open(self.log, "wb") as log:
                self.proc = subprocess.Popen(
                    [sys.executable, "-c", CHILD_CODE, str(write), str(os.getpid()), os.path.abspath(scene_path)]
                    + petsc_arguments(), pass_fds=(write,), stdin=subprocess.DEVNULL, stdout=log, stderr=log,
                    env=child_environment(), start_new_session=True)   # a terminal's Ctrl-C is for the run: stop()
        except BaseException:
            os.close(read)
            raise
        finally:
            os.close(write)      # the helper's end: its exit is then the reader's end of file
        self.read = read
        reducer.handle.set_count_source(read)

    def stop(self):
        if self.proc is None:
            return self.peak_rss_mb
        # reaped here (never by Popen's poll): wait4 gives the helper's own peak memory, the factors it held
        pid, status, usage = os.wait4(self.proc.pid, os.WNOHANG)
        if pid == 0:      # still counting: the run no longer needs it
            os.kill(self.proc.pid, signal.SIGKILL)
            pid, status, usage = os.wait4(self.proc.pid, 0)
        self.proc.returncode = os.waitstatus_to_exitcode(status)
        self.peak_rss_mb = usage.ru_maxrss / 1024.0
        failed = self.proc.returncode != 0
        self.proc = None
        os.close(self.read)
        if not failed:
            try:
                os.remove(self.log)
            except OSError:
                pass
        return self.peak_rss_mb


def start(reducer, scene_path, folder, ranks):
    """The helper for the certificate's count, or None: not wanted (wanted()), no certificate planned, or it cannot
    start (counted in-process then)."""
    if not wanted(ranks) or not reducer.verification_plan()[1]:
        return None
    try:
        return CountHelper(reducer, scene_path, folder)
    except OSError:
        return None


def main():
    """The helper: argv is the pipe's write end, the parent's process id, the scene, then the parent's PETSc options.
    Exits non-zero on any failure (the parent counts itself)."""
    fd, parent, scene_path = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
    try:
        import ctypes
        ctypes.CDLL(None).prctl(1, signal.SIGKILL)     # PR_SET_PDEATHSIG: never outlive the run
    except (OSError, AttributeError):
        pass
    if os.getppid() != parent:     # the parent ended before the line above
        sys.exit(1)
    signal.signal(signal.SIGPIPE, signal.SIG_DFL)
    from . import init
    init(["kryflex-count"] + sys.argv[4:])
    from .io.scene import load_scene
    from .reducer import Reducer
    reducer = Reducer(load_scene(scene_path), quiet=True)
    reducer.count_certificate(fd)
    os.close(fd)
