"""The summary a report is made from: its schema, and the checks that it can be reported.

Summary schema (JSON types only: dict with str keys, list, int, float (finite), str, bool, None; undefined
numbers are None). <label> is an entry of "angle_labels". Keys marked (opt) may be missing.

{
 "kryflex_version": str (opt), "scene": str, "scene_file": str (opt),
 "inputs": [names], "outputs": [names], "joints": [revolute joint names] (opt),
 "angles_deg": [[a1, a2, ..] per configuration, one entry per revolute joint] (opt),
 "angle_labels": ["0", "15", ...]  (file names and table headers; e.g. "0_30" for several joints; ["structure"]
                                  for a scene without revolute joints, whose angles_deg is [[]]),
 "band_hz": [f0, f1] (opt), "damping": z (opt), "accuracy": target (opt), "frf_floor_db": dB (opt),
 "settings": {"moments": c, "moments_max", "output_blocks", "importance", "keep_threshold", "cluster_rtol",
              "search", "deflation_tol", "reduction_angles_deg": [[..]], "method"} (opt, any keys shown),

 -- the verdict, always on the model the reducer chose (issue 11; all (opt) for summaries written before it) --
 "accuracy_measure": "elastic" | "total" (opt; the response the errors are of: the total minus its rigid-body and
                     mechanism part, or the total),
 "error_definition": str (the one measure: relative H-infinity error per input/output pair over the band, of the
                     accuracy_measure's response),
 "pointwise_definition": str (the pointwise error with a floor: information, never the verdict),
 "chosen_method": "single-angle" | "multi-angle"   (C chosen_method),
 "target_met": bool | None   (C target_met: error <= accuracy at every angle of interest AND every midpoint;
                              None when no error was measured or estimated; a reducer that records no
                              verdict gets the same rule applied to the errors it recorded),
 "error_max": float | None   (C error_max: the chosen model's worst error over angles and midpoints),
 "error_estimated": bool     (C error_estimated: true when the reference was the a-posteriori estimator),
 "reference_check": {"error", "rtol", "per_angle": {<label>: {"error", "frequency_hz"}}} | None (opt; the full-order
                    reference against direct solves of the full system, C reference_check_*),
 "moments_matched": c | None, "multi_moments_matched": c | None   (moments of each family's model),
 "chosen": {"method", "moments": c, "dofs_per_body": {body: v}, "dofs": sum of v, "system_dofs": {<label>: h},
            "expansion_angles_deg": [[..]], "kept_modes": [1-based Krylov modes] | None (multi-angle),
            "kept_clusters": int | "per body" | None (None: every cluster, or not known),
            "frf_error": {<label>: e}  (THE measure, the chosen model's C frf_error / multi_frf_error),
            "frf_pointwise_error": {<label>: e | None}  (information),
            "worst_error": e, "worst_where": <label> or a midpoint's label, "worst_kind": "angle" | "midpoint"},
 "midpoints": [{"angles_deg": [..], "label": "7.5", "frf_error": e | None (the chosen model's)}],
 "search": [{"family": "single-angle" | "multi-angle", "moments": c, "kept_clusters": int | "per body" | None (all),
             "expansion_angles": n, "reduced_dofs": n (sum over bodies), "max_system_dofs": n, "error": e}]
           (C search_table, one row per candidate evaluated), "search_chosen": row index of the chosen model | None,
 "expansion_point_search": {"factorizations_spent": n (C shift_factorizations_spent),
                            "rows": [{"moments", "points", "reduced_dofs", "system_dofs", "error",
                                      "factorizations_spent"}] (C shift_search)} (opt; -kf_max_factorizations;
           the chosen model's "expansion_points_hz": [f] and "expansion_point_factorizations": n are in "chosen"),
 "hankel": {<label>: {"order": r (C hankel_order: first-order states the target needs),
                      "singular_values": [descending] (C hankel_singular_values)}},
 -- the paper's study --
 "full": {"dofs_per_body": {body: n} (opt), "system_dofs": e (opt), "rigid_modes": r (opt),
          "body_frequencies_hz": {body: [..]} (opt; free-free component frequencies, lowest few),
          "frequencies_hz": {<label>: [lowest flexible system frequencies]},
          "moments": {<label>: [t x a nested list, per k = 0..c-1]} (None entries: not computed, the fixed recipe
                     without verification or -kf_full_moments)},
 "krylov": {<label>: {"frequency_hz": [c], "importance": [c] (normalized), "kept": [c bools],
                      "deflations": int (opt), "gram_condition_raw": float|None (opt)}},
 "reduction_label": <label> of alpha_G, "reduction_rule": str (opt; why this alpha_G),
 "kept_modes": [1-based Krylov mode numbers at alpha_G], "static_correction_modes": int (opt),
 "static_correction_frequency_hz": [..] (opt),
 "reduced": {"dofs_per_body": {body: v} (opt), "body_frequencies_hz": {body: [..]} (opt),
             "system_dofs": {<label>: h} (opt), "frequencies_hz": {<label>: [..]},
             "moments": {<label>: [same layout as full]} (opt),
             "moment_ratios": {<label>: [t x a per k]}  (full/reduced; None where the full moment is negligible),
             "static_gain_error": {<label>: float} (opt), "reassembly_rank": {<label>: int} (opt),
             "reassembly_sigma_ratio": {<label>: float} (opt), "reassembly_seconds": float (opt),
             "trimming": {"max_frequency": str|float|None, "max_frequency_hz": float|None,
                          "top_frequency_hz", "untrimmed_top_frequency_hz", "explicit_step_s", "trimmed_modes":
                          {<label>: ..}, "top_frequency_hz_max": float, "explicit_step_s_min": float|None} (opt)},
 "frf": {<label>: {"freq_hz": [nf], "full_re": [nf][t][a], "full_im", "reduced_re", "reduced_im" (the
                   single-angle model), "chosen_re", "chosen_im" (opt: the multi-angle model's, when it was chosen;
                   the plots draw the chosen model), "frf_error": float (single-angle model, relative H-inf),
                   "frf_pointwise_error": float | None (single-angle model, information),
                   "max_rel_error": float (= frf_error, the name scripts before issue 11 read),
                   "full_rigid_re", "full_rigid_im": [nf][t][a] (opt: the full response's rigid-body and
                   mechanism part, with the elastic accuracy measure)}},
 "dominant_modes": {<label>: [0-based indices into full["frequencies_hz"][<label>]]} (opt),
 "dominant_freq_error": {<label>: [relative error of the matched reduced frequency, same order]} (opt),
 "multi_angle": {"system_dofs": {<label>: h}, "dofs_per_body": {body: v}, "moment_ratios": {<label>: ..},
                 "frf_error": {<label>: float}, "frf_pointwise_error": {<label>: float},
                 "frf_max_rel_error": {<label>: float} (= frf_error)} (opt, every part optional),
 "timings_s": {stage: seconds} (opt), "notes": [str] (opt),
 "performance": {"factorization_s", "solves_s", "whole_s", "ratio" ((whole - verification) / (factorization +
                 solves)), "solve_calls", "solve_columns", "refinement_solves", "blocks_unconverged" (block solves left
                 above -kf_refine_rtol after escalation), "blocks_escalated" (escalated), "residual_first_max",
                 "residual_final_max", "memory_estimate_mb", "reference_eigensolve_s", "reference_check_s" (the
                 verification's eigensolves and direct solves), "search_s" (the accuracy search)} (opt; C results
                 time_* / solve_*)
 "paper": {...} (opt; scenes with paper: lee: the paper's tables and kryflex's fixed-recipe answer, kryflex/paper.py)
}

This module depends only on the standard library, NumPy and plots.py (no compiled kryflex code).
"""
import math

