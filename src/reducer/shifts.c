/*
  Expansion points inside the band, chosen by the search (rational Krylov). After the search over moments at zero
  (search.c), a model may add, beside the first c blocks of its expansion angles' bases at zero, the Krylov blocks of
  (K - sigma M)^-1 M at real points sigma = (2 pi f)^2: one factorization of the indefinite K_S - sigma M_S per point
  and expansion angle (MUMPS LDL^T, src/solve/flex_solver.c), a visit of its own whose basis keeps the rigid modes
  projected out of every block as at zero. The blocks at zero stay in every model, so the moments they match (the
  static moment L^0 with them) stay exact.

  Greedy, for c = 1, 2, ... moments at zero: measure the candidate; while it misses the target, add a point at the
  frequency of its largest error (over the evaluation points, pairs and the grid; one damping ratio above it, so that
  the point is never a natural frequency the grid samples exactly) and measure again. Each point costs one
  factorization per expansion angle; -kf_max_factorizations caps those a search spends (points already factored are
  reused by later candidates). The smallest passing model wins over the moment-only one only when it is smaller.
*/
#include <kryflex/reducerimpl.h>
#include <kryflex/krylovimpl.h>

typedef struct {
  PetscInt   n, nalloc;
  PetscReal *rows; /* 6 per row: moments at zero, points, reduced dofs, system dofs, error, factorizations spent */
} KFShiftTable;

static PetscErrorCode KFShiftRecord(KFShiftTable *tab, const KFCandidate *c, PetscInt npoints, PetscInt spent)
{
  PetscFunctionBegin;
  if (tab->n == tab->nalloc) {
    tab->nalloc = PetscMax(16, 2 * tab->nalloc);
    PetscCall(PetscRealloc(sizeof(PetscReal) * 6 * tab->nalloc, &tab->rows));
  }
  {
    PetscReal *row = &tab->rows[6 * tab->n++];

    row[0] = (PetscReal)c->c;
    row[1] = (PetscReal)npoints;
    row[2] = (PetscReal)c->size;
    row[3] = (PetscReal)c->sysdofs;
    row[4] = c->error;
    row[5] = (PetscReal)spent;
  }
  PetscFunctionReturn(0);
}

/* one more row of the search table (search.c's), the whole bases of its visits */
static PetscErrorCode KFSearchTableAppend(KFReducer r, PetscInt *nrows, PetscReal **rows, const KFCandidate *c)
{
  PetscFunctionBegin;
  PetscCall(PetscRealloc(sizeof(PetscReal) * KF_SEARCH_TABLE_COLUMNS * (*nrows + 1), rows));
  KFSearchTableRow_Private(r, c, &(*rows)[KF_SEARCH_TABLE_COLUMNS * (*nrows)++]);
  PetscFunctionReturn(0);
}

/* The rest of a visit at v0's angles once its basis V is made: the basis' size and health, its projected pencil and
   eigenpairs (the Gram matrix info->gram, freed here), and copies of the configuration's rigid modes and body maps.
   The caller sets the basis' blocks. */
static PetscErrorCode KFShiftVisitProject(KFReducer r, KFSystem sys, const KFVisit *v0, BV V, KFKrylovInfo *info, Mat Phir, Mat P[], KFVisit *v)
{
  PetscInt   nb, nrev, nrev1, a, t, l, k, n;
  PetscReal *Mr, *Kr;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, &nb, NULL, &nrev, NULL, &a, &t));
  nrev1 = PetscMax(nrev, 1);
  PetscCall(BVGetActiveColumns(V, &l, &k));
  n                       = k - l;
  v->basis.size           = n;
  v->basis.data           = V;
  v->basis.ndeflated      = info->ndeflated;
  v->basis.rigid_content  = info->rigid_content;
  v->basis.orthogonality  = info->orthogonality;
  v->basis.gram_condition = (PetscReal)NAN;
  PetscCall(PetscMalloc4(n, &v->basis.lambda, n * n, &v->basis.Phi, n * a, &v->basis.Gr, t * n, &v->basis.Hr));
  PetscCall(PetscMalloc2(n * n, &Mr, n * n, &Kr));
  PetscCall(KFSystemProjectGram_Private(sys, V, info->gram, Mr, Kr, v->basis.Gr, v->basis.Hr));
  PetscCall(PetscFree(info->gram));
  PetscCall(KFDenseEig(n, Kr, Mr, v->basis.lambda, v->basis.Phi));
  v->basis.Kr = Kr;
  v->basis.Mr = Mr;
  PetscCall(PetscMalloc1(nrev1, &v->angles));
  PetscCall(PetscArraycpy(v->angles, v0->angles, nrev1));
  v->interest = -1; /* not an angle the search expands at by itself */
  PetscCall(MatDuplicate(Phir, MAT_COPY_VALUES, &v->Phir));
  PetscCall(PetscMalloc1(nb, &v->P));
  for (PetscInt b = 0; b < nb; b++) PetscCall(MatDuplicate(P[b], MAT_COPY_VALUES, &v->P[b]));
  PetscFunctionReturn(0);
}

