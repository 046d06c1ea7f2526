/*
  Verification: the full-order reference at a configuration (SLEPc modes covering verify_cover x the band's top, the
  rigid modes' participation, the static residual of the modes not computed), and the errors of the reassembled
  reduced models against it and against the full-order moments at every angle of interest.
*/
#include <kryflex/reducerimpl.h>

PetscErrorCode KFReducerFullReference_Private(KFReducer r, KFSystem sys, KFFullReference *ref)
{
  PetscInt   nrev, nsys, a, t, nflex, nev, nconv;
  PetscReal *w2, *HPhi, *PhiG, fmax = r->verify_cover * r->band[1];

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, &nrev, &nsys, &a, &t));
  nflex = nsys - 6 - nrev;
  PetscCheck(nflex >= 1, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_WRONG, "the scene has no flexible modes to verify (%" PetscInt_FMT " system dofs, %" PetscInt_FMT " rigid-body and mechanism modes): switch verification off (-kf_verify 0)", nsys, 6 + nrev);
  nev = PetscMin(nflex, r->verify_modes == PETSC_DECIDE ? 20 : r->verify_modes);
  while (PETSC_TRUE) { /* double the count until the modes cover fmax */
    PetscCall(PetscMalloc3(nev, &w2, t * nev, &HPhi, nev * a, &PhiG));
    PetscCall(KFSystemEigen(sys, nev, &nconv, w2, HPhi, PhiG));
    if (r->verify_modes != PETSC_DECIDE || nev >= nflex || (nconv && PetscSqrtReal(w2[nconv - 1]) / (2 * PETSC_PI) >= fmax)) break;
    PetscCall(PetscFree3(w2, HPhi, PhiG));
    nev = PetscMin(nflex, 2 * nev);
  }
  ref->n = nconv;
  PetscCall(PetscMalloc3(PetscMax(nconv, 1), &ref->w2, PetscMax(t * nconv, 1), &ref->HPhi, PetscMax(nconv * a, 1), &ref->PhiG));
  PetscCall(PetscArraycpy(ref->w2, w2, nconv));
  PetscCall(PetscArraycpy(ref->HPhi, HPhi, t * nconv));
  for (PetscInt j = 0; j < a; j++) /* PhiG comes with leading dimension nev */
    for (PetscInt i = 0; i < nconv; i++) ref->PhiG[i + j * nconv] = PhiG[i + j * nev];
  PetscCall(PetscFree3(w2, HPhi, PhiG));
  PetscCall(KFSystemRigidIO(sys, &ref->r, NULL, NULL));
  PetscCall(PetscMalloc2(PetscMax(t * ref->r, 1), &ref->HPr, PetscMax(ref->r * a, 1), &ref->PrG));
  PetscCall(KFSystemRigidIO(sys, &ref->r, ref->HPr, ref->PrG));
  PetscFunctionReturn(0);
}

PetscErrorCode KFFullReferenceDestroy_Private(KFFullReference *ref)
{
  PetscFunctionBegin;
  if (!ref->w2) PetscFunctionReturn(0);
  PetscCall(PetscFree3(ref->w2, ref->HPhi, ref->PhiG));
  PetscCall(PetscFree2(ref->HPr, ref->PrG));
  PetscCall(PetscMemzero(ref, sizeof(*ref)));
  PetscFunctionReturn(0);
}

/* Full-order response: rigid modes, computed flexible modes, and the static residual L^0 - sum_i H phi_i phi_i^T G /
   omega_i^2 of the modes not computed. Tre, Tim: nw blocks of t x a. */
