"""The environment turns against a run: the disk fills (RLIMIT_FSIZE), the output folder is a file, a signal arrives
while the results are being written, a killed run left its staging folder; MPI ranks that disagree (MPMD: only one
rank has a bad option or scene); the accuracy target is missed.

- disk full: exit 4, earlier results byte-identical, nothing new (no staging folder, no .tmp), OUT absent if it was;
- SIGINT / SIGTERM (to the whole process group, as Ctrl-C or a batch system sends them): exit 130 / 143 (a death by
  the signal, -2 / -15 to Python, reads as the same code in a shell and is accepted), earlier results intact, no
  stray files; under mpiexec the ranks get the signal (see harness._signal_while_reducing);
- a stale .kryflex-* staging folder from a SIGKILLed run is removed by the next good run into the same OUT;
- MPMD: every rank exits 2, the error printed once, no hang;
- target missed: exit 6, the results written, summary.json "target_met": false, one line with the achieved error.
"""
import os
import signal
import time

from . import edits as e
from .harness import EXIT_INPUT, EXIT_OUTPUT, EXIT_SIGINT, EXIT_SIGTERM, EXIT_TARGET, FIX, Case

REDUCE = ("reduce", "{scene}", "-o", "{out}", "-quiet")
LOUD_REDUCE = ("reduce", "{scene}", "-o", "{out}")          # progress lines tell the signal cases when to strike
# the report (summary.json: ~700 kB) cannot be written under 200 kB per file; the model file (~75 kB) and each plot can
DISK = 200 << 10
FULL = ["re:space|full|too large|EFBIG|file size|limit"]
# the limit is set in each kryflex process once MPI has started (harness.disk_full_site); MPI's own shared memory
# (PMIx's dstore segments, the vader BTL's backing files) is kept off files too, so that only kryflex's writes meet
# the full disk
NO_MPI_FILES = (("PMIX_MCA_gds", "hash"), ("OMPI_MCA_btl", "self,tcp"))


def stale_staging(ctx):
    """What a SIGKILLed run leaves: a staging folder inside OUT with a half-written file, an hour old."""
    stale = os.path.join(ctx.out, ".kryflex-stage-killed")
    os.makedirs(stale)
    with open(os.path.join(stale, "summary.json"), "w") as f:
        f.write('{"half": ')
    old = time.time() - 3600
    os.utime(os.path.join(stale, "summary.json"), (old, old))
    os.utime(stale, (old, old))


ENV_CASES = [
    Case("env", "disk_full_new_output", None, argv=REDUCE, code=EXIT_OUTPUT, mentions=FULL, out="absent", fsize=DISK,
         env=NO_MPI_FILES),
    Case("env", "disk_full_earlier_output", None, argv=REDUCE, code=EXIT_OUTPUT, mentions=FULL, out="earlier",
         fsize=DISK, env=NO_MPI_FILES),
    Case("env", "disk_full_reassemble", None, argv=("reassemble", "{model}", "--angle", "30", "-o", "{out}"),
         code=EXIT_OUTPUT, mentions=["matrices.npz"] + FULL, out="absent", fsize=1024, out_name="matrices.npz",
         env=NO_MPI_FILES),
    Case("env", "output_folder_is_a_file", e.write("out", "keep me\n"), argv=REDUCE, code=EXIT_OUTPUT,
         mentions=["out", "re:not a folder|is a file|exists"], out="kept"),
    Case("env", "sigint_earlier_output", None, argv=LOUD_REDUCE, code=EXIT_SIGINT, kind="signal", signal=signal.SIGINT,
         out="earlier"),
    Case("env", "sigterm_earlier_output", None, argv=LOUD_REDUCE, code=EXIT_SIGTERM, kind="signal",
         signal=signal.SIGTERM, out="earlier"),
    Case("env", "sigint_new_output", None, argv=LOUD_REDUCE, code=EXIT_SIGINT, kind="signal", signal=signal.SIGINT,
         out="absent"),
    Case("env", "sigterm_new_output", None, argv=LOUD_REDUCE, code=EXIT_SIGTERM, kind="signal", signal=signal.SIGTERM,
         out="absent"),
    Case("env", "stale_staging_removed", stale_staging, argv=REDUCE + ("-scene.angles", "0", "-kf_verify", "0"),
         code=0, kind="accept_clean", out="earlier"),
]


def _bad_copy(name, old, new):
    """A broken copy of the scene beside the good one (rank 1 reads it)."""
    def prepare(ctx):
        with open(ctx.scene) as f:
            data = f.read()
        assert data.count(old) == 1
        with open(ctx.path(name), "w") as f:
            f.write(data.replace(old, new))
    return prepare


def MPMD(name, rank0, rank1, mentions, prepare=None, out="absent"):
    return Case("mpi", name, prepare, argv=rank0, mpmd=rank1, code=EXIT_INPUT, mentions=tuple(mentions), fix=FIX,
                out=out, ranks=(2,))


MPI_CASES = [
    MPMD("kf_moments_0_on_rank1_only", REDUCE, REDUCE + ("-kf_moments", "0"), ["re:moments"]),
    MPMD("kf_moments_0_on_rank0_only", REDUCE + ("-kf_moments", "0"), REDUCE, ["re:moments"]),
    MPMD("keep_threshold_on_rank1_only", REDUCE, REDUCE + ("-scene.reduction.keep_threshold", "1.5"),
         ["re:keep_threshold"], out="earlier"),
    MPMD("bad_scene_on_rank1_only", REDUCE, ("reduce", "{dir}/bad.yaml", "-o", "{out}", "-quiet"),
         ["re:damping|bad\\.yaml"], prepare=_bad_copy("bad.yaml", "damping: 0.0025", "damping: low")),
    MPMD("missing_scene_on_rank1_only", REDUCE, ("reduce", "{dir}/nothere.yaml", "-o", "{out}", "-quiet"),
         ["nothere.yaml"]),
    MPMD("info_bad_scene_on_rank1_only", ("info", "{scene}"), ("info", "{dir}/bad.yaml"), ["re:damping|bad\\.yaml"],
         prepare=_bad_copy("bad.yaml", "damping: 0.0025", "damping: low"), out="none"),
]

TARGET_CASES = [
    Case("target", "accuracy_1e-12_scene", None, argv=REDUCE + ("-scene.accuracy", "1e-12"), code=EXIT_TARGET,
         kind="target", out="earlier"),
    Case("target", "accuracy_1e-12_option", None, argv=REDUCE + ("-kf_accuracy", "1e-12"), code=EXIT_TARGET,
         kind="target", out="absent"),
]
