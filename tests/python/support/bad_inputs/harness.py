"""What every bad-input case shares: the Case record, editing a copy of Galileo, running the command (serial, under
mpiexec -n 2, or MPMD) with a timeout, and the checks every refusal must pass.

What a refusal must do is tested, not what today's code does:
- exit code from one table (the manual's "Troubleshooting and exit codes") (2 input, 3 numeric, 4 output, 5 model file, 6 target missed, 130 SIGINT, 143 SIGTERM);
- one line `kryflex: error: <message>` on stderr, printed once whatever the number of ranks, no traceback;
- the message names the entry/file and the offending value, and says what to do;
- no partial output: an OUT that did not exist does not exist after; an OUT holding earlier results is
  byte-identical after, with no new file or folder (no staging folder, no .tmp);
- never hang: every command runs under a timeout and a timeout fails the case as a hang.
"""
import dataclasses
import hashlib
import os
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
from typing import Callable, Optional

import disk_full  # support/, on sys.path from tests/python/conftest.py

HERE = os.path.dirname(os.path.abspath(__file__))
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
ROOT = run_env.ROOT
GALILEO_DIR = os.path.join(ROOT, "meshes", "galileo")
COMMAND = run_env.KRYFLEX
ENV = dict(run_env.ENV, MPLBACKEND="Agg", PYTHONPATH=run_env.PYTHONPATH)

# the documented exit-code table (python/kryflex/cli/common.py holds the same constants)
EXIT_OK, EXIT_INTERNAL, EXIT_INPUT, EXIT_NUMERIC, EXIT_OUTPUT, EXIT_MODEL, EXIT_TARGET = 0, 1, 2, 3, 4, 5, 6
EXIT_SIGINT, EXIT_SIGTERM = 130, 143

# seconds per command: a hang is a failed case, not a stuck CI job. Generous: CI has 2 cores and runs 2 cases at once.
TIMEOUT_FAST, TIMEOUT_REDUCE = 45, 90

# "says what to do": an imperative starting a clause, lenient about the wording (give a value in (0, 1]; fix the path;
# re-export the matrix; ...). "write" alone would match "cannot write", so a verb must open a clause.
FIX_VERBS = (r"give|use|fix|re-?export|choose|remove|rename|renumber|save|keep|declare|write|add|list|set|correct|"
             r"check|delete|free|reduce|convert|pass|make|quote|split|replace|run|try|put|spell|drop|read|export|"
             r"point|select|lower|raise|increase|decrease|type|specify|enter|provide|edit|shorten|indent|did you mean")
FIX = r"(^|[:;,.(\[{]\s*|\s-+\s*|\b(then|or|and|to|please)\s+)(%s)\b" % FIX_VERBS
DID_YOU_MEAN = r"did you mean"

ERROR_PREFIX = "kryflex: error:"


