"""The kryflex command: reduce, reassemble, info, convert. Runs alone or under mpirun.

Exit codes: 0 done; 2 bad command line, scene or input file; 3 the model cannot be reduced (numerical failure,
e.g. an undeclared mechanism or an indefinite stiffness); 4 the output cannot be written; 5 a reduced-model file
that cannot be used (unreadable, or from another scene); 1 an internal error (a bug: please report it).
"""
import os
import sys

from .common import EXIT_INPUT, EXIT_INTERNAL, EXIT_OK, error, rank, say
from .info import run as info
from .reassemble import run as reassemble
from .reduce import run as reduce

USAGE = """kryflex: Krylov reduction of articulated multi-flexible-body structures

  kryflex reduce SCENE -o OUTDIR        reduce a scene, verify it, write the reduced bodies and a report
  kryflex reassemble REDUCED --angle A  the reduced system at any angles, from the reduced-model file alone
  kryflex info SCENE                    bodies, dofs, joints, rigid and mechanism modes, inputs, outputs, memory
  kryflex convert INPUT --name NAME     import Matrix Market, NumPy .npz or Nastran DMIG (.pch) body matrices

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
    if not argv or argv[0] in ("-h", "-help", "--help", "help"):
        say(USAGE)
        return EXIT_OK if argv else EXIT_INPUT
    cmd, rest = argv[0], argv[1:]
    if cmd == "convert":
        from ..io.convert import main as convert_main
        return convert_main(rest)
    commands = {"reduce": reduce, "reassemble": reassemble, "info": info}
    if cmd not in commands:
        error("unknown command '%s': use reduce, reassemble, info or convert (kryflex -h)" % cmd)
        return EXIT_INPUT
    if "-quiet" in rest or "--quiet" in rest:
        from petsc4py import PETSc
        PETSc.Options().setValue("kf_quiet", True)
    try:
        return commands[cmd](rest)
    except SystemExit as e:
        return int(e.code or 0)
    except KeyboardInterrupt:
        error("interrupted")
        return EXIT_INTERNAL
    except BrokenPipeError:
        # the reader went away (kryflex info ... | head): stop quietly, as command-line tools do
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_OK
    except Exception as e:  # noqa: BLE001 - a bug: say so plainly, with the trace for the report
        import traceback
        if rank() == 0:
            traceback.print_exc()
        error("internal error (%s: %s): please report it with the command line" % (type(e).__name__, e))
        return EXIT_INTERNAL
