"""The flexible modes below given frequencies, counted by kryflex from the inertia of K_S - sigma M_S, on any number
of ranks (a helper of reducer/test_mode_count.py).

    mpiexec -n 2 .venv/bin/python tests/python/support/mode_count_probe.py SCENE ANGLES_DEG FREQS_HZ OUT.json

SCENE is a scene file or `bc:NAME` (a model of bc_models.py); ANGLES_DEG and FREQS_HZ are comma-separated (ANGLES_DEG
empty for a scene without revolute joints). Rank 0 writes {"counts": [...]}."""
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bc_models  # noqa: E402
import kryflex  # noqa: E402
from kryflex import _core  # noqa: E402
from petsc4py import PETSc  # noqa: E402


def main(scene_arg, angles_arg, freqs_arg, out):
    PETSc.Options().setValue("kf_quiet", True)
    if scene_arg.startswith("bc:"):
        scene = kryflex.scene_from_dict(getattr(bc_models, scene_arg[3:])())
    else:
        scene = kryflex.load_scene(scene_arg)
    system = _core.CSystem(scene.cscene)
    system.set_angles(np.radians([float(a) for a in angles_arg.split(",") if a]))
    counts = [system.count_modes_below(float(f)) for f in freqs_arg.split(",")]
    if PETSc.COMM_WORLD.getRank() == 0:
        with open(out, "w") as fh:
            json.dump({"counts": counts, "ranks": PETSc.COMM_WORLD.getSize()}, fh)


if __name__ == "__main__":
    main(*sys.argv[1:5])
