/* Tests of the reduced model (src/model, src/io, src/measure, scene names and reference counts) through the C API,
   on the Galileo-like two-body model (meshes/galileo, built here as in test_krylov.c):
   - the error measures against values computed by hand;
   - scene names, IO names and the fingerprint (same on every rank, sensitive to names);
   - reference counts: a scene destroyed before its system and body basis stays alive for them;
   - a model from a body basis (rigid modes + 10 Krylov vectors at 0 deg): its arrays are the basis's, its map the
     gathered body basis; settings replace in place;
   - reassembly equals KFReassemble called directly, bit for bit, at 0 and 60 deg; the moments at 0 deg match the
     full-order ones; the undamped FRF equals H (K - w^2 M)^-1 G solved directly;
   - save / load round trip equal bit for bit (arrays, names, joints, settings, angles, maps, reassembly);
   - loads of a missing, non-HDF5, non-kryflex, other-version, inconsistent (shape, interface, index) and damaged
     (checksum) file, and saves into a missing folder or with a body name HDF5 cannot take, fail with the right
     error code and message on every rank, leaving an earlier file byte-identical and no temporary behind.
   Run from the source folder (CTest does), serial or under mpiexec; rank 0 prints; non-zero exit on failure. */
#include "kftest.h"
#include <hdf5.h>
#include <petscblaslapack.h>
#include <unistd.h>
#include <sys/stat.h>

/* LAPACK's condition estimate (PETSc wraps no gecon; every LAPACK has it) */
extern void dgecon_(const char *norm, const PetscBLASInt *n, const PetscReal *a, const PetscBLASInt *lda, const PetscReal *anorm, PetscReal *rcond, PetscReal *work, PetscBLASInt *iwork, PetscBLASInt *info);

static PetscBool Same(PetscInt n, const PetscReal a[], const PetscReal b[])
{
  if (!n) return PETSC_TRUE;
  if (!a || !b) return PETSC_FALSE;
  return memcmp(a, b, sizeof(PetscReal) * n) ? PETSC_FALSE : PETSC_TRUE;
}

static PetscReal RelDiff(PetscReal x, PetscReal y)
{
  return PetscAbsReal(x - y) / PetscMax(PetscAbsReal(y), 1e-300);
}

/* ------------------------------------------------------------------ the Galileo-like scene */


/* stator and rotor on a revolute bearing about z; a torque pair in, the rotation about y at point A out */
static PetscErrorCode GalileoScene(const char rotor_name[], KFScene *scene)
{
  const PetscReal z[3] = {0, 0, 1};
  PetscInt        stator, rotor;

  PetscFunctionBegin;
  PetscCall(KFSceneCreate(PETSC_COMM_WORLD, scene));
  PetscCall(KFSceneSetName(*scene, "galileo"));
  PetscCall(AddGalileoBody(*scene, "stator", "stator", &stator));
  PetscCall(AddGalileoBody(*scene, "rotor", rotor_name, &rotor));
  PetscCall(KFSceneAddInterface(*scene, stator, "bearing", 1));
  PetscCall(KFSceneAddInterface(*scene, stator, "point_a", 2));
  PetscCall(KFSceneAddInterface(*scene, rotor, "hub", 101));
  PetscCall(KFSceneAddJoint(*scene, "spin_bearing", KF_JOINT_REVOLUTE, stator, "bearing", rotor, "hub", z, NULL));
  PetscCall(KFSceneSetNumIO(*scene, 1, 1));
  PetscCall(KFSceneAddInputLoad(*scene, 0, stator, 1, 5, 1.0));
  PetscCall(KFSceneAddInputLoad(*scene, 0, rotor, 101, 5, -1.0));
  PetscCall(KFSceneAddOutputReading(*scene, 0, stator, 2, 4, 1.0));
  PetscCall(KFSceneSetIOName(*scene, PETSC_TRUE, 0, "despin_torque"));
  PetscCall(KFSceneSetUp(*scene));
  PetscFunctionReturn(0);
}

/* rigid modes and 10 Krylov vectors (9 input blocks, 1 output block) at 0 deg, projected onto the bodies */
static PetscErrorCode BuildBodyBasis(KFScene scene, KFSystem *sys, KFFlexSolver *solver, KFBodyBasis *bb)
{
  PetscReal angle = 0, *C;
  Mat       Phi, X;
  BV        V;
  PetscInt  l, c, ndefl;

  PetscFunctionBegin;
  PetscCall(KFSystemCreate(scene, sys));
  PetscCall(KFSystemSetAngles(*sys, &angle));
  PetscCall(KFSystemGetRigidModes(*sys, &Phi, NULL));
  PetscCall(KFFlexSolverCreate(*sys, solver));
  PetscCall(KFKrylovBasis(*solver, 9, 1, 1e-10, &V, &ndefl));
  PetscCall(BVGetActiveColumns(V, &l, &c));
  PetscCall(PetscCalloc1((c - l) * (c - l), &C));
  for (PetscInt i = 0; i < c - l; i++) C[i + i * (c - l)] = 1;
  PetscCall(KFBVCombine(V, c - l, C, &X));
  PetscCall(PetscFree(C));
  PetscCall(KFBodyBasisCreate(scene, bb));
  PetscCall(KFBodyBasisAdd(*bb, *sys, Phi));
  PetscCall(KFBodyBasisAdd(*bb, *sys, X));
  PetscCall(KFBodyBasisFinish(*bb, 1e-8));
  PetscCall(MatDestroy(&X));
  PetscCall(BVDestroy(&V));
  PetscFunctionReturn(0);
}

