"""`kryflex convert`: turn an exported FE model into a kryflex body (matrices, nodes, scene entry).

Inputs:
  a Nastran punch file (.pch, or any bulk-data file) with DMIG stiffness and mass matrices
      (KAAX and MAAX by default), with GRID (CORD, SPOINT, PARAM) cards here or in --grids files
      (.bdf/.dat, or a run's .f06 bulk-data echo); read with pyNastran, see io/dmig.py;
  a NumPy .npz holding M and K (dense arrays 'M', 'K', or sparse parts 'M_data', 'M_indices',
      'M_indptr', 'M_shape' [, 'M_format' = csr|csc], or 'M_row', 'M_col', 'M_data', 'M_shape')
      and optionally 'nodes' (n x 5: id x y z ndof);
  a Nastran OUTPUT4 file (.op4, ASCII or binary) with the two matrices, plus a nodes file naming the rows;
  Matrix Market (.mtx) or PETSc binary (.petsc) mass and stiffness files plus a nodes file;
  a MATLAB .mat second-order model (M, K, D/E, B, C or Cp/Cv: MORwiki conventions), see io/matfile.py: written
      with its input/output vectors and a scene file that runs as is.
Output: see bodyfiles.write_body.
"""

import argparse
import os
import sys
import warnings
import zipfile
from dataclasses import dataclass, field

import numpy as np
import scipy.io
import scipy.sparse as sp

from .bodyfiles import ConversionError, ConversionWarning, FORMATS, dof_count, read_nodes, write_body
from .dmig import nastran_body

__all__ = ["convert", "main", "ConversionError", "ConversionWarning", "ConvertedBody"]

PETSC_MAT_CLASSID = 1211216
EXIT_USAGE, EXIT_BAD_INPUT, EXIT_OUTPUT = 2, 2, 4   # as the kryflex command: docs/guide/troubleshooting.md


@dataclass
class ConvertedBody:
    files: dict            # 'mass', 'stiffness', 'nodes', 'snippet' -> written path
    size: int              # number of dofs
    node_count: int
    interfaces: dict = field(default_factory=dict)


def convert(inputs, out_dir, name, fmt="petsc", interfaces=None, grids=None,
            stiffness_name="KAAX", mass_name="MAAX", nodes=None, mass_scale=None):
    """Convert one body and write it to out_dir; return a ConvertedBody.

    inputs: path of a Nastran punch file or of a .npz, or a mapping
            {'mass': file, 'stiffness': file, 'nodes': file} of Matrix Market / PETSc binary files.
    interfaces: {interface name: node id}; grids: bulk-data file(s) (.bdf/.dat/.pch, or a run's .f06 with
    its bulk-data echo) with GRID, CORD, SPOINT and PARAM cards (Nastran input);
    nodes: a nodes file for a .npz that holds no 'nodes' array;
    mass_scale: Nastran input only: a factor on the DMIG mass, or 'wtmass' (see io/dmig.py, WTMASS).
    Raises ConversionError (message names the file and the fix); nothing is written then.
    """
    interfaces = dict(interfaces or {})
    grids = [grids] if isinstance(grids, (str, os.PathLike)) else list(grids or [])
    if isinstance(inputs, dict):
        unknown = set(inputs) - {"mass", "stiffness", "nodes"}
        if unknown or not {"mass", "stiffness", "nodes"} <= set(inputs):
            raise ConversionError("matrix-file input needs exactly the keys 'mass', 'stiffness' and 'nodes'")
        _no_grids(grids, "Matrix Market / PETSc inputs")
        if nodes is not None:
            raise ConversionError("give the nodes file once (inputs['nodes'])")
        M, K, body_nodes, sources = load_matrix_files(inputs["mass"], inputs["stiffness"], inputs["nodes"])
    else:
        path = os.fspath(inputs)
        _require_file(path, "input")
        kind = os.path.splitext(path)[1].lower()
        if kind == ".npz":
            _no_grids(grids, "a .npz input (coordinates go in its 'nodes' array or a nodes file)")
            M, K, body_nodes, sources = load_npz(path, nodes)
        elif kind == ".op4":
            _no_grids(grids, "an OP4 input (its dofs and coordinates come from the nodes file)")
            M, K, body_nodes, sources = load_op4(path, nodes, stiffness_name, mass_name)
        elif kind in (".mtx", ".petsc"):
            raise ConversionError(
                f"{path} is a single matrix; a body needs mass, stiffness and nodes: "
                "use --mass M --stiffness K --nodes nodes.txt")
        else:
            if nodes is not None:
                raise ConversionError(
                    f"{path}: the nodes of a Nastran body come from its DMIG dofs; "
                    "give coordinates as GRID cards (--grids bulk.bdf), not a nodes file")
            M, K, body_nodes, sources = load_punch(path, grids, stiffness_name, mass_name, mass_scale)
    files = write_body(out_dir, name, M, K, body_nodes, interfaces, fmt=fmt, sources=sources)
    return ConvertedBody(files=files, size=int(sum(dof_count(n[4]) for n in body_nodes)),
                         node_count=len(body_nodes), interfaces=interfaces)


