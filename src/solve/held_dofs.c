#include <kryflex_impl.h>

/* The natural clamp: the 6 dofs of one node of the root body (its first interface node, else its node nearest the
   centroid) and each revolute joint's free rotation. Holding them leaves a cantilevered tree, which is as well
   conditioned as the structure itself; holding far-away dofs (what a plain pivoted QR picks) hangs the structure
   from its floppiest appendages and costs digits. Returns nheld = 0 when the scene has no 6-dof root node. */
PETSC_INTERN PetscErrorCode KFSelectClampDofs(KFScene s, PetscInt *nheld, PetscInt **held)
{
  KFBodyData *R = &s->bodies[s->order[0]];
  PetscInt    node = -1, loc[6], k = 0;

  PetscFunctionBegin;
  *nheld = 0;
  if (R->ninterfaces > 0) node = R->iface[0].node;
  else {
    PetscReal c[3] = {0, 0, 0}, best = PETSC_MAX_REAL;
    for (PetscInt i = 0; i < R->nnodes; i++)
      for (int d = 0; d < 3; d++) c[d] += R->xyz[3 * i + d] / R->nnodes;
    for (PetscInt i = 0; i < R->nnodes; i++) {
      PetscReal d2 = 0;
      if (R->ndof[i] != 6) continue;
      for (int d = 0; d < 3; d++) d2 += PetscSqr(R->xyz[3 * i + d] - c[d]);
      if (d2 < best) {
        best = d2;
        node = i;
      }
    }
  }
  if (node < 0) PetscFunctionReturn(0);
  for (int d = 0; d < 6; d++) {
    PetscInt dof = R->dof0[node] + d;
    loc[d]       = (dof >= R->rstart && dof < R->rend) ? R->sysidx[dof - R->rstart] : -1;
  }
  PetscCall(PetscMalloc1(6 + s->nrevolute, held));
  PetscCall(MPIU_Allreduce(loc, *held, 6, MPIU_INT, MPI_MAX, s->comm));
  for (int d = 0; d < 6; d++)
    if ((*held)[d] < 0) { /* the node is clamped or tied: no clamp choice here */
      PetscCall(PetscFree(*held));
      PetscFunctionReturn(0);
    }
  k = 6;
  for (PetscInt j = 0; j < s->nj; j++)
    if (s->joints[j].beta >= 0) (*held)[k++] = s->joints[j].beta;
  *nheld = k;
  PetscFunctionReturn(0);
}

/* Fallback: a statically determinate set of held dofs for any rigid modes: r dofs on which the rigid modes are independent, chosen by
   QR with column pivoting of Phi^T (each step takes the dof whose row of Phi has the largest part not yet
   spanned). Holding them removes every rigid and mechanism motion, so K with those rows and columns replaced by
   the identity is positive definite when the declared modes are all of K's null space. */
