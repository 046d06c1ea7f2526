/* MUMPS for the flexible solve: the factorization with kryflex's controls (ordering, SCOTCH seeds and their tries,
   block low-rank, out of core), the memory check before it, and the null-pivot cross-check's options. Every
   implementation of the flexible solver factors through KFFactorMumps. */
#define _GNU_SOURCE /* dladdr */
#include <dlfcn.h>
#if defined(__GLIBC__)
  #include <malloc.h>
#endif
#include <kryflex/flexsolverimpl.h>

/* Memory freed before the factorization back to the system. glibc keeps freed blocks below its (dynamic) mmap
   threshold in the process's heap, and MUMPS' workspace is one large allocation that cannot reuse them: on the 2M-dof
   solid the model check's and the assembly's temporaries, freed, still held 10 GB of the process's 17.5 GB before
   MUMPS' analysis (the 202k-dof solid: 1.71 GB resident after the check, 0.47 GB after malloc_trim). The memory check
   then also compares MUMPS' estimate with what is really available. */
static void KFReturnFreedMemory(void)
{
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
}

/* MemAvailable of this node (/proc/meminfo), in MB; -1 where it cannot be read (also the body-wise solve's share) */
PETSC_INTERN PetscReal KFNodeMemoryAvailableMB(void)
{
  FILE  *f = fopen("/proc/meminfo", "r");
  char   line[256];
  double kb = -1;

  if (!f) return -1;
  while (fgets(line, sizeof(line), f))
    if (sscanf(line, "MemAvailable: %lf kB", &kb) == 1) break;
  fclose(f);
  return kb < 0 ? -1 : kb / 1024.0;
}

/* MUMPS' estimate of the numerical factorization's memory on this rank, MB: INFO(15) in core, INFO(17) out of core,
   INFO(30) and INFO(31) for a block low-rank factor (a small model reports 0: then its factors' entries, INFO(3) reals and INFO(4) integers, negative: millions) */
static PetscErrorCode KFFactorEstimateMB(Mat F, PetscBool ooc, PetscReal *mb)
{
  PetscInt mine, blr;

  PetscFunctionBegin;
  PetscCall(MatMumpsGetIcntl(F, 35, &blr)); /* analysed block low-rank: INFO(30), INFO(31) (the factors compressed at ICNTL(38)'s rate) */
  PetscCall(MatMumpsGetInfo(F, blr ? (ooc ? 31 : 30) : (ooc ? 17 : 15), &mine));
  if (mine > 0) *mb = (PetscReal)mine;
  else {
    PetscInt nr, ni;

    PetscCall(MatMumpsGetInfo(F, 3, &nr));
    PetscCall(MatMumpsGetInfo(F, 4, &ni));
    *mb = ((nr < 0 ? -1e6 * nr : nr) * sizeof(PetscScalar) + (ni < 0 ? -1e6 * ni : ni) * sizeof(int)) / 1048576.0;
  }
  PetscFunctionReturn(0);
}

/* -kf_memory_check and -kf_memory_limit_mb (has_limit: whether given) */
static PetscErrorCode KFFactorMemoryOptions(MPI_Comm comm, const char prefix[], PetscBool *check, PetscReal *limit, PetscBool *has_limit)
{
  PetscFunctionBegin;
  *check = PETSC_TRUE;
  *limit = -1;
  PetscOptionsBegin(comm, prefix, "kryflex factorization memory check", "KFFlexSolverSetUp");
  PetscCall(KFOptionsSettingBool(PetscOptionsObject, "-kf_memory_check", *check, check, NULL));
  PetscCall(KFOptionsSettingReal(PetscOptionsObject, "-kf_memory_limit_mb", *limit, limit, has_limit));
  PetscOptionsEnd();
  PetscCheck(!*has_limit || *limit > 0, comm, PETSC_ERR_ARG_OUTOFRANGE, "-kf_memory_limit_mb is the memory per node in MB, a positive number; got %g", (double)*limit);
  PetscFunctionReturn(0);
}

/* The node-memory test: this rank's estimates mine[k] (MB, k < n <= 2) summed over the ranks of its node, need[k],
   and the most by which any node's sum exceeds the memory available there, over[k] (the same on every rank: the node
   that exceeds it by the most decides). A rank that does not check (check false, or avail < 0: its memory unknown)
   counts as fitting. nrank (optional): the number of ranks on this rank's node. */
