"""Sphinx configuration of the cvxgeodesic documentation: ``make docs`` builds it into ``build/docs``.

Why Sphinx: numpydoc, the reference renderer of the docstring style the package is written in, is a Sphinx
extension, and ``sphinx-build -W`` turns every docstring or link problem into a failed build (mkdocs with
mkdocstrings would need griffe's numpy parser and a theme on top, for the same pages). myst-parser reads the
Markdown pages of this folder as they are, so the same files read well on a code host and in the built site;
the default theme (alabaster) comes with Sphinx. ``make docs`` runs ``sphinx-build -W --keep-going``.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))  # the checkout's package, also without an editable install
import cvxgeodesic  # noqa: E402  (autodoc imports it anyway)

project = "cvxgeodesic"
author = "the cvxgeodesic authors"
copyright = "2026, the cvxgeodesic authors"
release = version = cvxgeodesic.__version__

extensions = ["sphinx.ext.autodoc", "numpydoc", "myst_parser"]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build"]

# Markdown: anchors for `page.md#a-heading` links (the GitHub rule, checked by tests/test_docs.py)
myst_heading_anchors = 4

# API reference: the docstrings' own Parameters/Returns sections carry the types, so no signature annotations
autodoc_typehints = "none"
autodoc_member_order = "bysource"
autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": False}
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

html_theme = "alabaster"
html_title = f"cvxgeodesic {release}"
html_theme_options = {"description": "Geodesic distances on triangle meshes by convex optimization"}