@dataclasses.dataclass
class Case:
    """One bad (or, with code 0, one good) input.

    cls, name   the class (scene, file, model, cli, env, mpi, target) and a readable name: the test id is cls-name-npN
    prepare     prepare(ctx): breaks the fresh copy of Galileo in ctx.dir (None: leave it as it is)
    argv        the command after 'kryflex', with {scene} {out} {dir} {model} {cache} placeholders
    code        the documented exit code
    mentions    what the message must name (case-insensitive substrings; 're:...' is a regular expression)
    fix         a pattern saying what to do (default: any imperative opening a clause)
    out         'none' (the command writes nothing), 'absent' (OUT does not exist before: not after either),
                'earlier' (OUT holds a good earlier result: byte-identical after, nothing added),
                'kept' (OUT is something prepare made, a file in the way: byte-identical after)
    api         'scene': kryflex.load_scene(ctx.scene) raises SceneError with the same content (serial case only);
                'model': kryflex.ReducedModel.load(ctx.model) raises ModelFileError; None: no in-process check
    ranks       the rank counts to run under (1: alone, 2: mpiexec -n 2)
    mpmd        for MPMD cases: rank 1's command after 'kryflex' (rank 0 runs argv): mpiexec -n 1 A : -n 1 B
    kind        'refuse' (the default), 'accept' (exit 0, no error line), 'target' (exit 6: written, marked missed),
                'signal' (a signal while reducing), 'accept_clean' (exit 0 and no stale staging folder left)
    signal      the signal of a 'signal' case
    fsize       RLIMIT_FSIZE in bytes, set in every kryflex process once MPI has started (see disk_full_site;
                Python ignores SIGXFSZ: writes get EFBIG)
    timeout     seconds before the case counts as a hang
    out_name    OUT's name in the case folder ('out' for reduce; a .npz file for reassemble -o)
    gone        paths outside the case folder that must not exist after the run (-o /proc/...)
    env         extra (name, value) environment pairs for the command
    why         one line: what the case is about (shown in failures)
    """
    cls: str
    name: str
    prepare: Optional[Callable] = None
    argv: tuple = ("info", "{scene}")
    code: int = EXIT_INPUT
    mentions: tuple = ()
    fix: str = FIX
    out: str = "none"
    api: Optional[str] = None
    ranks: tuple = (1, 2)
    mpmd: Optional[tuple] = None
    kind: str = "refuse"
    signal: int = 0
    fsize: int = 0
    timeout: int = 0
    out_name: str = "out"
    gone: tuple = ()
    env: tuple = ()
    why: str = ""

    def __post_init__(self):
        self.argv = tuple(self.argv)
        self.mentions = tuple(self.mentions)
        if not self.timeout:
            # a refusal before the reduction takes a second or two; a hang in MPI does not end by itself
            self.timeout = TIMEOUT_REDUCE if "reduce" in self.argv[:1] and self.mpmd is None else TIMEOUT_FAST
        assert re.fullmatch(r"[A-Za-z0-9_.+\-]+", self.name), self.name

    @property
    def command(self):
        return self.argv[0] if self.argv else ""

    def id(self, ranks):
        return "%s-%s-np%d" % (self.cls, self.name, ranks)


@dataclasses.dataclass
class Ctx:
    """Where a case runs: dir holds the copy of Galileo (dir/galileo.yaml), out the output folder or file."""
    dir: str
    out: str
    cache: str           # the good earlier result of `kryflex reduce meshes/galileo` (read-only: copy it)

    @property
    def scene(self):
        return os.path.join(self.dir, "galileo.yaml")

    @property
    def model(self):
        return os.path.join(self.dir, "reduced.h5")

    def path(self, name):
        return os.path.join(self.dir, name)

    def fill(self, words):
        return [str(w).format(scene=self.scene, out=self.out, dir=self.dir, model=self.model, cache=self.cache)
                for w in words]


@dataclasses.dataclass
class Outcome:
    argv: list
    returncode: Optional[int]
    stdout: str
    stderr: str
    seconds: float
    hang: bool = False
    note: str = ""           # what the harness itself saw (signal timing)
    before: dict = None      # snapshot of OUT (out == 'earlier')
    after: dict = None
    stray: list = None       # new paths in the case folder outside OUT
    touched: list = None     # input files changed by the run
    out_exists: bool = False


# ---------------------------------------------------------------------------------------------- snapshots

def snapshot(top, skip=None):
    """{relative path: digest} of everything under top (hidden entries included; folders as '<dir>')."""
    snap = {}
    if not os.path.lexists(top):
        return snap
    if not os.path.isdir(top) or os.path.islink(top):
        return {".": _digest(top)}
    for base, dirs, files in os.walk(top):
        rel = os.path.relpath(base, top)
        for d in dirs:
            p = os.path.join(base, d)
            if skip and os.path.abspath(p) == os.path.abspath(skip):
                continue
            snap[os.path.normpath(os.path.join(rel, d))] = "<dir>"
        if skip:
            dirs[:] = [d for d in dirs if os.path.abspath(os.path.join(base, d)) != os.path.abspath(skip)]
        for f in files:
            p = os.path.join(base, f)
            if skip and os.path.abspath(p) == os.path.abspath(skip):
                continue
            snap[os.path.normpath(os.path.join(rel, f))] = _digest(p)
    return snap


