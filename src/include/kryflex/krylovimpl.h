/* Private data of the Krylov stage (src/krylov): the damped input chain (damped.c), used by block_arnoldi.c. */
#ifndef KRYFLEX_KRYLOVIMPL_H
#define KRYFLEX_KRYLOVIMPL_H

#include <kryflex_impl.h>

/* the viscous damping the damped moments use (the bodies' C_b plus Rayleigh) and the chain's frequency scale (rad/s) */
typedef struct {
  PetscReal alpha, beta, gamma;
} KFKrylovDamping;

typedef struct {
  KFKrylovDamping d;
  BV              Z[2];    /* the u and v halves of the orthonormalized blocks */
  PetscInt        k, last; /* columns, first column of the last block */
  PetscInt        nblocks;
} KFDampedChain;

PETSC_INTERN PetscErrorCode KFDampedChainCreate_Private(KFFlexSolver, const KFKrylovDamping *, PetscInt maxcols, KFDampedChain *);
PETSC_INTERN PetscErrorCode KFDampedChainNext_Private(KFFlexSolver, KFDampedChain *, Mat B, PetscReal tol, Mat *U);
PETSC_INTERN PetscErrorCode KFDampedChainDestroy_Private(KFDampedChain *);
/* KFKrylovBasisWithInfo with the damped input chain when d is not NULL */
PETSC_INTERN PetscErrorCode KFKrylovBasisDamped_Private(KFFlexSolver, PetscInt nin, PetscInt nout, PetscReal tol, const KFKrylovDamping *d, BV *V, KFKrylovInfo *info);

/* one basis of the leading m[i] columns of n bases of the system, in order (src/reducer/shifts.c) */
PETSC_INTERN PetscErrorCode KFKrylovBasisMerge_Private(KFSystem, PetscInt n, BV Vs[], const PetscInt m[], PetscReal tol, BV *V, KFKrylovInfo *info);
#endif
