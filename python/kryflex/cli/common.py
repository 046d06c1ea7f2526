"""What every kryflex command shares: exit codes, rank-0 output, PETSc options on the command line, argument parsing,
and the agreement that ends every phase of a command under MPI.

A command runs in phases (read the command line, load the scene, set up the reducer, reduce, write). Each phase
ends in an agreement (collective(), agree()): every rank contributes how the phase went on it, every rank learns
the worst exit code and the message of the lowest rank that failed with it, rank 0 prints that message once and
every rank exits with that code. A rank that failed alone may have left the others waiting inside a collective C
call, where they never reach the agreement: the failing rank waits for them -kf_error_agreement_timeout seconds
(default 20), then prints its own message and ends the whole run with MPI_Abort(COMM_WORLD, code).
"""
import argparse
import difflib
import os
import re
import sys
import time

EXIT_OK, EXIT_INTERNAL, EXIT_INPUT, EXIT_NUMERIC, EXIT_OUTPUT, EXIT_MODEL = 0, 1, 2, 3, 4, 5
EXIT_TARGET, EXIT_SIGINT, EXIT_SIGTERM = 6, 130, 143

# signal number -> (exit code, name)
SIGNALS = {2: (EXIT_SIGINT, "interrupted (SIGINT)"), 15: (EXIT_SIGTERM, "terminated (SIGTERM)")}
# which code the run ends with when ranks fail differently: a stop the user asked for first, then bugs, then the
# failures of the model, the files and the input
SEVERITY = (EXIT_OK, EXIT_TARGET, EXIT_INPUT, EXIT_OUTPUT, EXIT_MODEL, EXIT_NUMERIC, EXIT_INTERNAL, EXIT_SIGINT,
            EXIT_SIGTERM)
AGREEMENT_TIMEOUT = 20.0      # seconds; -kf_error_agreement_timeout
RECORD = 4096                 # bytes per rank in an agreement: the code, then the message (cut if longer)

# -kf_ options read after the reducer's own (KFReducerSetFromOptions, which also reads and checks those of the solve's
# stages), by the views, the eigenvector baseline and this command: not unknown when unused before the solve.
# tests/python/commands/test_collective_errors.py checks the list against the C sources.
LATER_OPTIONS = ("kf_quiet", "kf_reducer_view", "kf_reducer_view_pre", "kf_model_view", "kf_eigen_cover",
                 "kf_error_agreement_timeout")
# option prefixes of PETSc/SLEPc objects the library configures (the verification eigensolver: -kf_verify_eps_...)
LATER_PREFIXES = ("kf_verify_",)

_stdout_gone = False
_agreement = None             # the agreements' own communicator (a duplicate of COMM_WORLD)
_timeout = AGREEMENT_TIMEOUT
# what a command adds to "kryflex: interrupted (SIGINT)", e.g. ": results in OUT left as they were"
interrupt_note = ""
# what the failing rank does before MPI_Abort (remove a staging folder...): callables, run in order
before_abort = []


def rank():
    from petsc4py import PETSc
    return PETSc.COMM_WORLD.getRank()


def size():
    from petsc4py import PETSc
    return PETSc.COMM_WORLD.getSize()


def say(msg, stream=sys.stdout):
    """A line on rank 0. A reader that went away (kryflex info ... | head) silences the rest of the standard output
    instead of stopping rank 0 alone: the other ranks may still need it in collective calls."""
    global _stdout_gone
    if rank() != 0 or (_stdout_gone and stream is sys.stdout):
        return
    try:
        print(msg, file=stream, flush=True)
    except BrokenPipeError:
        if stream is not sys.stdout:
            raise
        _stdout_gone = True
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())


def error(msg):
    say("kryflex: error: %s" % msg, sys.stderr)


# ---------------------------------------------------------------------------------------------- failures

class Failure(Exception):
    """How a phase failed on this rank: the exit code and the text to print (the agreed one is printed by rank 0)."""

    def __init__(self, code, message, usage=None, text=None):
        super().__init__(message)
        self.code = code
        self.text = text or ((usage + "\n" if usage else "") + "kryflex: error: " + message)


def interrupted(signum):
    code, what = SIGNALS.get(signum, (EXIT_SIGINT, "interrupted (signal %d)" % signum))
    return Failure(code, what, text="kryflex: %s%s" % (what, interrupt_note))


