# The settings table (src/util/settings_table.c): every -kf_ option, as the C readers take it.

cdef _text(const char *s):
    return None if s == NULL else s.decode()


def settings_table():
    """Every -kf_ setting as a dict: name ("-kf_accuracy"), type (bool, int, real, enum, string, list), default (the
    text: auto and none are decided at run time), range (an interval's text, "(0, 1]", or None), choices (an enum's
    values; the words a number also takes, such as auto), help, scene (the scene file's key, or None), object (who
    reads it) and setter (the C function that sets it). A new list each call."""
    cdef const KFSettingInfo *table = NULL
    cdef PetscInt n = 0
    check(KFSettingsTableGet(&table, &n))
    rows = []
    for i in range(n):
        row = table[i]
        rows.append({"name": _text(row.name), "type": KFSettingTypes[<int>row.type].decode(),
                     "default": _text(row.default), "range": _text(row.range),
                     "choices": _text(row.choices).split() if row.choices != NULL else [],
                     "help": _text(row.help), "scene": _text(row.scene), "object": _text(row.object),
                     "setter": _text(row.setter) or None})
    return rows
