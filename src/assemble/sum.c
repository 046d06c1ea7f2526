#include <kryflex_impl.h>

/* S = sum_b P_b^T A_b P_b without sparse matrix products.

   P_b reads a kept body dof as one system dof, a clamped one as nothing, and the 6 dofs of a child's tied interface
   node as short expressions in its parent's interface dofs and the joint's free rotation (KFSystemInterfaceExprs).
   So a row of S is a body row with its columns renamed (tied columns expanded into their expressions), plus, at the
   few system dofs a tied interface reads through, the tied body rows weighted by the expression's coefficients.
   This file writes that sum directly: every rank renames the rows it owns and receives the (few) tied rows of every
   body from their owners, so no entry travels in the assembly, and the matrix's CSR arrays (over ranks, those of its
   diagonal and off-diagonal blocks) are written row by row in one pass and adopted by the matrix.

   MatPtAP followed by MatAXPY(DIFFERENT_NONZERO_PATTERN) did the same with a generic symbolic product per body and a
   merge that copies the whole matrix: 3.8 s of a 202,447-dof scene, against O(nnz) renaming here.
   The pattern does not depend on the angles (expressions keep zero coefficients, KFExprAdd): a later angle writes
   new values into the same matrix. */

/* one body matrix as this rank sees it: CSR of the diagonal block (local columns) and of the off-diagonal block
   (ghost columns, with their P_b rows fetched from their owners) */
typedef struct {
  Mat                Aconv;        /* a non-AIJ body matrix converted to AIJ, or NULL */
  Mat                Ad, Ao;       /* Ao NULL on one rank */
  const PetscInt    *ia, *ja, *ib, *jb;
  const PetscScalar *va, *vb;
  const PetscInt    *garray;       /* ghost column -> body dof */
  PetscInt          *gsys;         /* ghost column -> its system dof, -1 tied, -2 clamped */
  PetscInt           rstart, nl, e0, ci; /* local rows; first tied dof and child interface (-1: root body) */
} KFBodyRows;

/* a row being written: system columns and values */
typedef struct {
  PetscInt     n, cap;
  PetscInt    *col;
  PetscScalar *val;
} KFRowBuf;

static PetscErrorCode KFRowBufReserve(KFRowBuf *r, PetscInt extra)
{
  PetscFunctionBegin;
  if (r->n + extra <= r->cap) PetscFunctionReturn(0);
  r->cap = PetscMax(2 * r->cap, r->n + extra);
  PetscCall(PetscRealloc(sizeof(PetscInt) * r->cap, &r->col));
  PetscCall(PetscRealloc(sizeof(PetscScalar) * r->cap, &r->val));
  PetscFunctionReturn(0);
}

/* sorted by column, repeated columns summed */
static PetscErrorCode KFRowBufCompress(KFRowBuf *r)
{
  PetscInt m = 0;

  PetscFunctionBegin;
  PetscCall(PetscSortIntWithScalarArray(r->n, r->col, r->val));
  for (PetscInt k = 0; k < r->n; k++) {
    if (m > 0 && r->col[m - 1] == r->col[k]) r->val[m - 1] += r->val[k];
    else {
      r->col[m] = r->col[k];
      r->val[m] = r->val[k];
      m++;
    }
  }
  r->n = m;
  PetscFunctionReturn(0);
}

