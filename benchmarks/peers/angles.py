"""kryflex's model for every angle of interest against pyMOR's best at each angle alone, side by side in one run.

    .venv/bin/python benchmarks/peers/angles.py --scene meshes/galileo/galileo.yaml [--targets 1e-2 1e-3 1e-4]
        [--kryflex-options "compress:" "nostatic:static_exact=0"] [--methods SOR-IRKA] [--orders 4 8 12 16]

kryflex reduces the scene once per target with all its angles of interest (the multi-angle search, the bench's
Rayleigh damping). At every angle of interest and every midpoint between consecutive ones, the one model is
reassembled and measured on bench.py's independent elastic measure (its full order, rigid modes, grid and direct
reference at that angle), and its elastic first-order states there (2 x (system dofs - rigid modes)) are set beside
the smallest pyMOR model reduced at that angle alone that meets the target. pyMOR's models each serve one angle; the
kryflex model serves them all. The bench's damping (beta = 2 zeta / omega_1) is taken at the first angle.
"""
import argparse
import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import bench  # noqa: E402
from bench import ref  # noqa: E402


def kryflex_model(scene_path, angles, beta, target, options):
    import kryflex
    spec = bench.kryflex_spec(scene_path, angles[0], beta, target)
    spec["angles"] = list(angles)
    t0 = time.perf_counter()
    reducer = kryflex.Reducer(kryflex.scene_from_dict(spec), quiet=True, **options)
    out = reducer.reduce()
    return out.model, time.perf_counter() - t0, out.summary


def setup(path):
    """The scene, its angles of interest, the points (angles and midpoints), the full order at every point
    (M, K, G, H, R, lam), the bench's beta (taken at the first angle) and the reference at every point
    (freqs, T_el, T_full, Ge, He)."""
    scene = ref.load_scene(path)
    angles = [float(a) for a in scene.raw["angles"]]
    points = sorted(set(angles) | {0.5 * (a + b) for a, b in zip(angles, angles[1:])})
    band, zeta = scene.raw["band"], float(scene.raw["damping"])
    full = {}
    for a in points:     # the full order, its reference and its elastic split at every point
        M, K, G, H, R = bench.full_order(scene, a)
        lam, _ = bench.modes(M, K, band[1], R.shape[1])
        full[a] = (M, K, G, H, R, lam)
    M0, K0, _, _, R0, lam0 = full[angles[0]]
    beta = 2 * zeta / np.sqrt(lam0[R0.shape[1]])
    ref_at = {}
    for a in points:
        M, K, G, H, R, lam = full[a]
        f_res = np.sqrt(np.maximum(lam[R.shape[1]:], 0)) / (2 * np.pi)
        f_res = f_res[f_res <= band[1]]
        freqs = bench.grid(band, f_res, beta * 2 * np.pi * f_res / 2)
        Ge, He = G - M @ (R @ (R.T @ G)), H - (H @ R) @ (R.T @ M)
        T_el = bench.direct_response(M, K, beta, Ge, He, freqs)
        w = 2 * np.pi * freqs
        ref_at[a] = (freqs, T_el, T_el - (H @ R @ R.T @ G)[None] / (w ** 2)[:, None, None], Ge, He)
    return scene, angles, points, full, beta, ref_at


def kryflex_rows(path, angles, points, beta, ref_at, name, opts, target, rows):
    """kryflex's one model for all the angles at one target, measured at every point into rows[(target, name,
    point)] = (elastic states, error); prints its line and returns (wall, CPU) of the reduction."""
    c0 = time.process_time()
    model, sec, summ = kryflex_model(path, angles, beta, target, opts)
    cpu = time.process_time() - c0
    worst, states = 0.0, []
    for a in points:
        freqs, T_el, T_full, _, _ = ref_at[a]
        s = model.at([a])
        err = bench.elastic_error(T_full, s.frf(freqs), T_el)
        st = 2 * (s.dofs - s.rigid_modes.shape[1])
        rows[(target, name, a)] = (st, err)
        worst = max(worst, err)
        states.append(st)
    ch = summ.chosen
    print("kryflex %-9s target %g: %s model, bodies %s, elastic states %d..%d over the points, worst elastic "
          "error %.3g, static columns %s, L0 error at the angles of interest up to %.2g, %.2f s (CPU %.2f s)" %
          (name, target, summ.verdict.chosen_method, model.sizes, min(states), max(states), worst,
           "kept" if ch.static_exact else "truncated",
           max([e for e in (ch.static_moment_error or {}).values() if e is not None] or [float("nan")]), sec, cpu),
          flush=True)
    return sec, cpu


