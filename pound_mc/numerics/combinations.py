"""Every combination of structure, storey law, restitution and method against the reference.

Five structures (an SDOF pair, a pair of shear buildings, an SDOF against a wall, a row of
three SDOF buildings, a 3-storey frame's slabs against a 2-storey building's columns) x four
storey laws of the yielding building (elastic, bilinear with 5 % hardening, elastic-perfectly
plastic, Bouc-Wen) x two restitutions (fixed ``e = 0.65``; set per impact from Table 2,
concrete, median) x four methods, 160 runs on 3 s of El Centro 1940 at 0.5 g.  Each run is
compared with :func:`pound_mc.integrators.reference.reference_solution` (SciPy DOP853 at
``rtol = 1e-11`` with every switch located; it shares no code with the kernels):
``adaptive`` at its defaults, the fixed-step methods at ``dt_s`` = :data:`FIXED_DT_S`.

``python -m pound_mc.numerics.combinations [--out FILE.md]`` runs them all (a progress bar;
about a minute of references, cached for the next run in ``outputs/``) and writes the table
that ``docs/integrators.md`` includes (``docs/tables/combinations.md``);
``tests/test_every_combination.py`` runs the same cases
and holds each to :data:`TOLERANCE`.
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import sys
import time
from dataclasses import replace
from pathlib import Path

from tqdm import tqdm

from pound_mc.integrators.reference import reference_solution
from pound_mc.scene import scene_from_dict, simulate

__all__ = [
    "FIXED_DT_S",
    "LAWS",
    "METHODS",
    "RESTITUTIONS",
    "STRUCTURES",
    "TOLERANCE",
    "compare",
    "reference",
    "run",
    "scene",
]

STRUCTURES = ("sdof-pair", "shear-pair", "wall", "row", "columns")
LAWS = ("elastic", "bilinear", "elastoplastic", "bouc-wen")
RESTITUTIONS = ("fixed", "per-impact")
METHODS = ("adaptive", "newmark", "newmark-explicit", "central-difference")
#: The fixed-step methods' step [s] (a contact lasts about 30 ms here: some 600 steps).
FIXED_DT_S = 5e-5
#: The largest relative error each method may have in any compared quantity: ``adaptive`` its
#: documented 1e-5 at the defaults; the fixed-step methods about twice the largest error of
#: the 40 cases at :data:`FIXED_DT_S` (``newmark`` second order, 9e-5 at most;
#: ``newmark-explicit``, its contact force lagged a step, and ``central-difference``, its
#: contact damping from the backward-difference velocity, first order in the contact: 1.7e-3
#: and 4.9e-4 at most).
TOLERANCE = {
    "adaptive": 1e-5,
    "newmark": 2e-4,
    "newmark-explicit": 3e-3,
    "central-difference": 1e-3,
}
#: Compared outputs (a building that cannot yield has no ductility: skipped).
QUANTITIES = ("peak_force", "peak_disp_left", "peak_disp_right", "peak_ductility_left")

_RECORD = {"source": "builtin:elcentro", "duration_s": 3.0, "pga_g": 0.5}
_SDOF = {"model": "sdof", "damping_ratio": 0.05, "mass_kg": 1.0e6}
_THREE = {"model": "shear", "storey_mass_kg": [1.0e6] * 3,
          "storey_stiffness_N_per_m": [1.2e9, 1.0e9, 0.8e9], "storey_height_m": [3.0] * 3,
          "damping_ratio": 0.05}  # fmt: skip
_SOFT_THREE = {**_THREE, "storey_stiffness_N_per_m": [0.6e9, 0.5e9, 0.4e9]}
_TWO = {"model": "shear", "storey_mass_kg": [1.5e6] * 2,
        "storey_stiffness_N_per_m": [0.5e9, 0.4e9], "storey_height_m": [4.5] * 2,
        "damping_ratio": 0.05}  # fmt: skip


def _law(building: dict, law: str, yields) -> dict:
    """``building`` with storey law ``law`` (yield drift(s) ``yields`` [m])."""
    if law == "elastic":
        return building
    key = "storey_yield_disp_m" if building["model"] == "shear" else "yield_disp_m"
    return {**building, key: yields, "hysteresis": "bouc-wen" if law == "bouc-wen" else "bilinear",
            "post_yield_ratio": 0.0 if law == "elastoplastic" else 0.05}  # fmt: skip


def _buildings(structure: str, law: str) -> dict:
    """The buildings of ``structure``, the first (left) one with storey law ``law``."""
    sdof_05 = _law({**_SDOF, "period_s": 0.5}, law, 0.01)
    if structure == "sdof-pair":
        return {"left": sdof_05, "right": {**_SDOF, "period_s": 1.0}}
    if structure == "shear-pair":
        return {"left": _law(_THREE, law, [0.008, 0.007, 0.006]), "right": _SOFT_THREE}
    if structure == "wall":
        return {"left": _law({**_SDOF, "period_s": 0.6}, law, 0.01), "right": {"model": "wall"}}
    if structure == "row":
        return {"buildings": [sdof_05, {**_SDOF, "period_s": 1.0}, {**_SDOF, "period_s": 0.7}]}
    return {"left": _law(_THREE, law, [0.008, 0.007, 0.006]), "right": _TWO}  # columns


def scene(structure: str, law: str, restitution: str):
    """The scene of one combination (method left to :func:`run`), without a tail."""
    contact = {"model": "jankowski", "beta": 2.75e9, "gap_m": 0.005}
    if restitution == "fixed":
        contact["e"] = 0.65
    else:
        contact |= {"restitution": "velocity", "material": "concrete", "e_quantile": 0.5}
    data = {"record": _RECORD, **_buildings(structure, law), "contact": contact}
    return replace(scene_from_dict(data), tail_s=0.0)


def reference(structure: str, law: str, restitution: str) -> dict:
    """The SciPy reference's outputs of one combination (``seconds``: how long it took)."""
    sc = scene(structure, law, restitution)
    t0 = time.perf_counter()
    ref = reference_solution(sc, sc.record_arrays())
    out = {k: float(ref[k]) for k in ("impacts", *QUANTITIES)}
    out["seconds"] = time.perf_counter() - t0
    return out


