#include <kryflex_impl.h>

PETSC_INTERN PetscErrorCode KFSystemBuildBodyMaps(KFSystem);
PETSC_INTERN PetscErrorCode KFSystemBuildFrames(KFSystem);
PETSC_INTERN PetscErrorCode KFSystemSumBodies(KFSystem, PetscBool mass, Mat *S);

PetscErrorCode KFSystemCreate(KFScene s, KFSystem *sys)
{
  KFSystem y;

  PetscFunctionBegin;
  PetscCall(KFSceneSetUp(s));
  PetscCall(PetscNew(&y));
  y->refct = 1;
  PetscCall(PetscObjectReference((PetscObject)s)); /* the scene lives as long as the system */
  y->scene = s;
  y->nb    = s->nb;
  y->nconfig = 1;
  PetscCall(PetscCalloc1(PetscMax(s->nrevolute, 1), &y->angles));
  PetscCall(PetscCalloc3(s->nb, &y->Q, s->nb, &y->o, s->nb, &y->P));
  *sys = y;
  PetscFunctionReturn(0);
}

PetscErrorCode KFSystemDestroy(KFSystem *sys)
{
  KFSystem y = *sys;

  PetscFunctionBegin;
  if (!y) PetscFunctionReturn(0);
  *sys = NULL;
  if (--y->refct > 0) PetscFunctionReturn(0);
  for (PetscInt b = 0; b < y->nb; b++) PetscCall(MatDestroy(&y->P[b]));
  PetscCall(PetscFree3(y->Q, y->o, y->P));
  PetscCall(PetscFree(y->angles));
  PetscCall(MatDestroy(&y->Ms));
  PetscCall(MatDestroy(&y->Ks));
  PetscCall(MatDestroy(&y->G));
  PetscCall(MatDestroy(&y->Ht));
  PetscCall(MatDestroy(&y->Phi));
  PetscCall(MatDestroy(&y->MPhi));
  PetscCall(MatDestroy(&y->KPhi));
  PetscCall(KFBodyFactorsDestroy(&y->bodyf));
  for (int m = 0; m < 2; m++) PetscCall(PetscFree3(y->sumvar[m], y->sumbodyid[m], y->sumbodystate[m]));
  PetscCall(KFSceneDestroy(&y->scene)); /* drops the system's reference */
  PetscCall(PetscFree(y));
  PetscFunctionReturn(0);
}

/* one more holder: KFSystemDestroy frees the system when the last one lets it go (PetscObjectReference's idiom) */
PetscErrorCode KFSystemReference(KFSystem y)
{
  PetscFunctionBegin;
  PetscValidPointer(y, 1);
  y->refct++;
  PetscFunctionReturn(0);
}

/* sum_b P_b^T X_b for the bodies' dense G_b or H_b^T */
static PetscErrorCode KFSystemSumPtX(KFSystem y, PetscBool inputs, Mat *S)
{
  KFScene s = y->scene;

  PetscFunctionBegin;
  PetscCall(MatDestroy(S));
  for (PetscInt b = 0; b < s->nb; b++) {
    Mat X = inputs ? s->bodies[b].G : s->bodies[b].Ht, T;
    PetscCall(MatTransposeMatMult(y->P[b], X, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &T));
    if (!*S) *S = T;
    else {
      PetscCall(MatAXPY(*S, 1.0, T, SAME_NONZERO_PATTERN));
      PetscCall(MatDestroy(&T));
    }
  }
  PetscFunctionReturn(0);
}

PetscErrorCode KFSystemSetConfigurationCount(KFSystem y, PetscInt n)
{
  PetscFunctionBegin;
  PetscCheck(n >= 1, y->scene->comm, PETSC_ERR_ARG_OUTOFRANGE, "a system is solved at one configuration or more; got %" PetscInt_FMT, n);
  y->nconfig = n;
  PetscFunctionReturn(0);
}

