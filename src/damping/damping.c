/* The damping description shared by the full-order reference and the reduced model: modal ratios (uniform or per
   band), Rayleigh, structural; checks with actionable messages; one equivalent ratio for the stages that need one. */
#include <kryflex/reducerimpl.h>

const char *const KFQuantities[] = {"displacement", "velocity", "acceleration", "KFQuantity", "KF_QUANTITY_", NULL};

PetscErrorCode KFDampingSetUniform(KFDamping *d, PetscReal zeta)
{
  PetscFunctionBegin;
  PetscCall(PetscMemzero(d, sizeof(*d)));
  d->nbands     = 1;
  d->fmax_hz[0] = PETSC_INFINITY;
  d->zeta[0]    = zeta;
  PetscFunctionReturn(0);
}

PetscErrorCode KFDampingCheck(MPI_Comm comm, const KFDamping *d)
{
  PetscFunctionBegin;
  PetscCheck(d->nbands >= 0 && d->nbands <= KF_MAX_DAMPING_BANDS, comm, PETSC_ERR_ARG_OUTOFRANGE, "damping: %" PetscInt_FMT " modal damping bands; give 0 to %d ([[f_max_hz, zeta], ...] or -kf_damping_bands)", d->nbands, KF_MAX_DAMPING_BANDS);
  for (PetscInt k = 0; k < d->nbands; k++) {
    PetscCheck(d->zeta[k] >= 0 && d->zeta[k] < 1, comm, PETSC_ERR_ARG_OUTOFRANGE, "damping: modal damping ratio %g%s; a ratio must lie in [0, 1) (damping.modal)", (double)d->zeta[k], d->nbands > 1 ? " in a band" : "");
    PetscCheck(d->fmax_hz[k] > 0 && !PetscIsNanReal(d->fmax_hz[k]), comm, PETSC_ERR_ARG_OUTOFRANGE, "damping: modal band %" PetscInt_FMT " ends at %g Hz; give a positive upper frequency f_max_hz (damping.modal: [[f_max_hz, zeta], ...])", k, (double)d->fmax_hz[k]);
    PetscCheck(!k || d->fmax_hz[k] > d->fmax_hz[k - 1], comm, PETSC_ERR_ARG_WRONG, "damping: the modal bands must be in ascending f_max_hz, got %g Hz after %g Hz (damping.modal: [[f_max_hz, zeta], ...])", (double)d->fmax_hz[k], (double)d->fmax_hz[k - 1]);
  }
  PetscCheck(d->alpha >= 0 && !PetscIsInfOrNanReal(d->alpha), comm, PETSC_ERR_ARG_OUTOFRANGE, "damping: Rayleigh alpha %g (1/s); give alpha >= 0 (damping.rayleigh.alpha, -kf_damping_rayleigh alpha,beta)", (double)d->alpha);
  PetscCheck(d->beta >= 0 && !PetscIsInfOrNanReal(d->beta), comm, PETSC_ERR_ARG_OUTOFRANGE, "damping: Rayleigh beta %g (s); give beta >= 0 (damping.rayleigh.beta, -kf_damping_rayleigh alpha,beta)", (double)d->beta);
  PetscCheck(d->g >= 0 && d->g < 1, comm, PETSC_ERR_ARG_OUTOFRANGE, "damping: structural damping g = %g; give 0 <= g < 1 (damping.structural, -kf_damping_structural)", (double)d->g);
  PetscFunctionReturn(0);
}

PetscReal KFDampingModalRatio(const KFDamping *d, PetscReal f_hz)
{
  if (!d->nbands) return 0;
  for (PetscInt k = 0; k < d->nbands; k++)
    if (f_hz <= d->fmax_hz[k]) return d->zeta[k];
  return d->zeta[d->nbands - 1];
}

/* the ratio of a mode at f_hz: modal + Rayleigh (alpha / (2 w) + beta w / 2) + structural (g / 2 near resonance) */
static PetscReal KFDampingRatioAt(const KFDamping *d, PetscReal f_hz)
{
  const PetscReal w = 2 * PETSC_PI * f_hz;
  return KFDampingModalRatio(d, f_hz) + d->alpha / (2 * w) + d->beta * w / 2 + d->g / 2;
}

PetscErrorCode KFDampingEffectiveRatio(const KFDamping *d, const PetscReal band[2], PetscReal *zeta)
{
  PetscReal z = PetscMin(KFDampingRatioAt(d, band[0]), KFDampingRatioAt(d, band[1]));

  PetscFunctionBegin;
  for (PetscInt k = 0; k < d->nbands; k++)
    if (d->fmax_hz[k] > band[0] && d->fmax_hz[k] < band[1]) z = PetscMin(z, KFDampingRatioAt(d, d->fmax_hz[k]));
  /* Rayleigh's ratio is smallest at w = sqrt(alpha / beta) */
  if (d->alpha > 0 && d->beta > 0) {
    const PetscReal f = PetscSqrtReal(d->alpha / d->beta) / (2 * PETSC_PI);
    if (f > band[0] && f < band[1]) z = PetscMin(z, KFDampingRatioAt(d, f));
  }
  *zeta = PetscMin(PetscMax(z, 1e-4), 0.99);
  PetscFunctionReturn(0);
}

/* JSON text of the damping, as the scene file writes it: {"modal": zeta or [[f_max_hz, zeta], ...], "rayleigh":
   {"alpha": a, "beta": b}, "structural": g} */
PetscErrorCode KFDampingDescribe_Private(const KFDamping *d, char buf[], size_t len)
{
  size_t used;

  PetscFunctionBegin;
  if (d->nbands == 1 && d->fmax_hz[0] >= PETSC_INFINITY) PetscCall(PetscSNPrintf(buf, len, "{\"modal\": %.17g", (double)d->zeta[0]));
  else {
    PetscCall(PetscStrncpy(buf, "{\"modal\": [", len));
    for (PetscInt k = 0; k < d->nbands; k++) {
      PetscCall(PetscStrlen(buf, &used));
      PetscCall(PetscSNPrintf(buf + used, len - used, "%s[%.17g, %.17g]", k ? ", " : "", d->fmax_hz[k] >= PETSC_INFINITY ? 1e300 : (double)d->fmax_hz[k], (double)d->zeta[k]));
    }
    PetscCall(PetscStrlcat(buf, "]", len));
  }
  PetscCall(PetscStrlen(buf, &used));
  PetscCall(PetscSNPrintf(buf + used, len - used, ", \"rayleigh\": {\"alpha\": %.17g, \"beta\": %.17g}, \"structural\": %.17g}", (double)d->alpha, (double)d->beta, (double)d->g));
  PetscFunctionReturn(0);
}
