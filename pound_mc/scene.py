"""One deterministic simulation: a scene file (TOML) to a :class:`SimulationResult`.

A scene holds ``[record]``, ``[left]``, ``[right]``, ``[contact]`` and ``[integrator]``
(``../shared/DESIGN.md`` section 6).  :func:`simulate` runs it through the compiled kernels of
:mod:`pound_mc.integrators`.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from pound_mc.errors import InputError
from pound_mc.integrators import METHODS, run_kernel
from pound_mc.motions import records
from pound_mc.motions.records import record_arrays
from pound_mc.physics.contact import CONTACT_MODELS, check_relation, reported_xi
from pound_mc.physics.structures import Building, Contact, building_from_dict, contacts_between

__all__ = ["Scene", "SimulationResult", "scene_from_dict", "load_scene", "simulate"]

_SCENE_TABLES = {"record", "left", "right", "contact", "integrator"}
_CONTACT_KEYS = {"model", "gap_m", "beta", "k_N_per_m", "xi", "e", "relation"}
_INTEGRATOR_KEYS = {"method", "dt_s", "substeps"}
_RECORD_KEYS = {
    "source", "name", "demean", "duration_s", "pga_g", "units", "component", "seed", "params",
    "resample_hz", "filter",
}  # fmt: skip
#: Contact laws whose stiffness is ``k_N_per_m`` [N/m] (the others take ``beta`` [N/m^1.5]).
_LINEAR_LAWS = {"linear", "kelvin"}


@dataclass
class Scene:
    """A validated scene: record specification, two buildings, their contacts and settings."""

    record: dict[str, Any]
    left: Building
    right: Building
    contacts: list[Contact]
    gap_m: np.ndarray
    contact_model: str = "jankowski"
    stiffness: float = 2.75e9
    xi: float = 0.35
    e: float | None = None
    relation: str | None = None
    method: str = "adaptive"
    dt_s: float = 0.001
    substeps: int = 16
    file: str | None = None
    base_dir: Path | None = None

    def modal_arrays(self) -> dict[str, np.ndarray]:
        """Arrays the kernels take: modes of both buildings, floor maps and contacts."""
        nl, nr = self.left.omega.size, self.right.omega.size
        fl, fr = self.left.n_floors, self.right.n_floors
        phi = np.zeros((fl + fr, nl + nr))
        phi[:fl, :nl] = self.left.phi
        phi[fl:, nl:] = self.right.phi
        side = np.r_[np.zeros(fl, dtype=np.int64), np.ones(fr, dtype=np.int64)]
        psi = np.array([phi[c.left_floor] - phi[fl + c.right_floor] for c in self.contacts])
        nc = len(self.contacts)
        # the kernels' damping parameter: xi, or the restitution e for laws whose damping is set
        # per impact from e and the impact velocity (hertzdamp)
        per_impact = CONTACT_MODELS[self.contact_model].damping == "zeta"
        xi = self.e if per_impact else self.xi
        return {
            "omega": np.r_[self.left.omega, self.right.omega],
            "zeta": np.r_[
                np.full(nl, self.left.damping_ratio), np.full(nr, self.right.damping_ratio)
            ],
            "gamma": np.r_[self.left.gamma, self.right.gamma],
            "phi": phi,
            "side": side,
            "psi": psi.reshape(nc, nl + nr),
            "gap": np.asarray(self.gap_m, dtype=float),
            "meff": np.array([c.m_eff for c in self.contacts]),
            "beta": np.full(nc, float(self.stiffness)),
            "xi": np.full(nc, float(xi if xi is not None else 0.0)),
        }

    def load_record(self):
        """The scene's record as an obspy Trace [m/s^2], preprocessed."""
        spec = dict(self.record)
        spec.pop("name", None)
        source = spec.pop("source")
        return records.load_record(source, base_dir=self.base_dir, **spec)


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
        Histories at the record's samples (only with ``history=True``).
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

    @property
    def status(self) -> str:
        """``"ok"``, ``"unstable"`` or ``"not_converged"``."""
        return {0: "ok", 1: "unstable", 2: "not_converged"}[int(self.outputs["status"])]

    def to_json(self) -> dict[str, Any]:
        """JSON-serialisable summary with the pinned keys of DESIGN.md section 7.

        ``xi`` is the damping ratio the kernels ran with; null for ``hertzdamp``, whose damping
        constant is set at every impact from ``e`` and the impact velocity (no constant ratio).
        """

        def num(x):
            x = float(x)
            return x if math.isfinite(x) else None

        o = self.outputs
        return {
            "peak_force_N": num(o["peak_force"]),
            "impacts": int(o["impacts"]),
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
            "steps": int(o["steps"]),
            "contacts": [
                {
                    "left_floor": c.left_floor + 1,
                    "right_floor": c.right_floor + 1,
                    "elevation_m": c.elevation_m,
                    "gap_m": float(self.scene.gap_m[k]),
                    "peak_force_N": num(self.contacts["peak_force"][k]),
                    "impacts": int(self.contacts["impacts"][k]),
                }
                for k, c in enumerate(self.scene.contacts)
            ],
        }


