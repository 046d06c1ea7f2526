/* Modes of a small pencil whose rigid-body and mechanism modes are known from geometry: the rigid modes as given
   (M-orthonormalized, eigenvalue exactly 0), the flexible ones from the pencil restricted to their M-orthogonal
   complement. An eigensolve of the whole pencil would blur a stiff model's rigid subspace into its softest flexible
   modes, and a frequency response built on those eigenvectors gets the rigid gain wrong (issue 12: 15 %). */
#include "dense_impl.h"
#include <petscblaslapack.h>

PetscErrorCode KFDenseEigRigid(PetscInt n, const PetscReal K[], const PetscReal M[], PetscInt r, const PetscReal Phir[], PetscReal lambda[], PetscReal Phi[])
{
  PetscReal   *Pr, *MP, *Gm, *C, *Q, *W, *Kq, *Mq, *V;
  PetscInt     nq = 0;
  PetscBLASInt bp, info;

  PetscFunctionBegin;
  PetscCheck(n >= 1 && r >= 0 && r <= n, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFDenseEigRigid: bad sizes (n %" PetscInt_FMT ", r %" PetscInt_FMT ")", n, r);
  if (!r) {
    PetscCall(KFDenseEig(n, K, M, lambda, Phi));
    PetscFunctionReturn(0);
  }
  PetscCall(PetscMalloc5(n * r, &Pr, n * r, &MP, r * r, &Gm, r * n, &C, n * n, &Q));
  PetscCall(PetscMalloc4(n * n, &W, n * n, &Kq, n * n, &Mq, n * n, &V));
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
  PetscCall(KFDenseNullSpace(r, n, C, 1e-12, &nq, Q, NULL, NULL));
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
    PetscCall(KFDenseEig(nq, Kq, Mq, lambda + r, V));
    PetscCall(KFDenseGemm_Private('N', 'N', n, nq, nq, 1.0, Q, n, V, nq, 0.0, Phi + n * r, n));
  }
  PetscCall(PetscFree5(Pr, MP, Gm, C, Q));
  PetscCall(PetscFree4(W, Kq, Mq, V));
  PetscFunctionReturn(0);
}
