"""Lognormal fragility functions fitted to stripes.

The gap a target probability needs is :mod:`pound_mc.analysis.gap_probability`'s.

Fragility (Baker 2015, eq. 1): the probability of an event (pounding, a peak force above a
threshold, a ductility above a limit) at intensity ``x``

    P(event | IM = x) = Phi(ln(x / theta) / beta),

with median ``theta`` (same units as the IM) and dispersion ``beta`` [-].  Fitted by maximum
likelihood to a multiple-stripe analysis: at stripe ``j`` (intensity ``x_j``) ``z_j`` of
``n_j`` simulations have the event, and the likelihood is binomial (Baker 2015, eqs. 11-12)

    ln L = sum_j [ z_j ln p_j + (n_j - z_j) ln(1 - p_j) ] + const,   p_j = Phi(ln(x_j/theta)/beta).

The constant (the binomial coefficients) is left out of :attr:`FragilityFit.loglik`.  Written
as a probit regression ``p_j = Phi(a + b ln x_j)`` with ``b = 1/beta`` and
``a = -ln(theta)/beta``, ``ln L`` is concave in ``(a, b)``, so Newton's method with step halving
finds the unique maximum whenever it exists.  It exists (finite ``theta``, ``beta > 0``) unless
the stripes are *separated*: every stripe below some intensity has no event and every stripe
above it has all events, the stripe at it either or both (then ``beta -> 0``), or the event
fraction does not rise with the intensity (then ``beta -> infinity``), or no stripe (or every
stripe) has the event.  Such data are refused with an :class:`~pound_mc.errors.InputError`.

Confidence intervals come from a nonparametric bootstrap that resamples the simulations within each
stripe (``z*_j ~ Binomial(n_j, z_j / n_j)``, the same as drawing ``n_j`` of the stripe's
simulations with replacement), refitting each replicate, and taking percentiles (Efron & Tibshirani
1993, ch. 13).  With few stripes a resample can lose the few events (or non-events) that make the
stripes overlap: with 0/88, 2/88 and 48/88 events at PGA 0.1, 0.2 and 0.4 g (the quickstart's
100 mm gap on 15-s record windows) the 0.2 g stripe draws no event in ``(86/88)^88 = 13 %`` of the
resamples, which are then separated.  Such a resample has no maximum-likelihood fit, the data the
point fit refuses: its likelihood grows without bound towards a step (``beta -> 0``).  That limit is
not a value the data allow: while the observed stripes overlap, their likelihood tends to 0 as
``beta -> 0``, so a replicate kept at the limit only drags the percentiles to ``beta = 0`` and the
band to a 0-to-1 step.  A replicate with no fit (separated, no event, only events, a falling
fraction, not converged) is therefore not a valid replicate of the estimator: it is discarded and
counted (:attr:`FragilityFit.n_boot_discarded`, by kind in :attr:`FragilityFit.discarded`), and
resamples are drawn on from the same generator (a second batch of ``n_boot``) until ``n_boot``
replicates have a fit.  The intervals then describe the estimator where it exists; the discarded
resamples are the steep end, so the larger their share the more the lower bound of ``beta`` is too
high (with 0/88, 1/88 and 43/88 events, 36 % discarded, it is 0.28 where the likelihood-ratio
interval has 0.22).  When more than half of the resamples have no fit (fewer than ``n_boot`` fits in
``2 n_boot`` draws) the percentiles describe the conditioning more than the data, and the intervals
are NaN (:attr:`FragilityFit.bootstrap_note` says why: add stripes near ``theta``).  Resampling from
the fitted curve instead (a parametric bootstrap, ``z*_j ~ Binomial(n_j, p_j)``) would not avoid
this: the fitted probability at 0.2 g (0.023) is the observed 2/88.  When no replicate is discarded
the intervals are those of the plain percentile bootstrap.

The required gap (:func:`required_gap`) reads the smallest gap from which on the pounding
probability stays at or below a target, interpolating linearly between the gaps studied; its
confidence interval is where the pointwise Wilson (1927) score bounds of the probability cross
the target.

References
----------
Baker, J. W. (2015). Efficient analytical fragility function fitting using dynamic structural
analysis. Earthquake Spectra 31(1), 579-599.
Efron, B., Tibshirani, R. J. (1993). An Introduction to the Bootstrap. Chapman & Hall.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.special import log_ndtr, ndtr, ndtri

from pound_mc.errors import InputError

__all__ = ["FragilityFit", "fit_fragility", "fragility_probability"]

#: Newton iterations before a fit is declared not converged.
_MAX_ITER = 200
#: Bootstrap batches of ``n_boot`` resamples drawn at most: fewer than ``n_boot`` fits among
#: them means more than half of the resamples had none, and the intervals are NaN.
_BOOT_BATCHES = 2
#: Replicates without a fit, by :func:`_classify`'s kind, in words.
_DISCARDED_WORDS = {
    "separated": "separated stripes",
    "none": "no event",
    "all": "only events",
    "decreasing": "falling event fraction",
    "not converged": "not converged",
}
#: Convergence: Newton decrement (twice the log-likelihood still to gain) below this times
#: max(1, -lnL); one more Newton step is taken after it.
_TOL = 1e-12


# --------------------------------------------------------------------------- the curve


def fragility_probability(x, theta, beta) -> np.ndarray:
    """``Phi(ln(x / theta) / beta)``, with the limits of ``beta -> 0`` and ``theta -> 0, inf``.

    Parameters
    ----------
    x : array_like
        Intensity, > 0 (same units as ``theta``).
    theta : array_like
        Median [IM units]; ``inf`` gives 0, ``0`` gives 1.
    beta : array_like
        Dispersion [-]; ``0`` gives a step at ``theta`` (0.5 on it), ``inf`` gives NaN (the
        curve is flat at a level the parameters do not carry).

    Returns
    -------
    numpy.ndarray
        Probability, broadcast over the inputs.
    """
    x, theta, beta = np.broadcast_arrays(
        *(np.asarray(v, dtype=np.float64) for v in (x, theta, beta))
    )
    with np.errstate(divide="ignore", invalid="ignore"):
        u = (np.log(x) - np.log(theta)) / beta
    p = ndtr(u)
    step = beta == 0
    p = np.where(step, np.where(x > theta, 1.0, np.where(x < theta, 0.0, 0.5)), p)
    p = np.where(np.isposinf(theta), 0.0, p)
    p = np.where(theta == 0, 1.0, p)
    return np.where(np.isposinf(beta) | np.isnan(theta), np.nan, p)


# --------------------------------------------------------------------------- probit MLE


def _loglik(a, b, t, z, n):
    """Binomial log-likelihood (no constant) for rows of ``(a, b)``; ``t = ln x``."""
    eta = a[:, None] + b[:, None] * t
    return np.sum(z * log_ndtr(eta) + (n - z) * log_ndtr(-eta), axis=1)


def _newton(t, z, n, a, b):
    """Maximise the probit likelihood for every row of ``z`` at once.

    Parameters
    ----------
    t : numpy.ndarray, shape (k,)
        ``ln x`` of the stripes.
    z, n : numpy.ndarray, shape (m, k)
        Events and simulations per stripe, one fit per row.
    a, b : numpy.ndarray, shape (m,)
        Starting point.

    Returns
    -------
    a, b, loglik : numpy.ndarray, shape (m,)
    converged : numpy.ndarray of bool, shape (m,)
    """
    a, b = a.copy(), b.copy()
    ll = _loglik(a, b, t, z, n)
    converged = np.zeros(a.shape, dtype=bool)
    for _ in range(_MAX_ITER):
        active = ~converged
        if not active.any():
            break
        eta = a[:, None] + b[:, None] * t
        # inverse Mills ratios phi/Phi at +eta and -eta, computed in logs (no 0/0 in the tails)
        log_phi = -0.5 * eta**2 - 0.5 * math.log(2.0 * math.pi)
        lam_p = np.exp(log_phi - log_ndtr(eta))
        lam_m = np.exp(log_phi - log_ndtr(-eta))
        d1 = z * lam_p - (n - z) * lam_m  # d lnL / d eta
        d2 = -z * lam_p * (eta + lam_p) - (n - z) * lam_m * (lam_m - eta)  # d2 lnL / d eta2 < 0
        g_a, g_b = d1.sum(1), (d1 * t).sum(1)
        h_aa, h_ab, h_bb = d2.sum(1), (d2 * t).sum(1), (d2 * t * t).sum(1)
        det = h_aa * h_bb - h_ab**2
        with np.errstate(divide="ignore", invalid="ignore"):
            step_a = -(h_bb * g_a - h_ab * g_b) / det
            step_b = -(-h_ab * g_a + h_aa * g_b) / det
        decrement = step_a * g_a + step_b * g_b  # -g' H^-1 g >= 0, about 2 (lnL* - lnL)
        done = active & np.isfinite(decrement) & (decrement < _TOL * np.maximum(1.0, -ll))
        active &= np.isfinite(step_a) & np.isfinite(step_b)
        scale = np.ones_like(a)
        for _halving in range(60):
            a_new = np.where(active, a + scale * step_a, a)
            b_new = np.where(active, b + scale * step_b, b)
            ll_new = _loglik(a_new, b_new, t, z, n)
            worse = active & ~(ll_new >= ll)
            if not worse.any():
                break
            scale = np.where(worse, 0.5 * scale, scale)
        a, b, ll = a_new, b_new, np.where(active, ll_new, ll)
        converged |= done  # after the last step: its error is of the order of the step squared
    return a, b, ll, converged


def _start(t, z, n):
    """Starting ``(a, b)``: least squares of probit(smoothed fraction) on ``ln x``, per row."""
    p = (z + 0.5) / (n + 1.0)
    y = ndtri(p)
    w = n / np.maximum(n.sum(1, keepdims=True), 1.0)
    t_mean = (w * t).sum(1)
    y_mean = (w * y).sum(1)
    s_tt = (w * (t - t_mean[:, None]) ** 2).sum(1)
    s_ty = (w * (t - t_mean[:, None]) * (y - y_mean[:, None])).sum(1)
    b = np.where(s_tt > 0, s_ty / np.where(s_tt > 0, s_tt, 1.0), 0.0)
    b = np.maximum(b, 0.1 / np.sqrt(np.maximum(s_tt, 1e-12)))
    return y_mean - b * t_mean, b


def _classify(t, z, n):
    """Which rows have no finite fit with ``beta > 0``, and the limit each tends to.

    Returns
    -------
    theta_lim, beta_lim : numpy.ndarray, shape (m,)
        The limits (NaN where a finite fit exists).
    kind : numpy.ndarray of object, shape (m,)
        ``""`` (a finite fit exists, unless the fitted slope turns out <= 0), ``"none"``,
        ``"all"``, ``"separated"`` or ``"decreasing"`` (separated the wrong way round).
    """
    m = z.shape[0]
    has_event = z > 0
    has_non = (n - z) > 0
    used = n > 0
    inf = np.inf
    low_event = np.min(np.where(has_event, t, inf), axis=1)  # smallest ln x with an event
    high_non = np.max(np.where(has_non, t, -inf), axis=1)  # largest ln x with a non-event
    none = ~np.any(has_event & used, axis=1)
    every = ~np.any(has_non & used, axis=1)
    separated = ~none & ~every & (high_non <= low_event)
    # events only at the lower intensities, non-events only at the higher: the curve falls
    high_event = np.max(np.where(has_event, t, -inf), axis=1)
    low_non = np.min(np.where(has_non, t, inf), axis=1)
    falls = ~none & ~every & ~separated & (high_event <= low_non)
    theta = np.full(m, np.nan)
    beta = np.full(m, np.nan)
    theta[none], theta[every] = inf, 0.0
    theta[separated] = np.exp(0.5 * (high_non[separated] + low_event[separated]))
    beta[separated] = 0.0
    kind = np.full(m, "", dtype=object)
    overall = z.sum(1) / np.maximum(n.sum(1), 1.0)
    theta[falls] = np.where(overall[falls] < 0.5, inf, 0.0)
    beta[falls] = inf
    kind[none], kind[every], kind[separated] = "none", "all", "separated"
    kind[falls] = "decreasing"
    return theta, beta, kind


def _fit_rows(t, z, n):
    """Fit every row; ``(theta, beta, loglik, kind)`` with limits for rows without a fit."""
    theta, beta, kind = _classify(t, z, n)
    loglik = np.full(z.shape[0], np.nan)
    rows = np.flatnonzero(kind == "")
    if rows.size:
        a0, b0 = _start(t, z[rows], n[rows])
        a, b, ll, converged = _newton(t, z[rows], n[rows], a0, b0)
        loglik[rows] = ll
        good = converged & (b > 0)
        theta[rows[good]] = np.exp(-a[good] / b[good])
        beta[rows[good]] = 1.0 / b[good]
        flat = converged & (b <= 0)
        # the constrained maximum (beta > 0) is at b -> 0+: a level curve at Phi(a*), theta at
        # +inf below one half and 0 above it
        overall = z[rows].sum(1) / n[rows].sum(1)
        theta[rows[flat]] = np.where(overall[flat] < 0.5, np.inf, 0.0)
        beta[rows[flat]] = np.inf
        kind[rows[flat]] = "decreasing"
        kind[rows[~converged]] = "not converged"
    return theta, beta, loglik, kind


# --------------------------------------------------------------------------- public fit


@dataclass(frozen=True)
class FragilityFit:
    """A lognormal fragility fitted to stripes (:func:`fit_fragility`).

    Attributes
    ----------
    theta : float
        Median [IM units].
    beta : float
        Dispersion (standard deviation of ln IM) [-].
    theta_ci, beta_ci : tuple of float
        Bootstrap percentile confidence intervals at level ``ci``; NaN without replicates or
        when more than half of the resamples had no fit (see :attr:`bootstrap_note`).
    loglik : float
        Maximised binomial log-likelihood, without the binomial coefficients.
    ci : float
        Confidence level of the intervals.
    n_boot : int
        Bootstrap replicates asked for.
    n_boot_discarded : int
        Resamples drawn and discarded because they have no fit, as the point fit would refuse
        them (see the module notes); 0 when every resample had one.
    im, n_event, n_total : numpy.ndarray
        The stripes fitted (intensity, events, simulations).
    theta_boot, beta_boot : numpy.ndarray
        The bootstrap replicates with a fit, in the order drawn: ``n_boot`` of them, fewer when
        more than half of the resamples had none.
    discarded : dict of str to int
        :attr:`n_boot_discarded` by reason (``"separated"``, ``"none"``, ``"all"``,
        ``"decreasing"``, ``"not converged"``).
    """

    theta: float
    beta: float
    theta_ci: tuple[float, float]
    beta_ci: tuple[float, float]
    loglik: float
    ci: float
    n_boot: int
    n_boot_discarded: int
    im: np.ndarray = field(repr=False)
    n_event: np.ndarray = field(repr=False)
    n_total: np.ndarray = field(repr=False)
    theta_boot: np.ndarray = field(repr=False)
    beta_boot: np.ndarray = field(repr=False)
    discarded: dict[str, int] = field(default_factory=dict, repr=False)

    @property
    def bootstrap_note(self) -> str:
        """Why the bootstrap left resamples out, in words; ``""`` when it left none out."""
        if not self.n_boot_discarded:
            return ""
        drawn = self.theta_boot.size + self.n_boot_discarded
        why = ", ".join(
            f"{_DISCARDED_WORDS[kind]}: {count}" for kind, count in self.discarded.items()
        )
        share = f"{self.n_boot_discarded} of {drawn} bootstrap resamples"
        if self.theta_boot.size == self.n_boot:
            return f"{share} left out: no fit ({why})"
        advice = "more than half; add stripes near theta"
        return f"no interval: {share} have no fit ({why}), {advice}"

    def probability(self, x) -> np.ndarray:
        """Fitted probability of the event at intensity ``x``."""
        return fragility_probability(x, self.theta, self.beta)

    def band(self, x, ci: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Pointwise bootstrap band ``(lower, upper)`` of the curve at ``x`` (level ``ci``).

        NaN where the fit has no intervals (no replicates, or more than half of the resamples
        without a fit).
        """
        level = self.ci if ci is None else _level(ci)
        x = np.atleast_1d(np.asarray(x, dtype=np.float64))
        if self.theta_boot.size == 0 or self.theta_boot.size < self.n_boot:
            return np.full(x.shape, np.nan), np.full(x.shape, np.nan)
        curves = fragility_probability(
            x[None, :], self.theta_boot[:, None], self.beta_boot[:, None]
        )
        q = [(1 - level) / 2, (1 + level) / 2]
        lower, upper = np.nanquantile(curves, q, axis=0, method="inverted_cdf")
        return lower, upper

    def to_dict(self) -> dict[str, Any]:
        """The fit as JSON-serialisable values (keys ``theta``, ``beta``, ``theta_ci``, ...)."""
        return {
            "theta": self.theta,
            "beta": self.beta,
            "theta_ci": list(self.theta_ci),
            "beta_ci": list(self.beta_ci),
            "loglik": self.loglik,
            "ci": self.ci,
            "n_boot": self.n_boot,
            "n_boot_discarded": self.n_boot_discarded,
            "stripes": {
                "im": self.im.tolist(),
                "n_event": self.n_event.tolist(),
                "n_total": self.n_total.tolist(),
            },
            "discarded": dict(self.discarded),
        }


