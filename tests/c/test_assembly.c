/* Tests of scene building and assembly (src/scene, src/assemble, src/rigid) through the C API, on the Galileo-like
   two-body model (meshes/galileo: stator 12 dofs, rotor 21 dofs, one revolute joint about z), built here by hand:
   matrices with KFMatLoadFile, nodes parsed from the text files, the joint and interfaces added one by one.
   At two angles it checks, against quantities computed here from the node coordinates and the joint alone:
   - the system size: body dofs minus 5 constraint rows per revolute joint;
   - K_S and M_S symmetric;
   - the rigid-body and mechanism modes Phi: the reported residual, ||K_S Phi|| on its own, Phi^T M_S Phi = I;
   - the body maps: P_b Phi is a rigid motion of body b (u = t + theta x X, node by node) spanning all 6 of them;
     for a random system vector x, P_b x satisfies the joint ties (u_p = R u_c, theta_p - R theta_c along the axis)
     and the rotation about the axis stays free;
   and that bad scenes (an interface on a missing node, a joint from a body to itself, a body no joint reaches)
   return an error code instead of aborting.
   Run from the source folder (CTest does), serial or under mpiexec; rank 0 prints; non-zero exit on failure. */
#include "kftest.h"

/* ------------------------------------------------------------------ a body from meshes/galileo */

typedef struct {
  Mat        M, K;
  PetscInt   nnodes, n; /* nodes, dofs */
  PetscInt   ids[64], ndof[64], first[64];
  PetscReal  xyz[3 * 64];
} Body;

/* the nodes file (kftest.h's reader) into the fixed arrays of a Body, with each node's first dof */
static PetscErrorCode ReadBodyNodes(const char path[], Body *b)
{
  PetscInt  *ids, *ndof, n = 0;
  PetscReal *xyz;

  PetscFunctionBegin;
  PetscCall(ReadNodes(path, &n, &ids, &xyz, &ndof));
  PetscCheck(n <= 64, PETSC_COMM_SELF, PETSC_ERR_SUP, "%s: too many nodes for this test", path);
  b->nnodes = n;
  b->n      = 0;
  for (PetscInt k = 0; k < n; k++) {
    b->ids[k]   = ids[k];
    b->ndof[k]  = ndof[k];
    b->first[k] = b->n;
    for (PetscInt j = 0; j < 3; j++) b->xyz[3 * k + j] = xyz[3 * k + j];
    b->n += ndof[k];
  }
  PetscCall(PetscFree3(ids, xyz, ndof));
  PetscFunctionReturn(0);
}

static PetscErrorCode LoadBody(const char stem[], Body *b)
{
  char path[PETSC_MAX_PATH_LEN];

  PetscFunctionBegin;
  PetscCall(PetscSNPrintf(path, sizeof(path), "meshes/galileo/%s_nodes.txt", stem));
  PetscCall(ReadBodyNodes(path, b));
  PetscCall(PetscSNPrintf(path, sizeof(path), "meshes/galileo/%s_M.mtx", stem));
  PetscCall(KFMatLoadFile(PETSC_COMM_WORLD, path, &b->M));
  PetscCall(PetscSNPrintf(path, sizeof(path), "meshes/galileo/%s_K.mtx", stem));
  PetscCall(KFMatLoadFile(PETSC_COMM_WORLD, path, &b->K));
  PetscFunctionReturn(0);
}

static PetscInt NodeIndex(const Body *b, PetscInt id)
{
  for (PetscInt k = 0; k < b->nnodes; k++)
    if (b->ids[k] == id) return k;
  return -1;
}

