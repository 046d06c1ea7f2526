/*
  The accuracy search: the smallest reduced model whose error (KFFRFElasticErrors: relative H-infinity, on the
  response -kf_accuracy_measure names) meets the scene's accuracy at every evaluation point (angles of interest and
  the midpoints between them).

  Single-angle family, for each candidate alpha_G (the named one, or every angle of interest):
    1. the fewest moments c whose whole Krylov basis meets the target;
    2. for c, c + 1 and c + 2, the fewest clusters of Krylov modes (in band-aware importance order, with the static
       correction of the rest) that still meet it, by bisection (the error falls as clusters are added).
  Multi-angle family: expansion angles added one at a time (the angle of interest farthest from those already in),
  and for each set the fewest moments whose whole bases meet the target.
  Sizes are the reduced bodies' dofs summed (what is stored and simulated); ties go to the smaller error. Every model
  tried is a row of the search table (results "search_table").
*/
#include <kryflex/reducerimpl.h>

typedef struct {
  PetscInt   n, nalloc;
  PetscReal *rows; /* 7 per row */
} KFSearchTable;

static PetscErrorCode KFSearchRecord(KFSearchTable *tab, const KFCandidate *c)
{
  PetscFunctionBegin;
  if (tab->n == tab->nalloc) {
    tab->nalloc = PetscMax(64, 2 * tab->nalloc);
    PetscCall(PetscRealloc(sizeof(PetscReal) * 7 * tab->nalloc, &tab->rows));
  }
  {
    PetscReal *row = &tab->rows[7 * tab->n++];

    row[0] = (PetscReal)c->family;
    row[1] = (PetscReal)c->c;
    row[2] = (PetscReal)c->kept;
    row[3] = (PetscReal)c->nexp;
    row[4] = (PetscReal)c->size;
    row[5] = (PetscReal)c->sysdofs;
    row[6] = c->error;
  }
  PetscFunctionReturn(0);
}

static PetscBool KFPasses(KFReducer r, const KFCandidate *c)
{
  return (PetscBool)(c->complete && c->error <= r->accuracy);
}

/* b better than a: passing beats failing; among passing the smaller, then the clearly more accurate (errors within 1 %
   of the target are a tie, kept by the earlier candidate: at the rounding floor, 1e-6 on Galileo, the order of two
   errors can differ between 1 and 2 ranks, and the model chosen must not); among failing the more accurate */
static PetscBool KFBetter(KFReducer r, const KFCandidate *b, const KFCandidate *a)
{
  const PetscBool pa = KFPasses(r, a), pb = KFPasses(r, b);

  if (!a->nexp) return PETSC_TRUE;
  if (pa != pb) return pb;
  if (pb) return (PetscBool)(b->size < a->size || (b->size == a->size && b->error < a->error - 0.01 * r->accuracy));
  return (PetscBool)(b->error < a->error);
}

static PetscErrorCode KFTry(KFReducer r, KFVisit visits[], PetscInt neval, KFEvalPoint evals[], KFSearchTable *tab, KFCandidate *c, KFCandidate *best)
{
  PetscFunctionBegin;
  PetscCall(KFInterruptCheck(PetscObjectComm((PetscObject)r)));
  /* a candidate already worse than the target is not measured further: its error is then a lower bound */
  PetscCall(KFCandidateEvaluate_Private(r, visits, neval, evals, r->accuracy, c));
  PetscCall(KFSearchRecord(tab, c));
  if (KFBetter(r, c, best)) *best = *c;
  PetscFunctionReturn(0);
}

/* moments the bases of the expansion visits can give: beyond the last block that added columns nothing changes */
static PetscInt KFUsefulMoments(KFVisit visits[], const KFCandidate *c, PetscInt cmax)
{
  PetscInt useful = 1;

  for (PetscInt e = 0; e < c->nexp; e++) {
    const KFReducerBasis *b = &visits[c->exp[e]].basis;

    for (PetscInt k = 1; k < PetscMin(b->nblocks, cmax); k++)
      if (b->block_end[k] > b->block_end[k - 1]) useful = PetscMax(useful, k + 1);
  }
  return PetscMin(useful, cmax);
}

