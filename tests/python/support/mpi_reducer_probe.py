#!/usr/bin/python3
"""kryflex.Reducer on a scene file, for comparing the Python face with the kryflex command on the same ranks.

    mpiexec -n 2 /usr/bin/python3 tests/python/support/mpi_reducer_probe.py SCENE OUT.h5 OUT.json

Reduces the scene with kryflex.Reducer (quiet), writes the chosen model to OUT.h5 (every rank together: the C
writer is collective) and, from rank 0, the summary to OUT.json."""
import json
import sys


def main():
    scene_path, model_path, summary_path = sys.argv[1:4]
    import kryflex
    kryflex.init(sys.argv[:1] + sys.argv[4:])
    from petsc4py import PETSc

    scene = kryflex.load_scene(scene_path)
    reduction = kryflex.Reducer(scene, quiet=True).reduce()
    reduction.model.save(model_path)
    if PETSc.COMM_WORLD.getRank() == 0:
        with open(summary_path, "w") as f:
            json.dump(reduction.summary.to_json(), f, allow_nan=False)


if __name__ == "__main__":
    main()