def pending_interrupt():
    """A Failure for a signal the C handlers noted on this rank (None: none)."""
    from .. import _core
    sig = _core.interrupt_signal()
    return interrupted(sig) if sig else None


def raise_if_interrupted():
    """Stops a long Python step of one rank (the plots) when a signal was noted; its phase's agreement tells the others."""
    failure = pending_interrupt()
    if failure is not None:
        raise failure


def internal(exc):
    """A bug: the trace on this rank's stderr for the report, and the message."""
    import traceback
    traceback.print_exception(type(exc), exc, exc.__traceback__)
    return Failure(EXIT_INTERNAL, "internal error (%s: %s): please report it with the command line"
                   % (type(exc).__name__, exc))


def load_reduced_model(reduced, scene=None):
    """A reduced-model file, checked against the scene file it is to serve when one is named (kryflex reassemble,
    kryflex export): raises ModelFileError, SceneError, or the binding's error for a scene the model does not fit."""
    from ..api import ReducedModel
    from ..io.scene import load_scene
    model = ReducedModel.load(reduced)
    if scene:
        model.check_scene(load_scene(scene), reduced)
    return model


def collective(fn, *errors, interruptible=True):
    """Runs one phase, fn(), on every rank and ends it with an agreement: returns fn()'s value when it succeeded on
    every rank, else every rank exits (SystemExit) with the agreed code. errors: (exception class, exit code, message
    function of the exception), tried in order; Failure passes as it is, a signal is an interrupt, anything else is
    a bug. A signal noted while the phase ran stops the command here too, unless interruptible is false (a phase
    after which nothing is left to undo)."""
    from .. import _core
    failure, value = None, None
    try:
        value = fn()
    except Failure as e:
        failure = e
    except _core.Interrupted as e:
        failure = interrupted(e.signal)
    except KeyboardInterrupt:       # before the C handlers were installed
        failure = interrupted(2)
    except Exception as e:  # noqa: BLE001 - classified below, a bug otherwise
        for cls, code, message in errors:
            if isinstance(e, cls):
                failure = Failure(code, message(e))
                break
        else:
            failure = internal(e)
    agree(failure or (pending_interrupt() if interruptible else None))
    return value


# ---------------------------------------------------------------------------------------------- the agreement

def start_agreement():
    """Every rank, at start-up: the agreements' own communicator, so that an agreement never matches a collective
    call of PETSc's, and the deadline of a failing rank (-kf_error_agreement_timeout)."""
    global _agreement, _timeout
    from petsc4py import PETSc
    _timeout = PETSc.Options().getReal("kf_error_agreement_timeout", AGREEMENT_TIMEOUT)
    if _timeout <= 0:
        raise Failure(EXIT_INPUT, "-kf_error_agreement_timeout %g: give a number of seconds > 0" % _timeout)
    if PETSc.COMM_WORLD.getSize() > 1:
        _agreement = PETSc.COMM_WORLD.tompi4py().Dup()


def agree(failure):
    """Ends a phase on every rank. failure: this rank's Failure, or None. Returns when no rank failed; otherwise rank
    0 prints the agreed message and every rank raises SystemExit with the agreed code. Nonblocking: a failing rank
    whose peers do not come within the deadline prints its message and aborts the run (MPI_Abort with its code)."""
    comm = _agreement
    if comm is None:
        if failure is not None:
            print(failure.text, file=sys.stderr, flush=True)
            raise SystemExit(failure.code)
        return
    import numpy as np
    size = comm.Get_size()
    mine = np.zeros(RECORD, dtype=np.uint8)
    if failure is not None:
        text = failure.text.encode("utf-8", errors="replace")[:RECORD - 4]
        mine[:4] = np.frombuffer(np.int32(failure.code).tobytes(), dtype=np.uint8)
        mine[4:4 + len(text)] = np.frombuffer(text, dtype=np.uint8)
    every = np.zeros(size * RECORD, dtype=np.uint8)
    request = comm.Iallgather(mine, every)
    deadline = None if failure is None else time.monotonic() + _timeout
    pause = 0.001
    while not request.Test():
        if deadline is not None and time.monotonic() > deadline:
            _abort(failure, comm.Get_rank(), size)
        time.sleep(pause)                 # a polled wait: the deadline, and the signal handlers, stay in force
        pause = min(2 * pause, 0.05)
    records = every.reshape(size, RECORD)
    codes = [int(np.frombuffer(r[:4].tobytes(), dtype=np.int32)[0]) for r in records]
    worst = max(codes, key=_severity)
    if worst == EXIT_OK:
        return
    first = codes.index(worst)
    if comm.Get_rank() == 0:
        text = records[first][4:].tobytes().rstrip(b"\0").decode("utf-8", errors="replace")
        print(text, file=sys.stderr, flush=True)
    raise SystemExit(worst)


