/*
  KFReducerSetUp and KFReducerSolve: the whole reduction of a scene (paper eq. 5-24).

  For every configuration: assemble, factor once, build the implementation's basis, solve its small eigenproblem,
  rank the modes, compute the full-order moments and (for verification) the full-order modes. Then choose alpha_G,
  project rigid + kept + static-correction vectors onto the bodies, and compare the reassembled model with the full
  order at every angle of interest. The multi-angle model projects the whole bases of several configurations
  together, so that every moment matches at each of them.
*/
#include <kryflex/reducerimpl.h>

/* full-order moments (by solves, or from the configuration's basis where it matches them: full_moments.c): for the
   verification (its reference needs the first two), or when asked for */
static PetscBool KFReducerFullMoments_Private(KFReducer r)
{
  return (PetscBool)(r->verify || (r->full_moments_set && r->full_moments));
}

/* one configuration the solve visits */
typedef struct {
  const PetscReal *angles;   /* nrev (points into the reducer's arrays) */
  PetscInt         interest; /* index among the angles of interest, -1 if not one */
  PetscBool        is_g;     /* the named alpha_G */
  PetscBool        in_multi; /* one of the multi-angle configurations */
} KFConfig;

static PetscBool KFSameAngles(PetscInt nrev, const PetscReal a[], const PetscReal b[])
{
  for (PetscInt j = 0; j < nrev; j++)
    if (a[j] != b[j]) return PETSC_FALSE;
  return PETSC_TRUE;
}

/* Checks what the solve needs before any heavy work; the same on every rank (every value is replicated). */
PetscErrorCode KFReducerSetUp(KFReducer r)
{
  MPI_Comm comm;
  PetscInt nrev, nsys;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  if (r->setupcalled) PetscFunctionReturn(0);
  PetscCall(PetscObjectGetComm((PetscObject)r, &comm));
  PetscCheck(r->scene, comm, PETSC_ERR_ORDER, "no scene: call KFReducerSetScene() before KFReducerSetUp()");
  if (!((PetscObject)r)->type_name) PetscCall(KFReducerSetType(r, KFREDUCERKRYLOV));
  PetscCall(PetscLogEventBegin(KF_EVENT_REDUCER_SETUP, r, 0, 0, 0));
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, &nrev, &nsys, NULL, NULL));
  nrev = PetscMax(nrev, 1);
  if (!r->nconfig) { /* no angles given: the scene at angle 0 */
    PetscCall(PetscCalloc1(nrev, &r->angles));
    r->nconfig = 1;
  }
  for (PetscInt c = 0; c < r->nconfig; c++)
    for (PetscInt d = 0; d < c; d++) PetscCheck(!KFSameAngles(nrev, &r->angles[c * nrev], &r->angles[d * nrev]), comm, PETSC_ERR_ARG_WRONG, "angles of interest: configuration %" PetscInt_FMT " repeats configuration %" PetscInt_FMT " (%g deg): give each configuration once", c + 1, d + 1, (double)(r->angles[c * nrev] * 180.0 / PETSC_PI));
  for (PetscInt c = 0; c < r->nmulti; c++)
    for (PetscInt d = 0; d < c; d++) PetscCheck(!KFSameAngles(nrev, &r->multi[c * nrev], &r->multi[d * nrev]), comm, PETSC_ERR_ARG_WRONG, "multi-angle configurations: configuration %" PetscInt_FMT " repeats configuration %" PetscInt_FMT ": give each configuration once", c + 1, d + 1);
  PetscCheck(r->moments == PETSC_DECIDE || r->moments > r->output_blocks, comm, PETSC_ERR_ARG_OUTOFRANGE, "moments (%" PetscInt_FMT ") must exceed output_blocks (%" PetscInt_FMT ")", r->moments, r->output_blocks);
  PetscCall(PetscLogEventEnd(KF_EVENT_REDUCER_SETUP, r, 0, 0, 0));
  r->setupcalled = PETSC_TRUE;
  PetscFunctionReturn(0);
}

/* configurations to visit: the angles of interest, then a named alpha_G and the multi-angle configurations that are
   not among them; the named alpha_G is visited last so that nothing has to be factored twice */
static PetscErrorCode KFReducerConfigurations_Private(KFReducer r, PetscInt nrev, PetscInt *nc, KFConfig **configs)
{
  const PetscInt nmulti = r->nmulti ? r->nmulti : r->nconfig;
  const PetscReal *multi = r->nmulti ? r->multi : r->angles;
  KFConfig      *list, tmp;
  PetscInt       n = 0, g = -1;

  PetscFunctionBegin;
  PetscCall(PetscCalloc1(r->nconfig + nmulti + 1, &list));
  for (PetscInt c = 0; c < r->nconfig; c++) {
    list[n].angles   = &r->angles[c * nrev];
    list[n].interest = c;
    n++;
  }
  for (PetscInt m = -1; m < nmulti; m++) {
    const PetscReal *a = m < 0 ? (r->auto_alpha ? NULL : r->alpha_g) : &multi[m * nrev];
    PetscInt         i;

    if (!a) continue;
    for (i = 0; i < n; i++)
      if (KFSameAngles(nrev, list[i].angles, a)) break;
    if (i == n) {
      list[n].angles   = a;
      list[n].interest = -1;
      n++;
    }
    if (m < 0) list[i].is_g = PETSC_TRUE;
    else list[i].in_multi = PETSC_TRUE;
  }
  for (PetscInt i = 0; i < n; i++)
    if (list[i].is_g) g = i;
  if (g >= 0) { /* alpha_G last */
    tmp = list[g];
    for (PetscInt i = g; i < n - 1; i++) list[i] = list[i + 1];
    list[n - 1] = tmp;
  }
  *nc      = n;
  *configs = list;
  PetscFunctionReturn(0);
}

static PetscErrorCode KFReducerBasisDestroy_Private(KFReducer r, KFReducerBasis *basis)
{
  PetscFunctionBegin;
  if (r->ops->destroybasis) PetscCall((*r->ops->destroybasis)(r, basis));
  PetscCall(PetscFree4(basis->lambda, basis->Phi, basis->Gr, basis->Hr));
  PetscCall(PetscFree2(basis->Mr, basis->Kr));
  PetscCall(PetscFree(basis->block_end));
  PetscCall(PetscMemzero(basis, sizeof(*basis)));
  PetscFunctionReturn(0);
}

/* a reduced model from a finished body basis, with the settings that made it */
static PetscErrorCode KFReducerMakeModel_Private(KFReducer r, KFBodyBasis bb, KFReducerMethod method, PetscInt n, const PetscReal angles[], KFReducedModel *model)
{
  PetscInt  nb, maxdofs = 0;
  PetscBool keep;

  PetscFunctionBegin;
  PetscCall(KFBodyBasisFinish(bb, r->body_tol));
  PetscCall(KFSceneGetInfo(r->scene, &nb, NULL, NULL, NULL, NULL, NULL));
  for (PetscInt b = 0; b < nb; b++) {
    PetscInt nd;

    PetscCall(KFSceneGetBodyInfo(r->scene, b, NULL, &nd, NULL));
    maxdofs = PetscMax(maxdofs, nd);
  }
  keep = r->save_maps == PETSC_DECIDE ? (PetscBool)(maxdofs <= r->save_maps_max_dofs) : (PetscBool)r->save_maps;
  PetscCall(KFReducedModelCreateFromBodyBasis(r->scene, bb, n, angles, keep, model));
  PetscCall(KFReducerRecordSettings_Private(r, *model, method, r->build_moments, n, angles));
  {
    PetscInt nrigid;
    char     value[32];
    PetscCall(KFSceneGetRigidCount(r->scene, &nrigid));
    if (nrigid >= 0) { /* saved with the model: KFReducedModelGetInfo after a load */
      PetscCall(PetscSNPrintf(value, sizeof(value), "%" PetscInt_FMT, nrigid));
      PetscCall(KFReducedModelSetSetting(*model, "rigid_modes", value));
    }
  }
  PetscFunctionReturn(0);
}

/* the reduced dofs of each body of a model, as the whole result name */
static PetscErrorCode KFReducerRecordBodySizes_Private(KFReducer r, KFReducedModel model, const char name[])
{
  PetscInt   nb;
  PetscReal *dofs;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, &nb, NULL, NULL, NULL, NULL, NULL));
  PetscCall(PetscMalloc1(nb, &dofs));
  for (PetscInt b = 0; b < nb; b++) {
    KFReducedBody body;

    PetscCall(KFReducedModelGetBody(model, b, NULL, NULL, &body, NULL));
    dofs[b] = (PetscReal)body.v;
  }
  PetscCall(KFReducerResultSet_Private(r, -1, name, 1, &nb, dofs));
  PetscCall(PetscFree(dofs));
  PetscFunctionReturn(0);
}

/* the factorization stage's time outside MUMPS (the stiffness copied, dofs held, the factor's options): the stage's
   seconds less the solver's factorization seconds */
static PetscErrorCode KFReducerAddFactorSetUp_Private(KFFlexSolver solver, PetscLogDouble stage, PetscReal *setup)
{
  KFFlexSolverPerf p;

  PetscFunctionBegin;
  PetscCall(KFFlexSolverGetPerf(solver, &p));
  *setup += (PetscReal)PetscMax(stage - p.factor_seconds, 0);
  PetscFunctionReturn(0);
}

/* The system a solve's configurations are assembled in: the one given to the reducer (KFReducerSetSystem), taken
   over by this solve, or a new one */
static PetscErrorCode KFReducerSystemCreate_Private(KFReducer r, KFSystem *sys)
{
  PetscFunctionBegin;
  if (r->given_sys) {
    *sys         = r->given_sys;
    r->given_sys = NULL;
    r->fresh_sys = *sys;
  } else PetscCall(KFSystemCreate(r->scene, sys));
  PetscFunctionReturn(0);
}

/* The per-configuration pipeline that the fixed recipe and the search share: the system at the configuration's
   angles, its rigid modes, its factored flexible solver (the reducer's prefix and shift) and the basis the reducer's
   type builds with it. times[0..2]: assembly, factorization, basis; setup_s: the factorization stage outside MUMPS. */
