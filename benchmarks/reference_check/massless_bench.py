#!/usr/bin/python3
"""The verification's eigensolve on a large model with massless dofs, two builds side by side in one run.

The model: meshes/frames.py's random articulated frame (3 bodies, 6-dof beam nodes) with its mass replaced the way
lumped-mass exports write it: every node's mass m (its translational diagonal) as a point mass, at the node on every
third node (its rotations massless: zero rows of M) and offset from it by r (|r_i| <= 0.3 m) on the others, a CONM2
with an offset: m T^T T on the node, T = [I, -[r]x], rank 3 with a full diagonal. M is singular beyond its zero
diagonal (half the dofs are in its null space).

    PYTHONPATH=python .venv/bin/python benchmarks/reference_check/massless_bench.py \\
        --dofs 24000 --before-python /tmp/refmain/python --rounds 2 --work /tmp/massless/bench \\
        --after-options "-kf_verify_eigen_max_blocks 60" [--band-top 5] [--massless-every 0]

Each round runs `kryflex reduce` (default settings: the block Krylov eigensolve from 20,000 system dofs on) with the
other build's python/ folder (--before-python) and then with this tree's, and prints per run the verification's
eigensolve seconds (summary.json performance.reference_eigensolve_s), the process's user CPU seconds, how many
configurations the block path took and how many fell back to Krylov-Schur (the progress lines), the chosen model's
error and the reference check's worst disagreement. --after-options adds a third run per round: this tree with
those options.
"""
import argparse
import json
import os
import resource
import subprocess
import sys
import time

import numpy as np
import scipy.io
import scipy.sparse as sp
import yaml

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "meshes"))


def lumped_offset_mass(M, rng, max_offset=0.3, every=3):
    """M replaced by point masses: node i's mass its translational diagonal M[6i, 6i]; at the node on every `every`-th
    node (rotations massless), offset by r on the others (m T^T T, T = [I, -[r]x]). every 0: every mass offset, so
    that no diagonal entry is zero, yet M is as singular (rank 3 per node)."""
    n = M.shape[0] // 6
    m = M.diagonal()[0::6].copy()
    rows, cols, vals = [], [], []
    for i in range(n):
        if every and i % every == 0:
            block = m[i] * np.diag([1.0, 1, 1, 0, 0, 0])
        else:
            r = rng.uniform(-max_offset, max_offset, 3)
            T = np.hstack([np.eye(3), -np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])])
            block = m[i] * T.T @ T
        ii, jj = np.nonzero(block)
        rows.append(6 * i + ii)
        cols.append(6 * i + jj)
        vals.append(block[ii, jj])
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=M.shape)


def write_model(work, dofs, seed, band=None, every=3):
    import frames
    folder = os.path.join(work, "model%d" % dofs + ("_band%g" % band if band else "") + ("" if every == 3 else "_every%d" % every))
    scene = os.path.join(folder, "scene.yaml")
    if os.path.exists(scene):
        return scene
    frames.write_random_scene(folder, dofs, nbodies=3, ninputs=3, noutputs=2, seed=seed, fmt="mtx", nangles=2)
    with open(scene) as f:
        spec = yaml.safe_load(f)
    rng = np.random.default_rng(seed)
    for name, body in spec["bodies"].items():
        path = os.path.join(folder, body["mass"])
        M = lumped_offset_mass(sp.csr_matrix(scipy.io.mmread(path)), rng, every=every)
        frames.write_mtx_symmetric(path, M, "lumped translational masses, %s offset from their nodes: %s" % (
            "every one" if not every else "%d of %d" % (every - 1, every), name))
    spec["name"] = "frames%d_lumped" % dofs
    if band:
        spec["band"] = [spec["band"][0], float(band)]
    with open(scene, "w") as f:
        f.write("# meshes/frames.py's scene, masses lumped and offset by benchmarks/reference_check/massless_bench.py\n")
        yaml.safe_dump(spec, f, sort_keys=False, default_flow_style=None, width=120)
    return scene


def run(scene, python_dir, out, options=(), lib=None):
    env = dict(os.environ, PYTHONPATH=python_dir, OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg")
    if lib:     # the binding's RUNPATH gives way to LD_LIBRARY_PATH: this libkryflex.so is loaded instead
        env["LD_LIBRARY_PATH"] = os.path.abspath(lib) + os.pathsep + env.get("LD_LIBRARY_PATH", "")
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.time()
    p = subprocess.run([sys.executable, "-m", "kryflex", "reduce", scene, "-o", out, *options], env=env, cwd=ROOT,
                       capture_output=True, text=True)
    wall = time.time() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    text = p.stdout + p.stderr
    row = dict(exit=p.returncode, wall=wall, cpu=after.ru_utime - before.ru_utime,
               block=text.count("block Krylov of K+ M"), fallback=text.count("Krylov-Schur (SLEPc) instead"),
               slepc=text.count("(Krylov-Schur, shift-and-invert"))
    if p.returncode == 0:
        s = json.load(open(os.path.join(out, "summary.json")))
        perf = s["performance"]
        row.update(eig=perf.get("reference_eigensolve_s"), error=s.get("error_max"),
                   check=(s.get("reference_check") or {}).get("error"),
                   modes=[len(f) for f in s["full"]["frequencies_hz"].values()])
    else:
        row["tail"] = text[-1500:]
    return row, text


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dofs", type=int, default=24000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--massless-every", type=int, default=3, help="a mass at its node (rotations massless: zero "
                    "rows of M) on every N-th node, offset on the others; 0: every mass offset, M singular with no "
                    "zero diagonal")
    ap.add_argument("--band-top", type=float, help="the band's top (Hz) instead of frames.py's 10 Hz: fewer modes "
                    "below the eigensolve's cut (3x the band's top)")
    ap.add_argument("--before-python", required=True, help="the other build's python/ folder (e.g. main's)")
    ap.add_argument("--before-lib", help="a folder with another build's libkryflex.so, loaded by --before-python's "
                    "binding (this tree's python/ with main's library: only the C library changed)")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--work", default="/tmp/massless_bench")
    ap.add_argument("--after-options", default="", help="a third run per round: this tree with these options "
                    "(e.g. '-kf_verify_eigen_max_blocks 60')")
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    scene = write_model(a.work, a.dofs, a.seed, a.band_top, a.massless_every)
    print("model: %s (uptime: %s)" % (scene, os.popen("uptime").read().strip()), flush=True)
    builds = [("before", os.path.abspath(a.before_python), [], a.before_lib), ("after", os.path.join(ROOT, "python"), [], None)]
    if a.after_options:
        builds.append(("after+", os.path.join(ROOT, "python"), a.after_options.split(), None))
    for r in range(a.rounds):
        for label, py, options, lib in builds:
            out = os.path.join(a.work, "%s_%d" % (label.replace("+", "_opts"), r))
            row, text = run(scene, py, out, options, lib)
            with open(out + ".log", "w") as f:
                f.write(text)
            print("round %d %-6s %s %s | load %.2f" % (r, label, " ".join(options), json.dumps(row), os.getloadavg()[0]),
                  flush=True)


if __name__ == "__main__":
    main()
