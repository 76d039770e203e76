"""Lognormal fragility fitting (Baker 2015), the required gap and the fragility chart."""

from __future__ import annotations

import json

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from scipy import optimize, stats

from pound_mc.analysis.fragility import fit_fragility, fragility_probability
from pound_mc.analysis.fragility_chart import fragility_chart
from pound_mc.analysis.gap_probability import required_gap, wilson_interval
from pound_mc.analysis.risk import fragility
from pound_mc.analysis.risk_chart import fragility_panels
from pound_mc.cli import main
from pound_mc.errors import InputError
from studies import counted_dataset

STRIPES = np.array([0.1, 0.2, 0.3, 0.4, 0.6, 0.8, 1.0])

# Pounding counts of studies/separation_gap.toml (dataset written by the engine: impacts > 0,
# summed over its 20 records x 256 samples = 5120 simulations per gap) at gaps 0.02-0.30 m.
# P(pounding | gap) = P(D > gap) for a lognormal peak relative displacement D is a lognormal
# fragility in 1/gap: Phi(ln((1/gap) / (1/theta_D)) / beta).
SEP_GAPS = np.arange(1, 16) * 0.02
SEP_POUNDING = np.array([5075, 5033, 4710, 3343, 1901, 1007, 499, 253, 124, 56, 15, 2, 1, 1, 1])
# the same study, record cp-04 alone (256 simulations per gap; stripes with 0 events)
SEP_CP04 = np.array([253, 252, 232, 191, 180, 171, 146, 101, 50, 17, 5, 0, 0, 0, 0])


def _draw(theta, beta, n, seed):
    rng = np.random.default_rng(seed)
    n_total = np.full(STRIPES.size, n)
    return rng.binomial(n_total, stats.norm.cdf(np.log(STRIPES / theta) / beta)), n_total


def test_bootstrap_intervals_cover_the_true_parameters():
    # closed form: stripes drawn from a known lognormal fragility (Baker 2015, eq. 1); the 95 %
    # bootstrap intervals must hold the true theta and beta in >= 90 of 100 seeded trials
    theta, beta = 0.4, 0.5
    hits_theta = hits_beta = 0
    for trial in range(100):
        n_event, n_total = _draw(theta, beta, 40, [2015, trial])
        fit = fit_fragility(STRIPES, n_event, n_total, n_boot=1000, seed=trial)
        hits_theta += fit.theta_ci[0] <= theta <= fit.theta_ci[1]
        hits_beta += fit.beta_ci[0] <= beta <= fit.beta_ci[1]
    assert hits_theta >= 90 and hits_beta >= 90, (hits_theta, hits_beta)


def _independent_fit(im, n_event, n_total):
    # Baker (2015) eq. 12 written directly in (ln theta, ln beta), without the binomial
    # coefficients, and minimised by Nelder-Mead (no derivatives) from the stripes' median
    # intensity and beta = 1: nothing shared with the probit Newton fit
    def nll(params):
        theta, beta = np.exp(params)
        u = np.log(im / theta) / beta
        return -np.sum(n_event * stats.norm.logcdf(u) + (n_total - n_event) * stats.norm.logsf(u))

    result = optimize.minimize(
        nll,
        np.log([np.median(im), 1.0]),
        method="Nelder-Mead",
        options={"xatol": 1e-11, "fatol": 1e-12, "maxiter": 5000},
    )
    assert result.success, result.message
    theta, beta = np.exp(result.x)
    return theta, beta, -result.fun


@pytest.mark.parametrize(
    ("im", "n_event", "n_total"),
    [
        (1.0 / SEP_GAPS, SEP_POUNDING, np.full(15, 5120)),
        (1.0 / SEP_GAPS, SEP_CP04, np.full(15, 256)),
        (STRIPES, *_draw(0.4, 0.5, 40, 7)),
    ],
    ids=["separation_gap", "separation_gap_cp04", "synthetic"],
)
def test_fit_agrees_with_an_independent_scipy_fit(im, n_event, n_total):
    fit = fit_fragility(im, n_event, n_total, n_boot=0)
    theta, beta, loglik = _independent_fit(im, n_event, n_total)
    assert fit.theta == pytest.approx(theta, rel=1e-6)
    assert fit.beta == pytest.approx(beta, rel=1e-6)
    assert fit.loglik == pytest.approx(loglik, rel=1e-9)