def _digest(path):
    try:
        st = os.lstat(path)
        if st.st_size > 16 << 20:      # the huge scene: size and time are enough
            return "size=%d mtime=%d" % (st.st_size, st.st_mtime_ns)
        with open(path, "rb") as f:
            return hashlib.sha256(f.read()).hexdigest()
    except OSError as e:
        return "unreadable (%s)" % e.strerror


# ---------------------------------------------------------------------------------------------- running

def command_line(case, ctx, ranks):
    argv = [COMMAND] + ctx.fill(case.argv)
    if case.mpmd is not None:
        return ["mpiexec", "-n", "1"] + argv + [":", "-n", "1", COMMAND] + ctx.fill(case.mpmd)
    if ranks > 1:
        return ["mpiexec", "-n", str(ranks)] + argv
    return argv


def disk_full_site(folder, nbytes):
    """A sitecustomize (in folder: for PYTHONPATH) that limits the files a kryflex process writes to nbytes once MPI
    has started (support/disk_full.py says why then)."""
    return disk_full.write_site(folder, disk_full.after_init(nbytes))


def _kill_group(proc):
    """The command, mpiexec and its ranks all run in their own session: stop them all."""
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    proc.wait()


# signal cases: the signal goes once the reduction is under way (its progress lines) and the results are being
# written (plots take seconds); if the run ends first the case cannot judge and says so
SIGNAL_AFTER = re.compile(r"multi-angle model|reduced bodies|alpha_G")


def execute(case, ctx, ranks, site=None):
    """Runs the case's command; site: a folder put first on PYTHONPATH (a sitecustomize: disk_full_site)."""
    argv = command_line(case, ctx, ranks)
    env = dict(ENV, **dict(case.env))
    if site:
        env["PYTHONPATH"] = site + ":" + env["PYTHONPATH"]
    kwargs = dict(env=env, cwd=ctx.dir, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                  errors="replace", start_new_session=True)
    t0 = time.monotonic()
    proc = subprocess.Popen(argv, **kwargs)
    note = ""
    if case.kind == "signal":
        stdout, stderr, hang, note = _signal_while_reducing(proc, case, t0, ranks)
    else:
        try:
            stdout, stderr = proc.communicate(timeout=case.timeout)
            hang = False
        except subprocess.TimeoutExpired:
            _kill_group(proc)
            stdout, stderr = proc.communicate()
            hang = True
    return Outcome(argv, None if hang else proc.returncode, stdout or "", stderr or "", time.monotonic() - t0, hang,
                   note)


def _job_processes(pid):
    """The processes below pid (mpiexec's ranks, found from /proc)."""
    children = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open("/proc/%s/stat" % entry) as f:
                    ppid = int(f.read().rsplit(")", 1)[1].split()[1])
            except (OSError, ValueError, IndexError):
                continue
            children.setdefault(ppid, []).append(int(entry))
    found, todo = [], [pid]
    while todo:
        for c in children.get(todo.pop(), []):
            found.append(c)
            todo.append(c)
    return found


