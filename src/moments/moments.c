#include <kryflex_impl.h>

/* L^k = H (K+ M)^k K+ G (eq. 5-6) by repeated flexible solves with the one factorization. */
PetscErrorCode KFFlexSolverMoments(KFFlexSolver solver, PetscInt nmom, PetscReal L[])
{
  KFSystem sys = KFFlexSolverSystem_Private(solver);
  KFScene  s   = sys->scene;
  PetscInt a = s->ninputs, t = s->noutputs;
  Mat      X, B;

  PetscFunctionBegin;
  PetscCall(KFFlexSolverSetUp(solver));
  PetscCall(PetscLogEventBegin(KF_EVENT_MOMENTS, 0, 0, 0, 0));
  PetscCall(MatDuplicate(sys->G, MAT_DO_NOT_COPY_VALUES, &X));
  PetscCall(KFFlexSolverApply(solver, sys->G, X));
  for (PetscInt k = 0; k < nmom; k++) {
    PetscReal *Lt;
    PetscCall(PetscMalloc1(t * a, &Lt));
    PetscCall(KFMatTransposeMatMultGather(sys->Ht, X, Lt)); /* (H^T)^T X: t x a */
    PetscCall(PetscArraycpy(&L[k * t * a], Lt, t * a));
    PetscCall(PetscFree(Lt));
    if (k + 1 == nmom) break;
    PetscCall(MatMatMult(sys->Ms, X, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &B));
    PetscCall(KFFlexSolverApply(solver, B, X));
    PetscCall(MatDestroy(&B));
  }
  PetscCall(MatDestroy(&X));
  PetscCall(PetscLogEventEnd(KF_EVENT_MOMENTS, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}
