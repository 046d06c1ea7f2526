/* Moment error measures: normwise errors per moment and entrywise ratios, one definition everywhere. */
#include <kryflex_impl.h>

/*
  KFMomentErrors - errors[k] = ||L_full^k - L_red^k||_F / ||L_full^k||_F, NaN where the whole full moment is
  negligible (||L_full^k||_F <= negligible * max over the nconfig configurations of ||L^k||_F); for one input and one
  output it is |L_full/L_red - 1| to second order, and for blocks it does not let an entry that is small by geometry
  (and so carries the solves' rounding) dominate. ratios[k*t*a + j*t + i] = L_full / L_red entrywise, NaN where the
  entry is negligible (|L_full| <= negligible * max over configurations of |L|) or L_red = 0.
  Lall: nconfig blocks of nmom x t x a (layout of KFFlexSolverMoments); the full moments are block config.
  errors (nmom) or ratios (nmom t a) may be NULL. The former Python moment_errors and _ratios, None -> NaN.
*/
PetscErrorCode KFMomentErrors(PetscInt nmom, PetscInt t, PetscInt a, PetscInt nconfig, const PetscReal Lall[], PetscInt config, const PetscReal Lred[], PetscReal negligible, PetscReal errors[], PetscReal ratios[])
{
  const PetscInt   m = t * a, blk = nmom * t * a;
  const PetscReal *Lf;

  PetscFunctionBegin;
  PetscCheck(nmom >= 0 && t >= 0 && a >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFMomentErrors: negative size (nmom %" PetscInt_FMT ", t %" PetscInt_FMT ", a %" PetscInt_FMT ")", nmom, t, a);
  PetscCheck(config >= 0 && config < nconfig, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFMomentErrors: configuration %" PetscInt_FMT " is not among the %" PetscInt_FMT " given", config, nconfig);
  PetscCheck(negligible >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFMomentErrors: negative threshold %g for negligible moments", (double)negligible);
  Lf = Lall + config * blk;
  for (PetscInt k = 0; k < nmom; k++) {
    if (errors) {
      PetscReal scale = 0, nf = 0, nd = 0;
      for (PetscInt c = 0; c < nconfig; c++) {
        PetscReal s = 0;
        for (PetscInt e = 0; e < m; e++) s += Lall[c * blk + k * m + e] * Lall[c * blk + k * m + e];
        scale = PetscMax(scale, PetscSqrtReal(s));
      }
      for (PetscInt e = 0; e < m; e++) {
        const PetscReal d = Lf[k * m + e] - Lred[k * m + e];
        nf += Lf[k * m + e] * Lf[k * m + e];
        nd += d * d;
      }
      nf        = PetscSqrtReal(nf);
      errors[k] = nf <= negligible * scale ? (PetscReal)NAN : PetscSqrtReal(nd) / nf;
    }
    if (ratios) {
      for (PetscInt e = 0; e < m; e++) {
        PetscReal scale = 0;
        for (PetscInt c = 0; c < nconfig; c++) scale = PetscMax(scale, PetscAbsReal(Lall[c * blk + k * m + e]));
        ratios[k * m + e] = (PetscAbsReal(Lf[k * m + e]) <= negligible * scale || Lred[k * m + e] == 0) ? (PetscReal)NAN : Lf[k * m + e] / Lred[k * m + e];
      }
    }
  }
  PetscFunctionReturn(0);
}
