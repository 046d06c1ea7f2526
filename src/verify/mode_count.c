/* The number of flexible modes of the full-order system below a frequency, without an eigensolve: Sylvester's law of
   inertia. K_S - sigma M_S is congruent to its LDL^T factor's D, so its negative pivots (MUMPS SYM=2, INFOG(12), exact
   in parallel with ICNTL(13) = 1, which KFFactorMumps sets) number the eigenvalues of (K_S, M_S) below sigma. The
   rigid-body and mechanism modes sit at 0 < sigma and are subtracted. A direction of M_S's null space is an infinite
   eigenvalue: K_S is positive there (the verification refuses a null space of M_S that K_S does not hold), so by
   static condensation K_S - sigma M_S ~ diag(K_zz, K_c - sigma M_c) and it adds a positive pivot, never a count. */
#include <kryflex_impl.h>
#include <kryflex/flexsolverimpl.h>

/* negative and null pivots of K_S - sigma M_S (sigma = omega^2, rad^2/s^2). bf (or NULL): the bodies' interior factors
   of K_b - sigma M_b (KFModeCountBodyFactors), whose count serves every configuration: then only the small interface
   problem at the system's angles is factored (Haynsworth: the inertia of a matrix is its interior block's plus its
   Schur complement's), else one MUMPS LDL^T of the whole K_S - sigma M_S. A singular interface problem (sigma a
   natural frequency) is reported as a null pivot, as MUMPS' is. */
PETSC_INTERN PetscErrorCode KFSystemShiftedInertia(KFSystem sys, PetscReal sigma, KFBodyFactors bf, PetscInt *nneg, PetscInt *nnull)
{
  Mat A, F;

  PetscFunctionBegin;
  if (bf) {
    KFBodywiseOp   op = NULL;
    PetscErrorCode ierr;

    PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
    ierr = KFBodywiseOpCreate(sys, bf, &op);
    PetscCall(PetscPopErrorHandler());
    *nnull = ierr == PETSC_ERR_MAT_LU_ZRPVT;
    if (ierr && !*nnull) PetscCall(ierr);
    if (!ierr) PetscCall(KFBodywiseOpInertia(bf, op, nneg));
    PetscCall(KFBodywiseOpDestroy(&op));
    PetscFunctionReturn(0);
  }
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

/* -kf_verify_count (whether the verification's sparse eigensolves are certified by a count, default false) and
   -kf_verify_count_bodywise (the count on the body-wise split where it applies, default true); either may be NULL */
PETSC_INTERN PetscErrorCode KFModeCountOptions(MPI_Comm comm, const char prefix[], PetscBool *count, PetscBool *bodywise)
{
  PetscBool c = PETSC_FALSE, b = PETSC_TRUE;

  PetscFunctionBegin;
  PetscOptionsBegin(comm, prefix, "kryflex verification: the modes' count certified", "KFReducerSolve");
  PetscCall(KFOptionsSettingBool(PetscOptionsObject, "-kf_verify_count", c, &c, NULL));
  PetscCall(KFOptionsSettingBool(PetscOptionsObject, "-kf_verify_count_bodywise", b, &b, NULL));
  PetscOptionsEnd();
  if (count) *count = c;
  if (bodywise) *bodywise = b;
  PetscFunctionReturn(0);
}

/* The bodies' interior factors of K_b - sigma M_b for counts at sigma on every configuration of the scene, where the
   body-wise split applies (KFBodywiseApplies) and -kf_verify_count_bodywise (default true) allows it; else *bf = NULL
   (a count is then one factorization of the whole system). The caller destroys them (KFBodyFactorsDestroy). reuse: the
   caller solves with the system's own body factors no more, whose MUMPS analyses then serve the count's factorizations
   of the same patterns (KFBodyFactorsCreateShiftedReusing; the system's factors are gone after). */
PETSC_INTERN PetscErrorCode KFModeCountBodyFactors(KFSystem sys, const char prefix[], PetscReal sigma, PetscBool reuse, KFBodyFactors *bf)
{
  PetscBool use, opt;

  PetscFunctionBegin;
  *bf = NULL;
  PetscCall(KFBodywiseApplies(sys->scene, &use));
  PetscCall(KFModeCountOptions(sys->scene->comm, prefix, NULL, &opt));
  if (use && opt && reuse) PetscCall(KFBodyFactorsCreateShiftedReusing(sys, prefix, -sigma, bf));
  else if (use && opt) PetscCall(KFBodyFactorsCreateShifted(sys, prefix, -sigma, bf));
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
  PetscCall(KFSystemShiftedInertia(sys, w * w, NULL, &nneg, &nnull));
  PetscCheck(nnull == 0, s->comm, PETSC_ERR_ARG_WRONG, "%g Hz is a natural frequency of the full-order system (K_S - sigma M_S has %" PetscInt_FMT " null pivots): count at a frequency off it", (double)freq, nnull);
  PetscCheck(nneg >= sys->nrigid, s->comm, PETSC_ERR_PLIB, "K_S - sigma M_S at %g Hz has %" PetscInt_FMT " negative pivots, fewer than the %" PetscInt_FMT " rigid-body and mechanism modes below it: the mass matrix M_S is indefinite or the rigid modes are wrong", (double)freq, nneg, sys->nrigid);
  *count = nneg - sys->nrigid;
  PetscFunctionReturn(0);
}
