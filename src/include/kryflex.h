/*
  kryflex: Krylov reduction of articulated multi-flexible-body structures (A. Y. Lee, JPL).

  Stages, one folder each under src/, from the foundations to the reduction that drives them:
    util/      shared helpers: the package initializer (class ids, log events), progress lines, parallel dense
               products in extended precision, interrupts, error recording
    dense/     small dense algebra: Krylov modes, importance, static correction,
               reassembly at any angle (eq. 12-24), moments and frequency responses
    damping/   the damping description (modal, Rayleigh, structural) shared by the reference and the reduced model
    measure/   comparison measures: frequency grids, FRF and moment errors, rigid-mode tolerances
    body/      load and check one body's M and K
    scene/     bodies, joints, inputs, outputs: the tree and its dof maps
    assemble/  P(alpha) by elimination and the full-order system (eq. 2-4)
    rigid/     rigid-body and mechanism modes from geometry
    solve/     the flexible solve operator K+, a PETSc object (KFFlexSolver): MUMPS factorization (mumps.c), held
               dofs, and one implementation per type under solve/impls/ (monolithic, bodywise)
    krylov/    deflated block Krylov basis in the M-inner product (eq. 8-9), raw recurrence
    moments/   low-frequency moments L^k of the full-order system (eq. 5)
    verify/    full-order eigensolve with SLEPc and the direct check of the verification's reference
    project/   reduced system (eq. 10-11) and reduced bodies (eq. 18-19)
    model/     the reduced model (KFReducedModel): reassembly at any angle, trimming, its damping and outputs
    io/        reduced-model files (HDF5): the one writer and the one reader
    reducer/   the reduction as a PETSc object (KFReducer): options, the per-configuration pipeline, the accuracy
               search, the verification; one basis per type under reducer/impls/ (krylov, eigen)
    include/   this header, kryflex_impl.h (private data of the stages) and kryflex/<object>impl.h (the objects' private data)

  Dense arrays in this API are column-major, replicated on every rank.
*/
#ifndef KRYFLEX_H
#define KRYFLEX_H

#include <petscmat.h>
#include <slepcbv.h>

#define KF_MAX_NAME 64

/* ---------------------------------------------------------------- scene */

typedef enum {
  KF_JOINT_REVOLUTE = 0, /* ties 3 translations and the 2 rotations perpendicular to the axis */
  KF_JOINT_FIXED    = 1  /* ties all 6 dofs */
} KFJointType;

/* Node dof components: 0..2 translations x,y,z; 3..5 rotations about x,y,z (body frame). */

typedef struct _n_KFScene *KFScene;

PETSC_EXTERN PetscErrorCode KFInitialize(void); /* registers log events; called by KFSceneCreate */
PETSC_EXTERN PetscErrorCode KFSceneCreate(MPI_Comm, KFScene *);
PETSC_EXTERN PetscErrorCode KFSceneDestroy(KFScene *);
/* M and K are referenced (not copied); nodes: ids, coordinates (3 per node), dofs per node (3 or 6).
   Dofs are ordered node by node in the given order, ux uy uz [rx ry rz]. */
PETSC_EXTERN PetscErrorCode KFSceneAddBody(KFScene, const char name[], Mat M, Mat K, PetscInt nnodes, const PetscInt ids[], const PetscReal xyz[], const PetscInt ndof[], PetscInt *body);
/* Any dof layout: comps[i] is node i's set of components, bit c for component c (0..5: ux uy uz rx ry rz), e.g.
   (1 << 2) | (1 << 3) | (1 << 4) for a plate node carrying uz rx ry (Nastran "c345"); KF_SCALAR_POINT (0) for a scalar
   point (one dof without geometric meaning: its rigid-motion values come from static condensation, and inputs and
   outputs address it as component KF_COMPONENT_SCALAR). Dofs are numbered node by node, components ascending.
   Interface nodes need all six components. */
#define KF_SCALAR_POINT     0
#define KF_COMPONENT_SCALAR 6
#define KF_COMPONENTS_ALL   63
PETSC_EXTERN PetscErrorCode KFSceneAddBodyComponents(KFScene, const char name[], Mat M, Mat K, PetscInt nnodes, const PetscInt ids[], const PetscReal xyz[], const PetscInt comps[], PetscInt *body);
PETSC_EXTERN PetscErrorCode KFSceneAddInterface(KFScene, PetscInt body, const char name[], PetscInt node_id);
/* axis: unit vector in the parent's frame (ignored for fixed joints);
   R0: child frame orientation in the parent frame at angle 0 (column-major 3x3), NULL for identity.
   The child's frame is R(alpha) = Rot(axis, alpha) R0: a child vector v_c reads R v_c in the parent frame.
   Ties (parent node p, child node c): u_p = R u_c ; (theta_p - R theta_c) parallel to axis (revolute). */
PETSC_EXTERN PetscErrorCode KFSceneAddJoint(KFScene, const char name[], KFJointType, PetscInt parent, const char parent_interface[], PetscInt child, const char child_interface[], const PetscReal axis[3], const PetscReal R0[9]);
/* Boundary conditions. KF_GROUND as the parent of KFSceneAddJoint (parent_interface NULL) grounds the child's
   interface node: a fixed joint clamps its 6 dofs, a revolute joint its translations and the rotations perpendicular
   to the axis (the axis, in the child's frame R0^T axis, must lie along one of the child's x, y, z axes). A grounded
   joint has no angle (it turns the whole structure, which no input, output or stiffness sees).
   KFSceneAddConstraint clamps components of a node: dofs a Nastran component string ("123456", "3", "456"), NULL or
   "" for all the node has. KFSceneAddSpring adds a spring to ground of the given stiffness on one component
   (0..5: ux uy uz rx ry rz). The rigid-body and mechanism modes are then derived (geometry restricted to what the
   conditions allow) and checked against K; a scene with none takes a plain Cholesky path. */
#define KF_GROUND (-1)
PETSC_EXTERN PetscErrorCode KFSceneAddConstraint(KFScene, PetscInt body, PetscInt node_id, const char dofs[]);
PETSC_EXTERN PetscErrorCode KFSceneAddSpring(KFScene, PetscInt body, PetscInt node_id, PetscInt component, PetscReal stiffness);
/* rigid-body and mechanism modes of the scene (after a system derived them, e.g. KFSystemComputeRigidModes), else -1 */
PETSC_EXTERN PetscErrorCode KFSceneGetRigidCount(KFScene, PetscInt *nrigid);
PETSC_EXTERN PetscErrorCode KFSceneSetNumIO(KFScene, PetscInt ninputs, PetscInt noutputs);
/* input column j gets weight at (body, node_id, component); several terms may share an input */
PETSC_EXTERN PetscErrorCode KFSceneAddInputLoad(KFScene, PetscInt input, PetscInt body, PetscInt node_id, PetscInt component, PetscReal weight);
PETSC_EXTERN PetscErrorCode KFSceneAddInputVector(KFScene, PetscInt input, PetscInt body, Vec g);
PETSC_EXTERN PetscErrorCode KFSceneAddOutputReading(KFScene, PetscInt output, PetscInt body, PetscInt node_id, PetscInt component, PetscReal weight);
PETSC_EXTERN PetscErrorCode KFSceneAddOutputVector(KFScene, PetscInt output, PetscInt body, Vec h);
/* Checks everything (sizes, symmetry, nodes, joints reach every body, no cycles) and builds dof maps. */
PETSC_EXTERN PetscErrorCode KFSceneSetUp(KFScene);
PETSC_EXTERN PetscErrorCode KFSceneGetInfo(KFScene, PetscInt *nbodies, PetscInt *njoints, PetscInt *nrevolute, PetscInt *nsystem, PetscInt *ninputs, PetscInt *noutputs);
PETSC_EXTERN PetscErrorCode KFSceneGetBodyInfo(KFScene, PetscInt body, const char **name, PetscInt *ndofs, PetscInt *nnodes);
PETSC_EXTERN PetscErrorCode KFSceneGetBodyMatrices(KFScene, PetscInt body, Mat *M, Mat *K, Mat *G, Mat *Ht);
PETSC_EXTERN PetscErrorCode KFSceneGetBodySymmetric(KFScene, PetscInt body, PetscBool *M, PetscBool *K);
PETSC_EXTERN PetscErrorCode KFSceneView(KFScene, PetscViewer);

/* Body matrices from files: PETSc binary (*.petsc, *.bin, *.dat) or Matrix Market (*.mtx), loaded in parallel. */
PETSC_EXTERN PetscErrorCode KFMatLoadFile(MPI_Comm, const char path[], Mat *);
/* Symmetry check: ||A - A^T||_F <= rtol ||A||_F */
PETSC_EXTERN PetscErrorCode KFMatCheckSymmetric(Mat, const char what[], PetscReal rtol);

