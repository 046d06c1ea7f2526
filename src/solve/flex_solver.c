#include <kryflex_impl.h>

PETSC_INTERN PetscErrorCode KFSelectHeldDofs(KFSystem, PetscInt *nheld, PetscInt **held);

PetscErrorCode KFFlexSolverCreate(KFSystem sys, KFFlexSolver *solver)
{
  PetscFunctionBegin;
  PetscCheck(sys->assembled, sys->scene->comm, PETSC_ERR_ORDER, "call KFSystemSetAngles() before KFFlexSolverCreate()");
  PetscCall(PetscNew(solver));
  (*solver)->sys    = sys;
  (*solver)->refine = 1;
  PetscOptionsBegin(sys->scene->comm, NULL, "kryflex flexible solve operator K+", "KFFlexSolverCreate");
  PetscCall(PetscOptionsReal("-kf_shift", "Factor K + shift M instead of K with dofs held (default 0: held dofs)", "KFFlexSolverSetShift", (*solver)->shift, &(*solver)->shift, NULL));
  PetscCall(PetscOptionsInt("-kf_refine", "Steps of iterative refinement of each solve (default 1)", "KFFlexSolverApply", (*solver)->refine, &(*solver)->refine, NULL));
  PetscOptionsEnd();
  PetscFunctionReturn(0);
}

PetscErrorCode KFFlexSolverSetShift(KFFlexSolver solver, PetscReal shift)
{
  PetscFunctionBegin;
  PetscCheck(!solver->setup, PETSC_COMM_SELF, PETSC_ERR_ORDER, "set the shift before KFFlexSolverSetUp()");
  PetscCheck(shift >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "the shift must be >= 0 (K + shift M must be positive definite); got %g", (double)shift);
  solver->shift = shift;
  PetscFunctionReturn(0);
}

PetscErrorCode KFFlexSolverDestroy(KFFlexSolver *solver)
{
  PetscFunctionBegin;
  if (!*solver) PetscFunctionReturn(0);
  PetscCall(MatDestroy(&(*solver)->Kh));
  PetscCall(MatDestroy(&(*solver)->F));
  PetscCall(KFBodywiseDestroy(&(*solver)->bw));
  PetscCall(PetscFree((*solver)->held));
  PetscCall(PetscFree(*solver));
  PetscFunctionReturn(0);
}

/* MUMPS LDL^T factorization with null-pivot detection; reports the inertia MUMPS sees. */
PETSC_INTERN PetscErrorCode KFFactorMumps(Mat A, PetscReal null_threshold, Mat *F, PetscInt *null_pivots, PetscInt *negative_pivots)
{
  MatFactorInfo  info;
  MatFactorError err;

  PetscFunctionBegin;
  PetscCall(MatFactorInfoInitialize(&info));
  PetscCall(MatGetFactor(A, MATSOLVERMUMPS, MAT_FACTOR_CHOLESKY, F));
  PetscCall(MatMumpsSetIcntl(*F, 24, 1)); /* null-pivot detection */
  if (null_threshold != 0) PetscCall(MatMumpsSetCntl(*F, 3, null_threshold));
  PetscCall(MatMumpsSetIcntl(*F, 13, 1)); /* no ScaLAPACK on the root node: LDL^T keeps the inertia exact */
  PetscCall(MatSetErrorIfFailure(A, PETSC_FALSE));
  PetscCall(MatCholeskyFactorSymbolic(*F, A, NULL, &info));
  PetscCall(MatCholeskyFactorNumeric(*F, A, &info));
  PetscCall(MatFactorGetError(*F, &err));
  PetscCheck(err == MAT_FACTOR_NOERROR, PetscObjectComm((PetscObject)A), PETSC_ERR_MAT_LU_ZRPVT, "MUMPS could not factor the stiffness matrix (error type %d): it is singular beyond its rigid-body and mechanism modes, or out of memory (-mat_mumps_icntl_14 raises MUMPS' workspace)", (int)err);
  PetscCall(MatMumpsGetInfog(*F, 28, null_pivots));
  PetscCall(MatMumpsGetInfog(*F, 12, negative_pivots));
  PetscFunctionReturn(0);
}