def _number(table: dict, key: str, *, file, prefix: str, positive=False, default=None):
    value = table.get(key, default)
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise InputError(f"must be a finite number, got {value!r}", file=file, key=prefix + key)
    if positive and value <= 0:
        raise InputError(f"must be > 0, got {value!r}", file=file, key=prefix + key)
    return float(value)


def scene_from_dict(data: dict, *, file: str | Path | None = None) -> Scene:
    """Validate a scene (the parsed TOML tables) and build a :class:`Scene`.

    Raises
    ------
    InputError
        Naming the file and the key of the first problem found.
    """
    file_s = None if file is None else str(file)
    extra = sorted(set(data) - _SCENE_TABLES - {"study", "grid", "sampling", "records"})
    if extra:
        raise InputError(
            f"unknown table(s) {', '.join(extra)}; allowed: {', '.join(sorted(_SCENE_TABLES))}",
            file=file_s,
            key=extra[0],
        )
    for table in ("record", "left", "right"):
        if not isinstance(data.get(table), dict):
            raise InputError("is required (a table)", file=file_s, key=table)
    record = dict(data["record"])
    unknown = sorted(set(record) - _RECORD_KEYS)
    if unknown:
        raise InputError(f"unknown key {unknown[0]!r}", file=file_s, key=f"record.{unknown[0]}")
    if "source" not in record:
        raise InputError("is required", file=file_s, key="record.source")
    left = building_from_dict(data["left"], file=file_s, side="left")
    right = building_from_dict(data["right"], file=file_s, side="right")
    contacts = contacts_between(left, right, file=file_s)

    for table in ("contact", "integrator"):
        if table in data and not isinstance(data[table], dict):
            raise InputError(f"must be a table, got {data[table]!r}", file=file_s, key=table)
    ct = dict(data.get("contact", {}))
    unknown = sorted(set(ct) - _CONTACT_KEYS)
    if unknown:
        raise InputError(
            f"unknown key; allowed: {', '.join(sorted(_CONTACT_KEYS))}",
            file=file_s,
            key=f"contact.{unknown[0]}",
        )
    model = ct.get("model", "jankowski")
    if not isinstance(model, str) or model not in CONTACT_MODELS:
        raise InputError(
            f"unknown contact model {model!r}; allowed: {', '.join(CONTACT_MODELS)}",
            file=file_s,
            key="contact.model",
        )
    gap = ct.get("gap_m", 0.0)
    gaps = np.atleast_1d(np.asarray(gap, dtype=float)) if _numeric_list(gap) else None
    if gaps is None or not np.all(np.isfinite(gaps)) or np.any(gaps < 0):
        raise InputError(
            f"must be a number >= 0 or one per contact, got {gap!r}",
            file=file_s,
            key="contact.gap_m",
        )
    if gaps.size == 1:
        gaps = np.full(len(contacts), gaps[0])
    elif gaps.size != len(contacts):
        raise InputError(
            f"gives {gaps.size} gaps for {len(contacts)} contacts", file=file_s, key="contact.gap_m"
        )
    skey = "k_N_per_m" if model in _LINEAR_LAWS else "beta"
    other = "beta" if skey == "k_N_per_m" else "k_N_per_m"
    if other in ct:
        raise InputError(
            f"the {model!r} law takes {skey!r}, not {other!r}", file=file_s, key=f"contact.{other}"
        )
    stiffness = _number(ct, skey, file=file_s, prefix="contact.", positive=True, default=2.75e9)
    xi = e = relation = None
    if "xi" in ct and "e" in ct:
        raise InputError("give either xi or e, not both", file=file_s, key="contact.xi")
    if "relation" in ct:
        check_relation(model, ct["relation"], file=file_s)  # only the law's own relations
    if "e" in ct:
        e = _number(ct, "e", file=file_s, prefix="contact.")
        if not 0.0 < e <= 1.0:
            raise InputError(f"must be in (0, 1], got {e!r}", file=file_s, key="contact.e")
        relation = check_relation(model, ct.get("relation"), file=file_s)
        # the damping the kernels run with: NaN for hertzdamp (no constant ratio)
        xi = float(reported_xi(model, e, relation))
    elif "xi" in ct:
        xi = _number(ct, "xi", file=file_s, prefix="contact.")
        if xi < 0:
            raise InputError(f"must be >= 0, got {xi!r}", file=file_s, key="contact.xi")
    elif model in ("jankowski", "kelvin"):
        raise InputError(f"the {model!r} law needs xi or e", file=file_s, key="contact.xi")
    if model == "hertzdamp" and e is None:
        raise InputError("the 'hertzdamp' law needs e", file=file_s, key="contact.e")

    it = dict(data.get("integrator", {}))
    unknown = sorted(set(it) - _INTEGRATOR_KEYS)
    if unknown:
        raise InputError(f"unknown key {unknown[0]!r}", file=file_s, key=f"integrator.{unknown[0]}")
    method = it.get("method", "adaptive")
    if not isinstance(method, str) or method not in METHODS:
        raise InputError(
            f"unknown method {method!r}; allowed: {', '.join(METHODS)}",
            file=file_s,
            key="integrator.method",
        )
    dt_s = _number(it, "dt_s", file=file_s, prefix="integrator.", positive=True, default=0.001)
    substeps = it.get("substeps", 16)
    if isinstance(substeps, bool) or not isinstance(substeps, int) or substeps < 4:
        raise InputError(
            f"must be an integer >= 4, got {substeps!r}", file=file_s, key="integrator.substeps"
        )
    return Scene(
        record=record,
        left=left,
        right=right,
        contacts=contacts,
        gap_m=gaps,
        contact_model=model,
        stiffness=stiffness,
        xi=xi,
        e=e,
        relation=relation,
        method=method,
        dt_s=dt_s,
        substeps=substeps,
        file=file_s,
        base_dir=None if file is None else Path(file).parent,
    )


