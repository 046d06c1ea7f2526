/*
  The verification's eigensolve seeded with what the reduction already knows: the modes of the references made at
  neighbouring configurations span the band's modes at this one well. Rayleigh-Ritz of (K_S, M_S) on them, refined
  by block solves of K+ M (one multi-right-hand-side solve per step: a column costs a fraction of a single solve),
  gives the modes below the cut; Krylov-Schur, deflated by them, then confirms that none is missing.
*/
#include <kryflex_impl.h>
#include <slepceps.h>
#include <petscblaslapack.h>

PETSC_INTERN PetscErrorCode KFEigenRecordVector_Private(KFSystem, Vec, Vec, PetscInt, PetscInt, PetscReal[], PetscReal[], Mat);
PETSC_INTERN PetscErrorCode KFEPSStopCovered_Private(EPS, PetscInt, PetscInt, PetscInt, PetscInt, EPSConvergedReason *, void *);
PETSC_INTERN PetscErrorCode KFFlexPCApply_Private(PC, Vec, Vec);

/* The basis U (M-orthonormal, M-orthogonal to the rigid modes R) and its images Z = K+ M U, kept together */
typedef struct {
  BV       U, Z, R; /* R: the rigid modes (NULL: none) */
  PetscInt m, mmax;
  Mat      Ms;
} KFSeedBasis;

static PetscErrorCode KFSeedApply(KFSystem, KFFlexSolver, Mat, Mat *);

/* Append the columns of A: each made M-orthogonal to R and U (classical Gram-Schmidt, twice, with M a formed here: the
   BVs carry no inner-product matrix) and M-normalized, a column left with less than 1e-8 of its own M-norm dropped;
   then the images of the new columns in one block solve. Solved after the orthogonalization, not carried through it:
   a new direction is the small remainder of a nearly converged one, and its image carried along would be the solve's
   rounding divided by that remainder. */
static PetscErrorCode KFSeedAppend(KFSeedBasis *b, KFSystem sys, KFFlexSolver solver, Mat A)
{
  const PetscInt m0 = b->m;
  PetscInt       n, nr = 0;
  Vec            a, ma;
  PetscScalar   *h, *g, n0, n1;

  PetscFunctionBegin;
  PetscCall(MatGetSize(A, NULL, &n));
  if (b->R) PetscCall(BVGetActiveColumns(b->R, NULL, &nr));
  PetscCall(MatCreateVecs(b->Ms, &a, &ma));
  PetscCall(PetscMalloc2(b->mmax, &h, PetscMax(nr, 1), &g));
  for (PetscInt j = 0; j < n && b->m < b->mmax; j++) {
    Vec c;

    PetscCall(MatDenseGetColumnVecRead(A, j, &c));
    PetscCall(VecCopy(c, a));
    PetscCall(MatDenseRestoreColumnVecRead(A, j, &c));
    PetscCall(MatMult(b->Ms, a, ma));
    PetscCall(VecDot(a, ma, &n0)); /* a massless column's M-norm may round below zero */
    if (!(PetscRealPart(n0) > 0)) continue;
    for (PetscInt pass = 0; pass < 2; pass++) {
      if (nr) {
        PetscCall(MatMult(b->Ms, a, ma));
        PetscCall(BVDotVec(b->R, ma, g));
        PetscCall(BVMultVec(b->R, -1.0, 1.0, a, g));
      }
      if (b->m) {
        PetscCall(MatMult(b->Ms, a, ma));
        PetscCall(BVSetActiveColumns(b->U, 0, b->m));
        PetscCall(BVDotVec(b->U, ma, h));
        PetscCall(BVMultVec(b->U, -1.0, 1.0, a, h));
      }
    }
    PetscCall(MatMult(b->Ms, a, ma));
    PetscCall(VecDot(a, ma, &n1));
    if (!(PetscRealPart(n1) > 1e-16 * PetscRealPart(n0))) continue;
    PetscCall(VecScale(a, 1.0 / PetscSqrtReal(PetscRealPart(n1))));
    PetscCall(BVInsertVec(b->U, b->m, a));
    b->m++;
  }
  if (b->m > m0) {
    Mat N, W;
    KFScene s = sys->scene;

    PetscCall(KFDenseCreate(s->comm, s->nsys_local, s->nsys, b->m - m0, &N));
    for (PetscInt j = m0; j < b->m; j++) {
      Vec col;
      PetscCall(MatDenseGetColumnVecWrite(N, j - m0, &col));
      PetscCall(BVCopyVec(b->U, j, col));
      PetscCall(MatDenseRestoreColumnVecWrite(N, j - m0, &col));
    }
    PetscCall(KFSeedApply(sys, solver, N, &W));
    for (PetscInt j = m0; j < b->m; j++) {
      Vec col;
      PetscCall(MatDenseGetColumnVecRead(W, j - m0, &col));
      PetscCall(BVInsertVec(b->Z, j, col));
      PetscCall(MatDenseRestoreColumnVecRead(W, j - m0, &col));
    }
    PetscCall(MatDestroy(&N));
    PetscCall(MatDestroy(&W));
  }
  PetscCall(BVSetActiveColumns(b->U, 0, b->m));
  PetscCall(BVSetActiveColumns(b->Z, 0, b->m));
  PetscCall(PetscFree2(h, g));
  PetscCall(VecDestroy(&a));
  PetscCall(VecDestroy(&ma));
  PetscFunctionReturn(0);
}