PetscErrorCode KFFlexSolverSetUp(KFFlexSolver solver)
{
  KFSystem  sys = solver->sys;
  KFScene   s   = sys->scene;
  PetscBool check;
  PetscInt  check_max = 20000;

  PetscFunctionBegin;
  if (solver->setup) PetscFunctionReturn(0);
  PetscCheck(solver->shift >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "the shift must be >= 0 (K + shift M must be positive definite); got %g", (double)solver->shift);
  PetscCall(KFBodywiseSetUp(solver)); /* -kf_flex_solver bodywise: body factorizations and an interface problem instead */
  solver->setup = (PetscBool)(solver->bw != NULL);
  if (solver->setup) PetscFunctionReturn(0);
  PetscCall(KFSystemComputeRigidModes(sys));
  PetscCall(PetscLogEventBegin(KF_EVENT_FACTOR, 0, 0, 0, 0));
  PetscCall(MatDuplicate(sys->Ks, MAT_COPY_VALUES, &solver->Kh));
  if (solver->shift > 0) PetscCall(MatAXPY(solver->Kh, solver->shift, sys->Ms, UNKNOWN_NONZERO_PATTERN));
  else {
    Vec       d;
    PetscReal dsum;
    PetscInt  rstart, rend, nloc = 0, *loc;
    PetscCall(KFSelectHeldDofs(sys, &solver->nheld, &solver->held));
    PetscCall(MatCreateVecs(solver->Kh, &d, NULL));
    PetscCall(MatGetDiagonal(solver->Kh, d));
    PetscCall(VecNorm(d, NORM_1, &dsum));
    PetscCall(VecDestroy(&d));
    PetscCall(MatGetOwnershipRange(solver->Kh, &rstart, &rend));
    PetscCall(PetscMalloc1(solver->nheld, &loc));
    for (PetscInt k = 0; k < solver->nheld; k++)
      if (solver->held[k] >= rstart && solver->held[k] < rend) loc[nloc++] = solver->held[k];
    /* a unit-scaled identity on the held rows keeps the factor well conditioned */
    PetscCall(MatZeroRowsColumns(solver->Kh, nloc, loc, dsum / s->nsys, NULL, NULL));
    PetscCall(PetscFree(loc));
  }
  PetscCall(KFProgress(s->comm, "factorization of the %" PetscInt_FMT "-dof system (MUMPS LDL^T, %" PetscInt_FMT " dofs held)", s->nsys, solver->nheld));
  PetscCall(KFFactorMumps(solver->Kh, 0.0, &solver->F, &solver->null_pivots, &solver->negative_pivots));
  sys->nfactor++;
  PetscCheck(solver->negative_pivots == 0, s->comm, PETSC_ERR_ARG_WRONG, "the assembled stiffness matrix is indefinite: MUMPS found %" PetscInt_FMT " negative pivots. A body's K is not positive semi-definite (check its export and units)", solver->negative_pivots);
  PetscCheck(solver->null_pivots == 0, s->comm, PETSC_ERR_ARG_WRONG, "the structure has %" PetscInt_FMT " zero-energy mode(s) beyond the %" PetscInt_FMT " rigid-body and mechanism modes the joints declare: a mechanism no joint declares (an unconnected dof, a missing tie, a body in pieces). Fix the model, or declare the joint", solver->null_pivots, sys->nrigid);
  PetscCall(PetscLogEventEnd(KF_EVENT_FACTOR, 0, 0, 0, 0));

  /* cross-check (small models by default): MUMPS' null pivots of K_S itself should number the rigid modes */
  PetscOptionsBegin(s->comm, NULL, "kryflex null-pivot cross-check", "KFFlexSolverSetUp");
  PetscCall(PetscOptionsInt("-kf_null_pivot_check_max_dofs", "Cross-check the rigid count with MUMPS' null pivots of K_S by default up to this many system dofs (default 20000)", "KFFlexSolverSetUp", check_max, &check_max, NULL));
  check = (PetscBool)(s->nsys <= check_max && solver->shift == 0);
  PetscCall(PetscOptionsBool("-kf_check_null_pivots", "Cross-check the rigid count with MUMPS' null pivots of K_S, one extra factorization (default: on up to -kf_null_pivot_check_max_dofs dofs without shift)", "KFFlexSolverSetUp", check, &check, NULL));
  PetscOptionsEnd();
  if (check) {
    Mat      F0;
    PetscInt nnull, nneg;
    PetscCall(KFFactorMumps(sys->Ks, -1e-10, &F0, &nnull, &nneg)); /* relative threshold: rigid pivots are rounding-sized */
    PetscCall(MatDestroy(&F0));
    /* MUMPS' threshold is a heuristic: a disagreement is worth a line, not an alarm (the held factorization above
       is the mechanism that catches undeclared modes) */
    if (nnull != sys->nrigid)
      PetscCall(KFProgress(s->comm, "cross-check: MUMPS null-pivot detection finds %" PetscInt_FMT " zero-energy modes in K_S, geometry gives %" PetscInt_FMT " (the count depends on MUMPS' threshold, -mat_mumps_cntl_3)", nnull, sys->nrigid));
    else PetscCall(KFProgress(s->comm, "cross-check: MUMPS null pivots of K_S = %" PetscInt_FMT " = rigid-body and mechanism modes", nnull));
  }
  solver->setup = PETSC_TRUE;
  PetscFunctionReturn(0);
}

