/* Private data structures of kryflex: shared by the stages, not part of the public API. */
#ifndef KRYFLEX_IMPL_H
#define KRYFLEX_IMPL_H

#include <kryflex.h>
#include <petsc/private/petscimpl.h>

/* M's null space: a direction whose mass is below this fraction of the masses its own dofs carry (diag(M) on it).
   Exported mass matrices are rounded (8 to 12 digits in a punch) entry by entry, so a cancellation leaves that
   fraction of the entries it cancels, whatever the other bodies weigh; its static part is kept exactly by the
   verification's condensation, and the Krylov basis drops such columns (src/krylov/block_arnoldi.c) */
#define KF_MASS_NULL_RTOL 1e-8

/* A linear combination of system dofs: how one interface dof of a body reads in system coordinates. */
#define KF_MAX_TERMS 96
typedef struct {
  PetscInt  n;
  PetscInt  idx[KF_MAX_TERMS];
  PetscReal c[KF_MAX_TERMS];
} KFExpr;

typedef struct {
  char     name[KF_MAX_NAME];
  PetscInt node_id, node, dof0; /* node index in the body, first dof of that node */
} KFInterface;

typedef struct {
  char         name[KF_MAX_NAME];
  Mat          M, K;       /* referenced */
  PetscInt     n;          /* dofs */
  PetscInt     nnodes;
  PetscInt    *ids, *ndof, *dof0;
  PetscInt    *comps;      /* per node: bit c set when component c (ux uy uz rx ry rz) is present; 0: scalar point */
  PetscInt     nscalar;    /* scalar points, their dofs and their values in the 6 body-frame rigid motions */
  PetscInt    *scalar_of_node; /* node -> index among the scalar points, -1 */
  PetscReal   *scalar_rigid;   /* nscalar x 6, by static condensation (minimum strain energy) */
  PetscReal   *xyz;
  PetscInt     ninterfaces;
  KFInterface *iface;
  Mat          G, Ht;      /* n x a, n x t (MPIDENSE), built at set-up */
  PetscInt     parent_joint; /* joint in which this body is the child; -1 for the root */
  PetscInt     child_iface;  /* its interface eliminated by that joint */
  PetscInt     rstart, rend;
  Mat          C;          /* viscous damping, referenced, or NULL (KFSceneSetBodyDamping) */
  PetscInt    *sysidx;     /* local dofs -> system dof, -1 where tied by the parent joint, -2 where clamped */
  /* boundary conditions (KFSceneAddConstraint, KFSceneAddSpring, joints to ground): body dofs, replicated */
  PetscInt     nclamp, nspring;
  PetscInt    *clamp;      /* clamped body dofs (eliminated: the body's map P_b reads them as zero) */
  PetscInt    *spring_dof; /* springs to ground, added to the diagonal of K at set-up */
  PetscReal   *spring_k;
  PetscBool    own_K;      /* K is the scene's copy with the springs added */
  PetscBool    exact_M, exact_K; /* found exactly symmetric at set-up (springs, on the diagonal, keep K so) */
  PetscReal    mnorm;            /* ||M||_inf, kept for every configuration (KFBodyMassNorm) while M's state is mnorm_state */
  PetscObjectState mnorm_state;  /* 0: not yet computed */
} KFBodyData;

typedef struct {
  char        name[KF_MAX_NAME];
  KFJointType type;
  PetscInt    parent, child, parent_iface, child_iface;
  PetscReal   axis[3], R0[9];
  PetscInt    revolute;  /* index among revolute joints, -1 if fixed */
  PetscInt    beta;      /* system dof of the joint's free rotation, -1 if fixed */
} KFJointData;

typedef struct {
  PetscInt  io, body, node_id, comp;
  PetscReal w;
  Vec       v; /* or a whole vector */
} KFTerm;

/* The scene is a PETSc object: whatever holds it (a system, a body basis, a reducer) takes a reference with
   PetscObjectReference, and KFSceneDestroy drops one, so a scene outlives everything built on it. */
