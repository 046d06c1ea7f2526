/*
  Where models are measured: an evaluation point is an angle of interest or a midpoint between two, with the reference
  response on a frequency grid (the full order: SLEPc modes, rigid modes and the static residual of the modes not
  computed; or, verification off, the richest candidate model as an estimator). A reduced system's error there is
  KFFRFElasticErrors on the elastic response (the reference minus its rigid-body and mechanism part) or on the total
  one (-kf_accuracy_measure), on the grid plus points across the reduced system's own resonances, with the worst
  pair's maximum refined between points (a peak of the difference can fall between two points when a reduced
  resonance is shifted by less than the damping width).
*/
#include <kryflex/reducerimpl.h>


/* the reference's rigid-body and mechanism part at nw frequencies */
static PetscErrorCode KFEvalPointRigid(KFReducer r, KFEvalPoint *p, PetscInt nw, const PetscReal w[], PetscReal re[], PetscReal im[])
{
  PetscInt a, t;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, NULL, NULL, &a, &t));
  if (p->rich) PetscCall(KFReducedSystemRigidResponse(p->rich, nw, w, re, im));
  else PetscCall(KFFullRigidFRF_Private(&p->ref, t, a, &r->damping, r->scene->nquantity == t ? r->scene->out_quantity : NULL, nw, w, re, im));
  PetscFunctionReturn(0);
}

/* the reference response at nw frequencies */
static PetscErrorCode KFEvalPointResponse(KFReducer r, KFEvalPoint *p, PetscInt nw, const PetscReal w[], PetscReal re[], PetscReal im[])
{
  PetscInt a, t;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, NULL, NULL, &a, &t));
  if (p->rich) PetscCall(KFReducedSystemResponse(p->rich, nw, w, re, im));
  else PetscCall(KFFullFRF_Private(&p->ref, t, a, p->nmom, p->L0, &r->damping, r->scene->nquantity == t ? r->scene->out_quantity : NULL, nw, w, re, im));
  PetscFunctionReturn(0);
}

/* the grid (the band's log-spaced points plus 7 around each reference resonance), the reference on it and, with the
   elastic measure, the reference's rigid-body and mechanism part there */
PetscErrorCode KFEvalPointSetUp_Private(KFReducer r, KFEvalPoint *p)
{
  PetscInt   a, t, nres = 0;
  PetscReal *fres;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, NULL, NULL, &a, &t));
  if (p->rich) {
    const PetscReal *f;

    PetscCall(KFReducedSystemGetFrequencies(p->rich, &nres, &f));
    PetscCall(PetscMalloc1(PetscMax(nres, 1), &fres));
    PetscCall(PetscArraycpy(fres, f, nres));
  } else {
    nres = p->ref.n;
    PetscCall(PetscMalloc1(PetscMax(nres, 1), &fres));
    for (PetscInt k = 0; k < nres; k++) fres[k] = PetscSqrtReal(p->ref.w2[k]) / (2 * PETSC_PI);
  }
  PetscCall(PetscMalloc1(r->frequency_points + 7 * nres, &p->fhz));
  PetscCall(KFFrequencyGrid(r->band[0], r->band[1], r->frequency_points, nres, fres, r->zeta, &p->nw, p->fhz));
  PetscCall(PetscFree(fres));
  PetscCall(PetscMalloc3(p->nw, &p->w, p->nw * t * a, &p->Tre, p->nw * t * a, &p->Tim));
  for (PetscInt f = 0; f < p->nw; f++) p->w[f] = 2 * PETSC_PI * p->fhz[f];
  PetscCall(KFEvalPointResponse(r, p, p->nw, p->w, p->Tre, p->Tim));
  if (r->accuracy_measure == KF_ACCURACY_ELASTIC) {
    PetscCall(PetscMalloc2(p->nw * t * a, &p->Tgre, p->nw * t * a, &p->Tgim));
    PetscCall(KFEvalPointRigid(r, p, p->nw, p->w, p->Tgre, p->Tgim));
    if (p->interest >= 0) { /* beside frf_full_*: what scripts measuring the elastic response take out of it */
      const PetscInt shape[3] = {t, a, p->nw};

      PetscCall(KFReducerResultSet_Private(r, p->interest, "frf_full_rigid_re", 3, shape, p->Tgre));
      PetscCall(KFReducerResultSet_Private(r, p->interest, "frf_full_rigid_im", 3, shape, p->Tgim));
    }
  }
  if (!p->rich) PetscCall(KFEvalPointCheckReference_Private(r, p));
  PetscFunctionReturn(0);
}

