/*
  The estimated verdict certified by the mode count (-kf_verify auto from -kf_verify_certified_min_dofs system dofs).

  The estimator measures every candidate against the search's richest candidate (every visit's whole Krylov basis)
  instead of the full order. Its dangerous failure is a full-order resonance in or near the band that the richest
  candidate does not hold: then no candidate holds it and the estimate passes what the full order fails. The richest
  candidate is a Galerkin (Rayleigh-Ritz) model of the full order at every configuration, so by the Poincare
  separation theorem its k-th eigenvalue is >= the full order's k-th: its count of modes below a frequency is <= the
  full order's. Equal counts at every configuration (angles of interest and midpoints) prove that it misses no mode
  below the cut; the full order's count is Sylvester's inertia of K_S - sigma M_S (src/verify/mode_count.c), the
  bodies' shifted interiors factored once, a small interface problem per configuration. Not equal anywhere: the
  verdict is measured instead (KFReducerSolve's search builds the full order's references, solve.c).

  The cut is -kf_verify_certified_cover (default 1.5) x the band's top: a mode just above the band shapes the
  response in it (its quasi-static tail, 1 / (1 - (f / f_m)^2): 1.8 times its static share at the band's top for
  f_m = 1.5 f_top), while one beyond that is carried to within the moments' accuracy by the static and low-frequency
  moments the richest candidate matches. The count proves the number of modes, not their shapes or residues: a mode
  the richest candidate holds at the wrong frequency is the estimator's own error, which it reports as such.
*/
#include <kryflex/reducerimpl.h>

PETSC_INTERN PetscErrorCode KFSystemShiftedInertia(KFSystem, PetscReal, KFBodyFactors, PetscInt *, PetscInt *);
PETSC_INTERN PetscErrorCode KFModeCountBodyFactors(KFSystem, const char[], PetscReal, PetscBool, KFBodyFactors *);

/* The full order's modes (rigid and flexible) below the cut at every evaluation point: count[e] and the shift
   sigma[e] it was taken at (omega^2; 1e-6 below the cut where the cut is a natural frequency there); nrigid[e] the
   rigid-body and mechanism modes among them. Body-wise, a configuration needs only its interface problem, so the
   system is not assembled there (7 assemblies and rigid-mode sets were a fifth of the count at 57k dofs), and its
   rigid and mechanism modes are those the visits found: their number is the scene's, 6 + revolute joints less what
   the constraints hold, whatever the angles. sys is left at the last point's angles, body-wise unassembled (the
   search's expansion points set their angles again, src/reducer/shifts.c). Unless expansion points will factor the
   system again (-kf_max_factorizations), the visits' solves are over here: the count takes the system's body factors
   over and factors each body's K_b - sigma M_b on its MUMPS analysis (the same pattern where M_b's lies within K_b's:
   the ordering and symbolic factorization, 0.9 s of the count's 4.7 s at 57k dofs under load, not made again). */
PetscErrorCode KFReducerCertifyCount_Private(KFReducer r, KFSystem sys, PetscInt neval, const KFEvalPoint evals[], PetscInt count[], PetscInt nrigid[], PetscReal sigma[])
{
  MPI_Comm       comm = PetscObjectComm((PetscObject)r);
  const PetscReal w = 2 * PETSC_PI * r->verify_certified_cover * r->band[1];
  KFBodyFactors  bf = NULL;
  PetscBool      bodywise;
  PetscLogDouble t0, t1;
  PetscInt       nrig = 0;

  PetscFunctionBegin;
  PetscCall(PetscTime(&t0));
  PetscCall(KFModeCountBodyFactors(sys, ((PetscObject)r)->prefix, w * w, (PetscBool)!r->max_factorizations, &bf));
  bodywise = (PetscBool)!!bf;
  if (bodywise) PetscCall(KFSystemRigidIO(sys, &nrig, NULL, NULL)); /* the last visit's, made already */
  for (PetscInt e = 0; e < neval; e++) {
    PetscInt nnull;

    PetscCall(KFInterruptCheck(comm));
    if (bodywise) {
      PetscCall(KFSystemSetInterfaceAngles(sys, evals[e].angles));
      nrigid[e] = nrig;
    } else {
      PetscCall(KFSystemSetAngles(sys, evals[e].angles));
      PetscCall(KFSystemRigidIO(sys, &nrigid[e], NULL, NULL));
    }
    sigma[e] = w * w;
    PetscCall(KFSystemShiftedInertia(sys, sigma[e], bf, &count[e], &nnull));
    if (nnull) { /* the whole system factored 1e-6 below the cut: it needs the matrices */
      if (bodywise) PetscCall(KFSystemSetAngles(sys, evals[e].angles));
      sigma[e] *= 1 - 1e-6;
      PetscCall(KFSystemShiftedInertia(sys, sigma[e], NULL, &count[e], &nnull));
    }
    PetscCheck(nnull == 0, comm, PETSC_ERR_CONV_FAILED, "the certificate's mode count: K_S - sigma M_S is singular at the cut %g Hz and 1e-6 below it; move the cut with -kf_verify_certified_cover", (double)(w / (2 * PETSC_PI)));
  }
  PetscCall(KFBodyFactorsDestroy(&bf));
  PetscCall(PetscTime(&t1));
  PetscCall(KFReducerResultScalar_Private(r, -1, "time_certificate_count", (PetscReal)(t1 - t0)));
  PetscCall(KFProgress(comm, "  certificate: the full order's flexible modes below %.6g Hz counted at %" PetscInt_FMT " configurations (inertia of K_S - sigma M_S, %.3g s, %s)", (double)(w / (2 * PETSC_PI)), neval, (double)(t1 - t0), bodywise ? "body-wise" : "monolithic"));
  PetscFunctionReturn(0);
}

