/* KFReducer: life cycle, implementations, what the reduction must serve (setters) and what the solve left (getters). */
#include <kryflex/reducerimpl.h>

PetscFunctionList KFReducerList      = NULL;
static PetscBool  KFReducerPackageInitialized = PETSC_FALSE;

const char *const KFReducerMethods[] = {"single-angle", "multi-angle", "auto", "KFReducerMethod", "KF_METHOD_", NULL};
const char *const KFImportances[]    = {"h2", "hinf", "static", "band", "KFImportance", "KF_IMPORTANCE_", NULL};
const char *const KFAccuracyMeasures[] = {"elastic", "total", "KFAccuracyMeasure", "KF_ACCURACY_", NULL};

static PetscErrorCode KFReducerFinalizePackage(void)
{
  PetscFunctionBegin;
  PetscCall(PetscFunctionListDestroy(&KFReducerList));
  KFReducerPackageInitialized = PETSC_FALSE;
  PetscFunctionReturn(0);
}

/* the two implementations; once per PetscInitialize (the class id and log events: KFInitialize) */
static PetscErrorCode KFReducerInitializePackage(void)
{
  PetscFunctionBegin;
  if (KFReducerPackageInitialized) PetscFunctionReturn(0);
  KFReducerPackageInitialized = PETSC_TRUE;
  PetscCall(KFInitialize());
  PetscCall(PetscFunctionListAdd(&KFReducerList, KFREDUCERKRYLOV, KFReducerCreate_Krylov));
  PetscCall(PetscFunctionListAdd(&KFReducerList, KFREDUCEREIGEN, KFReducerCreate_Eigen));
  PetscCall(PetscRegisterFinalize(KFReducerFinalizePackage));
  PetscFunctionReturn(0);
}

