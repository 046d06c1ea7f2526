"""Nastran models for kryflex bodies: DMIG matrices, GRIDs with coordinate systems, SPOINTs, WTMASS.

The cards are read by pyNastran (pyNastran.bdf.bdf.BDF: small, large (`DMIG*`, `GRID*`) and free field,
continuations, every Nastran spelling of a real); this module turns what it read into a kryflex body:

  files      a punch file (.pch: bulk data without BEGIN BULK), a bulk-data deck (.bdf/.dat, with or without
             executive and case control), or a run's .f06 whose sorted bulk-data echo (ECHO=SORT, the default)
             is cut out and read as bulk data. Several files are merged; a card given twice must be the same.
  DMIG       IFO 6 (symmetric, one triangle or both) or 1 (square), TIN 1 or 2 (real). An entry given twice must
             agree to round-off. Components 1..6 of GRIDs, component 0 (blank) of scalar points.
  nodes      every (point, component) any of the matrices uses is a dof; nodes are ordered by id (grids and
             scalar points together, as Nastran sorts its a-set), components ascending. A grid keeps the
             components the matrices use: all six -> `6`, ux uy uz -> `3`, others -> `c<components>` (e.g. a
             grid whose rotations carry neither mass nor stiffness: `c123`, a plate grid without drilling
             stiffness and inertia: `c12345`); a scalar point -> `s` (docs/guide/boundary-conditions.md: dof layouts).
  positions  GRID X1 X2 X3 are in the grid's CP system (rectangular, cylindrical r theta z or spherical
             r theta phi, angles in degrees; CORD1x/CORD2x, chained through RID); they are written in the basic
             system. A grid the matrices use must have a GRID card (never silently at 0, 0, 0).
  dofs       the matrix rows of a grid are in its CD system, evaluated at the grid (for CORD2C/CORD2S the axes
             turn with the grid's position): with R the 3 x 3 matrix whose columns are the local axes in basic,
             u_basic = T u_local, T = blockdiag(R, R) per grid, and K_basic = T K T^T (the same for M), so
             rigid-body modes from the written coordinates are right. A grid that has only some components can
             be transformed only if R maps their span onto itself (e.g. only `3` with a CD rotated about z);
             otherwise the rows mix with absent components: an error names the grid.
  WTMASS     Nastran multiplies the mass it generates from elements and mass cards by PARAM,WTMASS, so a punched
             mass matrix (MAAX) already holds it, and DMIG input is not scaled by WTMASS (M2GG/M2PP
             documentation). The DMIG mass is therefore used as stored; mass_scale multiplies it when it was
             written in weight units (mass_scale='wtmass' takes the model's PARAM,WTMASS). The stiffness is never
             scaled.
Errors are ConversionError naming the file, the card and the fix.
"""

import io
import os
import re
import warnings

import numpy as np
import scipy.sparse as sp

from .bodyfiles import ConversionError, ConversionWarning

COMPONENT_NAMES = {0: "scalar", 1: "ux", 2: "uy", 3: "uz", 4: "rx", 5: "ry", 6: "rz"}
SUPPORTED_IFO = {1: "square", 6: "symmetric"}
REAL_TIN = (1, 2)
DUPLICATE_TOLERANCE = 1e-10   # an entry given twice (both triangles) must agree to round-off
AXIS_TOLERANCE = 1e-9         # |R[absent, present]| below this: the present components are closed under R

# the cards kryflex needs; the rest of a deck (elements, loads, ...) is not parsed
CARDS = ["DMIG", "GRID", "GRDSET", "SPOINT", "PARAM",
         "CORD1R", "CORD1C", "CORD1S", "CORD2R", "CORD2C", "CORD2S"]

_F06_ECHO = re.compile(r"B\s?U\s?L\s?K\s+D\s?A\s?T\s?A\s+E\s?C\s?H\s?O")
_F06_LINE = re.compile(r"^\s*\d+-\s{8}(.*)$")


# ---------------------------------------------------------------- reading files with pyNastran

def _pynastran():
    """pyNastran's BDF class, or a clear error when this Python lacks it."""
    try:
        from pyNastran.bdf.bdf import BDF
    except ImportError as exc:
        raise ConversionError(
            f"reading Nastran files needs pyNastran, which this Python cannot import ({exc}); run kryflex from the "
            "project's .venv (scripts/setup installs pyNastran 1.4.1 there)") from None
    return BDF


