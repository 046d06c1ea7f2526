/* Mode importance (paper eq. 12-13): how much each mode contributes to the input-to-output map. */
#include "dense_impl.h"

PetscErrorCode KFDenseModeImportance(PetscInt n, const PetscReal lambda[], const PetscReal Phi[], PetscInt a, const PetscReal G[], PetscInt t, const PetscReal H[], PetscReal zeta, KFImportance kind, PetscReal rigid_tol, PetscReal importance[])
{
  PetscReal *HPhi, *PhiG, lmax, imax = 0;

  PetscFunctionBegin;
  PetscCheck(n >= 0 && a >= 0 && t >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFDenseModeImportance: negative size (n %" PetscInt_FMT ", a %" PetscInt_FMT ", t %" PetscInt_FMT ")", n, a, t);
  PetscCheck(kind == KF_IMPORTANCE_H2 || kind == KF_IMPORTANCE_HINF || kind == KF_IMPORTANCE_STATIC, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFDenseModeImportance: unknown importance measure %d: use KF_IMPORTANCE_H2, _HINF or _STATIC", (int)kind);
  PetscCheck(kind == KF_IMPORTANCE_STATIC || zeta > 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFDenseModeImportance: the %s measure needs a positive damping ratio, got %g: set the scene's damping, or rank by the static measure",
             kind == KF_IMPORTANCE_H2 ? "H2" : "Hinf", (double)zeta);
  PetscCheck(rigid_tol >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFDenseModeImportance: negative rigid tolerance %g", (double)rigid_tol);
  if (!n) PetscFunctionReturn(0);
  PetscCall(PetscMalloc2(t * n, &HPhi, n * a, &PhiG));
  PetscCall(KFDenseGemm_Private('N', 'N', t, n, n, 1.0, H, t, Phi, n, 0.0, HPhi, t));
  PetscCall(KFDenseGemm_Private('T', 'N', n, a, n, 1.0, Phi, n, G, n, 0.0, PhiG, n));
  lmax = KFDenseMaxReal_Private(n, lambda);
  for (PetscInt i = 0; i < n; i++) {
    PetscReal hn = 0, gn = 0, w;

    importance[i] = 0;
    if (!KFDenseIsFlexible_Private(lambda[i], lmax, rigid_tol)) continue;
    for (PetscInt r = 0; r < t; r++) hn += HPhi[r + i * t] * HPhi[r + i * t];
    for (PetscInt j = 0; j < a; j++) gn += PhiG[i + j * n] * PhiG[i + j * n];
    /* H phi phi^T G has rank one: its Frobenius norm is the product of the two 2-norms */
    hn = PetscSqrtReal(hn) * PetscSqrtReal(gn);
    w  = PetscSqrtReal(lambda[i]);
    switch (kind) {
    case KF_IMPORTANCE_H2:
      importance[i] = hn / (2 * PetscSqrtReal(zeta * w * w * w));
      break;
    case KF_IMPORTANCE_HINF:
      importance[i] = hn / (2 * zeta * w * w);
      break;
    case KF_IMPORTANCE_STATIC:
      importance[i] = hn / (w * w);
      break;
    }
    imax = PetscMax(imax, importance[i]);
  }
  if (imax > 0)
    for (PetscInt i = 0; i < n; i++) importance[i] /= imax;
  PetscCall(PetscFree2(HPhi, PhiG));
  PetscFunctionReturn(0);
}
