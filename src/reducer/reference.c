/*
  The full-order reference at a configuration, its whole life: made (SLEPc modes: all of a small system, else those
  covering verify_cover x the band's top; the rigid modes' participation; M's null space condensed), evaluated at any
  frequency (the modes not computed by their first two residual moments) and destroyed. Where it is used: evaluate.c
  (the evaluation points' grids and errors), compare.c (the models against it), verify/direct_check.c (it against
  direct solves of the full system).
*/
#include <kryflex/reducerimpl.h>

/* up to this many modes (rigid and flexible) the damping matrices couple all of them: the cut at cover x the band's
   top is an approximation, and a dense 2m x 2m solve per grid frequency stays cheap (m = 64: ~1e6 flops, a second
   over a 2,000-point grid; m = 200 would be 30 times that) */
#define KF_COUPLED_ALL 64

PETSC_INTERN PetscErrorCode KFSystemMassNullity(KFSystem, PetscBool, PetscInt *, PetscInt *);
PETSC_INTERN PetscErrorCode KFSystemMasslessCount(KFSystem, PetscInt *);
PETSC_INTERN PetscErrorCode KFSystemMassNullStatic(KFSystem, PetscReal[]);
PETSC_INTERN PetscErrorCode KFFlexSolverEigen_Private(KFFlexSolver, const KFEigenHint *, PetscInt, PetscInt *, PetscReal[], PetscReal[], PetscReal[], Mat *);
PETSC_INTERN PetscErrorCode KFSystemEigen_Private(KFSystem, const KFEigenHint *, PetscInt, PetscInt *, PetscReal[], PetscReal[], PetscReal[], Mat *);
PETSC_INTERN PetscErrorCode KFSystemShiftedInertia(KFSystem, PetscReal, KFBodyFactors, PetscInt *, PetscInt *);
PETSC_INTERN PetscErrorCode KFModeCountBodyFactors(KFSystem, const char[], PetscReal, PetscBool, KFBodyFactors *);
PETSC_INTERN PetscErrorCode KFModeCountOptions(MPI_Comm, const char[], PetscBool *, PetscBool *);

/* The certificate of a sparse eigensolve stopped at the cut (cut2 = omega^2): the flexible modes below it counted by
   Sylvester's inertia of K_S - cut2 M_S (one LDL^T factorization) against those the eigensolve returned below it. A
   Krylov method cannot see a mode its start block misses; the count can. Fewer returned than counted is a mode
   missed: with retry, *missed (the caller solves again by Krylov-Schur, whose random start reaches what the block
   path's inputs, outputs and random columns may not), else exit 3 naming the configuration and both counts (more
   returned than counted, a spurious mode, is exit 3 at once). A cut that is itself an eigenvalue (a null pivot) is
   moved 1e-6 lower, with the returned count taken there. */
