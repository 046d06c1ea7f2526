/* Small generalized symmetric eigenproblem K phi = lambda M phi (LAPACK sygv). */
#include "dense_impl.h"
#include <petscblaslapack.h> /* after the PETSc headers it relies on */

PetscErrorCode KFDenseEig(PetscInt n, const PetscReal K[], const PetscReal M[], PetscReal lambda[], PetscReal Phi[])
{
  PetscBLASInt bn, itype = 1, lwork = -1, info = 0;
  PetscReal   *B, *work, wquery = 0;

  PetscFunctionBegin;
  PetscCheck(n >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFDenseEig: negative size %" PetscInt_FMT, n);
  if (!n) PetscFunctionReturn(0);
  PetscCall(KFDenseCheckSymmetric_Private(n, K, "stiffness matrix K", "KFDenseEig"));
  PetscCall(KFDenseCheckSymmetric_Private(n, M, "mass matrix M", "KFDenseEig"));
  PetscCall(PetscBLASIntCast(n, &bn));
  PetscCall(PetscMalloc1(n * n, &B));
  PetscCall(PetscArraycpy(Phi, K, n * n));
  PetscCall(PetscArraycpy(B, M, n * n));
  PetscCall(PetscFPTrapPush(PETSC_FP_TRAP_OFF));
  PetscCallBLAS("LAPACKsygv", LAPACKsygv_(&itype, "V", "U", &bn, Phi, &bn, B, &bn, lambda, &wquery, &lwork, &info));
  lwork = (PetscBLASInt)wquery;
  lwork = PetscMax(lwork, 3 * bn);
  PetscCall(PetscMalloc1(lwork, &work));
  PetscCallBLAS("LAPACKsygv", LAPACKsygv_(&itype, "V", "U", &bn, Phi, &bn, B, &bn, lambda, work, &lwork, &info));
  PetscCall(PetscFPTrapPop());
  PetscCall(PetscFree(work));
  PetscCall(PetscFree(B));
  PetscCheck(info <= bn, PETSC_COMM_SELF, PETSC_ERR_MAT_CH_ZRPVT,
             "KFDenseEig: the %" PetscInt_FMT " x %" PetscInt_FMT " mass matrix is not positive definite (its leading minor of order %d is not; LAPACK sygv info %d): if it is a reduced mass matrix the basis lost rank, so raise the deflation tolerance",
             n, n, (int)(info - bn), (int)info);
  PetscCheck(info == 0, PETSC_COMM_SELF, PETSC_ERR_LIB, "KFDenseEig: the symmetric eigensolver did not converge on the %" PetscInt_FMT "-dof pencil (LAPACK sygv info %d): check K and M for huge or tiny entries", n, (int)info);
  PetscFunctionReturn(0);
}
