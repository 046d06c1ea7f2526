"""The peers bench at sizes where a reference of one LU per grid point is out of reach (57k dofs: --refine 1.55).

The same scene, damping, grid, error measure, kryflex runs and pyMOR reductors as bench.py (its functions are used),
with modal_reference.ModalReference as the full-order reference, checked by direct complex sparse solves at
--check-points grid points. Each step is its own process, so that every run stays within a few minutes and one
heavy process runs at a time; they share DIR (the scene, the reference's data, the rows measured so far):

    nice -n 10 .venv/bin/python benchmarks/peers/large.py reference DIR [--refine 1.55] [--cover 4]
    nice -n 10 .venv/bin/python benchmarks/peers/large.py kryflex DIR [--kryflex-options "default:" "bare:verify=false"]
    nice -n 10 .venv/bin/python benchmarks/peers/large.py pymor DIR [--methods "SO Galerkin" ...] [--orders ...]
    .venv/bin/python benchmarks/peers/large.py table DIR

kryflex's "default" row is its default run with its own verification against the full order; the "bare" row
(verify=false) is the reduction alone, comparable with pyMOR's times, which are its reductor's alone. Times are
wall times of separate processes on a shared machine: ratios are noisy.
"""
import argparse
import json
import os
import resource
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import bench  # noqa: E402
import modal_reference as mref  # noqa: E402


def rss_gb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6


def scene_in(folder, refine):
    path = os.path.join(folder, "scene", "spacecraft.yaml")
    if not os.path.exists(path):
        subprocess.run([sys.executable, os.path.join(bench.ROOT, "meshes", "solid", "generate.py"), "--refine",
                        str(refine), "-o", os.path.dirname(path)], check=True, capture_output=True)
    return path


def system(folder, refine, angle):
    """The scene, its full order and the elastic inputs and outputs."""
    scene = bench.ref.load_scene(scene_in(folder, refine))
    M, K, G, H, R = mref.full_order(scene, angle)
    Ge, He = G - M @ (R @ (R.T @ G)), H - (H @ R) @ (R.T @ M)
    return scene, M, K, G, H, R, Ge, He


def check_points(freqs, f_res):
    """Grid points for the direct check: the band's top (where the residual weighs most), the points nearest the
    highest and the lowest resonance in the band."""
    near = [freqs[np.argmin(abs(freqs - f))] for f in (f_res[-1], f_res[0])]
    return sorted({float(freqs[-1]), *map(float, near)}, reverse=True)


def reference(args):
    t0 = time.perf_counter()
    scene, M, K, G, H, R, Ge, He = system(args.dir, args.refine, args.angle)
    band, zeta = scene.raw["band"], float(scene.raw["damping"])
    t_full = time.perf_counter() - t0
    mr = mref.ModalReference(M, K, G, H, R, 0.0, args.cover * band[1], args.terms)
    mr.beta = beta = 2 * zeta / np.sqrt(mr.lam[0])     # bench.py's beta; the modal data do not depend on it
    f_res = mr.flexible_hz[mr.flexible_hz <= band[1]]
    freqs = bench.grid(band, f_res, beta * 2 * np.pi * f_res / 2)
    T_el, T_rigid = mr.elastic(freqs), mr.rigid_part(freqs)
    print("full order: %d dofs after the ties (%.1f s), %d rigid, %d flexible modes in the band (%.3g .. %.3g Hz), "
          "beta %.3g, %d grid points; modal reference: %d flexible modes up to %.1f Hz, %d residual terms, %.1f s, "
          "maxrss %.2f GB" % (M.shape[0], t_full, R.shape[1], len(f_res), f_res[0], f_res[-1], beta, len(freqs),
                              len(mr.lam), mr.flexible_hz[-1], args.terms, mr.seconds, rss_gb()), flush=True)
    peak = mref.pair_peak(T_el)
    t0 = time.perf_counter()
    check = mr.check(M, K, Ge, He, check_points(freqs, f_res), peak)
    print("direct complex SuperLU check: %s (of each pair's elastic peak), %.1f s, maxrss %.2f GB" %
          (", ".join("%.3g Hz %.2e" % c for c in check), time.perf_counter() - t0, rss_gb()), flush=True)
    np.savez(os.path.join(args.dir, "reference.npz"), freqs=freqs, T_el=T_el, T_rigid=T_rigid, beta=beta,
             f_res=f_res, check=np.array(check), dofs=M.shape[0], band=band)


def load(folder):
    with np.load(os.path.join(folder, "reference.npz")) as z:
        return {k: z[k] for k in z.files}


def add_rows(folder, rows):
    path = os.path.join(folder, "rows.json")
    old = json.load(open(path)) if os.path.exists(path) else []
    with open(path, "w") as f:
        json.dump(old + rows, f, indent=0)


