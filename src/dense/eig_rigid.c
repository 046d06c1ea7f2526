/* Modes of a small pencil whose rigid-body and mechanism modes are known from geometry: the rigid modes as given
   (M-orthonormalized, eigenvalue exactly 0), the flexible ones from the pencil restricted to their M-orthogonal
   complement. An eigensolve of the whole pencil would blur a stiff model's rigid subspace into its softest flexible
   modes, and a frequency response built on those eigenvectors gets the rigid gain wrong (issue 12: 15 %). */
#include "dense_impl.h"
#include <petscblaslapack.h>

/* Reals of workspace KFDenseEigRigid_Private needs at n dofs and r rigid modes, and the LAPACK workspaces it is to be
   given: lsvd of the r x n SVD, leig of the (n - r)-dof eigensolve (n when r = 0) */
PetscErrorCode KFDenseEigRigidWorkSize_Private(PetscInt n, PetscInt r, PetscInt *size, PetscBLASInt *lsvd_out, PetscBLASInt *leig_out)
{
  PetscBLASInt lsvd, leig;

  PetscFunctionBegin;
  PetscCall(KFDenseNullSpaceWorkSize_Private(r, n, &lsvd));
  PetscCall(KFDenseEigWorkSize_Private(r ? n - r : n, &leig));
  if (lsvd_out) *lsvd_out = lsvd;
  if (leig_out) *leig_out = leig;
  /* Pr, MP, Gm, C, Q, W, Kq, Mq, V; the SVD's A, s, VT, work; the eigensolver's B, work */
  *size = 2 * n * r + r * r + r * n + 5 * n * n + (r * n + PetscMin(r, n) + n * n + lsvd) + (n * n + leig);
  PetscFunctionReturn(0);
}

/* KFDenseEigRigid in the caller's workspace (work: at least the size KFDenseEigRigidWorkSize_Private gives, with the
   lsvd and leig it gives at these n and r): no allocation */
PetscErrorCode KFDenseEigRigid_Private(PetscInt n, const PetscReal K[], const PetscReal M[], PetscInt r, const PetscReal Phir[], PetscReal lambda[], PetscReal Phi[], PetscReal work[], PetscBLASInt lsvd, PetscBLASInt leig)
{
  PetscReal   *Pr, *MP, *Gm, *C, *Q, *W, *Kq, *Mq, *V, *A, *s, *VT, *wsvd, *B, *weig;
  PetscInt     nq = 0;
  PetscBLASInt bp, info;

  PetscFunctionBegin;
  PetscCheck(n >= 1 && r >= 0 && r <= n, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFDenseEigRigid: bad sizes (n %" PetscInt_FMT ", r %" PetscInt_FMT ")", n, r);
  Pr   = work;
  MP   = Pr + n * r;
  Gm   = MP + n * r;
  C    = Gm + r * r;
  Q    = C + r * n;
  W    = Q + n * n;
  Kq   = W + n * n;
  Mq   = Kq + n * n;
  V    = Mq + n * n;
  A    = V + n * n;
  s    = A + r * n;
  VT   = s + PetscMin(r, n);
  wsvd = VT + n * n;
  B    = wsvd + lsvd;
  weig = B + n * n;
  if (!r) {
    PetscCall(KFDenseEig_Private(n, K, M, lambda, Phi, B, weig, leig));
    PetscFunctionReturn(0);
  }
  /* M-orthonormal rigid modes: Phi_r L^-T with M-Gram L L^T, twice */
  PetscCall(PetscArraycpy(Pr, Phir, n * r));
  PetscCall(PetscBLASIntCast(r, &bp));
  for (int pass = 0; pass < 2; pass++) {
    PetscCall(KFDenseGemm_Private('N', 'N', n, r, n, 1.0, M, n, Pr, n, 0.0, MP, n));
    PetscCall(KFDenseGemm_Private('T', 'N', r, r, n, 1.0, Pr, n, MP, n, 0.0, Gm, r));
    PetscCallBLAS("LAPACKpotrf", LAPACKpotrf_("L", &bp, Gm, &bp, &info));
    PetscCheck(!info, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG, "KFDenseEigRigid: the %" PetscInt_FMT " rigid-body and mechanism modes are linearly dependent in the M-inner product (LAPACK potrf info %d)", r, (int)info);
    for (PetscInt i = 0; i < n; i++)
      for (PetscInt j = 0; j < r; j++) {
        PetscReal v = Pr[i + j * n];
        for (PetscInt k = 0; k < j; k++) v -= Gm[j + k * r] * Pr[i + k * n];
        Pr[i + j * n] = v / Gm[j + j * r];
      }
  }
  PetscCall(KFDenseGemm_Private('N', 'N', n, r, n, 1.0, M, n, Pr, n, 0.0, MP, n));
  /* the flexible subspace: Q spans null((M Phi_r)^T), orthonormal (SVD) */
  for (PetscInt i = 0; i < r; i++)
    for (PetscInt j = 0; j < n; j++) C[i + j * r] = MP[j + i * n];
  PetscCall(KFDenseNullSpace_Private(r, n, C, 1e-12, &nq, Q, NULL, NULL, A, s, VT, wsvd, lsvd));
  PetscCheck(nq == n - r, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG, "KFDenseEigRigid: the M-complement of the %" PetscInt_FMT " rigid modes has dimension %" PetscInt_FMT ", expected %" PetscInt_FMT, r, nq, n - r);
  for (PetscInt i = 0; i < r; i++) lambda[i] = 0;
  PetscCall(PetscArraycpy(Phi, Pr, n * r));
  if (nq) {
    PetscCall(KFDenseGemm_Private('N', 'N', n, nq, n, 1.0, K, n, Q, n, 0.0, W, n));
    PetscCall(KFDenseGemm_Private('T', 'N', nq, nq, n, 1.0, Q, n, W, n, 0.0, Kq, nq));
    PetscCall(KFDenseGemm_Private('N', 'N', n, nq, n, 1.0, M, n, Q, n, 0.0, W, n));
    PetscCall(KFDenseGemm_Private('T', 'N', nq, nq, n, 1.0, Q, n, W, n, 0.0, Mq, nq));
    PetscCall(KFDenseSymmetrize_Private(nq, Kq));
    PetscCall(KFDenseSymmetrize_Private(nq, Mq));
    PetscCall(KFDenseEig_Private(nq, Kq, Mq, lambda + r, V, B, weig, leig));
    PetscCall(KFDenseGemm_Private('N', 'N', n, nq, nq, 1.0, Q, n, V, nq, 0.0, Phi + n * r, n));
  }
  PetscFunctionReturn(0);
}

PetscErrorCode KFDenseEigRigid(PetscInt n, const PetscReal K[], const PetscReal M[], PetscInt r, const PetscReal Phir[], PetscReal lambda[], PetscReal Phi[])
{
  PetscReal   *work;
  PetscInt     size;
  PetscBLASInt lsvd, leig;

  PetscFunctionBegin;
  PetscCheck(n >= 1 && r >= 0 && r <= n, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFDenseEigRigid: bad sizes (n %" PetscInt_FMT ", r %" PetscInt_FMT ")", n, r);
  PetscCall(KFDenseEigRigidWorkSize_Private(n, r, &size, &lsvd, &leig));
  PetscCall(PetscMalloc1(size, &work));
  PetscCall(KFDenseEigRigid_Private(n, K, M, r, Phir, lambda, Phi, work, lsvd, leig));
  PetscCall(PetscFree(work));
  PetscFunctionReturn(0);
}
