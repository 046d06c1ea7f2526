"""The summary dict of a reduction (schema in schema.py), from the C reducer's results and the scene's names.

Every number is one the C reducer recorded (KFReducerGetResult); this module only names, labels and shapes them
for JSON: arrays become nested lists, NaN ("negligible" or "not available") becomes None, moments and responses are
laid out (k or frequency, outputs, inputs) as the report reads them.

The one error measure (docs/guide/accuracy.md, src/measure/frf_error.c) is ERROR_DEFINITION: the summary's verdict (target_met,
error_max) and every per-angle "frf_error" are of it; "frf_pointwise_error" is the notch-aware pointwise measure,
information only. The verdict and the chosen-model blocks are always those of the model the reducer chose
(chosen_method), never the single-angle model's when the multi-angle one was chosen. Results a reducer did not
record (an older C library, the eigen basis, verification off) are left out or None, never invented.
"""
import numpy as np

from .. import _core
from .._runtime import collector_paused

# the reducer's stage timings, as the report names them, in the order stages run ("krylov" / "eigen basis": the
# basis of the reducer's type)
TIMINGS = [("time_assembly", "assembly"), ("time_factorization", "factorization"), ("time_basis", None),
           ("time_modes", "krylov modes"), ("time_moments", "moments"), ("time_projection", "projection"),
           ("time_verification", "verification eigensolve"), ("time_other", "other")]

ERROR_DEFINITIONS = {
    "elastic": ("relative H-infinity error of the elastic response per input/output pair: max over pairs (i, j) of "
                "max_w |Tf_ij(w) - Tr_ij(w)| / max_w |Tf_ij(w) - Tf_rigid,ij(w)| over the band, Tf_rigid the "
                "rigid-body and mechanism part from the geometric rigid modes (a pair whose elastic peak is below "
                "1e-4 of the largest pair's is measured against 1e-4 x that peak)"),
    "total": ("relative H-infinity error of the total response per input/output pair: max over pairs (i, j) of "
              "max_w |Tf_ij(w) - Tr_ij(w)| / max_w |Tf_ij(w)| over the band (a pair whose peak is below 1e-4 of "
              "the largest pair's peak is measured against 1e-4 x that peak)")}
ERROR_DEFINITION = ERROR_DEFINITIONS["total"]     # models written before the accuracy measure was a setting
POINTWISE_DEFINITION = ("pointwise error with a floor (information, not the verdict): max over pairs of "
                        "max_w |Tf_ij(w) - Tr_ij(w)| / max(|Tf_ij(w)|, 10^(floor_db/20) max_w |Tf_ij|)")
METHODS = {0: "single-angle", 1: "multi-angle"}
SEARCH_COLUMNS = ("family", "moments", "kept_clusters", "expansion_angles", "reduced_dofs", "max_system_dofs",
                  "error", "variant")
# a candidate's variant (-kf_shared_directions): split, tied, or tied without the static correction of the dropped
# clusters; tables of libraries before the column have 7 rows and leave it None
VARIANTS = {0: "split", 1: "tied", 2: "tied, no static correction", 3: "compressed body by body",
            4: "compressed, tied across the bodies"}


def _none(x):
    """A float for JSON, None for NaN."""
    x = float(x)
    return None if np.isnan(x) else x


PERFORMANCE = [("time_factor_total", "factorization_s"), ("time_solves", "solves_s"), ("time_whole", "whole_s"),
               ("time_ratio", "ratio"), ("solve_calls", "solve_calls"), ("solve_columns", "solve_columns"),
               ("refinement_solves", "refinement_solves"), ("solve_blocks_unconverged", "blocks_unconverged"),
               ("solve_blocks_escalated", "blocks_escalated"),
               ("solve_residual_first_max", "residual_first_max"),
               ("solve_residual_final_max", "residual_final_max"), ("factor_memory_estimate_mb", "memory_estimate_mb"),
               ("time_reference_eigensolve", "reference_eigensolve_s"), ("time_reference_check", "reference_check_s"),
               ("time_reference_count", "reference_count_s"), ("time_certificate_count", "certificate_count_s"),
               ("time_certificate_count_helper", "certificate_count_helper_s"),
               ("time_search", "search_s"), ("time_compress", "compress_s")]
