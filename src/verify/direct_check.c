/*
  The verification's reference checked against the truth: at a few frequencies of the band, away from the reference's
  resonances, one direct solve of the full-order system gives H_S X exactly; the reference evaluated at w under the
  same damping must agree with it. Undamped, or with only modal ratios (whose equivalent viscous matrix is built on
  the reference's own modes and adds the same term to both sides: damped_check.c), it is one MUMPS LDL^T of the
  symmetric indefinite K_S - w^2 M_S, here; with Rayleigh, structural damping or the bodies' damping matrices it is the
  real 2 x 2 block form of the complex system, damped_check.c. What can go wrong in the reference is its modal content
  (modes missed, rigid modes, the residual of the modes not computed, M's null space) and its damping. A disagreement
  above -kf_verify_check_rtol of the pair's peak fails the run (exit 3) naming the frequency, the angle and the pair:
  a verdict against a wrong reference would be wrong.
*/
#include <kryflex/reducerimpl.h>

/* The geometric rigid modes Phi_r are exact in the reference (and in the reduced models) but carry a little energy in
   an exported K_S, whose entries are rounded (8 to 12 digits in a punch): K_r = Phi_r^T K_S Phi_r is not zero, and a
   plain direct solve of the rounded K_S answers 1/(K_r - w^2) where the model as kryflex defines it has -1/w^2 (near
   the band's bottom, ||K_r|| / w^2 of the rigid response: the export's rounding, not an error of the reference). So
   the truth is solved as kryflex defines the model: the rigid part exactly, -H Phi_r Phi_r^T G / w^2, and the
   flexible part X = P (K_S - w^2 M_S)^-1 P^T G with P = I - Phi_r Phi_r^T M_S (exact to second order in the
   rounding). The rounding's size, K_r's largest entry against the first flexible eigenvalue, is recorded
   (reference_check_rigid_energy). */
static PetscErrorCode KFRigidEnergy(KFSystem sys, const KFFullReference *ref, PetscReal *energy)
{
  const PetscInt r = ref->r;
  Mat            Phi, KPhi;
  PetscReal     *Kr, emax = 0;

  PetscFunctionBegin;
  *energy = 0;
  if (!r) PetscFunctionReturn(0);
  PetscCall(KFSystemGetRigidModes(sys, &Phi, NULL));
  PetscCall(KFMatMultExtended(sys->Ks, Phi, &KPhi)); /* in double-double: K Phi is a small difference of large terms */
  PetscCall(PetscMalloc1(r * r, &Kr));
  PetscCall(KFMatTransposeMatMultGather(Phi, KPhi, Kr));
  PetscCall(MatDestroy(&KPhi));
  for (PetscInt i = 0; i < r * r; i++) emax = PetscMax(emax, PetscAbsReal(Kr[i]));
  *energy = ref->n ? emax / ref->w2[0] : emax;
  PetscCall(PetscFree(Kr));
  PetscFunctionReturn(0);
}

/* npts frequencies (rad/s) in the band, one per log-equal slice, each the geometric middle of the widest gap
   between the reference's resonances (and the slice's ends) in its slice: as far from a resonance as the slice allows */
static PetscErrorCode KFCheckFrequencies(KFReducer r, const KFFullReference *ref, PetscInt npts, PetscReal w[])
{
  const PetscReal f0 = r->band[0] > 0 ? r->band[0] : 1e-3 * r->band[1], f1 = r->band[1];
  PetscReal      *pts;

  PetscFunctionBegin;
  PetscCall(PetscMalloc1(ref->n + 2, &pts));
  for (PetscInt s = 0; s < npts; s++) {
    const PetscReal lo = f0 * PetscPowReal(f1 / f0, (PetscReal)s / npts), hi = f0 * PetscPowReal(f1 / f0, (PetscReal)(s + 1) / npts);
    PetscInt        m = 0;
    PetscReal       best = -1, at = PetscSqrtReal(lo * hi);

    pts[m++] = lo;
    for (PetscInt k = 0; k < ref->n; k++) {
      const PetscReal f = PetscSqrtReal(PetscMax(ref->w2[k], 0)) / (2 * PETSC_PI);
      if (f > lo && f < hi) pts[m++] = f;
    }
    pts[m++] = hi;
    PetscCall(PetscSortReal(m, pts));
    for (PetscInt i = 0; i + 1 < m; i++) {
      const PetscReal gap = PetscLogReal(pts[i + 1] / pts[i]);
      if (gap > best) {
        best = gap;
        at   = PetscSqrtReal(pts[i] * pts[i + 1]);
      }
    }
    w[s] = 2 * PETSC_PI * at;
  }
  PetscCall(PetscFree(pts));
  PetscFunctionReturn(0);
}