static PetscErrorCode AddBody(KFScene s, const char name[], Body *b, PetscInt *index)
{
  PetscFunctionBegin;
  PetscCall(KFSceneAddBody(s, name, b->M, b->K, b->nnodes, b->ids, b->xyz, b->ndof, index));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------ small dense helpers (column-major) */

/* A distributed dense Mat (or AIJ, converted) replicated on every rank: a[i + j*m] */
static PetscErrorCode GatherDense(Mat A, PetscInt *m, PetscInt *n, PetscReal **a)
{
  Mat                D;
  const PetscScalar *loc;
  PetscInt           lda, rstart, rend, nloc;
  PetscMPIInt        size, *counts, *displs;
  const PetscInt    *ranges;
  MPI_Comm           comm;
  PetscBool          dense;

  PetscFunctionBegin;
  PetscCall(PetscObjectGetComm((PetscObject)A, &comm));
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCall(PetscObjectTypeCompareAny((PetscObject)A, &dense, MATSEQDENSE, MATMPIDENSE, ""));
  if (dense) {
    PetscCall(PetscObjectReference((PetscObject)A));
    D = A;
  } else PetscCall(MatConvert(A, MATDENSE, MAT_INITIAL_MATRIX, &D));
  PetscCall(MatGetSize(D, m, n));
  PetscCall(MatGetOwnershipRange(D, &rstart, &rend));
  PetscCall(MatGetOwnershipRanges(D, &ranges));
  nloc = rend - rstart;
  PetscCall(PetscMalloc1((*m) * (*n), a));
  PetscCall(PetscMalloc2(size, &counts, size, &displs));
  for (PetscMPIInt r = 0; r < size; r++) {
    counts[r] = (PetscMPIInt)(ranges[r + 1] - ranges[r]);
    displs[r] = (PetscMPIInt)ranges[r];
  }
  PetscCall(MatDenseGetLDA(D, &lda));
  PetscCall(MatDenseGetArrayRead(D, &loc));
  for (PetscInt j = 0; j < *n; j++) PetscCallMPI(MPI_Allgatherv(loc + j * lda, (PetscMPIInt)nloc, MPIU_REAL, *a + j * (*m), counts, displs, MPIU_REAL, comm));
  PetscCall(MatDenseRestoreArrayRead(D, &loc));
  PetscCall(PetscFree2(counts, displs));
  PetscCall(MatDestroy(&D));
  PetscFunctionReturn(0);
}

static PetscReal Dot(PetscInt n, const PetscReal x[], const PetscReal y[])
{
  PetscReal s = 0;
  for (PetscInt i = 0; i < n; i++) s += x[i] * y[i];
  return s;
}

/* The body's 6 rigid motions from its node coordinates, orthonormalized (Q: n x 6). u = t + theta x X, rotations theta. */
static void RigidBasis(const Body *b, PetscReal Q[])
{
  PetscInt n = b->n;

  for (PetscInt i = 0; i < 6 * n; i++) Q[i] = 0;
  for (PetscInt k = 0; k < b->nnodes; k++) {
    const PetscReal *X = b->xyz + 3 * k;
    PetscInt         d = b->first[k];
    for (PetscInt j = 0; j < 3; j++) {
      PetscReal e[3] = {0, 0, 0}, c[3];
      e[j]           = 1;
      c[0]           = e[1] * X[2] - e[2] * X[1]; /* e_j x X */
      c[1]           = e[2] * X[0] - e[0] * X[2];
      c[2]           = e[0] * X[1] - e[1] * X[0];
      Q[d + j + j * n] = 1;
      for (PetscInt i = 0; i < 3; i++) Q[d + i + (3 + j) * n] = c[i];
      if (b->ndof[k] == 6) Q[d + 3 + j + (3 + j) * n] = 1;
    }
  }
  for (int pass = 0; pass < 2; pass++) /* modified Gram-Schmidt, twice */
    for (PetscInt j = 0; j < 6; j++) {
      for (PetscInt l = 0; l < j; l++) {
        PetscReal r = Dot(n, Q + l * n, Q + j * n);
        for (PetscInt i = 0; i < n; i++) Q[i + j * n] -= r * Q[i + l * n];
      }
      PetscReal nr = PetscSqrtReal(Dot(n, Q + j * n, Q + j * n));
      for (PetscInt i = 0; i < n; i++) Q[i + j * n] /= nr;
    }
}

/* Rot(axis, alpha) by Rodrigues' formula, row-major R[3*i + j] */
static void Rotation(const PetscReal axis[3], PetscReal alpha, PetscReal R[9])
{
  PetscReal S[9] = {0, -axis[2], axis[1], axis[2], 0, -axis[0], -axis[1], axis[0], 0}, c = PetscCosReal(alpha), s = PetscSinReal(alpha);

  for (PetscInt i = 0; i < 3; i++)
    for (PetscInt j = 0; j < 3; j++) {
      PetscReal SS = 0;
      for (PetscInt k = 0; k < 3; k++) SS += S[3 * i + k] * S[3 * k + j];
      R[3 * i + j] = (i == j ? 1.0 : 0.0) + s * S[3 * i + j] + (1 - c) * SS;
    }
}

/* ------------------------------------------------------------------ the checks at one angle */

typedef struct {
  Body     *body[2];   /* 0 stator (parent), 1 rotor (child) */
  PetscInt  iface[2];  /* interface node ids */
  PetscReal axis[3];
} Galileo;

static PetscErrorCode CheckAtAngle(KFSystem y, const Galileo *g, PetscReal alpha_deg)
{
  Mat       Ms, Ks, G, Ht, Phi, KPhi, P[2], X[2];
  PetscReal residual, nK, nKPhi, nPhi, alpha = alpha_deg * PETSC_PI / 180.0, R[9];
  PetscInt  e, r, nb[2];
  PetscBool sym;
  char      what[256];

  PetscFunctionBegin;
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "at %g deg:\n", (double)alpha_deg));
  PetscCall(KFSystemSetAngles(y, &alpha));
  PetscCall(KFSystemGetMatrices(y, &Ms, &Ks, &G, &Ht));
  PetscCall(MatGetSize(Ks, &e, NULL));

  /* symmetry, entry by entry, relative to the largest row sum */
  {
    PetscReal nrm;
    PetscCall(MatNorm(Ks, NORM_INFINITY, &nrm));
    PetscCall(MatIsSymmetric(Ks, 1e-14 * nrm, &sym));
    PetscCall(CheckTrue("MatIsSymmetric(K_S) (entries within 1e-14 ||K_S||_inf)", sym));
    PetscCall(MatNorm(Ms, NORM_INFINITY, &nrm));
    PetscCall(MatIsSymmetric(Ms, 1e-14 * nrm, &sym));
    PetscCall(CheckTrue("MatIsSymmetric(M_S) (entries within 1e-14 ||M_S||_inf)", sym));
  }

  /* rigid-body and mechanism modes */
  PetscCall(KFSystemGetRigidModes(y, &Phi, &residual));
  PetscCall(MatGetSize(Phi, NULL, &r));
  PetscCall(PetscSNPrintf(what, sizeof(what), "rigid + mechanism modes: %" PetscInt_FMT " (6 + 1 revolute joint)", r));
  PetscCall(CheckTrue(what, r == 7 ? PETSC_TRUE : PETSC_FALSE));
  PetscCall(Check("reported rigid-mode residual ||K Phi|| / (||K|| ||Phi||)", residual, 1e-14));
  PetscCall(MatMatMult(Ks, Phi, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &KPhi));
  PetscCall(MatNorm(KPhi, NORM_FROBENIUS, &nKPhi));
  PetscCall(MatNorm(Ks, NORM_FROBENIUS, &nK));
  PetscCall(MatNorm(Phi, NORM_FROBENIUS, &nPhi));
  PetscCall(MatDestroy(&KPhi));
  PetscCall(Check("K_S Phi ~ 0: ||K_S Phi||_F / (||K_S||_F ||Phi||_F), computed here", nKPhi / (nK * nPhi), 1e-14));
  {
    Mat        MPhi, Gram;
    PetscReal *a, err = 0;
    PetscInt   m, n;
    PetscCall(MatMatMult(Ms, Phi, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &MPhi));
    PetscCall(MatTransposeMatMult(Phi, MPhi, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &Gram));
    PetscCall(GatherDense(Gram, &m, &n, &a));
    for (PetscInt i = 0; i < m; i++)
      for (PetscInt j = 0; j < n; j++) err = PetscMax(err, PetscAbsReal(a[i + j * m] - (i == j ? 1.0 : 0.0)));
    PetscCall(PetscFree(a));
    PetscCall(MatDestroy(&Gram));
    PetscCall(MatDestroy(&MPhi));
    PetscCall(Check("Phi^T M_S Phi = I (max entry error)", err, 1e-12));
  }

  /* P_b Phi: rigid motions of each body, all six of them */
  for (PetscInt b = 0; b < 2; b++) {
    const Body *B = g->body[b];
    PetscReal  *x, *Q, worst = 0, C[36], lam[6], V[36], I6[36];
    PetscInt    m, n;

    PetscCall(KFSystemGetBodyMap(y, b, &P[b]));
    PetscCall(MatGetSize(P[b], &nb[b], NULL));
    PetscCall(MatMatMult(P[b], Phi, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &X[b]));
    PetscCall(GatherDense(X[b], &m, &n, &x));
    PetscCall(PetscMalloc1(6 * m, &Q));
    RigidBasis(B, Q);
    for (PetscInt i = 0; i < 36; i++) C[i] = I6[i] = 0;
    for (PetscInt j = 0; j < n; j++) {
      PetscReal c[6], res = 0, nx = Dot(m, x + j * m, x + j * m);
      for (PetscInt l = 0; l < 6; l++) c[l] = Dot(m, Q + l * m, x + j * m);
      for (PetscInt i = 0; i < m; i++) {
        PetscReal v = x[i + j * m];
        for (PetscInt l = 0; l < 6; l++) v -= Q[i + l * m] * c[l];
        res += v * v;
      }
      worst = PetscMax(worst, PetscSqrtReal(res / nx));
      for (PetscInt k = 0; k < 6; k++)
        for (PetscInt l = 0; l < 6; l++) C[k + 6 * l] += c[k] * c[l]; /* Gram of the rigid-motion coordinates */
    }
    for (PetscInt i = 0; i < 6; i++) I6[i + 6 * i] = 1;
    PetscCall(KFDenseEig(6, C, I6, lam, V));
    PetscCall(PetscSNPrintf(what, sizeof(what), "body %" PetscInt_FMT ": P_b Phi off the span of its rigid motions (relative)", b));
    PetscCall(Check(what, worst, 1e-12));
    PetscCall(PetscSNPrintf(what, sizeof(what), "body %" PetscInt_FMT ": P_b Phi spans all 6 rigid motions (cond of their Gram)", b));
    PetscCall(Check(what, lam[0] > 0 ? lam[5] / lam[0] : PETSC_INFINITY, 1e8));
    PetscCall(PetscFree(Q));
    PetscCall(PetscFree(x));
    PetscCall(MatDestroy(&X[b]));
  }
  PetscCall(PetscSNPrintf(what, sizeof(what), "system size %" PetscInt_FMT " = body dofs %" PetscInt_FMT " + %" PetscInt_FMT " - 5 (one revolute joint)", e, nb[0], nb[1]));
  PetscCall(CheckTrue(what, e == nb[0] + nb[1] - 5 && e == g->body[0]->n + g->body[1]->n - 5 ? PETSC_TRUE : PETSC_FALSE));

  /* the joint ties hold for any system vector; the rotation about the axis is free */
  {
    Vec         xe, xb[2];
    VecScatter  sc;
    Vec         all;
    PetscRandom rnd;
    PetscReal   u[2][6], tie = 0, scale = 0, free_rot;

    PetscCall(MatCreateVecs(P[0], &xe, NULL));
    PetscCall(PetscRandomCreate(PETSC_COMM_WORLD, &rnd));
    PetscCall(PetscRandomSetFromOptions(rnd));
    PetscCall(VecSetRandom(xe, rnd));
    PetscCall(PetscRandomDestroy(&rnd));
    for (PetscInt b = 0; b < 2; b++) {
      const PetscScalar *a;
      PetscInt           k = NodeIndex(g->body[b], g->iface[b]), d = g->body[b]->first[k];
      PetscCall(MatCreateVecs(P[b], NULL, &xb[b]));
      PetscCall(MatMult(P[b], xe, xb[b]));
      PetscCall(VecScatterCreateToAll(xb[b], &sc, &all));
      PetscCall(VecScatterBegin(sc, xb[b], all, INSERT_VALUES, SCATTER_FORWARD));
      PetscCall(VecScatterEnd(sc, xb[b], all, INSERT_VALUES, SCATTER_FORWARD));
      PetscCall(VecGetArrayRead(all, &a));
      for (PetscInt i = 0; i < 6; i++) u[b][i] = a[d + i];
      PetscCall(VecRestoreArrayRead(all, &a));
      PetscCall(VecScatterDestroy(&sc));
      PetscCall(VecDestroy(&all));
      PetscCall(VecDestroy(&xb[b]));
    }
    PetscCall(VecDestroy(&xe));
    Rotation(g->axis, alpha, R);
    {
      PetscReal dt[3], dr[3], along = 0;
      for (PetscInt i = 0; i < 3; i++) {
        dt[i] = u[0][i];
        dr[i] = u[0][3 + i];
        for (PetscInt j = 0; j < 3; j++) {
          dt[i] -= R[3 * i + j] * u[1][j];
          dr[i] -= R[3 * i + j] * u[1][3 + j];
        }
      }
      for (PetscInt i = 0; i < 3; i++) along += dr[i] * g->axis[i];
      for (PetscInt i = 0; i < 3; i++) {
        tie   = PetscMax(tie, PetscMax(PetscAbsReal(dt[i]), PetscAbsReal(dr[i] - along * g->axis[i])));
        scale = PetscMax(scale, PetscMax(PetscAbsReal(u[0][i]), PetscAbsReal(u[0][3 + i])));
      }
      free_rot = PetscAbsReal(along) / scale;
    }
    PetscCall(Check("P x ties: u_p - R u_c and (theta_p - R theta_c) across the axis, random x", tie / scale, 1e-13));
    PetscCall(CheckTrue("P x: the rotation about the joint axis is free (nonzero for random x)", free_rot > 1e-6 ? PETSC_TRUE : PETSC_FALSE));
  }
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------ scenes */