PERFORMANCE_COUNTS = ("solve_calls", "solve_columns", "refinement_solves", "blocks_unconverged", "blocks_escalated")  # ints in the JSON


def _performance(reducer, whole):
    """The flexible solver's share of the run (C KFReducerSolve's timing table): seconds, counts, residuals."""
    out = {}
    for name, key in PERFORMANCE:
        if name in whole:
            v = _none(reducer.result(-1, name).ravel()[0])
            out[key] = int(v) if v is not None and key in PERFORMANCE_COUNTS else v
    return out


def _list(a):
    """Nested lists of floats (None for NaN) of an array: NumPy's tolist, NaN replaced where there is one (an element
    at a time took 0.1 s of a 57k-dof reduction's FRF blocks)."""
    a = np.asarray(a, dtype=float)
    if a.ndim == 0:
        return _none(a)
    if not np.isnan(a).any():
        with collector_paused():
            return a.tolist()
    return [_list(x) for x in a]


def _ints(a):
    return [int(x) for x in np.asarray(a).ravel()]


def _scalar(reducer, config, name, kind=float):
    value = float(reducer.result(config, name).ravel()[0])
    if np.isnan(value):
        return None
    return kind(value)


def _max_defined(values):
    """The largest of values that are defined (not None), 0 when none is: how the report states "all match"."""
    vals = [v for v in values if v is not None]
    return max(vals) if vals else 0.0


def _max_ratio_deviation(ratios):
    """max |r - 1| over the defined moment ratios (nested lists), 0 when none is defined."""
    return _max_defined(abs(x - 1) for k in ratios for row in k for x in row if x is not None)


def _optional(reducer, config, name, has):
    """The result as C recorded it, or None when this reducer did not record it."""
    return reducer.result(config, name) if name in has else None


def _optional_scalar(reducer, config, name, has, kind=float):
    return _scalar(reducer, config, name, kind) if name in has else None


def _static_moment(reducer, labels, has, whole, prefix):
    """static_exact: whether the chosen model keeps L^0 as the search made it (false only after a compression with
    -kf_static_exact false, docs/guide/expansion-points.md); static_moment_error: {label: the chosen model's measured
    ||L^0_full - L^0_red|| / ||L^0_full||} at the angles of interest, reported either way."""
    flag = _optional_scalar(reducer, -1, "static_exact", whole, int)
    name = prefix + "moment_error"
    errors = {lab: _none(np.ravel(reducer.result(c, name))[0]) if name in has[c] else None
              for c, lab in enumerate(labels)}
    return {"static_exact": flag is None or bool(flag), "static_moment_error": errors}


def _degrees(angles_rad):
    """Degrees with the 12 digits a user gives (30, not 29.999999999999996)."""
    return [float("%.12g" % d) for d in np.degrees(np.asarray(angles_rad, dtype=float))]


def _search_rows(table):
    """The rows of the search_table result (8 x ncand, or 7 without the variant) as dicts named by SEARCH_COLUMNS."""
    table = np.asarray(table, dtype=float)
    widths = (len(SEARCH_COLUMNS), len(SEARCH_COLUMNS) - 1)
    if table.ndim != 2 or not (table.shape[0] in widths or table.shape[1] in widths):
        return []
    if table.shape[0] in widths:                        # C records it 8 x ncand: one column per candidate
        table = table.T
    rows = []
    for values in table:
        row = {"variant": None}
        for name, v in zip(SEARCH_COLUMNS, values):
            if name == "family":
                row[name] = METHODS.get(int(v), str(int(v)))
            elif name == "error":
                row[name] = _none(v)
            elif name == "variant":
                row[name] = VARIANTS.get(int(v), str(int(v)))
            elif name == "kept_clusters":
                # None: every cluster kept; "per body": each body its share (body_kept_clusters)
                row[name] = None if np.isnan(v) or v == -1 else ("per body" if v == -2 else int(v))
            else:
                row[name] = None if np.isnan(v) else int(v)
        rows.append(row)
    return rows


