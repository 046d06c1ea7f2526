"""The kryflex command: reduce, reassemble, info, convert. Runs alone or under mpirun.

Exit codes: 0 done; 2 bad command line, scene or input file; 3 the model cannot be reduced (numerical failure,
e.g. an undeclared mechanism or an indefinite stiffness); 4 the output cannot be written; 5 a reduced-model file
that cannot be used (unreadable, or from another scene); 1 an internal error (a bug: please report it).
"""
import argparse
import json
import os
import shutil
import sys

import numpy as np

EXIT_OK, EXIT_INTERNAL, EXIT_INPUT, EXIT_NUMERIC, EXIT_OUTPUT, EXIT_MODEL = 0, 1, 2, 3, 4, 5

USAGE = """kryflex: Krylov reduction of articulated multi-flexible-body structures

  kryflex reduce SCENE -o OUTDIR        reduce a scene, verify it, write the reduced bodies and a report
  kryflex reassemble REDUCED --angle A  the reduced system at any angles, from the reduced-model file alone
  kryflex info SCENE                    bodies, dofs, joints, rigid and mechanism modes, inputs, outputs, memory
  kryflex convert INPUT --name NAME     import Matrix Market, NumPy .npz or Nastran DMIG (.pch) body matrices

PETSc options may follow (e.g. -log_view, -scene.damping 0.005, -scene.reduction.moments 12); -quiet silences
progress. Run under MPI as: mpirun -n 2 kryflex reduce SCENE -o OUTDIR. 'kryflex COMMAND -h' for details.
"""


def _rank():
    from petsc4py import PETSc
    return PETSc.COMM_WORLD.getRank()


def _say(msg, stream=sys.stdout):
    if _rank() == 0:
        print(msg, file=stream, flush=True)


def _error(msg):
    _say("kryflex: error: %s" % msg, sys.stderr)


def _split_petsc_options(argv, flags_with_value, flags):
    """Keeps the command's own arguments; PETSc options (already read by PETSc) are dropped with their values."""
    out, i = [], 0
    while i < len(argv):
        a = argv[i]
        if a.split("=", 1)[0] in flags_with_value and "=" in a:
            out.append(a)
            i += 1
            continue
        if a in flags_with_value:
            out.extend(argv[i:i + 2])
            i += 2
            continue
        if a in flags or not a.startswith("-") or a == "-" or _is_number(a):
            out.append(a)
            i += 1
            continue
        # a PETSc option: its value is the next token unless that is another option
        i += 1
        if i < len(argv) and (not argv[i].startswith("-") or _is_number(argv[i])):
            i += 1
    return out


def _is_number(s):
    try:
        float(s)
        return True
    except ValueError:
        return False


class _Parser(argparse.ArgumentParser):
    def error(self, message):
        _say("%s\nkryflex: error: %s" % (self.format_usage().rstrip(), message), sys.stderr)
        raise SystemExit(EXIT_INPUT)


def _cmd_reduce(argv):
    p = _Parser(prog="kryflex reduce", description="Reduce a scene and verify the reduced model against the full order.")
    p.add_argument("scene", help="scene file (YAML)")
    p.add_argument("-o", "--output", required=True, help="output folder (created if needed)")
    p.add_argument("--npz", action="store_true", help="also write the reduced bodies as NumPy .npz")
    p.add_argument("-quiet", "--quiet", action="store_true", help="no progress lines")
    args = p.parse_args(_split_petsc_options(argv, {"-o", "--output"}, {"--npz", "-quiet", "--quiet", "-h", "--help"}))
    from . import _core
    from .pipeline import reduce as run_reduce
    from .report import write_report, write_unverified
    from .scene import SceneError, load_scene

    out = os.path.abspath(args.output)
    created = _prepare_output(out)
    try:
        scene = load_scene(args.scene)
        result = run_reduce(scene, quiet=True if args.quiet else None)
    except SceneError as e:
        _cleanup(out, created)
        _error(str(e))
        return EXIT_INPUT
    except _core.Error as e:
        _cleanup(out, created)
        _error("the model cannot be reduced: %s" % e)
        return EXIT_NUMERIC
    written, problem = [], None
    try:
        if _rank() == 0:
            # the report first (it leaves nothing behind if it fails), then the model files; a failure removes all
            report = write_report if result.summary["frf"] else write_unverified
            written.extend(report(result.summary, out))
            written.append(result.model.save(os.path.join(out, "reduced.h5")))
            if args.npz:
                written.append(result.model.save(os.path.join(out, "reduced.npz")))
    except OSError as e:
        problem = "cannot write the results to %s: %s" % (out, e)
        for path in written:
            if os.path.exists(path):
                os.unlink(path)
    problem = _from_rank0(problem)   # every rank exits with the same code
    if problem is not None:
        _cleanup(out, created)
        _error(problem)
        return EXIT_OUTPUT
    s = result.summary
    _say("kryflex: reduced '%s': %s reduced dofs per body (%s), alpha_G = %s deg, kept Krylov modes %s"
         % (s["scene"], " + ".join(str(v) for v in result.model.sizes), result.model.settings["method"],
            s["reduction_label"], s["kept_modes"]))
    errs = [v["max_rel_error"] for v in s["frf"].values()]
    if errs:
        _say("kryflex: max relative frequency-response error over the band: %.3g (target %.3g)" % (max(errs), s["accuracy"]))
    _say("kryflex: results in %s (reduced.h5, report.md, summary.json, plots)" % out)
    return EXIT_OK


