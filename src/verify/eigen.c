#include <kryflex_impl.h>
#include <slepceps.h>
#include <slepc/private/epsimpl.h> /* the Ritz values at a stopping test: SLEPc passes the test only their count */
#include "../dense/dense_impl.h"
#include <kryflex/flexsolverimpl.h> /* the solver's refinement steps, off for the unsampled applications */
#include <petscblaslapack.h>
#include "eigen_impl.h"

/* replicated column-major copy of any small parallel matrix */
static PetscErrorCode KFGatherAny(Mat A, PetscReal out[])
{
  Mat D;

  PetscFunctionBegin;
  PetscCall(MatConvert(A, MATDENSE, MAT_INITIAL_MATRIX, &D));
  PetscCall(KFDenseGather(D, out));
  PetscCall(MatDestroy(&D));
  PetscFunctionReturn(0);
}

/* The eigendecomposition M = U diag(mu) U^T of a replicated n x n M (U overwrites a copy of M): the null directions
   are the nz first columns of U, LAPACK ordering the eigenvalues ascending. A direction u is null when its mass is
   rounding: below KF_MASS_NULL_RTOL of the masses its own dofs carry, sum_k u_k^2 M_kk (an export rounds each entry
   relative to itself, so a cancellation such as an offset lumped mass's rank-1 block leaves that fraction of its
   diagonal), or below the eigensolver's own rounding, n eps max mu. Not against the largest mass alone: a light
   body (a rotor 1e-6 of the stator's mass) has masses 1e-9 of the largest that are its own, not rounding, and
   condensing them statically drops its dynamics (and the elastic response its modes carry). */
static PetscErrorCode KFMassEig(PetscInt n, const PetscReal M[], PetscReal U[], PetscReal mu[], PetscInt *nz)
{
  PetscBLASInt bn, lwork, info;
  PetscReal   *work, top;

  PetscFunctionBegin;
  PetscCall(PetscBLASIntCast(n, &bn));
  PetscCall(PetscArraycpy(U, M, n * n));
  PetscCall(KFDenseSymmetrize_Private(n, U));
  lwork = PetscMax(3 * bn, 1) * 8;
  PetscCall(PetscMalloc1(lwork, &work));
  PetscCallBLAS("LAPACKsyev", LAPACKsyev_("V", "L", &bn, U, &bn, mu, work, &lwork, &info));
  PetscCall(PetscFree(work));
  PetscCheck(!info, PETSC_COMM_SELF, PETSC_ERR_LIB, "the full-order system's mass matrix M_S: the symmetric eigensolver did not converge (LAPACK syev info %d); check M for huge or tiny entries", (int)info);
  top = n ? PetscMax(PetscAbsReal(mu[n - 1]), PetscAbsReal(mu[0])) : 0;
  PetscCheck(!n || mu[0] >= -1e-6 * top, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG, "the full-order system's mass matrix M_S is indefinite (eigenvalue %g against a largest %g): a mass matrix must be positive semi-definite; check the bodies' mass matrices (signs, units, a stiffness given as mass)", (double)mu[0], (double)top);
  *nz = 0;
  while (*nz < n) {
    const PetscReal *u = &U[*nz * n];
    PetscReal        own = 0;

    for (PetscInt k = 0; k < n; k++) own += u[k] * u[k] * PetscAbsReal(M[k + k * n]);
    if (!(mu[*nz] <= PetscMax(KF_MASS_NULL_RTOL * own, n * PETSC_MACHINE_EPSILON * top))) break;
    (*nz)++;
  }
  PetscFunctionReturn(0);
}

/* The dimension of the null space of the full-order mass M_S (dense: its eigenvalues; sparse: MUMPS null pivots of M_S
   with a relative threshold) and how many of its dofs have a zero row (massless dofs) */
PETSC_INTERN PetscErrorCode KFSystemMassNullity(KFSystem sys, PetscBool dense, PetscInt *nnull, PetscInt *nzero)
{
  KFScene s = sys->scene;

  PetscFunctionBegin;
  PetscCall(KFSystemMasslessCount(sys, nzero));
  if (dense) {
    PetscInt   n = s->nsys;
    PetscReal *M, *U, *mu;

    PetscCall(PetscMalloc3(n * n, &M, n * n, &U, n, &mu));
    PetscCall(KFGatherAny(sys->Ms, M));
    PetscCall(KFMassEig(n, M, U, mu, nnull));
    PetscCall(PetscFree3(M, U, mu));
  } else PetscCall(KFSystemMassNullPivots(sys, nnull));
  PetscFunctionReturn(0);
}

/* The static response of M_S's null space Z: D = H Z K_zz^-1 Z^T G (t x a, column-major), replicated. A load on the
   null space moves it at every frequency without inertia; no mode carries that, so the modal reference adds it. */
