"""Fragility curves and the required gap of a study dataset (``ds.pound.fragility``, ...).

A study with an intensity axis (``sa_g`` or ``pga_g``: a multiple-stripe analysis) gives at
each intensity the number of simulations (records x samples, status ok; for pounding also
``inaccurate``, :func:`~pound_mc.study.dataset.pounding_counted`) and how many of them
had an event; :func:`fragility` fits the lognormal fragility of
:func:`pound_mc.analysis.fragility.fit_fragility` to these stripes for every combination of
the other grid axes (e.g. per gap).  :func:`required_gap` reads, per combination of the grid
axes other than the gap, the smallest gap whose pounding probability (over records and
samples) is at or below a target (:func:`pound_mc.analysis.gap_probability.required_gap`), and sets
the separation rules' gaps beside it (:func:`pound_mc.analysis.gaps.study_gaps`).

Events (``event=``): ``"pounding"`` (at least one impact), ``"peak_force>N"`` (a peak impact
force above N newtons), ``"ductility>X"`` (a peak ductility ``peak_ductility_left`` or
``peak_ductility_right`` above X) and ``"drift>X"`` (a peak inter-storey drift ratio
``peak_drift_left`` or ``peak_drift_right`` above X); the last two are refused for datasets
without these outputs.
"""

from __future__ import annotations

import itertools
import math
import re

import numpy as np
import xarray as xr

from pound_mc.analysis.fragility import fit_fragility
from pound_mc.analysis.gap_probability import required_gap as _required_gap
from pound_mc.analysis.gaps import RulesDoNotApply, study_gaps
from pound_mc.errors import InputError
from pound_mc.study.dataset import pounding_counted

__all__ = [
    "INTENSITY_DIMS",
    "GAP_DIM",
    "counted",
    "left_out",
    "left_out_why",
    "event_mask",
    "fragility",
    "required_gap",
]

#: Dataset dimensions of the intensity axes (``record.sa_g``, ``record.pga_g``).
INTENSITY_DIMS = ("sa_g", "pga_g")
#: Dataset dimension of the initial gap.
GAP_DIM = "contact_gap_m"
_DUCTILITY = ("peak_ductility_left", "peak_ductility_right")
_DRIFT = ("peak_drift_left", "peak_drift_right")
_EVENT = re.compile(r"^\s*(peak_force|ductility|drift)\s*>\s*([-+0-9.eE]+)\s*$")


def _is_pounding(event) -> bool:
    """Whether ``event`` names pounding (spaces around it allowed, as the CLI may pass them)."""
    return str(event).strip() == "pounding"


def event_mask(ds: xr.Dataset, event: str = "pounding") -> xr.DataArray:
    """Per simulation, whether it had ``event`` (``pounding``, ``peak_force>N``, ``ductility>X``).

    Raises
    ------
    InputError
        An event that is not one of these forms, or ``ductility>X`` on a dataset without the
        ductility outputs.
    """
    text = str(event).strip()
    if text == "pounding":
        return ds["impacts"] > 0
    match = _EVENT.match(text)
    try:
        threshold = float(match.group(2)) if match else math.nan
    except ValueError:
        threshold = math.nan
    if match is None or not math.isfinite(threshold):
        raise InputError(
            f"unknown event {event!r}; use pounding, peak_force>N (newtons), ductility>X or "
            "drift>X (a drift ratio)",
            key="--event",
        )
    if match.group(1) == "peak_force":
        return ds["peak_force"] > threshold
    names = _DUCTILITY if match.group(1) == "ductility" else _DRIFT
    missing = [name for name in names if name not in ds]
    if missing:
        raise InputError(
            f"the event {event!r} needs the outputs {', '.join(names)}, which this dataset "
            "does not have (its buildings are elastic)",
            key="--event",
        )
    return (ds[names[0]] > threshold) | (ds[names[1]] > threshold)


def _intensity_dim(ds: xr.Dataset, im: str | None) -> str:
    dims = [d for d in ds["peak_force"].dims if d not in ("record", "sample")]
    if im is None:
        found = [d for d in INTENSITY_DIMS if d in dims]
        if not found:
            raise InputError(
                f"the dataset has no intensity axis ({' or '.join(INTENSITY_DIMS)}); name a "
                f"grid dimension as the intensity (--im, or im= in Python; one of {dims})",
                key="--im",
            )
        return found[0]
    if im not in dims:
        raise InputError(f"no grid dimension {im!r}; the dataset has {dims}", key="--im")
    if not np.all(np.asarray(ds[im].values, dtype=float) > 0):
        raise InputError(f"the intensities of {im!r} must all be > 0", key="--im")
    return im


#: ``n_total``'s long name (:func:`_counts`).
_COUNTED = "simulations counted (status ok; for pounding also inaccurate)"


def counted(ds: xr.Dataset, event: str = "pounding") -> xr.DataArray:
    """The simulations a summary of ``event`` counts (every summary, chart and check asks here).

    Status ok; for ``pounding`` also ``inaccurate``
    (:func:`~pound_mc.study.dataset.pounding_counted`: the flag doubts the peak force, and
    only pounding runs carry it); a force or ductility event counts status ok only.
    """
    return pounding_counted(ds["status"]) if _is_pounding(event) else ds["status"] == 0