static PetscErrorCode KFNodeMemoryOver(MPI_Comm comm, PetscInt n, const PetscReal mine[], PetscBool check, PetscReal avail, PetscReal need[], PetscReal over[], PetscMPIInt *nrank)
{
  MPI_Comm  node;
  PetscReal in[2];

  PetscFunctionBegin;
  PetscCheck(n >= 1 && n <= 2, comm, PETSC_ERR_ARG_OUTOFRANGE, "the node-memory test takes 1 or 2 estimates, not %d", (int)n);
  PetscCallMPI(MPI_Comm_split_type(comm, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node));
  if (nrank) PetscCallMPI(MPI_Comm_size(node, nrank));
  PetscCall(MPIU_Allreduce(mine, need, n, MPIU_REAL, MPIU_SUM, node));
  PetscCallMPI(MPI_Comm_free(&node));
  for (PetscInt k = 0; k < n; k++) in[k] = (check && avail >= 0) ? need[k] - avail : -PETSC_MAX_REAL;
  PetscCall(MPIU_Allreduce(in, over, n, MPIU_REAL, MPIU_MAX, comm));
  PetscFunctionReturn(0);
}

/* After MUMPS' analysis: its estimates of the factorization's memory in core and out of core, summed over the ranks
   of each node, against the node's available memory (or -kf_memory_limit_mb). ooc_mode: 0 in core, 1 out of core,
   2 auto (in core when it fits on every node, else out of core when that fits: *ooc tells which, and MUMPS is told
   before its factorization). Too much either way stops every rank with one message, before the factorization that
   would be killed. */
static PetscErrorCode KFCheckFactorMemory(Mat F, const char prefix[], PetscInt ooc_mode, PetscBool *ooc, PetscReal *estimate_mb)
{
  MPI_Comm  comm = PetscObjectComm((PetscObject)F);
  PetscReal limit, mine[2], need[2], avail, worst[2], largest[2];
  PetscBool check, has_limit;

  PetscFunctionBegin;
  PetscCall(KFFactorMemoryOptions(comm, prefix, &check, &limit, &has_limit));
  PetscCall(KFFactorEstimateMB(F, PETSC_FALSE, &mine[0]));
  PetscCall(KFFactorEstimateMB(F, PETSC_TRUE, &mine[1]));
  avail = has_limit ? limit : KFNodeMemoryAvailableMB();
  PetscCall(KFNodeMemoryOver(comm, 2, mine, check, avail, need, worst, NULL)); /* [0] in core, [1] out of core */
  PetscCall(MPIU_Allreduce(mine, largest, 2, MPIU_REAL, MPIU_MAX, comm));
  *ooc         = (PetscBool)(ooc_mode == 1 || (ooc_mode == 2 && worst[0] > 0 && worst[1] <= 0));
  *estimate_mb = largest[*ooc ? 1 : 0];
  if (worst[*ooc ? 1 : 0] > 0) {
    /* every rank learns the offending node's figures */
    PetscReal fig[3], myfig[3] = {-1, -1, -1};
    if (check && avail >= 0 && need[*ooc ? 1 : 0] - avail == worst[*ooc ? 1 : 0]) {
      myfig[0] = need[0];
      myfig[1] = need[1];
      myfig[2] = avail;
    }
    PetscCall(MPIU_Allreduce(myfig, fig, 3, MPIU_REAL, MPIU_MAX, comm));
    SETERRQ(comm, PETSC_ERR_MEM, "not enough memory to factor the stiffness matrix: MUMPS' analysis estimates %.3g MB in core and %.3g MB out of core (-kf_ooc) for the factorization on one node, %.3g MB are available%s. Run on more nodes or a machine with more memory, free memory on this one, or try anyway with -kf_memory_check 0", (double)fig[0], (double)fig[1], (double)fig[2], has_limit ? " (-kf_memory_limit_mb)" : " (MemAvailable)");
  }
  if (*ooc && ooc_mode == 2) PetscCall(KFProgress(comm, "  the in-core factorization would need %.4g MB on one node, %.4g MB are available: the factors go out of core (%.4g MB in core; -kf_ooc false keeps them in core)", (double)need[0], (double)avail, (double)need[1]));
  if (*ooc) PetscCall(MatMumpsSetIcntl(F, 22, 1)); /* read by MUMPS at the factorization */
  PetscFunctionReturn(0);
}

/* MUMPS' ordering (ICNTL(7)) by name; ptscotch: the parallel analysis (ICNTL(28) = 2) with PT-SCOTCH (ICNTL(29) = 1);
   auto: MUMPS' own choice among the orderings it was built with (the SCOTCH build chose SCOTCH for the solid
   spacecraft from 13k to 1M dofs, on 1 and 2 ranks: README, "Nested dissection") */
