/*
  Coordinate ties of a model of shared directions (-kf_shared_directions): each kept system vector is one direction of
  the system instead of one per body. The bodies keep their bases; their stacked coordinates q = (q_1, ..., q_nb) are
  tied to span[R C], R the bodies' rigid motions (block diagonal, free: they absorb any interface motion, so the
  joints' ties stay satisfiable at every angle) and C the kept vectors' body coordinates. The ties are the rows D
  (orthonormal) with D [R C] = 0; the model then reassembles as a Galerkin model on a subspace of the split one.
*/
#include <kryflex/reducerimpl.h>

PetscErrorCode KFCandidateTies_Private(KFReducer r, KFReducedModel model, PetscInt k, PetscReal *const C[])
{
  PetscInt   nb, n = 0, p, h, rank, *off;
  PetscReal *At, *N, *D;

  PetscFunctionBegin;
  PetscCall(KFReducedModelGetInfo(model, &nb, NULL, NULL, NULL, NULL, NULL));
  PetscCall(PetscMalloc1(nb + 1, &off));
  for (PetscInt b = 0; b < nb; b++) {
    KFReducedBody body;

    PetscCall(KFReducedModelGetBody(model, b, NULL, NULL, &body, NULL));
    off[b] = n;
    n += body.v;
  }
  off[nb] = n;
  p       = 6 * nb + k;
  /* A^T (p x n): the rows of the bodies' rigid motions, then of the kept vectors, each scaled to unit length (the
     rigid rotations about the origin and the unit-M-norm vectors differ in scale; the rank should not see it) */
  PetscCall(PetscCalloc2(p * n + 1, &At, n * n + 1, &N));
  for (PetscInt b = 0; b < nb; b++) {
    KFReducedBody  body;
    const PetscInt v = off[b + 1] - off[b];

    PetscCall(KFReducedModelGetBody(model, b, NULL, NULL, &body, NULL));
    PetscCheck(body.rigid, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_WRONG, "shared directions need the bodies' rigid motions, and body %" PetscInt_FMT " has none recorded: use -kf_shared_directions false", b);
    if (!v) continue;
    /* the motions' coordinates are M_b^-1 rigid_b; M_b is the identity to rounding (an M-orthonormal basis), and the
       reassembly takes rigid_b itself for the system's rigid modes (KFReassemblyRigidMotions): the same R here keeps
       D R = 0 exactly for them */
    for (PetscInt j = 0; j < 6; j++)
      for (PetscInt i = 0; i < v; i++) At[(6 * b + j) + (off[b] + i) * p] = body.rigid[i + j * v];
    for (PetscInt j = 0; j < k; j++)
      for (PetscInt i = 0; i < v; i++) At[(6 * nb + j) + (off[b] + i) * p] = C[b][i + j * v];
  }
  for (PetscInt j = 0; j < p; j++) {
    PetscReal s = 0;

    for (PetscInt i = 0; i < n; i++) s += PetscSqr(At[j + i * p]);
    if (s > 0)
      for (PetscInt i = 0; i < n; i++) At[j + i * p] /= PetscSqrtReal(s);
  }
  /* the ties: the orthonormal complement of span[R C], null(A^T), at the reassembly's rank tolerance */
  PetscCall(KFDenseNullSpace(p, n, At, r->reassembly_rtol, &h, N, &rank, NULL));
  PetscCall(PetscMalloc1(h * n + 1, &D));
  for (PetscInt j = 0; j < n; j++)
    for (PetscInt i = 0; i < h; i++) D[i + j * h] = N[j + i * n];
  PetscCall(KFReducedModelSetTies(model, h, n, D));
  PetscCall(PetscInfo(r, "shared directions: %" PetscInt_FMT " body coordinates, rank [R C] %" PetscInt_FMT " (%" PetscInt_FMT " kept vectors): %" PetscInt_FMT " ties\n", n, rank, k, h));
  PetscCall(PetscFree(D));
  PetscCall(PetscFree2(At, N));
  PetscCall(PetscFree(off));
  PetscFunctionReturn(0);
}
