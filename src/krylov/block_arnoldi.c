#include <kryflex/krylovimpl.h>
#include <petscblaslapack.h>
#include "../dense/dense_impl.h"

/* A growing M-orthonormal basis: its columns in a BV and, beside them, M times each column (MV: local rows,
   column-major, leading dimension nl), computed when the column was made, so that no column's product with M is
   formed twice. Without a BV (V NULL, KFMBasisCreateGrowing) the columns are an array of its own, Vc (leading
   dimension nl), and Vc and MV grow with the columns appended up to mmax: a BV is allocated for its whole size and
   zero-filled, touched up front for columns an eigensolve that stops early never makes. */
typedef struct {
  BV           V;
  PetscScalar *MV;
  PetscInt     k, nl;
  MPI_Comm     comm;
  PetscScalar *Vc;      /* the columns without a BV */
  PetscInt     m, mmax; /* columns allocated in Vc and MV, the most they may grow to (with a BV: its size, both) */
  PetscScalar *work; /* the appended block and its product (2 x nl x wcap): kept from block to block, since a fresh
                        allocation of that size is fresh pages, faulted in and zeroed by the system at every block */
  PetscInt     wcap;
} KFMBasis;

/* The rigid modes the blocks are kept M-orthogonal to, with M Phi formed once for the whole basis. */
typedef struct {
  KFSystem           sys;
  Mat                MPhi; /* NULL without rigid modes (clamped) */
  PetscInt           r, ldp, ldmp;
  const PetscScalar *phi, *mphi; /* the local rows of Phi and M Phi while the basis is built (KFRigidSpaceOpen) */
  PetscReal         *mscale;     /* per local row: ||M_b||_inf of the body the dof belongs to (null-space test) */
  PetscBool          mnorm_only; /* KFMBasisAppend's deflation on M-norms alone, without the null-space test */
} KFRigidSpace;

/* ||M_b||_inf of a body, computed once for all the configurations (a sweep of M_b per body per configuration was
   half the set-up of each configuration's basis) and again only when M_b changed */
static PetscErrorCode KFBodyMassNorm(KFBodyData *B, PetscReal *nb)
{
  PetscObjectState st;

  PetscFunctionBegin;
  PetscCall(PetscObjectStateGet((PetscObject)B->M, &st));
  if (!B->mnorm_state || st != B->mnorm_state) {
    PetscCall(MatNorm(B->M, NORM_INFINITY, &B->mnorm));
    B->mnorm_state = st ? st : 1;
  }
  *nb = B->mnorm;
  PetscFunctionReturn(0);
}

/* The rigid modes of the system, M Phi (the system's own: no product here), their local arrays and, for the
   null-space test (null_test), each local system dof's body mass scale. The arrays are read while the basis is built;
   neither matrix changes meanwhile. */
static PetscErrorCode KFRigidSpaceOpen(KFSystem sys, PetscBool null_test, KFRigidSpace *rs)
{
  PetscFunctionBegin;
  PetscCall(PetscMemzero(rs, sizeof(*rs)));
  rs->sys        = sys;
  rs->mnorm_only = (PetscBool)!null_test;
  PetscCall(MatGetSize(sys->Phi, NULL, &rs->r));
  PetscCall(KFSystemGetMPhi(sys, &rs->MPhi));
  if (rs->r) {
    PetscCall(MatDenseGetLDA(sys->Phi, &rs->ldp));
    PetscCall(MatDenseGetLDA(rs->MPhi, &rs->ldmp));
    const PetscScalar *a;

    PetscCall(MatDenseGetArrayRead(sys->Phi, &a));
    rs->phi = a; /* the restore clears its argument, not the array */
    PetscCall(MatDenseRestoreArrayRead(sys->Phi, &a));
    PetscCall(MatDenseGetArrayRead(rs->MPhi, &a));
    rs->mphi = a;
    PetscCall(MatDenseRestoreArrayRead(rs->MPhi, &a));
  }
  if (null_test) { /* a system dof is one body's kept dof: that body's ||M_b|| */
    KFScene            s = sys->scene;
    Vec                v;
    const PetscScalar *a;
    PetscReal          mnorm;
    PetscInt           nl;
    PetscBool          unset = PETSC_FALSE, anyunset;

    PetscCall(MatCreateVecs(sys->Ms, &v, NULL));
    PetscCall(VecSet(v, -1.0)); /* not yet a body's */
    for (PetscInt b = 0; b < s->nb; b++) {
      KFBodyData *B = &s->bodies[b];
      PetscReal   nb = 0;

      PetscCall(KFBodyMassNorm(B, &nb));
      for (PetscInt i = 0; i < B->rend - B->rstart; i++)
        if (B->sysidx[i] >= 0 && nb > 0) PetscCall(VecSetValue(v, B->sysidx[i], nb, INSERT_VALUES));
    }
    PetscCall(VecAssemblyBegin(v));
    PetscCall(VecAssemblyEnd(v));
    PetscCall(VecGetLocalSize(v, &nl));
    PetscCall(PetscMalloc1(nl + 1, &rs->mscale));
    PetscCall(VecGetArrayRead(v, &a));
    for (PetscInt i = 0; i < nl; i++) {
      rs->mscale[i] = PetscRealPart(a[i]);
      unset         = (PetscBool)(unset || rs->mscale[i] < 0);
    }
    PetscCall(VecRestoreArrayRead(v, &a));
    PetscCall(VecDestroy(&v));
    PetscCall(MPIU_Allreduce(&unset, &anyunset, 1, MPIU_BOOL, MPI_LOR, s->comm));
    if (anyunset) { /* a dof no body with mass keeps (none expected): the whole system's scale */
      PetscCall(MatNorm(sys->Ms, NORM_INFINITY, &mnorm));
      for (PetscInt i = 0; i < nl; i++)
        if (rs->mscale[i] < 0) rs->mscale[i] = mnorm;
    }
  }
  PetscFunctionReturn(0);
}

static PetscErrorCode KFRigidSpaceClose(KFRigidSpace *rs)
{
  PetscFunctionBegin;
  PetscCall(PetscFree(rs->mscale));
  PetscFunctionReturn(0);
}

static PetscErrorCode KFMBasisCreate(BV V, KFMBasis *mb)
{
  PetscInt nl, m;

  PetscFunctionBegin;
  PetscCall(PetscMemzero(mb, sizeof(*mb)));
  PetscCall(BVGetSizes(V, &nl, NULL, &m));
  mb->V    = V;
  mb->comm = PetscObjectComm((PetscObject)V);
  mb->nl   = nl;
  mb->m = mb->mmax = m;
  PetscCall(PetscMalloc1(nl * m + 1, &mb->MV));
  PetscFunctionReturn(0);
}

