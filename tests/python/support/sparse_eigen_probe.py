"""A scene reduced on the ranks this runs on with the sparse verification eigensolve forced (for its 2-rank test,
tests/python/reducer/test_sparse_eigensolve.py):

    mpiexec -n 2 .venv/bin/python tests/python/support/sparse_eigen_probe.py SCENE.yaml OUT.npz [PETSc options]

Writes (rank 0) per configuration the full-order frequencies and the full-order reference response on its grid."""
import sys

import numpy as np


def main():
    scene_path, out = sys.argv[1:3]
    import kryflex
    kryflex.init(sys.argv[:1] + ["-kf_verify_dense_max_dofs", "0"] + sys.argv[3:])
    from petsc4py import PETSc

    reducer = kryflex.Reducer(kryflex.load_scene(scene_path), quiet=True, search=False)
    reducer.reduce()
    data = {}
    for c in range(len(reducer.configurations)):
        data["f%d" % c] = np.ravel(reducer.result(c, "full_frequencies_hz"))
        data["T%d" % c] = reducer.frf(c, "full")
    if PETSc.COMM_WORLD.getRank() == 0:
        np.savez(out, **data)


if __name__ == "__main__":
    main()
