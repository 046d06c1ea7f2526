/* The body-wise flexible solve (src/solve/bodywise.c) through the C API: K+ G body-wise equals K+ G monolithic at
   several configurations of a 3-body chain made of the Galileo-like bodies (a stator with both nodes on interfaces,
   so an empty interior; the rotor on its bearing; a second stator hinged to the first's node 2 about a skew axis),
   with a shift too; the sparse factorization counts (one per configuration monolithic, one per body for all of them
   body-wise); -kf_flex_solver auto going body-wise for this articulated scene; a single-body scene falling back. */
#include "kftest.h"

#define SAME    1e-10


static PetscErrorCode ChainScene(PetscBool single, KFScene *scene)
{
  PetscInt  stator, rotor, arm;
  PetscReal z[3] = {0, 0, 1}, skew[3] = {0.6, 0.0, 0.8};

  PetscFunctionBegin;
  PetscCall(KFSceneCreate(PETSC_COMM_WORLD, scene));
  PetscCall(AddGalileoBody(*scene, "stator", "stator", &stator));
  PetscCall(KFSceneSetNumIO(*scene, 1, single ? 1 : 2));
  if (!single) {
    PetscCall(AddGalileoBody(*scene, "rotor", "rotor", &rotor));
    PetscCall(AddGalileoBody(*scene, "stator", "arm", &arm));
    PetscCall(KFSceneAddInterface(*scene, stator, "bearing", 1));
    PetscCall(KFSceneAddInterface(*scene, stator, "hinge", 2));
    PetscCall(KFSceneAddInterface(*scene, rotor, "bearing", 101));
    PetscCall(KFSceneAddInterface(*scene, arm, "hinge", 1));
    PetscCall(KFSceneAddJoint(*scene, "spin_bearing", KF_JOINT_REVOLUTE, stator, "bearing", rotor, "bearing", z, NULL));
    PetscCall(KFSceneAddJoint(*scene, "arm_hinge", KF_JOINT_REVOLUTE, stator, "hinge", arm, "hinge", skew, NULL));
    PetscCall(KFSceneAddInputLoad(*scene, 0, rotor, 102, 1, 1.0));
    PetscCall(KFSceneAddOutputReading(*scene, 1, arm, 2, 0, 1.0));
  } else PetscCall(KFSceneAddInputLoad(*scene, 0, stator, 2, 1, 1.0));
  PetscCall(KFSceneAddOutputReading(*scene, 0, stator, 2, 4, 1.0));
  PetscCall(KFSceneSetUp(*scene));
  PetscFunctionReturn(0);
}

/* K+ G with the given implementation (and shift); the type actually set up */
static PetscErrorCode Solve(KFSystem sys, KFFlexSolverType type, PetscReal shift, Mat *X, char used[32])
{
  KFFlexSolver     solver;
  KFFlexSolverType t;
  Mat              G;

  PetscFunctionBegin;
  PetscCall(KFSystemGetMatrices(sys, NULL, NULL, &G, NULL));
  PetscCall(KFFlexSolverCreate(sys, &solver));
  PetscCall(KFFlexSolverSetType(solver, type));
  if (shift > 0) PetscCall(KFFlexSolverSetShift(solver, shift));
  PetscCall(MatDuplicate(G, MAT_DO_NOT_COPY_VALUES, X));
  PetscCall(KFFlexSolverApply(solver, G, *X));
  PetscCall(KFFlexSolverGetType(solver, &t));
  PetscCall(PetscStrncpy(used, t, 32)); /* the name is the solver's: copied before it goes */
  PetscCall(KFFlexSolverDestroy(&solver));
  PetscFunctionReturn(0);
}