def _level(ci) -> float:
    if not (isinstance(ci, int | float) and 0 < ci < 1):
        raise InputError(f"ci must be a confidence level in (0, 1), got {ci!r}", key="ci")
    return float(ci)


def _stripes(im, n_event, n_total):
    im = np.atleast_1d(np.asarray(im, dtype=np.float64))
    z = np.atleast_1d(np.asarray(n_event, dtype=np.float64))
    n = np.atleast_1d(np.asarray(n_total, dtype=np.float64))
    if not (im.ndim == z.ndim == n.ndim == 1 and im.size == z.size == n.size):
        raise InputError(
            f"im, n_event and n_total must be 1-D and of one length, got shapes "
            f"{im.shape}, {z.shape}, {n.shape}",
            key="stripes",
        )
    if not np.all(np.isfinite(im) & (im > 0)):
        raise InputError("intensities must be finite and > 0", key="im")
    for name, v in (("n_event", z), ("n_total", n)):
        if not np.all(np.isfinite(v) & (v >= 0) & (v == np.round(v))):
            raise InputError(f"{name} must hold counts (integers >= 0)", key=name)
    if np.any(z > n):
        raise InputError("n_event exceeds n_total at some stripe", key="n_event")
    return im, z, n


def fit_fragility(
    im,
    n_event,
    n_total,
    *,
    n_boot: int = 1000,
    seed: int | np.random.SeedSequence | None = 0,
    ci: float = 0.95,
) -> FragilityFit:
    """Fit a lognormal fragility to stripes by maximum likelihood (Baker 2015).

    Parameters
    ----------
    im : array_like
        Intensity of each stripe, > 0 (PGA [g], Sa [g], ...).
    n_event : array_like of int
        Simulations with the event at each stripe (0 and ``n_total`` are allowed).
    n_total : array_like of int
        Simulations at each stripe.
    n_boot : int, default 1000
        Bootstrap replicates with a fit (0: no intervals, they are NaN).  Resamples without a
        fit are discarded and drawn again, up to ``2 n_boot`` resamples in all (module notes).
    seed : int or numpy.random.SeedSequence, default 0
        Seed of the bootstrap's :class:`numpy.random.Generator`.
    ci : float, default 0.95
        Confidence level of the percentile intervals.

    Returns
    -------
    FragilityFit

    Raises
    ------
    InputError
        Malformed stripes, or data that cannot identify a fit: fewer than two intensities with
        simulations, no event at all, events in every simulation, separated stripes (no overlap
        between the intensities with and without the event), or an event fraction that falls
        with the intensity.
    """
    im, z, n = _stripes(im, n_event, n_total)
    level = _level(ci)
    if not (isinstance(n_boot, int | np.integer) and n_boot >= 0):
        raise InputError(f"n_boot must be an integer >= 0, got {n_boot!r}", key="n_boot")
    used = n > 0
    if np.unique(im[used]).size < 2:
        raise InputError(
            "a fragility needs stripes at two or more intensities with simulations", key="im"
        )
    t = np.log(im)
    theta, beta, loglik, kind = _fit_rows(t, z[None, :], n[None, :])
    reason = {
        "none": "no simulation has the event: the median lies beyond the highest intensity; "
        "add stronger stripes",
        "all": "every simulation has the event: the median lies below the lowest intensity; "
        "add weaker stripes",
        "separated": "the stripes are separated (events only from one intensity up, "
        "non-events only up to it): the dispersion tends to 0; add stripes near it",
        "decreasing": "the event fraction does not increase with the intensity, so no "
        "lognormal fragility fits (the dispersion tends to infinity)",
        "not converged": "the likelihood maximisation did not converge",
    }.get(kind[0])
    if reason:
        raise InputError(f"cannot fit a fragility: {reason}", key="n_event")
    theta_ci = beta_ci = (np.nan, np.nan)
    theta_b = beta_b = np.empty(0)
    discarded: dict[str, int] = {}
    if n_boot:
        theta_b, beta_b, discarded = _bootstrap(t, z, n, int(n_boot), seed)
        if theta_b.size == n_boot:
            q = [(1 - level) / 2, (1 + level) / 2]
            theta_ci = np.nanquantile(theta_b, q, method="inverted_cdf")
            beta_ci = np.nanquantile(beta_b, q, method="inverted_cdf")
    return FragilityFit(
        theta=float(theta[0]),
        beta=float(beta[0]),
        theta_ci=(float(theta_ci[0]), float(theta_ci[1])),
        beta_ci=(float(beta_ci[0]), float(beta_ci[1])),
        loglik=float(loglik[0]),
        ci=level,
        n_boot=int(n_boot),
        n_boot_discarded=sum(discarded.values()),
        im=im,
        n_event=z.astype(np.int64),
        n_total=n.astype(np.int64),
        theta_boot=theta_b,
        beta_boot=beta_b,
        discarded=discarded,
    )


