#include <kryflex_impl.h>

static PetscErrorCode KFPathHasSuffix(const char path[], const char suffix[], PetscBool *flg)
{
  size_t lp, ls;

  PetscFunctionBegin;
  PetscCall(PetscStrlen(path, &lp));
  PetscCall(PetscStrlen(suffix, &ls));
  *flg = PETSC_FALSE;
  if (lp >= ls) PetscCall(PetscStrcasecmp(path + lp - ls, suffix, flg));
  PetscFunctionReturn(0);
}

/* Matrix Market coordinate files: every rank reads the file and keeps its own rows, so large bodies load in
   parallel without a rank-0 bottleneck in memory. Symmetric storage (one triangle) is mirrored. */
static PetscErrorCode KFMatLoadMatrixMarket(MPI_Comm comm, const char path[], Mat *A)
{
  FILE      *fp;
  char       line[1024], object[64], format[64], field[64], symmetry[64];
  long long  m = 0, n = 0, nnz = 0, k, i, j;
  double     v;
  PetscBool  symmetric, pass;
  PetscInt   rstart, rend, *dnnz, *onnz, cstart, cend;

  PetscFunctionBegin;
  PetscCall(PetscFOpen(PETSC_COMM_SELF, path, "r", &fp));
  PetscCheck(fgets(line, sizeof(line), fp), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "%s is empty: expected a Matrix Market file", path);
  PetscCheck(sscanf(line, "%%%%MatrixMarket %63s %63s %63s %63s", object, format, field, symmetry) == 4, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "%s: first line is not a Matrix Market header (%%%%MatrixMarket matrix coordinate real symmetric)", path);
  PetscCheck(!strcmp(format, "coordinate"), PETSC_COMM_SELF, PETSC_ERR_SUP, "%s: only 'coordinate' Matrix Market files hold sparse body matrices (found '%s')", path, format);
  PetscCheck(!strcmp(field, "real") || !strcmp(field, "integer"), PETSC_COMM_SELF, PETSC_ERR_SUP, "%s: field '%s' not supported, write the matrix as real", path, field);
  symmetric = (PetscBool)(!strcmp(symmetry, "symmetric"));
  PetscCheck(symmetric || !strcmp(symmetry, "general"), PETSC_COMM_SELF, PETSC_ERR_SUP, "%s: symmetry '%s' not supported (use symmetric or general)", path, symmetry);
  while (fgets(line, sizeof(line), fp)) {
    if (line[0] == '%') continue;
    PetscCheck(sscanf(line, "%lld %lld %lld", &m, &n, &nnz) == 3, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "%s: bad size line '%s'", path, line);
    break;
  }
  PetscCheck(m > 0 && m == n, PETSC_COMM_SELF, PETSC_ERR_ARG_SIZ, "%s: a body matrix must be square and non-empty (found %lld x %lld)", path, m, n);
  PetscCall(PetscFClose(PETSC_COMM_SELF, fp));

  {
    PetscInt nlocal = PETSC_DECIDE, N = (PetscInt)m;
    PetscCall(PetscSplitOwnership(comm, &nlocal, &N));
    PetscCallMPI(MPI_Scan(&nlocal, &rend, 1, MPIU_INT, MPI_SUM, comm));
    rstart = rend - nlocal;
    cstart = rstart;
    cend   = rend;
    PetscCall(MatCreate(comm, A));
    PetscCall(MatSetSizes(*A, nlocal, nlocal, (PetscInt)m, (PetscInt)n));
    PetscCall(MatSetType(*A, MATAIJ));
  }
  PetscCall(PetscCalloc2(rend - rstart, &dnnz, rend - rstart, &onnz));
  /* pass 0 counts nonzeros per local row for preallocation, pass 1 inserts */
  for (pass = PETSC_FALSE;; pass = PETSC_TRUE) {
    PetscCall(PetscFOpen(PETSC_COMM_SELF, path, "r", &fp));
    while (fgets(line, sizeof(line), fp) && line[0] == '%') { }
    for (k = 0; k < nnz; k++) {
      PetscCheck(fgets(line, sizeof(line), fp), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "%s is truncated: %lld of %lld entries read; re-export the matrix", path, k, nnz);
      PetscCheck(sscanf(line, "%lld %lld %lf", &i, &j, &v) == 3, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "%s: entry %lld is malformed: '%s'", path, k + 1, line);
      PetscCheck(i >= 1 && i <= m && j >= 1 && j <= n, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "%s: entry %lld (%lld, %lld) is outside the %lld x %lld matrix", path, k + 1, i, j, m, n);
      PetscCheck(PetscIsNormalReal((PetscReal)v) || v == 0.0, PETSC_COMM_SELF, PETSC_ERR_FP, "%s: entry %lld (%lld, %lld) is not a finite number", path, k + 1, i, j);
      i--; j--;
      for (int mirror = 0; mirror < (symmetric && i != j ? 2 : 1); mirror++) {
        long long r = mirror ? j : i, c = mirror ? i : j;
        if (r < rstart || r >= rend) continue;
        if (!pass) {
          if (c >= cstart && c < cend) dnnz[r - rstart]++;
          else onnz[r - rstart]++;
        } else PetscCall(MatSetValue(*A, (PetscInt)r, (PetscInt)c, (PetscScalar)v, ADD_VALUES));
      }
    }
    PetscCall(PetscFClose(PETSC_COMM_SELF, fp));
    if (pass) break;
    for (i = 0; i < rend - rstart; i++) {
      dnnz[i] = PetscMin(dnnz[i], cend - cstart);
      onnz[i] = PetscMin(onnz[i], n - (cend - cstart));
    }
    PetscCall(MatSeqAIJSetPreallocation(*A, 0, dnnz));
    PetscCall(MatMPIAIJSetPreallocation(*A, 0, dnnz, 0, onnz));
    PetscCall(MatSetOption(*A, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_FALSE));
  }
  PetscCall(PetscFree2(dnnz, onnz));
  PetscCall(MatAssemblyBegin(*A, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*A, MAT_FINAL_ASSEMBLY));
  PetscFunctionReturn(0);
}

