"""Record units (#38, point 3): the units an AT2 header names, the ``units`` key, the PEER default.

Conversion factors to m/s^2, written out here rather than read from the package so that a
wrong table entry fails (all exact by definition):
    g    = 9.80665     standard acceleration of gravity g_n (3rd CGPM, 1901; NIST SP 811, 2008,
                       appendix B.9, "acceleration"); the package's G
    in   = 0.0254 m    international inch (NIST SP 811, 2008, appendix B.8, "inch")
    ft   = 0.3048 m    international foot (NIST SP 811, 2008, appendix B.8, "foot")
    Gal  = 0.01 m/s^2  1 cm/s^2 (NIST SP 811, 2008, appendix B.8, "gal"); kilogal = 1000 Gal
"""

import json
from pathlib import Path

import numpy as np
import pytest

from pound_mc.cli import main
from pound_mc.errors import InputError
from pound_mc.motions import UNIT_SPELLINGS, UNITS, G, load_record, read_at2, read_record
from pound_mc.study.definition import load_study
from pound_mc.study.engine import load_traces

G_N = 9.80665  # standard gravity (CGPM 1901)
INCH = 0.0254  # m (NIST SP 811, B.8)
FOOT = 0.3048  # m (NIST SP 811, B.8)
GAL = 0.01  # m/s^2 (NIST SP 811, B.8)

# Samples as written in the file: peak |value| 40 at sample 2.
SAMPLES = [0.0, 12.5, -40.0, 3.0, 7.25, -1.5, 0.0, 2.0]
PEAK = 40.0

# header units (as the third line spells them) -> (canonical name, factor to m/s^2)
HEADER_UNITS = {
    "MM/S^2": ("mm/s^2", 1.0e-3),
    "MM/S/S": ("mm/s^2", 1.0e-3),
    "IN/S^2": ("in/s^2", INCH),
    "IN/S/S": ("in/s^2", INCH),
    "FT/S^2": ("ft/s^2", FOOT),
    "FT/S/S": ("ft/s^2", FOOT),
    "KILOGAL": ("kilogal", 1000.0 * GAL),
    "CM/S^2": ("gal", GAL),
    "G": ("g", G_N),
}


def write_at2(path: Path, third_line: str, samples=SAMPLES, *, title="PEER NGA STRONG MOTION"):
    """A small AT2 file in the NGA-West2 layout of the shipped RSN6 El Centro file."""
    lines = [
        title,
        "Test Event, 1/2/2003, Test Station #1, 090",
        third_line,
        f"NPTS= {len(samples):6d}, DT=   .0100 SEC,",
    ]
    for i in range(0, len(samples), 5):
        lines.append("".join(f"{v:15.7E}" for v in samples[i : i + 5]))
    path.write_text("\n".join(lines) + "\n", encoding="latin-1")
    return path


def peak(trace) -> float:
    return float(np.max(np.abs(trace.data)))


# ------------------------------------------------------------------------- header units


@pytest.mark.parametrize("spelling", [*HEADER_UNITS, None])
def test_header_units_converted(tmp_path, spelling):
    third = (
        "ACCELERATION TIME SERIES"
        if spelling is None
        else f"ACCELERATION TIME SERIES IN UNITS OF {spelling}"
    )
    path = write_at2(tmp_path / "r.AT2", third)
    name, factor = HEADER_UNITS[spelling] if spelling else ("g", G_N)
    for trace in (read_record(path), read_at2(path), load_record(path, demean=False)):
        assert peak(trace) == pytest.approx(PEAK * factor, rel=1e-12), spelling
        assert trace.stats.pound.source_units == name
        assert trace.stats.pound.source_units_from == ("header" if spelling else "default")
        np.testing.assert_allclose(trace.data, np.array(SAMPLES) * factor, rtol=1e-12)


