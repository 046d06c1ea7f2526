#include <kryflex_impl.h>
#include <slepceps.h>
#include "../dense/dense_impl.h"
#include <petscblaslapack.h>

/* System dofs whose row of M_S is zero (massless: rotations of a lumped-mass model): they carry infinite
   eigenvalues, which a dense generalized eigensolver cannot take (LAPACK sygv needs M positive definite) */
PETSC_INTERN PetscErrorCode KFSystemMasslessCount(KFSystem sys, PetscInt *n0)
{
  Vec                v;
  const PetscScalar *x;
  PetscInt           nl, c = 0;

  PetscFunctionBegin;
  PetscCall(MatCreateVecs(sys->Ms, NULL, &v));
  PetscCall(MatGetRowMaxAbs(sys->Ms, v, NULL));
  PetscCall(VecGetLocalSize(v, &nl));
  PetscCall(VecGetArrayRead(v, &x));
  for (PetscInt i = 0; i < nl; i++) c += PetscAbsScalar(x[i]) == 0;
  PetscCall(VecRestoreArrayRead(v, &x));
  PetscCall(VecDestroy(&v));
  PetscCall(MPIU_Allreduce(&c, n0, 1, MPIU_INT, MPI_SUM, sys->scene->comm));
  PetscFunctionReturn(0);
}

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

/* The dense verification of a system with massless dofs: they are condensed statically (K_cc = K_mm - K_m0 K_00^-1
   K_0m on the dofs with mass, whose M_mm is then positive definite), the pencil solved with the rigid modes known
   (KFDenseEigRigid), and each mode expanded to the massless dofs by x_0 = -K_00^-1 K_0m x_m. Exact: the massless
   rows of K x = lambda M x say K_0m x_m + K_00 x_0 = 0. */