static PetscErrorCode KFReferenceCount(KFReducer r, KFSystem sys, PetscReal cut2, PetscInt nconv, const PetscReal w2[], PetscBool retry, KFFullReference *ref, PetscBool *missed)
{
  MPI_Comm       comm = PetscObjectComm((PetscObject)r);
  PetscInt       nneg, nnull, below = 0, nrigid;
  PetscReal      sigma = cut2;
  PetscLogDouble t0, t1;

  PetscFunctionBegin;
  PetscCall(PetscTime(&t0));
  PetscCall(KFSystemRigidIO(sys, &nrigid, NULL, NULL));
  if (!r->count_bf_made) { /* the cut is the same at every configuration: the bodies' factors at it serve them all */
    PetscCall(KFModeCountBodyFactors(sys, ((PetscObject)r)->prefix, sigma, PETSC_FALSE, &r->count_bf));
    r->count_bf_made = PETSC_TRUE;
  }
  PetscCall(KFSystemShiftedInertia(sys, sigma, r->count_bf, &nneg, &nnull));
  if (nnull) {
    sigma *= 1 - 1e-6;
    PetscCall(KFSystemShiftedInertia(sys, sigma, NULL, &nneg, &nnull));
  }
  PetscCheck(nnull == 0, comm, PETSC_ERR_CONV_FAILED, "the verification's mode count: K_S - sigma M_S is singular at the cut %g Hz and 1e-6 below it; set -kf_verify_cover to move the cut", (double)(PetscSqrtReal(cut2) / (2 * PETSC_PI)));
  while (below < nconv && w2[below] < sigma) below++;
  ref->count    = nneg - nrigid;
  ref->count_hz = PetscSqrtReal(sigma) / (2 * PETSC_PI);
  PetscCall(PetscTime(&t1));
  r->verify_count_seconds += t1 - t0;
  PetscCall(KFReducerResultScalar_Private(r, -1, "time_reference_count", (PetscReal)r->verify_count_seconds));
  PetscCall(KFProgress(comm, "  mode count (inertia of K_S - sigma M_S): %" PetscInt_FMT " flexible modes below %.6g Hz, the eigensolve found %" PetscInt_FMT " (%.3g s, %s)", ref->count, (double)ref->count_hz, below, (double)(t1 - t0), r->count_bf ? "body-wise" : "monolithic"));
  *missed = (PetscBool)(retry && ref->count > below);
  if (*missed) {
    PetscCall(KFProgress(comm, "  the eigensolve missed %" PetscInt_FMT " of the %" PetscInt_FMT " flexible modes below %.6g Hz: solved again by Krylov-Schur", ref->count - below, ref->count, (double)ref->count_hz));
    PetscFunctionReturn(0);
  }
  PetscCheck(ref->count == below, comm, PETSC_ERR_CONV_FAILED, "the verification eigensolve found %" PetscInt_FMT " flexible modes below %.6g Hz, the inertia of K_S - sigma M_S (Sylvester) counts %" PetscInt_FMT ": %s. Widen its start block (-kf_verify_eigen_random) or take Krylov-Schur (-kf_verify_eigen_method slepc)", below, (double)ref->count_hz, ref->count, ref->count > below ? "it missed a mode its start block did not reach" : "it returned a mode that is not one");
  PetscFunctionReturn(0);
}

/* Whether the sparse eigensolve may take the reduction's flexible solver as its shift-and-invert step: K+ is what
   it needs when the solver holds dofs (no shift) and no target was asked for (-kf_verify_target: that target's own
   MUMPS factorization) */
static PetscErrorCode KFReferenceUsesSolver(KFReducer r, KFFlexSolver solver, PetscBool dense, PetscBool *use)
{
  PetscInt  dense_max;
  PetscReal target;
  PetscBool has_target;

  PetscFunctionBegin;
  PetscCall(KFVerifyEigenOptions(PetscObjectComm((PetscObject)r), &dense_max, &target, &has_target));
  *use = (PetscBool)(solver && !dense && r->shift == 0 && !has_target);
  PetscFunctionReturn(0);
}

/* The lowest nev flexible modes (w2, H Phi, Phi^T G; or the modes themselves with viscous damping), with the
   flexible solver's factor when it may serve: its block solves are the verification's, so the solver's own
   accounting (the reduction's solves) is left as it was. With the automatic count and fmax > 0 (the sparse path)
   the eigensolve stops once its modes reach fmax, sized by the count the previous reference took to reach it.
   keep (or NULL): the modes themselves, for the iterative reference check (src/verify/refined_check.c). */
