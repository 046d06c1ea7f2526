#include <kryflex_impl.h>

PetscErrorCode KFSceneCreate(MPI_Comm comm, KFScene *scene)
{
  KFScene s;

  PetscFunctionBegin;
  PetscValidPointer(scene, 2);
  PetscCall(KFInitialize());
  PetscCall(PetscHeaderCreate(s, KF_SCENE_CLASSID, "KFScene", "Articulated multi-flexible-body scene", "KF", comm, KFSceneDestroy, KFSceneView));
  s->comm   = comm; /* the caller's communicator, as before: the header keeps PETSc's duplicate */
  s->nrigid = -1;
  PetscCall(PetscStrncpy(s->name, "scene", sizeof(s->name)));
  *scene = s;
  PetscFunctionReturn(0);
}

/* Drops one reference; the last one frees the scene (systems, body bases and reducers hold references). */
PetscErrorCode KFSceneDestroy(KFScene *scene)
{
  KFScene s = *scene;

  PetscFunctionBegin;
  if (!s) PetscFunctionReturn(0);
  PetscValidHeaderSpecific(s, KF_SCENE_CLASSID, 1);
  if (--((PetscObject)s)->refct > 0) {
    *scene = NULL;
    PetscFunctionReturn(0);
  }
  for (PetscInt b = 0; b < s->nb; b++) {
    KFBodyData *B = &s->bodies[b];
    PetscCall(MatDestroy(&B->M));
    PetscCall(MatDestroy(&B->K));
    PetscCall(MatDestroy(&B->G));
    PetscCall(MatDestroy(&B->Ht));
    PetscCall(MatDestroy(&B->C));
    PetscCall(PetscFree4(B->ids, B->ndof, B->dof0, B->xyz));
    PetscCall(PetscFree2(B->comps, B->scalar_of_node));
    PetscCall(PetscFree(B->scalar_rigid));
    PetscCall(PetscFree(B->iface));
    PetscCall(PetscFree(B->sysidx));
    PetscCall(PetscFree(B->clamp));
    PetscCall(PetscFree2(B->spring_dof, B->spring_k));
  }
  for (PetscInt k = 0; k < s->nin_terms; k++) PetscCall(VecDestroy(&s->in_terms[k].v));
  for (PetscInt k = 0; k < s->nout_terms; k++) PetscCall(VecDestroy(&s->out_terms[k].v));
  PetscCall(PetscFree(s->bodies));
  PetscCall(PetscFree(s->joints));
  PetscCall(PetscFree(s->in_terms));
  PetscCall(PetscFree(s->out_terms));
  PetscCall(PetscFree(s->order));
  PetscCall(PetscFree(s->input_names));
  PetscCall(PetscFree(s->output_names));
  PetscCall(PetscFree(s->out_quantity));
  PetscCall(PetscHeaderDestroy(scene));
  PetscFunctionReturn(0);
}

#define KF_GROW(arr, n, alloc) \
  do { \
    if ((n) >= (alloc)) { \
      PetscInt newalloc = (alloc) ? 2 * (alloc) : 4; \
      PetscCall(PetscRealloc(sizeof(*(arr)) * newalloc, &(arr))); \
      PetscCall(PetscMemzero((arr) + (alloc), sizeof(*(arr)) * (newalloc - (alloc)))); \
      (alloc) = newalloc; \
    } \
  } while (0)

static PetscInt KFPopCount(PetscInt mask)
{
  PetscInt n = 0;
  for (int c = 0; c < 6; c++) n += (mask >> c) & 1;
  return n;
}

PetscErrorCode KFSceneAddBody(KFScene s, const char name[], Mat M, Mat K, PetscInt nnodes, const PetscInt ids[], const PetscReal xyz[], const PetscInt ndof[], PetscInt *body)
{
  PetscInt *comps;

  PetscFunctionBegin;
  PetscCheck(nnodes > 0, s->comm, PETSC_ERR_ARG_SIZ, "body '%s' has no nodes: its nodes file must list 'id x y z ndof' per node", name);
  PetscCall(PetscMalloc1(nnodes, &comps));
  for (PetscInt i = 0; i < nnodes; i++) {
    PetscCheck(ndof[i] == 3 || ndof[i] == 6, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "body '%s', node %" PetscInt_FMT ": %" PetscInt_FMT " dofs per node; KFSceneAddBody takes 6 (ux uy uz rx ry rz) or 3 (ux uy uz): use KFSceneAddBodyComponents for other layouts", name, ids[i], ndof[i]);
    comps[i] = ndof[i] == 6 ? KF_COMPONENTS_ALL : 7;
  }
  PetscCall(KFSceneAddBodyComponents(s, name, M, K, nnodes, ids, xyz, comps, body));
  PetscCall(PetscFree(comps));
  PetscFunctionReturn(0);
}

