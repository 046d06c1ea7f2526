#include <kryflex_impl.h>
#include <ctype.h>
#include <errno.h>
#include <stdarg.h>
#include <stdlib.h>
#include <fcntl.h>
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

/* ---------------------------------------------------------------- a verdict every rank shares */

#define KF_LOAD_MSG (PETSC_MAX_PATH_LEN + 1024)

/* The first fault a rank finds in a file, as a PETSc error code and a message naming the file, the place and the fix.
   Readers record faults here instead of raising them, and LoadAgree makes every rank raise the same one: a rank that
   failed alone (a file that differs between nodes, a fault seen only in its own rows) would leave the others
   waiting in the next collective call for ever. */
typedef struct {
  PetscErrorCode code;
  char           msg[KF_LOAD_MSG];
} LoadStatus;

static PetscErrorCode LoadFail(LoadStatus *st, PetscErrorCode code, const char fmt[], ...)
{
  va_list args;
  size_t  len;

  PetscFunctionBegin;
  if (st->code) PetscFunctionReturn(0); /* the first fault only: later ones are its consequences */
  st->code = code;
  va_start(args, fmt);
  PetscCall(PetscVSNPrintf(st->msg, sizeof(st->msg), fmt, &len, args));
  va_end(args);
  PetscFunctionReturn(0);
}

/* collective: the fault of the lowest failing rank, on every rank (st->code stays 0 when all is well) */
static PetscErrorCode LoadAgree(MPI_Comm comm, LoadStatus *st)
{
  PetscMPIInt rank, size, failed, first;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCallMPI(MPI_Comm_size(comm, &size));
  failed = st->code ? rank : size;
  PetscCallMPI(MPI_Allreduce(&failed, &first, 1, MPI_INT, MPI_MIN, comm));
  if (first < size) PetscCallMPI(MPI_Bcast(st, (PetscMPIInt)sizeof(*st), MPI_BYTE, first, comm));
  PetscFunctionReturn(0);
}

/* ---------------------------------------------------------------- Matrix Market */

/* Lines of a text file of any length, numbered from 1, without their line end (LF or CRLF): exporters on Windows
   write CRLF, and a long comment must not be cut into a line that reads as an entry. */
typedef struct {
  FILE       *fp;
  const char *path;
  char       *line;
  size_t      cap;
  long long   lineno;
  PetscBool   newline; /* the line read last ended with a line end: without one, the last line may be cut */
} MMFile;

static PetscErrorCode MMOpen(const char path[], MMFile *f, LoadStatus *st)
{
  PetscFunctionBegin;
  PetscCall(PetscMemzero(f, sizeof(*f)));
  f->path = path;
  f->fp   = fopen(path, "r");
  if (!f->fp) PetscCall(LoadFail(st, PETSC_ERR_FILE_OPEN, "%s: cannot open the matrix file (%s): check the path and its permissions", path, strerror(errno)));
  PetscFunctionReturn(0);
}

static void MMClose(MMFile *f)
{
  if (f->fp) fclose(f->fp);
  free(f->line);
  f->fp   = NULL;
  f->line = NULL;
}

/* the next line, or NULL at the end of the file */
static char *MMNextLine(MMFile *f)
{
  ssize_t len = getline(&f->line, &f->cap, f->fp);

  if (len < 0) return NULL;
  f->lineno++;
  f->newline = PETSC_FALSE;
  if (len > 0 && f->line[len - 1] == '\n') {
    f->line[--len] = 0;
    f->newline     = PETSC_TRUE;
  }
  if (len > 0 && f->line[len - 1] == '\r') f->line[--len] = 0;
  if (f->lineno == 1 && !strncmp(f->line, "\xEF\xBB\xBF", 3)) memmove(f->line, f->line + 3, (size_t)len - 2); /* UTF-8 byte order mark */
  return f->line;
}

/* the next line holding data: comments ('%') and blank lines may appear anywhere after the header */
static char *MMNextData(MMFile *f)
{
  char *s;

  while ((s = MMNextLine(f))) {
    while (isspace((unsigned char)*s)) s++;
    if (*s && *s != '%') return s;
  }
  return NULL;
}

/* a line quoted in a message: at most 60 characters */
static const char *MMQuote(const char s[], char buf[64])
{
  size_t n = strlen(s);

  if (n <= 60) return s;
  memcpy(buf, s, 57);
  strcpy(buf + 57, "...");
  return buf;
}

/* an integer token: 1 on success, 0 if the text is not an integer, -1 if it does not fit in 64 bits */
static int MMParseInt(char **s, long long *v)
{
  char *end;

  while (*s && isspace((unsigned char)**s)) (*s)++;
  errno = 0;
  *v    = strtoll(*s, &end, 10);
  if (end == *s || (*end && !isspace((unsigned char)*end))) return 0;
  *s = end;
  return errno == ERANGE ? -1 : 1;
}

/* a real token, kept as written in token for messages; Fortran exporters write exponents with D (1.5D+03).
   Underflow to a subnormal or zero is a value like any other (glibc flags it with ERANGE: not an error here);
   overflow gives Inf, which the caller refuses with the entry. */
static int MMParseReal(char **s, double *v, char token[64])
{
  char   buf[64], *copy = buf, *end;
  size_t n;
  int    ok;

  while (isspace((unsigned char)**s)) (*s)++;
  for (n = 0; (*s)[n] && !isspace((unsigned char)(*s)[n]); n++) { }
  if (n < 64) {
    memcpy(token, *s, n);
    token[n] = 0;
  } else {
    memcpy(token, *s, 60);
    strcpy(token + 60, "...");
  }
  if (!n) return 0;
  if (n < sizeof(buf)) {
    memcpy(buf, *s, n);
    buf[n] = 0;
  } else if (!(copy = strndup(*s, n))) return 0; /* 0.1000...0001 with 80 digits is still a number */
  if (!strpbrk(copy, "xX"))
    for (char *p = copy; *p; p++)
      if (*p == 'D' || *p == 'd') *p = 'e';
  *v = strtod(copy, &end);
  ok = end != copy && !*end;
  if (copy != buf) free(copy);
  if (ok) *s += n;
  return ok;
}

/* what is wrong with an entry line: the fix is re-exporting; a bad last line without a line end is a cut file */
static PetscErrorCode MMBadEntry(MMFile *f, LoadStatus *st, long long k, long long nnz, const char what[], const char text[])
{
  char q[64];

  PetscFunctionBegin;
  if (!f->newline) PetscCall(LoadFail(st, PETSC_ERR_FILE_UNEXPECTED, "%s is truncated: it ends inside entry %lld of %lld (line %lld: '%s'); re-export the matrix", f->path, k, nnz, f->lineno, MMQuote(text, q)));
  else PetscCall(LoadFail(st, PETSC_ERR_FILE_UNEXPECTED, "%s: entry %lld (line %lld: '%s') %s; re-export the matrix (expected 'row column value' per line)", f->path, k, f->lineno, MMQuote(text, q), what));
  PetscFunctionReturn(0);
}

typedef struct {
  long long m, nnz; /* rows (= columns) and the entries the size line declares */
  PetscBool symmetric;
} MMHeader;

