#include <kryflex_impl.h>
#include <petscblaslapack.h>

/* Rigid-body and mechanism modes from node coordinates and joints: 6 rigid motions of the whole scene
   (translations and rotations in the root frame) and, per revolute joint, the rotation of the child's subtree about
   the joint axis. They are written in system dofs: kept body dofs take the body-frame motion, the joints' free
   rotations (beta) are 1 for their own mechanism mode. */

static void Cross(const PetscReal a[3], const PetscReal b[3], PetscReal c[3])
{
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

/* is body b in the subtree hanging from joint j's child? */
static PetscBool InSubtree(KFScene s, PetscInt b, PetscInt j)
{
  while (b >= 0) {
    if (b == s->joints[j].child) return PETSC_TRUE;
    b = s->bodies[b].parent_joint >= 0 ? s->joints[s->bodies[b].parent_joint].parent : -1;
  }
  return PETSC_FALSE;
}

/* Candidate m on body b as a body-frame rigid motion: translation tb at the body origin and rotation wb (0-2
   translations, 3-5 rotations about the root frame's axes, 6+ the rotation of revolute joint m-6's child subtree
   about the joint axis; zero when body b is not in that subtree). It depends on the body and the candidate only,
   so it is formed once per pair, not once per dof. */
static void KFRigidCandidateMotion(KFSystem y, PetscInt b, PetscInt m, PetscReal tb[3], PetscReal wb[3])
{
  KFScene   s = y->scene;
  PetscReal *Q = y->Q[b], *o = y->o[b];
  PetscReal  t[3] = {0, 0, 0}, w[3] = {0, 0, 0}, anchor[3] = {0, 0, 0}, d[3], disp[3];

  for (int c = 0; c < 3; c++) tb[c] = wb[c] = 0;
  if (m < 3) t[m] = 1;
  else if (m < 6) w[m - 3] = 1;
  else {
    /* mechanism: the child subtree of revolute joint m-6 turns about the joint axis through the joint */
    PetscInt j;
    for (j = 0; j < s->nj; j++)
      if (s->joints[j].revolute == m - 6) break;
    if (!InSubtree(s, b, j)) return;
    {
      KFJointData *J  = &s->joints[j];
      KFBodyData  *Pb = &s->bodies[J->parent];
      PetscReal   *Qp = y->Q[J->parent], *op = y->o[J->parent], *xp = &Pb->xyz[3 * Pb->iface[J->parent_iface].node];
      for (int c = 0; c < 3; c++) {
        anchor[c] = op[c];
        for (int k = 0; k < 3; k++) {
          w[c] += Qp[c + 3 * k] * J->axis[k];
          anchor[c] += Qp[c + 3 * k] * xp[k];
        }
      }
    }
  }
  for (int c = 0; c < 3; c++) d[c] = o[c] - anchor[c];
  Cross(w, d, disp);
  for (int c = 0; c < 3; c++) disp[c] += t[c]; /* the motion of the body origin */
  for (int c = 0; c < 3; c++) { /* in the body frame: Q^T */
    for (int k = 0; k < 3; k++) {
      tb[c] += Q[k + 3 * c] * disp[k];
      wb[c] += Q[k + 3 * c] * w[k];
    }
  }
}

/* Value at one dof of the body-frame motion (tb, wb), from the values R[0..5] of the body's 6 motions there
   (KFBodyRigidValue; scalar points included) */
static PetscReal KFRigidMotionValue(const PetscReal R[6], const PetscReal tb[3], const PetscReal wb[3])
{
  PetscReal val = 0;

  for (int c = 0; c < 3; c++) val += tb[c] * R[c] + wb[c] * R[3 + c];
  return val;
}

/* Value at (body b, node, component comp) of candidate m */
static PetscReal KFRigidCandidateValue(KFSystem y, PetscInt b, PetscInt node, PetscInt comp, PetscInt m)
{
  PetscReal tb[3], wb[3], R[6];

  KFRigidCandidateMotion(y, b, m, tb, wb);
  for (PetscInt c = 0; c < 6; c++) R[c] = KFBodyRigidValue(&y->scene->bodies[b], node, comp, c);
  return KFRigidMotionValue(R, tb, wb);
}

/* The independent combinations of the columns of C (a dof layout without some components sees some candidates not
   at all: a plate of uz rx ry nodes in the xy plane does not see ux, uy, rz): the eigenvectors of the small Gram
   matrix C^T C above 1e-20 scale2 (singular values 1e-10 of the candidates' scale: ||C_0||_F^2 of the unrestricted
   candidates, since a restriction to a space the layout does not see leaves columns of rounding size only), scaled. */
static PetscErrorCode KFRigidIndependent(Mat C, PetscReal scale2, Mat *Phi)
{
  PetscInt   n, N, nl, k = 0;
  PetscReal *G, *Id, *lam, *V, *W;
  MPI_Comm   comm;

  PetscFunctionBegin;
  PetscCall(PetscObjectGetComm((PetscObject)C, &comm));
  PetscCall(MatGetSize(C, &N, &n));
  PetscCall(MatGetLocalSize(C, &nl, NULL));
  if (!n) {
    PetscCall(MatDuplicate(C, MAT_COPY_VALUES, Phi));
    PetscFunctionReturn(0);
  }
  PetscCall(PetscMalloc5(n * n, &G, n * n, &Id, n, &lam, n * n, &V, n * n, &W));
  PetscCall(KFMatTransposeMatMultGather(C, C, G));
  for (PetscInt i = 0; i < n * n; i++) Id[i] = (i % (n + 1)) == 0;
  for (PetscInt j = 0; j < n; j++)
    for (PetscInt i = 0; i < j; i++) G[i + j * n] = G[j + i * n] = 0.5 * (G[i + j * n] + G[j + i * n]);
  PetscCall(KFDenseEig(n, G, Id, lam, V));
  for (PetscInt j = 0; j < n; j++)
    if (lam[j] > 1e-20 * scale2 && lam[j] > 0) {
      for (PetscInt i = 0; i < n; i++) W[i + k * n] = V[i + j * n] / PetscSqrtReal(lam[j]);
      k++;
    }
  PetscCall(KFDenseCreate(comm, nl, N, k, Phi));
  if (k) PetscCall(KFDenseMultSmall(C, n, k, W, 1.0, *Phi));
  PetscCall(PetscFree5(G, Id, lam, V, W));
  PetscFunctionReturn(0);
}

/* The candidates restricted to what the boundary conditions allow: combinations Z of the 6 + nrevolute geometric
   motions that vanish on every clamped and spring dof (the null space of the small matrix D of their values there,
   by SVD). A clamp leaves none, a grounded revolute joint one (its mechanism), springs on one node some. */
static PetscErrorCode KFSystemRigidFromGeometry(KFSystem y, Mat *Phi)
{
  KFScene      s = y->scene;
  PetscInt     ncand = 6 + s->nrevolute, lda, nbc = 0, r, row = 0;
  PetscScalar *a;
  PetscReal   *D, *Z, scale2, *motion;
  Mat          C;

  PetscFunctionBegin;
  PetscCall(KFDenseCreate(s->comm, s->nsys_local, s->nsys, ncand, &C));
  PetscCall(MatDenseGetLDA(C, &lda));
  PetscCall(MatDenseGetArrayWrite(C, &a));
  for (PetscInt m = 0; m < ncand; m++)
    for (PetscInt i = 0; i < s->nsys_local; i++) a[i + m * lda] = 0;
  PetscCall(PetscMalloc1(6 * ncand, &motion));
  for (PetscInt b = 0; b < s->nb; b++) {
    KFBodyData *B = &s->bodies[b];
    for (PetscInt m = 0; m < ncand; m++) KFRigidCandidateMotion(y, b, m, &motion[6 * m], &motion[6 * m + 3]);
    for (PetscInt i = B->rstart; i < B->rend; i++) {
      PetscInt  sys = B->sysidx[i - B->rstart], node, comp;
      PetscReal R[6];
      if (sys < 0) continue;
      PetscCall(KFBodyDofComponent(B, i, &node, &comp));
      for (PetscInt c = 0; c < 6; c++) R[c] = KFBodyRigidValue(B, node, comp, c);
      for (PetscInt m = 0; m < ncand; m++) a[(sys - s->sys_rstart) + m * lda] = KFRigidMotionValue(R, &motion[6 * m], &motion[6 * m + 3]);
    }
  }
  PetscCall(PetscFree(motion));
  for (PetscInt j = 0; j < s->nj; j++) {
    PetscInt beta = s->joints[j].beta;
    if (beta >= s->sys_rstart && beta < s->sys_rstart + s->nsys_local) a[(beta - s->sys_rstart) + (6 + s->joints[j].revolute) * lda] = 1.0;
  }
  PetscCall(MatDenseRestoreArrayWrite(C, &a));
  PetscCall(MatAssemblyBegin(C, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(C, MAT_FINAL_ASSEMBLY));

  PetscCall(MatNorm(C, NORM_FROBENIUS, &scale2));
  scale2 *= scale2;
  for (PetscInt b = 0; b < s->nb; b++) nbc += s->bodies[b].nclamp + s->bodies[b].nspring;
  if (!nbc) {
    PetscCall(KFRigidIndependent(C, scale2, Phi));
    PetscFunctionReturn(0);
  }
  /* D (nbc x ncand): every rank has the node coordinates and frames, so D is the same everywhere without messages */
  PetscCall(PetscMalloc2(nbc * ncand, &D, ncand * ncand, &Z));
  for (PetscInt b = 0; b < s->nb; b++) {
    KFBodyData *B = &s->bodies[b];
    for (PetscInt k = 0; k < B->nclamp + B->nspring; k++, row++) {
      PetscInt dof = k < B->nclamp ? B->clamp[k] : B->spring_dof[k - B->nclamp], node, comp;
      PetscCall(KFBodyDofComponent(B, dof, &node, &comp));
      for (PetscInt m = 0; m < ncand; m++) D[row + m * nbc] = KFRigidCandidateValue(y, b, node, comp, m);
    }
  }
  PetscCall(KFDenseNullSpace(nbc, ncand, D, 1e-10, &r, Z, NULL, NULL));
  {
    Mat R;
    PetscCall(KFDenseCreate(s->comm, s->nsys_local, s->nsys, r, &R));
    if (r) PetscCall(KFDenseMultSmall(C, ncand, r, Z, 1.0, R));
    PetscCall(KFRigidIndependent(R, scale2, Phi));
    PetscCall(MatDestroy(&R));
  }
  PetscCall(MatDestroy(&C));
  PetscCall(PetscFree2(D, Z));
  PetscFunctionReturn(0);
}

/* Value at (node, comp) of body-frame rigid motion m (0-2 translations, 3-5 rotations about the body origin) */
PetscReal KFBodyRigidValue(const KFBodyData *B, PetscInt node, PetscInt comp, PetscInt m)
{
  const PetscReal *x = &B->xyz[3 * node];
  PetscReal        w[3] = {0, 0, 0};

  if (comp == KF_COMPONENT_SCALAR) return B->scalar_rigid ? B->scalar_rigid[B->scalar_of_node[node] + m * B->nscalar] : 0;
  if (m < 3) return comp == m ? 1.0 : 0.0;
  w[m - 3] = 1;
  if (comp >= 3) return w[comp - 3];
  {
    PetscReal c[3];
    Cross(w, x, c);
    return c[comp];
  }
}

/* Scalar points have no geometry: each of a body's 6 rigid motions gives them the values of least strain energy with
   the geometric dofs following the motion, x_s = -K_ss^-1 K_sg g (static condensation). A rigid motion then strains
   nothing exactly when the body is rigid in that motion, which the check against K verifies as for any dof. */
PetscErrorCode KFSceneScalarRigid(KFScene s)
{
  PetscFunctionBegin;
  for (PetscInt bi = 0; bi < s->nb; bi++) {
    KFBodyData  *B  = &s->bodies[bi];
    PetscInt     ns = B->nscalar, *sd, lda, k = 0;
    Mat          C, Y, *sub;
    IS           is;
    PetscScalar *c;
    PetscReal   *Ys, *Kss;
    PetscBLASInt bn, six = 6, info;

    if (!ns || B->scalar_rigid) continue;
    PetscCall(PetscMalloc1(ns, &sd));
    PetscCall(PetscMalloc1(6 * ns, &Ys));
    PetscCall(PetscMalloc1(ns * ns, &Kss));
    for (PetscInt i = 0; i < B->nnodes; i++)
      if (!B->comps[i]) sd[k++] = B->dof0[i];
    PetscCall(KFDenseCreate(s->comm, B->rend - B->rstart, B->n, 6, &C));
    PetscCall(MatDenseGetLDA(C, &lda));
    PetscCall(MatDenseGetArray(C, &c));
    for (PetscInt i = B->rstart; i < B->rend; i++) {
      PetscInt node, comp;
      PetscCall(KFBodyDofComponent(B, i, &node, &comp));
      for (PetscInt m = 0; m < 6; m++) c[(i - B->rstart) + m * lda] = comp == KF_COMPONENT_SCALAR ? 0 : KFBodyRigidValue(B, node, comp, m);
    }
    PetscCall(MatDenseRestoreArray(C, &c));
    PetscCall(MatMatMult(B->K, C, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &Y));
    PetscCall(PetscArrayzero(Ys, 6 * ns));
    PetscCall(MatDenseGetLDA(Y, &lda));
    PetscCall(MatDenseGetArray(Y, &c));
    for (PetscInt q = 0; q < ns; q++)
      if (sd[q] >= B->rstart && sd[q] < B->rend)
        for (PetscInt m = 0; m < 6; m++) Ys[q + m * ns] = -PetscRealPart(c[(sd[q] - B->rstart) + m * lda]);
    PetscCall(MatDenseRestoreArray(Y, &c));
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, Ys, (PetscMPIInt)(6 * ns), MPIU_REAL, MPIU_SUM, s->comm));
    PetscCall(MatDestroy(&Y));
    PetscCall(MatDestroy(&C));
    /* K_ss on every rank */
    PetscCall(ISCreateGeneral(PETSC_COMM_SELF, ns, sd, PETSC_COPY_VALUES, &is));
    PetscCall(MatCreateSubMatrices(B->K, 1, &is, &is, MAT_INITIAL_MATRIX, &sub));
    PetscCall(ISDestroy(&is));
    for (PetscInt i = 0; i < ns; i++) {
      PetscInt           nc;
      const PetscInt    *cols;
      const PetscScalar *vals;
      for (PetscInt j = 0; j < ns; j++) Kss[i + j * ns] = 0;
      PetscCall(MatGetRow(sub[0], i, &nc, &cols, &vals));
      for (PetscInt j = 0; j < nc; j++) Kss[i + cols[j] * ns] = PetscRealPart(vals[j]);
      PetscCall(MatRestoreRow(sub[0], i, &nc, &cols, &vals));
    }
    PetscCall(MatDestroySubMatrices(1, &sub));
    PetscCall(PetscBLASIntCast(ns, &bn));
    PetscCallBLAS("LAPACKpotrf", LAPACKpotrf_("L", &bn, Kss, &bn, &info));
    PetscCheck(!info, s->comm, PETSC_ERR_ARG_WRONG, "body '%s': the stiffness among its %" PetscInt_FMT " scalar points is singular (leading minor %d): a scalar point not held by stiffness has no defined rigid motion; tie it to the structure, clamp it, or give it a spring", B->name, ns, (int)info);
    PetscCallBLAS("LAPACKpotrs", LAPACKpotrs_("L", &bn, &six, Kss, &bn, Ys, &bn, &info));
    B->scalar_rigid = Ys; /* ns x 6 */
    PetscCall(PetscFree(sd));
    PetscCall(PetscFree(Kss));
  }
  PetscFunctionReturn(0);
}

