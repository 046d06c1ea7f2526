"""The summary dict of a reduction (schema in schema.py), from the C reducer's results and the scene's names.

Every number is one the C reducer recorded (KFReducerGetResult); this module only names, labels and shapes them
for JSON: arrays become nested lists, NaN ("negligible" or "not available") becomes None, moments and responses are
laid out (k or frequency, outputs, inputs) as the report reads them.
"""
import numpy as np

# the reducer's stage timings, as the report names them, in the order stages run ("krylov" / "eigen basis": the
# basis of the reducer's type)
TIMINGS = [("time_assembly", "assembly"), ("time_factorization", "factorization"), ("time_basis", None),
           ("time_modes", "krylov modes"), ("time_moments", "moments"), ("time_projection", "projection"),
           ("time_verification", "verification eigensolve")]


def _none(x):
    """A float for JSON, None for NaN."""
    x = float(x)
    return None if np.isnan(x) else x


def _list(a):
    """Nested lists of floats (None for NaN) of an array."""
    a = np.asarray(a, dtype=float)
    if a.ndim == 0:
        return _none(a)
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

    full_freqs, frf, dom, dom_err = {}, {}, {}, {}
    for c, lab in enumerate(labels):
        if "full_frequencies_hz" in has[c]:
            full_freqs[lab] = _list(reducer.result(c, "full_frequencies_hz"))
        if "frf_error" in has[c]:
            frf[lab] = dict(freq_hz=_list(reducer.result(c, "frf_frequencies_hz")),
                            full_re=_list(reducer.result(c, "frf_full_re").transpose(2, 0, 1)),
                            full_im=_list(reducer.result(c, "frf_full_im").transpose(2, 0, 1)),
                            reduced_re=_list(reducer.result(c, "frf_reduced_re").transpose(2, 0, 1)),
                            reduced_im=_list(reducer.result(c, "frf_reduced_im").transpose(2, 0, 1)),
                            max_rel_error=_scalar(reducer, c, "frf_error"))
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
        "accuracy": float(settings["accuracy"]),
        "settings": {key: settings[key] for key in ("basis", "moments", "output_blocks", "importance",
                                                     "keep_threshold", "deflation_tol", "body_tol",
                                                     "reduction_angles_deg", "method")},
        "full": {"dofs_per_body": dict(zip(scene.body_names, scene.body_dofs)),
                 "system_dofs": _scalar(reducer, -1, "full_system_dofs", int),
                 "rigid_modes": _scalar(reducer, -1, "rigid_modes", int),
                 "frequencies_hz": full_freqs,
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
        "notes": list(reducer.notes),
    }
    if multi is not None:
        m_ratios = {lab: _list(reducer.moments(c, "multi_moment_ratios")) for c, lab in enumerate(labels)}
        m_err = {lab: _list(reducer.result(c, "multi_moment_error")) for c, lab in enumerate(labels)}
        summary["multi_angle"] = {
            "system_dofs": {lab: _scalar(reducer, c, "multi_reduced_dofs", int) for c, lab in enumerate(labels)},
            "dofs_per_body": dict(zip(scene.body_names, _ints(reducer.result(-1, "multi_dofs_per_body")))),
            "moment_ratios": m_ratios,
            "frf_max_rel_error": {lab: _scalar(reducer, c, "multi_frf_error") for c, lab in enumerate(labels)
                                  if "multi_frf_error" in has[c]},
            "reduction_angles_deg": multi.settings["reduction_angles_deg"],
            "moment_error": m_err,
            "max_moment_ratio_deviation": {lab: _max_ratio_deviation(m_ratios[lab]) for lab in labels},
            "max_moment_error": {lab: _max_defined(m_err[lab]) for lab in labels}}
    return summary