/* the banner and the size line; every word of the banner is case-insensitive (Matrix Market specification) */
static PetscErrorCode MMReadHeader(MMFile *f, MMHeader *h, LoadStatus *st)
{
  char      *s, word[5][64], q[64];
  int        nw = 0;
  long long  m, n, nnz;
  PetscBool  same;
  const char *path = f->path;

  PetscFunctionBegin;
  PetscCall(PetscMemzero(h, sizeof(*h)));
  if (!(s = MMNextLine(f))) {
    PetscCall(LoadFail(st, PETSC_ERR_FILE_UNEXPECTED, "%s is empty: expected a Matrix Market file; re-export the matrix", path));
    PetscFunctionReturn(0);
  }
  for (char *p = s; *p && nw < 5;) {
    size_t len;
    while (isspace((unsigned char)*p)) p++;
    for (len = 0; p[len] && !isspace((unsigned char)p[len]); len++) { }
    if (!len) break;
    if (len >= sizeof(word[0])) len = sizeof(word[0]) - 1;
    memcpy(word[nw], p, len);
    word[nw++][len] = 0;
    for (; *p && !isspace((unsigned char)*p); p++) { }
  }
  same = PETSC_FALSE;
  if (nw >= 1) PetscCall(PetscStrcasecmp(word[0], "%%MatrixMarket", &same));
  if (!same || nw != 5) {
    PetscCall(LoadFail(st, PETSC_ERR_FILE_UNEXPECTED, "%s: line 1 '%s' is not a Matrix Market header; expected '%%%%MatrixMarket matrix coordinate real symmetric' (or 'general'): re-export the matrix as Matrix Market", path, MMQuote(s, q)));
    PetscFunctionReturn(0);
  }
  for (int w = 1; w < 5; w++)
    for (char *p = word[w]; *p; p++) *p = (char)tolower((unsigned char)*p);
  if (strcmp(word[1], "matrix")) PetscCall(LoadFail(st, PETSC_ERR_FILE_UNEXPECTED, "%s: line 1 declares object '%s': a body matrix file holds a 'matrix'; re-export the matrix", path, word[1]));
  else if (!strcmp(word[2], "array")) PetscCall(LoadFail(st, PETSC_ERR_SUP, "%s: line 1 declares format 'array' (dense): body matrices are read from sparse 'coordinate' files; write it as coordinate (e.g. scipy.io.mmwrite(path, scipy.sparse.coo_matrix(A)))", path));
  else if (strcmp(word[2], "coordinate")) PetscCall(LoadFail(st, PETSC_ERR_FILE_UNEXPECTED, "%s: line 1 declares format '%s', neither 'coordinate' nor 'array'; re-export the matrix as a coordinate Matrix Market file", path, word[2]));
  else if (!strcmp(word[3], "pattern")) PetscCall(LoadFail(st, PETSC_ERR_SUP, "%s: line 1 declares field 'pattern': the file holds where the entries are but not their values, and a mass or stiffness matrix needs its values; export it with field 'real'", path));
  else if (!strcmp(word[3], "complex")) PetscCall(LoadFail(st, PETSC_ERR_SUP, "%s: line 1 declares field 'complex': mass and stiffness matrices are real; export it with field 'real'", path));
  else if (strcmp(word[3], "real") && strcmp(word[3], "integer") && strcmp(word[3], "double")) PetscCall(LoadFail(st, PETSC_ERR_FILE_UNEXPECTED, "%s: line 1 declares field '%s', not a Matrix Market field; export it with field 'real'", path, word[3]));
  else if (!strcmp(word[4], "hermitian") || !strcmp(word[4], "skew-symmetric"))
    PetscCall(LoadFail(st, PETSC_ERR_SUP, "%s: line 1 declares symmetry '%s': a mass or stiffness matrix is symmetric; write it as 'symmetric' (one triangle) or 'general' (both triangles)", path, word[4]));
  else if (strcmp(word[4], "symmetric") && strcmp(word[4], "general")) PetscCall(LoadFail(st, PETSC_ERR_FILE_UNEXPECTED, "%s: line 1 declares symmetry '%s', not a Matrix Market symmetry; write it as 'symmetric' (one triangle) or 'general' (both triangles)", path, word[4]));
  if (st->code) PetscFunctionReturn(0);
  h->symmetric = (PetscBool)!strcmp(word[4], "symmetric");

  if (!(s = MMNextData(f))) {
    PetscCall(LoadFail(st, PETSC_ERR_FILE_UNEXPECTED, "%s has no size line after its header: the file is truncated; re-export the matrix", path));
    PetscFunctionReturn(0);
  }
  {
    char *p = s;
    int   a = MMParseInt(&p, &m), b = a > 0 ? MMParseInt(&p, &n) : 0, c = b > 0 ? MMParseInt(&p, &nnz) : 0;
    while (isspace((unsigned char)*p)) p++;
    if (a < 0 || b < 0 || c < 0) PetscCall(LoadFail(st, PETSC_ERR_FILE_UNEXPECTED, "%s: the size line (line %lld: '%s') holds a number too large for a 64-bit integer: a damaged header; re-export the matrix", path, f->lineno, MMQuote(s, q)));
    else if (!a || !b || !c || *p) PetscCall(LoadFail(st, PETSC_ERR_FILE_UNEXPECTED, "%s: bad size line (line %lld: '%s'): expected three integers 'rows columns entries'; re-export the matrix", path, f->lineno, MMQuote(s, q)));
  }
  if (st->code) PetscFunctionReturn(0);
  if (m <= 0 || m != n) PetscCall(LoadFail(st, PETSC_ERR_ARG_SIZ, "%s: a body matrix must be square and non-empty (the size line, line %lld, says %lld x %lld): re-export the matrix as n x n, n the body's dofs", path, f->lineno, m, n));
  else if (m > PETSC_MAX_INT) PetscCall(LoadFail(st, PETSC_ERR_ARG_SIZ, "%s: %lld rows is more than this PETSc build can index (%lld: PetscInt has %d bits): use a PETSc configured with --with-64-bit-indices", path, m, (long long)PETSC_MAX_INT, (int)(8 * sizeof(PetscInt))));
  else if (nnz < 0 || nnz > (h->symmetric ? m + (m * (m - 1)) / 2 : m * m)) /* m <= 2^31 here: no overflow */
    PetscCall(LoadFail(st, PETSC_ERR_FILE_UNEXPECTED, "%s: the size line (line %lld) declares %lld entries, but a %s %lld x %lld matrix has %lld places: a wrong or damaged header; re-export the matrix", path, f->lineno, nnz, h->symmetric ? "symmetric (one triangle)" : "general", m, m, h->symmetric ? m + (m * (m - 1)) / 2 : m * m));
  /* every row of a mass or stiffness matrix holds at least its diagonal: fewer entries than rows is a wrong header */
  else if (nnz < m) PetscCall(LoadFail(st, PETSC_ERR_FILE_UNEXPECTED, "%s declares %lld rows but only %lld entries (size line, line %lld): a wrong or damaged header; re-export the matrix", path, m, nnz, f->lineno));
  h->m   = m;
  h->nnz = nnz;
  PetscFunctionReturn(0);
}

