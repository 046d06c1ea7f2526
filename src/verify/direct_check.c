/*
  The verification's reference checked against the truth: at a few frequencies of the band, away from the reference's
  resonances, one direct solve of the full-order system gives H_S X exactly; the reference evaluated at w under the
  same damping must agree with it. Undamped, or with only modal ratios (whose equivalent viscous matrix is built on
  the reference's own modes and adds the same term to both sides: damped_check.c), it is a solve of the symmetric
  indefinite K_S - w^2 M_S, here: body-wise where the scene allows (the bodies' K_b - w^2 M_b factored once per check
  frequency for every angle, the frequencies common to all angles), else one MUMPS LDL^T per angle and frequency;
  either way refined against K_S - w^2 M_S and taken only at a backward error of a few eps. With Rayleigh, structural damping or the bodies' damping matrices it is the
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
   between the resonances f[] (Hz; every evaluation point's, and the slice's ends) in its slice: as far from a
   resonance of any point as the slice allows. One set for all points, so that the bodies' factorizations at a check
   frequency serve every angle (KFDirectSolvesBodywise). */
PetscErrorCode KFCheckFrequencies_Private(KFReducer r, PetscInt nf, const PetscReal f[], PetscInt npts, PetscReal w[])
{
  const PetscReal f0 = r->band[0] > 0 ? r->band[0] : 1e-3 * r->band[1], f1 = r->band[1];
  PetscReal      *pts;

  PetscFunctionBegin;
  PetscCall(PetscMalloc1(nf + 2, &pts));
  for (PetscInt s = 0; s < npts; s++) {
    const PetscReal lo = f0 * PetscPowReal(f1 / f0, (PetscReal)s / npts), hi = f0 * PetscPowReal(f1 / f0, (PetscReal)(s + 1) / npts);
    PetscInt        m = 0;
    PetscReal       best = -1, at = PetscSqrtReal(lo * hi);

    pts[m++] = lo;
    for (PetscInt k = 0; k < nf; k++)
      if (f[k] > lo && f[k] < hi) pts[m++] = f[k];
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

/* every checked point's resonances (Hz) in one array */
static PetscErrorCode KFAllResonances(PetscInt neval, const KFEvalPoint evals[], PetscInt *nf, PetscReal **f)
{
  PetscInt n = 0;

  PetscFunctionBegin;
  for (PetscInt e = 0; e < neval; e++)
    if (evals[e].ref.w2) n += evals[e].ref.n;
  PetscCall(PetscMalloc1(n + 1, f));
  *nf = 0;
  for (PetscInt e = 0; e < neval; e++)
    for (PetscInt k = 0; evals[e].ref.w2 && k < evals[e].ref.n; k++) (*f)[(*nf)++] = PetscSqrtReal(PetscMax(evals[e].ref.w2[k], 0)) / (2 * PETSC_PI);
  PetscFunctionReturn(0);
}

/* The truth at w from X = A^-1 P^T G (system layout): projected, read by the outputs, and the rigid part added
   exactly, -H Phi_r Phi_r^T G / w^2; into T (t x a, column-major) */
static PetscErrorCode KFCheckTruth(KFSystem sys, const KFFullReference *ref, PetscReal w, PetscInt t, PetscInt a, Mat X, PetscReal T[])
{
  Mat Ht;

  PetscFunctionBegin;
  PetscCall(KFSystemGetMatrices(sys, NULL, NULL, NULL, &Ht));
  if (ref->r) PetscCall(KFProjectFlexible(sys, X, PETSC_FALSE)); /* P X */
  PetscCall(KFMatTransposeMatMultGather(Ht, X, T));
  for (PetscInt j = 0; j < a; j++)
    for (PetscInt q = 0; q < t; q++)
      for (PetscInt k = 0; k < ref->r; k++) T[q + j * t] -= ref->HPr[q + k * t] * ref->PrG[k + j * ref->r] / (w * w);
  PetscFunctionReturn(0);
}

/* A = K_S - w^2 M_S at the system's configuration, and the loads P^T G as a dense matrix of MUMPS' own (G may be a
   sub-matrix view) */
static PetscErrorCode KFCheckOperator(KFSystem sys, PetscBool project, PetscReal w, Mat *A, Mat *Gd)
{
  Mat Ms, Ks, G;

  PetscFunctionBegin;
  PetscCall(KFSystemGetMatrices(sys, &Ms, &Ks, &G, NULL));
  PetscCall(MatDuplicate(Ks, MAT_COPY_VALUES, A));
  PetscCall(MatAXPY(*A, -w * w, Ms, DIFFERENT_NONZERO_PATTERN));
  PetscCall(MatSetOption(*A, MAT_SYMMETRIC, PETSC_TRUE));
  PetscCall(MatConvert(G, MATDENSE, MAT_INITIAL_MATRIX, Gd));
  if (project) PetscCall(KFProjectFlexible(sys, *Gd, PETSC_TRUE)); /* P^T G: the loads self-equilibrated */
  PetscFunctionReturn(0);
}

/* the solve X = A^-1 Gd by one of the two ways (F: a MUMPS factor of A; else the body-wise operator), then two
   refinement steps against A itself: near the band's bottom A is nearly singular on the rigid modes (eigenvalues
   -w^2 m), and the truth must not carry eps cond(A). res: the normwise backward error after,
   ||Gd - A X||_F / (||A||_F ||X||_F + ||Gd||_F) (a backward-stable solve's is a few eps; the residual relative to
   Gd alone would grow with cond(A) near the band's bottom whichever way solved it). */
static PetscErrorCode KFCheckSolve(KFSystem sys, Mat F, KFBodyFactors bf, KFBodywiseOp op, Mat A, Mat Gd, Mat X, PetscReal *res)
{
  Mat       R = NULL, dX;
  PetscReal ng, nr, na, nx;

  PetscFunctionBegin;
  if (F) PetscCall(MatMatSolve(F, Gd, X));
  else PetscCall(KFBodywiseOpSolve(sys, bf, op, Gd, X));
  for (PetscInt it = 0; it < 3; it++) {
    PetscCall(MatDestroy(&R));
    PetscCall(MatMatMult(A, X, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &R));
    PetscCall(MatAYPX(R, -1.0, Gd, SAME_NONZERO_PATTERN)); /* R = G - A X */
    if (it == 2) break;
    PetscCall(MatDuplicate(X, MAT_DO_NOT_COPY_VALUES, &dX));
    if (F) PetscCall(MatMatSolve(F, R, dX));
    else PetscCall(KFBodywiseOpSolve(sys, bf, op, R, dX));
    PetscCall(MatAXPY(X, 1.0, dX, SAME_NONZERO_PATTERN));
    PetscCall(MatDestroy(&dX));
  }
  PetscCall(MatNorm(R, NORM_FROBENIUS, &nr));
  PetscCall(MatNorm(Gd, NORM_FROBENIUS, &ng));
  PetscCall(MatNorm(A, NORM_FROBENIUS, &na));
  PetscCall(MatNorm(X, NORM_FROBENIUS, &nx));
  PetscCall(MatDestroy(&R));
  *res = na * nx + ng > 0 ? nr / (na * nx + ng) : 0;
  PetscFunctionReturn(0);
}

/* one MUMPS LDL^T of A (symmetric indefinite: MUMPS SYM=2) and the refined solve: the monolithic way */
static PetscErrorCode KFCheckSolveMonolithic(KFSystem sys, Mat A, Mat Gd, Mat X, PetscReal *res)
{
  Mat           F;
  MatFactorInfo info;
  IS            rp, cp;

  PetscFunctionBegin;
  PetscCall(MatGetFactor(A, MATSOLVERMUMPS, MAT_FACTOR_CHOLESKY, &F));
  PetscCall(MatGetOrdering(A, MATORDERINGNATURAL, &rp, &cp));
  PetscCall(MatFactorInfoInitialize(&info));
  PetscCall(MatCholeskyFactorSymbolic(F, A, rp, &info));
  PetscCall(MatCholeskyFactorNumeric(F, A, &info));
  PetscCall(KFCheckSolve(sys, F, NULL, NULL, A, Gd, X, res));
  PetscCall(ISDestroy(&rp));
  PetscCall(ISDestroy(&cp));
  PetscCall(MatDestroy(&F));
  PetscFunctionReturn(0);
}

/* a refined solve whose backward error stays above KF_CHECK_RESIDUAL is not taken as the truth: the body-wise way is
   then redone by the monolithic factorization (a check frequency near a body's own fixed-interface frequency makes its
   interior factor nearly singular, which refinement against A may not repair) */

/* One evaluation point at one check frequency s, the system at its configuration: the truth into p->chk_T. bf NULL:
   the monolithic way; else the body-wise one, its interface problem made here at the point's angles. *nfact counts
   the numerical factorizations, *resmax the worst residual taken. */
static PetscErrorCode KFCheckPointAt(KFReducer r, KFSystem sys, KFBodyFactors bf, KFEvalPoint *p, PetscInt s, PetscInt *nfact, PetscReal *resmax)
{
  const PetscReal w = p->chk_w[s];
  PetscInt        a, t;
  Mat             A, Gd, X;
  PetscReal       res;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, NULL, NULL, &a, &t));
  PetscCall(KFCheckOperator(sys, (PetscBool)(p->ref.r > 0), w, &A, &Gd));
  PetscCall(MatDuplicate(Gd, MAT_DO_NOT_COPY_VALUES, &X));
  if (bf) {
    KFBodywiseOp op;

    PetscCall(KFBodywiseOpCreate(sys, bf, &op));
    PetscCall(KFCheckSolve(sys, NULL, bf, op, A, Gd, X, &res));
    PetscCall(KFBodywiseOpDestroy(&op));
    if (!(res <= KF_CHECK_RESIDUAL)) {
      PetscCall(KFProgress(PetscObjectComm((PetscObject)r), "reference check at %.4g Hz: the body-wise solve's backward error %.1e is above %.0e, solved again by a factorization of the whole system", (double)(w / (2 * PETSC_PI)), (double)res, (double)KF_CHECK_RESIDUAL));
      bf = NULL;
    }
  }
  if (!bf) {
    PetscCall(KFCheckSolveMonolithic(sys, A, Gd, X, &res));
    (*nfact)++;
  }
  *resmax = PetscMax(*resmax, res);
  PetscCall(KFCheckTruth(sys, &p->ref, w, t, a, X, &p->chk_T[s * t * a]));
  PetscCall(MatDestroy(&X));
  PetscCall(MatDestroy(&Gd));
  PetscCall(MatDestroy(&A));
  PetscFunctionReturn(0);
}

