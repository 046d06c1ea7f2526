"""Directions shared between bodies, emulated: how small a model whose elastic coordinates each have a part in every
body (a tie q_b1,k = q_b2,k beside the joint ties) could be, at every angle of interest and midpoint of a scene.
The search's model (uncompressed) is reassembled at every point; its elastic response to every input there, in the
stacked body coordinates (q = N(theta) y: both bodies at once), each input weighted by 1 / its pairs' largest peak, is
ordered by an SVD in the blockdiag(M_b) norm, each body's rigid motions kept. The model with the first k directions
is, at each point, the reassembled model restricted to range(N(theta)) and range(T), T = [each body's rigid motions,
the k stacked directions]: the joint ties and the shared coordinates together. Measured by bench.py's independent
elastic error at every point (angles.py's references). Not a kryflex model: a measure of what one would gain.
    python tied.py --scene meshes/galileo/galileo.yaml [--single 0] --targets 1e-2 1e-3 1e-4
    python tied.py --large DIR --targets 1e-3      # large.py's scene and modal reference (after large.py reference DIR)
"""
import sys, os, argparse
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
import numpy as np, scipy.linalg as sl
import bench as B
from compress import reassemble

ap = argparse.ArgumentParser()
ap.add_argument("--scene")
ap.add_argument("--large", help="a large.py folder: its scene at 0 deg and its reference.npz")
ap.add_argument("--single", type=float, help="one angle only (the scene's angles otherwise, with their midpoints)")
ap.add_argument("--targets", type=float, nargs="+", default=[1e-2, 1e-3, 1e-4])
args = ap.parse_args()
if args.large:
    args.scene, args.single = os.path.join(args.large, "scene", "spacecraft.yaml"), 0.0
path = os.path.abspath(args.scene)
scene = B.ref.load_scene(path)
angles = [args.single] if args.single is not None else [float(a) for a in scene.raw["angles"]]
points = sorted(set(angles) | {0.5 * (a + b) for a, b in zip(angles, angles[1:])})
band, zeta = scene.raw["band"], float(scene.raw["damping"])
full = {}
for a in ([] if args.large else points):
    M, K, G, H, R = B.full_order(scene, a)
    lam, _ = B.modes(M, K, band[1], R.shape[1])
    full[a] = (M, K, G, H, R, lam)
ref_at = {}
if args.large:
    with np.load(os.path.join(args.large, "reference.npz")) as z:
        beta, w = float(z["beta"]), 2 * np.pi * z["freqs"]
        ref_at[0.0] = (w, z["T_el"], z["T_el"] + z["T_rigid"])
else:
    _, _, _, _, R0, lam0 = full[angles[0]]
    beta = 2 * zeta / np.sqrt(lam0[R0.shape[1]])
for a in ([] if args.large else points):
    M, K, G, H, R, lam = full[a]
    f_res = np.sqrt(np.maximum(lam[R.shape[1]:], 0)) / (2 * np.pi)
    f_res = f_res[f_res <= band[1]]
    freqs = B.grid(band, f_res, beta * 2 * np.pi * f_res / 2)
    Ge, He = G - M @ (R @ (R.T @ G)), H - (H @ R) @ (R.T @ M)
    T_el = B.direct_response(M, K, beta, Ge, He, freqs)
    w = 2 * np.pi * freqs
    ref_at[a] = (w, T_el, T_el - (H @ R @ R.T @ G)[None] / (w ** 2)[:, None, None])
print("tied directions, %s at %s and midpoints" % (args.scene, angles), flush=True)


def measure(a, Mr, Kr, Gr, Hr, P):
    w, T_el, T_full = ref_at[a]
    P = P @ np.linalg.inv(np.linalg.cholesky(P.T @ Mr @ P)).T
    Q = sl.null_space(P.T @ Mr)
    lr, X = sl.eigh(Q.T @ Kr @ Q, Q.T @ Mr @ Q)
    X = Q @ X
    den = lr[None, :] * (1 + 1j * w[:, None] * beta) - (w ** 2)[:, None]
    Tr = np.einsum("tk,fk,ka->fta", Hr @ X, 1.0 / den, X.T @ Gr) - (Hr @ P @ P.T @ Gr)[None] / (w ** 2)[:, None, None]
    return B.elastic_error(T_full, Tr, T_el)


