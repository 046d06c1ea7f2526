/* Tests of the reducer object (KFReducer, src/reducer) through the C API:
   - life cycle: create and destroy without a solve; KFReducerSetFromOptions without a scene; types krylov and eigen
     (by KFReducerSetType and by -<prefix>kf_reducer_type); reference counts of the reducer (PetscObjectReference) and
     of the scene it holds;
   - wrong use returns an error code, the same on every rank, and never aborts: an unknown type, KFReducerSolve before
     KFReducerSetScene, results and models before a solve, moments <= output blocks, a band with f_low >= f_high, and
     -kf_angles whose count is not a multiple of the scene's revolute joints (3-body chain, 2 revolute joints);
   - one real solve on a tiny scene generated here (two beam-like bodies of 3-D Euler-Bernoulli elements with lumped
     masses, on a revolute joint about z; 2 inputs, 2 outputs), every Krylov mode kept: the model exists and has the
     scene's bodies and joint; "reduction_config" names the configuration of alpha_G; "moment_error" there is below
     1e-8 for the first moments; "frf_error" is recorded at every angle of interest with verification on; a model
     saved and loaded back reassembles to the same K, bit for bit, at an angle that is not an angle of interest;
   - a solve of the eigen type (the eigenvector baseline) on the same scene gives a model.
   Run from the source folder (CTest does), serial or under mpiexec; rank 0 prints; non-zero exit on failure. */
#include "kftest.h"
#include <unistd.h>

/* a call that must fail (ierr set by the caller under KFPushErrorRecorder), with the same code on every rank */
static PetscErrorCode ExpectFailure(const char what[], PetscErrorCode ierr)
{
  int  lo, hi, code = (int)ierr;
  char msg[512];

  PetscFunctionBegin;
  PetscCallMPI(MPI_Allreduce(&code, &lo, 1, MPI_INT, MPI_MIN, PETSC_COMM_WORLD));
  PetscCallMPI(MPI_Allreduce(&code, &hi, 1, MPI_INT, MPI_MAX, PETSC_COMM_WORLD));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "    -> error %d: %s\n", code, KFLastError()));
  PetscCall(PetscSNPrintf(msg, sizeof(msg), "%s: an error code, the same on every rank", what));
  PetscCall(CheckTrue(msg, (PetscBool)(lo != 0 && lo == hi)));
  KFClearError();
  PetscFunctionReturn(0);
}

static PetscBool Same(PetscInt n, const PetscReal a[], const PetscReal b[])
{
  if (!n) return PETSC_TRUE;
  if (!a || !b) return PETSC_FALSE;
  return memcmp(a, b, sizeof(PetscReal) * n) ? PETSC_FALSE : PETSC_TRUE;
}

static PetscBool HasResult(KFReducer r, PetscInt config, const char name[])
{
  PetscInt           n;
  const char *const *names;

  if (KFReducerGetResultNames(r, config, &n, &names)) return PETSC_FALSE;
  for (PetscInt i = 0; i < n; i++)
    if (!strcmp(names[i], name)) return PETSC_TRUE;
  return PETSC_FALSE;
}

/* ------------------------------------------------------------------ beam-like bodies generated here */

/* A body of 6-dof nodes joined by 3-D Euler-Bernoulli beam elements (the same section everywhere) with lumped masses
   and rotary inertias at the nodes: K is exactly free of strain under the 6 rigid-body motions of the nodes. */
typedef struct {
  const char *name;
  PetscInt    nnodes, ids[8];
  PetscReal   xyz[24];
  PetscInt    nelem, elem[16]; /* node indices, 2 per element */
  PetscReal   EA, GJ, EIy, EIz;
  PetscReal   mass[8], inertia[24]; /* per node: mass, diagonal rotary inertia (global axes) */
} BeamBody;