/* A basis of at most mmax columns of nl local rows, its arrays allocated as it grows (KFMBasisReserve) */
static PetscErrorCode KFMBasisCreateGrowing(MPI_Comm comm, PetscInt nl, PetscInt mmax, KFMBasis *mb)
{
  PetscFunctionBegin;
  PetscCall(PetscMemzero(mb, sizeof(*mb)));
  mb->comm = comm;
  mb->nl   = nl;
  mb->mmax = mmax;
  PetscFunctionReturn(0);
}

/* room for ncols columns (at most mmax; a BV's basis has its room already), by realloc: what is not yet written is
   not touched */
static PetscErrorCode KFMBasisReserve(KFMBasis *mb, PetscInt ncols)
{
  PetscFunctionBegin;
  ncols = PetscMin(ncols, mb->mmax);
  if (mb->V || ncols <= mb->m) PetscFunctionReturn(0);
  PetscCall(PetscRealloc(sizeof(PetscScalar) * (mb->nl * ncols + 1), &mb->Vc));
  PetscCall(PetscRealloc(sizeof(PetscScalar) * (mb->nl * ncols + 1), &mb->MV));
  mb->m = ncols;
  PetscFunctionReturn(0);
}

static PetscErrorCode KFMBasisDestroy(KFMBasis *mb)
{
  PetscFunctionBegin;
  PetscCall(PetscFree(mb->MV));
  PetscCall(PetscFree(mb->Vc));
  PetscCall(PetscFree(mb->work));
  mb->wcap = 0;
  PetscFunctionReturn(0);
}

/* the local rows of the columns (leading dimension nl), from the BV or the basis's own array */
static PetscErrorCode KFMBasisGetColumnsRead(const KFMBasis *mb, const PetscScalar **v)
{
  PetscFunctionBegin;
  if (mb->V) PetscCall(BVGetArrayRead(mb->V, v));
  else *v = mb->Vc;
  PetscFunctionReturn(0);
}

static PetscErrorCode KFMBasisRestoreColumnsRead(const KFMBasis *mb, const PetscScalar **v)
{
  PetscFunctionBegin;
  if (mb->V) PetscCall(BVRestoreArrayRead(mb->V, v));
  else *v = NULL;
  PetscFunctionReturn(0);
}

static PetscErrorCode KFMBasisGetColumns(KFMBasis *mb, PetscScalar **v)
{
  PetscFunctionBegin;
  if (mb->V) PetscCall(BVGetArray(mb->V, v));
  else *v = mb->Vc;
  PetscFunctionReturn(0);
}

static PetscErrorCode KFMBasisRestoreColumns(KFMBasis *mb, PetscScalar **v)
{
  PetscFunctionBegin;
  if (mb->V) PetscCall(BVRestoreArray(mb->V, v));
  else *v = NULL;
  PetscFunctionReturn(0);
}

/* y = M x for p local columns x (nl x p, leading dimension nl): one sparse-times-dense product for the whole block
   (several times faster per column than one MatMult per column), written in place into y (no product matrix of its
   own to allocate, fault in and copy from at every append) */
static PetscErrorCode KFMProduct(Mat M, PetscInt nl, PetscInt p, PetscScalar *x, PetscScalar *y)
{
  Mat      X, Y;
  PetscInt N;
  MPI_Comm comm = PetscObjectComm((PetscObject)M);

  PetscFunctionBegin;
  PetscCall(MatGetSize(M, &N, NULL));
  PetscCall(MatCreateDense(comm, nl, PETSC_DECIDE, N, p, x, &X));
  PetscCall(MatCreateDense(comm, nl, PETSC_DECIDE, N, p, y, &Y));
  PetscCall(KFMatMultDenseInto(M, X, Y));
  PetscCall(MatDestroy(&Y));
  PetscCall(MatDestroy(&X));
  PetscFunctionReturn(0);
}

/* The coefficients c ((r + k) x p, column-major, rigid rows first, replicated) of the block w (nl x p) against the
   rigid modes and the basis columns: [Phi V]^T (M w) from mw = M w, or with mw NULL from the kept products,
   (M [Phi V])^T w: a first pass needs no product of w with M. One reduction over the ranks. */
static PetscErrorCode KFMBasisCoefficients(const KFRigidSpace *rs, const KFMBasis *mb, PetscInt p, const PetscScalar *w, const PetscScalar *mw, PetscReal c[])
{
  const PetscInt     r = rs->r, k = mb->k, nl = mb->nl;
  const PetscScalar *x = mw ? mw : w, *v;
  PetscReal         *loc;

  PetscFunctionBegin;
  PetscCall(PetscCalloc1((r + k) * p + 1, &loc));
  if (r) PetscCall(KFArraySkinnyTransposeMult(nl, r, mw ? rs->phi : rs->mphi, mw ? rs->ldp : rs->ldmp, p, x, nl, loc, r + k));
  PetscCall(KFMBasisGetColumnsRead(mb, &v));
  PetscCall(KFArraySkinnyTransposeMult(nl, k, mw ? v : mb->MV, nl, p, x, nl, loc + r, r + k));
  PetscCall(KFMBasisRestoreColumnsRead(mb, &v));
  PetscCall(MPIU_Allreduce(loc, c, (PetscMPIInt)((r + k) * p), MPIU_REAL, MPIU_SUM, mb->comm));
  PetscCall(PetscFree(loc));
  PetscFunctionReturn(0);
}

/* w -= [Phi V] c, and mw -= [M Phi, M V] c when mw is given (from the kept products: exact up to the rounding of the
   correction, so only used when the coefficients are small) */
static PetscErrorCode KFMBasisSubtract(const KFRigidSpace *rs, const KFMBasis *mb, PetscInt p, const PetscReal c[], PetscScalar *w, PetscScalar *mw)
{
  const PetscInt     r = rs->r, k = mb->k, nl = mb->nl;
  const PetscScalar *v;

  PetscFunctionBegin;
  if (r) {
    PetscCall(KFArraySkinnyMultAdd(nl, r, rs->phi, rs->ldp, p, -1.0, c, r + k, w, nl));
    if (mw) PetscCall(KFArraySkinnyMultAdd(nl, r, rs->mphi, rs->ldmp, p, -1.0, c, r + k, mw, nl));
  }
  PetscCall(KFMBasisGetColumnsRead(mb, &v));
  PetscCall(KFArraySkinnyMultAdd(nl, k, v, nl, p, -1.0, c + r, r + k, w, nl));
  PetscCall(KFMBasisRestoreColumnsRead(mb, &v));
  if (mw) PetscCall(KFArraySkinnyMultAdd(nl, k, mb->MV, nl, p, -1.0, c + r, r + k, mw, nl));
  PetscFunctionReturn(0);
}

