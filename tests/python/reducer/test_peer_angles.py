"""The several-angle peer of benchmarks/peers/peer_angles.py measures what it says: its reduced models, formed from
products taken once on all the directions (submatrices for a subset, the rigid modes projected out by formula, the
ties of another angle imposed through their null space), against the same Galerkin models formed directly and
densely in NumPy, on Galileo (28 dofs) at the angle the basis is made at and at another.

The basis is NumPy's (second-order Galerkin interpolation vectors at 5 Hz and the first 3 flexible modes), not pyMOR's: the
module's pyMOR parts (the one-angle reductors, its pod) are pyMOR's own, and pyMOR is not in the project's venv.
"""
import os
import sys

import numpy as np
import scipy.linalg as sl

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "support"))
import run_env  # noqa: E402
sys.path.insert(0, os.path.join(run_env.ROOT, "benchmarks", "peers"))
import bench  # noqa: E402
import peer_angles as pa  # noqa: E402
import reference as ref  # noqa: E402

GALILEO = os.path.join(run_env.ROOT, "meshes", "galileo", "galileo.yaml")
SOURCE, OTHER = 15.0, 22.5
RTOL = 1e-9

_cache = {}


def setup():
    """Galileo at the two angles: the full tuples and references as peer_angles.py takes them, the basis from the
    source angle, the ties; the grid thinned to every 4th point (the check is of the algebra, not the grid)."""
    if not _cache:
        scene = ref.load_scene(GALILEO)
        full, refs = {}, {}
        for a in (SOURCE, OTHER):
            M, K, G, H, R, beta, freqs, Ge, He = bench.elastic_setup(scene, a)
            if a == SOURCE:
                b0 = beta
            freqs = freqs[::4]
            full[a] = (M, K, G, H, R, None)
            refs[a] = (freqs, bench.direct_response(M, K, b0, Ge, He, freqs), None, Ge, He)
        M, K, _, _, R, _ = full[SOURCE]
        Ge = refs[SOURCE][3]
        X = []
        for f in (5.0,):
            w = 2 * np.pi * f
            Y = np.linalg.solve((K * (1 + 1j * w * b0) - w ** 2 * M).toarray(), Ge)
            X += [Y.real, Y.imag]
        lam, modes = sl.eigh(K.toarray(), M.toarray())
        X.append(modes[:, R.shape[1]:R.shape[1] + 3])      # and the first 3 flexible modes: errors below 1
        Phi = np.linalg.qr(np.hstack(X))[0]
        _cache.update(scene=scene, full=full, refs=refs, beta=b0, Phi=Phi,
                      ties={a: bench.ties(scene, a) for a in (SOURCE, OTHER)})
    return _cache


def dense_error(full_a, ref_a, beta, Phi):
    """The Galerkin model on span(Phi) made M-orthogonal to the rigid modes, formed and solved densely."""
    M, K, _, _, R, _ = full_a
    freqs, T_el, _, Ge, He = ref_a
    M, K = M.toarray(), K.toarray()
    V = Phi - R @ (R.T @ (M @ Phi))
    U, s, _ = np.linalg.svd(V, full_matrices=False)
    Q = U[:, s > 1e-6 * s[0]]
    T = np.array([(He @ Q) @ np.linalg.solve(Q.T @ (K * (1 + 2j * np.pi * f * beta) - (2 * np.pi * f) ** 2 * M) @ Q,
                                             Q.T @ Ge) for f in freqs])
    return bench.elastic_error(T_el, T, T_el), Q.shape[1]


def test_the_assembled_dofs_peer_is_the_dense_galerkin_model():
    c = setup()
    Phi, errs = c["Phi"], {}
    for a in (SOURCE, OTHER):
        blocks = pa.reduced_blocks(c["full"][a], c["refs"][a], Phi)
        for n in (3, Phi.shape[1]):
            err, rank = pa.measure(blocks, c["refs"][a], c["beta"], list(range(n)))
            want, want_rank = dense_error(c["full"][a], c["refs"][a], c["beta"], Phi[:, :n])
            assert rank == want_rank
            assert abs(err - want) <= RTOL * want, (a, n, err, want)
            errs[(a, n)] = err
    # Not two zero responses compared (whose error is 1 exactly): at the source angle the models resolve the band;
    # at the other, the source angle's basis misses its resonances (what the bench measures) but is not zero there.
    zero = bench.elastic_error(c["refs"][OTHER][1], 0 * c["refs"][OTHER][1], c["refs"][OTHER][1])
    assert max(errs[(SOURCE, n)] for n in (3, Phi.shape[1])) < 1e-2, errs
    assert min(abs(errs[(OTHER, n)] - zero) for n in (3, Phi.shape[1])) > 1e-5, errs


def test_the_tied_peer_is_the_dense_galerkin_model_on_the_tied_subspace():
    """The basis in the bodies' dofs (x = T y at the source angle): at the source angle its ties hold and it is the
    assembled peer; at the other angle the model is on {W q : C W q = 0}, formed here by SciPy's null_space."""
    c = setup()
    _, T, _ = c["ties"][SOURCE]
    W = T @ c["Phi"]
    scene = c["scene"]
    import scipy.sparse as sp
    Mb = sp.block_diag([b.M for b in scene.bodies]).tocsc()
    Kb = sp.block_diag([b.K for b in scene.bodies]).tocsc()
    Gx, Hx = ref.body_io(scene)
    tied = pa.Tied(W, Mb, Kb, Gx, Hx, c["full"], c["ties"], (SOURCE, OTHER))
    sel = list(range(W.shape[1]))
    at_source = tied.worst(c["refs"], c["beta"], sel, [SOURCE])
    assembled = pa.measure(pa.reduced_blocks(c["full"][SOURCE], c["refs"][SOURCE], c["Phi"]), c["refs"][SOURCE],
                           c["beta"], sel)
    assert at_source[1] == assembled[1] == W.shape[1]
    assert abs(at_source[0] - assembled[0]) <= RTOL * assembled[0]
    C, _, kept = c["ties"][OTHER]
    Z = sl.null_space(C @ W)
    assert Z.shape[1] < W.shape[1]        # the other angle's ties cut the source angle's vectors
    want, want_rank = dense_error(c["full"][OTHER], c["refs"][OTHER], c["beta"], (W @ Z)[kept])
    err, rank, _ = tied.worst(c["refs"], c["beta"], sel, [OTHER])
    assert rank == want_rank
    assert abs(err - want) <= RTOL * want, (err, want)
