/*
  The verification's reference modes from a BLOCK Krylov space of K+ M (the flexible solver's K+: shift-and-invert
  about 0, the rigid modes mapped to zero), the default sparse path from 20,000 system dofs on (src/verify/eigen.c).
  The space starts from K+ [G, H^T, R] (the configuration's inputs and outputs, R a few random columns: damping
  matrices couple modes the inputs and outputs do not reach) and grows block by block, each block one block solve of
  the flexible solver (8 columns cost about twice one on the 57k solid: the bodies' factors are read once per block),
  rotated (KFBlockEigRotate) and M-orthonormalized with the Krylov basis's own numerics (src/krylov/block_arnoldi.c:
  rigid modes projected out, two classical Gram-Schmidt passes, deflation).
  Rayleigh-Ritz on V^T M K+ M V (LAPACK), the residual of every Ritz pair measured from the vectors themselves,
  ||theta K+ M x - x||_M for x = V y, ||x||_M = 1, with K+ M V kept from the solves: the quantity SLEPc's
  Krylov-Schur estimates from its recurrence and stops on (relative error of the shift-and-invert eigenvalue, 1e-10),
  here computed, not estimated. The stop is KFEPSStopCovered's: the Ritz pairs in order, every one converged, up to
  the first at or above the cut and the rest of its multiple mode. The modes returned are purified for free:
  theta K+ M x = theta W y.
  Why not a SLEPc block solver: subspace iteration on block solves took 3x Krylov-Schur's time and LOBPCG broke down
  (benchmarks/proof_cost/README.md); the projected problem here is small and exact.
*/
#include <kryflex_impl.h>
#include <kryflex/flexsolverimpl.h>
#include <petscblaslapack.h>
#include <time.h>
#include "eigen_impl.h"

const char *const KFVerifyEigenMethods[] = {"auto", "block", "slepc", "KFVerifyEigenMethod", "KF_VERIFY_EIGEN_", NULL};

#define KF_BLOCK_EIGEN_RTOL 1e-10 /* SLEPc's tolerance in the Krylov-Schur path (EPSSetTolerances) */
#define KF_BLOCK_EIGEN_DEFL 1e-10 /* a column of a new block that keeps less of its M-norm depends on the space */
#define KF_CLUSTER_RTOL     1e-8  /* omega^2 this close (relative): one multiple mode */
/* The deflation where M_S is singular. A column's part in M's null space is not measured by its M-norm: after the
   Gram-Schmidt it is rounding, about eps times the column's own size, and normalizing a column that kept a fraction
   f of its M-norm multiplies it by 1 / f. At f = 1e-10 that leaves basis columns 1e-6 out of the range of K+ M, and
   the Ritz vectors' residuals stall there (the rigid offset frame of tests/python/support/bc_models.py, 45 of its 90
   dofs in M's null space, on an AMD EPYC: residuals 1e-6 to 5e-5 when the basis ran out at 90 columns, no mode
   returned; with 1e-9 or 1e-8 converged in 6 blocks, largest residual 1.6e-10). Near sqrt(eps) a kept column's
   null-space rounding stays below 1e-8 of its size. */
#define KF_BLOCK_EIGEN_DEFL_SINGULAR_M 1e-8

/* -kf_verify_eigen_method (0 auto: block from KF_BLOCK_EIGEN_MIN_DOFS system dofs on, else slepc; 1 block; 2 slepc),
   -kf_verify_eigen_random (random columns per block),
   -kf_verify_eigen_max_blocks (blocks before the fall back to SLEPc's Krylov-Schur; PETSC_DECIDE, the default: sized
   from the modes asked, KFBlockEigenMaxBlocks), -kf_verify_eigen_first_mb (the arrays' first allocation,
   KFBlockEigReserve), read and checked */
PetscErrorCode KFBlockEigenOptions(MPI_Comm comm, PetscInt *method, PetscInt *nrand, PetscInt *maxblocks, PetscInt *firstmb)
{
  PetscFunctionBegin;
  *method    = 0;
  *nrand     = 3;
  *maxblocks = PETSC_DECIDE;
  *firstmb   = 32;
  PetscOptionsBegin(comm, NULL, "kryflex verification eigensolve (block Krylov)", "KFSystemEigen");
  PetscCall(KFOptionsSettingEList(PetscOptionsObject, "-kf_verify_eigen_method", KFVerifyEigenMethods, 3, KFVerifyEigenMethods[*method], method, NULL));
  PetscCall(KFOptionsSettingInt(PetscOptionsObject, "-kf_verify_eigen_random", *nrand, nrand, NULL));
  PetscCall(KFOptionsSettingInt(PetscOptionsObject, "-kf_verify_eigen_max_blocks", *maxblocks, maxblocks, NULL));
  PetscCall(KFOptionsSettingInt(PetscOptionsObject, "-kf_verify_eigen_first_mb", *firstmb, firstmb, NULL));
  PetscOptionsEnd();
  PetscCheck(*nrand >= 0, comm, PETSC_ERR_ARG_OUTOFRANGE, "-kf_verify_eigen_random %" PetscInt_FMT ": give the number of random start columns, 0 or more", *nrand);
  PetscCheck(*maxblocks >= 1 || *maxblocks == PETSC_DECIDE, comm, PETSC_ERR_ARG_OUTOFRANGE, "-kf_verify_eigen_max_blocks %" PetscInt_FMT ": give at least 1 block, or -1 (auto: sized from the modes asked)", *maxblocks);
  PetscCheck(*firstmb >= 0, comm, PETSC_ERR_ARG_OUTOFRANGE, "-kf_verify_eigen_first_mb %" PetscInt_FMT ": give the megabytes of the first allocation, 0 or more", *firstmb);
  PetscFunctionReturn(0);
}