def _prepare_output(out):
    """Creates the output folder if needed and checks it is writable before any long work; True if created here.
    Rank 0 decides and every rank learns the outcome: a rank that went on alone would wait forever in the
    reduction's collective calls."""
    created, problem = False, None
    if _rank() == 0:
        if os.path.exists(out) and not os.path.isdir(out):
            problem = "output %s exists and is not a folder: choose another -o" % out
        elif not os.path.isdir(out):
            try:
                os.makedirs(out)
                created = True
            except OSError as e:
                problem = "cannot create the output folder %s: %s" % (out, e)
        if problem is None and not os.access(out, os.W_OK | os.X_OK):
            problem = "the output folder %s is not writable: choose another -o or fix its permissions" % out
    created, problem = _from_rank0((created, problem))
    if problem is not None:
        _error(problem)
        raise SystemExit(EXIT_OUTPUT)
    return created


def _from_rank0(value):
    """Rank 0's value on every rank (a no-op when run alone)."""
    from petsc4py import PETSc
    comm = PETSc.COMM_WORLD
    if comm.getSize() == 1:
        return value
    return comm.tompi4py().bcast(value, root=0)


def _cleanup(out, created):
    if created and _rank() == 0 and os.path.isdir(out) and not os.listdir(out):
        shutil.rmtree(out, ignore_errors=True)


def _cmd_reassemble(argv):
    p = _Parser(prog="kryflex reassemble",
                description="The reduced system at any angles from a reduced-model file alone (paper eq. 20-24).")
    p.add_argument("reduced", help="reduced-model file (.h5 or .npz) written by 'kryflex reduce'")
    p.add_argument("--angle", action="append", required=True,
                   help="angle(s) in degrees, comma-separated for several revolute joints; repeat for more configurations")
    p.add_argument("--scene", help="check that the reduced model comes from this scene")
    p.add_argument("-o", "--output", help="write the reassembled matrices (Mh, Kh, Gh, Hh per angle) to this .npz")
    p.add_argument("--json", action="store_true", help="print the results as JSON")
    p.add_argument("--modes", type=int, default=10, help="flexible frequencies to print (default 10)")
    kept = _split_petsc_options(argv, {"--angle", "--scene", "-o", "--output", "--modes"}, {"--json", "-h", "--help"})
    # '--angle -30,95' would read as an option to argparse: glue the value on
    kept = [a + "=" + kept[i + 1] if a == "--angle" and i + 1 < len(kept) else a for i, a in enumerate(kept)
            if not (i > 0 and kept[i - 1] == "--angle")]
    args = p.parse_args(kept)
    import time

    from .model import ModelFileError, ReducedModel
    from .scene import SceneError, load_scene
    try:
        model = ReducedModel.load(args.reduced)
        if args.scene:
            model.check_scene(load_scene(args.scene), args.reduced)
    except ModelFileError as e:
        _error(str(e))
        return EXIT_MODEL
    except SceneError as e:
        _error(str(e))
        return EXIT_INPUT
    results, arrays = [], {}
    for text in args.angle:
        try:
            angles = [float(x) for x in text.split(",")]
            t0 = time.perf_counter()
            Mh, Kh, Gh, Hh, rank, ratio, Phir = model.reassemble(angles)
            dt = time.perf_counter() - t0
        except ValueError as e:
            _error("--angle %s: %s" % (text, e))
            return EXIT_INPUT
        f = model.frequencies_hz(angles)
        results.append(dict(angles_deg=angles, dofs=int(Kh.shape[0]), constraint_rank=int(rank), sigma_ratio=float(ratio),
                            rigid_modes=None if Phir is None else int(Phir.shape[1]), seconds=dt,
                            frequencies_hz=[float(x) for x in f[:args.modes]]))
        key = "_".join("%g" % a for a in angles)
        arrays.update({"M_" + key: Mh, "K_" + key: Kh, "G_" + key: Gh, "H_" + key: Hh})
    if args.output:
        problem = _write_npz(args.output, arrays) if _rank() == 0 else None
        problem = _from_rank0(problem)
        if problem is not None:
            _error(problem)
            return EXIT_OUTPUT
    if args.json:
        _say(json.dumps(results, indent=1))
    else:
        for r in results:
            _say("angles %s deg: %d dofs (constraint rank %d, %s rigid/mechanism modes), reassembled in %.2f ms"
                 % (r["angles_deg"], r["dofs"], r["constraint_rank"], r["rigid_modes"], 1e3 * r["seconds"]))
            _say("  flexible frequencies (Hz): " + " ".join("%.6g" % x for x in r["frequencies_hz"]))
    return EXIT_OK


