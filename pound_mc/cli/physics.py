"""Sub-commands about the impact physics: ``materials``, ``calibrate`` and ``droptest``.

Their arguments are declared in :mod:`pound_mc.cli.commands`.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from pound_mc.analysis.plot import droptest_chart, restitution_chart, restitution_ranges_chart
from pound_mc.analysis.style import output_path
from pound_mc.errors import InputError
from pound_mc.physics import materials
from pound_mc.physics.contact import CONTACT_MODELS, default_relation, reported_xi
from pound_mc.physics.droptest import drop_test
from pound_mc.physics.relations import (
    RELATIONS,
    effective_restitution,
    largest_xi,
    lowest_e,
    xi_from_e,
)


def materials_command(args) -> int:
    """``pound-mc materials``: the seed's Tables 1-3."""
    numbers = (args.table,) if args.table else (1, 2, 3)
    if args.plot:
        output_path(args.plot, key="--plot", suffix=".png")
    if args.json:
        out = {f"table{n}": materials.table(n).to_dict(orient="records") for n in numbers}
        print(json.dumps(out, indent=1))
    else:
        titles = {
            1: "Table 1. Balls used in the drop experiment",
            2: "Table 2. Coefficient of restitution e [-] against prior-impact velocity [m/s]",
            3: "Table 3. Impact stiffness parameter beta [N/m^1.5] against ball mass [kg]",
        }
        for n in numbers:
            print(f"Jankowski (2008) {titles[n]}")
            print(materials.table(n).to_string(index=False))
            print()
    if args.plot:
        restitution_ranges_chart(args.plot)
        print(f"wrote {args.plot}")
    return 0


def calibrate_command(args) -> int:
    """``pound-mc calibrate``: xi for a restitution e under every relation."""
    e = args.e
    if args.relation not in RELATIONS:
        raise InputError(
            f"unknown relation {args.relation!r}; choose one of {sorted(RELATIONS)}",
            key="--relation",
        )
    # every relation's row is shown: e from where each reaches the Jankowski law's table
    # (xi <= 71.17) to 1, the lower end rounded up to 1e-5
    low = math.ceil(max(lowest_e(name) for name in RELATIONS) * 1e5) / 1e5
    if not low <= e <= 1.0:  # nan too
        raise InputError(
            f"coefficient of restitution must lie in [{low:g}, 1] (below {low:g} a relation's "
            f"xi exceeds {largest_xi():.4g}, the end of the Jankowski law's restitution table), "
            f"got {e:g}",
            key="--e",
        )
    rows = {}
    for name in RELATIONS:
        xi = float(xi_from_e(e, name))
        if name == "kelvin":
            # The Kelvin relation belongs to the linear viscoelastic law: check it there.
            achieved = drop_test(1.0, 1.0, 1.0e7, xi=xi, model="kelvin", n_history=4).restitution
            law = "kelvin"
        else:
            achieved = float(effective_restitution(e, name))
            law = "jankowski"
        rows[name] = {"xi": xi, "e_effective": achieved, "contact_model": law}
    chosen = rows[args.relation]
    if args.json:
        print(
            json.dumps(
                {
                    "e": e,
                    "relation": args.relation,
                    "xi": chosen["xi"],
                    "e_effective": chosen["e_effective"],
                    "relations": rows,
                }
            )
        )
        return 0
    print(f"target restitution e = {e:g}")
    print(f"{'relation':<15}{'law':<11}{'xi':>12}{'e really produced':>20}")
    for name, row in rows.items():
        mark = "  <-" if name == args.relation else ""
        print(
            f"{name:<15}{row['contact_model']:<11}{row['xi']:>12.6f}"
            f"{row['e_effective']:>20.6f}{mark}"
        )
    return 0


def droptest_command(args) -> int:
    """``pound-mc droptest``: the virtual drop test of the seed's experiment."""
    t1 = materials.table(1)
    balls = t1[t1["material"] == args.material]
    if args.mass is None:
        middle = balls.iloc[len(balls) // 2]
        mass = 0.5 * (middle["mass_min_kg"] + middle["mass_max_kg"])
    else:
        mass = args.mass
    if not (np.isfinite(args.velocity) and args.velocity > 0):
        raise InputError(f"must be > 0, got {args.velocity}", key="--velocity")
    if not (mass > 0 and math.isfinite(mass)):
        raise InputError(f"must be > 0, got {mass}", key="--mass")
    if args.plot:
        output_path(args.plot, key="--plot", suffix=".png")
    if args.model not in CONTACT_MODELS:
        raise InputError(f"unknown contact law {args.model!r}; choose one of "
                         f"{', '.join(CONTACT_MODELS)}", key="--model")  # fmt: skip
    beta = args.beta
    if beta is None:
        units = CONTACT_MODELS[args.model].stiffness_units
        if units != "N m-1.5":  # Table 3's beta is the Hertz-type laws' N/m^1.5
            raise InputError(
                f"the {args.model!r} law's stiffness is in {units.replace(' m-1', '/m')}; "
                "Table 3 gives beta in N/m^1.5 (Hertz-type laws): give the stiffness with --beta",
                key="--beta",
            )
        beta = materials.stiffness_range(args.material, mass)[2]
    xi, e = args.xi, args.e
    elastic = args.model in CONTACT_MODELS and CONTACT_MODELS[args.model].damping is None
    if elastic and (e is not None or xi not in (None, 0.0)):
        raise InputError(f"the {args.model!r} law has no damping (elastic: it rebounds with "
                         "e = 1); give neither --e nor --xi",
                         key="--e" if e is not None else "--xi")  # fmt: skip
    if xi is None and e is None and not elastic:
        e = float(np.mean(materials.restitution_range(args.material, args.velocity)))
    if e is not None and CONTACT_MODELS[args.model].damping == "xi":
        try:  # the bound a scene's contact.e has (the Jankowski law's restitution table)
            reported_xi(args.model, e, args.relation)
        except InputError as exc:
            key = "--relation" if "relation" in (exc.key or "") else "--e"
            raise InputError(exc.message, key=key) from None
    result = drop_test(
        mass, args.velocity, beta, xi=xi, e=e, relation=args.relation, model=args.model
    )
    out = result.as_dict()
    # the relation that turned e into xi (none where xi was given or the law is elastic)
    relation = (args.relation or default_relation(args.model)) if e is not None else None
    out.update(material=args.material, e_target=e, relation=relation)
    if args.json:
        print(json.dumps(out))
    else:
        print(f"virtual drop test: {args.material} ball on a rigid {args.material} surface")
        print(f"  mass {mass:.4g} kg, impact velocity {args.velocity:g} m/s, beta {beta:.4g}")
        if e is not None:
            print(f"  target e {e:.4f} -> xi {result.xi:.5f} ({relation})")
        print(f"  restitution achieved  {result.restitution:.6f}")
        print(f"  peak penetration      {result.max_penetration_m * 1e6:.4f} um")
        print(f"  peak force            {result.peak_force_N:.6g} N")
        print(f"  contact duration      {result.contact_duration_s * 1e3:.6f} ms")
    written = []
    if args.plot:
        droptest_chart(result, args.plot)
        written.append(args.plot)
    if args.out:
        folder = Path(args.out)
        written.append(droptest_chart(result, folder / "droptest.png") and folder / "droptest.png")
        restitution_chart(folder / "restitution_relations.png")
        restitution_ranges_chart(folder / "restitution_table2.png")
        written += [folder / "restitution_relations.png", folder / "restitution_table2.png"]
    if written and not args.json:
        for path in written:
            print(f"wrote {path}")
    return 0