/* ---------------------------------------------------------------- full-order system at alpha */

typedef struct _n_KFSystem *KFSystem;

/* A system at one configuration. KFSystemSetAngles (re)assembles, reusing the symbolic work. */
PETSC_EXTERN PetscErrorCode KFSystemCreate(KFScene, KFSystem *);
PETSC_EXTERN PetscErrorCode KFSystemDestroy(KFSystem *);
/* one more holder (PetscObjectReference's idiom): KFSystemDestroy frees the system when the last holder lets it go */
PETSC_EXTERN PetscErrorCode KFSystemReference(KFSystem);
/* angles: one per revolute joint, in the order the joints were added, radians */
PETSC_EXTERN PetscErrorCode KFSystemSetAngles(KFSystem, const PetscReal angles[]);
/* how many configurations this system will be solved at (default 1): -kf_flex_solver auto factors the bodies once for
   all of them (the body-wise solve) when there are two or more; the reducer sets it */
PETSC_EXTERN PetscErrorCode KFSystemSetConfigurationCount(KFSystem, PetscInt);
/* Ms, Ks: e x e MPIAIJ; G: e x a MPIDENSE; Ht: e x t MPIDENSE (H^T). Borrowed references. */
PETSC_EXTERN PetscErrorCode KFSystemGetMatrices(KFSystem, Mat *Ms, Mat *Ks, Mat *G, Mat *Ht);
/* P_b: n_b x e MPIAIJ, x_b = P_b x_e. Borrowed. */
PETSC_EXTERN PetscErrorCode KFSystemGetBodyMap(KFSystem, PetscInt body, Mat *P);
/* Rigid-body and mechanism modes (e x r, M-orthonormal). From geometry unless set by the user. */
PETSC_EXTERN PetscErrorCode KFSystemComputeRigidModes(KFSystem);
PETSC_EXTERN PetscErrorCode KFSystemSetRigidModes(KFSystem, Mat Phi);
PETSC_EXTERN PetscErrorCode KFSystemGetRigidModes(KFSystem, Mat *Phi, PetscReal *residual);
PETSC_EXTERN PetscErrorCode KFSystemGetRigidProducts(KFSystem, Mat *KPhi, Mat *MPhi); /* Ks Phi, Ms Phi (borrowed) */

/* ---------------------------------------------------------------- flexible solve operator K+ */

typedef struct _p_KFFlexSolver *KFFlexSolver;

/* K+ applied by factorizations of K_S with a statically determinate set of dofs held (or of K_S + shift M_S), a PETSc
   object with one implementation per type (KFFlexSolverSetType). Options: -kf_shift <sigma>, -kf_refine <steps of
   iterative refinement, 1>, -kf_check_null_pivots, -kf_null_pivot_check_max_dofs <20000>, -kf_held_cond_max <1e8> */
PETSC_EXTERN PetscErrorCode KFFlexSolverCreate(KFSystem, KFFlexSolver *);
PETSC_EXTERN PetscErrorCode KFFlexSolverSetShift(KFFlexSolver, PetscReal);
/* an expansion point inside the band: the solver applies (K_S - sigma M_S)^-1 (sigma > 0, indefinite, MUMPS LDL^T) */
PETSC_EXTERN PetscErrorCode KFFlexSolverSetInteriorShift(KFFlexSolver, PetscReal sigma);
PETSC_EXTERN PetscErrorCode KFFlexSolverSetUp(KFFlexSolver);
/* X = K+ B for a block of right-hand sides (e x p dense) */
PETSC_EXTERN PetscErrorCode KFFlexSolverApply(KFFlexSolver, Mat B, Mat X);
PETSC_EXTERN PetscErrorCode KFFlexSolverDestroy(KFFlexSolver *);
PETSC_EXTERN PetscErrorCode KFFlexSolverGetStats(KFFlexSolver, PetscInt *nheld, PetscInt *null_pivots, PetscInt *negative_pivots);
/* What a flexible solver's work cost: factorization seconds (analysis + numeric) and MUMPS' memory estimate per
   rank (MB, max over ranks), block solves (MatMatSolve calls, columns, seconds, refinement solves among them), and
   the relative residuals ||P B - K_S X||_F / ||P B||_F of each block's first solve (max) and of its final X (max),
   the blocks refined and those whose final residual stayed above -kf_refine_rtol. */
typedef struct {
  PetscLogDouble factor_seconds, solve_seconds;
  PetscReal      memory_estimate_mb, residual_first_max, residual_final_max;
  PetscInt       solve_calls, solve_columns, refinement_solves, blocks, blocks_refined, blocks_unconverged;
  PetscInt       blocks_escalated; /* blocks still above -kf_refine_rtol after the refinement steps: escalated */
} KFFlexSolverPerf;
PETSC_EXTERN PetscErrorCode KFFlexSolverGetPerf(KFFlexSolver, KFFlexSolverPerf *);
/* Which implementation applies K+ (src/solve/impls/<type>/): monolithic (one factorization of K_S per
   configuration), bodywise (one factorization per body interior, kept on the KFSystem for all its configurations, and
   a dense interface problem per configuration: the same K+ B), auto (body-wise where it pays, decided at the set-up).
   -kf_flex_solver overrides KFFlexSolverSetType. New types: KFFlexSolverRegister(name, create), create filling the
   solver's ops table (src/include/kryflex/flexsolverimpl.h). */
typedef const char *KFFlexSolverType;
#define KFFLEXSOLVERAUTO       "auto"
#define KFFLEXSOLVERMONOLITHIC "monolithic"
#define KFFLEXSOLVERBODYWISE   "bodywise"
PETSC_EXTERN PetscErrorCode KFFlexSolverRegister(const char[], PetscErrorCode (*)(KFFlexSolver));
PETSC_EXTERN PetscErrorCode KFFlexSolverSetType(KFFlexSolver, KFFlexSolverType);
/* the implementation set up (after KFFlexSolverSetUp): monolithic or bodywise */
PETSC_EXTERN PetscErrorCode KFFlexSolverGetType(KFFlexSolver, KFFlexSolverType *);
/* options are read with this prefix (a reducer's solvers take the reducer's) */
PETSC_EXTERN PetscErrorCode KFFlexSolverSetOptionsPrefix(KFFlexSolver, const char[]);
PETSC_EXTERN PetscErrorCode KFFlexSolverSetFromOptions(KFFlexSolver);
PETSC_EXTERN PetscErrorCode KFFlexSolverView(KFFlexSolver, PetscViewer);
PETSC_EXTERN PetscErrorCode KFFlexSolverGetSystem(KFFlexSolver, KFSystem *);
/* the body-wise implementation's settings (nothing on another type): bodies spread over the ranks, and the system dofs
   from which auto takes it (-kf_bodywise_spread, -kf_bodywise_min_dofs) */
PETSC_EXTERN PetscErrorCode KFFlexSolverBodywiseSetSpread(KFFlexSolver, PetscBool);
PETSC_EXTERN PetscErrorCode KFFlexSolverBodywiseSetMinDofs(KFFlexSolver, PetscInt);
/* sparse factorizations made for the solves on this system so far (all its configurations; a null-pivot cross-check
   is not counted) */
PETSC_EXTERN PetscErrorCode KFSystemGetFactorCount(KFSystem, PetscInt *);

/* ---------------------------------------------------------------- Krylov basis */

/* Block Arnoldi in the M-inner product: input blocks K+G, (K+M)K+G, ... (nin blocks) and
   output blocks K+H^T, ... (nout blocks); columns deflated below tol (relative). V is e x c, M-orthonormal.
   Matches nin + nout moments. */
PETSC_EXTERN PetscErrorCode KFKrylovBasis(KFFlexSolver, PetscInt nin, PetscInt nout, PetscReal tol, BV *V, PetscInt *ndeflated);
/* The same, block by block, with what the basis is worth: blocks alternate input, output, input ... while both chains
   have blocks left, so the first c blocks span the basis of c moments (block_end[c-1] columns) for every c; each
   column is M-orthogonalized against the basis and the rigid modes (twice), so no rigid content creeps in with c.
   rigid_content = max |Phi_r^T M V|, orthogonality = max |V^T M V - I|, from gram = V^T M V (a fresh product).
   KFKrylovInfoReset frees block_end and gram. */