/* every rank gets the whole dense Mat, column-major */
static PetscErrorCode GatherDense(Mat A, PetscReal **a)
{
  PetscInt   m, n;
  Vec        col, all;
  VecScatter sc;

  PetscFunctionBegin;
  PetscCall(MatGetSize(A, &m, &n));
  PetscCall(PetscMalloc1(m * n, a));
  for (PetscInt j = 0; j < n; j++) {
    const PetscScalar *x;
    PetscCall(MatDenseGetColumnVecRead(A, j, &col));
    PetscCall(VecScatterCreateToAll(col, &sc, &all));
    PetscCall(VecScatterBegin(sc, col, all, INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(VecScatterEnd(sc, col, all, INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(VecGetArrayRead(all, &x));
    for (PetscInt i = 0; i < m; i++) (*a)[i + j * m] = PetscRealPart(x[i]);
    PetscCall(VecRestoreArrayRead(all, &x));
    PetscCall(VecScatterDestroy(&sc));
    PetscCall(VecDestroy(&all));
    PetscCall(MatDenseRestoreColumnVecRead(A, j, &col));
  }
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------ error measures by hand */

static PetscErrorCode TestMeasures(void)
{
  PetscReal rtol, err, f[32];
  PetscInt  nf;

  PetscFunctionBegin;
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "error measures\n"));
  {
    const PetscReal lam[4] = {100, 2e-9, 4, 1e-10}; /* unsorted on purpose */
    PetscCall(KFRigidTolerance(4, lam, 2, &rtol));
    PetscCall(Check("KFRigidTolerance: sqrt(2e-9 * 4) / 100", RelDiff(rtol, PetscSqrtReal(2e-9 * 4) / 100), 1e-15));
    PetscCall(KFRigidTolerance(4, lam, 0, &rtol));
    PetscCall(Check("KFRigidTolerance: no rigid modes -> 0", rtol, 0));
    PetscCall(KFRigidTolerance(4, lam, 4, &rtol));
    PetscCall(Check("KFRigidTolerance: all rigid -> 1", PetscAbsReal(rtol - 1), 0));
  }
  {
    /* 2 frequencies, 1 x 2 blocks (pairs p0, p1): Tf = (1, 0.01), (0.001, 0.02); Tr = (1, 0.011), (0.0013, 0.02) */
    const PetscReal Tfre[4] = {1, 0.01, 0.001, 0.02}, Tfim[4] = {0, 0, 0, 0}, Trre[4] = {1, 0.011, 0.0013, 0.02}, Trim[4] = {0, 0, 0, 0};
    const PetscReal Zre[4] = {1, 0, 0.5, 0}, Zim[4] = {0, 0, 0, 0}, Zrre[4] = {1, 1e-7, 0.5, 0};
    PetscReal       pw;
    /* hinf: p0 3e-4 / 1, p1 0.001 / 0.02 = 0.05 */
    PetscCall(KFFRFErrors(2, 1, 2, Tfre, Tfim, Trre, Trim, -40, &err, &pw));
    PetscCall(Check("KFFRFErrors: relative H-inf per pair = max(3e-4 / 1, 0.001 / 0.02) = 0.05", RelDiff(err, 0.05), 1e-13));
    /* pointwise, -40 dB: p0 at w1 3e-4 / max(0.001, 0.01 x 1), p1 at w0 0.001 / max(0.01, 0.0002) = 0.1 */
    PetscCall(Check("KFFRFErrors, -40 dB floor: pointwise max(0.03, 0.1) = 0.1", RelDiff(pw, 0.1), 1e-13));
    PetscCall(KFFRFErrors(2, 1, 2, Tfre, Tfim, Trre, Trim, -80, NULL, &pw)); /* p0 at w1: 3e-4 / max(0.001, 1e-4) */
    PetscCall(Check("KFFRFErrors, -80 dB floor: pointwise 3e-4 / 0.001 = 0.3", RelDiff(pw, 0.3), 1e-13));
    /* a pair that is zero in the full response is measured against KF_FRF_PAIR_FLOOR (1e-4) of the largest pair's
       peak (1) */
    PetscCall(KFFRFErrors(2, 1, 2, Zre, Zim, Zrre, Zim, -60, &err, NULL));
    PetscCall(Check("KFFRFErrors: a zero pair: 1e-7 / (1e-4 x 1) = 1e-3", RelDiff(err, 1e-7 / KF_FRF_PAIR_FLOOR), 1e-12));
    PetscCall(Check("KFFRFErrors: the pair floor is 1e-4", RelDiff(KF_FRF_PAIR_FLOOR, 1e-4), 0));
  }
  {
    /* 2 moments of 1 x 2 blocks at 2 configurations; config 0 is compared */
    const PetscReal Lall[8] = {2, 1e-12, 4, 0, /* config 0: L0 = (2, 1e-12), L1 = (4, 0) */
                               1, 3, 0, 0};    /* config 1: L0 = (1, 3), L1 = (0, 0) */
    const PetscReal Lred[4] = {2.2, 1, 0, 5};
    PetscReal       e[2], r[4];
    PetscCall(KFMomentErrors(2, 1, 2, 2, Lall, 0, Lred, 1e-8, e, r));
    /* L0: ||(2,1e-12) - (2.2,1)|| / ||(2,1e-12)||; L1: ||(4,0)-(0,5)|| / 4 */
    PetscCall(Check("KFMomentErrors: k = 0", RelDiff(e[0], PetscSqrtReal(0.2 * 0.2 + (1 - 1e-12) * (1 - 1e-12)) / PetscSqrtReal(4 + 1e-24)), 1e-14));
    PetscCall(Check("KFMomentErrors: k = 1", RelDiff(e[1], PetscSqrtReal(16 + 25) / 4), 1e-14));
    PetscCall(Check("KFMomentErrors: ratio L0[0] = 2 / 2.2", RelDiff(r[0], 2 / 2.2), 1e-15));
    PetscCall(CheckTrue("KFMomentErrors: ratio NaN where negligible (1e-12 vs scale 3) and where L_red = 0", (PetscBool)(PetscIsNanReal(r[1]) && PetscIsNanReal(r[2]))));
    PetscCall(CheckTrue("KFMomentErrors: ratio NaN where the full entry is 0", PetscIsNanReal(r[3])));
    PetscCall(KFMomentErrors(2, 1, 2, 2, Lall, 1, Lred, 1e-8, e, NULL));
    PetscCall(CheckTrue("KFMomentErrors: error NaN where the whole moment vanishes at that configuration", PetscIsNanReal(e[1])));
  }
  {
    const PetscReal fres[2] = {10, 200}, expect[9] = {1, 8, 9, 9.5, 10, 10.5, 11, 12, 100};
    PetscReal       dev = 0;
    PetscCall(KFFrequencyGrid(1, 100, 3, 2, fres, 0.1, &nf, f));
    for (PetscInt i = 0; i < PetscMin(nf, 9); i++) dev = PetscMax(dev, RelDiff(f[i], expect[i]));
    PetscCall(CheckTrue("KFFrequencyGrid: 3 log points + 7 around 10 Hz, 10 Hz once, 200 Hz out of band: 9 points", (PetscBool)(nf == 9)));
    PetscCall(Check("KFFrequencyGrid: the points 1, 8, 9, 9.5, 10, 10.5, 11, 12, 100", dev, 1e-15));
    PetscCall(CheckTrue("KFFrequencyGrid: geomspace ends exact", (PetscBool)(f[0] == 1 && f[nf - 1] == 100)));
  }
  {
    const PetscReal fres[1] = {1};
    PetscCall(KFFrequencyGrid(1, 100, 2, 1, fres, 0.5, &nf, f)); /* 0, 0.5, 0.75 clipped to 1 */
    PetscCall(CheckTrue("KFFrequencyGrid: points below the band clipped to it and merged: 1 1.25 1.5 2 100", (PetscBool)(nf == 5 && f[0] == 1 && f[1] == 1.25 && f[3] == 2 && f[4] == 100)));
  }
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------ scene names, fingerprint, references */

static PetscErrorCode TestScene(KFScene scene)
{
  char        fp[17], fp2[17], fp0[17];
  const char *name;
  PetscInt    refs;

  PetscFunctionBegin;
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "scene names and fingerprint\n"));
  PetscCall(KFSceneGetName(scene, &name));
  PetscCall(CheckTrue("scene name 'galileo'", (PetscBool)!strcmp(name, "galileo")));
  PetscCall(KFSceneGetIOName(scene, PETSC_TRUE, 0, &name));
  PetscCall(CheckTrue("input named 'despin_torque'", (PetscBool)!strcmp(name, "despin_torque")));
  PetscCall(KFSceneGetIOName(scene, PETSC_FALSE, 0, &name));
  PetscCall(CheckTrue("output unnamed: 'out0'", (PetscBool)!strcmp(name, "out0")));
  PetscCall(KFSceneGetInterfaceName(scene, 1, 0, &name));
  PetscCall(CheckTrue("rotor interface 0 is 'hub'", (PetscBool)!strcmp(name, "hub")));
  {
    KFJointDef J;
    PetscCall(KFSceneGetJointInfo(scene, 0, &name, &J));
    PetscCall(CheckTrue("joint 0: spin_bearing, revolute, stator.bearing -> rotor.hub, axis z", (PetscBool)(!strcmp(name, "spin_bearing") && J.type == KF_JOINT_REVOLUTE && J.parent == 0 && J.parent_interface == 0 && J.child == 1 && J.child_interface == 0 && J.axis[2] == 1 && J.R0[0] == 1)));
  }
  PetscCall(KFSceneGetFingerprint(scene, fp));
  PetscCall(PetscStrncpy(fp0, fp, sizeof(fp0)));
  PetscCallMPI(MPI_Bcast(fp0, 17, MPI_CHAR, 0, PETSC_COMM_WORLD));
  PetscCall(CheckTrue("fingerprint: 16 hex digits, the same on every rank", (PetscBool)(strlen(fp) == 16 && strspn(fp, "0123456789abcdef") == 16 && !strcmp(fp, fp0))));
  PetscCall(KFSceneSetIOName(scene, PETSC_FALSE, 0, "pointA_ry"));
  PetscCall(KFSceneGetFingerprint(scene, fp2));
  PetscCall(CheckTrue("fingerprint changes with an output name", (PetscBool)strcmp(fp, fp2)));
  PetscCall(KFSceneSetIOName(scene, PETSC_FALSE, 0, "out0"));
  PetscCall(KFSceneGetFingerprint(scene, fp2));
  PetscCall(CheckTrue("fingerprint is deterministic (same names, same fingerprint)", (PetscBool)!strcmp(fp, fp2)));
  PetscCall(KFSceneSetIOName(scene, PETSC_FALSE, 0, "pointA_ry"));
  PetscCall(PetscObjectGetReference((PetscObject)scene, &refs));
  PetscCall(CheckTrue("a new scene holds one reference", (PetscBool)(refs == 1)));
  PetscFunctionReturn(0);
}

/* the scene goes first: its system and body basis keep it alive and still work */
static PetscErrorCode TestReferences(void)
{
  KFScene      scene;
  KFSystem     sys;
  KFFlexSolver solver;
  KFBodyBasis  bb;
  PetscInt     refs, v;
  PetscReal    angle = PETSC_PI / 4;
  Mat          Ms;

  PetscFunctionBegin;
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "reference counts\n"));
  PetscCall(GalileoScene("rotor", &scene));
  PetscCall(BuildBodyBasis(scene, &sys, &solver, &bb));
  PetscCall(PetscObjectGetReference((PetscObject)scene, &refs));
  PetscCall(CheckTrue("scene referenced by its system and body basis: 3 references", (PetscBool)(refs == 3)));
  PetscCall(KFSceneDestroy(&scene));
  PetscCall(CheckTrue("KFSceneDestroy clears the caller's handle", (PetscBool)(scene == NULL)));
  PetscCall(KFFlexSolverDestroy(&solver));
  PetscCall(KFSystemSetAngles(sys, &angle)); /* reads the scene's bodies */
  PetscCall(KFSystemGetMatrices(sys, &Ms, NULL, NULL, NULL));
  PetscCall(KFBodyBasisGetReduced(bb, 1, &v, NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL));
  PetscCall(CheckTrue("system reassembled and basis read after the scene's KFSceneDestroy", (PetscBool)(Ms && v > 0)));
  PetscCall(KFSystemDestroy(&sys));
  PetscCall(KFBodyBasisDestroy(&bb)); /* the last reference: frees the scene */
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------ the model */

static PetscErrorCode CompareSystems(const char what[], KFReducedSystem x, KFReducedSystem y)
{
  PetscInt         n1, n2, a1, a2, t1, t2, r1, r2, k1, k2, nf1, nf2;
  const PetscReal *M1, *K1, *G1, *H1, *M2, *K2, *G2, *H2, *l1, *l2, *P1, *P2, *R1, *R2, *f1, *f2;
  PetscReal        s1, s2;
  char             msg[256];

  PetscFunctionBegin;
  PetscCall(KFReducedSystemGetMatrices(x, &n1, &a1, &t1, &M1, &K1, &G1, &H1));
  PetscCall(KFReducedSystemGetMatrices(y, &n2, &a2, &t2, &M2, &K2, &G2, &H2));
  PetscCall(KFReducedSystemGetModes(x, &l1, &P1, &k1, &R1));
  PetscCall(KFReducedSystemGetModes(y, &l2, &P2, &k2, &R2));
  PetscCall(KFReducedSystemGetReassemblyInfo(x, &r1, &s1));
  PetscCall(KFReducedSystemGetReassemblyInfo(y, &r2, &s2));
  PetscCall(KFReducedSystemGetFrequencies(x, &nf1, &f1));
  PetscCall(KFReducedSystemGetFrequencies(y, &nf2, &f2));
  PetscCall(PetscSNPrintf(msg, sizeof(msg), "%s: sizes, M, K, G, H, modes, rigid modes, frequencies bit for bit", what));
  PetscCall(CheckTrue(msg, (PetscBool)(n1 == n2 && a1 == a2 && t1 == t2 && k1 == k2 && r1 == r2 && s1 == s2 && nf1 == nf2 && Same(n1 * n1, M1, M2) && Same(n1 * n1, K1, K2) && Same(n1 * a1, G1, G2) && Same(t1 * n1, H1, H2) && Same(n1, l1, l2) && Same(n1 * n1, P1, P2) && Same(n1 * k1, R1, R2) && Same(nf1, f1, f2))));
  PetscFunctionReturn(0);
}

/* KFReassemble called directly on the body basis and the scene's joints, against the model's reassembly */
static PetscErrorCode TestReassembly(KFScene scene, KFBodyBasis bb, KFReducedModel model, PetscReal degrees)
{
  KFReducedBody    bodies[2];
  KFJointDef       joint;
  PetscInt         n = 0, h, rank, nrigid, hm, am, tm, nrm;
  PetscReal        angle = degrees * PETSC_PI / 180, sratio, *Mh, *Kh, *Gh, *Hh, *Phir, srm;
  const PetscReal *M, *K, *G, *H, *Pr;
  KFReducedSystem  sys;
  char             what[128];

  PetscFunctionBegin;
  for (PetscInt b = 0; b < 2; b++) {
    PetscCall(KFBodyBasisGetReduced(bb, b, &bodies[b].v, &bodies[b].M, &bodies[b].K, &bodies[b].G, &bodies[b].H, &bodies[b].ninterfaces, &bodies[b].iface, &bodies[b].rigid, NULL));
    n += bodies[b].v;
  }
  PetscCall(KFSceneGetJointInfo(scene, 0, NULL, &joint));
  PetscCall(PetscMalloc5(n * n, &Mh, n * n, &Kh, n, &Gh, n, &Hh, n * n, &Phir));
  PetscCall(KFReassemble(2, bodies, 1, &joint, &angle, 1, 1, 1e-9, &h, Mh, Kh, Gh, Hh, &rank, &sratio, &nrigid, Phir));
  PetscCall(KFReducedModelReassemble(model, &angle, &sys));
  PetscCall(KFReducedSystemGetMatrices(sys, &hm, &am, &tm, &M, &K, &G, &H));
  PetscCall(KFReducedSystemGetModes(sys, NULL, NULL, &nrm, &Pr));
  PetscCall(KFReducedSystemGetReassemblyInfo(sys, NULL, &srm));
  PetscCall(PetscSNPrintf(what, sizeof(what), "reassembly at %d deg equals KFReassemble bit for bit (h = %" PetscInt_FMT ", %" PetscInt_FMT " rigid)", (int)degrees, h, nrigid));
  PetscCall(CheckTrue(what, (PetscBool)(hm == h && am == 1 && tm == 1 && nrm == nrigid && srm == sratio && Same(h * h, M, Mh) && Same(h * h, K, Kh) && Same(h, G, Gh) && Same(h, H, Hh) && Same(h * nrigid, Pr, Phir))));
  PetscCall(CheckTrue("7 rigid-body and mechanism modes (6 + 1 revolute joint), from the bodies' rigid motions", (PetscBool)(nrm == 7)));
  PetscCall(PetscFree5(Mh, Kh, Gh, Hh, Phir));
  PetscCall(KFReducedSystemDestroy(&sys));
  PetscFunctionReturn(0);
}

/* the moments at the reduction angle match the full order's; the undamped FRF is H (K - w^2 M)^-1 G */
static PetscErrorCode TestResponses(KFReducedModel model, KFFlexSolver solver)
{
  const PetscInt   nmom = 6, nw = 3;
  PetscReal        angle = 0, Lf[6], Lr[6], dev = 0, w[3], Tre[3], Tim[3], fdev = 0;
  PetscInt         n, nf, nrigid;
  const PetscReal *M, *K, *G, *H, *freq, *lambda;
  KFReducedSystem  sys;

  PetscFunctionBegin;
  PetscCall(KFReducedModelReassemble(model, &angle, &sys));
  PetscCall(KFFlexSolverMoments(solver, nmom, Lf));
  PetscCall(KFReducedSystemMoments(sys, nmom, Lr));
  for (PetscInt k = 0; k < nmom; k++) dev = PetscMax(dev, PetscAbsReal(Lf[k] / Lr[k] - 1));
  PetscCall(Check("moments at 0 deg: max_k |L_full^k / L_reduced^k - 1|, 6 moments", dev, 1e-7));
  PetscCall(KFReducedSystemGetMatrices(sys, &n, NULL, NULL, &M, &K, &G, &H));
  PetscCall(KFReducedSystemGetFrequencies(sys, &nf, &freq));
  PetscCall(KFReducedSystemGetModes(sys, &lambda, NULL, &nrigid, NULL));
  PetscCall(CheckTrue("flexible frequencies: n - nrigid, ascending, sqrt(lambda) / 2 pi", (PetscBool)(nf == n - nrigid && nf > 1 && freq[0] <= freq[1] && RelDiff(freq[0], PetscSqrtReal(lambda[nrigid]) / (2 * PETSC_PI)) < 1e-15)));
  /* between resonances, against a direct solve of the same matrices. Both answers carry the rounding of a solve
     with K - w^2 M, whose condition number at the first flexible modes of this stiff model (lambda_max / lambda_1
     ~ 1e8) is ~1e7: the BLAS kernels alone moved the difference from 1.4e-9 (AVX2) to 1.3e-7 (AVX-512), with the
     matrices' exact response (long double elimination) between the two. So the difference is measured in units of
     eps cond_1(K - w^2 M) (LAPACK's estimate) and held to the textbook bound of a backward-stable solve, a small
     multiple of n of them (4 n; measured 0.3-14 over the BLAS kernels and 1 or 2 ranks); a wrong mode or scaling
     errs by orders of magnitude more. */
  for (PetscInt f = 0; f < nw; f++) w[f] = 2 * PETSC_PI * PetscSqrtReal(freq[f] * freq[f + 1]);
  PetscCall(KFReducedSystemFRF(sys, 0.0, nw, w, Tre, Tim));
  for (PetscInt f = 0; f < nw; f++) {
    PetscReal   *A, *x, *work, T = 0, anorm = 0, rcond;
    PetscBLASInt bn, one = 1, info, *piv, *iwork;
    PetscCall(PetscMalloc5(n * n, &A, n, &x, n, &piv, 4 * n, &work, n, &iwork));
    for (PetscInt i = 0; i < n * n; i++) A[i] = K[i] - w[f] * w[f] * M[i];
    for (PetscInt j = 0; j < n; j++) {
      PetscReal c = 0;
      for (PetscInt i = 0; i < n; i++) c += PetscAbsReal(A[i + j * n]);
      anorm = PetscMax(anorm, c);
    }
    for (PetscInt i = 0; i < n; i++) x[i] = G[i];
    PetscCall(PetscBLASIntCast(n, &bn));
    PetscCallBLAS("LAPACKgetrf", LAPACKgetrf_(&bn, &bn, A, &bn, piv, &info));
    PetscCheck(!info, PETSC_COMM_SELF, PETSC_ERR_LIB, "getrf failed: %d", (int)info);
    PetscCallBLAS("LAPACKgecon", dgecon_("1", &bn, A, &bn, &anorm, &rcond, work, iwork, &info));
    PetscCheck(!info && rcond > 0, PETSC_COMM_SELF, PETSC_ERR_LIB, "gecon failed: %d", (int)info);
    PetscCallBLAS("LAPACKgetrs", LAPACKgetrs_("N", &bn, &one, A, &bn, piv, x, &bn, &info));
    PetscCheck(!info, PETSC_COMM_SELF, PETSC_ERR_LIB, "getrs failed: %d", (int)info);
    for (PetscInt i = 0; i < n; i++) T += H[i] * x[i];
    fdev = PetscMax(fdev, (PetscAbsReal(Tre[f] - T) / PetscAbsReal(T) + PetscAbsReal(Tim[f]) / PetscAbsReal(T)) / (PETSC_MACHINE_EPSILON / rcond));
    PetscCall(PetscFree5(A, x, piv, work, iwork));
  }
  PetscCall(Check("undamped FRF between the first resonances vs H (K - w^2 M)^-1 G solved directly, in eps cond_1", fdev, 4.0 * n));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "  reduced system at 0 deg:\n"));
  PetscCall(KFReducedSystemView(sys, PETSC_VIEWER_STDOUT_WORLD));
  PetscCall(KFReducedSystemDestroy(&sys));
  PetscFunctionReturn(0);
}

