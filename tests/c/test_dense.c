/* Tests of the small dense algebra stage (src/dense) against independent references computed here
   with plain loops and Gaussian elimination: eigenpairs, null spaces, moments, frequency responses,
   static correction, mode importance (per mode, and band-aware by cluster), Hankel singular values of modal
   systems, joint rotations and reassembly at any angle.
   Every rank runs every check on the same data; rank 0 prints; the exit code is non-zero on failure. */
#include "kftest.h"

/* ------------------------------------------------------------------ plain dense helpers (column-major) */

static unsigned long long rng_state = 88172645463325252ULL;
static PetscReal          Rand(void) /* uniform in [-1, 1], identical on every rank */
{
  rng_state ^= rng_state << 13;
  rng_state ^= rng_state >> 7;
  rng_state ^= rng_state << 17;
  return 2.0 * (PetscReal)(rng_state >> 11) / 9007199254740992.0 - 1.0;
}

static void RandomMatrix(PetscInt m, PetscInt n, PetscReal A[])
{
  for (PetscInt i = 0; i < m * n; i++) A[i] = Rand();
}

/* C (m x n) = op(A) op(B), with op(A) m x k */
static void Mul(char ta, char tb, PetscInt m, PetscInt n, PetscInt k, const PetscReal A[], const PetscReal B[], PetscReal C[])
{
  for (PetscInt j = 0; j < n; j++)
    for (PetscInt i = 0; i < m; i++) {
      PetscReal s = 0;
      for (PetscInt l = 0; l < k; l++) {
        PetscReal x = ta == 'T' ? A[l + i * k] : A[i + l * m];
        PetscReal y = tb == 'T' ? B[j + l * n] : B[l + j * k];
        s += x * y;
      }
      C[i + j * m] = s;
    }
}

static PetscReal NormF(PetscInt m, PetscInt n, const PetscReal A[])
{
  PetscReal s = 0;
  for (PetscInt i = 0; i < m * n; i++) s += A[i] * A[i];
  return PetscSqrtReal(s);
}

static PetscReal DiffF(PetscInt len, const PetscReal A[], const PetscReal B[])
{
  PetscReal s = 0;
  for (PetscInt i = 0; i < len; i++) s += (A[i] - B[i]) * (A[i] - B[i]);
  return PetscSqrtReal(s);
}

/* max |A - I| */
static PetscReal DistIdentity(PetscInt n, const PetscReal A[])
{
  PetscReal e = 0;
  for (PetscInt j = 0; j < n; j++)
    for (PetscInt i = 0; i < n; i++) e = PetscMax(e, PetscAbsReal(A[i + j * n] - (i == j ? 1 : 0)));
  return e;
}

/* A = B^T B / n + shift I: symmetric positive definite for shift > 0 */
static PetscErrorCode RandomSPD(PetscInt n, PetscReal shift, PetscReal A[])
{
  PetscReal *B;

  PetscFunctionBegin;
  PetscCall(PetscMalloc1(n * n, &B));
  RandomMatrix(n, n, B);
  Mul('T', 'N', n, n, n, B, B, A);
  for (PetscInt i = 0; i < n * n; i++) A[i] /= n;
  for (PetscInt i = 0; i < n; i++) A[i + i * n] += shift;
  PetscCall(PetscFree(B));
  PetscFunctionReturn(0);
}

/* X (n x nrhs) = A^-1 B by Gaussian elimination with partial pivoting: the independent reference solver */
static PetscErrorCode Solve(PetscInt n, const PetscReal A[], PetscInt nrhs, const PetscReal B[], PetscReal X[])
{
  PetscReal *LU;

  PetscFunctionBegin;
  PetscCall(PetscMalloc1(n * n, &LU));
  PetscCall(PetscArraycpy(LU, A, n * n));
  PetscCall(PetscArraycpy(X, B, n * nrhs));
  for (PetscInt k = 0; k < n; k++) {
    PetscInt p = k;
    for (PetscInt i = k + 1; i < n; i++)
      if (PetscAbsReal(LU[i + k * n]) > PetscAbsReal(LU[p + k * n])) p = i;
    PetscCheck(LU[p + k * n] != 0, PETSC_COMM_SELF, PETSC_ERR_MAT_LU_ZRPVT, "test: singular reference system");
    if (p != k) {
      for (PetscInt j = 0; j < n; j++) {
        PetscReal t = LU[k + j * n];
        LU[k + j * n] = LU[p + j * n];
        LU[p + j * n] = t;
      }
      for (PetscInt j = 0; j < nrhs; j++) {
        PetscReal t = X[k + j * n];
        X[k + j * n] = X[p + j * n];
        X[p + j * n] = t;
      }
    }
    for (PetscInt i = k + 1; i < n; i++) {
      PetscReal f = LU[i + k * n] / LU[k + k * n];
      for (PetscInt j = k; j < n; j++) LU[i + j * n] -= f * LU[k + j * n];
      for (PetscInt j = 0; j < nrhs; j++) X[i + j * n] -= f * X[k + j * n];
    }
  }
  for (PetscInt j = 0; j < nrhs; j++)
    for (PetscInt k = n - 1; k >= 0; k--) {
      PetscReal s = X[k + j * n];
      for (PetscInt l = k + 1; l < n; l++) s -= LU[k + l * n] * X[l + j * n];
      X[k + j * n] = s / LU[k + k * n];
    }
  PetscCall(PetscFree(LU));
  PetscFunctionReturn(0);
}

/* Orthonormalize the columns of Q (n x k) in the W-inner product (W NULL: Euclidean), Gram-Schmidt twice */
static PetscErrorCode Orthonormalize(PetscInt n, PetscInt k, const PetscReal W[], PetscReal Q[])
{
  PetscReal *Wq;

  PetscFunctionBegin;
  PetscCall(PetscMalloc1(n, &Wq));
  for (PetscInt j = 0; j < k; j++) {
    PetscReal *q = Q + j * n, nrm = 0;
    for (int pass = 0; pass < 2; pass++) {
      if (W) Mul('N', 'N', n, 1, n, W, q, Wq);
      else PetscCall(PetscArraycpy(Wq, q, n));
      for (PetscInt l = 0; l < j; l++) {
        PetscReal c = 0;
        for (PetscInt i = 0; i < n; i++) c += Q[i + l * n] * Wq[i];
        for (PetscInt i = 0; i < n; i++) q[i] -= c * Q[i + l * n];
      }
    }
    if (W) Mul('N', 'N', n, 1, n, W, q, Wq);
    else PetscCall(PetscArraycpy(Wq, q, n));
    for (PetscInt i = 0; i < n; i++) nrm += q[i] * Wq[i];
    nrm = PetscSqrtReal(nrm);
    for (PetscInt i = 0; i < n; i++) q[i] /= nrm;
  }
  PetscCall(PetscFree(Wq));
  PetscFunctionReturn(0);
}

/* K = C^T S C with C the orthogonal projector off span(Z) (n x r) and S SPD: positive semidefinite with
   null space exactly span(Z): a pencil with r rigid modes. */
static PetscErrorCode SingularStiffness(PetscInt n, PetscInt r, const PetscReal Z[], PetscReal K[])
{
  PetscReal *Q, *C, *S, *T;

  PetscFunctionBegin;
  PetscCall(PetscMalloc4(n * r, &Q, n * n, &C, n * n, &S, n * n, &T));
  PetscCall(PetscArraycpy(Q, Z, n * r));
  PetscCall(Orthonormalize(n, r, NULL, Q));
  Mul('N', 'T', n, n, r, Q, Q, C);
  for (PetscInt i = 0; i < n * n; i++) C[i] = -C[i];
  for (PetscInt i = 0; i < n; i++) C[i + i * n] += 1;
  PetscCall(RandomSPD(n, 0.5, S));
  Mul('N', 'N', n, n, n, S, C, T);
  Mul('T', 'N', n, n, n, C, T, K);
  for (PetscInt j = 0; j < n; j++) /* exact symmetry */
    for (PetscInt i = j + 1; i < n; i++) K[i + j * n] = K[j + i * n] = 0.5 * (K[i + j * n] + K[j + i * n]);
  PetscCall(PetscFree4(Q, C, S, T));
  PetscFunctionReturn(0);
}

/* X = K+ B on the flexible subspace, from rigid modes Phir (n x r, M-orthonormal, K Phir = 0):
   (K + M Phir Phir^T M)^-1 = K+ + Phir Phir^T */
