"""The coordinate ties of a model of shared directions (-kf_shared_directions, docs/guide/reassembly.md) in the export's
coordinates, and their split into rows a multibody code can hold.

The model stores rows D with D phi = 0 on the stacked reduced body coordinates phi = (phi_1, ..., phi_nb), and
D [R C] = 0 with R the bodies' rigid motions. A floating-frame body's coordinates are phi_b = R_b r_b + F_b q_b
(bodies.py: [R_b F_b] square, invertible), so

    D phi = sum_b D_b R_b r_b + sum_b D_b F_b q_b,     and D_b R_b = 0:    sum_b (D_b F_b) q_b = 0

the ties bind the flexible coordinates alone: T = [D_1 F_1 ... D_nb F_nb], the same constraint set as D, linear in
the exported coordinates at any frame motion. A body without a floating frame exports its reduced coordinates phi_b
themselves (T_b = D_b).

    T = export_ties(D, bodies)                 # on the stacked exported coordinates (coordinates(body) per body)
    groups, rest = split_ties(T, sizes)        # [(bodies, rows)]: rows on one or two bodies; rest: rows on more
"""
import numpy as np

from .bodies import ExportError

# |D_b R_b| relative to |R_b| above which a tie reaches the rigid motions (D is orthonormal; measured ~1e-16)
RIGID_TIE_TOL = 1e-8
# singular values below this fraction of the largest are rank-deficient when the ties are split
SPLIT_RTOL = 1e-10


def coordinates(body):
    """The body's exported coordinates: its flexible ones when it floats, else its reduced ones."""
    return body.nflex if body.floating else body.M.shape[0]


def export_ties(D, bodies, scene=""):
    """T (h x sum coordinates(b)) from the model's ties D (h x sum v_b); ExportError naming the tie and the body when
    a tie moves a floating body's rigid motions (then it cannot act on the flexible coordinates alone)."""
    D = np.asarray(D, dtype=float)
    sizes = [b.M.shape[0] for b in bodies]
    if D.ndim != 2 or D.shape[1] != sum(sizes):
        raise ExportError("model of scene '%s': its coordinate ties have %s columns, its bodies %d coordinates: the "
                          "model file is inconsistent; reduce again" % (scene, D.shape[1:] or "no", sum(sizes)))
    off = np.concatenate([[0], np.cumsum(sizes)])
    parts = []
    for b, body in enumerate(bodies):
        Db = D[:, off[b]:off[b + 1]]
        if not body.floating:
            parts.append(Db)
            continue
        R = body.rigid_coords
        E = np.abs(Db @ R) / np.maximum(np.linalg.norm(R, axis=0), 1e-300)
        if E.size and E.max() > RIGID_TIE_TOL:
            i, j = np.unravel_index(np.argmax(E), E.shape)
            raise ExportError("model of scene '%s': coordinate tie %d moves the rigid motion %s of body '%s' "
                              "(|D_b R_b| / |R_b| = %.2g > %.0e): the floating-frame bodies cannot carry it; reduce again with "
                              "-kf_shared_directions false (scene key reduction.shared_directions: false) to export "
                              "the model" % (scene, i, ("ux", "uy", "uz", "rx", "ry", "rz")[j], body.name, E[i, j],
                                             RIGID_TIE_TOL))
        parts.append(Db @ body.modes)
    return np.hstack(parts) if parts else np.zeros((D.shape[0], 0))


def _rows_on(S, cols):
    """An orthonormal basis (rows) of the rows of span(S) that vanish outside the columns cols."""
    from scipy.linalg import null_space
    out = np.ones(S.shape[1], dtype=bool)
    out[cols] = False
    if not out.any():
        return S
    Y = null_space(S[:, out].T, rcond=SPLIT_RTOL)     # y with y^T S zero outside cols
    W = Y.T @ S
    W[:, out] = 0.0
    return W


def split_ties(T, sizes):
    """The ties T (on the stacked coordinates, sizes per body) as rows on one or two bodies where they can be: a list
    of (bodies tuple, rows on the stacked coordinates), spanning with rest the same row space as T; rest (rows on three
    or more bodies, or None): what a chain of pair connectors cannot hold."""
    T = np.asarray(T, dtype=float)
    if not T.size:
        return [], None
    U, s, Vt = np.linalg.svd(T, full_matrices=False)
    S = Vt[s > SPLIT_RTOL * s.max()]           # the ties' row space, orthonormal
    off = np.concatenate([[0], np.cumsum(sizes)])
    cols = [np.arange(off[b], off[b + 1]) for b in range(len(sizes))]
    live = [b for b in range(len(sizes)) if sizes[b] and np.abs(S[:, cols[b]]).max() > 0]
    groups, Q = [], np.zeros((0, T.shape[1]))
    sets = [(b,) for b in live] + [(a, b) for i, a in enumerate(live) for b in live[i + 1:]]
    for bodies in sets:
        if Q.shape[0] == S.shape[0]:
            break
        W = _rows_on(S, np.concatenate([cols[b] for b in bodies]))
        if not W.shape[0]:
            continue
        # the combinations of W independent of the rows already taken (they keep W's support)
        Res = W - (W @ Q.T) @ Q
        Ur, sr, _ = np.linalg.svd(Res, full_matrices=False)
        k = int(np.sum(sr > 1e3 * SPLIT_RTOL))
        if not k:
            continue
        rows = Ur[:, :k].T @ W
        groups.append((bodies, rows))
        Qn, _ = np.linalg.qr(np.vstack([Q, rows]).T)
        Q = Qn.T[:Q.shape[0] + k]
    rest = None
    if Q.shape[0] < S.shape[0]:
        Res = S - (S @ Q.T) @ Q
        Ur, sr, _ = np.linalg.svd(Res, full_matrices=False)
        rest = Ur[:, :S.shape[0] - Q.shape[0]].T @ S
    return groups, rest