/*
  KFReducerCreate - a reducer with the defaults of README.md ("Options"): Krylov basis, 10 moments of which one
  output block, h2 importance with threshold 0.05, static correction, automatic alpha_G, single-angle method,
  band 0.01-10 Hz, damping 0.0025, accuracy 0.05, full-order verification.
*/
PetscErrorCode KFReducerCreate(MPI_Comm comm, KFReducer *reducer)
{
  KFReducer r;

  PetscFunctionBegin;
  PetscValidPointer(reducer, 2);
  PetscCall(KFReducerInitializePackage());
  PetscCall(PetscHeaderCreate(r, KF_REDUCER_CLASSID, "KFReducer", "Reduction of an articulated structure", "KF", comm, KFReducerDestroy, KFReducerView));
  r->auto_alpha              = PETSC_TRUE;
  r->method                  = KF_METHOD_AUTO;
  r->band[0]                 = 0.01;
  r->band[1]                 = 10.0;
  r->zeta                    = 0.0025;
  PetscCall(KFDampingSetUniform(&r->damping, 0.0025));
  r->accuracy                = 0.05;
  r->accuracy_measure        = KF_ACCURACY_ELASTIC;
  r->moments                 = PETSC_DECIDE;
  r->moments_max             = 24;
  r->search                  = PETSC_TRUE;
  r->sub_bases               = PETSC_TRUE;
  r->cluster_rtol            = 1e-3;
  r->max_factorizations      = 0;
  r->static_exact            = PETSC_TRUE; /* L^0 exact: the compression keeps the static response's columns */
  r->compress                = PETSC_TRUE; /* measured: never loses the target (only a measured passing model replaces
                                             the chosen one), about 0.1 s; solid 32 -> 28 states at 1e-3 */
  r->shared_auto             = PETSC_TRUE; /* measured split and tied, the one with fewer system dofs kept (split on a tie):
                                             the solid at 1e-2/1e-3/1e-4 18/18/22 states against 20/24/30 split */
  r->shift_blocks            = 3; /* the solid spacecraft at 1e-4 (elastic): 23 system dofs with 3 blocks per point, no win with 2 */
  r->output_blocks           = 1;
  r->importance              = KF_IMPORTANCE_BAND;
  r->keep_threshold          = 0.05;
  r->static_correction       = PETSC_TRUE;
  r->deflation_tol           = 1e-10;
  r->body_tol                = 1e-10;
  r->reassembly_rtol         = 1e-9;
  r->shift                   = 0.0;
  r->eigen_cover             = 1.0;
  r->save_maps               = PETSC_DECIDE;
  r->save_maps_max_dofs      = 200000;
  r->gram_condition_max_dofs = 20000;
  r->negligible              = 1e-8;
  r->verify                  = PETSC_TRUE;
  r->verify_auto             = PETSC_TRUE;
  r->verify_certified_min_dofs = 50000;
  r->verify_certified_cover  = 1.5;
  r->count_fd                = -1;
  r->verify_certified_min_accuracy = 1e-3;
  r->verify_modes            = PETSC_DECIDE;
  r->verify_cover            = 3.0;
  r->verify_check_points     = 3;
  r->verify_check_rtol       = 1e-6;
  r->verify_check_bodywise   = PETSC_TRUE;
  r->verify_check_iterative  = PETSC_TRUE;
  r->frequency_points        = 400;
  r->frf_floor_db            = -60.0;
  PetscCall(PetscMalloc1(1, &r->alpha_g));
  r->alpha_g[0] = 0;
  *reducer      = r;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerRegister(const char name[], PetscErrorCode (*create)(KFReducer))
{
  PetscFunctionBegin;
  PetscCall(KFReducerInitializePackage());
  PetscCall(PetscFunctionListAdd(&KFReducerList, name, create));
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerSetType(KFReducer r, KFReducerType type)
{
  PetscErrorCode (*create)(KFReducer);
  PetscBool same;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCall(PetscObjectTypeCompare((PetscObject)r, type, &same));
  if (same) PetscFunctionReturn(0);
  PetscCall(PetscFunctionListFind(KFReducerList, type, &create));
  PetscCheck(create, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_UNKNOWN_TYPE, "unknown reducer type '%s': use krylov or eigen (-kf_reducer_type)", type);
  if (r->ops->destroy) PetscCall((*r->ops->destroy)(r));
  PetscCall(PetscMemzero(r->ops, sizeof(struct _KFReducerOps)));
  r->data        = NULL;
  r->setupcalled = PETSC_FALSE;
  PetscCall(PetscObjectChangeTypeName((PetscObject)r, type));
  PetscCall((*create)(r));
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerGetType(KFReducer r, KFReducerType *type)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  *type = ((PetscObject)r)->type_name;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerSetOptionsPrefix(KFReducer r, const char prefix[])
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCall(PetscObjectSetOptionsPrefix((PetscObject)r, prefix));
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerSetScene(KFReducer r, KFScene scene)
{
  PetscInt nrev;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscValidPointer(scene, 2);
  if (!scene->setup) PetscCall(KFSceneSetUp(scene));
  PetscCall(PetscObjectReference((PetscObject)scene));
  PetscCall(KFSystemDestroy(&r->given_sys)); /* made of the scene it replaces */
  PetscCall(KFSceneDestroy(&r->scene));
  r->scene = scene;
  PetscCall(KFSceneGetInfo(scene, NULL, NULL, &nrev, NULL, NULL, NULL));
  PetscCall(PetscFree(r->alpha_g));
  PetscCall(PetscCalloc1(PetscMax(nrev, 1), &r->alpha_g));
  r->setupcalled = PETSC_FALSE;
  PetscFunctionReturn(0);
}

/*
  KFReducerSetSystem - an assembled system of the reducer's scene (KFSystemSetAngles, its rigid modes as computed or
  set) that the next KFReducerSolve starts from: where its angles are those of the solve's first configuration, the
  solve uses its matrices and rigid modes instead of assembling and computing them again (a model check made them
  there, kryflex reduce). The reducer holds a reference until that solve ends, and the solve assembles the system at
  its other configurations: the caller should not rely on its state afterwards. NULL drops a system given before.
  Collective: a system given on some ranks only is dropped on all (the solve's assemblies are collective).
*/
PetscErrorCode KFReducerSetSystem(KFReducer r, KFSystem sys)
{
  PetscBool given = (PetscBool)(sys != NULL), all;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCall(MPIU_Allreduce(&given, &all, 1, MPIU_BOOL, MPI_LAND, PetscObjectComm((PetscObject)r)));
  if (!all) sys = NULL;
  if (sys) {
    PetscCheck(r->scene, PetscObjectComm((PetscObject)r), PETSC_ERR_ORDER, "set the scene first (KFReducerSetScene)");
    PetscCheck(sys->scene == r->scene, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_INCOMP, "the system belongs to another scene than the reducer's: give a system made of the reducer's scene (KFSystemCreate)");
    PetscCheck(sys->assembled, PetscObjectComm((PetscObject)r), PETSC_ERR_ORDER, "the system is not assembled: call KFSystemSetAngles() first");
    /* body factors made by earlier solves on it hold their own options and shift, not the reducer's */
    PetscCheck(!sys->bodyf, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_WRONG, "the system holds the factorizations of solves made on it: give a system that has only been assembled (KFSystemSetAngles) and had its rigid modes computed");
    PetscCall(KFSystemReference(sys));
  }
  PetscCall(KFSystemDestroy(&r->given_sys));
  r->given_sys = sys;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerGetScene(KFReducer r, KFScene *scene)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  *scene = r->scene;
  PetscFunctionReturn(0);
}

static PetscErrorCode KFReducerRevolute_Private(KFReducer r, PetscInt *nrev)
{
  PetscFunctionBegin;
  PetscCheck(r->scene, PetscObjectComm((PetscObject)r), PETSC_ERR_ORDER, "set the scene first (KFReducerSetScene)");
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, nrev, NULL, NULL, NULL));
  PetscFunctionReturn(0);
}

/* copies n configurations of nrev angles, checking they are finite */
static PetscErrorCode KFReducerCopyAngles_Private(KFReducer r, const char what[], PetscInt n, const PetscReal in[], PetscReal **out)
{
  PetscInt nrev, i;

  PetscFunctionBegin;
  PetscCall(KFReducerRevolute_Private(r, &nrev));
  PetscCheck(n >= 0, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_OUTOFRANGE, "%s: the number of configurations must be >= 0, got %" PetscInt_FMT, what, n);
  for (i = 0; i < n * nrev; i++) PetscCheck(!PetscIsInfOrNanReal(in[i]), PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_OUTOFRANGE, "%s: angles must be finite numbers, entry %" PetscInt_FMT " is %g", what, i, (double)in[i]);
  PetscCall(PetscFree(*out));
  PetscCall(PetscCalloc1(PetscMax(n * nrev, 1), out));
  if (n > 0 && nrev > 0) PetscCall(PetscArraycpy(*out, in, n * nrev));
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerSetAngles(KFReducer r, PetscInt nconfig, const PetscReal angles[])
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCheck(nconfig >= 1, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_OUTOFRANGE, "give at least one configuration of interest, got %" PetscInt_FMT, nconfig);
  PetscCall(KFReducerCopyAngles_Private(r, "angles of interest", nconfig, angles, &r->angles));
  r->nconfig     = nconfig;
  r->setupcalled = PETSC_FALSE;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerGetAngles(KFReducer r, PetscInt *nconfig, const PetscReal **angles)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  if (nconfig) *nconfig = r->nconfig;
  if (angles) *angles = r->angles;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerSetReductionAngle(KFReducer r, const PetscReal angles[])
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  r->auto_alpha = angles ? PETSC_FALSE : PETSC_TRUE;
  if (angles) PetscCall(KFReducerCopyAngles_Private(r, "reduction angle", 1, angles, &r->alpha_g));
  r->setupcalled = PETSC_FALSE;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerSetMultiAngles(KFReducer r, PetscInt n, const PetscReal angles[])
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCall(KFReducerCopyAngles_Private(r, "multi-angle configurations", n, angles, &r->multi));
  r->nmulti      = n;
  r->setupcalled = PETSC_FALSE;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerSetMethod(KFReducer r, KFReducerMethod method)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  r->method = method;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerSetBand(KFReducer r, PetscReal fmin, PetscReal fmax)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCheck(fmin > 0 && fmin < fmax && PetscIsNormalReal(fmax), PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_OUTOFRANGE, "band: give 0 < f_low < f_high in Hz, got %g, %g (-kf_band low,high)", (double)fmin, (double)fmax);
  r->band[0] = fmin;
  r->band[1] = fmax;
  PetscCall(KFReducerDampingUpdate_Private(r));
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerSetDamping(KFReducer r, PetscReal zeta)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCheck(zeta > 0 && zeta < 1, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_OUTOFRANGE, "damping: the modal damping ratio must lie in (0, 1), got %g (-kf_damping)", (double)zeta);
  /* the modal part only: Rayleigh and structural damping set by KFReducerSetDampingModel stay */
  r->damping.nbands     = 1;
  r->damping.fmax_hz[0] = PETSC_INFINITY;
  r->damping.zeta[0]    = zeta;
  PetscCall(KFReducerDampingUpdate_Private(r));
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerSetAccuracy(KFReducer r, PetscReal target)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCheck(target > 0 && PetscIsNormalReal(target), PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_OUTOFRANGE, "accuracy: give a positive relative error, got %g (-kf_accuracy)", (double)target);
  r->accuracy = target;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerSetAccuracyMeasure(KFReducer r, KFAccuracyMeasure measure)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCheck(measure == KF_ACCURACY_ELASTIC || measure == KF_ACCURACY_TOTAL, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_OUTOFRANGE, "accuracy measure: give elastic or total (-kf_accuracy_measure), got %d", (int)measure);
  r->accuracy_measure = measure;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerGetAccuracyMeasure(KFReducer r, KFAccuracyMeasure *measure)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscValidPointer(measure, 2);
  *measure = r->accuracy_measure;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerSetMoments(KFReducer r, PetscInt moments, PetscInt output_blocks)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCheck(moments == PETSC_DECIDE || (moments >= 1 && output_blocks >= 0 && moments > output_blocks), PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_OUTOFRANGE, "moments (%" PetscInt_FMT ") must exceed output_blocks (%" PetscInt_FMT ") >= 0 (-kf_moments, -kf_output_blocks)", moments, output_blocks);
  PetscCheck(output_blocks >= 0, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_OUTOFRANGE, "output_blocks must be >= 0, got %" PetscInt_FMT " (-kf_output_blocks)", output_blocks);
  r->moments       = moments;
  r->output_blocks = output_blocks;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerSetSearch(KFReducer r, PetscBool search, PetscInt moments_max)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCheck(moments_max >= 1 && moments_max <= 1000, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_OUTOFRANGE, "moments_max: give 1 to 1000 moments, got %" PetscInt_FMT " (-kf_moments_max)", moments_max);
  r->search      = search;
  r->moments_max = moments_max;
  PetscFunctionReturn(0);
}

/* the chosen model compressed body by body by what its response needs, when that makes it smaller (-kf_compress) */
PetscErrorCode KFReducerSetCompress(KFReducer r, PetscBool compress)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  r->compress = compress;
  PetscFunctionReturn(0);
}

