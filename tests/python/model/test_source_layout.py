"""The C library's layout: no two files of src/ call into each other, directly or around a loop, so that each file
can be read with only what it calls below it (docs/developer/index.md)."""
import glob
import os
import re

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
SRC = os.path.join(ROOT, "src")

COMMENT = re.compile(r"/\*.*?\*/|//[^\n]*", re.S)
STRING = re.compile(r'"(?:[^"\\\n]|\\.)*"')
# a function defined at file scope and visible to other files (not static): its name before "(" on a line of its own
DEFINITION = re.compile(r"^(?!static\b)(?:PETSC_INTERN\s+|PETSC_EXTERN\s+)?[A-Za-z_][\w \*]*?\b(\w+)\s*\([^;]*\)\s*\n\{",
                        re.M)


def _code(path):
    with open(path) as f:
        return STRING.sub('""', COMMENT.sub(" ", f.read()))


def _call_graph():
    """file -> the other files whose functions it names (its calls, as text: comments and strings left out)."""
    files = sorted(glob.glob(os.path.join(SRC, "**", "*.c"), recursive=True))
    code = {f: _code(f) for f in files}
    owner = {}
    for f in files:
        for name in DEFINITION.findall(code[f]):
            owner.setdefault(name, f)
    graph = {f: set() for f in files}
    word = re.compile(r"\b(\w+)\b")
    for f in files:
        for name in set(word.findall(code[f])):
            g = owner.get(name)
            if g is not None and g != f:
                graph[f].add(g)
    return graph


def _cycle(graph):
    """One loop of the graph as a list of files, or None (depth-first search)."""
    state, stack = {}, []

    def visit(f):
        state[f] = 1
        stack.append(f)
        for g in sorted(graph[f]):
            if state.get(g) == 1:
                return stack[stack.index(g):] + [g]
            if g not in state:
                found = visit(g)
                if found:
                    return found
        stack.pop()
        state[f] = 2
        return None

    for f in sorted(graph):
        if f not in state:
            found = visit(f)
            if found:
                return found
    return None


@pytest.mark.fast
def test_the_call_graph_is_found():
    """The scan sees the calls it must: the reducer's solve reaches the flexible solver and the reference."""
    graph = _call_graph()
    solve = os.path.join(SRC, "reducer", "solve.c")
    assert os.path.join(SRC, "solve", "flex_solver.c") in graph[solve]
    assert os.path.join(SRC, "reducer", "reference.c") in graph[os.path.join(SRC, "reducer", "evaluate.c")]
    assert sum(len(v) for v in graph.values()) > 100


@pytest.mark.fast
def test_no_two_source_files_call_into_each_other():
    cycle = _cycle(_call_graph())
    assert cycle is None, "files of src/ that call into each other: " + " -> ".join(os.path.relpath(f, ROOT)
                                                                                  for f in cycle)