#define KF_BLOCK_EIGEN_BLOCKS       12 /* the least automatic cap: what the block path always had */
#define KF_BLOCK_EIGEN_COLS_PER_MODE 4 /* measured: 20 modes in 12 blocks of 8, 39 in 19 (the 24k lumped frame) */
#define KF_BLOCK_EIGEN_MEM_FACTOR   12 /* the arrays' columns at the cap at most this many times Krylov-Schur's basis */

/* The automatic cap for nev modes asked in blocks of b columns: the blocks that KF_BLOCK_EIGEN_COLS_PER_MODE columns
   per mode expected fill, half again as a margin, and two blocks to spare, at least KF_BLOCK_EIGEN_BLOCKS. The modes
   expected: with a count that covered the cut before (the previous configuration's, hint->covered) that count and a
   quarter more (neighbouring configurations' counts differ by a few modes; nev is twice it, most of which the stop at
   the cut never computes), else nev (the first configuration, or a doubled nev that the last count did not cover).
   The margin is for models that need more columns per mode than the one measured (its first configuration, 20
   modes, took all 12 blocks of a cap without margin; a 13th would have meant the fall back to Krylov-Schur, several
   times slower). The arrays (V, M V and W: 3 b (blocks + 2) columns at the cap) grow with the blocks made
   (KFBlockEigReserve), so the cap costs memory only to a run that reaches it, one that falls back; that worst case
   is bounded by KF_BLOCK_EIGEN_MEM_FACTOR times the basis Krylov-Schur holds for the same nev (SLEPc's ncv,
   max(2 nev, nev + 15) vectors) unless that is below the least cap. With b = 8 the bound does not bind (18 columns
   per mode and the spare blocks at the cap, against 2 nev x 12); it does for blocks much wider than the modes
   asked, where the least cap decides. */
static PetscErrorCode KFBlockEigenMaxBlocks(const KFEigenHint *hint, PetscInt nev, PetscInt b, PetscInt *maxblocks)
{
  PetscInt n = nev, blocks, want, ncv, bound;

  PetscFunctionBegin;
  if (hint->cut2 > 0 && hint->covered && hint->count > 0) n = PetscMin(nev, hint->count + (hint->count + 3) / 4);
  blocks = (KF_BLOCK_EIGEN_COLS_PER_MODE * n + b - 1) / b;
  want   = blocks + (blocks + 1) / 2 + 2;
  ncv    = PetscMax(2 * nev, nev + 15);
  bound  = KF_BLOCK_EIGEN_MEM_FACTOR * ncv / (3 * b) - 2;
  *maxblocks = PetscMax(KF_BLOCK_EIGEN_BLOCKS, PetscMin(want, bound));
  PetscFunctionReturn(0);
}

typedef struct {
  KFSystem     sys;
  KFFlexSolver solver;
  KFMOrthBasis basis;
  KFFlexPCCtx  pc;         /* the block solves, their residual sampled as the Krylov-Schur path's applications */
  PetscInt     b, cap, nl; /* columns per block, most columns, local rows */
  PetscInt     ld, grown;  /* columns allocated in the basis, W, H, Y (KFBlockEigReserve), in how many steps */
  PetscInt     firstcols;  /* the first allocation's columns at least (-kf_verify_eigen_first_mb) */
  PetscScalar *W;          /* K+ M V for the basis's first kw columns, as solved (nl x ld) */
  PetscReal   *H;          /* V^T M W (ld x ld, column-major): the projected K+ M */
  PetscInt     kw, k0, k2, blocks, solved; /* W's columns (the square of H), the last block's first, the basis's */
  PetscBool    purify;     /* M is singular: the start block taken through K+ M once more (KFBlockEigStart) */
  PetscReal   *theta, *Y, *res; /* the Ritz pairs of the last step: omega^2 ascending, vectors (kw x kw), residuals */
  PetscLogDouble t_apply, t_orth, t_proj, t_res; /* seconds: the block solves (residual checks included), Gram-Schmidt, H, the Ritz residuals */
  PetscLogDouble t_start, t_out;                 /* ... the start block (its solve and append), the modes returned (purified, normalized) */
  PetscLogDouble t_grow;                         /* ... the arrays' growth (within Gram-Schmidt's and the start block's) */
} KFBlockEig;