PetscErrorCode KFBodyAdmissibleRigid(KFBodyData *B, PetscInt *rb, PetscReal Z[36])
{
  PetscInt   nbc = B->nclamp + B->nspring;
  PetscReal *D;

  PetscFunctionBegin;
  PetscCall(PetscMalloc1(6 * nbc + 1, &D));
  for (PetscInt k = 0; k < nbc; k++) {
    PetscInt dof = k < B->nclamp ? B->clamp[k] : B->spring_dof[k - B->nclamp], node, comp;
    PetscCall(KFBodyDofComponent(B, dof, &node, &comp));
    for (PetscInt m = 0; m < 6; m++) D[k + m * nbc] = KFBodyRigidValue(B, node, comp, m);
  }
  PetscCall(KFDenseNullSpace(nbc, 6, D, 1e-10, rb, Z, NULL, NULL));
  PetscCall(PetscFree(D));
  PetscFunctionReturn(0);
}

/* M-orthonormalizes the columns (Cholesky of the small Gram matrix, twice for accuracy) */
PETSC_INTERN PetscErrorCode KFMOrthonormalize(Mat M, Mat X, const char what[])
{
  PetscFunctionBegin;
  PetscCall(KFMOrthonormalizeProduct(M, X, 2, NULL, what));
  PetscFunctionReturn(0);
}

