"""The kryflex command: reduce, reassemble, info, check, study, slew, export, convert. Runs alone or under mpirun.

Exit codes (cli/common.py; docs/guide/troubleshooting.md), the same on every rank:
  0    done (verification passed, or verification was off and the run says so)
  1    internal error (a bug: please report it)
  2    bad command line, scene, option value or input file
  3    numerical failure: the model cannot be reduced (indefinite K, undeclared mechanism, MUMPS failure)
  4    the output cannot be written (not a folder, read-only, disk full); earlier results left intact
  5    a reduced-model file that cannot be used (unreadable, truncated, inconsistent, other version, other scene)
  6    accuracy target missed: the results are written, summary.json says "target_met": false
  130  interrupted by SIGINT; 143 terminated by SIGTERM (earlier results intact, no stray files)
Under mpirun a rank that fails alone while the others wait in a collective call ends the run with MPI_Abort(code)
after -kf_error_agreement_timeout seconds (cli/common.py).
"""
import importlib
import sys

from .common import EXIT_INPUT, EXIT_INTERNAL, EXIT_OK, EXIT_SIGINT, Failure, agree, error, internal, say, start_agreement

# the commands, each run(argv) of its module cli/<command>.py: only the one run is imported (a reduction then loads
# none of the others' modules)
COMMANDS = ("reduce", "reassemble", "info", "study", "slew", "export", "check")

USAGE = """kryflex: Krylov reduction of articulated multi-flexible-body structures

  kryflex reduce SCENE -o OUTDIR        reduce a scene, verify it, write the reduced bodies and a report
  kryflex reassemble REDUCED --angle A  the reduced system at any angles, from the reduced-model file alone
  kryflex info SCENE                    bodies, dofs, joints, rigid and mechanism modes, inputs, outputs, memory
  kryflex info OUT                      a reduction's results (OUT/summary.json): chosen model, verdict, errors, time
  kryflex check SCENE                   model health before a reduction: rigid-body energy, symmetry, massless dofs
  kryflex study SCENE -o OUTDIR         every method swept on one full-order reference: error vs size and time
  kryflex slew SCENE -o OUTDIR          time simulations under slewing: full vs reduced output error against slew rate
  kryflex convert INPUT --name NAME     import Matrix Market, NumPy .npz or Nastran DMIG (.pch) body matrices
  kryflex export REDUCED -o OUT.npz     the reduced bodies for multibody codes (--format neutral or exudyn)

PETSc options may follow (e.g. -log_view, -kf_moments 12, -kf_damping 0.005, -scene.reduction.moments 12); -quiet
silences progress. Run under MPI as: mpirun -n 2 kryflex reduce SCENE -o OUTDIR. 'kryflex COMMAND -h' for details;
'kryflex reduce -help' lists the reducer's -kf_ options with their defaults.
"""


def main(argv=None):
    argv = list(sys.argv[1:] if argv is None else argv)
    # PETSc reads the command line's options (-log_view, -kf_*, -scene.*) when it starts: before anything else. The
    # help flags are the commands' own (kryflex reduce -help lists the reducer's options itself): PETSc's general
    # help is left out.
    from .. import init
    init([sys.argv[0] if sys.argv else "kryflex"] + [a for a in argv if a not in ("-h", "-help", "--help")])
    if argv and argv[0] in ("-h", "-help", "--help", "help"):
        say(USAGE)
        return EXIT_OK
    if not argv:
        # the usage, and the one error line every refusal has (on stderr: standard output stays empty)
        say(USAGE.rstrip(), sys.stderr)
        error("no command given: use reduce, reassemble, info, check, study, slew, export or convert (kryflex -h)")
        return EXIT_INPUT
    cmd, rest = argv[0], argv[1:]
    if cmd == "convert":
        from ..io.convert import main as convert_main
        return convert_main(rest)
    if cmd not in COMMANDS:
        error("unknown command '%s': use reduce, reassemble, info, check, study, slew, export or convert (kryflex -h)" % cmd)
        return EXIT_INPUT
    run = importlib.import_module("." + cmd, __package__).run
    if "-quiet" in rest or "--quiet" in rest:
        from petsc4py import PETSc
        PETSc.Options().setValue("kf_quiet", True)
    try:
        if any(a in ("-h", "-help", "--help") for a in rest):
            # help only prints, on rank 0; and the binding must not start before 'kryflex reduce -help' sets PETSc's
            # help option (KFInitialize lists -kf_quiet then)
            try:
                return run(rest)
            except Failure as f:  # an option given beside the help with a value it refuses: the same on every rank
                say(f.text, sys.stderr)
                return f.code
        # SIGINT and SIGTERM are noted by the C library's handlers from here on, and the work stops at its next
        # stage or phase boundary, on every rank together (before: Python's KeyboardInterrupt, or the default)
        from .. import _core
        _core.interrupt_catch()
        try:
            start_agreement()
        except Failure as f:
            agree(f)
        from .._runtime import start_up_objects_kept
        start_up_objects_kept()
        return run(rest)
    except SystemExit as e:
        return int(e.code or 0)
    except KeyboardInterrupt:
        print("kryflex: interrupted (SIGINT)", file=sys.stderr, flush=True)
        return EXIT_SIGINT
    except Exception as e:  # noqa: BLE001 - a bug outside the phases: say so plainly, with the trace for the report
        try:
            agree(internal(e))
        except SystemExit as stop:
            return int(stop.code or 0)
        return EXIT_INTERNAL