/* the fewest moments in [cmin, cmax] whose whole bases meet the target (the most accurate one when none does) */
static PetscErrorCode KFSearchMoments(KFReducer r, KFVisit visits[], PetscInt neval, KFEvalPoint evals[], KFSearchTable *tab, KFCandidate *proto, PetscInt cmin, PetscInt cmax, KFCandidate *found)
{
  const PetscInt useful = KFUsefulMoments(visits, proto, cmax);

  PetscFunctionBegin;
  found->nexp = 0;
  for (PetscInt c = PetscMin(cmin, useful); c <= useful; c++) {
    KFCandidate cand = *proto;

    cand.c    = c;
    cand.kept = -1;
    PetscCall(KFTry(r, visits, neval, evals, tab, &cand, found));
    if (KFPasses(r, &cand)) break;
  }
  PetscFunctionReturn(0);
}

/* Each body no more than its share of the target: from a passing model that keeps k clusters in every body, body by
   body the fewest clusters it can keep (bisection, the other bodies as found so far) with the model still meeting the
   target. Kept only when it is smaller; recorded as one row of the table with kept clusters -2 (per body). */
static PetscErrorCode KFShareBodies(KFReducer r, KFVisit visits[], PetscInt neval, KFEvalPoint evals[], KFSearchTable *tab, KFCandidate *best)
{
  KFCandidate cur, cand;
  PetscInt    nb, k0 = best->kept;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, &nb, NULL, NULL, NULL, NULL, NULL));
  if (!best->nexp || !KFPasses(r, best) || nb < 2 || nb > KF_MAX_BODY_SHARE) PetscFunctionReturn(0);
  if (k0 < 0) /* the whole basis: every cluster of the richest expansion visit */
    for (PetscInt e = 0; e < best->nexp; e++) {
      PetscInt n, nclusters, *clu;
      PetscReal *lambda, *Phi, *imp;

      PetscCall(KFVisitModes_Private(r, &visits[best->exp[e]], best->c, &n, &lambda, &Phi, &imp, &clu, &nclusters));
      PetscCall(PetscFree4(lambda, Phi, imp, clu));
      k0 = PetscMax(k0, nclusters);
    }
  cur       = *best;
  cur.nbody = nb;
  for (PetscInt b = 0; b < nb; b++) cur.bkept[b] = k0;
  for (PetscInt b = 0; b < nb; b++) {
    PetscInt lo = -1, hi = k0;

    while (hi - lo > 1) { /* invariant: hi passes, lo fails (or -1) */
      const PetscInt mid = (lo + hi) / 2;

      PetscCall(KFInterruptCheck(PetscObjectComm((PetscObject)r)));
      cand          = cur;
      cand.bkept[b] = mid;
      PetscCall(KFCandidateEvaluate_Private(r, visits, neval, evals, r->accuracy, &cand));
      if (KFPasses(r, &cand)) {
        hi  = mid;
        cur = cand;
      } else lo = mid;
    }
  }
  if (cur.size < best->size) {
    cur.kept = -2;
    PetscCall(KFSearchRecord(tab, &cur));
    *best = cur;
  }
  PetscFunctionReturn(0);
}

