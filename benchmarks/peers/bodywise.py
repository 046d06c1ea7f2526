"""What a body-wise basis costs against a system-level one, at one angle, on the peers bench's scene and measure.

    .venv/bin/python benchmarks/peers/bodywise.py [--refine 0.5]

kryflex's models reassemble at any angle, so their bases are body-wise: a system vector X (tied coordinates) becomes
its restrictions to the bodies, each body basis holds its 6 rigid modes and the restrictions' elastic part, and the
reduced system is the bodies' direct sum under the joint ties. pyMOR projects the assembled system at one angle.
For several system bases V (pyMOR's 3-point Galerkin interpolation among them), this prints:

- the system-level Galerkin model on span(rigid modes, V): its elastic dofs and the bench's elastic error;
- the body-wise model of the same vectors: every body direction kept (the span contains the system model's);
- the smallest body-wise model that meets each target when each body keeps only its leading principal directions
  (M_b-weighted SVD of the restriction, rigid part out), over every pair of counts (bus, rotor): an oracle;
- the model a search could find: body by body, the fewest leading directions that still meet the target
  (bisection, the other bodies as found so far).

Dense NumPy/SciPy throughout (2,755 dofs); the reference is bench.py's (sparse LU per grid point). The rigid modes
are held exactly null in every reduced stiffness (P^T K_r P), as kryflex does, so the band's bottom measures the
elastic part only.
"""
import argparse
import os
import sys
import tempfile

import numpy as np
import scipy.linalg as sl
import scipy.sparse as sp
import scipy.sparse.linalg as spla

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import bench as B  # noqa: E402

ref = B.ref


def tie_map(scene, C):
    """Sparse T with x = T y satisfying the ties C x = 0 (the bench's elimination of the child's interface dofs)."""
    off, child = scene.offsets, []
    for j in scene.joints:
        c = scene.body_index(j["child"])
        child += list(off[c] + ref.interface_dofs(scene.bodies[c], j["child_interface"]))
    T = B.eliminate_ties(C, child)
    return T[0] if isinstance(T, tuple) else T


def geometric_rigid(scene, C, T, M):
    """The rigid-body and mechanism modes from node coordinates and joints, in the tied coordinates, M-orthonormal:
    exact, where an eigensolver's null space of K is good to about 1e-9 only, which the band's bottom amplifies to
    2e-4 of a pair's elastic peak."""
    Bg = sl.block_diag(*[ref.body_rigid_modes(scene, b) for b in range(len(scene.bodies))])
    X = Bg @ sl.null_space(C @ Bg)
    Tt = T.tocsc()
    Y = np.asarray(spla.spsolve((Tt.T @ Tt).tocsc(), Tt.T @ X)).reshape(Tt.shape[1], X.shape[1])
    return Y @ np.linalg.inv(np.linalg.cholesky(Y.T @ (M @ Y))).T


