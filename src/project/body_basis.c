#include <kryflex_impl.h>

/* Reduced bodies (eq. 18-19): system vectors (rigid, kept and static-correction modes, possibly from several
   configurations) are mapped onto each body, Psi_b = P_b X, and compressed to an M_b-orthonormal basis by
   Gram-Schmidt with column pivoting: the column with the largest remaining M_b-norm goes next, and the process
   stops when every remaining column is below the tolerance (rank deflation). Columns of X are first scaled to
   unit system M-norm, so a body's share of each column is at most 1 and the tolerance is absolute. */

struct _n_KFBodyBasis {
  KFScene     s;
  PetscInt    nb;        /* bodies: destroying needs no scene */
  PetscInt   *ncols;   /* per body: number of collected matrices */
  Mat       **cols;    /* per body: collected n_b x m dense blocks */
  PetscBool   finished;
  Mat        *Psi;
  PetscInt   *v, *ndefl;
  PetscReal **M, **K, **G, **H, **iface, **rigid;
  /* a basis that sub-bases are made from (KFBodyBasisKeepProducts): M Psi, and the coordinates Psi^T M X_adm of the
     admissible rigid motions Finish added (nadm columns, 0 when none) */
  PetscBool   keep;
  Mat        *MPsi;
  PetscInt   *nadm;
  PetscReal **adm;
  /* a sub-basis (KFBodyBasisCreateSub): Psi = Psi_parent Z, made when asked for (KFBodyBasisGetMap) */
  Mat        *ppsi;
  PetscInt   *vp;
  PetscReal **Z;
};

PetscErrorCode KFBodyBasisCreate(KFScene s, KFBodyBasis *bb)
{
  KFBodyBasis b;

  PetscFunctionBegin;
  PetscCall(KFSceneSetUp(s));
  PetscCall(PetscNew(&b));
  PetscCall(PetscObjectReference((PetscObject)s)); /* the scene lives as long as the basis */
  b->s  = s;
  b->nb = s->nb;
  PetscCall(PetscCalloc3(s->nb, &b->ncols, s->nb, &b->cols, s->nb, &b->Psi));
  PetscCall(PetscCalloc2(s->nb, &b->v, s->nb, &b->ndefl));
  PetscCall(PetscCalloc5(s->nb, &b->M, s->nb, &b->K, s->nb, &b->G, s->nb, &b->H, s->nb, &b->iface));
  PetscCall(PetscCalloc1(s->nb, &b->rigid));
  PetscCall(PetscCalloc3(s->nb, &b->MPsi, s->nb, &b->nadm, s->nb, &b->adm));
  PetscCall(PetscCalloc3(s->nb, &b->ppsi, s->nb, &b->vp, s->nb, &b->Z));
  *bb = b;
  PetscFunctionReturn(0);
}

PetscErrorCode KFBodyBasisDestroy(KFBodyBasis *bb)
{
  KFBodyBasis b = *bb;

  PetscFunctionBegin;
  if (!b) PetscFunctionReturn(0);
  for (PetscInt i = 0; i < b->nb; i++) {
    for (PetscInt k = 0; k < b->ncols[i]; k++) PetscCall(MatDestroy(&b->cols[i][k]));
    PetscCall(PetscFree(b->cols[i]));
    PetscCall(MatDestroy(&b->Psi[i]));
    PetscCall(PetscFree5(b->M[i], b->K[i], b->G[i], b->H[i], b->iface[i]));
    PetscCall(PetscFree(b->rigid[i]));
    PetscCall(MatDestroy(&b->MPsi[i]));
    PetscCall(PetscFree(b->adm[i]));
    PetscCall(MatDestroy(&b->ppsi[i]));
    PetscCall(PetscFree(b->Z[i]));
  }
  PetscCall(PetscFree3(b->MPsi, b->nadm, b->adm));
  PetscCall(PetscFree3(b->ppsi, b->vp, b->Z));
  PetscCall(PetscFree(b->rigid));
  PetscCall(PetscFree3(b->ncols, b->cols, b->Psi));
  PetscCall(PetscFree2(b->v, b->ndefl));
  PetscCall(PetscFree5(b->M, b->K, b->G, b->H, b->iface));
  PetscCall(KFSceneDestroy(&b->s)); /* drops the basis's reference */
  PetscCall(PetscFree(b));
  *bb = NULL;
  PetscFunctionReturn(0);
}