/* The richest candidate's count below the same shifts (its reassembled systems evals[e].rich, their eigenvalues)
   against the full order's: *certified when equal at every point. Recorded: the counts (flexible modes) per point,
   the cut, and whether it certified; a failure names the first configuration and both counts. */
PetscErrorCode KFReducerCertifyCompare_Private(KFReducer r, PetscInt neval, const KFEvalPoint evals[], const PetscInt count[], const PetscInt nrigid[], const PetscReal sigma[], PetscBool *certified)
{
  MPI_Comm   comm = PetscObjectComm((PetscObject)r);
  PetscInt   nrev, bad = -1;
  PetscReal *fc, *rc, cut = PetscSqrtReal(sigma[0]) / (2 * PETSC_PI);
  char       place[160];

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, &nrev, NULL, NULL, NULL));
  PetscCall(PetscMalloc2(neval, &fc, neval, &rc));
  for (PetscInt e = 0; e < neval; e++) {
    const PetscReal *lambda;
    PetscInt         n, below = 0;

    PetscCheck(evals[e].rich, comm, PETSC_ERR_PLIB, "the certificate needs the estimator's richest candidate at every point");
    PetscCall(KFReducedSystemGetMatrices(evals[e].rich, &n, NULL, NULL, NULL, NULL, NULL, NULL));
    PetscCall(KFReducedSystemGetModes(evals[e].rich, &lambda, NULL, NULL, NULL));
    while (below < n && lambda[below] < sigma[e]) below++;
    fc[e] = (PetscReal)(count[e] - nrigid[e]);
    rc[e] = (PetscReal)(below - nrigid[e]);
    if (below != count[e] && bad < 0) bad = e;
  }
  *certified = (PetscBool)(bad < 0);
  PetscCall(KFReducerResultSet_Private(r, -1, "certificate_full_counts", 1, &neval, fc));
  PetscCall(KFReducerResultSet_Private(r, -1, "certificate_rich_counts", 1, &neval, rc));
  PetscCall(KFReducerResultScalar_Private(r, -1, "certificate_below_hz", cut));
  PetscCall(KFReducerResultScalar_Private(r, -1, "certified", *certified ? 1.0 : 0.0));
  if (*certified) {
    PetscInt lo = count[0] - nrigid[0], hi = lo;

    for (PetscInt e = 1; e < neval; e++) {
      lo = PetscMin(lo, count[e] - nrigid[e]);
      hi = PetscMax(hi, count[e] - nrigid[e]);
    }
    if (lo == hi) PetscCall(PetscSNPrintf(place, sizeof(place), "%" PetscInt_FMT, lo));
    else PetscCall(PetscSNPrintf(place, sizeof(place), "%" PetscInt_FMT "-%" PetscInt_FMT, lo, hi));
    PetscCall(KFReducerNote_Private(r, "verification estimated, certified: errors are estimated against the richest candidate, which holds as many flexible modes as the full order below %.4g Hz (%s, counted by Sylvester's inertia) at each of the %" PetscInt_FMT " configurations (angles of interest and midpoints)", (double)cut, place, neval));
  } else {
    PetscCall(KFReducerConfigPlace_Private(nrev, evals[bad].angles, place, sizeof(place)));
    PetscCall(KFReducerNote_Private(r, "verification measured: the certificate failed %s%s: the full order has %" PetscInt_FMT " flexible modes below %.4g Hz, the richest candidate %" PetscInt_FMT "; the verdict is measured against the full order instead", place, evals[bad].interest < 0 ? " (midpoint)" : "", (PetscInt)fc[bad], (double)cut, (PetscInt)rc[bad]));
  }
  PetscCall(PetscFree2(fc, rc));
  PetscFunctionReturn(0);
}
