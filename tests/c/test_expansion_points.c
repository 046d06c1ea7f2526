/* An expansion point inside the band through the C API alone, on the Galileo-like model at 30 deg: the solver of
   K_S - sigma M_S (KFFlexSolverSetInteriorShift, indefinite, MUMPS LDL^T) and the Krylov blocks it gives.
   Checked: the block solve's residual against K_S - sigma M_S itself; the blocks M-orthonormal and free of rigid
   content; and the interpolation property that makes the point worth a factorization: the reduced flexible response
   Hr (Kr - sigma Mr)^-1 Gr of a basis holding x = (K_S - sigma M_S)^-1 P G equals H x, the full one, at sigma.
   Serial and on 2 ranks; rank 0 prints; the exit code is non-zero on failure. */
#include "kftest.h"
#include <slepcsys.h>

#define NB 3 /* blocks: input, output, input */

static PetscErrorCode GalileoScene(KFScene *scene)
{
  const PetscReal z[3] = {0, 0, 1};
  PetscInt        stator, rotor;

  PetscFunctionBegin;
  PetscCall(KFSceneCreate(PETSC_COMM_WORLD, scene));
  PetscCall(AddGalileoBody(*scene, "stator", "stator", &stator));
  PetscCall(AddGalileoBody(*scene, "rotor", "rotor", &rotor));
  PetscCall(KFSceneAddInterface(*scene, stator, "bearing", 1));
  PetscCall(KFSceneAddInterface(*scene, rotor, "bearing", 101));
  PetscCall(KFSceneAddJoint(*scene, "spin_bearing", KF_JOINT_REVOLUTE, stator, "bearing", rotor, "bearing", z, NULL));
  PetscCall(KFSceneSetNumIO(*scene, 1, 1));
  PetscCall(KFSceneAddInputLoad(*scene, 0, stator, 1, 5, 1.0));
  PetscCall(KFSceneAddInputLoad(*scene, 0, rotor, 101, 5, -1.0));
  PetscCall(KFSceneAddOutputReading(*scene, 0, stator, 2, 4, 1.0));
  PetscCall(KFSceneSetUp(*scene));
  PetscFunctionReturn(0);
}

/* x = A^-1 b for a small dense A (n x n, column-major), Gaussian elimination with partial pivoting */
static void SmallSolve(PetscInt n, PetscReal A[], PetscReal b[])
{
  for (PetscInt k = 0; k < n; k++) {
    PetscInt p = k;
    for (PetscInt i = k + 1; i < n; i++)
      if (PetscAbsReal(A[i + k * n]) > PetscAbsReal(A[p + k * n])) p = i;
    for (PetscInt j = 0; j < n; j++) {
      PetscReal t = A[k + j * n];
      A[k + j * n] = A[p + j * n];
      A[p + j * n] = t;
    }
    { PetscReal t = b[k]; b[k] = b[p]; b[p] = t; }
    for (PetscInt i = k + 1; i < n; i++) {
      PetscReal f = A[i + k * n] / A[k + k * n];
      for (PetscInt j = k; j < n; j++) A[i + j * n] -= f * A[k + j * n];
      b[i] -= f * b[k];
    }
  }
  for (PetscInt k = n - 1; k >= 0; k--) {
    for (PetscInt j = k + 1; j < n; j++) b[k] -= A[k + j * n] * b[j];
    b[k] /= A[k + k * n];
  }
}

