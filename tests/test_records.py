import json
import re
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from pound_mc.cli import main
from pound_mc.errors import InputError
from pound_mc.motions import (
    G,
    builtin_catalogue,
    catalogue,
    load_record,
    make_trace,
    preprocess,
    read_at2,
    read_record,
    record_arrays,
    record_info,
    traces,
)
from pound_mc.physics.spectra import response_spectrum

# obspy is imported through pound_mc.motions.traces, which silences its import-time deprecation
# warning (filterwarnings = error)
obspy = traces.obspy
ELCENTRO = catalogue._builtin_path("elcentro")
KNET = catalogue._builtin_path("knet-akt013")


# ----------------------------------------------------------------------------- real records


def test_elcentro_through_the_at2_reader():
    tr = read_at2(ELCENTRO)
    # PEER NGA RSN6 file header: "NPTS=   5372, DT=   .0100 SEC", units of g; its largest
    # sample is -.2807955E+00 (line 48 of the file), so PGA = 0.2807955 g to the file's 7 digits.
    assert tr.stats.npts == 5372
    assert tr.stats.delta == 0.01
    assert np.max(np.abs(tr.data)) / G == pytest.approx(0.2807955, abs=5e-8)
    assert tr.data.min() / G == pytest.approx(-0.2807955, abs=5e-8)
    pound = tr.stats.pound
    assert pound.event == "Imperial Valley-02"
    assert pound.date == "5/19/1940"
    assert pound.station == "El Centro Array #9"
    assert pound.component == "180"
    assert pound.source_units == "g" and pound.units == "m/s^2"
    # the builtin resolves to the same samples, demeaned by default
    b = load_record("builtin:elcentro", demean=False)
    np.testing.assert_array_equal(b.data, tr.data)
    info = record_info(load_record("builtin:elcentro"))
    assert info["npts"] == 5372 and info["dt_s"] == 0.01
    assert info["duration_s"] == pytest.approx(53.71)


def test_knet_pga_matches_the_header_after_demeaning():
    text = KNET.read_text()
    header_gal = float(re.search(r"Max\. Acc\. \(gal\)\s+(\S+)", text).group(1))
    scale = re.search(r"Scale Factor\s+(\d+)\(gal\)/(\d+)", text)
    assert header_gal == 4.383
    tr = read_record(KNET)
    raw = obspy.read(str(KNET))[0]
    # obspy gives raw counts and puts the header's scale factor, in m/s^2, in stats.calib
    assert raw.stats.calib == pytest.approx(0.01 * int(scale[1]) / int(scale[2]), rel=1e-15)
    np.testing.assert_allclose(tr.data, raw.data * raw.stats.calib, rtol=1e-15)
    assert tr.stats.pound.units == "m/s^2" and tr.stats.pound.component == "EW"
    # the header's maximum is that of the demeaned record, 4.383 gal = 0.04383 m/s^2; the
    # header gives 3 decimals in gal, so it is exact to +-0.0005 gal = 5e-6 m/s^2
    demeaned = load_record("builtin:knet-akt013")
    pga = np.max(np.abs(demeaned.data))
    assert pga == pytest.approx(header_gal * 0.01, abs=5e-6)  # measured 0.0438328 m/s^2
    assert demeaned.stats.pound.units == "m/s^2"
    assert record_info(demeaned)["units"] == "m/s^2"
    assert "M5.9" in demeaned.stats.pound.event


def test_evt_builtins_calibrated_and_channels_selected():
    tr = load_record("builtin:evt-mola-2012", component="2", demean=False)
    path = catalogue._builtin_path("evt-mola-2012")
    # obspy's EVT calibration uses g = 9.81; ours uses the standard gravity
    with pytest.warns(UserWarning, match="Unmatched raw value"):
        raw = obspy.read(str(path)).select(channel="2")[0]
    np.testing.assert_allclose(tr.data, raw.data * raw.stats.calib * G / 9.81, rtol=1e-14)
    # obspy warns about header fields of this file: recorded, not raised
    assert any("Unmatched raw value" in w for w in tr.stats.pound.read_warnings)
    with pytest.raises(InputError) as err:
        read_record(path)
    assert "6 components" in str(err.value) and "'0', '1', '2', '3', '4', '5'" in str(err.value)
    assert str(path) in str(err.value)


