"""Write and read the files that describe one kryflex body.

A body on disk is four files in one folder:

    <name>_M.petsc | <name>_M.mtx     mass matrix (sparse, symmetric)
    <name>_K.petsc | <name>_K.mtx     stiffness matrix
    <name>_nodes.txt                  one line per node: id x y z dofs
    <name>.body.yaml                  the `bodies:` entry to paste into a scene file

Dofs are numbered node by node in nodes-file order, components ascending within a
node, so the matrix size is the sum of the nodes' dof counts. The dofs field is 6
(ux uy uz rx ry rz), 3 (ux uy uz), a Nastran component string prefixed with c
listing the components present (c345 = uz rx ry), or s (a scalar point: one dof).

Every file is first written under a temporary name in the output folder and the
set is renamed only once all of them are complete, so an error (bad input, full
disk, interrupt) never leaves a half-written or mismatched body behind.
"""

import math
import os
import re
import tempfile

import numpy as np
import scipy.io
import scipy.sparse as sp

from .files import commit

SYMMETRY_TOLERANCE = 1e-10  # relative to the largest entry: round-off of a symmetric export
VALID_NDOF = (3, 6)
DOFS_RULE = ("6 (ux uy uz rx ry rz), 3 (ux uy uz), c<components> (Nastran components present, ascending, "
             "e.g. c345 = uz rx ry) or s (a scalar point)")
_COMPONENTS = re.compile(r"^[cC](1?2?3?4?5?6?)$")
NAME_PATTERN = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.-]*$")
FORMATS = ("petsc", "mtx")


class ConversionError(Exception):
    """A body cannot be converted or written; the message names the input and the fix."""


class ConversionWarning(UserWarning):
    """The body was written, but something needs the user's attention."""


def matrix_file_names(name, fmt):
    """File names (no folder) of a body's mass and stiffness files in format fmt."""
    return f"{name}_M.{fmt}", f"{name}_K.{fmt}"


def parse_dofs(value):
    """A node's dofs field (6, 3, 'c345', 's', or their text) in canonical form, or None if it is not one:
    'c123456' is 6 and 'c123' is 3, so one set of components has one spelling."""
    if isinstance(value, (bool, np.bool_)):
        return None
    if isinstance(value, (int, np.integer, float, np.floating)):
        return int(value) if float(value) in VALID_NDOF else None
    if not isinstance(value, str):
        return None
    text = value.strip()
    if text in ("3", "6"):
        return int(text)
    if text.lower() == "s":
        return "s"
    match = _COMPONENTS.match(text)
    if not match or not match.group(1):
        return None
    return {"123456": 6, "123": 3}.get(match.group(1), "c" + match.group(1))


def dof_count(dofs):
    """How many matrix rows a node with this (canonical) dofs field has."""
    if dofs == "s":
        return 1
    return len(dofs) - 1 if isinstance(dofs, str) else int(dofs)


def read_nodes(path):
    """Parse a nodes file; return a list of (id, x, y, z, dofs) tuples in file order (dofs: see parse_dofs).

    Raises ConversionError naming the file, the line number and what is wrong.
    """
    try:
        with open(path, "r", encoding="utf-8", errors="replace") as handle:
            lines = handle.readlines()
    except OSError as exc:
        raise ConversionError(f"cannot read nodes file {path}: {exc.strerror or exc}") from exc
    nodes = []
    first_line_of = {}
    for number, raw in enumerate(lines, start=1):
        text = raw.split("#", 1)[0].strip()
        if not text:
            continue
        where = f"nodes file {path}, line {number}"
        fields = text.replace(",", " ").split()
        if len(fields) != 5:
            raise ConversionError(
                f"{where}: expected 5 fields 'id x y z dofs', found {len(fields)}: {text!r}")
        try:
            node_id = int(fields[0])
        except ValueError:
            raise ConversionError(f"{where}: node id {fields[0]!r} is not an integer") from None
        if node_id < 0:
            raise ConversionError(f"{where}: node id {node_id} is negative; ids must be >= 0")
        xyz = []
        for axis, field in zip("xyz", fields[1:4]):
            try:
                value = float(field)
            except ValueError:
                raise ConversionError(f"{where}: coordinate {axis} = {field!r} is not a number") from None
            if not math.isfinite(value):
                raise ConversionError(f"{where}: coordinate {axis} = {field!r} is not finite")
            xyz.append(value)
        ndof = parse_dofs(fields[4])
        if ndof is None:
            raise ConversionError(f"{where}: dofs = {fields[4]!r}; it must be {DOFS_RULE}")
        if node_id in first_line_of:
            raise ConversionError(
                f"{where}: node id {node_id} already defined on line {first_line_of[node_id]}; ids must be unique")
        first_line_of[node_id] = number
        nodes.append((node_id, xyz[0], xyz[1], xyz[2], ndof))
    if not nodes:
        raise ConversionError(f"nodes file {path} holds no node lines ('id x y z dofs')")
    return nodes


