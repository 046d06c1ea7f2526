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

/* Full-order response: rigid modes, computed flexible modes, and the modes not computed by their first two moments:
   sum_{i not computed} H phi_i phi_i^T G / (omega_i^2 - w^2) = R^0 + w^2 R^1 + O(w^4 / omega_i^4), with
   R^k = L^k - sum_{i computed} H phi_i phi_i^T G / omega_i^(2k+2) (L^k = H (K+ M)^k K+ G). The w^2 term makes the
   truncation error (w / omega_i)^4 of the residual instead of (w / omega_i)^2: with modes to 3x the band's top, 1e-2
   of the residual instead of 1e-1. The residuals are differences of large numbers when the computed modes include
   very soft ones (1/omega_i^4 in R^1), so: none when every mode was computed, and R^1 dropped when it is below the
   accuracy of L^1 itself (||R^1|| <= 1e-8 ||L^1||). L: nmom blocks of t x a (nmom 1: the static residual
   alone). Tre, Tim: nw blocks of t x a. */
PetscErrorCode KFFullFRF_Private(const KFFullReference *ref, PetscInt t, PetscInt a, PetscInt nmom, const PetscReal L[], const KFDamping *d, const PetscInt quantity[], PetscInt nw, const PetscReal w[], PetscReal Tre[], PetscReal Tim[])
{
  const PetscInt n = ref->r + ref->n;
  PetscReal     *lam, *HPhi, *PhiG, *resid;

  PetscFunctionBegin;
  PetscCall(PetscMalloc4(n, &lam, t * n, &HPhi, n * a, &PhiG, 2 * t * a, &resid));
  for (PetscInt k = 0; k < n; k++) lam[k] = k < ref->r ? 0 : ref->w2[k - ref->r];
  PetscCall(PetscArraycpy(HPhi, ref->HPr, t * ref->r));
  PetscCall(PetscArraycpy(HPhi + t * ref->r, ref->HPhi, t * ref->n));
  for (PetscInt j = 0; j < a; j++) {
    for (PetscInt k = 0; k < ref->r; k++) PhiG[k + j * n] = ref->PrG[k + j * ref->r];
    for (PetscInt k = 0; k < ref->n; k++) PhiG[ref->r + k + j * n] = ref->PhiG[k + j * ref->n];
  }
  PetscCall(KFDampedModalFRF(n, lam, t, HPhi, a, PhiG, d, ref->Cm, ref->nc, quantity, 1e-300, nw, w, Tre, Tim));
  for (PetscInt j = 0; j < a; j++)
    for (PetscInt i = 0; i < t; i++) {
      PetscReal s0 = L[i + j * t], s1 = nmom > 1 ? L[t * a + i + j * t] : 0;
      for (PetscInt k = 0; k < ref->n; k++) {
        const PetscReal rk = ref->HPhi[i + k * t] / ref->w2[k] * ref->PhiG[k + j * ref->n];

        s0 -= rk;
        if (nmom > 1) s1 -= rk / ref->w2[k];
      }
      resid[i + j * t]         = s0;
      resid[t * a + i + j * t] = s1;
    }
  {
    PetscReal n0 = 0, n1 = 0, l1 = 0, wmax = nw ? w[nw - 1] : 0;

    for (PetscInt e = 0; e < t * a; e++) {
      n0 += resid[e] * resid[e];
      n1 += resid[t * a + e] * resid[t * a + e];
      if (nmom > 1) l1 += L[t * a + e] * L[t * a + e];
    }
    /* R^1 is kept where it is above its own noise and the small correction it must be. Noise: L^1 comes from block
       solves (refined to a residual of 1e-6) and R^1 = L^1 - (computed part) cancels, so below 1e-8 ||L^1|| it is
       taken for noise. Small: ||R^1|| w_max^2 <= ||R^0|| / 4; beyond that R^1 is the difference of large numbers
       (hundreds of computed modes, 1/omega_i^4), which acceleration outputs multiply by w^2 again: a 2,012-dof panel
       scene with 640 computed modes gave a reference 4 times its own peak off the dense one with R^1 kept there. */
    const PetscBool keep0 = (PetscBool)!ref->complete;
    const PetscBool keep1 = (PetscBool)(keep0 && nmom > 1 && n1 > 1e-16 * l1 && PetscSqrtReal(n1) * wmax * wmax <= 0.25 * PetscSqrtReal(n0));

    for (PetscInt e = 0; e < t * a; e++) {
      if (!keep0) resid[e] = 0;
      if (!keep1) resid[t * a + e] = 0;
      if (ref->D) resid[e] += ref->D[e]; /* the static response of M's null space (dense path) */
    }
  }
  /* the residual is quasi-static: structural damping divides it by 1 + i g; then the output's quantity */
  for (PetscInt f = 0; f < nw; f++)
    for (PetscInt j = 0; j < a; j++)
      for (PetscInt i = 0; i < t; i++) {
        const PetscInt  e  = i + j * t;
        const PetscReal rr = resid[e] + w[f] * w[f] * resid[t * a + e], g = d->g;
        PetscReal       xr = rr / (1 + g * g), xi = -rr * g / (1 + g * g), yr = xr, yi = xi;

        if (quantity && quantity[i] == KF_QUANTITY_VELOCITY) {
          yr = -w[f] * xi;
          yi = w[f] * xr;
        } else if (quantity && quantity[i] == KF_QUANTITY_ACCELERATION) {
          yr = -w[f] * w[f] * xr;
          yi = -w[f] * w[f] * xi;
        }
        Tre[f * t * a + e] += yr;
        Tim[f * t * a + e] += yi;
      }
  PetscCall(PetscFree4(lam, HPhi, PhiG, resid));
  PetscFunctionReturn(0);
}