/* Rayleigh-Ritz of the shift-and-invert operator K+ M in the M inner product: T = U^T M Z, its eigenvalues nu
   descending (theta = 1 / nu ascending), U and Z replaced by the Ritz vectors and their images. K itself is never
   applied: V^T K V would carry its rounding, eps ||K|| / theta (1e-8 on the 57k solid, 2e-9 in the frequencies).
   T is replicated, so every rank takes the same Ritz vectors. */
static PetscErrorCode KFSeedRitz(KFSeedBasis *b, PetscReal theta[])
{
  const PetscInt m = b->m;
  Mat            T, Q;
  PetscScalar   *t, *q;
  PetscReal     *work, *nu;
  PetscBLASInt   bm, lwork, info;

  PetscFunctionBegin;
  PetscCall(MatCreateSeqDense(PETSC_COMM_SELF, m, m, NULL, &T));
  PetscCall(MatCreateSeqDense(PETSC_COMM_SELF, m, m, NULL, &Q));
  {
    Mat Um, Zm, MZ;

    PetscCall(BVSetActiveColumns(b->U, 0, m));
    PetscCall(BVSetActiveColumns(b->Z, 0, m));
    PetscCall(BVGetMat(b->Z, &Zm));
    PetscCall(KFMatMultDense(b->Ms, Zm, &MZ));
    PetscCall(BVRestoreMat(b->Z, &Zm));
    PetscCall(BVGetMat(b->U, &Um));
    PetscCall(MatDenseGetArray(T, &t));
    PetscCall(KFMatTransposeMatMultGather(Um, MZ, t)); /* U^T M Z, replicated */
    PetscCall(MatDenseRestoreArray(T, &t));
    PetscCall(BVRestoreMat(b->U, &Um));
    PetscCall(MatDestroy(&MZ));
  }
  PetscCall(MatDenseGetArray(T, &t));
  for (PetscInt j = 0; j < m; j++) /* symmetric in exact arithmetic (K+ M is M-self-adjoint): its mean */
    for (PetscInt i = 0; i < j; i++) t[i + j * m] = t[j + i * m] = 0.5 * (t[i + j * m] + t[j + i * m]);
  PetscCall(PetscBLASIntCast(m, &bm));
  lwork = PetscMax(3 * bm, 1) * 8;
  PetscCall(PetscMalloc2(lwork, &work, m, &nu));
  PetscCallBLAS("LAPACKsyev", LAPACKsyev_("V", "L", &bm, t, &bm, nu, work, &lwork, &info));
  PetscCheck(!info, PETSC_COMM_SELF, PETSC_ERR_LIB, "the verification's seeded eigensolve: the Rayleigh-Ritz problem's eigensolver did not converge (LAPACK syev info %d)", (int)info);
  PetscCall(MatDenseGetArray(Q, &q));
  for (PetscInt j = 0; j < m; j++) { /* nu descending */
    theta[j] = nu[m - 1 - j] > 0 ? 1 / nu[m - 1 - j] : PETSC_MAX_REAL;
    for (PetscInt i = 0; i < m; i++) q[i + j * m] = t[i + (m - 1 - j) * m];
  }
  PetscCall(MatDenseRestoreArray(Q, &q));
  PetscCall(MatDenseRestoreArray(T, &t));
  PetscCall(PetscFree2(work, nu));
  PetscCall(BVMultInPlace(b->U, Q, 0, m));
  PetscCall(BVMultInPlace(b->Z, Q, 0, m));
  PetscCall(MatDestroy(&T));
  PetscCall(MatDestroy(&Q));
  PetscFunctionReturn(0);
}

