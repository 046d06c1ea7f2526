/* KFReducerView: the reducer's settings and, after a solve, what it chose, for -kf_reducer_view and the Python
   face's view(). */
#include <kryflex/reducerimpl.h>

static PetscErrorCode KFReducerViewAngles_Private(PetscViewer v, const char what[], PetscInt n, PetscInt nrev, const PetscReal a[])
{
  char label[128];

  PetscFunctionBegin;
  if (!nrev) { /* a single structure: one configuration, no angle, whichever list this is */
    PetscCall(PetscViewerASCIIPrintf(v, "configuration: the structure (no revolute joint)\n"));
    PetscFunctionReturn(0);
  }
  PetscCall(PetscViewerASCIIPrintf(v, "%s (deg):", what));
  PetscCall(PetscViewerASCIIUseTabs(v, PETSC_FALSE));
  for (PetscInt c = 0; c < n; c++) {
    PetscCall(KFReducerConfigLabel_Private(nrev, &a[c * PetscMax(nrev, 1)], label, sizeof(label)));
    PetscCall(PetscViewerASCIIPrintf(v, "%s%s", c ? ", " : " ", label));
  }
  PetscCall(PetscViewerASCIIPrintf(v, "\n"));
  PetscCall(PetscViewerASCIIUseTabs(v, PETSC_TRUE));
  PetscFunctionReturn(0);
}

/* the configuration, and after a solve what it did: alpha_G and why, model sizes, errors per angle, notes */
PetscErrorCode KFReducerView(KFReducer r, PetscViewer viewer)
{
  PetscBool iascii;
  PetscInt  nrev = 0;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  if (!viewer) PetscCall(PetscViewerASCIIGetStdout(PetscObjectComm((PetscObject)r), &viewer));
  PetscCall(PetscObjectTypeCompare((PetscObject)viewer, PETSCVIEWERASCII, &iascii));
  if (!iascii) PetscFunctionReturn(0);
  PetscCall(PetscObjectPrintClassNamePrefixType((PetscObject)r, viewer));
  PetscCall(PetscViewerASCIIPushTab(viewer));
  if (r->scene) {
    const char *name;
    PetscInt    nb, nsys, a, t;

    PetscCall(KFSceneGetName(r->scene, &name));
    PetscCall(KFSceneGetInfo(r->scene, &nb, NULL, &nrev, &nsys, &a, &t));
    PetscCall(PetscViewerASCIIPrintf(viewer, "scene '%s': %" PetscInt_FMT " bodies, %" PetscInt_FMT " system dofs, %" PetscInt_FMT " revolute joints, %" PetscInt_FMT " inputs, %" PetscInt_FMT " outputs\n", name, nb, nsys, nrev, a, t));
  } else PetscCall(PetscViewerASCIIPrintf(viewer, "no scene set\n"));
  if (r->nconfig) PetscCall(KFReducerViewAngles_Private(viewer, "angles of interest", r->nconfig, nrev, r->angles));
  PetscCall(PetscViewerASCIIPrintf(viewer, "method %s; band %g-%g Hz; damping %g; accuracy %g on the %s response\n", KFReducerMethods[r->method], (double)r->band[0], (double)r->band[1], (double)r->zeta, (double)r->accuracy, KFAccuracyMeasures[r->accuracy_measure]));
  {
    char buf[1024];
    PetscCall(KFDampingDescribe_Private(&r->damping, buf, sizeof(buf)));
    PetscCall(PetscViewerASCIIPrintf(viewer, "damping: %s\n", buf));
  }
  if (r->auto_alpha) PetscCall(PetscViewerASCIIPrintf(viewer, "alpha_G: auto (the paper's rule)\n"));
  else PetscCall(KFReducerViewAngles_Private(viewer, "alpha_G", 1, nrev, r->alpha_g));
  if (r->nmulti) PetscCall(KFReducerViewAngles_Private(viewer, "multi-angle configurations", r->nmulti, nrev, r->multi));
  if (r->moments == PETSC_DECIDE) PetscCall(PetscViewerASCIIPrintf(viewer, "moments auto (the accuracy search, up to %" PetscInt_FMT ")\n", r->moments_max));
  PetscCall(PetscViewerASCIIPrintf(viewer, "moments %" PetscInt_FMT " (%" PetscInt_FMT " output blocks); importance %s, keep threshold %g; static correction %s\n", r->moments, r->output_blocks, KFImportances[r->importance], (double)r->keep_threshold, r->static_correction ? "yes" : "no"));
  PetscCall(PetscViewerASCIIPrintf(viewer, "tolerances: deflation %g, body %g, reassembly %g; shift %g\n", (double)r->deflation_tol, (double)r->body_tol, (double)r->reassembly_rtol, (double)r->shift));
  if (r->max_frequency > 0) PetscCall(PetscViewerASCIIPrintf(viewer, "trimming: modes above %g%s out of the dynamics (static share kept)\n", (double)r->max_frequency, r->max_frequency_hz ? " Hz" : " x the band's top"));
  PetscCall(PetscViewerASCIIPrintf(viewer, "verification: %s, %" PetscInt_FMT " frequency points, FRF floor %g dB\n", r->verify ? "full order" : "off", r->frequency_points, (double)r->frf_floor_db));
  if (r->ops->view) PetscCall((*r->ops->view)(r, viewer));
  if (r->solved) {
    PetscInt nb;

    PetscCall(PetscViewerASCIIPrintf(viewer, "%s\n", r->rule));
    PetscCall(KFSceneGetInfo(r->scene, &nb, NULL, NULL, NULL, NULL, NULL));
    for (PetscInt c = 0; c < r->nconfig; c++) {
      const PetscReal *dofs, *err = NULL;
      PetscInt         nd;
      const char *const *names;
      PetscBool        has = PETSC_FALSE;

      PetscCall(KFReducerGetResult(r, c, "reduced_dofs", NULL, NULL, &dofs));
      PetscCall(KFReducerGetResultNames(r, c, &nd, &names));
      for (PetscInt i = 0; i < nd; i++) has = has || !strcmp(names[i], "frf_error");
      if (has) PetscCall(KFReducerGetResult(r, c, "frf_error", NULL, NULL, &err));
      PetscCall(KFReducerViewAngles_Private(viewer, "configuration", 1, nrev, &r->angles[c * PetscMax(nrev, 1)]));
      PetscCall(PetscViewerASCIIPushTab(viewer));
      if (err) PetscCall(PetscViewerASCIIPrintf(viewer, "single-angle model: %d system dofs, FRF max relative %s error %.3g (target %g)\n", (int)dofs[0], KFAccuracyMeasures[r->accuracy_measure], (double)err[0], (double)r->accuracy));
      else PetscCall(PetscViewerASCIIPrintf(viewer, "single-angle model: %d system dofs, not verified\n", (int)dofs[0]));
      PetscCall(PetscViewerASCIIPopTab(viewer));
    }
    for (PetscInt i = 0; i < r->nnotes; i++) PetscCall(PetscViewerASCIIPrintf(viewer, "note: %s\n", r->notes[i]));
  }
  PetscCall(PetscViewerASCIIPopTab(viewer));
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerViewFromOptions(KFReducer r, PetscObject obj, const char name[])
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCall(PetscObjectViewFromOptions((PetscObject)r, obj, name));
  PetscFunctionReturn(0);
}
