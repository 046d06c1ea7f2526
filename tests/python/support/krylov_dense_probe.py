#!/usr/bin/python3
"""The Krylov basis of one configuration against a dense NumPy reference, on any number of ranks.

    mpiexec -n 2 /usr/bin/python3 tests/python/support/krylov_dense_probe.py SCENE OUT.json --input-blocks 8 --output-blocks 2

SCENE: a scene file, or bc:NAME for a model of tests/python/support/bc_models.py (bc:clamped: no rigid modes).

Every rank gathers the system's M, K, G, H^T, the rigid modes and kryflex's basis V (whole, in the same global row
order); rank 0 builds the reference with NumPy alone: the flexible inverse K+ = P pinv(K) P^T (P = I - Phi Phi^T M,
the M-orthogonal projector off the rigid modes), each chain (K+ G, K+ M K+ G, ... and K+ H^T, ...) by block Arnoldi
with full re-orthogonalization in the M inner product, the two chains' union M-orthonormalized. It writes to OUT.json:
the basis sizes, |V^T M V - I|, |Phi^T M V|, the sine of the largest principal angle between span(V) and the
reference's span, and the largest relative difference of the reduced model's eigenvalues (kryflex's projection,
KrylovBasis.project, against the reference's V_ref^T K V_ref). test_krylov_dense_reference.py runs it."""
import argparse
import json
import os
import sys

import numpy as np
import scipy.linalg as sla


sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))   # bc_models


def gathered(A, PETSc):
    """the whole matrix on every rank, as a dense NumPy array (global row order)"""
    m, n = A.getSize()
    rows = PETSc.IS().createStride(m, 0, 1, comm=PETSc.COMM_SELF)
    cols = PETSc.IS().createStride(n, 0, 1, comm=PETSc.COMM_SELF)
    S = A.createSubMatrices(rows, cols)[0]
    if S.getType() in ("seqdense",):
        return S.getDenseArray().copy()
    return S.convert("dense").getDenseArray().copy()


def m_orthonormalize(X, M, against, tol=1e-10):
    """the columns of X, in order, M-orthonormal and M-orthogonal to the columns of `against` and to those kept before
    them (Gram-Schmidt, each projection twice); a column that falls to tol of its M-norm is dropped"""
    Q = against
    for x in X.T:
        n0 = np.sqrt(x @ M @ x)
        for _ in range(2):
            x = x - Q @ (Q.T @ (M @ x))
        n = np.sqrt(x @ M @ x)
        if n > tol * n0:
            Q = np.column_stack([Q, x / n])
    return Q[:, against.shape[1]:]


def reference_basis(M, K, G, Ht, Phi, nin, nout):
    P = np.eye(len(M)) - Phi @ (Phi.T @ M)
    Kp = P @ np.linalg.pinv(K, hermitian=True) @ P.T
    chains = []
    for start, nblk in ((G, nin), (Ht, nout)):
        Q = np.zeros((len(M), 0))
        X = Kp @ start
        for _ in range(nblk):
            B = m_orthonormalize(X, M, np.hstack([Phi, Q]))
            if B.shape[1] == 0:
                break
            Q = np.hstack([Q, B])
            X = Kp @ (M @ B)
        chains.append(Q)
    return m_orthonormalize(np.hstack(chains), M, Phi)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene")
    ap.add_argument("out")
    ap.add_argument("--input-blocks", type=int, default=8)
    ap.add_argument("--output-blocks", type=int, default=2)
    args = ap.parse_args()

    import kryflex
    from kryflex import _core
    from petsc4py import PETSc
    PETSc.Options().setValue("kf_quiet", True)

    if args.scene.startswith("bc:"):
        import bc_models
        scene = kryflex.scene_from_dict(bc_models.CASES[args.scene[3:]]())
    else:
        scene = kryflex.load_scene(args.scene)
    system = _core.CSystem(scene.cscene)
    system.set_angles(scene.angles_rad(scene.configurations[0]))
    solver = _core.FlexSolver(system)
    basis, ndeflated = solver.krylov_basis(args.input_blocks, args.output_blocks)
    Mr, Kr, _, _ = basis.project()
    Ms, Ks, G, Ht = system.matrices()
    M, K, G, Ht = (gathered(A, PETSc) for A in (Ms, Ks, G, Ht))
    Phi = system.rigid_modes()[0]
    Phi = gathered(Phi, PETSc) if Phi.getSize()[1] else np.zeros((len(M), 0))
    V = gathered(basis.combine(np.eye(basis.size)), PETSc)
    if PETSc.COMM_WORLD.getRank() == 0:
        try:
            write_result(args, PETSc.COMM_WORLD.getSize(), basis, ndeflated, Mr, Kr, M, K, G, Ht, Phi, V)
        except Exception:   # the other ranks wait in MPI_Finalize: take them down with this one
            import traceback
            traceback.print_exc()
            PETSc.COMM_WORLD.abort(1)


def write_result(args, nranks, basis, ndeflated, Mr, Kr, M, K, G, Ht, Phi, V):
    """the reference and the comparison, written to args.out (rank 0)"""
    R = reference_basis(M, K, G, Ht, Phi, args.input_blocks, args.output_blocks)
    sines = np.sqrt(np.clip(1 - np.linalg.svd(V.T @ M @ R, compute_uv=False) ** 2, 0, None))
    lam = sla.eigh(Kr, Mr, eigvals_only=True)
    lam_ref = np.linalg.eigvalsh(R.T @ K @ R)
    result = {
        "ranks": nranks, "dofs": len(M), "size": basis.size, "reference_size": R.shape[1],
        "deflated": ndeflated,
        "orthonormality": float(np.abs(V.T @ M @ V - np.eye(V.shape[1])).max()),
        "rigid_content": float(np.abs(Phi.T @ M @ V).max()) if Phi.size else 0.0,
        "largest_sine": float(sines.max()) if len(lam) == len(lam_ref) else None,
        "eigenvalues_rel": float(np.max(np.abs(lam - lam_ref) / np.abs(lam_ref))) if len(lam) == len(lam_ref) else None,
    }
    with open(args.out, "w") as f:
        json.dump(result, f, indent=1)


if __name__ == "__main__":
    main()
