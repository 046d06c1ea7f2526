/* The monolithic flexible solve: one MUMPS factorization of the system's K_S with a statically determinate set of
   dofs held (or of K_S + shift M_S), made per configuration. */
#include <kryflex/flexsolverimpl.h>

typedef struct {
  Mat Kh, F; /* shifted stiffness (NULL without a shift: K_S is factored in place) and the MUMPS factor */
} KFFlexSolver_Monolithic;

/* cross-check (small models by default): MUMPS' null pivots of K_S itself should number the rigid modes */
static PetscErrorCode KFFlexSolverCrossCheck_Monolithic(KFFlexSolver solver)
{
  KFSystem  sys = solver->sys;
  KFScene   s   = sys->scene;
  PetscBool check;

  PetscFunctionBegin;
  PetscCall(KFNullPivotCheckOptions(s->comm, ((PetscObject)solver)->prefix, s->nsys, solver->shift, &check));
  if (check) {
    Mat      F0;
    PetscInt nnull, nneg;
    PetscCall(KFFactorMumps(sys->Ks, ((PetscObject)solver)->prefix, -1e-10, PETSC_FALSE, &F0, &nnull, &nneg, NULL)); /* relative threshold: rigid pivots are rounding-sized */
    PetscCall(MatDestroy(&F0));
    /* MUMPS' threshold is a heuristic: a disagreement is worth a line, not an alarm (the held factorization above
       is the mechanism that catches undeclared modes) */
    if (nnull != sys->nrigid)
      PetscCall(KFProgress(s->comm, "cross-check: MUMPS null-pivot detection finds %" PetscInt_FMT " zero-energy modes in K_S, geometry gives %" PetscInt_FMT " (the count depends on MUMPS' threshold, -mat_mumps_cntl_3)", nnull, sys->nrigid));
    else PetscCall(KFProgress(s->comm, "cross-check: MUMPS null pivots of K_S = %" PetscInt_FMT " = rigid-body and mechanism modes", nnull));
  }
  PetscFunctionReturn(0);
}

static PetscErrorCode KFFlexSolverSetUp_Monolithic(KFFlexSolver solver)
{
  KFFlexSolver_Monolithic *mono = (KFFlexSolver_Monolithic *)solver->data;
  KFSystem  sys = solver->sys;
  KFScene   s   = sys->scene;
  KFHeldEntries held = NULL;

  PetscFunctionBegin;
  PetscCall(KFSystemComputeRigidModes(sys));
  PetscCall(PetscLogEventBegin(KF_EVENT_FACTOR, 0, 0, 0, 0));
  if (solver->shift != 0) {
    PetscCall(MatDuplicate(sys->Ks, MAT_COPY_VALUES, &mono->Kh));
    PetscCall(MatAXPY(mono->Kh, solver->shift, sys->Ms, UNKNOWN_NONZERO_PATTERN));
    if (solver->shift < 0) PetscCall(MatSetOption(mono->Kh, MAT_SPD, PETSC_FALSE)); /* never SYM=1 (-kf_spd) */
  } else if (sys->nrigid > 0) { /* a clamped scene (no rigid modes) factors K_S itself: plain Cholesky */
    Vec       d;
    PetscReal dsum;
    PetscCall(KFSelectHeldDofs(sys, ((PetscObject)solver)->prefix, &solver->nheld, &solver->held));
    PetscCall(MatCreateVecs(sys->Ks, &d, NULL));
    PetscCall(MatGetDiagonal(sys->Ks, d));
    PetscCall(VecNorm(d, NORM_1, &dsum));
    PetscCall(VecDestroy(&d));
    /* a unit-scaled identity on the held rows keeps the factor well conditioned; K_S is held in place (no copy of
       the system's largest matrix) and restored after the factorization */
    PetscCall(KFHoldDofsInPlace(sys->Ks, solver->nheld, solver->held, dsum / s->nsys, &held));
  }
  PetscCall(KFProgress(s->comm, "factorization of the %" PetscInt_FMT "-dof system (MUMPS LDL^T, %" PetscInt_FMT " dofs held)", s->nsys, solver->nheld));
  {
    PetscLogDouble t0, t1;

    PetscCall(PetscTime(&t0));
    PetscErrorCode ierr;

    ierr = KFFactorMumps(mono->Kh ? mono->Kh : sys->Ks, ((PetscObject)solver)->prefix, 0.0, PETSC_TRUE, &mono->F, &solver->null_pivots, &solver->negative_pivots, &solver->perf.memory_estimate_mb);
    /* K_S unheld again even when the factorization failed (a caller may retry with other options) */
    PetscCall(KFRestoreHeldDofs(sys->Ks, &held));
    if (!mono->Kh) PetscCall(MatSetOption(sys->Ks, MAT_SPD, PETSC_FALSE)); /* -kf_spd holds for the held K_S only */
    PetscCall(ierr);
    PetscCall(PetscTime(&t1));
    solver->perf.factor_seconds += t1 - t0;
    if (!solver->refine_set) { /* -kf_ooc auto may have chosen block low-rank: its refinement steps (KFFlexSolverRefineSteps) */
      PetscInt blr;

      PetscCall(MatMumpsGetIcntl(mono->F, 35, &blr));
      if (blr) solver->refine = PetscMax(solver->refine, 5);
    }
    sys->nfactor++;
  }
  PetscCheck(solver->negative_pivots == 0 || solver->shift < 0, s->comm, PETSC_ERR_ARG_WRONG, "the assembled stiffness matrix is indefinite: MUMPS found %" PetscInt_FMT " negative pivots. A body's K is not positive semi-definite (check its export and units)", solver->negative_pivots);
  PetscCheck(solver->null_pivots == 0 || solver->shift >= 0, s->comm, PETSC_ERR_ARG_WRONG, "the expansion point sigma = %g (%g Hz) is a natural frequency of the structure: K - sigma M is singular (MUMPS found %" PetscInt_FMT " null pivots). Move the point off the resonance", (double)-solver->shift, (double)(PetscSqrtReal(-solver->shift) / (2 * PETSC_PI)), solver->null_pivots);
  PetscCheck(solver->null_pivots == 0, s->comm, PETSC_ERR_ARG_WRONG, "the structure has %" PetscInt_FMT " zero-energy mode(s) beyond the %" PetscInt_FMT " rigid-body and mechanism modes that geometry, joints and boundary conditions give: a mechanism nothing declares (an unconnected dof, a missing tie, a body in pieces, a support missing from the scene's constraints). Fix the model, or declare the joint or constraint", solver->null_pivots, sys->nrigid);
  PetscCall(PetscLogEventEnd(KF_EVENT_FACTOR, 0, 0, 0, 0));

  PetscCall(KFFlexSolverCrossCheck_Monolithic(solver));
  PetscFunctionReturn(0);
}

