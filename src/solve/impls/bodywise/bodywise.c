/* The body-wise (substructured) flexible solve: K_S = sum_b P_b^T K_b P_b solved from one factorization per body and a
   small dense interface problem, so that a multi-angle reduction factors the bodies once, not the system per angle.

   Each body's dofs split into its interface dofs Gamma_b (the 6 dofs of every interface node) and its interior I_b.
   The system's interface unknowns x_G are the kept interface dofs of all bodies and the joints' free rotations; a
   body's interface reads u_Gamma = T_b(alpha) x_G (the rows of P_b, src/assemble/body_map.c), its interior reads the
   system's interior dofs as themselves. With Psi_b = K_II^-1 K_IG (zero on Gamma) the Schur complement
   S_b = K_GG - K_GI K_II^-1 K_IG does not depend on the angles, and at any angle
       S(alpha) x_G = f_G - sum_b T_b^T Psi_b^T f_b,I,      x_b,I = K_II^-1 f_b,I - Psi_b T_b x_G,
   with S(alpha) = sum_b T_b^T S_b T_b (dense, 6 x interface nodes + revolute joints). The rigid and mechanism modes
   of K_S live in x_G when every body has an interface node, so the held dofs of the monolithic solve (or a pivoted
   choice among the interface unknowns) are held in S: the result is the same K+ B.

   The body factors (K_b with its Gamma rows and columns replaced by a scaled identity: the interior factor) are kept
   on the KFSystem, which lives for the whole reduction while the solvers are made per angle. */
#include <kryflex/flexsolverimpl.h>
#include <petscblaslapack.h>
#include <petscsf.h>

/* angle-independent, per system: one factorization per body */
struct _n_KFBodyFactors {
  PetscReal   shift; /* K_b + shift M_b is what was factored */
  PetscInt    nb;
  PetscBool   factored; /* Kb, F, Psi, S made (ng and gif are made first: the interface needs only them) */
  PetscInt   *ng;     /* |Gamma_b| = 6 x the body's distinct interface nodes */
  PetscInt  **gif;    /* per body and Gamma node: an interface at that node (its expressions are the node's) */
  Mat        *Kb, *F; /* the interior-held body stiffness and its MUMPS factor */
  Mat        *Psi;    /* n_b x |Gamma_b|: K_II^-1 K_IG on the interior rows, 0 on Gamma */
  PetscReal **S;      /* |Gamma_b|^2, replicated: the body's Schur complement on its interface */
  /* bodies spread over the ranks (-kf_bodywise_spread): body b's interior is factored by rank owner[b] alone
     (sequential MUMPS on its gathered K_b), so the ranks factor and solve different bodies at the same time instead of
     every body on all ranks. Kb, F and Psi are then sequential on the owner and NULL elsewhere; sf[b] moves a dense
     block's body rows between the body's row layout (leaves) and the owner's whole body (roots). */
  PetscBool    spread;
  PetscMPIInt *owner;
  PetscSF     *sf;
  PetscReal    estimate_mb; /* MUMPS' estimate of the largest body factorization's memory on a rank, MB */
  PetscInt     nneg;        /* shift < 0: the interior factors' negative pivots, all bodies (KFBodywiseOpInertia) */
  /* another factor set's interiors taken over (KFBodyFactorsCreateShiftedReusing): body b's MUMPS analysis of a matrix
     with prev_K[b]'s pattern, reused where K_b + shift M_b's pattern agrees; NULL where none */
  Mat         *prev_K, *prev_F;
};

/* per solver (one angle): the interface problem, and the options that choose and spread the body-wise solve */
typedef struct _n_KFBodywiseOp {
  PetscBool   asked_auto; /* type auto: body-wise only where it pays (KFBodywiseWanted), else monolithic */
  PetscInt    min_dofs;   /* -kf_bodywise_min_dofs */
  PetscBool   spread;     /* -kf_bodywise_spread */
  PetscInt    nb;
  PetscInt    nG, *Gidx; /* interface unknowns: their system dofs, sorted, replicated */
  PetscReal **T;         /* per body |Gamma_b| x nG (column-major): u_Gamma = T_b x_G */
  PetscReal  *S;         /* nG x nG: Cholesky factor of S(alpha) with the held unknowns replaced by identity rows */
  PetscInt    nheldG, *heldG;
  PetscBLASInt *ipiv;    /* a shift below zero (K_b - w^2 M_b): S(alpha) indefinite, its LDL^T's pivots (LAPACK sytrf) */
} KFFlexSolver_Bodywise;
typedef KFFlexSolver_Bodywise *KFBodywise;

PetscErrorCode KFBodyFactorsDestroy(KFBodyFactors *bf)
{
  PetscFunctionBegin;
  if (!*bf) PetscFunctionReturn(0);
  for (PetscInt b = 0; b < (*bf)->nb; b++) {
    PetscCall(MatDestroy(&(*bf)->Kb[b]));
    PetscCall(MatDestroy(&(*bf)->F[b]));
    PetscCall(MatDestroy(&(*bf)->Psi[b]));
    PetscCall(PetscFree((*bf)->S[b]));
    PetscCall(PetscFree((*bf)->gif[b]));
    if ((*bf)->sf) PetscCall(PetscSFDestroy(&(*bf)->sf[b]));
  }
  if ((*bf)->prev_F)
    for (PetscInt b = 0; b < (*bf)->nb; b++) {
      PetscCall(MatDestroy(&(*bf)->prev_K[b]));
      PetscCall(MatDestroy(&(*bf)->prev_F[b]));
    }
  PetscCall(PetscFree2((*bf)->prev_K, (*bf)->prev_F));
  PetscCall(PetscFree2((*bf)->owner, (*bf)->sf));
  PetscCall(PetscFree6((*bf)->ng, (*bf)->gif, (*bf)->Kb, (*bf)->F, (*bf)->Psi, (*bf)->S));
  PetscCall(PetscFree(*bf));
  PetscFunctionReturn(0);
}

/* body-local Gamma dof k (0..ng-1) -> the body's global dof */
static PetscInt KFGammaDof(const KFBodyData *B, const PetscInt gif[], PetscInt k)
{
  return B->iface[gif[k / 6]].dof0 + k % 6;
}

/* Zero the rows of a body-layout dense X at the body's Gamma dofs (the rank's own rows). */
static PetscErrorCode KFZeroGammaRows(const KFBodyData *B, PetscInt ng, const PetscInt gif[], Mat X)
{
  PetscInt     rstart, rend, p, lda;
  PetscScalar *x;

  PetscFunctionBegin;
  PetscCall(MatGetOwnershipRange(X, &rstart, &rend));
  PetscCall(MatGetSize(X, NULL, &p));
  PetscCall(MatDenseGetLDA(X, &lda));
  PetscCall(MatDenseGetArray(X, &x));
  for (PetscInt k = 0; k < ng; k++) {
    PetscInt dof = KFGammaDof(B, gif, k);
    if (dof >= rstart && dof < rend)
      for (PetscInt j = 0; j < p; j++) x[(dof - rstart) + j * lda] = 0;
  }
  PetscCall(MatDenseRestoreArray(X, &x));
  PetscFunctionReturn(0);
}

/* One body's Gamma: its distinct interface nodes (two interface names may share a node) */
static PetscErrorCode KFBodyGammaNodes(KFScene s, PetscInt b, KFBodyFactors bf)
{
  KFBodyData *B  = &s->bodies[b];
  PetscInt    ng = 0;

  PetscFunctionBegin;
  PetscCall(PetscMalloc1(PetscMax(B->ninterfaces, 1), &bf->gif[b]));
  for (PetscInt i = 0; i < B->ninterfaces; i++) {
    PetscBool seen = PETSC_FALSE;
    for (PetscInt k = 0; k < ng; k++) seen = (PetscBool)(seen || B->iface[bf->gif[b][k]].node == B->iface[i].node);
    if (!seen) bf->gif[b][ng++] = i;
  }
  ng *= 6;
  bf->ng[b] = ng;
  PetscCheck(ng > 0, s->comm, PETSC_ERR_PLIB, "body %s has no interface node", B->name);
  PetscFunctionReturn(0);
}

#define KF_TINY_BODY 100 /* dofs */

/* whether A and B (same type and layout) have the same nonzero pattern on every rank of their communicator */
static PetscErrorCode KFSamePattern(Mat A, Mat B, PetscBool *same)
{
  PetscInt  rs, re, rsb, reb;
  PetscBool mine, typed;

  PetscFunctionBegin;
  PetscCall(PetscObjectTypeCompare((PetscObject)A, ((PetscObject)B)->type_name, &typed));
  PetscCall(MatGetOwnershipRange(A, &rs, &re));
  PetscCall(MatGetOwnershipRange(B, &rsb, &reb));
  mine = (PetscBool)(typed && rs == rsb && re == reb);
  for (PetscInt i = rs; i < re && mine; i++) {
    const PetscInt *ca, *cb;
    PetscInt        na, nb;

    PetscCall(MatGetRow(A, i, &na, &ca, NULL));
    PetscCall(MatGetRow(B, i, &nb, &cb, NULL));
    mine = (PetscBool)(na == nb);
    for (PetscInt k = 0; k < na && mine; k++) mine = (PetscBool)(ca[k] == cb[k]);
    PetscCall(MatRestoreRow(B, i, &nb, &cb, NULL));
    PetscCall(MatRestoreRow(A, i, &na, &ca, NULL));
  }
  PetscCall(MPIU_Allreduce(&mine, same, 1, MPIU_BOOL, MPI_LAND, PetscObjectComm((PetscObject)A)));
  PetscFunctionReturn(0);
}

