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
#include <errno.h>
#include <poll.h>
#include <unistd.h>
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
   the ordering and symbolic factorization, 0.9 s of the count's 4.7 s at 57k dofs under load, not made again):
   reuse, which a helper process counting beside the reduction has no factors for (KFReducerCertifyCountWrite). */
PetscErrorCode KFReducerCertifyCount_Private(KFReducer r, KFSystem sys, PetscBool reuse, PetscInt neval, const KFEvalPoint evals[], PetscInt count[], PetscInt nrigid[], PetscReal sigma[])
{
  MPI_Comm       comm = PetscObjectComm((PetscObject)r);
  const PetscReal w = 2 * PETSC_PI * r->verify_certified_cover * r->band[1];
  KFBodyFactors  bf = NULL;
  PetscBool      bodywise;
  PetscLogDouble t0, t1;
  PetscInt       nrig = 0;

  PetscFunctionBegin;
  PetscCall(PetscTime(&t0));
  PetscCall(KFModeCountBodyFactors(sys, ((PetscObject)r)->prefix, w * w, reuse, &bf));
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
  if (r->results) PetscCall(KFReducerResultScalar_Private(r, -1, "time_certificate_count", (PetscReal)(t1 - t0))); /* none in a helper (no solve) */
  PetscCall(KFProgress(comm, "  certificate: the full order's flexible modes below %.6g Hz counted at %" PetscInt_FMT " configurations (inertia of K_S - sigma M_S, %.3g s, %s)", (double)(w / (2 * PETSC_PI)), neval, (double)(t1 - t0), bodywise ? "body-wise" : "monolithic"));
  PetscFunctionReturn(0);
}

/* The count beside the reduction. The full order's counts depend on the scene, the cut and the configurations only,
   not on the reduction: on one process, with a core free, kryflex reduce starts a helper process (a fresh interpreter,
   python/kryflex/count_helper.py) that loads the same scene with the same options and counts by
   KFReducerCertifyCount_Private on its own factors, while this process reduces; the solve takes the helper's counts
   from a pipe where it would count. The message is text: "kfcount1 neval nrev1 seconds", then per configuration its
   nrev1 angles, the count, the rigid and mechanism modes among it and the shift, then "end" (%.17g: the doubles
   read back exactly). Anything else (the helper ended without them, wrote other configurations or another cut, or
   took longer than the reduction had run when it came to the count, at least 30 s) and the count is made here. */
#define KF_COUNT_MAGIC "kfcount1"

/* fd: the read end of the helper's pipe, or -1 (count in-process); the caller keeps it and closes it */
PetscErrorCode KFReducerSetCountSource(KFReducer r, int fd)
{
  PetscMPIInt size;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCallMPI(MPI_Comm_size(PetscObjectComm((PetscObject)r), &size));
  PetscCheck(fd < 0 || size == 1, PetscObjectComm((PetscObject)r), PETSC_ERR_SUP, "the certificate's count beside the reduction is for a run on one process: on more, each counts its share in-process");
  r->count_fd = fd < 0 ? -1 : fd;
  PetscCall(PetscTime(&r->count_t0));
  PetscFunctionReturn(0);
}

/* The helper's side: the reducer set up (KFReducerSetUp) as the reduction's (same scene, same options), the counts at every
   configuration made on factors of its own and written to fd */
