"""``pound-mc sensitivity RESULT.nc [--output VAR] [--json] [--plot FILE.png]``.

Sobol' first- and total-order indices of a study output with respect to its sampled keys
(:func:`pound_mc.analysis.sensitivity.sensitivity`), for a study run with ``[sampling]
method = "saltelli"``.  ``--json`` prints one object: ``output``, ``variables`` (the study
keys), ``dims`` and ``coords`` (record and grid axes), ``S1``, ``S1_ci``, ``ST``, ``ST_ci``
(nested lists over ``dims`` then ``variables``; an interval is ``[lo, hi]``), ``n_left_out``
and ``n_used`` (over ``dims``), ``message``, ``base_n``, ``conf_level``, ``n_boot``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from pound_mc.analysis.sensitivity import left_out_why, sensitivity
from pound_mc.analysis.sensitivity_chart import sensitivity_chart
from pound_mc.analysis.style import output_path
from pound_mc.cli.analysis import _jsonable, _open_dataset
from pound_mc.errors import InputError

__all__ = ["sensitivity_command", "sensitivity_json"]


def sensitivity_json(found) -> dict:
    """The ``--json`` object of :func:`~pound_mc.analysis.sensitivity.sensitivity`'s dataset."""
    dims = [d for d in found["S1"].dims if d != "variable"]
    return {
        "output": found.attrs["output"],
        "output_units": found.attrs["output_units"],
        "variables": [str(k) for k in found["variable"].values],
        "dims": dims,
        "coords": {d: np.asarray(found[d].values).tolist() for d in dims},
        "S1": _jsonable(found["S1"].values),
        "S1_ci": _jsonable(found["S1_ci"].values),
        "ST": _jsonable(found["ST"].values),
        "ST_ci": _jsonable(found["ST_ci"].values),
        "n_left_out": np.asarray(found["n_left_out"].values).tolist(),
        "n_used": np.asarray(found["n_used"].values).tolist(),
        "message": np.asarray(found["message"].values, dtype=object).tolist(),
        "base_n": int(found.attrs["base_n"]),
        "conf_level": float(found.attrs["conf_level"]),
        "n_boot": int(found.attrs["n_boot"]),
    }


def _print_table(found, name: str) -> None:
    """The indices as text: a block per record and grid point."""
    out = sensitivity_json(found)
    keys = out["variables"]
    print(f"Sobol' indices of {out['output']} ({name}); N = {out['base_n']} base points, "
          f"{round(100 * out['conf_level'])} % bootstrap intervals")  # fmt: skip
    n_used, n_out = int(found["n_used"].sum()), int(found["n_left_out"].sum())
    left = f"{n_out:,} left out ({left_out_why(out['output'])})" if n_out else "none left out"
    print(f"  {n_used:,} simulations used, {left}")
    width = max(len(k) for k in keys)
    stacked = found.stack(point=out["dims"]) if out["dims"] else found.expand_dims(point=[0])
    for p in range(stacked.sizes["point"]):
        at = stacked.isel(point=p)
        where = ", ".join(f"{d} = {np.asarray(at[d].values).item()}" for d in out["dims"])
        print(f"  {where or 'all'}:")
        if str(at["message"].values):
            print(f"    no indices ({at['message'].values})")
            continue
        for j, key in enumerate(keys):
            s1, st = at["S1"].values[j], at["ST"].values[j]
            c1, ct = at["S1_ci"].values[j], at["ST_ci"].values[j]
            print(f"    {key:<{width}}  S1 = {s1:6.3f} [{c1[0]:6.3f}, {c1[1]:6.3f}]  "
                  f"ST = {st:6.3f} [{ct[0]:6.3f}, {ct[1]:6.3f}]")  # fmt: skip


def sensitivity_command(args) -> int:
    """``pound-mc sensitivity``: Sobol' indices of a ``saltelli`` study's output."""
    path = Path(args.file)
    if args.n_boot < 2:
        raise InputError(f"must be >= 2, got {args.n_boot}", key="--n-boot")
    if args.plot:
        output_path(args.plot, key="--plot", suffix=".png")  # before anything is computed
    ds = _open_dataset(path)
    with ds:
        ds.load()
        try:
            found = sensitivity(ds, args.output, n_boot=args.n_boot)
            if args.plot:
                sensitivity_chart(ds, args.plot, output=args.output, indices=found)
        except InputError as exc:
            raise InputError(exc.message, file=str(path), key=exc.key) from None
    if args.json:
        print(json.dumps(sensitivity_json(found), indent=1))
    else:
        _print_table(found, path.name)
    if args.plot and not args.json:
        print(f"wrote {args.plot}")
    return 0