static PetscErrorCode KFReferenceEigen(KFReducer r, KFSystem sys, KFFlexSolver solver, PetscBool viscous, PetscReal fmax, PetscInt nev, PetscInt *nconv, PetscReal w2[], PetscReal HPhi[], PetscReal PhiG[], Mat *modes, Mat *keep)
{
  KFFlexSolverPerf perf;
  PetscLogDouble   t0, t1;

  PetscFunctionBegin;
  PetscCall(PetscTime(&t0));
  if (solver) PetscCall(KFFlexSolverGetPerf(solver, &perf));
  if (viscous) PetscCall(MatDestroy(modes));
  if (keep) PetscCall(MatDestroy(keep));
  {
    const PetscReal wcut = 2 * PETSC_PI * fmax;
    KFEigenHint     hint = {r->verify_modes == PETSC_DECIDE ? wcut * wcut : 0, r->verify_count, r->verify_covered, r->verify_krylov_schur};
    PetscInt        c    = 0;

    if (solver) PetscCall(KFFlexSolverEigen_Private(solver, &hint, nev, nconv, w2, HPhi, PhiG, viscous ? modes : keep));
    else PetscCall(KFSystemEigen_Private(sys, &hint, nev, nconv, w2, HPhi, PhiG, viscous ? modes : keep));
    while (c < *nconv && w2[c] < hint.cut2) c++;
    /* ... and the rest of its multiple mode (a pair's partner: left to the residual term it costs 3e-6 of the peak on
       a beam with paired frequencies) */
    while (c + 1 < *nconv && w2[c + 1] <= (1 + 1e-8) * w2[c]) c++;
    /* the modes to the first at or above the cut, whatever the last restart cycle converged beyond it: the same
       reference on any number of ranks */
    if (hint.cut2 > 0) {
      r->verify_covered = (PetscBool)(c < *nconv);
      *nconv = r->verify_count = PetscMin(c + 1, *nconv);
    }
  }
  if (solver) PetscCall(KFFlexSolverSetPerf_Private(solver, &perf));
  PetscCall(PetscTime(&t1));
  r->verify_eigen_seconds += t1 - t0;
  PetscCall(KFReducerResultScalar_Private(r, -1, "time_reference_eigensolve", (PetscReal)r->verify_eigen_seconds));
  PetscFunctionReturn(0);
}