def test_stripes_with_no_or_all_events_take_part():
    n_total = np.full(STRIPES.size, 20)
    n_event = np.array([0, 0, 3, 9, 17, 20, 20])
    fit = fit_fragility(STRIPES, n_event, n_total, n_boot=200, seed=1)
    theta, beta, _ = _independent_fit(STRIPES, n_event, n_total)
    assert (fit.theta, fit.beta) == pytest.approx((theta, beta), rel=1e-6)
    assert fit.theta_ci[0] < fit.theta < fit.theta_ci[1]
    assert fit.beta_ci[0] < fit.beta < fit.beta_ci[1]


def test_bootstrap_is_seeded():
    n_event, n_total = _draw(0.4, 0.5, 40, 3)
    a = fit_fragility(STRIPES, n_event, n_total, n_boot=300, seed=11)
    b = fit_fragility(STRIPES, n_event, n_total, n_boot=300, seed=11)
    c = fit_fragility(STRIPES, n_event, n_total, n_boot=300, seed=12)
    assert np.array_equal(a.theta_boot, b.theta_boot) and a.theta_ci == b.theta_ci
    assert not np.array_equal(a.theta_boot, c.theta_boot)
    assert a.to_dict()["theta_ci"] == list(a.theta_ci)


@pytest.mark.parametrize(
    ("n_event", "message"),
    [
        ([0, 0, 0, 0, 0, 0, 0], "no simulation has the event"),
        ([10] * 7, "every simulation has the event"),
        # events only from one stripe on, that one mixed (quasi-separation): it said "only
        # events above it" of a stripe with non-events
        (
            [0, 0, 0, 4, 10, 10, 10],
            "separated .events only from one intensity up, non-events only up",
        ),
        (
            [0, 0, 0, 0, 0, 0, 2],
            "separated .events only from one intensity up, non-events only up to it",
        ),
        ([0, 0, 0, 10, 10, 10, 10], "separated"),
        ([10, 10, 10, 4, 0, 0, 0], "does not increase"),
        ([10, 8, 7, 6, 4, 2, 1], "does not increase"),
    ],
)
def test_data_that_cannot_identify_a_fit_are_refused(n_event, message):
    with pytest.raises(InputError, match=message):
        fit_fragility(STRIPES, n_event, np.full(7, 10), n_boot=0)


@pytest.mark.parametrize(
    ("im", "n_event", "n_total", "message"),
    [
        ([0.3, 0.3], [1, 2], [5, 5], "two or more intensities"),
        ([0.3, -0.1], [1, 2], [5, 5], "> 0"),
        ([0.3, 0.5], [6, 2], [5, 5], "exceeds"),
        ([0.3, 0.5], [1.5, 2], [5, 5], "counts"),
        ([0.3, 0.5, 0.7], [1, 2], [5, 5], "one length"),
    ],
)
def test_malformed_stripes_are_refused(im, n_event, n_total, message):
    with pytest.raises(InputError, match=message):
        fit_fragility(im, n_event, n_total)


def test_probability_limits():
    assert fragility_probability(0.5, 0.5, 0.3) == pytest.approx(0.5)
    assert fragility_probability([0.4, 0.5, 0.6], 0.5, 0.0).tolist() == [0.0, 0.5, 1.0]
    assert fragility_probability(0.4, np.inf, np.nan) == 0.0
    assert fragility_probability(0.4, 0.0, np.nan) == 1.0


def test_wilson_interval_matches_scipy():
    # scipy.stats.binomtest(...).proportion_ci(method="wilson") (Wilson 1927)
    for k, n in [(0, 50), (3, 50), (25, 50), (50, 50), (499, 5120)]:
        lower, upper = wilson_interval(k / n, n, 0.95)
        ref = stats.binomtest(k, n).proportion_ci(0.95, method="wilson")
        assert (lower, upper) == pytest.approx((ref.low, ref.high), rel=1e-12, abs=1e-15)


