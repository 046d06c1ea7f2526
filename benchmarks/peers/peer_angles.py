"""A peer model serving every angle of interest at once, made from pyMOR's one-angle bases, beside kryflex's one model
and pyMOR's one-angle models, in one run.

    PYTHONPATH=$PWD/python VENV/bin/python benchmarks/peers/peer_angles.py --scene SCENE.yaml
        [--targets 1e-2 1e-3 1e-4] [--methods "SO Galerkin"] [--orders 2 4 6 8] [--kryflex-options "default:"]
        [--no-greedy] [--no-body-wise]    (--no-greedy: the two POD variants only)

The set-up, the measure and kryflex's rows are angles.py's (the bench's Rayleigh damping beta K taken at the first
angle, its grid, full order, geometric rigid modes and direct reference at every angle of interest and midpoint).

The common dof space. bench.full_order eliminates the same 5 dofs at every angle (the revolute joint's child
interface translations and two rotations, expressed by the parent's and the spin angle's ties), so a vector of the
assembled system is, at every angle, a vector of the bodies' own dofs less those 5, the tied ones recomputed from
the ties at that angle: what kryflex's reassembly does with its body bases. A basis in that space is one stored
model; at each angle its Galerkin projection needs no other data than that angle's M, K, G, H, and it loses no
dimension to the ties. (The bodies' dofs with the ties imposed at each angle, the other way, are variants 4 and 5
below: there a fixed basis gives a subspace that turns with the angle, less up to 5 directions to the ties.)

The peer, for each target:
- pyMOR's one-angle model at every source point (the angles of interest; in the second variant also the
  midpoints): of the methods given, the smallest order that meets the target at that point alone; its projection
  bases (V, and W for two-sided methods: a Galerkin projection on V + W interpolates on both sides) kept.
- Each point's bases orthonormalized in the M inner product (M at the first angle, one product for all), stacked,
  and compressed by pyMOR's pod in the same product.
- At every point, the model is the Galerkin projection of that point's elastic system (bench.py's M, beta K, K, Ge,
  He) on the leading directions made M-orthogonal to that point's rigid modes (the rigid modes turn with the angle,
  so directions elastic at one angle are not at another; this keeps the rigid poles out as pyMOR's one-angle model
  does). States: 2 x the rank of that projected basis, the largest over the points.
- The smallest number of leading directions that meets the target at every angle of interest and every midpoint.

Stronger peers, from the second variant's vectors (not what a pyMOR user makes, but fair: the same vectors):
- "POD, by the true error": the POD directions chosen by this bench's error (forward greedy, then pruned; the
  leading set pruned too; the smaller kept): the POD orders by energy, not by the error.
- "bodies' dofs, tied": the vectors in the bodies' own dofs (x = T y at their angle), one POD in the bodies' mass,
  and at each point the ties of that angle imposed on the leading directions (Galerkin on {W q : C W q = 0}, as
  kryflex's reassembly does): a subspace that turns with the angle, at the cost of up to 5 directions to the ties.
- "body-wise, tied, by the true error": the same vectors split by body (each body's POD in its own mass, kryflex's
  form), the ties at each point, directions chosen by the true error.

Times, wall (CPU): a peer's are pyMOR's one-angle reductions at its source points (the chosen orders; every order
tried is printed on its own line), the POD and the choice of directions (its measurements against the reference,
which is not counted); kryflex's are its whole reduction (its own verification at every point included).
"""
import argparse
import os
import sys
import time

import numpy as np
import scipy.sparse as sp

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import angles as ang  # noqa: E402
import bench  # noqa: E402
from bench import ref  # noqa: E402


def reduced_blocks(full_a, ref_a, Phi):
    """The elastic system at one point on the directions Phi (columns), made M-orthogonal to the point's rigid
    modes R: with P = I - R R^T M, K P = K, Ge^T P = Ge^T and He P = He (R^T Ge = 0, He R = 0), so
    P^T K P = Phi^T K Phi, P^T M P = Phi^T M Phi - (Phi^T M R)(R^T M Phi), and any subset of the directions is a
    submatrix of these."""
    M, K, G, H, R, lam = full_a
    _, _, _, Ge, He = ref_a
    MPhi = M @ Phi
    MR = Phi.T @ (M @ R)
    Mr = Phi.T @ MPhi - MR @ MR.T
    Kr = Phi.T @ (K @ Phi)
    return 0.5 * (Mr + Mr.T), 0.5 * (Kr + Kr.T), Phi.T @ Ge, He @ Phi