/* W = K+ M A in one block solve */
static PetscErrorCode KFSeedApply(KFSystem sys, KFFlexSolver solver, Mat A, Mat *W)
{
  KFScene  s = sys->scene;
  Mat      MA;
  PetscInt k;

  PetscFunctionBegin;
  PetscCall(MatGetSize(A, NULL, &k));
  PetscCall(KFMatMultDense(sys->Ms, A, &MA));
  PetscCall(KFDenseCreate(s->comm, s->nsys_local, s->nsys, k, W));
  PetscCall(KFFlexSolverApply(solver, MA, *W));
  PetscCall(MatDestroy(&MA));
  PetscFunctionReturn(0);
}

/* Residuals of the first k Ritz pairs in the shift-and-invert sense, as Krylov-Schur measures them:
   ||theta K+ M x - x||_M for x of unit M-norm, from the images kept with the basis (no solve). The residual
   ||K x - theta M x|| itself has a rounding floor of about eps ||K|| / theta, 1e-8 on the 57k solid. */
static PetscErrorCode KFSeedResiduals(KFSeedBasis *b, PetscInt k, const PetscReal theta[], PetscReal res[])
{
  Vec x, z, y;

  PetscFunctionBegin;
  PetscCall(MatCreateVecs(b->Ms, &x, &y));
  PetscCall(VecDuplicate(x, &z));
  for (PetscInt j = 0; j < k; j++) {
    PetscScalar d;

    PetscCall(BVCopyVec(b->U, j, x));
    PetscCall(BVCopyVec(b->Z, j, z));
    PetscCall(VecAXPY(x, -theta[j], z)); /* x - theta z */
    PetscCall(MatMult(b->Ms, x, y));
    PetscCall(VecDot(x, y, &d));
    res[j] = PetscSqrtReal(PetscAbsReal(PetscRealPart(d)));
  }
  PetscCall(VecDestroy(&x));
  PetscCall(VecDestroy(&y));
  PetscCall(VecDestroy(&z));
  PetscFunctionReturn(0);
}

/* -kf_verify_seeded: whether to seed at all; -kf_verify_seed_tol: the seeded modes' residual ||theta K+ M x - x||_M taken as converged (their eigenvalues are good
   to its square; the reference's response to about it, well inside the reference check's 1e-6 of a pair's peak);
   -kf_verify_seed_confirm_tol: the confirming eigensolve's; -kf_verify_seed_steps: block steps before the seeds are
   given up for an eigensolve from scratch; -kf_verify_seed_ncv: the confirming eigensolve's Krylov dimension (6 took the
   fewest applications of K+ on the 57k solid: 16, against 19 with 12 and 21 with 20, at the tolerance 1e-10) */
