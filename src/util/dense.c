#include <kryflex_impl.h>
#include <petscblaslapack.h>
#include <string.h>

/* A parallel dense matrix with the given local row count (the row layout of the system or a body). */
PetscErrorCode KFDenseCreate(MPI_Comm comm, PetscInt nlocal, PetscInt N, PetscInt ncols, Mat *A)
{
  PetscFunctionBegin;
  PetscCall(MatCreateDense(comm, nlocal, PETSC_DECIDE, N, ncols, NULL, A));
  PetscCall(MatAssemblyBegin(*A, MAT_FINAL_ASSEMBLY)); /* zero-filled and usable as an operand at once */
  PetscCall(MatAssemblyEnd(*A, MAT_FINAL_ASSEMBLY));
  PetscFunctionReturn(0);
}

/* The same without the zero fill, for a matrix the caller overwrites entirely (products, solves, copies): PETSc
   zero-fills a dense matrix it allocates, and on the 200k-dof panels those fills of fresh pages were about 1 GB per
   reduction, written once more right after. The array is PETSc's (freed with the matrix). */
PetscErrorCode KFDenseCreateUninitialized(MPI_Comm comm, PetscInt nlocal, PetscInt N, PetscInt ncols, Mat *A)
{
  PetscScalar *a;

  PetscFunctionBegin;
  PetscCall(PetscMalloc1(nlocal * ncols + 1, &a));
  PetscCall(MatCreateDense(comm, nlocal, PETSC_DECIDE, N, ncols, a, A));
  PetscCall(MatDenseReplaceArray(*A, a)); /* a caller's array becomes the matrix' own */
  PetscCall(MatAssemblyBegin(*A, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*A, MAT_FINAL_ASSEMBLY));
  PetscFunctionReturn(0);
}

/* A copy of the dense matrix A (its layout, its values), without PETSc's zero fill before the copy */
PetscErrorCode KFDenseCopyCreate(Mat A, Mat *B)
{
  PetscInt           nl, N, p, lda, ldb;
  const PetscScalar *a;
  PetscScalar       *b;

  PetscFunctionBegin;
  PetscCall(MatGetLocalSize(A, &nl, NULL));
  PetscCall(MatGetSize(A, &N, &p));
  PetscCall(KFDenseCreateUninitialized(PetscObjectComm((PetscObject)A), nl, N, p, B));
  PetscCall(MatDenseGetLDA(A, &lda));
  PetscCall(MatDenseGetLDA(*B, &ldb));
  PetscCall(MatDenseGetArrayRead(A, &a));
  PetscCall(MatDenseGetArrayWrite(*B, &b));
  for (PetscInt j = 0; j < p; j++) PetscCall(PetscArraycpy(b + j * ldb, a + j * lda, nl));
  PetscCall(MatDenseRestoreArrayRead(A, &a));
  PetscCall(MatDenseRestoreArrayWrite(*B, &b));
  PetscFunctionReturn(0);
}

/* Every rank gets the whole (small) matrix, column-major: its rows are spread over the ranks. */
PetscErrorCode KFDenseGather(Mat A, PetscReal out[])
{
  PetscInt           m, n, rstart, rend, lda, i, j;
  const PetscScalar *a;
  PetscReal         *buf;
  MPI_Comm           comm;

  PetscFunctionBegin;
  PetscCall(PetscObjectGetComm((PetscObject)A, &comm));
  PetscCall(MatGetSize(A, &m, &n));
  PetscCall(MatGetOwnershipRange(A, &rstart, &rend));
  PetscCall(MatDenseGetLDA(A, &lda));
  PetscCall(PetscCalloc1(m * n, &buf));
  PetscCall(MatDenseGetArrayRead(A, &a));
  for (j = 0; j < n; j++)
    for (i = rstart; i < rend; i++) buf[i + j * m] = PetscRealPart(a[(i - rstart) + j * lda]);
  PetscCall(MatDenseRestoreArrayRead(A, &a));
  PetscCall(MPIU_Allreduce(buf, out, (PetscMPIInt)(m * n), MPIU_REAL, MPIU_SUM, comm));
  PetscCall(PetscFree(buf));
  PetscFunctionReturn(0);
}

