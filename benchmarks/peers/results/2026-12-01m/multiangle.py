"""Several angles of interest: the smallest Galerkin model of kryflex's form serving all of them, from a rich source
(the search's model for the target x --srcf, uncompressed), of both kinds: body-wise (each body's own basis, a joint SVD
of its share of the responses at every point, the two bodies' counts searched over every split of each total) and
tied (stacked directions: one SVD of all points' snapshots in both bodies' coordinates); each kind with the static responses at every point kept exactly and without.
The set-up (references, reassembly, the error) and the snapshots are results/2026-11-29p/tied.py's, run as they are
(its description says what they are).
    python multiangle.py --scene SCENE [--srcf 0.01] [--targets 1e-2 1e-3 1e-4] [--kryflex-only]
"""
import sys, os, argparse, time, textwrap
HERE = os.path.dirname(os.path.abspath(__file__))
ap = argparse.ArgumentParser()
ap.add_argument("--srcf", type=float, default=0.01)
ap.add_argument("--kmax", type=int, default=24)
ap.add_argument("--kryflex-only", action="store_true", help="kryflex's own models (compressed, static exact and not), measured the same way")
mine, rest = ap.parse_known_args()
sys.argv = [sys.argv[0]] + rest
# tied.py's set-up as it is (its options, the scene, the points, the references, measure() and system()): one copy
TIED = os.path.join(HERE, "..", "2026-11-29p", "tied.py")
exec(compile(open(TIED).read().split("\nfor target in args.targets:")[0], TIED, "exec"))
args.srcf, args.kmax, args.kryflex_only = mine.srcf, mine.kmax, mine.kryflex_only
_src = open(TIED).read()
SNAPSHOTS = compile(textwrap.dedent(_src[_src.index("    bodies = [dict(b)"):_src.index("    L = np.linalg.cholesky(Mblk)")]), TIED, "exec")


def restricted(T, at_a, a):
    Ms, Ks, Gs, Hs, P, N = at_a
    Tp = T @ np.linalg.pinv(T)
    Y = sl.null_space((np.eye(N.shape[0]) - Tp) @ N, rcond=1e-9)
    if Y.shape[1] <= P.shape[1]:    # rigid only: no elastic response at all
        return np.inf, 0, P.shape[1]
    Mr, Kr, Gr, Hr = Y.T @ Ms @ Y, Y.T @ Ks @ Y, Y.T @ Gs, Hs @ Y
    Pr = np.linalg.lstsq(Y, P, rcond=None)[0]
    return measure(a, Mr, Kr, Gr, Hr, Pr), Y.shape[1] - P.shape[1], P.shape[1]


def worst_over(T, at, stop):
    worst, el = 0.0, []
    for a in points:
        e, n, nr = restricted(T, at[a], a)
        worst, el = max(worst, e), el + [n + nr / 1000]   # elastic dofs, the rigid count in the fraction
        if worst > stop:
            break
    return worst, max(el)


def independent(model):
    """A kryflex model's worst independent elastic error over the points, its elastic dofs at each, its system there."""
    worst, el = 0.0, []
    for a in points:
        s_ = model.at([a])
        w, T_el, T_full = ref_at[a]
        worst = max(worst, B.elastic_error(T_full, s_.frf(w / (2 * np.pi)), T_el))
        el.append(s_.dofs - s_.rigid_modes.shape[1])
    return worst, el, s_


import kryflex
for target in (args.targets if args.kryflex_only else []):
    for label, opts in (("static exact", {}), ("static_exact 0", {"static_exact": "0"})):
        c0 = time.process_time()
        spec = B.kryflex_spec(path, angles[0], beta, target)
        spec["angles"] = list(angles)
        out = kryflex.Reducer(kryflex.scene_from_dict(spec), quiet=True, **opts).reduce()
        model = out.model
        worst, el, s_ = independent(model)
        print("kryflex target %g %-14s: bodies %s, ties %s, %d elastic states (%d system dofs), independent worst error %.2g, "
              "kryflex's %.2g, %s, whole %.2f s" % (target, label, model.sizes, None if model.ties is None else model.ties.shape[0],
              2 * max(el), max(el) + s_.rigid_modes.shape[1], worst, out.summary.verdict.error_max, out.summary.chosen.method,
              out.summary.performance.whole_s), flush=True)