/* The visit of the point sigma at the angles of visit v0: its factorization, its Krylov blocks (input and output
   chains interleaved as at zero), their projected pencil. The system is reassembled at v0's angles. */
static PetscErrorCode KFShiftVisitCreate(KFReducer r, KFSystem sys, const KFVisit *v0, PetscReal sigma, KFVisit *v)
{
  KFFlexSolver solver;
  KFKrylovInfo info;
  BV           V;
  PetscInt     nout, nin;
  Mat          Phir;
  PetscReal    rigid_res;

  PetscFunctionBegin;
  PetscCall(PetscMemzero(v, sizeof(*v)));
  PetscCall(KFSystemSetAngles(sys, v0->angles));
  PetscCall(KFSystemGetRigidModes(sys, &Phir, &rigid_res));
  PetscCall(KFFlexSolverCreate(sys, &solver));
  PetscCall(KFFlexSolverSetOptionsPrefix(solver, ((PetscObject)r)->prefix)); /* the reducer\'s options are the solver\'s */
  PetscCall(KFFlexSolverSetInteriorShift(solver, sigma));
  PetscCall(KFFlexSolverSetUp(solver));
  nout = PetscMin(r->output_blocks, r->shift_blocks / 2);
  nin  = r->shift_blocks - nout;
  PetscCall(PetscMemzero(&info, sizeof(info)));
  PetscCall(KFKrylovBasisWithInfo(solver, nin, nout, r->deflation_tol, &V, &info));
  v->basis.nblocks   = info.nblocks;
  v->basis.block_end = info.block_end; /* the visit owns it now */
  PetscCall(KFShiftVisitProject(r, sys, v0, V, &info, Phir, sys->P, v));
  if (v->basis.rigid_content > 1e-6 || v->basis.orthogonality > 1e-6) PetscCall(KFReducerNote_Private(r, "Krylov blocks at the expansion point %.6g Hz: rigid content %.2e, loss of M-orthogonality %.2e", (double)(PetscSqrtReal(sigma) / (2 * PETSC_PI)), (double)v->basis.rigid_content, (double)v->basis.orthogonality));
  PetscCall(KFReducerAddPerf_Private(r, solver));
  PetscCall(KFFlexSolverDestroy(&solver));
  PetscFunctionReturn(0);
}

/* The frequency (rad/s) of a candidate's largest error: over the evaluation points, the pairs (each against its own
   elastic peak, the response less its rigid part H Phir Phir^T G / (-w^2) where the full-order reference has it, with
   a floor of 1e-4 of the largest pair's) and the points of the grid. Replicated data only: every rank
   finds the same. */
