#include <kryflex_impl.h>
#include <petsc/private/matimpl.h>

/* Y = A X for sparse A (AIJ) and tall dense X, each entry accumulated in double-double and rounded once. For a soft
   vector x of a stiff structure, K x is a small difference of large terms: in double its rounding is eps |K| |x|, far
   above |K x|; accumulated in twice the working precision it is eps |K x| (up to eps^2 |K| |x|). The residuals of
   iterative refinement and the reduced stiffness matrices need that.

   The sums are Ogita, Rump and Oishi's Dot2 (SIAM J. Sci. Comput. 26, 2005): each product split exactly into p + pe
   by an FMA, p added to the running sum s by Knuth's TwoSum (s + p = t + e exactly), the errors pe + e summed in c,
   y = s + c rounded once. The result is as if computed in quadruple precision and rounded (error <= eps |y| +
   gamma_n^2 |A| |x|): more accurate than the x87 long double (64-bit mantissa) these sums used before, and 4-6x
   faster, because it is plain double arithmetic the CPU runs 4 or 8 columns wide. It needs the operations exactly as
   written: this file is compiled with -ffp-contract=off (CMakeLists.txt), else the compiler may fuse s + a x into an
   FMA and lose the error terms. Every path below (AVX-512, AVX2, generic with libm's fma) does the same operations
   per entry in the same order, so Y is the same to the bit on any x86-64. */
#define KF_EXT_CHUNK 8 /* columns per sweep over A: one AVX-512 register, two AVX2 ones */

/* y[i + j ldy] (j < nj) = sum_k a_ik x_k for a chunk of W columns stored row by row (xt: nc x W, xgt: the
   off-process block's ghost rows, ng x W, zero-padded past nj): row by row, each row of A read once per chunk, the
   chunk's W sums independent and contiguous. W is a constant at each call (8, 4, 2 or 1: a block of 3 columns, the
   refinement residual's usual size, costs 4 sums per entry, not 8); a column's operations do not depend on W. */
static inline __attribute__((always_inline)) void KFExtKernel(const int W, PetscInt m, const PetscInt *ia, const PetscInt *ja, const PetscScalar *a, const PetscScalar *xt, const PetscInt *ib, const PetscInt *jb, const PetscScalar *b, const PetscScalar *xgt, PetscInt nj, PetscScalar *y, PetscInt ldy)
{
  for (PetscInt i = 0; i < m; i++) {
    double s[KF_EXT_CHUNK] = {0}, c[KF_EXT_CHUNK] = {0};

    for (int blk = 0; blk < 2; blk++) {
      const PetscInt    *ir = blk ? ib : ia, *jr = blk ? jb : ja;
      const PetscScalar *ar = blk ? b : a, *xr = blk ? xgt : xt;

      if (!ir) continue;
      for (PetscInt k = ir[i]; k < ir[i + 1]; k++) {
        const double  ak = ar[k];
        const double *xk = xr + (size_t)jr[k] * W;

        for (int j = 0; j < W; j++) {
          const double p = ak * xk[j], pe = __builtin_fma(ak, xk[j], -p); /* TwoProduct: ak xk = p + pe */
          const double t = s[j] + p, z = t - s[j], e = (s[j] - (t - z)) + (p - z); /* TwoSum: s + p = t + e */

          c[j] += pe + e;
          s[j] = t;
        }
      }
    }
    for (PetscInt j = 0; j < nj; j++) y[i + j * ldy] = s[j] + c[j];
  }
}

/* The same sweep in plain double, for products that need no more than double (M X): each entry summed as PETSc's
   MatMatMult sums it (the diagonal block's row in order, then the off-process block's row in order added to it), so
   the result is the same to the bit on 1 and 2 ranks, only with one read of A per chunk of up to 8 columns stored
   row by row, run 4 or 8 columns wide. */
