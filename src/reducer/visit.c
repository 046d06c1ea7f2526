/*
  What the accuracy search makes models from: the visited configurations (their bases, rigid modes and body maps,
  kept after their factorization is gone) and, for a candidate (family, moments, kept clusters, expansion angles),
  its system vectors and its reduced model.
*/
#include <kryflex/reducerimpl.h>

PetscErrorCode KFVisitDestroy_Private(KFReducer r, KFVisit *v)
{
  PetscInt nb;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, &nb, NULL, NULL, NULL, NULL, NULL));
  if (r->ops->destroybasis && v->basis.data) PetscCall((*r->ops->destroybasis)(r, &v->basis));
  PetscCall(PetscFree4(v->basis.lambda, v->basis.Phi, v->basis.Gr, v->basis.Hr));
  PetscCall(PetscFree2(v->basis.Mr, v->basis.Kr));
  PetscCall(PetscFree(v->basis.block_end));
  PetscCall(MatDestroy(&v->Phir));
  if (v->P)
    for (PetscInt b = 0; b < nb; b++) PetscCall(MatDestroy(&v->P[b]));
  PetscCall(PetscFree(v->P));
  PetscCall(PetscFree(v->angles));
  PetscCall(PetscMemzero(v, sizeof(*v)));
  PetscFunctionReturn(0);
}

/* columns of the first c blocks */
static PetscInt KFVisitColumns(const KFVisit *v, PetscInt c)
{
  if (!v->basis.nblocks) return v->basis.size;
  c = PetscMin(PetscMax(c, 1), v->basis.nblocks);
  return v->basis.block_end[c - 1];
}

/* The Krylov modes of the first c blocks (the leading sub-pencil), their importance by the reducer's measure and their
   clusters (band importance: near-equal frequencies together; the other measures: one mode per cluster). */
PetscErrorCode KFVisitModes_Private(KFReducer r, KFVisit *v, PetscInt c, PetscInt *n, PetscReal **lambda, PetscReal **Phi, PetscReal **imp, PetscInt **clu, PetscInt *nclusters)
{
  const PetscInt N = v->basis.size, m = KFVisitColumns(v, c);
  PetscInt       a, t;
  PetscReal     *K, *M, *G, *H;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, NULL, NULL, &a, &t));
  PetscCall(PetscMalloc4(m * m, &K, m * m, &M, m * a, &G, t * m, &H));
  for (PetscInt j = 0; j < m; j++)
    for (PetscInt i = 0; i < m; i++) {
      K[i + j * m] = v->basis.Kr[i + j * N];
      M[i + j * m] = v->basis.Mr[i + j * N];
    }
  for (PetscInt j = 0; j < a; j++)
    for (PetscInt i = 0; i < m; i++) G[i + j * m] = v->basis.Gr[i + j * N];
  for (PetscInt j = 0; j < m; j++)
    for (PetscInt i = 0; i < t; i++) H[i + j * t] = v->basis.Hr[i + j * t];
  PetscCall(PetscMalloc4(m, lambda, m * m, Phi, m, imp, m, clu));
  PetscCall(KFDenseEig(m, K, M, *lambda, *Phi));
  /* a Ritz value near zero is rigid content the basis should not carry (spurious): cluster -1, never kept, never
     corrected; with the rigid modes projected out of every block it does not occur, and the solve notes it if it does */
  if (r->importance == KF_IMPORTANCE_BAND) {
    PetscCall(KFDenseModeImportanceBand(m, *lambda, *Phi, a, G, t, H, r->zeta, r->band, r->cluster_rtol, KF_SPURIOUS_RTOL, *imp, *clu));
  } else {
    PetscReal lmax = 0;

    PetscCall(KFDenseModeImportance(m, *lambda, *Phi, a, G, t, H, r->zeta, r->importance, KF_SPURIOUS_RTOL, *imp));
    for (PetscInt i = 0; i < m; i++) lmax = PetscMax(lmax, PetscAbsReal((*lambda)[i]));
    for (PetscInt i = 0, k = 0; i < m; i++) (*clu)[i] = (*lambda)[i] <= KF_SPURIOUS_RTOL * lmax ? -1 : k++;
  }
  *nclusters = 0;
  for (PetscInt i = 0; i < m; i++) *nclusters = PetscMax(*nclusters, (*clu)[i] + 1);
  *n = m;
  PetscCall(PetscFree4(K, M, G, H));
  PetscFunctionReturn(0);
}

