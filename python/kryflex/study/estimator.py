"""The a-posteriori error estimator against the truth (is the search's estimate safe to stop on?): the accuracy search run twice on the same
scene, once measuring every candidate against the full-order reference (verify.full_order on) and once estimating
it against the richest candidate (verify.full_order off, result error_estimated 1), the two search tables joined
candidate by candidate.

    check = EstimatorCheck(scene).run()          # two reductions (collective), or one when reuse= gives the other
    check.rows                                   # one dict per candidate both searches tried (FIELDS)
    check.summary()                              # ratios estimate / true, false passes, the chosen models

A search-table column is one candidate: family (0 single-angle, 1 multi-angle), moments c, kept clusters (-1 every
mode), expansion angles, reduced dofs (summed over bodies), system dofs, error, variant (0 split, 1 tied, 2 tied
without the static correction: -kf_shared_directions; src/reducer/search.c). The variant is part of the key: under
-kf_shared_directions auto the search makes a split pass and a tied pass over the same (c, kept). The table does
not say which expansion angle a single-angle candidate used, nor where a multi-angle one started, so the key adds it
(`start`, see _starts): with reduction_angle auto every angle of interest is tried as alpha_G in turn, and the same
(c, kept) comes back once per angle with a different error.

Lower bounds: the search stops measuring a candidate at the first evaluation point (angles of interest, then the
midpoints) where its error exceeds the accuracy (KFCandidateEvaluate_Private), and the table does not record that it
stopped. A recorded error above the accuracy is then the candidate's error at the points measured so far: a lower
bound of its error, unless there is a single evaluation point. Such values are marked (true_lower_bound,
estimate_lower_bound) and kept out of the ratios; they still decide pass or fail (a lower bound above the accuracy
fails), so the false passes and false fails are counted on every joined candidate.
"""
import math
import time

import numpy as np

from .. import _core

SINGLE, MULTI = 0, 1
FAMILIES = {SINGLE: "single-angle", MULTI: "multi-angle"}
SPLIT = 0
VARIANTS = {SPLIT: "split", 1: "tied", 2: "tied, no static correction"}
COMPRESSED = (3, 4)     # search-table rows of the chosen model compressed (body by body, tied across the bodies)
FIELDS = ("family", "moments", "kept_clusters", "expansion_angles", "start_deg", "variant", "reduced_dofs", "system_dofs",
          "true_error", "true_lower_bound", "estimated_error", "estimate_lower_bound", "ratio", "verdict",
          "chosen_full_order", "chosen_estimator")
# the ratios where pass or fail is decided: candidates whose true error is at least accuracy / DECISION_BAND (far
# below the accuracy the true error is the full-order reference's own floor, ~1e-6, not the model's)
DECISION_BAND = 10.0
# C records an error that came out NaN as PETSC_MAX_REAL (a model that cannot be evaluated): shown as inf
NAN_ERROR = 1e300


class EstimatorCheckError(Exception):
    """The two searches cannot be joined (or were not searches): the message says why."""


class SearchRun:
    """One accuracy search: its reducer, time, candidates (search table columns with their key) and chosen model."""

    def __init__(self, reducer, seconds, scene):
        self.reducer = reducer
        self.seconds = seconds
        names = reducer.result_names(-1)
        if "search_table" not in names:
            raise EstimatorCheckError("the reduction made no accuracy search (no search_table result): the estimator "
                                      "is checked on the search's candidates (reduction.search: true)")
        self.estimated = _whole(reducer, "error_estimated") == 1.0
        self.error_max = _whole(reducer, "error_max")
        self.target_met = _whole(reducer, "target_met")
        self.candidates = read_search_table(reducer, scene)
        self.chosen = chosen_candidate(reducer, scene, self.candidates)


