"""report.md: one function per section: the scene, the verdict on the chosen model (its accuracy, how it was chosen),
then the paper's study (Tables 1-6, Fig. 3). Sections are numbered in render_markdown (optional ones may be absent).

One error measure decides: the relative H-infinity error per input/output pair of the CHOSEN model (summary
"chosen"/"frf_error", schema.py), at the angles of interest and at the midpoints between them. The pointwise error is
shown in its own table, labelled as information, never beside the verdict."""
import numpy as np

from . import plots
from .context import _Context
from .formatting import (DASH, MAX_MISMATCHES_LISTED, RATIO_EXACT_TOL, decade_scale, fmt_freq, fmt_general,
                         fmt_percent, fmt_ratio, mode_ranges, table)
from .paper import section_paper
from .schema import _get

ERROR_TEXT = "relative H∞ error per input/output pair over the band"


def _error_text(s):
    """the verdict's measure in words, naming the response it is of (the verdict's accuracy_measure; s: the
    Summary or its JSON dict)"""
    measure = s.verdict.accuracy_measure if hasattr(s, "verdict") else s.get("accuracy_measure")
    return f"relative H∞ error of the {measure} response per input/output pair over the band" if measure else ERROR_TEXT
INFO_TEXT = "information only, not the verdict"


def _fmt_error(x):
    return DASH if x is None else f"{x:.3g}"


def _verdict(err, accuracy):
    if err is None or accuracy is None:
        return DASH
    return "PASS" if err <= accuracy else "MISS"


def _where_text(c, where, kind):
    if where is None:
        return DASH
    if kind == "midpoint":
        return f"the midpoint {where}°"
    return c.angle(where)


def _angles_text(config):
    """[30] -> '30°'; [0, 30] -> '(0°, 30°)'."""
    values = config if isinstance(config, (list, tuple)) else [config]
    text = ", ".join(f"{v:g}°" for v in values)
    return text if len(values) == 1 else f"({text})"


def _no_angles(value):
    """True for the configurations of a scene without revolute joints: a list of empty angle lists ([[]])."""
    return isinstance(value, (list, tuple)) and len(value) > 0 and all(
        isinstance(a, (list, tuple)) and len(a) == 0 for a in value)


def _chosen_sentence(c):
    """The chosen model in one sentence: method, moments, kept set, sizes."""
    s, ch = c.summary, c.chosen
    parts = [f"The chosen model is the **{c.model_name}**"]
    if ch.moments is not None:
        parts.append(f"c = {ch.moments} moments")
    if ch.method == "multi-angle" and ch.expansion_angles_deg:
        parts.append("expansion angles " + ", ".join(_angles_text(a) for a in ch.expansion_angles_deg))
    elif c.no_joint(s.reduction_label):
        parts.append("one configuration (no revolute joint)")
    elif s.reduction_label is not None:
        parts.append(f"α_G = {s.reduction_label}°")
    if ch.kept_modes is not None:
        parts.append(f"kept Krylov modes {mode_ranges(ch.kept_modes)}")
    elif ch.kept_clusters == "per body":
        parts.append("each body its share of the mode clusters")
    elif ch.kept_clusters is not None:
        parts.append(f"{ch.kept_clusters} kept mode clusters")
    elif "kept_clusters" not in ch.absent:
        parts.append("every mode kept")
    sizes = ch.dofs_per_body or {}
    if sizes:
        parts.append("body sizes " + ", ".join(f"{b} {v}" for b, v in sizes.items())
                     + f" ({ch.dofs if ch.dofs is not None else sum(sizes.values())} dofs in all)")
    system = [v for v in (ch.system_dofs or {}).values() if v is not None]
    if system:
        parts.append(f"{max(system)} system dofs at most after reassembly")
    points = ch.expansion_points_hz or []
    if points:   # docs/guide/expansion-points.md: their blocks beside those at zero, one factorization each
        parts.append("expansion points inside the band at " + ", ".join(f"{f:.4g}" for f in points)
                     + f" Hz ({ch.expansion_point_factorizations or 0} factorizations of K - sigma M"
                     + " beside those at zero)")
    before, after = ch.compressed_from_dofs, ch.compressed_to_dofs
    if before is not None and after is not None:   # docs/guide/expansion-points.md, "Compression"
        how = "tied across the bodies" if ch.compressed_tied else "body by body"
        parts.append(f"compressed {how} from {before} to {after} reduced dofs" if after < before
                     else f"compression tried, no direction could go ({before} reduced dofs)")
    if ch.static_exact is False:
        parts.append(static_moment_text(ch))
    return parts[0] + ": " + "; ".join(parts[1:]) + "." if len(parts) > 1 else parts[0] + "."


def static_moment_text(ch):
    """The chosen model's static moment in words when the compression did not keep it exact (-kf_static_exact
    false): its measured error, never "exact"."""
    errors = [e for e in (ch.static_moment_error or {}).values() if e is not None]
    worst = f"{max(errors):.2g}" if errors else "not measured"
    return ("the static moment L⁰ not kept exact (reduction.static_exact: false), its largest relative error at the "
            f"angles of interest {worst}, measured")


