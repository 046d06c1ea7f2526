"""kryflex: Krylov reduction of articulated multi-flexible-body structures (A. Y. Lee's methodology).

    import kryflex
    scene = kryflex.load_scene("meshes/galileo/galileo.yaml")
    result = kryflex.reduce(scene)                  # reduced bodies + verification summary
    Mh, Kh, Gh, Hh = result.model.reassemble([60.0])[:4]

Runs under mpirun with mpi4py; PETSc options on the command line reach PETSc and SLEPc.
"""
import sys as _sys

# SLEPc (and with it PETSc) must see the command line before anything initializes them.
import slepc4py as _slepc4py

_slepc4py.init(_sys.argv)
from slepc4py import SLEPc as _SLEPc  # noqa: E402,F401  (initializes SLEPc)

__version__ = "0.1.0"

from ._core import Error  # noqa: E402,F401
from .model import ModelFileError, ReducedModel  # noqa: E402,F401
from .pipeline import reduce  # noqa: E402,F401
from .scene import Scene, SceneError, load_scene, scene_from_dict  # noqa: E402,F401
