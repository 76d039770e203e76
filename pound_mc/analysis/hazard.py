"""Seismic hazard curves and the mean annual rate of an event at a site.

A hazard curve gives the mean annual rate ``lambda(im)`` at which the intensity measure
exceeds ``im``: read from a CSV file (columns ``im`` [g] and ``annual_rate`` [1/year], the IM
rising and the rate strictly falling) by :func:`read_hazard`, or the power law
``lambda = k0 im^-k`` (:func:`power_law`).  Between the file's points the curve is
interpolated log-log; beyond them its end segments are extended log-log, and
:meth:`HazardCurve.extrapolated` says where a result leans on that.

The mean annual rate of an event E (pounding, a force, a ductility) is the fragility
integrated over the hazard (Cornell & Krawinkler 2000; Tubaldi, Barbato & Ghazizadeh 2012,
Structural Safety 36-37:14-22, eq. 4):

    lambda_E = int P(E | im) |d lambda(im)| = int lambda(im) dP(E | im)

(by parts, with ``P -> 0`` as ``im -> 0`` and ``lambda -> 0`` as ``im -> inf``).  For a
lognormal fragility (median ``theta``, dispersion ``beta``) the second form is a Gaussian
integral in ``ln im`` (:func:`rate_lognormal`); for the power law it has the closed form
``k0 theta^-k exp(k^2 beta^2 / 2)`` the tests hold it to.  Without a fit
(:func:`rate_stripes`) ``P(E | im)`` is the stripes' event fraction, linear in ``ln im``
between them, held at the first stripe's below it and at the last's above it.  The
probability of at least one event in ``T`` years is ``1 - exp(-lambda_E T)`` (a Poisson
process).
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import xarray as xr

from pound_mc.errors import InputError, read_text_file

__all__ = [
    "HazardCurve",
    "read_hazard",
    "power_law",
    "rate_lognormal",
    "rate_stripes",
    "probability_in",
]

#: Columns of a hazard CSV file.
HAZARD_COLUMNS = ("im", "annual_rate")
#: Points per unit of ``ln im`` / ``beta`` of the Gaussian integral, and its half-width in
#: ``beta``: the tail beyond 8 beta weighs ``Phi(-8) = 6e-16``.
_NODES, _HALF_WIDTH = 4001, 8.0


@dataclass(frozen=True)
class HazardCurve:
    """Mean annual rate of exceedance of an intensity measure.

    Attributes
    ----------
    im : numpy.ndarray
        Intensities [g], rising (two or more; empty for a power law).
    annual_rate : numpy.ndarray
        Mean annual rate of exceedance at each [1/year], strictly falling.
    source : str
        Where it came from (the file, or ``"k0 im^-k"`` with the values).
    k0, k : float
        The power law's constants (NaN for a curve from a file).
    """

    im: np.ndarray
    annual_rate: np.ndarray
    source: str
    k0: float = math.nan
    k: float = math.nan
    #: What the file's comments say of its IM (``# im = sa_g``, ``# sa_period_s = 1.0``,
    #: ``# damping = 0.05``): checked against the study's by :meth:`check_im`.
    meta: dict = field(default_factory=dict)

    @property
    def is_power_law(self) -> bool:
        """Whether the curve is ``k0 im^-k`` (no range of its own)."""
        return self.im.size == 0

    def rate(self, x) -> np.ndarray:
        """``lambda(x)`` [1/year]: log-log between the points, their end segments beyond."""
        x = np.asarray(x, dtype=float)
        if self.is_power_law:
            return self.k0 * x ** (-self.k)
        lx, li, lr = np.log(x), np.log(self.im), np.log(self.annual_rate)
        inside = np.interp(lx, li, lr)
        lo = lr[0] + (lx - li[0]) * (lr[1] - lr[0]) / (li[1] - li[0])
        hi = lr[-1] + (lx - li[-1]) * (lr[-1] - lr[-2]) / (li[-1] - li[-2])
        return np.exp(np.where(lx < li[0], lo, np.where(lx > li[-1], hi, inside)))

    def check_im(self, ds: xr.Dataset, dim: str) -> None:
        """Refuse a curve whose stated IM is not the study's ``dim`` (``sa_g``, ``pga_g``).

        A file may say, in comments, ``im`` (``sa_g`` or ``pga_g``), ``sa_period_s`` [s] and
        ``damping`` (the Sa's damping ratio; the study's Sa is 5 %-damped); each stated one
        must match the dataset's (``record_sa_period_s``, every record's).
        """
        where = {"file": self.source if not self.is_power_law else None, "key": "--hazard"}
        said = self.meta.get("im")
        if said is not None and said != dim:
            raise InputError(f"the hazard is of {said}, the fragility of {dim}: the IMs must "
                             "be the same", **where)  # fmt: skip
        period = self.meta.get("sa_period_s")
        if period is not None and "record_sa_period_s" in ds:
            own = np.unique(np.asarray(ds["record_sa_period_s"].values, float))
            if own.size != 1 or not math.isclose(float(period), float(own[0]), rel_tol=1e-6):
                raise InputError(f"the hazard's Sa is at {float(period):g} s, the study's at "
                                 f"{', '.join(f'{v:g}' for v in own)} s", **where)  # fmt: skip
        damping = self.meta.get("damping")
        if damping is not None and not math.isclose(float(damping), 0.05, rel_tol=1e-9):
            raise InputError(f"the hazard's Sa is {100 * float(damping):g} %-damped, the "
                             "study's 5 %-damped", **where)  # fmt: skip

    def extrapolated(self, low: float, high: float) -> str:
        """Words on where ``[low, high]`` [g] leaves the curve's points ("" where it does not)."""
        if self.is_power_law:
            return ""
        out = []
        if low < self.im[0]:
            out.append(f"below its lowest intensity {self.im[0]:g} g")
        if high > self.im[-1]:
            out.append(f"above its highest {self.im[-1]:g} g")
        if not out:
            return ""
        return ("the hazard curve is extended log-log " + " and ".join(out) + " (from its end "
                "segments), where the result leans on it")  # fmt: skip