class Problem:
    def __init__(self, scene, angle):
        self.scene = scene
        band, zeta = scene.raw["band"], float(scene.raw["damping"])
        self.Mb = sp.block_diag([b.M for b in scene.bodies]).tocsc()
        self.Kb = sp.block_diag([b.K for b in scene.bodies]).tocsc()
        self.Gb, self.Hb = ref.body_io(scene)
        self.C = ref.constraint_matrix(scene, [angle])
        T, Mb, Kb = tie_map(scene, self.C), self.Mb, self.Kb
        M, K = (T.T @ Mb @ T).tocsc(), (T.T @ Kb @ T).tocsc()
        M, K = 0.5 * (M + M.T), 0.5 * (K + K.T)
        G, H = T.T @ self.Gb, self.Hb @ T
        self.T, self.G, self.H = T, G, H
        self.PhiR = geometric_rigid(scene, self.C, T, M)
        self.nr = self.PhiR.shape[1]
        self.M, self.K = M.toarray(), K.toarray()
        lam, Phi = sl.eigh(self.K, self.M)
        self.lam, self.Phi = lam, Phi
        w1 = np.sqrt(lam[self.nr])
        self.beta = 2 * zeta / w1
        f_res = np.sqrt(lam[self.nr:]) / (2 * np.pi)
        f_res = f_res[f_res <= band[1]]
        self.f_res, self.band = f_res, band
        self.freqs = B.grid(band, f_res, self.beta * 2 * np.pi * f_res / 2)
        self.w = 2 * np.pi * self.freqs
        P = self.PhiR
        self.Ge = G - M @ (P @ (P.T @ G))
        He = H - (H @ P) @ (P.T @ M)
        self.T_el = B.direct_response(M, K, self.beta, self.Ge, He, self.freqs)
        self.T_full = self.T_el - (H @ P @ P.T @ G)[None] / (self.w ** 2)[:, None, None]
        self.Rb = [ref.body_rigid_modes(scene, b) for b in range(len(scene.bodies))]
        self.Mbd = [b.M.toarray() for b in scene.bodies]
        self.off = scene.offsets

    def error(self, Q, Mfull, Kfull, G, H, Xrigid):
        """the bench's elastic error of the Galerkin model on span Q, its rigid modes Xrigid held exactly null"""
        Mr, Kr = Q.T @ (Mfull @ Q), Q.T @ (Kfull @ Q)
        z = np.linalg.solve(Mr, Q.T @ (Mfull @ Xrigid))
        z = z @ np.linalg.inv(np.linalg.cholesky(z.T @ Mr @ z)).T
        P = np.eye(Q.shape[1]) - z @ (z.T @ Mr)
        lr, Pr = sl.eigh(P.T @ Kr @ P, Mr)
        lr = np.where(np.abs(lr) < 1.0, 0.0, lr)
        a, b = H @ Q @ Pr, Pr.T @ (Q.T @ G)
        den = lr[None, :] * (1 + 1j * self.w[:, None] * self.beta) - (self.w ** 2)[:, None]
        return B.elastic_error(self.T_full, np.einsum("tk,fk,ka->fta", a, 1.0 / den, b), self.T_el)

    def system_model(self, V):
        Q = np.linalg.qr(np.hstack([self.PhiR, V]))[0]
        s, u = np.linalg.eigh(Q.T @ self.M @ Q)
        Q = Q @ u[:, s > 1e-12 * s.max()]
        return self.error(Q, self.M, self.K, self.G, self.H, self.PhiR), Q.shape[1] - self.nr

    def body_directions(self, V):
        """per body: its rigid modes (M_b-orthonormal) and the restrictions' principal directions, leading first"""
        X = self.T @ V
        out = []
        for b, (R, Mm) in enumerate(zip(self.Rb, self.Mbd)):
            Xb = X[self.off[b]:self.off[b + 1]]
            R = R @ np.linalg.inv(np.linalg.cholesky(R.T @ Mm @ R)).T
            Xb = Xb - R @ (R.T @ Mm @ Xb)
            s, u = np.linalg.eigh(Xb.T @ Mm @ Xb)
            s, u = s[::-1], u[:, ::-1]
            keep = s > 1e-22 * s[0]
            out.append((R, Xb @ u[:, keep] / np.sqrt(s[keep])))
        return out

    def body_model(self, dirs, counts):
        Psi = sl.block_diag(*[np.hstack([R, E[:, :r]]) for (R, E), r in zip(dirs, counts)])
        Q = Psi @ ref.null_space_svd(self.C @ Psi)
        return self.error(Q, self.Mb, self.Kb, self.Gb, self.Hb, self.T @ self.PhiR), Q.shape[1] - self.nr

    def real_points(self, pts):
        """kryflex's kind of basis: one block at zero (K + 1e-3 M)^-1 G_e and one input block (K - sigma M)^-1 G_e at
        each real point sigma = (2 pi f)^2"""
        V = [np.linalg.solve(self.K + 1e-3 * self.M, self.Ge)]
        V += [np.linalg.solve(self.K - (2 * np.pi * f) ** 2 * self.M, self.Ge) for f in pts]
        return np.hstack(V)

    def galerkin(self, pts):
        V = []
        for f in pts:
            s = 2j * np.pi * f
            X = np.linalg.solve(s * s * self.M + s * self.beta * self.K + self.K, self.Ge)
            V += [X.real, X.imag]
        return np.hstack(V)


