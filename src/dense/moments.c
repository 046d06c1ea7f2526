/* Low-frequency moments of a small pencil on its flexible subspace: L^k = H (K+ M)^k K+ G. */
#include "dense_impl.h"

PetscErrorCode KFDenseMoments(PetscInt n, const PetscReal K[], const PetscReal M[], PetscInt a, const PetscReal G[], PetscInt t, const PetscReal H[], PetscReal rigid_tol, PetscInt nmom, PetscReal L[])
{
  PetscReal *lambda, *Phi, *HPhi, *PhiG, lmax;
  PetscInt   f0 = 0, nf;

  PetscFunctionBegin;
  PetscCheck(n >= 0 && a >= 0 && t >= 0 && nmom >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFDenseMoments: negative size (n %" PetscInt_FMT ", a %" PetscInt_FMT ", t %" PetscInt_FMT ", nmom %" PetscInt_FMT ")", n, a, t, nmom);
  PetscCheck(rigid_tol >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFDenseMoments: negative rigid tolerance %g", (double)rigid_tol);
  if (!nmom || !a || !t) PetscFunctionReturn(0);
  PetscCall(PetscArrayzero(L, nmom * t * a));
  if (!n) PetscFunctionReturn(0);
  PetscCall(PetscMalloc4(n, &lambda, n * n, &Phi, t * n, &HPhi, n * a, &PhiG));
  PetscCall(KFDenseEig(n, K, M, lambda, Phi));
  /* K+ = sum over flexible modes of phi phi^T / lambda, and phi^T M phi_j = delta_ij, so
     (K+ M)^k K+ = sum phi phi^T / lambda^(k+1). Eigenvalues ascend: flexible modes are the tail. */
  lmax = lambda[n - 1];
  while (f0 < n && !KFDenseIsFlexible_Private(lambda[f0], lmax, rigid_tol)) f0++;
  nf = n - f0;
  if (nf) {
    PetscCall(KFDenseGemm_Private('N', 'N', t, nf, n, 1.0, H, t, Phi + f0 * n, n, 0.0, HPhi, t));
    PetscCall(KFDenseGemm_Private('T', 'N', nf, a, n, 1.0, Phi + f0 * n, n, G, n, 0.0, PhiG, nf));
    for (PetscInt k = 0; k < nmom; k++) {
      for (PetscInt j = 0; j < a; j++)
        for (PetscInt i = 0; i < nf; i++) PhiG[i + j * nf] /= lambda[f0 + i];
      PetscCall(KFDenseGemm_Private('N', 'N', t, a, nf, 1.0, HPhi, t, PhiG, nf, 0.0, L + k * t * a, t));
    }
  }
  PetscCall(PetscFree4(lambda, Phi, HPhi, PhiG));
  PetscFunctionReturn(0);
}
