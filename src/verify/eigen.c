#include <kryflex_impl.h>
#include <slepceps.h>

/* Small systems are solved densely: every mode at once, as cheap as a few */
PetscErrorCode KFSystemEigenIsDense(KFSystem sys, PetscBool *dense)
{
  KFScene  s         = sys->scene;
  PetscInt dense_max = 600;

  PetscFunctionBegin;
  PetscOptionsBegin(s->comm, NULL, "kryflex verification eigensolve (full order)", "KFSystemEigen");
  PetscCall(PetscOptionsInt("-kf_verify_dense_max_dofs", "Dense LAPACK verification eigensolve up to this many system dofs, Krylov-Schur with shift-and-invert above (default 600)", "KFSystemEigen", dense_max, &dense_max, NULL));
  PetscOptionsEnd();
  *dense = (PetscBool)(s->nsys <= dense_max);
  PetscFunctionReturn(0);
}

/* Full-order modes, for verification only: generalized Hermitian problem with the rigid modes as a deflation
   space. Small systems go to LAPACK through EPS; larger ones use Krylov-Schur with shift-and-invert (MUMPS) about a
   small negative target, so that K - target M is positive definite. */
static PetscErrorCode KFSystemEigenSolve(KFSystem sys, PetscInt nev, PetscInt *nconv, PetscReal omega2[], PetscReal HPhi[], PetscReal PhiG[], Mat *modes)
{
  KFScene   s = sys->scene;
  EPS       eps;
  ST        st;
  KSP       ksp;
  PC        pc;
  Vec      *defl, x, y;
  PetscInt  r, nflex, nc, a = s->ninputs, t = s->noutputs, got = 0;
  PetscReal target = 0;
  PetscBool dense, has_target;

  PetscFunctionBegin;
  PetscCall(KFSystemComputeRigidModes(sys));
  PetscCall(PetscLogEventBegin(KF_EVENT_VERIFY, 0, 0, 0, 0));
  r     = sys->nrigid;
  nflex = s->nsys - r;
  PetscCheck(nev >= 1, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "ask for at least one mode");
  nev   = PetscMin(nev, nflex);
  PetscCall(KFSystemEigenIsDense(sys, &dense));
  PetscOptionsBegin(s->comm, NULL, "kryflex verification eigensolve (full order)", "KFSystemEigen");
  PetscCall(PetscOptionsReal("-kf_verify_target", "Shift-and-invert target of the sparse verification eigensolve (default -1e-8 ||K_S||_F / ||M_S||_F); its EPS takes -kf_verify_eps_* options", "KFSystemEigen", target, &target, &has_target));
  PetscOptionsEnd();
  PetscCall(KFProgress(s->comm, "verification eigensolve: %" PetscInt_FMT " lowest flexible modes of the %" PetscInt_FMT "-dof system (%s)", nev, s->nsys, dense ? "dense LAPACK" : "Krylov-Schur, shift-and-invert with MUMPS"));
  PetscCall(EPSCreate(s->comm, &eps));
  PetscCall(EPSSetOperators(eps, sys->Ks, sys->Ms));
  PetscCall(EPSSetProblemType(eps, EPS_GHEP));
  if (dense) {
    PetscCall(EPSSetType(eps, EPSLAPACK));
    PetscCall(EPSSetDimensions(eps, s->nsys, PETSC_DEFAULT, PETSC_DEFAULT));
    PetscCall(EPSSetWhichEigenpairs(eps, EPS_SMALLEST_REAL));
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
    PetscCall(EPSSetType(eps, EPSKRYLOVSCHUR));
    PetscCall(EPSSetDimensions(eps, nev, PETSC_DEFAULT, PETSC_DEFAULT));
    PetscCall(EPSSetTarget(eps, target));
    PetscCall(EPSSetWhichEigenpairs(eps, EPS_TARGET_REAL));
    PetscCall(EPSGetST(eps, &st));
    PetscCall(STSetType(st, STSINVERT));
    PetscCall(STGetKSP(st, &ksp));
    PetscCall(KSPSetType(ksp, KSPPREONLY));
    PetscCall(KSPGetPC(ksp, &pc));
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
  PetscCall(KFSystemEigenSolve(sys, nev, nconv, omega2, HPhi, PhiG, NULL));
  PetscFunctionReturn(0);
}

PetscErrorCode KFSystemEigenModes(KFSystem sys, PetscInt nev, PetscInt *nconv, PetscReal omega2[], Mat *modes)
{
  PetscFunctionBegin;
  PetscCall(KFSystemEigenSolve(sys, nev, nconv, omega2, NULL, NULL, modes));
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