static PetscErrorCode RelDiff(Mat A, Mat B, PetscReal *rel)
{
  PetscReal na, nb;
  Mat       D;

  PetscFunctionBegin;
  PetscCall(MatDuplicate(A, MAT_COPY_VALUES, &D));
  PetscCall(MatAXPY(D, -1.0, B, SAME_NONZERO_PATTERN));
  PetscCall(MatNorm(D, NORM_FROBENIUS, &na));
  PetscCall(MatNorm(B, NORM_FROBENIUS, &nb));
  *rel = na / nb;
  PetscCall(MatDestroy(&D));
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  KFScene          scene;
  KFSystem         mono, body, autos;
  PetscReal        configs[4][2] = {{0, 0}, {0.4, 1.1}, {2.5, -0.7}, {4.0, 3.0}}, rel;
  PetscInt         nmono, nbody, nauto;
  char             used[32], used2[32];
  char             what[256];
  PetscBool        types_ok = PETSC_TRUE, auto_ok = PETSC_TRUE;
  Mat              X1;

  PetscCall(SlepcInitialize(&argc, &argv, NULL, "body-wise flexible solve"));
  PetscCall(KFInitialize());
  PetscCall(PetscOptionsSetValue(NULL, "-kf_quiet", "1"));
  PetscCall(ChainScene(PETSC_FALSE, &scene));
  PetscCall(KFSystemCreate(scene, &mono));
  PetscCall(KFSystemCreate(scene, &body));
  PetscCall(KFSystemCreate(scene, &autos));
  PetscCall(KFSystemSetConfigurationCount(autos, 4)); /* auto: the bodies factored once for the 4 configurations */
  for (PetscInt c = 0; c < 4; c++) {
    Mat Xm, Xb;
    PetscCall(KFSystemSetAngles(mono, configs[c]));
    PetscCall(KFSystemSetAngles(body, configs[c]));
    PetscCall(KFSystemSetAngles(autos, configs[c]));
    PetscCall(Solve(mono, KFFLEXSOLVERMONOLITHIC, 0, &Xm, used));
    types_ok = (PetscBool)(types_ok && !strcmp(used, KFFLEXSOLVERMONOLITHIC));
    PetscCall(Solve(body, KFFLEXSOLVERBODYWISE, 0, &Xb, used));
    types_ok = (PetscBool)(types_ok && !strcmp(used, KFFLEXSOLVERBODYWISE));
    PetscCall(RelDiff(Xb, Xm, &rel));
    PetscCall(PetscSNPrintf(what, sizeof(what), "3-body chain at (%g, %g) rad: |K+G body-wise - monolithic| / |K+G|", (double)configs[c][0], (double)configs[c][1]));
    PetscCall(Check(what, rel, SAME));
    PetscCall(MatDestroy(&Xb));
    /* auto takes the body-wise solve from -kf_bodywise_min_dofs system dofs on: 0 for this small chain */
    PetscCall(PetscOptionsSetValue(NULL, "-kf_bodywise_min_dofs", "0"));
    PetscCall(Solve(autos, KFFLEXSOLVERAUTO, 0, &Xb, used));
    PetscCall(PetscOptionsClearValue(NULL, "-kf_bodywise_min_dofs"));
    auto_ok = (PetscBool)(auto_ok && !strcmp(used, KFFLEXSOLVERBODYWISE));
    PetscCall(RelDiff(Xb, Xm, &rel));
    PetscCall(PetscSNPrintf(what, sizeof(what), "  the same with -kf_flex_solver auto (%s)", !strcmp(used, KFFLEXSOLVERBODYWISE) ? "body-wise" : "monolithic"));
    PetscCall(Check(what, rel, SAME));
    PetscCall(MatDestroy(&Xb));
    PetscCall(MatDestroy(&Xm));
  }
  PetscCall(KFSystemGetFactorCount(mono, &nmono));
  PetscCall(KFSystemGetFactorCount(body, &nbody));
  PetscCall(KFSystemGetFactorCount(autos, &nauto));
  PetscCall(CheckTrue("each solver set up the implementation asked for", types_ok));
  PetscCall(CheckTrue("auto (-kf_bodywise_min_dofs 0): body-wise for this articulated scene", auto_ok));
  {
    /* the default solver is auto: monolithic for a system solved at one configuration (whatever its size), and for
       this chain far below the default -kf_bodywise_min_dofs even at 4 */
    KFSystem sys1;
    PetscCall(KFSystemCreate(scene, &sys1));
    PetscCall(KFSystemSetAngles(sys1, configs[1]));
    PetscCall(PetscOptionsSetValue(NULL, "-kf_bodywise_min_dofs", "0"));
    PetscCall(Solve(sys1, KFFLEXSOLVERAUTO, 0, &X1, used));
    PetscCall(PetscOptionsClearValue(NULL, "-kf_bodywise_min_dofs"));
    PetscCall(CheckTrue("auto at one configuration: monolithic", (PetscBool)(!strcmp(used, KFFLEXSOLVERMONOLITHIC))));
    PetscCall(MatDestroy(&X1));
    PetscCall(KFSystemSetConfigurationCount(sys1, 4));
    PetscCall(Solve(sys1, KFFLEXSOLVERAUTO, 0, &X1, used));
    PetscCall(CheckTrue("auto at 4 configurations of a scene below -kf_bodywise_min_dofs (20000): monolithic", (PetscBool)(!strcmp(used, KFFLEXSOLVERMONOLITHIC))));
    PetscCall(MatDestroy(&X1));
    { /* the threshold through the implementation's composed setter: body-wise; a monolithic solver ignores the call */
      KFFlexSolver     f;
      KFFlexSolverType t;

      PetscCall(KFFlexSolverCreate(sys1, &f));
      PetscCall(KFFlexSolverSetFromOptions(f)); /* auto, the default type */
      PetscCall(KFFlexSolverBodywiseSetMinDofs(f, 0));
      PetscCall(KFFlexSolverSetUp(f));
      PetscCall(KFFlexSolverGetType(f, &t));
      PetscCall(CheckTrue("auto at 4 configurations after KFFlexSolverBodywiseSetMinDofs(0): body-wise", (PetscBool)!strcmp(t, KFFLEXSOLVERBODYWISE)));
      PetscCall(KFFlexSolverDestroy(&f));
      PetscCall(KFFlexSolverCreate(sys1, &f));
      PetscCall(KFFlexSolverSetType(f, KFFLEXSOLVERMONOLITHIC));
      PetscCall(KFFlexSolverBodywiseSetMinDofs(f, 0));
      PetscCall(KFFlexSolverSetUp(f));
      PetscCall(KFFlexSolverGetType(f, &t));
      PetscCall(CheckTrue("a monolithic solver ignores KFFlexSolverBodywiseSetMinDofs", (PetscBool)!strcmp(t, KFFLEXSOLVERMONOLITHIC)));
      PetscCall(KFFlexSolverDestroy(&f));
    }
    PetscCall(KFSystemDestroy(&sys1));
  }
  PetscCall(PetscSNPrintf(what, sizeof(what), "factorizations over 4 configurations: monolithic %" PetscInt_FMT " (4), body-wise %" PetscInt_FMT " (3 bodies), auto %" PetscInt_FMT " (3)", nmono, nbody, nauto));
  PetscCall(CheckTrue(what, (PetscBool)(nmono == 4 && nbody == 3 && nauto == 3)));
  {
    /* a shift: K + sigma M factored body by body (the body factors are made again for it) */
    Mat Xm, Xb;
    PetscCall(Solve(mono, KFFLEXSOLVERMONOLITHIC, 10.0, &Xm, used));
    PetscCall(Solve(body, KFFLEXSOLVERBODYWISE, 10.0, &Xb, used2));
    PetscCall(RelDiff(Xb, Xm, &rel));
    PetscCall(Check("with shift 10: |K+G body-wise - monolithic| / |K+G|", rel, SAME));
    PetscCall(MatDestroy(&Xm));
    PetscCall(MatDestroy(&Xb));
  }
  {
    /* without iterative refinement (which makes both the nearest doubles of one answer): the raw solves agree */
    Mat Xm, Xb;
    PetscCall(PetscOptionsSetValue(NULL, "-kf_refine", "0"));
    PetscCall(Solve(mono, KFFLEXSOLVERMONOLITHIC, 0, &Xm, used));
    PetscCall(Solve(body, KFFLEXSOLVERBODYWISE, 0, &Xb, used2));
    PetscCall(PetscOptionsClearValue(NULL, "-kf_refine"));
    PetscCall(RelDiff(Xb, Xm, &rel));
    PetscCall(Check("without refinement (-kf_refine 0): |K+G body-wise - monolithic| / |K+G|", rel, SAME));
    PetscCall(MatDestroy(&Xm));
    PetscCall(MatDestroy(&Xb));
  }
  PetscCall(KFSystemDestroy(&mono));
  PetscCall(KFSystemDestroy(&body));
  PetscCall(KFSystemDestroy(&autos));
  PetscCall(KFSceneDestroy(&scene));

  /* one body: no interface problem, the monolithic solve */
  PetscCall(ChainScene(PETSC_TRUE, &scene));
  PetscCall(KFSystemCreate(scene, &body));
  PetscCall(KFSystemSetAngles(body, NULL));
  {
    Mat X;
    PetscCall(Solve(body, KFFLEXSOLVERBODYWISE, 0, &X, used));
    PetscCall(CheckTrue("a single body falls back to the monolithic solve", (PetscBool)(!strcmp(used, KFFLEXSOLVERMONOLITHIC))));
    PetscCall(MatDestroy(&X));
  }
  PetscCall(KFSystemDestroy(&body));
  PetscCall(KFSceneDestroy(&scene));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "%s: %d failed\n", nfail ? "FAIL" : "PASS", nfail));
  PetscCall(SlepcFinalize());
  return nfail ? 1 : 0;
}