def power_law(k0: float, k: float) -> HazardCurve:
    """The hazard curve ``k0 im^-k`` [1/year] (``k0`` the rate at 1 g, ``k`` > 0)."""
    if not (math.isfinite(k0) and k0 > 0):
        raise InputError(f"k0 must be a finite number > 0, got {k0!r}", key="--hazard-power")
    if not (math.isfinite(k) and k > 0):
        raise InputError(f"k must be a finite number > 0, got {k!r}", key="--hazard-power")
    return HazardCurve(np.zeros(0), np.zeros(0), f"{k0:g} im^-{k:g}", float(k0), float(k))


def read_hazard(path) -> HazardCurve:
    """Read a hazard curve from a CSV file with the columns ``im`` [g] and ``annual_rate``.

    Lines starting with ``#`` are comments; ``# im = sa_g``, ``# sa_period_s = 1.0`` and
    ``# damping = 0.05`` among them say what the IM is (:meth:`HazardCurve.check_im`).
    Raises :class:`InputError` naming the file and the line for missing columns, values that
    are not finite numbers > 0, intensities that do not rise or rates that do not fall
    strictly, and fewer than two points.
    """
    path = Path(path)
    text = read_text_file(path, "hazard file")
    rows = [(n, line) for n, line in enumerate(text.splitlines(), start=1)
            if line.strip() and not line.lstrip().startswith("#")]  # fmt: skip
    meta = {}
    for n, line in enumerate(text.splitlines(), start=1):
        said = line.lstrip()
        if said.startswith("#") and ("=" in said or ":" in said):
            key, _, value = said[1:].replace(":", "=", 1).partition("=")
            key, value = key.strip().lower(), value.strip()
            if key in ("im", "sa_period_s", "damping"):
                try:
                    meta[key] = value if key == "im" else float(value)
                except ValueError:
                    raise InputError(f"{key} must be a number, got {value!r}", file=str(path),
                                     key=f"line {n}") from None  # fmt: skip
    if not rows:
        raise InputError("no rows: give a header line `im,annual_rate` and two or more points",
                         file=str(path))  # fmt: skip
    head_line, head = rows[0]
    names = [c.strip().lower() for c in next(csv.reader([head]))]
    missing = [c for c in HAZARD_COLUMNS if c not in names]
    if missing:
        raise InputError(f"missing column{'s' * (len(missing) > 1)} {', '.join(missing)} (the "
                         f"header has {', '.join(names) or 'none'}); give `im,annual_rate`",
                         file=str(path), key=f"line {head_line}")  # fmt: skip
    at = [names.index(c) for c in HAZARD_COLUMNS]
    im, rate = [], []
    for n, line in rows[1:]:
        cells = next(csv.reader([line]))
        try:
            values = [float(cells[k]) for k in at]
        except (IndexError, ValueError):
            raise InputError(f"not two numbers in the columns im and annual_rate: {line!r}",
                             file=str(path), key=f"line {n}") from None  # fmt: skip
        if not all(math.isfinite(v) and v > 0 for v in values):
            raise InputError(f"im and annual_rate must be finite numbers > 0, got {line!r}",
                             file=str(path), key=f"line {n}")  # fmt: skip
        if im and values[0] <= im[-1]:
            raise InputError(f"the intensities must rise: {values[0]:g} after {im[-1]:g}",
                             file=str(path), key=f"line {n}")  # fmt: skip
        if rate and values[1] >= rate[-1]:
            raise InputError(f"the annual rates must fall strictly as the intensity rises: "
                             f"{values[1]:g} after {rate[-1]:g}", file=str(path),
                             key=f"line {n}")  # fmt: skip
        im.append(values[0])
        rate.append(values[1])
    if len(im) < 2:
        raise InputError("needs two or more points", file=str(path))
    return HazardCurve(np.array(im), np.array(rate), str(path), meta=meta)