def _shift_rows(table):
    """The rows of the shift_search result (6 x ncand): moments at zero, points, dofs, error, factorizations spent."""
    if table is None:
        return []
    table = np.asarray(table, dtype=float)
    if table.ndim != 2 or table.shape[0] != 6:       # C records it 6 x ncand: one column per candidate
        return []
    table = table.T
    names = ("moments", "points", "reduced_dofs", "system_dofs", "error", "factorizations_spent")
    return [{n: (_none(v) if n == "error" else int(v)) for n, v in zip(names, row)} for row in table]


def _chosen_row(rows, method, moments, dofs, variant=None):
    """Index of the search row of the chosen model (its family, moments, reduced dofs and, when known, variant; the
    smallest error among equal ones), or None when no row matches (the search was off, or an older C library)."""
    matches = [k for k, row in enumerate(rows) if row["family"] == method and row["reduced_dofs"] == dofs
               and (moments is None or row["moments"] == moments)
               and (variant is None or row["variant"] is None or row["variant"] == variant)]
    if not matches:
        return None
    return min(matches, key=lambda k: float("inf") if rows[k]["error"] is None else rows[k]["error"])


def _worst(per_angle, midpoints):
    """(value, where, kind) of the largest defined error over the angles of interest ({label: e}) and the midpoints
    ([{"label", "frf_error"}]); kind "angle" or "midpoint"; (None, None, None) when none is defined."""
    places = [(e, label, "angle") for label, e in per_angle.items() if e is not None]
    places += [(m["frf_error"], m["label"], "midpoint") for m in midpoints if m["frf_error"] is not None]
    if not places:
        return None, None, None
    return max(places, key=lambda p: p[0])


def accuracy_measure(settings):
    """elastic | total: the response a model's errors are of (its settings; "total" for models written before the
    measure was a setting, which all used it)."""
    measure = settings.get("accuracy_measure", "total")
    return measure if measure in ERROR_DEFINITIONS else "total"


def _floored_pairs(reducer, scene, labels, has, measure):
    """Per angle of interest, the pairs whose error is measured against a floor instead of their own peak, from the
    verification's full response on its grid (KFFRFPairFloors, the floors of the error measure): "largest_pair",
    [output, input] names of the pairs whose peak is below 1e-4 of the largest pair's; "own_total", those whose
    elastic peak is below 1e-6 of their own total peak (elastic measure only). None where nothing was verified."""
    out = {}
    for c, lab in enumerate(labels):
        if "frf_full_re" not in has[c]:
            out[lab] = None
            continue
        rigid = reducer.full_rigid(c) if measure == "elastic" else None
        kinds = _core.frf_pair_floors(reducer.frf(c, "full"), rigid)
        out[lab] = {kind: [[scene.output_names[i], scene.input_names[j]] for i, row in enumerate(kinds)
                           for j, k in enumerate(row) if k == kind] for kind in ("largest_pair", "own_total")}
    return out


