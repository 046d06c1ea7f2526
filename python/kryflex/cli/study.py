"""kryflex study SCENE -o OUTDIR: the speed-accuracy study of a scene (docs/guide/accuracy.md): every method swept over its size
parameter on one full-order reference; writes study.csv, accuracy_vs_size.png, accuracy_vs_time.png and study.md.
Unless --no-estimator, also the check of the search's error estimator against the truth (study/estimator.py):
estimator.csv, estimate_vs_truth.png and a section of study.md; it reuses the kryflex run's search, so it costs one
more search, without the full-order reference.

Phases as in `kryflex reduce`: the command line, the output folder (refused before any long work), the scene, the
reference (the C reducer's full-order verification), the sweep, the files (rank 0, staged, moved into place
together). Every reduction is collective; rank 0 writes."""
import os
import sys

from . import common
from .common import (EXIT_INPUT, EXIT_NUMERIC, EXIT_OK, EXIT_OUTPUT, Failure, Parser, collective, rank,
                     say, split_petsc_options)
from .reduce import HELP_FLAGS, cannot_write, staged_output


def parser():
    from ..study.sweep import METHODS
    p = Parser(prog="kryflex study",
               description="Sweep every reduction method over its size on one full-order reference: error against "
                           "reduced size and against reduction time, kryflex's choice marked.",
               epilog="Methods: %s. PETSc and -scene.<path> options apply to every run." % ", ".join(METHODS))
    p.add_argument("scene", help="scene file (YAML)")
    p.add_argument("-o", "--output", required=True, help="output folder (created if needed)")
    p.add_argument("--cmax", type=common.nonnegative_int, default=30,
                   help="largest number of moments c of the fixed-c Krylov sweeps (default 30)")
    p.add_argument("--methods", default=None, help="comma list of the methods to run (default: all)")
    p.add_argument("--no-estimator", dest="estimator", action="store_false",
                   help="skip the check of the search's error estimator against the truth (the accuracy search run "
                        "with verify.full_order on and off, candidates joined: estimator.csv, estimate_vs_truth.png)")
    p.add_argument("-quiet", "--quiet", action="store_true", help="no progress lines")
    return p