for target in ([] if args.kryflex_only else args.targets):
    t0 = time.process_time()
    spec = B.kryflex_spec(path, angles[0], beta, target * args.srcf)
    spec["angles"] = list(angles)
    model = kryflex.Reducer(kryflex.scene_from_dict(spec), quiet=True, compress="0").reduce().model
    exec(SNAPSHOTS)      # tied.py's: the source reassembled at every point (at[a]) and its snapshots there
    stat = [snaps[i - 1] for i in np.cumsum([2 * len(ref_at[a][0]) + 1 for a in points])]    # each point's last: f = 0
    L = np.linalg.cholesky(Mblk)
    print("target %g: source (target x %g) %s, error %.2g over the points" % (target, args.srcf, "+".join(map(str, v)), e_src), flush=True)
    for static in (False, True):
        # tied: stacked directions (static responses first, exactly, when static)
        base = np.hstack([Rblk] + (stat if static else []))
        Qb, sb, _ = np.linalg.svd(L.T @ base, full_matrices=False)
        Qb = Qb[:, sb > 1e-10 * sb[0]]
        S = L.T @ np.hstack(snaps)
        S -= Qb @ (Qb.T @ S)
        u, s, _ = np.linalg.svd(S, full_matrices=False)
        r = min(int((s > 1e-10 * s[0]).sum()), args.kmax)
        found = None
        for k in range(0, r + 1):
            T = sl.solve_triangular(L.T, np.hstack([Qb, u[:, :k]]), lower=False)
            worst, el = worst_over(T, at, target)
            if worst <= target:
                found = (el, worst, k)
                break
        print("  tied,      static %-5s: %s" % (static, "%d elastic states (%d system dofs), %d stacked directions beyond the static, worst error %.2g" % (2 * int(found[0]), int(found[0]) + round(found[0] % 1 * 1000), found[2], found[1]) if found else "not met within %d" % r), flush=True)
        # body-wise: per body, its share of the snapshots, rigid (and static shares) kept, an SVD in its M norm
        dirs = []
        for i in range(len(v)):
            Lb = np.linalg.cholesky(0.5 * (bodies[i]["M"] + bodies[i]["M"].T))
            sl_i = slice(off[i], off[i + 1])
            bb = np.hstack([bodies[i]["rigid"]] + ([st[sl_i] for st in stat] if static else []))
            Qi, si, _ = np.linalg.svd(Lb.T @ bb, full_matrices=False)
            Qi = Qi[:, si > 1e-10 * si[0]]
            Si = Lb.T @ np.hstack(snaps)[sl_i]
            Si -= Qi @ (Qi.T @ Si)
            ui, s_i, _ = np.linalg.svd(Si, full_matrices=False)
            ri = int((s_i > 1e-10 * s_i[0]).sum())
            dirs.append((Lb, Qi, ui[:, :ri]))
        found = None
        for tot in range(0, sum(d[2].shape[1] for d in dirs) + 1):
            best = None
            for k0 in range(0, tot + 1):
                ks = [k0, tot - k0]
                if any(k > d[2].shape[1] for k, d in zip(ks, dirs)):
                    continue
                T = sl.block_diag(*[sl.solve_triangular(Lb.T, np.hstack([Qi, ui[:, :k]]), lower=False) for (Lb, Qi, ui), k in zip(dirs, ks)])
                worst, el = worst_over(T, at, target)
                if worst <= target and (best is None or el < best[0]):
                    best = (el, worst, ks, [d[1].shape[1] + k for d, k in zip(dirs, ks)])
            if best:
                found = best
                break
        print("  body-wise, static %-5s: %s" % (static, "%d elastic states (%d system dofs), bodies %s dofs (directions beyond rigid/static %s), worst error %.2g" % (2 * int(found[0]), int(found[0]) + round(found[0] % 1 * 1000), found[3], found[2], found[1]) if found else "not met"), flush=True)
    print("  %.1f CPU s" % (time.process_time() - t0), flush=True)
