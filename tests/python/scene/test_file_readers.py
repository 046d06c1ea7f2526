"""The file readers say what is wrong and where, and accept what real exporters write.

Body matrices (src/body/load.c, through kryflex.load_scene on a copy of meshes/galileo with the rotor's stiffness
replaced, and through the binding's loader kryflex._core.load_matrix):
- Matrix Market files the way exporters write them (upper-case headers, CRLF line ends, a byte order mark, comments
  and blank lines anywhere, tabs, long lines, subnormal values, Fortran 'D' exponents, integer fields, one triangle
  either side) load and equal scipy.io.mmread's matrix;
- bad ones (pattern/complex fields, hermitian/skew-symmetric, dense 'array', extra or missing entries, cut lines,
  NaN/Inf, both triangles of a 'symmetric' file, sizes beyond PetscInt, overflowing numbers, indices outside the
  matrix) are refused with a message naming the scene entry, the file, the entry and line, and the fix;
- damaged PETSc binary files (column indices outside the matrix or out of order, bad row lengths, cut files,
  little-endian files, NaN) are refused before MatLoad can trust them;
- under mpiexec -n 2 both ranks refuse a bad file with the same message, and neither hangs.
Reduced models (src/io/model_hdf5.c, through kryflex.ReducedModel.load and `kryflex reassemble`): a file edited with
h5py keeps valid checksums (every dataset is chunked with a fletcher32 checksum per chunk, which HDF5 recomputes
when h5py writes), so only the reader's consistency checks can find the edit: each is a kryflex.ModelFileError
(exit 5 from the command) naming the dataset or attribute and the problem.
"""
import os
import re
import shutil
import struct
import subprocess
import sys
import textwrap

import h5py
import numpy as np
import pytest
import scipy.io
import scipy.sparse as sp

import kryflex
from kryflex import _core

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "support"))
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
ROOT = run_env.ROOT
GALILEO_DIR = os.path.join(ROOT, "meshes", "galileo")
COMMAND = run_env.KRYFLEX
ENV = dict(run_env.ENV, PYTHONPATH=run_env.PACKAGE + os.pathsep + os.environ.get("PYTHONPATH", ""))
TIMEOUT = 120            # seconds per command: a hang is a failure, not a stuck test run
EXIT_MODEL = 5

sys.path.insert(0, os.path.join(ROOT, "meshes"))
import frames  # noqa: E402  (the scene generators' PETSc binary writer)


# ------------------------------------------------------------------ writing matrix files as exporters do

def rotor_K():
    """A sparse sample matrix: the rotor stiffness of Galileo's stick model (meshes/galileo/generate.py build_rotor,
    109 entries in one triangle; the committed, fitted rotor K is dense), the counts the messages below name."""
    import importlib.util
    spec = importlib.util.spec_from_file_location("galileo_generate", os.path.join(GALILEO_DIR, "generate.py"))
    gen = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(gen)
    return gen.build_rotor()[1]


def mtx_text(A, field="real", symmetry="symmetric", banner="%%MatrixMarket matrix coordinate", comments=(),
             triangle="lower", fmt="%.17g", nnz=None, extra=(), newline="\n", size=None):
    """A coordinate Matrix Market file of the dense A as text: the banner, comment lines, the size line, one entry per
    line (one triangle for 'symmetric'), then the lines of extra; nnz and size override the size line."""
    rows = []
    n = A.shape[0]
    for j in range(n):
        for i in range(n):
            if A[i, j] == 0:
                continue
            if symmetry == "symmetric" and (i < j if triangle == "lower" else i > j):
                continue
            value = ("%d" % A[i, j]) if field == "integer" else (fmt % A[i, j])
            rows.append("%d %d %s" % (i + 1, j + 1, value))
    lines = ["%s %s %s" % (banner, field, symmetry)] + ["%" + c for c in comments]
    lines.append(size if size is not None else "%d %d %d" % (n, n, len(rows) if nnz is None else nnz))
    lines += rows + list(extra)
    return newline.join(lines) + newline


def write(path, text):
    with open(path, "wb") as f:
        f.write(text.encode() if isinstance(text, str) else text)


def entry_line(text, k):
    """The line number (1-based) of entry k (1-based) of a file written by mtx_text without blank lines."""
    lines = text.splitlines()
    data = [i for i, l in enumerate(lines) if l.strip() and not l.lstrip().startswith("%")]
    return data[k] + 1          # data[0] is the size line


def dense(mat):
    return mat.convert("dense").getDenseArray().copy()


# ------------------------------------------------------------------ bad Matrix Market files (rotor stiffness)

