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

/* v <- v - Phi (Phi^T M v): the rigid content a column picks up from Gram-Schmidt's rounding (DESIGN.md: it creeps
   back and grows with the number of moments) */
static PetscErrorCode KFRemoveRigid(KFSystem sys, Vec v, Vec Mv, Vec c, Vec Pc)
{
  PetscFunctionBegin;
  PetscCall(MatMult(sys->Ms, v, Mv));
  PetscCall(MatMultTranspose(sys->Phi, Mv, c));
  PetscCall(MatMult(sys->Phi, c, Pc));
  PetscCall(VecAXPY(v, -1.0, Pc));
  PetscFunctionReturn(0);
}

/* Appends the columns of W to V, each M-orthonormalized against all before it (Gram-Schmidt with refinement) and
   kept M-orthogonal to the rigid modes (orthogonalize, remove the rigid content, orthogonalize again, so that neither
   pass leaves rounding of the other behind); a column whose M-norm falls below tol times its norm before
   orthogonalization is linearly dependent on the basis and is dropped (deflation). */
static PetscErrorCode KFBVAppendDeflated(KFSystem sys, BV V, Mat W, PetscReal tol, PetscInt *k, PetscInt *ndeflated)
{
  PetscInt p;
  Vec      Mv, c, Pc;

  PetscFunctionBegin;
  PetscCall(MatGetSize(W, NULL, &p));
  PetscCall(MatCreateVecs(sys->Phi, &c, &Pc));
  PetscCall(VecDuplicate(Pc, &Mv));
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
    if (!lindep && norm > tol * norm0 && sys->nrigid > 0) {
      Vec v;

      PetscCall(BVGetColumn(V, *k, &v));
      PetscCall(KFRemoveRigid(sys, v, Mv, c, Pc));
      PetscCall(BVRestoreColumn(V, *k, &v));
      PetscCall(BVOrthogonalizeColumn(V, *k, NULL, &norm, &lindep));
    }
    if (lindep || norm <= tol * norm0) (*ndeflated)++;
    else {
      PetscCall(BVScaleColumn(V, *k, 1.0 / norm));
      (*k)++;
    }
  }
  PetscCall(BVSetActiveColumns(V, 0, *k));
  PetscCall(VecDestroy(&Mv));
  PetscCall(VecDestroy(&c));
  PetscCall(VecDestroy(&Pc));
  PetscFunctionReturn(0);
}

/* max |Phi^T M V| and max |V^T M V - I| of the finished basis: what the user is told about its numerical health */
static PetscErrorCode KFKrylovHealth(KFSystem sys, BV V, PetscInt k, PetscReal *rigid, PetscReal *orth)
{
  Mat        A, MA;
  PetscInt   r;
  PetscReal *c, *g;

  PetscFunctionBegin;
  *rigid = *orth = 0;
  if (!k) PetscFunctionReturn(0);
  PetscCall(MatGetSize(sys->Phi, NULL, &r));
  PetscCall(BVSetActiveColumns(V, 0, k));
  PetscCall(BVGetMat(V, &A));
  PetscCall(MatMatMult(sys->Ms, A, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &MA));
  PetscCall(PetscMalloc2(PetscMax(r * k, 1), &c, k * k, &g));
  if (r) PetscCall(KFMatTransposeMatMultGather(sys->Phi, MA, c));
  PetscCall(KFMatTransposeMatMultGather(A, MA, g));
  PetscCall(BVRestoreMat(V, &A));
  PetscCall(MatDestroy(&MA));
  for (PetscInt i = 0; i < r * k; i++) *rigid = PetscMax(*rigid, PetscAbsReal(c[i]));
  for (PetscInt j = 0; j < k; j++)
    for (PetscInt i = 0; i < k; i++) *orth = PetscMax(*orth, PetscAbsReal(g[i + j * k] - (i == j)));
  PetscCall(PetscFree2(c, g));
  PetscFunctionReturn(0);
}

PetscErrorCode KFKrylovInfoReset(KFKrylovInfo *info)
{
  PetscFunctionBegin;
  if (!info) PetscFunctionReturn(0);
  PetscCall(PetscFree(info->block_end));
  PetscCall(PetscMemzero(info, sizeof(*info)));
  PetscFunctionReturn(0);
}

PetscErrorCode KFKrylovBasis(KFFlexSolver solver, PetscInt nin, PetscInt nout, PetscReal tol, BV *Vout, PetscInt *ndeflated)
{
  KFKrylovInfo info;

  PetscFunctionBegin;
  PetscCall(PetscMemzero(&info, sizeof(info)));
  PetscCall(KFKrylovBasisWithInfo(solver, nin, nout, tol, Vout, &info));
  if (ndeflated) *ndeflated = info.ndeflated;
  PetscCall(KFKrylovInfoReset(&info));
  PetscFunctionReturn(0);
}

/* Blocks alternate input, output, input, output ... while both chains have blocks left, then the rest: the first c
   blocks are then the basis of c moments for any c, so one basis serves a search over the number of moments. A chain
   whose block deflates away is exhausted (its Krylov space is spanned); its later blocks add nothing. */