def test_every_builtin_resolves_without_network():
    catalogue = builtin_catalogue()
    assert {"knet-akt013", "elcentro", "elcentro-270"} <= set(catalogue)
    for name, entry in catalogue.items():
        assert re.fullmatch(r"[a-z0-9]+(-[a-z0-9]+)*", name)
        for key in ("event", "year", "station", "component", "source_package", "format"):
            assert entry[key], (name, key)
        info = record_info(load_record(f"builtin:{name}"))
        assert info["npts"] > 900 and 0 < info["pga_g"] < 2, name
        assert info["component"] == entry["component"]


# ----------------------------------------------------------------------------- AT2 variants


def _at2(path: Path, values, *, per_line=5, variant="nga", dt=0.02, npts=None, units_line=None):
    npts = len(values) if npts is None else npts
    # PEER files write DT without the leading zero ("DT=   .0100 SEC", as in the shipped
    # RSN6 El Centro file); the "-dot" variants do the same
    dot = f"{dt:.4f}".removeprefix("0")
    line4 = {
        "nga": f"NPTS= {npts:6d}, DT=   {dt:.4f} SEC,",
        "old": f"{npts}   {dt:.4f}   NPTS, DT",
        "nga-dot": f"NPTS= {npts:6d}, DT=   {dot} SEC",
        "old-dot": f"{npts:7d}   {dot}   NPTS, DT",
    }[variant]
    lines = [
        "PEER NGA STRONG MOTION DATABASE RECORD",
        "Test Event, 1/2/2003, Test Station #1, 090",
        units_line or "ACCELERATION TIME SERIES IN UNITS OF G",
        line4,
    ]
    for i in range(0, len(values), per_line):
        lines.append("".join(f"{v:15.7E}" for v in values[i : i + per_line]))
    path.write_text("\n".join(lines) + "\n")
    return path


VALUES = [0.001 * (-1) ** i * (i % 7) for i in range(23)]


@pytest.mark.parametrize("variant", ["nga", "old", "nga-dot", "old-dot"])
@pytest.mark.parametrize("per_line", [1, 5, 8])
def test_at2_header_variants_and_line_widths_parse_identically(tmp_path, variant, per_line):
    path = _at2(tmp_path / "r.at2", VALUES, per_line=per_line, variant=variant)
    if variant.endswith("-dot"):
        assert re.search(r"\s\.0200\s", path.read_text().splitlines()[3])
    tr = read_at2(path)
    reference = read_at2(_at2(tmp_path / "ref.at2", VALUES))
    np.testing.assert_array_equal(tr.data, reference.data)
    np.testing.assert_allclose(tr.data, np.array(VALUES) * G, rtol=1e-7)
    assert tr.stats.delta == 0.02 and tr.stats.npts == 23
    assert tr.stats.pound.component == "090"


def test_at2_detected_by_content_and_units_from_header(tmp_path):
    path = _at2(tmp_path / "motion.txt", VALUES, units_line="ACCELERATION IN CM/S/S")
    tr = read_record(path)
    assert tr.stats.pound.format == "AT2" and tr.stats.pound.source_units == "gal"
    np.testing.assert_allclose(tr.data, np.array(VALUES) * 0.01, rtol=1e-7)
    # an explicit units key overrides the header
    tr = read_record(path, units="m/s^2")
    np.testing.assert_allclose(tr.data, VALUES, rtol=1e-7)


def test_relative_path_resolved_against_base_dir(tmp_path):
    _at2(tmp_path / "r.AT2", VALUES)
    tr = load_record("r.AT2", base_dir=tmp_path, demean=False)
    np.testing.assert_allclose(tr.data, np.array(VALUES) * G, rtol=1e-7)
    assert record_info(tr)["source"] == "r.AT2"