typedef struct {
  PetscInt   nblocks;       /* blocks of the basis (nin + nout) */
  PetscInt  *block_end;     /* columns of the basis after each block */
  PetscInt   ndeflated;     /* columns dropped as dependent */
  PetscReal  rigid_content, orthogonality;
  PetscReal *gram;          /* V^T M V, size x size column-major, replicated (the reduced mass on V) */
} KFKrylovInfo;
PETSC_EXTERN PetscErrorCode KFKrylovBasisWithInfo(KFFlexSolver, PetscInt nin, PetscInt nout, PetscReal tol, BV *V, KFKrylovInfo *info);
PETSC_EXTERN PetscErrorCode KFKrylovInfoReset(KFKrylovInfo *);
/* The paper's raw recurrence (eq. 9), unorthogonalized, for diagnostics: returns the e x c matrix and the
   condition number of its M-Gram matrix after scaling the columns to unit norm (1/eps once the rank is lost). */
PETSC_EXTERN PetscErrorCode KFKrylovRawBasis(KFFlexSolver, PetscInt nin, PetscInt nout, Mat *Praw, PetscReal *gram_cond);

/* ---------------------------------------------------------------- moments */

/* L^k = H (K+ M)^k K+ G, k = 0..nmom-1, stored L[k*t*a + j*t + i] (t x a column-major per k) */
PETSC_EXTERN PetscErrorCode KFFlexSolverMoments(KFFlexSolver, PetscInt nmom, PetscReal L[]);

/* ---------------------------------------------------------------- projection */

/* Reduced system of eq. (10-11) on a basis V (e x c): Kr, Mr (c x c), Gr (c x a), Hr (t x c), replicated. */
PETSC_EXTERN PetscErrorCode KFSystemProject(KFSystem, BV V, PetscReal Mr[], PetscReal Kr[], PetscReal Gr[], PetscReal Hr[]);
/* Combines BV columns: X = V C (C: c x m column-major), returns a new e x m dense Mat. */
PETSC_EXTERN PetscErrorCode KFBVCombine(BV V, PetscInt m, const PetscReal C[], Mat *X);
/* The same for a tall dense Mat: Y = X C (C: p x m replicated), and the small replicated product A^T B of two tall
   dense Mats with the same row layout. */
PETSC_EXTERN PetscErrorCode KFMatCombine(Mat X, PetscInt m, const PetscReal C[], Mat *Y);
PETSC_EXTERN PetscErrorCode KFMatInner(Mat A, Mat B, PetscReal out[]);

/* Reduced bodies (eq. 18-19). A body basis collects system vectors from one or more configurations,
   projected onto each body (Psi_b = P_b X), then M-orthonormalizes per body with rank deflation. */
typedef struct _n_KFBodyBasis *KFBodyBasis;
PETSC_EXTERN PetscErrorCode KFBodyBasisCreate(KFScene, KFBodyBasis *);
PETSC_EXTERN PetscErrorCode KFBodyBasisAdd(KFBodyBasis, KFSystem, Mat X);
PETSC_EXTERN PetscErrorCode KFBodyBasisFinish(KFBodyBasis, PetscReal tol);
PETSC_EXTERN PetscErrorCode KFBodyBasisDestroy(KFBodyBasis *);
/* After Finish: reduced size v and dense data of body b. Arrays are owned by the basis.
   M, K: v x v; G: v x a; H: t x v; iface: (6 * ninterfaces) x v, rows in interface order, components 0..5;
   rigid: v x 6, the body's own rigid-body motions (from its node coordinates) in reduced coordinates. */
PETSC_EXTERN PetscErrorCode KFBodyBasisGetReduced(KFBodyBasis, PetscInt body, PetscInt *v, const PetscReal **M, const PetscReal **K, const PetscReal **G, const PetscReal **H, PetscInt *ninterfaces, const PetscReal **iface, const PetscReal **rigid, PetscInt *ndeflated);
/* The map back to full dofs: Psi_b (n_b x v dense). Borrowed. */
PETSC_EXTERN PetscErrorCode KFBodyBasisGetMap(KFBodyBasis, PetscInt body, Mat *Psi);

/* ---------------------------------------------------------------- verification eigensolve */

/* Lowest nev flexible modes of (K_S, M_S) with SLEPc (GHEP, shift-and-invert with MUMPS, small negative target,
   rigid modes as deflation space). omega2: eigenvalues; HPhi (t x nconv) and PhiG (nconv x a) column-major,
   arrays sized for nev. Either array may be NULL. */
/* The same eigensolve returning the M-normalized modes (e x min(nev, the flexible modes' count) dense, first nconv
   columns filled): the basis of the eigenvector baseline (EP&A / COMPARE style) that kryflex's Krylov basis replaces. */
PETSC_EXTERN PetscErrorCode KFSystemEigenModes(KFSystem, PetscInt nev, PetscInt *nconv, PetscReal omega2[], Mat *modes);
PETSC_EXTERN PetscErrorCode KFFlexSolverEigenModes(KFFlexSolver, PetscInt nev, PetscInt *nconv, PetscReal omega2[], Mat *modes); /* with its factor */
/* Rigid modes' participation: HPhi (t x r), PhiG (r x a); arrays sized for r = 6 + revolute joints (or the supplied count). */
PETSC_EXTERN PetscErrorCode KFSystemRigidIO(KFSystem, PetscInt *nrigid, PetscReal HPhi[], PetscReal PhiG[]);
PETSC_EXTERN PetscErrorCode KFSystemEigen(KFSystem, PetscInt nev, PetscInt *nconv, PetscReal omega2[], PetscReal HPhi[], PetscReal PhiG[]);
/* Whether the verification eigensolve is dense (LAPACK: every mode at once, -kf_verify_dense_max_dofs) */
PETSC_EXTERN PetscErrorCode KFSystemEigenIsDense(KFSystem, PetscBool *dense);
/* The flexible modes below freq (Hz), from the inertia of one LDL^T of K_S - (2 pi freq)^2 M_S (src/verify/mode_count.c) */
PETSC_EXTERN PetscErrorCode KFSystemCountModesBelow(KFSystem, PetscReal freq, PetscInt *count);

/* ---------------------------------------------------------------- small dense algebra (src/dense) */

/* Generalized symmetric eigenproblem K phi = lambda M phi (M SPD), ascending; Phi M-orthonormal (n x n). */
PETSC_EXTERN PetscErrorCode KFDenseEig(PetscInt n, const PetscReal K[], const PetscReal M[], PetscReal lambda[], PetscReal Phi[]);
/* the same with the r rigid-body and mechanism modes known (Phir, n x r, from geometry): they come first, with
   eigenvalue exactly 0 and M-orthonormalized; the flexible modes are those of the pencil on their M-complement */
PETSC_EXTERN PetscErrorCode KFDenseEigRigid(PetscInt n, const PetscReal K[], const PetscReal M[], PetscInt r, const PetscReal Phir[], PetscReal lambda[], PetscReal Phi[]);

typedef enum {
  KF_IMPORTANCE_H2     = 0, /* ||H phi|| ||phi^T G|| / (2 sqrt(zeta w^3)) */
  KF_IMPORTANCE_HINF   = 1, /* ||H phi|| ||phi^T G|| / (2 zeta w^2) */
  KF_IMPORTANCE_STATIC = 2, /* ||H phi phi^T G|| / w^2 */
  KF_IMPORTANCE_BAND   = 3  /* band-aware and cluster-invariant: KFDenseModeImportanceBand */
} KFImportance;
/* Importance of each mode (n modes, Phi n x n M-orthonormal), normalized by the largest; rigid (lambda <= rigid_tol * max lambda) get 0. */
PETSC_EXTERN PetscErrorCode KFDenseModeImportance(PetscInt n, const PetscReal lambda[], const PetscReal Phi[], PetscInt a, const PetscReal G[], PetscInt t, const PetscReal H[], PetscReal zeta, KFImportance, PetscReal rigid_tol, PetscReal importance[]);
/* Band-aware, cluster-invariant importance: modes whose frequencies lie within cluster_rtol (relative) of each other
   form a cluster; the cluster's residue R = H Phi_C Phi_C^T G (invariant to the basis chosen inside it) gives
   importance = ||R||_2 max_{w in band} 1/|lambda_C - w^2 + 2 i zeta sqrt(lambda_C) w|, normalized by the largest. Every
   mode of a cluster gets its cluster's importance and id (0, 1, ... in ascending frequency); rigid modes
   (lambda <= rigid_tol * max lambda) get importance 0 and cluster -1. band_hz: [fmin, fmax]. */
PETSC_EXTERN PetscErrorCode KFDenseModeImportanceBand(PetscInt n, const PetscReal lambda[], const PetscReal Phi[], PetscInt a, const PetscReal G[], PetscInt t, const PetscReal H[], PetscReal zeta, const PetscReal band_hz[2], PetscReal cluster_rtol, PetscReal rigid_tol, PetscReal importance[], PetscInt cluster[]);
/* Hankel singular values of the damped modal system: n flexible modes (w2 > 0), outputs HPhi (t x n), inputs PhiG
   (n x a), uniform damping zeta, states (q, qdot) per mode; descending, 2n values. No model of first-order order r has
   an H-infinity error below hsv[r]. */