/* entry k (1-based) of the file: row and column 0-based; the checks do not depend on the rank */
static PetscErrorCode MMReadEntry(MMFile *f, const MMHeader *h, long long k, long long *i, long long *j, double *v, LoadStatus *st)
{
  char *s, *p, token[64];
  int   a, b;

  PetscFunctionBegin;
  if (!(s = MMNextData(f))) {
    PetscCall(LoadFail(st, PETSC_ERR_FILE_UNEXPECTED, "%s is truncated: it holds %lld of the %lld entries its size line declares (it ends at line %lld); re-export the matrix", f->path, k - 1, h->nnz, f->lineno));
    PetscFunctionReturn(0);
  }
  p = s;
  a = MMParseInt(&p, i);
  b = a > 0 ? MMParseInt(&p, j) : 0;
  if (a < 0 || b < 0) PetscCall(MMBadEntry(f, st, k, h->nnz, "has a row or column number too large for a 64-bit integer", s));
  else if (!a || !b) PetscCall(MMBadEntry(f, st, k, h->nnz, "does not start with a row and a column number", s));
  else if (!MMParseReal(&p, v, token)) PetscCall(MMBadEntry(f, st, k, h->nnz, token[0] ? "has a value that is not a number" : "has no value", s));
  else {
    while (isspace((unsigned char)*p)) p++;
    if (*p) PetscCall(MMBadEntry(f, st, k, h->nnz, "has more than three fields (a complex value in a 'real' file?)", s));
    else if (*i < 1 || *i > h->m || *j < 1 || *j > h->m) PetscCall(LoadFail(st, PETSC_ERR_FILE_UNEXPECTED, "%s: entry %lld (line %lld) is at (%lld, %lld), outside the %lld x %lld matrix (rows and columns count from 1); re-export the matrix", f->path, k, f->lineno, *i, *j, h->m, h->m));
    else if (PetscIsInfOrNanReal((PetscReal)*v)) PetscCall(LoadFail(st, PETSC_ERR_FP, "%s: entry %lld (line %lld) at (%lld, %lld) is '%s', not a finite number: re-export the matrix (NaN or Inf comes from a failed computation upstream)", f->path, k, f->lineno, *i, *j, token));
  }
  (*i)--;
  (*j)--;
  PetscFunctionReturn(0);
}

/* after the declared entries only comments and blank lines: more entries mean a wrong count, and dropping them
   would give another matrix than the file's */
static PetscErrorCode MMCheckEnd(MMFile *f, const MMHeader *h, LoadStatus *st)
{
  char *s, q[64];

  PetscFunctionBegin;
  if ((s = MMNextData(f))) PetscCall(LoadFail(st, PETSC_ERR_FILE_UNEXPECTED, "%s holds more than the %lld entries its size line declares (line %lld: '%s'): fix the entry count in the size line or re-export the matrix", f->path, h->nnz, f->lineno, MMQuote(s, q)));
  PetscFunctionReturn(0);
}

typedef struct {
  long long hi, lo, line; /* the entry's place in the lower triangle and its line */
  int       upper;        /* written above the diagonal */
} MMMirror;

static int MMCompareMirror(const void *x, const void *y)
{
  const MMMirror *a = (const MMMirror *)x, *b = (const MMMirror *)y;

  if (a->hi != b->hi) return a->hi < b->hi ? -1 : 1;
  if (a->lo != b->lo) return a->lo < b->lo ? -1 : 1;
  if (a->upper != b->upper) return a->upper - b->upper;
  return a->line < b->line ? -1 : (a->line > b->line);
}

/* A 'symmetric' file stores one triangle and the other is its mirror. A file with entries on both sides of the
   diagonal is legal as long as no place is written twice; an entry (i, j) and its mirror (j, i) means the exporter
   wrote both triangles, and mirroring them again would double the off-diagonal. Each rank looks at the places whose
   lower-triangle row it keeps (so the memory is its share of the matrix), and the first offence in file order is
   reported by every rank. */
static PetscErrorCode MMCheckBothTriangles(MPI_Comm comm, const char path[], const MMHeader *h, PetscInt rstart, PetscInt rend, LoadStatus *st)
{
  MMFile     f;
  MMMirror  *e = NULL;
  size_t     n = 0, cap = 0;
  long long  found[5] = {-1, -1, -1, -1, -1}, best[5], line = LLONG_MAX, first;

  PetscFunctionBegin;
  PetscCall(MMOpen(path, &f, st));
  if (f.fp) {
    MMHeader h2;
    PetscCall(MMReadHeader(&f, &h2, st));
    for (long long k = 1; k <= h->nnz && !st->code; k++) {
      long long i, j;
      double    v;
      PetscCall(MMReadEntry(&f, h, k, &i, &j, &v, st));
      if (st->code || i == j || PetscMax(i, j) < rstart || PetscMax(i, j) >= rend) continue;
      if (n == cap) {
        MMMirror *grown;
        cap = cap ? 2 * cap : 1024;
        PetscCall(PetscMalloc1(cap, &grown));
        if (n) PetscCall(PetscArraycpy(grown, e, n));
        PetscCall(PetscFree(e));
        e = grown;
      }
      e[n].hi    = PetscMax(i, j);
      e[n].lo    = PetscMin(i, j);
      e[n].upper = i < j;
      e[n].line  = f.lineno;
      n++;
    }
  }
  MMClose(&f);
  if (n) qsort(e, n, sizeof(*e), MMCompareMirror);
  /* within a place the entries below the diagonal sort first, each side by line */
  for (size_t g = 0, g1; g < n; g = g1) {
    size_t u = n;
    for (g1 = g; g1 < n && e[g1].hi == e[g].hi && e[g1].lo == e[g].lo; g1++)
      if (e[g1].upper && u == n) u = g1;
    if (!e[g].upper && u < g1 && PetscMax(e[g].line, e[u].line) < line) {
      line     = PetscMax(e[g].line, e[u].line);
      found[0] = line;
      found[1] = e[g].hi;
      found[2] = e[g].lo;
      found[3] = e[g].line;
      found[4] = e[u].line;
    }
  }
  PetscCall(PetscFree(e));
  PetscCallMPI(MPI_Allreduce(&line, &first, 1, MPI_LONG_LONG, MPI_MIN, comm));
  if (first == LLONG_MAX) PetscFunctionReturn(0);
  if (line != first) found[0] = found[1] = found[2] = found[3] = found[4] = -1;
  PetscCallMPI(MPI_Allreduce(found, best, 5, MPI_LONG_LONG, MPI_MAX, comm));
  PetscCall(LoadFail(st, PETSC_ERR_FILE_UNEXPECTED, "%s declares 'symmetric' but holds both triangles (entries (%lld, %lld) at line %lld and (%lld, %lld) at line %lld): write one triangle or declare it 'general'", path, best[1] + 1, best[2] + 1, best[3], best[2] + 1, best[1] + 1, best[4]));
  PetscFunctionReturn(0);
}

/* Matrix Market coordinate files: every rank reads the whole file and keeps its own rows, so large bodies load in
   parallel without a rank-0 bottleneck in memory. Symmetric storage (one triangle) is mirrored. Every check of the
   file is made on every rank on the whole file, whichever rows the rank keeps, and the ranks agree on the verdict
   before anything collective: a bad file fails every rank with the same message. Pass 1 checks the file and counts
   the nonzeros of the rank's rows; pass 2 inserts. */