/* A^T B for local row blocks A (nl x p, leading dimension lda) and B (nl x q): local products (BLAS) summed over the
   ranks of comm into out (p x q, column-major, replicated) */
PetscErrorCode KFArrayTransposeMultGather(MPI_Comm comm, PetscInt nl, PetscInt p, const PetscScalar *a, PetscInt lda, PetscInt q, const PetscScalar *b, PetscInt ldb, PetscReal out[])
{
  PetscReal *buf;

  PetscFunctionBegin;
  PetscCall(PetscCalloc1(p * q + 1, &buf));
  if (nl > 0 && p > 0 && q > 0) {
    PetscBLASInt bp, bq, bn, bla, blb;
    PetscScalar  one = 1.0, zero = 0.0;
    PetscCall(PetscBLASIntCast(p, &bp));
    PetscCall(PetscBLASIntCast(q, &bq));
    PetscCall(PetscBLASIntCast(nl, &bn));
    PetscCall(PetscBLASIntCast(lda, &bla));
    PetscCall(PetscBLASIntCast(ldb, &blb));
    PetscCallBLAS("BLASgemm", BLASgemm_("T", "N", &bp, &bq, &bn, &one, a, &bla, b, &blb, &zero, buf, &bp));
  }
  PetscCall(MPIU_Allreduce(buf, out, (PetscMPIInt)(p * q), MPIU_REAL, MPIU_SUM, comm));
  PetscCall(PetscFree(buf));
  PetscFunctionReturn(0);
}

/* X += alpha A c for local row blocks A (nl x r, leading dimension lda), X (nl x p) and a small replicated c (r x p,
   column-major) */
PetscErrorCode KFArrayMultSmall(PetscInt nl, PetscInt r, PetscInt p, const PetscScalar *a, PetscInt lda, const PetscReal c[], PetscReal alpha, PetscScalar *x, PetscInt ldx)
{
  PetscBLASInt bn, br, bp, bla, blx;
  PetscScalar  one = 1.0, al = alpha;

  PetscFunctionBegin;
  if (nl == 0 || r == 0 || p == 0) PetscFunctionReturn(0);
  PetscCall(PetscBLASIntCast(nl, &bn));
  PetscCall(PetscBLASIntCast(r, &br));
  PetscCall(PetscBLASIntCast(p, &bp));
  PetscCall(PetscBLASIntCast(lda, &bla));
  PetscCall(PetscBLASIntCast(ldx, &blx));
  PetscCallBLAS("BLASgemm", BLASgemm_("N", "N", &bn, &bp, &br, &al, a, &bla, c, &br, &one, x, &blx));
  PetscFunctionReturn(0);
}

/* Row chunk of the skinny products below: a chunk of the block (ROWS x p) stays in cache while every basis column
   meets it, and each operand is read once from memory in order. A whole-height BLAS gemm of a tall basis with a block
   of 1-8 columns copies (packs) the basis into a buffer before using it for 2-16 flops per entry: on this
   bandwidth-bound product the copy was half of the Gram-Schmidt's time (perf, 200k-dof panel scene). For the Krylov basis' Gram-Schmidt and the projections onto
   the flexible subspace (a few rigid modes against a block). */
#define KF_SKINNY_ROWS 2048

#if !defined(PETSC_USE_COMPLEX) && defined(PETSC_USE_REAL_DOUBLE) && defined(__GNUC__)
  #define KF_SKINNY_TN_OWN 1
/* The transposed product A^T X of a chunk for a block X of at most KF_SKINNY_TN_COLS columns, without BLAS: OpenBLAS'
   gemm ("T", "N") took the chunk's basis columns at 6.7 GB/s where a plain read of them runs at 11 (a 200,000 x 60
   basis against 2 columns: 14.4 against 8.7 ms per product, this machine); it is the Gram-Schmidt's coefficient sweep,
   bound by the bytes of the basis. Four columns of A meet two of X at a time, rows four wide, in eight independent
   sums; the places past the last group of four columns of A (or the last pair of X) repeat its last column, already
   in cache, and their sums are discarded. */
  #define KF_SKINNY_TN_COLS 8
typedef double KFVec4 __attribute__((vector_size(32)));

