"""What the refinement of the block solves changes in the reduced model, side by side in one run: the same scene
reduced with the default -kf_refine_rtol (1e-6: refine a block solve while its relative residual is above it) and
with refinement off (-kf_refine_rtol 1e30), the fixed recipe of benchmarks/scaling (c moments, single angle, no
search, no verification).

    .venv/bin/python benchmarks/refinement/bench.py [--dofs 200000] [--moments 30] [--work DIR]

The scene is the modally dense panel spacecraft of meshes/panels.py (generated into --work once). Printed per run:
wall time of the reduction, the factorization and the block solves (PETSc events MatLUFactorNum / MatCholFctrNum
and MatMatSolve), the reduced dofs; then the difference of the two models: the frequencies
of their reassembled systems and their frequency responses on 400 points over the scene's band (max over the pairs
of max |T_a - T_b| / max |T_b|).
"""
import argparse
import os
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "python"))
import kryflex  # noqa: E402  (before petsc4py: PETSc then calls the SCOTCH build of MUMPS)
from petsc4py import PETSc  # noqa: E402

EVENTS = ("MatLUFactorNum", "MatCholFctrNum", "MatMatSolve")


def events():
    out = {}
    for name in EVENTS:
        try:
            info = PETSc.Log.Event(name).getPerfInfo()
            out[name] = info["time"]
        except Exception:
            out[name] = 0.0
    return out


def _has(reducer, key):
    try:
        reducer.result(-1, key)
        return True
    except Exception:
        return False


def reduce(scene_path, moments, rtol):
    opts = PETSc.Options()
    if rtol is None:
        opts.delValue("kf_refine_rtol")
    else:
        opts.setValue("kf_refine_rtol", rtol)
    scene = kryflex.load_scene(scene_path)
    nrev = len(scene.configurations[0]) if scene.configurations else 1
    scene.configurations = [[0.0] * nrev]
    scene.reduction.update(moments=moments, output_blocks=1, reduction_angle=[0.0] * nrev, method="single-angle",
                           reduction_angles=None, save_maps=False, search=False)
    scene.verify.update(full_order=False)
    e0 = events()
    t0 = time.perf_counter()
    reducer = kryflex.Reducer(scene, quiet=True)
    model = reducer.reduce().model
    wall = time.perf_counter() - t0
    keys = ("time_whole", "time_factor_total", "time_solves", "time_ratio", "solve_blocks", "refinement_solves",
            "solve_residual_first_max", "solve_residual_final_max")
    extra = {k: float(np.ravel(reducer.result(-1, k))[0]) for k in keys if _has(reducer, k)}
    e1 = events()
    fact = e1["MatLUFactorNum"] - e0["MatLUFactorNum"] + e1["MatCholFctrNum"] - e0["MatCholFctrNum"]
    solves = e1["MatMatSolve"] - e0["MatMatSolve"]
    return model, scene, wall, fact, solves, nrev, extra


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dofs", type=int, default=200000)
    ap.add_argument("--moments", type=int, default=30)
    ap.add_argument("--work", default=os.path.join(ROOT, "build", "bench-refinement"))
    args = ap.parse_args()
    PETSc.Log.begin()
    folder = os.path.join(args.work, "panels_%d" % args.dofs)
    scene_path = os.path.join(folder, "scene.yaml")
    if not os.path.exists(scene_path):
        subprocess.run([sys.executable, os.path.join(ROOT, "meshes", "panels.py"), "--dofs", str(args.dofs),
                        "--angles", "1", "--out", folder], check=True, capture_output=True)
    print("refinement bench, %s UTC, panels %d dofs, %d moments, 1 rank" %
          (time.strftime("%Y-%m-%d %H:%M", time.gmtime()), args.dofs, args.moments), flush=True)
    runs = {}
    for label, rtol in (("refine 1e-6 (default)", None), ("no refinement", "1e30")):
        model, scene, wall, fact, solves, nrev, extra = reduce(scene_path, args.moments, rtol)
        s = model.at([0.0] * nrev)
        band = scene.band
        freqs = np.geomspace(max(band[0], 1e-3), band[1], 400)
        runs[label] = (s, s.frf(freqs))
        print("%-22s reduction %.1f s, factorization %.1f s, block solves %.1f s, whole / (fact + solves) %.2f, "
              "%d reduced dofs, %s" % (label, wall, fact, solves, wall / max(fact + solves, 1e-9), s.dofs,
                                       ", ".join("%s %g" % kv for kv in extra.items())), flush=True)
    (a, Ta), (b, Tb) = runs.values()
    if a.dofs == b.dofs:
        fa, fb = a.frequencies_hz, b.frequencies_hz
        print("frequencies: max relative difference %.3g (%d flexible)" % (np.abs(fa / fb - 1).max(), len(fb)))
    else:
        print("the two models differ in size: %d and %d dofs" % (a.dofs, b.dofs))
    peak = np.abs(Tb).max(axis=0)
    diff = (np.abs(Ta - Tb).max(axis=0) / np.maximum(peak, 1e-300)).max()
    print("frequency response: max over pairs of max |T_refined - T_unrefined| / max |T_unrefined| = %.3g" % diff)


if __name__ == "__main__":
    main()
