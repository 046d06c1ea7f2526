#include <kryflex_impl.h>

/* Bindings turn a PETSc error into an exception carrying the message of the call that failed first, instead of
   a traceback on stderr: this handler keeps that first message and returns the error code. */
static char kf_last_error[4096];

static PetscErrorCode KFRecordError(MPI_Comm comm, int line, const char *fun, const char *file, PetscErrorCode n, PetscErrorType p, const char *mess, void *ctx)
{
  (void)comm; (void)ctx; (void)line; (void)fun; (void)file;
  if (p == PETSC_ERROR_INITIAL) {
    const char *text = NULL;
    if (!mess || !mess[0]) PetscErrorMessage(n, &text, NULL);
    PetscSNPrintf(kf_last_error, sizeof(kf_last_error), "%s", (mess && mess[0]) ? mess : (text ? text : "unknown PETSc error"));

  }
  return n;
}

PetscErrorCode KFPushErrorRecorder(void)
{
  PetscFunctionBegin;
  PetscCall(PetscPushErrorHandler(KFRecordError, NULL));
  PetscFunctionReturn(0);
}

const char *KFLastError(void)
{
  return kf_last_error;
}

void KFClearError(void)
{
  kf_last_error[0] = 0;
}
