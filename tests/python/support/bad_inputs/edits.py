"""Breaking a fresh copy of Galileo one thing at a time: each helper returns prepare(ctx) for a Case.

Text edits (replace_once) keep the file as a user wrote it, for what YAML round trips would hide (duplicate keys,
encodings, aliases, comments); spec edits (set_key, rename) load, change and dump the scene.
"""
import os
import struct

import numpy as np
import scipy.io
import scipy.sparse as sp
import yaml

from .harness import ROOT

import sys
sys.path.insert(0, os.path.join(ROOT, "meshes"))
import frames  # noqa: E402  (the scene generators' PETSc binary writer)


def replace_once(path, old, new):
    with open(path) as f:
        text = f.read()
    assert text.count(old) == 1, "%s: expected %r exactly once (has meshes/galileo changed?)" % (path, old)
    with open(path, "w") as f:
        f.write(text.replace(old, new))


def text(old, new, name="galileo.yaml"):
    """Replaces one exact piece of a file of the copy."""
    def prepare(ctx):
        replace_once(ctx.path(name), old, new)
    return prepare


def all_of(*prepares):
    def prepare(ctx):
        for p in prepares:
            p(ctx)
    return prepare


def load_spec(ctx):
    with open(ctx.scene) as f:
        return yaml.safe_load(f)


def dump_spec(ctx, spec):
    with open(ctx.scene, "w") as f:
        yaml.safe_dump(spec, f, sort_keys=False, default_flow_style=None, allow_unicode=True)


def spec_edit(fn):
    """fn(spec) changes the loaded scene in place; the scene is written back."""
    def prepare(ctx):
        spec = load_spec(ctx)
        fn(spec)
        dump_spec(ctx, spec)
    return prepare


def set_key(path, value):
    """set_key('reduction.keep_threshold', 1.5): one scene value (missing mappings are created)."""
    def fn(spec):
        keys = path.split(".")
        node = spec
        for k in keys[:-1]:
            node = node.setdefault(k, {})
        node[keys[-1]] = value
    return spec_edit(fn)


def del_key(path):
    def fn(spec):
        keys = path.split(".")
        node = spec
        for k in keys[:-1]:
            node = node[k]
        del node[keys[-1]]
    return spec_edit(fn)


def _renamed(d, old, new):
    return {(new if k == old else k): v for k, v in d.items()}


def rename_body(old, new):
    """A body renamed everywhere it is named (bodies, joints, input and output terms)."""
    def fn(spec):
        spec["bodies"] = _renamed(spec["bodies"], old, new)
        for j in spec["joints"].values():
            for key in ("parent", "child"):
                if j[key] == old:
                    j[key] = new
        for key in ("inputs", "outputs"):
            for terms in spec[key].values():
                for t in terms:
                    if t.get("body") == old:
                        t["body"] = new
    return spec_edit(fn)


def rename_joint(old, new):
    return spec_edit(lambda spec: spec.__setitem__("joints", _renamed(spec["joints"], old, new)))


def rename_io(key, old, new):
    return spec_edit(lambda spec: spec.__setitem__(key, _renamed(spec[key], old, new)))


def rename_interface(body, old, new):
    """An interface renamed in its body and in the joints that use it."""
    def fn(spec):
        b = spec["bodies"][body]
        b["interfaces"] = _renamed(b["interfaces"], old, new)
        for j in spec["joints"].values():
            for side in ("parent", "child"):
                if j[side] == body and j[side + "_interface"] == old:
                    j[side + "_interface"] = new
    return spec_edit(fn)


def write(name, content):
    """Writes a file of the copy (str: UTF-8 text; bytes as they are)."""
    def prepare(ctx):
        mode = "wb" if isinstance(content, bytes) else "w"
        with open(ctx.path(name), mode) as f:
            f.write(content)
    return prepare


def remove(name):
    def prepare(ctx):
        os.remove(ctx.path(name))
    return prepare


def make_folder(name):
    """A folder where a file is expected (the file itself removed)."""
    def prepare(ctx):
        p = ctx.path(name)
        if os.path.isfile(p):
            os.remove(p)
        os.makedirs(p)
    return prepare


def append_yaml(extra):
    """Appends raw YAML text to the scene."""
    def prepare(ctx):
        with open(ctx.scene, "a") as f:
            f.write(extra)
    return prepare


# ---------------------------------------------------------------------------------------------- YAML abuse

def alias_bomb(levels=9, width=9):
    """A 'billion laughs': each level a list of `width` aliases of the one below (9^9 leaves once expanded)."""
    lines = ["a0: &a0 [lol]"]
    for i in range(1, levels + 1):
        lines.append("a%d: &a%d [%s]" % (i, i, ", ".join(["*a%d" % (i - 1)] * width)))
    body = "\n".join("  " + ln for ln in lines)
    return append_yaml("description:\n%s\n" % body)