/* A block low-rank factor refactored full rank (MUMPS takes ICNTL(35) = 0 at a new numerical factorization of the
   same analysis): K_S held again as at the set-up, factored, restored */
static PetscErrorCode KFFlexSolverRefactor_Monolithic(KFFlexSolver solver, PetscBool *done)
{
  KFFlexSolver_Monolithic *mono = (KFFlexSolver_Monolithic *)solver->data;
  KFSystem      sys = solver->sys;
  KFScene       s   = sys->scene;
  PetscInt      blr = 0, cap = 0;
  KFHeldEntries held = NULL;
  Mat           A = mono->Kh ? mono->Kh : sys->Ks;

  PetscFunctionBegin;
  *done = PETSC_FALSE;
  if (!mono->F) PetscFunctionReturn(0);
  PetscCall(MatMumpsGetIcntl(mono->F, 35, &blr));
  if (!blr) PetscFunctionReturn(0);
  PetscCall(MatMumpsGetIcntl(mono->F, 23, &cap));
  if (cap > 0) { /* -kf_ooc auto chose block low-rank because the full-rank factor does not fit in core */
    PetscCall(KFProgress(s->comm, "block solves above -kf_refine_rtol after refinement: the block low-rank factor stays (-kf_ooc auto chose it because the full-rank one does not fit in core; -kf_ooc true factors full rank out of core)"));
    PetscFunctionReturn(0);
  }
  PetscCall(KFProgress(s->comm, "block solves above -kf_refine_rtol after refinement: the block low-rank factor is refactored full rank"));
  if (!mono->Kh && solver->nheld) {
    Vec       d;
    PetscReal dsum;

    PetscCall(MatCreateVecs(sys->Ks, &d, NULL));
    PetscCall(MatGetDiagonal(sys->Ks, d));
    PetscCall(VecNorm(d, NORM_1, &dsum));
    PetscCall(VecDestroy(&d));
    PetscCall(KFHoldDofsInPlace(sys->Ks, solver->nheld, solver->held, dsum / s->nsys, &held));
  }
  PetscCall(MatMumpsSetIcntl(mono->F, 35, 0));
  PetscCall(KFMumpsFactorNumeric(mono->F, A)); /* an out-of-core factor's files into its folder again */
  if (held) PetscCall(KFRestoreHeldDofs(sys->Ks, &held));
  sys->nfactor++;
  *done = PETSC_TRUE;
  PetscFunctionReturn(0);
}


static PetscErrorCode KFFlexSolverSolve_Monolithic(KFFlexSolver solver, Mat W, Mat X)
{
  KFFlexSolver_Monolithic *mono = (KFFlexSolver_Monolithic *)solver->data;

  PetscFunctionBegin;
  PetscCall(KFMumpsMatSolve(mono->F, W, X));
  PetscFunctionReturn(0);
}

static PetscErrorCode KFFlexSolverView_Monolithic(KFFlexSolver solver, PetscViewer viewer)
{
  KFFlexSolver_Monolithic *mono = (KFFlexSolver_Monolithic *)solver->data;

  PetscFunctionBegin;
  PetscCall(PetscViewerASCIIPrintf(viewer, "one MUMPS factorization of %s\n", mono->Kh ? "K_S + shift M_S" : "K_S with its held dofs"));
  PetscFunctionReturn(0);
}

static PetscErrorCode KFFlexSolverDestroy_Monolithic(KFFlexSolver solver)
{
  KFFlexSolver_Monolithic *mono = (KFFlexSolver_Monolithic *)solver->data;

  PetscFunctionBegin;
  PetscCall(MatDestroy(&mono->Kh));
  PetscCall(MatDestroy(&mono->F));
  PetscCall(PetscFree(solver->data));
  PetscFunctionReturn(0);
}

PETSC_INTERN PetscErrorCode KFFlexSolverCreate_Monolithic(KFFlexSolver solver)
{
  KFFlexSolver_Monolithic *mono;

  PetscFunctionBegin;
  PetscCall(PetscNew(&mono));
  solver->data          = mono;
  solver->ops->setup    = KFFlexSolverSetUp_Monolithic;
  solver->ops->solve    = KFFlexSolverSolve_Monolithic;
  solver->ops->refactor = KFFlexSolverRefactor_Monolithic;
  solver->ops->view     = KFFlexSolverView_Monolithic;
  solver->ops->destroy  = KFFlexSolverDestroy_Monolithic;
  PetscFunctionReturn(0);
}
