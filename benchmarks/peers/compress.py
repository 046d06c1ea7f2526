"""How far each body of a kryflex model can be truncated by what the assembled response needs, on the peers bench's
scene and elastic measure: the prototype of -kf_compress (src/project/body_compress.c), dense, on top of the library,
kept as an independent check of the C step's sizes.

    .venv/bin/python benchmarks/peers/compress.py [--refine 0.5] [--targets 1e-2 1e-3 1e-4]
            [--kryflex-options "default:" "points:max_factorizations=6"] [--source-factor 0.01] [--cache ref.npz]
            [--weight peak|none]

For each kryflex model (the search's, at each target):
- snapshots of each body's share of the assembled reduced model's elastic response: the reduced displacement
  q_b(w) = N_b y(w) for every input, at the bench's grid (points across every resonance), in the body's reduced
  coordinates (N: the reassembly's null space of the ties, read as the outputs of an identity H);
- per body the rigid motions (6) and the static elastic response N_b y(0) kept exactly, the rest of the snapshots
  M_b-orthogonal to them and ordered by an SVD in the M_b norm (how much of the response each direction carries),
  each input's snapshots weighted by 1 / the largest elastic peak of its pairs in the reference (--weight peak, as
  kryflex does; none: unweighted, kryflex until 2026-11-29 13:30);
- body by body, the fewest leading directions (bisection) that still meet the target, then with two bodies every
  pair of counts along the frontier (for each count of the first body the fewest of the second), each candidate's
  elastic error measured against the bench's full-order reference. The static moment L^0 of the compressed model is
  checked against the uncompressed one's.
kryflex's C step goes further than this prototype: after the frontier it drops single directions of any body by
backward elimination, and it orders the directions on two snapshot grids and keeps the smaller result (the README's
14:03 section); the prototype's snapshots are on the bench's grid only.
Sizes are first-order states of the elastic part, 2 x (system dofs - rigid modes), as in bench.py.
"""
import argparse
import os
import sys
import tempfile
import time

import numpy as np
import scipy.linalg as sl

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import bench as B  # noqa: E402


def reassemble(bodies, joints, angles_rad, a, t):
    from kryflex import _core
    return _core.reassemble(bodies, joints, angles_rad, a, t)


