"""How small a model of the same source could be without the body-wise form: the search's model (uncompressed),
reassembled at the bench's angle, its elastic response to every input (snapshots on the bench's grid, each input
weighted by 1 / its pairs' largest peak as kryflex's compression does) ordered by an SVD in the M norm of the
reassembled system, the rigid modes kept exactly; the fewest leading system directions meeting the target, measured
by bench.py's independent elastic error. A model truncated this way is valid at its angle only: it is what a
body-wise model whose bodies' directions were tied together (one coordinate for a direction in each body) would be
at that angle, and a measure of what the body-wise form costs.
    python systemlevel.py [--scene S] --targets 1e-2 1e-3 1e-4 [--static-exact] [--source-opts key=value ...]
"""
import sys, os, argparse, subprocess, tempfile
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
import numpy as np, scipy.linalg as sl
import bench as B
from compress import Compressor
import kryflex

ap = argparse.ArgumentParser()
ap.add_argument("--scene")
ap.add_argument("--refine", type=float, default=0.5)
ap.add_argument("--angle", type=float, default=0.0)
ap.add_argument("--targets", type=float, nargs="+", default=[1e-2, 1e-3, 1e-4])
ap.add_argument("--static-exact", action="store_true", help="keep the static response's columns exactly too")
args = ap.parse_args()
if args.scene:
    scene_path = os.path.abspath(args.scene)
else:
    folder = tempfile.mkdtemp()
    subprocess.run([sys.executable, os.path.join(B.ROOT, "meshes", "solid", "generate.py"), "--refine", str(args.refine),
                    "-o", folder], check=True, capture_output=True)
    scene_path = os.path.join(folder, "spacecraft.yaml")
scene = B.ref.load_scene(scene_path)
band, zeta = scene.raw["band"], float(scene.raw["damping"])
M, K, G, H, PhiR = B.full_order(scene, args.angle)
nrigid = PhiR.shape[1]
lam, Phi = B.modes(M, K, band[1], nrigid)
beta = 2 * zeta / np.sqrt(lam[nrigid])
f_res = np.sqrt(np.maximum(lam[nrigid:], 0)) / (2 * np.pi); f_res = f_res[f_res <= band[1]]
freqs = B.grid(band, f_res, beta * 2 * np.pi * f_res / 2)
Ge = G - M @ (PhiR @ (PhiR.T @ G)); He = H - (H @ PhiR) @ (PhiR.T @ M)
T_el = B.direct_response(M, K, beta, Ge, He, freqs)
w = 2 * np.pi * freqs
T_full = T_el - (H @ PhiR @ PhiR.T @ G)[None] / (w ** 2)[:, None, None]
peak = np.maximum(np.abs(T_el).max(axis=0), 1e-4 * np.abs(T_el).max())
inw = 1 / peak.max(axis=0)
print("scene %s at %g deg: %d dofs, %d band modes" % (scene_path, args.angle, M.shape[0], len(f_res)), flush=True)


def measure(Mr, Kr, Gr, Hr, P):
    P = P @ np.linalg.inv(np.linalg.cholesky(P.T @ Mr @ P)).T
    Q = sl.null_space(P.T @ Mr)
    lr, X = sl.eigh(Q.T @ Kr @ Q, Q.T @ Mr @ Q)
    X = Q @ X
    den = lr[None, :] * (1 + 1j * w[:, None] * beta) - (w ** 2)[:, None]
    Tr = np.einsum("tk,fk,ka->fta", Hr @ X, 1.0 / den, X.T @ Gr) - (Hr @ P @ P.T @ Gr)[None] / (w ** 2)[:, None, None]
    return B.elastic_error(T_full, Tr, T_el)


for target in args.targets:
    spec = B.kryflex_spec(scene_path, args.angle, beta, target)
    model = kryflex.Reducer(kryflex.scene_from_dict(spec), quiet=True, compress="0").reduce().model
    cp = Compressor(model, [args.angle], beta, freqs, measure)
    Ms, Ks, Gs, Hs, P = cp._system(cp.bodies, cp.angles[0])
    Ms = 0.5 * (Ms + Ms.T)
    e_src = measure(Ms, Ks, Gs, Hs, P)
    lam_r, X, Pn = cp._modes(Ms, Ks, P)                      # flexible modes of the reassembled model
    PG = X.T @ Gs
    keep = [Pn]
    if args.static_exact:
        keep.append(X @ (PG / lam_r[:, None]))
    snaps = []
    for f in w:
        y = X @ (PG / (lam_r * (1 + 1j * f * beta) - f * f)[:, None]) * inw[None, :]
        snaps += [y.real, y.imag]
    if not args.static_exact:
        snaps.append(X @ (PG / lam_r[:, None]) * inw[None, :])
    L = np.linalg.cholesky(Ms)
    Kp = np.hstack(keep)
    Z = L.T @ Kp
    Qk, _ = np.linalg.qr(Z)
    Qk = Qk[:, np.linalg.svd(Z, compute_uv=False) > 1e-8 * np.linalg.svd(Z, compute_uv=False)[0]] if Z.size else Qk
    S = L.T @ np.hstack(snaps)
    S -= Qk @ (Qk.T @ S)
    u, s, _ = np.linalg.svd(S, full_matrices=False)
    r = int((s > 1e-10 * s[0]).sum())
    found = None
    for k in range(1, r + 1):
        Wz = np.hstack([Qk, u[:, :k]])
        W = sl.solve_triangular(L.T, Wz, lower=False)
        Mr, Kr, Gr, Hr = W.T @ Ms @ W, W.T @ Ks @ W, W.T @ Gs, Hs @ W
        Pr = np.linalg.lstsq(W, Pn, rcond=None)[0]
        e = measure(Mr, Kr, Gr, Hr, Pr)
        if e <= target:
            found = (W.shape[1] - nrigid, e)
            break
    src_el = Ms.shape[0] - P.shape[1]
    print("target %g: source %s (%d elastic states, error %.2g); system-level truncation%s: %s" % (
        target, "+".join(str(v) for v in model.sizes), 2 * src_el, e_src, " (static kept)" if args.static_exact else "",
        "%d elastic states, error %.2g" % (2 * found[0], found[1]) if found else "not met"), flush=True)