static PetscErrorCode BuildGalileo(Galileo *g, KFScene *s)
{
  PetscInt b0, b1;

  PetscFunctionBegin;
  PetscCall(KFSceneCreate(PETSC_COMM_WORLD, s));
  PetscCall(AddBody(*s, "stator", g->body[0], &b0));
  PetscCall(AddBody(*s, "rotor", g->body[1], &b1));
  PetscCall(KFSceneAddInterface(*s, b0, "bearing", g->iface[0]));
  PetscCall(KFSceneAddInterface(*s, b1, "bearing", g->iface[1]));
  PetscCall(KFSceneAddJoint(*s, "spin_bearing", KF_JOINT_REVOLUTE, b0, "bearing", b1, "bearing", g->axis, NULL));
  PetscCall(KFSceneSetNumIO(*s, 1, 1));
  PetscCall(KFSceneAddInputLoad(*s, 0, b0, g->iface[0], 5, 1.0));
  PetscCall(KFSceneAddInputLoad(*s, 0, b1, g->iface[1], 5, -1.0));
  PetscCall(KFSceneAddOutputReading(*s, 0, b0, g->body[0]->ids[1], 4, 1.0));
  PetscFunctionReturn(0);
}

typedef enum {
  BAD_MISSING_INTERFACE_NODE,
  BAD_JOINT_TO_ITSELF,
  BAD_UNREACHED_BODY
} BadCase;

