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
``saltelli``
    Saltelli's design for first- and total-order Sobol' indices, made by SALib
    (:func:`SALib.sample.sobol.sample`, ``calc_second_order=False``, scrambled, seeded by
    ``seed``): base ``N`` (a power of two) points of a ``2d``-dimensional scrambled Sobol'
    sequence, split into matrices A and B, give ``N`` blocks of ``d + 2`` rows each: A's row,
    A's row with column j taken from B's (j = 1..d), B's row.  The study's ``n`` is ``N``; it
    runs ``N (d + 2)`` samples at every grid point (:func:`saltelli_samples`), in this order,
    which :mod:`pound_mc.analysis.sensitivity` reads back.

Distributions (``[sampling.vary]`` values):

* ``{ material = "concrete" }`` for ``contact.e`` or ``contact.beta``: uniform over the seed's
  measured range (Table 2 over all velocities, or at ``velocity_m_s``; Table 3 over all ball
  masses, or at ``mass_kg``);
* ``{ distribution = "uniform", low = .., high = .. }`` (or ``{ uniform = [low, high] }``);
* ``{ distribution = "normal", mean = .., std = .. }``;
* ``{ distribution = "lognormal", median = .., sigma_ln = .. }``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from SALib.sample import sobol as salib_sobol
from scipy import stats
from scipy.stats import qmc

from pound_mc.errors import InputError, did_you_mean
from pound_mc.physics import materials
from pound_mc.scene.schema import Field, Table, check_table

__all__ = [
    "DESIGNS",
    "DISTRIBUTIONS",
    "VARY_TABLES",
    "RandomVariable",
    "design",
    "saltelli_samples",
    "is_saltelli_base",
    "parse_variable",
    "draw",
    "per_impact",
]


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


def saltelli_samples(base_n: int, d: int) -> int:
    """Samples of Saltelli's design (first and total order) of base ``base_n`` and ``d`` keys."""
    return base_n * (d + 2)


def is_saltelli_base(n: int) -> bool:
    """Whether ``n`` may be Saltelli's base N: a power of two >= 2 (SALib warns for others)."""
    return n >= 2 and not n & (n - 1)


def _saltelli_design(n: int, d: int, seed: int) -> np.ndarray:
    """Saltelli's design of ``n = N (d + 2)`` rows (SALib), in the unit cube."""
    base_n, rest = divmod(n, d + 2)
    if rest or not is_saltelli_base(base_n):  # a study refuses it first, naming sampling.n
        raise InputError(
            f"Saltelli's design needs N (d + 2) samples with N a power of two >= 2 (d = {d}), "
            f"got {n}",
            key="n",
        )
    problem = {"num_vars": d, "names": [f"x{j}" for j in range(d)], "bounds": [[0.0, 1.0]] * d}
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    return salib_sobol.sample(problem, base_n, calc_second_order=False, scramble=True, seed=rng)


#: Sampling designs by name.
DESIGNS = {
    "random": _random_design,
    "lhs": _lhs_design,
    "sobol": _sobol_design,
    "saltelli": _saltelli_design,
}


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
    method : {"random", "lhs", "sobol", "saltelli"}
        Design (see the module docstring); ``saltelli`` takes ``n`` = N (d + 2)
        (:func:`saltelli_samples`) with N a power of two.
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


#: The optional key of a material range, by the sampled key it applies to.
MATERIAL_OPTIONS = {"contact.e": "velocity_m_s", "contact.beta": "mass_kg"}


def _distribution(kind: str, description: str, a: tuple, b: tuple) -> Table:
    """The table of ``{ distribution = kind, a = .., b = .. }``; ``a``, ``b``: (name, text, > 0)."""
    params = [
        Field(name, "number", text, unit="as the key", required=True,
              minimum=0.0 if positive else None, exclusive_minimum=positive)
        for name, text, positive in (a, b)
    ]  # fmt: skip
    kind_field = Field("distribution", "string", f"`{kind}`.", required=True, choices=(kind,))
    return Table("sampling.vary.KEY", description, (kind_field, *params),
                 variant=f"distribution = '{kind}'")  # fmt: skip