def test_required_gap_interpolates_and_brackets():
    gaps = np.array([0.0, 0.1, 0.2, 0.3])
    p = np.array([1.0, 0.5, 0.05, 0.0])
    result = required_gap(gaps, p, 400, 0.1)
    # linear between (0.1 m, 0.5) and (0.2 m, 0.05): 0.1 + 0.4 / 0.45 * 0.1
    assert result.gap == pytest.approx(0.1 + 0.4 / 0.45 * 0.1, rel=1e-12)
    lower, upper = wilson_interval(p, 400)
    assert result.gap_ci[0] == pytest.approx(0.1 + (lower[1] - 0.1) / (lower[1] - lower[2]) * 0.1)
    assert result.gap_ci[1] == pytest.approx(0.1 + (upper[1] - 0.1) / (upper[1] - upper[2]) * 0.1)
    assert result.gap_ci[0] < result.gap < result.gap_ci[1]
    assert result.to_dict()["gap_m"] == result.gap


def test_required_gap_on_the_separation_study():
    # studies/separation_gap.toml (counts above, 5120 simulations per gap): 10 % pounding is
    # crossed between 0.14 m (499/5120 = 0.0975 <= 0.1) and 0.12 m (1007/5120 = 0.197)
    p = SEP_POUNDING / 5120
    result = required_gap(SEP_GAPS, p, 5120, 0.1)
    expected = 0.12 + (p[5] - 0.1) / (p[5] - p[6]) * 0.02
    assert result.gap == pytest.approx(expected, rel=1e-12)
    assert 0.12 < result.gap_ci[0] < result.gap < result.gap_ci[1] < 0.16


def test_required_gap_ignores_an_early_dip_and_refuses_an_unreached_target():
    gaps = np.array([0.0, 0.1, 0.2, 0.3])
    # dips below 0.2 at 0.1 m, back above at 0.2 m: the gap is after the last crossing
    assert required_gap(gaps, [0.9, 0.15, 0.3, 0.1], 1000, 0.2).gap == pytest.approx(0.25)
    with pytest.raises(InputError, match="widen the gap range"):
        required_gap(gaps, [0.9, 0.6, 0.4, 0.3], 1000, 0.1)
    # upper Wilson bound never reaches the target within the grid: open upper end
    assert required_gap(gaps, [0.9, 0.6, 0.4, 0.1], 50, 0.1).gap_ci[1] == np.inf


def test_chart_draws_the_fit(tmp_path):
    n_event, n_total = _draw(0.4, 0.5, 40, 1)
    fit = fit_fragility(STRIPES, n_event, n_total, n_boot=500, seed=1)
    ax = fragility_chart(fit, im_label="PGA [g]", event_label="pounding")
    curve, points = ax.lines[0], ax.lines[1]
    x = curve.get_xdata()
    assert np.allclose(curve.get_ydata(), stats.norm.cdf(np.log(x / fit.theta) / fit.beta))
    assert np.array_equal(points.get_xdata(), STRIPES)
    assert np.array_equal(points.get_ydata(), n_event / n_total)
    # every stripe has 40 simulations: each point says its events, the legend says "of 40"
    assert [t.get_text() for t in ax.texts] == [f"{z}" for z in n_event]
    assert "the 40 simulations" in points.get_label()
    ax = fragility_chart(fit, totals=True)
    assert [t.get_text() for t in ax.texts] == [f"{z}/40" for z in n_event]
    ax = fragility_chart(fit, im_label="PGA [g]", event_label="pounding")
    band = ax.collections[0].get_paths()[0].vertices
    lower, upper = fit.band(x)
    assert np.isclose(band[:, 1].min(), min(lower.min(), upper.min()))
    ax.figure.savefig(tmp_path / "fragility.png")
    assert (tmp_path / "fragility.png").stat().st_size > 0


# Pounding counts of studies/quickstart.toml on 15-s record windows, as it ran until 0.2.0, at
# its 100 mm gap (dataset written by the engine:
# impacts > 0 over 44 records x 2 samples = 88 simulations per stripe) at PGA 0.1, 0.2, 0.4 g
QS_PGA = np.array([0.1, 0.2, 0.4])
QS_100MM = np.array([0, 2, 48])
# 1/88, 87/88, 88/88: a resample is separated when 0.1 g draws no event or 0.2 g draws only
# events, (87/88)^88 = 37 % each, 60 % either: more than half of the resamples have no fit
HALF_SEPARATED = np.array([1, 87, 88])


