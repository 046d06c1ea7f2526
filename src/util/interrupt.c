#include <kryflex_impl.h>
#include <signal.h>
#include <string.h>

/* The signal a command was asked to stop by. A handler may only set a flag of this type; the work notices it at
   its next KFInterruptCheck, so results and files are never left half-made by the signal itself. */
static volatile sig_atomic_t kf_signal = 0;

static void KFInterruptHandler(int sig)
{
  if (kf_signal == sig) { /* asked twice: the user does not want to wait for the next check */
    signal(sig, SIG_DFL);
    raise(sig);
    return;
  }
  if (!kf_signal) kf_signal = sig;
}

PetscErrorCode KFInterruptCatch(void)
{
  struct sigaction sa;

  PetscFunctionBegin;
  memset(&sa, 0, sizeof(sa));
  sa.sa_handler = KFInterruptHandler;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART; /* system calls in progress (MPI, file writes) go on: the checks stop the work */
  PetscCheck(sigaction(SIGINT, &sa, NULL) == 0 && sigaction(SIGTERM, &sa, NULL) == 0, PETSC_COMM_SELF, PETSC_ERR_SYS, "cannot install the SIGINT/SIGTERM handlers");
  PetscFunctionReturn(0);
}

int KFInterruptSignal(void)
{
  return (int)kf_signal;
}

/* Collective: the largest signal number noted on any rank (SIGTERM over SIGINT), so every rank stops here together
   and reports the same signal afterwards. */
PetscErrorCode KFInterruptCheck(MPI_Comm comm)
{
  int local = (int)kf_signal, sig = 0;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Allreduce(&local, &sig, 1, MPI_INT, MPI_MAX, comm));
  if (sig && sig != local) kf_signal = (sig_atomic_t)sig;
  PetscCheck(!sig, comm, KF_ERR_INTERRUPTED, "interrupted by %s", sig == SIGTERM ? "SIGTERM" : (sig == SIGINT ? "SIGINT" : "a signal"));
  PetscFunctionReturn(0);
}