static PetscErrorCode CheckPoint(KFSystem sys, PetscReal fhz)
{
  const PetscReal sigma = PetscSqr(2 * PETSC_PI * fhz), angle = 30 * PETSC_PI / 180;
  KFFlexSolver    solver;
  BV              V;
  Mat             Ms, Ks, G, Ht, X, R, PG;
  PetscInt        l, k, n, ndefl;
  PetscReal       Mr[NB * NB], Kr[NB * NB], Gr[NB], Hr[NB], A[NB * NB], orth = 0, nr, nb, Tf, Tr = 0;
  Vec             x, h;
  char            what[160];

  PetscFunctionBegin;
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "point %g Hz at 30 deg\n", (double)fhz));
  PetscCall(KFSystemSetAngles(sys, &angle));
  PetscCall(KFSystemGetMatrices(sys, &Ms, &Ks, &G, &Ht));
  PetscCall(KFFlexSolverCreate(sys, &solver));
  PetscCall(KFFlexSolverSetInteriorShift(solver, sigma));
  /* the block solve: (K_S - sigma M_S) X = P G, P G = G - M Phi Phi^T G */
  PetscCall(MatDuplicate(G, MAT_DO_NOT_COPY_VALUES, &X));
  PetscCall(KFFlexSolverApply(solver, G, X));
  PetscCall(MatDuplicate(G, MAT_COPY_VALUES, &PG));
  { /* P G = G - M Phi Phi^T G, one input column, from the public rigid modes */
    Mat       Phi;
    PetscReal res;
    PetscInt  r;
    Vec       pg, phi, mphi;

    PetscCall(KFSystemGetRigidModes(sys, &Phi, &res));
    PetscCall(MatGetSize(Phi, NULL, &r));
    PetscCall(MatDenseGetColumnVecWrite(PG, 0, &pg));
    PetscCall(MatCreateVecs(Ms, NULL, &mphi));
    for (PetscInt j = 0; j < r; j++) {
      PetscReal c;

      PetscCall(MatDenseGetColumnVecRead(Phi, j, &phi));
      PetscCall(MatDenseGetColumnVecRead(G, 0, &x));
      PetscCall(VecDot(phi, x, &c));
      PetscCall(MatDenseRestoreColumnVecRead(G, 0, &x));
      PetscCall(MatMult(Ms, phi, mphi));
      PetscCall(MatDenseRestoreColumnVecRead(Phi, j, &phi));
      PetscCall(VecAXPY(pg, -c, mphi));
    }
    PetscCall(VecDestroy(&mphi));
    PetscCall(MatDenseRestoreColumnVecWrite(PG, 0, &pg));
  }
  PetscCall(MatMatMult(Ks, X, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &R));
  {
    Mat MX;
    PetscCall(MatMatMult(Ms, X, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &MX));
    PetscCall(MatAXPY(R, -sigma, MX, SAME_NONZERO_PATTERN));
    PetscCall(MatDestroy(&MX));
  }
  PetscCall(MatAXPY(R, -1.0, PG, SAME_NONZERO_PATTERN));
  PetscCall(MatNorm(R, NORM_FROBENIUS, &nr));
  PetscCall(MatNorm(PG, NORM_FROBENIUS, &nb));
  PetscCall(Check("||(K_S - sigma M_S) X - P G|| / ||P G||", nr / nb, 1e-9));
  /* the full flexible response at sigma: H x */
  PetscCall(MatDenseGetColumnVecRead(X, 0, &x));
  PetscCall(MatDenseGetColumnVecRead(Ht, 0, &h));
  PetscCall(VecDot(x, h, &Tf));
  PetscCall(MatDenseRestoreColumnVecRead(Ht, 0, &h));
  PetscCall(MatDenseRestoreColumnVecRead(X, 0, &x));
  /* the blocks at the point, projected */
  PetscCall(KFKrylovBasis(solver, 2, 1, 1e-10, &V, &ndefl));
  PetscCall(BVGetActiveColumns(V, &l, &k));
  n = k - l;
  PetscCall(Check("basis size - 3 (input, output, input)", (PetscReal)PetscAbsInt(n - NB), 0));
  if (n == NB) {
    PetscCall(KFSystemProject(sys, V, Mr, Kr, Gr, Hr));
    for (PetscInt j = 0; j < NB; j++)
      for (PetscInt i = 0; i < NB; i++) {
        orth   = PetscMax(orth, PetscAbsReal(Mr[i + j * NB] - (i == j)));
        A[i + j * NB] = Kr[i + j * NB] - sigma * Mr[i + j * NB];
      }
    PetscCall(Check("||V^T M V - I||_max", orth, 1e-12));
    SmallSolve(NB, A, Gr);
    for (PetscInt i = 0; i < NB; i++) Tr += Hr[i] * Gr[i];
    PetscCall(PetscPrintf(PETSC_COMM_WORLD, "    H x full % .12e  reduced % .12e\n", (double)Tf, (double)Tr));
    PetscCall(PetscSNPrintf(what, sizeof(what), "|T_reduced(sigma) / T_full(sigma) - 1| (interpolation at %g Hz)", (double)fhz));
    PetscCall(Check(what, PetscAbsReal(Tr / Tf - 1), 1e-9));
  }
  PetscCall(BVDestroy(&V));
  PetscCall(MatDestroy(&R));
  PetscCall(MatDestroy(&PG));
  PetscCall(MatDestroy(&X));
  PetscCall(KFFlexSolverDestroy(&solver));
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  KFScene     scene;
  KFSystem    sys;
  PetscMPIInt size;

  PetscCall(SlepcInitialize(&argc, &argv, NULL, "Expansion points inside the band through the C API"));
  PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
  PetscCall(PetscOptionsSetValue(NULL, "-kf_quiet", NULL));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "test_expansion_points on %d rank(s)\n", size));
  PetscCall(GalileoScene(&scene));
  PetscCall(KFSystemCreate(scene, &sys));
  PetscCall(CheckPoint(sys, 2.0));
  PetscCall(CheckPoint(sys, 7.5));
  PetscCall(KFSystemDestroy(&sys));
  PetscCall(KFSceneDestroy(&scene));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "%s: %d failure(s)\n", nfail ? "FAILED" : "passed", nfail));
  PetscCall(SlepcFinalize());
  return nfail ? 1 : 0;
}