static inline __attribute__((always_inline)) void KFPlainKernel(const int W, PetscInt m, const PetscInt *ia, const PetscInt *ja, const PetscScalar *a, const PetscScalar *xt, const PetscInt *ib, const PetscInt *jb, const PetscScalar *b, const PetscScalar *xgt, PetscInt nj, PetscScalar *y, PetscInt ldy)
{
  for (PetscInt i = 0; i < m; i++) {
    double s[KF_EXT_CHUNK] = {0}, o[KF_EXT_CHUNK] = {0};

    for (PetscInt k = ia[i]; k < ia[i + 1]; k++) {
      const double  ak = a[k];
      const double *xk = xt + (size_t)ja[k] * W;

      for (int j = 0; j < W; j++) s[j] += ak * xk[j];
    }
    if (ib) {
      for (PetscInt k = ib[i]; k < ib[i + 1]; k++) {
        const double  bk = b[k];
        const double *xk = xgt + (size_t)jb[k] * W;

        for (int j = 0; j < W; j++) o[j] += bk * xk[j];
      }
      for (int j = 0; j < W; j++) s[j] += o[j];
    }
    for (PetscInt j = 0; j < nj; j++) y[i + j * ldy] = s[j];
  }
}

/* The plain sweep with, beside each sum, a bound on its rounding: a row's recursive sum of n rounded products is
   within gamma_n sum |a_k x_k| of the exact one (gamma_n = n u / (1 - n u), u the unit roundoff; Higham, Accuracy and
   Stability, 3.1), and the computed sum of the magnitudes is within a factor 1 + gamma_n of theirs. The sums are the
   plain kernel's (the same bits); yb[i + j ldy] receives gamma (1 + gamma) times the magnitudes' sum, with n the row's
   entries in both blocks and 2 for the products' rounding and the blocks' addition. */
static inline __attribute__((always_inline)) void KFBoundKernel(const int W, PetscInt m, const PetscInt *ia, const PetscInt *ja, const PetscScalar *a, const PetscScalar *xt, const PetscInt *ib, const PetscInt *jb, const PetscScalar *b, const PetscScalar *xgt, PetscInt nj, PetscScalar *y, PetscInt ldy, PetscScalar *yb)
{
  const double u = 0.5 * PETSC_MACHINE_EPSILON;

  for (PetscInt i = 0; i < m; i++) {
    double   s[KF_EXT_CHUNK] = {0}, o[KF_EXT_CHUNK] = {0}, sa[KF_EXT_CHUNK] = {0};
    PetscInt n = 2;

    for (int blk = 0; blk < 2; blk++) { /* the diagonal block's sums in s, the off-process block's in o */
      const PetscInt    *ir = blk ? ib : ia, *jr = blk ? jb : ja;
      const PetscScalar *ar = blk ? b : a, *xr = blk ? xgt : xt;
      double            *acc = blk ? o : s;

      if (!ir) continue;
      n += ir[i + 1] - ir[i];
      for (PetscInt k = ir[i]; k < ir[i + 1]; k++) {
        const double  ak = ar[k];
        const double *xk = xr + (size_t)jr[k] * W;

        for (int j = 0; j < W; j++) {
          const double p = ak * xk[j];

          acc[j] += p;
          sa[j] += __builtin_fabs(p);
        }
      }
    }
    if (ib)
      for (int j = 0; j < W; j++) s[j] += o[j];
    {
      const double g = n * u / (1 - n * u), f = g * (1 + g);

      for (PetscInt j = 0; j < nj; j++) {
        y[i + j * ldy]  = s[j];
        yb[i + j * ldy] = f * sa[j];
      }
    }
  }
}

/* One function per instruction set, kernel and width (the width a constant in each: one function holding every
   variant was not vectorized as well, 2.5x slower), and a table per instruction set: [plain, extended][8, 4, 2, 1]. */
