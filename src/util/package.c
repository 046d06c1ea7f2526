/* The library's one package initializer (as PETSc's dlregisksp.c): the class ids of every kryflex object, one log
   event per stage so that -log_view shows where the time goes, and the help of -kf_quiet (read by KFProgress, which is
   called too often for an options block). The types of the reducer and of the flexible solver are registered by their
   own objects on first use (KFReducerRegister, KFFlexSolverRegister), so that this file calls nothing of kryflex. */
#include <kryflex_impl.h>

PetscClassId  KF_SCENE_CLASSID = 0, KF_REDUCEDMODEL_CLASSID = 0, KF_REDUCER_CLASSID = 0, KF_FLEXSOLVER_CLASSID = 0;
PetscLogEvent KF_EVENT_LOAD, KF_EVENT_ASSEMBLE, KF_EVENT_RIGID, KF_EVENT_FACTOR, KF_EVENT_SOLVE, KF_EVENT_ORTHO, KF_EVENT_PROJECT, KF_EVENT_VERIFY, KF_EVENT_MOMENTS;
PetscLogEvent KF_EVENT_BODY_BASIS, KF_EVENT_BODY_REDUCE;
PetscLogEvent KF_EVENT_REDUCER_SETUP, KF_EVENT_REDUCER_SOLVE, KF_EVENT_REDUCER_BASIS, KF_EVENT_REDUCER_VERIFY;
static PetscBool      kf_initialized = PETSC_FALSE;
static PetscLogDouble kf_t0;

static PetscErrorCode KFFinalize(void)
{
  PetscFunctionBegin;
  /* PetscFinalize forgets the class ids and log events: a later PetscInitialize (the Python face may run several)
     registers anew */
  kf_initialized          = PETSC_FALSE;
  KF_SCENE_CLASSID        = 0;
  KF_REDUCEDMODEL_CLASSID = 0;
  KF_REDUCER_CLASSID      = 0;
  KF_FLEXSOLVER_CLASSID   = 0;
  PetscFunctionReturn(0);
}

static PetscErrorCode KFRegisterEvents(void)
{
  PetscClassId classid;

  PetscFunctionBegin;
  PetscCall(PetscClassIdRegister("kryflex", &classid));
  PetscCall(PetscLogEventRegister("KFLoad", classid, &KF_EVENT_LOAD));
  PetscCall(PetscLogEventRegister("KFAssemble", classid, &KF_EVENT_ASSEMBLE));
  PetscCall(PetscLogEventRegister("KFRigidModes", classid, &KF_EVENT_RIGID));
  PetscCall(PetscLogEventRegister("KFFactor", classid, &KF_EVENT_FACTOR));
  PetscCall(PetscLogEventRegister("KFSolve", classid, &KF_EVENT_SOLVE));
  PetscCall(PetscLogEventRegister("KFOrthogonalize", classid, &KF_EVENT_ORTHO));
  PetscCall(PetscLogEventRegister("KFProject", classid, &KF_EVENT_PROJECT));
  /* inside KFOrthogonalize: the body bases (KFBodyBasisFinish), and of them the reduced matrices (K Psi and the
     projections); the rest of KFOrthogonalize is the Krylov basis */
  PetscCall(PetscLogEventRegister("KFBodyBasis", classid, &KF_EVENT_BODY_BASIS));
  PetscCall(PetscLogEventRegister("KFBodyReduce", classid, &KF_EVENT_BODY_REDUCE));
  PetscCall(PetscLogEventRegister("KFMoments", classid, &KF_EVENT_MOMENTS));
  PetscCall(PetscLogEventRegister("KFVerify", classid, &KF_EVENT_VERIFY));
  PetscCall(PetscLogEventRegister("KFReducerSetUp", KF_REDUCER_CLASSID, &KF_EVENT_REDUCER_SETUP));
  PetscCall(PetscLogEventRegister("KFReducerSolve", KF_REDUCER_CLASSID, &KF_EVENT_REDUCER_SOLVE));
  PetscCall(PetscLogEventRegister("KFReducerBasis", KF_REDUCER_CLASSID, &KF_EVENT_REDUCER_BASIS));
  PetscCall(PetscLogEventRegister("KFReducerVerify", KF_REDUCER_CLASSID, &KF_EVENT_REDUCER_VERIFY));
  PetscFunctionReturn(0);
}

/* Once per PetscInitialize; every object's constructor calls it, so that it never matters who comes first. */
PetscErrorCode KFInitialize(void)
{
  PetscBool quiet = PETSC_FALSE;

  PetscFunctionBegin;
  if (kf_initialized) PetscFunctionReturn(0);
  kf_initialized = PETSC_TRUE;
  PetscCall(PetscTime(&kf_t0));
  PetscCall(PetscRegisterFinalize(KFFinalize));
  PetscCall(PetscClassIdRegister("KFScene", &KF_SCENE_CLASSID));
  PetscCall(PetscClassIdRegister("KFReducedModel", &KF_REDUCEDMODEL_CLASSID));
  PetscCall(PetscClassIdRegister("KFReducer", &KF_REDUCER_CLASSID));
  PetscCall(PetscClassIdRegister("KFFlexSolver", &KF_FLEXSOLVER_CLASSID));
  PetscCall(KFRegisterEvents());
  PetscOptionsBegin(PETSC_COMM_WORLD, NULL, "kryflex progress lines", "KFProgress");
  PetscCall(KFOptionsSettingBool(PetscOptionsObject, "-kf_quiet", quiet, &quiet, NULL));
  PetscOptionsEnd();
  PetscFunctionReturn(0);
}

/* when kryflex started (the first KFInitialize of this PetscInitialize) */
PETSC_INTERN PetscErrorCode KFGetStartTime(PetscLogDouble *t0)
{
  PetscFunctionBegin;
  PetscCall(KFInitialize());
  *t0 = kf_t0;
  PetscFunctionReturn(0);
}
