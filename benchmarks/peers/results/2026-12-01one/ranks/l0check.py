"""The solid's L^0 reference two ways: bench.full_order (ties eliminated by a pivoted QR) and the tests' ref.assemble
(ties by an SVD null space), each solved dense in double and refined once with a long-double residual."""
import os, sys
import numpy as np
ROOT, D = sys.argv[1], sys.argv[2]
sys.path.insert(0, os.path.join(ROOT, "benchmarks", "peers")); sys.path.insert(0, os.path.join(ROOT, "python"))
sys.path.insert(0, os.path.join(ROOT, "tests", "python", "support"))
import bench, kryflex
import reference as ref

def L0(M, K, G, H, R):
    R = R @ np.linalg.inv(np.linalg.cholesky(R.T @ M @ R)).T
    Ge = G - M @ R @ (R.T @ G)
    A = K + M @ R @ R.T @ M
    x = np.linalg.solve(A, Ge)
    r = (Ge.astype(np.longdouble) - A.astype(np.longdouble) @ x.astype(np.longdouble)).astype(float)
    x1 = x + np.linalg.solve(A, r)
    out = []
    for y in (x, x1):
        y = y - R @ (R.T @ (M @ y))
        out.append(H @ y)
    return out, np.linalg.cond(A)

path = os.path.join(D, "solid_0.001.yaml")
s = ref.load_scene(path)
M, K, G, H, R = bench.full_order(s, 0.0)
(a0, a1), ca = L0(M.toarray(), K.toarray(), G, H, R)
Ms, Ks, Gs, Hs = ref.assemble(s, [0.0])
Rs = ref.geometric_rigid_modes(s, [0.0])
(b0, b1), cb = L0(Ms, Ks, Gs, Hs, Rs)
n = np.linalg.norm
print("cond(K + M R R^T M): bench %.2e, ref.assemble %.2e" % (ca, cb))
print("bench: refined vs not %.2e; ref.assemble: refined vs not %.2e; bench vs ref.assemble (refined) %.2e"
      % (n(a1 - a0) / n(a1), n(b1 - b0) / n(b1), n(a1 - b1) / n(b1)))
for t in ("0.01", "0.001", "0.0001"):
    for v in ("default", "nse"):
        m = kryflex.ReducedModel.load(os.path.join(D, "out", "solid_%s_%s_1" % (t, v), "reduced.h5"))
        L = m.at([0.0]).moments(1)[0]
        print("solid %s %s: L0 error against bench (plain, refined) %.2e %.2e, against ref.assemble (plain, refined) %.2e %.2e"
              % (t, v, n(L - a0) / n(a0), n(L - a1) / n(a1), n(L - b0) / n(b0), n(L - b1) / n(b1)))