/* clusters in descending importance (ties: ascending id, i.e. frequency) */
static PetscErrorCode KFClusterOrder(PetscInt m, const PetscReal imp[], const PetscInt clu[], PetscInt nclusters, PetscInt order[])
{
  PetscReal *ci;

  PetscFunctionBegin;
  PetscCall(PetscCalloc1(PetscMax(nclusters, 1), &ci));
  for (PetscInt i = 0; i < m; i++)
    if (clu[i] >= 0) ci[clu[i]] = PetscMax(ci[clu[i]], imp[i]);
  for (PetscInt k = 0; k < nclusters; k++) order[k] = k;
  for (PetscInt k = 1; k < nclusters; k++) /* insertion sort: a few dozen clusters */
    for (PetscInt j = k; j > 0 && ci[order[j]] > ci[order[j - 1]]; j--) {
      PetscInt tmp = order[j];
      order[j]     = order[j - 1];
      order[j - 1] = tmp;
    }
  PetscCall(PetscFree(ci));
  PetscFunctionReturn(0);
}

/* The Krylov combinations: kept modes (columns of Phi) and the static correction of the others (eq. 15-17), each
   scaled to unit M-norm (c^T Mr c = 1), as KFBodyBasisAddMapped expects; X = V C on the first m columns of the BV. */
/* whether a candidate's vectors carry the static correction of the clusters it drops: the reducer's setting, unless
   the candidate was tried without it (KFCandidate.nostatic) */
static inline PetscBool KFCandidateStaticCorrection(KFReducer r, const KFCandidate *cand)
{
  return (PetscBool)(r->static_correction && !cand->nostatic);
}

static PetscErrorCode KFVisitCombination(KFReducer r, KFVisit *v, PetscInt c, PetscInt kept, PetscBool static_correction, PetscInt *mout, PetscInt *ncolout, PetscReal **Cout, PetscInt *nclusters)
{
  const PetscInt N = v->basis.size;
  PetscInt       m, nc, *clu, *order, a, nk = 0, nd, ncol;
  PetscReal     *lambda, *Phi, *imp, *C;
  PetscBool     *keep;

  PetscFunctionBegin;
  PetscCheck(v->basis.nblocks, PetscObjectComm((PetscObject)r), PETSC_ERR_SUP, "the accuracy search needs a basis of Krylov blocks (-kf_reducer_type krylov); use -kf_search 0 with this type");
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, NULL, NULL, &a, NULL));
  PetscCall(KFVisitModes_Private(r, v, c, &m, &lambda, &Phi, &imp, &clu, &nc));
  if (nclusters) *nclusters = nc;
  PetscCall(PetscMalloc2(m, &keep, PetscMax(nc, 1), &order));
  PetscCall(KFClusterOrder(m, imp, clu, nc, order));
  for (PetscInt i = 0; i < m; i++) keep[i] = (PetscBool)(kept < 0 && clu[i] >= 0);
  for (PetscInt k = 0; kept >= 0 && k < PetscMin(kept, nc); k++)
    for (PetscInt i = 0; i < m; i++)
      if (clu[i] == order[k]) keep[i] = PETSC_TRUE;
  nd = 0;
  for (PetscInt i = 0; i < m; i++) {
    nk += keep[i];
    nd += !keep[i] && clu[i] >= 0;
  }
  ncol = nk + (static_correction && nd ? a : 0);
  PetscCall(PetscCalloc1(m * PetscMax(ncol, 1), &C));
  for (PetscInt i = 0, j = 0; i < m; i++)
    if (keep[i]) PetscCall(PetscArraycpy(&C[j++ * m], &Phi[i * m], m));
  if (ncol > nk) {
    PetscReal *Phid, *lamd, *G;

    PetscCall(PetscMalloc3(m * nd, &Phid, nd, &lamd, m * a, &G));
    for (PetscInt i = 0, j = 0; i < m; i++)
      if (!keep[i] && clu[i] >= 0) {
        PetscCall(PetscArraycpy(&Phid[j * m], &Phi[i * m], m));
        lamd[j++] = lambda[i];
      }
    for (PetscInt j = 0; j < a; j++)
      for (PetscInt i = 0; i < m; i++) G[i + j * m] = v->basis.Gr[i + j * N];
    PetscCall(KFDenseStaticCorrection(m, nd, Phid, lamd, a, G, &C[nk * m]));
    PetscCall(PetscFree3(Phid, lamd, G));
  }
  for (PetscInt j = 0; j < ncol; j++) { /* unit M-norm: c^T Mr c */
    PetscReal q = 0;

    for (PetscInt k = 0; k < m; k++)
      for (PetscInt i = 0; i < m; i++) q += C[i + j * m] * v->basis.Mr[i + k * N] * C[k + j * m];
    if (q > 0)
      for (PetscInt i = 0; i < m; i++) C[i + j * m] /= PetscSqrtReal(q);
  }
  *mout    = m;
  *ncolout = ncol;
  *Cout    = C;
  PetscCall(PetscFree2(keep, order));
  PetscCall(PetscFree4(lambda, Phi, imp, clu));
  PetscFunctionReturn(0);
}