@pytest.mark.parametrize(
    ("third", "name", "factor"),
    [
        ("ACCELERATION IN MM/S/S", "mm/s^2", 1.0e-3),  # "IN", no "UNITS OF"
        ("ACCELERATION (FT/SEC/SEC)", "ft/s^2", FOOT),  # in parentheses, "SEC"
        ("ACCELERATION TIME SERIES IN UNITS OF MM / S / S", "mm/s^2", 1.0e-3),  # spaces
        ("acceleration in units of in/sec^2", "in/s^2", INCH),  # lower case
        ("ACCELERATION, UNITS: KGAL", "kilogal", 1000.0 * GAL),
        ("ACCELERATION IN M/S**2", "m/s^2", 1.0),
        ("ACCELERATION IN IN/S/S", "in/s^2", INCH),  # the preposition is not the unit
        ("ACCELERATION TIME HISTORY IN UNITS OF G.", "g", G_N),  # trailing full stop
    ],
)
def test_header_layouts(tmp_path, third, name, factor):
    trace = read_record(write_at2(tmp_path / "r.AT2", third))
    assert trace.stats.pound.source_units == name
    assert peak(trace) == pytest.approx(PEAK * factor, rel=1e-12)


@pytest.mark.parametrize(
    ("third", "named"),
    [
        ("ACCELERATION TIME SERIES IN UNITS OF FURLONG/FORTNIGHT^2", "FURLONG/FORTNIGHT^2"),
        ("ACCELERATION IN FURLONG/FORTNIGHT^2", "FURLONG/FORTNIGHT^2"),  # no "UNITS OF"
        ("ACCELERATION IN FT/MIN2", "FT/MIN2"),
        ("ACCELERATION IN G, CM/S/S", "'G', 'CM/S/S'"),  # two units: which?
    ],
)
def test_unknown_header_units_refused(tmp_path, third, named):
    path = write_at2(tmp_path / "odd.AT2", third)
    for reader in (read_record, read_at2, load_record):
        with pytest.raises(InputError) as err:
            reader(path)
        msg = str(err.value)
        assert msg.startswith(f"{path}: line 3: the header names ")
        assert f"{third!r}" in msg and named in msg  # the line quoted, the units named
        assert "units key" in msg and "'mm/s^2'" in msg  # how to say what they are
        assert "\n" not in msg


def test_control_characters_in_the_header_are_escaped(tmp_path):
    third = "ACCELERATION IN UNITS OF \x1b[31mFURLONG/FORTNIGHT^2\x07"
    path = write_at2(tmp_path / "odd.AT2", third)
    with pytest.raises(InputError) as err:
        read_record(path)
    msg = str(err.value)
    assert "\\x1b[31mFURLONG/FORTNIGHT^2\\x07" in msg
    assert not any(ord(c) < 32 or 0x7F <= ord(c) < 0xA0 for c in msg), repr(msg)


def test_a_form_feed_does_not_shift_the_header_lines(tmp_path):
    # str.splitlines() splits at \x0c, \x0b, \x1c-\x1e and \x85 too: the title's form feed
    # made line 3 the NPTS line ("not a PEER AT2 file") and the units were never seen
    path = write_at2(tmp_path / "ff.AT2", "UNITS OF FT/S/S", title="PEER\x0cNGA\x85")
    trace = read_record(path)
    assert trace.stats.pound.source_units == "ft/s^2"
    assert peak(trace) == pytest.approx(PEAK * FOOT, rel=1e-12)


# ------------------------------------------------------------------------- the units key

# spellings of the units key -> factor to m/s^2
KEY_SPELLINGS = {
    "g": G_N,
    "G": G_N,
    "m/s^2": 1.0,
    "m/s/s": 1.0,
    "gal": GAL,
    "cm/s^2": GAL,
    "cm/sec/sec": GAL,
    "mm/s^2": 1.0e-3,
    "mm/s/s": 1.0e-3,
    "mm/sec2": 1.0e-3,
    " MM / S ^ 2 ": 1.0e-3,
    "in/s^2": INCH,
    "in/s/s": INCH,
    "in/sec^2": INCH,
    "ft/s^2": FOOT,
    "ft/s/s": FOOT,
    "ft/sec/sec": FOOT,
    "ft/s\u00b2": FOOT,
    "kilogal": 1000.0 * GAL,
    "kgal": 1000.0 * GAL,
}


@pytest.mark.parametrize(("units", "factor"), KEY_SPELLINGS.items())
def test_units_key_overrides_the_header(tmp_path, units, factor):
    path = write_at2(tmp_path / "r.AT2", "ACCELERATION TIME SERIES IN UNITS OF G")
    trace = read_record(path, units=units)
    assert peak(trace) == pytest.approx(PEAK * factor, rel=1e-12)
    assert trace.stats.pound.source_units_from == "units"
    assert UNITS[trace.stats.pound.source_units] == pytest.approx(factor, rel=1e-15)