PetscErrorCode KFEvalPointDestroy_Private(KFEvalPoint *p)
{
  PetscFunctionBegin;
  PetscCall(KFFullReferenceDestroy_Private(&p->ref));
  PetscCall(KFReducedSystemDestroy(&p->rich));
  PetscCall(PetscFree(p->L0));
  PetscCall(PetscFree(p->fhz));
  PetscCall(PetscFree3(p->w, p->Tre, p->Tim));
  PetscCall(PetscFree2(p->Tgre, p->Tgim));
  PetscCall(PetscFree3(p->chk_w, p->chk_T, p->chk_Ti));
  PetscCall(PetscFree(p->angles));
  PetscCall(MatDestroy(&p->kg));
  PetscCall(PetscMemzero(p, sizeof(*p)));
  PetscFunctionReturn(0);
}

/* |Tf_ij - Tr_ij| at one frequency */
static PetscErrorCode KFPairError(KFReducer r, KFEvalPoint *p, KFReducedSystem rs, PetscInt ij, PetscReal w, PetscReal *e)
{
  PetscInt   a, t;
  PetscReal *buf;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, NULL, NULL, &a, &t));
  PetscCall(PetscMalloc1(4 * t * a, &buf));
  PetscCall(KFEvalPointResponse(r, p, 1, &w, buf, buf + t * a));
  PetscCall(KFReducedSystemResponse(rs, 1, &w, buf + 2 * t * a, buf + 3 * t * a));
  {
    const PetscReal dre = buf[ij] - buf[2 * t * a + ij], dim = buf[t * a + ij] - buf[3 * t * a + ij];
    *e = PetscSqrtReal(dre * dre + dim * dim);
  }
  PetscCall(PetscFree(buf));
  PetscFunctionReturn(0);
}

/* the evaluation point's grid plus 7 points across each of the candidate's own resonances in the band, so that a
   shifted or spurious reduced peak cannot fall between grid points: W (rad/s, sorted) holds the nw + ne points, from[k]
   the index on the point's grid of W[k], or -1 for a new point */
static PetscErrorCode KFMergedGrid(KFReducer r, KFEvalPoint *p, KFReducedSystem rs, PetscInt *n, PetscReal **W, PetscInt **from)
{
  PetscInt         nf, ne = 0, i = 0, j = 0, k = 0;
  const PetscReal *fr;
  PetscReal       *extra;

  PetscFunctionBegin;
  PetscCall(KFReducedSystemGetFrequencies(rs, &nf, &fr));
  PetscCall(PetscMalloc1(PetscMax(7 * nf, 1), &extra));
  if (nf) PetscCall(KFFrequencyGrid(r->band[0], r->band[1], 0, nf, fr, r->zeta, &ne, extra));
  PetscCall(PetscMalloc2(p->nw + ne, W, p->nw + ne, from));
  while (i < p->nw || j < ne) { /* both sorted: merge, points of the grid first at ties */
    if (j >= ne || (i < p->nw && p->fhz[i] <= extra[j])) {
      (*W)[k]      = p->w[i];
      (*from)[k++] = i++;
    } else {
      (*W)[k]      = 2 * PETSC_PI * extra[j++];
      (*from)[k++] = -1;
    }
  }
  *n = k;
  PetscCall(PetscFree(extra));
  PetscFunctionReturn(0);
}