def _numeric_list(value) -> bool:
    vals = value if isinstance(value, list) else [value]
    return bool(vals) and all(isinstance(v, int | float) and not isinstance(v, bool) for v in vals)


def load_scene(path: str | Path) -> Scene:
    """Read and validate a scene file (TOML)."""
    path = Path(path)
    if not path.is_file():
        raise InputError("no such scene file", file=str(path))
    try:
        data = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"not valid TOML: {exc}", file=str(path)) from None
    return scene_from_dict(data, file=path)


def simulate(
    scene: Scene,
    *,
    history: bool = False,
    record=None,
    method: str | None = None,
    dt_s: float | None = None,
    substeps: int | None = None,
) -> SimulationResult:
    """Run one simulation of ``scene``.

    Parameters
    ----------
    scene : Scene
        The scene.
    history : bool
        Also return histories at the record's samples.
    record : tuple (dt_s, acceleration), optional
        A record already loaded (``records.record_arrays``); default the scene's own.
    method, dt_s, substeps : optional
        Override the scene's integrator settings.
    """
    if record is None:
        record = record_arrays(scene.load_record())
    dt_rec, acc = record
    arrays = scene.modal_arrays()
    m = method or scene.method
    outputs, contacts, hist = run_kernel(
        acc,
        dt_rec,
        **arrays,
        model=scene.contact_model,
        method=m,
        relation=scene.relation,
        dt_s=dt_s or scene.dt_s,
        substeps=substeps or scene.substeps,
        history=history,
    )
    if m != scene.method or dt_s or substeps:
        scene = replace(
            scene, method=m, dt_s=dt_s or scene.dt_s, substeps=substeps or scene.substeps
        )
    res = SimulationResult(outputs, contacts, scene)
    if hist is not None:
        hx, hd, hf = hist
        fl = scene.left.n_floors
        res.time_s = np.arange(acc.size) * dt_rec
        res.disp_left_m = hx[:, :fl]
        res.disp_right_m = hx[:, fl:]
        res.penetration_m = hd
        res.force_N = hf
    return res
