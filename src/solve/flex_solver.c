/* KFFlexSolver, the flexible solve operator K+: the generic object (life cycle, type, options, view) and what every
   implementation shares, the projection of a block onto the flexible subspace and its iterative refinement against
   K_S. How K_h^-1 is applied is the implementation's (src/solve/impls/<type>/, registered in src/solve/register.c). */
#include <kryflex/flexsolverimpl.h>

/* A solver with no type yet, on sys (NULL: a solver whose options are only read and checked) */
static PetscErrorCode KFFlexSolverCreate_Private(MPI_Comm comm, KFSystem sys, KFFlexSolver *solver)
{
  KFFlexSolver f;

  PetscFunctionBegin;
  PetscCall(KFFlexSolverRegisterAll());
  PetscCall(PetscHeaderCreate(f, KF_FLEXSOLVER_CLASSID, "KFFlexSolver", "Flexible solve operator K+", "KF", comm, KFFlexSolverDestroy, KFFlexSolverView));
  f->sys         = sys;
  f->refine      = 1;
  f->refine_rtol = 1e-6;
  *solver        = f;
  PetscFunctionReturn(0);
}

/*
  KFFlexSolverCreate - the flexible solver of an assembled system. Its type (KFFlexSolverSetType; -kf_flex_solver,
  default auto) and options (-kf_shift, -kf_refine, -kf_refine_rtol, the factorization's) are read with the solver's
  options prefix (KFFlexSolverSetOptionsPrefix; a reducer's solvers take the reducer's) by KFFlexSolverSetFromOptions,
  which KFFlexSolverSetUp calls when nobody did.
*/
PetscErrorCode KFFlexSolverCreate(KFSystem sys, KFFlexSolver *solver)
{
  PetscFunctionBegin;
  PetscValidPointer(solver, 2);
  PetscCheck(sys->assembled, sys->scene->comm, PETSC_ERR_ORDER, "call KFSystemSetAngles() before KFFlexSolverCreate()");
  PetscCall(KFFlexSolverCreate_Private(sys->scene->comm, sys, solver));
  PetscFunctionReturn(0);
}

PetscErrorCode KFFlexSolverSetOptionsPrefix(KFFlexSolver solver, const char prefix[])
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(solver, KF_FLEXSOLVER_CLASSID, 1);
  PetscCall(PetscObjectSetOptionsPrefix((PetscObject)solver, prefix));
  PetscFunctionReturn(0);
}

/*
  KFFlexSolverSetType - how K+ is applied: KFFLEXSOLVERMONOLITHIC (one factorization of K_S per configuration),
  KFFLEXSOLVERBODYWISE (one factorization per body interior, kept on the KFSystem for all its configurations, and a
  dense interface problem per configuration: the same K+ B), KFFLEXSOLVERAUTO (body-wise where it pays, decided at
  the set-up), or any type added by KFFlexSolverRegister. -kf_flex_solver overrides it.
*/
PetscErrorCode KFFlexSolverSetType(KFFlexSolver solver, KFFlexSolverType type)
{
  PetscErrorCode (*create)(KFFlexSolver);
  PetscBool same;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(solver, KF_FLEXSOLVER_CLASSID, 1);
  PetscCheck(!solver->setup, PETSC_COMM_SELF, PETSC_ERR_ORDER, "set the type before KFFlexSolverSetUp()");
  PetscCall(PetscObjectTypeCompare((PetscObject)solver, type, &same));
  if (same) PetscFunctionReturn(0);
  PetscCall(KFFlexSolverRegisterAll());
  PetscCall(PetscFunctionListFind(KFFlexSolverList, type, &create));
  PetscCheck(create, PetscObjectComm((PetscObject)solver), PETSC_ERR_ARG_UNKNOWN_TYPE, "unknown flexible solver type '%s': give auto, monolithic or bodywise (or a type added by KFFlexSolverRegister)", type);
  if (solver->ops->destroy) PetscCall((*solver->ops->destroy)(solver));
  PetscCall(PetscMemzero(solver->ops, sizeof(struct _KFFlexSolverOps)));
  solver->data = NULL;
  PetscCall(PetscObjectChangeTypeName((PetscObject)solver, type));
  PetscCall((*create)(solver));
  PetscFunctionReturn(0);
}