/* KFShareBodies for a model found elsewhere (src/reducer/shifts.c): its rows are not recorded */
PetscErrorCode KFReducerShareBodies_Private(KFReducer r, KFVisit visits[], PetscInt neval, KFEvalPoint evals[], KFCandidate *best)
{
  KFSearchTable tab = {0, 0, NULL};

  PetscFunctionBegin;
  PetscCall(KFShareBodies(r, visits, neval, evals, &tab, best));
  PetscCall(PetscFree(tab.rows));
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerSearch_Private(KFReducer r, PetscInt nvisit, KFVisit visits[], PetscInt neval, KFEvalPoint evals[], KFCandidate *single, KFCandidate *multi, PetscInt *nrows, PetscReal **rows)
{
  KFSearchTable tab  = {0, 0, NULL};
  const PetscBool fixed = (PetscBool)(r->moments != PETSC_DECIDE);
  const PetscInt  cmax  = r->build_moments, cmin = fixed ? r->moments : 1;
  PetscInt        nrev, nrev1, ninterest = 0;
  MPI_Comm        comm;

  PetscFunctionBegin;
  PetscCall(PetscObjectGetComm((PetscObject)r, &comm));
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, &nrev, NULL, NULL, NULL));
  nrev1 = PetscMax(nrev, 1);
  PetscCall(PetscMemzero(single, sizeof(*single)));
  PetscCall(PetscMemzero(multi, sizeof(*multi)));
  for (PetscInt i = 0; i < nvisit; i++) ninterest += visits[i].interest >= 0;

  if (r->method != KF_METHOD_MULTI_ANGLE) {
    for (PetscInt g = 0; g < nvisit; g++) {
      KFCandidate proto = {0}, found;
      PetscInt    cstar;

      if (r->auto_alpha ? visits[g].interest < 0 : !visits[g].is_g) continue;
      proto.family = KF_METHOD_SINGLE_ANGLE;
      proto.nexp   = 1;
      proto.exp[0] = g;
      PetscCall(KFSearchMoments(r, visits, neval, evals, &tab, &proto, cmin, cmax, &found));
      if (KFBetter(r, &found, single)) *single = found;
      if (!KFPasses(r, &found)) continue;
      cstar = found.c;
      for (PetscInt c = cstar; c <= PetscMin(cstar + 2, fixed ? cstar : KFUsefulMoments(visits, &proto, cmax)); c++) {
        KFCandidate cand = proto, best = {0};
        PetscInt    lo = -1, hi, nclusters, n, *clu;
        PetscReal  *lambda, *Phi, *imp;

        PetscCall(KFVisitModes_Private(r, &visits[g], c, &n, &lambda, &Phi, &imp, &clu, &nclusters));
        PetscCall(PetscFree4(lambda, Phi, imp, clu));
        cand.c = c;
        hi     = nclusters; /* every cluster kept: the whole basis, which passes for c = cstar */
        if (c > cstar) {
          cand.kept = hi;
          PetscCall(KFTry(r, visits, neval, evals, &tab, &cand, &best));
          if (!KFPasses(r, &cand)) continue;
        }
        while (hi - lo > 1) { /* invariant: hi passes, lo fails (or -1) */
          const PetscInt mid = (lo + hi) / 2;

          cand.kept = mid;
          PetscCall(KFTry(r, visits, neval, evals, &tab, &cand, &best));
          if (KFPasses(r, &cand)) hi = mid;
          else lo = mid;
        }
        if (best.nexp && KFBetter(r, &best, single)) *single = best;
      }
    }
  }

  if (r->method != KF_METHOD_SINGLE_ANGLE && ninterest > 1) {
    KFCandidate proto = {0};
    PetscBool   in[1024] = {PETSC_FALSE};

    proto.family = KF_METHOD_MULTI_ANGLE;
    if (r->nmulti) { /* named expansion configurations */
      for (PetscInt i = 0; i < nvisit && proto.nexp < KF_MAX_EXPANSION; i++)
        if (visits[i].in_multi) proto.exp[proto.nexp++] = i;
    } else { /* start from the best single-angle model's angle (or the first angle of interest) */
      PetscInt first = single->nexp ? single->exp[0] : -1;

      for (PetscInt i = 0; first < 0 && i < nvisit; i++)
        if (visits[i].interest >= 0) first = i;
      proto.exp[proto.nexp++] = first;
      in[first]               = PETSC_TRUE;
    }
    for (;;) {
      KFCandidate found;

      if (proto.nexp > 1) {
        PetscCall(KFSearchMoments(r, visits, neval, evals, &tab, &proto, cmin, cmax, &found));
        if (KFBetter(r, &found, multi)) *multi = found;
        if (KFPasses(r, &found) || r->nmulti) break;
      }
      if (proto.nexp >= PetscMin(ninterest, KF_MAX_EXPANSION) || nvisit > 1024) break;
      { /* the angle of interest farthest (in the largest joint-angle difference) from the expansion angles */
        PetscInt  far = -1;
        PetscReal dfar = -1;

        for (PetscInt i = 0; i < nvisit; i++) {
          PetscReal dmin = PETSC_MAX_REAL;

          if (visits[i].interest < 0 || in[i]) continue;
          for (PetscInt e = 0; e < proto.nexp; e++) {
            PetscReal d = 0;

            for (PetscInt j = 0; j < nrev1; j++) d = PetscMax(d, PetscAbsReal(visits[i].angles[j] - visits[proto.exp[e]].angles[j]));
            dmin = PetscMin(dmin, d);
          }
          if (dmin > dfar) {
            dfar = dmin;
            far  = i;
          }
        }
        if (far < 0) break;
        proto.exp[proto.nexp++] = far;
        in[far]                 = PETSC_TRUE;
      }
    }
  }
  PetscCall(KFShareBodies(r, visits, neval, evals, &tab, single));
  PetscCall(KFShareBodies(r, visits, neval, evals, &tab, multi));
  *nrows = tab.n;
  *rows  = tab.rows;
  PetscFunctionReturn(0);
}

