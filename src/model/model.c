/* The reduced model object: life cycle, construction from a body basis, getters and settings. */
#include <kryflex/modelimpl.h>

/* An empty model: counts set, name arrays and body/joint tables allocated and zeroed. Used by the constructor
   from a body basis and by KFReducedModelLoad. */
PetscErrorCode KFReducedModelCreateEmpty_Private(MPI_Comm comm, PetscInt nb, PetscInt nj, PetscInt a, PetscInt t, KFReducedModel *model)
{
  KFReducedModel m;

  PetscFunctionBegin;
  PetscCall(KFInitialize());
  PetscCall(PetscHeaderCreate(m, KF_REDUCEDMODEL_CLASSID, "KFReducedModel", "Reduced model of an articulated structure", "KF", comm, KFReducedModelDestroy, KFReducedModelView));
  /* one kind so far: reduced bodies reassembled at any angle (the view would otherwise say "type not yet set") */
  PetscCall(PetscObjectChangeTypeName((PetscObject)m, "reduced-bodies"));
  m->nb       = nb;
  m->nrigid   = -1;
  m->nj       = nj;
  m->ninputs  = a;
  m->noutputs = t;
  PetscCall(PetscCalloc1(nb, &m->bodies));
  PetscCall(PetscCalloc2(nj, &m->joint_names, nj, &m->joints));
  PetscCall(PetscCalloc1(a, &m->input_names));
  PetscCall(PetscCalloc1(t, &m->output_names));
  /* the reducer's default until it records its own (KFReducedModelSetDamping); displacement outputs */
  PetscCall(KFDampingSetUniform(&m->damping, 0.0025));
  PetscCall(PetscCalloc1(PetscMax(t, 1), &m->quantity));
  *model = m;
  PetscFunctionReturn(0);
}

/* a private copy of an n-array (NULL for n = 0) */
static PetscErrorCode CopyArray(PetscInt n, const PetscReal src[], PetscReal **dst)
{
  PetscFunctionBegin;
  PetscCall(PetscMalloc1(n, dst));
  if (n) PetscCall(PetscArraycpy(*dst, src, n));
  PetscFunctionReturn(0);
}