static PetscErrorCode KFMatLoadMatrixMarket(MPI_Comm comm, const char path[], Mat *A)
{
  MMFile     f;
  MMHeader   h;
  LoadStatus st;
  PetscInt   rstart = 0, rend = 0, *dnnz = NULL, *onnz = NULL;
  long long  below = 0, above = 0;

  PetscFunctionBegin;
  *A = NULL;
  PetscCall(PetscMemzero(&st, sizeof(st)));
  PetscCall(MMOpen(path, &f, &st));
  if (f.fp) PetscCall(MMReadHeader(&f, &h, &st));
  PetscCall(LoadAgree(comm, &st));
  if (st.code) {
    MMClose(&f);
    SETERRQ(comm, st.code, "%s", st.msg);
  }
  {
    PetscInt nlocal = PETSC_DECIDE, N = (PetscInt)h.m;
    PetscCall(PetscSplitOwnership(comm, &nlocal, &N));
    PetscCallMPI(MPI_Scan(&nlocal, &rend, 1, MPIU_INT, MPI_SUM, comm));
    rstart = rend - nlocal;
  }
  PetscCall(PetscCalloc2(rend - rstart, &dnnz, rend - rstart, &onnz));
  for (long long k = 1; k <= h.nnz && !st.code; k++) {
    long long i, j;
    double    v;
    PetscCall(MMReadEntry(&f, &h, k, &i, &j, &v, &st));
    if (st.code) break;
    below += i > j;
    above += i < j;
    for (int mirror = 0; mirror < (h.symmetric && i != j ? 2 : 1); mirror++) {
      long long r = mirror ? j : i, c = mirror ? i : j;
      if (r < rstart || r >= rend) continue;
      if (c >= rstart && c < rend) dnnz[r - rstart]++;
      else onnz[r - rstart]++;
    }
  }
  if (!st.code) PetscCall(MMCheckEnd(&f, &h, &st));
  MMClose(&f);
  PetscCall(LoadAgree(comm, &st));
  /* both triangles present: look for an entry written twice (the counts are the same on every rank) */
  if (!st.code && h.symmetric && below && above) {
    PetscCall(MMCheckBothTriangles(comm, path, &h, rstart, rend, &st));
    PetscCall(LoadAgree(comm, &st));
  }
  if (st.code) {
    PetscCall(PetscFree2(dnnz, onnz));
    SETERRQ(comm, st.code, "%s", st.msg);
  }

  for (PetscInt r = 0; r < rend - rstart; r++) { /* duplicates (summed) were counted twice */
    dnnz[r] = PetscMin(dnnz[r], rend - rstart);
    onnz[r] = PetscMin(onnz[r], (PetscInt)h.m - (rend - rstart));
  }
  PetscCall(MatCreate(comm, A));
  PetscCall(MatSetSizes(*A, rend - rstart, rend - rstart, (PetscInt)h.m, (PetscInt)h.m));
  PetscCall(MatSetType(*A, MATAIJ));
  PetscCall(MatSeqAIJSetPreallocation(*A, 0, dnnz));
  PetscCall(MatMPIAIJSetPreallocation(*A, 0, dnnz, 0, onnz));
  PetscCall(MatSetOption(*A, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_FALSE));
  PetscCall(PetscFree2(dnnz, onnz));

  /* the file was checked: a fault now means it changed under us; entries are then skipped, not inserted, so that
     no rank fails inside MatSetValue while the others assemble */
  PetscCall(MMOpen(path, &f, &st));
  if (f.fp) PetscCall(MMReadHeader(&f, &h, &st));
  for (long long k = 1; k <= h.nnz && !st.code; k++) {
    long long i, j;
    double    v;
    PetscCall(MMReadEntry(&f, &h, k, &i, &j, &v, &st));
    if (st.code) break;
    if (i >= rstart && i < rend) PetscCall(MatSetValue(*A, (PetscInt)i, (PetscInt)j, (PetscScalar)v, ADD_VALUES));
    if (h.symmetric && i != j && j >= rstart && j < rend) PetscCall(MatSetValue(*A, (PetscInt)j, (PetscInt)i, (PetscScalar)v, ADD_VALUES));
  }
  MMClose(&f);
  PetscCall(LoadAgree(comm, &st));
  if (st.code) {
    PetscCall(MatDestroy(A));
    SETERRQ(comm, PETSC_ERR_FILE_UNEXPECTED, "%s (the file changed while it was read: load it again)", st.msg);
  }
  PetscCall(MatAssemblyBegin(*A, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*A, MAT_FINAL_ASSEMBLY));
  PetscFunctionReturn(0);
}

/* ---------------------------------------------------------------- PETSc binary */

/* bytes from fd until they are all read or the file ends: how many were read */
static size_t KFReadAll(int fd, void *buf, size_t bytes)
{
  char  *p    = (char *)buf;
  size_t done = 0;

  while (done < bytes) {
    ssize_t r = read(fd, p + done, bytes - done);

    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) break;
    done += (size_t)r;
  }
  return done;
}

/* n big-endian integers of a PETSc binary file: PetscBinaryRead's, but swapped by a loop the compiler vectorizes
   (PETSc's byte-by-byte swap was a tenth of loading the 57k-dof solid's bodies); got: how many were read */
static PetscErrorCode KFReadBinaryInts(int fd, PetscInt buf[], PetscInt n, PetscInt *got)
{
  PetscFunctionBegin;
  if (sizeof(PetscInt) != 4) {
    PetscCall(PetscBinaryRead(fd, buf, n, got, PETSC_INT));
    PetscFunctionReturn(0);
  }
  *got = (PetscInt)(KFReadAll(fd, buf, (size_t)n * sizeof(PetscInt)) / sizeof(PetscInt));
#if !defined(PETSC_WORDS_BIGENDIAN)
  {
    uint32_t *u = (uint32_t *)buf;

    for (PetscInt i = 0; i < *got; i++) u[i] = __builtin_bswap32(u[i]);
  }
#endif
  PetscFunctionReturn(0);
}

/* the integers of a file one after another, read in chunks (fd < 0: the n integers of buf, already in memory) */
typedef struct {
  int       fd;
  PetscInt *buf, n, pos;
} KFIntStream;

static PetscErrorCode KFIntStreamNext(KFIntStream *st, PetscInt *value, PetscBool *ok)
{
  PetscFunctionBegin;
  if (st->pos == st->n && st->fd >= 0) {
    PetscCall(KFReadBinaryInts(st->fd, st->buf, 1 << 16, &st->n));
    st->pos = 0;
  }
  *ok = (PetscBool)(st->pos < st->n);
  *value = *ok ? st->buf[st->pos++] : 0;
  PetscFunctionReturn(0);
}

/* The arrays of a checked PETSc binary matrix file, read once by the check (one process): the row offsets (n + 1),
   column indices and values (nz) MatCreateSeqAIJWithArrays takes; rows is NULL where the check kept nothing. */
typedef struct {
  PetscInt  n, nz, *rows, *cols;
  PetscReal *vals;
  PetscBool finite; /* every value a finite number (found while the values were swapped) */
} KFBinaryCSR;

static PetscErrorCode KFReadBinaryReals(int, PetscReal[], PetscInt64, PetscInt64 *, PetscBool *);

/* A PETSc binary matrix file checked before MatLoad sees it: optimized PETSc trusts the row lengths and column
   indices it reads, and a damaged file would crash the program or hang it later. Rank 0 reads the header, the row
   lengths and the column indices in chunks; every rank gets its verdict. keep (one process, 4-byte indices, 8-byte
   real scalars): the row lengths and column indices are read into the matrix's own arrays as they are checked, and
   the values after them, so that the file is read once (reading it again to load it was a quarter of loading the
   57k-dof solid's matrices); keep->rows stays NULL where this PETSc's layout differs and MatLoad must read it. */
