"""Writing result files so that a failure never leaves a half-written one: a temporary name in the same folder,
renamed into place when complete, with the permissions the umask gives any new file."""
import contextlib
import os
import tempfile


def file_mode():
    """The mode a new file gets under the current umask (mkstemp makes owner-only files)."""
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


def temporary_beside(path):
    """A new empty temporary file in path's folder; returns its name."""
    fd, tmp = tempfile.mkstemp(prefix="." + os.path.basename(path) + ".", suffix=".tmp",
                               dir=os.path.dirname(os.path.abspath(path)))
    os.close(fd)
    return tmp


def commit(tmp, path):
    """Gives the temporary file the usual permissions and renames it into place."""
    os.chmod(tmp, file_mode())
    os.replace(tmp, path)


@contextlib.contextmanager
def atomic_path(path):
    """with atomic_path(p) as tmp: write tmp; it becomes p only if the block succeeds."""
    tmp = temporary_beside(path)
    try:
        yield tmp
        commit(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