def test_miniseed_needs_units_and_sac_keeps_event(tmp_path):
    data = np.array([0.0, 1.5, -3.0, 2.0, 0.5])
    tr = obspy.Trace(data=data.copy(), header={"delta": 0.01, "station": "ST1", "channel": "HNE"})
    tr.write(str(tmp_path / "a.mseed"), format="MSEED")
    with pytest.raises(InputError) as err:
        read_record(tmp_path / "a.mseed")
    assert "MSEED does not say what units" in str(err.value)
    assert "a.mseed" in str(err.value) and err.value.key == "record.units"
    ms = read_record(tmp_path / "a.mseed", units="gal")
    np.testing.assert_allclose(ms.data, data * 0.01)
    tr.stats.sac = {"kevnm": "TESTQUAKE"}
    tr.write(str(tmp_path / "a.sac"), format="SAC")
    sac = read_record(tmp_path / "a.sac", units="g", component="HNE")
    np.testing.assert_allclose(sac.data, data * G)
    assert sac.stats.pound.event == "TESTQUAKE" and sac.stats.pound.format == "SAC"


# ----------------------------------------------------------------------------- bad input


def _message(call, *args, **kwargs) -> str:
    with pytest.raises(InputError) as err:
        call(*args, **kwargs)
    return str(err.value)


def test_pickle_refused(tmp_path):
    obspy.Stream([obspy.Trace(np.zeros(3))]).write(str(tmp_path / "s.pkl"), format="PICKLE")
    assert "pickled obspy streams are not read" in _message(read_record, tmp_path / "s.pkl")


def test_missing_file(tmp_path):
    msg = _message(read_record, tmp_path / "nope.AT2")
    assert "nope.AT2" in msg and "file not found" in msg


def test_unknown_format(tmp_path):
    path = tmp_path / "notes.dat"
    path.write_text("this is not a seismogram\n1 2 3\n")
    msg = _message(read_record, path)
    assert "notes.dat" in msg and "unknown format" in msg and "MSEED" in msg and "AT2" in msg


def test_truncated_miniseed(tmp_path):
    """A MiniSEED file cut inside a record was read as its first 223 of 2,400 samples without a
    word (obspy warns and stops); it is refused, as a truncated AT2 file is."""
    data = Path(obspy.__file__).parent / "clients" / "filesystem" / "tests" / "data"
    whole = data / "tsindex_data" / "IU" / "2018" / "001"
    whole = whole / "IU.ANMO.10.BHZ.2018.001_first_minute.mseed"
    if not whole.is_file():
        pytest.skip("obspy's test data are not installed")
    assert len(read_record(whole, units="m/s^2").data) == 2400  # the whole file reads
    cut = tmp_path / "cut.mseed"
    cut.write_bytes(whole.read_bytes()[:700])
    msg = _message(read_record, cut)
    assert "cut.mseed" in msg and "truncated" in msg and "223 samples" in msg


def test_truncated_and_padded_at2(tmp_path):
    short = _at2(tmp_path / "short.AT2", VALUES, npts=30)
    msg = _message(read_record, short)
    assert "short.AT2" in msg and "NPTS = 30" in msg and "holds 23" in msg and "truncated" in msg
    long = _at2(tmp_path / "long.AT2", VALUES, npts=20)
    msg = _message(read_at2, long)
    assert "long.AT2" in msg and "NPTS = 20" in msg and "padded" in msg


def test_non_numeric_value(tmp_path):
    path = _at2(tmp_path / "bad.AT2", VALUES)
    lines = path.read_text().splitlines()
    lines[6] = lines[6].replace("E-03", "X-03", 1)
    path.write_text("\n".join(lines))
    msg = _message(read_at2, path)
    assert "bad.AT2: line 7" in msg and "non-numeric value" in msg


