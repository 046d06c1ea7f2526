/* Private to the verification's eigensolves (src/verify/eigen.c: SLEPc and dense; block_eigen.c: block Krylov) */
#ifndef KRYFLEX_VERIFY_EIGEN_IMPL_H
#define KRYFLEX_VERIFY_EIGEN_IMPL_H

#include <kryflex_impl.h>

/* K+ applications of one eigensolve with the flexible solver's factor, their residual sampled (KFFlexPCApplySampled) */
typedef struct {
  KFFlexSolver solver;
  PetscInt     applications; /* applications (one vector or one block) so far in this eigensolve */
  PetscInt     checked;      /* ... of them with the residual checked */
  PetscBool    check_all;    /* a sampled application needed refinement: check every one */
} KFFlexPCCtx;

PETSC_INTERN PetscErrorCode KFFlexPCApplySampled(KFFlexPCCtx *, Mat B, Mat X);
PETSC_INTERN PetscErrorCode KFEPSNormalizeBlock(KFSystem, Mat P);
PETSC_INTERN PetscErrorCode KFSystemMasslessCount(KFSystem, PetscInt *);
PETSC_INTERN PetscErrorCode KFSystemMassSingular(KFSystem, PetscBool *);
PETSC_INTERN PetscErrorCode KFSystemMassNullPivots(KFSystem, PetscInt *);
PETSC_INTERN PetscErrorCode KFBlockEigenSolve(KFSystem, KFFlexSolver, const KFEigenHint *, PetscInt nev, PetscInt *nconv, PetscReal omega2[], Mat *P, PetscBool *ok, PetscInt *nblocks, PetscInt *bcols, PetscInt *cap);
#endif