PetscErrorCode KFSceneAddBodyComponents(KFScene s, const char name[], Mat M, Mat K, PetscInt nnodes, const PetscInt ids[], const PetscReal xyz[], const PetscInt comps[], PetscInt *body)
{
  KFBodyData *B;
  PetscInt    n = 0, mM, nM, mK, nK, *ndof;

  PetscFunctionBegin;
  PetscCheck(!s->setup, s->comm, PETSC_ERR_ORDER, "cannot add body %s after KFSceneSetUp()", name);
  for (PetscInt b = 0; b < s->nb; b++) {
    PetscBool same;
    PetscCall(PetscStrcmp(s->bodies[b].name, name, &same));
    PetscCheck(!same, s->comm, PETSC_ERR_ARG_WRONG, "body '%s' is defined twice: give each body a unique name", name);
  }
  PetscCheck(nnodes > 0, s->comm, PETSC_ERR_ARG_SIZ, "body '%s' has no nodes: its nodes file must list 'id x y z ndof' per node", name);
  PetscCall(PetscMalloc1(nnodes, &ndof));
  for (PetscInt i = 0; i < nnodes; i++) {
    PetscCheck(comps[i] >= 0 && comps[i] <= KF_COMPONENTS_ALL, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "body '%s', node %" PetscInt_FMT ": component set %" PetscInt_FMT " is not a set of the six components (bits 0-5) or a scalar point (0)", name, ids[i], comps[i]);
    ndof[i] = comps[i] ? KFPopCount(comps[i]) : 1;
    n += ndof[i];
  }
  PetscCall(MatGetSize(M, &mM, &nM));
  PetscCall(MatGetSize(K, &mK, &nK));
  PetscCheck(mM == nM && mK == nK, s->comm, PETSC_ERR_ARG_SIZ, "body '%s': M is %" PetscInt_FMT " x %" PetscInt_FMT " and K is %" PetscInt_FMT " x %" PetscInt_FMT "; both must be square", name, mM, nM, mK, nK);
  PetscCheck(mM == mK, s->comm, PETSC_ERR_ARG_SIZ, "body '%s': M is %" PetscInt_FMT " x %" PetscInt_FMT " but K is %" PetscInt_FMT " x %" PetscInt_FMT "; they must have the same size", name, mM, nM, mK, nK);
  PetscCheck(mM == n, s->comm, PETSC_ERR_ARG_SIZ, "body '%s': its nodes carry %" PetscInt_FMT " dofs but M and K are %" PetscInt_FMT " x %" PetscInt_FMT "; the nodes file must match the matrices (the components each node lists, node by node)", name, n, mM, mM);
  KF_GROW(s->bodies, s->nb, s->nb_alloc);
  B = &s->bodies[s->nb];
  PetscCall(PetscStrncpy(B->name, name, sizeof(B->name)));
  PetscCall(PetscObjectReference((PetscObject)M));
  PetscCall(PetscObjectReference((PetscObject)K));
  B->M = M;
  B->K = K;
  B->n = n;
  B->nnodes = nnodes;
  PetscCall(PetscMalloc4(nnodes, &B->ids, nnodes, &B->ndof, nnodes, &B->dof0, 3 * nnodes, &B->xyz));
  PetscCall(PetscMalloc2(nnodes, &B->comps, nnodes, &B->scalar_of_node));
  B->nscalar = 0;
  for (PetscInt i = 0; i < nnodes; i++) {
    B->comps[i]          = comps[i];
    B->scalar_of_node[i] = comps[i] ? -1 : B->nscalar++;
  }
  for (PetscInt i = 0, d = 0; i < nnodes; i++) {
    B->ids[i]  = ids[i];
    B->ndof[i] = ndof[i];
    B->dof0[i] = d;
    d += ndof[i];
    for (int c = 0; c < 3; c++) B->xyz[3 * i + c] = xyz[3 * i + c];
  }
  {
    /* duplicate ids would make node references ambiguous */
    PetscInt *sorted;
    PetscCall(PetscMalloc1(nnodes, &sorted));
    PetscCall(PetscArraycpy(sorted, ids, nnodes));
    PetscCall(PetscSortInt(nnodes, sorted));
    for (PetscInt i = 1; i < nnodes; i++) PetscCheck(sorted[i] != sorted[i - 1], s->comm, PETSC_ERR_ARG_WRONG, "body '%s': node id %" PetscInt_FMT " appears twice in its nodes list", name, sorted[i]);
    PetscCall(PetscFree(sorted));
  }
  PetscCall(PetscFree(ndof));
  B->parent_joint = -1;
  B->child_iface  = -1;
  if (body) *body = s->nb;
  s->nb++;
  PetscFunctionReturn(0);
}

/* index of a node id in a body, or -1 */
PetscErrorCode KFBodyFindNode(KFBodyData *B, PetscInt id, PetscInt *node)
{
  PetscFunctionBegin;
  *node = -1;
  for (PetscInt i = 0; i < B->nnodes; i++)
    if (B->ids[i] == id) {
      *node = i;
      break;
    }
  PetscFunctionReturn(0);
}

