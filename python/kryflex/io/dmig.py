"""Read Nastran DMIG matrices (e.g. KAAX, MAAX of a punch file) and GRID coordinates.

Nastran bulk data comes in three layouts, all read here, mixed freely in one file:
  small field  8-character fields: field 1 (name) + 8 data fields + field 10 (continuation marker);
               continuation lines start with '+' or a blank field 1.
  large field  name ending in '*' (DMIG*, GRID*): 4 data fields of 16 characters per line;
               continuation lines start with '*' and carry the next 4 fields.
  free field   comma separated; DMIG* ,... lines carry 4 data fields, others 8.
Each card is turned into its list of data fields 2, 3, ... (continuation markers dropped),
so the three layouts give the same list and the card readers below never see the layout.

DMIG cards:
  header  DMIG NAME 0 IFO TIN TOUT POLAR (blank) NCOL     IFO 6 = symmetric, 1 = square
  column  DMIG NAME GJ CJ (blank) G1 C1 A1 B1 / G2 C2 A2 B2 / ...
A symmetric matrix (IFO 6) stores one triangle (Nastran punches (GI,CI) <= (GJ,CJ)); the other
half is filled here. Components: 1..6 = ux uy uz rx ry rz; 0 would be a scalar point.

The dofs found in the matrices become kryflex nodes: a grid whose entries only touch
components 1..3 becomes a 3-dof node, any other grid a 6-dof node; nodes are ordered by grid
id, dofs by component, and components a 6-dof node lacks become zero rows and columns.
"""

import math
import re
import warnings
from array import array

import numpy as np
import scipy.sparse as sp

from .bodyfiles import ConversionError, ConversionWarning

COMPONENT_NAMES = {1: "ux", 2: "uy", 3: "uz", 4: "rx", 5: "ry", 6: "rz"}
SUPPORTED_IFO = {1: "square", 6: "symmetric"}
REAL_TIN = (1, 2)
DUPLICATE_TOLERANCE = 1e-10  # a symmetric entry given in both triangles must agree to round-off

_IMPLICIT_EXPONENT = re.compile(r"^([+-]?(?:\d+\.?\d*|\.\d+))([+-]\d+)$")


# ---------------------------------------------------------------- bulk-data cards

def iter_cards(path, wanted):
    """Yield (card name without '*', data fields, first line number) for cards named in wanted."""
    wanted = {w.upper() for w in wanted}
    name, fields, start = None, None, 0
    try:
        handle = open(path, "r", encoding="latin-1")
    except OSError as exc:
        raise ConversionError(f"cannot read Nastran file {path}: {exc.strerror or exc}") from exc
    unterminated = False
    with handle:
        for number, raw in enumerate(handle, start=1):
            line = raw.rstrip("\r\n")
            cut = line.find("$")
            if cut >= 0:
                line = line[:cut]
            if not line.strip():
                continue
            unterminated = not raw.endswith("\n")  # only the last line can lack it
            free = "," in line
            if free:
                tokens = [t.strip() for t in line.split(",")]
                first = tokens[0]
            else:
                line = line.expandtabs(8)
                first = line[:8].strip()
            if first == "" or first[0] in "+*":
                if fields is None:
                    continue  # continuation of a card we skip
                large = first.startswith("*")
            else:
                if fields is not None:
                    yield name, fields, start
                upper = first.upper()
                if upper.startswith("ENDDATA"):
                    return
                if upper.startswith("INCLUDE"):
                    warnings.warn(f"{path}, line {number}: INCLUDE statements are not followed; "
                                  "pass the included file separately (e.g. with --grids)", ConversionWarning)
                large = upper.endswith("*")
                name = upper.rstrip("*").strip()
                if name not in wanted:
                    name, fields = None, None
                    continue
                fields, start = [], number
            width = 4 if large else 8
            if free:
                data = tokens[1:1 + width]
                if any(tokens[2 + width:]):
                    raise ConversionError(
                        f"{path}, line {number}: free-field line holds more than 10 fields; "
                        "put the rest on a continuation line")
                data += [""] * (width - len(data))
            elif large:
                data = [line[8 + 16 * k:24 + 16 * k] for k in range(4)]
            else:
                data = [line[8 + 8 * k:16 + 8 * k] for k in range(8)]
            if not large and len(fields) % 8:
                fields.extend([""] * (8 - len(fields) % 8))  # a small line follows half a large pair
            fields.extend(f.strip() for f in data)
        if fields is not None:
            if unterminated:
                raise ConversionError(
                    f"{path}: the last line ({number}) has no end-of-line, so the {name} card on line {start} "
                    "may be cut off: the file looks truncated; if it is complete, end it with a newline")
            yield name, fields, start