PetscErrorCode KFBodyBasisAdd(KFBodyBasis bb, KFSystem sys, Mat X)
{
  KFScene    s = bb->s;
  Mat        Xn, MX;
  PetscInt   m, N;
  PetscReal *gram, *scale;

  PetscFunctionBegin;
  PetscCheck(!bb->finished, s->comm, PETSC_ERR_ORDER, "KFBodyBasisAdd() after KFBodyBasisFinish()");
  PetscCheck(sys->scene == s, s->comm, PETSC_ERR_ARG_INCOMP, "the system belongs to another scene");
  PetscCall(MatGetSize(X, &N, &m));
  PetscCheck(N == s->nsys, s->comm, PETSC_ERR_ARG_SIZ, "vectors of %" PetscInt_FMT " rows for a %" PetscInt_FMT "-dof system", N, s->nsys);
  PetscCall(PetscLogEventBegin(KF_EVENT_PROJECT, 0, 0, 0, 0));
  /* unit system M-norm per column */
  PetscCall(MatDuplicate(X, MAT_COPY_VALUES, &Xn));
  PetscCall(KFMatMultDense(sys->Ms, Xn, &MX));
  PetscCall(PetscMalloc2(m * m, &gram, m * m, &scale));
  PetscCall(KFMatTransposeMatMultGather(Xn, MX, gram));
  PetscCall(MatDestroy(&MX));
  PetscCall(PetscArrayzero(scale, m * m));
  for (PetscInt j = 0; j < m; j++) scale[j + j * m] = gram[j + j * m] > 0 ? 1.0 / PetscSqrtReal(gram[j + j * m]) : 0.0;
  PetscCall(MatZeroEntries(Xn));
  PetscCall(KFDenseMultSmall(X, m, m, scale, 1.0, Xn));
  PetscCall(PetscFree2(gram, scale));
  PetscCall(KFBodyBasisAddMapped(bb, sys->P, Xn));
  PetscCall(MatDestroy(&Xn));
  PetscCall(PetscLogEventEnd(KF_EVENT_PROJECT, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

/* Columns X of unit system M-norm mapped onto each body with the body maps P (n_b x e) of their configuration: what
   KFBodyBasisAdd does after scaling, for callers that keep the maps but not the system (the accuracy search). */
PetscErrorCode KFBodyBasisAddMapped(KFBodyBasis bb, const Mat P[], Mat X)
{
  PetscFunctionBegin;
  for (PetscInt b = 0; b < bb->s->nb; b++) PetscCall(KFBodyBasisAddMappedTo(bb, b, P[b], X));
  PetscFunctionReturn(0);
}

/* The same for one body: the accuracy search gives each body its own share of the Krylov modes */
PetscErrorCode KFBodyBasisAddMappedTo(KFBodyBasis bb, PetscInt b, Mat Pb, Mat X)
{
  KFScene s = bb->s;
  Mat     Y;

  PetscFunctionBegin;
  PetscCheck(!bb->finished, s->comm, PETSC_ERR_ORDER, "KFBodyBasisAdd() after KFBodyBasisFinish()");
  PetscCall(MatMatMult(Pb, X, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &Y));
  PetscCall(PetscRealloc(sizeof(Mat) * (bb->ncols[b] + 1), &bb->cols[b]));
  bb->cols[b][bb->ncols[b]++] = Y;
  PetscFunctionReturn(0);
}

/* d[cols[k]] = x^T A_cols[k] for n columns (1 to 4) of A (leading dimension nl): x is read once for the n columns and
   the sums are independent (a single running sum's latency bounded the loop); each sum still runs over i in order,
   so the values are those of one column at a time. */
static void KFGroupDots(PetscInt nl, PetscInt n, const PetscInt cols[], const PetscReal *x, const PetscReal *A, PetscReal d[])
{
  const PetscReal *a0 = &A[cols[0] * nl], *a1 = &A[cols[n > 1 ? 1 : 0] * nl], *a2 = &A[cols[n > 2 ? 2 : 0] * nl], *a3 = &A[cols[n > 3 ? 3 : 0] * nl];
  PetscReal        s0 = 0, s1 = 0, s2 = 0, s3 = 0;

  for (PetscInt i = 0; i < nl; i++) {
    s0 += x[i] * a0[i];
    s1 += x[i] * a1[i];
    s2 += x[i] * a2[i];
    s3 += x[i] * a3[i];
  }
  d[cols[0]] = s0;
  if (n > 1) d[cols[1]] = s1;
  if (n > 2) d[cols[2]] = s2;
  if (n > 3) d[cols[3]] = s3;
}

/* One Gram-Schmidt pass over n columns (1 to 4) of (W, MW) (nl rows, leading dimension nl): w -= c q, mw -= c mq for
   each, and its local sum t = mq^T w (first pass: the next pass's coefficient) or w^T mw (second pass: the remaining
   M-norm). Four columns per sweep: each column's sum still runs over i in order (the same numbers as one sweep per
   column), but the four sums are independent, so the loop is no longer bound by one running sum's latency (it was,
   at 28k rows per body). */
static void KFGroupPass(PetscInt nl, PetscInt n, const PetscInt cols[], const PetscReal c[], const PetscReal *q, const PetscReal *mq, PetscReal *W, PetscReal *MW, PetscBool second, PetscReal t[])
{
  if (n == 4) {
    PetscReal *w0 = &W[cols[0] * nl], *w1 = &W[cols[1] * nl], *w2 = &W[cols[2] * nl], *w3 = &W[cols[3] * nl];
    PetscReal *m0 = &MW[cols[0] * nl], *m1 = &MW[cols[1] * nl], *m2 = &MW[cols[2] * nl], *m3 = &MW[cols[3] * nl];
    const PetscReal c0 = c[0], c1 = c[1], c2 = c[2], c3 = c[3];
    PetscReal       s0 = 0, s1 = 0, s2 = 0, s3 = 0;

    /* the sum's left factor: mq (first pass) or the column's own mw (second pass) */
    const PetscReal *d0 = second ? m0 : mq, *d1 = second ? m1 : mq, *d2 = second ? m2 : mq, *d3 = second ? m3 : mq;

    for (PetscInt i = 0; i < nl; i++) {
      w0[i] -= c0 * q[i];
      m0[i] -= c0 * mq[i];
      s0 += d0[i] * w0[i];
      w1[i] -= c1 * q[i];
      m1[i] -= c1 * mq[i];
      s1 += d1[i] * w1[i];
      w2[i] -= c2 * q[i];
      m2[i] -= c2 * mq[i];
      s2 += d2[i] * w2[i];
      w3[i] -= c3 * q[i];
      m3[i] -= c3 * mq[i];
      s3 += d3[i] * w3[i];
    }
    t[0] = s0;
    t[1] = s1;
    t[2] = s2;
    t[3] = s3;
    return;
  }
  for (PetscInt k = 0; k < n; k++) {
    PetscReal      *w = &W[cols[k] * nl], *mw = &MW[cols[k] * nl], s = 0;
    const PetscReal ck = c[k];

    const PetscReal *d = second ? mw : mq;

    for (PetscInt i = 0; i < nl; i++) {
      w[i] -= ck * q[i];
      mw[i] -= ck * mq[i];
      s += d[i] * w[i];
    }
    t[k] = s;
  }
}

/* Both passes of one rank's Gram-Schmidt over n columns (1 to 4) of (W, MW), c the first pass's coefficients, t the
   second's sums (the remaining M-norms): the numbers of KFGroupPass's first pass followed by its second, with one
   sweep over W and MW fewer. The first sweep only reads: its sum mq^T (w - c q) takes w - c q as it comes, and the
   second sweep forms (w - c q) - s q and (mw - c mq) - s mq again in that order before writing them: the same
   operations on the same numbers (the file is built for baseline x86-64, no FMA to contract into), so the same bits
   as the two stored passes. The columns are memory-bound at 28k rows per body: this reads W twice and writes W and
   MW once per chosen column, against three reads and two writes of each. */
static void KFGroupPassFused(PetscInt nl, PetscInt n, const PetscInt cols[], const PetscReal c[], const PetscReal *q, const PetscReal *mq, PetscReal *W, PetscReal *MW, PetscReal t[])
{
  if (n == 4) {
    PetscReal *w0 = &W[cols[0] * nl], *w1 = &W[cols[1] * nl], *w2 = &W[cols[2] * nl], *w3 = &W[cols[3] * nl];
    PetscReal *m0 = &MW[cols[0] * nl], *m1 = &MW[cols[1] * nl], *m2 = &MW[cols[2] * nl], *m3 = &MW[cols[3] * nl];
    const PetscReal c0 = c[0], c1 = c[1], c2 = c[2], c3 = c[3];
    PetscReal       s0 = 0, s1 = 0, s2 = 0, s3 = 0, r0 = 0, r1 = 0, r2 = 0, r3 = 0;

    for (PetscInt i = 0; i < nl; i++) {
      s0 += mq[i] * (w0[i] - c0 * q[i]);
      s1 += mq[i] * (w1[i] - c1 * q[i]);
      s2 += mq[i] * (w2[i] - c2 * q[i]);
      s3 += mq[i] * (w3[i] - c3 * q[i]);
    }
    for (PetscInt i = 0; i < nl; i++) {
      const PetscReal a0 = (w0[i] - c0 * q[i]) - s0 * q[i], b0 = (m0[i] - c0 * mq[i]) - s0 * mq[i];
      const PetscReal a1 = (w1[i] - c1 * q[i]) - s1 * q[i], b1 = (m1[i] - c1 * mq[i]) - s1 * mq[i];
      const PetscReal a2 = (w2[i] - c2 * q[i]) - s2 * q[i], b2 = (m2[i] - c2 * mq[i]) - s2 * mq[i];
      const PetscReal a3 = (w3[i] - c3 * q[i]) - s3 * q[i], b3 = (m3[i] - c3 * mq[i]) - s3 * mq[i];

      w0[i] = a0;
      m0[i] = b0;
      r0 += b0 * a0;
      w1[i] = a1;
      m1[i] = b1;
      r1 += b1 * a1;
      w2[i] = a2;
      m2[i] = b2;
      r2 += b2 * a2;
      w3[i] = a3;
      m3[i] = b3;
      r3 += b3 * a3;
    }
    t[0] = r0;
    t[1] = r1;
    t[2] = r2;
    t[3] = r3;
    return;
  }
  /* a group of 1 to 3 (the last one): the two stored passes, the same numbers */
  KFGroupPass(nl, n, cols, c, q, mq, W, MW, PETSC_FALSE, t);
  KFGroupPass(nl, n, cols, t, q, mq, W, MW, PETSC_TRUE, t);
}

/* A Gram-Schmidt pass (KFGroupPass) over the columns j of (W, MW) with skip[j] false, with c_j = d[j], its sums back
   in d[j]. A column with c_j = 0 is not updated, only summed. (One rank makes both passes at once:
   KFColumnStep.) */
static void KFColumnUpdates(PetscInt nl, PetscInt m, const PetscReal *q, const PetscReal *mq, PetscReal *W, PetscReal *MW, const PetscBool *skip, PetscBool second, PetscReal d[])
{
  PetscInt  cols[4], n = 0;
  PetscReal c[4], t[4];

  for (PetscInt j = 0; j <= m; j++) {
    if (j < m) {
      if (skip[j]) continue;
      if (d[j] == 0) { /* nothing to remove: the sum only */
        const PetscReal *w = &W[j * nl], *mw = &MW[j * nl];
        PetscReal        s = 0;

        if (!second)
          for (PetscInt i = 0; i < nl; i++) s += mq[i] * w[i];
        else
          for (PetscInt i = 0; i < nl; i++) s += w[i] * mw[i];
        d[j] = s;
        continue;
      }
      c[n]      = d[j];
      cols[n++] = j;
    }
    if (n == 4 || (j == m && n > 0)) {
      KFGroupPass(nl, n, cols, c, q, mq, W, MW, second, t);
      for (PetscInt k = 0; k < n; k++) d[cols[k]] = t[k];
      n = 0;
    }
  }
}

/* A step of the pivoted Gram-Schmidt over the columns j with skip[j] false, four at a time: their coefficients
   d[j] = mq^T w_j (KFGroupDots; d[j] = 0 for the others) and, with both (one rank, where a local sum is the global
   one), both passes right after (KFGroupPassFused), while the group's columns are still in cache, d[j] then the
   remaining M-norm. Every column's operations are those of a coefficient sweep and two passes apart: the same
   numbers. */
static void KFColumnStep(PetscInt nl, PetscInt m, const PetscReal *q, const PetscReal *mq, PetscReal *W, PetscReal *MW, const PetscBool *skip, PetscBool both, PetscReal d[])
{
  PetscInt cols[4], n = 0;

  for (PetscInt j = 0; j <= m; j++) {
    if (j < m) {
      d[j] = 0;
      if (skip[j]) continue;
      cols[n++] = j;
    }
    if (n == 4 || (j == m && n > 0)) {
      PetscInt  gc[4], ng = 0;
      PetscReal c[4], t[4];

      KFGroupDots(nl, n, cols, mq, W, d); /* the group's coefficients */
      if (!both) {
        n = 0;
        continue;
      }
      /* both passes on the group; a column with nothing to remove (c = 0) is summed, then makes its second pass */
      for (PetscInt k = 0; k < n; k++) {
        const PetscInt jk = cols[k];

        if (d[jk] == 0) { /* nothing to remove: the sum only */
          const PetscReal *w = &W[jk * nl];
          PetscReal        s = 0;

          for (PetscInt i = 0; i < nl; i++) s += mq[i] * w[i];
          d[jk] = s;
          KFGroupPass(nl, 1, &jk, &d[jk], q, mq, W, MW, PETSC_TRUE, &d[jk]);
          continue;
        }
        c[ng]    = d[jk];
        gc[ng++] = jk;
      }
      if (ng > 0) {
        KFGroupPassFused(nl, ng, gc, c, q, mq, W, MW, t);
        for (PetscInt k = 0; k < ng; k++) d[gc[k]] = t[k];
      }
      n = 0;
    }
  }
}

/* Pivoted Gram-Schmidt in the M-inner product on local arrays (W, MW: nl x m, column-major). Returns the chosen
   columns' count and the orthonormal basis in Q (nl x v). The remaining M-norms of the next step are summed in the
   sweep of the second update (the same sums in the same order as a sweep of their own), and the dot products and
   the updates run four columns at a time (KFColumnStep, KFColumnUpdates): the same numbers as
   one loop per column.
   A column whose remaining M-norm is below the tolerance is dead: no later step can raise it above (each only
   removes a component), so it is neither updated nor summed again (the pivots and the basis are those of the
   sweeps over every column: its norm only falls further below the tolerance). */
#define KF_PIVOT_TIE 1e-8

static PetscErrorCode KFPivotedMGS(MPI_Comm comm, PetscInt nl, PetscInt m, PetscReal *W, PetscReal *MW, PetscReal tol, PetscInt *v, PetscReal *Q)
{
  PetscReal  *res, *dots, *MQ;
  PetscBool  *used;
  PetscMPIInt size;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCall(PetscMalloc4(m, &res, m, &dots, m, &used, nl * m + 1, &MQ));
  for (PetscInt j = 0; j < m; j++) {
    PetscReal d = 0;
    for (PetscInt i = 0; i < nl; i++) d += W[i + j * nl] * MW[i + j * nl];
    res[j]  = d;
    used[j] = PETSC_FALSE;
  }
  *v = 0;
  for (;;) {
    PetscInt  jmax = -1;
    PetscReal rmax = 0, nrm;

    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, res, (PetscMPIInt)m, MPIU_REAL, MPIU_SUM, comm));
    for (PetscInt j = 0; j < m; j++)
      if (!used[j] && res[j] > rmax) {
        rmax = res[j];
        jmax = j;
      }
    if (jmax < 0 || PetscSqrtReal(rmax) <= tol) break;
    /* ties go to the first column: residuals within KF_PIVOT_TIE of the largest are equal (a single body's columns all
       have unit norm at first), so that rounding (another rank count, or a sub-basis's coordinates) does not pick */
    for (PetscInt j = 0; j < jmax; j++)
      if (!used[j] && res[j] >= (1 - KF_PIVOT_TIE) * rmax) {
        rmax = res[j];
        jmax = j;
        break;
      }
    used[jmax] = PETSC_TRUE;
    for (PetscInt j = 0; j < m; j++) /* dead columns (the residuals are global sums: every rank agrees) */
      if (!used[j] && !(PetscSqrtReal(PetscMax(res[j], 0)) > tol)) used[j] = PETSC_TRUE;
    nrm = PetscSqrtReal(rmax);
    {
      PetscReal *q = &Q[*v * nl], *mq = &MQ[*v * nl];
      for (PetscInt i = 0; i < nl; i++) {
        q[i]  = W[i + jmax * nl] / nrm;
        mq[i] = MW[i + jmax * nl] / nrm;
      }
      /* remove q from every remaining column, twice (classical Gram-Schmidt with refinement); the first pass's
         update also sums the second pass's dot products (each column's sum in the same order as a sweep of its
         own: the same numbers, one sweep over W fewer per chosen column); on one rank both passes at once, a group
         of columns at a time (KFColumnStep) */
      if (size == 1) KFColumnStep(nl, m, q, mq, W, MW, used, PETSC_TRUE, dots);
      else
        for (int pass = 0; pass < 2; pass++) {
          if (pass == 0) KFColumnStep(nl, m, q, mq, W, MW, used, PETSC_FALSE, dots);
          PetscCall(MPIU_Allreduce(MPI_IN_PLACE, dots, (PetscMPIInt)m, MPIU_REAL, MPIU_SUM, comm));
          KFColumnUpdates(nl, m, q, mq, W, MW, used, (PetscBool)(pass == 1), dots);
        }
      for (PetscInt j = 0; j < m; j++) res[j] = used[j] ? 0 : dots[j];
    }
    (*v)++;
  }
  PetscCall(PetscFree4(res, dots, used, MQ));
  PetscFunctionReturn(0);
}

/* the body's 6 rigid motions (translations, rotations about its frame's axes) on its own dofs, n_b x 6 dense */
static PetscErrorCode KFBodyRigidMotions(MPI_Comm comm, KFBodyData *B, Mat *Phi)
{
  PetscInt     lda;
  PetscScalar *p;

  PetscFunctionBegin;
  PetscCall(KFDenseCreate(comm, B->rend - B->rstart, B->n, 6, Phi));
  PetscCall(MatDenseGetLDA(*Phi, &lda));
  PetscCall(MatDenseGetArray(*Phi, &p));
  for (PetscInt i = B->rstart; i < B->rend; i++) {
    PetscInt node, comp;
    PetscCall(KFBodyDofComponent(B, i, &node, &comp));
    for (int m = 0; m < 6; m++) p[(i - B->rstart) + m * lda] = KFBodyRigidValue(B, node, comp, m);
  }
  PetscCall(MatDenseRestoreArray(*Phi, &p));
  PetscFunctionReturn(0);
}

/* The body's rigid motions from its node coordinates, in reduced coordinates Psi^T M Phi_geom (v x 6): with them
   reassembly finds the system's rigid and mechanism modes exactly, at any angle. A body with boundary conditions
   keeps only the motions they allow (Phi_geom Z, KFBodyAdmissibleRigid), the other columns are zero: reassembly
   skips zero columns, so a clamped body contributes no motion and a grounded revolute joint one. MPsi = M Psi. */
static PetscErrorCode KFBodyRigidReduced(KFBodyData *B, Mat Psi, Mat MPsi, PetscReal **rigid)
{
  Mat          Phi;
  PetscInt     v, rb = 6;
  PetscReal    Z[36], *full;
  MPI_Comm     comm = PetscObjectComm((PetscObject)Psi);

  PetscFunctionBegin;
  PetscCall(MatGetSize(Psi, NULL, &v));
  PetscCall(KFBodyRigidMotions(comm, B, &Phi));
  PetscCall(PetscMalloc1(v * 6, &full));
  PetscCall(KFMatTransposeMatMultGather(MPsi, Phi, full)); /* (M Psi)^T Phi: the basis's product, no other */
  PetscCall(MatDestroy(&Phi));
  if (B->nclamp + B->nspring) PetscCall(KFBodyAdmissibleRigid(B, &rb, Z));
  else {
    PetscCall(PetscArrayzero(Z, 36));
    for (int k = 0; k < 6; k++) Z[k + 6 * k] = 1;
  }
  PetscCall(PetscCalloc1(v * 6, rigid));
  for (PetscInt j = 0; j < rb; j++)
    for (PetscInt k = 0; k < 6; k++)
      for (PetscInt i = 0; i < v; i++) (*rigid)[i + j * v] += full[i + k * v] * Z[k + 6 * j];
  { /* a combination the layout does not see (ux uy rz of a plate) keeps only rounding: zero it against the scale of
       the unrestricted motions, so that reassembly skips it */
    PetscReal scale = 0;
    for (PetscInt k = 0; k < 6; k++) {
      PetscReal c = 0;
      for (PetscInt i = 0; i < v; i++) c += PetscSqr(full[i + k * v]);
      scale = PetscMax(scale, c);
    }
    for (PetscInt j = 0; j < rb; j++) {
      PetscReal c = 0;
      for (PetscInt i = 0; i < v; i++) c += PetscSqr((*rigid)[i + j * v]);
      if (!(c > 1e-16 * scale))
        for (PetscInt i = 0; i < v; i++) (*rigid)[i + j * v] = 0;
    }
  }
  PetscCall(PetscFree(full));
  PetscFunctionReturn(0);
}

/* The rigid motions a body's boundary conditions allow (Phi_geom Z, n_b x rb), each of unit M-norm (columns without
   mass are dropped): in a scene whose conditions remove rigid modes, the system's remaining modes need not move a
   body in every way it may move, and reassembly at other angles needs them all. */
static PetscErrorCode KFBodyAdmissibleRigidColumns(KFBodyData *B, Mat *X)
{
  PetscReal    Z[36], G6[36], g[6], scale = 0;
  PetscInt     rb, lda, ldx, k = 0, keep[6];
  Mat          Phi, MPhi;
  PetscScalar *p, *x;
  MPI_Comm     comm = PetscObjectComm((PetscObject)B->M);

  PetscFunctionBegin;
  PetscCall(KFBodyAdmissibleRigid(B, &rb, Z));
  /* the 6 body motions and their M-Gram matrix: its largest diagonal is the scale a kept motion's mass is measured
     against (a combination the layout does not see has only rounding left) */
  PetscCall(KFBodyRigidMotions(comm, B, &Phi));
  PetscCall(KFMatMultDense(B->M, Phi, &MPhi));
  PetscCall(KFMatTransposeMatMultGather(Phi, MPhi, G6));
  PetscCall(MatDestroy(&MPhi));
  for (int m = 0; m < 6; m++) scale = PetscMax(scale, G6[m + 6 * m]);
  for (PetscInt j = 0; j < rb; j++) {
    g[j] = 0;
    for (int q = 0; q < 6; q++)
      for (int m = 0; m < 6; m++) g[j] += Z[m + 6 * j] * G6[m + 6 * q] * Z[q + 6 * j];
    if (g[j] > 1e-16 * scale) keep[k++] = j;
  }
  PetscCall(KFDenseCreate(comm, B->rend - B->rstart, B->n, k, X));
  PetscCall(MatDenseGetLDA(*X, &ldx));
  PetscCall(MatDenseGetLDA(Phi, &lda));
  PetscCall(MatDenseGetArray(Phi, &p));
  PetscCall(MatDenseGetArray(*X, &x));
  for (PetscInt c = 0; c < k; c++) {
    PetscInt j = keep[c];
    for (PetscInt i = 0; i < B->rend - B->rstart; i++) {
      PetscReal v = 0;
      for (int m = 0; m < 6; m++) v += PetscRealPart(p[i + m * lda]) * Z[m + 6 * j];
      x[i + c * ldx] = v / PetscSqrtReal(g[j]);
    }
  }
  PetscCall(MatDenseRestoreArray(*X, &x));
  PetscCall(MatDenseRestoreArray(Phi, &p));
  PetscCall(MatDestroy(&Phi));
  PetscFunctionReturn(0);
}

PetscErrorCode KFBodyBasisFinish(KFBodyBasis bb, PetscReal tol)
{
  KFScene s = bb->s;

  PetscFunctionBegin;
  PetscCheck(!bb->finished, s->comm, PETSC_ERR_ORDER, "KFBodyBasisFinish() called twice");
  PetscCheck(tol > 0 && tol < 1, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "body deflation tolerance must lie in (0, 1); got %g", (double)tol);
  PetscCall(PetscLogEventBegin(KF_EVENT_ORTHO, 0, 0, 0, 0));
  PetscCall(PetscLogEventBegin(KF_EVENT_BODY_BASIS, 0, 0, 0, 0));
  for (PetscInt b = 0; b < s->nb; b++) {
    KFBodyData *B  = &s->bodies[b];
    PetscInt    nl = B->rend - B->rstart, m = 0, v = 0, a = s->ninputs, t = s->noutputs;
    PetscReal  *W, *MW, *Q;
    Mat         Wm, MWm, AQ, MPsi;
    PetscCheck(bb->ncols[b] > 0, s->comm, PETSC_ERR_ORDER, "no vectors were added to the body basis");
    if (s->nrigid >= 0 && s->nrigid < 6 + s->nrevolute) { /* boundary conditions took rigid modes away */
      Mat X;
      PetscCall(KFBodyAdmissibleRigidColumns(B, &X));
      PetscCall(PetscRealloc(sizeof(Mat) * (bb->ncols[b] + 1), &bb->cols[b]));
      bb->cols[b][bb->ncols[b]++] = X;
    }
    for (PetscInt k = 0; k < bb->ncols[b]; k++) {
      PetscInt mk;
      PetscCall(MatGetSize(bb->cols[b][k], NULL, &mk));
      m += mk;
    }
    /* the collected blocks side by side in the Gram-Schmidt's own arrays, M W written into MW by the product: each
       26 MB array (57k dofs, 112 columns) filled once, not made as a matrix and copied */
    PetscCall(PetscMalloc2(nl * m + 1, &W, nl * m + 1, &MW));
    PetscCall(PetscMalloc1(nl * m + 1, &Q)); /* apart: its first v columns become Psi's array */
    {
      PetscInt off = 0;
      for (PetscInt k = 0; k < bb->ncols[b]; k++) {
        const PetscScalar *y;
        PetscInt           mk, ldy;
        PetscCall(MatGetSize(bb->cols[b][k], NULL, &mk));
        PetscCall(MatDenseGetLDA(bb->cols[b][k], &ldy));
        PetscCall(MatDenseGetArrayRead(bb->cols[b][k], &y));
        for (PetscInt j = 0; j < mk; j++)
          for (PetscInt i = 0; i < nl; i++) W[i + (off + j) * nl] = PetscRealPart(y[i + j * ldy]);
        PetscCall(MatDenseRestoreArrayRead(bb->cols[b][k], &y));
        PetscCall(MatDestroy(&bb->cols[b][k]));
        off += mk;
      }
    }
    PetscCall(MatCreateDense(s->comm, nl, PETSC_DECIDE, B->n, m, W, &Wm)); /* on the arrays: they stay ours */
    PetscCall(MatCreateDense(s->comm, nl, PETSC_DECIDE, B->n, m, MW, &MWm));
    PetscCall(MatAssemblyBegin(Wm, MAT_FINAL_ASSEMBLY));
    PetscCall(MatAssemblyEnd(Wm, MAT_FINAL_ASSEMBLY));
    PetscCall(KFMatMultDenseInto(B->M, Wm, MWm));
    PetscCall(MatDestroy(&Wm));
    PetscCall(MatDestroy(&MWm));
    PetscCall(KFPivotedMGS(s->comm, nl, m, W, MW, tol, &v, Q));
    PetscCheck(v > 0, s->comm, PETSC_ERR_ARG_WRONG, "body '%s' gets no basis vector: the modes do not move it", B->name);
    PetscCall(PetscInfo(NULL, "body '%s': %" PetscInt_FMT " of %" PetscInt_FMT " columns kept (%" PetscInt_FMT " rows here)\n", B->name, v, m, nl));
    bb->v[b]     = v;
    bb->ndefl[b] = m - v;
    PetscCall(PetscFree2(W, MW));
    /* the kept columns are Q's first v (leading dimension nl): Psi takes them over, neither zero-filled nor copied */
    PetscCall(PetscRealloc(sizeof(PetscReal) * (nl * v + 1), &Q));
    PetscCall(MatCreateDense(s->comm, nl, PETSC_DECIDE, B->n, v, Q, &bb->Psi[b]));
    PetscCall(MatDenseReplaceArray(bb->Psi[b], Q)); /* the array becomes the matrix' own, as KFDenseCreateUninitialized's */
    PetscCall(MatAssemblyBegin(bb->Psi[b], MAT_FINAL_ASSEMBLY));
    PetscCall(MatAssemblyEnd(bb->Psi[b], MAT_FINAL_ASSEMBLY));
    /* one more M-orthonormalization of the chosen basis squeezes out the rounding of the updates: one pass, the
       Gram-Schmidt's columns are M-orthonormal to a few digits already (|Psi^T M Psi - I| ~ 1e-15 after it on the
       200k-dof solid); its product M Psi serves the reduced mass and the rigid rows, no other product with M */
    PetscCall(KFMOrthonormalizeProduct(B->M, bb->Psi[b], 1, &MPsi, "reduced body basis"));
    /* reduced matrices (eq. 18-19) and interface rows */
    PetscCall(PetscLogEventBegin(KF_EVENT_BODY_REDUCE, 0, 0, 0, 0));
    PetscCall(PetscMalloc5(v * v, &bb->M[b], v * v, &bb->K[b], v * a, &bb->G[b], t * v, &bb->H[b], 6 * B->ninterfaces * v + 1, &bb->iface[b]));
    PetscCall(KFMatTransposeMatMultGather(bb->Psi[b], MPsi, bb->M[b]));
    PetscCall(KFMatMultExtended(B->K, bb->Psi[b], &AQ)); /* stiff bodies: K Psi without K's rounding */
    PetscCall(KFMatTransposeMatMultGather(bb->Psi[b], AQ, bb->K[b]));
    PetscCall(MatDestroy(&AQ));
    PetscCall(KFMatTransposeMatMultGather(bb->Psi[b], B->G, bb->G[b]));
    PetscCall(KFMatTransposeMatMultGather(B->Ht, bb->Psi[b], bb->H[b]));
    {
      PetscInt           ni = 6 * B->ninterfaces, ldp;
      const PetscScalar *p;
      PetscCall(PetscArrayzero(bb->iface[b], ni * v));
      PetscCall(MatDenseGetLDA(bb->Psi[b], &ldp));
      PetscCall(MatDenseGetArrayRead(bb->Psi[b], &p));
      for (PetscInt r = 0; r < ni; r++) {
        PetscInt dof = B->iface[r / 6].dof0 + r % 6;
        if (dof < B->rstart || dof >= B->rend) continue;
        for (PetscInt j = 0; j < v; j++) bb->iface[b][r + j * ni] = PetscRealPart(p[(dof - B->rstart) + j * ldp]);
      }
      PetscCall(MatDenseRestoreArrayRead(bb->Psi[b], &p));
      PetscCall(MPIU_Allreduce(MPI_IN_PLACE, bb->iface[b], (PetscMPIInt)(ni * v), MPIU_REAL, MPIU_SUM, s->comm));
    }
    PetscCall(KFBodyRigidReduced(B, bb->Psi[b], MPsi, &bb->rigid[b]));
    if (bb->keep) { /* what sub-bases need: M Psi for the coordinates of vectors, those of the admissible motions */
      if (s->nrigid >= 0 && s->nrigid < 6 + s->nrevolute) {
        Mat X;
        PetscCall(KFBodyAdmissibleRigidColumns(B, &X));
        PetscCall(MatGetSize(X, NULL, &bb->nadm[b]));
        PetscCall(PetscMalloc1(v * bb->nadm[b] + 1, &bb->adm[b]));
        PetscCall(KFMatTransposeMatMultGather(MPsi, X, bb->adm[b]));
        PetscCall(MatDestroy(&X));
      }
      bb->MPsi[b] = MPsi;
    } else PetscCall(MatDestroy(&MPsi));
    PetscCall(PetscLogEventEnd(KF_EVENT_BODY_REDUCE, 0, 0, 0, 0));
  }
  bb->finished = PETSC_TRUE;
  PetscCall(PetscLogEventEnd(KF_EVENT_BODY_BASIS, 0, 0, 0, 0));
  PetscCall(PetscLogEventEnd(KF_EVENT_ORTHO, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

PetscErrorCode KFBodyBasisGetReduced(KFBodyBasis bb, PetscInt b, PetscInt *v, const PetscReal **M, const PetscReal **K, const PetscReal **G, const PetscReal **H, PetscInt *ninterfaces, const PetscReal **iface, const PetscReal **rigid, PetscInt *ndeflated)
{
  PetscFunctionBegin;
  PetscCheck(bb->finished, bb->s->comm, PETSC_ERR_ORDER, "call KFBodyBasisFinish() first");
  PetscCheck(b >= 0 && b < bb->s->nb, bb->s->comm, PETSC_ERR_ARG_OUTOFRANGE, "body index %" PetscInt_FMT " does not exist", b);
  if (v) *v = bb->v[b];
  if (M) *M = bb->M[b];
  if (K) *K = bb->K[b];
  if (G) *G = bb->G[b];
  if (H) *H = bb->H[b];
  if (ninterfaces) *ninterfaces = bb->s->bodies[b].ninterfaces;
  if (iface) *iface = bb->iface[b];
  if (rigid) *rigid = bb->rigid[b];
  if (ndeflated) *ndeflated = bb->ndefl[b];
  PetscFunctionReturn(0);
}

PetscErrorCode KFBodyBasisGetMap(KFBodyBasis bb, PetscInt b, Mat *Psi)
{
  PetscFunctionBegin;
  PetscCheck(bb->finished, bb->s->comm, PETSC_ERR_ORDER, "call KFBodyBasisFinish() first");
  PetscCheck(b >= 0 && b < bb->s->nb, bb->s->comm, PETSC_ERR_ARG_OUTOFRANGE, "body index %" PetscInt_FMT " does not exist", b);
  if (!bb->Psi[b] && bb->ppsi[b]) { /* a sub-basis: its map when first asked for, Psi_parent Z */
    KFBodyData *B = &bb->s->bodies[b];
    PetscCall(KFDenseCreate(bb->s->comm, B->rend - B->rstart, B->n, bb->v[b], &bb->Psi[b]));
    PetscCall(MatZeroEntries(bb->Psi[b]));
    PetscCall(KFDenseMultSmall(bb->ppsi[b], bb->vp[b], bb->v[b], bb->Z[b], 1.0, bb->Psi[b]));
  }
  *Psi = bb->Psi[b];
  PetscFunctionReturn(0);
}

/* Keep, at KFBodyBasisFinish, what sub-bases are made from (M Psi per body): call before Finish */
PetscErrorCode KFBodyBasisKeepProducts(KFBodyBasis bb)
{
  PetscFunctionBegin;
  PetscCheck(!bb->finished, bb->s->comm, PETSC_ERR_ORDER, "KFBodyBasisKeepProducts() after KFBodyBasisFinish()");
  bb->keep = PETSC_TRUE;
  PetscFunctionReturn(0);
}

/* T = Psi_b^T M_b (P_b X) (v x m, replicated): the coordinates of body vectors P_b X in the M-orthonormal basis, of which
   Psi_b T is the M-orthogonal projection */
PetscErrorCode KFBodyBasisCoordinates(KFBodyBasis bb, PetscInt b, Mat Pb, Mat X, PetscReal T[])
{
  Mat Y;

  PetscFunctionBegin;
  PetscCheck(bb->finished && bb->keep, bb->s->comm, PETSC_ERR_ORDER, "call KFBodyBasisKeepProducts() and KFBodyBasisFinish() first");
  PetscCall(MatMatMult(Pb, X, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &Y));
  PetscCall(KFMatTransposeMatMultGather(bb->MPsi[b], Y, T));
  PetscCall(MatDestroy(&Y));
  PetscFunctionReturn(0);
}

/* C (r x p) = op(A) B, with op(A) = A (r x k) or A^T (A k x r); B k x p, column-major, small replicated arrays. Each
   entry is the sum over l in order from 0, as one dot product at a time: A B a column of A at a time into a column of C
   (adjacent rows, one vector operation), A^T B four entries at a time (KFGroupDots: independent sums, not one sum's
   latency). */
static void KFSmallMult(PetscBool trans, PetscInt r, PetscInt k, PetscInt p, const PetscReal *A, PetscInt lda, const PetscReal *B, PetscReal *C)
{
  for (PetscInt j = 0; j < p; j++) {
    const PetscReal *b = &B[j * k];
    PetscReal       *c = &C[j * r];

    if (!trans) {
      for (PetscInt i = 0; i < r; i++) c[i] = 0;
      for (PetscInt l = 0; l < k; l++) {
        const PetscReal *a = &A[l * lda], bl = b[l];

        for (PetscInt i = 0; i < r; i++) c[i] += a[i] * bl;
      }
      continue;
    }
    for (PetscInt i = 0; i < r; i += 4) { /* A^T is always a whole array here (lda = k), as KFGroupDots reads it */
      const PetscInt cols[4] = {i, i + 1, i + 2, i + 3};

      KFGroupDots(k, PetscMin(4, r - i), cols, b, A, c);
    }
  }
}

/* T = Z_b^T M_p Y (v x m): the coordinates in a sub-basis (KFBodyBasisCreateSub of parent) of body vectors given by
   their parent coordinates Y (parent v_b x m), as KFBodyBasisCoordinates gives them in a basis of its own */
PetscErrorCode KFBodyBasisSubCoordinates(KFBodyBasis sub, KFBodyBasis parent, PetscInt b, PetscInt m, const PetscReal Y[], PetscReal T[])
{
  PetscInt   vp, v;
  PetscReal *MY;

  PetscFunctionBegin;
  PetscCheck(sub->finished && sub->Z && sub->Z[b] && parent->finished && sub->ppsi[b] == parent->Psi[b], sub->s->comm, PETSC_ERR_ARG_WRONG, "KFBodyBasisSubCoordinates: not a sub-basis of this parent");
  vp = sub->vp[b];
  v  = sub->v[b];
  PetscCall(PetscMalloc1(vp * m + 1, &MY));
  KFSmallMult(PETSC_FALSE, vp, vp, m, parent->M[b], vp, Y, MY);
  KFSmallMult(PETSC_TRUE, v, vp, m, sub->Z[b], vp, MY, T);
  PetscCall(PetscFree(MY));
  PetscFunctionReturn(0);
}

/* A finished body basis spanned by a parent's (kept with KFBodyBasisKeepProducts): body b's vectors given by their
   coordinates Y[b] (parent v_b x m[b], column-major; KFBodyBasisCoordinates), scaled as KFBodyBasisAdd's are. In
   these coordinates the M-inner product is the parent's reduced mass M_p (the identity to rounding), so the pivoted
   Gram-Schmidt with deflation at tol, the one M-orthonormalization pass after it (Cholesky) and the reduced matrices
   (Z^T M_p Z, Z^T K_p Z, Z^T G_p, H_p Z, interface rows iface_p Z, rigid rows Z^T R_p) are small dense work: nothing
   of the bodies' size. The same basis as KFBodyBasisFinish of the vectors themselves, but for their parts outside the
   parent's span (below the parent's deflation tolerance) and rounding. The rigid rows are the parent's, rotated:
   those of the rigid motions' projection, exactly rigid as the parent's are. The map Psi = Psi_p Z is made only when
   KFBodyBasisGetMap asks for it; the sub-basis holds a reference to the parent's maps, not to the parent. */
PetscErrorCode KFBodyBasisCreateSub(KFBodyBasis parent, PetscReal tol, const PetscInt m[], PetscReal *const Y[], KFBodyBasis *sub)
{
  KFScene     s = parent->s;
  KFBodyBasis bb;
  PetscInt    a = s->ninputs, t = s->noutputs;

  PetscFunctionBegin;
  PetscCheck(parent->finished && parent->keep, s->comm, PETSC_ERR_ORDER, "the parent basis needs KFBodyBasisKeepProducts() and KFBodyBasisFinish()");
  PetscCheck(tol > 0 && tol < 1, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "body deflation tolerance must lie in (0, 1); got %g", (double)tol);
  PetscCall(PetscLogEventBegin(KF_EVENT_ORTHO, 0, 0, 0, 0));
  PetscCall(PetscLogEventBegin(KF_EVENT_BODY_BASIS, 0, 0, 0, 0));
  PetscCall(KFBodyBasisCreate(s, &bb));
  for (PetscInt b = 0; b < s->nb; b++) {
    KFBodyData      *B  = &s->bodies[b];
    const PetscInt   vp = parent->v[b], na = parent->nadm[b], mt = m[b] + na, ni = 6 * B->ninterfaces;
    const PetscReal *Mp = parent->M[b];
    PetscReal       *W, *MW, *Q, *Gm, *tmp;
    PetscInt         v;

    PetscCall(PetscMalloc5(vp * mt + 1, &W, vp * mt + 1, &MW, vp * mt + 1, &Q, vp * vp + 1, &Gm, vp * PetscMax(PetscMax(vp, a), PetscMax(t, ni)) + 6 * vp + 1, &tmp));
    PetscCall(PetscArraycpy(W, Y[b], vp * m[b]));
    if (na) PetscCall(PetscArraycpy(&W[vp * m[b]], parent->adm[b], vp * na)); /* as KFBodyBasisFinish appends them */
    KFSmallMult(PETSC_FALSE, vp, vp, mt, Mp, vp, W, MW);
    PetscCall(KFPivotedMGS(PETSC_COMM_SELF, vp, mt, W, MW, tol, &v, Q)); /* replicated: the same on every rank */
    PetscCheck(v > 0, s->comm, PETSC_ERR_ARG_WRONG, "body '%s' gets no basis vector: the modes do not move it", B->name);
    { /* one M_p-orthonormalization pass (Cholesky), as KFBodyBasisFinish's KFMOrthonormalizeProduct */
      KFSmallMult(PETSC_FALSE, vp, vp, v, Mp, vp, Q, tmp);
      KFSmallMult(PETSC_TRUE, v, vp, v, Q, vp, tmp, Gm);
      for (PetscInt j = 0; j < v; j++) {
        PetscReal d = Gm[j + j * v];
        for (PetscInt k = 0; k < j; k++) d -= Gm[j + k * v] * Gm[j + k * v];
        PetscCheck(d > 0, s->comm, PETSC_ERR_PLIB, "body '%s': the sub-basis is not M-orthonormalizable (column %" PetscInt_FMT ")", B->name, j);
        Gm[j + j * v] = PetscSqrtReal(d);
        for (PetscInt i = j + 1; i < v; i++) {
          PetscReal x = Gm[i + j * v];
          for (PetscInt k = 0; k < j; k++) x -= Gm[i + k * v] * Gm[j + k * v];
          Gm[i + j * v] = x / Gm[j + j * v];
        }
      }
      for (PetscInt i = 0; i < vp; i++) /* Q <- Q L^-T: row by row, forward substitution */
        for (PetscInt j = 0; j < v; j++) {
          PetscReal x = Q[i + j * vp];
          for (PetscInt k = 0; k < j; k++) x -= Q[i + k * vp] * Gm[j + k * v];
          Q[i + j * vp] = x / Gm[j + j * v];
        }
    }
    bb->v[b]     = v;
    bb->ndefl[b] = mt - v;
    bb->vp[b]    = vp;
    PetscCall(PetscMalloc1(vp * v, &bb->Z[b]));
    PetscCall(PetscArraycpy(bb->Z[b], Q, vp * v));
    PetscCall(PetscObjectReference((PetscObject)parent->Psi[b]));
    bb->ppsi[b] = parent->Psi[b];
    PetscCall(PetscLogEventBegin(KF_EVENT_BODY_REDUCE, 0, 0, 0, 0));
    PetscCall(PetscMalloc5(v * v, &bb->M[b], v * v, &bb->K[b], v * a, &bb->G[b], t * v, &bb->H[b], ni * v + 1, &bb->iface[b]));
    PetscCall(PetscMalloc1(v * 6, &bb->rigid[b]));
    KFSmallMult(PETSC_FALSE, vp, vp, v, Mp, vp, Q, tmp);
    KFSmallMult(PETSC_TRUE, v, vp, v, Q, vp, tmp, bb->M[b]);
    KFSmallMult(PETSC_FALSE, vp, vp, v, parent->K[b], vp, Q, tmp);
    KFSmallMult(PETSC_TRUE, v, vp, v, Q, vp, tmp, bb->K[b]);
    KFSmallMult(PETSC_TRUE, v, vp, a, Q, vp, parent->G[b], bb->G[b]);
    KFSmallMult(PETSC_FALSE, t, vp, v, parent->H[b], t, Q, bb->H[b]);
    KFSmallMult(PETSC_FALSE, ni, vp, v, parent->iface[b], ni, Q, bb->iface[b]);
    KFSmallMult(PETSC_TRUE, v, vp, 6, Q, vp, parent->rigid[b], bb->rigid[b]);
    PetscCall(PetscLogEventEnd(KF_EVENT_BODY_REDUCE, 0, 0, 0, 0));
    PetscCall(PetscFree5(W, MW, Q, Gm, tmp));
  }
  bb->finished = PETSC_TRUE;
  *sub         = bb;
  PetscCall(PetscLogEventEnd(KF_EVENT_BODY_BASIS, 0, 0, 0, 0));
  PetscCall(PetscLogEventEnd(KF_EVENT_ORTHO, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}