PETSC_EXTERN PetscErrorCode KFModalHankelSingularValues(PetscInt n, const PetscReal w2[], PetscInt t, const PetscReal HPhi[], PetscInt a, const PetscReal PhiG[], PetscReal zeta, PetscReal hsv[]);
/* Static correction (eq. 17): given discarded modes Phid (n x d) with eigenvalues lambdad and G (n x a),
   S = Phid Lambdad^-1 Phid^T G (n x a). */
PETSC_EXTERN PetscErrorCode KFDenseStaticCorrection(PetscInt n, PetscInt d, const PetscReal Phid[], const PetscReal lambdad[], PetscInt a, const PetscReal G[], PetscReal S[]);
/* Null space of D (m x n) by SVD: N (n x h) orthonormal, h = n - rank, rank = #{sigma > rtol sigma_max}.
   N must hold n*n. smin_kept/smax: smallest singular value counted in the rank / largest (reported). */
PETSC_EXTERN PetscErrorCode KFDenseNullSpace(PetscInt m, PetscInt n, const PetscReal D[], PetscReal rtol, PetscInt *h, PetscReal N[], PetscInt *rank, PetscReal *sratio);
/* Moments of a small (possibly singular) system on its flexible subspace: L as in KFFlexSolverMoments.
   KFDenseMoments finds the rigid modes as eigenvalues below rigid_tol (relative); KFDenseMomentsRigid takes them
   (Phir: n x r) and uses solves with K + sigma M Phir Phir^T M, which keeps the digits a stiff model loses in an
   eigendecomposition (its rigid subspace is then only accurate to eps * lambda_max / lambda_1). */
PETSC_EXTERN PetscErrorCode KFDenseMoments(PetscInt n, const PetscReal K[], const PetscReal M[], PetscInt a, const PetscReal G[], PetscInt t, const PetscReal H[], PetscReal rigid_tol, PetscInt nmom, PetscReal L[]);
PETSC_EXTERN PetscErrorCode KFDenseMomentsRigid(PetscInt n, const PetscReal K[], const PetscReal M[], PetscInt a, const PetscReal G[], PetscInt t, const PetscReal H[], PetscInt r, const PetscReal Phir[], PetscInt nmom, PetscReal L[]);
/* Modal frequency response with uniform modal damping zeta (rigid modes undamped, 1/(-w^2)):
   T(w) = sum_i H phi_i phi_i^T G / (lambda_i - w^2 + 2 i zeta sqrt(lambda_i) w), at nw frequencies w (rad/s).
   Tre, Tim: nw blocks of t x a. */
PETSC_EXTERN PetscErrorCode KFModalFRF(PetscInt nmodes, const PetscReal lambda[], PetscInt t, const PetscReal HPhi[], PetscInt a, const PetscReal PhiG[], PetscReal zeta, PetscReal rigid_tol, PetscInt nw, const PetscReal w[], PetscReal Tre[], PetscReal Tim[]);

/* Reassembly of reduced bodies at any angle (eq. 20-24), without the full-order model. */
typedef struct {
  PetscInt         v;          /* reduced size */
  const PetscReal *M, *K;      /* v x v */
  const PetscReal *G;          /* v x a */
  const PetscReal *H;          /* t x v */
  PetscInt         ninterfaces;
  const PetscReal *iface;      /* (6 ninterfaces) x v */
  const PetscReal *rigid;      /* v x 6: the body's rigid-body motions, or NULL if unknown */
  const PetscReal *C;          /* v x v viscous damping, or NULL: read by KFReassembleDamped only */
} KFReducedBody;
typedef struct {
  KFJointType type;
  PetscInt    parent, parent_interface, child, child_interface; /* body indices, interface indices within body */
  PetscReal   axis[3], R0[9];
} KFJointDef;
/* Output: h x h Mh, Kh; h x a Gh; t x h Hh (arrays sized for n = sum v: n*n, n*a, t*n).
   With every body's rigid motions given, also the system's rigid-body and mechanism modes Phir (h x nrigid, array
   sized n*n): the compatible combinations of the bodies' rigid motions. Phir may be NULL; nrigid is -1 when unknown. */
PETSC_EXTERN PetscErrorCode KFReassemble(PetscInt nbodies, const KFReducedBody bodies[], PetscInt njoints, const KFJointDef joints[], const PetscReal angles[], PetscInt a, PetscInt t, PetscReal rtol, PetscInt *h, PetscReal Mh[], PetscReal Kh[], PetscReal Gh[], PetscReal Hh[], PetscInt *rank, PetscReal *sratio, PetscInt *nrigid, PetscReal Phir[]);
/* The joint rotation R(alpha) = Rot(axis, alpha) R0 (column-major 3x3). */
PETSC_EXTERN PetscErrorCode KFJointRotation(const PetscReal axis[3], const PetscReal R0[9], PetscReal alpha, PetscReal R[9]);

/* ---------------------------------------------------------------- reduced system at one configuration */

/* A reassembled reduced model at one configuration: small, dense, replicated on every rank (not a PETSc object:
   plain data with its own Destroy). Arrays are column-major and owned by the system. */
typedef struct _n_KFReducedSystem *KFReducedSystem;
/* n: reduced system dofs; a, t: inputs, outputs; M, K: n x n; G: n x a; H: t x n */
PETSC_EXTERN PetscErrorCode KFReducedSystemGetMatrices(KFReducedSystem, PetscInt *n, PetscInt *a, PetscInt *t, const PetscReal **M, const PetscReal **K, const PetscReal **G, const PetscReal **H);
/* eigenvalues (ascending, n) and M-orthonormal modes (n x n); nrigid: rigid-body and mechanism modes, which come
   from the bodies' stored rigid motions (Phir, n x nrigid), never from the lowest eigenvalues; Phir NULL if unknown */
PETSC_EXTERN PetscErrorCode KFReducedSystemGetModes(KFReducedSystem, const PetscReal **lambda, const PetscReal **Phi, PetscInt *nrigid, const PetscReal **Phir);
/* interface-constraint rank and sigma_min(kept)/sigma_max of the reassembly's SVD */
PETSC_EXTERN PetscErrorCode KFReducedSystemGetReassemblyInfo(KFReducedSystem, PetscInt *rank, PetscReal *sratio);
/* flexible frequencies in Hz (n - nrigid of them, ascending) */
PETSC_EXTERN PetscErrorCode KFReducedSystemGetFrequencies(KFReducedSystem, PetscInt *nf, const PetscReal **freq_hz);
/* moments L^k, k = 0..nmom-1, layout as KFFlexSolverMoments (t x a per k), on the flexible subspace */
PETSC_EXTERN PetscErrorCode KFReducedSystemMoments(KFReducedSystem, PetscInt nmom, PetscReal L[]);
/* Trimming (src/model/trim.c): modes above fmax_hz out of the dynamics, their static share kept as a feedthrough D */
PETSC_EXTERN PetscErrorCode KFReducedSystemTrim(KFReducedSystem, PetscReal fmax_hz);
PETSC_EXTERN PetscErrorCode KFReducedSystemGetTrim(KFReducedSystem, PetscInt *ntrimmed, PetscReal *fmax_hz, PetscReal *ftop_untrimmed_hz, const PetscReal **D);
PETSC_EXTERN PetscErrorCode KFParseMaxFrequency(MPI_Comm, const char text[], PetscReal *value, PetscBool *hz);
/* modal frequency response with uniform modal damping zeta at nw frequencies w (rad/s): nw blocks of t x a */
PETSC_EXTERN PetscErrorCode KFReducedSystemFRF(KFReducedSystem, PetscReal zeta, PetscInt nw, const PetscReal w[], PetscReal Tre[], PetscReal Tim[]);
PETSC_EXTERN PetscErrorCode KFReducedSystemView(KFReducedSystem, PetscViewer);
PETSC_EXTERN PetscErrorCode KFReducedSystemDestroy(KFReducedSystem *);

/* ---------------------------------------------------------------- reduced model (KFReducedModel) */

/* The reduced bodies, how they are jointed, their inputs and outputs, and the settings that made them: everything
   reassembly needs and nothing of the full-order model. A PETSc object (reference counted), the same on every rank.
   Stored as HDF5 (layout in README.md) by one writer, KFReducedModelSave, and read by KFReducedModelLoad. */
typedef struct _p_KFReducedModel *KFReducedModel;
PETSC_EXTERN PetscClassId KF_REDUCEDMODEL_CLASSID;

/* From a finished body basis of a scene; angles: the nangles reduction configurations (nangles x nrevolute,
   radians) the basis was built at. */
