/* Boundary conditions and dof layouts through the C API: a chain of N scalar points (masses m) between two
   clamped uz-only nodes (layout c3), springs k between neighbours. No rigid modes remain, and the verification's
   eigenvalues are the chain's, (4k/m) sin^2(j pi / (2(N+1))). A constraint on a component a node does not have, and
   an output on one, are errors (a code, the same on every rank). */
#include "kftest.h"

#define N 12

static PetscErrorCode BuildChain(KFScene *scene, PetscBool bad_clamp, PetscBool bad_output)
{
  KFScene   s;
  Mat       M, K;
  PetscInt  n = N + 2, ids[N + 2], comps[N + 2], rstart, rend, b;
  PetscReal xyz[3 * (N + 2)], k = 1000.0, m = 2.0;

  PetscFunctionBegin;
  for (PetscInt i = 0; i < n; i++) {
    ids[i]           = i + 1;
    comps[i]         = (i == 0 || i == n - 1) ? (1 << 2) : KF_SCALAR_POINT; /* c3 ends, scalar points between */
    xyz[3 * i + 0]   = 0.1 * i;
    xyz[3 * i + 1]   = 0;
    xyz[3 * i + 2]   = 0;
  }
  PetscCall(MatCreateAIJ(PETSC_COMM_WORLD, PETSC_DECIDE, PETSC_DECIDE, n, n, 3, NULL, 2, NULL, &K));
  PetscCall(MatCreateAIJ(PETSC_COMM_WORLD, PETSC_DECIDE, PETSC_DECIDE, n, n, 1, NULL, 0, NULL, &M));
  PetscCall(MatGetOwnershipRange(K, &rstart, &rend));
  for (PetscInt i = rstart; i < rend; i++) {
    PetscCall(MatSetValue(M, i, i, (i == 0 || i == n - 1) ? 0.0 : m, INSERT_VALUES)); /* the clamped ends massless */
    PetscCall(MatSetValue(K, i, i, (i == 0 || i == n - 1) ? k : 2 * k, INSERT_VALUES));
    if (i > 0) PetscCall(MatSetValue(K, i, i - 1, -k, INSERT_VALUES));
    if (i < n - 1) PetscCall(MatSetValue(K, i, i + 1, -k, INSERT_VALUES));
  }
  PetscCall(MatAssemblyBegin(K, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(K, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyBegin(M, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(M, MAT_FINAL_ASSEMBLY));
  PetscCall(KFSceneCreate(PETSC_COMM_WORLD, &s));
  PetscCall(KFSceneAddBodyComponents(s, "chain", M, K, n, ids, xyz, comps, &b));
  PetscCall(MatDestroy(&M));
  PetscCall(MatDestroy(&K));
  PetscCall(KFSceneAddConstraint(s, b, 1, bad_clamp ? "34" : "3"));
  PetscCall(KFSceneAddConstraint(s, b, n, NULL));
  PetscCall(KFSceneSetNumIO(s, 1, 1));
  PetscCall(KFSceneAddInputLoad(s, 0, b, 4, KF_COMPONENT_SCALAR, 1.0));
  PetscCall(KFSceneAddOutputReading(s, 0, b, bad_output ? 1 : 9, bad_output ? 3 : KF_COMPONENT_SCALAR, 1.0));
  *scene = s;
  PetscFunctionReturn(0);
}

static PetscErrorCode TryBad(PetscBool bad_clamp, PetscBool bad_output, PetscErrorCode *code)
{
  KFScene s = NULL;

  PetscFunctionBegin;
  PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  *code = BuildChain(&s, bad_clamp, bad_output);
  PetscCall(PetscPopErrorHandler());
  if (s) PetscCall(KFSceneDestroy(&s));
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  KFScene        s;
  KFSystem       y;
  PetscInt       nrigid, nconv;
  PetscReal      w2[N], HPhi[N], PhiG[N], err = 0;
  PetscErrorCode code;

  PetscCall(SlepcInitialize(&argc, &argv, NULL, "Tests of boundary conditions and dof layouts"));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "a chain of %d scalar points between clamped c3 nodes:\n", N));
  PetscCall(BuildChain(&s, PETSC_FALSE, PETSC_FALSE));
  PetscCall(KFSceneSetUp(s));
  PetscCall(KFSystemCreate(s, &y));
  PetscCall(KFSystemSetAngles(y, NULL));
  PetscCall(KFSystemComputeRigidModes(y));
  PetscCall(KFSceneGetRigidCount(s, &nrigid));
  PetscCall(CheckTrue("no rigid modes remain (both ends clamped)", nrigid == 0 ? PETSC_TRUE : PETSC_FALSE));
  PetscCall(KFSystemEigen(y, N, &nconv, w2, HPhi, PhiG));
  PetscCall(CheckTrue("the verification finds the N modes", nconv == N ? PETSC_TRUE : PETSC_FALSE));
  for (PetscInt j = 0; j < nconv; j++) {
    PetscReal s2 = PetscSinReal((j + 1) * PETSC_PI / (2.0 * (N + 1))), exact = 4 * 1000.0 / 2.0 * s2 * s2;
    err = PetscMax(err, PetscAbsReal(w2[j] - exact) / exact);
  }
  PetscCall(Check("eigenvalues against (4k/m) sin^2(j pi / (2(N+1))), relative", err, 1e-10));
  PetscCall(KFSystemDestroy(&y));
  PetscCall(KFSceneDestroy(&s));

  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "bad layouts return an error code:\n"));
  PetscCall(TryBad(PETSC_TRUE, PETSC_FALSE, &code));
  PetscCall(CheckTrue("a constraint on rx of a c3 node", code != 0 ? PETSC_TRUE : PETSC_FALSE));
  PetscCall(TryBad(PETSC_FALSE, PETSC_TRUE, &code));
  PetscCall(CheckTrue("an output on rx of a c3 node", code != 0 ? PETSC_TRUE : PETSC_FALSE));
  PetscCall(SlepcFinalize());
  return nfail ? 1 : 0;
}