def report(p, name, V, targets):
    e, n = p.system_model(V)
    dirs = p.body_directions(V)
    full = [d[1].shape[1] for d in dirs]
    ea, na = p.body_model(dirs, full)
    best = {}
    for ra in range(full[0] + 1):
        for rr in range(full[1] + 1):
            e2, n2 = p.body_model(dirs, [ra, rr])
            for t in targets:
                if e2 <= t and (t not in best or n2 < best[t][0]):
                    best[t] = (n2, ra, rr, e2)
    cells = ["%d (%d+%d) %.1e" % ((2 * best[t][0],) + best[t][1:]) if t in best else "not met" for t in targets]
    for t in targets:   # what a search can find: each body in turn, the fewest directions by bisection
        c = list(full)
        if p.body_model(dirs, c)[0] > t:
            cells.append("not met")
            continue
        for b in range(len(c)):
            lo, hi = -1, c[b]
            while hi - lo > 1:
                mid = (lo + hi) // 2
                if p.body_model(dirs, c[:b] + [mid] + c[b + 1:])[0] <= t:
                    hi = mid
                else:
                    lo = mid
            c[b] = hi
        e2, n2 = p.body_model(dirs, c)
        cells.append("%d (%d+%d) %.1e" % (2 * n2, c[0], c[1], e2))
    print("| %s | %d, %.1e | %d (%d+%d), %.1e | %s |" % (name, 2 * n, e, 2 * na, full[0], full[1], ea,
                                                       " | ".join(cells)), flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--refine", type=float, default=0.5)
    ap.add_argument("--angle", type=float, default=0.0)
    ap.add_argument("--targets", type=float, nargs="+", default=[1e-2, 1e-3, 1e-4])
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        B.subprocess.run([sys.executable, os.path.join(B.ROOT, "meshes", "solid", "generate.py"), "--refine",
                          str(args.refine), "-o", folder], check=True, capture_output=True)
        p = Problem(ref.load_scene(os.path.join(folder, "spacecraft.yaml")), args.angle)
    nr, f_res, zeta = p.nr, p.f_res, float(p.scene.raw["damping"])
    print("body-wise against system-level bases, solid --refine %g at %g deg: %d dofs, %d flexible modes in the band "
          "(%s Hz)" % (args.refine, args.angle, p.M.shape[0], len(f_res), ", ".join("%.3g" % f for f in f_res)))
    print("states = 2 x elastic dofs; body-wise (bus+rotor) = elastic directions per body\n")
    print("| system basis V | system-level: states, error | body-wise, every direction: states (bus+rotor), error | "
          + " | ".join("smallest body-wise meeting %g" % t for t in args.targets) + " | "
          + " | ".join("per-body bisection, %g" % t for t in args.targets) + " |")
    print("|---|---|---|" + "---|" * (2 * len(args.targets)))
    top = p.band[1]
    Fm = p.Phi[:, nr:nr + len(f_res)]
    S = np.linalg.solve(p.K + 1e-3 * p.M, p.Ge)
    S -= Fm @ (Fm.T @ p.M @ S) + p.PhiR @ (p.PhiR.T @ p.M @ S)
    report(p, "Galerkin, 3 points evenly in the band (pyMOR's)", p.galerkin(np.linspace(top / 3, top, 3)), args.targets)
    report(p, "Galerkin, 4 points evenly", p.galerkin(np.linspace(top / 4, top, 4)), args.targets)
    report(p, "Galerkin at the %d resonances x (1 + zeta)" % len(f_res), p.galerkin(f_res * (1 + zeta)), args.targets)
    report(p, "real points at the %d resonances x (1 + zeta) + static" % len(f_res), p.real_points(f_res * (1 + zeta)),
           args.targets)
    report(p, "the %d modes in the band + static correction of the inputs" % len(f_res), np.hstack([Fm, S]),
           args.targets)


if __name__ == "__main__":
    main()
