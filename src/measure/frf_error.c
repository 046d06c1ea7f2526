/* The frequency-response error measures: one definition for the reducer, the verification and the Python face. */
#include <kryflex_impl.h>

/* max that lets a NaN through, as NumPy's max does: a NaN response must not pass for a small error */
static inline PetscReal MaxNaN(PetscReal x, PetscReal y)
{
  if (PetscIsNanReal(x) || PetscIsNanReal(y)) return (PetscReal)NAN;
  return x < y ? y : x;
}

/*
  KFFRFErrors - the two measures of a reduced frequency response against the full one, per input/output pair (i, j):

    hinf      = max_ij  max_w |Tf_ij - Tr_ij| / max_w |Tf_ij|        relative H-infinity error over the band: the
                                                                       accuracy target applies to this one
    pointwise = max_ij  max_w |Tf_ij - Tr_ij| / max(|Tf_ij(w)|, floor_ij),  floor_ij = 10^(floor_db/20) max_w |Tf_ij|

  A pair whose peak is below 1e-4 of the largest pair's peak (zero by symmetry, or nearly) is measured against 1e-4
  times that largest peak, so that its rounding does not pass for a large relative error: at a lightly damped
  resonance any double-precision response (full order or reduced) carries about eps cond(K) / (2 zeta) of the largest
  peak in every pair, 1e-8 on the Galileo scene with 8 inputs and 8 outputs, which a 1e-6 floor would turn into 1e-2. pointwise is notch-aware:
  in antiresonances deeper than floor_db below the pair's peak it is measured against that floor; it is reported for
  information. Either output may be NULL. T*: nw blocks of t x a.
*/
PetscErrorCode KFFRFErrors(PetscInt nw, PetscInt t, PetscInt a, const PetscReal Tfre[], const PetscReal Tfim[], const PetscReal Trre[], const PetscReal Trim[], PetscReal floor_db, PetscReal *hinf, PetscReal *pointwise)
{
  const PetscInt  m = t * a;
  const PetscReal negligible = KF_FRF_PAIR_FLOOR;
  PetscReal      *peak, *dmax, top = 0, eh = 0, ep = 0, fl;

  PetscFunctionBegin;
  PetscCheck(nw >= 1, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFFRFErrors: no frequencies (nw = %" PetscInt_FMT "); give at least one", nw);
  PetscCheck(t >= 0 && a >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFFRFErrors: negative size (t %" PetscInt_FMT ", a %" PetscInt_FMT ")", t, a);
  PetscCheck(!PetscIsInfOrNanReal(floor_db), PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFFRFErrors: the floor must be a finite number of dB (such as -60)");
  fl = PetscPowReal(10.0, floor_db / 20.0);
  PetscCall(PetscCalloc2(PetscMax(m, 1), &peak, PetscMax(m, 1), &dmax));
  for (PetscInt f = 0; f < nw; f++)
    for (PetscInt k = 0; k < m; k++) {
      const PetscReal full = PetscSqrtReal(Tfre[f * m + k] * Tfre[f * m + k] + Tfim[f * m + k] * Tfim[f * m + k]);
      const PetscReal dre = Tfre[f * m + k] - Trre[f * m + k], dim = Tfim[f * m + k] - Trim[f * m + k];

      peak[k] = MaxNaN(peak[k], full);
      dmax[k] = MaxNaN(dmax[k], PetscSqrtReal(dre * dre + dim * dim));
    }
  for (PetscInt k = 0; k < m; k++) top = MaxNaN(top, peak[k]);
  for (PetscInt k = 0; k < m; k++) {
    const PetscReal ref = MaxNaN(MaxNaN(peak[k], negligible * top), 1e-300);

    eh = MaxNaN(eh, dmax[k] / ref);
  }
  for (PetscInt f = 0; f < nw; f++)
    for (PetscInt k = 0; k < m; k++) {
      const PetscReal full = PetscSqrtReal(Tfre[f * m + k] * Tfre[f * m + k] + Tfim[f * m + k] * Tfim[f * m + k]);
      const PetscReal dre = Tfre[f * m + k] - Trre[f * m + k], dim = Tfim[f * m + k] - Trim[f * m + k];
      const PetscReal ref = MaxNaN(MaxNaN(full, fl * MaxNaN(peak[k], negligible * top)), 1e-300);

      ep = MaxNaN(ep, PetscSqrtReal(dre * dre + dim * dim) / ref);
    }
  if (PetscIsNanReal(top)) eh = ep = (PetscReal)NAN;
  if (hinf) *hinf = eh;
  if (pointwise) *pointwise = ep;
  PetscCall(PetscFree2(peak, dmax));
  PetscFunctionReturn(0);
}
