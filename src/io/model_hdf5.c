/* Reduced-model files (HDF5): the one writer, KFReducedModelSave, and the one reader, KFReducedModelLoad.

   Layout, format "kryflex-reduced-model" version 2 (matrices row-major, shape (rows, cols), as NumPy reads them):
     /                     attributes format, version, scene, scene_fingerprint
     /inputs, /outputs     string datasets
     /reduction_angles     nangles x nrevolute, radians (the configurations the basis was built at)
     /settings             one string attribute per key, in creation order
     /bodies/<name>        attributes index, full_dofs; string dataset interfaces; datasets M, K (v x v), G (v x a),
                           H (t x v), iface (6 ninterfaces x v), rigid (v x 6), each chunked with a fletcher32
                           checksum; optional map (full_dofs x v, gzip + fletcher32)
     /joints/<name>        attributes index, type ("revolute"/"fixed"), parent, child, parent_interface,
                           child_interface (indices), axis (3), orientation (3 x 3 R0), revolute_index (-1 if fixed)
     /bodies/<name>/C      optional: the reduced viscous damping Psi^T C_b Psi (v x v)
     /ties                 optional: coordinate ties between the bodies (shared directions), ms x n with n the sum of
                           the bodies' v in body index order, rows D with D q = 0 appended to the joints' ties at
                           reassembly; a file without it is a model without ties
     /damping              optional group (files before it: uniform modal damping, the 'damping' setting; displacement
                           outputs): attributes modal_bands (count), modal_fmax_hz, modal_zeta (count each, inf for
                           the last band of a uniform ratio), rayleigh (alpha, beta), structural (g),
                           output_quantities (per output 0 displacement, 1 velocity, 2 acceleration)

   Failures of the file (not of memory) are collected in a KFIOStatus with a PETSc error code and a message that
   names the file, the fault and the fix; every rank then raises the same error together. */
#include <kryflex/modelimpl.h>
#include <hdf5.h>
#include <petscblaslapack.h>
#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdio.h>
#include <unistd.h>

#define KF_IO_MSG (PETSC_MAX_PATH_LEN + 1024)

typedef struct {
  PetscErrorCode code; /* 0 while all is well */
  char           msg[KF_IO_MSG];
} KFIOStatus;

static const char *const BodyArrays[] = {"M", "K", "G", "H", "iface", "rigid"};

/* records the first failure only: later ones are its consequences */
static PetscErrorCode IOFail(KFIOStatus *st, PetscErrorCode code, const char fmt[], ...)
{
  va_list args;
  size_t  len;

  PetscFunctionBegin;
  if (st->code) PetscFunctionReturn(0);
  st->code = code;
  va_start(args, fmt);
  PetscCall(PetscVSNPrintf(st->msg, sizeof(st->msg), fmt, &len, args));
  va_end(args);
  PetscFunctionReturn(0);
}

/* ---------------------------------------------------------------- HDF5's own diagnosis */

typedef struct {
  char      detail[256];
  PetscBool checksum;
} H5Diagnosis;

static herr_t H5WalkCollect(unsigned n, const H5E_error2_t *e, void *ctx)
{
  H5Diagnosis *d = (H5Diagnosis *)ctx;

  if (!e->desc) return 0;
  if (n == 0) (void)PetscStrncpy(d->detail, e->desc, sizeof(d->detail));
  if (strstr(e->desc, "checksum") || strstr(e->desc, "Fletcher32") || strstr(e->desc, "fletcher32")) d->checksum = PETSC_TRUE;
  return 0;
}

/* the innermost message of HDF5's error stack (printing is off: kryflex writes its own message) */
static void H5Diagnose(H5Diagnosis *d)
{
  d->detail[0] = 0;
  d->checksum  = PETSC_FALSE;
  (void)H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, H5WalkCollect, d);
}

/* ---------------------------------------------------------------- writing */

typedef struct {
  const char *path; /* the final name, for messages */
  KFIOStatus *st;
} KFWriter;

static PetscErrorCode WriteFail(KFWriter *w, const char what[])
{
  H5Diagnosis d;

  PetscFunctionBegin;
  H5Diagnose(&d);
  PetscCall(IOFail(w->st, PETSC_ERR_FILE_WRITE, "%s: cannot write %s (%s); the previous file, if any, is unchanged: check the free space and permissions of the folder and write it again", w->path, what, d.detail[0] ? d.detail : "HDF5 error"));
  PetscFunctionReturn(0);
}

static hid_t StringType(void)
{
  hid_t type = H5Tcopy(H5T_C_S1);

  if (type < 0) return type;
  if (H5Tset_size(type, H5T_VARIABLE) < 0 || H5Tset_cset(type, H5T_CSET_UTF8) < 0) {
    H5Tclose(type);
    return -1;
  }
  return type;
}

static PetscErrorCode WriteStringAttr(KFWriter *w, hid_t loc, const char name[], const char value[])
{
  hid_t type, space = -1, attr = -1;

  PetscFunctionBegin;
  if (w->st->code) PetscFunctionReturn(0);
  type = StringType();
  if (type >= 0) space = H5Screate(H5S_SCALAR);
  if (space >= 0) attr = H5Acreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
  if (attr < 0 || H5Awrite(attr, type, &value) < 0) {
    char what[2 * KF_MAX_NAME];
    PetscCall(PetscSNPrintf(what, sizeof(what), "attribute '%s'", name));
    PetscCall(WriteFail(w, what));
  }
  if (attr >= 0) H5Aclose(attr);
  if (space >= 0) H5Sclose(space);
  if (type >= 0) H5Tclose(type);
  PetscFunctionReturn(0);
}

/* integers as 64-bit, reals as doubles; n values in an array of rank ndims (0: scalar) */
static PetscErrorCode WriteNumberAttr(KFWriter *w, hid_t loc, const char name[], PetscBool real, int ndims, const hsize_t dims[], const void *data)
{
  hid_t space, attr = -1, ftype = real ? H5T_IEEE_F64LE : H5T_STD_I64LE, mtype = real ? H5T_NATIVE_DOUBLE : H5T_NATIVE_LLONG;

  PetscFunctionBegin;
  if (w->st->code) PetscFunctionReturn(0);
  space = ndims ? H5Screate_simple(ndims, dims, NULL) : H5Screate(H5S_SCALAR);
  if (space >= 0) attr = H5Acreate2(loc, name, ftype, space, H5P_DEFAULT, H5P_DEFAULT);
  if (attr < 0 || H5Awrite(attr, mtype, data) < 0) {
    char what[2 * KF_MAX_NAME];
    PetscCall(PetscSNPrintf(what, sizeof(what), "attribute '%s'", name));
    PetscCall(WriteFail(w, what));
  }
  if (attr >= 0) H5Aclose(attr);
  if (space >= 0) H5Sclose(space);
  PetscFunctionReturn(0);
}

static PetscErrorCode WriteIntAttr(KFWriter *w, hid_t loc, const char name[], PetscInt value)
{
  long long v = (long long)value;

  PetscFunctionBegin;
  PetscCall(WriteNumberAttr(w, loc, name, PETSC_FALSE, 0, NULL, &v));
  PetscFunctionReturn(0);
}

static PetscErrorCode WriteStrings(KFWriter *w, hid_t loc, const char name[], PetscInt n, char (*names)[KF_MAX_NAME])
{
  hid_t        type, space = -1, dset = -1;
  hsize_t      dims[1] = {(hsize_t)n};
  const char **ptrs;

  PetscFunctionBegin;
  if (w->st->code) PetscFunctionReturn(0);
  PetscCall(PetscMalloc1(n + 1, &ptrs));
  for (PetscInt i = 0; i < n; i++) ptrs[i] = names[i];
  type = StringType();
  if (type >= 0) space = H5Screate_simple(1, dims, NULL);
  if (space >= 0) dset = H5Dcreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (dset < 0 || (n > 0 && H5Dwrite(dset, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, ptrs) < 0)) {
    char what[2 * KF_MAX_NAME];
    PetscCall(PetscSNPrintf(what, sizeof(what), "dataset '%s'", name));
    PetscCall(WriteFail(w, what));
  }
  if (dset >= 0) H5Dclose(dset);
  if (space >= 0) H5Sclose(space);
  if (type >= 0) H5Tclose(type);
  PetscCall(PetscFree(ptrs));
  PetscFunctionReturn(0);
}

/* a rows x cols column-major array as a row-major (rows, cols) dataset: chunks of about 1 MiB with a fletcher32
   checksum (a flipped bit is then refused on reading instead of giving a wrong model), gzip if asked; an empty
   array has nothing to check and is stored contiguous */
