import os
import sys
from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")
# tests/ holds helper modules (independent reference solutions, shared studies) imported by name
sys.path.insert(0, str(Path(__file__).parent))
os.environ.setdefault("MPLBACKEND", "Agg")

import matplotlib.pyplot as plt  # noqa: E402  (after the backend is chosen)

import studies  # noqa: E402  (found through the path set above)


@pytest.fixture(autouse=True)
def _close_pyplot_figures():
    """Close the pyplot figures a test opened (``ds.pound.plot`` without ``ax`` or ``path``
    draws on one, as a notebook user wants): they would pile up in the worker."""
    yield
    plt.close("all")


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_auto_num_workers(config):
    """Worker processes for ``-n auto`` (pyproject's ``addopts``): one a core, at most 4.

    None (this process) where the command names one test file: its tests stay in one worker
    anyway (``--dist loadfile``), and a second worker would only collect them again.
    """
    files = {str(arg).split("::")[0] for arg in config.args}
    if len(files) == 1 and (config.invocation_params.dir / files.pop()).is_file():
        return 0
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    workers = min(cores or 1, 4)
    return workers if workers > 1 else 0


@pytest.fixture
def make_study(tmp_path):
    """Factory writing a small SDOF study (``studies.SMALL_SDOF``) to ``tmp_path``.

    ``make_study(study={"name": "tiny"}, sampling={"n": 4})`` returns the path of
    ``tmp_path / "tiny.toml"``; keywords override tables as ``studies.study_text`` describes.
    """

    def make(**tables) -> Path:
        return studies.write_study(tmp_path, studies.SMALL_SDOF, **tables)

    return make


@pytest.fixture
def make_shear_study(tmp_path):
    """Factory writing the small 3 + 5 storey study (``studies.SMALL_SHEAR``) to ``tmp_path``."""

    def make(**tables) -> Path:
        return studies.write_study(tmp_path, studies.SMALL_SHEAR, **tables)

    return make
