"""The project's SciPy reference on real-record scenes of every model.

:func:`pound_mc.integrators.reference.reference_solution` integrates a scene in physical floor
coordinates with SciPy's DOP853 at ``rtol = 1e-11``, sample interval by sample interval, with
every contact phase, yield and unload located as an event; it shares no code with the compiled
kernels.  Each scene here runs :func:`pound_mc.scene.simulate` at its defaults (``adaptive``)
on a few seconds of a real record and compares the peak contact force, the impacts, the peak
displacements and, for yielding buildings, the peak ductilities.  Tolerance 1e-4 on each: the
accuracy the test suite holds ``adaptive`` to at its defaults on every contact law
(``tests/test_laws_vs_reference.py``); the measured differences are about 1e-7.  The impact
count must match exactly.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from pound_mc.integrators.reference import reference_solution
from pound_mc.scene import scene_from_dict, simulate
from pound_mc.validation.runner import Case

__all__ = ["CASES", "SCENES", "compare"]

SOURCE = "SciPy reference (DOP853, rtol 1e-11)"
TOLERANCE = 1e-4

SDOF = {"model": "sdof", "damping_ratio": 0.05, "mass_kg": 1.0e6}
CONTACT = {"model": "jankowski", "beta": 2.75e9, "xi": 0.35, "gap_m": 0.01}
KNET = {"source": "builtin:knet-akt013", "duration_s": 6.0, "pga_g": 0.5}
ELCENTRO = {"source": "builtin:elcentro", "duration_s": 6.0, "pga_g": 0.5}
SHORT = {"source": "builtin:elcentro", "duration_s": 8.0, "pga_g": 0.4}
THREE = {"model": "shear", "storey_mass_kg": [1.0e6] * 3,
         "storey_stiffness_N_per_m": [1.2e9, 1.0e9, 0.8e9], "storey_height_m": [3.0] * 3,
         "damping_ratio": 0.05}  # fmt: skip
FIVE = {"model": "shear", "storey_mass_kg": [1.0e6] * 5,
        "storey_stiffness_N_per_m": [0.9e9, 0.8e9, 0.7e9, 0.6e9, 0.5e9],
        "storey_height_m": [3.0] * 5, "damping_ratio": 0.05}  # fmt: skip
TWO = {"model": "shear", "storey_mass_kg": [1.5e6] * 2,
       "storey_stiffness_N_per_m": [0.5e9, 0.4e9], "storey_height_m": [4.5] * 2,
       "damping_ratio": 0.05}  # fmt: skip
#: Chopra's five-storey shear frame (Sec. 12.8, Fig. 12.8.1; Sec. 13.2.6 on El Centro):
#: storey mass 100 kips/g, storey stiffness 31.54 kips/in, storeys of 12 ft, 5 % damping.
KIP = 4448.2216152605  # N
CHOPRA_FIVE = {"model": "shear", "storey_mass_kg": [100.0 * KIP / 9.80665] * 5,
               "storey_stiffness_N_per_m": [31.54 * KIP / 0.0254] * 5,
               "storey_height_m": [12.0 * 0.3048] * 5, "damping_ratio": 0.05}  # fmt: skip


def _bilinear(building, yields, alpha=0.05):
    return {**building, "hysteresis": "bilinear", "storey_yield_disp_m": yields,
            "post_yield_ratio": alpha}  # fmt: skip


def _pair(record, left, right, contact=CONTACT) -> dict:
    return {"record": record, "left": left, "right": right, "contact": contact}


#: Scenes by case name: (scene table, what it checks, in the quick set).
SCENES = {
    "reference-sdof-pair": (_pair(KNET, {**SDOF, "period_s": 0.5}, {**SDOF, "period_s": 1.0},
                                  {**CONTACT, "gap_m": 0.005}),
                            "B1's SDOF pair (0.5 s and 1 s), K-NET AKT013 at 0.5 g", True),
    "reference-laws": (None, "the same pair with the linear, Kelvin, Hertz and Hertz-damp laws "
                       "(the quick set: Kelvin and Hertz-damp)", True),
    "reference-wall": (_pair(SHORT, {**SDOF, "period_s": 0.6, "hysteresis": "bilinear",
                                     "yield_disp_m": 0.02, "post_yield_ratio": 0.05},
                             {"model": "wall"}),
                       "a bilinear SDOF building against a rigid wall", False),
    "reference-row": ({"record": {"source": "builtin:elcentro", "duration_s": 6.0,
                                  "pga_g": 0.2},
                       "buildings": [{**SDOF, "period_s": 0.5}, {**SDOF, "period_s": 1.0},
                                     {**SDOF, "period_s": 0.7}],
                       "contact": {**CONTACT, "gap_m": 0.003}},
                      "a row of three SDOF buildings (two contacts)", False),
    "reference-columns": (_pair(ELCENTRO, _bilinear(THREE, [0.01, 0.009, 0.008], 0.03), TWO,
                                {**CONTACT, "gap_m": 0.005}),
                          "a yielding 3-storey frame's slabs against a 2-storey building's "
                          "columns", False),
    "reference-shear-bilinear": (_pair(ELCENTRO, _bilinear(THREE, [0.012, 0.011, 0.010]),
                                       _bilinear(FIVE, [0.012, 0.012, 0.011, 0.011, 0.010])),
                                 "a 3- and a 5-storey frame with bilinear storeys", False),
    "reference-bouc-wen": (_pair(ELCENTRO, {**_bilinear(THREE, [0.012, 0.011, 0.010]),
                                            "hysteresis": "bouc-wen"},
                                 {**_bilinear(FIVE, [0.012] * 5), "hysteresis": "bouc-wen",
                                  "bw_exponent": 1.0}),
                           "Bouc-Wen storeys (n = 2 and n = 1)", False),
    "reference-elastoplastic": (_pair(SHORT, {**SDOF, "period_s": 0.5, "hysteresis": "bilinear",
                                              "yield_disp_m": 0.02, "post_yield_ratio": 0.0},
                                      {**SDOF, "period_s": 1.0, "hysteresis": "bilinear",
                                       "yield_disp_m": 0.04, "post_yield_ratio": 0.0}),
                                "an elastic-perfectly plastic SDOF pair", False),
    "reference-velocity-restitution": (
        _pair(SHORT, {**SDOF, "period_s": 0.5, "hysteresis": "bilinear", "yield_disp_m": 0.02,
                      "post_yield_ratio": 0.05}, {**SDOF, "period_s": 1.0},
              {"model": "jankowski", "beta": 2.75e9, "restitution": "velocity",
               "material": "concrete", "e_quantile": 0.5, "gap_m": 0.01}),
        "restitution set per impact from Table 2 (concrete), a yielding building", False),
    "reference-chopra-five-storey": (
        _pair({"source": "builtin:elcentro-chopra", "demean": False},
              CHOPRA_FIVE, {**SDOF, "period_s": 1.0, "height_m": 10.0},
              {**CONTACT, "gap_m": 10.0}),
        "Chopra's five-storey frame on his El Centro record, no pounding", False),
}  # fmt: skip

#: The other laws of the ``reference-laws`` case, on the SDOF pair.
LAWS = {
    "linear": {"k_N_per_m": 1.0e9},
    "kelvin": {"k_N_per_m": 1.0e9, "e": 0.6},
    "hertz": {"beta": 2.75e9},
    "hertzdamp": {"beta": 2.75e9, "e": 0.6},
}
_COMPARED = ("peak_force", "peak_disp_left", "peak_disp_right", "peak_ductility_left",
             "peak_ductility_right")  # fmt: skip
_UNITS = {"peak_force": "N", "peak_disp_left": "m", "peak_disp_right": "m"}


def compare(data: dict, label: str = "") -> list[dict]:
    """Rows comparing ``simulate`` at its defaults with the reference on the scene ``data``.

    Yielding buildings run without the free-vibration tail (``tail_s = 0``), as the reference
    does: both stop at the last sample.
    """
    scene = replace(scene_from_dict(data), tail_s=0.0)
    record = scene.record_arrays()
    ref = reference_solution(scene, record)
    res = simulate(scene, record=record, history=True)
    out = res.outputs
    if out["status"] != 0:
        raise RuntimeError(f"the simulation's status is {out['status']}, not ok")
    rows = []
    if ref["impacts"] > 0:
        rows.append({"quantity": f"impacts{label}", "value": float(out["impacts"]),
                     "reference": float(ref["impacts"]), "tolerance": 0.0})  # fmt: skip
    for key in _COMPARED:
        if key == "peak_force" and ref["impacts"] == 0:
            continue
        if math.isnan(ref[key]) or ref[key] == 0.0:
            continue  # an elastic building has no ductility, a wall no displacement
        rows.append({"quantity": key + label, "value": float(out[key]),
                     "reference": float(ref[key]), "tolerance": TOLERANCE,
                     "units": _UNITS.get(key, "")})  # fmt: skip
    rows[0]["_plot"] = _plot(res, ref, scene)
    return rows


def _plot(res, ref, scene) -> dict:
    """The tool's and the reference's histories at the record's samples.

    The force of the contact with the largest peak, or the left roof's displacement where
    nothing pounds.
    """
    t = res.time_s[: ref["x_samples"].shape[0]]
    if ref["impacts"] > 0:
        j = int(np.argmax(ref["contact_peak_force"]))
        tool, want = res.force_N[: t.size, j] / 1e6, ref["f_samples"][:, j] / 1e6
        ylabel = f"force at contact {j} [MN]"
    else:
        roof = scene.left.n_floors - 1
        tool, want = res.disp_left_m[: t.size, roof] * 1e3, ref["x_samples"][:, roof] * 1e3
        ylabel = "left roof displacement [mm]"
    return {
        "title": "",
        "xlabel": "time [s]",
        "ylabel": ylabel,
        "series": [("pound-mc (adaptive)", t, tool), ("SciPy reference", t, want)],
    }


def _case(name: str):
    data, _what, _quick = SCENES[name]

    def run(quick: bool = False) -> list[dict]:
        return compare(data)

    return run


def laws(quick: bool = False) -> list[dict]:
    """The SDOF pair with each of the other contact laws (``quick``: two of them)."""
    base = SCENES["reference-sdof-pair"][0]
    rows = []
    for law, params in LAWS.items():
        if quick and law not in ("kelvin", "hertzdamp"):
            continue
        contact = {"model": law, "gap_m": 0.005, **params}
        rows += [row for row in compare({**base, "contact": contact}, f" ({law})")
                 if row["quantity"].startswith(("peak_force", "impacts"))]  # fmt: skip
    return rows


_ABOUT = (
    "The tool: pound_mc.simulate at its defaults (adaptive). The reference: "
    "pound_mc.integrators.reference.reference_solution, SciPy's DOP853 at rtol 1e-11 in "
    "physical floor coordinates with every contact phase, yield and unload located as an "
    "event; it shares no code with the kernels. Tolerance 1e-4 on each peak (what the test "
    "suite holds adaptive to at its defaults; the differences measured are about 1e-7); the "
    "impacts must match. Scene: "
)

#: The reference cases.
CASES = tuple(
    Case(name, "reference", SOURCE, laws if name == "reference-laws" else _case(name),
         quick=quick, about=_ABOUT + what + ".")
    for name, (_data, what, quick) in SCENES.items()
)  # fmt: skip
