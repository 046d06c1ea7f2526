/* The folder of an out-of-core MUMPS factor: one private folder per rank under a parent (-kf_ooc_dir; else the
   environment's MUMPS_OOC_TMPDIR, TMPDIR, or /tmp), made before the numerical factorization and removed with the
   factor, so that no factor file outlives the reduction. PETSc 3.18 has no call that sets MUMPS' ooc_tmpdir; MUMPS
   reads MUMPS_OOC_TMPDIR when it names its files, at the numerical factorization (mumps_io.c), and keeps the names
   for the solves: the variable is set around that call only. */
#define _GNU_SOURCE /* mkdtemp */
#include <dirent.h>
#include <errno.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>
#include <kryflex/flexsolverimpl.h>

#define KF_OOC_KEY "KFOocFolder"

typedef struct {
  char path[PETSC_MAX_PATH_LEN];
} KFOocFolder;

/* the folder's files (MUMPS names them flat inside it), then the folder; what cannot be removed stays (the caller's
   error path must not fail on it) */
static void KFOocRemoveTree(const char path[])
{
  DIR           *d = opendir(path);
  struct dirent *e;
  char           name[PETSC_MAX_PATH_LEN];

  if (!d) return;
  while ((e = readdir(d))) {
    if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
    snprintf(name, sizeof(name), "%s/%s", path, e->d_name);
    if (unlink(name)) KFOocRemoveTree(name); /* a folder: nothing MUMPS makes, but remove it all the same */
  }
  closedir(d);
  rmdir(path);
}

/* the container's destructor: runs when the factor is destroyed, after MUMPS' own end (JOB = -2, which deletes its
   files when all went well) */
static PetscErrorCode KFOocFolderDestroy(void *ctx)
{
  KFOocFolder *f = (KFOocFolder *)ctx;

  PetscFunctionBegin;
  KFOocRemoveTree(f->path);
  PetscCall(PetscFree(f));
  PetscFunctionReturn(0);
}

/* the parent of the folders: -kf_ooc_dir, else MUMPS_OOC_TMPDIR, TMPDIR, /tmp */
PETSC_INTERN PetscErrorCode KFOocParent(const char given[], const char **parent)
{
  PetscFunctionBegin;
  if (given && given[0]) *parent = given;
  else if (getenv("MUMPS_OOC_TMPDIR") && getenv("MUMPS_OOC_TMPDIR")[0]) *parent = getenv("MUMPS_OOC_TMPDIR");
  else if (getenv("TMPDIR") && getenv("TMPDIR")[0]) *parent = getenv("TMPDIR");
  else *parent = "/tmp";
  PetscFunctionReturn(0);
}

/* Makes this rank's folder under parent (collective: a rank that cannot stops every rank) and attaches it to F.
   Hidden (a leading dot), so that an output folder's staging never moves it into the results. */
PETSC_INTERN PetscErrorCode KFOocFolderCreate(Mat F, const char parent[])
{
  MPI_Comm       comm = PetscObjectComm((PetscObject)F);
  KFOocFolder   *f;
  PetscContainer ct;
  PetscMPIInt    rank;
  char           host[64] = "host";
  int            ok, all, err = 0;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCall(PetscNew(&f));
  gethostname(host, sizeof(host) - 1);
  host[sizeof(host) - 1] = 0;
  snprintf(f->path, sizeof(f->path), "%s/.kryflex-ooc-%s-%d-r%d-XXXXXX", parent, host, (int)getpid(), (int)rank);
  ok = mkdtemp(f->path) != NULL;
  if (!ok) err = errno;
  PetscCall(MPIU_Allreduce(&ok, &all, 1, MPI_INT, MPI_MIN, comm));
  if (!all) {
    if (ok) rmdir(f->path);
    PetscCall(PetscFree(f));
    SETERRQ(comm, PETSC_ERR_FILE_OPEN, "cannot make the out-of-core factor's folder in %s on every rank%s%s: give a writable folder that every rank sees with -kf_ooc_dir (or MUMPS_OOC_TMPDIR), or factor in core with -kf_ooc false", parent, err ? ": " : "", err ? strerror(err) : "");
  }
  PetscCall(PetscContainerCreate(PETSC_COMM_SELF, &ct));
  PetscCall(PetscContainerSetPointer(ct, f));
  PetscCall(PetscContainerSetUserDestroy(ct, KFOocFolderDestroy));
  PetscCall(PetscObjectCompose((PetscObject)F, KF_OOC_KEY, (PetscObject)ct));
  PetscCall(PetscContainerDestroy(&ct)); /* the factor holds the only reference */
  PetscFunctionReturn(0);
}