/* the implementation set up (after KFFlexSolverSetUp): monolithic or bodywise; auto has chosen one of them by then */
PetscErrorCode KFFlexSolverGetType(KFFlexSolver solver, KFFlexSolverType *type)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(solver, KF_FLEXSOLVER_CLASSID, 1);
  PetscCheck(solver->setup, PETSC_COMM_SELF, PETSC_ERR_ORDER, "call KFFlexSolverSetUp() first");
  *type = ((PetscObject)solver)->type_name;
  PetscFunctionReturn(0);
}

PetscErrorCode KFFlexSolverSetShift(KFFlexSolver solver, PetscReal shift)
{
  PetscFunctionBegin;
  PetscCheck(!solver->setup, PETSC_COMM_SELF, PETSC_ERR_ORDER, "set the shift before KFFlexSolverSetUp()");
  PetscCheck(shift >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "the shift must be >= 0 (K + shift M must be positive definite); got %g", (double)shift);
  solver->shift     = shift;
  solver->shift_set = PETSC_TRUE;
  PetscFunctionReturn(0);
}

/* An expansion point inside the band: factor K_S - sigma M_S (sigma > 0), indefinite, by MUMPS' LDL^T with pivoting
   (SYM=2); the solve then gives the Krylov blocks of (K - sigma M)^-1 M at sigma (src/reducer/shifts.c). The
   shift is stored as -sigma: what is factored is always K + shift M, by the monolithic implementation. */
PetscErrorCode KFFlexSolverSetInteriorShift(KFFlexSolver solver, PetscReal sigma)
{
  PetscFunctionBegin;
  PetscCheck(!solver->setup, PETSC_COMM_SELF, PETSC_ERR_ORDER, "set the shift before KFFlexSolverSetUp()");
  PetscCheck(sigma > 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "an expansion point inside the band is a positive sigma = (2 pi f)^2; got %g", (double)sigma);
  solver->shift     = -sigma;
  solver->shift_set = PETSC_TRUE;
  PetscFunctionReturn(0);
}

PetscErrorCode KFFlexSolverDestroy(KFFlexSolver *solver)
{
  PetscFunctionBegin;
  if (!*solver) PetscFunctionReturn(0);
  PetscValidHeaderSpecific(*solver, KF_FLEXSOLVER_CLASSID, 1);
  if (--((PetscObject)(*solver))->refct > 0) {
    *solver = NULL;
    PetscFunctionReturn(0);
  }
  if ((*solver)->ops->destroy) PetscCall((*(*solver)->ops->destroy)(*solver));
  PetscCall(PetscFree((*solver)->held));
  PetscCall(PetscHeaderDestroy(solver));
  PetscFunctionReturn(0);
}

PetscErrorCode KFFlexSolverView(KFFlexSolver solver, PetscViewer viewer)
{
  PetscBool ascii;

  PetscFunctionBegin;
  if (!viewer) PetscCall(PetscViewerASCIIGetStdout(PetscObjectComm((PetscObject)solver), &viewer));
  PetscCall(PetscObjectTypeCompare((PetscObject)viewer, PETSCVIEWERASCII, &ascii));
  if (!ascii) PetscFunctionReturn(0);
  PetscCall(PetscObjectPrintClassNamePrefixType((PetscObject)solver, viewer));
  PetscCall(PetscViewerASCIIPushTab(viewer));
  PetscCall(PetscViewerASCIIPrintf(viewer, "shift %g, %" PetscInt_FMT " held dofs, at most %" PetscInt_FMT " refinement steps above relative residual %g\n", (double)solver->shift, solver->nheld, solver->refine, (double)solver->refine_rtol));
  if (solver->ops->view) PetscCall((*solver->ops->view)(solver, viewer));
  PetscCall(PetscViewerASCIIPopTab(viewer));
  PetscFunctionReturn(0);
}

/* the implementation's own options, in a block of their own */
static PetscErrorCode KFFlexSolverTypeOptions(KFFlexSolver solver)
{
  PetscFunctionBegin;
  if (!solver->ops->setfromoptions) PetscFunctionReturn(0);
  PetscObjectOptionsBegin((PetscObject)solver);
  PetscCall((*solver->ops->setfromoptions)(solver, PetscOptionsObject));
  PetscOptionsEnd();
  PetscFunctionReturn(0);
}