/* One pass: X = K+ B with the factor: loads made self-equilibrated, held dofs at zero, a block solve, the result
   projected onto the flexible subspace (M-orthogonal to the rigid modes). */
static PetscErrorCode KFFlexSolverSolveOnce(KFFlexSolver solver, Mat B, Mat X)
{
  KFSystem sys = solver->sys;
  Mat      W;

  PetscFunctionBegin;
  PetscCall(MatDuplicate(B, MAT_COPY_VALUES, &W));
  PetscCall(KFProjectFlexible(sys, W, PETSC_TRUE));
  if (solver->nheld) {
    PetscInt     rstart, rend, p, lda;
    PetscScalar *w;
    PetscCall(MatGetOwnershipRange(W, &rstart, &rend));
    PetscCall(MatGetSize(W, NULL, &p));
    PetscCall(MatDenseGetLDA(W, &lda));
    PetscCall(MatDenseGetArray(W, &w));
    for (PetscInt k = 0; k < solver->nheld; k++)
      if (solver->held[k] >= rstart && solver->held[k] < rend)
        for (PetscInt j = 0; j < p; j++) w[(solver->held[k] - rstart) + j * lda] = 0;
    PetscCall(MatDenseRestoreArray(W, &w));
  }
  if (solver->bw) PetscCall(KFBodywiseSolve(solver, W, X));
  else PetscCall(MatMatSolve(solver->F, W, X));
  PetscCall(MatDestroy(&W));
  PetscCall(KFProjectFlexible(sys, X, PETSC_FALSE));
  PetscFunctionReturn(0);
}

/* X = K+ B, refined against K_S itself: the residual (I - M Phi Phi^T) B - K_S X goes through the factor again.
   A stiff structure's solve loses about eps * cond digits; one step wins most of them back (the moments of a
   20,000-dof frame moved by 3e-10 with it), at the price of one matrix product and one more block solve. */
PetscErrorCode KFFlexSolverApply(KFFlexSolver solver, Mat B, Mat X)
{
  KFSystem sys = solver->sys;
  Mat      R, dX, KX;

  PetscFunctionBegin;
  PetscCall(KFFlexSolverSetUp(solver));
  PetscCall(PetscLogEventBegin(KF_EVENT_SOLVE, 0, 0, 0, 0));
  PetscCall(KFFlexSolverSolveOnce(solver, B, X));
  for (PetscInt it = 0; it < solver->refine && solver->shift == 0; it++) {
    PetscCall(MatDuplicate(B, MAT_COPY_VALUES, &R));
    PetscCall(KFProjectFlexible(sys, R, PETSC_TRUE));
    PetscCall(KFMatMultExtended(sys->Ks, X, &KX)); /* the residual must be free of K's rounding: long double */
    PetscCall(MatAXPY(R, -1.0, KX, SAME_NONZERO_PATTERN));
    PetscCall(MatDestroy(&KX));
    PetscCall(MatDuplicate(X, MAT_DO_NOT_COPY_VALUES, &dX));
    PetscCall(KFFlexSolverSolveOnce(solver, R, dX));
    PetscCall(MatAXPY(X, 1.0, dX, SAME_NONZERO_PATTERN));
    PetscCall(MatDestroy(&dX));
    PetscCall(MatDestroy(&R));
  }
  PetscCall(PetscLogEventEnd(KF_EVENT_SOLVE, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

PetscErrorCode KFFlexSolverGetStats(KFFlexSolver solver, PetscInt *nheld, PetscInt *null_pivots, PetscInt *negative_pivots)
{
  PetscFunctionBegin;
  if (nheld) *nheld = solver->nheld;
  if (null_pivots) *null_pivots = solver->null_pivots;
  if (negative_pivots) *negative_pivots = solver->negative_pivots;
  PetscFunctionReturn(0);
}
