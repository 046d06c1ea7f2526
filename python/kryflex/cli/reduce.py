"""kryflex reduce SCENE -o OUTDIR: reduce a scene, verify it, write the reduced model and the report (on the C reducer,
KFReducer: every -kf_ option applies; kryflex reduce -help lists them)."""
import os
import shutil
import sys

from . import common
from ..io.scene_schema import NO_JOINT_LABEL
from ..results import ModelCheck
from .common import (EXIT_INPUT, EXIT_NUMERIC, EXIT_OK, EXIT_OUTPUT, EXIT_TARGET, Failure, Parser, collective,
                     from_rank0, rank, say, split_petsc_options)


HELP_FLAGS = ("-h", "-help", "--help")


def parser():
    p = Parser(prog="kryflex reduce", description="Reduce a scene and verify the reduced model against the full order.",
               epilog="Every scene value can be overridden with -scene.<path> <value> (e.g. -scene.reduction.moments 12); "
                      "the reducer's own options (-kf_*, listed below with their defaults) override the scene.")
    p.add_argument("scene", help="scene file (YAML)")
    p.add_argument("-o", "--output", required=True, help="output folder (created if needed)")
    p.add_argument("--npz", action="store_true", help="also export the reduced bodies' arrays as NumPy .npz (kryflex reads only reduced.h5)")
    p.add_argument("-quiet", "--quiet", action="store_true", help="no progress lines (-kf_quiet)")
    p.add_argument("--pair-plots", action="store_true",
                   help="also a Bode plot per configuration and input/output pair (bode_<angle>deg_<output>_<input>.png)")
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
    from .. import _core
    try:
        from ..reducer import print_options_help
        print_options_help()
    except _core.Error as e:      # an option given beside -help with a value the reducer refuses
        raise Failure(EXIT_INPUT, common.option_error(e, "kryflex reduce -help"))
    finally:
        if added:
            opts.delValue("help")
    return EXIT_OK