static PetscErrorCode KFSeedOptions(MPI_Comm comm, PetscBool *use, PetscReal *tol, PetscReal *ctol, PetscInt *steps, PetscInt *ncv)
{
  PetscFunctionBegin;
  *use   = PETSC_TRUE;
  *tol   = 1e-8;
  *ctol  = 1e-5;
  *steps = 3;
  *ncv   = 6;
  PetscOptionsBegin(comm, NULL, "kryflex verification eigensolve seeded by neighbouring references", "KFFlexSolverEigenSeeded_Private");
  PetscCall(PetscOptionsBool("-kf_verify_seeded", "seed the sparse reference's eigensolve with the references nearest in angle", NULL, *use, use, NULL));
  PetscCall(PetscOptionsReal("-kf_verify_seed_tol", "residual ||theta K+ M x - x||_M of a converged seeded mode", NULL, *tol, tol, NULL));
  PetscCall(PetscOptionsReal("-kf_verify_seed_confirm_tol", "tolerance of the eigensolve confirming the seeded count", NULL, *ctol, ctol, NULL));
  PetscCall(PetscOptionsInt("-kf_verify_seed_steps", "block steps of K+ M before the seeds are given up", NULL, *steps, steps, NULL));
  PetscCall(PetscOptionsInt("-kf_verify_seed_ncv", "Krylov dimension of the confirming eigensolve", NULL, *ncv, ncv, NULL));
  PetscOptionsEnd();
  PetscFunctionReturn(0);
}

/* Rayleigh-Ritz on the seeds' span (one block solve for their images), then refined until the Ritz pairs below
   cut2, and the first at or above it, meet tol: each step appends the images of the wanted Ritz vectors and a few
   guard vectors (their images: one block solve), a block Lanczos step. Returns in *c the converged count (0: the
   seeds did not make it in steps), in *kk the Ritz vectors kept (the guards after the c), and their vectors purified:
   theta K+ M x, in the range of K+ M as Krylov-Schur's are after their purification. */
static PetscErrorCode KFSeedRefine(KFSeedBasis *b, KFSystem sys, KFFlexSolver solver, PetscInt nseeds, const Mat seeds[], PetscReal cut2, PetscReal tol, PetscInt steps, PetscReal theta[], PetscInt *c, PetscInt *kk, Mat *X, PetscInt *nblock)
{
  PetscInt   want = 0;
  PetscReal *res, prev = 0;

  PetscFunctionBegin;
  *c = 0;
  PetscCall(PetscMalloc1(b->mmax, &res));
  for (PetscInt i = 0; i < nseeds; i++) {
    PetscCall(KFSeedAppend(b, sys, solver, seeds[i]));
    (*nblock)++;
  }
  if (b->m) PetscCall(KFSeedRitz(b, theta));
  for (PetscInt it = 0; b->m; it++) {
    PetscInt  k, below = 0;
    PetscReal worst = 0;
    Mat       A, Zk;

    while (below < b->m && theta[below] < cut2) below++;
    want = below + 1;
    /* guard vectors: the Ritz vectors just above the wanted ones speed them up and leave room for a Ritz value that
       falls below the cut as the basis improves */
    k = PetscMin(b->m, want + PetscMax(3, want / 2));
    if (want > b->m - 1 || 2 * k > b->mmax) break; /* the seeds do not reach past the cut: the count is not theirs */
    PetscCall(KFSeedResiduals(b, want, theta, res));
    for (PetscInt j = 0; j < want; j++) worst = PetscMax(worst, res[j]);
    PetscCall(PetscInfo(NULL, "seeded eigensolve, step %" PetscInt_FMT ": %" PetscInt_FMT " Ritz values below the cut, worst residual %g\n", it, below, (double)worst));
    PetscCall(BVSetActiveColumns(b->Z, 0, k));
    PetscCall(BVGetMat(b->Z, &Zk));
    PetscCall(MatDuplicate(Zk, MAT_COPY_VALUES, &A));
    PetscCall(BVRestoreMat(b->Z, &Zk));
    if (worst <= tol) {
      for (PetscInt j = 0; j < k; j++) {
        Vec col;
        PetscCall(MatDenseGetColumnVecWrite(A, j, &col));
        PetscCall(VecScale(col, theta[j] < PETSC_MAX_REAL ? theta[j] : 0));
        PetscCall(MatDenseRestoreColumnVecWrite(A, j, &col));
      }
      *X  = A;
      *c  = want;
      *kk = k;
      break;
    }
    /* given up when the steps left, at the rate of the last one, would not reach tol: a slow start (modes that change
       much between the neighbouring angles) costs two block steps, not all of them */
    if (it >= steps || (it && worst * PetscPowReal(PetscMin(worst / prev, 1.0), (PetscReal)(steps - it)) > tol)) {
      PetscCall(MatDestroy(&A));
      break;
    }
    prev = worst;
    b->m = k;
    PetscCall(KFSeedAppend(b, sys, solver, A));
    (*nblock)++;
    PetscCall(MatDestroy(&A));
    PetscCall(KFSeedRitz(b, theta));
  }
  PetscCall(PetscFree(res));
  PetscFunctionReturn(0);
}