import numpy as np


class ReportError(ValueError):
    """The summary cannot be turned into a report; the message names the offending key and the fix."""


# =============================================================================================== validation

REQUIRED_KEYS = [
    ("scene",), ("inputs",), ("outputs",), ("angle_labels",),
    ("full", "frequencies_hz"), ("full", "moments"),
    ("krylov",), ("reduction_label",), ("kept_modes",),
    ("reduced", "frequencies_hz"), ("reduced", "moment_ratios"),
    ("frf",),
]
# Keys that must hold one entry per configuration label.
PER_LABEL_KEYS = [("full", "frequencies_hz"), ("full", "moments"), ("krylov",), ("reduced", "moment_ratios"), ("frf",)]


def _key_text(path):
    return "summary" + "".join(f"[{p!r}]" for p in path)


def _get(summary, path, default=None):
    node = summary
    for part in path:
        if not isinstance(node, dict) or part not in node:
            return default
        node = node[part]
    return node


def _check_json_types(node, path):
    """Reject anything json would refuse or change: numpy objects, NaN/inf, non-str keys."""
    if node is None or isinstance(node, (str, bool, int)):  # numpy integers are not int: rejected below
        return
    if isinstance(node, float):
        if not math.isfinite(node):
            raise ReportError(f"{_key_text(path)} is {node}: JSON has no NaN/inf; use None for an undefined number")
        return
    if isinstance(node, (list, tuple)):
        for index, item in enumerate(node):
            _check_json_types(item, path + (index,))
        return
    if isinstance(node, dict):
        for key, value in node.items():
            if not isinstance(key, str):
                raise ReportError(f"{_key_text(path)} has key {key!r} of type {type(key).__name__}: use str keys")
            _check_json_types(value, path + (key,))
        return
    raise ReportError(f"{_key_text(path)} is a {type(node).__module__}.{type(node).__name__}, not a JSON type: "
                      "convert with float()/int()/.tolist() before calling write_report")