PETSC_INTERN PetscErrorCode KFSystemMassNullStatic(KFSystem sys, PetscReal D[])
{
  KFScene      s = sys->scene;
  PetscInt     n = s->nsys, a = s->ninputs, t = s->noutputs, nz;
  PetscReal   *K, *M, *G, *Ht, *U, *mu, *Kzz, *Zg, *Zh;
  PetscBLASInt bz, ba, info;

  PetscFunctionBegin;
  PetscCall(PetscMalloc4(n * n, &K, n * n, &M, n * a, &G, n * t, &Ht));
  PetscCall(PetscMalloc2(n * n, &U, n, &mu));
  PetscCall(KFGatherAny(sys->Ks, K));
  PetscCall(KFGatherAny(sys->Ms, M));
  PetscCall(KFDenseGather(sys->G, G));
  PetscCall(KFDenseGather(sys->Ht, Ht));
  PetscCall(KFMassEig(n, M, U, mu, &nz));
  PetscCall(PetscArrayzero(D, t * a));
  if (nz) {
    PetscReal *KZ;

    PetscCall(PetscMalloc4(nz * nz, &Kzz, nz * a, &Zg, nz * t, &Zh, n * nz, &KZ));
    for (PetscInt j = 0; j < nz; j++) /* K Z, then K_zz = Z^T (K Z) */
      for (PetscInt k = 0; k < n; k++) {
        PetscReal d = 0;
        for (PetscInt l = 0; l < n; l++) d += K[k + l * n] * U[l + j * n];
        KZ[k + j * n] = d;
      }
    for (PetscInt j = 0; j < nz; j++)
      for (PetscInt i = 0; i <= j; i++) {
        PetscReal d = 0;
        for (PetscInt k = 0; k < n; k++) d += U[k + i * n] * KZ[k + j * n];
        Kzz[i + j * nz] = Kzz[j + i * nz] = d;
      }
    for (PetscInt q = 0; q < a; q++)
      for (PetscInt i = 0; i < nz; i++) {
        PetscReal d = 0;
        for (PetscInt k = 0; k < n; k++) d += U[k + i * n] * G[k + q * n];
        Zg[i + q * nz] = d;
      }
    for (PetscInt q = 0; q < t; q++)
      for (PetscInt i = 0; i < nz; i++) {
        PetscReal d = 0;
        for (PetscInt k = 0; k < n; k++) d += U[k + i * n] * Ht[k + q * n];
        Zh[i + q * nz] = d;
      }
    PetscCall(PetscBLASIntCast(nz, &bz));
    PetscCall(PetscBLASIntCast(a, &ba));
    PetscCallBLAS("LAPACKpotrf", LAPACKpotrf_("L", &bz, Kzz, &bz, &info));
    PetscCheck(!info, s->comm, PETSC_ERR_ARG_WRONG, "the full-order system's mass matrix M_S has a null space of dimension %" PetscInt_FMT " on which its stiffness K_S is singular (leading minor %d): a combination of dofs without inertia can move freely, a mechanism without mass; clamp or connect it, or give it mass", nz, (int)info);
    PetscCallBLAS("LAPACKpotrs", LAPACKpotrs_("L", &bz, &ba, Kzz, &bz, Zg, &bz, &info)); /* K_zz^-1 Z^T G */
    for (PetscInt q = 0; q < a; q++)
      for (PetscInt p = 0; p < t; p++) {
        PetscReal d = 0;
        for (PetscInt i = 0; i < nz; i++) d += Zh[i + p * nz] * Zg[i + q * nz];
        D[p + q * t] = d;
      }
    PetscCall(PetscFree4(Kzz, Zg, Zh, KZ));
  }
  PetscCall(PetscFree4(K, M, G, Ht));
  PetscCall(PetscFree2(U, mu));
  PetscFunctionReturn(0);
}

/* The flexible modes of KFDenseEigRigid (M definite) refined to each eigenvalue's own accuracy: a Householder
   eigensolve knows every eigenvalue to eps lam_max only, and the softest flexible modes of a stiff structure are
   below that (Galileo: lam_1 = 3e-9 lam_max, its first eigenvalue 2e-8 off, and off differently with the system's
   dofs numbered for 1 or 2 ranks, which moved a pair's reference by 4e-6 of its peak near that resonance). The
   computed modes X span the rigid modes' M-complement exactly (to rounding), so the Rayleigh-Ritz pencil
   (X^T K X, X^T M X) on them has the flexible eigenvalues exactly: X is M-orthonormalized again, K X formed in
   double-double, X^T K X taken from its lower triangle (x_i^T (K x_j), K on the softer mode: each entry to eps of
   the softer mode's stiffness) and solved by Cholesky and one-sided Jacobi (LAPACK gesvj, KFDenseEigJacobi_Private),
   which keeps each eigenvalue of that nearly diagonal matrix to a few eps of itself. lam, V: KFDenseEigRigid's (n x n, the r rigid modes first), the flexible ones replaced. */
static PetscErrorCode KFSystemEigenRefine(KFSystem sys, const PetscReal M[], PetscInt r, PetscReal lam[], PetscReal V[])
{
  KFScene      s = sys->scene;
  PetscInt     n = s->nsys, m = n - r, ld;
  PetscReal   *X = V + n * r, *MX, *B, *A, *W, *Y, *lf;
  PetscScalar *x;
  PetscBLASInt bm, info;
  Mat          Xd, Yd;

  PetscFunctionBegin;
  if (m <= 0) PetscFunctionReturn(0);
  PetscCall(PetscMalloc5(n * m, &MX, m * m, &B, m * m, &A, m * m, &W, m, &lf));
  PetscCall(PetscMalloc1(n * m, &Y));
  /* X <- X L^-T with X^T M X = L L^T */
  PetscCall(KFDenseGemm_Private('N', 'N', n, m, n, 1.0, M, n, X, n, 0.0, MX, n));
  PetscCall(KFDenseGemm_Private('T', 'N', m, m, n, 1.0, X, n, MX, n, 0.0, B, m));
  PetscCall(PetscBLASIntCast(m, &bm));
  PetscCallBLAS("LAPACKpotrf", LAPACKpotrf_("L", &bm, B, &bm, &info));
  PetscCheck(!info, s->comm, PETSC_ERR_LIB, "the verification's flexible modes are not M-independent (leading minor %d of their M-Gram matrix)", (int)info);
  {
    const PetscScalar one = 1.0;
    PetscBLASInt      bn;

    PetscCall(PetscBLASIntCast(n, &bn));
    PetscCallBLAS("BLAStrsm", BLAStrsm_("R", "L", "T", "N", &bn, &bm, &one, B, &bm, X, &bn));
  }
  /* K X in double-double, on the distributed K_S */
  PetscCall(KFDenseCreate(s->comm, s->nsys_local, n, m, &Xd));
  PetscCall(MatDenseGetLDA(Xd, &ld));
  PetscCall(MatDenseGetArrayWrite(Xd, &x));
  for (PetscInt j = 0; j < m; j++)
    for (PetscInt i = 0; i < s->nsys_local; i++) x[i + j * ld] = X[s->sys_rstart + i + j * n];
  PetscCall(MatDenseRestoreArrayWrite(Xd, &x));
  PetscCall(KFMatMultExtended(sys->Ks, Xd, &Yd));
  PetscCall(KFDenseGather(Yd, Y));
  PetscCall(MatDestroy(&Xd));
  PetscCall(MatDestroy(&Yd));
  PetscCall(KFDenseGemm_Private('T', 'N', m, m, n, 1.0, X, n, Y, n, 0.0, A, m));
  for (PetscInt j = 0; j < m; j++)
    for (PetscInt i = j + 1; i < m; i++) A[j + i * m] = A[i + j * m];
  PetscCall(KFDenseEigJacobi_Private(m, A, lf, W));
  PetscCall(KFDenseGemm_Private('N', 'N', n, m, m, 1.0, X, n, W, m, 0.0, Y, n));
  PetscCall(PetscArraycpy(X, Y, n * m));
  PetscCall(PetscArraycpy(lam + r, lf, m));
  PetscCall(PetscFree5(MX, B, A, W, lf));
  PetscCall(PetscFree(Y));
  PetscFunctionReturn(0);
}

