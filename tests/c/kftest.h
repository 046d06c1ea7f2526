/* What the C tests share: pass/fail lines on rank 0 with a failure count, and the nodes files of meshes/. */
#ifndef KFTEST_H
#define KFTEST_H

#include <kryflex.h>

static int nfail = 0; /* the test's exit code is non-zero when any check failed */

/* an error measure against its tolerance (NaN and Inf fail) */
static inline PetscErrorCode Check(const char what[], PetscReal err, PetscReal tol)
{
  PetscBool ok = (err <= tol && !PetscIsInfOrNanReal(err)) ? PETSC_TRUE : PETSC_FALSE;

  PetscFunctionBegin;
  if (!ok) nfail++;
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "  %-76s %9.2e  (tol %7.1e)  %s\n", what, (double)err, (double)tol, ok ? "ok" : "FAIL"));
  PetscFunctionReturn(0);
}

/* a condition that must hold on every rank */
static inline PetscErrorCode CheckTrue(const char what[], PetscBool ok)
{
  PetscBool all;

  PetscFunctionBegin;
  PetscCall(MPIU_Allreduce(&ok, &all, 1, MPIU_BOOL, MPI_LAND, PETSC_COMM_WORLD));
  if (!all) nfail++;
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "  %-96s %s\n", what, all ? "ok" : "FAIL"));
  PetscFunctionReturn(0);
}

/* A nodes file: "id x y z ndof" per line, '#' comments. Every rank reads it (it is small). Arrays: PetscFree3. */
static inline PetscErrorCode ReadNodes(const char path[], PetscInt *nnodes, PetscInt **ids, PetscReal **xyz, PetscInt **ndof)
{
  FILE    *fp;
  char     line[512];
  PetscInt n = 0, cap = 64;

  PetscFunctionBegin;
  PetscCall(PetscFOpen(PETSC_COMM_SELF, path, "r", &fp));
  PetscCall(PetscMalloc3(cap, ids, 3 * cap, xyz, cap, ndof));
  while (fgets(line, sizeof(line), fp)) {
    long long id, d;
    double    x, y, z;
    char     *hash = strchr(line, '#');
    if (hash) *hash = 0;
    if (sscanf(line, "%lld %lf %lf %lf %lld", &id, &x, &y, &z, &d) != 5) continue;
    PetscCheck(n < cap, PETSC_COMM_SELF, PETSC_ERR_SUP, "%s: more than %" PetscInt_FMT " nodes; this test reads small files only", path, cap);
    (*ids)[n]         = (PetscInt)id;
    (*ndof)[n]        = (PetscInt)d;
    (*xyz)[3 * n + 0] = x;
    (*xyz)[3 * n + 1] = y;
    (*xyz)[3 * n + 2] = z;
    n++;
  }
  PetscCall(PetscFClose(PETSC_COMM_SELF, fp));
  PetscCheck(n > 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "%s holds no nodes", path);
  *nnodes = n;
  PetscFunctionReturn(0);
}

#endif