class Compressor:
    """Body-wise compression of one reduced model at the angles of interest (snapshots and measure at each)."""

    def __init__(self, model, angles_deg, beta, freqs, measure, input_weights=None):
        self.inw = np.ones(model.bodies[0]["G"].shape[1]) if input_weights is None else np.asarray(input_weights)
        self.bodies = [dict(b) for b in model.bodies]
        self.joints = [model.joint(j) for j in range(len(model.joints))]
        self.a, self.t = self.bodies[0]["G"].shape[1], self.bodies[0]["H"].shape[0]
        self.angles = [np.radians(np.atleast_1d(x)) for x in angles_deg]
        self.beta, self.w, self.measure = beta, 2 * np.pi * np.asarray(freqs), measure
        self.directions = self._directions()

    def _system(self, bodies, ang, H=None):
        bs = [dict(M=b["M"], K=b["K"], G=b["G"], H=b["H"] if H is None else H[i], iface=b["iface"], rigid=b["rigid"])
              for i, b in enumerate(bodies)]
        M, K, G, Hh, rank, ratio, P = reassemble(bs, self.joints, ang, self.a, bs[0]["H"].shape[0])
        return M, K, G, Hh, P

    def _modes(self, M, K, P):
        """flexible modes on the M-complement of the rigid modes P (held exactly null)"""
        P = P @ np.linalg.inv(np.linalg.cholesky(P.T @ M @ P)).T
        Q = sl.null_space(P.T @ M)
        lam, X = sl.eigh(Q.T @ K @ Q, Q.T @ M @ Q)
        return lam, Q @ X, P

    def _directions(self):
        """per body: (the kept-exactly columns: rigid + static, M_b-orthonormal; the other directions, leading first)"""
        v = [b["M"].shape[0] for b in self.bodies]
        off = np.concatenate([[0], np.cumsum(v)])
        ident = [np.eye(off[-1])[:, off[i]:off[i + 1]] for i in range(len(v))]   # outputs H = I: Hh = N
        stat = [[] for _ in v]
        snap = [[] for _ in v]
        for ang in self.angles:
            M, K, G, N, P = self._system(self.bodies, ang, H=ident)
            lam, Phi, _ = self._modes(M, K, P)
            PG = Phi.T @ G
            y0 = Phi @ (PG / lam[:, None])
            for f in self.w:
                den = lam * (1 + 1j * f * self.beta) - f * f
                y = Phi @ (PG / den[:, None])
                for i in range(len(v)):
                    q = (N[off[i]:off[i + 1]] @ y) * self.inw[None, :]
                    snap[i] += [q.real, q.imag]
            for i in range(len(v)):
                stat[i].append(N[off[i]:off[i + 1]] @ y0)
        out = []
        for i, b in enumerate(self.bodies):
            Mb = 0.5 * (b["M"] + b["M"].T)
            L = np.linalg.cholesky(Mb)
            keep = mgs(L, np.hstack([b["rigid"]] + stat[i]))
            S = np.hstack(snap[i])
            S = S - keep @ (keep.T @ (Mb @ S))
            u, s, _ = np.linalg.svd(L.T @ S, full_matrices=False)
            r = int((s > 1e-10 * s[0]).sum()) if s.size and s[0] > 0 else 0
            D = sl.solve_triangular(L.T, u[:, :r], lower=False)
            D = D - keep @ (keep.T @ (Mb @ D))
            out.append((keep, D, s[:r]))
        return out

    def bodies_for(self, counts):
        out = []
        for b, (keep, D, _), k in zip(self.bodies, self.directions, counts):
            W = np.hstack([keep, D[:, :k]])
            W = mgs(np.linalg.cholesky(0.5 * (b["M"] + b["M"].T)), W)
            rig = np.linalg.lstsq(W, b["rigid"], rcond=None)[0]
            out.append(dict(M=W.T @ b["M"] @ W, K=W.T @ b["K"] @ W, G=W.T @ b["G"], H=b["H"] @ W,
                            iface=b["iface"] @ W, rigid=rig))
        return out

    def error(self, bodies):
        err, dofs = 0.0, 0
        for ang in self.angles:
            M, K, G, H, P = self._system(bodies, ang)
            err = max(err, self.measure(M, K, G, H, P))
            dofs = max(dofs, M.shape[0] - P.shape[1])
        return err, dofs

    def static(self, bodies, ang):
        M, K, G, H, P = self._system(bodies, ang)
        lam, Phi, _ = self._modes(M, K, P)
        return (H @ Phi) @ ((Phi.T @ G) / lam[:, None])

    def search(self, target):
        full = [D.shape[1] for _, D, _ in self.directions]
        c = list(full)
        e, _ = self.error(self.bodies_for(c))
        if e > target:
            return None
        for i in range(len(c)):
            lo, hi = -1, c[i]
            while hi - lo > 1:
                mid = (lo + hi) // 2
                if self.error(self.bodies_for(c[:i] + [mid] + c[i + 1:]))[0] <= target:
                    hi = mid
                else:
                    lo = mid
            c[i] = hi
        return self.frontier(target, c) if len(c) == 2 else c

    def frontier(self, target, c):
        """two bodies: from the bisection's pair, for each larger count of body 0 the fewest of body 1 (the error falls
        as directions are added), the smallest total kept (ties: the earlier)"""
        best, j = list(c), c[1]
        for i in range(c[0] + 1, len(self.directions[0][2]) + 1):
            if i >= sum(best):
                break
            while j > 0 and self.error(self.bodies_for([i, j - 1]))[0] <= target:
                j -= 1
            if i + j < sum(best):
                best = [i, j]
            if j == 0:
                break
        return best