PetscErrorCode KFVisitVectors_Private(KFReducer r, KFVisit *v, PetscInt c, PetscInt kept, PetscBool static_correction, Mat *X, PetscInt *nclusters)
{
  BV         V = (BV)v->basis.data;
  PetscInt   m, ncol, l0, k0;
  PetscReal *C;

  PetscFunctionBegin;
  PetscCall(KFVisitCombination(r, v, c, kept, static_correction, &m, &ncol, &C, nclusters));
  PetscCall(BVGetActiveColumns(V, &l0, &k0));
  PetscCall(BVSetActiveColumns(V, 0, m));
  PetscCall(KFBVCombine(V, ncol, C, X));
  PetscCall(BVSetActiveColumns(V, l0, k0));
  PetscCall(PetscFree(C));
  PetscFunctionReturn(0);
}

/* The last candidate's finished body basis, kept for the next model with the same vectors: the family and the
   settings recorded differ, the body bases do not. The estimator's richest model (every basis whole) and the search's
   first candidate (the same at one expansion angle), and the search's last candidate and the model made of it, are
   such pairs: each is a body basis (products with M and K, Gram-Schmidt, K Psi in extended precision) not made twice.
   And the parent: the body basis of the whole Krylov bases of one or more visits (with their rigid modes), at the most
   moments made so far, kept with what sub-bases need (KFBodyBasisKeepProducts), and the coordinates in it of each of
   its visits' rigid modes Tr_eb = Psi_b^T M_b P_eb Phir_e and Krylov basis T_eb = Psi_b^T M_b P_eb V_e. Every later
   candidate of the parent's visits with no more moments has its vectors X_e = V_e C_e in the parent's span (up to
   the parent's deflation), so its body vectors are T_eb C_e in the parent's coordinates and its body basis a
   sub-basis (KFBodyBasisCreateSub): small dense work, no product of the bodies' size. The search's bisection over
   kept clusters makes all its candidates so; without verification the estimator's richest model (every visit's whole
   basis) is the parent of every multi-angle candidate too (at 3 angles of the 202k-dof solid, 15 body bases made the
   full way took 9.5 s of a 31 s reduction). */
/* The parent deflates at this fraction of the body tolerance: a candidate's vectors are then in its span to a
   thousandth of the tolerance its own deflation works at. With the parent at the body tolerance itself, what the
   parent dropped (up to ~1e-10 of a unit column) came back divided by the residual norm of a nearly dependent
   candidate column: 7.7e-8 of the bus's reduced K on the 202k-dof solid, 4e-13 with this factor.
   A parent is never a model itself: every candidate of its visit, the one it was made for included, is a sub-basis. */
#define KF_PARENT_TOL_FACTOR 1e-3