static const char *const KFOrderings[] = {"amd", "amf", "scotch", "pord", "metis", "qamd", "auto", "ptscotch"};
static const PetscInt    KFOrderingIcntl[] = {0, 2, 3, 4, 5, 6, 7, -1};
#define KF_ORDERING_SCOTCH   2
#define KF_ORDERING_AUTO     6
#define KF_ORDERING_PTSCOTCH 7

/* MUMPS' controls that the options set (the factorization of the flexible solve; the null-pivot cross-check takes
   MUMPS' defaults) */
typedef struct {
  PetscInt  ordering, seed, tries;
  PetscInt  ooc_mode; /* 0 in core, 1 out of core, 2 auto */
  PetscReal blr;      /* CNTL(7) of a block low-rank factorization; 0: full rank */
  PetscBool spd;
  char      ooc_dir[PETSC_MAX_PATH_LEN]; /* -kf_ooc_dir: the parent of the out-of-core folders; empty: the default */
} KFMumpsControls;

/* -kf_ordering, -kf_scotch_seed, -kf_ordering_tries, -kf_blr, -kf_ooc, -kf_ooc_dir and -kf_spd */
static PetscErrorCode KFMumpsControlsFromOptions(MPI_Comm comm, const char prefix[], KFMumpsControls *c)
{
  char      val[16] = "auto";
  PetscBool set, on;

  PetscFunctionBegin;
  c->ordering = KF_ORDERING_AUTO;
  c->seed     = 1;
  c->tries    = 1;
  c->ooc_mode = 2;
  c->blr      = 0;
  c->spd      = PETSC_FALSE;
  c->ooc_dir[0] = 0;
  PetscOptionsBegin(comm, prefix, "kryflex factorization", "KFFlexSolverSetUp");
  PetscCall(KFOptionsSettingEList(PetscOptionsObject, "-kf_ordering", KFOrderings, 8, KFOrderings[c->ordering], &c->ordering, NULL));
  PetscCall(KFOptionsSettingInt(PetscOptionsObject, "-kf_scotch_seed", c->seed, &c->seed, NULL));
  PetscCall(KFOptionsSettingInt(PetscOptionsObject, "-kf_ordering_tries", c->tries, &c->tries, NULL));
  PetscCall(KFOptionsSettingReal(PetscOptionsObject, "-kf_blr", c->blr, &c->blr, NULL));
  PetscCall(KFOptionsSettingString(PetscOptionsObject, "-kf_ooc", val, val, sizeof(val), &set));
  PetscCall(KFOptionsSettingBool(PetscOptionsObject, "-kf_spd", c->spd, &c->spd, NULL));
  PetscCall(KFOptionsSettingString(PetscOptionsObject, "-kf_ooc_dir", c->ooc_dir, c->ooc_dir, sizeof(c->ooc_dir), NULL));
  PetscOptionsEnd();
  if (set && !val[0]) c->ooc_mode = 1; /* a bare -kf_ooc */
  else if (set) {
    PetscBool isauto, ok;

    PetscCall(KFStringToAutoBool(val, &isauto, &on, &ok));
    PetscCheck(ok, comm, PETSC_ERR_ARG_WRONG, "-kf_ooc takes true, false or auto; got '%s'", val);
    if (!isauto) c->ooc_mode = on ? 1 : 0;
  }
  PetscFunctionReturn(0);
}

/* Whether the MUMPS that PETSc calls is Debian's SCOTCH/PT-SCOTCH build (libdmumps_ptscotch: the kryflex command and
   the C programs linked by CMakeLists.txt load it before PETSc's plain build, which has PORD, AMD, AMF and QAMD only):
   the library that the process's global scope resolves dmumps_c to, by its file name. */
static PetscBool KFMumpsHasScotch(void)
{
  void   *sym = dlsym(RTLD_DEFAULT, "dmumps_c");
  Dl_info info;

  return (PetscBool)(sym && dladdr(sym, &info) && info.dli_fname && strstr(info.dli_fname, "scotch"));
}

/* A repeatable SCOTCH ordering: with its default threads SCOTCH 7 ordered the same matrix differently from run to run
   (flops 1.76e11..1.86e11 at 202k dofs: factors, and so reduced models, that differ by rounding between runs of the
   same reduction); on one thread (SCOTCH_PTHREAD_NUMBER, read when SCOTCH makes its first context; the user's value is
   kept) and with its generator at a given seed it gave the same ordering every time. SCOTCH_Num may be 32 or 64 bits:
   a long argument serves both on this ABI. */
