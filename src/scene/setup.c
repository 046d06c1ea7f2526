#include <kryflex_impl.h>

/* The scene must be a tree: one root, every other body the child of exactly one joint, all reachable. */
static PetscErrorCode KFSceneCheckTree(KFScene s)
{
  PetscInt *queue, head = 0, tail = 0, root = -1;
  PetscBool *seen;

  PetscFunctionBegin;
  for (PetscInt j = 0; j < s->nj; j++) {
    KFJointData *J = &s->joints[j];
    KFBodyData  *C = &s->bodies[J->child];
    PetscCheck(C->parent_joint < 0, s->comm, PETSC_ERR_ARG_WRONG, "body '%s' is the child of two joints ('%s' and '%s'): a scene is a tree; make one of them its parent instead", C->name, s->joints[C->parent_joint].name, J->name);
    C->parent_joint = j;
    C->child_iface  = J->child_iface;
  }
  for (PetscInt b = 0; b < s->nb && root < 0; b++)
    if (s->bodies[b].parent_joint < 0) root = b;
  PetscCheck(root >= 0, s->comm, PETSC_ERR_ARG_WRONG, "the joints form a loop: every body is some joint's child; kryflex needs a tree (one root body that is no joint's child)");
  PetscCall(PetscMalloc1(s->nb, &queue));
  PetscCall(PetscCalloc1(s->nb, &seen));
  queue[tail++] = root;
  seen[root]    = PETSC_TRUE;
  while (head < tail) {
    PetscInt b = queue[head++];
    for (PetscInt j = 0; j < s->nj; j++)
      if (s->joints[j].parent == b && !seen[s->joints[j].child]) {
        seen[s->joints[j].child] = PETSC_TRUE;
        queue[tail++]            = s->joints[j].child;
      }
  }
  for (PetscInt b = 0; b < s->nb; b++)
    PetscCheck(seen[b], s->comm, PETSC_ERR_ARG_WRONG, "body '%s' is not attached to the root body '%s': no chain of joints reaches it; add a joint that connects it (or remove the body)", s->bodies[b].name, s->bodies[root].name);
  s->order = queue;
  PetscCall(PetscFree(seen));
  PetscFunctionReturn(0);
}

