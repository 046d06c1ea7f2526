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
  /* for the accuracy search (Krylov): the projected pencil of the whole basis and where each block ends, so that the
     first c blocks (c moments) are a leading sub-basis; NULL/0 for bases without blocks */
  PetscReal *Kr, *Mr;      /* size x size */
  PetscInt   nblocks, *block_end;
  PetscReal  rigid_content, orthogonality;
  /* the full-order moments its projected pencil matches exactly (the plain block recurrence, nothing deflated: the
     span holds every input and output block), 0 when not known: src/reducer/full_moments.c */
  PetscInt   nmoments;
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
  /* the basis comes in blocks of moments whose leading blocks are sub-bases: the accuracy search applies (cleared
     with the table when the type changes) */
  PetscBool blocks;
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
  void     *candcache; /* the last candidate's finished body basis (visit.c), during a search only */
  PetscErrorCode (*candcache_reset)(KFReducer); /* releases it: set with it, called by KFReducerReset */
  KFScene   scene;
  PetscBool setupcalled, solved;
  KFSystem  given_sys;  /* KFReducerSetSystem: an assembled system of the scene the next solve starts from */
  KFSystem  fresh_sys;  /* that system, taken by the solve and not yet assembled again: its first visit may use it */

  /* what the reduction must serve */
  PetscInt        nconfig;        /* angles of interest: nconfig x nrevolute, radians */
  PetscReal      *angles;
  PetscBool       auto_alpha;     /* alpha_G chosen by the paper's rule */
  PetscReal      *alpha_g;        /* nrevolute (at least 1 entry) */
  PetscInt        nmulti;         /* multi-angle configurations (0: the angles of interest) */
  PetscReal      *multi;
  KFReducerMethod method;
  PetscReal       band[2], zeta, accuracy;
  KFAccuracyMeasure accuracy_measure; /* what the accuracy is stated on (KFFRFElasticErrors) */
  PetscInt        moments, output_blocks;
  KFImportance    importance;
  PetscReal       keep_threshold;
  PetscBool       static_correction;
  PetscReal       deflation_tol, body_tol, reassembly_rtol, shift;
  PetscReal       max_frequency;  /* trimming limit: a multiple of the band's top, or Hz with max_frequency_hz; 0: off */
  PetscBool       max_frequency_hz;
  PetscReal       eigen_cover;    /* eigen type's cover, kept here so that it survives a change of type */
  PetscInt        save_maps;      /* PETSC_TRUE, PETSC_FALSE or PETSC_DECIDE */
  PetscInt        save_maps_max_dofs, gram_condition_max_dofs;
  PetscReal       negligible;     /* a moment below this fraction of its largest value over the angles is zero */
  PetscBool       verify;         /* this solve's references: measured (true) or estimated against the richest candidate */
  PetscBool       verify_auto;    /* -kf_verify auto: measured below verify_certified_min_dofs system dofs, else the
                                     estimate certified by the mode count (src/reducer/certify.c) */
  PetscInt        verify_certified_min_dofs;
  PetscReal       verify_certified_cover; /* the certificate counts modes below this multiple of the band's top */
  PetscReal       verify_certified_min_accuracy; /* auto measures targets tighter than this */
  PetscBool       certify;        /* this solve's estimate is certified (resolved from verify_auto at KFReducerSolve) */
  int             count_fd;       /* -1, or the pipe a helper process writes the certificate's counts to
                                     (KFReducerSetCountSource, src/reducer/certify.c) */
  PetscLogDouble  count_t0;       /* when the helper started */
  PetscInt        verify_modes;   /* PETSC_DECIDE: cover verify_cover x the band's top */
  PetscReal       verify_cover;
  PetscInt        verify_check_points; /* direct solves per evaluation point checking the reference (0: none) */
  PetscReal       verify_check_rtol;   /* their allowed disagreement, a fraction of the pair's peak */
  PetscBool       verify_check_bodywise; /* the undamped check from the bodies' factorizations where it applies */
  PetscBool       verify_check_iterative; /* the check iterated with the reference as preconditioner (refined_check.c) */
  PetscInt        verify_check_iter_points, verify_check_iter_steps, verify_check_iter_steps_max, verify_check_fallbacks;
  PetscReal       verify_check_iter_residual; /* the worst backward error the iterative check took */
  PetscReal       verify_check_worst, verify_check_worst_hz; /* the worst disagreement so far and where (-1: none) */
  PetscLogDouble  verify_check_seconds; /* the direct solves' time, part of the verification's */
  PetscLogDouble  verify_eigen_seconds; /* the reference's eigensolves' time, part of the verification's */
  PetscLogDouble  verify_count_seconds; /* the references' mode counts (-kf_verify_count), part of the verification's */
  KFBodyFactors   count_bf;             /* the bodies' interior factors of K_b - sigma M_b at the count's cut, for every configuration (or NULL) */
  PetscBool       verify_krylov_schur;  /* this reference's eigensolve again by Krylov-Schur: the count found the first missed modes */
  PetscBool       count_bf_made;        /* count_bf tried (NULL then: the count factors the whole system) */
  PetscInt        verify_count;   /* the modes the last sparse reference took to cover its cut (0: none yet): the next
                                     eigensolve's size (KFEigenHint) */
  PetscBool       verify_covered; /* whether they reached it (else they were all the modes asked, below the cut) */
  PetscInt        frequency_points;
  PetscReal       frf_floor_db;
  PetscBool       search;         /* the accuracy search (KFReducerSetSearch) */
  PetscBool       sub_bases;      /* search candidates' body bases in their visit's richest one (-kf_search_sub_bases) */
  PetscInt        moments_max;
  PetscReal       cluster_rtol;
  PetscBool       full_moments, full_moments_set; /* full-order moments by solves: -kf_full_moments, default -kf_verify */
  KFFlexSolverPerf perf;          /* the flexible solvers' work during the solve, summed (KFReducerAddPerf_Private) */
  PetscInt        build_moments;  /* blocks the implementation builds for this solve (moments, or moments_max) */
  PetscInt        max_factorizations; /* expansion points inside the band: factorizations the search may spend on them
                                         (-kf_max_factorizations, 0: moments at zero only) */
  PetscInt        shift_blocks;   /* Krylov blocks per expansion point inside the band (-kf_shift_blocks) */
  PetscBool       compress;       /* the chosen model compressed body by body by its response (-kf_compress) */
  PetscBool       static_exact;   /* compression keeps each body's share of the static response exactly (-kf_static_exact) */
  PetscBool       shift_family_only; /* the best model with expansion points chosen even when not smaller (-kf_shift_family_only) */
  PetscBool       shared_directions; /* every candidate's bodies tied to the kept system vectors' directions (-kf_shared_directions true) */
  PetscBool       shared_auto;       /* -kf_shared_directions auto: each candidate measured split and tied (KFCandidate.tied) */
  KFDamping       damping;        /* what the frequency responses use; zeta above: its equivalent ratio over the band
                                     (KFDampingEffectiveRatio) for the grid and the mode importance */

  /* results of the solve */
  KFReducedModel single, multi_model;
  KFReducerMethod chosen;         /* the family of the model KFReducerGetReducedModel returns */
  KFResultSet   *results;         /* nconfig + 1 sets; the last one holds the whole solve's */
  PetscInt       nnotes;
  char         **notes;
  char           rule[512];
};

