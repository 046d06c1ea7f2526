/* The reducer's damping: the description both the full-order reference and the reduced models use, its equivalent
   ratio for the grid and the importance, and the bodies' viscous matrices in full-order modal coordinates. */
#include <kryflex/reducerimpl.h>

PetscErrorCode KFReducerDampingUpdate_Private(KFReducer r)
{
  PetscFunctionBegin;
  PetscCall(KFDampingEffectiveRatio(&r->damping, r->band, &r->zeta));
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerSetDampingModel(KFReducer r, const KFDamping *d)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscValidPointer(d, 2);
  PetscCall(KFDampingCheck(PetscObjectComm((PetscObject)r), d));
  r->damping = *d;
  PetscCall(KFReducerDampingUpdate_Private(r));
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerGetDampingModel(KFReducer r, KFDamping *d)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscValidPointer(d, 2);
  *d = r->damping;
  PetscFunctionReturn(0);
}

/* X^T (sum_b P_b^T C_b P_b) X, body by body: the system's damping matrix is never assembled */
PetscErrorCode KFSystemProjectDamping_Private(KFSystem sys, Mat X, PetscBool *has, PetscReal Cm[])
{
  KFScene   s = sys->scene;
  PetscInt  m;
  PetscReal *part;

  PetscFunctionBegin;
  *has = PETSC_FALSE;
  for (PetscInt b = 0; b < s->nb; b++)
    if (s->bodies[b].C) *has = PETSC_TRUE;
  if (!*has) PetscFunctionReturn(0);
  PetscCall(MatGetSize(X, NULL, &m));
  PetscCall(PetscArrayzero(Cm, m * m));
  PetscCall(PetscMalloc1(PetscMax(m * m, 1), &part));
  for (PetscInt b = 0; b < s->nb; b++) {
    Mat Xb, CX;

    if (!s->bodies[b].C) continue;
    PetscCall(MatMatMult(sys->P[b], X, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &Xb));
    PetscCall(MatMatMult(s->bodies[b].C, Xb, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &CX));
    PetscCall(KFMatTransposeMatMultGather(Xb, CX, part));
    for (PetscInt e = 0; e < m * m; e++) Cm[e] += part[e];
    PetscCall(MatDestroy(&CX));
    PetscCall(MatDestroy(&Xb));
  }
  for (PetscInt i = 0; i < m; i++)
    for (PetscInt j = 0; j < i; j++) Cm[i + j * m] = Cm[j + i * m] = 0.5 * (Cm[i + j * m] + Cm[j + i * m]);
  PetscCall(PetscFree(part));
  PetscFunctionReturn(0);
}
