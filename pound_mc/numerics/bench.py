"""Speed against accuracy of every integration method (``pound-mc bench``).

Two parts.  :func:`head_to_head` times, in one process, on one thread and interleaved (every
repeat runs each contender once, in turn, so a change of machine load hits all of them alike),
``adaptive`` at the scene's settings, ``newmark`` at dt = 1e-3 s and 1e-4 s, a textbook Newmark
loop (:func:`textbook_newmark`, this module's own code, the yardstick) at the same steps, and
the public call :func:`pound_mc.scene.simulate` with ``adaptive`` and ``newmark``; it reports
medians, peak-force errors against the SciPy reference, the ratios between them and the load
average.  :func:`benchmark` is the work-precision sweep: for scene B1
(``studies/scenes/b1.toml``, DESIGN.md section 5) and a shear-building pair
(``studies/scenes/shear_3_5.toml``), every method runs on a ladder of step sizes (contact
sub-steps per contact duration for ``adaptive``).  Time per simulation is the median of repeated
runs after compilation, on one thread; errors are relative to a reference run: the SciPy
reference solution (:mod:`pound_mc.integrators.reference`) for B1, else ``adaptive`` with 256
sub-steps at ``dt_s`` / 10.  :func:`shear_scaling` times ``adaptive`` on shear-building pairs
of growing size (3+5, 10+10, 20+20 storeys): the cost against the number of modes.
:func:`peers` times B1 in OpenSees (``JankowskiImpact``, :mod:`pound_mc.validation.opensees`)
beside ``adaptive`` (``pound-mc bench --peers``).
"""

from __future__ import annotations

import math
import os
import time
import tomllib
from pathlib import Path

import numba
import numpy as np
import pandas as pd
from tqdm import tqdm

from pound_mc.integrators import run_kernel
from pound_mc.integrators.reference import reference_solution
from pound_mc.motions import record_arrays
from pound_mc.scene import load_scene, scene_from_dict, simulate
from pound_mc.validation.opensees import opensees_run, unavailable

__all__ = [
    "SCENES",
    "LADDER",
    "CONTENDERS",
    "benchmark",
    "head_to_head",
    "peers",
    "shear_pair",
    "shear_scaling",
    "textbook_newmark",
    "reference_values",
]

_STUDIES = Path(__file__).resolve().parents[2] / "studies" / "scenes"
#: Benchmark scenes by label.
SCENES = {"B1": "b1.toml", "shear-3-5": "shear_3_5.toml"}
#: Step ladder per method: (dt_s, substeps).
LADDER = {
    "adaptive": [(0.01, s) for s in (4, 8, 16, 32, 64, 128)],
    "newmark": [(dt, 16) for dt in (2e-3, 1e-3, 5e-4, 2.5e-4, 1.25e-4, 6.25e-5)],
    "newmark-explicit": [(dt, 16) for dt in (1e-3, 5e-4, 2.5e-4, 1.25e-4, 6.25e-5)],
    "central-difference": [(dt, 16) for dt in (1e-3, 5e-4, 2.5e-4, 1.25e-4, 6.25e-5)],
}
_QUANTITIES = ("peak_force", "peak_disp_left", "peak_disp_right")


def _scene(label):
    return load_scene(_STUDIES / SCENES[label])


def reference_values(label: str, scene, record) -> tuple[dict, str]:
    """Reference peak force and displacements for a benchmark scene, and where they come from."""
    if label == "B1":
        ref = reference_solution(scene, record=record)
        return {k: ref[k] for k in (*_QUANTITIES, "impacts")}, "SciPy reference"
    res = simulate(scene, record=record, method="adaptive", dt_s=scene.dt_s / 10, substeps=256)
    return {k: res.outputs[k] for k in (*_QUANTITIES, "impacts")}, "adaptive, 256 sub-steps"


