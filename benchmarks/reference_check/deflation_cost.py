#!/usr/bin/python3
"""What the reduction's Krylov deflations cost on lumped-mass models: the reduced model at a fixed number of moments
(-kf_search 0, every Krylov mode kept: -kf_keep_threshold 0) against an independent dense SciPy response (M's null
space condensed, every mode: tests/python/reducer/test_reference_truth.py's scipy_frf), beside the Galerkin
projection of the same model on the same Krylov space built here without any M-norm deflation (NumPy: blocks of
K+ G and K+ H^T alternating as the reduction's, each new block orthonormalized in the Euclidean inner product,
columns dropped only at 1e-10 of their length), so that a floor of the reduction that the undeflated space does not
have is what its deflated columns cost.

    PYTHONPATH=python .venv/bin/python benchmarks/reference_check/deflation_cost.py frame|small|large|aircraft 4,6,8,...

frame: bc_models.lumped_frame (90 dofs, every rotation massless); small, large, aircraft: the lumped plates and the
stick aircraft exported as DMIG punches and read back (tests/python/support/reference_truth_probe.py). Per number of
moments c: the reduction's deflations, reduced dofs, its own error (error_max, elastic response against its
reference) and its distance to SciPy (max over pairs of max |T - T_scipy| / the pair's peak), then the Galerkin
model's dimension and distance to SciPy on a grid of 4000 points over the band.
"""
import os
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tests", "python", "support"))
sys.path.insert(0, os.path.join(ROOT, "tests", "python", "reducer"))


def model(name):
    import bc_models
    import reference_truth_probe as probe
    spec = bc_models.lumped_frame() if name == "frame" else probe.plate_spec(name, tempfile.mkdtemp())
    body = next(iter(spec["bodies"].values()))
    _, _, G, H = bc_models.layout_reference(spec)
    return spec, np.asarray(body["mass"]), np.asarray(body["stiffness"]), G, H, 6 if name in ("frame", "aircraft") else 3


def galerkin(M, K, G, H, c, f, zeta, nrigid):
    """The model projected on the undeflated Krylov space of c blocks, every mode, against SciPy"""
    import bc_models
    from test_reference_truth import scipy_frf
    Phi = bc_models.rigid_null(K)
    Phi = Phi @ np.linalg.inv(np.linalg.cholesky(Phi.T @ M @ Phi)).T
    MP = M @ Phi
    Kreg = K + MP @ MP.T          # K+ on loads M-orthogonal... self-equilibrated: x = Kreg^-1 (b - M Phi Phi^T b)

    def kplus(B):
        return np.linalg.solve(Kreg, B - MP @ (Phi.T @ B))
    Q, nxt = np.linalg.qr(Phi)[0], [kplus(G), kplus(H.T)]
    for b in range(c):
        ch = b % 2
        X = nxt[ch]
        if not X.shape[1]:        # this chain's space is exhausted
            continue
        n0 = np.linalg.norm(X, axis=0).max()
        for _ in range(2):
            X = X - Q @ (Q.T @ X)
        U, s, _ = np.linalg.svd(X, full_matrices=False)
        U = U[:, s > 1e-10 * n0]
        Q = np.hstack([Q, U])
        nxt[ch] = kplus(M @ U)
    Kr, Mr = Q.T @ K @ Q, Q.T @ M @ Q
    T, _ = scipy_frf(0.5 * (Mr + Mr.T), 0.5 * (Kr + Kr.T), Q.T @ G, H @ Q, f, zeta, nrigid=nrigid)
    return Q.shape[1], T


def main():
    name, counts = sys.argv[1], [int(x) for x in sys.argv[2].split(",")]
    import kryflex
    kryflex.init(sys.argv[:1] + sys.argv[3:])
    from test_reference_truth import pair_distance, scipy_frf
    spec, M, K, G, H, nrigid = model(name)
    spec["accuracy"] = 1e-9
    f = np.linspace(*spec["band"], 4000)
    exact, _ = scipy_frf(M, K, G, H, f, spec["damping"], nrigid=nrigid)
    for c in counts:
        r = kryflex.Reducer(kryflex.scene_from_dict(spec), quiet=True, search=False, moments=c, keep_threshold=0.0)
        reduced = r.reduce().model.at([])
        T = np.asarray(reduced.frf(f)).reshape(exact.shape)
        dim, Tg = galerkin(M, K, G, H, c, f, spec["damping"], nrigid)
        print("%s c=%2d: reduction: %d deflated, %d dofs, error_max %.3e, vs SciPy %.3e | undeflated Galerkin: %d dofs, "
              "vs SciPy %.3e" % (name, c, int(np.ravel(r.result(0, "krylov_deflations"))[0]), reduced.M.shape[0],
                                 float(np.ravel(r.result(-1, "error_max"))[0]), pair_distance(T, exact), dim,
                                 pair_distance(Tg, exact)), flush=True)


if __name__ == "__main__":
    main()