/* One body: the interior factor, Psi_b and S_b, from the body's K and M on their communicator (the scene's, or the
   owner's PETSC_COMM_SELF when the bodies are spread over the ranks). The pivots' counts are returned for the caller
   to check collectively. */
static PetscErrorCode KFBodyFactorSetUp(KFScene s, const char prefix[], PetscInt b, Mat K, Mat M, PetscReal shift, KFBodyFactors bf, PetscInt *nnull, PetscInt *nneg)
{
  KFBodyData *B = &s->bodies[b];
  PetscInt    ng = bf->ng[b], rstart, rend, nloc = 0, *loc;
  PetscReal   estimate_mb;
  Vec         d;
  PetscReal   dsum;
  Mat         E, KE, KPhi;
  MPI_Comm    comm = PetscObjectComm((PetscObject)K);

  PetscFunctionBegin;
  PetscCall(MatDuplicate(K, MAT_COPY_VALUES, &bf->Kb[b]));
  if (shift != 0) PetscCall(MatAXPY(bf->Kb[b], shift, M, DIFFERENT_NONZERO_PATTERN));
  if (shift < 0) PetscCall(MatSetOption(bf->Kb[b], MAT_SPD, PETSC_FALSE)); /* K_b - w^2 M_b: MUMPS' LDL^T with pivoting */
  PetscCall(MatCreateVecs(bf->Kb[b], &d, NULL));
  PetscCall(MatGetDiagonal(bf->Kb[b], d));
  PetscCall(VecNorm(d, NORM_1, &dsum));
  PetscCall(VecDestroy(&d));
  PetscCall(MatGetOwnershipRange(bf->Kb[b], &rstart, &rend));
  PetscCall(PetscMalloc1(ng, &loc));
  for (PetscInt k = 0; k < ng; k++) {
    PetscInt dof = KFGammaDof(B, bf->gif[b], k);
    if (dof >= rstart && dof < rend) loc[nloc++] = dof;
  }
  /* K with its Gamma rows and columns zeroed: the columns go to K_IG below, from the unmodified K */
  if (shift != 0) PetscCall(MatDuplicate(bf->Kb[b], MAT_COPY_VALUES, &KPhi)); /* kept as the body's shifted K for S_b */
  else { /* unshifted: K itself, which the products below only read (no copy of the body's stiffness) */
    PetscCall(PetscObjectReference((PetscObject)K));
    KPhi = K;
  }
  PetscCall(MatZeroRowsColumns(bf->Kb[b], nloc, loc, dsum / B->n, NULL, NULL));
  PetscCall(PetscFree(loc));
  /* the user's ordering, BLR, OOC and memory check apply, except on a tiny body: PORD stops the process on a graph of a
     few vertices ("no valid number of stages in multisector", Galileo's 12-dof stator), so MUMPS' defaults there */
  {
    PetscBool same = PETSC_FALSE;

    if (bf->prev_F && bf->prev_F[b]) PetscCall(KFSamePattern(bf->Kb[b], bf->prev_K[b], &same));
    if (same) { /* the ordering and symbolic factorization made for that pattern: the numerical phase alone */
      bf->F[b]         = bf->prev_F[b];
      bf->prev_F[b]    = NULL;
      PetscCall(KFFactorMumpsNumericAgain(bf->Kb[b], &bf->F[b], nnull, nneg));
    } else {
      PetscCall(KFFactorMumps(bf->Kb[b], prefix, 0.0, (PetscBool)(B->n >= KF_TINY_BODY), &bf->F[b], nnull, nneg, &estimate_mb));
      bf->estimate_mb = PetscMax(bf->estimate_mb, estimate_mb);
    }
    if (bf->prev_F) {
      PetscCall(MatDestroy(&bf->prev_F[b]));
      PetscCall(MatDestroy(&bf->prev_K[b]));
    }
  }
  if (shift < 0) bf->nneg += *nneg;             /* above the body's first fixed-interface frequency: negative pivots, */
  if (shift < 0) *nneg = 0;                     /* counted (Sylvester), not an error */
  if (*nnull || *nneg) PetscFunctionReturn(0); /* Psi and S would be meaningless: the caller stops */

  /* E: unit columns at Gamma; Psi = K_II^-1 K_IG; Phi_c = E - Psi (constraint modes); S_b = Phi_c^T K Phi_c */
  PetscCall(KFDenseCreate(comm, rend - rstart, B->n, ng, &E));
  for (PetscInt k = 0; k < ng; k++) {
    PetscInt dof = KFGammaDof(B, bf->gif[b], k);
    if (dof >= rstart && dof < rend) PetscCall(MatSetValue(E, dof, k, 1.0, INSERT_VALUES));
  }
  PetscCall(MatAssemblyBegin(E, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(E, MAT_FINAL_ASSEMBLY));
  PetscCall(MatMatMult(KPhi, E, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &KE));
  PetscCall(KFZeroGammaRows(B, ng, bf->gif[b], KE));
  PetscCall(MatDuplicate(E, MAT_DO_NOT_COPY_VALUES, &bf->Psi[b]));
  PetscCall(KFMumpsMatSolve(bf->F[b], KE, bf->Psi[b]));
  PetscCall(KFZeroGammaRows(B, ng, bf->gif[b], bf->Psi[b])); /* exact zeros: the identity rows give f_G / d = 0 */
  PetscCall(MatDestroy(&KE));
  PetscCall(MatAXPY(E, -1.0, bf->Psi[b], SAME_NONZERO_PATTERN)); /* E <- Phi_c */
  PetscCall(KFMatMultExtended(KPhi, E, &KE));
  PetscCall(PetscMalloc1(ng * ng, &bf->S[b]));
  PetscCall(KFMatTransposeMatMultGather(E, KE, bf->S[b]));
  for (PetscInt i = 0; i < ng; i++) /* symmetric by construction: remove the rounding */
    for (PetscInt j = 0; j < i; j++) bf->S[b][i + j * ng] = bf->S[b][j + i * ng] = 0.5 * (bf->S[b][i + j * ng] + bf->S[b][j + i * ng]);
  PetscCall(MatDestroy(&KE));
  PetscCall(MatDestroy(&E));
  PetscCall(MatDestroy(&KPhi));
  PetscFunctionReturn(0);
}

/* -kf_bodywise_min_dofs and -kf_bodywise_spread (also read and checked before any work: KFFlexSolverCheckOptions) */
static PetscErrorCode KFFlexSolverSetFromOptions_Bodywise(KFFlexSolver solver, PetscOptionItems *PetscOptionsObject)
{
  KFBodywise bw = (KFBodywise)solver->data;

  PetscFunctionBegin;
  PetscOptionsHeadBegin(PetscOptionsObject, "kryflex flexible solve: monolithic or body-wise");
  PetscCall(KFOptionsSettingInt(PetscOptionsObject, "-kf_bodywise_min_dofs", bw->min_dofs, &bw->min_dofs, NULL));
  PetscCall(KFOptionsSettingBool(PetscOptionsObject, "-kf_bodywise_spread", bw->spread, &bw->spread, NULL));
  PetscOptionsHeadEnd();
  PetscCheck(bw->min_dofs >= 0, PetscObjectComm((PetscObject)solver), PETSC_ERR_ARG_OUTOFRANGE, "-kf_bodywise_min_dofs must be >= 0; got %" PetscInt_FMT, bw->min_dofs);
  PetscFunctionReturn(0);
}

/* Which rank factors which body (-kf_bodywise_spread, on by default): with at least as many bodies as ranks, each
   body goes whole to one rank, the bodies in decreasing order of cost each to the least loaded rank (LPT). The cost
   of a body's factorization is taken as n_b^2 (the flops of a nested-dissection factorization of a 3-D solid mesh
   grow as n^2): what matters is the order of the bodies and the balance of the loads. More ranks than bodies, or one
   rank: every body on all ranks (distributed MUMPS per body), as before. */
static PetscErrorCode KFBodywiseAssign(KFScene s, PetscBool spread, KFBodyFactors bf)
{
  PetscMPIInt      size;
  PetscReal       *cost, *load;
  PetscInt        *order;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_size(s->comm, &size));
  bf->spread = (PetscBool)(spread && size > 1 && size <= s->nb);
  if (!bf->spread) PetscFunctionReturn(0);
  PetscCall(PetscCalloc2(s->nb, &bf->owner, s->nb, &bf->sf));
  PetscCall(PetscMalloc3(s->nb, &cost, s->nb, &order, size, &load));
  for (PetscInt b = 0; b < s->nb; b++) {
    cost[b]  = -(PetscReal)s->bodies[b].n * (PetscReal)s->bodies[b].n; /* sorted ascending: the largest first */
    order[b] = b;
  }
  for (PetscMPIInt r = 0; r < size; r++) load[r] = 0;
  PetscCall(PetscSortRealWithArrayInt(s->nb, cost, order));
  for (PetscInt k = 0; k < s->nb; k++) {
    PetscMPIInt least = 0;
    for (PetscMPIInt r = 1; r < size; r++)
      if (load[r] < load[least]) least = r;
    bf->owner[order[k]] = least;
    load[least] -= cost[k];
  }
  PetscCall(PetscFree3(cost, order, load));
  PetscFunctionReturn(0);
}

