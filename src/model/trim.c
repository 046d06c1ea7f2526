/*
  Trimming a reassembled reduced system: the modes above a frequency limit taken out of the dynamics, their static
  contribution kept as a quasi-static feedthrough (residualization, the paper's open item (i)).

  With the system's M-orthonormal modes Phi = [Phi_r, Phi_k, Phi_h] (rigid, kept flexible, high), the trimmed system
  is the kept modes' modal system and a feedthrough:

      q'' + diag(lambda_k) q = Phi_k^T G u,     y = H Phi_k q + D u,     D = L^0 - L^0_kept

  where L^0 is the untrimmed system's static moment (by solves, KFReducedSystemMoments) and L^0_kept the kept modal
  system's. D is sum_high H phi phi^T G / lambda in exact arithmetic; taking it as the difference keeps the trimmed
  L^0 equal to the untrimmed one to round-off even where the modal sum loses digits. The higher moments
  L^k (k >= 1) lose the high modes' share, H phi phi^T G / lambda^(k+1), which is what the accuracy measure sees.
*/
#include <kryflex/modelimpl.h>
#include "../dense/dense_impl.h"

/*
  KFParseMaxFrequency - "3" or "3x": a multiple of the band's top; "40 Hz" (or "40hz"): an explicit frequency;
  "none", "off" or "0": no trimming. value <= 0 means off; *hz tells which of the two a positive value is.
*/
PetscErrorCode KFParseMaxFrequency(MPI_Comm comm, const char text[], PetscReal *value, PetscBool *hz)
{
  char      *end;
  double     x;
  PetscBool  off;
  const char usage[] = "give a multiple of the band's top frequency (3 or 3x), a frequency (\"40 Hz\") or none";

  PetscFunctionBegin;
  *value = 0;
  *hz    = PETSC_FALSE;
  PetscCheck(text, comm, PETSC_ERR_ARG_NULL, "max_frequency: no value: %s", usage);
  PetscCall(PetscStrcasecmp(text, "none", &off));
  if (!off) PetscCall(PetscStrcasecmp(text, "off", &off));
  if (off) PetscFunctionReturn(0);
  x = strtod(text, &end);
  PetscCheck(end != text && !PetscIsInfOrNanReal((PetscReal)x) && x >= 0, comm, PETSC_ERR_ARG_WRONG, "max_frequency '%s' is not a non-negative number: %s", text, usage);
  while (*end == ' ') end++;
  if (*end == 'x' || *end == 'X') end++;
  else if ((end[0] == 'H' || end[0] == 'h') && (end[1] == 'z' || end[1] == 'Z')) {
    end += 2;
    *hz = PETSC_TRUE;
  }
  PetscCheck(*end == 0, comm, PETSC_ERR_ARG_WRONG, "max_frequency '%s' has an unknown unit: %s", text, usage);
  PetscCheck(x == 0 || *hz || x >= 1, comm, PETSC_ERR_ARG_OUTOFRANGE, "max_frequency '%s' is below the band's top: the band's own modes would be removed; give a multiple >= 1 (3 is a good start)", text);
  *value = (PetscReal)x;
  PetscFunctionReturn(0);
}

/* max_frequency (Hz) from the model's settings (the reducer records the limit it reduced with), 0 (off) otherwise */
PetscErrorCode KFReducedModelGetMaxFrequency(KFReducedModel m, PetscReal *fmax_hz)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, KF_REDUCEDMODEL_CLASSID, 1);
  PetscValidRealPointer(fmax_hz, 2);
  *fmax_hz = 0;
  for (PetscInt k = 0; k < m->nsettings; k++) {
    PetscBool same;
    char     *end;
    double    x;

    PetscCall(PetscStrcmp(m->keys[k], "max_frequency_hz", &same));
    if (!same) continue;
    PetscCall(PetscStrcmp(m->values[k], "null", &same));
    if (same) continue;
    x = strtod(m->values[k], &end);
    PetscCheck(end != m->values[k] && *end == 0 && x >= 0 && !PetscIsInfOrNanReal((PetscReal)x), PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_WRONG, "the model's setting max_frequency_hz = '%s' is not a frequency >= 0 (Hz; 0 or null: no trimming): set it again (KFReducedModelSetSetting) or reduce again", m->values[k]);
    *fmax_hz = (PetscReal)x;
  }
  PetscFunctionReturn(0);
}

