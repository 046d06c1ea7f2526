/* Tests of trimming (src/model/trim.c) through the C API, on the Galileo bodies of meshes/galileo:
   - KFParseMaxFrequency: "3", "3x", "40 Hz", "none" accepted; "0.5" (below the band's top), "3 kHz", "-1" refused with
     an error code, the same on every rank;
   - the paper's fixed recipe (c = 10, h2 importance, threshold 0.1, search off) with KFReducerSetMaxFrequency(3, false)
     and with -kf_max_frequency unset: at 0, 37.5 and 72 deg the trimmed system keeps no flexible frequency above 30
     Hz, its static moment L^0 is the untrimmed one (the same model with the setting max_frequency_hz 0) to 1e-10, its
     L^1 is within 1e-3 of it, and its frequency response at 1 Hz within 1e-3 of the untrimmed one;
   - KFReducedSystemTrim again with the same limit changes nothing.
   Run from the source folder (CTest does), serial or under mpiexec; rank 0 prints; non-zero exit on failure. */
#include "kftest.h"

static PetscErrorCode GalileoScene(KFScene *scene)
{
  const PetscReal z[3] = {0, 0, 1};
  PetscInt        stator, rotor;

  PetscFunctionBegin;
  PetscCall(KFSceneCreate(PETSC_COMM_WORLD, scene));
  PetscCall(KFSceneSetName(*scene, "galileo"));
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

static PetscErrorCode TestParse(void)
{
  const char *good[] = {"3", "3x", "40 Hz", "40hz", "none"}, *bad[] = {"0.5", "3 kHz", "-1", "x"};
  PetscReal   v;
  PetscBool   hz;

  PetscFunctionBegin;
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "KFParseMaxFrequency\n"));
  for (size_t i = 0; i < sizeof(good) / sizeof(good[0]); i++) {
    char what[128];
    PetscCall(KFParseMaxFrequency(PETSC_COMM_WORLD, good[i], &v, &hz));
    PetscCall(PetscSNPrintf(what, sizeof(what), "'%s' accepted as %g%s", good[i], (double)v, hz ? " Hz" : ""));
    PetscCall(CheckTrue(what, (PetscBool)(i < 2 ? (v == 3 && !hz) : i < 4 ? (v == 40 && hz) : v == 0)));
  }
  for (size_t i = 0; i < sizeof(bad) / sizeof(bad[0]); i++) {
    PetscErrorCode ierr;
    int            code, lo, hi;
    char           what[128];

    PetscCall(KFPushErrorRecorder());
    ierr = KFParseMaxFrequency(PETSC_COMM_WORLD, bad[i], &v, &hz);
    PetscCall(PetscPopErrorHandler());
    code = (int)ierr;
    PetscCallMPI(MPI_Allreduce(&code, &lo, 1, MPI_INT, MPI_MIN, PETSC_COMM_WORLD));
    PetscCallMPI(MPI_Allreduce(&code, &hi, 1, MPI_INT, MPI_MAX, PETSC_COMM_WORLD));
    PetscCall(PetscPrintf(PETSC_COMM_WORLD, "    -> %s\n", KFLastError()));
    PetscCall(PetscSNPrintf(what, sizeof(what), "'%s' refused (an error code, the same on every rank)", bad[i]));
    PetscCall(CheckTrue(what, (PetscBool)(lo != 0 && lo == hi)));
    KFClearError();
  }
  PetscFunctionReturn(0);
}

static PetscReal MaxAbs(PetscInt n, const PetscReal x[])
{
  PetscReal m = 0;
  for (PetscInt i = 0; i < n; i++) m = PetscMax(m, PetscAbsReal(x[i]));
  return m;
}