PetscErrorCode KFReducerCertifyCountWrite(KFReducer r, int fd)
{
  MPI_Comm       comm = PetscObjectComm((PetscObject)r);
  PetscMPIInt    size;
  PetscBool      certified;
  PetscInt       neval, nrev, nrev1, *count, *nrigid;
  PetscReal     *sigma;
  KFEvalPoint   *evals;
  KFSystem       sys;
  PetscLogDouble t0, t1;
  size_t         cap, len = 0;
  char          *buf;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCheck(size == 1, comm, PETSC_ERR_SUP, "the count beside the reduction runs on one process");
  PetscCall(PetscTime(&t0));
  PetscCheck(r->setupcalled, comm, PETSC_ERR_ORDER, "call KFReducerSetUp() first");
  PetscCall(KFReducerGetVerificationPlan(r, NULL, &certified));
  PetscCheck(certified, comm, PETSC_ERR_ARG_WRONGSTATE, "the verification plan has no certificate: nothing to count");
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, &nrev, NULL, NULL, NULL));
  nrev1 = PetscMax(nrev, 1);
  PetscCall(KFReducerEvalPoints_Private(r, &neval, &evals));
  PetscCall(PetscMalloc3(neval, &count, neval, &nrigid, neval, &sigma));
  PetscCall(KFSystemCreate(r->scene, &sys));
  PetscCall(KFSystemSetConfigurationCount(sys, neval));
  PetscCall(KFSystemSetAngles(sys, evals[0].angles)); /* the rigid and mechanism modes the body-wise count takes */
  PetscCall(KFReducerCertifyCount_Private(r, sys, PETSC_FALSE, neval, evals, count, nrigid, sigma));
  PetscCall(KFSystemDestroy(&sys));
  PetscCall(PetscTime(&t1));
  cap = (size_t)(64 + neval * (nrev1 + 3) * 32);
  PetscCall(PetscMalloc1(cap, &buf));
  len += (size_t)snprintf(buf, cap, KF_COUNT_MAGIC " %" PetscInt_FMT " %" PetscInt_FMT " %.17g\n", neval, nrev1, (double)(t1 - t0));
  for (PetscInt e = 0; e < neval; e++) {
    for (PetscInt j = 0; j < nrev1; j++) len += (size_t)snprintf(buf + len, cap - len, "%.17g ", (double)evals[e].angles[j]);
    len += (size_t)snprintf(buf + len, cap - len, "%" PetscInt_FMT " %" PetscInt_FMT " %.17g\n", count[e], nrigid[e], (double)sigma[e]);
  }
  len += (size_t)snprintf(buf + len, cap - len, "end\n");
  for (size_t off = 0; off < len;) {
    ssize_t n = write(fd, buf + off, len - off);

    if (n < 0 && errno == EINTR) continue;
    PetscCheck(n > 0, comm, PETSC_ERR_FILE_WRITE, "the count's pipe closed: the reduction ended");
    off += (size_t)n;
  }
  PetscCall(PetscFree(buf));
  PetscCall(PetscFree3(count, nrigid, sigma));
  for (PetscInt e = 0; e < neval; e++) PetscCall(KFEvalPointDestroy_Private(&evals[e]));
  PetscCall(PetscFree(evals));
  PetscFunctionReturn(0);
}

/* the helper's message parsed against this solve's configurations and cut; NULL if it is not theirs */
static const char *KFCountParse_Private(KFReducer r, char *buf, PetscInt neval, const KFEvalPoint evals[], PetscInt count[], PetscInt nrigid[], PetscReal sigma[], PetscReal *seconds)
{
  const PetscReal w = 2 * PETSC_PI * r->verify_certified_cover * r->band[1];
  PetscInt        nrev, n, m;
  char           *p = buf, *q;

  (void)KFSceneGetInfo(r->scene, NULL, NULL, &nrev, NULL, NULL, NULL);
  if (strncmp(p, KF_COUNT_MAGIC " ", sizeof(KF_COUNT_MAGIC))) return "it wrote no counts";
  p += sizeof(KF_COUNT_MAGIC);
  n = (PetscInt)strtol(p, &q, 10);
  if (q == p) return "its message is not a count";
  p = q;
  m = (PetscInt)strtol(p, &q, 10);
  if (q == p || n != neval || m != PetscMax(nrev, 1)) return "it counted other configurations";
  p        = q;
  *seconds = strtod(p, &q);
  if (q == p) return "its message is not a count";
  p = q;
  for (PetscInt e = 0; e < neval; e++) {
    for (PetscInt j = 0; j < m; j++) {
      PetscReal a = strtod(p, &q);

      if (q == p || a != evals[e].angles[j]) return "it counted other configurations";
      p = q;
    }
    count[e] = (PetscInt)strtol(p, &q, 10);
    if (q == p) return "its message is not a count";
    p         = q;
    nrigid[e] = (PetscInt)strtol(p, &q, 10);
    if (q == p || nrigid[e] < 0 || count[e] < nrigid[e]) return "its message is not a count";
    p        = q;
    sigma[e] = strtod(p, &q);
    if (q == p || (sigma[e] != w * w && sigma[e] != w * w * (1 - 1e-6))) return "it counted below another cut";
    p = q;
  }
  while (*p == ' ' || *p == '\n') p++;
  if (strcmp(p, "end\n")) return "its message is cut short";
  return NULL;
}

