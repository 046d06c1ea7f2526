"""Bad command lines: unknown commands and options (with did-you-mean), missing arguments, bad values of the
command's own options and of -kf_ options, and -o where nothing can be written.

Exit 2 for the command line, 4 for an output that cannot be written; the message names the option and the value and
says what to do; nothing is left behind.
"""
from . import edits as e
from .harness import DID_YOU_MEAN, EXIT_INPUT, EXIT_OUTPUT, FIX, Case

REDUCE = ("reduce", "{scene}", "-o", "{out}", "-quiet")
REASSEMBLE = ("reassemble", "{model}")


def C(name, argv, mentions, fix=FIX, code=EXIT_INPUT, out="none", **kw):
    return Case("cli", name, kw.pop("prepare", None), argv=argv, code=code, mentions=tuple(mentions), fix=fix, out=out,
                **kw)


def K(name, option, value, mentions=(), fix=FIX, out="absent"):
    """A -kf_ option with a value the reducer refuses, on `kryflex reduce`."""
    return C(name, REDUCE + (option, value), (option, value) + tuple(mentions), fix=fix, out=out)


def file_at(name, content="keep me\n"):
    return e.write(name, content)


CASES = [
    C("unknown_command", ("reduse", "{scene}"), ["reduse", "reduce"], fix=DID_YOU_MEAN + "|use"),
    C("no_arguments", (), ["re:command|usage"]),
    C("reduce_no_scene", ("reduce", "-o", "{out}"), ["re:scene|SCENE"], out="absent"),
    C("reduce_no_output", ("reduce", "{scene}"), ["-o"]),
    C("info_no_scene", ("info",), ["re:scene|SCENE"]),
    C("info_extra_argument", ("info", "{scene}", "extra"), ["extra"]),
    C("reassemble_no_angle", REASSEMBLE, ["--angle"]),
    C("npz_misspelt", REDUCE + ("--npzz",), ["--npzz", "--npz"], fix=DID_YOU_MEAN, out="absent"),
    C("petsc_option_misspelt", REDUCE + ("-kf_momnets", "12"), ["-kf_momnets", "-kf_moments"], fix=DID_YOU_MEAN,
      out="absent"),
    C("modes_negative", REASSEMBLE + ("--angle", "30", "--modes", "-3"), ["--modes", "-3"]),
    C("angle_not_a_number", REASSEMBLE + ("--angle", "abc"), ["--angle", "abc"]),
    C("angle_count", REASSEMBLE + ("--angle", "30,40"), ["--angle", "30,40", "re:1 revolute|one revolute"]),
    C("angle_nan", REASSEMBLE + ("--angle", "nan"), ["--angle", "nan"]),
    K("kf_moments_0", "-kf_moments", "0"),
    K("kf_keep_threshold_2", "-kf_keep_threshold", "2", fix=r"\(0, 1\]|\(0,1\]|between 0 and 1|give|use"),
    K("kf_damping_not_a_number", "-kf_damping", "abc"),
    K("kf_reducer_type_misspelt", "-kf_reducer_type", "krylof", mentions=("krylov",)),
    C("kf_band_reversed", REDUCE + ("-kf_band", "10,0.01"), ["-kf_band", "re:10\\.?,\\s*0\\.01"], out="absent"),
    K("kf_method_misspelt", "-kf_method", "multi", mentions=("multi-angle",)),
    K("kf_verify_modes_negative", "-kf_verify_modes", "-7"),
    K("kf_accuracy_negative", "-kf_accuracy", "-1"),
    # -o where nothing can be written (tests may run as root: permission bits stop nothing, these places do)
    C("output_under_a_file", ("reduce", "{scene}", "-o", "{dir}/afile/out", "-quiet"), ["afile"], code=EXIT_OUTPUT,
      prepare=file_at("afile")),
    C("output_in_proc", ("reduce", "{scene}", "-o", "/proc/kryflex-out", "-quiet"), ["/proc/kryflex-out"],
      code=EXIT_OUTPUT, gone=("/proc/kryflex-out",)),
    C("output_in_sys", ("reduce", "{scene}", "-o", "/sys/kryflex-out", "-quiet"), ["/sys/kryflex-out"],
      code=EXIT_OUTPUT, gone=("/sys/kryflex-out",)),
    C("reassemble_output_is_a_folder", REASSEMBLE + ("--angle", "30", "-o", "{dir}/taken.npz"), ["taken.npz"],
      code=EXIT_OUTPUT, prepare=e.make_folder("taken.npz")),
    C("reassemble_output_in_proc", REASSEMBLE + ("--angle", "30", "-o", "/proc/kryflex.npz"), ["/proc/kryflex.npz"],
      code=EXIT_OUTPUT, gone=("/proc/kryflex.npz",)),
    C("convert_missing_input", ("convert", "{dir}/nothere.mtx", "--name", "x", "-o", "{out}"), ["nothere.mtx"],
      out="absent"),
]