def _median_time(scene, record, method, dt_s, substeps, repeats):
    """Median time of the compiled kernel on prepared arrays, and the run's result.

    The scene's arrays are built once, as a study does for all its simulations; what is timed
    is one call of the kernel (its Python entry included).
    """
    res = simulate(scene, record=record, method=method, dt_s=dt_s, substeps=substeps)  # compile
    dt_rec, acc = record
    arrays = scene.modal_arrays()
    kw = dict(
        model=scene.contact_model,
        method=method,
        relation=scene.relation,
        dt_s=dt_s,
        substeps=substeps,
    )
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        run_kernel(acc, dt_rec, **arrays, **kw)
        times.append(time.perf_counter() - t0)
    return float(np.median(times)), res


def benchmark(scenes=("B1", "shear-3-5"), methods=None, *, repeats: int = 7, progress=True):
    """Run the work-precision benchmark.

    Returns
    -------
    pandas.DataFrame
        One row per scene, method and step: ``seconds`` (median), ``steps_per_second``,
        relative errors of ``peak_force``, ``peak_disp_left``, ``peak_disp_right``, ``impacts``
        and the reference's ``impacts``, ``status``.
    """
    methods = list(LADDER) if methods is None else list(methods)
    rows = []
    old = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        for label in scenes:
            scene = _scene(label)
            record = record_arrays(scene.load_record())
            ref, source = reference_values(label, scene, record)
            jobs = [(m, dt, sub) for m in methods for dt, sub in LADDER[m]]
            for method, dt, sub in tqdm(jobs, desc=f"bench {label}", disable=not progress):
                seconds, res = _median_time(scene, record, method, dt, sub, repeats)
                o = res.outputs
                row = {
                    "scene": label,
                    "method": method,
                    "dt_s": dt,
                    "substeps": sub if method == "adaptive" else None,
                    "seconds": seconds,
                    "steps_per_second": o["steps"] / seconds,
                    "impacts": int(o["impacts"]),
                    "reference_impacts": int(ref["impacts"]),
                    "status": res.status,
                    "reference": source,
                }
                for q in _QUANTITIES:
                    row[f"err_{q}"] = abs(o[q] - ref[q]) / abs(ref[q])
                rows.append(row)
    finally:
        numba.set_num_threads(old)
    return pd.DataFrame(rows)


# -- cost against modes ----------------------------------------------------------------------------

#: Storeys of the shear pairs of :func:`shear_scaling` (left, right).
SHEAR_SIZES = ((3, 5), (10, 10), (20, 20))


def shear_pair(n_left: int, n_right: int):
    """The shear pair of ``studies/scenes/shear_3_5.toml`` with ``n_left`` and ``n_right`` storeys.

    Storeys of 1e6 kg and 3 m; storey stiffness falling linearly up the building as in the
    scene, from 1.2e9 to 0.8e9 N/m (left) and from 0.9e9 to 0.5e9 N/m (right); the scene's
    record, contact and integrator; the contacts at every common floor.  ``shear_pair(3, 5)``
    is the scene itself.
    """
    path = _STUDIES / SCENES["shear-3-5"]
    data = tomllib.loads(path.read_text())
    for side, n, k0, k1 in (("left", n_left, 1.2e9, 0.8e9), ("right", n_right, 0.9e9, 0.5e9)):
        data[side].update({
            "storey_mass_kg": [1.0e6] * n,
            "storey_stiffness_N_per_m": [float(k) for k in np.linspace(k0, k1, n)],
            "storey_height_m": [3.0] * n,
        })  # fmt: skip
    return scene_from_dict(data, file=path)