/* The dense verification of a system whose mass is singular: M = U diag(mu) U^T splits the dofs into M's range Y
   (mu > 0) and null space Z, x = Y y + Z z. The null coordinates carry no inertia, so their rows of K x = lambda M x
   say K_zy y + K_zz z = 0: they are condensed statically (K_c = K_yy - K_yz K_zz^-1 K_zy, M_c = diag(mu) positive
   definite), the pencil solved with the rigid modes known (KFDenseEigRigid; y = Y^T phi_r), and each mode expanded
   by z = -K_zz^-1 K_zy y. This takes M's whole null space, not only its zero rows: a lumped mass offset from its node
   gives a rank-1 block with a full diagonal, singular beyond any zero diagonal. With M definite (nz = 0) it is the
   pencil itself with the rigid modes known, its flexible eigenvalues refined (KFSystemEigenRefine). */
static PetscErrorCode KFSystemEigenCondensed(KFSystem sys, PetscBool definite, PetscInt nev, PetscInt *nconv, PetscReal omega2[], PetscReal HPhi[], PetscReal PhiG[], Mat *modes)
{
  KFScene      s = sys->scene;
  PetscInt     n = s->nsys, a = s->ninputs, t = s->noutputs, r = sys->nrigid, nz, ny, got;
  PetscReal   *K, *M, *G, *Ht, *Phr, *U, *mu, *KU, *Kt, *Kzz, *X, *Kc, *Mc, *Pm, *lam, *V, *x, *zc;
  PetscBLASInt bz, by, info;

  PetscFunctionBegin;
  PetscCall(PetscMalloc4(n * n, &K, n * n, &M, n * a, &G, n * t, &Ht));
  PetscCall(PetscMalloc1(n * PetscMax(r, 1), &Phr));
  PetscCall(KFGatherAny(sys->Ks, K));
  PetscCall(KFGatherAny(sys->Ms, M));
  PetscCall(KFDenseGather(sys->G, G));
  PetscCall(KFDenseGather(sys->Ht, Ht));
  if (r) PetscCall(KFDenseGather(sys->Phi, Phr));
  PetscCall(PetscMalloc4(n * n, &U, n, &mu, n * n, &KU, n * n, &Kt));
  nz = 0; /* definite: the caller found M's null space empty (KFSystemMassNullity), no second eigensolve of M */
  if (!definite) PetscCall(KFMassEig(n, M, U, mu, &nz));
  ny = n - nz;
  if (!nz) { /* M definite: the pencil itself, no change of coordinates (U = I, y = x) */
    for (PetscInt k = 0; k < n * n; k++) U[k] = 0;
    for (PetscInt k = 0; k < n; k++) U[k + k * n] = 1;
  }
  /* Kt = U^T K U: the stiffness in (z, y) coordinates, z first */
  if (!nz) PetscCall(PetscArraycpy(Kt, K, n * n));
  else {
    for (PetscInt j = 0; j < n; j++)
      for (PetscInt i = 0; i < n; i++) {
        PetscReal d = 0;
        for (PetscInt k = 0; k < n; k++) d += K[i + k * n] * U[k + j * n];
        KU[i + j * n] = d;
      }
    for (PetscInt j = 0; j < n; j++)
      for (PetscInt i = 0; i < n; i++) {
        PetscReal d = 0;
        for (PetscInt k = 0; k < n; k++) d += U[k + i * n] * KU[k + j * n];
        Kt[i + j * n] = d;
      }
  }
  PetscCall(KFDenseSymmetrize_Private(n, Kt));
  PetscCall(PetscMalloc5(nz * nz + 1, &Kzz, nz * ny + 1, &X, ny * ny, &Kc, ny * ny, &Mc, ny * PetscMax(r, 1), &Pm));
  PetscCall(PetscMalloc4(ny, &lam, ny * ny, &V, n, &x, nz + 1, &zc));
  for (PetscInt j = 0; j < nz; j++)
    for (PetscInt i = 0; i < nz; i++) Kzz[i + j * nz] = Kt[i + j * n];
  for (PetscInt j = 0; j < ny; j++)
    for (PetscInt i = 0; i < nz; i++) X[i + j * nz] = Kt[i + (nz + j) * n];
  PetscCall(PetscBLASIntCast(nz, &bz));
  PetscCall(PetscBLASIntCast(ny, &by));
  if (nz) {
    PetscCallBLAS("LAPACKpotrf", LAPACKpotrf_("L", &bz, Kzz, &bz, &info));
    PetscCheck(!info, s->comm, PETSC_ERR_ARG_WRONG, "the full-order system's mass matrix M_S has a null space of dimension %" PetscInt_FMT " on which its stiffness K_S is singular (leading minor %d): a combination of dofs without inertia can move freely, a mechanism without mass; clamp or connect it, or give it mass", nz, (int)info);
    PetscCallBLAS("LAPACKpotrs", LAPACKpotrs_("L", &bz, &by, Kzz, &bz, X, &bz, &info)); /* X = K_zz^-1 K_zy */
  }
  for (PetscInt j = 0; j < ny; j++)
    for (PetscInt i = 0; i < ny; i++) {
      Kc[i + j * ny] = Kt[nz + i + (nz + j) * n];
      Mc[i + j * ny] = nz ? (i == j ? mu[nz + i] : 0) : M[i + j * n];
      for (PetscInt k = 0; k < nz; k++) Kc[i + j * ny] -= Kt[nz + i + k * n] * X[k + j * nz];
    }
  PetscCall(KFDenseSymmetrize_Private(ny, Kc));
  for (PetscInt j = 0; j < r; j++) /* y = Y^T phi_r */
    for (PetscInt i = 0; i < ny; i++) {
      PetscReal d = 0;
      for (PetscInt k = 0; k < n; k++) d += U[k + (nz + i) * n] * Phr[k + j * n];
      Pm[i + j * ny] = d;
    }
  PetscCall(KFDenseEigRigid(ny, Kc, Mc, r, Pm, lam, V));
  if (!nz) PetscCall(KFSystemEigenRefine(sys, M, r, lam, V));
  got = PetscMax(PetscMin(nev, ny - r), 0);
  if (modes) PetscCall(KFDenseCreate(s->comm, s->nsys_local, s->nsys, nev, modes));
  for (PetscInt k = 0; k < got; k++) {
    const PetscReal *v = V + (r + k) * ny;
    omega2[k] = lam[r + k];
    for (PetscInt i = 0; i < nz; i++) {
      zc[i] = 0;
      for (PetscInt j = 0; j < ny; j++) zc[i] -= X[i + j * nz] * v[j];
    }
    for (PetscInt i = 0; i < n && !nz; i++) x[i] = v[i];
    for (PetscInt i = 0; i < n && nz; i++) { /* x = Y y + Z z */
      PetscReal d = 0;
      for (PetscInt j = 0; j < ny; j++) d += U[i + (nz + j) * n] * v[j];
      for (PetscInt j = 0; j < nz; j++) d += U[i + j * n] * zc[j];
      x[i] = d;
    }
    if (HPhi)
      for (PetscInt q = 0; q < t; q++) {
        PetscReal d = 0;
        for (PetscInt i = 0; i < n; i++) d += Ht[i + q * n] * x[i];
        HPhi[q + k * t] = d;
      }
    if (PhiG)
      for (PetscInt q = 0; q < a; q++) {
        PetscReal d = 0;
        for (PetscInt i = 0; i < n; i++) d += G[i + q * n] * x[i];
        PhiG[k + q * nev] = d;
      }
    if (modes) {
      PetscScalar *c;
      PetscInt     ld;
      PetscCall(MatDenseGetLDA(*modes, &ld));
      PetscCall(MatDenseGetArray(*modes, &c));
      for (PetscInt i = 0; i < s->nsys_local; i++) c[i + k * ld] = x[s->sys_rstart + i];
      PetscCall(MatDenseRestoreArray(*modes, &c));
    }
  }
  *nconv = got;
  PetscCall(PetscFree4(K, M, G, Ht));
  PetscCall(PetscFree(Phr));
  PetscCall(PetscFree4(U, mu, KU, Kt));
  PetscCall(PetscFree5(Kzz, X, Kc, Mc, Pm));
  PetscCall(PetscFree4(lam, V, x, zc));
  PetscFunctionReturn(0);
}