def system(bodies, joints, a, H=None):
    bs = [dict(M=b["M"], K=b["K"], G=b["G"], H=b["H"] if H is None else H[i], iface=b["iface"], rigid=b["rigid"])
          for i, b in enumerate(bodies)]
    Ms, Ks, Gs, Hs, rank, ratio, P = reassemble(bs, joints, [np.radians(a)], bs[0]["G"].shape[1], bs[0]["H"].shape[0] if H is None else H[0].shape[0])
    return 0.5 * (Ms + Ms.T), Ks, Gs, Hs, P


for target in args.targets:
    import kryflex
    spec = B.kryflex_spec(path, angles[0], beta, target)
    spec["angles"] = list(angles)
    model = kryflex.Reducer(kryflex.scene_from_dict(spec), quiet=True, compress="0").reduce().model
    bodies = [dict(b) for b in model.bodies]
    joints = [model.joint(j) for j in range(len(model.joints))]
    v = [b["M"].shape[0] for b in bodies]
    off = np.concatenate([[0], np.cumsum(v)])
    ident = [np.eye(off[-1])[:, off[i]:off[i + 1]] for i in range(len(v))]
    Mblk = sl.block_diag(*[0.5 * (b["M"] + b["M"].T) for b in bodies])
    Rblk = sl.block_diag(*[b["rigid"] for b in bodies])
    at, snaps, e_src = {}, [], 0.0
    for a in points:
        Ms, Ks, Gs, Hs, P = system(bodies, joints, a)
        N = system(bodies, joints, a, H=ident)[3]
        at[a] = (Ms, Ks, Gs, Hs, P, N)
        e_src = max(e_src, measure(a, Ms, Ks, Gs, Hs, P))
        w, T_el, _ = ref_at[a]
        inw = 1 / np.maximum(np.abs(T_el).max(axis=0), 1e-4 * np.abs(T_el).max()).max(axis=0)
        Pm = P @ np.linalg.inv(np.linalg.cholesky(P.T @ Ms @ P)).T
        Q = sl.null_space(Pm.T @ Ms)
        lr, X = sl.eigh(Q.T @ Ks @ Q, Q.T @ Ms @ Q)
        X = Q @ X
        PG = X.T @ Gs
        for f in list(w) + [0.0]:
            y = X @ (PG / (lr * (1 + 1j * f * beta) - f * f)[:, None]) * inw[None, :]
            q = N @ y
            snaps += [q.real, q.imag] if f else [q.real]
    L = np.linalg.cholesky(Mblk)
    Qr, _ = np.linalg.qr(L.T @ Rblk)
    S = L.T @ np.hstack(snaps)
    S -= Qr @ (Qr.T @ S)
    u, s, _ = np.linalg.svd(S, full_matrices=False)
    r = int((s > 1e-10 * s[0]).sum())
    found = None
    for k in range(1, r + 1):
        T = np.hstack([Rblk, sl.solve_triangular(L.T, u[:, :k], lower=False)])
        Tp = T @ np.linalg.pinv(T)
        worst, el = 0.0, []
        for a in points:
            Ms, Ks, Gs, Hs, P, N = at[a]
            Y = sl.null_space((np.eye(N.shape[0]) - Tp) @ N, rcond=1e-9)
            Mr, Kr, Gr, Hr = Y.T @ Ms @ Y, Y.T @ Ks @ Y, Y.T @ Gs, Hs @ Y
            Pr = np.linalg.lstsq(Y, P, rcond=None)[0]
            worst = max(worst, measure(a, Mr, Kr, Gr, Hr, Pr))
            el.append(Y.shape[1] - P.shape[1])
        if worst <= target:
            found = (min(el), max(el), worst)
            break
    print("target %g: source %s (error %.2g over the points); tied directions: %s" % (
        target, "+".join(map(str, model.sizes)), e_src,
        "%d..%d elastic states over %d points, worst error %.2g" % (2 * found[0], 2 * found[1], len(points), found[2])
        if found else "not met"), flush=True)
