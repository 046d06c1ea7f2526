/* Null space of a small constraint matrix by SVD (eq. 21-22), with a relative rank tolerance. */
#include "dense_impl.h"
#include <petscblaslapack.h> /* after the PETSc headers it relies on */

/* The LAPACK workspace gesvd asks for at m x n (with the documented minimum), queried without allocation */
PetscErrorCode KFDenseNullSpaceWorkSize_Private(PetscInt m, PetscInt n, PetscBLASInt *lwork)
{
  PetscBLASInt bm, bn, one = 1, query = -1, info = 0;
  PetscReal    wquery = 0, udummy = 0, adummy = 0, sdummy = 0, vdummy = 0;

  PetscFunctionBegin;
  *lwork = 1;
  if (!m || !n) PetscFunctionReturn(0);
  PetscCall(PetscBLASIntCast(m, &bm));
  PetscCall(PetscBLASIntCast(n, &bn));
  PetscCall(PetscFPTrapPush(PETSC_FP_TRAP_OFF));
  PetscCallBLAS("LAPACKgesvd", LAPACKgesvd_("N", "A", &bm, &bn, &adummy, &bm, &sdummy, &udummy, &one, &vdummy, &bn, &wquery, &query, &info));
  PetscCall(PetscFPTrapPop());
  *lwork = (PetscBLASInt)wquery;
  *lwork = PetscMax(*lwork, PetscMax(3 * PetscMin(bm, bn) + PetscMax(bm, bn), 5 * PetscMin(bm, bn)));
  PetscFunctionReturn(0);
}

/* KFDenseNullSpace in the caller's workspace (A: m n, s: min(m, n), VT: n n, work: lwork reals, lwork exactly what
   KFDenseNullSpaceWorkSize_Private gives at m x n: the same blocking, the same digits; the caller queries once):
   no allocation, for reassembly inside a time integration */
PetscErrorCode KFDenseNullSpace_Private(PetscInt m, PetscInt n, const PetscReal D[], PetscReal rtol, PetscInt *h, PetscReal N[], PetscInt *rank, PetscReal *sratio, PetscReal A[], PetscReal s[], PetscReal VT[], PetscReal work[], PetscBLASInt lwork)
{
  PetscBLASInt bm, bn, one = 1, info = 0;
  PetscReal    udummy = 0, smax;
  PetscInt     ns = PetscMin(m, n), r = 0;

  PetscFunctionBegin;
  PetscCheck(m >= 0 && n >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFDenseNullSpace: negative size %" PetscInt_FMT " x %" PetscInt_FMT, m, n);
  PetscCheck(rtol >= 0 && rtol < 1, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFDenseNullSpace: relative rank tolerance %g is outside [0, 1): use a small positive value such as 1e-10", (double)rtol);
  if (!m || !n) { /* no constraints: the whole space is free */
    PetscCall(PetscArrayzero(N, n * n));
    for (PetscInt i = 0; i < n; i++) N[i + i * n] = 1;
    *h = n;
    if (rank) *rank = 0;
    if (sratio) *sratio = 1;
    PetscFunctionReturn(0);
  }
  PetscCall(PetscBLASIntCast(m, &bm));
  PetscCall(PetscBLASIntCast(n, &bn));
  PetscCall(PetscArraycpy(A, D, m * n));
  PetscCall(PetscFPTrapPush(PETSC_FP_TRAP_OFF));
  PetscCallBLAS("LAPACKgesvd", LAPACKgesvd_("N", "A", &bm, &bn, A, &bm, s, &udummy, &one, VT, &bn, work, &lwork, &info));
  PetscCall(PetscFPTrapPop());
  PetscCheck(info == 0, PETSC_COMM_SELF, PETSC_ERR_LIB, "KFDenseNullSpace: the SVD of the %" PetscInt_FMT " x %" PetscInt_FMT " constraint matrix did not converge (LAPACK gesvd info %d)", m, n, (int)info);
  smax = s[0];
  PetscCheck(!PetscIsInfOrNanReal(smax), PETSC_COMM_SELF, PETSC_ERR_FP, "KFDenseNullSpace: the %" PetscInt_FMT " x %" PetscInt_FMT " constraint matrix has Inf or NaN entries: check the interface rows of the reduced bodies", m, n);
  if (smax > 0)
    while (r < ns && s[r] > rtol * smax) r++;
  /* N = the right singular vectors beyond the rank: rows r..n-1 of V^T, transposed */
  for (PetscInt j = 0; j < n - r; j++)
    for (PetscInt c = 0; c < n; c++) N[c + j * n] = VT[(r + j) + c * n];
  *h = n - r;
  if (rank) *rank = r;
  if (sratio) *sratio = r ? s[r - 1] / smax : 1;
  PetscFunctionReturn(0);
}

PetscErrorCode KFDenseNullSpace(PetscInt m, PetscInt n, const PetscReal D[], PetscReal rtol, PetscInt *h, PetscReal N[], PetscInt *rank, PetscReal *sratio)
{
  PetscBLASInt lwork;
  PetscReal   *A, *s, *VT, *work;

  PetscFunctionBegin;
  PetscCheck(m >= 0 && n >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFDenseNullSpace: negative size %" PetscInt_FMT " x %" PetscInt_FMT, m, n);
  PetscCall(KFDenseNullSpaceWorkSize_Private(m, n, &lwork));
  PetscCall(PetscMalloc4(m * n, &A, PetscMin(m, n), &s, n * n, &VT, lwork, &work));
  PetscCall(KFDenseNullSpace_Private(m, n, D, rtol, h, N, rank, sratio, A, s, VT, work, lwork));
  PetscCall(PetscFree4(A, s, VT, work));
  PetscFunctionReturn(0);
}