static PetscErrorCode PseudoSolve(PetscInt n, const PetscReal K[], const PetscReal M[], PetscInt r, const PetscReal Phir[], PetscInt nrhs, const PetscReal B[], PetscReal X[])
{
  PetscReal *MP, *A, *T;

  PetscFunctionBegin;
  PetscCall(PetscMalloc3(n * PetscMax(r, 1), &MP, n * n, &A, PetscMax(r, 1) * nrhs, &T));
  Mul('N', 'N', n, r, n, M, Phir, MP);
  Mul('N', 'T', n, n, r, MP, MP, A);
  for (PetscInt i = 0; i < n * n; i++) A[i] += K[i];
  PetscCall(Solve(n, A, nrhs, B, X));
  Mul('T', 'N', r, nrhs, n, Phir, B, T);
  for (PetscInt j = 0; j < nrhs; j++)
    for (PetscInt i = 0; i < n; i++)
      for (PetscInt l = 0; l < r; l++) X[i + j * n] -= Phir[i + l * n] * T[l + j * r];
  PetscCall(PetscFree3(MP, A, T));
  PetscFunctionReturn(0);
}

/* A random pencil with r rigid modes: M SPD, K PSD with K Phir = 0; Phir M-orthonormal */
static PetscErrorCode RigidPencil(PetscInt n, PetscInt r, PetscReal K[], PetscReal M[], PetscReal Phir[])
{
  PetscFunctionBegin;
  PetscCall(RandomSPD(n, 0.5, M));
  RandomMatrix(n, r, Phir);
  PetscCall(SingularStiffness(n, r, Phir, K));
  PetscCall(Orthonormalize(n, r, M, Phir));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------ eigenproblem */

static PetscErrorCode EigErrors(PetscInt n, const PetscReal K[], const PetscReal M[], const PetscReal lambda[], const PetscReal Phi[], PetscReal *res, PetscReal *orth, PetscReal *order)
{
  PetscReal *KP, *MP, *G, nK = NormF(n, n, K), nM = NormF(n, n, M);

  PetscFunctionBegin;
  PetscCall(PetscMalloc3(n * n, &KP, n * n, &MP, n * n, &G));
  Mul('N', 'N', n, n, n, K, Phi, KP);
  Mul('N', 'N', n, n, n, M, Phi, MP);
  *res = *order = 0;
  for (PetscInt j = 0; j < n; j++) {
    PetscReal r = 0, p = NormF(n, 1, Phi + j * n);
    for (PetscInt i = 0; i < n; i++) r += PetscSqr(KP[i + j * n] - lambda[j] * MP[i + j * n]);
    *res = PetscMax(*res, PetscSqrtReal(r) / ((nK + PetscAbsReal(lambda[j]) * nM) * p));
    if (j) *order = PetscMax(*order, lambda[j - 1] - lambda[j]);
  }
  Mul('T', 'N', n, n, n, Phi, MP, G);
  *orth = DistIdentity(n, G);
  PetscCall(PetscFree3(KP, MP, G));
  PetscFunctionReturn(0);
}

static PetscErrorCode TestEig(void)
{
  const PetscInt n = 14, r = 3;
  PetscReal     *K, *M, *Phi, *Phir, lambda[14], res, orth, order;
  PetscErrorCode ierr;

  PetscFunctionBegin;
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "KFDenseEig: K phi = lambda M phi\n"));
  PetscCall(PetscMalloc4(n * n, &K, n * n, &M, n * n, &Phi, n * r, &Phir));
  PetscCall(RandomSPD(n, 0.1, K));
  PetscCall(RandomSPD(n, 0.5, M));
  PetscCall(KFDenseEig(n, K, M, lambda, Phi));
  PetscCall(EigErrors(n, K, M, lambda, Phi, &res, &orth, &order));
  PetscCall(Check("SPD pencil (n 14): max ||K phi - lambda M phi|| / ((|K|+|lambda||M|)|phi|)", res, 1e-13));
  PetscCall(Check("SPD pencil: max |Phi^T M Phi - I|", orth, 1e-12));
  PetscCall(Check("SPD pencil: eigenvalues ascend (max lambda_i - lambda_i+1)", order, 0));

  PetscCall(RigidPencil(n, r, K, M, Phir));
  PetscCall(KFDenseEig(n, K, M, lambda, Phi));
  PetscCall(EigErrors(n, K, M, lambda, Phi, &res, &orth, &order));
  PetscCall(Check("pencil with 3 rigid modes: residual", res, 1e-13));
  PetscCall(Check("pencil with 3 rigid modes: max |Phi^T M Phi - I|", orth, 1e-12));
  PetscCall(Check("pencil with 3 rigid modes: max |lambda_rigid| / lambda_max", PetscMax(PetscMax(PetscAbsReal(lambda[0]), PetscAbsReal(lambda[1])), PetscAbsReal(lambda[2])) / lambda[n - 1], 1e-12));
  PetscCall(Check("pencil with 3 rigid modes: lambda_max / lambda_4 (flexible ones clear of 0)", lambda[n - 1] / lambda[3], 1e6));

  /* an indefinite mass matrix must be reported, not eigen-solved */
  for (PetscInt i = 0; i < n; i++) M[i + i * n] -= 10;
  PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  ierr = KFDenseEig(n, K, M, lambda, Phi);
  PetscCall(PetscPopErrorHandler());
  PetscCall(Check("indefinite M is refused with an error (1 = not refused)", ierr ? 0 : 1, 0));
  PetscCall(PetscFree4(K, M, Phi, Phir));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------ null space */

static PetscErrorCode NullSpaceCase(PetscInt m, PetscInt n, PetscInt r, PetscBool zero)
{
  PetscReal *A, *B, *D, *N, *DN, *G, sratio, nD, errD, errO;
  PetscInt   h, rank, want = zero ? 0 : PetscMin(r, PetscMin(m, n));
  char       what[128];

  PetscFunctionBegin;
  PetscCall(PetscMalloc6(m * r + 1, &A, r * n + 1, &B, m * n + 1, &D, n * n, &N, m * n + 1, &DN, n * n, &G));
  RandomMatrix(m, r, A);
  RandomMatrix(r, n, B);
  Mul('N', 'N', m, n, r, A, B, D); /* rank r */
  if (zero) PetscCall(PetscArrayzero(D, m * n));
  PetscCall(KFDenseNullSpace(m, n, D, 1e-10, &h, N, &rank, &sratio));
  nD = NormF(m, n, D);
  Mul('N', 'N', m, h, n, D, N, DN);
  Mul('T', 'N', h, h, n, N, N, G);
  errD = nD > 0 ? NormF(m, h, DN) / nD : NormF(m, h, DN);
  errO = DistIdentity(h, G);
  PetscCall(PetscSNPrintf(what, sizeof(what), "D %" PetscInt_FMT " x %" PetscInt_FMT " of rank %" PetscInt_FMT ": |rank - %" PetscInt_FMT "| + |h - n + rank|", m, n, want, want));
  PetscCall(Check(what, (PetscReal)(PetscAbsInt(rank - want) + PetscAbsInt(h - (n - want))), 0));
  PetscCall(PetscSNPrintf(what, sizeof(what), "   ||D N||_F / ||D||_F  (h %" PetscInt_FMT ", sratio %.2e)", h, (double)sratio));
  PetscCall(Check(what, errD, 1e-13));
  PetscCall(Check("   max |N^T N - I|", errO, 1e-13));
  PetscCall(PetscFree6(A, B, D, N, DN, G));
  PetscFunctionReturn(0);
}

static PetscErrorCode TestNullSpace(void)
{
  PetscFunctionBegin;
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "KFDenseNullSpace: SVD null space, rtol 1e-10\n"));
  PetscCall(NullSpaceCase(7, 12, 5, PETSC_FALSE));  /* wide, rank deficient */
  PetscCall(NullSpaceCase(20, 9, 6, PETSC_FALSE));  /* tall, rank deficient */
  PetscCall(NullSpaceCase(6, 6, 6, PETSC_FALSE));   /* full rank: h = 0 */
  PetscCall(NullSpaceCase(5, 11, 5, PETSC_FALSE));  /* full row rank */
  PetscCall(NullSpaceCase(4, 5, 2, PETSC_TRUE));    /* all zero: rank 0 */
  PetscCall(NullSpaceCase(0, 8, 0, PETSC_FALSE));   /* no constraints */
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------ moments */