/* the export's rigid energy at point p, the system at its angles (also the iterative check's: refined_check.c) */
PetscErrorCode KFCheckRigidEnergy_Private(KFReducer r, KFSystem sys, KFEvalPoint *p)
{
  PetscReal e;

  PetscFunctionBegin;
  PetscCall(KFSystemComputeRigidModes(sys));
  PetscCall(KFRigidEnergy(sys, &p->ref, &e));
  if (p->interest >= 0) PetscCall(KFReducerResultScalar_Private(r, p->interest, "reference_check_rigid_energy", e));
  PetscFunctionReturn(0);
}

/* the system at point p's angles, its rigid modes, and the export's rigid energy recorded there */
static PetscErrorCode KFCheckConfigure(KFReducer r, KFSystem sys, KFEvalPoint *p, PetscBool energy)
{
  PetscFunctionBegin;
  PetscCall(KFSystemSetAngles(sys, p->angles));
  PetscCall(KFSystemComputeRigidModes(sys));
  if (energy) PetscCall(KFCheckRigidEnergy_Private(r, sys, p));
  PetscFunctionReturn(0);
}

/* Undamped, body-wise: at each check frequency the bodies' K_b - w^2 M_b are factored once and every point's
   jointed system is solved from them with its own small interface problem (the bodies' matrices do not depend on
   the angle, only the joint's transformation of the interface does): npts x bodies factorizations, not
   npts x points. The npts sets of factors are kept together, so that each point's system is assembled once (its
   assembly and rigid modes cost about a factorization at 57k dofs): the memory of npts body-wise factorizations. */