def _require_file(path, what):
    if not os.path.isfile(path):
        state = "is a folder" if os.path.isdir(path) else "does not exist"
        raise ConversionError(f"{what} file {path} {state}: give the path of an existing file")


def _no_grids(grids, what):
    if grids:
        raise ConversionError(f"--grids applies to Nastran punch files only, not to {what}")


# ---------------------------------------------------------------- Nastran punch

def load_punch(path, grid_files, stiffness_name, mass_name, mass_scale=None):
    """A Nastran body read with pyNastran: see io/dmig.py for what is read and how it is transformed."""
    for grid_file in grid_files:
        _require_file(grid_file, "GRID")
    M, K, nodes, notes = nastran_body(path, grid_files, stiffness_name, mass_name, mass_scale)
    scale = f" x {notes['mass_scale']:g}" if notes["mass_scale"] != 1.0 else ""
    frame = " turned to basic" if notes["rotated"] else ""
    sources = {"mass": f"DMIG {mass_name.upper()}{scale}{frame} of {path}",
               "stiffness": f"DMIG {stiffness_name.upper()}{frame} of {path}",
               "nodes": f"grids of {' + '.join([os.fspath(path), *map(os.fspath, grid_files)])}"}
    return M, K, nodes, sources


# ---------------------------------------------------------------- Nastran OUTPUT4

def load_op4(path, nodes_file, stiffness_name, mass_name):
    """Mass and stiffness from a Nastran OUTPUT4 file (ASCII or binary, read with pyNastran's OP4 reader). An OP4
    matrix has no dof labels, so the nodes file names the rows: one line per node in the matrices' (a-set) order,
    with its components (6, 3, c<components>, s) and basic coordinates; the rows must already be in basic dofs."""
    if nodes_file is None:
        raise ConversionError(
            f"{path}: an OP4 matrix has no dof labels; give the nodes of its rows with --nodes (one 'id x y z dofs' "
            "line per node, in the matrix order, dofs 6, 3, c<components> or s)")
    _require_file(nodes_file, "nodes")
    from .dmig import _pynastran, _quiet_log
    _pynastran()
    from pyNastran.op4.op4 import read_op4
    try:
        matrices = read_op4(os.fspath(path), log=_quiet_log())
    except Exception as exc:  # noqa: BLE001 - pyNastran raises ValueError, AssertionError, struct.error, ...
        raise ConversionError(f"{path}: pyNastran cannot read this OP4 file "
                              f"({' '.join(str(exc).split())[:300] or type(exc).__name__}); re-export it") from None
    by_name = {str(k).strip().upper(): v for k, v in matrices.items()}
    picked = []
    for name in (stiffness_name.upper(), mass_name.upper()):
        if name not in by_name:
            raise ConversionError(
                f"{path} holds no matrix {name} (matrices: {', '.join(sorted(by_name)) or 'none'}); give the "
                "names with --stiffness-name and --mass-name")
        data = by_name[name].data
        try:
            picked.append(sp.csr_matrix(data, dtype=np.float64))
        except (TypeError, ValueError) as exc:
            raise ConversionError(f"{path}: matrix {name} is not a real matrix ({exc})") from None
    K, M = picked
    sources = {"mass": f"OP4 {mass_name.upper()} of {path}", "stiffness": f"OP4 {stiffness_name.upper()} of {path}",
               "nodes": f"nodes file {nodes_file}"}
    return M, K, read_nodes(nodes_file), sources


# ---------------------------------------------------------------- NumPy archive

