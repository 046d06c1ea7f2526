"""A full-order reference for the peers bench that is affordable at 57k dofs and independent of kryflex (SciPy only).

The bench's own reference is one sparse complex LU per grid frequency (335 of them): 58 s at 2,760 dofs, far beyond
a run's 8 minutes at 57k. This one factors once:

- the rigid-body and mechanism modes R from geometry (node coordinates and the joint ties, M-orthonormal): an
  eigensolver knows K's null space only to eps lam_max / lam_1, which at the band's bottom is 2e-4 of a pair's elastic
  peak (bench.rigid_modes);
- the flexible modes up to --cover times the band's top: scipy eigsh, shift-invert on one SuperLU factor of K + M;
- the damping C = beta K is diagonal in the modes: mode k's denominator is lam_k a - w^2 with a = 1 + i w beta, so the
  computed modes are exact;
- the modes not computed (lam_k > lam_c) enter through their static residual and its first frequency corrections:
      sum_high phi phi^T G / (lam a - w^2) = sum_{j>=0} w^(2j) / a^(j+1) S_j,   S_j = sum_high phi phi^T G / lam^(j+1)
  and S_j = (K^+ M)^j K^+ Ge minus the computed modes' part, Ge = G - M R R^T G; K^+ is applied on the same factor
  by the fixed-point iteration x <- (K + M)^-1 (b + M x), which converges as 1 / (1 + lam_1). With `terms` = J the
  neglected tail is at most (w^2 / (lam_c |a|))^J / (1 - w^2 / lam_c) of the high modes' contribution, at the band's
  top (1 / cover^2)^J: 2.4e-4 for cover 4 and J = 3, of a contribution that is itself a small part of the response.
  The direct checks below measure what is left;
- the rigid part is exact under C R = 0: T = He Z^-1 Ge - H R R^T G / w^2.

check() validates against direct complex sparse solves (SuperLU of K (1 + i w beta) - w^2 M) at a few frequencies,
relative to each pair's elastic peak. --self-check compares the whole grid of the bench at 2,760 dofs with the
bench's per-point LU reference (direct_response) and exits non-zero above --tol (1e-6 of the peak).

    nice -n 10 .venv/bin/python benchmarks/peers/modal_reference.py --self-check [--refine 0.5] [--cover 4]
"""
import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np
import scipy.sparse.linalg as spla

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import bench  # noqa: E402

ref = bench.ref


def factor(A, dtype=float):
    """SuperLU of a symmetric sparse matrix with a symmetric ordering (a third of COLAMD's fill on the 3-D solid)."""
    return spla.splu(A.tocsc().astype(dtype), permc_spec="MMD_AT_PLUS_A", options=dict(SymmetricMode=True),
                     diag_pivot_thresh=0.0)


def flexible_modes(M, K, R, lu, top_hz, first):
    """The flexible eigenpairs (lam ascending, Phi M-orthonormal and M-orthogonal to R, the rigid-body and mechanism
    modes) up to top_hz: shift-invert Lanczos (eigsh) on lu = K + M, asking for `first` modes beyond R's, then twice
    as many until the highest is past top_hz."""
    op = spla.LinearOperator(K.shape, matvec=lu.solve, dtype=float)
    nr, k = R.shape[1], R.shape[1] + first
    while True:
        lam, Phi = spla.eigsh(K, k=min(k, K.shape[0] - 2), M=M, sigma=-1.0, which="LM", OPinv=op)
        order = np.argsort(lam)
        lam, Phi = lam[order], Phi[:, order]
        if lam[-1] > (2 * np.pi * top_hz) ** 2 or k >= K.shape[0] - 2:
            break
        k *= 2
    lam, Phi = lam[nr:], Phi[:, nr:]
    Phi -= R @ (R.T @ (M @ Phi))                         # the rigid modes exactly out (round-off)
    keep = lam <= (2 * np.pi * top_hz) ** 2
    return lam[keep], Phi[:, keep]


def pinv(M, R, lu, b, rtol=1e-14):
    """K^+ b for b in range(K) (R^T b = 0) on lu = K + M: x <- (K + M)^-1 (b + M x), kept M-orthogonal to R, which
    converges as 1 / (1 + lam_1)."""
    x = np.zeros_like(b)
    for _ in range(80):
        new = lu.solve(np.asarray(b + M @ x))
        new -= R @ (R.T @ (M @ new))
        change = np.abs(new - x).max() / max(np.abs(new).max(), 1e-300)
        x = new
        if change <= rtol:
            return x
    raise RuntimeError("K^+ by fixed-point iteration did not converge (change %.3g)" % change)


def full_order(scene, angle):
    """bench.full_order's M, K, G, H and R, the geometric rigid-body and mechanism modes in the same coordinates."""
    return bench.full_order(scene, angle)


