"""L^0 at 57k dofs against the full order, independent of kryflex: the bench's full order (modal_reference.full_order
= bench.full_order, as large.py), L^0 = H K^+ Ge with Ge = G - M R R^T G and K^+ by modal_reference.pinv (the
fixed-point iteration on the SuperLU factor of K + M, kept M-orthogonal to the geometric rigid modes R), refined once
with a long-double residual; against the reduced models kryflex reduce wrote (reduced.h5, moments(1) at 0 deg).
(A first version compared against the scene file as generated, whose outputs are in another order than the
written YAML's: 1.4 "error", a permutation; fixed by loading the file the models were reduced from.)"""
import os, sys, time
import numpy as np
ROOT, D = sys.argv[1], sys.argv[2]
sys.path.insert(0, os.path.join(ROOT, "benchmarks", "peers")); sys.path.insert(0, os.path.join(ROOT, "python"))
import kryflex
import modal_reference as mref
t0 = time.perf_counter()
scene = mref.bench.ref.load_scene(os.path.join(D, "solid57k_0.001.yaml"))   # the file the models were reduced from (its
# outputs in yaml.safe_dump's sorted order, as theirs)
M, K, G, H, R = mref.full_order(scene, 0.0)
Ge = G - M @ (R @ (R.T @ G))
lu = mref.factor(K + M)
x = mref.pinv(M, R, lu, Ge)
r = (Ge.astype(np.longdouble) - (K.astype(np.longdouble) @ x.astype(np.longdouble))).astype(float)
r -= M @ (R @ (R.T @ r))
x1 = x + mref.pinv(M, R, lu, r)
n = np.linalg.norm
L0, L1 = H @ x, H @ x1
print("57k: %d dofs; residual |Ge - K x| / |Ge| %.2e before, %.2e after one refinement; L0 refined vs not %.2e; %.1f s"
      % (K.shape[0], n(r) / n(Ge), n(Ge - K @ x1) / n(Ge), n(L1 - L0) / n(L1), time.perf_counter() - t0))
for name in sorted(os.listdir(os.path.join(D, "out"))):
    m = kryflex.ReducedModel.load(os.path.join(D, "out", name, "reduced.h5"))
    Lr = m.at([0.0]).moments(1)[0]
    print("%s: %s reduced dofs per body, L0 error against the full order %.2e (unrefined %.2e)" % (
        name, m.sizes, n(Lr - L1) / n(L1), n(Lr - L0) / n(L0)))
