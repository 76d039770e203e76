"""Classical separation-gap rules for two adjacent buildings.

Given the peak linear displacements ``u1`` and ``u2`` [m] of two adjacent buildings (relative to
the ground, each building analysed alone), the gap that design codes and the literature ask for
is one of

``ABS``
    absolute sum, ``|u1| + |u2|``: the buildings move out of phase at the same instant; an upper
    bound on the linear relative displacement, so no pounding can occur with a larger gap.
``SRSS``
    square root of the sum of squares, ``sqrt(u1^2 + u2^2)``: the two peaks statistically
    independent.
``DDC``
    double difference combination, ``sqrt(u1^2 + u2^2 - 2 rho u1 u2)`` (Jeng et al. 1992,
    Penzien 1997): the peak of the relative displacement of two linear oscillators under the
    same random excitation, with ``rho`` the cross-correlation of their responses, the CQC
    coefficient of Der Kiureghian (1981) for white-noise excitation,

    ``rho = 8 sqrt(z1 z2) (z1 + r z2) r^1.5 /
    ((1 - r^2)^2 + 4 z1 z2 r (1 + r^2) + 4 (z1^2 + z2^2) r^2)``,  ``r = T1 / T2 = omega2 /
    omega1``

    (Der Kiureghian 1981, eq. for ``rho_ij`` with ``r = omega_j / omega_i``; the same formula
    is Chopra 2012, eq. 13.7.10).  ``rho = 1`` for equal periods and equal damping (the
    buildings move in phase, DDC = ``|u1 - u2|``) and ``rho -> 0`` for well separated
    periods (DDC -> SRSS).  ``0 <= rho <= 1`` for positive damping, so DDC <= SRSS <= ABS.

:func:`required_gaps` computes the three from a record and two SDOF oscillators (the exact
linear response of :mod:`pound_mc.physics.spectra`); :func:`study_gaps` does so for every
simulation of
a study (or of the dataset it wrote), so that a chart of pounding probability against gap can
mark the three rules.

References
----------
Der Kiureghian, A. (1981). A response spectrum method for random vibration analysis of MDF
systems. Earthq. Eng. Struct. Dyn. 9(5), 419-435.
Jeng, V., Kasai, K., Maison, B. F. (1992). A spectral difference method to estimate building
separations to avoid pounding. Earthq. Spectra 8(2), 201-223.
Penzien, J. (1997). Evaluation of building separation distance required to prevent pounding
during strong earthquakes. Earthq. Eng. Struct. Dyn. 26(8), 849-858.
Chopra, A. K. (2012). Dynamics of Structures, 4th ed. Prentice Hall, sec. 13.7.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pound_mc.errors import InputError
from pound_mc.physics.spectra import response_spectrum

__all__ = [
    "gap_abs",
    "gap_srss",
    "gap_ddc",
    "cqc_correlation",
    "SeparationGaps",
    "peak_displacements",
    "required_gaps",
    "study_gaps",
]


def gap_abs(u1, u2):
    """Absolute-sum separation rule ``|u1| + |u2|``.

    Parameters
    ----------
    u1, u2 : float or array_like
        Peak displacements of the two buildings [m].

    Returns
    -------
    float or numpy.ndarray
        Required gap [m].
    """
    return np.abs(u1) + np.abs(u2)


def gap_srss(u1, u2):
    """Square-root-of-sum-of-squares separation rule ``sqrt(u1^2 + u2^2)``.

    Parameters
    ----------
    u1, u2 : float or array_like
        Peak displacements of the two buildings [m].

    Returns
    -------
    float or numpy.ndarray
        Required gap [m].
    """
    return np.hypot(u1, u2)


def cqc_correlation(period1_s, period2_s, damping1=0.05, damping2=0.05):
    """Correlation of two linear oscillators' responses: the CQC coefficient.

    ``rho = 8 sqrt(z1 z2) (z1 + r z2) r^1.5 / ((1 - r^2)^2 + 4 z1 z2 r (1 + r^2)
    + 4 (z1^2 + z2^2) r^2)`` with ``r = T1 / T2`` (Der Kiureghian 1981; Chopra 2012,
    eq. 13.7.10, where ``r = omega_j / omega_i`` and ``i`` is building 1).

    Parameters
    ----------
    period1_s, period2_s : float or array_like
        Natural periods [s], > 0.
    damping1, damping2 : float or array_like
        Viscous damping ratios [-], > 0 (with zero damping ``rho`` is 0 unless ``r = 1``,
        where it is undefined).

    Returns
    -------
    float or numpy.ndarray
        ``rho`` [-], in ``[0, 1]``; 1 for equal periods and damping ratios.
    """
    t1 = np.asarray(period1_s, dtype=float)
    t2 = np.asarray(period2_s, dtype=float)
    z1 = np.asarray(damping1, dtype=float)
    z2 = np.asarray(damping2, dtype=float)
    if np.any(~(t1 > 0)) or np.any(~(t2 > 0)):
        raise InputError("periods must be > 0 s", key="period_s")
    if np.any(~(z1 > 0)) or np.any(~(z2 > 0)):
        raise InputError("damping ratios must be > 0", key="damping_ratio")
    r = t1 / t2
    num = 8.0 * np.sqrt(z1 * z2) * (z1 + r * z2) * r**1.5
    den = (1.0 - r**2) ** 2 + 4.0 * z1 * z2 * r * (1.0 + r**2) + 4.0 * (z1**2 + z2**2) * r**2
    rho = num / den
    return float(rho) if rho.ndim == 0 else rho


def gap_ddc(u1, u2, rho):
    """Double-difference-combination separation rule ``sqrt(u1^2 + u2^2 - 2 rho u1 u2)``.

    Parameters
    ----------
    u1, u2 : float or array_like
        Peak displacements of the two buildings [m] (magnitudes).
    rho : float or array_like
        Correlation of the two responses [-] (:func:`cqc_correlation`).

    Returns
    -------
    float or numpy.ndarray
        Required gap [m] (Jeng et al. 1992; Penzien 1997).
    """
    a, b = np.abs(u1), np.abs(u2)
    return np.sqrt(np.maximum(a**2 + b**2 - 2.0 * np.asarray(rho) * a * b, 0.0))


@dataclass(frozen=True)
class SeparationGaps:
    """Peak linear displacements of two buildings and the gaps the three rules require.

    Attributes
    ----------
    u1, u2 : float
        Peak linear displacements of building 1 (left) and 2 (right) [m].
    rho : float
        CQC correlation of their responses [-].
    abs, srss, ddc : float
        Required gaps [m] by the ABS, SRSS and DDC rules.
    """

    u1: float
    u2: float
    rho: float
    abs: float
    srss: float
    ddc: float


def _fine(dt: float, acc: np.ndarray, substeps: int) -> tuple[float, np.ndarray]:
    """The record linearly interpolated at ``substeps`` points per interval (same excitation)."""
    if substeps == 1:
        return dt, acc
    t = np.arange(acc.size) * dt
    fine_t = np.linspace(0.0, t[-1], (acc.size - 1) * substeps + 1)
    return dt / substeps, np.interp(fine_t, t, acc)


def peak_displacements(dt, acc, periods, damping=0.05, *, substeps: int = 8) -> np.ndarray:
    """Peak linear displacements ``max |u(t)|`` of SDOF oscillators starting at rest.

    The excitation is ``acc`` linearly interpolated (as in the engine, DESIGN.md section 2); the
    oscillators are stepped exactly (:func:`pound_mc.physics.spectra.response_spectrum`) at
    ``substeps`` points per sample interval, so the maximum between samples is caught to a
    relative error of about ``(pi dt / (substeps T))^2 / 2``.

    Parameters
    ----------
    dt : float
        Sampling interval of ``acc`` [s].
    acc : array_like
        Ground acceleration [m/s^2].
    periods : array_like
        Natural periods [s], > 0.
    damping : float, default 0.05
        Viscous damping ratio [-], >= 0.
    substeps : int, default 8
        Evaluation points per sample interval (>= 1).

    Returns
    -------
    numpy.ndarray
        Peak displacement [m] relative to the ground, one per period.
    """
    if not (isinstance(substeps, int) and substeps >= 1):
        raise InputError(f"substeps must be an integer >= 1, got {substeps!r}", key="substeps")
    acc = np.asarray(acc, dtype=float)
    periods = np.atleast_1d(np.asarray(periods, dtype=float))
    fdt, facc = _fine(float(dt), acc, substeps)
    omega = 2.0 * math.pi / periods
    return response_spectrum(fdt, facc, periods, damping) / omega**2


def required_gaps(
    dt,
    acc,
    period1_s: float,
    period2_s: float,
    damping1: float = 0.05,
    damping2: float = 0.05,
    *,
    substeps: int = 8,
) -> SeparationGaps:
    """Peak linear displacements of two SDOF buildings under a record, and the required gaps.

    Parameters
    ----------
    dt : float
        Sampling interval of ``acc`` [s].
    acc : array_like
        Ground acceleration [m/s^2] (e.g. from :func:`pound_mc.motions.record_arrays`).
    period1_s, period2_s : float
        Natural periods of building 1 (left) and 2 (right) [s].
    damping1, damping2 : float, default 0.05
        Their viscous damping ratios [-].
    substeps : int, default 8
        Evaluation points per sample interval (:func:`peak_displacements`).

    Returns
    -------
    SeparationGaps
        ``u1``, ``u2`` [m] (elastic spectral displacements), ``rho`` [-] and the ABS, SRSS and
        DDC gaps [m].
    """
    u1 = float(peak_displacements(dt, acc, [period1_s], damping1, substeps=substeps)[0])
    u2 = float(peak_displacements(dt, acc, [period2_s], damping2, substeps=substeps)[0])
    rho = float(cqc_correlation(period1_s, period2_s, damping1, damping2))
    return SeparationGaps(
        u1=u1,
        u2=u2,
        rho=rho,
        abs=float(gap_abs(u1, u2)),
        srss=float(gap_srss(u1, u2)),
        ddc=float(gap_ddc(u1, u2, rho)),
    )


def _linear_peaks(records, rec_idx, periods, dampings, substeps) -> np.ndarray:
    """Peak displacement for each (record index, period, damping) triple, computed once each."""
    out = np.empty(rec_idx.size)
    triples = np.stack([rec_idx.astype(float), periods, dampings], axis=1)
    unique, inverse = np.unique(triples, axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    peaks = np.empty(len(unique))
    for r in np.unique(unique[:, 0]).astype(int):
        for z in np.unique(unique[unique[:, 0] == r, 2]):
            sel = np.flatnonzero((unique[:, 0] == r) & (unique[:, 2] == z))
            dt, acc = records[r]
            peaks[sel] = peak_displacements(dt, acc, unique[sel, 1], z, substeps=substeps)
    out[:] = peaks[inverse]
    return out


def study_gaps(study_or_dataset, *, base_dir=None, substeps: int = 8):
    """The three required gaps for every simulation of a study.

    The periods and damping ratios of each simulation (fixed, grid axes or sampled) are those
    the study runs; each record's linear peak displacements are computed once per distinct
    period and damping ratio.

    Parameters
    ----------
    study_or_dataset : pound_mc.study.definition.Study or xarray.Dataset
        A validated study, or a dataset written by ``pound-mc run`` (the study is rebuilt from
        its ``study_text`` attribute).
    base_dir : str or Path, optional
        Folder for relative record paths when a dataset is given (default: the working
        directory).
    substeps : int, default 8
        Evaluation points per sample interval (:func:`peak_displacements`).

    Returns
    -------
    xarray.Dataset
        Dims ``(record, *grid axes, sample)`` and coordinates as in the study's dataset:
        ``linear_disp_left``, ``linear_disp_right`` [m] (peak linear displacements),
        ``rho`` [-], ``gap_abs``, ``gap_srss``, ``gap_ddc`` [m].  Summaries over records and
        samples (e.g. ``ds.gap_abs.mean(("record", "sample"))``) are what a chart of
        pounding probability against ``contact_gap_m`` marks.
    """
    import xarray as xr

    from pound_mc.study.definition import Study, grid_dim_name, study_from_text
    from pound_mc.study.engine import StudyEngine

    if isinstance(study_or_dataset, Study):
        study = study_or_dataset
    else:
        text = study_or_dataset.attrs.get("study_text")
        if not text:
            raise InputError("the dataset has no study_text attribute", key="study_text")
        file = None if base_dir is None else str(base_dir) + "/dataset-study.toml"
        study = study_from_text(text, file=file)
    engine = StudyEngine(study)
    p = engine.parameters(np.arange(study.n_simulations))
    u1 = _linear_peaks(
        engine.records, p["record"], p["left.period_s"], p["left.damping_ratio"], substeps
    )
    u2 = _linear_peaks(
        engine.records, p["record"], p["right.period_s"], p["right.damping_ratio"], substeps
    )
    rho = cqc_correlation(
        p["left.period_s"], p["right.period_s"], p["left.damping_ratio"], p["right.damping_ratio"]
    )
    dims = ("record", *(grid_dim_name(k) for k in study.grid), "sample")
    coords = {"record": np.asarray(study.record_names, dtype=object), "sample": np.arange(study.n)}
    for key, values in study.grid.items():
        coords[grid_dim_name(key)] = values
    shape = study.shape
    variables = {
        "linear_disp_left": (u1, "m", "peak linear displacement of the left building alone"),
        "linear_disp_right": (u2, "m", "peak linear displacement of the right building alone"),
        "rho": (rho, "1", "CQC correlation of the two linear responses (Der Kiureghian 1981)"),
        "gap_abs": (gap_abs(u1, u2), "m", "required gap, absolute sum rule (ABS)"),
        "gap_srss": (gap_srss(u1, u2), "m", "required gap, square root of sum of squares (SRSS)"),
        "gap_ddc": (
            gap_ddc(u1, u2, rho),
            "m",
            "required gap, double difference combination (DDC; Jeng et al. 1992, Penzien 1997)",
        ),
    }
    data_vars = {
        name: (dims, np.asarray(values).reshape(shape), {"units": units, "long_name": long})
        for name, (values, units, long) in variables.items()
    }
    return xr.Dataset(data_vars, coords=coords, attrs={"study_name": study.name})