def shear_scaling(sizes=SHEAR_SIZES, *, repeats: int = 7) -> pd.DataFrame:
    """Time ``adaptive`` on shear pairs of growing size (:func:`shear_pair`), interleaved.

    One thread; every round runs each pair once, in turn, after an untimed first run
    (compilation).  Returns one row per pair: ``storeys`` (``"3+5"``), ``modes``,
    ``contacts``, ``seconds`` (median of ``repeats`` rounds), ``us_per_mode_step`` (the time
    per mode and integration step [us]), ``steps``, ``impacts``, ``peak_force`` [N].
    """
    scenes = {f"{a}+{b}": shear_pair(a, b) for a, b in sizes}
    results = {label: simulate(sc) for label, sc in scenes.items()}  # compile, read the record
    times = {label: [] for label in scenes}
    old = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        for _ in range(repeats):
            for label, sc in scenes.items():
                t0 = time.perf_counter()
                simulate(sc)
                times[label].append(time.perf_counter() - t0)
    finally:
        numba.set_num_threads(old)
    rows = []
    for label, sc in scenes.items():
        o = results[label].outputs
        modes = sc.kernel_arrays()["omega"].size
        seconds = float(np.median(times[label]))
        rows.append({
            "storeys": label,
            "modes": modes,
            "contacts": len(sc.contacts),
            "seconds": seconds,
            "us_per_mode_step": seconds / (modes * o["steps"]) * 1e6,
            "steps": int(o["steps"]),
            "impacts": int(o["impacts"]),
            "peak_force": o["peak_force"],
        })  # fmt: skip
    return pd.DataFrame(rows)


# -- head to head on B1 ---------------------------------------------------------------------------

#: Contenders of :func:`head_to_head`: label -> (how it is called, method, dt_s or None for
#: the scene's own).  ``kernel``: :func:`pound_mc.integrators.run_kernel` on prepared arrays;
#: ``textbook``: :func:`textbook_newmark`; ``simulate``: the public
#: :func:`~pound_mc.scene.simulate`.
CONTENDERS = {
    "adaptive": ("kernel", "adaptive", None),
    "newmark dt=1e-3": ("kernel", "newmark", 1e-3),
    "newmark dt=1e-4": ("kernel", "newmark", 1e-4),
    "textbook newmark dt=1e-3": ("textbook", "newmark", 1e-3),
    "textbook newmark dt=1e-4": ("textbook", "newmark", 1e-4),
    "simulate() adaptive": ("simulate", "adaptive", None),
    "simulate() newmark dt=1e-3": ("simulate", "newmark", 1e-3),
}


