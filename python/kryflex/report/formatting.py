"""Number and table formatting of the report (the paper's digits), and the constants that decide what is shown."""
import math
import re

RATIO_EXACT_TOL = 1e-8
# Show every (output, input) entry in the moment tables up to this many entries, else the dominant one only.
MAX_MOMENT_ENTRIES_SHOWN = 4
# A mismatch list longer than this is cut, the rest being in summary.json.
MAX_MISMATCHES_LISTED = 40
DASH = "—"
# The Bode plots of a configuration with at most this many input/output pairs are one figure (a cell per pair); with
# more, one figure per pair (a figure of more cells would be too large to read).
MAX_PAIRS_PER_FIGURE = 12


def pair_name(output, input_):
    """An input/output pair as the report names it: "output ← input"."""
    return f"{output} ← {input_}"


def fmt_freq(x):
    """Five significant digits, like the paper's frequency tables (0.11060, 57.253, 1217.7)."""
    if x is None:
        return DASH
    text = f"{x:#.5g}"
    return text[:-1] if text.endswith(".") else text


def fmt_ratio(x):
    """Ten significant digits: enough to see a departure from 1 at the 1e-8 exact-match tolerance."""
    return DASH if x is None else f"{x:#.10g}"


def fmt_percent(x, digits=4):
    return DASH if x is None else f"{100.0 * x:.{digits}g} %"


def fmt_general(x):
    if x is None:
        return DASH
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, float):
        return f"{x:.6g}"
    if isinstance(x, (list, tuple)):
        return "[" + ", ".join(fmt_general(v) for v in x) + "]"
    return str(x)


def mode_ranges(numbers):
    """[1, 2, 3, 4, 7, 8] -> '1-4, 7, 8' (runs of three or more collapsed)."""
    numbers = sorted(numbers)
    parts, start = [], 0
    while start < len(numbers):
        end = start
        while end + 1 < len(numbers) and numbers[end + 1] == numbers[end] + 1:
            end += 1
        if end - start >= 2:
            parts.append(f"{numbers[start]}–{numbers[end]}")
        else:
            parts.extend(str(n) for n in numbers[start:end + 1])
        start = end + 1
    return ", ".join(parts) if parts else "none"


def table(header, rows, align=None):
    """A Markdown table; align: string of 'l'/'r' per column (default: first left, rest right)."""
    align = align or "l" + "r" * (len(header) - 1)
    rule = ["---:" if c == "r" else ":---" for c in align]
    lines = ["| " + " | ".join(header) + " |", "| " + " | ".join(rule) + " |"]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def safe_name(text):
    """A file-name-safe form of an angle label or I/O name."""
    return re.sub(r"[^A-Za-z0-9._-]+", "_", str(text)).strip("_") or "x"


def decade_scale(values):
    """Common power of ten p of a row of numbers: max |v| / 10^p in [1, 10); 0 for an all-zero row."""
    biggest = max((abs(v) for v in values if v is not None), default=0.0)
    return 0 if biggest == 0 else int(math.floor(math.log10(biggest)))
