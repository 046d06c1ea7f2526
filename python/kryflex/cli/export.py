"""kryflex export REDUCED -o OUT.npz [--format neutral|exudyn]: the reduced bodies for multibody codes."""
import json
import os
import sys

import numpy as np

from .common import (EXIT_INPUT, EXIT_MODEL, EXIT_NUMERIC, EXIT_OK, EXIT_OUTPUT, Failure, Parser, collective,
                     load_reduced_model, rank, say, split_petsc_options)
from .reassemble import _angles

FORMATS = ("neutral", "exudyn")
# Exudyn's linearized frequencies must equal kryflex's reassembled ones to this (relative, --format exudyn)
MATCH_TOL = 1e-6


def run(argv):
    p = Parser(prog="kryflex export",
               description="The reduced bodies for multibody codes: the neutral file (NumPy .npz; each body's reduced "
                           "matrices, and its floating frame when it has its 6 rigid motions), and with --format exudyn "
                           "the Exudyn system built from it and checked against kryflex's reassembly: floating-frame "
                           "bodies and their joints, or, for a structure without joints whose bodies do not all "
                           "float, its reassembled reduced system as one ObjectGenericODE2.")
    p.add_argument("reduced", help="reduced-model file (.h5) written by 'kryflex reduce'")
    p.add_argument("-o", "--output", required=True, help="the neutral export file to write (.npz)")
    p.add_argument("--format", default="neutral",
                   help="neutral (default): the file only; exudyn: also build the Exudyn system (one "
                        "ObjectFFRFreducedOrder per body, its joints; without joints and with a body lacking rigid "
                        "motions, one ObjectGenericODE2 of the reassembled system) and compare its linearized "
                        "frequencies with kryflex's at each --angle")
    p.add_argument("--angle", action="append",
                   help="with --format exudyn: angle(s) in degrees, comma-separated for several revolute joints; "
                        "repeat for more configurations (default: 0 for every joint)")
    p.add_argument("--scene", help="check that the reduced model comes from this scene")
    p.add_argument("--json", action="store_true", help="print the check's results as JSON")

    def parse():
        kept = split_petsc_options(argv, {"--angle", "--scene", "-o", "--output", "--format"},
                                   {"--json", "-h", "--help"})
        kept = [a + "=" + kept[i + 1] if a == "--angle" and i + 1 < len(kept) else a for i, a in enumerate(kept)
                if not (i > 0 and kept[i - 1] == "--angle")]
        args = p.parse_args(kept)
        if args.format not in FORMATS:
            raise Failure(EXIT_INPUT, "--format %s: unknown export format: use %s" % (args.format, " or ".join(FORMATS)))
        if args.angle and args.format != "exudyn":
            raise Failure(EXIT_INPUT, "--angle is for --format exudyn's check: add --format exudyn, or drop --angle")
        if not args.output.lower().endswith(".npz"):
            raise Failure(EXIT_INPUT, "-o %s: the export is a NumPy archive: give a file name ending in .npz"
                          % args.output)
        args.angles = [_angles(text) for text in args.angle] if args.angle else None
        return args
    args = collective(parse)

    from .. import _core
    from ..api import ModelFileError
    from ..export import ExportError, from_model, write_neutral
    from ..io.scene import SceneError

    def load():
        model = load_reduced_model(args.reduced, args.scene)
        return model, from_model(model, args.angles)
    model, data = collective(load, (ModelFileError, EXIT_MODEL, str), (SceneError, EXIT_INPUT, str),
                             (ExportError, EXIT_MODEL, lambda e: "%s: cannot export: %s" % (args.reduced, e)),
                             (_core.Error, EXIT_INPUT, lambda e: "%s: %s" % (args.scene, e)))
    results = None
    if args.format == "exudyn" and not data.floating and data.joints:
        body = next(b for b in data.bodies if not b.floating)
        collective(lambda: _refuse(EXIT_MODEL, "%s: cannot export to Exudyn: %s, and a scene with joints goes to Exudyn "
                                               "as floating-frame bodies, which need all 6; the neutral file holds it as "
                                               "reduced (drop --format exudyn)" % (args.reduced, body.why_not_floating())))
    if args.format == "exudyn" and not data.floating:
        results = collective(lambda: check_exudyn_system(data),
                             (ExportError, EXIT_NUMERIC, lambda e: "the Exudyn system: %s" % e))
    elif args.format == "exudyn":
        angles = args.angles or [[0.0] * len(data.revolute)]
        results = collective(lambda: check_exudyn(model, data, angles),
                             (ExportError, EXIT_NUMERIC, lambda e: "the Exudyn system: %s" % e))
    path = os.path.abspath(args.output)
    folder = os.path.dirname(path)

    def write():
        if os.path.isdir(path):
            raise Failure(EXIT_OUTPUT, "-o %s is a folder: give a file name (.npz)" % path)
        if not os.path.isdir(folder):
            raise Failure(EXIT_OUTPUT, "cannot write %s: %s is not an existing folder: choose another -o" % (path, folder))
        if rank() == 0:
            write_neutral(data, path)
    collective(write, (OSError, EXIT_OUTPUT, lambda e: "cannot write %s (%s): choose another -o, or free space on its "
                                                       "disk" % (path, e.strerror or e)))
    if args.json:
        say(json.dumps(dict(output=path, format=args.format, bodies=[b.name for b in data.bodies],
                            flexible_modes=[b.nflex for b in data.bodies], check=results,
                            max_frequency_hz=data.max_frequency_hz, trimmed_systems=len(data.systems),
                            coordinate_ties=0 if data.ties is None else int(data.ties.shape[0])), indent=1))
    else:
        say("kryflex: exported %d bod%s (%s) of '%s' to %s" % (
            len(data.bodies), "y" if len(data.bodies) == 1 else "ies",
            ", ".join(("%s: 6 rigid + %d flexible" % (b.name, b.nflex)) if b.floating else
                      ("%s: %d reduced dofs, no floating frame (no rigid %s)" % (b.name, b.M.shape[0],
                                                                                " ".join(b.missing_rigid)))
                      for b in data.bodies), data.scene, path))
        if data.ties is not None:
            say("  with %d coordinate ties between the bodies' flexible coordinates (shared directions: the file's "
                "ties, Exudyn's coordinate connectors)" % data.ties.shape[0])
        if data.systems and not data.max_frequency_hz:
            say("  the structure's reassembled reduced system in the file (system0/M, K, B, C, D): %d dofs, highest "
                "frequency %.4g Hz" % (data.systems[0]["M"].shape[0],
                                       float(np.max(data.systems[0]["frequencies_hz"], initial=0.0))))
        elif data.systems:
            say("  trimmed model (modes above %.4g Hz out of the dynamics): its fixed-angle systems at %s deg in the file "
                "(system<i>/M, K, B, C, D); highest frequency %.4g Hz, stable explicit step %.3g s"
                % (data.max_frequency_hz, "; ".join(",".join("%g" % a for a in sy["angles_deg"]) for sy in data.systems),
                   max(float(np.max(sy["frequencies_hz"], initial=0.0)) for sy in data.systems),
                   1.0 / (np.pi * max(float(np.max(sy["frequencies_hz"], initial=1e-300)) for sy in data.systems))))
        for r in results or []:
            say("  %s: %d flexible modes, max relative difference Exudyn vs kryflex %.2g (rigid/mechanism modes: "
                "Exudyn %d, kryflex %s)" % ("%s deg" % r["angles_deg"] if r["angles_deg"] else
                                            "the structure (ObjectGenericODE2)" if r.get("generic") else
                                            "no revolute joint", len(r["kryflex_hz"]), r["max_rel_diff"], r["exudyn_zero"],
                                            r["kryflex_rigid"]))
            say("    kryflex (Hz): " + " ".join("%.6g" % x for x in r["kryflex_hz"][:8]))
            say("    Exudyn  (Hz): " + " ".join("%.6g" % x for x in r["exudyn_hz"][:8]))
    return EXIT_OK