static PetscErrorCode KFBlockEigRotate(KFBlockEig *, Mat);

/* the process's CPU seconds (the -info line gives them beside the wall: the machine is shared) */
static PetscLogDouble KFBlockEigCPU(void)
{
  struct timespec t;

  if (clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t)) return 0;
  return (PetscLogDouble)t.tv_sec + 1e-9 * (PetscLogDouble)t.tv_nsec;
}

/* Room for n columns in the basis and in W, H, Y and the Ritz values (at most cap): when it grows, at least doubled and
   at least firstcols (-kf_verify_eigen_first_mb's worth of local rows). The big arrays (the basis's V and M V, W)
   grow by realloc and are never zero-filled: a page not yet written is not resident, so they hold in memory the
   columns made, not the cap. The first allocation's 32 MB default is glibc malloc's largest mmap threshold: a block
   that size is mapped on its own and realloc remaps its pages instead of copying them; blocks from the heap were
   copied, the old and the new both resident meanwhile (measured on the 57k solid: 28 MB more than the cap's arrays
   at the peak, growing from the start block). H is laid out again at the new leading dimension (its entries never
   written are the block Hessenberg zeros Rayleigh-Ritz reads). */
static PetscErrorCode KFBlockEigReserve(KFBlockEig *be, PetscInt n)
{
  PetscInt       ld;
  PetscReal     *H;
  PetscLogDouble t0, t1;

  PetscFunctionBegin;
  n = PetscMin(n, be->cap);
  if (n <= be->ld) PetscFunctionReturn(0);
  PetscCall(PetscTime(&t0));
  ld = PetscMin(be->cap, PetscMax(PetscMax(n, 2 * be->ld), be->firstcols));
  PetscCall(KFMOrthBasisReserve(be->basis, ld));
  PetscCall(PetscRealloc(sizeof(PetscScalar) * (be->nl * ld + 1), &be->W));
  PetscCall(PetscCalloc1(ld * ld, &H));
  for (PetscInt j = 0; j < be->ld; j++) PetscCall(PetscArraycpy(&H[j * ld], &be->H[j * be->ld], be->ld));
  PetscCall(PetscFree(be->H));
  be->H = H;
  PetscCall(PetscFree3(be->theta, be->Y, be->res));
  PetscCall(PetscMalloc3(ld, &be->theta, ld * ld, &be->Y, ld, &be->res));
  be->ld = ld;
  be->grown++;
  PetscCall(PetscTime(&t1));
  be->t_grow += t1 - t0;
  PetscFunctionReturn(0);
}

/* a uniform number in [-1, 1) from the global row, the column and nothing else: the same start on any rank count */
static PetscReal KFBlockRandom(PetscInt row, PetscInt col)
{
  uint64_t z = (uint64_t)row * 0x9E3779B97F4A7C15ULL + (uint64_t)(col + 1) * 0xBF58476D1CE4E5B9ULL + 0x2545F4914F6CDD1DULL;

  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL; /* splitmix64's finalizer */
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  z ^= z >> 31;
  return (PetscReal)(z >> 11) / 4503599627370496.0 - 1.0; /* 53 bits over 2^52 */
}

static PetscReal KFBlockEigDeflation(const KFBlockEig *be)
{
  return be->purify ? KF_BLOCK_EIGEN_DEFL_SINGULAR_M : KF_BLOCK_EIGEN_DEFL;
}

/* The start block K+ [G, H^T, R] appended to the basis (one block solve), or with M singular K+ M K+ [G, H^T, R]
   (two): K+ G is the static response to the loads, which on a massless dof (the inputs of the stick aircraft act
   there) or through M's null space is not in the space the modes live in, K+ M's range (on M's null space the
   static condensation of the rest); what M cannot see of it the basis's M-orthonormalization cannot control either,
   and the Gram-Schmidt passes spread it over every later column (the Ritz residuals of the stick aircraft then stayed
   at 1e-8 to 1e-5 from the first mode on). Once more through K+ M, the start is in that range and so is every
   block after it; with a definite M the start stays as it was. */