def _row_name(c, label):
    """The angle, marked α_G only when the chosen model is the single-angle one (α_G is its expansion angle)."""
    return c.short_angle(label) if c.model_name.startswith("single") else c.angle(label)[4:]


def _certified_text(verdict):
    """The certified estimate's sentence: what was counted and what that proves."""
    cert = verdict.certificate or {}
    counts = sorted(set(cert.get("full_counts") or [0]))
    n = str(counts[0]) if len(counts) == 1 else "%d to %d" % (counts[0], counts[-1])
    return ("It is **estimated** against the search's richest candidate and **certified** by the mode count "
            "(`verify.full_order: auto`): at every angle of interest and midpoint the full order has %s flexible "
            "modes below %.4g Hz (Sylvester's inertia) and the richest candidate as many, so it lacks none of them; "
            "the count does not bound the estimate's own error." % (n, cert.get("below_hz") or 0))


def _floored_text(c, floored):
    """The pairs measured against a floor instead of their own peak (summary floored_pairs), per angle of interest;
    empty when none was."""
    what = {"largest_pair": "below 1e-4 of the largest pair's peak, measured against 1e-4 x that peak",
            "own_total": "elastic peak below 1e-6 of their own total peak (the rigid part's rounding), measured "
                         "against 1e-6 x the total peak"}
    parts = []
    for label in c.labels:
        block = (floored or {}).get(label) or {}
        for kind, text in what.items():
            pairs = block.get(kind) or []
            if pairs:
                parts.append(f"{_row_name(c, label)}: " + ", ".join(f"{o}/{i}" for o, i in pairs) + f" ({text})")
    return ("Pairs (output/input) whose error is measured against a floor, their own peak negligible: "
            + "; ".join(parts) + ".") if parts else ""


def _section_accuracy(c):
    s, verdict = c.summary, c.summary.verdict
    accuracy = s.accuracy
    estimated = bool(verdict.error_estimated)
    lines = ["## Accuracy of the chosen model", "", _chosen_sentence(c), ""]
    lines += [f"Error measure (the verdict): the {verdict.error_definition or ERROR_TEXT}. "
              + (_certified_text(verdict) if estimated and verdict.verdict_kind == "certified" else
                 "It is **estimated** by the a-posteriori estimator (the full-order verification was off: "
                 "`verify.full_order: false`), not measured." if estimated else
                 "It is **measured** against the full-order model "
                 + ("of the structure" if c.no_joint(c.label_g) else "at every angle of interest")
                 + (" and at every midpoint between consecutive ones." if s.midpoints else ".")), ""]
    measure = (f"relative H∞ error ({verdict.accuracy_measure})" if verdict.accuracy_measure
               else "relative H∞ error")
    measure += " (estimated)" if estimated else ""
    rows, judged, passed = [], 0, 0
    for label in c.labels:
        err = c.chosen_error(label)
        result = _verdict(err, accuracy)
        judged += result != DASH
        passed += result == "PASS"
        rows.append([_row_name(c, label), "one configuration" if c.no_joint(label) else "angle of interest",
                     _fmt_error(err), _fmt_error(accuracy), result])
    for m in s.midpoints or []:
        result = _verdict(m.frf_error, accuracy)
        judged += result != DASH
        passed += result == "PASS"
        rows.append([f"{m.label}°", "midpoint", _fmt_error(m.frf_error), _fmt_error(accuracy), result])
    lines += [f"Table 7. The {c.model_name}'s {_error_text(s)} against the accuracy target, "
              + ("of the structure." if c.no_joint(c.label_g) else "at the angles of interest and the midpoints between them."), "",
              table(["configuration", "where", measure, "target", "result"], rows, "llrrl"), ""]
    floored = _floored_text(c, verdict.floored_pairs)
    if floored:
        lines += [floored, ""]
    check = verdict.reference_check
    if check is not None and check.error is not None:
        if check.iterative_points:   # src/verify/refined_check.c
            how = (f"The truth was iterated from the reference itself with the reduction's own factorizations at "
                   f"{check.iterative_points} angles and midpoints ({check.iterative_steps_max} steps at most)"
                   + (f"; {check.fallbacks} did not converge and were solved directly" if check.fallbacks else "")
                   + (f" ({check.factorizations} numerical factorizations)." if check.factorizations else "."))
        else:
            how = f"The truth came from direct solves ({check.factorizations or 0} numerical factorizations)."
        lines += [f"The full-order reference was checked against solves of the full system (K − ω²M) x = G "
                  f"off resonance {'of the structure' if c.single else 'at every angle'}: worst disagreement "
                  f"{check.error:.2e} of the pair's peak "
                  f"(allowed {check.rtol or 1e-6:.0e}). {how}", ""]
    met, worst = verdict.target_met, verdict.error_max
    where, kind = c.chosen.worst_where, c.chosen.worst_kind
    if worst is None:
        worst = c.chosen.worst_error
    if met is None and worst is not None and accuracy is not None:
        met = worst <= accuracy
    if judged:
        lines += [f"{passed} of {judged} rows meet the target."]
    if worst is not None:
        text = (f"Worst error {worst:.3g} ({'estimated' if estimated else 'measured'}) at "
                f"{_where_text(c, where, kind)}")
        text += f", target {accuracy:g}: " if accuracy is not None else ": "
        text += ("**target met**." if met else "**target MISSED**: the model is written all the same, and "
                 "`kryflex reduce` exits with code 6.") if met is not None else "no verdict."
        lines += [text]
    lines += [""]
    info_rows = [[_row_name(c, l), _fmt_error(c.chosen_error(l, "frf_pointwise_error"))] for l in c.labels]
    if any(r[1] != DASH for r in info_rows):
        lines += [f"Table 7b. Pointwise error with a floor of the {c.model_name} ({INFO_TEXT}): per pair "
                  "max_w |T_full − T_red| / max(|T_full(w)|, floor · max_w |T_full|), floor "
                  f"{_fmt_floor(c.s)}. It is large in deep notches, where the response itself is tiny; the "
                  "verdict above does not use it.", "",
                  table(["configuration", f"pointwise error ({INFO_TEXT})"], info_rows), ""]
    return lines


