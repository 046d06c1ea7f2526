"""The model sizes and errors the elastic and the total accuracy measures lead to, side by side in one run.

For each scene (the 2,760-dof solid spacecraft of meshes/solid at refine 0.5, Galileo) and each target, the scene is
reduced twice in this process (accuracy search on, moments auto, the scene's other settings), once per measure;
each run prints the reduced dofs per body, the largest reassembled system, the reported elastic or total error
(error_max) and the reduction's wall time (time_whole). Timings are noisy on a shared machine: compare the two
measures' times as a ratio within one row.

    PYTHONPATH=python .venv/bin/python benchmarks/elastic/sizes.py [--out DIR]
"""
import argparse
import os
import sys

import numpy as np
import yaml

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tests", "python", "support"))
import accuracy_scenes as acs  # noqa: E402

TARGETS = (0.05, 1e-2, 1e-3)


def variant(base, path, target, measure):
    with open(base) as f:
        reduction = dict(yaml.safe_load(f).get("reduction") or {}, moments="auto", search=True)
    reduction.pop("keep_threshold", None)
    acs.write_variant(base, path, accuracy=target, reduction=reduction)
    with open(path) as f:
        spec = yaml.safe_load(f)
    spec["accuracy_measure"] = measure
    with open(path, "w") as f:
        yaml.safe_dump(spec, f, sort_keys=False, default_flow_style=None, width=120)
    return path


def scalar(reducer, name):
    v = np.asarray(reducer.result(-1, name), float).ravel()
    return float(v[0]) if v.size else float("nan")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "bench-elastic"))
    args = ap.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    import kryflex
    scenes = [("solid 2,760", acs.solid_base(os.path.join(args.out, "solid"))), ("galileo", acs.GALILEO)]
    print("%-12s %-7s | %-8s %-12s %-6s %-10s %-8s | %-8s %-12s %-6s %-10s %-8s | %s"
          % ("scene", "target", "measure", "dofs/body", "system", "error", "whole s", "measure", "dofs/body",
             "system", "error", "whole s", "time ratio"))
    for name, base in scenes:
        for target in TARGETS:
            cells = []
            for measure in ("elastic", "total"):
                path = variant(base, os.path.join(args.out, "%s_%g_%s.yaml" % (name.split()[0], target, measure)),
                               target, measure)
                reducer = kryflex.Reducer(kryflex.load_scene(path), quiet=True)
                model = reducer.reduce().model
                dofs = max(int(np.asarray(reducer.result(c, "reduced_dofs" if scalar(reducer, "chosen_method") == 0
                                                         else "multi_reduced_dofs")).ravel()[0])
                           for c in range(reducer.nconfig))
                cells.append((measure, "+".join(str(int(v)) for v in model.sizes), dofs, scalar(reducer, "error_max"),
                              scalar(reducer, "time_whole")))
            print("%-12s %-7g | %-8s %-12s %-6d %-10.3g %-8.2f | %-8s %-12s %-6d %-10.3g %-8.2f | %.2f"
                  % ((name, target) + cells[0] + cells[1] + (cells[0][4] / cells[1][4],)), flush=True)


if __name__ == "__main__":
    main()