/* whether the compression keeps each body's share of the static elastic response exactly, so that L^0 stays exact
   (true), or orders and truncates it like the other snapshots, L^0 then measured, not exact (-kf_static_exact) */
PetscErrorCode KFReducerSetStaticExact(KFReducer r, PetscBool exact)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  r->static_exact = exact;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerSetClusterTolerance(KFReducer r, PetscReal rtol)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCheck(rtol >= 0 && rtol < 1, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_OUTOFRANGE, "cluster_rtol: give a relative frequency gap in [0, 1), got %g (-kf_cluster_rtol)", (double)rtol);
  r->cluster_rtol = rtol;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerSetImportance(KFReducer r, KFImportance importance, PetscReal keep_threshold)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCheck(importance >= KF_IMPORTANCE_H2 && importance <= KF_IMPORTANCE_BAND, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_OUTOFRANGE, "importance: use band, h2, hinf or static (-kf_importance)");
  PetscCheck(keep_threshold >= 0 && keep_threshold <= 1, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_OUTOFRANGE, "keep_threshold: importances are normalized to 1, give a value in [0, 1], got %g (-kf_keep_threshold)", (double)keep_threshold);
  r->importance     = importance;
  r->keep_threshold = keep_threshold;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerSetStaticCorrection(KFReducer r, PetscBool flg)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  r->static_correction = flg;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerSetTolerances(KFReducer r, PetscReal deflation_tol, PetscReal body_tol, PetscReal reassembly_rtol)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCheck(deflation_tol > 0 && deflation_tol < 1 && body_tol > 0 && body_tol < 1 && reassembly_rtol > 0 && reassembly_rtol < 1, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_OUTOFRANGE, "tolerances are relative: give values in (0, 1), got deflation %g, body %g, reassembly %g (-kf_deflation_tol, -kf_body_tol, -kf_reassembly_rtol)", (double)deflation_tol, (double)body_tol, (double)reassembly_rtol);
  r->deflation_tol   = deflation_tol;
  r->body_tol        = body_tol;
  r->reassembly_rtol = reassembly_rtol;
  PetscFunctionReturn(0);
}

