#!/usr/bin/python3
"""Brute-force sweep: the smallest reduced model that meets a target, found by trying every candidate, beside the
model the reducer's accuracy search chose (the requirement: "each size is within 1.5x of the smallest found by a
brute-force sweep").

    benchmarks/sweep/bench-sweep [--scene galileo|frame|solid] [--target 1e-3] [--moments 1-20] [--methods single,multi]
                        [--workdir DIR] [--cache DIR] [--csv out.csv]

Candidates: method single-angle and multi-angle (with --full also every alpha_G of interest, and evenly spread
expansion-angle subsets), moments c = 1..20, and for each (method, basis, importance ranking, c) every kept set
the ranking allows: with the search off (the paper's fixed recipe) a first run keeps every mode (keep_threshold =
KEEP_ALL), and its normalized importances at every configuration of interest give the thresholds of all
importance-ranked prefixes (the reducer exposes no kept count). Rankings: band (the search's), h2, hinf. Each candidate is reduced by kryflex (search off, its own
verification off) and checked here, independently, against the dense reference (accuracy_scenes.py: relative
H-infinity error per input/output pair, angles of interest and midpoints, grid 4x finer than the reducer's).
Size = the sum of the reduced bodies' dofs. The smallest candidate meeting the target is compared with the
reducer's choice (its defaults: moments auto, method auto, search on, the target as accuracy).
"""
import argparse
import csv
import os
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import accuracy_scenes as acs  # noqa: E402

METHODS = {"single": "single-angle", "multi": "multi-angle"}
KEEP_ALL = 1e-12          # keep_threshold that keeps every Krylov mode of a nonzero importance
SIZE_FACTOR = 1.5         # the required bound: chosen size <= SIZE_FACTOR x the sweep's smallest


def _whole(reducer, name):
    """A whole-solve scalar result, or None when the reducer does not record it."""
    try:
        v = np.asarray(reducer.result(-1, name), float).ravel()
    except Exception:
        return None
    return float(v[0]) if v.size and np.isfinite(v[0]) else None


def reducer_grid_points(reducer, scene):
    """The point count of the reducer's verification grid (the most over the angles of interest: result
    frf_frequencies_hz), or the scene's verify.frequency_points when the reducer recorded none. The check grid takes
    GRID_FACTOR x this many log-spaced points, so it is at least GRID_FACTOR x finer than the reducer's."""
    n = 0
    for c in range(reducer.nconfig):
        try:
            f = np.asarray(reducer.result(c, "frf_frequencies_hz"), float).ravel()
            n = max(n, int(np.isfinite(f).sum()))
        except Exception:
            pass
    return n or int(scene.verify["frequency_points"])


class Evaluator:
    """Reduces variants of one scene with kryflex (in this process) and checks them against the dense reference."""

    def __init__(self, spec, workdir, cache_dir):
        import kryflex
        self.kryflex = kryflex
        self.spec = spec
        self.workdir = workdir
        self.dense = acs.DenseReference(spec.variant(os.path.join(workdir, "%s_dense.yaml" % spec.name), 0.05),
                                        cache_dir)
        self._scenes = {}

    def scene(self, target, reduction=None):
        """(path, loaded scene) of the variant with accuracy target and the contract's reduction settings, updated
        by the reduction keys given."""
        reduction = dict(acs.CONTRACT_REDUCTION, **(reduction or {}))
        key = (float(target), repr(sorted(reduction.items())))
        if key not in self._scenes:
            path = os.path.join(self.workdir, "%s_%d.yaml" % (self.spec.name, len(self._scenes)))
            self.spec.variant(path, float(target), reduction=reduction)
            self._scenes[key] = (path, self.kryflex.load_scene(path))
        return self._scenes[key]

    def reduce(self, target, reduction=None, **options):
        """(reducer, reduction, seconds) for the scene variant with accuracy target and the given -kf_ options."""
        _, scene = self.scene(target, reduction)
        t0 = time.perf_counter()
        reducer = self.kryflex.Reducer(scene, quiet=True, **options)
        result = reducer.reduce()
        return reducer, result, time.perf_counter() - t0

    def check(self, model, scene, n_log):
        return acs.evaluate_model(model, self.dense, self.spec.configurations, scene.band, scene.damping, n_log)


def importance_thresholds(reducer):
    """Every distinct normalized importance of a keep-all run over the configurations of interest, descending: as
    keep_threshold each keeps one importance-ranked prefix (keep the modes whose importance reaches it)."""
    values = set()
    for c in range(reducer.nconfig):
        imp = np.asarray(reducer.result(c, "krylov_importance"), float).ravel()
        values.update(float(v) for v in imp[np.isfinite(imp) & (imp > KEEP_ALL) & (imp <= 1.0)])
    return sorted(values, reverse=True)


