#include <kryflex_impl.h>

/* How every interface dof of every body reads in system dofs at the system's angles (replicated on all ranks).
   Kept dofs read as themselves; a child's tied interface dofs read through its parent's (eq. 25 generalized):
     u_c = R^T u_p,   theta_c = R^T (theta_p + beta axis)  (revolute)   or   R^T theta_p  (fixed). */
PETSC_INTERN PetscErrorCode KFSystemInterfaceExprs(KFSystem sys, KFExpr ***exprs)
{
  KFScene   s = sys->scene;
  KFExpr  **E;
  PetscInt *owned, *idx;

  PetscFunctionBegin;
  PetscCall(PetscMalloc1(s->nb, &E));
  for (PetscInt b = 0; b < s->nb; b++) {
    KFBodyData *B = &s->bodies[b];
    PetscInt    n = 6 * B->ninterfaces;
    PetscCall(PetscCalloc1(PetscMax(n, 1), &E[b]));
    /* the rank that owns a kept interface dof knows its system index: share it */
    PetscCall(PetscMalloc2(PetscMax(n, 1), &owned, PetscMax(n, 1), &idx));
    for (PetscInt k = 0; k < n; k++) {
      PetscInt dof = B->iface[k / 6].dof0 + k % 6;
      owned[k]     = (dof >= B->rstart && dof < B->rend) ? B->sysidx[dof - B->rstart] : -1;
    }
    PetscCall(MPIU_Allreduce(owned, idx, (PetscMPIInt)n, MPIU_INT, MPI_MAX, s->comm));
    for (PetscInt k = 0; k < n; k++)
      if (idx[k] >= 0) PetscCall(KFExprAdd(&E[b][k], idx[k], 1.0));
    PetscCall(PetscFree2(owned, idx));
  }
  /* parents before children, so a parent's interface expressions are complete when a child needs them */
  for (PetscInt o = 0; o < s->nb; o++) {
    KFBodyData  *C = &s->bodies[s->order[o]];
    KFJointData *J;
    PetscReal    R[9], alpha;
    KFExpr      *ep, *ec;
    if (C->parent_joint < 0) continue;
    J     = &s->joints[C->parent_joint];
    alpha = J->revolute >= 0 ? sys->angles[J->revolute] : 0.0;
    PetscCall(KFJointRotation(J->axis, J->R0, alpha, R));
    ep = &E[J->parent][6 * J->parent_iface];
    ec = &E[J->child][6 * J->child_iface];
    for (int i = 0; i < 3; i++) {
      PetscCheck(ec[i].n == 0 && ec[3 + i].n == 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "interface dof eliminated twice");
      for (int k = 0; k < 3; k++) {
        PetscCall(KFExprAXPY(&ec[i], R[k + 3 * i], &ep[k]));         /* (R^T)_{ik} = R_{ki} */
        PetscCall(KFExprAXPY(&ec[3 + i], R[k + 3 * i], &ep[3 + k]));
      }
      if (J->beta >= 0) {
        PetscReal rta = 0;
        for (int k = 0; k < 3; k++) rta += R[k + 3 * i] * J->axis[k];
        PetscCall(KFExprAdd(&ec[3 + i], J->beta, rta));
      }
    }
    /* another interface name on the same (tied) node reads the same */
    for (PetscInt i2 = 0; i2 < C->ninterfaces; i2++)
      if (i2 != J->child_iface && C->iface[i2].node == C->iface[J->child_iface].node) PetscCall(PetscArraycpy(&E[J->child][6 * i2], ec, 6));
  }
  *exprs = E;
  PetscFunctionReturn(0);
}

PETSC_INTERN PetscErrorCode KFSystemInterfaceExprsDestroy(KFSystem sys, KFExpr ***exprs)
{
  PetscFunctionBegin;
  for (PetscInt b = 0; b < sys->scene->nb; b++) PetscCall(PetscFree((*exprs)[b]));
  PetscCall(PetscFree(*exprs));
  PetscFunctionReturn(0);
}

/* Fills P_b (n_b x e): one 1 per kept dof, the interface expression on the tied rows. The pattern is the same at
   every angle; the first call creates and preallocates. */
