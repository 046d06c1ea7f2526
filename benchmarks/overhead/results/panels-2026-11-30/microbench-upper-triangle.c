#include <time.h>
#include "/work/wt/panels/src/util/extended_product.c"
PetscErrorCode KFDenseCreateUninitialized(MPI_Comm comm, PetscInt nlocal, PetscInt N, PetscInt ncols, Mat *A)
{
  PetscFunctionBegin;
  PetscCall(MatCreateDense(comm, nlocal, ncols, N, ncols, NULL, A));
  PetscFunctionReturn(0);
}
int main(int argc, char **argv)
{
  Mat A, X, Y; PetscViewer v; PetscInt n, ncols = 2, reps = 20; char path[512];
  PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
  PetscCall(PetscOptionsGetString(NULL, NULL, "-f", path, sizeof(path), NULL));
  PetscCall(PetscOptionsGetInt(NULL, NULL, "-cols", &ncols, NULL));
  PetscCall(PetscViewerBinaryOpen(PETSC_COMM_SELF, path, FILE_MODE_READ, &v));
  PetscCall(MatCreate(PETSC_COMM_SELF, &A)); PetscCall(MatSetType(A, MATSEQAIJ)); PetscCall(MatLoad(A, v)); PetscCall(PetscViewerDestroy(&v));
  PetscCall(MatSetOption(A, MAT_SYMMETRIC, PETSC_TRUE));
  PetscCall(MatGetSize(A, &n, NULL));
  PetscCall(MatCreateDense(PETSC_COMM_SELF, n, ncols, n, ncols, NULL, &X));
  { PetscScalar *x; PetscCall(MatDenseGetArray(X, &x)); for (PetscInt i = 0; i < n * ncols; i++) x[i] = 1 + 1e-6 * sin(0.001 * i); PetscCall(MatDenseRestoreArray(X, &x)); }
  PetscCall(MatAssemblyBegin(X, MAT_FINAL_ASSEMBLY)); PetscCall(MatAssemblyEnd(X, MAT_FINAL_ASSEMBLY));
  double tf = 0, ts = 0; int same = 1; Mat Yf = NULL;
  for (int r = 0; r < reps; r++) {
    for (int sym = 0; sym < 2; sym++) {
      PetscLogDouble t0, t1; clock_t c0 = clock();
      if (sym) unsetenv("KF_NOSYM"); else setenv("KF_NOSYM", "1", 1);
      PetscCall(PetscTime(&t0)); if (getenv("MB_PLAIN")) PetscCall(KFMatMultDense(A, X, &Y)); else PetscCall(KFMatMultExtended(A, X, &Y)); PetscCall(PetscTime(&t1));
      double cpu = (double)(clock() - c0) / CLOCKS_PER_SEC;
      if (r > 1) { if (sym) ts += cpu; else tf += cpu; }
      if (!sym) { PetscCall(MatDestroy(&Yf)); Yf = Y; }
      else { const PetscScalar *a, *b; PetscCall(MatDenseGetArrayRead(Yf, &a)); PetscCall(MatDenseGetArrayRead(Y, &b)); same &= !memcmp(a, b, sizeof(double) * n * ncols); PetscCall(MatDenseRestoreArrayRead(Yf, &a)); PetscCall(MatDenseRestoreArrayRead(Y, &b)); PetscCall(MatDestroy(&Y)); }
    }
  }
  MatInfo info; PetscCall(MatGetInfo(A, MAT_LOCAL, &info));
  printf("n %d nnz %.0f cols %d: full %.2f ms, upper %.2f ms (CPU per product, %d reps), same bits %d\n", (int)n, info.nz_used, (int)ncols, 1e3 * tf / (reps - 2), 1e3 * ts / (reps - 2), (int)reps - 2, same);
  PetscCall(MatDestroy(&Yf)); PetscCall(MatDestroy(&A)); PetscCall(MatDestroy(&X));
  PetscCall(PetscFinalize());
  return 0;
}