def _quiet_log():
    from cpylog import SimpleLogger
    return SimpleLogger(level="critical")


def f06_bulk_echo(path):
    """The bulk-data cards of a Nastran .f06's sorted bulk-data echo (ECHO=SORT, Nastran's default): the numbered
    lines ('   12-        GRID    ...') between the echo's heading and ENDDATA, page headers skipped."""
    try:
        with open(path, "r", encoding="latin-1") as handle:
            text = handle.read()
    except OSError as exc:
        raise ConversionError(f"cannot read {path}: {exc.strerror or exc}") from None
    lines, inside = [], False
    for raw in text.splitlines():
        if _F06_ECHO.search(raw):
            inside = True
            continue
        if not inside:
            continue
        match = _F06_LINE.match(raw.rstrip())
        if match:
            card = match.group(1)
            lines.append(card)
            if card.strip().upper().startswith("ENDDATA"):
                inside = False
        elif raw.strip().upper().startswith("ENDDATA"):
            inside = False
    if not lines:
        raise ConversionError(
            f"{path} holds no bulk-data echo (no 'B U L K   D A T A   E C H O' section with numbered cards); "
            "rerun Nastran with ECHO=SORT in the case control, or give the .bdf/.dat instead")
    return lines


def _read_file(path):
    """One file into a pyNastran BDF (not cross-referenced)."""
    BDF = _pynastran()

    path = os.fspath(path)
    try:
        with open(path, "rb") as handle:
            handle.seek(0, os.SEEK_END)
            size = handle.tell()
            if size:
                handle.seek(size - 1)
                last = handle.read(1)
            handle.seek(0)
            head = handle.read(1 << 20)
    except OSError as exc:
        raise ConversionError(f"cannot read Nastran file {path}: {exc.strerror or exc}") from None
    if size == 0:
        raise ConversionError(f"Nastran file {path} is empty")
    f06 = path.lower().endswith(".f06") or _F06_ECHO.search(head.decode("latin-1")) is not None
    if not f06 and last not in b"\n\r":
        raise ConversionError(
            f"{path}: the last line has no end-of-line, so its last card may be cut off: the file looks "
            "truncated; if it is complete, end it with a newline")
    model = BDF(log=_quiet_log())
    model.enable_cards(CARDS)
    try:
        if f06:
            deck = "\n".join(f06_bulk_echo(path)) + "\n"
            model.read_bdf(io.StringIO(deck), punch=True, xref=False, validate=False)
        else:
            begin = re.search(rb"^\s*BEGIN\s+(BULK|SUPER)[^\n]*\n", head, re.M | re.I)
            if begin is None:                                   # a punch: bulk data only
                model.read_bdf(path, punch=True, xref=False, validate=False)
            elif re.search(rb"^\s*CEND", head[:begin.start()], re.M | re.I):   # a whole deck
                model.read_bdf(path, punch=False, xref=False, validate=False)
            else:                                               # BEGIN BULK without the decks before it
                with open(path, "r", encoding="latin-1") as handle:
                    text = handle.read()
                bulk = text[re.search(r"^\s*BEGIN\s+(BULK|SUPER)[^\n]*\n", text, re.M | re.I).end():]
                model.read_bdf(io.StringIO(bulk), punch=True, xref=False, validate=False)
    except ConversionError:
        raise
    except Exception as exc:  # noqa: BLE001 - pyNastran raises SyntaxError, AssertionError, RuntimeError, ...
        detail = " ".join(str(exc).split())[:400] or type(exc).__name__
        raise ConversionError(
            f"{path}: pyNastran cannot read this Nastran file ({detail}); the file is incomplete "
            "(truncated?) or holds a malformed card: fix or re-export it") from None
    return model


def _same(a, b):
    return a.raw_fields() == b.raw_fields()


