"""Writes the manual's reference tables from what the code holds, before Sphinx reads the sources.

    reference/generated/options.md     every -kf_ option of `kryflex reduce -help`: name, default, choices, help, setter
    reference/generated/scene-file.md  the scene file's keys, defaults, choices and limits from kryflex.io.scene_schema
    reference/generated/c-api.md       src/include/kryflex.h, section by section, each declaration with its comment

The pages under reference/ include these files, so a new option, scene key or C function shows up in the manual
without an edit to it. The generated folder is rebuilt on every build and not tracked.
"""
import ast
import os
import re
import subprocess

DOCS = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ROOT = os.path.dirname(DOCS)
OUT = os.path.join(DOCS, "reference", "generated")

_SPECIAL = re.compile(r"([\\`*_\[\]<>|#{}$~])")


def escape(text):
    """Plain text as Markdown text: every character MyST could read as markup escaped."""
    return _SPECIAL.sub(r"\\\1", text)


def code(text):
    """Inline code that may hold backticks."""
    return "`` %s ``" % text if "`" in text else "`%s`" % text


# ------------------------------------------------------------------------------------------------ options (-help)

_OPTION = re.compile(r"^\s+-(?P<name>kf_\w+):?\s*<(?P<value>[^>]*)>:?\s*(?P<rest>.*)$")
_SETTER = re.compile(r"\s*\((?P<setter>[A-Z]\w*)\)\s*$")
_CHOICES = re.compile(r"\s*\((?:choose )?one of\)\s*(?P<choices>[\w.+-]+(?:\s+[\w.+-]+)*)\s*$")


def parse_help(text):
    """The -kf_ options of a PETSc -help listing, by section: [(title, [(name, default, choices, help, setter)])]."""
    sections, title, expect_title = [], None, False
    for line in text.splitlines():
        if line.startswith("-----"):
            expect_title = True
            continue
        if expect_title:
            expect_title = False
            title = line.strip().rstrip(":")
            if title.endswith(" options"):
                title = title[:-len(" options")]
            sections.append((title, []))
            continue
        m = _OPTION.match(line)
        if not m or not sections:
            continue
        value = m.group("value").strip()
        now = re.match(r"now (.*) : formerly .*", value)
        default = now.group(1) if now else value.split(" : ")[0]
        default = default.lower() if default in ("TRUE", "FALSE") else default
        rest, setter, choices = m.group("rest"), "", ""
        s = _SETTER.search(rest)
        if s:
            setter, rest = s.group("setter"), rest[:s.start()]
        c = _CHOICES.search(rest)
        if c:
            choices, rest = ", ".join(c.group("choices").split()), rest[:c.start()]
        sections[-1][1].append((m.group("name"), default, choices, rest.strip(), setter))
    return [(t, rows) for t, rows in sections if rows]


def options_page():
    kryflex = os.path.join(ROOT, "build", "kryflex")
    if not os.access(kryflex, os.X_OK):
        raise RuntimeError("%s is not built: run ./scripts/setup first (scripts/docs does)" % kryflex)
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OPENBLAS_NUM_THREADS="1")
    run = subprocess.run([kryflex, "reduce", "-help"], capture_output=True, text=True, env=env, timeout=120)
    if run.returncode != 0:
        raise RuntimeError("`kryflex reduce -help` failed (exit %d): %s" % (run.returncode, run.stderr[-500:]))
    sections = parse_help(run.stdout)
    if not sections:
        raise RuntimeError("`kryflex reduce -help` listed no -kf_ option: has its format changed?")
    lines = []
    for title, rows in sections:
        lines += ["## %s" % escape(title[:1].upper() + title[1:]), "",
                  "| option | default | choices | meaning | set in C by |", "| --- | --- | --- | --- | --- |"]
        for name, default, choices, text, setter in rows:
            lines.append("| %s | %s | %s | %s | %s |" % (code("-" + name), code(default) if default else "",
                                                         escape(choices), escape(text),
                                                         code(setter) if setter else ""))
        lines.append("")
    return "\n".join(lines)


# ------------------------------------------------------------------------------------------------ scene file

def _source_comments(source, block):
    """{key: comment} of the `"key": value,  # comment` lines of the dict literal assigned to `block`."""
    m = re.search(r"^%s = \{\n(.*?)^\}" % block, source, re.M | re.S)
    out = {}
    for line in (m.group(1).splitlines() if m else []):
        k = re.match(r'\s*"(\w+)":\s*.*?#\s*(.*)$', line)
        if k:
            out[k.group(1)] = k.group(2).strip()
    return out


def _constant_comments(source):
    """{NAME: (value source, comment)} of the module's `NAME = value  # comment` lines."""
    out = {}
    for line in source.splitlines():
        m = re.match(r"^([A-Z][A-Z_]*) = (.+?)\s+#\s*(.*)$", line)
        if m:
            out[m.group(1)] = (m.group(2).strip(), m.group(3).strip())
    return out