/* The same with the given number of passes, each with a fresh product M X (one pass is enough for columns that are
   M-orthonormal to a few digits already: the body basis after its Gram-Schmidt). MX, if asked for, is M times the
   result: the last pass's product transformed as X was (X <- X L^-T, MX <- MX L^-T), so that the caller needs no
   further product with M (its error is rounding times the condition of L, ~1 after the first pass). */
PETSC_INTERN PetscErrorCode KFMOrthonormalizeProduct(Mat M, Mat X, PetscInt passes, Mat *MXout, const char what[])
{
  PetscInt     r, nl, lda, ldm;
  PetscReal   *Gm;
  PetscScalar *x, *mx;
  Mat          MX = NULL;
  MPI_Comm     comm;

  PetscFunctionBegin;
  PetscCall(PetscObjectGetComm((PetscObject)X, &comm));
  PetscCall(MatGetSize(X, NULL, &r));
  PetscCall(MatGetLocalSize(X, &nl, NULL));
  if (MXout) *MXout = NULL;
  if (!r) {
    if (MXout) PetscCall(KFMatMultDense(M, X, MXout));
    PetscFunctionReturn(0);
  }
  PetscCall(PetscMalloc1(r * r, &Gm));
  for (PetscInt pass = 0; pass < passes; pass++) {
    PetscCall(MatDestroy(&MX));
    PetscCall(KFMatMultDense(M, X, &MX));
    PetscCall(KFMatTransposeMatMultGather(X, MX, Gm));
    /* Cholesky Gm = L L^T, then X <- X L^-T */
    for (PetscInt j = 0; j < r; j++) {
      PetscReal d = Gm[j + j * r];
      for (PetscInt k = 0; k < j; k++) d -= Gm[j + k * r] * Gm[j + k * r];
      PetscCheck(d > 0, comm, PETSC_ERR_ARG_WRONG, "%s are linearly dependent in the M-inner product (column %" PetscInt_FMT "), or M is not positive definite; check node coordinates and the mass matrix", what, j);
      Gm[j + j * r] = PetscSqrtReal(d);
      for (PetscInt i = j + 1; i < r; i++) {
        PetscReal v = Gm[i + j * r];
        for (PetscInt k = 0; k < j; k++) v -= Gm[i + k * r] * Gm[j + k * r];
        Gm[i + j * r] = v / Gm[j + j * r];
      }
    }
    PetscCall(MatDenseGetLDA(X, &lda));
    PetscCall(MatDenseGetLDA(MX, &ldm));
    PetscCall(MatDenseGetArray(X, &x));
    PetscCall(MatDenseGetArray(MX, &mx));
    if (nl > 0) { /* X <- X L^-T, and MX with it (the last pass's product is then M X of the result) */
      PetscBLASInt bn, br, bla, blm, bld;
      PetscScalar  one = 1.0;
      PetscCall(PetscBLASIntCast(nl, &bn));
      PetscCall(PetscBLASIntCast(r, &br));
      PetscCall(PetscBLASIntCast(lda, &bla));
      PetscCall(PetscBLASIntCast(ldm, &blm));
      bld = br;
      PetscCallBLAS("BLAStrsm", BLAStrsm_("R", "L", "T", "N", &bn, &br, &one, Gm, &bld, x, &bla));
      if (MXout && pass == passes - 1) PetscCallBLAS("BLAStrsm", BLAStrsm_("R", "L", "T", "N", &bn, &br, &one, Gm, &bld, mx, &blm));
    }
    PetscCall(MatDenseRestoreArray(MX, &mx));
    PetscCall(MatDenseRestoreArray(X, &x));
  }
  PetscCall(PetscFree(Gm));
  if (MXout) *MXout = MX;
  else PetscCall(MatDestroy(&MX));
  PetscFunctionReturn(0);
}