def _check_matrix(value, rows, cols, path, allow_none=False):
    if not isinstance(value, (list, tuple)) or len(value) != rows or any(
            not isinstance(row, (list, tuple)) or len(row) != cols for row in value):
        raise ReportError(f"{_key_text(path)} must be a {rows} x {cols} nested list (outputs x inputs)")
    if not allow_none and any(v is None for row in value for v in row):
        raise ReportError(f"{_key_text(path)} contains None; only moment ratios may be undefined")


def _validate_accuracy(summary, labels, t, a):
    """The verdict keys (all optional): types the report relies on."""
    for key in ("target_met", "error_estimated"):
        if summary.get(key) is not None and not isinstance(summary[key], bool):
            raise ReportError(f"summary[{key!r}] must be true, false or null, got {summary[key]!r}")
    if summary.get("chosen_method") not in (None, "single-angle", "multi-angle"):
        raise ReportError(f"summary['chosen_method'] = {summary['chosen_method']!r}: "
                          "'single-angle' or 'multi-angle' expected")
    chosen = summary.get("chosen") or {}
    for name in ("frf_error", "frf_pointwise_error"):
        unknown = set(chosen.get(name) or {}) - set(labels)
        if unknown:
            raise ReportError(f"summary['chosen'][{name!r}] has labels {sorted(unknown)} not in angle_labels")
    for k, m in enumerate(summary.get("midpoints") or []):
        if not isinstance(m, dict) or not isinstance(m.get("label"), str) or "frf_error" not in m:
            raise ReportError(f"summary['midpoints'][{k}] must be a dict with 'label' (str) and 'frf_error'")
    rows = summary.get("search") or []
    for k, row in enumerate(rows):
        if not isinstance(row, dict) or "family" not in row or "error" not in row:
            raise ReportError(f"summary['search'][{k}] must be a dict with at least 'family' and 'error'")
    index = summary.get("search_chosen")
    if index is not None and not (isinstance(index, int) and 0 <= index < len(rows)):
        raise ReportError(f"summary['search_chosen'] = {index!r} is not a row of summary['search']")
    for label in labels:
        frf = summary["frf"][label]
        if ("chosen_re" in frf) != ("chosen_im" in frf):
            raise ReportError(f"summary['frf'][{label!r}] needs both chosen_re and chosen_im, or neither")
        if "chosen_re" in frf:
            for name in ("chosen_re", "chosen_im"):
                shape = np.shape(np.asarray(frf[name], dtype=float))
                if shape != (len(frf["freq_hz"]), t, a):
                    raise ReportError(f"{_key_text(('frf', label, name))} has shape {shape}, expected "
                                      f"(len(freq_hz), outputs, inputs) = {(len(frf['freq_hz']), t, a)}")