/* -kf_verify_dense_max_dofs and -kf_verify_target (has_target: whether given), read and checked (also before any
   work: KFReducerSetFromOptions) */
PETSC_INTERN PetscErrorCode KFVerifyEigenOptions(MPI_Comm comm, PetscInt *dense_max, PetscReal *target, PetscBool *has_target)
{
  PetscFunctionBegin;
  *dense_max = 600;
  *target    = 0;
  PetscOptionsBegin(comm, NULL, "kryflex verification eigensolve (full order)", "KFSystemEigen");
  PetscCall(KFOptionsSettingInt(PetscOptionsObject, "-kf_verify_dense_max_dofs", *dense_max, dense_max, NULL));
  PetscCall(KFOptionsSettingReal(PetscOptionsObject, "-kf_verify_target", *target, target, has_target));
  PetscOptionsEnd();
  PetscFunctionReturn(0);
}

/* Small systems are solved densely: every mode at once, as cheap as a few */
PetscErrorCode KFSystemEigenIsDense(KFSystem sys, PetscBool *dense)
{
  KFScene   s = sys->scene;
  PetscInt  dense_max;
  PetscReal target;
  PetscBool has_target;

  PetscFunctionBegin;
  PetscCall(KFVerifyEigenOptions(s->comm, &dense_max, &target, &has_target));
  *dense = (PetscBool)(s->nsys <= dense_max);
  PetscFunctionReturn(0);
}

/* Krylov-Schur for the nev eigenvalues nearest target by shift-and-invert with a direct solve: the PC to set */
static PetscErrorCode KFEPSShiftInvert(EPS eps, PetscInt nev, PetscReal target, PC *pc)
{
  ST  st;
  KSP ksp;

  PetscFunctionBegin;
  PetscCall(EPSSetType(eps, EPSKRYLOVSCHUR));
  PetscCall(EPSSetDimensions(eps, nev, PETSC_DEFAULT, PETSC_DEFAULT));
  PetscCall(EPSSetTarget(eps, target));
  PetscCall(EPSSetWhichEigenpairs(eps, EPS_TARGET_REAL));
  PetscCall(EPSGetST(eps, &st));
  PetscCall(STSetType(st, STSINVERT));
  PetscCall(STGetKSP(st, &ksp));
  PetscCall(KSPSetType(ksp, KSPPREONLY));
  PetscCall(KSPGetPC(ksp, pc));
  PetscFunctionReturn(0);
}

/* Full-order modes, for verification only: generalized Hermitian problem with the rigid modes as a deflation
   space. Small systems go to LAPACK through EPS; larger ones use Krylov-Schur with shift-and-invert (MUMPS) about a
   small negative target, so that K - target M is positive definite. */
/* The shift-and-invert step x -> K+ (M x) with a flexible solver's factor (PCSHELL in a preonly KSP): the eigensolve
   shares the reduction's factorization instead of making its own, its applications' residual sampled
   (src/verify/eigen_apply.c, KFFlexPCApplySampled). */
static PetscErrorCode KFFlexPCApply(PC pc, Vec b, Vec x)
{
  KFFlexPCCtx       *ctx;
  Mat                B, X;
  const PetscScalar *pb;
  PetscScalar       *px;
  PetscInt           n, N;

  PetscFunctionBegin;
  PetscCall(PCShellGetContext(pc, &ctx));
  PetscCall(VecGetLocalSize(b, &n));
  PetscCall(VecGetSize(b, &N));
  PetscCall(VecGetArrayRead(b, &pb));
  PetscCall(VecGetArrayWrite(x, &px));
  PetscCall(MatCreateDense(PetscObjectComm((PetscObject)b), n, PETSC_DECIDE, N, 1, (PetscScalar *)pb, &B));
  PetscCall(MatCreateDense(PetscObjectComm((PetscObject)b), n, PETSC_DECIDE, N, 1, px, &X));
  PetscCall(KFFlexPCApplySampled(ctx, B, X));
  PetscCall(MatDestroy(&B));
  PetscCall(MatDestroy(&X));
  PetscCall(VecRestoreArrayWrite(x, &px));
  PetscCall(VecRestoreArrayRead(b, &pb));
  PetscFunctionReturn(0);
}

/* The same step on a block of vectors in one block solve (STApplyMat, KSPMatSolve: the block eigensolvers), the
   flexible solver's own block K+ as for the Krylov basis */
static PetscErrorCode KFFlexPCMatApply(PC pc, Mat B, Mat X)
{
  KFFlexPCCtx *ctx;

  PetscFunctionBegin;
  PetscCall(PCShellGetContext(pc, &ctx));
  PetscCall(KFFlexSolverApply(ctx->solver, B, X));
  PetscFunctionReturn(0);
}

/* The first m eigenvectors purified in one block solve: P = K+ M X. SLEPc purifies shift-and-invert vectors the same
   way (EPSSetPurify), one K+ application per vector: a third of a 20-mode eigensolve's applications, where a block
   solve costs a fraction of that (benchmarks/proof_cost/README.md). The columns come out M-normalized. */
