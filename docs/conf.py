"""Sphinx configuration of nhham's documentation (``pip install 'nhham[docs]'``).

Build: ``python -m sphinx -W -b html docs docs/_build/html`` (the tests build it too,
with warnings as errors).
"""

import os
import sys

sys.path.insert(0, os.path.abspath(".."))

import nhham  # noqa: E402

project = "nhham"
author = "the nhham authors"
copyright = "the nhham authors (BSD-3-Clause)"
release = version = nhham.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "myst_parser",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "tutorials/*.ipynb", "paper-errata.md"]
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False
autodoc_member_order = "bysource"
autodoc_typehints = "none"
autodoc_default_options = {"members": False}
myst_heading_anchors = 3
suppress_warnings = ["myst.xref_missing", "myst.header"]
html_theme = "alabaster"
html_static_path = []
