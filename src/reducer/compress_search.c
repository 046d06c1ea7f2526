/*
  Compression of the search's model: each body's reduced basis cut to its leading directions of the in-band response
  (src/project/body_compress.c orders them) while the model still meets the scene's accuracy at every evaluation point.
  The counts are searched by bisection body by body, then (two bodies) along the frontier of count pairs, then by
  backward elimination of single directions; every model tried is measured as the search measures its candidates.
  A tied model (or, under -kf_shared_directions auto, the chosen one as well) is compressed across its bodies instead:
  one set of directions of the stacked coordinates, the count searched by bisection, the model tied to them.
*/
#include <kryflex/reducerimpl.h>

/* the size of model c: its reduced dofs summed, less its coordinate ties (a tied model's) */
static PetscErrorCode KFCompressSize(KFReducedModel c, PetscInt *size)
{
  PetscInt nb, nties;

  PetscFunctionBegin;
  PetscCall(KFReducedModelGetInfo(c, &nb, NULL, NULL, NULL, NULL, NULL));
  PetscCall(KFReducedModelGetTies(c, &nties, NULL, NULL));
  *size = -nties;
  for (PetscInt b = 0; b < nb; b++) {
    KFReducedBody body;

    PetscCall(KFReducedModelGetBody(c, b, NULL, NULL, &body, NULL));
    *size += body.v;
  }
  PetscFunctionReturn(0);
}

/* the size and error of the candidate c, measured as the search measures its candidates (every evaluation point; a
   model already worse than the target is not measured further); c is destroyed */
static PetscErrorCode KFCompressMeasure(KFReducer r, PetscInt neval, KFEvalPoint evals[], KFReducedModel *c, PetscInt *size, PetscReal *error)
{
  PetscInt  sysdofs;
  PetscBool complete;

  PetscFunctionBegin;
  PetscCall(KFCompressSize(*c, size));
  PetscCall(KFReducerModelError_Private(r, *c, neval, evals, r->accuracy, error, &sysdofs, &complete));
  PetscCall(KFReducedModelDestroy(c));
  PetscCall(PetscInfo(r, "compression candidate: %" PetscInt_FMT " reduced dofs, error %g\n", *size, (double)*error));
  PetscFunctionReturn(0);
}

/* The models of one ordering already measured, by the directions they keep: the bisection, the frontier and the
   elimination come back to the same selections (the elimination's first sweep drops each body's last direction, as
   the bisection did; the selection found is measured again), and one selection is one model, its columns in the
   directions' order whichever way it was named. A flag per direction of every body, selection after selection. */
typedef struct {
  PetscInt   nflag, n, nalloc;
  char      *flags, *cur;
  PetscInt  *size;
  PetscReal *error;
} KFCompressMemo;

static PetscErrorCode KFCompressMemoCreate(PetscInt nb, const KFBodyDirections d[], KFCompressMemo *memo)
{
  PetscFunctionBegin;
  PetscCall(PetscMemzero(memo, sizeof(*memo)));
  for (PetscInt b = 0; b < nb; b++) memo->nflag += d[b].ndir;
  PetscCall(PetscMalloc1(memo->nflag + 1, &memo->cur));
  PetscFunctionReturn(0);
}

static PetscErrorCode KFCompressMemoDestroy(KFCompressMemo *memo)
{
  PetscFunctionBegin;
  PetscCall(PetscFree(memo->cur));
  PetscCall(PetscFree3(memo->flags, memo->size, memo->error));
  PetscFunctionReturn(0);
}

/* memo->cur: the flags of the selection of body b's first counts[b] directions (counts NULL: every one), or of its
   directions sel[b][0 .. n[b]) (sel non-NULL) */
static void KFCompressMemoSelect(KFCompressMemo *memo, PetscInt nb, const KFBodyDirections d[], const PetscInt counts[], PetscInt *const sel[], const PetscInt n[])
{
  char *f = memo->cur;

  for (PetscInt b = 0; b < nb; b++) {
    for (PetscInt i = 0; i < d[b].ndir; i++) f[i] = (char)(!sel && (!counts || i < counts[b]));
    for (PetscInt i = 0; sel && i < n[b]; i++) f[sel[b][i]] = 1;
    f += d[b].ndir;
  }
}