static PetscErrorCode KFFullFRF(const KFFullReference *ref, PetscInt t, PetscInt a, const PetscReal L0[], PetscReal zeta, PetscInt nw, const PetscReal w[], PetscReal Tre[], PetscReal Tim[])
{
  const PetscInt n = ref->r + ref->n;
  PetscReal     *lam, *HPhi, *PhiG, *resid;

  PetscFunctionBegin;
  PetscCall(PetscMalloc4(n, &lam, t * n, &HPhi, n * a, &PhiG, t * a, &resid));
  for (PetscInt k = 0; k < n; k++) lam[k] = k < ref->r ? 0 : ref->w2[k - ref->r];
  PetscCall(PetscArraycpy(HPhi, ref->HPr, t * ref->r));
  PetscCall(PetscArraycpy(HPhi + t * ref->r, ref->HPhi, t * ref->n));
  for (PetscInt j = 0; j < a; j++) {
    for (PetscInt k = 0; k < ref->r; k++) PhiG[k + j * n] = ref->PrG[k + j * ref->r];
    for (PetscInt k = 0; k < ref->n; k++) PhiG[ref->r + k + j * n] = ref->PhiG[k + j * ref->n];
  }
  PetscCall(KFModalFRF(n, lam, t, HPhi, a, PhiG, zeta, 1e-300, nw, w, Tre, Tim));
  for (PetscInt j = 0; j < a; j++)
    for (PetscInt i = 0; i < t; i++) {
      PetscReal s = L0[i + j * t];
      for (PetscInt k = 0; k < ref->n; k++) s -= ref->HPhi[i + k * t] / ref->w2[k] * ref->PhiG[k + j * ref->n];
      resid[i + j * t] = s;
    }
  for (PetscInt f = 0; f < nw; f++)
    for (PetscInt e = 0; e < t * a; e++) Tre[f * t * a + e] += resid[e];
  PetscCall(PetscFree4(lam, HPhi, PhiG, resid));
  PetscFunctionReturn(0);
}

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

