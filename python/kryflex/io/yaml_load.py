"""Safe YAML loading for scene files: bounded in size, nesting and alias expansion, strict about duplicate keys.

A scene is small (body matrices live in their own files), so anything past the limits below is a mistake or an
attack, and is refused in milliseconds with a one-line message instead of a MemoryError, a RecursionError or a
message as long as the file. yaml's own SafeLoader (libyaml's when present) does the parsing; this module adds:
- a first pass over the event stream (no recursion, nothing built) that bounds the nesting depth and counts the
  nodes aliases would create (a "billion laughs" bomb is a few hundred bytes that expand to 10^9 nodes);
- duplicate keys at any level refused with their entry path and both line numbers (yaml keeps the last
  one silently);
- non-UTF-8 bytes refused with their byte offset;
- syntax errors reduced to their line, column and problem.
Errors are YAMLInputError (a ValueError) without the file name: the caller prefixes it.
"""
import os
import re

import yaml

MAX_BYTES = 1 << 20          # the scene YAML itself; body matrices, nodes and vectors are separate files
MAX_DEPTH = 32               # nested sequences and mappings (a scene needs 5)
MAX_ALIAS_NODES = 100000     # nodes created through aliases, counting nested ones expanded
MAX_MESSAGE = 200            # characters of a parser's problem text kept in a message

_MERGE = "tag:yaml.org,2002:merge"


class _Base(getattr(yaml, "CSafeLoader", yaml.SafeLoader)):
    """yaml's safe loader, reading 1e-12 as the number it is (YAML 1.1 wants a dot, 1.0e-12, and would make it
    the text '1e-12': a scene's `accuracy: 1e-12` or `-scene.accuracy 1e-12` refused as 'not a number')."""


_Base.add_implicit_resolver("tag:yaml.org,2002:float", re.compile(r"^[-+]?[0-9][0-9_]*[eE][-+]?[0-9]+$"),
                            list("-+0123456789"))


class YAMLInputError(ValueError):
    """Bad YAML input; the message says where (line, column or byte) and what to do."""


def _key_path(path, key):
    """The entry path of a mapping value as the messages write it: bodies.rotor.interfaces, inputs.x[1].node."""
    return "%s.%s" % (path, key) if path else str(key)


def _check_duplicate_keys(loader, root):
    """Refuses a key given twice in one mapping, at any level, naming the entry path and both lines (yaml keeps
    the last one silently). Walks the composed node tree once (a node reached again through an alias is not walked
    again), before anything is constructed."""
    seen_nodes = set()
    todo = [(root, "")]
    while todo:
        node, path = todo.pop()
        if id(node) in seen_nodes:
            continue
        seen_nodes.add(id(node))
        if isinstance(node, yaml.SequenceNode):
            todo.extend((item, "%s[%d]" % (path, i)) for i, item in enumerate(node.value))
        elif isinstance(node, yaml.MappingNode):
            first = {}
            for key_node, value_node in node.value:
                if key_node.tag == _MERGE:     # '<<: *base' merges: explicit keys override merged ones (YAML rule)
                    todo.append((value_node, path))
                    continue
                key = loader.construct_object(key_node, deep=True)
                mark = key_node.start_mark
                try:
                    earlier = first.get(key)
                except TypeError:              # an unhashable key: yaml's own message says so
                    continue
                if earlier is not None:
                    at = ("lines %d and %d" % (earlier.line + 1, mark.line + 1) if earlier.line != mark.line else
                          "line %d, columns %d and %d" % (mark.line + 1, earlier.column + 1, mark.column + 1))
                    raise YAMLInputError("%s: key %s appears twice (%s); keep one"
                                         % (_key_path(path, key), short_repr(key, 60), at))
                first[key] = mark
                todo.append((value_node, _key_path(path, key)))


def short_repr(value, limit=80):
    """repr(value), cut to limit characters: a message quotes a value, never a whole mapping or an alias bomb."""
    text = repr(value)
    return text if len(text) <= limit else text[:limit - 3] + "..."


