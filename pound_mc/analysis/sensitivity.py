"""Sobol' sensitivity indices of a study output (``ds.pound.sensitivity``).

A study run with ``[sampling] method = "saltelli"`` holds, at every record and grid point,
Saltelli's design of base N over its D sampled keys (:mod:`pound_mc.study.sampling`): N
blocks of D + 2 samples (A, A with column j from B for j = 1..D, B).  :func:`sensitivity`
hands each record's and grid point's output over those samples to SALib
(:func:`SALib.analyze.sobol.analyze`, ``calc_second_order=False``): the first-order index S1
(the share of the output's variance due to one key alone) and the total-order index ST (its
share with all its interactions) of every sampled key, estimated as Saltelli et al. (2010)
and Jansen (1999) do, each with a bootstrap confidence interval (SALib's: the index plus and
minus z times the standard deviation of its estimates over resampled base points).

Outputs (``output=``): ``"peak_force"`` (default), ``"pounding"`` (1 where a run had an
impact, else 0: the indices of the pounding probability), ``"ductility"`` (the larger peak
ductility of the buildings; refused where they are elastic) or any per-simulation variable of
the dataset (``impacts``, ``max_penetration``, ``peak_disp_left``, ...).

Runs left out.  The estimator needs every sample of a block: a run whose value is in doubt
(status unstable or not converged, and ``inaccurate`` for every output but ``pounding``, as
:func:`pound_mc.analysis.risk.counted`; or a run without a value, NaN) takes its whole block
out, and the indices are estimated on the complete blocks alone.  They are then the
sensitivities over the part of the input space where the runs succeed, not over all of it, so
``n_left_out`` (every run of the incomplete blocks) is reported with them at every record and
grid point; a grid point with fewer than :data:`MIN_BLOCKS` complete blocks, or whose output
does not vary over them, has no indices (NaN) and says why in ``message``.
"""

from __future__ import annotations

import itertools
import warnings

import numpy as np
import xarray as xr
from SALib.analyze import sobol as salib_sobol

from pound_mc.errors import InputError
from pound_mc.study.dataset import pounding_counted

__all__ = ["MIN_BLOCKS", "OUTPUTS", "saltelli_design", "output_values", "sobol_indices",
           "sensitivity", "left_out_why"]  # fmt: skip

#: Fewest complete design blocks (base points) a grid point's indices are estimated from.
MIN_BLOCKS = 2
#: Outputs computed from the dataset's variables (any per-simulation variable is one too).
OUTPUTS = {
    "pounding": "1 where the run had at least one impact, else 0",
    "ductility": "larger peak ductility of the buildings (peak storey drift over yield drift)",
}
_DUCTILITY = ("peak_ductility_left", "peak_ductility_right")


def saltelli_design(ds: xr.Dataset) -> tuple[int, list[str]]:
    """Base N and sampled study keys (in the design's order) of a ``saltelli`` study dataset.

    Raises
    ------
    InputError
        The dataset was sampled with another design, or its attributes do not match its
        ``sample`` dimension.
    """
    method = ds.attrs.get("sampling_method")
    if method != "saltelli" or "saltelli_base_n" not in ds.attrs:
        raise InputError(
            "Sobol' indices need a study sampled with Saltelli's design ([sampling] method = "
            f'"saltelli", n a power of two); this dataset\'s method is {method!r}',
            key="sampling.method",
        )
    base_n = int(ds.attrs["saltelli_base_n"])
    keys = [k for k in str(ds.attrs.get("saltelli_variables", "")).split("; ") if k]
    d = int(ds.attrs.get("saltelli_n_variables", len(keys)))
    if len(keys) != d or ds.sizes.get("sample") != base_n * (d + 2):
        raise InputError(
            f"its Saltelli design (N = {base_n}, {d} keys: N (D + 2) = {base_n * (d + 2)} "
            f"samples) does not match its {ds.sizes.get('sample')} samples"
        )
    return base_n, keys