def _fmt_floor(s):
    floor = s.get("frf_floor_db")
    return f"{floor:g} dB" if isinstance(floor, (int, float)) else "`verify.frf_floor_db` (default −60 dB)"


def _search_marker(k, chosen_row):
    return "◀ chosen" if k == chosen_row else ""


def _flexible_dofs(c, label):
    dofs = (c.chosen.system_dofs or {}).get(label)
    if dofs is None:
        return None
    return dofs - (c.rigid or 0)


def _section_choice(c):
    s = c.summary
    candidates = s.search or []
    hankel = s.hankel or {}
    if not candidates and not hankel:
        return []
    accuracy = s.accuracy
    lines = ["## How the model was chosen", ""]
    if candidates:
        lines += [f"The reducer evaluated {len(candidates)} candidate model(s), smallest first within each family, "
                  "and kept the smallest that meets the target (`reduction.method: auto`: the smaller of the two "
                  "families; otherwise the family asked for). Error: the " + _error_text(s)
                  + (" (estimated)" if s.verdict.error_estimated else "") + "."
                  + (" No candidate met the target: the one written is marked." if s.verdict.target_met is False
                     else ""), ""]
        rows = []
        for k, r in enumerate(candidates):
            kept = "all" if r.kept_clusters is None else str(r.kept_clusters)
            rows.append([r.family or DASH, fmt_general(r.moments), kept, fmt_general(r.expansion_angles),
                         fmt_general(r.reduced_dofs), fmt_general(r.max_system_dofs), _fmt_error(r.error),
                         _verdict(r.error, accuracy), r.variant or DASH, _search_marker(k, s.search_chosen)])
        lines += ["Table 8. The search: one row per candidate evaluated (variant: split, or its bodies tied to "
                  "shared directions, -kf_shared_directions).", "",
                  table(["family", "moments c", "kept clusters", "expansion angles", "size (dofs, all bodies)",
                         "max system dofs", "error", "target", "variant", ""], rows, "lrrrrrrlll"), ""]
    elif s.settings is not None and s.settings.search is False:
        lines += ["The search was off (`reduction.search: false`): the paper's fixed recipe (fixed moments, "
                  "keep threshold%s)." % ("" if c.single else ", α_G rule"), ""]
    if hankel:
        rows = []
        for label in c.labels:
            h = hankel.get(label)
            if h is None:
                continue
            order = h.order
            flex = _flexible_dofs(c, label)
            needed = None if order is None else (order + 1) // 2
            states = h.chosen_states if "chosen_states" not in h.absent else (None if flex is None else 2 * flex)
            rows.append([c.short_angle(label), fmt_general(flex), fmt_general(states),
                         _fmt_error(h.bound_at_chosen), fmt_general(order), fmt_general(needed),
                         DASH if not needed or flex is None else f"{flex / needed:.2g}×"])
        caption = ("Table 9. How close to the limit: the Hankel singular values σ of the full model's flexible part "
                   "(two first-order states (q, q̇) per mode). No model of k states has an H∞ error below σ_(k+1); a "
                   "model whose every pair is within e of its peak has one below √(t·a) · e · max|T_full|. So no "
                   "model of the chosen size k can have a relative error per pair below "
                   "σ_(k+1) / (√(t·a) · max|T_full|) (column 4), and the target")
        caption += f" {accuracy:g}" if accuracy is not None else ""
        caption += " needs at least r states (the Hankel order, column 5), about r/2 flexible dofs."
        lines += [caption, "",
                  table(["configuration", "chosen: flexible system dofs", "states k = 2 × dofs",
                         "no model of k states can do better than", "Hankel order r for the target",
                         "≈ flexible dofs r/2", "chosen / needed"], rows), ""]
    return lines