/*
  KFFlexSolverSetFromOptions - -kf_flex_solver, -kf_shift (unless KFFlexSolverSetShift set one), -kf_refine (the
  default, 1 or 5, follows -kf_blr: KFFlexSolverRefineSteps), -kf_refine_rtol and the implementation's options,
  read and checked with the solver's prefix.
*/
PetscErrorCode KFFlexSolverSetFromOptions(KFFlexSolver solver)
{
  char      type[256] = KFFLEXSOLVERAUTO;
  PetscReal shift     = 0;
  PetscBool flg, shift_given;
  MPI_Comm  comm = PetscObjectComm((PetscObject)solver);

  PetscFunctionBegin;
  PetscValidHeaderSpecific(solver, KF_FLEXSOLVER_CLASSID, 1);
  if (((PetscObject)solver)->type_name) PetscCall(PetscStrncpy(type, ((PetscObject)solver)->type_name, sizeof(type)));
  PetscObjectOptionsBegin((PetscObject)solver);
  PetscCall(KFOptionsSettingReal(PetscOptionsObject, "-kf_shift", shift, &shift, &shift_given));
  PetscCall(KFOptionsSettingInt(PetscOptionsObject, "-kf_refine", solver->refine, &solver->refine, &flg));
  solver->refine_set = (PetscBool)(solver->refine_set || flg);
  PetscCall(KFOptionsSettingReal(PetscOptionsObject, "-kf_refine_rtol", solver->refine_rtol, &solver->refine_rtol, NULL));
  PetscCall(KFOptionsSettingFList(PetscOptionsObject, "-kf_flex_solver", KFFlexSolverList, type, type, sizeof(type), &flg));
  PetscOptionsEnd();
  PetscCheck(!shift_given || shift >= 0, comm, PETSC_ERR_ARG_OUTOFRANGE, "-kf_shift must be >= 0 (K + shift M must be positive definite; expansion points inside the band are -kf_max_factorizations); got %g", (double)shift);
  PetscCheck(solver->refine >= 0, comm, PETSC_ERR_ARG_OUTOFRANGE, "-kf_refine must be >= 0; got %" PetscInt_FMT, solver->refine);
  PetscCheck(solver->refine_rtol >= 0, comm, PETSC_ERR_ARG_OUTOFRANGE, "-kf_refine_rtol must be >= 0; got %g", (double)solver->refine_rtol);
  if (shift_given && !solver->shift_set) solver->shift = shift;
  PetscCall(KFFlexSolverSetType(solver, type));
  PetscCall(KFFlexSolverTypeOptions(solver));
  solver->setfromoptionscalled = PETSC_TRUE;
  PetscFunctionReturn(0);
}

/* Every option of the flexible solver under prefix, of each registered implementation, its factorization and its held
   dofs, read and checked with nothing made: a bad value is refused here, before the scene is assembled
   (KFReducerSetFromOptions) */
PETSC_INTERN PetscErrorCode KFFlexSolverCheckOptions(MPI_Comm comm, const char prefix[])
{
  KFFlexSolver       solver;
  PetscReal          cond_max;
  const char        *chosen;
  const char *const *names;
  PetscInt           ntypes;

  PetscFunctionBegin;
  PetscCall(KFFlexSolverCreate_Private(comm, NULL, &solver));
  PetscCall(PetscObjectSetOptionsPrefix((PetscObject)solver, prefix));
  PetscCall(KFFlexSolverSetFromOptions(solver));
  chosen = ((PetscObject)solver)->type_name;
  PetscCall(KFFlexSolverGetTypeNames(&ntypes, &names));
  for (PetscInt i = 0; i < ntypes; i++) { /* the options of the types not chosen are checked too */
    PetscBool same;

    PetscCall(PetscStrcmp(names[i], chosen, &same));
    if (same) continue;
    PetscCall(KFFlexSolverSetType(solver, names[i]));
    PetscCall(KFFlexSolverTypeOptions(solver));
    chosen = ((PetscObject)solver)->type_name;
  }
  PetscCall(KFFlexSolverDestroy(&solver));
  PetscCall(KFMumpsCheckOptions(comm, prefix));
  PetscCall(KFHeldDofsOptions(comm, prefix, &cond_max));
  PetscFunctionReturn(0);
}