def output_values(ds: xr.Dataset, output: str = "peak_force") -> tuple[xr.DataArray, xr.DataArray]:
    """An output per simulation and where it counts (see the module docstring).

    Returns
    -------
    values : xarray.DataArray
        Float values with the dims of ``status``, ``units`` and ``long_name`` in its attributes.
    counted : xarray.DataArray
        True where the run's value stands (:func:`pound_mc.analysis.risk.counted`).

    Raises
    ------
    InputError
        An unknown output (naming those there are), or ``ductility`` of elastic buildings.
    """
    status = ds["status"]
    ok = status == 0
    if output == "pounding":
        values = (ds["impacts"] > 0).astype(float)
        return values.assign_attrs(units="1", long_name=OUTPUTS["pounding"]), pounding_counted(
            status
        )
    if output == "ductility":
        if "peak_ductility" in ds:
            values = ds["peak_ductility"].max("building", skipna=True)
        elif all(name in ds for name in _DUCTILITY):
            values = np.fmax(ds[_DUCTILITY[0]], ds[_DUCTILITY[1]])
        else:
            values = None
        if values is None or bool(values.where(ok).isnull().all()):
            raise InputError(
                "the output 'ductility' needs buildings that can yield; this dataset's are "
                "elastic (no peak ductility)",
                key="--output",
            )
        return values.assign_attrs(units="1", long_name=OUTPUTS["ductility"]), ok
    per_simulation = [
        name for name, var in ds.data_vars.items()
        if var.dims == status.dims and var.dtype.kind in "fiu" and name != "status"
    ]  # fmt: skip
    if output not in per_simulation:
        raise InputError(
            f"unknown output {output!r}; choose pounding, ductility or a per-simulation "
            f"variable: {', '.join(per_simulation)}",
            key="--output",
        )
    var = ds[output]
    attrs = {"units": var.attrs.get("units", "1"), "long_name": var.attrs.get("long_name", output)}
    return var.astype(float).assign_attrs(attrs), ok


def sobol_indices(
    y: np.ndarray, d: int, *, conf_level: float = 0.95, n_boot: int = 1000, seed: int = 0
) -> dict[str, np.ndarray]:
    """First- and total-order Sobol' indices of one output over Saltelli's design (SALib).

    Parameters
    ----------
    y : numpy.ndarray
        The output at the ``N (d + 2)`` samples of :func:`SALib.sample.sobol.sample`
        (``calc_second_order=False``), in its order.
    d : int
        Number of sampled variables.
    conf_level : float, default 0.95
        Level of the bootstrap intervals.
    n_boot : int, default 1000
        Bootstrap resamples of the base points.
    seed : int, default 0
        Seed of the resampling.

    Returns
    -------
    dict
        ``S1``, ``ST`` (``(d,)``) and ``S1_ci``, ``ST_ci`` (``(d, 2)``: lower, upper).
    """
    problem = {"num_vars": d, "names": [f"x{j}" for j in range(d)], "bounds": [[0.0, 1.0]] * d}
    rng = np.random.default_rng(np.random.SeedSequence(seed))  # SALib reseeds from it alone
    with warnings.catch_warnings():
        # a bootstrap resample whose A and B rows are all equal gives 0 for its estimate
        warnings.filterwarnings("ignore", "Constant values encountered", UserWarning)
        found = salib_sobol.analyze(
            problem,
            np.asarray(y, dtype=float),
            calc_second_order=False,
            num_resamples=n_boot,
            conf_level=conf_level,
            seed=rng,
        )
    out = {}
    for name in ("S1", "ST"):
        value, half = np.asarray(found[name]), np.asarray(found[f"{name}_conf"])
        out[name] = value
        out[f"{name}_ci"] = np.stack([value - half, value + half], axis=-1)
    return out


def left_out_why(output: str = "peak_force") -> str:
    """Which runs take their design block out of the estimate, in words."""
    statuses = "unstable or not converged"
    if output != "pounding":
        statuses = "unstable, not converged or inaccurate"
    return f"runs of design blocks with a run {statuses} or without a value"


def _indices_at(y, counted, base_n: int, d: int, **kwargs) -> tuple[dict | None, int, str]:
    """Indices over the complete blocks of one grid point, runs used and why none (or "")."""
    blocks = (np.asarray(counted, bool) & np.isfinite(y)).reshape(base_n, d + 2).all(axis=1)
    used = int(blocks.sum())
    if used < MIN_BLOCKS:
        why = f"{used} of {base_n} design blocks complete (every run counted), < {MIN_BLOCKS}"
        return None, used * (d + 2), why
    y = np.asarray(y, dtype=float).reshape(base_n, d + 2)[blocks]
    ends = y[:, [0, d + 1]]  # the A and B samples: the variance the indices divide
    if np.ptp(ends) == 0.0:
        why = f"the output is {ends.flat[0]:g} at every A and B sample: no variance to apportion"
        return None, used * (d + 2), why
    return sobol_indices(y.ravel(), d, **kwargs), used * (d + 2), ""


