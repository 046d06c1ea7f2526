"""A full disk for the kryflex command in a test: a sitecustomize (in a folder put on PYTHONPATH) that sets
RLIMIT_FSIZE in each kryflex process. Python ignores SIGXFSZ, so a write past the limit fails with EFBIG ("File too
large"), as on a full disk. Shared by commands/test_collective_errors.py and the bad-input harness
(bad_inputs/harness.py).

The limit is set once MPI has started (right after kryflex.init), never before: PMIx and the shared-memory transport
size their files with ftruncate, and a limit set before MPI_Init (e.g. by preexec_fn) makes MPI_Init fail or
mpiexec's helpers die of SIGXFSZ. The disk is then full for kryflex, not for MPI's start-up.
"""
import os

# kryflex.init, wrapped: `start` is the library's own; AFTER_INIT runs once MPI has started
_WRAP_INIT = ("import resource, kryflex, kryflex._runtime as rt\n"
              "start, done = rt.init, []\n"
              "def init(argv=None):\n"
              "    start(argv)\n"
              "%s"
              "rt.init = kryflex.init = init\n")


def after_init(nbytes):
    """The source of a sitecustomize that limits every file a kryflex process writes to nbytes."""
    return _WRAP_INIT % ("    resource.setrlimit(resource.RLIMIT_FSIZE, (%d, %d))\n" % (nbytes, nbytes))


def at_model_save(nbytes):
    """The source of a sitecustomize that limits files to nbytes from the moment the command starts writing reduced.h5
    (ReducedModel.save): every file written before the model file is written whole."""
    return _WRAP_INIT % ("    if done:\n"
                         "        return\n"                      # the binding's own import calls init again
                         "    done.append(1)\n"
                         "    import kryflex.api as api\n"
                         "    save = api.ReducedModel.save\n"
                         "    def limited(self, path):\n"
                         "        resource.setrlimit(resource.RLIMIT_FSIZE, (%d, %d))\n"
                         "        return save(self, path)\n"
                         "    api.ReducedModel.save = limited\n" % (nbytes, nbytes))


def write_site(folder, source):
    """folder/sitecustomize.py holding source (after_init or at_model_save); returns folder, for PYTHONPATH."""
    folder = str(folder)
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, "sitecustomize.py"), "w") as f:
        f.write(source)
    return folder
