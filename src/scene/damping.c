/* A scene's damping matrices (per body) and what its outputs read (displacement, velocity, acceleration). */
#include <kryflex_impl.h>

/*
  KFSceneSetBodyDamping - body's viscous damping matrix C_b (n_b x n_b), referenced. Checked at once, on every rank:
  the size and row layout of the body's M, symmetric, a non-negative diagonal (a necessary condition for C_b to
  dissipate energy).
*/
PetscErrorCode KFSceneSetBodyDamping(KFScene s, PetscInt body, Mat C)
{
  KFBodyData *B;
  PetscInt    m, n, rs, re, rsM, reM, bad;
  Vec         d;
  PetscReal   dmin;
  char        what[2 * KF_MAX_NAME];

  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, KF_SCENE_CLASSID, 1);
  PetscCheck(!s->setup, s->comm, PETSC_ERR_ORDER, "cannot set a damping matrix after KFSceneSetUp()");
  PetscCheck(body >= 0 && body < s->nb, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "damping matrix: body index %" PetscInt_FMT " does not exist", body);
  B = &s->bodies[body];
  if (!C) {
    PetscCall(MatDestroy(&B->C));
    PetscFunctionReturn(0);
  }
  PetscValidHeaderSpecific(C, MAT_CLASSID, 3);
  PetscCall(MatGetSize(C, &m, &n));
  PetscCheck(m == B->n && n == B->n, s->comm, PETSC_ERR_ARG_SIZ, "body '%s': the damping matrix is %" PetscInt_FMT " x %" PetscInt_FMT " but the body has %" PetscInt_FMT " dofs; give its viscous damping C (n x n, the dofs of its M and K)", B->name, m, n, B->n);
  PetscCall(MatGetOwnershipRange(C, &rs, &re));
  PetscCall(MatGetOwnershipRange(B->M, &rsM, &reM));
  bad = (rs != rsM || re != reM);
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &bad, 1, MPIU_INT, MPI_MAX, s->comm));
  PetscCheck(!bad, s->comm, PETSC_ERR_ARG_INCOMP, "body '%s': the damping matrix is distributed differently from M over the ranks; load it with the same layout", B->name);
  PetscCall(PetscSNPrintf(what, sizeof(what), "damping matrix C of body '%s'", B->name));
  PetscCall(KFMatCheckSymmetric(C, what, 1e-10));
  PetscCall(MatCreateVecs(C, &d, NULL));
  PetscCall(MatGetDiagonal(C, d));
  PetscCall(VecMin(d, NULL, &dmin));
  PetscCall(VecDestroy(&d));
  PetscCheck(dmin >= 0, s->comm, PETSC_ERR_ARG_WRONG, "damping matrix C of body '%s' has a negative diagonal entry %g: it would feed energy in; a viscous damping matrix is symmetric positive semi-definite", B->name, (double)dmin);
  PetscCall(PetscObjectReference((PetscObject)C));
  PetscCall(MatDestroy(&B->C));
  B->C = C;
  PetscFunctionReturn(0);
}

PetscErrorCode KFSceneGetBodyDamping(KFScene s, PetscInt body, Mat *C)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, KF_SCENE_CLASSID, 1);
  PetscCheck(body >= 0 && body < s->nb, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "body index %" PetscInt_FMT " does not exist", body);
  *C = s->bodies[body].C;
  PetscFunctionReturn(0);
}

PetscErrorCode KFSceneSetOutputQuantity(KFScene s, PetscInt output, KFQuantity q)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, KF_SCENE_CLASSID, 1);
  PetscCheck(output >= 0 && output < s->noutputs, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "output %" PetscInt_FMT " does not exist (the scene has %" PetscInt_FMT "); call KFSceneSetNumIO first", output, s->noutputs);
  PetscCheck(q >= KF_QUANTITY_DISPLACEMENT && q <= KF_QUANTITY_ACCELERATION, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "output %" PetscInt_FMT ": quantity %d; give displacement, velocity or acceleration", output, (int)q);
  if (s->nquantity < s->noutputs) {
    PetscCall(PetscRealloc(sizeof(PetscInt) * s->noutputs, &s->out_quantity));
    for (PetscInt i = s->nquantity; i < s->noutputs; i++) s->out_quantity[i] = KF_QUANTITY_DISPLACEMENT;
    s->nquantity = s->noutputs;
  }
  s->out_quantity[output] = (PetscInt)q;
  PetscFunctionReturn(0);
}

PetscErrorCode KFSceneGetOutputQuantity(KFScene s, PetscInt output, KFQuantity *q)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, KF_SCENE_CLASSID, 1);
  PetscCheck(output >= 0 && output < s->noutputs, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "output %" PetscInt_FMT " does not exist (the scene has %" PetscInt_FMT ")", output, s->noutputs);
  *q = output < s->nquantity ? (KFQuantity)s->out_quantity[output] : KF_QUANTITY_DISPLACEMENT;
  PetscFunctionReturn(0);
}