/* solver: the flexible solver of the system's configuration, or NULL (the eigensolve then factors on its own) */
PetscErrorCode KFReducerFullReference_Private(KFReducer r, KFSystem sys, KFFlexSolver solver, KFFullReference *ref)
{
  PetscInt   nrev, nsys, a, t, nflex, nev, nconv, nb, nrigid, nnull = 0, n0;
  PetscReal *w2, *HPhi, *PhiG, fmax = r->verify_cover * r->band[1];
  PetscBool  dense, viscous = PETSC_FALSE, use = PETSC_FALSE, exact, keep;
  Mat        modes = NULL;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, &nb, NULL, &nrev, &nsys, &a, &t));
  for (PetscInt b = 0; b < nb; b++)
    if (r->scene->bodies[b].C) viscous = PETSC_TRUE;
  PetscCall(KFSystemRigidIO(sys, &nrigid, NULL, NULL)); /* the rigid count geometry and boundary conditions give */
  PetscCall(KFSystemEigenIsDense(sys, &dense));
  PetscCall(KFReferenceUsesSolver(r, solver, dense, &use));
  /* the modes kept for the iterative reference check (src/verify/refined_check.c), which iterates with this
     solver's K+: no shift, no damping matrices */
  keep = (PetscBool)(r->verify && r->verify_check_iterative && r->verify_check_points > 0 && solver && r->shift == 0 && !viscous);
  /* the null space of the mass carries infinite eigenvalues: no flexible modes of its own. Its zero rows are in it;
     the sparse path finds the rest with a factorization of M_S, needed only when the modes asked for could reach
     the flexible count (otherwise the residual is kept whatever the nullity: ref->complete is false) */
  PetscCall(KFSystemMasslessCount(sys, &n0));
  exact = dense;
  if (dense) PetscCall(KFSystemMassNullity(sys, dense, &nnull, &n0));
  nflex = nsys - nrigid - PetscMax(nnull, n0);
  /* dense: every mode (no residual to approximate) */
  /* sparse: twice the count the previous reference took to reach the cut (its eigensolve stops there), at least 20 */
  nev = r->verify_modes == PETSC_DECIDE ? (dense ? nflex : PetscMax(20, 2 * r->verify_count)) : r->verify_modes;
  for (PetscInt attempt = 0; attempt < 2; attempt++) { /* again by Krylov-Schur when the count finds modes missed */
  while (PETSC_TRUE) { /* double the count until the modes cover fmax */
    if (!exact && 2 * nev >= nflex) {
      PetscCall(KFSystemMassNullity(sys, PETSC_FALSE, &nnull, &n0));
      nflex = nsys - nrigid - nnull;
      exact = PETSC_TRUE;
    }
    PetscCheck(nflex >= 1, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_WRONG, "the scene has no flexible modes to verify (%" PetscInt_FMT " system dofs, %" PetscInt_FMT " rigid-body and mechanism modes): switch verification off (-kf_verify 0)", nsys, nrigid);
    nev = PetscMin(nev, nflex);
    PetscCall(PetscMalloc3(nev, &w2, t * nev, &HPhi, nev * a, &PhiG));
    /* with viscous damping matrices the modes themselves are needed: their damping Phi^T C Phi couples them */
    /* the cut stops a sparse eigensolve early; asked for every flexible mode it computes them all (exact, no residual).
       With damping matrices the modes beyond the cut are coupled too (KF_COUPLED_ALL): the count asked is kept */
    PetscCall(KFReferenceEigen(r, sys, use ? solver : NULL, viscous, dense || viscous || nev >= nflex ? 0 : fmax, nev, &nconv, w2, HPhi, PhiG, &modes, keep ? &ref->V : NULL));
    if (r->verify_modes != PETSC_DECIDE || nev >= nflex || (nconv && PetscSqrtReal(w2[nconv - 1]) / (2 * PETSC_PI) >= fmax)) break;
    PetscCall(PetscFree3(w2, HPhi, PhiG));
    nev = PetscMin(nflex, 2 * nev);
  }
  ref->count = -1;
  {
    PetscBool count, missed = PETSC_FALSE;

    PetscCall(KFModeCountOptions(PetscObjectComm((PetscObject)r), ((PetscObject)r)->prefix, &count, NULL));
    /* the sparse eigensolve stopped at the cut (a dense or complete one has every mode) */
    if (count && !dense && r->verify_modes == PETSC_DECIDE && !viscous && nev < nflex) PetscCall(KFReferenceCount(r, sys, PetscSqr(2 * PETSC_PI * fmax), nconv, w2, (PetscBool)(attempt == 0), ref, &missed));
    if (!missed) break;
    PetscCall(PetscFree3(w2, HPhi, PhiG));
    r->verify_krylov_schur = PETSC_TRUE;
    nev = PetscMin(nflex, PetscMax(nev, 2 * ref->count)); /* room for every mode counted below the cut */
  }
  }
  r->verify_krylov_schur = PETSC_FALSE;
  ref->n = nconv;
  /* with M singular the modes are not the whole response: a load on M's null space moves it statically,
     H Z K_zz^-1 Z^T G at every frequency, which no mode carries. The dense path computes that term exactly (ref->D);
     the sparse path's static residual R^0 = L^0 - sum over the modes holds it, so it is kept there even when every
     finite mode was computed (R^1, which M annihilates on Z, falls below its noise and is dropped) */
  ref->complete = (PetscBool)(exact && nconv == nflex && (dense || nnull == 0));
  if (dense && nnull) {
    PetscCall(PetscMalloc1(t * a, &ref->D));
    PetscCall(KFSystemMassNullStatic(sys, ref->D));
  }
  PetscCall(PetscMalloc3(PetscMax(nconv, 1), &ref->w2, PetscMax(t * nconv, 1), &ref->HPhi, PetscMax(nconv * a, 1), &ref->PhiG));
  PetscCall(PetscArraycpy(ref->w2, w2, nconv));
  PetscCall(KFSystemRigidIO(sys, &ref->r, NULL, NULL));
  if (viscous) {
    /* X = [Phi_r, modes]: H X, X^T G and X^T C X, with C = sum_b P_b^T C_b P_b never assembled */
    Mat        X, Phir, Ms, Ks, G, Ht;
    PetscInt   m = ref->r + nconv, nloc, lda, ldx, ldr;
    PetscReal *XtH, *XtG;
    PetscBool  has;
    PetscScalar       *x;
    const PetscScalar *p, *q;

    PetscCall(KFSystemGetMatrices(sys, &Ms, &Ks, &G, &Ht));
    PetscCall(KFSystemGetRigidModes(sys, &Phir, NULL));
    PetscCall(MatGetLocalSize(Ms, &nloc, NULL));
    PetscCall(KFDenseCreate(PetscObjectComm((PetscObject)r), nloc, nsys, m, &X));
    PetscCall(MatDenseGetArrayWrite(X, &x));
    PetscCall(MatDenseGetLDA(X, &ldx));
    PetscCall(MatDenseGetArrayRead(Phir, &p));
    PetscCall(MatDenseGetLDA(Phir, &ldr));
    PetscCall(MatDenseGetArrayRead(modes, &q));
    PetscCall(MatDenseGetLDA(modes, &lda));
    for (PetscInt c = 0; c < m; c++)
      for (PetscInt i = 0; i < nloc; i++) x[i + c * ldx] = c < ref->r ? p[i + c * ldr] : q[i + (c - ref->r) * lda];
    PetscCall(MatDenseRestoreArrayRead(modes, &q));
    PetscCall(MatDenseRestoreArrayRead(Phir, &p));
    PetscCall(MatDenseRestoreArrayWrite(X, &x));
    PetscCall(PetscMalloc2(m * t, &XtH, m * a, &XtG));
    PetscCall(PetscMalloc1(m * m, &ref->Cm));
    PetscCall(KFMatTransposeMatMultGather(X, Ht, XtH));
    PetscCall(KFMatTransposeMatMultGather(X, G, XtG));
    for (PetscInt k = 0; k < nconv; k++) {
      for (PetscInt i = 0; i < t; i++) ref->HPhi[i + k * t] = XtH[ref->r + k + i * m];
      for (PetscInt j = 0; j < a; j++) ref->PhiG[k + j * nconv] = XtG[ref->r + k + j * m];
    }
    PetscCall(KFSystemProjectDamping_Private(sys, X, &has, ref->Cm));
    /* the modes to cover x the band's top are solved together; the higher ones keep their own damping only. Up to
       KF_COUPLED_ALL modes all are coupled: on Galileo with damping matrices the modes above 3x the band's top,
       left uncoupled, put the reference 3e-6 of the peak off the damped direct solve at the band's bottom */
    ref->nc = ref->r;
    for (PetscInt k = 0; k < nconv; k++)
      if (PetscSqrtReal(w2[k]) / (2 * PETSC_PI) <= fmax || m <= KF_COUPLED_ALL) ref->nc = ref->r + k + 1;
    PetscCall(PetscFree2(XtH, XtG));
    PetscCall(MatDestroy(&X));
    PetscCall(MatDestroy(&modes));
  } else {
    PetscCall(PetscArraycpy(ref->HPhi, HPhi, t * nconv));
    for (PetscInt j = 0; j < a; j++) /* PhiG comes with leading dimension nev */
      for (PetscInt i = 0; i < nconv; i++) ref->PhiG[i + j * nconv] = PhiG[i + j * nev];
  }
  PetscCall(PetscFree3(w2, HPhi, PhiG));
  PetscCall(PetscMalloc2(PetscMax(t * ref->r, 1), &ref->HPr, PetscMax(ref->r * a, 1), &ref->PrG));
  PetscCall(KFSystemRigidIO(sys, &ref->r, ref->HPr, ref->PrG));
  PetscFunctionReturn(0);
}

