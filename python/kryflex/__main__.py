"""python -m kryflex: the kryflex command."""
import sys

from .cli.main import main


def _end(code):
    """End the process once the command returned: the exit handlers run as at any exit (the cyclic garbage collected:
    kryflex._runtime), SLEPc, PETSc and MPI are finalized, every stream is flushed (Python's first, then C's: PETSc's
    -log_view is printed while it finalizes); then the process ends without the interpreter's teardown of its modules
    and objects, memory the system takes back at once (benchmarks/proof_cost/README.md, 2026-11-29p)."""
    import atexit
    import ctypes
    import os
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):     # before PETSc's last words, as the interpreter's own exit does
        try:
            stream.flush()
        except (OSError, ValueError):    # a closed or broken stream: nothing more can be said on it
            pass
    # what petsc4py and slepc4py leave to the interpreter's teardown (Py_AtExit), in its order: SLEPc, then PETSc
    # (and MPI, which PETSc started)
    for name in ("slepc4py.SLEPc", "petsc4py.PETSc"):
        module = sys.modules.get(name)
        if module is not None and hasattr(module, "_finalize"):
            module._finalize()
    ctypes.CDLL(None).fflush(None)
    os._exit(code)


if __name__ == "__main__":
    code = main()
    _end(code if isinstance(code, int) else (0 if code is None else 1))
