/* Reassembly of a reduced model (HDF5 from kryflex reduce or ReducedModel.save) at changing angles: per-call times
   of KFReducedModelReassemble (one shot: allocates, always with the eigen-decomposition), KFReassemblyApply (caller
   arrays, no allocation) on the SVD path and on the closed form, for the matrices alone and with the ties' rank and
   the rigid modes (which need SVDs on either path), and the closed form plus KFReassemblyEig, measured side by side
   in one run, with their ratios.

     bench_reassembly model.h5 [-calls 2000] [-reps 5] [-cpu]

   The angles sweep every revolute joint through a full turn, the same angles for every path. */
#include <kryflex.h>
#include <time.h>

/* the process's CPU seconds (POSIX, nanosecond clock): on a shared machine the waits for a core are left out */
static PetscErrorCode CPUTime(PetscLogDouble *t)
{
  struct timespec ts;

  PetscFunctionBegin;
  PetscCheck(!clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts), PETSC_COMM_SELF, PETSC_ERR_SYS, "clock_gettime(CLOCK_PROCESS_CPUTIME_ID) failed: run without -cpu");
  *t = (PetscLogDouble)ts.tv_sec + 1e-9 * (PetscLogDouble)ts.tv_nsec;
  PetscFunctionReturn(0);
}

static PetscErrorCode Angles(PetscInt nrev, PetscInt i, PetscInt calls, PetscReal ang[])
{
  PetscFunctionBegin;
  for (PetscInt r = 0; r < nrev; r++) ang[r] = 2 * PETSC_PI * ((PetscReal)i / calls + 0.37 * r);
  PetscFunctionReturn(0);
}

#define NPATH 6
static const char *names[NPATH] = {"KFReducedModelReassemble (one shot, eigen)", "KFReassemblyApply, SVD (matrices)", "KFReassemblyApply, closed form (matrices)", "KFReassemblyApply, SVD, rank + rigid modes", "KFReassemblyApply, closed form, rank + rigid", "KFReassemblyApply + KFReassemblyEig (closed)"};

int main(int argc, char **argv)
{
  KFReducedModel model;
  KFReassembly   work, svd;
  char           path[PETSC_MAX_PATH_LEN] = "";
  PetscBool      set, viscous, rigid, closed, cpu = PETSC_FALSE;
  PetscInt       calls = 2000, nrev, n, a, t, h = 0, rank, nrigid, reps = 5;
  PetscReal     *M, *K, *C, *G, *H, *Phir, *lam, *Phi, ratio, ang[64];
  PetscLogDouble best[NPATH];
  double         checksum = 0;

  for (PetscInt p = 0; p < NPATH; p++) best[p] = 1e30;
  PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
  PetscCall(PetscOptionsGetString(NULL, NULL, "-model", path, sizeof(path), &set));
  if (!set && argc > 1 && argv[1][0] != '-') PetscCall(PetscStrncpy(path, argv[1], sizeof(path)));
  PetscCheck(path[0], PETSC_COMM_WORLD, PETSC_ERR_USER_INPUT, "give the reduced model file: bench_reassembly model.h5 [-calls N]");
  PetscCall(PetscOptionsGetInt(NULL, NULL, "-calls", &calls, NULL));
  PetscCall(PetscOptionsGetInt(NULL, NULL, "-reps", &reps, NULL));
  PetscCall(PetscOptionsGetBool(NULL, NULL, "-cpu", &cpu, NULL)); /* the process's CPU time, not the wall: a busy machine's waits left out */
  PetscCall(KFReducedModelLoad(PETSC_COMM_SELF, path, &model));
  PetscCall(KFReducedModelGetInfo(model, NULL, NULL, &nrev, NULL, NULL, NULL));
  PetscCheck(nrev <= 64, PETSC_COMM_SELF, PETSC_ERR_SUP, "at most 64 revolute joints in this bench");
  PetscCall(KFReducedModelCreateReassembly(model, &work));
  PetscCall(KFReassemblyGetSizes(work, &n, &a, &t, &viscous, &rigid));
  PetscCall(PetscMalloc4(n * n, &M, n * n, &K, n * n, &C, n * a + 1, &G));
  PetscCall(PetscMalloc4(t * n + 1, &H, n * n, &Phir, n, &lam, n * n, &Phi));
  PetscCall(KFReducedModelCreateReassembly(model, &svd));
  PetscCall(KFReassemblySetUseSVD(svd, PETSC_TRUE));
  PetscCall(KFReassemblyGetUseSVD(work, &closed));
  closed = closed ? PETSC_FALSE : PETSC_TRUE;
  /* the best of reps repetitions of each path, interleaved so that a busy machine slows them alike */
  for (PetscInt rep = 0; rep < reps; rep++) {
    for (PetscInt p = 0; p < NPATH; p++) {
      PetscLogDouble t0 = 0, t1 = 0;
      PetscCall(cpu ? CPUTime(&t0) : PetscTime(&t0));
      for (PetscInt i = 0; i < calls; i++) {
        KFReassembly w = (p == 1 || p == 3) ? svd : work;
        PetscCall(Angles(nrev, i, calls, ang));
        if (p == 0) {
          KFReducedSystem  y;
          const PetscReal *Ky;
          PetscCall(KFReducedModelReassemble(model, ang, &y));
          PetscCall(KFReducedSystemGetMatrices(y, &h, NULL, NULL, NULL, &Ky, NULL, NULL));
          checksum += Ky[0];
          PetscCall(KFReducedSystemDestroy(&y));
          continue;
        }
        if (p <= 2) PetscCall(KFReassemblyApply(w, ang, &h, M, K, (viscous ? C : NULL), G, H, NULL, NULL, NULL, NULL));
        else PetscCall(KFReassemblyApply(w, ang, &h, M, K, (viscous ? C : NULL), G, H, &rank, &ratio, &nrigid, rigid ? Phir : NULL));
        if (p >= 5) PetscCall(KFReassemblyEig(w, h, M, K, nrigid, rigid ? Phir : NULL, lam, Phi));
        checksum += K[0] + (p >= 5 ? lam[h - 1] : 0);
      }
      PetscCall(cpu ? CPUTime(&t1) : PetscTime(&t1));
      best[p] = PetscMin(best[p], (t1 - t0) / calls);
    }
  }
  PetscCall(PetscPrintf(PETSC_COMM_SELF, "model %s: %" PetscInt_FMT " system dofs, %" PetscInt_FMT " revolute joints, %" PetscInt_FMT " calls x %" PetscInt_FMT " repetitions (best, %s time); closed form %s\n", path, h, nrev, calls, reps, cpu ? "CPU" : "wall", closed ? "available" : "not available (the SVD path throughout)"));
  for (PetscInt p = 0; p < NPATH; p++) PetscCall(PetscPrintf(PETSC_COMM_SELF, "C  %-44s %9.2f us   ratio to the one-shot %.3f   to Apply (SVD) %.3f\n", names[p], best[p] * 1e6, best[p] / best[0], best[p] / best[1]));
  PetscCall(PetscPrintf(PETSC_COMM_SELF, "(checksum %g)\n", checksum));
  PetscCall(PetscFree4(M, K, C, G));
  PetscCall(PetscFree4(H, Phir, lam, Phi));
  PetscCall(KFReassemblyDestroy(&work));
  PetscCall(KFReassemblyDestroy(&svd));
  PetscCall(KFReducedModelDestroy(&model));
  PetscCall(PetscFinalize());
  return 0;
}