def _write_npz(path, arrays):
    """Writes arrays to path (.npz) under a temporary name renamed into place; None, or what went wrong."""
    from .files import atomic_path
    try:
        with atomic_path(path) as tmp:
            with open(tmp, "wb") as fh:
                np.savez(fh, **arrays)
        return None
    except OSError as e:
        return "cannot write %s: %s" % (path, e)


def _cmd_info(argv):
    p = _Parser(prog="kryflex info", description="What a scene holds and what reducing it will take.")
    p.add_argument("scene")
    args = p.parse_args(_split_petsc_options(argv, set(), {"-h", "--help"}))
    from . import _core
    from .scene import SceneError, load_scene
    try:
        scene = load_scene(args.scene)
        system = _core.CSystem(scene.cscene)
        system.set_angles(scene.angles_rad(scene.configurations[0]))
        _, residual = system.rigid_modes()
    except SceneError as e:
        _error(str(e))
        return EXIT_INPUT
    except _core.Error as e:
        _error(str(e))
        return EXIT_NUMERIC
    info = scene.info
    nnz = 0
    _say("scene '%s' (%s)" % (scene.name, scene.path))
    for b, name in enumerate(scene.body_names):
        M, K = scene.cscene.body_matrices(b)[:2]
        nz = int(K.getInfo(K.InfoType.GLOBAL_SUM)["nz_used"] + M.getInfo(M.InfoType.GLOBAL_SUM)["nz_used"])
        nnz += nz
        _say("  body %-16s %10d dofs %8d nodes  interfaces: %s" % (name, scene.body_dofs[b], len(scene.body_nodes[b][0]),
                                                                 ", ".join(scene.interfaces[b]) or "none"))
    for j in scene.joints:
        _say("  joint %-15s %-8s %s.%s -> %s.%s%s" % (j["name"], j["type"], scene.body_names[j["parent"]],
                                                   scene.interfaces[j["parent"]][j["parent_interface"]],
                                                   scene.body_names[j["child"]],
                                                   scene.interfaces[j["child"]][j["child_interface"]],
                                                   "  axis %s" % j["axis"] if j["type"] == "revolute" else ""))
    nr = 6 + len(scene.revolute)
    _say("  system: %d dofs; %d rigid-body and mechanism modes (6 + %d revolute); rigid-mode residual %.1e at %s deg"
         % (info["system_dofs"], nr, len(scene.revolute), residual, scene.label(scene.configurations[0])))
    _say("  inputs: %s" % ", ".join(scene.input_names))
    _say("  outputs: %s" % ", ".join(scene.output_names))
    _say("  angles of interest (deg): %s" % ", ".join(scene.label(c) for c in scene.configurations))
    _say("  band %g-%g Hz, damping %g, accuracy target %g, %d moments"
         % (scene.band[0], scene.band[1], scene.damping, scene.accuracy, int(scene.reduction["moments"])))
    c = len(scene.input_names) * (int(scene.reduction["moments"]) - int(scene.reduction["output_blocks"])) + \
        len(scene.output_names) * int(scene.reduction["output_blocks"])
    e = info["system_dofs"]
    base = 12 * 2 * nnz + 8 * e * (c + nr) * 3
    _say("  memory estimate: %.2g GiB for matrices and Krylov vectors, plus the MUMPS factor (typically 10-50 x the "
         "stiffness nonzeros for 3-D solids: %.2g-%.2g GiB)" % (base / 2**30, 10 * 12 * nnz / 2 / 2**30, 50 * 12 * nnz / 2 / 2**30))
    return EXIT_OK


def main(argv=None):
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] in ("-h", "--help", "help"):
        _say(USAGE)
        return EXIT_OK if argv else EXIT_INPUT
    cmd, rest = argv[0], argv[1:]
    if cmd == "convert":
        from .convert import main as convert_main
        return convert_main(rest)
    commands = {"reduce": _cmd_reduce, "reassemble": _cmd_reassemble, "info": _cmd_info}
    if cmd not in commands:
        _error("unknown command '%s': use reduce, reassemble, info or convert (kryflex -h)" % cmd)
        return EXIT_INPUT
    if "-quiet" in rest or "--quiet" in rest:
        from petsc4py import PETSc
        PETSc.Options().setValue("kryflex_quiet", True)
    try:
        return commands[cmd](rest)
    except SystemExit as e:
        return int(e.code or 0)
    except KeyboardInterrupt:
        _error("interrupted")
        return EXIT_INTERNAL
    except BrokenPipeError:
        # the reader went away (kryflex info ... | head): stop quietly, as command-line tools do
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_OK
    except Exception as e:  # noqa: BLE001 - a bug: say so plainly, with the trace for the report
        import traceback
        if _rank() == 0:
            traceback.print_exc()
        _error("internal error (%s: %s): please report it with the command line" % (type(e).__name__, e))
        return EXIT_INTERNAL