/* the size (reduced dofs summed) and error of model m compressed to counts, measured as the search measures its
   candidates (every evaluation point; a model already worse than the target is not measured further) */
static PetscErrorCode KFCompressTry(KFReducer r, PetscInt neval, KFEvalPoint evals[], KFReducedModel m, const KFBodyDirections d[], const PetscInt counts[], PetscInt *size, PetscReal *error)
{
  KFReducedModel c;
  PetscInt       nb;

  PetscFunctionBegin;
  PetscCall(KFInterruptCheck(PetscObjectComm((PetscObject)r)));
  PetscCall(KFReducedModelCompress(m, d, counts, &c));
  PetscCall(KFReducedModelGetInfo(c, &nb, NULL, NULL, NULL, NULL, NULL));
  *size = 0;
  for (PetscInt b = 0; b < nb; b++) {
    KFReducedBody body;

    PetscCall(KFReducedModelGetBody(c, b, NULL, NULL, &body, NULL));
    *size += body.v;
  }
  *error = 0;
  for (PetscInt e = 0; e < neval && *error <= r->accuracy; e++) {
    KFReducedSystem rs;
    PetscReal       hinf;

    PetscCall(KFReducedModelReassemble(c, evals[e].angles, &rs));
    PetscCall(KFEvalPointErrors_Private(r, &evals[e], rs, &hinf, NULL, NULL, NULL));
    PetscCall(KFReducedSystemDestroy(&rs));
    *error = PetscIsNanReal(hinf) ? PETSC_MAX_REAL : PetscMax(*error, hinf);
  }
  PetscCall(KFReducedModelDestroy(&c));
  PetscCall(PetscInfo(r, "compression candidate: %" PetscInt_FMT " reduced dofs, error %g\n", *size, (double)*error));
  PetscFunctionReturn(0);
}

/* each evaluation point's weight of each input's snapshots, inw (neval x a): 1 / the largest peak of that input's
   pairs in the reference (the measured part: elastic or total), so that every input's directions are ranked by their
   share of the relative error the target is stated on, not by the size of the input's response. Replicated. */