struct _KFSceneOps {
  PetscErrorCode (*view)(KFScene, PetscViewer);
};
PETSC_EXTERN PetscClassId KF_SCENE_CLASSID;
PETSC_INTERN PetscErrorCode KFMatCheckSymmetricExact(Mat, const char[], PetscReal, PetscBool *); /* src/body/load.c */
PETSC_INTERN PetscErrorCode KFMatCheckSymmetricPairExact(Mat M, Mat K, const char[], const char[], PetscReal, PetscBool *, PetscBool *);
PETSC_INTERN PetscErrorCode KFGetStartTime(PetscLogDouble *); /* src/util/package.c: when KFInitialize first ran */
/* src/measure/frf_error.c: KFFRFElasticErrors and the pair, frequency index and pair scale where hinf is made
   (pointwise NULL: not measured) */
PETSC_INTERN PetscErrorCode KFFRFElasticErrorsWorst_Private(PetscInt nw, PetscInt t, PetscInt a, const PetscReal Tfre[], const PetscReal Tfim[], const PetscReal Trre[], const PetscReal Trim[], const PetscReal Tgre[], const PetscReal Tgim[], PetscReal floor_db, PetscReal *hinf, PetscReal *pointwise, PetscInt *pair, PetscInt *freq, PetscReal *pscale);

struct _n_KFScene {
  PETSCHEADER(struct _KFSceneOps);
  MPI_Comm     comm;       /* the header's communicator, kept here because every stage reads s->comm */
  char         name[PETSC_MAX_PATH_LEN];
  char       (*input_names)[KF_MAX_NAME], (*output_names)[KF_MAX_NAME]; /* "in0".., "out0".. unless named */
  PetscInt     nb, nj, nb_alloc, nj_alloc;
  KFBodyData  *bodies;
  KFJointData *joints;
  PetscInt     ninputs, noutputs;
  PetscInt     nin_terms, nout_terms, nin_alloc, nout_alloc;
  KFTerm      *in_terms, *out_terms;
  PetscBool    setup;
  PetscInt    *order;      /* bodies, parents before children */
  PetscInt     nrevolute;
  PetscInt     nsys, nsys_local, sys_rstart;
  PetscInt     nquantity, *out_quantity; /* per output a KFQuantity (KFSceneSetOutputQuantity); NULL: displacements */
  PetscInt     nrigid;     /* rigid-body and mechanism modes once a system derived them (-1 before) */
};

/* the body-wise flexible solve (src/solve/impls/bodywise): body factors kept per system, valid at every angle */
typedef struct _n_KFBodyFactors *KFBodyFactors;
typedef struct _n_KFHeldEntries *KFHeldEntries; /* K_S's held rows and columns, saved while they are held */
PETSC_INTERN PetscErrorCode KFHoldDofsInPlace(Mat, PetscInt, const PetscInt[], PetscScalar, KFHeldEntries *);
PETSC_INTERN PetscErrorCode KFRestoreHeldDofs(Mat, KFHeldEntries *);

struct _n_KFSystem {
  PetscInt  refct;           /* KFSystemReference: a reducer may hold one handed to it (KFReducerSetSystem) */
  KFScene   scene;
  PetscInt  nb;              /* bodies: destroying needs no scene */
  PetscBool assembled;
  PetscReal *angles;
  PetscReal (*Q)[9], (*o)[3]; /* body frame -> root frame: y = Q x + o */
  Mat       *P;              /* per body, n_b x e */
  Mat        Ms, Ks, G, Ht;
  Mat        Phi;            /* rigid modes, e x r, M-orthonormal */
  Mat        MPhi;           /* Ms Phi, made by the first projection, destroyed with Phi */
  Mat        KPhi;           /* Ks Phi, as the rigid residual formed it (KFSystemGetRigidProducts), destroyed with Phi */
  PetscInt   nrigid;
  PetscReal  rigid_residual;
  PetscBool  user_rigid;
  KFBodyFactors bodyf;       /* body-wise solve: the bodies' factorizations, valid at every angle */
  PetscInt   nfactor;        /* sparse factorizations made for this system's solves (all angles) */
  PetscInt   nconfig;        /* configurations it will be solved at (KFSystemSetConfigurationCount) */
  /* KFSystemSumBodies (src/assemble/sum.c): per matrix (0 M_S, 1 K_S), the local rows an angle changes (those reading a
     tied column or receiving a tied row), and the ids and states of the matrix and of the body matrices it was summed
     from; while none changed since, a later angle writes those rows only */
  PetscInt          nsumvar[2], *sumvar[2];
  PetscObjectId     sumid[2], *sumbodyid[2];
  PetscObjectState  sumstate[2], *sumbodystate[2];
};