class NastranDeck:
    """The cards of one or more Nastran files, merged; each card remembers its file."""

    def __init__(self, paths):
        BDF = _pynastran()

        self.paths = [os.fspath(p) for p in paths]
        self.model = BDF(log=_quiet_log())
        self.origin = {}
        m = self.model
        for path in self.paths:
            part = _read_file(path)
            for kind, mine, theirs in (("GRID", m.nodes, part.nodes), ("SPOINT", m.spoints, part.spoints),
                                       ("coordinate system", m.coords, part.coords),
                                       ("DMIG", m.dmig, part.dmig), ("PARAM", m.params, part.params)):
                for key, card in theirs.items():
                    if kind == "coordinate system" and key == 0:
                        continue
                    if kind == "PARAM" and key != "WTMASS":
                        continue                      # the only PARAM kryflex uses
                    if key in mine and not (kind == "SPOINT" or _same(mine[key], card)):
                        raise ConversionError(
                            f"{kind} {key} is defined in {self.origin[kind, key]} and again, differently, in "
                            f"{path}; give each card once")
                    mine.setdefault(key, card)
                    self.origin.setdefault((kind, key), path)
            if part.grdset is not None:
                if m.grdset is not None and not _same(m.grdset, part.grdset):
                    raise ConversionError(f"GRDSET of {path} differs from the one in {self.origin['GRDSET']}")
                m.grdset = part.grdset
                self.origin.setdefault("GRDSET", path)
        self._xref = False

    def where(self, kind, key):
        return self.origin.get((kind, key), " + ".join(self.paths))

    # ---------------------------------------------------------------- coordinate systems

    def _check_coordinates(self, grid_ids):
        """Every system the grids use exists, and every system's RID chain ends in basic; then cross-reference."""
        m = self.model
        for cid, coord in m.coords.items():
            seen = [cid]
            while cid != 0:
                card = m.coords[cid]
                rid = getattr(card, "rid", 0) or 0
                if card.type.startswith("CORD1"):
                    for g in (card.G1(), card.G2(), card.G3()):
                        if g not in m.nodes:
                            raise ConversionError(
                                f"{self.where('coordinate system', cid)}: {card.type} {cid} is defined by GRID {g}, "
                                "which no file defines; add the bulk data that holds it (--grids)")
                    break
                if rid not in m.coords:
                    raise ConversionError(
                        f"{self.where('coordinate system', cid)}: {card.type} {cid} is defined in system "
                        f"RID={rid}, which no CORD card defines; add the file that defines it (--grids) or fix RID")
                if rid in seen:
                    raise ConversionError(
                        f"{self.where('coordinate system', cid)}: coordinate systems "
                        f"{' -> '.join(map(str, seen + [rid]))} refer to each other in a loop; fix RID")
                seen.append(rid)
                cid = rid
        grdset = m.grdset
        defaulted = []
        used = set(grid_ids)
        for gid, node in sorted(m.nodes.items()):   # pyNastran cross-references every GRID: check them all
            if grdset is not None:   # GRDSET's CP and CD stand for blank fields, which pyNastran reads as 0
                if gid in used and ((grdset.cp and not node.cp) or (grdset.cd and not node.cd)):
                    defaulted.append(gid)
                node.cp = node.cp or grdset.cp
                node.cd = node.cd or grdset.cd
            for field, cid in (("CP", node.cp), ("CD", node.cd)):
                if cid not in m.coords:
                    raise ConversionError(
                        f"{self.where('GRID', gid)}: GRID {gid} gives {field}={cid}, but no CORD card defines "
                        f"coordinate system {cid}; add the file that defines it (--grids) or fix the GRID")
        if defaulted:
            warnings.warn(
                f"GRDSET ({self.origin['GRDSET']}) sets CP={grdset.cp} CD={grdset.cd}: {len(defaulted)} GRID(s) "
                f"whose CP or CD is blank or 0 take it (e.g. {', '.join(map(str, defaulted[:5]))}); a GRID that "
                "means an explicit 0 (basic) needs CD/CP of a basic-aligned CORD2R instead", ConversionWarning)
        if not self._xref:
            try:
                m.cross_reference(xref=True, xref_nodes=True, xref_elements=False, xref_properties=False,
                                  xref_masses=False, xref_materials=False, xref_loads=False,
                                  xref_constraints=False, xref_aero=False, xref_sets=False,
                                  xref_optimization=False)
            except Exception as exc:  # noqa: BLE001 - e.g. a CORD2x whose three points are collinear
                raise ConversionError(
                    f"{' + '.join(self.paths)}: the coordinate systems cannot be set up "
                    f"({' '.join(str(exc).split())[:300]}); fix the CORD cards") from None
            self._xref = True

    def positions(self, grid_ids):
        """{grid id: basic (x, y, z)} of the grids asked for; each needs a GRID card."""
        missing = [g for g in grid_ids if g not in self.model.nodes]
        if missing:
            shown = ", ".join(map(str, missing[:10]))
            raise ConversionError(
                f"{len(missing)} grid(s) used by the matrices have no GRID card in {' + '.join(self.paths)} "
                f"({shown}{', ...' if len(missing) > 10 else ''}), so their positions are unknown; give the bulk "
                "data that defines them with --grids (a .bdf/.dat, or the run's .f06 with its bulk-data echo)")
        self._check_coordinates(grid_ids)
        return {g: tuple(float(v) for v in self.model.nodes[g].get_position()) for g in grid_ids}

    def axes(self, gid, xyz):
        """R (3 x 3): columns = the local axes of GRID gid's CD system at its basic position xyz."""
        node = self.model.nodes[gid]
        coord = self.model.coords[node.cd]
        if node.cd == 0:
            return np.eye(3)
        beta = np.asarray(coord.beta(), dtype=float)   # rows: the system's i, j, k in basic
        if coord.type.endswith("R"):
            return beta.T
        local = np.asarray(coord.transform_node_to_local(np.asarray(xyz, dtype=float)), dtype=float)
        if coord.type.endswith("C"):     # (r, theta, z)
            t = np.radians(local[1])
            ax = np.array([[np.cos(t), -np.sin(t), 0.0], [np.sin(t), np.cos(t), 0.0], [0.0, 0.0, 1.0]])
        else:                            # (r, theta from k, phi about k)
            t, p = np.radians(local[1]), np.radians(local[2])
            ax = np.array([[np.sin(t) * np.cos(p), np.cos(t) * np.cos(p), -np.sin(p)],
                           [np.sin(t) * np.sin(p), np.cos(t) * np.sin(p), np.cos(p)],
                           [np.cos(t), -np.sin(t), 0.0]])
        return beta.T @ ax

    def wtmass(self):
        param = self.model.params.get("WTMASS")
        return 1.0 if param is None else float(param.values[0])

    # ---------------------------------------------------------------- matrices

    def matrices(self, names):
        """{name: (CSR matrix over the dofs, as stored)} and the shared dof list [(id, component)]."""
        names = [n.upper() for n in names]
        dmigs = self.model.dmig
        for name in names:
            if name not in dmigs:
                found = ", ".join(sorted(dmigs)) or "none"
                raise ConversionError(
                    f"{' + '.join(self.paths)}: no DMIG matrix {name} (DMIG matrices found: {found}); the file is "
                    "incomplete, or give the right names (--stiffness-name/--mass-name)")
        raw = {}
        for name in names:
            d = dmigs[name]
            where = f"{self.where('DMIG', name)}: DMIG {name}"
            if d.matrix_form not in SUPPORTED_IFO:
                raise ConversionError(
                    f"{where} has matrix form IFO={d.matrix_form}; kryflex reads square (1) or symmetric (6) "
                    "mass and stiffness matrices")
            if d.tin not in REAL_TIN:
                raise ConversionError(f"{where} has TIN={d.tin} (complex); mass and stiffness must be real "
                                      "(TIN 1 or 2)")
            gci = np.asarray(d.GCi, dtype=np.int64).reshape(-1, 2)
            gcj = np.asarray(d.GCj, dtype=np.int64).reshape(-1, 2)
            if gci.shape[0] == 0:
                raise ConversionError(f"{where} has a header but no columns (file truncated?)")
            values = np.asarray(d.Real, dtype=np.float64)
            if not np.all(np.isfinite(values)):
                raise ConversionError(f"{where} holds a non-finite value; fix the export")
            raw[name] = (d, gci, gcj, values, where)
        keys = np.unique(np.concatenate([np.concatenate([gci, gcj]) @ [8, 1] for _, gci, gcj, _, _ in raw.values()]))
        dofs = [(int(k // 8), int(k % 8)) for k in keys]
        self._check_points(dofs)
        for name, (d, _, _, _, where) in raw.items():
            ncol = int(d.ncols or 0)
            if ncol > len(keys):
                raise ConversionError(
                    f"{where} declares NCOL={ncol} columns but only {len(keys)} dofs appear in the matrices: "
                    "the file looks truncated")
            present = np.unique(raw[name][2] @ [8, 1])
            if 0 < present.size < ncol:
                absent = [dofs[k] for k in np.flatnonzero(~np.isin(keys, present))]
                shown = ", ".join(dof_label(x) for x in absent[:6]) + (", ..." if len(absent) > 6 else "")
                warnings.warn(
                    f"{where} has {present.size} columns but its header declares NCOL={ncol}; the dofs without a "
                    f"column ({shown}) get zero columns in {name}, as Nastran leaves all-zero columns out (e.g. "
                    "rotations without rotary inertia in a mass matrix); if they should not be zero, the file is "
                    "truncated", ConversionWarning)
        result = {}
        for name, (d, gci, gcj, values, where) in raw.items():
            rows = np.searchsorted(keys, gci @ [8, 1])
            cols = np.searchsorted(keys, gcj @ [8, 1])
            result[name] = _assemble(where, d.matrix_form, rows, cols, values, len(keys), dofs)
        return result, dofs

    def _check_points(self, dofs):
        m = self.model
        for gid, comp in dofs:
            if comp == 0 and gid in m.nodes:
                raise ConversionError(
                    f"{' + '.join(self.paths)}: the matrices use point {gid} with component 0 (a scalar point), but "
                    f"{self.where('GRID', gid)} defines GRID {gid}; grids have components 1..6")
            if comp != 0 and gid in m.spoints:
                raise ConversionError(
                    f"{' + '.join(self.paths)}: the matrices use component {comp} of point {gid}, which "
                    f"{self.where('SPOINT', gid)} declares a scalar point (SPOINT: component 0 or blank only)")


def _assemble(where, ifo, rows, cols, values, size, dofs):
    """A CSR matrix from (row, column, value) triplets: one triangle (IFO 6) mirrored, duplicates checked."""
    if ifo == 6:   # gather both triangles onto the upper one
        rows, cols = np.minimum(rows, cols), np.maximum(rows, cols)
    order = np.lexsort((rows, cols))
    rows, cols, values = rows[order], cols[order], values[order]
    same = (rows[1:] == rows[:-1]) & (cols[1:] == cols[:-1])
    if same.any():
        scale = np.maximum(np.abs(values[1:]), np.abs(values[:-1]))
        clash = same & (np.abs(values[1:] - values[:-1]) > DUPLICATE_TOLERANCE * scale)
        if clash.any():
            k = int(np.flatnonzero(clash)[0])
            raise ConversionError(
                f"{where} gives entry (row {dof_label(dofs[rows[k]])}, column {dof_label(dofs[cols[k]])}) twice"
                f"{' (both triangles)' if ifo == 6 else ''} with different values {values[k]:.10g} and "
                f"{values[k + 1]:.10g}; give each entry once")
        keep = np.concatenate([[True], ~same])
        rows, cols, values = rows[keep], cols[keep], values[keep]
    if ifo == 6:
        off = rows != cols
        rows, cols, values = (np.concatenate([rows, cols[off]]), np.concatenate([cols, rows[off]]),
                              np.concatenate([values, values[off]]))
    return sp.csr_matrix((values, (rows, cols)), shape=(size, size))


def dof_label(dof):
    gid, comp = dof
    return f"{gid}-{COMPONENT_NAMES[comp]}"


# ---------------------------------------------------------------- nodes and transforms

def node_dofs(components):
    """The nodes-file dofs field of a set of components: 6, 3, 'c<digits>' or 's' (component 0)."""
    components = sorted(components)
    if components == [0]:
        return "s"
    if components == [1, 2, 3, 4, 5, 6]:
        return 6
    if components == [1, 2, 3]:
        return 3
    return "c" + "".join(map(str, components))


def group_dofs(dofs):
    """[(id, [components])] in dof order."""
    groups = []
    for gid, comp in dofs:
        if groups and groups[-1][0] == gid:
            groups[-1][1].append(comp)
        else:
            groups.append((gid, [comp]))
    return groups


def basic_transform(deck, groups, positions):
    """T (sparse, n x n) with u_basic = T u_stored over the dofs, block by block; None when every CD is basic."""
    rows, cols, vals = [], [], []
    start, rotated = 0, False
    for gid, comps in groups:
        n = len(comps)
        if comps == [0]:
            rows.append(start), cols.append(start), vals.append(1.0)
            start += 1
            continue
        R = deck.axes(gid, positions[gid])
        rotated = rotated or not np.array_equal(R, np.eye(3))
        for triple in (1, 4):
            present = [c for c in comps if triple <= c < triple + 3]
            if not present:
                continue
            inside = np.array([c - triple for c in present])
            outside = np.array([k for k in range(3) if k not in inside], dtype=int)
            if outside.size and np.abs(R[np.ix_(outside, inside)]).max() > AXIS_TOLERANCE:
                node = deck.model.nodes[gid]
                raise ConversionError(
                    f"GRID {gid} ({deck.where('GRID', gid)}) has only components "
                    f"{''.join(map(str, comps))} in the matrices, in its displacement system CD={node.cd}, whose "
                    f"{'translation' if triple == 1 else 'rotation'} axes {''.join(str(c) for c in present)} do not "
                    "map onto the same basic axes, so these rows cannot be turned into basic dofs without the "
                    "absent components; re-export with all components of this grid (or CD=0)")
            offset = start + comps.index(present[0])
            block = R[np.ix_(inside, inside)]
            for a in range(len(present)):
                for b in range(len(present)):
                    if block[a, b] != 0.0:
                        rows.append(offset + a), cols.append(offset + b), vals.append(block[a, b])
        start += n
    if not rotated:
        return None
    return sp.csr_matrix((vals, (rows, cols)), shape=(start, start))


def nastran_body(path, grid_files=(), stiffness_name="KAAX", mass_name="MAAX", mass_scale=None):
    """Read a Nastran body: (M, K, nodes, notes) with M, K in basic dofs and nodes (id, x, y, z, dofs).

    path: the file with the DMIG matrices; grid_files: more files with GRID/CORD/SPOINT/PARAM cards.
    mass_scale: None (the DMIG mass as stored), a number, or 'wtmass' (the model's PARAM,WTMASS).
    """
    names = (stiffness_name.upper(), mass_name.upper())
    if names[0] == names[1]:
        raise ConversionError(f"stiffness and mass matrix names are both {names[0]}; they must differ")
    deck = NastranDeck([path, *grid_files])
    matrices, dofs = deck.matrices(names)
    K, M = matrices[names[0]], matrices[names[1]]
    groups = group_dofs(dofs)
    grid_ids = [g for g, comps in groups if comps != [0]]
    positions = deck.positions(grid_ids)
    T = basic_transform(deck, groups, positions)
    if T is not None:
        K, M = (T @ K @ T.T).tocsr(), (T @ M @ T.T).tocsr()
    wtmass = deck.wtmass()
    if isinstance(mass_scale, str):
        if mass_scale.lower() != "wtmass":
            raise ConversionError(f"mass scale {mass_scale!r}: give a number or 'wtmass'")
        mass_scale = wtmass
    elif mass_scale is None and wtmass != 1.0:
        warnings.warn(
            f"PARAM,WTMASS={wtmass:g} in {deck.where('PARAM', 'WTMASS')}: the DMIG mass {names[1]} is used as "
            "stored (a punched mass matrix already holds WTMASS; Nastran does not scale DMIG input by it); if "
            f"{names[1]} is in weight units, convert with --mass-scale wtmass", ConversionWarning)
    if mass_scale is not None:
        mass_scale = float(mass_scale)
        if not np.isfinite(mass_scale) or mass_scale <= 0:
            raise ConversionError(f"mass scale {mass_scale!r} must be a positive number")
        M = M * mass_scale
    nodes = [(g, *(positions[g] if comps != [0] else (0.0, 0.0, 0.0)), node_dofs(comps)) for g, comps in groups]
    notes = {"dofs": dofs, "wtmass": wtmass, "mass_scale": 1.0 if mass_scale is None else mass_scale,
             "rotated": T is not None}
    return M, K, nodes, notes


# ---------------------------------------------------------------- small entry points

def read_dmig(path, names=("KAAX", "MAAX")):
    """The DMIG matrices named in names as stored (in the grids' CD systems): {name: (CSR, dof list)}, the
    dof list [(id, component)] shared by all (see the module notes)."""
    matrices, dofs = NastranDeck([path]).matrices(names)
    return {name: (A, dofs) for name, A in matrices.items()}


def read_grids(paths, ids=None):
    """Basic coordinates {grid id: (x, y, z)} of the GRIDs of one or more bulk-data files (or .f06 echoes)."""
    deck = NastranDeck([paths] if isinstance(paths, (str, os.PathLike)) else list(paths))
    return deck.positions(sorted(deck.model.nodes) if ids is None else list(ids))