typedef struct {
  KFCandidate key;
  KFBodyBasis bb;
  KFBodyBasis parent;                                   /* never bb (a parent is no model), but the code allows it */
  PetscInt    pn, pvisit[KF_MAX_EXPANSION], pm[KF_MAX_EXPANSION]; /* the parent's visits and their Krylov columns */
  PetscReal **Tr, **T; /* per parent visit e and body b, at e * nb + b: v_b x nr_e, v_b x pm[e] */
  PetscInt    tk;      /* with shared directions: the last basis' coordinates of its vectors, per body v_b x tk */
  PetscReal **tC;
} KFCandidateCache;

/* the same vectors: the same visits, moments, kept clusters (per body when shared); not the family */
static PetscBool KFSameVectors(const KFCandidate *a, const KFCandidate *b)
{
  if (a->c != b->c || a->kept != b->kept || a->nexp != b->nexp || a->nbody != b->nbody || a->nostatic != b->nostatic) return PETSC_FALSE;
  for (PetscInt e = 0; e < a->nexp; e++)
    if (a->exp[e] != b->exp[e]) return PETSC_FALSE;
  for (PetscInt k = 0; k < a->nbody; k++)
    if (a->bkept[k] != b->bkept[k]) return PETSC_FALSE;
  return PETSC_TRUE;
}

/* every cluster kept (kept < 0, or at least the number of clusters) at every visit of the candidate */
static PetscErrorCode KFWholeBasis(KFReducer r, KFVisit visits[], const KFCandidate *cand, PetscBool *whole)
{
  PetscInt   n, nclusters, *clu;
  PetscReal *lambda, *Phi, *imp;

  PetscFunctionBegin;
  *whole = (PetscBool)(cand->kept < 0);
  if (*whole || cand->nbody) PetscFunctionReturn(0);
  *whole = PETSC_TRUE;
  for (PetscInt e = 0; e < cand->nexp && *whole; e++) {
    PetscCall(KFVisitModes_Private(r, &visits[cand->exp[e]], cand->c, &n, &lambda, &Phi, &imp, &clu, &nclusters));
    PetscCall(PetscFree4(lambda, Phi, imp, clu));
    *whole = (PetscBool)(cand->kept >= nclusters);
  }
  PetscFunctionReturn(0);
}

/* the index of a visit among the parent's visits, -1 when it is not one of them */
static PetscInt KFParentVisit(const KFCandidateCache *cc, PetscInt visit)
{
  for (PetscInt pe = 0; pe < cc->pn; pe++)
    if (cc->pvisit[pe] == visit) return pe;
  return -1;
}

/* Whether the candidate's vectors lie in the parent's span: each of its visits is one of the parent's, with a Krylov
   basis, and with no more columns than the parent took of it */
static PetscBool KFInParent(const KFCandidateCache *cc, KFVisit visits[], const KFCandidate *cand)
{
  if (!cc->parent) return PETSC_FALSE;
  for (PetscInt e = 0; e < cand->nexp; e++) {
    const KFVisit *v  = &visits[cand->exp[e]];
    const PetscInt pe = KFParentVisit(cc, cand->exp[e]);

    if (pe < 0 || !v->basis.nblocks || KFVisitColumns(v, cand->c) > cc->pm[pe]) return PETSC_FALSE;
  }
  return PETSC_TRUE;
}

static PetscErrorCode KFCandidateCacheDropParent(KFReducer r, KFCandidateCache *cc)
{
  PetscInt nb;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, &nb, NULL, NULL, NULL, NULL, NULL));
  if (cc->T)
    for (PetscInt i = 0; i < cc->pn * nb; i++) PetscCall(PetscFree2(cc->Tr[i], cc->T[i]));
  PetscCall(PetscFree2(cc->Tr, cc->T));
  cc->pn = 0;
  if (cc->parent != cc->bb) PetscCall(KFBodyBasisDestroy(&cc->parent));
  cc->parent = NULL;
  PetscFunctionReturn(0);
}

/* the last model's basis replaced by bb (the parent is kept), with its vectors' coordinates tC (nb arrays of v_b x tk,
   taken over; NULL without shared directions) */