/* Lref^k = H (X M)^k X G with X = K^-1 (r = 0) or K+ (r rigid modes Phir) */
static PetscErrorCode ReferenceMoments(PetscInt n, const PetscReal K[], const PetscReal M[], PetscInt r, const PetscReal Phir[], PetscInt a, const PetscReal G[], PetscInt t, const PetscReal H[], PetscInt nmom, PetscReal L[])
{
  PetscReal *X, *Y;

  PetscFunctionBegin;
  PetscCall(PetscMalloc2(n * a, &X, n * a, &Y));
  PetscCall(PseudoSolve(n, K, M, r, Phir, a, G, X));
  for (PetscInt k = 0; k < nmom; k++) {
    Mul('N', 'N', t, a, n, H, X, L + k * t * a);
    Mul('N', 'N', n, a, n, M, X, Y);
    PetscCall(PseudoSolve(n, K, M, r, Phir, a, Y, X));
  }
  PetscCall(PetscFree2(X, Y));
  PetscFunctionReturn(0);
}

static PetscReal MaxRelMomentError(PetscInt nmom, PetscInt ta, const PetscReal L[], const PetscReal Lref[])
{
  PetscReal e = 0;
  for (PetscInt k = 0; k < nmom; k++) e = PetscMax(e, DiffF(ta, L + k * ta, Lref + k * ta) / NormF(ta, 1, Lref + k * ta));
  return e;
}

static PetscErrorCode TestMoments(void)
{
  const PetscInt n = 10, a = 2, t = 3, nmom = 6, r = 3;
  PetscReal     *K, *M, *G, *H, *Phir, *L, *Lref;

  PetscFunctionBegin;
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "KFDenseMoments: L^k = H (K+ M)^k K+ G, k = 0..5, against direct solves\n"));
  PetscCall(PetscMalloc7(n * n, &K, n * n, &M, n * a, &G, t * n, &H, n * r, &Phir, nmom * t * a, &L, nmom * t * a, &Lref));
  RandomMatrix(n, a, G);
  RandomMatrix(t, n, H);
  PetscCall(RandomSPD(n, 0.2, K));
  PetscCall(RandomSPD(n, 0.5, M));
  PetscCall(KFDenseMoments(n, K, M, a, G, t, H, 1e-8, nmom, L));
  PetscCall(ReferenceMoments(n, K, M, 0, NULL, a, G, t, H, nmom, Lref));
  PetscCall(Check("nonsingular K: max_k ||L^k - H (K^-1 M)^k K^-1 G|| / ||.||", MaxRelMomentError(nmom, t * a, L, Lref), 1e-11));

  PetscCall(RigidPencil(n, r, K, M, Phir));
  PetscCall(KFDenseMoments(n, K, M, a, G, t, H, 1e-8, nmom, L));
  PetscCall(ReferenceMoments(n, K, M, r, Phir, a, G, t, H, nmom, Lref));
  PetscCall(Check("3 rigid modes: vs K+ = (K + M Phir Phir^T M)^-1 - Phir Phir^T", MaxRelMomentError(nmom, t * a, L, Lref), 1e-10));
  PetscCall(PetscFree7(K, M, G, H, Phir, L, Lref));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------ frequency response */

/* T = H (K - w^2 M + i w C)^-1 G as the real block system [A -B; B A] [xr; xi] = [G; 0] */
static PetscErrorCode DirectFRF(PetscInt n, const PetscReal K[], const PetscReal M[], const PetscReal C[], PetscInt a, const PetscReal G[], PetscInt t, const PetscReal H[], PetscReal w, PetscReal Tre[], PetscReal Tim[])
{
  const PetscInt N2 = 2 * n;
  PetscReal     *A, *B, *X;

  PetscFunctionBegin;
  PetscCall(PetscMalloc3(N2 * N2, &A, N2 * a, &B, N2 * a, &X));
  for (PetscInt j = 0; j < n; j++)
    for (PetscInt i = 0; i < n; i++) {
      PetscReal re = K[i + j * n] - w * w * M[i + j * n], im = w * C[i + j * n];
      A[i + j * N2]             = re;
      A[(n + i) + (n + j) * N2] = re;
      A[i + (n + j) * N2]       = -im;
      A[(n + i) + j * N2]       = im;
    }
  for (PetscInt j = 0; j < a; j++)
    for (PetscInt i = 0; i < n; i++) {
      B[i + j * N2]       = G[i + j * n];
      B[n + i + j * N2] = 0;
    }
  PetscCall(Solve(N2, A, a, B, X));
  for (PetscInt j = 0; j < a; j++)
    for (PetscInt i = 0; i < t; i++) {
      PetscReal sr = 0, si = 0;
      for (PetscInt l = 0; l < n; l++) {
        sr += H[i + l * t] * X[l + j * N2];
        si += H[i + l * t] * X[n + l + j * N2];
      }
      Tre[i + j * t] = sr;
      Tim[i + j * t] = si;
    }
  PetscCall(PetscFree3(A, B, X));
  PetscFunctionReturn(0);
}

static PetscErrorCode TestFRF(void)
{
  const PetscInt  n = 10, r = 2, a = 3, t = 2, nw = 4;
  const PetscReal zeta = 0.02, rigid_tol = 1e-9;
  PetscReal      *K, *M, *Phir, *Phi, *G, *H, *HPhi, *PhiG, *C, *MP, *T1, lambda[10], w[4], Tre[4 * 6], Tim[4 * 6], Rre[6], Rim[6], err = 0;

  PetscFunctionBegin;
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "KFModalFRF: against H (K - w^2 M + i w C)^-1 G, C = M Phi diag(2 zeta w_i) Phi^T M, 2 rigid modes\n"));
  PetscCall(PetscMalloc6(n * n, &K, n * n, &M, n * r, &Phir, n * n, &Phi, n * a, &G, t * n, &H));
  PetscCall(PetscMalloc5(t * n, &HPhi, n * a, &PhiG, n * n, &C, n * n, &MP, n * n, &T1));
  PetscCall(RigidPencil(n, r, K, M, Phir));
  RandomMatrix(n, a, G);
  RandomMatrix(t, n, H);
  PetscCall(KFDenseEig(n, K, M, lambda, Phi));
  Mul('N', 'N', t, n, n, H, Phi, HPhi);
  Mul('T', 'N', n, a, n, Phi, G, PhiG);
  /* modal damping; the rigid modes (first r) are undamped */
  Mul('N', 'N', n, n, n, M, Phi, MP);
  for (PetscInt j = 0; j < n; j++) {
    PetscReal c = j < r ? 0 : 2 * zeta * PetscSqrtReal(lambda[j]);
    for (PetscInt i = 0; i < n; i++) T1[i + j * n] = MP[i + j * n] * c;
  }
  Mul('N', 'T', n, n, n, T1, MP, C);
  w[0] = 0.3 * PetscSqrtReal(lambda[r]);
  w[1] = PetscSqrtReal(lambda[r]); /* at the first resonance */
  w[2] = 0.5 * (PetscSqrtReal(lambda[r + 2]) + PetscSqrtReal(lambda[r + 3]));
  w[3] = 1.7 * PetscSqrtReal(lambda[n - 1]);
  PetscCall(KFModalFRF(n, lambda, t, HPhi, a, PhiG, zeta, rigid_tol, nw, w, Tre, Tim));
  for (PetscInt f = 0; f < nw; f++) {
    PetscReal e, nr;
    PetscCall(DirectFRF(n, K, M, C, a, G, t, H, w[f], Rre, Rim));
    e  = PetscSqrtReal(PetscSqr(DiffF(t * a, Tre + f * t * a, Rre)) + PetscSqr(DiffF(t * a, Tim + f * t * a, Rim)));
    nr = PetscSqrtReal(PetscSqr(NormF(t * a, 1, Rre)) + PetscSqr(NormF(t * a, 1, Rim)));
    err = PetscMax(err, e / nr);
  }
  PetscCall(Check("4 frequencies (below, at, between, above resonances): max rel. error", err, 1e-10));
  PetscCall(PetscFree6(K, M, Phir, Phi, G, H));
  PetscCall(PetscFree5(HPhi, PhiG, C, MP, T1));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------ static correction */

