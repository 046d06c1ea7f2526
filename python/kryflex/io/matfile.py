"""`kryflex convert MODEL.mat`: a second-order model from a MATLAB file (MORwiki / SLICOT benchmark conventions)
written as one kryflex body of scalar points, its input and output vectors, and a scene file that runs as is.

    M q'' + D q' + K q = B u,    y = Cp q + Cv q'

Keys (each overridable): M mass, K stiffness, damping the first of D, E present (or C when the outputs are given as
Cp/Cv), B inputs (n x m), outputs C or Cp (p x n, displacements) and Cv (velocities). A model with only A, B, C
(first order) is refused: kryflex reduces structural second-order models. M and K must be symmetric and positive
semi-definite (measured: the relative asymmetry ||A - A^T||_F / ||A||_F, and the smallest eigenvalue of a dense copy
for models up to DENSE_CHECK_MAX dofs; larger models are left to the factorization's check in `kryflex reduce`).
"""
import os

import numpy as np
import scipy.io
import scipy.sparse as sp

from .bodyfiles import (ConversionError, _write_all_or_nothing, _write_mtx, _write_nodes, _write_petsc, check_matrix,
                        matrix_file_names)

__all__ = ["convert_mat", "DEFAULT_KEYS"]

DEFAULT_KEYS = {"mass": "M", "stiffness": "K", "damping": None, "input": "B", "output": None, "velocity_output": "Cv"}
ASYMMETRY_TOL = 1e-10       # relative Frobenius asymmetry refused above this (as the scene's damping-matrix check)
DENSE_CHECK_MAX = 4000      # definiteness measured on a dense copy up to this many dofs
NEGATIVE_TOL = 1e-9         # eigenvalue below -this x the largest: indefinite


def _load(path):
    try:
        data = scipy.io.loadmat(path)
    except NotImplementedError:
        raise ConversionError(f"{path} is a MATLAB v7.3 (HDF5) file, which scipy.io.loadmat cannot read: save it "
                              "again in MATLAB with save(..., '-v7')") from None
    except Exception as exc:  # noqa: BLE001 - loadmat raises ValueError, IndexError, TypeError, ... on a foreign file
        raise ConversionError(f"{path}: not a MATLAB .mat file scipy can read ({exc})") from None
    return {k: v for k, v in data.items() if not k.startswith("__")}


def _matrix(path, data, key, what):
    A = data[key]
    if sp.issparse(A):
        A = A.tocsr().astype(np.float64)
    else:
        A = np.asarray(A)
        if A.dtype.kind not in "biuf" or A.ndim != 2:
            raise ConversionError(f"{path}: {key} ({what}) is not a real 2-D matrix (dtype {A.dtype}, shape "
                                  f"{A.shape}); a complex or cell entry cannot be a structural matrix")
        A = A.astype(np.float64)
    return A


def _pick_keys(path, data, keys):
    """The keys of each part, from the overrides and the MORwiki conventions."""
    names = sorted(data)
    k = dict(DEFAULT_KEYS)
    k.update({a: b for a, b in keys.items() if b})
    if k["mass"] not in data or k["stiffness"] not in data:
        if "A" in data and k["mass"] not in data:
            raise ConversionError(f"{path} holds a first-order model (A, B, C: keys {', '.join(names)}): kryflex reduces "
                                  "second-order structural models M q'' + D q' + K q = B u; give a file with M and K "
                                  "(or name them with --mass-key/--stiffness-key)")
        missing = [x for x in (k["mass"], k["stiffness"]) if x not in data]
        raise ConversionError(f"{path} has no {' and no '.join(missing)} (keys: {', '.join(names)}): name the mass and "
                              "stiffness with --mass-key and --stiffness-key")
    n = data[k["stiffness"]].shape[0]
    given_output = keys.get("output")
    if k["output"] is None:
        k["output"] = "Cp" if "Cp" in data else "C" if "C" in data and not keys.get("damping") == "C" else None
    if k["damping"] is None:
        for cand in ("D", "E"):
            if cand in data:
                k["damping"] = cand
                break
        else:
            # C is the damping only when the outputs are named otherwise (Cp / Cv)
            if "C" in data and k["output"] != "C" and tuple(data["C"].shape) == (n, n):
                k["damping"] = "C"
    if k["output"] == "C" and not given_output and tuple(data["C"].shape) == (n, n) and "Cv" not in data:
        raise ConversionError(f"{path}: C is {n} x {n}: it may be the damping or {n} outputs; say which with "
                              "--damping-key C (and --output-key for the outputs) or --output-key C")
    for part in ("damping", "input", "output", "velocity_output"):
        if keys.get(part) and keys[part] not in data:
            raise ConversionError(f"{path} has no key {keys[part]} (keys: {', '.join(names)}): fix --{part.replace('_', '-')}-key")
    if k["input"] not in data:
        raise ConversionError(f"{path} has no input matrix {k['input']} (keys: {', '.join(names)}): name it with "
                              "--input-key")
    if k["output"] not in data and k["velocity_output"] not in data:
        raise ConversionError(f"{path} has no output matrix (C, Cp or Cv; keys: {', '.join(names)}): name it with "
                              "--output-key or --velocity-output-key")
    return k