/* this rank's out-of-core folder of F, NULL when it has none */
PETSC_INTERN PetscErrorCode KFOocFolderGet(Mat F, const char **path)
{
  PetscContainer ct = NULL;
  KFOocFolder   *f;

  PetscFunctionBegin;
  *path = NULL;
  PetscCall(PetscObjectQuery((PetscObject)F, KF_OOC_KEY, (PetscObject *)&ct));
  if (!ct) PetscFunctionReturn(0);
  PetscCall(PetscContainerGetPointer(ct, (void **)&f));
  *path = f->path;
  PetscFunctionReturn(0);
}

/* MUMPS' numerical factorization of A into F, its out-of-core files (if any) in F's folder; the environment as it was
   after */
PETSC_INTERN PetscErrorCode KFMumpsFactorNumeric(Mat F, Mat A)
{
  MatFactorInfo  info;
  const char    *path, *old;
  char          *saved = NULL;
  PetscErrorCode ierr;

  PetscFunctionBegin;
  PetscCall(MatFactorInfoInitialize(&info));
  PetscCall(KFOocFolderGet(F, &path));
  if (!path) {
    PetscCall(MatCholeskyFactorNumeric(F, A, &info));
    PetscFunctionReturn(0);
  }
  old = getenv("MUMPS_OOC_TMPDIR");
  if (old) PetscCall(PetscStrallocpy(old, &saved));
  setenv("MUMPS_OOC_TMPDIR", path, 1);
  ierr = MatCholeskyFactorNumeric(F, A, &info);
  if (saved) setenv("MUMPS_OOC_TMPDIR", saved, 1);
  else unsetenv("MUMPS_OOC_TMPDIR");
  PetscCall(PetscFree(saved));
  PetscCall(ierr);
  PetscFunctionReturn(0);
}

/* X = F^-1 B for a block B. MUMPS solves a block of right-hand sides ICNTL(27) columns at a time, and an out-of-core
   factor is read from disk once per such group: behind one, the group is the whole block (ICNTL(27) = its columns;
   MUMPS' default, -32, groups 32 at most), so that the factor is read once per Krylov block; at most 1024 columns at
   a time (MUMPS' solve workspace grows with the group: the body-wise solve's interface responses can have thousands
   of columns). In core the default stays. */
PETSC_INTERN PetscErrorCode KFMumpsMatSolve(Mat F, Mat B, Mat X)
{
  const char *path;
  PetscInt    ncols;
  PetscBool   user = PETSC_FALSE;

  PetscFunctionBegin;
  PetscCall(KFOocFolderGet(F, &path));
  if (path) PetscCall(PetscOptionsHasName(NULL, ((PetscObject)F)->prefix, "-mat_mumps_icntl_27", &user));
  if (path && !user) { /* the user's -mat_mumps_icntl_27 stands (benchmarks/ooc: 1, a column at a time) */
    PetscCall(MatGetSize(B, NULL, &ncols));
    PetscCall(MatMumpsSetIcntl(F, 27, PetscClipInterval(ncols, 1, 1024)));
  }
  PetscCall(MatMatSolve(F, B, X));
  PetscFunctionReturn(0);
}
