/* Hankel singular values of the damped modal system, from Gramians assembled 2x2 block by 2x2 block. */
#include "dense_impl.h"
#include <petscblaslapack.h> /* after the PETSc headers it relies on */

PetscErrorCode KFDenseSingularValues_Private(PetscInt m, PetscInt n, PetscReal A[], PetscReal s[], const char caller[])
{
  PetscBLASInt bm, bn, one = 1, lwork = -1, info = 0;
  PetscReal   *work, wquery = 0, dummy = 0;

  PetscFunctionBegin;
  if (m <= 0 || n <= 0) PetscFunctionReturn(0);
  PetscCall(PetscBLASIntCast(m, &bm));
  PetscCall(PetscBLASIntCast(n, &bn));
  PetscCall(PetscFPTrapPush(PETSC_FP_TRAP_OFF));
  PetscCallBLAS("LAPACKgesvd", LAPACKgesvd_("N", "N", &bm, &bn, A, &bm, s, &dummy, &one, &dummy, &one, &wquery, &lwork, &info));
  lwork = (PetscBLASInt)wquery;
  lwork = PetscMax(lwork, PetscMax(3 * PetscMin(bm, bn) + PetscMax(bm, bn), 5 * PetscMin(bm, bn)));
  PetscCall(PetscMalloc1(lwork, &work));
  PetscCallBLAS("LAPACKgesvd", LAPACKgesvd_("N", "N", &bm, &bn, A, &bm, s, &dummy, &one, &dummy, &one, work, &lwork, &info));
  PetscCall(PetscFPTrapPop());
  PetscCall(PetscFree(work));
  PetscCheck(info == 0, PETSC_COMM_SELF, PETSC_ERR_LIB, "%s: the SVD of a %" PetscInt_FMT " x %" PetscInt_FMT " matrix did not converge (LAPACK gesvd info %d): check the inputs for huge or tiny entries", caller, m, n, (int)info);
  PetscFunctionReturn(0);
}

/* X (2x2) solving Ai X + X Aj^T + Q = 0, by its Kronecker form (I kron Ai + Aj kron I) vec X = -vec Q (column-major
   vec: entry r + 2c). The eigenvalues of the 4x4 matrix are sums of one eigenvalue of Ai and one of Aj, all in the
   open left half-plane when both blocks are damped, so the system is nonsingular. */
static PetscErrorCode SolveBlock(const PetscReal Ai[4], const PetscReal Aj[4], const PetscReal Q[4], PetscReal X[4])
{
  PetscReal    S[16];
  PetscBLASInt four = 4, one = 1, ipiv[4], info = 0;

  PetscFunctionBegin;
  for (int c = 0; c < 2; c++)
    for (int r = 0; r < 2; r++)
      for (int c2 = 0; c2 < 2; c2++)
        for (int r2 = 0; r2 < 2; r2++) S[(r + 2 * c) + 4 * (r2 + 2 * c2)] = (c == c2 ? Ai[r + 2 * r2] : 0) + (r == r2 ? Aj[c + 2 * c2] : 0);
  for (int k = 0; k < 4; k++) X[k] = -Q[k];
  PetscCallBLAS("LAPACKgesv", LAPACKgesv_(&four, &one, S, &four, ipiv, X, &four, &info));
  PetscCheck(info == 0, PETSC_COMM_SELF, PETSC_ERR_LIB, "KFModalHankelSingularValues: singular 4 x 4 Lyapunov block (LAPACK gesv info %d): the damping ratio must be positive", (int)info);
  PetscFunctionReturn(0);
}

/* L = U diag(sqrt(max(s, 0))) from the eigendecomposition W = U diag(s) U^T of a symmetric positive semidefinite W
   (m x m, overwritten by L): rounding leaves tiny negative eigenvalues, which are clipped to 0. */
static PetscErrorCode GramianFactor(PetscInt m, PetscReal W[], const char what[])
{
  PetscBLASInt bm, lwork = -1, info = 0;
  PetscReal   *s, *work, wquery = 0;

  PetscFunctionBegin;
  PetscCall(PetscBLASIntCast(m, &bm));
  PetscCall(PetscMalloc1(m, &s));
  PetscCall(PetscFPTrapPush(PETSC_FP_TRAP_OFF));
  PetscCallBLAS("LAPACKsyev", LAPACKsyev_("V", "U", &bm, W, &bm, s, &wquery, &lwork, &info));
  lwork = (PetscBLASInt)wquery;
  lwork = PetscMax(lwork, 3 * bm);
  PetscCall(PetscMalloc1(lwork, &work));
  PetscCallBLAS("LAPACKsyev", LAPACKsyev_("V", "U", &bm, W, &bm, s, work, &lwork, &info));
  PetscCall(PetscFPTrapPop());
  PetscCall(PetscFree(work));
  PetscCheck(info == 0, PETSC_COMM_SELF, PETSC_ERR_LIB, "KFModalHankelSingularValues: the eigensolver did not converge on the %" PetscInt_FMT " x %" PetscInt_FMT " %s Gramian (LAPACK syev info %d): check the inputs for huge or tiny entries", m, m, what, (int)info);
  for (PetscInt j = 0; j < m; j++) {
    PetscReal f = PetscSqrtReal(PetscMax(s[j], 0));
    for (PetscInt i = 0; i < m; i++) W[i + j * m] *= f;
  }
  PetscCall(PetscFree(s));
  PetscFunctionReturn(0);
}

