"""Risk at a site (issue #39): hazard curves, the annual rate of pounding, the risk-targeted gap
and the codes' separations beside it."""

import copy
import json
import math

import numpy as np
import pytest
import xarray as xr

from pound_mc.analysis.fragility import fit_fragility
from pound_mc.analysis.hazard import power_law, rate_lognormal, rate_stripes, read_hazard
from pound_mc.analysis.site_risk import code_gaps, design_intensity, gap_for_rate, rate_for, risk
from pound_mc.cli import main
from pound_mc.errors import InputError
from pound_mc.physics.separation import gap_asce7, gap_ec8
from pound_mc.scene import scene_from_dict, simulate
from pound_mc.study.definition import study_from_text
from pound_mc.study.engine import StudyEngine
from pound_mc.study.runner import run_study
from studies import (
    POUNDING_STATUSES,
    SMALL_SDOF,
    counted_dataset,
    dump_toml,
    pounding_counted,
    with_flagged_runs,
)

PGA = np.array([0.1, 0.2, 0.4, 0.8, 1.6])
GAPS = np.array([0.01, 0.03, 0.1])
# 40 records; at each gap the pounding fraction rises with the PGA and falls with the gap
COUNTS = np.array([[4, 1, 0], [12, 5, 1], [24, 14, 5], [34, 27, 15], [39, 36, 28]])
PGA_ATTRS = {"units": "1", "long_name": "peak ground acceleration in units of g"}


@pytest.fixture(scope="module")
def counted():
    return counted_dataset(COUNTS, PGA, GAPS, 40, PGA_ATTRS)


@pytest.mark.parametrize(
    ("theta", "beta", "k"), [(0.4, 0.3, 2.0), (1.1, 0.6, 2.8), (0.2, 1.0, 3.0)]
)
def test_rate_of_a_lognormal_fragility_on_a_power_law(theta, beta, k):
    # closed form (Cornell & Krawinkler 2000; e.g. Tubaldi et al. 2012 eq. 5):
    # int Phi(ln(x / theta) / beta) |d(k0 x^-k)| = k0 theta^-k exp(k^2 beta^2 / 2)
    k0 = 2e-4
    exact = k0 * theta**-k * math.exp(k * k * beta * beta / 2)
    assert rate_lognormal(power_law(k0, k), theta, beta) == pytest.approx(exact, rel=1e-6)


def test_risk_per_gap_is_the_closed_form_of_each_fit(counted, tmp_path, capsys):
    """Through the dataset path and ``pound-mc risk --json``: each gap's rate is the closed
    form at its own fitted (theta, beta), within 1e-3; the interval holds it."""
    hazard = power_law(1e-3, 2.5)
    out = risk(counted, hazard, n_boot=200)
    for j, _gap in enumerate(GAPS):
        fit = fit_fragility(PGA, COUNTS[:, j], np.full(5, 40), n_boot=0)
        exact = 1e-3 * fit.theta**-2.5 * math.exp(2.5**2 * fit.beta**2 / 2)
        assert out["annual_rate"].values[j] == pytest.approx(exact, rel=1e-3)
        lo, hi = out["annual_rate_ci"].values[j]
        assert lo < exact < hi
    assert out["annual_rate"].attrs["units"] == "year-1"
    path = tmp_path / "counted.nc"
    counted.to_netcdf(path)
    assert main(["risk", str(path), "--hazard-power", "1e-3,2.5", "--target-rate", "1e-3",
                 "--json", "--n-boot", "50"]) == 0  # fmt: skip
    info = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(info["annual_rate"], out["annual_rate"].values, rtol=1e-12)
    assert info["im"] == "pga_g" and info["dims"] == ["contact_gap_m"]
    assert info["target_rate"] == 1e-3 and info["n_left_out"] == 0