/*
  KFReducerSetMaxFrequency - reduced-system modes above the limit are taken out of the dynamics at every configuration
  the model is reassembled at, their static share kept as a feedthrough (KFReducedSystemTrim). value: a multiple of
  the band's top (hz false, >= 1) or a frequency in Hz (hz true); 0: no trimming.
*/
PetscErrorCode KFReducerSetMaxFrequency(KFReducer r, PetscReal value, PetscBool hz)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCheck(value >= 0 && !PetscIsInfOrNanReal(value) && (hz || value == 0 || value >= 1), PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_OUTOFRANGE, "max_frequency: give 0 (off), a multiple >= 1 of the band's top, or a frequency in Hz, got %g%s (-kf_max_frequency)", (double)value, hz ? " Hz" : "");
  r->max_frequency    = value;
  r->max_frequency_hz = hz;
  PetscFunctionReturn(0);
}

/* KFReducerGetMaxFrequency - the trimming limit in Hz (0: off), from a multiple of the band's top when given so */
PetscErrorCode KFReducerGetMaxFrequency(KFReducer r, PetscReal *fmax_hz)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  *fmax_hz = r->max_frequency_hz ? r->max_frequency : r->max_frequency * r->band[1];
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerSetShift(KFReducer r, PetscReal shift)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCheck(shift >= 0 && PetscIsNormalReal(shift + 1), PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_OUTOFRANGE, "shift: give sigma >= 0 (K + sigma M is factored), got %g (-kf_shift)", (double)shift);
  r->shift = shift;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerSetSaveMaps(KFReducer r, PetscInt save)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCheck(save == PETSC_TRUE || save == PETSC_FALSE || save == PETSC_DECIDE, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_OUTOFRANGE, "save maps: PETSC_TRUE, PETSC_FALSE or PETSC_DECIDE");
  r->save_maps = save;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerSetVerification(KFReducer r, PetscBool full_order, PetscInt modes, PetscInt frequency_points, PetscReal frf_floor_db)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCheck(modes == PETSC_DECIDE || modes >= 1, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_OUTOFRANGE, "verification modes: give a count >= 1 or auto, got %" PetscInt_FMT " (-kf_verify_modes)", modes);
  PetscCheck(frequency_points >= 2, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_OUTOFRANGE, "frequency points: give at least 2, got %" PetscInt_FMT " (-kf_frequency_points)", frequency_points);
  PetscCheck(frf_floor_db < 0, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_OUTOFRANGE, "FRF floor: give a level below the peak in dB (negative), got %g (-kf_frf_floor_db)", (double)frf_floor_db);
  r->verify           = full_order;
  r->verify_auto      = PETSC_FALSE;
  r->verify_modes     = modes;
  r->frequency_points = frequency_points;
  r->frf_floor_db     = frf_floor_db;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerSetVerificationAuto(KFReducer r, PetscInt min_dofs)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCheck(min_dofs == PETSC_DECIDE || min_dofs >= 0, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_OUTOFRANGE, "the certified estimate's threshold: give a number of system dofs >= 0, got %" PetscInt_FMT " (-kf_verify_certified_min_dofs)", min_dofs);
  r->verify_auto = PETSC_TRUE;
  if (min_dofs != PETSC_DECIDE) r->verify_certified_min_dofs = min_dofs;
  PetscFunctionReturn(0);
}

