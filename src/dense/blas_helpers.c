/* Thin, size-safe wrappers around BLAS for the dense stage. */
#include "dense_impl.h"
#include <petscblaslapack.h> /* after the PETSc headers it relies on */

PetscErrorCode KFDenseGemm_Private(char transa, char transb, PetscInt m, PetscInt n, PetscInt k, PetscReal alpha, const PetscReal A[], PetscInt lda, const PetscReal B[], PetscInt ldb, PetscReal beta, PetscReal C[], PetscInt ldc)
{
  PetscBLASInt bm, bn, bk, blda, bldb, bldc;
  char         ta[2] = {transa, 0}, tb[2] = {transb, 0};

  PetscFunctionBegin;
  if (m <= 0 || n <= 0) PetscFunctionReturn(0);
  PetscCall(PetscBLASIntCast(m, &bm));
  PetscCall(PetscBLASIntCast(n, &bn));
  PetscCall(PetscBLASIntCast(k, &bk));
  PetscCall(PetscBLASIntCast(PetscMax(lda, 1), &blda));
  PetscCall(PetscBLASIntCast(PetscMax(ldb, 1), &bldb));
  PetscCall(PetscBLASIntCast(PetscMax(ldc, 1), &bldc));
  PetscCallBLAS("BLASgemm", BLASgemm_(ta, tb, &bm, &bn, &bk, &alpha, A, &blda, B, &bldb, &beta, C, &bldc));
  PetscFunctionReturn(0);
}

PetscErrorCode KFDenseSymmetrize_Private(PetscInt n, PetscReal A[])
{
  PetscFunctionBegin;
  for (PetscInt j = 0; j < n; j++) {
    for (PetscInt i = j + 1; i < n; i++) {
      PetscReal s = 0.5 * (A[i + j * n] + A[j + i * n]);
      A[i + j * n] = A[j + i * n] = s;
    }
  }
  PetscFunctionReturn(0);
}

PetscErrorCode KFDenseCheckSymmetric_Private(PetscInt n, const PetscReal A[], const char what[], const char caller[])
{
  PetscReal amax = 0, dmax = 0;

  PetscFunctionBegin;
  for (PetscInt j = 0; j < n; j++) {
    for (PetscInt i = 0; i < n; i++) {
      PetscReal x = A[i + j * n];
      PetscCheck(!PetscIsInfOrNanReal(x), PETSC_COMM_SELF, PETSC_ERR_FP, "%s: %s has an Inf or NaN entry at (%" PetscInt_FMT ", %" PetscInt_FMT ")", caller, what, i, j);
      amax = PetscMax(amax, PetscAbsReal(x));
      if (i > j) dmax = PetscMax(dmax, PetscAbsReal(x - A[j + i * n]));
    }
  }
  PetscCheck(dmax <= KF_DENSE_SYMMETRY_RTOL * amax, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG,
             "%s: %s (%" PetscInt_FMT " x %" PetscInt_FMT ") is not symmetric: max |A_ij - A_ji| = %g, max |A_ij| = %g; pass a symmetric column-major array (symmetrize it with (A + A^T)/2 if the asymmetry is rounding)",
             caller, what, n, n, (double)dmax, (double)amax);
  PetscFunctionReturn(0);
}

PetscReal KFDenseMaxReal_Private(PetscInt n, const PetscReal x[])
{
  PetscReal m = PETSC_MIN_REAL;
  for (PetscInt i = 0; i < n; i++) m = PetscMax(m, x[i]);
  return m;
}

PetscBool KFDenseIsFlexible_Private(PetscReal lambda, PetscReal lmax, PetscReal rigid_tol)
{
  return (lambda > 0 && lambda > rigid_tol * lmax) ? PETSC_TRUE : PETSC_FALSE;
}