/* out (nc x p, ldo) += A^T X over m rows */
static inline __attribute__((always_inline)) void KFSkinnyTNKernel(PetscInt m, PetscInt nc, const double *a, PetscInt lda, PetscInt p, const double *x, PetscInt ldx, double *out, PetscInt ldo)
{
  const PetscInt m4 = m - m % 4;

  for (PetscInt j = 0; j < nc; j += 4) {
    const PetscInt nj = PetscMin(4, nc - j);
    const double  *ac[4];

    for (int t = 0; t < 4; t++) ac[t] = a + (size_t)(j + PetscMin(t, nj - 1)) * lda;
    for (PetscInt q = 0; q < p; q += 2) {
      const PetscInt nq = PetscMin(2, p - q);
      const double  *x0 = x + (size_t)q * ldx, *x1 = x + (size_t)(q + nq - 1) * ldx;
      KFVec4         s[4][2];
      double         r[4][2];

      for (int t = 0; t < 4; t++)
        for (int u = 0; u < 2; u++) {
          s[t][u] = (KFVec4){0, 0, 0, 0};
          r[t][u] = 0;
        }
      for (PetscInt i = 0; i < m4; i += 4) {
        KFVec4 y0, y1;

        memcpy(&y0, x0 + i, sizeof(y0)); /* unaligned loads */
        memcpy(&y1, x1 + i, sizeof(y1));
        for (int t = 0; t < 4; t++) {
          KFVec4 v;

          memcpy(&v, ac[t] + i, sizeof(v));
          s[t][0] += v * y0;
          s[t][1] += v * y1;
        }
      }
      for (PetscInt i = m4; i < m; i++)
        for (int t = 0; t < 4; t++) {
          r[t][0] += ac[t][i] * x0[i];
          r[t][1] += ac[t][i] * x1[i];
        }
      for (PetscInt t = 0; t < nj; t++)
        for (PetscInt u = 0; u < nq; u++) out[(j + t) + (q + u) * ldo] += ((s[t][u][0] + s[t][u][1]) + (s[t][u][2] + s[t][u][3])) + r[t][u];
    }
  }
}

typedef void (*KFSkinnyTNFn)(PetscInt, PetscInt, const double *, PetscInt, PetscInt, const double *, PetscInt, double *, PetscInt);
  #if defined(__x86_64__)
__attribute__((target("avx2,fma"))) static void KFSkinnyTNAVX2(PetscInt m, PetscInt nc, const double *a, PetscInt lda, PetscInt p, const double *x, PetscInt ldx, double *out, PetscInt ldo)
{
  KFSkinnyTNKernel(m, nc, a, lda, p, x, ldx, out, ldo);
}
  #endif
static void KFSkinnyTNGeneric(PetscInt m, PetscInt nc, const double *a, PetscInt lda, PetscInt p, const double *x, PetscInt ldx, double *out, PetscInt ldo)
{
  KFSkinnyTNKernel(m, nc, a, lda, p, x, ldx, out, ldo);
}

/* the kernel this CPU runs: AVX2 with FMA, else the generic one */
static KFSkinnyTNFn KFSkinnyTNSelect(void)
{
  #if defined(__x86_64__)
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return KFSkinnyTNAVX2;
  #endif
  return KFSkinnyTNGeneric;
}
#endif

/* out (nc x p, leading dimension ldo) += A^T X over local rows, A nl x nc (lda), X nl x p (ldx), chunk by chunk */
PetscErrorCode KFArraySkinnyTransposeMult(PetscInt nl, PetscInt nc, const PetscScalar *a, PetscInt lda, PetscInt p, const PetscScalar *x, PetscInt ldx, PetscScalar *out, PetscInt ldo)
{
  PetscBLASInt bc, bp, bm, bla, blx, blo;
  PetscScalar  one = 1.0;

  PetscFunctionBegin;
  if (nl <= 0 || nc <= 0 || p <= 0) PetscFunctionReturn(0);
#if defined(KF_SKINNY_TN_OWN)
  if (p <= KF_SKINNY_TN_COLS) {
    static KFSkinnyTNFn kernel = NULL;

    if (!kernel) kernel = KFSkinnyTNSelect();
    for (PetscInt i0 = 0; i0 < nl; i0 += KF_SKINNY_ROWS) kernel(PetscMin(KF_SKINNY_ROWS, nl - i0), nc, a + i0, lda, p, x + i0, ldx, out, ldo);
    PetscFunctionReturn(0);
  }
#endif
  PetscCall(PetscBLASIntCast(nc, &bc));
  PetscCall(PetscBLASIntCast(p, &bp));
  PetscCall(PetscBLASIntCast(lda, &bla));
  PetscCall(PetscBLASIntCast(ldx, &blx));
  PetscCall(PetscBLASIntCast(ldo, &blo));
  for (PetscInt i0 = 0; i0 < nl; i0 += KF_SKINNY_ROWS) {
    PetscCall(PetscBLASIntCast(PetscMin(KF_SKINNY_ROWS, nl - i0), &bm));
    PetscCallBLAS("BLASgemm", BLASgemm_("T", "N", &bc, &bp, &bm, &one, a + i0, &bla, x + i0, &blx, &one, out, &blo));
  }
  PetscFunctionReturn(0);
}

