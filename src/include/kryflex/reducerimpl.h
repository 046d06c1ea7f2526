/* Private data of the reducer (src/reducer): not part of the public API. The layout follows PETSc's KSP: the
   generic policy in the files of src/reducer, one basis per implementation under src/reducer/impls. */
#ifndef KRYFLEX_REDUCERIMPL_H
#define KRYFLEX_REDUCERIMPL_H

#include <kryflex_impl.h>
#include <math.h>

/*
  The projection basis of one configuration, as an implementation builds it: the small eigenproblem of the
  projected system (lambda ascending, Phi M-orthonormal, size x size), the projected inputs and outputs, and the
  implementation's own data (a BV of Krylov vectors, or full-order modes) from which system vectors are made.
*/
typedef struct {
  PetscInt   size, ndeflated;
  PetscReal *lambda, *Phi; /* size, size x size */
  PetscReal *Gr, *Hr;      /* size x a, t x size */
  PetscReal  gram_condition; /* of the raw recurrence (diagnostic), NaN when not computed */
  void      *data;
} KFReducerBasis;

struct _KFReducerOps {
  PetscErrorCode (*setfromoptions)(KFReducer, PetscOptionItems *);
  PetscErrorCode (*view)(KFReducer, PetscViewer);
  PetscErrorCode (*destroy)(KFReducer);
  /* the basis at the system's configuration, with its factored flexible solve operator */
  PetscErrorCode (*buildbasis)(KFReducer, KFSystem, KFFlexSolver, KFReducerBasis *);
  /* system vectors: the modes flagged in kept plus, with static, the static correction of the others (eq. 15-17);
     kept NULL: the whole basis */
  PetscErrorCode (*vectors)(KFReducer, KFSystem, KFFlexSolver, KFReducerBasis *, const PetscBool kept[], PetscBool static_correction, Mat *X);
  PetscErrorCode (*destroybasis)(KFReducer, KFReducerBasis *);
};

/* A named result array (column-major over shape) */
typedef struct {
  char      name[64];
  PetscInt  ndim, shape[3];
  PetscReal *data;
} KFResult;

typedef struct {
  PetscInt   n, nalloc;
  KFResult  *items;
  char     **names;
} KFResultSet;

struct _p_KFReducer {
  PETSCHEADER(struct _KFReducerOps);
  void     *data; /* the implementation's */
  KFScene   scene;
  PetscBool setupcalled, solved;

  /* what the reduction must serve */
  PetscInt        nconfig;        /* angles of interest: nconfig x nrevolute, radians */
  PetscReal      *angles;
  PetscBool       auto_alpha;     /* alpha_G chosen by the paper's rule */
  PetscReal      *alpha_g;        /* nrevolute (at least 1 entry) */
  PetscInt        nmulti;         /* multi-angle configurations (0: the angles of interest) */
  PetscReal      *multi;
  KFReducerMethod method;
  PetscReal       band[2], zeta, accuracy;
  PetscInt        moments, output_blocks;
  KFImportance    importance;
  PetscReal       keep_threshold;
  PetscBool       static_correction;
  PetscReal       deflation_tol, body_tol, reassembly_rtol, shift;
  PetscReal       eigen_cover;    /* eigen type's cover, kept here so that it survives a change of type */
  PetscInt        save_maps;      /* PETSC_TRUE, PETSC_FALSE or PETSC_DECIDE */
  PetscInt        save_maps_max_dofs, gram_condition_max_dofs;
  PetscReal       negligible;     /* a moment below this fraction of its largest value over the angles is zero */
  PetscBool       verify;
  PetscInt        verify_modes;   /* PETSC_DECIDE: cover verify_cover x the band's top */
  PetscReal       verify_cover;
  PetscInt        frequency_points;
  PetscReal       frf_floor_db;

  /* results of the solve */
  KFReducedModel single, multi_model;
  KFResultSet   *results;         /* nconfig + 1 sets; the last one holds the whole solve's */
  PetscInt       nnotes;
  char         **notes;
  char           rule[512];
};

PETSC_INTERN PetscErrorCode KFReducerResultSet_Private(KFReducer, PetscInt config, const char name[], PetscInt ndim, const PetscInt shape[], const PetscReal data[]);
PETSC_INTERN PetscErrorCode KFReducerResultScalar_Private(KFReducer, PetscInt config, const char name[], PetscReal value);
PETSC_INTERN PetscErrorCode KFReducerResultsReset_Private(KFReducer);
PETSC_INTERN PetscErrorCode KFReducerConfigLabel_Private(PetscInt nrev, const PetscReal angles[], char buf[], size_t len);
PETSC_INTERN PetscErrorCode KFReducerModelSizes_Private(KFReducedModel, char buf[], size_t len);
PETSC_INTERN PetscErrorCode KFReducerNote_Private(KFReducer, const char fmt[], ...);
/* the full-order reference of one configuration of interest, for verification */
typedef struct {
  PetscInt   n, r;           /* flexible modes computed, rigid-body and mechanism modes */
  PetscReal *w2;             /* n */
  PetscReal *HPhi, *PhiG;    /* t x n, n x a */
  PetscReal *HPr, *PrG;      /* t x r, r x a */
} KFFullReference;
PETSC_INTERN PetscErrorCode KFReducerFullReference_Private(KFReducer, KFSystem, KFFullReference *);
PETSC_INTERN PetscErrorCode KFFullReferenceDestroy_Private(KFFullReference *);
/* errors of the reassembled models against the full order at every configuration of interest (results, notes) */
PETSC_INTERN PetscErrorCode KFReducerCompare_Private(KFReducer, const PetscReal Lfull[], KFFullReference ref[]);
PETSC_INTERN PetscErrorCode KFReducerRecordSettings_Private(KFReducer, KFReducedModel, KFReducerMethod, PetscInt n, const PetscReal angles[]);

PETSC_EXTERN PetscLogEvent KF_EVENT_REDUCER_SETUP, KF_EVENT_REDUCER_SOLVE, KF_EVENT_REDUCER_BASIS, KF_EVENT_REDUCER_VERIFY;

PETSC_EXTERN PetscErrorCode KFReducerCreate_Krylov(KFReducer);
PETSC_EXTERN PetscErrorCode KFReducerCreate_Eigen(KFReducer);

#endif
