"""Risk at a site: the annual rate of an event per gap, the risk-targeted gap, the code gaps.

:func:`risk` integrates each gap's fragility (:mod:`pound_mc.analysis.fragility`, the
stripes of a multiple-stripe study) over a hazard curve (:mod:`pound_mc.analysis.hazard`):
the mean annual rate of the event (pounding, ``peak_force>N``, ``ductility>X``,
``drift>X``) at each gap, with the bootstrap interval of the fragility carried through
(each replicate's rate), and the gap whose rate equals a target (interpolated over the gap
axis in ``ln rate``; Tubaldi, Barbato & Ghazizadeh 2012; Flenga & Favvata 2024, Appl. Sci.
14:1165).  :func:`code_gaps` gives, from the same buildings, the separations the rules and
the codes ask for (ABS, SRSS, DDC; ASCE/SEI 7-22 section 12.12.2; EN 1998-1:2004 section
4.4.2.7, :mod:`pound_mc.physics.separation`) and how often a run pounds at a gap equal to
its own rule gap (the per-run exceedance a chart marks, rather than a median gap that would
read as a claim).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import xarray as xr

from pound_mc.analysis.fragility import fit_fragility
from pound_mc.analysis.gaps import RulesDoNotApply, engine_of, study_gaps
from pound_mc.analysis.hazard import HazardCurve, probability_in, rate_lognormal, rate_stripes
from pound_mc.analysis.risk import (
    _COUNTED,
    _LEFT_OUT,
    GAP_DIM,
    _counts,
    _intensity_dim,
    left_out,
)
from pound_mc.errors import InputError
from pound_mc.integrators.accuracy import STATUS_INACCURATE
from pound_mc.integrators.outputs import STATUS_OK
from pound_mc.physics.separation import gap_asce7, gap_ec8
from pound_mc.study.definition import grid_dim_name

__all__ = [
    "RISK_METHODS",
    "RULES",
    "DESIGN_RATES",
    "risk",
    "code_gaps",
    "design_intensity",
    "rate_for",
    "gap_for_rate",
]

#: How :func:`risk` gets the event's probability at each intensity.
RISK_METHODS = ("fragility", "stripes")
#: The separations :func:`code_gaps` gives, by name: the rules always, a code where its
#: factors are given.
RULES = {
    "abs": "absolute sum of the linear displacements (ABS)",
    "srss": "square root of the sum of squares (SRSS)",
    "ddc": "double difference combination (DDC)",
    "asce7_22": "ASCE/SEI 7-22 section 12.12.2: sqrt(dM1^2 + dM2^2), dM = Cd dmax / Ie",
    "en1998_1": "EN 1998-1:2004 4.4.2.7: SRSS of ds = qd de (x 0.7 at the same levels)",
}


#: Annual rate of exceedance of each code's design intensity and the factor on it: ASCE 7-22's
#: design earthquake is 2/3 of the MCE_R (2 % in 50 years, section 11.4), EN 1998-1's the
#: 10 % in 50 years action (its recommended reference return period of 475 years, 2.1(1)); the
#: rules are read at the latter.
DESIGN_RATES = {
    "asce7_22": (-math.log1p(-0.02) / 50.0, 2.0 / 3.0),
    "en1998_1": (-math.log1p(-0.10) / 50.0, 1.0),
}


def design_intensity(hazard: HazardCurve, rule: str) -> float:
    """The intensity [g] at which ``rule``'s code reads its design displacements on ``hazard``.

    :data:`DESIGN_RATES`; the rules (ABS, SRSS, DDC) at EN 1998-1's 10 % in 50 years.
    """
    rate, factor = DESIGN_RATES.get(rule, DESIGN_RATES["en1998_1"])
    if hazard.is_power_law:
        return factor * (hazard.k0 / rate) ** (1.0 / hazard.k)
    li, lr = np.log(hazard.im), np.log(hazard.annual_rate)
    # ln rate falls with ln im: interpolate ln im on ln rate (ends extended log-log)
    lx = np.interp(math.log(rate), lr[::-1], li[::-1], left=np.nan, right=np.nan)
    if np.isnan(lx):
        k = (0, 1) if math.log(rate) > lr[0] else (-2, -1)
        slope = (li[k[1]] - li[k[0]]) / (lr[k[1]] - lr[k[0]])
        lx = li[k[0]] + (math.log(rate) - lr[k[0]]) * slope
    return factor * math.exp(lx)


def rate_for(target_rate=None, target_probability=None, years=None) -> float | None:
    """The target annual rate: given, or ``-ln(1 - P) / T`` for a probability in ``T`` years.

    Raises :class:`InputError` for ``years`` without a probability (or the reverse), both a
    rate and a probability, and values out of range.
    """
    if years is not None and target_probability is None:
        raise InputError("--years goes with --target-probability (the probability of the "
                         "event in that many years)", key="--years")  # fmt: skip
    if target_probability is not None:
        if target_rate is not None:
            raise InputError("give --target-rate or --target-probability, not both",
                             key="--target-probability")  # fmt: skip
        if years is None:
            raise InputError("needs --years (the probability in how many years)",
                             key="--target-probability")  # fmt: skip
        if not 0 < target_probability < 1:
            raise InputError(f"must be in (0, 1), got {target_probability!r}",
                             key="--target-probability")  # fmt: skip
        if not (math.isfinite(years) and years > 0):
            raise InputError(f"must be > 0, got {years!r}", key="--years")
        return -math.log1p(-target_probability) / years
    if target_rate is not None and not (math.isfinite(target_rate) and target_rate > 0):
        raise InputError(f"must be > 0 [1/year], got {target_rate!r}", key="--target-rate")
    return target_rate


def gap_for_rate(gaps, rates, target: float) -> tuple[float, str]:
    """The gap whose annual rate equals ``target``: ``ln rate`` linear between the gaps.

    The first crossing from above of the rates from the smallest gap (where the rate stays at
    or below the target from there on).  Returns ``(gap, message)``: NaN and why where the
    target is not met within the gaps studied, or already at the smallest.
    """
    gaps, rates = np.asarray(gaps, float), np.asarray(rates, float)
    known = np.isfinite(rates)
    if not known[0]:
        return math.nan, f"no annual rate at the smallest gap ({1e3 * gaps[0]:g} mm)"
    first_below = np.flatnonzero(known & (rates <= target))
    unknown = np.flatnonzero(~known)
    if unknown.size and (not first_below.size or unknown[0] < first_below[0]):
        return math.nan, (f"no annual rate at {1e3 * gaps[unknown[0]]:g} mm, before the rate "
                          "meets the target")  # fmt: skip
    below = ~known | (rates <= target)  # past the crossing, an unknown rate does not matter
    if below[0]:
        return math.nan, (f"the smallest gap studied ({1e3 * gaps[0]:g} mm) already meets the "
                          f"target ({rates[0]:.3g}/year <= {target:.3g}/year)")  # fmt: skip
    if not below[-1]:
        last = f"{1e3 * gaps[-1]:g} mm {rates[-1]:.3g}/year > {target:.3g}/year"
        return math.nan, f"above the target at every gap studied (at {last}): the gap is wider"
    k = int(np.flatnonzero(~below)[-1])  # the last gap above the target
    hi, lo = rates[k], rates[k + 1]
    if lo <= 0:  # no event beyond: the rate falls to zero within the interval
        return float(gaps[k + 1]), ""
    w = (math.log(hi) - math.log(target)) / (math.log(hi) - math.log(lo))
    return float(gaps[k] + w * (gaps[k + 1] - gaps[k])), ""


def _rates(hazard, x, n_event, n_total, method, n_boot, seed, ci):
    """The rate at one combination, its interval ``(lo, hi)`` and why there is none.

    Also the intensities the rate leans on: the stripes', and a fit's ``theta e^(+-2 beta)``.
    """
    reach = (float(np.min(x)), float(np.max(x)))
    if method == "stripes":
        p = n_event / np.where(n_total > 0, n_total, np.nan)
        rate = rate_stripes(hazard, x, p)
        if n_boot == 0 or not np.all(n_total > 0):
            return rate, (math.nan, math.nan), "", reach
        rng = np.random.default_rng(seed)  # binomial resampling of each stripe
        boot = [rate_stripes(hazard, x, rng.binomial(n_total, p) / n_total)
                for _ in range(n_boot)]  # fmt: skip
        lo, hi = np.quantile(boot, [(1 - ci) / 2, (1 + ci) / 2])
        return rate, (float(lo), float(hi)), "", reach
    try:
        fit = fit_fragility(x, n_event, n_total, n_boot=n_boot, seed=seed, ci=ci)
    except InputError as exc:
        return math.nan, (math.nan, math.nan), exc.message, reach
    rate = float(rate_lognormal(hazard, fit.theta, fit.beta))
    reach = (min(reach[0], fit.theta * math.exp(-2 * fit.beta)),
             max(reach[1], fit.theta * math.exp(2 * fit.beta)))  # fmt: skip
    if fit.theta_boot.size == 0 or fit.theta_boot.size < fit.n_boot:
        return rate, (math.nan, math.nan), "", reach
    boot = rate_lognormal(hazard, fit.theta_boot, fit.beta_boot)
    lo, hi = np.nanquantile(boot, [(1 - ci) / 2, (1 + ci) / 2])
    return rate, (float(lo), float(hi)), "", reach


def risk(
    ds: xr.Dataset,
    hazard: HazardCurve,
    *,
    im: str | None = None,
    event: str = "pounding",
    method: str = "fragility",
    target_rate: float | None = None,
    target_probability: float | None = None,
    years: float | None = None,
    n_boot: int = 1000,
    seed: int = 0,
    ci: float = 0.95,
) -> xr.Dataset:
    """Mean annual rate of ``event`` per gap (and other grid axis) at a site, and its gap.

    Parameters
    ----------
    ds : xarray.Dataset
        A study dataset with an intensity axis (``sa_g`` or ``pga_g``, or ``im``).
    hazard : pound_mc.analysis.hazard.HazardCurve
        The site's hazard curve of the same IM (:meth:`HazardCurve.check_im`).
    im, event
        As :func:`pound_mc.analysis.risk.fragility`.
    method : {"fragility", "stripes"}
        Integrate the fitted lognormal fragility (default), or the stripes' event fractions
        without a fit (:func:`pound_mc.analysis.hazard.rate_stripes`).
    target_rate, target_probability, years
        The target (:func:`rate_for`): the risk-targeted gap is that whose rate equals it.
    n_boot, seed, ci
        Bootstrap replicates, seed and confidence level of the intervals.

    Returns
    -------
    xarray.Dataset
        ``annual_rate`` [1/year] and ``annual_rate_ci`` (``bound``) along the grid axes other
        than the IM, ``rate_message`` (why a combination has none), ``n_total`` and
        ``n_left_out`` per stripe; with ``years`` ``probability`` (of at least one event in
        that many years); with a target and a gap axis ``required_gap`` [m],
        ``required_gap_ci`` and ``gap_message``.  Attributes ``im``, ``event``, ``method``,
        ``hazard``, ``target_rate`` (NaN: none), ``years`` and ``extrapolation`` (where the
        hazard curve is extended beyond its points, "" where it is not).
    """
    if method not in RISK_METHODS:
        raise InputError(f"unknown method {method!r}; use {' or '.join(RISK_METHODS)}",
                         key="--method")  # fmt: skip
    target = rate_for(target_rate, target_probability, years)
    dim = _intensity_dim(ds, im)
    hazard.check_im(ds, dim)
    x = np.asarray(ds[dim].values, dtype=float)
    if not hazard.is_power_law and (x.max() < hazard.im[0] or x.min() > hazard.im[-1]):
        raise InputError(f"the hazard's intensities ({hazard.im[0]:g}-{hazard.im[-1]:g} g) miss "
                         f"the study's stripes ({x.min():g}-{x.max():g} g)", file=hazard.source,
                         key="--hazard")  # fmt: skip
    n_event, n_total = _counts(ds, event)
    rest = [d for d in n_event.dims if d != dim]
    n_event = n_event.transpose(*rest, dim).values
    n_total = n_total.transpose(*rest, dim).values
    n_out = left_out(ds, event).transpose(*rest, dim)
    shape = tuple(ds.sizes[d] for d in rest)
    rate = np.full(shape, np.nan)
    rate_ci = np.full((*shape, 2), np.nan)
    message = np.full(shape, "", dtype=object)
    spread = [float(x.min()), float(x.max())]  # the intensities the rates lean on
    for index in itertools.product(*(range(n) for n in shape)):
        rate[index], rate_ci[index], message[index], (low, high) = _rates(
            hazard, x, n_event[index], n_total[index], method, n_boot, seed, ci)  # fmt: skip
        spread = [min(spread[0], low), max(spread[1], high)]
    unit = "year-1"
    out = xr.Dataset(
        {
            "annual_rate": (rest, rate, {"units": unit, "long_name":
                            f"mean annual rate of {event} at the site"}),
            "annual_rate_ci": ((*rest, "bound"), rate_ci, {"units": unit, "long_name":
                               f"bootstrap {ci:g} confidence interval of annual_rate"}),
            "rate_message": (rest, message, {"long_name": "why there is no annual rate"}),
            "n_event": ((*rest, dim), n_event.astype(np.int64),
                        {"units": "1", "long_name": f"simulations with {event}"}),
            "n_total": ((*rest, dim), n_total.astype(np.int64),
                        {"units": "1", "long_name": _COUNTED}),
            "n_left_out": (n_out.dims, n_out.values.astype(np.int64),
                           {"units": "1", "long_name": _LEFT_OUT}),
        },
        coords={**{d: ds[d] for d in (*rest, dim)}, "bound": ["lower", "upper"]},
        attrs={"im": dim, "event": str(event), "method": method, "hazard": hazard.source,
               "target_rate": math.nan if target is None else float(target),
               "years": math.nan if years is None else float(years), "ci": float(ci)},
    )  # fmt: skip
    if years is not None:
        out["probability"] = (rest, probability_in(rate, years), {"units": "1", "long_name":
                              f"probability of {event} in {years:g} years"})  # fmt: skip
    out.attrs["extrapolation"] = hazard.extrapolated(*spread)
    if target is not None and GAP_DIM in rest:
        _risk_gap(out, rest, target)
    return out


def _risk_gap(out: xr.Dataset, rest: list[str], target: float) -> None:
    """``required_gap`` (and its interval, its message) of the rates in ``out``."""
    others = [d for d in rest if d != GAP_DIM]
    none = (out["n_event"].sum(out.attrs["im"]) == 0).transpose(*others, GAP_DIM).values
    # a gap at which no run had the event: its rate is below what the stripes resolve, 0 here
    rates = np.where(none, 0.0, out["annual_rate"].transpose(*others, GAP_DIM).values)
    bounds = out["annual_rate_ci"].transpose(*others, GAP_DIM, "bound").values
    bounds = np.where(none[..., None], 0.0, bounds)
    gaps = np.asarray(out[GAP_DIM].values, float)
    shape = rates.shape[:-1]
    gap = np.full(shape, np.nan)
    gap_ci = np.full((*shape, 2), np.nan)
    message = np.full(shape, "", dtype=object)
    for index in itertools.product(*(range(n) for n in shape)):
        gap[index], message[index] = gap_for_rate(gaps, rates[index], target)
        # the lower rates meet the target at a narrower gap, the upper at a wider one
        gap_ci[index] = [gap_for_rate(gaps, bounds[index][:, b], target)[0] for b in (0, 1)]
    out["required_gap"] = (
        others,
        gap,
        {"units": "m", "long_name": f"gap whose annual rate equals the target {target:.3g}/year"},
    )
    out["required_gap_ci"] = (
        (*others, "bound"),
        gap_ci,
        {"units": "m", "long_name": "gaps at which the interval's rates meet the target"},
    )
    out["gap_message"] = (others, message, {"long_name": "why there is no risk-targeted gap"})


def code_gaps(
    ds: xr.Dataset,
    *,
    asce: tuple[float, float, float] | None = None,
    ec8: tuple[float, float | None, bool] | None = None,
    base_dir=None,
) -> xr.Dataset:
    """The rules' and codes' separations of a study's buildings, and how often they fail.

    Per run, from the two SDOF buildings' peak linear displacements under its record
    (:func:`pound_mc.analysis.gaps.study_gaps`): ABS, SRSS and DDC, and with their factors
    ASCE/SEI 7-22 section 12.12.2 (``asce = (R, Cd, Ie)``) and EN 1998-1:2004 section
    4.4.2.7 (``ec8 = (q, qd or None, same_levels)``), :mod:`pound_mc.physics.separation`.
    Each run is then simulated again with its own rule gap, for each rule: whether it pounds
    there is known, not read off a median.

    Returns
    -------
    xarray.Dataset
        Along ``rule`` and the grid axes other than the gap: ``code_gap`` [m] (the median over
        records and samples), ``code_gap_exceedance`` [-] (the fraction of the runs, status ok
        or inaccurate at their rule gap, that pound at a gap equal to their own rule gap) and
        ``code_gap_left_out`` (the runs that were not, unstable or not converged).
    """
    engine = engine_of(ds, base_dir=base_dir)
    gaps_ds = study_gaps(ds, engine=engine)
    if GAP_DIM in gaps_ds.dims:
        gaps_ds = gaps_ds.isel({GAP_DIM: 0}, drop=True)  # the linear responses ignore the gap
    u1, u2 = gaps_ds["linear_disp_left"], gaps_ds["linear_disp_right"]
    per_run = {"abs": gaps_ds["gap_abs"], "srss": gaps_ds["gap_srss"], "ddc": gaps_ds["gap_ddc"]}
    if asce is not None:
        r, cd, ie = asce
        per_run["asce7_22"] = xr.apply_ufunc(lambda a, b: gap_asce7(a, b, r=r, cd=cd, ie=ie),
                                             u1, u2)  # fmt: skip
    if ec8 is not None:
        q, qd, same = ec8
        per_run["en1998_1"] = xr.apply_ufunc(
            lambda a, b: gap_ec8(a, b, q=q, qd=qd, same_levels=same), u1, u2)  # fmt: skip
    rules = list(per_run)
    table = xr.concat([per_run[k] for k in rules], dim="rule").assign_coords(rule=rules)
    median = table.median(("record", "sample"))
    hits, counted_runs = _pounding_at(engine, table)
    n_runs = table.sizes["record"] * table.sizes["sample"]
    exceed = hits.sum(("record", "sample")) / counted_runs.sum(("record", "sample"))
    missed = n_runs - counted_runs.sum(("record", "sample"))
    return xr.Dataset(
        {
            "code_gap": (median.dims, median.values, {"units": "m", "long_name":
                         "separation a rule or code asks for (median over records and samples)"}),
            "code_gap_exceedance": (exceed.dims, exceed.values, {"units": "1", "long_name":
                                    "fraction of runs that pound at their own rule gap"}),
            "code_gap_left_out": (missed.dims, missed.values.astype(np.int64), {"units": "1",
                                  "long_name": "runs unstable or not converged at their rule "
                                  "gap (not in code_gap_exceedance)"}),
            "rule_description": (("rule",), np.asarray([RULES[k] for k in rules], object)),
        },
        coords={d: median[d] for d in median.dims},
    )  # fmt: skip


def _pounding_at(engine, table: xr.DataArray) -> tuple[xr.DataArray, xr.DataArray]:
    """Each run simulated at each rule's gap: whether it pounds, and whether it counts."""
    study = engine.study
    dims = ("record", *(d for d in table.dims if d not in ("rule", "record", "sample")),
            "sample")  # fmt: skip
    names = ["record", *(grid_dim_name(k) for k in study.grid), "sample"]
    # the runs at the first gap (the gap is replaced): their flat indices, in ``dims`` order
    full = np.arange(study.n_simulations).reshape(study.shape)
    if GAP_DIM in names:
        full = np.take(full, 0, axis=names.index(GAP_DIM))
        names.remove(GAP_DIM)
    order = [names.index(d) for d in dims]
    indices = np.transpose(full, order).ravel()
    hits, ok = [], []
    for rule in table["rule"].values:
        gaps = table.sel(rule=rule).transpose(*dims).values.ravel()
        out = engine.run_at_gaps(indices, gaps)
        counted_run = np.isin(out["status"], (STATUS_OK, STATUS_INACCURATE))
        hits.append(
            (counted_run & (out["impacts"] > 0)).reshape(
                table.sel(rule=rule).transpose(*dims).shape
            )
        )
        ok.append(counted_run.reshape(hits[-1].shape))
    coords = {"rule": table["rule"], **{d: table[d] for d in dims if d in table.coords}}
    return (xr.DataArray(np.stack(hits), dims=("rule", *dims), coords=coords),
            xr.DataArray(np.stack(ok), dims=("rule", *dims), coords=coords))  # fmt: skip


