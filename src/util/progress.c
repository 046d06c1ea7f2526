#include <kryflex_impl.h>
#include <stdarg.h>

PetscLogEvent KF_EVENT_LOAD, KF_EVENT_ASSEMBLE, KF_EVENT_RIGID, KF_EVENT_FACTOR, KF_EVENT_SOLVE, KF_EVENT_ORTHO, KF_EVENT_PROJECT, KF_EVENT_VERIFY, KF_EVENT_MOMENTS;
PetscLogEvent KF_EVENT_BODY_BASIS, KF_EVENT_BODY_REDUCE;
static PetscBool     kf_initialized = PETSC_FALSE;
static PetscLogDouble kf_t0;

static PetscErrorCode KFFinalize(void)
{
  PetscFunctionBegin;
  /* PetscFinalize forgets the log events: a later PetscInitialize (the Python face may run several) registers anew */
  kf_initialized = PETSC_FALSE;
  PetscFunctionReturn(0);
}

/* Registers one log event per stage so that -log_view shows where the time goes, the class ids of the scene and the
   reduced model, and the help of -kf_quiet (read by KFProgress, which is called too often for an options block). */
PetscErrorCode KFInitialize(void)
{
  PetscClassId classid;
  PetscBool    quiet = PETSC_FALSE;

  PetscFunctionBegin;
  if (kf_initialized) PetscFunctionReturn(0);
  kf_initialized = PETSC_TRUE;
  PetscCall(PetscTime(&kf_t0));
  PetscCall(PetscRegisterFinalize(KFFinalize));
  PetscCall(KFModelInitializePackage());
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
  PetscOptionsBegin(PETSC_COMM_WORLD, NULL, "kryflex progress lines", "KFProgress");
  PetscCall(KFOptionsSettingBool(PetscOptionsObject, "-kf_quiet", quiet, &quiet, NULL));
  PetscOptionsEnd();
  PetscFunctionReturn(0);
}

/* Progress lines on rank 0 with the elapsed time since kryflex started; -kf_quiet silences them. */
PetscErrorCode KFProgress(MPI_Comm comm, const char fmt[], ...)
{
  PetscBool      quiet = PETSC_FALSE;
  PetscLogDouble now;
  char           line[1024];
  va_list        args;
  size_t         len;

  PetscFunctionBegin;
  PetscCall(PetscOptionsGetBool(NULL, NULL, "-kf_quiet", &quiet, NULL));
  if (quiet) PetscFunctionReturn(0);
  if (!kf_initialized) PetscCall(KFInitialize());
  PetscCall(PetscTime(&now));
  va_start(args, fmt);
  PetscCall(PetscVSNPrintf(line, sizeof(line), fmt, &len, args));
  va_end(args);
  PetscCall(PetscPrintf(comm, "[kryflex %8.2f s] %s\n", (double)(now - kf_t0), line));
  PetscFunctionReturn(0);
}
