/* Krylov reduction at one configuration through the C API alone (paper eq. 5-11), on the Galileo-like model:
   the scene is built here from the body files (KFMatLoadFile and the nodes files), K+ factored once, a 10-vector
   block Krylov basis built (9 input blocks and 1 output block) and projected, and the reduced system's moments
   (KFDenseMoments of KFSystemProject) compared with the full-order ones (KFFlexSolverMoments) at two clock angles.
   Runs from the source root (CMake sets the working folder), serial and on 2 ranks; rank 0 prints; the exit code
   is non-zero on failure. */
#include "kftest.h"
#include <slepcsys.h>

#define NMOM    10
#define MATCH   1e-8 /* the paper's Table 6: L_full^k / L_reduced^k = 1 to 8 digits */


/* Stator (node 1 bearing, node 2 point A) and rotor (node 101 hub) joined by a revolute bearing about z;
   input: +torque about z on the stator's bearing node, -torque on the rotor's; output: rotation about y at A. */
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

static PetscErrorCode CheckAngle(KFSystem sys, PetscReal degrees)
{
  const PetscInt nin = NMOM - 1, nout = 1;
  PetscReal      angle = degrees * PETSC_PI / 180, Lf[NMOM], Lr[NMOM], ratio = 0, orth = 0, gram_cond;
  PetscReal      Mr[NMOM * NMOM], Kr[NMOM * NMOM], Gr[NMOM], Hr[NMOM];
  PetscInt       c0, c, ndeflated;
  KFFlexSolver   solver;
  BV             V;
  Mat            raw;
  char           what[128];

  PetscFunctionBegin;
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "alpha = %d deg\n", (int)degrees));
  PetscCall(KFSystemSetAngles(sys, &angle));
  PetscCall(KFFlexSolverCreate(sys, &solver));
  { /* the factorization holds dofs in K_S itself and must give K_S back bit for bit */
    Mat       Ks, K0;
    PetscReal diff;
    PetscCall(KFSystemGetMatrices(sys, NULL, &Ks, NULL, NULL));
    PetscCall(MatDuplicate(Ks, MAT_COPY_VALUES, &K0));
    PetscCall(KFFlexSolverSetUp(solver));
    PetscCall(MatAXPY(K0, -1.0, Ks, SAME_NONZERO_PATTERN));
    PetscCall(MatNorm(K0, NORM_MAX, &diff));
    PetscCall(Check("max |K_S after the held factorization - K_S before| (restored exactly)", diff, 0));
    PetscCall(MatDestroy(&K0));
  }
  PetscCall(KFFlexSolverMoments(solver, NMOM, Lf));
  PetscCall(KFKrylovBasis(solver, nin, nout, 1e-10, &V, &ndeflated));
  PetscCall(BVGetActiveColumns(V, &c0, &c));
  PetscCall(Check("basis size - 10 (1 input, 1 output: 9 + 1 vectors)", (PetscReal)PetscAbsInt(c - c0 - NMOM), 0));
  PetscCall(Check("deflated columns", (PetscReal)ndeflated, 0));
  if (c - c0 == NMOM) {
    PetscCall(KFSystemProject(sys, V, Mr, Kr, Gr, Hr));
    for (PetscInt j = 0; j < NMOM; j++)
      for (PetscInt i = 0; i < NMOM; i++) orth = PetscMax(orth, PetscAbsReal(Mr[i + j * NMOM] - (i == j)));
    PetscCall(Check("||V^T M V - I||_max (M-orthonormal basis)", orth, 1e-12));
    /* the basis is M-orthogonal to the rigid modes: no reduced eigenvalue is rigid, hence the tiny tolerance */
    PetscCall(KFDenseMoments(NMOM, Kr, Mr, 1, Gr, 1, Hr, 1e-14, NMOM, Lr));
    for (PetscInt k = 0; k < NMOM; k++) {
      PetscReal r = PetscAbsReal(Lf[k] / Lr[k] - 1);
      PetscCall(PetscPrintf(PETSC_COMM_WORLD, "    L^%" PetscInt_FMT " full % .10e  reduced % .10e  ratio %.12f\n", k, (double)Lf[k], (double)Lr[k], (double)(Lf[k] / Lr[k])));
      ratio = PetscMax(ratio, PetscIsInfOrNanReal(r) ? PETSC_INFINITY : r);
    }
    PetscCall(PetscSNPrintf(what, sizeof(what), "max_k |L_full^k / L_reduced^k - 1|, %d moments", NMOM));
    PetscCall(Check(what, ratio, MATCH));
  }
  /* the paper's raw recurrence spans the same space but is numerically rank deficient */
  PetscCall(KFKrylovRawBasis(solver, nin, nout, &raw, &gram_cond));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "    raw recurrence (eq. 9): condition of its M-Gram matrix %.3e\n", (double)gram_cond));
  PetscCall(Check("raw recurrence ill-conditioned: 1e10 / cond(M-Gram) <= 1", 1e10 / gram_cond, 1));
  PetscCall(MatDestroy(&raw));
  PetscCall(BVDestroy(&V));
  PetscCall(KFFlexSolverDestroy(&solver));
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  KFScene     scene;
  KFSystem    sys;
  PetscMPIInt size;

  PetscCall(SlepcInitialize(&argc, &argv, NULL, "Krylov reduction of the Galileo-like model through the C API"));
  PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
  PetscCall(PetscOptionsSetValue(NULL, "-kf_quiet", NULL));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "test_krylov on %d rank(s)\n", size));
  PetscCall(GalileoScene(&scene));
  PetscCall(KFSystemCreate(scene, &sys));
  PetscCall(CheckAngle(sys, 0.0));
  PetscCall(CheckAngle(sys, 60.0));
  PetscCall(KFSystemDestroy(&sys));
  PetscCall(KFSceneDestroy(&scene));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "%s: %d failure(s)\n", nfail ? "FAILED" : "passed", nfail));
  PetscCall(SlepcFinalize());
  return nfail ? 1 : 0;
}