/* the flexible solver's body-wise implementation keeps the bodies' factors on the system (src/solve/impls/bodywise) */
PETSC_INTERN PetscErrorCode KFBodyFactorsDestroy(KFBodyFactors *);
/* the body-wise solve of K_S + shift M_S at any shift and configuration, outside a flexible solver (bodywise.c) */
typedef struct _n_KFBodywiseOp *KFBodywiseOp;
PETSC_INTERN PetscErrorCode KFBodywiseApplies(KFScene, PetscBool *);
PETSC_INTERN PetscErrorCode KFBodyFactorsCreateShifted(KFSystem, const char[], PetscReal, KFBodyFactors *);
PETSC_INTERN PetscErrorCode KFBodyFactorsCreateShiftedReusing(KFSystem, const char[], PetscReal, KFBodyFactors *); /* sys's own body factors taken over */
PETSC_INTERN PetscErrorCode KFBodywiseOpCreate(KFSystem, KFBodyFactors, KFBodywiseOp *);
PETSC_INTERN PetscErrorCode KFBodywiseOpInertia(KFBodyFactors, KFBodywiseOp, PetscInt *nneg); /* negative pivots of K_S + shift M_S */
PETSC_INTERN PetscErrorCode KFBodywiseOpSolve(KFSystem, KFBodyFactors, KFBodywiseOp, Mat, Mat);
PETSC_INTERN PetscErrorCode KFBodywiseOpDestroy(KFBodywiseOp *);
PETSC_INTERN PetscErrorCode KFHeldDofsOptions(MPI_Comm, const char prefix[], PetscReal *cond_max); /* src/solve/held_dofs.c */
PETSC_INTERN KFSystem       KFFlexSolverSystem_Private(KFFlexSolver); /* the system it solves on (in declarations) */
PETSC_INTERN PetscErrorCode KFFlexSolverSetPerf_Private(KFFlexSolver, const KFFlexSolverPerf *);
PETSC_INTERN PetscErrorCode KFFlexSolverCheckOptions(MPI_Comm, const char prefix[]); /* every option of the flexible solve, before any work */
PETSC_INTERN PetscErrorCode KFRigidTolFromOptions(MPI_Comm, PetscReal *tol); /* src/rigid/rigid.c */
PETSC_INTERN PetscErrorCode KFKrylovProgressOptions(MPI_Comm, PetscInt *progress_min); /* src/krylov/block_arnoldi.c */
/* What is known of the modes before a verification eigensolve (src/verify/eigen.c, KFEPSApplyHint): cut2, the
   omega^2 its modes must reach (0: none, the count asked); count, the modes expected to reach it (0: unknown);
   covered, whether count is what a previous eigensolve took to reach the cut (else the modes it was asked for, all
   below the cut: a lower bound) */
typedef struct {
  PetscReal cut2;
  PetscInt  count;
  PetscBool covered;
  PetscBool krylov_schur; /* Krylov-Schur even where the block path applies: the inertia count found it missed modes */
} KFEigenHint;
/* An M-orthonormal basis kept M-orthogonal to the rigid modes (src/krylov/block_arnoldi.c: the Krylov basis's own
   numerics), for the verification's block eigensolve */
typedef struct _n_KFMOrthBasis *KFMOrthBasis;
PETSC_INTERN PetscErrorCode KFMOrthBasisCreate(KFSystem, PetscInt maxcols, KFMOrthBasis *);
PETSC_INTERN PetscErrorCode KFMOrthBasisAppend(KFMOrthBasis, Mat W, PetscReal tol, PetscInt *ndeflated);
PETSC_INTERN PetscErrorCode KFMOrthBasisReserve(KFMOrthBasis, PetscInt ncols);
PETSC_INTERN PetscErrorCode KFMOrthBasisGetArrays(KFMOrthBasis, PetscInt *k, PetscInt *nl, const PetscScalar **V, const PetscScalar **MV);
PETSC_INTERN PetscErrorCode KFMOrthBasisDestroy(KFMOrthBasis *);
PETSC_INTERN PetscErrorCode KFVerifyEigenOptions(MPI_Comm, PetscInt *dense_max, PetscReal *target, PetscBool *has_target); /* src/verify/eigen.c */
PETSC_INTERN PetscErrorCode KFBlockEigenOptions(MPI_Comm, PetscInt *method, PetscInt *nrand, PetscInt *maxblocks, PetscInt *firstmb); /* src/verify/block_eigen.c */