def parse_real(text, where):
    """A Nastran real: 1.5, 1.5E+3, 1.5D+3 or the exponent-only form 1.5+3."""
    s = text.strip().upper().replace("D", "E")
    try:
        value = float(s)
    except ValueError:
        match = _IMPLICIT_EXPONENT.match(s)
        if not match:
            raise ConversionError(f"{where}: {text.strip()!r} is not a number") from None
        value = float(f"{match.group(1)}E{match.group(2)}")
    if not math.isfinite(value):
        raise ConversionError(f"{where}: value {text.strip()!r} is not finite")
    return value


def parse_int(text, where, default=None):
    s = text.strip()
    if not s and default is not None:
        return default
    try:
        return int(s)
    except ValueError:
        raise ConversionError(f"{where}: {s!r} is not an integer") from None


def _field(fields, k):
    return fields[k] if k < len(fields) else ""


# ---------------------------------------------------------------- scan of one file

class _RawMatrix:
    """The header and the (column, row, value) triplets of one DMIG matrix as read."""

    def __init__(self, name, ifo, ncol, line):
        self.name, self.ifo, self.ncol, self.line = name, ifo, ncol, line
        self.col_grid, self.col_comp = array("q"), array("q")
        self.row_grid, self.row_comp = array("q"), array("q")
        self.values = array("d")
        self.columns = 0


def scan_bulk(path, names, grids=True):
    """One pass over a bulk-data file: the DMIG matrices named in names, GRID and GRDSET cards."""
    names = [n.upper() for n in names]
    matrices, other_dmig = {}, set()
    grid_records, grdset = {}, None
    cards = ("DMIG", "GRID", "GRDSET") if grids else ("DMIG",)
    for card, fields, line in iter_cards(path, cards):
        where = f"{path}, line {line}"
        if card == "DMIG":
            mname = _field(fields, 0).upper()
            if mname not in names:
                other_dmig.add(mname)
                continue
            _read_dmig_card(where, line, mname, fields, matrices)
        elif card == "GRID":
            gid = parse_int(_field(fields, 0), f"{where} (GRID id)")
            record = (_field(fields, 1), [parse_real(_field(fields, k) or "0", f"{where} (GRID {gid} x{k - 1})")
                                          for k in (2, 3, 4)], _field(fields, 5), line)
            if gid in grid_records and grid_records[gid][1] != record[1]:
                raise ConversionError(
                    f"{where}: GRID {gid} is defined again (first on line {grid_records[gid][3]}) "
                    "with other coordinates; grid ids must be unique")
            grid_records[gid] = record
        elif card == "GRDSET":
            grdset = (_field(fields, 1), _field(fields, 5), line)
    return matrices, other_dmig, grid_records, grdset


def _read_dmig_card(where, line, mname, fields, matrices):
    if _field(fields, 1) == "0":
        if mname in matrices:
            raise ConversionError(
                f"{where}: second header card for DMIG matrix {mname} (first on line {matrices[mname].line}); "
                "each matrix must be defined once")
        ifo = parse_int(_field(fields, 2), f"{where} (DMIG {mname} IFO)")
        tin = parse_int(_field(fields, 3), f"{where} (DMIG {mname} TIN)")
        if ifo not in SUPPORTED_IFO:
            raise ConversionError(
                f"{where}: DMIG {mname} has matrix form IFO={ifo}; kryflex reads square (1) or "
                "symmetric (6) mass and stiffness matrices")
        if tin not in REAL_TIN:
            raise ConversionError(
                f"{where}: DMIG {mname} has TIN={tin} (complex); mass and stiffness must be real (TIN 1 or 2)")
        ncol = parse_int(_field(fields, 7), f"{where} (DMIG {mname} NCOL)", default=0)
        matrices[mname] = _RawMatrix(mname, ifo, ncol, line)
        return
    if mname not in matrices:
        raise ConversionError(
            f"{where}: column card of DMIG {mname} comes before its header card "
            f"('DMIG {mname} 0 IFO TIN ...'); the file is incomplete or out of order")
    raw = matrices[mname]
    gj = parse_int(_field(fields, 1), f"{where} (DMIG {mname} column grid GJ)")
    cj = parse_int(_field(fields, 2), f"{where} (DMIG {mname} column component CJ)", default=0)
    _check_component(gj, cj, where, mname)
    entries = 0
    for k in range(4, len(fields), 4):
        g, c, a, b = (_field(fields, k + i) for i in range(4))
        if not (g or c or a or b):
            continue
        entry = f"{where} (DMIG {mname} column {gj}-{cj}, entry {entries + 1})"
        if not g:
            raise ConversionError(f"{entry}: value without a row grid GI")
        if not a:
            raise ConversionError(
                f"{entry}: row {g}-{c} has no value; the card is incomplete (file truncated?)")
        gi = parse_int(g, f"{entry} row grid")
        ci = parse_int(c, f"{entry} row component", default=0)
        _check_component(gi, ci, entry, mname)
        value = parse_real(a, entry)
        if b and parse_real(b, entry) != 0.0:
            raise ConversionError(f"{entry}: imaginary part {b!r} given for a real matrix")
        raw.col_grid.append(gj)
        raw.col_comp.append(cj)
        raw.row_grid.append(gi)
        raw.row_comp.append(ci)
        raw.values.append(value)
        entries += 1
    if entries == 0:
        raise ConversionError(
            f"{where}: column {gj}-{cj} of DMIG {mname} has no entries; the card is incomplete "
            "(file truncated?)")
    raw.columns += 1