def _value(v):
    if v is None:
        return "none"
    if isinstance(v, bool):
        return "true" if v else "false"
    return str(v)


def scene_page():
    import kryflex.io.scene_schema as schema
    path = schema.__file__
    source = open(path).read()
    ast.parse(source)
    choices = {"importance": schema.IMPORTANCES, "basis": schema.BASES, "method": schema.METHODS,
               "flex_solver": schema.FLEX_SOLVERS, "type": schema.JOINT_TYPES, "quantity": schema.QUANTITIES,
               "paper": schema.PAPERS}
    lines = []

    def keys_table(title, keys, defaults=None, comments=None, prefix=""):
        nonlocal lines
        lines += ["## %s" % title, "", "| key | default | choices | meaning |", "| --- | --- | --- | --- |"]
        for k in sorted(keys):
            d = defaults.get(k, "") if defaults else ""
            lines.append("| %s | %s | %s | %s |" % (code(prefix + k), code(_value(d)) if defaults and k in defaults
                                                     else "", escape(", ".join(choices.get(k, ()))),
                                                     escape((comments or {}).get(k, ""))))
        lines.append("")

    keys_table("Top level", schema.TOP_KEYS, schema.DEFAULTS)
    keys_table("`reduction:`", schema.REDUCTION_DEFAULTS, schema.REDUCTION_DEFAULTS,
               _source_comments(source, "REDUCTION_DEFAULTS"), "reduction.")
    keys_table("`verify:`", schema.VERIFY_DEFAULTS, schema.VERIFY_DEFAULTS,
               _source_comments(source, "VERIFY_DEFAULTS"), "verify.")
    keys_table("A body (`bodies.<name>:`)", schema.BODY_KEYS)
    keys_table("A joint (`joints.<name>:`)", schema.JOINT_KEYS)
    keys_table("A term of an input or output (`inputs.<name>: [...]`, `outputs.<name>: [...]`)", schema.TERM_KEYS)
    keys_table("A clamp (`bodies.<name>.constraints: [...]`)", schema.CONSTRAINT_KEYS)
    keys_table("A spring to ground (`bodies.<name>.springs: [...]`)", schema.SPRING_KEYS)
    keys_table("`damping:` as a mapping", schema.DAMPING_KEYS)
    lines += ["## Names, components and limits", "", "| constant | value | meaning |", "| --- | --- | --- |"]
    for name, (value, comment) in sorted(_constant_comments(source).items()):
        lines.append("| %s | %s | %s |" % (code(name), code(value), escape(comment)))
    lines += ["", "A joint's `parent` may be %s: the child's interface node is grounded." % code(schema.GROUND),
              "Dof names: %s." % ", ".join(code(d) for d in schema.DOF_NAMES), ""]
    return "\n".join(lines)


# ------------------------------------------------------------------------------------------------ C API

def c_api_page():
    header = os.path.join(ROOT, "src", "include", "kryflex.h")
    text = open(header).read()
    opening = re.match(r"\s*/\*(.*?)\*/", text, re.S)
    lines = ["The public header `src/include/kryflex.h`, declaration by declaration with its comment.", ""]
    if opening:
        lines += ["```text", opening.group(1).strip("\n"), "```", ""]
        text = text[opening.end():]
    comment, code_lines, depth = [], [], 0

    def flush():
        nonlocal comment, code_lines
        body = [c for c in code_lines if c.strip()]
        if comment:
            lines.extend([escape(" ".join(c.strip() for c in comment)), ""])
        if body:
            lines.extend(["```c"] + body + ["```", ""])
        comment, code_lines = [], []

    it = iter(text.splitlines())
    for line in it:
        s = line.strip()
        if re.match(r"#(ifndef|endif|include)\b", s) or s == "#define KRYFLEX_H":
            continue
        if depth == 0 and s.startswith("/*"):
            block = [s]
            while "*/" not in block[-1]:
                block.append(next(it).strip())
            joined = " ".join(block)
            section = re.match(r"/\*\s*-{5,}\s*(.*?)\s*\*/", joined)
            if code_lines or section:
                flush()
            if section:
                lines += ["## %s" % escape(section.group(1)), ""]
                continue
            inner = joined[2:joined.index("*/")].strip()
            comment.append(inner)
            continue
        if not s and depth == 0:
            if code_lines:
                flush()
            continue
        code_lines.append(line)
        depth += line.count("{") - line.count("}")
    flush()
    return "\n".join(lines)


def generate(app=None):
    os.makedirs(OUT, exist_ok=True)
    for name, make in (("options.md", options_page), ("scene-file.md", scene_page), ("c-api.md", c_api_page)):
        text = make().rstrip("\n") + "\n"
        path = os.path.join(OUT, name)
        if not os.path.exists(path) or open(path).read() != text:
            with open(path, "w") as f:
                f.write(text)


def setup(app):
    app.connect("builder-inited", generate)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
