"""Sphinx configuration of the plm_pin documentation (``make docs``; see docs/README.md)."""

from __future__ import annotations

import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # the analyses package, for the study pages
sys.path.insert(0, str(ROOT / "docs"))

import _api  # noqa: E402

import plm_pin  # noqa: E402

_api.write_pages(ROOT / "docs" / "api")  # the index and one page per public package, from their __all__

project = "plm_pin"
author = "plm_pin developers"
release = plm_pin.__version__  # the source, not an installed copy's metadata
version = release

extensions = [
    "myst_nb",  # Markdown pages (MyST) and notebooks, executed at build time
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",  # Google-style docstrings
    "sphinx.ext.mathjax",
    "sphinx-mathjax-offline",  # MathJax copied into _static/mathjax: formulas render offline, no CDN
]

source_suffix = {".md": "myst-nb", ".ipynb": "myst-nb", ".rst": "restructuredtext"}
exclude_patterns = [
    "_build",
    "_generated",  # included by the pages that show them (benchmarks.md)
    "jupyter_execute",
    "README.md",
    "_api.py",
    "**.ipynb_checkpoints",
]
myst_enable_extensions = ["colon_fence", "dollarmath", "deflist"]
myst_heading_anchors = 3

# Tutorials run on every build: a cell that fails (or warns as an error) fails the build.
nb_execution_mode = os.environ.get("PLM_PIN_DOCS_EXECUTE", "force")
nb_execution_timeout = 300
nb_execution_raise_on_error = True
nb_execution_show_tb = True
nb_merge_streams = True

autodoc_default_options = {"members": True, "show-inheritance": True}
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_typehints_description_target = "documented_params"  # no second, bare list of a dataclass's fields
autodoc_typehints_format = "short"
napoleon_google_docstring = True
napoleon_numpy_docstring = False
napoleon_use_rtype = False
napoleon_attr_annotations = True
napoleon_use_ivar = True  # "Attributes:" as a field list: no second description of dataclass fields

html_theme = "furo"
html_title = f"plm_pin {release}"
html_extra_path = [str(ROOT / "plm_pin" / "schemas")]  # the JSON Schemas, at the site's root
html_static_path = ["_static"]
html_css_files = ["plm_pin.css"]  # code blocks wrap: no sideways scroll at 1280 px

suppress_warnings = ["myst.header"]