static PetscErrorCode KFBlockEigStart(KFBlockEig *be, PetscInt nrand)
{
  KFScene            s = be->sys->scene;
  PetscInt           a = s->ninputs, t = s->noutputs, ldg, ldh, lds, ndefl = 0;
  Mat                S, X;
  PetscScalar       *x;
  const PetscScalar *g, *h;

  PetscFunctionBegin;
  PetscCall(KFDenseCreateUninitialized(s->comm, s->nsys_local, s->nsys, be->b, &S));
  PetscCall(MatDenseGetLDA(S, &lds));
  PetscCall(MatDenseGetLDA(be->sys->G, &ldg));
  PetscCall(MatDenseGetLDA(be->sys->Ht, &ldh));
  PetscCall(MatDenseGetArrayWrite(S, &x));
  PetscCall(MatDenseGetArrayRead(be->sys->G, &g));
  PetscCall(MatDenseGetArrayRead(be->sys->Ht, &h));
  for (PetscInt i = 0; i < be->nl; i++) {
    for (PetscInt j = 0; j < a; j++) x[i + j * lds] = g[i + j * ldg];
    for (PetscInt j = 0; j < t; j++) x[i + (a + j) * lds] = h[i + j * ldh];
    for (PetscInt j = 0; j < nrand; j++) x[i + (a + t + j) * lds] = KFBlockRandom(s->sys_rstart + i, j);
  }
  PetscCall(MatDenseRestoreArrayRead(be->sys->Ht, &h));
  PetscCall(MatDenseRestoreArrayRead(be->sys->G, &g));
  PetscCall(MatDenseRestoreArrayWrite(S, &x));
  PetscCall(KFDenseCreate(s->comm, s->nsys_local, s->nsys, be->b, &X));
  PetscCall(KFFlexPCApplySampled(&be->pc, S, X));
  be->solved += be->b;
  if (be->purify) {
    Mat MX;

    PetscCall(KFMatMultDense(be->sys->Ms, X, &MX));
    PetscCall(KFFlexPCApplySampled(&be->pc, MX, X));
    PetscCall(MatDestroy(&MX));
    be->solved += be->b;
  }
  PetscCall(KFBlockEigRotate(be, X));
  PetscCall(KFBlockEigReserve(be, be->b));
  PetscCall(KFMOrthBasisAppend(be->basis, X, KFBlockEigDeflation(be), &ndefl));
  PetscCall(MatDestroy(&X));
  PetscCall(MatDestroy(&S));
  PetscFunctionReturn(0);
}

/* X (p columns) rotated so that its parts M-orthogonal to the basis (k columns, V and M V) are M-orthogonal to each
   other, the largest first: their Gram matrix X^T M X - C^T C (C = V^T M X) diagonalized. The basis's own append
   (KFMBasisAppend) then finds no cancellation within the block: a Krylov block of K+ M, whose columns lean the same
   way once the converging modes are taken out, otherwise costs it a fresh M product and a pass against the whole
   basis per column (measured: most columns of every block on the solid). */
static PetscErrorCode KFBlockEigRotate(KFBlockEig *be, Mat X)
{
  KFScene            s = be->sys->scene;
  const PetscScalar *v, *mv;
  PetscScalar       *x, *y;
  PetscInt           k, nl, p, ldx;
  PetscReal         *G, *C, *U, *ev, *work;
  PetscBLASInt       bp, lwork, info;
  Mat                MX;

  PetscFunctionBegin;
  PetscCall(MatGetSize(X, NULL, &p));
  PetscCall(KFMOrthBasisGetArrays(be->basis, &k, &nl, &v, &mv));
  PetscCall(PetscMalloc5(p * p, &G, k * p + 1, &C, p * p, &U, p, &ev, nl * p + 1, &y));
  PetscCall(KFMatMultDense(be->sys->Ms, X, &MX));
  PetscCall(KFMatTransposeMatMultGather(X, MX, G));
  PetscCall(MatDestroy(&MX));
  PetscCall(MatDenseGetLDA(X, &ldx));
  PetscCall(MatDenseGetArray(X, &x));
  PetscCall(KFArrayTransposeMultGather(s->comm, nl, k, mv, nl, p, x, ldx, C));
  for (PetscInt j = 0; j < p; j++)
    for (PetscInt i = 0; i <= j; i++) {
      PetscReal d = G[i + j * p];
      for (PetscInt l = 0; l < k; l++) d -= C[l + i * k] * C[l + j * k];
      U[i + j * p] = U[j + i * p] = d;
    }
  PetscCall(PetscBLASIntCast(p, &bp));
  lwork = PetscMax(3 * bp, 1) * 8;
  PetscCall(PetscMalloc1(lwork, &work));
  PetscCallBLAS("LAPACKsyev", LAPACKsyev_("V", "L", &bp, U, &bp, ev, work, &lwork, &info));
  PetscCall(PetscFree(work));
  if (!info) { /* descending: the columns reversed */
    for (PetscInt j = 0; j < p / 2; j++)
      for (PetscInt i = 0; i < p; i++) {
        PetscReal t            = U[i + j * p];
        U[i + j * p]           = U[i + (p - 1 - j) * p];
        U[i + (p - 1 - j) * p] = t;
      }
    PetscCall(KFArraySkinnyMultSet(nl, p, x, ldx, p, 1.0, U, p, y, nl));
    for (PetscInt j = 0; j < p; j++) PetscCall(PetscArraycpy(&x[j * ldx], &y[j * nl], nl));
  } /* else the block as it is: the append's own refinement takes the cancellation */
  PetscCall(MatDenseRestoreArray(X, &x));
  PetscCall(PetscFree5(G, C, U, ev, y));
  PetscFunctionReturn(0);
}