@pytest.mark.parametrize("bad", ["NaN", "inf", "-Infinity"])
def test_non_finite_samples(tmp_path, bad):
    path = _at2(tmp_path / "nan.AT2", VALUES)
    lines = path.read_text().splitlines()
    tokens = lines[5].split()
    tokens[2] = bad
    lines[5] = "  ".join(tokens)
    path.write_text("\n".join(lines))
    msg = _message(read_at2, path)
    assert "nan.AT2: line 6" in msg and "NaN or infinite" in msg
    # the eighth value (line 5 holds samples 0-4): the index is 0-based and says so
    assert "sample 7 (0-based index" in msg
    # the value is printed plainly, not as numpy's repr
    assert "np.float64" not in msg
    assert f" {float(bad)}: " in msg


def test_at2_header_problems(tmp_path):
    path = _at2(tmp_path / "vel.AT2", VALUES, units_line="VELOCITY TIME SERIES IN UNITS OF CM/S")
    msg = _message(read_at2, path)
    assert "vel.AT2: line 3" in msg and "not an acceleration record" in msg
    path = tmp_path / "head.AT2"
    path.write_text("title\nevent\nACCELERATION\n5372 samples every 0.01 s\n0.1 0.2\n")
    msg = _message(read_record, path)
    assert "head.AT2: line 4" in msg and "NPTS=  5372, DT=   .0100 SEC" in msg


@pytest.mark.parametrize("dt", [0.0, -0.01])
def test_zero_or_negative_dt(tmp_path, dt):
    path = _at2(tmp_path / "dt.AT2", VALUES)
    text = path.read_text().replace("DT=   0.0200", f"DT=   {dt}")
    path.write_text(text)
    msg = _message(read_at2, path)
    assert "dt.AT2" in msg and "sampling interval must be > 0 s" in msg


def test_empty_records(tmp_path):
    empty = tmp_path / "empty.AT2"
    empty.write_text("")
    assert "empty.AT2: the file is empty" in _message(read_record, empty)
    none = _at2(tmp_path / "none.AT2", [], npts=0)
    msg = _message(read_record, none)
    assert "none.AT2" in msg and "empty record" in msg
    with pytest.raises(InputError, match="empty record"):
        preprocess(make_trace([], 0.01, source="x"))


def test_duration_longer_than_the_record():
    msg = _message(load_record, "builtin:elcentro", duration_s=60.0)
    assert "builtin:elcentro" in msg or "ELC180" in msg
    assert "record.duration_s" in msg and "longer than the record (53.71 s" in msg
    # the whole record is allowed
    assert load_record("builtin:elcentro", duration_s=53.71).stats.npts == 5372


@pytest.mark.parametrize("units", ["furlongs", "G's", 9.81])
def test_bad_units(units):
    msg = _message(load_record, "builtin:elcentro", units=units)
    assert "record.units" in msg and "'g', 'gal', 'm/s^2'" in msg and "ELC180" in msg


def test_units_aliases_and_case():
    a = read_record(ELCENTRO, units="G")
    b = read_record(ELCENTRO, units="cm/s^2")
    np.testing.assert_allclose(a.data, b.data * G / 0.01)


def test_unknown_builtin_name():
    msg = _message(load_record, "builtin:elcentr0")
    assert "builtin:elcentr0" in msg and "unknown built-in record 'elcentr0'" in msg
    assert "knet-akt013" in msg and "elcentro" in msg


def test_unknown_source_kind():
    msg = _message(load_record, "bultin:elcentro")
    assert "unknown source kind 'bultin:'" in msg


def test_bad_component(tmp_path):
    msg = _message(load_record, "builtin:knet-akt013", component="NS")
    assert "test.knet" in msg and "record.component" in msg and "no component 'NS'" in msg
    assert "('EW')" in msg
    msg = _message(load_record, "builtin:evt-stna-2002", component="9")
    assert "STNA.20020722.044649.evt.gz" in msg and "'0', '1', '2'" in msg


@pytest.mark.parametrize("value", [0.0, -5.0, float("nan"), "ten"])
def test_bad_duration_and_pga(value):
    assert "record.duration_s" in _message(load_record, "builtin:elcentro", duration_s=value)
    assert "record.pga_g" in _message(load_record, "builtin:elcentro", pga_g=value)


