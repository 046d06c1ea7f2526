/* What a solve leaves: named result arrays per configuration and for the whole solve, notes for the user, and the
   flexible solvers' work summed.
   The names and their meanings are listed in README.md ("Results of a reduction"). */
#include <kryflex/reducerimpl.h>
#include <stdarg.h>

/* the set of a configuration; config -1 is the whole solve's (stored last) */
static PetscErrorCode KFReducerResultSetGet_Private(KFReducer r, PetscInt config, KFResultSet **set)
{
  PetscFunctionBegin;
  PetscCheck(r->results, PetscObjectComm((PetscObject)r), PETSC_ERR_ORDER, "no results yet: call KFReducerSolve() first");
  PetscCheck(config >= -1 && config < r->nconfig, PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_OUTOFRANGE, "configuration %" PetscInt_FMT " does not exist: give -1 (the whole solve) or 0..%" PetscInt_FMT, config, r->nconfig - 1);
  *set = &r->results[config < 0 ? r->nconfig : config];
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerResultSet_Private(KFReducer r, PetscInt config, const char name[], PetscInt ndim, const PetscInt shape[], const PetscReal data[])
{
  KFResultSet *set;
  KFResult    *item = NULL;
  PetscInt     i, n = 1;

  PetscFunctionBegin;
  PetscCall(KFReducerResultSetGet_Private(r, config, &set));
  for (i = 0; i < ndim; i++) n *= shape[i];
  for (i = 0; i < set->n; i++)
    if (!strcmp(set->items[i].name, name)) item = &set->items[i];
  if (!item) {
    if (set->n == set->nalloc) {
      KFResult *items;
      char    **names;

      set->nalloc = PetscMax(16, 2 * set->nalloc);
      PetscCall(PetscCalloc1(set->nalloc, &items));
      PetscCall(PetscCalloc1(set->nalloc, &names));
      if (set->n) {
        PetscCall(PetscArraycpy(items, set->items, set->n));
        PetscCall(PetscArraycpy(names, set->names, set->n));
      }
      PetscCall(PetscFree(set->items));
      PetscCall(PetscFree(set->names));
      set->items = items;
      set->names = names;
    }
    item = &set->items[set->n];
    PetscCall(PetscStrncpy(item->name, name, sizeof(item->name)));
    set->names[set->n] = item->name;
    set->n++;
  }
  PetscCall(PetscFree(item->data));
  item->ndim = ndim;
  for (i = 0; i < 3; i++) item->shape[i] = i < ndim ? shape[i] : 1;
  PetscCall(PetscMalloc1(PetscMax(n, 1), &item->data));
  if (n) PetscCall(PetscArraycpy(item->data, data, n));
  /* names point into items, which may have moved */
  for (i = 0; i < set->n; i++) set->names[i] = set->items[i].name;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerResultScalar_Private(KFReducer r, PetscInt config, const char name[], PetscReal value)
{
  PetscInt one = 1;

  PetscFunctionBegin;
  PetscCall(KFReducerResultSet_Private(r, config, name, 1, &one, &value));
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerResultsReset_Private(KFReducer r)
{
  PetscFunctionBegin;
  if (r->results) {
    for (PetscInt c = 0; c <= r->nconfig; c++) {
      for (PetscInt i = 0; i < r->results[c].n; i++) PetscCall(PetscFree(r->results[c].items[i].data));
      PetscCall(PetscFree(r->results[c].items));
      PetscCall(PetscFree(r->results[c].names));
    }
    PetscCall(PetscFree(r->results));
  }
  for (PetscInt i = 0; i < r->nnotes; i++) PetscCall(PetscFree(r->notes[i]));
  PetscCall(PetscFree(r->notes));
  r->nnotes  = 0;
  r->rule[0] = 0;
  PetscCall(KFReducedModelDestroy(&r->single));
  PetscCall(KFReducedModelDestroy(&r->multi_model));
  r->solved = PETSC_FALSE;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerNote_Private(KFReducer r, const char fmt[], ...)
{
  char    line[1024], **notes;
  size_t  len;
  va_list args;

  PetscFunctionBegin;
  va_start(args, fmt);
  PetscCall(PetscVSNPrintf(line, sizeof(line), fmt, &len, args));
  va_end(args);
  PetscCall(PetscMalloc1(r->nnotes + 1, &notes));
  if (r->nnotes) PetscCall(PetscArraycpy(notes, r->notes, r->nnotes));
  PetscCall(PetscStrallocpy(line, &notes[r->nnotes]));
  PetscCall(PetscFree(r->notes));
  r->notes = notes;
  r->nnotes++;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerGetResultNames(KFReducer r, PetscInt config, PetscInt *n, const char *const **names)
{
  KFResultSet *set;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCall(KFReducerResultSetGet_Private(r, config, &set));
  if (n) *n = set->n;
  if (names) *names = (const char *const *)set->names;
  PetscFunctionReturn(0);
}

PetscErrorCode KFReducerGetResult(KFReducer r, PetscInt config, const char name[], PetscInt *ndim, const PetscInt **shape, const PetscReal **data)
{
  KFResultSet *set;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(r, KF_REDUCER_CLASSID, 1);
  PetscCall(KFReducerResultSetGet_Private(r, config, &set));
  for (PetscInt i = 0; i < set->n; i++) {
    if (strcmp(set->items[i].name, name)) continue;
    if (ndim) *ndim = set->items[i].ndim;
    if (shape) *shape = set->items[i].shape;
    if (data) *data = set->items[i].data;
    PetscFunctionReturn(0);
  }
  SETERRQ(PetscObjectComm((PetscObject)r), PETSC_ERR_ARG_WRONG, "no result '%s' for configuration %" PetscInt_FMT ": KFReducerGetResultNames lists what the solve recorded (see README.md, Results of a reduction)", name, config);
}

/* "15", "15_30" or "structure": the configuration's label in progress lines, notes and the Python summary (C's %g,
   not PETSc's, which would write "15."); a scene without revolute joints has one configuration, the structure, and
   no angle */
PetscErrorCode KFReducerConfigLabel_Private(PetscInt nrev, const PetscReal angles[], char buf[], size_t len)
{
  size_t used = 0;

  PetscFunctionBegin;
  buf[0] = 0;
  if (!nrev) PetscCall(PetscStrncpy(buf, "structure", len));
  for (PetscInt j = 0; j < nrev && used < len; j++) used += (size_t)snprintf(buf + used, len - used, "%s%g", j ? "_" : "", (double)(angles[j] * 180.0 / PETSC_PI));
  PetscFunctionReturn(0);
}

/* "at 15 deg" or, without revolute joints, "of the structure": where a sentence places a configuration */
PetscErrorCode KFReducerConfigPlace_Private(PetscInt nrev, const PetscReal angles[], char buf[], size_t len)
{
  char label[128];

  PetscFunctionBegin;
  PetscCall(KFReducerConfigLabel_Private(nrev, angles, label, sizeof(label)));
  if (nrev) PetscCall(PetscSNPrintf(buf, len, "at %s deg", label));
  else PetscCall(PetscStrncpy(buf, "of the structure", len));
  PetscFunctionReturn(0);
}

/* "12 + 19": reduced dofs per body, for progress lines */
PetscErrorCode KFReducerModelSizes_Private(KFReducedModel m, char buf[], size_t len)
{
  PetscInt nb;
  size_t   used = 0;

  PetscFunctionBegin;
  buf[0] = 0;
  PetscCall(KFReducedModelGetInfo(m, &nb, NULL, NULL, NULL, NULL, NULL));
  for (PetscInt b = 0; b < nb; b++) {
    KFReducedBody body;

    PetscCall(KFReducedModelGetBody(m, b, NULL, NULL, &body, NULL));
    PetscCall(PetscSNPrintf(buf + used, len - used, "%s%" PetscInt_FMT, b ? " + " : "", body.v));
    PetscCall(PetscStrlen(buf, &used));
  }
  PetscFunctionReturn(0);
}

/* a flexible solver's work added to the solve's (the timing table and the summary's performance) */
PetscErrorCode KFReducerAddPerf_Private(KFReducer r, KFFlexSolver solver)
{
  KFFlexSolverPerf p;

  PetscFunctionBegin;
  PetscCall(KFFlexSolverGetPerf(solver, &p));
  r->perf.factor_seconds += p.factor_seconds;
  r->perf.solve_seconds += p.solve_seconds;
  r->perf.memory_estimate_mb = PetscMax(r->perf.memory_estimate_mb, p.memory_estimate_mb);
  r->perf.residual_first_max = PetscMax(r->perf.residual_first_max, p.residual_first_max);
  r->perf.residual_final_max = PetscMax(r->perf.residual_final_max, p.residual_final_max);
  r->perf.solve_calls += p.solve_calls;
  r->perf.solve_columns += p.solve_columns;
  r->perf.refinement_solves += p.refinement_solves;
  r->perf.blocks += p.blocks;
  r->perf.blocks_refined += p.blocks_refined;
  r->perf.blocks_unconverged += p.blocks_unconverged;
  r->perf.blocks_escalated += p.blocks_escalated;
  PetscFunctionReturn(0);
}