PetscErrorCode KFFullReferenceDestroy_Private(KFFullReference *ref)
{
  PetscFunctionBegin;
  if (!ref->w2) PetscFunctionReturn(0);
  PetscCall(PetscFree3(ref->w2, ref->HPhi, ref->PhiG));
  PetscCall(PetscFree2(ref->HPr, ref->PrG));
  PetscCall(PetscFree(ref->Cm));
  PetscCall(PetscFree(ref->D));
  PetscCall(MatDestroy(&ref->V));
  PetscCall(PetscMemzero(ref, sizeof(*ref)));
  PetscFunctionReturn(0);
}

/* Full-order response: rigid modes, computed flexible modes, and the modes not computed by their first two moments:
   sum_{i not computed} H phi_i phi_i^T G / (omega_i^2 - w^2) = R^0 + w^2 R^1 + O(w^4 / omega_i^4), with
   R^k = L^k - sum_{i computed} H phi_i phi_i^T G / omega_i^(2k+2) (L^k = H (K+ M)^k K+ G). The w^2 term makes the
   truncation error (w / omega_i)^4 of the residual instead of (w / omega_i)^2: with modes to 3x the band's top, 1e-2
   of the residual instead of 1e-1. The residuals are differences of large numbers when the computed modes include
   very soft ones (1/omega_i^4 in R^1), so: none when every mode was computed, and R^1 dropped when it is below the
   accuracy of L^1 itself (||R^1|| <= 1e-8 ||L^1||). L: nmom blocks of t x a (nmom 1: the static residual
   alone). Tre, Tim: nw blocks of t x a. */