#define KF_KERNEL_ARGS PetscInt m, const PetscInt *ia, const PetscInt *ja, const PetscScalar *a, const PetscScalar *xt, const PetscInt *ib, const PetscInt *jb, const PetscScalar *b, const PetscScalar *xgt, PetscInt nj, PetscScalar *y, PetscInt ldy
#define KF_KERNEL_PASS m, ia, ja, a, xt, ib, jb, b, xgt, nj, y, ldy
typedef void (*KFKernelFn)(KF_KERNEL_ARGS);
typedef void (*KFBoundFn)(KF_KERNEL_ARGS, PetscScalar *yb);
#define KF_DEFINE_KERNELS(ATTR, SFX) \
  ATTR static void KFPlain8##SFX(KF_KERNEL_ARGS) { KFPlainKernel(8, KF_KERNEL_PASS); } \
  ATTR static void KFPlain4##SFX(KF_KERNEL_ARGS) { KFPlainKernel(4, KF_KERNEL_PASS); } \
  ATTR static void KFPlain2##SFX(KF_KERNEL_ARGS) { KFPlainKernel(2, KF_KERNEL_PASS); } \
  ATTR static void KFPlain1##SFX(KF_KERNEL_ARGS) { KFPlainKernel(1, KF_KERNEL_PASS); } \
  ATTR static void KFExt8##SFX(KF_KERNEL_ARGS) { KFExtKernel(8, KF_KERNEL_PASS); } \
  ATTR static void KFExt4##SFX(KF_KERNEL_ARGS) { KFExtKernel(4, KF_KERNEL_PASS); } \
  ATTR static void KFExt2##SFX(KF_KERNEL_ARGS) { KFExtKernel(2, KF_KERNEL_PASS); } \
  ATTR static void KFExt1##SFX(KF_KERNEL_ARGS) { KFExtKernel(1, KF_KERNEL_PASS); } \
  static const KFKernelFn KFKernels##SFX[2][4] = { \
    {KFPlain8##SFX, KFPlain4##SFX, KFPlain2##SFX, KFPlain1##SFX}, \
    {KFExt8##SFX,   KFExt4##SFX,   KFExt2##SFX,   KFExt1##SFX  } \
  }; \
  ATTR static void KFBound8##SFX(KF_KERNEL_ARGS, PetscScalar *yb) { KFBoundKernel(8, KF_KERNEL_PASS, yb); } \
  ATTR static void KFBound4##SFX(KF_KERNEL_ARGS, PetscScalar *yb) { KFBoundKernel(4, KF_KERNEL_PASS, yb); } \
  ATTR static void KFBound2##SFX(KF_KERNEL_ARGS, PetscScalar *yb) { KFBoundKernel(2, KF_KERNEL_PASS, yb); } \
  ATTR static void KFBound1##SFX(KF_KERNEL_ARGS, PetscScalar *yb) { KFBoundKernel(1, KF_KERNEL_PASS, yb); } \
  static const KFBoundFn KFBounds##SFX[4] = {KFBound8##SFX, KFBound4##SFX, KFBound2##SFX, KFBound1##SFX};

#if defined(__GNUC__) && defined(__x86_64__)
  #define KF_EXT_DISPATCH 1
KF_DEFINE_KERNELS(__attribute__((target("avx512f,fma"))), AVX512)
KF_DEFINE_KERNELS(__attribute__((target("avx2,fma"))), AVX2)
#endif
KF_DEFINE_KERNELS(, Generic)

/* the kernels this CPU runs: AVX-512, else AVX2 (both with FMA), else the generic ones; bounds: the bound kernels */
static const KFKernelFn (*KFKernelTable(const KFBoundFn **bounds))[4]
{
#if defined(KF_EXT_DISPATCH)
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("fma")) {
    *bounds = KFBoundsAVX512;
    return KFKernelsAVX512;
  }
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) {
    *bounds = KFBoundsAVX2;
    return KFKernelsAVX2;
  }
#endif
  *bounds = KFBoundsGeneric;
  return KFKernelsGeneric;
}

/* the chunk width for nj columns: the smallest of 1, 2, 4, 8 that holds them, and its place in the tables */
static int KFExtWidth(PetscInt nj, int *slot)
{
  *slot = nj > 4 ? 0 : nj > 2 ? 1 : nj > 1 ? 2 : 3;
  return 8 >> *slot;
}