def _resamples(n_event, n_total, n_boot, seed):
    # the bootstrap's resamples drawn again from the same generator: two batches of n_boot
    rng = np.random.default_rng(seed)
    p = np.asarray(n_event) / n_total
    return np.concatenate([rng.binomial(n_total, p, size=(n_boot, p.size)) for _ in range(2)])


def test_resamples_without_a_fit_are_discarded_and_counted():
    n_total = np.full(3, 88)
    fit = fit_fragility(QS_PGA, QS_100MM, n_total, n_boot=200, seed=5)
    draws = _resamples(QS_100MM, n_total, 200, 5)
    # 0.1 g never draws an event (0/88) and 0.4 g never only events (48/88, 1 - 0.55^88): a
    # resample is separated exactly when 0.2 g draws no event ((86/88)^88 = 13 %)
    assert not np.any(draws[:, 0]) and np.all(draws[:, 2] < 88)
    separated = draws[:, 1] == 0
    used = np.flatnonzero(~separated)[199] + 1  # draws up to the 200th with a fit
    assert fit.n_boot_discarded == np.count_nonzero(separated[:used]) > 0
    assert fit.discarded == {"separated": fit.n_boot_discarded}
    # no step (beta = 0) and no infinite median among the replicates, each the point fit of its
    # resample
    assert fit.theta_boot.size == fit.beta_boot.size == 200
    assert np.all(fit.beta_boot > 0) and np.all(np.isfinite(fit.theta_boot + fit.beta_boot))
    kept = draws[:used][~separated[:used]]
    for k in (0, 199):
        ref = fit_fragility(QS_PGA, kept[k], n_total, n_boot=0)
        assert (fit.theta_boot[k], fit.beta_boot[k]) == pytest.approx((ref.theta, ref.beta))
    with pytest.raises(InputError, match="separated"):  # what was discarded, the fit refuses
        fit_fragility(QS_PGA, draws[separated][0], n_total, n_boot=0)
    # kept at beta = 0, these replicates made the lower bound 0; the profile-likelihood 95 %
    # interval of beta (chi2(1) = 3.84 on Baker's eq. 12, scipy) is [0.246, 0.448]
    assert 0.2 < fit.beta_ci[0] < fit.beta < fit.beta_ci[1] < 0.5
    assert fit.bootstrap_note == (
        f"{fit.n_boot_discarded} of {200 + fit.n_boot_discarded} bootstrap resamples left out: "
        f"no fit (separated stripes: {fit.n_boot_discarded})"
    )
    assert fit.to_dict()["n_boot_discarded"] == fit.n_boot_discarded


def test_more_than_half_without_a_fit_gives_no_interval():
    n_total = np.full(3, 88)
    fit = fit_fragility(QS_PGA, HALF_SEPARATED, n_total, n_boot=200, seed=3)
    draws = _resamples(HALF_SEPARATED, n_total, 200, 3)
    no_fit = (draws[:, 0] == 0) | (draws[:, 1] == 88)
    assert fit.n_boot_discarded == np.count_nonzero(no_fit) > 200
    assert fit.discarded == {"separated": fit.n_boot_discarded}
    assert fit.theta_boot.size == 400 - fit.n_boot_discarded
    assert np.isnan(fit.theta_ci + fit.beta_ci).all()
    assert np.isnan(fit.band([0.1, 0.2])).all()
    assert fit.bootstrap_note.startswith(f"no interval: {fit.n_boot_discarded} of 400 ")
    assert "more than half" in fit.bootstrap_note
    assert not fragility_chart(fit).collections  # no band


def _percentile(values, q):
    """The inverted-CDF percentile: the smallest value whose share at or below it is >= q.

    The k-th smallest of n for the smallest k >= q n (here q n is 2.5 or 97.5: no tie of
    definitions at an integer).
    """
    ordered = np.sort(np.asarray(values))
    return ordered[int(np.ceil(q * ordered.size)) - 1]