/*
  KFReducedModelCreateFromBodyBasis - the reduced model of a scene from its finished body basis: every body's
  reduced M, K, G, H, interface rows and rigid motions, the scene's names, joints and fingerprint, and the nangles
  reduction configurations (nangles x nrevolute, row by row, radians). keep_maps gathers each body's map back to
  full dofs (n_b x v) on every rank: it costs n_b v numbers per body. The model lives on the scene's communicator,
  replicated, and keeps no reference to the scene or the basis.
*/
PetscErrorCode KFReducedModelCreateFromBodyBasis(KFScene s, KFBodyBasis bb, PetscInt nangles, const PetscReal angles[], PetscBool keep_maps, KFReducedModel *model)
{
  KFReducedModel m;
  PetscInt       a, t;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, KF_SCENE_CLASSID, 1);
  PetscValidPointer(bb, 2);
  PetscValidPointer(model, 6);
  PetscCheck(s->setup, s->comm, PETSC_ERR_ORDER, "the scene is not set up: build the body basis from it first (KFBodyBasisCreate sets it up)");
  PetscCheck(nangles >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "negative number of reduction configurations %" PetscInt_FMT, nangles);
  PetscCheck(!nangles || !s->nrevolute || angles, s->comm, PETSC_ERR_ARG_NULL, "%" PetscInt_FMT " reduction configurations but no angles: pass nangles x %" PetscInt_FMT " angles (radians)", nangles, s->nrevolute);
  a = s->ninputs;
  t = s->noutputs;
  PetscCall(KFReducedModelCreateEmpty_Private(s->comm, s->nb, s->nj, a, t, &m));
  PetscCall(PetscStrncpy(m->scene_name, s->name, sizeof(m->scene_name)));
  PetscCall(PetscObjectSetName((PetscObject)m, s->name));
  PetscCall(KFSceneGetFingerprint(s, m->fingerprint));
  m->nrevolute = s->nrevolute;
  for (PetscInt b = 0; b < s->nb; b++) {
    KFBodyData      *B = &s->bodies[b];
    KFModelBody     *R = &m->bodies[b];
    const PetscReal *M, *K, *G, *H, *iface, *rigid;
    PetscInt         v, ni;

    PetscCall(KFBodyBasisGetReduced(bb, b, &v, &M, &K, &G, &H, &ni, &iface, &rigid, NULL));
    PetscCheck(ni == B->ninterfaces, s->comm, PETSC_ERR_ARG_INCOMP, "body '%s': the body basis has %" PetscInt_FMT " interfaces, the scene %" PetscInt_FMT ": the basis belongs to another scene", B->name, ni, B->ninterfaces);
    PetscCall(PetscStrncpy(R->name, B->name, sizeof(R->name)));
    R->full_dofs   = B->n;
    R->v           = v;
    R->ninterfaces = ni;
    PetscCall(PetscMalloc1(ni, &R->iface_names));
    for (PetscInt i = 0; i < ni; i++) PetscCall(PetscStrncpy(R->iface_names[i], B->iface[i].name, KF_MAX_NAME));
    PetscCall(CopyArray(v * v, M, &R->M));
    PetscCall(CopyArray(v * v, K, &R->K));
    PetscCall(CopyArray(v * a, G, &R->G));
    PetscCall(CopyArray(t * v, H, &R->H));
    PetscCall(CopyArray(6 * ni * v, iface, &R->iface));
    PetscCall(CopyArray(6 * v, rigid, &R->rigid));
    if (B->C) { /* the reduced viscous damping Psi^T C_b Psi, as M and K (eq. 18-19) */
      Mat Psi, CQ;
      PetscCall(KFBodyBasisGetMap(bb, b, &Psi));
      PetscCall(MatMatMult(B->C, Psi, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &CQ));
      PetscCall(PetscMalloc1(PetscMax(v * v, 1), &R->C));
      PetscCall(KFMatTransposeMatMultGather(Psi, CQ, R->C));
      PetscCall(MatDestroy(&CQ));
      for (PetscInt i = 0; i < v; i++)
        for (PetscInt j = 0; j < i; j++) R->C[i + j * v] = R->C[j + i * v] = 0.5 * (R->C[i + j * v] + R->C[j + i * v]);
    }
    if (keep_maps) {
      Mat      Psi;
      PetscInt rows, cols;
      PetscCall(KFBodyBasisGetMap(bb, b, &Psi));
      PetscCall(MatGetSize(Psi, &rows, &cols));
      PetscCheck(rows == B->n && cols == v, s->comm, PETSC_ERR_ARG_INCOMP, "body '%s': the body basis maps %" PetscInt_FMT " x %" PetscInt_FMT ", the scene needs %" PetscInt_FMT " x %" PetscInt_FMT ": the basis belongs to another scene", B->name, rows, cols, B->n, v);
      PetscCall(PetscMalloc1(rows * cols, &R->map));
      PetscCall(KFDenseGather(Psi, R->map));
    }
  }
  for (PetscInt j = 0; j < s->nj; j++) {
    const char *name;
    /* scene order: the revolute joints come in revolute order, as KFReassemble consumes the angles */
    PetscCall(KFSceneGetJointInfo(s, j, &name, &m->joints[j]));
    PetscCall(PetscStrncpy(m->joint_names[j], name, KF_MAX_NAME));
  }
  for (PetscInt i = 0; i < a; i++) PetscCall(PetscStrncpy(m->input_names[i], s->input_names[i], KF_MAX_NAME));
  for (PetscInt i = 0; i < t; i++) PetscCall(PetscStrncpy(m->output_names[i], s->output_names[i], KF_MAX_NAME));
  for (PetscInt i = 0; i < t; i++) m->quantity[i] = i < s->nquantity ? s->out_quantity[i] : KF_QUANTITY_DISPLACEMENT;
  m->nangles = nangles;
  PetscCall(CopyArray(nangles * s->nrevolute, angles, &m->angles));
  m->nrigid = s->nrigid; /* the count geometry, joints and boundary conditions gave (the reducer records it too) */
  *model = m;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducedModelDestroy(KFReducedModel *model)
{
  KFReducedModel m = *model;

  PetscFunctionBegin;
  if (!m) PetscFunctionReturn(0);
  PetscValidHeaderSpecific(m, KF_REDUCEDMODEL_CLASSID, 1);
  if (--((PetscObject)m)->refct > 0) {
    *model = NULL;
    PetscFunctionReturn(0);
  }
  for (PetscInt b = 0; b < m->nb; b++) {
    KFModelBody *R = &m->bodies[b];
    PetscCall(PetscFree(R->iface_names));
    PetscCall(PetscFree(R->M));
    PetscCall(PetscFree(R->K));
    PetscCall(PetscFree(R->G));
    PetscCall(PetscFree(R->H));
    PetscCall(PetscFree(R->iface));
    PetscCall(PetscFree(R->rigid));
    PetscCall(PetscFree(R->map));
    PetscCall(PetscFree(R->C));
  }
  PetscCall(PetscFree(m->bodies));
  PetscCall(PetscFree2(m->joint_names, m->joints));
  PetscCall(PetscFree(m->input_names));
  PetscCall(PetscFree(m->output_names));
  PetscCall(PetscFree(m->angles));
  PetscCall(PetscFree(m->quantity));
  PetscCall(PetscFree(m->ties));
  for (PetscInt k = 0; k < m->nsettings; k++) {
    PetscCall(PetscFree(m->keys[k]));
    PetscCall(PetscFree(m->values[k]));
  }
  PetscCall(PetscFree2(m->keys, m->values));
  PetscCall(PetscHeaderDestroy(model));
  PetscFunctionReturn(0);
}

