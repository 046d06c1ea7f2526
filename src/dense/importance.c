/* Mode importance (paper eq. 12-13): how much each mode contributes to the input-to-output map; and its band-aware,
   cluster-invariant variant. */
#include "dense_impl.h"

/* With zeta = 0 a mode inside the band has an infinite peak; the band measure then uses this damping ratio, so that
   in-band clusters rank by ||R||_2 / lambda among themselves and above every out-of-band one. */
#define KF_IMPORTANCE_ZETA_FLOOR 1e-6

PetscErrorCode KFDenseModeImportance(PetscInt n, const PetscReal lambda[], const PetscReal Phi[], PetscInt a, const PetscReal G[], PetscInt t, const PetscReal H[], PetscReal zeta, KFImportance kind, PetscReal rigid_tol, PetscReal importance[])
{
  PetscReal *HPhi, *PhiG, lmax, imax = 0;

  PetscFunctionBegin;
  PetscCheck(n >= 0 && a >= 0 && t >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFDenseModeImportance: negative size (n %" PetscInt_FMT ", a %" PetscInt_FMT ", t %" PetscInt_FMT ")", n, a, t);
  PetscCheck(kind != KF_IMPORTANCE_BAND, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG, "KFDenseModeImportance: the band measure needs the band and the cluster tolerance: call KFDenseModeImportanceBand");
  PetscCheck(kind == KF_IMPORTANCE_H2 || kind == KF_IMPORTANCE_HINF || kind == KF_IMPORTANCE_STATIC, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFDenseModeImportance: unknown importance measure %d: use KF_IMPORTANCE_H2, _HINF or _STATIC (or KFDenseModeImportanceBand)", (int)kind);
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
    case KF_IMPORTANCE_BAND: /* refused above */
      break;
    }
    imax = PetscMax(imax, importance[i]);
  }
  if (imax > 0)
    for (PetscInt i = 0; i < n; i++) importance[i] /= imax;
  PetscCall(PetscFree2(HPhi, PhiG));
  PetscFunctionReturn(0);
}

/* max over w in [wmin, wmax] of 1 / |lambda - w^2 + 2 i zeta sqrt(lambda) w|. With u = w^2 the squared denominator
   (lambda - u)^2 + 4 zeta^2 lambda u is a convex quadratic in u with its minimum at u* = lambda (1 - 2 zeta^2), so on
   [wmin^2, wmax^2] it is smallest at u* clamped to the interval; u* <= 0 (zeta >= 1/sqrt 2) clamps to wmin. */
static PetscReal BandPeak(PetscReal lambda, PetscReal zeta, PetscReal wmin, PetscReal wmax)
{
  PetscReal w = PetscSqrtReal(PetscMax(lambda * (1 - 2 * zeta * zeta), 0));

  w = PetscMin(PetscMax(w, wmin), wmax);
  return 1 / PetscHypotReal(lambda - w * w, 2 * zeta * PetscSqrtReal(lambda) * w);
}