static PetscErrorCode TestStaticCorrection(void)
{
  const PetscInt n = 12, b = 4, d = n - b, a = 2;
  PetscReal     *K, *M, *G, *Phi, *S, *X, *Q, *MX, *C, *R, lambda[12], nX, err, errS;

  PetscFunctionBegin;
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "KFDenseStaticCorrection: 12 modes, keep 4, S = Phid Lambdad^-1 Phid^T G\n"));
  PetscCall(PetscMalloc5(n * n, &K, n * n, &M, n * a, &G, n * n, &Phi, n * a, &S));
  PetscCall(PetscMalloc5(n * a, &X, n * (b + a), &Q, n * a, &MX, (b + a) * a, &C, n * a, &R));
  PetscCall(RandomSPD(n, 0.2, K));
  PetscCall(RandomSPD(n, 0.5, M));
  RandomMatrix(n, a, G);
  PetscCall(KFDenseEig(n, K, M, lambda, Phi));
  PetscCall(KFDenseStaticCorrection(n, d, Phi + b * n, lambda + b, a, G, S));
  PetscCall(Solve(n, K, a, G, X));
  nX = NormF(n, a, X);
  /* orthogonal projection of K^-1 G onto span [Phi_b, S] */
  PetscCall(PetscArraycpy(Q, Phi, n * b));
  PetscCall(PetscArraycpy(Q + n * b, S, n * a));
  PetscCall(Orthonormalize(n, b + a, NULL, Q));
  Mul('T', 'N', b + a, a, n, Q, X, C);
  Mul('N', 'N', n, a, b + a, Q, C, R);
  err = DiffF(n * a, X, R) / nX;
  /* the same without S: the static gain of the discarded modes is missing */
  Mul('T', 'N', b, a, n, Q, X, C);
  Mul('N', 'N', n, a, b, Q, C, R);
  errS = DiffF(n * a, X, R) / nX;
  PetscCall(Check("||K^-1 G - its projection on span [Phi_b, S]|| / ||K^-1 G||", err, 1e-12));
  PetscCall(Check("without S that residual is large (check fails if < 1e-3): 1e-3 / residual", 1e-3 / errS, 1));
  /* exact split: K^-1 G = Phi_b Phi_b^T M K^-1 G + S */
  Mul('N', 'N', n, a, n, M, X, MX);
  Mul('T', 'N', b, a, n, Phi, MX, C);
  Mul('N', 'N', n, a, b, Phi, C, R);
  for (PetscInt i = 0; i < n * a; i++) R[i] += S[i];
  PetscCall(Check("||K^-1 G - Phi_b Phi_b^T M K^-1 G - S|| / ||K^-1 G||", DiffF(n * a, X, R) / nX, 1e-12));
  PetscCall(PetscFree5(K, M, G, Phi, S));
  PetscCall(PetscFree5(X, Q, MX, C, R));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------ mode importance */

static PetscErrorCode TestImportance(void)
{
  const PetscInt  n = 8, r = 2, a = 2, t = 2, nq = 40001;
  const PetscReal zeta = 0.03, rigid_tol = 1e-9, umax = 14;
  PetscReal      *K, *M, *Phir, *Phi, *G, *H, *HPhi, *PhiG, *wq, *Tre, *Tim, lambda[8], imp[3][8], ref[3][8], rmax[3] = {0, 0, 0}, err[3] = {0, 0, 0}, econst = 0;
  const char     *names[3] = {"H2 (vs (1/pi) int_0^inf ||T_i(w)||^2 dw by quadrature)", "Hinf (vs ||T_i(w_i)|| at resonance)", "static (vs ||T_i(0)||)"};

  PetscFunctionBegin;
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "KFDenseModeImportance: each measure against the response of the single mode (KFModalFRF), 2 rigid modes\n"));
  PetscCall(PetscMalloc6(n * n, &K, n * n, &M, n * r, &Phir, n * n, &Phi, n * a, &G, t * n, &H));
  PetscCall(PetscMalloc5(t * n, &HPhi, n * a, &PhiG, nq, &wq, nq * t * a, &Tre, nq * t * a, &Tim));
  PetscCall(RigidPencil(n, r, K, M, Phir));
  RandomMatrix(n, a, G);
  RandomMatrix(t, n, H);
  PetscCall(KFDenseEig(n, K, M, lambda, Phi));
  for (int kind = 0; kind < 3; kind++) PetscCall(KFDenseModeImportance(n, lambda, Phi, a, G, t, H, zeta, (KFImportance)kind, rigid_tol, imp[kind]));
  Mul('N', 'N', t, n, n, H, Phi, HPhi);
  Mul('T', 'N', n, a, n, Phi, G, PhiG);
  for (PetscInt i = 0; i < n; i++) {
    PetscReal hp[2], pg[2], wi = PetscSqrtReal(PetscAbsReal(lambda[i])), s = 0, du = 2 * umax / (nq - 1);
    for (int kind = 0; kind < 3; kind++) ref[kind][i] = 0;
    if (i < r) continue;
    for (PetscInt k = 0; k < t; k++) hp[k] = HPhi[k + i * t];
    for (PetscInt j = 0; j < a; j++) pg[j] = PhiG[i + j * n];
    /* H2: w = w_i e^u, dw = w du, trapezoid in u (the integrand decays like e^u and e^-3u) */
    for (PetscInt q = 0; q < nq; q++) wq[q] = wi * PetscExpReal(-umax + q * du);
    PetscCall(KFModalFRF(1, &lambda[i], t, hp, a, pg, zeta, rigid_tol, nq, wq, Tre, Tim));
    for (PetscInt q = 0; q < nq; q++) s += (q == 0 || q == nq - 1 ? 0.5 : 1) * (PetscSqr(NormF(t * a, 1, Tre + q * t * a)) + PetscSqr(NormF(t * a, 1, Tim + q * t * a))) * wq[q] * du;
    ref[0][i] = PetscSqrtReal(s / PETSC_PI);
    /* the closed form of the header, unnormalized: ||H phi|| ||phi^T G|| / (2 sqrt(zeta w^3)) */
    econst = PetscMax(econst, PetscAbsReal(ref[0][i] / (NormF(t, 1, hp) * NormF(a, 1, pg) / (2 * PetscSqrtReal(zeta * wi * wi * wi))) - 1));
    PetscCall(KFModalFRF(1, &lambda[i], t, hp, a, pg, zeta, rigid_tol, 1, &wi, Tre, Tim));
    ref[1][i] = PetscSqrtReal(PetscSqr(NormF(t * a, 1, Tre)) + PetscSqr(NormF(t * a, 1, Tim)));
    wq[0] = 0;
    PetscCall(KFModalFRF(1, &lambda[i], t, hp, a, pg, zeta, rigid_tol, 1, wq, Tre, Tim));
    ref[2][i] = NormF(t * a, 1, Tre);
  }
  for (int kind = 0; kind < 3; kind++) {
    for (PetscInt i = 0; i < n; i++) rmax[kind] = PetscMax(rmax[kind], ref[kind][i]);
    for (PetscInt i = 0; i < n; i++) err[kind] = PetscMax(err[kind], PetscAbsReal(imp[kind][i] - ref[kind][i] / rmax[kind]));
    PetscCall(Check(names[kind], err[kind], kind == 0 ? 1e-8 : 1e-12));
  }
  PetscCall(Check("H2 closed form vs quadrature, unnormalized: max |ratio - 1|", econst, 1e-6));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "    H2 importance by mode:"));
  for (PetscInt i = 0; i < n; i++) PetscCall(PetscPrintf(PETSC_COMM_WORLD, " %.3g", (double)imp[0][i]));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "\n"));
  PetscCall(PetscFree6(K, M, Phir, Phi, G, H));
  PetscCall(PetscFree5(HPhi, PhiG, wq, Tre, Tim));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------ band-aware importance and Hankel singular values */

/* max over a uniform grid of nq frequencies on [wmin, wmax] (endpoints included) of 1/|lambda - w^2 + 2 i zeta sqrt(lambda) w| */
static PetscReal GridPeak(PetscReal lambda, PetscReal zeta, PetscReal wmin, PetscReal wmax, PetscInt nq)
{
  PetscReal p = 0;
  for (PetscInt q = 0; q < nq; q++) {
    PetscReal w = wmin + (wmax - wmin) * q / (nq - 1), x = lambda - w * w, y = 2 * zeta * PetscSqrtReal(lambda) * w;
    p = PetscMax(p, 1 / PetscSqrtReal(x * x + y * y));
  }
  return p;
}