/* Body b's star forest: leaf i (the body's row rstart + i on this rank) <- root rstart + i on the owner */
static PetscErrorCode KFBodySFCreate(KFScene s, PetscInt b, KFBodyFactors bf)
{
  KFBodyData  *B = &s->bodies[b];
  PetscInt     nl = B->rend - B->rstart;
  PetscMPIInt  rank;
  PetscSFNode *remote;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  PetscCall(PetscMalloc1(nl, &remote));
  for (PetscInt i = 0; i < nl; i++) {
    remote[i].rank  = bf->owner[b];
    remote[i].index = B->rstart + i;
  }
  PetscCall(PetscSFCreate(s->comm, &bf->sf[b]));
  PetscCall(PetscSFSetGraph(bf->sf[b], rank == bf->owner[b] ? B->n : 0, nl, NULL, PETSC_COPY_VALUES, remote, PETSC_OWN_POINTER));
  PetscCall(PetscSFSetUp(bf->sf[b]));
  PetscFunctionReturn(0);
}

/* Dense block rows between body b's row layout (D, on the scene's ranks) and its owner's sequential copy (Q, n_b x p,
   NULL on the other ranks): to_owner gathers D into Q, else Q is spread into D. Column by column through sf[b]. */
static PetscErrorCode KFBodyMoveRows(KFBodyFactors bf, PetscInt b, Mat D, Mat Q, PetscBool to_owner)
{
  PetscInt     p, ldd, ldq = 0;
  PetscScalar *d, *q = NULL;

  PetscFunctionBegin;
  PetscCall(MatGetSize(D, NULL, &p));
  PetscCall(MatDenseGetLDA(D, &ldd));
  PetscCall(MatDenseGetArray(D, &d));
  if (Q) {
    PetscCall(MatDenseGetLDA(Q, &ldq));
    PetscCall(MatDenseGetArray(Q, &q));
  }
  for (PetscInt j = 0; j < p; j++) {
    if (to_owner) {
      PetscCall(PetscSFReduceBegin(bf->sf[b], MPIU_SCALAR, d + j * ldd, q ? q + j * ldq : NULL, MPI_REPLACE));
      PetscCall(PetscSFReduceEnd(bf->sf[b], MPIU_SCALAR, d + j * ldd, q ? q + j * ldq : NULL, MPI_REPLACE));
    } else {
      PetscCall(PetscSFBcastBegin(bf->sf[b], MPIU_SCALAR, q ? q + j * ldq : NULL, d + j * ldd, MPI_REPLACE));
      PetscCall(PetscSFBcastEnd(bf->sf[b], MPIU_SCALAR, q ? q + j * ldq : NULL, d + j * ldd, MPI_REPLACE));
    }
  }
  if (Q) PetscCall(MatDenseRestoreArray(Q, &q));
  PetscCall(MatDenseRestoreArray(D, &d));
  PetscFunctionReturn(0);
}

/* Stops every rank when a body's factorization found negative or null pivots (the counts of the rank(s) that factored it) */
static PetscErrorCode KFBodyPivotsCheck(KFScene s, PetscInt b, PetscInt nnull, PetscInt nneg)
{
  PetscInt in[2] = {nnull, nneg}, out[2];

  PetscFunctionBegin;
  PetscCall(MPIU_Allreduce(in, out, 2, MPIU_INT, MPI_MAX, s->comm));
  PetscCheck(out[1] == 0, s->comm, PETSC_ERR_ARG_WRONG, "body %s: its stiffness with the interface nodes held is indefinite (MUMPS found %" PetscInt_FMT " negative pivots): its K is not positive semi-definite (check its export and units)", s->bodies[b].name, out[1]);
  PetscCheck(out[0] == 0, s->comm, PETSC_ERR_ARG_WRONG, "body %s: its stiffness with the interface nodes held still has %" PetscInt_FMT " zero-energy mode(s): a mechanism no joint declares, in a part of the body no interface node holds (an unconnected dof, a body in pieces). Fix the model, or declare the joint", s->bodies[b].name, out[0]);
  PetscFunctionReturn(0);
}

/* An error on one rank alone (a spread body's factorization on its owner: MUMPS, the memory check) would leave the
   other ranks waiting: the owner keeps the first message, and KFBodyErrorsCheck raises it on every rank. */
typedef struct {
  PetscErrorCode code;
  char           msg[1024];
} KFBodyError;

static PetscErrorCode KFBodyErrorHandler(MPI_Comm comm, int line, const char *fun, const char *file, PetscErrorCode n, PetscErrorType p, const char *mess, void *ctx)
{
  KFBodyError *e = (KFBodyError *)ctx;

  if (!e->code && mess) {
    e->code = n;
    PetscStrncpy(e->msg, mess, sizeof(e->msg));
  }
  return n;
}

static PetscErrorCode KFBodyErrorsCheck(KFScene s, KFBodyError *e)
{
  PetscMPIInt rank, first, mine;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  mine = e->code ? rank : PETSC_MPI_INT_MAX;
  PetscCall(MPIU_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, s->comm));
  if (first == PETSC_MPI_INT_MAX) PetscFunctionReturn(0);
  PetscCallMPI(MPI_Bcast(e, (PetscMPIInt)sizeof(*e), MPI_BYTE, first, s->comm));
  SETERRQ(s->comm, e->code, "%s (on rank %d, which factors the body alone: -kf_bodywise_spread%s)", e->msg, (int)first, e->code == PETSC_ERR_MEM ? "; the ranks of a node factor their bodies at the same time, each checked against its share of the node's memory unless -kf_memory_limit_mb is given" : "");
}

/* Spread bodies: each gathered onto its owner and factored there, the ranks at once, then S_b broadcast from the owner */
static PetscErrorCode KFBodyFactorsSetUpSpread(KFScene s, const char prefix[], PetscReal shift, KFBodyFactors bf)
{
  PetscMPIInt rank;
  PetscInt   *nnull, *nneg;
  Mat        *Kq, *Mq;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  PetscCall(PetscCalloc4(s->nb, &nnull, s->nb, &nneg, s->nb, &Kq, s->nb, &Mq));
  for (PetscInt b = 0; b < s->nb; b++) {
    KFBodyData *B    = &s->bodies[b];
    PetscBool   mine = (PetscBool)(rank == bf->owner[b]);
    IS          is;
    Mat        *sub;

    if (shift < 0) PetscCall(KFProgress(s->comm, "  body %s's K - w^2 M at %.4g Hz (%" PetscInt_FMT " dofs) factored on rank %d alone, for every configuration", B->name, (double)(PetscSqrtReal(-shift) / (2 * PETSC_PI)), B->n, (int)bf->owner[b]));
    else PetscCall(KFProgress(s->comm, "body-wise solve: body %s's interior (%" PetscInt_FMT " dofs) factored on rank %d alone (sequential MUMPS LDL^T), once for all configurations", B->name, B->n, (int)bf->owner[b]));
    PetscCall(ISCreateStride(PETSC_COMM_SELF, mine ? B->n : 0, 0, 1, &is));
    PetscCall(MatCreateSubMatrices(B->K, 1, &is, &is, MAT_INITIAL_MATRIX, &sub)); /* collective: the owner gets all of K_b */
    if (mine) PetscCall(PetscObjectReference((PetscObject)sub[0]));
    if (mine) Kq[b] = sub[0];
    PetscCall(MatDestroySubMatrices(1, &sub));
    if (shift != 0) {
      PetscCall(MatCreateSubMatrices(B->M, 1, &is, &is, MAT_INITIAL_MATRIX, &sub));
      if (mine) PetscCall(PetscObjectReference((PetscObject)sub[0]));
      if (mine) Mq[b] = sub[0];
      PetscCall(MatDestroySubMatrices(1, &sub));
    }
    PetscCall(ISDestroy(&is));
    PetscCall(KFBodySFCreate(s, b, bf));
  }
  /* the ranks factor their own bodies at the same time: no communication until every rank is done */
  {
    KFBodyError    e = {0, ""};
    PetscErrorCode ierr = 0;
    PetscBool      has_limit, share = PETSC_FALSE;
    MPI_Comm       node;
    PetscMPIInt    nn;

    /* the memory check of a factorization weighs MUMPS' estimate on its communicator's ranks against the node's
       memory: a spread body's factorization is alone on its communicator while the node's other ranks factor
       theirs, so unless -kf_memory_limit_mb says otherwise each rank is checked against its share of the node
       (MemAvailable / ranks on the node; -kf_ooc auto then puts a body that exceeds it out of core) */
    char limit_name[256];

    PetscCall(PetscSNPrintf(limit_name, sizeof(limit_name), "-%skf_memory_limit_mb", prefix ? prefix : ""));
    PetscCall(PetscOptionsHasName(NULL, NULL, limit_name, &has_limit));
    PetscCallMPI(MPI_Comm_split_type(s->comm, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node));
    PetscCallMPI(MPI_Comm_size(node, &nn));
    if (!has_limit && nn > 1) {
      PetscReal avail = KFNodeMemoryAvailableMB(), least;
      char      val[32];

      PetscCall(MPIU_Allreduce(&avail, &least, 1, MPIU_REAL, MPIU_MIN, node));
      if (least > 0) {
        PetscCall(PetscSNPrintf(val, sizeof(val), "%.17g", (double)(least / nn)));
        PetscCall(PetscOptionsSetValue(NULL, limit_name, val));
        share = PETSC_TRUE;
      }
    }
    PetscCallMPI(MPI_Comm_free(&node));
    PetscCall(PetscPushErrorHandler(KFBodyErrorHandler, &e));
    for (PetscInt b = 0; b < s->nb && !ierr; b++)
      if (Kq[b]) ierr = KFBodyFactorSetUp(s, prefix, b, Kq[b], Mq[b], shift, bf, &nnull[b], &nneg[b]);
    PetscCall(PetscPopErrorHandler());
    if (share) PetscCall(PetscOptionsClearValue(NULL, limit_name));
    if (ierr && !e.code) e.code = ierr;
    for (PetscInt b = 0; b < s->nb; b++) {
      PetscCall(MatDestroy(&Kq[b]));
      PetscCall(MatDestroy(&Mq[b]));
    }
    PetscCall(KFBodyErrorsCheck(s, &e));
  }
  for (PetscInt b = 0; b < s->nb; b++) {
    PetscCall(KFBodyPivotsCheck(s, b, nnull[b], nneg[b]));
    if (rank != bf->owner[b]) PetscCall(PetscMalloc1(bf->ng[b] * bf->ng[b], &bf->S[b]));
    PetscCallMPI(MPI_Bcast(bf->S[b], (PetscMPIInt)(bf->ng[b] * bf->ng[b]), MPIU_REAL, bf->owner[b], s->comm));
  }
  PetscCall(PetscFree4(nnull, nneg, Kq, Mq));
  PetscFunctionReturn(0);
}

