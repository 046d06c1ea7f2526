/* KFREDUCERKRYLOV: A. Y. Lee's basis, the deflated block Krylov vectors of K+ (eq. 8-9), their small eigenproblem
   (eq. 12-13), and the kept modes plus the paper's static correction of the others (eq. 15-17). */
#include <kryflex/reducerimpl.h>

static PetscErrorCode KFReducerBuildBasis_Krylov(KFReducer r, KFSystem sys, KFFlexSolver solver, KFReducerBasis *basis)
{
  BV         V;
  PetscInt   c, a, t, nsys, l, k;
  PetscReal *Mr, *Kr;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, NULL, &nsys, &a, &t));
  PetscCall(KFKrylovBasis(solver, r->moments - r->output_blocks, r->output_blocks, r->deflation_tol, &V, &basis->ndeflated));
  PetscCall(BVGetActiveColumns(V, &l, &k));
  c           = k - l;
  basis->size = c;
  basis->data = V;
  PetscCall(PetscMalloc4(c, &basis->lambda, c * c, &basis->Phi, c * a, &basis->Gr, t * c, &basis->Hr));
  PetscCall(PetscMalloc2(c * c, &Mr, c * c, &Kr));
  PetscCall(KFSystemProject(sys, V, Mr, Kr, basis->Gr, basis->Hr));
  PetscCall(KFDenseEig(c, Kr, Mr, basis->lambda, basis->Phi));
  PetscCall(PetscFree2(Mr, Kr));
  if (nsys <= r->gram_condition_max_dofs) { /* the raw recurrence's conditioning: why the basis is orthogonalized */
    Mat       P;
    PetscReal cond;

    PetscCall(KFKrylovRawBasis(solver, r->moments - r->output_blocks, r->output_blocks, &P, &cond));
    PetscCall(MatDestroy(&P));
    basis->gram_condition = PetscMin(cond, 1e300);
  }
  PetscFunctionReturn(0);
}

static PetscErrorCode KFReducerVectors_Krylov(KFReducer r, KFSystem sys, KFFlexSolver solver, KFReducerBasis *basis, const PetscBool kept[], PetscBool static_correction, Mat *X)
{
  BV         V = (BV)basis->data;
  PetscInt   c = basis->size, a, nk = 0, nd, m;
  PetscReal *C;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, NULL, NULL, &a, NULL));
  if (!kept) { /* the whole basis */
    PetscCall(PetscCalloc1(c * c, &C));
    for (PetscInt i = 0; i < c; i++) C[i + i * c] = 1;
    PetscCall(KFBVCombine(V, c, C, X));
    PetscCall(PetscFree(C));
    PetscFunctionReturn(0);
  }
  for (PetscInt i = 0; i < c; i++) nk += kept[i];
  nd = c - nk;
  m  = nk + (static_correction && nd ? a : 0);
  PetscCall(PetscMalloc1(c * PetscMax(m, 1), &C));
  for (PetscInt i = 0, j = 0; i < c; i++)
    if (kept[i]) PetscCall(PetscArraycpy(&C[j++ * c], &basis->Phi[i * c], c));
  if (m > nk) { /* S = Phid Lambdad^-1 Phid^T Gr: the static response of the discarded modes */
    PetscReal *Phid, *lamd;

    PetscCall(PetscMalloc2(c * nd, &Phid, nd, &lamd));
    for (PetscInt i = 0, j = 0; i < c; i++)
      if (!kept[i]) {
        PetscCall(PetscArraycpy(&Phid[j * c], &basis->Phi[i * c], c));
        lamd[j++] = basis->lambda[i];
      }
    PetscCall(KFDenseStaticCorrection(c, nd, Phid, lamd, a, basis->Gr, &C[nk * c]));
    PetscCall(PetscFree2(Phid, lamd));
  }
  PetscCall(KFBVCombine(V, m, C, X));
  PetscCall(PetscFree(C));
  PetscFunctionReturn(0);
}

static PetscErrorCode KFReducerDestroyBasis_Krylov(KFReducer r, KFReducerBasis *basis)
{
  BV V = (BV)basis->data;

  PetscFunctionBegin;
  PetscCall(BVDestroy(&V));
  basis->data = NULL;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerCreate_Krylov(KFReducer r)
{
  PetscFunctionBegin;
  r->ops->buildbasis   = KFReducerBuildBasis_Krylov;
  r->ops->vectors      = KFReducerVectors_Krylov;
  r->ops->destroybasis = KFReducerDestroyBasis_Krylov;
  PetscFunctionReturn(0);
}