static PetscErrorCode TestImportanceBand(void)
{
  /* 1 rigid mode; 0.2 Hz below the band; a cluster at 1.0 and 1.0005 Hz (gap 5e-4 relative, within cluster_rtol
     1e-3); 2 Hz; an exactly repeated pair at 3 Hz; 5 Hz; 100 Hz far above the band [0.5, 6] Hz */
  const PetscInt  n = 9, a = 2, t = 3, single[4] = {1, 4, 7, 8}, expect[9] = {-1, 0, 1, 1, 2, 3, 3, 4, 5};
  const PetscReal fhz[9] = {0, 0.2, 1.0, 1.0005, 2.0, 3.0, 3.0, 5.0, 100.0}, band[2] = {0.5, 6.0}, wmin = 2 * PETSC_PI * band[0], wmax = 2 * PETSC_PI * band[1];
  PetscReal      *Phi, *Phi2, *G, *H, *HPhi, *PhiG, lambda[9], imp[9], imp2[9], hg[9], e;
  PetscInt        cl[9], cl2[9];
  PetscBool       ok = PETSC_TRUE;
  PetscErrorCode  ierr;

  PetscFunctionBegin;
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "KFDenseModeImportanceBand: clusters, invariance inside a cluster, the peak over the band\n"));
  PetscCall(PetscMalloc6(n * n, &Phi, n * n, &Phi2, n * a, &G, t * n, &H, t * n, &HPhi, n * a, &PhiG));
  RandomMatrix(n, n, Phi);
  PetscCall(Orthonormalize(n, n, NULL, Phi)); /* M = I */
  RandomMatrix(n, a, G);
  RandomMatrix(t, n, H);
  for (PetscInt i = 0; i < n; i++) lambda[i] = PetscSqr(2 * PETSC_PI * fhz[i]);
  Mul('N', 'N', t, n, n, H, Phi, HPhi);
  Mul('T', 'N', n, a, n, Phi, G, PhiG);
  /* ||H phi phi^T G||_2 of a single mode: rank one, the product of the two norms */
  for (PetscInt i = 0; i < n; i++) {
    PetscReal h = 0, g = 0;
    for (PetscInt r = 0; r < t; r++) h += PetscSqr(HPhi[r + i * t]);
    for (PetscInt j = 0; j < a; j++) g += PetscSqr(PhiG[i + j * n]);
    hg[i] = PetscSqrtReal(h * g);
  }

  PetscCall(KFDenseModeImportanceBand(n, lambda, Phi, a, G, t, H, 0.02, band, 1e-3, 1e-9, imp, cl));
  for (PetscInt i = 0; i < n; i++) ok = (PetscBool)(ok && cl[i] == expect[i]);
  PetscCall(CheckTrue("cluster ids: rigid -1, then 0.. ascending; 1.0 and 1.0005 Hz share one, so do the 3 Hz pair", ok));
  PetscCall(CheckTrue("one importance per cluster (1.0 and 1.0005 Hz; the 3 Hz pair), 0 for the rigid mode", (PetscBool)(imp[2] == imp[3] && imp[5] == imp[6] && imp[0] == 0)));
  /* single-mode clusters against the brute-force peak of their response over 20001 frequencies in the band: exact at
     the edges (0.2 and 100 Hz peak there), ~1e-5 for the in-band peaks, whose width is ~zeta w */
  e = 0;
  for (int k = 0; k < 4; k++) {
    PetscInt i = single[k], j = single[0];
    PetscReal ref = hg[i] * GridPeak(lambda[i], 0.02, wmin, wmax, 20001) / (hg[j] * GridPeak(lambda[j], 0.02, wmin, wmax, 20001));
    e = PetscMax(e, PetscAbsReal(imp[i] / imp[j] / ref - 1));
  }
  PetscCall(Check("single-mode clusters: importance ratios vs the grid peak of the response, zeta 0.02", e, 1e-4));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "    importance by mode:"));
  for (PetscInt i = 0; i < n; i++) PetscCall(PetscPrintf(PETSC_COMM_WORLD, " %.3g", (double)imp[i]));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "\n"));
  PetscCall(Check("100 Hz mode, 16x above the band's top: importance (small)", imp[8], 1e-2));
  /* the band edge: above the band the peak is at wmax, 1/|lambda - wmax^2 + 2 i zeta sqrt(lambda) wmax| */
  {
    PetscReal e8 = hg[8] / PetscHypotReal(lambda[8] - wmax * wmax, 2 * 0.02 * PetscSqrtReal(lambda[8]) * wmax);
    PetscReal e1 = hg[1] / PetscHypotReal(lambda[1] - wmin * wmin, 2 * 0.02 * PetscSqrtReal(lambda[1]) * wmin);
    PetscCall(Check("modes outside the band peak at the nearest edge: |ratio / edge formula - 1|", PetscAbsReal(imp[8] / imp[1] / (e8 / e1) - 1), 1e-12));
  }
  /* inside the band with zeta < 1/sqrt 2 the peak is the textbook 1 / (2 zeta sqrt(1 - zeta^2) lambda), at
     w = sqrt(lambda (1 - 2 zeta^2)): 2 and 5 Hz with zeta 0.3 (their peaks at 1.8 and 4.5 Hz, inside) */
  PetscCall(KFDenseModeImportanceBand(n, lambda, Phi, a, G, t, H, 0.3, band, 1e-3, 1e-9, imp2, cl2));
  e = PetscAbsReal(imp2[7] / imp2[4] / ((hg[7] / lambda[7]) / (hg[4] / lambda[4])) - 1);
  PetscCall(Check("zeta 0.3, in-band peaks 1/(2 zeta sqrt(1-zeta^2) lambda): |ratio - 1|", e, 1e-12));
  /* zeta > 1/sqrt 2: the response decreases in w, so every mode peaks at the lower edge */
  PetscCall(KFDenseModeImportanceBand(n, lambda, Phi, a, G, t, H, 0.8, band, 1e-3, 1e-9, imp2, cl2));
  e = 0;
  for (int k = 0; k < 4; k++) {
    PetscInt  i = single[k], j = single[0];
    PetscReal pi = 1 / PetscHypotReal(lambda[i] - wmin * wmin, 1.6 * PetscSqrtReal(lambda[i]) * wmin), pj = 1 / PetscHypotReal(lambda[j] - wmin * wmin, 1.6 * PetscSqrtReal(lambda[j]) * wmin);
    e = PetscMax(e, PetscAbsReal(imp2[i] / imp2[j] / (hg[i] * pi / (hg[j] * pj)) - 1));
  }
  PetscCall(Check("zeta 0.8 > 1/sqrt 2: every peak at the lower band edge: |ratio - 1|", e, 1e-12));

  /* a rotation inside each cluster (the exactly repeated 3 Hz pair and the 1.0/1.0005 Hz pair) changes the modes
     but not H Phi_C Phi_C^T G: the importances must not move */
  PetscCall(PetscArraycpy(Phi2, Phi, n * n));
  for (int p = 0; p < 2; p++) {
    PetscInt  c0 = p ? 5 : 2;
    PetscReal th = p ? 0.7 : 2.1, cs = PetscCosReal(th), sn = PetscSinReal(th);
    for (PetscInt r = 0; r < n; r++) {
      Phi2[r + c0 * n]       = cs * Phi[r + c0 * n] + sn * Phi[r + (c0 + 1) * n];
      Phi2[r + (c0 + 1) * n] = -sn * Phi[r + c0 * n] + cs * Phi[r + (c0 + 1) * n];
    }
  }
  PetscCall(KFDenseModeImportanceBand(n, lambda, Phi2, a, G, t, H, 0.02, band, 1e-3, 1e-9, imp2, cl2));
  e = 0;
  for (PetscInt i = 0; i < n; i++) e = PetscMax(e, PetscAbsReal(imp2[i] - imp[i]));
  PetscCall(Check("rotation inside the two clusters: max |importance change|", e, 1e-13));
  {
    PetscReal h1[9], h2[9], d = 0;
    PetscCall(KFDenseModeImportance(n, lambda, Phi, a, G, t, H, 0.02, KF_IMPORTANCE_HINF, 1e-9, h1));
    PetscCall(KFDenseModeImportance(n, lambda, Phi2, a, G, t, H, 0.02, KF_IMPORTANCE_HINF, 1e-9, h2));
    for (PetscInt i = 5; i < 7; i++) d = PetscMax(d, PetscAbsReal(h1[i] - h2[i]));
    PetscCall(CheckTrue("... while the per-mode Hinf measure of the 3 Hz pair moves (the rotation is not a no-op)", (PetscBool)(d > 1e-6)));
  }

  /* zeta = 0: the floor keeps in-band peaks finite */
  PetscCall(KFDenseModeImportanceBand(n, lambda, Phi, a, G, t, H, 0.0, band, 1e-3, 1e-9, imp2, cl2));
  ok = PETSC_TRUE;
  for (PetscInt i = 0; i < n; i++) ok = (PetscBool)(ok && !PetscIsInfOrNanReal(imp2[i]) && imp2[i] >= 0 && imp2[i] <= 1);
  PetscCall(CheckTrue("zeta = 0: finite importances in [0, 1]", ok));

  PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  ierr = KFDenseModeImportance(n, lambda, Phi, a, G, t, H, 0.02, KF_IMPORTANCE_BAND, 1e-9, imp2);
  PetscCall(PetscPopErrorHandler());
  PetscCall(Check("KFDenseModeImportance refuses KF_IMPORTANCE_BAND (1 = not refused)", ierr ? 0 : 1, 0));
  {
    const PetscReal bad[2] = {6.0, 0.5};
    PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
    ierr = KFDenseModeImportanceBand(n, lambda, Phi, a, G, t, H, 0.02, bad, 1e-3, 1e-9, imp2, cl2);
    PetscCall(PetscPopErrorHandler());
    PetscCall(Check("KFDenseModeImportanceBand refuses a band with fmin > fmax (1 = not refused)", ierr ? 0 : 1, 0));
  }
  PetscCall(PetscFree6(Phi, Phi2, G, H, HPhi, PhiG));
  PetscFunctionReturn(0);
}

