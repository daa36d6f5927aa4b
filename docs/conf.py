"""Sphinx configuration of the documentation site (``make docs`` -> docs/_build/html/index.html).

The pages are the Markdown files of docs/ (myst-parser), the benchmark reports they include from
benchmarks/, the API from the docstrings (autodoc, numpydoc) and a gallery of examples that run
in seconds (sphinx-gallery, docs/gallery_src/). docs/model.md is cut into one page per piece of
physics at each build (docs/_ext/model_pages.py). Built with warnings as errors.
"""

import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # solver, pipeline: as in the clone
sys.path.insert(0, str(HERE / "_ext"))
os.environ.setdefault("MPLBACKEND", "Agg")

from solver import SOLVER_VERSION  # noqa: E402

project = "ehd-collision"
author = "ehd-collision developers"
copyright = "ehd-collision developers"
version = release = SOLVER_VERSION

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.mathjax",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
    "model_pages",
    "api_tables",
]

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build", "gallery_src", "Thumbs.db", ".DS_Store"]

# headings of levels 1-3 get the anchors GitHub gives them: links like solver.md#presets work
# on the site as in the repository
myst_heading_anchors = 3
myst_enable_extensions = ["dollarmath"]

autodoc_member_order = "bysource"
autodoc_typehints = "none"  # the numpydoc parameter lists say the types
numpydoc_show_class_members = False
numpydoc_validation_checks = set()
numpydoc_xref_param_type = False

sphinx_gallery_conf = {
    "examples_dirs": "gallery_src",
    "gallery_dirs": "gallery",
    "filename_pattern": r"/plot_",
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
}

html_theme = "pydata_sphinx_theme"
html_title = f"ehd-collision {release}"
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
}
html_static_path = []