static PetscErrorCode KFBodyCheck(KFScene s, KFBodyData *B)
{
  PetscInt  rs, re, rsK, reK;
  Vec       d;
  PetscReal dmin;
  char      what[2 * KF_MAX_NAME], whatK[2 * KF_MAX_NAME];

  PetscFunctionBegin;
  PetscCall(PetscSNPrintf(what, sizeof(what), "mass matrix M of body '%s'", B->name));
  PetscCall(PetscSNPrintf(whatK, sizeof(whatK), "stiffness matrix K of body '%s'", B->name));
  PetscCall(KFMatCheckSymmetricPairExact(B->M, B->K, what, whatK, 1e-10, &B->exact_M, &B->exact_K));
  PetscCall(MatGetOwnershipRange(B->M, &rs, &re));
  PetscCall(MatGetOwnershipRange(B->K, &rsK, &reK));
  PetscCheck(rs == rsK && re == reK, PETSC_COMM_SELF, PETSC_ERR_ARG_INCOMP, "body '%s': M and K are distributed differently over the ranks; load them with the same layout", B->name);
  B->rstart = rs;
  B->rend   = re;
  /* a mass matrix needs a non-negative diagonal (massless dofs, e.g. rotations of a lumped-mass model, are fine:
     the Krylov recurrence on K+ M copes, the verification condenses them); a stiffness matrix a non-negative one
     (else it is indefinite); a dof with neither mass nor stiffness has no equation at all */
  PetscCall(MatCreateVecs(B->M, &d, NULL));
  PetscCall(MatGetDiagonal(B->M, d));
  PetscCall(VecMin(d, NULL, &dmin));
  PetscCheck(dmin >= 0, s->comm, PETSC_ERR_ARG_WRONG, "mass matrix M of body '%s' is indefinite: its diagonal has a negative entry %g; check the export (masses and inertias are >= 0)", B->name, (double)dmin);
  {
    Vec                dk;
    const PetscScalar *m, *k;
    PetscInt           bad = PETSC_MAX_INT, first;
    PetscCall(VecDuplicate(d, &dk));
    PetscCall(MatGetDiagonal(B->K, dk));
    PetscCall(VecMin(dk, NULL, &dmin));
    PetscCheck(dmin >= 0, s->comm, PETSC_ERR_ARG_WRONG, "stiffness matrix K of body '%s' is indefinite: its diagonal has a negative entry %g; check the export", B->name, (double)dmin);
    PetscCall(VecGetArrayRead(d, &m));
    PetscCall(VecGetArrayRead(dk, &k));
    for (PetscInt i = 0; i < re - rs && bad == PETSC_MAX_INT; i++)
      if (PetscRealPart(m[i]) == 0 && PetscRealPart(k[i]) == 0) {
        PetscBool held = PETSC_FALSE; /* clamped, or given a spring: determined after all */
        for (PetscInt c = 0; c < B->nclamp; c++) held = (PetscBool)(held || B->clamp[c] == rs + i);
        for (PetscInt c = 0; c < B->nspring; c++) held = (PetscBool)(held || B->spring_dof[c] == rs + i);
        if (!held) bad = rs + i;
      }
    PetscCall(VecRestoreArrayRead(d, &m));
    PetscCall(VecRestoreArrayRead(dk, &k));
    PetscCall(VecDestroy(&dk));
    PetscCall(MPIU_Allreduce(&bad, &first, 1, MPIU_INT, MPI_MIN, s->comm));
    if (first != PETSC_MAX_INT) {
      PetscInt          node, comp;
      static const char *cn[] = {"ux", "uy", "uz", "rx", "ry", "rz"};
      PetscCall(KFBodyDofComponent(B, first, &node, &comp));
      SETERRQ(s->comm, PETSC_ERR_ARG_WRONG, "body '%s', node %" PetscInt_FMT ", component %s (dof %" PetscInt_FMT "): the dof has neither mass nor stiffness, so nothing determines its motion; remove it from the model (and the nodes file), give it stiffness, or clamp it (constraints)", B->name, B->ids[node], comp < 6 ? cn[comp] : "?", first + 1);
    }
  }
  PetscCall(VecDestroy(&d));
  PetscFunctionReturn(0);
}

/* System dofs are numbered rank by rank: each rank owns the kept dofs of the body rows it owns, so P(alpha) is
   nearly block-diagonal across ranks; the joints' free rotations go last, on the last rank. */