def mgs(L, X, tol=1e-10):
    """M-orthonormal basis (M = L L^T) of span X, columns in order, dependent ones dropped"""
    Y = L.T @ X
    q, r, p = sl.qr(Y, mode="economic", pivoting=True)
    d = np.abs(np.diag(r))
    k = int((d > tol * d[0]).sum()) if d.size else 0
    return sl.solve_triangular(L.T, q[:, :k], lower=False)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--refine", type=float, default=0.5)
    ap.add_argument("--angle", type=float, default=0.0)
    ap.add_argument("--targets", type=float, nargs="+", default=[1e-2, 1e-3, 1e-4])
    ap.add_argument("--source-factor", type=float, default=1.0,
                    help="compress the model kryflex makes for target x this factor (a richer model: < 1)")
    ap.add_argument("--cache", help="an .npz file keeping the full-order reference between runs")
    ap.add_argument("--kryflex-options", nargs="+", default=["default:", "points:max_factorizations=6"])
    ap.add_argument("--weight", choices=["peak", "none"], default="peak",
                    help="each input's snapshots: 1 / its pairs' largest elastic peak (kryflex's), or unweighted")
    args = ap.parse_args()
    print("compression prototype, %s UTC, solid --refine %g at %g deg, 1 rank" %
          (time.strftime("%Y-%m-%d %H:%M", time.gmtime()), args.refine, args.angle), flush=True)
    with tempfile.TemporaryDirectory() as folder:
        B.subprocess.run([sys.executable, os.path.join(B.ROOT, "meshes", "solid", "generate.py"), "--refine",
                          str(args.refine), "-o", folder], check=True, capture_output=True)
        scene_path = os.path.join(folder, "spacecraft.yaml")
        scene = B.ref.load_scene(scene_path)
        band, zeta = scene.raw["band"], float(scene.raw["damping"])
        M, K, G, H, PhiR = B.full_order(scene, args.angle)
        nrigid = PhiR.shape[1]
        lam, Phi = B.modes(M, K, band[1], nrigid)
        beta = 2 * zeta / np.sqrt(lam[nrigid])
        f_res = np.sqrt(np.maximum(lam[nrigid:], 0)) / (2 * np.pi)
        f_res = f_res[f_res <= band[1]]
        freqs = B.grid(band, f_res, beta * 2 * np.pi * f_res / 2)
        Ge = G - M @ (PhiR @ (PhiR.T @ G))
        He = H - (H @ PhiR) @ (PhiR.T @ M)
        t0 = time.perf_counter()
        cache = args.cache and os.path.exists(args.cache) and np.load(args.cache)
        if cache and cache["T_el"].shape[0] == len(freqs):
            T_el = cache["T_el"]
        else:
            T_el = B.direct_response(M, K, beta, Ge, He, freqs)
            if args.cache:
                np.savez(args.cache, T_el=T_el)
        w = 2 * np.pi * freqs
        T_full = T_el - (H @ PhiR @ PhiR.T @ G)[None] / (w ** 2)[:, None, None]
        print("full order: %d dofs, %d grid points, reference %.1f s" % (M.shape[0], len(freqs),
                                                                         time.perf_counter() - t0), flush=True)

        def measure(Mr, Kr, Gr, Hr, P):
            """the bench's elastic error of a reduced system, its rigid modes P held exactly null"""
            P = P @ np.linalg.inv(np.linalg.cholesky(P.T @ Mr @ P)).T
            Q = sl.null_space(P.T @ Mr)
            lr, X = sl.eigh(Q.T @ Kr @ Q, Q.T @ Mr @ Q)
            X = Q @ X
            a_, b_ = Hr @ X, X.T @ Gr
            den = lr[None, :] * (1 + 1j * w[:, None] * beta) - (w ** 2)[:, None]
            Tr = np.einsum("tk,fk,ka->fta", a_, 1.0 / den, b_) - (Hr @ P @ P.T @ Gr)[None] / (w ** 2)[:, None, None]
            return B.elastic_error(T_full, Tr, T_el)

        print("\n| options | target | kryflex: states (bus+rotor dofs), error | compressed: states (bus+rotor), "
              "error | L^0 rel. change | compression s |")
        print("|---|---|---|---|---|---|")
        for name, opts in B.parse_options(args.kryflex_options).items():
            opts = dict({"compress": "0"}, **opts)      # the search's own model; kryflex's compression is the C one
            for target in args.targets:
                s, sec, model = kryflex_model(scene_path, args.angle, beta, target * args.source_factor, opts)
                e0 = B.elastic_error(T_full, s.frf(freqs), T_el)
                st0 = 2 * (s.dofs - s.rigid_modes.shape[1])
                t1 = time.perf_counter()
                peak = np.abs(T_el).max(axis=0)
                peak = np.maximum(peak, 1e-4 * peak.max())
                cp = Compressor(model, [args.angle], beta, freqs, measure,
                                1 / peak.max(axis=0) if args.weight == "peak" else None)
                e_chk, _ = cp.error(cp.bodies)
                c = cp.search(target)
                if c is None:
                    cell = "not met with every direction (%.1e)" % e_chk
                    l0 = float("nan")
                else:
                    bods = cp.bodies_for(c)
                    e1, d1 = cp.error(bods)
                    L0a = cp.static(cp.bodies, cp.angles[0])
                    L0b = cp.static(bods, cp.angles[0])
                    l0 = np.abs(L0a - L0b).max() / np.abs(L0a).max()
                    cell = "%d (%s), %.1e" % (2 * d1, "+".join(str(b["M"].shape[0]) for b in bods), e1)
                print("| %s | %g | %d (%s), %.1e [recomputed %.1e] | %s | %.1e | %.1f |" % (
                    name, target, st0, "+".join(str(v) for v in model.sizes), e0, e_chk, cell, l0,
                    time.perf_counter() - t1), flush=True)


def kryflex_model(scene_path, angle, beta, target, options):
    """bench.py's kryflex run, with the model itself: (system at the angle, seconds, model)"""
    import kryflex
    spec = B.kryflex_spec(scene_path, angle, beta, target)
    t0 = time.perf_counter()
    model = kryflex.Reducer(kryflex.scene_from_dict(spec), quiet=True, **options).reduce().model
    return model.at([angle]), time.perf_counter() - t0, model


if __name__ == "__main__":
    main()