PETSC_INTERN PetscErrorCode KFReducerResultSet_Private(KFReducer, PetscInt config, const char name[], PetscInt ndim, const PetscInt shape[], const PetscReal data[]);
PETSC_INTERN PetscErrorCode KFReducerResultScalar_Private(KFReducer, PetscInt config, const char name[], PetscReal value);
PETSC_INTERN PetscErrorCode KFReducerResultsReset_Private(KFReducer);
PETSC_INTERN PetscErrorCode KFReducerConfigLabel_Private(PetscInt nrev, const PetscReal angles[], char buf[], size_t len);
PETSC_INTERN PetscErrorCode KFReducerConfigPlace_Private(PetscInt nrev, const PetscReal angles[], char buf[], size_t len);
PETSC_INTERN PetscErrorCode KFReducerModelSizes_Private(KFReducedModel, char buf[], size_t len);
PETSC_INTERN PetscErrorCode KFReducerNote_Private(KFReducer, const char fmt[], ...);
/* the full-order reference of one configuration of interest, for verification */
typedef struct {
  PetscInt   n, r;           /* flexible modes computed, rigid-body and mechanism modes */
  PetscBool  complete;       /* every flexible mode computed: no residual */
  PetscReal *w2;             /* n */
  PetscReal *HPhi, *PhiG;    /* t x n, n x a */
  PetscReal *HPr, *PrG;      /* t x r, r x a */
  PetscInt   nc;             /* modes coupled by the viscous damping (rigid first, then flexible), 0: none */
  PetscReal *Cm;             /* (r + n) x (r + n): [Phi_r Phi]^T C [Phi_r Phi] of the bodies' C_b, or NULL */
  PetscReal *D;              /* t x a: H Z K_zz^-1 Z^T G, the static response of M's null space Z (dense path), or NULL */
  Mat        V;              /* e x n: the flexible modes themselves (M-orthonormal), kept only until the iterative
                                reference check has used them (src/verify/refined_check.c), else NULL */
  PetscInt   count;          /* flexible modes of the full order below count_hz by the inertia of K_S - sigma M_S
                                (-kf_verify_count, src/verify/mode_count.c), -1: not counted */
  PetscReal  count_hz;
} KFFullReference;
PETSC_INTERN PetscErrorCode KFReducerFullReference_Private(KFReducer, KFSystem, KFFlexSolver, KFFullReference *);
PETSC_INTERN PetscErrorCode KFFullReferenceDestroy_Private(KFFullReference *);
/* errors of the reassembled models against the full order at every configuration of interest (results, notes) */
PETSC_INTERN PetscErrorCode KFReducerRecordSettings_Private(KFReducer, KFReducedModel, KFReducerMethod, PetscInt moments, PetscInt n, const PetscReal angles[]);

