"""Writes the manual's reference tables from what the code holds, before Sphinx reads the sources.

    reference/generated/options.md     every -kf_ option of the settings table (src/util/settings_table.c, through
                                       kryflex.settings): type, default, range or choices, help, scene key, setter
    reference/generated/scene-file.md  the scene file's keys: the settings' from the same table, the others' from
                                       kryflex.io.scene_schema
    reference/generated/c-api.md       src/include/kryflex.h, section by section, each declaration with its comment

The pages under reference/ include these files, so a new option, scene key or C function shows up in the manual
without an edit to it. The generated folder is rebuilt on every build and not tracked.
"""
import ast
import os
import re

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


# ------------------------------------------------------------------------------------------------ options (the table)

def _settings():
    import kryflex.settings
    return kryflex.settings.table()


def _choices(row):
    return ", ".join(row["choices"])


def options_page():
    """Every -kf_ option of the settings table, grouped by the object that reads it, in the table's order."""
    groups = {}
    for row in _settings():
        groups.setdefault(row["object"], []).append(row)
    if not groups:
        raise RuntimeError("the settings table is empty: is the binding built?")
    lines = []
    for obj, rows in groups.items():
        lines += ["## %s" % escape(obj), "",
                  "| option | type | default | range or choices | meaning | scene key | set in C by |",
                  "| --- | --- | --- | --- | --- | --- | --- |"]
        for r in rows:
            limits = " ".join(x for x in (code(r["range"]) if r["range"] else "", escape(_choices(r))) if x)
            lines.append("| %s | %s | %s | %s | %s | %s | %s |" % (
                code(r["name"]), r["type"], code(r["default"]) if r["default"] else "", limits, escape(r["help"]),
                code(r["scene"]) if r["scene"] else "", code(r["setter"]) if r["setter"] else ""))
        lines.append("")
    return "\n".join(lines)


# ------------------------------------------------------------------------------------------------ scene file

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
    choices = {"type": schema.JOINT_TYPES, "quantity": schema.QUANTITIES, "paper": schema.PAPERS}
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

    def settings_table(title, section, others):
        """The keys of a section that are settings (the settings table's rows with a scene key there), then the
        section's other keys."""
        nonlocal lines
        rows = {r["scene"].rpartition(".")[2]: r for r in _settings()
                if r["scene"] and r["scene"].rpartition(".")[0] == section}
        lines += ["## %s" % title, "", "| key | default | range or choices | meaning | option |",
                  "| --- | --- | --- | --- | --- |"]
        for k in sorted(set(rows) | set(others)):
            r = rows.get(k)
            if r is None:
                lines.append("| %s | | %s | | |" % (code(k), escape(", ".join(choices.get(k, ())))))
                continue
            key = (section + "." if section else "") + k
            rng = schema.SCENE_RANGES.get(key, r["range"])
            limits = " ".join(x for x in (code(rng) if rng else "", escape(_choices(r))) if x)
            lines.append("| %s | %s | %s | %s | %s |" % (code(key),
                                                         code(r["default"]) if r["default"] else "", limits,
                                                         escape(r["help"]), code(r["name"])))
        lines.append("")

    settings_table("Top level", "", schema.TOP_KEYS)
    settings_table("`reduction:`", "reduction", ())
    settings_table("`verify:`", "verify", ())
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