static void BeamElement(const BeamBody *b, PetscInt e, PetscReal Kg[144])
{
  const PetscReal *xi = &b->xyz[3 * b->elem[2 * e]], *xj = &b->xyz[3 * b->elem[2 * e + 1]];
  PetscReal        d[3] = {xj[0] - xi[0], xj[1] - xi[1], xj[2] - xi[2]}, L, ex[3], ey[3], ez[3], ref[3] = {0, 0, 1}, lam[9], Kl[144] = {0}, T[144] = {0}, dot, n;
  const PetscInt   v[4] = {1, 5, 7, 11}, w[4] = {2, 4, 8, 10};

  L = PetscSqrtReal(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  for (int i = 0; i < 3; i++) ex[i] = d[i] / L;
  if (PetscAbsReal(ex[2]) > 0.9) {
    ref[0] = 1;
    ref[2] = 0;
  }
  dot = ref[0] * ex[0] + ref[1] * ex[1] + ref[2] * ex[2];
  for (int i = 0; i < 3; i++) ey[i] = ref[i] - dot * ex[i];
  n = PetscSqrtReal(ey[0] * ey[0] + ey[1] * ey[1] + ey[2] * ey[2]);
  for (int i = 0; i < 3; i++) ey[i] /= n;
  ez[0] = ex[1] * ey[2] - ex[2] * ey[1];
  ez[1] = ex[2] * ey[0] - ex[0] * ey[2];
  ez[2] = ex[0] * ey[1] - ex[1] * ey[0];
  for (int j = 0; j < 3; j++) { /* rows: local axes in global coordinates */
    lam[0 + 3 * j] = ex[j];
    lam[1 + 3 * j] = ey[j];
    lam[2 + 3 * j] = ez[j];
  }
  /* local stiffness, dofs u v w rx ry rz per node (row-major 12 x 12, symmetric) */
#define KL(i, j) Kl[12 * (i) + (j)]
  KL(0, 0) = KL(6, 6) = b->EA / L;
  KL(0, 6) = KL(6, 0) = -b->EA / L;
  KL(3, 3) = KL(9, 9) = b->GJ / L;
  KL(3, 9) = KL(9, 3) = -b->GJ / L;
  {
    /* bending in the local x-y plane (v, rz) and in the x-z plane (w, ry, opposite sign convention) */
    const PetscReal kv[16] = {12, 6 * L, -12, 6 * L, 6 * L, 4 * L * L, -6 * L, 2 * L * L, -12, -6 * L, 12, -6 * L, 6 * L, 2 * L * L, -6 * L, 4 * L * L};
    const PetscReal kw[16] = {12, -6 * L, -12, -6 * L, -6 * L, 4 * L * L, 6 * L, 2 * L * L, -12, 6 * L, 12, 6 * L, -6 * L, 2 * L * L, 6 * L, 4 * L * L};
    for (int i = 0; i < 4; i++)
      for (int j = 0; j < 4; j++) {
        KL(v[i], v[j]) = b->EIz / (L * L * L) * kv[4 * i + j];
        KL(w[i], w[j]) = b->EIy / (L * L * L) * kw[4 * i + j];
      }
  }
#undef KL
  /* K_global = T^T K_local T, T = diag(lam, lam, lam, lam) */
  for (int blk = 0; blk < 4; blk++)
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < 3; j++) T[12 * (3 * blk + i) + 3 * blk + j] = lam[i + 3 * j];
  for (int i = 0; i < 12; i++)
    for (int j = 0; j < 12; j++) {
      PetscReal s = 0;
      for (int k = 0; k < 12; k++)
        for (int l = 0; l < 12; l++) s += T[12 * k + i] * Kl[12 * k + l] * T[12 * l + j];
      Kg[12 * i + j] = s;
    }
}