/* One classical Gram-Schmidt pass of the block w (nl x p, mw = M w) against the rigid modes and the basis columns:
   the coefficients (KFMBasisCoefficients: from mw, or from the kept products with mw NULL), then w -= [Phi V] c, and
   mw with it when update is set. cnorm2, when given, receives each column's |c|^2 (its M-norm squared inside the span
   of [Phi V], which is M-orthonormal). */
static PetscErrorCode KFMBasisProjectOut(const KFRigidSpace *rs, KFMBasis *mb, PetscInt p, PetscScalar *w, PetscScalar *mw, PetscBool update, PetscReal cnorm2[])
{
  const PetscInt r = rs->r, k = mb->k;
  PetscReal     *c;

  PetscFunctionBegin;
  if (cnorm2)
    for (PetscInt j = 0; j < p; j++) cnorm2[j] = 0;
  if (!r && !k) PetscFunctionReturn(0);
  PetscCall(PetscMalloc1((r + k) * p + 1, &c));
  PetscCall(KFMBasisCoefficients(rs, mb, p, w, mw, c));
  if (cnorm2)
    for (PetscInt j = 0; j < p; j++)
      for (PetscInt i = 0; i < r + k; i++) cnorm2[j] += PetscRealPart(c[i + j * (r + k)] * c[i + j * (r + k)]);
  PetscCall(KFMBasisSubtract(rs, mb, p, c, w, update ? mw : NULL));
  PetscCall(PetscFree(c));
  PetscFunctionReturn(0);
}

/* the M-norms sqrt(w_j^T M w_j) of p local columns from their products; each local sum in long double: the columns
   are normalized by these, and a plain running sum's rounding (~sqrt(n) eps) showed in |V^T M V - I| */
static PetscErrorCode KFMNorms(MPI_Comm comm, PetscInt nl, PetscInt p, const PetscScalar *w, const PetscScalar *mw, PetscReal nrm[])
{
  PetscFunctionBegin;
  for (PetscInt j = 0; j < p; j++) {
    long double d = 0;
    for (PetscInt i = 0; i < nl; i++) d += (long double)PetscRealPart(w[i + j * nl]) * (long double)PetscRealPart(mw[i + j * nl]);
    nrm[j] = (PetscReal)d;
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, nrm, (PetscMPIInt)p, MPIU_REAL, MPIU_SUM, comm));
  for (PetscInt j = 0; j < p; j++) nrm[j] = PetscSqrtReal(PetscMax(nrm[j], 0));
  PetscFunctionReturn(0);
}

/* The block w (nl x p) made M-orthogonal to the rigid modes and the basis, mw = M w with it; nrm0: each column's M-norm
   before. Both passes take their coefficients from the kept products, (M [Phi V])^T w, applied to the block as it is
   after the pass before: pass 2 sees pass 1's rounding in w itself, which is what makes it a refinement (DGKS: a Krylov
   block loses 35-99 % of its M-norm in pass 1, so the second pass is needed). No product of w with M until the end:
   mw is formed once from the final block, and the norm before follows by Pythagoras ([Phi V] being M-orthonormal).
   nrm: each column's M-norm after the passes.
   Each pass reads the basis twice (the kept products, then the columns). */
static PetscErrorCode KFMBasisPasses(const KFRigidSpace *rs, KFMBasis *mb, PetscInt p, PetscScalar *w, PetscScalar *mw, PetscReal nrm0[], PetscReal nrm[])
{
  const PetscInt nl   = mb->nl;
  MPI_Comm       comm = mb->comm;
  PetscReal     *cn1, *cn2;

  PetscFunctionBegin;
  PetscCall(PetscCalloc2(p, &cn1, p, &cn2));
  PetscCall(KFMBasisProjectOut(rs, mb, p, w, NULL, PETSC_FALSE, cn1)); /* pass 1 */
  PetscCall(KFMBasisProjectOut(rs, mb, p, w, NULL, PETSC_FALSE, cn2)); /* pass 2 */
  PetscCall(KFMProduct(rs->sys->Ms, nl, p, w, mw));
  PetscCall(KFMNorms(comm, nl, p, w, mw, nrm));
  for (PetscInt j = 0; j < p; j++) nrm0[j] = PetscSqrtReal(nrm[j] * nrm[j] + cn1[j] + cn2[j]);
  PetscCall(PetscFree2(cn1, cn2));
  PetscFunctionReturn(0);
}

/* Appends columns j0..j1-1 of W to the basis, each M-orthonormalized against the rigid modes and all columns before
   it; a column whose M-norm falls to tol times its M-norm before orthogonalization (or below) depends on the basis and
   is dropped (deflation). nrm0, when given, receives each column's M-norm before orthogonalization.

   Block classical Gram-Schmidt (KFMBasisPasses: twice; DESIGN.md:
   rigid content creeps back through rounding, so the rigid modes are projected out of every block together with the
   basis). Then the block's own columns, in order, by Gram-Schmidt on the products; a column that loses more than half
   of its norm there gets a fresh product and one more pass against everything (DGKS's criterion), so that the
   near-dependent inputs of a block stay as orthogonal as the rest. At most one block product with M per append,
   whatever the basis size, instead of several mat-vecs per column. */
