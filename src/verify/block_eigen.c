/*
  The verification's sparse eigensolve with the reduction's flexible solver, in blocks. S = K+ M is M-self-adjoint on
  the flexible subspace; its largest eigenvalues theta = 1 / omega^2 are the lowest flexible modes. SLEPc 3.18's
  Krylov-Schur applies its spectral transformation one vector at a time (STApply: one pair of MUMPS triangular solves
  and one residual check per vector); only LOBPCG applies it to blocks (STApplyMat), and there as a preconditioner of
  the residuals K x - lambda M x, whose rounding floor (eps ||K|| / lambda_1) lies above the reference's 1e-10. So the
  space here is a block Krylov space of S (a few solves of many columns each: MUMPS solves a block at a fraction of
  the per-column cost of single vectors), its Ritz pairs in the M inner product, each accepted on SLEPc's own
  shift-and-invert rule: ||S x - theta x||_M / theta <= tol with x M-normalized.
*/
#include <kryflex_impl.h>
#include <petscblaslapack.h>

typedef struct {
  MPI_Comm     comm;
  KFFlexSolver solver;
  Mat          Ms;
  PetscInt     nl, N, rstart, b, maxdim, k; /* k: basis columns held */
  PetscReal    normM;                       /* ||M||_1: the scale of the rounding in an M-norm */
  PetscScalar *V, *MV, *W;                  /* nl x maxdim: the M-orthonormal basis, M V and S V */
  PetscInt     solves, columns;
} KFBlockKrylov;

/* a Mat over p contiguous local columns (leading dimension nl) */
static PetscErrorCode KFBlockWrap(KFBlockKrylov *bk, PetscScalar *a, PetscInt p, Mat *A)
{
  PetscFunctionBegin;
  PetscCall(MatCreateDense(bk->comm, bk->nl, PETSC_DECIDE, bk->N, p, a, A));
  PetscFunctionReturn(0);
}

/* Y = M X on p local columns */
static PetscErrorCode KFBlockMultM(KFBlockKrylov *bk, PetscScalar *x, PetscInt p, PetscScalar *y)
{
  Mat                X, Y;
  const PetscScalar *py;
  PetscInt           ld;

  PetscFunctionBegin;
  PetscCall(KFBlockWrap(bk, x, p, &X));
  PetscCall(KFMatMultDense(bk->Ms, X, &Y));
  PetscCall(MatDenseGetLDA(Y, &ld));
  PetscCall(MatDenseGetArrayRead(Y, &py));
  for (PetscInt j = 0; j < p; j++) PetscCall(PetscArraycpy(y + j * bk->nl, py + j * ld, bk->nl));
  PetscCall(MatDenseRestoreArrayRead(Y, &py));
  PetscCall(MatDestroy(&Y));
  PetscCall(MatDestroy(&X));
  PetscFunctionReturn(0);
}

/* Y = K+ B on p local columns: one block solve (with the solver's refinement) */
static PetscErrorCode KFBlockApplyK(KFBlockKrylov *bk, PetscScalar *b, PetscInt p, PetscScalar *y)
{
  Mat B, Y;

  PetscFunctionBegin;
  PetscCall(KFBlockWrap(bk, b, p, &B));
  PetscCall(KFBlockWrap(bk, y, p, &Y));
  PetscCall(KFFlexSolverApply(bk->solver, B, Y));
  PetscCall(MatDestroy(&B));
  PetscCall(MatDestroy(&Y));
  bk->solves++;
  bk->columns += p;
  PetscFunctionReturn(0);
}

/* the symmetric eigendecomposition of a replicated n x n A in place (eigenvalues ascending into w) */
static PetscErrorCode KFBlockSyev(PetscInt n, PetscReal A[], PetscReal w[])
{
  PetscBLASInt bn, lwork, info;
  PetscReal   *work;

  PetscFunctionBegin;
  if (!n) PetscFunctionReturn(0);
  for (PetscInt j = 0; j < n; j++)
    for (PetscInt i = 0; i < j; i++) A[i + j * n] = A[j + i * n] = 0.5 * (A[i + j * n] + A[j + i * n]);
  PetscCall(PetscBLASIntCast(n, &bn));
  lwork = 8 * PetscMax(3 * bn, 1);
  PetscCall(PetscMalloc1(lwork, &work));
  PetscCallBLAS("LAPACKsyev", LAPACKsyev_("V", "L", &bn, A, &bn, w, work, &lwork, &info));
  PetscCall(PetscFree(work));
  PetscCheck(!info, PETSC_COMM_SELF, PETSC_ERR_LIB, "the verification's block eigensolve: LAPACK syev failed on a %" PetscInt_FMT " x %" PetscInt_FMT " projected matrix (info %d)", n, n, (int)info);
  PetscFunctionReturn(0);
}