PetscErrorCode KFSystemSetAngles(KFSystem y, const PetscReal angles[])
{
  KFScene s = y->scene;

  PetscFunctionBegin;
  PetscCall(PetscLogEventBegin(KF_EVENT_ASSEMBLE, 0, 0, 0, 0));
  for (PetscInt r = 0; r < s->nrevolute; r++) {
    PetscCheck(PetscIsNormalReal(angles[r]) || angles[r] == 0, s->comm, PETSC_ERR_ARG_WRONG, "angle %" PetscInt_FMT " is not a finite number", r);
    y->angles[r] = angles[r];
  }
  PetscCall(KFSystemBuildFrames(y));
  PetscCall(KFSystemBuildBodyMaps(y));
  PetscCall(KFSystemSumBodies(y, PETSC_TRUE, &y->Ms)); /* src/assemble/sum.c: P_b^T A_b P_b without products */
  PetscCall(KFSystemSumBodies(y, PETSC_FALSE, &y->Ks));
  PetscCall(KFSystemSumPtX(y, PETSC_TRUE, &y->G));
  PetscCall(KFSystemSumPtX(y, PETSC_FALSE, &y->Ht));
  PetscCall(MatSetOption(y->Ms, MAT_SYMMETRIC, PETSC_TRUE));
  PetscCall(MatSetOption(y->Ks, MAT_SYMMETRIC, PETSC_TRUE));
  y->assembled = PETSC_TRUE;
  PetscCall(MatDestroy(&y->Phi)); /* rigid modes depend on the angles: set or compute them again */
  PetscCall(MatDestroy(&y->MPhi));
  PetscCall(MatDestroy(&y->KPhi));
  y->user_rigid = PETSC_FALSE;
  PetscCall(PetscLogEventEnd(KF_EVENT_ASSEMBLE, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

/* The angles alone, nothing assembled: what the body-wise interface problem reads (KFSystemInterfaceExprs), for the
   certificate's counts at every configuration, which need no assembled matrix (src/reducer/certify.c). The system
   is unassembled until KFSystemSetAngles: anything that needs its matrices or rigid modes refuses it until then. */
PETSC_INTERN PetscErrorCode KFSystemSetInterfaceAngles(KFSystem y, const PetscReal angles[])
{
  KFScene s = y->scene;

  PetscFunctionBegin;
  for (PetscInt r = 0; r < s->nrevolute; r++) {
    PetscCheck(PetscIsNormalReal(angles[r]) || angles[r] == 0, s->comm, PETSC_ERR_ARG_WRONG, "angle %" PetscInt_FMT " is not a finite number", r);
    y->angles[r] = angles[r];
  }
  y->assembled = PETSC_FALSE;
  PetscCall(MatDestroy(&y->Phi));
  PetscCall(MatDestroy(&y->MPhi));
  PetscCall(MatDestroy(&y->KPhi));
  y->user_rigid = PETSC_FALSE;
  PetscFunctionReturn(0);
}

PetscErrorCode KFSystemGetMatrices(KFSystem y, Mat *Ms, Mat *Ks, Mat *G, Mat *Ht)
{
  PetscFunctionBegin;
  PetscCheck(y->assembled, y->scene->comm, PETSC_ERR_ORDER, "call KFSystemSetAngles() first");
  if (Ms) *Ms = y->Ms;
  if (Ks) *Ks = y->Ks;
  if (G) *G = y->G;
  if (Ht) *Ht = y->Ht;
  PetscFunctionReturn(0);
}

PetscErrorCode KFSystemGetBodyMap(KFSystem y, PetscInt body, Mat *P)
{
  PetscFunctionBegin;
  PetscCheck(y->assembled, y->scene->comm, PETSC_ERR_ORDER, "call KFSystemSetAngles() first");
  PetscCheck(body >= 0 && body < y->scene->nb, y->scene->comm, PETSC_ERR_ARG_OUTOFRANGE, "body index %" PetscInt_FMT " does not exist", body);
  *P = y->P[body];
  PetscFunctionReturn(0);
}