static PetscErrorCode KFMBasisAppend(const KFRigidSpace *rs, KFMBasis *mb, Mat W, PetscInt j0, PetscInt j1, PetscReal tol, PetscInt *ndeflated, PetscReal nrm0out[])
{
  const PetscInt     p = j1 - j0, nl = mb->nl, k0 = mb->k;
  MPI_Comm           comm = mb->comm;
  Mat                Ms   = rs->sys->Ms;
  PetscScalar       *w, *mw;
  const PetscScalar *src;
  PetscInt           ld;
  PetscReal         *nrm0, *nrm;

  PetscFunctionBegin;
  if (p <= 0) PetscFunctionReturn(0);
  PetscCall(KFMBasisReserve(mb, k0 + p));
  if (p > mb->wcap) {
    PetscCall(PetscFree(mb->work));
    PetscCall(PetscMalloc1(2 * nl * p + 1, &mb->work));
    mb->wcap = p;
  }
  w  = mb->work;
  mw = mb->work + nl * p;
  PetscCall(PetscMalloc2(p, &nrm0, p, &nrm));
  PetscCall(MatDenseGetLDA(W, &ld));
  PetscCall(MatDenseGetArrayRead(W, &src));
  for (PetscInt j = 0; j < p; j++) PetscCall(PetscArraycpy(&w[j * nl], &src[(j0 + j) * ld], nl));
  PetscCall(MatDenseRestoreArrayRead(W, &src));
  PetscCall(KFMBasisPasses(rs, mb, p, w, mw, nrm0, nrm));
  if (nrm0out) PetscCall(PetscArraycpy(nrm0out, nrm0, p));
  for (PetscInt j = 0; j < p; j++) {
    PetscScalar *wj = &w[j * nl], *mwj = &mw[j * nl], *v;
    PetscReal    nb, na;

    if (!(nrm0[j] > 0)) { /* a zero column: nothing to add */
      (*ndeflated)++;
      continue;
    }
    nb = na = nrm[j]; /* as the passes left it: the block's own columns not yet taken out */
    if (mb->k > k0) { /* the block's columns kept so far: the trailing columns of the basis */
      const PetscInt kb = mb->k - k0;
      PetscReal     *c;
      const PetscScalar *vb;

      PetscCall(PetscMalloc1(kb, &c));
      PetscCall(KFMBasisGetColumnsRead(mb, &vb));
      PetscCall(KFArrayTransposeMultGather(comm, nl, kb, vb + k0 * nl, nl, 1, mwj, nl, c));
      PetscCall(KFArrayMultSmall(nl, kb, 1, vb + k0 * nl, nl, c, -1.0, wj, nl));
      PetscCall(KFMBasisRestoreColumnsRead(mb, &vb));
      PetscCall(KFArrayMultSmall(nl, kb, 1, mb->MV + k0 * nl, nl, c, -1.0, mwj, nl));
      PetscCall(PetscFree(c));
      PetscCall(KFMNorms(comm, nl, 1, wj, mwj, &na));
    }
    if (na > tol * nrm0[j] && na < PETSC_SQRT2 / 2 * nb) { /* cancellation within the block: refine with a fresh product */
      PetscCall(KFMProduct(Ms, nl, 1, wj, mwj));
      PetscCall(KFMBasisProjectOut(rs, mb, 1, wj, mwj, PETSC_TRUE, NULL));
      PetscCall(KFMNorms(comm, nl, 1, wj, mwj, &na));
    }
    { /* M singular (lumped masses without rotary inertia, masses offset from their nodes) and rounded as exported: once
         the M-positive directions the Krylov space reaches are spanned, what is left of a column lies in M's
         numerical null space, with a Rayleigh quotient w^T M w / w^T w at the rounding of M (1e-14 of the largest
         mass) but an M-norm well above tol nrm0; normalized, it would put that rounding into the basis. Such a column
         is dropped: w^T M w below KF_MASS_NULL_RTOL of sum_k w_k^2 ||M_b(k)||, each dof weighed by its own body's
         mass scale (the verification's null space of M too is relative to a direction's own masses, src/verify/
         eigen.c). Not against the whole system's ||M||: a light body (a rotor 1e-6 of the stator's mass, its masses
         2e-9 of the largest) has masses that are its own, and at 1e-8 of ||M|| every Krylov column after the static
         one was dropped, so even the richest candidate lacked the rotor's dynamics */
      PetscReal m2 = 0; /* sum_k w_k^2 ||M_b(k)|| */

      if (!rs->mnorm_only) {
        for (PetscInt i = 0; i < nl; i++) m2 += PetscRealPart(wj[i] * wj[i]) * rs->mscale[i];
        PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &m2, 1, MPIU_REAL, MPIU_SUM, comm));
      }
      if (!(na > tol * nrm0[j]) || (!rs->mnorm_only && !(na * na > KF_MASS_NULL_RTOL * m2))) {
        (*ndeflated)++;
        continue;
      }
    }
    PetscCall(KFMBasisGetColumns(mb, &v));
    for (PetscInt i = 0; i < nl; i++) {
      v[i + mb->k * nl]      = wj[i] / na;
      mb->MV[i + mb->k * nl] = mwj[i] / na;
    }
    PetscCall(KFMBasisRestoreColumns(mb, &v));
    mb->k++;
  }
  if (mb->V) PetscCall(BVSetActiveColumns(mb->V, 0, mb->k));
  PetscCall(PetscFree2(nrm0, nrm));
  PetscFunctionReturn(0);
}

/* What a chain (the input or the output Krylov process) needs of the basis for its next right-hand side, without an
   orthonormal basis of its own: U, an M-orthonormal basis of the span of the basis minus the chain's own space (span V
   = S_c + span U, M-orthogonally), of which only M U is kept (U itself is never needed). The chain's next block is its
   solve's block W made M-orthogonal to S_c and normalized; W lies in span [Phi V] once the basis holds it, and its part
   M-orthogonal to S_c and Phi is its part along [U, V_new] (V_new: the columns W brought into the basis). So the
   chain's block is [U, V_new] Q, Q from the small coordinates (M [U, V_new])^T W, and M times it is [M U, M V_new] Q: no
   pass over the chain's own columns (they were a second copy of most of the basis, orthonormalized twice per block).
   For the other chain, the columns a block brings join the complement. */
typedef struct {
  PetscScalar *MU, *spare; /* nl x m, leading dimension nl, room for cap columns; spare: as much room, the rotation's target */
  PetscInt     m, cap, nl;
} KFChainComplement;

/* room for m more columns (grown as needed: an input chain beside one output block keeps a few columns, not a copy of
   the basis) */
static PetscErrorCode KFChainComplementReserve(KFChainComplement *cc, PetscInt m)
{
  PetscFunctionBegin;
  if (cc->m + m <= cc->cap) PetscFunctionReturn(0);
  cc->cap = PetscMax(cc->m + m, 2 * cc->cap);
  PetscCall(PetscRealloc(sizeof(PetscScalar) * (cc->nl * cc->cap + 1), &cc->MU));
  PetscCall(PetscRealloc(sizeof(PetscScalar) * (cc->nl * cc->cap + 1), &cc->spare));
  PetscFunctionReturn(0);
}

/* the basis columns [k0, k) join the complement (another chain's block brought them: they are M-orthogonal to the
   whole basis before, so to this chain's space and its complement) */
static PetscErrorCode KFChainComplementAdd(KFChainComplement *cc, KFMBasis *mb, PetscInt k0)
{
  const PetscInt nl = cc->nl, p = mb->k - k0;

  PetscFunctionBegin;
  if (p <= 0) PetscFunctionReturn(0);
  PetscCall(KFChainComplementReserve(cc, p));
  PetscCall(PetscArraycpy(cc->MU + cc->m * nl, mb->MV + k0 * nl, p * nl));
  cc->m += p;
  PetscFunctionReturn(0);
}

/* out (nl x q, ld ldo) = [A, B] F, A the complement's first mu columns, B the basis columns [k0, k), F (mu + k - k0) x q
   (ld mu + k - k0); out is written, not read (no zero fill first) */