static PetscErrorCode TestHankel(void)
{
  /* one mode, rank-one input and output maps: T(s) = h g^T / (s^2 + 2 zeta w s + w^2), whose two Hankel singular
     values are ||h|| ||g|| (sqrt(1 + zeta^2) +- zeta) / (4 zeta w^2). Two modes whose input rows and output columns
     are orthogonal decouple: the union of the single-mode values. */
  const PetscReal w2[2] = {PetscSqr(2 * PETSC_PI * 1.3), PetscSqr(2 * PETSC_PI * 7.0)};
  const PetscReal HPhi[4] = {0.6, -0.8, 1.6, 1.2}, PhiG[4] = {1.0, -2.0, 2.0, 1.0}; /* t = a = 2: columns of HPhi, rows of PhiG orthogonal */
  PetscReal       hsv[4], ref[4], e = 0;
  PetscErrorCode  ierr;

  PetscFunctionBegin;
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "KFModalHankelSingularValues: closed forms of one mode and of decoupled modes\n"));
  for (int z = 0; z < 2; z++) {
    const PetscReal zeta = z ? 0.25 : 0.01;
    PetscReal       hg[2];

    for (int k = 0; k < 2; k++) {
      hg[k]          = PetscHypotReal(HPhi[2 * k], HPhi[2 * k + 1]) * PetscHypotReal(PhiG[k], PhiG[k + 2]);
      ref[2 * k]     = hg[k] * (PetscSqrtReal(1 + zeta * zeta) + zeta) / (4 * zeta * w2[k]);
      ref[2 * k + 1] = hg[k] * (PetscSqrtReal(1 + zeta * zeta) - zeta) / (4 * zeta * w2[k]);
    }
    /* mode 0 with input 0 alone (n = a = 1: its PhiG is the single entry PhiG(0,0) = PhiG[0]) */
    PetscCall(KFModalHankelSingularValues(1, w2, 2, HPhi, 1, PhiG, zeta, hsv));
    {
      const PetscReal s = PetscHypotReal(HPhi[0], HPhi[1]) * PetscAbsReal(PhiG[0]) / (4 * zeta * w2[0]);
      e = PetscMax(PetscAbsReal(hsv[0] / (s * (PetscSqrtReal(1 + zeta * zeta) + zeta)) - 1), PetscAbsReal(hsv[1] / (s * (PetscSqrtReal(1 + zeta * zeta) - zeta)) - 1));
    }
    PetscCall(Check(z ? "one mode, zeta 0.25: max |hsv / closed form - 1|" : "one mode, zeta 0.01: max |hsv / closed form - 1|", e, 1e-12));
    PetscCall(KFModalHankelSingularValues(2, w2, 2, HPhi, 2, PhiG, zeta, hsv));
    PetscCall(PetscSortReal(4, ref));
    e = 0;
    for (int k = 0; k < 4; k++) e = PetscMax(e, PetscAbsReal(hsv[k] - ref[3 - k]) / ref[3]);
    PetscCall(Check(z ? "two decoupled modes, zeta 0.25: max |hsv - union| / hsv_1" : "two decoupled modes, zeta 0.01: max |hsv - union| / hsv_1", e, 1e-12));
  }
  PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  ierr = KFModalHankelSingularValues(2, w2, 2, HPhi, 2, PhiG, 0.0, hsv);
  PetscCall(PetscPopErrorHandler());
  PetscCall(Check("zeta = 0 is refused (1 = not refused)", ierr ? 0 : 1, 0));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------ joint rotation */

static PetscErrorCode TestJointRotation(void)
{
  const PetscReal axis[3] = {1, 2, 2}, k[3] = {1.0 / 3, 2.0 / 3, 2.0 / 3}, z[3] = {0, 0, 1}, zero[3] = {0, 0, 0};
  PetscReal       R[9], Ra[9], Rb[9], Rab[9], R0[9], RR0[9], RtR[9], Rz[9], e = 0, det;
  PetscErrorCode  ierr;

  PetscFunctionBegin;
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "KFJointRotation: Rodrigues rotation about the axis, times R0\n"));
  PetscCall(KFJointRotation(axis, NULL, 0.9, R));
  Mul('T', 'N', 3, 3, 3, R, R, RtR);
  det = R[0] * (R[4] * R[8] - R[7] * R[5]) - R[3] * (R[1] * R[8] - R[7] * R[2]) + R[6] * (R[1] * R[5] - R[4] * R[2]);
  PetscCall(Check("unnormalized axis (1,2,2): max |R^T R - I| + |det R - 1|", DistIdentity(3, RtR) + PetscAbsReal(det - 1), 1e-14));
  for (int i = 0; i < 3; i++) e = PetscMax(e, PetscAbsReal(R[i] * k[0] + R[i + 3] * k[1] + R[i + 6] * k[2] - k[i]));
  PetscCall(Check("the axis is fixed: max |R k - k|", e, 1e-15));
  PetscCall(KFJointRotation(z, NULL, PETSC_PI / 2, Rz));
  PetscCall(Check("positive sense: Rot(z, 90 deg) e_x = e_y: |R e_x - e_y|", PetscAbsReal(Rz[0]) + PetscAbsReal(Rz[1] - 1) + PetscAbsReal(Rz[2]), 1e-15));
  PetscCall(KFJointRotation(axis, NULL, 0.4, Ra));
  PetscCall(KFJointRotation(axis, NULL, -1.3, Rb));
  PetscCall(KFJointRotation(axis, NULL, 0.4 - 1.3, Rab));
  Mul('N', 'N', 3, 3, 3, Ra, Rb, R);
  PetscCall(Check("R(a) R(b) = R(a+b): max diff", DiffF(9, R, Rab), 1e-14));
  PetscCall(KFJointRotation(z, NULL, 0.77, R0)); /* any rotation as R0 */
  PetscCall(KFJointRotation(axis, R0, 0.4, RR0));
  Mul('N', 'N', 3, 3, 3, Ra, R0, R);
  PetscCall(Check("R0 applied after the joint rotation: |R(a, R0) - R(a) R0|", DiffF(9, R, RR0), 1e-14));
  PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  ierr = KFJointRotation(zero, NULL, 0.1, R);
  PetscCall(PetscPopErrorHandler());
  PetscCall(Check("a zero axis is refused with an error (1 = not refused)", ierr ? 0 : 1, 0));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------ reassembly */

#define NB 4
#define NJ 3

typedef struct {
  PetscInt   nnodes, n, nif, ifnode[2];
  PetscReal *M, *K, *G, *H, *iface, *xyz;
} TestBody;

/* Rigid-body modes of a body's nodes (6 dofs each): translation t: u = t; rotation w: u = w x x, theta = w */
static void RigidBodyModes(const TestBody *B, PetscReal Z[])
{
  for (PetscInt c = 0; c < 6; c++)
    for (PetscInt p = 0; p < B->nnodes; p++) {
      PetscReal *u = Z + c * B->n + 6 * p, w[3] = {0, 0, 0};
      const PetscReal *x = B->xyz + 3 * p;
      for (int i = 0; i < 6; i++) u[i] = 0;
      if (c < 3) u[c] = 1;
      else {
        w[c - 3] = 1;
        u[0]     = w[1] * x[2] - w[2] * x[1];
        u[1]     = w[2] * x[0] - w[0] * x[2];
        u[2]     = w[0] * x[1] - w[1] * x[0];
        u[3 + c - 3] = 1;
      }
    }
}