static PetscErrorCode KFCheckPetscBinary(MPI_Comm comm, const char path[], KFBinaryCSR *keep)
{
  PetscMPIInt rank;
  LoadStatus  st;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCall(PetscMemzero(&st, sizeof(st)));
  if (keep) {
    PetscMPIInt size;
    PetscCallMPI(MPI_Comm_size(comm, &size));
    PetscCall(PetscMemzero(keep, sizeof(*keep)));
    if (size > 1 || sizeof(PetscInt) != 4 || sizeof(PetscScalar) != sizeof(PetscReal) || sizeof(PetscReal) != 8) keep = NULL;
  }
  if (!rank) {
    int        fd;
    PetscInt   header[4], *buf = NULL, got;
    PetscInt64 total = 0;
    off_t      size;

    fd = open(path, O_RDONLY);
    if (fd < 0) PetscCall(LoadFail(&st, PETSC_ERR_FILE_OPEN, "%s: cannot open the matrix file (%s): check the path and its permissions", path, strerror(errno)));
    else {
      size = lseek(fd, 0, SEEK_END);
      (void)lseek(fd, 0, SEEK_SET);
      PetscCall(PetscBinaryRead(fd, header, 4, &got, PETSC_INT));
      if (got < 4) PetscCall(LoadFail(&st, PETSC_ERR_FILE_UNEXPECTED, "%s is too short (%lld bytes) for a PETSc binary matrix header: the file is truncated or not a PETSc binary matrix; re-export the matrix", path, (long long)size));
      else if (header[0] != MAT_FILE_CLASSID) {
        const char *why = "";
        PetscInt    swapped = header[0];
        PetscCall(PetscByteSwap(&swapped, PETSC_INT, 1));
        if (swapped == MAT_FILE_CLASSID) why = " (it is written little-endian: PETSc binary files are big-endian)";
        else if (header[0] == 0 && header[1] == MAT_FILE_CLASSID) why = " (it is written with 64-bit indices; this PETSc reads 32-bit ones)";
        PetscCall(LoadFail(&st, PETSC_ERR_FILE_UNEXPECTED, "%s is not a PETSc binary matrix (class id %d, expected %d)%s: write it with PETSc's binary viewer (MatView), or use Matrix Market (.mtx)", path, (int)header[0], (int)MAT_FILE_CLASSID, why));
      } else if (header[1] <= 0 || header[1] != header[2] || header[3] < header[1])
        PetscCall(LoadFail(&st, PETSC_ERR_FILE_UNEXPECTED, "%s: the header says %d x %d with %d entries; a body matrix is square with at least its diagonal: re-export the matrix", path, (int)header[1], (int)header[2], (int)header[3]));
      else {
        const PetscInt chunk = 1 << 20, N = header[1];
        PetscInt64     need;
        PetscInt      *lens = NULL;
        if (keep) {
          char      info[PETSC_MAX_PATH_LEN];
          PetscBool has_info;
          PetscCall(PetscSNPrintf(info, sizeof(info), "%s.info", path));
          PetscCall(PetscTestFile(info, 'r', &has_info)); /* a block size from it: MatLoad reads the file */
          if (has_info) keep = NULL;
        }
        if (keep) { /* read into the row offsets' array, one place on: the offsets are summed in place after the check */
          PetscCall(PetscMalloc1(N + 1, &keep->rows));
          keep->rows[0] = 0;
          lens = keep->rows + 1;
        } else PetscCall(PetscMalloc1(chunk, &buf));
        for (PetscInt done = 0; done < N && !st.code; done += chunk) {
          PetscInt  cnt = PetscMin(chunk, N - done);
          PetscInt *b   = lens ? lens + done : buf;
          PetscCall(KFReadBinaryInts(fd, b, cnt, &got));
          if (got < cnt) PetscCall(LoadFail(&st, PETSC_ERR_FILE_UNEXPECTED, "%s is truncated in its row lengths: re-export the matrix", path));
          for (PetscInt i = 0; i < cnt && !st.code; i++) {
            if (b[i] < 0 || b[i] > N) PetscCall(LoadFail(&st, PETSC_ERR_FILE_UNEXPECTED, "%s: row %d has %d entries, but the matrix has %d columns: the file is corrupt; re-export the matrix", path, (int)(done + i + 1), (int)b[i], (int)N));
            total += b[i];
          }
        }
        if (!st.code && total != header[3]) PetscCall(LoadFail(&st, PETSC_ERR_FILE_UNEXPECTED, "%s: its rows hold %lld entries, its header says %d: the file is corrupt; re-export the matrix", path, (long long)total, (int)header[3]));
        /* the row lengths agree with the header: a file shorter than they announce is cut */
        need = (4 + (PetscInt64)N + header[3]) * (PetscInt64)sizeof(PetscInt) + (PetscInt64)header[3] * (PetscInt64)sizeof(PetscScalar);
        if (!st.code && (PetscInt64)size < need) PetscCall(LoadFail(&st, PETSC_ERR_FILE_UNEXPECTED, "%s is truncated (%lld bytes; its header announces a %d x %d matrix with %d entries, %lld bytes): re-export the matrix", path, (long long)size, (int)N, (int)N, (int)header[3], (long long)need));
        /* the column indices, row by row: the row lengths again (a second descriptor), then each row's indices must
           lie in [0, N) and increase, as MatLoad assumes */
        if (!st.code) {
          int         fr = lens ? -1 : open(path, O_RDONLY);
          PetscInt    row = 0, left = 0, prev = -1, len = 0;
          KFIntStream rl = {fr, lens, lens ? N : 0, 0}; /* the row lengths: in memory, or read in chunks (one read per row was a tenth of the check) */
          PetscBool   ok = PETSC_TRUE;
          if (!lens && (fr < 0 || lseek(fr, (off_t)(4 * sizeof(PetscInt)), SEEK_SET) < 0)) PetscCall(LoadFail(&st, PETSC_ERR_FILE_READ, "%s: cannot read the matrix file again (%s)", path, strerror(errno)));
          if (!lens) PetscCall(PetscMalloc1(1 << 16, &rl.buf));
          else {
            keep->n  = N;
            keep->nz = header[3];
            PetscCall(PetscMalloc2(keep->nz, &keep->cols, keep->nz, &keep->vals));
          }
          for (PetscInt64 done = 0; done < total && !st.code; done += chunk) {
            PetscInt  cnt = (PetscInt)PetscMin((PetscInt64)chunk, total - done);
            PetscInt *b   = lens ? keep->cols + done : buf;
            PetscCall(KFReadBinaryInts(fd, b, cnt, &got));
            if (got < cnt) PetscCall(LoadFail(&st, PETSC_ERR_FILE_UNEXPECTED, "%s is truncated in its column indices: re-export the matrix", path));
            for (PetscInt i = 0; i < cnt && !st.code; i++) {
              while (!left && row < N && !st.code) { /* the next row that holds entries */
                PetscCall(KFIntStreamNext(&rl, &len, &ok));
                if (!ok) PetscCall(LoadFail(&st, PETSC_ERR_FILE_UNEXPECTED, "%s is truncated in its row lengths: re-export the matrix", path));
                left = len;
                prev = -1;
                row++;
              }
              if (b[i] < 0 || b[i] >= N) PetscCall(LoadFail(&st, PETSC_ERR_FILE_UNEXPECTED, "%s: row %d lists column %d, outside the %d columns (counting from 1): the file is corrupt; re-export the matrix", path, (int)row, (int)b[i] + 1, (int)N));
              else if (b[i] <= prev) PetscCall(LoadFail(&st, PETSC_ERR_FILE_UNEXPECTED, "%s: row %d lists column %d after column %d (the columns of a row must increase): the file is corrupt; re-export the matrix", path, (int)row, (int)b[i] + 1, (int)prev + 1));
              prev = b[i];
              left--;
            }
          }
          if (lens && !st.code) { /* checked: the values, and the row lengths summed into offsets */
            PetscInt64 gotv = 0;
            PetscCall(KFReadBinaryReals(fd, keep->vals, keep->nz, &gotv, &keep->finite));
            if (gotv < keep->nz) PetscCall(LoadFail(&st, PETSC_ERR_FILE_UNEXPECTED, "%s is not a readable PETSc binary matrix (corrupt or truncated?): re-export it, or use Matrix Market (.mtx)", path));
            for (PetscInt i = 0; i < N; i++) keep->rows[i + 1] += keep->rows[i];
          }
          if (!lens) PetscCall(PetscFree(rl.buf));
          if (fr >= 0) close(fr);
        }
        PetscCall(PetscFree(buf));
      }
      close(fd);
    }
  }
  PetscCall(LoadAgree(comm, &st));
  if (keep && (st.code || !keep->vals)) { /* nothing kept: a fault, or a file this reader leaves to MatLoad */
    PetscCall(PetscFree(keep->rows));
    PetscCall(PetscFree2(keep->cols, keep->vals));
  }
  PetscCheck(!st.code, comm, st.code, "%s", st.msg);
  PetscFunctionReturn(0);
}