/* All bodies' factors: spread (KFBodyFactorsSetUpSpread), else each body on all ranks in turn. */
static PetscErrorCode KFBodyFactorsSetUpAll(KFScene s, const char prefix[], PetscReal shift, KFBodyFactors bf)
{
  PetscFunctionBegin;
  if (bf->spread) {
    PetscCall(KFBodyFactorsSetUpSpread(s, prefix, shift, bf));
    PetscFunctionReturn(0);
  }
  for (PetscInt b = 0; b < s->nb; b++) {
    PetscInt nnull = 0, nneg = 0;
    if (shift < 0) PetscCall(KFProgress(s->comm, "  body %s's K - w^2 M at %.4g Hz (%" PetscInt_FMT " dofs, interior MUMPS LDL^T), for every configuration", s->bodies[b].name, (double)(PetscSqrtReal(-shift) / (2 * PETSC_PI)), s->bodies[b].n));
    else PetscCall(KFProgress(s->comm, "body-wise solve: factorization of body %s's interior (%" PetscInt_FMT " dofs, MUMPS LDL^T), once for all configurations", s->bodies[b].name, s->bodies[b].n));
    PetscCall(KFBodyFactorSetUp(s, prefix, b, s->bodies[b].K, s->bodies[b].M, shift, bf, &nnull, &nneg));
    PetscCall(KFBodyPivotsCheck(s, b, nnull, nneg));
  }
  PetscFunctionReturn(0);
}

/* -kf_flex_solver: which implementation this solver uses.
   auto (the default): body-wise when the system will be solved at two or more configurations
   (KFSystemSetConfigurationCount: the reducer's visits), the scene has two or more bodies, a revolute joint, an
   interface node on every body, a small dense interface problem, at least -kf_bodywise_min_dofs system dofs (default
   20,000: from there on the monolithic solve has no null-pivot cross-check either), interface responses Psi_b that
   take no more memory than the bodies' stiffness matrices, and when the monolithic solve's held dofs are interface
   unknowns; monolithic otherwise. The choice depends on the scene and the configuration count only, not on which
   configurations a system visited before. Measured (README, "Body-wise flexible solve"): the body factorizations cost
   about one factorization of K_S, so at one configuration the monolithic solve is as fast or faster (with nested
   dissection 13.0 s against 14.8 s at 202k dofs), and from the second configuration on every monolithic
   factorization is saved (6 configurations: 1.27-2.68x at 57k-540k dofs). On more ranks than bodies (or
   -kf_bodywise_spread false) auto keeps the monolithic solve. */
#define KF_AUTO_MAX_INTERFACE 3000
static PetscErrorCode KFBodywiseWanted(KFFlexSolver solver, PetscBool *use)
{
  KFBodywise       bw  = (KFBodywise)solver->data;
  KFSystem         sys = solver->sys;
  KFScene          s   = sys->scene;
  PetscBool        all_iface = PETSC_TRUE, bcs = PETSC_FALSE;
  PetscInt         nG = s->nrevolute;
  PetscReal        psi_entries = 0, k_entries = 0;

  PetscFunctionBegin;
  for (PetscInt b = 0; b < s->nb; b++) {
    all_iface = (PetscBool)(all_iface && s->bodies[b].ninterfaces > 0);
    nG += 6 * s->bodies[b].ninterfaces; /* at most: shared nodes and tied dofs count once */
    /* the body interiors are factored as the bodies come, with no boundary condition removed: clamped dofs (and joints
       to ground, which clamp) are system dofs no longer, so a scene with them takes the monolithic solve */
    bcs = (PetscBool)(bcs || s->bodies[b].nclamp > 0);
    if (bw->asked_auto) {
      MatInfo info;

      /* Psi_b = K_II^-1 K_IGamma is dense: n_b x |Gamma_b| entries (at most 6 per interface node) */
      PetscCall(MatGetInfo(s->bodies[b].K, MAT_GLOBAL_SUM, &info));
      k_entries += info.nz_used;
      psi_entries += (PetscReal)s->bodies[b].n * 6 * s->bodies[b].ninterfaces;
    }
  }
  *use = PETSC_FALSE;
  if (!bw->asked_auto) {
    if (s->nb > 1 && all_iface && !bcs) *use = PETSC_TRUE;
    else PetscCall(KFProgress(s->comm, "-kf_flex_solver bodywise: %s; the monolithic solve is used", s->nb < 2 ? "a single body has no interface problem" : (bcs ? "the body-wise solve does not take clamped dofs or joints to ground yet" : "a body without interface node")));
  } else {
    PetscMPIInt size;

    /* on several ranks only when the bodies can be spread: every body distributed over all ranks paid a distributed
       MUMPS solve per body per block and came out even with the monolithic solve (README, run 4) */
    PetscCallMPI(MPI_Comm_size(s->comm, &size));
    *use = (PetscBool)(s->nb > 1 && all_iface && !bcs && nG <= KF_AUTO_MAX_INTERFACE && s->nrevolute > 0 && sys->nconfig > 1 && s->nsys >= bw->min_dofs && psi_entries <= k_entries && (size == 1 || (bw->spread && size <= s->nb)));
  }
  PetscFunctionReturn(0);
}

/* the interface unknowns and T_b at the system's angles */
static PetscErrorCode KFBodywiseInterface(KFSystem sys, KFBodyFactors bf, KFBodywise bw)
{
  KFScene   s = sys->scene;
  KFExpr  **E;
  PetscInt *owned, *idx, nmax = 0, cnt = 0;

  PetscFunctionBegin;
  for (PetscInt b = 0; b < s->nb; b++) nmax += bf->ng[b];
  PetscCall(PetscMalloc1(nmax + s->nj + 1, &bw->Gidx));
  PetscCall(PetscMalloc2(nmax + 1, &owned, nmax + 1, &idx));
  /* the kept Gamma dofs: the rank that owns one knows its system index */
  for (PetscInt b = 0; b < s->nb; b++) {
    KFBodyData *B = &s->bodies[b];
    for (PetscInt k = 0; k < bf->ng[b]; k++) {
      PetscInt dof = KFGammaDof(B, bf->gif[b], k);
      owned[k]     = (dof >= B->rstart && dof < B->rend) ? B->sysidx[dof - B->rstart] : -1;
    }
    PetscCall(MPIU_Allreduce(owned, idx, (PetscMPIInt)bf->ng[b], MPIU_INT, MPI_MAX, s->comm));
    for (PetscInt k = 0; k < bf->ng[b]; k++)
      if (idx[k] >= 0) bw->Gidx[cnt++] = idx[k];
  }
  PetscCall(PetscFree2(owned, idx));
  for (PetscInt j = 0; j < s->nj; j++)
    if (s->joints[j].beta >= 0) bw->Gidx[cnt++] = s->joints[j].beta;
  PetscCall(PetscSortRemoveDupsInt(&cnt, bw->Gidx));
  bw->nG = cnt;

  /* T_b: the interface expressions (replicated) in the interface unknowns */
  PetscCall(KFSystemInterfaceExprs(sys, &E));
  PetscCall(PetscCalloc1(s->nb, &bw->T));
  for (PetscInt b = 0; b < s->nb; b++) {
    PetscInt ng = bf->ng[b];
    PetscCall(PetscCalloc1(ng * bw->nG, &bw->T[b]));
    for (PetscInt k = 0; k < ng; k++) {
      const KFExpr *x = &E[b][6 * bf->gif[b][k / 6] + k % 6];
      for (PetscInt t = 0; t < x->n; t++) {
        PetscInt g;
        PetscCall(PetscFindInt(x->idx[t], bw->nG, bw->Gidx, &g));
        PetscCheck(g >= 0, s->comm, PETSC_ERR_PLIB, "body %s: an interface dof reads system dof %" PetscInt_FMT ", which is not an interface unknown", s->bodies[b].name, x->idx[t]);
        bw->T[b][k + g * ng] += x->c[t];
      }
    }
  }
  PetscCall(KFSystemInterfaceExprsDestroy(sys, &E));
  PetscFunctionReturn(0);
}