def load_npz(path, nodes_file=None):
    try:
        archive = np.load(path, allow_pickle=False)
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as exc:
        raise ConversionError(f"{path} is not a readable NumPy .npz archive ({exc})") from None
    if not isinstance(archive, np.lib.npyio.NpzFile):
        raise ConversionError(f"{path} holds a single array; a body .npz holds M, K (and nodes): "
                              "save it with numpy.savez(path, M=..., K=..., nodes=...)")
    with archive:
        M = _npz_matrix(archive, "M", path)
        K = _npz_matrix(archive, "K", path)
        has_nodes = "nodes" in archive.files
        if has_nodes and nodes_file is not None:
            raise ConversionError(f"{path} holds a 'nodes' array and a nodes file was given too; give one")
        if has_nodes:
            table = _npz_array(archive, "nodes", path)
            if table.ndim != 2 or table.shape[1] != 5:
                raise ConversionError(
                    f"'nodes' array of {path} has shape {table.shape}; it must be n x 5 (id x y z ndof)")
            nodes = [tuple(row) for row in table.tolist()]
            nodes_source = f"'nodes' array of {path}"
        elif nodes_file is not None:
            _require_file(nodes_file, "nodes")
            nodes, nodes_source = read_nodes(nodes_file), f"nodes file {nodes_file}"
        else:
            nodes, nodes_source = _default_nodes(path, M.shape[0]), f"default nodes for {path}"
    sources = {"mass": f"'M' of {path}", "stiffness": f"'K' of {path}", "nodes": nodes_source}
    return M, K, nodes, sources


def _npz_array(archive, key, path):
    try:
        return archive[key]
    except ValueError as exc:  # object arrays (e.g. a pickled scipy matrix) need pickle: refused
        raise ConversionError(
            f"'{key}' of {path} cannot be read without pickle ({exc}); store plain arrays: a dense "
            f"'{key}' or sparse parts '{key}_data', '{key}_indices', '{key}_indptr', '{key}_shape'") from None


def _npz_matrix(archive, key, path):
    keys = set(archive.files)
    where = f"{path}, matrix {key}"
    try:
        if key in keys:
            dense = _npz_array(archive, key, path)
            if dense.ndim != 2:
                raise ConversionError(f"{where}: array '{key}' has {dense.ndim} dimensions; it must be 2-D")
            return sp.csr_matrix(dense.astype(np.float64))
        part = lambda suffix: _npz_array(archive, f"{key}_{suffix}", path)  # noqa: E731
        if {f"{key}_{s}" for s in ("data", "indices", "indptr", "shape")} <= keys:
            layout = "csr"
            if f"{key}_format" in keys:
                layout = part("format").item()
                layout = layout.decode() if isinstance(layout, bytes) else str(layout)
            if layout not in ("csr", "csc"):
                raise ConversionError(f"{where}: '{key}_format' is {layout!r}; use 'csr' or 'csc'")
            build = sp.csr_matrix if layout == "csr" else sp.csc_matrix
            return build((part("data").astype(np.float64), part("indices"), part("indptr")),
                         shape=tuple(int(n) for n in part("shape"))).tocsr()
        if {f"{key}_{s}" for s in ("row", "col", "data", "shape")} <= keys:
            return sp.csr_matrix((part("data").astype(np.float64), (part("row"), part("col"))),
                                 shape=tuple(int(n) for n in part("shape")))
    except (ValueError, TypeError, IndexError) as exc:
        raise ConversionError(f"{where}: the stored arrays do not form a matrix ({exc})") from None
    raise ConversionError(
        f"{path} holds no matrix {key} (arrays: {', '.join(sorted(keys)) or 'none'}); store a dense "
        f"'{key}', or sparse parts '{key}_data', '{key}_indices', '{key}_indptr', '{key}_shape' "
        f"(CSR; '{key}_format'='csc' for CSC), or '{key}_row', '{key}_col', '{key}_data', '{key}_shape'")