def _counts(ds: xr.Dataset, event: str, over=("record", "sample")):
    """Simulations counted (:func:`counted`) and those with the event, summed over ``over``."""
    ok = counted(ds, event)
    hit = event_mask(ds, event) & ok
    return hit.sum(over), ok.sum(over)


def left_out(ds: xr.Dataset, event: str = "pounding", over=("record", "sample")) -> xr.DataArray:
    """Simulations a summary of ``event`` leaves out (not :func:`counted`), summed over ``over``.

    Unstable and not-converged runs always; ``inaccurate`` runs (their peak force in doubt)
    for a force or ductility event.  No analysis leaves runs out silently: every summary
    reports this count (``n_left_out``).
    """
    return (~counted(ds, event)).sum(over)


def left_out_why(event: str = "pounding") -> str:
    """The statuses of the simulations a summary of ``event`` leaves out, in words."""
    if _is_pounding(event):
        return "unstable or not converged"
    return "unstable, not converged or inaccurate: their peak force is in doubt"


#: ``n_left_out``'s long name.
_LEFT_OUT = (
    "simulations left out (unstable or not converged; inaccurate unless the event is pounding)"
)


def fragility(
    ds: xr.Dataset,
    im: str | None = None,
    event: str = "pounding",
    *,
    n_boot: int = 1000,
    seed: int = 0,
    ci: float = 0.95,
) -> xr.Dataset:
    """Lognormal fragility fitted per combination of the grid axes other than ``im``.

    Parameters
    ----------
    ds : xarray.Dataset
        A study dataset.
    im : str, optional
        The intensity dimension (default the dataset's ``sa_g`` or ``pga_g`` axis); any grid
        dimension with values > 0 may stand in.
    event : str, default "pounding"
        ``"pounding"``, ``"peak_force>N"`` or ``"ductility>X"``.
    n_boot, seed, ci
        Bootstrap replicates, seed and confidence level
        (:func:`pound_mc.analysis.fragility.fit_fragility`); the same seed for every
        combination.

    Returns
    -------
    xarray.Dataset
        Along the remaining grid axes: ``theta`` (median, units of the IM), ``beta`` [-],
        ``theta_ci`` and ``beta_ci`` (with a ``bound`` dimension: lower, upper), the stripes
        ``n_event``, ``n_total`` and ``n_left_out`` (the runs not counted, :func:`left_out`;
        with the IM dimension) and ``fit_message`` (why a
        combination has no fit, "" where it has one), ``n_boot_discarded`` (bootstrap resamples
        without a fit, left out) and ``bootstrap_note`` (why, "" where none was; the intervals
        are NaN when more than half were); attributes ``im``, ``event``, ``ci``.
    """
    dim = _intensity_dim(ds, im)
    n_event, n_total = _counts(ds, event)
    rest = [d for d in n_event.dims if d != dim]
    n_event = n_event.transpose(*rest, dim)
    n_total = n_total.transpose(*rest, dim)
    n_out = left_out(ds, event).transpose(*rest, dim)
    shape = tuple(ds.sizes[d] for d in rest)
    theta = np.full(shape, np.nan)
    beta = np.full(shape, np.nan)
    theta_ci = np.full((*shape, 2), np.nan)
    beta_ci = np.full((*shape, 2), np.nan)
    message = np.full(shape, "", dtype=object)
    discarded = np.zeros(shape, dtype=np.int64)
    note = np.full(shape, "", dtype=object)
    x = np.asarray(ds[dim].values, dtype=float)
    for index in itertools.product(*(range(n) for n in shape)):
        try:
            fit = fit_fragility(
                x, n_event.values[index], n_total.values[index], n_boot=n_boot, seed=seed, ci=ci
            )
        except InputError as exc:
            message[index] = exc.message
            continue
        theta[index], beta[index] = fit.theta, fit.beta
        theta_ci[index], beta_ci[index] = fit.theta_ci, fit.beta_ci
        discarded[index], note[index] = fit.n_boot_discarded, fit.bootstrap_note
    units = ds[dim].attrs.get("units", "1")
    bound = ("bound",)
    out = xr.Dataset(
        {
            "theta": (rest, theta, {"units": units, "long_name": "median of the fragility"}),
            "beta": (rest, beta, {"units": "1", "long_name": "dispersion of the fragility"}),
            "theta_ci": ((*rest, *bound), theta_ci, {"units": units,
                         "long_name": f"bootstrap {ci:g} confidence interval of theta"}),
            "beta_ci": ((*rest, *bound), beta_ci, {"units": "1",
                        "long_name": f"bootstrap {ci:g} confidence interval of beta"}),
            "n_event": (n_event.dims, n_event.values.astype(np.int64),
                        {"units": "1", "long_name": f"simulations with {event}"}),
            "n_total": (n_total.dims, n_total.values.astype(np.int64),
                        {"units": "1", "long_name": _COUNTED}),
            "n_left_out": (n_out.dims, n_out.values.astype(np.int64),
                           {"units": "1", "long_name": _LEFT_OUT}),
            "fit_message": (rest, message, {"long_name": "why there is no fit"}),
            "n_boot_discarded": (rest, discarded, {"units": "1", "long_name":
                                 "bootstrap resamples without a fit, left out"}),
            "bootstrap_note": (rest, note, {"long_name": "why bootstrap resamples were left out"}),
        },
        coords={**{d: ds[d] for d in (*rest, dim)}, "bound": ["lower", "upper"]},
        attrs={"im": dim, "event": str(event), "ci": ci, "n_boot": n_boot},
    )  # fmt: skip
    return out