static PetscErrorCode TestModel(KFScene scene, KFBodyBasis bb, KFReducedModel model)
{
  PetscInt            nb, nj, nrev, a, t, nrigid, n, nang;
  const char         *name, *fp;
  const char *const  *keys, *const *values;
  char                sfp[17];
  const PetscReal    *angles;
  PetscBool           ok = PETSC_TRUE;

  PetscFunctionBegin;
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "model from the body basis\n"));
  PetscCall(KFReducedModelGetInfo(model, &nb, &nj, &nrev, &a, &t, &nrigid));
  PetscCall(CheckTrue("2 bodies, 1 joint (revolute), 1 input, 1 output, 7 rigid", (PetscBool)(nb == 2 && nj == 1 && nrev == 1 && a == 1 && t == 1 && nrigid == 7)));
  PetscCall(KFReducedModelGetSceneName(model, &name, &fp));
  PetscCall(KFSceneGetFingerprint(scene, sfp));
  PetscCall(CheckTrue("scene name and fingerprint recorded", (PetscBool)(!strcmp(name, "galileo") && !strcmp(fp, sfp))));
  PetscCall(KFReducedModelGetIOName(model, PETSC_TRUE, 0, &name));
  PetscCall(CheckTrue("input and output names recorded", (PetscBool)!strcmp(name, "despin_torque")));
  PetscCall(KFReducedModelGetIOName(model, PETSC_FALSE, 0, &name));
  PetscCall(CheckTrue("input and output names recorded", (PetscBool)!strcmp(name, "pointA_ry")));
  PetscCall(KFReducedModelGetReductionAngles(model, &nang, &angles));
  PetscCall(CheckTrue("one reduction configuration, 0 rad", (PetscBool)(nang == 1 && angles[0] == 0)));
  for (PetscInt b = 0; b < 2; b++) {
    KFReducedBody    R;
    const PetscReal *M, *K, *G, *H, *iface, *rigid, *map;
    PetscInt         v, ni, full;
    PetscReal       *psi;
    Mat              Psi;
    PetscCall(KFBodyBasisGetReduced(bb, b, &v, &M, &K, &G, &H, &ni, &iface, &rigid, NULL));
    PetscCall(KFReducedModelGetBody(model, b, &name, &full, &R, &map));
    PetscCall(KFBodyBasisGetMap(bb, b, &Psi));
    PetscCall(GatherDense(Psi, &psi));
    ok = (PetscBool)(ok && R.v == v && R.ninterfaces == ni && R.M != M && Same(v * v, R.M, M) && Same(v * v, R.K, K) && Same(v, R.G, G) && Same(v, R.H, H) && Same(6 * ni * v, R.iface, iface) && Same(6 * v, R.rigid, rigid) && map && Same(full * v, map, psi));
    PetscCall(PetscFree(psi));
  }
  PetscCall(CheckTrue("bodies: copies of the basis's reduced arrays, maps equal to the gathered basis", ok));
  PetscCall(KFReducedModelGetInterfaceName(model, 0, 1, &name));
  PetscCall(CheckTrue("interface names recorded", (PetscBool)!strcmp(name, "point_a")));
  PetscCall(KFReducedModelSetSetting(model, "method", "single-angle"));
  PetscCall(KFReducedModelSetSetting(model, "reassembly_rtol", "1e-09"));
  PetscCall(KFReducedModelSetSetting(model, "method", "multi-angle"));
  PetscCall(KFReducedModelGetSettings(model, &n, &keys, &values));
  PetscCall(CheckTrue("settings: a known key keeps its place and takes the new value", (PetscBool)(n == 2 && !strcmp(keys[0], "method") && !strcmp(values[0], "multi-angle") && !strcmp(keys[1], "reassembly_rtol"))));
  PetscCall(TestReassembly(scene, bb, model, 0));
  PetscCall(TestReassembly(scene, bb, model, 60));
  PetscCall(KFReducedModelView(model, PETSC_VIEWER_STDOUT_WORLD));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------ files */

