/* KFREDUCEREIGEN: the baseline Lee's method replaces (EP&A / COMPARE style): full-order modes covering cover x the
   band's top frequency (SLEPc), ranked like the Krylov modes, with the static correction of every mode not kept
   (one solve with K+). */
#include <kryflex/reducerimpl.h>

static PetscErrorCode KFReducerBuildBasis_Eigen(KFReducer r, KFSystem sys, KFFlexSolver solver, KFReducerBasis *basis)
{
  PetscInt         nrev, nsys, a, t, nflex, nev, nconv = 0, m = 0;
  PetscReal       *w2 = NULL, *C, *HrT, fmax = r->eigen_cover * r->band[1];
  Mat              modes = NULL, Mm, Ms, Ks, G, Ht;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, &nrev, &nsys, &a, &t));
  nflex = nsys - 6 - nrev;
  PetscCheck(nflex >= 1, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_WRONG, "the scene has no flexible modes (%" PetscInt_FMT " system dofs)", nsys);
  nev = PetscMin(nflex, 10);
  while (PETSC_TRUE) { /* double the count until the modes pass fmax */
    PetscCall(PetscMalloc1(nev, &w2));
    PetscCall(KFFlexSolverEigenModes(solver, nev, &nconv, w2, &modes)); /* the flexible solver's factor: no second one */
    if (nev >= nflex || (nconv && PetscSqrtReal(w2[nconv - 1]) / (2 * PETSC_PI) > fmax)) break;
    PetscCall(PetscFree(w2));
    PetscCall(MatDestroy(&modes));
    nev = PetscMin(nflex, 2 * nev);
  }
  for (PetscInt i = 0; i < nconv; i++) m += (i == 0 || PetscSqrtReal(PetscMax(w2[i], 0)) / (2 * PETSC_PI) <= fmax);
  PetscCall(PetscCalloc1(nev * m, &C));
  for (PetscInt i = 0; i < m; i++) C[i + i * nev] = 1;
  PetscCall(KFMatCombine(modes, m, C, &Mm));
  PetscCall(PetscFree(C));
  PetscCall(MatDestroy(&modes));
  basis->size      = m;
  basis->ndeflated = 0;
  basis->data      = Mm;
  PetscCall(PetscMalloc4(m, &basis->lambda, m * m, &basis->Phi, m * a, &basis->Gr, t * m, &basis->Hr));
  PetscCall(PetscArraycpy(basis->lambda, w2, m));
  PetscCall(PetscArrayzero(basis->Phi, m * m));
  for (PetscInt i = 0; i < m; i++) basis->Phi[i + i * m] = 1;
  PetscCall(KFSystemGetMatrices(sys, &Ms, &Ks, &G, &Ht));
  PetscCall(KFMatInner(Mm, G, basis->Gr));
  PetscCall(PetscMalloc1(m * t, &HrT));
  PetscCall(KFMatInner(Mm, Ht, HrT)); /* m x t */
  for (PetscInt i = 0; i < t; i++)
    for (PetscInt j = 0; j < m; j++) basis->Hr[i + j * t] = HrT[j + i * m];
  PetscCall(PetscFree(HrT));
  PetscCall(PetscFree(w2));
  PetscFunctionReturn(0);
}

static PetscErrorCode KFReducerVectors_Eigen(KFReducer r, KFSystem sys, KFFlexSolver solver, KFReducerBasis *basis, const PetscBool kept[], PetscBool static_correction, Mat *X)
{
  Mat        Mm = (Mat)basis->data, K, X0, S, Ms, Ks, G, Ht;
  PetscInt   m = basis->size, a, nk = 0;
  PetscReal *C;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, NULL, NULL, &a, NULL));
  PetscCall(PetscCalloc1(m * m, &C));
  for (PetscInt i = 0; i < m; i++)
    if (!kept || kept[i]) C[i + nk++ * m] = 1;
  PetscCall(KFMatCombine(Mm, nk, C, &K));
  PetscCall(PetscFree(C));
  if (!kept || !static_correction) {
    *X = K;
    PetscFunctionReturn(0);
  }
  /* residual flexibility: K+ G minus what the kept modes already carry */
  PetscCall(KFSystemGetMatrices(sys, &Ms, &Ks, &G, &Ht));
  PetscCall(MatDuplicate(G, MAT_DO_NOT_COPY_VALUES, &X0));
  PetscCall(KFFlexSolverApply(solver, G, X0));
  PetscCall(PetscCalloc1(m * a, &C));
  for (PetscInt i = 0; i < m; i++)
    if (kept[i])
      for (PetscInt j = 0; j < a; j++) C[i + j * m] = basis->Gr[i + j * m] / basis->lambda[i];
  PetscCall(KFMatCombine(Mm, a, C, &S));
  PetscCall(PetscFree(C));
  PetscCall(MatAXPY(X0, -1.0, S, SAME_NONZERO_PATTERN));
  PetscCall(KFDenseHStack(K, X0, X));
  PetscCall(MatDestroy(&S));
  PetscCall(MatDestroy(&X0));
  PetscCall(MatDestroy(&K));
  PetscFunctionReturn(0);
}

static PetscErrorCode KFReducerDestroyBasis_Eigen(KFReducer r, KFReducerBasis *basis)
{
  Mat Mm = (Mat)basis->data;

  PetscFunctionBegin;
  PetscCall(MatDestroy(&Mm));
  basis->data = NULL;
  PetscFunctionReturn(0);
}

static PetscErrorCode KFReducerSetFromOptions_Eigen(KFReducer r, PetscOptionItems *PetscOptionsObject)
{
  PetscReal cover = r->eigen_cover;
  PetscBool flg;

  PetscFunctionBegin;
  PetscOptionsHeadBegin(PetscOptionsObject, "Eigenvector baseline (-kf_reducer_type eigen)");
  PetscCall(KFOptionsSettingReal(PetscOptionsObject, "-kf_eigen_cover", cover, &cover, &flg));
  PetscOptionsHeadEnd();
  if (flg) PetscCall(KFReducerEigenSetCover(r, cover));
  PetscFunctionReturn(0);
}

static PetscErrorCode KFReducerView_Eigen(KFReducer r, PetscViewer viewer)
{
  PetscFunctionBegin;
  PetscCall(PetscViewerASCIIPrintf(viewer, "eigenvector basis: full-order modes up to %g x the band's top frequency\n", (double)r->eigen_cover));
  PetscFunctionReturn(0);
}

/* kept by the reducer whatever its type, so that a later -kf_reducer_type eigen finds it */
PetscErrorCode KFReducerEigenSetCover(KFReducer r, PetscReal cover)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCheck(cover > 0 && !PetscIsInfOrNanReal(cover), PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_OUTOFRANGE, "eigen cover: give a positive multiple of the band's top frequency, got %g (-kf_eigen_cover)", (double)cover);
  r->eigen_cover = cover;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerCreate_Eigen(KFReducer r)
{
  PetscFunctionBegin;
  r->ops->buildbasis     = KFReducerBuildBasis_Eigen;
  r->ops->vectors        = KFReducerVectors_Eigen;
  r->ops->destroybasis   = KFReducerDestroyBasis_Eigen;
  r->ops->setfromoptions = KFReducerSetFromOptions_Eigen;
  r->ops->view           = KFReducerView_Eigen;
  PetscFunctionReturn(0);
}