def sensitivity(
    ds: xr.Dataset,
    output: str = "peak_force",
    *,
    conf_level: float = 0.95,
    n_boot: int = 1000,
    seed: int = 0,
) -> xr.Dataset:
    """First- and total-order Sobol' indices of ``output`` at every record and grid point.

    Parameters
    ----------
    ds : xarray.Dataset
        A study dataset of a ``saltelli`` study (:func:`saltelli_design`).
    output : str, default "peak_force"
        ``"peak_force"``, ``"pounding"``, ``"ductility"`` or a per-simulation variable
        (:func:`output_values`).
    conf_level, n_boot, seed
        Level, resamples and seed of the bootstrap intervals (:func:`sobol_indices`); the same
        seed at every grid point.

    Returns
    -------
    xarray.Dataset
        Dims ``record``, the grid axes and ``variable`` (coordinate: the sampled study keys,
        ``contact.beta``): ``S1`` and ``ST`` [1], ``S1_ci`` and ``ST_ci`` [1] (with ``bound``:
        lower, upper); along ``record`` and the grid axes ``n_used`` and ``n_left_out`` (the
        runs of complete and of incomplete design blocks, see the module docstring) and
        ``message`` (why a grid point has no indices, "" where it has them); attributes
        ``output``, ``output_units``, ``output_long_name``, ``conf_level``, ``n_boot``,
        ``base_n``.
    """
    base_n, keys = saltelli_design(ds)
    d = len(keys)
    values, counted = output_values(ds, output)
    rest = [dim for dim in ds["status"].dims if dim != "sample"]
    y = values.transpose(*rest, "sample").values
    ok = counted.transpose(*rest, "sample").values
    shape = tuple(ds.sizes[dim] for dim in rest)
    arrays = {name: np.full((*shape, d), np.nan) for name in ("S1", "ST")}
    arrays |= {f"{name}_ci": np.full((*shape, d, 2), np.nan) for name in ("S1", "ST")}
    n_used = np.zeros(shape, dtype=np.int64)
    message = np.full(shape, "", dtype=object)
    options = {"conf_level": conf_level, "n_boot": n_boot, "seed": seed}
    for index in itertools.product(*(range(n) for n in shape)):
        found, n_used[index], message[index] = _indices_at(y[index], ok[index], base_n, d,
                                                           **options)  # fmt: skip
        for name, value in (found or {}).items():
            arrays[name][index] = value
    n_left_out = ds.sizes["sample"] - n_used
    level = f"bootstrap {conf_level:g} confidence interval"
    why = left_out_why(output)
    dims = (*rest, "variable")
    out = xr.Dataset(
        {
            "S1": (dims, arrays["S1"], {"units": "1", "long_name":
                   f"first-order Sobol' index of {output}"}),
            "S1_ci": ((*dims, "bound"), arrays["S1_ci"], {"units": "1", "long_name":
                      f"{level} of S1"}),
            "ST": (dims, arrays["ST"], {"units": "1", "long_name":
                   f"total-order Sobol' index of {output}"}),
            "ST_ci": ((*dims, "bound"), arrays["ST_ci"], {"units": "1", "long_name":
                      f"{level} of ST"}),
            "n_used": (rest, n_used, {"units": "1", "long_name":
                       "simulations of complete design blocks, used"}),
            "n_left_out": (rest, n_left_out, {"units": "1", "long_name":
                           f"simulations left out: {why}"}),
            "message": (rest, message, {"long_name": "why there are no indices"}),
        },
        coords={
            **{dim: ds[dim] for dim in rest},
            "variable": ("variable", np.asarray(keys, dtype=object),
                         {"long_name": "sampled study key"}),
            "bound": ("bound", np.asarray(["lower", "upper"], dtype=object),
                      {"long_name": "end of the confidence interval"}),
        },
        attrs={"output": output, "output_units": values.attrs["units"],
               "output_long_name": values.attrs["long_name"], "conf_level": float(conf_level),
               "n_boot": int(n_boot), "base_n": base_n},
    )  # fmt: skip
    return out