/* The counts from the helper process (KFReducerSetCountSource), waited for with poll(): *got false, with a progress
   line saying why, when they are not there or not this solve's (then the caller counts in-process). Recorded:
   certificate_count_helper (1: the helper's counts taken), time_certificate_count (this process's wait) and
   time_certificate_count_helper (the helper's own seconds). */
PetscErrorCode KFReducerCertifyCountRead_Private(KFReducer r, PetscInt neval, const KFEvalPoint evals[], PetscInt count[], PetscInt nrigid[], PetscReal sigma[], PetscBool *got)
{
  MPI_Comm       comm = PetscObjectComm((PetscObject)r);
  const char    *why  = NULL;
  char           late[96];
  PetscLogDouble t0, t1, limit;
  PetscReal      seconds = 0;
  PetscInt       nrev;
  size_t         cap, len = 0;
  char          *buf;
  int            fd = r->count_fd;

  PetscFunctionBegin;
  *got = PETSC_FALSE;
  PetscCall(KFReducerResultScalar_Private(r, -1, "certificate_count_helper", 0.0));
  if (fd < 0) PetscFunctionReturn(0);
  r->count_fd = -1; /* read once */
  PetscCall(PetscTime(&t0));
  limit = PetscMax(30.0, t0 - r->count_t0); /* as long again as the reduction had run beside it */
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, &nrev, NULL, NULL, NULL));
  cap = (size_t)(64 + neval * (PetscMax(nrev, 1) + 3) * 32);
  PetscCall(PetscMalloc1(cap + 1, &buf));
  for (;;) {
    struct pollfd  pfd = {fd, POLLIN, 0};
    PetscLogDouble now;
    ssize_t        n;
    int            k;

    PetscCall(KFInterruptCheck(comm));
    PetscCall(PetscTime(&now));
    if (now - t0 > limit) {
      PetscCall(PetscSNPrintf(late, sizeof(late), "it was not done %.0f s after the reduction came to the count", (double)limit));
      why = late;
      break;
    }
    k = poll(&pfd, 1, 200);
    if (k < 0 && errno == EINTR) continue;
    if (k < 0) {
      why = "its pipe failed";
      break;
    }
    if (k == 0) continue;
    n = read(fd, buf + len, cap - len);
    if (n < 0 && (errno == EINTR || errno == EAGAIN)) continue;
    if (n < 0) {
      why = "its pipe failed";
      break;
    }
    if (n == 0) break; /* the helper is done (or dead) */
    len += (size_t)n;
    if (len == cap) {
      why = "its message is not a count";
      break;
    }
  }
  buf[len] = 0;
  if (!why) why = KFCountParse_Private(r, buf, neval, evals, count, nrigid, sigma, &seconds);
  PetscCall(PetscFree(buf));
  PetscCall(PetscTime(&t1));
  if (why) {
    PetscCall(KFProgress(comm, "  certificate: the helper process's counts are not used (%s): counting here", why));
    PetscFunctionReturn(0);
  }
  *got = PETSC_TRUE;
  PetscCall(KFReducerResultScalar_Private(r, -1, "certificate_count_helper", 1.0));
  PetscCall(KFReducerResultScalar_Private(r, -1, "time_certificate_count", (PetscReal)(t1 - t0)));
  PetscCall(KFReducerResultScalar_Private(r, -1, "time_certificate_count_helper", seconds));
  PetscCall(KFProgress(comm, "  certificate: the full order's flexible modes below %.6g Hz counted at %" PetscInt_FMT " configurations by the helper process beside the reduction (%.3g s there, %.3g s waited here)", (double)(PetscSqrtReal(sigma[0]) / (2 * PETSC_PI)), neval, (double)seconds, (double)(t1 - t0)));
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
