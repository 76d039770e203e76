"""Sphinx configuration of the pound-mc documentation (``sphinx-build -W docs docs/_build``)."""

import os
import shutil
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from pound_mc._version import __version__  # noqa: E402

# the notebook lives with the studies; it runs on the main job's dataset where there is one
# (README command 1 writes it), else it is shown as stored, without outputs
GENERATED = Path(__file__).resolve().parent / "_generated"
GENERATED.mkdir(exist_ok=True)
shutil.copyfile(ROOT / "studies" / "analysis.ipynb", GENERATED / "analysis.ipynb")
QUICKSTART = ROOT / "outputs" / "quickstart.nc"
if QUICKSTART.is_file():
    os.environ["POUND_MC_DATASET"] = str(QUICKSTART)

project = "pound-mc"
author = "pound-mc developers"
copyright = "2026, pound-mc developers"
version = release = __version__

extensions = [
    "myst_nb",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    # MathJax from the package, copied into _static/mathjax: formulas render offline, no CDN
    "sphinx-mathjax-offline",
]
source_suffix = {".md": "myst-nb", ".ipynb": "myst-nb"}
exclude_patterns = ["_build", "jupyter_execute", "tables"]
nb_execution_mode = "force" if QUICKSTART.is_file() else "off"
nb_execution_timeout = 600
nb_execution_raise_on_error = True
# what a cell prints on stderr (library notices such as tqdm's about notebook widgets) is left out
nb_output_stderr = "remove"
myst_enable_extensions = ["dollarmath", "deflist"]
myst_heading_anchors = 3
suppress_warnings = ["myst.header", "myst.xref_missing"]

napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False
napoleon_use_ivar = True
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"members": True, "undoc-members": False}

html_theme = "furo"
html_title = f"pound-mc {release}"
html_static_path = ["_static"]
html_css_files = ["pound-mc.css"]  # a wider column: code lines of 100 characters fit
