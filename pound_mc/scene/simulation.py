"""One simulation of a scene: :func:`simulate` and its :class:`SimulationResult`.

:func:`simulate` runs a :class:`~pound_mc.scene.model.Scene` through the compiled kernels of
:mod:`pound_mc.integrators` and names what they return: the per-simulation outputs, the
contacts', each building's (:func:`building_results`) and each yielding storey's
(:func:`storey_results`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from pound_mc.errors import InputError
from pound_mc.integrators import run_kernel
from pound_mc.integrators.accuracy import (
    ADAPTIVE_SUBSTEPS_FACTOR,
    COMPANION_DT_S,
    COMPANION_SUBSTEPS,
    flag_inaccurate,
    judged_change,
    substep_check_due,
)
from pound_mc.integrators.batch import FINER_SIZE
from pound_mc.integrators.outputs import INELASTIC_OUTPUTS, STATUS_OK
from pound_mc.scene import schema
from pound_mc.scene.model import Scene

__all__ = [
    "SimulationResult",
    "simulate",
    "with_tail",
    "BUILDING_KEYS",
    "building_results",
    "STOREY_KEYS",
    "storey_results",
]

#: Keys of each of :attr:`SimulationResult.buildings` (``simulate --json``'s ``buildings``).
BUILDING_KEYS = ("building", "model", "peak_disp", "peak_ductility", "peak_drift",
                 "residual_drift")  # fmt: skip
_BUILDING_NUMBERS = BUILDING_KEYS[2:]


@dataclass
class SimulationResult:
    """Outputs of one simulation.

    Attributes
    ----------
    outputs : dict
        Every name of :data:`pound_mc.integrators.OUTPUTS` (forces [N], lengths [m], energies
        [J], ``status`` 0 ok / 1 unstable / 2 not converged).
    contacts : dict
        Per-contact arrays (``peak_force``, ``impacts``, ``max_penetration``, ``impulse``).
    time_s, disp_left_m, disp_right_m, penetration_m, force_N : numpy.ndarray or None
        Histories at the record's samples (only with ``history=True``); with yielding
        buildings they go on over the free-vibration tail (``integrator.tail_s``) after it.
        NaN from where a run that stopped (unstable, not converged) stopped.
    storeys : dict or None
        With yielding buildings, per storey (left building's first, bottom to top):
        ``building`` ("left" / "right"; in a row "building 0", "building 1", ... or "wall"),
        ``storey`` (1-based within it), ``peak_drift_ratio``
        and ``residual_drift_ratio`` (``|drift|`` over storey height, NaN without heights),
        ``peak_ductility`` (peak ``|drift|`` over yield drift, NaN for a storey that cannot yield);
        the scalar outputs ``peak_drift_left`` ... are their maxima over a building's storeys.
    buildings : list of dict
        Per building from left to right (a wall is none), :data:`BUILDING_KEYS`:
        ``building`` (its place, from 0), ``model``, ``peak_disp`` [m] (peak ``|x|`` of its
        floors), ``peak_ductility``, ``peak_drift`` and ``residual_drift`` (ratios; their
        maxima over its storeys, NaN for elastic buildings and without heights).  For a pair,
        ``peak_disp_left`` ... are the first's and ``..._right`` the last's.
    """

    outputs: dict[str, float]
    contacts: dict[str, np.ndarray]
    scene: Scene
    time_s: np.ndarray | None = None
    disp_left_m: np.ndarray | None = None
    disp_right_m: np.ndarray | None = None
    penetration_m: np.ndarray | None = None
    force_N: np.ndarray | None = None
    extra: dict = field(default_factory=dict)
    storeys: dict | None = None
    buildings: list = field(default_factory=list)

    @property
    def status(self) -> str:
        """``"ok"``, ``"unstable"``, ``"not_converged"`` or ``"inaccurate"``."""
        return {0: "ok", 1: "unstable", 2: "not_converged", 3: "inaccurate"}[
            int(self.outputs["status"])
        ]

    def to_json(self) -> dict[str, Any]:
        """JSON-serialisable summary with the pinned keys of DESIGN.md section 7.

        ``xi`` is the damping ratio the kernels ran with; null for ``hertzdamp``, whose damping
        constant is set at every impact from ``e`` and the impact velocity (no constant ratio).
        """

        def num(x):
            x = float(x)
            return x if math.isfinite(x) else None

        def count(x):  # NaN where a run that is not ok has no count
            x = float(x)
            return int(x) if math.isfinite(x) else None

        o = self.outputs
        inelastic = {}
        if self.scene.inelastic:
            # the storeys' responses (DESIGN.md section 9), only for yielding buildings
            inelastic = {name: num(o[name]) for name in INELASTIC_OUTPUTS}
        return {
            "peak_force_N": num(o["peak_force"]),
            "impacts": count(o["impacts"]),
            "peak_disp_left_m": num(o["peak_disp_left"]),
            "peak_disp_right_m": num(o["peak_disp_right"]),
            "max_penetration_m": num(o["max_penetration"]),
            "impulse_N_s": num(o["impulse"]),
            "dissipated_energy_J": num(o["dissipated_energy"]),
            "input_energy_J": num(o["input_energy"]),
            "energy_residual": num(o["energy_residual"]),
            "peak_force_time_s": num(o["peak_force_time"]),
            "status": self.status,
            "method": self.scene.method,
            "contact_model": self.scene.contact_model,
            "xi": num(self.scene.xi) if self.scene.xi is not None else None,
            "steps": count(o["steps"]),
            "max_impact_velocity": num(o["max_impact_velocity"]),
            "median_impact_velocity": num(o["median_impact_velocity"]),
            "peak_force_restitution": num(o["peak_force_restitution"]),
            "contacts": [
                {
                    "kind": c.kind,
                    "left_floor": c.left_floor + 1,
                    "right_floor": c.right_floor + 1,
                    "elevation_m": c.elevation_m,
                    "gap_m": float(self.scene.gap_m[k]),
                    "peak_force_N": num(self.contacts["peak_force"][k]),
                    "impacts": count(self.contacts["impacts"][k]),
                    "max_impact_velocity": num(self.contacts["max_impact_velocity"][k]),
                    **({"pair": c.pair + 1} if self.scene.row is not None else {}),
                }
                for k, c in enumerate(self.scene.contacts)
            ],
            "buildings": [
                {k: (num(v) if k in _BUILDING_NUMBERS else v) for k, v in b.items()}
                for b in self.buildings
            ],
            **inelastic,
            **(
                {
                    "storeys": [
                        {
                            "building": str(b),
                            "storey": int(n),
                            "peak_drift_ratio": num(d),
                            "peak_ductility": num(mu),
                            "residual_drift_ratio": num(r),
                        }
                        for b, n, d, mu, r in zip(
                            *(self.storeys[k] for k in STOREY_KEYS), strict=True
                        )
                    ]
                }
                if self.storeys is not None and self.scene.inelastic
                else {}
            ),
        }


def with_tail(acc, dt_rec: float, tail_s: float) -> np.ndarray:
    """The record followed by ``tail_s`` [s] of free vibration (zero ground acceleration).

    The ground acceleration falls linearly from the last sample to zero over one interval.
    """
    n_tail = int(round(tail_s / dt_rec))
    return np.concatenate((np.asarray(acc, dtype=float), np.zeros(n_tail)))


#: Keys of :attr:`SimulationResult.storeys`, in the order ``simulate --json`` lists them.
STOREY_KEYS = ("building", "storey", "peak_drift_ratio", "peak_ductility", "residual_drift_ratio")


def storey_results(table: np.ndarray, storey_out: np.ndarray, owner=None) -> dict[str, np.ndarray]:
    """Per-storey outputs (:attr:`SimulationResult.storeys`) from the storey table.

    ``table``: :meth:`Scene.storey_arrays`'s (stiffness, yield drift, post-yield ratio,
    height, building 0/1 per row); ``storey_out``: the kernel's peak and final drifts [m].
    ``owner``: each storey's building by name (default ``left`` / ``right`` from the table;
    a row's are ``building 1``, ``building 2``, ...); storeys are numbered within it.
    """
    side = table[:, 4].astype(int)
    owner = np.where(side == 0, "left", "right") if owner is None else np.asarray(owner)
    number = np.empty(side.size, dtype=np.int32)
    for name in dict.fromkeys(owner.tolist()):
        number[owner == name] = np.arange(1, np.count_nonzero(owner == name) + 1)
    uy = table[:, 1]
    with np.errstate(invalid="ignore"):
        ductility = np.where(np.isfinite(uy), storey_out[:, 0] / uy, np.nan)
    return {
        "building": owner,
        "storey": number,
        "peak_drift_ratio": storey_out[:, 0] / table[:, 3],
        "peak_ductility": ductility,
        "residual_drift_ratio": np.abs(storey_out[:, 1]) / table[:, 3],
    }


def _nanmax(values: np.ndarray) -> float:
    """The largest of ``values`` that is not NaN (NaN when there is none)."""
    values = np.asarray(values, dtype=float)
    kept = values[~np.isnan(values)]
    return float(kept.max()) if kept.size else math.nan


def building_results(scene: Scene, code_peaks, table=None, storey_out=None) -> list[dict]:
    """Each building's outputs (:attr:`SimulationResult.buildings`), left to right.

    ``code_peaks``: the kernel's peak displacement per building code
    (:meth:`~pound_mc.scene.model.Scene.side_codes`); ``table`` and ``storey_out``: the
    storey table and the storeys' peak and final drifts of a yielding run (None: elastic,
    whose ductility and drifts are NaN).  A wall is no building and has no entry.
    """
    per_storey = None
    if table is not None and storey_out is not None:
        per_storey = storey_results(table, storey_out)
    out = []
    for k, (b, code) in enumerate(zip(scene.buildings, scene.side_codes(), strict=True)):
        if b.model == "wall":
            continue
        entry = {"building": k, "model": b.model, "peak_disp": float(code_peaks[code])}
        if per_storey is None:
            entry |= {"peak_ductility": math.nan, "peak_drift": math.nan,
                      "residual_drift": math.nan}  # fmt: skip
        else:
            mine = table[:, 4] == code
            entry |= {
                "peak_ductility": _nanmax(per_storey["peak_ductility"][mine]),
                "peak_drift": _nanmax(per_storey["peak_drift_ratio"][mine]),
                "residual_drift": _nanmax(per_storey["residual_drift_ratio"][mine]),
            }
        out.append(entry)
    return out


def _checked_status(res: SimulationResult, kernel, start, table) -> int:
    """The status of an ``ok`` run after the accuracy check (:mod:`pound_mc.integrators.accuracy`).

    ``kernel(**settings)``: :func:`~pound_mc.integrators.run_kernel` of the run's scene and
    record; ``start``: the run's ``finer_start`` (``adaptive`` on an SDOF pair: whether its
    finer run would be the run itself, and where that run may start, else NaN).
    """
    scene, o = res.scene, res.outputs
    resume = None
    if scene.method == "adaptive":
        if start[0] == 1.0 or not substep_check_due(o["peak_force"], o["status"]):
            return int(o["status"])
        second = {"method": "adaptive", "dt_s": scene.dt_s,
                  "substeps": scene.substeps * ADAPTIVE_SUBSTEPS_FACTOR}  # fmt: skip
        if not np.isnan(start[0]):  # from the last onset up to which it is the run
            resume = start[1:]
    else:
        second = {"method": "adaptive", "dt_s": COMPANION_DT_S, "substeps": COMPANION_SUBSTEPS}
    storey_out = None if table is None else np.empty((table.shape[0], 2))
    other = kernel(**second, storey_out=storey_out, resume=resume)
    buildings = building_results(scene, other.code_peaks, table, storey_out)
    contacts = resume is None  # a resumed run gives the peak force and the floors' peaks
    change = judged_change(_judged(o, res.contacts, res.buildings, contacts),
                           _judged(other.outputs, other.contacts, buildings, contacts))  # fmt: skip
    return int(flag_inaccurate([o["status"]], None, np.inf, 0.0, change=change)[0])


def _judged(outputs: dict, contacts: dict, buildings: list, per_contact: bool = True) -> dict:
    """A run's judged quantities (:func:`~pound_mc.integrators.accuracy.judged_change`)."""
    got = {
        "peak_force": [outputs["peak_force"]],
        "impacts": [outputs["impacts"]],
        "peak_disp": [[b["peak_disp"] for b in buildings]],
        "peak_ductility": [[b["peak_ductility"] for b in buildings]],
    }
    if per_contact:  # an SDOF pair's one contact is its peak force
        got["contact_peak_force"] = [contacts["peak_force"]]
    return got