/* ---- the accuracy search (src/reducer/visit.c, evaluate.c, search.c) */

/* a configuration the solve visited: its basis (the implementation's data alive), its rigid modes and body maps,
   kept so that candidate models can be made from it after the factorization is gone */
typedef struct {
  PetscReal     *angles;     /* nrev1 */
  PetscInt       interest;   /* index among the angles of interest, -1 if not one */
  PetscBool      is_g, in_multi;
  KFReducerBasis basis;
  Mat            Phir;       /* e x r */
  Mat           *P;          /* per body, n_b x e */
} KFVisit;
PETSC_INTERN PetscErrorCode KFVisitDestroy_Private(KFReducer, KFVisit *);
/* system vectors of the first c blocks of a visit's basis, columns of unit M-norm: the kept clusters (the first kept in
   importance order; -1: the whole sub-basis) plus the static correction of the others; nclusters (may be NULL): the
   clusters of the sub-basis. KFVisitModes_Private: the sub-basis' modes, importance and clusters (caller frees with
   PetscFree4(lambda, Phi, imp, clu)). */
PETSC_INTERN PetscErrorCode KFVisitVectors_Private(KFReducer, KFVisit *, PetscInt c, PetscInt kept, PetscBool static_correction, Mat *X, PetscInt *nclusters);
PETSC_INTERN PetscErrorCode KFVisitModes_Private(KFReducer, KFVisit *, PetscInt c, PetscInt *n, PetscReal **lambda, PetscReal **Phi, PetscReal **imp, PetscInt **clu, PetscInt *nclusters);