PetscErrorCode KFSceneAddInterface(KFScene s, PetscInt body, const char name[], PetscInt node_id)
{
  KFBodyData *B;
  PetscInt    node, alloc;

  PetscFunctionBegin;
  PetscCheck(body >= 0 && body < s->nb, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "interface '%s': body index %" PetscInt_FMT " does not exist", name, body);
  B = &s->bodies[body];
  PetscCall(KFBodyFindNode(B, node_id, &node));
  PetscCheck(node >= 0, s->comm, PETSC_ERR_ARG_WRONG, "body '%s': interface '%s' names node %" PetscInt_FMT ", which is not in the body's nodes list; use one of its node ids", B->name, name, node_id);
  PetscCheck(B->comps[node] == KF_COMPONENTS_ALL, s->comm, PETSC_ERR_ARG_WRONG, "body '%s': interface '%s' (node %" PetscInt_FMT ") has %" PetscInt_FMT " dofs; an interface node needs all six components (ux uy uz rx ry rz: a joint ties translations and rotations)", B->name, name, node_id, B->ndof[node]);
  alloc = B->ninterfaces;
  PetscCall(PetscRealloc(sizeof(KFInterface) * (alloc + 1), &B->iface));
  PetscCall(PetscStrncpy(B->iface[alloc].name, name, KF_MAX_NAME));
  B->iface[alloc].node_id = node_id;
  B->iface[alloc].node    = node;
  B->iface[alloc].dof0    = B->dof0[node];
  B->ninterfaces++;
  PetscFunctionReturn(0);
}

static PetscErrorCode KFBodyFindInterface(KFScene s, PetscInt body, const char name[], const char role[], const char joint[], PetscInt *k)
{
  KFBodyData *B = &s->bodies[body];

  PetscFunctionBegin;
  *k = -1;
  for (PetscInt i = 0; i < B->ninterfaces; i++) {
    PetscBool same;
    PetscCall(PetscStrcmp(B->iface[i].name, name, &same));
    if (same) *k = i;
  }
  PetscCheck(*k >= 0, s->comm, PETSC_ERR_ARG_WRONG, "joint '%s': %s body '%s' has no interface named '%s'; declare it under the body's interfaces", joint, role, B->name, name);
  PetscFunctionReturn(0);
}

/* node and component (0..5) of body dof i: dofs are numbered node by node, components ascending */
PetscErrorCode KFBodyDofComponent(KFBodyData *B, PetscInt dof, PetscInt *node, PetscInt *comp)
{
  PetscInt lo = 0, hi = B->nnodes - 1;

  PetscFunctionBegin;
  while (lo < hi) { /* the last node whose first dof is <= dof */
    PetscInt mid = (lo + hi + 1) / 2;
    if (B->dof0[mid] <= dof) lo = mid;
    else hi = mid - 1;
  }
  *node = lo;
  if (!B->comps[lo]) *comp = KF_COMPONENT_SCALAR;
  else { /* the (dof - dof0)-th component present */
    PetscInt k = dof - B->dof0[lo];
    for (PetscInt c = 0; c < 6; c++)
      if ((B->comps[lo] >> c) & 1) {
        if (!k--) {
          *comp = c;
          break;
        }
      }
  }
  PetscFunctionReturn(0);
}

PetscInt KFBodyNodeDof(const KFBodyData *B, PetscInt node, PetscInt comp)
{
  PetscInt off = 0;

  if (!B->comps[node]) return comp == KF_COMPONENT_SCALAR ? B->dof0[node] : -1;
  if (comp < 0 || comp > 5 || !((B->comps[node] >> comp) & 1)) return -1;
  for (PetscInt c = 0; c < comp; c++) off += (B->comps[node] >> c) & 1;
  return B->dof0[node] + off;
}

static PetscErrorCode KFBodyAddClamp(KFScene s, KFBodyData *B, PetscInt dof)
{
  PetscFunctionBegin;
  for (PetscInt k = 0; k < B->nclamp; k++)
    if (B->clamp[k] == dof) PetscFunctionReturn(0);
  PetscCall(PetscRealloc(sizeof(PetscInt) * (B->nclamp + 1), &B->clamp));
  B->clamp[B->nclamp++] = dof;
  PetscFunctionReturn(0);
}

static const char *const KFComponentNames[] = {"ux", "uy", "uz", "rx", "ry", "rz", "s"};

/* "c345"-style description of a node's components, for messages */
static const char *KFNodeLayout(const KFBodyData *B, PetscInt node, char buf[8])
{
  PetscInt k = 0;
  if (!B->comps[node]) return "a scalar point";
  buf[k++] = 'c';
  for (int c = 0; c < 6; c++)
    if ((B->comps[node] >> c) & 1) buf[k++] = (char)('1' + c);
  buf[k] = 0;
  return buf;
}