def test_risk_counts_flagged_runs_and_leaves_unstable_ones_out(counted):
    """Runs flagged inaccurate count for the pounding rate (their peak force is in doubt, not
    that they pounded), unstable ones do not: each gap's rate is the closed form at the fit of
    the stripes counted by hand (status 0 and 3), and n_left_out the unstable runs."""
    ds = with_flagged_runs(counted)
    ok = pounding_counted(ds)
    z = ((ds["impacts"] > 0) & ok).sum(("record", "sample")).transpose("pga_g", ...).values
    n = ok.sum(("record", "sample")).transpose("pga_g", ...).values
    status_ok = (ds["status"] == 0).sum(("record", "sample")).transpose("pga_g", ...).values
    assert (status_ok < n).any()  # a count of status 0 alone would differ: this can fail
    out = risk(ds, power_law(1e-3, 2.5), n_boot=0)
    for j, _gap in enumerate(GAPS):
        fit = fit_fragility(PGA, z[:, j], n[:, j], n_boot=0)
        exact = 1e-3 * fit.theta**-2.5 * math.exp(2.5**2 * fit.beta**2 / 2)
        assert out["annual_rate"].values[j] == pytest.approx(exact, rel=1e-3)
    left_out = int((~ds["status"].isin(POUNDING_STATUSES)).sum())
    assert left_out > 0 and int(out["n_left_out"].sum()) == left_out


def test_risk_targeted_gap_meets_the_target(counted):
    """The rate at the returned gap (ln rate linear over the gap axis, as documented) is the
    target within 1e-3; the interval brackets it; a target outside the gaps says so."""
    for target in (0.03, 0.015):  # the rates are 0.196, 0.0451 and 0.00745 per year
        out = risk(counted, power_law(1e-3, 2.5), target_rate=target, n_boot=100)
        gap = float(out["required_gap"])
        rates = out["annual_rate"].values
        back = math.exp(np.interp(gap, GAPS, np.log(rates)))
        assert back == pytest.approx(target, rel=1e-3)
        lo, hi = out["required_gap_ci"].values
        # NaN: the interval's upper rates stay above the target at every gap studied
        assert lo <= gap and (gap <= hi or np.isnan(hi))
    out = risk(counted, power_law(1e-3, 2.5), target_rate=1e-9, n_boot=0)
    assert np.isnan(out["required_gap"]) and "the gap is wider" in str(out["gap_message"].values)
    gap, why = gap_for_rate(GAPS, [1e-4, 1e-5, 1e-6], 1e-3)
    assert np.isnan(gap) and "already meets the target" in why


def test_probability_in_years_and_targets():
    # P = 1 - exp(-rate T): 10 % in 50 years is a rate of -ln(0.9) / 50 = 2.107e-3 / year
    assert rate_for(target_probability=0.1, years=50) == pytest.approx(2.1072103e-3, rel=1e-7)
    with pytest.raises(InputError, match="--years goes with --target-probability"):
        rate_for(years=50)
    with pytest.raises(InputError, match="needs --years"):
        rate_for(target_probability=0.1)
    with pytest.raises(InputError, match="not both"):
        rate_for(target_rate=1e-3, target_probability=0.1, years=50)


def test_stripes_without_a_fit():
    """P linear in ln im between stripes, held beyond: on a power law the integral over each
    segment is k0 (slope / k) (x_k^-k - x_k+1^-k) (closed form of int x^-k d ln x)."""
    h = power_law(1e-3, 2.0)
    im, p = np.array([0.2, 0.4, 0.8]), np.array([0.1, 0.5, 0.9])
    exact = p[0] * 1e-3 * 0.2**-2
    for a, b, pa, pb in ((0.2, 0.4, 0.1, 0.5), (0.4, 0.8, 0.5, 0.9)):
        slope = (pb - pa) / math.log(b / a)
        exact += slope * 1e-3 * (a**-2 - b**-2) / 2.0
    assert rate_stripes(h, im, p) == pytest.approx(exact, rel=1e-4)


HAZARD = "im,annual_rate\n0.05,0.1\n0.1,0.03\n0.2,0.008\n0.4,0.0015\n0.8,0.0002\n1.6,0.00002\n"


