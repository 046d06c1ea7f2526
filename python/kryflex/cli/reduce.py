"""kryflex reduce SCENE -o OUTDIR: reduce a scene, verify it, write the reduced model and the report (on the C reducer,
KFReducer: every -kf_ option applies; kryflex reduce -help lists them)."""
import os
import shutil

from .common import (EXIT_INPUT, EXIT_NUMERIC, EXIT_OK, EXIT_OUTPUT, Parser, error, from_rank0, rank, say,
                     split_petsc_options)


HELP_FLAGS = ("-h", "-help", "--help")


def parser():
    p = Parser(prog="kryflex reduce", description="Reduce a scene and verify the reduced model against the full order.",
               epilog="Every scene value can be overridden with -scene.<path> <value> (e.g. -scene.reduction.moments 12); "
                      "the reducer's own options (-kf_*, listed below with their defaults) override the scene.")
    p.add_argument("scene", help="scene file (YAML)")
    p.add_argument("-o", "--output", required=True, help="output folder (created if needed)")
    p.add_argument("--npz", action="store_true", help="also export the reduced bodies' arrays as NumPy .npz (kryflex reads only reduced.h5)")
    p.add_argument("-quiet", "--quiet", action="store_true", help="no progress lines (-kf_quiet)")
    return p


def print_help(p):
    """The command's usage, then the reducer's PETSc options with their defaults (KFReducerSetFromOptions under
    -help, on a reducer without a scene)."""
    say(p.format_help())
    from petsc4py import PETSc
    opts = PETSc.Options()
    added = not opts.hasName("help")
    if added:
        opts.setValue("help", True)      # before the binding starts: KFInitialize lists -kf_quiet then
    try:
        from ..reducer import print_options_help
        print_options_help()
    finally:
        if added:
            opts.delValue("help")
    return EXIT_OK


def run(argv):
    p = parser()
    if any(a in HELP_FLAGS for a in argv):
        return print_help(p)
    args = p.parse_args(split_petsc_options(argv, {"-o", "--output"}, {"--npz", "-quiet", "--quiet"}))
    from .. import _core
    from ..reducer import Reducer
    from ..report import write_report, write_unverified
    from ..io.scene import SceneError, load_scene

    out = os.path.abspath(args.output)
    created = _prepare_output(out)
    try:
        scene = load_scene(args.scene)
        reducer = Reducer(scene, quiet=True if args.quiet else None)   # the scene's settings, then the -kf_ options
    except SceneError as e:
        _cleanup(out, created)
        error(str(e))
        return EXIT_INPUT
    except _core.Error as e:     # a setting the reducer refuses (a scene value or a -kf_ option)
        _cleanup(out, created)
        error("%s: %s" % (args.scene, e))
        return EXIT_INPUT
    try:
        result = reducer.reduce()
    except _core.Error as e:
        _cleanup(out, created)
        error("the model cannot be reduced: %s" % e)
        return EXIT_NUMERIC
    # the report first, on rank 0 (it leaves nothing behind if it fails); then the model file, written by every rank
    # together (the C writer is collective and fails on every rank alike); a failure removes all
    written, problem = [], None
    try:
        if rank() == 0:
            report = write_report if result.summary["frf"] else write_unverified
            written.extend(report(result.summary, out))
    except OSError as e:
        problem = "cannot write the results to %s: %s" % (out, e)
    problem = from_rank0(problem)   # every rank exits with the same code
    if problem is None:
        try:
            written.append(result.model.save(os.path.join(out, "reduced.h5")))
            if args.npz and rank() == 0:
                written.append(result.model.export_npz(os.path.join(out, "reduced.npz")))
        except (OSError, _core.Error) as e:
            problem = "cannot write the results to %s: %s" % (out, e)
        problem = from_rank0(problem)
    if problem is not None:
        if rank() == 0:
            for path in written:
                if os.path.exists(path):
                    os.unlink(path)
        _cleanup(out, created)
        error(problem)
        return EXIT_OUTPUT
    s = result.summary
    say("kryflex: reduced '%s': %s reduced dofs per body (%s), alpha_G = %s deg, kept Krylov modes %s"
         % (s["scene"], " + ".join(str(v) for v in result.model.sizes), result.model.settings["method"],
            s["reduction_label"], s["kept_modes"]))
    errs = [v["max_rel_error"] for v in s["frf"].values()]
    if errs:
        say("kryflex: max relative frequency-response error over the band: %.3g (target %.3g)" % (max(errs), s["accuracy"]))
    say("kryflex: results in %s (reduced.h5, report.md, summary.json, plots)" % out)
    return EXIT_OK


def _prepare_output(out):
    """Creates the output folder if needed and checks it is writable before any long work; True if created here.
    Rank 0 decides and every rank learns the outcome: a rank that went on alone would wait forever in the
    reduction's collective calls."""
    created, problem = False, None
    if rank() == 0:
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
    created, problem = from_rank0((created, problem))
    if problem is not None:
        error(problem)
        raise SystemExit(EXIT_OUTPUT)
    return created


def _cleanup(out, created):
    if created and rank() == 0 and os.path.isdir(out) and not os.listdir(out):
        shutil.rmtree(out, ignore_errors=True)