/* The refinement steps a block may take when -kf_refine was not given: 1 behind a full-rank factor (its first
   residual is near rounding, ~6e-7 on the 1M-dof solid), 5 behind a block low-rank one, whose forward error is about
   the dropping tolerance times K's condition number: 0.1 after the first solve of the 1M-dof solid at -kf_blr 1e-8,
   each step winning a factor ~170, so 3 steps reach 1e-6. */
static PetscErrorCode KFFlexSolverRefineSteps(KFFlexSolver solver)
{
  PetscReal blr;

  PetscFunctionBegin;
  if (solver->refine_set) PetscFunctionReturn(0);
  PetscCall(KFMumpsGetBLR(PetscObjectComm((PetscObject)solver), ((PetscObject)solver)->prefix, &blr));
  if (blr > 0) solver->refine = 5;
  PetscFunctionReturn(0);
}

/* The implementation's factorization(s). An expansion point inside the band (a negative shift,
   KFFlexSolverSetInteriorShift) is factored indefinite by the monolithic implementation whatever the type. */
PetscErrorCode KFFlexSolverSetUp(KFFlexSolver solver)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(solver, KF_FLEXSOLVER_CLASSID, 1);
  if (solver->setup) PetscFunctionReturn(0);
  if (!solver->setfromoptionscalled) PetscCall(KFFlexSolverSetFromOptions(solver));
  PetscCall(KFFlexSolverRefineSteps(solver));
  if (solver->shift < 0) PetscCall(KFFlexSolverSetType(solver, KFFLEXSOLVERMONOLITHIC));
  PetscCall((*solver->ops->setup)(solver));
  if (solver->handoff) { /* the type found it does not apply here: the one it named sets the solver up instead */
    const char *handoff = solver->handoff;

    solver->handoff = NULL;
    PetscCall(KFFlexSolverSetType(solver, handoff));
    PetscCall((*solver->ops->setup)(solver));
  }
  solver->setup = PETSC_TRUE;
  PetscFunctionReturn(0);
}

/* One pass: X = K+ B with the factor: loads made self-equilibrated, held dofs at zero, a block solve, the result
   projected onto the flexible subspace (M-orthogonal to the rigid modes). PB, when asked for, receives the
   self-equilibrated loads P B (the residual's right-hand side: formed once per block, not again per residual).
   consume: B is the caller's scratch (a residual about to be destroyed), projected and held in place, not copied. */
static PetscErrorCode KFFlexSolverSolveOnce(KFFlexSolver solver, Mat B, Mat X, Mat *PB, PetscBool consume)
{
  KFSystem     sys = solver->sys;
  Mat          W;
  PetscScalar *held = NULL;
  PetscInt     rstart, rend, p, lda;

  PetscFunctionBegin;
  if (consume) W = B;
  else PetscCall(KFDenseCopyCreate(B, &W));
  PetscCall(KFProjectFlexible(sys, W, PETSC_TRUE));
  PetscCall(MatGetSize(W, NULL, &p));
  if (solver->nheld) { /* the held rows at zero for the solve, their values kept for P B */
    PetscScalar *w;

    PetscCall(PetscMalloc1(solver->nheld * p + 1, &held));
    PetscCall(MatGetOwnershipRange(W, &rstart, &rend));
    PetscCall(MatDenseGetLDA(W, &lda));
    PetscCall(MatDenseGetArray(W, &w));
    for (PetscInt k = 0; k < solver->nheld; k++)
      if (solver->held[k] >= rstart && solver->held[k] < rend)
        for (PetscInt j = 0; j < p; j++) {
          held[k + j * solver->nheld]              = w[(solver->held[k] - rstart) + j * lda];
          w[(solver->held[k] - rstart) + j * lda] = 0;
        }
    PetscCall(MatDenseRestoreArray(W, &w));
  }
  {
    PetscLogDouble t0, t1;

    PetscCall(PetscTime(&t0));
    PetscCall((*solver->ops->solve)(solver, W, X));
    PetscCall(PetscTime(&t1));
    solver->perf.solve_seconds += t1 - t0;
    solver->perf.solve_calls++;
    solver->perf.solve_columns += p;
  }
  PetscCall(KFProjectFlexible(sys, X, PETSC_FALSE));
  if (PB && solver->nheld) {
    PetscScalar *w;

    PetscCall(MatDenseGetArray(W, &w));
    for (PetscInt k = 0; k < solver->nheld; k++)
      if (solver->held[k] >= rstart && solver->held[k] < rend)
        for (PetscInt j = 0; j < p; j++) w[(solver->held[k] - rstart) + j * lda] = held[k + j * solver->nheld];
    PetscCall(MatDenseRestoreArray(W, &w));
  }
  PetscCall(PetscFree(held));
  if (PB) *PB = W;
  else if (!consume) PetscCall(MatDestroy(&W));
  PetscFunctionReturn(0);
}