static PetscErrorCode WriteMatrix(KFWriter *w, hid_t loc, const char name[], PetscInt rows, PetscInt cols, const PetscReal a[], PetscBool rowmajor, PetscBool gzip)
{
  hid_t      space = -1, dcpl = -1, dset = -1;
  hsize_t    dims[2] = {(hsize_t)rows, (hsize_t)cols}, chunk[2];
  PetscReal *buf;
  PetscBool  ok;

  PetscFunctionBegin;
  if (w->st->code) PetscFunctionReturn(0);
  PetscCall(PetscMalloc1(rows * cols + 1, &buf));
  if (rowmajor) PetscCall(PetscArraycpy(buf, a, rows * cols));
  else
    for (PetscInt i = 0; i < rows; i++)
      for (PetscInt j = 0; j < cols; j++) buf[i * cols + j] = a[i + j * rows];
  space = H5Screate_simple(2, dims, NULL);
  dcpl  = H5Pcreate(H5P_DATASET_CREATE);
  ok    = (PetscBool)(space >= 0 && dcpl >= 0);
  if (ok && rows > 0 && cols > 0) {
    chunk[1] = (hsize_t)cols;
    chunk[0] = (hsize_t)PetscMin(rows, PetscMax(1, 131072 / cols));
    ok       = (PetscBool)(H5Pset_chunk(dcpl, 2, chunk) >= 0 && (!gzip || H5Pset_deflate(dcpl, 4) >= 0) && H5Pset_fletcher32(dcpl) >= 0);
  }
  if (ok) dset = H5Dcreate2(loc, name, H5T_IEEE_F64LE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
  if (dset < 0 || (rows * cols > 0 && H5Dwrite(dset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) < 0)) {
    char what[2 * KF_MAX_NAME];
    PetscCall(PetscSNPrintf(what, sizeof(what), "dataset '%s'", name));
    PetscCall(WriteFail(w, what));
  }
  if (dset >= 0) H5Dclose(dset);
  if (dcpl >= 0) H5Pclose(dcpl);
  if (space >= 0) H5Sclose(space);
  PetscCall(PetscFree(buf));
  PetscFunctionReturn(0);
}

/* a group for an object named by the user: HDF5 takes '/' as a path separator and '.' as the group itself */
static PetscErrorCode CreateNamedGroup(KFWriter *w, hid_t parent, const char kind[], const char name[], hid_t gcpl, hid_t *g)
{
  PetscFunctionBegin;
  *g = -1;
  if (w->st->code) PetscFunctionReturn(0);
  if (!name[0] || strchr(name, '/') || !strcmp(name, ".")) {
    PetscCall(IOFail(w->st, PETSC_ERR_FILE_WRITE, "%s: %s name '%s' cannot name a group in the model file ('/' and '.' alone are not allowed); the previous file, if any, is unchanged: rename the %s in the scene and reduce again", w->path, kind, name, kind));
    PetscFunctionReturn(0);
  }
  *g = H5Gcreate2(parent, name, H5P_DEFAULT, gcpl, H5P_DEFAULT);
  if (*g < 0) {
    char what[2 * KF_MAX_NAME + 16];
    PetscCall(PetscSNPrintf(what, sizeof(what), "%s group '%s'", kind, name));
    PetscCall(WriteFail(w, what));
  }
  PetscFunctionReturn(0);
}

static PetscErrorCode KFReducedModelWriteFile_Private(KFReducedModel m, hid_t f, KFWriter *w)
{
  hid_t   g = -1, gcpl;
  hsize_t dims[2];

  PetscFunctionBegin;
  PetscCall(WriteStringAttr(w, f, "format", KF_MODEL_FORMAT));
  PetscCall(WriteIntAttr(w, f, "version", KF_MODEL_VERSION));
  PetscCall(WriteStringAttr(w, f, "scene", m->scene_name));
  PetscCall(WriteStringAttr(w, f, "scene_fingerprint", m->fingerprint));
  PetscCall(WriteStrings(w, f, "inputs", m->ninputs, m->input_names));
  PetscCall(WriteStrings(w, f, "outputs", m->noutputs, m->output_names));
  PetscCall(WriteMatrix(w, f, "reduction_angles", m->nangles, m->nrevolute, m->angles, PETSC_TRUE, PETSC_FALSE));
  if (m->nties) {
    PetscInt n = 0;

    for (PetscInt b = 0; b < m->nb; b++) n += m->bodies[b].v;
    PetscCall(WriteMatrix(w, f, "ties", m->nties, n, m->ties, PETSC_TRUE, PETSC_FALSE));
  }

  /* settings keep their order: attributes are tracked by creation order */
  if (!w->st->code) {
    gcpl = H5Pcreate(H5P_GROUP_CREATE);
    if (gcpl >= 0 && H5Pset_attr_creation_order(gcpl, H5P_CRT_ORDER_TRACKED | H5P_CRT_ORDER_INDEXED) >= 0) g = H5Gcreate2(f, "settings", H5P_DEFAULT, gcpl, H5P_DEFAULT);
    if (gcpl >= 0) H5Pclose(gcpl);
    if (g < 0) PetscCall(WriteFail(w, "group 'settings'"));
    for (PetscInt k = 0; k < m->nsettings; k++) PetscCall(WriteStringAttr(w, g, m->keys[k], m->values[k]));
    if (g >= 0) H5Gclose(g);
  }

  if (!w->st->code) {
    hid_t bg = H5Gcreate2(f, "bodies", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (bg < 0) PetscCall(WriteFail(w, "group 'bodies'"));
    for (PetscInt b = 0; b < m->nb && !w->st->code; b++) {
      KFModelBody     *R = &m->bodies[b];
      const PetscInt   v = R->v, ni = R->ninterfaces;
      const PetscReal *arrays[6] = {R->M, R->K, R->G, R->H, R->iface, R->rigid};
      const PetscInt   rows[6] = {v, v, v, m->noutputs, 6 * ni, v}, cols[6] = {v, v, m->ninputs, v, v, 6};

      PetscCall(CreateNamedGroup(w, bg, "body", R->name, H5P_DEFAULT, &g));
      PetscCall(WriteIntAttr(w, g, "index", b));
      PetscCall(WriteIntAttr(w, g, "full_dofs", R->full_dofs));
      PetscCall(WriteStrings(w, g, "interfaces", ni, R->iface_names));
      for (int k = 0; k < 6; k++) PetscCall(WriteMatrix(w, g, BodyArrays[k], rows[k], cols[k], arrays[k], PETSC_FALSE, PETSC_FALSE));
      /* the map stored as it is: gzip took 0.3 s of a 57k-dof reduction for a fifth of its size (dense doubles
         hardly compress) */
      if (R->map) PetscCall(WriteMatrix(w, g, "map", R->full_dofs, v, R->map, PETSC_FALSE, PETSC_FALSE));
      if (R->C) PetscCall(WriteMatrix(w, g, "C", v, v, R->C, PETSC_FALSE, PETSC_FALSE));
      if (g >= 0) H5Gclose(g);
    }
    if (bg >= 0) H5Gclose(bg);
  }

  if (!w->st->code) {
    hid_t jg = H5Gcreate2(f, "joints", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (jg < 0) PetscCall(WriteFail(w, "group 'joints'"));
    for (PetscInt j = 0, irev = 0; j < m->nj && !w->st->code; j++) {
      const KFJointDef *J = &m->joints[j];
      PetscReal         R0[9];

      for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) R0[3 * r + c] = J->R0[r + 3 * c]; /* row-major on file */
      PetscCall(CreateNamedGroup(w, jg, "joint", m->joint_names[j], H5P_DEFAULT, &g));
      PetscCall(WriteIntAttr(w, g, "index", j));
      PetscCall(WriteStringAttr(w, g, "type", J->type == KF_JOINT_REVOLUTE ? "revolute" : "fixed"));
      PetscCall(WriteIntAttr(w, g, "parent", J->parent));
      PetscCall(WriteIntAttr(w, g, "child", J->child));
      PetscCall(WriteIntAttr(w, g, "parent_interface", J->parent_interface));
      PetscCall(WriteIntAttr(w, g, "child_interface", J->child_interface));
      dims[0] = 3;
      PetscCall(WriteNumberAttr(w, g, "axis", PETSC_TRUE, 1, dims, J->axis));
      dims[0] = dims[1] = 3;
      PetscCall(WriteNumberAttr(w, g, "orientation", PETSC_TRUE, 2, dims, R0));
      PetscCall(WriteIntAttr(w, g, "revolute_index", J->type == KF_JOINT_REVOLUTE ? irev++ : -1));
      if (g >= 0) H5Gclose(g);
    }
    if (jg >= 0) H5Gclose(jg);
  }

  if (!w->st->code) { /* the damping the model's frequency responses use, and what its outputs read */
    const KFDamping *d  = &m->damping;
    hid_t            dg = H5Gcreate2(f, "damping", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    long long       *q;

    if (dg < 0) PetscCall(WriteFail(w, "group 'damping'"));
    PetscCall(WriteIntAttr(w, dg, "modal_bands", d->nbands));
    if (d->nbands) {
      dims[0] = (hsize_t)d->nbands;
      PetscCall(WriteNumberAttr(w, dg, "modal_fmax_hz", PETSC_TRUE, 1, dims, d->fmax_hz));
      PetscCall(WriteNumberAttr(w, dg, "modal_zeta", PETSC_TRUE, 1, dims, d->zeta));
    }
    {
      const double ab[2] = {(double)d->alpha, (double)d->beta}, g = (double)d->g;
      dims[0]            = 2;
      PetscCall(WriteNumberAttr(w, dg, "rayleigh", PETSC_TRUE, 1, dims, ab));
      PetscCall(WriteNumberAttr(w, dg, "structural", PETSC_TRUE, 0, NULL, &g));
    }
    PetscCall(PetscMalloc1(m->noutputs, &q));
    for (PetscInt i = 0; i < m->noutputs; i++) q[i] = (long long)m->quantity[i];
    dims[0] = (hsize_t)m->noutputs;
    PetscCall(WriteNumberAttr(w, dg, "output_quantities", PETSC_FALSE, 1, dims, q));
    PetscCall(PetscFree(q));
    if (dg >= 0) H5Gclose(dg);
  }
  PetscFunctionReturn(0);
}

/* the file image to disk under tmp: every write(2) checked, then fsync. Returns 0 when done, PETSC_ERR_FILE_OPEN
   when tmp cannot be created, PETSC_ERR_FILE_WRITE when it cannot be written; errno is left for the message */
static PetscErrorCode WriteImage(const char tmp[], const char *image, size_t size)
{
  int       fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666), saved;
  size_t    done = 0;
  PetscBool ok;

  if (fd < 0) return PETSC_ERR_FILE_OPEN;
  errno = 0;
  while (done < size) {
    ssize_t n = write(fd, image + done, size - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    done += (size_t)n;
  }
  /* on disk before it takes the final name: a crash then leaves the old file or the new one, never half of one */
  ok    = (PetscBool)(done == size && fsync(fd) == 0);
  saved = errno;
  if (close(fd) != 0 && ok) { /* a file system that reports a failed write only here (NFS) */
    ok    = PETSC_FALSE;
    saved = errno;
  }
  if (ok) return 0;
  errno = saved ? saved : EIO;
  return PETSC_ERR_FILE_WRITE;
}

/* rank 0's part of KFReducedModelSave. HDF5 builds the file in memory (the core driver, no backing store) and
   kryflex writes its image itself: HDF5 1.10 never sees a failing disk. A write that fails inside HDF5 (a full disk
   found while a dataset or the file is closed) leaves a file id whose close at exit (MPI_Finalize) crashes the
   process (HDF5 bug HDFFV-11052, fixed in 1.14.1). Then rename(2) replaces the previous file in one step; on any
   failure the temporary is removed and the previous file is untouched. Costs memory: the image and its copy, each
   the file's size, while the model is still held. Writing from the core driver's own buffer (file image callbacks)
   would save the copy, but it does not lower the reduction's peak: on the 57k-dof solid with its maps (a 7.4 MB
   file) the copy is 7 MB, freed before the report, whose plotting sets the peak (780 MB, the same with
   -kf_save_maps false); the maps are a few doubles per dof against the factorization's fill. */
static PetscErrorCode KFReducedModelWrite_Private(KFReducedModel m, const char path[], KFIOStatus *st)
{
  char     tmp[PETSC_MAX_PATH_LEN + 32], *image = NULL;
  hid_t    f = -1, fapl;
  ssize_t  size = -1;
  KFWriter w = {path, st};

  PetscFunctionBegin;
  PetscCall(PetscSNPrintf(tmp, sizeof(tmp), "%s.tmp-%d", path, (int)getpid()));
  fapl = H5Pcreate(H5P_FILE_ACCESS);
  if (fapl >= 0 && H5Pset_fapl_core(fapl, 4 << 20, 0) >= 0) f = H5Fcreate(tmp, H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
  if (fapl >= 0) H5Pclose(fapl);
  if (f < 0) {
    H5Diagnosis d;
    H5Diagnose(&d);
    PetscCall(IOFail(st, PETSC_ERR_FILE_OPEN, "%s: cannot create the model file in memory (%s); the previous file, if any, is unchanged: check the memory available and write it again", path, d.detail[0] ? d.detail : "HDF5 error"));
    PetscFunctionReturn(0);
  }
  PetscCall(KFReducedModelWriteFile_Private(m, f, &w));
  if (!st->code && H5Fflush(f, H5F_SCOPE_GLOBAL) < 0) PetscCall(WriteFail(&w, "the file (flushing it)"));
  if (!st->code) size = H5Fget_file_image(f, NULL, 0);
  if (!st->code && size < 0) PetscCall(WriteFail(&w, "the file (its size)"));
  if (!st->code) PetscCall(PetscMalloc1((size_t)size + 1, &image));
  if (!st->code && H5Fget_file_image(f, image, (size_t)size) != size) PetscCall(WriteFail(&w, "the file (its image)"));
  if (H5Fclose(f) < 0) PetscCall(WriteFail(&w, "the file (closing it)"));
  if (!st->code) {
    PetscErrorCode fail = WriteImage(tmp, image, (size_t)size);
    if (fail == PETSC_ERR_FILE_OPEN) PetscCall(IOFail(st, fail, "%s: cannot create the model file (%s); the previous file, if any, is unchanged: check that the folder exists and is writable", path, strerror(errno)));
    else if (fail) PetscCall(IOFail(st, fail, "%s: cannot write the model file (%s); the previous file, if any, is unchanged: free space on its disk or write it to another folder", path, strerror(errno)));
  }
  PetscCall(PetscFree(image));
  if (!st->code && rename(tmp, path) != 0) PetscCall(IOFail(st, PETSC_ERR_FILE_WRITE, "%s: cannot move the new model file into place (%s); the previous file, if any, is unchanged: check that the path is not a folder and the folder is writable", path, strerror(errno)));
  if (st->code) (void)remove(tmp);
  PetscFunctionReturn(0);
}

/*
  KFReducedModelSave - writes the model as HDF5 (layout at the top of this file). Rank 0 writes under a temporary
  name in the same folder and renames the file into place when it is complete; on failure the previous file stays
  as it was. Every rank returns the same error: PETSC_ERR_FILE_OPEN (cannot create), PETSC_ERR_FILE_WRITE.
*/
PetscErrorCode KFReducedModelSave(KFReducedModel m, const char path[])
{
  MPI_Comm    comm;
  PetscMPIInt rank;
  KFIOStatus  st;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, KF_REDUCEDMODEL_CLASSID, 1);
  PetscCheck(path && path[0], PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_WRONG, "KFReducedModelSave: give a file name");
  comm = PetscObjectComm((PetscObject)m);
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCall(PetscMemzero(&st, sizeof(st)));
  if (rank == 0) {
    PetscErrorCode ierr;
    (void)H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    /* an error here (memory) must still reach the broadcast, or the other ranks would wait for ever */
    ierr = KFReducedModelWrite_Private(m, path, &st);
    if (ierr && !st.code) PetscCall(IOFail(&st, ierr, "%s: writing the model failed (error %d, see above); the previous file, if any, is unchanged", path, (int)ierr));
  }
  PetscCallMPI(MPI_Bcast(&st, (PetscMPIInt)sizeof(st), MPI_BYTE, 0, comm));
  PetscCheck(!st.code, comm, st.code, "%s", st.msg);
  PetscFunctionReturn(0);
}

/* ---------------------------------------------------------------- reading */

typedef struct {
  const char *path;
  KFIOStatus *st;
} KFReader;

/* the file is damaged or written by something else: FILE_UNEXPECTED with the fix */
static PetscErrorCode Inconsistent(KFReader *r, const char fmt[], ...)
{
  va_list args;
  char    what[1000];
  size_t  len;

  PetscFunctionBegin;
  if (r->st->code) PetscFunctionReturn(0);
  va_start(args, fmt);
  PetscCall(PetscVSNPrintf(what, sizeof(what), fmt, &len, args));
  va_end(args);
  PetscCall(IOFail(r->st, PETSC_ERR_FILE_UNEXPECTED, "%s: %s: the file is inconsistent; write it again with 'kryflex reduce'", r->path, what));
  PetscFunctionReturn(0);
}

/* a failed HDF5 read: a checksum failure says so */
static PetscErrorCode ReadFail(KFReader *r, const char what[])
{
  H5Diagnosis d;

  PetscFunctionBegin;
  H5Diagnose(&d);
  if (d.checksum) PetscCall(IOFail(r->st, PETSC_ERR_FILE_READ, "%s: %s fails its checksum: the file is damaged; write it again with 'kryflex reduce'", r->path, what));
  else PetscCall(IOFail(r->st, PETSC_ERR_FILE_READ, "%s: cannot read %s (%s): the file is damaged or incomplete; write it again with 'kryflex reduce'", r->path, what, d.detail[0] ? d.detail : "HDF5 error"));
  PetscFunctionReturn(0);
}

static PetscBool Exists(hid_t loc, const char name[])
{
  return H5Lexists(loc, name, H5P_DEFAULT) > 0 ? PETSC_TRUE : PETSC_FALSE;
}

/* n strings of an attribute (n = 1: scalar) or a dataset, variable or fixed length, into names (len each) */
static PetscErrorCode ReadStringsOf(KFReader *r, hid_t obj, PetscBool attr, const char what[], PetscInt n, size_t len, char *names)
{
  hid_t   ftype = -1, mtype = -1, space = -1;
  PetscBool ok = PETSC_FALSE;

  PetscFunctionBegin;
  ftype = attr ? H5Aget_type(obj) : H5Dget_type(obj);
  space = attr ? H5Aget_space(obj) : H5Dget_space(obj);
  if (ftype < 0 || space < 0) {
    PetscCall(ReadFail(r, what));
    goto done;
  }
  if (H5Tget_class(ftype) != H5T_STRING) {
    PetscCall(Inconsistent(r, "%s is not text", what));
    goto done;
  }
  mtype = H5Tcopy(H5T_C_S1);
  H5Tset_cset(mtype, H5Tget_cset(ftype)); /* HDF5 does not convert between ASCII and UTF-8 */
  if (H5Tis_variable_str(ftype) > 0) {
    char **ptrs;
    H5Tset_size(mtype, H5T_VARIABLE);
    PetscCall(PetscCalloc1(n + 1, &ptrs));
    if ((attr ? H5Aread(obj, mtype, ptrs) : H5Dread(obj, mtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, ptrs)) >= 0) {
      ok = PETSC_TRUE;
      for (PetscInt i = 0; i < n; i++) {
        if (!ptrs[i] || strlen(ptrs[i]) >= len) ok = PETSC_FALSE;
        else PetscCall(PetscStrncpy(names + i * len, ptrs[i], len));
      }
      (void)H5Dvlen_reclaim(mtype, space, H5P_DEFAULT, ptrs);
      if (!ok) PetscCall(Inconsistent(r, "%s holds a string longer than %d characters", what, (int)len - 1));
      ok = PETSC_TRUE;
    } else PetscCall(ReadFail(r, what));
    PetscCall(PetscFree(ptrs));
  } else {
    size_t size = H5Tget_size(ftype);
    char  *buf;
    H5Tset_size(mtype, size);
    PetscCall(PetscCalloc1(n * size + 1, &buf));
    if ((attr ? H5Aread(obj, mtype, buf) : H5Dread(obj, mtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf)) >= 0) {
      for (PetscInt i = 0; i < n; i++) {
        size_t l = strnlen(buf + i * size, size);
        if (l >= len) {
          PetscCall(Inconsistent(r, "%s holds a string longer than %d characters", what, (int)len - 1));
          break;
        }
        PetscCall(PetscMemcpy(names + i * len, buf + i * size, l));
        names[i * len + l] = 0;
      }
    } else PetscCall(ReadFail(r, what));
    PetscCall(PetscFree(buf));
  }
done:
  if (mtype >= 0) H5Tclose(mtype);
  if (ftype >= 0) H5Tclose(ftype);
  if (space >= 0) H5Sclose(space);
  PetscFunctionReturn(0);
}

/* opens dataset name of loc, or records why not ('what' names it for messages); dset < 0 then */
static PetscErrorCode OpenDataset(KFReader *r, hid_t loc, const char where[], const char name[], char what[], size_t len, hid_t *dset)
{
  PetscFunctionBegin;
  *dset = -1;
  PetscCall(PetscSNPrintf(what, len, "%sdataset '%s'", where, name));
  if (r->st->code) PetscFunctionReturn(0);
  if (!Exists(loc, name)) PetscCall(Inconsistent(r, "%s is missing", what));
  else if ((*dset = H5Dopen2(loc, name, H5P_DEFAULT)) < 0) PetscCall(ReadFail(r, what));
  PetscFunctionReturn(0);
}

/* opens attribute name of loc, or records why not; attr < 0 then */
static PetscErrorCode OpenAttribute(KFReader *r, hid_t loc, const char where[], const char name[], char what[], size_t len, hid_t *attr)
{
  PetscFunctionBegin;
  *attr = -1;
  PetscCall(PetscSNPrintf(what, len, "%sattribute '%s'", where, name));
  if (r->st->code) PetscFunctionReturn(0);
  if (H5Aexists(loc, name) <= 0) PetscCall(Inconsistent(r, "%s is missing", what));
  else if ((*attr = H5Aopen(loc, name, H5P_DEFAULT)) < 0) PetscCall(ReadFail(r, what));
  PetscFunctionReturn(0);
}

static PetscErrorCode ReadStringAttr(KFReader *r, hid_t loc, const char where[], const char name[], size_t len, char value[])
{
  hid_t attr;
  char  what[3 * KF_MAX_NAME];

  PetscFunctionBegin;
  PetscCall(OpenAttribute(r, loc, where, name, what, sizeof(what), &attr));
  if (attr >= 0) {
    hid_t    space = H5Aget_space(attr);
    hssize_t np    = space >= 0 ? H5Sget_simple_extent_npoints(space) : -1;
    if (space >= 0) H5Sclose(space);
    if (np != 1) PetscCall(Inconsistent(r, "%s is not one string", what));
    else PetscCall(ReadStringsOf(r, attr, PETSC_TRUE, what, 1, len, value));
    H5Aclose(attr);
  }
  PetscFunctionReturn(0);
}

/* n numbers of an attribute as integers or doubles (n = 1 also reads a scalar) */
static PetscErrorCode ReadNumberAttr(KFReader *r, hid_t loc, const char where[], const char name[], PetscBool real, hssize_t n, void *data)
{
  hid_t attr;
  char  what[3 * KF_MAX_NAME];

  PetscFunctionBegin;
  PetscCall(OpenAttribute(r, loc, where, name, what, sizeof(what), &attr));
  if (attr >= 0) {
    hid_t       space = H5Aget_space(attr), type = H5Aget_type(attr);
    hssize_t    np    = space >= 0 ? H5Sget_simple_extent_npoints(space) : -1;
    H5T_class_t cls   = type >= 0 ? H5Tget_class(type) : H5T_NO_CLASS;
    if (np != n || !(cls == H5T_INTEGER || (real && cls == H5T_FLOAT))) PetscCall(Inconsistent(r, "%s should hold %d %s", what, (int)n, real ? "real numbers" : "integers"));
    else if (H5Aread(attr, real ? H5T_NATIVE_DOUBLE : H5T_NATIVE_LLONG, data) < 0) PetscCall(ReadFail(r, what));
    if (space >= 0) H5Sclose(space);
    if (type >= 0) H5Tclose(type);
    H5Aclose(attr);
  }
  PetscFunctionReturn(0);
}

static PetscErrorCode ReadIntAttr(KFReader *r, hid_t loc, const char where[], const char name[], PetscInt *value)
{
  long long v = 0;

  PetscFunctionBegin;
  PetscCall(ReadNumberAttr(r, loc, where, name, PETSC_FALSE, 1, &v));
  *value = (PetscInt)v;
  PetscFunctionReturn(0);
}

/* a 1-D string dataset: its length and the strings */
static PetscErrorCode ReadStrings(KFReader *r, hid_t loc, const char where[], const char name[], PetscInt *n, char (**names)[KF_MAX_NAME])
{
  hid_t dset, space;
  int   ndims;
  hsize_t dims[1] = {0};
  char  what[3 * KF_MAX_NAME];

  PetscFunctionBegin;
  *n     = 0;
  *names = NULL;
  PetscCall(OpenDataset(r, loc, where, name, what, sizeof(what), &dset));
  if (dset < 0) PetscFunctionReturn(0);
  space = H5Dget_space(dset);
  ndims = space >= 0 ? H5Sget_simple_extent_ndims(space) : -1;
  if (ndims == 1) H5Sget_simple_extent_dims(space, dims, NULL);
  if (space >= 0) H5Sclose(space);
  if (ndims != 1) PetscCall(Inconsistent(r, "%s is not a list of strings", what));
  else {
    *n = (PetscInt)dims[0];
    PetscCall(PetscCalloc1(*n + 1, names));
    if (*n) PetscCall(ReadStringsOf(r, dset, PETSC_FALSE, what, *n, KF_MAX_NAME, (char *)*names));
  }
  H5Dclose(dset);
  PetscFunctionReturn(0);
}

/* a real (rows, cols) dataset of the expected shape (why: what fixes it, for messages) into a new column-major
   array (row-major if rowmajor); every value finite: NaN or Inf in a model is an edit or a damage the checksums
   did not see, and would surface later as a failed eigensolve or SVD */
static PetscErrorCode ReadMatrix(KFReader *r, hid_t loc, const char where[], const char name[], PetscInt rows, PetscInt cols, const char why[], PetscBool rowmajor, PetscReal **a)
{
  hid_t      dset, space, type;
  int        ndims;
  hsize_t    dims[2] = {0, 0};
  char       what[3 * KF_MAX_NAME];
  PetscReal *buf;

  PetscFunctionBegin;
  *a = NULL;
  PetscCall(OpenDataset(r, loc, where, name, what, sizeof(what), &dset));
  if (dset < 0) PetscFunctionReturn(0);
  space = H5Dget_space(dset);
  type  = H5Dget_type(dset);
  ndims = space >= 0 ? H5Sget_simple_extent_ndims(space) : -1;
  if (ndims == 2) H5Sget_simple_extent_dims(space, dims, NULL);
  if (ndims != 2 || type < 0 || H5Tget_class(type) != H5T_FLOAT) PetscCall(Inconsistent(r, "%s is not a matrix of real numbers", what));
  else if (dims[0] != (hsize_t)rows || dims[1] != (hsize_t)cols)
    PetscCall(Inconsistent(r, "%s is %llu x %llu, expected %" PetscInt_FMT " x %" PetscInt_FMT " (%s)", what, (unsigned long long)dims[0], (unsigned long long)dims[1], rows, cols, why));
  else {
    PetscBool ok  = PETSC_TRUE;
    PetscInt  bad = -1;
    PetscCall(PetscMalloc1(rows * cols + 1, &buf));
    if (rows * cols > 0 && H5Dread(dset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) < 0) {
      PetscCall(ReadFail(r, what));
      ok = PETSC_FALSE;
    }
    for (PetscInt k = 0; ok && k < rows * cols && bad < 0; k++)
      if (PetscIsInfOrNanReal(buf[k])) bad = k;
    if (bad >= 0) {
      char value[32];
      (void)snprintf(value, sizeof(value), "%g", (double)buf[bad]); /* PETSc's printf writes "nan." */
      PetscCall(Inconsistent(r, "%s holds %s at [%" PetscInt_FMT ", %" PetscInt_FMT "] (NumPy indexing), not a finite number", what, value, bad / cols, bad % cols));
      ok = PETSC_FALSE;
    }
    if (!ok) PetscCall(PetscFree(buf));
    else if (rowmajor) *a = buf;
    else {
      PetscCall(PetscMalloc1(rows * cols, a));
      for (PetscInt i = 0; i < rows; i++)
        for (PetscInt j = 0; j < cols; j++) (*a)[i + j * rows] = buf[i * cols + j];
      PetscCall(PetscFree(buf));
    }
  }
  if (type >= 0) H5Tclose(type);
  if (space >= 0) H5Sclose(space);
  H5Dclose(dset);
  PetscFunctionReturn(0);
}

/* the rows of a dataset (its first dimension), or -1 */
static PetscInt DatasetRows(hid_t loc, const char name[])
{
  hid_t   dset, space;
  hsize_t dims[2] = {0, 0};
  int     ndims   = -1;

  if (!Exists(loc, name)) return -1;
  dset = H5Dopen2(loc, name, H5P_DEFAULT);
  if (dset < 0) return -1;
  space = H5Dget_space(dset);
  if (space >= 0) ndims = H5Sget_simple_extent_ndims(space);
  if (ndims >= 1 && ndims <= 2) H5Sget_simple_extent_dims(space, dims, NULL);
  if (space >= 0) H5Sclose(space);
  H5Dclose(dset);
  return ndims >= 1 && ndims <= 2 ? (PetscInt)dims[0] : -1;
}

/* names of the members of a group, in name order */
static PetscErrorCode GroupMembers(KFReader *r, hid_t g, const char what[], PetscInt *n, char (**names)[KF_MAX_NAME])
{
  H5G_info_t info;

  PetscFunctionBegin;
  *n     = 0;
  *names = NULL;
  if (r->st->code) PetscFunctionReturn(0);
  if (H5Gget_info(g, &info) < 0) {
    PetscCall(ReadFail(r, what));
    PetscFunctionReturn(0);
  }
  *n = (PetscInt)info.nlinks;
  PetscCall(PetscCalloc1(*n + 1, names));
  for (PetscInt i = 0; i < *n; i++) {
    ssize_t len = H5Lget_name_by_idx(g, ".", H5_INDEX_NAME, H5_ITER_INC, (hsize_t)i, NULL, 0, H5P_DEFAULT);
    if (len < 0) {
      PetscCall(ReadFail(r, what));
      break;
    }
    if (len >= KF_MAX_NAME) {
      PetscCall(Inconsistent(r, "a member of %s has a name longer than %d characters", what, KF_MAX_NAME - 1));
      break;
    }
    (void)H5Lget_name_by_idx(g, ".", H5_INDEX_NAME, H5_ITER_INC, (hsize_t)i, (*names)[i], KF_MAX_NAME, H5P_DEFAULT);
  }
  PetscFunctionReturn(0);
}

/* every index attribute in [0, n) and none twice */
static PetscErrorCode CheckPermutation(KFReader *r, const char what[], PetscInt n, const PetscInt index[])
{
  PetscBool *seen;

  PetscFunctionBegin;
  if (r->st->code) PetscFunctionReturn(0);
  PetscCall(PetscCalloc1(n + 1, &seen));
  for (PetscInt i = 0; i < n; i++) {
    if (index[i] < 0 || index[i] >= n || seen[index[i]]) {
      PetscCall(Inconsistent(r, "the index attributes of the %s are not 0..%" PetscInt_FMT " each once", what, n - 1));
      break;
    }
    seen[index[i]] = PETSC_TRUE;
  }
  PetscCall(PetscFree(seen));
  PetscFunctionReturn(0);
}

typedef struct {
  KFReader      *r;
  KFReducedModel m;
} SettingsCtx;

static herr_t ReadSetting(hid_t loc, const char *name, const H5A_info_t *info, void *ctx)
{
  SettingsCtx   *c = (SettingsCtx *)ctx;
  hid_t          attr;
  char          *value = NULL, what[3 * KF_MAX_NAME];
  hssize_t       np;
  hid_t          space;
  PetscErrorCode ierr;

  (void)info;
  if (PetscSNPrintf(what, sizeof(what), "setting '%s'", name)) return -1;
  attr = H5Aopen(loc, name, H5P_DEFAULT);
  if (attr < 0) return ReadFail(c->r, what) ? -1 : 1;
  space = H5Aget_space(attr);
  np    = space >= 0 ? H5Sget_simple_extent_npoints(space) : -1;
  if (space >= 0) H5Sclose(space);
  if (np != 1) ierr = Inconsistent(c->r, "%s is not one string", what);
  else {
    ierr = PetscCalloc1(65536, &value);
    if (!ierr) ierr = ReadStringsOf(c->r, attr, PETSC_TRUE, what, 1, 65536, value);
    if (!ierr && !c->r->st->code) ierr = KFReducedModelSetSetting(c->m, name, value);
    if (value) (void)PetscFree(value);
  }
  H5Aclose(attr);
  if (ierr) return -1;
  return c->r->st->code ? 1 : 0;
}

static PetscErrorCode ReadSettings(KFReader *r, hid_t f, KFReducedModel m)
{
  hid_t       g;
  hsize_t     idx = 0;
  SettingsCtx ctx = {r, m};
  herr_t      e;
  unsigned    order = 0;
  hid_t       gcpl;

  PetscFunctionBegin;
  if (r->st->code) PetscFunctionReturn(0);
  if (!Exists(f, "settings")) {
    PetscCall(Inconsistent(r, "group 'settings' is missing"));
    PetscFunctionReturn(0);
  }
  g = H5Gopen2(f, "settings", H5P_DEFAULT);
  if (g < 0) {
    PetscCall(ReadFail(r, "group 'settings'"));
    PetscFunctionReturn(0);
  }
  /* in the order they were recorded when the writer tracked it (kryflex does), else by name */
  gcpl = H5Gget_create_plist(g);
  if (gcpl >= 0) {
    (void)H5Pget_attr_creation_order(gcpl, &order);
    H5Pclose(gcpl);
  }
  e = H5Aiterate2(g, (order & H5P_CRT_ORDER_INDEXED) ? H5_INDEX_CRT_ORDER : H5_INDEX_NAME, H5_ITER_INC, &idx, ReadSetting, &ctx);
  H5Gclose(g);
  if (e < 0 && !r->st->code) PetscCall(ReadFail(r, "group 'settings'"));
  PetscFunctionReturn(0);
}

/* the names of a string dataset are keys (inputs, outputs, interfaces): none twice */
static PetscErrorCode CheckNames(KFReader *r, const char where[], const char name[], PetscInt n, char (*names)[KF_MAX_NAME])
{
  PetscFunctionBegin;
  if (r->st->code) PetscFunctionReturn(0);
  for (PetscInt i = 0; i < n; i++)
    for (PetscInt k = 0; k < i; k++)
      if (!strcmp(names[i], names[k])) {
        PetscCall(Inconsistent(r, "%sdataset '%s' names '%s' twice (entries %" PetscInt_FMT " and %" PetscInt_FMT ")", where, name, names[i], k, i));
        PetscFunctionReturn(0);
      }
  PetscFunctionReturn(0);
}

/* The largest |r^T K r| / r^T r over the body's stored rigid motions r (the columns of dataset 'rigid'; M = I): the
   energy a stiffness exported with rounding (8 digits in a Nastran punch) leaves in its rigid-body modes. The
   projection keeps it, so the reduced K is indefinite by about that much; the reader allows RIGID_ENERGY_MARGIN
   times it (the margin kryflex check's null-pivot count takes), not more. 0 without stored rigid motions. */
#define RIGID_ENERGY_MARGIN 100.0
static PetscReal RigidEnergy(const KFModelBody *R)
{
  const PetscInt v = R->v;
  PetscReal      worst = 0;

  if (!R->rigid) return 0;
  for (PetscInt m = 0; m < 6; m++) {
    const PetscReal *x = R->rigid + m * v;
    PetscReal        xx = 0, xkx = 0;
    for (PetscInt i = 0; i < v; i++) {
      PetscReal kx = 0;
      for (PetscInt j = 0; j < v; j++) kx += R->K[i + j * v] * x[j];
      xx += x[i] * x[i];
      xkx += x[i] * kx;
    }
    if (xx > 0) worst = PetscMax(worst, PetscAbsReal(xkx) / xx);
  }
  return worst;
}

/* The reduced mass is the identity and the reduced stiffness symmetric positive semi-definite
   (projections of the full ones on a mass-orthonormal basis): an edit that breaks this would make reassembly fail or give a wrong model. The
   tolerances are far above the rounding of the projection (about 1e-16 for symmetry and 1e-12 for the smallest
   eigenvalue of K relative to its largest on the Galileo model). */
static PetscErrorCode CheckBodyMatrices(KFReader *r, const char where[], KFModelBody *R)
{
  const PetscInt v = R->v;
  PetscBLASInt   bn, info, lwork;
  PetscReal     *A, *w, *work, wq, amax, asym, rigid;

  PetscFunctionBegin;
  if (r->st->code || v < 1) PetscFunctionReturn(0);
  for (int k = 0; k < 2 && !r->st->code; k++) {
    const PetscReal *X = k ? R->K : R->M;
    amax = asym = 0;
    for (PetscInt i = 0; i < v; i++)
      for (PetscInt j = 0; j < v; j++) {
        amax = PetscMax(amax, PetscAbsReal(X[i + j * v]));
        asym = PetscMax(asym, PetscAbsReal(X[i + j * v] - X[j + i * v]));
      }
    if (asym > 1e-8 * amax) PetscCall(Inconsistent(r, "%sdataset '%s' is not symmetric (largest |%s - %s^T| is %g of its largest entry)", where, k ? "K" : "M", k ? "K" : "M", k ? "K" : "M", (double)(asym / amax)));
  }
  if (r->st->code) PetscFunctionReturn(0);
  PetscCall(PetscBLASIntCast(v, &bn));
  PetscCall(PetscMalloc2(v * v, &A, v, &w));
  PetscCall(PetscArraycpy(A, R->M, v * v));
  PetscCallBLAS("LAPACKpotrf", LAPACKpotrf_("L", &bn, A, &bn, &info));
  if (info) PetscCall(Inconsistent(r, "%sdataset 'M' is not positive definite (its leading minor of order %d is not); a reduced mass matrix always is", where, (int)info));
  else {
    PetscCall(PetscArraycpy(A, R->K, v * v));
    lwork = -1;
    PetscCallBLAS("LAPACKsyev", LAPACKsyev_("N", "L", &bn, A, &bn, w, &wq, &lwork, &info));
    PetscCall(PetscBLASIntCast((PetscInt)wq, &lwork));
    PetscCall(PetscMalloc1(lwork, &work));
    PetscCallBLAS("LAPACKsyev", LAPACKsyev_("N", "L", &bn, A, &bn, w, work, &lwork, &info));
    PetscCall(PetscFree(work));
    amax = PetscMax(PetscAbsReal(w[0]), PetscAbsReal(w[v - 1]));
    rigid = RigidEnergy(R);
    if (info) PetscCall(Inconsistent(r, "%sdataset 'K': its eigenvalues cannot be computed (LAPACK syev info %d)", where, (int)info));
    else if (w[0] < -PetscMax(1e-8 * amax, RIGID_ENERGY_MARGIN * rigid)) PetscCall(Inconsistent(r, "%sdataset 'K' has the negative eigenvalue %g (largest %g; the energy K carries in the body's rigid motions, dataset 'rigid', is %g): a reduced stiffness matrix is positive semi-definite up to the energy of its rigid motions", where, (double)w[0], (double)w[v - 1], (double)rigid));
  }
  /* the body basis is M-orthonormal (KFMOrthonormalize before the projection), so the reduced mass is the identity
     to rounding; reassembly and the rigid modes take it as it is, so an edited M would give another model silently */
  if (!r->st->code) {
    PetscReal dev = 0;
    for (PetscInt i = 0; i < v; i++)
      for (PetscInt j = 0; j < v; j++) dev = PetscMax(dev, PetscAbsReal(R->M[i + j * v] - (i == j ? 1.0 : 0.0)));
    if (dev > 1e-6) PetscCall(Inconsistent(r, "%sdataset 'M' is not the identity (largest |M - I| is %g): a reduced mass is the identity by construction (its basis is mass-orthonormal), so M was edited", where, (double)dev));
  }
  PetscCall(PetscFree2(A, w));
  PetscFunctionReturn(0);
}

/* the settings reassembly uses: damping, the uniform modal damping ratio of the model's frequency responses */
static PetscErrorCode CheckSettings(KFReader *r, KFReducedModel m)
{
  PetscFunctionBegin;
  if (r->st->code) PetscFunctionReturn(0);
  for (PetscInt k = 0; k < m->nsettings; k++)
    if (!strcmp(m->keys[k], "damping")) {
      char  *end;
      double d = strtod(m->values[k], &end);
      while (*end == ' ') end++;
      if (end == m->values[k] || *end || !(d >= 0 && d < 1)) PetscCall(Inconsistent(r, "setting 'damping' is '%s', not a damping ratio in [0, 1)", m->values[k]));
    }
  PetscFunctionReturn(0);
}

static PetscErrorCode ReadBodies(KFReader *r, hid_t f, KFReducedModel m)
{
  hid_t    bg;
  PetscInt n, *index;
  char (*names)[KF_MAX_NAME];

  PetscFunctionBegin;
  if (r->st->code) PetscFunctionReturn(0);
  if (!Exists(f, "bodies")) {
    PetscCall(Inconsistent(r, "group 'bodies' is missing"));
    PetscFunctionReturn(0);
  }
  bg = H5Gopen2(f, "bodies", H5P_DEFAULT);
  if (bg < 0) {
    PetscCall(ReadFail(r, "group 'bodies'"));
    PetscFunctionReturn(0);
  }
  PetscCall(GroupMembers(r, bg, "group 'bodies'", &n, &names));
  if (!r->st->code && n < 1) PetscCall(Inconsistent(r, "the model has no bodies"));
  PetscCall(PetscCalloc1(n + 1, &index));
  for (PetscInt i = 0; i < n && !r->st->code; i++) {
    hid_t g = H5Gopen2(bg, names[i], H5P_DEFAULT);
    char  where[2 * KF_MAX_NAME];
    PetscCall(PetscSNPrintf(where, sizeof(where), "body '%s' ", names[i]));
    if (g < 0) PetscCall(ReadFail(r, where));
    else {
      PetscCall(ReadIntAttr(r, g, where, "index", &index[i]));
      H5Gclose(g);
    }
  }
  PetscCall(CheckPermutation(r, "bodies", n, index));
  if (!r->st->code) {
    PetscCall(PetscFree(m->bodies));
    PetscCall(PetscCalloc1(n, &m->bodies));
    m->nb = n;
  }
  for (PetscInt i = 0; i < n && !r->st->code; i++) {
    KFModelBody *R = &m->bodies[index[i]];
    hid_t        g = H5Gopen2(bg, names[i], H5P_DEFAULT);
    char         where[2 * KF_MAX_NAME];
    PetscInt     v, ni, a = m->ninputs, t = m->noutputs;

    PetscCall(PetscSNPrintf(where, sizeof(where), "body '%s' ", names[i]));
    if (g < 0) {
      PetscCall(ReadFail(r, where));
      break;
    }
    PetscCall(PetscStrncpy(R->name, names[i], sizeof(R->name)));
    PetscCall(ReadIntAttr(r, g, where, "full_dofs", &R->full_dofs));
    if (!r->st->code && R->full_dofs < 1) PetscCall(Inconsistent(r, "%sattribute 'full_dofs' is %" PetscInt_FMT, where, R->full_dofs));
    PetscCall(ReadStrings(r, g, where, "interfaces", &ni, &R->iface_names));
    R->ninterfaces = ni;
    /* the reduced size is M's; every other array must agree with it */
    v = DatasetRows(g, "M");
    if (!r->st->code && v < 0) PetscCall(ReadMatrix(r, g, where, "M", 0, 0, "a square matrix", PETSC_FALSE, &R->M)); /* reports what is wrong with M */
    R->v = v;
    if (!r->st->code) {
      PetscReal    **arrays[6] = {&R->M, &R->K, &R->G, &R->H, &R->iface, &R->rigid};
      const PetscInt rows[6]   = {v, v, v, t, 6 * ni, v}, cols[6] = {v, v, a, v, v, 6};
      const char    *why[6]    = {"square", "the size of M", "the rows of M x the names in dataset 'inputs'", "the names in dataset 'outputs' x the rows of M", "6 per name in dataset 'interfaces' x the rows of M", "the rows of M x 6"};
      for (int k = 0; k < 6; k++) PetscCall(ReadMatrix(r, g, where, BodyArrays[k], rows[k], cols[k], why[k], PETSC_FALSE, arrays[k]));
      if (Exists(g, "map")) PetscCall(ReadMatrix(r, g, where, "map", R->full_dofs, v, "attribute 'full_dofs' x the rows of M", PETSC_FALSE, &R->map));
      if (Exists(g, "C")) {
        PetscCall(ReadMatrix(r, g, where, "C", v, v, "the size of M", PETSC_FALSE, &R->C));
        if (!r->st->code && R->C) { /* a viscous damping matrix is symmetric with a non-negative diagonal */
          PetscReal top = 0, asym = 0, dmin = 0;
          for (PetscInt i = 0; i < v; i++) {
            dmin = PetscMin(dmin, R->C[i + i * v]);
            for (PetscInt j = 0; j < v; j++) {
              top  = PetscMax(top, PetscAbsReal(R->C[i + j * v]));
              asym = PetscMax(asym, PetscAbsReal(R->C[i + j * v] - R->C[j + i * v]));
            }
          }
          /* a projected C that leaves rigid motions undamped (C = beta K) has round-off on their diagonal: -1e-14 */
          if (asym > 1e-8 * top || dmin < -1e-10 * top) PetscCall(Inconsistent(r, "%sdataset 'C' is not a damping matrix (asymmetry %g of its largest entry, smallest diagonal entry %g): write the model again with 'kryflex reduce'", where, (double)(top > 0 ? asym / top : asym), (double)dmin));
        }
      }
      if (!r->st->code && v > R->full_dofs) PetscCall(Inconsistent(r, "%shas %" PetscInt_FMT " reduced dofs (the rows of M) but attribute 'full_dofs' is %" PetscInt_FMT ": a reduced body is never larger than the full one", where, v, R->full_dofs));
      PetscCall(CheckNames(r, where, "interfaces", ni, R->iface_names));
      PetscCall(CheckBodyMatrices(r, where, R));
    }
    H5Gclose(g);
  }
  PetscCall(PetscFree(index));
  PetscCall(PetscFree(names));
  H5Gclose(bg);
  PetscFunctionReturn(0);
}

typedef struct {
  PetscInt index, revolute_index;
  char     name[KF_MAX_NAME];
} JointKey;

/* the file's joint order: its index attributes, or for files without them revolute joints in revolute order first */
static int CompareJoints(const void *x, const void *y)
{
  const JointKey *a = (const JointKey *)x, *b = (const JointKey *)y;

  if (a->index != b->index) return a->index < b->index ? -1 : 1;
  if ((a->revolute_index < 0) != (b->revolute_index < 0)) return a->revolute_index < 0 ? 1 : -1;
  if (a->revolute_index != b->revolute_index) return a->revolute_index < b->revolute_index ? -1 : 1;
  return strcmp(a->name, b->name);
}

static PetscErrorCode ReadJoints(KFReader *r, hid_t f, KFReducedModel m)
{
  hid_t     jg;
  PetscInt  n, *index, nrev = 0, nindexed = 0;
  JointKey *keys;
  char (*names)[KF_MAX_NAME];

  PetscFunctionBegin;
  if (r->st->code) PetscFunctionReturn(0);
  if (!Exists(f, "joints")) {
    PetscCall(Inconsistent(r, "group 'joints' is missing"));
    PetscFunctionReturn(0);
  }
  jg = H5Gopen2(f, "joints", H5P_DEFAULT);
  if (jg < 0) {
    PetscCall(ReadFail(r, "group 'joints'"));
    PetscFunctionReturn(0);
  }
  PetscCall(GroupMembers(r, jg, "group 'joints'", &n, &names));
  PetscCall(PetscCalloc2(n + 1, &index, n + 1, &keys));
  if (!r->st->code) {
    PetscCall(PetscFree2(m->joint_names, m->joints));
    PetscCall(PetscCalloc2(n, &m->joint_names, n, &m->joints));
    m->nj = n;
  }
  for (PetscInt i = 0; i < n && !r->st->code; i++) {
    hid_t       g = H5Gopen2(jg, names[i], H5P_DEFAULT);
    char        where[2 * KF_MAX_NAME], type[KF_MAX_NAME];
    KFJointDef *J = &m->joints[i];
    PetscReal   R0[9], err = 0, nrm;

    PetscCall(PetscSNPrintf(where, sizeof(where), "joint '%s' ", names[i]));
    if (g < 0) {
      PetscCall(ReadFail(r, where));
      break;
    }
    keys[i].index = 0;
    if (H5Aexists(g, "index") > 0) {
      PetscCall(ReadIntAttr(r, g, where, "index", &index[i]));
      keys[i].index = index[i];
      nindexed++;
    }
    keys[i].revolute_index = -1;
    PetscCall(PetscStrncpy(keys[i].name, names[i], KF_MAX_NAME));
    PetscCall(ReadStringAttr(r, g, where, "type", sizeof(type), type));
    PetscCall(ReadIntAttr(r, g, where, "parent", &J->parent));
    PetscCall(ReadIntAttr(r, g, where, "child", &J->child));
    PetscCall(ReadIntAttr(r, g, where, "parent_interface", &J->parent_interface));
    PetscCall(ReadIntAttr(r, g, where, "child_interface", &J->child_interface));
    PetscCall(ReadNumberAttr(r, g, where, "axis", PETSC_TRUE, 3, J->axis));
    PetscCall(ReadNumberAttr(r, g, where, "orientation", PETSC_TRUE, 9, R0));
    PetscCall(ReadIntAttr(r, g, where, "revolute_index", &keys[i].revolute_index));
    H5Gclose(g);
    if (r->st->code) break;
    if (!strcmp(type, "revolute")) J->type = KF_JOINT_REVOLUTE;
    else if (!strcmp(type, "fixed")) J->type = KF_JOINT_FIXED;
    else {
      PetscCall(Inconsistent(r, "%stype is '%s', neither 'revolute' nor 'fixed'", where, type));
      break;
    }
    nrev += J->type == KF_JOINT_REVOLUTE;
    for (int c = 0; c < 3; c++)
      for (int q = 0; q < 3; q++) J->R0[c + 3 * q] = R0[3 * c + q];
    if (J->parent < 0 || J->parent >= m->nb || J->child < 0 || J->child >= m->nb || J->parent == J->child) {
      PetscCall(Inconsistent(r, "%sties bodies %" PetscInt_FMT " (attribute parent) and %" PetscInt_FMT " (attribute child), but the file has bodies 0..%" PetscInt_FMT, where, J->parent, J->child, m->nb - 1));
      break;
    }
    if (J->parent_interface < 0 || J->parent_interface >= m->bodies[J->parent].ninterfaces || J->child_interface < 0 || J->child_interface >= m->bodies[J->child].ninterfaces) {
      PetscCall(Inconsistent(r, "%snames an interface its bodies '%s' and '%s' do not have", where, m->bodies[J->parent].name, m->bodies[J->child].name));
      break;
    }
    nrm = PetscSqrtReal(J->axis[0] * J->axis[0] + J->axis[1] * J->axis[1] + J->axis[2] * J->axis[2]);
    if (J->type == KF_JOINT_REVOLUTE && (!(nrm > 0.5 && nrm < 2) || PetscIsInfOrNanReal(nrm))) {
      PetscCall(Inconsistent(r, "%shas the axis (%g %g %g), not a unit vector", where, (double)J->axis[0], (double)J->axis[1], (double)J->axis[2]));
      break;
    }
    for (int c = 0; c < 3; c++)
      for (int q = 0; q < 3; q++) {
        PetscReal d = J->R0[0 + 3 * c] * J->R0[0 + 3 * q] + J->R0[1 + 3 * c] * J->R0[1 + 3 * q] + J->R0[2 + 3 * c] * J->R0[2 + 3 * q];
        err         = PetscMax(err, PetscAbsReal(d - (c == q)));
      }
    if (!(err <= 1e-6)) {
      PetscCall(Inconsistent(r, "%sorientation is not a rotation matrix", where));
      break;
    }
  }
  if (!r->st->code && nindexed && nindexed != n) PetscCall(Inconsistent(r, "only some joints carry an index attribute"));
  if (nindexed == n) PetscCall(CheckPermutation(r, "joints", n, index));
  if (!r->st->code) {
    /* put the joints in file order; the revolute ones must then come in revolute order, as the angles do */
    KFJointDef *joints;
    PetscInt    irev = 0;
    {
      PetscInt *pos;
      PetscCall(PetscMalloc1(n + 1, &pos));
      for (PetscInt i = 0; i < n; i++) {
        keys[i].index = nindexed ? index[i] : 0;
        pos[i]        = i;
      }
      /* sort positions by the keys (small n: insertion sort keeps it simple and stable) */
      for (PetscInt i = 1; i < n; i++)
        for (PetscInt k = i; k > 0 && CompareJoints(&keys[pos[k - 1]], &keys[pos[k]]) > 0; k--) {
          PetscInt tmp = pos[k];
          pos[k]       = pos[k - 1];
          pos[k - 1]   = tmp;
        }
      PetscCall(PetscMalloc1(n + 1, &joints));
      for (PetscInt k = 0; k < n; k++) joints[k] = m->joints[pos[k]];
      for (PetscInt k = 0; k < n; k++) {
        m->joints[k] = joints[k];
        PetscCall(PetscStrncpy(m->joint_names[k], names[pos[k]], KF_MAX_NAME));
        if (m->joints[k].type == KF_JOINT_REVOLUTE) {
          if (keys[pos[k]].revolute_index != irev) {
            PetscCall(Inconsistent(r, "joint '%s' has revolute_index %" PetscInt_FMT " but is revolute joint %" PetscInt_FMT " in joint order", names[pos[k]], keys[pos[k]].revolute_index, irev));
            break;
          }
          irev++;
        } else if (keys[pos[k]].revolute_index != -1) {
          PetscCall(Inconsistent(r, "fixed joint '%s' has revolute_index %" PetscInt_FMT ", expected -1", names[pos[k]], keys[pos[k]].revolute_index));
          break;
        }
      }
      PetscCall(PetscFree(joints));
      PetscCall(PetscFree(pos));
    }
    m->nrevolute = nrev;
  }
  PetscCall(PetscFree2(index, keys));
  PetscCall(PetscFree(names));
  H5Gclose(jg);
  PetscFunctionReturn(0);
}

/* the joints make a tree of the bodies, as the scene did: one root, every other body the child of one joint, all
   reached (a body no joint reaches would add its own rigid-body modes to the reassembled model) */
static PetscErrorCode CheckTree(KFReader *r, KFReducedModel m)
{
  PetscInt *parent, *queue, head = 0, tail = 0, root = -1;

  PetscFunctionBegin;
  if (r->st->code) PetscFunctionReturn(0);
  PetscCall(PetscMalloc2(m->nb, &parent, m->nb, &queue));
  for (PetscInt b = 0; b < m->nb; b++) parent[b] = -1;
  for (PetscInt j = 0; j < m->nj && !r->st->code; j++) {
    PetscInt c = m->joints[j].child;
    if (parent[c] >= 0) PetscCall(Inconsistent(r, "body '%s' is the child of joints '%s' and '%s'; the joints of a model form a tree", m->bodies[c].name, m->joint_names[parent[c]], m->joint_names[j]));
    parent[c] = j;
  }
  for (PetscInt b = 0; b < m->nb && root < 0; b++)
    if (parent[b] < 0) root = b;
  if (!r->st->code && root < 0) PetscCall(Inconsistent(r, "the joints form a loop (every body is some joint's child); the joints of a model form a tree"));
  if (!r->st->code) {
    for (PetscInt b = 0; b < m->nb; b++) parent[b] = -2; /* now: not reached */
    queue[tail++] = root;
    parent[root]  = -1;
    while (head < tail) {
      PetscInt b = queue[head++];
      for (PetscInt j = 0; j < m->nj; j++)
        if (m->joints[j].parent == b && parent[m->joints[j].child] == -2) {
          parent[m->joints[j].child] = j;
          queue[tail++]              = m->joints[j].child;
        }
    }
    for (PetscInt b = 0; b < m->nb && !r->st->code; b++)
      if (parent[b] == -2) PetscCall(Inconsistent(r, "body '%s' is tied to the root body '%s' by no chain of joints (%" PetscInt_FMT " bodies, %" PetscInt_FMT " joints): a body or joint was added or removed", m->bodies[b].name, m->bodies[root].name, m->nb, m->nj));
  }
  PetscCall(PetscFree2(parent, queue));
  PetscFunctionReturn(0);
}

/* the damping group, or for files without it the uniform ratio of the 'damping' setting and displacement outputs */
static PetscErrorCode ReadDamping(KFReader *r, hid_t f, KFReducedModel m)
{
  KFDamping *d = &m->damping;

  PetscFunctionBegin;
  if (r->st->code) PetscFunctionReturn(0);
  PetscCall(PetscFree(m->quantity));
  PetscCall(PetscCalloc1(PetscMax(m->noutputs, 1), &m->quantity));
  if (!Exists(f, "damping")) {
    for (PetscInt k = 0; k < m->nsettings; k++)
      if (!strcmp(m->keys[k], "damping")) PetscCall(KFDampingSetUniform(d, (PetscReal)strtod(m->values[k], NULL))); /* checked by CheckSettings */
    PetscFunctionReturn(0);
  }
  {
    hid_t      dg = H5Gopen2(f, "damping", H5P_DEFAULT);
    double     ab[2] = {0, 0}, g = 0;
    long long  nb = 0, *q;
    PetscBool  ok = PETSC_TRUE;

    if (dg < 0) {
      PetscCall(ReadFail(r, "group 'damping'"));
      PetscFunctionReturn(0);
    }
    PetscCall(PetscMemzero(d, sizeof(*d)));
    PetscCall(ReadNumberAttr(r, dg, "group 'damping' ", "modal_bands", PETSC_FALSE, 1, &nb));
    if (!r->st->code && (nb < 0 || nb > KF_MAX_DAMPING_BANDS)) PetscCall(Inconsistent(r, "group 'damping': attribute 'modal_bands' is %lld, not 0 to %d", nb, KF_MAX_DAMPING_BANDS));
    if (!r->st->code && nb > 0) {
      d->nbands = (PetscInt)nb;
      PetscCall(ReadNumberAttr(r, dg, "group 'damping' ", "modal_fmax_hz", PETSC_TRUE, nb, d->fmax_hz));
      PetscCall(ReadNumberAttr(r, dg, "group 'damping' ", "modal_zeta", PETSC_TRUE, nb, d->zeta));
    }
    PetscCall(ReadNumberAttr(r, dg, "group 'damping' ", "rayleigh", PETSC_TRUE, 2, ab));
    PetscCall(ReadNumberAttr(r, dg, "group 'damping' ", "structural", PETSC_TRUE, 1, &g));
    d->alpha = ab[0];
    d->beta  = ab[1];
    d->g     = g;
    for (PetscInt k = 0; k < d->nbands; k++) ok = (PetscBool)(ok && d->zeta[k] >= 0 && d->zeta[k] < 1 && d->fmax_hz[k] > 0 && (!k || d->fmax_hz[k] > d->fmax_hz[k - 1]));
    ok = (PetscBool)(ok && d->alpha >= 0 && d->beta >= 0 && d->g >= 0 && d->g < 1);
    if (!r->st->code && !ok) PetscCall(Inconsistent(r, "group 'damping' holds an invalid damping (ratios in [0, 1) over ascending bands, alpha, beta >= 0, 0 <= g < 1)"));
    PetscCall(PetscMalloc1(PetscMax(m->noutputs, 1), &q));
    PetscCall(ReadNumberAttr(r, dg, "group 'damping' ", "output_quantities", PETSC_FALSE, m->noutputs, q));
    for (PetscInt i = 0; i < m->noutputs && !r->st->code; i++) {
      if (q[i] < 0 || q[i] > 2) {
        PetscCall(Inconsistent(r, "group 'damping': output %" PetscInt_FMT " has quantity %lld, not 0 (displacement), 1 (velocity) or 2 (acceleration)", i, q[i]));
        break;
      }
      m->quantity[i] = (PetscInt)q[i];
    }
    PetscCall(PetscFree(q));
    H5Gclose(dg);
  }
  PetscFunctionReturn(0);
}

/* one rank's reading of the whole file into m (created empty); file faults go to st */
static PetscErrorCode KFReducedModelRead_Private(const char path[], KFReducedModel m, KFIOStatus *st)
{
  KFReader  r = {path, st};
  hid_t     f, fapl;
  htri_t    is;
  char      format[KF_MAX_NAME];
  PetscInt  version = -1, n;
  PetscBool exists;

  PetscFunctionBegin;
  PetscCall(PetscTestFile(path, 'r', &exists));
  if (!exists) {
    PetscCall(IOFail(st, PETSC_ERR_FILE_OPEN, "%s: reduced-model file not found or not readable: check the path, or write the model with 'kryflex reduce'", path));
    PetscFunctionReturn(0);
  }
  is = H5Fis_hdf5(path);
  if (is <= 0) {
    PetscCall(IOFail(st, PETSC_ERR_FILE_UNEXPECTED, "%s: not an HDF5 file, so not a kryflex reduced model: give the model file written by 'kryflex reduce'", path));
    PetscFunctionReturn(0);
  }
  /* models are replaced by rename, never rewritten in place: no lock is needed, and some file systems refuse them */
  fapl = H5Pcreate(H5P_FILE_ACCESS);
  if (fapl >= 0) (void)H5Pset_file_locking(fapl, 0, 1);
  f = H5Fopen(path, H5F_ACC_RDONLY, fapl >= 0 ? fapl : H5P_DEFAULT);
  if (f < 0) {
    H5Diagnosis d;
    /* before any other HDF5 call: each one clears the error stack, and with it HDF5's reason (a truncated file) */
    H5Diagnose(&d);
    if (fapl >= 0) H5Pclose(fapl);
    PetscCall(IOFail(st, PETSC_ERR_FILE_OPEN, "%s: cannot open the model file, it is damaged or incomplete (%s): write it again with 'kryflex reduce'", path, d.detail[0] ? d.detail : "HDF5 error"));
    PetscFunctionReturn(0);
  }
  if (fapl >= 0) H5Pclose(fapl);
  if (H5Aexists(f, "format") <= 0) PetscCall(IOFail(st, PETSC_ERR_FILE_UNEXPECTED, "%s: not a kryflex reduced model (no format attribute): give the model file written by 'kryflex reduce'", path));
  PetscCall(ReadStringAttr(&r, f, "", "format", sizeof(format), format));
  if (!st->code && strcmp(format, KF_MODEL_FORMAT)) PetscCall(IOFail(st, PETSC_ERR_FILE_UNEXPECTED, "%s: not a kryflex reduced model (format attribute '%s', expected '%s'): give the model file written by 'kryflex reduce'", path, format, KF_MODEL_FORMAT));
  PetscCall(ReadIntAttr(&r, f, "", "version", &version));
  if (!st->code && version > KF_MODEL_VERSION) PetscCall(IOFail(st, PETSC_ERR_FILE_UNEXPECTED, "%s: written in format version %" PetscInt_FMT "; this kryflex reads format version %d: use a newer kryflex or re-run kryflex reduce", path, version, KF_MODEL_VERSION));
  if (!st->code && version < KF_MODEL_VERSION) PetscCall(IOFail(st, PETSC_ERR_FILE_UNEXPECTED, "%s: written in format version %" PetscInt_FMT " (an older kryflex); this kryflex reads format version %d: re-run kryflex reduce", path, version, KF_MODEL_VERSION));
  PetscCall(ReadStringAttr(&r, f, "", "scene", sizeof(m->scene_name), m->scene_name));
  PetscCall(ReadStringAttr(&r, f, "", "scene_fingerprint", sizeof(m->fingerprint), m->fingerprint));
  if (!st->code && strlen(m->fingerprint) != 16) PetscCall(Inconsistent(&r, "the scene fingerprint '%s' is not 16 hex digits", m->fingerprint));
  PetscCall(PetscFree(m->input_names));
  PetscCall(PetscFree(m->output_names));
  PetscCall(ReadStrings(&r, f, "", "inputs", &m->ninputs, &m->input_names));
  PetscCall(ReadStrings(&r, f, "", "outputs", &m->noutputs, &m->output_names));
  if (!st->code && (m->ninputs < 1 || m->noutputs < 1)) PetscCall(Inconsistent(&r, "the model has %" PetscInt_FMT " inputs and %" PetscInt_FMT " outputs; it needs at least one of each", m->ninputs, m->noutputs));
  PetscCall(CheckNames(&r, "", "inputs", m->ninputs, m->input_names));
  PetscCall(CheckNames(&r, "", "outputs", m->noutputs, m->output_names));
  PetscCall(ReadSettings(&r, f, m));
  PetscCall(CheckSettings(&r, m));
  PetscCall(ReadBodies(&r, f, m));
  PetscCall(ReadDamping(&r, f, m));
  PetscCall(ReadJoints(&r, f, m));
  PetscCall(CheckTree(&r, m));
  n = Exists(f, "reduction_angles") ? DatasetRows(f, "reduction_angles") : 0;
  if (!st->code && n > 0) {
    m->nangles = n;
    PetscCall(ReadMatrix(&r, f, "", "reduction_angles", n, m->nrevolute, "one column per revolute joint", PETSC_TRUE, &m->angles));
  }
  if (!st->code && Exists(f, "ties")) {
    PetscInt nsum = 0;

    for (PetscInt b = 0; b < m->nb; b++) nsum += m->bodies[b].v;
    n = DatasetRows(f, "ties");
    if (n < 1 || n > nsum) PetscCall(Inconsistent(&r, "the dataset 'ties' has %" PetscInt_FMT " rows; a model of %" PetscInt_FMT " body coordinates has 1 to %" PetscInt_FMT " ties", n, nsum, nsum));
    else {
      PetscCall(ReadMatrix(&r, f, "", "ties", n, nsum, "one column per body coordinate (the sum of the bodies' reduced sizes)", PETSC_TRUE, &m->ties));
      if (!st->code) m->nties = n;
    }
  }
  H5Fclose(f);
  PetscFunctionReturn(0);
}

/*
  KFReducedModelLoad - reads a model written by KFReducedModelSave on every rank of comm, with checks of the format,
  the version and the internal consistency (shapes, names, indices, checksums). All ranks fail together with the
  same message: PETSC_ERR_FILE_OPEN (missing or unreadable), PETSC_ERR_FILE_UNEXPECTED (not a kryflex model, another
  version, inconsistent), PETSC_ERR_FILE_READ (damaged: checksum or read failure).
*/
PetscErrorCode KFReducedModelLoad(MPI_Comm comm, const char path[], KFReducedModel *model)
{
  KFReducedModel m;
  KFIOStatus     st;
  PetscMPIInt    rank, size, failed, first;
  PetscErrorCode ierr;

  PetscFunctionBegin;
  PetscValidPointer(model, 3);
  PetscCheck(path && path[0], comm, PETSC_ERR_ARG_WRONG, "KFReducedModelLoad: give a file name");
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCallMPI(MPI_Comm_size(comm, &size));
  (void)H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
  /* the object first, on every rank together (creating it may be collective); then each rank reads alone */
  PetscCall(KFReducedModelCreateEmpty_Private(comm, 0, 0, 0, 0, &m));
  PetscCall(PetscMemzero(&st, sizeof(st)));
  ierr = KFReducedModelRead_Private(path, m, &st);
  if (ierr && !st.code) PetscCall(IOFail(&st, ierr, "%s: reading the model failed (error %d, see above)", path, (int)ierr));
  failed = st.code ? rank : size;
  PetscCallMPI(MPI_Allreduce(&failed, &first, 1, MPI_INT, MPI_MIN, comm));
  if (first < size) {
    PetscCallMPI(MPI_Bcast(&st, (PetscMPIInt)sizeof(st), MPI_BYTE, first, comm));
    PetscCall(KFReducedModelDestroy(&m));
    SETERRQ(comm, st.code, "%s", st.msg);
  }
  PetscCall(PetscObjectSetName((PetscObject)m, m->scene_name));
  *model = m;
  PetscFunctionReturn(0);
}