static PetscErrorCode KFDirectSolvesBodywise(KFReducer r, KFSystem sys, PetscInt neval, KFEvalPoint evals[], PetscInt npts, const PetscReal w[], PetscInt *nfact, PetscReal *resmax)
{
  KFScene        s = r->scene;
  KFBodyFactors *bf;

  PetscFunctionBegin;
  PetscCall(PetscCalloc1(npts, &bf));
  for (PetscInt k = 0; k < npts; k++) {
    PetscCall(KFProgress(s->comm, "reference check at %.4g Hz: the %" PetscInt_FMT " bodies' K - w^2 M factored once for every angle", (double)(w[k] / (2 * PETSC_PI)), s->nb));
    PetscCall(KFBodyFactorsCreateShifted(sys, ((PetscObject)r)->prefix, -w[k] * w[k], &bf[k]));
    *nfact += s->nb;
  }
  for (PetscInt e = 0; e < neval; e++) {
    if (!evals[e].ref.w2 || evals[e].chk_done) continue;
    PetscCall(KFInterruptCheck(s->comm));
    PetscCall(KFCheckConfigure(r, sys, &evals[e], PETSC_TRUE));
    for (PetscInt k = 0; k < npts; k++) PetscCall(KFCheckPointAt(r, sys, bf[k], &evals[e], k, nfact, resmax));
  }
  for (PetscInt k = 0; k < npts; k++) PetscCall(KFBodyFactorsDestroy(&bf[k]));
  PetscCall(PetscFree(bf));
  PetscFunctionReturn(0);
}