static PetscErrorCode CompareModels(KFReducedModel x, KFReducedModel y)
{
  PetscInt           nb1, nj1, nr1, a1, t1, nb2, nj2, nr2, a2, t2, ns1, ns2, na1, na2;
  const char        *s1, *s2, *f1, *f2;
  const char *const *k1, *const *v1, *const *k2, *const *v2;
  const PetscReal   *ang1, *ang2;
  PetscBool          ok;
  PetscReal          angle = 1.0;
  KFReducedSystem    sx, sy;

  PetscFunctionBegin;
  PetscCall(KFReducedModelGetInfo(x, &nb1, &nj1, &nr1, &a1, &t1, NULL));
  PetscCall(KFReducedModelGetInfo(y, &nb2, &nj2, &nr2, &a2, &t2, NULL));
  PetscCall(KFReducedModelGetSceneName(x, &s1, &f1));
  PetscCall(KFReducedModelGetSceneName(y, &s2, &f2));
  PetscCall(KFReducedModelGetReductionAngles(x, &na1, &ang1));
  PetscCall(KFReducedModelGetReductionAngles(y, &na2, &ang2));
  ok = (PetscBool)(nb1 == nb2 && nj1 == nj2 && nr1 == nr2 && a1 == a2 && t1 == t2 && !strcmp(s1, s2) && !strcmp(f1, f2) && na1 == na2 && Same(na1 * nr1, ang1, ang2));
  for (PetscInt b = 0; ok && b < nb1; b++) {
    KFReducedBody    R1, R2;
    const PetscReal *m1, *m2;
    PetscInt         d1, d2;
    PetscCall(KFReducedModelGetBody(x, b, &s1, &d1, &R1, &m1));
    PetscCall(KFReducedModelGetBody(y, b, &s2, &d2, &R2, &m2));
    ok = (PetscBool)(!strcmp(s1, s2) && d1 == d2 && R1.v == R2.v && R1.ninterfaces == R2.ninterfaces && Same(R1.v * R1.v, R1.M, R2.M) && Same(R1.v * R1.v, R1.K, R2.K) && Same(R1.v * a1, R1.G, R2.G) && Same(t1 * R1.v, R1.H, R2.H) && Same(6 * R1.ninterfaces * R1.v, R1.iface, R2.iface) && Same(6 * R1.v, R1.rigid, R2.rigid) && (!m1) == (!m2) && (!m1 || Same(d1 * R1.v, m1, m2)));
    for (PetscInt i = 0; ok && i < R1.ninterfaces; i++) {
      PetscCall(KFReducedModelGetInterfaceName(x, b, i, &s1));
      PetscCall(KFReducedModelGetInterfaceName(y, b, i, &s2));
      ok = (PetscBool)!strcmp(s1, s2);
    }
  }
  for (PetscInt j = 0; ok && j < nj1; j++) {
    KFJointDef J1, J2;
    PetscCall(KFReducedModelGetJoint(x, j, &s1, &J1));
    PetscCall(KFReducedModelGetJoint(y, j, &s2, &J2));
    ok = (PetscBool)(!strcmp(s1, s2) && J1.type == J2.type && J1.parent == J2.parent && J1.child == J2.child && J1.parent_interface == J2.parent_interface && J1.child_interface == J2.child_interface && Same(3, J1.axis, J2.axis) && Same(9, J1.R0, J2.R0));
  }
  for (PetscInt i = 0; ok && i < a1 + t1; i++) {
    PetscCall(KFReducedModelGetIOName(x, (PetscBool)(i < a1), i < a1 ? i : i - a1, &s1));
    PetscCall(KFReducedModelGetIOName(y, (PetscBool)(i < a1), i < a1 ? i : i - a1, &s2));
    ok = (PetscBool)!strcmp(s1, s2);
  }
  PetscCall(KFReducedModelGetSettings(x, &ns1, &k1, &v1));
  PetscCall(KFReducedModelGetSettings(y, &ns2, &k2, &v2));
  ok = (PetscBool)(ok && ns1 == ns2);
  for (PetscInt k = 0; ok && k < ns1; k++) ok = (PetscBool)(!strcmp(k1[k], k2[k]) && !strcmp(v1[k], v2[k]));
  PetscCall(CheckTrue("load(save(model)): names, bodies, maps, joints, settings, angles bit for bit", ok));
  PetscCall(KFReducedModelReassemble(x, &angle, &sx));
  PetscCall(KFReducedModelReassemble(y, &angle, &sy));
  PetscCall(CompareSystems("reassembly of the loaded model at 57 deg", sx, sy));
  PetscCall(KFReducedSystemDestroy(&sx));
  PetscCall(KFReducedSystemDestroy(&sy));
  PetscFunctionReturn(0);
}