def pymor_orders(so, band, methods, orders, freqs, T_el, a, stop, bases=None):
    """pyMOR's methods (by the start of their names) on the elastic system at the point a, order after order until
    the elastic error is at most stop (a failed order ends its method): yields (method, r, states, error, wall, CPU)
    after printing its line. With a dict bases, the order's projection bases are in it when it is yielded."""
    for mname, fn in bench.pymor_methods(so, band, False, bases).items():
        if not any(mname.startswith(m) for m in methods):
            continue
        for r in orders:
            t0, c0 = time.perf_counter(), time.process_time()
            try:
                rom, st = fn(r)
                err = bench.elastic_error(T_el, rom.transfer_function.freq_resp(2 * np.pi * freqs), T_el)
            except Exception as e:
                print("pyMOR %s at %g deg r=%d failed: %s" % (mname, a, r, str(e).splitlines()[0][:100]))
                break
            sec, cpu = time.perf_counter() - t0, time.process_time() - c0
            print("pyMOR %-34s at %6.2f deg: %3d states, elastic error %.3g, %.2f s (CPU %.2f s)%s"
                  % (mname, a, st, err, sec, cpu, ", bases %s" % "+".join(str(bases[k].shape[1]) for k in ("V", "W")
                                                                          if k in bases) if bases is not None else ""),
                  flush=True)
            yield mname, r, st, err, sec, cpu
            if err <= stop:
                break


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", required=True)
    ap.add_argument("--targets", type=float, nargs="+", default=[1e-2, 1e-3, 1e-4])
    ap.add_argument("--kryflex-options", nargs="+", default=["compress:", "nostatic:static_exact=0"])
    ap.add_argument("--methods", nargs="+", default=["SOR-IRKA"])
    ap.add_argument("--orders", type=int, nargs="+", default=[4, 8, 12, 16])
    args = ap.parse_args()
    bench.ensure_pymor()
    path = os.path.abspath(args.scene)
    scene, angles, points, full, beta, ref_at = setup(path)
    band = scene.raw["band"]
    print("peers bench (angles), %s UTC, %s, angles %s and midpoints, 1 rank"
          % (time.strftime("%Y-%m-%d %H:%M", time.gmtime()), args.scene, angles), flush=True)
    rows = {}     # (target, name or pyMOR, point) -> states
    for name, opts in bench.parse_options(args.kryflex_options).items():
        for target in args.targets:
            kryflex_rows(path, angles, points, beta, ref_at, name, opts, target, rows)
    for a in points:
        M, K, G, H, R, lam = full[a]
        freqs, T_el, _, Ge, He = ref_at[a]
        so = bench.pymor_model(M, K, beta, Ge, He)
        for mname, r, st, err, sec, cpu in pymor_orders(so, band, args.methods, args.orders, freqs, T_el, a,
                                                        min(args.targets)):
            for target in args.targets:
                if err <= target:
                    key = (target, "pyMOR", a)
                    rows[key] = min(rows.get(key, (10 ** 9, 0)), (st, err))
    names = list(bench.parse_options(args.kryflex_options))
    print("\n| target | point (deg) | " + " | ".join("kryflex %s states (error)" % n for n in names)
          + " | best pyMOR at the point alone | " + " | ".join("%s / pyMOR" % n for n in names) + " |")
    print("|---|---|" + "---|" * (2 * len(names) + 1))
    for target in args.targets:
        for a in points:
            p = rows.get((target, "pyMOR", a))
            ks = [rows[(target, n, a)] for n in names]
            print("| %g | %g%s | %s | %s | %s |" % (
                target, a, "" if a in angles else " (mid)",
                " | ".join("%d (%.2g)%s" % (st, e, "" if e <= target else " MISSED") for st, e in ks),
                "%d (%.2g)" % p if p else "none of the orders met it",
                " | ".join("%.2f" % (st / p[0]) if p else "" for st, _ in ks)))


if __name__ == "__main__":
    main()