def _check_definite(A, label):
    n = A.shape[0]
    if n > DENSE_CHECK_MAX:
        return None
    w = np.linalg.eigvalsh(A.toarray())
    top = max(abs(w).max(), 1e-300)
    if w[0] < -NEGATIVE_TOL * top:
        raise ConversionError(f"{label} is indefinite: its smallest eigenvalue is {w[0]:.3e} ({w[0] / top:.1e} of the "
                              "largest); kryflex needs positive semi-definite M and K: check the export (signs, units, "
                              "a constraint eliminated with the wrong sign)")
    return w


def _first_frequency(K, M):
    """The lowest flexible frequency (Hz) of a dense copy, or None (a large model, or no mass)."""
    n = K.shape[0]
    if n > DENSE_CHECK_MAX:
        return None
    import scipy.linalg as sl
    Md, Kd = M.toarray(), K.toarray()
    keep = np.flatnonzero(np.diag(Md) > 0)
    try:
        w = sl.eigh(Kd[np.ix_(keep, keep)], Md[np.ix_(keep, keep)], eigvals_only=True)
    except (np.linalg.LinAlgError, ValueError):
        return None
    w = w[w > 1e-8 * max(abs(w).max(), 1e-300)]
    return float(np.sqrt(w[0]) / (2 * np.pi)) if len(w) else None