/* columns j0 .. j0 + nj - 1 of x (nr rows, leading dimension ldx) row by row into xt (nr x W, zero-padded) */
static void KFExtTransposeChunk(PetscInt nr, const PetscScalar *x, PetscInt ldx, PetscInt j0, PetscInt nj, int W, PetscScalar *xt)
{
  for (PetscInt r = 0; r < nr; r++)
    for (PetscInt j = 0; j < W; j++) xt[r * W + j] = j < nj ? x[r + (j0 + j) * ldx] : 0.0;
}

/* yb not NULL: the plain sums and their rounding bounds (KFBoundKernel), ext ignored */
static PetscErrorCode KFSeqAIJMultChunked(PetscBool ext, Mat A, PetscInt ncols, const PetscScalar *x, PetscInt ldx, const PetscScalar *xg, PetscInt ldg, Mat B, PetscScalar *y, PetscInt ldy, PetscScalar *yb)
{
  const PetscInt    *ia, *ja, *ib = NULL, *jb = NULL;
  const PetscScalar *a, *b = NULL;
  PetscScalar       *xt, *xgt;
  PetscInt           m, mb, nc, ng = 0;
  PetscBool          done;
  const KFBoundFn *bounds;
  const KFKernelFn(*kernels)[4] = KFKernelTable(&bounds);

  PetscFunctionBegin;
  PetscCall(MatGetSize(A, NULL, &nc));
  PetscCall(MatGetRowIJ(A, 0, PETSC_FALSE, PETSC_FALSE, &m, &ia, &ja, &done));
  PetscCheck(done, PETSC_COMM_SELF, PETSC_ERR_SUP, "cannot get the rows of the matrix");
  PetscCall(MatSeqAIJGetArrayRead(A, &a));
  if (B) {
    PetscCall(MatGetSize(B, NULL, &ng));
    PetscCall(MatGetRowIJ(B, 0, PETSC_FALSE, PETSC_FALSE, &mb, &ib, &jb, &done));
    PetscCheck(done && mb == m, PETSC_COMM_SELF, PETSC_ERR_SUP, "cannot get the rows of the off-process block");
    PetscCall(MatSeqAIJGetArrayRead(B, &b));
  }
  /* a chunk of columns per sweep over A, each stored row by row: one entry of A meets eight contiguous values */
  PetscCall(PetscMalloc2(nc * KF_EXT_CHUNK + 1, &xt, ng * KF_EXT_CHUNK + 1, &xgt));
  for (PetscInt j0 = 0; j0 < ncols; j0 += KF_EXT_CHUNK) {
    const PetscInt nj = PetscMin(KF_EXT_CHUNK, ncols - j0);
    int            slot;
    const int      W = KFExtWidth(nj, &slot);

    KFExtTransposeChunk(nc, x, ldx, j0, nj, W, xt);
    if (B) KFExtTransposeChunk(ng, xg, ldg, j0, nj, W, xgt);
    if (yb) bounds[slot](m, ia, ja, a, xt, ib, jb, b, xgt, nj, y + j0 * ldy, ldy, yb + j0 * ldy);
    else kernels[ext ? 1 : 0][slot](m, ia, ja, a, xt, ib, jb, b, xgt, nj, y + j0 * ldy, ldy);
  }
  PetscCall(PetscFree2(xt, xgt));
  PetscCall(MatSeqAIJRestoreArrayRead(A, &a));
  PetscCall(MatRestoreRowIJ(A, 0, PETSC_FALSE, PETSC_FALSE, &m, &ia, &ja, &done));
  if (B) {
    PetscCall(MatSeqAIJRestoreArrayRead(B, &b));
    PetscCall(MatRestoreRowIJ(B, 0, PETSC_FALSE, PETSC_FALSE, &mb, &ib, &jb, &done));
  }
  PetscFunctionReturn(0);
}

