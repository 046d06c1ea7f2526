/* The settings a reduced model records (what made it), as JSON text values so that every reader parses them alike. */
#include <kryflex/reducerimpl.h>

/* JSON list of n configurations in degrees, [[a, b], ...], or one configuration [a, b] when outer is false */
static PetscErrorCode KFAnglesJSON(PetscInt nrev, PetscInt n, const PetscReal rad[], PetscBool outer, char buf[], size_t len)
{
  size_t used;

  PetscFunctionBegin;
  PetscCall(PetscStrncpy(buf, outer ? "[" : "", len));
  for (PetscInt c = 0; c < n; c++) {
    PetscCall(PetscStrlen(buf, &used));
    PetscCall(PetscSNPrintf(buf + used, len - used, "%s[", c ? ", " : ""));
    for (PetscInt j = 0; j < nrev; j++) {
      PetscCall(PetscStrlen(buf, &used));
      /* 12 digits: the degrees the user gave, not their round trip through radians */
      PetscCall(PetscSNPrintf(buf + used, len - used, "%s%.12g", j ? ", " : "", (double)(rad[c * PetscMax(nrev, 1) + j] * 180.0 / PETSC_PI)));
    }
    PetscCall(PetscStrlcat(buf, "]", len));
  }
  if (outer) PetscCall(PetscStrlcat(buf, "]", len));
  PetscFunctionReturn(0);
}

static PetscErrorCode KFSetReal(KFReducedModel m, const char key[], PetscReal x)
{
  char v[64];

  PetscFunctionBegin;
  PetscCall(PetscSNPrintf(v, sizeof(v), "%.17g", (double)x));
  PetscCall(KFReducedModelSetSetting(m, key, v));
  PetscFunctionReturn(0);
}

static PetscErrorCode KFSetString(KFReducedModel m, const char key[], const char s[])
{
  char v[256];

  PetscFunctionBegin;
  PetscCall(PetscSNPrintf(v, sizeof(v), "\"%s\"", s));
  PetscCall(KFReducedModelSetSetting(m, key, v));
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerRecordSettings_Private(KFReducer r, KFReducedModel m, KFReducerMethod method, PetscInt moments, PetscInt n, const PetscReal angles[])
{
  PetscInt    nrev;
  KFReducerType type;
  char        buf[16384], num[64];

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, &nrev, NULL, NULL, NULL));
  PetscCall(KFReducerGetType(r, &type));
  PetscCall(KFSetString(m, "basis", type));
  PetscCall(KFSetReal(m, "eigen_cover", r->eigen_cover));
  PetscCall(PetscSNPrintf(num, sizeof(num), "%" PetscInt_FMT, moments)); /* the moments this model matches */
  PetscCall(KFReducedModelSetSetting(m, "moments", num));
  PetscCall(PetscSNPrintf(num, sizeof(num), "%" PetscInt_FMT, r->output_blocks));
  PetscCall(KFReducedModelSetSetting(m, "output_blocks", num));
  PetscCall(KFSetString(m, "importance", KFImportances[r->importance]));
  PetscCall(KFSetReal(m, "keep_threshold", r->keep_threshold));
  if (r->auto_alpha) PetscCall(KFSetString(m, "reduction_angle", "auto"));
  else {
    PetscCall(KFAnglesJSON(nrev, 1, r->alpha_g, PETSC_FALSE, buf, sizeof(buf)));
    PetscCall(KFReducedModelSetSetting(m, "reduction_angle", buf));
  }
  PetscCall(KFSetString(m, "method", KFReducerMethods[method]));
  if (r->nmulti) {
    PetscCall(KFAnglesJSON(nrev, r->nmulti, r->multi, PETSC_TRUE, buf, sizeof(buf)));
    PetscCall(KFReducedModelSetSetting(m, "reduction_angles", buf));
  } else PetscCall(KFReducedModelSetSetting(m, "reduction_angles", "null"));
  PetscCall(KFSetReal(m, "deflation_tol", r->deflation_tol));
  PetscCall(KFSetReal(m, "body_tol", r->body_tol));
  PetscCall(KFSetReal(m, "reassembly_rtol", r->reassembly_rtol));
  { /* the trimming limit as given, and in Hz: KFReducedModelReassemble trims with the latter */
    PetscReal fmax;

    if (r->max_frequency > 0) {
      PetscCall(PetscSNPrintf(num, sizeof(num), r->max_frequency_hz ? "\"%.12g Hz\"" : "%.12g", (double)r->max_frequency));
      PetscCall(KFReducedModelSetSetting(m, "max_frequency", num));
    } else PetscCall(KFReducedModelSetSetting(m, "max_frequency", "null"));
    PetscCall(KFReducerGetMaxFrequency(r, &fmax));
    PetscCall(KFSetReal(m, "max_frequency_hz", fmax));
  }
  PetscCall(KFReducedModelSetSetting(m, "static_correction", r->static_correction ? "true" : "false"));
  if (r->shared_directions) PetscCall(KFReducedModelSetSetting(m, "shared_directions", "true")); /* auto: set on the tied models (visit.c) */
  PetscCall(KFSetReal(m, "shift", r->shift));
  if (r->save_maps == PETSC_DECIDE) PetscCall(KFSetString(m, "save_maps", "auto"));
  else PetscCall(KFReducedModelSetSetting(m, "save_maps", r->save_maps ? "true" : "false"));
  PetscCall(KFAnglesJSON(nrev, n, angles, PETSC_TRUE, buf, sizeof(buf)));
  PetscCall(KFReducedModelSetSetting(m, "reduction_angles_deg", buf));
  PetscCall(KFSetReal(m, "damping", r->zeta));
  PetscCall(KFDampingDescribe_Private(&r->damping, buf, sizeof(buf)));
  PetscCall(KFReducedModelSetSetting(m, "damping_model", buf));
  PetscCall(KFReducedModelSetDamping(m, &r->damping));
  PetscCall(PetscSNPrintf(buf, sizeof(buf), "[%.17g, %.17g]", (double)r->band[0], (double)r->band[1]));
  PetscCall(KFReducedModelSetSetting(m, "band_hz", buf));
  PetscCall(KFSetReal(m, "accuracy", r->accuracy));
  PetscCall(KFSetString(m, "accuracy_measure", KFAccuracyMeasures[r->accuracy_measure]));
  PetscFunctionReturn(0);
}