def run(argv):
    p = parser()
    if any(a in HELP_FLAGS for a in argv):
        return print_help(p)
    args = collective(lambda: p.parse_args(split_petsc_options(argv, {"-o", "--output"}, {"--npz", "-quiet", "--quiet"})))
    from .. import _core
    from ..io.scene import SceneError, load_scene

    out = os.path.abspath(args.output)
    staging, created, clean_up = staged_output(out)
    ooc_folder_default(staging.path)
    committed = False
    pending = []        # the report begun, finished after the model file is written
    counting = []       # the certificate's count helper, while it runs
    try:
        scene = collective(lambda: load_scene(args.scene), (SceneError, EXIT_INPUT, str),
                           (_core.Error, EXIT_INPUT, lambda e: "%s: %s" % (args.scene, e)))
        # the model check (kryflex check): its warnings before any work, also under -quiet
        health, checked = collective(lambda: model_check(scene))
        for f in (health[1] if health else []):
            if f.severity == "warning" and not f.refused:
                say("kryflex: warning: %s" % f.text(), sys.stderr)

        # the scene's settings, then the -kf_ options; checked here, before the solve, on every rank
        reducer = collective(lambda: common.checked_reducer(scene, quiet=True if args.quiet else None),
                             (SceneError, EXIT_INPUT, str),
                             (_core.Error, EXIT_INPUT, lambda e: common.option_error(e, args.scene)))
        # every rank, with or without a checked system (collective); the reducer's reference is then the system's last
        collective(lambda: reducer.start_from(checked), (_core.Error, EXIT_NUMERIC, str))
        checked = None
        if rank() == 0 and reducer.verification_plan()[0]:
            # the figures compare with the full order: their helper processes, where cores are free, load matplotlib
            # while the reduction runs (report/helper.py). An estimated verdict (-kf_verify false, or auto's certified
            # estimate from -kf_verify_certified_min_dofs on) draws none, and helpers started for it would only take
            # the core the reduction's factorizations run on; where the certificate fails, the report starts its own
            from ..report.formatting import MAX_PAIRS_PER_FIGURE, pair_name
            from ..report.helper import start_helpers
            pairs = [pair_name(o, i) for o in scene.output_names for i in scene.input_names]
            start_helpers(ranks=common.size(), prepare={
                "band_hz": list(scene.band), "configurations": len(scene.configurations),
                "pairs": pairs if len(pairs) <= MAX_PAIRS_PER_FIGURE else []})
        if common.size() == 1:
            # the certificate's count beside the reduction, on a free core (count_helper.py)
            from .. import count_helper
            counting.append(count_helper.start(reducer, args.scene, staging.path, common.size()))
        result = collective(reducer.reduce, (_core.Error, EXIT_NUMERIC, lambda e: "the model cannot be reduced: %s" % e))
        if counting and counting[0] is not None:
            rss = counting.pop().stop()      # its counts are taken: its memory freed before the report
            if result.summary.performance is not None:
                result.summary.performance.certificate_count_helper_rss_mb = rss

        s = result.summary
        if health:
            s.model_check = ModelCheck(facts=health[0], findings=[f.as_dict() for f in health[1]])
        if getattr(scene, "paper", None) and scene.verify["full_order"]:
            # the paper's example (paper: lee): its tables beside kryflex's, computed in the paper's fixed recipe
            # (compared with the full order: without it, verify.full_order false, the short report has no section)
            from ..paper import paper_block
            s.paper = collective(lambda: paper_block(scene, s),
                                    (_core.Error, EXIT_NUMERIC, lambda e: "the paper's recipe failed: %s" % e))
        met, worst, where = target(result)
        s.verdict.target_met = met
        _core.progress("writing the results to %s" % out)
        cannot = (OSError, EXIT_OUTPUT, lambda e: cannot_write(out, e.strerror or e, created))
        cannot_c = (_core.Error, EXIT_OUTPUT, lambda e: cannot_write(out, model_write_error(e, staging.path), created))

        def begin_report_files():
            # rank 0 alone: the report and the NumPy export (the model file below is written by every rank together)
            if rank() == 0:
                from ..report import begin_report, write_unverified
                # the full report compares with the full order; without it (verify.full_order: false, errors
                # estimated against the richest candidate) the short report with the estimated verdict
                if s.frf and not s.verdict.error_estimated:
                    # its figures drawn by the helpers while the model file is written, then finished below
                    pending.append(begin_report(s, staging.path, between=common.raise_if_interrupted,
                                                pair_plots=args.pair_plots))
                else:
                    write_unverified(s, staging.path)

        def finish_report_files():
            if rank() == 0:
                if pending:
                    pending.pop().finish()
                if health:
                    append_check_section(staging.file("report.md"), health[1])
                if args.npz:
                    result.model.export_npz(staging.file("reduced.npz"))
        collective(begin_report_files, cannot)
        collective(lambda: result.model.save(staging.file("reduced.h5")), cannot, cannot_c)
        collective(finish_report_files, cannot)
        # the results are complete: a signal from here on no longer undoes them
        collective(lambda: staging.commit() if rank() == 0 else None, cannot, interruptible=False)
        committed = True
    finally:
        for helper in counting:
            if helper is not None:
                helper.stop()
        if rank() == 0 and "kryflex.report.helper" in sys.modules:
            for report in pending:
                report.stop()
            sys.modules["kryflex.report.helper"].stop_helpers()     # those no report took
        if not committed and rank() == 0:
            clean_up()
    say("kryflex: reduced '%s': %s" % (s.scene, chosen_text(result)))
    say("kryflex: results in %s (reduced.h5, report.md, summary.json, plots)" % out)
    if s.chosen is not None and s.chosen.static_exact is False:
        from ..report.sections import static_moment_text
        say("kryflex: %s" % static_moment_text(s.chosen))
    trim = s.reduced.trimming if s.reduced else None
    if trim is not None and trim.top_frequency_hz_max:
        say("kryflex: highest reduced frequency %.4g Hz (%s), stable explicit step %.3g s (2 / omega_max)"
            % (trim.top_frequency_hz_max, "modes above %.4g Hz trimmed, static share kept" % trim.max_frequency_hz
               if trim.max_frequency_hz else "no trimming: reduction.max_frequency", trim.explicit_step_s_min))
    if met is None:
        say("kryflex: the accuracy target %g was not checked: no error was measured or estimated "
            "(verify.full_order: false and no estimate)" % s.accuracy)
        return EXIT_OK
    solves_inexact(s)
    how = how_text(s.verdict)
    measure = s.verdict.accuracy_measure or "total"
    say("kryflex: max relative %s-response error (relative H-inf per input/output pair, %s model, %s): "
        "%.3g%s (target %.3g)%s" % (measure, s.verdict.chosen_method or result.model.settings["method"], how,
                                    worst, at_text(where), s.accuracy, where_text(s) + inexact_text(s)))
    if not met:
        say("kryflex: target missed: max relative %s-response error %.3g%s > accuracy %.3g"
            % (measure, worst, at_text(where), s.accuracy), sys.stderr)
        return EXIT_TARGET
    return EXIT_OK