/* Rows Gidx of a system-layout dense X (nG x p, column-major), replicated */
static PetscErrorCode KFGatherRows(Mat X, PetscInt n, const PetscInt rows[], PetscReal out[])
{
  PetscInt           rstart, rend, p, lda;
  const PetscScalar *x;
  PetscReal         *buf;

  PetscFunctionBegin;
  PetscCall(MatGetOwnershipRange(X, &rstart, &rend));
  PetscCall(MatGetSize(X, NULL, &p));
  PetscCall(MatDenseGetLDA(X, &lda));
  PetscCall(PetscCalloc1(n * p + 1, &buf));
  PetscCall(MatDenseGetArrayRead(X, &x));
  for (PetscInt k = 0; k < n; k++)
    if (rows[k] >= rstart && rows[k] < rend)
      for (PetscInt j = 0; j < p; j++) buf[k + j * n] = PetscRealPart(x[(rows[k] - rstart) + j * lda]);
  PetscCall(MatDenseRestoreArrayRead(X, &x));
  PetscCall(MPIU_Allreduce(buf, out, (PetscMPIInt)(n * p), MPIU_REAL, MPIU_SUM, PetscObjectComm((PetscObject)X)));
  PetscCall(PetscFree(buf));
  PetscFunctionReturn(0);
}

/* C (m x p) = op(A) B for small column-major arrays, op(A) = A (m x k) or A^T (A k x m) */
static PetscErrorCode KFSmallGemm(const char *ta, PetscInt m, PetscInt p, PetscInt k, PetscReal alpha, const PetscReal A[], const PetscReal B[], PetscReal beta, PetscReal C[])
{
  PetscBLASInt bm, bp, bk, lda;

  PetscFunctionBegin;
  if (m == 0 || p == 0) PetscFunctionReturn(0);
  PetscCall(PetscBLASIntCast(m, &bm));
  PetscCall(PetscBLASIntCast(p, &bp));
  PetscCall(PetscBLASIntCast(k, &bk));
  lda = (ta[0] == 'N') ? bm : bk;
  if (k == 0) {
    for (PetscInt i = 0; i < m * p; i++) C[i] *= beta;
    PetscFunctionReturn(0);
  }
  PetscCallBLAS("BLASgemm", BLASgemm_(ta, "N", &bm, &bp, &bk, &alpha, A, &lda, B, &bk, &beta, C, &bm));
  PetscFunctionReturn(0);
}

/* the interface problem of the configuration set up (the options are kept: the solver may be set up again) */
static PetscErrorCode KFBodywiseReset(KFBodywise bw)
{
  PetscFunctionBegin;
  for (PetscInt b = 0; b < bw->nb && bw->T; b++) PetscCall(PetscFree(bw->T[b]));
  PetscCall(PetscFree(bw->T));
  PetscCall(PetscFree(bw->Gidx));
  PetscCall(PetscFree(bw->S));
  PetscCall(PetscFree(bw->heldG));
  PetscCall(PetscFree(bw->ipiv));
  bw->nb = bw->nG = bw->nheldG = 0;
  PetscFunctionReturn(0);
}

static PetscErrorCode KFFlexSolverDestroy_Bodywise(KFFlexSolver solver)
{
  PetscFunctionBegin;
  PetscCall(KFBodywiseReset((KFBodywise)solver->data));
  PetscCall(PetscFree(solver->data));
  PetscCall(PetscObjectComposeFunction((PetscObject)solver, "KFFlexSolverBodywiseSetSpread_C", NULL));
  PetscCall(PetscObjectComposeFunction((PetscObject)solver, "KFFlexSolverBodywiseSetMinDofs_C", NULL));
  PetscFunctionReturn(0);
}

/* The held dofs: the monolithic solve's when they are all interface unknowns (its clamp is: a root interface node and
   the joints' rotations), else a pivoted-QR choice among the interface unknowns, where the rigid modes live. */
static PetscErrorCode KFBodywiseHeld(KFFlexSolver solver, KFBodywise bw, PetscBool auto_only, PetscBool *same)
{
  KFSystem  sys = solver->sys;
  KFScene   s   = sys->scene;
  PetscBool inG = PETSC_TRUE;

  PetscFunctionBegin;
  PetscCall(KFSelectHeldDofs(sys, ((PetscObject)solver)->prefix, &solver->nheld, &solver->held));
  for (PetscInt k = 0; k < solver->nheld; k++) {
    PetscInt g;
    PetscCall(PetscFindInt(solver->held[k], bw->nG, bw->Gidx, &g));
    inG = (PetscBool)(inG && g >= 0);
  }
  *same = inG;
  if (!inG && auto_only) PetscFunctionReturn(0); /* auto: the monolithic solve, with these held dofs */
  if (!inG) {
    PetscInt     r, nl, rstart, lda;
    PetscReal   *phi;
    PetscScalar *a;
    Mat          PhiG;
    PetscMPIInt  rank;
    PetscCall(PetscFree(solver->held));
    PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
    PetscCall(MatGetSize(sys->Phi, NULL, &r));
    PetscCall(PetscMalloc1(bw->nG * r + 1, &phi));
    PetscCall(KFGatherRows(sys->Phi, bw->nG, bw->Gidx, phi));
    nl = rank == 0 ? bw->nG : 0; /* the small matrix on the first rank: the choice is the same everywhere */
    PetscCall(KFDenseCreate(s->comm, nl, bw->nG, r, &PhiG));
    PetscCall(MatGetOwnershipRange(PhiG, &rstart, NULL));
    PetscCall(MatDenseGetLDA(PhiG, &lda));
    PetscCall(MatDenseGetArray(PhiG, &a));
    for (PetscInt i = 0; i < nl; i++)
      for (PetscInt j = 0; j < r; j++) a[i + j * lda] = phi[i + j * bw->nG];
    PetscCall(MatDenseRestoreArray(PhiG, &a));
    PetscCall(KFSelectPivotedDofs(PhiG, &solver->nheld, &solver->held));
    PetscCall(MatDestroy(&PhiG));
    PetscCall(PetscFree(phi));
    for (PetscInt k = 0; k < solver->nheld; k++) solver->held[k] = bw->Gidx[solver->held[k]];
  }
  bw->nheldG = solver->nheld;
  PetscCall(PetscMalloc1(solver->nheld + 1, &bw->heldG));
  for (PetscInt k = 0; k < solver->nheld; k++) PetscCall(PetscFindInt(solver->held[k], bw->nG, bw->Gidx, &bw->heldG[k]));
  PetscFunctionReturn(0);
}

/* S(alpha) = sum_b T_b^T S_b T_b, held unknowns -> scaled identity, Cholesky-factored (replicated, LAPACK); below a
   zero shift (K_b - w^2 M_b) S(alpha) is indefinite: LDL^T with Bunch-Kaufman pivoting instead */