static PetscErrorCode KFCompressInputWeights(KFReducer r, PetscInt neval, KFEvalPoint evals[], PetscReal inw[])
{
  PetscInt   a, t;
  PetscReal *scale;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, NULL, NULL, &a, &t));
  PetscCall(PetscMalloc1(t * a + 1, &scale));
  for (PetscInt e = 0; e < neval; e++) {
    const KFEvalPoint *p = &evals[e];

    for (PetscInt j = 0; j < a; j++) inw[e * a + j] = 1;
    if (!p->nw || !t) continue;
    PetscCall(KFFRFPairScales(p->nw, t, a, p->Tre, p->Tim, p->Tgre, p->Tgim, scale, NULL));
    for (PetscInt j = 0; j < a; j++) {
      PetscReal big = 0;

      for (PetscInt i = 0; i < t; i++) big = PetscMax(big, scale[i + j * t]);
      inw[e * a + j] = 1 / big; /* KFFRFPairScales floors every pair above 0 */
    }
  }
  PetscCall(PetscFree(scale));
  PetscFunctionReturn(0);
}

/* An evaluation point's snapshot frequencies (rad/s, *w allocated here): the grid's log-spaced points and each of the
   reference's resonances in the band once. The evaluation grid has 7 points across each resonance so that the measure
   resolves its peak; as snapshots those 7 would weigh each resonance's shape 7 times against the response between
   resonances, which the projection needs as well (measured on the solid spacecraft at 1e-3: 24 states with each
   resonance once, 26 with the 7 points). */
static PetscErrorCode KFCompressSnapshotGrid(KFReducer r, const KFEvalPoint *p, PetscInt *n, PetscReal **w)
{
  PetscInt   nres = 0;
  PetscReal *fres;

  PetscFunctionBegin;
  if (p->rich) {
    const PetscReal *f;

    PetscCall(KFReducedSystemGetFrequencies(p->rich, &nres, &f));
    PetscCall(PetscMalloc1(nres + 1, &fres));
    PetscCall(PetscArraycpy(fres, f, nres));
  } else {
    nres = p->ref.n;
    PetscCall(PetscMalloc1(nres + 1, &fres));
    for (PetscInt k = 0; k < nres; k++) fres[k] = PetscSqrtReal(PetscMax(p->ref.w2[k], 0)) / (2 * PETSC_PI);
  }
  PetscCall(PetscMalloc1(r->frequency_points + 7 * nres + 1, w)); /* the grid writes 7 per resonance before merging */
  PetscCall(KFFrequencyGrid(r->band[0], r->band[1], r->frequency_points, nres, fres, 0, n, *w)); /* zeta 0: each once */
  for (PetscInt f = 0; f < *n; f++) (*w)[f] *= 2 * PETSC_PI;
  PetscCall(PetscFree(fres));
  PetscFunctionReturn(0);
}

/* body by body, the fewest leading directions that still meet the target (bisection, the other bodies as found so
   far); counts: every direction on entry (a passing model), the counts found on return; *nevals += models measured */
static PetscErrorCode KFCompressBisect(KFReducer r, PetscInt neval, KFEvalPoint evals[], KFReducedModel m, const KFBodyDirections d[], PetscInt nb, PetscInt counts[], PetscInt *nevals)
{
  PetscInt  size;
  PetscReal error;

  PetscFunctionBegin;
  for (PetscInt b = 0; b < nb; b++) {
    PetscInt lo = -1, hi = counts[b];

    while (hi - lo > 1) { /* invariant: hi passes, lo fails (or -1) */
      const PetscInt mid = (lo + hi) / 2;

      counts[b] = mid;
      PetscCall(KFCompressTry(r, neval, evals, m, d, counts, &size, &error));
      ++*nevals;
      if (error <= r->accuracy) hi = mid;
      else lo = mid;
    }
    counts[b] = hi;
  }
  PetscFunctionReturn(0);
}

/* Two bodies: every pair of counts, searched along its frontier. With more directions in one body the other needs
   no more (the error falls as directions are added), so from the bisection's pair (c0, c1) the fewest c1(i) for each
   i > c0 is found by walking c1 down: about d0 + d1 models, the smallest total wins (ties: the earlier). Body-by-body
   bisection favours the body it reduces first; this finds the best split of the directions between the two. */