def _section_scene(c):
    s = c.s
    lines = [f"# kryflex verification report: {s['scene']}", ""]
    origin = []
    if s.get("kryflex_version"):
        origin.append(f"kryflex {s['kryflex_version']}")
    if s.get("scene_file"):
        origin.append(f"scene file `{s['scene_file']}`")
    if origin:
        lines += ["; ".join(origin) + ".", ""]
    lines += ["## Scene and settings", ""]
    dofs = _get(s, ("full", "dofs_per_body")) or {}
    body_text = ", ".join(f"{b} ({n} dofs)" for b, n in dofs.items())
    text = []
    if body_text:
        text.append(f"The scene has {len(dofs)} bodies: {body_text}.")
    joints = s.get("joints")
    if joints:
        text.append(f"Revolute joints: {', '.join(joints)}.")
    e = _get(s, ("full", "system_dofs"))
    if e is not None:
        rigid = ""
        if c.rigid is not None:
            rigid = f", of which {c.rigid} are rigid-body/mechanism modes" if c.rigid else ", with no rigid-body modes"
        text.append(f"The assembled full-order system has {e} degrees of freedom{rigid}.")
    text.append(f"Inputs: {', '.join(c.inputs)}. Outputs: {', '.join(c.outputs)}.")
    text.append("Configurations: " + ", ".join(c.angle(l) for l in c.labels) + ".")
    if s.get("band_hz"):
        text.append(f"Frequency band of interest: {s['band_hz'][0]:g} to {s['band_hz'][1]:g} Hz.")
    model = s.get("damping_model")
    if model is not None and (damping_text(model) != f"modal {100 * s.get('damping', -1):g} %"
                              or s.get("damping_matrices")):
        text.append(f"Damping, the same on the full and reduced models: {damping_text(model)}"
                    + (f"; viscous damping matrices on {', '.join(s['damping_matrices'])}"
                       if s.get("damping_matrices") else "") + ".")
    elif s.get("damping") is not None:
        text.append(f"Uniform modal damping: {100 * s['damping']:g} % on both the full and reduced models.")
    quantities = s.get("output_quantities") or []
    if any(q != "displacement" for q in quantities):
        text.append("Output quantities: " + ", ".join(f"{o} {q}" for o, q in zip(c.outputs, quantities)) + ".")
    if s.get("accuracy") is not None:
        text.append(f"Accuracy target: {s['accuracy']:g} of the {_error_text(s)} (defined in the next section).")
    lines += [" ".join(text), ""]
    settings = s.get("settings") or {}
    if settings:
        # angles of a scene without revolute joints are empty lists: no row ("[[]]" would read as an angle)
        lines += [table(["setting", "value"], [(k, fmt_general(v)) for k, v in settings.items()
                                               if not (k.endswith("_deg") and _no_angles(v))], "ll"), ""]
    return lines


def _section_full_frequencies(c):
    s = c.s
    lines = ["## Full-order natural frequencies (cf. Table 1)", ""]
    bodies = _get(s, ("full", "body_frequencies_hz")) or {}
    if bodies:
        dofs = _get(s, ("full", "dofs_per_body")) or {}
        n = max(len(v) for v in bodies.values())
        header = ["Mode"] + [f"Ω_{b} (Hz)" + (f", {dofs[b]} dofs" if b in dofs else "") for b in bodies]
        rows = [[str(m + 1)] + [fmt_freq(v[m]) if m < len(v) else "" for v in bodies.values()] for m in range(n)]
        lines += ["Table 1a. Free-free component frequencies (lowest listed by the reducer).", "",
                  table(header, rows), ""]
    freqs = s["full"]["frequencies_hz"]
    n = max(len(freqs[l]) for l in c.labels)
    header = ["Mode"] + [f"Ω_system (Hz), {c.short_angle(l)}" for l in c.labels]
    rows = []
    if c.rigid:
        rows.append([f"1–{c.rigid}" if c.rigid > 1 else "1"] + ["0"] * len(c.labels))
    for m in range(n):
        rows.append([str(c.mode_number(m))] + [fmt_freq(freqs[l][m]) if m < len(freqs[l]) else "" for l in c.labels])
    rigid_note = (f" Modes 1–{c.rigid} are the rigid-body and mechanism modes (0 Hz);"
                  " flexible modes follow." if c.rigid else "")
    lines += ["Table 1b. System natural frequencies at each configuration (lowest flexible modes)." + rigid_note, "",
              table(header, rows), ""]
    lines += [_frequency_variation_sentence(c, freqs), ""]
    return lines


def _frequency_variation_sentence(c, freqs):
    """How the system frequencies move with the angle (the paper: some rise, some fall, a few stay)."""
    if len(c.labels) < 2:
        return "Only one configuration was analysed."
    n = min(len(freqs[l]) for l in c.labels)
    if n == 0:
        return ""
    table_ = np.array([[freqs[l][m] for l in c.labels] for m in range(n)], dtype=float)
    low, high = table_.min(axis=1), table_.max(axis=1)
    spread = np.where(low > 0, (high - low) / np.where(low > 0, low, 1.0), 0.0)
    moving = int(np.sum(spread > 1e-3))
    worst = int(np.argmax(spread))
    return (f"Across the {len(c.labels)} configurations, {moving} of the {n} listed flexible modes change by more "
            f"than 0.1 %; the largest change is mode {c.mode_number(worst)} "
            f"({fmt_freq(low[worst])} to {fmt_freq(high[worst])} Hz, {fmt_percent(spread[worst], 3)}).")


def _kept_numbers(krylov):
    return [m + 1 for m, k in enumerate(krylov["kept"]) if k]