static PetscErrorCode KFChainCombine(PetscInt nl, PetscInt mu, const PetscScalar *a, PetscInt pb, const PetscScalar *b, PetscInt q, const PetscScalar *f, PetscScalar *out, PetscInt ldo)
{
  PetscFunctionBegin;
  if (mu) {
    PetscCall(KFArraySkinnyMultSet(nl, mu, a, nl, q, 1.0, f, mu + pb, out, ldo));
    PetscCall(KFArraySkinnyMultAdd(nl, pb, b, nl, q, 1.0, f + mu, mu + pb, out, ldo));
  } else PetscCall(KFArraySkinnyMultSet(nl, pb, b, nl, q, 1.0, f + mu, mu + pb, out, ldo));
  PetscFunctionReturn(0);
}

/* f (m x (m - q)): an orthonormal basis of the complement of the orthonormal columns q (m x q) in R^m (the trailing
   columns of the full orthogonal factor of q's Householder QR) */
static PetscErrorCode KFSmallComplement(PetscInt m, PetscInt nq, const PetscScalar *q, PetscScalar *f)
{
  PetscScalar *a, *tau, *work, wq;
  PetscBLASInt bm, bn, lwork = -1, info;

  PetscFunctionBegin;
  if (nq >= m) PetscFunctionReturn(0);
  PetscCall(PetscBLASIntCast(m, &bm));
  PetscCall(PetscBLASIntCast(nq, &bn));
  PetscCall(PetscCalloc2(m * m, &a, m + 1, &tau));
  PetscCall(PetscArraycpy(a, q, m * nq));
  PetscCallBLAS("LAPACKgeqrf", LAPACKgeqrf_(&bm, &bn, a, &bm, tau, &wq, &lwork, &info));
  PetscCall(PetscBLASIntCast((PetscInt)PetscRealPart(wq) + m * m, &lwork));
  PetscCall(PetscMalloc1(lwork, &work));
  PetscCallBLAS("LAPACKgeqrf", LAPACKgeqrf_(&bm, &bn, a, &bm, tau, work, &lwork, &info));
  PetscCheck(!info, PETSC_COMM_SELF, PETSC_ERR_LIB, "LAPACK geqrf failed (info %d) on the chain's coordinates", (int)info);
  PetscCallBLAS("LAPACKorgqr", LAPACKorgqr_(&bm, &bm, &bn, a, &bm, tau, work, &lwork, &info));
  PetscCheck(!info, PETSC_COMM_SELF, PETSC_ERR_LIB, "LAPACK orgqr failed (info %d) on the chain's coordinates", (int)info);
  PetscCall(PetscArraycpy(f, a + nq * m, m * (m - nq)));
  PetscCall(PetscFree(work));
  PetscCall(PetscFree2(a, tau));
  PetscFunctionReturn(0);
}

/* After the chain's block W (columns j0.. of p) joined the basis as its columns [k0, k), with nrm0 the M-norms of W's
   columns: *MY = M times the chain's next block (NULL when the chain's space is exhausted: every column depends on
   it), and the complement rotated to span [U, V_new] minus the chain's new block. Replicated work: (mu + k - k0)^2 p. */
static PetscErrorCode KFChainNext(KFChainComplement *cc, KFMBasis *mb, PetscInt k0, Mat W, PetscInt j0, PetscInt p, const PetscReal nrm0[], PetscReal tol, Mat *MY)
{
  const PetscInt     nl = cc->nl, mu = cc->m, pb = mb->k - k0, m = mu + pb;
  MPI_Comm           comm = mb->comm;
  const PetscScalar *w;
  PetscScalar       *g, *f, *my, *nmu;
  PetscInt           ld, nq, N;

  PetscFunctionBegin;
  *MY = NULL;
  PetscCall(PetscCalloc2(m * p + 1, &g, m * m + 1, &f));
  PetscCall(MatDenseGetLDA(W, &ld));
  PetscCall(MatDenseGetArrayRead(W, &w));
  PetscCall(KFArraySkinnyTransposeMult(nl, mu, cc->MU, nl, p, w + j0 * ld, ld, g, m));
  PetscCall(KFArraySkinnyTransposeMult(nl, pb, mb->MV + k0 * nl, nl, p, w + j0 * ld, ld, g + mu, m));
  PetscCall(MatDenseRestoreArrayRead(W, &w));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, g, (PetscMPIInt)(m * p), MPIU_SCALAR, MPIU_SUM, comm));
  /* M-orthonormal in these coordinates (those of M-orthonormal vectors), a column dropped as the chain's own
     Gram-Schmidt dropped it: its remainder at tol times its vector's M-norm before any orthogonalization */
  PetscCall(KFDenseOrthonormalizeSmall_Private(m, p, g, nrm0, tol, &nq));
  if (nq) {
    PetscCall(BVGetSizes(mb->V, NULL, &N, NULL));
    PetscCall(KFDenseCreateUninitialized(comm, nl, N, nq, MY));
    PetscCall(MatDenseGetLDA(*MY, &ld));
    PetscCall(MatDenseGetArrayWrite(*MY, &my));
    PetscCall(KFChainCombine(nl, mu, cc->MU, pb, mb->MV + k0 * nl, nq, g, my, ld));
    PetscCall(MatDenseRestoreArrayWrite(*MY, &my));
    PetscCall(KFSmallComplement(m, nq, g, f));
    PetscCall(KFChainComplementReserve(cc, PetscMax(m - nq - mu, 0)));
    PetscCall(KFChainCombine(nl, mu, cc->MU, pb, mb->MV + k0 * nl, m - nq, f, cc->spare, nl));
    nmu       = cc->MU; /* the rotated complement becomes the kept one: no copy back */
    cc->MU    = cc->spare;
    cc->spare = nmu;
    cc->m = m - nq;
  }
  PetscCall(PetscFree2(g, f));
  PetscFunctionReturn(0);
}

/* max |Phi^T M V| and max |V^T M V - I| of the finished basis: what the user is told about its numerical health; the
   Gram matrix V^T M V (k x k, allocated here) is also the reduced mass the projection needs. M V is the basis' kept
   products (mb->MV: each column's product with M formed fresh from the final block, then carried through the block's
   own Gram-Schmidt and the normalization, so within a few roundings of a fresh M V): forming it again was one more
   sparse product over the whole basis. */
