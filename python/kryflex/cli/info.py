"""kryflex info SCENE: what a scene holds and what reducing it will take; kryflex info OUT (a results folder or its
summary.json): what a reduction found."""
import os

from .common import EXIT_INPUT, EXIT_NUMERIC, EXIT_OK, Parser, collective, say, split_petsc_options


def run(argv):
    p = Parser(prog="kryflex info", description="What a scene holds and what reducing it will take; given a results "
               "folder (or its summary.json), what the reduction found.")
    p.add_argument("scene", help="a scene file, or the folder 'kryflex reduce -o' wrote (or its summary.json)")
    args = collective(lambda: p.parse_args(split_petsc_options(argv, set(), {"-h", "--help"})))
    if os.path.isdir(args.scene) or args.scene.endswith(".json"):
        from ..results import Summary, SummaryError
        summary = collective(lambda: Summary.load(args.scene), (SummaryError, EXIT_INPUT, str))
        collective(lambda: describe_results(summary))
        return EXIT_OK
    from .. import _core
    from ..io.scene import SceneError, load_scene
    scene = collective(lambda: load_scene(args.scene), (SceneError, EXIT_INPUT, str),
                       (_core.Error, EXIT_INPUT, lambda e: "%s: %s" % (args.scene, e)))

    def rigid_modes():
        system = _core.CSystem(scene.cscene)
        system.set_angles(scene.angles_rad(scene.configurations[0]))
        Phi, residual = system.rigid_modes()[:2]
        return (Phi.getSize()[1] if Phi is not None else 0), residual
    nr, residual = collective(rigid_modes, (_core.Error, EXIT_NUMERIC, str))
    collective(lambda: describe(scene, nr, residual))
    return EXIT_OK


def describe(scene, nr, residual):
    """The description, on rank 0 (the matrices' nonzero counts are summed over the ranks)."""
    info = scene.info
    nnz = 0
    say("scene '%s' (%s)" % (scene.name, scene.path))
    for b, name in enumerate(scene.body_names):
        M, K = scene.cscene.body_matrices(b)[:2]
        nz = int(K.getInfo(K.InfoType.GLOBAL_SUM)["nz_used"] + M.getInfo(M.InfoType.GLOBAL_SUM)["nz_used"])
        nnz += nz
        say("  body %-16s %10d dofs %8d nodes  interfaces: %s" % (name, scene.body_dofs[b], len(scene.body_nodes[b][0]),
                                                                 ", ".join(scene.interfaces[b]) or "none"))
    for j in scene.joints:
        say("  joint %-15s %-8s %s.%s -> %s.%s%s" % (j["name"], j["type"], scene.body_names[j["parent"]],
                                                   scene.interfaces[j["parent"]][j["parent_interface"]],
                                                   scene.body_names[j["child"]],
                                                   scene.interfaces[j["child"]][j["child_interface"]],
                                                   "  axis %s" % j["axis"] if j["type"] == "revolute" else ""))
    where = " at %s deg" % scene.label(scene.configurations[0]) if scene.revolute else ""
    say("  system: %d dofs; %d rigid-body and mechanism modes (of 6 + %d revolute, before boundary conditions and "
        "dof layouts); rigid-mode residual %.1e%s" % (info["system_dofs"], nr, len(scene.revolute), residual, where))
    say("  inputs: %s" % ", ".join(scene.input_names))
    say("  outputs: %s" % ", ".join(scene.output_names))
    if scene.revolute:
        say("  angles of interest (deg): %s" % ", ".join(scene.label(c) for c in scene.configurations))
    else:
        say("  a single configuration (no revolute joint)")
    moments = scene.reduction["moments"]
    if moments in (None, "auto"):
        # the search tries up to moments_max: the memory estimate is for the largest basis it may build
        most = int(scene.reduction.get("moments_max", 24))
        moments_text = "moments auto (the search tries up to %d)" % most
    else:
        most = int(moments)
        moments_text = "%d moments" % most
    detailed = not getattr(scene, "damping_uniform", True) or getattr(scene, "damping_matrices", None)
    say("  band %g-%g Hz, %saccuracy target %g (relative H-inf error of the %s response per input/output pair), %s"
        % (scene.band[0], scene.band[1], "" if detailed else "damping %g, " % scene.damping, scene.accuracy,
           getattr(scene, "accuracy_measure", "elastic"), moments_text))
    if detailed:
        from ..report.sections import damping_text
        say("  damping: %s%s" % (damping_text(scene.damping_model),
                                 "; viscous damping matrices on " + ", ".join(scene.damping_matrices)
                                 if scene.damping_matrices else ""))
    if any(q != "displacement" for q in getattr(scene, "output_quantities", [])):
        say("  output quantities: %s" % ", ".join("%s %s" % (o, q) for o, q in zip(scene.output_names,
                                                                                   scene.output_quantities)))
    c = len(scene.input_names) * (most - int(scene.reduction["output_blocks"])) + \
        len(scene.output_names) * int(scene.reduction["output_blocks"])
    e = info["system_dofs"]
    base = 12 * 2 * nnz + 8 * e * (c + nr) * 3
    say("  memory estimate: %.2g GiB for matrices and Krylov vectors, plus the MUMPS factor (typically 10-50 x the "
         "stiffness nonzeros for 3-D solids: %.2g-%.2g GiB)" % (base / 2**30, 10 * 12 * nnz / 2 / 2**30, 50 * 12 * nnz / 2 / 2**30))


def describe_results(s):
    """A reduction's results from its summary (any summary version): the chosen model, its verdict and where the
    time went, on rank 0."""
    v, ch = s.verdict, s.chosen
    say("results of scene '%s'%s (summary version %d%s)" % (
        s.scene, " (%s)" % s.scene_file if s.scene_file else "", s.summary_version,
        ", kryflex %s" % s.kryflex_version if s.kryflex_version else ""))
    say("  angles of interest (deg): %s" % ", ".join(s.angle_labels))
    if ch is not None:
        say("  chosen: %s model, %s moments, %s reduced dofs (%s), %s system dofs at most" % (
            ch.method or v.chosen_method or "?", ch.moments if ch.moments is not None else "?", ch.dofs,
            ", ".join("%s %s" % kv for kv in (ch.dofs_per_body or {}).items()),
            max((d for d in (ch.system_dofs or {}).values() if d is not None), default="?")))
    if v.target_met is None:
        say("  accuracy target %s: not checked (no error measured or estimated)" % s.accuracy)
    else:
        where = ch.worst_where if ch is not None else None
        say("  accuracy target %g: %s; worst %s error %.3g%s (%s)" % (
            s.accuracy, "met" if v.target_met else "MISSED", v.accuracy_measure or "total", v.error_max,
            " at %s" % where if where is not None else "", "estimated" if v.error_estimated else "measured"))
    for c in s.configurations:
        if c.frf_error is not None:
            say("    %-12s error %.3g, %s system dofs" % (c.label, c.frf_error, c.system_dofs))
    for m in s.midpoints:
        if m.frf_error is not None:
            say("    %-12s error %.3g (midpoint)" % (m.label, m.frf_error))
    if s.search:
        say("  search: %d candidates evaluated%s" % (len(s.search), "" if s.search_chosen is None
                                                      else ", the chosen one row %d" % s.search_chosen))
    perf = s.performance
    if perf is not None and perf.whole_s is not None:
        say("  time: %.3g s in all, factorization %.3g s, solves %.3g s (%s solve calls)" % (
            perf.whole_s, perf.factorization_s or 0.0, perf.solves_s or 0.0, perf.solve_calls))