PETSC_EXTERN PetscErrorCode KFReducedModelCreateFromBodyBasis(KFScene, KFBodyBasis, PetscInt nangles, const PetscReal angles[], PetscBool keep_maps, KFReducedModel *);
PETSC_EXTERN PetscErrorCode KFReducedModelDestroy(KFReducedModel *);
PETSC_EXTERN PetscErrorCode KFReducedModelView(KFReducedModel, PetscViewer);
PETSC_EXTERN PetscErrorCode KFReducedModelViewFromOptions(KFReducedModel, PetscObject, const char[]);
PETSC_EXTERN PetscErrorCode KFReducedModelGetInfo(KFReducedModel, PetscInt *nbodies, PetscInt *njoints, PetscInt *nrevolute, PetscInt *ninputs, PetscInt *noutputs, PetscInt *nrigid);
PETSC_EXTERN PetscErrorCode KFReducedModelGetSceneName(KFReducedModel, const char **name, const char **fingerprint);
/* the reduction configurations the model was built at: nangles x nrevolute, row by row, radians (owned by the model) */
PETSC_EXTERN PetscErrorCode KFReducedModelGetReductionAngles(KFReducedModel, PetscInt *nangles, const PetscReal **angles);
/* body b: name, full-order dofs, reduced data (arrays owned by the model), map back to full dofs (n_b x v, the
   replicated column-major array, NULL when not kept) */
PETSC_EXTERN PetscErrorCode KFReducedModelGetBody(KFReducedModel, PetscInt b, const char **name, PetscInt *full_dofs, KFReducedBody *body, const PetscReal **map);
PETSC_EXTERN PetscErrorCode KFReducedModelGetInterfaceName(KFReducedModel, PetscInt b, PetscInt i, const char **name);
PETSC_EXTERN PetscErrorCode KFReducedModelGetJoint(KFReducedModel, PetscInt j, const char **name, KFJointDef *joint);
PETSC_EXTERN PetscErrorCode KFReducedModelGetIOName(KFReducedModel, PetscBool input, PetscInt i, const char **name);
/* settings: string key/value pairs recorded by the reducer (method, angles, damping, band, tolerances ...) */
PETSC_EXTERN PetscErrorCode KFReducedModelSetSetting(KFReducedModel, const char key[], const char value[]);
PETSC_EXTERN PetscErrorCode KFReducedModelGetMaxFrequency(KFReducedModel, PetscReal *fmax_hz);
PETSC_EXTERN PetscErrorCode KFReducedModelGetSettings(KFReducedModel, PetscInt *n, const char *const **keys, const char *const **values);
/* reassembly at one configuration (angles: one per revolute joint, radians), eq. 20-24 */
PETSC_EXTERN PetscErrorCode KFReducedModelReassemble(KFReducedModel, const PetscReal angles[], KFReducedSystem *);
/* coordinate ties between the bodies (ms x n, n = sum of the bodies' v), appended to the joints' ties at reassembly */
PETSC_EXTERN PetscErrorCode KFReducedModelSetTies(KFReducedModel, PetscInt ms, PetscInt n, const PetscReal D[]);
PETSC_EXTERN PetscErrorCode KFReducedModelGetTies(KFReducedModel, PetscInt *ms, PetscInt *n, const PetscReal **D);
/* HDF5, written under a temporary name in the same folder and renamed into place (earlier file left intact on
   failure); read with checks of format, version and internal consistency (shapes, names, counts). */
PETSC_EXTERN PetscErrorCode KFReducedModelSave(KFReducedModel, const char path[]);
PETSC_EXTERN PetscErrorCode KFReducedModelLoad(MPI_Comm, const char path[], KFReducedModel *);
/* fingerprint of a scene (bodies, dofs, interfaces, joints, inputs, outputs): 16 hex digits + NUL; a model used
   with a scene must carry the scene's fingerprint */
PETSC_EXTERN PetscErrorCode KFSceneGetFingerprint(KFScene, char fp[17]);
/* name of the scene, recorded in models */
PETSC_EXTERN PetscErrorCode KFSceneSetName(KFScene, const char name[]);
PETSC_EXTERN PetscErrorCode KFSceneGetName(KFScene, const char **name);
PETSC_EXTERN PetscErrorCode KFSceneGetJointInfo(KFScene, PetscInt j, const char **name, KFJointDef *joint);
PETSC_EXTERN PetscErrorCode KFSceneGetInterfaceName(KFScene, PetscInt body, PetscInt i, const char **name);
PETSC_EXTERN PetscErrorCode KFSceneSetIOName(KFScene, PetscBool input, PetscInt i, const char name[]);
PETSC_EXTERN PetscErrorCode KFSceneGetIOName(KFScene, PetscBool input, PetscInt i, const char **name);

/* ---------------------------------------------------------------- error measures (one definition everywhere) */

/* The frequency-response errors of a reduced model, per input/output pair (i, j) over a frequency grid:
   hinf = max_ij max_w |Tf_ij - Tr_ij| / max_w |Tf_ij| (relative H-infinity error: the accuracy target applies to it);
   pointwise = max_ij max_w |Tf_ij - Tr_ij| / max(|Tf_ij(w)|, 10^(floor_db/20) max_w |Tf_ij|) (notch-aware, for
   information). A pair whose peak is below KF_FRF_PAIR_FLOOR (1e-4) of the largest pair's peak is measured against that
   floor times the largest peak.
   T*: nw blocks of t x a, real and imaginary parts; hinf or pointwise may be NULL. */
#define KF_FRF_PAIR_FLOOR 1e-4
/* An elastic pair's denominator is also at least KF_FRF_ELASTIC_FLOOR of the pair's total peak: the reference is
   certified by the direct solves only to -kf_verify_check_rtol (1e-6) of that peak, and an elastic response below it
   (a light body's quasi-static deflection, 5e-8 of the rigid 1/w^2 response) is within the rigid part's rounding */
#define KF_FRF_ELASTIC_FLOOR 1e-6
/* The same measures on the elastic response: every |Tf| above becomes |Tf - Tg|, Tg the rigid-body and mechanism part
   of the full response (from the geometric rigid modes, exact in both models); Tg NULL: the total response
   (KFFRFErrors). KFFRFPairScales: each pair's denominator s_ij (its peak, raised to the floor), top: the largest peak. */
PETSC_EXTERN PetscErrorCode KFFRFElasticErrors(PetscInt nw, PetscInt t, PetscInt a, const PetscReal Tfre[], const PetscReal Tfim[], const PetscReal Trre[], const PetscReal Trim[], const PetscReal Tgre[], const PetscReal Tgim[], PetscReal floor_db, PetscReal *hinf, PetscReal *pointwise);
PETSC_EXTERN PetscErrorCode KFFRFPairScales(PetscInt nw, PetscInt t, PetscInt a, const PetscReal Tfre[], const PetscReal Tfim[], const PetscReal Tgre[], const PetscReal Tgim[], PetscReal scale[], PetscReal *top);
/* Which floor each pair's denominator is (t x a): 0 its own peak, 1 KF_FRF_PAIR_FLOOR x the largest pair's peak, 2
   KF_FRF_ELASTIC_FLOOR x its own total peak */
PETSC_EXTERN PetscErrorCode KFFRFPairFloors(PetscInt nw, PetscInt t, PetscInt a, const PetscReal Tfre[], const PetscReal Tfim[], const PetscReal Tgre[], const PetscReal Tgim[], PetscInt floor[]);
PETSC_EXTERN PetscErrorCode KFFRFErrors(PetscInt nw, PetscInt t, PetscInt a, const PetscReal Tfre[], const PetscReal Tfim[], const PetscReal Trre[], const PetscReal Trim[], PetscReal floor_db, PetscReal *hinf, PetscReal *pointwise);
/* Normwise moment errors ||L_full^k - L_red^k||_F / ||L_full^k||_F per k (NaN where the full moment is negligible,
   below negligible * scale[k]); ratios L_full / L_red entrywise (NaN where negligible or L_red = 0), with the scales
   taken over nconfig configurations (Lall: nconfig blocks of nmom x t x a) so a moment that vanishes at one angle
   by symmetry is not compared by its rounding. */
PETSC_EXTERN PetscErrorCode KFMomentErrors(PetscInt nmom, PetscInt t, PetscInt a, PetscInt nconfig, const PetscReal Lall[], PetscInt config, const PetscReal Lred[], PetscReal negligible, PetscReal errors[], PetscReal ratios[]);
/* A relative tolerance separating the nrigid lowest eigenvalues from the rest (the geometric mean of the last rigid
   and the first flexible eigenvalue, relative to the largest): lambda sorted ascending, n values. */
PETSC_EXTERN PetscErrorCode KFRigidTolerance(PetscInt n, const PetscReal lambda[], PetscInt nrigid, PetscReal *rtol);
/* Log-spaced points over [fmin, fmax] plus 7 points around each resonance in the band (peaks are 1/zeta sharp),
   sorted, unique; f must hold npoints + 7 nres values. */