#: ``[sampling.vary]`` entries: ``{ material = ... }`` and one table per distribution, whose
#: two parameters are :class:`RandomVariable` ``a`` and ``b``.
VARY_TABLES = {
    "material": Table(
        "sampling.vary.KEY",
        "Uniform over a material's measured range (Jankowski 2008): `contact.e` over Table 2, "
        "`contact.beta` over Table 3.  `material = \"grid\"` follows a `contact.material` grid "
        "axis.",
        (
            Field("material", "string", "Material of the seed's tables, or `grid`.",
                  required=True, choices=(*materials.MATERIALS, "grid")),
            Field("velocity_m_s", "number", "For `contact.e`: the range at this prior-impact "
                  "velocity (default: all velocities).", unit="m/s", minimum=0.0,
                  exclusive_minimum=True),
            Field("mass_kg", "number", "For `contact.beta`: the range at this ball mass "
                  "(default: all masses).", unit="kg", minimum=0.0, exclusive_minimum=True),
            Field("per_impact", "boolean", "For `contact.e`: each impact's e from Table 2 at its "
                  "own prior-impact velocity (`[contact] restitution = \"velocity\"` with this "
                  "material), the quantile `contact.e_quantile` sampled uniform over [0, 1]."),
        ),
        variant="material",
    ),
    "uniform": _distribution("uniform", "Uniform between `low` and `high` (> low).",
                             ("low", "Lower end.", False), ("high", "Upper end (> low).", False)),
    "normal": _distribution("normal", "Normal with `mean` and standard deviation `std`.",
                            ("mean", "Mean.", False), ("std", "Standard deviation.", True)),
    "lognormal": _distribution(
        "lognormal", "Lognormal with `median` and logarithmic standard deviation `sigma_ln`.",
        ("median", "Median.", True), ("sigma_ln", "Standard deviation of ln(value) [-].", True),
    ),
}  # fmt: skip
#: Parameters of each distribution, in the order of :class:`RandomVariable` ``a``, ``b``.
DISTRIBUTIONS = {kind: table.keys[1:] for kind, table in VARY_TABLES.items() if kind != "material"}


def _material_variable(key: str, spec: dict, where: str, file, errors: list):
    """A ``{ material = ... }`` entry: uniform over the seed's measured range."""
    material = spec["material"]
    if material not in materials.MATERIALS:
        errors.append(
            InputError(
                f"unknown material {material!r}; choose one of {list(materials.MATERIALS)}",
                file=file,
                key=f"{where}.material",
            )
        )
        return None
    if key not in MATERIAL_OPTIONS:
        errors.append(
            InputError(
                "material ranges exist only for 'contact.e' and 'contact.beta'",
                file=file,
                key=where,
            )
        )
        return None
    allowed = {"material", MATERIAL_OPTIONS[key]}
    extra = set(spec) - allowed
    if extra:
        errors.append(
            InputError(
                f"unknown keys {sorted(extra)}{did_you_mean(min(extra), allowed)}; allowed "
                f"{sorted(allowed)}",
                file=file,
                key=where,
            )
        )
        return None
    local: list[InputError] = []
    check_table(VARY_TABLES["material"], spec, file=file, prefix=f"{where}.", errors=local)
    errors.extend(local)
    if local:
        return None
    option = MATERIAL_OPTIONS[key]
    try:
        if key == "contact.e":
            if option in spec:
                lo, hi = materials.restitution_range(material, spec[option])
                source = f"{material}, Jankowski (2008) Table 2 at {spec[option]} m/s"
            else:
                lo, hi = materials.material_ranges(material)["e"]
                source = f"{material}, Jankowski (2008) Table 2, all velocities"
        elif option in spec:
            lo, hi, _ = materials.stiffness_range(material, spec[option])
            source = f"{material}, Jankowski (2008) Table 3 at {spec[option]} kg"
        else:
            lo, hi = materials.material_ranges(material)["beta"]
            source = f"{material}, Jankowski (2008) Table 3, all ball masses"
    except (InputError, TypeError) as exc:
        errors.append(InputError(str(getattr(exc, "message", exc)), file=file, key=where))
        return None
    return RandomVariable(key, "uniform", lo, hi, f"uniform over {source}")


