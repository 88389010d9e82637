"""Sphinx configuration of the rpr3-gwr documentation.

Build with ``make docs`` (or ``sphinx-build -W --keep-going docs docs/_build/html``
after ``source ros2_ws/env.sh``).  The figures of the concepts page are drawn
at build time by :mod:`make_figures` from the project's own core.
"""

import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
# The sources come first, so that the pages describe the files of this tree
# even where the colcon overlay is older.
sys.path[:0] = [os.path.join(ROOT, "src", "rpr3_gwr_core"),
                os.path.join(ROOT, "src", "rpr3_gwr_nodes"), HERE]

project = "rpr3-gwr"
author = "rpr3-gwr authors"
copyright = "the rpr3-gwr authors"

extensions = ["sphinx.ext.autodoc", "sphinx.ext.napoleon"]
exclude_patterns = ["_build", "_generated"]
html_theme = "alabaster"
html_theme_options = {"page_width": "1100px", "sidebar_width": "240px"}

napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False
# Attributes as fields of their class: the dataclasses' own attribute entries
# would otherwise describe each one twice.
napoleon_use_ivar = True
autodoc_member_order = "bysource"
autodoc_default_options = {"members": True, "show-inheritance": True}
# Typed names in docstrings ("Roadmap", "array of float") are words for the
# reader, not targets Sphinx has to resolve.
nitpicky = False
# The same words name several members (``max_solutions`` of a mechanism and of
# a field); a type written in prose may point to either.
suppress_warnings = ["ref.python"]


def setup(app):
    """Draw the figures before the sources are read."""
    import make_figures

    app.connect("builder-inited", lambda app: make_figures.main(
        os.path.join(app.srcdir, "_generated")))