/* Y = A X by the chunked sweeps above, extended (double-double) or plain; *Y NULL: made here, else a dense matrix of
   A's rows and X's columns that is overwritten. Yb not NULL: Y plain and *Yb (made here) the bounds of its rounding */
static PetscErrorCode KFMatMultChunked(PetscBool ext, Mat A, Mat X, Mat *Y, Mat *Yb)
{
  PetscBool          mpi;
  PetscInt           nl, N, ncols, ldx, ldy;
  const PetscScalar *x;
  PetscScalar       *y, *yb = NULL;
  MPI_Comm           comm;

  PetscFunctionBegin;
  PetscCall(PetscObjectGetComm((PetscObject)A, &comm));
  PetscCall(MatGetLocalSize(A, &nl, NULL));
  PetscCall(MatGetSize(A, &N, NULL));
  PetscCall(MatGetSize(X, NULL, &ncols));
  if (!*Y) PetscCall(KFDenseCreateUninitialized(comm, nl, N, ncols, Y)); /* every entry written below */
  else {
    PetscInt yl, yc;

    PetscCall(MatGetLocalSize(*Y, &yl, NULL));
    PetscCall(MatGetSize(*Y, NULL, &yc));
    PetscCheck(yl == nl && yc == ncols, comm, PETSC_ERR_ARG_SIZ, "the product's matrix has %" PetscInt_FMT " local rows and %" PetscInt_FMT " columns, not %" PetscInt_FMT " and %" PetscInt_FMT, yl, yc, nl, ncols);
  }
  PetscCall(PetscObjectTypeCompare((PetscObject)A, MATMPIAIJ, &mpi));
  PetscCall(MatDenseGetLDA(X, &ldx));
  PetscCall(MatDenseGetLDA(*Y, &ldy));
  PetscCall(MatDenseGetArrayRead(X, &x));
  PetscCall(MatDenseGetArrayWrite(*Y, &y));
  if (Yb) {
    PetscInt ldb;

    PetscCall(KFDenseCreateUninitialized(comm, nl, N, ncols, Yb));
    PetscCall(MatDenseGetLDA(*Yb, &ldb));
    PetscCheck(ldb == ldy, comm, PETSC_ERR_ARG_SIZ, "the product's bounds need its leading dimension (%" PetscInt_FMT ", not %" PetscInt_FMT ")", ldy, ldb);
    PetscCall(MatDenseGetArrayWrite(*Yb, &yb));
  }
  if (!mpi) PetscCall(KFSeqAIJMultChunked(ext, A, ncols, x, ldx, NULL, 0, NULL, y, ldy, yb));
  else {
    /* the diagonal block reads local rows of X, the off-process block reads the ghost rows listed in colmap */
    Mat             Ad, Ao;
    const PetscInt *colmap;
    PetscInt        ng, xstart;
    PetscScalar    *xg;
    IS              from;
    Vec             xcol, gcol;
    VecScatter      sc;
    PetscCall(MatMPIAIJGetSeqAIJ(A, &Ad, &Ao, &colmap));
    PetscCall(MatGetSize(Ao, NULL, &ng));
    PetscCall(MatGetOwnershipRange(X, &xstart, NULL));
    PetscCall(PetscMalloc1(ng * ncols + 1, &xg));
    PetscCall(ISCreateGeneral(PETSC_COMM_SELF, ng, colmap, PETSC_USE_POINTER, &from));
    PetscCall(VecCreateSeqWithArray(PETSC_COMM_SELF, 1, ng, xg, &gcol));
    PetscCall(MatDenseRestoreArrayRead(X, &x));
    for (PetscInt j = 0; j < ncols; j++) {
      PetscCall(MatDenseGetColumnVecRead(X, j, &xcol));
      if (j == 0) PetscCall(VecScatterCreate(xcol, from, gcol, NULL, &sc));
      PetscCall(VecPlaceArray(gcol, xg + j * ng));
      PetscCall(VecScatterBegin(sc, xcol, gcol, INSERT_VALUES, SCATTER_FORWARD));
      PetscCall(VecScatterEnd(sc, xcol, gcol, INSERT_VALUES, SCATTER_FORWARD));
      PetscCall(VecResetArray(gcol));
      PetscCall(MatDenseRestoreColumnVecRead(X, j, &xcol));
    }
    if (ncols) PetscCall(VecScatterDestroy(&sc));
    PetscCall(VecDestroy(&gcol));
    PetscCall(ISDestroy(&from));
    PetscCall(MatDenseGetArrayRead(X, &x));
    PetscCall(KFSeqAIJMultChunked(ext, Ad, ncols, x, ldx, xg, ng, Ao, y, ldy, yb));
    PetscCall(PetscFree(xg));
  }
  PetscCall(MatDenseRestoreArrayRead(X, &x));
  PetscCall(MatDenseRestoreArrayWrite(*Y, &y));
  PetscCall(MatAssemblyBegin(*Y, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*Y, MAT_FINAL_ASSEMBLY));
  if (Yb) {
    PetscCall(MatDenseRestoreArrayWrite(*Yb, &yb));
    PetscCall(MatAssemblyBegin(*Yb, MAT_FINAL_ASSEMBLY));
    PetscCall(MatAssemblyEnd(*Yb, MAT_FINAL_ASSEMBLY));
  }
  PetscFunctionReturn(0);
}

