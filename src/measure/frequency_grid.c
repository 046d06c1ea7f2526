/* The frequencies at which responses are compared. */
#include <kryflex_impl.h>

static int CompareReal(const void *x, const void *y)
{
  const PetscReal a = *(const PetscReal *)x, b = *(const PetscReal *)y;
  return a < b ? -1 : (a > b ? 1 : 0);
}

/*
  KFFrequencyGrid - npoints log-spaced points over [fmin, fmax] (numpy.geomspace: 10^(log10 fmin + i step), ends
  exact), plus fr (1 + zeta {-2, -1, -1/2, 0, 1/2, 1, 2}) for each resonance fr in the band (peaks are 1/zeta
  sharp), clipped to the band, sorted, exact duplicates removed. The former Python frequency_grid, value for value.
*/
PetscErrorCode KFFrequencyGrid(PetscReal fmin, PetscReal fmax, PetscInt npoints, PetscInt nres, const PetscReal fres[], PetscReal zeta, PetscInt *nf, PetscReal f[])
{
  static const PetscReal offsets[7] = {-2, -1, -0.5, 0, 0.5, 1, 2};
  PetscInt               n          = 0;

  PetscFunctionBegin;
  PetscValidIntPointer(nf, 7);
  PetscCheck(fmin > 0 && fmax >= fmin && !PetscIsInfOrNanReal(fmax), PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFFrequencyGrid: the band [%g, %g] Hz must satisfy 0 < fmin <= fmax < inf", (double)fmin, (double)fmax);
  PetscCheck(npoints >= 0 && nres >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFFrequencyGrid: negative count (points %" PetscInt_FMT ", resonances %" PetscInt_FMT ")", npoints, nres);
  PetscCheck(zeta >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFFrequencyGrid: negative damping ratio %g", (double)zeta);
  if (npoints > 0) {
    /* numpy.linspace on the logarithms, then 10^y: y_i = i * step + start in two roundings, as NumPy does */
    const PetscReal lstart = log10(fmin), lstop = log10(fmax), delta = lstop - lstart;
    const PetscInt  div    = npoints - 1;
    for (PetscInt i = 0; i < npoints; i++) {
      PetscReal y;
      if (div > 0) {
        const PetscReal step = delta / div;
        if (step == 0) {
          y = (PetscReal)i / div;
          y = y * delta;
        } else y = (PetscReal)i * step;
      } else y = (PetscReal)i * delta;
      y    = y + lstart;
      f[n++] = pow(10.0, y);
    }
    if (div > 0) f[npoints - 1] = fmax;
    f[0] = fmin;
  }
  for (PetscInt r = 0; r < nres; r++) {
    if (!(fmin <= fres[r] && fres[r] <= fmax)) continue;
    for (int k = 0; k < 7; k++) f[n++] = fres[r] * (1 + zeta * offsets[k]);
  }
  for (PetscInt i = 0; i < n; i++) f[i] = PetscMin(PetscMax(f[i], fmin), fmax);
  qsort(f, (size_t)n, sizeof(PetscReal), CompareReal);
  {
    PetscInt u = 0;
    for (PetscInt i = 0; i < n; i++)
      if (!u || f[i] != f[u - 1]) f[u++] = f[i];
    n = u;
  }
  *nf = n;
  PetscFunctionReturn(0);
}