static PetscErrorCode CopyFile(const char from[], const char to[])
{
  FILE  *in, *out;
  char   buf[8192];
  size_t n;

  PetscFunctionBegin;
  in  = fopen(from, "rb");
  out = fopen(to, "wb");
  PetscCheck(in && out, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN, "cannot copy %s to %s", from, to);
  while ((n = fread(buf, 1, sizeof(buf), in)) > 0) PetscCheck(fwrite(buf, 1, n, out) == n, PETSC_COMM_SELF, PETSC_ERR_FILE_WRITE, "cannot write %s", to);
  fclose(in);
  fclose(out);
  PetscFunctionReturn(0);
}

static PetscBool SameFile(const char a[], const char b[])
{
  FILE     *fa = fopen(a, "rb"), *fb = fopen(b, "rb");
  PetscBool same = (PetscBool)(fa && fb);
  int       ca, cb;

  while (same) {
    ca = fgetc(fa);
    cb = fgetc(fb);
    if (ca != cb) same = PETSC_FALSE;
    if (ca == EOF) break;
  }
  if (fa) fclose(fa);
  if (fb) fclose(fb);
  return same;
}

typedef enum {
  DAMAGE_VERSION,
  DAMAGE_SHAPE,
  DAMAGE_INTERFACE,
  DAMAGE_INDEX,
  DAMAGE_CHECKSUM,
  DAMAGE_NO_FORMAT
} Damage;

