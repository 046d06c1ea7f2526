"""What every kryflex command shares: exit codes, rank-0 output, PETSc options on the command line, argument parsing."""
import argparse
import sys

EXIT_OK, EXIT_INTERNAL, EXIT_INPUT, EXIT_NUMERIC, EXIT_OUTPUT, EXIT_MODEL = 0, 1, 2, 3, 4, 5


def rank():
    from petsc4py import PETSc
    return PETSc.COMM_WORLD.getRank()


def say(msg, stream=sys.stdout):
    if rank() == 0:
        print(msg, file=stream, flush=True)


def error(msg):
    say("kryflex: error: %s" % msg, sys.stderr)


def split_petsc_options(argv, flags_with_value, flags):
    """Keeps the command's own arguments; PETSc options (already read by PETSc) are dropped with their values."""
    out, i = [], 0
    while i < len(argv):
        a = argv[i]
        if a.split("=", 1)[0] in flags_with_value and "=" in a:
            out.append(a)
            i += 1
            continue
        if a in flags_with_value:
            out.extend(argv[i:i + 2])
            i += 2
            continue
        if a in flags or not a.startswith("-") or a == "-" or _is_number(a):
            out.append(a)
            i += 1
            continue
        # a PETSc option: its value is the next token unless that is another option
        i += 1
        if i < len(argv) and (not argv[i].startswith("-") or _is_number(argv[i])):
            i += 1
    return out


def _is_number(s):
    try:
        float(s)
        return True
    except ValueError:
        return False


class Parser(argparse.ArgumentParser):
    def error(self, message):
        say("%s\nkryflex: error: %s" % (self.format_usage().rstrip(), message), sys.stderr)
        raise SystemExit(EXIT_INPUT)


def from_rank0(value):
    """Rank 0's value on every rank (a no-op when run alone)."""
    from petsc4py import PETSc
    comm = PETSc.COMM_WORLD
    if comm.getSize() == 1:
        return value
    return comm.tompi4py().bcast(value, root=0)