/* The candidates C (p columns, M C in MC) made M-orthonormal to the basis and among themselves, two passes; directions
   whose M-norm falls below 1e-10 of their candidate's, or below the rounding of the M-norm itself, are dropped (the
   space is invariant there),
   and at most qmax of the strongest are kept: *q columns, C and MC overwritten */
static PetscErrorCode KFBlockOrth(KFBlockKrylov *bk, PetscScalar *C, PetscScalar *MC, PetscInt p, PetscInt qmax, PetscInt *q)
{
  PetscReal   *coef, *G, *g, *U, g0 = 0, noise;
  PetscScalar *T;
  PetscInt     nl = bk->nl, np = p;

  PetscFunctionBegin;
  PetscCall(PetscMalloc5(PetscMax(bk->k * p, 1), &coef, p * p, &G, p, &g, p * p, &U, nl * p + 1, &T));
  for (PetscInt pass = 0; pass < 2 && np; pass++) {
    PetscInt nk = 0;

    if (!pass) { /* each candidate to unit M-norm first: S's columns span theta_1 / theta_nev in size, and a small one's
                    new direction must not be taken for the large ones' rounding */
      PetscCall(KFArrayTransposeMultGather(bk->comm, nl, np, C, nl, np, MC, nl, G));
      for (PetscInt j = 0; j < np; j++) {
        const PetscReal d = G[j + j * np] > 0 ? 1 / PetscSqrtReal(G[j + j * np]) : 0;

        for (PetscInt i = 0; i < nl; i++) {
          C[i + j * nl] *= d;
          MC[i + j * nl] *= d;
        }
      }
      g0 = 1;
    }
    if (bk->k) { /* C -= V (MV^T C); M C made again: updated, it would keep the rounding of the large part removed */
      PetscCall(KFArrayTransposeMultGather(bk->comm, nl, bk->k, bk->MV, nl, np, C, nl, coef));
      PetscCall(KFArrayMultSmall(nl, bk->k, np, bk->V, nl, coef, -1.0, C, nl));
      PetscCall(KFBlockMultM(bk, C, np, MC));
    }
    { /* the rounding of C^T M C: eps ||M|| ||c||_2^2, far above eps when M is singular (a unit M-norm with a large part
         in M's null space): a direction below it is M's null space or noise, not a new one */
      PetscReal e = 0;

      PetscCall(KFArrayTransposeMultGather(bk->comm, nl, np, C, nl, np, C, nl, G));
      for (PetscInt j = 0; j < np; j++) e = PetscMax(e, G[j + j * np]);
      noise = 1e3 * PETSC_MACHINE_EPSILON * bk->normM * e;
    }
    PetscCall(KFArrayTransposeMultGather(bk->comm, nl, np, C, nl, np, MC, nl, G));
    PetscCall(KFBlockSyev(np, G, g));
    /* the strongest directions first, scaled to unit M-norm: U = G's eigenvectors / sqrt(g) */
    for (PetscInt i = np - 1; i >= 0 && nk < (pass ? np : qmax); i--) {
      if (!(g[i] > PetscMax(1e-20 * g0, noise))) break;
      for (PetscInt r = 0; r < np; r++) U[r + nk * np] = G[r + i * np] / PetscSqrtReal(g[i]);
      nk++;
    }
    PetscCall(PetscArrayzero(T, nl * nk));
    PetscCall(KFArrayMultSmall(nl, np, nk, C, nl, U, 1.0, T, nl));
    PetscCall(PetscArraycpy(C, T, nl * nk));
    PetscCall(PetscArrayzero(T, nl * nk));
    PetscCall(KFArrayMultSmall(nl, np, nk, MC, nl, U, 1.0, T, nl));
    PetscCall(PetscArraycpy(MC, T, nl * nk));
    np = nk;
  }
  *q = np;
  PetscCall(PetscFree5(coef, G, g, U, T));
  PetscFunctionReturn(0);
}