static PetscErrorCode KFReducerConfigBasis_Private(KFReducer r, KFSystem sys, PetscInt nrev, const PetscReal angles[], PetscReal times[], PetscReal *setup_s, Mat *Phir, PetscReal *rigid_res, KFFlexSolver *solver, KFReducerBasis *basis)
{
  MPI_Comm       comm = PetscObjectComm((PetscObject)r);
  PetscLogDouble t0, t1;
  char           label[128];

  PetscFunctionBegin;
  /* a command's SIGINT/SIGTERM stops the solve at stage boundaries, on every rank together */
  PetscCall(KFInterruptCheck(comm));
  PetscCall(KFReducerConfigLabel_Private(nrev, angles, label, sizeof(label)));
  if (nrev) PetscCall(KFProgress(comm, "configuration %s deg", label));
  else PetscCall(KFProgress(comm, "the structure (no revolute joint)"));
  PetscCall(PetscTime(&t0));
  /* a system handed over assembled at these very angles, untouched since: its matrices and rigid modes are what
     assembling again would give (the same code on the same input) */
  if (!(sys == r->fresh_sys && sys->assembled && KFSameAngles(nrev, sys->angles, angles))) PetscCall(KFSystemSetAngles(sys, angles));
  r->fresh_sys = NULL;
  PetscCall(KFSystemGetRigidModes(sys, Phir, rigid_res));
  PetscCall(PetscTime(&t1));
  times[0] += t1 - t0;

  t0 = t1;
  PetscCall(KFFlexSolverCreate(sys, solver));
  PetscCall(KFFlexSolverSetOptionsPrefix(*solver, ((PetscObject)r)->prefix)); /* the reducer's options are the solver's */
  PetscCall(KFFlexSolverSetShift(*solver, r->shift)); /* the reducer's value, whatever the global options say */
  PetscCall(KFFlexSolverSetUp(*solver));
  PetscCall(PetscTime(&t1));
  times[1] += t1 - t0;
  PetscCall(KFReducerAddFactorSetUp_Private(*solver, t1 - t0, setup_s));
  PetscCall(KFInterruptCheck(comm));

  t0 = t1;
  PetscCall(PetscMemzero(basis, sizeof(*basis)));
  basis->gram_condition = (PetscReal)NAN;
  PetscCall(PetscLogEventBegin(KF_EVENT_REDUCER_BASIS, r, 0, 0, 0));
  PetscCall((*r->ops->buildbasis)(r, sys, *solver, basis));
  PetscCall(PetscLogEventEnd(KF_EVENT_REDUCER_BASIS, r, 0, 0, 0));
  PetscCall(PetscTime(&t1));
  times[2] += t1 - t0;
  PetscFunctionReturn(0);
}

/* the stage times a solve records, in the order of its times[] */
static const char *const KFSolveTimeNames[] = {"time_assembly", "time_factorization", "time_basis", "time_modes", "time_moments", "time_projection", "time_verification"};

/* The fixed recipe's state across its configurations: the candidates for alpha_G and the multi-angle basis */
typedef struct {
  MPI_Comm     comm;
  const char  *type;
  PetscInt     nc, nrev, nrev1, a, t, nmom;
  KFConfig    *configs;
  KFBodyBasis *candidates, multi_bb;
  PetscInt     g, best_kept, nkept_g, nstatic_g, multi_n;
  PetscReal    best_imp, setup_s, *multi_angles, *kept_g;
  PetscReal    times[7]; /* assembly, factorization, basis, modes, moments, projection, verification */
} KFFixed;

/* One configuration's modes: frequencies, importance (band or per-mode rule), which the threshold keeps */
static PetscErrorCode KFReducerFixedModes_Private(KFReducer r, const KFFixed *fx, const KFReducerBasis *basis, PetscReal imp[], PetscBool kept[], PetscReal freq[], PetscReal keptf[], PetscInt *nkept)
{
  const PetscInt c = basis->size, a = fx->a, t = fx->t;

  PetscFunctionBegin;
  if (r->importance == KF_IMPORTANCE_BAND) {
    PetscInt *clu;

    PetscCall(PetscMalloc1(c, &clu));
    PetscCall(KFDenseModeImportanceBand(c, basis->lambda, basis->Phi, a, basis->Gr, t, basis->Hr, r->zeta, r->band, r->cluster_rtol, 0.0, imp, clu));
    PetscCall(PetscFree(clu));
  } else PetscCall(KFDenseModeImportance(c, basis->lambda, basis->Phi, a, basis->Gr, t, basis->Hr, r->zeta, r->importance, 0.0, imp));
  *nkept = 0;
  for (PetscInt k = 0; k < c; k++) {
    kept[k]  = (PetscBool)(imp[k] >= r->keep_threshold);
    keptf[k] = kept[k] ? 1.0 : 0.0;
    freq[k]  = PetscSqrtReal(PetscMax(basis->lambda[k], 0)) / (2 * PETSC_PI);
    *nkept += kept[k];
  }
  PetscFunctionReturn(0);
}

/* The paper's rule: alpha_G is the angle of interest whose model needs the most modes (ties: the larger kept
   importance, then the first); only the best candidate's body basis is kept. Configuration i's multi-angle vectors
   join the multi-angle basis. */
static PetscErrorCode KFReducerFixedBases_Private(KFReducer r, KFFixed *fx, PetscInt i, KFSystem sys, KFFlexSolver solver, KFReducerBasis *basis, Mat Phir, const PetscReal imp[], const PetscBool kept[], PetscInt nkept)
{
  KFConfig *cfg = &fx->configs[i];
  PetscInt  c   = basis->size;
  Mat       X;

  PetscFunctionBegin;
  if (cfg->is_g || (r->auto_alpha && cfg->interest >= 0)) {
    PetscReal sum = 0;
    PetscInt  ncols;

    for (PetscInt k = 0; k < c; k++)
      if (kept[k]) sum += imp[k];
    if (cfg->is_g || nkept > fx->best_kept || (nkept == fx->best_kept && sum > fx->best_imp)) {
      PetscCall((*r->ops->vectors)(r, sys, solver, basis, kept, r->static_correction, &X));
      PetscCall(MatGetSize(X, NULL, &ncols));
      if (fx->g >= 0) PetscCall(KFBodyBasisDestroy(&fx->candidates[fx->g]));
      fx->g         = i;
      fx->best_kept = nkept;
      fx->best_imp  = sum;
      fx->nkept_g   = nkept;
      fx->nstatic_g = ncols - nkept;
      PetscCall(PetscFree(fx->kept_g));
      PetscCall(PetscMalloc1(PetscMax(nkept, 1), &fx->kept_g));
      for (PetscInt k = 0, m = 0; k < c; k++)
        if (kept[k]) fx->kept_g[m++] = k + 1;
      PetscCall(KFBodyBasisCreate(r->scene, &fx->candidates[i]));
      PetscCall(KFBodyBasisAdd(fx->candidates[i], sys, Phir));
      PetscCall(KFBodyBasisAdd(fx->candidates[i], sys, X));
      PetscCall(MatDestroy(&X));
    }
  }
  if (fx->multi_bb && cfg->in_multi) {
    PetscCall(KFBodyBasisAdd(fx->multi_bb, sys, Phir));
    PetscCall((*r->ops->vectors)(r, sys, solver, basis, NULL, PETSC_FALSE, &X));
    PetscCall(KFBodyBasisAdd(fx->multi_bb, sys, X));
    PetscCall(MatDestroy(&X));
    PetscCall(PetscArraycpy(&fx->multi_angles[fx->multi_n * fx->nrev1], cfg->angles, fx->nrev1));
    fx->multi_n++;
  }
  PetscFunctionReturn(0);
}

/* What an angle of interest records, and its full-order reference when the models are verified */
static PetscErrorCode KFReducerFixedRecord_Private(KFReducer r, KFFixed *fx, const KFConfig *cfg, KFSystem sys, KFFlexSolver solver, const KFReducerBasis *basis, const PetscReal freq[], const PetscReal imp[], const PetscReal keptf[], PetscInt nheld, PetscReal rigid_res, KFEvalPoint evals[], PetscReal Lfull[])
{
  const PetscInt ci = cfg->interest, nmom = fx->nmom, t = fx->t, a = fx->a, c = basis->size, shape[3] = {t, a, nmom};
  PetscLogDouble t0, t1;

  PetscFunctionBegin;
  PetscCall(KFReducerResultSet_Private(r, ci, "full_moments", 3, shape, &Lfull[ci * nmom * t * a]));
  PetscCall(KFReducerResultSet_Private(r, ci, "krylov_frequencies_hz", 1, &c, freq));
  PetscCall(KFReducerResultSet_Private(r, ci, "krylov_importance", 1, &c, imp));
  PetscCall(KFReducerResultSet_Private(r, ci, "krylov_kept", 1, &c, keptf));
  PetscCall(KFReducerResultScalar_Private(r, ci, "krylov_deflations", (PetscReal)basis->ndeflated));
  PetscCall(KFReducerResultScalar_Private(r, ci, "gram_condition_raw", basis->gram_condition));
  PetscCall(KFReducerResultScalar_Private(r, ci, "held_dofs", (PetscReal)nheld));
  PetscCall(KFReducerResultScalar_Private(r, ci, "rigid_residual", rigid_res));
  if (r->verify) {
    PetscCall(KFInterruptCheck(fx->comm));
    PetscCall(PetscTime(&t0));
    PetscCall(KFReducerReference_Private(r, sys, solver, nmom, &Lfull[ci * nmom * t * a], &evals[ci]));
    PetscCall(PetscTime(&t1));
    fx->times[6] += t1 - t0;
  }
  PetscFunctionReturn(0);
}

/* The system at configuration i, its factorization and basis: KFReducerFixedModes_Private, the full-order moments where
   the models are compared, KFReducerFixedBases_Private and KFReducerFixedRecord_Private */
static PetscErrorCode KFReducerFixedConfig_Private(KFReducer r, KFFixed *fx, PetscInt i, KFSystem sys, KFEvalPoint evals[], PetscReal Lfull[])
{
  KFConfig       *cfg    = &fx->configs[i];
  KFFlexSolver    solver = NULL;
  KFReducerBasis  basis;
  Mat             Phir;
  PetscReal       rigid_res, *imp, *freq, *keptf;
  PetscBool      *kept;
  PetscInt        nkept = 0, nheld, c, tam = fx->nmom * fx->t * fx->a;
  PetscLogDouble  t0, t1;

  PetscFunctionBegin;
  PetscCall(KFReducerConfigBasis_Private(r, sys, fx->nrev, cfg->angles, fx->times, &fx->setup_s, &Phir, &rigid_res, &solver, &basis));
  PetscCall(PetscTime(&t0));
  c = basis.size;
  PetscCall(PetscMalloc4(c, &imp, c, &kept, c, &freq, c, &keptf));
  PetscCall(KFReducerFixedModes_Private(r, fx, &basis, imp, kept, freq, keptf, &nkept));
  PetscCall(PetscTime(&t1));
  fx->times[3] += t1 - t0;

  if (cfg->interest >= 0 && KFReducerFullMoments_Private(r)) { /* full-order moments where the models are compared */
    t0 = t1;
    PetscCall(KFReducerPointMoments_Private(r, &basis, solver, fx->nmom, &Lfull[cfg->interest * tam], r->verify ? &evals[cfg->interest].kg : NULL));
    PetscCall(PetscTime(&t1));
    fx->times[4] += t1 - t0;
  } else if (cfg->interest >= 0) { /* not asked for: the moment checks say "not computed" (NaN) */
    for (PetscInt e = 0; e < tam; e++) Lfull[cfg->interest * tam + e] = (PetscReal)NAN;
  }
  PetscCall(KFFlexSolverGetStats(solver, &nheld, NULL, NULL));

  t0 = t1;
  PetscCall(KFReducerFixedBases_Private(r, fx, i, sys, solver, &basis, Phir, imp, kept, nkept));
  PetscCall(PetscTime(&t1));
  fx->times[5] += t1 - t0;

  if (cfg->interest >= 0) PetscCall(KFReducerFixedRecord_Private(r, fx, cfg, sys, solver, &basis, freq, imp, keptf, nheld, rigid_res, evals, Lfull));
  PetscCall(KFReducerAddPerf_Private(r, solver));
  PetscCall(KFFlexSolverDestroy(&solver));
  PetscCall(KFProgress(fx->comm, "  %" PetscInt_FMT " %s vectors (%" PetscInt_FMT " deflated), %" PetscInt_FMT " of %" PetscInt_FMT " modes kept; held dofs %" PetscInt_FMT, c, fx->type, basis.ndeflated, nkept, c, nheld));
  PetscCall(PetscFree4(imp, kept, freq, keptf));
  PetscCall(KFReducerBasisDestroy_Private(r, &basis));
  PetscFunctionReturn(0);
}

