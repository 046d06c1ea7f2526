/*
  Verification: the errors of the reassembled reduced models against the full-order reference (reference.c) and
  against the full-order moments at every angle of interest.
*/
#include <kryflex/reducerimpl.h>
/* full-order modes in the band whose peak contribution to the input/output map reaches threshold of the largest */
static PetscErrorCode KFDominantModes(const KFFullReference *ref, PetscInt t, PetscInt a, const PetscReal band[2], PetscReal zeta, PetscReal threshold, PetscInt *nd, PetscReal dom[])
{
  PetscReal top = 0, *peak;
  PetscBool any = PETSC_FALSE;

  PetscFunctionBegin;
  *nd = 0;
  PetscCall(PetscMalloc1(PetscMax(ref->n, 1), &peak));
  for (PetscInt k = 0; k < ref->n; k++) {
    PetscReal h = 0, gg = 0, f = PetscSqrtReal(ref->w2[k]) / (2 * PETSC_PI);

    for (PetscInt i = 0; i < t; i++) h += ref->HPhi[i + k * t] * ref->HPhi[i + k * t];
    for (PetscInt j = 0; j < a; j++) gg += ref->PhiG[k + j * ref->n] * ref->PhiG[k + j * ref->n];
    peak[k] = PetscSqrtReal(h) * PetscSqrtReal(gg) / (2 * zeta * ref->w2[k]);
    if (f >= band[0] && f <= band[1]) {
      top = any ? PetscMax(top, peak[k]) : peak[k];
      any = PETSC_TRUE;
    }
  }
  for (PetscInt k = 0; any && k < ref->n; k++) {
    PetscReal f = PetscSqrtReal(ref->w2[k]) / (2 * PETSC_PI);
    if (f >= band[0] && f <= band[1] && peak[k] >= threshold * top) dom[(*nd)++] = (PetscReal)k;
  }
  PetscCall(PetscFree(peak));
  PetscFunctionReturn(0);
}

static PetscReal KFMaxNotNaN(PetscInt n, const PetscReal x[])
{
  PetscReal m = 0;
  for (PetscInt i = 0; i < n; i++)
    if (!PetscIsNanReal(x[i])) m = PetscMax(m, x[i]);
  return m;
}

/* the moments of the first nmom of nfull, as KFMomentErrors wants them: nconfig blocks of nmom x t x a */
static PetscErrorCode KFMomentPrefix(PetscInt nconfig, PetscInt nfull, PetscInt nmom, PetscInt ta, const PetscReal Lfull[], PetscReal **L)
{
  PetscFunctionBegin;
  PetscCall(PetscMalloc1(PetscMax(nconfig * nmom * ta, 1), L));
  for (PetscInt c = 0; c < nconfig; c++) PetscCall(PetscArraycpy(&(*L)[c * nmom * ta], &Lfull[c * nfull * ta], nmom * ta));
  PetscFunctionReturn(0);
}

/* one model at one angle of interest: moments, frequencies, and (with a reference) its frequency-response errors;
   prefix "" for the single-angle model, "multi_" for the multi-angle one */
