/* The reassembly workspace (KFReassembly), shared by the SVD path (reassemble.c) and the closed-form path of trees of
   bodies (reassemble_primal.c); private to src/dense. */
#ifndef KRYFLEX_REASSEMBLE_IMPL_H
#define KRYFLEX_REASSEMBLE_IMPL_H

#include "dense_impl.h"

typedef struct _n_KFPrimal *KFPrimal;

/* Everything a reassembly at one more angle needs, sized once: copies of the bodies and joints, the constraint matrix,
   its SVD, the products, the system's rigid motions R (angle-independent) and the eigensolver's workspace. */
struct _n_KFReassembly {
  PetscInt       nb, nj, nrev, n, m, a, t, vmax;
  PetscReal      rtol, alpha, beta; /* Rayleigh alpha M + beta K added to the damping */
  PetscBool      viscous;           /* some body has a viscous damping matrix */
  KFReducedBody *bodies;            /* pointers into data */
  KFJointDef    *joints;
  PetscInt      *off;
  PetscReal     *data;
  PetscReal     *D, *N, *A, *s, *VT, *svdwork, *W;
  PetscBLASInt   lsvd, lsvd_D, lsvd_E; /* allocated; LAPACK's query at D's size and at D R's */
  long double   *WL;
  PetscInt       nr; /* -1: some body's rigid motions unknown */
  PetscReal     *R, *E, *Z, *Y;
  PetscReal     *eigwork;
  PetscInt       leig;
  PetscInt       eig_h, eig_r;             /* the sizes of the last KFReassemblyEig, and LAPACK's queries there */
  PetscBLASInt   eig_lsvd, eig_leig;
  KFPrimal       primal; /* the closed-form path, NULL when the bodies and joints do not allow it */
  PetscInt       hprimal; /* its size, n - m */
  PetscBool      use_svd; /* the SVD of the constraints at every call even when primal exists */
  PetscInt       mj, ms;  /* m = mj joint rows + ms coordinate ties */
  PetscReal     *Ds;      /* the coordinate ties (ms x n), or NULL */
};

/* the interface ties D (m x n) at these angles into r->D */
PETSC_INTERN PetscErrorCode KFReassemblyConstraints_Private(KFReassembly, const PetscReal angles[]);
/* Two unit vectors spanning the plane perpendicular to the unit axis k */
/* the closed-form path: made at creation when the joints form a tree whose bodies see their interface motions
   (r->primal stays NULL otherwise), applied at each call, destroyed with the workspace */
PETSC_INTERN PetscErrorCode KFPrimalCreate_Private(KFReassembly);
PETSC_INTERN PetscErrorCode KFPrimalApply_Private(KFReassembly, const PetscReal angles[], PetscReal Mh[], PetscReal Kh[], PetscReal Ch[], PetscReal Gh[], PetscReal Hh[]);
PETSC_INTERN PetscErrorCode KFPrimalToCoordinates_Private(KFReassembly, PetscInt q, const PetscReal Y[], PetscReal Phir[]);
PETSC_INTERN PetscErrorCode KFPrimalDestroy_Private(KFPrimal *);

#endif