static PetscErrorCode KFWorstFrequency(KFReducer r, KFVisit visits[], PetscInt neval, KFEvalPoint evals[], const KFCandidate *cand, PetscReal *wworst)
{
  KFReducedModel model;
  PetscInt       a, t;
  PetscReal      worst = -1;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, NULL, NULL, &a, &t));
  PetscCall(KFCandidateModel_Private(r, visits, cand, PETSC_FALSE, &model));
  *wworst = 0;
  for (PetscInt e = 0; e < neval; e++) {
    KFEvalPoint    *p = &evals[e];
    KFReducedSystem rs;
    PetscReal       hinf, *re, *im, *peak, pmax = 0;

    if (!p->nw) continue;
    PetscCall(PetscMalloc3(p->nw * t * a, &re, p->nw * t * a, &im, t * a, &peak));
    PetscCall(KFReducedModelReassemble(model, p->angles, &rs));
    PetscCall(KFEvalPointErrors_Private(r, p, rs, &hinf, NULL, re, im));
    PetscCall(KFReducedSystemDestroy(&rs));
    for (PetscInt q = 0; q < t * a; q++) { /* the pair's elastic peak: its rigid part, when the reference has it, out */
      PetscReal rig = 0;

      if (p->ref.w2 && p->ref.r)
        for (PetscInt k = 0; k < p->ref.r; k++) rig += p->ref.HPr[q % t + k * t] * p->ref.PrG[k + (q / t) * p->ref.r];
      peak[q] = 0;
      for (PetscInt f = 0; f < p->nw; f++) peak[q] = PetscMax(peak[q], PetscHypotReal(p->Tre[f * t * a + q] + rig / PetscSqr(p->w[f]), p->Tim[f * t * a + q]));
      pmax = PetscMax(pmax, peak[q]);
    }
    for (PetscInt q = 0; q < t * a; q++) {
      const PetscReal ref = PetscMax(peak[q], 1e-4 * pmax);

      if (!(ref > 0)) continue;
      for (PetscInt f = 0; f < p->nw; f++) {
        const PetscInt  i = f * t * a + q;
        const PetscReal d = PetscHypotReal(p->Tre[i] - re[i], p->Tim[i] - im[i]) / ref;

        if (d > worst) {
          worst   = d;
          *wworst = p->w[f];
        }
      }
    }
    PetscCall(PetscFree3(re, im, peak));
  }
  PetscCall(KFReducedModelDestroy(&model));
  PetscFunctionReturn(0);
}

static PetscBool KFShiftPasses(KFReducer r, const KFCandidate *c)
{
  return (PetscBool)(c->nexp && c->complete && c->error <= r->accuracy);
}

/* The model's visit at the angles of v0: one basis of v0's first c blocks at zero and the whole bases of the points'
   visits pts[], re-orthonormalized together, with its pencil; every prefix of c blocks is the whole of it (the
   search's candidates take c = the moments at zero, for the record), and its modes are kept or dropped by clusters
   and statically corrected as a single basis's. */
static PetscErrorCode KFMergedVisitCreate(KFReducer r, KFSystem sys, KFVisit visits[], PetscInt i0, PetscInt c, PetscInt npts, const PetscInt pts[], KFVisit *v)
{
  const KFVisit *v0 = &visits[i0];
  KFKrylovInfo   info;
  BV             Vs[KF_MAX_EXPANSION + 1], V;
  PetscInt       m[KF_MAX_EXPANSION + 1];
  PetscReal      rigid_res;
  Mat            Phir;

  PetscFunctionBegin;
  PetscCall(PetscMemzero(v, sizeof(*v)));
  PetscCall(KFSystemSetAngles(sys, v0->angles));
  PetscCall(KFSystemGetRigidModes(sys, &Phir, &rigid_res));
  Vs[0] = (BV)v0->basis.data;
  m[0]  = v0->basis.block_end[PetscMin(PetscMax(c, 1), v0->basis.nblocks) - 1];
  for (PetscInt i = 0; i < npts; i++) {
    Vs[i + 1] = (BV)visits[pts[i]].basis.data;
    m[i + 1]  = visits[pts[i]].basis.size;
  }
  PetscCall(KFKrylovBasisMerge_Private(sys, npts + 1, Vs, m, r->deflation_tol, &V, &info));
  PetscCall(KFShiftVisitProject(r, sys, v0, V, &info, v0->Phir, v0->P, v));
  v->basis.nblocks = PetscMax(c, 1);
  PetscCall(PetscMalloc1(v->basis.nblocks, &v->basis.block_end));
  for (PetscInt b = 0; b < v->basis.nblocks; b++) v->basis.block_end[b] = v->basis.size;
  PetscFunctionReturn(0);
}

/* the fewest clusters of a passing single-visit candidate's modes (importance order, static correction of the rest)
   that still meet the target, by bisection as the moment search does; best receives the smallest passing */
static PetscErrorCode KFShiftClusters(KFReducer r, KFVisit visits[], PetscInt neval, KFEvalPoint evals[], const KFCandidate *whole, KFCandidate *best)
{
  PetscInt   lo = -1, hi, n, nclusters, *clu;
  PetscReal *lambda, *Phi, *imp;

  PetscFunctionBegin;
  *best = *whole;
  PetscCall(KFVisitModes_Private(r, &visits[whole->exp[0]], whole->c, &n, &lambda, &Phi, &imp, &clu, &nclusters));
  PetscCall(PetscFree4(lambda, Phi, imp, clu));
  hi = nclusters;
  while (hi - lo > 1) { /* invariant: hi passes (the whole basis), lo fails (or -1) */
    const PetscInt mid  = (lo + hi) / 2;
    KFCandidate    cand = *whole;

    PetscCall(KFInterruptCheck(PetscObjectComm((PetscObject)r)));
    cand.kept = mid;
    PetscCall(KFCandidateEvaluate_Private(r, visits, neval, evals, r->accuracy, &cand));
    if (KFShiftPasses(r, &cand)) {
      hi = mid;
      if (cand.size < best->size) *best = cand;
    } else lo = mid;
  }
  PetscFunctionReturn(0);
}

