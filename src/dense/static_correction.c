/* Static correction of eq. (17): the static gain of the discarded modes, S = Phid Lambdad^-1 Phid^T G. */
#include "dense_impl.h"

PetscErrorCode KFDenseStaticCorrection(PetscInt n, PetscInt d, const PetscReal Phid[], const PetscReal lambdad[], PetscInt a, const PetscReal G[], PetscReal S[])
{
  PetscReal *T;

  PetscFunctionBegin;
  PetscCheck(n >= 0 && d >= 0 && a >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFDenseStaticCorrection: negative size (n %" PetscInt_FMT ", d %" PetscInt_FMT ", a %" PetscInt_FMT ")", n, d, a);
  if (!n || !a) PetscFunctionReturn(0);
  if (!d) {
    PetscCall(PetscArrayzero(S, n * a));
    PetscFunctionReturn(0);
  }
  for (PetscInt i = 0; i < d; i++)
    PetscCheck(lambdad[i] > 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
               "KFDenseStaticCorrection: discarded mode %" PetscInt_FMT " has eigenvalue %g <= 0: a rigid-body or mechanism mode has no static gain to correct; keep it among the retained modes", i, (double)lambdad[i]);
  PetscCall(PetscMalloc1(d * a, &T));
  PetscCall(KFDenseGemm_Private('T', 'N', d, a, n, 1.0, Phid, n, G, n, 0.0, T, d));
  for (PetscInt j = 0; j < a; j++)
    for (PetscInt i = 0; i < d; i++) T[i + j * d] /= lambdad[i];
  PetscCall(KFDenseGemm_Private('N', 'N', n, a, d, 1.0, Phid, n, T, d, 0.0, S, n));
  PetscCall(PetscFree(T));
  PetscFunctionReturn(0);
}