/* nrigid: the rigid-body and mechanism modes the scene had (setting rigid_modes, recorded from geometry, joints and
   boundary conditions), else 6 + revolute joints, those of a free tree (a configuration's count comes from the
   bodies' rigid motions: KFReducedSystemGetModes) */
PetscErrorCode KFReducedModelGetInfo(KFReducedModel m, PetscInt *nbodies, PetscInt *njoints, PetscInt *nrevolute, PetscInt *ninputs, PetscInt *noutputs, PetscInt *nrigid)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, KF_REDUCEDMODEL_CLASSID, 1);
  if (nbodies) *nbodies = m->nb;
  if (njoints) *njoints = m->nj;
  if (nrevolute) *nrevolute = m->nrevolute;
  if (ninputs) *ninputs = m->ninputs;
  if (noutputs) *noutputs = m->noutputs;
  if (nrigid) {
    *nrigid = m->nrigid >= 0 ? m->nrigid : 6 + m->nrevolute;
    for (PetscInt k = 0; k < m->nsettings; k++) {
      PetscBool same;
      PetscCall(PetscStrcmp(m->keys[k], "rigid_modes", &same));
      if (same && m->nrigid < 0) *nrigid = (PetscInt)strtol(m->values[k], NULL, 10);
    }
  }
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducedModelGetSceneName(KFReducedModel m, const char **name, const char **fingerprint)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, KF_REDUCEDMODEL_CLASSID, 1);
  if (name) *name = m->scene_name;
  if (fingerprint) *fingerprint = m->fingerprint;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducedModelGetReductionAngles(KFReducedModel m, PetscInt *nangles, const PetscReal **angles)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, KF_REDUCEDMODEL_CLASSID, 1);
  if (nangles) *nangles = m->nangles;
  if (angles) *angles = m->angles;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducedModelGetBody(KFReducedModel m, PetscInt b, const char **name, PetscInt *full_dofs, KFReducedBody *body, const PetscReal **map)
{
  KFModelBody *R;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, KF_REDUCEDMODEL_CLASSID, 1);
  PetscCheck(b >= 0 && b < m->nb, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_OUTOFRANGE, "body index %" PetscInt_FMT " does not exist (the model has %" PetscInt_FMT " bodies)", b, m->nb);
  R = &m->bodies[b];
  if (name) *name = R->name;
  if (full_dofs) *full_dofs = R->full_dofs;
  if (body) {
    body->v           = R->v;
    body->M           = R->M;
    body->K           = R->K;
    body->G           = R->G;
    body->H           = R->H;
    body->ninterfaces = R->ninterfaces;
    body->iface       = R->iface;
    body->rigid       = R->rigid;
    body->C           = R->C;
  }
  if (map) *map = R->map;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducedModelGetInterfaceName(KFReducedModel m, PetscInt b, PetscInt i, const char **name)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, KF_REDUCEDMODEL_CLASSID, 1);
  PetscCheck(b >= 0 && b < m->nb, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_OUTOFRANGE, "body index %" PetscInt_FMT " does not exist (the model has %" PetscInt_FMT " bodies)", b, m->nb);
  PetscCheck(i >= 0 && i < m->bodies[b].ninterfaces, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_OUTOFRANGE, "body '%s' has no interface %" PetscInt_FMT " (it has %" PetscInt_FMT ")", m->bodies[b].name, i, m->bodies[b].ninterfaces);
  *name = m->bodies[b].iface_names[i];
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducedModelGetJoint(KFReducedModel m, PetscInt j, const char **name, KFJointDef *joint)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, KF_REDUCEDMODEL_CLASSID, 1);
  PetscCheck(j >= 0 && j < m->nj, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_OUTOFRANGE, "joint index %" PetscInt_FMT " does not exist (the model has %" PetscInt_FMT " joints)", j, m->nj);
  if (name) *name = m->joint_names[j];
  if (joint) *joint = m->joints[j];
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducedModelGetIOName(KFReducedModel m, PetscBool input, PetscInt i, const char **name)
{
  PetscInt n = input ? m->ninputs : m->noutputs;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, KF_REDUCEDMODEL_CLASSID, 1);
  PetscCheck(i >= 0 && i < n, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_OUTOFRANGE, "%s %" PetscInt_FMT " does not exist (the model has %" PetscInt_FMT ")", input ? "input" : "output", i, n);
  *name = input ? m->input_names[i] : m->output_names[i];
  PetscFunctionReturn(0);
}

