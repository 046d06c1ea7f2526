#include <kryflex_impl.h>

/* Copies the active columns [l, k) of a BV into a new dense Mat. */
static PetscErrorCode KFBVColumnsToMat(BV V, PetscInt l, PetscInt k, Mat *X)
{
  Mat      A;
  PetscInt l0, k0;

  PetscFunctionBegin;
  PetscCall(BVGetActiveColumns(V, &l0, &k0));
  PetscCall(BVSetActiveColumns(V, l, k));
  PetscCall(BVGetMat(V, &A));
  PetscCall(MatDuplicate(A, MAT_COPY_VALUES, X));
  PetscCall(BVRestoreMat(V, &A));
  PetscCall(BVSetActiveColumns(V, l0, k0));
  PetscFunctionReturn(0);
}

/* Appends the columns of W to V, each M-orthonormalized against all before it (Gram-Schmidt with refinement);
   a column whose M-norm falls below tol times its norm before orthogonalization is linearly dependent on the
   basis and is dropped (deflation). */
static PetscErrorCode KFBVAppendDeflated(BV V, Mat W, PetscReal tol, PetscInt *k, PetscInt *ndeflated)
{
  PetscInt p;

  PetscFunctionBegin;
  PetscCall(MatGetSize(W, NULL, &p));
  for (PetscInt j = 0; j < p; j++) {
    Vec       w;
    PetscReal norm0, norm;
    PetscBool lindep;
    PetscCall(MatDenseGetColumnVecRead(W, j, &w));
    PetscCall(BVInsertVec(V, *k, w));
    PetscCall(MatDenseRestoreColumnVecRead(W, j, &w));
    PetscCall(BVNormColumn(V, *k, NORM_2, &norm0));
    if (norm0 == 0) {
      (*ndeflated)++;
      continue;
    }
    PetscCall(BVSetActiveColumns(V, 0, *k + 1));
    /* orthogonalize only: BVOrthonormalizeColumn would swap a dependent column for a random vector */
    PetscCall(BVOrthogonalizeColumn(V, *k, NULL, &norm, &lindep));
    if (lindep || norm <= tol * norm0) (*ndeflated)++;
    else {
      PetscCall(BVScaleColumn(V, *k, 1.0 / norm));
      (*k)++;
    }
  }
  PetscCall(BVSetActiveColumns(V, 0, *k));
  PetscFunctionReturn(0);
}

PetscErrorCode KFKrylovBasis(KFFlexSolver solver, PetscInt nin, PetscInt nout, PetscReal tol, BV *Vout, PetscInt *ndeflated)
{
  KFSystem sys = solver->sys;
  KFScene  s   = sys->scene;
  PetscInt a = s->ninputs, t = s->noutputs, maxcols = a * nin + t * nout, k = 0, ndefl = 0, progress_min = 50000;
  BV       V;

  PetscFunctionBegin;
  PetscCheck(nin >= 1 && nout >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "the Krylov basis needs at least one input block (got %" PetscInt_FMT " input and %" PetscInt_FMT " output blocks)", nin, nout);
  PetscCheck(tol > 0 && tol < 1, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "deflation tolerance must lie in (0, 1); got %g", (double)tol);
  PetscOptionsBegin(s->comm, NULL, "kryflex Krylov basis", "KFKrylovBasis");
  PetscCall(PetscOptionsInt("-kf_progress_min_dofs", "Print a progress line per Krylov block from this many system dofs on (default 50000)", "KFKrylovBasis", progress_min, &progress_min, NULL));
  PetscOptionsEnd();
  PetscCall(KFFlexSolverSetUp(solver));
  PetscCall(BVCreate(s->comm, &V));
  PetscCall(BVSetSizes(V, s->nsys_local, s->nsys, maxcols));
  PetscCall(BVSetMatrix(V, sys->Ms, PETSC_FALSE));
  /* classical Gram-Schmidt, refined when the norm drops (DGKS): as safe as always refining, half the work */
  PetscCall(BVSetOrthogonalization(V, BV_ORTHOG_CGS, BV_ORTHOG_REFINE_IFNEEDED, PETSC_DEFAULT, BV_ORTHOG_BLOCK_GS));
  PetscCall(BVSetFromOptions(V));
  for (int source = 0; source < 2; source++) {
    PetscInt nblocks = source ? nout : nin;
    Mat      B       = source ? sys->Ht : sys->G, W = NULL, Prev = NULL;
    for (PetscInt blk = 0; blk < nblocks; blk++) {
      PetscInt k0 = k, p;
      if (blk == 0) PetscCall(MatDuplicate(B, MAT_DO_NOT_COPY_VALUES, &W));
      else {
        Mat MP;
        PetscCall(MatMatMult(sys->Ms, Prev, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &MP));
        PetscCall(MatDuplicate(Prev, MAT_DO_NOT_COPY_VALUES, &W));
        PetscCall(MatDestroy(&Prev));
        B = MP;
      }
      PetscCall(KFFlexSolverApply(solver, B, W));
      if (blk > 0) PetscCall(MatDestroy(&B));
      PetscCall(PetscLogEventBegin(KF_EVENT_ORTHO, 0, 0, 0, 0));
      PetscCall(KFBVAppendDeflated(V, W, tol, &k, &ndefl));
      PetscCall(PetscLogEventEnd(KF_EVENT_ORTHO, 0, 0, 0, 0));
      PetscCall(MatDestroy(&W));
      PetscCall(MatGetSize(source ? sys->Ht : sys->G, NULL, &p));
      if (s->nsys >= progress_min) PetscCall(KFProgress(s->comm, "Krylov %s block %" PetscInt_FMT "/%" PetscInt_FMT ": %" PetscInt_FMT " of %" PetscInt_FMT " columns kept (basis %" PetscInt_FMT ")", source ? "output" : "input", blk + 1, nblocks, k - k0, p, k));
      if (k == k0) break; /* the block deflated away: the Krylov space is exhausted */
      PetscCall(KFInterruptCheck(s->comm)); /* a command's SIGINT/SIGTERM: every rank stops after the same block */
      PetscCall(KFBVColumnsToMat(V, k0, k, &Prev));
    }
    PetscCall(MatDestroy(&Prev));
  }
  PetscCall(BVSetActiveColumns(V, 0, k));
  *Vout = V;
  if (ndeflated) *ndeflated = ndefl;
  PetscFunctionReturn(0);
}