/* Builds a broken scene; returns the first error code (0 if every call succeeded). */
static PetscErrorCode TryBadScene(Galileo *g, BadCase which, PetscErrorCode *code)
{
  KFScene        s;
  PetscInt       b0, b1, b2;
  PetscErrorCode ierr = 0;

  PetscFunctionBegin;
  PetscCall(KFSceneCreate(PETSC_COMM_WORLD, &s));
  PetscCall(AddBody(s, "stator", g->body[0], &b0));
  PetscCall(AddBody(s, "rotor", g->body[1], &b1));
  PetscCall(KFSceneAddInterface(s, b0, "bearing", g->iface[0]));
  PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  switch (which) {
  case BAD_MISSING_INTERFACE_NODE:
    ierr = KFSceneAddInterface(s, b1, "bearing", 9999);
    if (!ierr) ierr = KFSceneAddJoint(s, "j", KF_JOINT_REVOLUTE, b0, "bearing", b1, "bearing", g->axis, NULL);
    break;
  case BAD_JOINT_TO_ITSELF:
    ierr = KFSceneAddInterface(s, b1, "bearing", g->iface[1]);
    if (!ierr) ierr = KFSceneAddJoint(s, "j", KF_JOINT_REVOLUTE, b0, "bearing", b0, "bearing", g->axis, NULL);
    break;
  case BAD_UNREACHED_BODY:
    ierr = KFSceneAddInterface(s, b1, "bearing", g->iface[1]);
    if (!ierr) ierr = KFSceneAddJoint(s, "j", KF_JOINT_REVOLUTE, b0, "bearing", b1, "bearing", g->axis, NULL);
    if (!ierr) ierr = AddBody(s, "spare", g->body[0], &b2);
    break;
  }
  if (!ierr) ierr = KFSceneSetNumIO(s, 1, 1);
  if (!ierr) ierr = KFSceneAddInputLoad(s, 0, b0, g->iface[0], 5, 1.0);
  if (!ierr) ierr = KFSceneAddOutputReading(s, 0, b0, g->iface[0], 4, 1.0);
  if (!ierr) ierr = KFSceneSetUp(s);
  PetscCall(PetscPopErrorHandler());
  PetscCall(KFSceneDestroy(&s));
  *code = ierr;
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  Body           stator, rotor;
  Galileo        g;
  KFScene        s;
  KFSystem       y;
  PetscInt       nb, nj, nr, ns, ni, no;
  PetscErrorCode code = 0;
  const char    *bad_names[] = {"interface on a node the body does not have", "joint from a body to itself", "a body no joint reaches"};

  PetscCall(PetscInitialize(&argc, &argv, NULL, "Tests of scene building and assembly"));
  PetscCall(PetscMemzero(&stator, sizeof(stator)));
  PetscCall(PetscMemzero(&rotor, sizeof(rotor)));
  PetscCall(LoadBody("stator", &stator));
  PetscCall(LoadBody("rotor", &rotor));
  g.body[0] = &stator;
  g.body[1] = &rotor;
  g.iface[0] = stator.ids[0]; /* the bearing nodes: the first node of each file (see meshes/galileo/galileo.yaml) */
  g.iface[1] = rotor.ids[0];
  g.axis[0] = 0;
  g.axis[1] = 0;
  g.axis[2] = 1;

  PetscCall(BuildGalileo(&g, &s));
  PetscCall(KFSceneSetUp(s));
  PetscCall(KFSceneGetInfo(s, &nb, &nj, &nr, &ns, &ni, &no));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "Galileo-like scene built by hand: %" PetscInt_FMT " bodies, %" PetscInt_FMT " joint(s), %" PetscInt_FMT " system dofs\n", nb, nj, ns));
  PetscCall(CheckTrue("scene info: 2 bodies, 1 revolute joint, 1 input, 1 output", nb == 2 && nj == 1 && nr == 1 && ni == 1 && no == 1 ? PETSC_TRUE : PETSC_FALSE));
  PetscCall(CheckTrue("scene info: system dofs = stator + rotor dofs - 5", ns == stator.n + rotor.n - 5 ? PETSC_TRUE : PETSC_FALSE));
  PetscCall(KFSystemCreate(s, &y));
  PetscCall(CheckAtAngle(y, &g, 0.0));
  PetscCall(CheckAtAngle(y, &g, 40.0));
  PetscCall(KFSystemDestroy(&y));
  PetscCall(KFSceneDestroy(&s));

  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "bad scenes return an error code:\n"));
  for (BadCase c = BAD_MISSING_INTERFACE_NODE; c <= BAD_UNREACHED_BODY; c++) {
    char what[128];
    PetscCall(TryBadScene(&g, c, &code));
    PetscCall(PetscSNPrintf(what, sizeof(what), "%s: error code %d", bad_names[c], (int)code));
    PetscCall(CheckTrue(what, code ? PETSC_TRUE : PETSC_FALSE));
  }

  PetscCall(MatDestroy(&stator.M));
  PetscCall(MatDestroy(&stator.K));
  PetscCall(MatDestroy(&rotor.M));
  PetscCall(MatDestroy(&rotor.K));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "%s: %d failure(s)\n", nfail ? "FAILED" : "passed", nfail));
  PetscCall(PetscFinalize());
  return nfail ? 1 : 0;
}