static PetscErrorCode KFEPSPurifyBlock(EPS eps, KFSystem sys, KFFlexSolver solver, PetscInt m, Mat *P)
{
  Mat X, MX;
  Vec x;

  PetscFunctionBegin;
  PetscCall(KFDenseCreate(sys->scene->comm, sys->scene->nsys_local, sys->scene->nsys, m, &X));
  for (PetscInt i = 0; i < m; i++) {
    PetscCall(MatDenseGetColumnVecWrite(X, i, &x));
    PetscCall(EPSGetEigenvector(eps, i, x, NULL));
    PetscCall(MatDenseRestoreColumnVecWrite(X, i, &x));
  }
  PetscCall(KFMatMultDense(sys->Ms, X, &MX));
  PetscCall(KFDenseCreate(sys->scene->comm, sys->scene->nsys_local, sys->scene->nsys, m, P));
  PetscCall(KFFlexSolverApply(solver, MX, *P));
  PetscCall(MatDestroy(&MX));
  PetscCall(MatDestroy(&X));
  PetscCall(KFEPSNormalizeBlock(sys, *P));
  PetscFunctionReturn(0);
}

/* Stop once the converged modes reach cut2 (omega_cut^2): every mode below it is then computed, and the modes asked
   beyond it would only cost K+ applications. Shift-and-invert about 0 converges the Ritz values nearest 0 first and
   locks them in order, so the nconv converged are the lowest. */
static PetscErrorCode KFEPSStopCovered(EPS eps, PetscInt its, PetscInt max_it, PetscInt nconv, PetscInt nev, EPSConvergedReason *reason, void *ctx)
{
  const PetscReal cut2 = *(PetscReal *)ctx;

  PetscFunctionBegin;
  PetscCall(EPSStoppingBasic(eps, its, max_it, nconv, nev, reason, NULL));
  if (*reason != EPS_CONVERGED_ITERATING || cut2 <= 0) PetscFunctionReturn(0);
  for (PetscInt i = 0; i < nconv; i++) {
    PetscScalar re = eps->eigr[i], im = 0;

    PetscCall(STBackTransform(eps->st, 1, &re, &im));
    if (PetscRealPart(re) >= cut2) *reason = EPS_CONVERGED_USER;
  }
  PetscFunctionReturn(0);
}

/* The eigensolve's size from what is known of the modes (KFEigenHint): SLEPc's default Krylov dimension for the count
   expected to cover the cut, max(2c, c + 15) (one restart cycle converges them on the solid; smaller dimensions
   restart more and apply K+ more often), more than nev; and the cover test above, so that the modes asked beyond the
   cut are not computed. A neighbouring configuration's modes as the start vector were measured no cheaper (the
   single-vector Lanczos still takes about 2c steps), so the start stays SLEPc's. */
static PetscErrorCode KFEPSApplyHint(EPS eps, KFSystem sys, PetscInt nev, const KFEigenHint *hint)
{
  PetscInt c, ncv;

  PetscFunctionBegin;
  if (!hint) PetscFunctionReturn(0);
  c   = hint->count > 0 ? hint->count : nev;
  ncv = PetscMin(PetscMax(nev + 1, PetscMax(2 * c, c + 15)), sys->scene->nsys);
  PetscCall(EPSSetDimensions(eps, nev, ncv > nev ? ncv : PETSC_DEFAULT, PETSC_DEFAULT));
  PetscCall(EPSSetStoppingTestFunction(eps, KFEPSStopCovered, (void *)&hint->cut2, NULL));
  PetscFunctionReturn(0);
}

/* The sparse eigensolve's method (-kf_verify_eps_type): Krylov-Schur (the default: one K+ application per Krylov
   vector) or another SLEPc solver that works with shift-and-invert; subspace iteration applies K+ to whole blocks
   (STApplyMat, the flexible solver's block solve) and selects by magnitude of the transformed eigenvalues. A solver
   that needs a preconditioner instead of the operator (lobpcg, gd, jd, ...) is refused by name. A system small enough
   for the dense path stays with LAPACK whatever the option says: it takes every mode at once. */
static PetscErrorCode KFEPSCheckType(EPS eps, PetscBool dense)
{
  EPSType   type;
  PetscBool ok, sub;

  PetscFunctionBegin;
  if (dense) {
    PetscCall(EPSSetType(eps, EPSLAPACK));
    PetscFunctionReturn(0);
  }
  PetscCall(EPSGetType(eps, &type));
  PetscCall(PetscObjectTypeCompareAny((PetscObject)eps, &ok, EPSKRYLOVSCHUR, EPSSUBSPACE, EPSARNOLDI, EPSLANCZOS, ""));
  PetscCheck(ok, PetscObjectComm((PetscObject)eps), PETSC_ERR_SUP, "-kf_verify_eps_type %s: the sparse verification eigensolve applies shift-and-invert with K+; give krylovschur (the default), subspace (K+ applied to blocks), arnoldi or lanczos", type);
  PetscCall(PetscObjectTypeCompare((PetscObject)eps, EPSSUBSPACE, &sub));
  if (sub) PetscCall(EPSSetWhichEigenpairs(eps, EPS_TARGET_MAGNITUDE));
  PetscFunctionReturn(0);
}

/* The K+ work of one eigensolve (-info): applications, columns and seconds, and the seconds per column, which tell a
   block method's amortized solve from Krylov-Schur's single vectors */
static PetscErrorCode KFEPSInfoApplications(EPS eps, KFFlexSolver solver, const KFFlexSolverPerf *before, PetscInt checked)
{
  KFFlexSolverPerf after;
  PetscInt         its, calls, cols;
  PetscReal        sec;

  PetscFunctionBegin;
  PetscCall(KFFlexSolverGetPerf(solver, &after));
  PetscCall(EPSGetIterationNumber(eps, &its));
  calls = after.blocks - before->blocks;
  cols  = after.solve_columns - before->solve_columns;
  sec   = after.solve_seconds - before->solve_seconds;
  PetscCall(PetscInfo(eps, "kryflex verification eigensolve: %" PetscInt_FMT " iterations, %" PetscInt_FMT " K+ applications, %" PetscInt_FMT " columns, %g s in the factor's solves (%g s per column, %g s per application), %" PetscInt_FMT " one-vector applications with the residual checked\n", its, calls, cols, (double)sec, cols ? (double)(sec / cols) : 0.0, calls ? (double)(sec / calls) : 0.0, checked));
  PetscFunctionReturn(0);
}


/* What the callers take from M-normalized modes P (m columns): H P (t x m into HPhi, leading dimension t), P^T G
   (into PhiG, leading dimension nev) and the modes themselves (nsys x nev, the first m columns) */