def _accuracy(reducer, scene, labels, has, whole, chosen, multi, single_frf):
    """The accuracy part of the summary: the verdict of the chosen model (target_met, error_max, where, measured or
    estimated), its errors at the angles of interest and at the midpoints, the search table and the Hankel bound."""
    method_code = _optional_scalar(reducer, -1, "chosen_method", whole, int)
    method = METHODS.get(method_code) if method_code is not None else chosen.settings.get("method", "single-angle")
    is_multi = method == "multi-angle" and multi is not None
    prefix = "multi_" if is_multi else ""
    measure = accuracy_measure(chosen.settings)
    out = {"accuracy_measure": measure, "error_definition": ERROR_DEFINITIONS[measure],
           "pointwise_definition": POINTWISE_DEFINITION, "chosen_method": method}
    met = _optional_scalar(reducer, -1, "target_met", whole)
    out["target_met"] = None if met is None else bool(met)
    out["error_max"] = _optional_scalar(reducer, -1, "error_max", whole)
    estimated = _optional_scalar(reducer, -1, "error_estimated", whole)
    out["error_estimated"] = bool(estimated) if estimated is not None else False
    certified = _optional_scalar(reducer, -1, "certified", whole)
    out["certificate"] = None
    if certified is not None:     # -kf_verify auto's certificate (src/reducer/certify.c)
        out["certificate"] = {"certified": bool(certified),
                              "below_hz": _optional_scalar(reducer, -1, "certificate_below_hz", whole),
                              "full_counts": [int(x) for x in np.ravel(reducer.result(-1, "certificate_full_counts"))],
                              "rich_counts": [int(x) for x in np.ravel(reducer.result(-1, "certificate_rich_counts"))],
                              "count_source": "helper" if _optional_scalar(reducer, -1, "certificate_count_helper",
                                                                           whole) else "in-process"}
    out["verdict_kind"] = None if out["error_max"] is None else (
        "measured" if not out["error_estimated"] else "certified" if certified else "estimated")
    out["moments_matched"] = _optional_scalar(reducer, -1, "moments_matched", whole, int)
    out["multi_moments_matched"] = _optional_scalar(reducer, -1, "multi_moments_matched", whole, int)
    # the full-order reference checked against direct solves of the full system (src/verify/direct_check.c)
    out["reference_check"] = None if "reference_check_error" not in whole else {
        "error": _optional_scalar(reducer, -1, "reference_check_error", whole),
        "rtol": _optional_scalar(reducer, -1, "reference_check_rtol", whole),
        # how the truth was solved: factorizations of the direct solves, points iterated from the reference
        # (src/verify/refined_check.c), their steps, and the points that fell back to direct solves
        "factorizations": _optional_scalar(reducer, -1, "reference_check_factorizations", whole, int),
        "iterative_points": _optional_scalar(reducer, -1, "reference_check_iterative_points", whole, int),
        "iterative_steps": _optional_scalar(reducer, -1, "reference_check_iterative_steps", whole, int),
        "iterative_steps_max": _optional_scalar(reducer, -1, "reference_check_iterative_steps_max", whole, int),
        "fallbacks": _optional_scalar(reducer, -1, "reference_check_fallbacks", whole, int),
        "per_angle": {lab: {"error": _optional_scalar(reducer, c, "reference_check_error", has[c]),
                            "frequency_hz": _optional_scalar(reducer, c, "reference_check_frequency_hz", has[c])}
                      for c, lab in enumerate(labels)}}

    # the chosen model's errors at the angles of interest: THE measure, and the pointwise one for information
    errors, pointwise = {}, {}
    for c, lab in enumerate(labels):
        errors[lab] = _optional_scalar(reducer, c, prefix + "frf_error", has[c])
        pointwise[lab] = _optional_scalar(reducer, c, prefix + "frf_pointwise_error", has[c])
    out["floored_pairs"] = _floored_pairs(reducer, scene, labels, has, measure)
    midpoints = []
    mid_angles = _optional(reducer, -1, "midpoint_angles", whole)
    mid_errors = _optional(reducer, -1, "midpoint_frf_error", whole)
    if mid_angles is not None and mid_angles.size:
        mid_angles = np.asarray(mid_angles, dtype=float)
        if mid_angles.ndim < 2:                       # one revolute joint recorded as a vector
            mid_angles = mid_angles.reshape(1, -1)
        mid_errors = np.full(mid_angles.shape[1], np.nan) if mid_errors is None else np.ravel(mid_errors)
        for k in range(mid_angles.shape[1]):
            degrees = _degrees(mid_angles[:, k])
            midpoints.append({"angles_deg": degrees, "label": scene.label(degrees),
                              "frf_error": _none(mid_errors[k]) if k < mid_errors.size else None})
    worst, where, kind = _worst(errors, midpoints)
    if out["target_met"] is None and worst is not None:
        # a reducer that records no verdict (a type without the search): the same rule on the errors it measured
        out["error_max"] = worst if out["error_max"] is None else out["error_max"]
        out["target_met"] = bool(out["error_max"] <= float(chosen.settings.get("accuracy", reducer.scene.accuracy)))
    sizes = list(chosen.sizes)
    system_dofs = {lab: _optional_scalar(reducer, c, prefix + "reduced_dofs", has[c], int)
                   for c, lab in enumerate(labels)}
    moments = out["multi_moments_matched"] if is_multi else out["moments_matched"]
    if moments is None:
        moments = chosen.settings.get("moments")
        moments = moments if isinstance(moments, int) else None
    rows = _search_rows(reducer.result(-1, "search_table")) if "search_table" in whole else []
    # compression (-kf_compress): the search's row is the model before it, of compressed_from_dofs
    before = _optional_scalar(reducer, -1, "compressed_from_dofs", whole, int)
    after = _optional_scalar(reducer, -1, "compressed_to_dofs", whole, int)
    # the table's size of the chosen candidate (a tied model's: body dofs less its ties), when recorded
    dofs = _optional_scalar(reducer, -1, "chosen_search_dofs", whole, int)
    if dofs is None:
        dofs = before if before and after and after < before else sum(sizes)
    variant = _optional_scalar(reducer, -1, "chosen_variant", whole, int)
    row = _chosen_row(rows, method, moments, dofs, None if variant is None else VARIANTS.get(variant, str(variant)))
    expansion = chosen.settings.get("reduction_angles_deg")
    out["chosen"] = {
        "method": method, "moments": moments, "dofs_per_body": dict(zip(scene.body_names, [int(v) for v in sizes])),
        "dofs": int(sum(sizes)), "system_dofs": system_dofs,
        "expansion_angles_deg": expansion,
        "kept_clusters": rows[row]["kept_clusters"] if row is not None else None,
        "kept_modes": None if is_multi else _ints(reducer.result(-1, "kept_modes")),
        "frf_error": errors, "frf_pointwise_error": pointwise,
        "worst_error": worst, "worst_where": where, "worst_kind": kind}
    # expansion points inside the band (-kf_max_factorizations): where the chosen model's shifted blocks were
    # expanded and what they cost in factorizations of K - sigma M (one per point and expansion angle)
    points = _optional(reducer, -1, "expansion_points_hz", whole)
    out["chosen"]["expansion_points_hz"] = [] if points is None else [float(f) for f in np.ravel(points)]
    out["chosen"]["expansion_point_factorizations"] = \
        _optional_scalar(reducer, -1, "expansion_point_factorizations", whole, int) or 0
    if before is not None:
        out["chosen"]["compressed_from_dofs"], out["chosen"]["compressed_to_dofs"] = before, after
        tied = _optional_scalar(reducer, -1, "compressed_tied", whole, int)
        out["chosen"]["compressed_tied"] = None if tied is None else bool(tied)
    out["chosen"].update(_static_moment(reducer, labels, has, whole, prefix))
    out["expansion_point_search"] = {
        "factorizations_spent": _optional_scalar(reducer, -1, "shift_factorizations_spent", whole, int) or 0,
        "rows": _shift_rows(_optional(reducer, -1, "shift_search", whole))}
    out["midpoints"] = midpoints
    out["search"] = rows
    out["search_chosen"] = row
    hankel = {}
    nrigid = _optional_scalar(reducer, -1, "rigid_modes", whole, int) or 0
    for c, lab in enumerate(labels):
        order = _optional_scalar(reducer, c, "hankel_order", has[c], int)
        hsv = _optional(reducer, c, "hankel_singular_values", has[c])
        if order is None and hsv is None:
            continue
        hsv = np.array([]) if hsv is None else np.ravel(hsv)
        entry = {"order": order, "singular_values": _list(hsv)}
        # the scale of C's hankel_order: a model whose every pair is within e x its peak has a 2-norm error below
        # sqrt(t a) e max|T_full|, and no model of k first-order states has one below sigma_(k+1); so at the chosen
        # size e >= sigma_(k+1) / (sqrt(t a) max|T_full|)
        if single_frf.get(lab) and hsv.size:
            full = (np.asarray(single_frf[lab]["full_re"], dtype=float)
                    + 1j * np.asarray(single_frf[lab]["full_im"], dtype=float))
            scale = float(np.sqrt(full[0].size) * np.max(np.abs(full))) if full.size else 0.0
            dofs = system_dofs.get(lab)
            if scale > 0 and dofs is not None:
                states = 2 * max(dofs - nrigid, 0)
                entry.update(scale=scale, chosen_states=states,
                             bound_at_chosen=float(hsv[states] / scale) if states < hsv.size else 0.0)
        hankel[lab] = entry
    out["hankel"] = hankel
    if is_multi and single_frf:
        # the Bode plots and the plotted error show the chosen model: the multi-angle model's responses on the
        # verification grid, by the C reassembly and KFReducedSystemFRF (the multi model's C frf_error is measured
        # on the same grid from the same responses)
        for c, lab in enumerate(labels):
            block = single_frf.get(lab)
            if block is None:
                continue
            if "multi_frf_reduced_re" in has[c]:
                T = (reducer.result(c, "multi_frf_reduced_re") + 1j * reducer.result(c, "multi_frf_reduced_im")
                     ).transpose(2, 0, 1)
            else:
                T = multi.at(reducer.configurations[c]).frf(np.asarray(block["freq_hz"], dtype=float))
            block["chosen_re"], block["chosen_im"] = _list(T.real), _list(T.imag)
            block["chosen_model"] = method
    return out