static PetscErrorCode KFCandidateCacheSetLast(KFReducer r, KFCandidateCache *cc, const KFCandidate *cand, KFBodyBasis bb, PetscInt tk, PetscReal **tC)
{
  PetscInt nb;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, &nb, NULL, NULL, NULL, NULL, NULL));
  if (cc->bb != cc->parent) PetscCall(KFBodyBasisDestroy(&cc->bb));
  if (cc->tC)
    for (PetscInt b = 0; b < nb; b++) PetscCall(PetscFree(cc->tC[b]));
  PetscCall(PetscFree(cc->tC));
  cc->key = *cand;
  cc->bb  = bb;
  cc->tk  = tk;
  cc->tC  = tC;
  PetscFunctionReturn(0);
}

PetscErrorCode KFCandidateCacheReset_Private(KFReducer r)
{
  KFCandidateCache *cc = (KFCandidateCache *)r->candcache;

  PetscFunctionBegin;
  if (!cc) PetscFunctionReturn(0);
  PetscCall(KFCandidateCacheDropParent(r, cc));
  PetscCall(KFCandidateCacheSetLast(r, cc, &cc->key, NULL, 0, NULL));
  PetscCall(PetscFree(r->candcache));
  PetscFunctionReturn(0);
}

/* the coordinates of the parent's visits: Tr_eb, T_eb (one product P_eb [Phir_e, V_e] per visit and body with M Psi_b) */
static PetscErrorCode KFCandidateCacheCoordinates(KFReducer r, KFVisit visits[], KFCandidateCache *cc)
{
  PetscInt nb;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, &nb, NULL, NULL, NULL, NULL, NULL));
  PetscCall(PetscCalloc2(cc->pn * nb, &cc->Tr, cc->pn * nb, &cc->T));
  for (PetscInt e = 0; e < cc->pn; e++) {
    KFVisit   *v = &visits[cc->pvisit[e]];
    BV         V = (BV)v->basis.data;
    PetscInt   l0, k0, nr, pm = cc->pm[e];
    Mat        Vm;
    PetscReal *Id;

    PetscCall(MatGetSize(v->Phir, NULL, &nr));
    PetscCall(PetscCalloc1(pm * pm, &Id));
    for (PetscInt i = 0; i < pm; i++) Id[i + i * pm] = 1;
    PetscCall(BVGetActiveColumns(V, &l0, &k0));
    PetscCall(BVSetActiveColumns(V, 0, pm));
    PetscCall(KFBVCombine(V, pm, Id, &Vm));
    PetscCall(BVSetActiveColumns(V, l0, k0));
    PetscCall(PetscFree(Id));
    for (PetscInt b = 0; b < nb; b++) {
      PetscInt vb;

      PetscCall(KFBodyBasisGetReduced(cc->parent, b, &vb, NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL));
      PetscCall(PetscMalloc2(vb * nr + 1, &cc->Tr[e * nb + b], vb * pm + 1, &cc->T[e * nb + b]));
      PetscCall(KFBodyBasisCoordinates(cc->parent, b, v->P[b], v->Phir, cc->Tr[e * nb + b]));
      PetscCall(KFBodyBasisCoordinates(cc->parent, b, v->P[b], Vm, cc->T[e * nb + b]));
    }
    PetscCall(MatDestroy(&Vm));
  }
  PetscFunctionReturn(0);
}

/* a candidate of the parent's visits as a sub-basis: body vectors [Tr_eb, T_eb(:, 1:m_e) C_eb] per visit e of the
   candidate (the order of the full way: each visit's rigid modes, then its vectors), in the parent's coordinates */