/* the checks' accounting in the results: the direct solves' factorizations, the points the iteration solved
   (refined_check.c: their steps, the points that fell back to direct solves), the worst backward error taken
   (undamped direct solves and every iterative one) */
static PetscErrorCode KFDirectChecksRecord(KFReducer r, PetscInt nfact, PetscReal resmax, PetscBool damped)
{
  PetscFunctionBegin;
  PetscCall(KFReducerResultScalar_Private(r, -1, "reference_check_factorizations", (PetscReal)nfact));
  PetscCall(KFReducerResultScalar_Private(r, -1, "reference_check_iterative_points", (PetscReal)r->verify_check_iter_points));
  PetscCall(KFReducerResultScalar_Private(r, -1, "reference_check_iterative_steps", (PetscReal)r->verify_check_iter_steps));
  PetscCall(KFReducerResultScalar_Private(r, -1, "reference_check_iterative_steps_max", (PetscReal)r->verify_check_iter_steps_max));
  PetscCall(KFReducerResultScalar_Private(r, -1, "reference_check_fallbacks", (PetscReal)r->verify_check_fallbacks));
  if (!damped || r->verify_check_iter_points) PetscCall(KFReducerResultScalar_Private(r, -1, "reference_check_residual", PetscMax(damped ? 0 : resmax, r->verify_check_iter_residual)));
  PetscFunctionReturn(0);
}

/* Every evaluation point's direct solves, once all the references exist: the check frequencies are common to all
   points (KFCheckFrequencies), so that the undamped check shares the bodies' factorizations between the angles where
   the body-wise solve applies (KFBodywiseApplies; -kf_verify_check_bodywise); otherwise each point's system is
   factored at each frequency (MUMPS LDL^T), and the damped check takes the 2 x 2 block form (damped_check.c). */
