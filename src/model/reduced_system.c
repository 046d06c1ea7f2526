/* The reduced system at one configuration: getters, moments, frequency response, view. */
#include <kryflex/modelimpl.h>
#include "../dense/dense_impl.h"

static PetscErrorCode KFReducedSystemModalIO(KFReducedSystem);

PetscErrorCode KFReducedSystemDestroy(KFReducedSystem *system)
{
  KFReducedSystem y = *system;

  PetscFunctionBegin;
  if (!y) PetscFunctionReturn(0);
  PetscCall(PetscFree4(y->M, y->K, y->G, y->H));
  PetscCall(PetscFree(y->Phir));
  PetscCall(PetscFree2(y->lambda, y->Phi));
  PetscCall(PetscFree(y->freq));
  PetscCall(PetscFree2(y->HPhi, y->PhiG));
  PetscCall(PetscFree(y->quantity));
  PetscCall(PetscFree(y->C));
  PetscCall(PetscFree(y->Cm));
  PetscCall(PetscFree(y->D));
  PetscCall(PetscFree(y));
  *system = NULL;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducedSystemGetMatrices(KFReducedSystem y, PetscInt *n, PetscInt *a, PetscInt *t, const PetscReal **M, const PetscReal **K, const PetscReal **G, const PetscReal **H)
{
  PetscFunctionBegin;
  PetscValidPointer(y, 1);
  if (n) *n = y->n;
  if (a) *a = y->a;
  if (t) *t = y->t;
  if (M) *M = y->M;
  if (K) *K = y->K;
  if (G) *G = y->G;
  if (H) *H = y->H;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducedSystemGetModes(KFReducedSystem y, const PetscReal **lambda, const PetscReal **Phi, PetscInt *nrigid, const PetscReal **Phir)
{
  PetscFunctionBegin;
  PetscValidPointer(y, 1);
  if (lambda) *lambda = y->lambda;
  if (Phi) *Phi = y->Phi;
  if (nrigid) *nrigid = y->nrigid;
  if (Phir) *Phir = y->Phir;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducedSystemGetReassemblyInfo(KFReducedSystem y, PetscInt *rank, PetscReal *sratio)
{
  PetscFunctionBegin;
  PetscValidPointer(y, 1);
  if (rank) *rank = y->rank;
  if (sratio) *sratio = y->sratio;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducedSystemGetFrequencies(KFReducedSystem y, PetscInt *nf, const PetscReal **freq_hz)
{
  PetscFunctionBegin;
  PetscValidPointer(y, 1);
  if (nf) *nf = y->nf;
  if (freq_hz) *freq_hz = y->freq;
  PetscFunctionReturn(0);
}

/*
  KFReducedSystemMoments - L^k = H (K+ M)^k K+ G on the flexible subspace, k = 0..nmom-1. With the geometric rigid
  modes (Phir) of the expected count, by solves with them (KFDenseMomentsRigid: keeps the digits a stiff model
  loses in an eigendecomposition); otherwise from the eigenpairs with the rigid tolerance of KFRigidTolerance.
*/
PetscErrorCode KFReducedSystemMoments(KFReducedSystem y, PetscInt nmom, PetscReal L[])
{
  PetscFunctionBegin;
  PetscValidPointer(y, 1);
  PetscCheck(nmom >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "KFReducedSystemMoments: negative number of moments %" PetscInt_FMT, nmom);
  if (y->phir_known && y->nrigid == y->nrigid_expected) {
    PetscCall(KFDenseMomentsRigid(y->n, y->K, y->M, y->a, y->G, y->t, y->H, y->nrigid, y->Phir, nmom, L));
  } else {
    PetscReal rtol;
    PetscCall(KFRigidTolerance(y->n, y->lambda, y->nrigid, &rtol));
    PetscCall(KFDenseMoments(y->n, y->K, y->M, y->a, y->G, y->t, y->H, rtol, nmom, L));
  }
  /* a trimmed system: the trimmed modes' static share (KFReducedSystemTrim) */
  if (y->D && nmom > 0)
    for (PetscInt e = 0; e < y->t * y->a; e++) L[e] += y->D[e];
  PetscFunctionReturn(0);
}

/*
  KFReducedSystemFRF - modal frequency response with uniform modal damping zeta at nw frequencies w (rad/s),
  Tre/Tim: nw blocks of t x a; the nrigid lowest modes are undamped rigid modes (KFRigidTolerance).
*/
PetscErrorCode KFReducedSystemFRF(KFReducedSystem y, PetscReal zeta, PetscInt nw, const PetscReal w[], PetscReal Tre[], PetscReal Tim[])
{
  PetscReal rtol;

  PetscFunctionBegin;
  PetscValidPointer(y, 1);
  PetscCall(KFReducedSystemModalIO(y));
  PetscCall(KFRigidTolerance(y->n, y->lambda, y->nrigid, &rtol));
  PetscCall(KFModalFRF(y->n, y->lambda, y->t, y->HPhi, y->a, y->PhiG, zeta, rtol, nw, w, Tre, Tim));
  PetscCall(KFReducedSystemAddFeedthrough_Private(y, NULL, nw, w, Tre, Tim));
  PetscFunctionReturn(0);
}

/* H Phi and Phi^T G, made once */
static PetscErrorCode KFReducedSystemModalIO(KFReducedSystem y)
{
  PetscFunctionBegin;
  if (!y->HPhi) {
    PetscCall(PetscMalloc2(y->t * y->n, &y->HPhi, y->n * y->a, &y->PhiG));
    PetscCall(KFDenseGemm_Private('N', 'N', y->t, y->n, y->n, 1.0, y->H, y->t, y->Phi, y->n, 0.0, y->HPhi, y->t));
    PetscCall(KFDenseGemm_Private('T', 'N', y->n, y->a, y->n, 1.0, y->Phi, y->n, y->G, y->n, 0.0, y->PhiG, y->n));
  }
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducedSystemGetDamping(KFReducedSystem y, const PetscReal **C, KFDamping *d)
{
  PetscFunctionBegin;
  PetscValidPointer(y, 1);
  if (C) *C = y->C;
  if (d) *d = y->damping;
  PetscFunctionReturn(0);
}

/*
  KFReducedSystemResponse - the frequency response with the model's damping: modal ratios on the reduced model's own
  modes, Rayleigh and the reassembled viscous matrix through Phi^T C Phi (all modes coupled: the reduced model is
  small), structural damping, and the outputs' quantities (KFDampedModalFRF).
*/
PetscErrorCode KFReducedSystemResponse(KFReducedSystem y, PetscInt nw, const PetscReal w[], PetscReal Tre[], PetscReal Tim[])
{
  PetscReal rtol;
  KFDamping d;

  PetscFunctionBegin;
  PetscValidPointer(y, 1);
  PetscCall(KFReducedSystemModalIO(y));
  d = y->damping;
  if (y->C && !y->Cm) {
    PetscReal *W;
    PetscCall(PetscMalloc1(y->n * y->n, &y->Cm));
    PetscCall(PetscMalloc1(y->n * y->n, &W));
    PetscCall(KFDenseGemm_Private('N', 'N', y->n, y->n, y->n, 1.0, y->C, y->n, y->Phi, y->n, 0.0, W, y->n));
    PetscCall(KFDenseGemm_Private('T', 'N', y->n, y->n, y->n, 1.0, y->Phi, y->n, W, y->n, 0.0, y->Cm, y->n));
    PetscCall(PetscFree(W));
  }
  /* Rayleigh is inside C (y->C = C_bodies + alpha M + beta K): not twice */
  if (y->C) d.alpha = d.beta = 0;
  PetscCall(KFRigidTolerance(y->n, y->lambda, y->nrigid, &rtol));
  PetscCall(KFDampedModalFRF(y->n, y->lambda, y->t, y->HPhi, y->a, y->PhiG, &d, y->Cm, y->n, y->quantity, rtol, nw, w, Tre, Tim));
  PetscCall(KFReducedSystemAddFeedthrough_Private(y, y->quantity, nw, w, Tre, Tim));
  PetscFunctionReturn(0);
}

/*
  KFReducedSystemRigidResponse - the rigid-body and mechanism part of KFReducedSystemResponse: the nrigid lowest modes
  (the bodies' geometric rigid motions when known, eigenvalue zero) with the same damping model (their block of
  Phi^T C Phi, the modal ratios that are zero for them, structural damping that is zero on them) and quantities.
*/
PetscErrorCode KFReducedSystemRigidResponse(KFReducedSystem y, PetscInt nw, const PetscReal w[], PetscReal Tre[], PetscReal Tim[])
{
  const PetscInt nr = PetscMin(y ? y->nrigid : 0, y ? y->n : 0);
  PetscReal     *lam, *PrG, *Crr = NULL;
  KFDamping      d;

  PetscFunctionBegin;
  PetscValidPointer(y, 1);
  PetscCall(KFReducedSystemResponse(y, 0, NULL, NULL, NULL)); /* H Phi, Phi^T G and Phi^T C Phi made */
  d = y->damping;
  if (y->C) d.alpha = d.beta = 0;
  PetscCall(PetscCalloc2(PetscMax(nr, 1), &lam, PetscMax(nr * y->a, 1), &PrG));
  for (PetscInt j = 0; j < y->a; j++)
    for (PetscInt k = 0; k < nr; k++) PrG[k + j * nr] = y->PhiG[k + j * y->n];
  if (y->Cm && nr) {
    PetscCall(PetscMalloc1(nr * nr, &Crr));
    for (PetscInt j = 0; j < nr; j++)
      for (PetscInt i = 0; i < nr; i++) Crr[i + j * nr] = y->Cm[i + j * y->n];
  }
  PetscCall(KFDampedModalFRF(nr, lam, y->t, y->HPhi, y->a, PrG, &d, Crr, nr, y->quantity, 0, nw, w, Tre, Tim));
  PetscCall(PetscFree(Crr));
  PetscCall(PetscFree2(lam, PrG));
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducedSystemView(KFReducedSystem y, PetscViewer viewer)
{
  PetscBool iascii;

  PetscFunctionBegin;
  PetscValidPointer(y, 1);
  if (!viewer) PetscCall(PetscViewerASCIIGetStdout(PETSC_COMM_SELF, &viewer));
  PetscCall(PetscObjectTypeCompare((PetscObject)viewer, PETSCVIEWERASCII, &iascii));
  if (!iascii) PetscFunctionReturn(0);
  PetscCall(PetscViewerASCIIPrintf(viewer, "KFReducedSystem: %" PetscInt_FMT " dofs (%" PetscInt_FMT " rigid-body and mechanism modes%s), %" PetscInt_FMT " inputs, %" PetscInt_FMT " outputs\n", y->n, y->nrigid, y->phir_known ? "" : ", assumed: the bodies' rigid motions are unknown", y->a, y->t));
  PetscCall(PetscViewerASCIIPushTab(viewer));
  PetscCall(PetscViewerASCIIPrintf(viewer, "interface constraints: rank %" PetscInt_FMT ", sigma_min(kept)/sigma_max %.3e\n", y->rank, (double)y->sratio));
  PetscCall(PetscViewerASCIIPrintf(viewer, "flexible frequencies (Hz):"));
  PetscCall(PetscViewerASCIIUseTabs(viewer, PETSC_FALSE));
  for (PetscInt i = 0; i < y->nf; i++) PetscCall(PetscViewerASCIIPrintf(viewer, "%s %.6g", (i && i % 8 == 0) ? "\n   " : "", (double)y->freq[i]));
  PetscCall(PetscViewerASCIIPrintf(viewer, "\n"));
  PetscCall(PetscViewerASCIIUseTabs(viewer, PETSC_TRUE));
  if (y->ntrimmed) PetscCall(PetscViewerASCIIPrintf(viewer, "trimmed: %" PetscInt_FMT " mode(s) above %.6g Hz (up to %.6g Hz) residualized into a static feedthrough\n", y->ntrimmed, (double)y->fmax_trim, (double)y->ftop_untrimmed));
  PetscCall(PetscViewerASCIIPopTab(viewer));
  PetscFunctionReturn(0);
}

/* Tre + i Tim += (i w)^q D per output (q: its quantity: displacement 0, velocity 1, acceleration 2) */
PetscErrorCode KFReducedSystemAddFeedthrough_Private(KFReducedSystem y, const PetscInt quantity[], PetscInt nw, const PetscReal w[], PetscReal Tre[], PetscReal Tim[])
{
  const PetscInt t = y->t, a = y->a;

  PetscFunctionBegin;
  if (!y->D) PetscFunctionReturn(0);
  for (PetscInt k = 0; k < nw; k++)
    for (PetscInt j = 0; j < a; j++)
      for (PetscInt i = 0; i < t; i++) {
        const PetscInt  e = i + j * t, q = quantity ? quantity[i] : KF_QUANTITY_DISPLACEMENT;
        const PetscReal d = y->D[e];
        if (q == KF_QUANTITY_VELOCITY) Tim[k * t * a + e] += w[k] * d;
        else if (q == KF_QUANTITY_ACCELERATION) Tre[k * t * a + e] -= w[k] * w[k] * d;
        else Tre[k * t * a + e] += d;
      }
  PetscFunctionReturn(0);
}