/* ||K Phi||_F / (||K||_F ||Phi||_F): rigid modes must carry no strain energy */
static PetscErrorCode KFSystemRigidResidual(KFSystem y, PetscReal *res)
{
  Mat       KP;
  PetscReal nKP, nK, nP;

  PetscFunctionBegin;
  *res = 0;
  if (!y->nrigid) PetscFunctionReturn(0);
  PetscCall(KFMatMultDense(y->Ks, y->Phi, &KP)); /* MatMatMult's sums, one read of K per 8 columns */
  PetscCall(MatNorm(KP, NORM_FROBENIUS, &nKP));
  PetscCall(MatNorm(y->Ks, NORM_FROBENIUS, &nK));
  PetscCall(MatNorm(y->Phi, NORM_FROBENIUS, &nP));
  PetscCall(MatDestroy(&y->KPhi)); /* kept for the model check's rigid energy (KFSystemGetRigidProducts) */
  y->KPhi = KP;
  *res = nKP / (nK * nP);
  PetscFunctionReturn(0);
}

/* The dof where the rigid modes strain the structure most (largest row of K Phi), as "body 'b', node n, component c" */
static PetscErrorCode KFSystemRigidWorstDof(KFSystem y, char where[], size_t len)
{
  KFScene            s = y->scene;
  Mat                KP;
  const PetscScalar *a;
  PetscInt           lda, r, best = -1, gbest;
  PetscReal          vmax = -1, gmax, found[3] = {-1, -1, -1}, all[3];
  static const char *cn[] = {"ux", "uy", "uz", "rx", "ry", "rz", "s"};

  PetscFunctionBegin;
  PetscCall(MatMatMult(y->Ks, y->Phi, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &KP));
  PetscCall(MatGetSize(KP, NULL, &r));
  PetscCall(MatDenseGetLDA(KP, &lda));
  PetscCall(MatDenseGetArrayRead(KP, &a));
  for (PetscInt i = 0; i < s->nsys_local; i++) {
    PetscReal v = 0;
    for (PetscInt k = 0; k < r; k++) v += PetscRealPart(a[i + k * lda]) * PetscRealPart(a[i + k * lda]);
    if (v > vmax) {
      vmax = v;
      best = s->sys_rstart + i;
    }
  }
  PetscCall(MatDenseRestoreArrayRead(KP, &a));
  PetscCall(MatDestroy(&KP));
  PetscCall(MPIU_Allreduce(&vmax, &gmax, 1, MPIU_REAL, MPIU_MAX, s->comm));
  if (vmax < gmax) best = -1;
  PetscCall(MPIU_Allreduce(&best, &gbest, 1, MPIU_INT, MPI_MAX, s->comm));
  for (PetscInt b = 0; b < s->nb; b++) { /* the body dof that is system dof gbest (on the rank that owns it) */
    KFBodyData *B = &s->bodies[b];
    for (PetscInt i = 0; i < B->rend - B->rstart; i++)
      if (B->sysidx[i] == gbest) {
        PetscInt node, comp;
        PetscCall(KFBodyDofComponent(B, B->rstart + i, &node, &comp));
        found[0] = b;
        found[1] = node;
        found[2] = comp;
      }
  }
  PetscCall(MPIU_Allreduce(found, all, 3, MPIU_REAL, MPIU_MAX, s->comm));
  if (all[0] < 0) PetscCall(PetscSNPrintf(where, len, "system dof %" PetscInt_FMT " (a joint's free rotation)", gbest));
  else {
    KFBodyData *B = &s->bodies[(PetscInt)all[0]];
    PetscCall(PetscSNPrintf(where, len, "body '%s', node %" PetscInt_FMT ", component %s", B->name, B->ids[(PetscInt)all[1]], cn[(PetscInt)all[2]]));
  }
  PetscFunctionReturn(0);
}