/* M and K as distributed AIJ matrices (rank 0 inserts, assembly distributes) */
static PetscErrorCode AddBeamBody(KFScene scene, const BeamBody *b, PetscInt *body)
{
  PetscInt    n = 6 * b->nnodes, ndof[8];
  Mat         M, K;
  PetscMPIInt rank;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(PETSC_COMM_WORLD, &rank));
  PetscCall(MatCreateAIJ(PETSC_COMM_WORLD, PETSC_DECIDE, PETSC_DECIDE, n, n, 18, NULL, 18, NULL, &K));
  PetscCall(MatCreateAIJ(PETSC_COMM_WORLD, PETSC_DECIDE, PETSC_DECIDE, n, n, 1, NULL, 1, NULL, &M));
  PetscCall(MatSetOption(K, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_FALSE));
  if (!rank) {
    for (PetscInt e = 0; e < b->nelem; e++) {
      PetscReal Ke[144];
      PetscInt  idx[12];
      BeamElement(b, e, Ke);
      for (int k = 0; k < 6; k++) {
        idx[k]     = 6 * b->elem[2 * e] + k;
        idx[6 + k] = 6 * b->elem[2 * e + 1] + k;
      }
      PetscCall(MatSetValues(K, 12, idx, 12, idx, Ke, ADD_VALUES));
    }
    for (PetscInt i = 0; i < b->nnodes; i++)
      for (int k = 0; k < 6; k++) {
        PetscInt  r = 6 * i + k;
        PetscReal m = k < 3 ? b->mass[i] : b->inertia[3 * i + k - 3];
        PetscCall(MatSetValue(M, r, r, m, INSERT_VALUES));
      }
  }
  PetscCall(MatAssemblyBegin(K, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(K, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyBegin(M, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(M, MAT_FINAL_ASSEMBLY));
  for (PetscInt i = 0; i < b->nnodes; i++) ndof[i] = 6;
  PetscCall(KFSceneAddBody(scene, b->name, M, K, b->nnodes, b->ids, b->xyz, ndof, body));
  PetscCall(MatDestroy(&M));
  PetscCall(MatDestroy(&K));
  PetscFunctionReturn(0);
}

/* a post along -z with a side arm at its foot (anisotropic on purpose, so the response changes with the angle) */
static const BeamBody kBase = {
  "base", 4, {1, 2, 3, 4}, {0, 0, 0, 0, 0, -0.5, 0, 0, -1.0, 0.6, 0, -1.0}, 3, {0, 1, 1, 2, 2, 3},
  1e7, 2e3, 3e3, 1.2e3, {5, 3, 4, 6}, {0.05, 0.05, 0.05, 0.02, 0.02, 0.02, 0.03, 0.03, 0.03, 0.4, 0.1, 0.2}
};
/* an arm along x with a bent tip, on top of the post */
static const BeamBody kArm = {
  "arm", 4, {101, 102, 103, 104}, {0, 0, 0, 1, 0, 0, 2, 0, 0, 2, 0.5, 0.2}, 3, {0, 1, 1, 2, 2, 3},
  1e7, 1.5e3, 2e3, 2.5e3, {2, 2, 2, 3}, {0.03, 0.03, 0.03, 0.02, 0.02, 0.02, 0.02, 0.02, 0.02, 0.05, 0.05, 0.05}
};

/* base and arm on a revolute joint about z; in: the joint torque pair and a lateral force at the arm's tip;
   out: the post's rotation about y at its foot and the arm's lateral displacement at node 103 */
static PetscErrorCode TinyScene(KFScene *scene)
{
  const PetscReal z[3] = {0, 0, 1};
  PetscInt        base, arm;

  PetscFunctionBegin;
  PetscCall(KFSceneCreate(PETSC_COMM_WORLD, scene));
  PetscCall(KFSceneSetName(*scene, "tiny"));
  PetscCall(AddBeamBody(*scene, &kBase, &base));
  PetscCall(AddBeamBody(*scene, &kArm, &arm));
  PetscCall(KFSceneAddInterface(*scene, base, "hinge", 1));
  PetscCall(KFSceneAddInterface(*scene, arm, "hinge", 101));
  PetscCall(KFSceneAddJoint(*scene, "hinge", KF_JOINT_REVOLUTE, base, "hinge", arm, "hinge", z, NULL));
  PetscCall(KFSceneSetNumIO(*scene, 2, 2));
  PetscCall(KFSceneAddInputLoad(*scene, 0, base, 1, 5, 1.0));
  PetscCall(KFSceneAddInputLoad(*scene, 0, arm, 101, 5, -1.0));
  PetscCall(KFSceneAddInputLoad(*scene, 1, arm, 104, 1, 1.0));
  PetscCall(KFSceneAddOutputReading(*scene, 0, base, 3, 4, 1.0));
  PetscCall(KFSceneAddOutputReading(*scene, 1, arm, 103, 1, 1.0));
  PetscCall(KFSceneSetIOName(*scene, PETSC_TRUE, 0, "hinge_torque"));
  PetscCall(KFSceneSetIOName(*scene, PETSC_TRUE, 1, "tip_force_y"));
  PetscCall(KFSceneSetIOName(*scene, PETSC_FALSE, 0, "foot_ry"));
  PetscCall(KFSceneSetIOName(*scene, PETSC_FALSE, 1, "arm_uy"));
  PetscCall(KFSceneSetUp(*scene));
  PetscFunctionReturn(0);
}

/* base -> arm -> a second arm: two revolute joints (only for the angle-count error) */
static PetscErrorCode ChainScene(KFScene *scene)
{
  const PetscReal z[3] = {0, 0, 1};
  BeamBody        arm2 = kArm;
  PetscInt        base, arm, second;

  PetscFunctionBegin;
  arm2.name = "arm2";
  for (PetscInt i = 0; i < arm2.nnodes; i++) {
    arm2.ids[i] = 201 + i;
    arm2.xyz[3 * i + 0] += 2.0;
    arm2.xyz[3 * i + 1] += 0.5;
    arm2.xyz[3 * i + 2] += 0.2;
  }
  PetscCall(KFSceneCreate(PETSC_COMM_WORLD, scene));
  PetscCall(AddBeamBody(*scene, &kBase, &base));
  PetscCall(AddBeamBody(*scene, &kArm, &arm));
  PetscCall(AddBeamBody(*scene, &arm2, &second));
  PetscCall(KFSceneAddInterface(*scene, base, "hinge", 1));
  PetscCall(KFSceneAddInterface(*scene, arm, "hinge", 101));
  PetscCall(KFSceneAddInterface(*scene, arm, "elbow", 104));
  PetscCall(KFSceneAddInterface(*scene, second, "elbow", 201));
  PetscCall(KFSceneAddJoint(*scene, "hinge", KF_JOINT_REVOLUTE, base, "hinge", arm, "hinge", z, NULL));
  PetscCall(KFSceneAddJoint(*scene, "elbow", KF_JOINT_REVOLUTE, arm, "elbow", second, "elbow", z, NULL));
  PetscCall(KFSceneSetNumIO(*scene, 1, 1));
  PetscCall(KFSceneAddInputLoad(*scene, 0, base, 1, 5, 1.0));
  PetscCall(KFSceneAddOutputReading(*scene, 0, second, 204, 1, 1.0));
  PetscCall(KFSceneSetUp(*scene));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------ life cycle */

static PetscErrorCode TestLifeCycle(KFScene scene)
{
  KFReducer     r, r2;
  KFReducerType type;
  PetscInt      refs, srefs0, srefs;
  KFScene       got;

  PetscFunctionBegin;
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "life cycle\n"));
  PetscCall(KFReducerCreate(PETSC_COMM_WORLD, &r));
  PetscCall(KFReducerDestroy(&r));
  PetscCall(CheckTrue("create and destroy without a solve; KFReducerDestroy clears the handle", (PetscBool)(r == NULL)));
  PetscCall(KFReducerDestroy(&r));
  PetscCall(CheckTrue("KFReducerDestroy of a NULL handle is a no-op", PETSC_TRUE));

  PetscCall(KFReducerCreate(PETSC_COMM_WORLD, &r));
  PetscCall(KFReducerSetFromOptions(r));
  PetscCall(KFReducerGetType(r, &type));
  PetscCall(CheckTrue("KFReducerSetFromOptions without a scene: default type krylov", (PetscBool)(type && !strcmp(type, KFREDUCERKRYLOV))));
  PetscCall(KFReducerSetType(r, KFREDUCEREIGEN));
  PetscCall(KFReducerGetType(r, &type));
  PetscCall(CheckTrue("KFReducerSetType eigen", (PetscBool)(type && !strcmp(type, KFREDUCEREIGEN))));
  PetscCall(KFReducerSetType(r, KFREDUCERKRYLOV));
  PetscCall(KFReducerGetType(r, &type));
  PetscCall(CheckTrue("KFReducerSetType krylov (back from eigen)", (PetscBool)(type && !strcmp(type, KFREDUCERKRYLOV))));
  PetscCall(KFReducerView(r, PETSC_VIEWER_STDOUT_WORLD));

  /* the reducer's reference count */
  r2 = r;
  PetscCall(PetscObjectReference((PetscObject)r));
  PetscCall(PetscObjectGetReference((PetscObject)r, &refs));
  PetscCall(CheckTrue("PetscObjectReference: 2 references", (PetscBool)(refs == 2)));
  PetscCall(KFReducerDestroy(&r));
  PetscCall(PetscObjectGetReference((PetscObject)r2, &refs));
  PetscCall(CheckTrue("KFReducerDestroy drops one reference and clears the handle; the object lives on", (PetscBool)(r == NULL && refs == 1)));

  /* the scene is referenced by the reducer and outlives the caller's handle */
  PetscCall(PetscObjectGetReference((PetscObject)scene, &srefs0));
  PetscCall(KFReducerSetScene(r2, scene));
  PetscCall(KFReducerGetScene(r2, &got));
  PetscCall(PetscObjectGetReference((PetscObject)scene, &srefs));
  PetscCall(CheckTrue("KFReducerSetScene references the scene; KFReducerGetScene returns it", (PetscBool)(srefs == srefs0 + 1 && got == scene)));
  PetscCall(KFReducerSetScene(r2, scene));
  PetscCall(PetscObjectGetReference((PetscObject)scene, &srefs));
  PetscCall(CheckTrue("setting the same scene again keeps one reference", (PetscBool)(srefs == srefs0 + 1)));
  PetscCall(KFReducerDestroy(&r2));
  PetscCall(PetscObjectGetReference((PetscObject)scene, &srefs));
  PetscCall(CheckTrue("the last KFReducerDestroy releases the scene", (PetscBool)(srefs == srefs0)));

  /* the type from the options database, under a prefix */
  PetscCall(KFReducerCreate(PETSC_COMM_WORLD, &r));
  PetscCall(KFReducerSetOptionsPrefix(r, "lc_"));
  PetscCall(PetscOptionsSetValue(NULL, "-lc_kf_reducer_type", "eigen"));
  PetscCall(KFReducerSetFromOptions(r));
  PetscCall(PetscOptionsClearValue(NULL, "-lc_kf_reducer_type"));
  PetscCall(KFReducerGetType(r, &type));
  PetscCall(CheckTrue("-lc_kf_reducer_type eigen with the prefix lc_", (PetscBool)(type && !strcmp(type, KFREDUCEREIGEN))));
  PetscCall(KFReducerDestroy(&r));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------ wrong use */

static PetscErrorCode TestErrors(void)
{
  KFReducer       r;
  KFScene         chain;
  KFReducedModel  model;
  PetscErrorCode   ierr;
  const PetscReal *data;

  PetscFunctionBegin;
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "wrong use returns an error\n"));
  PetscCall(ChainScene(&chain));
  PetscCall(KFReducerCreate(PETSC_COMM_WORLD, &r));
  PetscCall(KFPushErrorRecorder());

  ierr = KFReducerSetType(r, "lanczos");
  PetscCall(ExpectFailure("KFReducerSetType with an unknown type", ierr));
  ierr = KFReducerSolve(r);
  PetscCall(ExpectFailure("KFReducerSolve before KFReducerSetScene", ierr));
  ierr = KFReducerSetUp(r);
  PetscCall(ExpectFailure("KFReducerSetUp before KFReducerSetScene", ierr));
  ierr = KFReducerGetReducedModel(r, &model);
  PetscCall(ExpectFailure("KFReducerGetReducedModel before a solve", ierr));
  ierr = KFReducerGetResult(r, -1, "kept_modes", NULL, NULL, &data);
  PetscCall(ExpectFailure("KFReducerGetResult before a solve", ierr));
  ierr = KFReducerSetMoments(r, 2, 2);
  PetscCall(ExpectFailure("KFReducerSetMoments: 2 moments, 2 output blocks", ierr));
  ierr = KFReducerSetMoments(r, 1, 3);
  PetscCall(ExpectFailure("KFReducerSetMoments: 1 moment, 3 output blocks", ierr));
  ierr = KFReducerSetBand(r, 10, 1);
  PetscCall(ExpectFailure("KFReducerSetBand: f_low 10 Hz > f_high 1 Hz", ierr));
  ierr = KFReducerSetBand(r, 5, 5);
  PetscCall(ExpectFailure("KFReducerSetBand: f_low = f_high", ierr));

  /* 3 angles for 2 revolute joints, through the options (the only way to give a flat list) */
  PetscCall(PetscPopErrorHandler());
  PetscCall(KFReducerSetOptionsPrefix(r, "bad_"));
  PetscCall(KFReducerSetScene(r, chain));
  PetscCall(PetscOptionsSetValue(NULL, "-bad_kf_angles", "0,15,30"));
  PetscCall(KFPushErrorRecorder());
  ierr = KFReducerSetFromOptions(r);
  PetscCall(ExpectFailure("-kf_angles 0,15,30 for a scene with 2 revolute joints", ierr));
  PetscCall(PetscPopErrorHandler());
  PetscCall(PetscOptionsClearValue(NULL, "-bad_kf_angles"));
  /* the reducer still works after the failures: 2 configurations of 2 angles */
  PetscCall(PetscOptionsSetValue(NULL, "-bad_kf_angles", "0,15,30,45"));
  PetscCall(KFReducerSetFromOptions(r));
  PetscCall(PetscOptionsClearValue(NULL, "-bad_kf_angles"));
  PetscCall(CheckTrue("after the failures: -kf_angles 0,15,30,45 (2 configurations of 2 angles) accepted", PETSC_TRUE));
  /* the flexible solver's options are read with the reducer's prefix: a bad -bad_kf_flex_solver or -bad_kf_refine is
     refused by the reducer's options reader, and the same values without the prefix do not reach this reducer */
  PetscCall(PetscOptionsSetValue(NULL, "-bad_kf_flex_solver", "nosuchsolver"));
  PetscCall(KFPushErrorRecorder());
  ierr = KFReducerSetFromOptions(r);
  PetscCall(ExpectFailure("-bad_kf_flex_solver nosuchsolver (the reducer's prefix reaches the flexible solver)", ierr));
  PetscCall(PetscPopErrorHandler());
  PetscCall(PetscOptionsClearValue(NULL, "-bad_kf_flex_solver"));
  PetscCall(PetscOptionsSetValue(NULL, "-bad_kf_refine", "-1"));
  PetscCall(KFPushErrorRecorder());
  ierr = KFReducerSetFromOptions(r);
  PetscCall(ExpectFailure("-bad_kf_refine -1", ierr));
  PetscCall(PetscPopErrorHandler());
  PetscCall(PetscOptionsClearValue(NULL, "-bad_kf_refine"));
  PetscCall(PetscOptionsSetValue(NULL, "-kf_flex_solver", "nosuchsolver"));
  PetscCall(PetscOptionsSetValue(NULL, "-bad_kf_angles", "0,15,30,45"));
  PetscCall(KFReducerSetFromOptions(r));
  PetscCall(PetscOptionsClearValue(NULL, "-kf_flex_solver"));
  PetscCall(PetscOptionsClearValue(NULL, "-bad_kf_angles"));
  PetscCall(CheckTrue("-kf_flex_solver without the prefix does not reach a reducer with prefix bad_", PETSC_TRUE));
  PetscCall(KFReducerDestroy(&r));
  PetscCall(KFSceneDestroy(&chain));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------ a real solve */

static PetscErrorCode TestSolve(KFScene scene)
{
  const PetscInt   nconfig = 3, nfirst = 4;
  const PetscReal  deg[3]  = {0, 30, 60};
  PetscReal        angles[3], probe = 0.7, maxerr = 0;
  KFReducer        r;
  KFReducedModel   model, loaded, single, multi;
  KFReducedSystem  s1, s2;
  PetscInt         nb, nj, nrev, a, t, nrigid, ndim, cfg = -1, n1, n2, nang, nf;
  const PetscInt  *shape;
  const PetscReal *data, *K1, *K2, *mang, *freq;
  const char      *rule;
  PetscMPIInt      rank;
  int              pid = (int)getpid();
  char             path[PETSC_MAX_PATH_LEN], what[256];
  PetscBool        all = PETSC_TRUE;

  PetscFunctionBegin;
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "a krylov solve on the tiny scene\n"));
  for (PetscInt c = 0; c < nconfig; c++) angles[c] = deg[c] * PETSC_PI / 180;
  PetscCall(KFReducerCreate(PETSC_COMM_WORLD, &r));
  PetscCall(KFReducerSetScene(r, scene));
  PetscCall(KFReducerSetAngles(r, nconfig, angles));
  PetscCall(KFReducerSetReductionAngle(r, &angles[1]));
  PetscCall(KFReducerSetBand(r, 0.1, 30));
  PetscCall(KFReducerSetDamping(r, 0.01));
  PetscCall(KFReducerSetMoments(r, 6, 1));
  PetscCall(KFReducerSetImportance(r, KF_IMPORTANCE_H2, 0.0)); /* keep every Krylov mode: moments exact */
  PetscCall(KFReducerSetSearch(r, PETSC_FALSE, 24)); /* the paper's fixed recipe: every mode of the 6 moments kept */
  PetscCall(KFReducerSetVerification(r, PETSC_TRUE, PETSC_DECIDE, 60, -60));
  PetscCall(KFReducerSetFromOptions(r));
  PetscCall(KFReducerSetUp(r));
  PetscCall(KFReducerSolve(r));
  PetscCall(KFReducerView(r, PETSC_VIEWER_STDOUT_WORLD));
  PetscCall(KFReducerGetReductionRule(r, &rule));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "  rule: %s\n", rule));

  PetscCall(KFReducerGetReducedModel(r, &model));
  PetscCall(KFReducerGetReducedModels(r, &single, &multi));
  PetscCall(CheckTrue("a model after the solve, the single-angle one (method single-angle)", (PetscBool)(model != NULL && model == single)));
  PetscCall(KFReducedModelGetInfo(model, &nb, &nj, &nrev, &a, &t, &nrigid));
  PetscCall(CheckTrue("model: 2 bodies, 1 revolute joint, 2 inputs, 2 outputs, 7 rigid-body and mechanism modes", (PetscBool)(nb == 2 && nj == 1 && nrev == 1 && a == 2 && t == 2 && nrigid == 7)));
  PetscCall(KFReducedModelGetReductionAngles(model, &nang, &mang));
  PetscCall(CheckTrue("model built at alpha_G = 30 deg", (PetscBool)(nang == 1 && PetscAbsReal(mang[0] - angles[1]) < 1e-14)));

  /* the configuration of alpha_G and the moments there */
  if (HasResult(r, -1, "reduction_config")) {
    PetscCall(KFReducerGetResult(r, -1, "reduction_config", &ndim, &shape, &data));
    cfg = (PetscInt)data[0];
  }
  PetscCall(CheckTrue("\"reduction_config\" is the configuration of alpha_G (index 1)", (PetscBool)(cfg == 1)));
  if (cfg < 0 || cfg >= nconfig) cfg = 1;
  PetscCall(CheckTrue("\"moment_error\" recorded at alpha_G", HasResult(r, cfg, "moment_error")));
  if (HasResult(r, cfg, "moment_error")) {
    PetscInt nmom = 1;
    PetscCall(KFReducerGetResult(r, cfg, "moment_error", &ndim, &shape, &data));
    for (PetscInt d = 0; d < ndim; d++) nmom *= shape[d];
    PetscCall(PetscPrintf(PETSC_COMM_WORLD, "  moment errors at alpha_G:"));
    for (PetscInt k = 0; k < nmom; k++) PetscCall(PetscPrintf(PETSC_COMM_WORLD, " %.2e", (double)data[k]));
    PetscCall(PetscPrintf(PETSC_COMM_WORLD, "\n"));
    for (PetscInt k = 0; k < PetscMin(nfirst, nmom); k++) maxerr = PetscIsNanReal(data[k]) ? data[k] : PetscMax(maxerr, data[k]);
    PetscCall(CheckTrue("at least 4 moments compared", (PetscBool)(nmom >= nfirst)));
    PetscCall(Check("\"moment_error\" at alpha_G, first 4 moments (max)", maxerr, 1e-8));
  }

  /* verification results at every angle of interest */
  for (PetscInt c = 0; c < nconfig; c++) {
    PetscBool has = HasResult(r, c, "frf_error");
    all           = (PetscBool)(all && has);
    if (has) {
      PetscCall(KFReducerGetResult(r, c, "frf_error", &ndim, &shape, &data));
      PetscCall(PetscSNPrintf(what, sizeof(what), "\"frf_error\" at %g deg = %.3e: finite, >= 0", (double)deg[c], (double)data[0]));
      PetscCall(CheckTrue(what, (PetscBool)(!PetscIsInfOrNanReal(data[0]) && data[0] >= 0)));
    }
  }
  PetscCall(CheckTrue("\"frf_error\" recorded at every angle of interest (verification on)", all));

  /* save, load, reassemble at 0.7 rad: the same K */
  PetscCallMPI(MPI_Comm_rank(PETSC_COMM_WORLD, &rank));
  PetscCallMPI(MPI_Bcast(&pid, 1, MPI_INT, 0, PETSC_COMM_WORLD));
  PetscCall(PetscSNPrintf(path, sizeof(path), "/tmp/kryflex-test-reducer-%d.h5", pid));
  PetscCall(KFReducedModelSave(model, path));
  PetscCall(KFReducedModelLoad(PETSC_COMM_WORLD, path, &loaded));
  PetscCall(KFReducedModelReassemble(model, &probe, &s1));
  PetscCall(KFReducedModelReassemble(loaded, &probe, &s2));
  PetscCall(KFReducedSystemGetMatrices(s1, &n1, NULL, NULL, NULL, &K1, NULL, NULL));
  PetscCall(KFReducedSystemGetMatrices(s2, &n2, NULL, NULL, NULL, &K2, NULL, NULL));
  PetscCall(PetscSNPrintf(what, sizeof(what), "load(save(model)) reassembled at 0.7 rad: the same K (%" PetscInt_FMT " x %" PetscInt_FMT "), bit for bit", n1, n1));
  PetscCall(CheckTrue(what, (PetscBool)(n1 == n2 && n1 > 0 && Same(n1 * n1, K1, K2))));
  PetscCall(KFReducedSystemGetFrequencies(s2, &nf, &freq));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "  reduced system at 0.7 rad: %" PetscInt_FMT " dofs, %" PetscInt_FMT " flexible frequencies (Hz):", n2, nf));
  for (PetscInt i = 0; i < nf; i++) PetscCall(PetscPrintf(PETSC_COMM_WORLD, " %.4g", (double)freq[i]));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "\n"));
  PetscCall(KFReducedSystemDestroy(&s1));
  PetscCall(KFReducedSystemDestroy(&s2));
  PetscCall(KFReducedModelDestroy(&loaded));
  PetscCallMPI(MPI_Barrier(PETSC_COMM_WORLD));
  if (!rank) (void)remove(path);

  /* the model outlives the reducer with a reference of its own */
  PetscCall(PetscObjectReference((PetscObject)model));
  PetscCall(KFReducerDestroy(&r));
  PetscCall(KFReducedModelReassemble(model, &probe, &s1));
  PetscCall(KFReducedSystemGetMatrices(s1, &n1, NULL, NULL, NULL, NULL, NULL, NULL));
  PetscCall(CheckTrue("a referenced model reassembles after KFReducerDestroy", (PetscBool)(n1 == n2)));
  PetscCall(KFReducedSystemDestroy(&s1));
  PetscCall(KFReducedModelDestroy(&model));
  PetscFunctionReturn(0);
}