PETSC_EXTERN PetscErrorCode KFFrequencyGrid(PetscReal fmin, PetscReal fmax, PetscInt npoints, PetscInt nres, const PetscReal fres[], PetscReal zeta, PetscInt *nf, PetscReal f[]);

/* ---------------------------------------------------------------- the reducer (KFReducer) */

/* The whole reduction of a scene as one object, in the manner of KSP: create, set the scene and what the
   reduction must serve, KFReducerSetFromOptions (every option under -kf_, listed by -help), KFReducerSetUp,
   KFReducerSolve, then take the reduced model and the verification results. Implementations (-kf_reducer_type):
   krylov (A. Y. Lee's methodology) and eigen (the eigenvector baseline it replaces, EP&A / COMPARE style). */
typedef struct _p_KFReducer *KFReducer;
typedef const char          *KFReducerType;
#define KFREDUCERKRYLOV "krylov"
#define KFREDUCEREIGEN  "eigen"
PETSC_EXTERN PetscClassId      KF_REDUCER_CLASSID;
PETSC_EXTERN PetscFunctionList KFReducerList;

typedef enum {
  KF_METHOD_SINGLE_ANGLE = 0, /* the paper: one basis at alpha_G, moments exact there */
  KF_METHOD_MULTI_ANGLE  = 1, /* bases at several angles projected together: moments exact at each */
  KF_METHOD_AUTO         = 2  /* the accuracy search chooses: the smaller model of the two that meets the target */
} KFReducerMethod;
PETSC_EXTERN const char *const KFReducerMethods[];
PETSC_EXTERN const char *const KFImportances[];

PETSC_EXTERN PetscErrorCode KFReducerCreate(MPI_Comm, KFReducer *);
PETSC_EXTERN PetscErrorCode KFReducerRegister(const char[], PetscErrorCode (*)(KFReducer));
PETSC_EXTERN PetscErrorCode KFReducerSetType(KFReducer, KFReducerType);
PETSC_EXTERN PetscErrorCode KFReducerGetType(KFReducer, KFReducerType *);
PETSC_EXTERN PetscErrorCode KFReducerSetOptionsPrefix(KFReducer, const char[]);
/* the scene is referenced; it is set up if it is not yet */
PETSC_EXTERN PetscErrorCode KFReducerSetScene(KFReducer, KFScene);
PETSC_EXTERN PetscErrorCode KFReducerGetScene(KFReducer, KFScene *);
/* an assembled system of the reducer's scene (after KFSystemSetAngles) the next KFReducerSolve starts from: at its
   first configuration, where the angles are the system's, the solve takes its matrices and rigid modes instead of
   making them again. Referenced until that solve ends, which assembles the system at its other configurations.
   Collective; NULL drops one given before */
PETSC_EXTERN PetscErrorCode KFReducerSetSystem(KFReducer, KFSystem);
/* angles of interest: nconfig configurations of nrevolute angles each (radians), row by row */
PETSC_EXTERN PetscErrorCode KFReducerSetAngles(KFReducer, PetscInt nconfig, const PetscReal angles[]);
/* the angles of interest as the reducer has them (after KFReducerSetFromOptions: -kf_angles); owned by the reducer */
PETSC_EXTERN PetscErrorCode KFReducerGetAngles(KFReducer, PetscInt *nconfig, const PetscReal **angles);
/* alpha_G of the single-angle model (nrevolute angles, radians); NULL: the paper's rule chooses it among the angles
   of interest (-kf_reduction_angle, degrees, or auto) */
PETSC_EXTERN PetscErrorCode KFReducerSetReductionAngle(KFReducer, const PetscReal angles[]);
/* the configurations whose Krylov bases make the multi-angle model (n x nrevolute, radians); n = 0: the angles of
   interest (-kf_multi_angles, degrees, flattened) */
PETSC_EXTERN PetscErrorCode KFReducerSetMultiAngles(KFReducer, PetscInt n, const PetscReal angles[]);
PETSC_EXTERN PetscErrorCode KFReducerSetMethod(KFReducer, KFReducerMethod);
PETSC_EXTERN PetscErrorCode KFReducerSetBand(KFReducer, PetscReal fmin_hz, PetscReal fmax_hz);
PETSC_EXTERN PetscErrorCode KFReducerSetDamping(KFReducer, PetscReal zeta);
PETSC_EXTERN PetscErrorCode KFReducerSetAccuracy(KFReducer, PetscReal target);
/* what the accuracy is stated on: the elastic response (the total minus its rigid-body and mechanism part, the
   default) or the total response (KFFRFElasticErrors) */
typedef enum {
  KF_ACCURACY_ELASTIC,
  KF_ACCURACY_TOTAL
} KFAccuracyMeasure;
PETSC_EXTERN const char *const KFAccuracyMeasures[];
PETSC_EXTERN PetscErrorCode KFReducerSetAccuracyMeasure(KFReducer, KFAccuracyMeasure);
PETSC_EXTERN PetscErrorCode KFReducerGetAccuracyMeasure(KFReducer, KFAccuracyMeasure *);
/* moments matched (c in the paper), of which nout are blocks started from K+ H^T; moments PETSC_DECIDE: the accuracy
   search chooses (up to -kf_moments_max) */
PETSC_EXTERN PetscErrorCode KFReducerSetMoments(KFReducer, PetscInt moments, PetscInt output_blocks);
/* The accuracy search (default on): the smallest model (moments, single- or multi-angle basis and its expansion
   angles, kept clusters of Krylov modes) whose relative H-infinity error (KFFRFErrors) meets the accuracy at every
   angle of interest and every midpoint between them, against the full order (or, verification off, the richest
   candidate as an estimator). Off: the paper's fixed recipe (moments, keep threshold, its alpha_G rule).
   moments_max: the most moments the search tries (-kf_moments_max, 24). */
PETSC_EXTERN PetscErrorCode KFReducerSetSearch(KFReducer, PetscBool search, PetscInt moments_max);
/* After the search: the chosen model compressed body by body, each body truncated to the fewest of its directions
   (ordered by their share of the reassembled model's response, rigid motions and static response kept exactly) that
   still meet the accuracy, when that is smaller (-kf_compress) */
PETSC_EXTERN PetscErrorCode KFReducerSetCompress(KFReducer, PetscBool compress);
/* Whether the compression keeps the static moment L^0 exact (default) or truncates the static response like the rest
   of the response, L^0 then measured (-kf_static_exact) */
PETSC_EXTERN PetscErrorCode KFReducerSetStaticExact(KFReducer, PetscBool exact);
/* Krylov modes whose frequencies lie within rtol (relative) of each other form a cluster, kept or dropped whole
   (-kf_cluster_rtol, 1e-3) */
PETSC_EXTERN PetscErrorCode KFReducerSetClusterTolerance(KFReducer, PetscReal rtol);
PETSC_EXTERN PetscErrorCode KFReducerSetImportance(KFReducer, KFImportance, PetscReal keep_threshold);
PETSC_EXTERN PetscErrorCode KFReducerSetStaticCorrection(KFReducer, PetscBool);
PETSC_EXTERN PetscErrorCode KFReducerSetTolerances(KFReducer, PetscReal deflation_tol, PetscReal body_tol, PetscReal reassembly_rtol);
PETSC_EXTERN PetscErrorCode KFReducerSetMaxFrequency(KFReducer, PetscReal value, PetscBool hz);
PETSC_EXTERN PetscErrorCode KFReducerGetMaxFrequency(KFReducer, PetscReal *fmax_hz);
PETSC_EXTERN PetscErrorCode KFReducerSetShift(KFReducer, PetscReal shift);
/* keep each reduced body's map back to its full dofs in the model: PETSC_TRUE, PETSC_FALSE, or PETSC_DECIDE (keep it
   while no body has more than -kf_save_maps_max_dofs dofs, 200000) */
PETSC_EXTERN PetscErrorCode KFReducerSetSaveMaps(KFReducer, PetscInt);
/* eigen type: full-order modes up to cover x the band's top frequency (-kf_eigen_cover, 1); kept whatever the type */
PETSC_EXTERN PetscErrorCode KFReducerEigenSetCover(KFReducer, PetscReal cover);
/* full-order verification: on/off, modes (PETSC_DECIDE: cover 3 x the band's top), frequency points, FRF floor (dB) */
PETSC_EXTERN PetscErrorCode KFReducerSetVerification(KFReducer, PetscBool full_order, PetscInt modes, PetscInt frequency_points, PetscReal frf_floor_db);
/* the verdict by size (-kf_verify auto, the default): measured below min_dofs system dofs, from there the estimate
   certified by the mode count (measured where it cannot certify); min_dofs PETSC_DECIDE keeps the current (50000) */
