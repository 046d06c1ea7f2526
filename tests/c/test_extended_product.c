/* KFMatMultExtended (src/util/extended_product.c, internal: the test compiles that file in, with its own
   -ffp-contract=off, see CMakeLists.txt): A X for a stiff sparse A and soft X must be the exact product rounded once,
   where the plain double product loses most digits to cancellation; the vectorized kernels and the generic one must
   give the same bits. KFMatMultBounded: the plain product's bits, each entry within its rounding bound. Reference: each row's sum in __float128 (quadruple precision), computed here independently. */
#include "kftest.h"
#include "../../src/util/extended_product.c"

/* what the library's KFDenseCreate does (it is internal to libkryflex) */
PetscErrorCode KFDenseCreate(MPI_Comm comm, PetscInt nlocal, PetscInt N, PetscInt ncols, Mat *A)
{
  PetscFunctionBegin;
  PetscCall(MatCreateDense(comm, nlocal, PETSC_DECIDE, N, ncols, NULL, A));
  PetscCall(MatAssemblyBegin(*A, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*A, MAT_FINAL_ASSEMBLY));
  PetscFunctionReturn(0);
}

/* the library's creates it without a zero fill (the product writes every entry); here it is filled with NaN, so an
   entry the product missed shows in the comparisons below */
PetscErrorCode KFDenseCreateUninitialized(MPI_Comm comm, PetscInt nlocal, PetscInt N, PetscInt ncols, Mat *A)
{
  PetscScalar *a;
  PetscInt     lda;

  PetscFunctionBegin;
  PetscCall(KFDenseCreate(comm, nlocal, N, ncols, A));
  PetscCall(MatDenseGetLDA(*A, &lda));
  PetscCall(MatDenseGetArrayWrite(*A, &a));
  for (PetscInt i = 0; i < lda * ncols; i++) a[i] = NAN;
  PetscCall(MatDenseRestoreArrayWrite(*A, &a));
  PetscFunctionReturn(0);
}

#if defined(__SIZEOF_FLOAT128__)
typedef __float128 quad;
#else
typedef long double quad;
#endif