static void KFScotchRepeatable(long seed)
{
  void (*set)(long)   = (void (*)(long))dlsym(RTLD_DEFAULT, "SCOTCH_randomSeed");
  void (*reset)(void) = (void (*)(void))dlsym(RTLD_DEFAULT, "SCOTCH_randomReset");

  setenv("SCOTCH_PTHREAD_NUMBER", "1", 0);
  if (set) set(seed);
  if (reset) reset();
}

/* The seed of the i-th SCOTCH ordering tried from -kf_scotch_seed s: s, s + 2, s + 4, ..., because in SCOTCH 7.0.3
   seeds 2j and 2j + 1 gave the same ordering of the solid spacecraft (1M dofs, seeds 1 to 8) */
static long KFScotchTrySeed(PetscInt seed, PetscInt i)
{
  return (long)seed + 2 * (long)i;
}

/* A MUMPS Cholesky factor of A with kryflex's controls, analysed (ordering and symbolic factorization); SCOTCH, when
   it is the build's, at the given seed. null_threshold: CNTL(3) (0: MUMPS' default); blr: CNTL(7) of a block low-rank
   factorization (0: full rank); ooc: out-of-core factors. ICNTL(7), (28), (29) come from the options database. */
static PetscErrorCode KFMumpsAnalyse(Mat A, PetscReal null_threshold, PetscReal blr, PetscBool ooc, PetscBool scotch, long seed, Mat *F)
{
  MatFactorInfo info;

  PetscFunctionBegin;
  PetscCall(MatFactorInfoInitialize(&info));
  PetscCall(MatGetFactor(A, MATSOLVERMUMPS, MAT_FACTOR_CHOLESKY, F));
  PetscCall(MatMumpsSetIcntl(*F, 24, 1)); /* null-pivot detection */
  if (null_threshold != 0) PetscCall(MatMumpsSetCntl(*F, 3, null_threshold));
  PetscCall(MatMumpsSetIcntl(*F, 13, 1)); /* no ScaLAPACK on the root node: LDL^T keeps the inertia exact */
  if (blr > 0) {
    PetscCall(MatMumpsSetIcntl(*F, 35, 1)); /* BLR factorization, automatic choice of the variant */
    PetscCall(MatMumpsSetCntl(*F, 7, blr));
  }
  if (ooc) PetscCall(MatMumpsSetIcntl(*F, 22, 1));
  if (scotch) KFScotchRepeatable(seed);
  PetscCall(MatCholeskyFactorSymbolic(*F, A, NULL, &info));
  PetscFunctionReturn(0);
}

/* MUMPS' estimate of the factorization's flops on the busiest rank (RINFO(1)): what the factorization's time follows */
static PetscErrorCode KFMumpsBusiestFlops(Mat F, PetscReal *flops)
{
  PetscReal mine;

  PetscFunctionBegin;
  PetscCall(MatMumpsGetRinfo(F, 1, &mine));
  PetscCall(MPIU_Allreduce(&mine, flops, 1, MPIU_REAL, MPIU_MAX, PetscObjectComm((PetscObject)F)));
  PetscFunctionReturn(0);
}

/* SCOTCH orders by recursive bisection from a random start, and its seed moved the factorization's work on the
   busiest rank by a quarter on the 1M-dof solid (2.72e12..3.53e12 flops over seeds 1..8, seed 1 the worst; 2 ranks
   factored in 103 s with seed 6 against 121 s). After the first analysis (-kf_scotch_seed), when SCOTCH ordered,
   tries - 1 more seeds are analysed and the factor whose busiest rank has the fewest flops is kept. Each try costs one
   analysis (7.7 s at 1M dofs), about what a better seed saves in one factorization: the tries are for finding the
   seed of a mesh reduced again and again, which -kf_scotch_seed then gives at no cost. */