def test_intervals_without_discarded_resamples_are_the_percentile_bootstrap():
    # the plain percentile bootstrap (Efron & Tibshirani 1993, ch. 13) recomputed here: the
    # fit's own resamples drawn again from its generator (z*_j ~ Binomial(n_j, z_j / n_j)),
    # each refitted by the independent Nelder-Mead fit of Baker's eq. 12 above, and the 2.5
    # and 97.5 % points of the replicates and of the curves they give (Baker 2015 eq. 1);
    # the fits agree to their tolerances (1e-6), so do the intervals
    n_event, n_total = _draw(0.4, 0.5, 40, 3)
    assert n_event.tolist() == [0, 2, 14, 21, 35, 37, 39]
    fit = fit_fragility(STRIPES, n_event, n_total, n_boot=100, seed=11)
    assert fit.n_boot_discarded == 0 and fit.discarded == {} and fit.bootstrap_note == ""
    draws = _resamples(n_event, n_total, 100, 11)[:100]  # no discard: the first batch alone
    replicates = np.array([_independent_fit(STRIPES, z, n_total)[:2] for z in draws])
    theta_b, beta_b = replicates.T
    for interval, values in ((fit.theta_ci, theta_b), (fit.beta_ci, beta_b)):
        expected = (_percentile(values, 0.025), _percentile(values, 0.975))
        assert interval == pytest.approx(expected, rel=1e-5)
    x = np.array([0.2, 0.4, 0.8])
    curves = stats.norm.cdf(np.log(x[None, :] / theta_b[:, None]) / beta_b[:, None])
    lower, upper = fit.band(x)
    for k in range(x.size):
        assert lower[k] == pytest.approx(_percentile(curves[:, k], 0.025), rel=1e-5)
        assert upper[k] == pytest.approx(_percentile(curves[:, k], 0.975), rel=1e-5)
    # the intervals hold the point fit, and are not degenerate
    assert fit.theta_ci[0] < fit.theta < fit.theta_ci[1]
    assert fit.beta_ci[0] < fit.beta < fit.beta_ci[1]


def _stripe_dataset(*columns, pga=QS_PGA):
    # a study dataset as pound-mc run writes it, reduced to what the fragility reads: 88
    # records x 1 sample at PGA 0.1, 0.2, 0.4 g (or ``pga``) and a gap per column of counts
    counts = np.stack(columns or [QS_100MM, HALF_SEPARATED], axis=1)  # (pga_g, contact_gap_m)
    gaps = [0.1, 0.2, 0.3, 0.4][: counts.shape[1]]
    return counted_dataset(counts, pga, gaps, 88,
                           {"units": "g", "long_name": "peak ground acceleration"})  # fmt: skip