static PetscErrorCode KFCompressFrontier(KFReducer r, PetscInt neval, KFEvalPoint evals[], KFReducedModel m, const KFBodyDirections d[], PetscInt counts[], PetscInt *nevals)
{
  PetscInt  best[2] = {counts[0], counts[1]}, c[2] = {counts[0], counts[1]}, size;
  PetscReal error;

  PetscFunctionBegin;
  for (c[0] = counts[0] + 1; c[0] <= d[0].ndir && c[0] < best[0] + best[1]; c[0]++) {
    while (c[1] > 0) { /* c[1] passes with c[0] - 1 directions, so with c[0]: try one fewer */
      const PetscInt one[2] = {c[0], c[1] - 1};

      PetscCall(KFCompressTry(r, neval, evals, m, d, one, &size, &error));
      ++*nevals;
      if (error > r->accuracy) break;
      c[1]--;
    }
    if (c[0] + c[1] < best[0] + best[1]) {
      best[0] = c[0];
      best[1] = c[1];
    }
    if (!c[1]) break; /* more directions in body 0 cannot help */
  }
  counts[0] = best[0];
  counts[1] = best[1];
  PetscFunctionReturn(0);
}

/* the directions d restricted to a selection: body b's kept columns and its directions sel[b][0 .. n[b]) (in that
   order), as directions of their own (freed with KFBodyDirectionsDestroy) */
static PetscErrorCode KFCompressSelect(PetscInt nb, const KFBodyDirections d[], PetscInt *const sel[], const PetscInt n[], KFBodyDirections **out)
{
  PetscFunctionBegin;
  PetscCall(PetscCalloc1(nb, out));
  for (PetscInt b = 0; b < nb; b++) {
    const PetscInt    v = d[b].v, nk = d[b].nkeep;
    KFBodyDirections *o = &(*out)[b];

    o->v     = v;
    o->nkeep = nk;
    o->ndir  = n[b];
    PetscCall(PetscMalloc2(v * (nk + n[b]) + 1, &o->W, n[b] + 1, &o->weight));
    PetscCall(PetscArraycpy(o->W, d[b].W, v * nk));
    for (PetscInt i = 0; i < n[b]; i++) {
      PetscCall(PetscArraycpy(o->W + (nk + i) * v, d[b].W + (nk + sel[b][i]) * v, v));
      o->weight[i] = d[b].weight[sel[b][i]];
    }
  }
  PetscFunctionReturn(0);
}

/* KFCompressTry for a selection of the directions */
static PetscErrorCode KFCompressTrySelection(KFReducer r, PetscInt neval, KFEvalPoint evals[], KFReducedModel m, PetscInt nb, const KFBodyDirections d[], PetscInt *const sel[], const PetscInt n[], PetscInt *size, PetscReal *error)
{
  KFBodyDirections *ds;

  PetscFunctionBegin;
  PetscCall(KFCompressSelect(nb, d, sel, n, &ds));
  PetscCall(KFCompressTry(r, neval, evals, m, ds, NULL, size, error));
  PetscCall(KFBodyDirectionsDestroy(nb, &ds));
  PetscFunctionReturn(0);
}

/* Backward elimination over every body's directions: from a passing selection (sel, n), drop the one direction, of
   any body and not only the last of its order, whose removal leaves the smallest measured error, while the target
   holds. The SVD orders each body's directions by its own share of the response, which is not the share of the
   error: a leading direction may be one the other body's directions already make up for. Ties within 1 % of the
   target go to the first found (body, then direction order), so that 1 and 2 ranks drop the same direction. */