static PetscErrorCode KFBodywiseFactorInterface(KFScene s, KFBodyFactors bf, KFBodywise bw)
{
  PetscInt     nG = bw->nG;
  PetscReal   *ST, dsum = 0;
  PetscBLASInt bn, info;

  PetscFunctionBegin;
  PetscCall(PetscCalloc1(nG * nG + 1, &bw->S));
  for (PetscInt b = 0; b < s->nb; b++) {
    PetscInt ng = bf->ng[b];
    PetscCall(PetscMalloc1(ng * nG + 1, &ST));
    PetscCall(KFSmallGemm("N", ng, nG, ng, 1.0, bf->S[b], bw->T[b], 0.0, ST));   /* S_b T_b */
    PetscCall(KFSmallGemm("T", nG, nG, ng, 1.0, bw->T[b], ST, 1.0, bw->S));      /* += T_b^T S_b T_b */
    PetscCall(PetscFree(ST));
  }
  for (PetscInt i = 0; i < nG; i++) dsum += PetscAbsReal(bw->S[i + i * nG]);
  for (PetscInt k = 0; k < bw->nheldG; k++) {
    PetscInt h = bw->heldG[k];
    for (PetscInt i = 0; i < nG; i++) bw->S[h + i * nG] = bw->S[i + h * nG] = 0;
    bw->S[h + h * nG] = dsum / nG; /* as the monolithic solve: a unit-scaled identity on the held rows */
  }
  PetscCall(PetscBLASIntCast(nG, &bn));
  if (bf->shift < 0) {
    PetscBLASInt lwork = PetscMax(64 * bn, 1);
    PetscReal   *work;

    PetscCall(PetscMalloc1(nG + 1, &bw->ipiv));
    PetscCall(PetscMalloc1(lwork, &work));
    if (nG > 0) PetscCallBLAS("LAPACKsytrf", LAPACKsytrf_("L", &bn, bw->S, &bn, bw->ipiv, work, &lwork, &info));
    else info = 0;
    PetscCall(PetscFree(work));
    PetscCheck(info == 0, s->comm, PETSC_ERR_MAT_LU_ZRPVT, "the body-wise interface problem of K - w^2 M at %g Hz is singular (LAPACK sytrf info %d): w^2 is an eigenvalue of the jointed structure; solve at other frequencies, or use -kf_verify_check_bodywise false for the reference check", (double)(PetscSqrtReal(-bf->shift) / (2 * PETSC_PI)), (int)info);
    PetscFunctionReturn(0);
  }
  if (nG > 0) PetscCallBLAS("LAPACKpotrf", LAPACKpotrf_("L", &bn, bw->S, &bn, &info));
  else info = 0;
  PetscCheck(info == 0, s->comm, PETSC_ERR_ARG_WRONG, "the body-wise interface problem (%" PetscInt_FMT " unknowns) is not positive definite with the %" PetscInt_FMT " held dofs (LAPACK potrf info %d): the structure has a zero-energy mode beyond the rigid-body and mechanism modes the joints declare (a missing tie, an undeclared mechanism). Fix the model, or declare the joint", nG, bw->nheldG, (int)info);
  PetscFunctionReturn(0);
}

/* The system's body factors, made once for all its configurations (and again for another shift): here only their
   interface nodes, the factorizations follow in KFFlexSolverSetUp_Bodywise */
static PetscErrorCode KFBodyFactorsGet(KFSystem sys, PetscReal shift, KFBodyFactors *bfo)
{
  KFScene       s = sys->scene;
  KFBodyFactors bf;

  PetscFunctionBegin;
  if (sys->bodyf && sys->bodyf->shift != shift) PetscCall(KFBodyFactorsDestroy(&sys->bodyf));
  if (!sys->bodyf) {
    PetscCall(PetscNew(&bf));
    bf->shift = shift;
    bf->nb    = s->nb;
    PetscCall(PetscCalloc6(s->nb, &bf->ng, s->nb, &bf->gif, s->nb, &bf->Kb, s->nb, &bf->F, s->nb, &bf->Psi, s->nb, &bf->S));
    sys->bodyf = bf;
    for (PetscInt b = 0; b < s->nb; b++) PetscCall(KFBodyGammaNodes(s, b, bf));
  }
  *bfo = sys->bodyf;
  PetscFunctionReturn(0);
}

/* Body-wise where it applies (auto: where it pays, KFBodywiseWanted), else handed to the monolithic implementation
   (solver->handoff) */
