#include <kryflex_impl.h>

/* A statically determinate set of held dofs: r dofs on which the rigid modes are independent, chosen by
   QR with column pivoting of Phi^T (each step takes the dof whose row of Phi has the largest part not yet
   spanned). Holding them removes every rigid and mechanism motion, so K with those rows and columns replaced by
   the identity is positive definite when the declared modes are all of K's null space. */
PETSC_INTERN PetscErrorCode KFSelectHeldDofs(Mat Phi, PetscInt *nheld, PetscInt **held)
{
  PetscInt           nl, r, lda, rstart;
  const PetscScalar *a;
  PetscReal         *W, *q;
  MPI_Comm           comm;
  PetscMPIInt        rank;

  PetscFunctionBegin;
  PetscCall(PetscObjectGetComm((PetscObject)Phi, &comm));
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCall(MatGetLocalSize(Phi, &nl, NULL));
  PetscCall(MatGetSize(Phi, NULL, &r));
  PetscCall(MatGetOwnershipRange(Phi, &rstart, NULL));
  PetscCall(MatDenseGetLDA(Phi, &lda));
  PetscCall(PetscMalloc2(nl * r + 1, &W, r, &q));
  PetscCall(PetscMalloc1(r, held));
  PetscCall(MatDenseGetArrayRead(Phi, &a));
  for (PetscInt i = 0; i < nl; i++) /* row-major copy: one r-vector per dof */
    for (PetscInt k = 0; k < r; k++) W[i * r + k] = PetscRealPart(a[i + k * lda]);
  PetscCall(MatDenseRestoreArrayRead(Phi, &a));
  for (PetscInt step = 0; step < r; step++) {
    struct {
      PetscReal v;
      PetscInt  i;
    } loc = {-1.0, -1}, glob;
    PetscReal nrm;
    PetscInt  owner_row;
    for (PetscInt i = 0; i < nl; i++) {
      PetscReal s = 0;
      for (PetscInt k = 0; k < r; k++) s += W[i * r + k] * W[i * r + k];
      if (s > loc.v) {
        loc.v = s;
        loc.i = rstart + i;
      }
    }
    PetscCallMPI(MPI_Allreduce(&loc, &glob, 1, MPIU_REAL_INT, MPI_MAXLOC, comm));
    PetscCheck(glob.v > 0, comm, PETSC_ERR_ARG_WRONG, "the rigid-body modes are linearly dependent: cannot find %" PetscInt_FMT " dofs to hold", r);
    owner_row = glob.i - rstart;
    for (PetscInt k = 0; k < r; k++) q[k] = (owner_row >= 0 && owner_row < nl) ? W[owner_row * r + k] : 0;
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, q, (PetscMPIInt)r, MPIU_REAL, MPIU_SUM, comm));
    nrm = PetscSqrtReal(glob.v);
    for (PetscInt k = 0; k < r; k++) q[k] /= nrm;
    for (PetscInt i = 0; i < nl; i++) {
      PetscReal d = 0;
      for (PetscInt k = 0; k < r; k++) d += W[i * r + k] * q[k];
      for (PetscInt k = 0; k < r; k++) W[i * r + k] -= d * q[k];
    }
    (*held)[step] = glob.i;
  }
  *nheld = r;
  PetscCall(PetscFree2(W, q));
  PetscFunctionReturn(0);
}