static PetscErrorCode KFCompressEliminate(KFReducer r, PetscInt neval, KFEvalPoint evals[], KFReducedModel m, PetscInt nb, const KFBodyDirections d[], PetscInt *sel[], PetscInt n[], PetscInt *nevals)
{
  PetscFunctionBegin;
  for (;;) {
    PetscInt  bb = -1, ib = -1, size;
    PetscReal eb = PETSC_MAX_REAL, error;

    for (PetscInt b = 0; b < nb; b++)
      for (PetscInt i = 0; i < n[b]; i++) {
        const PetscInt x = sel[b][i];

        for (PetscInt k = i; k + 1 < n[b]; k++) sel[b][k] = sel[b][k + 1]; /* without direction x */
        n[b]--;
        PetscCall(KFCompressTrySelection(r, neval, evals, m, nb, d, sel, n, &size, &error));
        ++*nevals;
        n[b]++;
        for (PetscInt k = n[b] - 1; k > i; k--) sel[b][k] = sel[b][k - 1];
        sel[b][i] = x;
        if (error <= r->accuracy && error < eb - 0.01 * r->accuracy) {
          eb = error;
          bb = b;
          ib = i;
        }
      }
    if (bb < 0) break;
    for (PetscInt k = ib; k + 1 < n[bb]; k++) sel[bb][k] = sel[bb][k + 1];
    n[bb]--;
  }
  PetscFunctionReturn(0);
}

/* body b's directions of the model m ordered by its response on snapshot grids: each resonance once (once), or the
   evaluation grid (the measure's 7 points across each resonance) */
static PetscErrorCode KFCompressDirections(KFReducer r, PetscInt neval, KFEvalPoint evals[], KFReducedModel m, PetscBool once, KFBodyDirections **d)
{
  PetscInt         nrev, nrev1, a, *nw;
  PetscReal       *angles, *inw, **w;
  const PetscReal **wk, **inwk;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, &nrev, NULL, &a, NULL));
  nrev1 = PetscMax(nrev, 1);
  PetscCall(PetscMalloc6(neval * nrev1, &angles, neval, &nw, neval, &w, neval, &wk, neval * a + 1, &inw, neval, &inwk));
  PetscCall(KFCompressInputWeights(r, neval, evals, inw));
  for (PetscInt e = 0; e < neval; e++) {
    PetscCall(PetscArraycpy(&angles[e * nrev1], evals[e].angles, nrev1));
    if (once) PetscCall(KFCompressSnapshotGrid(r, &evals[e], &nw[e], &w[e]));
    else {
      nw[e] = evals[e].nw;
      PetscCall(PetscMalloc1(nw[e] + 1, &w[e]));
      PetscCall(PetscArraycpy(w[e], evals[e].w, nw[e]));
    }
    wk[e]   = w[e];
    inwk[e] = &inw[e * a];
  }
  PetscCall(KFBodyCompressDirections(m, neval, angles, nw, wk, inwk, d));
  for (PetscInt e = 0; e < neval; e++) PetscCall(PetscFree(w[e]));
  PetscCall(PetscFree6(angles, nw, w, wk, inw, inwk));
  PetscFunctionReturn(0);
}

/* The smallest selection of d's directions found (bisection, frontier, elimination) as directions of their own, *ds
   (NULL when every direction together misses the target), its size and error; *nevals += models measured */
static PetscErrorCode KFCompressSearch(KFReducer r, PetscInt neval, KFEvalPoint evals[], KFReducedModel m, PetscInt nb, const KFBodyDirections d[], KFBodyDirections **ds, PetscInt *size, PetscReal *error, PetscInt *nevals)
{
  PetscInt *counts, **sel;

  PetscFunctionBegin;
  *ds = NULL;
  PetscCall(PetscMalloc1(nb, &counts));
  PetscCall(PetscCalloc1(nb, &sel));
  for (PetscInt b = 0; b < nb; b++) counts[b] = d[b].ndir;
  PetscCall(KFCompressTry(r, neval, evals, m, d, counts, size, error));
  ++*nevals;
  if (*error <= r->accuracy) {
    PetscCall(KFCompressBisect(r, neval, evals, m, d, nb, counts, nevals));
    if (nb == 2) PetscCall(KFCompressFrontier(r, neval, evals, m, d, counts, nevals));
    for (PetscInt b = 0; b < nb; b++) {
      PetscCall(PetscMalloc1(counts[b] + 1, &sel[b]));
      for (PetscInt i = 0; i < counts[b]; i++) sel[b][i] = i;
    }
    PetscCall(KFCompressEliminate(r, neval, evals, m, nb, d, sel, counts, nevals));
    PetscCall(KFCompressSelect(nb, d, sel, counts, ds));
    PetscCall(KFCompressTry(r, neval, evals, m, *ds, NULL, size, error));
    ++*nevals;
  }
  for (PetscInt b = 0; b < nb; b++) PetscCall(PetscFree(sel[b]));
  PetscCall(PetscFree(sel));
  PetscCall(PetscFree(counts));
  PetscFunctionReturn(0);
}