PetscErrorCode KFFullFRF_Private(const KFFullReference *ref, PetscInt t, PetscInt a, PetscInt nmom, const PetscReal L[], const KFDamping *d, const PetscInt quantity[], PetscInt nw, const PetscReal w[], PetscReal Tre[], PetscReal Tim[])
{
  const PetscInt n = ref->r + ref->n;
  PetscReal     *lam, *HPhi, *PhiG, *resid;

  PetscFunctionBegin;
  PetscCall(PetscMalloc4(n, &lam, t * n, &HPhi, n * a, &PhiG, 2 * t * a, &resid));
  for (PetscInt k = 0; k < n; k++) lam[k] = k < ref->r ? 0 : ref->w2[k - ref->r];
  PetscCall(PetscArraycpy(HPhi, ref->HPr, t * ref->r));
  PetscCall(PetscArraycpy(HPhi + t * ref->r, ref->HPhi, t * ref->n));
  for (PetscInt j = 0; j < a; j++) {
    for (PetscInt k = 0; k < ref->r; k++) PhiG[k + j * n] = ref->PrG[k + j * ref->r];
    for (PetscInt k = 0; k < ref->n; k++) PhiG[ref->r + k + j * n] = ref->PhiG[k + j * ref->n];
  }
  PetscCall(KFDampedModalFRF(n, lam, t, HPhi, a, PhiG, d, ref->Cm, ref->nc, quantity, 1e-300, nw, w, Tre, Tim));
  for (PetscInt j = 0; j < a; j++)
    for (PetscInt i = 0; i < t; i++) {
      PetscReal s0 = L[i + j * t], s1 = nmom > 1 ? L[t * a + i + j * t] : 0;
      for (PetscInt k = 0; k < ref->n; k++) {
        const PetscReal rk = ref->HPhi[i + k * t] / ref->w2[k] * ref->PhiG[k + j * ref->n];

        s0 -= rk;
        if (nmom > 1) s1 -= rk / ref->w2[k];
      }
      resid[i + j * t]         = s0;
      resid[t * a + i + j * t] = s1;
    }
  {
    PetscReal n0 = 0, n1 = 0, l1 = 0, wmax = nw ? w[nw - 1] : 0;

    for (PetscInt e = 0; e < t * a; e++) {
      n0 += resid[e] * resid[e];
      n1 += resid[t * a + e] * resid[t * a + e];
      if (nmom > 1) l1 += L[t * a + e] * L[t * a + e];
    }
    /* R^1 is kept where it is above its own noise and the small correction it must be. Noise: L^1 comes from block
       solves (refined to a residual of 1e-6) and R^1 = L^1 - (computed part) cancels, so below 1e-8 ||L^1|| it is
       taken for noise. Small: ||R^1|| w_max^2 <= ||R^0|| / 4; beyond that R^1 is the difference of large numbers
       (hundreds of computed modes, 1/omega_i^4), which acceleration outputs multiply by w^2 again: a 2,012-dof panel
       scene with 640 computed modes gave a reference 4 times its own peak off the dense one with R^1 kept there. */
    const PetscBool keep0 = (PetscBool)!ref->complete;
    const PetscBool keep1 = (PetscBool)(keep0 && nmom > 1 && n1 > 1e-16 * l1 && PetscSqrtReal(n1) * wmax * wmax <= 0.25 * PetscSqrtReal(n0));

    PetscCall(PetscInfo(NULL, "full-order reference's residual: %" PetscInt_FMT " modes, ||R0|| %g, ||R1|| w_max^2 %g, ||L1|| %g: static term %s, mass-weighted term %s\n", ref->n, (double)PetscSqrtReal(n0), (double)(PetscSqrtReal(n1) * wmax * wmax), (double)PetscSqrtReal(l1), keep0 ? "kept" : "dropped", keep1 ? "kept" : "dropped"));
    for (PetscInt e = 0; e < t * a; e++) {
      if (!keep0) resid[e] = 0;
      if (!keep1) resid[t * a + e] = 0;
      if (ref->D) resid[e] += ref->D[e]; /* the static response of M's null space (dense path) */
    }
  }
  /* the residual is quasi-static: structural damping divides it by 1 + i g; then the output's quantity */
  for (PetscInt f = 0; f < nw; f++)
    for (PetscInt j = 0; j < a; j++)
      for (PetscInt i = 0; i < t; i++) {
        const PetscInt  e  = i + j * t;
        const PetscReal rr = resid[e] + w[f] * w[f] * resid[t * a + e], g = d->g;
        PetscReal       xr = rr / (1 + g * g), xi = -rr * g / (1 + g * g), yr = xr, yi = xi;

        if (quantity && quantity[i] == KF_QUANTITY_VELOCITY) {
          yr = -w[f] * xi;
          yi = w[f] * xr;
        } else if (quantity && quantity[i] == KF_QUANTITY_ACCELERATION) {
          yr = -w[f] * w[f] * xr;
          yi = -w[f] * w[f] * xi;
        }
        Tre[f * t * a + e] += yr;
        Tim[f * t * a + e] += yi;
      }
  PetscCall(PetscFree4(lam, HPhi, PhiG, resid));
  PetscFunctionReturn(0);
}

