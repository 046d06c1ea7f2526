/* Low-frequency moments of a small pencil with known rigid modes, by solves: the rigid subspace from geometry is
   exact, where an eigendecomposition of a stiff model blurs it into the softest flexible mode. */
#include "dense_impl.h"
#include <petscblaslapack.h>

/* x <- x - Phi (Phi^T M x) (onto the flexible subspace) or, with left, x <- x - M Phi (Phi^T x) */
static PetscErrorCode Project(PetscInt n, PetscInt r, const PetscReal Phi[], const PetscReal MPhi[], PetscInt p, PetscReal X[], PetscBool left, PetscReal work[])
{
  PetscFunctionBegin;
  PetscCall(KFDenseGemm_Private('T', 'N', r, p, n, 1.0, left ? Phi : MPhi, n, X, n, 0.0, work, r));
  PetscCall(KFDenseGemm_Private('N', 'N', n, p, r, -1.0, left ? MPhi : Phi, n, work, r, 1.0, X, n));
  PetscFunctionReturn(0);
}

PetscErrorCode KFDenseMomentsRigid(PetscInt n, const PetscReal K[], const PetscReal M[], PetscInt a, const PetscReal G[], PetscInt t, const PetscReal H[], PetscInt r, const PetscReal Phir[], PetscInt nmom, PetscReal L[])
{
  PetscReal   *Phi, *MPhi, *A, *X, *Y, *work, *lambda, *vecs, sigma, *Gm, *A0, *work2;
  PetscBLASInt bn, bp, info;

  PetscFunctionBegin;
  PetscCheck(n >= 1 && r >= 0 && r <= n && a >= 1 && t >= 1 && nmom >= 1, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFDenseMomentsRigid: bad sizes (n %" PetscInt_FMT ", r %" PetscInt_FMT ", a %" PetscInt_FMT ", t %" PetscInt_FMT ", nmom %" PetscInt_FMT ")", n, r, a, t, nmom);
  if (r == n) { /* rigid motions only (a search's smallest candidate): no flexible subspace, every moment is zero */
    PetscCall(PetscArrayzero(L, nmom * t * a));
    PetscFunctionReturn(0);
  }
  PetscCall(PetscMalloc5(n * PetscMax(r, 1), &Phi, n * PetscMax(r, 1), &MPhi, n * n, &A, n * a, &X, n * a, &Y));
  PetscCall(PetscMalloc4(PetscMax(r, 1) * PetscMax(a, r), &work, n, &lambda, n * n, &vecs, PetscMax(r * r, 1), &Gm));
  PetscCall(PetscMalloc2(n * n, &A0, n * a, &work2));
  /* M-orthonormal rigid modes (Cholesky of their Gram matrix) */
  PetscCall(PetscArraycpy(Phi, Phir, n * r));
  for (int pass = 0; pass < 2 && r; pass++) {
    PetscCall(KFDenseGemm_Private('N', 'N', n, r, n, 1.0, M, n, Phi, n, 0.0, MPhi, n));
    PetscCall(KFDenseGemm_Private('T', 'N', r, r, n, 1.0, Phi, n, MPhi, n, 0.0, Gm, r));
    PetscCall(PetscBLASIntCast(r, &bp));
    PetscCallBLAS("LAPACKpotrf", LAPACKpotrf_("L", &bp, Gm, &bp, &info));
    PetscCheck(!info, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG, "KFDenseMomentsRigid: the rigid modes are linearly dependent (LAPACK info %d)", (int)info);
    for (PetscInt i = 0; i < n; i++) /* Phi <- Phi L^-T, row by row */
      for (PetscInt j = 0; j < r; j++) {
        PetscReal v = Phi[i + j * n];
        for (PetscInt k = 0; k < j; k++) v -= Gm[j + k * r] * Phi[i + k * n];
        Phi[i + j * n] = v / Gm[j + j * r];
      }
  }
  if (r) PetscCall(KFDenseGemm_Private('N', 'N', n, r, n, 1.0, M, n, Phi, n, 0.0, MPhi, n));
  /* A = K + sigma (M Phi)(M Phi)^T with sigma the first flexible eigenvalue: the rigid modes move up to it, the
     spectrum keeps its span, and A^-1 equals K+ on self-equilibrated loads */
  PetscCall(KFDenseEig(n, K, M, lambda, vecs));
  sigma = lambda[r] > 0 ? lambda[r] : 1.0;
  PetscCall(PetscArraycpy(A, K, n * n));
  if (r) PetscCall(KFDenseGemm_Private('N', 'T', n, n, r, sigma, MPhi, n, MPhi, n, 1.0, A, n));
  PetscCall(KFDenseSymmetrize_Private(n, A));
  PetscCall(PetscArraycpy(A0, A, n * n));
  PetscCall(PetscBLASIntCast(n, &bn));
  PetscCallBLAS("LAPACKpotrf", LAPACKpotrf_("L", &bn, A, &bn, &info));
  PetscCheck(!info, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG, "KFDenseMomentsRigid: K + sigma M Phi Phi^T M is not positive definite (LAPACK info %d): the stiffness has zero-energy modes beyond the %" PetscInt_FMT " rigid ones", (int)info, r);
  PetscCall(PetscArraycpy(X, G, n * a));
  for (PetscInt k = 0; k < nmom; k++) {
    /* X <- K+ X: self-equilibrate, solve, project onto the flexible subspace */
    if (r) PetscCall(Project(n, r, Phi, MPhi, a, X, PETSC_TRUE, work));
    PetscCall(PetscBLASIntCast(a, &bp));
    PetscCall(PetscArraycpy(Y, X, n * a));
    PetscCallBLAS("LAPACKpotrs", LAPACKpotrs_("L", &bn, &bp, A, &bn, X, &bn, &info));
    /* two steps of refinement with the residual in long double: the solve of a stiff model loses digits that the
       full-order solves (refined the same way) keep, and the moments compare the two */
    for (int it = 0; it < 2; it++) {
      for (PetscInt j = 0; j < a; j++)
        for (PetscInt i = 0; i < n; i++) {
          long double r = Y[i + j * n];
          for (PetscInt k = 0; k < n; k++) r -= (long double)A0[i + k * n] * X[k + j * n];
          work2[i + j * n] = (PetscReal)r;
        }
      PetscCallBLAS("LAPACKpotrs", LAPACKpotrs_("L", &bn, &bp, A, &bn, work2, &bn, &info));
      for (PetscInt i = 0; i < n * a; i++) X[i] += work2[i];
    }
    if (r) PetscCall(Project(n, r, Phi, MPhi, a, X, PETSC_FALSE, work));
    PetscCall(KFDenseGemm_Private('N', 'N', t, a, n, 1.0, H, t, X, n, 0.0, L + k * t * a, t));
    PetscCall(KFDenseGemm_Private('N', 'N', n, a, n, 1.0, M, n, X, n, 0.0, Y, n));
    PetscCall(PetscArraycpy(X, Y, n * a));
  }
  PetscCall(PetscFree5(Phi, MPhi, A, X, Y));
  PetscCall(PetscFree4(work, lambda, vecs, Gm));
  PetscCall(PetscFree2(A0, work2));
  PetscFunctionReturn(0);
}