def read_search_table(reducer, scene):
    """The search table as a list of candidates (dicts: family, c, kept, nexp, start, variant, size, sysdofs, error,
    key, lower_bound), in the order the search tried them. A table of 7 rows (a library before the variant) is split."""
    table = np.asarray(reducer.result(-1, "search_table"), float)
    if table.ndim != 2 or table.shape[0] not in (7, 8):
        raise EstimatorCheckError("search_table of shape %s: expected 8 rows (family, c, kept clusters, expansion "
                                  "angles, reduced dofs, system dofs, error, variant)" % (table.shape,))
    accuracy = reducer.accuracy()      # the target the search pruned against (-kf_accuracy over the scene's)
    npoints = evaluation_points(reducer.configurations)
    out = []
    for col in table.T:
        if len(col) > 7 and int(col[7]) in COMPRESSED:     # the chosen model compressed: not a search candidate
            continue
        error = float(col[6])
        if error >= NAN_ERROR:
            error = math.inf
        out.append(dict(family=int(col[0]), c=int(col[1]), kept=int(col[2]), nexp=int(col[3]), size=int(col[4]),
                        sysdofs=int(col[5]), error=error, lower_bound=npoints > 1 and not error <= accuracy,
                        variant=int(col[7]) if len(col) > 7 else SPLIT))
    for cand, start in zip(out, _starts(reducer, scene, out)):
        cand["start"] = start
        cand["key"] = (cand["family"], cand["c"], cand["kept"], cand["nexp"], start, cand["variant"])
    return out


def evaluation_points(configurations):
    """Where the search measures a candidate: the angles of interest and, for a jointed scene, the midpoints between
    consecutive ones (KFReducerEvalPoints_Private)."""
    n = len(configurations)
    jointed = n > 0 and len(configurations[0]) > 0
    return n + (n - 1 if jointed and n > 1 else 0)


def _starts(reducer, scene, cands):
    """Per candidate, what the table leaves out of its key. Single-angle: the index of its alpha_G among the angles
    of interest (reduction_angle auto: the search tries each in order, a block of rows each, and a block starts
    with a whole-basis row (kept -1) whose c does not continue the moments loop before it), -1 for a named alpha_G.
    Multi-angle: the first expansion angle (the best single-angle model's alpha_G, result reduction_config: the
    rest follow from it, farthest first), -1 for named expansion angles. Under -kf_shared_directions auto the split
    pass and the tied pass (variant 0, then 1 and 2 interleaved) each go through the angles: blocks are counted per
    pass."""
    auto_alpha = scene.reduction["reduction_angle"] == "auto"
    named_multi = bool(scene.reduction["reduction_angles"])
    first = _whole(reducer, "reduction_config")
    starts, blocks, prevs = [], {}, {}
    for cand in cands:
        if cand["family"] != SINGLE:
            starts.append(-1 if named_multi else (int(first) if first is not None else -1))
            continue
        if cand["kept"] == -2:   # each body its share of the best single-angle model: at its alpha_G, after the blocks
            starts.append(int(first) if auto_alpha and first is not None else -1)
            continue
        tied = cand["variant"] != SPLIT
        prev = prevs.get(tied)
        if prev is None or (cand["kept"] == -1 and (prev["kept"] != -1 or prev["c"] >= cand["c"])):
            blocks[tied] = blocks.get(tied, -1) + 1
        prevs[tied] = cand
        starts.append(blocks[tied] if auto_alpha else -1)
    for tied, block in blocks.items():
        nblocks = block + 1
        if auto_alpha and nblocks != reducer.nconfig:
            raise EstimatorCheckError("the %s single-angle rows of the search table fall into %d blocks, not one per "
                                      "configuration (%d): cannot tell which reduction configuration each candidate "
                                      "used" % ("tied" if tied else "split", nblocks, reducer.nconfig))
    nblocks = max([b + 1 for b in blocks.values()] or [0])
    if not auto_alpha and nblocks > 1:
        raise EstimatorCheckError("the single-angle rows of the search table fall into %d blocks with a named "
                                  "alpha_G: cannot tell the candidates apart" % nblocks)
    return starts