def measure(blocks, ref_a, beta, sel):
    """Error and rank of the Galerkin model on the directions sel at one point: T(w) = Hr (Kr (1 + i w beta)
    - w^2 Mr)^-1 Gr on the M-orthonormalized span (directions below 1e-6 of the largest M-norm dropped)."""
    Mr, Kr = blocks[0][np.ix_(sel, sel)], blocks[1][np.ix_(sel, sel)]
    Gr, Hr = blocks[2][sel], blocks[3][:, sel]
    freqs, T_el = ref_a[0], ref_a[1]
    if Mr.shape[0] == 0:     # no direction left (the ties took them all): the zero model
        return bench.elastic_error(T_el, np.zeros_like(T_el), T_el), 0
    mu, U = np.linalg.eigh(Mr)
    keep = mu > 1e-12 * max(mu.max(), 1e-300)
    S = U[:, keep] / np.sqrt(mu[keep])
    lam, Q = np.linalg.eigh(S.T @ Kr @ S)
    X = S @ Q
    g, h = X.T @ Gr, Hr @ X
    w = 2 * np.pi * freqs
    d = 1.0 / (lam[None, :] * (1 + 1j * w[:, None] * beta) - (w ** 2)[:, None])
    T = np.einsum("tk,wk,ka->wta", h, d, g)
    return bench.elastic_error(T_el, T, T_el), int(keep.sum())


def worst(blocks_at, ref_at, beta, sel, points):
    errs, ranks = [], []
    for a in points:
        e, r = measure(blocks_at[a], ref_at[a], beta, sel)
        errs.append(e)
        ranks.append(r)
    return max(errs), max(ranks), errs


def pod_directions(blocks, M0):
    """Each point's bases M0-orthonormalized, stacked, pyMOR's pod in the M0 product: the directions (columns),
    leading first, and the singular values."""
    from pymor.algorithms.gram_schmidt import gram_schmidt
    from pymor.algorithms.pod import pod
    from pymor.operators.numpy import NumpyMatrixOperator
    product = NumpyMatrixOperator(M0)
    space = product.source
    stack = space.empty()
    for B in blocks:
        stack.append(gram_schmidt(space.from_numpy(B), product=product, atol=1e-13, rtol=1e-13))
    modes, svals = pod(stack, product=product, rtol=1e-10)
    return modes.to_numpy(), svals, len(stack)


def by_true_error(worst_of, ncand, target, start=None):
    """Directions chosen by this bench's error: added one at a time, each the candidate that leaves the fewest points
    missing the target (then the smallest sum of log errors: the largest error alone is about 1 for every candidate
    while some resonance is still missed somewhere), until every point meets it; then pruned: the direction whose
    removal leaves the smallest largest error removed while the target stays met. With start (a set that meets the
    target), that set pruned too, and the one with fewer states kept. ((states, directions, worst error, errors)
    or None, chosen)."""
    def prune(sel):
        sel = list(sel)
        while len(sel) > 1:
            trial = min((worst_of([c for c in sel if c != d])[0], d) for d in sel)
            if trial[0] > target:
                break
            sel.remove(trial[1])
        err, rank, errs = worst_of(sel)
        return (2 * rank, len(sel), err, errs), sel

    sel, pool, found = [], list(range(ncand)), []
    while pool:
        trial = []
        for c in pool:
            err, rank, errs = worst_of(sel + [c])
            trial.append((sum(e > target for e in errs), float(np.sum(np.log(errs))), c))
        c = min(trial)[2]
        sel.append(c)
        pool.remove(c)
        if worst_of(sel)[0] <= target:
            found.append(prune(sel))
            break
    if start is not None:
        found.append(prune(start))
    return min(found, key=lambda f: (f[0][0], f[0][1])) if found else (None, sel)


