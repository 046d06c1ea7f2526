"""Writing result files so that a failure never leaves a half-written one: a temporary name in the same folder,
renamed into place when complete, with the permissions the umask gives any new file; and, for a command's whole set
of results, a staging folder inside the output folder (Staging), moved into place only when everything is written."""
import contextlib
import errno
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


# ---------------------------------------------------------------------------------------------- staging folders

STAGING_PREFIX = ".kryflex-"


def _process_alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:
        return True          # alive, someone else's
    return True


def remove_stale_staging(folder):
    """Removes staging folders left in folder by a run of this host that no longer runs (killed by SIGKILL, or
    aborted); returns their names. Another host's folder is left alone: its run may still be going."""
    import shutil
    import socket
    host, removed = socket.gethostname(), []
    try:
        names = os.listdir(folder)
    except OSError:
        return removed
    for name in names:
        if not name.startswith(STAGING_PREFIX):
            continue
        parts = name[len(STAGING_PREFIX):].rsplit("-", 2)     # <host>-<pid>-<random>
        if len(parts) == 3 and parts[0] == host and parts[1].isdigit() and _process_alive(int(parts[1])):
            continue
        if len(parts) == 3 and parts[0] != host:
            continue
        shutil.rmtree(os.path.join(folder, name), ignore_errors=True)
        removed.append(name)
    return removed


class Staging:
    """New result files for a folder, written into a hidden folder inside it (.kryflex-<host>-<pid>-<random>) and
    moved into place together by commit(): until then nothing visible changes in the folder, and discard() leaves
    it as it was. Files of earlier runs that a commit replaces are kept aside until every move succeeded, so a
    failing move puts them back."""

    def __init__(self, folder, path=None):
        self.folder = folder
        self.path = path

    def create(self):
        import socket
        self.path = tempfile.mkdtemp(prefix="%s%s-%d-" % (STAGING_PREFIX, socket.gethostname(), os.getpid()),
                                     dir=self.folder)
        return self.path

    def file(self, name):
        """Where the new file name is written."""
        return os.path.join(self.path, name)

    def commit(self):
        """Moves every staged file into the folder; returns their final paths. On failure the folder's earlier files
        are restored and the error raised."""
        names = sorted(n for n in os.listdir(self.path) if not n.startswith("."))
        for name in names:      # never move a user's folder (or anything but a file) aside
            final = os.path.join(self.folder, name)
            if os.path.lexists(final) and (os.path.isdir(final) or not os.path.isfile(final)):
                raise IsADirectoryError(errno.EISDIR, "%s is in the way of the new %s" % (
                    "a folder" if os.path.isdir(final) else "something other than a file", name), final)
        aside = os.path.join(self.path, ".previous")
        os.mkdir(aside)
        moved, kept = [], []
        try:
            for name in names:
                final = os.path.join(self.folder, name)
                if os.path.lexists(final):
                    os.replace(final, os.path.join(aside, name))
                    kept.append(name)
                os.replace(os.path.join(self.path, name), final)
                moved.append(name)
        except BaseException:
            for name in moved:
                os.replace(os.path.join(self.folder, name), os.path.join(self.path, name))
            for name in kept:
                os.replace(os.path.join(aside, name), os.path.join(self.folder, name))
            raise
        self.discard()
        return [os.path.join(self.folder, n) for n in names]

    def discard(self):
        import shutil
        if self.path and os.path.isdir(self.path):
            shutil.rmtree(self.path, ignore_errors=True)
