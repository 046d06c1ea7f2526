/* KFREDUCERKRYLOV: A. Y. Lee's basis, the deflated block Krylov vectors of K+ (eq. 8-9), their small eigenproblem
   (eq. 12-13), and the kept modes plus the paper's static correction of the others (eq. 15-17). */
#include <kryflex/reducerimpl.h>
#include <kryflex/krylovimpl.h>

typedef struct {
  PetscBool raw;    /* project on the paper's raw recurrence (eq. 9) instead of the orthogonalized blocks: diagnostics */
  PetscBool damped; /* input blocks from the moments of the damped system (src/krylov/damped.c) */
} KFReducer_Krylov;

static PetscErrorCode KFReducerBuildBasis_Krylov(KFReducer r, KFSystem sys, KFFlexSolver solver, KFReducerBasis *basis)
{
  KFReducer_Krylov *kr = (KFReducer_Krylov *)r->data;
  BV                V;
  PetscInt          c, a, t, nsys, l, k, nblk = r->build_moments, nout, nin;
  PetscReal        *Mr, *Kr, *gram = NULL;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, NULL, &nsys, &a, &t));
  /* c blocks: the output blocks interleave with the first input blocks, so each prefix of c' blocks is the basis of
     c' moments (KFKrylovBasisWithInfo) */
  nout = PetscMin(r->output_blocks, nblk / 2);
  nin  = nblk - nout;
  if (kr->raw) {
    Mat P;

    PetscCall(KFKrylovRawBasis(solver, nin, nout, &P, &basis->gram_condition));
    PetscCall(BVCreateFromMat(P, &V));
    PetscCall(BVSetType(V, BVSVEC)); /* the columns of P are copied into the BV only when it gets a type */
    PetscCall(BVSetMatrix(V, sys->Ms, PETSC_FALSE));
    PetscCall(MatDestroy(&P));
  } else {
    KFKrylovInfo info;

    if (kr->damped) { /* the viscous damping: the bodies' C_b and Rayleigh; frequency scale: the band's top */
      KFKrylovDamping d = {r->damping.alpha, r->damping.beta, 2 * PETSC_PI * r->band[1]};
      PetscCall(KFKrylovBasisDamped_Private(solver, nin, nout, r->deflation_tol, &d, &V, &info));
    } else PetscCall(KFKrylovBasisWithInfo(solver, nin, nout, r->deflation_tol, &V, &info));
    basis->ndeflated     = info.ndeflated;
    basis->nblocks       = info.nblocks;
    basis->block_end     = info.block_end; /* the basis owns it now */
    basis->rigid_content = info.rigid_content;
    basis->orthogonality = info.orthogonality;
    gram                 = info.gram; /* the health check's V^T M V: the reduced mass below, no second product */
    /* undeflated, the plain recurrence spans every block: its pencil has the full order's first nblk moments */
    basis->nmoments = !kr->damped && info.ndeflated == 0 ? nblk : 0;
  }
  PetscCall(BVGetActiveColumns(V, &l, &k));
  c           = k - l;
  basis->size = c;
  basis->data = V;
  PetscCall(PetscMalloc4(c, &basis->lambda, c * c, &basis->Phi, c * a, &basis->Gr, t * c, &basis->Hr));
  PetscCall(PetscMalloc2(c * c, &Mr, c * c, &Kr));
  PetscCall(KFSystemProjectGram_Private(sys, V, gram, Mr, Kr, basis->Gr, basis->Hr));
  PetscCall(PetscFree(gram));
  PetscCall(KFDenseEig(c, Kr, Mr, basis->lambda, basis->Phi));
  basis->Kr = Kr;
  basis->Mr = Mr;
  if (!kr->raw && nsys <= r->gram_condition_max_dofs) { /* the raw recurrence's conditioning: why the basis is orthogonalized */
    Mat       P;
    PetscReal cond;

    PetscCall(KFKrylovRawBasis(solver, nin, nout, &P, &cond));
    PetscCall(MatDestroy(&P));
    basis->gram_condition = PetscMin(cond, 1e300);
  }
  PetscFunctionReturn(0);
}

static PetscErrorCode KFReducerSetFromOptions_Krylov(KFReducer r, PetscOptionItems *PetscOptionsObject)
{
  KFReducer_Krylov *kr = (KFReducer_Krylov *)r->data;

  PetscFunctionBegin;
  PetscOptionsHeadBegin(PetscOptionsObject, "Krylov basis (-kf_reducer_type krylov)");
  PetscCall(KFOptionsSettingBool(PetscOptionsObject, "-kf_krylov_damped", kr->damped, &kr->damped, NULL));
  PetscCall(KFOptionsSettingBool(PetscOptionsObject, "-kf_krylov_raw", kr->raw, &kr->raw, NULL));
  PetscOptionsHeadEnd();
  PetscFunctionReturn(0);
}

static PetscErrorCode KFReducerDestroy_Krylov(KFReducer r)
{
  PetscFunctionBegin;
  PetscCall(PetscFree(r->data));
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
  KFReducer_Krylov *kr;

  PetscFunctionBegin;
  PetscCall(PetscNew(&kr));
  r->data                = kr;
  r->ops->setfromoptions = KFReducerSetFromOptions_Krylov;
  r->ops->destroy        = KFReducerDestroy_Krylov;
  r->ops->buildbasis   = KFReducerBuildBasis_Krylov;
  r->ops->vectors      = KFReducerVectors_Krylov;
  r->ops->destroybasis = KFReducerDestroyBasis_Krylov;
  r->ops->blocks       = PETSC_TRUE;
  PetscFunctionReturn(0);
}