/* n big-endian reals of a PETSc binary file, swapped as KFReadBinaryInts swaps integers; got: how many were read;
   finite: whether every one read is a finite number (its exponent not all ones), looked at in the same pass */
static PetscErrorCode KFReadBinaryReals(int fd, PetscReal buf[], PetscInt64 n, PetscInt64 *got, PetscBool *finite)
{
  uint64_t *u = (uint64_t *)buf, special = 0;
  const uint64_t exponent = 0x7ff0000000000000ULL;

  PetscFunctionBegin;
  *got = (PetscInt64)(KFReadAll(fd, buf, (size_t)n * sizeof(PetscReal)) / sizeof(PetscReal));
  for (PetscInt64 i = 0; i < *got; i++) {
#if !defined(PETSC_WORDS_BIGENDIAN)
    u[i] = __builtin_bswap64(u[i]);
#endif
    special |= (uint64_t)((u[i] & exponent) == exponent);
  }
  *finite = (PetscBool)!special;
  PetscFunctionReturn(0);
}

static PetscErrorCode KFFreeCSR(void *ctx)
{
  PetscInt **rc = (PetscInt **)ctx;

  PetscFunctionBegin;
  PetscCall(PetscFree(rc[0]));
  PetscCall(PetscFree2(rc[1], rc[2]));
  PetscCall(PetscFree(rc));
  PetscFunctionReturn(0);
}

/* The matrix of a checked file's kept arrays (KFCheckPetscBinary), which become its own (MatCreateSeqAIJWithArrays,
   freed with it). MatLoad swaps them with PETSc's byte by byte loop, 40 % of loading the 57k-dof solid's four
   matrices; the matrix is the same, array for array. */
static PetscErrorCode KFMatFromBinaryCSR(MPI_Comm comm, KFBinaryCSR *csr, Mat *A)
{
  PetscInt     **rc;
  PetscContainer owner;

  PetscFunctionBegin;
  PetscCall(MatCreateSeqAIJWithArrays(comm, csr->n, csr->n, csr->rows, csr->cols, (PetscScalar *)csr->vals, A));
  PetscCall(PetscMalloc1(3, &rc));
  rc[0] = csr->rows;
  rc[1] = csr->cols;
  rc[2] = (PetscInt *)csr->vals;
  PetscCall(PetscContainerCreate(PETSC_COMM_SELF, &owner));
  PetscCall(PetscContainerSetPointer(owner, rc));
  PetscCall(PetscContainerSetUserDestroy(owner, KFFreeCSR));
  PetscCall(PetscObjectCompose((PetscObject)*A, "KFLoadedCSR", (PetscObject)owner));
  PetscCall(PetscContainerDestroy(&owner));
  PetscFunctionReturn(0);
}

/* NaN or Inf anywhere: the first such entry in row order, named on every rank (finite: known on every rank to
   hold none) */
static PetscErrorCode KFMatCheckFinite(MPI_Comm comm, const char path[], Mat A, PetscBool finite)
{
  PetscInt  rstart, rend, where[2] = {PETSC_MAX_INT, -1}, first, best[2];
  PetscReal nrm;

  PetscFunctionBegin;
  if (finite) PetscFunctionReturn(0);
  PetscCall(MatNorm(A, NORM_FROBENIUS, &nrm));
  if (!PetscIsInfOrNanReal(nrm)) PetscFunctionReturn(0);
  PetscCall(MatGetOwnershipRange(A, &rstart, &rend));
  for (PetscInt r = rstart; r < rend && where[1] < 0; r++) {
    PetscInt           nc;
    const PetscInt    *cols;
    const PetscScalar *vals;
    PetscCall(MatGetRow(A, r, &nc, &cols, &vals));
    for (PetscInt c = 0; c < nc; c++)
      if (PetscIsInfOrNanScalar(vals[c])) {
        where[0] = r;
        where[1] = cols[c];
        break;
      }
    PetscCall(MatRestoreRow(A, r, &nc, &cols, &vals));
  }
  PetscCallMPI(MPI_Allreduce(&where[0], &first, 1, MPIU_INT, MPI_MIN, comm));
  if (where[0] != first) where[1] = -1;
  best[0] = first;
  PetscCallMPI(MPI_Allreduce(&where[1], &best[1], 1, MPIU_INT, MPI_MAX, comm));
  SETERRQ(comm, PETSC_ERR_FP, "%s: the entry at row %d, column %d (counting from 1) is not a finite number (NaN or Inf): re-export the matrix (NaN or Inf comes from a failed computation upstream)", path, (int)best[0] + 1, (int)best[1] + 1);
}

