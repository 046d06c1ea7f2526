/* Modal frequency response with uniform modal damping; rigid and mechanism modes are undamped. */
#include "dense_impl.h"

PetscErrorCode KFModalFRF(PetscInt nmodes, const PetscReal lambda[], PetscInt t, const PetscReal HPhi[], PetscInt a, const PetscReal PhiG[], PetscReal zeta, PetscReal rigid_tol, PetscInt nw, const PetscReal w[], PetscReal Tre[], PetscReal Tim[])
{
  PetscReal *Sre, *Sim, lmax;

  PetscFunctionBegin;
  PetscCheck(nmodes >= 0 && t >= 0 && a >= 0 && nw >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFModalFRF: negative size (nmodes %" PetscInt_FMT ", t %" PetscInt_FMT ", a %" PetscInt_FMT ", nw %" PetscInt_FMT ")", nmodes, t, a, nw);
  PetscCheck(zeta >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFModalFRF: negative damping ratio %g", (double)zeta);
  PetscCheck(rigid_tol >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFModalFRF: negative rigid tolerance %g", (double)rigid_tol);
  if (!t || !a || !nw) PetscFunctionReturn(0);
  PetscCall(PetscArrayzero(Tre, nw * t * a));
  PetscCall(PetscArrayzero(Tim, nw * t * a));
  if (!nmodes) PetscFunctionReturn(0);
  lmax = KFDenseMaxReal_Private(nmodes, lambda);
  PetscCall(PetscMalloc2(nmodes * a, &Sre, nmodes * a, &Sim));
  for (PetscInt f = 0; f < nw; f++) {
    const PetscReal w2 = w[f] * w[f];

    /* row i of PhiG scaled by the real and imaginary parts of the modal receptance */
    for (PetscInt i = 0; i < nmodes; i++) {
      PetscReal x, y, d2, cre, cim;

      if (KFDenseIsFlexible_Private(lambda[i], lmax, rigid_tol)) {
        x = lambda[i] - w2;
        y = 2 * zeta * PetscSqrtReal(lambda[i]) * w[f];
      } else {
        x = -w2;
        y = 0;
      }
      d2 = x * x + y * y;
      PetscCheck(d2 > 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
                 "KFModalFRF: the response of mode %" PetscInt_FMT " (lambda %g%s) is infinite at w[%" PetscInt_FMT "] = %g rad/s: %s", i, (double)lambda[i],
                 KFDenseIsFlexible_Private(lambda[i], lmax, rigid_tol) ? "" : ", rigid", f, (double)w[f],
                 KFDenseIsFlexible_Private(lambda[i], lmax, rigid_tol) ? "give a positive damping ratio or avoid the exact resonance" : "rigid modes have no static response; start the band above 0");
      cre = x / d2;
      cim = -y / d2;
      for (PetscInt j = 0; j < a; j++) {
        Sre[i + j * nmodes] = cre * PhiG[i + j * nmodes];
        Sim[i + j * nmodes] = cim * PhiG[i + j * nmodes];
      }
    }
    PetscCall(KFDenseGemm_Private('N', 'N', t, a, nmodes, 1.0, HPhi, t, Sre, nmodes, 0.0, Tre + f * t * a, t));
    PetscCall(KFDenseGemm_Private('N', 'N', t, a, nmodes, 1.0, HPhi, t, Sim, nmodes, 0.0, Tim + f * t * a, t));
  }
  PetscCall(PetscFree2(Sre, Sim));
  PetscFunctionReturn(0);
}