static PetscErrorCode KFMumpsTryOrderings(Mat A, PetscReal null_threshold, PetscReal blr, PetscBool ooc, PetscInt seed, PetscInt tries, Mat *F)
{
  PetscInt       used, analysis, kept = 0;
  PetscReal      best, f;
  PetscLogDouble t0, t1;
  char           list[256] = "";
  size_t         len;

  PetscFunctionBegin;
  PetscCall(MatMumpsGetInfog(*F, 7, &used));      /* the ordering MUMPS applied */
  PetscCall(MatMumpsGetInfog(*F, 32, &analysis)); /* 2: the parallel analysis (PT-SCOTCH's seeds are not tried) */
  if (used != KFOrderingIcntl[KF_ORDERING_SCOTCH] || analysis == 2 || tries < 2) PetscFunctionReturn(0);
  PetscCall(KFMumpsBusiestFlops(*F, &best));
  PetscCall(PetscSNPrintf(list, sizeof(list), "%.3g", (double)best));
  PetscCall(PetscTime(&t0));
  for (PetscInt i = 1; i < tries; i++) {
    Mat G;

    PetscCall(KFMumpsAnalyse(A, null_threshold, blr, ooc, PETSC_TRUE, KFScotchTrySeed(seed, i), &G));
    PetscCall(KFMumpsBusiestFlops(G, &f));
    PetscCall(PetscStrlen(list, &len));
    PetscCall(PetscSNPrintf(list + len, sizeof(list) - len, ", %.3g", (double)f));
    if (f < best) { /* strictly fewer: ties keep the earlier seed */
      PetscCall(MatDestroy(F));
      *F   = G;
      best = f;
      kept = i;
    } else PetscCall(MatDestroy(&G));
  }
  PetscCall(PetscTime(&t1));
  PetscCall(KFProgress(PetscObjectComm((PetscObject)A), "  SCOTCH orderings of %" PetscInt_FMT " seeds tried in %.1f s (-kf_ordering_tries), flops on the busiest rank %s: seed %ld kept (-kf_scotch_seed %ld orders so at once)", tries, (double)(t1 - t0), list, KFScotchTrySeed(seed, kept), KFScotchTrySeed(seed, kept)));
  PetscFunctionReturn(0);
}

/* ICNTL(i) = v for the analysis through the options database: PETSc 3.18 rereads ICNTL(7), (28) and (29) from
   -mat_mumps_icntl_i at the analysis (MatMumpsSetIcntl before it does not hold); nothing when the user gave the
   option. *set: whether it was set here (cleared after the analysis). */
static PetscErrorCode KFMumpsAnalysisIcntl(Mat A, PetscInt i, PetscInt v, PetscBool *set)
{
  char      name[32], val[8];
  PetscBool user;

  PetscFunctionBegin;
  PetscCall(PetscSNPrintf(name, sizeof(name), "-mat_mumps_icntl_%d", (int)i));
  PetscCall(PetscOptionsHasName(NULL, ((PetscObject)A)->prefix, name, &user));
  *set = (PetscBool)!user;
  if (user) PetscFunctionReturn(0);
  PetscCall(PetscSNPrintf(val, sizeof(val), "%d", (int)v));
  PetscCall(PetscOptionsSetValue(NULL, name, val));
  PetscFunctionReturn(0);
}

/* The block low-rank dropping tolerance -kf_ooc auto takes when the in-core factorization does not fit: on the 202k-dof
   solid -kf_blr 1e-8 left the reduced model unchanged (1.6e-13) and its solves refine to the full-rank residual */
#define KF_AUTO_BLR_TOL 1e-8

/* -kf_ooc auto when MUMPS' in-core estimate does not fit the node's memory (KFNodeMemoryOver): first a
   block low-rank factorization in core, analysed again with ICNTL(35) = 1, if MUMPS' estimate of it (INFO(30))
   fits; its workspace is then capped at the node's share (ICNTL(23)) so that factors compressing worse than MUMPS
   assumed fail cleanly (KFFactorMumps then factors out of core). *F becomes that factor and c->blr its tolerance;
   otherwise *F stays and the memory check sends it out of core. *why: the progress line's reason. */
