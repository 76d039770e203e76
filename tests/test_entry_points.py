"""The entry points (issue #41, DESIGN.md section 10): ``import pound_mc`` and its four calls,
a fast ``pound-mc --help``, and ``pound-mc init --new NAME``."""

import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import pound_mc
from pound_mc.cli import main
from pound_mc.cli.study import study_template
from pound_mc.errors import InputError
from pound_mc.physics.names import RELATION_NAMES
from pound_mc.physics.relations import RELATIONS, xi_from_e
from pound_mc.scene import load_scene, simulate

ROOT = Path(__file__).resolve().parents[1]
B1 = ROOT / "studies" / "scenes" / "b1.toml"
HEAVY = ("matplotlib", "numba", "scipy")


def _python(code: str) -> str:
    """Run ``code`` in a fresh interpreter (nothing imported yet); its standard output."""
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT
    )
    return done.stdout.strip()


def test_help_of_every_command_imports_no_heavy_library():
    # the parser of every sub-command is built for the program's --help; each --help exits
    # before its command's module is imported (DESIGN.md section 10: none of the three)
    code = f"""
import contextlib, io, sys
from pound_mc.cli import build_parser, main
from pound_mc.cli.commands import COMMANDS
for argv in [["--help"], *[name.split() + ["--help"] for name in COMMANDS]]:
    with contextlib.redirect_stdout(io.StringIO()):
        try:
            main(argv)
        except SystemExit as exc:
            assert exc.code == 0, (argv, exc.code)
print([m for m in {HEAVY!r} if m in sys.modules])
"""
    assert _python(code) == "[]"


def test_help_of_the_installed_script_imports_no_heavy_library():
    # the console script as a user runs it (python -m pound_mc is the same entry)
    code = (
        "import runpy, sys; sys.argv = ['pound-mc', '--help']\n"
        "try:\n    runpy.run_module('pound_mc', run_name='__main__')\n"
        "except SystemExit:\n    pass\n"
        f"print([m for m in {HEAVY!r} if m in sys.modules])"
    )
    out = _python(code)
    assert "usage: pound-mc" in out and out.endswith("[]"), out


def test_import_registers_the_accessor_and_loads_only_xarray(tmp_path):
    path = tmp_path / "tiny.nc"
    dims = ("record", "contact_gap_m", "sample")
    xr.Dataset(
        {
            "peak_force": (dims, [[[1.0e6, 0.0]]], {"units": "N"}),
            "impacts": (dims, [[[2, 0]]]),
            "status": (dims, [[[0, 0]]]),
        },
        coords={"record": ["r"], "contact_gap_m": [0.01], "sample": [0, 1]},
    ).to_netcdf(path)
    code = f"""
import sys
import xarray as xr
import pound_mc
heavy = [m for m in {HEAVY!r} if m in sys.modules]
counts = xr.open_dataset({str(path)!r}).pound.status_counts()
print(heavy, int(counts["ok"]), pound_mc.open_dataset({str(path)!r}).pound.grid_dims)
"""
    assert _python(code) == "[] 2 ['contact_gap_m']"


def test_public_names_load_on_first_use():
    for name in pound_mc.__all__:
        assert getattr(pound_mc, name) is not None, name
    assert set(pound_mc.__all__) <= set(dir(pound_mc))
    assert pound_mc.xi_from_e is xi_from_e and pound_mc.RELATIONS is RELATIONS
    assert pound_mc.load_scene is load_scene
    with pytest.raises(AttributeError, match="no attribute 'nosuch'"):
        pound_mc.nosuch  # noqa: B018


def test_relation_names_are_the_registry():
    # the command line offers these names without importing the relations (scipy)
    assert tuple(RELATIONS) == RELATION_NAMES


def test_simulate_takes_a_path_or_a_scene_and_overrides():
    scene = load_scene(B1)
    by_path = pound_mc.simulate(B1)
    # DESIGN.md section 5: 22 impacts, peak force 7.0259e6 N (adaptive within 3e-5)
    assert by_path.outputs["impacts"] == 22
    assert by_path.outputs["peak_force"] == pytest.approx(7.0259e6, rel=3e-5)
    np.testing.assert_equal(pound_mc.simulate(scene).outputs, simulate(scene).outputs)
    np.testing.assert_equal(pound_mc.simulate(str(B1)).outputs, by_path.outputs)
    newmark = pound_mc.simulate(scene, method="newmark", dt_s=1e-3, history=True)
    same = simulate(scene, method="newmark", dt_s=1e-3, history=True)
    np.testing.assert_equal(newmark.outputs, same.outputs)
    assert newmark.force_N.shape == (newmark.time_s.size, 1)  # one contact
    with pytest.raises(InputError, match="dt_s"):
        pound_mc.simulate(scene, dt_s=0.0)
    with pytest.raises(InputError, match="nosuch.toml: scene file not found"):
        pound_mc.simulate(ROOT / "nosuch.toml")


def test_run_study_takes_a_path_or_a_study(make_study, tmp_path):
    path = make_study(grid={"left.period_s": [0.5]}, sampling={"n": 2})
    report = pound_mc.run_study(path, out=tmp_path / "a", threads=1, progress=False)
    assert report.complete and report.n_simulations == 4 and report.path.is_file()
    again = pound_mc.run_study(
        pound_mc.load_study(path), out=tmp_path / "b", threads=1, progress=False
    )
    first, second = pound_mc.open_dataset(report.path), pound_mc.open_dataset(again.path)
    xr.testing.assert_identical(first[["peak_force", "impacts"]], second[["peak_force", "impacts"]])
    assert int(first.pound.status_counts().sum()) == 4


@pytest.mark.parametrize(
    ("name", "words"),
    [("missing.nc", "no such file"), (".", "is a folder"), ("x.nc", "is not a netCDF dataset")],
)
def test_open_dataset_names_what_is_wrong(tmp_path, name, words):
    (tmp_path / "x.nc").write_bytes(b"not netCDF")
    path = tmp_path / name
    with pytest.raises(InputError, match=words) as info:
        pound_mc.open_dataset(path)
    assert str(path) in str(info.value)


def test_init_new_writes_a_commented_template_that_checks(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["init", "--new", "mystudy"]) == 0
    path = tmp_path / "mystudy.toml"
    text = path.read_text()
    assert text == study_template("mystudy")
    assert 'name = "mystudy"' in text and "{name}" not in text
    # commented: every table says what it takes
    comments = [line for line in text.splitlines() if "#" in line]
    assert len(comments) > 30
    capsys.readouterr()
    assert main(["check", str(path), "--threads", "1", "--calibrate", "4"]) == 0
    assert "study 'mystudy'" in capsys.readouterr().out
    # not over a file that exists, nor with a name a study cannot have, nor beside a name
    assert main(["init", "--new", "mystudy"]) == 2
    assert main(["init", "--new", "my study"]) == 2
    assert main(["init", "quickstart", "--new", "other"]) == 2
    err = capsys.readouterr().err
    assert "--force" in err and "--new" in err and "not both" in err
    assert not (tmp_path / "other.toml").exists() and not (tmp_path / "quickstart.toml").exists()
    assert main(["init", "--new", "other.toml", "--dir", "sub"]) == 0
    assert (tmp_path / "sub" / "other.toml").is_file()


def test_template_is_package_data():
    data = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert "templates/*.toml" in data["tool"]["setuptools"]["package-data"]["pound_mc"]
    assert (ROOT / "pound_mc" / "templates" / "study.toml").is_file()
