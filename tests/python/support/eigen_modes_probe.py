"""Writes what CSystem.eigen_modes returns on a scene's first configuration when asked for more modes than the system
has (nev = its dofs) and for exactly the flexible modes' count, with the system it solved (gathered), for
test_eigen_modes.py: python eigen_modes_probe.py scene.yaml out.npz (any number of ranks; rank 0 writes)."""
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
system.set_angles(np.radians(scene.configurations[0]))
Ms, Ks, G, Ht = system.matrices()
n = Ks.getSize()[0]
w2_all, modes_all = system.eigen_modes(n)
w2_count, modes_count = system.eigen_modes(len(w2_all))
out = dict(K=gathered(Ks, PETSc), M=gathered(Ms, PETSc), w2_all=w2_all, modes_all=gathered(modes_all, PETSc),
           w2_count=w2_count, modes_count=gathered(modes_count, PETSc), nrigid=system.rigid_modes()[0].getSize()[1])
if MPI.COMM_WORLD.rank == 0:
    np.savez(sys.argv[2], **out)