# plain numba, not pound_mc._jit: the yardstick shares nothing with the package's kernels (and
# stays out of the sources that key their cache)
@numba.njit(cache=True, nogil=True)
def textbook_newmark(ag, dt_rec, m1, k1, c1, m2, k2, c2, gap, beta, xi, dt):  # pragma: no cover
    """Average-acceleration Newmark for two SDOF buildings with the Jankowski contact.

    The textbook scheme (Chopra, Dynamics of Structures, section 5.4 with Newton-Raphson
    iteration): constant step ``dt``, the record linearly interpolated at the steps, the
    contact force F = beta delta^1.5 + c delta_dot while approaching (Jankowski 2008,
    eq. 1.1), solved with the displacements by Newton's method in every step; peak force
    over the steps.

    Parameters
    ----------
    ag : numpy.ndarray
        Ground acceleration at the record's samples [m/s^2].
    dt_rec, dt : float
        Record's sample interval and integration step [s].
    m1, k1, c1, m2, k2, c2 : float
        Mass [kg], stiffness [N/m] and damping [N s/m] of the left and right building.
    gap, beta, xi : float
        Gap [m], impact stiffness [N/m^1.5] and impact damping ratio [-].

    Returns
    -------
    tuple of float
        Peak force [N], number of impacts, peak |displacement| of the left and right
        building [m].
    """
    n = int(round((ag.size - 1) * dt_rec / dt))
    mr = m1 * m2 / (m1 + m2)
    a0 = 4.0 / (dt * dt)
    a1 = 2.0 / dt
    kh1 = a0 * m1 + a1 * c1 + k1
    kh2 = a0 * m2 + a1 * c2 + k2
    x1 = v1 = x2 = v2 = 0.0
    acc1 = -ag[0]
    acc2 = -ag[0]
    peak = 0.0
    impacts = 0
    was_in = False
    u1max = 0.0
    u2max = 0.0
    for i in range(1, n + 1):
        t = i * dt / dt_rec
        j = min(int(t), ag.size - 2)
        g = ag[j] + (t - j) * (ag[j + 1] - ag[j])
        p1 = -m1 * g + m1 * (a0 * x1 + 4.0 / dt * v1 + acc1) + c1 * (a1 * x1 + v1)
        p2 = -m2 * g + m2 * (a0 * x2 + 4.0 / dt * v2 + acc2) + c2 * (a1 * x2 + v2)
        y1 = x1
        y2 = x2
        f = 0.0
        for _ in range(50):
            d = y1 - y2 - gap
            w = a1 * (y1 - x1) - v1 - (a1 * (y2 - x2) - v2)  # delta_dot at the step's end
            f = 0.0
            kt = 0.0
            if d > 0.0:
                sd = math.sqrt(d)
                f = beta * d * sd
                kt = 1.5 * beta * sd
                if w > 0.0:
                    c = 2.0 * xi * math.sqrt(beta * sd * mr)
                    f += c * w
                    kt += c * w / (4.0 * d) + c * a1
            r1 = kh1 * y1 + f - p1
            r2 = kh2 * y2 - f - p2
            j11 = kh1 + kt
            j22 = kh2 + kt
            det = j11 * j22 - kt * kt
            dy1 = -(j22 * r1 + kt * r2) / det
            dy2 = -(kt * r1 + j11 * r2) / det
            y1 += dy1
            y2 += dy2
            if abs(dy1) + abs(dy2) <= 1e-12 * (abs(y1) + abs(y2) + gap):
                break
        w1 = a1 * (y1 - x1) - v1
        w2 = a1 * (y2 - x2) - v2
        acc1 = a0 * (y1 - x1) - 4.0 / dt * v1 - acc1
        acc2 = a0 * (y2 - x2) - 4.0 / dt * v2 - acc2
        x1, v1, x2, v2 = y1, w1, y2, w2
        inside = x1 - x2 - gap > 0.0
        if inside and not was_in:
            impacts += 1
        was_in = inside
        peak = max(peak, f)
        u1max = max(u1max, abs(x1))
        u2max = max(u2max, abs(x2))
    return peak, impacts, u1max, u2max


def _textbook_args(scene, record, dt):
    """Arguments of :func:`textbook_newmark` for an SDOF-pair scene."""
    dt_rec, acc = record
    args = []
    for b in (scene.left, scene.right):
        m = float(b.storey_mass_kg[0])
        k = float(b.storey_stiffness_N_per_m[0])
        args += [m, k, 2.0 * b.damping_ratio * math.sqrt(k * m)]
    return (acc, float(dt_rec), *args, float(scene.gap_m[0]), float(scene.stiffness),
            float(scene.xi), float(dt))  # fmt: skip


