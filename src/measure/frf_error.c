/* The frequency-response error measures: one definition for the reducer, the verification and the Python face. */
#include <kryflex_impl.h>

/* max that lets a NaN through, as NumPy's max does: a NaN response must not pass for a small error */
static inline PetscReal MaxNaN(PetscReal x, PetscReal y)
{
  if (PetscIsNanReal(x) || PetscIsNanReal(y)) return (PetscReal)NAN;
  return x < y ? y : x;
}

/* |Tf - Tg| at entry e (Tg NULL: |Tf|) */
static inline PetscReal Part(const PetscReal Tfre[], const PetscReal Tfim[], const PetscReal Tgre[], const PetscReal Tgim[], PetscInt e)
{
  const PetscReal re = Tfre[e] - (Tgre ? Tgre[e] : 0), im = Tfim[e] - (Tgim ? Tgim[e] : 0);
  return PetscSqrtReal(re * re + im * im);
}

/*
  KFFRFPairScales - the denominator of each input/output pair's relative error: the peak over the grid of the measured
  part of the full response, |Tf - Tg| (the elastic response, Tg the rigid-body and mechanism part) or |Tf| (Tg NULL:
  the total response), raised to KF_FRF_PAIR_FLOOR times the largest pair's peak and, for the elastic response, to
  KF_FRF_ELASTIC_FLOOR times the pair's own total peak (an elastic response below it is the rigid part's rounding: two
  double-precision references of the light-mass stress scene, whose elastic peak is 5e-8 of its total, differ by
  3e-10 of the total, 1e-2 of the elastic peak). scale: t x a; top: the largest pair's peak, before the rounding
  floor (may be NULL).
*/
static PetscErrorCode KFFRFPairScalesFloors(PetscInt nw, PetscInt t, PetscInt a, const PetscReal Tfre[], const PetscReal Tfim[], const PetscReal Tgre[], const PetscReal Tgim[], PetscReal scale[], PetscReal *top, PetscInt floor[])
{
  const PetscInt m = t * a;
  PetscReal      big = 0;

  PetscFunctionBegin;
  PetscCheck(nw >= 1, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFFRFPairScales: no frequencies (nw = %" PetscInt_FMT "); give at least one", nw);
  PetscCheck(t >= 0 && a >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFFRFPairScales: negative size (t %" PetscInt_FMT ", a %" PetscInt_FMT ")", t, a);
  PetscCheck(!Tgre == !Tgim, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "KFFRFPairScales: give both parts of the rigid response or neither");
  for (PetscInt k = 0; k < m; k++) scale[k] = 0;
  for (PetscInt f = 0; f < nw; f++)
    for (PetscInt k = 0; k < m; k++) scale[k] = MaxNaN(scale[k], Part(Tfre, Tfim, Tgre, Tgim, f * m + k));
  for (PetscInt k = 0; k < m; k++) big = MaxNaN(big, scale[k]);
  for (PetscInt k = 0; k < m && floor; k++) floor[k] = scale[k] < KF_FRF_PAIR_FLOOR * big ? 1 : 0;
  for (PetscInt k = 0; k < m; k++) scale[k] = MaxNaN(MaxNaN(scale[k], KF_FRF_PAIR_FLOOR * big), 1e-300);
  if (top) *top = big;
  if (Tgre) { /* the total peak of each pair: the rounding floor of its elastic peak */
    PetscReal *tot;

    PetscCall(PetscCalloc1(PetscMax(m, 1), &tot));
    for (PetscInt f = 0; f < nw; f++)
      for (PetscInt k = 0; k < m; k++) tot[k] = MaxNaN(tot[k], Part(Tfre, Tfim, NULL, NULL, f * m + k));
    for (PetscInt k = 0; k < m && floor; k++)
      if (scale[k] < KF_FRF_ELASTIC_FLOOR * tot[k]) floor[k] = 2;
    for (PetscInt k = 0; k < m; k++) scale[k] = MaxNaN(scale[k], KF_FRF_ELASTIC_FLOOR * tot[k]);
    PetscCall(PetscFree(tot));
  }
  PetscFunctionReturn(0);
}

PetscErrorCode KFFRFPairScales(PetscInt nw, PetscInt t, PetscInt a, const PetscReal Tfre[], const PetscReal Tfim[], const PetscReal Tgre[], const PetscReal Tgim[], PetscReal scale[], PetscReal *top)
{
  PetscFunctionBegin;
  PetscCall(KFFRFPairScalesFloors(nw, t, a, Tfre, Tfim, Tgre, Tgim, scale, top, NULL));
  PetscFunctionReturn(0);
}

/* KFFRFPairFloors - which floor, if any, is each pair's denominator (KFFRFPairScales): 0 its own peak, 1
   KF_FRF_PAIR_FLOOR times the largest pair's peak (its peak negligible against that one's), 2 KF_FRF_ELASTIC_FLOOR
   times its own total peak (its elastic peak within the rigid part's rounding). floor: t x a */
PetscErrorCode KFFRFPairFloors(PetscInt nw, PetscInt t, PetscInt a, const PetscReal Tfre[], const PetscReal Tfim[], const PetscReal Tgre[], const PetscReal Tgim[], PetscInt floor[])
{
  PetscReal *scale;

  PetscFunctionBegin;
  PetscCall(PetscMalloc1(PetscMax(t * a, 1), &scale));
  PetscCall(KFFRFPairScalesFloors(nw, t, a, Tfre, Tfim, Tgre, Tgim, scale, NULL, floor));
  PetscCall(PetscFree(scale));
  PetscFunctionReturn(0);
}

/*
  KFFRFElasticErrors - the two measures of a reduced frequency response Tr against the full one Tf, per input/output
  pair (i, j), on the part of the response the accuracy is stated on: the elastic response Tf - Tg, where Tg is the
  rigid-body and mechanism part of Tf (the same in both models: both hold the geometric rigid modes exactly), or the
  total response (Tg NULL):

    hinf      = max_ij  max_w |Tf_ij - Tr_ij| / s_ij,  s_ij = max_w |Tf_ij - Tg_ij|    relative H-infinity error over
                                                                                         the band: the accuracy
                                                                                         target applies to this one
    pointwise = max_ij  max_w |Tf_ij - Tr_ij| / max(|Tf_ij(w) - Tg_ij(w)|, 10^(floor_db/20) s_ij)

  A pair whose peak is below 1e-4 of the largest pair's peak (zero by symmetry, or nearly) is measured against 1e-4
  times that largest peak (KFFRFPairScales), so that its rounding does not pass for a large relative error: at a
  lightly damped resonance any double-precision response (full order or reduced) carries about eps cond(K) / (2 zeta)
  of the largest peak in every pair, 1e-8 on the Galileo scene with 8 inputs and 8 outputs, which a 1e-6 floor would
  turn into 1e-2. Why the elastic part: at the band's bottom the rigid 1/w^2 response dominates every pair's total
  peak, and a model missing every resonance can then pass. pointwise is notch-aware: in antiresonances deeper than
  floor_db below the pair's peak it is measured against that floor; it is reported for information. Either output
  may be NULL. T*: nw blocks of t x a.
*/
/* KFFRFElasticErrors, and where hinf is made (the reducer refines it there): *pair and *freq the first pair and
   frequency, in frequency then pair order, of the largest |Tf - Tr| / s (-1 when no entry is a number), *pscale that
   pair's s; pointwise NULL: not measured */
PetscErrorCode KFFRFElasticErrorsWorst_Private(PetscInt nw, PetscInt t, PetscInt a, const PetscReal Tfre[], const PetscReal Tfim[], const PetscReal Trre[], const PetscReal Trim[], const PetscReal Tgre[], const PetscReal Tgim[], PetscReal floor_db, PetscReal *hinf, PetscReal *pointwise, PetscInt *pair, PetscInt *freq, PetscReal *pscale)
{
  const PetscInt m = t * a;
  PetscReal     *scale, *dmax, top = 0, eh = 0, ep = 0, fl, best = -1;
  PetscInt       kw = -1, fw = -1;

  PetscFunctionBegin;
  PetscCheck(nw >= 1, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFFRFErrors: no frequencies (nw = %" PetscInt_FMT "); give at least one", nw);
  PetscCheck(t >= 0 && a >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFFRFErrors: negative size (t %" PetscInt_FMT ", a %" PetscInt_FMT ")", t, a);
  PetscCheck(!PetscIsInfOrNanReal(floor_db), PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFFRFErrors: the floor must be a finite number of dB (such as -60)");
  fl = PetscPowReal(10.0, floor_db / 20.0);
  PetscCall(PetscCalloc2(PetscMax(m, 1), &scale, PetscMax(m, 1), &dmax));
  PetscCall(KFFRFPairScales(nw, t, a, Tfre, Tfim, Tgre, Tgim, scale, &top));
  for (PetscInt f = 0; f < nw; f++)
    for (PetscInt k = 0; k < m; k++) {
      const PetscReal dre = Tfre[f * m + k] - Trre[f * m + k], dim = Tfim[f * m + k] - Trim[f * m + k];
      const PetscReal d = PetscSqrtReal(dre * dre + dim * dim), e = d / scale[k];

      dmax[k] = MaxNaN(dmax[k], d);
      if (e > best) {
        best = e;
        kw   = k;
        fw   = f;
      }
      if (pointwise) {
        const PetscReal ref = MaxNaN(MaxNaN(Part(Tfre, Tfim, Tgre, Tgim, f * m + k), fl * scale[k]), 1e-300);

        ep = MaxNaN(ep, d / ref);
      }
    }
  for (PetscInt k = 0; k < m; k++) eh = MaxNaN(eh, dmax[k] / scale[k]);
  if (PetscIsNanReal(top)) eh = ep = (PetscReal)NAN;
  if (hinf) *hinf = eh;
  if (pointwise) *pointwise = ep;
  if (pair) *pair = kw;
  if (freq) *freq = fw;
  if (pscale) *pscale = kw >= 0 ? scale[kw] : 1;
  PetscCall(PetscFree2(scale, dmax));
  PetscFunctionReturn(0);
}

PetscErrorCode KFFRFElasticErrors(PetscInt nw, PetscInt t, PetscInt a, const PetscReal Tfre[], const PetscReal Tfim[], const PetscReal Trre[], const PetscReal Trim[], const PetscReal Tgre[], const PetscReal Tgim[], PetscReal floor_db, PetscReal *hinf, PetscReal *pointwise)
{
  PetscFunctionBegin;
  PetscCall(KFFRFElasticErrorsWorst_Private(nw, t, a, Tfre, Tfim, Trre, Trim, Tgre, Tgim, floor_db, hinf, pointwise, NULL, NULL, NULL));
  PetscFunctionReturn(0);
}

/* KFFRFErrors - the total-response measure: KFFRFElasticErrors without a rigid part */
PetscErrorCode KFFRFErrors(PetscInt nw, PetscInt t, PetscInt a, const PetscReal Tfre[], const PetscReal Tfim[], const PetscReal Trre[], const PetscReal Trim[], PetscReal floor_db, PetscReal *hinf, PetscReal *pointwise)
{
  PetscFunctionBegin;
  PetscCall(KFFRFElasticErrors(nw, t, a, Tfre, Tfim, Trre, Trim, NULL, NULL, floor_db, hinf, pointwise));
  PetscFunctionReturn(0);
}
