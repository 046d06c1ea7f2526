/* Small generalized symmetric eigenproblem K phi = lambda M phi (LAPACK sygv). */
#include "dense_impl.h"
#include <petscblaslapack.h> /* after the PETSc headers it relies on */

/* The LAPACK workspace sygv asks for at n (with the documented minimum), queried without allocation */
PetscErrorCode KFDenseEigWorkSize_Private(PetscInt n, PetscBLASInt *lwork)
{
  PetscBLASInt bn, itype = 1, query = -1, info = 0;
  PetscReal    wquery = 0, adummy = 0, bdummy = 0, ldummy = 0;

  PetscFunctionBegin;
  *lwork = 1;
  if (n <= 0) PetscFunctionReturn(0);
  PetscCall(PetscBLASIntCast(n, &bn));
  PetscCall(PetscFPTrapPush(PETSC_FP_TRAP_OFF));
  PetscCallBLAS("LAPACKsygv", LAPACKsygv_(&itype, "V", "U", &bn, &adummy, &bn, &bdummy, &bn, &ldummy, &wquery, &query, &info));
  PetscCall(PetscFPTrapPop());
  *lwork = (PetscBLASInt)wquery;
  *lwork = PetscMax(*lwork, 3 * bn);
  PetscFunctionReturn(0);
}

/* KFDenseEig in the caller's workspace (B: n n, work: lwork reals, lwork exactly what KFDenseEigWorkSize_Private gives
   at n: the same blocking, the same digits; the caller queries once): no allocation */
PetscErrorCode KFDenseEig_Private(PetscInt n, const PetscReal K[], const PetscReal M[], PetscReal lambda[], PetscReal Phi[], PetscReal B[], PetscReal work[], PetscBLASInt lwork)
{
  PetscBLASInt bn, itype = 1, info = 0;

  PetscFunctionBegin;
  PetscCheck(n >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFDenseEig: negative size %" PetscInt_FMT, n);
  if (!n) PetscFunctionReturn(0);
  PetscCall(KFDenseCheckSymmetric_Private(n, K, "stiffness matrix K", "KFDenseEig"));
  PetscCall(KFDenseCheckSymmetric_Private(n, M, "mass matrix M", "KFDenseEig"));
  PetscCall(PetscBLASIntCast(n, &bn));
  PetscCall(PetscArraycpy(Phi, K, n * n));
  PetscCall(PetscArraycpy(B, M, n * n));
  PetscCall(PetscFPTrapPush(PETSC_FP_TRAP_OFF));
  PetscCallBLAS("LAPACKsygv", LAPACKsygv_(&itype, "V", "U", &bn, Phi, &bn, B, &bn, lambda, work, &lwork, &info));
  PetscCall(PetscFPTrapPop());
  PetscCheck(info <= bn, PETSC_COMM_SELF, PETSC_ERR_MAT_CH_ZRPVT,
             "KFDenseEig: the %" PetscInt_FMT " x %" PetscInt_FMT " mass matrix is not positive definite (its leading minor of order %d is not; LAPACK sygv info %d): if it is a reduced mass matrix the basis lost rank, so raise the deflation tolerance",
             n, n, (int)(info - bn), (int)info);
  PetscCheck(info == 0, PETSC_COMM_SELF, PETSC_ERR_LIB, "KFDenseEig: the symmetric eigensolver did not converge on the %" PetscInt_FMT "-dof pencil (LAPACK sygv info %d): check K and M for huge or tiny entries", n, (int)info);
  PetscFunctionReturn(0);
}

PetscErrorCode KFDenseEig(PetscInt n, const PetscReal K[], const PetscReal M[], PetscReal lambda[], PetscReal Phi[])
{
  PetscBLASInt lwork;
  PetscReal   *B, *work;

  PetscFunctionBegin;
  PetscCheck(n >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFDenseEig: negative size %" PetscInt_FMT, n);
  if (!n) PetscFunctionReturn(0);
  PetscCall(KFDenseEigWorkSize_Private(n, &lwork));
  PetscCall(PetscMalloc2(n * n, &B, lwork, &work));
  PetscCall(KFDenseEig_Private(n, K, M, lambda, Phi, B, work, lwork));
  PetscCall(PetscFree2(B, work));
  PetscFunctionReturn(0);
}