/* One block: W for the columns kw..k1-1 of the basis (K+ of their M products, kept), appended to the basis, and
   their columns of H = V^T M W against every basis column, the new ones included (the recurrence's coupling rows,
   outside the square Rayleigh-Ritz takes). *grew: whether the basis took new columns. */
static PetscErrorCode KFBlockEigStep(KFBlockEig *be, PetscBool *grew)
{
  KFScene            s = be->sys->scene;
  const PetscScalar *v, *mv, *w;
  PetscInt           k1, k2, k0 = be->kw, p, nl, ldx, ndefl = 0;
  Mat                B, X;
  PetscScalar       *pb;
  PetscReal         *h;
  PetscLogDouble     t0, t1;

  PetscFunctionBegin;
  PetscCall(KFMOrthBasisGetArrays(be->basis, &k1, &nl, &v, &mv));
  p = k1 - k0;
  PetscCall(KFDenseCreateUninitialized(s->comm, nl, s->nsys, p, &B));
  PetscCall(MatDenseGetLDA(B, &ldx));
  PetscCall(MatDenseGetArrayWrite(B, &pb));
  for (PetscInt j = 0; j < p; j++) PetscCall(PetscArraycpy(&pb[j * ldx], &mv[(k0 + j) * nl], nl));
  PetscCall(MatDenseRestoreArrayWrite(B, &pb));
  PetscCall(KFDenseCreate(s->comm, nl, s->nsys, p, &X));
  PetscCall(PetscTime(&t0));
  PetscCall(KFFlexPCApplySampled(&be->pc, B, X));
  PetscCall(PetscTime(&t1));
  be->t_apply += t1 - t0;
  be->solved += p;
  be->blocks++;
  PetscCall(MatDenseGetLDA(X, &ldx));
  PetscCall(MatDenseGetArrayRead(X, &w));
  for (PetscInt j = 0; j < p; j++) PetscCall(PetscArraycpy(&be->W[(k0 + j) * nl], &w[j * ldx], nl));
  PetscCall(MatDenseRestoreArrayRead(X, &w));
  be->kw = k1;
  PetscCall(KFBlockEigRotate(be, X));
  PetscCall(KFBlockEigReserve(be, k1 + p));
  PetscCall(KFMOrthBasisAppend(be->basis, X, KFBlockEigDeflation(be), &ndefl));
  PetscCall(PetscTime(&t0));
  be->t_orth += t0 - t1;
  PetscCall(MatDestroy(&X));
  PetscCall(MatDestroy(&B));
  PetscCall(KFMOrthBasisGetArrays(be->basis, &k2, &nl, &v, &mv));
  *grew  = (PetscBool)(k2 > k1);
  be->k0 = k0;
  be->k2 = k2;
  PetscCall(PetscMalloc1(k2 * p + 1, &h));
  PetscCall(KFArrayTransposeMultGather(s->comm, nl, k2, mv, nl, p, &be->W[k0 * nl], nl, h));
  for (PetscInt j = 0; j < p; j++)
    for (PetscInt i = 0; i < k2; i++) be->H[i + (k0 + j) * be->ld] = h[i + j * k2];
  PetscCall(PetscFree(h));
  PetscCall(PetscTime(&t1));
  be->t_proj += t1 - t0;
  PetscFunctionReturn(0);
}

/* Rayleigh-Ritz on the square H (kw x kw, symmetrized: M K+ M is symmetric, its projection is up to rounding):
   theta = 1 / mu ascending, mu > 0 (the pencil's flexible part is positive; a mu at rounding is no mode) */