static PetscErrorCode KFKrylovHealth(KFSystem sys, const KFMBasis *mb, PetscReal *rigid, PetscReal *orth, PetscReal **gram)
{
  BV       V = mb->V;
  PetscInt k = mb->k, N;
  Mat        A, MA;
  PetscInt   r;
  PetscReal *c, *g;

  PetscFunctionBegin;
  *rigid = *orth = 0;
  *gram          = NULL;
  if (!k) PetscFunctionReturn(0);
  PetscCall(MatGetSize(sys->Phi, NULL, &r));
  PetscCall(BVSetActiveColumns(V, 0, k));
  PetscCall(BVGetMat(V, &A));
  PetscCall(MatGetSize(A, &N, NULL));
  PetscCall(MatCreateDense(PetscObjectComm((PetscObject)A), mb->nl, PETSC_DECIDE, N, k, mb->MV, &MA));
  PetscCall(PetscMalloc1(PetscMax(r * k, 1), &c));
  PetscCall(PetscMalloc1(k * k, &g));
  if (r) PetscCall(KFMatTransposeMatMultGather(sys->Phi, MA, c));
  PetscCall(KFMatTransposeMatMultGather(A, MA, g));
  PetscCall(BVRestoreMat(V, &A));
  PetscCall(MatDestroy(&MA));
  for (PetscInt i = 0; i < r * k; i++) *rigid = PetscMax(*rigid, PetscAbsReal(c[i]));
  for (PetscInt j = 0; j < k; j++)
    for (PetscInt i = 0; i < k; i++) *orth = PetscMax(*orth, PetscAbsReal(g[i + j * k] - (i == j)));
  PetscCall(PetscInfo(V, "Krylov basis of %" PetscInt_FMT " columns: rigid content %.3e, orthogonality %.3e\n", k, (double)*rigid, (double)*orth));
  PetscCall(PetscFree(c));
  *gram = g;
  PetscFunctionReturn(0);
}

/* -kf_progress_min_dofs (also read before any work: KFReducerSetFromOptions) */
PETSC_INTERN PetscErrorCode KFKrylovProgressOptions(MPI_Comm comm, PetscInt *progress_min)
{
  PetscFunctionBegin;
  *progress_min = 50000;
  PetscOptionsBegin(comm, NULL, "kryflex Krylov basis", "KFKrylovBasis");
  PetscCall(KFOptionsSettingInt(PetscOptionsObject, "-kf_progress_min_dofs", *progress_min, progress_min, NULL));
  PetscOptionsEnd();
  PetscFunctionReturn(0);
}

PetscErrorCode KFKrylovInfoReset(KFKrylovInfo *info)
{
  PetscFunctionBegin;
  if (!info) PetscFunctionReturn(0);
  PetscCall(PetscFree(info->block_end));
  PetscCall(PetscFree(info->gram));
  PetscCall(PetscMemzero(info, sizeof(*info)));
  PetscFunctionReturn(0);
}

PetscErrorCode KFKrylovBasis(KFFlexSolver solver, PetscInt nin, PetscInt nout, PetscReal tol, BV *Vout, PetscInt *ndeflated)
{
  KFKrylovInfo info;

  PetscFunctionBegin;
  PetscCall(PetscMemzero(&info, sizeof(info)));
  PetscCall(KFKrylovBasisWithInfo(solver, nin, nout, tol, Vout, &info));
  if (ndeflated) *ndeflated = info.ndeflated;
  PetscCall(KFKrylovInfoReset(&info));
  PetscFunctionReturn(0);
}

/* Blocks alternate input, output, input, output ... while both chains have blocks left, then the rest: the first c
   blocks are then the basis of c moments for any c, so one basis serves a search over the number of moments. A chain
   whose block deflates away is exhausted (its Krylov space is spanned); its later blocks add nothing. */
PetscErrorCode KFKrylovBasisWithInfo(KFFlexSolver solver, PetscInt nin, PetscInt nout, PetscReal tol, BV *Vout, KFKrylovInfo *info)
{
  PetscFunctionBegin;
  PetscCall(KFKrylovBasisDamped_Private(solver, nin, nout, tol, NULL, Vout, info));
  PetscFunctionReturn(0);
}

/* whether chain c will make a next block after its next one in the basis, so needs its complement (the damped input
   chain makes its own) */
static PetscBool KFChainNeedsComplement(int c, const PetscInt appended[], const PetscInt want[], const PetscBool done[], const KFKrylovDamping *damp)
{
  return (PetscBool)(!done[c] && appended[c] + 1 < want[c] && !(damp && c == 0));
}

