"""Random variables of a study and the designs that sample them.

A design is an ``n x d`` array of points in the unit cube; each random variable maps its
column to a physical value through its distribution's quantile function.  The same design is
used at every grid point and for every record (common random numbers), so differences across
the grid are not blurred by sampling noise.

Designs (``method``):

``random``
    Independent uniforms; sample ``i`` is drawn from its own stream
    ``SeedSequence(seed, spawn_key=(i,))``, a pure function of the seed and ``i``.
``lhs``
    Latin hypercube (:class:`scipy.stats.qmc.LatinHypercube`) seeded by ``seed``.
``sobol``
    Owen-scrambled Sobol' points (:class:`scipy.stats.qmc.Sobol`), the first ``n`` points of a
    ``2^m`` sequence, seeded by ``seed``.

Distributions (``[sampling.vary]`` values):

* ``{ material = "concrete" }`` for ``contact.e`` or ``contact.beta``: uniform over the seed's
  measured range (Table 2 over all velocities, or at ``velocity_m_s``; Table 3 over all ball
  masses, or at ``mass_kg``);
* ``{ distribution = "uniform", low = .., high = .. }``;
* ``{ distribution = "normal", mean = .., std = .. }``;
* ``{ distribution = "lognormal", median = .., sigma_ln = .. }``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import stats
from scipy.stats import qmc

from pound_mc.errors import InputError
from pound_mc.physics import materials

__all__ = ["DESIGNS", "RandomVariable", "design", "parse_variable", "draw"]


def _random_design(n: int, d: int, seed: int) -> np.ndarray:
    out = np.empty((n, d))
    for i in range(n):
        rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(i,)))
        out[i] = rng.random(d)
    return out


def _lhs_design(n: int, d: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    return qmc.LatinHypercube(d=d, rng=rng).random(n)


def _sobol_design(n: int, d: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    m = max(int(math.ceil(math.log2(n))), 0)
    return qmc.Sobol(d=d, scramble=True, rng=rng).random_base2(m)[:n]


#: Sampling designs by name.
DESIGNS = {"random": _random_design, "lhs": _lhs_design, "sobol": _sobol_design}


def design(n: int, d: int, seed: int, method: str = "sobol") -> np.ndarray:
    """Points in the unit cube, ``(n, d)``, reproducible from ``seed``.

    Parameters
    ----------
    n : int
        Number of samples (> 0).
    d : int
        Number of random variables.
    seed : int
        Root seed (>= 0).
    method : {"random", "lhs", "sobol"}
        Design (see the module docstring).
    """
    if method not in DESIGNS:
        raise InputError(
            f"unknown method {method!r}; choose one of {sorted(DESIGNS)}", key="method"
        )
    if d == 0:
        return np.empty((n, 0))
    return DESIGNS[method](n, d, seed)


@dataclass(frozen=True)
class RandomVariable:
    """One sampled scene key and the distribution it follows."""

    key: str
    kind: str  # "uniform" | "normal" | "lognormal"
    a: float  # low | mean | median
    b: float  # high | std | sigma_ln
    source: str  # human-readable description (material and table, or distribution)

    def ppf(self, u: np.ndarray) -> np.ndarray:
        """Map unit-interval points to values (quantile function)."""
        u = np.asarray(u, dtype=float)
        if self.kind == "uniform":
            return self.a + (self.b - self.a) * u
        if self.kind == "normal":
            return stats.norm.ppf(u, loc=self.a, scale=self.b)
        return self.a * np.exp(self.b * stats.norm.ppf(u))


_DISTRIBUTION_KEYS = {
    "uniform": ("low", "high"),
    "normal": ("mean", "std"),
    "lognormal": ("median", "sigma_ln"),
}


def _number(spec, name, key, file, errors):
    value = spec.get(name)
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        errors.append(InputError(f"needs a finite number {name!r}", file=file, key=key))
        return None
    return float(value)


def parse_variable(key: str, spec, *, file=None) -> tuple[RandomVariable | None, list]:
    """Validate one ``[sampling.vary]`` entry; returns the variable and a list of errors."""
    errors: list[InputError] = []
    where = f"sampling.vary.{key}"
    if not isinstance(spec, dict):
        errors.append(
            InputError("must be a table such as { material = ... }", file=file, key=where)
        )
        return None, errors
    if "material" in spec:
        material = spec["material"]
        if material not in materials.MATERIALS:
            errors.append(
                InputError(
                    f"unknown material {material!r}; choose one of {list(materials.MATERIALS)}",
                    file=file,
                    key=f"{where}.material",
                )
            )
            return None, errors
        allowed = {
            "contact.e": {"material", "velocity_m_s"},
            "contact.beta": {"material", "mass_kg"},
        }
        if key not in allowed:
            errors.append(
                InputError(
                    "material ranges exist only for 'contact.e' and 'contact.beta'",
                    file=file,
                    key=where,
                )
            )
            return None, errors
        extra = set(spec) - allowed[key]
        if extra:
            errors.append(
                InputError(
                    f"unknown keys {sorted(extra)}; allowed {sorted(allowed[key])}",
                    file=file,
                    key=where,
                )
            )
            return None, errors
        try:
            if key == "contact.e":
                if "velocity_m_s" in spec:
                    lo, hi = materials.restitution_range(material, spec["velocity_m_s"])
                    source = f"{material}, Jankowski (2008) Table 2 at {spec['velocity_m_s']} m/s"
                else:
                    lo, hi = materials.material_ranges(material)["e"]
                    source = f"{material}, Jankowski (2008) Table 2, all velocities"
            else:
                if "mass_kg" in spec:
                    lo, hi, _ = materials.stiffness_range(material, spec["mass_kg"])
                    source = f"{material}, Jankowski (2008) Table 3 at {spec['mass_kg']} kg"
                else:
                    lo, hi = materials.material_ranges(material)["beta"]
                    source = f"{material}, Jankowski (2008) Table 3, all ball masses"
        except (InputError, TypeError) as exc:
            errors.append(InputError(str(getattr(exc, "message", exc)), file=file, key=where))
            return None, errors
        return RandomVariable(key, "uniform", lo, hi, f"uniform over {source}"), errors

    kind = spec.get("distribution")
    if kind not in _DISTRIBUTION_KEYS:
        errors.append(
            InputError(
                f"needs 'material' or 'distribution' (one of {sorted(_DISTRIBUTION_KEYS)}), "
                f"got {kind!r}",
                file=file,
                key=f"{where}.distribution",
            )
        )
        return None, errors
    names = _DISTRIBUTION_KEYS[kind]
    extra = set(spec) - {"distribution", *names}
    if extra:
        errors.append(
            InputError(
                f"unknown keys {sorted(extra)}; {kind} takes {list(names)}", file=file, key=where
            )
        )
    a = _number(spec, names[0], f"{where}.{names[0]}", file, errors)
    b = _number(spec, names[1], f"{where}.{names[1]}", file, errors)
    if a is None or b is None or errors:
        return None, errors
    if kind == "uniform" and not b > a:
        errors.append(InputError("needs high > low", file=file, key=f"{where}.high"))
    if kind in ("normal", "lognormal") and not b > 0:
        errors.append(InputError("must be > 0", file=file, key=f"{where}.{names[1]}"))
    if kind == "lognormal" and not a > 0:
        errors.append(InputError("must be > 0", file=file, key=f"{where}.median"))
    if errors:
        return None, errors
    text = ", ".join(f"{n} {v:g}" for n, v in zip(names, (a, b), strict=True))
    return RandomVariable(key, kind, a, b, f"{kind} ({text})"), errors


def draw(variables: list[RandomVariable], n: int, seed: int, method: str) -> dict[str, np.ndarray]:
    """Sample values of every variable, ``{key: array of n}``, reproducible from ``seed``."""
    u = design(n, len(variables), seed, method)
    return {v.key: v.ppf(u[:, j]) for j, v in enumerate(variables)}
