/* Reassembly of a reduced model (HDF5 from kryflex reduce or ReducedModel.save) at changing angles: per-call times
   of KFReducedModelReassemble (allocates, always with the eigen-decomposition), KFReassemblyApply (caller arrays, no
   allocation) and KFReassemblyApply + KFReassemblyEig, measured side by side in one run, with their ratios.

     bench_reassembly model.h5 [-calls 2000]

   The angles sweep every revolute joint through a full turn, the same angles for every path. */
#include <kryflex.h>

static PetscErrorCode Angles(PetscInt nrev, PetscInt i, PetscInt calls, PetscReal ang[])
{
  PetscFunctionBegin;
  for (PetscInt r = 0; r < nrev; r++) ang[r] = 2 * PETSC_PI * ((PetscReal)i / calls + 0.37 * r);
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  KFReducedModel model;
  KFReassembly   work;
  char           path[PETSC_MAX_PATH_LEN] = "";
  PetscBool      set, viscous, rigid;
  PetscInt       calls = 2000, nrev, n, a, t, h = 0, rank, nrigid, reps = 5;
  PetscReal     *M, *K, *C, *G, *H, *Phir, *lam, *Phi, ratio, ang[64];
  PetscLogDouble best[3] = {1e30, 1e30, 1e30};
  double         checksum = 0;

  PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
  PetscCall(PetscOptionsGetString(NULL, NULL, "-model", path, sizeof(path), &set));
  if (!set && argc > 1 && argv[1][0] != '-') PetscCall(PetscStrncpy(path, argv[1], sizeof(path)));
  PetscCheck(path[0], PETSC_COMM_WORLD, PETSC_ERR_USER_INPUT, "give the reduced model file: bench_reassembly model.h5 [-calls N]");
  PetscCall(PetscOptionsGetInt(NULL, NULL, "-calls", &calls, NULL));
  PetscCall(PetscOptionsGetInt(NULL, NULL, "-reps", &reps, NULL));
  PetscCall(KFReducedModelLoad(PETSC_COMM_SELF, path, &model));
  PetscCall(KFReducedModelGetInfo(model, NULL, NULL, &nrev, NULL, NULL, NULL));
  PetscCheck(nrev <= 64, PETSC_COMM_SELF, PETSC_ERR_SUP, "at most 64 revolute joints in this bench");
  PetscCall(KFReducedModelCreateReassembly(model, &work));
  PetscCall(KFReassemblyGetSizes(work, &n, &a, &t, &viscous, &rigid));
  PetscCall(PetscMalloc4(n * n, &M, n * n, &K, n * n, &C, n * a + 1, &G));
  PetscCall(PetscMalloc4(t * n + 1, &H, n * n, &Phir, n, &lam, n * n, &Phi));
  /* the best of reps repetitions of each path, interleaved so that a busy machine slows them alike */
  for (PetscInt rep = 0; rep < reps; rep++) {
    PetscLogDouble t0, t1;
    PetscCall(PetscTime(&t0));
    for (PetscInt i = 0; i < calls; i++) {
      KFReducedSystem y;
      const PetscReal *Ky;
      PetscCall(Angles(nrev, i, calls, ang));
      PetscCall(KFReducedModelReassemble(model, ang, &y));
      PetscCall(KFReducedSystemGetMatrices(y, &h, NULL, NULL, NULL, &Ky, NULL, NULL));
      checksum += Ky[0];
      PetscCall(KFReducedSystemDestroy(&y));
    }
    PetscCall(PetscTime(&t1));
    best[0] = PetscMin(best[0], (t1 - t0) / calls);
    PetscCall(PetscTime(&t0));
    for (PetscInt i = 0; i < calls; i++) {
      PetscCall(Angles(nrev, i, calls, ang));
      PetscCall(KFReassemblyApply(work, ang, &h, M, K, (viscous ? C : NULL), G, H, &rank, &ratio, &nrigid, rigid ? Phir : NULL));
      checksum += K[0];
    }
    PetscCall(PetscTime(&t1));
    best[1] = PetscMin(best[1], (t1 - t0) / calls);
    PetscCall(PetscTime(&t0));
    for (PetscInt i = 0; i < calls; i++) {
      PetscCall(Angles(nrev, i, calls, ang));
      PetscCall(KFReassemblyApply(work, ang, &h, M, K, (viscous ? C : NULL), G, H, &rank, &ratio, &nrigid, rigid ? Phir : NULL));
      PetscCall(KFReassemblyEig(work, h, M, K, nrigid, rigid ? Phir : NULL, lam, Phi));
      checksum += lam[h - 1];
    }
    PetscCall(PetscTime(&t1));
    best[2] = PetscMin(best[2], (t1 - t0) / calls);
  }
  PetscCall(PetscPrintf(PETSC_COMM_SELF, "model %s: %" PetscInt_FMT " system dofs, %" PetscInt_FMT " revolute joints, %" PetscInt_FMT " calls x %" PetscInt_FMT " repetitions (best)\n", path, h, nrev, calls, reps));
  PetscCall(PetscPrintf(PETSC_COMM_SELF, "C  KFReducedModelReassemble (with eigen)   %9.2f us\n", best[0] * 1e6));
  PetscCall(PetscPrintf(PETSC_COMM_SELF, "C  KFReassemblyApply                        %9.2f us   ratio to the old path %.3f\n", best[1] * 1e6, best[1] / best[0]));
  PetscCall(PetscPrintf(PETSC_COMM_SELF, "C  KFReassemblyApply + KFReassemblyEig      %9.2f us   ratio to the old path %.3f\n", best[2] * 1e6, best[2] / best[0]));
  PetscCall(PetscPrintf(PETSC_COMM_SELF, "(checksum %g)\n", checksum));
  PetscCall(PetscFree4(M, K, C, G));
  PetscCall(PetscFree4(H, Phir, lam, Phi));
  PetscCall(KFReassemblyDestroy(&work));
  PetscCall(KFReducedModelDestroy(&model));
  PetscCall(PetscFinalize());
  return 0;
}
