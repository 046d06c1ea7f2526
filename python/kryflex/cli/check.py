"""kryflex check SCENE: a cheap model health report before any reduction (check/__init__.py)."""
import json

from .common import EXIT_INPUT, EXIT_NUMERIC, EXIT_OK, Parser, collective, say, split_petsc_options


def run(argv):
    p = Parser(prog="kryflex check", description="A model health report before any reduction: rigid-body modes and "
                                                 "the energy K carries in them, symmetry of K and M, massless dofs, M's "
                                                 "rank, K's null pivots and condition, the verification's modes.")
    p.add_argument("scene")
    p.add_argument("--json", action="store_true", help="print the facts and findings as JSON")
    args = collective(lambda: p.parse_args(split_petsc_options(argv, set(), {"--json", "-h", "--help"})))
    from .. import _core
    from ..check import check_scene
    from ..io.scene import SceneError, load_scene
    scene = collective(lambda: load_scene(args.scene), (SceneError, EXIT_INPUT, str),
                       (_core.Error, EXIT_INPUT, lambda e: "%s: %s" % (args.scene, e)))
    facts, findings = collective(lambda: check_scene(scene), (_core.Error, EXIT_NUMERIC, str))
    if args.json:
        say(json.dumps(dict(facts=facts, findings=[f.as_dict() for f in findings]), indent=1))
        return EXIT_OK
    say("kryflex check '%s': %d system dofs, %d rigid-body and mechanism modes (residual %.1e)"
        % (scene.name, facts["system_dofs"], facts["rigid_modes"], facts["rigid_residual"]))
    say("  rigid-body energy of K (Rayleigh frequencies, Hz): %s" % (
        " ".join("%.3g" % x for x in facts["rigid_hz"]) or "no rigid modes"))
    for b in facts["bodies"]:
        say("  body %-16s %8d dofs  asymmetry K %.1e M %.1e  massless dofs %d  rigid energy (Hz) %s" % (
            b["name"], b["dofs"], b["asymmetry"]["K"], b["asymmetry"]["M"], b["massless_dofs"],
            " ".join("%.3g" % x for x in b["rigid_hz"]) or "-"))
    if "factor_null_pivots" in facts:
        say("  MUMPS factorization of K: %d null pivots, %d negative pivots (ICNTL(24) null-pivot detection: a cross-check, threshold-dependent)"
            % (facts["factor_null_pivots"], facts["factor_negative_pivots"]))
    if facts["dense"]:
        cond = facts["stiffness_condition"]
        say("  M rank %d of %d (%d zero-diagonal dofs); K: %d near-zero eigenvalues (null pivots), condition on its "
            "flexible part %s" % (facts["mass_rank"], facts["system_dofs"], facts["mass_zero_diagonal"],
                                  facts["stiffness_null"], "%.2e" % cond if cond else "infinite"))
        if facts.get("verification_modes") is not None:
            say("  verification: %d full-order modes below 3 x the band's top (%g Hz); first flexible frequency %.6g Hz"
                % (facts["verification_modes"], 3 * facts["band_hz"][1], facts["first_flexible_hz"] or float("nan")))
    else:
        say("  " + facts["dense_skipped"])
    if not findings:
        say("  no findings: the model is ready to reduce")
    for f in findings:
        say("  %s: %s" % (f.severity, f.text()))
    return EXIT_OK