static PetscErrorCode KFSceneNumberDofs(KFScene s)
{
  PetscMPIInt rank, size;
  PetscInt    nlocal = 0, next;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  PetscCallMPI(MPI_Comm_size(s->comm, &size));
  s->nrevolute = 0;
  for (PetscInt j = 0; j < s->nj; j++) s->joints[j].revolute = s->joints[j].type == KF_JOINT_REVOLUTE ? s->nrevolute++ : -1;
  for (PetscInt b = 0; b < s->nb; b++) {
    KFBodyData *B  = &s->bodies[b];
    PetscInt    e0 = -1, e1 = -1;
    if (B->child_iface >= 0) {
      e0 = B->iface[B->child_iface].dof0;
      e1 = e0 + 6;
    }
    PetscCall(PetscMalloc1(B->rend - B->rstart, &B->sysidx));
    for (PetscInt i = B->rstart; i < B->rend; i++) {
      B->sysidx[i - B->rstart] = (i >= e0 && i < e1) ? -1 : 0;
      if (B->sysidx[i - B->rstart] == 0) nlocal++;
    }
    for (PetscInt k = 0; k < B->nclamp; k++) { /* clamped dofs are no system dofs: P_b reads them as zero */
      PetscInt dof = B->clamp[k];
      if (dof >= B->rstart && dof < B->rend && B->sysidx[dof - B->rstart] == 0) {
        B->sysidx[dof - B->rstart] = -2;
        nlocal--;
      }
    }
  }
  if (rank == size - 1) nlocal += s->nrevolute;
  PetscCallMPI(MPI_Scan(&nlocal, &next, 1, MPIU_INT, MPI_SUM, s->comm));
  s->nsys_local = nlocal;
  s->sys_rstart = next - nlocal;
  PetscCall(MPIU_Allreduce(&nlocal, &s->nsys, 1, MPIU_INT, MPI_SUM, s->comm));
  next = s->sys_rstart;
  for (PetscInt k = 0; k < s->nb; k++) {
    KFBodyData *B = &s->bodies[s->order[k]];
    for (PetscInt i = 0; i < B->rend - B->rstart; i++)
      if (B->sysidx[i] == 0) B->sysidx[i] = next++;
  }
  for (PetscInt j = 0; j < s->nj; j++)
    if (s->joints[j].revolute >= 0) s->joints[j].beta = s->nsys - s->nrevolute + s->joints[j].revolute;
  PetscFunctionReturn(0);
}

/* G_b (n_b x a) and H_b^T (n_b x t) of every body from the scene's point loads, readings and vectors. */
static PetscErrorCode KFSceneBuildIO(KFScene s)
{
  PetscFunctionBegin;
  for (PetscInt io = 0; io < s->ninputs; io++) {
    PetscBool found = PETSC_FALSE;
    for (PetscInt k = 0; k < s->nin_terms; k++) found = (PetscBool)(found || s->in_terms[k].io == io);
    PetscCheck(found, s->comm, PETSC_ERR_ARG_WRONG, "input %" PetscInt_FMT " has no load: give it at least one {body, node, dof} term", io);
  }
  for (PetscInt io = 0; io < s->noutputs; io++) {
    PetscBool found = PETSC_FALSE;
    for (PetscInt k = 0; k < s->nout_terms; k++) found = (PetscBool)(found || s->out_terms[k].io == io);
    PetscCheck(found, s->comm, PETSC_ERR_ARG_WRONG, "output %" PetscInt_FMT " has no reading: give it at least one {body, node, dof} term", io);
  }
  for (PetscInt b = 0; b < s->nb; b++) {
    KFBodyData *B = &s->bodies[b];
    for (int pass = 0; pass < 2; pass++) {
      PetscInt nterms = pass ? s->nout_terms : s->nin_terms;
      KFTerm  *terms  = pass ? s->out_terms : s->in_terms;
      Mat     *A      = pass ? &B->Ht : &B->G;
      PetscCall(KFDenseCreate(s->comm, B->rend - B->rstart, B->n, pass ? s->noutputs : s->ninputs, A));
      for (PetscInt k = 0; k < nterms; k++) {
        KFTerm *T = &terms[k];
        if (T->body != b) continue;
        if (T->v) {
          const PetscScalar *v;
          PetscCall(VecGetArrayRead(T->v, &v));
          for (PetscInt i = B->rstart; i < B->rend; i++) PetscCall(MatSetValue(*A, i, T->io, T->w * v[i - B->rstart], ADD_VALUES));
          PetscCall(VecRestoreArrayRead(T->v, &v));
        } else {
          PetscInt node, dof;
          PetscCall(KFBodyFindNode(B, T->node_id, &node));
          dof = KFBodyNodeDof(B, node, T->comp);
          { /* a load on a clamped dof goes to ground, a reading of one is always zero: say so rather than reduce
               a column of zeros */
            PetscInt at;
            PetscCall(PetscFindInt(dof, B->nclamp, B->clamp, &at));
            PetscCheck(at < 0, s->comm, PETSC_ERR_ARG_WRONG, "%s '%s' acts on body '%s', node %" PetscInt_FMT ", component %" PetscInt_FMT " (0-5: ux..rz), which is clamped: %s; move it to a dof that moves", pass ? "output" : "input", pass ? s->output_names[T->io] : s->input_names[T->io], B->name, T->node_id, T->comp, pass ? "it would always read zero" : "the load would go straight to ground");
          }
          if (dof >= B->rstart && dof < B->rend) PetscCall(MatSetValue(*A, dof, T->io, T->w, ADD_VALUES));
        }
      }
      PetscCall(MatAssemblyBegin(*A, MAT_FINAL_ASSEMBLY));
      PetscCall(MatAssemblyEnd(*A, MAT_FINAL_ASSEMBLY));
    }
  }
  PetscFunctionReturn(0);
}