/* The candidates appended to the basis (orthonormalized, at most b of them) and S applied to them: *q new columns */
static PetscErrorCode KFBlockExpand(KFBlockKrylov *bk, PetscScalar *C, PetscScalar *MC, PetscInt p, PetscInt *q)
{
  PetscInt nl = bk->nl;

  PetscFunctionBegin;
  PetscCall(KFBlockOrth(bk, C, MC, p, PetscMin(bk->b, bk->maxdim - bk->k), q));
  if (!*q) PetscFunctionReturn(0);
  PetscCall(PetscArraycpy(bk->V + bk->k * nl, C, nl * *q));
  PetscCall(PetscArraycpy(bk->MV + bk->k * nl, MC, nl * *q));
  PetscCall(KFBlockApplyK(bk, bk->MV + bk->k * nl, *q, bk->W + bk->k * nl));
  bk->k += *q;
  PetscFunctionReturn(0);
}

/* Rayleigh-Ritz: H = V^T M S V = MV^T W, its eigenvalues theta (descending) and vectors Y (k x k, the same order) */
static PetscErrorCode KFBlockRitz(KFBlockKrylov *bk, PetscReal theta[], PetscReal Y[])
{
  PetscInt   k = bk->k;
  PetscReal *H, *w;

  PetscFunctionBegin;
  PetscCall(PetscMalloc2(k * k, &H, k, &w));
  PetscCall(KFArrayTransposeMultGather(bk->comm, bk->nl, k, bk->MV, bk->nl, k, bk->W, bk->nl, H));
  PetscCall(KFBlockSyev(k, H, w));
  for (PetscInt j = 0; j < k; j++) {
    theta[j] = w[k - 1 - j];
    PetscCall(PetscArraycpy(Y + j * k, H + (k - 1 - j) * k, k));
  }
  PetscCall(PetscFree2(H, w));
  PetscFunctionReturn(0);
}

/* err[j] = ||(I - V V^T M) S x_j||_M / theta_j for the m Ritz vectors' S X (local columns): the part of S x outside
   the space, the residual of the block Krylov relation S V = V H + (next block), which is SLEPc's Krylov-Schur rule
   (its estimate beta |y_last| / theta). S x - theta x also holds V (V^T M S V - H) y, the asymmetry the solves'
   rounding leaves in V^T M S V: SLEPc's rule leaves it out too (on a clamped beam it is 5e-10 of theta_1 with every
   dof in the space, where the relation's residual is 1e-15). */
static PetscErrorCode KFBlockResidual(KFBlockKrylov *bk, PetscInt m, const PetscScalar *SX, const PetscReal theta[], PetscReal err[])
{
  PetscInt     nl = bk->nl;
  PetscScalar *R, *MR;
  PetscReal   *RR, *coef;

  PetscFunctionBegin;
  PetscCall(PetscMalloc4(nl * m + 1, &R, nl * m + 1, &MR, m * m + 1, &RR, bk->k * m + 1, &coef));
  PetscCall(PetscArraycpy(R, SX, nl * m));
  for (PetscInt pass = 0; pass < 2; pass++) { /* twice: S x is mostly inside the space */
    PetscCall(KFArrayTransposeMultGather(bk->comm, nl, bk->k, bk->MV, nl, m, R, nl, coef));
    PetscCall(KFArrayMultSmall(nl, bk->k, m, bk->V, nl, coef, -1.0, R, nl));
  }
  PetscCall(KFBlockMultM(bk, R, m, MR));
  PetscCall(KFArrayTransposeMultGather(bk->comm, nl, m, R, nl, m, MR, nl, RR));
  for (PetscInt j = 0; j < m; j++) err[j] = theta[j] > 0 ? PetscSqrtReal(PetscMax(RR[j + j * m], 0)) / theta[j] : PETSC_MAX_REAL;
  PetscCall(PetscFree4(R, MR, RR, coef));
  PetscFunctionReturn(0);
}

/* the leading m Ritz vectors X = V Y and their S X = W Y (no solve: S V is held) */
static PetscErrorCode KFBlockRitzVectors(KFBlockKrylov *bk, PetscInt m, const PetscReal Y[], PetscScalar *X, PetscScalar *SX)
{
  PetscInt nl = bk->nl;

  PetscFunctionBegin;
  PetscCall(PetscArrayzero(X, nl * m));
  PetscCall(KFArrayMultSmall(nl, bk->k, m, bk->V, nl, Y, 1.0, X, nl));
  if (SX) {
    PetscCall(PetscArrayzero(SX, nl * m));
    PetscCall(KFArrayMultSmall(nl, bk->k, m, bk->W, nl, Y, 1.0, SX, nl));
  }
  PetscFunctionReturn(0);
}