def _section_krylov(c):
    s = c.s
    settings = s.get("settings") or {}
    threshold = settings.get("keep_threshold")
    lines = ["## Importance of the Krylov modes (cf. Tables 2 and 3)", ""]
    lines += ["At each configuration the Krylov basis is built, the small reduced eigenproblem solved, and each "
              "Krylov mode ranked by its normalized contribution to the input-to-output map "
              f"(measure: {settings.get('importance', 'see settings')}). Modes marked * reach the keep threshold"
              + (f" {threshold:g}" if threshold is not None else "") + ".", ""]
    for number, label in enumerate(c.labels, start=1):
        kr = s["krylov"][label]
        count = len(kr["frequency_hz"])
        extra = []
        if kr.get("deflations") is not None:
            extra.append(f"{kr['deflations']} deflation(s)")
        if kr.get("gram_condition_raw") is not None:
            extra.append(f"condition of the raw-recurrence Gram matrix {kr['gram_condition_raw']:.3g}")
        caption = f"Table 3.{number}. Normalized importance of the Krylov modes ({c.angle(label)}, c = {count})"
        if label == c.label_g and not c.single:
            caption += ", the reduction configuration α_G"
        lines += [caption + "." + (" " + "; ".join(extra) + "." if extra else ""), ""]
        rows = [[f"{m + 1}*" if kept else str(m + 1), fmt_freq(f), f"{imp:.4f}"]
                for m, (f, imp, kept) in enumerate(zip(kr["frequency_hz"], kr["importance"], kr["kept"]))]
        lines += [table(["Mode", "Ω_Krylov (Hz)", "importance"], rows), "", "\\* kept Krylov modes", ""]
    return lines


def _section_alpha_g(c):
    s = c.s
    lines = ["## The reduction configuration" if c.single else "## Choice of the reduction configuration α_G", ""]
    rows = []
    for label in c.labels:
        kept = _kept_numbers(s["krylov"][label])
        rows.append([c.short_angle(label), str(len(kept)), mode_ranges(kept)])
    lines += [table(["configuration", "important modes", "mode numbers"], rows, "lrl"), ""]
    text = (f"The reduction basis is built on the structure (no revolute joint: one configuration)."
            if c.no_joint(c.label_g) else f"The reduction basis is built at α_G: {c.angle(c.label_g)}.")
    if s.get("reduction_rule"):
        text += f" Reason: {s['reduction_rule']}"
        text += "" if text.endswith(".") else "."
    settings = s.get("settings") or {}
    if settings.get("method"):
        text += f" Method: {settings['method']}."
    if settings.get("reduction_angles_deg") and not _no_angles(settings["reduction_angles_deg"]):
        text += f" Reduction angles: {fmt_general(settings['reduction_angles_deg'])} deg."
    lines += [text, ""]
    return lines


def _section_kept(c):
    s = c.s
    kr = s["krylov"][c.label_g]
    count = len(kr["frequency_hz"])
    kept = sorted(s["kept_modes"])
    discarded = [m for m in range(1, count + 1) if m not in kept]
    lines = ["## Kept Krylov modes and static correction", ""]
    where = "For the structure" if c.single else f"At α_G ({c.angle(c.label_g)})"
    text = (f"{where} the projection mode set keeps {len(kept)} of the {count} Krylov modes: "
            f"modes {mode_ranges(kept)} (numbers of Table 3.{c.labels.index(c.label_g) + 1}).")
    if discarded:
        best = max(discarded, key=lambda m: kr["importance"][m - 1])
        n_static = s.get("static_correction_modes")
        text += (f" The discarded modes {mode_ranges(discarded)} are replaced by "
                 + (f"{n_static} " if n_static is not None else "")
                 + "static correction mode(s)")
        sc = s.get("static_correction_frequency_hz")
        if sc:
            text += " at " + ", ".join(fmt_freq(f) for f in sc) + " Hz"
        text += (f". The discarded mode of highest importance is mode {best} "
                 f"({fmt_freq(kr['frequency_hz'][best - 1])} Hz, importance {kr['importance'][best - 1]:.4f}).")
    elif s.get("static_correction_modes"):
        text += f" {s['static_correction_modes']} static correction mode(s) are added."
    lines += [text, ""]
    return lines


def _nearest(values, target):
    if not values:
        return None
    return int(np.argmin([abs(v - target) for v in values]))


def _section_reduced(c):
    s = c.s
    red = s["reduced"]
    lines = ["## Reduced-order component and system models (cf. Table 4)", ""]
    full_dofs = _get(s, ("full", "dofs_per_body")) or {}
    red_dofs = red.get("dofs_per_body") or {}
    if red_dofs:
        parts = [f"{b}: {v}" + (f" (full {full_dofs[b]})" if b in full_dofs else "") for b, v in red_dofs.items()]
        sys_dofs = (red.get("system_dofs") or {}).get(c.label_g)
        full_sys = _get(s, ("full", "system_dofs"))
        sentence = "Projected body models, degrees of freedom: " + "; ".join(parts) + "."
        if sys_dofs is not None:
            sentence += (" Reduced system" if c.no_joint(c.label_g) else " Reduced system at α_G") + f": {sys_dofs} dofs" + (f" (full {full_sys})." if full_sys else ".")
        lines += [sentence, ""]
    bodies = red.get("body_frequencies_hz") or {}
    if bodies:
        n = max(len(v) for v in bodies.values())
        rows = [[str(m + 1)] + [fmt_freq(v[m]) if m < len(v) else "" for v in bodies.values()] for m in range(n)]
        lines += ["Table 4a. Natural frequencies of the projected (reduced) component models.", "",
                  table(["Mode"] + [f"ω_{b} (Hz)" for b in bodies], rows), ""]
    lines += _table_reduced_system(c)
    lines += _table_dominant_errors(c)
    lines += _table_reassembly(c)
    lines += _table_trimming(c)
    return lines