def test_scaling_an_all_zero_record():
    with pytest.raises(InputError, match="all zero"):
        preprocess(make_trace(np.zeros(5), 0.1, source="zeros"), pga_g=0.3)


# ----------------------------------------------------------------------------- preprocessing


def test_preprocess_order_demean_truncate_scale():
    # whole-record mean 4 -> [-2, 0, -4, 6]; keep t <= 2 s -> [-2, 0, -4]; peak 4 -> 0.5 g
    tr = make_trace([2.0, 4.0, 0.0, 10.0], 1.0, source="known")
    out = preprocess(tr, duration_s=2.0, pga_g=0.5)
    np.testing.assert_allclose(out.data, np.array([-2.0, 0.0, -4.0]) * (0.5 * G / 4.0))
    # any other order gives other numbers: truncating first would remove the mean 2, not 4;
    # scaling before truncating would use the peak 6
    assert [s.split(":")[0] for s in out.stats.pound.processing] == [
        "demean",
        "truncate",
        "scale",
    ]
    np.testing.assert_array_equal(tr.data, [2.0, 4.0, 0.0, 10.0])  # input untouched
    kept = preprocess(tr, demean=False, duration_s=1.999999)
    np.testing.assert_array_equal(kept.data, [2.0, 4.0])


def test_benchmark_b1_record():
    # DESIGN.md section 5: K-NET AKT013, demeaned, first 30 s, PGA 0.3 g
    tr = load_record("builtin:knet-akt013", duration_s=30.0, pga_g=0.3)
    dt, acc = record_arrays(tr)
    assert dt == 0.01 and acc.size == 3001
    assert acc.dtype == np.float64 and acc.flags.c_contiguous
    assert np.max(np.abs(acc)) == pytest.approx(0.3 * G, rel=1e-14)


def test_optional_filter_and_resample():
    tr = load_record("builtin:elcentro", filter={"type": "highpass", "freq": 0.1})
    assert tr.stats.pound.processing[1].startswith("filter")
    tr = load_record("builtin:elcentro", resample_hz=50.0, duration_s=10.0)
    assert tr.stats.delta == 0.02 and tr.stats.npts == 501
    msg = _message(load_record, "builtin:elcentro", filter={"freq": 1.0})
    assert "record.filter" in msg


def test_resampling_keeps_the_spectrum(tmp_path):
    """obspy's default Hann taper cut a 10-Hz sine at 100 Hz to 0.271 g of 0.3 g when resampled
    to 200 Hz (K-NET AKT013's PGA by 13 %).  Reference: the sine itself, 30 whole cycles (a
    periodic signal, which Fourier resampling reproduces to round-off)."""
    t = np.arange(300) * 0.01
    values = 0.3 * np.sin(2 * np.pi * 10.0 * t)
    rows = ["  ".join(f"{v: .9E}" for v in values[i : i + 5]) for i in range(0, 300, 5)]
    path = tmp_path / "sine.at2"
    path.write_text("\n".join(["PEER NGA STRONG MOTION DATABASE RECORD", "Sine, Test, 0",
                               "ACCELERATION TIME SERIES IN UNITS OF G",
                               "NPTS=  300, DT=   0.0100 SEC", *rows]) + "\n")  # fmt: skip
    dt, acc = record_arrays(load_record(str(path), resample_hz=200.0, demean=False))
    assert dt == 0.005 and acc.size == 600
    exact = 0.3 * G * np.sin(2 * np.pi * 10.0 * np.arange(600) * 0.005)
    np.testing.assert_allclose(acc, exact, rtol=0, atol=1e-8 * 0.3 * G)


# ----------------------------------------------------------------------------- spectra


