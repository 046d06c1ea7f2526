"""kryflex slew SCENE -o OUTDIR: the slewing study (docs/guide/slewing.md): the scene reduced as `kryflex reduce` does, then the full-order
and the reduced model integrated in time along the same slews at increasing rates (python/kryflex/slew/); a scene
without revolute joints (a single structure) instead gets a step or pulse of force on its inputs, at rest, of
decreasing duration. Writes slew.csv, slew.md, slew.json, slew.png and slew_histories.png. The time integration is
serial: the command runs on one rank (under mpirun with more it refuses, exit 2)."""
import os
import sys

from .common import (EXIT_INPUT, EXIT_NUMERIC, EXIT_OK, EXIT_OUTPUT, Failure, Parser, checked_reducer, collective,
                     option_error, say, split_petsc_options)
from .reduce import HELP_FLAGS, cannot_write, staged_output


def parser():
    p = Parser(prog="kryflex slew",
               description="Time simulations of the full-order and the reduced model along slews of increasing rate: "
                           "the error of the output histories against the peak slew rate, and the rate at which the "
                           "reduced model stops meeting the scene's accuracy. A scene without revolute joints (a "
                           "single structure) has no angle to slew: it is held at rest and its inputs get a force "
                           "history (--profile step or pulse) of decreasing duration, with the same error measure "
                           "and files.")
    p.add_argument("scene", help="scene file (YAML)")
    p.add_argument("-o", "--output", required=True, help="output folder (created if needed)")
    p.add_argument("--profile", default=None, choices=("slew", "spinup", "step", "pulse"),
                   help="slew: rest to rest (cycloidal); spinup: up to a constant rate, then spinning; step: the "
                        "angles held and a force ramped up on the inputs in the rise time T (cycloidal), then held; "
                        "pulse: the same with a Hann pulse of length T (default: slew, or step for a scene without "
                        "revolute joints, which takes only step and pulse)")
    p.add_argument("--amplitude", type=float, default=None,
                   help="angle change of every revolute joint, deg (default: the span of the scene's angles)")
    p.add_argument("--force", type=float, default=1.0,
                   help="peak of the step or pulse on each driven input, in the inputs' units (default 1; the models "
                        "are linear: the relative errors do not depend on it)")
    p.add_argument("--input", default=None,
                   help="comma list of the inputs the drive torque (or the step or pulse) acts on (default: every "
                        "input of the scene)")
    p.add_argument("--rates", type=int, default=10,
                   help="number of slew durations, or step and pulse lengths (default 10)")
    p.add_argument("--periods-max", type=float, default=20.0,
                   help="slowest slew duration (longest input) in first flexible periods P1 (default 20)")
    p.add_argument("--periods-min", type=float, default=0.02,
                   help="fastest slew duration (shortest input) in first flexible periods P1 (default 0.02)")
    p.add_argument("--steps-per-period", type=int, default=20,
                   help="time steps per period of the band's top frequency (default 20)")
    p.add_argument("--settle-periods", type=float, default=2.0,
                   help="first flexible periods simulated after the slew or input (default 2)")
    p.add_argument("--no-step-check", dest="step_check", action="store_false",
                   help="skip the rerun of the fastest slew (shortest input) with half the step")
    p.add_argument("--exudyn-check", action="store_true",
                   help="also integrate the full model's fastest slew with Exudyn's solver on the same equations and "
                        "report the difference (dense constraint Jacobians: for small scenes)")
    p.add_argument("--exudyn-ffrf", action="store_true",
                   help="also slew the reduced bodies in Exudyn's nonlinear floating-frame formulation (driven by the "
                        "torque) for the slowest and the middle slew, and compare them with the full and the reduced "
                        "model along Exudyn's angle history (for small scenes)")
    p.add_argument("-quiet", "--quiet", action="store_true", help="no progress lines")
    return p