/* the same with the input chain of the damped second-order system (src/krylov/damped.c) when damp is not NULL */
PetscErrorCode KFKrylovBasisDamped_Private(KFFlexSolver solver, PetscInt nin, PetscInt nout, PetscReal tol, const KFKrylovDamping *damp, BV *Vout, KFKrylovInfo *info)
{
  KFDampedChain dch;
  KFSystem sys = KFFlexSolverSystem_Private(solver);
  KFScene  s   = sys->scene;
  PetscInt a = s->ninputs, t = s->noutputs, maxcols = a * nin + t * nout, k = 0, ndefl = 0, progress_min;
  PetscInt made[2] = {0, 0}, want[2] = {nin, nout}, nblocks = nin + nout;
  PetscBool done[2] = {PETSC_FALSE, PETSC_FALSE};
  PetscInt appended[2] = {0, 0}; /* per chain: its blocks in the basis */
  Mat      Prev[2] = {NULL, NULL}; /* per chain: M times its last orthonormalized block, the next right-hand side */
  BV       V;
  KFMBasis          basis;
  KFChainComplement cc[2];
  KFRigidSpace      rs;

  PetscFunctionBegin;
  PetscCheck(nin >= 1 && nout >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "the Krylov basis needs at least one input block (got %" PetscInt_FMT " input and %" PetscInt_FMT " output blocks)", nin, nout);
  PetscCheck(tol > 0 && tol < 1, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "deflation tolerance must lie in (0, 1); got %g", (double)tol);
  PetscCall(KFKrylovProgressOptions(s->comm, &progress_min));
  PetscCall(KFFlexSolverSetUp(solver));
  PetscCall(PetscMemzero(info, sizeof(*info)));
  PetscCall(PetscMalloc1(nblocks, &info->block_end));
  PetscCall(BVCreate(s->comm, &V));
  PetscCall(BVSetSizes(V, s->nsys_local, s->nsys, PetscMax(maxcols, 1)));
  PetscCall(BVSetMatrix(V, sys->Ms, PETSC_FALSE));
  PetscCall(BVSetFromOptions(V));
  PetscCall(KFMBasisCreate(V, &basis));
  PetscCall(PetscMemzero(cc, sizeof(cc)));
  cc[0].nl = cc[1].nl = basis.nl;
  PetscCall(KFRigidSpaceOpen(sys, PETSC_TRUE, &rs));
  if (damp) PetscCall(KFDampedChainCreate_Private(solver, damp, a * nin, &dch));
  for (PetscInt blk = 0; blk < nblocks; blk++) {
    /* input on even blocks while outputs remain, otherwise whichever chain has blocks left */
    int       src[2], nsrc = 0;
    Mat       Bs[2] = {NULL, NULL}, B, W;
    PetscInt  off[3] = {0, 0, 0}, p;
    PetscBool fresh[2] = {PETSC_FALSE, PETSC_FALSE};

    src[0] = (blk % 2 == 1 && made[1] < want[1]) || made[0] >= want[0] ? 1 : 0;
    made[src[0]]++;
    if (!done[src[0]]) nsrc = 1;
    if (nsrc && damp && !src[0]) { /* the damped input chain: its blocks' u halves join the basis (own solves) */
      Mat      U;
      PetscInt k0d = k, pu;

      nsrc = 0;
      PetscCall(KFDampedChainNext_Private(solver, &dch, sys->G, tol, &U));
      if (U) {
        PetscCall(MatGetSize(U, NULL, &pu));
        PetscCall(KFMBasisAppend(&rs, &basis, U, 0, pu, tol, &ndefl, NULL));
        if (KFChainNeedsComplement(1, appended, want, done, damp)) PetscCall(KFChainComplementAdd(&cc[1], &basis, k0d));
        k = basis.k;
        PetscCall(MatDestroy(&U));
      } else done[0] = PETSC_TRUE;
      if (s->nsys >= progress_min) PetscCall(KFProgress(s->comm, "Krylov damped input block %" PetscInt_FMT "/%" PetscInt_FMT ": %" PetscInt_FMT " columns kept (basis %" PetscInt_FMT ")", made[0], want[0], k - k0d, k));
      PetscCall(KFInterruptCheck(s->comm));
    }
    /* the next block, when it belongs to the other chain, does not depend on this one: both go through the factor
       in one block solve (one MatMatSolve of a + t columns instead of two); a damped input block has its own solves */
    if (nsrc && blk + 1 < nblocks) {
      int next = ((blk + 1) % 2 == 1 && made[1] < want[1]) || made[0] >= want[0] ? 1 : 0;
      if (next != src[0] && !done[next] && !(damp && !next)) {
        src[1] = next;
        made[next]++;
        nsrc = 2;
      }
    }
    if (nsrc) {
      for (int q = 0; q < nsrc; q++) {
        const int c = src[q];
        if (!Prev[c]) Bs[q] = c ? sys->Ht : sys->G;
        else { /* M times the chain's last block: kept from its orthonormalization, no product here */
          Bs[q]    = Prev[c];
          Prev[c]  = NULL;
          fresh[q] = PETSC_TRUE;
        }
        PetscCall(MatGetSize(Bs[q], NULL, &p));
        off[q + 1] = off[q] + p;
      }
      if (nsrc == 1) B = Bs[0];
      else PetscCall(KFDenseHStack(Bs[0], Bs[1], &B));
      { /* W: written whole by the solve */
        PetscInt nlw, Nw, pw;

        PetscCall(MatGetLocalSize(B, &nlw, NULL));
        PetscCall(MatGetSize(B, &Nw, &pw));
        PetscCall(KFDenseCreateUninitialized(s->comm, nlw, Nw, pw, &W));
      }
      PetscCall(KFFlexSolverApply(solver, B, W));
      if (nsrc == 2) PetscCall(MatDestroy(&B));
      for (int q = 0; q < nsrc; q++)
        if (fresh[q]) PetscCall(MatDestroy(&Bs[q]));
      for (int q = 0; q < nsrc; q++) {
        const int      source = src[q];
        const PetscInt b      = blk + q, k0 = k;

        PetscCall(PetscLogEventBegin(KF_EVENT_ORTHO, 0, 0, 0, 0));
        /* each chain is an Arnoldi process of its own (its next block starts from its own orthonormalized block, not
           from one the other chain has been taken out of, which would leave its Krylov space); the basis collects
           both, and each chain's next block follows from the basis (KFChainNext) */
        {
          const PetscBool next = KFChainNeedsComplement(source, appended, want, done, damp);
          PetscReal      *nrm0;

          PetscCall(PetscMalloc1(off[q + 1] - off[q], &nrm0));
          PetscCall(KFMBasisAppend(&rs, &basis, W, off[q], off[q + 1], tol, &ndefl, nrm0));
          if (KFChainNeedsComplement(1 - source, appended, want, done, damp)) PetscCall(KFChainComplementAdd(&cc[1 - source], &basis, k0));
          if (next) {
            PetscCall(KFChainNext(&cc[source], &basis, k0, W, off[q], off[q + 1] - off[q], nrm0, tol, &Prev[source]));
            if (!Prev[source]) done[source] = PETSC_TRUE; /* the block deflated away: this chain's space is exhausted */
          }
          appended[source]++;
          k = basis.k;
          PetscCall(PetscFree(nrm0));
        }
        PetscCall(PetscLogEventEnd(KF_EVENT_ORTHO, 0, 0, 0, 0));
        if (s->nsys >= progress_min) PetscCall(KFProgress(s->comm, "Krylov %s block %" PetscInt_FMT "/%" PetscInt_FMT ": %" PetscInt_FMT " of %" PetscInt_FMT " columns kept (basis %" PetscInt_FMT ")", source ? "output" : "input", made[source], want[source], k - k0, off[q + 1] - off[q], k));
        info->block_end[b] = k;
      }
      PetscCall(MatDestroy(&W));
      PetscCall(KFInterruptCheck(s->comm)); /* a command's SIGINT/SIGTERM: every rank stops after the same block */
    } else info->block_end[blk] = k;
    if (nsrc == 2) blk++; /* the pair is done */
    info->nblocks = blk + 1;
    if (done[0] && (done[1] || !nout)) { /* both chains exhausted: later blocks would add nothing */
      for (PetscInt b = blk + 1; b < nblocks; b++) info->block_end[b] = k;
      info->nblocks = nblocks;
      break;
    }
  }
  PetscCall(MatDestroy(&Prev[0]));
  PetscCall(MatDestroy(&Prev[1]));
  for (int c = 0; c < 2; c++) PetscCall(PetscFree(cc[c].MU));
  for (int c = 0; c < 2; c++) PetscCall(PetscFree(cc[c].spare));
  if (damp) PetscCall(KFDampedChainDestroy_Private(&dch));
  PetscCall(BVSetActiveColumns(V, 0, k));
  PetscCall(KFKrylovHealth(sys, &basis, &info->rigid_content, &info->orthogonality, &info->gram));
  PetscCall(KFMBasisDestroy(&basis));
  PetscCall(KFRigidSpaceClose(&rs));
  PetscCall(BVSetActiveColumns(V, 0, k));
  info->ndeflated = ndefl;
  *Vout           = V;
  PetscFunctionReturn(0);
}