/* the direct solves at the evaluation point's configuration (sys), kept in p until the reference's grid exists */
PetscErrorCode KFEvalPointDirectSolves_Private(KFReducer r, KFSystem sys, KFEvalPoint *p)
{
  PetscInt       a, t, npts = r->verify_check_points;
  Mat            Ms, Ks, G, Ht;
  PetscLogDouble t0, t1;
  KFDamping      damp;
  PetscBool      viscous;

  PetscFunctionBegin;
  p->nchk = 0;
  if (!npts || !p->ref.w2) PetscFunctionReturn(0);
  PetscCall(PetscTime(&t0));
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, NULL, NULL, &a, &t));
  PetscCall(KFSystemGetMatrices(sys, &Ms, &Ks, &G, &Ht));
  PetscCall(PetscCalloc3(npts, &p->chk_w, npts * t * a, &p->chk_T, npts * t * a, &p->chk_Ti));
  PetscCall(KFCheckFrequencies(r, &p->ref, npts, p->chk_w));
  PetscCall(KFCheckDampingModel_Private(r, &damp, &viscous));
  if (viscous || damp.alpha != 0 || damp.beta != 0 || damp.g != 0) { /* damped_check.c */
    p->nchk = npts;
    PetscCall(KFEvalPointDampedSolves_Private(r, sys, p, &damp, viscous));
  } else {
    Mat           A, F, Gd;
    MatFactorInfo info;
    IS            rp, cp;

    /* one analysis for every frequency (K_S - w^2 M_S has one pattern), one numerical factorization each */
    PetscCall(MatDuplicate(Ks, MAT_COPY_VALUES, &A));
    PetscCall(MatAXPY(A, -1.0, Ms, DIFFERENT_NONZERO_PATTERN));
    PetscCall(MatSetOption(A, MAT_SYMMETRIC, PETSC_TRUE));
    PetscCall(MatGetFactor(A, MATSOLVERMUMPS, MAT_FACTOR_CHOLESKY, &F)); /* LDL^T (MUMPS SYM=2): A is indefinite */
    PetscCall(MatGetOrdering(A, MATORDERINGNATURAL, &rp, &cp));
    PetscCall(MatFactorInfoInitialize(&info));
    PetscCall(MatCholeskyFactorSymbolic(F, A, rp, &info));
    /* MUMPS wants a dense right-hand side of its own (G may be a sub-matrix view); the loads self-equilibrated */
    PetscCall(MatConvert(G, MATDENSE, MAT_INITIAL_MATRIX, &Gd));
    if (p->ref.r) PetscCall(KFProjectFlexible(sys, Gd, PETSC_TRUE)); /* P^T G */
    for (PetscInt s = 0; s < npts; s++) {
      Mat X;

      PetscCall(MatCopy(Ks, A, SUBSET_NONZERO_PATTERN));
      PetscCall(MatAXPY(A, -p->chk_w[s] * p->chk_w[s], Ms, SUBSET_NONZERO_PATTERN));
      PetscCall(MatCholeskyFactorNumeric(F, A, &info));
      PetscCall(MatDuplicate(Gd, MAT_DO_NOT_COPY_VALUES, &X));
      PetscCall(MatMatSolve(F, Gd, X));
      /* two steps of refinement against A itself: near the band's bottom A is nearly singular on the rigid modes
         (eigenvalues -w^2 m), and the truth must not carry eps cond(A) */
      for (PetscInt it = 0; it < 2; it++) {
        Mat Rr, dX;

        PetscCall(MatMatMult(A, X, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &Rr));
        PetscCall(MatAYPX(Rr, -1.0, Gd, SAME_NONZERO_PATTERN)); /* R = G - A X */
        PetscCall(MatDuplicate(X, MAT_DO_NOT_COPY_VALUES, &dX));
        PetscCall(MatMatSolve(F, Rr, dX));
        PetscCall(MatAXPY(X, 1.0, dX, SAME_NONZERO_PATTERN));
        PetscCall(MatDestroy(&dX));
        PetscCall(MatDestroy(&Rr));
      }
      if (p->ref.r) PetscCall(KFProjectFlexible(sys, X, PETSC_FALSE)); /* P X */
      PetscCall(KFMatTransposeMatMultGather(Ht, X, &p->chk_T[s * t * a])); /* t x a, column-major */
      for (PetscInt j = 0; j < a; j++) /* the rigid part, exact: -H Phi_r Phi_r^T G / w^2 */
        for (PetscInt q = 0; q < t; q++)
          for (PetscInt k = 0; k < p->ref.r; k++) p->chk_T[s * t * a + q + j * t] -= p->ref.HPr[q + k * t] * p->ref.PrG[k + j * p->ref.r] / (p->chk_w[s] * p->chk_w[s]);
      PetscCall(MatDestroy(&X));
    }
    PetscCall(MatDestroy(&Gd));
    PetscCall(ISDestroy(&rp));
    PetscCall(ISDestroy(&cp));
    PetscCall(MatDestroy(&F));
    PetscCall(MatDestroy(&A));
  }
  {
    PetscReal energy;

    PetscCall(KFRigidEnergy(sys, &p->ref, &energy));
    if (p->interest >= 0) PetscCall(KFReducerResultScalar_Private(r, p->interest, "reference_check_rigid_energy", energy));
  }
  p->nchk = npts;
  PetscCall(PetscTime(&t1));
  r->verify_check_seconds += t1 - t0;
  PetscFunctionReturn(0);
}

