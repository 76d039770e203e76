"""The separation rules for every simulation of a study: the gaps a chart marks.

The rules themselves (ABS, SRSS, DDC, the CQC correlation and the peak linear displacements)
live in :mod:`pound_mc.physics.separation`; this module applies them to the periods, damping
ratios and records of each simulation a study runs (or ran, for a dataset it wrote).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from pound_mc.errors import InputError
from pound_mc.physics.separation import (
    cqc_correlation,
    gap_abs,
    gap_ddc,
    gap_srss,
    peak_displacements,
)
from pound_mc.study.dataset import study_folder
from pound_mc.study.definition import Study, grid_dim_name, study_from_text
from pound_mc.study.engine import StudyEngine

__all__ = ["RulesDoNotApply", "engine_of", "study_gaps"]


class RulesDoNotApply(InputError):
    """A study whose buildings are not two SDOF buildings (shear buildings, a wall)."""


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


def engine_of(study_or_dataset, *, base_dir=None) -> StudyEngine:
    """The engine of a study, or of the study a dataset was run from (its ``study_text``).

    ``base_dir``: the folder of relative record paths for a dataset (default the one it
    says, :func:`~pound_mc.study.dataset.study_folder`).  The records are read here.
    """
    if isinstance(study_or_dataset, Study):
        return StudyEngine(study_or_dataset)
    text = study_or_dataset.attrs.get("study_text")
    if not text:
        raise InputError("the dataset has no study_text attribute", key="study_text")
    base_dir = study_folder(study_or_dataset) if base_dir is None else base_dir
    file = None if base_dir is None else str(base_dir) + "/dataset-study.toml"
    return StudyEngine(study_from_text(text, file=file))


def study_gaps(study_or_dataset, *, base_dir=None, substeps: int = 8, engine=None):
    """The three required gaps for every simulation of a study.

    The periods and damping ratios of each simulation (fixed, grid axes or sampled) are those
    the study runs; each record's linear peak displacements are computed once per distinct
    period and damping ratio (and, with an intensity axis, scaled by the record's factor: the
    linear peaks are proportional to the record).

    Parameters
    ----------
    study_or_dataset : pound_mc.study.definition.Study or xarray.Dataset
        A validated study, or a dataset written by ``pound-mc run`` (the study is rebuilt from
        its ``study_text`` attribute).
    base_dir : str or Path, optional
        Folder for relative record paths when a dataset is given (default: the working
        directory).
    substeps : int, default 8
        Evaluation points per sample interval
        (:func:`pound_mc.physics.separation.peak_displacements`).
    engine : pound_mc.study.engine.StudyEngine, optional
        The study's engine, if already built (:func:`engine_of`): its records are not read
        again.

    Raises
    ------
    pound_mc.errors.InputError
        Every problem of the study or its records; :class:`RulesDoNotApply` where a building is
        not an SDOF building (shear, wall): the rules do not describe it.

    Returns
    -------
    xarray.Dataset
        Dims ``(record, *grid axes, sample)`` and coordinates as in the study's dataset:
        ``linear_disp_left``, ``linear_disp_right`` [m] (peak linear displacements),
        ``rho`` [-], ``gap_abs``, ``gap_srss``, ``gap_ddc`` [m].  Summaries over records and
        samples (e.g. ``ds.gap_abs.mean(("record", "sample"))``) are what a chart of
        pounding probability against ``contact_gap_m`` marks.
    """
    engine = engine_of(study_or_dataset, base_dir=base_dir) if engine is None else engine
    study = engine.study
    p = engine.parameters(np.arange(study.n_simulations))
    lacking = [side for side in ("left", "right") if f"{side}.period_s" not in p]
    if lacking:
        raise RulesDoNotApply(
            "does not apply: the separation rules compare the linear responses of two SDOF "
            f"buildings; the {' and '.join(lacking)} building of study {study.name!r} is not one",
            key=f"{lacking[0]}.model",
        )
    u1 = _linear_peaks(
        engine.records, p["record"], p["left.period_s"], p["left.damping_ratio"], substeps
    )
    u2 = _linear_peaks(
        engine.records, p["record"], p["right.period_s"], p["right.damping_ratio"], substeps
    )
    if engine.scale_factors is not None:  # linear peaks scale with the record
        idx = np.unravel_index(np.arange(study.n_simulations), study.shape)
        factor = engine.scale_factors[p["record"], idx[list(study.grid).index(
            engine.intensity_key) + 1]]  # fmt: skip
        u1, u2 = u1 * factor, u2 * factor
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
