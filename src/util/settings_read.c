/* Option readers on the settings table: the help text, manual page and range of an option come from its row
   (settings_table.c), so that -help, the manual and the checks say the same as the table. */
#include <kryflex_impl.h>

static PetscErrorCode KFSettingRow_Private(MPI_Comm comm, const char name[], const KFSettingInfo **row)
{
  PetscFunctionBegin;
  PetscCall(KFSettingFind(name, row));
  PetscCheck(*row, comm, PETSC_ERR_PLIB, "%s is read but has no row in the settings table (src/util/settings_table.c): add one", name);
  PetscFunctionReturn(0);
}

/* whether x lies in the interval text "[lo, hi)" (strtod reads inf and -inf) */
static PetscBool KFSettingInRange_Private(const char range[], PetscReal x)
{
  char  *end;
  double lo, hi;

  if (!range) return PETSC_TRUE;
  lo = strtod(range + 1, &end);
  hi = strtod(end + 1, &end);
  if (PetscIsInfOrNanReal(x) && !(PetscIsInfReal(x) && (lo == x || hi == x))) return PETSC_FALSE;
  if (range[0] == '(' ? !(x > lo) : !(x >= lo)) return PETSC_FALSE;
  if (*end == ')' ? !(x < hi) : !(x <= hi)) return PETSC_FALSE;
  return PETSC_TRUE;
}

PetscErrorCode KFSettingCheckRange(MPI_Comm comm, const char name[], PetscReal x)
{
  const KFSettingInfo *row;
  char                 value[64], also[80] = "";

  PetscFunctionBegin;
  PetscCall(KFSettingRow_Private(comm, name, &row));
  if (KFSettingInRange_Private(row->range, x)) PetscFunctionReturn(0);
  /* the C library's %g, not PETSc's (which writes 2 as "2."): the value as the user wrote it */
  if (row->type == KF_SETTING_INT) snprintf(value, sizeof(value), "%lld", (long long)x);
  else snprintf(value, sizeof(value), "%g", (double)x);
  if (row->choices) PetscCall(PetscSNPrintf(also, sizeof(also), "%s or ", row->choices));
  SETERRQ(comm, PETSC_ERR_ARG_OUTOFRANGE, "%s %s is outside %s; give %s%s in %s", name, value, row->range, also, row->type == KF_SETTING_INT ? "an integer" : "a value", row->range);
}

/* the row's choices (space-separated) are the n names of list, in any order: the enum the reader stores into is the
   one the table lists */
static PetscErrorCode KFSettingCheckChoices_Private(MPI_Comm comm, const KFSettingInfo *row, const char *const *list, PetscInt n)
{
  char   buf[512], *word, *save = NULL;
  PetscInt count = 0;

  PetscFunctionBegin;
  PetscCall(PetscStrncpy(buf, row->choices ? row->choices : "", sizeof(buf)));
  for (word = strtok_r(buf, " ", &save); word; word = strtok_r(NULL, " ", &save)) {
    PetscBool found = PETSC_FALSE;

    for (PetscInt i = 0; i < n && !found; i++) found = (PetscBool)!strcmp(list[i], word);
    PetscCheck(found, comm, PETSC_ERR_PLIB, "%s: the settings table lists choice '%s' that its reader does not take", row->name, word);
    count++;
  }
  PetscCheck(count == n, comm, PETSC_ERR_PLIB, "%s: the reader takes %" PetscInt_FMT " choices, the settings table lists %" PetscInt_FMT, row->name, n, count);
  PetscFunctionReturn(0);
}

PetscErrorCode KFOptionsSettingBool(PetscOptionItems *PetscOptionsObject, const char name[], PetscBool cur, PetscBool *value, PetscBool *set)
{
  const KFSettingInfo *row;

  PetscFunctionBegin;
  PetscCall(KFSettingRow_Private(PetscOptionsObject->comm, name, &row));
  PetscCall(PetscOptionsBool_Private(PetscOptionsObject, name, row->help, row->setter, cur, value, set));
  PetscFunctionReturn(0);
}

/* an int whose row takes auto also takes PETSC_DECIDE (-1) for it */
PetscErrorCode KFOptionsSettingInt(PetscOptionItems *PetscOptionsObject, const char name[], PetscInt cur, PetscInt *value, PetscBool *set)
{
  const KFSettingInfo *row;
  PetscBool            flg;

  PetscFunctionBegin;
  PetscCall(KFSettingRow_Private(PetscOptionsObject->comm, name, &row));
  PetscCall(PetscOptionsInt_Private(PetscOptionsObject, name, row->help, row->setter, cur, value, &flg, PETSC_MIN_INT, PETSC_MAX_INT));
  if (flg && !(*value == PETSC_DECIDE && row->choices && strstr(row->choices, "auto"))) PetscCall(KFSettingCheckRange(PetscOptionsObject->comm, name, (PetscReal)*value));
  if (set) *set = flg;
  PetscFunctionReturn(0);
}

