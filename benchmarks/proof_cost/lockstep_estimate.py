"""What stepping the verification's eigensolves in lock-step would save on their block solves, before building it.

The body-wise flexible solve reads each body's factor once per block solve, whatever the configuration (the bodies'
factors are the same at every angle). The 7 configurations of the 57k solid each take 9 block solves of 8 columns;
stepped together, each step would be one solve of 7 x 8 = 56 columns per body instead of 7 of 8. This times exactly
that with MUMPS on the solid's body matrices: K_b + 1e-2 M_b (regular, the fill of the body's interior factor),
Cholesky (LDL^T) as kryflex factors, one BLAS thread, c solves of 8 random columns against one of 8c, both bodies,
alternating, process CPU seconds (the machine is shared: CPU is less sensitive to the load than wall).

    .venv/bin/python benchmarks/proof_cost/lockstep_estimate.py DIR   (DIR: meshes/solid/generate.py --refine 1.55 -o DIR)
"""
import sys
import time

import numpy as np
import petsc4py

petsc4py.init(sys.argv[:1])
from petsc4py import PETSc  # noqa: E402


def factor(path):
    """MUMPS Cholesky of K + 1e-2 M of one body (the objects kept alive with the factor)."""
    K = PETSc.Mat().load(PETSc.Viewer().createBinary(path + "_K.petsc", "r"))
    M = PETSc.Mat().load(PETSc.Viewer().createBinary(path + "_M.petsc", "r"))
    A = K.copy()
    A.axpy(1e-2, M)
    A.setOption(PETSc.Mat.Option.SPD, True)
    ksp = PETSc.KSP().create(PETSc.COMM_SELF)
    ksp.setOperators(A)
    ksp.setType("preonly")
    pc = ksp.getPC()
    pc.setType("cholesky")
    pc.setFactorSolverType("mumps")
    ksp.setUp()
    return A.getSize()[0], pc.getFactorMatrix(), (ksp, A)


def solve(F, n, p, rng):
    """CPU seconds of one MUMPS solve of p random columns."""
    B = PETSc.Mat().createDense([n, p], array=rng.standard_normal((n, p)), comm=PETSc.COMM_SELF)
    X = PETSc.Mat().createDense([n, p], comm=PETSc.COMM_SELF)
    X.setUp()
    c0 = time.process_time()
    F.matSolve(B, X)
    return time.process_time() - c0


def main():
    d = sys.argv[1].rstrip("/") + "/"
    rng = np.random.default_rng(0)
    bodies = [factor(d + b) for b in ("bus", "rotor")]
    for n, F, _ in bodies:
        solve(F, n, 8, rng)
    print("both bodies per configuration step (bus + rotor), CPU s; best of 5 alternating repeats")
    for c in (3, 4, 7):
        sep, one = [], []
        for _ in range(5):
            sep.append(sum(solve(F, n, 8, rng) for _ in range(c) for n, F, _ in bodies))
            one.append(sum(solve(F, n, 8 * c, rng) for n, F, _ in bodies))
        print("configurations %d: %d x 8 columns %.4f s, one %d-column solve %.4f s: ratio %.2f (medians %.4f / %.4f = %.2f)"
              % (c, c, min(sep), 8 * c, min(one), min(one) / min(sep), np.median(sep), np.median(one),
                 np.median(one) / np.median(sep)), flush=True)


if __name__ == "__main__":
    main()
