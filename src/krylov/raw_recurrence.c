#include <kryflex_impl.h>

/* The paper's recurrence (eq. 9) without orthogonalization: kept only to show how fast its vectors lose
   independence (the condition number of their M-Gram matrix). Each column is scaled to unit 2-norm as it is made: the
   raw vectors shrink or grow like omega_1^(-2k), which overflows or underflows a double after a few hundred steps on a
   structure whose first mode is far from 1 rad/s, and a column's scale changes neither the span nor (columns are
   made unit below anyway) the Gram matrix' conditioning. */
PetscErrorCode KFKrylovRawBasis(KFFlexSolver solver, PetscInt nin, PetscInt nout, Mat *Praw, PetscReal *gram_cond)
{
  KFSystem   sys = KFFlexSolverSystem_Private(solver);
  KFScene    s   = sys->scene;
  PetscInt   a = s->ninputs, t = s->noutputs, c = a * nin + t * nout, col = 0, lda, ldw;
  PetscReal *Gm, *ev, *vecs, *Id;
  Mat        MP;

  PetscFunctionBegin;
  PetscCall(KFFlexSolverSetUp(solver));
  PetscCall(KFDenseCreate(s->comm, s->nsys_local, s->nsys, c, Praw));
  for (int source = 0; source < 2; source++) {
    Mat B = source ? sys->Ht : sys->G, W;
    for (PetscInt blk = 0; blk < (source ? nout : nin); blk++) {
      PetscScalar *w, *p;
      PetscReal   *norms;
      PetscInt     nl, q;
      PetscCall(MatDuplicate(B, MAT_DO_NOT_COPY_VALUES, &W));
      PetscCall(KFFlexSolverApply(solver, B, W));
      if (blk > 0) PetscCall(MatDestroy(&B));
      PetscCall(MatGetLocalSize(W, &nl, NULL));
      PetscCall(MatGetSize(W, NULL, &q));
      PetscCall(PetscMalloc1(q, &norms));
      PetscCall(MatGetColumnNorms(W, NORM_2, norms));
      PetscCall(MatDenseGetLDA(*Praw, &lda));
      PetscCall(MatDenseGetLDA(W, &ldw));
      PetscCall(MatDenseGetArray(W, &w));
      PetscCall(MatDenseGetArray(*Praw, &p));
      for (PetscInt j = 0; j < q; j++) {
        PetscReal scale = norms[j] > 0 ? 1.0 / norms[j] : 1.0; /* a zero column (an input K+ does not see) stays zero */
        for (PetscInt i = 0; i < nl; i++) p[i + (col + j) * lda] = w[i + j * ldw] *= scale;
      }
      PetscCall(MatDenseRestoreArray(*Praw, &p));
      PetscCall(MatDenseRestoreArray(W, &w));
      PetscCall(PetscFree(norms));
      col += q;
      PetscCall(MatMatMult(sys->Ms, W, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &B)); /* next: K+ M x_k */
      PetscCall(MatDestroy(&W));
    }
    if ((source ? nout : nin) > 0) PetscCall(MatDestroy(&B));
  }
  PetscCall(MatAssemblyBegin(*Praw, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*Praw, MAT_FINAL_ASSEMBLY));
  /* Gram matrix in the M-inner product and its eigenvalues */
  PetscCall(PetscMalloc4(c * c, &Gm, c, &ev, c * c, &vecs, c * c, &Id));
  PetscCall(MatMatMult(sys->Ms, *Praw, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &MP));
  PetscCall(KFMatTransposeMatMultGather(*Praw, MP, Gm));
  PetscCall(MatDestroy(&MP));
  /* unit columns first: the raw vectors shrink like omega_1^(-2k), and that scaling alone says nothing about rank */
  for (PetscInt j = 0; j < c; j++) ev[j] = 1.0 / PetscSqrtReal(Gm[j + j * c]);
  for (PetscInt j = 0; j < c; j++)
    for (PetscInt i = 0; i < c; i++) Gm[i + j * c] *= ev[i] * ev[j];
  for (PetscInt i = 0; i < c * c; i++) Id[i] = (i % (c + 1) == 0);
  PetscCall(KFDenseEig(c, Gm, Id, ev, vecs));
  /* once the smallest eigenvalue is lost in rounding the condition number is only known to exceed 1/eps */
  *gram_cond = ev[0] > c * PETSC_MACHINE_EPSILON * ev[c - 1] ? ev[c - 1] / ev[0] : 1.0 / PETSC_MACHINE_EPSILON;
  PetscCall(PetscFree4(Gm, ev, vecs, Id));
  PetscFunctionReturn(0);
}