/* how many of err[0 .. m-1] are within tol, in order, and the largest */
static void KFBlockCount(PetscInt m, const PetscReal err[], PetscReal tol, PetscInt *got, PetscReal *worst)
{
  *got   = 0;
  *worst = 0;
  for (PetscInt j = 0; j < m; j++) {
    *worst = PetscMax(*worst, err[j]);
    if (err[j] <= tol && *got == j) (*got)++;
  }
}

/* The basis replaced by its leading m Ritz vectors (V Y, M V Y and S V Y = W Y: no solve) */
static PetscErrorCode KFBlockRestart(KFBlockKrylov *bk, PetscInt m, const PetscReal Y[])
{
  PetscInt     nl = bk->nl, k = bk->k;
  PetscScalar *T, *A[3] = {bk->V, bk->MV, bk->W};

  PetscFunctionBegin;
  PetscCall(PetscMalloc1(nl * m + 1, &T));
  for (PetscInt a = 0; a < 3; a++) {
    PetscCall(PetscArrayzero(T, nl * m));
    PetscCall(KFArrayMultSmall(nl, k, m, A[a], nl, Y, 1.0, T, nl));
    PetscCall(PetscArraycpy(A[a], T, nl * m));
  }
  bk->k = m;
  PetscCall(PetscFree(T));
  PetscFunctionReturn(0);
}

/* rank-independent start vectors (a hash of the global row and the column): serial and parallel runs start alike */
static PetscErrorCode KFBlockStart(KFBlockKrylov *bk, PetscInt p, PetscScalar *C)
{
  PetscFunctionBegin;
  for (PetscInt j = 0; j < p; j++)
    for (PetscInt i = 0; i < bk->nl; i++) {
      const PetscReal s = PetscSinReal(12.9898 * (PetscReal)(bk->rstart + i + 1) + 78.233 * (PetscReal)(j + 1)) * 43758.5453;

      C[i + j * bk->nl] = s - PetscFloorReal(s) - 0.5;
    }
  PetscFunctionReturn(0);
}

/* the modes found: a dense Mat of nev columns, the first got of them S x / ||S x||_M (the rest zero). The step through
   S purifies them as SLEPc does its shift-and-invert vectors (EPSSetPurify): the directions of the soft and the stiff
   modes the Ritz vector still holds shrink by their theta against the pair's, so that a family the structure leaves
   uncoupled (a beam's torsion from a lateral load) stays at its rounding. S X is held (W Y): no solve. */
static PetscErrorCode KFBlockModes(KFBlockKrylov *bk, PetscInt nev, PetscInt got, PetscScalar *SX, Mat *modes)
{
  PetscScalar *px, *MSX;
  PetscReal   *G;
  PetscInt     ld, nl = bk->nl;

  PetscFunctionBegin;
  PetscCall(PetscMalloc2(nl * got + 1, &MSX, got * got + 1, &G));
  if (got) {
    PetscCall(KFBlockMultM(bk, SX, got, MSX));
    PetscCall(KFArrayTransposeMultGather(bk->comm, nl, got, SX, nl, got, MSX, nl, G));
  }
  PetscCall(KFDenseCreate(bk->comm, nl, bk->N, nev, modes));
  PetscCall(MatDenseGetLDA(*modes, &ld));
  PetscCall(MatDenseGetArrayWrite(*modes, &px));
  for (PetscInt j = 0; j < nev; j++) {
    const PetscReal d = j < got ? 1 / PetscSqrtReal(G[j + j * got]) : 0;

    for (PetscInt i = 0; i < nl; i++) px[i + j * ld] = j < got ? d * SX[i + j * nl] : 0;
  }
  PetscCall(MatDenseRestoreArrayWrite(*modes, &px));
  PetscCall(PetscFree2(MSX, G));
  PetscFunctionReturn(0);
}