def test_dataset_cli_and_chart_say_what_was_discarded(tmp_path, capsys):
    ds = _stripe_dataset()
    fits = [
        fit_fragility(QS_PGA, z, np.full(3, 88), n_boot=200) for z in (QS_100MM, HALF_SEPARATED)
    ]
    out = fragility(ds, n_boot=200)
    assert out["n_boot_discarded"].values.tolist() == [f.n_boot_discarded for f in fits]
    assert out["bootstrap_note"].values.tolist() == [f.bootstrap_note for f in fits]
    assert np.isnan(out["beta_ci"].values[1]).all() and out["beta_ci"].values[0, 0] > 0
    path = tmp_path / "stripes.nc"
    ds.to_netcdf(path)
    assert main(["fragility", str(path), "--n-boot", "200"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[1].endswith("simulations counted, none left out")  # every stripe run is ok
    assert lines[3] == f"    {fits[0].bootstrap_note}" and "[nan, nan]" in lines[4]
    assert lines[5] == f"    {fits[1].bootstrap_note}"
    assert main(["fragility", str(path), "--n-boot", "200", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["n_boot_discarded"] == [f.n_boot_discarded for f in fits]
    assert data["beta_ci"][1] == [None, None]
    # the stripes the fits are made from: per gap, one count per intensity
    assert data["intensities"] == QS_PGA.tolist()
    assert data["n_event"] == [QS_100MM.tolist(), HALF_SEPARATED.tolist()]
    assert data["n_total"] == [[88] * 3] * 2
    fig = fragility_panels(ds, n_boot=200)
    for ax in fig.axes[:2]:  # the resamples left out are the fragility command's to say
        assert "bootstrap" not in ax.get_title() and "resample" not in fig.get_suptitle()
    assert fig.axes[0].collections and not fig.axes[1].collections  # the band only with a CI


def test_no_fit_panels_label_their_stripes():
    """A panel without a fit (separated stripes: 0/88, 0/88, 4/88, as the quickstart's 200 mm
    gap) drew its points without their counts, and cut its reason short; the counts are those
    of the dataset, and the reason is whole."""
    ds = _stripe_dataset(QS_100MM, np.array([0, 0, 4]))
    fig = fragility_panels(ds, n_boot=50)
    labels = [[t.get_text() for t in ax.texts] for ax in fig.axes[:2]]
    # 88 simulations in every stripe: the events at each point, "of 88" once in the legend
    assert labels[0] == ["0", "2", "48"] and labels[1] == ["0", "0", "4"]
    assert any("the 88 simulations" in t.get_text() for t in fig.legends[0].get_texts())
    assert fig.axes[1].get_title() == "gap 200 mm: no fit"
    caption = fig._pound_caption_artist.get_text().replace("\n", " ")
    assert "No fit at gap 200 mm: " in caption and caption.endswith("add stripes near it.")


def test_panels_share_the_stripes_range_and_keep_their_counts_apart():
    """The quickstart's panels (PGA 0.05-0.8 g, 88 simulations a stripe): the 200 mm panel ran
    to 1.8 g (its curve's reach) where the others stopped at 0.8 g; a count ("0/88") ran under
    the next point and crowded ones were stacked above the wrong points; theta had no unit; the
    title's "1000 bootstrap replicates" read against the panels' "25 of 1025 resamples left
    out".  Counts as the quickstart's 50, 200 and 300 mm gaps."""
    pga = np.array([0.05, 0.1, 0.2, 0.4, 0.8])
    columns = (np.array([0, 4, 54, 88, 88]), np.array([0, 0, 0, 4, 54]), np.array([0, 0, 0, 0, 16]))
    fig = fragility_panels(_stripe_dataset(*columns, pga=pga), n_boot=200)
    panels = [ax for ax in fig.axes if ax.get_visible()]
    assert len(panels) == 3
    # one intensity range, the stripes', though the middle fit alone would reach further
    wide = fit_fragility(pga, columns[1], np.full(5, 88), n_boot=0)
    assert wide.theta * np.exp(2.5 * wide.beta) > 1.05 * pga[-1]
    assert [ax.get_xlim() for ax in panels] == [(0.0, 1.05 * pga[-1])] * 3
    assert (
        panels[1].get_title()
        == f"gap 200 mm: \u03b8 = {wide.theta:.3g} g, \u03b2 = {wide.beta:.2g}"
    )
    # the counts: the events at each point, none over another count or over a point, inside
    FigureCanvasAgg(fig).draw()
    renderer = fig.canvas.get_renderer()
    radius = 3.0 * fig.dpi / 72.0  # the points' markers (ms 5 and 6) [px]
    for ax, z in zip(panels, columns, strict=True):
        assert [t.get_text() for t in ax.texts] == [str(v) for v in z]
        boxes = [t.get_window_extent(renderer) for t in ax.texts]
        points = ax.transData.transform(np.c_[pga, z / 88])
        for k, box in enumerate(boxes):
            assert ax.bbox.x0 <= box.x0 and box.x1 <= ax.bbox.x1, (ax.get_title(), z[k])
            assert ax.bbox.y0 <= box.y0 and box.y1 <= ax.bbox.y1, (ax.get_title(), z[k])
            assert not any(box.overlaps(other) for other in boxes[k + 1 :]), z[k]
            near = [
                (box.x0 - radius < px < box.x1 + radius)
                and (box.y0 - radius < py < box.y1 + radius)
                for px, py in points
            ]
            assert not any(near), (ax.get_title(), z[k])
    # the title: the median intensity of the first and the last panel with a fit; the method
    # (no resample counts) in the caption
    first = fit_fragility(pga, columns[0], np.full(5, 88), n_boot=0)
    assert fig.get_suptitle() == (
        f"Median PGA for pounding: {first.theta:.2g} g at gap 100 mm to {wide.theta:.2g} g at "
        "gap 200 mm"
    )
    caption = fig._pound_caption_artist.get_text().replace("\n", " ")
    assert "band: 95 % bootstrap interval of the fit" in caption and "resample" not in caption