def normalize_nodes(nodes, source="nodes"):
    """Turn nodes (list of tuples or an n x 5 array) into checked (id, x, y, z, dofs) tuples."""
    try:
        rows = [tuple(row) for row in nodes]
    except TypeError:
        raise ConversionError(f"{source}: expected a list of (id, x, y, z, ndof) rows") from None
    result = []
    seen = set()
    for index, row in enumerate(rows):
        where = f"{source}, row {index}"
        if len(row) != 5:
            raise ConversionError(f"{where}: expected 5 values (id, x, y, z, ndof), found {len(row)}")
        node_id, ndof = row[0], row[4]
        if not _is_integer(node_id) or int(node_id) < 0:
            raise ConversionError(f"{where}: node id {node_id!r} is not a non-negative integer")
        ndof = parse_dofs(ndof)
        if ndof is None:
            raise ConversionError(f"{where}: dofs = {row[4]!r}; it must be {DOFS_RULE}")
        try:
            xyz = [float(v) for v in row[1:4]]
        except (TypeError, ValueError):
            raise ConversionError(f"{where}: coordinates {row[1:4]} are not numbers") from None
        if not all(math.isfinite(v) for v in xyz):
            raise ConversionError(f"{where}: coordinates {xyz} are not finite")
        node_id = int(node_id)
        if node_id in seen:
            raise ConversionError(f"{where}: node id {node_id} appears twice; ids must be unique")
        seen.add(node_id)
        result.append((node_id, xyz[0], xyz[1], xyz[2], ndof))
    if not result:
        raise ConversionError(f"{source}: no nodes given")
    return result


def _is_integer(value):
    try:
        return float(value) == int(value)
    except (TypeError, ValueError, OverflowError):
        return False