def test_one_table_for_the_key_and_the_header(tmp_path):
    """Every spelling the units key takes, written in a header, reads the same."""
    assert UNITS["g"] == G == G_N
    for spelling, name in UNIT_SPELLINGS.items():
        path = write_at2(tmp_path / "r.AT2", f"ACCELERATION IN UNITS OF {spelling.upper()}")
        trace = read_record(path)
        assert trace.stats.pound.source_units == name, spelling
        assert read_record(path, units=spelling).stats.pound.source_units == name


def test_units_key_gives_units_to_a_refused_header(tmp_path):
    path = write_at2(tmp_path / "odd.AT2", "UNITS OF FURLONG/FORTNIGHT^2")
    trace = read_record(path, units="in/s^2")
    assert peak(trace) == pytest.approx(PEAK * INCH, rel=1e-12)
    assert read_at2(path, units="ft/s/s").stats.pound.source_units == "ft/s^2"


# ------------------------------------------------------------------------- studies


def test_study_naming_a_record_in_unknown_units(tmp_path, capsys, make_study):
    write_at2(tmp_path / "odd.AT2", "ACCELERATION TIME SERIES IN UNITS OF FURLONG/FORTNIGHT^2")
    record = {"source": "odd.AT2", "duration_s": None}
    path = make_study(record=record)
    out = tmp_path / "outputs"
    for argv in (
        ["check", str(path)],
        ["run", str(path), "--out", str(out), "--no-progress", "--no-plot"],
    ):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert "Traceback" not in err and err.count("\n") == 1, err
        assert f"{path}: record.source: {tmp_path / 'odd.AT2'}: line 3: the header names " in err
        assert "FURLONG/FORTNIGHT^2" in err and "units key" in err
    assert not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["odd.AT2", "small.toml"]


def test_study_units_key_reads_such_a_record(tmp_path, make_study):
    write_at2(tmp_path / "odd.AT2", "ACCELERATION TIME SERIES IN UNITS OF FURLONG/FORTNIGHT^2")
    record = {"source": "odd.AT2", "duration_s": None, "pga_g": None, "units": "in/sec^2"}
    (trace,) = load_traces(load_study(make_study(record=record)))
    # demeaned, so compare with the demeaned samples in inches per second squared
    expected = (np.array(SAMPLES) - np.mean(SAMPLES)) * INCH
    np.testing.assert_allclose(trace.data, expected, rtol=1e-12, atol=1e-15)
    assert trace.stats.pound.source_units == "in/s^2"


# ------------------------------------------------------------------------- pound-mc records info


def test_records_info_says_where_the_units_came_from(tmp_path, capsys):
    none = write_at2(tmp_path / "none.AT2", "ACCELERATION TIME SERIES")
    assert main(["records", "info", str(none)]) == 0
    out = capsys.readouterr().out
    assert "source units g (the PEER default: the AT2 header names no units, so g)" in out

    header = write_at2(tmp_path / "mm.AT2", "ACCELERATION TIME SERIES IN UNITS OF MM/S/S")
    assert main(["records", "info", str(header)]) == 0
    out = capsys.readouterr().out
    assert (
        "source units mm/s^2 (named by the file's header, line 3: "
        "'ACCELERATION TIME SERIES IN UNITS OF MM/S/S')"
    ) in out

    assert main(["records", "info", str(header), "--units", "ft/s/s", "--raw", "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["source_units"] == "ft/s^2" and info["source_units_from"] == "units"
    assert info["pga_m_s2"] == pytest.approx(PEAK * FOOT, rel=1e-12)
    assert main(["records", "info", str(header), "--units", "ft/s/s"]) == 0
    assert "source units ft/s^2 (given with --units)" in capsys.readouterr().out

    assert main(["records", "info", str(none), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["source_units_from"] == "default"


def test_records_info_refuses_unknown_units(tmp_path, capsys):
    path = write_at2(tmp_path / "odd.AT2", "UNITS OF FURLONG/FORTNIGHT^2")
    assert main(["records", "info", str(path)]) == 2
    err = capsys.readouterr().err
    assert f"{path}: line 3:" in err and "'UNITS OF FURLONG/FORTNIGHT^2'" in err
    assert "--units" in err and "Traceback" not in err


def test_records_info_units_help_lists_every_unit(capsys):
    with pytest.raises(SystemExit):
        main(["records", "info", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    for name in UNITS:
        assert name in text, name