/* a slot for n more visits */
static PetscErrorCode KFVisitsGrow(PetscInt *nvisit, KFVisit **visitsp, PetscInt n)
{
  PetscFunctionBegin;
  PetscCall(PetscRealloc(sizeof(KFVisit) * (*nvisit + n), visitsp));
  PetscCall(PetscMemzero(&(*visitsp)[*nvisit], sizeof(KFVisit) * n));
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerSearchShifts_Private(KFReducer r, KFSystem sys, PetscInt *nvisit, KFVisit **visitsp, PetscInt neval, KFEvalPoint evals[], KFCandidate *single, KFCandidate *multi, PetscInt *nrows, PetscReal **rows)
{
  KFCandidate  *base, best = {0};
  KFShiftTable  tab = {0, 0, NULL};
  PetscInt      nbase, spent = 0, npoints = 0, cmax, *ptvisit = NULL; /* point i at base angle e: visit ptvisit[i * nbase + e] */
  PetscReal    *fpoint = NULL;                                         /* Hz, one per point factored */
  PetscInt      best_np = 0;
  PetscReal     best_f[KF_MAX_EXPANSION];
  MPI_Comm      comm = PetscObjectComm((PetscObject)r);
  PetscBool     base_passes;

  PetscFunctionBegin;
  if (!r->max_factorizations) PetscFunctionReturn(0);
  for (PetscInt i = 0; i < *nvisit; i++) PetscCheck((*visitsp)[i].basis.nblocks, comm, PETSC_ERR_SUP, "expansion points inside the band (-kf_max_factorizations) need Krylov bases (-kf_reducer_type krylov)");
  /* the expansion angles of the model the moment search would choose */
  {
    const PetscBool sp = KFShiftPasses(r, single), mp = KFShiftPasses(r, multi);

    base = (mp && (!sp || KFCandidateSizeAgainst(multi, single) < KFCandidateSizeAgainst(single, multi))) || (!sp && !mp && multi->nexp && multi->error < single->error) ? multi : single;
  }
  if (!base->nexp) PetscFunctionReturn(0);
  base_passes = KFShiftPasses(r, base);
  nbase       = base->nexp;
  cmax        = base_passes ? base->c : r->build_moments;
  PetscCall(PetscMalloc2(r->max_factorizations / nbase + 1, &fpoint, r->max_factorizations + nbase, &ptvisit));
  PetscCall(KFProgress(comm, "searching expansion points inside the band: at most %" PetscInt_FMT " factorizations, %" PetscInt_FMT " expansion angle(s), up to %" PetscInt_FMT " moments at zero", r->max_factorizations, nbase, cmax));
  for (PetscInt c0 = 1; c0 <= cmax; c0++) {
    PetscInt np = 0, used[KF_MAX_EXPANSION];

    if (c0 == cmax && base_passes && !r->shift_family_only) break; /* the moment-only model at cmax passes: no smaller with points */
    for (;;) {
      KFCandidate cand = {0};
      PetscReal   w = 0, fhz;
      PetscInt    found = -1, pts[KF_MAX_EXPANSION];

      PetscCall(KFInterruptCheck(comm));
      /* the candidate: per base angle, one visit of its c0 blocks at zero and its points' blocks */
      cand.family = base->family;
      cand.tied   = base->tied;
      cand.c      = c0;
      cand.kept   = -1;
      PetscCall(KFVisitsGrow(nvisit, visitsp, nbase));
      for (PetscInt e = 0; e < nbase; e++) {
        for (PetscInt i = 0; i < np; i++) pts[i] = ptvisit[used[i] * nbase + e];
        PetscCall(KFMergedVisitCreate(r, sys, *visitsp, base->exp[e], c0, np, pts, &(*visitsp)[*nvisit]));
        cand.exp[cand.nexp++] = (*nvisit)++;
      }
      PetscCall(KFCandidateEvaluate_Private(r, *visitsp, neval, evals, 0, &cand));
      PetscCall(KFShiftRecord(&tab, &cand, np, spent));
      PetscCall(KFSearchTableAppend(r, nrows, rows, &cand));
      PetscCall(KFProgress(comm, "  %" PetscInt_FMT " moments at zero + %" PetscInt_FMT " point(s): %" PetscInt_FMT " system dofs, error %.3e", c0, np, cand.sysdofs, (double)cand.error));
      if (KFShiftPasses(r, &cand)) {
        KFCandidate small = cand;

        if (nbase == 1) PetscCall(KFShiftClusters(r, *visitsp, neval, evals, &cand, &small));
        PetscCall(KFReducerShareBodies_Private(r, *visitsp, neval, evals, &small)); /* each body its share, as at zero */
        PetscCall(KFProgress(comm, "    its clusters pruned: %" PetscInt_FMT " reduced dofs, %" PetscInt_FMT " system dofs, error %.3e", small.size, small.sysdofs, (double)small.error));
        if (small.kept != -1) {
          PetscCall(KFShiftRecord(&tab, &small, np, spent));
          PetscCall(KFSearchTableAppend(r, nrows, rows, &small));
        }
        if (!best.nexp || small.size < best.size) {
          best    = small;
          best_np = np;
          for (PetscInt i = 0; i < np; i++) best_f[i] = fpoint[used[i]];
        }
        break;
      }
      if (np + 1 >= KF_MAX_EXPANSION) break;
      PetscCall(KFWorstFrequency(r, *visitsp, neval, evals, &cand, &w));
      if (!(w > 0)) break;
      fhz = w * (1 + r->zeta) / (2 * PETSC_PI); /* one damping ratio above the largest error: never exactly a resonance */
      for (PetscInt i = 0; i < npoints; i++)
        if (PetscAbsReal(fpoint[i] - fhz) <= 1e-9 * fhz) found = i;
      if (found >= 0) { /* a point this candidate has already: the greedy step makes no progress */
        PetscBool have = PETSC_FALSE;

        for (PetscInt i = 0; i < np; i++) have = (PetscBool)(have || used[i] == found);
        if (have) break;
      } else {
        const PetscReal sigma = PetscSqr(2 * PETSC_PI * fhz);

        if (spent + nbase > r->max_factorizations) break;
        PetscCall(KFVisitsGrow(nvisit, visitsp, nbase));
        for (PetscInt e = 0; e < nbase; e++) {
          PetscCall(KFProgress(comm, "  expansion point %.6g Hz at expansion angle %" PetscInt_FMT ": factorization of K - sigma M", (double)fhz, e));
          PetscCall(KFShiftVisitCreate(r, sys, &(*visitsp)[base->exp[e]], sigma, &(*visitsp)[*nvisit]));
          ptvisit[npoints * nbase + e] = (*nvisit)++;
        }
        spent += nbase;
        fpoint[npoints] = fhz;
        found           = npoints++;
      }
      used[np++] = found;
    }
  }
  {
    const PetscInt shape[2] = {6, tab.n};

    PetscCall(KFReducerResultSet_Private(r, -1, "shift_search", 2, shape, tab.rows));
  }
  PetscCall(KFReducerResultScalar_Private(r, -1, "shift_factorizations_spent", (PetscReal)spent));
  if (best.nexp && (!base_passes || best.size < base->size || r->shift_family_only)) {
    const PetscInt shape[1] = {best_np};

    *base = best;
    PetscCall(KFReducerResultSet_Private(r, -1, "expansion_points_hz", 1, shape, best_f));
    PetscCall(KFReducerResultScalar_Private(r, -1, "expansion_point_factorizations", (PetscReal)(best_np * nbase)));
    PetscCall(KFProgress(comm, "expansion points inside the band: %" PetscInt_FMT " moments at zero + %" PetscInt_FMT " point(s), %" PetscInt_FMT " reduced dofs (error %.3e), %" PetscInt_FMT " factorizations spent", best.c, best_np, best.size, (double)best.error, spent));
  } else {
    PetscCall(KFReducerResultScalar_Private(r, -1, "expansion_point_factorizations", 0));
    PetscCall(KFProgress(comm, "expansion points inside the band: no model smaller than the moment-only one (%" PetscInt_FMT " factorizations spent)", spent));
  }
  PetscCall(PetscFree(tab.rows));
  PetscCall(PetscFree2(fpoint, ptvisit));
  PetscFunctionReturn(0);
}