static PetscErrorCode KFCandidateSubBasis(KFReducer r, KFVisit visits[], KFCandidateCache *cc, const KFCandidate *cand, KFBodyBasis *bb, PetscInt *tk, PetscReal ***tC)
{
  PetscInt    nb, *mb, *m, *ncol;
  PetscReal **Y, **C;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, &nb, NULL, NULL, NULL, NULL, NULL));
  PetscCall(PetscCalloc2(nb, &mb, nb, &Y));
  PetscCall(PetscCalloc3(cand->nexp, &m, cand->nexp, &ncol, cand->nexp, &C));
  for (PetscInt b = 0; b < nb; b++) {
    PetscInt vb, col = 0;

    PetscCall(KFBodyBasisGetReduced(cc->parent, b, &vb, NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL));
    for (PetscInt e = 0; e < cand->nexp; e++) { /* each visit's combination C_eb (m_e x ncol_e): the body's columns */
      KFVisit *v  = &visits[cand->exp[e]];
      PetscInt pe = KFParentVisit(cc, cand->exp[e]), nr;

      PetscCheck(pe >= 0, PetscObjectComm((PetscObject)r), PETSC_ERR_PLIB, "a sub-basis candidate has a visit its parent has not");
      /* the same for every body unless each body keeps its own clusters: made for the first body only then */
      if (!C[e]) PetscCall(KFVisitCombination(r, v, cand->c, cand->nbody ? cand->bkept[b] : cand->kept, KFCandidateStaticCorrection(r, cand), &m[e], &ncol[e], &C[e], NULL));
      PetscCheck(m[e] <= cc->pm[pe], PetscObjectComm((PetscObject)r), PETSC_ERR_PLIB, "a sub-basis candidate has more Krylov columns than its parent");
      PetscCall(MatGetSize(v->Phir, NULL, &nr));
      mb[b] += nr + ncol[e];
    }
    PetscCall(PetscMalloc1(vb * mb[b] + 1, &Y[b]));
    for (PetscInt e = 0; e < cand->nexp; e++) {
      const PetscInt pe = KFParentVisit(cc, cand->exp[e]);
      PetscReal     *Tr = cc->Tr[pe * nb + b], *T = cc->T[pe * nb + b];
      PetscInt       nr;

      PetscCall(MatGetSize(visits[cand->exp[e]].Phir, NULL, &nr));
      PetscCall(PetscArraycpy(&Y[b][col * vb], Tr, vb * nr));
      for (PetscInt j = 0; j < ncol[e]; j++)
        for (PetscInt i = 0; i < vb; i++) {
          PetscReal d = 0;
          for (PetscInt k = 0; k < m[e]; k++) d += T[i + k * vb] * C[e][k + j * m[e]];
          Y[b][i + (col + nr + j) * vb] = d;
        }
      col += nr + ncol[e];
      if (cand->nbody) PetscCall(PetscFree(C[e]));
    }
  }
  for (PetscInt e = 0; e < cand->nexp; e++) PetscCall(PetscFree(C[e]));
  PetscCall(PetscFree3(m, ncol, C));
  PetscCall(KFBodyBasisCreateSub(cc->parent, r->body_tol, mb, Y, bb));
  *tk = 0;
  *tC = NULL;
  if ((r->shared_directions || r->shared_auto) && !cand->nbody) { /* the same columns on every body: their coordinates in the sub-basis */
    *tk = mb[0];
    PetscCall(PetscMalloc1(nb, tC));
    for (PetscInt b = 0; b < nb; b++) {
      PetscInt vb;

      PetscCall(KFBodyBasisGetReduced(*bb, b, &vb, NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL));
      PetscCall(PetscMalloc1(vb * mb[b] + 1, &(*tC)[b]));
      PetscCall(KFBodyBasisSubCoordinates(*bb, cc->parent, b, mb[b], Y[b], (*tC)[b]));
    }
  }
  for (PetscInt b = 0; b < nb; b++) PetscCall(PetscFree(Y[b]));
  PetscCall(PetscFree2(mb, Y));
  PetscFunctionReturn(0);
}

/* the coordinates in bb (made with KFBodyBasisKeepProducts) of a candidate's columns, the full way: each visit's rigid
   modes, then its vectors, as KFCandidateModel_Private adds them */