PetscErrorCode KFReducerCompare_Private(KFReducer r, const PetscReal Lfull[], KFFullReference ref[])
{
  MPI_Comm       comm;
  PetscInt       nrev, nrev1, a, t, nmom = r->moments, ta, expected;
  PetscReal     *Lr, *errors, *ratios, max_multi_err = 0;
  PetscInt       max_multi_dofs = 0;

  PetscFunctionBegin;
  PetscCall(PetscObjectGetComm((PetscObject)r, &comm));
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, &nrev, NULL, &a, &t));
  nrev1    = PetscMax(nrev, 1);
  ta       = t * a;
  expected = 6 + nrev;
  PetscCall(PetscMalloc3(nmom * ta, &Lr, nmom, &errors, nmom * ta, &ratios));
  for (PetscInt c = 0; c < r->nconfig; c++) {
    const PetscReal *angles = &r->angles[c * nrev1], *Lf = &Lfull[c * nmom * ta];
    const PetscInt   mshape[3] = {t, a, nmom};
    KFReducedSystem  rs;
    const PetscReal *lambda, *Phi, *Phir, *freq;
    PetscInt         nrigid, nf, rank, n;
    PetscReal        sratio, dev = 0, sgain, num = 0, den = 0, dofs;
    PetscLogDouble   t0, t1;
    char             label[128], frfpart[96] = "";

    PetscCall(KFReducerConfigLabel_Private(nrev, angles, label, sizeof(label)));
    PetscCall(PetscTime(&t0));
    PetscCall(KFReducedModelReassemble(r->single, angles, &rs));
    PetscCall(PetscTime(&t1));
    PetscCall(KFReducerResultScalar_Private(r, c, "reassembly_seconds", t1 - t0));
    PetscCall(KFReducedSystemGetMatrices(rs, &n, NULL, NULL, NULL, NULL, NULL, NULL));
    PetscCall(KFReducedSystemGetModes(rs, &lambda, &Phi, &nrigid, &Phir));
    if (!Phir) PetscCall(KFReducerNote_Private(r, "reassembled model at %s deg: no rigid-body and mechanism modes from the bodies' rigid motions, expected %" PetscInt_FMT, label, expected));
    else if (nrigid != expected) PetscCall(KFReducerNote_Private(r, "reassembled model at %s deg: %" PetscInt_FMT " rigid-body and mechanism modes from the bodies' rigid motions, expected %" PetscInt_FMT, label, nrigid, expected));
    PetscCall(KFReducedSystemGetFrequencies(rs, &nf, &freq));
    PetscCall(KFReducedSystemMoments(rs, nmom, Lr));
    PetscCall(KFMomentErrors(nmom, t, a, r->nconfig, Lfull, c, Lr, r->negligible, errors, ratios));
    for (PetscInt e = 0; e < ta; e++) {
      num += (Lf[e] - Lr[e]) * (Lf[e] - Lr[e]);
      den += Lf[e] * Lf[e];
    }
    sgain = PetscSqrtReal(num) / PetscSqrtReal(den);
    PetscCall(KFReducedSystemGetReassemblyInfo(rs, &rank, &sratio));
    dofs = (PetscReal)n;
    PetscCall(KFReducerResultScalar_Private(r, c, "reduced_dofs", dofs));
    PetscCall(KFReducerResultSet_Private(r, c, "reduced_frequencies_hz", 1, &nf, freq));
    PetscCall(KFReducerResultSet_Private(r, c, "reduced_moments", 3, mshape, Lr));
    PetscCall(KFReducerResultSet_Private(r, c, "moment_ratios", 3, mshape, ratios));
    PetscCall(KFReducerResultSet_Private(r, c, "moment_error", 1, &nmom, errors));
    PetscCall(KFReducerResultScalar_Private(r, c, "static_gain_error", sgain));
    PetscCall(KFReducerResultScalar_Private(r, c, "reassembly_rank", (PetscReal)rank));
    PetscCall(KFReducerResultScalar_Private(r, c, "reassembly_sigma_ratio", sratio));
    dev = KFMaxNotNaN(nmom, errors);
    if (dev > 1e-8) {
      const PetscReal *rg;
      PetscInt         gi;

      PetscCall(KFReducerGetResult(r, -1, "reduction_config", NULL, NULL, &rg));
      gi = (PetscInt)rg[0];
      PetscReal        rdev = 0;

      for (PetscInt e = 0; e < nmom * ta; e++)
        if (!PetscIsNanReal(ratios[e])) rdev = PetscMax(rdev, PetscAbsReal(ratios[e] - 1));
      PetscCall(KFReducerNote_Private(r, "single-angle model at %s deg: moments not matched exactly, max ||L_full - L_red|| / ||L_full|| = %.3e (max entrywise |L_full/L_red - 1| = %.3e)%s", label, (double)dev, (double)rdev, gi == c ? " (alpha_G)" : ""));
    }
    if (r->verify && ref[c].w2) {
      PetscInt   nw, nd;
      PetscReal *ff, *fgrid, *w, *Tfre, *Tfim, *Trre, *Trim, err, *dom, *domerr;
      const PetscInt fshape[3] = {t, a, 0};
      PetscInt   shape[3];

      PetscCall(PetscMalloc1(PetscMax(ref[c].n, 1), &ff));
      for (PetscInt k = 0; k < ref[c].n; k++) ff[k] = PetscSqrtReal(ref[c].w2[k]) / (2 * PETSC_PI);
      PetscCall(PetscMalloc1(r->frequency_points + 7 * ref[c].n, &fgrid));
      PetscCall(KFFrequencyGrid(r->band[0], r->band[1], r->frequency_points, ref[c].n, ff, r->zeta, &nw, fgrid));
      PetscCall(PetscMalloc5(nw, &w, nw * ta, &Tfre, nw * ta, &Tfim, nw * ta, &Trre, nw * ta, &Trim));
      for (PetscInt f = 0; f < nw; f++) w[f] = 2 * PETSC_PI * fgrid[f];
      PetscCall(KFFullFRF(&ref[c], t, a, Lf, r->zeta, nw, w, Tfre, Tfim));
      PetscCall(KFReducedSystemFRF(rs, r->zeta, nw, w, Trre, Trim));
      PetscCall(KFFRFError(nw, t, a, Tfre, Tfim, Trre, Trim, r->frf_floor_db, &err));
      PetscCall(KFReducerResultSet_Private(r, c, "full_frequencies_hz", 1, &ref[c].n, ff));
      PetscCall(KFReducerResultSet_Private(r, c, "frf_frequencies_hz", 1, &nw, fgrid));
      PetscCall(PetscArraycpy(shape, fshape, 3));
      shape[2] = nw;
      PetscCall(KFReducerResultSet_Private(r, c, "frf_full_re", 3, shape, Tfre));
      PetscCall(KFReducerResultSet_Private(r, c, "frf_full_im", 3, shape, Tfim));
      PetscCall(KFReducerResultSet_Private(r, c, "frf_reduced_re", 3, shape, Trre));
      PetscCall(KFReducerResultSet_Private(r, c, "frf_reduced_im", 3, shape, Trim));
      PetscCall(KFReducerResultScalar_Private(r, c, "frf_error", err));
      PetscCall(PetscMalloc2(PetscMax(ref[c].n, 1), &dom, PetscMax(ref[c].n, 1), &domerr));
      PetscCall(KFDominantModes(&ref[c], t, a, r->band, r->zeta, r->keep_threshold, &nd, dom));
      for (PetscInt k = 0; k < nd; k++) {
        PetscReal fk = ff[(PetscInt)dom[k]], best = PETSC_MAX_REAL;
        for (PetscInt i = 0; i < nf; i++) best = PetscMin(best, PetscAbsReal(freq[i] - fk) / fk);
        domerr[k] = nf ? best : (PetscReal)NAN;
      }
      PetscCall(KFReducerResultSet_Private(r, c, "dominant_modes", 1, &nd, dom));
      PetscCall(KFReducerResultSet_Private(r, c, "dominant_frequency_error", 1, &nd, domerr));
      PetscCall(PetscSNPrintf(frfpart, sizeof(frfpart), ", FRF max rel. error %.3g", (double)err));
      PetscCall(PetscFree2(dom, domerr));
      PetscCall(PetscFree5(w, Tfre, Tfim, Trre, Trim));
      PetscCall(PetscFree(fgrid));
      PetscCall(PetscFree(ff));
    }
    PetscCall(KFProgress(comm, "  %s deg: reduced system %" PetscInt_FMT " dofs, moment error %.2e, static gain error %.2e%s", label, n, (double)dev, (double)sgain, frfpart));
    PetscCall(KFReducedSystemDestroy(&rs));

    if (r->multi_model) {
      PetscReal merr;

      PetscCall(KFReducedModelReassemble(r->multi_model, angles, &rs));
      PetscCall(KFReducedSystemGetMatrices(rs, &n, NULL, NULL, NULL, NULL, NULL, NULL));
      PetscCall(KFReducedSystemMoments(rs, nmom, Lr));
      PetscCall(KFMomentErrors(nmom, t, a, r->nconfig, Lfull, c, Lr, r->negligible, errors, ratios));
      PetscCall(KFReducerResultScalar_Private(r, c, "multi_reduced_dofs", (PetscReal)n));
      PetscCall(KFReducerResultSet_Private(r, c, "multi_moment_ratios", 3, mshape, ratios));
      PetscCall(KFReducerResultSet_Private(r, c, "multi_moment_error", 1, &nmom, errors));
      max_multi_dofs = PetscMax(max_multi_dofs, n);
      max_multi_err  = PetscMax(max_multi_err, KFMaxNotNaN(nmom, errors));
      if (r->verify && ref[c].w2) {
        PetscInt         ndim;
        const PetscInt  *shape;
        const PetscReal *fgrid, *Tfre, *Tfim;
        PetscReal       *w, *Trre, *Trim;

        PetscCall(KFReducerGetResult(r, c, "frf_frequencies_hz", &ndim, &shape, &fgrid));
        {
          const PetscInt nw = shape[0];

          PetscCall(KFReducerGetResult(r, c, "frf_full_re", NULL, NULL, &Tfre));
          PetscCall(KFReducerGetResult(r, c, "frf_full_im", NULL, NULL, &Tfim));
          PetscCall(PetscMalloc3(nw, &w, nw * ta, &Trre, nw * ta, &Trim));
          for (PetscInt f = 0; f < nw; f++) w[f] = 2 * PETSC_PI * fgrid[f];
          PetscCall(KFReducedSystemFRF(rs, r->zeta, nw, w, Trre, Trim));
          PetscCall(KFFRFError(nw, t, a, Tfre, Tfim, Trre, Trim, r->frf_floor_db, &merr));
          PetscCall(KFReducerResultScalar_Private(r, c, "multi_frf_error", merr));
          PetscCall(PetscFree3(w, Trre, Trim));
        }
      }
      PetscCall(KFReducedSystemDestroy(&rs));
    }
  }
  if (r->multi_model) {
    char sizes[256];

    PetscCall(KFReducerModelSizes_Private(r->multi_model, sizes, sizeof(sizes)));
    PetscCall(KFProgress(comm, "multi-angle model: %s dofs per body, reassembled %" PetscInt_FMT " dofs, max moment error %.2e", sizes, max_multi_dofs, (double)max_multi_err));
  }
  PetscCall(PetscFree3(Lr, errors, ratios));
  PetscFunctionReturn(0);
}
