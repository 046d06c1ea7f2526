/* Reassembly of reduced bodies at any joint angles (eq. 20-24): interface constraints D phi = 0 of the
   reduced coordinates, their null space N by SVD, and the reduced system projected on N. */
#include "dense_impl.h"

/* Two unit vectors spanning the plane perpendicular to the (unit) axis k: the rotation rows of a revolute
   joint. Any orthonormal pair gives the same constraint space; this one is well conditioned. */
static void PerpendicularPair(const PetscReal k[3], PetscReal e1[3], PetscReal e2[3])
{
  PetscReal c[3] = {0, 0, 0}, dot, len;
  int       imin = 0;

  for (int i = 1; i < 3; i++)
    if (PetscAbsReal(k[i]) < PetscAbsReal(k[imin])) imin = i;
  c[imin] = 1;
  dot     = k[imin];
  for (int i = 0; i < 3; i++) e1[i] = c[i] - dot * k[i];
  len = PetscSqrtReal(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
  for (int i = 0; i < 3; i++) e1[i] /= len;
  e2[0] = k[1] * e1[2] - k[2] * e1[1];
  e2[1] = k[2] * e1[0] - k[0] * e1[2];
  e2[2] = k[0] * e1[1] - k[1] * e1[0];
}

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

/* Kh += Nb^T K Nb accumulated in long double: a reduced body keeps its stiff modes, and the soft system modes'
   stiffness is a small difference of their large terms (the same reason the body stiffness is formed that way). */
static PetscErrorCode KFDenseCongruenceExtended(PetscInt v, PetscInt hh, const PetscReal K[], const PetscReal Nb[], PetscInt ldn, PetscReal Kh[])
{
  long double *W;

  PetscFunctionBegin;
  PetscCall(PetscMalloc1(v * hh + 1, &W));
  for (PetscInt j = 0; j < hh; j++)
    for (PetscInt i = 0; i < v; i++) {
      long double s = 0;
      for (PetscInt k = 0; k < v; k++) s += (long double)K[i + k * v] * Nb[k + j * ldn];
      W[i + j * v] = s;
    }
  for (PetscInt j = 0; j < hh; j++)
    for (PetscInt i = 0; i < hh; i++) {
      long double s = 0;
      for (PetscInt k = 0; k < v; k++) s += (long double)Nb[k + i * ldn] * W[k + j * v];
      Kh[i + j * hh] += (PetscReal)s;
    }
  PetscCall(PetscFree(W));
  PetscFunctionReturn(0);
}

/* The system's rigid and mechanism modes: combinations of the bodies' rigid motions R = blkdiag(R_b) that satisfy
   the ties, Z = null(D R), in reassembled coordinates N^T R Z. They come from geometry, not from an eigensolve. */
static PetscErrorCode KFReassembleRigid(PetscInt nbodies, const KFReducedBody bodies[], const PetscInt off[], PetscInt m, PetscInt n, const PetscReal D[], const PetscReal N[], PetscInt hh, PetscReal rtol, PetscInt *nrigid, PetscReal Phir[])
{
  PetscInt   nr = 6 * nbodies, r, rk;
  PetscReal *R, *E, *Z, *Y, ratio;

  PetscFunctionBegin;
  if (nrigid) *nrigid = -1;
  if (!nrigid || !Phir) PetscFunctionReturn(0);
  for (PetscInt b = 0; b < nbodies; b++)
    if (!bodies[b].rigid) PetscFunctionReturn(0);
  PetscCall(PetscCalloc4(n * nr, &R, PetscMax(m, 1) * nr, &E, nr * nr, &Z, n * nr, &Y));
  /* a body with boundary conditions (or a layout that does not see some motions) stores only the motions it has,
     the other columns zero, or of rounding size after a restriction: skip those below 1e-10 of the largest */
  {
    PetscReal cmax = 0;
    for (PetscInt b = 0; b < nbodies; b++)
      for (PetscInt k = 0; k < 6; k++) {
        PetscReal c = 0;
        for (PetscInt i = 0; i < bodies[b].v; i++) c += PetscSqr(bodies[b].rigid[i + k * bodies[b].v]);
        cmax = PetscMax(cmax, c);
      }
    ratio = cmax; /* reused below as the squared threshold's scale */
  }
  nr = 0;
  for (PetscInt b = 0; b < nbodies; b++)
    for (PetscInt k = 0; k < 6; k++) {
      PetscReal c = 0;
      for (PetscInt i = 0; i < bodies[b].v; i++) c += PetscSqr(bodies[b].rigid[i + k * bodies[b].v]);
      if (!(c > 1e-20 * ratio)) continue;
      for (PetscInt i = 0; i < bodies[b].v; i++) R[off[b] + i + nr * n] = bodies[b].rigid[i + k * bodies[b].v];
      nr++;
    }
  if (!nr) { /* clamped: no rigid motion at all */
    *nrigid = 0;
    PetscCall(PetscFree4(R, E, Z, Y));
    PetscFunctionReturn(0);
  }
  { /* dependent motions (a body whose conditions leave combinations that mix motions its layout does not see):
       R <- R V_k on the eigenvectors of R^T R above 1e-12 of the largest (singular values 1e-6: the bodies' bases hold
       their rigid motions to about 1e-8); independent columns are kept as they are */
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
  PetscCall(KFDenseGemm_Private('N', 'N', m, nr, n, 1.0, D, m, R, n, 0.0, E, PetscMax(m, 1)));
  PetscCall(KFDenseNullSpace(m, nr, E, rtol, &r, Z, &rk, &ratio));
  PetscCall(KFDenseGemm_Private('N', 'N', n, r, nr, 1.0, R, n, Z, nr, 0.0, Y, n));
  PetscCall(KFDenseGemm_Private('T', 'N', hh, r, n, 1.0, N, n, Y, n, 0.0, Phir, hh));
  *nrigid = r;
  PetscCall(PetscFree4(R, E, Z, Y));
  PetscFunctionReturn(0);
}

PetscErrorCode KFReassemble(PetscInt nbodies, const KFReducedBody bodies[], PetscInt njoints, const KFJointDef joints[], const PetscReal angles[], PetscInt a, PetscInt t, PetscReal rtol, PetscInt *h, PetscReal Mh[], PetscReal Kh[], PetscReal Gh[], PetscReal Hh[], PetscInt *rank, PetscReal *sratio, PetscInt *nrigid, PetscReal Phir[])
{
  PetscFunctionBegin;
  PetscCall(KFReassembleDamped(nbodies, bodies, njoints, joints, angles, a, t, rtol, h, Mh, Kh, NULL, Gh, Hh, rank, sratio, nrigid, Phir));
  PetscFunctionReturn(0);
}

/* KFReassemble, and with Ch the bodies' viscous damping N^T blkdiag(C_b) N (bodies without C_b add nothing) */
PetscErrorCode KFReassembleDamped(PetscInt nbodies, const KFReducedBody bodies[], PetscInt njoints, const KFJointDef joints[], const PetscReal angles[], PetscInt a, PetscInt t, PetscReal rtol, PetscInt *h, PetscReal Mh[], PetscReal Kh[], PetscReal Ch[], PetscReal Gh[], PetscReal Hh[], PetscInt *rank, PetscReal *sratio, PetscInt *nrigid, PetscReal Phir[])
{
  PetscInt  *off, n = 0, m = 0, row = 0, irev = 0, nrev = 0, hh, vmax = 0;
  PetscReal *D, *N, *W;

  PetscFunctionBegin;
  PetscCall(CheckInputs(nbodies, bodies, njoints, joints, a, t));
  PetscCall(PetscMalloc1(nbodies + 1, &off));
  for (PetscInt b = 0; b < nbodies; b++) {
    off[b] = n;
    n += bodies[b].v;
    vmax = PetscMax(vmax, bodies[b].v);
  }
  off[nbodies] = n;
  for (PetscInt j = 0; j < njoints; j++) {
    m += joints[j].type == KF_JOINT_REVOLUTE ? 5 : 6;
    nrev += joints[j].type == KF_JOINT_REVOLUTE;
  }
  PetscCheck(angles || !nrev, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "KFReassemble: the scene has %" PetscInt_FMT " revolute joints but no angles were given: pass one angle (radians) per revolute joint, in joint order", nrev);

  /* D: the interface ties (eq. 20) on the stacked reduced coordinates, body blocks in body order */
  PetscCall(PetscCalloc1(m * n, &D));
  for (PetscInt j = 0; j < njoints; j++) {
    const KFJointDef    *J = &joints[j];
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
      PerpendicularPair(k, E[0], E[1]);
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

  /* eq. (21-22): the reduced coordinates that satisfy the ties, phi = N phi_h */
  PetscCall(PetscMalloc1(n * n, &N));
  PetscCall(KFDenseNullSpace(m, n, D, rtol, &hh, N, rank, sratio));
  *h = hh;
  PetscCall(KFReassembleRigid(nbodies, bodies, off, m, n, D, N, hh, rtol, nrigid, Phir));
  PetscCall(PetscFree(D));

  /* eq. (23-24), body by body: blkdiag(M_b) is never formed */
  PetscCall(PetscArrayzero(Mh, hh * hh));
  PetscCall(PetscArrayzero(Kh, hh * hh));
  PetscCall(PetscArrayzero(Gh, hh * a));
  PetscCall(PetscArrayzero(Hh, t * hh));
  if (Ch) PetscCall(PetscArrayzero(Ch, hh * hh));
  PetscCall(PetscMalloc1(vmax * hh, &W));
  for (PetscInt b = 0; b < nbodies; b++) {
    const KFReducedBody *B  = &bodies[b];
    const PetscInt       v  = B->v;
    const PetscReal     *Nb = N + off[b]; /* v x hh block of N, leading dimension n */

    if (!v) continue;
    PetscCall(KFDenseGemm_Private('N', 'N', v, hh, v, 1.0, B->M, v, Nb, n, 0.0, W, v));
    PetscCall(KFDenseGemm_Private('T', 'N', hh, hh, v, 1.0, Nb, n, W, v, 1.0, Mh, hh));
    PetscCall(KFDenseCongruenceExtended(v, hh, B->K, Nb, n, Kh));
    if (Ch && B->C) {
      PetscCall(KFDenseGemm_Private('N', 'N', v, hh, v, 1.0, B->C, v, Nb, n, 0.0, W, v));
      PetscCall(KFDenseGemm_Private('T', 'N', hh, hh, v, 1.0, Nb, n, W, v, 1.0, Ch, hh));
    }
    PetscCall(KFDenseGemm_Private('T', 'N', hh, a, v, 1.0, Nb, n, B->G, v, 1.0, Gh, hh));
    PetscCall(KFDenseGemm_Private('N', 'N', t, hh, v, 1.0, B->H, t, Nb, n, 1.0, Hh, t));
  }
  PetscCall(KFDenseSymmetrize_Private(hh, Mh));
  PetscCall(KFDenseSymmetrize_Private(hh, Kh));
  if (Ch) PetscCall(KFDenseSymmetrize_Private(hh, Ch));
  PetscCall(PetscFree(W));
  PetscCall(PetscFree(N));
  PetscCall(PetscFree(off));
  PetscFunctionReturn(0);
}