static PetscErrorCode KFCandidateCoordinates(KFReducer r, KFVisit visits[], const KFCandidate *cand, KFBodyBasis bb, PetscInt *tk, PetscReal ***tC)
{
  PetscInt nb, k = 0, col = 0, *nr, *nx;
  Mat     *X;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, &nb, NULL, NULL, NULL, NULL, NULL));
  PetscCall(PetscMalloc3(cand->nexp, &X, cand->nexp, &nr, cand->nexp, &nx));
  for (PetscInt e = 0; e < cand->nexp; e++) {
    KFVisit *v = &visits[cand->exp[e]];

    PetscCall(MatGetSize(v->Phir, NULL, &nr[e]));
    PetscCall(KFVisitVectors_Private(r, v, cand->c, cand->kept, KFCandidateStaticCorrection(r, cand), &X[e], NULL));
    PetscCall(MatGetSize(X[e], NULL, &nx[e]));
    k += nr[e] + nx[e];
  }
  PetscCall(PetscMalloc1(nb, tC));
  for (PetscInt b = 0; b < nb; b++) {
    PetscInt vb;

    PetscCall(KFBodyBasisGetReduced(bb, b, &vb, NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL));
    PetscCall(PetscMalloc1(vb * k + 1, &(*tC)[b]));
    col = 0;
    for (PetscInt e = 0; e < cand->nexp; e++) {
      KFVisit *v = &visits[cand->exp[e]];

      PetscCall(KFBodyBasisCoordinates(bb, b, v->P[b], v->Phir, (*tC)[b] + col * vb));
      PetscCall(KFBodyBasisCoordinates(bb, b, v->P[b], X[e], (*tC)[b] + (col + nr[e]) * vb));
      col += nr[e] + nx[e];
    }
  }
  for (PetscInt e = 0; e < cand->nexp; e++) PetscCall(MatDestroy(&X[e]));
  PetscCall(PetscFree3(X, nr, nx));
  *tk = k;
  PetscFunctionReturn(0);
}

/* maps: the model keeps the bodies' maps as the reducer's options say (the models the reducer returns); the search's
   candidates (evaluated, then dropped) keep none */