PetscErrorCode KFMatLoadFile(MPI_Comm comm, const char path[], Mat *A)
{
  PetscBool   exists, mtx;
  PetscViewer viewer;

  PetscFunctionBegin;
  PetscCall(KFInitialize());
  PetscCall(PetscLogEventBegin(KF_EVENT_LOAD, 0, 0, 0, 0));
  PetscCall(PetscTestFile(path, 'r', &exists));
  PetscCheck(exists, comm, PETSC_ERR_FILE_OPEN, "matrix file %s does not exist or is not readable: check the path in the scene (relative paths are taken from the scene file's folder)", path);
  PetscCall(KFPathHasSuffix(path, ".mtx", &mtx));
  if (mtx) PetscCall(KFMatLoadMatrixMarket(comm, path, A));
  else {
    PetscErrorCode ierr;
    PetscCall(PetscViewerBinaryOpen(comm, path, FILE_MODE_READ, &viewer));
    PetscCall(MatCreate(comm, A));
    PetscCall(MatSetType(*A, MATAIJ));
    /* a truncated or foreign file makes MatLoad fail deep inside PETSc: say which file and what to do */
    PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
    ierr = MatLoad(*A, viewer);
    PetscCall(PetscPopErrorHandler());
    PetscCall(PetscViewerDestroy(&viewer));
    PetscCheck(!ierr, comm, PETSC_ERR_FILE_UNEXPECTED, "%s is not a readable PETSc binary matrix (corrupt or truncated?): re-export it, or use Matrix Market (.mtx)", path);
  }
  PetscCall(PetscLogEventEnd(KF_EVENT_LOAD, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

PetscErrorCode KFMatCheckSymmetric(Mat A, const char what[], PetscReal rtol)
{
  Mat       At;
  PetscReal nA, nD;
  MPI_Comm  comm;

  PetscFunctionBegin;
  PetscCall(PetscObjectGetComm((PetscObject)A, &comm));
  PetscCall(MatTranspose(A, MAT_INITIAL_MATRIX, &At));
  PetscCall(MatNorm(A, NORM_FROBENIUS, &nA));
  PetscCall(MatAXPY(At, -1.0, A, DIFFERENT_NONZERO_PATTERN));
  PetscCall(MatNorm(At, NORM_FROBENIUS, &nD));
  PetscCall(MatDestroy(&At));
  PetscCheck(nD <= rtol * nA, comm, PETSC_ERR_ARG_WRONG, "%s is not symmetric: ||A - A^T|| / ||A|| = %g (> %g); kryflex needs symmetric M and K: check the export (both triangles, or 'symmetric' storage)", what, (double)(nA > 0 ? nD / nA : nD), (double)rtol);
  PetscFunctionReturn(0);
}
