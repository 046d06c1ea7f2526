/* Progress lines on rank 0 with the time since kryflex started (src/util/package.c keeps it). */
#include <kryflex_impl.h>
#include <stdarg.h>

/* Progress lines on rank 0 with the elapsed time since kryflex started; -kf_quiet silences them. */
PetscErrorCode KFProgress(MPI_Comm comm, const char fmt[], ...)
{
  PetscBool      quiet = PETSC_FALSE;
  PetscLogDouble now, t0;
  char           line[1024];
  va_list        args;
  size_t         len;

  PetscFunctionBegin;
  PetscCall(PetscOptionsGetBool(NULL, NULL, "-kf_quiet", &quiet, NULL));
  if (quiet) PetscFunctionReturn(0);
  PetscCall(KFGetStartTime(&t0));
  PetscCall(PetscTime(&now));
  va_start(args, fmt);
  PetscCall(PetscVSNPrintf(line, sizeof(line), fmt, &len, args));
  va_end(args);
  PetscCall(PetscPrintf(comm, "[kryflex %8.2f s] %s\n", (double)(now - t0), line));
  PetscFunctionReturn(0);
}
