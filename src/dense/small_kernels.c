/* Plain-loop kernels on small dense arrays shared by several stages: the sizes are a body's or a block's reduced
   coordinates, where a BLAS call costs more than it saves and the summation order is part of the result. */
#include "dense_impl.h"

PetscErrorCode KFDenseOrthonormalizeSmall_Private(PetscInt m, PetscInt p, PetscReal X[], const PetscReal nrm0[], PetscReal tol, PetscInt *kept)
{
  PetscInt n = 0;

  PetscFunctionBegin;
  for (PetscInt j = 0; j < p; j++) {
    PetscReal *x = X + j * m, *y = X + n * m, n0 = 0, nrm = 0;

    if (nrm0) n0 = nrm0[j];
    else {
      for (PetscInt i = 0; i < m; i++) n0 += x[i] * x[i];
      n0 = PetscSqrtReal(n0);
    }
    if (!(n0 > 0)) continue; /* a zero column: nothing to keep, and no norm to measure its remainder against */
    for (int pass = 0; pass < 2; pass++)
      for (PetscInt l = 0; l < n; l++) {
        PetscReal d = 0;
        for (PetscInt i = 0; i < m; i++) d += X[i + l * m] * x[i];
        for (PetscInt i = 0; i < m; i++) x[i] -= d * X[i + l * m];
      }
    for (PetscInt i = 0; i < m; i++) nrm += x[i] * x[i];
    nrm = PetscSqrtReal(nrm);
    if (!(nrm > tol * n0)) continue;
    for (PetscInt i = 0; i < m; i++) y[i] = x[i] / nrm;
    n++;
  }
  *kept = n;
  PetscFunctionReturn(0);
}

void KFDenseCongruenceL_Private(PetscInt v, PetscInt l, const PetscReal S[], const PetscReal A[], PetscInt lda, const PetscReal B[], PetscInt ldb, long double X[], long double T[])
{
  for (PetscInt j = 0; j < l; j++)
    for (PetscInt i = 0; i < v; i++) {
      long double sum = 0;
      for (PetscInt k = 0; k < v; k++) sum += (long double)S[i + k * v] * B[k + j * ldb];
      X[i + j * v] = sum;
    }
  for (PetscInt j = 0; j < l; j++)
    for (PetscInt i = 0; i < l; i++) {
      long double sum = 0;
      for (PetscInt k = 0; k < v; k++) sum += (long double)A[k + i * lda] * X[k + j * v];
      T[i + j * l] = sum;
    }
}