def check_matrix(A, label, size, nodes_origin=""):
    """Return A as a canonical CSR matrix, exactly symmetrized, after checking it.

    label names the matrix in errors (e.g. "stiffness K of body 'rotor' (from K.mtx)").
    """
    try:
        A = sp.csr_matrix(A, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ConversionError(f"{label}: not a real matrix ({exc})") from None
    if A.shape[0] != A.shape[1]:
        raise ConversionError(f"{label} is {A.shape[0]} x {A.shape[1]}; it must be square")
    if A.shape[0] != size:
        raise ConversionError(
            f"{label} is {A.shape[0]} x {A.shape[1]} but the nodes{nodes_origin} hold {size} dofs "
            "(sum of the nodes' dof counts); "
            "the nodes list must describe exactly the matrix rows, node by node")
    A.sum_duplicates()
    if not np.all(np.isfinite(A.data)):
        bad = np.flatnonzero(~np.isfinite(A.data))[0]
        row = np.searchsorted(A.indptr, bad, side="right") - 1
        raise ConversionError(
            f"{label} holds a non-finite value ({A.data[bad]}) at row {row}, column {A.indices[bad]} "
            "(0-based); fix the export")
    scale = np.abs(A.data).max() if A.nnz else 0.0
    asym = abs(A - A.T)
    worst = asym.max() if asym.nnz else 0.0
    if worst > SYMMETRY_TOLERANCE * scale:
        r, c = _argmax_sparse(asym)
        raise ConversionError(
            f"{label} is not symmetric: |A - A^T| reaches {worst:.3e} at row {r}, column {c} (0-based), "
            f"{worst / scale:.1e} of the largest entry (tolerance {SYMMETRY_TOLERANCE:g}); "
            "kryflex needs symmetric M and K: check the export (full storage, not one triangle "
            "read as general), or symmetrize with (A + A^T)/2 if the difference is round-off")
    # Exact symmetry on disk: (a + a)/2 == a, so symmetric input is unchanged.
    A = ((A + A.T) * 0.5).tocsr()
    A.sum_duplicates()
    A.sort_indices()
    return A


def _argmax_sparse(A):
    A = A.tocoo()
    k = int(np.argmax(A.data))
    return int(A.row[k]), int(A.col[k])


def check_interfaces(interfaces, nodes, body):
    """Check that every interface names an existing 6-dof node; return {name: id}."""
    ndof_of = {n[0]: n[4] for n in nodes}
    checked = {}
    for iname, node_id in (interfaces or {}).items():
        if not isinstance(iname, str) or not iname.strip():
            raise ConversionError(f"body '{body}': interface name {iname!r} must be a non-empty string")
        try:
            node_id_int = int(node_id)
            if node_id_int != float(node_id):
                raise ValueError
        except (TypeError, ValueError):
            raise ConversionError(
                f"body '{body}': interface '{iname}' node {node_id!r} is not an integer node id") from None
        if node_id_int not in ndof_of:
            raise ConversionError(
                f"body '{body}': interface '{iname}' names node {node_id_int}, which is not a node of the body "
                f"({len(ndof_of)} nodes, ids {min(ndof_of)}..{max(ndof_of)}); give an existing node id")
        if ndof_of[node_id_int] != 6:
            raise ConversionError(
                f"body '{body}': interface '{iname}' node {node_id_int} has dofs {ndof_of[node_id_int]} "
                "(not all six); interface nodes need 6 dofs (ux uy uz rx ry rz): "
                "keep the rotations of this node in the exported matrices or choose another node")
        checked[iname] = node_id_int
    return checked


def write_body(out_dir, name, M, K, nodes, interfaces, fmt="petsc", sources=None):
    """Check and write a body; return {'mass', 'stiffness', 'nodes', 'snippet'} -> written paths.

    M, K: scipy.sparse (or dense) symmetric matrices; nodes: rows (id, x, y, z, dofs) (dofs: see parse_dofs);
    interfaces: {interface name: node id}; fmt: 'petsc' (PETSc binary) or 'mtx' (Matrix Market);
    sources: optional {'mass', 'stiffness', 'nodes'} -> where each came from, quoted in errors.
    The output folder is created if needed. Raises ConversionError; nothing is written then.
    """
    if fmt not in FORMATS:
        raise ConversionError(f"output format {fmt!r} is unknown; use one of {', '.join(FORMATS)}")
    if not isinstance(name, str) or not NAME_PATTERN.match(name):
        raise ConversionError(
            f"body name {name!r} is not usable in file names; use letters, digits, '_', '-' or '.'")
    sources = sources or {}
    origin = {key: f" (from {sources[key]})" if sources.get(key) else "" for key in ("mass", "stiffness", "nodes")}
    nodes = normalize_nodes(nodes, source=f"nodes of body '{name}'{origin['nodes']}")
    size = sum(dof_count(n[4]) for n in nodes)
    M = check_matrix(M, f"mass matrix M of body '{name}'{origin['mass']}", size, origin["nodes"])
    K = check_matrix(K, f"stiffness matrix K of body '{name}'{origin['stiffness']}", size, origin["nodes"])
    interfaces = check_interfaces(interfaces, nodes, name)

    mass_file, stiffness_file = matrix_file_names(name, fmt)
    nodes_file, snippet_file = f"{name}_nodes.txt", f"{name}.body.yaml"
    writer = _write_petsc if fmt == "petsc" else _write_mtx
    jobs = [
        (mass_file, lambda path: writer(path, M)),
        (stiffness_file, lambda path: writer(path, K)),
        (nodes_file, lambda path: _write_nodes(path, nodes, name)),
        (snippet_file, lambda path: _write_snippet(
            path, name, mass_file, stiffness_file, nodes_file, interfaces, size)),
    ]
    _write_all_or_nothing(out_dir, jobs)
    return {key: os.path.join(out_dir, file_name) for key, (file_name, _) in
            zip(("mass", "stiffness", "nodes", "snippet"), jobs)}


def _write_all_or_nothing(out_dir, jobs):
    """Write each job to a temporary file in out_dir; rename them all only if all succeeded."""
    temporaries = []
    created = not os.path.isdir(out_dir)
    try:
        if created:
            os.makedirs(out_dir)
        for file_name, write in jobs:
            handle, temp_path = tempfile.mkstemp(dir=out_dir, prefix=f".{file_name}.", suffix=".part")
            os.close(handle)
            temporaries.append((temp_path, os.path.join(out_dir, file_name)))
            write(temp_path)
        for temp_path, final_path in temporaries:
            commit(temp_path, final_path)
        created = False  # complete: keep the folder
    except OSError as exc:
        raise ConversionError(f"cannot write body files in {out_dir}: {exc}") from exc
    finally:
        for temp_path, _ in temporaries:
            for leftover in (temp_path, temp_path + ".info"):
                if os.path.exists(leftover):
                    os.remove(leftover)
        if created and os.path.isdir(out_dir) and not os.listdir(out_dir):
            os.rmdir(out_dir)


def _write_petsc(path, A):
    from petsc4py import PETSc  # imported here so the other formats work without PETSc

    if A.nnz > np.iinfo(PETSc.IntType).max:
        raise ConversionError(
            f"a matrix with {A.nnz} nonzeros exceeds this PETSc's {np.dtype(PETSc.IntType).itemsize * 8}-bit "
            "indices; use --format mtx")
    indptr = A.indptr.astype(PETSc.IntType)
    indices = A.indices.astype(PETSc.IntType)
    mat = PETSc.Mat().createAIJ(A.shape, csr=(indptr, indices, A.data.astype(PETSc.ScalarType)),
                                comm=PETSc.COMM_SELF)
    mat.assemble()
    try:
        viewer = PETSc.Viewer().createBinary(path, "w", comm=PETSc.COMM_SELF)
        try:
            mat.view(viewer)
        finally:
            viewer.destroy()
    except PETSc.Error as exc:
        raise OSError(f"PETSc cannot write a binary matrix there ({exc})") from None
    finally:
        mat.destroy()
    # PETSc adds <path>.info holding only "-matload_block_size 1" (the default): not part of the body.
    if os.path.exists(path + ".info"):
        os.remove(path + ".info")


def _write_mtx(path, A):
    # An open file: given a name, mmwrite would append ".mtx" to the temporary name.
    with open(path, "wb") as handle:
        scipy.io.mmwrite(handle, A, symmetry="symmetric", precision=17)


def _write_nodes(path, nodes, name):
    with open(path, "w", encoding="utf-8") as handle:
        handle.write(f"# nodes of kryflex body '{name}': id x y z dofs (6: ux uy uz rx ry rz, 3: ux uy uz, "
                     "c<components>: those Nastran components, s: a scalar point; dofs numbered node by node)\n")
        for node_id, x, y, z, ndof in nodes:
            handle.write(f"{node_id} {x!r} {y!r} {z!r} {ndof}\n")


def _write_snippet(path, name, mass_file, stiffness_file, nodes_file, interfaces, size):
    import yaml

    entry = {"bodies": {name: {"mass": mass_file, "stiffness": stiffness_file,
                               "nodes": nodes_file, "interfaces": dict(interfaces)}}}
    with open(path, "w", encoding="utf-8") as handle:
        handle.write(f"# kryflex body '{name}' ({size} dofs), written by kryflex convert.\n"
                     "# Paste the entry under `bodies:` of a scene file. Paths are relative to the\n"
                     "# scene file: keep the scene in this folder or prefix them with this folder.\n")
        yaml.safe_dump(entry, handle, default_flow_style=None, sort_keys=False)
