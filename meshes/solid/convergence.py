#!/usr/bin/python3
"""Mesh convergence of the spacecraft pair: lowest flexible frequencies versus --refine.

    /usr/bin/python3 meshes/solid/convergence.py --refine 0.5 1 2 3 --angle 0

For each refinement: assembles bus and rotor (solid_assembly), ties them at the
spin bearing as the scene's revolute joint does (translations and the two
rotations perpendicular to z shared; rotor rotated by the angle about z), and
computes the lowest system frequencies with SLEPc (shift-and-invert about a
small negative target, MUMPS Cholesky). Also prints the free-free frequencies
of each body alone. Serial: it gathers the matrices into SciPy to build the
tie, which is fine up to a few hundred thousand dofs.
"""
import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import numpy as np                        # noqa: E402
import scipy.sparse as sp                 # noqa: E402
from petsc4py import PETSc                # noqa: E402
from slepc4py import SLEPc                # noqa: E402

import generate                           # noqa: E402
import solid_assembly                     # noqa: E402


def to_scipy(mat):
    indptr, indices, data = mat.getValuesCSR()
    return sp.csr_matrix((data, indices, indptr), shape=mat.getSize())


def to_petsc(a):
    a = a.tocsr()
    a.sort_indices()
    return PETSc.Mat().createAIJ(size=a.shape, csr=(a.indptr.astype(PETSc.IntType),
                                                    a.indices.astype(PETSc.IntType), a.data),
                                 comm=PETSc.COMM_SELF)


def lowest_frequencies(K, M, count, shift_hz=0.05):
    """The `count` lowest eigenfrequencies (Hz) of K x = w^2 M x; K may be singular."""
    eps = SLEPc.EPS().create(PETSc.COMM_SELF)
    eps.setOperators(to_petsc(K), to_petsc(M))
    eps.setProblemType(SLEPc.EPS.ProblemType.GHEP)
    eps.setDimensions(count)
    eps.setTarget(-(2 * np.pi * shift_hz) ** 2)
    eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
    eps.setTolerances(1e-10, 500)
    st = eps.getST()
    st.setType(SLEPc.ST.Type.SINVERT)
    ksp = st.getKSP()
    ksp.setType("preonly")
    pc = ksp.getPC()
    pc.setType("cholesky")
    pc.setFactorSolverType("mumps")
    eps.solve()
    lam = np.sort([eps.getEigenvalue(i).real for i in range(eps.getConverged())])[:count]
    return np.sign(lam) * np.sqrt(np.abs(lam)) / (2 * np.pi)


def rotation_z(angle_deg):
    a = np.radians(angle_deg)
    return np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])


def system_matrices(bodies, mats, angle_deg):
    """K_S, M_S of the pair joined by the revolute spin bearing at the given angle."""
    bus, rotor = bodies["bus"], bodies["rotor"]
    R = rotation_z(angle_deg)
    # rotor dofs in the bus frame: u_bus_frame = R u_rotor_frame, per 3-dof group
    Rb = sp.block_diag([R] * (rotor.n_dofs // 3), format="csr")
    nb, nr = bus.n_dofs, rotor.n_dofs
    ib = 3 * bus.n_solid + 6 * [r.name for r in bus.rbe2].index("bearing")
    ir = 3 * rotor.n_solid + 6 * [r.name for r in rotor.rbe2].index("bearing")
    # system dofs: all bus dofs, then the rotor's except its bearing ux uy uz rx ry (rz stays free)
    keep = np.setdiff1d(np.arange(nr), ir + np.arange(5))
    rows = np.concatenate([keep, ir + np.arange(5)])
    cols = np.concatenate([nb + np.arange(len(keep)), ib + np.arange(5)])
    P_r = sp.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(nr, nb + len(keep)))
    P_b = sp.eye(nb, nb + len(keep), format="csr")
    out = []
    for kind in ("stiffness", "mass"):
        Ab, Ar = mats["bus"][kind], Rb @ mats["rotor"][kind] @ Rb.T
        out.append((P_b.T @ Ab @ P_b + P_r.T @ Ar @ P_r).tocsr())
    return out


def zero_modes(f, expected):
    """Count of zero-frequency modes (below 1e-3 of the first flexible one) and their largest |f|:
    shift-and-invert resolves exact zeros only to ~1e-3 Hz on the largest meshes."""
    zero = np.abs(f) < 1e-3 * np.abs(f[expected])
    return f"{np.count_nonzero(zero)} zero modes (|f| <= {np.abs(f[zero]).max(initial=0):.1e} Hz)"


def study(refines, angles, nfreq, log=print):
    results = []
    for r in refines:
        t0 = time.perf_counter()
        bodies = generate.build_bodies(r)
        mats = {name: {kind: to_scipy(solid_assembly.assemble(b, kind, PETSc.COMM_SELF))
                       for kind in ("stiffness", "mass")} for name, b in bodies.items()}
        free = {name: lowest_frequencies(m["stiffness"], m["mass"], 6 + nfreq) for name, m in mats.items()}
        system = {}
        for a in angles:
            K, M = system_matrices(bodies, mats, a)
            system[a] = lowest_frequencies(K, M, 7 + nfreq)
        dofs = sum(b.n_dofs for b in bodies.values())
        results.append((r, dofs, free, system))
        log(f"refine {r:g}: {dofs} dofs, {time.perf_counter() - t0:.1f} s")
        for name, f in free.items():
            log(f"  {name} free-free: {zero_modes(f, 6)}, flexible Hz " + " ".join(f"{x:.4f}" for x in f[6:]))
        for a, f in system.items():
            log(f"  system at {a:g} deg: {zero_modes(f, 7)}, flexible Hz " + " ".join(f"{x:.4f}" for x in f[7:]))
    return results


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--refine", type=float, nargs="+", default=[0.5, 1, 2, 3])
    p.add_argument("--angle", type=float, nargs="+", default=[0.0])
    p.add_argument("--nfreq", type=int, default=8, help="flexible frequencies to report")
    args = p.parse_args(argv)
    study(args.refine, args.angle, args.nfreq)


if __name__ == "__main__":
    main()