int main(int argc, char **argv)
{
  const PetscInt n = 3000, ncols = 11, w = 40; /* 11 columns: one full chunk of 8 and a partial one */
  Mat            A, X, Y, Yd;
  PetscInt       rstart, rend;
  PetscReal     *xall, errx = 0, errd = 0, cancel = 0;
  quad          *qref; /* each entry of A X in quadruple precision (this rank's rows) */
  PetscRandom    rnd;

  PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "extended-precision sparse x dense product\n"));
  /* A: a stiff banded Laplacian-like matrix (springs of stiffness 1e6 .. 1e10 between dofs up to w apart), rows
     summing to zero, so A times a constant vanishes and A times a smooth vector is a small difference of large terms */
  PetscCall(MatCreateAIJ(PETSC_COMM_WORLD, PETSC_DECIDE, PETSC_DECIDE, n, n, 2 * w + 1, NULL, 2 * w + 1, NULL, &A));
  PetscCall(MatGetOwnershipRange(A, &rstart, &rend));
  for (PetscInt i = rstart; i < rend; i++) {
    PetscReal diag = 0;
    for (PetscInt d = 1; d <= w; d++)
      for (int sgn = -1; sgn <= 1; sgn += 2) {
        const PetscInt j = i + sgn * d;
        if (j < 0 || j >= n) continue;
        {
          const PetscInt  lo = PetscMin(i, j), hi = PetscMax(i, j);
          const PetscReal k  = PetscPowReal(10.0, 6 + 4 * PetscSinReal(0.37 * lo + 1.3 * hi) * PetscSinReal(0.37 * lo + 1.3 * hi)) * (1 + 0.1 * d); /* symmetric in (i, j) */
          PetscCall(MatSetValue(A, i, j, -k, INSERT_VALUES));
          diag += k;
        }
      }
    PetscCall(MatSetValue(A, i, i, diag, INSERT_VALUES));
  }
  PetscCall(MatAssemblyBegin(A, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(A, MAT_FINAL_ASSEMBLY));
  /* X: soft columns, a constant plus small smooth and random parts of varied size (the same on every rank count) */
  PetscCall(PetscMalloc1(n * ncols, &xall));
  PetscCall(PetscRandomCreate(PETSC_COMM_SELF, &rnd));
  PetscCall(PetscRandomSetInterval(rnd, -1, 1));
  PetscCall(PetscRandomSetSeed(rnd, 7));
  PetscCall(PetscRandomSeed(rnd));
  for (PetscInt j = 0; j < ncols; j++)
    for (PetscInt i = 0; i < n; i++) {
      PetscReal r;
      PetscCall(PetscRandomGetValueReal(rnd, &r));
      xall[i + j * n] = 1 + j + PetscPowReal(10.0, -3 - (PetscReal)j / 2) * PetscSinReal((j + 1) * 3.0 * i / n) + PetscPowReal(10.0, -9 - (PetscReal)(j % 4)) * r;
    }
  PetscCall(PetscRandomDestroy(&rnd));
  PetscCall(MatCreateDense(PETSC_COMM_WORLD, rend - rstart, PETSC_DECIDE, n, ncols, NULL, &X));
  {
    PetscScalar *x;
    PetscInt     ld;
    PetscCall(MatDenseGetLDA(X, &ld));
    PetscCall(MatDenseGetArrayWrite(X, &x));
    for (PetscInt j = 0; j < ncols; j++)
      for (PetscInt i = rstart; i < rend; i++) x[(i - rstart) + j * ld] = xall[i + j * n];
    PetscCall(MatDenseRestoreArrayWrite(X, &x));
    PetscCall(MatAssemblyBegin(X, MAT_FINAL_ASSEMBLY));
    PetscCall(MatAssemblyEnd(X, MAT_FINAL_ASSEMBLY));
  }
  PetscCall(KFMatMultExtended(A, X, &Y));
  PetscCall(MatMatMult(A, X, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &Yd));
  PetscCall(PetscMalloc1((rend - rstart) * ncols + 1, &qref));
  { /* per entry: |y - y_quad| / |y_quad| for the extended and the plain product, and the cancellation |A||x| / |Ax| */
    const PetscScalar *y, *yd;
    PetscInt           ldy, ldd;
    PetscCall(MatDenseGetLDA(Y, &ldy));
    PetscCall(MatDenseGetLDA(Yd, &ldd));
    PetscCall(MatDenseGetArrayRead(Y, &y));
    PetscCall(MatDenseGetArrayRead(Yd, &yd));
    for (PetscInt i = rstart; i < rend; i++) {
      PetscInt           nz;
      const PetscInt    *cols;
      const PetscScalar *vals;
      PetscCall(MatGetRow(A, i, &nz, &cols, &vals));
      for (PetscInt j = 0; j < ncols; j++) {
        quad      s = 0;
        PetscReal sabs = 0, yq;
        for (PetscInt k = 0; k < nz; k++) {
          s += (quad)vals[k] * (quad)xall[cols[k] + j * n];
          sabs += PetscAbsReal(vals[k] * xall[cols[k] + j * n]);
        }
        qref[(i - rstart) + j * (rend - rstart)] = s; /* the reference of the bounded product below */
        yq = (PetscReal)s;
        if (yq == 0) continue;
        errx   = PetscMax(errx, PetscAbsReal(y[(i - rstart) + j * ldy] - yq) / PetscAbsReal(yq));
        errd   = PetscMax(errd, PetscAbsReal(yd[(i - rstart) + j * ldd] - yq) / PetscAbsReal(yq));
        cancel = PetscMax(cancel, sabs / PetscAbsReal(yq));
      }
      PetscCall(MatRestoreRow(A, i, &nz, &cols, &vals));
    }
    PetscCall(MatDenseRestoreArrayRead(Y, &y));
    PetscCall(MatDenseRestoreArrayRead(Yd, &yd));
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &errx, 1, MPIU_REAL, MPIU_MAX, PETSC_COMM_WORLD));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &errd, 1, MPIU_REAL, MPIU_MAX, PETSC_COMM_WORLD));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &cancel, 1, MPIU_REAL, MPIU_MAX, PETSC_COMM_WORLD));
  { /* KFMatMultDense: the plain product's own bits (the same sums in the same order as MatMatMult) */
    Mat                Yp;
    const PetscScalar *yp, *yd;
    PetscInt           ldp, ldd, nl;
    PetscBool          same = PETSC_TRUE;
    PetscCall(KFMatMultDense(A, X, &Yp));
    PetscCall(MatGetLocalSize(Yp, &nl, NULL));
    PetscCall(MatDenseGetLDA(Yp, &ldp));
    PetscCall(MatDenseGetLDA(Yd, &ldd));
    PetscCall(MatDenseGetArrayRead(Yp, &yp));
    PetscCall(MatDenseGetArrayRead(Yd, &yd));
    for (PetscInt j = 0; j < ncols; j++)
      for (PetscInt i = 0; i < nl; i++) same = (PetscBool)(same && yp[i + j * ldp] == yd[i + j * ldd]);
    PetscCall(MatDenseRestoreArrayRead(Yp, &yp));
    PetscCall(MatDenseRestoreArrayRead(Yd, &yd));
    PetscCall(MatDestroy(&Yp));
    PetscCall(CheckTrue("KFMatMultDense gives MatMatMult's bits (11 columns: chunks of 8 and 4)", same));
  }
  for (int w = 0; w < 2; w++) { /* KFMatMultBounded on 11 columns (chunks of 8 and 4), then on 2 */
    const PetscInt     nb = w ? 2 : ncols;
    Mat                Xb, Yp, Yb;
    const PetscScalar *yp, *yb, *yd;
    PetscInt           ldp, ldd;
    PetscBool          same = PETSC_TRUE, holds = PETSC_TRUE;
    PetscReal          tight = 0; /* the largest actual error over its bound: how much of the bound is used */

    PetscCall(MatDenseGetSubMatrix(X, PETSC_DECIDE, PETSC_DECIDE, 0, nb, &Xb));
    PetscCall(KFMatMultBounded(A, Xb, &Yp, &Yb));
    PetscCall(MatDenseRestoreSubMatrix(X, &Xb));
    PetscCall(MatDenseGetLDA(Yp, &ldp));
    PetscCall(MatDenseGetLDA(Yd, &ldd));
    PetscCall(MatDenseGetArrayRead(Yp, &yp));
    PetscCall(MatDenseGetArrayRead(Yb, &yb));
    PetscCall(MatDenseGetArrayRead(Yd, &yd));
    for (PetscInt i = rstart; i < rend; i++)
      for (PetscInt j = 0; j < nb; j++) {
        const PetscInt e = (i - rstart) + j * ldp;
        const quad     q = qref[(i - rstart) + j * (rend - rstart)];

        same  = (PetscBool)(same && yp[e] == yd[(i - rstart) + j * ldd]);
        holds = (PetscBool)(holds && (PetscReal)PetscAbsReal((PetscReal)((quad)yp[e] - q)) <= yb[e]);
        if (yb[e] > 0) tight = PetscMax(tight, (PetscReal)PetscAbsReal((PetscReal)((quad)yp[e] - q)) / yb[e]);
      }
    PetscCall(MatDenseRestoreArrayRead(Yp, &yp));
    PetscCall(MatDenseRestoreArrayRead(Yb, &yb));
    PetscCall(MatDenseRestoreArrayRead(Yd, &yd));
    PetscCall(MatDestroy(&Yp));
    PetscCall(MatDestroy(&Yb));
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &same, 1, MPIU_BOOL, MPI_LAND, PETSC_COMM_WORLD));
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &holds, 1, MPIU_BOOL, MPI_LAND, PETSC_COMM_WORLD));
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &tight, 1, MPIU_REAL, MPIU_MAX, PETSC_COMM_WORLD));
    PetscCall(PetscPrintf(PETSC_COMM_WORLD, "  %" PetscInt_FMT " columns: the plain product's error uses at most %.2g of its bound\n", nb, (double)tight));
    PetscCall(CheckTrue("KFMatMultBounded: the plain product's bits (MatMatMult's)", same));
    PetscCall(CheckTrue("KFMatMultBounded: every entry within its bound of the quadruple-precision sum", holds));
  }
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "  cancellation |A||x| / |Ax| up to %.1e\n", (double)cancel));
  PetscCall(CheckTrue("the data cancel (|A||x| / |Ax| > 1e8): a test the plain product fails", (PetscBool)(cancel > 1e8)));
  PetscCall(CheckTrue("the plain double product is off by more than 1e-6 relative here", (PetscBool)(errd > 1e-6)));
  PetscCall(Check("extended product vs quadruple precision, max relative error (one rounding)", errx, 2.3e-16));
