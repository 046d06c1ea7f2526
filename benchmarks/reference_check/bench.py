#!/usr/bin/python3
"""The full-order reference on models exported the way commercial codes write them (lumped translational masses, some
offset from their nodes: M singular beyond its zero diagonal), read back from a long-field DMIG punch: the
reference's distance to an independent dense SciPy response, the direct-solve check's worst disagreement, and the
check's time against the whole verification's, side by side in one run.

    PYTHONPATH=python .venv/bin/python benchmarks/reference_check/bench.py [--build-python DIR]

--build-python: run the same cases with another kryflex's python/ folder (for example a build of main) in a child
process, to print before and after side by side. Each case runs in its own process (kryflex.init takes the options).
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
TESTS = os.path.join(ROOT, "tests", "python")

CASES = [("plate 45 dofs, dense path", "plate_small", []),
         ("plate 45 dofs, sparse path", "plate_small", ["-kf_verify_dense_max_dofs", "0"]),
         ("plate 630 dofs, sparse path", "plate_large", []),
         ("plate 630 dofs, dense path", "plate_large", ["-kf_verify_dense_max_dofs", "1000"]),
         ("aircraft-like 192 dofs, dense path", "aircraft", []),
         ("aircraft-like 192 dofs, sparse path", "aircraft", ["-kf_verify_dense_max_dofs", "0"])]


def spec_of(model, folder):
    sys.path.insert(0, TESTS)
    import bc_models
    import nastran_model as nm
    from kryflex.io import dmig
    import warnings
    spec = {"plate_small": lambda: bc_models.lumped_plate(5, 3, band=(0.5, 200.0)),
            "plate_large": lambda: bc_models.lumped_plate(15, 14, band=(0.5, 20.0)),
            "aircraft": lambda: bc_models.lumped_aircraft(band=(0.5, 20.0))}[model]()
    body = next(iter(spec["bodies"].values()))
    pch, bdf = nm.write_punch(folder, body["stiffness"], body["mass"], body["nodes"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        M, K, nodes, _ = dmig.nastran_body(pch, [bdf])
    body.update(mass=M.toarray(), stiffness=K.toarray(), nodes=[list(n) for n in nodes])
    return spec


def child(model, options):
    """One case in this process: prints one JSON line."""
    import kryflex
    kryflex.init(["bench"] + options)
    sys.path.insert(0, TESTS)
    import bc_models
    import test_reference_truth as T
    spec = spec_of(model, tempfile.mkdtemp())
    M, K, G, H = bc_models.layout_reference(spec)
    out = {"model": model, "options": options}
    t0 = time.perf_counter()
    try:
        r = kryflex.Reducer(kryflex.scene_from_dict(spec), quiet=True)
        r.reduce()
    except kryflex.Error as e:
        out.update(error=str(e).splitlines()[0][:160], seconds=time.perf_counter() - t0)
        print(json.dumps(out))
        return
    out["seconds"] = time.perf_counter() - t0
    f = np.ravel(r.result(0, "frf_frequencies_hz"))
    exact, _ = T.scipy_frf(M, K, G, H, f, spec["damping"], nrigid=6 if model == "aircraft" else 3)
    out["reference_vs_scipy"] = T.pair_distance(r.frf(0, "full"), exact)
    names = r.result_names(-1)
    for key in ("reference_check_error", "time_reference_check", "time_verification", "error_max", "target_met"):
        out[key] = float(np.ravel(r.result(-1, key))[0]) if key in names else None
    print(json.dumps(out))


def run_all(python_dir):
    env = dict(os.environ, PYTHONPATH=python_dir, OPENBLAS_NUM_THREADS="1")
    rows = []
    for label, model, options in CASES:
        p = subprocess.run([sys.executable, os.path.abspath(__file__), "--child", model, *options], env=env,
                           capture_output=True, text=True, timeout=600)
        line = [x for x in p.stdout.splitlines() if x.startswith("{")]
        rows.append((label, json.loads(line[-1]) if line else {"error": (p.stderr.strip().splitlines() or ["?"])[-1]}))
    return rows


def fmt(x, spec="%.2e"):
    return "-" if x is None else spec % x


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        return child(sys.argv[2], sys.argv[3:])
    ap = argparse.ArgumentParser()
    ap.add_argument("--build-python", help="another kryflex's python/ folder, run beside this one (before)")
    args = ap.parse_args()
    builds = [("this tree", os.path.join(ROOT, "python"))]
    if args.build_python:
        builds.insert(0, ("before", os.path.abspath(args.build_python)))
    for name, folder in builds:
        print("## %s (%s)" % (name, folder))
        print("| case | reference vs dense SciPy | direct-solve check | check s | verification s | check / verification | error_max | exit/error |")
        print("|---|---|---|---|---|---|---|---|")
        for label, o in run_all(folder):
            ratio = (o["time_reference_check"] / o["time_verification"]
                     if o.get("time_reference_check") is not None and o.get("time_verification") else None)
            print("| %s | %s | %s | %s | %s | %s | %s | %s |" % (
                label, fmt(o.get("reference_vs_scipy")), fmt(o.get("reference_check_error")),
                fmt(o.get("time_reference_check"), "%.3f"), fmt(o.get("time_verification"), "%.3f"),
                fmt(ratio, "%.2f"), fmt(o.get("error_max"), "%.4f"), o.get("error", "ok")))
        print()


if __name__ == "__main__":
    main()