PETSC_INTERN PetscErrorCode KFSelectPivotedDofs(Mat Phi, PetscInt *nheld, PetscInt **held)
{
  PetscInt           nl, r, lda, rstart;
  const PetscScalar *a;
  PetscReal         *W, *q;
  MPI_Comm           comm;
  PetscMPIInt        rank;

  PetscFunctionBegin;
  PetscCall(PetscObjectGetComm((PetscObject)Phi, &comm));
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCall(MatGetLocalSize(Phi, &nl, NULL));
  PetscCall(MatGetSize(Phi, NULL, &r));
  PetscCall(MatGetOwnershipRange(Phi, &rstart, NULL));
  PetscCall(MatDenseGetLDA(Phi, &lda));
  PetscCall(PetscMalloc2(nl * r + 1, &W, r, &q));
  PetscCall(PetscMalloc1(r, held));
  PetscCall(MatDenseGetArrayRead(Phi, &a));
  for (PetscInt i = 0; i < nl; i++) /* row-major copy: one r-vector per dof */
    for (PetscInt k = 0; k < r; k++) W[i * r + k] = PetscRealPart(a[i + k * lda]);
  PetscCall(MatDenseRestoreArrayRead(Phi, &a));
  for (PetscInt step = 0; step < r; step++) {
    struct {
      PetscReal v;
      PetscInt  i;
    } loc = {-1.0, -1}, glob;
    PetscReal nrm;
    PetscInt  owner_row;
    for (PetscInt i = 0; i < nl; i++) {
      PetscReal s = 0;
      for (PetscInt k = 0; k < r; k++) s += W[i * r + k] * W[i * r + k];
      if (s > loc.v) {
        loc.v = s;
        loc.i = rstart + i;
      }
    }
    /* the largest row, the lowest global index among equals: the same choice on every rank */
    PetscCall(MPIU_Allreduce(&loc.v, &glob.v, 1, MPIU_REAL, MPIU_MAX, comm));
    loc.i = (loc.v == glob.v) ? loc.i : PETSC_MAX_INT;
    PetscCall(MPIU_Allreduce(&loc.i, &glob.i, 1, MPIU_INT, MPI_MIN, comm));
    PetscCheck(glob.v > 0, comm, PETSC_ERR_ARG_WRONG, "the rigid-body modes are linearly dependent: cannot find %" PetscInt_FMT " dofs to hold", r);
    owner_row = glob.i - rstart;
    for (PetscInt k = 0; k < r; k++) q[k] = (owner_row >= 0 && owner_row < nl) ? W[owner_row * r + k] : 0;
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, q, (PetscMPIInt)r, MPIU_REAL, MPIU_SUM, comm));
    nrm = PetscSqrtReal(glob.v);
    for (PetscInt k = 0; k < r; k++) q[k] /= nrm;
    for (PetscInt i = 0; i < nl; i++) {
      PetscReal d = 0;
      for (PetscInt k = 0; k < r; k++) d += W[i * r + k] * q[k];
      for (PetscInt k = 0; k < r; k++) W[i * r + k] -= d * q[k];
    }
    (*held)[step] = glob.i;
  }
  *nheld = r;
  PetscCall(PetscFree2(W, q));
  PetscFunctionReturn(0);
}

/* The held dofs must determine every rigid mode: Phi restricted to them is square and well conditioned. */
static PetscErrorCode KFHeldConditioning(Mat Phi, PetscInt nheld, const PetscInt held[], PetscReal *cond)
{
  PetscInt           r, rstart, rend, lda;
  const PetscScalar *a;
  PetscReal         *A, *Id, *ev, *vecs, *AtA;

  PetscFunctionBegin;
  PetscCall(MatGetSize(Phi, NULL, &r));
  *cond = PETSC_INFINITY;
  if (nheld != r) PetscFunctionReturn(0);
  PetscCall(MatGetOwnershipRange(Phi, &rstart, &rend));
  PetscCall(MatDenseGetLDA(Phi, &lda));
  PetscCall(PetscCalloc5(r * r, &A, r * r, &Id, r, &ev, r * r, &vecs, r * r, &AtA));
  PetscCall(MatDenseGetArrayRead(Phi, &a));
  for (PetscInt i = 0; i < r; i++)
    if (held[i] >= rstart && held[i] < rend)
      for (PetscInt j = 0; j < r; j++) A[i + j * r] = PetscRealPart(a[(held[i] - rstart) + j * lda]);
  PetscCall(MatDenseRestoreArrayRead(Phi, &a));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, A, (PetscMPIInt)(r * r), MPIU_REAL, MPIU_SUM, PetscObjectComm((PetscObject)Phi)));
  for (PetscInt i = 0; i < r; i++)
    for (PetscInt j = 0; j < r; j++) {
      for (PetscInt k = 0; k < r; k++) AtA[i + j * r] += A[k + i * r] * A[k + j * r];
      Id[i + j * r] = (i == j);
    }
  PetscCall(KFDenseEig(r, AtA, Id, ev, vecs));
  if (ev[0] > 0) *cond = PetscSqrtReal(ev[r - 1] / ev[0]);
  PetscCall(PetscFree5(A, Id, ev, vecs, AtA));
  PetscFunctionReturn(0);
}