#if defined(KF_EXT_DISPATCH)
  { /* every kernel the CPU can run gives the bits of the generic one (one row block, the first chunk) */
    Mat                Ad = A, Ao = NULL;
    const PetscInt    *ia, *ja, *ib = NULL, *jb = NULL, *colmap;
    const PetscScalar *a, *b = NULL, *x;
    PetscScalar       *xt, *xgt, *y0, *y1;
    PetscInt           m, nc, ng = 0, ldx, same = 1;
    PetscBool          done, mpi;
    PetscCall(PetscObjectTypeCompare((PetscObject)A, MATMPIAIJ, &mpi));
    if (mpi) PetscCall(MatMPIAIJGetSeqAIJ(A, &Ad, &Ao, &colmap));
    PetscCall(MatGetSize(Ad, NULL, &nc));
    if (Ao) PetscCall(MatGetSize(Ao, NULL, &ng));
    PetscCall(MatGetRowIJ(Ad, 0, PETSC_FALSE, PETSC_FALSE, &m, &ia, &ja, &done));
    PetscCall(MatSeqAIJGetArrayRead(Ad, &a));
    if (Ao) {
      PetscCall(MatGetRowIJ(Ao, 0, PETSC_FALSE, PETSC_FALSE, &m, &ib, &jb, &done));
      PetscCall(MatSeqAIJGetArrayRead(Ao, &b));
    }
    PetscCall(PetscMalloc4(nc * 8 + 1, &xt, ng * 8 + 1, &xgt, m * 8 + 1, &y0, m * 8 + 1, &y1));
    PetscCall(MatDenseGetLDA(X, &ldx));
    PetscCall(MatDenseGetArrayRead(X, &x));
    KFExtTransposeChunk(nc, x, ldx, 0, 8, 8, xt);
    for (PetscInt r = 0; r < ng; r++)
      for (PetscInt j = 0; j < 8; j++) xgt[r * 8 + j] = xall[colmap[r] + j * n];
    PetscCall(MatDenseRestoreArrayRead(X, &x));
    KFKernelsGeneric[1][0](m, ia, ja, a, xt, ib, jb, b, xgt, 8, y0, m);
    __builtin_cpu_init();
    if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) {
      KFKernelsAVX2[1][0](m, ia, ja, a, xt, ib, jb, b, xgt, 8, y1, m);
      for (PetscInt e = 0; e < m * 8; e++) same &= y0[e] == y1[e];
    }
    if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("fma")) {
      KFKernelsAVX512[1][0](m, ia, ja, a, xt, ib, jb, b, xgt, 8, y1, m);
      for (PetscInt e = 0; e < m * 8; e++) same &= y0[e] == y1[e];
    }
    for (int slot = 1, W = 4; slot < 4; slot++, W /= 2) { /* the narrower chunks: each column's sums as in the chunk of 8 */
      PetscCall(MatDenseGetArrayRead(X, &x));
      KFExtTransposeChunk(nc, x, ldx, 0, W, W, xt);
      PetscCall(MatDenseRestoreArrayRead(X, &x));
      for (PetscInt r = 0; r < ng; r++)
        for (PetscInt j = 0; j < W; j++) xgt[r * W + j] = xall[colmap[r] + j * n];
      KFKernelsGeneric[1][slot](m, ia, ja, a, xt, ib, jb, b, xgt, W, y1, m);
      for (PetscInt e = 0; e < m * W; e++) same &= y0[e] == y1[e];
    }
    PetscCall(PetscFree4(xt, xgt, y0, y1));
    PetscCall(MatSeqAIJRestoreArrayRead(Ad, &a));
    PetscCall(MatRestoreRowIJ(Ad, 0, PETSC_FALSE, PETSC_FALSE, &m, &ia, &ja, &done));
    if (Ao) {
      PetscCall(MatSeqAIJRestoreArrayRead(Ao, &b));
      PetscCall(MatRestoreRowIJ(Ao, 0, PETSC_FALSE, PETSC_FALSE, &m, &ib, &jb, &done));
    }
    PetscCall(CheckTrue("AVX-512 / AVX2 kernels and chunks of 4, 2, 1 columns give the generic 8-column bits", (PetscBool)same));
  }
#endif
  PetscCall(MatDestroy(&A));
  PetscCall(MatDestroy(&X));
  PetscCall(MatDestroy(&Y));
  PetscCall(MatDestroy(&Yd));
  PetscCall(PetscFree(xall));
  PetscCall(PetscFree(qref));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "%s\n", nfail ? "FAILED" : "all checks passed"));
  PetscCall(PetscFinalize());
  return nfail ? 1 : 0;
}