/* Whether the c seeded modes (the last of them, theta_top, the first at or above the cut) are all the modes up to it:
   Krylov-Schur from SLEPc's start vector, deflated by them (EPSSetDeflationSpace), stopped at its first converged
   mode at or above the cut. It converges the lowest remaining modes first, so a mode the seeds missed would come out
   before it: the assurance of the eigensolve from scratch, whose count rests on the same ordering. It only certifies
   the count (its modes are never kept), so it needs no more than a coarse tolerance (ctol, -kf_verify_seed_confirm_tol:
   its first mode's eigenvalue is then good to ctol^2): a mode it converges below the cut, or between the cut and
   theta_top, means the seeds missed one, and the caller solves from scratch. Cheaper checks were rejected: the previous
   configuration's count cannot see a mode entering the band between two angles; random columns in the block only find
   what they happen to contain by the time the wanted pairs converge; the inertia of K - cut M needs a factorization of
   the whole system. */
static PetscErrorCode KFSeedConfirm(Mat X, KFSystem sys, KFFlexSolver solver, PetscInt c, PetscReal cut2, PetscReal theta_top, PetscInt ncv, PetscReal ctol, PetscBool *certified, PetscInt *napply)
{
  KFScene            s = sys->scene;
  EPS                eps;
  ST                 st;
  KSP                ksp;
  PC                 pc;
  Vec               *defl, x;
  PetscInt           nc, its;
  PetscBool          covered = PETSC_FALSE, missed = PETSC_FALSE;
  EPSConvergedReason reason;
  KFFlexSolverPerf   perf;

  PetscFunctionBegin;
  PetscCall(KFFlexSolverGetPerf(solver, &perf));
  *napply = -perf.blocks;
  PetscCall(MatCreateVecs(sys->Ms, &x, NULL));
  PetscCall(VecDuplicateVecs(x, c, &defl));
  for (PetscInt j = 0; j < c; j++) {
    Vec col;
    PetscCall(MatDenseGetColumnVecRead(X, j, &col));
    PetscCall(VecCopy(col, defl[j]));
    PetscCall(MatDenseRestoreColumnVecRead(X, j, &col));
  }
  PetscCall(EPSCreate(s->comm, &eps));
  PetscCall(EPSSetOperators(eps, sys->Ks, sys->Ms));
  PetscCall(EPSSetProblemType(eps, EPS_GHEP));
  PetscCall(EPSSetType(eps, EPSKRYLOVSCHUR));
  PetscCall(EPSSetDimensions(eps, PetscMax(1, ncv - 1), ncv, PETSC_DEFAULT));
  PetscCall(EPSSetTarget(eps, 0.0));
  PetscCall(EPSSetWhichEigenpairs(eps, EPS_TARGET_REAL));
  PetscCall(EPSGetST(eps, &st));
  PetscCall(STSetType(st, STSINVERT));
  PetscCall(STGetKSP(st, &ksp));
  PetscCall(KSPSetType(ksp, KSPPREONLY));
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PCSetType(pc, PCSHELL));
  PetscCall(PCShellSetContext(pc, solver));
  PetscCall(PCShellSetApply(pc, KFFlexPCApply_Private));
  PetscCall(EPSSetTolerances(eps, ctol, PETSC_DEFAULT));
  PetscCall(EPSSetDeflationSpace(eps, c, defl));
  PetscCall(EPSSetStoppingTestFunction(eps, KFEPSStopCovered_Private, (void *)&cut2, NULL));
  PetscCall(EPSSetPurify(eps, PETSC_FALSE));
  PetscCall(EPSSetOptionsPrefix(eps, "kf_verify_confirm_"));
  PetscCall(EPSSetFromOptions(eps));
  PetscCall(EPSSolve(eps));
  PetscCall(EPSGetConverged(eps, &nc));
  PetscCall(EPSGetConvergedReason(eps, &reason));
  PetscCall(EPSGetIterationNumber(eps, &its));
  for (PetscInt i = 0; i < nc; i++) {
    PetscScalar kr;

    PetscCall(EPSGetEigenvalue(eps, i, &kr, NULL));
    if (PetscRealPart(kr) >= cut2) covered = PETSC_TRUE;
    /* a double mode at theta_top may come out again within the tolerance: the same frequency, not a missed mode */
    if (PetscRealPart(kr) < theta_top * (1 - 1e-4)) missed = PETSC_TRUE;
  }
  *certified = (PetscBool)(covered && !missed);
  PetscCall(KFFlexSolverGetPerf(solver, &perf));
  *napply += perf.blocks;
  PetscCall(PetscInfo(NULL, "seeded eigensolve's confirmation: %" PetscInt_FMT " modes deflated, %" PetscInt_FMT " converged beyond them (reason %d, %" PetscInt_FMT " restarts, %" PetscInt_FMT " applications of K+): %s\n", c, nc, (int)reason, its, *napply, *certified ? "certified" : "a mode missed, or none converged at or above the cut"));
  PetscCall(EPSDestroy(&eps));
  PetscCall(VecDestroyVecs(c, &defl));
  PetscCall(VecDestroy(&x));
  PetscFunctionReturn(0);
}

