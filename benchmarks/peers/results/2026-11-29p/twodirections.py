"""The best body-wise model with k elastic directions in total (beyond each body's 6 rigid motions) on Galileo at one
angle, over every split of k between the bodies: each body's directions optimized (Nelder-Mead on log error, 12
starts: the compression's SVD directions, then random picks of them, perturbed) within the span of the search's
model's bodies, measured by bench.py's independent elastic error (compress.py's Compressor reassembles).
    python twodirections.py SCENE SOURCE_FACTOR TARGET K
SOURCE_FACTOR: the search run for TARGET x SOURCE_FACTOR (the search's model, uncompressed, is the span)."""
import sys, os, time, itertools
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
import numpy as np, scipy.linalg as sl, scipy.optimize as so
import bench as B
from compress import Compressor, mgs
import kryflex

scene_path = os.path.abspath(sys.argv[1]) if len(sys.argv) > 1 else os.path.abspath("meshes/galileo/galileo.yaml")
srcf = float(sys.argv[2]) if len(sys.argv) > 2 else 1.0
target = float(sys.argv[3]) if len(sys.argv) > 3 else 1e-3
angle = 0.0
scene = B.ref.load_scene(scene_path)
band, zeta = scene.raw["band"], float(scene.raw["damping"])
M, K, G, H, PhiR = B.full_order(scene, angle)
nrigid = PhiR.shape[1]
lam, Phi = B.modes(M, K, band[1], nrigid)
beta = 2 * zeta / np.sqrt(lam[nrigid])
f_res = np.sqrt(np.maximum(lam[nrigid:], 0)) / (2 * np.pi); f_res = f_res[f_res <= band[1]]
freqs = B.grid(band, f_res, beta * 2 * np.pi * f_res / 2)
Ge = G - M @ (PhiR @ (PhiR.T @ G)); He = H - (H @ PhiR) @ (PhiR.T @ M)
T_el = B.direct_response(M, K, beta, Ge, He, freqs)
w = 2 * np.pi * freqs
T_full = T_el - (H @ PhiR @ PhiR.T @ G)[None] / (w ** 2)[:, None, None]

def measure(Mr, Kr, Gr, Hr, P):
    P = P @ np.linalg.inv(np.linalg.cholesky(P.T @ Mr @ P)).T
    Q = sl.null_space(P.T @ Mr)
    lr, X = sl.eigh(Q.T @ Kr @ Q, Q.T @ Mr @ Q)
    X = Q @ X
    a_, b_ = Hr @ X, X.T @ Gr
    den = lr[None, :] * (1 + 1j * w[:, None] * beta) - (w ** 2)[:, None]
    Tr = np.einsum("tk,fk,ka->fta", a_, 1.0 / den, b_) - (Hr @ P @ P.T @ Gr)[None] / (w ** 2)[:, None, None]
    return B.elastic_error(T_full, Tr, T_el)

spec = B.kryflex_spec(scene_path, angle, beta, target * srcf)
model = kryflex.Reducer(kryflex.scene_from_dict(spec), quiet=True, compress="0").reduce().model
cp = Compressor(model, [angle], beta, freqs, measure)
print("source sizes", model.sizes, "error", cp.error(cp.bodies))
# per body: rigid span and its M-orthogonal complement (all directions of the body)
comp = []
for b in cp.bodies:
    Mb = 0.5 * (b["M"] + b["M"].T); L = np.linalg.cholesky(Mb)
    R = mgs(L, b["rigid"])
    Q = sl.null_space((Mb @ R).T)
    comp.append((R, Q))
print("complement dims", [Q.shape[1] for _, Q in comp])

def bodies_for(Ws):
    out = []
    for b, (R, Q), X in zip(cp.bodies, comp, Ws):
        W = np.hstack([R, Q @ X]) if X.shape[1] else R
        W = mgs(np.linalg.cholesky(0.5 * (b["M"] + b["M"].T)), W)
        rig = np.linalg.lstsq(W, b["rigid"], rcond=None)[0]
        out.append(dict(M=W.T @ b["M"] @ W, K=W.T @ b["K"] @ W, G=W.T @ b["G"], H=b["H"] @ W, iface=b["iface"] @ W, rigid=rig))
    return out

def err_of(x, split):
    Ws, o = [], 0
    for (R, Q), k in zip(comp, split):
        d = Q.shape[1]
        X = x[o:o + d * k].reshape(d, k) if k else np.zeros((d, 0)); o += d * k
        Ws.append(X)
    try:
        return cp.error(bodies_for(Ws))[0]
    except Exception:
        return 10.0

rng = np.random.default_rng(0)
inits = []
for b, (R, Q), (keep, D, _) in zip(cp.bodies, comp, cp.directions):
    Mb = 0.5 * (b["M"] + b["M"].T)
    C = np.hstack([keep[:, 6:], D])
    inits.append(Q.T @ Mb @ C)      # candidate columns in complement coordinates, static first
ktot = int(sys.argv[4]) if len(sys.argv) > 4 else 2
for split in [s for s in itertools.product(*[range(min(ktot, Q.shape[1]) + 1) for _, Q in comp]) if sum(s) == ktot]:
    n = sum(Q.shape[1] * k for (_, Q), k in zip(comp, split))
    best = (np.inf, None)
    t0 = time.time()
    for rs in range(12):
        parts = []
        for X0, k in zip(inits, split):
            if not k: continue
            cols = list(range(X0.shape[1]))
            pick = cols[:k] if rs == 0 else list(rng.choice(cols[:min(len(cols), k + 3)], size=k, replace=False))
            parts.append((X0[:, pick] + (0 if rs < 2 else 0.1) * rng.standard_normal((X0.shape[0], k))).ravel())
        x0 = np.concatenate(parts) if parts else np.zeros(0)
        r = so.minimize(lambda x: np.log(err_of(x, split)), x0, method="Nelder-Mead", options=dict(maxiter=600, xatol=1e-6, fatol=1e-6))
        if r.fun < best[0]:
            best = (r.fun, r.x)
    print("split", split, "best error %.3g" % np.exp(best[0]), "%.0f s" % (time.time() - t0), flush=True)
