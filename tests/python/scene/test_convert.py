"""Tests of `kryflex convert`: Nastran DMIG punch files, .npz and Matrix Market inputs, body files.

The punch files are written here, card by card, in Nastran's own layouts (small field with
continuation cards, large field DMIG*/'*' pairs, free field) from known random symmetric
matrices, so the reader is checked against matrices it never saw in any other form.
"""

import os
import random
from decimal import Decimal

import numpy as np
import pytest
import scipy.io
import scipy.sparse as sp

from kryflex.io import bodyfiles, dmig
from kryflex.io.bodyfiles import ConversionError, ConversionWarning, read_nodes, write_body
from kryflex.io.convert import convert, main

# Grid ids are not contiguous; grid 13 has translations only (a 3-dof node).
GRIDS = {7: 6, 12: 6, 13: 3, 40: 6, 41: 6, 105: 6, 2000: 6}
COORDS = {g: (0.5 * g, -0.25 * g, 1.0 + 0.125 * g) for g in GRIDS}
DOFS = [(g, c) for g in sorted(GRIDS) for c in range(1, GRIDS[g] + 1)]

# A value printed in a 16-character large field keeps 10 significant digits (d.dddddddddD+xx),
# so the printed value is within half a unit of the 10th digit: |error| <= 5e-10 |value|.
LARGE_FIELD_RTOL = 5e-10 * (1 + 1e-9)


# ---------------------------------------------------------------- a Nastran card writer

def justify(field, width):
    """As Nastran punches: names left-justified, numbers right-justified."""
    return f"{field:<{width}}" if field[:1].isalpha() else f"{field:>{width}}"


def small_card(card, fields, blank_continuation=False):
    """Small-field lines: 8 data fields per line, continuation markers in fields 10 and 1."""
    lines, rows = [], [fields[i:i + 8] for i in range(0, max(len(fields), 1), 8)]
    for k, row in enumerate(rows):
        row = row + [""] * (8 - len(row))
        head = f"{card:<8}" if k == 0 else ("        " if blank_continuation else f"+C{k:06d}")
        tail = f"+C{k + 1:06d}" if k + 1 < len(rows) and not blank_continuation else ""
        lines.append(head + "".join(justify(f, 8) for f in row) + tail)
    return lines


def large_card(card, fields):
    """Large-field lines: 'CARD*' then '*' continuations, 4 fields of 16 characters each."""
    lines, rows = [], [fields[i:i + 4] for i in range(0, max(len(fields), 1), 4)]
    for k, row in enumerate(rows):
        row = row + [""] * (4 - len(row))
        head = f"{card + '*':<8}" if k == 0 else "*       "
        lines.append(head + "".join(justify(f, 16) for f in row))
    return lines