def convert_mat(path, out_dir, name, fmt="petsc", keys=None):
    """Writes the body files, vectors and <name>.yaml of the second-order model in path to out_dir. Returns
    {'files': [...], 'scene': path, 'dofs': n, 'inputs': m, 'outputs': p, 'damping': key or None, 'band': [lo, hi]}.
    Raises ConversionError naming the key and the fix; nothing is written then."""
    data = _load(path)
    k = _pick_keys(path, data, dict(keys or {}))
    n = data[k["stiffness"]].shape[0]
    nodes = [(i + 1, 0.0, 0.0, 0.0, "s") for i in range(n)]
    where = lambda key, what: f"{what} {key} of {path}"  # noqa: E731
    M = check_matrix(_matrix(path, data, k["mass"], "mass"), where(k["mass"], "mass matrix"), n)
    K = check_matrix(_matrix(path, data, k["stiffness"], "stiffness"), where(k["stiffness"], "stiffness matrix"), n)
    D = None
    if k["damping"]:
        D = check_matrix(_matrix(path, data, k["damping"], "damping"), where(k["damping"], "damping matrix"), n)
        if np.any(D.diagonal() < 0):
            raise ConversionError(f"damping matrix {k['damping']} of {path} has a negative diagonal entry "
                                  f"({D.diagonal().min():.3e}): check its sign")
    for A, key, what in ((M, k["mass"], "mass matrix"), (K, k["stiffness"], "stiffness matrix")):
        _check_definite(A, where(key, what))
    B = _matrix(path, data, k["input"], "inputs")
    B = B.toarray() if sp.issparse(B) else B
    if B.shape[0] != n and B.shape[1] == n:
        B = B.T
    if B.shape[0] != n:
        raise ConversionError(f"input matrix {k['input']} of {path} is {B.shape[0]} x {B.shape[1]}, the model has {n} "
                              "dofs: give an n x m input matrix")
    outputs = []
    for key, quantity in ((k["output"], "displacement"), (k["velocity_output"], "velocity")):
        if key not in data:
            continue
        C = _matrix(path, data, key, "outputs")
        C = C.toarray() if sp.issparse(C) else C
        if C.shape[1] != n and C.shape[0] == n:
            C = C.T
        if C.shape[1] != n:
            raise ConversionError(f"output matrix {key} of {path} is {C.shape[0]} x {C.shape[1]}, the model has {n} "
                                  "dofs: give a p x n output matrix")
        for r in range(C.shape[0]):
            if np.any(C[r]):
                outputs.append((("v%d" if quantity == "velocity" else "y%d") % (r + 1), C[r], quantity))
    if not outputs:
        raise ConversionError(f"{path}: every output row is zero: give an output matrix that reads the model")
    for A, label in ((B, "input"), (np.array([o[1] for o in outputs]), "output")):
        if not np.all(np.isfinite(A)):
            raise ConversionError(f"{path}: the {label} matrix holds a value that is not finite: fix the export")
    f1 = _first_frequency(K, M)
    band = [round(f1 / 100, 6), round(5 * f1, 6)] if f1 else [0.01, 100.0]

    mass_file, stiffness_file = matrix_file_names(name, fmt)
    damping_file = mass_file.replace("_M.", "_D.")
    writer = _write_petsc if fmt == "petsc" else _write_mtx
    jobs = [(mass_file, lambda p: writer(p, M)), (stiffness_file, lambda p: writer(p, K)),
            (f"{name}_nodes.txt", lambda p: _write_nodes(p, nodes, name))]
    if D is not None:
        jobs.append((damping_file, lambda p: writer(p, D)))
    inputs = {}
    for j in range(B.shape[1]):
        fname = f"{name}_u{j + 1}.txt"
        jobs.append((fname, lambda p, v=B[:, j]: np.savetxt(p, v, fmt="%.17g")))
        inputs["u%d" % (j + 1)] = [{"body": name, "vector": fname}]
    out_spec = {}
    for oname, row, quantity in outputs:
        fname = f"{name}_{oname}.txt"
        jobs.append((fname, lambda p, v=row: np.savetxt(p, v, fmt="%.17g")))
        term = {"body": name, "vector": fname}
        if quantity != "displacement":
            term["quantity"] = quantity
        out_spec[oname] = [term]
    body = {"mass": mass_file, "stiffness": stiffness_file, "nodes": f"{name}_nodes.txt"}
    if D is not None:
        body["damping"] = damping_file
    scene_file = f"{name}.yaml"
    jobs.append((scene_file, lambda p: _write_scene(p, path, name, body, inputs, out_spec, band, f1, D is not None,
                                                    k)))
    _write_all_or_nothing(out_dir, jobs)
    return dict(files=[os.path.join(out_dir, j[0]) for j in jobs], scene=os.path.join(out_dir, scene_file), dofs=n,
                inputs=B.shape[1], outputs=len(outputs), damping=k["damping"], band=band, first_hz=f1)


def _write_scene(p, source, name, body, inputs, outputs, band, f1, damped, keys):
    import yaml
    with open(p, "w", encoding="utf-8") as fh:
        fh.write(f"# kryflex scene of the second-order model in {os.path.basename(source)}, written by kryflex convert\n"
                 f"# (keys: mass {keys['mass']}, stiffness {keys['stiffness']}, damping {keys['damping'] or 'none'}, "
                 f"inputs {keys['input']}, outputs {keys['output'] or '-'} / velocity {keys['velocity_output']}).\n"
                 "# Every dof is a scalar point (node 's'): the file gives no geometry, so no rigid-body modes are\n"
                 "# derived; a model with rigid-body motion needs its nodes (see docs/guide/real-models.md).\n")
        yaml.safe_dump({"name": name, "bodies": {name: body}, "inputs": inputs, "outputs": outputs}, fh,
                       default_flow_style=None, sort_keys=False)
        fh.write("# GUESSES: edit them. The band runs from 1/100 to 5 x the first flexible frequency "
                 + (f"({f1:.6g} Hz)" if f1 else "(not computed: a large model; set it)") + "\n")
        fh.write(f"band: [{band[0]!r}, {band[1]!r}]\n")
        fh.write("accuracy: 0.01                  # GUESS: relative H-inf error per input/output pair\n")
        if damped:
            fh.write("# no damping key: the model's damping matrix is the whole damping (no modal damping added)\n")
        else:
            fh.write("damping: 0.0025                 # GUESS: the file has no damping matrix; a modal ratio\n")