static PetscErrorCode KFCompareOne(KFReducer r, KFReducedModel model, const char prefix[], PetscInt c, PetscInt nmom, const PetscReal L[], KFEvalPoint *p, PetscReal *hinf, PetscInt *ndofs, PetscReal *moment_dev)
{
  PetscInt         nrev, a, t, ta, n, nrigid, nf, rank, expected;
  KFReducedSystem  rs;
  const PetscReal *lambda, *Phi, *Phir, *freq;
  PetscReal       *Lr, *errors, *ratios, sratio, num = 0, den = 0;
  const PetscInt   mshape[3] = {0, 0, nmom};
  PetscInt         shape[3];
  char             name[96], label[128];
  PetscLogDouble   t0, t1;
  const PetscBool  single = (PetscBool)!prefix[0];

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, &nrev, NULL, &a, &t));
  ta       = t * a;
  PetscCall(KFReducedModelGetInfo(model, NULL, NULL, NULL, NULL, NULL, &expected));
  PetscCall(KFReducerConfigPlace_Private(nrev, p->angles, label, sizeof(label)));
  PetscCall(PetscTime(&t0));
  PetscCall(KFReducedModelReassemble(model, p->angles, &rs));
  PetscCall(PetscTime(&t1));
  if (single) PetscCall(KFReducerResultScalar_Private(r, c, "reassembly_seconds", t1 - t0));
  PetscCall(KFReducedSystemGetMatrices(rs, &n, NULL, NULL, NULL, NULL, NULL, NULL));
  *ndofs = n;
  PetscCall(KFReducedSystemGetModes(rs, &lambda, &Phi, &nrigid, &Phir));
  if (single && !Phir) PetscCall(KFReducerNote_Private(r, "reassembled model %s: no rigid-body and mechanism modes from the bodies' rigid motions, expected %" PetscInt_FMT, label, expected));
  else if (single && nrigid != expected) PetscCall(KFReducerNote_Private(r, "reassembled model %s: %" PetscInt_FMT " rigid-body and mechanism modes from the bodies' rigid motions, expected %" PetscInt_FMT, label, nrigid, expected));
  PetscCall(PetscMalloc3(nmom * ta, &Lr, nmom, &errors, nmom * ta, &ratios));
  PetscCall(KFReducedSystemMoments(rs, nmom, Lr));
  PetscCall(KFMomentErrors(nmom, t, a, r->nconfig, L, c, Lr, r->negligible, errors, ratios));
  *moment_dev = KFMaxNotNaN(nmom, errors);
  if (single) {
    /* the single-angle model matches every moment only at alpha_G and only with the whole Krylov basis kept: say
       where it does not, with the ratio (the README says what is exact) */
    const PetscReal *rg;
    PetscReal        rdev = 0, dev = *moment_dev;

    PetscCall(KFReducerGetResult(r, -1, "reduction_config", NULL, NULL, &rg));
    if (dev > 1e-8) {
      for (PetscInt e = 0; e < nmom * ta; e++)
        if (!PetscIsNanReal(ratios[e])) rdev = PetscMax(rdev, PetscAbsReal(ratios[e] - 1));
      PetscCall(KFReducerNote_Private(r, "single-angle model %s: moments not matched exactly, max ||L_full - L_red|| / ||L_full|| = %.3e (max entrywise |L_full/L_red - 1| = %.3e)%s", label, (double)dev, (double)rdev, (nrev && (PetscInt)rg[0] == c) ? " (alpha_G)" : ""));
    }
  }
  PetscCall(PetscArraycpy(shape, mshape, 3));
  shape[0] = t;
  shape[1] = a;
  PetscCall(PetscSNPrintf(name, sizeof(name), "%sreduced_dofs", prefix));
  PetscCall(KFReducerResultScalar_Private(r, c, name, (PetscReal)n));
  PetscCall(PetscSNPrintf(name, sizeof(name), "%smoment_ratios", prefix));
  PetscCall(KFReducerResultSet_Private(r, c, name, 3, shape, ratios));
  PetscCall(PetscSNPrintf(name, sizeof(name), "%smoment_error", prefix));
  PetscCall(KFReducerResultSet_Private(r, c, name, 1, &nmom, errors));
  if (single) {
    const PetscReal *Lf = &L[c * nmom * ta];

    for (PetscInt e = 0; e < ta; e++) {
      num += (Lf[e] - Lr[e]) * (Lf[e] - Lr[e]);
      den += Lf[e] * Lf[e];
    }
    PetscCall(KFReducedSystemGetFrequencies(rs, &nf, &freq));
    PetscCall(KFReducedSystemGetReassemblyInfo(rs, &rank, &sratio));
    PetscCall(KFReducerResultSet_Private(r, c, "reduced_frequencies_hz", 1, &nf, freq));
    PetscCall(KFReducerResultSet_Private(r, c, "reduced_moments", 3, shape, Lr));
    PetscCall(KFReducerResultScalar_Private(r, c, "static_gain_error", PetscSqrtReal(num) / PetscSqrtReal(den)));
    PetscCall(KFReducerResultScalar_Private(r, c, "reassembly_rank", (PetscReal)rank));
    PetscCall(KFReducerResultScalar_Private(r, c, "reassembly_sigma_ratio", sratio));
  }
  *hinf = (PetscReal)NAN;
  if (p->w) {
    PetscReal *Trre, *Trim, pw;

    PetscCall(PetscMalloc2(p->nw * ta, &Trre, p->nw * ta, &Trim));
    PetscCall(KFEvalPointErrors_Private(r, p, rs, hinf, &pw, Trre, Trim));
    shape[2] = p->nw;
    if (single) {
      PetscCall(KFReducerResultSet_Private(r, c, "frf_frequencies_hz", 1, &p->nw, p->fhz));
      PetscCall(KFReducerResultSet_Private(r, c, "frf_full_re", 3, shape, p->Tre));
      PetscCall(KFReducerResultSet_Private(r, c, "frf_full_im", 3, shape, p->Tim));
      PetscCall(KFReducerResultSet_Private(r, c, "frf_reduced_re", 3, shape, Trre));
      PetscCall(KFReducerResultSet_Private(r, c, "frf_reduced_im", 3, shape, Trim));
      PetscCall(KFReducerResultScalar_Private(r, c, "error_reference", p->rich ? 1.0 : 0.0));
      if (!p->rich) {
        PetscInt   nd;
        PetscReal *ff, *dom, *domerr;

        PetscCall(PetscMalloc3(PetscMax(p->ref.n, 1), &ff, PetscMax(p->ref.n, 1), &dom, PetscMax(p->ref.n, 1), &domerr));
        for (PetscInt k = 0; k < p->ref.n; k++) ff[k] = PetscSqrtReal(p->ref.w2[k]) / (2 * PETSC_PI);
        PetscCall(KFReducerResultSet_Private(r, c, "full_frequencies_hz", 1, &p->ref.n, ff));
        if (p->ref.count >= 0) {
          PetscCall(KFReducerResultScalar_Private(r, c, "full_order_mode_count", (PetscReal)p->ref.count));
          PetscCall(KFReducerResultScalar_Private(r, c, "full_order_mode_count_below_hz", p->ref.count_hz));
        }
        PetscCall(KFDominantModes(&p->ref, t, a, r->band, r->zeta, 0.05, &nd, dom));
        PetscCall(KFReducedSystemGetFrequencies(rs, &nf, &freq));
        for (PetscInt k = 0; k < nd; k++) {
          PetscReal fk = ff[(PetscInt)dom[k]], best = PETSC_MAX_REAL;
          for (PetscInt i = 0; i < nf; i++) best = PetscMin(best, PetscAbsReal(freq[i] - fk) / fk);
          domerr[k] = nf ? best : (PetscReal)NAN;
        }
        PetscCall(KFReducerResultSet_Private(r, c, "dominant_modes", 1, &nd, dom));
        PetscCall(KFReducerResultSet_Private(r, c, "dominant_frequency_error", 1, &nd, domerr));
        if (p->ref.n) { /* the Hankel lower bound of the flexible part (the modes computed) */
          PetscReal *hsv, top = 0;
          PetscInt   ns = 2 * p->ref.n, order = ns;

          PetscCall(PetscMalloc1(ns, &hsv));
          PetscCall(KFModalHankelSingularValues(p->ref.n, p->ref.w2, t, p->ref.HPhi, a, p->ref.PhiG, r->zeta, hsv));
          for (PetscInt f = 0; f < p->nw; f++)
            for (PetscInt k = 0; k < ta; k++) top = PetscMax(top, PetscSqrtReal(p->Tre[f * ta + k] * p->Tre[f * ta + k] + p->Tim[f * ta + k] * p->Tim[f * ta + k]));
          /* a model whose every pair is within accuracy x its peak (<= top) has a 2-norm error below
             sqrt(t a) accuracy top; no model of first-order order k has one below hsv[k] */
          for (PetscInt k = 0; k < ns; k++)
            if (hsv[k] <= PetscSqrtReal((PetscReal)ta) * r->accuracy * top) {
              order = k;
              break;
            }
          PetscCall(KFReducerResultSet_Private(r, c, "hankel_singular_values", 1, &ns, hsv));
          PetscCall(KFReducerResultScalar_Private(r, c, "hankel_order", (PetscReal)order));
          PetscCall(PetscFree(hsv));
        }
        PetscCall(PetscFree3(ff, dom, domerr));
      }
    }
    PetscCall(PetscSNPrintf(name, sizeof(name), "%sfrf_error", prefix));
    PetscCall(KFReducerResultScalar_Private(r, c, name, *hinf));
    PetscCall(PetscSNPrintf(name, sizeof(name), "%sfrf_pointwise_error", prefix));
    PetscCall(KFReducerResultScalar_Private(r, c, name, pw));
    PetscCall(PetscFree2(Trre, Trim));
  }
  PetscCall(PetscFree3(Lr, errors, ratios));
  PetscCall(KFReducedSystemDestroy(&rs));
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerCompare_Private(KFReducer r, PetscInt nfull, const PetscReal Lfull[], PetscInt neval, KFEvalPoint evals[])
{
  MPI_Comm         comm;
  PetscInt         nrev, nrev1, a, t, ta, msingle = nfull, mmulti = nfull, nmid = neval - r->nconfig, ndofs;
  PetscReal       *Ls, *Lm = NULL, worst = 0, dev;
  const PetscReal *v;
  KFReducedModel   chosen;
  PetscBool        measured = PETSC_FALSE, estimated = PETSC_FALSE;
  char             label[128], place[160], where[160] = "";

  PetscFunctionBegin;
  PetscCall(PetscObjectGetComm((PetscObject)r, &comm));
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, &nrev, NULL, &a, &t));
  nrev1 = PetscMax(nrev, 1);
  ta    = t * a;
  PetscCall(KFReducerGetResult(r, -1, "moments_matched", NULL, NULL, &v));
  msingle = PetscMin((PetscInt)v[0], nfull);
  PetscCall(KFMomentPrefix(r->nconfig, nfull, msingle, ta, Lfull, &Ls));
  if (r->multi_model) {
    PetscCall(KFReducerGetResult(r, -1, "multi_moments_matched", NULL, NULL, &v));
    mmulti = PetscMin((PetscInt)v[0], nfull);
    PetscCall(KFMomentPrefix(r->nconfig, nfull, mmulti, ta, Lfull, &Lm));
  }
  chosen = r->chosen == KF_METHOD_MULTI_ANGLE && r->multi_model ? r->multi_model : r->single;
  for (PetscInt c = 0; c < r->nconfig; c++) {
    PetscReal hinf, mh = (PetscReal)NAN;
    PetscInt  nm = 0;
    char      frfpart[96] = "";

    PetscCall(KFReducerConfigLabel_Private(nrev, evals[c].angles, label, sizeof(label)));
    PetscCall(KFReducerConfigPlace_Private(nrev, evals[c].angles, place, sizeof(place)));
    if (!nrev) PetscCall(PetscStrncpy(label, "the structure", sizeof(label)));
    else PetscCall(PetscStrlcat(label, " deg", sizeof(label)));
    PetscCall(KFCompareOne(r, r->single, "", c, msingle, Ls, &evals[c], &hinf, &ndofs, &dev));
    if (r->multi_model) PetscCall(KFCompareOne(r, r->multi_model, "multi_", c, mmulti, Lm, &evals[c], &mh, &nm, &dev));
    if (evals[c].w) {
      const PetscReal e = r->chosen == KF_METHOD_MULTI_ANGLE && r->multi_model ? mh : hinf;

      measured  = PETSC_TRUE;
      estimated = (PetscBool)(estimated || evals[c].rich);
      if (!(e <= worst)) {
        worst = e;
        PetscCall(PetscStrncpy(where, place, sizeof(where)));
      }
      PetscCall(PetscSNPrintf(frfpart, sizeof(frfpart), ", FRF rel. H-inf error %.3g%s", (double)hinf, evals[c].rich ? " (estimated)" : ""));
    }
    PetscCall(KFProgress(comm, "  %s: single-angle model %" PetscInt_FMT " system dofs%s%s", label, ndofs, frfpart, r->multi_model ? "" : ""));
    if (r->multi_model && evals[c].w) PetscCall(KFProgress(comm, "  %s: multi-angle model %" PetscInt_FMT " system dofs, FRF rel. H-inf error %.3g", label, nm, (double)mh));
  }
  if (nmid) { /* the chosen model between the angles of interest */
    PetscReal     *ang, *err;
    const PetscInt shape[2] = {nrev1, nmid};

    PetscCall(PetscMalloc2(nrev1 * nmid, &ang, nmid, &err));
    for (PetscInt m = 0; m < nmid; m++) {
      KFEvalPoint    *p = &evals[r->nconfig + m];
      KFReducedSystem rs;

      PetscCall(PetscArraycpy(&ang[m * nrev1], p->angles, nrev1));
      err[m] = (PetscReal)NAN;
      if (!p->w) continue;
      PetscCall(KFReducedModelReassemble(chosen, p->angles, &rs));
      PetscCall(KFEvalPointErrors_Private(r, p, rs, &err[m], NULL, NULL, NULL));
      PetscCall(KFReducedSystemDestroy(&rs));
      if (!(err[m] <= worst)) {
        worst = err[m];
        PetscCall(KFReducerConfigPlace_Private(nrev, p->angles, where, sizeof(where)));
        PetscCall(PetscStrlcat(where, " (midpoint)", sizeof(where)));
      }
    }
    PetscCall(KFReducerResultSet_Private(r, -1, "midpoint_angles", 2, shape, ang));
    PetscCall(KFReducerResultSet_Private(r, -1, "midpoint_frf_error", 1, &nmid, err));
    PetscCall(PetscFree2(ang, err));
  }
  PetscCall(KFReducerResultScalar_Private(r, -1, "chosen_method", (PetscReal)(r->chosen == KF_METHOD_MULTI_ANGLE && r->multi_model ? 1 : 0)));
  if (measured) {
    PetscCall(KFReducerResultScalar_Private(r, -1, "error_max", worst));
    PetscCall(KFReducerResultScalar_Private(r, -1, "error_estimated", estimated ? 1.0 : 0.0));
    PetscCall(KFReducerResultScalar_Private(r, -1, "target_met", worst <= r->accuracy ? 1.0 : 0.0));
    PetscCall(KFProgress(comm, "the %s model: max relative H-inf error %.3g %s (target %g)%s", r->chosen == KF_METHOD_MULTI_ANGLE && r->multi_model ? "multi-angle" : "single-angle", (double)worst, where, (double)r->accuracy, estimated ? ", estimated" : ""));
    if (!(worst <= r->accuracy)) PetscCall(KFReducerNote_Private(r, "the accuracy target %g is not met: the best model found has relative H-inf error %.3g %s; raise -kf_moments_max, loosen the accuracy or narrow the band", (double)r->accuracy, (double)worst, where));
  }
  PetscCall(PetscFree(Ls));
  PetscCall(PetscFree(Lm));
  PetscFunctionReturn(0);
}
