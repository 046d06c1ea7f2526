"""Verification report of one reduction: summary.json, report.md (laid out like the paper's study) and plots.

    paths = write_report(summary, out_dir)

writes into out_dir (created if needed):
  summary.json                                   every number, exactly as given
  report.md                                      tables in the order of the paper's Tables 1-6 and Fig. 3
  bode_<angle>deg_<output>_<input>.png           full vs reduced, one per configuration and I/O pair
  bode_overview.png                              magnitudes at every configuration (dominant I/O pair)
  importance_<angle>deg.png                      normalized importance of the Krylov modes, kept ones marked
  moment_ratios.png                              |L_full/L_reduced - 1| against k
  frf_error.png                                  pointwise relative FRF error against frequency
and returns the written paths. Everything is validated and rendered first, into temporary files; only when
all succeeded are they renamed into place (os.replace). A failure raises ReportError (or the plotting error),
removes the temporary files and leaves any earlier report in out_dir untouched.

Summary schema (JSON types only: dict with str keys, list, int, float (finite), str, bool, None; undefined
numbers are None). <label> is an entry of "angle_labels". Keys marked (opt) may be missing.

{
 "kryflex_version": str (opt), "scene": str, "scene_file": str (opt),
 "inputs": [names], "outputs": [names], "joints": [revolute joint names] (opt),
 "angles_deg": [[a1, a2, ..] per configuration, one entry per revolute joint] (opt),
 "angle_labels": ["0", "15", ...]  (file names and table headers; e.g. "0_30" for several joints),
 "band_hz": [f0, f1] (opt), "damping": z (opt), "accuracy": target (opt),
 "settings": {"moments": c, "output_blocks", "importance", "keep_threshold", "deflation_tol",
              "reduction_angles_deg": [[..]], "method": "single-angle" | "multi-angle"} (opt, any keys shown),
 "full": {"dofs_per_body": {body: n} (opt), "system_dofs": e (opt), "rigid_modes": r (opt),
          "body_frequencies_hz": {body: [..]} (opt; free-free component frequencies, lowest few),
          "frequencies_hz": {<label>: [lowest flexible system frequencies]},
          "moments": {<label>: [t x a nested list, per k = 0..c-1]}},
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
             "reassembly_sigma_ratio": {<label>: float} (opt), "reassembly_seconds": float (opt)},
 "frf": {<label>: {"freq_hz": [nf], "full_re": [nf][t][a], "full_im", "reduced_re", "reduced_im",
                   "max_rel_error": float}},
 "dominant_modes": {<label>: [0-based indices into full["frequencies_hz"][<label>]]} (opt),
 "dominant_freq_error": {<label>: [relative error of the matched reduced frequency, same order]} (opt),
 "multi_angle": {"system_dofs": {<label>: h}, "dofs_per_body": {body: v}, "moment_ratios": {<label>: ..},
                 "frf_max_rel_error": {<label>: float}} (opt, every part optional),
 "timings_s": {stage: seconds} (opt), "notes": [str] (opt)
}

This module depends only on the standard library, NumPy and plots.py (no compiled kryflex code).
"""

import json
import math
import os
import re

import numpy as np

from . import plots
from .files import commit, temporary_beside

# A moment ratio r with |r - 1| above this is reported as "not matched exactly".
RATIO_EXACT_TOL = 1e-8
# Show every (output, input) entry in the moment tables up to this many entries, else the dominant one only.
MAX_MOMENT_ENTRIES_SHOWN = 4
# A mismatch list longer than this is cut, the rest being in summary.json.
MAX_MISMATCHES_LISTED = 40
DASH = "—"


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
                _check_matrix(matrix, t, a, ("full", kind, label, k))
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
    for label, indices in (summary.get("dominant_modes") or {}).items():
        n_full = len(_get(summary, ("full", "frequencies_hz", label)) or [])
        bad = [i for i in indices if not isinstance(i, int) or not 0 <= i < n_full]
        if bad:
            raise ReportError(f"summary['dominant_modes'][{label!r}] has indices {bad} outside the "
                              f"{n_full} listed full-order frequencies (0-based indices expected)")


# =============================================================================================== formatting