def run(argv):
    p = parser()
    if any(a in HELP_FLAGS for a in argv):
        say(p.format_help())
        return EXIT_OK
    args = collective(lambda: _parse(p, argv))
    from .. import _core
    from ..io.scene import SceneError, load_scene
    from ..study import estimator_output, output
    from ..study.estimator import run_check
    from ..study.sweep import Study, features

    out = os.path.abspath(args.output)
    staging, created, clean_up = staged_output(out)
    committed = False
    try:
        # what the C library offers, read from the reducer's -help listing before any reducer reads its options
        # (the listing is read with the options given, so a bad -kf_ value is refused here already)
        flags = collective(features, (_core.Error, EXIT_INPUT, lambda e: common.option_error(e, args.scene)))
        scene = collective(lambda: load_scene(args.scene), (SceneError, EXIT_INPUT, str),
                           (_core.Error, EXIT_INPUT, lambda e: "%s: %s" % (args.scene, e)))
        # the scene's settings and the -kf_ options read and checked as the runs will read them (a reducer that is
        # not solved): a bad value or a misspelt option stops here, not as a failed run after the full-order reference
        collective(lambda: common.checked_reducer(scene, quiet=True, known=flags["option_names"]),
                   (SceneError, EXIT_INPUT, str), (_core.Error, EXIT_INPUT, lambda e: common.option_error(e, args.scene)))

        def progress(msg):
            if not args.quiet:
                say("[kryflex study] %s" % msg, sys.stderr)
        study = collective(lambda: Study(scene, args.cmax, args.methods, flags, progress),
                           (ValueError, EXIT_INPUT, str))
        progress("reference: the full-order verification at %d angle(s)" % len(scene.configurations)
                 if scene.revolute else "reference: the full-order verification of the structure (no revolute joint)")
        collective(study.run_reference,
                   (_core.Error, EXIT_NUMERIC, lambda e: "the full-order reference cannot be computed: %s" % e))
        rows = collective(lambda: list(study.sweep()),
                          (_core.Error, EXIT_NUMERIC, lambda e: "a study run failed: %s" % e))
        limit = collective(study.hankel_limit,
                           (_core.Error, EXIT_NUMERIC, lambda e: "the Hankel singular values failed: %s" % e))
        check, no_check = None, "skipped (--no-estimator)"
        if args.estimator and not flags["search"]:
            no_check = "the C library has no accuracy search (-kf_search) to estimate errors in"
        elif args.estimator:
            # a reduction that fails here is the check's finding (run_check), not the study's end
            check, no_check = collective(lambda: run_check(scene, study.default_run, progress))
        accuracy = study.accuracy      # the target the runs read: the scene's, or -kf_accuracy
        cannot = (OSError, EXIT_OUTPUT, lambda e: cannot_write(out, e.strerror or e, created))

        def write():
            if rank() == 0:
                output.write_csv(rows, staging.file("study.csv"))
                output.write_figures(rows, staging.path, scene.name, accuracy, limit)
                if check is not None:
                    estimator_output.write_csv(check.rows, staging.file(estimator_output.CSV_NAME))
                    estimator_output.write_figure(check.rows, staging.file(estimator_output.FIGURE_NAME), scene.name,
                                                  accuracy)
                common.raise_if_interrupted()
                sections = [estimator_output.markdown(check, no_check)] if args.estimator else []
                with open(staging.file("study.md"), "w") as f:
                    f.write(output.markdown(rows, scene.name, accuracy, study, limit, sections))
        collective(write, cannot)
        collective(lambda: staging.commit() if rank() == 0 else None, cannot, interruptible=False)
        committed = True
    finally:
        if not committed and rank() == 0:
            clean_up()
    chosen = [r for r in rows if r["method"] == "kryflex"]
    for method, (best, small) in output.best_rows(rows, accuracy).items():
        say("kryflex study: %-13s best error %-9s at %3s dofs; smallest meeting %g: %s" % (
            method, output._g(best["error_hinf"]), output._i(best["system_dofs"]), accuracy,
            "%s dofs (error %s, %s s)" % (output._i(small["system_dofs"]), output._g(small["error_hinf"]),
                                          output._g(small["seconds"])) if small else "none"))
    if chosen:
        c = chosen[0]
        say("kryflex study: kryflex's choice: %s dofs, error %s, exit code %d (%s)"
            % (output._i(c["system_dofs"]), output._g(c["error_hinf"]), c["exit_code"], c["note"] or c["failure"]))
    if args.estimator:
        say("kryflex study: %s" % estimator_output.console(check, no_check))
    say("kryflex study: results in %s (study.csv, study.md, accuracy_vs_size.png, accuracy_vs_time.png%s)"
        % (out, ", %s, %s" % (estimator_output.CSV_NAME, estimator_output.FIGURE_NAME) if check is not None else ""))
    return EXIT_OK


def _parse(p, argv):
    args = p.parse_args(split_petsc_options(argv, {"-o", "--output", "--cmax", "--methods"},
                                            {"-quiet", "--quiet", "--no-estimator"}))
    if args.methods is not None:
        args.methods = [m.strip() for m in args.methods.split(",") if m.strip()]
        from ..study.sweep import METHODS
        unknown = [m for m in args.methods if m not in METHODS]
        if unknown or not args.methods:
            raise Failure(EXIT_INPUT, "--methods %s: give a comma list of %s" % (",".join(unknown) or "(empty)",
                                                                                 ", ".join(METHODS)))
    if args.cmax < 1:
        raise Failure(EXIT_INPUT, "--cmax %d: give a number of moments >= 1" % args.cmax)
    return args
