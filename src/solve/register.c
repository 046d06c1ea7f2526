/* The flexible solver's implementations, registered by name (as PETSc's itregis.c): the one file that names them. */
#include <kryflex/flexsolverimpl.h>

PETSC_INTERN PetscErrorCode KFFlexSolverRegisterAll(void)
{
  PetscFunctionBegin;
  PetscCall(KFFlexSolverRegister(KFFLEXSOLVERAUTO, KFFlexSolverCreate_Auto));
  PetscCall(KFFlexSolverRegister(KFFLEXSOLVERMONOLITHIC, KFFlexSolverCreate_Monolithic));
  PetscCall(KFFlexSolverRegister(KFFLEXSOLVERBODYWISE, KFFlexSolverCreate_Bodywise));
  PetscFunctionReturn(0);
}