PETSC_INTERN PetscErrorCode KFSystemBuildBodyMaps(KFSystem sys)
{
  KFScene  s = sys->scene;
  KFExpr **E;

  PetscFunctionBegin;
  PetscCall(KFSystemInterfaceExprs(sys, &E));
  for (PetscInt b = 0; b < s->nb; b++) {
    KFBodyData *B  = &s->bodies[b];
    PetscInt    nl = B->rend - B->rstart, e0 = -1;
    if (B->child_iface >= 0) e0 = B->iface[B->child_iface].dof0;
    if (!sys->P[b]) {
      PetscInt *dnz, *onz;
      PetscCall(PetscMalloc2(nl, &dnz, nl, &onz));
      for (PetscInt i = 0; i < nl; i++) {
        PetscInt dof = B->rstart + i;
        dnz[i]       = 1;
        onz[i]       = 0;
        if (B->sysidx[i] == -2) dnz[i] = 0; /* clamped: an empty row */
        else if (B->sysidx[i] < 0) {
          const KFExpr *x = &E[b][6 * B->child_iface + (dof - e0)];
          dnz[i]          = 0;
          for (PetscInt k = 0; k < x->n; k++) {
            if (x->idx[k] >= s->sys_rstart && x->idx[k] < s->sys_rstart + s->nsys_local) dnz[i]++;
            else onz[i]++;
          }
        }
      }
      PetscCall(MatCreateAIJ(s->comm, nl, s->nsys_local, B->n, s->nsys, 0, dnz, 0, onz, &sys->P[b]));
      PetscCall(PetscFree2(dnz, onz));
    } else PetscCall(MatZeroEntries(sys->P[b]));
    for (PetscInt i = 0; i < nl; i++) {
      PetscInt dof = B->rstart + i;
      if (B->sysidx[i] >= 0) PetscCall(MatSetValue(sys->P[b], dof, B->sysidx[i], 1.0, INSERT_VALUES));
      else if (B->sysidx[i] == -1) {
        const KFExpr *x = &E[b][6 * B->child_iface + (dof - e0)];
        PetscScalar   vals[KF_MAX_TERMS];
        for (PetscInt k = 0; k < x->n; k++) vals[k] = x->c[k];
        PetscCall(MatSetValues(sys->P[b], 1, &dof, x->n, x->idx, vals, INSERT_VALUES));
      }
    }
    PetscCall(MatAssemblyBegin(sys->P[b], MAT_FINAL_ASSEMBLY));
    PetscCall(MatAssemblyEnd(sys->P[b], MAT_FINAL_ASSEMBLY));
  }
  PetscCall(KFSystemInterfaceExprsDestroy(sys, &E));
  PetscFunctionReturn(0);
}

/* Body frames in the root frame at the system's angles: y = Q x + o, with the tied nodes coinciding. */
PETSC_INTERN PetscErrorCode KFSystemBuildFrames(KFSystem sys)
{
  KFScene s = sys->scene;

  PetscFunctionBegin;
  for (PetscInt o = 0; o < s->nb; o++) {
    PetscInt    b = s->order[o];
    KFBodyData *C = &s->bodies[b];
    if (C->parent_joint < 0) {
      for (int k = 0; k < 9; k++) sys->Q[b][k] = (k % 4 == 0);
      for (int k = 0; k < 3; k++) sys->o[b][k] = 0;
    } else {
      KFJointData *J = &s->joints[C->parent_joint];
      KFBodyData  *Pb = &s->bodies[J->parent];
      PetscReal    R[9], *Qp = sys->Q[J->parent], *op = sys->o[J->parent], *Q = sys->Q[b];
      PetscReal   *xp = &Pb->xyz[3 * Pb->iface[J->parent_iface].node], *xc = &C->xyz[3 * C->iface[J->child_iface].node];
      PetscCall(KFJointRotation(J->axis, J->R0, J->revolute >= 0 ? sys->angles[J->revolute] : 0.0, R));
      for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
          Q[i + 3 * j] = 0;
          for (int k = 0; k < 3; k++) Q[i + 3 * j] += Qp[i + 3 * k] * R[k + 3 * j];
        }
      for (int i = 0; i < 3; i++) {
        sys->o[b][i] = op[i];
        for (int k = 0; k < 3; k++) sys->o[b][i] += Qp[i + 3 * k] * xp[k] - Q[i + 3 * k] * xc[k];
      }
    }
  }
  PetscFunctionReturn(0);
}