def _default_nodes(path, size):
    if size % 6:
        raise ConversionError(
            f"{path} has no 'nodes' array and its {size} dofs are not a multiple of 6; "
            "add 'nodes' (n x 5: id x y z ndof) or give a nodes file with --nodes")
    warnings.warn(
        f"{path} has no 'nodes' array: assuming {size // 6} nodes with 6 dofs, ids 1..{size // 6}, at "
        "coordinates 0, so rigid-body modes will then need to be supplied (add 'nodes' to fix)",
        ConversionWarning)
    return [(i, 0.0, 0.0, 0.0, 6) for i in range(1, size // 6 + 1)]


# ---------------------------------------------------------------- matrix files

def load_matrix_files(mass, stiffness, nodes_file):
    for path, what in ((mass, "mass"), (stiffness, "stiffness"), (nodes_file, "nodes")):
        _require_file(path, what)
    M, K = read_matrix_file(mass), read_matrix_file(stiffness)
    sources = {"mass": os.fspath(mass), "stiffness": os.fspath(stiffness),
               "nodes": f"nodes file {nodes_file}"}
    return M, K, read_nodes(nodes_file), sources


def read_matrix_file(path):
    """A sparse matrix from a Matrix Market (.mtx) or PETSc binary (.petsc) file."""
    path = os.fspath(path)
    try:
        with open(path, "rb") as handle:
            head = handle.read(4)
    except OSError as exc:
        raise ConversionError(f"cannot read matrix file {path}: {exc.strerror or exc}") from None
    if len(head) == 4 and int.from_bytes(head, "big") == PETSC_MAT_CLASSID:
        return _read_petsc(path)
    if path.lower().endswith(".petsc"):
        raise ConversionError(f"{path} is not a PETSc binary matrix (wrong header)")
    try:
        rows, cols, _, layout, value_field, _ = scipy.io.mminfo(path)
        if value_field not in ("real", "integer"):
            raise ConversionError(
                f"{path} is a Matrix Market '{value_field}' matrix; mass and stiffness must be real")
        A = scipy.io.mmread(path)
    except ConversionError:
        raise
    except Exception as exc:  # scipy raises ValueError, IndexError, ... on malformed files
        raise ConversionError(f"{path} is not a readable Matrix Market file ({exc})") from None
    return sp.csr_matrix(A, dtype=np.float64)


def _read_petsc(path):
    from petsc4py import PETSc

    viewer = PETSc.Viewer().createBinary(path, "r", comm=PETSc.COMM_SELF)
    mat = PETSc.Mat().create(comm=PETSc.COMM_SELF)
    try:
        mat.setType(PETSc.Mat.Type.AIJ)
        mat.load(viewer)
        indptr, indices, data = mat.getValuesCSR()
        return sp.csr_matrix((data.copy(), indices.copy(), indptr.copy()), shape=mat.getSize())
    except PETSc.Error as exc:
        raise ConversionError(f"{path}: PETSc cannot load this matrix ({exc})") from None
    finally:
        mat.destroy()
        viewer.destroy()


# ---------------------------------------------------------------- command line

USAGE_EXAMPLES = """examples:
  kryflex convert model.pch --name rotor --interface bearing=101 -o bodies
  kryflex convert model.pch --grids model.bdf --name rotor --interface bearing=101 -o bodies
  kryflex convert model.pch --grids model.f06 --name rotor --interface bearing=101 -o bodies
  kryflex convert model.op4 --nodes nodes.txt --stiffness-name KAA --mass-name MAA --name rotor -o bodies
  kryflex convert boom.npz --name boom --interface root=1 --format mtx -o bodies
  kryflex convert --mass M.mtx --stiffness K.mtx --nodes nodes.txt --name x --interface a=7 -o bodies
  kryflex convert beam.mat --name beam -o beam    (M, K, D or E, B, C or Cp/Cv: writes beam/beam.yaml too)

Writes <name>_M.<fmt>, <name>_K.<fmt>, <name>_nodes.txt and <name>.body.yaml (the scene entry).
Exit codes: 0 done, 2 bad command line or input (nothing written), 4 output folder not writable."""


class _UsageError(Exception):
    pass


def build_parser():
    from ..cli.common import Parser    # the kryflex conventions: one 'kryflex: error:' line, on rank 0, with the fix
    parser = Parser(
        prog="kryflex convert", formatter_class=argparse.RawDescriptionHelpFormatter,
        description="Convert an exported FE model (Nastran DMIG punch file with GRIDs from bulk data or an "
                    ".f06, Nastran OP4 + nodes file, NumPy .npz, or Matrix Market / PETSc matrices + nodes file) "
                    "into a kryflex body; or a MATLAB .mat second-order model (M, K, D/E, B, C or Cp/Cv) into a "
                    "body, its input/output vectors and a scene that runs as is.",
        epilog=USAGE_EXAMPLES)
    parser.add_argument("input", nargs="?", help="Nastran punch/bulk file with DMIG matrices, an OP4 file (with --nodes), a .npz, or a MATLAB .mat")
    parser.add_argument("--mass", metavar="FILE", help="mass matrix (.mtx or .petsc), with --stiffness and --nodes")
    parser.add_argument("--stiffness", metavar="FILE", help="stiffness matrix (.mtx or .petsc)")
    parser.add_argument("--nodes", metavar="FILE", help="nodes file (id x y z dofs per line: 6, 3, c<components> or s)")
    parser.add_argument("--name", required=True, help="body name (used in file names and the scene entry)")
    parser.add_argument("-o", "--output-dir", default=".", metavar="DIR", help="output folder (default: .)")
    parser.add_argument("--format", choices=FORMATS, default="petsc",
                        help="matrix file format (default: petsc)")
    parser.add_argument("--interface", action="append", default=[], metavar="NAME=NODE",
                        help="interface name and its node id (6 dofs); repeat for several")
    parser.add_argument("--grids", action="append", default=[], metavar="FILE",
                        help="bulk data (.bdf/.dat/.pch) or a run's .f06 (its bulk-data echo) with the GRID, "
                             "CORD, SPOINT and PARAM cards of a punch input; repeatable")
    parser.add_argument("--stiffness-name", metavar="NAME", help="DMIG or OP4 stiffness name (default: KAAX)")
    parser.add_argument("--mass-name", metavar="NAME", help="DMIG or OP4 mass name (default: MAAX)")
    parser.add_argument("--mass-scale", metavar="FACTOR|wtmass",
                        help="multiply the DMIG mass by FACTOR, or by the model's PARAM,WTMASS (only for a mass "
                             "written in weight units: a punched MAAX already holds WTMASS)")
    for part, default in (("mass", "M"), ("stiffness", "K"), ("damping", "D, E, or C beside Cp/Cv"),
                          ("input", "B"), ("output", "Cp or C"), ("velocity-output", "Cv")):
        parser.add_argument("--%s-key" % part, metavar="KEY",
                            help="MATLAB .mat input: the variable holding the %s matrix (default %s)"
                                 % (part.replace("-", " "), default))
    return parser


MAT_KEYS = ("mass_key", "stiffness_key", "damping_key", "input_key", "output_key", "velocity_output_key")


def _parse_interfaces(items):
    interfaces = {}
    for item in items:
        iname, sep, node = item.partition("=")
        iname, node = iname.strip(), node.strip()
        if not sep or not iname or not node:
            raise _UsageError(f"--interface {item!r}: expected NAME=NODE, e.g. --interface bearing=101")
        try:
            node_id = int(node)
        except ValueError:
            raise _UsageError(f"--interface {item!r}: node {node!r} is not an integer node id") from None
        if iname in interfaces:
            raise _UsageError(f"--interface: interface '{iname}' given twice")
        interfaces[iname] = node_id
    return interfaces


def _arguments_to_call(args):
    """Check the combination of options; return the keyword arguments of convert()."""
    interfaces = _parse_interfaces(args.interface)
    files = (args.mass, args.stiffness)
    if args.input and any(files):
        raise _UsageError("give either an input file or --mass/--stiffness/--nodes, not both")
    if not args.input and not any(files):
        raise _UsageError("no input: give a punch file or .npz, or --mass M --stiffness K --nodes N")
    call = dict(out_dir=args.output_dir, name=args.name, fmt=args.format, interfaces=interfaces)
    if not args.input:
        if not all(files) or not args.nodes:
            raise _UsageError("matrix-file input needs all of --mass, --stiffness and --nodes")
        if args.grids or args.stiffness_name or args.mass_name or args.mass_scale:
            raise _UsageError("--grids/--stiffness-name/--mass-name/--mass-scale apply to Nastran punch files only")
        call["inputs"] = {"mass": args.mass, "stiffness": args.stiffness, "nodes": args.nodes}
        return call
    call["inputs"] = args.input
    given_keys = [k for k in MAT_KEYS if getattr(args, k)]
    if args.input.lower().endswith(".mat"):
        if args.grids or args.nodes or args.stiffness_name or args.mass_name or args.mass_scale or interfaces:
            raise _UsageError("--grids/--nodes/--stiffness-name/--mass-name/--mass-scale/--interface do not apply to "
                              "a MATLAB .mat input (name its variables with --mass-key, --stiffness-key, ...)")
        return dict(mat=args.input, out_dir=args.output_dir, name=args.name, fmt=args.format,
                    keys={k[:-4]: getattr(args, k) for k in MAT_KEYS})
    if given_keys:
        raise _UsageError("--%s applies to MATLAB .mat input only" % given_keys[0].replace("_", "-"))
    if args.input.lower().endswith(".op4"):
        if args.grids or args.mass_scale:
            raise _UsageError("--grids/--mass-scale apply to Nastran bulk-data (DMIG) input only; an OP4 input "
                              "takes its dofs and coordinates from --nodes")
        call.update(nodes=args.nodes, stiffness_name=args.stiffness_name or "KAAX", mass_name=args.mass_name or "MAAX")
        return call
    if args.input.lower().endswith(".npz"):
        if args.grids or args.stiffness_name or args.mass_name or args.mass_scale:
            raise _UsageError("--grids/--stiffness-name/--mass-name/--mass-scale apply to Nastran punch files only")
        call["nodes"] = args.nodes
    else:
        if args.nodes:
            raise _UsageError("--nodes does not apply to a punch file: its nodes come from the DMIG dofs "
                              "and GRID cards (use --grids for coordinates)")
        call.update(grids=args.grids, stiffness_name=args.stiffness_name or "KAAX",
                    mass_name=args.mass_name or "MAAX", mass_scale=_mass_scale(args.mass_scale))
    return call


def _mass_scale(text):
    if text is None or text.strip().lower() == "wtmass":
        return None if text is None else "wtmass"
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not value > 0 or value == float("inf"):
        raise _UsageError(f"--mass-scale {text!r}: give a positive number or 'wtmass'")
    return value


def main(argv=None):
    """Run `kryflex convert` with argv (without the 'convert' word); return the exit code."""
    from ..cli.common import Failure, error, say
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except Failure as bad:      # the usage and the error line (code 2)
        say(bad.text, sys.stderr)
        return bad.code
    except SystemExit as stop:  # -h: argparse printed the help
        return stop.code if isinstance(stop.code, int) else EXIT_USAGE
    try:
        call = _arguments_to_call(args)
    except _UsageError as exc:
        say(parser.format_usage().rstrip(), sys.stderr)
        error(str(exc))
        return EXIT_USAGE
    problem = _unwritable(args.output_dir)
    if problem:
        error(problem)
        return EXIT_OUTPUT
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ConversionWarning)
        try:
            if "mat" in call:
                _require_file(call["mat"], "input")
                from .matfile import convert_mat
                done = convert_mat(call.pop("mat"), **call)
            else:
                body = convert(**call)
        except ConversionError as exc:
            _print_warnings(caught)
            error(str(exc))
            return EXIT_BAD_INPUT
    _print_warnings(caught)

    def out(text):   # the standard output of now (a test's capture), a closed pipe silenced (cli.common.say)
        say(text, sys.stdout)
    if "mat" not in call and "keys" in call:
        out(f"kryflex convert: model '{args.name}': {done['dofs']} dofs (scalar points), {done['inputs']} input(s), "
              f"{done['outputs']} output(s), damping matrix {done['damping'] or 'none'}; first flexible frequency "
              + (f"{done['first_hz']:.6g} Hz" if done["first_hz"] else "not computed (large model)"))
        out(f"  scene     {done['scene']}  (band and accuracy are guesses: edit them)")
        out(f"Run: kryflex reduce {done['scene']} -o OUTDIR")
        return 0
    interfaces = ", ".join(f"{k}={v}" for k, v in body.interfaces.items()) or "none"
    out(f"kryflex convert: body '{args.name}': {body.size} dofs, {body.node_count} nodes, "
          f"interfaces {interfaces}")
    for key in ("mass", "stiffness", "nodes", "snippet"):
        out(f"  {key:9s} {body.files[key]}")
    out(f"Paste the entry of {body.files['snippet']} under `bodies:` in your scene file.")
    return 0


def _unwritable(out):
    """Why the output folder cannot be written, or None: checked before any work, without creating anything."""
    path = os.path.abspath(out)
    if os.path.exists(path):
        if not os.path.isdir(path):
            return f"output {path} exists and is not a folder: choose another -o"
        if os.access(path, os.W_OK | os.X_OK):
            return None
        return f"the output folder {path} is not writable: choose another -o"
    parent = path
    while not os.path.exists(parent):
        parent = os.path.dirname(parent)
    if not os.path.isdir(parent) or not os.access(parent, os.W_OK | os.X_OK):
        return f"cannot create the output folder {path}: {parent} is not a writable folder: choose another -o"
    return None


def _print_warnings(caught):
    for item in caught:
        print(f"kryflex convert: warning: {item.message}", file=sys.stderr)


if __name__ == "__main__":
    sys.exit(main())