def _check_component(grid, comp, where, mname):
    if grid <= 0:
        raise ConversionError(f"{where}: grid id {grid} of DMIG {mname} must be positive")
    if comp == 0:
        raise ConversionError(
            f"{where}: DMIG {mname} uses scalar point {grid} (component 0); kryflex bodies have "
            "grid dofs only: keep scalar points out of the exported set (e.g. no SPOINTs in the a-set)")
    if not 1 <= comp <= 6:
        raise ConversionError(f"{where}: component {comp} of grid {grid} in DMIG {mname} must be 1..6")


# ---------------------------------------------------------------- matrices

def read_dmig(path, names=("KAAX", "MAAX")):
    """Read the DMIG matrices named in names from a Nastran punch (or bulk-data) file.

    Returns {name: (scipy.sparse CSR matrix, dof_list)} where dof_list = [(grid, component)]
    (component 1..6) gives the meaning of each row; all matrices read in one call share the
    same dof list, built from the dofs of all of them (see the module notes).
    """
    matrices, other, _, _ = scan_bulk(path, names, grids=False)
    return build_matrices(path, names, matrices, other)


def build_matrices(path, names, matrices, other_dmig):
    names = [n.upper() for n in names]
    for mname in names:
        if mname not in matrices:
            found = ", ".join(sorted(set(matrices) | other_dmig)) or "none"
            raise ConversionError(
                f"{path}: no DMIG matrix {mname} (DMIG matrices in the file: {found}); the file is "
                "incomplete, or give the right names (--stiffness-name/--mass-name)")
        if matrices[mname].columns == 0:
            raise ConversionError(f"{path}: DMIG {mname} has a header but no columns (file truncated?)")
    raws = [matrices[n] for n in names]
    keys = np.unique(np.concatenate([
        np.concatenate([_keys(r.col_grid, r.col_comp), _keys(r.row_grid, r.row_comp)]) for r in raws]))
    grids, comps = keys // 8, keys % 8
    node_ids, first = np.unique(grids, return_index=True)
    max_comp = np.maximum.reduceat(comps, first)
    ndof = np.where(max_comp > 3, 6, 3)
    offset = np.concatenate([[0], np.cumsum(ndof)])
    size = int(offset[-1])
    dof_list = [(int(g), c) for g, n in zip(node_ids, ndof) for c in range(1, n + 1)]

    for raw in raws:
        if raw.ncol > len(keys):
            raise ConversionError(
                f"{path}: DMIG {raw.name} (header on line {raw.line}) declares NCOL={raw.ncol} columns "
                f"but only {len(keys)} dofs appear in the file: the file looks truncated")
    for raw in raws:
        if 0 < raw.columns < raw.ncol:
            warnings.warn(
                f"{path}: DMIG {raw.name} has {raw.columns} column cards but its header (line {raw.line}) "
                f"declares NCOL={raw.ncol}; Nastran leaves all-zero columns out (e.g. rotations without "
                "rotary inertia), otherwise the file is truncated", ConversionWarning)
    if size > len(keys):
        missing = sorted(set(dof_list) - {(int(k // 8), int(k % 8)) for k in keys})
        shown = ", ".join(f"{g}-{COMPONENT_NAMES[c]}" for g, c in missing[:8])
        warnings.warn(
            f"{path}: {len(missing)} dofs of the matrices' grids are absent from them ({shown}"
            f"{', ...' if len(missing) > 8 else ''}); they are written as zero rows and columns "
            "(no mass, no stiffness), which leaves them undetermined: re-export with every "
            "component of these grids in the exported set (a 3-dof grid needs ux uy uz, a 6-dof grid all six)",
            ConversionWarning)

    def index(grid, comp):
        g = np.frombuffer(grid, dtype=np.int64)
        return offset[np.searchsorted(node_ids, g)] + np.frombuffer(comp, dtype=np.int64) - 1

    result = {}
    for raw in raws:
        rows, cols = index(raw.row_grid, raw.row_comp), index(raw.col_grid, raw.col_comp)
        values = np.frombuffer(raw.values, dtype=np.float64)
        result[raw.name] = (_assemble(path, raw, rows, cols, values, size, dof_list), dof_list)
    return result


def _keys(grid, comp):
    return np.frombuffer(grid, dtype=np.int64) * 8 + np.frombuffer(comp, dtype=np.int64)


def _assemble(path, raw, rows, cols, values, size, dof_list):
    if raw.ifo == 6:  # one triangle stored: gather both triangles onto the upper one
        rows, cols = np.minimum(rows, cols), np.maximum(rows, cols)
    order = np.lexsort((rows, cols))
    rows, cols, values = rows[order], cols[order], values[order]
    same = (rows[1:] == rows[:-1]) & (cols[1:] == cols[:-1])
    if same.any():
        scale = np.maximum(np.abs(values[1:]), np.abs(values[:-1]))
        clash = same & (np.abs(values[1:] - values[:-1]) > DUPLICATE_TOLERANCE * scale)
        if clash.any():
            k = int(np.flatnonzero(clash)[0])
            (gi, ci), (gj, cj) = dof_list[rows[k]], dof_list[cols[k]]
            raise ConversionError(
                f"{path}: DMIG {raw.name} gives entry (row {gi}-{COMPONENT_NAMES[ci]}, column "
                f"{gj}-{COMPONENT_NAMES[cj]}) twice{' (both triangles)' if raw.ifo == 6 else ''} with "
                f"different values {values[k]:.10g} and {values[k + 1]:.10g}; give each entry once")
        keep = np.concatenate([[True], ~same])
        rows, cols, values = rows[keep], cols[keep], values[keep]
    if raw.ifo == 6:
        off = rows != cols
        rows, cols, values = (np.concatenate([rows, cols[off]]), np.concatenate([cols, rows[off]]),
                              np.concatenate([values, values[off]]))
    return sp.csr_matrix((values, (rows, cols)), shape=(size, size))


def nodes_from_dofs(dof_list):
    """[(grid, ndof)] in order, from a dof list made by read_dmig."""
    nodes = []
    for grid, comp in dof_list:
        if nodes and nodes[-1][0] == grid:
            nodes[-1][1] = comp
        else:
            nodes.append([grid, comp])
    return [(g, n) for g, n in nodes]


# ---------------------------------------------------------------- coordinates

def read_grids(path, ids=None):
    """GRID coordinates of a bulk-data (or punch) file: {grid id: (x, y, z)} in the basic system.

    With ids, only those grids are returned and checked. A grid with a local position system
    (CP) or displacement system (CD) is an error: kryflex needs basic coordinates and dofs.
    """
    _, _, records, grdset = scan_bulk(path, (), grids=True)
    return grids_from_records(path, records, grdset, ids)


def grids_from_records(path, records, grdset, ids=None):
    default_cp = default_cd = ""
    if grdset is not None:
        default_cp, default_cd = grdset[0], grdset[1]
    wanted = records.keys() if ids is None else [i for i in ids if i in records]
    coords = {}
    for gid in wanted:
        cp_text, xyz, cd_text, line = records[gid]
        where = f"{path}, line {line}: GRID {gid}"
        cp = parse_int(cp_text or default_cp, f"{where} CP", default=0)
        cd = parse_int(cd_text or default_cd, f"{where} CD", default=0)
        if cp != 0:
            raise ConversionError(
                f"{where} is positioned in coordinate system CP={cp}; kryflex does not read CORD cards: "
                "export the grids with basic coordinates (CP=0), e.g. from a run with the grids "
                "listed in the basic system")
        if cd != 0:
            raise ConversionError(
                f"{where} has displacement system CD={cd}, so its matrix rows are in that local system; "
                "kryflex needs dofs in the basic system: set CD=0 for the exported grids and re-export")
        coords[gid] = tuple(xyz)
    return coords
