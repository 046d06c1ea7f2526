"""Moment-only models against models with expansion points inside the band, on the elastic error measured by an
independent dense reference (tests/python/support/elastic_measure.py), side by side in one run.

For each scene and family, kryflex reduces at a sweep of its own accuracy targets (-kf_accuracy: the search's measure
as built); every model is then measured on the elastic response. For each elastic target the table gives the
smallest model of each family that meets it: second-order dofs (rigid included), factorizations (at zero + at the
points), its elastic error and the reduction's wall time (kryflex's time_whole).

    .venv/bin/python benchmarks/expansion_points/bench.py [--scenes solid,galileo] [--max-factorizations 6]
"""
import argparse
import os
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tests", "python", "support"))
import accuracy_scenes as acc  # noqa: E402
import elastic_measure as em  # noqa: E402

SWEEP = [1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6, 1e-7, 1e-8]
TARGETS = [1e-2, 1e-3, 1e-4, 1.5e-5]


def scene_file(name, work):
    if name == "solid":
        base = acc.solid_base(os.path.join(work, "solid"))
        return acc.write_variant(base, os.path.join(work, "solid_one.yaml"), angles=[[90.0]], band=[0.01, 15.0],
                                 reduction=None), [[90.0]], [0.01, 15.0], 0.0025
    if name == "galileo":
        spec = acc.galileo_spec()
        return acc.write_variant(spec.base, os.path.join(work, "galileo.yaml"), reduction=None), \
            spec.configurations, [0.01, 10.0], 0.0025
    raise SystemExit("unknown scene %r (solid, galileo)" % name)


def run(kryflex, path, configs, band, zeta, dense, accuracy, maxf):
    scene = kryflex.load_scene(path)
    t0 = time.perf_counter()
    opts = dict(max_factorizations=maxf, shift_family_only=True) if maxf else {}
    red = kryflex.reduce(scene, quiet=True, accuracy=accuracy, **opts)
    wall = time.perf_counter() - t0
    s = red.summary
    el, tot = em.errors(red.model, dense, configs, band, zeta)
    nfz = len(configs) if s["chosen"]["method"] == "multi-angle" else 1
    return dict(accuracy=accuracy, dofs=em.system_dofs(red.model, configs), reduced=s["chosen"]["dofs"],
                points=s["chosen"].get("expansion_points_hz", []),
                fact=s["chosen"].get("expansion_point_factorizations", 0),
                spent=s.get("expansion_point_search", {}).get("factorizations_spent", 0),
                elastic=el, total=tot, wall=wall, whole=s.get("performance", {}).get("whole_s"),
                method=s["chosen"]["method"], moments=s["chosen"]["moments"])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenes", default="solid,galileo")
    ap.add_argument("--max-factorizations", type=int, default=6)
    ap.add_argument("--sweep", default=",".join("%g" % a for a in SWEEP))
    args = ap.parse_args()
    import kryflex
    work = tempfile.mkdtemp(prefix="kf_expansion_")
    for name in args.scenes.split(","):
        path, configs, band, zeta = scene_file(name, work)
        dense = acc.DenseReference(path, os.path.join(work, "dense"))
        rows = {}
        for fam, maxf in (("moments", 0), ("shifted", args.max_factorizations)):
            rows[fam] = []
            for a in [float(x) for x in args.sweep.split(",")]:
                r = run(kryflex, path, configs, band, zeta, dense, a, maxf)
                rows[fam].append(r)
                print("%-8s %-8s acc %-7g %3d dofs (%3d reduced) elastic %.2e total %.2e points %s (%d fact., %d spent)"
                      " %s c=%s wall %.2f s" % (name, fam, a, r["dofs"], r["reduced"], r["elastic"], r["total"],
                                               ["%.3g" % f for f in r["points"]], r["fact"], r["spent"],
                                               r["method"], r["moments"], r["wall"]), flush=True)
        print("\n%s: smallest model meeting each elastic target (dofs: second-order, rigid included)" % name)
        print("| target | moment-only dofs | elastic | wall s | shifted dofs | points (factorizations) | elastic | wall s |")
        print("|---:|---:|---:|---:|---:|---:|---:|---:|")
        for t in TARGETS:
            best = {}
            for fam in rows:
                ok = [r for r in rows[fam] if r["elastic"] <= t]
                best[fam] = min(ok, key=lambda r: (r["dofs"], r["elastic"])) if ok else None
            cells = []
            for fam in ("moments", "shifted"):
                b = best[fam]
                if b is None:
                    cells += ["none in the sweep", "", ""] if fam == "moments" else ["none in the sweep", "", "", ""]
                    continue
                if fam == "moments":
                    cells += ["%d" % b["dofs"], "%.2e" % b["elastic"], "%.2f" % b["wall"]]
                else:
                    cells += ["%d" % b["dofs"], "%d (%d)" % (len(b["points"]), b["fact"]), "%.2e" % b["elastic"],
                              "%.2f" % b["wall"]]
            print("| %g | %s |" % (t, " | ".join(cells)))
        print()


if __name__ == "__main__":
    main()