static PetscErrorCode KFMumpsAutoBLR(Mat A, const char prefix[], PetscReal null_threshold, PetscBool scotch, KFMumpsControls *c, Mat *F)
{
  MPI_Comm    comm = PetscObjectComm((PetscObject)A);
  PetscReal   limit, mine[2], need[2], avail, worst[2];
  PetscBool   check, has_limit;
  PetscMPIInt nrank;
  Mat         G;

  PetscFunctionBegin;
  PetscCall(KFFactorMemoryOptions(comm, prefix, &check, &limit, &has_limit));
  avail = has_limit ? limit : KFNodeMemoryAvailableMB();
  if (!check || avail < 0) PetscFunctionReturn(0);
  PetscCall(KFFactorEstimateMB(*F, PETSC_FALSE, &mine[0]));
  PetscCall(KFNodeMemoryOver(comm, 1, &mine[0], check, avail, &need[0], &worst[0], &nrank));
  if (worst[0] <= 0) PetscFunctionReturn(0); /* in core, full rank */
  if (scotch) { /* MUMPS 5.5's block low-rank analysis with the SCOTCH build crashed in SCOTCH (_SCOTCHthreadContextNbr,
                   from its graph coarsening) in 6 of 11 runs of -kf_blr 1e-8 on the 57k-dof solid: not taken unasked */
    PetscCall(KFProgress(comm, "  in core, full rank would need %.4g MB on one node, %.4g MB are available; block low-rank is not tried with the SCOTCH build of MUMPS (its analysis can crash: docs/guide/large-models.md)", (double)need[0], (double)avail));
    PetscFunctionReturn(0);
  }
  PetscCall(KFMumpsAnalyse(A, null_threshold, KF_AUTO_BLR_TOL, PETSC_FALSE, scotch, KFScotchTrySeed(c->seed, 0), &G));
  PetscCall(KFFactorEstimateMB(G, PETSC_FALSE, &mine[1]));
  PetscCall(KFNodeMemoryOver(comm, 1, &mine[1], check, avail, &need[1], &worst[1], NULL));
  if (worst[1] > 0) {
    PetscCall(MatDestroy(&G));
    PetscCall(KFProgress(comm, "  in core, full rank would need %.4g MB on one node and block low-rank (-kf_blr %g) %.4g MB, %.4g MB are available", (double)need[0], KF_AUTO_BLR_TOL, (double)need[1], (double)avail));
    PetscFunctionReturn(0);
  }
  PetscCall(MatMumpsSetIcntl(G, 23, (PetscInt)(avail / nrank))); /* MB per rank: a clean failure, not the OOM killer */
  PetscCall(MatDestroy(F));
  *F     = G;
  c->blr = KF_AUTO_BLR_TOL;
  PetscCall(KFProgress(comm, "  in core, full rank would need %.4g MB on one node, %.4g MB are available: block low-rank (-kf_blr %g), MUMPS' estimate %.4g MB (its factors compressed to ICNTL(38) per mille); -kf_ooc true or false chooses otherwise", (double)need[0], (double)avail, KF_AUTO_BLR_TOL, (double)need[1]));
  PetscFunctionReturn(0);
}

/* The out-of-core factor's folder on every rank, named in a progress line (rank 0's) */
static PetscErrorCode KFMumpsOocFolder(Mat F, const char given[])
{
  const char *parent, *path;

  PetscFunctionBegin;
  PetscCall(KFOocParent(given, &parent));
  PetscCall(KFOocFolderCreate(F, parent));
  PetscCall(KFOocFolderGet(F, &path));
  PetscCall(KFProgress(PetscObjectComm((PetscObject)F), "  out-of-core factors in %s (one folder per rank, removed with the factor; -kf_ooc_dir or MUMPS_OOC_TMPDIR chooses the parent)", path));
  PetscFunctionReturn(0);
}

/* A numerical factorization's outcome: a failure destroys *F (its out-of-core folder with it, on every rank) and is an
   error; else MUMPS' null (INFOG(28)) and negative (INFOG(12)) pivots */
static PetscErrorCode KFMumpsFactorResult(Mat A, Mat *F, MatFactorError err, PetscInt *null_pivots, PetscInt *negative_pivots)
{
  PetscFunctionBegin;
  if (err != MAT_FACTOR_NOERROR) PetscCall(MatDestroy(F));
  PetscCheck(err == MAT_FACTOR_NOERROR, PetscObjectComm((PetscObject)A), PETSC_ERR_MAT_LU_ZRPVT, "MUMPS could not factor the stiffness matrix (error type %d): it is singular beyond its rigid-body and mechanism modes, or out of memory (-mat_mumps_icntl_14 raises MUMPS' workspace)", (int)err);
  PetscCall(MatMumpsGetInfog(*F, 28, null_pivots));
  PetscCall(MatMumpsGetInfog(*F, 12, negative_pivots));
  PetscFunctionReturn(0);
}

/* MUMPS factorization with null-pivot detection; reports the inertia MUMPS sees. spd: K_h is known positive definite
   (held or shifted), MUMPS' SYM=1 (Cholesky without pivoting) instead of SYM=2; opts: the user's factorization
   options (ordering, block low-rank, out-of-core, memory check) apply, else MUMPS' defaults (the null-pivot check). */