static PetscErrorCode KFSystemEigenCondensed(KFSystem sys, PetscInt nev, PetscInt *nconv, PetscReal omega2[], PetscReal HPhi[], PetscReal PhiG[], Mat *modes)
{
  KFScene      s = sys->scene;
  PetscInt     n = s->nsys, a = s->ninputs, t = s->noutputs, r = sys->nrigid, n0 = 0, nm = 0, *im, *iz, got;
  PetscReal   *K, *M, *G, *Ht, *Phr, *K00, *X, *Kc, *Mc, *Pm, *lam, *V, *x;
  PetscBLASInt b0, bm, info;

  PetscFunctionBegin;
  PetscCall(PetscMalloc4(n * n, &K, n * n, &M, n * a, &G, n * t, &Ht));
  PetscCall(PetscMalloc1(n * PetscMax(r, 1), &Phr));
  PetscCall(KFGatherAny(sys->Ks, K));
  PetscCall(KFGatherAny(sys->Ms, M));
  PetscCall(KFDenseGather(sys->G, G));
  PetscCall(KFDenseGather(sys->Ht, Ht));
  if (r) PetscCall(KFDenseGather(sys->Phi, Phr));
  PetscCall(PetscMalloc2(n, &im, n, &iz));
  for (PetscInt i = 0; i < n; i++) {
    PetscBool zero = PETSC_TRUE;
    for (PetscInt j = 0; j < n && zero; j++) zero = (PetscBool)(M[i + j * n] == 0);
    if (zero) iz[n0++] = i;
    else im[nm++] = i;
  }
  PetscCall(PetscMalloc5(n0 * n0 + 1, &K00, n0 * nm + 1, &X, nm * nm, &Kc, nm * nm, &Mc, nm * PetscMax(r, 1), &Pm));
  PetscCall(PetscMalloc3(nm, &lam, nm * nm, &V, n, &x));
  for (PetscInt j = 0; j < n0; j++)
    for (PetscInt i = 0; i < n0; i++) K00[i + j * n0] = K[iz[i] + iz[j] * n];
  for (PetscInt j = 0; j < nm; j++)
    for (PetscInt i = 0; i < n0; i++) X[i + j * n0] = K[iz[i] + im[j] * n];
  PetscCall(PetscBLASIntCast(n0, &b0));
  PetscCall(PetscBLASIntCast(nm, &bm));
  PetscCallBLAS("LAPACKpotrf", LAPACKpotrf_("L", &b0, K00, &b0, &info));
  PetscCheck(!info, s->comm, PETSC_ERR_ARG_WRONG, "the %" PetscInt_FMT " massless dofs of the system are not held by stiffness (their stiffness block is singular at its leading minor %d): a massless dof or group of them can move freely, a mechanism without inertia; clamp it or connect it", n0, (int)info);
  PetscCallBLAS("LAPACKpotrs", LAPACKpotrs_("L", &b0, &bm, K00, &b0, X, &b0, &info)); /* X = K00^-1 K0m */
  for (PetscInt j = 0; j < nm; j++)
    for (PetscInt i = 0; i < nm; i++) {
      Kc[i + j * nm] = K[im[i] + im[j] * n];
      Mc[i + j * nm] = M[im[i] + im[j] * n];
      for (PetscInt k = 0; k < n0; k++) Kc[i + j * nm] -= K[im[i] + iz[k] * n] * X[k + j * n0];
    }
  PetscCall(KFDenseSymmetrize_Private(nm, Kc));
  for (PetscInt j = 0; j < r; j++)
    for (PetscInt i = 0; i < nm; i++) Pm[i + j * nm] = Phr[im[i] + j * n];
  PetscCall(KFDenseEigRigid(nm, Kc, Mc, r, Pm, lam, V));
  got = PetscMax(PetscMin(nev, nm - r), 0);
  if (modes) PetscCall(KFDenseCreate(s->comm, s->nsys_local, s->nsys, nev, modes));
  for (PetscInt k = 0; k < got; k++) {
    const PetscReal *v = V + (r + k) * nm;
    omega2[k] = lam[r + k];
    for (PetscInt i = 0; i < nm; i++) x[im[i]] = v[i];
    for (PetscInt i = 0; i < n0; i++) {
      x[iz[i]] = 0;
      for (PetscInt j = 0; j < nm; j++) x[iz[i]] -= X[i + j * n0] * v[j];
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
  PetscCall(PetscFree2(im, iz));
  PetscCall(PetscFree5(K00, X, Kc, Mc, Pm));
  PetscCall(PetscFree3(lam, V, x));
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
  PetscCall(PetscOptionsInt("-kf_verify_dense_max_dofs", "Dense LAPACK verification eigensolve up to this many system dofs, Krylov-Schur with shift-and-invert above (default 600)", "KFSystemEigen", *dense_max, dense_max, NULL));
  PetscCall(PetscOptionsReal("-kf_verify_target", "Shift-and-invert target of the sparse verification eigensolve (default -1e-8 ||K_S||_F / ||M_S||_F); its EPS takes -kf_verify_eps_* options", "KFSystemEigen", *target, target, has_target));
  PetscOptionsEnd();
  PetscCheck(*dense_max >= 0, comm, PETSC_ERR_ARG_OUTOFRANGE, "-kf_verify_dense_max_dofs is a number of system dofs, 0 or more; got %" PetscInt_FMT, *dense_max);
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
   shares the reduction's factorization instead of making its own. K+ is M-self-adjoint on the flexible subspace and
   maps the rigid modes to zero, so with target 0 the rigid modes never come out and need no deflation space. */
static PetscErrorCode KFFlexPCApply(PC pc, Vec b, Vec x)
{
  KFFlexSolver       solver;
  Mat                B, X;
  const PetscScalar *pb;
  PetscScalar       *px;
  PetscInt           n, N;

  PetscFunctionBegin;
  PetscCall(PCShellGetContext(pc, &solver));
  PetscCall(VecGetLocalSize(b, &n));
  PetscCall(VecGetSize(b, &N));
  PetscCall(VecGetArrayRead(b, &pb));
  PetscCall(VecGetArrayWrite(x, &px));
  PetscCall(MatCreateDense(PetscObjectComm((PetscObject)b), n, PETSC_DECIDE, N, 1, (PetscScalar *)pb, &B));
  PetscCall(MatCreateDense(PetscObjectComm((PetscObject)b), n, PETSC_DECIDE, N, 1, px, &X));
  PetscCall(KFFlexSolverApply(solver, B, X));
  PetscCall(MatDestroy(&B));
  PetscCall(MatDestroy(&X));
  PetscCall(VecRestoreArrayWrite(x, &px));
  PetscCall(VecRestoreArrayRead(b, &pb));
  PetscFunctionReturn(0);
}

static PetscErrorCode KFSystemEigenSolve(KFSystem sys, KFFlexSolver solver, PetscInt nev, PetscInt *nconv, PetscReal omega2[], PetscReal HPhi[], PetscReal PhiG[], Mat *modes)
{
  KFScene   s = sys->scene;
  EPS       eps;
  PC        pc;
  Vec      *defl, x, y;
  PetscInt  r, nflex, nc, a = s->ninputs, t = s->noutputs, got = 0;
  PetscReal target;
  PetscInt  dense_max;
  PetscBool dense, has_target;

  PetscFunctionBegin;
  PetscCall(KFSystemComputeRigidModes(sys));
  PetscCall(PetscLogEventBegin(KF_EVENT_VERIFY, 0, 0, 0, 0));
  r     = sys->nrigid;
  nflex = s->nsys - r;
  PetscCheck(nev >= 1, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "ask for at least one mode");
  nev   = PetscMin(nev, nflex);
  PetscCall(KFSystemEigenIsDense(sys, &dense));
  if (dense) {
    PetscInt n0;
    PetscCall(KFSystemMasslessCount(sys, &n0));
    if (n0) {
      PetscCall(KFProgress(s->comm, "verification eigensolve: %" PetscInt_FMT " lowest flexible modes of the %" PetscInt_FMT "-dof system (dense LAPACK, %" PetscInt_FMT " massless dofs condensed)", PetscMin(nev, nflex - n0), s->nsys, n0));
      PetscCall(KFSystemEigenCondensed(sys, nev, nconv, omega2, HPhi, PhiG, modes));
      PetscCall(PetscLogEventEnd(KF_EVENT_VERIFY, 0, 0, 0, 0));
      PetscFunctionReturn(0);
    }
  }
  PetscCall(KFVerifyEigenOptions(s->comm, &dense_max, &target, &has_target));
  PetscCall(KFProgress(s->comm, "verification eigensolve: %" PetscInt_FMT " lowest flexible modes of the %" PetscInt_FMT "-dof system (%s)", nev, s->nsys, dense ? "dense LAPACK" : (solver ? "Krylov-Schur, shift-and-invert with the flexible solver's factor" : "Krylov-Schur, shift-and-invert with MUMPS")));
  PetscCall(EPSCreate(s->comm, &eps));
  PetscCall(EPSSetOperators(eps, sys->Ks, sys->Ms));
  PetscCall(EPSSetProblemType(eps, EPS_GHEP));
  if (dense) {
    PetscCall(EPSSetType(eps, EPSLAPACK));
    PetscCall(EPSSetDimensions(eps, s->nsys, PETSC_DEFAULT, PETSC_DEFAULT));
    PetscCall(EPSSetWhichEigenpairs(eps, EPS_SMALLEST_REAL));
  } else if (solver) { /* the flexible solver's factor: target 0, no deflation space (K+ removes the rigid modes) */
    PetscCall(KFFlexSolverSetUp(solver));
    PetscCall(KFEPSShiftInvert(eps, nev, 0.0, &pc));
    PetscCall(PCSetType(pc, PCSHELL));
    PetscCall(PCShellSetContext(pc, solver));
    PetscCall(PCShellSetApply(pc, KFFlexPCApply));
    PetscCall(PCShellSetName(pc, "kryflex K+ (the flexible solver's factor)"));
    PetscCall(EPSSetTolerances(eps, 1e-10, PETSC_DEFAULT));
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
  }
  PetscCall(EPSSetOptionsPrefix(eps, "kf_verify_"));
  PetscCall(EPSSetFromOptions(eps));
  PetscCall(EPSSolve(eps));
  PetscCall(EPSGetConverged(eps, &nc));
  PetscCall(MatCreateVecs(sys->Ks, &x, &y));
  if (modes) PetscCall(KFDenseCreate(s->comm, s->nsys_local, s->nsys, nev, modes));
  /* the dense solver returns the rigid modes too: skip the r lowest */
  for (PetscInt i = dense ? r : 0; i < nc && got < nev; i++, got++) {
    PetscScalar kr;
    PetscCall(EPSGetEigenpair(eps, i, &kr, NULL, x, NULL));
    omega2[got] = PetscRealPart(kr);
    if (HPhi || PhiG || modes) {
      PetscReal nrm2;
      PetscScalar dot;
      /* M-normalize (EPS normalizes GHEP vectors in the M-norm; make sure) */
      PetscCall(MatMult(sys->Ms, x, y));
      PetscCall(VecDot(x, y, &dot));
      nrm2 = PetscSqrtReal(PetscRealPart(dot));
      PetscCall(VecScale(x, 1.0 / nrm2));
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
  PetscCall(EPSDestroy(&eps));
  *nconv = got;
  PetscCall(PetscLogEventEnd(KF_EVENT_VERIFY, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

PetscErrorCode KFSystemEigen(KFSystem sys, PetscInt nev, PetscInt *nconv, PetscReal omega2[], PetscReal HPhi[], PetscReal PhiG[])
{
  PetscFunctionBegin;
  PetscCall(KFSystemEigenSolve(sys, NULL, nev, nconv, omega2, HPhi, PhiG, NULL));
  PetscFunctionReturn(0);
}

PetscErrorCode KFSystemEigenModes(KFSystem sys, PetscInt nev, PetscInt *nconv, PetscReal omega2[], Mat *modes)
{
  PetscFunctionBegin;
  PetscCall(KFSystemEigenSolve(sys, NULL, nev, nconv, omega2, NULL, NULL, modes));
  PetscFunctionReturn(0);
}

/* KFSystemEigenModes with the flexible solver's factorization (the modal baseline: one factorization, as Krylov) */
PetscErrorCode KFFlexSolverEigenModes(KFFlexSolver solver, PetscInt nev, PetscInt *nconv, PetscReal omega2[], Mat *modes)
{
  PetscFunctionBegin;
  PetscCall(KFSystemEigenSolve(solver->sys, solver, nev, nconv, omega2, NULL, NULL, modes));
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