def _table_trimming(c):
    """The highest frequency the reduced system keeps in its dynamics and the explicit step it allows, with the
    trimming (reduction.max_frequency) that set them."""
    trim = c.s["reduced"].get("trimming") or {}
    tops = trim.get("top_frequency_hz") or {}
    if not tops:
        return []
    rows = [[c.short_angle(l), str(trim["trimmed_modes"].get(l, 0)), fmt_freq(trim["untrimmed_top_frequency_hz"][l]),
             fmt_freq(tops[l]), f"{trim['explicit_step_s'][l]:.3g}" if trim["explicit_step_s"].get(l) else DASH]
            for l in c.labels if l in tops]
    if trim.get("max_frequency_hz"):
        head = (f"Trimming: reduced-system modes above {trim['max_frequency_hz']:.4g} Hz "
                f"(max_frequency {trim['max_frequency']}) are taken out of the dynamics; their static share is kept "
                "as a feedthrough, so the static moment L^0 is unchanged (docs/guide/trimming.md).")
    else:
        head = "No trimming (reduction.max_frequency not set): every reduced mode is in the dynamics."
    return [head, "", table(["configuration", "modes trimmed", "highest before (Hz)", "highest kept (Hz)",
                             "stable explicit step 2/ω_max (s)"], rows), ""]


def _table_reduced_system(c):
    s = c.s
    full = s["full"]["frequencies_hz"][c.label_g]
    reduced = s["reduced"]["frequencies_hz"].get(c.label_g) or []
    dominant = set((s.get("dominant_modes") or {}).get(c.label_g) or [])
    captured = {_nearest(reduced, full[i]) for i in dominant} - {None}
    n = max(len(full), len(reduced))
    rows = []
    if c.rigid:
        rows.append([f"1–{c.rigid}" if c.rigid > 1 else "1", "0", "0"])
    for m in range(n):
        f_full = fmt_freq(full[m]) + (" †" if m in dominant else "") if m < len(full) else ""
        f_red = fmt_freq(reduced[m]) + (" ‡" if m in captured else "") if m < len(reduced) else ""
        rows.append([str(c.mode_number(m)), f_full, f_red])
    return [f"Table 4b. System natural frequencies {c.at_g()}: full order Ω and reduced ω.", "",
            table(["Mode", "Ω_system full (Hz)", "ω_system reduced (Hz)"], rows), "",
            "† dominant full-order system modes; ‡ the reduced mode nearest to each of them.", ""]


def _table_dominant_errors(c):
    s = c.s
    dominant = s.get("dominant_modes") or {}
    errors = s.get("dominant_freq_error") or {}
    if not dominant:
        return []
    rows, worst = [], {}
    for label in c.labels:
        indices = dominant.get(label) or []
        errs = errors.get(label) or []
        for j, index in enumerate(indices):
            err = errs[j] if j < len(errs) else None
            rows.append([c.short_angle(label), str(c.mode_number(index)),
                         fmt_freq(s["full"]["frequencies_hz"][label][index]), fmt_percent(err, 3)])
            if err is not None:
                worst[label] = max(worst.get(label, 0.0), abs(err))
    lines = ["Table 4c. Relative frequency error of the reduced model on each dominant full-order mode.", "",
             table(["configuration", "Mode", "Ω full (Hz)", "relative error"], rows), ""]
    if worst:
        at_g = worst.get(c.label_g)
        overall = max(worst.values())
        text = ""
        if at_g is not None:
            text = (f"{'For the structure' if c.single else 'At α_G'} the "
                    f"{len(dominant.get(c.label_g) or [])} dominant full-order modes are captured to "
                    f"within {fmt_percent(at_g, 3)}; ")
        text += f"over all configurations the worst dominant-mode frequency error is {fmt_percent(overall, 3)}."
        lines += [text, ""]
    return lines


def _table_reassembly(c):
    red = c.s["reduced"]
    columns = [("system_dofs", "reduced system dofs", str), ("reassembly_rank", "reassembly rank", str),
               ("reassembly_sigma_ratio", "σ ratio at the rank cut", lambda v: f"{v:.3g}"),
               ("static_gain_error", "static gain error", lambda v: f"{v:.3g}")]
    present = [(key, name, f) for key, name, f in columns if red.get(key)]
    if not present:
        return []
    rows = [[c.short_angle(l)] + [f(red[key][l]) if red[key].get(l) is not None else DASH for key, _, f in present]
            for l in c.labels]
    lines = ["Reassembly of the reduced bodies at each configuration (null space of the interface constraints by SVD).",
             "", table(["configuration"] + [name for _, name, _ in present], rows), ""]
    if red.get("reassembly_seconds") is not None:
        lines += [f"Total reassembly time: {red['reassembly_seconds']:.3g} s.", ""]
    return lines


