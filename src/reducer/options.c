/* KFReducerSetFromOptions: the reducer's -kf_ settings (their help, range and setter from the settings table,
   src/util/settings_table.c; -help lists them with their defaults). */
#include <kryflex/reducerimpl.h>

static const char *const KFSaveMaps[] = {"false", "true", "auto", "KFSaveMaps", "", NULL};

/* angles given in degrees on the command line, n configurations of nrev angles, into radians */
static PetscErrorCode KFReducerDegreesOption_Private(KFReducer r, const char what[], PetscInt n, PetscReal deg[], PetscInt *nconfig)
{
  PetscInt nrev;

  PetscFunctionBegin;
  PetscCheck(r->scene, PetscObjectComm((PetscObject)r), PETSC_ERR_ORDER, "%s: set the scene (KFReducerSetScene) before KFReducerSetFromOptions", what);
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, &nrev, NULL, NULL, NULL));
  nrev = PetscMax(nrev, 1);
  PetscCheck(n % nrev == 0 && n > 0, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_SIZ, "%s: the scene has %" PetscInt_FMT " revolute joint(s), so give a multiple of %" PetscInt_FMT " angles in degrees, comma-separated; got %" PetscInt_FMT, what, nrev, nrev, n);
  for (PetscInt i = 0; i < n; i++) deg[i] *= PETSC_PI / 180.0;
  *nconfig = n / nrev;
  PetscFunctionReturn(0);
}

/* The options of the objects a reduction makes later (the flexible solver and its factorization, the rigid modes, the
   Krylov chain's progress, the verification eigensolve), read and checked by their own readers now: a bad value is
   refused as a bad option before any work, not after the assembly as a failed reduction; -help lists them here. */
static PetscErrorCode KFReducerCheckStageOptions_Private(MPI_Comm comm, const char prefix[])
{
  PetscReal rigid_tol, target;
  PetscInt  progress_min, dense_max, method, nrand, maxblocks, firstmb;
  PetscBool has_target;

  PetscFunctionBegin;
  PetscCall(KFFlexSolverCheckOptions(comm, prefix));
  PetscCall(KFRigidTolFromOptions(comm, &rigid_tol));
  PetscCall(KFKrylovProgressOptions(comm, &progress_min));
  PetscCall(KFVerifyEigenOptions(comm, &dense_max, &target, &has_target));
  PetscCall(KFBlockEigenOptions(comm, &method, &nrand, &maxblocks, &firstmb));
  PetscFunctionReturn(0);
}

#define KF_MAX_OPTION_ANGLES 4096