def per_impact(vary: dict, scene: dict, file, errors: list) -> dict:
    """``contact.e = { material = NAME, per_impact = true }``: restitution set per impact.

    The scene's ``[contact]`` then takes ``restitution = "velocity"`` with that material, and
    its quantile ``contact.e_quantile`` is sampled uniform over [0, 1].  Returns ``vary``
    with that variable in place of ``contact.e``.
    """
    spec = vary.get("contact.e")
    if not (isinstance(spec, dict) and "per_impact" in spec):
        return vary
    where = "sampling.vary.contact.e"
    if spec["per_impact"] is not True:
        errors.append(
            InputError("must be true (or left out)", file=file, key=f"{where}.per_impact")
        )
        return {k: v for k, v in vary.items() if k != "contact.e"}
    material = spec.get("material")
    if material not in materials.MATERIALS or set(spec) != {"material", "per_impact"}:
        errors.append(InputError(f"per_impact takes only material, one of "
                                 f"{list(materials.MATERIALS)}", file=file, key=where))  # fmt: skip
        return {k: v for k, v in vary.items() if k != "contact.e"}
    contact = {k: v for k, v in scene.get("contact", {}).items() if k not in ("e", "xi")}
    contact.update(restitution="velocity", material=material, e_quantile=0.5)
    scene["contact"] = contact
    out = {k: v for k, v in vary.items() if k != "contact.e"}
    out["contact.e_quantile"] = {"distribution": "uniform", "low": 0.0, "high": 1.0}
    return out


def parse_variable(key: str, spec, *, file=None) -> tuple[RandomVariable | None, list]:
    """Validate one ``[sampling.vary]`` entry (:data:`VARY_TABLES`); the variable and errors."""
    errors: list[InputError] = []
    where = f"sampling.vary.{key}"
    if not isinstance(spec, dict):
        errors.append(
            InputError("must be a table such as { material = ... }", file=file, key=where)
        )
        return None, errors
    if "material" in spec:
        return _material_variable(key, spec, where, file, errors), errors
    if set(spec) == {"uniform"}:  # the shorthand { uniform = [low, high] }
        bounds = spec["uniform"]
        if not (isinstance(bounds, list) and len(bounds) == 2):
            errors.append(
                InputError(
                    "{ uniform = [low, high] } needs two numbers", file=file, key=f"{where}.uniform"
                )  # fmt: skip
            )
            return None, errors
        spec = {"distribution": "uniform", "low": bounds[0], "high": bounds[1]}
    kind = spec.get("distribution")
    known = {"distribution", "material", "uniform"}
    known.update(k for table in VARY_TABLES.values() for k in table.keys)
    unknown = [k for k in spec if k not in known]
    if kind is None and unknown:  # { dist = "uniform", ... }: the key, not a missing value
        errors.append(
            InputError(
                f"unknown key{did_you_mean(unknown[0], ['distribution', 'material'])}; a "
                "sampled variable takes 'material' or 'distribution'",
                file=file,
                key=f"{where}.{unknown[0]}",
            )
        )
        return None, errors
    if kind not in DISTRIBUTIONS:
        errors.append(
            InputError(
                f"needs 'material' or 'distribution' (one of {sorted(DISTRIBUTIONS)}), "
                f"got {kind!r}",
                file=file,
                key=f"{where}.distribution",
            )
        )
        return None, errors
    values = check_table(VARY_TABLES[kind], spec, file=file, prefix=f"{where}.", errors=errors)
    if errors:
        return None, errors
    names = DISTRIBUTIONS[kind]
    a, b = float(values[names[0]]), float(values[names[1]])
    if kind == "uniform" and not b > a:
        errors.append(InputError("needs high > low", file=file, key=f"{where}.high"))
        return None, errors
    text = ", ".join(f"{n} {v:g}" for n, v in zip(names, (a, b), strict=True))
    return RandomVariable(key, kind, a, b, f"{kind} ({text})"), errors


def draw(variables: list[RandomVariable], n: int, seed: int, method: str) -> dict[str, np.ndarray]:
    """Sample values of every variable, ``{key: array of n}``, reproducible from ``seed``."""
    u = design(n, len(variables), seed, method)
    return {v.key: v.ppf(u[:, j]) for j, v in enumerate(variables)}
