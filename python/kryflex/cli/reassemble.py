"""kryflex reassemble REDUCED --angle A: the reduced system at any angles from a reduced-model file alone."""
import io
import json
import os

import numpy as np

from . import common
from .common import (EXIT_INPUT, EXIT_MODEL, EXIT_NUMERIC, EXIT_OK, EXIT_OUTPUT, Failure, Parser, collective,
                     load_reduced_model, nonnegative_int, rank, say, split_petsc_options)


def run(argv):
    p = Parser(prog="kryflex reassemble",
                description="The reduced system at any angles from a reduced-model file alone (paper eq. 20-24).")
    p.add_argument("reduced", help="reduced-model file (.h5) written by 'kryflex reduce'")
    p.add_argument("--angle", action="append",
                   help="angle(s) in degrees, comma-separated for several revolute joints; repeat for more "
                        "configurations; 'none' (or no --angle) for a model without revolute joints")
    p.add_argument("--scene", help="check that the reduced model comes from this scene")
    p.add_argument("-o", "--output", help="write the reassembled matrices (Mh, Kh, Gh, Hh per angle, and the viscous damping Dh when the model has one) to this .npz")
    p.add_argument("--json", action="store_true", help="print the results as JSON")
    p.add_argument("--modes", type=nonnegative_int, default=10, help="flexible frequencies to print (default 10)")

    def parse():
        kept = split_petsc_options(argv, {"--angle", "--scene", "-o", "--output", "--modes"}, {"--json", "-h", "--help"})
        # '--angle -30,95' would read as an option to argparse: glue the value on
        kept = [a + "=" + kept[i + 1] if a == "--angle" and i + 1 < len(kept) else a for i, a in enumerate(kept)
                if not (i > 0 and kept[i - 1] == "--angle")]
        args = p.parse_args(kept)
        args.angles = [_angles(text) for text in args.angle] if args.angle else None
        return args
    args = collective(parse)
    import time

    from .. import _core
    from ..api import ModelFileError
    from ..io.scene import SceneError

    model = collective(lambda: load_reduced_model(args.reduced, args.scene), (ModelFileError, EXIT_MODEL, str), (SceneError, EXIT_INPUT, str),
                       (_core.Error, EXIT_INPUT, lambda e: "%s: %s" % (args.scene, e)))

    if args.angles is None:
        args.angle, args.angles = ["none"], [[]]
        if model.revolute:
            collective(lambda: _no_angle(model))

    def reassemble():
        results, arrays = [], {}
        for text, angles in zip(args.angle, args.angles):
            t0 = time.perf_counter()
            try:
                system = model.at(angles)
            except ValueError as e:
                raise Failure(EXIT_INPUT, "--angle %s: %s" % (text, e)) from None
            dt = time.perf_counter() - t0
            results.append(dict(angles_deg=angles, dofs=system.dofs, constraint_rank=system.constraint_rank,
                                sigma_ratio=system.sigma_ratio, seconds=dt,
                                rigid_modes=None if system.rigid_modes is None else int(system.rigid_modes.shape[1]),
                                frequencies_hz=[float(x) for x in system.frequencies_hz[:args.modes]],
                                top_frequency_hz=system.top_frequency_hz, trimmed_modes=int(system.trimmed),
                                max_frequency_hz=system.max_frequency_hz or None,
                                explicit_step_s=system.explicit_step_s if system.top_frequency_hz > 0 else None))
            key = "_".join("%g" % a for a in angles) if angles else "none"
            arrays.update({"M_" + key: system.M, "K_" + key: system.K, "G_" + key: system.B, "H_" + key: system.C})
            if system.damping_matrix is not None:   # the viscous damping (bodies' C_b + Rayleigh), docs/guide/damping.md
                arrays["D_" + key] = system.damping_matrix
            if system.feedthrough is not None:      # a trimmed model: y = H x + feedthrough u (docs/guide/trimming.md)
                arrays["feedthrough_" + key] = system.feedthrough
        return results, arrays
    results, arrays = collective(reassemble, (_core.Error, EXIT_NUMERIC, str))
    if args.output:
        path = os.path.abspath(args.output)
        common.interrupt_note = ": %s left as it was" % path
        collective(lambda: _write_npz(path, arrays) if rank() == 0 else None,
                   (OSError, EXIT_OUTPUT, lambda e: "cannot write %s (%s): choose another -o, or free space on its "
                    "disk" % (path, e.strerror or e)))
    if args.json:
        say(json.dumps(results, indent=1))
    else:
        for r in results:
            where = "angles %s deg" % r["angles_deg"] if r["angles_deg"] else "no revolute joint"
            say("%s: %d dofs (constraint rank %d, %s rigid/mechanism modes), reassembled in %.2f ms"
                % (where, r["dofs"], r["constraint_rank"], r["rigid_modes"], 1e3 * r["seconds"]))
            say("  flexible frequencies (Hz): " + " ".join("%.6g" % x for x in r["frequencies_hz"]))
            if r["trimmed_modes"]:
                say("  trimmed: %d mode(s) above %.4g Hz out of the dynamics (static share kept as a feedthrough); "
                    "highest kept %.4g Hz, stable explicit step %.3g s" % (r["trimmed_modes"], r["max_frequency_hz"],
                                                                         r["top_frequency_hz"], r["explicit_step_s"]))
    return EXIT_OK


def _no_angle(model):
    raise Failure(EXIT_INPUT, "the model has %d revolute joint(s) (%s): give --angle with %d angle(s) in degrees, "
                  "comma-separated" % (len(model.revolute), ", ".join(model.revolute), len(model.revolute)))


def _angles(text):
    """The angles of one --angle value; 'none' (a model without revolute joints) is the empty configuration."""
    fix = "give finite angles in degrees, comma-separated for several revolute joints ('none' without any)"
    if text.strip().lower() in ("none", ""):
        return []
    try:
        angles = [float(x) for x in text.split(",")]
    except ValueError as e:
        raise Failure(EXIT_INPUT, "--angle %s: %s: %s" % (text, e, fix)) from None
    if not np.all(np.isfinite(angles)):
        raise Failure(EXIT_INPUT, "--angle %s: not a finite number: %s" % (text, fix))
    return angles


def _write_npz(path, arrays):
    """Writes arrays to path (.npz) through a staging folder beside it (io/files.py Staging): path is replaced only
    by a complete file, and a failure leaves nothing behind."""
    from ..io.files import Staging, remove_stale_staging
    folder, name = os.path.split(path)
    if os.path.isdir(path):
        raise Failure(EXIT_OUTPUT, "-o %s is a folder: give a file name (.npz)" % path)
    if not os.path.isdir(folder):
        raise Failure(EXIT_OUTPUT, "cannot write %s: %s is not an existing folder: choose another -o" % (path, folder))
    remove_stale_staging(folder)
    staging = Staging(folder)
    staging.create()
    try:
        # built in memory, then written: a failed write (disk full) leaves no half-closed zip archive behind to
        # complain when it is collected
        archive = io.BytesIO()
        np.savez(archive, **arrays)
        with open(staging.file(name), "wb") as fh:
            fh.write(archive.getbuffer())
        staging.commit()
    finally:
        staging.discard()
