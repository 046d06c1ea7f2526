/* The number of flexible modes of the full-order system below a frequency, without an eigensolve: Sylvester's law of
   inertia. K_S - sigma M_S is congruent to its LDL^T factor's D, so its negative pivots (MUMPS SYM=2, INFOG(12), exact
   in parallel with ICNTL(13) = 1, which KFFactorMumps sets) number the eigenvalues of (K_S, M_S) below sigma. The
   rigid-body and mechanism modes sit at 0 < sigma and are subtracted. A direction of M_S's null space is an infinite
   eigenvalue: K_S is positive there (the verification refuses a null space of M_S that K_S does not hold), so by
   static condensation K_S - sigma M_S ~ diag(K_zz, K_c - sigma M_c) and it adds a positive pivot, never a count. */
#include <kryflex_impl.h>
#include <kryflex/flexsolverimpl.h>

/* negative and null pivots of the LDL^T factor of K_S - sigma M_S (sigma = omega^2, rad^2/s^2) */
PETSC_INTERN PetscErrorCode KFSystemShiftedInertia(KFSystem sys, PetscReal sigma, PetscInt *nneg, PetscInt *nnull)
{
  Mat A, F;

  PetscFunctionBegin;
  PetscCall(MatDuplicate(sys->Ks, MAT_COPY_VALUES, &A));
  PetscCall(MatAXPY(A, -sigma, sys->Ms, UNKNOWN_NONZERO_PATTERN));
  {
    PetscBool aij;

    PetscCall(PetscObjectTypeCompareAny((PetscObject)A, &aij, MATSEQAIJ, MATMPIAIJ, MATSEQSBAIJ, MATMPISBAIJ, ""));
    if (!aij) PetscCall(MatConvert(A, MATAIJ, MAT_INPLACE_MATRIX, &A)); /* a small scene's dense system: MUMPS takes sparse matrices */
  }
  PetscCall(MatSetOption(A, MAT_SPD, PETSC_FALSE)); /* indefinite: never SYM=1 */
  PetscCall(KFFactorMumps(A, "kf_count_", 0.0, PETSC_FALSE, &F, nnull, nneg, NULL));
  PetscCall(MatDestroy(&F));
  PetscCall(MatDestroy(&A));
  PetscFunctionReturn(0);
}

/* The flexible modes of the configuration with a frequency below freq (Hz): one factorization of K_S - (2 pi f)^2 M_S.
   freq a natural frequency (MUMPS finds a null pivot) is an error naming it: the count there is ambiguous. */
PetscErrorCode KFSystemCountModesBelow(KFSystem sys, PetscReal freq, PetscInt *count)
{
  KFScene   s = sys->scene;
  PetscInt  nneg, nnull;
  PetscReal w = 2 * PETSC_PI * freq;

  PetscFunctionBegin;
  PetscCheck(freq > 0 && PetscIsNormalReal(freq), s->comm, PETSC_ERR_ARG_OUTOFRANGE, "the frequency below which modes are counted is a positive number of Hz; got %g", (double)freq);
  PetscCall(KFSystemComputeRigidModes(sys));
  PetscCall(KFSystemShiftedInertia(sys, w * w, &nneg, &nnull));
  PetscCheck(nnull == 0, s->comm, PETSC_ERR_ARG_WRONG, "%g Hz is a natural frequency of the full-order system (K_S - sigma M_S has %" PetscInt_FMT " null pivots): count at a frequency off it", (double)freq, nnull);
  PetscCheck(nneg >= sys->nrigid, s->comm, PETSC_ERR_PLIB, "K_S - sigma M_S at %g Hz has %" PetscInt_FMT " negative pivots, fewer than the %" PetscInt_FMT " rigid-body and mechanism modes below it: the mass matrix M_S is indefinite or the rigid modes are wrong", (double)freq, nneg, sys->nrigid);
  *count = nneg - sys->nrigid;
  PetscFunctionReturn(0);
}