PetscErrorCode KFMatLoadFile(MPI_Comm comm, const char path[], Mat *A)
{
  PetscBool   exists, mtx, finite = PETSC_FALSE;
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
    KFBinaryCSR    csr;
    PetscCall(KFCheckPetscBinary(comm, path, &csr));
    *A = NULL;
    if (csr.rows) {
      finite = csr.finite;
      PetscCall(KFMatFromBinaryCSR(comm, &csr, A));
    } else {
      PetscCall(MatCreate(comm, A));
      PetscCall(MatSetType(*A, MATAIJ));
      PetscCall(PetscViewerBinaryOpen(comm, path, FILE_MODE_READ, &viewer));
      /* a file that passed the checks and still fails (it changed meanwhile?): say which file and what to do */
      PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
      ierr = MatLoad(*A, viewer);
      PetscCall(PetscPopErrorHandler());
      PetscCall(PetscViewerDestroy(&viewer));
      PetscCheck(!ierr, comm, PETSC_ERR_FILE_UNEXPECTED, "%s is not a readable PETSc binary matrix (corrupt or truncated?): re-export it, or use Matrix Market (.mtx)", path);
    }
  }
  PetscCall(KFMatCheckFinite(comm, path, *A, finite));
  PetscCall(PetscLogEventEnd(KF_EVENT_LOAD, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

/* sum over the entries of a local block of (a_ij - t_ij)^2, where t_ij is the transposed entry, and of a_ij^2: one
   pass over the entries, no transpose built. Rows are visited in order, so the partner (j, i) of an upper entry
   (i, j), j > i, lies in row j's strictly lower part past every partner looked up before: one cursor per row walks
   it once (the binary search per entry this replaced took 0.36 s on the 202k-dof solid's 4 matrices, the cursors
   0.18 s: perf, 1 rank). Lower entries the cursor steps over, or leaves behind at the end, have no upper partner.
   A matched pair counts twice, an entry without its partner twice (a^2), for the two positions of A - A^T each
   fills. B (or NULL): a second matrix of the same nonzero pattern (a body's M and K, most exports), its sums in
   dd[1], aa[1] from the same walk: the cursors and indices, most of the walk's memory traffic, are shared; each
   matrix's sums are added in the order of its own walk, so they are those of a walk of it alone. */
static PetscErrorCode KFSeqAIJAsymmetry(Mat A, Mat B, PetscReal dd[], PetscReal aa[])
{
  const PetscInt    *ia, *ja;
  const PetscScalar *va, *vb = NULL;
  PetscInt           m, *cur;
  PetscBool          done;

  PetscFunctionBegin;
  PetscCall(MatGetRowIJ(A, 0, PETSC_FALSE, PETSC_FALSE, &m, &ia, &ja, &done));
  PetscCheck(done, PETSC_COMM_SELF, PETSC_ERR_SUP, "cannot get the rows of the matrix");
  PetscCall(MatSeqAIJGetArrayRead(A, &va));
  if (B) PetscCall(MatSeqAIJGetArrayRead(B, &vb));
  PetscCall(PetscMalloc1(m + 1, &cur));
  for (PetscInt i = 0; i < m; i++) cur[i] = ia[i];
  for (PetscInt i = 0; i < m; i++)
    for (PetscInt k = ia[i]; k < ia[i + 1]; k++) {
      const PetscInt j = ja[k];
      PetscReal      a = PetscRealPart(va[k]), b = vb ? PetscRealPart(vb[k]) : 0;

      aa[0] += a * a;
      if (vb) aa[1] += b * b;
      if (j <= i) continue; /* the diagonal has no partner to differ from; lower entries are met from above */
      if (j >= m) { /* a rectangular block has no transposed partner here */
        dd[0] += 2 * a * a;
        if (vb) dd[1] += 2 * b * b;
        continue;
      }
      while (cur[j] < ia[j + 1] && ja[cur[j]] < i) { /* lower entries of row j whose partner row had none */
        const PetscReal t = PetscRealPart(va[cur[j]]);
        dd[0] += 2 * t * t;
        if (vb) {
          const PetscReal u = PetscRealPart(vb[cur[j]]);
          dd[1] += 2 * u * u;
        }
        cur[j]++;
      }
      if (cur[j] < ia[j + 1] && ja[cur[j]] == i) {
        dd[0] += 2 * PetscSqr(a - PetscRealPart(va[cur[j]]));
        if (vb) dd[1] += 2 * PetscSqr(b - PetscRealPart(vb[cur[j]]));
        cur[j]++;
      } else {
        dd[0] += 2 * a * a;
        if (vb) dd[1] += 2 * b * b;
      }
    }
  for (PetscInt j = 0; j < m; j++) /* what no upper entry reached */
    for (PetscInt k = cur[j]; k < ia[j + 1] && ja[k] < j; k++) {
      dd[0] += 2 * PetscSqr(PetscRealPart(va[k]));
      if (vb) dd[1] += 2 * PetscSqr(PetscRealPart(vb[k]));
    }
  PetscCall(PetscFree(cur));
  if (B) PetscCall(MatSeqAIJRestoreArrayRead(B, &vb));
  PetscCall(MatSeqAIJRestoreArrayRead(A, &va));
  PetscCall(MatRestoreRowIJ(A, 0, PETSC_FALSE, PETSC_FALSE, &m, &ia, &ja, &done));
  PetscFunctionReturn(0);
}

/* the off-process couplings of an MPIAIJ matrix: (a_ij - a_ji)^2 over the positions (i local, j remote), with a_ji
   from the transpose of a matrix holding only those couplings (a thin layer: cheap to transpose) */
static PetscErrorCode KFMPIAIJOffAsymmetry(Mat A, PetscReal *dd, PetscReal *aa)
{
  Mat                Ad, Ao, O, Ot;
  const PetscInt    *garray, *ib, *jb;
  const PetscScalar *vb;
  PetscInt           m, n, rstart, *onz, *cols, maxrow = 0;
  PetscBool          done;

  PetscFunctionBegin;
  PetscCall(MatMPIAIJGetSeqAIJ(A, &Ad, &Ao, &garray));
  PetscCall(MatGetLocalSize(A, &m, &n));
  PetscCall(MatGetOwnershipRange(A, &rstart, NULL));
  PetscCall(MatGetRowIJ(Ao, 0, PETSC_FALSE, PETSC_FALSE, &m, &ib, &jb, &done));
  PetscCheck(done, PETSC_COMM_SELF, PETSC_ERR_SUP, "cannot get the rows of the matrix");
  PetscCall(MatSeqAIJGetArrayRead(Ao, &vb));
  PetscCall(PetscMalloc1(m + 1, &onz));
  for (PetscInt i = 0; i < m; i++) {
    onz[i] = ib[i + 1] - ib[i];
    maxrow = PetscMax(maxrow, onz[i]);
  }
  PetscCall(MatCreateAIJ(PetscObjectComm((PetscObject)A), m, n, PETSC_DETERMINE, PETSC_DETERMINE, 0, NULL, 0, onz, &O));
  PetscCall(PetscMalloc1(maxrow + 1, &cols));
  for (PetscInt i = 0; i < m; i++) {
    const PetscInt row = rstart + i;

    for (PetscInt k = ib[i]; k < ib[i + 1]; k++) cols[k - ib[i]] = garray[jb[k]];
    PetscCall(MatSetValues(O, 1, &row, onz[i], cols, vb + ib[i], INSERT_VALUES));
  }
  PetscCall(MatAssemblyBegin(O, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(O, MAT_FINAL_ASSEMBLY));
  PetscCall(MatTranspose(O, MAT_INITIAL_MATRIX, &Ot));
  /* row i of A's off-process part against row i of O^T, both sorted by global column: a merge */
  for (PetscInt i = 0; i < m; i++) {
    const PetscInt    *tc;
    const PetscScalar *tv;
    PetscInt           nt, p = ib[i], q = 0, row = rstart + i;

    PetscCall(MatGetRow(Ot, row, &nt, &tc, &tv));
    while (p < ib[i + 1] || q < nt) {
      const PetscInt cp = p < ib[i + 1] ? garray[jb[p]] : PETSC_MAX_INT, cq = q < nt ? tc[q] : PETSC_MAX_INT;
      PetscReal      a = 0, t = 0;

      if (cp <= cq) a = PetscRealPart(vb[p++]);
      if (cq <= cp) t = PetscRealPart(tv[q++]);
      if (cp <= cq) *aa += a * a;
      *dd += PetscSqr(a - t);
    }
    PetscCall(MatRestoreRow(Ot, row, &nt, &tc, &tv));
  }
  PetscCall(MatSeqAIJRestoreArrayRead(Ao, &vb));
  PetscCall(MatRestoreRowIJ(Ao, 0, PETSC_FALSE, PETSC_FALSE, &m, &ib, &jb, &done));
  PetscCall(PetscFree(cols));
  PetscCall(PetscFree(onz));
  PetscCall(MatDestroy(&Ot));
  PetscCall(MatDestroy(&O));
  PetscFunctionReturn(0);
}

/* the verdict on ||A - A^T||_F = nD against ||A||_F = nA, and whether A - A^T is zero (exact, when not NULL) */
static PetscErrorCode KFSymmetryVerdict(MPI_Comm comm, const char what[], PetscReal nD, PetscReal nA, PetscReal rtol, PetscBool *exact)
{
  PetscFunctionBegin;
  if (exact) *exact = (PetscBool)(nD == 0);
  PetscCheck(nD <= rtol * nA, comm, PETSC_ERR_ARG_WRONG, "%s is not symmetric: ||A - A^T|| / ||A|| = %g (> %g); kryflex needs symmetric M, K and damping matrices: check the export (both triangles, or 'symmetric' storage)", what, (double)(nA > 0 ? nD / nA : nD), (double)rtol);
  PetscFunctionReturn(0);
}

/* ||A - A^T||_F <= rtol ||A||_F, collective. AIJ matrices in one pass over their entries (the local block against
   itself, the off-process couplings against their transpose); other types through MatTranspose. The whole
   transpose and a DIFFERENT_NONZERO_PATTERN MatAXPY cost 0.7 s per matrix of a 100,000-dof solid body. */
PetscErrorCode KFMatCheckSymmetric(Mat A, const char what[], PetscReal rtol)
{
  PetscFunctionBegin;
  PetscCall(KFMatCheckSymmetricExact(A, what, rtol, NULL));
  PetscFunctionReturn(0);
}

/* The same, and exact (when not NULL): whether A - A^T is zero, every rank the same answer (the model check reads
   it instead of comparing the matrix with its transpose again) */
PetscErrorCode KFMatCheckSymmetricExact(Mat A, const char what[], PetscReal rtol, PetscBool *exact)
{
  PetscReal nA, nD;
  MPI_Comm  comm;
  PetscBool seq, mpi;

  PetscFunctionBegin;
  PetscCall(PetscObjectGetComm((PetscObject)A, &comm));
  PetscCall(PetscObjectTypeCompare((PetscObject)A, MATSEQAIJ, &seq));
  PetscCall(PetscObjectTypeCompare((PetscObject)A, MATMPIAIJ, &mpi));
  if (mpi) { /* the local block is square in local indices only when rows and columns are laid out alike (everywhere) */
    PetscInt  rs, re, cs, ce;
    PetscBool same, all;

    PetscCall(MatGetOwnershipRange(A, &rs, &re));
    PetscCall(MatGetOwnershipRangeColumn(A, &cs, &ce));
    same = (PetscBool)(rs == cs && re == ce);
    PetscCall(MPIU_Allreduce(&same, &all, 1, MPIU_BOOL, MPI_LAND, comm));
    mpi = all;
  }
  if (seq || mpi) {
    PetscReal loc[2] = {0, 0}, sum[2];

    if (seq) PetscCall(KFSeqAIJAsymmetry(A, NULL, &loc[0], &loc[1]));
    else {
      Mat Ad;

      PetscCall(MatMPIAIJGetSeqAIJ(A, &Ad, NULL, NULL));
      PetscCall(KFSeqAIJAsymmetry(Ad, NULL, &loc[0], &loc[1]));
      PetscCall(KFMPIAIJOffAsymmetry(A, &loc[0], &loc[1]));
    }
    PetscCall(MPIU_Allreduce(loc, sum, 2, MPIU_REAL, MPIU_SUM, comm));
    nD = PetscSqrtReal(sum[0]);
    nA = PetscSqrtReal(sum[1]);
  } else {
    Mat At;

    PetscCall(MatTranspose(A, MAT_INITIAL_MATRIX, &At));
    PetscCall(MatNorm(A, NORM_FROBENIUS, &nA));
    PetscCall(MatAXPY(At, -1.0, A, DIFFERENT_NONZERO_PATTERN));
    PetscCall(MatNorm(At, NORM_FROBENIUS, &nD));
    PetscCall(MatDestroy(&At));
  }
  PetscCall(KFSymmetryVerdict(comm, what, nD, nA, rtol, exact));
  PetscFunctionReturn(0);
}

/* The same for a body's M and K together: one walk for both where they are sequential AIJ matrices of the same
   nonzero pattern (the walk's indices shared: KFSeqAIJAsymmetry), else one each; M is judged first, as apart. */
PetscErrorCode KFMatCheckSymmetricPairExact(Mat M, Mat K, const char whatM[], const char whatK[], PetscReal rtol, PetscBool *exactM, PetscBool *exactK)
{
  PetscBool          seqM, seqK, same = PETSC_FALSE;
  const PetscInt    *im, *jm, *ik, *jk;
  PetscInt           nm, nk;
  PetscBool          dm, dk;

  PetscFunctionBegin;
  PetscCall(PetscObjectTypeCompare((PetscObject)M, MATSEQAIJ, &seqM));
  PetscCall(PetscObjectTypeCompare((PetscObject)K, MATSEQAIJ, &seqK));
  if (seqM && seqK) {
    PetscCall(MatGetRowIJ(M, 0, PETSC_FALSE, PETSC_FALSE, &nm, &im, &jm, &dm));
    PetscCall(MatGetRowIJ(K, 0, PETSC_FALSE, PETSC_FALSE, &nk, &ik, &jk, &dk));
    same = (PetscBool)(dm && dk && nm == nk && (im == ik || !memcmp(im, ik, (size_t)(nm + 1) * sizeof(PetscInt))));
    if (same) same = (PetscBool)(jm == jk || !memcmp(jm, jk, (size_t)im[nm] * sizeof(PetscInt)));
    PetscCall(MatRestoreRowIJ(K, 0, PETSC_FALSE, PETSC_FALSE, &nk, &ik, &jk, &dk));
    PetscCall(MatRestoreRowIJ(M, 0, PETSC_FALSE, PETSC_FALSE, &nm, &im, &jm, &dm));
  }
  if (!same) {
    PetscCall(KFMatCheckSymmetricExact(M, whatM, rtol, exactM));
    PetscCall(KFMatCheckSymmetricExact(K, whatK, rtol, exactK));
  } else {
    PetscReal dd[2] = {0, 0}, aa[2] = {0, 0};

    PetscCall(KFSeqAIJAsymmetry(M, K, dd, aa));
    PetscCall(KFSymmetryVerdict(PetscObjectComm((PetscObject)M), whatM, PetscSqrtReal(dd[0]), PetscSqrtReal(aa[0]), rtol, exactM));
    PetscCall(KFSymmetryVerdict(PetscObjectComm((PetscObject)K), whatK, PetscSqrtReal(dd[1]), PetscSqrtReal(aa[1]), rtol, exactK));
  }
  PetscFunctionReturn(0);
}