def how_text(verdict):
    """How the verdict's error was obtained, for its line: measured, estimated and certified, or estimated only."""
    if not verdict.error_estimated:
        return "measured against the full order"
    cert = verdict.certificate
    if verdict.verdict_kind == "certified" and cert:
        counts = sorted(set(cert["full_counts"]))
        n = str(counts[0]) if len(counts) == 1 else "%d-%d" % (counts[0], counts[-1])
        return ("estimated, certified (%s modes below %.4g Hz at every angle, counted)" % (n, cert["below_hz"]))
    return "estimated, verify.full_order: false"


def at_text(label):
    """' at 30 deg' for a configuration's label; nothing for the one configuration of a scene without revolute joints."""
    return "" if label == NO_JOINT_LABEL else " at %s deg" % label


def model_check(scene):
    """((facts, findings) of kryflex check on the loaded scene, the system it checked: a CSystem assembled at the first
    configuration with its rigid modes, which the reduction starts from instead of making them again), or (None, None)
    when the check itself cannot run (a model the reducer will refuse with its own message: the rigid modes or the
    assembly fail)."""
    from .. import _core
    from ..check import REDUCE_DENSE_MAX, check_scene
    try:
        system = _core.CSystem(scene.cscene)
        system.set_angles(scene.angles_rad(scene.configurations[0]))
        return check_scene(scene, system=system, factor=False, dense_max=REDUCE_DENSE_MAX), system
    except _core.Error:
        return None, None


def append_check_section(path, findings):
    """The model check's findings as the report's last section."""
    lines = ["", "## Model check", ""]
    if not findings:
        lines.append("No findings: rigid-body energy, symmetry, massless dofs and null pivots as expected.")
    for f in findings:
        lines.append("- **%s** (%s): %s. *Effect:* %s. *Fix:* %s." % (f.where, f.severity, f.what, f.effect, f.fix))
    with open(path, "a", encoding="utf-8") as fh:
        fh.write("\n".join(lines) + "\n")


def chosen_text(result):
    """The chosen model in words: method, moments, kept set, sizes."""
    s = result.summary
    ch = s.chosen
    method = s.verdict.chosen_method or result.model.settings["method"]
    parts = ["%s model" % method]
    if ch is not None and ch.moments is not None:
        parts.append("%d moments" % ch.moments)
    if method == "multi-angle" and ch is not None and ch.expansion_angles_deg:
        parts.append("expansion angles %s deg" % ", ".join(
            "/".join("%g" % a for a in (c if isinstance(c, list) else [c])) for c in ch.expansion_angles_deg))
    elif s.reduction_label == NO_JOINT_LABEL:
        parts.append("one configuration (no revolute joint)")
    else:
        parts.append("alpha_G = %s deg" % s.reduction_label)
    if ch is None or ch.kept_modes is not None:
        parts.append("kept Krylov modes %s" % (ch.kept_modes if ch is not None else s.kept_modes))
    elif ch.kept_clusters == "per body":
        parts.append("each body its share of the mode clusters")
    elif ch.kept_clusters is not None:
        parts.append("%d kept mode clusters" % ch.kept_clusters)
    else:
        parts.append("every mode kept")
    system = [v for v in (ch.system_dofs if ch is not None else {}).values() if v is not None]
    parts.append("%s reduced dofs per body%s" % (" + ".join(str(v) for v in result.model.sizes),
                                                  ", %d system dofs at most" % max(system) if system else ""))
    return ", ".join(parts)


def _unconverged(s):
    """Block solves left above -kf_refine_rtol after refinement and escalation (0 when not recorded)."""
    return (s.performance.blocks_unconverged if s.performance is not None else None) or 0


def solves_inexact(s):
    """Block solves left above -kf_refine_rtol after refinement and escalation are never silent: one line (printed
    under -quiet too) saying how many, and what the verdict then rests on."""
    bad = _unconverged(s)
    if not bad:
        return
    check = s.verdict.reference_check
    rests = ("the full-order reference, checked against solves of the full system (worst disagreement %.1e), measures the "
             "model" % check.error) if check is not None and check.error is not None else (
             "the error is estimated from inexact vectors: verify against the full order (verify.full_order: true)")
    say("kryflex: warning: %d block solves stayed above -kf_refine_rtol after refinement and escalation (largest "
        "final residual %.1e); %s" % (bad, s.performance.residual_final_max or float("nan"), rests), sys.stderr)