PetscErrorCode KFDenseModeImportanceBand(PetscInt n, const PetscReal lambda[], const PetscReal Phi[], PetscInt a, const PetscReal G[], PetscInt t, const PetscReal H[], PetscReal zeta, const PetscReal band_hz[2], PetscReal cluster_rtol, PetscReal rigid_tol, PetscReal importance[], PetscInt cluster[])
{
  PetscReal *HPhi, *PhiG, *R, *s, lmax, imax = 0, wmin, wmax, zeff, wprev = 0;
  PetscInt  *perm, nc = 0, first = 0, nflex = 0;

  PetscFunctionBegin;
  PetscCheck(n >= 0 && a >= 0 && t >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFDenseModeImportanceBand: negative size (n %" PetscInt_FMT ", a %" PetscInt_FMT ", t %" PetscInt_FMT ")", n, a, t);
  PetscCheck(zeta >= 0 && !PetscIsInfOrNanReal(zeta), PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFDenseModeImportanceBand: the damping ratio must be >= 0 and finite, got %g", (double)zeta);
  PetscCheck(band_hz, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "KFDenseModeImportanceBand: no band: pass band_hz = {fmin, fmax} in Hz");
  PetscCheck(band_hz[0] >= 0 && band_hz[1] >= band_hz[0] && !PetscIsInfOrNanReal(band_hz[1]), PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
             "KFDenseModeImportanceBand: the band [%g, %g] Hz is not an interval 0 <= fmin <= fmax < inf", (double)band_hz[0], (double)band_hz[1]);
  PetscCheck(cluster_rtol >= 0 && cluster_rtol < 1, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFDenseModeImportanceBand: cluster tolerance %g is outside [0, 1): use a small relative gap such as 1e-3", (double)cluster_rtol);
  PetscCheck(rigid_tol >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFDenseModeImportanceBand: negative rigid tolerance %g", (double)rigid_tol);
  if (!n) PetscFunctionReturn(0);
  for (PetscInt i = 0; i < n; i++)
    PetscCheck(!PetscIsInfOrNanReal(lambda[i]), PETSC_COMM_SELF, PETSC_ERR_FP, "KFDenseModeImportanceBand: eigenvalue %" PetscInt_FMT " is Inf or NaN", i);
  wmin = 2 * PETSC_PI * band_hz[0];
  wmax = 2 * PETSC_PI * band_hz[1];
  zeff = PetscMax(zeta, KF_IMPORTANCE_ZETA_FLOOR);
  PetscCall(PetscMalloc5(t * n, &HPhi, n * a, &PhiG, t * a, &R, PetscMin(t, a) + 1, &s, n, &perm));
  PetscCall(KFDenseGemm_Private('N', 'N', t, n, n, 1.0, H, t, Phi, n, 0.0, HPhi, t));
  PetscCall(KFDenseGemm_Private('T', 'N', n, a, n, 1.0, Phi, n, G, n, 0.0, PhiG, n));
  lmax = KFDenseMaxReal_Private(n, lambda);
  /* the flexible modes in ascending frequency (KFDenseEig already gives them so; sorting costs nothing and makes the
     cluster ids ascending whatever the order), rigid ones marked */
  for (PetscInt i = 0; i < n; i++) {
    perm[i]       = i;
    importance[i] = 0;
    cluster[i]    = -1;
  }
  PetscCall(PetscSortRealWithPermutation(n, lambda, perm));
  for (PetscInt k = 0; k < n; k++)
    if (KFDenseIsFlexible_Private(lambda[perm[k]], lmax, rigid_tol)) perm[nflex++] = perm[k];
  /* clusters by the chain rule: mode k joins the open cluster when w_k - w_(k-1) <= cluster_rtol w_k; a cluster is
     closed (and scored) when the next mode does not join it or the modes run out */
  for (PetscInt k = 0; k <= nflex; k++) {
    PetscReal w = k < nflex ? PetscSqrtReal(lambda[perm[k]]) : 0, lc = 0, rn = 0;

    if (k > 0 && k < nflex && w - wprev <= cluster_rtol * w) {
      wprev = w;
      continue;
    }
    if (k > 0) { /* score the cluster perm[first .. k-1]: R = sum H phi phi^T G, invariant to the basis inside it */
      PetscCall(PetscArrayzero(R, t * a));
      for (PetscInt c = first; c < k; c++) {
        const PetscInt i = perm[c];

        lc += lambda[i];
        for (PetscInt j = 0; j < a; j++)
          for (PetscInt r = 0; r < t; r++) R[r + j * t] += HPhi[r + i * t] * PhiG[i + j * n];
      }
      lc /= (k - first);
      if (t && a) {
        PetscCall(KFDenseSingularValues_Private(t, a, R, s, "KFDenseModeImportanceBand"));
        rn = s[0];
      }
      for (PetscInt c = first; c < k; c++) {
        importance[perm[c]] = rn * BandPeak(lc, zeff, wmin, wmax);
        cluster[perm[c]]    = nc;
      }
      imax = PetscMax(imax, importance[perm[first]]);
      nc++;
    }
    first = k;
    wprev = w;
  }
  if (imax > 0)
    for (PetscInt i = 0; i < n; i++) importance[i] /= imax;
  PetscCall(PetscFree5(HPhi, PhiG, R, s, perm));
  PetscFunctionReturn(0);
}