/* utilities (src/util) */
PETSC_INTERN PetscErrorCode KFDenseGather(Mat, PetscReal[]);             /* replicated column-major copy of a small parallel dense Mat */
PETSC_INTERN PetscErrorCode KFDenseCreate(MPI_Comm, PetscInt nlocal, PetscInt N, PetscInt ncols, Mat *);
PETSC_INTERN PetscErrorCode KFDenseCreateUninitialized(MPI_Comm, PetscInt nlocal, PetscInt N, PetscInt ncols, Mat *); /* no zero fill: the caller writes every entry */
PETSC_INTERN PetscErrorCode KFDenseCopyCreate(Mat A, Mat *B); /* a copy of dense A, without the zero fill first */
PETSC_INTERN PetscErrorCode KFDenseHStack(Mat A, Mat B, Mat *X); /* [A, B]: two tall dense Mats, same row layout */
PETSC_INTERN PetscErrorCode KFMatTransposeMatMultGather(Mat A, Mat B, PetscReal out[]); /* A^T B replicated (A, B tall dense) */
PETSC_INTERN PetscErrorCode KFDenseMultSmall(Mat A, PetscInt r, PetscInt p, const PetscReal c[], PetscReal alpha, Mat X); /* X += alpha A c, c replicated r x p */
PETSC_INTERN PetscErrorCode KFArrayTransposeMultGather(MPI_Comm, PetscInt nl, PetscInt p, const PetscScalar *A, PetscInt lda, PetscInt q, const PetscScalar *B, PetscInt ldb, PetscReal out[]); /* the same on local row blocks */
PETSC_INTERN PetscErrorCode KFArrayMultSmall(PetscInt nl, PetscInt r, PetscInt p, const PetscScalar *A, PetscInt lda, const PetscReal c[], PetscReal alpha, PetscScalar *X, PetscInt ldx);
PETSC_INTERN PetscErrorCode KFArraySkinnyTransposeMult(PetscInt nl, PetscInt nc, const PetscScalar *A, PetscInt lda, PetscInt p, const PetscScalar *X, PetscInt ldx, PetscScalar *out, PetscInt ldo); /* out += A^T X, local rows, chunked: no packing of a tall A */
PETSC_INTERN PetscErrorCode KFArraySkinnyMultSet(PetscInt nl, PetscInt nc, const PetscScalar *A, PetscInt lda, PetscInt p, PetscScalar alpha, const PetscScalar *c, PetscInt ldc, PetscScalar *X, PetscInt ldx); /* X = alpha A c, X not read */
PETSC_INTERN PetscErrorCode KFArraySkinnyMultAdd(PetscInt nl, PetscInt nc, const PetscScalar *A, PetscInt lda, PetscInt p, PetscScalar alpha, const PetscScalar *c, PetscInt ldc, PetscScalar *X, PetscInt ldx); /* X += alpha A c, local rows, chunked */
PETSC_INTERN PetscErrorCode KFMatMultExtended(Mat A, Mat X, Mat *Y); /* Y = A X accumulated in double-double, rounded once */
PETSC_INTERN PetscErrorCode KFMatMultDense(Mat A, Mat X, Mat *Y);    /* Y = A X in double: MatMatMult's bits, faster */
PETSC_INTERN PetscErrorCode KFMatMultDenseInto(Mat A, Mat X, Mat Y); /* the same into the caller's dense Y */
PETSC_INTERN PetscErrorCode KFMatMultBounded(Mat A, Mat X, Mat *Y, Mat *Yb); /* Y = A X in double, Yb bounds its rounding */
/* KFSystemProject with V^T M V given (NULL: formed) (src/project/reduced_system.c) */
PETSC_INTERN PetscErrorCode KFSystemProjectGram_Private(KFSystem, BV V, const PetscReal gram[], PetscReal Mr[], PetscReal Kr[], PetscReal Gr[], PetscReal Hr[]);
PETSC_INTERN PetscErrorCode KFMOrthonormalize(Mat M, Mat X, const char what[]);
PETSC_INTERN PetscErrorCode KFMOrthonormalizeProduct(Mat M, Mat X, PetscInt passes, Mat *MX, const char what[]); /* MX = M X of the result */
PETSC_INTERN PetscErrorCode KFBodyBasisAddMapped(KFBodyBasis, const Mat P[], Mat X); /* X: columns of unit system M-norm */
PETSC_INTERN PetscErrorCode KFBodyBasisAddMappedTo(KFBodyBasis, PetscInt body, Mat Pb, Mat X); /* to one body only */
/* body-wise compression of a reduced model by its assembled response (src/project/body_compress.c): per body the
   kept columns (rigid motions, static response) and the other directions, leading first, M_b-orthonormal in W */