PETSC_INTERN PetscErrorCode KFFactorMumps(Mat A, const char prefix[], PetscReal null_threshold, PetscBool opts, Mat *F, PetscInt *null_pivots, PetscInt *negative_pivots, PetscReal *estimate_mb)
{
  MatFactorError  err;
  KFMumpsControls c = {KF_ORDERING_AUTO, 1, 1, 0, 0, PETSC_FALSE, ""};
  PetscMPIInt     size;
  PetscBool       auto_blr, user_blr, ooc = PETSC_FALSE, set7 = PETSC_FALSE, set28 = PETSC_FALSE, set29 = PETSC_FALSE, scotch = KFMumpsHasScotch();

  PetscFunctionBegin;
  if (opts) PetscCall(KFMumpsControlsFromOptions(PetscObjectComm((PetscObject)A), prefix, &c));
  user_blr = (PetscBool)(c.blr > 0);
  {
    PetscBool known, spd;

    PetscCall(MatIsSPDKnown(A, &known, &spd));
    if (c.spd && !(known && !spd)) PetscCall(MatSetOption(A, MAT_SPD, PETSC_TRUE)); /* an interior shift is known indefinite */
  }
  PetscCallMPI(MPI_Comm_size(PetscObjectComm((PetscObject)A), &size));
  if (opts) {
    if (c.ordering == KF_ORDERING_PTSCOTCH && size == 1) c.ordering = KF_ORDERING_SCOTCH; /* a parallel analysis on one rank: SCOTCH itself */
    if (c.ordering == KF_ORDERING_PTSCOTCH && scotch) {
      PetscCall(KFMumpsAnalysisIcntl(A, 28, 2, &set28));
      PetscCall(KFMumpsAnalysisIcntl(A, 29, 1, &set29));
    } else {
      /* the sequential analysis whichever MUMPS runs (the SCOTCH build's automatic choice could go parallel) */
      PetscCall(KFMumpsAnalysisIcntl(A, 28, 1, &set28));
      if (KFOrderingIcntl[c.ordering] >= 0 && KFOrderingIcntl[c.ordering] != 7) PetscCall(KFMumpsAnalysisIcntl(A, 7, KFOrderingIcntl[c.ordering], &set7));
    }
  }
  PetscCall(MatSetErrorIfFailure(A, PETSC_FALSE));
  KFReturnFreedMemory();
  ooc = (PetscBool)(c.ooc_mode == 1);
  /* out of core from the analysis on when asked (auto: decided after it) */
  PetscCall(KFMumpsAnalyse(A, null_threshold, c.blr, (PetscBool)(c.ooc_mode == 1), scotch, KFScotchTrySeed(c.seed, 0), F));
  if (opts && scotch) PetscCall(KFMumpsTryOrderings(A, null_threshold, c.blr, (PetscBool)(c.ooc_mode == 1), c.seed, c.tries, F));
  if (set7) PetscCall(PetscOptionsClearValue(NULL, "-mat_mumps_icntl_7"));
  if (set28) PetscCall(PetscOptionsClearValue(NULL, "-mat_mumps_icntl_28"));
  if (set29) PetscCall(PetscOptionsClearValue(NULL, "-mat_mumps_icntl_29"));
  if (estimate_mb && opts && c.ooc_mode == 2 && c.blr == 0) PetscCall(KFMumpsAutoBLR(A, prefix, null_threshold, scotch, &c, F));
  auto_blr = (PetscBool)(estimate_mb && opts && c.ooc_mode == 2 && c.blr > 0 && !user_blr);
  if (estimate_mb) {
    PetscInt    used, analysis;
    const char *name = "unknown";

    PetscCall(KFCheckFactorMemory(*F, prefix, c.ooc_mode, &ooc, estimate_mb));
    PetscCall(MatMumpsGetInfog(*F, 32, &analysis)); /* 2: the parallel analysis ran */
    PetscCall(MatMumpsGetInfog(*F, 7, &used));      /* the sequential analysis' ordering (auto, or a fallback) */
    for (PetscInt k = 0; k < KF_ORDERING_AUTO + 1; k++)
      if (KFOrderingIcntl[k] == used) name = KFOrderings[k];
    if (analysis == 2) name = "ptscotch (parallel analysis)";
    PetscCall(KFProgress(PetscObjectComm((PetscObject)A), "  MUMPS analysis: %s ordering, %s%s, estimate %.4g MB per rank (largest)", name, c.spd ? "SYM=1" : "SYM=2", c.blr > 0 ? (ooc ? ", block low-rank, out-of-core" : ", block low-rank") : (ooc ? ", out-of-core" : ""), (double)*estimate_mb));
    if (opts && !scotch && (c.ordering == KF_ORDERING_SCOTCH || c.ordering == KF_ORDERING_PTSCOTCH))
      PetscCall(KFProgress(PetscObjectComm((PetscObject)A), "  -kf_ordering %s: the MUMPS in use has no SCOTCH, MUMPS chose %s instead (install Debian's libmumps-ptscotch-5.5, which scripts/setup does, and import kryflex before petsc4py)", KFOrderings[c.ordering], name));

  }
  if (ooc) PetscCall(KFMumpsOocFolder(*F, c.ooc_dir));
  PetscCall(KFMumpsFactorNumeric(*F, A));
  PetscCall(MatFactorGetError(*F, &err));
  if (auto_blr && !ooc && err != MAT_FACTOR_NOERROR) { /* the factors compressed worse than MUMPS assumed: out of core, full rank */
    PetscCall(KFProgress(PetscObjectComm((PetscObject)A), "  the block low-rank factorization did not fit (MUMPS error type %d): factoring out of core, full rank", (int)err));
    PetscCall(MatDestroy(F));
    PetscCall(KFMumpsAnalyse(A, null_threshold, 0, PETSC_TRUE, scotch, KFScotchTrySeed(c.seed, 0), F));
    PetscCall(KFMumpsOocFolder(*F, c.ooc_dir));
    PetscCall(KFMumpsFactorNumeric(*F, A));
    PetscCall(MatFactorGetError(*F, &err));
    if (estimate_mb) { /* the timing line's estimate: this factor's */
      PetscReal mine;

      PetscCall(KFFactorEstimateMB(*F, PETSC_TRUE, &mine));
      PetscCall(MPIU_Allreduce(&mine, estimate_mb, 1, MPIU_REAL, MPIU_MAX, PetscObjectComm((PetscObject)A)));
    }
  }
  PetscCall(KFMumpsFactorResult(A, F, err, null_pivots, negative_pivots));
  PetscFunctionReturn(0);
}