/* X (nl x p, ldx) = alpha A c + beta X over local rows, A nl x nc (lda), c nc x p (ldc), chunk by chunk; with beta 0
   X's values before are not read (no zero fill needed) */
static PetscErrorCode KFArraySkinnyMult_Private(PetscInt nl, PetscInt nc, const PetscScalar *a, PetscInt lda, PetscInt p, PetscScalar alpha, const PetscScalar *c, PetscInt ldc, PetscScalar beta, PetscScalar *x, PetscInt ldx)
{
  PetscBLASInt bc, bp, bm, bla, blx, blc;

  PetscFunctionBegin;
  if (nl <= 0 || p <= 0) PetscFunctionReturn(0);
  if (nc <= 0) {
    if (beta == 0.0)
      for (PetscInt j = 0; j < p; j++) PetscCall(PetscArrayzero(x + j * ldx, nl));
    PetscFunctionReturn(0);
  }
  PetscCall(PetscBLASIntCast(nc, &bc));
  PetscCall(PetscBLASIntCast(p, &bp));
  PetscCall(PetscBLASIntCast(lda, &bla));
  PetscCall(PetscBLASIntCast(ldx, &blx));
  PetscCall(PetscBLASIntCast(ldc, &blc));
  for (PetscInt i0 = 0; i0 < nl; i0 += KF_SKINNY_ROWS) {
    PetscCall(PetscBLASIntCast(PetscMin(KF_SKINNY_ROWS, nl - i0), &bm));
    PetscCallBLAS("BLASgemm", BLASgemm_("N", "N", &bm, &bp, &bc, &alpha, a + i0, &bla, c, &blc, &beta, x + i0, &blx));
  }
  PetscFunctionReturn(0);
}

/* X (nl x p, ldx) = alpha A c over local rows (X's values before are not read: no zero fill needed) */
PetscErrorCode KFArraySkinnyMultSet(PetscInt nl, PetscInt nc, const PetscScalar *a, PetscInt lda, PetscInt p, PetscScalar alpha, const PetscScalar *c, PetscInt ldc, PetscScalar *x, PetscInt ldx)
{
  PetscFunctionBegin;
  PetscCall(KFArraySkinnyMult_Private(nl, nc, a, lda, p, alpha, c, ldc, 0.0, x, ldx));
  PetscFunctionReturn(0);
}

/* X (nl x p, ldx) += alpha A c over local rows, A nl x nc (lda), c nc x p (ldc), chunk by chunk */
PetscErrorCode KFArraySkinnyMultAdd(PetscInt nl, PetscInt nc, const PetscScalar *a, PetscInt lda, PetscInt p, PetscScalar alpha, const PetscScalar *c, PetscInt ldc, PetscScalar *x, PetscInt ldx)
{
  PetscFunctionBegin;
  PetscCall(KFArraySkinnyMult_Private(nl, nc, a, lda, p, alpha, c, ldc, 1.0, x, ldx));
  PetscFunctionReturn(0);
}