PetscErrorCode KFReducerSetFromOptions(KFReducer r)
{
  char           type[256] = KFREDUCERKRYLOV, alpha[PETSC_MAX_PATH_LEN] = "auto";
  PetscReal      band[2], deg[KF_MAX_OPTION_ANGLES];
  PetscInt       n, nconfig, save, method, importance, moments, oblocks, vmodes, npoints;
  PetscReal      zeta, accuracy, keep, dtol, btol, rtol, shift, floor_db;
  PetscBool      flg, sc, verify, verify_auto;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  if (((PetscObject)r)->type_name) PetscCall(PetscStrncpy(type, ((PetscObject)r)->type_name, sizeof(type)));
  PetscObjectOptionsBegin((PetscObject)r);
  PetscCall(KFOptionsSettingFList(PetscOptionsObject, "-kf_reducer_type", KFReducerList, type, type, sizeof(type), &flg));
  if (flg || !((PetscObject)r)->type_name) PetscCall(KFReducerSetType(r, type));

  PetscCall(PetscArrayzero(deg, KF_MAX_OPTION_ANGLES)); /* -help prints the array's first entry as the default */
  n = KF_MAX_OPTION_ANGLES;
  PetscCall(KFOptionsSettingRealArray(PetscOptionsObject, "-kf_angles", deg, &n, &flg));
  if (flg) {
    PetscCall(KFReducerDegreesOption_Private(r, "-kf_angles", n, deg, &nconfig));
    PetscCall(KFReducerSetAngles(r, nconfig, deg));
  }
  PetscCall(KFOptionsSettingString(PetscOptionsObject, "-kf_reduction_angle", alpha, alpha, sizeof(alpha), &flg));
  if (flg) {
    PetscBool isauto;

    PetscCall(PetscStrcasecmp(alpha, "auto", &isauto));
    if (isauto) PetscCall(KFReducerSetReductionAngle(r, NULL));
    else {
      n = KF_MAX_OPTION_ANGLES;
      PetscCall(PetscOptionsGetRealArray(((PetscObject)r)->options, ((PetscObject)r)->prefix, "-kf_reduction_angle", deg, &n, NULL));
      PetscCall(KFReducerDegreesOption_Private(r, "-kf_reduction_angle", n, deg, &nconfig));
      PetscCheck(nconfig == 1, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_SIZ, "-kf_reduction_angle: give one configuration (one angle per revolute joint) or auto, got %" PetscInt_FMT, nconfig);
      PetscCall(KFReducerSetReductionAngle(r, deg));
    }
  }
  PetscCall(PetscArrayzero(deg, KF_MAX_OPTION_ANGLES));
  n = KF_MAX_OPTION_ANGLES;
  PetscCall(KFOptionsSettingRealArray(PetscOptionsObject, "-kf_multi_angles", deg, &n, &flg));
  if (flg) {
    PetscCall(KFReducerDegreesOption_Private(r, "-kf_multi_angles", n, deg, &nconfig));
    PetscCall(KFReducerSetMultiAngles(r, nconfig, deg));
  }
  method = (PetscInt)r->method;
  PetscCall(KFOptionsSettingEList(PetscOptionsObject, "-kf_method", KFReducerMethods, 3, KFReducerMethods[r->method], &method, &flg));
  if (flg) PetscCall(KFReducerSetMethod(r, (KFReducerMethod)method));

  band[0] = r->band[0];
  band[1] = r->band[1];
  n       = 2;
  PetscCall(KFOptionsSettingRealArray(PetscOptionsObject, "-kf_band", band, &n, &flg));
  if (flg) {
    PetscCheck(n == 2, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_SIZ, "-kf_band: give two frequencies in Hz, low,high; got %" PetscInt_FMT, n);
    PetscCall(KFReducerSetBand(r, band[0], band[1]));
  }
  zeta = r->zeta;
  PetscCall(KFOptionsSettingReal(PetscOptionsObject, "-kf_damping", zeta, &zeta, &flg));
  if (flg) PetscCall(KFReducerSetDamping(r, zeta));
  {
    KFDamping d = r->damping;
    PetscReal bands[2 * KF_MAX_DAMPING_BANDS], ab[2] = {d.alpha, d.beta};
    PetscInt  nb = 2 * KF_MAX_DAMPING_BANDS, nab = 2;
    PetscBool fb, fr, fs;

    PetscCall(KFOptionsSettingRealArray(PetscOptionsObject, "-kf_damping_bands", bands, &nb, &fb));
    if (fb) {
      PetscCheck(nb % 2 == 0 && nb > 0, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_SIZ, "-kf_damping_bands: give pairs f_max_hz,zeta; got %" PetscInt_FMT " numbers", nb);
      d.nbands = nb / 2;
      for (PetscInt k = 0; k < d.nbands; k++) {
        d.fmax_hz[k] = bands[2 * k];
        d.zeta[k]    = bands[2 * k + 1];
      }
    }
    PetscCall(KFOptionsSettingRealArray(PetscOptionsObject, "-kf_damping_rayleigh", ab, &nab, &fr));
    if (fr) {
      PetscCheck(nab == 2, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_SIZ, "-kf_damping_rayleigh: give alpha,beta; got %" PetscInt_FMT " numbers", nab);
      d.alpha = ab[0];
      d.beta  = ab[1];
    }
    PetscCall(KFOptionsSettingReal(PetscOptionsObject, "-kf_damping_structural", d.g, &d.g, &fs));
    if (fb || fr || fs) PetscCall(KFReducerSetDampingModel(r, &d));
  }
  accuracy = r->accuracy;
  PetscCall(KFOptionsSettingReal(PetscOptionsObject, "-kf_accuracy", accuracy, &accuracy, &flg));
  if (flg) PetscCall(KFReducerSetAccuracy(r, accuracy));
  {
    PetscInt measure = (PetscInt)r->accuracy_measure;

    PetscCall(KFOptionsSettingEList(PetscOptionsObject, "-kf_accuracy_measure", KFAccuracyMeasures, 2, KFAccuracyMeasures[r->accuracy_measure], &measure, &flg));
    if (flg) PetscCall(KFReducerSetAccuracyMeasure(r, (KFAccuracyMeasure)measure));
  }

  moments = r->moments;
  oblocks = r->output_blocks;
  {
    char mtext[64] = "auto";

    if (moments != PETSC_DECIDE) PetscCall(PetscSNPrintf(mtext, sizeof(mtext), "%" PetscInt_FMT, moments));
    PetscCall(KFOptionsSettingString(PetscOptionsObject, "-kf_moments", mtext, mtext, sizeof(mtext), &flg));
    if (flg) {
      PetscBool isauto;
      char     *end;

      PetscCall(PetscStrcasecmp(mtext, "auto", &isauto));
      if (isauto) moments = PETSC_DECIDE;
      else {
        long v = strtol(mtext, &end, 10);

        PetscCheck(*mtext && !*end, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_WRONG, "-kf_moments: give auto or a number of moments, got '%s'", mtext);
        PetscCall(KFSettingCheckRange(PetscObjectComm((PetscObject)r), "-kf_moments", (PetscReal)v));
        moments = (PetscInt)v;
      }
    }
  }
  PetscCall(KFOptionsSettingInt(PetscOptionsObject, "-kf_output_blocks", oblocks, &oblocks, NULL));
  PetscCall(KFReducerSetMoments(r, moments, oblocks));
  {
    PetscBool search = r->search;
    PetscInt  mmax   = r->moments_max;
    PetscReal crtol  = r->cluster_rtol;

    PetscCall(KFOptionsSettingBool(PetscOptionsObject, "-kf_search", search, &search, NULL));
    PetscCall(KFOptionsSettingInt(PetscOptionsObject, "-kf_moments_max", mmax, &mmax, NULL));
    PetscCall(KFReducerSetSearch(r, search, mmax));
    PetscCall(KFOptionsSettingReal(PetscOptionsObject, "-kf_cluster_rtol", crtol, &crtol, NULL));
    PetscCall(KFReducerSetClusterTolerance(r, crtol));
    PetscCall(KFOptionsSettingInt(PetscOptionsObject, "-kf_max_factorizations", r->max_factorizations, &r->max_factorizations, NULL));
    PetscCall(KFOptionsSettingInt(PetscOptionsObject, "-kf_shift_blocks", r->shift_blocks, &r->shift_blocks, NULL));
    PetscCall(KFOptionsSettingBool(PetscOptionsObject, "-kf_shift_family_only", r->shift_family_only, &r->shift_family_only, NULL));
    PetscCall(KFOptionsSettingBool(PetscOptionsObject, "-kf_compress", r->compress, &r->compress, NULL));
    {
      char      text[16];
      PetscBool ok;

      PetscCall(KFOptionsSettingString(PetscOptionsObject, "-kf_shared_directions", r->shared_auto ? "auto" : (r->shared_directions ? "true" : "false"), text, sizeof(text), &flg));
      if (flg) {
        PetscCall(KFStringToAutoBool(text, &r->shared_auto, &r->shared_directions, &ok));
        PetscCheck(ok, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_WRONG, "-kf_shared_directions %s: give auto, true or false", text);
        if (r->shared_auto) r->shared_directions = PETSC_FALSE; /* auto ties candidate by candidate (KFCandidate.tied) */
      }
    }
    PetscCall(KFOptionsSettingBool(PetscOptionsObject, "-kf_static_exact", r->static_exact, &r->static_exact, NULL));
  }
  importance = (PetscInt)r->importance;
  keep       = r->keep_threshold;
  PetscCall(KFOptionsSettingEList(PetscOptionsObject, "-kf_importance", KFImportances, 4, KFImportances[r->importance], &importance, NULL));
  PetscCall(KFOptionsSettingReal(PetscOptionsObject, "-kf_keep_threshold", keep, &keep, NULL));
  PetscCall(KFReducerSetImportance(r, (KFImportance)importance, keep));
  sc = r->static_correction;
  PetscCall(KFOptionsSettingBool(PetscOptionsObject, "-kf_static_correction", sc, &sc, NULL));
  PetscCall(KFReducerSetStaticCorrection(r, sc));
  dtol = r->deflation_tol;
  btol = r->body_tol;
  rtol = r->reassembly_rtol;
  PetscCall(KFOptionsSettingReal(PetscOptionsObject, "-kf_deflation_tol", dtol, &dtol, NULL));
  PetscCall(KFOptionsSettingReal(PetscOptionsObject, "-kf_body_tol", btol, &btol, NULL));
  PetscCall(KFOptionsSettingReal(PetscOptionsObject, "-kf_reassembly_rtol", rtol, &rtol, NULL));
  PetscCall(KFReducerSetTolerances(r, dtol, btol, rtol));
  {
    char      text[64] = "none";
    PetscBool set;

    if (r->max_frequency > 0) PetscCall(PetscSNPrintf(text, sizeof(text), r->max_frequency_hz ? "%g Hz" : "%g", (double)r->max_frequency));
    PetscCall(KFOptionsSettingString(PetscOptionsObject, "-kf_max_frequency", text, text, sizeof(text), &set));
    if (set) {
      PetscReal value;
      PetscBool hz;

      PetscCall(KFParseMaxFrequency(PetscObjectComm((PetscObject)r), text, &value, &hz));
      PetscCall(KFReducerSetMaxFrequency(r, value, hz));
    }
  }
  PetscCall(KFOptionsSettingBool(PetscOptionsObject, "-kf_search_sub_bases", r->sub_bases, &r->sub_bases, NULL));
  shift = r->shift;
  PetscCall(KFOptionsSettingReal(PetscOptionsObject, "-kf_shift", shift, &shift, &flg));
  if (flg) PetscCall(KFReducerSetShift(r, shift));
  save = r->save_maps == PETSC_DECIDE ? 2 : r->save_maps;
  PetscCall(KFOptionsSettingEList(PetscOptionsObject, "-kf_save_maps", KFSaveMaps, 3, KFSaveMaps[save], &save, &flg));
  if (flg) PetscCall(KFReducerSetSaveMaps(r, save == 2 ? PETSC_DECIDE : save));
  PetscCall(KFOptionsSettingInt(PetscOptionsObject, "-kf_save_maps_max_dofs", r->save_maps_max_dofs, &r->save_maps_max_dofs, NULL));
  PetscCall(KFOptionsSettingInt(PetscOptionsObject, "-kf_gram_condition_max_dofs", r->gram_condition_max_dofs, &r->gram_condition_max_dofs, NULL));
  PetscCall(KFOptionsSettingReal(PetscOptionsObject, "-kf_negligible_moment", r->negligible, &r->negligible, NULL));

  verify   = r->verify;
  verify_auto = r->verify_auto;
  vmodes   = r->verify_modes;
  npoints  = r->frequency_points;
  floor_db = r->frf_floor_db;
  {
    char      text[16];
    PetscBool ok;

    PetscCall(KFOptionsSettingString(PetscOptionsObject, "-kf_verify", verify_auto ? "auto" : (verify ? "true" : "false"), text, sizeof(text), &flg));
    if (flg) {
      PetscCall(KFStringToAutoBool(text, &verify_auto, &verify, &ok));
      PetscCheck(ok, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_WRONG, "-kf_verify %s: give auto, true or false", text);
    }
  }
  PetscCall(KFOptionsSettingInt(PetscOptionsObject, "-kf_verify_certified_min_dofs", r->verify_certified_min_dofs, &r->verify_certified_min_dofs, NULL));
  PetscCall(KFOptionsSettingReal(PetscOptionsObject, "-kf_verify_certified_cover", r->verify_certified_cover, &r->verify_certified_cover, NULL));
  PetscCall(KFOptionsSettingReal(PetscOptionsObject, "-kf_verify_certified_min_accuracy", r->verify_certified_min_accuracy, &r->verify_certified_min_accuracy, NULL));
  PetscCall(KFOptionsSettingInt(PetscOptionsObject, "-kf_verify_modes", vmodes, &vmodes, NULL));
  PetscCall(KFOptionsSettingReal(PetscOptionsObject, "-kf_verify_cover", r->verify_cover, &r->verify_cover, NULL));
  PetscCall(KFOptionsSettingInt(PetscOptionsObject, "-kf_verify_check_points", r->verify_check_points, &r->verify_check_points, NULL));
  PetscCall(KFOptionsSettingReal(PetscOptionsObject, "-kf_verify_check_rtol", r->verify_check_rtol, &r->verify_check_rtol, NULL));
  PetscCall(KFOptionsSettingBool(PetscOptionsObject, "-kf_verify_check_bodywise", r->verify_check_bodywise, &r->verify_check_bodywise, NULL));
  {
    static const char *const methods[] = {"iterative", "direct"};
    PetscInt                  m = r->verify_check_iterative ? 0 : 1;

    PetscCall(KFOptionsSettingEList(PetscOptionsObject, "-kf_verify_check_method", methods, 2, methods[m], &m, NULL));
    r->verify_check_iterative = (PetscBool)(m == 0);
  }
  PetscCall(KFOptionsSettingInt(PetscOptionsObject, "-kf_frequency_points", npoints, &npoints, NULL));
  PetscCall(KFOptionsSettingReal(PetscOptionsObject, "-kf_frf_floor_db", floor_db, &floor_db, NULL));
  PetscCall(KFReducerSetVerification(r, verify, vmodes, npoints, floor_db));
  r->verify_auto = verify_auto; /* KFReducerSetVerification, an explicit verdict, turns auto off */
  {
    PetscBool full = r->full_moments_set ? r->full_moments : r->verify, set;

    PetscCall(KFOptionsSettingBool(PetscOptionsObject, "-kf_full_moments", full, &full, &set));
    if (set) {
      r->full_moments     = full;
      r->full_moments_set = PETSC_TRUE;
    }
  }
  if (r->ops->setfromoptions) PetscCall((*r->ops->setfromoptions)(r, PetscOptionsObject));
  PetscCall(PetscObjectProcessOptionsHandlers((PetscObject)r, PetscOptionsObject));
  PetscOptionsEnd();
  PetscCall(KFReducerCheckStageOptions_Private(PetscObjectComm((PetscObject)r), ((PetscObject)r)->prefix));
  PetscFunctionReturn(0);
}