def rate_lognormal(hazard: HazardCurve, theta, beta) -> np.ndarray:
    """Mean annual rate [1/year] of an event of lognormal fragility ``(theta, beta)``.

    ``int lambda(im) dPhi(ln(im / theta) / beta)``: trapezoids on ``ln im`` over
    ``ln theta +- 8 beta`` (4001 nodes: within 1e-9 of the power law's closed form for
    ``k beta`` up to 3).  Broadcast over ``theta`` and ``beta``; NaN where either is.
    """
    theta, beta = np.broadcast_arrays(np.asarray(theta, float), np.asarray(beta, float))
    out = np.full(theta.shape, np.nan)
    u = np.linspace(-_HALF_WIDTH, _HALF_WIDTH, _NODES)
    weight = np.exp(-0.5 * u * u) / math.sqrt(2 * math.pi)
    for index in np.ndindex(theta.shape):
        t, b = theta[index], beta[index]
        if not (np.isfinite(t) and np.isfinite(b) and t > 0 and b >= 0):
            continue
        if b == 0:  # a step at theta
            out[index] = float(hazard.rate(t))
            continue
        out[index] = float(np.trapezoid(hazard.rate(t * np.exp(b * u)) * weight, u))
    return out


def rate_stripes(hazard: HazardCurve, im, p) -> float:
    """Mean annual rate [1/year] of an event from the stripes' event fractions, without a fit.

    ``P(E | im)`` linear in ``ln im`` between the stripes ``im`` (rising), held at ``p[0]``
    below the first (so the rate gains ``p[0] lambda(im[0])``) and at ``p[-1]`` above the last;
    NaN where a stripe has no fraction.
    """
    im, p = np.asarray(im, float), np.asarray(p, float)
    if not np.all(np.isfinite(p)):
        return math.nan
    total = p[0] * float(hazard.rate(im[0]))
    for k in range(im.size - 1):  # int lambda dP over each segment, P linear in ln im
        if p[k + 1] == p[k]:
            continue
        z = np.linspace(math.log(im[k]), math.log(im[k + 1]), 201)
        slope = (p[k + 1] - p[k]) / (z[-1] - z[0])
        total += slope * float(np.trapezoid(hazard.rate(np.exp(z)), z))
    return total


def probability_in(rate, years: float) -> np.ndarray:
    """Probability of at least one event in ``years`` at a mean annual ``rate`` (Poisson)."""
    return -np.expm1(-np.asarray(rate, float) * years)