static PetscErrorCode TestEigenSolve(KFScene scene)
{
  const PetscReal angles[2] = {0, PETSC_PI / 4};
  KFReducer       r;
  KFReducedModel  model;
  PetscInt        nb, nj;

  PetscFunctionBegin;
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "an eigen solve on the tiny scene\n"));
  PetscCall(KFReducerCreate(PETSC_COMM_WORLD, &r));
  PetscCall(KFReducerSetType(r, KFREDUCEREIGEN));
  PetscCall(KFReducerSetScene(r, scene));
  PetscCall(KFReducerSetAngles(r, 2, angles));
  PetscCall(KFReducerSetBand(r, 0.1, 30));
  PetscCall(KFReducerSetVerification(r, PETSC_FALSE, PETSC_DECIDE, 60, -60));
  PetscCall(KFReducerSetFromOptions(r));
  PetscCall(KFReducerSolve(r)); /* sets up by itself */
  PetscCall(KFReducerGetReducedModel(r, &model));
  PetscCall(KFReducedModelGetInfo(model, &nb, &nj, NULL, NULL, NULL, NULL));
  PetscCall(CheckTrue("eigen type, KFReducerSolve without KFReducerSetUp: a model of 2 bodies and 1 joint", (PetscBool)(model && nb == 2 && nj == 1)));
  PetscCall(KFReducerDestroy(&r));
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  KFScene     scene;
  PetscMPIInt size;

  PetscCall(SlepcInitialize(&argc, &argv, NULL, "Reducer: life cycle, wrong use, a solve on a generated two-body scene"));
  PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
  PetscCall(PetscOptionsSetValue(NULL, "-kf_quiet", NULL));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "test_reducer on %d rank(s)\n", size));
  PetscCall(TinyScene(&scene));
  PetscCall(TestLifeCycle(scene));
  PetscCall(TestErrors());
  PetscCall(TestSolve(scene));
  PetscCall(TestEigenSolve(scene));
  PetscCall(KFSceneDestroy(&scene));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "%s: %d failure(s)\n", nfail ? "FAILED" : "passed", nfail));
  PetscCall(SlepcFinalize());
  return nfail ? 1 : 0;
}