typedef struct {
  PetscInt   v, nkeep, ndir;
  PetscReal *W;      /* v x (nkeep + ndir) */
  PetscReal *weight; /* ndir: each direction's share of the snapshots (singular values) */
} KFBodyDirections;
PETSC_INTERN PetscErrorCode KFBodyCompressDirections(KFReducedModel, PetscInt nconf, const PetscReal angles[], const PetscInt nw[], const PetscReal *const w[], const PetscReal *const inw[], PetscBool static_exact, KFBodyDirections **);
PETSC_INTERN PetscErrorCode KFBodyDirectionsDestroy(PetscInt nb, KFBodyDirections **);
PETSC_INTERN PetscErrorCode KFReducedModelCompress(KFReducedModel, const KFBodyDirections[], const PetscInt counts[], PetscBool with_map, KFReducedModel *);
/* the same across the bodies' stacked coordinates: one set of directions, a model tied to the leading ones */
PETSC_INTERN PetscErrorCode KFTiedCompressDirections(KFReducedModel, PetscInt nconf, const PetscReal angles[], const PetscInt nw[], const PetscReal *const w[], const PetscReal *const inw[], PetscBool static_exact, KFBodyDirections **);
PETSC_INTERN PetscErrorCode KFReducedModelCompressTied(KFReducedModel, const KFBodyDirections *, PetscInt count, PetscBool with_map, KFReducedModel *, PetscInt *k, PetscReal ***C);
/* sub-bases: bases in the span of a finished one, made in its coordinates (src/project/body_basis.c) */
PETSC_INTERN PetscErrorCode KFBodyBasisKeepProducts(KFBodyBasis);
PETSC_INTERN PetscErrorCode KFBodyBasisCoordinates(KFBodyBasis, PetscInt body, Mat Pb, Mat X, PetscReal T[]);
/* the coordinates in a sub-basis of body vectors given in its parent's (v_b x m) */
PETSC_INTERN PetscErrorCode KFBodyBasisSubCoordinates(KFBodyBasis sub, KFBodyBasis parent, PetscInt body, PetscInt m, const PetscReal Y[], PetscReal T[]);
PETSC_INTERN PetscErrorCode KFBodyBasisCreateSub(KFBodyBasis parent, PetscReal tol, const PetscInt m[], PetscReal *const Y[], KFBodyBasis *sub);
PETSC_INTERN PetscErrorCode KFSystemGetMPhi(KFSystem, Mat *); /* M Phi, kept on the system; NULL without rigid modes */
PETSC_INTERN PetscErrorCode KFProjectFlexible(KFSystem, Mat X, PetscBool left); /* X <- (I - Phi Phi^T M) X, or (I - M Phi Phi^T) X if left */
PETSC_INTERN PetscErrorCode KFBodyFindNode(KFBodyData *, PetscInt id, PetscInt *node);
PETSC_INTERN PetscErrorCode KFExprAdd(KFExpr *, PetscInt idx, PetscReal c);
PETSC_INTERN PetscErrorCode KFExprAXPY(KFExpr *, PetscReal a, const KFExpr *);
/* how each body's interface dofs read in system dofs at the system's angles, replicated (src/assemble/body_map.c) */
PETSC_INTERN PetscErrorCode KFSystemInterfaceExprs(KFSystem, KFExpr ***);
PETSC_INTERN PetscErrorCode KFSystemInterfaceExprsDestroy(KFSystem, KFExpr ***);
/* the system's angles set, its matrices not assembled (KFSystemSetAngles assembles): for the interface alone */
PETSC_INTERN PetscErrorCode KFSystemSetInterfaceAngles(KFSystem, const PetscReal[]);
/* node and component (0..5: ux uy uz rx ry rz; KF_COMPONENT_SCALAR for a scalar point) of body dof i */
PETSC_INTERN PetscErrorCode KFBodyDofComponent(KFBodyData *, PetscInt dof, PetscInt *node, PetscInt *comp);
/* the body dof of (node, comp), or -1 when the node has no such component */
PETSC_INTERN PetscInt KFBodyNodeDof(const KFBodyData *, PetscInt node, PetscInt comp);
/* scalar points' rigid-motion values (static condensation); called by KFSceneSetUp */
PETSC_INTERN PetscErrorCode KFSceneScalarRigid(KFScene);
/* the body's rigid motions its boundary conditions allow: Z (6 x rb, column-major, ld 6) combines the 6 body-frame
   motions (ux uy uz rx ry rz about the body origin) into motions that vanish on clamped and spring dofs */
