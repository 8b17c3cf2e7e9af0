"""Sphinx configuration of the cvxgeodesic documentation: ``make docs`` builds it into ``build/docs``.

Sphinx with numpydoc renders the API reference from the numpydoc docstrings (the style the package is written
in); myst-parser reads the Markdown pages of this folder as they are, so the same files read well on a code
host and in the built site. ``make docs`` runs ``sphinx-build -W --keep-going``: a warning fails the build.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))  # the checkout's package, also without an editable install

project = "cvxgeodesic"
author = "the cvxgeodesic authors"
copyright = "2026, the cvxgeodesic authors"
import cvxgeodesic  # noqa: E402  (autodoc imports it anyway)

release = version = cvxgeodesic.__version__

extensions = ["sphinx.ext.autodoc", "numpydoc", "myst_parser"]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build"]

# Markdown: anchors for `page.md#a-heading` links (the GitHub rule, checked by tests/test_docs.py), $…$ maths
myst_heading_anchors = 4
myst_enable_extensions = ["dollarmath"]
suppress_warnings = ["myst.header"]  # pages written for a code host start below h1 in places

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