def with_entry(A, value):
    """mtx text of A with entry 5 replaced by the text value; returns (text, its line)."""
    text = mtx_text(A)
    lines = text.splitlines()
    at = entry_line(text, 5)
    fields = lines[at - 1].split()
    lines[at - 1] = "%s %s %s" % (fields[0], fields[1], value)
    return "\n".join(lines) + "\n", at


def bad_pattern(A):
    return mtx_text(A, field="pattern"), ["field 'pattern'"], r"export it with field 'real'"


def bad_complex(A):
    text = mtx_text(A, field="complex", symmetry="hermitian")
    return text, ["field 'complex'"], r"export it with field 'real'"


def bad_hermitian(A):
    return mtx_text(A, symmetry="hermitian"), ["symmetry 'hermitian'"], r"'symmetric' \(one triangle\) or 'general'"


def bad_skew(A):
    return mtx_text(A, symmetry="skew-symmetric"), ["symmetry 'skew-symmetric'"], r"'symmetric' .* or 'general'"


def bad_array(A):
    body = "\n".join("%.17g" % x for x in A.T.ravel())
    return ("%%%%MatrixMarket matrix array real general\n21 21\n%s\n" % body, ["format 'array'"],
            r"write it as coordinate")


def bad_extra_entries(A):
    text = mtx_text(A, extra=["21 1 0.5", "21 2 0.5"])
    return text, ["holds more than the 109 entries its size line declares", "line %d" % (len(text.splitlines()) - 1)], \
        r"fix the entry count in the size line or re-export"


def bad_nan(A):
    text, line = with_entry(A, "NaN")
    return text, ["entry 5 (line %d)" % line, "'NaN'", "not a finite number"], r"re-export"


def bad_inf(A):
    text, line = with_entry(A, "-Infinity")
    return text, ["entry 5 (line %d)" % line, "'-Infinity'", "not a finite number"], r"re-export"


def bad_overflowing_value(A):
    text, line = with_entry(A, "1e999")
    return text, ["entry 5 (line %d)" % line, "'1e999'", "not a finite number"], r"re-export"


def bad_nan_crlf(A):
    text, line = with_entry(A, "nan")
    return text.replace("\n", "\r\n"), ["entry 5 (line %d)" % line, "not a finite number"], r"re-export"


def bad_both_triangles(A):
    # the whole matrix under a 'symmetric' header: mirrored again it would double every off-diagonal entry
    text = mtx_text(A, symmetry="general").replace("general", "symmetric", 1)
    return text, ["declares 'symmetric' but holds both triangles", "(2, 1) at line", "(1, 2) at line"], \
        r"write one triangle or declare it 'general'"