#define KF_MAX_EXPANSION 64
#define KF_MAX_BODY_SHARE 64 /* scenes with more bodies keep one kept set for all */
/* Ritz values at or below this fraction of the largest are rigid content, not modes (spurious near-zero modes) */
#define KF_SPURIOUS_RTOL 1e-12
/* the backward error at which a check's solve of the full system is taken as the truth (direct and iterated alike) */
#define KF_CHECK_RESIDUAL 1e-13
typedef struct {
  PetscInt  family;     /* KF_METHOD_SINGLE_ANGLE or KF_METHOD_MULTI_ANGLE */
  PetscInt  c;          /* moments (blocks) */
  PetscInt  kept;       /* clusters kept, -1: the whole basis */
  PetscInt  nexp, exp[KF_MAX_EXPANSION]; /* visits whose bases make the model */
  PetscInt  nbody;      /* > 0: body b keeps its own bkept[b] clusters (its share of the target); 0: kept for all */
  PetscInt  bkept[KF_MAX_BODY_SHARE];
  PetscBool tied;       /* with -kf_shared_directions auto: its bodies tied to its kept vectors (shared directions) */
  PetscBool nostatic;   /* the kept clusters alone, without the static correction of the others (L^0 then measured, not
                           exact: tried only under -kf_static_exact false, for tied candidates) */
  PetscInt  compressed; /* 0: a search candidate; the chosen model compressed (-kf_compress): 1 body by body, 2 tied
                           across the bodies (the search table's rows after the search's) */
  /* after evaluation */
  PetscInt  size, sysdofs;
  PetscReal error;      /* max over the evaluation points (a lower bound when aborted early) */
  PetscBool complete;   /* every evaluation point was measured */
} KFCandidate;
PETSC_INTERN PetscErrorCode KFCandidateModel_Private(KFReducer, KFVisit visits[], const KFCandidate *, PetscBool maps, KFReducedModel *);
/* a's size to compare with b's: its body dofs less its ties, or between a split and a tied candidate (-kf_shared_directions
   auto) its reassembled system dofs, since a tied model's own ties and the joints' overlap */
static inline PetscInt KFCandidateSizeAgainst(const KFCandidate *a, const KFCandidate *b)
{
  return a->tied == b->tied ? a->size : a->sysdofs;
}
PETSC_INTERN PetscErrorCode KFCandidateCacheReset_Private(KFReducer);

/* a configuration where models are measured: an angle of interest or a midpoint, with its reference response */
typedef struct _KFEvalPoint {
  PetscReal      *angles;      /* nrev1 */
  PetscInt        interest;    /* index among the angles of interest, -1 for a midpoint */
  KFFullReference ref;         /* full-order reference (ref.w2 NULL with the estimator) */
  PetscReal      *L0;          /* nmom (1 or 2) x t x a: the first moments of the full order (L^0, L^1) */
  PetscInt        nmom;
  KFReducedSystem rich;        /* the estimator's reference, NULL with the full order */
  PetscInt        nw;
  PetscReal      *fhz, *w, *Tre, *Tim; /* grid (Hz, rad/s) and the reference response, nw blocks of t x a */
  PetscReal      *Tgre, *Tgim; /* its rigid-body and mechanism part on the grid (elastic measure), else NULL */
  PetscInt        nchk;        /* direct solves of the full order (src/verify/direct_check.c) */
  PetscReal      *chk_w, *chk_T, *chk_Ti; /* their frequencies (rad/s) and responses (real, imaginary parts) under the
                                   damping without modal ratios (KFCheckDampingModel_Private), nchk x t x a */
  PetscBool       chk_done;    /* the truth already taken by the iterative check (refined_check.c) */
  Mat             kg;          /* K+ P^T G (e x a) left by the moments (full_moments.c) for the iterative check's first
                                  step, NULL when not left; released by the check */
} KFEvalPoint;
PETSC_INTERN PetscErrorCode KFEvalPointSetUp_Private(KFReducer, KFEvalPoint *);
PETSC_INTERN PetscErrorCode KFReducerReference_Private(KFReducer, KFSystem, KFFlexSolver, PetscInt nmom, const PetscReal L[], KFEvalPoint *);
/* the estimated verdict's certificate by the mode count (src/reducer/certify.c) */
PETSC_INTERN PetscErrorCode KFReducerCertifyCount_Private(KFReducer, KFSystem, PetscBool reuse, PetscInt neval, const KFEvalPoint[], PetscInt count[], PetscInt nrigid[], PetscReal sigma[]);
PETSC_INTERN PetscErrorCode KFReducerCertifyCountRead_Private(KFReducer, PetscInt neval, const KFEvalPoint[], PetscInt count[], PetscInt nrigid[], PetscReal sigma[], PetscBool *got);
PETSC_INTERN PetscErrorCode KFReducerEvalPoints_Private(KFReducer, PetscInt *neval, KFEvalPoint **evals);
PETSC_INTERN PetscErrorCode KFReducerCertifyCompare_Private(KFReducer, PetscInt neval, const KFEvalPoint[], const PetscInt count[], const PetscInt nrigid[], const PetscReal sigma[], PetscBool *certified);
/* the full-order moments at the system's configuration: from its basis (NULL: none) where it matches them, else by
   solves; kg (or NULL): K+ P^T G for the reference check */