/* The full-order system by elimination, written independently of KFReassemble: the root's dofs are system
   dofs; each child's interface node is expressed through its parent's (u_c = R^T u_p, theta_c = R^T theta_p,
   plus a free rotation s R^T k about the axis for a revolute joint); its other dofs are new system dofs. */
static PetscErrorCode EliminatedSystem(const TestBody B[], const KFJointDef J[], const PetscReal angles[], PetscInt a, PetscInt t, PetscInt *e_out, PetscReal **Ms, PetscReal **Ks, PetscReal **Gs, PetscReal **Hs)
{
  PetscInt   e = 0, col = 0, irev = 0;
  PetscReal *P[NB];

  PetscFunctionBegin;
  for (PetscInt b = 0; b < NB; b++) e += B[b].n;
  for (PetscInt j = 0; j < NJ; j++) e -= J[j].type == KF_JOINT_REVOLUTE ? 5 : 6;
  for (PetscInt b = 0; b < NB; b++) PetscCall(PetscCalloc1(B[b].n * e, &P[b]));
  for (PetscInt i = 0; i < B[0].n; i++) P[0][i + (col++) * B[0].n] = 1;
  for (PetscInt j = 0; j < NJ; j++) { /* parents come before children in this scene */
    const TestBody *Bp = &B[J[j].parent], *Bc = &B[J[j].child];
    PetscReal      *Pp = P[J[j].parent], *Pc = P[J[j].child], R[9], k[3], len;
    PetscInt        np = Bp->n, nc = Bc->n, ip = 6 * Bp->ifnode[J[j].parent_interface], ic = 6 * Bc->ifnode[J[j].child_interface];

    if (J[j].type == KF_JOINT_REVOLUTE) PetscCall(KFJointRotation(J[j].axis, J[j].R0, angles[irev++], R));
    else
      for (int i = 0; i < 9; i++) R[i] = J[j].R0[i];
    for (PetscInt i = 0; i < nc; i++)
      if (i < ic || i >= ic + 6) Pc[i + (col++) * nc] = 1;
    for (PetscInt c = 0; c < e; c++)
      for (int g = 0; g < 2; g++)     /* translations, rotations */
        for (int r = 0; r < 3; r++) { /* (R^T x_p)_r = sum_s R[s, r] x_p,s */
          PetscReal s = 0;
          for (int q = 0; q < 3; q++) s += R[q + 3 * r] * Pp[ip + 3 * g + q + c * np];
          Pc[ic + 3 * g + r + c * nc] = s;
        }
    if (J[j].type == KF_JOINT_REVOLUTE) {
      len = PetscSqrtReal(PetscSqr(J[j].axis[0]) + PetscSqr(J[j].axis[1]) + PetscSqr(J[j].axis[2]));
      for (int i = 0; i < 3; i++) k[i] = J[j].axis[i] / len;
      for (int r = 0; r < 3; r++) Pc[ic + 3 + r + col * nc] = R[0 + 3 * r] * k[0] + R[1 + 3 * r] * k[1] + R[2 + 3 * r] * k[2];
      col++;
    }
  }
  PetscCheck(col == e, PETSC_COMM_SELF, PETSC_ERR_PLIB, "test: elimination produced %" PetscInt_FMT " of %" PetscInt_FMT " system dofs", col, e);
  PetscCall(PetscCalloc1(e * e, Ms));
  PetscCall(PetscCalloc1(e * e, Ks));
  PetscCall(PetscCalloc1(e * a, Gs));
  PetscCall(PetscCalloc1(t * e, Hs));
  for (PetscInt b = 0; b < NB; b++) {
    PetscReal *X, *Y;
    PetscInt   n = B[b].n;
    PetscCall(PetscMalloc2(n * e, &X, e * e, &Y));
    Mul('N', 'N', n, e, n, B[b].M, P[b], X);
    Mul('T', 'N', e, e, n, P[b], X, Y);
    for (PetscInt i = 0; i < e * e; i++) (*Ms)[i] += Y[i];
    Mul('N', 'N', n, e, n, B[b].K, P[b], X);
    Mul('T', 'N', e, e, n, P[b], X, Y);
    for (PetscInt i = 0; i < e * e; i++) (*Ks)[i] += Y[i];
    Mul('T', 'N', e, a, n, P[b], B[b].G, Y);
    for (PetscInt i = 0; i < e * a; i++) (*Gs)[i] += Y[i];
    Mul('N', 'N', t, e, n, B[b].H, P[b], Y);
    for (PetscInt i = 0; i < t * e; i++) (*Hs)[i] += Y[i];
    PetscCall(PetscFree2(X, Y));
    PetscCall(PetscFree(P[b]));
  }
  for (PetscInt j = 0; j < e; j++) /* exact symmetry for KFDenseEig */
    for (PetscInt i = j + 1; i < e; i++) {
      (*Ms)[i + j * e] = (*Ms)[j + i * e] = 0.5 * ((*Ms)[i + j * e] + (*Ms)[j + i * e]);
      (*Ks)[i + j * e] = (*Ks)[j + i * e] = 0.5 * ((*Ks)[i + j * e] + (*Ks)[j + i * e]);
    }
  *e_out = e;
  PetscFunctionReturn(0);
}