@pytest.mark.slow
def test_response_spectrum_against_an_ode_solver():
    dt, acc = record_arrays(load_record("builtin:elcentro", duration_s=4.0))
    t = np.arange(acc.size) * dt
    periods = [0.1, 0.5, 2.0]
    psa = response_spectrum(dt, acc, periods, damping=0.05)
    for period, value in zip(periods, psa, strict=True):
        w = 2 * np.pi / period

        def rhs(s, y, w=w):
            return [y[1], -np.interp(s, t, acc) - 0.1 * w * y[1] - w * w * y[0]]

        sol = solve_ivp(
            rhs,
            (0, t[-1]),
            [0, 0],
            t_eval=t,
            method="DOP853",
            rtol=1e-10,
            atol=1e-12,
            max_step=dt,
        )
        # the exact recurrence and a tight-tolerance solver agree (sampled maxima)
        assert value == pytest.approx(w * w * np.max(np.abs(sol.y[0])), rel=1e-6)
    # a very stiff oscillator follows the ground: PSA -> PGA
    stiff = response_spectrum(dt, acc, [1e-3])[0]
    assert stiff == pytest.approx(np.max(np.abs(acc)), rel=1e-3)
    with pytest.raises(InputError, match="periods"):
        response_spectrum(dt, acc, [0.0])


# ----------------------------------------------------------------------------- CLI


def test_cli_records_list(capsys):
    assert main(["records", "list"]) == 0
    out = capsys.readouterr().out
    assert "builtin:knet-akt013" in out and "builtin:elcentro" in out and "El Centro" in out
    assert main(["records", "list", "--json"]) == 0
    assert "elcentro-270" in json.loads(capsys.readouterr().out)