def deep_nesting(depth=40):
    """A value nested deeper than 32 levels (flow lists)."""
    return append_yaml("description: %s1%s\n" % ("[" * depth, "]" * depth))


def huge_scene(nbytes=128 << 20):
    """A scene file padded with comment lines to nbytes: refused for its size, quickly, not parsed for minutes."""
    def prepare(ctx):
        line = "# " + "x" * 1021 + "\n"
        with open(ctx.scene, "a") as f:
            block = line * 1024
            for _ in range(nbytes // len(block)):
                f.write(block)
    return prepare


def non_utf8_scene(ctx):
    """The scene's name in Latin-1 (an editor's 'é' saved in ISO-8859-1)."""
    with open(ctx.scene, "rb") as f:
        data = f.read()
    assert data.count(b"name: galileo\n") == 1
    with open(ctx.scene, "wb") as f:
        f.write(data.replace(b"name: galileo\n", b"name: galil\xe9o\n"))


# ---------------------------------------------------------------------------------------------- Matrix Market

def read_mtx(ctx, name):
    return scipy.io.mmread(ctx.path(name)).toarray()


def write_mtx(ctx, name, A, symmetry):
    with open(ctx.path(name), "wb") as f:
        scipy.io.mmwrite(f, sp.coo_matrix(A), symmetry=symmetry, precision=17)


def mtx_lines(ctx, name):
    with open(ctx.path(name)) as f:
        return f.read().split("\n")


def mtx_edit(name, fn):
    """fn(header_lines, size_line, entry_lines) -> (header_lines, size_line, entry_lines): a raw edit of a .mtx."""
    def prepare(ctx):
        lines = [ln for ln in mtx_lines(ctx, name)]
        if lines and lines[-1] == "":
            lines.pop()
        k = 0
        while lines[k].startswith("%"):
            k += 1
        header, size, entries = lines[:k], lines[k], lines[k + 1:]
        header, size, entries = fn(header, size, entries)
        with open(ctx.path(name), "w") as f:
            f.write("\n".join(header + [size] + entries) + "\n")
    return prepare


def mtx_banner(name, banner):
    return mtx_edit(name, lambda h, s, e: ([banner] + h[1:], s, e))


def mtx_entry(name, index, new):
    """Replaces entry line `index` (0-based among the entries)."""
    def fn(h, s, e):
        e = list(e)
        e[index] = new
        return h, s, e
    return mtx_edit(name, fn)


def mtx_append_entries(name, extra, bump_count):
    """Appends entry lines; bump_count: also raise the declared count (else the file holds more than it declares)."""
    def fn(h, s, e):
        if bump_count:
            r, c, n = s.split()
            s = "%s %s %d" % (r, c, int(n) + len(extra))
        return h, s, list(e) + list(extra)
    return mtx_edit(name, fn)


def mtx_size_line(name, new):
    return mtx_edit(name, lambda h, s, e: (h, new, e))


def cut_mtx(name, inside_line):
    """Cuts a .mtx half-way, after a complete entry line or in the middle of one (a copy that failed)."""
    def prepare(ctx):
        with open(ctx.path(name)) as f:
            data = f.read()
        cut = data.index("\n", len(data) // 2) + (4 if inside_line else 1)
        with open(ctx.path(name), "w") as f:
            f.write(data[:cut])
    return prepare


def nonsymmetric_general(ctx):
    K = read_mtx(ctx, "stator_K.mtx")
    K[0, 5] += 0.1 * np.abs(K).max()
    write_mtx(ctx, "stator_K.mtx", K, "general")


def both_triangles_symmetric(ctx):
    """A symmetric header over a file holding both triangles (an exporter that wrote the full matrix)."""
    K = sp.coo_matrix(read_mtx(ctx, "stator_K.mtx"))
    with open(ctx.path("stator_K.mtx"), "w") as f:
        f.write("%%%%MatrixMarket matrix coordinate real symmetric\n%d %d %d\n" % (K.shape[0], K.shape[1], K.nnz))
        f.writelines("%d %d %.17g\n" % (r + 1, c + 1, v) for r, c, v in zip(K.row, K.col, K.data))


def negative_diagonal(ctx):
    K = read_mtx(ctx, "rotor_K.mtx")
    K[8, 8] = -K[8, 8]
    write_mtx(ctx, "rotor_K.mtx", K, "symmetric")


def negative_eigenvalue(ctx):
    """K - 2 lambda_7 (M phi_7)(M phi_7)^T: the first flexible eigenvalue changes sign, the rigid modes stay
    (phi_7 is M-orthogonal to them) and the diagonal stays positive, so only a factorization can tell."""
    import scipy.linalg as sl
    K, M = read_mtx(ctx, "rotor_K.mtx"), read_mtx(ctx, "rotor_M.mtx")
    lam, phi = sl.eigh(K, M)
    v = M @ phi[:, 6]
    K = K - 2 * lam[6] * np.outer(v, v)
    K = 0.5 * (K + K.T)
    new = sl.eigh(K, M, eigvals_only=True)
    assert new[0] < -0.5 * lam[6] and np.diag(K).min() > 0, "the construction should hide one negative eigenvalue"
    write_mtx(ctx, "rotor_K.mtx", K, "symmetric")


def crlf(name):
    def prepare(ctx):
        with open(ctx.path(name), "rb") as f:
            data = f.read()
        with open(ctx.path(name), "wb") as f:
            f.write(data.replace(b"\n", b"\r\n"))
    return prepare


def comments_and_blank_lines(name):
    """Comment lines after the banner and blank lines between entries (both allowed by the format)."""
    def fn(h, s, e):
        e = list(e)
        return h + ["% exported by a test", "%"], s, e[:3] + [""] + e[3:6] + ["", ""] + e[6:]
    return mtx_edit(name, fn)


# ---------------------------------------------------------------------------------------------- PETSc binary

def as_petsc(ctx, name="rotor_K"):
    """The body matrix as PETSc binary (the scene then points to it); returns the file's bytes."""
    path = ctx.path(name + ".petsc")
    frames.write_petsc_binary(path, read_mtx(ctx, name + ".mtx"))
    replace_once(ctx.scene, name + ".mtx", name + ".petsc")
    with open(path, "rb") as f:
        return bytearray(f.read())


def petsc_edit(fn, name="rotor_K"):
    """fn(bytearray) -> bytes: a raw edit of the PETSc binary file."""
    def prepare(ctx):
        data = as_petsc(ctx, name)
        with open(ctx.path(name + ".petsc"), "wb") as f:
            f.write(bytes(fn(data)))
    return prepare


def petsc_truncated(data):
    return data[: len(data) // 2]


def petsc_first_column(value):
    """The first column index (after the 4-int header and the row lengths) set to value."""
    def fn(data):
        _, m, _, _ = struct.unpack(">4i", data[:16])
        first = 16 + 4 * m
        data[first:first + 4] = struct.pack(">i", value)
        return data
    return fn


def petsc_classid(data):
    data[0:4] = struct.pack(">i", 1211214)        # a Vec's class id, not a Mat's
    return data


def petsc_nnz(data):
    """The header's nonzero count one more than the row lengths add up to."""
    cls, m, n, nz = struct.unpack(">4i", data[:16])
    data[0:16] = struct.pack(">4i", cls, m, n, nz + 1)
    return data


def petsc_nan_value(data):
    """The last stored value made a NaN (values are the file's last nz doubles)."""
    data[-8:] = struct.pack(">d", float("nan"))
    return data


# ---------------------------------------------------------------------------------------------- load vectors

def use_load_vector(name="load.txt", values=None):
    """The rotor's input term as a whole load vector read from a file (one entry per rotor dof: 21)."""
    def prepare(ctx):
        v = np.zeros(21) if values is None else np.asarray(values, dtype=float)
        if values is None:
            v[5] = -1.0                          # the hub's rz, as the point load it replaces
        with open(ctx.path(name), "w") as f:
            f.write("# rotor load vector\n" + "\n".join(repr(float(x)) for x in v) + "\n")
        replace_once(ctx.scene, "{body: rotor, node: 101, dof: rz, weight: -1.0}", "{body: rotor, vector: %s}" % name)
    return prepare


# ---------------------------------------------------------------------------------------------- model files (HDF5)

def h5_edit(fn, name="reduced.h5"):
    """fn(h5py.File) edits the copy of the good reduced model through HDF5 (checksums recomputed by the library)."""
    def prepare(ctx):
        import h5py
        with h5py.File(ctx.path(name), "r+") as f:
            fn(f)
    return prepare


def bytes_edit(fn, name="reduced.h5"):
    def prepare(ctx):
        with open(ctx.path(name), "rb") as f:
            data = bytearray(f.read())
        with open(ctx.path(name), "wb") as f:
            f.write(bytes(fn(data)))
    return prepare


def flip_chunk_byte(dataset):
    """One byte of a dataset's stored chunk flipped behind HDF5's back: its fletcher32 checksum no longer holds."""
    def prepare(ctx):
        import h5py
        with h5py.File(ctx.model, "r") as f:
            info = f[dataset].id.get_chunk_info(0)
        with open(ctx.model, "r+b") as f:
            f.seek(info.byte_offset + 17)
            b = f.read(1)
            f.seek(info.byte_offset + 17)
            f.write(bytes([b[0] ^ 0x5A]))
    return prepare


def other_scene(ctx):
    """A second scene beside the first, with another output (the same bodies): its model cannot serve the first."""
    with open(ctx.scene) as f:
        data = f.read()
    with open(ctx.path("other.yaml"), "w") as f:
        f.write(data.replace("pointA_ry: [{body: stator, node: 2, dof: ry}]", "pointA_rx: [{body: stator, node: 2, dof: rx}]"))