/* alpha_G and its model, the multi-angle model; the other candidates are not needed */
static PetscErrorCode KFReducerFixedModels_Private(KFReducer r, KFFixed *fx)
{
  const KFConfig *cg = &fx->configs[fx->g];
  PetscInt        nrigid, nsys;
  PetscLogDouble  t0, t1;
  char            label[128];
  const PetscInt  shape[2] = {fx->nrev1, 1};

  PetscFunctionBegin;
  PetscCall(KFReducerConfigLabel_Private(fx->nrev, cg->angles, label, sizeof(label)));
  if (!fx->nrev) PetscCall(PetscSNPrintf(r->rule, sizeof(r->rule), "the structure's Krylov model (no revolute joint: one configuration), %" PetscInt_FMT " modes above the importance threshold %g", fx->nkept_g, (double)r->keep_threshold));
  else if (r->auto_alpha) PetscCall(PetscSNPrintf(r->rule, sizeof(r->rule), "alpha_G = %s deg: of the angles of interest, its Krylov model needs the most modes above the importance threshold %g (%" PetscInt_FMT "), so its kept set covers the others' (the paper's rule)", label, (double)r->keep_threshold, fx->nkept_g));
  else PetscCall(PetscSNPrintf(r->rule, sizeof(r->rule), "alpha_G = %s deg, named in the scene", label));
  PetscCall(KFProgress(fx->comm, "%s", r->rule));
  PetscCall(PetscTime(&t0));
  PetscCall(KFReducerMakeModel_Private(r, fx->candidates[fx->g], KF_METHOD_SINGLE_ANGLE, 1, cg->angles, &r->single));
  if (fx->multi_bb) PetscCall(KFReducerMakeModel_Private(r, fx->multi_bb, KF_METHOD_MULTI_ANGLE, fx->multi_n, fx->multi_angles, &r->multi_model));
  PetscCall(PetscTime(&t1));
  fx->times[5] += t1 - t0;
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, NULL, &nsys, NULL, NULL));
  PetscCall(KFReducerResultSet_Private(r, -1, "reduction_angles", 2, shape, cg->angles));
  PetscCall(KFReducerResultScalar_Private(r, -1, "reduction_config", (PetscReal)cg->interest));
  PetscCall(KFReducerResultSet_Private(r, -1, "kept_modes", 1, &fx->nkept_g, fx->kept_g));
  PetscCall(KFReducerResultScalar_Private(r, -1, "static_correction_modes", (PetscReal)fx->nstatic_g));
  PetscCall(KFReducerResultScalar_Private(r, -1, "full_system_dofs", (PetscReal)nsys));
  PetscCall(KFSceneGetRigidCount(r->scene, &nrigid)); /* derived from geometry, joints and boundary conditions */
  PetscCall(KFReducerResultScalar_Private(r, -1, "rigid_modes", (PetscReal)nrigid));
  PetscFunctionReturn(0);
}

/* The models' sizes, the stage times and the moments matched */
static PetscErrorCode KFReducerFixedSummary_Private(KFReducer r, KFFixed *fx)
{
  char      sizes[256], sizes_multi[256];
  PetscReal mm = (PetscReal)fx->nmom;

  PetscFunctionBegin;
  PetscCall(KFReducerRecordBodySizes_Private(r, r->single, "reduced_dofs_per_body"));
  if (r->multi_model) {
    const PetscInt shape[2] = {fx->nrev1, fx->multi_n};

    PetscCall(KFReducerRecordBodySizes_Private(r, r->multi_model, "multi_dofs_per_body"));
    PetscCall(KFReducerResultSet_Private(r, -1, "multi_reduction_angles", 2, shape, fx->multi_angles));
  }
  PetscCall(KFReducerModelSizes_Private(r->single, sizes, sizeof(sizes)));
  if (r->multi_model) {
    char tmp[256];

    PetscCall(KFReducerModelSizes_Private(r->multi_model, tmp, sizeof(tmp)));
    PetscCall(PetscSNPrintf(sizes_multi, sizeof(sizes_multi), "; %s dofs (multi-angle)", tmp));
  } else sizes_multi[0] = 0;
  PetscCall(KFProgress(fx->comm, "reduced bodies: %s dofs (single-angle)%s", sizes, sizes_multi));
  for (PetscInt k = 0; k < 7; k++) PetscCall(KFReducerResultScalar_Private(r, -1, KFSolveTimeNames[k], fx->times[k]));
  PetscCall(KFReducerResultScalar_Private(r, -1, "time_factor_setup", fx->setup_s));
  r->chosen = r->method == KF_METHOD_MULTI_ANGLE && r->multi_model ? KF_METHOD_MULTI_ANGLE : KF_METHOD_SINGLE_ANGLE;
  PetscCall(KFReducerResultScalar_Private(r, -1, "moments_matched", mm));
  if (r->multi_model) PetscCall(KFReducerResultScalar_Private(r, -1, "multi_moments_matched", mm));
  PetscFunctionReturn(0);
}

/* The fixed recipe: every configuration reduced once (KFReducerFixedConfig_Private), then the models */
static PetscErrorCode KFReducerSolveFixed_Private(KFReducer r, KFEvalPoint evals[], PetscReal Lfull[])
{
  KFFixed  fx;
  KFSystem sys = NULL;

  PetscFunctionBegin;
  PetscCall(PetscMemzero(&fx, sizeof(fx)));
  fx.g         = -1;
  fx.best_kept = -1;
  fx.best_imp  = -1;
  PetscCall(PetscObjectGetComm((PetscObject)r, &fx.comm));
  PetscCall(KFReducerGetType(r, &fx.type));
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, &fx.nrev, NULL, &fx.a, &fx.t));
  fx.nrev1 = PetscMax(fx.nrev, 1);
  fx.nmom  = r->build_moments;
  PetscCall(KFReducerConfigurations_Private(r, fx.nrev1, &fx.nc, &fx.configs));
  PetscCall(PetscCalloc1(fx.nc, &fx.candidates));
  if (r->nmulti > 1 || (!r->nmulti && r->nconfig > 1) || r->method == KF_METHOD_MULTI_ANGLE) PetscCall(KFBodyBasisCreate(r->scene, &fx.multi_bb));
  PetscCall(PetscMalloc1(fx.nc * fx.nrev1, &fx.multi_angles));
  PetscCall(KFReducerSystemCreate_Private(r, &sys));
  PetscCall(KFSystemSetConfigurationCount(sys, fx.nc));
  for (PetscInt i = 0; i < fx.nc; i++) PetscCall(KFReducerFixedConfig_Private(r, &fx, i, sys, evals, Lfull));
  PetscCall(KFSystemDestroy(&sys));
  PetscCall(KFInterruptCheck(fx.comm));
  if (!KFReducerFullMoments_Private(r)) PetscCall(KFReducerNote_Private(r, "full-order moments not computed (verification off): the moment checks are empty; -kf_full_moments computes them"));
  PetscCall(KFReducerFixedModels_Private(r, &fx));
  PetscCall(KFReducerFixedSummary_Private(r, &fx));
  for (PetscInt i = 0; i < fx.nc; i++) PetscCall(KFBodyBasisDestroy(&fx.candidates[i]));
  PetscCall(KFBodyBasisDestroy(&fx.multi_bb));
  PetscCall(PetscFree(fx.candidates));
  PetscCall(PetscFree(fx.kept_g));
  PetscCall(PetscFree(fx.multi_angles));
  PetscCall(PetscFree(fx.configs));
  PetscFunctionReturn(0);
}

/* the scene in one line */
static PetscErrorCode KFReducerAnnounce_Private(KFReducer r)
{
  PetscInt    nb, nrev, nsys, a, t;
  const char *name;
  char        dofs[256];
  size_t      used = 0;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, &nb, NULL, &nrev, &nsys, &a, &t));
  PetscCall(KFSceneGetName(r->scene, &name));
  dofs[0] = 0;
  for (PetscInt b = 0; b < nb; b++) {
    PetscInt nd;

    PetscCall(KFSceneGetBodyInfo(r->scene, b, NULL, &nd, NULL));
    PetscCall(PetscSNPrintf(dofs + used, sizeof(dofs) - used, "%s%" PetscInt_FMT, b ? " + " : "", nd));
    PetscCall(PetscStrlen(dofs, &used));
  }
  PetscCall(KFProgress(PetscObjectComm((PetscObject)r), "scene '%s': %" PetscInt_FMT " bodies (%s dofs), %" PetscInt_FMT " system dofs, %" PetscInt_FMT " revolute joints, %" PetscInt_FMT " inputs, %" PetscInt_FMT " outputs", name, nb, dofs, nsys, nrev, a, t));
  PetscFunctionReturn(0);
}

/* the full-order reference of an evaluation point at the system's configuration; solver: the reduction's flexible
   solver there (its factor serves the eigensolve), or NULL: one is made here (the body-wise solve reuses the bodies'
   factorizations); L (nmom blocks of t x a) its first moments, or NULL: the first two computed here */