class ModalReference:
    """T(w) = H (K (1 + i w beta) - w^2 M)^-1 G of the full order from its modes, static residual and rigid modes."""

    def __init__(self, M, K, G, H, R, beta, top_hz, terms=3):
        t0 = time.perf_counter()
        self.beta, self.top_hz = beta, top_hz
        lu = factor(K + M)
        lam, Phi = flexible_modes(M, K, R, lu, top_hz, first=30)
        Ge = G - M @ (R @ (R.T @ G))
        self.lam, self.hp, self.pg = lam, H @ Phi, Phi.T @ G
        self.S, x = [], Ge
        for j in range(terms):                          # S_j = H (K^+ M)^j K^+ Ge - sum H phi phi^T G / lam^(j+1)
            x = pinv(M, R, lu, x if j == 0 else M @ x)
            self.S.append(H @ x - (self.hp / lam ** (j + 1)) @ self.pg)
        self.rigid = H @ (R @ (R.T @ G))
        self.seconds = time.perf_counter() - t0
        self.maxrss_gb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6

    @property
    def flexible_hz(self):
        return np.sqrt(self.lam) / (2 * np.pi)

    def elastic(self, freqs):
        """He Z^-1 Ge at freqs (Hz): (nf, outputs, inputs)."""
        w = 2 * np.pi * np.asarray(freqs, float)
        a = 1 + 1j * w * self.beta
        inv = 1.0 / (self.lam[None] * a[:, None] - w[:, None] ** 2)
        T = np.einsum("tn,fn,na->fta", self.hp, inv, self.pg)
        for j, S in enumerate(self.S):
            T += (w ** (2 * j) / a ** (j + 1))[:, None, None] * S[None]
        return T

    def rigid_part(self, freqs):
        w = 2 * np.pi * np.asarray(freqs, float)
        return -self.rigid[None] / (w ** 2)[:, None, None]

    def check(self, M, K, Ge, He, freqs, peak):
        """[(f, max over pairs |T_direct - T_modal| / pair's peak)] by a complex SuperLU at each of freqs."""
        out = []
        for f in freqs:
            w = 2 * np.pi * f
            lu = factor(K * (1 + 1j * w * self.beta) - w ** 2 * M, complex)
            T = He @ lu.solve(np.asarray(Ge, complex))
            del lu
            out.append((float(f), float((np.abs(T - self.elastic([f])[0]) / peak).max())))
        return out


def pair_peak(T_el):
    """Each pair's elastic peak over the grid, floored as bench.elastic_error floors it."""
    peak = np.abs(T_el).max(axis=0)
    return np.maximum(peak, 1e-6 * peak.max())


def self_check(refine, angle, cover, terms, tol):
    with tempfile.TemporaryDirectory() as folder:
        subprocess.run([sys.executable, os.path.join(bench.ROOT, "meshes", "solid", "generate.py"), "--refine",
                        str(refine), "-o", folder], check=True, capture_output=True)
        scene = ref.load_scene(os.path.join(folder, "spacecraft.yaml"))
        band, zeta = scene.raw["band"], float(scene.raw["damping"])
        M, K, G, H, R = full_order(scene, angle)
    Ge, He = G - M @ (R @ (R.T @ G)), H - (H @ R) @ (R.T @ M)
    mr = ModalReference(M, K, G, H, R, 0.0, cover * band[1], terms)
    beta = 2 * zeta / np.sqrt(mr.lam[0])
    mr.beta = beta                                     # the modes and residuals do not depend on beta
    fr = mr.flexible_hz[mr.flexible_hz <= band[1]]
    freqs = bench.grid(band, fr, beta * 2 * np.pi * fr / 2)
    t0 = time.perf_counter()
    T_direct = bench.direct_response(M, K, beta, Ge, He, freqs)
    t_direct = time.perf_counter() - t0
    T_modal = mr.elastic(freqs)
    peak = pair_peak(T_direct)
    err = float((np.abs(T_direct - T_modal).max(axis=0) / peak).max())
    print("self-check, --refine %g at %g deg: %d dofs, %d flexible modes up to %.1f Hz (cover %g, %d residual terms), "
          "modal reference %.1f s, per-point LU reference %.1f s at %d points" %
          (refine, angle, M.shape[0], len(mr.lam), mr.flexible_hz[-1], cover, terms, mr.seconds, t_direct, len(freqs)))
    for J in range(terms + 1):
        short = ModalReference.__new__(ModalReference)
        short.__dict__.update(mr.__dict__, S=mr.S[:J])
        e = float((np.abs(T_direct - short.elastic(freqs)).max(axis=0) / peak).max())
        print("  %d residual terms: max over pairs and %d points of |T_LU - T_modal| / pair's elastic peak = %.2e"
              % (J, len(freqs), e))
    print("agreement %.2e of the peak (tolerance %.0e): %s" % (err, tol, "ok" if err <= tol else "FAILED"))
    return err <= tol


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--self-check", action="store_true", required=True,
                    help="compare with the bench's per-point LU reference on the whole grid")
    ap.add_argument("--refine", type=float, default=0.5)
    ap.add_argument("--angle", type=float, default=0.0)
    ap.add_argument("--cover", type=float, default=4.0, help="modes computed up to cover x the band's top")
    ap.add_argument("--terms", type=int, default=3, help="static residual terms (frequency corrections)")
    ap.add_argument("--tol", type=float, default=1e-6)
    args = ap.parse_args()
    sys.exit(0 if self_check(args.refine, args.angle, args.cover, args.terms, args.tol) else 1)


if __name__ == "__main__":
    main()