def spread_subsets(configurations):
    """Expansion-angle sets of 2 .. n-1 configurations, each spread evenly over the angles of interest (first and
    last included); the full set is the multi-angle default."""
    n = len(configurations)
    out = []
    for k in range(2, n):
        idx = sorted(set(int(round(i)) for i in np.linspace(0, n - 1, k)))
        out.append([configurations[i] for i in idx])
    return out


def variants(method, configurations, full):
    """(label, -kf_ options) of the basis variants a method is swept over: the single-angle basis at the paper's
    alpha_G (and, with full, at every angle of interest); the multi-angle basis at all angles of interest (and, with
    full, at evenly spread subsets)."""
    if method == "single":
        out = [("alpha_G auto", {})]
        if full:
            out += [("alpha_G %s" % c, {"reduction_angle": c}) for c in configurations]
    else:
        out = [("all %d angles" % len(configurations), {})]
        if full:
            out += [("angles %s" % [c[0] if len(c) == 1 else c for c in sub],
                     {"multi_angles": [a for c in sub for a in c]}) for sub in spread_subsets(configurations)]
    return out


def _first_line(e):
    return (str(e).splitlines() or [""])[0][:120]


def sweep(ev, target, n_log, methods=("single", "multi"), moments=range(1, 21), importances=("band", "h2"),
          full=False, log=print):
    """Every candidate: [row dict(method, variant, importance, moments, keep_threshold, kept, size, sizes, error,
    meets, seconds)]; refused candidates are logged and skipped (refusals: a list of (candidate, reason))."""
    _, scene = ev.scene(target)
    rows, refusals = [], []
    for method in methods:
        for label, extra in variants(method, ev.spec.configurations, full):
            for imp in importances:
                for c in moments:
                    base = dict(extra, method=METHODS[method], moments=int(c), search=False, verify=False,
                                importance=imp, output_blocks=min(int(scene.reduction["output_blocks"]), int(c) - 1))
                    what = "%s %s, importance %s, c=%d" % (method, label, imp, c)
                    try:
                        reducer, _, _ = ev.reduce(target, **base, keep_threshold=KEEP_ALL)
                    except Exception as e:   # a candidate the reducer refuses
                        refusals.append((what, _first_line(e)))
                        continue
                    seen = set()
                    for thr in importance_thresholds(reducer) + [KEEP_ALL]:
                        try:
                            red_c, result, secs = ev.reduce(target, **base, keep_threshold=thr)
                        except Exception as e:
                            refusals.append(("%s keep %.3g" % (what, thr), _first_line(e)))
                            continue
                        model = result.model
                        sizes = tuple(int(s) for s in model.sizes)
                        kept = tuple(int(k) for k in np.asarray(red_c.result(-1, "kept_modes"), float).ravel()
                                     if np.isfinite(k))
                        if (sizes, kept) in seen:    # the kept set of a larger threshold again: nothing new
                            continue
                        seen.add((sizes, kept))
                        err = acs.worst(ev.check(model, scene, n_log))
                        rows.append(dict(method=method, variant=label, importance=imp, moments=int(c),
                                         keep_threshold=thr, kept=len(kept), size=int(sum(sizes)), sizes=sizes,
                                         error=err, meets=bool(err <= target), seconds=secs))
    reasons = {}
    for what, why in refusals:
        reasons.setdefault(why, []).append(what)
    for why, whats in reasons.items():
        log("  refused %d candidate(s), e.g. %s: %s" % (len(whats), whats[0], why))
    return rows


def smallest(rows):
    meeting = [r for r in rows if r["meets"]]
    return min(meeting, key=lambda r: (r["size"], r["error"])) if meeting else None


def chosen(ev, target):
    """The reducer's own choice with the contract's defaults: row dict plus the reducer's figures."""
    path, scene = ev.scene(target)
    reducer, result, secs = ev.reduce(target)
    n_log = reducer_grid_points(reducer, scene)
    checks = ev.check(result.model, scene, n_log)
    err = acs.worst(checks)
    method = {0: "single", 1: "multi"}.get(_whole(reducer, "chosen_method"), str(result.model.settings.get("method")))
    row = dict(method=method, moments=_whole(reducer, "moments_matched"), keep_threshold=None,
               kept=None, size=int(sum(result.model.sizes)), sizes=tuple(int(s) for s in result.model.sizes),
               error=err, meets=bool(err <= target), seconds=secs, target_met=_whole(reducer, "target_met"),
               error_max=_whole(reducer, "error_max"))
    return row, checks, n_log


