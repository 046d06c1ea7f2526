/* ASCII view of a reduced model: what it stands for and how large it is. */
#include <kryflex/modelimpl.h>

PetscErrorCode KFReducedModelView(KFReducedModel m, PetscViewer viewer)
{
  PetscBool iascii;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, KF_REDUCEDMODEL_CLASSID, 1);
  if (!viewer) PetscCall(PetscViewerASCIIGetStdout(PetscObjectComm((PetscObject)m), &viewer));
  PetscValidHeaderSpecific(viewer, PETSC_VIEWER_CLASSID, 2);
  PetscCall(PetscObjectTypeCompare((PetscObject)viewer, PETSCVIEWERASCII, &iascii));
  if (!iascii) PetscFunctionReturn(0);
  PetscCall(PetscObjectPrintClassNamePrefixType((PetscObject)m, viewer));
  PetscCall(PetscViewerASCIIPushTab(viewer));
  PetscCall(PetscViewerASCIIPrintf(viewer, "scene '%s' (fingerprint %s): %" PetscInt_FMT " bodies, %" PetscInt_FMT " joints (%" PetscInt_FMT " revolute), %" PetscInt_FMT " inputs, %" PetscInt_FMT " outputs\n", m->scene_name, m->fingerprint, m->nb, m->nj, m->nrevolute, m->ninputs, m->noutputs));
  for (PetscInt b = 0; b < m->nb; b++) {
    KFModelBody *R = &m->bodies[b];
    PetscCall(PetscViewerASCIIPrintf(viewer, "body %-16s %10" PetscInt_FMT " full dofs -> %4" PetscInt_FMT " reduced, interfaces:", R->name, R->full_dofs, R->v));
    PetscCall(PetscViewerASCIIUseTabs(viewer, PETSC_FALSE));
    for (PetscInt i = 0; i < R->ninterfaces; i++) PetscCall(PetscViewerASCIIPrintf(viewer, " %s", R->iface_names[i]));
    PetscCall(PetscViewerASCIIPrintf(viewer, "%s%s\n", R->ninterfaces ? "" : " none", R->map ? " (map to full dofs kept)" : ""));
    PetscCall(PetscViewerASCIIUseTabs(viewer, PETSC_TRUE));
  }
  for (PetscInt j = 0; j < m->nj; j++) {
    const KFJointDef *J = &m->joints[j];
    PetscCall(PetscViewerASCIIPrintf(viewer, "joint %-15s %-8s %s.%s -> %s.%s", m->joint_names[j], J->type == KF_JOINT_REVOLUTE ? "revolute" : "fixed", m->bodies[J->parent].name, m->bodies[J->parent].iface_names[J->parent_interface], m->bodies[J->child].name, m->bodies[J->child].iface_names[J->child_interface]));
    PetscCall(PetscViewerASCIIUseTabs(viewer, PETSC_FALSE));
    if (J->type == KF_JOINT_REVOLUTE) PetscCall(PetscViewerASCIIPrintf(viewer, " axis (%g %g %g)", (double)J->axis[0], (double)J->axis[1], (double)J->axis[2]));
    PetscCall(PetscViewerASCIIPrintf(viewer, "\n"));
    PetscCall(PetscViewerASCIIUseTabs(viewer, PETSC_TRUE));
  }
  for (int pass = 0; pass < 2; pass++) {
    PetscInt n = pass ? m->noutputs : m->ninputs;
    PetscCall(PetscViewerASCIIPrintf(viewer, "%s:", pass ? "outputs" : "inputs"));
    PetscCall(PetscViewerASCIIUseTabs(viewer, PETSC_FALSE));
    for (PetscInt i = 0; i < n; i++) PetscCall(PetscViewerASCIIPrintf(viewer, " %s", pass ? m->output_names[i] : m->input_names[i]));
    PetscCall(PetscViewerASCIIPrintf(viewer, "\n"));
    PetscCall(PetscViewerASCIIUseTabs(viewer, PETSC_TRUE));
  }
  if (m->nangles && !m->nrevolute) PetscCall(PetscViewerASCIIPrintf(viewer, "reduction configuration: the structure (no revolute joint)\n"));
  else if (m->nangles) {
    PetscCall(PetscViewerASCIIPrintf(viewer, "reduction configurations (deg):"));
    PetscCall(PetscViewerASCIIUseTabs(viewer, PETSC_FALSE));
    for (PetscInt c = 0; c < m->nangles; c++) {
      PetscCall(PetscViewerASCIIPrintf(viewer, " ("));
      for (PetscInt r = 0; r < m->nrevolute; r++) PetscCall(PetscViewerASCIIPrintf(viewer, "%s%g", r ? " " : "", (double)(m->angles[c * m->nrevolute + r] * 180 / PETSC_PI)));
      PetscCall(PetscViewerASCIIPrintf(viewer, ")"));
    }
    PetscCall(PetscViewerASCIIPrintf(viewer, "\n"));
    PetscCall(PetscViewerASCIIUseTabs(viewer, PETSC_TRUE));
  }
  if (m->nties) PetscCall(PetscViewerASCIIPrintf(viewer, "coordinate ties between the bodies (shared directions): %" PetscInt_FMT "\n", m->nties));
  if (m->nsettings) {
    PetscCall(PetscViewerASCIIPrintf(viewer, "settings:\n"));
    PetscCall(PetscViewerASCIIPushTab(viewer));
    for (PetscInt k = 0; k < m->nsettings; k++) PetscCall(PetscViewerASCIIPrintf(viewer, "%s = %s\n", m->keys[k], m->values[k]));
    PetscCall(PetscViewerASCIIPopTab(viewer));
  }
  PetscCall(PetscViewerASCIIPopTab(viewer));
  PetscFunctionReturn(0);
}

/* -kf_model_view (or the option the caller names) */
PetscErrorCode KFReducedModelViewFromOptions(KFReducedModel m, PetscObject obj, const char name[])
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, KF_REDUCEDMODEL_CLASSID, 1);
  PetscCall(PetscObjectViewFromOptions((PetscObject)m, obj, name));
  PetscFunctionReturn(0);
}
