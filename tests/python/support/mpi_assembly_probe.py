#!/usr/bin/python3
"""Basis-independent quantities of kryflex's assembled system, on any number of ranks (a helper of test_assembly.py).

    mpiexec -n 2 /usr/bin/python3 tests/python/support/mpi_assembly_probe.py SCENE OUT.json

assembles SCENE at each of its configurations with kryflex._core.CSystem, gathers M_S, K_S, G_S and H_S to rank 0
and writes there, per configuration: the system size, the generalized eigenvalues of (K_S, M_S) and the undamped
transfer function H_S (K_S - w^2 M_S)^-1 G_S at frequencies between resonances.  A different number of ranks may
eliminate different dofs, so M_S and K_S themselves may differ by a change of basis; these quantities may not.

The numerics below are shared with test_assembly.py, so serial and parallel systems, and kryflex and the NumPy
reference (reference.py), are all measured the same way:

- accurate_eigenvalues: a plain dense generalized eigensolver (LAPACK via scipy.linalg.eigh) has absolute errors
  ~ eps * lambda_max, which for the Galileo model (lambda_1 / lambda_max ~ 3e-9) is a relative error ~ 4e-8 on its
  first flexible eigenvalue, far above the 1e-10 at which two correct assemblies agree.  Shift-and-invert with a
  shift at the first flexible eigenvalue puts the low eigenvalues at the top of the spectrum of (M, K + sigma M),
  where the same solver has relative errors ~ eps; each eigenvalue is taken from whichever problem resolves it
  better (crossover at sqrt(sigma lambda_max)).  test_assembly.py checks this against 40-digit eigenvalues.
- transfer_condition: the M-norm condition number of K - w^2 M, max|lambda_i - w^2| / min|lambda_i - w^2|: two
  assemblies that each carry round-off ~ eps ||K|| (e.g. K_S Phi_rigid ~ eps ||K||, not 0) can differ in the
  transfer function by up to ~ eps times this, whoever assembled them.
"""
import json
import os
import sys

import numpy as np
import scipy.linalg as sl

ZERO_RTOL = 1e-12        # |lambda| <= ZERO_RTOL * lambda_max: a rigid-body or mechanism mode


# ------------------------------------------------------------------ shared numerics (dense, rank 0)

def accurate_eigenvalues(K, M, zero_rtol=ZERO_RTOL):
    """Generalized eigenvalues of (K, M), ascending, each with a small relative error (see the module docstring)."""
    lam = sl.eigh(K, M, eigvals_only=True)
    top = np.abs(lam).max()
    nzero = int(np.sum(np.abs(lam) <= zero_rtol * top))
    if nzero == len(lam):
        return lam
    sigma = lam[nzero]                                     # the first flexible eigenvalue, roughly: only a shift
    nu = sl.eigh(M, K + sigma * M, eigvals_only=True)[::-1]   # nu = 1 / (lambda + sigma), descending
    low = 1.0 / nu - sigma
    return np.where(lam < np.sqrt(sigma * top), low, lam)


def zero_split(lam, zero_rtol=ZERO_RTOL):
    """(number of zero eigenvalues, largest |zero| / lambda_max, smallest flexible / lambda_max)."""
    top = np.abs(lam).max()
    rel = np.abs(lam) / top
    zero = rel <= zero_rtol
    return int(zero.sum()), float(rel[zero].max()) if zero.any() else 0.0, float(rel[~zero].min())


def between_resonances(lam, nzero, count=8):
    """Frequencies (rad/s) half-way, geometrically, between consecutive flexible eigenfrequencies: up to `count`,
    spread over the whole spectrum (lowest gaps first)."""
    w = np.sqrt(np.asarray(lam[nzero:], float))
    mids = np.sqrt(w[:-1] * w[1:])
    if len(mids) <= count:
        return mids
    pick = np.unique(np.round(np.geomspace(1, len(mids), count)).astype(int) - 1)
    return mids[pick]


def transfer(M, K, G, H, omegas):
    """Undamped H (K - w^2 M)^-1 G at each w: (nw, t, a)."""
    return np.array([H @ np.linalg.solve(K - w * w * M, G) for w in omegas])


def transfer_condition(lam, w):
    """M-norm condition number of K - w^2 M (rigid modes included as lambda = 0)."""
    d = np.abs(np.where(np.abs(lam) <= ZERO_RTOL * np.abs(lam).max(), 0.0, lam) - w * w)
    return float(d.max() / d.min())


def relative_difference(A, B):
    """||A - B|| / ||B|| per leading index (Frobenius over the rest)."""
    A, B = np.asarray(A), np.asarray(B)
    axes = tuple(range(1, A.ndim))
    return np.sqrt((np.abs(A - B) ** 2).sum(axis=axes)) / np.sqrt((np.abs(B) ** 2).sum(axis=axes))


# ------------------------------------------------------------------ kryflex's distributed system on rank 0

def gather_rows(A):
    """A distributed petsc4py Mat (AIJ or dense) as a NumPy array on rank 0 (None on other ranks)."""
    from petsc4py import PETSc
    D = A if A.getType() in ("seqdense", "mpidense") else A.convert("dense", PETSc.Mat())   # a copy, not in place
    local = np.array(D.getDenseArray(), copy=True)
    comm = A.getComm()
    if comm.getSize() == 1:
        return local
    parts = comm.tompi4py().gather(local, root=0)
    return np.vstack(parts) if comm.getRank() == 0 else None


def system_arrays(csystem):
    """(M_S, K_S, G_S, H_S) of a kryflex._core.CSystem as dense arrays on rank 0 (None elsewhere)."""
    Ms, Ks, G, Ht = (gather_rows(A) for A in csystem.matrices())
    if Ms is None:
        return None
    return Ms, Ks, G, Ht.T.copy()


def quantities(M, K, G, H, omegas=None):
    """The basis-independent description of one assembled system."""
    lam = accurate_eigenvalues(K, M)
    nzero = zero_split(lam)[0]
    if omegas is None:
        omegas = between_resonances(lam, nzero)
    return dict(size=int(K.shape[0]), eigenvalues=lam.tolist(), zero_modes=nzero,
                omegas=[float(w) for w in omegas], transfer=transfer(M, K, G, H, omegas).tolist())


def main(argv):
    if len(argv) != 3:
        print("usage: mpi_assembly_probe.py SCENE OUT.json", file=sys.stderr)
        return 2
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))),
                                    "python"))
    import kryflex
    from kryflex import _core
    from petsc4py import PETSc

    scene = kryflex.load_scene(argv[1])
    system = _core.CSystem(scene.cscene)
    configs = []
    for config in scene.configurations:
        system.set_angles(scene.angles_rad(config))
        arrays = system_arrays(system)
        if arrays is not None:
            configs.append(dict(angles_deg=list(config), **quantities(*arrays)))
    comm = PETSc.COMM_WORLD
    if comm.getRank() == 0:
        with open(argv[2], "w") as f:
            json.dump(dict(ranks=comm.getSize(), configurations=configs), f)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