def _signal_while_reducing(proc, case, t0, ranks):
    """Reads stdout until the reduction has produced its models, waits a little (the report is being written),
    then signals the run. Alone: its process group (a terminal's Ctrl-C, a kill). Under mpiexec: every rank, as a
    batch system signals each task - Open MPI's mpiexec, signalled itself, kills its ranks with SIGTERM and exits
    with 1 whatever they do, so the 130/143 a rank returns is seen only when the ranks get the signal."""
    out_lines, err_chunks = [], []
    seen = threading.Event()

    def pump_out():
        for line in proc.stdout:
            out_lines.append(line)
            if SIGNAL_AFTER.search(line):
                seen.set()

    def pump_err():
        err_chunks.append(proc.stderr.read())

    threads = [threading.Thread(target=pump_out, daemon=True), threading.Thread(target=pump_err, daemon=True)]
    for t in threads:
        t.start()
    seen.wait(timeout=case.timeout / 2)
    time.sleep(0.5)
    note = "signal sent %.1f s after start" % (time.monotonic() - t0)
    if proc.poll() is not None:
        note = "the run ended (exit %s) before the signal could be sent: cannot judge" % proc.returncode
    else:
        targets = [p for p in _job_processes(proc.pid) if _is_rank(p)] if ranks > 1 else []
        try:
            if ranks > 1:
                for p in targets:
                    os.kill(p, case.signal)
                note += " to %d rank(s)" % len(targets)
            else:
                os.killpg(proc.pid, case.signal)
        except ProcessLookupError:
            pass
    try:
        proc.wait(timeout=case.timeout)
        hang = False
    except subprocess.TimeoutExpired:
        _kill_group(proc)
        hang = True
    for t in threads:
        t.join(timeout=10)
    return "".join(out_lines), "".join(err_chunks), hang, note


def _is_rank(pid):
    try:
        with open("/proc/%d/cmdline" % pid, "rb") as f:
            return b"kryflex" in f.read()
    except OSError:
        return False


# ---------------------------------------------------------------------------------------------- one case

def fresh_copy(folder):
    shutil.copytree(GALILEO_DIR, folder, ignore=shutil.ignore_patterns("generate.py", "README.md", "__pycache__"))


def run_case(case, ranks, base, cache):
    """Prepares a fresh copy of Galileo in base/<id>, breaks it, runs the command; returns (ctx, outcome)."""
    folder = os.path.join(base, case.id(ranks))
    if os.path.exists(folder):
        shutil.rmtree(folder)
    fresh_copy(folder)
    ctx = Ctx(folder, os.path.join(folder, case.out_name), cache)
    shutil.copy(os.path.join(cache, "reduced.h5"), ctx.model)     # the good model file: model cases break it
    if case.out == "earlier":
        if case.out_name.endswith(".npz"):
            shutil.copy(os.path.join(cache, "reduced.npz"), ctx.out)
        else:
            shutil.copytree(cache, ctx.out)
    if case.prepare is not None:
        case.prepare(ctx)
    # outside the case folder: nothing new may appear beside the inputs
    site = disk_full_site(folder + ".site", case.fsize) if case.fsize else None
    before = snapshot(ctx.out)
    around = snapshot(folder, skip=ctx.out)
    outcome = execute(case, ctx, ranks, site)
    outcome.before, outcome.after = before, snapshot(ctx.out)
    after_around = snapshot(folder, skip=ctx.out)
    outcome.stray = sorted(set(after_around) - set(around))
    outcome.touched = sorted(p for p in set(around) & set(after_around) if around[p] != after_around[p])
    outcome.out_exists = os.path.lexists(ctx.out)
    return ctx, outcome


# ---------------------------------------------------------------------------------------------- checks

def _has(text, mention):
    """A mention is found case-insensitively; in a dotted entry path (reduction.moments) a ': ' may stand for a
    dot (galileo.yaml: reduction: moments ...); 're:...' is a regular expression."""
    if mention.startswith("re:"):
        return re.search(mention[3:], text, re.IGNORECASE | re.DOTALL) is not None
    if re.fullmatch(r"[A-Za-z_][\w\[\]]*(\.[A-Za-z_][\w\[\]]*)+", mention):
        pattern = r"(\.|:\s*)".join(re.escape(p) for p in mention.split("."))
        return re.search(pattern, text, re.IGNORECASE) is not None
    return mention.lower() in text.lower()


