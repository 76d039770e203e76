"""Preprocessing of a record: demean, filter, resample, truncate and scale.

Preprocessing (DESIGN.md section 6, in this order): remove the mean of the whole record as read,
keep the samples with ``t - t0 <= duration_s``, scale so that the peak of the kept samples is
``pga_g * G``.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from typing import Any

import numpy as np

from pound_mc.errors import InputError
from pound_mc.motions.traces import AttribDict, G, _check_samples, _where, obspy

__all__ = ["preprocess"]


#: A ``duration_s`` window that keeps less than this fraction of a record's peak acceleration
#: is named by ``check``, ``run`` and ``simulate`` (``stats.pound.window_peak_fraction``): scaled
#: to an intensity, it scales what precedes the strong motion.
WINDOW_PEAK_WARN = 0.5


def _positive(value, *, name: str, file) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise InputError(f"must be a number, got {value!r}", file=file, key=name) from None
    if isinstance(value, bool) or not (math.isfinite(x) and x > 0):
        raise InputError(f"must be a finite number > 0, got {value!r}", file=file, key=name)
    return x


def preprocess(
    trace: obspy.Trace,
    *,
    demean: bool = True,
    duration_s: float | None = None,
    pga_g: float | None = None,
    resample_hz: float | None = None,
    filter: Mapping[str, Any] | None = None,  # the name obspy uses for it
) -> obspy.Trace:
    """Demean, truncate and scale a record, in that order (DESIGN.md section 6).

    Parameters
    ----------
    trace : obspy.Trace
        Acceleration [m/s^2]; not modified.
    demean : bool, default True
        Subtract the mean of the whole record as read.
    duration_s : float, optional
        Keep the samples with ``t - t0 <= duration_s`` [s]; must not exceed the record.
    pga_g : float, optional
        Scale so that max |a| of the kept samples is ``pga_g * G`` [g].
    resample_hz : float, optional
        Off by default.  New sampling rate [Hz] (obspy's Fourier resampling, without a taper:
        the spectrum below the lower Nyquist frequency is kept as it is), applied after
        demeaning and filtering, before truncation.
    filter : dict, optional
        Off by default.  Arguments of :meth:`obspy.Trace.filter`, e.g.
        ``{"type": "bandpass", "freqmin": 0.1, "freqmax": 25.0}``; applied after demeaning.

    Returns
    -------
    obspy.Trace
        A new trace; the steps are listed in ``stats.pound.processing``.

    Raises
    ------
    InputError
        Bad numbers, a duration longer than the record, scaling an all-zero record, a bad
        filter.
    """
    where = _where(trace)
    out = trace.copy()
    if "pound" not in out.stats:
        out.stats.pound = AttribDict({"processing": []})
    steps = list(out.stats.pound.get("processing", []))
    data = np.asarray(out.data, dtype=np.float64).copy()
    dt = float(out.stats.delta)
    _check_samples(data, dt, file=where)
    if demean:
        mean = float(data.mean())
        data -= mean
        steps.append(f"demean: subtracted {mean:.9g} m/s^2")
    out.data = data
    if filter is not None:
        if not isinstance(filter, Mapping) or "type" not in filter:
            raise InputError(
                "filter must be a table of obspy filter arguments with a 'type' "
                "(e.g. {type = 'bandpass', freqmin = 0.1, freqmax = 25.0})",
                file=where,
                key="record.filter",
            )
        options = dict(filter)
        kind = options.pop("type")
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error")
                out.filter(kind, **options)
        except Exception as exc:  # obspy raises ValueError/TypeError/warnings on bad options
            raise InputError(
                f"filter {dict(filter)!r} failed: {exc}", file=where, key="record.filter"
            ) from None
        steps.append(f"filter: {dict(filter)!r}")
    if resample_hz is not None:
        rate = _positive(resample_hz, name="record.resample_hz", file=where)
        # no window: obspy's default Hann taper scales a frequency f by (1 + cos(pi f / f_N)) / 2
        # (f_N the record's Nyquist frequency; a 10-Hz sine at 100 Hz lost 10 % of its peak)
        out.resample(rate, window=None)
        steps.append(f"resample: {rate:g} Hz")
    data = np.asarray(out.data, dtype=np.float64)
    dt = float(out.stats.delta)
    if duration_s is not None:
        duration = _positive(duration_s, name="record.duration_s", file=where)
        available = (data.size - 1) * dt
        if duration > available * (1 + 1e-9) + 1e-12:
            raise InputError(
                f"duration_s = {duration:g} s is longer than the record "
                f"({available:g} s, {data.size} samples at dt = {dt:g} s)",
                file=where,
                key="record.duration_s",
            )
        keep = min(data.size, int(math.floor(duration / dt + 1e-9)) + 1)
        whole = float(np.max(np.abs(data)))
        data = data[:keep]
        steps.append(f"truncate: kept {keep} samples, t - t0 <= {duration:g} s")
        # how much of the record's peak the window keeps (a window of pre-event noise: ~0)
        out.stats.pound.window_peak_fraction = (
            float(np.max(np.abs(data))) / whole if whole > 0.0 else 1.0
        )
    if pga_g is not None:
        target = _positive(pga_g, name="record.pga_g", file=where)
        peak = float(np.max(np.abs(data)))
        if peak == 0.0:
            raise InputError(
                "cannot scale to pga_g: the kept samples are all zero",
                file=where,
                key="record.pga_g",
            )
        factor = target * G / peak
        data = data * factor
        steps.append(f"scale: x{factor:.9g} to PGA {target:g} g")
    out.data = np.ascontiguousarray(data, dtype=np.float64)
    out.stats.pound.processing = steps
    return out