def _refuse(code, text):
    raise Failure(code, text)


def _warn_rigid_energy(lowest):
    """A rigid mode with negative energy (a stiffness rounded when exported) drifts away in a simulation: said once."""
    if lowest < 0:
        say("kryflex: warning: the Exudyn system's rigid-body modes carry the stiffness's rounding: lowest eigenvalue "
            "%.3g rad^2/s^2 (%.3g Hz imaginary), they drift in a simulation; `kryflex check SCENE` says what to do"
            % (lowest, np.sqrt(-lowest) / (2 * np.pi)), sys.stderr)


def check_exudyn_system(data):
    """A structure without joints whose bodies do not all float: its reassembled system (data.systems[0]) as one Exudyn
    ObjectGenericODE2, whose linearized frequencies must be kryflex's (a one-item list like check_exudyn's)."""
    from ..export.exudyn import linearized_frequencies
    from ..export.systems import system_mbs
    system = data.systems[0]
    _, mbs, _ = system_mbs(system, lambda t: 0.0)
    fx, nzero, low = linearized_frequencies(mbs, rigid=system.get("rigid_level", 0.0))
    _warn_rigid_energy(low)
    fk = np.asarray(system["frequencies_hz"], float)
    if len(fx) != len(fk):
        raise Failure(EXIT_NUMERIC, "the Exudyn system has %d flexible modes, kryflex's reassembled one %d: the export "
                      "does not reproduce the reduced model" % (len(fx), len(fk)))
    diff = float(np.max(np.abs(fx - fk) / fk)) if len(fk) else 0.0
    if diff > MATCH_TOL:
        raise Failure(EXIT_NUMERIC, "Exudyn's linearized frequencies differ from kryflex's by %.2g (relative; at most "
                      "%g expected)" % (diff, MATCH_TOL))
    rigid = system.get("rigid_modes")
    return [dict(angles_deg=[], generic=True, kryflex_hz=fk.tolist(), exudyn_hz=fx.tolist(), max_rel_diff=diff,
                 exudyn_zero=nzero, kryflex_rigid=rigid)]