PetscErrorCode KFEvalPointErrors_Private(KFReducer r, KFEvalPoint *p, KFReducedSystem rs, PetscReal *hinf, PetscReal *pointwise, PetscReal Trre[], PetscReal Trim[])
{
  const PetscReal gr      = 0.5 * (PetscSqrtReal(5.0) - 1);
  const PetscBool elastic = (PetscBool)(p->Tgre != NULL);
  PetscInt        a, t, ta, worst = -1, fw = 0, n = 0, nnew = 0, *from;
  PetscReal      *W, *fre, *fim, *gre = NULL, *gim = NULL, *re, *im, *nw_, *nre, *nim, scale = 1;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, NULL, NULL, &a, &t));
  ta = t * a;
  PetscCall(KFMergedGrid(r, p, rs, &n, &W, &from));
  PetscCall(PetscMalloc4(n * ta, &fre, n * ta, &fim, n * ta, &re, n * ta, &im));
  if (elastic) PetscCall(PetscMalloc2(n * ta, &gre, n * ta, &gim));
  /* the reference (and its rigid part) at the new points only: the grid's are stored */
  for (PetscInt k = 0; k < n; k++) nnew += from[k] < 0;
  PetscCall(PetscMalloc3(PetscMax(nnew, 1), &nw_, PetscMax(2 * nnew * ta, 1), &nre, PetscMax(2 * nnew * ta, 1), &nim));
  nnew = 0;
  for (PetscInt k = 0; k < n; k++)
    if (from[k] < 0) nw_[nnew++] = W[k];
  if (nnew) {
    PetscCall(KFEvalPointResponse(r, p, nnew, nw_, nre, nim));
    if (elastic) PetscCall(KFEvalPointRigid(r, p, nnew, nw_, nre + nnew * ta, nim + nnew * ta));
  }
  for (PetscInt k = 0, q = 0; k < n; k++) {
    const PetscInt i = from[k];

    PetscCall(PetscArraycpy(fre + k * ta, i >= 0 ? p->Tre + i * ta : nre + q * ta, ta));
    PetscCall(PetscArraycpy(fim + k * ta, i >= 0 ? p->Tim + i * ta : nim + q * ta, ta));
    if (elastic) {
      PetscCall(PetscArraycpy(gre + k * ta, i >= 0 ? p->Tgre + i * ta : nre + (nnew + q) * ta, ta));
      PetscCall(PetscArraycpy(gim + k * ta, i >= 0 ? p->Tgim + i * ta : nim + (nnew + q) * ta, ta));
    }
    if (i < 0) q++;
  }
  PetscCall(KFReducedSystemResponse(rs, n, W, re, im));
  /* with the pair and frequency that make hinf */
  PetscCall(KFFRFElasticErrorsWorst_Private(n, t, a, fre, fim, re, im, gre, gim, r->frf_floor_db, hinf, pointwise, &worst, &fw, &scale));
  /* golden-section search for the largest difference between the neighbours of the worst point */
  if (worst >= 0 && n > 2 && !PetscIsInfOrNanReal(*hinf)) {
    PetscReal lo = W[PetscMax(fw - 1, 0)], hi = W[PetscMin(fw + 1, n - 1)], x1, x2, e1, e2;

    x1 = hi - gr * (hi - lo);
    x2 = lo + gr * (hi - lo);
    PetscCall(KFPairError(r, p, rs, worst, x1, &e1));
    PetscCall(KFPairError(r, p, rs, worst, x2, &e2));
    for (int it = 0; it < 16; it++) {
      if (e1 > e2) {
        hi = x2;
        x2 = x1;
        e2 = e1;
        x1 = hi - gr * (hi - lo);
        PetscCall(KFPairError(r, p, rs, worst, x1, &e1));
      } else {
        lo = x1;
        x1 = x2;
        e1 = e2;
        x2 = lo + gr * (hi - lo);
        PetscCall(KFPairError(r, p, rs, worst, x2, &e2));
      }
    }
    *hinf = PetscMax(*hinf, PetscMax(e1, e2) / scale);
  }
  if (Trre) /* the reduced response on the point's own grid */
    for (PetscInt k = 0; k < n; k++)
      if (from[k] >= 0) {
        PetscCall(PetscArraycpy(Trre + from[k] * ta, re + k * ta, ta));
        PetscCall(PetscArraycpy(Trim + from[k] * ta, im + k * ta, ta));
      }
  PetscCall(PetscFree3(nw_, nre, nim));
  PetscCall(PetscFree2(gre, gim));
  PetscCall(PetscFree4(fre, fim, re, im));
  PetscCall(PetscFree2(W, from));
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerModelError_Private(KFReducer r, KFReducedModel model, PetscInt neval, KFEvalPoint evals[], PetscReal stop, PetscReal *error, PetscInt *sysdofs, PetscBool *complete)
{
  PetscFunctionBegin;
  *error    = 0;
  *sysdofs  = 0;
  *complete = PETSC_TRUE;
  for (PetscInt e = 0; e < neval; e++) {
    KFReducedSystem rs;
    PetscReal       hinf;
    PetscInt        n;

    PetscCall(KFReducedModelReassemble(model, evals[e].angles, &rs));
    PetscCall(KFReducedSystemGetMatrices(rs, &n, NULL, NULL, NULL, NULL, NULL, NULL));
    *sysdofs = PetscMax(*sysdofs, n);
    PetscCall(KFEvalPointErrors_Private(r, &evals[e], rs, &hinf, NULL, NULL, NULL));
    PetscCall(KFReducedSystemDestroy(&rs));
    *error = PetscIsNanReal(hinf) ? PETSC_MAX_REAL : PetscMax(*error, hinf);
    if (stop > 0 && *error > stop) {
      *complete = (PetscBool)(e == neval - 1);
      break;
    }
  }
  PetscFunctionReturn(0);
}