PetscErrorCode KFReducerReference_Private(KFReducer r, KFSystem sys, KFFlexSolver solver, PetscInt nmom, const PetscReal L[], KFEvalPoint *p)
{
  PetscInt     a, t;
  KFFlexSolver own = NULL;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, NULL, NULL, &a, &t));
  PetscCall(PetscLogEventBegin(KF_EVENT_REDUCER_VERIFY, r, 0, 0, 0));
  if (!solver) {
    PetscCall(KFFlexSolverCreate(sys, &own));
    PetscCall(KFFlexSolverSetOptionsPrefix(own, ((PetscObject)r)->prefix)); /* the reducer's options are the solver's */
    PetscCall(KFFlexSolverSetShift(own, r->shift));
    solver = own;
  }
  PetscCall(KFReducerFullReference_Private(r, sys, solver, &p->ref));
  PetscCall(PetscMalloc1(PetscMax(2 * t * a, 1), &p->L0));
  p->nmom = L ? PetscMin(nmom, 2) : 2;
  if (L) PetscCall(PetscArraycpy(p->L0, L, p->nmom * t * a));
  else PetscCall(KFReducerPointMoments_Private(r, NULL, solver, 2, p->L0, &p->kg));
  PetscCall(KFEvalPointRefinedCheck_Private(r, sys, solver, p)); /* while the solver is alive; no-op without ref.V */
  if (own) {
    PetscCall(KFReducerAddPerf_Private(r, own));
    PetscCall(KFFlexSolverDestroy(&own));
  }
  PetscCall(PetscLogEventEnd(KF_EVENT_REDUCER_VERIFY, r, 0, 0, 0));
  PetscFunctionReturn(0);
}

/* the full-order references of the midpoints (evaluation points nconfig .. neval - 1), each at its own angles;
   seconds: the time they took */
static PetscErrorCode KFReducerMidpointReferences_Private(KFReducer r, KFSystem sys, PetscInt neval, KFEvalPoint evals[], PetscReal *seconds)
{
  MPI_Comm       comm;
  PetscInt       nrev;
  PetscLogDouble t0, t1;

  PetscFunctionBegin;
  PetscCall(PetscObjectGetComm((PetscObject)r, &comm));
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, &nrev, NULL, NULL, NULL));
  for (PetscInt e = r->nconfig; e < neval; e++) {
    char label[128];

    PetscCall(KFInterruptCheck(comm));
    PetscCall(KFReducerConfigLabel_Private(nrev, evals[e].angles, label, sizeof(label)));
    PetscCall(KFProgress(comm, "full-order reference at the midpoint %s deg", label));
    PetscCall(PetscTime(&t0));
    PetscCall(KFSystemSetAngles(sys, evals[e].angles));
    PetscCall(KFReducerReference_Private(r, sys, NULL, 0, NULL, &evals[e]));
    PetscCall(PetscTime(&t1));
    *seconds += t1 - t0;
  }
  PetscFunctionReturn(0);
}

/* The certificate failed: the measured verdict instead. The estimator's references are replaced by the full order's
   at every point, and at the angles of interest the full-order moments by block solves (the moment checks' reference,
   as with -kf_verify true): the visits' solvers are gone, so each angle is factored again (the body-wise solve
   reusing the bodies' factors). The search then runs as with -kf_verify true. seconds: their time */
static PetscErrorCode KFReducerCertifyFallback_Private(KFReducer r, PetscInt neval, KFEvalPoint evals[], PetscInt nfull, PetscReal Lfull[], PetscReal *seconds)
{
  MPI_Comm       comm = PetscObjectComm((PetscObject)r);
  KFSystem       sys;
  PetscInt       nrev, a, t;
  PetscLogDouble t0, t1;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, &nrev, NULL, &a, &t));
  for (PetscInt e = 0; e < neval; e++) PetscCall(KFReducedSystemDestroy(&evals[e].rich));
  r->verify = PETSC_TRUE;
  PetscCall(KFSystemCreate(r->scene, &sys));
  PetscCall(KFSystemSetConfigurationCount(sys, neval));
  for (PetscInt ci = 0; ci < r->nconfig; ci++) {
    const PetscInt shape[3] = {t, a, nfull};
    char           label[128];
    KFFlexSolver   solver;
    PetscReal     *L = &Lfull[ci * nfull * t * a];

    PetscCall(KFInterruptCheck(comm));
    PetscCall(KFReducerConfigLabel_Private(nrev, evals[ci].angles, label, sizeof(label)));
    PetscCall(KFProgress(comm, "full-order reference at %s deg (the certificate failed)", label));
    PetscCall(PetscTime(&t0));
    PetscCall(KFSystemSetAngles(sys, evals[ci].angles));
    PetscCall(KFFlexSolverCreate(sys, &solver));
    PetscCall(KFFlexSolverSetOptionsPrefix(solver, ((PetscObject)r)->prefix));
    PetscCall(KFFlexSolverSetShift(solver, r->shift));
    PetscCall(KFReducerPointMoments_Private(r, NULL, solver, nfull, L, &evals[ci].kg));
    PetscCall(KFReducerResultSet_Private(r, ci, "full_moments", 3, shape, L));
    PetscCall(KFReducerResultScalar_Private(r, ci, "full_moments_estimated", 0.0));
    PetscCall(KFReducerReference_Private(r, sys, solver, nfull, L, &evals[ci]));
    PetscCall(KFReducerAddPerf_Private(r, solver));
    PetscCall(KFFlexSolverDestroy(&solver));
    PetscCall(PetscTime(&t1));
    *seconds += t1 - t0;
  }
  PetscCall(KFReducerMidpointReferences_Private(r, sys, neval, evals, seconds));
  PetscCall(KFBodyFactorsDestroy(&r->count_bf));
  PetscCall(KFSystemDestroy(&sys));
  PetscFunctionReturn(0);
}

/* the search's way: every configuration's basis kept (moments up to moments_max), the references, the search, and
   the best model of each family */
/* The search's state across its visits */
typedef struct {
  MPI_Comm  comm;
  PetscInt  nc, nrev, nrev1, nb, a, t, nfull;
  KFConfig *configs;
  KFVisit  *visits;
  PetscReal times[7], setup_s; /* assembly, factorization, basis, modes, moments, projection, verification */
} KFSearch;

/* What an angle of interest records of visit v, its full-order moments and reference */
static PetscErrorCode KFReducerSearchVisitRecord_Private(KFReducer r, KFSearch *st, KFVisit *v, KFSystem sys, KFFlexSolver solver, PetscInt nheld, PetscReal rigid_res, KFEvalPoint evals[], PetscReal Lfull[])
{
  const PetscInt nfull = st->nfull, t = st->t, a = st->a;
  PetscReal     *times = st->times;
  PetscLogDouble t0, t1;

  PetscFunctionBegin;
  PetscCall(PetscTime(&t1));
  {
    const PetscInt ci = v->interest, shape[3] = {t, a, nfull};

    if (KFReducerFullMoments_Private(r)) {
      t0 = t1;
      PetscCall(KFReducerPointMoments_Private(r, &v->basis, solver, nfull, &Lfull[ci * nfull * t * a], r->verify ? &evals[ci].kg : NULL));
      PetscCall(PetscTime(&t1));
      times[4] += t1 - t0;
      PetscCall(KFReducerResultSet_Private(r, ci, "full_moments", 3, shape, &Lfull[ci * nfull * t * a]));
    }
    PetscCall(KFReducerResultScalar_Private(r, ci, "krylov_deflations", (PetscReal)v->basis.ndeflated));
    PetscCall(KFReducerResultScalar_Private(r, ci, "gram_condition_raw", v->basis.gram_condition));
    PetscCall(KFReducerResultScalar_Private(r, ci, "krylov_rigid_content", v->basis.rigid_content));
    PetscCall(KFReducerResultScalar_Private(r, ci, "krylov_orthogonality", v->basis.orthogonality));
    PetscCall(KFReducerResultScalar_Private(r, ci, "held_dofs", (PetscReal)nheld));
    PetscCall(KFReducerResultScalar_Private(r, ci, "rigid_residual", rigid_res));
    if (r->verify) {
      PetscCall(PetscTime(&t0));
      PetscCall(KFReducerReference_Private(r, sys, solver, nfull, &Lfull[ci * nfull * t * a], &evals[ci]));
      PetscCall(PetscTime(&t1));
      times[6] += t1 - t0;
    }
  }
  PetscFunctionReturn(0);
}

/* Visit i: the system at its angles, its factorization and Krylov basis, kept for the search (the basis, the rigid
   modes and the body maps) */
static PetscErrorCode KFReducerSearchVisit_Private(KFReducer r, KFSearch *st, PetscInt i, KFSystem sys, KFEvalPoint evals[], PetscReal Lfull[])
{
  KFVisit       *v = &st->visits[i];
  KFConfig      *cfg = &st->configs[i];
  KFFlexSolver   solver;
  Mat            Phir;
  PetscReal      rigid_res;
  PetscInt       nheld;
  char           place[160];

  PetscFunctionBegin;
  PetscCall(KFReducerConfigPlace_Private(st->nrev, cfg->angles, place, sizeof(place)));
  PetscCall(KFReducerConfigBasis_Private(r, sys, st->nrev, cfg->angles, st->times, &st->setup_s, &Phir, &rigid_res, &solver, &v->basis));
  PetscCall(PetscMalloc1(st->nrev1, &v->angles));
  PetscCall(PetscArraycpy(v->angles, cfg->angles, st->nrev1));
  v->interest = cfg->interest;
  v->is_g     = cfg->is_g;
  v->in_multi = cfg->in_multi;
  PetscCall(MatDuplicate(Phir, MAT_COPY_VALUES, &v->Phir));
  PetscCall(PetscMalloc1(st->nb, &v->P));
  for (PetscInt b = 0; b < st->nb; b++) PetscCall(MatDuplicate(sys->P[b], MAT_COPY_VALUES, &v->P[b]));
  PetscCall(KFFlexSolverGetStats(solver, &nheld, NULL, NULL));
  if (v->interest >= 0) PetscCall(KFReducerSearchVisitRecord_Private(r, st, v, sys, solver, nheld, rigid_res, evals, Lfull));
  if (v->basis.rigid_content > 1e-6 || v->basis.orthogonality > 1e-6) PetscCall(KFReducerNote_Private(r, "Krylov basis %s: rigid content %.2e, loss of M-orthogonality %.2e: the moments beyond the first blocks may not be trusted (a stiffness or mass spread the solve cannot resolve)", place, (double)v->basis.rigid_content, (double)v->basis.orthogonality));
  PetscCall(KFProgress(st->comm, "  %" PetscInt_FMT " Krylov vectors in %" PetscInt_FMT " blocks (%" PetscInt_FMT " deflated); rigid content %.1e, orthogonality %.1e; held dofs %" PetscInt_FMT, v->basis.size, v->basis.nblocks, v->basis.ndeflated, (double)v->basis.rigid_content, (double)v->basis.orthogonality, nheld));
  PetscCall(KFReducerAddPerf_Private(r, solver));
  PetscCall(KFFlexSolverDestroy(&solver));
  PetscFunctionReturn(0);
}

/* The richest candidate: the multi-angle model of every visit's whole Krylov basis (at most KF_MAX_EXPANSION visits) */
static void KFReducerRichCandidate_Private(PetscInt nc, PetscInt nfull, KFCandidate *rich)
{
  rich->family = KF_METHOD_MULTI_ANGLE;
  rich->c      = nfull;
  rich->kept   = -1;
  for (PetscInt i = 0; i < nc && rich->nexp < KF_MAX_EXPANSION; i++) rich->exp[rich->nexp++] = i;
}