PetscErrorCode KFSceneAddConstraint(KFScene s, PetscInt body, PetscInt node_id, const char dofs[])
{
  KFBodyData *B;
  PetscInt    node;
  PetscBool   seen[6] = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE, PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};

  PetscFunctionBegin;
  PetscCheck(!s->setup, s->comm, PETSC_ERR_ORDER, "cannot add a constraint after KFSceneSetUp()");
  PetscCheck(body >= 0 && body < s->nb, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "constraint: body index %" PetscInt_FMT " does not exist", body);
  B = &s->bodies[body];
  PetscCall(KFBodyFindNode(B, node_id, &node));
  PetscCheck(node >= 0, s->comm, PETSC_ERR_ARG_WRONG, "body '%s': a constraint names node %" PetscInt_FMT ", which is not in the body's nodes list; use one of its node ids", B->name, node_id);
  if (!dofs || !dofs[0]) {
    for (PetscInt c = 0; c < B->ndof[node]; c++) PetscCall(KFBodyAddClamp(s, B, B->dof0[node] + c));
    PetscFunctionReturn(0);
  }
  PetscCheck(B->comps[node], s->comm, PETSC_ERR_ARG_WRONG, "body '%s', node %" PetscInt_FMT " is a scalar point: clamp it without dofs (its one dof)", B->name, node_id);
  for (const char *p = dofs; *p; p++) {
    PetscInt c = *p - '1';
    PetscCheck(c >= 0 && c < 6, s->comm, PETSC_ERR_ARG_WRONG, "body '%s', node %" PetscInt_FMT ": constraint dofs '%s' is not a component string; give digits 1-6 (1 2 3 = ux uy uz, 4 5 6 = rx ry rz), e.g. \"123456\"", B->name, node_id, dofs);
    PetscCheck(!seen[c], s->comm, PETSC_ERR_ARG_WRONG, "body '%s', node %" PetscInt_FMT ": constraint dofs '%s' lists component %d twice", B->name, node_id, dofs, (int)c + 1);
    seen[c] = PETSC_TRUE;
    {
      char lay[8];
      PetscCheck(KFBodyNodeDof(B, node, c) >= 0, s->comm, PETSC_ERR_ARG_WRONG, "body '%s', node %" PetscInt_FMT ": constraint on component %d (%s), which the node does not have (it has %" PetscInt_FMT " dofs, %s); clamp only the components the node carries", B->name, node_id, (int)c + 1, KFComponentNames[c], B->ndof[node], KFNodeLayout(B, node, lay));
    }
    PetscCall(KFBodyAddClamp(s, B, KFBodyNodeDof(B, node, c)));
  }
  PetscFunctionReturn(0);
}

PetscErrorCode KFSceneAddSpring(KFScene s, PetscInt body, PetscInt node_id, PetscInt comp, PetscReal k)
{
  KFBodyData *B;
  PetscInt    node;

  PetscFunctionBegin;
  PetscCheck(!s->setup, s->comm, PETSC_ERR_ORDER, "cannot add a spring after KFSceneSetUp()");
  PetscCheck(body >= 0 && body < s->nb, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "spring: body index %" PetscInt_FMT " does not exist", body);
  B = &s->bodies[body];
  PetscCall(KFBodyFindNode(B, node_id, &node));
  PetscCheck(node >= 0, s->comm, PETSC_ERR_ARG_WRONG, "body '%s': a spring names node %" PetscInt_FMT ", which is not in the body's nodes list; use one of its node ids", B->name, node_id);
  {
    char lay[8];
    PetscCheck(KFBodyNodeDof(B, node, comp) >= 0, s->comm, PETSC_ERR_ARG_WRONG, "body '%s', node %" PetscInt_FMT ": spring on component %s, which the node does not have (it has %" PetscInt_FMT " dofs, %s)", B->name, node_id, comp >= 0 && comp <= 6 ? KFComponentNames[comp] : "?", B->ndof[node], KFNodeLayout(B, node, lay));
  }
  PetscCheck(k > 0 && !PetscIsInfOrNanReal(k), s->comm, PETSC_ERR_ARG_OUTOFRANGE, "body '%s', node %" PetscInt_FMT ": spring stiffness %g; give a finite positive number", B->name, node_id, (double)k);
  {
    PetscInt  *dof;
    PetscReal *kk;
    PetscCall(PetscMalloc2(B->nspring + 1, &dof, B->nspring + 1, &kk));
    if (B->nspring) {
      PetscCall(PetscArraycpy(dof, B->spring_dof, B->nspring));
      PetscCall(PetscArraycpy(kk, B->spring_k, B->nspring));
    }
    PetscCall(PetscFree2(B->spring_dof, B->spring_k));
    B->spring_dof = dof;
    B->spring_k   = kk;
  }
  B->spring_dof[B->nspring] = KFBodyNodeDof(B, node, comp);
  B->spring_k[B->nspring++] = k;
  PetscFunctionReturn(0);
}

PetscErrorCode KFSceneGetRigidCount(KFScene s, PetscInt *nrigid)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, KF_SCENE_CLASSID, 1);
  *nrigid = s->nrigid;
  PetscFunctionReturn(0);
}

/* A joint to ground clamps its child's interface node: all 6 dofs (fixed), or all but the rotation about the axis
   (revolute; the axis in the child's frame must be one of its coordinate axes, so that the clamp is by component). */