/*
  The nev lowest flexible modes: omega2 (ascending) and X (nsys x nev, M-orthonormal, created), *nconv of them
  converged to tol. Blocks of b = min(2 nev, 64) columns; the basis holds at most nev + 4b and restarts on its nev + b best Ritz vectors.
  *solves, *columns: the block solves made and the columns they solved.
*/
PETSC_INTERN PetscErrorCode KFVerifyBlockEigen(KFFlexSolver solver, KFSystem sys, PetscInt nev, PetscReal tol, PetscInt maxit, PetscInt *nconv, PetscReal omega2[], Mat *modes, PetscInt *solves, PetscInt *columns)
{
  KFBlockKrylov bk;
  PetscScalar  *C, *MC, *X, *SX;
  PetscReal    *theta, *Y, *err, worst = 0;
  PetscInt      q, it, got = 0, m = 0;

  PetscFunctionBegin;
  PetscCall(PetscMemzero(&bk, sizeof(bk)));
  bk.comm   = PetscObjectComm((PetscObject)sys->Ms);
  bk.solver = solver;
  bk.Ms     = sys->Ms;
  PetscCall(MatGetLocalSize(sys->Ms, &bk.nl, NULL));
  PetscCall(MatGetSize(sys->Ms, &bk.N, NULL));
  PetscCall(MatGetOwnershipRange(sys->Ms, &bk.rstart, NULL));
  PetscCall(MatNorm(sys->Ms, NORM_1, &bk.normM));
  bk.b      = PetscMin(PetscMin(2 * nev, 64), bk.N);
  bk.maxdim = PetscMin(nev + 4 * bk.b, bk.N);
  PetscCall(PetscCalloc3(bk.nl * bk.maxdim + 1, &bk.V, bk.nl * bk.maxdim + 1, &bk.MV, bk.nl * bk.maxdim + 1, &bk.W));
  PetscCall(PetscMalloc4(bk.nl * bk.maxdim + 1, &C, bk.nl * bk.maxdim + 1, &MC, bk.nl * nev + 1, &X, bk.nl * nev + 1, &SX));
  PetscCall(PetscMalloc3(bk.maxdim, &theta, bk.maxdim * bk.maxdim, &Y, nev, &err));
  /* the first block: S applied to the start vectors, so that every basis vector is in S's range (flexible, and
     consistent on M's null space) */
  q = bk.b;
  PetscCall(KFBlockStart(&bk, q, C));
  PetscCall(KFBlockMultM(&bk, C, q, MC));
  PetscCall(KFBlockApplyK(&bk, MC, q, C));
  PetscCall(KFBlockMultM(&bk, C, q, MC));
  PetscCall(KFBlockExpand(&bk, C, MC, q, &q));
  for (it = 0;; it++) {
    PetscInt last = q, p;

    m = PetscMin(nev, bk.k);
    PetscCall(KFBlockRitz(&bk, theta, Y));
    PetscCall(KFBlockRitzVectors(&bk, m, Y, X, SX));
    PetscCall(KFBlockResidual(&bk, m, SX, theta, err));
    KFBlockCount(m, err, tol, &got, &worst);
    if (got == nev || !last || it >= maxit) break; /* all converged, the space invariant (nothing more to find), or the steps spent */
    if (bk.k + bk.b > bk.maxdim) { /* restart on the best Ritz vectors; the next candidates are S of them */
      p = PetscMin(bk.k, nev + bk.b);
      PetscCall(KFBlockRestart(&bk, p, Y));
      PetscCall(PetscArraycpy(C, bk.W, bk.nl * p));
    } else { /* the next block: S of the last one */
      p = last;
      PetscCall(PetscArraycpy(C, bk.W + (bk.k - last) * bk.nl, bk.nl * last));
    }
    PetscCall(KFBlockMultM(&bk, C, p, MC));
    PetscCall(KFBlockExpand(&bk, C, MC, p, &q));
  }
  PetscCall(PetscInfo(solver, "block eigensolve: %" PetscInt_FMT " of %" PetscInt_FMT " modes converged after %" PetscInt_FMT " steps, %" PetscInt_FMT " block solves of %" PetscInt_FMT " columns; worst estimate %g\n", got, nev, it, bk.solves, bk.columns, (double)worst));
  PetscCall(KFBlockModes(&bk, nev, got, SX, modes));
  for (PetscInt j = 0; j < got; j++) omega2[j] = 1.0 / theta[j];
  *nconv   = got;
  *solves  = bk.solves;
  *columns = bk.columns;
  PetscCall(PetscFree3(theta, Y, err));
  PetscCall(PetscFree4(C, MC, X, SX));
  PetscCall(PetscFree3(bk.V, bk.MV, bk.W));
  PetscFunctionReturn(0);
}