/*
  Compression of the model the search chose (-kf_compress): each body's directions ordered by its share of the
  model's response at every evaluation point, each input weighted by its pairs' peaks (src/project/body_compress.c),
  then the fewest leading directions per body with which the model still meets the target (body by body by bisection,
  and with two bodies along the frontier of the pairs of counts), then any direction whose removal keeps the target
  (backward elimination). Each candidate is measured against the same reference as the search's. The directions are
  ordered twice, on two snapshot grids (each resonance once; the evaluation grid), and the smaller result is kept
  (ties: the first): which ordering compresses further differs between scenes and sizes of one scene (measured on
  the solid spacecraft at 1e-3: 24 against 26 states at 2,760 dofs, 30 against 28 at 57k). The smaller model replaces
  *model; *from and *to: the sizes before and after (equal when nothing was gained).
*/
PetscErrorCode KFReducerCompress_Private(KFReducer r, PetscInt neval, KFEvalPoint evals[], KFReducedModel *model, PetscInt *from, PetscInt *to)
{
  KFBodyDirections *best = NULL;
  PetscInt          nb, nevals = 0, bsize = 0;
  PetscReal         berror = 0;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, &nb, NULL, NULL, NULL, NULL, NULL));
  *from = 0;
  for (PetscInt b = 0; b < nb; b++) {
    KFReducedBody body;

    PetscCall(KFReducedModelGetBody(*model, b, NULL, NULL, &body, NULL));
    *from += body.v;
  }
  *to = *from;
  for (PetscInt pass = 0; pass < 2; pass++) {
    KFBodyDirections *d, *ds;
    PetscInt          size;
    PetscReal         error;

    PetscCall(KFCompressDirections(r, neval, evals, *model, (PetscBool)(pass == 0), &d));
    for (PetscInt b = 0; b < nb; b++) PetscCall(PetscInfo(r, "compression, ordering %" PetscInt_FMT ": body %" PetscInt_FMT " of %" PetscInt_FMT " coordinates keeps %" PetscInt_FMT " exactly, %" PetscInt_FMT " directions ordered\n", pass, b, d[b].v, d[b].nkeep, d[b].ndir));
    PetscCall(KFCompressSearch(r, neval, evals, *model, nb, d, &ds, &size, &error, &nevals));
    PetscCall(KFBodyDirectionsDestroy(nb, &d));
    if (ds && error <= r->accuracy && (!best || size < bsize)) {
      PetscCall(KFBodyDirectionsDestroy(nb, &best));
      best   = ds;
      bsize  = size;
      berror = error;
    } else PetscCall(KFBodyDirectionsDestroy(nb, &ds));
  }
  if (best && bsize < *from) {
    KFReducedModel c;
    char           text[32];

    PetscCall(KFReducedModelCompress(*model, best, NULL, &c));
    PetscCall(PetscSNPrintf(text, sizeof(text), "%" PetscInt_FMT, *from)); /* a saved model says what it was made from */
    PetscCall(KFReducedModelSetSetting(c, "compressed_from_dofs", text));
    PetscCall(KFReducedModelDestroy(model));
    *model = c;
    *to    = bsize;
  }
  PetscCall(PetscInfo(r, "compression: %" PetscInt_FMT " models measured, %" PetscInt_FMT " -> %" PetscInt_FMT " reduced dofs (error %g)\n", nevals, *from, *to, (double)berror));
  PetscCall(KFBodyDirectionsDestroy(nb, &best));
  PetscFunctionReturn(0);
}