/* -kf_rigid_tol: how much strain the rigid-body modes may show, ||K Phi|| / (||K|| ||Phi||) (also read before any work:
   KFReducerSetFromOptions) */
PETSC_INTERN PetscErrorCode KFRigidTolFromOptions(MPI_Comm comm, PetscReal *tol)
{
  PetscFunctionBegin;
  *tol = 1e-8;
  PetscOptionsBegin(comm, NULL, "kryflex rigid-body and mechanism modes", "KFSystemComputeRigidModes");
  PetscCall(KFOptionsSettingReal(PetscOptionsObject, "-kf_rigid_tol", *tol, tol, NULL));
  PetscOptionsEnd();
  PetscFunctionReturn(0);
}

PetscErrorCode KFSystemComputeRigidModes(KFSystem y)
{
  PetscReal tol;

  PetscFunctionBegin;
  PetscCheck(y->assembled, y->scene->comm, PETSC_ERR_ORDER, "call KFSystemSetAngles() first");
  if (y->Phi) PetscFunctionReturn(0);
  PetscCall(PetscLogEventBegin(KF_EVENT_RIGID, 0, 0, 0, 0));
  PetscCall(KFRigidTolFromOptions(y->scene->comm, &tol));
  PetscCall(KFSystemRigidFromGeometry(y, &y->Phi));
  PetscCall(MatGetSize(y->Phi, NULL, &y->nrigid));
  PetscCall(KFMOrthonormalize(y->Ms, y->Phi, "rigid-body modes from node coordinates"));
  PetscCall(KFSystemRigidResidual(y, &y->rigid_residual));
  { /* the verdict is collective (the tolerance is an option, which ranks may be given differently): naming the
       strained dof takes collective calls */
    PetscBool bad = (PetscBool)(y->rigid_residual > tol), anybad;
    PetscCall(MPIU_Allreduce(&bad, &anybad, 1, MPIU_BOOL, MPI_LOR, y->scene->comm));
    if (anybad && !bad) tol = y->rigid_residual / 2; /* the message names the tolerance that failed */
  }
  if (y->rigid_residual > tol) {
    char where[2 * KF_MAX_NAME + 64] = "";
    /* a strain above rounding has a place worth naming; rounding-level residuals (a tolerance set below them) have none */
    if (y->rigid_residual > 1e-12) PetscCall(KFSystemRigidWorstDof(y, where, sizeof(where)));
    SETERRQ(y->scene->comm, PETSC_ERR_ARG_WRONG, "the %" PetscInt_FMT " rigid-body and mechanism modes built from node coordinates, joints and boundary conditions strain the structure: ||K Phi|| / (||K|| ||Phi||) = %g > %g%s%s. The node coordinates do not match K (wrong units, order, or missing coordinates), or K holds supports the scene does not declare (clamped dofs exported as stiff springs: declare them as constraints); fix the nodes files or supply rigid modes (-kf_rigid_tol to loosen)", y->nrigid, (double)y->rigid_residual, (double)tol, where[0] ? ", most at " : "", where);
  }
  if (y->scene->nrigid < 0) {
    PetscInt nbc = 0;
    for (PetscInt b = 0; b < y->scene->nb; b++) nbc += y->scene->bodies[b].nclamp + y->scene->bodies[b].nspring;
    PetscCall(KFProgress(y->scene->comm, "rigid-body and mechanism modes: %" PetscInt_FMT " (of 6 + %" PetscInt_FMT " revolute joints; %" PetscInt_FMT " clamped or spring dofs), ||K Phi|| / (||K|| ||Phi||) = %.1e", y->nrigid, y->scene->nrevolute, nbc, (double)y->rigid_residual));
  }
  y->scene->nrigid = y->nrigid;
  PetscCall(PetscLogEventEnd(KF_EVENT_RIGID, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

PetscErrorCode KFSystemSetRigidModes(KFSystem y, Mat Phi)
{
  PetscInt  m, r;
  PetscReal tol;

  PetscFunctionBegin;
  PetscCheck(y->assembled, y->scene->comm, PETSC_ERR_ORDER, "call KFSystemSetAngles() before KFSystemSetRigidModes(): the modes belong to one configuration");
  PetscCall(MatGetSize(Phi, &m, &r));
  PetscCheck(m == y->scene->nsys, y->scene->comm, PETSC_ERR_ARG_SIZ, "supplied rigid modes have %" PetscInt_FMT " rows, the system has %" PetscInt_FMT " dofs", m, y->scene->nsys);
  PetscCall(MatDestroy(&y->Phi));
  PetscCall(MatDestroy(&y->MPhi));
  PetscCall(MatDestroy(&y->KPhi));
  PetscCall(MatConvert(Phi, MATDENSE, MAT_INITIAL_MATRIX, &y->Phi));
  PetscCall(KFMOrthonormalize(y->Ms, y->Phi, "supplied rigid-body modes"));
  y->nrigid     = r;
  y->user_rigid = PETSC_TRUE;
  y->scene->nrigid = r;
  PetscCall(KFRigidTolFromOptions(y->scene->comm, &tol));
  PetscCall(KFSystemRigidResidual(y, &y->rigid_residual));
  PetscCheck(y->rigid_residual <= tol, y->scene->comm, PETSC_ERR_ARG_WRONG, "the supplied rigid-body modes strain the structure: ||K Phi|| / (||K|| ||Phi||) = %g > %g", (double)y->rigid_residual, (double)tol);
  PetscFunctionReturn(0);
}

PetscErrorCode KFSystemGetRigidModes(KFSystem y, Mat *Phi, PetscReal *residual)
{
  PetscFunctionBegin;
  PetscCall(KFSystemComputeRigidModes(y));
  if (Phi) *Phi = y->Phi;
  if (residual) *residual = y->rigid_residual;
  PetscFunctionReturn(0);
}

/* Ks Phi and Ms Phi of the rigid modes (computed first where needed), the system's own (borrowed; NULL without rigid
   modes): the products the rigid residual and the projections make, for a caller that needs Phi^T K Phi and
   Phi^T M Phi (the model check's rigid energy), which would otherwise form both again */
PetscErrorCode KFSystemGetRigidProducts(KFSystem y, Mat *KPhi, Mat *MPhi)
{
  PetscFunctionBegin;
  PetscCall(KFSystemGetMPhi(y, MPhi));
  if (y->nrigid && !y->KPhi) PetscCall(KFMatMultDense(y->Ks, y->Phi, &y->KPhi));
  *KPhi = y->nrigid ? y->KPhi : NULL;
  PetscFunctionReturn(0);
}

/* X <- (I - Phi Phi^T M) X  (onto the flexible subspace), or with left: X <- (I - M Phi Phi^T) X (self-equilibrated loads).
   Both go through M Phi, computed once per set of rigid modes (M symmetric: Phi^T M X = (M Phi)^T X): every block
   solve projects three times, and a sparse product with M per projection cost more than the rest of the solve's
   glue at 200k dofs. */
/* M Phi, formed once per set of rigid modes (NULL without rigid modes) and kept on the system for every projection and
   the Krylov basis' Gram-Schmidt */
PetscErrorCode KFSystemGetMPhi(KFSystem y, Mat *MPhi)
{
  PetscInt r;

  PetscFunctionBegin;
  PetscCall(KFSystemComputeRigidModes(y));
  PetscCall(MatGetSize(y->Phi, NULL, &r));
  if (r && !y->MPhi) PetscCall(KFMatMultDense(y->Ms, y->Phi, &y->MPhi)); /* MatMatMult's sums, one read of M per 8 columns */
  *MPhi = r ? y->MPhi : NULL;
  PetscFunctionReturn(0);
}

PetscErrorCode KFProjectFlexible(KFSystem y, Mat X, PetscBool left)
{
  Mat                MPhi;
  PetscInt           r, p, nl, ldx, ldp, ldmp;
  PetscReal         *c;
  PetscScalar       *x;
  const PetscScalar *phi, *mphi;

  PetscFunctionBegin;
  PetscCall(KFSystemGetMPhi(y, &MPhi));
  if (!MPhi) PetscFunctionReturn(0); /* clamped: every motion is flexible */
  PetscCall(MatGetSize(y->Phi, NULL, &r));
  PetscCall(MatGetSize(X, NULL, &p));
  PetscCall(MatGetLocalSize(X, &nl, NULL));
  PetscCall(PetscCalloc1(r * p + 1, &c));
  PetscCall(MatDenseGetLDA(X, &ldx));
  PetscCall(MatDenseGetLDA(y->Phi, &ldp));
  PetscCall(MatDenseGetLDA(MPhi, &ldmp));
  PetscCall(MatDenseGetArray(X, &x));
  PetscCall(MatDenseGetArrayRead(y->Phi, &phi));
  PetscCall(MatDenseGetArrayRead(MPhi, &mphi));
  /* a block of a few columns against r rigid modes: row chunk by row chunk (no packing of the tall Phi, M Phi) */
  PetscCall(KFArraySkinnyTransposeMult(nl, r, left ? phi : mphi, left ? ldp : ldmp, p, x, ldx, c, r)); /* Phi^T X or Phi^T M X */
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, c, (PetscMPIInt)(r * p), MPIU_REAL, MPIU_SUM, PetscObjectComm((PetscObject)X)));
  PetscCall(KFArraySkinnyMultAdd(nl, r, left ? mphi : phi, left ? ldmp : ldp, p, -1.0, c, r, x, ldx)); /* X -= M Phi c or Phi c */
  PetscCall(MatDenseRestoreArrayRead(MPhi, &mphi));
  PetscCall(MatDenseRestoreArrayRead(y->Phi, &phi));
  PetscCall(MatDenseRestoreArray(X, &x));
  PetscCall(PetscFree(c));
  PetscFunctionReturn(0);
}
