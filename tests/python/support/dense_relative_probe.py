"""Writes what kryflex's dense verification eigensolve returns on a scene's first configuration, with the system it
solved (gathered), for test_dense_reference_relative.py: python dense_relative_probe.py scene.yaml out.npz (any
number of ranks; rank 0 writes)."""
import os
import sys

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import kryflex  # noqa: E402
from kryflex import _core  # noqa: E402
from krylov_dense_probe import gathered  # noqa: E402

scene = kryflex.load_scene(sys.argv[1], quiet=True)
system = _core.CSystem(scene.cscene)
angles = scene.configurations[1] if len(scene.configurations) > 1 else scene.configurations[0]
system.set_angles(np.radians(angles))
Ms, Ks, G, Ht = system.matrices()
n = Ks.getSize()[0]
w2, HPhi, PhiG = system.eigen(n)
out = dict(K=gathered(Ks, PETSc), M=gathered(Ms, PETSc), G=gathered(G, PETSc), H=gathered(Ht, PETSc).T, w2=w2,
           HPhi=HPhi, PhiG=PhiG)
if MPI.COMM_WORLD.rank == 0:
    np.savez(sys.argv[2], **out)
