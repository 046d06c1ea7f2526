/* Where the rigid-body and mechanism modes end in a spectrum. */
#include <kryflex_impl.h>

/*
  KFRigidTolerance - a relative tolerance that separates the nrigid lowest eigenvalues from the rest: the geometric
  mean of the last rigid and the first flexible eigenvalue, relative to the largest (0 without rigid modes, 1 when
  every mode is rigid). The former Python rigid_tolerance.
*/
PetscErrorCode KFRigidTolerance(PetscInt n, const PetscReal lambda[], PetscInt nrigid, PetscReal *rtol)
{
  PetscReal *lam, top, lo, hi;

  PetscFunctionBegin;
  PetscValidRealPointer(rtol, 4);
  PetscCheck(n >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFRigidTolerance: negative size %" PetscInt_FMT, n);
  if (nrigid <= 0) {
    *rtol = 0.0;
    PetscFunctionReturn(0);
  }
  if (nrigid >= n) {
    *rtol = 1.0;
    PetscFunctionReturn(0);
  }
  /* sorted copy: callers pass eigenvalues in ascending order, but the measure must not depend on it */
  PetscCall(PetscMalloc1(n, &lam));
  PetscCall(PetscArraycpy(lam, lambda, n));
  PetscCall(PetscSortReal(n, lam));
  top   = PetscMax(PetscAbsReal(lam[n - 1]), 1e-300);
  lo    = PetscMax(PetscAbsReal(lam[nrigid - 1]), 1e-300 * top);
  hi    = PetscMax(lam[nrigid], 1e-300 * top);
  *rtol = PetscSqrtReal(lo * hi) / top;
  PetscCall(PetscFree(lam));
  PetscFunctionReturn(0);
}