def _section_moments(c):
    s = c.s
    lines = ["## Low-frequency moments of the full-order models (cf. Table 5)", ""]
    lines += ["L^k = H (K⁺M)^k K⁺ G on the flexible subspace. Each row shows mantissas: the entry times the row's "
              "scale is L^k (e.g. −1.8910 with scale 1e-07 means −1.8910 × 10⁻⁷).", ""]
    if len(c.shown_entries) < len(c.entries):
        lines += [f"With {len(c.entries)} (output, input) entries, only the dominant one (largest static gain), "
                  f"{c.entry_name(c.dominant_entry)}, is tabulated; every entry is in summary.json.", ""]
    moments = s["full"]["moments"]
    count = max(len(moments[l]) for l in c.labels)
    for entry in c.shown_entries:
        o, i = entry
        rows = []
        for k in range(count):
            values = [moments[l][k][o][i] if k < len(moments[l]) else None for l in c.labels]
            p = decade_scale(values)
            rows.append([f"L^{k}", f"1e{p:+03d}"] + [DASH if v is None else f"{v / 10.0 ** p:.4f}" for v in values])
        lines += [f"Table 5 ({c.entry_name(entry)}). Full-order moments L^k.", "",
                  table(["L^k", "scale"] + [c.short_angle(l) for l in c.labels], rows), ""]
    return lines


def _mismatches(ratios_by_label, c):
    """[(label, k, entry, ratio)] for every defined ratio with |ratio - 1| > RATIO_EXACT_TOL."""
    found = []
    for label in c.labels:
        for (o, i) in c.entries:
            for k, matrix in enumerate(ratios_by_label.get(label) or []):
                r = matrix[o][i]
                if r is not None and abs(r - 1.0) > RATIO_EXACT_TOL:
                    found.append((label, k, (o, i), r))
    return found


def _mismatch_sentence(c, found, model):
    if not found:
        return (f"All defined ratios of the {model} equal 1 to within {RATIO_EXACT_TOL:g} at every configuration: "
                f"its moments match the full-order ones exactly.")
    several = len(c.entries) > 1
    groups = {}          # one group per configuration and I/O entry: "α = 0°, out ← in: k = 0 ratio .., k = 1 .."
    for label, k, entry, r in found[:MAX_MISMATCHES_LISTED]:
        where = (c.short_angle(label) if c.no_joint(label) else f"α = {c.short_angle(label)}") + (f", {c.entry_name(entry)}" if several else "")
        groups.setdefault(where, []).append(f"k = {k} ratio {fmt_ratio(r)}")
    text = (f"**The {model} does NOT match the full-order moments exactly** (|ratio − 1| > {RATIO_EXACT_TOL:g}) "
            f"in {len(found)} place(s): "
            + "; ".join(f"{where}: {', '.join(items)}" for where, items in groups.items()))
    if len(found) > MAX_MISMATCHES_LISTED:
        text += f"; and {len(found) - MAX_MISMATCHES_LISTED} more (see summary.json)"
    text += "."
    if not (c.s.get("chosen") or {}).get("static_exact", True):
        return text + (" The compression truncated the static response (reduction.static_exact: false), so L⁰ is "
                       "approximated, its error measured (summary.json: chosen.static_moment_error).")
    if any(label == c.label_g for label, _, _, _ in found) and model.startswith("single"):
        text += (" This includes " + ("the structure's own expansion point" if c.single else "α_G itself") +
                 ", where the match is exact by construction: "
                 "treat it as a defect of the reduction, not an approximation.")
    return text


def _section_ratios(c):
    s = c.s
    ratios = s["reduced"]["moment_ratios"]
    lines = ["## Ratios of full to reduced moments, L_full^k / L_reduced^k (cf. Table 6)", ""]
    count = max(len(ratios[l]) for l in c.labels)
    for entry in c.shown_entries:
        o, i = entry
        rows = [[str(k)] + [fmt_ratio(ratios[l][k][o][i]) if k < len(ratios[l]) else DASH for l in c.labels]
                for k in range(count)]
        lines += [f"Table 6 ({c.entry_name(entry)}). L_full^k / L_reduced^k, single-angle model built "
                  f"{'on the structure' if c.single else 'at α_G'}.", "",
                  table(["k"] + [c.short_angle(l) for l in c.labels], rows), ""]
    lines += [f"{DASH} : the full-order moment is negligible, so the ratio is undefined.", ""]
    lines += [_mismatch_sentence(c, _mismatches(ratios, c), "single-angle model"), ""]
    return lines


