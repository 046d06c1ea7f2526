"""PETSc and SLEPc start-up: on first use, or from kryflex.init(argv) with a command line's options.

Importing kryflex starts nothing; the binding calls init() when it is first imported. Signals stay Python's:
PETSc's handler would replace Python's dispositions (SIGPIPE, SIGINT...) and turn a stray signal from a child process
into an exit with PETSc's signal error instead of a KeyboardInterrupt or nothing at all.

At exit, Python's cyclic garbage is collected before petsc4py cleans up and finalizes PETSc: a kryflex object kept
alive by a reference cycle on one rank only (a frame held by a plotting library, say) would otherwise still live on
that rank when PETSc's collective clean-up runs on the others, and the ranks would wait for each other forever.
"""
import atexit
import contextlib
import ctypes
import gc
import os
import sys

_started = False
_collect_registered = False
_mpi_defaults_added = []

# A process started alone (not by mpirun) is an MPI singleton. Open MPI's defaults cost it about half a second of
# wall before PETSc starts, without CPU: it starts a daemon (orted) to support MPI_Comm_spawn, which kryflex never
# calls, and selecting the point-to-point layer loads the Omni-Path library, whose constructor polls for adapters in
# short sleeps. One process exchanges no messages, so neither is of use; under mpirun the launcher's settings stand.
# Variables already set win (OMPI_MCA_ess_singleton_isolated=0 for a program that spawns processes).
MPI_SINGLETON_DEFAULTS = {"OMPI_MCA_pml": "ob1", "OMPI_MCA_ess_singleton_isolated": "1"}
# what Open MPI's, MPICH's and PMIx launchers set in the processes they start
MPI_LAUNCHED = ("OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE")

# Debian's MUMPS with SCOTCH and PT-SCOTCH orderings (package libmumps-ptscotch-5.5, installed by scripts/setup): the
# same MUMPS 5.5.1 as the plain build PETSc links, with nested dissection compiled in. Loaded into the process's
# global scope before PETSc, PETSc's calls to MUMPS bind to it, and MUMPS' own choice of ordering takes SCOTCH for large
# matrices (docs/guide/large-models.md, "Nested dissection"). KRYFLEX_MUMPS=plain keeps the build PETSc links.
MUMPS_WITH_ORDERINGS = "libdmumps_ptscotch-5.5.so"


def load_mumps_with_orderings():
    """Makes the SCOTCH build of MUMPS the one PETSc calls, if it is installed and PETSc is not loaded yet (a process
    that imported petsc4py first keeps the plain build: the factorizations then take MUMPS' own orderings)."""
    if os.environ.get("KRYFLEX_MUMPS") == "plain" or "petsc4py.PETSc" in sys.modules:
        return False
    try:
        ctypes.CDLL(MUMPS_WITH_ORDERINGS, mode=ctypes.RTLD_GLOBAL)
    except OSError:
        return False
    return True


def mpi_singleton_defaults():
    """Sets MPI_SINGLETON_DEFAULTS in the environment where MPI will start as a singleton, until init() has started
    it (they are then taken out again: a program kryflex's process starts, mpirun among them, does not inherit them)."""
    if "petsc4py.PETSc" in sys.modules or "mpi4py.MPI" in sys.modules or any(v in os.environ for v in MPI_LAUNCHED):
        return
    for name, value in MPI_SINGLETON_DEFAULTS.items():
        if name not in os.environ:
            os.environ[name] = value
            _mpi_defaults_added.append(name)


def _drop_mpi_defaults():
    """MPI has started and read them: out of the environment again."""
    while _mpi_defaults_added:
        os.environ.pop(_mpi_defaults_added.pop(), None)


def init(argv=None):
    """Initializes PETSc and SLEPc. argv: a command line (program name, then options such as -kf_moments 12 or
    -log_view); None: no options. Only the first call starts PETSc; when PETSc is already running (started by
    petsc4py or an earlier call), argv's options are added to its options database instead."""
    global _started
    options = [str(a) for a in (argv or [])[1:]]
    if _started or "petsc4py.PETSc" in sys.modules:
        _started = True
        _drop_mpi_defaults()
        _keep_python_signals()
        _collect_at_exit()
        if options:
            from petsc4py import PETSc
            PETSc.Options().insertString(" ".join(_quoted(a) for a in options))
        return
    import slepc4py
    program = str(argv[0]) if argv else "kryflex"
    slepc4py.init([program, "-no_signal_handler", "true"] + options)   # a value: PETSc would read the next word
    from slepc4py import SLEPc  # noqa: F401  (starts SLEPc, and PETSc with it)
    _started = True
    _drop_mpi_defaults()
    _collect_at_exit()


def _collect_at_exit():
    """Registers the exit-time collection once, after petsc4py registered its own exit handler (atexit runs the last
    registered first): the collection then runs before petsc4py's clean-up."""
    global _collect_registered
    if not _collect_registered:
        atexit.register(gc.collect)
        _collect_registered = True


def _quoted(word):
    return '"%s"' % word if any(c.isspace() for c in word) else word


def _keep_python_signals():
    """When PETSc was started before kryflex (without -no_signal_handler), take its handler back off."""
    import signal
    from petsc4py import PETSc
    if PETSc.Options().getBool("no_signal_handler", False) or not hasattr(PETSc.Sys, "popSignalHandler"):
        return
    PETSc.Sys.popSignalHandler()
    PETSc.Options().setValue("no_signal_handler", True)   # popped once: a second init must not pop another
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGPIPE, signal.SIG_IGN)


@contextlib.contextmanager
def collector_paused():
    """Python's cyclic collector held off for the duration of the block (as it was after it): for blocks that only
    build new containers, which cannot be garbage yet. Each full collection walks every container alive; one fell
    inside the 57k-dof summary's FRF blocks (44,000 new lists), 0.025 s of CPU."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


def start_up_objects_kept():
    """The objects made so far (the modules, classes and functions a command imported, which live to its end) taken
    out of the cyclic collector's passes (gc.freeze): every later collection, the one at exit among them, then walks
    only what the command itself makes. Called by the kryflex command after its start-up, before any PETSc or kryflex
    object of the run exists (a frozen cycle is never collected)."""
    gc.freeze()


@contextlib.contextmanager
def quiet_progress(quiet):
    """-kf_quiet set for the duration of the block when quiet is true (the C progress lines read it at each line)."""
    from petsc4py import PETSc
    opts = PETSc.Options()
    added = bool(quiet) and not opts.getBool("kf_quiet", False)
    if added:
        opts.setValue("kf_quiet", True)
    try:
        yield
    finally:
        if added:
            opts.delValue("kf_quiet")