PETSC_INTERN PetscErrorCode KFReducerPointMoments_Private(KFReducer, const KFReducerBasis *, KFFlexSolver, PetscInt nmom, PetscReal L[], Mat *kg);
PETSC_INTERN PetscErrorCode KFEvalPointDestroy_Private(KFEvalPoint *);
PETSC_INTERN PetscErrorCode KFReducerDirectChecks_Private(KFReducer, PetscInt, KFEvalPoint[]);
PETSC_INTERN PetscErrorCode KFEvalPointCheckReference_Private(KFReducer, KFEvalPoint *);
PETSC_INTERN PetscErrorCode KFCheckDampingModel_Private(KFReducer, KFDamping *, PetscBool *viscous);
PETSC_INTERN PetscErrorCode KFCheckFrequencies_Private(KFReducer, PetscInt nf, const PetscReal f[], PetscInt npts, PetscReal w[]);
/* the iterative check of one point's reference, while its flexible solver and its modes (ref.V) are alive */
PETSC_INTERN PetscErrorCode KFEvalPointRefinedCheck_Private(KFReducer, KFSystem, KFFlexSolver, KFEvalPoint *);
PETSC_INTERN PetscErrorCode KFCheckRigidEnergy_Private(KFReducer, KFSystem, KFEvalPoint *);
PETSC_INTERN PetscErrorCode KFEvalPointDampedSolves_Private(KFReducer, KFSystem, KFEvalPoint *, const KFDamping *, PetscBool viscous);
/* errors of the reassembled models at every evaluation point (results, notes): nfull moments of the full order per
   angle of interest in Lfull */
PETSC_INTERN PetscErrorCode KFReducerAddPerf_Private(KFReducer, KFFlexSolver);
PETSC_INTERN PetscErrorCode KFReducerCompare_Private(KFReducer, PetscInt nfull, const PetscReal Lfull[], PetscInt neval, KFEvalPoint evals[]);

/* the errors of a reduced system at an evaluation point (KFFRFErrors on its grid, the worst pair's maximum refined
   between grid points); Trre/Trim (nw blocks) may be NULL, or receive the reduced response on the grid */
PETSC_INTERN PetscErrorCode KFEvalPointErrors_Private(KFReducer, KFEvalPoint *, KFReducedSystem, PetscReal *hinf, PetscReal *pointwise, PetscReal Trre[], PetscReal Trim[]);
/* the full-order response of a reference at nw frequencies */
PETSC_INTERN PetscErrorCode KFFullFRF_Private(const KFFullReference *, PetscInt t, PetscInt a, PetscInt nmom, const PetscReal L[], const KFDamping *, const PetscInt quantity[], PetscInt nw, const PetscReal w[], PetscReal Tre[], PetscReal Tim[]);
PETSC_INTERN PetscErrorCode KFFullRigidFRF_Private(const KFFullReference *, PetscInt t, PetscInt a, const KFDamping *, const PetscInt quantity[], PetscInt nw, const PetscReal w[], PetscReal Tre[], PetscReal Tim[]);
/* the equivalent ratio r->zeta of r->damping over r->band (src/reducer/damping.c) */
PETSC_INTERN PetscErrorCode KFReducerDampingUpdate_Private(KFReducer);
/* JSON text of a damping description (src/damping/damping.c) */
PETSC_INTERN PetscErrorCode KFDampingDescribe_Private(const KFDamping *, char buf[], size_t len);
/* the full-order viscous damping of the bodies' C_b in the modal coordinates X (e x m dense): X^T (sum_b P_b^T C_b P_b) X
   (m x m, replicated); *has: whether any body has a C_b */