/* Boundary conditions checked against the tree (a clamp on a dof the parent joint ties would ground the parent
   through the joint: clamp the parent's node instead); springs to ground added to a copy of K. */
static PetscErrorCode KFSceneApplyBoundaryConditions(KFScene s)
{
  PetscFunctionBegin;
  for (PetscInt b = 0; b < s->nb; b++) {
    KFBodyData *B = &s->bodies[b];
    if (B->nclamp) PetscCall(PetscSortInt(B->nclamp, B->clamp));
    if (B->child_iface >= 0) {
      PetscInt e0 = B->iface[B->child_iface].dof0;
      for (PetscInt k = 0; k < B->nclamp; k++) {
        PetscInt node, comp;
        PetscCall(KFBodyDofComponent(B, B->clamp[k], &node, &comp));
        PetscCheck(B->clamp[k] < e0 || B->clamp[k] >= e0 + 6, s->comm, PETSC_ERR_ARG_WRONG, "body '%s', node %" PetscInt_FMT ": the node is tied to the parent body by joint '%s', so it cannot be clamped or grounded on its own; constrain the parent's interface node instead", B->name, B->ids[node], s->joints[B->parent_joint].name);
      }
    }
    if (B->nspring) {
      Mat K;
      PetscCall(MatDuplicate(B->K, MAT_COPY_VALUES, &K));
      PetscCall(MatSetOption(K, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_FALSE));
      for (PetscInt k = 0; k < B->nspring; k++)
        if (B->spring_dof[k] >= B->rstart && B->spring_dof[k] < B->rend) PetscCall(MatSetValue(K, B->spring_dof[k], B->spring_dof[k], B->spring_k[k], ADD_VALUES));
      PetscCall(MatAssemblyBegin(K, MAT_FINAL_ASSEMBLY));
      PetscCall(MatAssemblyEnd(K, MAT_FINAL_ASSEMBLY));
      PetscCall(MatDestroy(&B->K));
      B->K     = K;
      B->own_K = PETSC_TRUE;
    }
  }
  PetscFunctionReturn(0);
}

PetscErrorCode KFSceneSetUp(KFScene s)
{
  PetscFunctionBegin;
  if (s->setup) PetscFunctionReturn(0);
  PetscCheck(s->nb >= 1, s->comm, PETSC_ERR_ARG_WRONG, "the scene has no bodies");
  PetscCheck(s->ninputs >= 1 && s->noutputs >= 1, s->comm, PETSC_ERR_ARG_WRONG, "the scene needs at least one input and one output");
  for (PetscInt b = 0; b < s->nb; b++) PetscCall(KFBodyCheck(s, &s->bodies[b]));
  PetscCall(KFSceneCheckTree(s));
  PetscCall(KFSceneApplyBoundaryConditions(s));
  PetscCall(KFSceneScalarRigid(s));
  PetscCall(KFSceneNumberDofs(s));
  PetscCall(KFSceneBuildIO(s));
  s->setup = PETSC_TRUE;
  PetscFunctionReturn(0);
}