PetscErrorCode KFModalHankelSingularValues(PetscInt n, const PetscReal w2[], PetscInt t, const PetscReal HPhi[], PetscInt a, const PetscReal PhiG[], PetscReal zeta, PetscReal hsv[])
{
  const PetscInt m = 2 * n;
  PetscReal     *Wc, *Wo, *P;

  PetscFunctionBegin;
  PetscCheck(n >= 0 && t >= 0 && a >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFModalHankelSingularValues: negative size (n %" PetscInt_FMT ", t %" PetscInt_FMT ", a %" PetscInt_FMT ")", n, t, a);
  PetscCheck(zeta > 0 && !PetscIsInfOrNanReal(zeta), PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
             "KFModalHankelSingularValues: the damping ratio must be positive and finite, got %g: an undamped mode has unbounded Gramians (infinite Hankel singular values); set the scene's damping", (double)zeta);
  if (!n) PetscFunctionReturn(0);
  for (PetscInt k = 0; k < n; k++)
    PetscCheck(w2[k] > 0 && !PetscIsInfOrNanReal(w2[k]), PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
               "KFModalHankelSingularValues: mode %" PetscInt_FMT " has eigenvalue w^2 = %g: pass flexible modes only (w^2 > 0, finite); a rigid mode's Gramians are unbounded", k, (double)w2[k]);
  PetscCall(PetscMalloc3(m * m, &Wc, m * m, &Wo, m * m, &P));
  /* States x_k = (w_k q_k, qdot_k) instead of (q_k, qdot_k): a diagonal similarity, which leaves the Hankel singular
     values unchanged but gives both states of a mode Gramian entries of the same size (1/(4 zeta w) rather than
     1/(4 zeta w^3) and 1/(4 zeta w)), so the eigendecompositions below keep more digits of the small ones.
     A_k = [0 w; -w -2 zeta w], B_k = [0; PhiG(k,:)], C_k = [HPhi(:,k)/w 0]. A is block diagonal, so block (i,j) of
     Wc solves A_i X + X A_j^T + B_i B_j^T = 0 and block (i,j) of Wo solves A_i^T Y + Y A_j + C_i^T C_j = 0; block
     (j,i) is the transpose of block (i,j). */
  for (PetscInt j = 0; j < n; j++) {
    const PetscReal wj = PetscSqrtReal(w2[j]);
    const PetscReal Aj[4] = {0, -wj, wj, -2 * zeta * wj}, AjT[4] = {0, wj, -wj, -2 * zeta * wj};

    for (PetscInt i = 0; i <= j; i++) {
      const PetscReal wi = PetscSqrtReal(w2[i]);
      const PetscReal Ai[4] = {0, -wi, wi, -2 * zeta * wi}, AiT[4] = {0, wi, -wi, -2 * zeta * wi};
      PetscReal       gg = 0, hh = 0, Q[4], X[4], Y[4];

      for (PetscInt l = 0; l < a; l++) gg += PhiG[i + l * n] * PhiG[j + l * n];
      for (PetscInt l = 0; l < t; l++) hh += HPhi[l + i * t] * HPhi[l + j * t];
      Q[0] = Q[1] = Q[2] = 0;
      Q[3] = gg; /* B_i B_j^T */
      PetscCall(SolveBlock(Ai, Aj, Q, X));
      Q[0] = hh / (wi * wj); /* C_i^T C_j */
      Q[3] = 0;
      PetscCall(SolveBlock(AiT, AjT, Q, Y));
      for (int c = 0; c < 2; c++)
        for (int r = 0; r < 2; r++) {
          Wc[(2 * i + r) + (2 * j + c) * m] = Wc[(2 * j + c) + (2 * i + r) * m] = X[r + 2 * c];
          Wo[(2 * i + r) + (2 * j + c) * m] = Wo[(2 * j + c) + (2 * i + r) * m] = Y[r + 2 * c];
        }
    }
  }
  /* Wc = Lc Lc^T, Wo = Lo Lo^T: the eigenvalues of Wc Wo are the squared singular values of Lo^T Lc, which the SVD
     gets without forming the nonsymmetric product */
  PetscCall(GramianFactor(m, Wc, "controllability"));
  PetscCall(GramianFactor(m, Wo, "observability"));
  PetscCall(KFDenseGemm_Private('T', 'N', m, m, m, 1.0, Wo, m, Wc, m, 0.0, P, m));
  PetscCall(KFDenseSingularValues_Private(m, m, P, hsv, "KFModalHankelSingularValues"));
  PetscCall(PetscFree3(Wc, Wo, P));
  PetscFunctionReturn(0);
}