/*
  KFReducedSystemTrim - takes the flexible modes above fmax_hz out of the dynamics (see the file's comment): the system
  becomes the rigid and kept modes' modal system (M = I, K = diag(lambda)) with the feedthrough D. fmax_hz <= 0: no
  change. Idempotent for the same limit.
*/
PetscErrorCode KFReducedSystemTrim(KFReducedSystem y, PetscReal fmax_hz)
{
  PetscInt   n = y->n, a = y->a, t = y->t, nk, nh, nkeep = 0;
  PetscReal *L0, *Phik, *M, *K, *G, *H, *C = NULL, *Phir = NULL, *lambda, *Phi, *freq, *W;

  PetscFunctionBegin;
  PetscValidPointer(y, 1);
  if (!y->ntrimmed) y->ftop_untrimmed = y->nf ? y->freq[y->nf - 1] : 0;
  if (!(fmax_hz > 0)) PetscFunctionReturn(0);
  y->fmax_trim = fmax_hz;
  for (PetscInt i = 0; i < y->nf; i++) nkeep += y->freq[i] <= fmax_hz;
  nh = y->nf - nkeep;
  if (!nh) PetscFunctionReturn(0);
  nk = y->nrigid + nkeep; /* eigenpairs ascending: rigid first, then the kept flexible modes */

  PetscCall(PetscMalloc1(t * a + 1, &L0));
  PetscCall(KFReducedSystemMoments(y, 1, L0));

  Phik = y->Phi; /* its first nk columns */
  PetscCall(PetscMalloc4(nk * nk, &M, nk * nk, &K, nk * a, &G, t * nk, &H));
  PetscCall(PetscArrayzero(M, nk * nk));
  PetscCall(PetscArrayzero(K, nk * nk));
  for (PetscInt i = 0; i < nk; i++) {
    M[i + i * nk] = 1;
    K[i + i * nk] = y->lambda[i];
  }
  PetscCall(KFDenseGemm_Private('T', 'N', nk, a, n, 1.0, Phik, n, y->G, n, 0.0, G, nk));
  PetscCall(KFDenseGemm_Private('N', 'N', t, nk, n, 1.0, y->H, t, Phik, n, 0.0, H, t));
  PetscCall(PetscMalloc1(n * PetscMax(nk, y->nrigid), &W));
  if (y->C) {
    PetscCall(PetscMalloc1(nk * nk, &C));
    PetscCall(KFDenseGemm_Private('N', 'N', n, nk, n, 1.0, y->C, n, Phik, n, 0.0, W, n));
    PetscCall(KFDenseGemm_Private('T', 'N', nk, nk, n, 1.0, Phik, n, W, n, 0.0, C, nk));
    PetscCall(KFDenseSymmetrize_Private(nk, C));
  }
  if (y->Phir) { /* the rigid modes' modal coordinates: Phi_k^T M Phir */
    PetscCall(PetscMalloc1(nk * y->nrigid + 1, &Phir));
    PetscCall(KFDenseGemm_Private('N', 'N', n, y->nrigid, n, 1.0, y->M, n, y->Phir, n, 0.0, W, n));
    PetscCall(KFDenseGemm_Private('T', 'N', nk, y->nrigid, n, 1.0, Phik, n, W, n, 0.0, Phir, nk));
  }
  PetscCall(PetscFree(W));
  PetscCall(PetscMalloc2(nk, &lambda, nk * nk, &Phi));
  PetscCall(PetscArraycpy(lambda, y->lambda, nk));
  PetscCall(PetscArrayzero(Phi, nk * nk));
  for (PetscInt i = 0; i < nk; i++) Phi[i + i * nk] = 1;
  PetscCall(PetscMalloc1(nkeep + 1, &freq));
  PetscCall(PetscArraycpy(freq, y->freq, nkeep));

  PetscCall(PetscFree4(y->M, y->K, y->G, y->H));
  PetscCall(PetscFree2(y->lambda, y->Phi));
  PetscCall(PetscFree(y->Phir));
  PetscCall(PetscFree(y->C));
  PetscCall(PetscFree(y->Cm));
  PetscCall(PetscFree2(y->HPhi, y->PhiG));
  PetscCall(PetscFree(y->freq));
  y->n        = nk;
  y->M        = M;
  y->K        = K;
  y->G        = G;
  y->H        = H;
  y->C        = C;
  y->Phir     = Phir;
  y->lambda   = lambda;
  y->Phi      = Phi;
  y->freq     = freq;
  y->nf       = nkeep;
  y->ntrimmed = nh;

  /* D = L^0 - L^0_kept: the static moment stays the untrimmed one */
  {
    PetscReal *D;

    PetscCall(PetscFree(y->D)); /* the kept system's own L^0, without a feedthrough */
    PetscCall(PetscMalloc1(t * a + 1, &D));
    PetscCall(KFReducedSystemMoments(y, 1, D));
    for (PetscInt e = 0; e < t * a; e++) D[e] = L0[e] - D[e];
    y->D = D;
  }
  PetscCall(PetscFree(L0));
  PetscFunctionReturn(0);
}

/*
  KFReducedSystemGetTrim - the trimming of this system: modes taken out (0: none), the limit (Hz, 0: off), the highest
  flexible frequency before trimming (Hz) and the feedthrough D (t x a, column-major; NULL when nothing was trimmed).
*/
PetscErrorCode KFReducedSystemGetTrim(KFReducedSystem y, PetscInt *ntrimmed, PetscReal *fmax_hz, PetscReal *ftop_untrimmed_hz, const PetscReal **D)
{
  PetscFunctionBegin;
  PetscValidPointer(y, 1);
  if (ntrimmed) *ntrimmed = y->ntrimmed;
  if (fmax_hz) *fmax_hz = y->fmax_trim;
  if (ftop_untrimmed_hz) *ftop_untrimmed_hz = y->ftop_untrimmed;
  if (D) *D = y->D;
  PetscFunctionReturn(0);
}