def _severity(code):
    return SEVERITY.index(code) if code in SEVERITY else SEVERITY.index(EXIT_INTERNAL)


def _abort(failure, me, size):
    from mpi4py import MPI
    print(failure.text, file=sys.stderr, flush=True)
    print("kryflex: rank %d of %d failed alone and the other ranks did not reach the error agreement within %g s "
          "(-kf_error_agreement_timeout): ending the run with MPI_Abort" % (me, size, _timeout),
          file=sys.stderr, flush=True)
    for fn in before_abort:
        try:
            fn()
        except Exception:  # noqa: BLE001 - the abort must happen whatever the clean-up does
            pass
    MPI.COMM_WORLD.Abort(failure.code)


# ---------------------------------------------------------------------------------------------- the command line

def split_petsc_options(argv, flags_with_value, flags):
    """Keeps the command's own arguments; PETSc options (single dash, already read by PETSc) are dropped with their
    values. A double-dash word that is not the command's is kept, for the parser to refuse (--npzz is a typo, not a
    PETSc option)."""
    out, i = [], 0
    while i < len(argv):
        a = argv[i]
        if a.split("=", 1)[0] in flags_with_value and "=" in a:
            out.append(a)
            i += 1
            continue
        if a in flags_with_value:
            out.extend(argv[i:i + 2])
            i += 2
            continue
        if a in flags or not a.startswith("-") or a == "-" or a.startswith("--") or _is_number(a):
            out.append(a)
            i += 1
            continue
        # a PETSc option: its value is the next token unless that is another option
        i += 1
        if i < len(argv) and (not argv[i].startswith("-") or _is_number(argv[i])):
            i += 1
    return out


def _is_number(s):
    try:
        float(s)
        return True
    except ValueError:
        return False


class Parser(argparse.ArgumentParser):
    """argparse with kryflex's conventions: a bad command line is a Failure (EXIT_INPUT) the phase's agreement reports,
    and help goes out on rank 0 only."""

    def error(self, message):
        raise Failure(EXIT_INPUT, self.explain(message), usage=self.format_usage().rstrip())

    def explain(self, message):
        """argparse's message with what to do: the missing arguments to give, the closest of the command's options
        for an unknown one (--npzz: did you mean --npz?), and where the usage is."""
        where = "run '%s -h' for the usage" % self.prog
        missing = re.fullmatch(r"the following arguments are required: (.*)", message)
        if missing:
            return "missing %s: give %s (%s)" % (missing.group(1), "it" if "," not in missing.group(1) else "them",
                                                 where)
        unknown = re.fullmatch(r"unrecognized arguments: (.*)", message)
        if unknown:
            words = unknown.group(1).split()
            options = sorted(o for a in self._actions for o in a.option_strings if o.startswith("--"))
            close = [difflib.get_close_matches(w.split("=", 1)[0], options, n=1) for w in words if w.startswith("--")]
            close = [c[0] for c in close if c]
            if close:
                return "unknown option %s (did you mean %s?)" % (" ".join(words), " or ".join(close))
            return "unexpected argument%s %s: remove %s (%s)" % ("s" if len(words) > 1 else "", " ".join(words),
                                                                 "them" if len(words) > 1 else "it", where)
        return "%s: %s" % (message, where)

    def _print_message(self, message, file=None):
        if message and rank() == 0:
            (file or sys.stderr).write(message)


def nonnegative_int(text):
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError("%r is not an integer" % text) from None
    if value < 0:
        raise argparse.ArgumentTypeError("%s: give a count >= 0" % text)
    return value


def given_kf_options():
    """The -kf_ options given (command line, PETSC_OPTIONS, options files) that the reducer itself may read: the
    candidates of check_kf_options."""
    from .. import _core
    return [name for name, _ in _core.unused_options()
            if name.startswith("kf_") and name not in LATER_OPTIONS and not name.startswith(LATER_PREFIXES)]