/* -kf_held_cond_max, read and checked (also before any work: KFFlexSolverCheckOptions) */
PETSC_INTERN PetscErrorCode KFHeldDofsOptions(MPI_Comm comm, const char prefix[], PetscReal *cond_max)
{
  PetscFunctionBegin;
  *cond_max = 1e8;
  PetscOptionsBegin(comm, prefix, "kryflex held dofs of the flexible solve", "KFFlexSolverSetUp");
  PetscCall(KFOptionsSettingReal(PetscOptionsObject, "-kf_held_cond_max", *cond_max, cond_max, NULL));
  PetscOptionsEnd();
  PetscCheck(*cond_max >= 1, comm, PETSC_ERR_ARG_OUTOFRANGE, "-kf_held_cond_max is a condition number, 1 or more; got %g", (double)*cond_max);
  PetscFunctionReturn(0);
}

PETSC_INTERN PetscErrorCode KFSelectHeldDofs(KFSystem sys, const char prefix[], PetscInt *nheld, PetscInt **held)
{
  PetscReal cond = PETSC_INFINITY, cond_max;

  PetscFunctionBegin;
  PetscCall(KFHeldDofsOptions(sys->scene->comm, prefix, &cond_max));
  /* the clamp holds for supplied rigid modes too when they span the same motions: its conditioning tells */
  PetscCall(KFSelectClampDofs(sys->scene, nheld, held));
  if (*nheld) PetscCall(KFHeldConditioning(sys->Phi, *nheld, *held, &cond));
  if (!(cond < cond_max)) {
    if (*nheld) PetscCall(PetscFree(*held));
    PetscCall(KFSelectPivotedDofs(sys->Phi, nheld, held));
  }
  PetscFunctionReturn(0);
}

/* Holding dofs in K_S itself, for the time of its factorization: a copy of K_S (the largest matrix of a run after the
   factor) is what the held factorization used to cost in memory, and K_S is needed unchanged afterwards (residuals,
   verification). KFHoldDofsInPlace saves the entries of the held rows and columns (the pattern of K_S is symmetric,
   so a held column's rows are its row's columns), zeroes them with a scaled unit diagonal; KFRestoreHeldDofs writes
   the saved values back into the same (kept) pattern, bit for bit. */
struct _n_KFHeldEntries {
  PetscInt     n;       /* saved local entries */
  PetscInt    *row, *col;
  PetscScalar *val;
};

