#!/usr/bin/python3
"""Krylov reduction at each configuration of a scene, for comparing a serial run with an MPI run.

    mpiexec -n 2 /usr/bin/python3 tests/python/support/mpi_krylov_probe.py SCENE OUT.json [--moments 10] [--output-blocks 1]

For every configuration of the scene: the full-order moments (one MUMPS factorization, repeated flexible solves),
the moments of the projected Krylov system (eq. 10-11) and their ratios, the basis size and the number of deflated
columns. Rank 0 writes them to OUT.json; test_krylov.py runs this serially and on 2 ranks and compares."""
import argparse
import json

import numpy as np


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene")
    ap.add_argument("out")
    ap.add_argument("--moments", type=int, default=10)
    ap.add_argument("--output-blocks", type=int, default=1)
    args = ap.parse_args()

    import kryflex
    from kryflex import _core
    from petsc4py import PETSc
    PETSc.Options().setValue("kf_quiet", True)

    scene = kryflex.load_scene(args.scene)
    system = _core.CSystem(scene.cscene)
    nin = args.moments - args.output_blocks
    result = {"ranks": PETSc.COMM_WORLD.getSize(), "system_dofs": scene.info["system_dofs"], "configurations": {}}
    for cfg in scene.configurations:
        system.set_angles(scene.angles_rad(cfg))
        solver = _core.FlexSolver(system)
        full = solver.moments(args.moments)
        basis, ndeflated = solver.krylov_basis(nin, args.output_blocks)
        Mr, Kr, Gr, Hr = basis.project()
        # the Krylov basis is M-orthogonal to the rigid modes: the reduced system has none, hence the tiny tolerance
        reduced = _core.dense_moments(Kr, Mr, Gr, Hr, args.moments, 1e-14)
        result["configurations"][scene.label(cfg)] = {
            "full": full.tolist(), "reduced": reduced.tolist(), "ratio": (full / reduced).tolist(),
            "basis_size": basis.size, "deflated": ndeflated,
            "mass_orthonormality": float(np.abs(Mr - np.eye(basis.size)).max()),
        }
        del solver, basis
    if PETSc.COMM_WORLD.getRank() == 0:
        with open(args.out, "w") as f:
            json.dump(result, f, indent=1)


if __name__ == "__main__":
    main()