static PetscErrorCode KFBlockEigRitz(KFBlockEig *be, PetscInt *nritz)
{
  PetscInt     k = be->kw, m = 0;
  PetscReal   *A, *mu, *work, top;
  PetscBLASInt bk, lwork, info;

  PetscFunctionBegin;
  PetscCall(PetscMalloc2(k * k, &A, k, &mu));
  for (PetscInt j = 0; j < k; j++)
    for (PetscInt i = 0; i < k; i++) A[i + j * k] = 0.5 * (be->H[i + j * be->ld] + be->H[j + i * be->ld]);
  PetscCall(PetscBLASIntCast(k, &bk));
  lwork = PetscMax(3 * bk, 1) * 8;
  PetscCall(PetscMalloc1(lwork, &work));
  PetscCallBLAS("LAPACKsyev", LAPACKsyev_("V", "L", &bk, A, &bk, mu, work, &lwork, &info));
  PetscCall(PetscFree(work));
  PetscCheck(!info, PETSC_COMM_SELF, PETSC_ERR_LIB, "the verification's block eigensolve: LAPACK syev of the %" PetscInt_FMT "-column projected problem failed (info %d); take -kf_verify_eigen_method slepc", k, (int)info);
  top = k ? PetscAbsReal(mu[k - 1]) : 0;
  for (PetscInt i = k - 1; i >= 0 && mu[i] > 1e-14 * top; i--, m++) { /* descending mu: ascending omega^2 */
    be->theta[m] = 1.0 / mu[i];
    PetscCall(PetscArraycpy(&be->Y[m * k], &A[i * k], k));
  }
  *nritz = m;
  PetscCall(PetscFree2(A, mu));
  PetscFunctionReturn(0);
}

/* Z = theta_j W y_j - V y_j for the first n Ritz pairs (purified vector minus Ritz vector), their M-norms into res */
static PetscErrorCode KFBlockEigResiduals(KFBlockEig *be, PetscInt n)
{
  KFScene            s = be->sys->scene;
  const PetscScalar *v, *mv;
  PetscInt           k, kb, nl, ldz;
  Mat                Z, MZ;
  PetscScalar       *z;
  const PetscScalar *mz;

  PetscFunctionBegin;
  PetscCall(KFMOrthBasisGetArrays(be->basis, &kb, &nl, &v, &mv));
  k = be->kw;
  PetscCall(KFDenseCreateUninitialized(s->comm, nl, s->nsys, n, &Z));
  PetscCall(MatDenseGetLDA(Z, &ldz));
  PetscCall(MatDenseGetArrayWrite(Z, &z));
  PetscCall(KFArraySkinnyMultSet(nl, k, be->W, nl, n, 1.0, be->Y, k, z, ldz));
  for (PetscInt j = 0; j < n; j++)
    for (PetscInt i = 0; i < nl; i++) z[i + j * ldz] *= be->theta[j];
  PetscCall(KFArraySkinnyMultAdd(nl, k, v, nl, n, -1.0, be->Y, k, z, ldz));
  PetscCall(MatDenseRestoreArrayWrite(Z, &z));
  PetscCall(KFMatMultDense(be->sys->Ms, Z, &MZ));
  PetscCall(MatDenseGetArrayRead(Z, (const PetscScalar **)&z));
  PetscCall(MatDenseGetArrayRead(MZ, &mz));
  for (PetscInt j = 0; j < n; j++) {
    PetscReal d = 0;
    for (PetscInt i = 0; i < nl; i++) d += PetscRealPart(z[i + j * ldz] * mz[i + j * ldz]);
    be->res[j] = d;
  }
  PetscCall(MatDenseRestoreArrayRead(MZ, &mz));
  PetscCall(MatDenseRestoreArrayRead(Z, (const PetscScalar **)&z));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, be->res, (PetscMPIInt)n, MPIU_REAL, MPIU_SUM, s->comm));
  for (PetscInt j = 0; j < n; j++) be->res[j] = PetscSqrtReal(PetscMax(be->res[j], 0));
  PetscCall(MatDestroy(&MZ));
  PetscCall(MatDestroy(&Z));
  PetscFunctionReturn(0);
}

/* P = W Y for the first n Ritz pairs: the purified vectors theta_j K+ M x_j, unscaled. Their residuals are those the
   stop measured on this very space (KFBlockEigConverged), not measured again: an M product and a pass over the basis
   per configuration */
static PetscErrorCode KFBlockEigVectors(KFBlockEig *be, PetscInt n, Mat *P)
{
  KFScene      s = be->sys->scene;
  PetscInt     ldp;
  PetscScalar *x;

  PetscFunctionBegin;
  PetscCall(KFDenseCreateUninitialized(s->comm, be->nl, s->nsys, n, P));
  PetscCall(MatDenseGetLDA(*P, &ldp));
  PetscCall(MatDenseGetArrayWrite(*P, &x));
  PetscCall(KFArraySkinnyMultSet(be->nl, be->kw, be->W, be->nl, n, 1.0, be->Y, be->kw, x, ldp));
  PetscCall(MatDenseRestoreArrayWrite(*P, &x));
  PetscFunctionReturn(0);
}