def free_card(card, fields):
    """Free-field lines: comma separated, 8 fields per line, '+' or ',' continuations."""
    lines = []
    for k in range(0, max(len(fields), 1), 8):
        head = card if k == 0 else ("+" if (k // 8) % 2 else "")
        lines.append(",".join([head] + fields[k:k + 8]))
    return lines


def exact_short(value, rng):
    """At most 8 characters whose decimal value is exactly value (a multiple of 1/4), in one of
    Nastran's spellings: 1250.5, 1.2505+3 (exponent without E) or 1.2505D3."""
    sign, digits, exponent = Decimal(value).normalize().as_tuple()   # exact for k/4
    lead, rest = str(digits[0]), "".join(map(str, digits[1:]))
    power = len(digits) - 1 + exponent
    s = "-" if sign else ""
    forms = [(repr(value), repr(value)),
             (f"{s}{lead}.{rest}{power:+d}", f"{s}{lead}.{rest}E{power:+d}"),
             (f"{s}{lead}.{rest}D{power}", f"{s}{lead}.{rest}E{power}")]
    rng.shuffle(forms)
    nastran, standard = next(form for form in forms if len(form[0]) <= 8)
    assert Decimal(standard) == Decimal(value)
    return nastran


def dmig_lines(name, A, dofs, layout, rng, triangle="upper", ifo=6, shuffle_columns=False):
    """DMIG cards of dense matrix A (rows and columns = dofs) in the given layout.

    layout: 'small' (exact short values), 'small-blank' (blank continuation fields),
    'large' (10 significant digits, D exponent), 'free' (repr, exact).
    """
    n = len(dofs)
    header = [name, "0", str(ifo), "2", "0", "", "", str(n)]
    if layout == "large":
        text = lambda v: f"{v:16.9E}".replace("E", "D")  # noqa: E731
        write = large_card
    elif layout == "free":
        text, write = repr, free_card
    else:
        text = lambda v: exact_short(v, rng)  # noqa: E731
        write = lambda c, f: small_card(c, f, blank_continuation=(layout == "small-blank"))  # noqa: E731
    # Nastran's own punch: small-field header with a sequence number in columns 73-80; in the
    # large layout KAAX gets a large-field header (DMIG*) instead, so both spellings are read.
    if layout == "free" or (layout == "large" and name == "KAAX"):
        lines = write("DMIG", header)
    else:
        lines = [small_card("DMIG", header)[0] + "       1"]
    columns = list(range(n))
    if shuffle_columns:
        rng.shuffle(columns)
    for j in columns:
        if ifo == 1:
            rows = [i for i in range(n) if A[i, j] != 0]
        elif triangle == "upper":
            rows = [i for i in range(j + 1) if A[i, j] != 0]
        else:
            rows = [i for i in range(j, n) if A[i, j] != 0]
        if not rows:
            continue
        fields = [name, str(dofs[j][0]), str(dofs[j][1]), ""]
        for i in rows:
            fields += [str(dofs[i][0]), str(dofs[i][1]), text(A[i, j]), ""]
        lines += write("DMIG", fields)
    return lines


def grid_lines(coords, layouts=("small", "large", "free")):
    lines = []
    for k, gid in enumerate(sorted(coords)):
        layout = layouts[k % len(layouts)]
        x, y, z = coords[gid]
        if layout == "large":
            lines += large_card("GRID", [str(gid), "", f"{x:16.9E}", f"{y:16.9E}", f"{z:16.9E}", "0"])
        elif layout == "free":
            lines += free_card("GRID", [str(gid), "0", repr(x), repr(y), repr(z)])
        else:
            lines += small_card("GRID", [str(gid), "", repr(x), repr(y), repr(z)])
    return lines


def random_symmetric(rng, n, quarter_units=True):
    """A random sparse symmetric matrix with a full diagonal (so every dof appears)."""
    a = np.zeros((n, n))
    for i in range(n):
        for j in range(i, n):
            if i == j or rng.random() < 0.3:
                v = rng.randint(-39999, 39999) / 4 if quarter_units else \
                    rng.gauss(0, 1) * 10 ** rng.uniform(-3, 6)
                a[i, j] = a[j, i] = v if v != 0 else 0.25
    return a


def write_text(path, lines, final_newline=True):
    path.write_text("\n".join(lines) + ("\n" if final_newline else ""))
    return path


def build_punch(tmp_path, layout, seed=1, with_grids=True, **kw):
    rng = random.Random(seed)
    exact = layout != "large"
    K = random_symmetric(rng, len(DOFS), quarter_units=exact)
    M = random_symmetric(rng, len(DOFS), quarter_units=exact)
    lines = ["$ punch written by the kryflex test in Nastran's DMIG layout"]
    lines += dmig_lines("KAAX", K, DOFS, layout, rng, **kw)
    lines += dmig_lines("MAAX", M, DOFS, layout, rng, **kw)
    if with_grids:
        lines += grid_lines(COORDS)
    return write_text(tmp_path / f"model_{layout}.pch", lines), K, M


def files_in(folder):
    return sorted(os.listdir(folder)) if os.path.isdir(folder) else []


def expected_nodes():
    return [(g, *COORDS[g], GRIDS[g]) for g in sorted(GRIDS)]


# ---------------------------------------------------------------- Nastran reader

@pytest.mark.parametrize("layout", ["small", "small-blank", "free"])
def test_dmig_exact_layouts_reproduce_matrices(tmp_path, layout):
    path, K, M = build_punch(tmp_path, layout, shuffle_columns=(layout == "free"))
    result = dmig.read_dmig(path, names=("KAAX", "MAAX"))
    for name, A in (("KAAX", K), ("MAAX", M)):
        matrix, dofs = result[name]
        assert dofs == DOFS
        np.testing.assert_array_equal(matrix.toarray(), A)


def test_dmig_large_field_within_printed_precision(tmp_path):
    path, K, M = build_punch(tmp_path, "large")
    result = dmig.read_dmig(path)
    for name, A in (("KAAX", K), ("MAAX", M)):
        matrix, dofs = result[name]
        assert dofs == DOFS
        got = matrix.toarray()
        assert np.array_equal(got != 0, A != 0)
        assert np.all(np.abs(got - A) <= LARGE_FIELD_RTOL * np.abs(A))


@pytest.mark.parametrize("triangle,ifo", [("lower", 6), ("upper", 1)])
def test_dmig_lower_triangle_and_square_storage(tmp_path, triangle, ifo):
    path, K, M = build_punch(tmp_path, "small", seed=3, triangle=triangle, ifo=ifo)
    result = dmig.read_dmig(path)
    np.testing.assert_array_equal(result["KAAX"][0].toarray(), K)
    np.testing.assert_array_equal(result["MAAX"][0].toarray(), M)


def test_dmig_missing_component_is_left_out(tmp_path):
    # pyNastran route: a component no matrix uses is no dof (it was a zero row and column before, which left it
    # undetermined); the node then has the Nastran component string of what it has (dofs.md, nodes file).
    rng = random.Random(5)
    kept = [d for d in DOFS if d != (41, 6)]
    K = random_symmetric(rng, len(kept))
    M = random_symmetric(rng, len(kept))
    lines = dmig_lines("KAAX", K, kept, "small", rng) + dmig_lines("MAAX", M, kept, "small", rng)
    path = write_text(tmp_path / "partial.pch", lines)
    result = dmig.read_dmig(path)
    K_read, dofs = result["KAAX"]
    assert dofs == kept
    np.testing.assert_array_equal(K_read.toarray(), K)
    groups = dmig.group_dofs(dofs)
    assert [(g, dmig.node_dofs(c)) for g, c in groups] == \
        [(g, "c12345" if g == 41 else GRIDS[g]) for g in sorted(GRIDS)]


def test_dmig_scalar_point(tmp_path):
    lines = small_card("DMIG", ["KAAX", "0", "6", "2", "0", "", "", "2"]) + \
        small_card("DMIG", ["KAAX", "9", "0", "", "9", "0", "1.0", ""]) + \
        small_card("DMIG", ["KAAX", "9", "", "", "4", "0", "2.0", ""]) + \
        small_card("DMIG", ["KAAX", "4", "", "", "4", "", "3.0", ""])
    path = write_text(tmp_path / "spoint.pch", lines)
    K, dofs = dmig.read_dmig(path, names=("KAAX",))["KAAX"]
    assert dofs == [(4, 0), (9, 0)]
    np.testing.assert_array_equal(K.toarray(), [[3.0, 2.0], [2.0, 1.0]])
    assert dmig.node_dofs([0]) == "s"
    bad = write_text(tmp_path / "grid_spoint.pch", lines + small_card("GRID", ["9", "", "1.0", "2.0", "3.0"]))
    with pytest.raises(ConversionError, match="point 9 with component 0 .* defines GRID 9"):
        dmig.read_dmig(bad, names=("KAAX",))


def test_dmig_conflicting_triangles_are_an_error(tmp_path):
    lines = small_card("DMIG", ["KAAX", "0", "6", "2", "0", "", "", "2"]) + \
        small_card("DMIG", ["KAAX", "1", "1", "", "1", "1", "2.0", "", "1", "2", "1.0", ""]) + \
        small_card("DMIG", ["KAAX", "1", "2", "", "1", "1", "1.5", "", "1", "2", "3.0", ""]) + \
        small_card("DMIG", ["KAAX", "1", "3", "", "1", "3", "4.0", ""])
    path = write_text(tmp_path / "clash.pch", lines)
    with pytest.raises(ConversionError, match=r"row 1-ux, column 1-uy"):
        dmig.read_dmig(path, names=("KAAX",))


def test_read_grids_all_layouts_and_local_systems(tmp_path):
    path = write_text(tmp_path / "grids.bdf", ["BEGIN BULK"] + grid_lines(COORDS) + ["ENDDATA"])
    grids = dmig.read_grids(path)
    for gid, xyz in COORDS.items():
        # large-field coordinates carry 10 significant digits
        assert grids[gid] == pytest.approx(xyz, rel=LARGE_FIELD_RTOL, abs=0)
    # coordinate systems are read now (test_nastran_import.py); one that no CORD card defines is an error
    local = write_text(tmp_path / "local.bdf", small_card("GRID", ["5", "3", "1.0", "2.0", "3.0"]))
    with pytest.raises(ConversionError, match="GRID 5 gives CP=3, but no CORD card defines coordinate system 3"):
        dmig.read_grids(local)
    with pytest.raises(ConversionError, match=r"grid\(s\) used by the matrices have no GRID card .* \(6\)"):
        dmig.read_grids(local, ids=[6])
    disp = write_text(tmp_path / "disp.bdf", small_card("GRID", ["5", "", "1.0", "2.0", "3.0", "2"]))
    with pytest.raises(ConversionError, match="CD=2"):
        dmig.read_grids(disp)


# ---------------------------------------------------------------- convert: round trips

def load_petsc(path):
    from petsc4py import PETSc

    viewer = PETSc.Viewer().createBinary(str(path), "r", comm=PETSc.COMM_SELF)
    mat = PETSc.Mat().create(comm=PETSc.COMM_SELF)
    mat.setType("aij")
    mat.load(viewer)
    indptr, indices, data = mat.getValuesCSR()
    A = sp.csr_matrix((data.copy(), indices.copy(), indptr.copy()), shape=mat.getSize())
    mat.destroy()
    viewer.destroy()
    return A.toarray()


def read_body(out, name, fmt):
    import yaml

    entry = yaml.safe_load((out / f"{name}.body.yaml").read_text())["bodies"][name]
    load = load_petsc if fmt == "petsc" else (lambda p: scipy.io.mmread(str(p)).toarray())
    return (load(out / entry["mass"]), load(out / entry["stiffness"]),
            read_nodes(out / entry["nodes"]), entry["interfaces"])


@pytest.mark.parametrize("fmt", ["petsc", "mtx"])
def test_convert_punch_writes_body(tmp_path, fmt):
    path, K, M = build_punch(tmp_path, "small")
    out = tmp_path / "out"
    body = convert(str(path), str(out), "rotor", fmt, {"bearing": 105, "tip": 2000})
    assert body.size == len(DOFS) and body.node_count == len(GRIDS)
    assert files_in(out) == sorted([f"rotor_M.{fmt}", f"rotor_K.{fmt}", "rotor_nodes.txt", "rotor.body.yaml"])
    M_out, K_out, nodes, interfaces = read_body(out, "rotor", fmt)
    np.testing.assert_array_equal(M_out, M)
    np.testing.assert_array_equal(K_out, K)
    assert interfaces == {"bearing": 105, "tip": 2000}
    got = {n[0]: n for n in nodes}
    for gid, xyz in COORDS.items():   # grids 0, 3, 6: large field (10 digits); others exact
        assert got[gid][1:4] == pytest.approx(xyz, rel=LARGE_FIELD_RTOL, abs=0)
        assert got[gid][4] == GRIDS[gid]


def test_convert_punch_with_separate_grid_file_and_without_grids(tmp_path):
    path, K, M = build_punch(tmp_path, "large", with_grids=False)
    bulk = write_text(tmp_path / "model.bdf",
                      ["SOL 103", "CEND", "BEGIN BULK"] + grid_lines(COORDS, ("free",)) + ["ENDDATA"])
    convert(path, tmp_path / "a", "boom", "mtx", {"root": 7}, grids=[str(bulk)])
    _, _, nodes, _ = read_body(tmp_path / "a", "boom", "mtx")
    assert nodes == expected_nodes()
    # without GRID cards: an error, never nodes silently at (0, 0, 0)
    with pytest.raises(ConversionError, match="have no GRID card"):
        convert(path, tmp_path / "b", "boom", "mtx", {"root": 7})
    assert files_in(tmp_path / "b") == []


def test_convert_npz_dense_and_sparse(tmp_path):
    rng = random.Random(11)
    n = len(DOFS)
    K = random_symmetric(rng, n, quarter_units=False)
    M = random_symmetric(rng, n, quarter_units=False)
    table = np.array(expected_nodes(), dtype=float)
    Ks, Mc = sp.csr_matrix(K), sp.csc_matrix(M)
    np.savez(tmp_path / "sparse.npz", K_data=Ks.data, K_indices=Ks.indices, K_indptr=Ks.indptr,
             K_shape=Ks.shape, M_data=Mc.data, M_indices=Mc.indices, M_indptr=Mc.indptr,
             M_shape=Mc.shape, M_format="csc", nodes=table)
    np.savez(tmp_path / "dense.npz", K=K, M=M, nodes=table)
    for source in ("sparse.npz", "dense.npz"):
        out = tmp_path / source.replace(".npz", "")
        convert(str(tmp_path / source), str(out), "boom", "mtx", {"root": 40})
        M_out, K_out, nodes, _ = read_body(out, "boom", "mtx")
        np.testing.assert_array_equal(M_out, M)   # 17 significant digits: exact
        np.testing.assert_array_equal(K_out, K)
        assert nodes == expected_nodes()


def test_convert_matrix_market_round_trip(tmp_path):
    rng = random.Random(12)
    n = len(DOFS)
    K = random_symmetric(rng, n, quarter_units=False)
    M = random_symmetric(rng, n, quarter_units=False)
    scipy.io.mmwrite(str(tmp_path / "K.mtx"), sp.coo_matrix(K), symmetry="symmetric", precision=17)
    scipy.io.mmwrite(str(tmp_path / "M.mtx"), sp.coo_matrix(M), precision=17)   # general storage
    nodes_path = tmp_path / "nodes.txt"
    nodes_path.write_text("# id x y z ndof\n" + "".join(
        f"{g} {x!r} {y!r} {z!r} {d}  # node {g}\n" for g, x, y, z, d in expected_nodes()))
    inputs = {"mass": str(tmp_path / "M.mtx"), "stiffness": str(tmp_path / "K.mtx"), "nodes": str(nodes_path)}
    convert(inputs, str(tmp_path / "mtx"), "x", "petsc", {"a": 12})
    M_out, K_out, nodes, _ = read_body(tmp_path / "mtx", "x", "petsc")
    np.testing.assert_array_equal(M_out, M)
    np.testing.assert_array_equal(K_out, K)
    assert nodes == expected_nodes()
    # and back again from the PETSc files
    again = {"mass": str(tmp_path / "mtx" / "x_M.petsc"), "stiffness": str(tmp_path / "mtx" / "x_K.petsc"),
             "nodes": str(tmp_path / "mtx" / "x_nodes.txt")}
    convert(again, str(tmp_path / "back"), "x", "mtx", {"a": 12})
    M_back, K_back, _, _ = read_body(tmp_path / "back", "x", "mtx")
    np.testing.assert_array_equal(M_back, M)
    np.testing.assert_array_equal(K_back, K)


# ---------------------------------------------------------------- convert: bad inputs

def test_missing_input_file(tmp_path):
    with pytest.raises(ConversionError, match="nope.pch does not exist"):
        convert(str(tmp_path / "nope.pch"), str(tmp_path / "out"), "x", "petsc", {})
    assert files_in(tmp_path) == []


def test_truncated_punch_files(tmp_path):
    path, _, _ = build_punch(tmp_path, "large", with_grids=False)
    text = path.read_text()
    lines = text.splitlines(keepends=True)
    m_header = next(k for k, line in enumerate(lines) if line.startswith("DMIG    MAAX"))
    last_column = max(k for k, line in enumerate(lines) if line.startswith("DMIG*   MAAX"))
    cuts = {
        "inside KAAX, at a line end": "".join(lines[:m_header // 2]),
        "inside KAAX, mid-line": "".join(lines[:m_header // 2]) + lines[m_header // 2][:30],
        "inside MAAX, mid-value": "".join(lines[:-3]) + lines[-3][:50],
        "after a column card without entries": "".join(lines[:last_column + 1]),
        "before MAAX": "".join(lines[:m_header]),
    }
    for why, cut in cuts.items():
        bad = tmp_path / "cut.pch"
        bad.write_text(cut)
        out = tmp_path / "out"
        with pytest.raises(ConversionError, match="cut.pch") as info:
            convert(str(bad), str(out), "x", "petsc", {})
        assert any(w in str(info.value) for w in ("truncated", "incomplete", "cut off")), why
        assert files_in(out) == [], why
    assert sorted(os.listdir(tmp_path)) == ["cut.pch", path.name]


def test_truncation_at_a_column_boundary_of_the_last_matrix_warns(tmp_path):
    # Indistinguishable from Nastran leaving out all-zero columns, so only a warning: NCOL says so.
    path, _, _ = build_punch(tmp_path, "large", with_grids=False)
    lines = path.read_text().splitlines(keepends=True)
    last_column = max(k for k, line in enumerate(lines) if line.startswith("DMIG*   MAAX"))
    path.write_text("".join(lines[:last_column]))
    with pytest.warns(ConversionWarning, match="NCOL=39"):
        dmig.read_dmig(path)


def test_non_symmetric_matrix(tmp_path):
    rng = random.Random(13)
    K = random_symmetric(rng, len(DOFS))
    K[3, 5] += 1.0
    np.savez(tmp_path / "bad.npz", K=K, M=np.eye(len(DOFS)), nodes=np.array(expected_nodes()))
    with pytest.raises(ConversionError, match=r"stiffness matrix K of body 'x' \(from 'K' of .*bad.npz\) "
                                              r"is not symmetric.*row [35], column [35]"):
        convert(str(tmp_path / "bad.npz"), str(tmp_path / "out"), "x", "petsc", {})
    assert files_in(tmp_path / "out") == []


def test_size_mismatch_with_nodes(tmp_path):
    n = len(DOFS)
    scipy.io.mmwrite(str(tmp_path / "K.mtx"), sp.identity(n, format="coo"))
    scipy.io.mmwrite(str(tmp_path / "M.mtx"), sp.identity(n, format="coo"))
    (tmp_path / "nodes.txt").write_text("1 0 0 0 6\n2 0 0 0 3\n")
    inputs = {"mass": str(tmp_path / "M.mtx"), "stiffness": str(tmp_path / "K.mtx"),
              "nodes": str(tmp_path / "nodes.txt")}
    with pytest.raises(ConversionError, match=rf"M.mtx\) is {n} x {n} but the nodes .*nodes.txt\) hold 9 dofs"):
        convert(inputs, str(tmp_path / "out"), "x", "mtx", {})
    assert files_in(tmp_path / "out") == []


def test_unknown_or_translation_only_interface_node(tmp_path):
    path, _, _ = build_punch(tmp_path, "small")
    with pytest.raises(ConversionError, match="interface 'bearing' names node 106, which is not a node"):
        convert(str(path), str(tmp_path / "out"), "rotor", "petsc", {"bearing": 106})
    with pytest.raises(ConversionError, match="interface 'pin' node 13 has dofs 3"):
        convert(str(path), str(tmp_path / "out"), "rotor", "petsc", {"pin": 13})
    assert files_in(tmp_path / "out") == []


def test_failure_while_writing_leaves_nothing(tmp_path, monkeypatch):
    def broken(path, nodes, name):
        with open(path, "w") as handle:
            handle.write("1 0 0")   # half a file, then the disk "fills up"
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(bodyfiles, "_write_nodes", broken)
    out = tmp_path / "out"
    with pytest.raises(ConversionError, match="No space left"):
        write_body(str(out), "x", sp.identity(6), sp.identity(6), [(1, 0, 0, 0, 6)], {"a": 1})
    assert not out.exists()   # the folder it created is gone too
    out.mkdir()
    (out / "keep.txt").write_text("unrelated")
    with pytest.raises(ConversionError):
        write_body(str(out), "x", sp.identity(6), sp.identity(6), [(1, 0, 0, 0, 6)], {"a": 1})
    assert files_in(out) == ["keep.txt"]


def test_read_nodes_errors_name_the_line(tmp_path):
    cases = {
        "1 0 0 0 6\n2 0 0 6\n": "line 2: expected 5 fields",
        "1 0 0 0 6\n\n# c\n1 1 1 1 6\n": "line 4: node id 1 already defined on line 1",
        "1 0 zero 0 6\n": "line 1: coordinate y = 'zero' is not a number",
        "1 0 0 0 4\n": "line 1: dofs = '4'",
        "1 0 0 0 c31\n": "line 1: dofs = 'c31'",
        "a 0 0 0 6\n": "line 1: node id 'a' is not an integer",
        "# only a comment\n": "holds no node lines",
    }
    for text, message in cases.items():
        path = tmp_path / "nodes.txt"
        path.write_text(text)
        with pytest.raises(ConversionError, match=message):
            read_nodes(path)


# ---------------------------------------------------------------- command line

def test_main_success_and_exit_codes(tmp_path, capsys):
    path, K, M = build_punch(tmp_path, "small")
    out = tmp_path / "out"
    code = main([str(path), "--name", "rotor", "--interface", "bearing=101", "-o", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and "kryflex: error: body 'rotor': interface 'bearing' names node 101" in err
    assert files_in(out) == []

    code = main([str(path), "--name", "rotor", "--interface", "bearing=105", "-o", str(out), "--format", "mtx"])
    assert code == 0
    M_out, K_out, _, interfaces = read_body(out, "rotor", "mtx")
    np.testing.assert_array_equal(K_out, K)
    assert interfaces == {"bearing": 105}
    assert "rotor.body.yaml" in capsys.readouterr().out

    usage_errors = [
        [str(path), "--name", "r", "--interface", "bearing"],                       # no '='
        [str(path), "--name", "r", "--mass", "M.mtx"],                              # both kinds of input
        ["--name", "r", "--mass", "M.mtx", "--stiffness", "K.mtx"],                 # no nodes
        [str(path), "--name", "r", "--format", "hdf5"],                             # argparse choice
        [str(path)],                                                                # no --name
        [str(path), "--name", "r", "--nodes", "n.txt"],                             # nodes for a punch
    ]
    for argv in usage_errors:
        assert main(argv + ["-o", str(tmp_path / "never")]) == 2, argv
        err = capsys.readouterr().err
        assert err.count("kryflex: error:") == 1 and err.startswith("usage: kryflex convert"), argv
    assert not (tmp_path / "never").exists()

    assert main([str(tmp_path / "missing.pch"), "--name", "r", "-o", str(out)]) == 2
    assert "missing.pch does not exist" in capsys.readouterr().err


def test_main_reports_warnings(tmp_path, capsys):
    path, _, _ = build_punch(tmp_path, "free")
    with open(path, "a") as handle:
        handle.write("PARAM,WTMASS,0.5\n")
    assert main([str(path), "--name", "r", "-o", str(tmp_path / "o")]) == 0
    assert "kryflex convert: warning: PARAM,WTMASS=0.5" in capsys.readouterr().err


def test_nodes_dofs_field(tmp_path):
    # dofs.md: 6, 3, c<components ascending> or s; one spelling per set (c123456 is 6, c123 is 3)
    path = tmp_path / "nodes.txt"
    path.write_text("1 0 0 0 6\n2 1 0 0 c345\n3 2 0 0 s\n4 3 0 0 C123456\n5 4 0 0 c123\n6 5 0 0 3\n")
    nodes = read_nodes(path)
    assert [n[4] for n in nodes] == [6, "c345", "s", 6, 3, 3]
    assert [bodyfiles.dof_count(n[4]) for n in nodes] == [6, 3, 1, 6, 3, 3]
    for bad in ("c", "c7", "c33", "c54", "S1", "345", "c0"):
        path.write_text(f"1 0 0 0 {bad}\n")
        with pytest.raises(ConversionError, match=f"dofs = '{bad}'"):
            read_nodes(path)
    # written as read, and the body's size counts the components
    out = tmp_path / "out"
    write_body(str(out), "x", sp.identity(7), sp.identity(7), [(1, 0, 0, 0, "c345"), (2, 1, 0, 0, "s"),
                                                              (3, 2, 0, 0, 3)], {})
    assert [n[4] for n in read_nodes(out / "x_nodes.txt")] == ["c345", "s", 3]
