#!/usr/bin/python3
"""A mass singular with no zero diagonal, reduced and verified end to end against SciPy.

    PYTHONPATH=python .venv/bin/python benchmarks/reference_check/singular_mass.py rigid_offset_frame [PETSc options]

The model is tests/python/support/bc_models.py's (rigid_offset_frame: the lumped frame with rigid elements eliminated,
M = T^T M T, 45 of its 90 dofs in M's null space, no zero diagonal; lumped_frame for comparison). Prints the
verification eigensolve's progress lines (block path or its fall back to Krylov-Schur), then: the reference's modes
against dense SciPy with M's null space condensed, the reference response's and the reduced model's distance to SciPy's
response (max over pairs of max |T - T_scipy| / the pair's peak), the reported error, the direct-solve check's worst
disagreement and the Krylov deflations. Run under mpiexec for several ranks.
"""
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tests", "python", "support"))
sys.path.insert(0, os.path.join(ROOT, "tests", "python", "reducer"))


def main():
    import kryflex
    kryflex.init(sys.argv[:1] + sys.argv[2:] + ["-kf_quiet", "0"])
    from petsc4py import PETSc
    import bc_models
    from test_reference_truth import pair_distance, scipy_frf
    name = sys.argv[1]
    spec = getattr(bc_models, name)()
    M, K, G, H = (np.asarray(a) for a in bc_models.layout_reference(spec))
    r = kryflex.Reducer(kryflex.scene_from_dict(spec))
    reduced = r.reduce().model.at([])
    f = np.ravel(r.result(0, "frf_frequencies_hz"))
    exact, lam = scipy_frf(M, K, G, H, f, spec["damping"], nrigid=6)
    fk, fs = np.ravel(r.result(0, "full_frequencies_hz")), np.sqrt(np.abs(lam[6:])) / (2 * np.pi)
    if PETSc.COMM_WORLD.getRank() == 0:
        print("%s %s (%d ranks): %d modes, vs SciPy %.2e; reference vs SciPy %.2e; reduced model (%d dofs) vs SciPy "
              "%.2e; error_max %.3e, target met %s; direct-solve check %.2e; %d Krylov deflations" % (
                  name, " ".join(sys.argv[2:]), PETSc.COMM_WORLD.getSize(), fk.size, np.abs(fk / fs[:fk.size] - 1).max(),
                  pair_distance(np.asarray(r.frf(0, "full")).reshape(exact.shape), exact), reduced.M.shape[0],
                  pair_distance(np.asarray(reduced.frf(f)).reshape(exact.shape), exact),
                  float(np.ravel(r.result(-1, "error_max"))[0]), bool(np.ravel(r.result(-1, "target_met"))[0]),
                  float(np.ravel(r.result(-1, "reference_check_error"))[0]),
                  int(np.ravel(r.result(0, "krylov_deflations"))[0])), flush=True)


if __name__ == "__main__":
    main()