/* The Ritz pairs in order, up to the first at or above cut2 and the rest of its cluster (or the first nev without a
   cut; exhausted, the basis taking no more columns: all there are), every one with its residual in res at most the
   tolerance: how many (0: not yet). A basis that stops growing is not taken for an invariant
   space on its word: the residuals decide there too (its deflation compares M-norms only, src/krylov/block_arnoldi.c
   KFMOrthBasisCreate, so on massless dofs it stops where M's positive part is spanned: 39 columns of the lumped
   frame's 45 massed dofs less its 6 rigid modes, every residual below 1e-12), and if they do not, the caller falls
   back to Krylov-Schur. A multiple mode at the cut is
   kept whole: one vector of a pair, the one the Krylov space happens to give, leaves its partner to the residual
   term, which is a (w / omega)^4 approximation (3.3e-6 of the peak at 115 Hz on the clamped beam with paired
   frequencies, its pair at 653 Hz, against the reference check's 1e-6) */
static PetscBool KFBlockEigOK(const KFBlockEig *be, PetscInt j)
{
  /* the residual's rounding floor: K+ M x = x / theta is computed to eps ||K+|| ||M x||, which theta multiplies back,
     so a mode theta / theta_0 above the first cannot show a residual below about eps theta / theta_0 (every flexible
     mode of Galileo, the stiffest 1e7 above the first: 1e-9); the floor stays below the tolerance on the 57k solid
     (its cut 81 times the first omega^2) */
  const PetscReal floor = 1e3 * PETSC_MACHINE_EPSILON * be->theta[j] / be->theta[0];

  return (PetscBool)(be->res[j] <= PetscMax(KF_BLOCK_EIGEN_RTOL, floor));
}

static PetscInt KFBlockEigCount(const KFBlockEig *be, PetscInt n, PetscReal cut2, PetscInt nev, PetscBool exhausted)
{
  for (PetscInt j = 0; j < n; j++) {
    if (!KFBlockEigOK(be, j)) return 0;
    if (cut2 > 0 && be->theta[j] >= cut2) { /* the cluster of the first above the cut whole, converged too */
      PetscInt e = j;
      while (e + 1 < n && be->theta[e + 1] <= (1 + KF_CLUSTER_RTOL) * be->theta[j]) {
        if (!KFBlockEigOK(be, e + 1)) return 0;
        e++;
      }
      return e + 1;
    }
    if (j + 1 == nev || (exhausted && j + 1 == n)) return j + 1;
  }
  return 0;
}

/* The stop (KFEPSStopCovered's). The Krylov recurrence's estimate first (free: theta ||H_(k+1,k) y_k||, the coupling
   rows of the new block), and where it says the modes are there, the residuals measured from the vectors
   (KFBlockEigResiduals), which decide. *nret: the modes to return (0: not yet) */
static PetscErrorCode KFBlockEigConverged(KFBlockEig *be, PetscInt nritz, PetscReal cut2, PetscInt nev, PetscBool exhausted, PetscInt *nret)
{
  PetscInt       n = PetscMin(nritz, nev), k = be->kw, k0 = be->k0, k2 = be->k2;
  PetscLogDouble t0, t1;

  PetscFunctionBegin;
  *nret = 0;
  if (!n) PetscFunctionReturn(0);
  for (PetscInt j = 0; j < n; j++) {
    PetscReal e = 0;
    for (PetscInt i = k; i < k2; i++) {
      PetscReal d = 0;
      for (PetscInt c = k0; c < k; c++) d += be->H[i + c * be->ld] * be->Y[c + j * k];
      e += d * d;
    }
    be->res[j] = be->theta[j] * PetscSqrtReal(e);
  }
  if (!KFBlockEigCount(be, n, cut2, nev, exhausted)) PetscFunctionReturn(0);
  PetscCall(PetscTime(&t0));
  PetscCall(KFBlockEigResiduals(be, n));
  PetscCall(PetscTime(&t1));
  be->t_res += t1 - t0;
  *nret = KFBlockEigCount(be, n, cut2, nev, exhausted);
  PetscFunctionReturn(0);
}

static PetscErrorCode KFBlockEigCreate(KFSystem sys, KFFlexSolver solver, PetscInt nrand, PetscInt maxblocks, PetscInt firstmb, KFBlockEig *be)
{
  KFScene  s = sys->scene;

  PetscFunctionBegin;
  PetscCall(PetscMemzero(be, sizeof(*be)));
  PetscCall(KFSystemMassSingular(sys, &be->purify));
  be->sys    = sys;
  be->solver = solver;
  be->pc.solver = solver;
  be->b      = s->ninputs + s->noutputs + nrand;
  be->cap    = PetscMin(be->b * (maxblocks + 2), s->nsys);
  be->nl     = s->nsys_local;
  be->firstcols = be->nl ? (PetscInt)PetscMin((PetscReal)be->cap, PetscCeilReal(firstmb * 1048576.0 / (sizeof(PetscScalar) * be->nl))) : 0;
  PetscCall(KFMOrthBasisCreate(sys, be->cap, &be->basis)); /* W, H and the basis allocated as it grows */
  PetscFunctionReturn(0);
}