/* Without verification, the estimator: the richest candidate, every basis whole, stands in for the full order */
static PetscErrorCode KFReducerSearchEstimator_Private(KFReducer r, KFSearch *st, PetscInt neval, KFEvalPoint evals[], PetscReal Lfull[])
{
  const PetscInt nc = st->nc, nfull = st->nfull, t = st->t, a = st->a;
  KFVisit       *visits = st->visits;
  PetscReal     *times = st->times;
  PetscLogDouble t0, t1;

  PetscFunctionBegin;
if (!r->verify) { /* the estimator: the richest candidate, every basis whole */
  KFCandidate    rich = {0};
  KFReducedModel model;

  PetscCall(PetscTime(&t0)); /* its model is projection work (the bodies' bases and reduced matrices) */
  KFReducerRichCandidate_Private(nc, nfull, &rich);
  PetscCall(KFCandidateModel_Private(r, visits, &rich, PETSC_FALSE, &model));
  PetscCall(KFReducedModelSetSetting(model, "max_frequency_hz", "0")); /* the reference is never trimmed */
  for (PetscInt e = 0; e < neval; e++) PetscCall(KFReducedModelReassemble(model, evals[e].angles, &evals[e].rich));
  PetscCall(PetscTime(&t1));
  times[5] += t1 - t0;
  if (!KFReducerFullMoments_Private(r)) {
    /* the moment checks' reference without the full-order solves: the richest candidate holds every angle's whole
       Krylov basis, so its moments are the full order's (to the solves' accuracy) at the angles of interest */
    const PetscInt shape[3] = {t, a, nfull};

    PetscCall(PetscTime(&t0));
    for (PetscInt ci = 0; ci < r->nconfig; ci++) {
      PetscCall(KFReducedSystemMoments(evals[ci].rich, nfull, &Lfull[ci * nfull * t * a]));
      PetscCall(KFReducerResultSet_Private(r, ci, "full_moments", 3, shape, &Lfull[ci * nfull * t * a]));
      PetscCall(KFReducerResultScalar_Private(r, ci, "full_moments_estimated", 1.0));
    }
    PetscCall(PetscTime(&t1));
    times[4] += t1 - t0;
  }
  PetscCall(KFReducedModelDestroy(&model));
  if (!r->certify) PetscCall(KFReducerNote_Private(r, "verification off: errors are estimated against the richest candidate (every basis whole, %" PetscInt_FMT " moments, %" PetscInt_FMT " expansion angles), not measured against the full order", nfull, rich.nexp));
}
  PetscFunctionReturn(0);
}

/* With verification, the parent every search candidate is a sub-basis of, made before the search: the body basis of
   every visit's whole Krylov basis, as the estimator's richest model makes it without verification. The search
   would otherwise make a parent the full way (products with the bodies' M and K, pivoted Gram-Schmidt, K Psi in
   extended precision) for each angle's single-angle family and for each set of expansion angles of the multi-angle
   family, five on the 202k-dof solid, each of the bodies' size; one parent of all angles costs less than two of them.
   Not when the search tries a single named angle (its own parent is smaller). */
static PetscErrorCode KFReducerSearchParent_Private(KFReducer r, KFSearch *st)
{
  KFCandidate    rich = {0};
  KFReducedModel model;
  PetscInt       ninterest = 0;

  PetscFunctionBegin;
  if (!r->sub_bases || st->nc < 2 || st->nc > KF_MAX_EXPANSION) PetscFunctionReturn(0);
  for (PetscInt i = 0; i < st->nc; i++) {
    if (!st->visits[i].basis.nblocks) PetscFunctionReturn(0); /* an eigen basis: no parent of it */
    ninterest += st->visits[i].interest >= 0;
  }
  if (ninterest < 2 || (r->method == KF_METHOD_SINGLE_ANGLE && !r->auto_alpha)) PetscFunctionReturn(0);
  KFReducerRichCandidate_Private(st->nc, st->nfull, &rich);
  PetscCall(KFCandidateModel_Private(r, st->visits, &rich, PETSC_FALSE, &model));
  PetscCall(KFReducedModelDestroy(&model));
  PetscFunctionReturn(0);
}

/* The method of the chosen model: of the two that meet the target the smaller, else the one that meets it, else the
   one nearer it */
static PetscErrorCode KFReducerSearchChoose_Private(KFReducer r, const KFCandidate *sp_, const KFCandidate *mp_)
{
  const KFCandidate single = *sp_, multi = *mp_;

  PetscFunctionBegin;
  {
    const PetscBool sp = (PetscBool)(single.nexp && single.complete && single.error <= r->accuracy), mp = (PetscBool)(multi.nexp && multi.complete && multi.error <= r->accuracy);

    if (sp && mp) r->chosen = KFCandidateSizeAgainst(&multi, &single) < KFCandidateSizeAgainst(&single, &multi) || (KFCandidateSizeAgainst(&multi, &single) == KFCandidateSizeAgainst(&single, &multi) && multi.error < single.error) ? KF_METHOD_MULTI_ANGLE : KF_METHOD_SINGLE_ANGLE;
    else if (sp || mp) r->chosen = sp ? KF_METHOD_SINGLE_ANGLE : KF_METHOD_MULTI_ANGLE;
    else r->chosen = !single.nexp || (multi.nexp && multi.error < single.error) ? KF_METHOD_MULTI_ANGLE : KF_METHOD_SINGLE_ANGLE;
  }
  PetscFunctionReturn(0);
}

/* The kept modes of the single-angle model, in its sub-basis: what the report's tables show. Arrays of m (kept: its
   nkept 1-based indices). */
static PetscErrorCode KFReducerSearchKeptModes_Private(const KFCandidate *sp_, PetscInt m, const PetscReal lambda[], const PetscReal imp[], const PetscInt clu[], PetscInt nclu, PetscReal freq[], PetscReal keptf[], PetscReal kept[], PetscReal cluf[], PetscInt *nkept_)
{
  const KFCandidate single = *sp_;
  PetscInt          nkept = 0;

  PetscFunctionBegin;
  {
    PetscReal *ci;
    PetscInt  *order;

    PetscCall(PetscCalloc2(PetscMax(nclu, 1), &ci, PetscMax(nclu, 1), &order));
    for (PetscInt i = 0; i < m; i++)
      if (clu[i] >= 0) ci[clu[i]] = PetscMax(ci[clu[i]], imp[i]);
    PetscInt skept = single.kept;

    if (single.nbody) /* each body its share: the clusters of the body that keeps the most */
      for (PetscInt b = 0; b < single.nbody; b++) skept = PetscMax(skept, single.bkept[b]);
    for (PetscInt k = 0; k < nclu; k++) { /* the kept clusters are the skept most important */
      PetscInt rank = 0;

      for (PetscInt q = 0; q < nclu; q++) rank += ci[q] > ci[k] || (ci[q] == ci[k] && q < k);
      order[k] = rank;
    }
    for (PetscInt i = 0; i < m; i++) {
      keptf[i] = clu[i] >= 0 && (skept < 0 || order[clu[i]] < skept) ? 1.0 : 0.0;
      freq[i]  = PetscSqrtReal(PetscMax(lambda[i], 0)) / (2 * PETSC_PI);
      cluf[i]  = (PetscReal)clu[i];
      if (keptf[i] > 0) kept[nkept++] = (PetscReal)(i + 1);
    }
    PetscCall(PetscFree2(ci, order));
  }
  *nkept_ = nkept;
  PetscFunctionReturn(0);
}

/* The search's results: the single-angle model's modes at every angle of interest, what the chosen models keep, their
   sizes, and the rule in one sentence */
