"""The checks that a summary can be reported: the keys the report needs, per-label blocks, shapes, JSON types.

The summary's schema is kryflex.results: one dataclass per block of summary.json, its fields the block's keys
(docs/guide/results.md describes them). The checks here run on the JSON dict (Summary.to_json()), before the report
is rendered, so that a summary written by hand or by another program is refused with the offending key named.

This module depends only on the standard library and NumPy (no compiled kryflex code).
"""
import itertools
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


def _finite_numbers(node):
    """Whether a list holds finite floats only, or lists and tuples of them, every float at the same depth (no path
    built: where a check fails, _check_json_types walks it again to name the element). A level at a time, all its
    elements together in passes of C."""
    level = node
    while True:
        types = set(map(type, level))
        if types == {float}:
            return all(map(math.isfinite, level))
        if not types or not types <= {list, tuple}:
            return False
        level = list(itertools.chain.from_iterable(level))


def _check_json_types(node, path):
    """Reject anything json would refuse or change: numpy objects, NaN/inf, non-str keys."""
    if node is None or isinstance(node, (str, bool, int)):  # numpy integers are not int: rejected below
        return
    if isinstance(node, float):
        if not math.isfinite(node):
            raise ReportError(f"{_key_text(path)} is {node}: JSON has no NaN/inf; use None for an undefined number")
        return
    if isinstance(node, (list, tuple)):
        if _finite_numbers(node):
            return  # finite floats, or lists of them (most of a summary: the FRF blocks), checked in passes of C
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
                              "(see kryflex.results and docs/guide/results.md)")
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