def side_by_side(target, mine, best, nrows):
    lines = ["target %.0e: %d candidates evaluated" % (target, nrows),
             "  %-18s %-7s %-16s %-6s %-4s %-9s %-5s %-12s %-10s" % ("", "method", "basis", "imp.", "c",
                                                                   "keep_thr", "size", "sizes", "error")]
    for label, r in (("reducer's choice", mine), ("sweep's smallest", best)):
        if r is None:
            lines.append("  %-18s (no candidate meets the target)" % label)
            continue
        thr = "-" if r["keep_threshold"] is None else "%.3g" % r["keep_threshold"]
        c = "-" if r["moments"] is None else "%d" % r["moments"]
        lines.append("  %-18s %-7s %-16s %-6s %-4s %-9s %-5d %-12s %.3e"
                     % (label, r["method"], r.get("variant") or "-", r.get("importance") or "-", c, thr, r["size"],
                        "+".join(map(str, r["sizes"])), r["error"]))
    if mine is not None and best is not None:
        lines.append("  ratio size chosen / smallest = %.2f (bound %.1f); reducer target_met %s, its error_max %s"
                     % (mine["size"] / best["size"], SIZE_FACTOR, mine.get("target_met"), mine.get("error_max")))
    return "\n".join(lines)


def parse_range(text):
    if "-" in text:
        a, b = text.split("-")
        return list(range(int(a), int(b) + 1))
    return [int(x) for x in text.split(",")]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default="galileo", choices=["galileo", "frame", "solid"])
    ap.add_argument("--target", type=float, action="append", help="accuracy target (repeat for several; default "
                    "1e-2, 1e-3, 1e-4)")
    ap.add_argument("--moments", default="1-20", help="c values: 1-20 or 2,4,8")
    ap.add_argument("--methods", default="single,multi")
    ap.add_argument("--importances", default="band,h2,hinf", help="importance rankings whose prefixes are swept")
    ap.add_argument("--full", action="store_true", help="also every alpha_G of interest (single-angle) and evenly "
                    "spread expansion-angle subsets (multi-angle)")
    ap.add_argument("--workdir", help="scene files and generated bodies (default: a temporary folder)")
    ap.add_argument("--cache", help="dense modal data cache (default: WORKDIR/dense-cache)")
    ap.add_argument("--csv", help="write every candidate to this CSV file")
    args = ap.parse_args(argv)

    import kryflex
    kryflex.init(sys.argv[:1])
    workdir = args.workdir or tempfile.mkdtemp(prefix="kryflex-sweep-")
    os.makedirs(workdir, exist_ok=True)
    spec = {"galileo": lambda: acs.galileo_spec(),
            "frame": lambda: acs.frame_spec(os.path.join(workdir, "frame")),
            "solid": lambda: acs.solid_spec(os.path.join(workdir, "solid"))}[args.scene]()
    ev = Evaluator(spec, workdir, args.cache or os.path.join(workdir, "dense-cache"))
    status = 0
    all_rows = []
    for target in args.target or [1e-2, 1e-3, 1e-4]:
        mine, checks, n_log = chosen(ev, target)
        t0 = time.perf_counter()
        rows = sweep(ev, target, n_log, methods=args.methods.split(","), moments=parse_range(args.moments),
                     importances=args.importances.split(","), full=args.full)
        best = smallest(rows)
        print(side_by_side(target, mine, best, len(rows)))
        print("  sweep: %.0f s; the chosen model's checks:\n%s" % (time.perf_counter() - t0, acs.describe(checks)))
        if best is None or not mine["meets"] or mine["size"] > SIZE_FACTOR * best["size"]:
            status = 1
        all_rows += [dict(r, target=target, sizes="+".join(map(str, r["sizes"]))) for r in rows]
        all_rows.append(dict(mine, target=target, method="chosen:" + str(mine["method"]),
                             sizes="+".join(map(str, mine["sizes"]))))
        sys.stdout.flush()
    if args.csv:
        keys = ["target", "method", "variant", "importance", "moments", "keep_threshold", "kept", "size", "sizes",
                "error", "meets", "seconds"]
        with open(args.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=keys, extrasaction="ignore")
            w.writeheader()
            w.writerows(all_rows)
    return status


if __name__ == "__main__":
    sys.exit(main())