static PetscErrorCode KFSceneAddGroundJoint(KFScene s, const char name[], KFJointType type, PetscInt child, const char child_interface[], const PetscReal axis[3], const PetscReal R0[9])
{
  KFBodyData *C;
  PetscInt    k = -1, free_comp = -1;

  PetscFunctionBegin;
  PetscCheck(child >= 0 && child < s->nb, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "joint '%s': child body does not exist", name);
  C = &s->bodies[child];
  for (PetscInt i = 0; i < C->ninterfaces; i++) {
    PetscBool same;
    PetscCall(PetscStrcmp(C->iface[i].name, child_interface, &same));
    if (same) k = i;
  }
  PetscCheck(k >= 0, s->comm, PETSC_ERR_ARG_WRONG, "joint '%s': child body '%s' has no interface named '%s'; declare it under the body's interfaces", name, C->name, child_interface ? child_interface : "(null)");
  if (type == KF_JOINT_REVOLUTE) {
    PetscReal a[3], nrm = PetscSqrtReal(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    PetscCheck(nrm > 0 && !PetscIsInfOrNanReal(nrm), s->comm, PETSC_ERR_ARG_WRONG, "joint '%s': the rotation axis is zero or not finite; give a direction such as [0, 0, 1]", name);
    for (int i = 0; i < 3; i++) { /* the axis in the child's frame: R0^T axis */
      a[i] = 0;
      for (int j = 0; j < 3; j++) a[i] += (R0 ? R0[j + 3 * i] : (PetscReal)(i == j)) * axis[j] / nrm;
    }
    for (int i = 0; i < 3; i++)
      if (PetscAbsReal(PetscAbsReal(a[i]) - 1) < 1e-10) free_comp = 3 + i;
    PetscCheck(free_comp >= 0, s->comm, PETSC_ERR_SUP, "joint '%s' to ground: the axis (%g, %g, %g) in body '%s''s frame is not one of its coordinate axes; a grounded revolute joint clamps by component, so give an axis along x, y or z of the child's frame (or clamp the node with constraints)", name, (double)a[0], (double)a[1], (double)a[2], C->name);
  }
  for (PetscInt c = 0; c < 6; c++)
    if (c != free_comp) PetscCall(KFBodyAddClamp(s, C, C->iface[k].dof0 + c));
  PetscFunctionReturn(0);
}

PetscErrorCode KFSceneAddJoint(KFScene s, const char name[], KFJointType type, PetscInt parent, const char parent_interface[], PetscInt child, const char child_interface[], const PetscReal axis[3], const PetscReal R0[9])
{
  KFJointData *J;

  PetscFunctionBegin;
  PetscCheck(!s->setup, s->comm, PETSC_ERR_ORDER, "cannot add joint %s after KFSceneSetUp()", name);
  PetscCheck(type == KF_JOINT_REVOLUTE || type == KF_JOINT_FIXED, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "joint '%s': unknown type", name);
  if (parent == KF_GROUND) {
    PetscCall(KFSceneAddGroundJoint(s, name, type, child, child_interface, axis, R0));
    PetscFunctionReturn(0);
  }
  PetscCheck(parent >= 0 && parent < s->nb && child >= 0 && child < s->nb, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "joint '%s': parent or child body does not exist", name);
  PetscCheck(parent != child, s->comm, PETSC_ERR_ARG_WRONG, "joint '%s' ties body '%s' to itself; a joint connects two different bodies", name, s->bodies[parent].name);
  PetscCheck(type == KF_JOINT_REVOLUTE || type == KF_JOINT_FIXED, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "joint '%s': unknown type", name);
  KF_GROW(s->joints, s->nj, s->nj_alloc);
  J = &s->joints[s->nj];
  PetscCall(PetscStrncpy(J->name, name, sizeof(J->name)));
  J->type   = type;
  J->parent = parent;
  J->child  = child;
  PetscCall(KFBodyFindInterface(s, parent, parent_interface, "parent", name, &J->parent_iface));
  PetscCall(KFBodyFindInterface(s, child, child_interface, "child", name, &J->child_iface));
  if (type == KF_JOINT_REVOLUTE) {
    PetscReal nrm = PetscSqrtReal(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    PetscCheck(!PetscIsInfOrNanReal(nrm), s->comm, PETSC_ERR_ARG_WRONG, "joint '%s': the rotation axis is not a finite vector", name);
    PetscCheck(nrm > 0, s->comm, PETSC_ERR_ARG_WRONG, "joint '%s': the rotation axis is zero; give a direction such as [0, 0, 1]", name);
    for (int c = 0; c < 3; c++) J->axis[c] = axis[c] / nrm;
  } else {
    J->axis[0] = 0; J->axis[1] = 0; J->axis[2] = 1;
  }
  for (int c = 0; c < 9; c++) J->R0[c] = R0 ? R0[c] : (c % 4 == 0 ? 1.0 : 0.0);
  {
    /* R0 must be a rotation: R0^T R0 = I, det = +1 */
    PetscReal err = 0, *R = J->R0, det;
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < 3; j++) {
        PetscReal d = 0;
        for (int k = 0; k < 3; k++) d += R[k + 3 * i] * R[k + 3 * j];
        err = PetscMax(err, PetscAbsReal(d - (i == j)));
      }
    det = R[0] * (R[4] * R[8] - R[7] * R[5]) - R[3] * (R[1] * R[8] - R[7] * R[2]) + R[6] * (R[1] * R[5] - R[4] * R[2]);
    PetscCheck(err < 1e-8 && det > 0, s->comm, PETSC_ERR_ARG_WRONG, "joint '%s': orientation is not a rotation matrix (orthonormality error %g, det %g)", name, (double)err, (double)det);
  }
  J->revolute = -1;
  J->beta     = -1;
  s->nj++;
  PetscFunctionReturn(0);
}

PetscErrorCode KFSceneSetNumIO(KFScene s, PetscInt ninputs, PetscInt noutputs)
{
  PetscFunctionBegin;
  PetscCheck(ninputs >= 1 && noutputs >= 1, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "a scene needs at least one input and one output (got %" PetscInt_FMT " inputs, %" PetscInt_FMT " outputs)", ninputs, noutputs);
  PetscCheck(!s->setup || (ninputs == s->ninputs && noutputs == s->noutputs), s->comm, PETSC_ERR_ORDER, "cannot change the number of inputs or outputs after KFSceneSetUp()");
  /* names: "in0", "in1", ... and "out0", ... until KFSceneSetIOName names them; existing names are kept */
  for (int pass = 0; pass < 2; pass++) {
    char (**names)[KF_MAX_NAME] = pass ? &s->output_names : &s->input_names;
    PetscInt old = pass ? s->noutputs : s->ninputs, n = pass ? noutputs : ninputs;
    PetscCall(PetscRealloc(sizeof(**names) * n, names));
    for (PetscInt i = old; i < n; i++) PetscCall(PetscSNPrintf((*names)[i], KF_MAX_NAME, "%s%" PetscInt_FMT, pass ? "out" : "in", i));
  }
  s->ninputs  = ninputs;
  s->noutputs = noutputs;
  PetscFunctionReturn(0);
}

static PetscErrorCode KFSceneAddTerm(KFScene s, PetscBool input, PetscInt io, PetscInt body, PetscInt node_id, PetscInt comp, PetscReal w, Vec v)
{
  KFTerm  *T;
  PetscInt nio = input ? s->ninputs : s->noutputs;

  PetscFunctionBegin;
  PetscCheck(io >= 0 && io < nio, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "%s %" PetscInt_FMT " does not exist (the scene has %" PetscInt_FMT "); call KFSceneSetNumIO first", input ? "input" : "output", io, nio);
  PetscCheck(body >= 0 && body < s->nb, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "%s %" PetscInt_FMT ": body index %" PetscInt_FMT " does not exist", input ? "input" : "output", io, body);
  if (!v) {
    KFBodyData *B = &s->bodies[body];
    PetscInt    node;
    PetscCall(KFBodyFindNode(B, node_id, &node));
    PetscCheck(node >= 0, s->comm, PETSC_ERR_ARG_WRONG, "%s %" PetscInt_FMT ": body '%s' has no node %" PetscInt_FMT, input ? "input" : "output", io, B->name, node_id);
    {
      char lay[8];
      PetscCheck(KFBodyNodeDof(B, node, comp) >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "%s %" PetscInt_FMT ": node %" PetscInt_FMT " of body '%s' has no component %s (it has %" PetscInt_FMT " dofs, %s); address only the components the node carries", input ? "input" : "output", io, node_id, B->name, comp >= 0 && comp <= 6 ? KFComponentNames[comp] : "?", B->ndof[node], KFNodeLayout(B, node, lay));
    }
  } else {
    PetscInt n;
    PetscCall(VecGetSize(v, &n));
    PetscCheck(n == s->bodies[body].n, s->comm, PETSC_ERR_ARG_SIZ, "%s %" PetscInt_FMT ": vector of size %" PetscInt_FMT " for body '%s' of %" PetscInt_FMT " dofs", input ? "input" : "output", io, n, s->bodies[body].name, s->bodies[body].n);
    PetscCall(PetscObjectReference((PetscObject)v));
  }
  if (input) {
    KF_GROW(s->in_terms, s->nin_terms, s->nin_alloc);
    T = &s->in_terms[s->nin_terms++];
  } else {
    KF_GROW(s->out_terms, s->nout_terms, s->nout_alloc);
    T = &s->out_terms[s->nout_terms++];
  }
  T->io = io; T->body = body; T->node_id = node_id; T->comp = comp; T->w = w; T->v = v;
  PetscFunctionReturn(0);
}

PetscErrorCode KFSceneAddInputLoad(KFScene s, PetscInt input, PetscInt body, PetscInt node_id, PetscInt comp, PetscReal w)
{
  PetscFunctionBegin;
  PetscCall(KFSceneAddTerm(s, PETSC_TRUE, input, body, node_id, comp, w, NULL));
  PetscFunctionReturn(0);
}
PetscErrorCode KFSceneAddInputVector(KFScene s, PetscInt input, PetscInt body, Vec g)
{
  PetscFunctionBegin;
  PetscCall(KFSceneAddTerm(s, PETSC_TRUE, input, body, -1, -1, 1.0, g));
  PetscFunctionReturn(0);
}
PetscErrorCode KFSceneAddOutputReading(KFScene s, PetscInt output, PetscInt body, PetscInt node_id, PetscInt comp, PetscReal w)
{
  PetscFunctionBegin;
  PetscCall(KFSceneAddTerm(s, PETSC_FALSE, output, body, node_id, comp, w, NULL));
  PetscFunctionReturn(0);
}
PetscErrorCode KFSceneAddOutputVector(KFScene s, PetscInt output, PetscInt body, Vec h)
{
  PetscFunctionBegin;
  PetscCall(KFSceneAddTerm(s, PETSC_FALSE, output, body, -1, -1, 1.0, h));
  PetscFunctionReturn(0);
}

PetscErrorCode KFSceneGetInfo(KFScene s, PetscInt *nbodies, PetscInt *njoints, PetscInt *nrevolute, PetscInt *nsystem, PetscInt *ninputs, PetscInt *noutputs)
{
  PetscFunctionBegin;
  PetscCheck(s->setup, s->comm, PETSC_ERR_ORDER, "call KFSceneSetUp() first");
  if (nbodies) *nbodies = s->nb;
  if (njoints) *njoints = s->nj;
  if (nrevolute) *nrevolute = s->nrevolute;
  if (nsystem) *nsystem = s->nsys;
  if (ninputs) *ninputs = s->ninputs;
  if (noutputs) *noutputs = s->noutputs;
  PetscFunctionReturn(0);
}

PetscErrorCode KFSceneGetBodyInfo(KFScene s, PetscInt body, const char **name, PetscInt *ndofs, PetscInt *nnodes)
{
  PetscFunctionBegin;
  PetscCheck(body >= 0 && body < s->nb, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "body index %" PetscInt_FMT " does not exist", body);
  if (name) *name = s->bodies[body].name;
  if (ndofs) *ndofs = s->bodies[body].n;
  if (nnodes) *nnodes = s->bodies[body].nnodes;
  PetscFunctionReturn(0);
}

PetscErrorCode KFSceneGetBodyMatrices(KFScene s, PetscInt body, Mat *M, Mat *K, Mat *G, Mat *Ht)
{
  PetscFunctionBegin;
  PetscCheck(body >= 0 && body < s->nb, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "body index %" PetscInt_FMT " does not exist", body);
  if (M) *M = s->bodies[body].M;
  if (K) *K = s->bodies[body].K;
  if (G) *G = s->bodies[body].G;
  if (Ht) *Ht = s->bodies[body].Ht;
  PetscFunctionReturn(0);
}

/* Whether the body's M and K were found exactly symmetric (A = A^T, entry for entry) when the scene was set up */
PetscErrorCode KFSceneGetBodySymmetric(KFScene s, PetscInt body, PetscBool *M, PetscBool *K)
{
  PetscFunctionBegin;
  PetscCheck(s->setup, s->comm, PETSC_ERR_ORDER, "call KFSceneSetUp() first: the symmetry is found there");
  PetscCheck(body >= 0 && body < s->nb, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "body index %" PetscInt_FMT " does not exist", body);
  if (M) *M = s->bodies[body].exact_M;
  if (K) *K = s->bodies[body].exact_K;
  PetscFunctionReturn(0);
}

PetscErrorCode KFSceneView(KFScene s, PetscViewer viewer)
{
  PetscFunctionBegin;
  PetscCall(PetscViewerASCIIPrintf(viewer, "kryflex scene: %" PetscInt_FMT " bodies, %" PetscInt_FMT " joints (%" PetscInt_FMT " revolute), %" PetscInt_FMT " inputs, %" PetscInt_FMT " outputs\n", s->nb, s->nj, s->nrevolute, s->ninputs, s->noutputs));
  for (PetscInt b = 0; b < s->nb; b++) PetscCall(PetscViewerASCIIPrintf(viewer, "  body %-16s %10" PetscInt_FMT " dofs %8" PetscInt_FMT " nodes %2" PetscInt_FMT " interfaces\n", s->bodies[b].name, s->bodies[b].n, s->bodies[b].nnodes, s->bodies[b].ninterfaces));
  for (PetscInt j = 0; j < s->nj; j++) {
    KFJointData *J = &s->joints[j];
    PetscCall(PetscViewerASCIIPrintf(viewer, "  joint %-15s %-8s %s.%s -> %s.%s axis (%g %g %g)\n", J->name, J->type == KF_JOINT_REVOLUTE ? "revolute" : "fixed", s->bodies[J->parent].name, s->bodies[J->parent].iface[J->parent_iface].name, s->bodies[J->child].name, s->bodies[J->child].iface[J->child_iface].name, (double)J->axis[0], (double)J->axis[1], (double)J->axis[2]));
  }
  if (s->setup) PetscCall(PetscViewerASCIIPrintf(viewer, "  system dofs: %" PetscInt_FMT "\n", s->nsys));
  PetscFunctionReturn(0);
}

/* ---------------------------------------------------------------- names recorded in reduced models */

PetscErrorCode KFSceneSetName(KFScene s, const char name[])
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, KF_SCENE_CLASSID, 1);
  PetscCheck(name && name[0], s->comm, PETSC_ERR_ARG_WRONG, "a scene name must not be empty");
  PetscCheck(strlen(name) < sizeof(s->name), s->comm, PETSC_ERR_ARG_SIZ, "scene name '%.40s...' is longer than %d characters; give a shorter name", name, (int)sizeof(s->name) - 1);
  PetscCall(PetscStrncpy(s->name, name, sizeof(s->name)));
  PetscCall(PetscObjectSetName((PetscObject)s, name));
  PetscFunctionReturn(0);
}