def body_directions(stack, Mb, scene):
    """Bodies' dofs: the stacked vectors split by body (kryflex's form, fed with pyMOR's vectors), each body's rows
    compressed by pyMOR's pod in that body's mass; all bodies' directions (zero on the other bodies) as columns."""
    from pymor.algorithms.pod import pod
    from pymor.operators.numpy import NumpyMatrixOperator
    out = []
    for b, body in enumerate(scene.bodies):
        rows = np.arange(scene.offsets[b], scene.offsets[b] + body.M.shape[0])
        product = NumpyMatrixOperator(Mb[rows][:, rows].tocsc())
        modes, _ = pod(product.source.from_numpy(stack[rows]), product=product, rtol=1e-10)
        D = np.zeros((stack.shape[0], len(modes)))
        D[rows] = modes.to_numpy()
        out.append(D)
    return np.hstack(out)


class Tied:
    """Directions Wc of the bodies' dofs (columns), the ties imposed at each point: the model at a point is the
    Galerkin projection on {Wc[:, S] q : C Wc[:, S] q = 0}, i.e. on Phi = (Wc[:, S] Z)[kept] with Z = null(C Wc[:, S])
    in bench.full_order's coordinates (T Phi = Wc[:, S] Z), made M-orthogonal to the point's rigid modes R as
    reduced_blocks does; every product is formed once on all of Wc (T R are the rigid modes in the bodies' dofs)."""

    def __init__(self, Wc, Mb, Kb, Gx, Hx, full, ties_at, points):
        self.WMW, self.WKW = Wc.T @ (Mb @ Wc), Wc.T @ (Kb @ Wc)
        self.at, self.scale = {}, np.linalg.norm(Wc, axis=0).max()

        for a in points:
            C, T, indep = ties_at[a]
            R = T @ full[a][4]
            MR = Wc.T @ (Mb @ R)
            self.at[a] = (C @ Wc, np.linalg.norm(C, 2) * self.scale, MR, Wc.T @ Gx - MR @ (R.T @ Gx), Hx @ Wc - (Hx @ R) @ MR.T)

    def blocks(self, a, sel):
        CW, scale, MR, Gc, Hc = self.at[a]
        ix = np.ix_(sel, sel)
        _, sv, Vt = np.linalg.svd(CW[:, sel])     # the tolerance absolute: on vectors that already meet the ties,
        rank = int(np.sum(sv > 1e-10 * scale))    # C Wc is rounding, which a relative one would count as rank
        Z = Vt[rank:].T
        Mr = Z.T @ (self.WMW[ix] - MR[sel] @ MR[sel].T) @ Z
        Kr = Z.T @ self.WKW[ix] @ Z
        return 0.5 * (Mr + Mr.T), 0.5 * (Kr + Kr.T), Z.T @ Gc[sel], Hc[:, sel] @ Z

    def worst(self, ref_at, beta, sel, points):
        errs, ranks = [], []
        for a in points:
            blocks = self.blocks(a, sel)
            e, r = measure(blocks, ref_at[a], beta, list(range(blocks[0].shape[0])))
            errs.append(e)
            ranks.append(r)
        return max(errs), max(ranks), errs


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", required=True)
    ap.add_argument("--targets", type=float, nargs="+", default=[1e-2, 1e-3, 1e-4])
    ap.add_argument("--methods", nargs="+", default=["SO Galerkin", "SOR-IRKA"],
                    help="pyMOR's one-angle methods (by the start of their names; second-order ones: their "
                    "projection bases make the peer)")
    ap.add_argument("--orders", type=int, nargs="+", default=[2, 4, 6, 8])
    ap.add_argument("--kryflex-options", nargs="+", default=["default:"],
                    help="option sets NAME:key=value ... as bench.py's; none: no kryflex rows")
    ap.add_argument("--no-greedy", action="store_true")
    ap.add_argument("--no-body-wise", action="store_true", help="without the body-wise variant (its greedy tries "
                    "every body's every direction at every step: minutes at 2,760 dofs)")
    args = ap.parse_args()
    bench.ensure_pymor()
    path = os.path.abspath(args.scene)
    t0 = time.perf_counter()
    scene, angles, points, full, beta, ref_at = ang.setup(path)
    band = scene.raw["band"]
    mids = [a for a in points if a not in angles]
    print("peers bench (one peer model for several angles), %s UTC, %s, angles %s, midpoints %s, %d dofs, 1 rank, "
          "reference %.1f s" % (time.strftime("%Y-%m-%d %H:%M", time.gmtime()), args.scene, angles, mids,
                                full[angles[0]][0].shape[0], time.perf_counter() - t0), flush=True)

    rows, ktime = {}, {}
    names = [] if args.kryflex_options == ["none"] else list(bench.parse_options(args.kryflex_options))
    for name, opts in bench.parse_options(args.kryflex_options).items():
        if name not in names:
            continue
        for target in args.targets:
            ktime[(target, name)] = ang.kryflex_rows(path, angles, points, beta, ref_at, name, opts, target, rows)

    # pyMOR at every point alone: every order tried, its error, time and bases
    one = {a: [] for a in points}     # a -> [(states, err, wall, cpu, method, r, [bases])]
    for a in points:
        M, K, G, H, R, lam = full[a]
        freqs, T_el, _, Ge, He = ref_at[a]
        so = bench.pymor_model(M, K, beta, Ge, He)
        bases = {}
        for mname, r, st, err, sec, cpu in ang.pymor_orders(so, band, args.methods, args.orders, freqs, T_el, a,
                                                            min(args.targets), bases):
            one[a].append((st, err, sec, cpu, mname, r, [bases[k] for k in ("V", "W") if k in bases]))

    def best_at(a, target):
        ok = [row for row in one[a] if row[1] <= target]
        return min(ok, key=lambda row: (row[0], row[2])) if ok else None

    M0 = full[angles[0]][0]
    Mb = sp.block_diag([b.M for b in scene.bodies]).tocsc()
    Kb = sp.block_diag([b.K for b in scene.bodies]).tocsc()
    Gx, Hx = ref.body_io(scene)
    ties_at = {a: bench.ties(scene, a) for a in points}
    peer = {}     # (target, variant) -> (states, directions, worst error, errors, wall, cpu)

    def report(variant, target, found, ndir, what, sec, cpu):
        print("peer %-34s target %g: %s; %s; %.2f s (CPU %.2f s) with the reductions" % (
            variant, target, ("%d states (%d directions), worst error %.3g, at the points %s" %
                              (found[0], found[1], found[2], " ".join("%.2g" % e for e in found[3])))
            if found else "not met by any number of the %d directions" % ndir, what, sec, cpu), flush=True)
        if found:
            peer[(target, variant)] = tuple(found) + (sec, cpu)

    def leading(worst_of, ndir, target):
        for n in range(1, ndir + 1):
            err, rank, errs = worst_of(list(range(n)))
            if err <= target:
                return (2 * rank, n, err, errs)
        return None

    for target in args.targets:
        chosen = {a: best_at(a, target) for a in points}
        for variant, sources in (("angles", angles), ("angles+midpoints", points)):
            missing = [a for a in sources if chosen[a] is None]
            if missing:
                print("peer %-34s target %g: pyMOR met it at no order tried at %s: no peer" % (variant, target, missing),
                      flush=True)
                continue
            red_sec, red_cpu = sum(chosen[a][2] for a in sources), sum(chosen[a][3] for a in sources)
            stack = [B for a in sources for B in chosen[a][6]]
            print("peer %-34s target %g: pyMOR's %s at %d points (%s states each), %d vectors, reductions %.2f s "
                  "(CPU %.2f s)" % (variant, target, "/".join(sorted({chosen[a][4] for a in sources})), len(sources),
                                    "/".join(str(x) for x in sorted({chosen[a][0] for a in sources})),
                                    sum(B.shape[1] for B in stack), red_sec, red_cpu), flush=True)
            # the assembled dofs: one POD, the leading directions
            t1, c1 = time.perf_counter(), time.process_time()
            Phi, svals, nstack = pod_directions(stack, M0)
            blocks_at = {a: reduced_blocks(full[a], ref_at[a], Phi) for a in points}
            found = leading(lambda sel: worst(blocks_at, ref_at, beta, sel, points), Phi.shape[1], target)
            report(variant, target, found, Phi.shape[1], "%d POD directions (singular values %.3g .. %.3g)"
                   % (Phi.shape[1], svals[0], svals[-1]),
                   red_sec + time.perf_counter() - t1, red_cpu + time.process_time() - c1)
            if variant != "angles+midpoints" or args.no_greedy:
                continue
            # the same POD directions chosen by the true error
            t1, c1 = time.perf_counter(), time.process_time()
            gfound, sel = by_true_error(lambda sel: worst(blocks_at, ref_at, beta, sel, points), Phi.shape[1],
                                        target, list(range(found[1])) if found else None)
            report("POD, by the true error", target, gfound, Phi.shape[1], "chosen %s" % sel,
                   red_sec + time.perf_counter() - t1, red_cpu + time.process_time() - c1)
            # the bodies' dofs with the ties at each point: one POD of the vectors in the bodies' dofs, the leading
            # directions; and the vectors split by body, chosen by the true error
            t1, c1 = time.perf_counter(), time.process_time()
            X = np.hstack([ties_at[a][1] @ B for a in sources for B in chosen[a][6]])
            Wx, svx, _ = pod_directions([X], Mb)
            tied = Tied(Wx, Mb, Kb, Gx, Hx, full, ties_at, points)
            found = leading(lambda sel: tied.worst(ref_at, beta, sel, points), Wx.shape[1], target)
            report("bodies' dofs, tied", target, found, Wx.shape[1], "%d POD directions" % Wx.shape[1],
                   red_sec + time.perf_counter() - t1, red_cpu + time.process_time() - c1)
            if args.no_body_wise:
                continue
            t1, c1 = time.perf_counter(), time.process_time()
            Wb = body_directions(X, Mb, scene)
            tied = Tied(Wb, Mb, Kb, Gx, Hx, full, ties_at, points)
            gfound, sel = by_true_error(lambda sel: tied.worst(ref_at, beta, sel, points), Wb.shape[1], target)
            report("body-wise, tied, by the true error", target, gfound, Wb.shape[1], "%d candidates, chosen %s" %
                   (Wb.shape[1], sel), red_sec + time.perf_counter() - t1, red_cpu + time.process_time() - c1)

    variants = ["angles", "angles+midpoints"] + ([] if args.no_greedy else [
        "POD, by the true error", "bodies' dofs, tied"] + ([] if args.no_body_wise else [
            "body-wise, tied, by the true error"]))
    print("\nFirst-order elastic states, the largest over the %d angles of interest and %d midpoints (each model's "
          "worst error over them); times: wall (CPU) s" % (len(angles), len(mids)))
    heads = (["kryflex %s, one model" % n for n in names] + ["peer %s, one model" % v for v in variants]
             + ["pyMOR one model per point (largest; smallest)"])
    print("\n| target | " + " | ".join(heads) + " |")
    print("|---|" + "---|" * len(heads))
    for target in args.targets:
        cells = []
        for n in names:
            st = max(rows[(target, n, a)][0] for a in points)
            err = max(rows[(target, n, a)][1] for a in points)
            cells.append("%d, %.2g%s, %.2f s (%.2f)" % (st, err, "" if err <= target else " MISSED",
                                                        *ktime[(target, n)]))
        for v in variants:
            p = peer.get((target, v))
            cells.append("%d (%d directions), %.2g, %.2f s (%.2f)" % (p[0], p[1], p[2], p[4], p[5]) if p else "not met")
        b = [best_at(a, target) for a in points]
        if all(b):
            cells.append("%d; %d (%s), %.2f s (%.2f) each at most" % (
                max(x[0] for x in b), min(x[0] for x in b), "/".join(sorted({x[4] for x in b})),
                max(x[2] for x in b), max(x[3] for x in b)))
        else:
            cells.append("not met at %s by the orders tried" % [a for a, x in zip(points, b) if x is None])
        print("| %g | %s |" % (target, " | ".join(cells)))


if __name__ == "__main__":
    main()