/* A^T B for tall dense A (N x p) and B (N x q) with the same row layout: local products (BLAS) summed over ranks. */
PetscErrorCode KFMatTransposeMatMultGather(Mat A, Mat B, PetscReal out[])
{
  PetscInt           nl, p, q, lda, ldb;
  const PetscScalar *a, *b;
  MPI_Comm           comm;

  PetscFunctionBegin;
  PetscCall(PetscObjectGetComm((PetscObject)A, &comm));
  PetscCall(MatGetLocalSize(A, &nl, NULL));
  PetscCall(MatGetSize(A, NULL, &p));
  PetscCall(MatGetSize(B, NULL, &q));
  PetscCall(MatDenseGetLDA(A, &lda));
  PetscCall(MatDenseGetLDA(B, &ldb));
  PetscCall(MatDenseGetArrayRead(A, &a));
  PetscCall(MatDenseGetArrayRead(B, &b));
  PetscCall(KFArrayTransposeMultGather(comm, nl, p, a, lda, q, b, ldb, out));
  PetscCall(MatDenseRestoreArrayRead(A, &a));
  PetscCall(MatDenseRestoreArrayRead(B, &b));
  PetscFunctionReturn(0);
}

/* X += alpha A c for tall dense A (N x r), X (N x p) with the same row layout and a small replicated c (r x p) */
PetscErrorCode KFDenseMultSmall(Mat A, PetscInt r, PetscInt p, const PetscReal c[], PetscReal alpha, Mat X)
{
  PetscInt           nl, lda, ldx;
  const PetscScalar *a;
  PetscScalar       *x;

  PetscFunctionBegin;
  PetscCall(MatGetLocalSize(A, &nl, NULL));
  if (nl == 0 || r == 0 || p == 0) PetscFunctionReturn(0);
  PetscCall(MatDenseGetLDA(A, &lda));
  PetscCall(MatDenseGetLDA(X, &ldx));
  PetscCall(MatDenseGetArrayRead(A, &a));
  PetscCall(MatDenseGetArray(X, &x));
  PetscCall(KFArrayMultSmall(nl, r, p, a, lda, c, alpha, x, ldx));
  PetscCall(MatDenseRestoreArrayRead(A, &a));
  PetscCall(MatDenseRestoreArray(X, &x));
  PetscFunctionReturn(0);
}

PetscErrorCode KFMatCombine(Mat X, PetscInt m, const PetscReal C[], Mat *Y)
{
  PetscInt nl, N, p;

  PetscFunctionBegin;
  PetscCall(MatGetLocalSize(X, &nl, NULL));
  PetscCall(MatGetSize(X, &N, &p));
  PetscCall(KFDenseCreate(PetscObjectComm((PetscObject)X), nl, N, m, Y));
  PetscCall(KFDenseMultSmall(X, p, m, C, 1.0, *Y));
  PetscFunctionReturn(0);
}

PetscErrorCode KFMatInner(Mat A, Mat B, PetscReal out[])
{
  PetscFunctionBegin;
  PetscCall(KFMatTransposeMatMultGather(A, B, out));
  PetscFunctionReturn(0);
}

/* [A, B] for two tall dense Mats with the same row layout */
PetscErrorCode KFDenseHStack(Mat A, Mat B, Mat *X)
{
  PetscInt           nl, N, p, q, lda, ldb, ldx;
  const PetscScalar *pa, *pb;
  PetscScalar       *px;

  PetscFunctionBegin;
  PetscCall(MatGetLocalSize(A, &nl, NULL));
  PetscCall(MatGetSize(A, &N, &p));
  PetscCall(MatGetSize(B, NULL, &q));
  PetscCall(KFDenseCreate(PetscObjectComm((PetscObject)A), nl, N, p + q, X));
  PetscCall(MatDenseGetLDA(A, &lda));
  PetscCall(MatDenseGetLDA(B, &ldb));
  PetscCall(MatDenseGetLDA(*X, &ldx));
  PetscCall(MatDenseGetArrayRead(A, &pa));
  PetscCall(MatDenseGetArrayRead(B, &pb));
  PetscCall(MatDenseGetArrayWrite(*X, &px));
  for (PetscInt j = 0; j < p; j++) PetscCall(PetscArraycpy(&px[j * ldx], &pa[j * lda], nl));
  for (PetscInt j = 0; j < q; j++) PetscCall(PetscArraycpy(&px[(p + j) * ldx], &pb[j * ldb], nl));
  PetscCall(MatDenseRestoreArrayWrite(*X, &px));
  PetscCall(MatDenseRestoreArrayRead(B, &pb));
  PetscCall(MatDenseRestoreArrayRead(A, &pa));
  PetscFunctionReturn(0);
}
