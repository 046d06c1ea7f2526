/* The frequency-response error measure: one definition for the reducer, the verification and the Python face. */
#include <kryflex_impl.h>

/* max that lets a NaN through, as NumPy's max does: a NaN response must not pass for a small error */
static inline PetscReal MaxNaN(PetscReal x, PetscReal y)
{
  if (PetscIsNanReal(x) || PetscIsNanReal(y)) return (PetscReal)NAN;
  return x < y ? y : x;
}

/*
  KFFRFError - max over frequency of ||T_full - T_red||_F / max(||T_full||_F, floor), floor = 10^(floor_db/20) times
  the band's largest ||T_full||_F: a relative error, except that in antiresonance notches deeper than floor_db below
  the peak it is measured against that floor (a notch 1e-9 below the peak would otherwise turn rounding into a
  'large' relative error). Same as the former Python frf_error.
*/
PetscErrorCode KFFRFError(PetscInt nw, PetscInt t, PetscInt a, const PetscReal Tfre[], const PetscReal Tfim[], const PetscReal Trre[], const PetscReal Trim[], PetscReal floor_db, PetscReal *err)
{
  const PetscInt m = t * a;
  PetscReal     *num, *den, dmax = 0, floor, e = 0;

  PetscFunctionBegin;
  PetscValidRealPointer(err, 9);
  PetscCheck(nw >= 1, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFFRFError: no frequencies (nw = %" PetscInt_FMT "); give at least one", nw);
  PetscCheck(t >= 0 && a >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFFRFError: negative size (t %" PetscInt_FMT ", a %" PetscInt_FMT ")", t, a);
  PetscCheck(!PetscIsInfOrNanReal(floor_db), PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFFRFError: the floor must be a finite number of dB (such as -60)");
  PetscCall(PetscMalloc2(nw, &num, nw, &den));
  for (PetscInt f = 0; f < nw; f++) {
    PetscReal sn = 0, sd = 0;
    for (PetscInt k = f * m; k < (f + 1) * m; k++) {
      const PetscReal dre = Tfre[k] - Trre[k], dim = Tfim[k] - Trim[k];
      sn += dre * dre + dim * dim;
      sd += Tfre[k] * Tfre[k] + Tfim[k] * Tfim[k];
    }
    num[f] = PetscSqrtReal(sn);
    den[f] = PetscSqrtReal(sd);
    dmax   = f ? MaxNaN(dmax, den[f]) : den[f];
  }
  floor = MaxNaN(PetscPowReal(10.0, floor_db / 20.0) * dmax, 1e-300);
  for (PetscInt f = 0; f < nw; f++) {
    const PetscReal r = num[f] / MaxNaN(den[f], floor);
    e                 = f ? MaxNaN(e, r) : r;
  }
  *err = e;
  PetscCall(PetscFree2(num, den));
  PetscFunctionReturn(0);
}