/* How KFReducerSolve will give its verdict, known before it starts: *measured against the full order (-kf_verify true;
   auto below -kf_verify_certified_min_dofs system dofs, for a target tighter than -kf_verify_certified_min_accuracy,
   or for a basis without an accuracy search) or estimated, then *certified by the mode count (auto otherwise; the
   count may still send the verdict to the full order: src/reducer/certify.c). Either may be NULL. */
PetscErrorCode KFReducerGetVerificationPlan(KFReducer r, PetscBool *measured, PetscBool *certified)
{
  PetscBool verify = r->verify;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCheck(r->scene, PetscObjectComm((PetscObject)r), PETSC_ERR_ORDER, "no scene: call KFReducerSetScene() first");
  if (r->verify_auto) {
    PetscInt nsys;

    PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, NULL, &nsys, NULL, NULL));
    verify = (PetscBool)(!(r->search && r->ops->blocks) || nsys < r->verify_certified_min_dofs || r->accuracy < r->verify_certified_min_accuracy);
  }
  if (measured) *measured = verify;
  if (certified) *certified = (PetscBool)(r->verify_auto && !verify);
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerGetReducedModel(KFReducer r, KFReducedModel *model)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCheck(r->solved, PetscObjectComm((PetscObject)r), PETSC_ERR_ORDER, "call KFReducerSolve() first");
  *model = r->chosen == KF_METHOD_MULTI_ANGLE && r->multi_model ? r->multi_model : r->single;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerGetReducedModels(KFReducer r, KFReducedModel *single, KFReducedModel *multi)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCheck(r->solved, PetscObjectComm((PetscObject)r), PETSC_ERR_ORDER, "call KFReducerSolve() first");
  if (single) *single = r->single;
  if (multi) *multi = r->multi_model;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerGetNotes(KFReducer r, PetscInt *n, const char *const **notes)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  if (n) *n = r->nnotes;
  if (notes) *notes = (const char *const *)r->notes;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerGetReductionRule(KFReducer r, const char **rule)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  *rule = r->rule;
  PetscFunctionReturn(0);
}