def check_message(msg, case, where, folder):
    """The case folder's path is blanked out first: it holds the case's name (mtx_is_a_folder, truncated_half), which
    would otherwise satisfy a mention the message itself never makes."""
    msg = msg.replace(os.path.realpath(folder), "<case>").replace(folder, "<case>")
    missing = [m for m in case.mentions if not _has(msg, m)]
    assert not missing, "%s: the message should name %s: %r" % (where, missing, msg)
    assert re.search(case.fix, msg, re.IGNORECASE | re.MULTILINE), \
        "%s: the message should say what to do (%r): %r" % (where, case.fix, msg)


def error_lines(stderr):
    return [line for line in stderr.splitlines() if ERROR_PREFIX in line]


def describe(o):
    return "%s\n  exit %s after %.1f s%s\n  stderr: %s\n  stdout: %s" % (
        " ".join(o.argv), o.returncode, o.seconds, ("; " + o.note) if o.note else "",
        o.stderr.strip()[-1500:] or "(empty)", o.stdout.strip()[-600:] or "(empty)")


def check_outcome(case, ctx, o):
    """Everything a refusal must do, checked on the command's run."""
    if o.hang:
        raise AssertionError("hang: no exit within %d s\n%s" % (case.timeout, describe(o)))
    assert "Traceback" not in o.stderr + o.stdout, "a traceback instead of a message\n" + describe(o)
    if case.kind == "signal":
        assert not o.note.startswith("the run ended"), o.note + "\n" + describe(o)
        expected = {EXIT_SIGINT: (EXIT_SIGINT, -signal.SIGINT), EXIT_SIGTERM: (EXIT_SIGTERM, -signal.SIGTERM)}[case.code]
        assert o.returncode in expected, "exit %s, expected %d\n%s" % (o.returncode, case.code, describe(o))
        assert len(error_lines(o.stderr)) <= 1, "the error line is printed more than once\n" + describe(o)
    elif case.kind == "target":
        assert o.returncode == case.code, "exit %s, expected %d\n%s" % (o.returncode, case.code, describe(o))
        both = o.stdout + "\n" + o.stderr
        lines = [ln for ln in both.splitlines()
                 if re.search(r"target", ln, re.I) and re.search(r"miss|not met|not reached", ln, re.I)]
        assert len(lines) == 1, "one line should say the target is missed (got %d)\n%s" % (len(lines), describe(o))
        assert re.search(r"\d(\.\d+)?(e[-+]?\d+)?", lines[0]), "the line should give the achieved error: " + lines[0]
    elif case.kind in ("accept", "accept_clean"):
        assert o.returncode == EXIT_OK, "a good input is refused: exit %s\n%s" % (o.returncode, describe(o))
        assert not error_lines(o.stderr), "a good input gives an error line\n" + describe(o)
    else:
        assert o.returncode == case.code, "exit %s, expected %d\n%s" % (o.returncode, case.code, describe(o))
        lines = error_lines(o.stderr)
        assert len(lines) == 1, "'%s' should be on stderr exactly once, found %d\n%s" % (ERROR_PREFIX, len(lines),
                                                                                          describe(o))
        check_message(lines[0], case, "command", ctx.dir)
    check_output_folder(case, ctx, o)