/* R = P B - K_S X with K_S X accumulated in extended precision (the residual must be free of K's rounding); its
   relative Frobenius norm against P B (PB: the self-equilibrated loads, nb: their norm) */
static PetscErrorCode KFFlexSolverResidual(KFFlexSolver solver, Mat PB, PetscReal nb, Mat X, Mat *R, PetscReal *rel)
{
  KFSystem  sys = solver->sys;
  PetscReal nr;

  PetscFunctionBegin;
  PetscCall(KFMatMultExtended(sys->Ks, X, R));
  PetscCall(MatAYPX(*R, -1.0, PB, SAME_NONZERO_PATTERN)); /* in place: P B - K_S X */
  PetscCall(MatNorm(*R, NORM_FROBENIUS, &nr));
  *rel = nb > 0 ? nr / nb : 0;
  PetscFunctionReturn(0);
}

/* Whether the first residual of a block is certainly at most -kf_refine_rtol, from K_S X in double and the bound on
   its rounding (KFMatMultBounded, one sweep of K_S at the cost of a plain product): the exact ||P B - K_S X||_F is at
   most the double residual's norm plus the bounds' norm plus the subtraction's rounding (u per entry). When it is, no
   refinement follows and the residual's entries are not needed: the double-double product (about twice the sweep's
   cost, 0.2 s of the 57k-dof solid's 36 block solves) is not made, and X, hence the model, is what it was. Otherwise
   (a residual near or above the threshold, or a stiff block whose double product is all rounding) the caller measures
   it in double-double as before, so refinement is decided and driven by the same figures. The margin 1e-8 covers the
   norms' own rounding. rel: the double residual's relative norm (within the bounds' of the exact one). */
static PetscErrorCode KFFlexSolverResidualBelow(KFFlexSolver solver, Mat PB, PetscReal nb, Mat X, PetscReal *rel, PetscBool *below)
{
  KFSystem  sys = solver->sys;
  Mat       Y, Yb;
  PetscReal nr, nbound;

  PetscFunctionBegin;
  PetscCall(KFMatMultBounded(sys->Ks, X, &Y, &Yb));
  PetscCall(MatAYPX(Y, -1.0, PB, SAME_NONZERO_PATTERN)); /* P B - K_S X, K_S X in double */
  PetscCall(MatNorm(Y, NORM_FROBENIUS, &nr));
  PetscCall(MatNorm(Yb, NORM_FROBENIUS, &nbound));
  PetscCall(MatDestroy(&Y));
  PetscCall(MatDestroy(&Yb));
  nbound += PETSC_MACHINE_EPSILON * nr;
  *rel   = nb > 0 ? nr / nb : 0;
  *below = (PetscBool)(nb > 0 && (nr + nbound) * (1 + 1e-8) <= solver->refine_rtol * nb);
  PetscCall(PetscInfo(solver, "first residual %.3e in double, its rounding bound %.3e (relative): %s\n", (double)*rel, nb > 0 ? (double)(nbound / nb) : 0.0, *below ? "below -kf_refine_rtol" : "measured in double-double"));
  PetscFunctionReturn(0);
}

