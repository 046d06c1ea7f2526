/* Eigenvalues of a symmetric positive definite matrix to high relative accuracy, the LAPACK way of Demmel and Veselic
   (SIAM J. Matrix Anal. Appl. 13, 1992): Cholesky A = L L^T, then the one-sided Jacobi SVD of G = L^T (dgesvj),
   A = G^T G = V diag(sigma^2) V^T. G's columns have the norms sqrt(a_ii), so G = B D^1/2 with B^T B = D^-1/2 A D^-1/2,
   and one-sided Jacobi keeps each singular value to eps kappa(B) of itself. A Householder eigensolver (LAPACK syev)
   knows every eigenvalue to eps times the largest only; on a nearly diagonal matrix whose diagonal spans many orders
   (a stiff structure's modal stiffness) this keeps each small eigenvalue to a few eps of itself. */
#include "dense_impl.h"
#include <petscblaslapack.h> /* after the PETSc headers it relies on */

/* one-sided Jacobi SVD; not among PETSc's LAPACK declarations (Fortran's hidden string lengths omitted, as PETSc's) */
#if defined(PETSC_BLASLAPACK_UNDERSCORE)
  #define KFLAPACKgesvj_ dgesvj_
#else
  #define KFLAPACKgesvj_ dgesvj
#endif
extern void KFLAPACKgesvj_(const char *, const char *, const char *, const PetscBLASInt *, const PetscBLASInt *, PetscReal *, const PetscBLASInt *, PetscReal *, const PetscBLASInt *, PetscReal *, const PetscBLASInt *, PetscReal *, const PetscBLASInt *, PetscBLASInt *);

/* A (m x m, column-major, symmetric, overwritten) = W diag(lambda) W^T; lambda ascending, W's columns with it. Each
   eigenvalue to a few eps of itself when A is positive definite and D^-1/2 A D^-1/2 (D its diagonal) well
   conditioned. An A that is not positive definite (a mechanism the rigid modes missed) is solved by syev, without
   the relative accuracy. */
PetscErrorCode KFDenseEigJacobi_Private(PetscInt m, PetscReal A[], PetscReal lambda[], PetscReal W[])
{
  PetscBLASInt bm, lwork, info;
  PetscReal   *work, *sva, scale;

  PetscFunctionBegin;
  if (m <= 0) PetscFunctionReturn(0);
  PetscCall(PetscBLASIntCast(m, &bm));
  PetscCall(PetscArraycpy(W, A, m * m)); /* for syev, should A not be positive definite */
  lwork = PetscMax(6, 2 * bm);
  lwork = PetscMax(lwork, 34 * bm); /* syev's, blocked */
  PetscCall(PetscMalloc2(lwork, &work, m, &sva));
  PetscCallBLAS("LAPACKpotrf", LAPACKpotrf_("L", &bm, A, &bm, &info));
  if (info) {
    PetscCallBLAS("LAPACKsyev", LAPACKsyev_("V", "L", &bm, W, &bm, lambda, work, &lwork, &info));
    PetscCheck(!info, PETSC_COMM_SELF, PETSC_ERR_CONV_FAILED, "KFDenseEigJacobi: the symmetric eigensolver did not converge on the %" PetscInt_FMT " x %" PetscInt_FMT " matrix, which is not positive definite (LAPACK syev info %d)", m, m, (int)info);
    PetscCall(PetscFree2(work, sva));
    PetscFunctionReturn(0);
  }
  for (PetscInt j = 0; j < m; j++) /* G = L^T, upper triangular */
    for (PetscInt i = j + 1; i < m; i++) {
      A[j + i * m] = A[i + j * m];
      A[i + j * m] = 0;
    }
  PetscCallBLAS("LAPACKgesvj", KFLAPACKgesvj_("U", "N", "V", &bm, &bm, A, &bm, sva, &bm, W, &bm, work, &lwork, &info));
  PetscCheck(!info, PETSC_COMM_SELF, PETSC_ERR_CONV_FAILED, "KFDenseEigJacobi: the one-sided Jacobi SVD did not converge on the %" PetscInt_FMT " x %" PetscInt_FMT " Cholesky factor (LAPACK gesvj info %d)", m, m, (int)info);
  scale = work[0]; /* the singular values are scale sva, descending */
  for (PetscInt i = 0; i < m; i++) {
    PetscReal s = scale * sva[m - 1 - i];
    lambda[i] = s * s;
  }
  for (PetscInt j = 0; j < m / 2; j++) /* ascending: W's columns reversed with them */
    for (PetscInt k = 0; k < m; k++) {
      PetscReal w = W[k + j * m];
      W[k + j * m]           = W[k + (m - 1 - j) * m];
      W[k + (m - 1 - j) * m] = w;
    }
  PetscCall(PetscFree2(work, sva));
  PetscFunctionReturn(0);
}