static PetscErrorCode KFBodyRowsGet(KFScene s, PetscInt b, Mat A, KFBodyRows *R)
{
  KFBodyData *B = &s->bodies[b];
  PetscBool   seq, mpi, done;
  PetscInt    cstart, cend, n, nghost = 0;

  PetscFunctionBegin;
  PetscCall(PetscMemzero(R, sizeof(*R)));
  PetscCall(PetscObjectTypeCompare((PetscObject)A, MATSEQAIJ, &seq));
  PetscCall(PetscObjectTypeCompare((PetscObject)A, MATMPIAIJ, &mpi));
  if (!seq && !mpi) { /* another type (dense, BAIJ, an AIJ subclass): its AIJ copy */
    PetscCall(MatConvert(A, MATAIJ, MAT_INITIAL_MATRIX, &R->Aconv));
    A = R->Aconv;
    PetscCall(PetscObjectTypeCompare((PetscObject)A, MATMPIAIJ, &mpi));
  }
  PetscCall(MatGetOwnershipRangeColumn(A, &cstart, &cend));
  { /* a collective verdict: a rank that stopped alone would leave the others waiting in the scatter below */
    PetscBool same = (PetscBool)(cstart == B->rstart && cend == B->rend), all;

    PetscCall(MPIU_Allreduce(&same, &all, 1, MPIU_BOOL, MPI_LAND, s->comm));
    PetscCheck(all, s->comm, PETSC_ERR_ARG_INCOMP, "body '%s': its matrices' local columns differ from their local rows on some rank; create them with equal row and column layouts (the default for square matrices)", B->name);
  }
  if (mpi) PetscCall(MatMPIAIJGetSeqAIJ(A, &R->Ad, &R->Ao, &R->garray));
  else R->Ad = A;
  R->rstart = B->rstart;
  R->nl     = B->rend - B->rstart;
  R->ci = B->child_iface;
  R->e0 = B->child_iface >= 0 ? B->iface[B->child_iface].dof0 : -1;
  PetscCall(MatGetRowIJ(R->Ad, 0, PETSC_FALSE, PETSC_FALSE, &n, &R->ia, &R->ja, &done));
  PetscCheck(done && n == R->nl, PETSC_COMM_SELF, PETSC_ERR_PLIB, "no row access to body '%s'", B->name);
  PetscCall(MatSeqAIJGetArrayRead(R->Ad, &R->va));
  if (R->Ao) {
    PetscCall(MatGetRowIJ(R->Ao, 0, PETSC_FALSE, PETSC_FALSE, &n, &R->ib, &R->jb, &done));
    PetscCheck(done && n == R->nl, PETSC_COMM_SELF, PETSC_ERR_PLIB, "no row access to body '%s'", B->name);
    PetscCall(MatSeqAIJGetArrayRead(R->Ao, &R->vb));
    PetscCall(MatGetSize(R->Ao, NULL, &nghost));
  }
  /* the ghost columns' system dofs live with their owners: one scatter (collective: every rank takes part) */
  if (mpi) {
    Vec                x, g;
    IS                 is;
    VecScatter         sc;
    PetscScalar       *xa;
    const PetscScalar *ga;

    PetscCall(MatCreateVecs(A, &x, NULL));
    PetscCall(VecGetArrayWrite(x, &xa));
    for (PetscInt i = 0; i < R->nl; i++) xa[i] = (PetscScalar)B->sysidx[i];
    PetscCall(VecRestoreArrayWrite(x, &xa));
    PetscCall(ISCreateGeneral(PETSC_COMM_SELF, nghost, R->garray, PETSC_USE_POINTER, &is));
    PetscCall(VecCreateSeq(PETSC_COMM_SELF, nghost, &g));
    PetscCall(VecScatterCreate(x, is, g, NULL, &sc));
    PetscCall(VecScatterBegin(sc, x, g, INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(VecScatterEnd(sc, x, g, INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(PetscMalloc1(PetscMax(nghost, 1), &R->gsys));
    PetscCall(VecGetArrayRead(g, &ga));
    for (PetscInt k = 0; k < nghost; k++) R->gsys[k] = (PetscInt)PetscRealPart(ga[k]);
    PetscCall(VecRestoreArrayRead(g, &ga));
    PetscCall(VecScatterDestroy(&sc));
    PetscCall(VecDestroy(&g));
    PetscCall(ISDestroy(&is));
    PetscCall(VecDestroy(&x));
  }
  PetscFunctionReturn(0);
}

static PetscErrorCode KFBodyRowsRestore(KFBodyRows *R)
{
  PetscInt  n;
  PetscBool done;

  PetscFunctionBegin;
  PetscCall(MatSeqAIJRestoreArrayRead(R->Ad, &R->va));
  PetscCall(MatRestoreRowIJ(R->Ad, 0, PETSC_FALSE, PETSC_FALSE, &n, &R->ia, &R->ja, &done));
  if (R->Ao) {
    PetscCall(MatSeqAIJRestoreArrayRead(R->Ao, &R->vb));
    PetscCall(MatRestoreRowIJ(R->Ao, 0, PETSC_FALSE, PETSC_FALSE, &n, &R->ib, &R->jb, &done));
  }
  PetscCall(PetscFree(R->gsys));
  PetscCall(MatDestroy(&R->Aconv));
  PetscFunctionReturn(0);
}

/* appends (A_b P_b)[i, :] (local row i of body b) to r; *sorted stays true while the columns come in increasing order,
   *tied (if given) is set true when a column is tied (read through its expression, which the angles change) */
static PetscErrorCode KFRowAppendBody(const KFBodyRows *R, const KFExpr *Eb, const PetscInt sysidx[], PetscInt i, KFRowBuf *r, PetscBool *sorted, PetscBool *tied)
{
  const PetscInt nd = R->ia[i + 1] - R->ia[i], no = R->Ao ? R->ib[i + 1] - R->ib[i] : 0;

  PetscFunctionBegin;
  PetscCall(KFRowBufReserve(r, nd + no));
  for (int part = 0; part < 2; part++) {
    const PetscInt     m  = part ? no : nd;
    const PetscInt    *cj;
    const PetscScalar *cv;

    if (!m) continue;
    cj = part ? R->jb + R->ib[i] : R->ja + R->ia[i];
    cv = part ? R->vb + R->ib[i] : R->va + R->ia[i];
    for (PetscInt k = 0; k < m; k++) {
      const PetscInt sj = part ? R->gsys[cj[k]] : sysidx[cj[k]];

      if (sj >= 0) {
        if (r->n && r->col[r->n - 1] >= sj) *sorted = PETSC_FALSE;
        r->col[r->n]   = sj;
        r->val[r->n++] = cv[k];
      } else if (sj == -1) { /* a tied column reads through its expression */
        const PetscInt dof = part ? R->garray[cj[k]] : R->rstart + cj[k];
        const KFExpr  *x   = &Eb[6 * R->ci + (dof - R->e0)];

        PetscCheck(R->ci >= 0 && dof >= R->e0 && dof < R->e0 + 6, PETSC_COMM_SELF, PETSC_ERR_PLIB, "tied dof %" PetscInt_FMT " outside its interface node", dof);
        PetscCall(KFRowBufReserve(r, x->n + nd + no)); /* the expression and what may follow it */
        for (PetscInt t = 0; t < x->n; t++) {
          r->col[r->n]   = x->idx[t];
          r->val[r->n++] = cv[k] * x->c[t];
        }
        *sorted = PETSC_FALSE;
        if (tied) *tied = PETSC_TRUE;
      } /* clamped (-2): P_b reads it as zero */
    }
  }
  PetscFunctionReturn(0);
}

/* the tied rows of every body, on every rank: (A_b P_b)[i, :] for the tied dofs i, gathered from their owners */
typedef struct {
  PetscInt     n;            /* tied rows over all bodies and ranks */
  PetscInt    *body, *k;     /* per tied row: its body and its place in the tied node (0..5) */
  PetscInt    *ptr, *col;    /* CSR of the expanded rows (system columns) */
  PetscScalar *val;
} KFTiedRows;

static PetscErrorCode KFTiedRowsGather(KFScene s, const KFBodyRows R[], KFExpr **E, KFTiedRows *T)
{
  KFRowBuf     r = {0};
  PetscInt     nmine = 0, *hdr, *mptr, nnz, *all;
  PetscInt    *mcol;
  PetscScalar *mval;
  PetscMPIInt  size, nh, ne, *rc, *rd, *ec, *ed;
  PetscBool    sorted;

  PetscFunctionBegin;
  PetscCall(PetscMemzero(T, sizeof(*T)));
  PetscCallMPI(MPI_Comm_size(s->comm, &size));
  for (PetscInt b = 0; b < s->nb; b++)
    for (PetscInt i = 0; i < R[b].nl; i++) nmine += s->bodies[b].sysidx[i] == -1;
  /* my tied rows: (body, k, length) headers, then their columns and values */
  PetscCall(PetscMalloc2(3 * nmine + 1, &hdr, nmine + 1, &mptr));
  mptr[0] = 0;
  for (PetscInt b = 0, m = 0; b < s->nb; b++)
    for (PetscInt i = 0; i < R[b].nl; i++) {
      if (s->bodies[b].sysidx[i] != -1) continue;
      sorted = PETSC_TRUE;
      PetscCall(KFRowAppendBody(&R[b], E[b], s->bodies[b].sysidx, i, &r, &sorted, NULL));
      mptr[m + 1]    = r.n; /* rows appended one after another into r */
      hdr[3 * m]     = b;
      hdr[3 * m + 1] = R[b].rstart + i - R[b].e0;
      hdr[3 * m + 2] = r.n - mptr[m];
      m++;
    }
  mcol = r.col;
  mval = r.val;
  /* each row sorted and compressed in place: compress row by row into the front */
  nnz = 0;
  for (PetscInt m = 0; m < nmine; m++) {
    KFRowBuf row = {hdr[3 * m + 2], hdr[3 * m + 2], mcol + mptr[m], mval + mptr[m]};

    PetscCall(KFRowBufCompress(&row));
    PetscCall(PetscArraymove(mcol + nnz, row.col, row.n));
    PetscCall(PetscArraymove(mval + nnz, row.val, row.n));
    hdr[3 * m + 2] = row.n;
    nnz += row.n;
  }
  /* everyone's */
  PetscCall(PetscMalloc4(size, &rc, size, &rd, size, &ec, size, &ed));
  nh = (PetscMPIInt)(3 * nmine);
  ne = (PetscMPIInt)nnz;
  PetscCallMPI(MPI_Allgather(&nh, 1, MPI_INT, rc, 1, MPI_INT, s->comm));
  PetscCallMPI(MPI_Allgather(&ne, 1, MPI_INT, ec, 1, MPI_INT, s->comm));
  rd[0] = ed[0] = 0;
  for (PetscMPIInt p = 1; p < size; p++) {
    rd[p] = rd[p - 1] + rc[p - 1];
    ed[p] = ed[p - 1] + ec[p - 1];
  }
  T->n = (rd[size - 1] + rc[size - 1]) / 3;
  nnz  = ed[size - 1] + ec[size - 1];
  PetscCall(PetscMalloc1(3 * T->n + 1, &all));
  PetscCall(PetscMalloc5(T->n + 1, &T->body, T->n + 1, &T->k, T->n + 1, &T->ptr, nnz + 1, &T->col, nnz + 1, &T->val));
  PetscCallMPI(MPI_Allgatherv(hdr, nh, MPIU_INT, all, rc, rd, MPIU_INT, s->comm));
  PetscCallMPI(MPI_Allgatherv(mcol, ne, MPIU_INT, T->col, ec, ed, MPIU_INT, s->comm));
  PetscCallMPI(MPI_Allgatherv(mval, ne, MPIU_SCALAR, T->val, ec, ed, MPIU_SCALAR, s->comm));
  T->ptr[0] = 0;
  for (PetscInt t = 0; t < T->n; t++) {
    T->body[t]    = all[3 * t];
    T->k[t]       = all[3 * t + 1];
    T->ptr[t + 1] = T->ptr[t] + all[3 * t + 2];
  }
  PetscCall(PetscFree(all));
  PetscCall(PetscFree4(rc, rd, ec, ed));
  PetscCall(PetscFree2(hdr, mptr));
  PetscCall(PetscFree(r.col));
  PetscCall(PetscFree(r.val));
  PetscFunctionReturn(0);
}

static PetscErrorCode KFTiedRowsDestroy(KFTiedRows *T)
{
  PetscFunctionBegin;
  PetscCall(PetscFree5(T->body, T->k, T->ptr, T->col, T->val));
  PetscFunctionReturn(0);
}

/* CSR arrays written row after row (entries pushed, then the row closed), grown when a row does not fit */
typedef struct {
  PetscInt    *i, *j, n, cap;
  PetscScalar *a;
} KFGrowCSR;

static PetscErrorCode KFGrowCSRCreate(PetscInt rows, PetscInt cap, KFGrowCSR *c)
{
  PetscFunctionBegin;
  c->n   = 0;
  c->cap = PetscMax(cap, 1);
  PetscCall(PetscMalloc1(rows + 1, &c->i));
  PetscCall(PetscMalloc1(c->cap, &c->j));
  PetscCall(PetscMalloc1(c->cap, &c->a));
  c->i[0] = 0;
  PetscFunctionReturn(0);
}

/* appends m entries to the open row, their columns less shift */
static PetscErrorCode KFGrowCSRPush(KFGrowCSR *c, PetscInt m, const PetscInt col[], const PetscScalar val[], PetscInt shift)
{
  PetscFunctionBegin;
  if (c->n + m > c->cap) {
    c->cap = PetscMax(2 * c->cap, c->n + m);
    PetscCall(PetscRealloc(sizeof(PetscInt) * c->cap, &c->j));
    PetscCall(PetscRealloc(sizeof(PetscScalar) * c->cap, &c->a));
  }
  for (PetscInt k = 0; k < m; k++) c->j[c->n + k] = col[k] - shift;
  PetscCall(PetscArraycpy(c->a + c->n, val, m));
  c->n += m;
  PetscFunctionReturn(0);
}

static PetscErrorCode KFGrowCSRFree(KFGrowCSR *c)
{
  PetscFunctionBegin;
  PetscCall(PetscFree(c->i));
  PetscCall(PetscFree(c->j));
  PetscCall(PetscFree(c->a));
  PetscFunctionReturn(0);
}

/* the CSR arrays of a matrix that the matrix itself frees (MatCreateSeqAIJWithArrays and
   MatCreateMPIAIJWithSplitArrays do not take them over): its diagonal block and, over ranks, its off-diagonal one */
typedef struct {
  KFGrowCSR d, o;
} KFAdoptedCSR;

static PetscErrorCode KFAdoptedCSRDestroy(void *ctx)
{
  KFAdoptedCSR *c = (KFAdoptedCSR *)ctx;

  PetscFunctionBegin;
  PetscCall(KFGrowCSRFree(&c->d));
  PetscCall(KFGrowCSRFree(&c->o));
  PetscCall(PetscFree(c));
  PetscFunctionReturn(0);
}

/* An AIJ matrix on the given sorted CSR arrays (the diagonal block's columns local, the off-diagonal block's global),
   which it keeps and frees: the rows are written in place in one pass, instead of counted in a first pass and set
   entry by entry through MatSetValues in a second (its search and insertion per entry were two thirds of the
   assembly's time on the 202k-dof solid). New nonzeros are an error, as for a preallocated matrix. */
static PetscErrorCode KFMatAdoptCSR(MPI_Comm comm, PetscInt n, PetscInt N, KFGrowCSR *d, KFGrowCSR *o, Mat *S)
{
  KFAdoptedCSR  *c;
  PetscContainer ct;
  PetscMPIInt    size;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_size(comm, &size));
  if (size == 1) PetscCall(MatCreateSeqAIJWithArrays(comm, n, n, d->i, d->j, d->a, S));
  else PetscCall(MatCreateMPIAIJWithSplitArrays(comm, n, n, N, N, d->i, d->j, d->a, o->i, o->j, o->a, S));
  PetscCall(PetscNew(&c));
  c->d = *d;
  c->o = *o;
  PetscCall(PetscContainerCreate(comm, &ct));
  PetscCall(PetscContainerSetPointer(ct, c));
  PetscCall(PetscContainerSetUserDestroy(ct, KFAdoptedCSRDestroy));
  PetscCall(PetscObjectCompose((PetscObject)*S, "KFAdoptedCSR", (PetscObject)ct));
  PetscCall(PetscContainerDestroy(&ct)); /* the matrix holds the only reference */
  PetscCall(MatSetOption(*S, MAT_NEW_NONZERO_LOCATION_ERR, PETSC_TRUE));
  PetscCall(MatSetOption(*S, MAT_NO_OFF_PROC_ENTRIES, PETSC_TRUE));
  PetscFunctionReturn(0);
}

/* A matrix of the same pattern refilled row by row in place: the values of its diagonal and off-diagonal blocks'
   CSR arrays written directly (MatSetValues' search per entry was half of a refill's time at 57k dofs). The local
   columns of a row are those of the diagonal block, the others those of the off-diagonal one (its compressed columns
   ascending, as their global numbers are): a row given sorted is written in place when its columns are the row's. */
typedef struct {
  Mat                Ad, Ao;
  const PetscInt    *ia, *ja, *ib, *jb, *garray;
  PetscScalar       *va, *vb;
  PetscInt           cstart, cend;
} KFRefill;

static PetscErrorCode KFRefillBegin(Mat S, KFRefill *f)
{
  PetscBool mpi, done;
  PetscInt  n;

  PetscFunctionBegin;
  PetscCall(PetscMemzero(f, sizeof(*f)));
  PetscCall(PetscObjectTypeCompare((PetscObject)S, MATMPIAIJ, &mpi));
  if (mpi) PetscCall(MatMPIAIJGetSeqAIJ(S, &f->Ad, &f->Ao, &f->garray));
  else f->Ad = S;
  PetscCall(MatGetOwnershipRangeColumn(S, &f->cstart, &f->cend));
  PetscCall(MatGetRowIJ(f->Ad, 0, PETSC_FALSE, PETSC_FALSE, &n, &f->ia, &f->ja, &done));
  PetscCheck(done, PETSC_COMM_SELF, PETSC_ERR_PLIB, "no row access to the system matrix");
  PetscCall(MatSeqAIJGetArray(f->Ad, &f->va));
  if (f->Ao) {
    PetscCall(MatGetRowIJ(f->Ao, 0, PETSC_FALSE, PETSC_FALSE, &n, &f->ib, &f->jb, &done));
    PetscCheck(done, PETSC_COMM_SELF, PETSC_ERR_PLIB, "no row access to the system matrix");
    PetscCall(MatSeqAIJGetArray(f->Ao, &f->vb));
  }
  PetscFunctionReturn(0);
}

static PetscErrorCode KFRefillEnd(Mat S, KFRefill *f)
{
  PetscInt  n;
  PetscBool done;

  PetscFunctionBegin;
  PetscCall(MatSeqAIJRestoreArray(f->Ad, &f->va));
  PetscCall(MatRestoreRowIJ(f->Ad, 0, PETSC_FALSE, PETSC_FALSE, &n, &f->ia, &f->ja, &done));
  if (f->Ao) {
    PetscCall(MatSeqAIJRestoreArray(f->Ao, &f->vb));
    PetscCall(MatRestoreRowIJ(f->Ao, 0, PETSC_FALSE, PETSC_FALSE, &n, &f->ib, &f->jb, &done));
  }
  PetscCall(PetscObjectStateIncrease((PetscObject)S));
  PetscFunctionReturn(0);
}

/* local row i's values written in place; *done false when its columns are not the row's (nothing written then) */
static void KFRefillRow(KFRefill *f, PetscInt i, PetscInt n, const PetscInt col[], const PetscScalar val[], PetscBool *done)
{
  const PetscInt nd = f->ia[i + 1] - f->ia[i], no = f->Ao ? f->ib[i + 1] - f->ib[i] : 0;
  PetscInt       lo = 0, k = 0;

  *done = PETSC_FALSE;
  if (n != nd + no) return;
  while (lo < no && f->garray[f->jb[f->ib[i] + lo]] < f->cstart) lo++; /* off-diagonal columns before the local ones */
  for (PetscInt t = 0; t < lo; t++, k++)
    if (col[k] != f->garray[f->jb[f->ib[i] + t]]) return;
  for (PetscInt t = 0; t < nd; t++, k++)
    if (col[k] != f->cstart + f->ja[f->ia[i] + t]) return;
  for (PetscInt t = lo; t < no; t++, k++)
    if (col[k] != f->garray[f->jb[f->ib[i] + t]]) return;
  k = 0;
  for (PetscInt t = 0; t < lo; t++) f->vb[f->ib[i] + t] = val[k++];
  for (PetscInt t = 0; t < nd; t++) f->va[f->ia[i] + t] = val[k++];
  for (PetscInt t = lo; t < no; t++) f->vb[f->ib[i] + t] = val[k++];
  *done = PETSC_TRUE;
}

/* Whether *S and the body matrices are as the last sum left them (ids and states: nothing wrote into them since,
   as the monolithic solve's held rows do), so that a row no angle changes holds its value already */
static PetscErrorCode KFSumUnchanged(KFSystem y, PetscInt m, Mat S, PetscBool *same)
{
  KFScene          s = y->scene;
  PetscObjectId    id;
  PetscObjectState st;

  PetscFunctionBegin;
  *same = PETSC_FALSE;
  if (!S || !y->sumbodyid[m]) PetscFunctionReturn(0);
  PetscCall(PetscObjectGetId((PetscObject)S, &id));
  PetscCall(PetscObjectStateGet((PetscObject)S, &st));
  if (id != y->sumid[m] || st != y->sumstate[m]) PetscFunctionReturn(0);
  for (PetscInt b = 0; b < s->nb; b++) {
    Mat A = m ? s->bodies[b].K : s->bodies[b].M;

    PetscCall(PetscObjectGetId((PetscObject)A, &id));
    PetscCall(PetscObjectStateGet((PetscObject)A, &st));
    if (id != y->sumbodyid[m][b] || st != y->sumbodystate[m][b]) PetscFunctionReturn(0);
  }
  *same = PETSC_TRUE;
  PetscFunctionReturn(0);
}

/* after a sum: the states it leaves and, after one written whole (var given), the rows the angles change */
static PetscErrorCode KFSumRecord(KFSystem y, PetscInt m, Mat S, PetscInt nvar, const PetscInt var[])
{
  KFScene s = y->scene;

  PetscFunctionBegin;
  if (var) {
    PetscCall(PetscFree3(y->sumvar[m], y->sumbodyid[m], y->sumbodystate[m]));
    PetscCall(PetscMalloc3(nvar + 1, &y->sumvar[m], s->nb, &y->sumbodyid[m], s->nb, &y->sumbodystate[m]));
    PetscCall(PetscArraycpy(y->sumvar[m], var, nvar));
    y->nsumvar[m] = nvar;
  }
  PetscCall(PetscObjectGetId((PetscObject)S, &y->sumid[m]));
  PetscCall(PetscObjectStateGet((PetscObject)S, &y->sumstate[m]));
  for (PetscInt b = 0; b < s->nb; b++) {
    Mat A = m ? s->bodies[b].K : s->bodies[b].M;

    PetscCall(PetscObjectGetId((PetscObject)A, &y->sumbodyid[m][b]));
    PetscCall(PetscObjectStateGet((PetscObject)A, &y->sumbodystate[m][b]));
  }
  PetscFunctionReturn(0);
}

/* S = sum_b P_b^T A_b P_b (A_b = M_b with mass, else K_b), every diagonal entry present (an unconnected dof must
   reach MUMPS as a null pivot, not as a missing entry). *S NULL: created on its CSR arrays, written in one pass; else
   the same pattern (an earlier angle's) refilled. The angles reach a row only through a tied column or a tied row
   received; a refill of a matrix nothing else wrote into since the last sum writes those rows only (the others would
   be written with the values they hold: the same operations on the same entries). */
PETSC_INTERN PetscErrorCode KFSystemSumBodies(KFSystem y, PetscBool mass, Mat *S)
{
  KFScene     s = y->scene;
  KFExpr    **E;
  KFBodyRows *R;
  KFTiedRows  T;
  KFRowBuf    r = {0};
  PetscInt    n = s->nsys_local, r0 = s->sys_rstart, *srcb, *srci, *cptr, *ct, ncon = 0;
  PetscReal  *cc;
  PetscBool   create = (PetscBool)(*S == NULL), some;
  PetscInt    m = mass ? 0 : 1, nrows, nvar = 0, *var = NULL;
  KFGrowCSR   D = {0}, O = {0}; /* a new matrix: its diagonal and off-diagonal blocks' CSR, written directly */
  KFRefill    F;                /* an earlier angle's matrix: its values written in place */

  PetscFunctionBegin;
  PetscCall(KFSystemInterfaceExprs(y, &E));
  PetscCall(PetscMalloc1(s->nb, &R));
  for (PetscInt b = 0; b < s->nb; b++) PetscCall(KFBodyRowsGet(s, b, mass ? s->bodies[b].M : s->bodies[b].K, &R[b]));
  PetscCall(KFTiedRowsGather(s, R, E, &T));

  /* which body row each local system row renames (-1: none, a joint's free rotation) */
  PetscCall(PetscMalloc2(n, &srcb, n, &srci));
  for (PetscInt i = 0; i < n; i++) srcb[i] = -1;
  for (PetscInt b = 0; b < s->nb; b++)
    for (PetscInt i = 0; i < R[b].nl; i++) {
      const PetscInt sr = s->bodies[b].sysidx[i] - r0;

      if (s->bodies[b].sysidx[i] < 0) continue;
      PetscCheck(sr >= 0 && sr < n, PETSC_COMM_SELF, PETSC_ERR_PLIB, "body '%s': kept dof %" PetscInt_FMT " is not on its body row's rank", s->bodies[b].name, s->bodies[b].sysidx[i]);
      srcb[sr] = b;
      srci[sr] = i;
    }
  /* the tied rows each local system row receives, with their coefficients: CSR by local row */
  PetscCall(PetscCalloc1(n + 1, &cptr));
  for (PetscInt t = 0; t < T.n; t++) {
    const KFBodyRows *Rb = &R[T.body[t]];
    const KFExpr     *x  = &E[T.body[t]][6 * Rb->ci + T.k[t]];

    for (PetscInt q = 0; q < x->n; q++)
      if (x->idx[q] >= r0 && x->idx[q] < r0 + n) {
        cptr[x->idx[q] - r0 + 1]++;
        ncon++;
      }
  }
  for (PetscInt i = 0; i < n; i++) cptr[i + 1] += cptr[i];
  PetscCall(PetscMalloc2(ncon + 1, &ct, ncon + 1, &cc));
  {
    PetscInt *fill;

    PetscCall(PetscMalloc1(n + 1, &fill));
    PetscCall(PetscArraycpy(fill, cptr, n + 1));
    for (PetscInt t = 0; t < T.n; t++) {
      const KFBodyRows *Rb = &R[T.body[t]];
      const KFExpr     *x  = &E[T.body[t]][6 * Rb->ci + T.k[t]];

      for (PetscInt q = 0; q < x->n; q++)
        if (x->idx[q] >= r0 && x->idx[q] < r0 + n) {
          ct[fill[x->idx[q] - r0]]   = t;
          cc[fill[x->idx[q] - r0]++] = x->c[q];
        }
    }
    PetscCall(PetscFree(fill));
  }

  if (create) { /* room for the bodies' entries, the tied rows' and a diagonal per row: enough unless tied columns expand */
    PetscInt cap = n + 1;

    for (PetscInt b = 0; b < s->nb; b++) cap += R[b].ia[R[b].nl] + (R[b].Ao ? R[b].ib[R[b].nl] : 0);
    for (PetscInt q = 0; q < ncon; q++) cap += T.ptr[ct[q] + 1] - T.ptr[ct[q]];
    PetscCall(KFGrowCSRCreate(n, cap, &D));
    PetscCall(KFGrowCSRCreate(n, 1, &O));
  } else {
    PetscCall(MatSetOption(*S, MAT_NEW_NONZERO_LOCATION_ERR, PETSC_TRUE)); /* the same pattern: anything new is a bug */
    PetscCall(MatSetOption(*S, MAT_NO_OFF_PROC_ENTRIES, PETSC_TRUE));      /* every rank writes its own rows only */
    PetscCall(KFRefillBegin(*S, &F));
  }
  PetscCall(KFSumUnchanged(y, m, create ? NULL : *S, &some));
  nrows = some ? y->nsumvar[m] : n;
  if (!some) PetscCall(PetscMalloc1(n + 1, &var));
  for (PetscInt q0 = 0; q0 < nrows; q0++) {
    const PetscInt i = some ? y->sumvar[m][q0] : q0, row = r0 + i;
    PetscBool      sorted = PETSC_TRUE, diag = PETSC_FALSE, tied = (PetscBool)(cptr[i + 1] > cptr[i]);

    r.n = 0;
    if (srcb[i] >= 0) PetscCall(KFRowAppendBody(&R[srcb[i]], E[srcb[i]], s->bodies[srcb[i]].sysidx, srci[i], &r, &sorted, &tied));
    if (!some && tied) var[nvar++] = i;
    for (PetscInt q = cptr[i]; q < cptr[i + 1]; q++) {
      const PetscInt t = ct[q];

      PetscCall(KFRowBufReserve(&r, T.ptr[t + 1] - T.ptr[t]));
      for (PetscInt e = T.ptr[t]; e < T.ptr[t + 1]; e++) {
        r.col[r.n]   = T.col[e];
        r.val[r.n++] = cc[q] * T.val[e];
      }
      sorted = PETSC_FALSE;
    }
    if (!sorted) PetscCall(KFRowBufCompress(&r));
    for (PetscInt k = 0; k < r.n && !diag; k++) diag = (PetscBool)(r.col[k] == row);
    if (!diag) { /* an explicit zero on the diagonal */
      PetscCall(KFRowBufReserve(&r, 1));
      r.col[r.n]   = row;
      r.val[r.n++] = 0;
      if (r.n > 1 && r.col[r.n - 2] > row) PetscCall(KFRowBufCompress(&r));
    }
    if (create) { /* sorted, no repeats (KFRowBufCompress): the local columns are one slice, the others before and after it */
      PetscInt lo = 0, hi;

      while (lo < r.n && r.col[lo] < r0) lo++;
      hi = lo;
      while (hi < r.n && r.col[hi] < r0 + n) hi++;
      PetscCall(KFGrowCSRPush(&D, hi - lo, r.col + lo, r.val + lo, r0));
      PetscCall(KFGrowCSRPush(&O, lo, r.col, r.val, 0));
      PetscCall(KFGrowCSRPush(&O, r.n - hi, r.col + hi, r.val + hi, 0));
      D.i[i + 1] = D.n;
      O.i[i + 1] = O.n;
    } else {
      PetscBool done;

      KFRefillRow(&F, i, r.n, r.col, r.val, &done);
      if (!done) { /* not the pattern the matrix was made with (no angle changes it): the general way */
        PetscCall(KFRefillEnd(*S, &F));
        PetscCall(MatSetValues(*S, 1, &row, r.n, r.col, r.val, INSERT_VALUES));
        PetscCall(KFRefillBegin(*S, &F));
      }
    }
  }
  if (create) PetscCall(KFMatAdoptCSR(s->comm, n, s->nsys, &D, &O, S));
  else PetscCall(KFRefillEnd(*S, &F));
  PetscCall(MatAssemblyBegin(*S, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*S, MAT_FINAL_ASSEMBLY));
  PetscCall(KFSumRecord(y, m, *S, nvar, var)); /* the states this refill leaves: the next angle's starting point */
  PetscCall(PetscInfo(*S, "%s: %" PetscInt_FMT " of %" PetscInt_FMT " local rows written\n", mass ? "M_S" : "K_S", nrows, n));
  PetscCall(PetscFree(var));
  PetscCall(PetscFree2(ct, cc));
  PetscCall(PetscFree(cptr));
  PetscCall(PetscFree2(srcb, srci));
  PetscCall(PetscFree(r.col));
  PetscCall(PetscFree(r.val));
  PetscCall(KFTiedRowsDestroy(&T));
  for (PetscInt b = 0; b < s->nb; b++) PetscCall(KFBodyRowsRestore(&R[b]));
  PetscCall(PetscFree(R));
  PetscCall(KFSystemInterfaceExprsDestroy(y, &E));
  PetscFunctionReturn(0);
}