def head_to_head(repeats: int = 15, contenders=None) -> tuple[pd.DataFrame, dict]:
    """Time the :data:`CONTENDERS` on B1, interleaved, one thread; medians and ratios.

    Every contender runs once before timing (compilation, the scene's cached record), then
    ``repeats`` rounds each run every contender twice in turn and time the second call.

    Returns
    -------
    table : pandas.DataFrame
        One row per contender: ``label``, ``call``, ``method``, ``dt_s``, ``seconds``
        (median), ``x_adaptive`` (its time over the ``adaptive`` kernel's, or for the public
        calls over ``simulate()`` with ``adaptive``), ``peak_force`` [N], ``err_peak_force``
        (relative, against the SciPy reference), ``impacts``.
    info : dict
        ``load_before`` and ``load_after`` (``os.getloadavg()``), ``reference_peak_force``,
        ``repeats`` and the ``ratios`` named in words: the median over the rounds of one
        contender's time over the other's in the same round (the table's ``x_adaptive`` is the
        ratio of the medians).
    """
    labels = list(CONTENDERS) if contenders is None else list(contenders)
    scene = _scene("B1")
    record = scene.record_arrays()
    dt_rec, acc = record
    arrays = scene.kernel_arrays()
    ref = reference_solution(scene, record=record)
    kw = dict(model=scene.contact_model, relation=scene.relation, substeps=scene.substeps)

    def call(label):
        how, method, dt = CONTENDERS[label]
        if how == "kernel":
            o = run_kernel(acc, dt_rec, **arrays, method=method, dt_s=dt or scene.dt_s, **kw)
            return o.outputs["peak_force"], o.outputs["impacts"]
        if how == "simulate":
            o = simulate(scene, method=method, dt_s=dt)
            return o.outputs["peak_force"], o.outputs["impacts"]
        peak, impacts, _, _ = textbook_newmark(*_textbook_args(scene, record, dt))
        return peak, impacts

    load_before = os.getloadavg()
    old = numba.get_num_threads()
    times = {label: [] for label in labels}
    try:
        numba.set_num_threads(1)
        results = {label: call(label) for label in labels}  # compile, read the record
        for _ in range(repeats):
            for label in labels:
                # each timed call follows an untimed one of the same contender, as in a study's
                # loop over simulations: the previous contender's code and data are not what
                # the caches hold (measured: up to 0.3 ms more for the call after a 12-ms one)
                call(label)
                t0 = time.perf_counter()
                call(label)
                times[label].append(time.perf_counter() - t0)
    finally:
        numba.set_num_threads(old)
    med = {label: float(np.median(times[label])) for label in labels}
    rows = []
    for label in labels:
        how, method, dt = CONTENDERS[label]
        base = "simulate() adaptive" if how == "simulate" else "adaptive"
        peak, impacts = results[label]
        rows.append({
            "label": label,
            "call": how,
            "method": method,
            "dt_s": dt or scene.dt_s,
            "seconds": med[label],
            "x_adaptive": med[label] / med[base] if base in med else float("nan"),
            "peak_force": float(peak),
            "err_peak_force": abs(peak - ref["peak_force"]) / ref["peak_force"],
            "impacts": int(impacts),
        })  # fmt: skip

    def ratio(a, b):
        # paired, as the overheads below: the load a round's two calls share cancels
        if a not in med or b not in med:
            return None
        return float(np.median(np.divide(times[a], times[b])))

    ratios = {
        "newmark dt=1e-3 / adaptive": ratio("newmark dt=1e-3", "adaptive"),
        "newmark dt=1e-4 / adaptive": ratio("newmark dt=1e-4", "adaptive"),
        "textbook dt=1e-3 / newmark dt=1e-3": ratio("textbook newmark dt=1e-3", "newmark dt=1e-3"),
        "textbook dt=1e-4 / newmark dt=1e-4": ratio("textbook newmark dt=1e-4", "newmark dt=1e-4"),
        "simulate() newmark / simulate() adaptive": ratio(
            "simulate() newmark dt=1e-3", "simulate() adaptive"
        ),
    }
    # paired: the difference within each round, so that load common to the round cancels
    overhead = {
        f"simulate() overhead {m} [ms]": float(np.median(np.subtract(times[s], times[k])) * 1e3)
        for m, s, k in (
            ("adaptive", "simulate() adaptive", "adaptive"),
            ("newmark dt=1e-3", "simulate() newmark dt=1e-3", "newmark dt=1e-3"),
        )
        if s in med and k in med
    }
    info = {
        "repeats": repeats,
        "threads": 1,
        "load_before": list(load_before),
        "load_after": list(os.getloadavg()),
        "reference_peak_force": float(ref["peak_force"]),
        "ratios": {k: v for k, v in ratios.items() if v is not None},
        "overheads": overhead,
    }
    return pd.DataFrame(rows), info


# -- B1 in other tools ----------------------------------------------------------------------------

#: OpenSees's steps in :func:`peers` [s].
PEER_STEPS = (1.0e-3, 1.0e-4)


