/* The damped frequency response in undamped modal coordinates: modal, Rayleigh and structural damping are diagonal
   there; a viscous matrix (Phi^T C Phi) couples the modes, solved at each frequency in the real 2 x 2 block form of
   the complex system (PETSc and its LAPACK here are real): [A -B; B A] [xr; xi] = [br; bi]. */
#include <kryflex.h>
#include <petscblaslapack.h>

PetscErrorCode KFDampedModalFRF(PetscInt n, const PetscReal lambda[], PetscInt t, const PetscReal HPhi[], PetscInt a, const PetscReal PhiG[], const KFDamping *d, const PetscReal Cm[], PetscInt nc, const PetscInt quantity[], PetscReal rigid_tol, PetscInt nw, const PetscReal w[], PetscReal Tre[], PetscReal Tim[])
{
  PetscReal   *lam, *glam, *dw, *dre, *dim, *Xre, *Xim, *S = NULL, *rhs = NULL, lmax = 0;
  PetscBLASInt *ipiv = NULL;

  PetscFunctionBegin;
  PetscCheck(n >= 0 && t >= 0 && a >= 0 && nw >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFDampedModalFRF: negative size (n %" PetscInt_FMT ", t %" PetscInt_FMT ", a %" PetscInt_FMT ", nw %" PetscInt_FMT ")", n, t, a, nw);
  PetscCall(KFDampingCheck(PETSC_COMM_SELF, d));
  if (!Cm) nc = 0;
  PetscCheck(nc >= 0 && nc <= n, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFDampedModalFRF: %" PetscInt_FMT " coupled modes of %" PetscInt_FMT, nc, n);
  if (!t || !a || !nw) PetscFunctionReturn(0);
  PetscCall(PetscArrayzero(Tre, nw * t * a));
  PetscCall(PetscArrayzero(Tim, nw * t * a));
  if (!n) PetscFunctionReturn(0);
  for (PetscInt i = 0; i < n; i++) lmax = PetscMax(lmax, lambda[i]);
  PetscCall(PetscMalloc7(n, &lam, n, &glam, n, &dw, n, &dre, n, &dim, n * a, &Xre, n * a, &Xim));
  /* the diagonal of Z in the modes: real part lambda - w^2, imaginary part g lambda + w (2 zeta sqrt(lambda) + alpha +
     beta lambda + Cm_kk); its parts that do not depend on w made once (per frequency they cost more than the rest) */
  for (PetscInt k = 0; k < n; k++) {
    PetscReal z;

    lam[k]  = (lambda[k] > 0 && lambda[k] > rigid_tol * lmax) ? lambda[k] : 0;
    z       = lam[k] > 0 ? KFDampingModalRatio(d, PetscSqrtReal(lam[k]) / (2 * PETSC_PI)) : 0;
    glam[k] = d->g * lam[k];
    dw[k]   = 2 * z * PetscSqrtReal(lam[k]) + d->alpha + d->beta * lam[k] + (Cm ? Cm[k + k * n] : 0);
  }
  if (nc) PetscCall(PetscMalloc3(4 * nc * nc, &S, 2 * nc * a, &rhs, 2 * nc, &ipiv));
  for (PetscInt f = 0; f < nw; f++) {
    const PetscReal wf = w[f], w2 = wf * wf;

    for (PetscInt k = 0; k < n; k++) {
      dre[k] = lam[k] - w2;
      dim[k] = glam[k] + wf * dw[k];
    }
    /* uncoupled modes: X = PhiG / Z_kk */
    for (PetscInt k = nc; k < n; k++) {
      const PetscReal d2 = dre[k] * dre[k] + dim[k] * dim[k];
      PetscReal       cr, ci;

      PetscCheck(d2 > 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFDampedModalFRF: the response of mode %" PetscInt_FMT " (lambda %g) is infinite at w[%" PetscInt_FMT "] = %g rad/s: %s", k, (double)lambda[k], f, (double)wf,
                 lam[k] > 0 ? "give it some damping or avoid the exact resonance" : "rigid modes have no static response; start the band above 0");
      cr = dre[k] / d2;
      ci = -dim[k] / d2;
      for (PetscInt j = 0; j < a; j++) {
        Xre[k + j * n] = cr * PhiG[k + j * n];
        Xim[k + j * n] = ci * PhiG[k + j * n];
      }
    }
    if (nc) { /* coupled modes: [A -B; B A] [xr; xi] = [PhiG; 0], A = diag(dre), B = diag(dim) + w offdiag(Cm) */
      const PetscInt m = 2 * nc;
      PetscBLASInt   bm, bn, info;

      PetscCall(PetscArrayzero(S, m * m));
      for (PetscInt c = 0; c < nc; c++)
        for (PetscInt r = 0; r < nc; r++) {
          const PetscReal A = r == c ? dre[r] : 0, B = r == c ? dim[r] : wf * Cm[r + c * n];
          S[r + c * m]             = A;
          S[(r + nc) + (c + nc) * m] = A;
          S[r + (c + nc) * m]      = -B;
          S[(r + nc) + c * m]      = B;
        }
      for (PetscInt j = 0; j < a; j++)
        for (PetscInt r = 0; r < nc; r++) {
          rhs[r + j * m]      = PhiG[r + j * n];
          rhs[r + nc + j * m] = 0;
        }
      PetscCall(PetscBLASIntCast(m, &bm));
      PetscCall(PetscBLASIntCast(a, &bn));
      PetscCallBLAS("LAPACKgesv", LAPACKgesv_(&bm, &bn, S, &bm, ipiv, rhs, &bm, &info));
      PetscCheck(info == 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFDampedModalFRF: the damped dynamic stiffness is singular at w[%" PetscInt_FMT "] = %g rad/s (LAPACK gesv info %d): an undamped resonance, or a rigid mode at w = 0", f, (double)wf, (int)info);
      for (PetscInt j = 0; j < a; j++)
        for (PetscInt r = 0; r < nc; r++) {
          Xre[r + j * n] = rhs[r + j * m];
          Xim[r + j * n] = rhs[r + nc + j * m];
        }
    }
    {
      PetscReal *Re = Tre + f * t * a, *Im = Tim + f * t * a;
      PetscBLASInt bt, ba, bn, one_i;
      PetscReal    one = 1, zero = 0;

      PetscCall(PetscBLASIntCast(t, &bt));
      PetscCall(PetscBLASIntCast(a, &ba));
      PetscCall(PetscBLASIntCast(n, &bn));
      one_i = bt;
      PetscCallBLAS("BLASgemm", BLASgemm_("N", "N", &bt, &ba, &bn, &one, HPhi, &one_i, Xre, &bn, &zero, Re, &bt));
      PetscCallBLAS("BLASgemm", BLASgemm_("N", "N", &bt, &ba, &bn, &one, HPhi, &one_i, Xim, &bn, &zero, Im, &bt));
      /* velocity: i w x; acceleration: -w^2 x */
      for (PetscInt i = 0; quantity && i < t; i++) {
        if (quantity[i] == KF_QUANTITY_VELOCITY)
          for (PetscInt j = 0; j < a; j++) {
            const PetscReal xr = Re[i + j * t], xi = Im[i + j * t];
            Re[i + j * t] = -wf * xi;
            Im[i + j * t] = wf * xr;
          }
        else if (quantity[i] == KF_QUANTITY_ACCELERATION)
          for (PetscInt j = 0; j < a; j++) {
            Re[i + j * t] *= -w2;
            Im[i + j * t] *= -w2;
          }
      }
    }
  }
  PetscCall(PetscFree7(lam, glam, dw, dre, dim, Xre, Xim));
  if (nc) PetscCall(PetscFree3(S, rhs, ipiv));
  PetscFunctionReturn(0);
}