def test_cli_records_info_json(capsys):
    assert main(["records", "info", "builtin:elcentro", "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["npts"] == 5372 and info["dt_s"] == 0.01 and info["units"] == "m/s^2"
    assert info["pga_g"] == pytest.approx(0.2808, abs=1e-4)
    assert info["duration_s"] == pytest.approx(53.71)


def test_cli_records_info_plot(tmp_path, capsys):
    png = tmp_path / "knet.png"
    assert main(["records", "info", "knet-akt013", "--plot", str(png)]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    out = capsys.readouterr().out
    assert "PGA" in out and f"wrote {png}" in out


def test_cli_records_info_errors(capsys):
    assert main(["records", "info", "builtin:nowhere"]) == 2
    err = capsys.readouterr().err
    assert "unknown built-in record 'nowhere'" in err
    assert main(["records", "info", "builtin:evt-mola-2012", "--component", "7"]) == 2
    assert "no component '7'" in capsys.readouterr().err
    # a bare name that is neither a file nor a catalogue entry: where the names are
    assert main(["records", "info", "elcentr"]) == 2
    err = capsys.readouterr().err
    assert "elcentr: file not found, nor a built-in record (pound-mc records list)" in err


def _bad_record_files(tmp_path) -> dict[str, Path]:
    """Broken records, each with the problem its name says."""
    files = {"missing": tmp_path / "missing.AT2"}
    files["truncated"] = _at2(tmp_path / "truncated.AT2", VALUES, npts=30)
    nan = _at2(tmp_path / "nan.AT2", VALUES)
    nan.write_text(nan.read_text().replace("1.0000000E-03", "NaN", 1))
    files["nan"] = nan
    zero = _at2(tmp_path / "zerodt.AT2", VALUES)
    zero.write_text(zero.read_text().replace("DT=   0.0200", "DT=   0.0000"))
    files["zero dt"] = zero
    files["empty"] = tmp_path / "empty.AT2"
    files["empty"].write_text("")
    return files


@pytest.mark.parametrize("problem", ["missing", "truncated", "nan", "zero dt", "empty"])
def test_cli_records_info_bad_files(tmp_path, capsys, problem):
    path = _bad_record_files(tmp_path)[problem]
    assert main(["records", "info", str(path)]) == 2
    captured = capsys.readouterr()
    assert path.name in captured.err
    assert "Traceback" not in captured.err and "Traceback" not in captured.out
    expected = {
        "missing": "file not found",
        "truncated": "NPTS = 30",
        "nan": "NaN or infinite",
        "zero dt": "sampling interval must be > 0 s",
        "empty": "the file is empty",
    }[problem]
    assert expected in captured.err


# ------------------------------------------------- record errors in a study: each thing once


def _study_error(tmp_path, capsys, make_study, **tables) -> str:
    """``pound-mc run`` on the small study with ``tables``: exit 2, one line, nothing written;
    the message after the program's prefix, the study's folder written as ``DIR``."""
    path = make_study(**tables)
    out = tmp_path / "outputs"
    assert main(["run", str(path), "--out", str(out), "--no-progress", "--no-plot"]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and err.count("\n") == 1, err
    assert not out.exists()
    return err.removeprefix("pound-mc run: error: ").rstrip("\n").replace(str(tmp_path), "DIR")


def test_record_file_line_is_the_record_files_not_the_studys(tmp_path, capsys, make_study):
    # a glob matching a three-line file: "line 4" was given as the study's key, and the
    # record's name twice ("small.toml: line 4: r/a.AT2: r/a.AT2: line 4: ...")
    (tmp_path / "r").mkdir()
    (tmp_path / "r" / "a.AT2").write_text("PEER\nquake\nACCELERATION IN G\n")
    records = [{"source": "r/*.AT2", "duration_s": 0.5}]
    err = _study_error(tmp_path, capsys, make_study, record=None, records=records)
    assert err.startswith(
        "DIR/small.toml: records[0].source: DIR/r/a.AT2: line 4: not a PEER AT2 file: "
    ), err
    assert err.count("a.AT2") == 1 and err.count("line 4") == 2  # "... line 4 must give ..."


def test_record_key_error_names_the_record_once(tmp_path, capsys, make_study):
    record = {"source": "builtin:knet-akt013", "component": "XYZ"}
    err = _study_error(tmp_path, capsys, make_study, record=record)
    # was "small.toml: record.component: builtin:knet-akt013 (test.knet): builtin:knet-akt013
    # (test.knet): record.component: no component ..."
    assert err == (
        "DIR/small.toml: record.component: builtin:knet-akt013 (test.knet): no component 'XYZ' "
        "in the file; choose one of ('EW')"
    )


def test_a_window_that_misses_the_strong_motion_is_named(make_study, capsys):
    """``duration_s`` cut the FEMA P695 Chi-Chi components of the quickstart to their
    pre-event noise (0.04 % of the peak), which ``pga_g`` then scaled by up to 2,600 without a
    word.  The fraction of the peak a window keeps is recorded, and ``check`` and ``run`` name
    the records that keep less than half.  Reference: the maxima of the demeaned record by hand
    (K-NET AKT013: its first 4 s hold the P-wave onset only)."""
    whole = load_record("builtin:knet-akt013")
    cut = load_record("builtin:knet-akt013", duration_s=4.0)
    kept = np.max(np.abs(cut.data)) / np.max(np.abs(whole.data))
    assert cut.stats.pound.window_peak_fraction == pytest.approx(kept, rel=1e-12)
    assert kept < 0.02
    assert load_record("builtin:knet-akt013", duration_s=30.0).stats.pound.window_peak_fraction == 1
    study = make_study(record={"source": "builtin:knet-akt013"})  # its first 4 s
    assert main(["check", str(study)]) == 0
    out = capsys.readouterr().out
    assert f"warning: {study}: the duration_s window of 1 of 1 records keeps less than " in out
    assert "50 % of their peak acceleration, which comes later: builtin:knet-akt013 " in out
    assert f"({100 * kept:.2g} %); scaled" in out
    # a scene file with that window: simulate says so too (on standard error)
    scene = study.with_name("scene.toml")
    text = study.read_text()
    scene.write_text(text[text.index("[record]") : text.index("[grid]")])
    assert main(["simulate", str(scene)]) == 0
    assert f"warning: {scene}: the record.duration_s window keeps {100 * kept:.2g} %" in (
        capsys.readouterr().err
    )
    whole_record = make_study(record={"duration_s": None})
    assert main(["check", str(whole_record)]) == 0
    assert "peak acceleration" not in capsys.readouterr().out
