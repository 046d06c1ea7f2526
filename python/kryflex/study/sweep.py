"""The runs of the speed-accuracy study and how each is measured.

One reference: a Reducer run with the full-order verification on gives, per angle of interest, the frequency grid
(result frf_frequencies_hz) and the full response (reducer.frf(c, "full")). Every method's model is reassembled at
each angle of interest (ReducedModel.at), its response evaluated on that grid by the C reduced system
(KFReducedSystemFRF) and compared with the full one by the C error measure (KFFRFErrors: relative H-infinity error
per input/output pair, and the pointwise error with a floor). A run's error is the worst over the angles of interest.

Methods (METHODS), each a sweep of its size parameter:
  krylov-single   Krylov single-angle, c = 1..cmax moments, every Krylov mode kept (the paper's fixed recipe)
  krylov-multi    Krylov multi-angle, c = 1..cmax, every mode kept
  krylov-paper    Krylov single-angle, c = 1..cmax, with the scene's importance and keep_threshold, or the -kf_
                  options' (the modes the paper's importance rule keeps)
  eigen-static    the eigenvector (modal) baseline with static correction, over eigen_cover values
  eigen-plain     the modal baseline without static correction
  krylov-raw      the raw recurrence of the paper's eq. (9) (-kf_krylov_raw), c = 1..cmax, when the C library has it
  kryflex         the reducer's own choice: what `kryflex reduce` makes of the scene and the -kf_ options (its
                  accuracy, search, ...), one point, marked on the charts
  krylov-search   the accuracy search over moments at zero alone, over the accuracy targets ACCURACY_SWEEP
  krylov-points   the accuracy search with expansion points inside the band (-kf_max_factorizations POINT_FACTORIZATIONS,
                  the family forced: -kf_shift_family_only), over the same targets; when the C library has them
"""
import math
import time

import numpy as np

from .. import _core

METHODS = ("krylov-single", "krylov-multi", "krylov-paper", "eigen-static", "eigen-plain", "krylov-raw", "krylov-search",
           "krylov-points", "kryflex")
LABELS = {"krylov-single": "Krylov single-angle, fixed c", "krylov-multi": "Krylov multi-angle, fixed c",
          "krylov-paper": "Krylov single-angle, fixed c, scene's keep_threshold",
          "eigen-static": "modal + static correction", "eigen-plain": "modal, no static correction",
          "krylov-raw": "raw recurrence (eq. 9)", "krylov-search": "Krylov search, moments at zero",
          "krylov-points": "Krylov search, expansion points in the band", "kryflex": "kryflex's choice"}
# the accuracy targets the two search families are run at, and the factorizations the points may spend
ACCURACY_SWEEP = (1e-1, 3e-2, 1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 1e-6)
POINT_FACTORIZATIONS = 6
EIGEN_COVERS = (0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0)
CSV_FIELDS = ("method", "parameter", "size_dofs", "system_dofs", "error_hinf", "error_pointwise", "seconds", "chosen",
              "worst_angle_deg", "flexible_dofs", "min_frequency_ratio", "moment_error", "gram_condition",
              "exit_code", "failure", "error_measure", "note")
# a reduced flexible frequency below this fraction of the full model's lowest one is not a mode of the structure
# (Ritz values bound the full ones from above): a spurious near-rigid mode
SPURIOUS_RATIO = 1.0 - 1e-3
# a moment the basis matches exactly, measured with a relative error above this, is lost
LOST_MOMENT = 1e-6


def features():
    """What this C library offers (a library built without some of them still sweeps the rest): the -kf_search and
    -kf_krylov_raw options, the binding's frf_errors (KFFRFErrors) and modal_hankel_singular_values. The option
    names are the settings table's (cli/common.reducer_option_names)."""
    from ..cli.common import reducer_option_names
    names = set(reducer_option_names())
    return {"search": "kf_search" in names, "krylov_raw": "kf_krylov_raw" in names,
            "points": "kf_max_factorizations" in names,
            "frf_errors": hasattr(_core, "frf_errors"), "modal_hsv": hasattr(_core, "modal_hankel_singular_values"),
            "option_names": sorted(names)}


