"""Reassembly per call, side by side in one run: the C paths (bench_reassembly: KFReducedModelReassemble against
KFReassemblyApply on the SVD path and on the closed form, with and without the rank, rigid modes and
KFReassemblyEig) and the Python ones (the binding's CReassembly.apply on either path, ReducedModel.at() on the closed
form with and without its lazy modes, against the previous at(): CReducedModel.reassemble plus a copy of every array
and the settings parsed at each call).

    .venv/bin/python benchmarks/reassembly/bench.py [--calls 2000] [--reps 5]

Models: Galileo (meshes/galileo, default reduction) and a random 3-body frame scene with two revolute joints
(meshes/frames.py, 600 dofs, seed 1) reduced at accuracy 1e-3 and 1e-4 (about 30 system dofs). Times are the best
of --reps repetitions of --calls calls each, the paths interleaved, so a busy machine slows them alike; the ratios
are what to read.
"""
import argparse
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "python"))
sys.path.insert(0, os.path.join(ROOT, "meshes"))
import frames  # noqa: E402
import kryflex  # noqa: E402
from kryflex import _core  # noqa: E402
from kryflex.api import ReducedSystem  # noqa: E402

BENCH = os.path.join(ROOT, "build", "benchmarks", "bench_reassembly")


def previous_at(model, angles_deg):
    """ReducedModel.at() as it was before the fast path: the C system (with its eigen-decomposition), every array
    copied out of it, the settings and output quantities read at each call."""
    angles = np.atleast_1d(np.asarray(angles_deg, dtype=float))
    if angles.ndim != 1 or angles.size != len(model.revolute):
        raise ValueError("wrong number of angles")
    return ReducedSystem.from_handle(model.reassemble(np.radians(angles)), [float(a) for a in angles],
                                     float(model.settings.get("damping", 0.0)), model.output_quantities())


def python_times(model, nrev, calls, reps, clock=time.perf_counter):
    angles = [np.degrees(2 * np.pi * (i / calls + 0.37 * np.arange(nrev))) for i in range(calls)]
    svd, closed = _core.CReassembly(model, svd=True), _core.CReassembly(model)
    paths = {"previous at() (C system, copies)": lambda a: previous_at(model, a),
             "CReassembly.apply, SVD (matrices)": lambda a: svd.apply(np.radians(a), False, False),
             "CReassembly.apply, closed form (matrices)": lambda a: closed.apply(np.radians(a), False, False),
             "at() (closed form, matrices)": lambda a: model.at(a),
             "at() + frequencies_hz (lazy eig)": lambda a: model.at(a).frequencies_hz}
    best = {k: np.inf for k in paths}
    for _ in range(reps):
        for name, fn in paths.items():
            t0 = clock()
            for a in angles:
                fn(a)
            best[name] = min(best[name], (clock() - t0) / calls)
    return best


def models(folder):
    scene = kryflex.load_scene(os.path.join(ROOT, "meshes", "galileo", "galileo.yaml"))
    yield "galileo", kryflex.reduce(scene, quiet=True).model
    path = frames.write_random_scene(os.path.join(folder, "frames"), 600, nbodies=3, ninputs=3, noutputs=3, seed=1)
    scene = kryflex.load_scene(path)
    for acc in (1e-3, 1e-4):
        yield "frames600 acc %g" % acc, kryflex.reduce(scene, quiet=True, accuracy=acc).model


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--calls", type=int, default=2000)
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--cpu", action="store_true",
                    help="the process's CPU time instead of the wall (a busy machine's waits for a core left out)")
    args = ap.parse_args()
    if not os.path.exists(BENCH):
        sys.exit("%s not built: run scripts/setup (or cmake --build build)" % BENCH)
    print("reassembly bench, %s UTC, %d calls x %d repetitions (best, %s time), 1 rank" %
          (time.strftime("%Y-%m-%d %H:%M", time.gmtime()), args.calls, args.reps, "CPU" if args.cpu else "wall"))
    with tempfile.TemporaryDirectory() as folder:
        for name, model in models(folder):
            path = model.save(os.path.join(folder, "model.h5"))
            nrev = len(model.revolute)
            h = model.at([0.0] * nrev).dofs
            print("\n== %s: %d system dofs, %d revolute joint(s)" % (name, h, nrev))
            out = subprocess.run([BENCH, path, "-calls", str(args.calls), "-reps", str(args.reps)]
                                 + (["-cpu"] if args.cpu else []),
                                 capture_output=True, text=True, check=True).stdout
            print("\n".join(line for line in out.splitlines() if line.startswith("C ")))
            best = python_times(model, nrev, args.calls, args.reps,
                                time.process_time if args.cpu else time.perf_counter)
            ref = best["previous at() (C system, copies)"]
            for k, v in best.items():
                print("Py %-44s %9.2f us   ratio to the previous at() %.3f" % (k, v * 1e6, v / ref))


if __name__ == "__main__":
    main()