static PetscErrorCode TestTrim(KFScene scene)
{
  const PetscReal deg[6] = {0, 15, 30, 45, 60, 72}, probe[3] = {0, 37.5, 72}, w = 2 * PETSC_PI * 1.0;
  PetscReal       angles[6], limit, fmax;
  KFReducer       r;
  KFReducedModel  model;
  char            what[256];

  PetscFunctionBegin;
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "the paper's recipe on Galileo, max_frequency 3 x the band's top\n"));
  for (PetscInt c = 0; c < 6; c++) angles[c] = deg[c] * PETSC_PI / 180;
  PetscCall(KFReducerCreate(PETSC_COMM_WORLD, &r));
  PetscCall(KFReducerSetScene(r, scene));
  PetscCall(KFReducerSetAngles(r, 6, angles));
  PetscCall(KFReducerSetBand(r, 0.01, 10));
  PetscCall(KFReducerSetDamping(r, 0.0025));
  PetscCall(KFReducerSetMoments(r, 10, 1));
  PetscCall(KFReducerSetImportance(r, KF_IMPORTANCE_H2, 0.1));
  PetscCall(KFReducerSetSearch(r, PETSC_FALSE, 24));
  PetscCall(KFReducerSetVerification(r, PETSC_FALSE, PETSC_DECIDE, 100, -60));
  PetscCall(KFReducerSetMaxFrequency(r, 3, PETSC_FALSE));
  PetscCall(KFReducerSetFromOptions(r));
  PetscCall(KFReducerGetMaxFrequency(r, &limit));
  PetscCall(Check("KFReducerGetMaxFrequency: 3 x 10 Hz", PetscAbsReal(limit - 30), 1e-12));
  PetscCall(KFReducerSolve(r));
  PetscCall(KFReducerGetReducedModel(r, &model));
  PetscCall(PetscObjectReference((PetscObject)model));
  PetscCall(KFReducerDestroy(&r));
  PetscCall(KFReducedModelGetMaxFrequency(model, &fmax));
  PetscCall(Check("the model records max_frequency_hz = 30", PetscAbsReal(fmax - 30), 1e-12));

  for (PetscInt p = 0; p < 3; p++) {
    const PetscReal  alpha = probe[p] * PETSC_PI / 180;
    KFReducedSystem  st, su;
    PetscInt         nt, nft, nfu, ntrim, a, t;
    PetscReal        L[4], Lu[4], Tr[2], Ti[2], Tur[2], Tui[2], f, ftop;
    const PetscReal *freqt, *frequ, *D;

    PetscCall(KFReducedModelReassemble(model, &alpha, &st));
    PetscCall(KFReducedModelSetSetting(model, "max_frequency_hz", "0"));
    PetscCall(KFReducedModelReassemble(model, &alpha, &su));
    PetscCall(KFReducedModelSetSetting(model, "max_frequency_hz", "30"));
    PetscCall(KFReducedSystemGetMatrices(st, &nt, &a, &t, NULL, NULL, NULL, NULL));
    PetscCall(KFReducedSystemGetFrequencies(st, &nft, &freqt));
    PetscCall(KFReducedSystemGetFrequencies(su, &nfu, &frequ));
    PetscCall(KFReducedSystemGetTrim(st, &ntrim, &f, &ftop, &D));
    PetscCall(PetscPrintf(PETSC_COMM_WORLD, "  %g deg: %" PetscInt_FMT " flexible modes up to %.4g Hz untrimmed, %" PetscInt_FMT " trimmed, kept up to %.4g Hz\n", (double)probe[p], nfu, (double)frequ[nfu - 1], ntrim, (double)(nft ? freqt[nft - 1] : 0)));
    PetscCall(PetscSNPrintf(what, sizeof(what), "%g deg: modes above 30 Hz trimmed (%" PetscInt_FMT "), none left above it, a feedthrough", (double)probe[p], ntrim));
    PetscCall(CheckTrue(what, (PetscBool)(ntrim > 0 && ntrim == nfu - nft && (!nft || freqt[nft - 1] <= 30) && frequ[nfu - 1] > 30 && D && PetscAbsReal(ftop - frequ[nfu - 1]) <= 1e-12 * ftop)));
    PetscCall(KFReducedSystemMoments(st, 2, L));
    PetscCall(KFReducedSystemMoments(su, 2, Lu));
    PetscCall(PetscSNPrintf(what, sizeof(what), "%g deg: L^0 trimmed vs untrimmed (relative)", (double)probe[p]));
    PetscCall(Check(what, PetscAbsReal(L[0] - Lu[0]) / MaxAbs(1, Lu), 1e-10));
    PetscCall(PetscSNPrintf(what, sizeof(what), "%g deg: L^1 trimmed vs untrimmed (relative; the trimmed modes' share)", (double)probe[p]));
    PetscCall(Check(what, PetscAbsReal(L[1] - Lu[1]) / MaxAbs(1, Lu + 1), 1e-3));
    PetscCall(KFReducedSystemFRF(st, 0.0025, 1, &w, Tr, Ti));
    PetscCall(KFReducedSystemFRF(su, 0.0025, 1, &w, Tur, Tui));
    PetscCall(PetscSNPrintf(what, sizeof(what), "%g deg: frequency response at 1 Hz, trimmed vs untrimmed (relative)", (double)probe[p]));
    PetscCall(Check(what, PetscSqrtReal(PetscSqr(Tr[0] - Tur[0]) + PetscSqr(Ti[0] - Tui[0])) / PetscSqrtReal(PetscSqr(Tur[0]) + PetscSqr(Tui[0])), 1e-3));
    PetscCall(KFReducedSystemTrim(st, 30));
    PetscCall(KFReducedSystemGetFrequencies(st, &nfu, NULL));
    PetscCall(KFReducedSystemGetTrim(st, &nt, NULL, &f, NULL));
    PetscCall(CheckTrue("trimming again with the same limit changes nothing", (PetscBool)(nfu == nft && nt == ntrim && f == ftop)));
    PetscCall(KFReducedSystemDestroy(&st));
    PetscCall(KFReducedSystemDestroy(&su));
  }
  PetscCall(KFReducedModelDestroy(&model));
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  KFScene     scene;
  PetscMPIInt size;

  PetscCall(SlepcInitialize(&argc, &argv, NULL, "Trimming: modes above max_frequency out of the dynamics, L^0 kept"));
  PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
  PetscCall(PetscOptionsSetValue(NULL, "-kf_quiet", NULL));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "test_trim on %d rank(s)\n", size));
  PetscCall(TestParse());
  PetscCall(GalileoScene(&scene));
  PetscCall(TestTrim(scene));
  PetscCall(KFSceneDestroy(&scene));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "%s: %d failure(s)\n", nfail ? "FAILED" : "passed", nfail));
  PetscCall(SlepcFinalize());
  return nfail ? 1 : 0;
}