PETSC_INTERN PetscErrorCode KFHoldDofsInPlace(Mat K, PetscInt nheld, const PetscInt held[], PetscScalar diag, KFHeldEntries *saved)
{
  MPI_Comm     comm;
  PetscInt     rstart, rend, nloc = 0, *loc, npairs = 0, cap = 0, *pairs = NULL, *allpairs, total, nrowent = 0;
  PetscMPIInt  size, mine, *counts, *displs;
  KFHeldEntries h;

  PetscFunctionBegin;
  PetscCall(PetscObjectGetComm((PetscObject)K, &comm));
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCall(MatGetOwnershipRange(K, &rstart, &rend));
  PetscCall(PetscNew(&h));
  PetscCall(PetscMalloc1(PetscMax(nheld, 1), &loc));
  /* (row, held column) pairs of the held rows this rank owns: every entry a held row or column holds */
  for (PetscInt k = 0; k < nheld; k++) {
    PetscInt           r = held[k], nc;
    const PetscInt    *cols;
    if (r < rstart || r >= rend) continue;
    loc[nloc++] = r;
    PetscCall(MatGetRow(K, r, &nc, &cols, NULL));
    nrowent += nc;
    if (npairs + 2 * nc > cap) {
      cap = 2 * (npairs + 2 * nc);
      PetscCall(PetscRealloc(sizeof(PetscInt) * cap, &pairs));
    }
    for (PetscInt j = 0; j < nc; j++) {
      pairs[npairs++] = cols[j];
      pairs[npairs++] = r;
    }
    PetscCall(MatRestoreRow(K, r, &nc, &cols, NULL));
  }
  PetscCall(PetscMPIIntCast(npairs, &mine));
  PetscCall(PetscMalloc2(size, &counts, size, &displs));
  PetscCallMPI(MPI_Allgather(&mine, 1, MPI_INT, counts, 1, MPI_INT, comm));
  displs[0] = 0;
  for (PetscMPIInt p = 1; p < size; p++) displs[p] = displs[p - 1] + counts[p - 1];
  total = displs[size - 1] + counts[size - 1];
  PetscCall(PetscMalloc1(PetscMax(total, 1), &allpairs));
  PetscCallMPI(MPI_Allgatherv(pairs, mine, MPIU_INT, allpairs, counts, displs, MPIU_INT, comm));
  PetscCall(PetscFree(pairs));
  PetscCall(PetscFree2(counts, displs));
  /* each rank saves the entries of its own rows: the held columns' entries (i, r) and the held rows (r, c) */
  PetscCall(PetscMalloc3(total / 2 + nrowent + 1, &h->row, total / 2 + nrowent + 1, &h->col, total / 2 + nrowent + 1, &h->val));
  for (PetscInt q = 0; q < total / 2; q++) {
    PetscInt i = allpairs[2 * q], r = allpairs[2 * q + 1];
    if (i < rstart || i >= rend) continue;
    h->row[h->n] = i;
    h->col[h->n] = r;
    PetscCall(MatGetValues(K, 1, &i, 1, &r, &h->val[h->n]));
    h->n++;
  }
  for (PetscInt k = 0; k < nloc; k++) { /* the held rows themselves */
    PetscInt           r = loc[k], nc;
    const PetscInt    *cols;
    const PetscScalar *vals;
    PetscCall(MatGetRow(K, r, &nc, &cols, &vals));
    for (PetscInt j = 0; j < nc; j++) {
      h->row[h->n] = r;
      h->col[h->n] = cols[j];
      h->val[h->n] = vals[j];
      h->n++;
    }
    PetscCall(MatRestoreRow(K, r, &nc, &cols, &vals));
  }
  PetscCall(PetscFree(allpairs));
  /* MatZeroRowsColumns keeps the pattern (the entries become zeros), so the restore inserts into existing entries */
  PetscCall(MatZeroRowsColumns(K, nloc, loc, diag, NULL, NULL));
  PetscCall(PetscFree(loc));
  *saved = h;
  PetscFunctionReturn(0);
}

PETSC_INTERN PetscErrorCode KFRestoreHeldDofs(Mat K, KFHeldEntries *saved)
{
  KFHeldEntries h = *saved;

  PetscFunctionBegin;
  if (!h) PetscFunctionReturn(0);
  PetscCall(MatSetOption(K, MAT_NEW_NONZERO_LOCATION_ERR, PETSC_TRUE)); /* the pattern must not grow */
  for (PetscInt k = 0; k < h->n; k++) PetscCall(MatSetValues(K, 1, &h->row[k], 1, &h->col[k], &h->val[k], INSERT_VALUES));
  PetscCall(MatAssemblyBegin(K, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(K, MAT_FINAL_ASSEMBLY));
  PetscCall(MatSetOption(K, MAT_NEW_NONZERO_LOCATION_ERR, PETSC_FALSE));
  PetscCall(PetscFree3(h->row, h->col, h->val));
  PetscCall(PetscFree(h));
  *saved = NULL;
  PetscFunctionReturn(0);
}