static PetscErrorCode KFReducerSearchRecord_Private(KFReducer r, KFSearch *st, const KFCandidate *sp_, const KFCandidate *mp_)
{
  const KFCandidate single = *sp_, multi = *mp_;
  const PetscInt    g = single.exp[0], shape[2] = {st->nrev1, 1}, nb = st->nb, nrev = st->nrev, nrev1 = st->nrev1, a = st->a;
  PetscInt          m, nclu, *clu, nkept = 0, nstatic;
  PetscReal        *lambda, *Phi, *imp, *freq, *keptf, *kept, *cluf, *dofs;
  char              label[128];
  KFVisit          *visits = st->visits, *v = &visits[g];

  PetscFunctionBegin;
  PetscCall(KFReducerConfigLabel_Private(nrev, v->angles, label, sizeof(label)));
  PetscCall(KFVisitModes_Private(r, v, single.c, &m, &lambda, &Phi, &imp, &clu, &nclu));
  PetscCall(PetscMalloc5(m, &freq, m, &keptf, m, &kept, m, &cluf, nb, &dofs));
  PetscCall(KFReducerSearchKeptModes_Private(&single, m, lambda, imp, clu, nclu, freq, keptf, kept, cluf, &nkept));
  nstatic = nkept < m && r->static_correction && !single.nostatic ? a : 0;
  for (PetscInt ci = 0; ci < r->nconfig; ci++) {
    PetscCall(KFReducerResultSet_Private(r, ci, "krylov_frequencies_hz", 1, &m, freq));
    PetscCall(KFReducerResultSet_Private(r, ci, "krylov_importance", 1, &m, imp));
    PetscCall(KFReducerResultSet_Private(r, ci, "krylov_kept", 1, &m, keptf));
    PetscCall(KFReducerResultSet_Private(r, ci, "krylov_clusters", 1, &m, cluf));
  }
  PetscCall(KFReducerResultSet_Private(r, -1, "reduction_angles", 2, shape, v->angles));
  PetscCall(KFReducerResultScalar_Private(r, -1, "reduction_config", (PetscReal)v->interest));
  PetscCall(KFReducerResultSet_Private(r, -1, "kept_modes", 1, &nkept, kept));
  PetscCall(KFReducerResultScalar_Private(r, -1, "static_correction_modes", (PetscReal)nstatic));
  PetscCall(KFReducerResultScalar_Private(r, -1, "moments_matched", (PetscReal)single.c));
  { /* per body, the clusters of Krylov modes the chosen model keeps (-1: every mode) */
    const KFCandidate *ch = r->chosen == KF_METHOD_MULTI_ANGLE && multi.nexp ? &multi : &single;

    for (PetscInt b = 0; b < nb; b++) dofs[b] = (PetscReal)(ch->nbody ? ch->bkept[b] : ch->kept);
    PetscCall(KFReducerResultSet_Private(r, -1, "body_kept_clusters", 1, &nb, dofs));
  }
  {
    PetscInt nrigid;
    PetscCall(KFSceneGetRigidCount(r->scene, &nrigid)); /* derived from geometry, joints and boundary conditions */
    PetscCall(KFReducerResultScalar_Private(r, -1, "rigid_modes", (PetscReal)nrigid));
  }
  {
    PetscInt nsys;

    PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, NULL, &nsys, NULL, NULL));
    PetscCall(KFReducerResultScalar_Private(r, -1, "full_system_dofs", (PetscReal)nsys));
  }
  PetscCall(KFReducerRecordBodySizes_Private(r, r->single, "reduced_dofs_per_body"));
  if (r->multi_model) {
    PetscReal     *ma;
    const PetscInt mshape[2] = {nrev1, multi.nexp};

    PetscCall(KFReducerRecordBodySizes_Private(r, r->multi_model, "multi_dofs_per_body"));
    PetscCall(PetscMalloc1(nrev1 * multi.nexp, &ma));
    for (PetscInt e = 0; e < multi.nexp; e++) PetscCall(PetscArraycpy(&ma[e * nrev1], visits[multi.exp[e]].angles, nrev1));
    PetscCall(KFReducerResultSet_Private(r, -1, "multi_reduction_angles", 2, mshape, ma));
    PetscCall(KFReducerResultScalar_Private(r, -1, "multi_moments_matched", (PetscReal)multi.c));
    PetscCall(PetscFree(ma));
  }
  if (!nrev) PetscCall(PetscSNPrintf(r->rule, sizeof(r->rule), "the accuracy search: the smallest model meeting relative H-inf error %g of the %s response of the structure is %" PetscInt_FMT " moments%s (%" PetscInt_FMT " reduced dofs)%s", (double)r->accuracy, KFAccuracyMeasures[r->accuracy_measure], single.c,
                                     single.kept == -1 ? ", every Krylov mode" : (single.nbody ? ", each body its share of the important clusters + static correction" : ", important clusters + static correction"), single.size, (single.complete && single.error <= r->accuracy) ? "" : " (misses the target)"));
  else PetscCall(PetscSNPrintf(r->rule, sizeof(r->rule), "the accuracy search: the smallest model meeting relative H-inf error %g of the %s response at the %" PetscInt_FMT " angles of interest and the midpoints between them is %s (%" PetscInt_FMT " moments%s%s, %" PetscInt_FMT " reduced dofs); single-angle alpha_G = %s deg with %" PetscInt_FMT " moments%s", (double)r->accuracy, KFAccuracyMeasures[r->accuracy_measure], r->nconfig, r->chosen == KF_METHOD_MULTI_ANGLE ? "multi-angle" : "single-angle", r->chosen == KF_METHOD_MULTI_ANGLE ? multi.c : single.c,
                         r->chosen == KF_METHOD_MULTI_ANGLE ? ", bases at several angles" : "", r->chosen == KF_METHOD_MULTI_ANGLE ? "" : (single.kept == -1 ? ", every Krylov mode" : (single.nbody ? ", each body its share of the important clusters + static correction" : ", important clusters + static correction")), r->chosen == KF_METHOD_MULTI_ANGLE ? multi.size : single.size, label, single.c, (single.complete && single.error <= r->accuracy) ? "" : " (misses the target)"));
  PetscCall(KFProgress(st->comm, "%s", r->rule));
  PetscCall(PetscFree5(freq, keptf, kept, cluf, dofs));
  PetscCall(PetscFree4(lambda, Phi, imp, clu));
  {
    char sizes[256], tmp[256] = "";

    PetscCall(KFReducerModelSizes_Private(r->single, sizes, sizeof(sizes)));
    if (r->multi_model) {
      char ms[200];

      PetscCall(KFReducerModelSizes_Private(r->multi_model, ms, sizeof(ms)));
      PetscCall(PetscSNPrintf(tmp, sizeof(tmp), "; %s dofs (multi-angle)", ms));
    }
    PetscCall(KFProgress(st->comm, "reduced bodies: %s dofs (single-angle)%s", sizes, tmp));
  }
  PetscFunctionReturn(0);
}

/* a model's reassembled system dofs, the largest over the evaluation points (what is simulated) */
static PetscErrorCode KFReducerSystemDofs_Private(PetscInt neval, KFEvalPoint evals[], KFReducedModel model, PetscInt *n)
{
  PetscFunctionBegin;
  *n = 0;
  for (PetscInt e = 0; e < neval; e++) {
    KFReducedSystem rs;
    PetscInt        ne;

    PetscCall(KFReducedModelReassemble(model, evals[e].angles, &rs));
    PetscCall(KFReducedSystemGetMatrices(rs, &ne, NULL, NULL, NULL, NULL, NULL, NULL));
    PetscCall(KFReducedSystemDestroy(&rs));
    *n = PetscMax(*n, ne);
  }
  PetscFunctionReturn(0);
}

/* -kf_shared_directions auto, a tied model chosen: the split model the search would have chosen, compressed body by
   body, may have fewer system dofs than the tied one compressed across the bodies (tsys of them). Measured; when it has no more, the split candidates replace the
   tied ones and the model measured is the one chosen, already compressed (*nties 0, cz[] its dofs before and after,
   *ckept whether the static columns stayed, *csec += the compression's seconds: the caller records them and does not
   compress again; *crow the compressed model's search-table row, crow->compressed 0 when nothing was gained) */
static PetscErrorCode KFReducerSplitCompressed_Private(KFReducer r, KFSearch *st, PetscInt neval, KFEvalPoint evals[], PetscInt tsys, KFCandidate *single, KFCandidate *multi, const KFCandidate split[2], PetscInt *nties, PetscInt cz[2], PetscBool *ckept, PetscLogDouble *csec, KFCandidate *crow)
{
  const KFReducerMethod tchosen = r->chosen;
  const KFCandidate    *alt;
  KFReducedModel        model;
  PetscInt              from, to, n = 0;
  PetscBool             kept;
  PetscReal             cerr;
  PetscLogDouble        c0, c1;

  PetscFunctionBegin;
  PetscCall(KFReducerSearchChoose_Private(r, &split[0], &split[1]));
  alt = r->chosen == KF_METHOD_MULTI_ANGLE && split[1].nexp ? &split[1] : &split[0];
  if (!alt->nexp || !alt->complete || alt->error > r->accuracy) {
    r->chosen = tchosen;
    PetscFunctionReturn(0);
  }
  PetscCall(KFCandidateModel_Private(r, st->visits, alt, PETSC_TRUE, &model)); /* with its maps: it may be the one returned */
  PetscCall(PetscTime(&c0));
  PetscCall(KFReducerCompress_Private(r, neval, evals, PETSC_FALSE, &model, &from, &to, &kept, &cerr));
  PetscCall(PetscTime(&c1));
  *csec += c1 - c0;
  PetscCall(KFReducerSystemDofs_Private(neval, evals, model, &n));
  if (to < from) { /* its row of the search table */
    *crow            = *alt;
    crow->compressed = 1;
    crow->size       = to;
    crow->sysdofs    = n;
    crow->error      = cerr;
  }
  PetscCall(PetscInfo(r, "shared directions auto: tied %" PetscInt_FMT " system dofs, split compressed %" PetscInt_FMT "\n", tsys, n));
  if (n > tsys) {
    PetscCall(KFReducedModelDestroy(&model));
    r->chosen = tchosen;
    PetscFunctionReturn(0);
  }
  *single = split[0];
  *multi  = split[1];
  if (!single->nexp) { /* as the caller's: the single-angle model of the first expansion angle, for reference */
    *single        = *multi;
    single->family = KF_METHOD_SINGLE_ANGLE;
    single->nexp   = 1;
  }
  PetscCall(KFReducedModelDestroy(&r->single));
  PetscCall(KFReducedModelDestroy(&r->multi_model));
  if (alt == &split[1]) { /* the multi-angle model chosen: the measured one; the single-angle one made for reference */
    r->multi_model = model;
    PetscCall(KFCandidateModel_Private(r, st->visits, single, PETSC_TRUE, &r->single));
  } else {
    r->single = model;
    if (multi->nexp) PetscCall(KFCandidateModel_Private(r, st->visits, multi, PETSC_TRUE, &r->multi_model));
  }
  *nties = 0;
  cz[0]  = from;
  cz[1]  = to;
  *ckept = kept;
  PetscFunctionReturn(0);
}

/* The accuracy search: every configuration visited (KFReducerSearchVisit_Private), the references or the estimator set
   up, the smallest models meeting the target found (src/reducer/search.c, shifts.c), then made and recorded */
