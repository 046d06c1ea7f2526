/* Reassembly of reduced bodies at any joint angles (eq. 20-24): interface constraints D phi = 0 of the
   reduced coordinates, their null space N by SVD, and the reduced system projected on N. */
#include "reassemble_impl.h"

/* Rows E (nrows x 3, row-wise) of the tie E (x_p - R x_c) on the components comp..comp+2 of the
   interface nodes, added to D (m x n) at row0. */
static void AddTieRows(PetscInt m, PetscReal D[], PetscInt row0, PetscInt nrows, const PetscReal E[][3], const PetscReal R[9], PetscInt comp, const KFReducedBody *parent, PetscInt poff, PetscInt pif, const KFReducedBody *child, PetscInt coff, PetscInt cif)
{
  const PetscInt ldp = 6 * parent->ninterfaces, ldc = 6 * child->ninterfaces;
  const PetscInt rp = 6 * pif + comp, rc = 6 * cif + comp;

  for (PetscInt q = 0; q < nrows; q++) {
    PetscReal ER[3]; /* E_q R: the child's coefficients */
    for (int s = 0; s < 3; s++) ER[s] = E[q][0] * R[0 + 3 * s] + E[q][1] * R[1 + 3 * s] + E[q][2] * R[2 + 3 * s];
    for (PetscInt col = 0; col < parent->v; col++) {
      const PetscReal *x = parent->iface + col * ldp + rp;
      D[row0 + q + (poff + col) * m] += E[q][0] * x[0] + E[q][1] * x[1] + E[q][2] * x[2];
    }
    for (PetscInt col = 0; col < child->v; col++) {
      const PetscReal *x = child->iface + col * ldc + rc;
      D[row0 + q + (coff + col) * m] -= ER[0] * x[0] + ER[1] * x[1] + ER[2] * x[2];
    }
  }
}