PetscErrorCode KFMatMultExtended(Mat A, Mat X, Mat *Y)
{
  PetscFunctionBegin;
  *Y = NULL;
  PetscCall(KFMatMultChunked(PETSC_TRUE, A, X, Y, NULL));
  PetscFunctionReturn(0);
}

/* Y = A X in double, the bits of MatMatMult(A, X) for AIJ A (other types: MatMatMult itself). The products with the
   mass matrices of the Krylov and body bases (sparse x a block of dense columns) were 1.4 s of the 202k-dof solid's
   reduction; this sweep reads A once per 8 columns and runs them as vectors. */
PetscErrorCode KFMatMultDense(Mat A, Mat X, Mat *Y)
{
  PetscBool aij;

  PetscFunctionBegin;
  PetscCall(PetscObjectTypeCompareAny((PetscObject)A, &aij, MATSEQAIJ, MATMPIAIJ, ""));
  *Y = NULL;
  if (aij) PetscCall(KFMatMultChunked(PETSC_FALSE, A, X, Y, NULL));
  else PetscCall(MatMatMult(A, X, MAT_INITIAL_MATRIX, PETSC_DEFAULT, Y));
  PetscFunctionReturn(0);
}

/* The same into a dense Y the caller made (A's rows, X's columns; e.g. on an array of its own), overwritten */
PetscErrorCode KFMatMultDenseInto(Mat A, Mat X, Mat Y)
{
  PetscBool aij;

  PetscFunctionBegin;
  PetscCall(PetscObjectTypeCompareAny((PetscObject)A, &aij, MATSEQAIJ, MATMPIAIJ, ""));
  if (aij) PetscCall(KFMatMultChunked(PETSC_FALSE, A, X, &Y, NULL));
  else {
    Mat T;

    PetscCall(MatMatMult(A, X, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &T));
    PetscCall(MatCopy(T, Y, SAME_NONZERO_PATTERN));
    PetscCall(MatDestroy(&T));
  }
  PetscFunctionReturn(0);
}

/* Y = A X in double (KFMatMultDense's bits) and Yb, entry by entry, a bound on Y's rounding error (KFBoundKernel), in
   one sweep of AIJ A: what decides whether the double product is accurate enough for its use (the first residual of
   a block solve, src/solve/flex_solver.c) before a double-double one is paid for */
PetscErrorCode KFMatMultBounded(Mat A, Mat X, Mat *Y, Mat *Yb)
{
  PetscFunctionBegin;
  *Y = *Yb = NULL;
  PetscCall(KFMatMultChunked(PETSC_FALSE, A, X, Y, Yb));
  PetscFunctionReturn(0);
}