PETSC_EXTERN PetscErrorCode KFReducerSetVerificationAuto(KFReducer, PetscInt min_dofs);
/* the verdict KFReducerSolve will give, resolved from -kf_verify auto before it starts: measured against the full
   order, or the estimate certified by the mode count (which may still fall back to measuring) */
PETSC_EXTERN PetscErrorCode KFReducerGetVerificationPlan(KFReducer, PetscBool *measured, PetscBool *certified);
/* the certificate's counts made beside the reduction: a helper process writes them (KFReducerCertifyCountWrite) to
   a pipe whose read end the solve reads them from at the count (KFReducerSetCountSource; -1: count in-process) */
PETSC_EXTERN PetscErrorCode KFReducerSetCountSource(KFReducer, int fd);
PETSC_EXTERN PetscErrorCode KFReducerCertifyCountWrite(KFReducer, int fd);
PETSC_EXTERN PetscErrorCode KFReducerSetFromOptions(KFReducer);
PETSC_EXTERN PetscErrorCode KFReducerSetUp(KFReducer);
PETSC_EXTERN PetscErrorCode KFReducerSolve(KFReducer);
PETSC_EXTERN PetscErrorCode KFReducerView(KFReducer, PetscViewer);
PETSC_EXTERN PetscErrorCode KFReducerViewFromOptions(KFReducer, PetscObject, const char[]);
/* releases the results, models and caches of the last solve; the settings stay */
PETSC_EXTERN PetscErrorCode KFReducerReset(KFReducer);
PETSC_EXTERN PetscErrorCode KFReducerDestroy(KFReducer *);
/* after Solve: the model of the chosen method (borrowed); both models (multi NULL when not built) */
PETSC_EXTERN PetscErrorCode KFReducerGetReducedModel(KFReducer, KFReducedModel *);
PETSC_EXTERN PetscErrorCode KFReducerGetReducedModels(KFReducer, KFReducedModel *single_angle, KFReducedModel *multi_angle);
/* Results of the solve as named arrays, replicated, column-major over shape (ndim <= 3). config: index into the
   angles of interest, or -1 for the results of the whole solve. Names and meanings are listed in README.md
   ("Results of a reduction"); KFReducerGetResultNames enumerates what a solve recorded. */
PETSC_EXTERN PetscErrorCode KFReducerGetResultNames(KFReducer, PetscInt config, PetscInt *n, const char *const **names);
PETSC_EXTERN PetscErrorCode KFReducerGetResult(KFReducer, PetscInt config, const char name[], PetscInt *ndim, const PetscInt **shape, const PetscReal **data);
/* notes a user should read (moments not matched, rigid-mode counts ...) and the rule that chose alpha_G */
PETSC_EXTERN PetscErrorCode KFReducerGetNotes(KFReducer, PetscInt *n, const char *const **notes);
PETSC_EXTERN PetscErrorCode KFReducerGetReductionRule(KFReducer, const char **rule);

/* ---------------------------------------------------------------- progress */
/* Progress lines with elapsed time on rank 0, unless -kf_quiet. */
PETSC_EXTERN PetscErrorCode KFProgress(MPI_Comm, const char fmt[], ...);

/* Error messages for bindings: after KFPushErrorRecorder(), KFLastError() holds the first message of a failed call. */
PETSC_EXTERN PetscErrorCode KFPushErrorRecorder(void);
PETSC_EXTERN const char    *KFLastError(void);
PETSC_EXTERN void           KFClearError(void);

/* Interrupts (SIGINT, SIGTERM) for a command that wants long work to stop cleanly: KFInterruptCatch() installs
   handlers that only note the signal (a second identical signal ends the process at once, as without them);
   KFInterruptCheck(comm), called at stage boundaries of the reducer (per configuration, per Krylov block), is
   collective: every rank stops at the same point with the error KF_ERR_INTERRUPTED ("interrupted by SIGINT").
   Library users who do not call KFInterruptCatch keep their own signal handling; the checks then cost one
   allreduce of an int. KFInterruptSignal() is the signal noted (0: none). */
#define KF_ERR_INTERRUPTED 190 /* outside PETSc's error codes */
PETSC_EXTERN PetscErrorCode KFInterruptCatch(void);
PETSC_EXTERN PetscErrorCode KFInterruptCheck(MPI_Comm);
PETSC_EXTERN int            KFInterruptSignal(void);

/* ---------------------------------------------------------------- damping and output quantities */

/* The damping of a model beside the bodies' viscous matrices C_b (KFSceneSetBodyDamping), the same for the full-order
   reference and the reduced model:
   modal: ratio zeta[k] for the modes with frequency <= fmax_hz[k] (bands ascending; a mode takes the first band that
     holds it, modes above the last band take its ratio), in the undamped modal coordinates of each model (the full
     order's and the reduced one's); rigid-body and mechanism modes get none. Uniform: one band, fmax_hz = infinity.
   Rayleigh: C += alpha M + beta K (exact under projection: Psi^T (alpha M + beta K) Psi = alpha M_r + beta K_r).
   structural (hysteretic): K (1 + i g) on the flexible modes. */
#define KF_MAX_DAMPING_BANDS 16
typedef struct {
  PetscInt  nbands;
  PetscReal fmax_hz[KF_MAX_DAMPING_BANDS], zeta[KF_MAX_DAMPING_BANDS];
  PetscReal alpha, beta, g;
} KFDamping;
/* uniform modal damping zeta, no Rayleigh, no structural damping */
PETSC_EXTERN PetscErrorCode KFDampingSetUniform(KFDamping *, PetscReal zeta);
/* collective checks with messages naming the key to fix: ratios in [0, 1), bands ascending, alpha, beta, g >= 0 */
PETSC_EXTERN PetscErrorCode KFDampingCheck(MPI_Comm, const KFDamping *);
/* the modal damping ratio of a mode of frequency f_hz */
PETSC_EXTERN PetscReal      KFDampingModalRatio(const KFDamping *, PetscReal f_hz);
/* one equivalent ratio over the band (for the frequency grid and the mode importance, which need one): the smallest
   over the band's ends and the bands' edges of modal + Rayleigh (alpha / 2w + beta w / 2) + g / 2, floored at 1e-4 */
PETSC_EXTERN PetscErrorCode KFDampingEffectiveRatio(const KFDamping *, const PetscReal band_hz[2], PetscReal *zeta);

/* What an output reads: displacement x, velocity i w x or acceleration -w^2 x (frequency responses only; the moments
   are those of the displacement map) */
typedef enum {
  KF_QUANTITY_DISPLACEMENT = 0,
  KF_QUANTITY_VELOCITY     = 1,
  KF_QUANTITY_ACCELERATION = 2
} KFQuantity;
PETSC_EXTERN const char *const KFQuantities[];
/* a body's viscous damping matrix C_b (n_b x n_b, symmetric, same row layout as its M), referenced; NULL removes it */
PETSC_EXTERN PetscErrorCode KFSceneSetBodyDamping(KFScene, PetscInt body, Mat C);
PETSC_EXTERN PetscErrorCode KFSceneGetBodyDamping(KFScene, PetscInt body, Mat *C);
PETSC_EXTERN PetscErrorCode KFSceneSetOutputQuantity(KFScene, PetscInt output, KFQuantity);
PETSC_EXTERN PetscErrorCode KFSceneGetOutputQuantity(KFScene, PetscInt output, KFQuantity *);

/* Damped frequency response in undamped modal coordinates (n modes, lambda ascending, HPhi t x n, PhiG n x a):
   T(w) = diag((i w)^q_i) HPhi Z(w)^-1 PhiG, Z = diag(lambda_k (1 + i g) - w^2 + i w (2 zeta_k sqrt(lambda_k) + alpha +
   beta lambda_k)) + i w Cm. Cm: the viscous damping in modal coordinates (n x n, Phi^T C Phi) or NULL; with Cm the
   first ncoupled modes are solved together (one complex LU per frequency, ncoupled^3), the others keep Cm's diagonal.
   Rigid modes (lambda <= rigid_tol max lambda) count as lambda = 0: no modal, stiffness or structural damping.
   quantity: per output a KFQuantity, NULL for displacements. Tre, Tim: nw blocks of t x a. */
PETSC_EXTERN PetscErrorCode KFDampedModalFRF(PetscInt n, const PetscReal lambda[], PetscInt t, const PetscReal HPhi[], PetscInt a, const PetscReal PhiG[], const KFDamping *, const PetscReal Cm[], PetscInt ncoupled, const PetscInt quantity[], PetscReal rigid_tol, PetscInt nw, const PetscReal w[], PetscReal Tre[], PetscReal Tim[]);
/* KFReassemble that also reassembles the bodies' viscous damping (KFReducedBody.C, NULL for none) into Ch (h x h,
   sized n*n); Ch NULL: KFReassemble */