def inexact_text(s):
    """'; N block solves inexact (...)' on the verdict's line when block solves stayed above -kf_refine_rtol."""
    bad = _unconverged(s)
    return "; %d block solves inexact (warning above)" % bad if bad else ""


def where_text(s):
    """', a midpoint between angles of interest' when the worst error is at a midpoint."""
    if s.chosen is not None and s.chosen.worst_kind == "midpoint":
        return ", a midpoint between two angles of interest"
    return ""


def target(result):
    """(met, worst error, where: an angle label or a midpoint's) of the model the reducer chose, from the C results:
    met is target_met (KFReducer: the chosen model's relative H-inf error per input/output pair at every angle of
    interest and every midpoint, measured or estimated), worst is error_max; met is None when the reducer recorded
    no verdict (no error measured or estimated)."""
    s = result.summary
    met, worst = s.verdict.target_met, s.verdict.error_max
    if met is None or worst is None:
        return None, None, None
    where = s.chosen.worst_where if s.chosen is not None else None
    return bool(met), worst, where if where is not None else "?"


def staged_output(out):
    """The staging folder of an output folder, made before any long work so that an output that cannot be written is
    refused first; every rank knows its name (the model file is written by every rank together). Returns (Staging,
    whether the output folder was created, clean_up): clean_up removes what this run made, and runs too when one rank
    ends the run alone (MPI_Abort)."""
    from ..io.files import Staging
    common.interrupt_note = ": results in %s left as they were" % out
    prepared = {}

    def prepare():
        if rank() == 0:
            prepared["created"], prepared["path"] = _prepare_output(out)
    try:
        collective(prepare)
    except SystemExit:
        if prepared:
            Staging(out, prepared["path"]).discard()
            if prepared["created"]:
                _remove_if_empty(out)
        raise
    created, path = from_rank0((prepared.get("created"), prepared.get("path")))
    staging = Staging(out, path)

    def clean_up():
        staging.discard()
        if created:
            _remove_if_empty(out)
    common.before_abort.append(clean_up)
    return staging, created, clean_up


def ooc_folder_default(path):
    """An out-of-core factorization writes its factors under the output's staging folder (its own folder per rank,
    removed with the factor, and with the staging folder when the run fails), unless the user chose the folder:
    -kf_ooc_dir, or MUMPS_OOC_TMPDIR in the environment."""
    from petsc4py import PETSc
    opts = PETSc.Options()
    if not opts.hasName("kf_ooc_dir") and not os.environ.get("MUMPS_OOC_TMPDIR"):
        opts.setValue("kf_ooc_dir", path)


def _prepare_output(out):
    """Rank 0: the output folder (created if needed: True if created here) and a new staging folder inside it, after
    removing stale ones; a Failure (EXIT_OUTPUT) when the folder cannot be written."""
    from ..io.files import Staging, remove_stale_staging
    created = False
    if os.path.exists(out) and not os.path.isdir(out):
        raise Failure(EXIT_OUTPUT, "output %s exists and is not a folder: choose another -o" % out)
    if not os.path.isdir(out):
        try:
            os.makedirs(out)
            created = True
        except OSError as e:
            raise Failure(EXIT_OUTPUT, "cannot create the output folder %s: %s: choose another -o"
                          % (out, e.strerror or e)) from None
    remove_stale_staging(out)
    try:
        path = Staging(out).create()
    except OSError as e:
        if created:
            _remove_if_empty(out)
        raise Failure(EXIT_OUTPUT, "the output folder %s is not writable (%s): choose another -o or fix its "
                      "permissions" % (out, e.strerror or e)) from None
    return created, path


def cannot_write(out, why, created):
    """The message of a failed write of the results: nothing of this run is left, earlier results are as they were."""
    return "cannot write the results to %s: %s: free space on its disk or choose another -o (%s)" % (
        out, why, "nothing was left there" if created else "its earlier contents are left as they were")


def model_write_error(e, staging):
    """The C writer's message, as said of the output folder: the file by its name in it (not in the staging folder
    that is removed), without the writer's own advice (cannot_write gives the command's)."""
    text = str(e).replace(os.path.join(staging, ""), "")
    return text.split("; the previous file, if any, is unchanged")[0]


def _remove_if_empty(out):
    if os.path.isdir(out) and not os.listdir(out):
        shutil.rmtree(out, ignore_errors=True)