static PetscErrorCode KFEigenModesOut(KFSystem sys, Mat P, PetscInt m, PetscInt nev, PetscReal HPhi[], PetscReal PhiG[], Mat *modes)
{
  KFScene    s = sys->scene;
  PetscInt   a = s->ninputs, t = s->noutputs;
  PetscReal *ph;

  PetscFunctionBegin;
  PetscCall(PetscMalloc1(m * PetscMax(a, t) + 1, &ph));
  if (HPhi) {
    PetscCall(KFMatTransposeMatMultGather(P, sys->Ht, ph)); /* m x t */
    for (PetscInt k = 0; k < m; k++)
      for (PetscInt q = 0; q < t; q++) HPhi[q + k * t] = ph[k + q * m];
  }
  if (PhiG) {
    PetscCall(KFMatTransposeMatMultGather(P, sys->G, ph)); /* m x a */
    for (PetscInt q = 0; q < a; q++)
      for (PetscInt k = 0; k < m; k++) PhiG[k + q * nev] = ph[k + q * m];
  }
  PetscCall(PetscFree(ph));
  if (modes) {
    PetscCall(KFDenseCreate(s->comm, s->nsys_local, s->nsys, nev, modes));
    for (PetscInt k = 0; k < m; k++) {
      Vec p, col;
      PetscCall(MatDenseGetColumnVecRead(P, k, &p));
      PetscCall(MatDenseGetColumnVecWrite(*modes, k, &col));
      PetscCall(VecCopy(p, col));
      PetscCall(MatDenseRestoreColumnVecWrite(*modes, k, &col));
      PetscCall(MatDenseRestoreColumnVecRead(P, k, &p));
    }
  }
  PetscFunctionReturn(0);
}

/* The block Krylov path (src/verify/block_eigen.c) for a reference with the flexible solver's factor
   (-kf_verify_eigen_method block, or auto from KF_BLOCK_EIGEN_MIN_DOFS system dofs on); *done false when it is not
   taken or did not converge: SLEPc's Krylov-Schur then. auto's threshold: the block path took 0.46 to 0.74 of
   Krylov-Schur's eigensolve time on the 57,031-dof solid and 1.05 to 1.3 times it on the 2,755-dof one, where the
   factor's solves are cheap and its Gram-Schmidt over blocks is not (benchmarks/proof_cost/README.md, 2026-11-29p); between the two sizes the
   crossing is not measured */
#define KF_BLOCK_EIGEN_MIN_DOFS 20000
static PetscErrorCode KFSystemEigenBlock(KFSystem sys, KFFlexSolver solver, const KFEigenHint *hint, PetscInt nev, PetscInt *nconv, PetscReal omega2[], PetscReal HPhi[], PetscReal PhiG[], Mat *modes, PetscBool *done)
{
  KFScene   s = sys->scene;
  PetscInt  method, nrand, maxblocks, firstmb, nblocks, b, cap;
  PetscReal fcut = hint && hint->cut2 > 0 ? PetscSqrtReal(hint->cut2) / (2 * PETSC_PI) : 0;
  Mat       P;

  PetscFunctionBegin;
  *done = PETSC_FALSE;
  PetscCall(KFBlockEigenOptions(s->comm, &method, &nrand, &maxblocks, &firstmb));
  if (method == 0) method = s->nsys >= KF_BLOCK_EIGEN_MIN_DOFS ? 1 : 2;
  if (method != 1 || !hint || hint->krylov_schur) PetscFunctionReturn(0);
  PetscCall(KFFlexSolverSetUp(solver));
  PetscCall(KFBlockEigenSolve(sys, solver, hint, nev, nconv, omega2, &P, done, &nblocks, &b, &cap));
  if (!*done) {
    if (fcut > 0) PetscCall(KFProgress(s->comm, "verification eigensolve: the block Krylov space did not converge the modes to %.4g Hz in %" PetscInt_FMT " blocks of %" PetscInt_FMT " columns (its cap %" PetscInt_FMT "): Krylov-Schur (SLEPc) instead", (double)fcut, nblocks, b, cap));
    else PetscCall(KFProgress(s->comm, "verification eigensolve: the block Krylov space did not converge the %" PetscInt_FMT " lowest modes in %" PetscInt_FMT " blocks of %" PetscInt_FMT " columns (its cap %" PetscInt_FMT "): Krylov-Schur (SLEPc) instead", nev, nblocks, b, cap));
    PetscFunctionReturn(0);
  }
  if (fcut > 0) PetscCall(KFProgress(s->comm, "verification eigensolve: %" PetscInt_FMT " flexible modes of the %" PetscInt_FMT "-dof system to %.4g Hz (block Krylov of K+ M with the flexible solver's factor: %" PetscInt_FMT " blocks of %" PetscInt_FMT " columns, at most %" PetscInt_FMT ")", *nconv, s->nsys, (double)fcut, nblocks, b, cap));
  else PetscCall(KFProgress(s->comm, "verification eigensolve: %" PetscInt_FMT " lowest flexible modes of the %" PetscInt_FMT "-dof system (block Krylov of K+ M with the flexible solver's factor: %" PetscInt_FMT " blocks of %" PetscInt_FMT " columns, at most %" PetscInt_FMT ")", *nconv, s->nsys, nblocks, b, cap));
  PetscCall(KFEigenModesOut(sys, P, *nconv, nev, HPhi, PhiG, modes));
  PetscCall(MatDestroy(&P));
  PetscFunctionReturn(0);
}