/* the rigid-body and mechanism part of the full-order response: the geometric rigid modes (H Phi_r, Phi_r^T G) with
   the damping model the full response uses (their block of the modal viscous damping, Rayleigh; modal ratios and
   structural damping are zero on them) */
static PetscErrorCode KFFullRigidFRF(const KFFullReference *ref, PetscInt t, PetscInt a, const KFDamping *d, const PetscInt quantity[], PetscInt nw, const PetscReal w[], PetscReal Tre[], PetscReal Tim[])
{
  const PetscInt nr = ref->r, m = ref->r + ref->n;
  PetscReal     *lam, *Crr = NULL;

  PetscFunctionBegin;
  PetscCall(PetscCalloc1(PetscMax(nr, 1), &lam));
  if (ref->Cm && ref->nc >= nr && nr) {
    PetscCall(PetscMalloc1(nr * nr, &Crr));
    for (PetscInt j = 0; j < nr; j++)
      for (PetscInt i = 0; i < nr; i++) Crr[i + j * nr] = ref->Cm[i + j * m];
  }
  PetscCall(KFDampedModalFRF(nr, lam, t, ref->HPr, a, ref->PrG, d, Crr, nr, quantity, 0, nw, w, Tre, Tim));
  PetscCall(PetscFree(Crr));
  PetscCall(PetscFree(lam));
  PetscFunctionReturn(0);
}

/* the reference's rigid-body and mechanism part at nw frequencies */
static PetscErrorCode KFEvalPointRigid(KFReducer r, KFEvalPoint *p, PetscInt nw, const PetscReal w[], PetscReal re[], PetscReal im[])
{
  PetscInt a, t;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, NULL, NULL, &a, &t));
  if (p->rich) PetscCall(KFReducedSystemRigidResponse(p->rich, nw, w, re, im));
  else PetscCall(KFFullRigidFRF(&p->ref, t, a, &r->damping, r->scene->nquantity == t ? r->scene->out_quantity : NULL, nw, w, re, im));
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
  PetscReal      *W, *fre, *fim, *gre = NULL, *gim = NULL, *re, *im, *nw_, *nre, *nim, *scale, best = -1;

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, NULL, NULL, &a, &t));
  ta = t * a;
  PetscCall(KFMergedGrid(r, p, rs, &n, &W, &from));
  PetscCall(PetscMalloc4(n * ta, &fre, n * ta, &fim, n * ta, &re, n * ta, &im));
  if (elastic) PetscCall(PetscMalloc2(n * ta, &gre, n * ta, &gim));
  /* the reference (and its rigid part) at the new points only: the grid's are stored */
  for (PetscInt k = 0; k < n; k++) nnew += from[k] < 0;
  PetscCall(PetscMalloc4(PetscMax(nnew, 1), &nw_, PetscMax(2 * nnew * ta, 1), &nre, PetscMax(2 * nnew * ta, 1), &nim, PetscMax(ta, 1), &scale));
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
  PetscCall(KFFRFElasticErrors(n, t, a, fre, fim, re, im, gre, gim, r->frf_floor_db, hinf, pointwise));
  /* the pair and frequency that make hinf */
  PetscCall(KFFRFPairScales(n, t, a, fre, fim, gre, gim, scale, NULL));
  for (PetscInt f = 0; f < n; f++)
    for (PetscInt k = 0; k < ta; k++) {
      const PetscReal dre = fre[f * ta + k] - re[f * ta + k], dim = fim[f * ta + k] - im[f * ta + k], e = PetscSqrtReal(dre * dre + dim * dim) / scale[k];

      if (e > best) {
        best  = e;
        worst = k;
        fw    = f;
      }
    }
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
    *hinf = PetscMax(*hinf, PetscMax(e1, e2) / scale[worst]);
  }
  if (Trre) /* the reduced response on the point's own grid */
    for (PetscInt k = 0; k < n; k++)
      if (from[k] >= 0) {
        PetscCall(PetscArraycpy(Trre + from[k] * ta, re + k * ta, ta));
        PetscCall(PetscArraycpy(Trim + from[k] * ta, im + k * ta, ta));
      }
  PetscCall(PetscFree4(nw_, nre, nim, scale));
  PetscCall(PetscFree2(gre, gim));
  PetscCall(PetscFree4(fre, fim, re, im));
  PetscCall(PetscFree2(W, from));
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
  cand->error    = 0;
  cand->sysdofs  = 0;
  cand->complete = PETSC_TRUE;
  for (PetscInt e = 0; e < neval; e++) {
    KFReducedSystem rs;
    PetscReal       hinf;
    PetscInt        n;

    PetscCall(KFReducedModelReassemble(model, evals[e].angles, &rs));
    PetscCall(KFReducedSystemGetMatrices(rs, &n, NULL, NULL, NULL, NULL, NULL, NULL));
    cand->sysdofs = PetscMax(cand->sysdofs, n);
    PetscCall(KFEvalPointErrors_Private(r, &evals[e], rs, &hinf, NULL, NULL, NULL));
    PetscCall(KFReducedSystemDestroy(&rs));
    cand->error = PetscIsNanReal(hinf) ? PETSC_MAX_REAL : PetscMax(cand->error, hinf);
    if (stop > 0 && cand->error > stop && e < neval - 1) {
      cand->complete = PETSC_FALSE;
      break;
    }
  }
  PetscCall(KFReducedModelDestroy(&model));
  PetscFunctionReturn(0);
}