static PetscErrorCode KFReducerSolveSearch_Private(KFReducer r, PetscInt neval, KFEvalPoint evals[], PetscReal Lfull[])
{
  KFSearch       st;
  KFSystem       sys;
  KFCandidate    single, multi, split[2];
  PetscInt       nties = 0, cz[2] = {-1, -1}; /* cz: the chosen model already compressed, its dofs before and after */
  PetscBool      ckept = PETSC_TRUE;
  PetscLogDouble csec  = 0;
  PetscInt       nrows, *ccount = NULL, *crigid = NULL;
  PetscReal     *rows, *csigma = NULL;
  PetscLogDouble t0, t1;

  PetscFunctionBegin;
  PetscCall(PetscMemzero(&st, sizeof(st)));
  st.nfull = r->build_moments;
  PetscCall(PetscObjectGetComm((PetscObject)r, &st.comm));
  PetscCall(KFSceneGetInfo(r->scene, &st.nb, NULL, &st.nrev, NULL, &st.a, &st.t));
  st.nrev1 = PetscMax(st.nrev, 1);
  PetscCall(KFReducerConfigurations_Private(r, st.nrev1, &st.nc, &st.configs));
  PetscCall(PetscCalloc1(st.nc, &st.visits));
  PetscCall(KFReducerSystemCreate_Private(r, &sys));
  PetscCall(KFSystemSetConfigurationCount(sys, st.nc + (r->verify || r->certify ? neval - r->nconfig : 0))); /* the midpoints' references or counts too */
  for (PetscInt i = 0; i < st.nc; i++) PetscCall(KFReducerSearchVisit_Private(r, &st, i, sys, evals, Lfull));
  if (r->verify) PetscCall(KFReducerMidpointReferences_Private(r, sys, neval, evals, &st.times[6]));
  if (r->certify) { /* the helper process's counts (src/reducer/certify.c), else counted here */
    PetscBool got = PETSC_FALSE;

    PetscCall(PetscMalloc3(neval, &ccount, neval, &crigid, neval, &csigma));
    PetscCall(KFReducerCertifyCountRead_Private(r, neval, evals, ccount, crigid, csigma, &got));
    if (!got) PetscCall(KFReducerCertifyCount_Private(r, sys, (PetscBool)!r->max_factorizations, neval, evals, ccount, crigid, csigma));
  }
  PetscCall(KFBodyFactorsDestroy(&r->count_bf)); /* the last reference is made: the count's factors go */
  if (!r->max_factorizations) PetscCall(KFSystemDestroy(&sys)); /* else kept for the expansion points' factorizations */
  if (!r->verify) PetscCall(KFReducerSearchEstimator_Private(r, &st, neval, evals, Lfull));
  if (r->certify) {
    PetscBool certified;

    PetscCall(KFReducerCertifyCompare_Private(r, neval, evals, ccount, crigid, csigma, &certified));
    PetscCall(PetscFree3(ccount, crigid, csigma));
    if (!certified) PetscCall(KFReducerCertifyFallback_Private(r, neval, evals, st.nfull, Lfull, &st.times[6]));
  }
  if (r->verify) { /* the truth the references are checked against, verification too */
    const PetscLogDouble c0 = r->verify_check_seconds;

    PetscCall(KFReducerDirectChecks_Private(r, neval, evals));
    st.times[6] += r->verify_check_seconds - c0;
  }
  for (PetscInt e = 0; e < neval; e++) PetscCall(KFEvalPointSetUp_Private(r, &evals[e]));

  if (!st.nrev) PetscCall(KFProgress(st.comm, "searching the smallest model with relative H-inf error of the %s response <= %g of the structure", KFAccuracyMeasures[r->accuracy_measure], (double)r->accuracy));
  else PetscCall(KFProgress(st.comm, "searching the smallest model with relative H-inf error of the %s response <= %g at %" PetscInt_FMT " angles (%" PetscInt_FMT " of interest, %" PetscInt_FMT " midpoints)", KFAccuracyMeasures[r->accuracy_measure], (double)r->accuracy, neval, r->nconfig, neval - r->nconfig));
  PetscCall(PetscTime(&t0));
  if (r->verify) PetscCall(KFReducerSearchParent_Private(r, &st));
  PetscCall(KFReducerSearch_Private(r, st.nc, st.visits, neval, evals, &single, &multi, split, &nrows, &rows));
  PetscCall(KFReducerSearchShifts_Private(r, sys, &st.nc, &st.visits, neval, evals, &single, &multi, &nrows, &rows));
  PetscCall(KFSystemDestroy(&sys));
  PetscCall(PetscTime(&t1)); /* the search's share of the projection stage, apart: what the proof's cost is made of */
  PetscCall(KFReducerResultScalar_Private(r, -1, "time_search", (PetscReal)(t1 - t0)));
  PetscCheck(single.nexp || multi.nexp, st.comm, PETSC_ERR_PLIB, "the accuracy search tried no model");
  PetscCall(KFReducerSearchChoose_Private(r, &single, &multi));
  if (!single.nexp) { /* multi-angle only: the single-angle model of the first expansion angle, whole, for reference */
    single        = multi;
    single.family = KF_METHOD_SINGLE_ANGLE;
    single.nexp   = 1;
  }
  PetscCall(KFCandidateModel_Private(r, st.visits, &single, PETSC_TRUE, &r->single));
  if (multi.nexp) PetscCall(KFCandidateModel_Private(r, st.visits, &multi, PETSC_TRUE, &r->multi_model));
  if (r->compress) { /* the chosen model compressed: tied across its bodies (-kf_shared_directions true or auto) and
                        body by body (false or auto); under auto the smaller by system dofs, the body-wise one at equal */
    KFReducedModel *chosen = r->chosen == KF_METHOD_MULTI_ANGLE && r->multi_model ? &r->multi_model : &r->single;
    KFReducedModel  tmodel = NULL;
    PetscInt        from = 0, to = 0, tfrom = 0, tto = 0, tsys = PETSC_MAX_INT, ssys;
    PetscBool       kept = PETSC_TRUE, tkept = PETSC_TRUE, tied_won = PETSC_FALSE, nostatic;
    PetscReal       terr = -1, serr = -1;
    PetscLogDouble  c0, c1;
    KFCandidate     crow[2]; /* the search-table rows of the compressed models: tied, body by body */

    nostatic = (r->chosen == KF_METHOD_MULTI_ANGLE && multi.nexp ? multi : single).nostatic;
    crow[0]  = r->chosen == KF_METHOD_MULTI_ANGLE && multi.nexp ? multi : single;
    crow[1]  = crow[0];
    crow[0].compressed = crow[1].compressed = 0;
    PetscCall(KFReducedModelGetTies(*chosen, &nties, NULL, NULL));
    if (r->shared_directions || r->shared_auto) { /* across the bodies: on a reference, the chosen model kept for the body-wise one */
      tmodel = *chosen;
      PetscCall(PetscObjectReference((PetscObject)tmodel));
      PetscCall(PetscTime(&c0));
      PetscCall(KFReducerCompress_Private(r, neval, evals, PETSC_TRUE, &tmodel, &tfrom, &tto, &tkept, &terr));
      PetscCall(PetscTime(&c1));
      csec += c1 - c0;
      PetscCall(KFReducerSystemDofs_Private(neval, evals, tmodel, &tsys));
      if (tto < tfrom) {
        crow[0].compressed = 2;
        crow[0].size       = tto;
        crow[0].sysdofs    = tsys;
        crow[0].error      = terr;
      }
    }
    if (r->shared_directions) tied_won = PETSC_TRUE;
    else if (nties) { /* auto, a tied model chosen: its split rival compressed */
      PetscCall(KFReducerSplitCompressed_Private(r, &st, neval, evals, tsys, &single, &multi, split, &nties, cz, &ckept, &csec, &crow[1]));
      tied_won = (PetscBool)(nties > 0);
      if (!tied_won) {
        from = cz[0];
        to   = cz[1];
        kept = ckept;
      }
    } else { /* split chosen: compressed body by body */
      PetscCall(PetscTime(&c0));
      PetscCall(KFReducerCompress_Private(r, neval, evals, PETSC_FALSE, chosen, &from, &to, &kept, &serr));
      PetscCall(PetscTime(&c1));
      csec += c1 - c0;
      PetscCall(KFReducerSystemDofs_Private(neval, evals, *chosen, &ssys));
      if (to < from) {
        crow[1].compressed = 1;
        crow[1].size       = to;
        crow[1].sysdofs    = ssys;
        crow[1].error      = serr;
      }
      if (tmodel) {
        PetscCall(PetscInfo(r, "compression: tied across the bodies %" PetscInt_FMT " system dofs, body by body %" PetscInt_FMT "\n", tsys, ssys));
        tied_won = (PetscBool)(tsys < ssys);
      }
    }
    chosen = r->chosen == KF_METHOD_MULTI_ANGLE && r->multi_model ? &r->multi_model : &r->single;
    if (tied_won) {
      PetscCall(KFReducedModelDestroy(chosen));
      *chosen = tmodel;
      from    = tfrom;
      to      = tto;
      kept    = (PetscBool)(tkept && !nostatic);
    } else PetscCall(KFReducedModelDestroy(&tmodel));
    for (PetscInt k = 0; k < 2; k++) /* the compressed models measured: rows after the search's */
      if (crow[k].compressed) {
        PetscCall(PetscRealloc(sizeof(PetscReal) * KF_SEARCH_TABLE_COLUMNS * (nrows + 1), &rows));
        KFSearchTableRow_Private(r, &crow[k], &rows[KF_SEARCH_TABLE_COLUMNS * nrows++]);
      }
    PetscCall(KFReducerResultScalar_Private(r, -1, "time_compress", (PetscReal)csec));
    PetscCall(KFReducerResultScalar_Private(r, -1, "compressed_from_dofs", (PetscReal)from));
    PetscCall(KFReducerResultScalar_Private(r, -1, "compressed_to_dofs", (PetscReal)to));
    PetscCall(KFReducerResultScalar_Private(r, -1, "compressed_tied", tied_won ? 1.0 : 0.0));
    /* a compression without the static columns changes L^0: the summary reports its measured error, not "exact" */
    PetscCall(KFReducerResultScalar_Private(r, -1, "static_exact", kept ? 1.0 : 0.0));
    if (to < from) PetscCall(KFProgress(st.comm, "compressed: %" PetscInt_FMT " -> %" PetscInt_FMT " reduced dofs (%s)", from, to, tied_won ? "tied: the leading directions of the whole response across the bodies" : "each body its leading directions of the response"));
    else PetscCall(KFProgress(st.comm, "compression: no direction can go and the model meet the target (%" PetscInt_FMT " reduced dofs kept)", from));
  } else {
    KFReducedModel *chosen = r->chosen == KF_METHOD_MULTI_ANGLE && r->multi_model ? &r->multi_model : &r->single;

    PetscCall(KFReducedModelGetTies(*chosen, &nties, NULL, NULL));
    if ((nties || r->shared_directions) && (r->chosen == KF_METHOD_MULTI_ANGLE && multi.nexp ? multi : single).nostatic) PetscCall(KFReducerResultScalar_Private(r, -1, "static_exact", 0.0));
  }
  {
    const PetscInt shape[2] = {KF_SEARCH_TABLE_COLUMNS, nrows};

    PetscCall(KFReducerResultSet_Private(r, -1, "search_table", 2, shape, rows));
    PetscCall(PetscFree(rows));
  }
  PetscCall(PetscTime(&t1));
  st.times[5] += t1 - t0;
  { /* the chosen candidate's search-table row names it: its variant and size (a tied model's, body dofs less its ties) */
    const KFCandidate *c = r->chosen == KF_METHOD_MULTI_ANGLE && multi.nexp ? &multi : &single;

    PetscCall(KFReducerResultScalar_Private(r, -1, "chosen_variant", KFCandidateVariant_Private(r, c)));
    PetscCall(KFReducerResultScalar_Private(r, -1, "chosen_search_dofs", (PetscReal)c->size));
  }
  PetscCall(KFReducerSearchRecord_Private(r, &st, &single, &multi));
  for (PetscInt k = 0; k < 7; k++) PetscCall(KFReducerResultScalar_Private(r, -1, KFSolveTimeNames[k], st.times[k]));
  PetscCall(KFReducerResultScalar_Private(r, -1, "time_factor_setup", st.setup_s));
  for (PetscInt i = 0; i < st.nc; i++) PetscCall(KFVisitDestroy_Private(r, &st.visits[i]));
  PetscCall(KFCandidateCacheReset_Private(r)); /* its body bases belong to these visits */
  PetscCall(PetscFree(st.visits));
  PetscCall(PetscFree(st.configs));
  PetscFunctionReturn(0);
}

/* The cost of the solve, stage by stage, with the flexible solvers' factorizations and block solves apart: a result
   "timings" (seconds: assembly, factorization, solves, basis without its solves, modes, moments, projection,
   verification, whole; then whole without verification / (factorization + solves)), scalars for the solver's
   work, and a table at the end of the progress lines. The ratio says how much of a reduction is not the
   factorization and the solves (1: nothing else). The table accounts for every second of whole: "factor set-up" is
   the factorization stage outside MUMPS (time_factor_setup), "other" what no stage holds (time_other). */