PetscErrorCode KFKrylovBasisWithInfo(KFFlexSolver solver, PetscInt nin, PetscInt nout, PetscReal tol, BV *Vout, KFKrylovInfo *info)
{
  KFSystem sys = solver->sys;
  KFScene  s   = sys->scene;
  PetscInt a = s->ninputs, t = s->noutputs, maxcols = a * nin + t * nout, k = 0, ndefl = 0, progress_min = 50000;
  PetscInt made[2] = {0, 0}, want[2] = {nin, nout}, nblocks = nin + nout;
  PetscBool done[2] = {PETSC_FALSE, PETSC_FALSE};
  Mat      Prev[2] = {NULL, NULL};
  BV       V, chain[2] = {NULL, NULL};
  PetscInt kc[2] = {0, 0};

  PetscFunctionBegin;
  PetscCheck(nin >= 1 && nout >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "the Krylov basis needs at least one input block (got %" PetscInt_FMT " input and %" PetscInt_FMT " output blocks)", nin, nout);
  PetscCheck(tol > 0 && tol < 1, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "deflation tolerance must lie in (0, 1); got %g", (double)tol);
  PetscOptionsBegin(s->comm, NULL, "kryflex Krylov basis", "KFKrylovBasis");
  PetscCall(PetscOptionsInt("-kf_progress_min_dofs", "Print a progress line per Krylov block from this many system dofs on (default 50000)", "KFKrylovBasis", progress_min, &progress_min, NULL));
  PetscOptionsEnd();
  PetscCall(KFFlexSolverSetUp(solver));
  PetscCall(PetscMemzero(info, sizeof(*info)));
  PetscCall(PetscMalloc1(nblocks, &info->block_end));
  PetscCall(BVCreate(s->comm, &V));
  PetscCall(BVSetSizes(V, s->nsys_local, s->nsys, PetscMax(maxcols, 1)));
  PetscCall(BVSetMatrix(V, sys->Ms, PETSC_FALSE));
  /* classical Gram-Schmidt, refined when the norm drops (DGKS): as safe as always refining, half the work */
  PetscCall(BVSetOrthogonalization(V, BV_ORTHOG_CGS, BV_ORTHOG_REFINE_IFNEEDED, PETSC_DEFAULT, BV_ORTHOG_BLOCK_GS));
  PetscCall(BVSetFromOptions(V));
  for (int c = 0; c < 2; c++) {
    PetscCall(BVDuplicateResize(V, PetscMax(c ? t * nout : a * nin, 1), &chain[c]));
    PetscCall(BVSetActiveColumns(chain[c], 0, 0));
  }
  for (PetscInt blk = 0; blk < nblocks; blk++) {
    /* input on even blocks while outputs remain, otherwise whichever chain has blocks left */
    int      source = (blk % 2 == 1 && made[1] < want[1]) || made[0] >= want[0] ? 1 : 0;
    Mat      B = source ? sys->Ht : sys->G, W;
    PetscInt k0 = k, p;

    made[source]++;
    if (!done[source]) {
      if (!Prev[source]) PetscCall(MatDuplicate(B, MAT_DO_NOT_COPY_VALUES, &W));
      else {
        PetscCall(MatMatMult(sys->Ms, Prev[source], MAT_INITIAL_MATRIX, PETSC_DEFAULT, &B));
        PetscCall(MatDuplicate(Prev[source], MAT_DO_NOT_COPY_VALUES, &W));
        PetscCall(MatDestroy(&Prev[source]));
      }
      PetscCall(KFFlexSolverApply(solver, B, W));
      if (made[source] > 1) PetscCall(MatDestroy(&B));
      PetscCall(PetscLogEventBegin(KF_EVENT_ORTHO, 0, 0, 0, 0));
      /* each chain is an Arnoldi process of its own (its next block starts from its own orthonormalized block, not
         from one the other chain has been taken out of, which would leave its Krylov space); the basis collects both */
      {
        PetscInt kc0 = kc[source], dummy = 0;

        PetscCall(KFBVAppendDeflated(sys, chain[source], W, tol, &kc[source], &dummy));
        if (kc[source] > kc0) {
          PetscCall(KFBVColumnsToMat(chain[source], kc0, kc[source], &Prev[source]));
          PetscCall(KFBVAppendDeflated(sys, V, Prev[source], tol, &k, &ndefl));
        }
        ndefl += dummy;
        if (kc[source] == kc0) done[source] = PETSC_TRUE; /* the block deflated away: this chain's space is exhausted */
      }
      PetscCall(PetscLogEventEnd(KF_EVENT_ORTHO, 0, 0, 0, 0));
      PetscCall(MatDestroy(&W));
      PetscCall(MatGetSize(source ? sys->Ht : sys->G, NULL, &p));
      if (s->nsys >= progress_min) PetscCall(KFProgress(s->comm, "Krylov %s block %" PetscInt_FMT "/%" PetscInt_FMT ": %" PetscInt_FMT " of %" PetscInt_FMT " columns kept (basis %" PetscInt_FMT ")", source ? "output" : "input", made[source], want[source], k - k0, p, k));
      PetscCall(KFInterruptCheck(s->comm)); /* a command's SIGINT/SIGTERM: every rank stops after the same block */
    }
    info->block_end[blk] = k;
    info->nblocks        = blk + 1;
    if (done[0] && (done[1] || !nout)) { /* both chains exhausted: later blocks would add nothing */
      for (PetscInt b = blk + 1; b < nblocks; b++) info->block_end[b] = k;
      info->nblocks = nblocks;
      break;
    }
  }
  PetscCall(MatDestroy(&Prev[0]));
  PetscCall(MatDestroy(&Prev[1]));
  PetscCall(BVDestroy(&chain[0]));
  PetscCall(BVDestroy(&chain[1]));
  PetscCall(BVSetActiveColumns(V, 0, k));
  PetscCall(KFKrylovHealth(sys, V, k, &info->rigid_content, &info->orthogonality));
  PetscCall(BVSetActiveColumns(V, 0, k));
  info->ndeflated = ndefl;
  *Vout           = V;
  PetscFunctionReturn(0);
}