def run(structure: str, law: str, restitution: str, method: str) -> dict:
    """One combination's outputs from ``pound_mc.simulate`` (accuracy check off: compared here)."""
    sc = scene(structure, law, restitution)
    dt = {} if method == "adaptive" else {"dt_s": FIXED_DT_S}
    out = simulate(sc, record=sc.record_arrays(), method=method, accuracy_check=False,
                   **dt).outputs  # fmt: skip
    return {k: float(out[k]) for k in ("status", "impacts", *QUANTITIES)}


def compare(got: dict, ref: dict) -> dict:
    """Relative error of each compared quantity (NaN both: skipped) and the largest."""
    errors = {}
    for key in QUANTITIES:
        if (math.isnan(ref[key]) and math.isnan(got[key])) or ref[key] == got[key] == 0.0:
            continue  # a building that cannot yield, a wall (it does not move)
        errors[key] = abs(got[key] - ref[key]) / abs(ref[key]) if ref[key] else math.inf
    errors["largest"] = max(errors.values())
    return errors


def _cases():
    return list(itertools.product(STRUCTURES, LAWS, RESTITUTIONS))


def table(rows: list[dict]) -> str:
    """The Markdown table of the runs: one line per structure, law and restitution."""
    head = "| structure | storey law | restitution | impacts | " + " | ".join(
        f"`{m}`" for m in METHODS) + " |"  # fmt: skip
    lines = [head, "| --- " * (4 + len(METHODS)) + "|"]
    for s, law, r in _cases():
        mine = {x["method"]: x for x in rows if (x["structure"], x["law"], x["restitution"])
                == (s, law, r)}  # fmt: skip
        cells = [f"{mine[m]['largest']:.1e}" if mine[m]["status"] == 0 else "failed"
                 for m in METHODS]  # fmt: skip
        impacts = int(mine[METHODS[0]]["ref_impacts"])
        lines.append(f"| {s} | {law} | {r} | {impacts} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    """Run every combination, print and write the table (``--out``)."""
    parser = argparse.ArgumentParser(prog="python -m pound_mc.numerics.combinations")
    parser.add_argument("--out", default="docs/tables/combinations.md")
    parser.add_argument("--refs", default="outputs/combination_refs.json",
                        help="cache of the references (kept for the next run)")  # fmt: skip
    args = parser.parse_args(argv)
    refs_path = Path(args.refs)
    refs = json.loads(refs_path.read_text()) if refs_path.exists() else {}
    rows = []
    for s, law, r in tqdm(_cases(), desc="combinations", file=sys.stderr):
        key = f"{s}|{law}|{r}"
        if key not in refs:
            refs[key] = reference(s, law, r)
            refs_path.parent.mkdir(parents=True, exist_ok=True)
            refs_path.write_text(json.dumps(refs, indent=1))  # kept as they come
        for m in METHODS:
            got = run(s, law, r, m)
            rows.append({"structure": s, "law": law, "restitution": r, "method": m,
                         "status": got["status"], "impacts": got["impacts"],
                         "ref_impacts": refs[key]["impacts"],
                         **compare(got, refs[key])})  # fmt: skip
    refs_path.parent.mkdir(parents=True, exist_ok=True)
    refs_path.write_text(json.dumps(refs, indent=1))
    text = table(rows)
    Path(args.out).write_text(text)
    print(text)
    bad = [x for x in rows if x["status"] != 0 or x["impacts"] != x["ref_impacts"]
           or x["largest"] > TOLERANCE[x["method"]]]  # fmt: skip
    for x in bad:
        print("outside:", x, file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