class Study:
    """The study of one loaded Scene: the reference, the runs (sweep()), the Hankel limit (hankel_limit())."""

    def __init__(self, scene, cmax=30, methods=None, feature_flags=None, progress=None):
        self.scene = scene
        self.cmax = int(cmax)
        self.methods = list(methods or METHODS)
        unknown = [m for m in self.methods if m not in METHODS]
        if unknown:
            raise ValueError("unknown method %s: use a comma list of %s" % (", ".join(unknown), ", ".join(METHODS)))
        self.features = feature_flags if feature_flags is not None else features()
        self.progress = progress or (lambda msg: None)
        self.floor_db = float(scene.verify["frf_floor_db"])
        self.reference = None
        # the target the runs read (the scene's, or -kf_accuracy): the reference's, once it has run
        self.accuracy = float(scene.accuracy)
        # the kryflex run's (reducer, seconds): the estimator check (estimator.py) reuses its accuracy search
        self.default_run = None
        self.notes = []
        self.error_measure = ("KFFRFElasticErrors (%s response)" % getattr(scene, "accuracy_measure", "elastic")
                              if self.features["frf_errors"] else
                              "KFFRFError fallback: Frobenius norm over pairs, floor 0 dB (= the relative H-inf "
                              "error for one input and one output)")

    # ------------------------------------------------------------------ the reference

    def run_reference(self):
        """The full-order reference: grid, full responses and full frequencies per angle of interest (collective)."""
        # every Krylov mode kept and no static correction: the reference's own reduced model (not used) cannot fail
        # where the scene's recipe would (a near-zero discarded mode has no static gain to correct)
        # (importance h2: with every mode kept it changes nothing, and the band importance of the fixed recipe
        # fails on main at the merge of the accuracy search: KFDenseModeImportance without the band)
        opts = {"verify": True, "keep_threshold": 0.0, "static_correction": False, "importance": "h2"}
        if self.features["search"]:
            opts["search"] = False          # the reference needs the verification only, not a search
        ref = _core_reducer(self.scene, opts)
        t0 = time.perf_counter()
        ref.reduce()
        self.reference_seconds = time.perf_counter() - t0
        self.reference = ref
        self.accuracy = ref.accuracy()
        if self.features["frf_errors"]:
            self.error_measure = "KFFRFElasticErrors (%s response)" % ref.accuracy_measure()
        self.angles = ref.configurations
        self.grids = [ref.result(c, "frf_frequencies_hz").ravel() for c in range(ref.nconfig)]
        self.full = [ref.frf(c, "full") for c in range(ref.nconfig)]
        # the elastic measure (the scene's accuracy_measure) takes the reference's rigid part out; None: total
        self.full_rigid = [ref.full_rigid(c) for c in range(ref.nconfig)]
        self.full_min_hz = [float(np.nanmin(ref.result(c, "full_frequencies_hz"))) for c in range(ref.nconfig)]
        self.nrigid = int(ref.result(-1, "rigid_modes").ravel()[0])
        self.full_dofs = int(ref.result(-1, "full_system_dofs").ravel()[0])
        return ref

    # ------------------------------------------------------------------ the runs

    def runs(self):
        """(method, parameter, -kf_ options) of every run, in order."""
        out = []
        fixed = {"search": False} if self.features["search"] else {}
        for method in self.methods:
            if method in ("krylov-single", "krylov-multi", "krylov-paper", "krylov-raw"):
                if method == "krylov-raw" and not self.features["krylov_raw"]:
                    continue
                for c in range(1, self.cmax + 1):
                    opts = dict(fixed, moments=c, output_blocks=min(1, c - 1),
                                method="multi-angle" if method == "krylov-multi" else "single-angle")
                    # krylov-paper: the importance and keep_threshold the scene and the -kf_ options give, as
                    # `kryflex reduce` reads them (no keyword: a keyword would override the command line)
                    if method != "krylov-paper":    # every mode kept: the importance measure does not matter
                        opts.update(importance="h2", keep_threshold=0.0)
                    if method == "krylov-raw":
                        opts["krylov_raw"] = True
                    out.append((method, c, opts))
            elif method in ("eigen-static", "eigen-plain"):
                for cover in EIGEN_COVERS:
                    out.append((method, cover, dict(reducer_type="eigen", eigen_cover=cover, keep_threshold=0.0,
                                                    importance="h2",
                                                    static_correction=method == "eigen-static")))
            elif method in ("krylov-search", "krylov-points"):
                if not self.features["search"] or (method == "krylov-points" and not self.features.get("points")):
                    continue
                for acc in ACCURACY_SWEEP:   # the search measures against the full order: verification on
                    opts = dict(search=True, accuracy=acc, verify=True)
                    if method == "krylov-points":
                        opts.update(max_factorizations=POINT_FACTORIZATIONS, shift_family_only=True)
                    out.append((method, acc, opts))
            elif method == "kryflex":   # `kryflex reduce`'s reducer: the scene and the -kf_ options, nothing else
                out.append((method, "default", {}))
        return out

    def skipped(self):
        """Rows for the methods the C library does not offer yet (a note in the CSV instead of a curve)."""
        if "krylov-points" in self.methods and not self.features.get("points"):
            return [_row("krylov-points", "", note="skipped: the C library has no -kf_max_factorizations (expansion "
                                                   "points inside the band)")]
        if "krylov-raw" in self.methods and not self.features["krylov_raw"]:
            return [_row("krylov-raw", "", note="skipped: the C library has no -kf_krylov_raw yet (the raw "
                                                "recurrence of eq. 9 is not in this C library)")]
        return []

    def sweep(self):
        """Runs every run (collective: every rank the same runs in the same order); yields one row (dict) each."""
        if self.reference is None:
            self.run_reference()
        runs = self.runs()
        for k, (method, parameter, opts) in enumerate(runs):
            row = self.run_one(method, parameter, opts)
            self.progress("study %d/%d: %s %s: %s dofs, error %s, %.2f s%s" % (
                k + 1, len(runs), method, parameter, row["system_dofs"], _g(row["error_hinf"]), row["seconds"] or 0,
                ", " + row["failure"] if row["failure"] else ""))
            yield row
        for row in self.skipped():
            yield row

    def run_one(self, method, parameter, opts):
        """One reduction, timed, reassembled and measured at every angle of interest."""
        opts = dict(opts)
        if method != "kryflex":
            opts.setdefault("verify", False)     # the study's reference measures it; no second verification
            if method.startswith("krylov"):      # its moment diagnostics need the full-order moments
                opts.setdefault("full_moments", True)
        row = _row(method, parameter, error_measure=self.error_measure, chosen=int(method == "kryflex"))
        try:
            reducer = _core_reducer(self.scene, opts)
            t0 = time.perf_counter()
            reduction = reducer.reduce()
            row["seconds"] = time.perf_counter() - t0
        except _core.Error as e:
            row.update(exit_code=3, failure="exit 3: %s" % _one_line(e))
            return row
        if method == "kryflex":
            self.default_run = (reducer, row["seconds"])
        model = reduction.model
        row["size_dofs"] = int(sum(model.sizes))
        worst = (-1.0, None)
        system_dofs, flexible, ratios, pointwise = 0, 0, [], []
        for c, angle in enumerate(self.angles):
            system = model.at(angle)
            system_dofs = max(system_dofs, system.dofs)
            flexible = max(flexible, len(system.frequencies_hz))
            if len(system.frequencies_hz):
                ratios.append(float(np.min(system.frequencies_hz)) / self.full_min_hz[c])
            Tr = system.frf(self.grids[c])
            hinf, pw = self.errors(self.full[c], Tr, self.full_rigid[c])
            pointwise.append(pw)
            if not hinf <= worst[0]:        # NaN counts as the worst
                worst = (hinf, angle)
        row.update(system_dofs=system_dofs, flexible_dofs=flexible, error_hinf=worst[0],
                   worst_angle_deg=" ".join("%g" % a for a in worst[1]), error_pointwise=_nanmax(pointwise),
                   min_frequency_ratio=min(ratios) if ratios else math.nan)
        row["moment_error"], row["gram_condition"] = self._moment_diagnostics(reducer, method, parameter)
        failures = []
        if not row["error_hinf"] <= 1.0:
            failures.append("error > 1")
        if row["min_frequency_ratio"] < SPURIOUS_RATIO:
            failures.append("spurious near-zero mode (lowest reduced/full frequency %.2g)" % row["min_frequency_ratio"])
        if row["moment_error"] > LOST_MOMENT:
            failures.append("lost moments (%.2g)" % row["moment_error"])
        if method == "kryflex":
            row["exit_code"], row["note"] = self._default_outcome(reducer, row)
        row["failure"] = "; ".join(failures)
        return row

    def errors(self, Tf, Tr, rigid=None):
        """(relative H-inf error per pair, pointwise error with the floor), both from C, on the elastic response when
        the reference's rigid part is given."""
        if self.features["frf_errors"]:
            hinf, pw = _core.frf_errors(Tf, Tr, self.floor_db, rigid=rigid)
            return float(hinf), float(pw)
        return _core.frf_error(Tf, Tr, 0.0), _core.frf_error(Tf, Tr, self.floor_db)

    def _moment_diagnostics(self, reducer, method, c):
        """(worst relative error of the c moments the basis matches exactly, Gram condition of the raw recurrence)
        at the expansion angle, from the reducer's own results; NaN for the modal baseline and where not recorded.
        The fixed-c single-angle basis matches c moments at alpha_G; the multi-angle basis c at each of its angles."""
        if not method.startswith("krylov") or method in ("krylov-search", "krylov-points"):  # sized by the search
            return math.nan, math.nan
        whole = reducer.result_names(-1)
        if "reduction_config" not in whole:
            return math.nan, math.nan
        cfg = reducer.result(-1, "reduction_config").ravel()
        if not len(cfg) or not np.isfinite(cfg[0]) or cfg[0] < 0:
            return math.nan, math.nan
        cfg = int(cfg[0])
        names = reducer.result_names(cfg)
        name = "multi_moment_error" if method == "krylov-multi" else "moment_error"
        err = reducer.result(cfg, name).ravel()[:int(c)] if name in names else np.array([])
        gram = reducer.result(cfg, "gram_condition_raw").ravel() if "gram_condition_raw" in names else np.array([])
        return _nanmax(err), _nanmax(gram)

    def _default_outcome(self, reducer, row):
        """(exit code `kryflex reduce` gives this model, note): 6 when the target is missed, by the C reducer's
        target_met when it records one, else by the study's error against the accuracy the reducer read."""
        accuracy = reducer.accuracy()
        if "target_met" in reducer.result_names(-1):
            met = bool(reducer.result(-1, "target_met").ravel()[0])
            source = "the reducer's target_met"
        else:
            met = row["error_hinf"] <= accuracy
            source = "the study's error against the accuracy (the reducer records no target_met yet)"
        return (0 if met else 6), "accuracy %g %s, by %s" % (accuracy, "met" if met else "missed", source)

    # ------------------------------------------------------------------ the Hankel limit

    def hankel_limit(self, eigen_cover=8.0):
        """The smallest error any model of n flexible second-order dofs can reach (Hankel singular values of the
        full model's flexible part): {"dofs": system dofs n + rigid, "error": sigma_(2n+1) / peak, "source": text},
        the worst over the angles of interest, peak = the full response's largest entry over the band. None when
        the C library gives no Hankel singular values yet. An H-inf bound over all frequencies: a band-limited
        error may dip below it slightly."""
        per_angle, source = [], None
        ref = self.reference
        if any("hankel_singular_values" in ref.result_names(c) for c in range(ref.nconfig)):
            for c in range(ref.nconfig):
                per_angle.append(ref.result(c, "hankel_singular_values").ravel())
            source = "the reducer's hankel_singular_values (per angle)"
        elif "hankel_singular_values" in ref.result_names(-1):
            hsv = ref.result(-1, "hankel_singular_values")
            per_angle = [np.asarray(hsv)[..., c].ravel() if np.ndim(hsv) > 1 else np.ravel(hsv)
                         for c in range(ref.nconfig)]
            source = "the reducer's hankel_singular_values (whole solve)"
        elif self.features["modal_hsv"]:
            # the full model's flexible part as the modal baseline resolves it: modes up to eigen_cover x the band top
            model = _core_reducer(self.scene, dict(reducer_type="eigen", eigen_cover=eigen_cover, keep_threshold=0.0,
                                                  importance="h2",
                                                  static_correction=False, verify=False)).reduce().model
            for angle in self.angles:
                s = model.at(angle)
                nr = s.dofs - len(s.frequencies_hz)
                phi = s.modes[:, nr:]
                per_angle.append(np.ravel(_core.modal_hankel_singular_values(
                    s.eigenvalues[nr:], s.C @ phi, phi.T @ s.B, self.scene.damping)))
            source = "modal_hankel_singular_values of the modal model with modes up to %g x the band top" % eigen_cover
        if not per_angle:
            return None
        n = min(len(h) for h in per_angle) // 2
        peaks = [float(np.max(np.abs(T))) for T in self.full]
        bound = np.array([max(h[2 * k] / p if 2 * k < len(h) else 0.0 for h, p in zip(per_angle, peaks))
                          for k in range(n)])
        return {"dofs": np.arange(n) + self.nrigid, "flexible": np.arange(n), "error": bound, "source": source}


# ---------------------------------------------------------------------------------------------- helpers

def _core_reducer(scene, opts):
    from ..reducer import Reducer
    return Reducer(scene, quiet=True, **opts)


def _row(method, parameter, **values):
    row = {k: "" for k in CSV_FIELDS}
    row.update(method=method, parameter=parameter, chosen=0, exit_code=0, seconds=math.nan, error_hinf=math.nan,
               error_pointwise=math.nan, size_dofs="", system_dofs="", moment_error=math.nan,
               gram_condition=math.nan, min_frequency_ratio=math.nan)
    row.update(values)
    return row


def _nanmax(values):
    values = np.asarray(values, dtype=float).ravel()
    values = values[np.isfinite(values)]
    return float(values.max()) if values.size else math.nan


def _g(x):
    return "n/a" if x is None or (isinstance(x, float) and math.isnan(x)) else "%.3g" % x


def _one_line(e):
    """The C message on one line, without the ';' that separates a row's failure modes."""
    return " ".join(str(e).replace(";", ",").split())