PetscErrorCode KFCandidateModel_Private(KFReducer r, KFVisit visits[], const KFCandidate *cand, PetscBool maps, KFReducedModel *model)
{
  KFBodyBasis       bb;
  PetscInt          nrev, nrev1, nb, maxdofs = 0;
  PetscReal        *angles;
  /* coords: the vectors' body coordinates kept (for ties, also of the split candidates under auto, so that one cached
     body basis serves both); shared: this candidate tied */
  PetscBool         keep, coords = (PetscBool)((r->shared_directions || r->shared_auto) && !cand->nbody), shared = (PetscBool)(coords && (r->shared_directions || cand->tied));
  KFCandidateCache *cc = (KFCandidateCache *)r->candcache;
  PetscInt          tk = 0;
  PetscReal       **tC = NULL;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, &nb, NULL, &nrev, NULL, NULL, NULL));
  nrev1 = PetscMax(nrev, 1);
  PetscCall(PetscMalloc1(cand->nexp * nrev1, &angles));
  for (PetscInt e = 0; e < cand->nexp; e++) PetscCall(PetscArraycpy(&angles[e * nrev1], visits[cand->exp[e]].angles, nrev1));
  if (!cc) {
    PetscCall(PetscNew(&cc));
    r->candcache       = cc;
    r->candcache_reset = KFCandidateCacheReset_Private;
  }
  if (!cc->bb || !KFSameVectors(&cc->key, cand)) { /* not the vectors of the last model: a body basis of its own */
    PetscBool krylov = PETSC_TRUE; /* every visit has a Krylov basis (block columns; an eigen basis has none) */

    for (PetscInt e = 0; e < cand->nexp; e++) krylov = (PetscBool)(krylov && visits[cand->exp[e]].basis.nblocks);
    if (r->sub_bases && KFInParent(cc, visits, cand)) {
      PetscCall(PetscInfo(r, "candidate c=%" PetscInt_FMT " kept=%" PetscInt_FMT " nbody=%" PetscInt_FMT " nexp=%" PetscInt_FMT ": a sub-basis of the parent's %" PetscInt_FMT " visits\n", cand->c, cand->kept, cand->nbody, cand->nexp, cc->pn));
      PetscCall(KFCandidateSubBasis(r, visits, cc, cand, &bb, &tk, &tC));
      PetscCall(KFCandidateCacheSetLast(r, cc, cand, bb, tk, tC));
    } else {
      /* the whole bases of its visits: the new parent */
      PetscBool parent = PETSC_FALSE;

      if (r->sub_bases && krylov && !cand->nbody) PetscCall(KFWholeBasis(r, visits, cand, &parent));

      PetscCall(KFBodyBasisCreate(r->scene, &bb));
      if (parent || coords) PetscCall(KFBodyBasisKeepProducts(bb)); /* coords: for the vectors' coordinates */
      for (PetscInt e = 0; e < cand->nexp; e++) {
        KFVisit *v = &visits[cand->exp[e]];
        Mat      X;

        PetscCall(KFBodyBasisAddMapped(bb, v->P, v->Phir));
        if (!cand->nbody) {
          PetscCall(KFVisitVectors_Private(r, v, cand->c, cand->kept, KFCandidateStaticCorrection(r, cand), &X, NULL));
          PetscCall(KFBodyBasisAddMapped(bb, v->P, X));
          PetscCall(MatDestroy(&X));
        } else
          for (PetscInt b = 0; b < nb; b++) {
            PetscCall(KFVisitVectors_Private(r, v, cand->c, cand->bkept[b], KFCandidateStaticCorrection(r, cand), &X, NULL));
            PetscCall(KFBodyBasisAddMappedTo(bb, b, v->P[b], X));
            PetscCall(MatDestroy(&X));
          }
      }
      PetscCall(KFBodyBasisFinish(bb, parent ? KF_PARENT_TOL_FACTOR * r->body_tol : r->body_tol));
      if (parent) { /* the candidate itself is then a sub-basis of it, as the later ones */
        PetscCall(KFCandidateCacheDropParent(r, cc));
        cc->parent = bb;
        cc->pn     = cand->nexp;
        for (PetscInt e = 0; e < cand->nexp; e++) {
          cc->pvisit[e] = cand->exp[e];
          cc->pm[e]     = KFVisitColumns(&visits[cand->exp[e]], cand->c);
        }
        PetscCall(KFCandidateCacheCoordinates(r, visits, cc));
        PetscCall(KFCandidateSubBasis(r, visits, cc, cand, &bb, &tk, &tC));
      } else if (coords) PetscCall(KFCandidateCoordinates(r, visits, cand, bb, &tk, &tC));
      PetscCall(KFCandidateCacheSetLast(r, cc, cand, bb, tk, tC));
    }
  }
  bb = cc->bb;
  for (PetscInt b = 0; b < nb; b++) {
    PetscInt nd;

    PetscCall(KFSceneGetBodyInfo(r->scene, b, NULL, &nd, NULL));
    maxdofs = PetscMax(maxdofs, nd);
  }
  keep = r->save_maps == PETSC_DECIDE ? (PetscBool)(maxdofs <= r->save_maps_max_dofs) : (PetscBool)r->save_maps;
  keep = (PetscBool)(keep && maps);
  PetscCall(KFReducedModelCreateFromBodyBasis(r->scene, bb, cand->nexp, angles, keep, model));
  PetscCall(KFReducerRecordSettings_Private(r, *model, (KFReducerMethod)cand->family, cand->c, cand->nexp, angles));
  if (shared) {
    PetscCheck(cc->tC, PetscObjectComm((PetscObject)r), PETSC_ERR_PLIB, "shared directions: the candidate's body basis has no coordinates of its vectors");
    PetscCall(KFCandidateTies_Private(r, *model, cc->tk, cc->tC));
    if (r->shared_auto) PetscCall(KFReducedModelSetSetting(*model, "shared_directions", "true"));
  }
  PetscCall(PetscFree(angles)); /* bb stays in the cache */
  if (cand->nostatic) { /* its vectors lack the dropped clusters' static correction: its L^0 is measured, not exact */
    PetscCall(KFReducedModelSetSetting(*model, "static_correction", "false"));
    PetscCall(KFReducedModelSetSetting(*model, "static_exact", "false"));
  }
  PetscFunctionReturn(0);
}