def run(argv):
    p = parser()
    if any(a in HELP_FLAGS for a in argv):
        say(p.format_help())
        return EXIT_OK
    args = collective(lambda: p.parse_args(split_petsc_options(
        argv, {"-o", "--output", "--input", "--profile", "--amplitude", "--force", "--rates", "--periods-max",
               "--periods-min", "--steps-per-period", "--settle-periods"},
        {"-quiet", "--quiet", "--no-step-check", "--exudyn-check", "--exudyn-ffrf"})))
    collective(_one_rank)
    from .. import _core
    from ..io.scene import SceneError, load_scene
    from ..slew import output
    from ..slew.study import SlewStudy

    def progress(msg):
        if not args.quiet:
            say("[kryflex slew] %s" % msg, sys.stderr)

    out = os.path.abspath(args.output)
    staging, created, clean_up = staged_output(out)
    committed = False
    try:
        scene = collective(lambda: load_scene(args.scene), (SceneError, EXIT_INPUT, str),
                           (_core.Error, EXIT_INPUT, lambda e: "%s: %s" % (args.scene, e)))
        progress("reducing %s" % scene.name)
        reducer = collective(lambda: checked_reducer(scene, quiet=True if args.quiet else None),
                             (SceneError, EXIT_INPUT, str), (_core.Error, EXIT_INPUT, lambda e: option_error(e, args.scene)))
        reduction = collective(reducer.reduce, (_core.Error, EXIT_NUMERIC, lambda e: "the reduction failed: %s" % e))
        frf_error = _frf_error(reducer)
        study = collective(lambda: SlewStudy(scene, reduction.model, args.profile, args.amplitude, args.periods_max,
                                             args.periods_min, args.rates, args.steps_per_period, args.settle_periods,
                                             progress=progress, inputs=None if args.input is None else
                                             [x.strip() for x in args.input.split(",") if x.strip()],
                                             force=args.force),
                           (ValueError, EXIT_INPUT, str))
        if study.held and args.exudyn_ffrf:
            collective(lambda: _no_ffrf(study.kind))
        rows = study.sweep()
        baseline = study.baseline()
        if baseline is not None:
            progress("no slew (angle held), the slowest torque: error %.3g" % baseline["error"])
        check = study.convergence() if args.step_check else None
        exudyn = None
        if args.exudyn_check:
            progress("the fastest slew by Exudyn's solver")
            exudyn = collective(study.exudyn_check, (ImportError, EXIT_INPUT, lambda e: "--exudyn-check: Exudyn is not "
                                                     "installed (%s): run scripts/setup" % e),
                                (Exception, EXIT_NUMERIC, lambda e: "--exudyn-check: Exudyn's solution failed: %s" % e))
        ffrf = None
        if args.exudyn_ffrf:
            progress("the reduced bodies in Exudyn's floating-frame formulation")
            ffrf = collective(study.exudyn_ffrf, (ImportError, EXIT_INPUT, lambda e: "--exudyn-ffrf: Exudyn is not "
                                                  "installed (%s): run scripts/setup" % e),
                              (Exception, EXIT_NUMERIC, lambda e: "--exudyn-ffrf: Exudyn's solution failed: %s" % e))
            for r in ffrf:
                progress("Exudyn FFRF, %.3g P1 (turn %.3g deg): reduced vs full %.3g, the reduction alone %.3g"
                         % (r["periods"], r["turn_deg"], r["exudyn_vs_full"], r["reduced_vs_full"]))
        limit = study.limit(rows)
        names = reduction.model.output_names

        def write():
            title = "%s: %s, full %d vs reduced %d dofs" % (scene.name, study.kind, study.full.dofs,
                                                            study.reduced.dofs)
            output.write_csv(rows, staging.file("slew.csv"), names)
            output.write_chart(rows, staging.file("slew.png"), title, study.accuracy, limit, frf_error, baseline,
                               reducer.accuracy_measure())
            output.write_histories(rows, staging.file("slew_histories.png"), title, names)
            output.write_json(rows, staging.file("slew.json"), study, limit, check, frf_error, baseline)
            with open(staging.file("slew.md"), "w") as f:
                f.write(output.markdown(rows, study, limit, check, frf_error, exudyn, baseline, ffrf,
                                        reducer.accuracy_measure()))
        collective(write, (OSError, EXIT_OUTPUT, lambda e: cannot_write(out, e.strerror or e, created)))
        collective(staging.commit, (OSError, EXIT_OUTPUT, lambda e: cannot_write(out, e.strerror or e, created)),
                   interruptible=False)
        committed = True
    finally:
        if not committed:
            clean_up()
    say("kryflex slew: %s" % _verdict(study, rows, limit))
    say("kryflex slew: reduced model's highest frequency %.4g Hz%s, stable explicit step %.3g s"
        % (study.top_hz, " (trimmed above %.4g Hz; untrimmed %.4g Hz)" % (study.trim_hz, study.untrimmed_top_hz)
           if study.trim_hz > 0 else "", study.explicit_step[0]))
    say("kryflex slew: results in %s (slew.csv, slew.md, slew.json, slew.png, slew_histories.png)" % out)
    return EXIT_OK


def _no_ffrf(kind):
    raise Failure(EXIT_INPUT, "--exudyn-ffrf slews the reduced bodies: --profile %s holds the angles (drop "
                              "--exudyn-ffrf)" % kind)


def _verdict(study, rows, limit):
    if study.held:
        who = "the structure's" if study.jointfree else "the held configuration's"
        return ("%s %s response: adequate for every input down to %.3g P1" % (who, study.kind, rows[-1]["periods"])
                if limit is None else "%s %s response: not adequate from an input of %.3g P1 (error %.3g > %g)"
                % (who, study.kind, limit["periods"], limit["error"], study.accuracy))
    return ("adequate at every rate up to %.4g deg/s" % rows[-1]["peak_rate_deg_s"] if limit is None
            else "not adequate from %.4g deg/s (error %.3g > %g)" % (limit["peak_rate_deg_s"], limit["error"],
                                                                     study.accuracy))


def _one_rank():
    from petsc4py import PETSc
    if PETSc.COMM_WORLD.getSize() > 1:
        raise Failure(EXIT_INPUT, "kryflex slew integrates in time on one rank (%d ranks given): run it without mpirun "
                                  "(or with -n 1)" % PETSc.COMM_WORLD.getSize())


def _frf_error(reducer):
    """The reduction's frequency-domain error (max over the angles of interest), or None when it was not verified."""
    import numpy as np
    values = []
    for c in range(reducer.nconfig):
        if "frf_error" in reducer.result_names(c):
            values.append(float(np.nanmax(reducer.result(c, "frf_error"))))
    values = [v for v in values if np.isfinite(v)]
    return max(values) if values else None
