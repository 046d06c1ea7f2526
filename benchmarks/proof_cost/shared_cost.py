"""What -kf_shared_directions auto (the default) costs against false (split only): `kryflex reduce` of the solid
spacecraft (meshes/solid) run with each, alternately (false first), bare (-kf_verify false) and the default verdict,
and optionally another scene (the demo's Galileo) the same way.

    .venv/bin/python benchmarks/proof_cost/shared_cost.py [--refine 1.55] [--repeat 2] [--work DIR] [--bare-only]
        [--scene meshes/galileo/galileo.yaml]

Printed per run: the process's CPU seconds, the factorization + block solves and the search (summary.json's
performance: wall seconds, inflated by the load where the CPU seconds are not), the chosen model's system dofs and
bodies, whether it is tied (shared directions), and the ratio auto / false of CPU and search seconds of the runs
taken together, and the default's CPU over the bare run's of the same setting. The runs reuse bench.py's run() and scene_of().
"""
import argparse
import json
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import bench  # noqa: E402
from kryflex import ReducedModel  # noqa: E402

MODES = ("false", "auto")


def model_facts(out):
    """(system dofs: the most over the angles of interest, dofs per body, whether it has coordinate ties) of the chosen model."""
    with open(os.path.join(out, "summary.json")) as f:
        s = json.load(f)
    chosen = s.get("chosen") or {}
    tied = ReducedModel.load(os.path.join(out, "reduced.h5")).ties is not None
    return max((chosen.get("system_dofs") or {0: 0}).values()), chosen.get("dofs_per_body"), tied


def one(scene, out, extra, mode):
    r = bench.run(scene, out, extra + ["-kf_shared_directions", mode])
    r["sysdofs"], r["bodies"], r["tied"] = model_facts(out)
    return r


def show(label, mode, r):
    print("  %-9s %-5s cpu %7.2f s, factorization + solves %6.2f s, search %6.2f s, %s system dofs, bodies %s, "
          "tied %s" % (label, mode, r["cpu"], r["factorization"] + r["solves"],
                                            r["search"] or 0.0, r["sysdofs"], r["bodies"], r["tied"]))


def pair(scene, name, work, label, extra):
    got = {m: one(scene, os.path.join(work, "%s_%s_%s" % (label, name, m)), extra, m) for m in MODES}
    for m in MODES:
        show(label, m, got[m])
    a, b = got["auto"], got["false"]
    print("  %-9s auto / false: cpu %.3f, search %s" % (
        label, a["cpu"] / b["cpu"], "%.3f" % (a["search"] / b["search"]) if a["search"] and b["search"] else "-"))
    return got


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--refine", type=float, nargs="*", default=[1.55], help="meshes/solid refinements (1.55: 57k)")
    ap.add_argument("--scene", nargs="*", default=[], help="other scenes run the same way (the demo's Galileo)")
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--bare-only", action="store_true", help="the bare runs alone")
    ap.add_argument("--work", default="/tmp/kryflex-shared-cost")
    args = ap.parse_args()
    os.makedirs(args.work, exist_ok=True)
    print("shared directions cost, %s UTC, load average %s" % (time.strftime("%Y-%m-%d %H:%M", time.gmtime()),
                                                              bench.load()))
    scenes = [(bench.scene_of(r, args.work), "solid_%s" % r) for r in args.refine]
    scenes += [(os.path.abspath(s), os.path.splitext(os.path.basename(s))[0]) for s in args.scene]
    for scene, name in scenes:
        for rep in range(args.repeat):
            print("\n%s, run %d, load average %s" % (name, rep + 1, bench.load()))
            bare = pair(scene, name, args.work, "bare", ["-kf_verify", "false"])
            if not args.bare_only:
                full = pair(scene, name, args.work, "default", [])
                for m in MODES:     # CPU over CPU: the summary's stage seconds are wall, inflated by the load
                    print("  default %-5s cpu / bare cpu %.3f" % (m, full[m]["cpu"] / bare[m]["cpu"]))


if __name__ == "__main__":
    main()