def fmt_freq(x):
    """Five significant digits, like the paper's frequency tables (0.11060, 57.253, 1217.7)."""
    if x is None:
        return DASH
    text = f"{x:#.5g}"
    return text[:-1] if text.endswith(".") else text


def fmt_ratio(x):
    """Ten significant digits: enough to see a departure from 1 at the 1e-8 exact-match tolerance."""
    return DASH if x is None else f"{x:#.10g}"


def fmt_percent(x, digits=4):
    return DASH if x is None else f"{100.0 * x:.{digits}g} %"


def fmt_general(x):
    if x is None:
        return DASH
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, float):
        return f"{x:.6g}"
    if isinstance(x, (list, tuple)):
        return "[" + ", ".join(fmt_general(v) for v in x) + "]"
    return str(x)


def mode_ranges(numbers):
    """[1, 2, 3, 4, 7, 8] -> '1-4, 7, 8' (runs of three or more collapsed)."""
    numbers = sorted(numbers)
    parts, start = [], 0
    while start < len(numbers):
        end = start
        while end + 1 < len(numbers) and numbers[end + 1] == numbers[end] + 1:
            end += 1
        if end - start >= 2:
            parts.append(f"{numbers[start]}–{numbers[end]}")
        else:
            parts.extend(str(n) for n in numbers[start:end + 1])
        start = end + 1
    return ", ".join(parts) if parts else "none"


def table(header, rows, align=None):
    """A Markdown table; align: string of 'l'/'r' per column (default: first left, rest right)."""
    align = align or "l" + "r" * (len(header) - 1)
    rule = ["---:" if c == "r" else ":---" for c in align]
    lines = ["| " + " | ".join(header) + " |", "| " + " | ".join(rule) + " |"]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def safe_name(text):
    """A file-name-safe form of an angle label or I/O name."""
    return re.sub(r"[^A-Za-z0-9._-]+", "_", str(text)).strip("_") or "x"


def decade_scale(values):
    """Common power of ten p of a row of numbers: max |v| / 10^p in [1, 10); 0 for an all-zero row."""
    biggest = max((abs(v) for v in values if v is not None), default=0.0)
    return 0 if biggest == 0 else int(math.floor(math.log10(biggest)))


class _Context:
    """Derived facts used by several sections (labels, headers, displayed I/O entries)."""

    def __init__(self, summary):
        self.s = summary
        self.labels = list(summary["angle_labels"])
        self.label_g = summary["reduction_label"]
        self.outputs = list(summary["outputs"])
        self.inputs = list(summary["inputs"])
        self.rigid = _get(summary, ("full", "rigid_modes"))
        self.entries = [(o, i) for o in range(len(self.outputs)) for i in range(len(self.inputs))]
        self.dominant_entry = self._dominant_entry()
        self.shown_entries = self.entries if len(self.entries) <= MAX_MOMENT_ENTRIES_SHOWN else [self.dominant_entry]

    def _dominant_entry(self):
        """The (output, input) entry with the largest static gain |L^0| summed over configurations."""
        weight = {e: 0.0 for e in self.entries}
        for label in self.labels:
            moments = self.s["full"]["moments"][label]
            if moments:
                for (o, i) in self.entries:
                    weight[(o, i)] += abs(moments[0][o][i])
        return max(self.entries, key=lambda e: weight[e])

    def angle(self, label):
        """'α = 15°' from angles_deg when available (several joints: 'α = (0°, 30°)'), else from the label."""
        angles = self.s.get("angles_deg")
        if angles is not None:
            values = angles[self.labels.index(label)]
            values = values if isinstance(values, (list, tuple)) else [values]
            if len(values) == 1:
                return f"α = {values[0]:g}°"
            return "α = (" + ", ".join(f"{v:g}°" for v in values) + ")"
        return f"α = {label}°"

    def short_angle(self, label):
        text = self.angle(label)[4:]
        return text + " (α_G)" if label == self.label_g else text

    def entry_name(self, entry):
        o, i = entry
        return f"{self.outputs[o]} ← {self.inputs[i]}"

    def mode_number(self, flex_index):
        """Paper-style mode number of the flex_index-th (0-based) flexible mode: rigid modes come first."""
        return flex_index + 1 + (self.rigid or 0)