static void SetIntAttr(hid_t f, const char obj[], const char name[], long long value)
{
  hid_t o = H5Oopen(f, obj, H5P_DEFAULT), s = H5Screate(H5S_SCALAR), a;

  if (H5Aexists(o, name) > 0) H5Adelete(o, name);
  a = H5Acreate2(o, name, H5T_STD_I64LE, s, H5P_DEFAULT, H5P_DEFAULT);
  H5Awrite(a, H5T_NATIVE_LLONG, &value);
  H5Aclose(a);
  H5Sclose(s);
  H5Oclose(o);
}

/* a copy of a good file with one fault (rank 0 writes it) */
static PetscErrorCode Damage_(const char good[], const char bad[], Damage what)
{
  PetscMPIInt rank;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(PETSC_COMM_WORLD, &rank));
  if (!rank) {
    hid_t f;
    PetscCall(CopyFile(good, bad));
    f = H5Fopen(bad, H5F_ACC_RDWR, H5P_DEFAULT);
    PetscCheck(f >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN, "test: cannot open %s", bad);
    switch (what) {
    case DAMAGE_VERSION:
      SetIntAttr(f, "/", "version", 1);
      break;
    case DAMAGE_SHAPE: {
      hsize_t dims[2] = {3, 4};
      hid_t   s       = H5Screate_simple(2, dims, NULL), d;
      double  zeros[12] = {0};
      H5Ldelete(f, "/bodies/rotor/K", H5P_DEFAULT);
      d = H5Dcreate2(f, "/bodies/rotor/K", H5T_IEEE_F64LE, s, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
      H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, zeros);
      H5Dclose(d);
      H5Sclose(s);
    } break;
    case DAMAGE_INTERFACE:
      SetIntAttr(f, "/joints/spin_bearing", "child_interface", 3);
      break;
    case DAMAGE_INDEX:
      SetIntAttr(f, "/bodies/rotor", "index", 0);
      break;
    case DAMAGE_NO_FORMAT:
      H5Adelete(f, "format");
      break;
    case DAMAGE_CHECKSUM: {
      hid_t    d = H5Dopen2(f, "/bodies/stator/M", H5P_DEFAULT), s = H5Dget_space(d);
      hsize_t  offset[2], size;
      unsigned mask;
      haddr_t  addr;
      FILE    *fp;
      int      c;
      PetscCheck(H5Dget_chunk_info(d, s, 0, offset, &mask, &addr, &size) >= 0, PETSC_COMM_SELF, PETSC_ERR_LIB, "test: no chunk info");
      H5Sclose(s);
      H5Dclose(d);
      H5Fclose(f);
      f  = -1;
      fp = fopen(bad, "r+b");
      fseek(fp, (long)addr + 3, SEEK_SET);
      c = fgetc(fp);
      fseek(fp, (long)addr + 3, SEEK_SET);
      fputc(c ^ 0x10, fp); /* one flipped bit in the first entry of M */
      fclose(fp);
    } break;
    }
    if (f >= 0) H5Fclose(f);
  }
  PetscCallMPI(MPI_Barrier(PETSC_COMM_WORLD));
  PetscFunctionReturn(0);
}