/* The modes below cut2 and the first at or above it, from the seeds (the columns of the matrices seeds[]), refined
   and confirmed as above; done: false when the seeds did not make it, and the caller solves from scratch. At most
   nev modes; omega2, HPhi, PhiG and modes (M-normalized) as KFSystemEigen's, then in modes the guard Ritz vectors:
   *nseed columns of modes in all. */
PETSC_INTERN PetscErrorCode KFFlexSolverEigenSeeded_Private(KFFlexSolver solver, PetscReal cut2, PetscInt nseeds, const Mat seeds[], PetscInt nev, PetscInt *nconv, PetscReal omega2[], PetscReal HPhi[], PetscReal PhiG[], Mat *modes, PetscInt *nseed, PetscBool *done)
{
  KFSystem    sys = KFFlexSolverSystem_Private(solver);
  KFScene     s   = sys->scene;
  KFSeedBasis b   = {0};
  Vec         x, y;
  PetscInt    m0 = 0, c = 0, kk = 0, steps, ncv, nblock = 0, napply = 0, n;
  PetscReal   tol, ctol, *theta;
  PetscBool   certified = PETSC_FALSE, use;
  Mat         X = NULL;

  PetscFunctionBegin;
  *done  = PETSC_FALSE;
  *nconv = 0;
  PetscCall(KFSeedOptions(s->comm, &use, &tol, &ctol, &steps, &ncv));
  if (!use) PetscFunctionReturn(0);
  PetscCall(KFSystemComputeRigidModes(sys));
  PetscCall(KFFlexSolverSetUp(solver));
  for (PetscInt i = 0; i < nseeds; i++) {
    PetscInt nc;
    PetscCall(MatGetSize(seeds[i], NULL, &nc));
    m0 += nc;
  }
  if (!m0) PetscFunctionReturn(0);
  PetscCall(PetscLogEventBegin(KF_EVENT_VERIFY, 0, 0, 0, 0));
  PetscCall(MatCreateVecs(sys->Ms, &x, &y));
  b.Ms   = sys->Ms;
  b.mmax = 2 * m0;
  PetscCall(BVCreate(s->comm, &b.U));
  PetscCall(BVSetType(b.U, BVSVEC));
  PetscCall(BVSetSizesFromVec(b.U, x, b.mmax));
  PetscCall(BVDuplicate(b.U, &b.Z));
  if (sys->nrigid) { /* the rigid modes: M-orthogonal to every flexible mode, kept out of the basis */
    PetscCall(BVDuplicateResize(b.U, sys->nrigid, &b.R));
    for (PetscInt k = 0; k < sys->nrigid; k++) {
      Vec col;
      PetscCall(MatDenseGetColumnVecRead(sys->Phi, k, &col));
      PetscCall(BVInsertVec(b.R, k, col));
      PetscCall(MatDenseRestoreColumnVecRead(sys->Phi, k, &col));
    }
  }
  PetscCall(PetscMalloc1(b.mmax, &theta));
  PetscCall(KFSeedRefine(&b, sys, solver, nseeds, seeds, cut2, tol, steps, theta, &c, &kk, &X, &nblock));
  if (c && c <= nev) PetscCall(KFSeedConfirm(X, sys, solver, c, cut2, theta[c - 1], ncv, ctol, &certified, &napply));
  PetscCall(PetscInfo(NULL, "seeded eigensolve: %" PetscInt_FMT " seed columns, %" PetscInt_FMT " block solves, %" PetscInt_FMT " seeded modes%s\n", m0, nblock, c, certified ? ", certified" : ": solved from scratch"));
  if (certified) {
    if (modes) PetscCall(KFDenseCreate(s->comm, s->nsys_local, s->nsys, nev, modes));
    for (n = 0; n < c; n++) {
      Vec p;

      PetscCall(MatDenseGetColumnVecRead(X, n, &p));
      PetscCall(VecCopy(p, x));
      PetscCall(MatDenseRestoreColumnVecRead(X, n, &p));
      omega2[n] = theta[n];
      PetscCall(KFEigenRecordVector_Private(sys, x, y, n, nev, HPhi, PhiG, modes ? *modes : NULL));
    }
    *nconv = c;
    /* the guard Ritz vectors after the modes (columns no mode uses): more of the band's span for the next seeds */
    for (PetscInt j = c; j < kk && modes && j < nev; j++) {
      Vec col, p;
      PetscCall(MatDenseGetColumnVecWrite(*modes, j, &col));
      PetscCall(MatDenseGetColumnVecRead(X, j, &p));
      PetscCall(VecCopy(p, col));
      PetscCall(MatDenseRestoreColumnVecRead(X, j, &p));
      PetscCall(MatDenseRestoreColumnVecWrite(*modes, j, &col));
    }
    if (nseed) *nseed = modes ? PetscMin(nev, kk) : c;
    *done = PETSC_TRUE;
  }
  PetscCall(PetscFree(theta));
  PetscCall(MatDestroy(&X));
  PetscCall(BVDestroy(&b.U));
  PetscCall(BVDestroy(&b.Z));
  PetscCall(BVDestroy(&b.R));
  PetscCall(VecDestroy(&x));
  PetscCall(VecDestroy(&y));
  PetscCall(PetscLogEventEnd(KF_EVENT_VERIFY, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}
