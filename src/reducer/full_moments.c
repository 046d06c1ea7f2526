/*
  The full-order moments L^k = H (K+ M)^k K+ G at a configuration: the verification's reference takes the first two
  (the residual of the modes it does not compute), the moment checks all of them.

  They are the reference a reduced model's moments are measured against, so each block solve is refined to the
  factor's floor (KFFlexSolverApplyRefined) whatever its first residual: the Krylov basis's own solves, refined only
  above -kf_refine_rtol, keep about eps * cond of K+ G in error, and a reference that carried that would charge it to
  the model (Galileo at one angle, a deflated basis: its static moment error read 1.07e-10 against moments solved
  unrefined, 1.9e-12 against refined ones; a dense NumPy L^0 of the same ties is within 6e-14 of the refined ones
  and 2e-12 of the model).

  Where the configuration's Krylov basis V matches them exactly, L^k for k >= 1 are its own: the plain block
  recurrence with nothing deflated spans K+ G, ..., (K+ M)^(q-1) K+ G and K+ H^T, ..., so the projected pencil
  (Kr = V^T K V, Mr = V^T M V) has the full order's moments for k < q + p (Galerkin on a symmetric pencil: q + p
  moments), to the block solves' accuracy; L^k = Hr Phi Lambda^-(k+1) Phi^T Gr from the basis's own small
  eigenproblem, no solve. L^0 is solved for even then (one refined block): a model holds that same basis, so against
  the basis's L^0 its static moment would share the basis's solve error and show only its projection's rounding.
  Otherwise (a deflated, damped or raw basis, no basis at a midpoint, or -kf_full_moments asking for the solves) every
  moment is solved for, one block per moment with the configuration's flexible solver.

  Either way K+ P^T G, the first (refined) solve, is left for the reference check, whose first step it is
  (src/verify/refined_check.c).
*/
#include <kryflex/reducerimpl.h>
#include <kryflex/flexsolverimpl.h> /* KFFlexSolverApplyRefined */

/* from the basis: L (nmom blocks of t x a); *done false when its pencil is not definite */
static PetscErrorCode KFBasisMoments(const KFReducerBasis *basis, PetscInt t, PetscInt a, PetscInt nmom, PetscReal L[], PetscBool *done)
{
  const PetscInt c = basis->size;
  PetscReal     *HPhi, *PhiG;

  PetscFunctionBegin;
  *done = PETSC_FALSE;
  for (PetscInt m = 0; m < c; m++)
    if (!(basis->lambda[m] > 0)) PetscFunctionReturn(0);
  PetscCall(PetscCalloc2(t * c, &HPhi, c * a, &PhiG));
  for (PetscInt m = 0; m < c; m++) { /* Hr Phi (t x c) and Phi^T Gr (c x a) */
    const PetscReal *phi = basis->Phi + m * c;

    for (PetscInt l = 0; l < c; l++) {
      for (PetscInt i = 0; i < t; i++) HPhi[i + m * t] += basis->Hr[i + l * t] * phi[l];
      for (PetscInt j = 0; j < a; j++) PhiG[m + j * c] += phi[l] * basis->Gr[l + j * c];
    }
  }
  PetscCall(PetscArrayzero(L, nmom * t * a));
  for (PetscInt k = 0; k < nmom; k++) {
    for (PetscInt j = 0; j < a; j++)
      for (PetscInt m = 0; m < c; m++) PhiG[m + j * c] /= basis->lambda[m];
    for (PetscInt j = 0; j < a; j++)
      for (PetscInt m = 0; m < c; m++)
        for (PetscInt i = 0; i < t; i++) L[k * t * a + i + j * t] += HPhi[i + m * t] * PhiG[m + j * c];
  }
  PetscCall(PetscFree2(HPhi, PhiG));
  *done = PETSC_TRUE;
  PetscFunctionReturn(0);
}

/* by refined solves: X = K+ G, then X <- K+ M X, L^k = H X; kg (or NULL): the first X */
static PetscErrorCode KFSolvedMoments(KFFlexSolver solver, PetscInt t, PetscInt a, PetscInt nmom, PetscReal L[], Mat *kg)
{
  KFSystem   sys = KFFlexSolverSystem_Private(solver);
  Mat        X, B;
  PetscReal *Lt;

  PetscFunctionBegin;
  PetscCall(KFFlexSolverSetUp(solver));
  PetscCall(PetscLogEventBegin(KF_EVENT_MOMENTS, 0, 0, 0, 0));
  PetscCall(PetscMalloc1(PetscMax(t * a, 1), &Lt));
  PetscCall(MatConvert(sys->G, MATDENSE, MAT_INITIAL_MATRIX, &X));
  PetscCall(KFFlexSolverApplyRefined(solver, sys->G, X));
  if (kg) PetscCall(MatDuplicate(X, MAT_COPY_VALUES, kg));
  for (PetscInt k = 0; k < nmom; k++) {
    PetscCall(KFMatTransposeMatMultGather(sys->Ht, X, Lt)); /* (H^T)^T X: t x a */
    PetscCall(PetscArraycpy(&L[k * t * a], Lt, t * a));
    if (k + 1 == nmom) break;
    PetscCall(KFMatMultDense(sys->Ms, X, &B));
    PetscCall(KFFlexSolverApplyRefined(solver, B, X));
    PetscCall(MatDestroy(&B));
  }
  PetscCall(MatDestroy(&X));
  PetscCall(PetscFree(Lt));
  PetscCall(PetscLogEventEnd(KF_EVENT_MOMENTS, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerPointMoments_Private(KFReducer r, const KFReducerBasis *basis, KFFlexSolver solver, PetscInt nmom, PetscReal L[], Mat *kg)
{
  PetscInt  a, t;
  PetscBool done = PETSC_FALSE;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, NULL, NULL, &a, &t));
  if (kg) PetscCall(MatDestroy(kg));
  /* -kf_full_moments asked for explicitly: the solves, the moment checks' independent reference */
  if (basis && basis->data && basis->nmoments >= nmom && !(r->full_moments_set && r->full_moments)) PetscCall(KFBasisMoments(basis, t, a, nmom, L, &done));
  PetscCall(KFSolvedMoments(solver, t, a, done ? 1 : nmom, L, kg)); /* from the basis: L^0 (and K+ P^T G) solved */
  PetscCall(PetscInfo(r, "full-order moments (%" PetscInt_FMT ") %s\n", nmom, done ? "L^0 by a refined block solve, the others from the configuration's Krylov basis" : "by refined block solves"));
  PetscFunctionReturn(0);
}