PetscErrorCode KFSceneGetName(KFScene s, const char **name)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, KF_SCENE_CLASSID, 1);
  *name = s->name;
  PetscFunctionReturn(0);
}

PetscErrorCode KFSceneSetIOName(KFScene s, PetscBool input, PetscInt i, const char name[])
{
  PetscInt n = input ? s->ninputs : s->noutputs;
  char (*names)[KF_MAX_NAME] = input ? s->input_names : s->output_names;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, KF_SCENE_CLASSID, 1);
  PetscCheck(i >= 0 && i < n, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "%s %" PetscInt_FMT " does not exist (the scene has %" PetscInt_FMT "); call KFSceneSetNumIO first", input ? "input" : "output", i, n);
  PetscCheck(name && name[0], s->comm, PETSC_ERR_ARG_WRONG, "%s %" PetscInt_FMT ": a name must not be empty", input ? "input" : "output", i);
  PetscCheck(strlen(name) < KF_MAX_NAME, s->comm, PETSC_ERR_ARG_SIZ, "%s name '%.40s...' is longer than %d characters; give a shorter name", input ? "input" : "output", name, KF_MAX_NAME - 1);
  for (PetscInt k = 0; k < n; k++) {
    PetscBool same;
    if (k == i) continue;
    PetscCall(PetscStrcmp(names[k], name, &same));
    PetscCheck(!same, s->comm, PETSC_ERR_ARG_WRONG, "%s name '%s' is used twice (%s %" PetscInt_FMT " and %" PetscInt_FMT "): give each a unique name", input ? "input" : "output", name, input ? "inputs" : "outputs", k, i);
  }
  PetscCall(PetscStrncpy(names[i], name, KF_MAX_NAME));
  PetscFunctionReturn(0);
}