static PetscErrorCode KFFlexSolverSetUp_Bodywise(KFFlexSolver solver)
{
  KFBodywise       bw  = (KFBodywise)solver->data;
  KFSystem         sys = solver->sys;
  KFScene          s   = sys->scene;
  KFBodyFactors    bf  = NULL;
  PetscBool        use = PETSC_FALSE, same = PETSC_TRUE, asked_auto = bw->asked_auto;
  PetscInt         nfact = 0;
  PetscLogDouble   t0, t1;

  PetscFunctionBegin;
  PetscCall(KFBodywiseWanted(solver, &use));
  if (!use) { /* the monolithic solve instead */
    solver->handoff = KFFLEXSOLVERMONOLITHIC;
    PetscFunctionReturn(0);
  }
  PetscCall(KFSystemComputeRigidModes(sys));
  PetscCall(PetscLogEventBegin(KF_EVENT_FACTOR, 0, 0, 0, 0));
  PetscCall(PetscTime(&t0));
  PetscCall(KFBodyFactorsGet(sys, solver->shift, &bf));
  PetscCall(KFBodywiseReset(bw));
  bw->nb = s->nb;
  PetscCall(KFBodywiseInterface(sys, bf, bw));
  if (solver->shift == 0) PetscCall(KFBodywiseHeld(solver, bw, asked_auto, &same));
  if (!same && asked_auto) {
    /* the monolithic held dofs are off the interface (a clamp elsewhere): auto keeps the monolithic solve */
    PetscCall(PetscFree(solver->held));
    solver->nheld = 0;
    PetscCall(PetscLogEventEnd(KF_EVENT_FACTOR, 0, 0, 0, 0));
    solver->handoff = KFFLEXSOLVERMONOLITHIC;
    PetscFunctionReturn(0);
  }
  if (asked_auto) PetscCall(PetscObjectChangeTypeName((PetscObject)solver, KFFLEXSOLVERBODYWISE));
  if (!bf->factored) {
    if (asked_auto) PetscCall(KFProgress(s->comm, "flexible solve: body-wise, the bodies factored once for all configurations (-kf_flex_solver auto; monolithic or bodywise to choose)"));
    PetscCall(KFBodywiseAssign(s, bw->spread, bf));
    PetscCall(KFBodyFactorsSetUpAll(s, ((PetscObject)solver)->prefix, solver->shift, bf));
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &bf->estimate_mb, 1, MPIU_REAL, MPIU_MAX, s->comm));
    bf->factored = PETSC_TRUE;
    nfact        = s->nb;
    sys->nfactor += s->nb;
  }
  PetscCall(KFBodywiseFactorInterface(s, bf, bw));
  PetscCall(KFProgress(s->comm, "body-wise solve of the %" PetscInt_FMT "-dof system: dense interface problem of %" PetscInt_FMT " unknowns (%" PetscInt_FMT " held), %" PetscInt_FMT " body factorizations now, %" PetscInt_FMT " sparse factorizations for this system so far", s->nsys, bw->nG, solver->nheld, nfact, sys->nfactor));
  solver->null_pivots = solver->negative_pivots = 0; /* both checked body by body and by the interface Cholesky */
  /* the timing table's factorization: the body factorizations (with Psi_b and S_b) where this solver made them, and
     the interface problem's */
  PetscCall(PetscTime(&t1));
  solver->perf.factor_seconds += t1 - t0;
  solver->perf.memory_estimate_mb = bf->estimate_mb;
  PetscCall(PetscLogEventEnd(KF_EVENT_FACTOR, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

/* Copies between a system-layout dense S and a body-layout dense B (same columns) on the body's kept dofs: a kept
   dof's system row is on the rank that owns its body row (KFSystemBuildBodyMaps preallocates P_b so). */
static PetscErrorCode KFCopyKept(KFScene s, const KFBodyData *B, Mat Sm, Mat Bm, PetscBool to_body)
{
  PetscInt     p, lds, ldb, nl = B->rend - B->rstart;
  PetscScalar *a, *b;

  PetscFunctionBegin;
  PetscCall(MatGetSize(Sm, NULL, &p));
  PetscCall(MatDenseGetLDA(Sm, &lds));
  PetscCall(MatDenseGetLDA(Bm, &ldb));
  PetscCall(MatDenseGetArray(Sm, &a));
  PetscCall(MatDenseGetArray(Bm, &b));
  for (PetscInt i = 0; i < nl; i++) {
    PetscInt r = B->sysidx[i] - s->sys_rstart;
    if (B->sysidx[i] < 0) continue;
    PetscCheck(r >= 0 && r < s->nsys_local, PETSC_COMM_SELF, PETSC_ERR_PLIB, "body %s: kept dof %" PetscInt_FMT " is not on its body row's rank", B->name, B->sysidx[i]);
    if (to_body)
      for (PetscInt j = 0; j < p; j++) b[i + j * ldb] = a[r + j * lds];
    else
      for (PetscInt j = 0; j < p; j++) a[r + j * lds] = b[i + j * ldb];
  }
  PetscCall(MatDenseRestoreArray(Sm, &a));
  PetscCall(MatDenseRestoreArray(Bm, &b));
  PetscFunctionReturn(0);
}

/* x_b,I = y_b - Psi_b T_b x_G, scattered to the system's interior rows; x_G (g, nG x p) set directly. Y[b]: body b's
   K_II^-1 f_b,I (on its owner alone when spread), destroyed here. */
static PetscErrorCode KFBodywiseBackSubstitute(KFSystem sys, KFBodyFactors bf, KFBodywise bw, PetscInt p, const PetscReal g[], Mat Y[], Mat X)
{
  KFScene       s   = sys->scene;
  PetscInt      nG = bw->nG, rstart, rend, lda;
  PetscReal    *z;
  PetscScalar  *x;

  PetscFunctionBegin;
  PetscCall(MatZeroEntries(X));
  for (PetscInt b = 0; b < s->nb; b++) { /* spread: every owner back-substitutes its bodies before any rows move */
    PetscInt ng = bf->ng[b];
    if (!Y[b]) continue;
    PetscCall(PetscMalloc1(ng * p + 1, &z));
    PetscCall(KFSmallGemm("N", ng, p, nG, 1.0, bw->T[b], g, 0.0, z));
    PetscCall(KFDenseMultSmall(bf->Psi[b], ng, p, z, -1.0, Y[b]));
    PetscCall(PetscFree(z));
  }
  for (PetscInt b = 0; b < s->nb; b++) {
    KFBodyData *B = &s->bodies[b];
    if (bf->spread) {
      Mat D;
      PetscCall(KFDenseCreate(s->comm, B->rend - B->rstart, B->n, p, &D));
      PetscCall(KFBodyMoveRows(bf, b, D, Y[b], PETSC_FALSE));
      PetscCall(MatDestroy(&Y[b]));
      Y[b] = D;
    }
    PetscCall(KFCopyKept(s, B, X, Y[b], PETSC_FALSE)); /* Y is zero on Gamma; x_G is set below */
    PetscCall(MatDestroy(&Y[b]));
  }
  PetscCall(MatGetOwnershipRange(X, &rstart, &rend));
  PetscCall(MatDenseGetLDA(X, &lda));
  PetscCall(MatDenseGetArray(X, &x));
  for (PetscInt k = 0; k < nG; k++)
    if (bw->Gidx[k] >= rstart && bw->Gidx[k] < rend)
      for (PetscInt j = 0; j < p; j++) x[(bw->Gidx[k] - rstart) + j * lda] = g[k + j * nG];
  PetscCall(MatDenseRestoreArray(X, &x));
  PetscFunctionReturn(0);
}

/* X = Kh^-1 W (W: system layout, zero on the held rows), body-wise: condense, interface solve, back-substitute.
   Spread bodies: each body's rows of W go to its owner, which solves its interior and condenses alone; the ranks do
   so for their bodies at the same time, and only the small condensed pieces (nG x p) are summed over the ranks. */
static PetscErrorCode KFBodywiseSolveWith(KFSystem sys, KFBodyFactors bf, KFBodywise bw, Mat W, Mat X)
{
  KFScene       s   = sys->scene;
  PetscInt      nG = bw->nG, p;
  PetscReal    *g, *c, *gl = NULL;
  Mat          *Y, *Q;
  PetscMPIInt   rank;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  PetscCall(MatGetSize(W, NULL, &p));
  PetscCall(PetscMalloc1(nG * p + 1, &g));
  PetscCall(PetscCalloc2(s->nb, &Y, s->nb, &Q));
  PetscCall(KFGatherRows(W, nG, bw->Gidx, g)); /* f_G */
  if (bf->spread) PetscCall(PetscCalloc1(nG * p + 1, &gl));
  for (PetscInt b = 0; b < s->nb; b++) {
    PetscInt    ng = bf->ng[b];
    Mat         Fb;
    KFBodyData *B = &s->bodies[b];
    PetscCall(KFDenseCreate(s->comm, B->rend - B->rstart, B->n, p, &Fb));
    PetscCall(KFCopyKept(s, B, W, Fb, PETSC_TRUE)); /* interior rows: f_b,I (the interior dofs are kept) */
    PetscCall(KFZeroGammaRows(&s->bodies[b], ng, bf->gif[b], Fb));
    if (bf->spread) { /* f_b,I to the owner; solved below, once every body's rows have moved */
      if (rank == bf->owner[b]) PetscCall(KFDenseCreate(PETSC_COMM_SELF, B->n, B->n, p, &Q[b]));
      PetscCall(KFBodyMoveRows(bf, b, Fb, Q[b], PETSC_TRUE));
      PetscCall(MatDestroy(&Fb));
      continue;
    }
    /* MUMPS' solve writes every entry of Y: no zero fill (a fresh matrix per block solve) */
    PetscCall(KFDenseCreateUninitialized(s->comm, B->rend - B->rstart, B->n, p, &Y[b]));
    PetscCall(KFMumpsMatSolve(bf->F[b], Fb, Y[b])); /* K_II^-1 f_b,I, zero on Gamma */
    PetscCall(PetscMalloc1(ng * p + 1, &c));
    PetscCall(KFMatTransposeMatMultGather(bf->Psi[b], Fb, c)); /* K_GI K_II^-1 f_b,I */
    PetscCall(KFSmallGemm("T", nG, p, ng, -1.0, bw->T[b], c, 1.0, g));
    PetscCall(PetscFree(c));
    PetscCall(MatDestroy(&Fb));
  }
  if (bf->spread) {
    for (PetscInt b = 0; b < s->nb; b++) {
      PetscInt ng = bf->ng[b];
      if (!Q[b]) continue;
      PetscCall(KFDenseCreateUninitialized(PETSC_COMM_SELF, s->bodies[b].n, s->bodies[b].n, p, &Y[b]));
      PetscCall(KFMumpsMatSolve(bf->F[b], Q[b], Y[b]));
      PetscCall(PetscMalloc1(ng * p + 1, &c));
      PetscCall(KFMatTransposeMatMultGather(bf->Psi[b], Q[b], c)); /* sequential: no communication */
      PetscCall(KFSmallGemm("T", nG, p, ng, -1.0, bw->T[b], c, 1.0, gl));
      PetscCall(PetscFree(c));
      PetscCall(MatDestroy(&Q[b]));
    }
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, gl, (PetscMPIInt)(nG * p), MPIU_REAL, MPIU_SUM, s->comm));
    for (PetscInt i = 0; i < nG * p; i++) g[i] += gl[i];
    PetscCall(PetscFree(gl));
  }
  for (PetscInt k = 0; k < bw->nheldG; k++)
    for (PetscInt j = 0; j < p; j++) g[bw->heldG[k] + j * nG] = 0;
  if (nG > 0 && p > 0) {
    PetscBLASInt bn, bp, info;
    PetscCall(PetscBLASIntCast(nG, &bn));
    PetscCall(PetscBLASIntCast(p, &bp));
    if (bw->ipiv) PetscCallBLAS("LAPACKsytrs", LAPACKsytrs_("L", &bn, &bp, bw->S, &bn, bw->ipiv, g, &bn, &info));
    else PetscCallBLAS("LAPACKpotrs", LAPACKpotrs_("L", &bn, &bp, bw->S, &bn, g, &bn, &info));
    PetscCheck(info == 0, PETSC_COMM_SELF, PETSC_ERR_LIB, "LAPACK %s failed (info %d)", bw->ipiv ? "sytrs" : "potrs", (int)info);
  }
  PetscCall(KFBodywiseBackSubstitute(sys, bf, bw, p, g, Y, X));
  PetscCall(PetscFree2(Y, Q));
  PetscCall(PetscFree(g));
  PetscFunctionReturn(0);
}

static PetscErrorCode KFFlexSolverSolve_Bodywise(KFFlexSolver solver, Mat W, Mat X)
{
  PetscFunctionBegin;
  PetscCall(KFBodywiseSolveWith(solver->sys, solver->sys->bodyf, (KFBodywise)solver->data, W, X));
  PetscFunctionReturn(0);
}

/*
  The body-wise solve of K_S + shift M_S at any shift, for callers that solve the jointed system at one shift and many
  configurations outside a flexible solver (the verification's direct check: shift -w^2 at a check frequency w). The
  bodies' factors of K_b + shift M_b (KFBodyFactorsCreateShifted) belong to the caller, not to the system, and serve
  every configuration; an operator (KFBodywiseOpCreate) is the interface problem at the system's angles. Nothing is
  held: away from the structure's resonances K_S - w^2 M_S is regular, and the result is (K_S + shift M_S)^-1 W.
  KFBodywiseApplies says whether the scene allows it (the rules of -kf_flex_solver bodywise).
*/
PetscErrorCode KFBodywiseApplies(KFScene s, PetscBool *use)
{
  PetscBool all_iface = PETSC_TRUE, bcs = PETSC_FALSE;

  PetscFunctionBegin;
  for (PetscInt b = 0; b < s->nb; b++) {
    all_iface = (PetscBool)(all_iface && s->bodies[b].ninterfaces > 0);
    bcs       = (PetscBool)(bcs || s->bodies[b].nclamp > 0);
  }
  *use = (PetscBool)(s->nb > 1 && all_iface && !bcs);
  PetscFunctionReturn(0);
}

