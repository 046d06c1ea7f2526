/* Private helpers of the small dense algebra stage (src/dense); not part of the public API. */
#ifndef KRYFLEX_DENSE_IMPL_H
#define KRYFLEX_DENSE_IMPL_H

#include <kryflex.h>

/* C = alpha op(A) op(B) + beta C with PetscInt sizes; quick return on empty C; tolerant of zero
   leading dimensions (BLAS rejects ld < 1 even when the matrix is empty). */
PETSC_INTERN PetscErrorCode KFDenseGemm_Private(char transa, char transb, PetscInt m, PetscInt n, PetscInt k, PetscReal alpha, const PetscReal A[], PetscInt lda, const PetscReal B[], PetscInt ldb, PetscReal beta, PetscReal C[], PetscInt ldc);
/* A = (A + A^T) / 2 for an n x n array */
PETSC_INTERN PetscErrorCode KFDenseSymmetrize_Private(PetscInt n, PetscReal A[]);
/* Error unless max |A_ij - A_ji| <= rtol max |A_ij|: catches transposed or unrelated arrays, not rounding. */
PETSC_INTERN PetscErrorCode KFDenseCheckSymmetric_Private(PetscInt n, const PetscReal A[], const char what[], const char caller[]);
/* Largest eigenvalue, and whether mode i is flexible: lambda_i > rigid_tol * max(lambda) and lambda_i > 0 */
PETSC_INTERN PetscReal KFDenseMaxReal_Private(PetscInt n, const PetscReal x[]);
PETSC_INTERN PetscBool KFDenseIsFlexible_Private(PetscReal lambda, PetscReal lmax, PetscReal rigid_tol);
/* Singular values (min(m, n), descending) of A (m x n, overwritten) by LAPACK gesvd without vectors; caller names the
   function in the error message. In hankel.c, its main user. */
PETSC_INTERN PetscErrorCode KFDenseSingularValues_Private(PetscInt m, PetscInt n, PetscReal A[], PetscReal s[], const char caller[]);

/* Workspace variants of KFDenseNullSpace, KFDenseEig and KFDenseEigRigid (the public ones allocate and call them):
   no allocation, for reassembly inside a time integration (KFReassembly). Each is given exactly the LAPACK workspace
   queried at its size (the caller queries once, not per call), so the results are those of the allocating versions. */
PETSC_INTERN PetscErrorCode KFDenseNullSpaceWorkSize_Private(PetscInt m, PetscInt n, PetscBLASInt *lwork);
PETSC_INTERN PetscErrorCode KFDenseNullSpace_Private(PetscInt m, PetscInt n, const PetscReal D[], PetscReal rtol, PetscInt *h, PetscReal N[], PetscInt *rank, PetscReal *sratio, PetscReal A[], PetscReal s[], PetscReal VT[], PetscReal work[], PetscBLASInt lwork);
PETSC_INTERN PetscErrorCode KFDenseEigWorkSize_Private(PetscInt n, PetscBLASInt *lwork);
PETSC_INTERN PetscErrorCode KFDenseEig_Private(PetscInt n, const PetscReal K[], const PetscReal M[], PetscReal lambda[], PetscReal Phi[], PetscReal B[], PetscReal work[], PetscBLASInt lwork);
PETSC_INTERN PetscErrorCode KFDenseEigRigidWorkSize_Private(PetscInt n, PetscInt r, PetscInt *size, PetscBLASInt *lsvd, PetscBLASInt *leig);
PETSC_INTERN PetscErrorCode KFDenseEigRigid_Private(PetscInt n, const PetscReal K[], const PetscReal M[], PetscInt r, const PetscReal Phir[], PetscReal lambda[], PetscReal Phi[], PetscReal work[], PetscBLASInt lsvd, PetscBLASInt leig);

/* A (m x m, symmetric, overwritten) = W diag(lambda) W^T by Cholesky and LAPACK's one-sided Jacobi SVD (gesvj), each
   eigenvalue to a few eps of itself where A is positive definite and nearly diagonal; lambda ascending (eig_jacobi.c) */
PETSC_INTERN PetscErrorCode KFDenseEigJacobi_Private(PetscInt m, PetscReal A[], PetscReal lambda[], PetscReal W[]);

/* Tolerance of KFDenseCheckSymmetric_Private for input pencils */
#define KF_DENSE_SYMMETRY_RTOL 1e-6

/* two unit vectors spanning the plane perpendicular to a unit joint axis (joint_rotation.c) */
PETSC_INTERN void           KFPerpendicularPair_Private(const PetscReal k[3], PetscReal e1[3], PetscReal e2[3]);

/* Gram-Schmidt twice (classical, against the columns kept before it) of the p columns of X (m x p, column-major, in
   place, Euclidean), in order; a column is dropped when its remainder's norm is not above tol n0, n0 its norm before
   any orthogonalization: nrm0[j] when given (the caller measured it in another inner product), else computed here.
   Zero columns are dropped. The kept columns are moved to the front; *kept: their number. (small_kernels.c) */
PETSC_INTERN PetscErrorCode KFDenseOrthonormalizeSmall_Private(PetscInt m, PetscInt p, PetscReal X[], const PetscReal nrm0[], PetscReal tol, PetscInt *kept);
/* T = A^T S B (l x l, leading dimension l) accumulated in long double, S v x v, A and B v x l with leading dimensions
   lda, ldb; X: v x l of long double workspace (holds S B after). A reduced body keeps its stiff modes, and its soft
   directions' stiffness is a small difference of their large terms. (small_kernels.c) */
PETSC_INTERN void KFDenseCongruenceL_Private(PetscInt v, PetscInt l, const PetscReal S[], const PetscReal A[], PetscInt lda, const PetscReal B[], PetscInt ldb, long double X[], long double T[]);

#endif
