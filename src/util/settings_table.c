/* The one table of kryflex's settings: every -kf_ option with its type, default, range or choices, help text, scene
   file key and reader. The readers take their help text and range from here (KFOptionsSetting*), the binding hands
   the table to Python (the scene schema's defaults, choices and JSON Schema, the command's list of known options, the
   manual's reference pages), so a setting is added by one row here and the line of its reader that stores it. */
#include <kryflex_impl.h>

const char *const KFSettingTypes[] = {"bool", "int", "real", "enum", "string", "list", "KFSettingType", "KF_SETTING_", NULL};

#define TB KF_SETTING_BOOL
#define TI KF_SETTING_INT
#define TR KF_SETTING_REAL
#define TE KF_SETTING_ENUM
#define TS KF_SETTING_STRING
#define TL KF_SETTING_LIST

/* name, type, default (auto, none: decided at run time), range, choices (an enum's values; the words a number or a
   list also takes), help, scene key, reader, setter */
static const KFSettingInfo KFSettings[] = {
  /* the reducer (KFReducerSetFromOptions, src/reducer/options.c) */
  {"-kf_reducer_type", TE, "krylov", NULL, "krylov eigen", "Basis: krylov (Lee's Krylov methodology) or eigen (the eigenvector baseline)", "reduction.basis", "KFReducer", "KFReducerSetType"},
  {"-kf_angles", TL, "", "[-360, 360]", NULL, "Angles of interest in degrees, one per revolute joint per configuration, comma-separated", "angles", "KFReducer", "KFReducerSetAngles"},
  {"-kf_reduction_angle", TL, "auto", "[-360, 360]", "auto", "alpha_G of the single-angle model in degrees (one per revolute joint), or auto: the paper's rule", "reduction.reduction_angle", "KFReducer", "KFReducerSetReductionAngle"},
  {"-kf_multi_angles", TL, "none", "[-360, 360]", NULL, "Configurations of the multi-angle basis in degrees (default: the angles of interest)", "reduction.reduction_angles", "KFReducer", "KFReducerSetMultiAngles"},
  {"-kf_method", TE, "auto", NULL, "auto single-angle multi-angle", "auto (the smaller model that meets the accuracy), single-angle (the paper: one basis at alpha_G) or multi-angle (bases at several angles)", "reduction.method", "KFReducer", "KFReducerSetMethod"},
  {"-kf_band", TL, "0.01,10", "(0, inf)", NULL, "Frequency band of interest in Hz: low,high (default 0.01,10)", "band", "KFReducer", "KFReducerSetBand"},
  {"-kf_damping", TR, "0.0025", "[0, 1)", NULL, "Uniform modal damping ratio", "damping", "KFReducer", "KFReducerSetDamping"},
  {"-kf_damping_bands", TL, "none", "[0, inf)", NULL, "Modal damping per band: f_max_hz,zeta,f_max_hz,zeta,... (ascending; modes above the last band take its ratio)", "damping.modal", "KFReducer", "KFReducerSetDampingModel"},
  {"-kf_damping_rayleigh", TL, "0,0", "[0, inf)", NULL, "Rayleigh damping C = alpha M + beta K: alpha,beta", "damping.rayleigh", "KFReducer", "KFReducerSetDampingModel"},
  {"-kf_damping_structural", TR, "0", "[0, 1)", NULL, "Structural (hysteretic) damping g: stiffness K (1 + i g)", "damping.structural", "KFReducer", "KFReducerSetDampingModel"},
  {"-kf_accuracy", TR, "0.05", "(0, 1)", NULL, "Target relative H-infinity error of the frequency response over the band, per input/output pair, on the response -kf_accuracy_measure names (KFFRFElasticErrors)", "accuracy", "KFReducer", "KFReducerSetAccuracy"},
  {"-kf_accuracy_measure", TE, "elastic", NULL, "elastic total", "What the accuracy is stated on: elastic (the response minus its rigid-body and mechanism part) or total", "accuracy_measure", "KFReducer", "KFReducerSetAccuracyMeasure"},
  {"-kf_moments", TI, "auto", "[1, 200]", "auto", "Low-frequency moments matched exactly (c in the paper), or auto: the accuracy search chooses", "reduction.moments", "KFReducer", "KFReducerSetMoments"},
  {"-kf_output_blocks", TI, "1", "[0, inf)", NULL, "Krylov blocks started from K+ H^T (of the moments)", "reduction.output_blocks", "KFReducer", "KFReducerSetMoments"},
  {"-kf_search", TB, "true", NULL, NULL, "The accuracy search: the smallest model that meets -kf_accuracy (false: the paper's fixed recipe)", "reduction.search", "KFReducer", "KFReducerSetSearch"},
  {"-kf_moments_max", TI, "24", "[1, 200]", NULL, "The most moments the accuracy search tries", "reduction.moments_max", "KFReducer", "KFReducerSetSearch"},
  {"-kf_cluster_rtol", TR, "0.001", "[0, 1)", NULL, "Krylov modes this close in frequency (relative) are kept or dropped together", "reduction.cluster_rtol", "KFReducer", "KFReducerSetClusterTolerance"},
  {"-kf_max_factorizations", TI, "0", "[0, inf)", NULL, "Expansion points inside the band: the most sparse factorizations of K - sigma M the accuracy search may spend on them, one per point and expansion angle (0: moments at zero only)", NULL, "KFReducer", "KFReducerSolve"},
  {"-kf_shift_blocks", TI, "3", "[1, 100]", NULL, "Krylov blocks at each expansion point inside the band: 1 input block, 2 input and output blocks, more: further input blocks of (K - sigma M)^-1 M (default 3)", NULL, "KFReducer", "KFReducerSolve"},
  {"-kf_shift_family_only", TB, "false", NULL, NULL, "With -kf_max_factorizations: the smallest model with expansion points inside the band is chosen even when a moment-only model is as small (to compare the families: kryflex study, benchmarks); under -kf_shared_directions auto such a search runs split (as false)", NULL, "KFReducer", "KFReducerSolve"},
  {"-kf_compress", TB, "true", NULL, NULL, "After the search: each body of the chosen model truncated to the fewest of its directions, ordered by their share of the reassembled response (rigid motions, and with -kf_static_exact the static response, kept exactly), that still meet the accuracy, when that is smaller", "reduction.compress", "KFReducer", "KFReducerSetCompress"},
  {"-kf_shared_directions", TE, "auto", NULL, "false true auto", "Each kept system vector one direction of the system, not one per body: the bodies' coordinates tied (angle-independent constraints stored in the model, appended to the joints' ties at reassembly) to the span of their rigid motions and the kept vectors. Smaller models at one angle; no per-body compression (under static_exact false the search drops the static correction instead); exported body by body with the ties. auto (the default): the search measures every candidate split and tied and keeps the one with fewer system dofs (split on a tie); false: one direction per body (split models, compressed body by body)", "reduction.shared_directions", "KFReducer", "KFReducerSolve"},
  {"-kf_static_exact", TB, "true", NULL, NULL, "Compression keeps each body's share of the static elastic response exactly, so the static moment L^0 stays exact (false: it is ordered and truncated like the rest of the response, smaller models, L^0 measured and reported)", "reduction.static_exact", "KFReducer", "KFReducerSetStaticExact"},
  {"-kf_importance", TE, "band", NULL, "band h2 hinf static", "Mode importance: band (band-aware, cluster-invariant), h2, hinf or static", "reduction.importance", "KFReducer", "KFReducerSetImportance"},
  {"-kf_keep_threshold", TR, "0.05", "[0, 1]", NULL, "Keep modes whose importance (normalized to the largest) reaches this", "reduction.keep_threshold", "KFReducer", "KFReducerSetImportance"},
  {"-kf_static_correction", TB, "true", NULL, NULL, "Add the static correction of the discarded modes (eq. 15-17)", "reduction.static_correction", "KFReducer", "KFReducerSetStaticCorrection"},
  {"-kf_deflation_tol", TR, "1e-10", "(0, 1)", NULL, "Krylov block deflation tolerance (relative)", "reduction.deflation_tol", "KFReducer", "KFReducerSetTolerances"},
  {"-kf_body_tol", TR, "1e-10", "(0, 1)", NULL, "Per-body rank deflation of the projected vectors (relative)", "reduction.body_tol", "KFReducer", "KFReducerSetTolerances"},
  {"-kf_reassembly_rtol", TR, "1e-09", "(0, 1)", NULL, "SVD rank tolerance of the reduced interface constraints", "reduction.reassembly_rtol", "KFReducer", "KFReducerSetTolerances"},
  {"-kf_max_frequency", TS, "none", NULL, NULL, "Reduced-system modes above this are taken out of the dynamics, their static share kept: a multiple of the band's top (3), a frequency (\"40 Hz\") or none", "reduction.max_frequency", "KFReducer", "KFReducerSetMaxFrequency"},
  {"-kf_search_sub_bases", TB, "true", NULL, NULL, "Search candidates' body bases made in their visit's richest body basis (small dense work) rather than from their vectors", NULL, "KFReducer", "KFReducerSolve"},
  {"-kf_shift", TR, "0", "[0, inf)", NULL, "Factor K + shift M instead of holding dofs (moments then expand about -shift)", "reduction.shift", "KFReducer, KFFlexSolver", "KFReducerSetShift"},
  {"-kf_save_maps", TE, "auto", NULL, "auto true false", "Store each reduced body's map back to its full dofs: true, false or auto", "reduction.save_maps", "KFReducer", "KFReducerSetSaveMaps"},
  {"-kf_save_maps_max_dofs", TI, "200000", "[0, inf)", NULL, "With -kf_save_maps auto: store the maps while no body has more dofs", NULL, "KFReducer", "KFReducerSetSaveMaps"},
  {"-kf_gram_condition_max_dofs", TI, "20000", "[0, inf)", NULL, "Report the raw recurrence's Gram condition (diagnostic) up to this many system dofs", NULL, "KFReducer", "KFReducerSolve"},
  {"-kf_negligible_moment", TR, "1e-08", "[0, 1)", NULL, "A moment below this fraction of its largest value over the angles counts as zero", NULL, "KFReducer", "KFMomentErrors"},
  {"-kf_verify", TE, "auto", NULL, "auto true false", "The verdict: true measures the reduced model against the full order (SLEPc eigensolves and direct checks at every angle), false estimates its error against the search's richest candidate, auto (default) measures below -kf_verify_certified_min_dofs system dofs and from there gives the estimate certified by the full order's mode count (measured where the count finds a mode the richest candidate lacks)", "verify.full_order", "KFReducer", "KFReducerSetVerification"},
  {"-kf_verify_certified_min_dofs", TI, "50000", "[0, inf)", NULL, "With -kf_verify auto: the certified estimate from this many system dofs on (below: measured)", "verify.certified_min_dofs", "KFReducer", "KFReducerSolve"},
  {"-kf_verify_certified_cover", TR, "1.5", "[1, inf)", NULL, "The certified estimate counts the full order's and the richest candidate's flexible modes below this multiple of the band's top at every angle of interest and midpoint", NULL, "KFReducer", "KFReducerSolve"},
  {"-kf_verify_certified_min_accuracy", TR, "0.001", "(0, 1)", NULL, "With -kf_verify auto: an accuracy target tighter than this is measured whatever the size (the certificate counts modes, it does not bound the estimate's own error: the stress scenes' damping-light and spread-1e-5 variants pass falsely, certified, at 1e-4)", NULL, "KFReducer", "KFReducerSolve"},
  {"-kf_verify_modes", TI, "auto", "[1, inf)", "auto", "Full-order modes for verification (-1: cover -kf_verify_cover x the band's top)", "verify.modes", "KFReducer", "KFReducerSetVerification"},
  {"-kf_verify_cover", TR, "3", "(0, inf)", NULL, "Automatic verification modes cover this multiple of the band's top frequency (the sparse eigensolve stops at the first mode there)", NULL, "KFReducer", "KFReducerSetVerification"},
  {"-kf_verify_count", TB, "false", NULL, NULL, "Certify the sparse verification eigensolve: count the full order's flexible modes below its cut by the inertia of one LDL^T factorization of K_S - sigma M_S (Sylvester), a mode the eigensolve missed is exit 3", NULL, "KFReducer", "KFReducerSolve"},
  {"-kf_verify_count_bodywise", TB, "true", NULL, NULL, "The verification's mode count (-kf_verify_count) on the body-wise split where it applies: the bodies' interiors of K_b - sigma M_b factored once for every configuration, the small interface problem per configuration (Haynsworth); false: K_S - sigma M_S factored whole per configuration", NULL, "KFReducer", "KFReducerSolve"},
  {"-kf_verify_check_points", TI, "3", "[0, inf)", NULL, "Direct solves of the full-order system per angle checking the verification's reference, off resonance (0: no check)", NULL, "KFReducer", "KFReducerSolve"},
  {"-kf_verify_check_bodywise", TB, "true", NULL, NULL, "Undamped reference check: factor the bodies once per check frequency and solve every angle from them (where the body-wise solve applies); false: the whole system factored per angle and frequency", NULL, "KFReducer", "KFReducerSolve"},
  {"-kf_verify_check_method", TE, "iterative", NULL, "iterative direct", "How the reference check solves the full system: iterative (refined from the reference itself with the reduction's own K+ factor, no new factorization; a point whose iteration does not contract falls back to direct) or direct (factorizations at each check frequency)", NULL, "KFReducer", "KFReducerSolve"},
  {"-kf_verify_check_rtol", TR, "1e-06", "(0, 1)", NULL, "Largest disagreement allowed between the reference and a direct solve, a fraction of the pair's peak (beyond it the run fails, exit 3)", NULL, "KFReducer", "KFReducerSolve"},
  {"-kf_frequency_points", TI, "400", "[2, 100000]", NULL, "Log-spaced frequency-response points over the band (plus 7 around each resonance)", "verify.frequency_points", "KFReducer", "KFReducerSetVerification"},
  {"-kf_frf_floor_db", TR, "-60", "(-inf, 0)", NULL, "FRF error: notches deeper than this below the band's peak count against this level", "verify.frf_floor_db", "KFReducer", "KFFRFError"},
  {"-kf_full_moments", TB, "auto", NULL, NULL, "Full-order moments by block solves for the moment checks (default: with -kf_verify; without, the search's richest candidate gives them)", NULL, "KFReducer", "KFReducerSolve"},
  /* the reducer's implementations */
  {"-kf_eigen_cover", TR, "1", "(0, inf)", NULL, "Full-order modes up to this multiple of the band's top frequency", "reduction.eigen_cover", "KFReducer (eigen)", "KFReducerEigenSetCover"},
  {"-kf_krylov_damped", TB, "false", NULL, NULL, "Input blocks from the moments of the damped system (second-order Krylov: x_k = -K+ (C x_{k-1} + M x_{k-2})), with the bodies' damping matrices and Rayleigh damping", "reduction.damped_moments", "KFReducer (krylov)", "KFReducerSolve"},
  {"-kf_krylov_raw", TB, "false", NULL, NULL, "Project on the paper's raw recurrence (eq. 9), not orthogonalized: to show its failure (needs -kf_search 0)", NULL, "KFReducer (krylov)", "KFReducerSolve"},
  /* the flexible solve K+ and its factorization */
  {"-kf_flex_solver", TE, "auto", NULL, "auto monolithic bodywise", "The flexible solve: monolithic (one factorization of K_S per configuration), bodywise (one per body interior for all configurations and a dense interface problem per configuration), auto (body-wise for large articulated multi-body scenes; the default)", "reduction.flex_solver", "KFFlexSolver", "KFFlexSolverSetType"},
  {"-kf_bodywise_min_dofs", TI, "20000", "[0, inf)", NULL, "auto takes the body-wise solve from this many system dofs on (default 20000)", NULL, "KFFlexSolver", "KFFlexSolverSetType"},
  {"-kf_bodywise_spread", TB, "true", NULL, NULL, "Body-wise solve: factor each body on one rank, the bodies spread over the ranks (when there are at least as many bodies as ranks); false: every body on all ranks", "reduction.bodywise_spread", "KFFlexSolver", "KFFlexSolverSetUp"},
  {"-kf_refine", TI, "1", "[0, inf)", NULL, "At most this many steps of iterative refinement of a block solve (default 1; 5 with -kf_blr)", NULL, "KFFlexSolver", "KFFlexSolverApply"},
  {"-kf_refine_rtol", TR, "1e-06", "[0, inf)", NULL, "Refine a block solve only while its relative residual ||P B - K_S X||_F / ||P B||_F exceeds this (default 1e-6; 0: always)", NULL, "KFFlexSolver", "KFFlexSolverApply"},
  {"-kf_memory_check", TB, "true", NULL, NULL, "Stop before the factorization when MUMPS' memory estimate exceeds the available memory (default true)", NULL, "KFFlexSolver", "KFFlexSolverSetUp"},
  {"-kf_memory_limit_mb", TR, "auto", "(0, inf)", NULL, "Memory available to the factorization per node, MB (default: MemAvailable of /proc/meminfo)", NULL, "KFFlexSolver", "KFFlexSolverSetUp"},
  {"-kf_ordering", TE, "auto", NULL, "auto amd amf scotch pord metis qamd ptscotch", "Fill-reducing ordering of MUMPS (ICNTL(7); ptscotch: parallel analysis, ICNTL(28) and (29)): auto lets MUMPS choose among those it was built with (-mat_mumps_icntl_7 overrides it)", NULL, "KFFlexSolver", "KFFlexSolverSetUp"},
  {"-kf_scotch_seed", TI, "1", "[1, inf)", NULL, "Seed of SCOTCH's ordering (default 1)", NULL, "KFFlexSolver", "KFFlexSolverSetUp"},
  {"-kf_ordering_tries", TI, "1", "[1, inf)", NULL, "SCOTCH orderings to analyse (seeds s, s + 2, s + 4, ... from -kf_scotch_seed s), the factor with the fewest flops on the busiest rank kept (default 1)", NULL, "KFFlexSolver", "KFFlexSolverSetUp"},
  {"-kf_blr", TR, "0", "[0, 1)", NULL, "Block low-rank factorization with this dropping tolerance (MUMPS ICNTL(35), CNTL(7)); 0: full rank (default)", NULL, "KFFlexSolver", "KFFlexSolverSetUp"},
  {"-kf_ooc", TE, "auto", NULL, "auto true false", "Out-of-core factorization (MUMPS ICNTL(22)): the factors on disk, under -kf_ooc_dir: true, false, or auto (in core when MUMPS' estimate fits the node's memory, else block low-rank in core when its estimate fits (not with the SCOTCH build), else out of core)", NULL, "KFFlexSolver", "KFFlexSolverSetUp"},
  {"-kf_ooc_dir", TS, "auto", NULL, NULL, "Folder under which an out-of-core factorization writes its factors, one private folder per rank removed with the factor (default: MUMPS_OOC_TMPDIR, else TMPDIR, else /tmp; kryflex reduce: the output folder's staging folder)", NULL, "KFFlexSolver", "KFFlexSolverSetUp"},
  {"-kf_spd", TB, "false", NULL, NULL, "Tell MUMPS the held stiffness is positive definite (SYM=1, no pivoting)", NULL, "KFFlexSolver", "KFFlexSolverSetUp"},
  {"-kf_null_pivot_check_max_dofs", TI, "20000", "[0, inf)", NULL, "Cross-check the rigid count with MUMPS' null pivots of K_S by default up to this many system dofs (default 20000)", NULL, "KFFlexSolver", "KFFlexSolverSetUp"},
  {"-kf_check_null_pivots", TB, "auto", NULL, NULL, "Cross-check the rigid count with MUMPS' null pivots of K_S, one extra factorization (default: on up to -kf_null_pivot_check_max_dofs dofs without shift)", NULL, "KFFlexSolver", "KFFlexSolverSetUp"},
  {"-kf_held_cond_max", TR, "1e+08", "[1, inf)", NULL, "Largest condition number of the rigid modes on the clamp's held dofs before falling back to pivoted QR (default 1e8)", NULL, "KFFlexSolver", "KFFlexSolverSetUp"},
  /* the other stages */
  {"-kf_rigid_tol", TR, "1e-08", "(0, 1)", NULL, "Largest ||K Phi|| / (||K|| ||Phi||) accepted for rigid-body modes from node coordinates or supplied (default 1e-8)", NULL, "KFSystem (rigid modes)", "KFSystemComputeRigidModes"},
  {"-kf_progress_min_dofs", TI, "50000", "[0, inf)", NULL, "Print a progress line per Krylov block from this many system dofs on (default 50000)", NULL, "KFKrylovBasis", "KFKrylovBasis"},
  {"-kf_verify_dense_max_dofs", TI, "600", "[0, inf)", NULL, "Dense LAPACK verification eigensolve up to this many system dofs, Krylov-Schur with shift-and-invert above (default 600)", NULL, "KFSystemEigen", "KFSystemEigen"},
  {"-kf_verify_eigen_method", TE, "auto", NULL, "auto block slepc", "Sparse verification eigensolve with the flexible solver's factor: block (a block Krylov space of K+ M from the inputs, outputs and random columns, Rayleigh-Ritz), slepc (Krylov-Schur, one K+ application per vector) or auto (block from 20,000 system dofs on, slepc below; the default)", NULL, "KFSystemEigen", "KFSystemEigen"},
  {"-kf_verify_eigen_random", TI, "3", "[0, inf)", NULL, "Random columns in the block Krylov eigensolve's blocks, beside the inputs and outputs (default 3)", NULL, "KFSystemEigen", "KFSystemEigen"},
  {"-kf_verify_eigen_max_blocks", TI, "auto", "[1, inf)", "auto", "Blocks of the block Krylov eigensolve before it falls back to Krylov-Schur (auto or -1, the default: room for 4 columns per mode expected, half again as a margin, and 2 blocks, at least 12)", NULL, "KFSystemEigen", "KFSystemEigen"},
  {"-kf_verify_eigen_first_mb", TI, "32", "[0, inf)", NULL, "Megabytes per rank each array of the block Krylov eigensolve (its basis, M times it, K+ M times it) is first allocated for, then at least doubled as the basis grows; untouched until written (default 32: glibc maps a block that size on its own and grows it by remapping its pages, not copying them; 0: the start block's columns)", NULL, "KFSystemEigen", "KFSystemEigen"},
  {"-kf_verify_target", TR, "auto", NULL, NULL, "Shift-and-invert target of the sparse verification eigensolve (default -1e-8 ||K_S||_F / ||M_S||_F); its EPS takes -kf_verify_eps_* options", NULL, "KFSystemEigen", "KFSystemEigen"},
  {"-kf_quiet", TB, "false", NULL, NULL, "Silence the progress lines with elapsed time on rank 0 (default false)", NULL, "KFProgress", "KFProgress"},
  /* viewers, and the command's own */
  {"-kf_reducer_view_pre", TS, "none", NULL, NULL, "View the reducer (PetscViewer: ascii or ascii:file) before the solve", NULL, "KFReducer", "KFReducerViewFromOptions"},
  {"-kf_reducer_view", TS, "none", NULL, NULL, "View the reducer (PetscViewer: ascii or ascii:file) after the solve: what it did", NULL, "KFReducer", "KFReducerViewFromOptions"},
  {"-kf_model_view", TS, "none", NULL, NULL, "View the reduced model the solve chose (PetscViewer: ascii or ascii:file)", NULL, "KFReducedModel", "KFReducedModelViewFromOptions"},
  {"-kf_error_agreement_timeout", TR, "20", "(0, inf)", NULL, "Seconds a failing rank of the kryflex command waits for the others to reach the error agreement before MPI_Abort", NULL, "kryflex command", ""},
};

#undef TB
#undef TI
#undef TR
#undef TE
#undef TS
#undef TL

PetscErrorCode KFSettingsTableGet(const KFSettingInfo **table, PetscInt *n)
{
  PetscFunctionBegin;
  if (table) *table = KFSettings;
  if (n) *n = (PetscInt)PETSC_STATIC_ARRAY_LENGTH(KFSettings);
  PetscFunctionReturn(0);
}

/* the row of option name (with its dash: "-kf_accuracy"); NULL when the table has none */
PetscErrorCode KFSettingFind(const char name[], const KFSettingInfo **info)
{
  PetscFunctionBegin;
  PetscValidCharPointer(name, 1);
  PetscValidPointer(info, 2);
  *info = NULL;
  for (size_t i = 0; i < PETSC_STATIC_ARRAY_LENGTH(KFSettings); i++)
    if (!strcmp(KFSettings[i].name, name)) {
      *info = &KFSettings[i];
      break;
    }
  PetscFunctionReturn(0);
}