def check_exudyn(model, data, angles_list):
    """Per configuration: kryflex's reassembled flexible frequencies, the Exudyn system's linearized ones, and their
    largest relative difference; a Failure when they differ by more than MATCH_TOL."""
    from ..export.exudyn import build_mbs, linearized_frequencies, rigid_level
    out = []
    for angles in angles_list:
        try:
            system = model.at(angles, trimmed=False)   # the floating-frame bodies are the untrimmed ones
        except ValueError as e:
            raise Failure(EXIT_INPUT, "--angle %s: %s" % (",".join("%g" % a for a in angles), e)) from None
        _, mbs, _ = build_mbs(data, angles)
        fx, nzero, low = linearized_frequencies(mbs, rigid=rigid_level(system.M, system.K, system.rigid_modes))
        _warn_rigid_energy(low)
        fk = np.asarray(system.frequencies_hz)
        if len(fx) != len(fk):
            raise Failure(EXIT_NUMERIC, "at %s deg the Exudyn system has %d flexible modes, kryflex's %d: the export "
                          "does not reproduce the reduced model" % (angles, len(fx), len(fk)))
        diff = float(np.max(np.abs(fx - fk) / fk)) if len(fk) else 0.0
        if diff > MATCH_TOL:
            raise Failure(EXIT_NUMERIC, "at %s deg Exudyn's linearized frequencies differ from kryflex's by %.2g "
                          "(relative; at most %g expected)" % (angles, diff, MATCH_TOL))
        out.append(dict(angles_deg=list(angles), kryflex_hz=fk.tolist(), exudyn_hz=fx.tolist(), max_rel_diff=diff,
                        exudyn_zero=nzero,
                        kryflex_rigid=None if system.rigid_modes is None else int(system.rigid_modes.shape[1])))
    return out
