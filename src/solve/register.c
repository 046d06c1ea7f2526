/* The flexible solver's registry (as PETSc's itregis.c): the implementations by name, the one file that names them. */
#include <kryflex/flexsolverimpl.h>

PetscFunctionList KFFlexSolverList = NULL;
static PetscBool  KFFlexSolverRegisterAllCalled = PETSC_FALSE;
static char     **KFFlexSolverNames      = NULL; /* the registered names, in order: KFFlexSolverCheckOptions reads each one's options */
static PetscInt   KFFlexSolverNamesCount = 0;

static PetscErrorCode KFFlexSolverFinalizePackage(void)
{
  PetscFunctionBegin;
  PetscCall(PetscFunctionListDestroy(&KFFlexSolverList));
  for (PetscInt i = 0; i < KFFlexSolverNamesCount; i++) PetscCall(PetscFree(KFFlexSolverNames[i]));
  PetscCall(PetscFree(KFFlexSolverNames));
  KFFlexSolverNamesCount        = 0;
  KFFlexSolverRegisterAllCalled = PETSC_FALSE;
  PetscFunctionReturn(0);
}

/*
  KFFlexSolverRegister - adds an implementation of the flexible solve: KFFlexSolverSetType(solver, name) then calls
  create(solver), which fills solver->ops and solver->data.
*/
PetscErrorCode KFFlexSolverRegister(const char name[], PetscErrorCode (*create)(KFFlexSolver))
{
  char **names;

  PetscFunctionBegin;
  PetscCall(KFFlexSolverRegisterAll());
  PetscCall(PetscFunctionListAdd(&KFFlexSolverList, name, create));
  PetscCall(PetscMalloc1(KFFlexSolverNamesCount + 1, &names));
  PetscCall(PetscArraycpy(names, KFFlexSolverNames, KFFlexSolverNamesCount));
  PetscCall(PetscStrallocpy(name, &names[KFFlexSolverNamesCount]));
  PetscCall(PetscFree(KFFlexSolverNames));
  KFFlexSolverNames = names;
  KFFlexSolverNamesCount++;
  PetscFunctionReturn(0);
}

/* the registered names, in the order they were registered */
PETSC_INTERN PetscErrorCode KFFlexSolverGetTypeNames(PetscInt *n, const char *const **names)
{
  PetscFunctionBegin;
  PetscCall(KFFlexSolverRegisterAll());
  *n     = KFFlexSolverNamesCount;
  *names = (const char *const *)KFFlexSolverNames;
  PetscFunctionReturn(0);
}

/* the built-in types, once per PetscInitialize (on the first solver made) */
PETSC_INTERN PetscErrorCode KFFlexSolverRegisterAll(void)
{
  PetscFunctionBegin;
  if (KFFlexSolverRegisterAllCalled) PetscFunctionReturn(0);
  KFFlexSolverRegisterAllCalled = PETSC_TRUE;
  PetscCall(KFInitialize());
  PetscCall(PetscRegisterFinalize(KFFlexSolverFinalizePackage));
  PetscCall(KFFlexSolverRegister(KFFLEXSOLVERAUTO, KFFlexSolverCreate_Auto));
  PetscCall(KFFlexSolverRegister(KFFLEXSOLVERMONOLITHIC, KFFlexSolverCreate_Monolithic));
  PetscCall(KFFlexSolverRegister(KFFLEXSOLVERBODYWISE, KFFlexSolverCreate_Bodywise));
  PetscFunctionReturn(0);
}