/* Refinement steps X += K+ R while the residual is above rtol, at most maxit, ending when a step does not bring it
   below shrink x the one before (the factor's floor). R: the current residual (replaced), rel its norm. */
static PetscErrorCode KFFlexSolverRefine(KFFlexSolver solver, Mat PB, PetscReal nb, Mat X, Mat *R, PetscReal *rel, PetscInt maxit, PetscReal shrink, PetscReal rtol)
{
  PetscReal before = PETSC_MAX_REAL;
  Mat       dX;

  PetscFunctionBegin;
  for (PetscInt it = 0; it < maxit && *rel > rtol && *rel < shrink * before; it++) {
    PetscCall(MatDuplicate(X, MAT_DO_NOT_COPY_VALUES, &dX));
    PetscCall(KFFlexSolverSolveOnce(solver, *R, dX, NULL, PETSC_TRUE));
    solver->perf.refinement_solves++;
    PetscCall(MatAXPY(X, 1.0, dX, SAME_NONZERO_PATTERN));
    PetscCall(MatDestroy(&dX));
    PetscCall(MatDestroy(R));
    before = *rel;
    PetscCall(KFFlexSolverResidual(solver, PB, nb, X, R, rel));
  }
  PetscFunctionReturn(0);
}

/* X = K+ B, refined against K_S itself when the residual says so: the residual (I - M Phi Phi^T) B - K_S X of the
   first solve is measured, and only above -kf_refine_rtol goes through the factor again (up to -kf_refine steps,
   fewer when a step does not halve the residual: the factor can do no better, more solves would be wasted).
   Whether a block is refined at all is a plain threshold (no adaptive rule that rounding could flip between 1 and 2
   ranks); the halving rule only ends steps at the factor's floor, where one more changes X by no more than that.
   A stiff structure's solve loses about eps * cond digits; one step wins most of them back (the moments of a
   20,000-dof frame moved by 3e-10 with it). Always refining doubled the solves of every reduction; a well-conditioned
   factor's residual is near rounding, and the check costs one matrix product: in double where that decides it
   (KFFlexSolverResidualBelow), else in double-double.
   A block still above the threshold is escalated, never left silently: more steps while each gains 10 % (slow but
   real convergence the halving rule cut short), then, with a block low-rank factor, the factor refactored full rank
   and the block solved again. One left above after that is counted (perf.blocks_unconverged): the reducer says so in
   its summary, report and last line, and the verification's direct solves decide the verdict.
   floor: the steps (at least one) are taken whatever the residual, down to the factor's floor; escalation and the
   counts still go by -kf_refine_rtol (KFFlexSolverApplyRefined). */
