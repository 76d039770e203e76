"""pound-mc: Monte Carlo parametric studies of earthquake-induced structural pounding.

The impact physics is Jankowski's non-linear viscoelastic model (Jankowski 2008, J. Theor.
Appl. Mech. 46(3)); see :mod:`pound_mc.physics.contact`, :mod:`pound_mc.physics.relations` and
:mod:`pound_mc.physics.materials`.
"""

from __future__ import annotations

from pound_mc._version import __version__
from pound_mc.analysis import accessor as _accessor  # noqa: E402, F401  (registers ``ds.pound``)
from pound_mc.errors import InputError, InputErrors  # noqa: E402
from pound_mc.physics.contact import (  # noqa: E402
    CONTACT_MODELS,
    contact_duration_hertz,
    effective_mass,
    hertz_force,
    hertzdamp_force,
    jankowski_force,
    kelvin_force,
    linear_force,
    max_penetration_elastic,
)
from pound_mc.physics.relations import (  # noqa: E402
    RELATIONS,
    effective_restitution,
    hertzdamp_zeta,
    restitution_of_xi,
    xi_from_e,
)

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
    "max_penetration_elastic",
    "restitution_of_xi",
    "xi_from_e",
]