PETSC_INTERN PetscErrorCode KFSystemProjectDamping_Private(KFSystem, Mat X, PetscBool *has, PetscReal Cm[]);
/* measure a candidate: error over the points (stopping at the first point above stop, stop <= 0: all), sizes */
/* the coordinate ties of a model whose kept system vectors have body coordinates C[b] (v_b x k each): the rows D with
   D [R C] = 0, R the bodies' rigid motions (src/reducer/ties.c), set on the model */
PETSC_INTERN PetscErrorCode KFCandidateTies_Private(KFReducer, KFReducedModel, PetscInt k, PetscReal *const C[]);
PETSC_INTERN PetscErrorCode KFCandidateEvaluate_Private(KFReducer, KFVisit[], PetscInt neval, KFEvalPoint[], PetscReal stop, KFCandidate *);
/* a model's error over the points (the largest hinf; a NaN counts as the largest real), stopping after the first point
   above stop (stop <= 0: every point; the error is then a lower bound), the largest reassembled system's dofs among
   the points measured, and whether every point was measured */
PETSC_INTERN PetscErrorCode KFReducerModelError_Private(KFReducer, KFReducedModel, PetscInt neval, KFEvalPoint[], PetscReal stop, PetscReal *error, PetscInt *sysdofs, PetscBool *complete);
/* expansion points inside the band (src/reducer/shifts.c): after the search over moments, models with the Krylov blocks
   of points sigma = (2 pi f)^2 chosen greedily; visits of those points appended to *visits; the chosen family's
   candidate replaced when such a model is smaller */
PETSC_INTERN PetscErrorCode KFReducerShareBodies_Private(KFReducer, KFVisit[], PetscInt neval, KFEvalPoint[], KFCandidate *);
PETSC_INTERN PetscErrorCode KFReducerSearchShifts_Private(KFReducer, KFSystem, PetscInt *nvisit, KFVisit **visits, PetscInt neval, KFEvalPoint[], KFCandidate *single, KFCandidate *multi, PetscInt *nrows, PetscReal **rows);
/* the chosen model compressed body by body by what its response needs (compress_search.c, -kf_compress): replaced when smaller
   and still meeting the target; its reduced dofs before and after, and whether it keeps the static response (-kf_static_exact) */
PETSC_INTERN PetscErrorCode KFReducerCompress_Private(KFReducer, PetscInt neval, KFEvalPoint[], PetscBool tied, KFReducedModel *, PetscInt *from, PetscInt *to, PetscBool *static_kept, PetscReal *error);
/* the search: the best single-angle and multi-angle candidates (multi->nexp = 0 when none), the rows it tried */
/* split[2]: the best split single-angle and multi-angle candidates (under -kf_shared_directions auto the others may be tied) */
/* the search table (results "search_table"): one row per candidate tried, family, moments c, kept clusters, expansion
   angles, reduced dofs, system dofs, error, variant (KFSearchTableRow_Private) */
#define KF_SEARCH_TABLE_COLUMNS 8
PETSC_INTERN PetscReal      KFCandidateVariant_Private(KFReducer, const KFCandidate *);
PETSC_INTERN void           KFSearchTableRow_Private(KFReducer, const KFCandidate *, PetscReal[]);
PETSC_INTERN PetscErrorCode KFReducerSearch_Private(KFReducer, PetscInt nvisit, KFVisit[], PetscInt neval, KFEvalPoint[], KFCandidate *single, KFCandidate *multi, KFCandidate split[2], PetscInt *nrows, PetscReal **rows);

PETSC_EXTERN PetscLogEvent KF_EVENT_REDUCER_SETUP, KF_EVENT_REDUCER_SOLVE, KF_EVENT_REDUCER_BASIS, KF_EVENT_REDUCER_VERIFY;

PETSC_EXTERN PetscErrorCode KFReducerCreate_Krylov(KFReducer);
PETSC_EXTERN PetscErrorCode KFReducerCreate_Eigen(KFReducer);

#endif
