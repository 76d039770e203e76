"""Speed against accuracy of every integration method (``pound-mc bench``).

For scene B1 (``studies/scenes/b1.toml``, DESIGN.md section 5) and a shear-building pair
(``studies/scenes/shear_3_5.toml``), every method runs on a ladder of step sizes (contact
sub-steps per contact duration for ``adaptive``).  Time per simulation is the median of repeated
runs after compilation, on one thread; errors are relative to a reference run: the SciPy
reference solution (:mod:`pound_mc.integrators.reference`) for B1, else ``adaptive`` with 256
sub-steps at ``dt_s`` / 10.
"""

from __future__ import annotations

import time
from pathlib import Path

import numba
import numpy as np
import pandas as pd
from tqdm import tqdm

from pound_mc.integrators import run_kernel
from pound_mc.integrators.reference import reference_solution
from pound_mc.motions import record_arrays
from pound_mc.scene import load_scene, simulate

__all__ = ["SCENES", "LADDER", "benchmark", "reference_values"]

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