def chosen_candidate(reducer, scene, cands):
    """The candidate the reduction chose (chosen_method; moments_matched or multi_moments_matched; the reduced dofs
    of that model, or chosen_search_dofs; its alpha_G, reduction_config; chosen_variant), or None when no table column matches it (the search's fallback
    model when it tried no single-angle one)."""
    method = _whole(reducer, "chosen_method")
    if method == 1.0:
        family, c = MULTI, _whole(reducer, "multi_moments_matched")
        size = _sum(reducer, "multi_dofs_per_body")
        angles = np.asarray(reducer.result(-1, "multi_reduction_angles"), float)
        nexp = angles.shape[1] if angles.ndim == 2 else angles.size
        start = None
    else:
        family, c, nexp = SINGLE, _whole(reducer, "moments_matched"), 1
        size = _sum(reducer, "reduced_dofs_per_body")
        cfg = _whole(reducer, "reduction_config")
        start = int(cfg) if scene.reduction["reduction_angle"] == "auto" and cfg is not None else -1
    variant = _whole(reducer, "chosen_variant")      # split or tied: under auto both passes try each (c, kept)
    if _whole(reducer, "chosen_search_dofs") is not None:   # the table's size: a tied model's body dofs less its ties
        size = int(_whole(reducer, "chosen_search_dofs"))
    matches = [x for x in cands if x["family"] == family and c is not None and x["c"] == int(c)
               and x["nexp"] == nexp and x["size"] == size and (start is None or x["start"] == start)
               and (variant is None or x["variant"] == int(variant))]
    # kept -1 and kept = every cluster are the same model: the first of the smallest error
    return min(matches, key=lambda x: x["error"]) if matches else None