static PetscErrorCode KFReducerTimingTable_Private(KFReducer r, PetscLogDouble whole)
{
  static const char *const stages[] = {"time_assembly", "time_factorization", "time_basis", "time_modes", "time_moments", "time_projection", "time_verification"};
  MPI_Comm         comm;
  PetscReal        st[7] = {0}, tab[10], fs, ratio, setup, other;
  const PetscInt   n = 10;
  const PetscReal *v;
  KFFlexSolverPerf *p = &r->perf;

  PetscFunctionBegin;
  PetscCall(PetscObjectGetComm((PetscObject)r, &comm));
  for (PetscInt k = 0; k < 7; k++) { /* both ways of solving record every stage */
    PetscCall(KFReducerGetResult(r, -1, stages[k], NULL, NULL, &v));
    st[k] = v[0];
  }
  /* the ranks' clocks differ a little: every rank reports rank 0's figures */
  {
    PetscReal w = (PetscReal)whole, f = (PetscReal)p->factor_seconds, sv = (PetscReal)p->solve_seconds, buf[3] = {w, f, sv};

    PetscCallMPI(MPI_Bcast(buf, 3, MPIU_REAL, 0, comm));
    whole = buf[0];
    p->factor_seconds = buf[1];
    p->solve_seconds  = buf[2];
  }
  PetscCall(KFReducerGetResult(r, -1, "time_factor_setup", NULL, NULL, &v));
  setup = v[0];
  /* what no stage holds (the announcement, the estimator's richest model, the comparison, destroying the system):
     the table accounts for every second of whole */
  other = (PetscReal)whole;
  for (PetscInt k = 0; k < 7; k++) other -= st[k];
  fs     = (PetscReal)(p->factor_seconds + p->solve_seconds);
  ratio  = fs > 0 ? ((PetscReal)whole - st[6]) / fs : (PetscReal)NAN;
  tab[0] = st[0];
  tab[1] = (PetscReal)p->factor_seconds;
  tab[2] = (PetscReal)p->solve_seconds;
  tab[3] = st[2]; /* the basis stage, its solves included (the solves are also in tab[2]) */
  tab[4] = st[3];
  tab[5] = st[4];
  tab[6] = st[5];
  tab[7] = st[6];
  tab[8] = (PetscReal)whole;
  tab[9] = ratio;
  PetscCall(KFReducerResultSet_Private(r, -1, "timings", 1, &n, tab));
  PetscCall(KFReducerResultScalar_Private(r, -1, "time_solves", (PetscReal)p->solve_seconds));
  PetscCall(KFReducerResultScalar_Private(r, -1, "time_factor_total", (PetscReal)p->factor_seconds));
  PetscCall(KFReducerResultScalar_Private(r, -1, "time_whole", (PetscReal)whole));
  PetscCall(KFReducerResultScalar_Private(r, -1, "time_ratio", ratio));
  PetscCall(KFReducerResultScalar_Private(r, -1, "time_other", other));
  PetscCall(KFReducerResultScalar_Private(r, -1, "solve_calls", (PetscReal)p->solve_calls));
  PetscCall(KFReducerResultScalar_Private(r, -1, "solve_columns", (PetscReal)p->solve_columns));
  PetscCall(KFReducerResultScalar_Private(r, -1, "solve_blocks", (PetscReal)p->blocks));
  PetscCall(KFReducerResultScalar_Private(r, -1, "refinement_solves", (PetscReal)p->refinement_solves));
  PetscCall(KFReducerResultScalar_Private(r, -1, "solve_blocks_unconverged", (PetscReal)p->blocks_unconverged));
  PetscCall(KFReducerResultScalar_Private(r, -1, "solve_blocks_escalated", (PetscReal)p->blocks_escalated));
  PetscCall(KFReducerResultScalar_Private(r, -1, "solve_residual_first_max", p->residual_first_max));
  PetscCall(KFReducerResultScalar_Private(r, -1, "solve_residual_final_max", p->residual_final_max));
  PetscCall(KFReducerResultScalar_Private(r, -1, "factor_memory_estimate_mb", p->memory_estimate_mb));
  PetscCall(KFProgress(comm, "timings (s): assembly %.3g | factor set-up %.3g | factorization %.3g (MUMPS estimate %.0f MB per rank) | block solves %.3g (%" PetscInt_FMT " MatMatSolve, %" PetscInt_FMT " columns, %" PetscInt_FMT " of %" PetscInt_FMT " blocks refined; residual first %.1e, final %.1e)", (double)tab[0], (double)setup, (double)tab[1], (double)p->memory_estimate_mb, (double)tab[2], p->solve_calls, p->solve_columns, p->blocks_refined, p->blocks, (double)p->residual_first_max, (double)p->residual_final_max));
  if (p->blocks_unconverged) PetscCall(KFProgress(comm, "warning: %" PetscInt_FMT " of %" PetscInt_FMT " block solves stayed above -kf_refine_rtol after refinement (largest final residual %.1e), escalation included (more steps, a full-rank factor for a block low-rank one): their Krylov vectors are that inexact; the verdict rests on the verification's direct solves", p->blocks_unconverged, p->blocks, (double)p->residual_final_max));
  if (p->blocks_unconverged) /* and a note: the summary, the report and the command's last lines carry it, -quiet or not */
    PetscCall(KFReducerNote_Private(r, "%" PetscInt_FMT " of %" PetscInt_FMT " block solves stayed above -kf_refine_rtol after refinement and escalation (more steps, a full-rank factor where block low-rank was used; largest final residual %.1e): their Krylov vectors are that inexact, the moments matched only so far; the verdict rests on the verification's direct solves (keep -kf_verify on). Check the model's conditioning (units, near-mechanisms) or drop -kf_blr", p->blocks_unconverged, p->blocks, (double)p->residual_final_max));
  PetscCall(KFProgress(comm, "timings (s): basis %.3g (solves included) | modes %.3g | moments %.3g | projection %.3g | verification %.3g | other %.3g | whole %.3g | (whole - verification) / (factorization + solves) = %.3g", (double)tab[3], (double)tab[4], (double)tab[5], (double)tab[6], (double)tab[7], (double)other, (double)tab[8], (double)ratio));
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerSolve(KFReducer r)
{
  MPI_Comm     comm;
  KFEvalPoint *evals;
  PetscInt     neval = 0, a, t, nfull;
  PetscReal   *Lfull;
  PetscBool    search;
  PetscLogDouble tstart, tend;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCall(KFReducerSetUp(r));
  PetscCall(PetscObjectGetComm((PetscObject)r, &comm));
  PetscCall(KFReducerViewFromOptions(r, NULL, "-kf_reducer_view_pre"));
  PetscCall(PetscLogEventBegin(KF_EVENT_REDUCER_SOLVE, r, 0, 0, 0));
  PetscCall(KFReducerReset(r));
  r->verify_check_worst    = -1;
  r->verify_check_worst_hz = 0;
  r->verify_check_seconds  = 0;
  r->verify_eigen_seconds  = 0;
  r->verify_count_seconds  = 0;
  r->verify_check_iter_points    = 0;
  r->verify_check_iter_steps     = 0;
  r->verify_check_iter_steps_max = 0;
  r->verify_check_fallbacks      = 0;
  r->verify_check_iter_residual  = 0;
  PetscCall(PetscCalloc1(r->nconfig + 1, &r->results));
  PetscCall(PetscMemzero(&r->perf, sizeof(r->perf)));
  PetscCall(PetscTime(&tstart));
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, NULL, NULL, &a, &t));
  search = (PetscBool)(r->search && r->ops->blocks);
  if (r->search && !r->ops->blocks) PetscCall(KFReducerNote_Private(r, "the %s basis has no accuracy search: its fixed recipe was used (-kf_search applies to the krylov type)", ((PetscObject)r)->type_name));
  /* moments: the fixed number, the search's most, or the paper's 10 for a fixed recipe without a number */
  r->build_moments = r->moments != PETSC_DECIDE ? r->moments : (search ? r->moments_max : 10);
  if (r->build_moments <= r->output_blocks) r->build_moments = r->output_blocks + 1;
  nfull = r->build_moments;
  /* auto: measured below the size threshold or for a target tighter than the estimate is trusted to; else the
     estimate, certified (the search's only) */
  PetscCall(KFReducerGetVerificationPlan(r, &r->verify, &r->certify));
  PetscCall(KFReducerAnnounce_Private(r));
  PetscCall(KFReducerEvalPoints_Private(r, &neval, &evals));
  PetscCall(PetscCalloc1(r->nconfig * nfull * t * a, &Lfull));
  if (search) PetscCall(KFReducerSolveSearch_Private(r, neval, evals, Lfull));
  else {
    PetscCall(KFReducerSolveFixed_Private(r, evals, Lfull));
    if (r->verify) { /* the midpoints' references, then every point's grid */
      KFSystem  sys;
      PetscReal seconds = 0;

      PetscCall(KFSystemCreate(r->scene, &sys));
      PetscCall(KFSystemSetConfigurationCount(sys, PetscMax(neval - r->nconfig, 1)));
      PetscCall(KFReducerMidpointReferences_Private(r, sys, neval, evals, &seconds));
      PetscCall(KFBodyFactorsDestroy(&r->count_bf));
      PetscCall(KFSystemDestroy(&sys));
      seconds -= r->verify_check_seconds; /* the truth the references are checked against, verification too */
      PetscCall(KFReducerDirectChecks_Private(r, neval, evals));
      seconds += r->verify_check_seconds;
      { /* the midpoints' references are verification too */
        const PetscReal *v;

        PetscCall(KFReducerGetResult(r, -1, "time_verification", NULL, NULL, &v));
        seconds += v[0];
        PetscCall(KFReducerResultScalar_Private(r, -1, "time_verification", seconds));
      }
  for (PetscInt e = 0; e < neval; e++) PetscCall(KFEvalPointSetUp_Private(r, &evals[e]));
    }
  }
  PetscCall(KFInterruptCheck(comm));
  PetscCall(KFReducerCompare_Private(r, nfull, Lfull, neval, evals));
  PetscCall(PetscTime(&tend));
  PetscCall(KFReducerTimingTable_Private(r, tend - tstart));
  for (PetscInt e = 0; e < neval; e++) PetscCall(KFEvalPointDestroy_Private(&evals[e]));
  PetscCall(PetscFree(evals));
  PetscCall(PetscFree(Lfull));
  PetscCall(KFSystemDestroy(&r->given_sys)); /* for this solve only, taken or not */
  r->fresh_sys = NULL;
  r->solved = PETSC_TRUE;
  PetscCall(PetscLogEventEnd(KF_EVENT_REDUCER_SOLVE, r, 0, 0, 0));
  PetscCall(KFReducerViewFromOptions(r, NULL, "-kf_reducer_view"));
  {
    KFReducedModel model;

    PetscCall(KFReducerGetReducedModel(r, &model));
    PetscCall(KFReducedModelViewFromOptions(model, (PetscObject)r, "-kf_model_view"));
  }
  PetscFunctionReturn(0);
}