/* the rigid-body and mechanism part of the full-order response: the geometric rigid modes (H Phi_r, Phi_r^T G) with
   the damping model the full response uses (their block of the modal viscous damping, Rayleigh; modal ratios and
   structural damping are zero on them) */
PetscErrorCode KFFullRigidFRF_Private(const KFFullReference *ref, PetscInt t, PetscInt a, const KFDamping *d, const PetscInt quantity[], PetscInt nw, const PetscReal w[], PetscReal Tre[], PetscReal Tim[])
{
  const PetscInt nr = ref->r, m = ref->r + ref->n;
  PetscReal     *lam, *Crr = NULL;

  PetscFunctionBegin;
  PetscCall(PetscCalloc1(PetscMax(nr, 1), &lam));
  if (ref->Cm && ref->nc >= nr && nr) {
    PetscCall(PetscMalloc1(nr * nr, &Crr));
    for (PetscInt j = 0; j < nr; j++)
      for (PetscInt i = 0; i < nr; i++) Crr[i + j * nr] = ref->Cm[i + j * m];
  }
  PetscCall(KFDampedModalFRF(nr, lam, t, ref->HPr, a, ref->PrG, d, Crr, nr, quantity, 0, nw, w, Tre, Tim));
  PetscCall(PetscFree(Crr));
  PetscCall(PetscFree(lam));
  PetscFunctionReturn(0);
}
