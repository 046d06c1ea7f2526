/* Null space of a small constraint matrix by SVD (eq. 21-22), with a relative rank tolerance. */
#include "dense_impl.h"
#include <petscblaslapack.h> /* after the PETSc headers it relies on */

PetscErrorCode KFDenseNullSpace(PetscInt m, PetscInt n, const PetscReal D[], PetscReal rtol, PetscInt *h, PetscReal N[], PetscInt *rank, PetscReal *sratio)
{
  PetscBLASInt bm, bn, one = 1, lwork = -1, info = 0;
  PetscReal   *A, *s, *VT, *work, wquery = 0, udummy = 0, smax;
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
  PetscCall(PetscMalloc3(m * n, &A, ns, &s, n * n, &VT));
  PetscCall(PetscArraycpy(A, D, m * n));
  PetscCall(PetscFPTrapPush(PETSC_FP_TRAP_OFF));
  PetscCallBLAS("LAPACKgesvd", LAPACKgesvd_("N", "A", &bm, &bn, A, &bm, s, &udummy, &one, VT, &bn, &wquery, &lwork, &info));
  lwork = (PetscBLASInt)wquery;
  lwork = PetscMax(lwork, PetscMax(3 * PetscMin(bm, bn) + PetscMax(bm, bn), 5 * PetscMin(bm, bn)));
  PetscCall(PetscMalloc1(lwork, &work));
  PetscCallBLAS("LAPACKgesvd", LAPACKgesvd_("N", "A", &bm, &bn, A, &bm, s, &udummy, &one, VT, &bn, work, &lwork, &info));
  PetscCall(PetscFPTrapPop());
  PetscCall(PetscFree(work));
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
  PetscCall(PetscFree3(A, s, VT));
  PetscFunctionReturn(0);
}
