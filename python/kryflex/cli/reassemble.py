"""kryflex reassemble REDUCED --angle A: the reduced system at any angles from a reduced-model file alone."""
import json

import numpy as np

from .common import (EXIT_INPUT, EXIT_MODEL, EXIT_OK, EXIT_OUTPUT, Parser, error, from_rank0, rank, say,
                     split_petsc_options)


def run(argv):
    p = Parser(prog="kryflex reassemble",
                description="The reduced system at any angles from a reduced-model file alone (paper eq. 20-24).")
    p.add_argument("reduced", help="reduced-model file (.h5) written by 'kryflex reduce'")
    p.add_argument("--angle", action="append", required=True,
                   help="angle(s) in degrees, comma-separated for several revolute joints; repeat for more configurations")
    p.add_argument("--scene", help="check that the reduced model comes from this scene")
    p.add_argument("-o", "--output", help="write the reassembled matrices (Mh, Kh, Gh, Hh per angle) to this .npz")
    p.add_argument("--json", action="store_true", help="print the results as JSON")
    p.add_argument("--modes", type=int, default=10, help="flexible frequencies to print (default 10)")
    kept = split_petsc_options(argv, {"--angle", "--scene", "-o", "--output", "--modes"}, {"--json", "-h", "--help"})
    # '--angle -30,95' would read as an option to argparse: glue the value on
    kept = [a + "=" + kept[i + 1] if a == "--angle" and i + 1 < len(kept) else a for i, a in enumerate(kept)
            if not (i > 0 and kept[i - 1] == "--angle")]
    args = p.parse_args(kept)
    import time

    from ..api import ModelFileError, ReducedModel
    from ..io.scene import SceneError, load_scene
    try:
        model = ReducedModel.load(args.reduced)
        if args.scene:
            model.check_scene(load_scene(args.scene), args.reduced)
    except ModelFileError as e:
        error(str(e))
        return EXIT_MODEL
    except SceneError as e:
        error(str(e))
        return EXIT_INPUT
    results, arrays = [], {}
    for text in args.angle:
        try:
            angles = [float(x) for x in text.split(",")]
            t0 = time.perf_counter()
            system = model.at(angles)
            dt = time.perf_counter() - t0
        except ValueError as e:
            error("--angle %s: %s" % (text, e))
            return EXIT_INPUT
        results.append(dict(angles_deg=angles, dofs=system.dofs, constraint_rank=system.constraint_rank,
                            sigma_ratio=system.sigma_ratio, seconds=dt,
                            rigid_modes=None if system.rigid_modes is None else int(system.rigid_modes.shape[1]),
                            frequencies_hz=[float(x) for x in system.frequencies_hz[:args.modes]]))
        key = "_".join("%g" % a for a in angles)
        arrays.update({"M_" + key: system.M, "K_" + key: system.K, "G_" + key: system.B, "H_" + key: system.C})
    if args.output:
        problem = _write_npz(args.output, arrays) if rank() == 0 else None
        problem = from_rank0(problem)
        if problem is not None:
            error(problem)
            return EXIT_OUTPUT
    if args.json:
        say(json.dumps(results, indent=1))
    else:
        for r in results:
            say("angles %s deg: %d dofs (constraint rank %d, %s rigid/mechanism modes), reassembled in %.2f ms"
                 % (r["angles_deg"], r["dofs"], r["constraint_rank"], r["rigid_modes"], 1e3 * r["seconds"]))
            say("  flexible frequencies (Hz): " + " ".join("%.6g" % x for x in r["frequencies_hz"]))
    return EXIT_OK


def _write_npz(path, arrays):
    """Writes arrays to path (.npz) under a temporary name renamed into place; None, or what went wrong."""
    from ..io.files import atomic_path
    try:
        with atomic_path(path) as tmp:
            with open(tmp, "wb") as fh:
                np.savez(fh, **arrays)
        return None
    except OSError as e:
        return "cannot write %s: %s" % (path, e)