static PetscErrorCode CheckInputs(PetscInt nbodies, const KFReducedBody bodies[], PetscInt njoints, const KFJointDef joints[], PetscInt a, PetscInt t)
{
  PetscFunctionBegin;
  PetscCheck(nbodies >= 1, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFReassemble: no bodies to reassemble");
  PetscCheck(njoints >= 0 && a >= 0 && t >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFReassemble: negative size (joints %" PetscInt_FMT ", inputs %" PetscInt_FMT ", outputs %" PetscInt_FMT ")", njoints, a, t);
  for (PetscInt b = 0; b < nbodies; b++) {
    const KFReducedBody *B = &bodies[b];
    PetscCheck(B->v >= 0 && B->ninterfaces >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFReassemble: body %" PetscInt_FMT " has negative size (v %" PetscInt_FMT ", interfaces %" PetscInt_FMT ")", b, B->v, B->ninterfaces);
    PetscCheck(!B->v || (B->M && B->K && (B->G || !a) && (B->H || !t) && (B->iface || !B->ninterfaces)), PETSC_COMM_SELF, PETSC_ERR_ARG_NULL,
               "KFReassemble: body %" PetscInt_FMT " (v %" PetscInt_FMT ") lacks one of its reduced arrays M, K, G, H, iface", b, B->v);
  }
  for (PetscInt j = 0; j < njoints; j++) {
    const KFJointDef *J = &joints[j];
    PetscReal         err = 0;

    PetscCheck(J->type == KF_JOINT_REVOLUTE || J->type == KF_JOINT_FIXED, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFReassemble: joint %" PetscInt_FMT " has unknown type %d", j, (int)J->type);
    PetscCheck(J->parent >= 0 && J->parent < nbodies && J->child >= 0 && J->child < nbodies, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
               "KFReassemble: joint %" PetscInt_FMT " links bodies %" PetscInt_FMT " and %" PetscInt_FMT ", but there are %" PetscInt_FMT " bodies", j, J->parent, J->child, nbodies);
    PetscCheck(J->parent != J->child, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG, "KFReassemble: joint %" PetscInt_FMT " links body %" PetscInt_FMT " to itself", j, J->parent);
    PetscCheck(J->parent_interface >= 0 && J->parent_interface < bodies[J->parent].ninterfaces, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
               "KFReassemble: joint %" PetscInt_FMT ": parent interface %" PetscInt_FMT " does not exist (body %" PetscInt_FMT " has %" PetscInt_FMT ")", j, J->parent_interface, J->parent, bodies[J->parent].ninterfaces);
    PetscCheck(J->child_interface >= 0 && J->child_interface < bodies[J->child].ninterfaces, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
               "KFReassemble: joint %" PetscInt_FMT ": child interface %" PetscInt_FMT " does not exist (body %" PetscInt_FMT " has %" PetscInt_FMT ")", j, J->child_interface, J->child, bodies[J->child].ninterfaces);
    /* R0 is an array in the struct, not an optional pointer: a zeroed struct would silently drop the child's ties */
    for (int c = 0; c < 3; c++)
      for (int r = 0; r < 3; r++) {
        PetscReal g = J->R0[0 + 3 * r] * J->R0[0 + 3 * c] + J->R0[1 + 3 * r] * J->R0[1 + 3 * c] + J->R0[2 + 3 * r] * J->R0[2 + 3 * c];
        err         = PetscMax(err, PetscAbsReal(g - (r == c ? 1 : 0)));
      }
    PetscCheck(err <= 1e-6, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG, "KFReassemble: joint %" PetscInt_FMT ": R0 is not a rotation (max |R0^T R0 - I| = %g); set it to the identity when the frames are aligned", j, (double)err);
  }
  PetscFunctionReturn(0);
}

/* The system's rigid motions R = blkdiag(R_b) (n x nr), without the columns a body does not have and with dependent
   motions combined: depends on the bodies only, not on the angles. */
static PetscErrorCode KFReassemblyRigidMotions(KFReassembly r, PetscReal **Rout, PetscInt *nrout)
{
  const KFReducedBody *bodies = r->bodies;
  PetscInt             nb = r->nb, n = r->n, nr = 6 * nb;
  PetscReal           *R, ratio;

  PetscFunctionBegin;
  *Rout  = NULL;
  *nrout = -1;
  for (PetscInt b = 0; b < nb; b++)
    if (!bodies[b].rigid) PetscFunctionReturn(0);
  PetscCall(PetscCalloc1(n * nr + 1, &R));
  /* a body with boundary conditions (or a layout that does not see some motions) stores only the motions it has,
     the other columns zero, or of rounding size after a restriction: skip those below 1e-10 of the largest */
  {
    PetscReal cmax = 0;
    for (PetscInt b = 0; b < nb; b++)
      for (PetscInt k = 0; k < 6; k++) {
        PetscReal c = 0;
        for (PetscInt i = 0; i < bodies[b].v; i++) c += PetscSqr(bodies[b].rigid[i + k * bodies[b].v]);
        cmax = PetscMax(cmax, c);
      }
    ratio = cmax; /* the squared threshold's scale */
  }
  nr = 0;
  for (PetscInt b = 0; b < nb; b++)
    for (PetscInt k = 0; k < 6; k++) {
      PetscReal c = 0;
      for (PetscInt i = 0; i < bodies[b].v; i++) c += PetscSqr(bodies[b].rigid[i + k * bodies[b].v]);
      if (!(c > 1e-20 * ratio)) continue;
      for (PetscInt i = 0; i < bodies[b].v; i++) R[r->off[b] + i + nr * n] = bodies[b].rigid[i + k * bodies[b].v];
      nr++;
    }
  if (nr) { /* dependent motions (a body whose conditions leave combinations that mix motions its layout does not see):
               R <- R V_k on the eigenvectors of R^T R above 1e-12 of the largest (singular values 1e-6: the bodies'
               bases hold their rigid motions to about 1e-8); independent columns are kept as they are */
    PetscReal *Gm, *Id, *lam, *V, *R2;
    PetscInt   k = 0;
    PetscCall(PetscMalloc5(nr * nr, &Gm, nr * nr, &Id, nr, &lam, nr * nr, &V, n * nr, &R2));
    PetscCall(KFDenseGemm_Private('T', 'N', nr, nr, n, 1.0, R, n, R, n, 0.0, Gm, nr));
    PetscCall(KFDenseSymmetrize_Private(nr, Gm));
    for (PetscInt i = 0; i < nr * nr; i++) Id[i] = (i % (nr + 1)) == 0;
    PetscCall(KFDenseEig(nr, Gm, Id, lam, V));
    for (PetscInt j = 0; j < nr; j++) k += lam[j] > 1e-12 * lam[nr - 1];
    if (k < nr) {
      PetscCall(KFDenseGemm_Private('N', 'N', n, k, nr, 1.0, R, n, V + (nr - k) * nr, nr, 0.0, R2, n));
      PetscCall(PetscArraycpy(R, R2, n * k));
      nr = k;
    }
    PetscCall(PetscFree5(Gm, Id, lam, V, R2));
  }
  *Rout  = R;
  *nrout = nr;
  PetscFunctionReturn(0);
}

/*
  KFReassemblyCreate - the workspace of repeated reassembly of the same bodies and joints at changing angles (a time
  integration under moving joints): the bodies' arrays are copied, every array the reassembly and its
  eigen-decomposition need is allocated here, and KFReassemblyApply / KFReassemblyEig then allocate nothing.
  alpha, beta: Rayleigh damping added to the reassembled viscous damping (0, 0: none).
*/
static PetscErrorCode KFReassemblyCreate_Private(PetscInt nbodies, const KFReducedBody bodies[], PetscInt njoints, const KFJointDef joints[], PetscInt ms, const PetscReal Ds[], PetscInt a, PetscInt t, PetscReal rtol, PetscReal alpha, PetscReal beta, PetscBool witheig, KFReassembly *reassembly)
{
  KFReassembly r;
  PetscInt     n = 0, m = 0, total = 0, ldm, nrc;
  PetscReal   *p, *R;

  PetscFunctionBegin;
  PetscCheck(reassembly, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "KFReassemblyCreate: give the address of a KFReassembly");
  *reassembly = NULL;
  PetscCall(CheckInputs(nbodies, bodies, njoints, joints, a, t));
  PetscCheck(rtol >= 0 && rtol < 1, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFReassemblyCreate: relative rank tolerance %g is outside [0, 1): use a small positive value such as 1e-9", (double)rtol);
  PetscCheck(alpha >= 0 && beta >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFReassemblyCreate: Rayleigh coefficients alpha %g, beta %g must not be negative", (double)alpha, (double)beta);
  PetscCall(PetscNew(&r));
  r->nb = nbodies;
  r->nj = njoints;
  r->a = a;
  r->t = t;
  r->rtol = rtol;
  r->alpha = alpha;
  r->beta = beta;
  PetscCall(PetscMalloc3(nbodies, &r->bodies, PetscMax(njoints, 1), &r->joints, nbodies + 1, &r->off));
  if (njoints) PetscCall(PetscArraycpy(r->joints, joints, njoints));
  for (PetscInt b = 0; b < nbodies; b++) {
    const KFReducedBody *B = &bodies[b];
    const PetscInt       v = B->v;
    r->off[b] = n;
    n += v;
    r->vmax = PetscMax(r->vmax, v);
    total += 2 * v * v + v * a + t * v + 6 * B->ninterfaces * v + (B->rigid ? 6 * v : 0) + (B->C ? v * v : 0);
  }
  r->off[nbodies] = n;
  r->n            = n;
  for (PetscInt j = 0; j < njoints; j++) {
    m += joints[j].type == KF_JOINT_REVOLUTE ? 5 : 6;
    r->nrev += joints[j].type == KF_JOINT_REVOLUTE;
  }
  PetscCheck(ms >= 0 && (Ds || !ms), PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "KFReassemblyCreate: %" PetscInt_FMT " coordinate ties without their matrix", ms);
  r->mj = m;
  r->ms = ms;
  m += ms;
  r->m = m;
  if (ms) { /* the coordinate ties, angle-independent: copied once, appended to the joints' rows at each call */
    PetscCall(PetscMalloc1(ms * n, &r->Ds));
    PetscCall(PetscArraycpy(r->Ds, Ds, ms * n));
  }
  /* the bodies' arrays, copied: the workspace does not depend on the lifetime of the caller's */
  PetscCall(PetscMalloc1(total + 1, &r->data));
  p = r->data;
#define KF_COPY(field, size) \
  do { \
    if (B->field) { \
      PetscCall(PetscArraycpy(p, B->field, size)); \
      r->bodies[b].field = p; \
      p += size; \
    } else r->bodies[b].field = NULL; \
  } while (0)
  for (PetscInt b = 0; b < nbodies; b++) {
    const KFReducedBody *B = &bodies[b];
    const PetscInt       v = B->v;
    r->bodies[b]           = *B;
    KF_COPY(M, v * v);
    KF_COPY(K, v * v);
    KF_COPY(G, v * a);
    KF_COPY(H, t * v);
    KF_COPY(iface, 6 * B->ninterfaces * v);
    KF_COPY(rigid, 6 * v);
    KF_COPY(C, v * v);
    if (B->C) r->viscous = PETSC_TRUE;
  }
#undef KF_COPY
  PetscCall(KFReassemblyRigidMotions(r, &R, &r->nr));
  r->R = R;
  nrc  = PetscMax(r->nr, 0);
  ldm  = PetscMax(m, 1);
  /* the SVDs: D (m x n) and D R (m x nr) */
  PetscCall(KFDenseNullSpaceWorkSize_Private(m, n, &r->lsvd_D));
  PetscCall(KFDenseNullSpaceWorkSize_Private(m, nrc, &r->lsvd_E));
  r->lsvd = PetscMax(r->lsvd_D, r->lsvd_E);
  PetscCall(PetscMalloc4(m * n + 1, &r->D, n * n + 1, &r->N, ldm * PetscMax(n, nrc) + 1, &r->A, PetscMin(m, PetscMax(n, nrc)) + 1, &r->s));
  PetscCall(PetscMalloc3(PetscMax(n, nrc) * PetscMax(n, nrc) + 1, &r->VT, r->lsvd, &r->svdwork, r->vmax * n + 1, &r->W));
  PetscCall(PetscMalloc1(r->vmax * n + n * n + 1, &r->WL)); /* S B (v x hh) then B^T S B (hh x hh), hh <= n */
  PetscCall(PetscMalloc3(ldm * nrc + 1, &r->E, nrc * nrc + 1, &r->Z, n * nrc + 1, &r->Y));
  /* the eigensolver at the largest size, n dofs, with any rigid count r <= min(nr, n) (a smaller pencil needs less;
     KFReassemblyEig checks) */
  r->leig  = 1;
  r->eig_h = -1;
  if (witheig) {
    for (PetscInt q = 0; q <= PetscMin(nrc, n); q++) {
      PetscInt size;
      PetscCall(KFDenseEigRigidWorkSize_Private(n, q, &size, NULL, NULL));
      r->leig = PetscMax(r->leig, size);
    }
    PetscCall(PetscMalloc1(r->leig, &r->eigwork));
  }
  /* the closed form costs a few one-shot reassemblies to make: for workspaces that serve many angles only */
  /* the closed form eliminates the joints' ties only: with coordinate ties every call takes the SVD path */
  if (witheig && !ms) PetscCall(KFPrimalCreate_Private(r));
  *reassembly = r;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReassemblyCreate(PetscInt nbodies, const KFReducedBody bodies[], PetscInt njoints, const KFJointDef joints[], PetscInt a, PetscInt t, PetscReal rtol, PetscReal alpha, PetscReal beta, KFReassembly *reassembly)
{
  PetscFunctionBegin;
  PetscCall(KFReassemblyCreate_Private(nbodies, bodies, njoints, joints, 0, NULL, a, t, rtol, alpha, beta, PETSC_TRUE, reassembly));
  PetscFunctionReturn(0);
}

/*
  KFReassemblyCreateTied - KFReassemblyCreate with ms coordinate ties Ds (ms x n, column-major, n = sum of the bodies'
  v): angle-independent rows appended to the joints' ties at every angle (a reduced model's shared directions,
  KFReducedModelGetTies). ms 0: KFReassemblyCreate.
*/
PetscErrorCode KFReassemblyCreateTied(PetscInt nbodies, const KFReducedBody bodies[], PetscInt njoints, const KFJointDef joints[], PetscInt ms, const PetscReal Ds[], PetscInt a, PetscInt t, PetscReal rtol, PetscReal alpha, PetscReal beta, KFReassembly *reassembly)
{
  PetscFunctionBegin;
  PetscCall(KFReassemblyCreate_Private(nbodies, bodies, njoints, joints, ms, Ds, a, t, rtol, alpha, beta, PETSC_TRUE, reassembly));
  PetscFunctionReturn(0);
}

PetscErrorCode KFReassemblyDestroy(KFReassembly *reassembly)
{
  KFReassembly r;

  PetscFunctionBegin;
  if (!reassembly || !*reassembly) PetscFunctionReturn(0);
  r = *reassembly;
  PetscCall(PetscFree3(r->bodies, r->joints, r->off));
  PetscCall(PetscFree(r->data));
  PetscCall(PetscFree(r->R));
  PetscCall(PetscFree(r->Ds));
  PetscCall(PetscFree4(r->D, r->N, r->A, r->s));
  PetscCall(PetscFree3(r->VT, r->svdwork, r->W));
  PetscCall(PetscFree(r->WL));
  PetscCall(PetscFree3(r->E, r->Z, r->Y));
  PetscCall(PetscFree(r->eigwork));
  PetscCall(KFPrimalDestroy_Private(&r->primal));
  PetscCall(PetscFree(r));
  *reassembly = NULL;
  PetscFunctionReturn(0);
}

/* n: the largest reassembled size (sum of the bodies' v: size the n x n outputs for it); a, t: inputs, outputs;
   viscous: whether the damping output is more than Rayleigh (some body has a viscous matrix); rigid: the rigid
   motions of the bodies are known (Phir will be given) */
PetscErrorCode KFReassemblyGetSizes(KFReassembly r, PetscInt *n, PetscInt *a, PetscInt *t, PetscBool *viscous, PetscBool *rigid)
{
  PetscFunctionBegin;
  PetscCheck(r, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "KFReassembly: NULL workspace: make one with KFReassemblyCreate or KFReducedModelCreateReassembly");
  if (n) *n = r->n;
  if (a) *a = r->a;
  if (t) *t = r->t;
  if (viscous) *viscous = r->viscous;
  if (rigid) *rigid = r->nr >= 0 ? PETSC_TRUE : PETSC_FALSE;
  PetscFunctionReturn(0);
}

/* D (r->D, m x n): the interface ties (eq. 20) on the stacked reduced coordinates at these angles */
PetscErrorCode KFReassemblyConstraints_Private(KFReassembly r, const PetscReal angles[])
{
  const KFReducedBody *bodies = r->bodies;
  const PetscInt       n = r->n, m = r->m, *off = r->off;
  PetscInt             row = 0, irev = 0;
  PetscReal           *D = r->D;

  PetscFunctionBegin;
  PetscCall(PetscArrayzero(D, m * n));
  for (PetscInt j = 0; j < r->nj; j++) {
    const KFJointDef    *J = &r->joints[j];
    const KFReducedBody *P = &bodies[J->parent], *C = &bodies[J->child];
    const PetscReal      I3[3][3] = {
      {1, 0, 0},
      {0, 1, 0},
      {0, 0, 1}
    };
    PetscReal R[9];

    if (J->type == KF_JOINT_REVOLUTE) {
      PetscReal E[2][3], k[3], len;

      PetscCall(KFJointRotation(J->axis, J->R0, angles[irev++], R));
      len = PetscSqrtReal(J->axis[0] * J->axis[0] + J->axis[1] * J->axis[1] + J->axis[2] * J->axis[2]);
      for (int i = 0; i < 3; i++) k[i] = J->axis[i] / len;
      KFPerpendicularPair_Private(k, E[0], E[1]);
      AddTieRows(m, D, row, 3, I3, R, 0, P, off[J->parent], J->parent_interface, C, off[J->child], J->child_interface);
      AddTieRows(m, D, row + 3, 2, (const PetscReal(*)[3])E, R, 3, P, off[J->parent], J->parent_interface, C, off[J->child], J->child_interface);
      row += 5;
    } else {
      for (int i = 0; i < 9; i++) R[i] = J->R0[i];
      AddTieRows(m, D, row, 3, I3, R, 0, P, off[J->parent], J->parent_interface, C, off[J->child], J->child_interface);
      AddTieRows(m, D, row + 3, 3, I3, R, 3, P, off[J->parent], J->parent_interface, C, off[J->child], J->child_interface);
      row += 6;
    }
  }
  for (PetscInt j = 0; j < n; j++)
    for (PetscInt i = 0; i < r->ms; i++) D[row + i + j * m] = r->Ds[i + j * r->ms];
  PetscFunctionReturn(0);
}

/*
  KFReassemblyApply - KFReassembleDamped of the workspace's bodies and joints at these angles (one per revolute joint,
  radians) into the caller's arrays, with no allocation: h x h Mh, Kh (and Ch: the bodies' viscous damping plus
  Rayleigh, if Ch is not NULL), h x a Gh, t x h Hh, the constraints' rank and sigma ratio (either may be NULL), the
  rigid-body and mechanism modes Phir (h x nrigid; nrigid -1 when unknown; Phir may be NULL). Arrays sized for n
  (KFReassemblyGetSizes): n n, n a, t n.
*/
PetscErrorCode KFReassemblyApply(KFReassembly r, const PetscReal angles[], PetscInt *h, PetscReal Mh[], PetscReal Kh[], PetscReal Ch[], PetscReal Gh[], PetscReal Hh[], PetscInt *rank, PetscReal *sratio, PetscInt *nrigid, PetscReal Phir[])
{
  const KFReducedBody *bodies = r ? r->bodies : NULL;
  PetscInt             n, m, a, t, *off, hh, rk = -1;
  PetscReal           *D, *N, ratio = 0;
  PetscBool            primal;

  PetscFunctionBegin;
  PetscCheck(r, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "KFReassembly: NULL workspace: make one with KFReassemblyCreate or KFReducedModelCreateReassembly");
  PetscCheck(angles || !r->nrev, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "KFReassemble: the scene has %" PetscInt_FMT " revolute joints but no angles were given: pass one angle (radians) per revolute joint, in joint order", r->nrev);
  PetscCheck(h && Mh && Kh && (Gh || !r->a) && (Hh || !r->t), PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "KFReassemblyApply: give the output arrays h, M, K, G, H (sized n n, n n, n a, t n)");
  n = r->n, m = r->m, a = r->a, t = r->t, off = r->off, D = r->D, N = r->N;
  primal = r->primal && !r->use_svd ? PETSC_TRUE : PETSC_FALSE;

  /* D and, for the SVD path or when the rank is asked for, its SVD (eq. 21-22): phi = N phi_h. The closed-form path
     needs neither; where it exists the SVD's rank is m unless the ties degenerate at these angles, and then this
     call takes the SVD path. */
  if (!primal || rank || sratio || (nrigid && Phir && r->nr > 0)) PetscCall(KFReassemblyConstraints_Private(r, angles));
  if (!primal || rank || sratio) {
    PetscCall(KFDenseNullSpace_Private(m, n, D, r->rtol, &hh, N, &rk, &ratio, r->A, r->s, r->VT, r->svdwork, r->lsvd_D));
    if (rk != m) primal = PETSC_FALSE;
  }
  if (primal) hh = r->hprimal;
  *h = hh;
  if (rank) *rank = rk;
  if (sratio) *sratio = ratio;

  /* the system's rigid and mechanism modes: combinations of the bodies' rigid motions R that satisfy the ties,
     Z = null(D R), in reassembled coordinates (N^T R Z on the SVD path's orthonormal N). They come from geometry,
     not from an eigensolve. */
  if (nrigid) *nrigid = -1;
  if (nrigid && Phir && r->nr >= 0) {
    const PetscInt nr = r->nr;
    PetscInt       q, qrank;
    PetscReal      qratio;

    if (!nr) *nrigid = 0; /* clamped: no rigid motion at all */
    else {
      PetscCall(KFDenseGemm_Private('N', 'N', m, nr, n, 1.0, D, m, r->R, n, 0.0, r->E, PetscMax(m, 1)));
      PetscCall(KFDenseNullSpace_Private(m, nr, r->E, r->rtol, &q, r->Z, &qrank, &qratio, r->A, r->s, r->VT, r->svdwork, r->lsvd_E));
      PetscCall(KFDenseGemm_Private('N', 'N', n, q, nr, 1.0, r->R, n, r->Z, nr, 0.0, r->Y, n));
      if (primal) PetscCall(KFPrimalToCoordinates_Private(r, q, r->Y, Phir));
      else PetscCall(KFDenseGemm_Private('T', 'N', hh, q, n, 1.0, N, n, r->Y, n, 0.0, Phir, hh));
      *nrigid = q;
    }
  }
  if (primal) {
    PetscCall(KFPrimalApply_Private(r, angles, Mh, Kh, Ch, Gh, Hh));
    if (Ch && (r->alpha > 0 || r->beta > 0))
      for (PetscInt e = 0; e < hh * hh; e++) Ch[e] += r->alpha * Mh[e] + r->beta * Kh[e];
    PetscFunctionReturn(0);
  }

  /* eq. (23-24), body by body: blkdiag(M_b) is never formed */
  PetscCall(PetscArrayzero(Mh, hh * hh));
  PetscCall(PetscArrayzero(Kh, hh * hh));
  PetscCall(PetscArrayzero(Gh, hh * a));
  PetscCall(PetscArrayzero(Hh, t * hh));
  if (Ch) PetscCall(PetscArrayzero(Ch, hh * hh));
  for (PetscInt b = 0; b < r->nb; b++) {
    const KFReducedBody *B  = &bodies[b];
    const PetscInt       v  = B->v;
    const PetscReal     *Nb = N + off[b]; /* v x hh block of N, leading dimension n */

    if (!v) continue;
    PetscCall(KFDenseGemm_Private('N', 'N', v, hh, v, 1.0, B->M, v, Nb, n, 0.0, r->W, v));
    PetscCall(KFDenseGemm_Private('T', 'N', hh, hh, v, 1.0, Nb, n, r->W, v, 1.0, Mh, hh));
    /* K in long double: a reduced body keeps its stiff modes, and the soft system modes' stiffness is a small
       difference of their large terms (the same reason the body stiffness is formed that way) */
    KFDenseCongruenceL_Private(v, hh, B->K, Nb, n, Nb, n, r->WL, r->WL + r->vmax * n);
    for (PetscInt e = 0; e < hh * hh; e++) Kh[e] += (PetscReal)r->WL[r->vmax * n + e];
    if (Ch && B->C) {
      PetscCall(KFDenseGemm_Private('N', 'N', v, hh, v, 1.0, B->C, v, Nb, n, 0.0, r->W, v));
      PetscCall(KFDenseGemm_Private('T', 'N', hh, hh, v, 1.0, Nb, n, r->W, v, 1.0, Ch, hh));
    }
    PetscCall(KFDenseGemm_Private('T', 'N', hh, a, v, 1.0, Nb, n, B->G, v, 1.0, Gh, hh));
    PetscCall(KFDenseGemm_Private('N', 'N', t, hh, v, 1.0, B->H, t, Nb, n, 1.0, Hh, t));
  }
  PetscCall(KFDenseSymmetrize_Private(hh, Mh));
  PetscCall(KFDenseSymmetrize_Private(hh, Kh));
  if (Ch) {
    PetscCall(KFDenseSymmetrize_Private(hh, Ch));
    /* Rayleigh: alpha M + beta K, exact under projection */
    if (r->alpha > 0 || r->beta > 0)
      for (PetscInt e = 0; e < hh * hh; e++) Ch[e] += r->alpha * Mh[e] + r->beta * Kh[e];
  }
  PetscFunctionReturn(0);
}

/*
  KFReassemblyEig - eigenvalues (ascending) and M-orthonormal modes of a reassembled pencil (h x h Kh, Mh) with no
  allocation: the nrigid modes Phir (h x nrigid) as given with eigenvalue 0 and the flexible ones on their
  M-complement (KFDenseEigRigid); Phir NULL or nrigid < 0: the whole pencil (KFDenseEig). lambda: h, Phi: h h.
*/
PetscErrorCode KFReassemblyEig(KFReassembly r, PetscInt h, const PetscReal Mh[], const PetscReal Kh[], PetscInt nrigid, const PetscReal Phir[], PetscReal lambda[], PetscReal Phi[])
{
  PetscFunctionBegin;
  PetscCheck(r, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "KFReassembly: NULL workspace: make one with KFReassemblyCreate or KFReducedModelCreateReassembly");
  PetscCheck(h >= 1 && h <= r->n, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFReassemblyEig: size %" PetscInt_FMT " is outside 1..%" PetscInt_FMT ", the sizes this reassembly makes", h, r->n);
  if (Phir && nrigid >= 0) {
    PetscCheck(nrigid <= h && nrigid <= PetscMax(r->nr, 0), PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFReassemblyEig: %" PetscInt_FMT " rigid modes at %" PetscInt_FMT " dofs: give the count KFReassemblyApply returned", nrigid, h);
  } else nrigid = -1;
  if (h != r->eig_h || nrigid != r->eig_r) { /* LAPACK's workspace queries, once per size */
    PetscInt size = 0;
    if (nrigid >= 0) PetscCall(KFDenseEigRigidWorkSize_Private(h, nrigid, &size, &r->eig_lsvd, &r->eig_leig));
    else {
      PetscCall(KFDenseEigWorkSize_Private(h, &r->eig_leig));
      size = h * h + r->eig_leig;
    }
    PetscCheck(r->eigwork && size <= r->leig, PETSC_COMM_SELF, PETSC_ERR_PLIB, "KFReassemblyEig: workspace of %" PetscInt_FMT " reals, %" PetscInt_FMT " needed", r->eigwork ? r->leig : 0, size);
    r->eig_h = h;
    r->eig_r = nrigid;
  }
  if (nrigid >= 0) PetscCall(KFDenseEigRigid_Private(h, Kh, Mh, nrigid, Phir, lambda, Phi, r->eigwork, r->eig_lsvd, r->eig_leig));
  else PetscCall(KFDenseEig_Private(h, Kh, Mh, lambda, Phi, r->eigwork, r->eigwork + h * h, r->eig_leig));
  PetscFunctionReturn(0);
}

PetscErrorCode KFReassemble(PetscInt nbodies, const KFReducedBody bodies[], PetscInt njoints, const KFJointDef joints[], const PetscReal angles[], PetscInt a, PetscInt t, PetscReal rtol, PetscInt *h, PetscReal Mh[], PetscReal Kh[], PetscReal Gh[], PetscReal Hh[], PetscInt *rank, PetscReal *sratio, PetscInt *nrigid, PetscReal Phir[])
{
  PetscFunctionBegin;
  PetscCall(KFReassembleDamped(nbodies, bodies, njoints, joints, angles, a, t, rtol, h, Mh, Kh, NULL, Gh, Hh, rank, sratio, nrigid, Phir));
  PetscFunctionReturn(0);
}

/* KFReassemble, and with Ch the bodies' viscous damping N^T blkdiag(C_b) N (bodies without C_b add nothing): one
   reassembly through a KFReassembly made for it */
PetscErrorCode KFReassembleDamped(PetscInt nbodies, const KFReducedBody bodies[], PetscInt njoints, const KFJointDef joints[], const PetscReal angles[], PetscInt a, PetscInt t, PetscReal rtol, PetscInt *h, PetscReal Mh[], PetscReal Kh[], PetscReal Ch[], PetscReal Gh[], PetscReal Hh[], PetscInt *rank, PetscReal *sratio, PetscInt *nrigid, PetscReal Phir[])
{
  PetscFunctionBegin;
  PetscCall(KFReassembleTied(nbodies, bodies, njoints, joints, 0, NULL, angles, a, t, rtol, h, Mh, Kh, Ch, Gh, Hh, rank, sratio, nrigid, Phir));
  PetscFunctionReturn(0);
}

/* KFReassembleDamped with ms coordinate ties Ds (ms x n) appended to the joints' ties (KFReassemblyCreateTied) */
PetscErrorCode KFReassembleTied(PetscInt nbodies, const KFReducedBody bodies[], PetscInt njoints, const KFJointDef joints[], PetscInt ms, const PetscReal Ds[], const PetscReal angles[], PetscInt a, PetscInt t, PetscReal rtol, PetscInt *h, PetscReal Mh[], PetscReal Kh[], PetscReal Ch[], PetscReal Gh[], PetscReal Hh[], PetscInt *rank, PetscReal *sratio, PetscInt *nrigid, PetscReal Phir[])
{
  KFReassembly   r;
  KFReducedBody *used;

  PetscFunctionBegin;
  PetscCheck(nbodies >= 1, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFReassemble: no bodies to reassemble");
  /* only what this call reads: C with Ch, the rigid motions with Phir (callers may leave the others unset) */
  PetscCall(PetscMalloc1(nbodies, &used));
  for (PetscInt b = 0; b < nbodies; b++) {
    used[b] = bodies[b];
    if (!Ch) used[b].C = NULL;
    if (!nrigid || !Phir) used[b].rigid = NULL;
  }
  PetscCall(KFReassemblyCreate_Private(nbodies, used, njoints, joints, ms, Ds, a, t, rtol, 0, 0, PETSC_FALSE, &r)); /* one reassembly, no modes */
  PetscCall(PetscFree(used));
  PetscCall(KFReassemblyApply(r, angles, h, Mh, Kh, Ch, Gh, Hh, rank, sratio, nrigid, Phir));
  PetscCall(KFReassemblyDestroy(&r));
  PetscFunctionReturn(0);
}

/*
  KFReassemblySetUseSVD - svd PETSC_TRUE: the null space of the ties by SVD at every call (the reference path, an
  orthonormal basis); PETSC_FALSE (the default): the closed-form path where the joints form a tree whose bodies see
  their interface motions (the same null space in another basis, no SVD per call), the SVD elsewhere.
  KFReassemblyGetUseSVD: whether calls take the SVD path (PETSC_TRUE also when the closed form is not available).
*/
PetscErrorCode KFReassemblySetUseSVD(KFReassembly r, PetscBool svd)
{
  PetscFunctionBegin;
  PetscCheck(r, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "KFReassembly: NULL workspace: make one with KFReassemblyCreate or KFReducedModelCreateReassembly");
  r->use_svd = svd;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReassemblyGetUseSVD(KFReassembly r, PetscBool *svd)
{
  PetscFunctionBegin;
  PetscCheck(r, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "KFReassembly: NULL workspace: make one with KFReassemblyCreate or KFReducedModelCreateReassembly");
  *svd = (r->use_svd || !r->primal) ? PETSC_TRUE : PETSC_FALSE;
  PetscFunctionReturn(0);
}