def bad_cut_inside_line(A):
    text = mtx_text(A)
    cut = text.index("\n", len(text) // 2) + 4
    return text[:cut], ["is truncated", "ends inside entry"], r"re-export the matrix"


def bad_cut_after_line(A):
    text = mtx_text(A)
    cut = text.index("\n", len(text) // 2) + 1
    return text[:cut], ["is truncated", "of the 109 entries its size line declares"], r"re-export the matrix"


def bad_size_beyond_petscint(A):
    return mtx_text(A, size="3000000000 3000000000 3000000000"), ["3000000000 rows", "32 bits"], \
        r"--with-64-bit-indices"


def bad_size_overflow(A):
    return mtx_text(A, size="21 21 99999999999999999999"), ["too large for a 64-bit integer", "line 2"], \
        r"re-export the matrix"


def bad_more_entries_than_places(A):
    return mtx_text(A, nnz=400), ["declares 400 entries", "231 places"], r"re-export the matrix"


def bad_not_square(A):
    return mtx_text(A, size="21 20 109"), ["square", "21 x 20"], r"square and non-empty"


def bad_outside(A):
    return mtx_text(A, extra=["22 1 1.0"], nnz=110), ["entry 110", "(22, 1)", "outside the 21 x 21 matrix"], \
        r"count from 1.*re-export"


def bad_row_zero(A):
    text = mtx_text(A)
    return text.replace("\n1 1 ", "\n0 1 ", 1), ["entry 1 (line 3)", "(0, 1)", "outside"], r"count from 1"


def bad_not_a_number(A):
    text, line = with_entry(A, "1.0.0")
    return text, ["entry 5 (line %d: " % line, "value that is not a number"], r"re-export.*row column value"


def bad_four_fields(A):
    text, line = with_entry(A, "1.0 0.0")
    return text, ["entry 5 (line %d" % line, "more than three fields"], r"re-export"


def bad_header(A):
    return mtx_text(A).replace("%%MatrixMarket", "%MatrixMarket", 1), ["line 1", "not a Matrix Market header"], \
        r"re-export the matrix as Matrix Market"


def bad_empty(A):
    return "", ["is empty"], r"re-export"


def bad_no_size_line(A):
    return "%%MatrixMarket matrix coordinate real symmetric\n% just a comment\n", ["no size line"], \
        r"truncated; re-export"


BAD_MTX = {name[4:]: f for name, f in dict(globals()).items() if name.startswith("bad_")}


def scene_with_rotor_K(tmp_path, data, name="rotor_K.mtx"):
    """A copy of meshes/galileo whose rotor stiffness is the file name holding data (text or bytes)."""
    folder = os.path.join(str(tmp_path), "scene")
    shutil.copytree(GALILEO_DIR, folder)
    write(os.path.join(folder, name), data)
    scene = os.path.join(folder, "galileo.yaml")
    if name != "rotor_K.mtx":
        with open(scene) as f:
            text = f.read()
        with open(scene, "w") as f:
            f.write(text.replace("stiffness: rotor_K.mtx", "stiffness: " + name))
    return scene


def check_message(msg, mentions, fix):
    for m in mentions:
        assert m in msg, f"the message should say '{m}': {msg!r}"
    assert re.search(fix, msg, re.IGNORECASE | re.DOTALL), f"the message should say what to do ({fix!r}): {msg!r}"


@pytest.mark.parametrize("case", sorted(BAD_MTX))
def test_bad_matrix_market_refused(tmp_path, case):
    data, mentions, fix = BAD_MTX[case](rotor_K())
    scene = scene_with_rotor_K(tmp_path, data)
    with pytest.raises(kryflex.SceneError) as err:
        kryflex.load_scene(scene)
    print(f"{case}: {err.value}")
    check_message(str(err.value), ["galileo.yaml: bodies.rotor.stiffness", "rotor_K.mtx"] + mentions, fix)


# ------------------------------------------------------------------ good Matrix Market files: scipy's matrix

def spd(n=7, integer=False, seed=3):
    """A small symmetric positive definite matrix with zeros (integer entries if asked)."""
    rng = np.random.default_rng(seed)
    A = np.round(rng.standard_normal((n, n)) * 4)
    A[np.abs(A) < 3] = 0
    A = A + A.T + np.diag(np.full(n, 40.0))
    return A if integer else A * 1.234567890123


def good_uppercase_header():
    return mtx_text(spd(), banner="%%MATRIXMARKET MATRIX COORDINATE").replace("real symmetric", "REAL Symmetric")


def good_mixed_case_header():
    return mtx_text(spd(), banner="%%MatrixMarket Matrix Coordinate", symmetry="General").replace("real", "Real")


def good_crlf():
    return mtx_text(spd(), comments=["written on Windows"], newline="\r\n")


def good_subnormal_values():
    A = spd()
    A[0, 1] = A[1, 0] = 1e-310          # subnormal: finite, kept as is
    A[2, 3] = A[3, 2] = -4.9e-324
    return mtx_text(A, fmt="%.17g")


def good_integer_field():
    return mtx_text(spd(integer=True), field="integer")


def good_comments_and_blank_lines():
    text = mtx_text(spd(), comments=[" exported by a FE code", "", " units: SI"])
    lines = text.splitlines()
    lines.insert(5, "")
    lines.insert(8, "% a comment between entries")
    lines.insert(9, "   ")
    return "\n".join(lines) + "\n\n% trailing comment\n\n"


def good_long_lines():
    text = mtx_text(spd(), comments=[" " + "x" * 5000], fmt="%.40e")
    return text


def good_tabs_and_spaces():
    return mtx_text(spd()).replace(" ", "\t").replace("%%MatrixMarket\tmatrix\tcoordinate\treal\tsymmetric",
                                                          "%%MatrixMarket  matrix coordinate   real symmetric  ")


def good_upper_triangle():
    return mtx_text(spd(), triangle="upper")


def good_general():
    return mtx_text(spd(), symmetry="general")


def good_no_final_newline():
    return mtx_text(spd()).rstrip("\n")


def good_general_duplicates_summed():
    A = spd()
    return mtx_text(A, symmetry="general", extra=["1 1 1.5", "2 3 -0.25"], nnz=np.count_nonzero(A) + 2)


GOOD_MTX = {name[5:]: f for name, f in dict(globals()).items() if name.startswith("good_")}


@pytest.mark.parametrize("case", sorted(GOOD_MTX))
def test_good_matrix_market_equals_scipy(tmp_path, case):
    text = GOOD_MTX[case]()
    path = os.path.join(str(tmp_path), "A.mtx")
    write(path, text)
    # scipy reads the banner word '%%MatrixMarket' case-sensitively (the specification does not): its copy has it so
    first, rest = text.split("\n", 1)
    ref = os.path.join(str(tmp_path), "ref.mtx")
    write(ref, re.sub(r"(?i)^%%matrixmarket", "%%MatrixMarket", first) + "\n" + rest)
    expected = scipy.io.mmread(ref)
    expected = expected.toarray() if sp.issparse(expected) else np.asarray(expected)
    got = dense(_core.load_matrix(path))
    np.testing.assert_array_equal(got, expected)


def test_fortran_exponents_and_byte_order_mark(tmp_path):
    """What scipy does not read: 1.5D+03 (Fortran) and a UTF-8 byte order mark (Windows editors)."""
    A = spd()
    path = os.path.join(str(tmp_path), "A.mtx")
    write(path, "\ufeff" + mtx_text(A, fmt="%.17e").replace("e+", "D+").replace("e-", "d-"))
    np.testing.assert_array_equal(dense(_core.load_matrix(path)), A)


def test_scene_loads_crlf_uppercase_rotor(tmp_path):
    """The rotor's stiffness re-written as a Windows exporter would (CRLF, upper case, comments): the same scene."""
    A = rotor_K()
    text = mtx_text(A, banner="%%MatrixMarket MATRIX Coordinate", comments=[" exported", ""], newline="\r\n")
    scene = kryflex.load_scene(scene_with_rotor_K(tmp_path, text.replace("real symmetric", "Real Symmetric")))
    ref = kryflex.load_scene(os.path.join(GALILEO_DIR, "galileo.yaml"))
    assert scene.cscene.fingerprint() == ref.cscene.fingerprint()


def test_petsc_binary_equals_matrix_market(tmp_path):
    A = rotor_K()
    path = os.path.join(str(tmp_path), "K.petsc")
    frames.write_petsc_binary(path, A)
    np.testing.assert_array_equal(dense(_core.load_matrix(path)), A)


# ------------------------------------------------------------------ bad PETSc binary files

def petsc_bytes(A):
    """The bytes of A as a PETSc binary AIJ file (big-endian 32-bit ints: header, row lengths, columns, values)."""
    C = sp.csr_matrix(A)
    C.sort_indices()
    n = A.shape[0]
    return bytearray(struct.pack(">4i", 1211216, n, n, C.nnz) + np.diff(C.indptr).astype(">i4").tobytes()
                     + C.indices.astype(">i4").tobytes() + C.data.astype(">f8").tobytes())


def cols_at(n):
    return 16 + 4 * n


def binary_column_minus_one(data, n, nnz):
    data[cols_at(n):cols_at(n) + 4] = struct.pack(">i", -1)
    return ["row 1 lists column 0, outside the 21 columns"], r"corrupt; re-export"


def binary_column_too_large(data, n, nnz):
    at = cols_at(n) + 4 * (nnz - 1)
    data[at:at + 4] = struct.pack(">i", n)
    return ["row 21 lists column 22, outside the 21 columns"], r"corrupt; re-export"


def binary_columns_out_of_order(data, n, nnz):
    a, b = data[cols_at(n):cols_at(n) + 4], data[cols_at(n) + 4:cols_at(n) + 8]
    data[cols_at(n):cols_at(n) + 8] = b + a
    return ["row 1 lists column 1 after column", "must increase"], r"corrupt; re-export"


def binary_negative_row_length(data, n, nnz):
    data[16:20] = struct.pack(">i", -3)
    return ["row 1 has -3 entries"], r"corrupt; re-export"


def binary_header_count(data, n, nnz):
    data[12:16] = struct.pack(">i", nnz + 1)
    return ["its rows hold %d entries, its header says %d" % (nnz, nnz + 1)], r"corrupt; re-export"


def binary_truncated_half(data, n, nnz):
    del data[len(data) // 2:]
    return ["is truncated"], r"re-export the matrix"


def binary_truncated_values(data, n, nnz):
    del data[-8:]
    return ["is truncated", "bytes"], r"re-export the matrix"


def binary_header_only(data, n, nnz):
    del data[10:]
    return ["too short", "for a PETSc binary matrix header"], r"truncated or not a PETSc binary matrix; re-export"


def binary_little_endian(data, n, nnz):
    data[0:16] = struct.pack("<4i", 1211216, n, n, nnz)
    return ["not a PETSc binary matrix", "little-endian"], r"MatView|Matrix Market"


def binary_nan(data, n, nnz):
    at = len(data) - 8 * nnz + 8 * 2           # the third value: row 1's third entry
    data[at:at + 8] = struct.pack(">d", float("nan"))
    return ["row 1, column", "not a finite number"], r"re-export"


BAD_BINARY = {name[7:]: f for name, f in dict(globals()).items() if name.startswith("binary_")}


@pytest.mark.parametrize("case", sorted(BAD_BINARY))
def test_bad_petsc_binary_refused(tmp_path, case):
    A = rotor_K()
    data = petsc_bytes(A)
    mentions, fix = BAD_BINARY[case](data, A.shape[0], sp.csr_matrix(A).nnz)
    scene = scene_with_rotor_K(tmp_path, bytes(data), name="rotor_K.petsc")
    # in a child process with a timeout: a file that MatLoad trusts may crash or hang the process
    probe = ("import sys, kryflex\ntry:\n    kryflex.load_scene(sys.argv[1])\nexcept kryflex.SceneError as e:\n"
             "    print(e)\n    sys.exit(2)\n")
    r = subprocess.run([sys.executable, "-c", probe, scene], capture_output=True, text=True, env=ENV, timeout=TIMEOUT)
    print(f"{case}: {r.stdout.strip()}")
    assert r.returncode == 2 and "Traceback" not in r.stderr, f"exit {r.returncode}\n{r.stdout}\n{r.stderr[-2000:]}"
    check_message(r.stdout, ["galileo.yaml: bodies.rotor.stiffness", "rotor_K.petsc"] + mentions, fix)


# ------------------------------------------------------------------ two ranks: the same refusal, no hang

MPI_PROBE = textwrap.dedent("""
    import sys
    from mpi4py import MPI
    import numpy as np
    from kryflex import _core
    rank = MPI.COMM_WORLD.rank
    with open("%s.%d" % (sys.argv[1], rank), "w") as out:      # one file per rank: their stdout would interleave
        for path in sys.argv[2:]:
            try:
                A = _core.load_matrix(path)
                lo, hi = A.getOwnershipRange()
                rows = A.convert("dense").getDenseArray()
                out.write("%d|%s|OK %d %d %.17g\\n" % (rank, path, lo, hi, float(np.abs(rows).sum())))
            except _core.Error as e:
                out.write("%d|%s|ERR %s\\n" % (rank, path, e))
    """)


@pytest.mark.mpi
def test_two_ranks_fail_alike(tmp_path):
    """Each bad file under mpiexec -n 2: both ranks raise the same message (no rank fails alone, no hang); a good
    file gives each rank its rows of the same matrix."""
    A = rotor_K()
    files = {}
    for case in ("both_triangles", "nan", "extra_entries", "cut_inside_line", "outside", "pattern"):
        files[case] = os.path.join(str(tmp_path), case + ".mtx")
        write(files[case], BAD_MTX[case](A)[0])
    for case in ("column_minus_one", "truncated_values"):
        data = petsc_bytes(A)
        BAD_BINARY[case](data, A.shape[0], sp.csr_matrix(A).nnz)
        files["binary_" + case] = os.path.join(str(tmp_path), case + ".petsc")
        write(files["binary_" + case], bytes(data))
    files["good"] = os.path.join(str(tmp_path), "good.mtx")
    write(files["good"], mtx_text(A, newline="\r\n"))
    probe = os.path.join(str(tmp_path), "probe.py")
    write(probe, MPI_PROBE)
    answers = os.path.join(str(tmp_path), "answers")
    r = subprocess.run(["mpiexec", "-n", "2", sys.executable, probe, answers] + list(files.values()),
                       capture_output=True, text=True, env=ENV, timeout=TIMEOUT)
    assert r.returncode == 0, r.stderr[-3000:]
    seen = {}
    for rank in (0, 1):
        with open("%s.%d" % (answers, rank)) as f:
            for line in f.read().splitlines():
                rank, path, result = line.split("|", 2)
                seen.setdefault(path, {})[int(rank)] = result
    for case, path in files.items():
        results = seen.get(path, {})
        assert set(results) == {0, 1}, f"{case}: answers from ranks {sorted(results)}\n{r.stdout}\n{r.stderr}"
        if case == "good":
            assert results[0].startswith("OK 0 ") and results[1].startswith("OK ") and " 21 " in results[1], results
            total = sum(float(results[k].split()[3]) for k in (0, 1))
            assert total == pytest.approx(np.abs(A).sum(), rel=1e-14)
        else:
            assert results[0].startswith("ERR ") and results[0] == results[1], f"{case}: {results}"


# ------------------------------------------------------------------ reduced models edited with h5py

@pytest.fixture(scope="module")
def model_file(tmp_path_factory):
    path = str(tmp_path_factory.mktemp("model") / "galileo.h5")
    scene = kryflex.load_scene(os.path.join(GALILEO_DIR, "galileo.yaml"))
    # the paper's fixed recipe: 12 + 13 reduced dofs (stator + rotor), the sizes the messages below name
    kryflex.Reducer(scene, quiet=True, search=False, method="single-angle").reduce().model.save(path)
    return path


def rewrite(f, name, data):
    """Replaces dataset name as the C writer writes it (src/io/model_hdf5.c WriteMatrix: float64, chunks of about
    1 MiB rows, a fletcher32 checksum per chunk): HDF5 computes the checksum of the new data, so it is valid."""
    data = np.asarray(data)
    del f[name]
    if data.ndim == 2 and data.size:
        chunk = (min(data.shape[0], max(1, 131072 // data.shape[1])), data.shape[1])
        f.create_dataset(name, data=data, chunks=chunk, fletcher32=True)
    else:
        f.create_dataset(name, data=data)


def edit_array(name, change):
    def edit(f):
        rewrite(f, name, change(f[name][()].copy()))
    return edit


def set_attr(name, key, value):
    def edit(f):
        f[name].attrs[key] = value
    return edit


def set_strings(name, values):
    def edit(f):
        del f[name]
        f.create_dataset(name, data=np.array(values, dtype=object), dtype=h5py.string_dtype())
    return edit


def put(a, index, value):
    a[index] = value
    return a


def add_extra_body(f):
    f.copy("bodies/stator", "bodies/spare")
    f["bodies/spare"].attrs["index"] = 2


def add_second_parent(f):
    f.copy("joints/spin_bearing", "joints/loop")
    f["joints/loop"].attrs.update(index=1, type="fixed", revolute_index=-1)


def remove_body(f):
    del f["bodies/rotor"]


def make_asymmetric(a):
    a[0, 1] += 1e-3 * np.abs(a).max()
    return a


# name -> (edit, what the message must say)
H5_EDITS = {
    "newer_format": (set_attr("/", "version", 3),
                     ["written in format version 3; this kryflex reads format version 2", "use a newer kryflex or re-run kryflex reduce"]),
    "older_format": (set_attr("/", "version", 1), ["written in format version 1", "re-run kryflex reduce"]),
    "K_shape": (edit_array("bodies/stator/K", lambda a: a[:-1, :-1]),
                ["body 'stator' dataset 'K' is 11 x 11, expected 12 x 12"]),
    "G_columns": (edit_array("bodies/rotor/G", lambda a: np.hstack([a, a])),
                  ["body 'rotor' dataset 'G' is 13 x 2, expected 13 x 1", "dataset 'inputs'"]),
    "inputs_count": (set_strings("inputs", ["bearing_torque", "extra"]),
                     ["dataset 'G' is 13 x 1, expected 13 x 2", "names in dataset 'inputs'"]),
    "outputs_empty": (set_strings("outputs", []), ["0 outputs", "at least one"]),
    "outputs_repeated": (lambda f: (set_strings("outputs", ["a", "a"])(f),
                                    [rewrite(f, "bodies/%s/H" % b, np.vstack([f["bodies/%s/H" % b][()]] * 2))
                                     for b in ("stator", "rotor")]),
                         ["dataset 'outputs' names 'a' twice"]),
    "missing_body": (remove_body, ["joint 'spin_bearing' ties bodies 0 (attribute parent) and 1 (attribute child)", "bodies 0..0"]),
    "extra_body": (add_extra_body, ["body 'spare' is tied to the root body 'stator' by no chain of joints"]),
    "repeated_body_index": (set_attr("bodies/rotor", "index", 0), ["index attributes of the bodies"]),
    "negative_full_dofs": (set_attr("bodies/rotor", "full_dofs", -3), ["body 'rotor' attribute 'full_dofs' is -3"]),
    "full_dofs_vs_map": (set_attr("bodies/rotor", "full_dofs", 30), ["body 'rotor' dataset 'map' is 21 x 13",
                                                                     "attribute 'full_dofs'"]),
    "full_dofs_below_reduced": (lambda f: (set_attr("bodies/rotor", "full_dofs", 5)(f),
                                           rewrite(f, "bodies/rotor/map", f["bodies/rotor/map"][:5])),
                                ["body 'rotor' has 13 reduced dofs", "'full_dofs' is 5"]),
    "K_nan": (edit_array("bodies/stator/K", lambda a: put(a, (0, 0), np.nan)),
              ["body 'stator' dataset 'K' holds nan at [0, 0]", "not a finite number"]),
    "H_inf": (edit_array("bodies/rotor/H", lambda a: put(a, (0, 11), np.inf)),
              ["body 'rotor' dataset 'H' holds inf at [0, 11]"]),
    "rigid_nan": (edit_array("bodies/stator/rigid", lambda a: put(a, (3, 2), np.nan)),
                  ["body 'stator' dataset 'rigid' holds nan at [3, 2]"]),
    "map_nan": (edit_array("bodies/rotor/map", lambda a: put(a, (20, 0), -np.inf)),
                ["body 'rotor' dataset 'map' holds -inf at [20, 0]"]),
    "angles_nan": (edit_array("reduction_angles", lambda a: put(a, (0, 0), np.nan)),
                   ["dataset 'reduction_angles' holds nan"]),
    "angles_columns": (edit_array("reduction_angles", lambda a: np.hstack([a, a])),
                       ["dataset 'reduction_angles' is 1 x 2, expected 1 x 1", "one column per revolute joint"]),
    "K_asymmetric": (edit_array("bodies/rotor/K", make_asymmetric), ["body 'rotor' dataset 'K' is not symmetric"]),
    "M_not_definite": (edit_array("bodies/rotor/M", lambda a: -a), ["body 'rotor' dataset 'M' is not positive definite"]),
    "K_indefinite": (edit_array("bodies/rotor/K", lambda a: -a), ["body 'rotor' dataset 'K' has the negative eigenvalue"]),
    # symmetric positive definite, but not the identity a mass-orthonormal basis gives: edited
    "M_scaled": (edit_array("bodies/stator/M", lambda a: 2 * a), ["body 'stator' dataset 'M' is not the identity",
                                                                  "largest |M - I| is 1"]),
    "M_integer": (lambda f: (lambda a: (f.__delitem__("bodies/rotor/M"),
                                        f.create_dataset("bodies/rotor/M", data=a.astype(np.int32))))(f["bodies/rotor/M"][()]),
                  ["body 'rotor' dataset 'M' is not a matrix of real numbers"]),
    "iface_rows": (edit_array("bodies/rotor/iface", lambda a: np.vstack([a, a])),
                   ["body 'rotor' dataset 'iface' is 12 x 13, expected 6 x 13", "dataset 'interfaces'"]),
    "interfaces_count": (set_strings("bodies/rotor/interfaces", ["bearing", "other"]),
                         ["body 'rotor' dataset 'iface' is 6 x 13, expected 12 x 13"]),
    "joint_parent": (set_attr("joints/spin_bearing", "parent", 5), ["joint 'spin_bearing' ties bodies 5 (attribute parent) and 1"]),
    "joint_interface": (set_attr("joints/spin_bearing", "child_interface", 3),
                        ["joint 'spin_bearing' names an interface"]),
    "joint_axis": (set_attr("joints/spin_bearing", "axis", np.zeros(3)), ["joint 'spin_bearing' has the axis"]),
    "joint_second_parent": (add_second_parent, ["body 'rotor' is the child of joints 'spin_bearing' and 'loop'"]),
    "damping_text": (set_attr("settings", "damping", '"low"'), ["setting 'damping' is '\"low\"'", "damping ratio"]),
    "damping_nan": (set_attr("settings", "damping", "NaN"), ["setting 'damping' is 'NaN'"]),
    "fingerprint": (set_attr("/", "scene_fingerprint", "xyz"), ["scene fingerprint 'xyz'"]),
}


def edited_model(model_file, tmp_path, case):
    path = os.path.join(str(tmp_path), case + ".h5")
    shutil.copy(model_file, path)
    with h5py.File(path, "r+") as f:
        H5_EDITS[case][0](f)
    # the edit kept valid checksums: h5py reads every dataset back (a fletcher32 mismatch would raise here)
    with h5py.File(path, "r") as f:
        f.visititems(lambda name, obj: obj[()] if isinstance(obj, h5py.Dataset) else None)
    return path


@pytest.mark.parametrize("case", sorted(H5_EDITS))
def test_edited_model_refused(model_file, tmp_path, case):
    path = edited_model(model_file, tmp_path, case)
    with pytest.raises(kryflex.ModelFileError) as err:
        kryflex.ReducedModel.load(path)
    msg = str(err.value)
    print(f"{case}: {msg}")
    assert msg.startswith(path + ": not a readable kryflex reduced model: "), msg
    assert msg.count(path) == 1, f"the file is named once: {msg}"
    for m in H5_EDITS[case][1]:
        assert m in msg, f"the message should say '{m}': {msg!r}"
    assert re.search(r"kryflex reduce", msg), msg


def _rigid_basis(f, body):
    """An orthonormal basis of a body's stored rigid motions (dataset 'rigid', v x 6; M = I) and its K."""
    R, K = f["bodies/%s/rigid" % body][()], f["bodies/%s/K" % body][()]
    R = R if R.shape[0] == K.shape[0] else R.T
    U, s, _ = np.linalg.svd(R, full_matrices=False)
    return U[:, s > 1e-10 * s.max()], K


@pytest.mark.parametrize("where, loads", [("rigid", True), ("flexible", False)])
def test_negative_stiffness_energy_only_in_the_rigid_motions(model_file, tmp_path, where, loads):
    """A stiffness rounded when exported gives the rigid motions a little energy of either sign and the reduced K a
    negative eigenvalue of that size: such a file loads. The same negative eigenvalue on a flexible direction (an
    edit) is refused. Both at -1e-6 of K's largest eigenvalue, 100 x the reader's round-off allowance."""
    path = os.path.join(str(tmp_path), where + ".h5")
    shutil.copy(model_file, path)
    with h5py.File(path, "r+") as f:
        Q, K = _rigid_basis(f, "rotor")
        lam, X = np.linalg.eigh(K)
        eps = 1e-6 * lam[-1]
        if where == "rigid":
            Knew = K - Q @ (Q.T @ K @ Q + eps * np.eye(Q.shape[1])) @ Q.T
        else:
            x = X[:, np.flatnonzero(lam > 1e-8 * lam[-1])[0]]
            assert np.abs(Q.T @ x).max() < 1e-6
            Knew = K - (x @ K @ x + eps) * np.outer(x, x)
        assert np.isclose(np.linalg.eigvalsh(Knew)[0], -eps, rtol=1e-6)
        rewrite(f, "bodies/rotor/K", 0.5 * (Knew + Knew.T))
    if loads:
        model = kryflex.ReducedModel.load(path)
        assert len(model.at([30]).frequencies_hz) > 0
    else:
        with pytest.raises(kryflex.ModelFileError, match="dataset 'K' has the negative eigenvalue"):
            kryflex.ReducedModel.load(path)


def test_unedited_copy_loads(model_file, tmp_path):
    """The helpers themselves change nothing: a dataset rewritten with its own values loads and reassembles alike."""
    path = os.path.join(str(tmp_path), "same.h5")
    shutil.copy(model_file, path)
    with h5py.File(path, "r+") as f:
        for name in ("bodies/rotor/K", "bodies/stator/G", "reduction_angles"):
            rewrite(f, name, f[name][()])
    a, b = kryflex.ReducedModel.load(model_file), kryflex.ReducedModel.load(path)
    np.testing.assert_array_equal(a.at([30]).K, b.at([30]).K)


def test_truncated_model_says_so(model_file, tmp_path):
    """A file cut short cannot even be opened: the message gives HDF5's reason (truncated), not a bare 'HDF5 error'."""
    data = open(model_file, "rb").read()
    path = str(tmp_path / "cut.h5")
    with open(path, "wb") as f:
        f.write(data[:len(data) // 2])
    with pytest.raises(kryflex.ModelFileError, match=r"cut\.h5: .*damaged or incomplete \(truncated file"):
        kryflex.ReducedModel.load(path)


def test_flipped_bit_fails_its_checksum(model_file, tmp_path):
    """Without an edit through HDF5 the checksum catches a change: one flipped bit in the rotor's K."""
    path = os.path.join(str(tmp_path), "flipped.h5")
    shutil.copy(model_file, path)
    with h5py.File(path, "r") as f:
        offset = f["bodies/rotor/K"].id.get_chunk_info(0).byte_offset
    with open(path, "r+b") as fh:
        fh.seek(offset + 100)
        byte = fh.read(1)
        fh.seek(offset + 100)
        fh.write(bytes([byte[0] ^ 0x10]))
    with pytest.raises(kryflex.ModelFileError, match=r"body 'rotor' dataset 'K' fails its checksum"):
        kryflex.ReducedModel.load(path)


@pytest.mark.mpi
@pytest.mark.parametrize("case", ["newer_format", "K_nan", "extra_body", "damping_text", "M_not_definite"])
def test_edited_model_exit_5(model_file, tmp_path, case):
    """`kryflex reassemble` refuses an edited model with exit 5, one message, no traceback; so do 2 ranks, alike."""
    path = edited_model(model_file, tmp_path, case)
    for cmd in ([COMMAND], ["mpiexec", "-n", "2", COMMAND]):
        r = subprocess.run(cmd + ["reassemble", path, "--angle", "30"], capture_output=True, text=True, env=ENV,
                           cwd=ROOT, timeout=TIMEOUT)
        assert r.returncode == EXIT_MODEL, f"{cmd}: exit {r.returncode}\n{r.stderr}"
        assert "Traceback" not in r.stderr + r.stdout, r.stderr
        assert r.stderr.count("kryflex: error:") == 1, r.stderr
        for m in H5_EDITS[case][1]:
            assert m in r.stderr, f"the message should say '{m}': {r.stderr!r}"