def required_gap(
    ds: xr.Dataset,
    probability: float = 0.1,
    *,
    ci: float = 0.95,
    rules: bool = True,
    base_dir=None,
) -> xr.Dataset:
    """Smallest gap with pounding probability at or below ``probability``, per other grid axis.

    The probability at each gap is the fraction of the simulations (records x samples, status
    ok or inaccurate) with an impact; the gap and its Wilson interval are
    :func:`pound_mc.analysis.gap_probability.required_gap`'s.

    Parameters
    ----------
    ds : xarray.Dataset
        A study dataset with ``contact_gap_m`` on its grid (two or more gaps).
    probability : float, default 0.1
        Target probability, in (0, 1).
    ci : float, default 0.95
        Confidence level.
    rules : bool, default True
        Add the separation rules' gaps: the median over records and samples of ``gap_abs``,
        ``gap_srss`` and ``gap_ddc`` (:func:`pound_mc.analysis.gaps.study_gaps`; the records
        are read again).
    base_dir : str or Path, optional
        Folder of relative record paths, for the rules.

    Returns
    -------
    xarray.Dataset
        Along the grid axes other than the gap: ``required_gap`` [m], ``required_gap_ci``
        (``bound``: lower, upper) [m], ``message`` (why there is none, else ""), the
        ``pounding_probability``, ``n_total`` and ``n_left_out`` (:func:`left_out`) per gap,
        and with ``rules`` ``gap_abs``,
        ``gap_srss``, ``gap_ddc`` [m]; attributes ``target`` and ``ci`` (and ``rules``, why
        the rules' gaps are left out, for a study of shear buildings or a wall).
    """
    if GAP_DIM not in ds.dims or ds.sizes[GAP_DIM] < 2:
        raise InputError(
            "the required gap needs a study with two or more gaps on its grid (contact.gap_m)",
            key="contact.gap_m",
        )
    n_event, n_total = _counts(ds, "pounding")
    rest = [d for d in n_event.dims if d != GAP_DIM]
    n_event = n_event.transpose(*rest, GAP_DIM)
    n_total = n_total.transpose(*rest, GAP_DIM)
    n_out = left_out(ds, "pounding").transpose(*rest, GAP_DIM)
    p = n_event / n_total.where(n_total > 0)
    shape = tuple(ds.sizes[d] for d in rest)
    gap = np.full(shape, np.nan)
    gap_ci = np.full((*shape, 2), np.nan)
    message = np.full(shape, "", dtype=object)
    gaps = np.asarray(ds[GAP_DIM].values, dtype=float)
    for index in itertools.product(*(range(n) for n in shape)):
        try:
            found = _required_gap(gaps, p.values[index], n_total.values[index], probability, ci=ci)
        except InputError as exc:
            message[index] = exc.message
            continue
        gap[index] = found.gap
        gap_ci[index] = found.gap_ci
    out = xr.Dataset(
        {
            "required_gap": (rest, gap, {"units": "m", "long_name":
                             f"smallest gap with pounding probability <= {probability:g}"}),
            "required_gap_ci": ((*rest, "bound"), gap_ci, {"units": "m", "long_name":
                                f"Wilson {ci:g} confidence interval of required_gap"}),
            "message": (rest, message, {"long_name": "why there is no required gap"}),
            "pounding_probability": (p.dims, p.values, {"units": "1", "long_name":
                                     "fraction of the simulations with an impact"}),
            "n_total": (n_total.dims, n_total.values.astype(np.int64),
                        {"units": "1", "long_name": _COUNTED}),
            "n_left_out": (n_out.dims, n_out.values.astype(np.int64),
                           {"units": "1", "long_name": _LEFT_OUT}),
        },
        coords={**{d: ds[d] for d in (*rest, GAP_DIM)}, "bound": ["lower", "upper"]},
        attrs={"target": float(probability), "ci": float(ci)},
    )  # fmt: skip
    if rules:
        try:
            gaps_ds = study_gaps(ds, base_dir=base_dir)
        except RulesDoNotApply as exc:  # shear buildings, a wall: the rules do not describe them
            out.attrs["rules"] = exc.message
            return out
        for name in ("gap_abs", "gap_srss", "gap_ddc"):
            value = gaps_ds[name].median([d for d in gaps_ds[name].dims if d not in rest])
            out[name] = value.assign_attrs(gaps_ds[name].attrs).drop_vars(
                [c for c in value.coords if c not in rest]
            )
    return out
