/* What the C tests share: pass/fail lines on rank 0 with a failure count, the nodes files of meshes/, and the Galileo
   bodies. */
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

/* A body of meshes/galileo/ (stem: "stator" or "rotor") added to the scene under the given name; the scene holds its
   own references to the matrices. */
static inline PetscErrorCode AddGalileoBody(KFScene scene, const char stem[], const char name[], PetscInt *body)
{
  char       path[PETSC_MAX_PATH_LEN];
  Mat        M, K;
  PetscInt   nnodes = 0, *ids, *ndof;
  PetscReal *xyz;

  PetscFunctionBegin;
  PetscCall(PetscSNPrintf(path, sizeof(path), "meshes/galileo/%s_M.mtx", stem));
  PetscCall(KFMatLoadFile(PETSC_COMM_WORLD, path, &M));
  PetscCall(PetscSNPrintf(path, sizeof(path), "meshes/galileo/%s_K.mtx", stem));
  PetscCall(KFMatLoadFile(PETSC_COMM_WORLD, path, &K));
  PetscCall(PetscSNPrintf(path, sizeof(path), "meshes/galileo/%s_nodes.txt", stem));
  PetscCall(ReadNodes(path, &nnodes, &ids, &xyz, &ndof));
  PetscCall(KFSceneAddBody(scene, name, M, K, nnodes, ids, xyz, ndof, body));
  PetscCall(PetscFree3(ids, xyz, ndof));
  PetscCall(MatDestroy(&M));
  PetscCall(MatDestroy(&K));
  PetscFunctionReturn(0);
}

#endif