def design_code_gaps(ds, out, hazard, codes):
    """The rules' and codes' gaps at each code's design intensity on ``hazard``.

    ASCE 7-22's design earthquake is two thirds of the MCE_R (2 % in 50 years), EN 1998-1's
    the 10 % in 50 years action (:func:`~pound_mc.analysis.site_risk.design_intensity`); the
    rules (ABS, SRSS, DDC) are taken at EN 1998-1's.  Each gap is read at that intensity
    from the stripes (linear in the intensity, as the linear displacements are).
    """
    gaps = code_gaps(ds, **codes)
    dim = out.attrs["im"]
    levels = {rule: design_intensity(hazard, rule) for rule in gaps["rule"].values}
    x = np.asarray(gaps[dim].values, float)
    picked = []
    for rule in gaps["rule"].values:
        g = gaps.sel(rule=rule)
        picked.append(g.interp({dim: levels[rule]}, kwargs={"fill_value": "extrapolate"})
                      if x.size > 1 else g.isel({dim: 0}))  # fmt: skip
    table = xr.concat(picked, dim="rule", coords="minimal", compat="override")
    table = table.drop_vars(dim, errors="ignore")
    table.attrs["design_im"] = {str(k): v for k, v in levels.items()}
    return table


def site_assessment(ds: xr.Dataset, hazard: HazardCurve, codes: dict | None = None, **options):
    """:func:`risk` of ``ds`` on ``hazard`` and, where it gives a risk-targeted gap, the codes'.

    ``options`` go to :func:`risk`; ``codes``: the factors of :func:`code_gaps` (``asce``,
    ``ec8``; none: the rules alone).  Returns ``(risk, gaps)``, ``gaps`` None where no rule
    describes the buildings (shear buildings, a wall) or the dataset has no study text.
    """
    out = risk(ds, hazard, **options)
    gaps = None
    if "required_gap" in out and ds.attrs.get("study_text"):
        try:
            gaps = design_code_gaps(ds, out, hazard, codes or {})
        except RulesDoNotApply:
            gaps = None
    return out, gaps
