/* A reduced model reassembled at one configuration (eq. 20-24), with its modes: a KFReducedSystem. */
#include <kryflex/modelimpl.h>

/* reassembly_rtol from the settings (the reducer records the tolerance it used), 1e-9 otherwise */
static PetscErrorCode KFReducedModelGetReassemblyRtol(KFReducedModel m, PetscReal *rtol)
{
  PetscFunctionBegin;
  *rtol = 1e-9;
  for (PetscInt k = 0; k < m->nsettings; k++) {
    PetscBool same;
    char     *end;
    double    x;

    PetscCall(PetscStrcmp(m->keys[k], "reassembly_rtol", &same));
    if (!same) continue;
    x = strtod(m->values[k], &end);
    PetscCheck(end != m->values[k] && *end == 0 && x > 0 && x < 1, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_WRONG, "the model's setting reassembly_rtol = '%s' is not a number in (0, 1): set it again (KFReducedModelSetSetting) or reduce again", m->values[k]);
    *rtol = (PetscReal)x;
  }
  PetscFunctionReturn(0);
}

/*
  KFReducedModelCreateReassembly - a KFReassembly of the model's bodies and joints with its reassembly_rtol and its
  Rayleigh damping: the allocation-free path of KFReducedModelReassemble's matrices (a simulation's path).
*/
PetscErrorCode KFReducedModelCreateReassembly(KFReducedModel m, KFReassembly *reassembly)
{
  KFReducedBody *bodies;
  PetscReal      rtol;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, KF_REDUCEDMODEL_CLASSID, 1);
  PetscValidPointer(reassembly, 2);
  PetscCall(KFReducedModelGetReassemblyRtol(m, &rtol));
  PetscCall(PetscMalloc1(m->nb, &bodies));
  for (PetscInt b = 0; b < m->nb; b++) PetscCall(KFReducedModelGetBody(m, b, NULL, NULL, &bodies[b], NULL));
  PetscCall(KFReassemblyCreateTied(m->nb, bodies, m->nj, m->joints, m->nties, m->ties, m->ninputs, m->noutputs, rtol, m->damping.alpha, m->damping.beta, reassembly));
  PetscCall(PetscFree(bodies));
  PetscFunctionReturn(0);
}

/*
  KFReducedModelReassemble - the reduced system at one configuration (angles: one per revolute joint, radians):
  KFReassemble of the model's bodies and joints with the model's reassembly_rtol, then the eigenpairs of the
  reassembled pencil. The rigid-body and mechanism modes come from the bodies' stored rigid motions (Phir); only a
  model without them falls back to 6 + revolute joints.
*/
PetscErrorCode KFReducedModelReassemble(KFReducedModel m, const PetscReal angles[], KFReducedSystem *system)
{
  MPI_Comm        comm = PetscObjectComm((PetscObject)m);
  KFReducedSystem y;
  KFReducedBody  *bodies;
  PetscInt        n = 0, h, nrigid, a = m->ninputs, t = m->noutputs;
  PetscReal       rtol, fmax;
  PetscBool       viscous = PETSC_FALSE;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, KF_REDUCEDMODEL_CLASSID, 1);
  PetscValidPointer(system, 3);
  PetscCheck(angles || !m->nrevolute, comm, PETSC_ERR_ARG_NULL, "the model has %" PetscInt_FMT " revolute joint(s): give one angle (radians) per revolute joint", m->nrevolute);
  for (PetscInt r = 0; r < m->nrevolute; r++) PetscCheck(!PetscIsInfOrNanReal(angles[r]), comm, PETSC_ERR_ARG_WRONG, "angle %" PetscInt_FMT " is not a finite number", r);
  PetscCall(KFReducedModelGetReassemblyRtol(m, &rtol));
  PetscCall(PetscMalloc1(m->nb, &bodies));
  for (PetscInt b = 0; b < m->nb; b++) {
    PetscCall(KFReducedModelGetBody(m, b, NULL, NULL, &bodies[b], NULL));
    n += bodies[b].v;
    if (bodies[b].C) viscous = PETSC_TRUE;
  }
  PetscCall(PetscNew(&y));
  y->a               = a;
  y->t               = t;
  PetscCall(KFReducedModelGetInfo(m, NULL, NULL, NULL, NULL, NULL, &y->nrigid_expected));
  PetscCall(PetscMalloc4(n * n, &y->M, n * n, &y->K, n * a, &y->G, t * n, &y->H));
  PetscCall(PetscMalloc1(n * n, &y->Phir));
  y->damping = m->damping;
  PetscCall(PetscMalloc1(PetscMax(t, 1), &y->quantity));
  PetscCall(PetscArraycpy(y->quantity, m->quantity, t));
  if (viscous || m->damping.alpha > 0 || m->damping.beta > 0) PetscCall(PetscMalloc1(n * n, &y->C));
  PetscCall(KFReassembleTied(m->nb, bodies, m->nj, m->joints, m->nties, m->ties, angles, a, t, rtol, &h, y->M, y->K, viscous ? y->C : NULL, y->G, y->H, &y->rank, &y->sratio, &nrigid, y->Phir));
  if (y->C) { /* Rayleigh: alpha M + beta K, exact under projection */
    if (!viscous) PetscCall(PetscArrayzero(y->C, h * h));
    for (PetscInt e = 0; e < h * h; e++) y->C[e] += m->damping.alpha * y->M[e] + m->damping.beta * y->K[e];
  }
  PetscCall(PetscFree(bodies));
  y->n = h;
  PetscCheck(h > 0, comm, PETSC_ERR_ARG_WRONG, "the joints' interface ties (and the model's %" PetscInt_FMT " coordinate ties) leave no free coordinate in the reduced model: reduce again with a larger body basis", m->nties);
  if (nrigid >= 0) {
    y->nrigid     = nrigid;
    y->phir_known = PETSC_TRUE;
  } else {
    y->nrigid = y->nrigid_expected;
    PetscCall(PetscFree(y->Phir));
  }
  PetscCall(PetscMalloc2(h, &y->lambda, h * h, &y->Phi));
  /* the rigid modes from the bodies' geometric motions, not the lowest eigenvectors (the frequency response and the
     verification take them from here) */
  if (y->phir_known && y->nrigid <= h) PetscCall(KFDenseEigRigid(h, y->K, y->M, y->nrigid, y->Phir, y->lambda, y->Phi));
  else PetscCall(KFDenseEig(h, y->K, y->M, y->lambda, y->Phi));
  y->nf = PetscMax(h - y->nrigid, 0);
  PetscCall(PetscMalloc1(y->nf, &y->freq));
  for (PetscInt i = 0; i < y->nf; i++) y->freq[i] = PetscSqrtReal(PetscMax(y->lambda[y->nrigid + i], 0.0)) / (2 * PETSC_PI);
  PetscCall(KFReducedModelGetMaxFrequency(m, &fmax));
  PetscCall(KFReducedSystemTrim(y, fmax)); /* the model's max_frequency: modes above it out of the dynamics */
  *system = y;
  PetscFunctionReturn(0);
}