def validate_summary(summary):
    """Raise ReportError naming the first problem; return nothing if the summary can be reported."""
    if not isinstance(summary, dict):
        raise ReportError(f"summary must be a dict, got {type(summary).__name__}")
    for path in REQUIRED_KEYS:
        if _get(summary, path) is None:
            raise ReportError(f"{_key_text(path)} is missing: the report needs it "
                              "(see the schema in kryflex/report.py)")
    _check_json_types(summary, ())
    labels = summary["angle_labels"]
    if not labels or len(set(labels)) != len(labels) or not all(isinstance(a, str) for a in labels):
        raise ReportError("summary['angle_labels'] must be a non-empty list of distinct strings")
    angles = summary.get("angles_deg")
    if angles is not None and len(angles) != len(labels):
        raise ReportError(f"summary['angles_deg'] has {len(angles)} configurations but angle_labels has {len(labels)}")
    if summary["reduction_label"] not in labels:
        raise ReportError(f"summary['reduction_label'] = {summary['reduction_label']!r} "
                          f"is not one of angle_labels {labels}")
    for path in PER_LABEL_KEYS:
        block = _get(summary, path)
        for label in labels:
            if label not in block:
                raise ReportError(f"{_key_text(path + (label,))} is missing: every angle label needs an entry")
    t, a = len(summary["outputs"]), len(summary["inputs"])
    if t == 0 or a == 0:
        raise ReportError("summary['inputs'] and summary['outputs'] must name at least one input and one output")
    for label in labels:
        krylov = summary["krylov"][label]
        sizes = {name: len(krylov.get(name) or []) for name in ("frequency_hz", "importance", "kept")}
        if len(set(sizes.values())) != 1:
            raise ReportError(f"summary['krylov'][{label!r}] lists of different lengths {sizes}: "
                              "one entry per Krylov mode")
        for kind in ("moments",):
            for k, matrix in enumerate(summary["full"][kind][label]):
                _check_matrix(matrix, t, a, ("full", kind, label, k), allow_none=True)  # None: not computed
        for k, matrix in enumerate(summary["reduced"]["moment_ratios"][label]):
            _check_matrix(matrix, t, a, ("reduced", "moment_ratios", label, k), allow_none=True)
        frf = summary["frf"][label]
        for name in ("freq_hz", "full_re", "full_im", "reduced_re", "reduced_im"):
            if name not in frf:
                raise ReportError(f"{_key_text(('frf', label, name))} is missing")
        nf = len(frf["freq_hz"])
        for name in ("full_re", "full_im", "reduced_re", "reduced_im"):
            shape = np.shape(np.asarray(frf[name], dtype=float))
            if shape != (nf, t, a):
                raise ReportError(f"{_key_text(('frf', label, name))} has shape {shape}, expected "
                                  f"(len(freq_hz), outputs, inputs) = {(nf, t, a)}")
    _validate_accuracy(summary, labels, t, a)
    for label, indices in (summary.get("dominant_modes") or {}).items():
        n_full = len(_get(summary, ("full", "frequencies_hz", label)) or [])
        bad = [i for i in indices if not isinstance(i, int) or not 0 <= i < n_full]
        if bad:
            raise ReportError(f"summary['dominant_modes'][{label!r}] has indices {bad} outside the "
                              f"{n_full} listed full-order frequencies (0-based indices expected)")