def kryflex_rows(args):
    z = load(args.dir)
    path = scene_in(args.dir, args.refine)
    T_full = z["T_el"] + z["T_rigid"]
    for name, opts in bench.parse_options(args.kryflex_options).items():
        for target in args.targets:
            try:
                s, sec, reported, _, static, cpu = bench.kryflex_run(path, args.angle, float(z["beta"]), target, opts)
            except Exception as e:      # a failed run is a row of the table
                print("kryflex %s target %g failed: %s" % (name, target, e), flush=True)
                continue
            err = bench.elastic_error(T_full, s.frf(z["freqs"]), z["T_el"])
            states = 2 * (s.dofs - s.rigid_modes.shape[1])
            print("kryflex %-8s target %g: %d dofs (%d elastic states), elastic error %.3g (reported %.3g), %.1f s "
                  "(CPU %.1f s), maxrss %.2f GB, %s" % (name, target, s.dofs, states, err, reported, sec, cpu, rss_gb(),
                                                        static), flush=True)
            add_rows(args.dir, [["kryflex", name, target, states, err, sec]])


def pymor_rows(args):
    bench.ensure_pymor()
    z = load(args.dir)
    scene, M, K, G, H, R, Ge, He = system(args.dir, args.refine, args.angle)
    so = bench.pymor_model(M, K, float(z["beta"]), Ge, He)
    w = 2 * np.pi * z["freqs"]
    for mname, fn in bench.pymor_methods(so, list(z["band"]), False).items():
        if args.methods and not any(mname.startswith(m) for m in args.methods):
            continue
        for r in args.orders:
            t0 = time.perf_counter()
            try:
                rom, states = fn(r)
                sec = time.perf_counter() - t0
                err = bench.elastic_error(z["T_el"], rom.transfer_function.freq_resp(w), z["T_el"])
            except Exception as e:
                print("pyMOR %s r=%d failed: %s" % (mname, r, str(e).splitlines()[0][:120]), flush=True)
                break
            print("pyMOR %-32s %3d states: elastic error %.3g, %.1f s, maxrss %.2f GB"
                  % (mname, states, err, sec, rss_gb()), flush=True)
            add_rows(args.dir, [["pyMOR", mname, t, states, err, sec] for t in args.targets])
            if err <= min(args.targets):
                break
            if sec > args.budget:
                print("pyMOR %s: %.0f s at %d states, over the --budget: larger orders not tried"
                      % (mname, sec, states), flush=True)
                break


def table(args):
    rows = json.load(open(os.path.join(args.dir, "rows.json")))
    print("| target | method | states | elastic error | wall (s) | kryflex states / best pyMOR | time / best pyMOR |")
    print("|---|---|---|---|---|---|---|")
    for target in sorted({r[2] for r in rows}, reverse=True):
        best = {}
        for fam, m, t, st, err, sec in rows:
            if t == target and err <= target and (m not in best or st < best[m][0]):
                best[m] = (st, err, sec, fam)
        peers = [(v[0], v[2], m) for m, v in best.items() if v[3] == "pyMOR"]
        small = min(peers) if peers else None
        for m, (st, err, sec, fam) in sorted(best.items(), key=lambda kv: (kv[1][3] != "kryflex", kv[1][0])):
            ratio = ("%.2f | %.2f" % (st / small[0], sec / small[1])) if fam == "kryflex" and small else " | "
            print("| %g | %s %s | %d | %.2e | %.1f | %s |" % (target, fam, m, st, err, sec, ratio))
        for m in sorted({r[1] for r in rows if r[2] == target} - set(best)):
            low = min((r[4], r[3]) for r in rows if r[1] == m and r[2] == target)
            print("| %g | %s | not met (best %.2e at %d states) | | | | |" % (target, m, low[0], low[1]))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("step", choices=["reference", "kryflex", "pymor", "table"])
    ap.add_argument("dir", help="the folder the steps share")
    ap.add_argument("--refine", type=float, default=1.55)
    ap.add_argument("--angle", type=float, default=0.0)
    ap.add_argument("--targets", type=float, nargs="+", default=[1e-2, 1e-3, 1e-4])
    ap.add_argument("--cover", type=float, default=4.0, help="modes computed up to cover x the band's top")
    ap.add_argument("--terms", type=int, default=3, help="static residual terms (frequency corrections)")
    ap.add_argument("--kryflex-options", nargs="+", default=["default:", "bare:verify=false"])
    ap.add_argument("--methods", nargs="+", default=None, help="pyMOR methods by the start of their names")
    ap.add_argument("--orders", type=int, nargs="+", default=[8, 16, 24, 32])
    ap.add_argument("--budget", type=float, default=120.0)
    args = ap.parse_args()
    os.makedirs(args.dir, exist_ok=True)
    print("peers bench (large), %s UTC, %s, solid spacecraft --refine %g at %g deg, 1 rank" %
          (time.strftime("%Y-%m-%d %H:%M", time.gmtime()), args.step, args.refine, args.angle), flush=True)
    {"reference": reference, "kryflex": kryflex_rows, "pymor": pymor_rows, "table": table}[args.step](args)


if __name__ == "__main__":
    main()
