#!/usr/bin/python3
"""One boundary-condition case of bc_models.py reduced with kryflex.Reducer on the ranks it runs on:

    mpiexec -n 2 .venv/bin/python tests/python/support/bc_probe.py CASE OUT.npz [PETSc options]

Writes (rank 0) the reduced model's FRF at the case's angles and midpoints, its rigid count per angle and the
reducer's rigid_modes result. A bad case (bc_models.bad_case) prints 'error: <message>' on rank 0 and exits 2."""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))


def main():
    case, out = sys.argv[1:3]
    import kryflex
    kryflex.init(sys.argv[:1] + sys.argv[3:])
    from petsc4py import PETSc
    import bc_models

    rank = PETSc.COMM_WORLD.getRank()
    try:
        spec = bc_models.CASES[case]() if case in bc_models.CASES else bc_models.bad_case(case)
        scene = kryflex.scene_from_dict(spec)
        reducer = kryflex.Reducer(scene, quiet=True)
        reduction = reducer.reduce()
    except (kryflex.SceneError, kryflex.Error) as e:
        if rank == 0:
            print("error: %s" % e, flush=True)
        sys.exit(2)
    angles = spec.get("angles", [])
    evals = sorted(set(angles) | {0.5 * (a + b) for a, b in zip(angles, angles[1:])}) if angles else [None]
    f = np.geomspace(bc_models.BAND[0], bc_models.BAND[1], 400)
    T, nrig = [], []
    for a in evals:
        s = reduction.model.at([] if a is None else [a])
        T.append(s.frf(f))
        nrig.append(-1 if s.rigid_modes is None else s.rigid_modes.shape[1])
    if rank == 0:
        np.savez(out, angles=np.array([np.nan if a is None else a for a in evals]), f=f, T=np.array(T),
                 nrigid=np.array(nrig), rigid_modes=reducer.result(-1, "rigid_modes"),
                 sizes=np.array(reduction.model.sizes))


if __name__ == "__main__":
    main()
