# cython: language_level=3, boundscheck=False, wraparound=False
"""The binding of the kryflex C library (src/include/kryflex.h) on petsc4py and slepc4py objects and NumPy arrays.

Declarations are in _kryflex.pxd (PETSc's handle types cimported from petsc4py and slepc4py, scalar typedefs
extern); the wrappers are grouped by job in _binding/*.pxi. Every call checks its arguments before it reaches C,
and a PETSc error becomes a kryflex Error carrying the message of the call that failed, never a crash.

Importing this module initializes PETSc and SLEPc (petsc4py's default, or kryflex.init(argv) when called first)."""

import numpy as np
cimport numpy as cnp
from libc.string cimport memcpy, memset
from libc.math cimport isfinite
from cpython.mem cimport PyMem_Malloc, PyMem_Free
from petsc4py.PETSc cimport Comm, Mat, Object, Vec, Viewer
from slepc4py.SLEPc cimport BV
from petsc4py import PETSc

from ._kryflex cimport *
from . import _runtime

cnp.import_array()
_runtime.init()   # a no-op after kryflex.init(argv); else keeps Python's signal handlers (see _runtime)

include "_binding/common.pxi"
include "_binding/damping.pxi"
include "_binding/scene.pxi"
include "_binding/system.pxi"
include "_binding/dense.pxi"
include "_binding/model.pxi"
include "_binding/measure.pxi"
include "_binding/reducer.pxi"
include "_binding/settings.pxi"
