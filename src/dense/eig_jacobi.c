/* Eigenvalues of a symmetric positive definite matrix to high relative accuracy: two-sided cyclic Jacobi with the
   relative stopping test |a_ij| <= eps sqrt(a_ii a_jj) (Demmel and Veselic, SIAM J. Matrix Anal. Appl. 13, 1992).
   A Householder eigensolver (LAPACK syev) knows every eigenvalue to eps times the largest only; on a nearly
   diagonal matrix whose diagonal spans many orders (a stiff structure's modal stiffness) Jacobi keeps each small
   eigenvalue to a few eps of itself. */
#include "dense_impl.h"

/* A (m x m, column-major, symmetric, overwritten) = W diag(lambda) W^T; lambda ascending, W's columns with it. Each
   eigenvalue to a few eps of itself when A is positive definite and D^-1/2 A D^-1/2 (D its diagonal) well conditioned */
PetscErrorCode KFDenseEigJacobi_Private(PetscInt m, PetscReal A[], PetscReal lambda[], PetscReal W[])
{
  PetscInt  sweep, rotations = 1;
  PetscReal tol = PETSC_MACHINE_EPSILON;

  PetscFunctionBegin;
  PetscCall(PetscArrayzero(W, m * m));
  for (PetscInt i = 0; i < m; i++) W[i + i * m] = 1;
  for (sweep = 0; sweep < 30 && rotations; sweep++) {
    rotations = 0;
    for (PetscInt p = 0; p < m - 1; p++)
      for (PetscInt q = p + 1; q < m; q++) {
        PetscReal app = A[p + p * m], aqq = A[q + q * m], apq = A[p + q * m], zeta, t, c, s;

        PetscReal gap = PetscAbsReal(aqq - app), low = PetscMin(PetscAbsReal(app), PetscAbsReal(aqq));

        /* negligible relative to both (|a_ii|: an indefinite matrix, a mechanism the rigid modes missed, converges
           too, without the relative accuracy), or against their gap: the rotation below 1e-12 rad and the softer
           eigenvalue moved by less than eps of itself (a_pq^2 / gap). The computed entries of a nearly diagonal
           matrix are rounding of that size; rotating them all costs a second per sweep at 600 dofs */
        if (PetscAbsReal(apq) <= tol * PetscSqrtReal(PetscAbsReal(app * aqq))) continue;
        if (PetscAbsReal(apq) <= 1e-12 * gap && apq * apq <= tol * gap * low) continue;
        rotations++;
        /* the rotation that zeroes a_pq (Rutishauser's formulas: t the smaller root of t^2 + 2 zeta t - 1) */
        zeta = (aqq - app) / (2 * apq);
        t    = (zeta >= 0 ? 1 : -1) / (PetscAbsReal(zeta) + PetscSqrtReal(1 + zeta * zeta));
        c    = 1 / PetscSqrtReal(1 + t * t);
        s    = c * t;
        for (PetscInt k = 0; k < m; k++) { /* columns p, q */
          PetscReal akp = A[k + p * m], akq = A[k + q * m];
          A[k + p * m] = c * akp - s * akq;
          A[k + q * m] = s * akp + c * akq;
        }
        for (PetscInt k = 0; k < m; k++) { /* rows p, q */
          PetscReal apk = A[p + k * m], aqk = A[q + k * m];
          A[p + k * m] = c * apk - s * aqk;
          A[q + k * m] = s * apk + c * aqk;
        }
        A[p + p * m] = app - t * apq; /* the exact updates of the pivot block */
        A[q + q * m] = aqq + t * apq;
        A[p + q * m] = A[q + p * m] = 0;
        for (PetscInt k = 0; k < m; k++) {
          PetscReal wkp = W[k + p * m], wkq = W[k + q * m];
          W[k + p * m] = c * wkp - s * wkq;
          W[k + q * m] = s * wkp + c * wkq;
        }
      }
  }
  PetscCheck(!rotations, PETSC_COMM_SELF, PETSC_ERR_CONV_FAILED, "KFDenseEigJacobi: %" PetscInt_FMT " rotations still needed after %" PetscInt_FMT " sweeps on the %" PetscInt_FMT " x %" PetscInt_FMT " matrix", rotations, sweep, m, m);
  for (PetscInt i = 0; i < m; i++) lambda[i] = A[i + i * m];
  for (PetscInt i = 1; i < m; i++) { /* ascending (insertion: the order is nearly right already) */
    for (PetscInt j = i; j > 0 && lambda[j - 1] > lambda[j]; j--) {
      PetscReal l = lambda[j];
      lambda[j]     = lambda[j - 1];
      lambda[j - 1] = l;
      for (PetscInt k = 0; k < m; k++) {
        PetscReal w      = W[k + j * m];
        W[k + j * m]       = W[k + (j - 1) * m];
        W[k + (j - 1) * m] = w;
      }
    }
  }
  PetscFunctionReturn(0);
}