class EstimatorCheck:
    """The two searches of a loaded Scene and their join."""

    def __init__(self, scene, progress=None):
        self.scene = scene
        self.accuracy = float(scene.accuracy)        # until the searches have run (run())
        self.progress = progress or (lambda msg: None)
        self.full = self.estimated = None
        self.rows = []
        self.notes = []

    def run(self, reuse=None):
        """Runs the full-order search and the estimator search (collective), then joins them. reuse: (reducer,
        seconds) of a search already made on this scene (the study's kryflex run): it stands for the run of its kind
        (error_estimated 0 or 1). Returns self."""
        if reuse is not None and reuse[0] is not None and "search_table" in reuse[0].result_names(-1):
            run = SearchRun(reuse[0], reuse[1], self.scene)
            if run.estimated:
                self.estimated = run
            else:
                self.full = run
        if self.full is None:
            self.progress("estimator check: the accuracy search measured against the full order")
            self.full = self._search(verify=True)
        if self.estimated is None:
            self.progress("estimator check: the accuracy search estimated against its richest candidate")
            self.estimated = self._search(verify=False)
        if self.full.estimated or not self.estimated.estimated:
            raise EstimatorCheckError("the full-order search reports error_estimated %s and the estimator search %s: "
                                      "expected 0 and 1" % (int(self.full.estimated), int(self.estimated.estimated)))
        self.accuracy = self.full.reducer.accuracy()     # the searches' target: -kf_accuracy over the scene's
        self.rows = self.join()
        return self

    def _search(self, verify):
        from ..reducer import Reducer
        reducer = Reducer(self.scene, quiet=True, search=True, verify=verify)
        t0 = time.perf_counter()
        reducer.reduce()
        return SearchRun(reducer, time.perf_counter() - t0, self.scene)

    # ------------------------------------------------------------------ the join

    def join(self):
        """One row (FIELDS) per candidate key present in both tables, in the full-order search's order."""
        est = {}
        for cand in self.estimated.candidates:
            est.setdefault(cand["key"], cand)
        chosen_full = self.full.chosen["key"] if self.full.chosen else None
        chosen_est = self.estimated.chosen["key"] if self.estimated.chosen else None
        rows, seen = [], set()
        for t in self.full.candidates:
            key = t["key"]
            if key in seen or key not in est:
                continue
            seen.add(key)
            e = est[key]
            if (e["size"], e["sysdofs"]) != (t["size"], t["sysdofs"]):
                self.notes.append("candidate %s: %d reduced / %d system dofs in the full-order search, %d / %d in the "
                                  "estimator search (the same candidate should be the same model)"
                                  % (describe_key(key, self.full.reducer, self.scene), t["size"], t["sysdofs"],
                                     e["size"], e["sysdofs"]))
            rows.append(dict(
                family=FAMILIES.get(t["family"], str(t["family"])), moments=t["c"], kept_clusters=t["kept"],
                expansion_angles=t["nexp"], start_deg=start_label(t, self.full.reducer, self.scene),
                variant=VARIANTS.get(t["variant"], str(t["variant"])),
                reduced_dofs=t["size"], system_dofs=t["sysdofs"], true_error=t["error"],
                true_lower_bound=int(t["lower_bound"]), estimated_error=e["error"],
                estimate_lower_bound=int(e["lower_bound"]), ratio=_ratio(e["error"], t["error"]),
                verdict=verdict(t["error"], e["error"], self.accuracy),
                chosen_full_order=int(key == chosen_full), chosen_estimator=int(key == chosen_est), key=key))
        return rows

    # ------------------------------------------------------------------ the figures

    def summary(self):
        """The figures of the check: counts, ratios estimate / true over the candidates where both are exact (all,
        and within DECISION_BAND of the accuracy), false passes and false fails, the chosen models."""
        full_keys = {c["key"] for c in self.full.candidates}
        est_keys = {c["key"] for c in self.estimated.candidates}
        out = figures(self.rows, self.accuracy)
        out.update(full_candidates=len(full_keys), estimator_candidates=len(est_keys),
                   only_full=len(full_keys - est_keys), only_estimator=len(est_keys - full_keys),
                   full_seconds=self.full.seconds, estimator_seconds=self.estimated.seconds)
        true_errors = [c["error"] for c in self.full.candidates if c["error"] > 0]
        out["lowest_true"] = min(true_errors) if true_errors else math.nan
        firsts = {name: sorted({start_label(c, run.reducer, self.scene) for c in run.candidates
                                if c["family"] == MULTI})
                  for name, run in (("full", self.full), ("estimator", self.estimated))}
        out["multi_starts"] = firsts if firsts["full"] != firsts["estimator"] else None
        for name, run in (("full", self.full), ("estimator", self.estimated)):
            row = None
            if run.chosen is not None:
                row = next((r for r in self.rows if r["key"] == run.chosen["key"]), None)
            out["chosen_" + name] = dict(error_max=run.error_max, target_met=run.target_met,
                                         candidate=describe_candidate(run.chosen, run.reducer, self.scene)
                                         if run.chosen else None, row=row,
                                         at_angles=self.truth_at_angles(run.reducer))
        return out

    def truth_at_angles(self, reducer):
        """The true error of a search's chosen model at the angles of interest (no midpoints): its response on the
        full-order search's grid against the full-order response there, by the C error measure (KFFRFElasticErrors,
        on the response the reducer's accuracy_measure names), worst
        over the angles. The truth of the estimator's choice even when the full-order search never tried it. None
        when the binding has no frf_errors."""
        if not hasattr(_core, "frf_errors"):
            return None
        ref = self.full.reducer
        model = reducer.reduce().model          # the Reduction of a solved reducer: made once, kept
        worst = 0.0
        for c, angles in enumerate(ref.configurations):
            grid = ref.result(c, "frf_frequencies_hz").ravel()
            Tr = model.at(angles).frf(grid)
            hinf, _ = _core.frf_errors(ref.frf(c, "full"), Tr, float(self.scene.verify["frf_floor_db"]),
                                       rigid=ref.full_rigid(c))
            worst = max(worst, float(hinf)) if not math.isnan(hinf) else math.inf
        return worst


# ---------------------------------------------------------------------------------------------- helpers

def figures(rows, accuracy):
    """The figures of joined rows (FIELDS; the check's or an estimator.csv's): counts, ratios estimate / true over
    the candidates whose two errors are exact (all, and those with a true error >= accuracy / DECISION_BAND),
    false passes and false fails (lists of rows)."""
    exact = [r for r in rows if not r["true_lower_bound"] and not r["estimate_lower_bound"]
             and np.isfinite(r["ratio"]) and r["ratio"] > 0]
    near = [r for r in exact if r["true_error"] >= accuracy / DECISION_BAND]
    out = dict(accuracy=accuracy, joined=len(rows), exact=len(exact), near=len(near),
               lower_bounds=sum(1 for r in rows if r["true_lower_bound"] or r["estimate_lower_bound"]),
               false_passes=[r for r in rows if r["verdict"] == "false pass"],
               false_fails=[r for r in rows if r["verdict"] == "false fail"])
    out.update(_ratio_figures(exact, ""))
    out.update(_ratio_figures(near, "near_"))
    return out