@pytest.mark.parametrize(
    ("text", "line", "words"),
    [
        ("im,rate\n0.1,0.01\n", "line 1", "missing column annual_rate"),
        ("im,annual_rate\n0.1,0.01\n0.2,0.02\n", "line 3", "must fall strictly"),
        ("im,annual_rate\n0.1,-0.01\n0.2,0.002\n", "line 2", "finite numbers > 0"),
        ("im,annual_rate\n0.2,0.01\n0.1,0.002\n", "line 3", "must rise"),
        ("im,annual_rate\n0.1,abc\n", "line 2", "not two numbers"),
        ("# im = sa_g\n" + HAZARD, "--hazard", "the IMs must be the same"),
        ("im,annual_rate\n5,1e-6\n9,1e-7\n", "--hazard", "miss the study's stripes"),
    ],
)  # fmt: skip
def test_bad_hazard_files(counted, tmp_path, capsys, text, line, words):
    path = tmp_path / "hazard.csv"
    path.write_text(text)
    data = tmp_path / "counted.nc"
    counted.to_netcdf(data)
    assert main(["risk", str(data), "--hazard", str(path), "--n-boot", "0"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(path) in err and line in err and words in err, err


def test_hazard_file_is_log_log_and_says_where_it_is_extended(counted, tmp_path):
    path = tmp_path / "hazard.csv"
    path.write_text("# im = pga_g\n" + HAZARD)
    h = read_hazard(path)
    # log-log between the points: at sqrt(0.1 * 0.2) the geometric mean of the rates
    assert h.rate(math.sqrt(0.02)) == pytest.approx(math.sqrt(0.03 * 0.008), rel=1e-12)
    # beyond them the end segment's slope: at 3.2 g, 2e-5 (2e-5 / 2e-4)
    assert h.rate(3.2) == pytest.approx(2e-6, rel=1e-12)
    out = risk(counted, h, n_boot=0)
    assert "extended log-log above its highest 1.6 g" in out.attrs["extrapolation"]
    # the 10 % in 50 years intensity, read back on the curve
    x = design_intensity(h, "en1998_1")
    assert h.rate(x) == pytest.approx(-math.log(0.9) / 50, rel=1e-9)


def test_code_gaps_by_hand():
    # ASCE/SEI 7-22 12.12.2: dM = Cd dmax / Ie with dmax = u / R; dMT = sqrt(dM1^2 + dM2^2)
    # u = 50 and 80 mm, R = 8, Cd = 5.5, Ie = 1.25: dM = 27.5 and 44.0 mm, dMT = 51.887 mm
    assert gap_asce7(0.05, 0.08, r=8, cd=5.5, ie=1.25) == pytest.approx(0.0518869, rel=1e-5)
    # EN 1998-1 4.4.2.7: ds = qd de, de = u / q; SRSS; x 0.7 at the same levels.  q = 3.9,
    # qd = q: ds = u, sqrt(50^2 + 80^2) = 94.340 mm, x 0.7 = 66.038 mm; qd = 3: x 3 / 3.9
    assert gap_ec8(0.05, 0.08, q=3.9) == pytest.approx(0.0943398, rel=1e-6)
    assert gap_ec8(0.05, 0.08, q=3.9, same_levels=True) == pytest.approx(0.0660379, rel=1e-6)
    assert gap_ec8(0.05, 0.08, q=3.9, qd=3.0) == pytest.approx(0.0943398 * 3 / 3.9, rel=1e-6)


def test_drift_event(counted):
    from pound_mc.analysis.risk import event_mask

    with pytest.raises(InputError, match="drift"):
        event_mask(counted, "drift>0.01")
    ds = counted.assign(peak_drift_left=counted["peak_force"] * 0 + 0.02,
                        peak_drift_right=counted["peak_force"] * 0)  # fmt: skip
    assert bool(event_mask(ds, "drift>0.01").all()) and not event_mask(ds, "drift>0.03").any()


def test_rule_marks_are_each_runs_own_outcome(tmp_path):
    """The exceedance a chart marks for a rule: every run simulated again at its own rule gap.
    Checked here against ``simulate`` of each run's scene with that gap, written by hand."""
    data = copy.deepcopy(SMALL_SDOF)
    data["grid"] = {"left.period_s": [0.4, 0.7], "contact.gap_m": [0.0, 0.01, 0.05]}
    data["sampling"] = {"n": 3, "vary": {"contact.e": {"material": "concrete"}}}
    study = study_from_text(dump_toml(data), file=tmp_path / "small.toml")
    ds = xr.open_dataset(run_study(study, tmp_path / "out", progress=False).path).load()
    out = code_gaps(ds, asce=(8.0, 5.5, 1.0), ec8=(3.9, None, False))
    engine = StudyEngine(study)
    for rule in ("srss", "asce7_22"):
        for i, period in enumerate(data["grid"]["left.period_s"]):
            hits = runs = 0
            for k in range(3):
                index = np.ravel_multi_index((0, i, 0, k), study.shape)
                gap = float(_run_gap(ds, engine, rule, i, k))  # from the run's linear peaks
                tables = engine.study.scene_dict(
                    0,
                    {
                        "left.period_s": period,
                        "contact.gap_m": gap,
                        "contact.e": float(ds["e"].values[k]),
                    },
                )
                res = simulate(scene_from_dict(tables), record=engine.record_of(index))
                # a run counts as the pounding probability counts it: status ok or flagged
                # inaccurate (studies.POUNDING_STATUSES)
                counted_run = res.outputs["status"] in POUNDING_STATUSES
                runs += counted_run
                hits += counted_run and res.outputs["impacts"] > 0
            share = float(out["code_gap_exceedance"].sel(rule=rule).isel(left_period_s=i))
            assert runs > 0 and share == pytest.approx(hits / runs), (rule, period)


def _run_gap(ds, engine, rule, i, k):
    """Run ``(record 0, left_period_s i, sample k)``'s own gap of ``rule``."""
    from pound_mc.analysis.gaps import study_gaps
    from pound_mc.physics.separation import gap_asce7

    g = study_gaps(ds, engine=engine).isel(record=0, left_period_s=i, contact_gap_m=0, sample=k)
    if rule == "srss":
        return g["gap_srss"]
    return gap_asce7(g["linear_disp_left"], g["linear_disp_right"], r=8.0, cd=5.5, ie=1.0)


def test_report_risk_section_tables_the_risk(counted):
    """``pound-mc report --hazard ...``'s section: the chart, each gap's annual rate and its
    interval, the risk-targeted gap: the numbers of :func:`risk` itself (``pound-mc risk``)."""
    import re

    from pound_mc.analysis.report import _site_html
    from pound_mc.analysis.site_risk import site_assessment

    out, gaps = site_assessment(counted, power_law(1e-3, 2.5), target_rate=1e-2, n_boot=50)
    assert np.isfinite(float(out["required_gap"]))  # a target inside the gaps studied
    assert gaps is None  # a dataset without a study: no rule describes its buildings
    html = "".join(_site_html(out, gaps))
    assert "<h2>Risk at the site</h2>" in html and 'id="chart-site-risk"' in html
    rates = re.search(r'<table id="site-rates">(.*?)</table>', html).group(1)
    cells = re.findall(r"<td[^>]*>([^<]*)</td>", rates)
    for j, gap in enumerate(GAPS):
        row = cells[5 * j : 5 * j + 5]
        assert row[1] == f"{1e3 * gap:.0f} mm"
        assert row[2] == f"{out['annual_rate'].values[j]:.3g}"
        lo, hi = out["annual_rate_ci"].values[j]
        assert row[3] == f"{lo:.3g} - {hi:.3g}"
    gap = re.search(r'<table id="site-gap">(.*?)</table>', html).group(1)
    assert f"{1e3 * float(out['required_gap']):.0f} mm" in gap