def _bootstrap(t, z, n, n_boot, seed):
    """Bootstrap replicates of the fit: the first ``n_boot`` resamples with a fit, in order.

    Resamples are drawn in batches of ``n_boot`` from one generator (the first batch is the
    whole bootstrap when every resample has a fit), at most :data:`_BOOT_BATCHES` of them.

    Returns
    -------
    theta, beta : numpy.ndarray
        The replicates with a fit (``n_boot``, fewer when the batches ran out).
    discarded : dict of str to int
        Resamples without a fit drawn before the last replicate kept, by kind.
    """
    rng = np.random.default_rng(seed)
    p_hat = np.divide(z, n, out=np.zeros_like(z), where=n > 0)
    thetas, betas, kinds = [], [], []
    found = 0
    for _batch in range(_BOOT_BATCHES):
        z_boot = rng.binomial(n.astype(np.int64), p_hat, size=(n_boot, z.size))
        z_boot = z_boot.astype(np.float64)
        theta_b, beta_b, _ll, kind_b = _fit_rows(t, z_boot, np.broadcast_to(n, z_boot.shape))
        valid = kind_b == ""
        # rows up to and with the replicate that completes n_boot (all rows if none does)
        reach = np.cumsum(valid) >= n_boot - found
        rows = slice(0, int(np.argmax(reach)) + 1 if reach.any() else n_boot)
        valid = valid[rows]
        thetas.append(theta_b[rows][valid])
        betas.append(beta_b[rows][valid])
        kinds.extend(kind_b[rows][~valid])
        found += int(np.count_nonzero(valid))
        if found == n_boot:
            break
    discarded = {kind: kinds.count(kind) for kind in _DISCARDED_WORDS if kind in kinds}
    return np.concatenate(thetas), np.concatenate(betas), discarded