/* whether memo->cur's selection was measured: then its size and error */
static PetscBool KFCompressMemoFind(const KFCompressMemo *memo, PetscInt *size, PetscReal *error)
{
  for (PetscInt k = 0; k < memo->n; k++)
    if (!memo->nflag || !memcmp(memo->flags + k * memo->nflag, memo->cur, (size_t)memo->nflag)) {
      *size  = memo->size[k];
      *error = memo->error[k];
      return PETSC_TRUE;
    }
  return PETSC_FALSE;
}

static PetscErrorCode KFCompressMemoAdd(KFCompressMemo *memo, PetscInt size, PetscReal error)
{
  PetscFunctionBegin;
  if (memo->n == memo->nalloc) {
    char      *flags;
    PetscInt  *sz;
    PetscReal *er;

    memo->nalloc = PetscMax(16, 2 * memo->nalloc);
    PetscCall(PetscMalloc3(memo->nalloc * memo->nflag + 1, &flags, memo->nalloc, &sz, memo->nalloc, &er));
    if (memo->n) {
      PetscCall(PetscArraycpy(flags, memo->flags, memo->n * memo->nflag));
      PetscCall(PetscArraycpy(sz, memo->size, memo->n));
      PetscCall(PetscArraycpy(er, memo->error, memo->n));
    }
    PetscCall(PetscFree3(memo->flags, memo->size, memo->error));
    memo->flags = flags;
    memo->size  = sz;
    memo->error = er;
  }
  PetscCall(PetscArraycpy(memo->flags + memo->n * memo->nflag, memo->cur, memo->nflag));
  memo->size[memo->n]  = size;
  memo->error[memo->n] = error;
  memo->n++;
  PetscFunctionReturn(0);
}

/* the size (reduced dofs summed) and error of model m compressed to counts, measured (KFCompressMeasure) unless memo
   (may be NULL) has them */
static PetscErrorCode KFCompressTry(KFReducer r, PetscInt neval, KFEvalPoint evals[], KFReducedModel m, PetscInt nb, const KFBodyDirections d[], const PetscInt counts[], KFCompressMemo *memo, PetscInt *size, PetscReal *error)
{
  KFReducedModel c;

  PetscFunctionBegin;
  PetscCall(KFInterruptCheck(PetscObjectComm((PetscObject)r)));
  if (memo) {
    KFCompressMemoSelect(memo, nb, d, counts, NULL, NULL);
    if (KFCompressMemoFind(memo, size, error)) PetscFunctionReturn(0);
  }
  PetscCall(KFReducedModelCompress(m, d, counts, PETSC_FALSE, &c)); /* measured, then dropped: no maps */
  PetscCall(KFCompressMeasure(r, neval, evals, &c, size, error));
  if (memo) PetscCall(KFCompressMemoAdd(memo, *size, *error));
  PetscFunctionReturn(0);
}

/* the model m tied to the kept columns of the stacked directions d and its first count directions
   (KFReducedModelCompressTied), its ties made as the search makes a tied candidate's */
static PetscErrorCode KFCompressTied(KFReducer r, KFReducedModel m, const KFBodyDirections *d, PetscInt count, PetscBool with_map, KFReducedModel *c)
{
  PetscInt    nb, k;
  PetscReal **C;

  PetscFunctionBegin;
  PetscCall(KFReducedModelGetInfo(m, &nb, NULL, NULL, NULL, NULL, NULL));
  PetscCall(KFReducedModelCompressTied(m, d, count, with_map, c, &k, &C));
  PetscCall(KFCandidateTies_Private(r, *c, k, C));
  for (PetscInt b = 0; b < nb; b++) PetscCall(PetscFree(C[b]));
  PetscCall(PetscFree(C));
  PetscFunctionReturn(0);
}

/* the fewest leading stacked directions with which the tied model meets the target (bisection; the error falls as
   directions are added): *count the count found (-1: every direction together misses the target), *size and *error
   its; *nevals += models measured */