# =============================================================================================== sections

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
    lines += ["## 1. Scene and settings", ""]
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
    if s.get("damping") is not None:
        text.append(f"Uniform modal damping: {100 * s['damping']:g} % on both the full and reduced models.")
    if s.get("accuracy") is not None:
        text.append(f"Accuracy target: maximum relative frequency-response error {fmt_percent(s['accuracy'], 3)}.")
    lines += [" ".join(text), ""]
    settings = s.get("settings") or {}
    if settings:
        lines += [table(["setting", "value"], [(k, fmt_general(v)) for k, v in settings.items()], "ll"), ""]
    return lines


def _section_full_frequencies(c):
    s = c.s
    lines = ["## 2. Full-order natural frequencies (cf. Table 1)", ""]
    bodies = _get(s, ("full", "body_frequencies_hz")) or {}
    if bodies:
        dofs = _get(s, ("full", "dofs_per_body")) or {}
        n = max(len(v) for v in bodies.values())
        header = ["Mode"] + [f"Ω_{b} (Hz)" + (f", {dofs[b]} dofs" if b in dofs else "") for b in bodies]
        rows = [[str(m + 1)] + [fmt_freq(v[m]) if m < len(v) else "" for v in bodies.values()] for m in range(n)]
        lines += ["Table 1a. Free-free component frequencies (lowest listed by the pipeline).", "",
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
    lines = ["## 3. Importance of the Krylov modes (cf. Tables 2 and 3)", ""]
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
        if label == c.label_g:
            caption += ", the reduction configuration α_G"
        lines += [caption + "." + (" " + "; ".join(extra) + "." if extra else ""), ""]
        rows = [[f"{m + 1}*" if kept else str(m + 1), fmt_freq(f), f"{imp:.4f}"]
                for m, (f, imp, kept) in enumerate(zip(kr["frequency_hz"], kr["importance"], kr["kept"]))]
        lines += [table(["Mode", "Ω_Krylov (Hz)", "importance"], rows), "", "\\* kept Krylov modes", ""]
    return lines


def _section_alpha_g(c):
    s = c.s
    lines = ["## 4. Choice of the reduction configuration α_G", ""]
    rows = []
    for label in c.labels:
        kept = _kept_numbers(s["krylov"][label])
        rows.append([c.short_angle(label), str(len(kept)), mode_ranges(kept)])
    lines += [table(["configuration", "important modes", "mode numbers"], rows, "lrl"), ""]
    text = f"The reduction basis is built at α_G: {c.angle(c.label_g)}."
    if s.get("reduction_rule"):
        text += f" Reason: {s['reduction_rule']}"
        text += "" if text.endswith(".") else "."
    settings = s.get("settings") or {}
    if settings.get("method"):
        text += f" Method: {settings['method']}."
    if settings.get("reduction_angles_deg"):
        text += f" Reduction angles: {fmt_general(settings['reduction_angles_deg'])} deg."
    lines += [text, ""]
    return lines


def _section_kept(c):
    s = c.s
    kr = s["krylov"][c.label_g]
    count = len(kr["frequency_hz"])
    kept = sorted(s["kept_modes"])
    discarded = [m for m in range(1, count + 1) if m not in kept]
    lines = ["## 5. Kept Krylov modes and static correction", ""]
    text = (f"At α_G ({c.angle(c.label_g)}) the projection mode set keeps {len(kept)} of the {count} Krylov modes: "
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
    lines = ["## 6. Reduced-order component and system models (cf. Table 4)", ""]
    full_dofs = _get(s, ("full", "dofs_per_body")) or {}
    red_dofs = red.get("dofs_per_body") or {}
    if red_dofs:
        parts = [f"{b}: {v}" + (f" (full {full_dofs[b]})" if b in full_dofs else "") for b, v in red_dofs.items()]
        sys_dofs = (red.get("system_dofs") or {}).get(c.label_g)
        full_sys = _get(s, ("full", "system_dofs"))
        sentence = "Projected body models, degrees of freedom: " + "; ".join(parts) + "."
        if sys_dofs is not None:
            sentence += f" Reduced system at α_G: {sys_dofs} dofs" + (f" (full {full_sys})." if full_sys else ".")
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
    return lines


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
    return [f"Table 4b. System natural frequencies at α_G ({c.angle(c.label_g)}): full order Ω and reduced ω.", "",
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
            text = (f"At α_G the {len(dominant.get(c.label_g) or [])} dominant full-order modes are captured to "
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
    lines = ["## 7. Low-frequency moments of the full-order models (cf. Table 5)", ""]
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
        where = f"α = {c.short_angle(label)}" + (f", {c.entry_name(entry)}" if several else "")
        groups.setdefault(where, []).append(f"k = {k} ratio {fmt_ratio(r)}")
    text = (f"**The {model} does NOT match the full-order moments exactly** (|ratio − 1| > {RATIO_EXACT_TOL:g}) "
            f"in {len(found)} place(s): "
            + "; ".join(f"{where}: {', '.join(items)}" for where, items in groups.items()))
    if len(found) > MAX_MISMATCHES_LISTED:
        text += f"; and {len(found) - MAX_MISMATCHES_LISTED} more (see summary.json)"
    text += "."
    if any(label == c.label_g for label, _, _, _ in found) and model.startswith("single"):
        text += (" This includes α_G itself, where the match is exact by construction: "
                 "treat it as a defect of the reduction, not an approximation.")
    return text


def _section_ratios(c):
    s = c.s
    ratios = s["reduced"]["moment_ratios"]
    lines = ["## 8. Ratios of full to reduced moments, L_full^k / L_reduced^k (cf. Table 6)", ""]
    count = max(len(ratios[l]) for l in c.labels)
    for entry in c.shown_entries:
        o, i = entry
        rows = [[str(k)] + [fmt_ratio(ratios[l][k][o][i]) if k < len(ratios[l]) else DASH for l in c.labels]
                for k in range(count)]
        lines += [f"Table 6 ({c.entry_name(entry)}). L_full^k / L_reduced^k, single-angle model built at α_G.", "",
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
    lines = ["## 9. Multi-angle model beside the single-angle model", ""]
    single_body = red.get("dofs_per_body") or {}
    multi_body = multi.get("dofs_per_body") or {}
    bodies = list(dict.fromkeys(list(single_body) + list(multi_body)))
    if bodies:
        rows = [["single-angle (α_G)"] + [str(single_body.get(b, DASH)) for b in bodies],
                ["multi-angle"] + [str(multi_body.get(b, DASH)) for b in bodies]]
        lines += [table(["model"] + [f"{b} dofs" for b in bodies], rows), ""]
    single_sys = red.get("system_dofs") or {}
    multi_sys = multi.get("system_dofs") or {}
    multi_err = multi.get("frf_max_rel_error") or {}
    rows = []
    for label in c.labels:
        rows.append([c.short_angle(label), str(single_sys.get(label, DASH)), str(multi_sys.get(label, DASH)),
                     fmt_percent(s["frf"][label].get("max_rel_error")), fmt_percent(multi_err.get(label))])
    lines += [table(["configuration", "single: system dofs", "multi: system dofs", "single: max FRF error",
                     "multi: max FRF error"], rows), ""]
    if multi.get("moment_ratios"):
        lines += [_mismatch_sentence(c, _mismatches(multi["moment_ratios"], c), "multi-angle model"), ""]
    return lines


def _section_frf(c, plot_names):
    s = c.s
    accuracy = s.get("accuracy")
    lines = ["## 10. Frequency responses (cf. Fig. 3)", ""]
    lines += ["Relative FRF error: the pipeline's maximum over the band, and, as a cross-check, the maximum of the "
              "pointwise error ||H_full − H_red||_F / ||H_full||_F of the plotted responses.", ""]
    rows, passed, judged = [], 0, 0
    for label in c.labels:
        frf = s["frf"][label]
        err = frf.get("max_rel_error")
        freq, full, red = plots.frf_arrays(frf)
        plotted = float(np.max(plots.frf_relative_error(full, red))) if freq.size else None
        verdict = DASH
        if err is not None and accuracy is not None:
            judged += 1
            ok = err <= accuracy
            passed += ok
            verdict = "PASS" if ok else "MISS"
        rows.append([c.short_angle(label), fmt_percent(err), fmt_percent(plotted),
                     fmt_percent(accuracy, 3) if accuracy is not None else DASH, verdict])
    lines += ["Table 7. Maximum relative frequency-response error over the band against the accuracy target.", "",
              table(["configuration", "max relative error", "max pointwise (plotted)", "target", "result"], rows), ""]
    if judged:
        lines += [f"{passed} of {judged} configurations meet the accuracy target.", ""]
    lines += ["![Bode overview](bode_overview.png)", "", "Bode plots, full vs reduced:", ""]
    for label in c.labels:
        links = [f"[{c.entry_name(e)}]({plot_names['bode'][(label, e)]})" for e in c.entries]
        lines.append(f"- {c.short_angle(label)}: " + ", ".join(links))
    lines += ["", "![Relative FRF error](frf_error.png)", "", "![Moment ratios](moment_ratios.png)", "",
              "Importance of the Krylov modes: " + ", ".join(
                  f"[{c.short_angle(l)}]({plot_names['importance'][l]})" for l in c.labels), "",
              f"![Importance at α_G]({plot_names['importance'][c.label_g]})", ""]
    return lines


def _section_timings(c):
    timings = c.s.get("timings_s") or {}
    if not timings:
        return []
    rows = [[stage, f"{seconds:.3g}"] for stage, seconds in timings.items()]
    rows.append(["**total**", f"{sum(timings.values()):.3g}"])
    return ["## 11. Timings", "", table(["stage", "seconds"], rows), ""]


def _section_notes(c):
    notes = c.s.get("notes") or []
    if not notes:
        return []
    return ["## 12. Notes", ""] + [f"- {n}" for n in notes] + [""]


def render_markdown(summary, plot_names):
    """report.md text; plot_names as returned by plot_file_names."""
    c = _Context(summary)
    lines = []
    for section in (_section_scene, _section_full_frequencies, _section_krylov, _section_alpha_g, _section_kept,
                    _section_reduced, _section_moments, _section_ratios, _section_multi):
        lines += section(c)
    lines += _section_frf(c, plot_names)
    lines += _section_timings(c) + _section_notes(c)
    return "\n".join(lines).rstrip() + "\n"


# =============================================================================================== plots

def plot_file_names(summary):
    """{"bode": {(label, (o, i)): file}, "importance": {label: file}} with file-name-safe, distinct names."""
    c = _Context(summary)
    used = set()

    def unique(name):
        stem, candidate, n = name[:-4], name, 2
        while candidate in used:
            candidate, n = f"{stem}_{n}.png", n + 1
        used.add(candidate)
        return candidate

    names = {"bode": {}, "importance": {}}
    for label in c.labels:
        for (o, i) in c.entries:
            names["bode"][(label, (o, i))] = unique(
                f"bode_{safe_name(label)}deg_{safe_name(c.outputs[o])}_{safe_name(c.inputs[i])}.png")
        names["importance"][label] = unique(f"importance_{safe_name(label)}deg.png")
    return names


def _render_plots(summary, plot_names):
    """Yield (file name, PNG bytes) for every figure of the report."""
    c = _Context(summary)
    settings = summary.get("settings") or {}
    arrays = {label: plots.frf_arrays(summary["frf"][label]) for label in c.labels}
    for label in c.labels:
        freq, full, red = arrays[label]
        for (o, i) in c.entries:
            title = f"{c.angle(label)}{' (α_G)' if label == c.label_g else ''}: {c.entry_name((o, i))}"
            yield plot_names["bode"][(label, (o, i))], plots.figure_png_bytes(
                plots.bode_figure(freq, full[:, o, i], red[:, o, i], title))
    o, i = c.dominant_entry
    panels = [(c.short_angle(l), arrays[l][0], arrays[l][1][:, o, i], arrays[l][2][:, o, i]) for l in c.labels]
    yield "bode_overview.png", plots.figure_png_bytes(
        plots.bode_overview_figure(panels, f"{summary['scene']}: full vs reduced, {c.entry_name((o, i))}"))
    for label in c.labels:
        kr = summary["krylov"][label]
        title = f"Krylov mode importance, {c.angle(label)}{' (α_G)' if label == c.label_g else ''}"
        yield plot_names["importance"][label], plots.figure_png_bytes(plots.importance_figure(
            kr["frequency_hz"], kr["importance"], kr["kept"], title,
            threshold=settings.get("keep_threshold"), band_hz=summary.get("band_hz")))
    series = [(f"single, {c.short_angle(l)}", summary["reduced"]["moment_ratios"][l], False) for l in c.labels]
    multi = (summary.get("multi_angle") or {}).get("moment_ratios") or {}
    series += [(f"multi, {c.short_angle(l)}", multi[l], True) for l in c.labels if l in multi]
    yield "moment_ratios.png", plots.figure_png_bytes(plots.moment_ratio_figure(series, RATIO_EXACT_TOL))
    curves = [(c.short_angle(l), arrays[l][0], plots.frf_relative_error(arrays[l][1], arrays[l][2])) for l in c.labels]
    yield "frf_error.png", plots.figure_png_bytes(plots.frf_error_figure(curves, summary.get("accuracy")))


# =============================================================================================== writing

class _StagedFiles:
    """Files written under temporary names in out_dir and renamed into place together by commit().

    Until commit() nothing visible changes in out_dir; abort() removes the temporary files, so a failure
    never leaves a partial or mixed old/new report behind."""

    def __init__(self, out_dir):
        self.out_dir = out_dir
        self.staged = []

    def add(self, name, data):
        final = os.path.join(self.out_dir, name)
        tmp = temporary_beside(final)
        self.staged.append((tmp, final))
        with open(tmp, "wb") as handle:
            handle.write(data)

    def commit(self):
        written = []
        for tmp, final in self.staged:
            commit(tmp, final)
            written.append(final)
        self.staged = []
        return written

    def abort(self):
        for tmp, _ in self.staged:
            if os.path.exists(tmp):
                os.unlink(tmp)
        self.staged = []


def write_report(summary, out_dir):
    """Write summary.json, report.md and the PNG plots into out_dir; return the written paths.

    Raises ReportError (a ValueError) naming the offending key when the summary is incomplete or not plain JSON;
    on any failure no file of this report is left in out_dir (earlier files there are untouched).
    """
    validate_summary(summary)
    text_json = json.dumps(summary, indent=1, allow_nan=False) + "\n"
    plot_names = plot_file_names(summary)
    markdown = render_markdown(summary, plot_names)
    os.makedirs(out_dir, exist_ok=True)
    staging = _StagedFiles(out_dir)
    try:
        for name, data in _render_plots(summary, plot_names):
            staging.add(name, data)
        staging.add("summary.json", text_json.encode("utf-8"))
        staging.add("report.md", markdown.encode("utf-8"))
        return staging.commit()
    except BaseException:
        staging.abort()
        raise


def write_unverified(summary, out_dir):
    """When the full-order verification was skipped (verify.full_order: false): summary.json and a short report.md
    with what is known without the full order (sizes, alpha_G, kept modes, full-order moments). Same guarantees as
    write_report."""
    _check_json_types(summary, ())
    lines = [f"# kryflex reduction: {summary.get('scene', '?')}", "",
             "The full-order verification was skipped (`verify.full_order: false`): no frequency-response or",
             "frequency comparison. Reduced body sizes: " + ", ".join(
                 f"{b} {v}" for b, v in (summary.get("reduced", {}).get("dofs_per_body") or {}).items()) + ".",
             f"Reduction angle α_G: {summary.get('reduction_label')} deg; kept Krylov modes: {summary.get('kept_modes')}.", ""]
    ratios = summary.get("reduced", {}).get("moment_ratios") or {}
    if ratios:
        lines += ["| angle (deg) | max abs(L_full/L_reduced - 1) |", "| :--- | ---: |"]
        for label, r in ratios.items():
            devs = [abs(x - 1) for k in r for row in k for x in row if x is not None]
            lines.append(f"| {label} | {max(devs) if devs else 0:.3e} |")
    os.makedirs(out_dir, exist_ok=True)
    staging = _StagedFiles(out_dir)
    try:
        staging.add("summary.json", (json.dumps(summary, indent=1, allow_nan=False) + "\n").encode("utf-8"))
        staging.add("report.md", ("\n".join(lines) + "\n").encode("utf-8"))
        return staging.commit()
    except BaseException:
        staging.abort()
        raise
