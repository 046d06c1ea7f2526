#include <kryflex_impl.h>

/* A parallel dense matrix with the given local row count (the row layout of the system or a body). */
PetscErrorCode KFDenseCreate(MPI_Comm comm, PetscInt nlocal, PetscInt N, PetscInt ncols, Mat *A)
{
  PetscFunctionBegin;
  PetscCall(MatCreateDense(comm, nlocal, PETSC_DECIDE, N, ncols, NULL, A));
  PetscCall(MatAssemblyBegin(*A, MAT_FINAL_ASSEMBLY)); /* zero-filled and usable as an operand at once */
  PetscCall(MatAssemblyEnd(*A, MAT_FINAL_ASSEMBLY));
  PetscFunctionReturn(0);
}

/* Every rank gets the whole (small) matrix, column-major: its rows are spread over the ranks. */
PetscErrorCode KFDenseGather(Mat A, PetscReal out[])
{
  PetscInt           m, n, rstart, rend, lda, i, j;
  const PetscScalar *a;
  PetscReal         *buf;
  MPI_Comm           comm;

  PetscFunctionBegin;
  PetscCall(PetscObjectGetComm((PetscObject)A, &comm));
  PetscCall(MatGetSize(A, &m, &n));
  PetscCall(MatGetOwnershipRange(A, &rstart, &rend));
  PetscCall(MatDenseGetLDA(A, &lda));
  PetscCall(PetscCalloc1(m * n, &buf));
  PetscCall(MatDenseGetArrayRead(A, &a));
  for (j = 0; j < n; j++)
    for (i = rstart; i < rend; i++) buf[i + j * m] = PetscRealPart(a[(i - rstart) + j * lda]);
  PetscCall(MatDenseRestoreArrayRead(A, &a));
  PetscCall(MPIU_Allreduce(buf, out, (PetscMPIInt)(m * n), MPIU_REAL, MPIU_SUM, comm));
  PetscCall(PetscFree(buf));
  PetscFunctionReturn(0);
}

/* A^T B for tall dense A (N x p) and B (N x q) with the same row layout: local products summed over ranks. */
PetscErrorCode KFMatTransposeMatMultGather(Mat A, Mat B, PetscReal out[])
{
  PetscInt           nl, p, q, i, j, k, lda, ldb;
  const PetscScalar *a, *b;
  PetscReal         *buf;
  MPI_Comm           comm;

  PetscFunctionBegin;
  PetscCall(PetscObjectGetComm((PetscObject)A, &comm));
  PetscCall(MatGetLocalSize(A, &nl, NULL));
  PetscCall(MatGetSize(A, NULL, &p));
  PetscCall(MatGetSize(B, NULL, &q));
  PetscCall(MatDenseGetLDA(A, &lda));
  PetscCall(MatDenseGetLDA(B, &ldb));
  PetscCall(PetscCalloc1(p * q, &buf));
  PetscCall(MatDenseGetArrayRead(A, &a));
  PetscCall(MatDenseGetArrayRead(B, &b));
  for (j = 0; j < q; j++)
    for (i = 0; i < p; i++) {
      PetscReal s = 0;
      for (k = 0; k < nl; k++) s += PetscRealPart(a[k + i * lda] * b[k + j * ldb]);
      buf[i + j * p] = s;
    }
  PetscCall(MatDenseRestoreArrayRead(A, &a));
  PetscCall(MatDenseRestoreArrayRead(B, &b));
  PetscCall(MPIU_Allreduce(buf, out, (PetscMPIInt)(p * q), MPIU_REAL, MPIU_SUM, comm));
  PetscCall(PetscFree(buf));
  PetscFunctionReturn(0);
}

/* X += alpha A c for tall dense A (N x r), X (N x p) with the same row layout and a small replicated c (r x p) */
PetscErrorCode KFDenseMultSmall(Mat A, PetscInt r, PetscInt p, const PetscReal c[], PetscReal alpha, Mat X)
{
  PetscInt           nl, lda, ldx;
  const PetscScalar *a;
  PetscScalar       *x;

  PetscFunctionBegin;
  PetscCall(MatGetLocalSize(A, &nl, NULL));
  PetscCall(MatDenseGetLDA(A, &lda));
  PetscCall(MatDenseGetLDA(X, &ldx));
  PetscCall(MatDenseGetArrayRead(A, &a));
  PetscCall(MatDenseGetArray(X, &x));
  for (PetscInt j = 0; j < p; j++)
    for (PetscInt k = 0; k < r; k++) {
      PetscReal ck = alpha * c[k + j * r];
      if (ck == 0) continue;
      for (PetscInt i = 0; i < nl; i++) x[i + j * ldx] += ck * a[i + k * lda];
    }
  PetscCall(MatDenseRestoreArrayRead(A, &a));
  PetscCall(MatDenseRestoreArray(X, &x));
  PetscFunctionReturn(0);
}

PetscErrorCode KFMatCombine(Mat X, PetscInt m, const PetscReal C[], Mat *Y)
{
  PetscInt nl, N, p;

  PetscFunctionBegin;
  PetscCall(MatGetLocalSize(X, &nl, NULL));
  PetscCall(MatGetSize(X, &N, &p));
  PetscCall(KFDenseCreate(PetscObjectComm((PetscObject)X), nl, N, m, Y));
  PetscCall(KFDenseMultSmall(X, p, m, C, 1.0, *Y));
  PetscFunctionReturn(0);
}

PetscErrorCode KFMatInner(Mat A, Mat B, PetscReal out[])
{
  PetscFunctionBegin;
  PetscCall(KFMatTransposeMatMultGather(A, B, out));
  PetscFunctionReturn(0);
}
