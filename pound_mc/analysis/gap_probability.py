"""The smallest gap whose pounding probability meets a target, with a Wilson interval.

At each gap of a study's grid ``z`` of ``n`` simulations pound; the fraction ``z / n`` falls as
the gap widens.  :func:`required_gap` is the gap where the fractions, joined linearly between
the gaps studied, last come down to the target; its interval is where the Wilson score bounds
of the fractions (:func:`wilson_interval`) do.

References
----------
Wilson, E. B. (1927). Probable inference, the law of succession, and statistical inference.
J. Am. Stat. Assoc. 22(158), 209-212.
Brown, L. D., Cai, T. T., DasGupta, A. (2001). Interval estimation for a binomial proportion.
Statistical Science 16(2), 101-133.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.special import ndtri

from pound_mc.analysis.fragility import _level
from pound_mc.errors import InputError

__all__ = ["RequiredGap", "required_gap", "wilson_interval"]


def wilson_interval(p_hat, n, ci: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
    """Wilson (1927) score interval of a binomial proportion.

    ``(p + z^2/2n -/+ z sqrt(p(1-p)/n + z^2/4n^2)) / (1 + z^2/n)`` with ``z = Phi^-1((1+ci)/2)``
    (Brown, Cai & DasGupta 2001, eq. 4).

    Parameters
    ----------
    p_hat : array_like
        Observed fraction(s) in [0, 1].
    n : array_like
        Number of trials, > 0.
    ci : float, default 0.95
        Confidence level.

    Returns
    -------
    lower, upper : numpy.ndarray
    """
    level = _level(ci)
    p = np.asarray(p_hat, dtype=np.float64)
    n = np.asarray(n, dtype=np.float64)
    zq = ndtri(0.5 + level / 2)
    centre = p + zq**2 / (2 * n)
    half = zq * np.sqrt(p * (1 - p) / n + zq**2 / (4 * n**2))
    denominator = 1 + zq**2 / n
    return (
        np.clip((centre - half) / denominator, 0.0, 1.0),
        np.clip((centre + half) / denominator, 0.0, 1.0),
    )


@dataclass(frozen=True)
class RequiredGap:
    """The gap a target pounding probability needs (:func:`required_gap`).

    Attributes
    ----------
    gap : float
        Smallest gap from which on the probability stays at or below ``target`` [m].
    gap_ci : tuple of float
        Where the Wilson bounds of the probability cross the target [m]; the upper end is
        ``inf`` when the upper bound stays above the target over every gap studied.
    target : float
        Target probability [-].
    ci : float
        Confidence level.
    method : str
        ``"wilson"``.
    """

    gap: float
    gap_ci: tuple[float, float]
    target: float
    ci: float
    method: str = "wilson"

    def to_dict(self) -> dict[str, Any]:
        """JSON-serialisable values."""
        return {
            "gap_m": self.gap,
            "gap_ci_m": list(self.gap_ci),
            "target": self.target,
            "ci": self.ci,
            "method": self.method,
        }


def _crossing(gaps: np.ndarray, p: np.ndarray, target: float) -> float:
    """Smallest gap from which on the piecewise-linear ``p(gap)`` is <= target (inf if never)."""
    above = np.flatnonzero(p > target)
    if above.size == 0:
        return float(gaps[0])
    i = above[-1]  # the last gap above the target; the curve stays at or below after it
    if i == gaps.size - 1:
        return math.inf
    g0, g1, p0, p1 = gaps[i], gaps[i + 1], p[i], p[i + 1]
    return float(g0 + (p0 - target) / (p0 - p1) * (g1 - g0))


def required_gap(gaps, probabilities, n_total, target: float, *, ci: float = 0.95) -> RequiredGap:
    """The smallest gap whose pounding probability is at or below a target, with its interval.

    The probabilities are joined linearly between the gaps studied; the gap is where that
    curve last comes down to ``target`` (so a noisy rise above the target at a wider gap is
    not overlooked).  The confidence interval inverts the pointwise Wilson score bounds of the
    probability at each gap (:func:`wilson_interval`): the lower bound curve crosses the target
    at the lower end, the upper bound curve at the upper end.  The bounds treat the ``n_total``
    simulations at a gap as independent trials; where they share records, record-to-record
    variability makes the true interval wider.

    Parameters
    ----------
    gaps : array_like
        Gaps studied [m], strictly increasing.
    probabilities : array_like
        Pounding probability at each gap [-] (fraction of the simulations that pound).
    n_total : int or array_like
        Simulations behind each probability.
    target : float
        Acceptable probability [-], in (0, 1).
    ci : float, default 0.95
        Confidence level.

    Returns
    -------
    RequiredGap

    Raises
    ------
    InputError
        Malformed inputs, or a probability still above ``target`` at the widest gap studied
        (widen the gap range).
    """
    level = _level(ci)
    gaps = np.atleast_1d(np.asarray(gaps, dtype=np.float64))
    p = np.atleast_1d(np.asarray(probabilities, dtype=np.float64))
    n = np.broadcast_to(np.asarray(n_total, dtype=np.float64), p.shape)
    if gaps.ndim != 1 or gaps.size < 2 or p.shape != gaps.shape:
        raise InputError(
            "gaps and probabilities must be 1-D, of one length, with two or more gaps", key="gaps"
        )
    if not (np.all(np.isfinite(gaps)) and np.all(np.diff(gaps) > 0)):
        raise InputError("gaps must be finite and strictly increasing [m]", key="gaps")
    if not np.all(np.isfinite(p) & (p >= 0) & (p <= 1)):
        raise InputError("probabilities must lie in [0, 1]", key="probabilities")
    if not np.all(np.isfinite(n) & (n > 0)):
        raise InputError("n_total must be > 0 at every gap", key="n_total")
    if not (isinstance(target, int | float) and 0 < target < 1):
        raise InputError(f"target must be a probability in (0, 1), got {target!r}", key="target")
    gap = _crossing(gaps, p, target)
    if math.isinf(gap):
        raise InputError(
            f"the pounding probability is {p[-1]:.3g} > {target:g} at the widest gap studied "
            f"({gaps[-1]:g} m): widen the gap range",
            key="gaps",
        )
    lower, upper = wilson_interval(p, n, level)
    return RequiredGap(
        gap=gap,
        gap_ci=(_crossing(gaps, lower, target), _crossing(gaps, upper, target)),
        target=float(target),
        ci=level,
    )