static PetscErrorCode ReassemblyCase(PetscBool free_bodies)
{
  const PetscInt  nnodes[NB] = {3, 3, 2, 3}, nif[NB] = {2, 2, 1, 1}, ifnode[NB][2] = {{0, 2}, {1, 2}, {0, -1}, {2, -1}}, a = 2, t = 3, nmom = 4;
  const PetscReal angles[2] = {0.7, -2.3}, I3[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  const PetscReal rigid_tol = 1e-9;
  TestBody        B[NB];
  KFReducedBody   rb[NB];
  KFJointDef      J[NJ];
  PetscInt        n = 0, e = 0, h, rank, nzero_h = 0, nzero_s = 0;
  PetscReal      *Mh, *Kh, *Gh, *Hh, *Ms, *Ks, *Gs, *Hs, *lh, *ls, *Phi, sratio, err = 0;
  const PetscReal yaxis[3] = {0, 1, 0};
  char            what[160];

  PetscFunctionBegin;
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "KFReassemble: 4 full bodies (v = n_b), revolute + fixed + revolute, %s, against elimination\n", free_bodies ? "free bodies (6 rigid modes each)" : "grounded bodies (K SPD)"));
  for (PetscInt b = 0; b < NB; b++) {
    B[b].nnodes = nnodes[b];
    B[b].n      = 6 * nnodes[b];
    B[b].nif    = nif[b];
    for (PetscInt q = 0; q < nif[b]; q++) B[b].ifnode[q] = ifnode[b][q];
    n += B[b].n;
    PetscCall(PetscMalloc6(B[b].n * B[b].n, &B[b].M, B[b].n * B[b].n, &B[b].K, B[b].n * a, &B[b].G, t * B[b].n, &B[b].H, 6 * nif[b] * B[b].n, &B[b].iface, 3 * nnodes[b], &B[b].xyz));
    RandomMatrix(3 * nnodes[b], 1, B[b].xyz);
    PetscCall(RandomSPD(B[b].n, 0.5, B[b].M));
    if (free_bodies) {
      PetscReal *Z;
      PetscCall(PetscMalloc1(B[b].n * 6, &Z));
      RigidBodyModes(&B[b], Z);
      PetscCall(SingularStiffness(B[b].n, 6, Z, B[b].K));
      PetscCall(PetscFree(Z));
    } else PetscCall(RandomSPD(B[b].n, 0.2, B[b].K));
    RandomMatrix(B[b].n, a, B[b].G);
    RandomMatrix(t, B[b].n, B[b].H);
    PetscCall(PetscArrayzero(B[b].iface, 6 * nif[b] * B[b].n));
    for (PetscInt q = 0; q < nif[b]; q++)
      for (PetscInt c = 0; c < 6; c++) B[b].iface[(6 * q + c) + (6 * ifnode[b][q] + c) * 6 * nif[b]] = 1;
    rb[b].v           = B[b].n;
    rb[b].M           = B[b].M;
    rb[b].K           = B[b].K;
    rb[b].G           = B[b].G;
    rb[b].H           = B[b].H;
    rb[b].ninterfaces = nif[b];
    rb[b].iface       = B[b].iface;
    rb[b].rigid       = NULL;
  }
  /* joint 0: revolute 0 -> 1 about a skew axis with a nontrivial R0; joint 1: fixed 0 -> 2 turned about y;
     joint 2: revolute 1 -> 3 about x. The fixed joint in between checks which angle each revolute gets. */
  J[0] = (KFJointDef){KF_JOINT_REVOLUTE, 0, 0, 1, 0, {0.3, -0.5, 0.8}, {0}};
  PetscCall(KFJointRotation(yaxis, NULL, 0.4, J[0].R0));
  J[1] = (KFJointDef){KF_JOINT_FIXED, 0, 1, 2, 0, {0, 0, 0}, {0}};
  PetscCall(KFJointRotation(yaxis, NULL, -1.1, J[1].R0));
  J[2] = (KFJointDef){KF_JOINT_REVOLUTE, 1, 1, 3, 0, {1, 0, 0}, {0}};
  for (int i = 0; i < 9; i++) J[2].R0[i] = I3[i];

  PetscCall(PetscMalloc4(n * n, &Mh, n * n, &Kh, n * a, &Gh, t * n, &Hh));
  PetscCall(KFReassemble(NB, rb, NJ, J, angles, a, t, 1e-10, &h, Mh, Kh, Gh, Hh, &rank, &sratio, NULL, NULL));
  PetscCall(EliminatedSystem(B, J, angles, a, t, &e, &Ms, &Ks, &Gs, &Hs));
  PetscCall(PetscSNPrintf(what, sizeof(what), "h = %" PetscInt_FMT " (system dofs %" PetscInt_FMT "), rank %" PetscInt_FMT " (ties 16), sratio %.2e: |h - e| + |rank - 16|", h, e, rank, (double)sratio));
  PetscCall(Check(what, (PetscReal)(PetscAbsInt(h - e) + PetscAbsInt(rank - 16)), 0));
  if (h == e) {
    PetscReal *Lh, *Ls;
    PetscCall(PetscMalloc3(h, &lh, h, &ls, h * h, &Phi));
    PetscCall(KFDenseEig(h, Kh, Mh, lh, Phi));
    PetscCall(KFDenseEig(e, Ks, Ms, ls, Phi));
    for (PetscInt i = 0; i < h; i++) err = PetscMax(err, PetscAbsReal(lh[i] - ls[i]));
    PetscCall(Check("max |lambda_reassembled - lambda_eliminated| / lambda_max", err / ls[e - 1], 1e-12));
    for (PetscInt i = 0; i < h; i++) {
      nzero_h += lh[i] <= rigid_tol * lh[h - 1];
      nzero_s += ls[i] <= rigid_tol * ls[e - 1];
    }
    if (free_bodies) {
      PetscCall(PetscSNPrintf(what, sizeof(what), "zero modes: %" PetscInt_FMT " reassembled, %" PetscInt_FMT " eliminated, want 6 rigid + 2 mechanism", nzero_h, nzero_s));
      PetscCall(Check(what, (PetscReal)(PetscAbsInt(nzero_h - 8) + PetscAbsInt(nzero_s - 8)), 0));
      PetscCall(Check("   largest zero eigenvalue / first flexible one", PetscAbsReal(lh[7]) / lh[8], 1e-9));
    } else {
      PetscReal *Xh, *Xs, Th[6], Ts[6];
      PetscCall(PetscMalloc2(h * a, &Xh, e * a, &Xs));
      PetscCall(Solve(h, Kh, a, Gh, Xh));
      PetscCall(Solve(e, Ks, a, Gs, Xs));
      Mul('N', 'N', t, a, h, Hh, Xh, Th);
      Mul('N', 'N', t, a, e, Hs, Xs, Ts);
      PetscCall(Check("static gain: ||Hh Kh^-1 Gh - Hs Ks^-1 Gs|| / ||Hs Ks^-1 Gs||", DiffF(t * a, Th, Ts) / NormF(t * a, 1, Ts), 1e-11));
      PetscCall(PetscFree2(Xh, Xs));
    }
    PetscCall(PetscMalloc2(nmom * t * a, &Lh, nmom * t * a, &Ls));
    PetscCall(KFDenseMoments(h, Kh, Mh, a, Gh, t, Hh, rigid_tol, nmom, Lh));
    PetscCall(KFDenseMoments(e, Ks, Ms, a, Gs, t, Hs, rigid_tol, nmom, Ls));
    PetscCall(Check("moments k = 0..3 (KFDenseMoments on both): max rel. difference", MaxRelMomentError(nmom, t * a, Lh, Ls), 1e-10));
    PetscCall(PetscFree2(Lh, Ls));
    PetscCall(PetscFree3(lh, ls, Phi));
  }
  PetscCall(PetscFree4(Mh, Kh, Gh, Hh));
  PetscCall(PetscFree(Ms));
  PetscCall(PetscFree(Ks));
  PetscCall(PetscFree(Gs));
  PetscCall(PetscFree(Hs));
  for (PetscInt b = 0; b < NB; b++) PetscCall(PetscFree6(B[b].M, B[b].K, B[b].G, B[b].H, B[b].iface, B[b].xyz));
  PetscFunctionReturn(0);
}

/* Cost of one reassembly at the size of a typical reduced scene (informative, nothing asserted) */
static PetscErrorCode TimeReassembly(void)
{
  const PetscInt  v = 60, nif = 1, a = 4, t = 6, reps = 50;
  KFReducedBody   rb[2];
  KFJointDef      J = {KF_JOINT_REVOLUTE, 0, 0, 1, 0, {0, 0, 1}, {1, 0, 0, 0, 1, 0, 0, 0, 1}};
  PetscReal      *M, *K, *G, *H, *Ifc, *Mh, *Kh, *Gh, *Hh, sratio, angle;
  PetscInt        h, rank;
  PetscLogDouble  t0, t1;

  PetscFunctionBegin;
  PetscCall(PetscMalloc5(v * v, &M, v * v, &K, v * a, &G, t * v, &H, 6 * nif * v, &Ifc));
  PetscCall(PetscMalloc4(4 * v * v, &Mh, 4 * v * v, &Kh, 2 * v * a, &Gh, 2 * t * v, &Hh));
  PetscCall(RandomSPD(v, 0.5, M));
  PetscCall(RandomSPD(v, 0.5, K));
  RandomMatrix(v, a, G);
  RandomMatrix(t, v, H);
  RandomMatrix(6 * nif, v, Ifc);
  for (int b = 0; b < 2; b++) rb[b] = (KFReducedBody){v, M, K, G, H, nif, Ifc};
  PetscCall(PetscTime(&t0));
  for (PetscInt s = 0; s < reps; s++) {
    angle = 0.01 * s;
    PetscCall(KFReassemble(2, rb, 1, &J, &angle, a, t, 1e-10, &h, Mh, Kh, Gh, Hh, &rank, &sratio, NULL, NULL));
  }
  PetscCall(PetscTime(&t1));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "KFReassemble timing: 2 bodies of v = 60, 1 revolute joint: %.3f ms per call (h = %" PetscInt_FMT ")\n", 1e3 * (t1 - t0) / reps, h));
  PetscCall(PetscFree5(M, K, G, H, Ifc));
  PetscCall(PetscFree4(Mh, Kh, Gh, Hh));
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  int total;

  PetscCall(PetscInitialize(&argc, &argv, NULL, "Tests of the small dense algebra stage"));
  PetscCall(TestEig());
  PetscCall(TestNullSpace());
  PetscCall(TestMoments());
  PetscCall(TestFRF());
  PetscCall(TestStaticCorrection());
  PetscCall(TestImportance());
  PetscCall(TestImportanceBand());
  PetscCall(TestHankel());
  PetscCall(TestJointRotation());
  PetscCall(ReassemblyCase(PETSC_FALSE));
  PetscCall(ReassemblyCase(PETSC_TRUE));
  PetscCall(TimeReassembly());
  PetscCallMPI(MPI_Allreduce(&nfail, &total, 1, MPI_INT, MPI_MAX, PETSC_COMM_WORLD));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "test_dense: %s (%d failed checks)\n", total ? "FAILED" : "all checks passed", total));
  PetscCall(PetscFinalize());
  return total ? 1 : 0;
}
