"""``pound-mc risk`` and ``pound-mc required-gap``: the gap a site needs, beside the codes'."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from pound_mc.analysis.gaps import RulesDoNotApply
from pound_mc.analysis.risk import left_out_why
from pound_mc.analysis.risk import required_gap as probability_gap
from pound_mc.analysis.site_chart import risk_chart
from pound_mc.analysis.site_risk import code_gaps, site_assessment
from pound_mc.cli.analysis import _jsonable, _open_dataset, _where, codes_of, hazard_of
from pound_mc.errors import InputError


def _named(exc: InputError, path: Path) -> InputError:
    return InputError(exc.message, file=exc.file or str(path), key=exc.key)


def risk_command(args) -> int:
    """``pound-mc risk``: annual rate per gap, the risk-targeted gap, the code gaps."""
    path = Path(args.file)
    if args.n_boot < 0:
        raise InputError(f"must be >= 0, got {args.n_boot}", key="--n-boot")
    hazard = hazard_of(args)
    codes = codes_of(args)
    with _open_dataset(path) as ds:
        ds.load()
        try:
            out, gaps = site_assessment(ds, hazard, codes, im=args.im, event=args.event,
                                        method=args.method, target_rate=args.target_rate,
                                        target_probability=args.target_probability,
                                        years=args.years, n_boot=args.n_boot)  # fmt: skip
        except InputError as exc:
            raise _named(exc, path) from None
    rest = list(out["annual_rate"].dims)
    info = {
        "im": out.attrs["im"],
        "im_units": "g",
        "event": out.attrs["event"],
        "method": out.attrs["method"],
        "hazard": out.attrs["hazard"],
        "dims": rest,
        "coords": {d: np.asarray(out[d].values).tolist() for d in rest},
        "annual_rate": _jsonable(out["annual_rate"].values),
        "annual_rate_ci": _jsonable(out["annual_rate_ci"].values),
        "rate_message": np.asarray(out["rate_message"].values, dtype=object).tolist(),
        "target_rate": None if math.isnan(out.attrs["target_rate"]) else out.attrs["target_rate"],
        "years": None if math.isnan(out.attrs["years"]) else out.attrs["years"],
        "extrapolation": out.attrs["extrapolation"],
        "n_left_out": int(out["n_left_out"].sum()),
    }
    if "probability" in out:
        info["probability"] = _jsonable(out["probability"].values)
    if "required_gap" in out:
        info["required_gap_m"] = _jsonable(out["required_gap"].values)
        info["required_gap_ci"] = _jsonable(out["required_gap_ci"].values)
        info["gap_message"] = np.asarray(out["gap_message"].values, dtype=object).tolist()
    if gaps is not None:
        info["code_gaps_m"] = {str(r): _jsonable(gaps["code_gap"].sel(rule=r).values)
                               for r in gaps["rule"].values}  # fmt: skip
        info["code_gap_exceedance"] = {str(r): _jsonable(gaps["code_gap_exceedance"]
                                                         .sel(rule=r).values)
                                       for r in gaps["rule"].values}  # fmt: skip
        info["design_im"] = {k: float(v) for k, v in gaps.attrs["design_im"].items()}
    if args.plot:
        risk_chart(out, args.plot, code=gaps)
    if args.json:
        print(json.dumps(info, indent=1))
        return 0
    _print_risk(path, out, gaps)
    if args.plot:
        print(f"wrote {args.plot}")
    return 0


def _value(out, dim: str, i: int) -> str:
    """``"gap 20 mm"`` (a gap in mm) or ``"name value"``, as people write them."""
    return _where(out, dim, float(out[dim].values[i]))


def _print_risk(path: Path, out, gaps) -> None:
    target = out.attrs["target_rate"]
    print(f"annual rate of {out.attrs['event']} at the site ({path.name}); hazard "
          f"{out.attrs['hazard']}, {out.attrs['method']}, {round(100 * out.attrs['ci'])} % "
          "bootstrap intervals")  # fmt: skip
    n_used, n_out = int(out["n_total"].sum()), int(out["n_left_out"].sum())
    print(f"  {n_used:,} simulations counted, "
          + (f"{n_out:,} left out ({left_out_why(out.attrs['event'])})" if n_out else
             "none left out"))  # fmt: skip
    if out.attrs["extrapolation"]:
        print(f"  note: {out.attrs['extrapolation']}")
    rates = out["annual_rate"]
    for index in np.ndindex(rates.shape):
        where = ", ".join(_value(out, d, i) for d, i in zip(rates.dims, index, strict=True))
        msg = out["rate_message"].values[index]
        lo, hi = out["annual_rate_ci"].values[index]
        text = f"no rate ({msg})" if msg else f"{rates.values[index]:.4g}/year [{lo:.3g}, {hi:.3g}]"
        if "probability" in out and not msg:
            text += (
                f", {100 * out['probability'].values[index]:.3g} % in {out.attrs['years']:g} years"
            )
        print(f"  {where or 'all'}: {text}")
    if "required_gap" in out:
        gap = out["required_gap"]
        for index in np.ndindex(gap.shape):
            msg = out["gap_message"].values[index]
            lo, hi = out["required_gap_ci"].values[index]
            head = f"  gap for {target:.3g}/year"
            head += "".join(f", {_value(out, d, i)}" for d, i in zip(gap.dims, index, strict=True))
            found = f"{1e3 * gap.values[index]:.1f} mm [{1e3 * lo:.1f}, {1e3 * hi:.1f}]"
            print(head + (f": none ({msg})" if msg else f": {found}"))
    if gaps is not None:
        print("  rules and codes at their design intensity (runs pounding at their own gap):")
        for rule in gaps["rule"].values:
            g = gaps.sel(rule=rule)
            level = gaps.attrs["design_im"][str(rule)]
            print(f"    {rule:<9} {1e3 * float(g['code_gap'].mean()):7.1f} mm at "
                  f"{out.attrs['im']} = {level:.3g} g; "
                  f"{100 * float(g['code_gap_exceedance'].mean()):.0f} % pound")  # fmt: skip


def required_gap_command(args) -> int:
    """``pound-mc required-gap``: the gap for a pounding probability, per intensity, in mm."""
    path = Path(args.file)
    if not 0 < args.probability < 1:
        raise InputError(f"must be in (0, 1), got {args.probability!r}", key="--probability")
    codes = codes_of(args)
    with _open_dataset(path) as ds:
        ds.load()
        try:
            out = probability_gap(ds, args.probability, rules=False)
        except InputError as exc:
            raise _named(exc, path) from None
        try:
            if not ds.attrs.get("study_text"):  # a dataset without its study: no rules
                raise RulesDoNotApply("the dataset has no study_text")
            rules = code_gaps(ds, **codes)
        except RulesDoNotApply:
            rules = None  # shear buildings, a wall: the rules do not describe them
        except InputError as exc:
            raise _named(exc, path) from None
    rest = list(out["required_gap"].dims)
    info = {
        "probability": float(args.probability),
        "dims": rest,
        "coords": {d: np.asarray(out[d].values).tolist() for d in rest},
        "required_gap_m": _jsonable(out["required_gap"].values),
        "required_gap_ci": _jsonable(out["required_gap_ci"].values),
        "message": np.asarray(out["message"].values, dtype=object).tolist(),
        "n_left_out": int(out["n_left_out"].sum()),
        "rules_m": None if rules is None else {
            str(r): _jsonable(rules["code_gap"].sel(rule=r).transpose(*rest).values)
            for r in rules["rule"].values},
        "rules_exceedance": None if rules is None else {
            str(r): _jsonable(rules["code_gap_exceedance"].sel(rule=r).transpose(*rest).values)
            for r in rules["rule"].values},
    }  # fmt: skip
    if args.json:
        print(json.dumps(info, indent=1))
        return 0
    names = [] if rules is None else [str(r) for r in rules["rule"].values]
    print(
        f"gap for a pounding probability <= {args.probability:g} ({path.name}), mm; "
        "beside it each rule's median gap and how often runs pound at their own rule gap"
    )
    print(
        f"  {int(out['n_total'].sum()):,} simulations counted, "
        f"{int(out['n_left_out'].sum()):,} left out"
    )
    head = "  " + " ".join(f"{d:>12}" for d in rest) + f" {'gap':>8} {'interval':>17}"
    head += "".join(f" {n:>16}" for n in names)
    print(head)
    for index in np.ndindex(out["required_gap"].shape):
        cells = [f"{float(out[d][i]):>12g}" for d, i in zip(rest, index, strict=True)]
        msg = out["message"].values[index]
        gap = out["required_gap"].values[index]
        lo, hi = out["required_gap_ci"].values[index]
        found = f" {1e3 * gap:8.1f} [{1e3 * lo:6.1f}, {1e3 * hi:6.1f}]"
        line = "  " + " ".join(cells) + (f" {'none':>8} {'':>17}" if msg else found)
        for n in names:
            sel = rules.sel(rule=n).transpose(*rest)
            share = 100 * float(sel["code_gap_exceedance"].values[index])
            line += f" {1e3 * float(sel['code_gap'].values[index]):7.1f} ({share:3.0f} %)"
        print(line)
    notes = sorted({m for m in np.ravel(out["message"].values) if m})
    for m in notes:
        print(f"  none: {m}")
    return 0