def peers(repeats: int = 7, steps=None) -> tuple[pd.DataFrame, dict]:
    """Time B1 in pound-mc ``adaptive`` and in OpenSees at each of ``steps``, interleaved.

    One process, one numba thread; every contender runs once untimed (compilation, the
    record, openseespy's import), then each of ``repeats`` rounds runs every contender in
    turn.  pound-mc's kernel runs twice in a round and the second call is timed, as in
    :func:`head_to_head` (a 0.1-ms call just after a 100-ms one would be timed with cold
    caches); an OpenSees run is timed whole: building the model
    (:func:`pound_mc.validation.opensees.opensees_run`), ``analyze`` and reading its
    recorders (``analyze`` alone in ``analyze_seconds``).  Errors are relative to the SciPy
    reference (:mod:`pound_mc.integrators.reference`).  Without openseespy only pound-mc's
    rows are made, and ``info["opensees_reason"]`` says why.  ``steps``: OpenSees's steps
    [s], default :data:`PEER_STEPS`.

    Returns
    -------
    table : pandas.DataFrame
        One row per contender: ``label``, ``tool``, ``method``, ``dt_s``, ``seconds``
        (median), ``analyze_seconds`` (OpenSees; NaN for pound-mc), ``x_adaptive`` (over
        pound-mc's ``adaptive``), ``peak_force`` [N], ``err_peak_force``,
        ``err_peak_disp_left``, ``err_peak_disp_right`` (relative), ``impacts``.
    info : dict
        ``repeats``, ``threads``, ``load_before`` and ``load_after`` (``os.getloadavg()``),
        ``reference_peak_force``, ``reference_impacts``, ``opensees_reason`` (None when
        OpenSees ran).
    """
    scene = _scene("B1")
    record = scene.record_arrays()
    dt_rec, acc = record
    arrays = scene.kernel_arrays()
    ref = reference_solution(scene, record=record)
    reason = unavailable()
    contenders = {"pound-mc adaptive": ("pound-mc", "adaptive", scene.dt_s)}
    if reason is None:
        contenders |= {f"OpenSees dt={dt:g}": ("OpenSees", "newmark", float(dt))
                       for dt in (PEER_STEPS if steps is None else steps)}  # fmt: skip
    kw = dict(model=scene.contact_model, relation=scene.relation, substeps=scene.substeps)

    def call(label):
        tool, method, dt = contenders[label]
        if tool == "OpenSees":
            return opensees_run(scene, dt, record=record)
        o = run_kernel(acc, dt_rec, **arrays, method=method, dt_s=dt, **kw).outputs
        return {**o, "seconds": math.nan}

    load_before = os.getloadavg()
    old = numba.get_num_threads()
    times = {label: [] for label in contenders}
    analyze = {label: [] for label in contenders}
    try:
        numba.set_num_threads(1)
        results = {label: call(label) for label in contenders}
        for _ in range(repeats):
            for label, (tool, _m, _dt) in contenders.items():
                if tool == "pound-mc":
                    call(label)
                t0 = time.perf_counter()
                out = call(label)
                times[label].append(time.perf_counter() - t0)
                analyze[label].append(out["seconds"])
    finally:
        numba.set_num_threads(old)
    base = float(np.median(times["pound-mc adaptive"]))
    rows = []
    for label, (tool, method, dt) in contenders.items():
        o = results[label]
        seconds = float(np.median(times[label]))
        rows.append({
            "label": label,
            "tool": tool,
            "method": method,
            "dt_s": dt,
            "seconds": seconds,
            "analyze_seconds": float(np.median(analyze[label])),
            "x_adaptive": seconds / base,
            "peak_force": float(o["peak_force"]),
            **{f"err_{q}": abs(o[q] - ref[q]) / abs(ref[q]) for q in _QUANTITIES},
            "impacts": int(o["impacts"]),
        })  # fmt: skip
    info = {
        "repeats": repeats,
        "threads": 1,
        "load_before": list(load_before),
        "load_after": list(os.getloadavg()),
        "reference_peak_force": float(ref["peak_force"]),
        "reference_impacts": int(ref["impacts"]),
        "opensees_reason": reason,
    }
    return pd.DataFrame(rows), info