def _where(mark):
    return "line %d, column %d" % (mark.line + 1, mark.column + 1)


def _check_events(text, max_depth, max_alias_nodes):
    """Walks the event stream once: nesting depth and the node count of every anchor, so that an alias's expansion
    is counted without building it."""
    sizes = {}          # anchor -> nodes it stands for, once its node is complete
    stack = []          # open collections: [anchor, nodes so far]
    expanded = 0
    for event in yaml.parse(text, Loader=_Base):
        if isinstance(event, (yaml.SequenceStartEvent, yaml.MappingStartEvent)):
            stack.append([event.anchor, 1])
            if len(stack) > max_depth:
                raise YAMLInputError("%s: entries nested deeper than %d levels; remove the extra nesting (a scene "
                                     "needs 5 levels)" % (_where(event.start_mark), max_depth))
            continue
        if isinstance(event, (yaml.SequenceEndEvent, yaml.MappingEndEvent)):
            anchor, n = stack.pop()
        elif isinstance(event, yaml.ScalarEvent):
            anchor, n = event.anchor, 1
        elif isinstance(event, yaml.AliasEvent):
            anchor, n = None, sizes.get(event.anchor)
            if n is None:
                if any(a == event.anchor for a, _ in stack):
                    raise YAMLInputError("%s: alias *%s refers to the entry that contains it (a loop): write the "
                                         "entry out" % (_where(event.start_mark), event.anchor))
                continue        # an undefined alias: the composer's own message says so
            expanded += n
            if expanded > max_alias_nodes:
                raise YAMLInputError("%s: aliases (*%s) expand to more than %d entries; write the entries out or "
                                     "use fewer nested aliases" % (_where(event.start_mark), event.anchor,
                                                                   max_alias_nodes))
        else:
            continue
        if anchor is not None:
            sizes[anchor] = n
        if stack:
            stack[-1][1] += n


def _decode(data):
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        raise YAMLInputError("not UTF-8 text at byte %d: save the scene as UTF-8" % e.start) from None


def load_text(text, max_depth=MAX_DEPTH, max_alias_nodes=MAX_ALIAS_NODES):
    """The Python value of one YAML document given as text (str or UTF-8 bytes)."""
    if isinstance(text, bytes):
        text = _decode(text)
    try:
        _check_events(text, max_depth, max_alias_nodes)
        loader = _Base(text)
        try:
            root = loader.get_single_node()
            if root is None:
                return None
            _check_duplicate_keys(loader, root)
            return loader.construct_document(root)
        finally:
            loader.dispose()
    except yaml.MarkedYAMLError as e:
        mark = e.problem_mark or e.context_mark
        problem = " ".join(str(e.problem or e.context or "syntax error").split())[:MAX_MESSAGE]
        at = _where(mark) + ": " if mark is not None else ""
        raise YAMLInputError("not valid YAML at %s%s; fix the syntax there (quote text holding ': ' or '#')"
                             % (at, problem)) from None
    except yaml.YAMLError as e:     # reader errors (control characters) and the like
        raise YAMLInputError("not valid YAML: %s; fix the file" % " ".join(str(e).split())[:MAX_MESSAGE]) from None


def load_file(path, max_bytes=MAX_BYTES, **limits):
    """The Python value of a YAML file, refused early if it is over max_bytes, not UTF-8 or past the limits."""
    size = os.path.getsize(path)
    if size > max_bytes:
        raise YAMLInputError("the file has %d bytes, more than the %d a scene may have; keep body matrices, nodes "
                             "and load vectors in their own files and name them in the scene" % (size, max_bytes))
    with open(path, "rb") as f:
        data = f.read(max_bytes + 1)
    if len(data) > max_bytes:       # grown since the stat
        raise YAMLInputError("the file has more than %d bytes, more than a scene may have" % max_bytes)
    return load_text(_decode(data), **limits)