/* a call that must fail with code and a message containing words, on every rank */
static PetscErrorCode ExpectFailure(const char what[], PetscErrorCode ierr, PetscErrorCode code, const char words[])
{
  char        msg[512];
  const char *last = KFLastError();
  PetscBool   ok   = (PetscBool)(ierr == code && strstr(last, words) != NULL);
  int         lo, hi;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Allreduce(&ierr, &lo, 1, MPI_INT, MPI_MIN, PETSC_COMM_WORLD));
  PetscCallMPI(MPI_Allreduce(&ierr, &hi, 1, MPI_INT, MPI_MAX, PETSC_COMM_WORLD));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "    -> %s\n", last));
  PetscCall(PetscSNPrintf(msg, sizeof(msg), "%s: error %d with '%s', the same on every rank", what, (int)code, words));
  PetscCall(CheckTrue(msg, (PetscBool)(ok && lo == hi)));
  KFClearError();
  PetscFunctionReturn(0);
}

static PetscErrorCode TestFiles(KFReducedModel model)
{
  char           dir[PETSC_MAX_PATH_LEN], good[PETSC_MAX_PATH_LEN], bad[PETSC_MAX_PATH_LEN], copy[PETSC_MAX_PATH_LEN], tmp[PETSC_MAX_PATH_LEN];
  KFReducedModel loaded, other;
  PetscErrorCode ierr;
  PetscMPIInt    rank;
  int            pid = (int)getpid();
  KFScene        scene2;
  KFSystem       sys2;
  KFFlexSolver   solver2;
  KFBodyBasis    bb2;
  const char    *value;
  const char *const *keys, *const *values;
  PetscInt       n;

  PetscFunctionBegin;
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "model files\n"));
  PetscCallMPI(MPI_Comm_rank(PETSC_COMM_WORLD, &rank));
  PetscCallMPI(MPI_Bcast(&pid, 1, MPI_INT, 0, PETSC_COMM_WORLD));
  PetscCall(PetscSNPrintf(dir, sizeof(dir), "/tmp/kryflex-test-model-%d", pid));
  if (!rank) PetscCheck(mkdir(dir, 0700) == 0, PETSC_COMM_SELF, PETSC_ERR_FILE_WRITE, "test: cannot create %s", dir);
  PetscCallMPI(MPI_Barrier(PETSC_COMM_WORLD));
  PetscCall(PetscSNPrintf(good, sizeof(good), "%s/galileo.h5", dir));
  PetscCall(PetscSNPrintf(bad, sizeof(bad), "%s/bad.h5", dir));
  PetscCall(PetscSNPrintf(copy, sizeof(copy), "%s/copy.h5", dir));

  PetscCall(KFReducedModelSave(model, good));
  PetscCall(KFReducedModelLoad(PETSC_COMM_WORLD, good, &loaded));
  PetscCall(CompareModels(model, loaded));
  PetscCall(KFReducedModelDestroy(&loaded));
  /* saving again replaces the file */
  PetscCall(KFReducedModelSetSetting(model, "note", "saved twice"));
  PetscCall(KFReducedModelSave(model, good));
  PetscCall(KFReducedModelLoad(PETSC_COMM_WORLD, good, &loaded));
  PetscCall(KFReducedModelGetSettings(loaded, &n, &keys, &values));
  value = n == 3 ? values[2] : "";
  PetscCall(CheckTrue("a second save replaces the file (new setting read back, in order)", (PetscBool)(n == 3 && !strcmp(keys[2], "note") && !strcmp(value, "saved twice"))));
  PetscCall(KFReducedModelDestroy(&loaded));

  PetscCall(KFPushErrorRecorder());
  ierr = KFReducedModelLoad(PETSC_COMM_WORLD, "/nonexistent/model.h5", &loaded);
  PetscCall(ExpectFailure("load a missing file", ierr, PETSC_ERR_FILE_OPEN, "not found"));
  ierr = KFReducedModelLoad(PETSC_COMM_WORLD, "meshes/galileo/stator_nodes.txt", &loaded);
  PetscCall(ExpectFailure("load a text file", ierr, PETSC_ERR_FILE_UNEXPECTED, "not an HDF5 file"));
  PetscCall(Damage_(good, bad, DAMAGE_NO_FORMAT));
  ierr = KFReducedModelLoad(PETSC_COMM_WORLD, bad, &loaded);
  PetscCall(ExpectFailure("load an HDF5 file without the format attribute", ierr, PETSC_ERR_FILE_UNEXPECTED, "not a kryflex reduced model"));
  PetscCall(Damage_(good, bad, DAMAGE_VERSION));
  ierr = KFReducedModelLoad(PETSC_COMM_WORLD, bad, &loaded);
  PetscCall(ExpectFailure("load a version 1 file", ierr, PETSC_ERR_FILE_UNEXPECTED, "written in format version 1"));
  PetscCall(Damage_(good, bad, DAMAGE_SHAPE));
  ierr = KFReducedModelLoad(PETSC_COMM_WORLD, bad, &loaded);
  PetscCall(ExpectFailure("load a file whose rotor K is 3 x 4", ierr, PETSC_ERR_FILE_UNEXPECTED, "'K' is 3 x 4"));
  PetscCall(Damage_(good, bad, DAMAGE_INTERFACE));
  ierr = KFReducedModelLoad(PETSC_COMM_WORLD, bad, &loaded);
  PetscCall(ExpectFailure("load a file whose joint names a missing interface", ierr, PETSC_ERR_FILE_UNEXPECTED, "interface"));
  PetscCall(Damage_(good, bad, DAMAGE_INDEX));
  ierr = KFReducedModelLoad(PETSC_COMM_WORLD, bad, &loaded);
  PetscCall(ExpectFailure("load a file whose body indices repeat", ierr, PETSC_ERR_FILE_UNEXPECTED, "index attributes"));
  PetscCall(Damage_(good, bad, DAMAGE_CHECKSUM));
  ierr = KFReducedModelLoad(PETSC_COMM_WORLD, bad, &loaded);
  PetscCall(ExpectFailure("load a file with one flipped bit in stator M", ierr, PETSC_ERR_FILE_READ, "checksum"));

  ierr = KFReducedModelSave(model, "/nonexistent/model.h5");
  PetscCall(ExpectFailure("save into a missing folder", ierr, PETSC_ERR_FILE_OPEN, "cannot create"));
  /* a failure in the middle of writing: a body name HDF5 cannot take as a group name */
  PetscCall(PetscPopErrorHandler());
  PetscCall(GalileoScene("rotor/x", &scene2));
  PetscCall(BuildBodyBasis(scene2, &sys2, &solver2, &bb2));
  PetscCall(KFReducedModelCreateFromBodyBasis(scene2, bb2, 0, NULL, PETSC_FALSE, &other));
  if (!rank) PetscCall(CopyFile(good, copy));
  PetscCallMPI(MPI_Barrier(PETSC_COMM_WORLD));
  PetscCall(KFPushErrorRecorder());
  ierr = KFReducedModelSave(other, good);
  PetscCall(ExpectFailure("save a model with a body named 'rotor/x' over an earlier file", ierr, PETSC_ERR_FILE_WRITE, "rotor/x"));
  PetscCall(PetscPopErrorHandler());
  PetscCall(PetscSNPrintf(tmp, sizeof(tmp), "%s.tmp-%d", good, pid));
  PetscCall(CheckTrue("after the failed save: the earlier file byte-identical, no temporary left", (PetscBool)(rank || (SameFile(good, copy) && access(tmp, F_OK) != 0))));
  PetscCall(KFReducedModelDestroy(&other));
  PetscCall(KFBodyBasisDestroy(&bb2));
  PetscCall(KFFlexSolverDestroy(&solver2));
  PetscCall(KFSystemDestroy(&sys2));
  PetscCall(KFSceneDestroy(&scene2));

  PetscCallMPI(MPI_Barrier(PETSC_COMM_WORLD));
  if (!rank) {
    (void)remove(good);
    (void)remove(bad);
    (void)remove(copy);
    (void)rmdir(dir);
  }
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  KFScene        scene;
  KFSystem       sys;
  KFFlexSolver   solver;
  KFBodyBasis    bb;
  KFReducedModel model;
  PetscMPIInt    size;
  PetscReal      angle = 0;

  PetscCall(SlepcInitialize(&argc, &argv, NULL, "Reduced model: life cycle, reassembly, files, error measures"));
  PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
  PetscCall(PetscOptionsSetValue(NULL, "-kf_quiet", NULL));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "test_model on %d rank(s)\n", size));
  PetscCall(TestMeasures());
  PetscCall(GalileoScene("rotor", &scene));
  PetscCall(TestScene(scene));
  PetscCall(TestReferences());
  PetscCall(BuildBodyBasis(scene, &sys, &solver, &bb));
  PetscCall(KFReducedModelCreateFromBodyBasis(scene, bb, 1, &angle, PETSC_TRUE, &model));
  PetscCall(TestModel(scene, bb, model));
  PetscCall(TestResponses(model, solver));
  PetscCall(TestFiles(model));
  {
    /* -save_model <path>: keep a copy, e.g. to read it with h5py */
    char      path[PETSC_MAX_PATH_LEN];
    PetscBool set;
    PetscCall(PetscOptionsGetString(NULL, NULL, "-save_model", path, sizeof(path), &set));
    if (set) PetscCall(KFReducedModelSave(model, path));
  }
  PetscCall(KFReducedModelDestroy(&model));
  PetscCall(KFBodyBasisDestroy(&bb));
  PetscCall(KFFlexSolverDestroy(&solver));
  PetscCall(KFSystemDestroy(&sys));
  PetscCall(KFSceneDestroy(&scene));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "%s: %d failure(s)\n", nfail ? "FAILED" : "passed", nfail));
  PetscCall(SlepcFinalize());
  return nfail ? 1 : 0;
}
