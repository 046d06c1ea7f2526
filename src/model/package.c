/* Class ids of the scene and the reduced model, registered once per PetscInitialize. */
#include <kryflex/modelimpl.h>

PetscClassId     KF_SCENE_CLASSID        = 0;
PetscClassId     KF_REDUCEDMODEL_CLASSID = 0;
static PetscBool KFModelPackageInitialized = PETSC_FALSE;

static PetscErrorCode KFModelFinalizePackage(void)
{
  PetscFunctionBegin;
  /* PetscFinalize forgets the class ids: a later PetscInitialize (the Python face may run several) registers anew */
  KFModelPackageInitialized = PETSC_FALSE;
  KF_SCENE_CLASSID          = 0;
  KF_REDUCEDMODEL_CLASSID   = 0;
  PetscFunctionReturn(0);
}

/*
  KFModelInitializePackage - registers the class ids of KFScene and KFReducedModel; called by KFInitialize (and
  by KFSceneCreate and the model constructors, so that it never matters who comes first).
*/
PetscErrorCode KFModelInitializePackage(void)
{
  PetscFunctionBegin;
  if (KFModelPackageInitialized) PetscFunctionReturn(0);
  KFModelPackageInitialized = PETSC_TRUE;
  PetscCall(PetscClassIdRegister("KFScene", &KF_SCENE_CLASSID));
  PetscCall(PetscClassIdRegister("KFReducedModel", &KF_REDUCEDMODEL_CLASSID));
  PetscCall(PetscRegisterFinalize(KFModelFinalizePackage));
  PetscFunctionReturn(0);
}