def _trimming(chosen, configurations, labels):
    """The chosen model's highest flexible frequency in its dynamics and the explicit step it allows, per angle of
    interest, with its trimming (reduction.max_frequency; docs/guide/trimming.md): the systems as the model reassembles
    them (trimmed when the model was reduced with a limit)."""
    limit = chosen.settings.get("max_frequency_hz")
    out = {"max_frequency": chosen.settings.get("max_frequency"),
           "max_frequency_hz": float(limit) if limit else None,
           "top_frequency_hz": {}, "explicit_step_s": {}, "trimmed_modes": {}, "untrimmed_top_frequency_hz": {}}
    for config, lab in zip(configurations, labels):
        system = chosen.at(config)
        out["top_frequency_hz"][lab] = system.top_frequency_hz
        out["explicit_step_s"][lab] = system.explicit_step_s if system.top_frequency_hz > 0 else None
        out["trimmed_modes"][lab] = int(system.trimmed)
        out["untrimmed_top_frequency_hz"][lab] = system.untrimmed_top_hz
    tops = list(out["top_frequency_hz"].values())
    out["top_frequency_hz_max"] = max(tops) if tops else 0.0
    out["explicit_step_s_min"] = 1.0 / (np.pi * max(tops)) if tops and max(tops) > 0 else None
    return out