def verdict(true, estimate, accuracy):
    """What the estimator would decide about a candidate against the truth."""
    passes, truly = estimate <= accuracy, true <= accuracy
    if passes == truly:
        return "both pass" if truly else "both fail"
    return "false pass" if passes else "false fail"


def _ratio(estimate, true):
    if not true > 0 or not math.isfinite(true) or not math.isfinite(estimate):
        return math.nan
    return estimate / true


def _ratio_figures(rows, prefix):
    """median, min, max ratio and the worst (farthest from 1 by factor) row."""
    if not rows:
        return {prefix + "median_ratio": math.nan, prefix + "min_ratio": math.nan, prefix + "max_ratio": math.nan,
                prefix + "worst": None}
    ratios = np.array([r["ratio"] for r in rows])
    worst = rows[int(np.argmax(np.abs(np.log(ratios))))]
    return {prefix + "median_ratio": float(np.median(ratios)), prefix + "min_ratio": float(ratios.min()),
            prefix + "max_ratio": float(ratios.max()), prefix + "worst": worst}


def start_label(cand, reducer, scene):
    """The start of a candidate in degrees: its alpha_G (single-angle) or first expansion angle (multi-angle)."""
    if cand["start"] < 0:
        if cand["family"] == SINGLE:
            return " ".join("%g" % a for a in np.atleast_1d(scene.reduction["reduction_angle"]))
        return "named"
    return " ".join("%g" % a for a in reducer.configurations[cand["start"]])


def describe(family, c, kept, nexp, start_deg):
    """'single-angle c = 5, 3 clusters, alpha_G 30 deg' / 'multi-angle c = 2, every mode, 2 angles from 0 deg';
    'single-angle c = 5, 3 clusters, the structure' without revolute joints (start_deg empty)."""
    what = ("every mode" if kept == -1 else "each body its share" if kept == -2
            else "%d cluster%s" % (kept, "" if kept == 1 else "s"))
    if family in (SINGLE, FAMILIES[SINGLE]):
        where = "alpha_G %s deg" % start_deg if start_deg else "the structure"   # no revolute joint: no angle
    else:
        where = "%d angles %s" % (nexp, "named" if start_deg == "named" else "from %s deg" % start_deg)
    return "%s c = %d, %s, %s" % (FAMILIES.get(family, family), c, what, where)


def describe_key(key, reducer, scene):
    family, c, kept, nexp, start, variant = key
    text = describe(family, c, kept, nexp, start_label(dict(family=family, start=start), reducer, scene))
    return text if variant == SPLIT else "%s, %s" % (text, VARIANTS.get(variant, variant))


def describe_candidate(cand, reducer, scene):
    return "%s (%d reduced dofs, %d system dofs)" % (describe_key(cand["key"], reducer, scene), cand["size"],
                                                     cand["sysdofs"])


def _whole(reducer, name):
    """A whole-solve scalar result, None when not recorded."""
    if name not in reducer.result_names(-1):
        return None
    v = np.asarray(reducer.result(-1, name), float).ravel()
    return float(v[0]) if v.size and np.isfinite(v[0]) else None


def _sum(reducer, name):
    if name not in reducer.result_names(-1):
        return -1
    return int(np.nansum(np.asarray(reducer.result(-1, name), float)))


def run_check(scene, reuse=None, progress=None):
    """EstimatorCheck(scene).run(reuse), or (None, why) when it cannot be made: (check, None) otherwise. A failed
    reduction or a table that cannot be joined is a finding of the study, not a reason to lose the rest of it."""
    try:
        return EstimatorCheck(scene, progress).run(reuse), None
    except EstimatorCheckError as e:
        return None, str(e)
    except _core.Error as e:
        return None, "a reduction of the estimator check failed: %s" % " ".join(str(e).split())
