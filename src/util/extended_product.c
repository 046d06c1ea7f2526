#include <kryflex_impl.h>
#include <petsc/private/matimpl.h>

/* Y = A X for sparse A (AIJ) and tall dense X, each row accumulated in long double (64-bit mantissa) and rounded once.
   For a soft vector x of a stiff structure, K x is a small difference of large terms: in double its rounding is
   eps |K| |x|, far above |K x|; accumulated in long double it is eps |K x|. The residuals of iterative refinement and
   the reduced stiffness matrices need that. */
static PetscErrorCode KFSeqAIJMultExtended(Mat A, PetscInt ncols, const PetscScalar *x, PetscInt ldx, const PetscScalar *xg, PetscInt ldg, Mat B, PetscScalar *y, PetscInt ldy)
{
  const PetscInt    *ia, *ja, *ib = NULL, *jb = NULL;
  const PetscScalar *a, *b = NULL;
  PetscInt           m, mb;
  PetscBool          done;

  PetscFunctionBegin;
  PetscCall(MatGetRowIJ(A, 0, PETSC_FALSE, PETSC_FALSE, &m, &ia, &ja, &done));
  PetscCheck(done, PETSC_COMM_SELF, PETSC_ERR_SUP, "cannot get the rows of the matrix");
  PetscCall(MatSeqAIJGetArrayRead(A, &a));
  if (B) {
    PetscCall(MatGetRowIJ(B, 0, PETSC_FALSE, PETSC_FALSE, &mb, &ib, &jb, &done));
    PetscCheck(done && mb == m, PETSC_COMM_SELF, PETSC_ERR_SUP, "cannot get the rows of the off-process block");
    PetscCall(MatSeqAIJGetArrayRead(B, &b));
  }
  /* four columns per sweep over the rows: the matrix is read once per four columns instead of once per column, and
     the four sums are independent chains the FPU overlaps (one long double sum's latency bounded the loop); each sum
     still runs over the row in the same order, so the result is the same to the bit */
  for (PetscInt j0 = 0; j0 < ncols; j0 += 4) {
    const PetscInt     nj = PetscMin(4, ncols - j0);
    const PetscScalar *x0 = x + j0 * ldx, *x1 = x0 + (nj > 1 ? ldx : 0), *x2 = x0 + (nj > 2 ? 2 * ldx : 0), *x3 = x0 + (nj > 3 ? 3 * ldx : 0);
    const PetscScalar *g0 = NULL, *g1 = NULL, *g2 = NULL, *g3 = NULL;

    if (B) {
      g0 = xg + j0 * ldg;
      g1 = g0 + (nj > 1 ? ldg : 0);
      g2 = g0 + (nj > 2 ? 2 * ldg : 0);
      g3 = g0 + (nj > 3 ? 3 * ldg : 0);
    }
    for (PetscInt i = 0; i < m; i++) {
      long double s0 = 0, s1 = 0, s2 = 0, s3 = 0; /* columns past nj repeat the last one: computed, not stored */
      for (PetscInt k = ia[i]; k < ia[i + 1]; k++) {
        const long double av = (long double)a[k];
        const PetscInt    c  = ja[k];
        s0 += av * (long double)x0[c];
        s1 += av * (long double)x1[c];
        s2 += av * (long double)x2[c];
        s3 += av * (long double)x3[c];
      }
      if (B)
        for (PetscInt k = ib[i]; k < ib[i + 1]; k++) {
          const long double bv = (long double)b[k];
          const PetscInt    c  = jb[k];
          s0 += bv * (long double)g0[c];
          s1 += bv * (long double)g1[c];
          s2 += bv * (long double)g2[c];
          s3 += bv * (long double)g3[c];
        }
      y[i + j0 * ldy] = (PetscScalar)s0;
      if (nj > 1) y[i + (j0 + 1) * ldy] = (PetscScalar)s1;
      if (nj > 2) y[i + (j0 + 2) * ldy] = (PetscScalar)s2;
      if (nj > 3) y[i + (j0 + 3) * ldy] = (PetscScalar)s3;
    }
  }
  PetscCall(MatSeqAIJRestoreArrayRead(A, &a));
  PetscCall(MatRestoreRowIJ(A, 0, PETSC_FALSE, PETSC_FALSE, &m, &ia, &ja, &done));
  if (B) {
    PetscCall(MatSeqAIJRestoreArrayRead(B, &b));
    PetscCall(MatRestoreRowIJ(B, 0, PETSC_FALSE, PETSC_FALSE, &mb, &ib, &jb, &done));
  }
  PetscFunctionReturn(0);
}

PetscErrorCode KFMatMultExtended(Mat A, Mat X, Mat *Y)
{
  PetscBool          mpi;
  PetscInt           nl, N, ncols, ldx, ldy;
  const PetscScalar *x;
  PetscScalar       *y;
  MPI_Comm           comm;

  PetscFunctionBegin;
  PetscCall(PetscObjectGetComm((PetscObject)A, &comm));
  PetscCall(MatGetLocalSize(A, &nl, NULL));
  PetscCall(MatGetSize(A, &N, NULL));
  PetscCall(MatGetSize(X, NULL, &ncols));
  PetscCall(KFDenseCreate(comm, nl, N, ncols, Y));
  PetscCall(PetscObjectTypeCompare((PetscObject)A, MATMPIAIJ, &mpi));
  PetscCall(MatDenseGetLDA(X, &ldx));
  PetscCall(MatDenseGetLDA(*Y, &ldy));
  PetscCall(MatDenseGetArrayRead(X, &x));
  PetscCall(MatDenseGetArrayWrite(*Y, &y));
  if (!mpi) PetscCall(KFSeqAIJMultExtended(A, ncols, x, ldx, NULL, 0, NULL, y, ldy));
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
    PetscCall(KFSeqAIJMultExtended(Ad, ncols, x, ldx, xg, ng, Ao, y, ldy));
    PetscCall(PetscFree(xg));
  }
  PetscCall(MatDenseRestoreArrayRead(X, &x));
  PetscCall(MatDenseRestoreArrayWrite(*Y, &y));
  PetscCall(MatAssemblyBegin(*Y, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*Y, MAT_FINAL_ASSEMBLY));
  PetscFunctionReturn(0);
}
