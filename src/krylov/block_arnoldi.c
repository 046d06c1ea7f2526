#include <kryflex/krylovimpl.h>

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
static PetscErrorCode KFBVAppendDeflated(KFSystem sys, BV V, Mat W, PetscInt j0, PetscInt j1, PetscReal tol, PetscInt *k, PetscInt *ndeflated)
{
  Vec Mv, c, Pc;

  PetscFunctionBegin;
  PetscCall(MatCreateVecs(sys->Phi, &c, &Pc));
  PetscCall(VecDuplicate(Pc, &Mv));
  for (PetscInt j = j0; j < j1; j++) {
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
  PetscFunctionBegin;
  PetscCall(KFKrylovBasisDamped_Private(solver, nin, nout, tol, NULL, Vout, info));
  PetscFunctionReturn(0);
}

/* the same with the input chain of the damped second-order system (src/krylov/damped.c) when damp is not NULL */
PetscErrorCode KFKrylovBasisDamped_Private(KFFlexSolver solver, PetscInt nin, PetscInt nout, PetscReal tol, const KFKrylovDamping *damp, BV *Vout, KFKrylovInfo *info)
{
  KFDampedChain dch;
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
  if (damp) PetscCall(KFDampedChainCreate_Private(solver, damp, a * nin, &dch));
  for (PetscInt blk = 0; blk < nblocks; blk++) {
    /* input on even blocks while outputs remain, otherwise whichever chain has blocks left */
    int       src[2], nsrc = 0;
    Mat       Bs[2] = {NULL, NULL}, B, W;
    PetscInt  off[3] = {0, 0, 0}, p;
    PetscBool fresh[2] = {PETSC_FALSE, PETSC_FALSE};

    src[0] = (blk % 2 == 1 && made[1] < want[1]) || made[0] >= want[0] ? 1 : 0;
    made[src[0]]++;
    if (!done[src[0]]) nsrc = 1;
    if (nsrc && damp && !src[0]) { /* the damped input chain: its blocks' u halves join the basis (own solves) */
      Mat      U;
      PetscInt k0d = k, pu;

      nsrc = 0;
      PetscCall(KFDampedChainNext_Private(solver, &dch, sys->G, tol, &U));
      if (U) {
        PetscCall(MatGetSize(U, NULL, &pu));
        PetscCall(KFBVAppendDeflated(sys, V, U, 0, pu, tol, &k, &ndefl));
        PetscCall(MatDestroy(&U));
      } else done[0] = PETSC_TRUE;
      if (s->nsys >= progress_min) PetscCall(KFProgress(s->comm, "Krylov damped input block %" PetscInt_FMT "/%" PetscInt_FMT ": %" PetscInt_FMT " columns kept (basis %" PetscInt_FMT ")", made[0], want[0], k - k0d, k));
      PetscCall(KFInterruptCheck(s->comm));
    }
    /* the next block, when it belongs to the other chain, does not depend on this one: both go through the factor
       in one block solve (one MatMatSolve of a + t columns instead of two); a damped input block has its own solves */
    if (nsrc && blk + 1 < nblocks) {
      int next = ((blk + 1) % 2 == 1 && made[1] < want[1]) || made[0] >= want[0] ? 1 : 0;
      if (next != src[0] && !done[next] && !(damp && !next)) {
        src[1] = next;
        made[next]++;
        nsrc = 2;
      }
    }
    if (nsrc) {
      for (int q = 0; q < nsrc; q++) {
        const int c = src[q];
        if (!Prev[c]) Bs[q] = c ? sys->Ht : sys->G;
        else {
          PetscCall(MatMatMult(sys->Ms, Prev[c], MAT_INITIAL_MATRIX, PETSC_DEFAULT, &Bs[q]));
          PetscCall(MatDestroy(&Prev[c]));
          fresh[q] = PETSC_TRUE;
        }
        PetscCall(MatGetSize(Bs[q], NULL, &p));
        off[q + 1] = off[q] + p;
      }
      if (nsrc == 1) B = Bs[0];
      else PetscCall(KFDenseHStack(Bs[0], Bs[1], &B));
      PetscCall(MatDuplicate(B, MAT_DO_NOT_COPY_VALUES, &W));
      PetscCall(KFFlexSolverApply(solver, B, W));
      if (nsrc == 2) PetscCall(MatDestroy(&B));
      for (int q = 0; q < nsrc; q++)
        if (fresh[q]) PetscCall(MatDestroy(&Bs[q]));
      for (int q = 0; q < nsrc; q++) {
        const int      source = src[q];
        const PetscInt b      = blk + q, k0 = k;

        PetscCall(PetscLogEventBegin(KF_EVENT_ORTHO, 0, 0, 0, 0));
        /* each chain is an Arnoldi process of its own (its next block starts from its own orthonormalized block, not
           from one the other chain has been taken out of, which would leave its Krylov space); the basis collects
           both */
        {
          PetscInt kc0 = kc[source], dummy = 0;

          PetscCall(KFBVAppendDeflated(sys, chain[source], W, off[q], off[q + 1], tol, &kc[source], &dummy));
          if (kc[source] > kc0) {
            PetscCall(KFBVColumnsToMat(chain[source], kc0, kc[source], &Prev[source]));
            PetscCall(KFBVAppendDeflated(sys, V, Prev[source], 0, kc[source] - kc0, tol, &k, &ndefl));
          }
          ndefl += dummy;
          if (kc[source] == kc0) done[source] = PETSC_TRUE; /* the block deflated away: this chain's space is exhausted */
        }
        PetscCall(PetscLogEventEnd(KF_EVENT_ORTHO, 0, 0, 0, 0));
        if (s->nsys >= progress_min) PetscCall(KFProgress(s->comm, "Krylov %s block %" PetscInt_FMT "/%" PetscInt_FMT ": %" PetscInt_FMT " of %" PetscInt_FMT " columns kept (basis %" PetscInt_FMT ")", source ? "output" : "input", made[source], want[source], k - k0, off[q + 1] - off[q], k));
        info->block_end[b] = k;
      }
      PetscCall(MatDestroy(&W));
      PetscCall(KFInterruptCheck(s->comm)); /* a command's SIGINT/SIGTERM: every rank stops after the same block */
    } else info->block_end[blk] = k;
    if (nsrc == 2) blk++; /* the pair is done */
    info->nblocks = blk + 1;
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
  if (damp) PetscCall(KFDampedChainDestroy_Private(&dch));
  PetscCall(BVSetActiveColumns(V, 0, k));
  PetscCall(KFKrylovHealth(sys, V, k, &info->rigid_content, &info->orthogonality));
  PetscCall(BVSetActiveColumns(V, 0, k));
  info->ndeflated = ndefl;
  *Vout           = V;
  PetscFunctionReturn(0);
}