/*
  KFReducerReset - releases what a solve left: its results and models, and the search's cache (which a search stopped
  by an error leaves behind); the settings stay.
*/
PetscErrorCode KFReducerReset(KFReducer r)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCall(KFReducerResultsReset_Private(r));
  r->verify_count   = 0;
  r->verify_covered = PETSC_FALSE;
  PetscCall(KFBodyFactorsDestroy(&r->count_bf));
  r->count_bf_made = PETSC_FALSE;
  if (r->candcache_reset) PetscCall((*r->candcache_reset)(r));
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerDestroy(KFReducer *reducer)
{
  KFReducer r;

  PetscFunctionBegin;
  if (!reducer || !*reducer) PetscFunctionReturn(0);
  r = *reducer;
  *reducer = NULL;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  if (--((PetscObject)r)->refct > 0) PetscFunctionReturn(0);
  if (r->ops->destroy) PetscCall((*r->ops->destroy)(r));
  PetscCall(KFReducerReset(r));
  PetscCall(KFSystemDestroy(&r->given_sys));
  PetscCall(KFSceneDestroy(&r->scene));
  PetscCall(PetscFree(r->angles));
  PetscCall(PetscFree(r->alpha_g));
  PetscCall(PetscFree(r->multi));
  PetscCall(PetscHeaderDestroy(&r));
  PetscFunctionReturn(0);
}