PetscErrorCode KFCandidateEvaluate_Private(KFReducer r, KFVisit visits[], PetscInt neval, KFEvalPoint evals[], PetscReal stop, KFCandidate *cand)
{
  KFReducedModel model;
  PetscInt       nb;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, &nb, NULL, NULL, NULL, NULL, NULL));
  PetscCall(KFCandidateModel_Private(r, visits, cand, PETSC_FALSE, &model));
  cand->size = 0;
  for (PetscInt b = 0; b < nb; b++) {
    KFReducedBody body;

    PetscCall(KFReducedModelGetBody(model, b, NULL, NULL, &body, NULL));
    cand->size += body.v;
  }
  { /* a model of shared directions: its coordinate ties take as many dofs out at every angle */
    PetscInt ms;

    PetscCall(KFReducedModelGetTies(model, &ms, NULL, NULL));
    cand->size -= ms;
  }
  PetscCall(KFReducerModelError_Private(r, model, neval, evals, stop, &cand->error, &cand->sysdofs, &cand->complete));
  PetscCall(KFReducedModelDestroy(&model));
  PetscFunctionReturn(0);
}

/* evaluation points: the angles of interest, then the midpoints between consecutive ones (one joint angle each:
   the shorter way round) */
PetscErrorCode KFReducerEvalPoints_Private(KFReducer r, PetscInt *neval, KFEvalPoint **evals)
{
  PetscInt nrev, nrev1, nmid;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, &nrev, NULL, NULL, NULL));
  nrev1 = PetscMax(nrev, 1);
  nmid  = nrev && r->nconfig > 1 ? r->nconfig - 1 : 0;
  *neval = r->nconfig + nmid;
  PetscCall(PetscCalloc1(*neval, evals));
  for (PetscInt e = 0; e < *neval; e++) {
    KFEvalPoint *p = &(*evals)[e];

    PetscCall(PetscMalloc1(nrev1, &p->angles));
    if (e < r->nconfig) {
      p->interest = e;
      PetscCall(PetscArraycpy(p->angles, &r->angles[e * nrev1], nrev1));
    } else {
      const PetscReal *x = &r->angles[(e - r->nconfig) * nrev1], *y = &r->angles[(e - r->nconfig + 1) * nrev1];

      p->interest = -1;
      for (PetscInt j = 0; j < nrev1; j++) {
        PetscReal d = y[j] - x[j];

        while (d > PETSC_PI) d -= 2 * PETSC_PI;
        while (d < -PETSC_PI) d += 2 * PETSC_PI;
        p->angles[j] = x[j] + 0.5 * d;
      }
    }
  }
  PetscFunctionReturn(0);
}