def check_output_folder(case, ctx, o):
    if case.kind in ("target", "accept", "accept_clean"):
        assert not o.touched, "input files changed by the run: %s" % o.touched
        if case.kind == "accept_clean":
            stale = [p for p in o.after if os.path.basename(p).startswith(".kryflex-") or p.endswith(".tmp")]
            assert not stale, "stale staging left in OUT after a good run: %s" % stale
        if case.kind == "target":
            import json
            assert "reduced.h5" in o.after and "summary.json" in o.after, \
                "target missed: the results should be written: %s" % sorted(o.after)
            with open(os.path.join(ctx.out, "summary.json")) as f:
                summary = json.load(f)
            assert summary.get("target_met") is False, "summary.json should say \"target_met\": false, has %r" \
                % summary.get("target_met", "(no key)")
            stale = [p for p in o.after if os.path.basename(p).startswith(".kryflex-") or p.endswith(".tmp")]
            assert not stale, "staging left in OUT: %s" % stale
        return
    assert not o.stray, "stray files left beside the inputs: %s" % o.stray
    assert not o.touched, "input files changed by the run: %s" % o.touched
    left = [p for p in case.gone if os.path.lexists(p)]
    assert not left, "the failed run left %s behind" % left
    if case.out == "absent":
        assert not o.out_exists, "the failed run left %s behind (it did not exist before): %s" % (
            ctx.out, sorted(o.after)[:10])
    elif case.out in ("earlier", "kept"):
        added = sorted(set(o.after) - set(o.before))
        removed = sorted(set(o.before) - set(o.after))
        changed = sorted(p for p in set(o.before) & set(o.after) if o.before[p] != o.after[p])
        assert not (added or removed or changed), \
            "the earlier results in OUT are not intact: added %s, removed %s, changed %s" % (added, removed, changed)


# ---------------------------------------------------------------------------------------------- in-process API

def check_api(case, ctx):
    """The Python face refuses the same input with the same content (run only after the command did not crash or
    hang: a crash here would take the whole test session with it)."""
    import kryflex
    from petsc4py import PETSc
    overrides = scene_overrides(case.argv) + [("kf_quiet", "1")]     # no progress lines in the test's output
    opts = PETSc.Options()
    had_quiet = opts.hasName("kf_quiet")
    if had_quiet:
        overrides.pop()
    for k, v in overrides:
        opts.setValue(k, v)
    try:
        if case.api == "scene" and case.kind == "accept":
            try:
                kryflex.load_scene(ctx.scene)
            except Exception as e:  # noqa: BLE001
                raise AssertionError("kryflex.load_scene refused a good input: %s: %s" % (type(e).__name__, e))
            return
        if case.api == "scene":
            try:
                kryflex.load_scene(ctx.scene)
            except kryflex.SceneError as e:
                assert isinstance(e, ValueError)
                check_message(str(e), case, "kryflex.load_scene", ctx.dir)
                return
            except Exception as e:  # noqa: BLE001 - a bad scene raises SceneError, nothing else
                raise AssertionError("kryflex.load_scene raised %s, expected kryflex.SceneError: %s"
                                     % (type(e).__name__, str(e)[:500]))
            raise AssertionError("kryflex.load_scene accepted the bad scene")
        if case.api == "model":
            path = ctx.fill([case.argv[1]])[0]
            try:
                model = kryflex.ReducedModel.load(path)
                if "--scene" in case.argv:
                    model.check_scene(kryflex.load_scene(ctx.fill([case.argv[case.argv.index("--scene") + 1]])[0]),
                                      path)
            except kryflex.ModelFileError as e:
                check_message(str(e), case, "kryflex.ReducedModel.load", ctx.dir)
                return
            except Exception as e:  # noqa: BLE001
                raise AssertionError("kryflex.ReducedModel.load raised %s, expected kryflex.ModelFileError: %s"
                                     % (type(e).__name__, str(e)[:500]))
            raise AssertionError("kryflex.ReducedModel.load accepted the bad model file")
    finally:
        for k, _ in overrides:
            opts.delValue(k)


def scene_overrides(argv):
    """The -scene.<path> VALUE pairs of a command line, as PETSc option (name, value) pairs."""
    pairs, argv = [], list(argv)
    for i, a in enumerate(argv):
        if a.startswith("-scene."):
            value = argv[i + 1] if i + 1 < len(argv) and not argv[i + 1].startswith("-scene.") else ""
            pairs.append((a[1:], value))
    return pairs


def python_exe():
    return sys.executable