PetscErrorCode KFReducerDirectChecks_Private(KFReducer r, PetscInt neval, KFEvalPoint evals[])
{
  PetscInt       a, t, npts = r->verify_check_points, nf = 0, nfact = 0, npoints = 0;
  PetscReal     *f, *w, resmax = 0;
  PetscLogDouble t0, t1;
  KFDamping      damp;
  PetscBool      viscous, damped, bodywise;
  KFSystem       sys;

  PetscFunctionBegin;
  for (PetscInt e = 0; e < neval; e++) {
    if (evals[e].chk_done) continue; /* its truth taken by the iterative check (refined_check.c) */
    evals[e].nchk = 0;
    if (evals[e].ref.w2) npoints++;
  }
  if (!npts) PetscFunctionReturn(0);
  if (!npoints) {
    PetscCall(KFDirectChecksRecord(r, 0, 0, PETSC_FALSE));
    PetscFunctionReturn(0);
  }
  PetscCall(PetscLogEventBegin(KF_EVENT_REDUCER_VERIFY, r, 0, 0, 0));
  PetscCall(PetscTime(&t0));
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, NULL, NULL, &a, &t));
  PetscCall(KFAllResonances(neval, evals, &nf, &f));
  PetscCall(PetscMalloc1(npts, &w));
  PetscCall(KFCheckFrequencies_Private(r, nf, f, npts, w));
  PetscCall(PetscFree(f));
  for (PetscInt e = 0; e < neval; e++) {
    if (!evals[e].ref.w2 || evals[e].chk_done) continue;
    PetscCall(PetscCalloc3(npts, &evals[e].chk_w, npts * t * a, &evals[e].chk_T, npts * t * a, &evals[e].chk_Ti));
    PetscCall(PetscArraycpy(evals[e].chk_w, w, npts));
    evals[e].nchk = npts;
  }
  PetscCall(KFCheckDampingModel_Private(r, &damp, &viscous));
  damped = (PetscBool)(viscous || damp.alpha != 0 || damp.beta != 0 || damp.g != 0);
  PetscCall(KFBodywiseApplies(r->scene, &bodywise));
  bodywise = (PetscBool)(bodywise && r->verify_check_bodywise && !damped);
  PetscCall(KFSystemCreate(r->scene, &sys));
  if (bodywise) PetscCall(KFDirectSolvesBodywise(r, sys, neval, evals, npts, w, &nfact, &resmax));
  else
    for (PetscInt e = 0; e < neval; e++) {
      if (!evals[e].ref.w2 || evals[e].chk_done) continue;
      PetscCall(KFInterruptCheck(r->scene->comm));
      PetscCall(KFCheckConfigure(r, sys, &evals[e], PETSC_TRUE));
      if (damped) {
        PetscCall(KFEvalPointDampedSolves_Private(r, sys, &evals[e], &damp, viscous));
        nfact += npts;
      } else
        for (PetscInt k = 0; k < npts; k++) PetscCall(KFCheckPointAt(r, sys, NULL, &evals[e], k, &nfact, &resmax));
    }
  PetscCall(KFSystemDestroy(&sys));
  PetscCall(PetscFree(w));
  PetscCall(PetscTime(&t1));
  r->verify_check_seconds += t1 - t0;
  PetscCall(KFDirectChecksRecord(r, nfact, resmax, damped));
  PetscCall(PetscLogEventEnd(KF_EVENT_REDUCER_VERIFY, r, 0, 0, 0));
  PetscCall(KFProgress(r->scene->comm, "reference checks: %" PetscInt_FMT " points x %" PetscInt_FMT " frequencies solved directly, %s, %" PetscInt_FMT " numerical factorizations, %.3g s", npoints, npts, bodywise ? "body-wise (the bodies factored once per frequency)" : (damped ? "damped 2 x 2 block form" : "the whole system factored per point and frequency"), nfact, (double)(t1 - t0)));
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
  PetscCall(KFProgress(comm, "reference check %s: %" PetscInt_FMT " %s solves of the full order, worst disagreement %.2e of the pair's peak at %.4g Hz (allowed %.0e)", label, p->nchk, p->chk_done ? "iterated" : "direct", (double)worst, (double)(p->chk_w[fw] / (2 * PETSC_PI)), (double)r->verify_check_rtol));
  PetscCheck(worst <= r->verify_check_rtol, comm, PETSC_ERR_NOT_CONVERGED, "the full-order reference %s disagrees with %s solve of the full system at %.6g Hz by %.3e of the peak of output %" PetscInt_FMT " <- input %" PetscInt_FMT " (allowed %.1e): the verification's modes are wrong or incomplete there, so no verdict is given; raise -kf_verify_modes or -kf_verify_cover, or take the dense reference (-kf_verify_dense_max_dofs above the system size)",
             label, p->chk_done ? "an iterated" : "a direct", (double)(p->chk_w[fw] / (2 * PETSC_PI)), (double)worst, pw % t, pw / t, (double)r->verify_check_rtol);
  PetscFunctionReturn(0);
}
