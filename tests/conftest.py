import os
import sys
from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")
# tests/ holds helper modules (independent reference solutions, shared studies) imported by name
sys.path.insert(0, str(Path(__file__).parent))
os.environ.setdefault("MPLBACKEND", "Agg")

import studies  # noqa: E402  (found through the path set above)


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
