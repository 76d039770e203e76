"""Lognormal fragility fitting (Baker 2015), the required gap and the fragility chart."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import optimize, stats

from pound_mc.analysis.fragility import (
    fit_fragility,
    fragility_probability,
    required_gap,
    wilson_interval,
)
from pound_mc.analysis.fragility_chart import fragility_chart
from pound_mc.errors import InputError

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
        ([0, 0, 0, 4, 10, 10, 10], "separated"),
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
    assert [t.get_text() for t in ax.texts] == [f"{z}/40" for z in n_event]
    band = ax.collections[0].get_paths()[0].vertices
    lower, upper = fit.band(x)
    assert np.isclose(band[:, 1].min(), min(lower.min(), upper.min()))
    ax.figure.savefig(tmp_path / "fragility.png")
    assert (tmp_path / "fragility.png").stat().st_size > 0