/* the comparison, once the reference is on its grid (its peaks per pair): results, a progress line, exit 3 beyond
   the tolerance */
PetscErrorCode KFEvalPointCheckReference_Private(KFReducer r, KFEvalPoint *p)
{
  PetscInt   a, t, ta, nrev, fw = -1, pw = -1;
  PetscReal *pk, *Tre, *Tim, top = 0, worst = 0;
  KFDamping  damp;
  PetscBool  viscous;
  char       label[128];
  MPI_Comm   comm = PetscObjectComm((PetscObject)r);

  PetscFunctionBegin;
  if (!p->nchk) PetscFunctionReturn(0);
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, &nrev, NULL, &a, &t));
  ta = t * a;
  PetscCall(KFCheckDampingModel_Private(r, &damp, &viscous));
  PetscCall(PetscCalloc1(PetscMax(ta, 1), &pk));
  PetscCall(PetscMalloc2(p->nchk * ta, &Tre, p->nchk * ta, &Tim));
  for (PetscInt f = 0; f < p->nw; f++)
    for (PetscInt k = 0; k < ta; k++) pk[k] = PetscMax(pk[k], PetscSqrtReal(p->Tre[f * ta + k] * p->Tre[f * ta + k] + p->Tim[f * ta + k] * p->Tim[f * ta + k]));
  for (PetscInt k = 0; k < ta; k++) top = PetscMax(top, pk[k]);
  {
    KFFullReference same = p->ref; /* the same modes under the damping the direct solves used */

    if (!viscous) {
      same.Cm = NULL;
      same.nc = 0;
    }
    PetscCall(KFFullFRF_Private(&same, t, a, p->nmom, p->L0, &damp, NULL, p->nchk, p->chk_w, Tre, Tim));
  }
  for (PetscInt s = 0; s < p->nchk; s++)
    for (PetscInt k = 0; k < ta; k++) {
      const PetscReal dre = Tre[s * ta + k] - p->chk_T[s * ta + k], dim = Tim[s * ta + k] - p->chk_Ti[s * ta + k];
      const PetscReal e   = PetscSqrtReal(dre * dre + dim * dim) / PetscMax(PetscMax(pk[k], KF_FRF_PAIR_FLOOR * top), 1e-300);

      if (!(e <= worst)) {
        worst = e;
        fw    = s;
        pw    = k;
      }
    }
  if (p->interest >= 0) { /* both sides of the check, for scripts that verify it: (t, a, nchk) each */
    const PetscInt shape[3] = {t, a, p->nchk};
    PetscReal     *fhz;

    PetscCall(PetscMalloc1(p->nchk, &fhz));
    for (PetscInt s = 0; s < p->nchk; s++) fhz[s] = p->chk_w[s] / (2 * PETSC_PI);
    PetscCall(KFReducerResultSet_Private(r, p->interest, "reference_check_frequencies_hz", 1, &p->nchk, fhz));
    PetscCall(KFReducerResultSet_Private(r, p->interest, "reference_check_truth_re", 3, shape, p->chk_T));
    PetscCall(KFReducerResultSet_Private(r, p->interest, "reference_check_truth_im", 3, shape, p->chk_Ti));
    PetscCall(KFReducerResultSet_Private(r, p->interest, "reference_check_reference_re", 3, shape, Tre));
    PetscCall(KFReducerResultSet_Private(r, p->interest, "reference_check_reference_im", 3, shape, Tim));
    PetscCall(PetscFree(fhz));
  }
  PetscCall(PetscFree(pk));
  PetscCall(PetscFree2(Tre, Tim));
  PetscCall(KFReducerConfigPlace_Private(nrev, p->angles, label, sizeof(label)));
  if (p->interest >= 0) {
    PetscCall(KFReducerResultScalar_Private(r, p->interest, "reference_check_error", worst));
    PetscCall(KFReducerResultScalar_Private(r, p->interest, "reference_check_frequency_hz", p->chk_w[fw] / (2 * PETSC_PI)));
  }
  if (!(worst <= r->verify_check_worst)) {
    r->verify_check_worst    = worst;
    r->verify_check_worst_hz = p->chk_w[fw] / (2 * PETSC_PI);
  }
  PetscCall(KFReducerResultScalar_Private(r, -1, "reference_check_error", r->verify_check_worst));
  PetscCall(KFReducerResultScalar_Private(r, -1, "reference_check_rtol", r->verify_check_rtol));
  PetscCall(KFReducerResultScalar_Private(r, -1, "time_reference_check", (PetscReal)r->verify_check_seconds));
  PetscCall(KFProgress(comm, "reference check %s: %" PetscInt_FMT " direct solves of the full order, worst disagreement %.2e of the pair's peak at %.4g Hz (allowed %.0e)", label, p->nchk, (double)worst, (double)(p->chk_w[fw] / (2 * PETSC_PI)), (double)r->verify_check_rtol));
  PetscCheck(worst <= r->verify_check_rtol, comm, PETSC_ERR_NOT_CONVERGED, "the full-order reference %s disagrees with a direct solve of the full system at %.6g Hz by %.3e of the peak of output %" PetscInt_FMT " <- input %" PetscInt_FMT " (allowed %.1e): the verification's modes are wrong or incomplete there, so no verdict is given; raise -kf_verify_modes or -kf_verify_cover, or take the dense reference (-kf_verify_dense_max_dofs above the system size)",
             label, (double)(p->chk_w[fw] / (2 * PETSC_PI)), (double)worst, pw % t, pw / t, (double)r->verify_check_rtol);
  PetscFunctionReturn(0);
}