static PetscErrorCode KFSystemEigenSolve(KFSystem sys, KFFlexSolver solver, const KFEigenHint *hint, PetscInt nev, PetscInt *nconv, PetscReal omega2[], PetscReal HPhi[], PetscReal PhiG[], Mat *modes)
{
  KFScene   s = sys->scene;
  EPS       eps;
  PC        pc;
  Vec      *defl, x, y;
  PetscInt  r, nflex, nc, a = s->ninputs, t = s->noutputs, got = 0;
  PetscReal target;
  PetscInt  dense_max;
  PetscBool dense, has_target;
  Mat       P = NULL; /* the purified eigenvectors (with the flexible solver's factor) */
  KFFlexSolverPerf before;
  KFFlexPCCtx      pcctx = {solver, 0, 0, PETSC_FALSE};

  PetscFunctionBegin;
  PetscCall(KFSystemComputeRigidModes(sys));
  PetscCall(PetscLogEventBegin(KF_EVENT_VERIFY, 0, 0, 0, 0));
  r     = sys->nrigid;
  nflex = s->nsys - r;
  PetscCheck(nev >= 1, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "ask for at least one mode");
  nev   = PetscMin(nev, nflex);
  PetscCall(KFSystemEigenIsDense(sys, &dense));
  if (dense) {
    PetscInt nnull, n0;
    PetscCall(KFSystemMassNullity(sys, PETSC_TRUE, &nnull, &n0));
    if (nnull) {
      PetscCall(KFProgress(s->comm, "verification eigensolve: %" PetscInt_FMT " lowest flexible modes of the %" PetscInt_FMT "-dof system (dense LAPACK, %" PetscInt_FMT " massless dofs condensed with the rest of the mass matrix's null space: %" PetscInt_FMT " directions)", PetscMin(nev, nflex - nnull), s->nsys, n0, nnull));
      PetscCall(KFSystemEigenCondensed(sys, PETSC_FALSE, nev, nconv, omega2, HPhi, PhiG, modes));
      PetscCall(PetscLogEventEnd(KF_EVENT_VERIFY, 0, 0, 0, 0));
      PetscFunctionReturn(0);
    }
    if (r) { /* the flexible modes on the geometric rigid modes' M-orthogonal complement: an eigensolve of the whole
                pencil knows the rigid subspace only to eps lam_max, and mixes it into a flexible mode as soft as
                that (a rotor 1e-5 as stiff as its stator: 1e-3 of a rigid mode in its first flexible mode); each eigenvalue is
                then refined to its own accuracy (KFSystemEigenRefine) */
      PetscCall(KFProgress(s->comm, "verification eigensolve: %" PetscInt_FMT " lowest flexible modes of the %" PetscInt_FMT "-dof system (dense LAPACK, on the complement of the %" PetscInt_FMT " geometric rigid modes, refined)", nev, s->nsys, r));
      PetscCall(KFSystemEigenCondensed(sys, PETSC_TRUE, nev, nconv, omega2, HPhi, PhiG, modes));
      PetscCall(PetscLogEventEnd(KF_EVENT_VERIFY, 0, 0, 0, 0));
      PetscFunctionReturn(0);
    }
  }
  PetscCall(KFVerifyEigenOptions(s->comm, &dense_max, &target, &has_target));
  if (solver && !dense) {
    PetscBool done;

    PetscCall(KFSystemEigenBlock(sys, solver, hint, nev, nconv, omega2, HPhi, PhiG, modes, &done));
    if (done) {
      PetscCall(PetscLogEventEnd(KF_EVENT_VERIFY, 0, 0, 0, 0));
      PetscFunctionReturn(0);
    }
  }
  if (hint && hint->cut2 > 0 && !dense)
    PetscCall(KFProgress(s->comm, "verification eigensolve: the flexible modes of the %" PetscInt_FMT "-dof system up to %.4g Hz, at most %" PetscInt_FMT " (Krylov-Schur, shift-and-invert with %s)", s->nsys, (double)(PetscSqrtReal(hint->cut2) / (2 * PETSC_PI)), nev, solver ? "the flexible solver's factor" : "MUMPS"));
  else PetscCall(KFProgress(s->comm, "verification eigensolve: %" PetscInt_FMT " lowest flexible modes of the %" PetscInt_FMT "-dof system (%s)", nev, s->nsys, dense ? "dense LAPACK" : (solver ? "Krylov-Schur, shift-and-invert with the flexible solver's factor" : "Krylov-Schur, shift-and-invert with MUMPS")));
  /* before the operators are set: the factorization holds dofs of K_S in place, which would change its state */
  if (solver && !dense) PetscCall(KFFlexSolverSetUp(solver));
  PetscCall(EPSCreate(s->comm, &eps));
  PetscCall(EPSSetOperators(eps, sys->Ks, sys->Ms));
  PetscCall(EPSSetProblemType(eps, EPS_GHEP));
  if (dense) {
    PetscCall(EPSSetType(eps, EPSLAPACK));
    PetscCall(EPSSetDimensions(eps, s->nsys, PETSC_DEFAULT, PETSC_DEFAULT));
    PetscCall(EPSSetWhichEigenpairs(eps, EPS_SMALLEST_REAL));
  } else if (solver) { /* the flexible solver's factor: target 0, no deflation space (K+ removes the rigid modes) */
    PetscCall(KFEPSShiftInvert(eps, nev, 0.0, &pc));
    PetscCall(PCSetType(pc, PCSHELL));
    PetscCall(PCShellSetContext(pc, &pcctx));
    PetscCall(PCShellSetApply(pc, KFFlexPCApply));
    PetscCall(PCShellSetMatApply(pc, KFFlexPCMatApply));
    PetscCall(PCShellSetName(pc, "kryflex K+ (the flexible solver's factor)"));
    PetscCall(EPSSetTolerances(eps, 1e-10, PETSC_DEFAULT));
    PetscCall(KFEPSApplyHint(eps, sys, nev, hint));
  } else {
    PetscReal nK, nM;
    if (!has_target) {
      /* without a hint, a tiny fraction of K's scale keeps K - target M positive definite and well conditioned */
      PetscCall(MatNorm(sys->Ks, NORM_FROBENIUS, &nK));
      PetscCall(MatNorm(sys->Ms, NORM_FROBENIUS, &nM));
      target = -1e-8 * nK / nM;
    }
    if (r) { /* a clamped scene has no rigid modes to deflate */
      PetscCall(MatCreateVecs(sys->Ks, &x, NULL));
      PetscCall(VecDuplicateVecs(x, r, &defl));
      for (PetscInt k = 0; k < r; k++) PetscCall(MatGetColumnVector(sys->Phi, defl[k], k));
      PetscCall(EPSSetDeflationSpace(eps, r, defl));
      PetscCall(VecDestroyVecs(r, &defl));
      PetscCall(VecDestroy(&x));
    }
    PetscCall(KFEPSShiftInvert(eps, nev, target, &pc));
    PetscCall(PCSetType(pc, PCCHOLESKY));
    PetscCall(PCFactorSetMatSolverType(pc, MATSOLVERMUMPS));
    PetscCall(EPSSetTolerances(eps, 1e-10, PETSC_DEFAULT));
    PetscCall(KFEPSApplyHint(eps, sys, nev, hint));
  }
  if (solver && !dense) PetscCall(EPSSetPurify(eps, PETSC_FALSE)); /* purified below, in one block solve */
  PetscCall(EPSSetOptionsPrefix(eps, "kf_verify_"));
  PetscCall(EPSSetFromOptions(eps));
  PetscCall(KFEPSCheckType(eps, dense));
  if (solver && !dense) PetscCall(KFFlexSolverGetPerf(solver, &before));
  PetscCall(EPSSolve(eps));
  PetscCall(EPSGetConverged(eps, &nc));
  if (solver && !dense) PetscCall(KFEPSInfoApplications(eps, solver, &before, pcctx.checked));
  if (solver && !dense && PetscMin(nc, nev)) PetscCall(KFEPSPurifyBlock(eps, sys, solver, PetscMin(nc, nev), &P));
  PetscCall(MatCreateVecs(sys->Ks, &x, &y));
  if (modes) PetscCall(KFDenseCreate(s->comm, s->nsys_local, s->nsys, nev, modes));
  /* the dense solver returns the rigid modes too: skip the r lowest */
  for (PetscInt i = dense ? r : 0; i < nc && got < nev; i++, got++) {
    PetscScalar kr;
    if (P) {
      Vec p;
      PetscCall(EPSGetEigenvalue(eps, i, &kr, NULL));
      PetscCall(MatDenseGetColumnVecRead(P, i, &p));
      PetscCall(VecCopy(p, x));
      PetscCall(MatDenseRestoreColumnVecRead(P, i, &p));
    } else PetscCall(EPSGetEigenpair(eps, i, &kr, NULL, x, NULL));
    omega2[got] = PetscRealPart(kr);
    if (HPhi || PhiG || modes) {
      PetscScalar dot;
      if (!P) { /* M-normalize (EPS normalizes GHEP vectors in the M-norm; make sure); P's columns are */
        PetscCall(MatMult(sys->Ms, x, y));
        PetscCall(VecDot(x, y, &dot));
        PetscCall(VecScale(x, 1.0 / PetscSqrtReal(PetscRealPart(dot))));
      }
      for (PetscInt k = 0; k < t && HPhi; k++) {
        Vec h;
        PetscCall(MatDenseGetColumnVecRead(sys->Ht, k, &h));
        PetscCall(VecDot(x, h, &dot));
        PetscCall(MatDenseRestoreColumnVecRead(sys->Ht, k, &h));
        HPhi[k + got * t] = PetscRealPart(dot);
      }
      for (PetscInt k = 0; k < a && PhiG; k++) {
        Vec g;
        PetscCall(MatDenseGetColumnVecRead(sys->G, k, &g));
        PetscCall(VecDot(x, g, &dot));
        PetscCall(MatDenseRestoreColumnVecRead(sys->G, k, &g));
        PhiG[got + k * nev] = PetscRealPart(dot);
      }
      if (modes) {
        Vec col;
        PetscCall(MatDenseGetColumnVecWrite(*modes, got, &col));
        PetscCall(VecCopy(x, col));
        PetscCall(MatDenseRestoreColumnVecWrite(*modes, got, &col));
      }
    }
  }
  PetscCall(VecDestroy(&x));
  PetscCall(VecDestroy(&y));
  PetscCall(MatDestroy(&P));
  PetscCall(EPSDestroy(&eps));
  *nconv = got;
  PetscCall(PetscLogEventEnd(KF_EVENT_VERIFY, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

PetscErrorCode KFSystemEigen(KFSystem sys, PetscInt nev, PetscInt *nconv, PetscReal omega2[], PetscReal HPhi[], PetscReal PhiG[])
{
  PetscFunctionBegin;
  PetscCall(KFSystemEigenSolve(sys, NULL, NULL, nev, nconv, omega2, HPhi, PhiG, NULL));
  PetscFunctionReturn(0);
}

PetscErrorCode KFSystemEigenModes(KFSystem sys, PetscInt nev, PetscInt *nconv, PetscReal omega2[], Mat *modes)
{
  PetscFunctionBegin;
  PetscCall(KFSystemEigenSolve(sys, NULL, NULL, nev, nconv, omega2, NULL, NULL, modes));
  PetscFunctionReturn(0);
}

/* KFSystemEigenModes with the flexible solver's factorization (the modal baseline: one factorization, as Krylov) */
PetscErrorCode KFFlexSolverEigenModes(KFFlexSolver solver, PetscInt nev, PetscInt *nconv, PetscReal omega2[], Mat *modes)
{
  KFSystem sys;

  PetscFunctionBegin;
  PetscCall(KFFlexSolverGetSystem(solver, &sys));
  PetscCall(KFSystemEigenSolve(sys, solver, NULL, nev, nconv, omega2, NULL, NULL, modes));
  PetscFunctionReturn(0);
}

/* KFSystemEigen with a flexible solver's factor: K+ is the shift-and-invert step (target 0), so the verification's
   reference at a configuration the reduction has factored needs no factorization of its own. hint (or NULL): the
   cut to cover and the count expected (KFEPSApplyHint); modes (or NULL): the M-normalized modes */
PETSC_INTERN PetscErrorCode KFFlexSolverEigen_Private(KFFlexSolver solver, const KFEigenHint *hint, PetscInt nev, PetscInt *nconv, PetscReal omega2[], PetscReal HPhi[], PetscReal PhiG[], Mat *modes)
{
  PetscFunctionBegin;
  PetscCall(KFSystemEigenSolve(KFFlexSolverSystem_Private(solver), solver, hint, nev, nconv, omega2, HPhi, PhiG, modes));
  PetscFunctionReturn(0);
}

/* KFSystemEigen with a hint (KFEPSApplyHint) and, optionally, the M-normalized modes: the verification's own
   factorization of K_S - target M_S */
PETSC_INTERN PetscErrorCode KFSystemEigen_Private(KFSystem sys, const KFEigenHint *hint, PetscInt nev, PetscInt *nconv, PetscReal omega2[], PetscReal HPhi[], PetscReal PhiG[], Mat *modes)
{
  PetscFunctionBegin;
  PetscCall(KFSystemEigenSolve(sys, NULL, hint, nev, nconv, omega2, HPhi, PhiG, modes));
  PetscFunctionReturn(0);
}

/* Input and output participation of the rigid modes: H Phi_r (t x r) and Phi_r^T G (r x a). */
PetscErrorCode KFSystemRigidIO(KFSystem sys, PetscInt *nrigid, PetscReal HPhi[], PetscReal PhiG[])
{
  PetscInt   r, t = sys->scene->noutputs;
  PetscReal *tmp;

  PetscFunctionBegin;
  PetscCall(KFSystemComputeRigidModes(sys));
  r = sys->nrigid;
  if (nrigid) *nrigid = r;
  if (!r) PetscFunctionReturn(0);
  if (HPhi) {
    PetscCall(PetscMalloc1(r * t, &tmp));
    PetscCall(KFMatTransposeMatMultGather(sys->Phi, sys->Ht, tmp)); /* r x t */
    for (PetscInt i = 0; i < t; i++)
      for (PetscInt j = 0; j < r; j++) HPhi[i + j * t] = tmp[j + i * r];
    PetscCall(PetscFree(tmp));
  }
  if (PhiG) PetscCall(KFMatTransposeMatMultGather(sys->Phi, sys->G, PhiG));
  PetscFunctionReturn(0);
}
