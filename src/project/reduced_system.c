#include <kryflex_impl.h>

/* The reduced system of eq. (10-11) on the basis V: Mr = V^T M V, Kr = V^T K V, Gr = V^T G, Hr = H V. */
PetscErrorCode KFSystemProject(KFSystem sys, BV V, PetscReal Mr[], PetscReal Kr[], PetscReal Gr[], PetscReal Hr[])
{
  PetscFunctionBegin;
  PetscCall(KFSystemProjectGram_Private(sys, V, NULL, Mr, Kr, Gr, Hr));
  PetscFunctionReturn(0);
}

/* The same with V^T M V given when the caller has it (the Krylov basis' health check formed it: a product of M with
   the whole basis saved), else formed here */
PetscErrorCode KFSystemProjectGram_Private(KFSystem sys, BV V, const PetscReal gram[], PetscReal Mr[], PetscReal Kr[], PetscReal Gr[], PetscReal Hr[])
{
  Mat        Vd, AV;
  PetscInt   l, c, t = sys->scene->noutputs;
  PetscReal *HtV;

  PetscFunctionBegin;
  PetscCall(PetscLogEventBegin(KF_EVENT_PROJECT, 0, 0, 0, 0));
  PetscCall(BVGetActiveColumns(V, &l, &c));
  PetscCall(BVGetMat(V, &Vd));
  if (gram) PetscCall(PetscArraycpy(Mr, gram, (c - l) * (c - l)));
  else {
    PetscCall(KFMatMultDense(sys->Ms, Vd, &AV));
    PetscCall(KFMatTransposeMatMultGather(Vd, AV, Mr));
    PetscCall(MatDestroy(&AV));
  }
  PetscCall(KFMatMultExtended(sys->Ks, Vd, &AV)); /* soft Krylov vectors: K V without K's rounding */
  PetscCall(KFMatTransposeMatMultGather(Vd, AV, Kr));
  PetscCall(MatDestroy(&AV));
  PetscCall(KFMatTransposeMatMultGather(Vd, sys->G, Gr));
  PetscCall(PetscMalloc1(c * t, &HtV));
  PetscCall(KFMatTransposeMatMultGather(Vd, sys->Ht, HtV)); /* c x t */
  for (PetscInt i = 0; i < t; i++)
    for (PetscInt j = 0; j < c; j++) Hr[i + j * t] = HtV[j + i * c];
  PetscCall(PetscFree(HtV));
  PetscCall(BVRestoreMat(V, &Vd));
  PetscCall(PetscLogEventEnd(KF_EVENT_PROJECT, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

PetscErrorCode KFBVCombine(BV V, PetscInt m, const PetscReal C[], Mat *X)
{
  Mat      Vd;
  PetscInt l, c, nl, N;

  PetscFunctionBegin;
  PetscCall(BVGetActiveColumns(V, &l, &c));
  PetscCall(BVGetMat(V, &Vd));
  PetscCall(MatGetLocalSize(Vd, &nl, NULL));
  PetscCall(MatGetSize(Vd, &N, NULL));
  PetscCall(KFDenseCreate(PetscObjectComm((PetscObject)Vd), nl, N, m, X));
  PetscCall(MatZeroEntries(*X));
  PetscCall(KFDenseMultSmall(Vd, c - l, m, C, 1.0, *X));
  PetscCall(BVRestoreMat(V, &Vd));
  PetscFunctionReturn(0);
}