PETSC_EXTERN PetscErrorCode KFReassembleDamped(PetscInt nbodies, const KFReducedBody bodies[], PetscInt njoints, const KFJointDef joints[], const PetscReal angles[], PetscInt a, PetscInt t, PetscReal rtol, PetscInt *h, PetscReal Mh[], PetscReal Kh[], PetscReal Ch[], PetscReal Gh[], PetscReal Hh[], PetscInt *rank, PetscReal *sratio, PetscInt *nrigid, PetscReal Phir[]);
/* KFReassembleDamped with ms coordinate ties Ds (ms x n, n = sum of the bodies' v; angle-independent rows appended to
   the joints' ties: a reduced model's shared directions); ms 0: KFReassembleDamped */
PETSC_EXTERN PetscErrorCode KFReassembleTied(PetscInt nbodies, const KFReducedBody bodies[], PetscInt njoints, const KFJointDef joints[], PetscInt ms, const PetscReal Ds[], const PetscReal angles[], PetscInt a, PetscInt t, PetscReal rtol, PetscInt *h, PetscReal Mh[], PetscReal Kh[], PetscReal Ch[], PetscReal Gh[], PetscReal Hh[], PetscInt *rank, PetscReal *sratio, PetscInt *nrigid, PetscReal Phir[]);
/* Reassembly at changing angles without allocation (a simulation reassembles at every time step): a workspace made
   once for the bodies and joints (their arrays are copied), then KFReassemblyApply at each angle into the caller's
   arrays, and KFReassemblyEig for the eigen-decomposition when it is wanted. Plain data, not a PETSc object; one per
   thread. Where the joints form a tree whose bodies see their interface motions, Apply takes a closed form made at
   creation (no SVD per call): KFReassembleDamped's system in another, non-orthonormal basis of the same null space
   (same eigenvalues and transfer functions). KFReassemblySetUseSVD(r, PETSC_TRUE): exactly KFReassembleDamped's
   arrays (plus Rayleigh alpha M + beta K in Ch). The rank, sigma ratio and rigid modes, when asked for, cost an SVD
   of the ties on either path. */
typedef struct _n_KFReassembly *KFReassembly;
PETSC_EXTERN PetscErrorCode KFReassemblyCreate(PetscInt nbodies, const KFReducedBody bodies[], PetscInt njoints, const KFJointDef joints[], PetscInt a, PetscInt t, PetscReal rtol, PetscReal alpha, PetscReal beta, KFReassembly *);
/* with ms coordinate ties Ds (ms x n) appended to the joints' (no closed form: every call takes the SVD path) */
PETSC_EXTERN PetscErrorCode KFReassemblyCreateTied(PetscInt nbodies, const KFReducedBody bodies[], PetscInt njoints, const KFJointDef joints[], PetscInt ms, const PetscReal Ds[], PetscInt a, PetscInt t, PetscReal rtol, PetscReal alpha, PetscReal beta, KFReassembly *);
/* n: the largest reassembled size (outputs sized n n, n a, t n); viscous: some body has a damping matrix; rigid: the
   bodies' rigid motions are known (Apply returns Phir) */
PETSC_EXTERN PetscErrorCode KFReassemblyGetSizes(KFReassembly, PetscInt *n, PetscInt *a, PetscInt *t, PetscBool *viscous, PetscBool *rigid);
PETSC_EXTERN PetscErrorCode KFReassemblyApply(KFReassembly, const PetscReal angles[], PetscInt *h, PetscReal Mh[], PetscReal Kh[], PetscReal Ch[], PetscReal Gh[], PetscReal Hh[], PetscInt *rank, PetscReal *sratio, PetscInt *nrigid, PetscReal Phir[]);
/* eigenvalues (h, ascending) and M-orthonormal modes (h x h) of the pencil Apply returned; with Phir (nrigid >= 0) the
   rigid modes as given (KFDenseEigRigid), otherwise the whole pencil (KFDenseEig) */
PETSC_EXTERN PetscErrorCode KFReassemblyEig(KFReassembly, PetscInt h, const PetscReal Mh[], const PetscReal Kh[], PetscInt nrigid, const PetscReal Phir[], PetscReal lambda[], PetscReal Phi[]);
PETSC_EXTERN PetscErrorCode KFReassemblyDestroy(KFReassembly *);
/* the null space by SVD at every call (PETSC_TRUE) or in closed form on trees of bodies (PETSC_FALSE, the default) */
PETSC_EXTERN PetscErrorCode KFReassemblySetUseSVD(KFReassembly, PetscBool svd);
PETSC_EXTERN PetscErrorCode KFReassemblyGetUseSVD(KFReassembly, PetscBool *svd);
/* the workspace of KFReassemblyApply for this model: its bodies, joints, reassembly_rtol and Rayleigh damping (the
   rigid count when the bodies' rigid motions are unknown: KFReducedModelGetInfo's nrigid) */
PETSC_EXTERN PetscErrorCode KFReducedModelCreateReassembly(KFReducedModel, KFReassembly *);
/* the model's damping (what its frequency responses use) and its outputs' quantities (t values) */
PETSC_EXTERN PetscErrorCode KFReducedModelSetDamping(KFReducedModel, const KFDamping *);
PETSC_EXTERN PetscErrorCode KFReducedModelGetDamping(KFReducedModel, KFDamping *);
PETSC_EXTERN PetscErrorCode KFReducedModelGetOutputQuantities(KFReducedModel, const PetscInt **quantity);
/* body b's reduced viscous damping Psi_b^T C_b Psi_b (v x v), NULL when the body has none */
PETSC_EXTERN PetscErrorCode KFReducedModelGetBodyDamping(KFReducedModel, PetscInt b, const PetscReal **C);
/* the reduced system's viscous damping matrix (n x n: the bodies' C_b reassembled plus alpha M + beta K; NULL when
   there is none) and the model's damping */
PETSC_EXTERN PetscErrorCode KFReducedSystemGetDamping(KFReducedSystem, const PetscReal **C, KFDamping *);
/* the frequency response with the model's damping (KFReducedModelGetDamping, the viscous matrix) and output
   quantities at nw frequencies w (rad/s): nw blocks of t x a. KFReducedSystemFRF is uniform modal damping only. */
PETSC_EXTERN PetscErrorCode KFReducedSystemResponse(KFReducedSystem, PetscInt nw, const PetscReal w[], PetscReal Tre[], PetscReal Tim[]);
/* the rigid-body and mechanism part of that response: its nrigid lowest modes with the same damping model */
PETSC_EXTERN PetscErrorCode KFReducedSystemRigidResponse(KFReducedSystem, PetscInt nw, const PetscReal w[], PetscReal Tre[], PetscReal Tim[]);
/* the reducer's damping (KFReducerSetDamping sets a uniform modal ratio); options -kf_damping zeta,
   -kf_damping_bands f1,z1,f2,z2,..., -kf_damping_rayleigh alpha,beta, -kf_damping_structural g */
PETSC_EXTERN PetscErrorCode KFReducerSetDampingModel(KFReducer, const KFDamping *);
PETSC_EXTERN PetscErrorCode KFReducerGetDampingModel(KFReducer, KFDamping *);

/* ---------------------------------------------------------------- settings (src/util/settings_table.c) */
/* every -kf_ option, one row each: what the readers, the binding, the scene schema, the command and the manual use */
typedef enum {
  KF_SETTING_BOOL,
  KF_SETTING_INT,
  KF_SETTING_REAL,
  KF_SETTING_ENUM,   /* one of choices */
  KF_SETTING_STRING,
  KF_SETTING_LIST    /* comma-separated numbers */
} KFSettingType;
PETSC_EXTERN const char *const KFSettingTypes[];
typedef struct {
  const char   *name;    /* the option, "-kf_accuracy" */
  KFSettingType type;
  const char   *def;     /* the default as text; auto, none: decided at run time, "": no default */
  const char   *range;   /* an interval of the value (of each entry of a list), "(0, 1]", "[0, inf)"; NULL: any */
  const char   *choices; /* an enum's values, space-separated; of a number or list: the words it also takes (auto) */
  const char   *help;
  const char   *scene;   /* the scene file's key of the same setting ("reduction.moments"); NULL: none */
  const char   *object;  /* who reads it (KFReducer, KFFlexSolver, ...) */
  const char   *setter;  /* the C function that sets it */
} KFSettingInfo;
PETSC_EXTERN PetscErrorCode KFSettingsTableGet(const KFSettingInfo **, PetscInt *);
/* the row of an option ("-kf_accuracy"); NULL when there is none */
PETSC_EXTERN PetscErrorCode KFSettingFind(const char[], const KFSettingInfo **);

#endif
