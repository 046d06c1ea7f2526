/* A reduced model's damping (modal, Rayleigh, structural; the bodies' reduced viscous matrices live with the bodies)
   and its outputs' quantities. */
#include <kryflex/modelimpl.h>

PetscErrorCode KFReducedModelSetDamping(KFReducedModel m, const KFDamping *d)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, KF_REDUCEDMODEL_CLASSID, 1);
  PetscValidPointer(d, 2);
  PetscCall(KFDampingCheck(PetscObjectComm((PetscObject)m), d));
  m->damping = *d;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducedModelGetDamping(KFReducedModel m, KFDamping *d)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, KF_REDUCEDMODEL_CLASSID, 1);
  PetscValidPointer(d, 2);
  *d = m->damping;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducedModelGetOutputQuantities(KFReducedModel m, const PetscInt **quantity)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, KF_REDUCEDMODEL_CLASSID, 1);
  *quantity = m->quantity;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducedModelGetBodyDamping(KFReducedModel m, PetscInt b, const PetscReal **C)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, KF_REDUCEDMODEL_CLASSID, 1);
  PetscCheck(b >= 0 && b < m->nb, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_OUTOFRANGE, "body index %" PetscInt_FMT " does not exist (the model has %" PetscInt_FMT " bodies)", b, m->nb);
  *C = m->bodies[b].C;
  PetscFunctionReturn(0);
}
