/* Private data of the flexible solver (src/solve): not part of the public API. The layout follows PETSc's KSP: the
   generic object and its refinement in src/solve/flex_solver.c, MUMPS in src/solve/mumps.c, one way of applying K+
   per implementation under src/solve/impls/<type>/, each registered by name (src/solve/register.c). */
#ifndef KRYFLEX_FLEXSOLVERIMPL_H
#define KRYFLEX_FLEXSOLVERIMPL_H

#include <kryflex_impl.h>

struct _KFFlexSolverOps {
  PetscErrorCode (*setfromoptions)(KFFlexSolver, PetscOptionItems *);
  /* the factorization(s); an implementation that does not apply names another type in solver->handoff and returns:
     KFFlexSolverSetUp sets that type up instead */
  PetscErrorCode (*setup)(KFFlexSolver);
  /* X = K_h^-1 W for a block W already made self-equilibrated and zero on the held rows */
  PetscErrorCode (*solve)(KFFlexSolver, Mat W, Mat X);
  /* a block low-rank factor refactored full rank (*done: whether it was); NULL where there is none */
  PetscErrorCode (*refactor)(KFFlexSolver, PetscBool *done);
  PetscErrorCode (*view)(KFFlexSolver, PetscViewer);
  PetscErrorCode (*destroy)(KFFlexSolver);
};

struct _p_KFFlexSolver {
  PETSCHEADER(struct _KFFlexSolverOps);
  void     *data;            /* the implementation's */
  KFSystem  sys;
  PetscInt  nheld, *held;    /* held system dofs (global), chosen by the implementation at its set-up */
  PetscReal shift;           /* K + shift M is factored; negative: an expansion point inside the band */
  PetscBool shift_set;       /* KFFlexSolverSetShift/SetInteriorShift called: -kf_shift does not override it */
  PetscInt  null_pivots, negative_pivots;
  PetscInt  refine;          /* at most this many iterative refinement steps against K_S per block */
  PetscBool refine_set;      /* -kf_refine given: no default by the factor (KFFlexSolverRefineSteps) */
  PetscReal refine_rtol;     /* ... taken only while ||P B - K_S X||_F / ||P B||_F exceeds it */
  PetscBool setfromoptionscalled, setup;
  const char *handoff;       /* set by an implementation's setup that does not apply: the type to set up instead */
  KFFlexSolverPerf perf;     /* what the factorization and the solves cost (KFFlexSolverGetPerf) */
  PetscInt  residual_decided, residual_undecided; /* first residuals the double product decided, and did not */
};

PETSC_EXTERN PetscClassId      KF_FLEXSOLVER_CLASSID; /* src/util/package.c */
PETSC_EXTERN PetscFunctionList KFFlexSolverList;
/* KFFlexSolverApply refined to the factor's floor whatever the first residual (src/solve/flex_solver.c) */
PETSC_INTERN PetscErrorCode    KFFlexSolverApplyRefined(KFFlexSolver, Mat B, Mat X);
PETSC_INTERN PetscErrorCode    KFFlexSolverRegisterAll(void); /* src/solve/register.c: the built-in types, once */
PETSC_INTERN PetscErrorCode    KFFlexSolverGetTypeNames(PetscInt *, const char *const **);
PETSC_INTERN PetscErrorCode    KFFlexSolverCreate_Monolithic(KFFlexSolver);
PETSC_INTERN PetscErrorCode    KFFlexSolverCreate_Bodywise(KFFlexSolver);
PETSC_INTERN PetscErrorCode    KFFlexSolverCreate_Auto(KFFlexSolver);

/* MUMPS (src/solve/mumps.c): a Cholesky/LDL^T factor of A with null-pivot detection and its inertia. prefix: the
   options prefix of the user's factorization controls; opts: those controls (ordering, block low-rank, out of core,
   memory check) apply, else MUMPS' defaults; estimate_mb: non-NULL runs the memory check and reports the estimate. */
PETSC_INTERN PetscErrorCode KFFactorMumps(Mat A, const char prefix[], PetscReal null_threshold, PetscBool opts, Mat *F, PetscInt *null_pivots, PetscInt *negative_pivots, PetscReal *estimate_mb);
PETSC_INTERN PetscErrorCode KFFactorMumpsNumericAgain(Mat A, Mat *F, PetscInt *null_pivots, PetscInt *negative_pivots); /* F's analysis kept */
PETSC_INTERN PetscErrorCode KFMumpsCheckOptions(MPI_Comm, const char prefix[]); /* every factorization option, read and checked */
PETSC_INTERN PetscErrorCode KFMumpsGetBLR(MPI_Comm, const char prefix[], PetscReal *blr); /* -kf_blr */
PETSC_INTERN PetscReal      KFNodeMemoryAvailableMB(void);
/* out-of-core folders (src/solve/ooc_folder.c): the parent (-kf_ooc_dir given, else MUMPS_OOC_TMPDIR, TMPDIR, /tmp),
   a private folder per rank attached to the factor and removed with it, and the numerical factorization that puts
   the factor's files there */
PETSC_INTERN PetscErrorCode KFOocParent(const char given[], const char **parent);
PETSC_INTERN PetscErrorCode KFOocFolderCreate(Mat F, const char parent[]);
PETSC_INTERN PetscErrorCode KFOocFolderGet(Mat F, const char **path);
PETSC_INTERN PetscErrorCode KFMumpsFactorNumeric(Mat F, Mat A);
PETSC_INTERN PetscErrorCode KFMumpsMatSolve(Mat F, Mat B, Mat X); /* an out-of-core factor read once per block */
/* -kf_null_pivot_check_max_dofs and -kf_check_null_pivots: whether a system of nsys dofs factored with this shift gets
   the cross-check of its rigid count by MUMPS' null pivots of K_S */
PETSC_INTERN PetscErrorCode KFNullPivotCheckOptions(MPI_Comm, const char prefix[], PetscInt nsys, PetscReal shift, PetscBool *check);

PETSC_INTERN PetscErrorCode KFSelectHeldDofs(KFSystem, const char prefix[], PetscInt *nheld, PetscInt **held);         /* src/solve/held_dofs.c */
PETSC_INTERN PetscErrorCode KFSelectPivotedDofs(Mat Phi, PetscInt *nheld, PetscInt **held);

#endif
