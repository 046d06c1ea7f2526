#include <kryflex_impl.h>
#include <unistd.h>

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
  {
    PetscBool sized = PETSC_FALSE;
    while (fgets(line, sizeof(line), fp)) {
      if (line[0] == '%') continue;
      PetscCheck(sscanf(line, "%lld %lld %lld", &m, &n, &nnz) == 3, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "%s: bad size line '%s' (expected 'rows columns entries')", path, line);
      sized = PETSC_TRUE;
      break;
    }
    PetscCheck(sized, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "%s has no size line after its header: the file is truncated; re-export the matrix", path);
  }
  PetscCheck(m > 0 && m == n, PETSC_COMM_SELF, PETSC_ERR_ARG_SIZ, "%s: a body matrix must be square and non-empty (found %lld x %lld)", path, m, n);
  /* every row of a mass or stiffness matrix holds at least its diagonal: a header declaring more rows than entries is
     wrong (and would have every rank allocate for nothing) */
  PetscCheck(nnz >= m, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "%s declares %lld rows but only %lld entries: a wrong or damaged header; re-export the matrix", path, m, nnz);
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
      PetscCheck(sscanf(line, "%lld %lld %lf", &i, &j, &v) == 3, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "%s: entry %lld is malformed: '%s' (expected 'row column value'; a cut line means a truncated file: re-export the matrix)", path, k + 1, line);
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

/* A PETSc binary matrix file checked before MatLoad sees it: MatLoad trusts the column indices, and a damaged
   file would crash the program or hang it. Rank 0 reads the header, row lengths and column indices in chunks. */
static PetscErrorCode KFCheckPetscBinary(MPI_Comm comm, const char path[])
{
  PetscMPIInt rank;
  char        msg[512] = "";

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (!rank) {
    int         fd;
    PetscInt    header[4], *buf = NULL;
    PetscInt64  total = 0;
    PetscCall(PetscBinaryOpen(path, FILE_MODE_READ, &fd));
    PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
    if (PetscBinaryRead(fd, header, 4, NULL, PETSC_INT)) PetscCall(PetscSNPrintf(msg, sizeof(msg), "%s is too short for a PETSc binary matrix header", path));
    else if (header[0] != MAT_FILE_CLASSID) PetscCall(PetscSNPrintf(msg, sizeof(msg), "%s is not a PETSc binary matrix (wrong class id %d)", path, (int)header[0]));
    else if (header[1] <= 0 || header[1] != header[2] || header[3] < header[1]) PetscCall(PetscSNPrintf(msg, sizeof(msg), "%s: header says %d x %d with %d entries; a body matrix is square with at least its diagonal", path, (int)header[1], (int)header[2], (int)header[3]));
    else {
      const PetscInt chunk = 1 << 20, N = header[1];
      PetscCall(PetscMalloc1(chunk, &buf));
      for (PetscInt done = 0; done < N && !msg[0]; done += chunk) {
        PetscInt cnt = PetscMin(chunk, N - done);
        if (PetscBinaryRead(fd, buf, cnt, NULL, PETSC_INT)) PetscCall(PetscSNPrintf(msg, sizeof(msg), "%s is truncated in its row lengths", path));
        for (PetscInt i = 0; i < cnt && !msg[0]; i++) {
          if (buf[i] < 0 || buf[i] > N) PetscCall(PetscSNPrintf(msg, sizeof(msg), "%s: row %d has %d entries (of %d columns)", path, (int)(done + i), (int)buf[i], (int)N));
          total += buf[i];
        }
      }
      if (!msg[0] && total != header[3]) PetscCall(PetscSNPrintf(msg, sizeof(msg), "%s: its rows hold %lld entries, its header says %d", path, (long long)total, (int)header[3]));
      for (PetscInt64 done = 0; done < total && !msg[0]; done += chunk) {
        PetscInt cnt = (PetscInt)PetscMin((PetscInt64)chunk, total - done);
        if (PetscBinaryRead(fd, buf, cnt, NULL, PETSC_INT)) PetscCall(PetscSNPrintf(msg, sizeof(msg), "%s is truncated in its column indices", path));
        for (PetscInt i = 0; i < cnt && !msg[0]; i++)
          if (buf[i] < 0 || buf[i] >= N) PetscCall(PetscSNPrintf(msg, sizeof(msg), "%s: column index %d is outside the %d columns", path, (int)buf[i], (int)N));
      }
      if (!msg[0]) {
        off_t pos = lseek(fd, 0, SEEK_CUR), end = lseek(fd, 0, SEEK_END);
        if (end - pos < (off_t)(total * (PetscInt64)sizeof(PetscScalar))) PetscCall(PetscSNPrintf(msg, sizeof(msg), "%s is truncated in its values", path));
      }
      PetscCall(PetscFree(buf));
    }
    PetscCall(PetscPopErrorHandler());
    PetscCall(PetscBinaryClose(fd));
  }
  PetscCallMPI(MPI_Bcast(msg, sizeof(msg), MPI_CHAR, 0, comm));
  PetscCheck(!msg[0], comm, PETSC_ERR_FILE_UNEXPECTED, "%s: re-export the matrix (or use Matrix Market, .mtx)", msg);
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
    PetscCall(KFCheckPetscBinary(comm, path));
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
  {
    PetscReal nrm;
    PetscCall(MatNorm(*A, NORM_FROBENIUS, &nrm));
    PetscCheck(!PetscIsInfOrNanReal(nrm), comm, PETSC_ERR_FP, "%s holds values that are not finite (NaN or Inf): re-export the matrix", path);
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
