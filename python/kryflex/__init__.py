"""kryflex: Krylov reduction of articulated multi-flexible-body structures (A. Y. Lee's methodology).

    import kryflex
    scene = kryflex.load_scene("meshes/galileo/galileo.yaml")
    result = kryflex.reduce(scene)          # reduced bodies + verification summary
    Mh, Kh, Gh, Hh = result.reduced.reassemble([60.0])[:4]
"""
import sys as _sys

# petsc4py must see the command line (PETSc options) before anything initializes PETSc.
import petsc4py as _petsc4py

if not _petsc4py.PETSc_initialized if hasattr(_petsc4py, "PETSc_initialized") else True:
    pass
try:
    _petsc4py.init(_sys.argv)
except Exception:  # already initialized by the caller
    pass

__version__ = "0.1.0"

from ._core import Error  # noqa: E402