/* One M-orthonormal basis of the leading m[i] columns of each of n bases of one system (the blocks at zero first, then
   those of expansion points inside the band, src/reducer/shifts.c): appended in order with the rigid modes projected
   out again, columns that depend on those before deflated. info: its health and Gram matrix (block_end NULL). */
PETSC_INTERN PetscErrorCode KFKrylovBasisMerge_Private(KFSystem sys, PetscInt n, BV Vs[], const PetscInt m[], PetscReal tol, BV *Vout, KFKrylovInfo *info)
{
  KFScene      s     = sys->scene;
  PetscInt     total = 0, ndefl = 0;
  BV           V;
  KFMBasis     basis;
  KFRigidSpace rs;

  PetscFunctionBegin;
  for (PetscInt i = 0; i < n; i++) total += m[i];
  PetscCall(PetscMemzero(info, sizeof(*info)));
  PetscCall(BVCreate(s->comm, &V));
  PetscCall(BVSetSizes(V, s->nsys_local, s->nsys, PetscMax(total, 1)));
  PetscCall(BVSetMatrix(V, sys->Ms, PETSC_FALSE));
  PetscCall(BVSetFromOptions(V));
  PetscCall(KFMBasisCreate(V, &basis));
  PetscCall(KFRigidSpaceOpen(sys, PETSC_TRUE, &rs));
  for (PetscInt i = 0; i < n; i++) {
    Mat      A;
    PetscInt l0, k0;

    if (!m[i]) continue;
    PetscCall(BVGetActiveColumns(Vs[i], &l0, &k0));
    PetscCall(BVSetActiveColumns(Vs[i], 0, m[i]));
    PetscCall(BVGetMat(Vs[i], &A));
    PetscCall(KFMBasisAppend(&rs, &basis, A, 0, m[i], tol, &ndefl, NULL));
    PetscCall(BVRestoreMat(Vs[i], &A));
    PetscCall(BVSetActiveColumns(Vs[i], l0, k0));
  }
  PetscCall(BVSetActiveColumns(V, 0, basis.k));
  PetscCall(KFKrylovHealth(sys, &basis, &info->rigid_content, &info->orthogonality, &info->gram));
  PetscCall(KFMBasisDestroy(&basis));
  PetscCall(KFRigidSpaceClose(&rs));
  PetscCall(BVSetActiveColumns(V, 0, basis.k));
  info->ndeflated = ndefl;
  *Vout           = V;
  PetscFunctionReturn(0);
}

/* The M-orthonormal basis above (rigid modes projected out, two Gram-Schmidt passes, deflation) for another user of
   the same numerics: the verification's block eigensolve (src/verify/block_eigen.c) grows its Krylov space with it.
   Its deflation compares M-norms only (a column keeping at most tol of its M-norm depends on the basis), without the
   null-space test: that test weighs a column's length, and a column of a Krylov space of K+ M is long where M is
   null for a reason, not by rounding: the massless dofs (rotations of a lumped-mass model) follow the rest by static
   condensation (K x = M v has no load there). On the lumped frame it dropped most columns of the later blocks, their
   M-norms 6e-4 to 0.2 of what they had before the passes, so the space stopped before the modes converged; on the
   stick aircraft (M singular beyond its zero diagonal, rounded as exported) it dropped columns whose length lay in
   M's numerical null space but which still held 2e-5 to 1e-3 of their M-norm, and the frequencies of the space it
   took as exhausted were 5e-5 off. The eigensolve reads its basis only through M V (the projection, the Ritz
   residuals in the M-norm, the vectors returned purified, K+ M V y), so what such a column carries where M is null
   or at its rounding weighs nothing there; the reduction projects K on its basis, so it keeps the test. */
struct _n_KFMOrthBasis {
  KFMBasis     mb; /* its own arrays, grown with the columns (KFMBasisCreateGrowing) */
  KFRigidSpace rs;
};

PETSC_INTERN PetscErrorCode KFMOrthBasisCreate(KFSystem sys, PetscInt maxcols, KFMOrthBasis *ob)
{
  KFScene s = sys->scene;

  PetscFunctionBegin;
  PetscCall(PetscNew(ob));
  PetscCall(KFMBasisCreateGrowing(s->comm, s->nsys_local, PetscMax(maxcols, 1), &(*ob)->mb));
  PetscCall(KFRigidSpaceOpen(sys, PETSC_FALSE, &(*ob)->rs));
  PetscFunctionReturn(0);
}

/* the columns of W appended (KFMBasisAppend); ndeflated counts the columns dropped. At most maxcols in all (the rest
   are not appended, nor counted): deflating on M-norms alone, a basis of a model whose mass is singular can take
   columns of M's numerical null space, and so could reach the system's size. The arrays grow with the columns
   (KFMOrthBasisReserve before, or else exactly what the append needs), so the memory follows the columns made, not
   maxcols. */
PETSC_INTERN PetscErrorCode KFMOrthBasisAppend(KFMOrthBasis ob, Mat W, PetscReal tol, PetscInt *ndeflated)
{
  PetscInt p;

  PetscFunctionBegin;
  PetscCall(MatGetSize(W, NULL, &p));
  PetscCall(KFMBasisAppend(&ob->rs, &ob->mb, W, 0, PetscMin(p, ob->mb.mmax - ob->mb.k), tol, ndeflated, NULL));
  PetscFunctionReturn(0);
}

/* room for ncols columns in all (at most the basis's maxcols), the growth's policy the caller's */
PETSC_INTERN PetscErrorCode KFMOrthBasisReserve(KFMOrthBasis ob, PetscInt ncols)
{
  PetscFunctionBegin;
  PetscCall(KFMBasisReserve(&ob->mb, ncols));
  PetscFunctionReturn(0);
}

/* the columns so far (k), local rows (nl, the leading dimension), V and M V: valid until the next append */
PETSC_INTERN PetscErrorCode KFMOrthBasisGetArrays(KFMOrthBasis ob, PetscInt *k, PetscInt *nl, const PetscScalar **V, const PetscScalar **MV)
{
  PetscFunctionBegin;
  *k  = ob->mb.k;
  *nl = ob->mb.nl;
  *V  = ob->mb.Vc;
  *MV = ob->mb.MV;
  PetscFunctionReturn(0);
}

PETSC_INTERN PetscErrorCode KFMOrthBasisDestroy(KFMOrthBasis *ob)
{
  PetscFunctionBegin;
  if (!*ob) PetscFunctionReturn(0);
  PetscCall(KFMBasisDestroy(&(*ob)->mb));
  PetscCall(KFRigidSpaceClose(&(*ob)->rs));
  PetscCall(PetscFree(*ob));
  PetscFunctionReturn(0);
}
