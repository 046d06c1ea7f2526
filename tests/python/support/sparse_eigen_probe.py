"""A scene reduced on the ranks this runs on with the sparse verification eigensolve forced (for its 2-rank test,
tests/python/reducer/test_sparse_eigensolve.py):

    mpiexec -n 2 .venv/bin/python tests/python/support/sparse_eigen_probe.py SCENE.yaml OUT.npz [PETSc options]

SCENE may also be bc_models:NAME, a model of tests/python/support/bc_models.py built in place.

Writes (rank 0) per configuration the full-order frequencies and the full-order reference response on its grid."""
import sys

import numpy as np


def main():
    scene_path, out = sys.argv[1:3]
    import kryflex
    kryflex.init(sys.argv[:1] + ["-kf_verify_dense_max_dofs", "0"] + sys.argv[3:])
    from petsc4py import PETSc

    if scene_path.startswith("bc_models:"):
        import os
        sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
        import bc_models
        scene = kryflex.scene_from_dict(getattr(bc_models, scene_path.split(":", 1)[1])())
    else:
        scene = kryflex.load_scene(scene_path)
    reducer = kryflex.Reducer(scene, quiet=True, search=False)
    reducer.reduce()
    data = {}
    for c in range(len(reducer.configurations)):
        data["f%d" % c] = np.ravel(reducer.result(c, "full_frequencies_hz"))
        data["T%d" % c] = reducer.frf(c, "full")
        data["w%d" % c] = np.ravel(reducer.result(c, "frf_frequencies_hz"))
    if PETSc.COMM_WORLD.getRank() == 0:
        np.savez(out, **data)


if __name__ == "__main__":
    main()
