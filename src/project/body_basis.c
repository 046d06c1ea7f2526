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
  }
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

/* d[j] = x^T A_j for the columns j of A (nl x m, leading dimension nl) with skip[j] false, d[j] = 0 otherwise. Four
   columns per sweep: x is read once per four columns and the four sums are independent (a single running sum's
   latency bounded the loop); each sum still runs over i in order, so the values are those of one column at a time. */
static void KFColumnDots(PetscInt nl, PetscInt m, const PetscReal *x, const PetscReal *A, const PetscBool *skip, PetscReal d[])
{
  PetscInt cols[4], n = 0;

  for (PetscInt j = 0; j <= m; j++) {
    if (j < m) {
      d[j] = 0;
      if (skip[j]) continue;
      cols[n++] = j;
    }
    if (n == 4 || (j == m && n > 0)) {
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
      n = 0;
    }
  }
}

/* Pivoted Gram-Schmidt in the M-inner product on local arrays (W, MW: nl x m, column-major). Returns the chosen
   columns' count and the orthonormal basis in Q (nl x v). The remaining M-norms of the next step are summed in the
   sweep of the second update (the same sums in the same order as a sweep of their own), and the dot products run
   four columns at a time (KFColumnDots): the same numbers as one loop per column, with a third of the sweeps. */
static PetscErrorCode KFPivotedMGS(MPI_Comm comm, PetscInt nl, PetscInt m, PetscReal *W, PetscReal *MW, PetscReal tol, PetscInt *v, PetscReal *Q)
{
  PetscReal *res, *dots, *MQ;
  PetscBool *used;

  PetscFunctionBegin;
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
    used[jmax] = PETSC_TRUE;
    nrm        = PetscSqrtReal(rmax);
    {
      PetscReal *q = &Q[*v * nl], *mq = &MQ[*v * nl];
      for (PetscInt i = 0; i < nl; i++) {
        q[i]  = W[i + jmax * nl] / nrm;
        mq[i] = MW[i + jmax * nl] / nrm;
      }
      /* remove q from every remaining column, twice (classical Gram-Schmidt with refinement); the first pass's
         update also sums the second pass's dot products (each column's sum in the same order as a sweep of its
         own: the same numbers, one sweep over W fewer per chosen column) */
      KFColumnDots(nl, m, mq, W, used, dots);
      for (int pass = 0; pass < 2; pass++) {
        PetscCall(MPIU_Allreduce(MPI_IN_PLACE, dots, (PetscMPIInt)m, MPIU_REAL, MPIU_SUM, comm));
        for (PetscInt j = 0; j < m; j++) {
          PetscReal *w = &W[j * nl], *mw = &MW[j * nl], d = 0;

          if (used[j]) continue;
          if (dots[j] != 0) {
            const PetscReal c = dots[j];

            if (pass == 0)
              for (PetscInt i = 0; i < nl; i++) {
                w[i] -= c * q[i];
                mw[i] -= c * mq[i];
                d += mq[i] * w[i];
              }
            else
              for (PetscInt i = 0; i < nl; i++) {
                w[i] -= c * q[i];
                mw[i] -= c * mq[i];
                d += w[i] * mw[i];
              }
          } else if (pass == 0)
            for (PetscInt i = 0; i < nl; i++) d += mq[i] * w[i];
          else
            for (PetscInt i = 0; i < nl; i++) d += w[i] * mw[i];
          if (pass == 0) dots[j] = d; /* the second pass's coefficient (local part) */
          else res[j] = d;
        }
      }
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
    /* concatenate the collected blocks */
    PetscCall(KFDenseCreate(s->comm, nl, B->n, m, &Wm));
    {
      PetscScalar *w;
      PetscInt     off = 0, ldw;
      PetscCall(MatDenseGetLDA(Wm, &ldw));
      PetscCall(MatDenseGetArray(Wm, &w));
      for (PetscInt k = 0; k < bb->ncols[b]; k++) {
        const PetscScalar *y;
        PetscInt           mk, ldy;
        PetscCall(MatGetSize(bb->cols[b][k], NULL, &mk));
        PetscCall(MatDenseGetLDA(bb->cols[b][k], &ldy));
        PetscCall(MatDenseGetArrayRead(bb->cols[b][k], &y));
        for (PetscInt j = 0; j < mk; j++)
          for (PetscInt i = 0; i < nl; i++) w[i + (off + j) * ldw] = y[i + j * ldy];
        PetscCall(MatDenseRestoreArrayRead(bb->cols[b][k], &y));
        PetscCall(MatDestroy(&bb->cols[b][k]));
        off += mk;
      }
      PetscCall(MatDenseRestoreArray(Wm, &w));
    }
    PetscCall(KFMatMultDense(B->M, Wm, &MWm));
    PetscCall(PetscMalloc3(nl * m + 1, &W, nl * m + 1, &MW, nl * m + 1, &Q));
    {
      const PetscScalar *w, *mw;
      PetscInt           ldw, ldmw;
      PetscCall(MatDenseGetLDA(Wm, &ldw));
      PetscCall(MatDenseGetLDA(MWm, &ldmw));
      PetscCall(MatDenseGetArrayRead(Wm, &w));
      PetscCall(MatDenseGetArrayRead(MWm, &mw));
      for (PetscInt j = 0; j < m; j++)
        for (PetscInt i = 0; i < nl; i++) {
          W[i + j * nl]  = PetscRealPart(w[i + j * ldw]);
          MW[i + j * nl] = PetscRealPart(mw[i + j * ldmw]);
        }
      PetscCall(MatDenseRestoreArrayRead(Wm, &w));
      PetscCall(MatDenseRestoreArrayRead(MWm, &mw));
    }
    PetscCall(MatDestroy(&Wm));
    PetscCall(MatDestroy(&MWm));
    PetscCall(KFPivotedMGS(s->comm, nl, m, W, MW, tol, &v, Q));
    PetscCheck(v > 0, s->comm, PETSC_ERR_ARG_WRONG, "body '%s' gets no basis vector: the modes do not move it", B->name);
    bb->v[b]     = v;
    bb->ndefl[b] = m - v;
    PetscCall(KFDenseCreate(s->comm, nl, B->n, v, &bb->Psi[b]));
    {
      PetscScalar *p;
      PetscInt     ldp;
      PetscCall(MatDenseGetLDA(bb->Psi[b], &ldp));
      PetscCall(MatDenseGetArray(bb->Psi[b], &p));
      for (PetscInt j = 0; j < v; j++)
        for (PetscInt i = 0; i < nl; i++) p[i + j * ldp] = Q[i + j * nl];
      PetscCall(MatDenseRestoreArray(bb->Psi[b], &p));
    }
    PetscCall(PetscFree3(W, MW, Q));
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
    PetscCall(MatDestroy(&MPsi));
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
  *Psi = bb->Psi[b];
  PetscFunctionReturn(0);
}