/* A factor made by KFFactorMumps factored again for A, a matrix of the pattern it was analysed for (the ordering and
   symbolic factorization kept: MUMPS' numerical phase alone, with the controls it was analysed with); the pivots'
   counts as KFFactorMumps reports them. */
PETSC_INTERN PetscErrorCode KFFactorMumpsNumericAgain(Mat A, Mat *F, PetscInt *null_pivots, PetscInt *negative_pivots)
{
  MatFactorError err;

  PetscFunctionBegin;
  KFReturnFreedMemory();
  PetscCall(KFMumpsFactorNumeric(*F, A));
  PetscCall(MatFactorGetError(*F, &err));
  PetscCall(KFMumpsFactorResult(A, F, err, null_pivots, negative_pivots));
  PetscFunctionReturn(0);
}

/* -kf_null_pivot_check_max_dofs and -kf_check_null_pivots: whether a system of nsys dofs factored with this shift
   gets the cross-check */
PETSC_INTERN PetscErrorCode KFNullPivotCheckOptions(MPI_Comm comm, const char prefix[], PetscInt nsys, PetscReal shift, PetscBool *check)
{
  PetscInt check_max = 20000;

  PetscFunctionBegin;
  PetscOptionsBegin(comm, prefix, "kryflex null-pivot cross-check", "KFFlexSolverSetUp");
  PetscCall(KFOptionsSettingInt(PetscOptionsObject, "-kf_null_pivot_check_max_dofs", check_max, &check_max, NULL));
  *check = (PetscBool)(nsys <= check_max && shift == 0);
  PetscCall(KFOptionsSettingBool(PetscOptionsObject, "-kf_check_null_pivots", *check, check, NULL));
  PetscOptionsEnd();
  PetscCheck(check_max >= 0, comm, PETSC_ERR_ARG_OUTOFRANGE, "-kf_null_pivot_check_max_dofs is a number of system dofs, 0 or more; got %" PetscInt_FMT, check_max);
  PetscFunctionReturn(0);
}


/* -kf_blr: a block low-rank factorization's dropping tolerance (0: full rank), what KFFactorMumps factors with */
PETSC_INTERN PetscErrorCode KFMumpsGetBLR(MPI_Comm comm, const char prefix[], PetscReal *blr)
{
  KFMumpsControls c;

  PetscFunctionBegin;
  PetscCall(KFMumpsControlsFromOptions(comm, prefix, &c));
  *blr = c.blr;
  PetscFunctionReturn(0);
}

/* Every option of the factorization, its memory check and the null-pivot cross-check, read and checked with nothing
   made: a bad value is refused before the scene is assembled (KFFlexSolverCheckOptions) */
PETSC_INTERN PetscErrorCode KFMumpsCheckOptions(MPI_Comm comm, const char prefix[])
{
  KFMumpsControls c;
  PetscReal       limit;
  PetscBool       check, has_limit;

  PetscFunctionBegin;
  PetscCall(KFMumpsControlsFromOptions(comm, prefix, &c));
  PetscCall(KFFactorMemoryOptions(comm, prefix, &check, &limit, &has_limit));
  PetscCall(KFNullPivotCheckOptions(comm, prefix, 0, 0, &check));
  PetscFunctionReturn(0);
}