def _section_multi(c):
    s = c.s
    multi = s.get("multi_angle")
    if not multi:
        return []
    red = s["reduced"]
    lines = ["## Multi-angle model beside the single-angle model", ""]
    single_body = red.get("dofs_per_body") or {}
    multi_body = multi.get("dofs_per_body") or {}
    bodies = list(dict.fromkeys(list(single_body) + list(multi_body)))
    if bodies:
        rows = [["single-angle" + c.g_mark(c.label_g)] + [str(single_body.get(b, DASH)) for b in bodies],
                ["multi-angle"] + [str(multi_body.get(b, DASH)) for b in bodies]]
        lines += [table(["model"] + [f"{b} dofs" for b in bodies], rows), ""]
    single_sys = red.get("system_dofs") or {}
    multi_sys = multi.get("system_dofs") or {}
    multi_err = multi.get("frf_error") or multi.get("frf_max_rel_error") or {}
    rows = []
    for label in c.labels:
        single_err = s["frf"][label].get("frf_error", s["frf"][label].get("max_rel_error"))
        rows.append([c.short_angle(label), str(single_sys.get(label, DASH)), str(multi_sys.get(label, DASH)),
                     _fmt_error(single_err), _fmt_error(multi_err.get(label))])
    lines += [f"Both models, the {c.model_name} being the one chosen (its errors are the verdict of Table 7); "
              f"errors: the {_error_text(c.s)}.", "",
              table(["configuration", "single: system dofs", "multi: system dofs", "single: relative H∞ error",
                     "multi: relative H∞ error"], rows), ""]
    if multi.get("moment_ratios"):
        lines += [_mismatch_sentence(c, _mismatches(multi["moment_ratios"], c), "multi-angle model"), ""]
    return lines


def _section_frf(c, plot_names):
    lines = ["## Frequency responses (cf. Fig. 3)", ""]
    lines += [f"Full order against the {c.model_name} "
              + ("of the structure" if c.no_joint(c.label_g) else "at every angle of interest")
              + ". The error plot draws, at each "
              "frequency, |T_full − T_red| / max_w |T_full| for the worst input/output pair: the peak of each curve "
              "is that configuration's relative H∞ error of Table 7. Phases are unwrapped, the reduced curve drawn within "
              "180° of the full one at every frequency.", ""]
    lines += ["![Bode overview](bode_overview.png)", ""]
    if plot_names.get("bode_pairs"):
        lines += ["Bode plots, full vs reduced, every input/output pair: " + ", ".join(
            f"[{c.short_angle(l)}]({plot_names['bode_pairs'][l]})" for l in c.labels), "",
            f"![Bode plots {c.at_g()}]({plot_names['bode_pairs'][c.label_g]})"]
    if plot_names.get("bode"):
        lines += [""] if plot_names.get("bode_pairs") else []
        lines += ["Bode plots, full vs reduced, a figure per pair:", ""]
        for label in c.labels:
            links = [f"[{c.entry_name(e)}]({plot_names['bode'][(label, e)]})" for e in c.entries]
            lines.append(f"- {c.short_angle(label)}: " + ", ".join(links))
    lines += ["", "![Relative FRF error](frf_error.png)", "", "![Moment ratios](moment_ratios.png)", "",
              "Importance of the Krylov modes: " + ", ".join(
                  f"[{c.short_angle(l)}]({plot_names['importance'][l]})" for l in c.labels), "",
              f"![Importance {c.at_g()}]({plot_names['importance'][c.label_g]})", ""]
    return lines


def _section_timings(c):
    timings = c.s.get("timings_s") or {}
    if not timings:
        return []
    rows = [[stage, f"{seconds:.3g}"] for stage, seconds in timings.items()]
    rows.append(["**total**", f"{sum(timings.values()):.3g}"])
    return ["## Timings", "", table(["stage", "seconds"], rows), ""]


def _section_notes(c):
    notes = c.s.get("notes") or []
    if not notes:
        return []
    return ["## Notes", ""] + [f"- {n}" for n in notes] + [""]


def render_markdown(summary, plot_names):
    """report.md text; plot_names as returned by plot_file_names."""
    c = _Context(summary)
    lines = []
    for section in (_section_scene, _section_accuracy, _section_choice, _section_full_frequencies, _section_krylov,
                    _section_alpha_g, _section_kept, _section_reduced, _section_moments, _section_ratios,
                    _section_multi, lambda c: _section_frf(c, plot_names), lambda c: section_paper(c.s),
                    _section_timings, _section_notes):
        lines += section(c)
    number = 0
    for k, line in enumerate(lines):
        if line.startswith("## "):
            number += 1
            lines[k] = f"## {number}. {line[3:]}"
    return "\n".join(lines).rstrip() + "\n"


def damping_text(d):
    """One line for a damping description {modal, rayleigh: {alpha, beta}, structural} (docs/guide/damping.md)."""
    parts = []
    modal = d.get("modal") or 0.0
    if isinstance(modal, list):
        parts.append("modal per band " + ", ".join(f"{100 * z:g} % up to {f:g} Hz" for f, z in modal))
    elif modal:
        parts.append(f"modal {100 * modal:g} %")
    ray = d.get("rayleigh") or {}
    if ray.get("alpha") or ray.get("beta"):
        parts.append(f"Rayleigh alpha {ray.get('alpha', 0):g} 1/s, beta {ray.get('beta', 0):g} s")
    if d.get("structural"):
        parts.append(f"structural g = {d['structural']:g}")
    return "; ".join(parts) or "none"
