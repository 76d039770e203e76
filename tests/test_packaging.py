"""Packaging, ``pound-mc init`` and the help texts (issue 15)."""

import argparse
import re
import tomllib
from pathlib import Path

import pytest
import xarray as xr

from pound_mc.cli import build_parser, main
from pound_mc.cli.study import shipped_studies

ROOT = Path(__file__).resolve().parent.parent


def test_init_lists_and_writes_a_shipped_study(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["init"]) == 0
    listed = capsys.readouterr().out
    for path in (ROOT / "studies").glob("*.toml"):
        # each by its whole one-line description (the first comment line was cut mid-sentence)
        about = tomllib.loads(path.read_text())["study"]["description"]
        assert f"{path.stem:20s} {about}\n" in listed
    assert main(["init", "quickstart"]) == 0
    written = tmp_path / "quickstart.toml"
    assert written.read_text() == (ROOT / "studies" / "quickstart.toml").read_text()
    # a second init does not overwrite; --force does
    assert main(["init", "quickstart"]) == 2
    err = capsys.readouterr().err.strip()
    assert "quickstart.toml" in err and "--force" in err and "\n" not in err
    assert main(["init", "quickstart", "--force"]) == 0
    assert main(["init", "nosuch"]) == 2
    assert "quickstart" in capsys.readouterr().err  # the message lists what there is
    assert main(["check", str(written)]) == 0


def test_the_shipped_studies_are_package_data():
    # the package's studies are the repository's (pound_mc/studies -> ../studies)
    assert {p.name for p in shipped_studies().values()} == {
        p.name for p in (ROOT / "studies").glob("*.toml")
    }
    data = tomllib.loads((ROOT / "pyproject.toml").read_text())
    package_data = data["tool"]["setuptools"]["package-data"]["pound_mc"]
    assert "studies/*.toml" in package_data and "py.typed" in package_data
    assert (ROOT / "pound_mc" / "py.typed").exists()


def test_license_citation_and_one_version():
    text = (ROOT / "LICENSE").read_text()
    assert text.startswith("BSD 3-Clause License") and "pound-mc developers" in text
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert project["license"] == "BSD-3-Clause" and project["dynamic"] == ["version"]
    assert any(c.startswith("Typing :: Typed") for c in project["classifiers"])
    citation = (ROOT / "CITATION.cff").read_text()
    assert "cff-version: 1.2.0" in citation and "pound-mc developers" in citation
    assert "\nversion:" not in citation  # the version lives in pound_mc/_version.py only


def _parsers():
    parser = build_parser()
    yield "pound-mc", parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield name, sub
                for inner in sub._actions:
                    if isinstance(inner, argparse._SubParsersAction):
                        yield from ((f"{name} {n}", p) for n, p in inner.choices.items())


def test_help_texts_are_plain_and_show_defaults():
    names = [n for n, _ in _parsers()]
    assert names[1:3] == ["run", "check"]  # run and check first
    for name, parser in _parsers():
        text = parser.format_help()
        assert not re.search(r"``|:func:|:mod:|:class:|^=+\s+=+", text, re.M), name
        for action in parser._actions:
            if action.option_strings and action.default not in (None, False, [], "==SUPPRESS=="):
                line = " ".join(text.split())
                assert "default" in (action.help or "") or f"default: {action.default}" in (
                    line.replace("'", "").replace("[", "").replace("]", "")
                    if isinstance(action.default, list)
                    else line
                ), (name, action.dest)


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["plot", "{nc}", "--kind", "work-precision"], "is not a CSV table"),
        (["plot", "{png}", "--kind", "spectrum"], "is not a netCDF dataset"),
        (["report", "{png}"], "is not a netCDF dataset"),
        (["report", "{missing}"], "no such file"),
        (["plot", "{nc}", "--kind", "probability", "--record", "99"], "out of range"),
        (["records", "info", "{png}"], "unknown format"),
    ],
)
def test_error_paths_name_the_file_in_one_line(args, words, tmp_path, capsys):
    png = tmp_path / "chart.png"
    png.write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(64))
    nc = tmp_path / "result.nc"
    dims = ("record", "contact_gap_m", "sample")
    xr.Dataset(
        {name: (dims, [[[value]]]) for name, value in (("peak_force", 1.0), ("impacts", 1),
                                                       ("status", 0))},
        coords={"record": ["r"], "contact_gap_m": [0.0], "sample": [0]},
    ).to_netcdf(nc)  # fmt: skip
    paths = {"nc": nc, "png": png, "missing": tmp_path / "missing.nc"}
    argv = [a.format(**paths) for a in args]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err, err
    file = next(a for a in argv if a.startswith(str(tmp_path)))
    assert Path(file).name in err and words in err, err