static PetscErrorCode KFFlexSolverApply_Private(KFFlexSolver solver, Mat B, Mat X, PetscBool floor)
{
  Mat       R, PB = NULL;
  PetscReal rel = 0, nb = 0;
  PetscBool check;

  PetscFunctionBegin;
  PetscCall(KFFlexSolverSetUp(solver));
  PetscCall(PetscLogEventBegin(KF_EVENT_SOLVE, 0, 0, 0, 0));
  check = (PetscBool)((solver->refine > 0 || floor) && solver->shift == 0);
  PetscCall(KFFlexSolverSolveOnce(solver, B, X, check ? &PB : NULL, PETSC_FALSE));
  solver->perf.blocks++;
  if (check) {
    PetscBool below = PETSC_FALSE;

    PetscCall(MatNorm(PB, NORM_FROBENIUS, &nb));
    /* tried while it decides at least as many blocks as it leaves undecided (after a few): where the double product
       is mostly rounding (a stiff model), each block would pay for both sweeps */
    if (!floor && solver->refine_rtol > 0 && (solver->residual_undecided < 4 || solver->residual_decided >= solver->residual_undecided)) {
      PetscCall(KFFlexSolverResidualBelow(solver, PB, nb, X, &rel, &below));
      if (below) solver->residual_decided++;
      else solver->residual_undecided++;
    }
    if (below) {
      solver->perf.residual_first_max = PetscMax(solver->perf.residual_first_max, rel);
      solver->perf.residual_final_max = PetscMax(solver->perf.residual_final_max, rel);
      PetscCall(MatDestroy(&PB));
      PetscCall(PetscLogEventEnd(KF_EVENT_SOLVE, 0, 0, 0, 0));
      PetscFunctionReturn(0);
    }
    PetscCall(KFFlexSolverResidual(solver, PB, nb, X, &R, &rel));
    solver->perf.residual_first_max = PetscMax(solver->perf.residual_first_max, rel);
    if (rel > solver->refine_rtol) solver->perf.blocks_refined++;
    PetscCall(KFFlexSolverRefine(solver, PB, nb, X, &R, &rel, floor ? PetscMax(solver->refine, 1) : solver->refine, 0.5, floor ? 0.0 : solver->refine_rtol));
    if (rel > solver->refine_rtol && solver->refine_rtol > 0) { /* escalation (-kf_refine_rtol 0 asks for the steps, not a residual) */
      PetscBool refactored;

      solver->perf.blocks_escalated++;
      PetscCall(KFFlexSolverRefine(solver, PB, nb, X, &R, &rel, 4 * solver->refine + 10, 0.9, solver->refine_rtol));
      if (rel > solver->refine_rtol && solver->ops->refactor) PetscCall((*solver->ops->refactor)(solver, &refactored));
      else refactored = PETSC_FALSE;
      if (refactored) {
        PetscCall(MatDestroy(&R));
        PetscCall(KFFlexSolverSolveOnce(solver, B, X, NULL, PETSC_FALSE));
        PetscCall(KFFlexSolverResidual(solver, PB, nb, X, &R, &rel));
        PetscCall(KFFlexSolverRefine(solver, PB, nb, X, &R, &rel, 4 * solver->refine + 10, 0.9, solver->refine_rtol));
      }
    }
    PetscCall(MatDestroy(&R));
    PetscCall(MatDestroy(&PB));
    solver->perf.residual_final_max = PetscMax(solver->perf.residual_final_max, rel);
    if (rel > solver->refine_rtol) solver->perf.blocks_unconverged++;
  }
  PetscCall(PetscLogEventEnd(KF_EVENT_SOLVE, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

PetscErrorCode KFFlexSolverApply(KFFlexSolver solver, Mat B, Mat X)
{
  PetscFunctionBegin;
  PetscCall(KFFlexSolverApply_Private(solver, B, X, PETSC_FALSE));
  PetscFunctionReturn(0);
}

/* X = K+ B refined whatever its first residual, until a step no longer halves it (-kf_refine steps, at least one):
   for a reference (the full-order moments), whose every digit a comparison with a reduced model would otherwise
   charge to the model. A residual below -kf_refine_rtol is no forward error below it: a stiff structure's solve loses
   about eps * cond digits of X that the residual, scaled by K, hardly shows. */
PetscErrorCode KFFlexSolverApplyRefined(KFFlexSolver solver, Mat B, Mat X)
{
  PetscFunctionBegin;
  PetscCall(KFFlexSolverApply_Private(solver, B, X, PETSC_TRUE));
  PetscFunctionReturn(0);
}

PetscErrorCode KFFlexSolverGetPerf(KFFlexSolver solver, KFFlexSolverPerf *perf)
{
  PetscFunctionBegin;
  *perf = solver->perf;
  PetscFunctionReturn(0);
}

/* the accounting set back: the verification borrows the factor for its eigensolves, which are not the reduction's
   solves */
PetscErrorCode KFFlexSolverSetPerf_Private(KFFlexSolver solver, const KFFlexSolverPerf *perf)
{
  PetscFunctionBegin;
  solver->perf = *perf;
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

PetscErrorCode KFSystemGetFactorCount(KFSystem sys, PetscInt *n)
{
  PetscFunctionBegin;
  *n = sys->nfactor;
  PetscFunctionReturn(0);
}

PetscErrorCode KFFlexSolverGetSystem(KFFlexSolver solver, KFSystem *sys)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(solver, KF_FLEXSOLVER_CLASSID, 1);
  *sys = solver->sys;
  PetscFunctionReturn(0);
}

/* the same as a value, for the declarations of the stages that apply the solver */
PETSC_INTERN KFSystem KFFlexSolverSystem_Private(KFFlexSolver solver)
{
  return solver->sys;
}