def reducer_option_names():
    """The -kf_ option names (without the dash) of the settings table (src/util/settings_table.c): every option the
    library and this command read."""
    from .. import settings
    return sorted(r["name"][1:] for r in settings.table())


def check_kf_options(known):
    """Refuses a -kf_ option that nothing read (a misspelt name would otherwise be ignored without a word), naming the
    closest of known (reducer_option_names()). Called once the reducer has read its options: options of later stages
    (LATER_OPTIONS, LATER_PREFIXES) are not read yet and are accepted."""
    unknown = given_kf_options()
    if not unknown:
        return
    name = sorted(unknown)[0]
    close = difflib.get_close_matches(name, sorted(set(known) | set(LATER_OPTIONS)), n=1)
    hint = " (did you mean -%s?)" % close[0] if close else ": 'kryflex reduce -help' lists the -kf_ options"
    raise Failure(EXIT_INPUT, "unknown option -%s%s" % (name, hint))


def checked_reducer(scene, quiet=None, known=None):
    """The Reducer of a loaded scene with the scene's settings and every -kf_ option read and checked before any work,
    as each command that reduces needs it: a value the C library refuses raises its Error (option_error() words it),
    an option nothing read a Failure naming the closest real one. known: the reducer's option names when this process
    has read them already (reducer_option_names()). Collective."""
    from ..reducer import Reducer
    if known is None:
        known = reducer_option_names() if given_kf_options() else ()
    reducer = Reducer(scene, quiet=quiet)
    reducer.setup()
    check_kf_options(known)
    return reducer


def option_error(exc, scene_path):
    """The message of a C error raised while the reducer read its settings (the scene's, then the -kf_ options). An
    error about a -kf_ option that was given names that option and its value, not the scene, and says what to do;
    PETSc's own refusals of a value (not a number, not one of the choices) are said the same way. Any other error
    is the scene's."""
    from petsc4py import PETSc
    msg = str(exc).strip()
    given = {k: v for k, v in PETSc.Options().getAll().items() if k.startswith("kf_")}
    listing = "'kryflex reduce -help' lists the -kf_ options with their defaults"
    def named(value):
        names = ["-%s %s: " % (k, v) for k, v in sorted(given.items()) if v is not None and value in v.split(",")]
        return (names or [""])[0]
    bad_number = re.search(r"Input string (.*?) has no (numeric|integer) value", msg)
    if bad_number:
        value, kind = bad_number.group(1), bad_number.group(2)
        return "%s%r is not %s: give %s (%s)" % (named(value), value, "a number" if kind == "numeric" else "an integer",
                                                 "a number" if kind == "numeric" else "a whole number", listing)
    bad_bool = re.search(r"Unknown logical value: (\S+)", msg)
    if bad_bool:
        value = bad_bool.group(1)
        return "%s%r is not true or false: give true or false (%s)" % (named(value), value, listing)
    bad_choice = re.search(r"Unknown option (\S+) for -(\w+)\. Available options: (.*)", msg)
    if bad_choice:
        value, name, choices = bad_choice.group(1), bad_choice.group(2), bad_choice.group(3).split()
        close = difflib.get_close_matches(value, choices, n=1, cutoff=0.3)
        return "-%s %s: not one of %s: use one of them%s" % (name, value, ", ".join(choices),
                                                             " (did you mean %s?)" % close[0] if close else "")
    outside = re.match(r"-(kf_\w+) (\S+) is outside (.*)", msg)
    if outside and outside.group(1) in given:   # the C readers' range check (src/util/settings_read.c)
        return "-%s %s: %s is outside %s (%s)" % (outside.group(1), given[outside.group(1)], outside.group(2),
                                                 outside.group(3), listing)
    names = [k for k in sorted(given) if re.search(r"-%s\b" % re.escape(k), msg)]
    if names:
        return "-%s %s: %s; give -%s a valid value (%s)" % (names[0], given[names[0]], msg, names[0], listing)
    return "%s: %s" % (scene_path, msg)


def from_rank0(value):
    """Rank 0's value on every rank (a no-op when run alone). Only where every rank is known to be: right after an
    agreement."""
    from petsc4py import PETSc
    comm = PETSc.COMM_WORLD
    if comm.getSize() == 1:
        return value
    return comm.tompi4py().bcast(value, root=0)