static PetscErrorCode KFBlockEigDestroy(KFBlockEig *be)
{
  PetscFunctionBegin;
  PetscCall(KFMOrthBasisDestroy(&be->basis));
  PetscCall(PetscFree(be->W));
  PetscCall(PetscFree(be->H));
  PetscCall(PetscFree3(be->theta, be->Y, be->res));
  PetscFunctionReturn(0);
}

/* The lowest flexible modes of the flexible solver's configuration by the block Krylov space above: with hint->cut2 > 0
   every mode below it and the first at or above it (at most nev), else the nev lowest. On success (*ok) nconv modes:
   omega2 ascending, P (nsys x nconv) purified and M-normalized. *ok false: not converged within *cap blocks (the option's,
   or KFBlockEigenMaxBlocks's from the hint and nev), nothing returned: the caller falls back to SLEPc. */
PetscErrorCode KFBlockEigenSolve(KFSystem sys, KFFlexSolver solver, const KFEigenHint *hint, PetscInt nev, PetscInt *nconv, PetscReal omega2[], Mat *P, PetscBool *ok, PetscInt *nblocks, PetscInt *bcols, PetscInt *cap)
{
  KFScene          s = sys->scene;
  KFBlockEig       be;
  PetscInt         method, nrand, maxblocks, firstmb, nret = 0, nritz = 0;
  PetscBool        grew = PETSC_TRUE;
  PetscReal        worst = 0;
  KFFlexSolverPerf before, after;
  PetscLogDouble   t0, t1, c0, c1;

  PetscFunctionBegin;
  c0 = KFBlockEigCPU();
  PetscCall(KFBlockEigenOptions(s->comm, &method, &nrand, &maxblocks, &firstmb));
  if (maxblocks == PETSC_DECIDE) PetscCall(KFBlockEigenMaxBlocks(hint, nev, s->ninputs + s->noutputs + nrand, &maxblocks));
  *cap    = maxblocks;
  *ok     = PETSC_FALSE;
  *nconv  = 0;
  *P      = NULL;
  PetscCall(KFBlockEigCreate(sys, solver, nrand, maxblocks, firstmb, &be));
  *bcols = be.b;
  PetscCall(KFFlexSolverGetPerf(solver, &before));
  PetscCall(PetscTime(&t0));
  PetscCall(KFBlockEigStart(&be, nrand));
  PetscCall(PetscTime(&t1));
  be.t_start = t1 - t0;
  while (!nret && grew && be.blocks < maxblocks) {
    PetscCall(KFBlockEigStep(&be, &grew));
    PetscCall(KFBlockEigRitz(&be, &nritz));
    PetscCall(KFBlockEigConverged(&be, nritz, hint->cut2, nev, (PetscBool)!grew, &nret));
  }
  *nblocks = be.blocks;
  if (nret) {
    PetscCall(PetscTime(&t0));
    PetscCall(KFBlockEigVectors(&be, nret, P));
    PetscCall(KFEPSNormalizeBlock(sys, *P));
    PetscCall(PetscArraycpy(omega2, be.theta, nret));
    *nconv = nret;
    *ok    = PETSC_TRUE;
    PetscCall(PetscTime(&t1));
    be.t_out = t1 - t0;
  }
  PetscCall(KFFlexSolverGetPerf(solver, &after));
  for (PetscInt j = 0; j < nret; j++) worst = PetscMax(worst, be.res[j]);
  c1 = KFBlockEigCPU();
  /* the -info line of the Krylov-Schur path (iterations: blocks), which benchmarks/proof_cost/bench.py reads */
  PetscCall(PetscInfo(NULL, "kryflex verification eigensolve: %" PetscInt_FMT " iterations, %" PetscInt_FMT " K+ applications, %" PetscInt_FMT " columns, %g s in the factor's solves (block Krylov, %" PetscInt_FMT " columns per block, cap %" PetscInt_FMT " blocks for %" PetscInt_FMT " modes asked, %" PetscInt_FMT " Ritz pairs, %" PetscInt_FMT " returned, largest residual returned %g; seconds: block solves %g, Gram-Schmidt %g, projection %g, Ritz residuals %g, start block %g, modes out %g, the arrays' growth %g, process CPU %g; arrays for %" PetscInt_FMT " of the cap's %" PetscInt_FMT " columns, allocated in %" PetscInt_FMT " steps)\n", be.blocks, after.blocks - before.blocks, after.solve_columns - before.solve_columns, (double)(after.solve_seconds - before.solve_seconds), be.b, maxblocks, nev, nritz, nret, (double)worst, be.t_apply, be.t_orth, be.t_proj, be.t_res, be.t_start, be.t_out, be.t_grow, (double)(c1 - c0), be.ld, be.cap, be.grown));
  PetscCall(KFBlockEigDestroy(&be));
  PetscFunctionReturn(0);
}