def build_summary(reducer, single, multi, chosen):
    """The summary of a solved Reducer (reducer.py): its results at every angle of interest and of the whole solve,
    with the scene's names and labels. single, multi, chosen: the reducer's models (multi may be None)."""
    import kryflex
    scene = reducer.scene
    configurations = reducer.configurations
    labels = [scene.label(c) for c in configurations]
    settings = chosen.settings
    has = [set(reducer.result_names(c)) for c in range(len(labels))]
    whole = set(reducer.result_names(-1))

    # alpha_G: an angle of interest (reduction_config), or another named configuration
    index_g = int(reducer.result(-1, "reduction_config").ravel()[0])
    if index_g >= 0:
        label_g = labels[index_g]
    else:
        alpha_g = reducer.result(-1, "reduction_angles")[:, 0]
        label_g = scene.label([float(a) for a in np.degrees(alpha_g)])

    full_freqs, frf, dom, dom_err, mode_count = {}, {}, {}, {}, {}
    for c, lab in enumerate(labels):
        if "full_frequencies_hz" in has[c]:
            full_freqs[lab] = _list(reducer.result(c, "full_frequencies_hz"))
        if "full_order_mode_count" in has[c]:
            mode_count[lab] = {"count": _scalar(reducer, c, "full_order_mode_count", int),
                               "below_hz": _scalar(reducer, c, "full_order_mode_count_below_hz")}
        if "frf_error" in has[c]:
            frf[lab] = dict(freq_hz=_list(reducer.result(c, "frf_frequencies_hz")),
                            full_re=_list(reducer.result(c, "frf_full_re").transpose(2, 0, 1)),
                            full_im=_list(reducer.result(c, "frf_full_im").transpose(2, 0, 1)),
                            reduced_re=_list(reducer.result(c, "frf_reduced_re").transpose(2, 0, 1)),
                            reduced_im=_list(reducer.result(c, "frf_reduced_im").transpose(2, 0, 1)),
                            frf_error=_scalar(reducer, c, "frf_error"),
                            frf_pointwise_error=_optional_scalar(reducer, c, "frf_pointwise_error", has[c]),
                            max_rel_error=_scalar(reducer, c, "frf_error"))
            if "frf_full_rigid_re" in has[c]:   # the elastic measure's: the full response's rigid part
                frf[lab]["full_rigid_re"] = _list(reducer.result(c, "frf_full_rigid_re").transpose(2, 0, 1))
                frf[lab]["full_rigid_im"] = _list(reducer.result(c, "frf_full_rigid_im").transpose(2, 0, 1))
        if "dominant_modes" in has[c]:
            dom[lab] = _ints(reducer.result(c, "dominant_modes"))
            dom_err[lab] = _list(reducer.result(c, "dominant_frequency_error"))

    per = {name: {lab: reducer.result(c, name) for c, lab in enumerate(labels)}
           for name in ("reduced_dofs", "reassembly_rank", "reassembly_sigma_ratio", "static_gain_error",
                        "reassembly_seconds")}
    reassembly_seconds = [float(v.ravel()[0]) for v in per["reassembly_seconds"].values()]
    basis = settings["basis"]
    timings = {}
    for name, key in TIMINGS:
        if name in whole:
            seconds = float(reducer.result(-1, name).ravel()[0])
            if seconds > 0:
                timings[key or ("krylov" if basis == "krylov" else "eigen basis")] = seconds

    summary = {
        "kryflex_version": kryflex.__version__,
        "scene": scene.name, "scene_file": scene.path,
        "inputs": list(scene.input_names), "outputs": list(scene.output_names), "joints": list(scene.revolute),
        "angles_deg": [list(c) for c in configurations], "angle_labels": labels,
        "band_hz": [float(f) for f in settings["band_hz"]], "damping": float(settings["damping"]),
        "damping_model": settings.get("damping_model"),
        "damping_matrices": list(getattr(scene, "damping_matrices", [])),
        "output_quantities": list(getattr(scene, "output_quantities", ["displacement"] * len(scene.output_names))),
        "accuracy": float(settings["accuracy"]), "frf_floor_db": float(scene.verify["frf_floor_db"]),
        "settings": {key: settings[key] for key in ("basis", "moments", "moments_max", "output_blocks", "importance",
                                                     "keep_threshold", "cluster_rtol", "search", "deflation_tol",
                                                     "body_tol", "reduction_angles_deg", "method")
                     if key in settings},
        "full": {"dofs_per_body": dict(zip(scene.body_names, scene.body_dofs)),
                 "system_dofs": _scalar(reducer, -1, "full_system_dofs", int),
                 "rigid_modes": _scalar(reducer, -1, "rigid_modes", int),
                 "frequencies_hz": full_freqs,
                 "mode_count": mode_count,
                 "moments": {lab: _list(reducer.moments(c, "full_moments")) for c, lab in enumerate(labels)}},
        "krylov": {lab: {"frequency_hz": _list(reducer.result(c, "krylov_frequencies_hz")),
                         "importance": _list(reducer.result(c, "krylov_importance")),
                         "kept": [bool(k) for k in reducer.result(c, "krylov_kept")],
                         "deflations": _scalar(reducer, c, "krylov_deflations", int),
                         "gram_condition_raw": _scalar(reducer, c, "gram_condition_raw")}
                   for c, lab in enumerate(labels)},
        "reduction_label": label_g, "reduction_rule": reducer.rule,
        "kept_modes": _ints(reducer.result(-1, "kept_modes")),
        "static_correction_modes": _scalar(reducer, -1, "static_correction_modes", int),
        "reduced": {"dofs_per_body": dict(zip(scene.body_names, _ints(reducer.result(-1, "reduced_dofs_per_body")))),
                    "system_dofs": {lab: int(v.ravel()[0]) for lab, v in per["reduced_dofs"].items()},
                    "frequencies_hz": {lab: _list(reducer.result(c, "reduced_frequencies_hz"))
                                       for c, lab in enumerate(labels)},
                    "moments": {lab: _list(reducer.moments(c, "reduced_moments")) for c, lab in enumerate(labels)},
                    "moment_ratios": {lab: _list(reducer.moments(c, "moment_ratios")) for c, lab in enumerate(labels)},
                    "moment_error": {lab: _list(reducer.result(c, "moment_error")) for c, lab in enumerate(labels)},
                    "static_gain_error": {lab: _none(v.ravel()[0]) for lab, v in per["static_gain_error"].items()},
                    "reassembly_rank": {lab: int(v.ravel()[0]) for lab, v in per["reassembly_rank"].items()},
                    "reassembly_sigma_ratio": {lab: _none(v.ravel()[0])
                                               for lab, v in per["reassembly_sigma_ratio"].items()},
                    "reassembly_seconds": float(np.median(reassembly_seconds)) if reassembly_seconds else None},
        "frf": frf, "dominant_modes": dom, "dominant_freq_error": dom_err,
        "timings_s": timings,
        "performance": _performance(reducer, whole),
        "notes": list(reducer.notes),
    }
    summary.update(_accuracy(reducer, scene, labels, has, whole, chosen, multi, frf))
    summary["reduced"]["trimming"] = _trimming(chosen, configurations, labels)
    if multi is not None:
        m_ratios = {lab: _list(reducer.moments(c, "multi_moment_ratios")) for c, lab in enumerate(labels)}
        m_err = {lab: _list(reducer.result(c, "multi_moment_error")) for c, lab in enumerate(labels)}
        summary["multi_angle"] = {
            "system_dofs": {lab: _scalar(reducer, c, "multi_reduced_dofs", int) for c, lab in enumerate(labels)},
            "dofs_per_body": dict(zip(scene.body_names, _ints(reducer.result(-1, "multi_dofs_per_body")))),
            "moment_ratios": m_ratios,
            "frf_error": {lab: _scalar(reducer, c, "multi_frf_error") for c, lab in enumerate(labels)
                          if "multi_frf_error" in has[c]},
            "frf_pointwise_error": {lab: _scalar(reducer, c, "multi_frf_pointwise_error")
                                    for c, lab in enumerate(labels) if "multi_frf_pointwise_error" in has[c]},
            "frf_max_rel_error": {lab: _scalar(reducer, c, "multi_frf_error") for c, lab in enumerate(labels)
                                  if "multi_frf_error" in has[c]},
            "reduction_angles_deg": multi.settings["reduction_angles_deg"],
            "moment_error": m_err,
            "max_moment_ratio_deviation": {lab: _max_ratio_deviation(m_ratios[lab]) for lab in labels},
            "max_moment_error": {lab: _max_defined(m_err[lab]) for lab in labels}}
    return summary
