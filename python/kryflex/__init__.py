"""kryflex: Krylov reduction of articulated multi-flexible-body structures (A. Y. Lee's methodology).

    import kryflex
    scene = kryflex.load_scene("meshes/galileo/galileo.yaml")
    result = kryflex.reduce(scene)                  # reduced bodies + verification summary
    Mh, Kh, Gh, Hh = result.model.reassemble([60.0])[:4]

Runs under mpirun with mpi4py; PETSc options on the command line reach PETSc and SLEPc.
"""
import sys as _sys

# SLEPc (and with it PETSc) must see the command line before anything initializes them. Signals stay Python's:
# PETSc's handler would replace Python's dispositions (SIGPIPE, SIGINT...) and turn a stray signal from a child
# process into an exit with PETSc's signal error instead of a KeyboardInterrupt or nothing at all.
import slepc4py as _slepc4py

_slepc4py.init(_sys.argv[:1] + ["-no_signal_handler", "true"] + _sys.argv[1:])   # a value: PETSc would read the next word
from slepc4py import SLEPc as _SLEPc  # noqa: E402,F401  (initializes SLEPc)


def _keep_python_signals():
    """When PETSc was initialized before kryflex (without -no_signal_handler), take its handler back off."""
    import signal
    from petsc4py import PETSc
    if PETSc.Options().getBool("no_signal_handler", False) or not hasattr(PETSc.Sys, "popSignalHandler"):
        return
    PETSc.Sys.popSignalHandler()
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGPIPE, signal.SIG_IGN)


_keep_python_signals()

__version__ = "0.1.0"

from ._core import Error  # noqa: E402,F401
from .model import ModelFileError, ReducedModel  # noqa: E402,F401
from .pipeline import reduce  # noqa: E402,F401
from .scene import Scene, SceneError, load_scene, scene_from_dict  # noqa: E402,F401