PETSC_INTERN PetscErrorCode KFBodyAdmissibleRigid(KFBodyData *, PetscInt *rb, PetscReal Z[36]);
/* value at (node, comp) of body-frame rigid motion m (0..5) */
PETSC_INTERN PetscReal KFBodyRigidValue(const KFBodyData *, PetscInt node, PetscInt comp, PetscInt m);

PETSC_EXTERN PetscLogEvent KF_EVENT_LOAD, KF_EVENT_ASSEMBLE, KF_EVENT_RIGID, KF_EVENT_FACTOR, KF_EVENT_SOLVE, KF_EVENT_ORTHO, KF_EVENT_PROJECT, KF_EVENT_VERIFY, KF_EVENT_MOMENTS;
PETSC_EXTERN PetscLogEvent KF_EVENT_BODY_BASIS, KF_EVENT_BODY_REDUCE; /* nested in KF_EVENT_ORTHO */

/* option readers that take their help text, manual page and range from the settings table (src/util/settings_read.c):
   inside a PetscOptionsBegin/End block, as PetscOptionsReal and friends; a given value outside the row's range is
   refused naming the option, the value and the range */
PETSC_INTERN PetscErrorCode KFOptionsSettingBool(PetscOptionItems *, const char[], PetscBool, PetscBool *, PetscBool *);
PETSC_INTERN PetscErrorCode KFOptionsSettingInt(PetscOptionItems *, const char[], PetscInt, PetscInt *, PetscBool *);
PETSC_INTERN PetscErrorCode KFOptionsSettingReal(PetscOptionItems *, const char[], PetscReal, PetscReal *, PetscBool *);
PETSC_INTERN PetscErrorCode KFOptionsSettingRealArray(PetscOptionItems *, const char[], PetscReal[], PetscInt *, PetscBool *);
PETSC_INTERN PetscErrorCode KFOptionsSettingString(PetscOptionItems *, const char[], const char[], char[], size_t, PetscBool *);
PETSC_INTERN PetscErrorCode KFOptionsSettingEList(PetscOptionItems *, const char[], const char *const *, PetscInt, const char[], PetscInt *, PetscBool *);
PETSC_INTERN PetscErrorCode KFOptionsSettingEnum(PetscOptionItems *, const char[], const char *const *, PetscEnum, PetscEnum *, PetscBool *);
PETSC_INTERN PetscErrorCode KFOptionsSettingFList(PetscOptionItems *, const char[], PetscFunctionList, const char[], char[], size_t, PetscBool *);
/* a value given another way (a word parsed by hand) checked against the row's range */
PETSC_INTERN PetscErrorCode KFSettingCheckRange(MPI_Comm, const char[], PetscReal);
PETSC_INTERN PetscErrorCode KFStringToAutoBool(const char[], PetscBool *, PetscBool *, PetscBool *);

#endif