PetscErrorCode KFSceneGetIOName(KFScene s, PetscBool input, PetscInt i, const char **name)
{
  PetscInt n = input ? s->ninputs : s->noutputs;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, KF_SCENE_CLASSID, 1);
  PetscCheck(i >= 0 && i < n, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "%s %" PetscInt_FMT " does not exist (the scene has %" PetscInt_FMT ")", input ? "input" : "output", i, n);
  *name = input ? s->input_names[i] : s->output_names[i];
  PetscFunctionReturn(0);
}

PetscErrorCode KFSceneGetJointInfo(KFScene s, PetscInt j, const char **name, KFJointDef *joint)
{
  KFJointData *J;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, KF_SCENE_CLASSID, 1);
  PetscCheck(j >= 0 && j < s->nj, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "joint index %" PetscInt_FMT " does not exist (the scene has %" PetscInt_FMT " joints)", j, s->nj);
  J = &s->joints[j];
  if (name) *name = J->name;
  if (joint) {
    joint->type             = J->type;
    joint->parent           = J->parent;
    joint->parent_interface = J->parent_iface;
    joint->child            = J->child;
    joint->child_interface  = J->child_iface;
    for (int c = 0; c < 3; c++) joint->axis[c] = J->axis[c];
    for (int c = 0; c < 9; c++) joint->R0[c] = J->R0[c];
  }
  PetscFunctionReturn(0);
}

PetscErrorCode KFSceneGetInterfaceName(KFScene s, PetscInt body, PetscInt i, const char **name)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, KF_SCENE_CLASSID, 1);
  PetscCheck(body >= 0 && body < s->nb, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "body index %" PetscInt_FMT " does not exist", body);
  PetscCheck(i >= 0 && i < s->bodies[body].ninterfaces, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "body '%s' has no interface %" PetscInt_FMT " (it has %" PetscInt_FMT ")", s->bodies[body].name, i, s->bodies[body].ninterfaces);
  *name = s->bodies[body].iface[i].name;
  PetscFunctionReturn(0);
}