static PetscErrorCode KFCompressTiedSearch(KFReducer r, PetscInt neval, KFEvalPoint evals[], KFReducedModel m, const KFBodyDirections *d, PetscInt *count, PetscInt *size, PetscReal *error, PetscInt *nevals)
{
  PetscInt       lo = -1, hi = d->ndir, sz;
  PetscReal      er;
  KFReducedModel c;

  PetscFunctionBegin;
  *count = -1;
  PetscCall(KFInterruptCheck(PetscObjectComm((PetscObject)r)));
  PetscCall(KFCompressTied(r, m, d, hi, PETSC_FALSE, &c));
  PetscCall(KFCompressMeasure(r, neval, evals, &c, size, error));
  ++*nevals;
  if (*error > r->accuracy) PetscFunctionReturn(0);
  while (hi - lo > 1) { /* invariant: hi passes, lo fails (or -1) */
    const PetscInt mid = (lo + hi) / 2;

    PetscCall(KFInterruptCheck(PetscObjectComm((PetscObject)r)));
    PetscCall(KFCompressTied(r, m, d, mid, PETSC_FALSE, &c));
    PetscCall(KFCompressMeasure(r, neval, evals, &c, &sz, &er));
    ++*nevals;
    if (er <= r->accuracy) {
      hi     = mid;
      *size  = sz;
      *error = er;
    } else lo = mid;
  }
  *count = hi;
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
static PetscErrorCode KFCompressBisect(KFReducer r, PetscInt neval, KFEvalPoint evals[], KFReducedModel m, const KFBodyDirections d[], PetscInt nb, PetscInt counts[], KFCompressMemo *memo, PetscInt *nevals)
{
  PetscInt  size;
  PetscReal error;

  PetscFunctionBegin;
  for (PetscInt b = 0; b < nb; b++) {
    PetscInt lo = -1, hi = counts[b];

    while (hi - lo > 1) { /* invariant: hi passes, lo fails (or -1) */
      const PetscInt mid = (lo + hi) / 2;

      counts[b] = mid;
      PetscCall(KFCompressTry(r, neval, evals, m, nb, d, counts, memo, &size, &error));
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
static PetscErrorCode KFCompressFrontier(KFReducer r, PetscInt neval, KFEvalPoint evals[], KFReducedModel m, const KFBodyDirections d[], PetscInt counts[], KFCompressMemo *memo, PetscInt *nevals)
{
  PetscInt  best[2] = {counts[0], counts[1]}, c[2] = {counts[0], counts[1]}, size;
  PetscReal error;

  PetscFunctionBegin;
  for (c[0] = counts[0] + 1; c[0] <= d[0].ndir && c[0] < best[0] + best[1]; c[0]++) {
    while (c[1] > 0) { /* c[1] passes with c[0] - 1 directions, so with c[0]: try one fewer */
      const PetscInt one[2] = {c[0], c[1] - 1};

      PetscCall(KFCompressTry(r, neval, evals, m, 2, d, one, memo, &size, &error));
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

/* KFCompressTry for a selection of the directions (sel[b] ascending: the directions' order, as memo takes it) */
static PetscErrorCode KFCompressTrySelection(KFReducer r, PetscInt neval, KFEvalPoint evals[], KFReducedModel m, PetscInt nb, const KFBodyDirections d[], PetscInt *const sel[], const PetscInt n[], KFCompressMemo *memo, PetscInt *size, PetscReal *error)
{
  KFBodyDirections *ds;

  PetscFunctionBegin;
  KFCompressMemoSelect(memo, nb, d, NULL, sel, n);
  if (KFCompressMemoFind(memo, size, error)) {
    PetscCall(KFInterruptCheck(PetscObjectComm((PetscObject)r)));
    PetscFunctionReturn(0);
  }
  PetscCall(KFCompressSelect(nb, d, sel, n, &ds));
  PetscCall(KFCompressTry(r, neval, evals, m, nb, ds, NULL, NULL, size, error)); /* memo->cur still the selection */
  PetscCall(KFBodyDirectionsDestroy(nb, &ds));
  PetscCall(KFCompressMemoAdd(memo, *size, *error));
  PetscFunctionReturn(0);
}

/* Backward elimination over every body's directions: from a passing selection (sel, n), drop the one direction, of
   any body and not only the last of its order, whose removal leaves the smallest measured error, while the target
   holds. The SVD orders each body's directions by its own share of the response, which is not the share of the
   error: a leading direction may be one the other body's directions already make up for. Ties within 1 % of the
   target go to the first found (body, then direction order), so that 1 and 2 ranks drop the same direction. */
static PetscErrorCode KFCompressEliminate(KFReducer r, PetscInt neval, KFEvalPoint evals[], KFReducedModel m, PetscInt nb, const KFBodyDirections d[], PetscInt *sel[], PetscInt n[], KFCompressMemo *memo, PetscInt *nevals)
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
        PetscCall(KFCompressTrySelection(r, neval, evals, m, nb, d, sel, n, memo, &size, &error));
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
   evaluation grid (the measure's 7 points across each resonance); static_exact: the static response's columns kept
   exactly, else one more snapshot; tied: one set of directions of the bodies' stacked coordinates instead */
static PetscErrorCode KFCompressDirections(KFReducer r, PetscInt neval, KFEvalPoint evals[], KFReducedModel m, PetscBool once, PetscBool static_exact, PetscBool tied, KFBodyDirections **d)
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
  if (tied) PetscCall(KFTiedCompressDirections(m, neval, angles, nw, wk, inwk, static_exact, d));
  else PetscCall(KFBodyCompressDirections(m, neval, angles, nw, wk, inwk, static_exact, d));
  for (PetscInt e = 0; e < neval; e++) PetscCall(PetscFree(w[e]));
  PetscCall(PetscFree6(angles, nw, w, wk, inw, inwk));
  PetscFunctionReturn(0);
}

/* The smallest selection of d's directions found (bisection, frontier, elimination) as directions of their own, *ds
   (NULL when every direction together misses the target), its size and error; *nevals += models measured */
static PetscErrorCode KFCompressSearch(KFReducer r, PetscInt neval, KFEvalPoint evals[], KFReducedModel m, PetscInt nb, const KFBodyDirections d[], KFBodyDirections **ds, PetscInt *size, PetscReal *error, PetscInt *nevals)
{
  PetscInt      *counts, **sel;
  KFCompressMemo memo;

  PetscFunctionBegin;
  *ds = NULL;
  PetscCall(KFCompressMemoCreate(nb, d, &memo));
  PetscCall(PetscMalloc1(nb, &counts));
  PetscCall(PetscCalloc1(nb, &sel));
  for (PetscInt b = 0; b < nb; b++) counts[b] = d[b].ndir;
  PetscCall(KFCompressTry(r, neval, evals, m, nb, d, counts, &memo, size, error));
  ++*nevals;
  if (*error <= r->accuracy) {
    PetscCall(KFCompressBisect(r, neval, evals, m, d, nb, counts, &memo, nevals));
    if (nb == 2) PetscCall(KFCompressFrontier(r, neval, evals, m, d, counts, &memo, nevals));
    for (PetscInt b = 0; b < nb; b++) {
      PetscCall(PetscMalloc1(counts[b] + 1, &sel[b]));
      for (PetscInt i = 0; i < counts[b]; i++) sel[b][i] = i;
    }
    PetscCall(KFCompressEliminate(r, neval, evals, m, nb, d, sel, counts, &memo, nevals));
    PetscCall(KFCompressSelect(nb, d, sel, counts, ds));
    PetscCall(KFCompressTrySelection(r, neval, evals, m, nb, d, sel, counts, &memo, size, error));
    ++*nevals;
  }
  PetscCall(KFCompressMemoDestroy(&memo));
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
  the solid spacecraft at 1e-3: 24 against 26 states at 2,760 dofs, 30 against 28 at 57k). Without -kf_static_exact
  the static columns are kept in the first two orderings and are snapshots in two more, which win only when strictly
  smaller: the result is never larger than with the static columns kept (the snapshot orderings alone gave 26 states
  against 24 on the solid at 1e-3), and at equal size L^0 stays exact. The smaller model replaces *model; *from and
  *to: the sizes before and after (equal when nothing was gained); *static_kept: whether the result keeps the static
  columns (true when nothing was gained); *error: the compressed model's (-1 when nothing was gained).
  tied: the model's stacked body coordinates instead, one set of directions ordered by one SVD of the whole response
  (the bodies' rigid motions and the static columns kept, also under -kf_static_exact false), the fewest leading ones meeting the target by bisection,
  the result tied to them (its ties as a tied candidate's); the model may be tied or split. Its size is its body
  dofs less its ties.
*/
PetscErrorCode KFReducerCompress_Private(KFReducer r, PetscInt neval, KFEvalPoint evals[], PetscBool tied, KFReducedModel *model, PetscInt *from, PetscInt *to, PetscBool *static_kept, PetscReal *error)
{
  KFBodyDirections *best = NULL;
  PetscInt          nb, nd, nevals = 0, bsize = 0;
  PetscReal         berror = 0;
  PetscBool         bkept  = PETSC_TRUE;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, &nb, NULL, NULL, NULL, NULL, NULL));
  nd = tied ? 1 : nb; /* sets of directions: one per body, or one of the stacked coordinates */
  PetscCall(KFCompressSize(*model, from));
  *to          = *from;
  *static_kept = PETSC_TRUE;
  /* tied: the static columns always kept. As a snapshot the static response (solved to the stiff model's rounding)
     leads the stacked Gram, and 1 and 2 ranks then truncated to models 4e-6 apart in frequency (Galileo, 1e-3) */
  for (PetscInt pass = 0; pass < (r->static_exact || tied ? 2 : 4); pass++) {
    KFBodyDirections *d, *ds = NULL;
    PetscInt          size = 0;
    PetscReal         error = 0;
    const PetscBool   kept = (PetscBool)(pass < 2);

    PetscCall(KFCompressDirections(r, neval, evals, *model, (PetscBool)(pass % 2 == 0), kept, tied, &d));
    if (!d) { /* KFTiedCompressDirections: the model's reassembly misses a rigid or mechanism mode; kept as it is */
      PetscCall(PetscInfo(r, "compression (tied) skipped: the model reassembled has fewer rigid and mechanism modes than the scene\n"));
      break;
    }
    for (PetscInt b = 0; b < nd; b++) PetscCall(PetscInfo(r, "compression, ordering %" PetscInt_FMT ": %s %" PetscInt_FMT " of %" PetscInt_FMT " coordinates keeps %" PetscInt_FMT " exactly, %" PetscInt_FMT " directions ordered\n", pass, tied ? "stacked bodies" : "body", b, d[b].v, d[b].nkeep, d[b].ndir));
    if (tied) {
      PetscInt count;

      PetscCall(KFCompressTiedSearch(r, neval, evals, *model, d, &count, &size, &error, &nevals));
      if (count >= 0) { /* the directions truncated to the count found */
        d->ndir = count;
        ds      = d;
        d       = NULL;
      }
    } else PetscCall(KFCompressSearch(r, neval, evals, *model, nb, d, &ds, &size, &error, &nevals));
    PetscCall(KFBodyDirectionsDestroy(nd, &d));
    if (ds && error <= r->accuracy && (!best || size < bsize)) {
      PetscCall(KFBodyDirectionsDestroy(nd, &best));
      best   = ds;
      bsize  = size;
      berror = error;
      bkept  = kept;
    } else PetscCall(KFBodyDirectionsDestroy(nd, &ds));
  }
  if (best && bsize < *from) {
    KFReducedModel c;
    char           text[32];

    if (tied) PetscCall(KFCompressTied(r, *model, best, best->ndir, PETSC_TRUE, &c));
    else PetscCall(KFReducedModelCompress(*model, best, NULL, PETSC_TRUE, &c));
    PetscCall(PetscSNPrintf(text, sizeof(text), "%" PetscInt_FMT, *from)); /* a saved model says what it was made from */
    PetscCall(KFReducedModelSetSetting(c, "compressed_from_dofs", text));
    if (!bkept) PetscCall(KFReducedModelSetSetting(c, "static_exact", "false")); /* a saved model says its L^0 is approximated */
    PetscCall(KFReducedModelDestroy(model));
    *model       = c;
    *to          = bsize;
    *static_kept = bkept;
  }
  *error = best && bsize < *from ? berror : -1;
  PetscCall(PetscInfo(r, "compression%s: %" PetscInt_FMT " models measured, %" PetscInt_FMT " -> %" PetscInt_FMT " reduced dofs (error %g)\n", tied ? " (tied)" : "", nevals, *from, *to, (double)berror));
  PetscCall(KFBodyDirectionsDestroy(nd, &best));
  PetscFunctionReturn(0);
}