/* prev (or NULL): factors of the system made for the same bodies whose interiors are taken over (prev is destroyed) */
static PetscErrorCode KFBodyFactorsCreateShifted_Private(KFSystem sys, const char prefix[], PetscReal shift, KFBodyFactors *prev, KFBodyFactors *bfo)
{
  KFScene       s      = sys->scene;
  PetscBool     spread = PETSC_TRUE;
  KFBodyFactors bf;

  PetscFunctionBegin;
  PetscCall(PetscOptionsGetBool(NULL, prefix, "-kf_bodywise_spread", &spread, NULL)); /* as the flexible solve's */
  PetscCall(PetscNew(&bf));
  bf->shift = shift;
  bf->nb    = s->nb;
  PetscCall(PetscCalloc6(s->nb, &bf->ng, s->nb, &bf->gif, s->nb, &bf->Kb, s->nb, &bf->F, s->nb, &bf->Psi, s->nb, &bf->S));
  for (PetscInt b = 0; b < s->nb; b++) PetscCall(KFBodyGammaNodes(s, b, bf));
  PetscCall(KFBodywiseAssign(s, spread, bf));
  if (prev && *prev) {
    KFBodyFactors p    = *prev;
    PetscBool     same = (PetscBool)(p->factored && p->nb == bf->nb && p->spread == bf->spread);

    /* each body's interior where this set factors it (the same rank, or the same ranks), so that the pattern's check
       and the factorization stay on the communicator both share */
    for (PetscInt b = 0; b < s->nb && same && bf->spread; b++) same = (PetscBool)(p->owner[b] == bf->owner[b]);
    if (same) {
      PetscCall(PetscCalloc2(s->nb, &bf->prev_K, s->nb, &bf->prev_F));
      for (PetscInt b = 0; b < s->nb; b++) {
        bf->prev_K[b] = p->Kb[b];
        bf->prev_F[b] = p->F[b];
        p->Kb[b] = p->F[b] = NULL;
      }
    }
    PetscCall(KFBodyFactorsDestroy(prev));
  }
  PetscCall(KFBodyFactorsSetUpAll(s, prefix, shift, bf));
  if (bf->spread) PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &bf->nneg, 1, MPIU_INT, MPI_SUM, s->comm)); /* each body counted on its owner */
  bf->factored = PETSC_TRUE;
  *bfo         = bf;
  PetscFunctionReturn(0);
}

PetscErrorCode KFBodyFactorsCreateShifted(KFSystem sys, const char prefix[], PetscReal shift, KFBodyFactors *bfo)
{
  PetscFunctionBegin;
  PetscCall(KFBodyFactorsCreateShifted_Private(sys, prefix, shift, NULL, bfo));
  PetscFunctionReturn(0);
}

/* As KFBodyFactorsCreateShifted, for a caller that solves with the system's own body factors (sys->bodyf) no more:
   they are taken over and gone from the system, and a body whose K_b + shift M_b has the pattern its interior was
   analysed for (M_b's pattern within K_b's) is factored on that MUMPS analysis, its ordering and symbolic
   factorization not made again. The factors are MUMPS' of the same matrices either way; the analysis was made for
   the same pattern, with the same controls. */
PetscErrorCode KFBodyFactorsCreateShiftedReusing(KFSystem sys, const char prefix[], PetscReal shift, KFBodyFactors *bfo)
{
  PetscFunctionBegin;
  PetscCall(KFBodyFactorsCreateShifted_Private(sys, prefix, shift, &sys->bodyf, bfo));
  PetscFunctionReturn(0);
}

PetscErrorCode KFBodywiseOpCreate(KFSystem sys, KFBodyFactors bf, KFBodywiseOp *op)
{
  KFBodywise bw;

  PetscFunctionBegin;
  PetscCall(PetscNew(&bw));
  bw->nb = sys->scene->nb;
  PetscCall(KFBodywiseInterface(sys, bf, bw));
  PetscCall(KFBodywiseFactorInterface(sys->scene, bf, bw));
  *op = bw;
  PetscFunctionReturn(0);
}

PetscErrorCode KFBodywiseOpSolve(KFSystem sys, KFBodyFactors bf, KFBodywiseOp op, Mat W, Mat X)
{
  PetscFunctionBegin;
  PetscCall(KFBodywiseSolveWith(sys, bf, op, W, X));
  PetscFunctionReturn(0);
}

/* The inertia of K_S + shift M_S (shift < 0) on the body-wise split (Haynsworth): the bodies' interior factors'
   negative pivots (their interface rows held by a positive diagonal add none) and those of the interface problem's
   LDL^T (LAPACK sytrf: D's 1 x 1 blocks, and its 2 x 2 blocks, one negative eigenvalue where the determinant is
   negative, two where it is positive with a negative diagonal) */
PetscErrorCode KFBodywiseOpInertia(KFBodyFactors bf, KFBodywiseOp op, PetscInt *nneg)
{
  PetscInt nG = op->nG, n = bf->nneg;

  PetscFunctionBegin;
  PetscCheck(bf->shift < 0 && op->ipiv, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONGSTATE, "the body-wise inertia needs factors of K - w^2 M (a negative shift)");
  for (PetscInt k = 0; k < nG; k++) {
    const PetscReal a = op->S[k + k * nG];

    if (op->ipiv[k] > 0) n += a < 0;
    else { /* a 2 x 2 block on k, k + 1 */
      const PetscReal b = op->S[k + 1 + k * nG], c = op->S[k + 1 + (k + 1) * nG], det = a * c - b * b;

      n += det < 0 ? 1 : (a < 0 ? 2 : 0);
      k++;
    }
  }
  *nneg = n;
  PetscFunctionReturn(0);
}

PetscErrorCode KFBodywiseOpDestroy(KFBodywiseOp *op)
{
  PetscFunctionBegin;
  if (!*op) PetscFunctionReturn(0);
  PetscCall(KFBodywiseReset(*op));
  PetscCall(PetscFree(*op));
  PetscFunctionReturn(0);
}

static PetscErrorCode KFFlexSolverView_Bodywise(KFFlexSolver solver, PetscViewer viewer)
{
  KFBodywise bw = (KFBodywise)solver->data;

  PetscFunctionBegin;
  PetscCall(PetscViewerASCIIPrintf(viewer, "one MUMPS factorization per body interior, %s; dense interface problem of %" PetscInt_FMT " unknowns\n", bw->spread ? "the bodies spread over the ranks where they are at least as many" : "every body on all ranks", bw->nG));
  PetscFunctionReturn(0);
}

static PetscErrorCode KFFlexSolverBodywiseSetSpread_Bodywise(KFFlexSolver solver, PetscBool spread)
{
  PetscFunctionBegin;
  ((KFBodywise)solver->data)->spread = spread;
  PetscFunctionReturn(0);
}

static PetscErrorCode KFFlexSolverBodywiseSetMinDofs_Bodywise(KFFlexSolver solver, PetscInt min_dofs)
{
  PetscFunctionBegin;
  PetscCheck(min_dofs >= 0, PetscObjectComm((PetscObject)solver), PETSC_ERR_ARG_OUTOFRANGE, "the body-wise solve's least system dofs must be >= 0; got %" PetscInt_FMT, min_dofs);
  ((KFBodywise)solver->data)->min_dofs = min_dofs;
  PetscFunctionReturn(0);
}

/*
  KFFlexSolverBodywiseSetSpread - whether each body is factored on one rank, the bodies spread over the ranks (when
  there are at least as many bodies as ranks; the default), or every body on all ranks (-kf_bodywise_spread). Does
  nothing on a solver of another type.
*/
PetscErrorCode KFFlexSolverBodywiseSetSpread(KFFlexSolver solver, PetscBool spread)
{
  PetscFunctionBegin;
  PetscTryMethod(solver, "KFFlexSolverBodywiseSetSpread_C", (KFFlexSolver, PetscBool), (solver, spread));
  PetscFunctionReturn(0);
}

/*
  KFFlexSolverBodywiseSetMinDofs - the system dofs from which auto takes the body-wise solve (default 20000;
  -kf_bodywise_min_dofs). Does nothing on a solver of another type.
*/
PetscErrorCode KFFlexSolverBodywiseSetMinDofs(KFFlexSolver solver, PetscInt min_dofs)
{
  PetscFunctionBegin;
  PetscTryMethod(solver, "KFFlexSolverBodywiseSetMinDofs_C", (KFFlexSolver, PetscInt), (solver, min_dofs));
  PetscFunctionReturn(0);
}

PETSC_INTERN PetscErrorCode KFFlexSolverCreate_Bodywise(KFFlexSolver solver)
{
  KFBodywise bw;

  PetscFunctionBegin;
  PetscCall(PetscNew(&bw));
  bw->min_dofs                = 20000;
  bw->spread                  = PETSC_TRUE;
  solver->data                = bw;
  solver->ops->setfromoptions = KFFlexSolverSetFromOptions_Bodywise;
  solver->ops->setup          = KFFlexSolverSetUp_Bodywise;
  solver->ops->solve          = KFFlexSolverSolve_Bodywise;
  solver->ops->view           = KFFlexSolverView_Bodywise;
  solver->ops->destroy        = KFFlexSolverDestroy_Bodywise;
  PetscCall(PetscObjectComposeFunction((PetscObject)solver, "KFFlexSolverBodywiseSetSpread_C", KFFlexSolverBodywiseSetSpread_Bodywise));
  PetscCall(PetscObjectComposeFunction((PetscObject)solver, "KFFlexSolverBodywiseSetMinDofs_C", KFFlexSolverBodywiseSetMinDofs_Bodywise));
  PetscFunctionReturn(0);
}

/* auto: the body-wise implementation, which at its set-up keeps itself only where it pays (KFBodywiseWanted) */
PETSC_INTERN PetscErrorCode KFFlexSolverCreate_Auto(KFFlexSolver solver)
{
  PetscFunctionBegin;
  PetscCall(KFFlexSolverCreate_Bodywise(solver));
  ((KFBodywise)solver->data)->asked_auto = PETSC_TRUE;
  PetscFunctionReturn(0);
}
