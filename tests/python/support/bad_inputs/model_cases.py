"""Reduced-model files that `kryflex reassemble` cannot use: exit 5, the file named with the fix (reduce again), and
the -o file not written (or an earlier one left byte-identical); kryflex.ReducedModel.load raises ModelFileError.

Each case starts from a copy of a good reduced.h5 (the session's real reduction of Galileo). Its datasets carry
HDF5's fletcher32 filter (src/io/model_hdf5.c WriteMatrix): flipping a stored byte breaks it, while an edit made
through HDF5 (h5py) recomputes it - such an edit is caught only by the reader's own consistency checks.
"""
import numpy as np

from . import edits as e
from .harness import EXIT_INPUT, EXIT_MODEL, EXIT_OK, FIX, Case

AGAIN = r"reduce|write it again|re-?run|give"


def M(name, prepare, mentions, argv=None, fix=AGAIN, code=EXIT_MODEL, out="absent", api="model", model="{model}"):
    """reassemble MODEL --angle 30 -o matrices.npz: the message names the model file."""
    argv = argv or ("reassemble", model, "--angle", "30", "-o", "{out}")
    return Case("model", name, prepare, argv=argv, code=code, mentions=(model.split("/")[-1].replace("{model}", "reduced.h5"),)
                + tuple(mentions), fix=fix, out=out, api=api, out_name="matrices.npz")


def _set_attr(path, key, value):
    return e.h5_edit(lambda f: f[path].attrs.__setitem__(key, value))


def _scale(dataset, factor):
    def fn(f):
        d = f[dataset]
        d[...] = d[...] * factor
    return e.h5_edit(fn)


def _asymmetric(dataset):
    def fn(f):
        d = f[dataset]
        a = d[...]
        a[0, 1] += 0.5 * abs(a).max()
        d[...] = a
    return e.h5_edit(fn)


def _nan(dataset):
    def fn(f):
        d = f[dataset]
        a = d[...]
        a[0, 0] = np.nan
        d[...] = a
    return e.h5_edit(fn)


def _reshape(dataset, cols):
    """The dataset replaced by one with another column count (fletcher32 as the writer does)."""
    def fn(f):
        a = f[dataset][...]
        del f[dataset]
        f.create_dataset(dataset, data=np.zeros((a.shape[0], cols)), chunks=(a.shape[0], cols), fletcher32=True)
    return e.h5_edit(fn)


def _delete(path):
    return e.h5_edit(lambda f: f.__delitem__(path))


def _delete_attr(path, key):
    return e.h5_edit(lambda f: f[path].attrs.__delitem__(key))


CASES = [
    M("missing", None, ["re:not found"], model="{dir}/nothere.h5", api=None),
    M("empty_file", e.write("reduced.h5", b""), ["re:empty|not an HDF5|truncated"]),
    M("not_hdf5", e.write("reduced.h5", "not an HDF5 file\n"), ["re:not an HDF5|not a kryflex"]),
    M("truncated_half", e.bytes_edit(lambda d: d[: len(d) // 2]), ["re:truncated|incomplete|damaged"]),
    M("truncated_tail", e.bytes_edit(lambda d: d[:-200]), ["re:truncated|incomplete|damaged"]),
    M("hdf5_not_kryflex", e.h5_edit(lambda f: [f.attrs.__delitem__(k) for k in list(f.attrs)]),
      ["re:not a kryflex|format"]),
    M("checksum_broken", e.flip_chunk_byte("bodies/rotor/K"), ["re:checksum|damaged", "re:bodies/rotor/K|rotor"]),
    M("format_version_newer", _set_attr("/", "version", 3), ["re:version", "3"], fix=r"reduce|upgrade|use|install"),
    M("format_name_other", _set_attr("/", "format", "someone-elses-model"), ["someone-elses-model"]),
    M("edited_K_asymmetric", _asymmetric("bodies/rotor/K"), ["re:bodies/rotor/K|rotor", "re:symmetric|edited|inconsistent"]),
    # K scaled by a negative factor: no longer positive semi-definite (a scaling by 1.01 is a consistent, stiffer
    # rotor that no check can tell from a reduction's: edited_K_scaled_consistent, accepted)
    M("edited_K_scaled", _scale("bodies/rotor/K", -1.01), ["re:bodies/rotor/K|rotor", "re:negative|definite|edited"]),
    # the reduced mass is the identity by construction (a mass-orthonormal basis): any other M was edited
    M("edited_M_not_identity", _scale("bodies/stator/M", 2.0), ["re:bodies/stator/M|stator",
                                                                "re:identity|edited|inconsistent"]),
    M("edited_nan", _nan("bodies/rotor/G"), ["re:bodies/rotor/G|rotor", "re:nan|finite"]),
    M("edited_G_shape", _reshape("bodies/rotor/G", 2), ["re:bodies/rotor/G|\\bG\\b", "re:shape|inputs|columns|2"]),
    M("missing_dataset", _delete("bodies/rotor/K"), ["re:bodies/rotor/K|\\bK\\b", "re:missing|no dataset|not found"]),
    M("missing_joint_attribute", _delete_attr("joints/spin_bearing", "axis"), ["axis"]),
    M("joint_parent_out_of_range", _set_attr("joints/spin_bearing", "parent", 7), ["spin_bearing", "parent"]),
    M("is_a_folder", e.make_folder("reduced.h5"), ["re:folder|directory"]),
    M("other_scene", e.other_scene, ["re:other\\.yaml|scene"],
      argv=("reassemble", "{model}", "--angle", "30", "--scene", "{dir}/other.yaml", "-o", "{out}")),
    M("earlier_output_kept", e.bytes_edit(lambda d: d[: len(d) // 2]), ["re:truncated|incomplete|damaged"],
      out="earlier"),
    # a stiffer rotor (K x 1.01: symmetric, semi-definite, its rigid motions still unstrained) is a valid model, as a
    # what-if edit may make on purpose: reassembled, not refused (the file holds no second copy of K to compare with)
    Case("model", "edited_K_scaled_consistent", _scale("bodies/rotor/K", 1.01),
         argv=("reassemble", "{model}", "--angle", "30", "-o", "{out}"), code=EXIT_OK, kind="accept", out_name="matrices.npz"),
    # --scene pointing at a bad scene: a bad input (2), not a bad model file
    Case("model", "scene_check_bad_scene", e.text("damping: 0.0025", "damping: low"),
         argv=("reassemble", "{model}", "--angle", "30", "--scene", "{scene}", "-o", "{out}"), code=EXIT_INPUT,
         mentions=("galileo.yaml", "damping", "low"), fix=FIX, out="absent", out_name="matrices.npz"),
]
