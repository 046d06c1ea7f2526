"""Sphinx configuration of the kryflex manual (MyST Markdown; built by scripts/docs with warnings as errors)."""
import os
import sys

DOCS = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(DOCS)
sys.path.insert(0, os.path.join(ROOT, "python"))     # autodoc imports kryflex from the source tree
sys.path.insert(0, os.path.join(DOCS, "_ext"))

project = "kryflex"
author = "the kryflex authors"
copyright = "the kryflex authors"
release = version = "0.1.0"

extensions = ["myst_parser", "sphinx.ext.autodoc", "kryflex_reference"]
source_suffix = {".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "reference/generated", "**/*-text.md"]
myst_enable_extensions = ["dollarmath"]
myst_heading_anchors = 3

html_theme = "nature"
html_static_path = ["_static"]
html_title = "kryflex manual"

autodoc_member_order = "bysource"
autodoc_typehints = "none"
autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": False}


def _verbatim_docstring(app, what, name, obj, options, lines):
    """The package's docstrings are plain text laid out for a terminal, not reStructuredText: shown as written."""
    if lines:
        lines[:] = ["::", ""] + ["   " + line for line in lines] + [""]


def setup(app):
    app.connect("autodoc-process-docstring", _verbatim_docstring)
