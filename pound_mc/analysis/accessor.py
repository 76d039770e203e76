"""The ``pound`` accessor of :class:`xarray.Dataset`: study results one call away.

Registered on ``import pound_mc``::

    import xarray as xr
    import pound_mc

    ds = xr.open_dataset("outputs/quickstart.nc")
    ds.pound.spectrum(contact_gap_m=0.01)      # quantiles of peak force over samples [N]
    ds.pound.probability()                     # fraction of samples with an impact [-]
    ds.pound.fragility(im="sa_g")              # lognormal fragility per other grid axis
    ds.pound.required_gap(probability=0.1)     # gap for a target probability, and the rules
    ds.pound.sensitivity(output="peak_force")  # Sobol' S1 and ST (saltelli studies)
    ds.pound.plot.spectrum(ax=ax)              # draws on ax, returns the Axes
    ds.pound.plot.spectrum_panels()            # a panel per material (jankowski_spectrum)
    ds.pound.worst("peak_force")               # the simulation with the largest peak force
    ds.pound.to_dataframe()                    # one row per simulation
    ds.pound.plot.history(left_period_s=0.5, contact_gap_m=0.01, sample=3)

Selections (``**sel``) take a dimension and a value; numeric coordinates pick the nearest value,
so ``left_period_s=0.3`` works although the stored value is ``0.30000000000000004``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd
import xarray as xr

from pound_mc.errors import InputError

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from pound_mc.scene import Scene, SimulationResult

# ``import pound_mc`` registers this accessor, and ``pound-mc --help`` imports ``pound_mc``: so
# this module loads xarray alone, and each method imports the charts (matplotlib), the
# analysis (scipy) and the scenes and studies (numba) it uses when it is first called.

__all__ = ["PoundAccessor", "PoundPlot", "scene_at"]

_OK = 0


def _select(obj, ds: xr.Dataset, sel: dict):
    """``obj.sel(sel)``, nearest for numeric coordinates, exact otherwise.

    ``sel`` may name a dimension by its study key and a material by name
    (:func:`~pound_mc.analysis.selection.selection`).
    """
    from pound_mc.analysis.selection import MATERIAL_DIM, selection

    sel = selection(ds, sel)
    unknown = sorted(set(sel) - set(ds.dims))
    if unknown:
        raise ValueError(f"no dimension {unknown[0]!r}; the dataset has {list(ds.dims)}")
    # nearest for numeric axes; the material axis (numbers standing for names) exactly
    numeric = {k: v for k, v in sel.items() if ds[k].dtype.kind in "fiu" and k != MATERIAL_DIM}
    other = {k: v for k, v in sel.items() if k not in numeric}
    if numeric:
        obj = obj.sel(numeric, method="nearest")
    if other:
        obj = obj.sel(other)
    return obj


def _position(ds: xr.Dataset, dim: str, value) -> int:
    """Position along ``dim`` of ``value``: the nearest for numbers, the equal one otherwise."""
    from pound_mc.analysis.selection import MATERIAL_DIM, no_value_message

    method = "nearest" if ds[dim].dtype.kind in "fiu" and dim != MATERIAL_DIM else None
    i = int(ds.indexes[dim].get_indexer([value], method=method)[0])
    if i < 0:
        raise ValueError(no_value_message(dim, value, ds[dim].values))
    return i


def scene_at(
    ds: xr.Dataset,
    *,
    record: int | str = 0,
    sample: int = 0,
    study_path: str | Path | None = None,
    **coords: Any,
) -> tuple[Scene, tuple[float, np.ndarray], dict[str, int]]:
    """Rebuild the scene of one simulation of a study dataset.

    The study is rebuilt from the dataset's ``study_text`` (its records read again) and the
    scene is :meth:`~pound_mc.study.engine.StudyEngine.scene_of` the simulation at the given
    coordinates (nearest) and ``sample`` (the study's sampling is deterministic), holding the
    record as the study ran it (:meth:`~pound_mc.scene.Scene.hold_record`: scaled to the
    intensity where the study has an intensity axis), so :func:`pound_mc.scene.simulate`
    reproduces the dataset's numbers for that simulation.

    Parameters
    ----------
    ds : xarray.Dataset
        A study dataset (:mod:`pound_mc.study.dataset`).
    record : int or str
        Record index or name.
    sample : int
        Sample index.
    study_path : str or Path, optional
        Where the study file was, for records given by a relative path (default: the folder
        the dataset says it ran from, ``study_dir``, else the current folder).
    **coords
        One value per grid dimension (default: its first value).

    Returns
    -------
    scene : pound_mc.scene.Scene
    record_arrays : tuple
        ``(dt_s, acceleration)`` of the record, as the study engine ran it (scaled to the
        simulation's intensity where the study has an intensity axis).
    index : dict
        The integer position of the simulation along every dimension of ``peak_force``.
    """
    from pound_mc.analysis.selection import selection
    from pound_mc.study.dataset import study_file
    from pound_mc.study.definition import grid_dim_name, study_from_text
    from pound_mc.study.engine import StudyEngine

    if study_path is None:
        study_path = study_file(ds)  # in the study's own folder: its relative records
    text = ds.attrs.get("study_text")
    if not text:
        raise InputError("the dataset carries no study_text attribute; is it a pound-mc result?")
    study = study_from_text(text, file=study_path)
    if study.hash != ds.attrs.get("study_hash", study.hash):
        raise InputError("the dataset's study_text does not match its study_hash")
    coords = selection(ds, coords)
    unknown = sorted(set(coords) - {grid_dim_name(k) for k in study.grid})
    if unknown:
        raise ValueError(f"{unknown[0]!r} is not a grid dimension of this study")
    r = record if isinstance(record, int | np.integer) else _position(ds, "record", record)
    if not 0 <= int(r) < ds.sizes["record"]:
        raise ValueError(f"record must be in 0..{ds.sizes['record'] - 1}, got {record}")
    if not 0 <= int(sample) < study.n:
        raise ValueError(f"sample must be in 0..{study.n - 1}, got {sample}")
    index = {"record": int(r)}
    for key in study.grid:
        dim = grid_dim_name(key)
        index[dim] = _position(ds, dim, coords[dim]) if dim in coords else 0
    index["sample"] = int(sample)
    engine = StudyEngine(study)
    flat = int(np.ravel_multi_index(tuple(index.values()), study.shape))
    scene, rec = engine.scene_of(flat), engine.record_of(flat)
    scene.hold_record(rec)
    return scene, rec, index


def _axes_of(fig, ax):
    """What a plot method returns: the Axes it drew on (one), or an array of them (panels).

    Those given, or the new figure's less its colour bars; either less the spare ones a chart
    hid (the last row of a panel grid).
    """
    from matplotlib.axes import Axes

    if ax is not None:
        axes = np.asarray([ax] if isinstance(ax, Axes) else list(ax), dtype=object).ravel()
    else:
        axes = [a for a in fig.axes if a.get_label() != "<colorbar>"]
    axes = np.asarray([a for a in axes if a.get_visible()], dtype=object)
    return axes[0] if axes.size == 1 else axes


def _chart(name: str) -> Callable:
    """The chart function ``name`` of the analysis modules, imported now (matplotlib with it)."""
    from pound_mc.analysis import (
        distribution_chart,
        plot,
        profiles,
        risk_chart,
        sensitivity_chart,
    )

    charts = {
        "sensitivity_chart": sensitivity_chart.sensitivity_chart,
        "spectrum_chart": plot.spectrum_chart,
        "spectrum_panels": plot.spectrum_panels,
        "probability_chart": plot.probability_chart,
        "distribution_chart": distribution_chart.distribution_chart,
        "fragility_panels": risk_chart.fragility_panels,
        "required_gap_chart": risk_chart.required_gap_chart,
        "contacts_chart": profiles.contacts_chart,
        "profile_chart": profiles.profile_chart,
    }
    return charts[name]


def _chart_method(name: str, chart: str, returns: str, doc: str, **fixed: Any) -> Callable:
    """A :class:`PoundPlot` method ``name`` that draws the chart named ``chart`` of the dataset.

    The method takes ``path``, ``ax`` and the chart's keywords (``fixed`` ones given here), and
    returns what :func:`_axes_of` gives; ``returns`` is its return annotation, ``doc`` its
    docstring.  The chart's module is imported at the first call (:func:`_chart`).
    """

    def method(self, path: str | Path | None = None, *, ax: Axes | None = None, **kwargs: Any):
        from pound_mc.analysis.selection import dim_name, selection
        from pound_mc.analysis.style import pyplot_figures

        ds = self._ds
        if kwargs.get("sel"):  # study keys and material names, as --sel takes them
            kwargs["sel"] = selection(ds, kwargs["sel"])
        for option in ("line", "by", "x"):  # a dimension, or its study key
            if isinstance(kwargs.get(option), str):
                kwargs[option] = dim_name(ds, kwargs[option])
        with pyplot_figures(path is None, unless_set=True):
            return _axes_of(_chart(chart)(ds, path, ax=ax, **fixed, **kwargs), ax)

    method.__name__ = name
    method.__qualname__ = f"PoundPlot.{name}"
    method.__doc__ = doc
    method.__annotations__["return"] = returns
    return method


class PoundPlot:
    """Charts of a study dataset (``ds.pound.plot``), in the manner of xarray's ``ds.plot``.

    Each method draws on ``ax`` (a new figure's when not given; a sequence of Axes for the
    charts with several panels), writes a PNG when given ``path``, and returns the Axes it drew
    on: one :class:`matplotlib.axes.Axes`, or a numpy array of them for several panels.  The
    figure is ``ax.figure``.  Without ``ax`` and ``path`` the new figure is pyplot's, as with
    xarray's ``ds.plot``: a notebook shows it and ``plt.show()`` or ``plt.savefig()`` take it;
    with ``path`` it is written to the file and left out of pyplot (no figures pile up in a
    script that writes many).
    """

    def __init__(self, ds: xr.Dataset):
        self._ds = ds

    spectrum = _chart_method(
        "spectrum",
        "spectrum_chart",
        "Axes",
        """Impact force spectrum (:func:`pound_mc.analysis.plot.spectrum_chart`).

        ``record="pooled"`` (default: every record and sample together), ``"median"`` (the
        median over records of each record's quantiles), ``"each"`` (a line per record) or one
        record's index or name.  Grid axes other than ``x`` and ``line`` are held at their
        first value (the title names it); :meth:`spectrum_panels` draws a panel per material.
        """,
    )
    spectrum_panels = _chart_method(
        "spectrum_panels",
        "spectrum_panels",
        "np.ndarray",
        """Impact force spectrum with a panel per material (``plot.spectrum_panels``).

        What ``pound-mc run`` and ``pound-mc report`` draw: where the spectrum chart would hold
        the material axis (``studies/jankowski_spectrum.toml``), one panel per material (``by``:
        another grid axis), returned as an array of Axes; otherwise the one chart of
        :meth:`spectrum` and its Axes.
        """,
    )
    probability = _chart_method(
        "probability",
        "probability_chart",
        "Axes",
        "Pounding probability against gap (:func:`pound_mc.analysis.plot.probability_chart`).",
    )

    fragility = _chart_method(
        "fragility",
        "fragility_panels",
        "np.ndarray",
        """Fragility panels (:func:`pound_mc.analysis.risk_chart.fragility_panels`).

        One panel per combination of the other grid axes: ``ax`` is a sequence of as many
        Axes; one panel returns its Axes.
        """,
    )

    sensitivity = _chart_method(
        "sensitivity",
        "sensitivity_chart",
        "np.ndarray",
        """Sobol' indices as bars (:func:`pound_mc.analysis.sensitivity_chart.sensitivity_chart`).

        S1 and ST of every sampled key with their intervals, a panel per value of ``by``
        (default the first grid axis, at most six); ``output`` as :meth:`PoundAccessor.sensitivity`.
        """,
    )

    required_gap = _chart_method(
        "required_gap",
        "required_gap_chart",
        "Axes",
        "Probability against gap with the required gap marked (``required_gap_chart``).",
    )
    distribution = _chart_method(
        "distribution",
        "distribution_chart",
        "np.ndarray",
        """Peak force distribution (``distribution_chart.distribution_chart``).

        Two panels: ``ax`` is a sequence of two Axes (box plot, histograms); a group of boxes
        per intensity where the study has an intensity axis.
        """,
    )
    contacts = _chart_method(
        "contacts",
        "contacts_chart",
        "Axes",
        "Peak force at each contact (:func:`pound_mc.analysis.profiles.contacts_chart`).",
    )
    drift = _chart_method(
        "drift",
        "profile_chart",
        "np.ndarray",
        "Peak storey drift profiles (:func:`pound_mc.analysis.profiles.profile_chart`).",
        quantity="drift",
    )
    ductility = _chart_method(
        "ductility",
        "profile_chart",
        "np.ndarray",
        "Peak ductility profiles (:func:`pound_mc.analysis.profiles.profile_chart`).",
        quantity="ductility",
    )

    def restitution(
        self, path: str | Path | None = None, *, ax: Axes | None = None, **kwargs: Any
    ) -> Axes:
        """Restitution relations with the study's sampled ``e`` and ``e_effective`` marked."""
        from pound_mc.analysis.physics_charts import restitution_chart
        from pound_mc.analysis.style import pyplot_figures

        ds = self._ds
        samples = None
        if "e" in ds and "e_effective" in ds:
            e, e_eff = xr.broadcast(ds["e"], ds["e_effective"])
            law = ds.attrs.get("contact_model", "contact")
            relation = ds.attrs.get("xi_relation", "")
            samples = (e.values, e_eff.values, f"study: {law} law, {relation} ({e.size} values)")
        with pyplot_figures(path is None, unless_set=True):
            return _axes_of(restitution_chart(path, samples=samples, ax=ax, **kwargs), ax)

    def history(
        self,
        path: str | Path | None = None,
        *,
        ax: Sequence[Axes] | None = None,
        record: int | str = 0,
        sample: int = 0,
        study_path: str | Path | None = None,
        **coords: Any,
    ) -> np.ndarray:
        """Time history of one simulation of the study, rebuilt and run again.

        See :func:`scene_at` for the arguments; three panels (displacements, penetration,
        force); the figure's title names the simulation.
        """
        from pound_mc.analysis.labels import coord_text, text_of
        from pound_mc.analysis.plot import save
        from pound_mc.analysis.plot_numerics import time_history_chart
        from pound_mc.analysis.style import pyplot_figures

        result, index = self._ds.pound.simulate(
            record=record, sample=sample, study_path=study_path, **coords
        )
        with pyplot_figures(path is None, unless_set=True):
            fig = time_history_chart(result, ax=ax)
        names = {"record": lambda i: f"record {text_of(self._ds['record'].values[i])}"}
        names["sample"] = lambda i: f"sample {i}"
        where = ", ".join(
            names[d](i) if d in names else coord_text(self._ds, d, i) for d, i in index.items()
        )
        fig.suptitle(f"{self._ds.attrs.get('study_name', '')}: {where}", fontsize=9)
        save(fig, path)
        return _axes_of(fig, ax)


@xr.register_dataset_accessor("pound")
class PoundAccessor:
    """Analysis of a pound-mc study dataset: ``ds.pound``."""

    def __init__(self, ds: xr.Dataset):
        self._ds = ds

    @property
    def plot(self) -> PoundPlot:
        """Charts: ``ds.pound.plot.spectrum()``, ``.probability()``, ``.distribution()``, ..."""
        return PoundPlot(self._ds)

    @property
    def ok(self) -> xr.DataArray:
        """True where the simulation finished with status ok."""
        return self._ds["status"] == _OK

    @property
    def grid_dims(self) -> list[str]:
        """Grid dimensions of the study (``peak_force``'s dims less record and sample)."""
        return [d for d in self._ds["peak_force"].dims if d not in ("record", "sample")]

    def spectrum(
        self,
        quantiles: float | Sequence[float] = (0.05, 0.5, 0.95),
        *,
        variable: str = "peak_force",
        pooled: bool = False,
        **sel: Any,
    ) -> xr.DataArray:
        """Quantiles of a result over the samples (status ok): the impact force spectrum.

        Parameters
        ----------
        quantiles : sequence of float
            Quantile levels in [0, 1].
        variable : str
            Per-simulation result (default ``peak_force`` [N]).
        pooled : bool
            Over the records and samples together (what the spectrum chart draws by default)
            instead of each record's samples.
        **sel
            ``dim=value`` selections (nearest for numeric coordinates).

        Returns
        -------
        xarray.DataArray
            Dims ``quantile`` and the dims left after the selection, less ``sample`` (and
            ``record`` when pooled); the variable's units; NaN where no run ended ok.
        """
        from pound_mc.analysis.plot import quantiles_over

        ds = self._ds
        values = ds[variable].where(self.ok)
        values = _select(values, ds, sel)
        over = [d for d in (("record", "sample") if pooled else ("sample",)) if d in values.dims]
        q = quantiles_over(values, quantiles, over)
        q.attrs = {
            "units": ds[variable].attrs.get("units", "1"),
            "long_name": f"quantiles over {' and '.join(d + 's' for d in over)} of "
            f"{ds[variable].attrs.get('long_name', '')}",
        }
        return q.rename(f"{variable}_quantile")

    def probability(self, threshold: float | None = None, **sel: Any) -> xr.DataArray:
        """Fraction of the samples (status ok or inaccurate) that pounded.

        Parameters
        ----------
        threshold : float, optional
            Count only impacts with a peak force above this [N] (default: any impact).
        **sel
            ``dim=value`` selections (nearest for numeric coordinates).

        Returns
        -------
        xarray.DataArray
            Pounding probability [-] over the dims left, less ``sample``.
        """
        from pound_mc.analysis.risk import counted

        ds = self._ds
        pounded = ds["impacts"] > 0
        if threshold is not None:
            pounded = pounded & (ds["peak_force"] > threshold)
        # any impact: the runs flagged inaccurate count too (their impacts stand); above a
        # force: status ok only (risk.counted)
        event = "pounding" if threshold is None else "peak_force"
        p = _select(pounded.where(counted(ds, event)), ds, sel).mean("sample")
        more = "" if threshold is None else f" and a peak force above {threshold:g} N"
        p.attrs = {"units": "1", "long_name": f"fraction of samples with an impact{more}"}
        return p.rename("pounding_probability")

    def fragility(
        self, im: str | None = None, event: str = "pounding", **kwargs: Any
    ) -> xr.Dataset:
        """Lognormal fragility per combination of the other grid axes.

        See :func:`pound_mc.analysis.risk.fragility`: ``theta``, ``beta``, ``theta_ci``,
        ``beta_ci`` along the remaining axes (``event``: ``"pounding"``, ``"peak_force>N"``,
        ``"ductility>X"``).
        """
        from pound_mc.analysis.risk import fragility

        return fragility(self._ds, im, event, **kwargs)

    def required_gap(self, probability: float = 0.1, **kwargs) -> xr.Dataset:
        """Smallest gap with pounding probability at or below ``probability``, with the rules.

        See :func:`pound_mc.analysis.risk.required_gap`.
        """
        from pound_mc.analysis.risk import required_gap

        return required_gap(self._ds, probability, **kwargs)

    def risk(self, hazard, **kwargs: Any) -> xr.Dataset:
        """Mean annual rate of an event per gap at a site, and the gap that meets a target.

        ``hazard``: a :class:`~pound_mc.analysis.hazard.HazardCurve`, the path of a hazard
        CSV file (columns ``im`` [g], ``annual_rate``) or ``(k0, k)`` of ``k0 im^-k``; the
        keywords are :func:`pound_mc.analysis.site_risk.risk`'s (``event``, ``method``,
        ``target_rate`` or ``target_probability`` with ``years``, ...).
        """
        from pound_mc.analysis.hazard import HazardCurve, power_law, read_hazard
        from pound_mc.analysis.site_risk import risk as site_risk

        if isinstance(hazard, tuple):
            hazard = power_law(*hazard)
        elif not isinstance(hazard, HazardCurve):
            hazard = read_hazard(hazard)
        return site_risk(self._ds, hazard, **kwargs)

    def code_gaps(self, **kwargs: Any) -> xr.Dataset:
        """The rules' and codes' gaps of the study's buildings, and how often runs pound there.

        See :func:`pound_mc.analysis.site_risk.code_gaps` (``asce=(R, Cd, Ie)``,
        ``ec8=(q, qd, same_levels)``); every run is simulated again at each rule's gap.
        """
        from pound_mc.analysis.site_risk import code_gaps

        return code_gaps(self._ds, **kwargs)

    def sensitivity(self, output: str = "peak_force", **kwargs) -> xr.Dataset:
        """Sobol' first- and total-order indices of ``output`` (a ``saltelli`` study).

        See :func:`pound_mc.analysis.sensitivity.sensitivity`: ``S1``, ``ST``, ``S1_ci``,
        ``ST_ci`` [1] along ``record``, the grid axes and ``variable`` (the sampled study keys),
        with ``n_used``, ``n_left_out`` and ``message``.  ``output``: ``"peak_force"``,
        ``"pounding"``, ``"ductility"`` or a per-simulation variable.
        """
        from pound_mc.analysis.sensitivity import sensitivity

        return sensitivity(self._ds, output, **kwargs)

    def status_counts(self) -> pd.Series:
        """Number of simulations per status (the dataset's ``status`` flags).

        Index ``ok``, ``unstable``, ``not_converged``, ``inaccurate``.
        """
        status = self._ds["status"]
        values = np.asarray(status.attrs.get("flag_values", [0, 1, 2])).tolist()
        names = str(status.attrs.get("flag_meanings", "ok unstable not_converged")).split()
        data = status.values
        counts = [int(np.count_nonzero(data == v)) for v in values]
        return pd.Series(counts, index=pd.Index(names, name="status"), name="simulations")

    def energy_summary(self) -> pd.Series:
        """Magnitude of the energy balance residual [-] over the simulations with status ok.

        Returns
        -------
        pandas.Series
            ``median``, ``p95``, ``max`` of ``|energy_residual|`` and ``n`` (simulations).
        """
        r = np.abs(self._ds["energy_residual"].where(self.ok).values)
        r = r[np.isfinite(r)]
        if not r.size:
            values = [np.nan, np.nan, np.nan, 0]
        else:
            values = [float(np.median(r)), float(np.quantile(r, 0.95)), float(r.max()), r.size]
        index = ["median", "p95", "max", "n"]
        return pd.Series(values, index=index, dtype=object, name="energy_residual")

    def per_simulation(self) -> list[str]:
        """Variables with one value per simulation, per sample or per record (not summaries).

        Per record: the record's own variables (:data:`~pound_mc.study.dataset.RECORD_VARIABLES`,
        ``scale_factor`` per record and intensity), not the summaries over its samples.
        """
        from pound_mc.study.dataset import RECORD_VARIABLES

        dims = set(self._ds["peak_force"].dims)
        return [
            name
            for name, var in self._ds.data_vars.items()
            if var.dims
            and set(var.dims) <= dims
            and ("sample" in var.dims or name in RECORD_VARIABLES)
            and var.dtype.kind in "fiub"
        ]

    def to_dataframe(self) -> pd.DataFrame:
        """One row per simulation: its coordinates and every per-simulation result.

        Returns
        -------
        pandas.DataFrame
            Columns ``record``, the grid dims, ``sample`` (``material`` names on a material
            axis), then :meth:`per_simulation`'s variables in the dataset's units.
        """
        ds = self._ds
        dims = list(ds["peak_force"].dims)
        names = self.per_simulation()
        table = ds[names].to_dataframe(dim_order=dims)
        keep = [n for n in names if n in table]
        table = table[keep].reset_index()
        if "material" in ds and ds["material"].dims == ("contact_material",):
            names_of = dict(zip(ds["contact_material"].values, ds["material"].values, strict=True))
            table.insert(
                dims.index("contact_material") + 1,
                "material",
                table["contact_material"].map(names_of),
            )
        return table

    def worst_index(self, variable: str = "peak_force") -> dict[str, int]:
        """Position of the simulation (status ok) with the largest ``variable``, by dim."""
        values = self._ds[variable].where(self.ok)
        extra = [d for d in values.dims if d not in self._ds["peak_force"].dims]
        if extra:  # per-contact or per-storey results: the largest over those
            values = values.max(extra)
        data = values.transpose(*self._ds["peak_force"].dims).values
        if not np.isfinite(data).any():
            raise ValueError(f"no simulation with status ok has a finite {variable}")
        flat = int(np.nanargmax(data))
        dims = self._ds["peak_force"].dims
        return {d: int(i) for d, i in zip(dims, np.unravel_index(flat, data.shape), strict=True)}

    def worst(
        self,
        variable: str = "peak_force",
        *,
        rerun: bool = False,
        study_path: str | Path | None = None,
    ) -> xr.Dataset | tuple[xr.Dataset, SimulationResult]:
        """The simulation (status ok) with the largest ``variable``; optionally run again.

        Parameters
        ----------
        variable : str
            A per-simulation result (default ``peak_force``); per-contact or per-storey results
            take their largest value.
        rerun : bool
            Also run the simulation again with its time histories (:meth:`simulate`).
        study_path : str or Path, optional
            Where the study file was, for records given by a relative path.

        Returns
        -------
        xarray.Dataset or tuple
            The dataset at that simulation (``ds.isel``: every variable there, coordinates as
            scalars); with ``rerun``, ``(selection, result)`` with the
            :class:`~pound_mc.scene.SimulationResult`.
        """
        index = self.worst_index(variable)
        selection = self._ds.isel(index)
        if not rerun:
            return selection
        coords = {
            d: self._ds[d].values[i] for d, i in index.items() if d not in ("record", "sample")
        }
        result, _ = self.simulate(
            record=index["record"], sample=index["sample"], study_path=study_path, **coords
        )
        return selection, result

    def scene(
        self,
        *,
        record: int | str = 0,
        sample: int = 0,
        study_path: str | Path | None = None,
        **coords: Any,
    ) -> Scene:
        """The scene of one simulation (see :func:`scene_at`)."""
        return scene_at(self._ds, record=record, sample=sample, study_path=study_path, **coords)[0]

    def simulate(
        self,
        *,
        record: int | str = 0,
        sample: int = 0,
        history: bool = True,
        study_path: str | Path | None = None,
        **coords: Any,
    ) -> tuple[SimulationResult, dict[str, int]]:
        """Run one simulation of the study again, with its histories.

        Returns
        -------
        result : pound_mc.scene.SimulationResult
        index : dict
            Integer position of the simulation along every dimension of ``peak_force``
            (``ds.peak_force[index]`` is the stored result).
        """
        from pound_mc.scene import simulate

        scene, rec, index = scene_at(
            self._ds, record=record, sample=sample, study_path=study_path, **coords
        )
        return simulate(scene, record=rec, history=history), index
