"""pound-mc: Monte Carlo parametric studies of earthquake-induced structural pounding.

The entry points::

    import pound_mc

    result = pound_mc.simulate("studies/scenes/b1.toml")  # one simulation
    result.outputs["peak_force"]  # [N]
    report = pound_mc.run_study("studies/quickstart.toml", out="outputs")  # a study
    ds = pound_mc.open_dataset(report.path)  # its dataset, with ds.pound registered

The impact physics is Jankowski's non-linear viscoelastic model (Jankowski 2008, J. Theor.
Appl. Mech. 46(3)); see :mod:`pound_mc.physics.contact`, :mod:`pound_mc.physics.relations` and
:mod:`pound_mc.physics.materials`.

``import pound_mc`` registers the ``ds.pound`` accessor and loads xarray, nothing heavier: the
kernels (numba), the analysis (scipy) and the charts (matplotlib) load when first used, and
the names below are imported from their modules on first access (PEP 562).
"""

from __future__ import annotations

import importlib
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pound_mc._version import __version__
from pound_mc.analysis import accessor as _accessor  # noqa: F401  (registers ``ds.pound``)
from pound_mc.errors import InputError, InputErrors

if TYPE_CHECKING:
    from pound_mc.scene import Scene, SimulationResult
    from pound_mc.study.definition import Study
    from pound_mc.study.runner import RunReport

#: Public names imported from their modules on first access: name -> module.
_LAZY = {
    "CONTACT_MODELS": "pound_mc.physics.contact",
    "contact_duration_hertz": "pound_mc.physics.contact",
    "effective_mass": "pound_mc.physics.contact",
    "hertz_force": "pound_mc.physics.contact",
    "hertzdamp_force": "pound_mc.physics.contact",
    "jankowski_force": "pound_mc.physics.contact",
    "kelvin_force": "pound_mc.physics.contact",
    "linear_force": "pound_mc.physics.contact",
    "max_penetration_elastic": "pound_mc.physics.contact",
    "RELATIONS": "pound_mc.physics.relations",
    "effective_restitution": "pound_mc.physics.relations",
    "hertzdamp_zeta": "pound_mc.physics.relations",
    "restitution_of_xi": "pound_mc.physics.relations",
    "xi_from_e": "pound_mc.physics.relations",
    "load_scene": "pound_mc.scene",
    "load_study": "pound_mc.study.definition",
    "open_dataset": "pound_mc.study.dataset",
}

__all__ = [
    "__version__",
    "CONTACT_MODELS",
    "RELATIONS",
    "InputError",
    "InputErrors",
    "contact_duration_hertz",
    "effective_mass",
    "effective_restitution",
    "hertz_force",
    "hertzdamp_force",
    "hertzdamp_zeta",
    "jankowski_force",
    "kelvin_force",
    "linear_force",
    "load_scene",
    "load_study",
    "max_penetration_elastic",
    "open_dataset",
    "restitution_of_xi",
    "run_study",
    "simulate",
    "xi_from_e",
]


def __getattr__(name: str) -> Any:
    """A public name of :data:`_LAZY`, imported from its module now (PEP 562)."""
    if name not in _LAZY:
        raise AttributeError(f"module 'pound_mc' has no attribute {name!r}")
    value = getattr(importlib.import_module(_LAZY[name]), name)
    globals()[name] = value  # once: later lookups find it without this function
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


def simulate(scene_or_path: Scene | str | Path, **overrides: Any) -> SimulationResult:
    """Run one simulation: a scene, or the scene file at a path.

    Parameters
    ----------
    scene_or_path : pound_mc.scene.Scene, str or Path
        A scene (:func:`load_scene`) or the path of a scene file (TOML: ``[record]``,
        ``[left]``, ``[right]``, ``[contact]``, ``[integrator]``).  A path is read on every
        call; in a loop, load the scene once: it keeps its record and modal arrays.
    **overrides
        The keywords of :func:`pound_mc.scene.simulate`: ``history`` (also return the time
        histories), ``method``, ``dt_s`` [s] and ``substeps`` (the integrator's settings,
        within the scene file's bounds).

    Returns
    -------
    pound_mc.scene.SimulationResult
        ``outputs`` (``peak_force`` [N], ``impacts``, ``peak_disp_left`` [m], ...),
        ``status`` and, with ``history=True``, ``time_s``, ``disp_left_m``, ``force_N``, ...

    Raises
    ------
    pound_mc.errors.InputError
        A scene file that cannot be read or is not valid, or an override out of bounds; the
        message names the file and the key.
    """
    from pound_mc.scene import Scene, load_scene
    from pound_mc.scene import simulate as simulate_scene

    scene = scene_or_path if isinstance(scene_or_path, Scene) else load_scene(scene_or_path)
    return simulate_scene(scene, **overrides)


def run_study(
    path_or_study: Study | str | Path,
    out: str | Path = "outputs",
    *,
    threads: int | None = None,
    **options: Any,
) -> RunReport:
    """Run every simulation of a study and write ``<out>/<name>.nc``, as ``pound-mc run`` does.

    Parameters
    ----------
    path_or_study : pound_mc.study.definition.Study, str or Path
        A study (:func:`load_study`) or the path of a study file.
    out : str or Path
        Output folder; the chunk files of a run in progress go to ``<out>/<name>/`` and an
        interrupted run resumes from them.
    threads : int, optional
        Threads of the compiled kernels (default: every core).
    **options
        The keywords of :func:`pound_mc.study.runner.run_study`: ``fresh`` (discard earlier
        results), ``chunk_size``, ``progress`` (a progress bar, default true).

    Returns
    -------
    pound_mc.study.runner.RunReport
        ``path`` of the dataset (open it with :func:`open_dataset`), ``n_simulations``,
        ``seconds``, ``complete``, ...

    Notes
    -----
    The charts are not drawn here: ``ds.pound.plot`` draws them from the dataset.
    """
    from pound_mc.study.definition import Study, load_study
    from pound_mc.study.runner import run_study as run

    study = path_or_study if isinstance(path_or_study, Study) else load_study(path_or_study)
    return run(study, out, threads=threads, **options)