def simulate(
    scene: Scene,
    *,
    history: bool = False,
    record=None,
    method: str | None = None,
    dt_s: float | None = None,
    substeps: int | None = None,
    accuracy_check: bool | None = None,
) -> SimulationResult:
    """Run one simulation of ``scene``, with the accuracy check of a study's runs.

    Parameters
    ----------
    scene : Scene
        The scene.
    history : bool
        Also return histories at the record's samples.
    record : tuple (dt_s, acceleration), optional
        A record already loaded (``records.record_arrays``); default the scene's own, read
        once and cached on the scene (:meth:`Scene.record_arrays`).
    method, dt_s, substeps : optional
        Override the scene's integrator settings, within the bounds of the scene file's
        ``[integrator]`` keys.
    accuracy_check : bool, optional
        Override ``integrator.accuracy_check``: an ``ok`` run is compared with a second run
        (:mod:`pound_mc.integrators.accuracy`: ``adaptive`` at its defaults for a fixed-step
        run, twice the contact sub-steps for an ``adaptive`` run with a contact, unless that
        run would be this one) and its status becomes ``inaccurate`` where a judged quantity
        differs by more than 0.5 %; its numbers are kept.  False: only a fixed-step run's
        steps-per-contact criterion.

    Raises
    ------
    InputError
        An override out of those bounds (``dt_s = 0``, an unknown method), naming it.

    Notes
    -----
    The first call on a scene reads its record (tens of milliseconds through obspy); later
    calls on the same scene reuse it and the modal arrays, and cost the kernel plus a few
    microseconds of Python, and the check's second run where it is due.
    """
    for key, value in (("method", method), ("dt_s", dt_s), ("substeps", substeps)):
        if value is not None and (problem := schema.INTEGRATOR[key].problem(value)):
            raise InputError(problem, key=key)
    m = scene.method if method is None else method
    dt_s = scene.dt_s if dt_s is None else float(dt_s)
    substeps = scene.substeps if substeps is None else int(substeps)  # numpy integers too
    if record is None:
        record = scene.record_arrays()
    dt_rec, acc = record
    arrays = scene.kernel_arrays()
    storeys = scene.kernel_storeys()
    storey_out = None
    if storeys is not None:
        acc = with_tail(acc, dt_rec, scene.tail_s)
        storey_out = np.empty((storeys[1].shape[0], 2))
    check = scene.accuracy_check if accuracy_check is None else bool(accuracy_check)
    kernel = functools.partial(run_kernel, acc, dt_rec, **arrays, model=scene.contact_model,
                               relation=scene.relation, storeys=storeys,
                               restitution=scene.restitution_rule())  # fmt: skip
    start = np.empty(FINER_SIZE)  # where adaptive's finer run may start (SDOF pairs)
    outputs, contacts, hist, code_peaks = kernel(
        method=m, dt_s=dt_s, substeps=substeps, history=history, storey_out=storey_out,
        contact_steps_flag=not check, finer_start=start,
    )  # fmt: skip
    if (m, dt_s, substeps) != (scene.method, scene.dt_s, scene.substeps):
        scene = replace(scene, method=m, dt_s=dt_s, substeps=substeps)
    res = SimulationResult(outputs, contacts, scene)
    table = None if storeys is None else np.asarray(storeys[1], dtype=float)
    res.buildings = building_results(scene, code_peaks, table, storey_out)
    if check and outputs["status"] == STATUS_OK:
        outputs["status"] = _checked_status(res, kernel, start, table)
    if storey_out is not None:
        owner = None
        if scene.row is not None:  # a row's buildings by their place in it
            names = ["wall" if b.model == "wall" else f"building {k}"
                     for k, b in enumerate(scene.row)]  # fmt: skip
            owner = np.repeat(names, [b.n_floors for b in scene.row])
        res.storeys = storey_results(table, storey_out, owner)
    if hist is not None:
        hx, hd, hf = hist
        fl = scene.left.n_floors
        res.time_s = np.arange(acc.size) * dt_rec
        res.disp_left_m = hx[:, :fl]
        res.disp_right_m = hx[:, fl:]
        res.penetration_m = hd
        res.force_N = hf
    return res