PetscErrorCode KFOptionsSettingReal(PetscOptionItems *PetscOptionsObject, const char name[], PetscReal cur, PetscReal *value, PetscBool *set)
{
  const KFSettingInfo *row;
  PetscBool            flg;

  PetscFunctionBegin;
  PetscCall(KFSettingRow_Private(PetscOptionsObject->comm, name, &row));
  PetscCall(PetscOptionsReal_Private(PetscOptionsObject, name, row->help, row->setter, cur, value, &flg));
  if (flg) PetscCall(KFSettingCheckRange(PetscOptionsObject->comm, name, *value));
  if (set) *set = flg;
  PetscFunctionReturn(0);
}

/* each entry in the row's range */
PetscErrorCode KFOptionsSettingRealArray(PetscOptionItems *PetscOptionsObject, const char name[], PetscReal value[], PetscInt *n, PetscBool *set)
{
  const KFSettingInfo *row;
  PetscBool            flg;

  PetscFunctionBegin;
  PetscCall(KFSettingRow_Private(PetscOptionsObject->comm, name, &row));
  PetscCall(PetscOptionsRealArray_Private(PetscOptionsObject, name, row->help, row->setter, value, n, &flg));
  if (flg)
    for (PetscInt i = 0; i < *n; i++) PetscCall(KFSettingCheckRange(PetscOptionsObject->comm, name, value[i]));
  if (set) *set = flg;
  PetscFunctionReturn(0);
}

/* The value of an option that takes auto or a boolean in PETSc's spellings (0, 1, yes, no, ...): *isauto, else
   *value; *ok false when it is neither (the caller names the option in its error) */
PetscErrorCode KFStringToAutoBool(const char text[], PetscBool *isauto, PetscBool *value, PetscBool *ok)
{
  PetscErrorCode ierr;

  PetscFunctionBegin;
  *ok = PETSC_TRUE;
  PetscCall(PetscStrcasecmp(text, "auto", isauto));
  if (*isauto) PetscFunctionReturn(0);
  PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  ierr = PetscOptionsStringToBool(text, value);
  PetscCall(PetscPopErrorHandler());
  *ok = (PetscBool)!ierr;
  PetscFunctionReturn(0);
}

PetscErrorCode KFOptionsSettingString(PetscOptionItems *PetscOptionsObject, const char name[], const char cur[], char value[], size_t len, PetscBool *set)
{
  const KFSettingInfo *row;

  PetscFunctionBegin;
  PetscCall(KFSettingRow_Private(PetscOptionsObject->comm, name, &row));
  PetscCall(PetscOptionsString_Private(PetscOptionsObject, name, row->help, row->setter, cur, value, len, set));
  PetscFunctionReturn(0);
}

PetscErrorCode KFOptionsSettingEList(PetscOptionItems *PetscOptionsObject, const char name[], const char *const *list, PetscInt n, const char cur[], PetscInt *value, PetscBool *set)
{
  const KFSettingInfo *row;

  PetscFunctionBegin;
  PetscCall(KFSettingRow_Private(PetscOptionsObject->comm, name, &row));
  PetscCall(KFSettingCheckChoices_Private(PetscOptionsObject->comm, row, list, n));
  PetscCall(PetscOptionsEList_Private(PetscOptionsObject, name, row->help, row->setter, list, n, cur, value, set));
  PetscFunctionReturn(0);
}

/* list: PETSc's enum names, then the type name, the prefix and NULL */
PetscErrorCode KFOptionsSettingEnum(PetscOptionItems *PetscOptionsObject, const char name[], const char *const *list, PetscEnum cur, PetscEnum *value, PetscBool *set)
{
  const KFSettingInfo *row;
  PetscInt             n = 0;

  PetscFunctionBegin;
  PetscCall(KFSettingRow_Private(PetscOptionsObject->comm, name, &row));
  while (list[n]) n++;
  PetscCall(KFSettingCheckChoices_Private(PetscOptionsObject->comm, row, list, n - 2));
  PetscCall(PetscOptionsEnum_Private(PetscOptionsObject, name, row->help, row->setter, list, cur, value, set));
  PetscFunctionReturn(0);
}

PetscErrorCode KFOptionsSettingFList(PetscOptionItems *PetscOptionsObject, const char name[], PetscFunctionList list, const char cur[], char value[], size_t len, PetscBool *set)
{
  const KFSettingInfo *row;
  PetscBool            given = PETSC_FALSE;

  PetscFunctionBegin;
  PetscCall(KFSettingRow_Private(PetscOptionsObject->comm, name, &row));
  PetscCall(PetscOptionsFList_Private(PetscOptionsObject, name, row->help, row->setter, list, cur, value, len, &given));
  if (given) { /* PETSc takes any string here: a name no type was registered under is refused as an enum's would be */
    void (*create)(void) = NULL;

    PetscCall(PetscFunctionListFind(list, value, &create));
    PetscCheck(create, PetscOptionsObject->comm, PETSC_ERR_ARG_UNKNOWN_TYPE, "Unknown option %s for -%s%s. Available options: %s", value, PetscOptionsObject->prefix ? PetscOptionsObject->prefix : "", name + 1, row->choices);
  }
  if (set) *set = given;
  PetscFunctionReturn(0);
}