/* Settings are an ordered list of string pairs: a new key goes last, a known key keeps its place and takes the
   new value. Numbers are written by the caller (with %.17g for reals, so that they read back exactly). */
PetscErrorCode KFReducedModelSetSetting(KFReducedModel m, const char key[], const char value[])
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, KF_REDUCEDMODEL_CLASSID, 1);
  PetscCheck(key && key[0], PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_WRONG, "a setting needs a non-empty key");
  PetscCheck(value, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_NULL, "setting '%s': the value is NULL; give a string (possibly empty)", key);
  for (PetscInt k = 0; k < m->nsettings; k++) {
    PetscBool same;
    PetscCall(PetscStrcmp(m->keys[k], key, &same));
    if (same) {
      PetscCall(PetscFree(m->values[k]));
      PetscCall(PetscStrallocpy(value, &m->values[k]));
      PetscFunctionReturn(0);
    }
  }
  if (m->nsettings == m->nsettings_alloc) {
    PetscInt newalloc = m->nsettings_alloc ? 2 * m->nsettings_alloc : 16;
    char   **keys, **values;
    PetscCall(PetscMalloc2(newalloc, &keys, newalloc, &values));
    for (PetscInt k = 0; k < m->nsettings; k++) {
      keys[k]   = m->keys[k];
      values[k] = m->values[k];
    }
    PetscCall(PetscFree2(m->keys, m->values));
    m->keys            = keys;
    m->values          = values;
    m->nsettings_alloc = newalloc;
  }
  PetscCall(PetscStrallocpy(key, &m->keys[m->nsettings]));
  PetscCall(PetscStrallocpy(value, &m->values[m->nsettings]));
  m->nsettings++;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducedModelGetSettings(KFReducedModel m, PetscInt *n, const char *const **keys, const char *const **values)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, KF_REDUCEDMODEL_CLASSID, 1);
  if (n) *n = m->nsettings;
  if (keys) *keys = (const char *const *)m->keys;
  if (values) *values = (const char *const *)m->values;
  PetscFunctionReturn(0);
}

/*
  KFReducedModelSetTies - ms coordinate ties between the bodies (D, ms x n column-major, n the sum of the bodies'
  reduced sizes, copied): angle-independent rows D q = 0 on the stacked body coordinates q = (q_1, ..., q_nb) that
  every reassembly appends to the joints' ties. A model of shared directions keeps each system vector one direction
  of the system instead of one per body. ms 0 removes them.
*/
PetscErrorCode KFReducedModelSetTies(KFReducedModel m, PetscInt ms, PetscInt n, const PetscReal D[])
{
  PetscInt nsum = 0;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, KF_REDUCEDMODEL_CLASSID, 1);
  for (PetscInt b = 0; b < m->nb; b++) nsum += m->bodies[b].v;
  PetscCheck(ms >= 0 && ms <= nsum, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_OUTOFRANGE, "KFReducedModelSetTies: %" PetscInt_FMT " ties on %" PetscInt_FMT " body coordinates: give 0 to %" PetscInt_FMT, ms, nsum, nsum);
  PetscCheck(!ms || n == nsum, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_SIZ, "KFReducedModelSetTies: the ties have %" PetscInt_FMT " columns, the bodies %" PetscInt_FMT " coordinates", n, nsum);
  PetscCheck(!ms || D, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_NULL, "KFReducedModelSetTies: %" PetscInt_FMT " ties without their matrix", ms);
  for (PetscInt i = 0; i < ms * n; i++) PetscCheck(!PetscIsInfOrNanReal(D[i]), PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_WRONG, "KFReducedModelSetTies: entry %" PetscInt_FMT " of the ties is not a finite number", i);
  PetscCall(PetscFree(m->ties));
  m->nties = ms;
  if (ms) {
    PetscCall(PetscMalloc1(ms * n, &m->ties));
    PetscCall(PetscArraycpy(m->ties, D, ms * n));
  }
  PetscFunctionReturn(0);
}

/* the model's coordinate ties (KFReducedModelSetTies): ms rows on n coordinates, D NULL when ms is 0 */
PetscErrorCode KFReducedModelGetTies(KFReducedModel m, PetscInt *ms, PetscInt *n, const PetscReal **D)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, KF_REDUCEDMODEL_CLASSID, 1);
  if (ms) *ms = m->nties;
  if (n) {
    *n = 0;
    for (PetscInt b = 0; b < m->nb; b++) *n += m->bodies[b].v;
  }
  if (D) *D = m->ties;
  PetscFunctionReturn(0);
}
