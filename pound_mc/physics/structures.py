"""Structural models of the two buildings: SDOF oscillators and shear buildings.

Both are described to the integrators by their classical modes: mass-normalised mode shapes
``phi`` (floors x modes, ``phi.T @ M @ phi = I``), circular frequencies ``omega`` [rad/s],
damping ratios ``zeta`` [-] (the building's damping ratio in every mode: classical damping) and
participation factors ``gamma = phi.T @ M @ 1`` [kg^0.5], so that each modal coordinate obeys
``q'' + 2 zeta omega q' + omega^2 q = -gamma a_g(t) + phi.T @ f(t)``.  Floor displacements are
``x = phi @ q``, relative to the ground, positive to the right.

Contacts (``../shared/DESIGN.md`` section 6): an SDOF pair has one contact between the two
masses; with shear buildings every pair of floors at equal height can pound, each with its own
gap, and the masses that meet are the two storey masses.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from pound_mc._docstring import fill
from pound_mc.errors import InputError, did_you_mean

__all__ = [
    "Building",
    "Contact",
    "sdof",
    "shear_building",
    "building_from_dict",
    "contacts_between",
    "HYSTERESIS",
    "wall",
]

#: Hysteresis laws of a building's storeys (DESIGN.md section 9); the first is the default.
HYSTERESIS = ("elastic", "bilinear", "bouc-wen")

#: Floors whose elevations differ by less than this are at equal height [m].
HEIGHT_TOLERANCE_M = 1e-6

#: Keyword descriptions :func:`sdof` and :func:`shear_building` share (``%(name)s`` lines).
_keyword_doc = fill(
    bw_exponent="bw_exponent : float, optional\n    Bouc-Wen exponent ``n`` [-] (default 2)."
)


@dataclass(frozen=True)
class Building:
    """A linear building model with classical damping.

    Attributes
    ----------
    model : {"sdof", "shear", "wall"}
        Kind of model (``wall``: rigid and immovable, one "floor" of infinite mass and no
        modes).
    storey_mass_kg : numpy.ndarray
        Floor masses, bottom to top [kg].
    storey_stiffness_N_per_m : numpy.ndarray
        Storey (inter-floor) stiffnesses, bottom to top [N/m].
    elevation_m : numpy.ndarray or None
        Floor elevations above the ground [m] (``None`` for an SDOF without a height).
    damping_ratio : float
        Damping ratio of every mode [-].
    hysteresis : {"elastic", "bilinear", "bouc-wen"}
        Storey law: linear elastic, bilinear with kinematic hardening (storey force
        ``alpha k u + (1 - alpha) k z``, ``z`` elastic-perfectly-plastic with ``|z| <= u_y``),
        or Bouc-Wen (same force, ``z`` [m] smooth:
        ``z' = u' (A - |z / u_y|^n (beta_bw sign(u' z) + gamma_bw))`` with ``A = 1``,
        ``beta_bw = gamma_bw = 0.5``, so that ``|z| -> u_y`` as in the bilinear law; no
        stiffness or strength degradation, no pinching).  The modes, and the damping built
        from them, are those of the initial elastic building.
    yield_disp_m : numpy.ndarray or None
        Storey drift at yield ``u_y`` per storey [m] (inelastic only).
    post_yield_ratio : float
        Post-yield stiffness over the elastic stiffness ``alpha`` [-] (inelastic only).
    bw_exponent : float
        Bouc-Wen exponent ``n`` [-] (sharpness of the transition to yield; large ``n``
        approaches the bilinear law), Bouc-Wen only.
    """

    model: str
    storey_mass_kg: np.ndarray
    storey_stiffness_N_per_m: np.ndarray
    elevation_m: np.ndarray | None
    damping_ratio: float
    omega: np.ndarray = field(init=False, repr=False)
    phi: np.ndarray = field(init=False, repr=False)
    gamma: np.ndarray = field(init=False, repr=False)
    hysteresis: str = "elastic"
    yield_disp_m: np.ndarray | None = None
    post_yield_ratio: float = 0.0
    bw_exponent: float = 2.0

    def __post_init__(self):
        if self.model == "wall":
            object.__setattr__(self, "omega", np.zeros(0))
            object.__setattr__(self, "phi", np.zeros((1, 0)))
            object.__setattr__(self, "gamma", np.zeros(0))
            return
        omega, phi = _modes(self.mass_matrix(), self.stiffness_matrix())
        gamma = phi.T @ self.storey_mass_kg
        object.__setattr__(self, "omega", omega)
        object.__setattr__(self, "phi", phi)
        object.__setattr__(self, "gamma", gamma)

    @property
    def n_floors(self) -> int:
        """Number of floors (degrees of freedom)."""
        return int(self.storey_mass_kg.size)

    @property
    def inelastic(self) -> bool:
        """Whether the storeys can yield (a hysteresis other than ``"elastic"``)."""
        return self.hysteresis != "elastic"

    @property
    def storey_height_m(self) -> np.ndarray:
        """Storey heights [m], bottom to top (NaN for an SDOF without a height)."""
        if self.elevation_m is None:
            return np.full(self.n_floors, np.nan)
        return np.diff(np.r_[0.0, self.elevation_m])

    def drift_matrix(self) -> np.ndarray:
        """Storey drifts over floor displacements ``u = B x`` (storeys x floors)."""
        n = self.n_floors
        return np.eye(n) - np.eye(n, k=-1)

    @property
    def periods_s(self) -> np.ndarray:
        """Natural periods [s], longest first."""
        return 2.0 * np.pi / self.omega

    def mass_matrix(self) -> np.ndarray:
        """Diagonal mass matrix [kg]."""
        return np.diag(self.storey_mass_kg)

    def stiffness_matrix(self) -> np.ndarray:
        """Shear-building stiffness matrix [N/m] (tridiagonal)."""
        k = self.storey_stiffness_N_per_m
        n = k.size
        mat = np.zeros((n, n))
        if self.model == "wall":
            return mat  # immovable: no storey spring
        for i in range(n):
            mat[i, i] += k[i]
            if i + 1 < n:
                mat[i, i] += k[i + 1]
                mat[i, i + 1] = mat[i + 1, i] = -k[i + 1]
        return mat

    def damping_matrix(self) -> np.ndarray:
        """Classical damping matrix ``M phi diag(2 zeta omega) phi.T M`` [N s/m]."""
        if self.model == "wall":
            return np.zeros((1, 1))
        m = self.mass_matrix()
        return m @ self.phi @ np.diag(2.0 * self.damping_ratio * self.omega) @ self.phi.T @ m


def _modes(m: np.ndarray, k: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mass-normalised modes of ``K phi = omega^2 M phi`` with ``M`` diagonal."""
    m_half = np.sqrt(np.diag(m))
    a = k / np.outer(m_half, m_half)
    w2, vecs = np.linalg.eigh(a)
    phi = vecs / m_half[:, None]
    # a deterministic sign: the top floor moves positively in every mode
    signs = np.where(phi[-1, :] < 0.0, -1.0, 1.0)
    return np.sqrt(w2), phi * signs


def _check_positive(values, *, key: str, file=None) -> np.ndarray:
    vals = values if isinstance(values, list | tuple) else [values]
    if not vals or not all(isinstance(x, int | float) and not isinstance(x, bool) for x in vals):
        raise InputError(
            f"must be a number or a list of numbers, got {values!r}", file=file, key=key
        )
    arr = np.atleast_1d(np.asarray(values, dtype=float))
    if arr.ndim != 1 or arr.size == 0:
        raise InputError("must be a number or a non-empty list of numbers", file=file, key=key)
    if not np.all(np.isfinite(arr)) or np.any(arr <= 0.0):
        raise InputError(f"must be finite and > 0, got {values!r}", file=file, key=key)
    return arr


def _check_damping(value, *, key: str, file=None) -> float:
    if not (isinstance(value, int | float) and 0.0 <= value < 1.0):
        raise InputError(
            f"must be a number in [0, 1) (underdamped modes), got {value!r}", file=file, key=key
        )
    return float(value)


def _hysteresis(
    hysteresis, yield_disp, ratio, n: int, *, yield_key: str, file, prefix: str, exponent=None
):
    """Checked ``(hysteresis, yield drifts [m] or None, post-yield ratio, Bouc-Wen exponent)``."""
    if hysteresis not in HYSTERESIS:
        raise InputError(
            f"unknown hysteresis {hysteresis!r}; allowed: {', '.join(map(repr, HYSTERESIS))}",
            file=file,
            key=f"{prefix}hysteresis",
        )
    if hysteresis == "elastic":
        for key, value in ((yield_key, yield_disp), ("post_yield_ratio", ratio)):
            if value is not None:
                raise InputError(
                    "applies only to hysteresis = 'bilinear' or 'bouc-wen'",
                    file=file,
                    key=prefix + key,
                )
    if hysteresis != "bouc-wen" and exponent is not None:
        raise InputError(
            "applies only to hysteresis = 'bouc-wen'", file=file, key=prefix + "bw_exponent"
        )
    if hysteresis == "elastic":
        return "elastic", None, 0.0, 2.0
    if yield_disp is None:
        raise InputError(
            f"is required for hysteresis = {hysteresis!r}", file=file, key=prefix + yield_key
        )
    uy = _check_positive(yield_disp, key=prefix + yield_key, file=file)
    if uy.size == 1:
        uy = np.full(n, uy[0])
    elif uy.size != n:
        raise InputError(
            f"gives {uy.size} yield drifts for {n} storeys", file=file, key=prefix + yield_key
        )
    ratio = 0.0 if ratio is None else ratio
    if not (isinstance(ratio, int | float) and not isinstance(ratio, bool) and 0 <= ratio < 1):
        raise InputError(
            f"must be a number in [0, 1), got {ratio!r}", file=file, key=prefix + "post_yield_ratio"
        )
    exponent = 2.0 if exponent is None else exponent
    if not (
        isinstance(exponent, int | float)
        and not isinstance(exponent, bool)
        and 1.0 <= exponent <= 50.0
    ):
        raise InputError(
            f"must be a number in [1, 50], got {exponent!r}", file=file, key=prefix + "bw_exponent"
        )
    return hysteresis, uy, float(ratio), float(exponent)


@_keyword_doc
def sdof(
    period_s: float,
    mass_kg: float,
    damping_ratio: float = 0.05,
    height_m: float | None = None,
    *,
    hysteresis: str = "elastic",
    yield_disp_m: float | None = None,
    post_yield_ratio: float | None = None,
    file=None,
    prefix: str = "",
    bw_exponent: float | None = None,
) -> Building:
    """Single-degree-of-freedom building.

    Its storey stiffness follows from the period and the mass: ``k = m (2 pi / T)^2`` [N/m].

    Parameters
    ----------
    period_s : float
        Natural period [s].
    mass_kg : float
        Mass [kg].
    damping_ratio : float
        Viscous damping ratio [-].
    height_m : float, optional
        Height of the mass [m]; needed only to pair it with a shear building's floors.
    hysteresis : {"elastic", "bilinear", "bouc-wen"}
        Law of the storey (:class:`Building`).
    yield_disp_m : float, optional
        Displacement at yield [m] (bilinear, Bouc-Wen).
    post_yield_ratio : float, optional
        Post-yield over elastic stiffness [-] (bilinear, Bouc-Wen; default 0:
        elastic-perfectly-plastic).
    %(bw_exponent)s
    """
    t = _check_positive(period_s, key=f"{prefix}period_s", file=file)[0]
    m = _check_positive(mass_kg, key=f"{prefix}mass_kg", file=file)[0]
    z = _check_damping(damping_ratio, key=f"{prefix}damping_ratio", file=file)
    elevation = None
    if height_m is not None:
        elevation = _check_positive(height_m, key=f"{prefix}height_m", file=file)
    k = m * (2.0 * math.pi / t) ** 2
    hyst = _hysteresis(hysteresis, yield_disp_m, post_yield_ratio, 1, yield_key="yield_disp_m",
                       file=file, prefix=prefix, exponent=bw_exponent)  # fmt: skip
    return Building("sdof", np.array([m]), np.array([k]), elevation, z, *hyst)


@_keyword_doc
def shear_building(
    storey_mass_kg,
    storey_stiffness_N_per_m,
    storey_height_m,
    damping_ratio: float = 0.05,
    *,
    hysteresis: str = "elastic",
    storey_yield_disp_m=None,
    post_yield_ratio: float | None = None,
    file=None,
    prefix: str = "",
    bw_exponent: float | None = None,
) -> Building:
    """Shear building (lumped storey masses, storey shear springs, classical damping).

    Parameters
    ----------
    storey_mass_kg : array_like
        Floor masses, bottom to top [kg].
    storey_stiffness_N_per_m : array_like
        Storey stiffnesses, bottom to top [N/m].
    storey_height_m : array_like
        Storey heights, bottom to top [m]; floor elevations are their cumulative sums.
    damping_ratio : float
        Damping ratio of every mode [-].
    hysteresis : {"elastic", "bilinear", "bouc-wen"}
        Law of the storeys (:class:`Building`).
    storey_yield_disp_m : array_like, optional
        Inter-storey drift at yield per storey (or one for all) [m] (bilinear, Bouc-Wen).
    post_yield_ratio : float, optional
        Post-yield over elastic stiffness [-] (bilinear, Bouc-Wen; default 0).
    %(bw_exponent)s
    """
    m = _check_positive(storey_mass_kg, key=f"{prefix}storey_mass_kg", file=file)
    k = _check_positive(
        storey_stiffness_N_per_m, key=f"{prefix}storey_stiffness_N_per_m", file=file
    )
    h = _check_positive(storey_height_m, key=f"{prefix}storey_height_m", file=file)
    if not (m.size == k.size == h.size):
        raise InputError(
            f"storey lists differ in length (masses {m.size}, stiffnesses {k.size}, "
            f"heights {h.size})",
            file=file,
            key=f"{prefix}storey_mass_kg",
        )
    z = _check_damping(damping_ratio, key=f"{prefix}damping_ratio", file=file)
    hyst = _hysteresis(hysteresis, storey_yield_disp_m, post_yield_ratio, m.size,
                       yield_key="storey_yield_disp_m", file=file, prefix=prefix,
                       exponent=bw_exponent)  # fmt: skip
    return Building("shear", m, k, np.cumsum(h), z, *hyst)


def wall(height_m: float | None = None, *, file=None, prefix: str = "") -> Building:
    """A rigid, immovable wall (a moat wall, an abutment): infinite mass, no modes.

    Its one "floor" stays at the ground's displacement; a contact with it has the effective
    mass of the building's floor (``m_eff = m1``).

    Parameters
    ----------
    height_m : float, optional
        Height of the wall's top [m]: it meets the other building's floors at or below it
        (default: only its lowest floor).
    """
    elevation = None
    if height_m is not None:
        elevation = _check_positive(height_m, key=f"{prefix}height_m", file=file)
    return Building("wall", np.array([np.inf]), np.array([np.inf]), elevation, 0.0)


def building_from_dict(spec: dict, *, file=None, side: str = "left") -> Building:
    """Build a :class:`Building` from a scene file's ``[left]`` or ``[right]`` table."""
    prefix = f"{side}."
    model = spec.get("model", "sdof")
    # the storeys' law and where errors point: alike for both models
    common = {
        "hysteresis": spec.get("hysteresis", "elastic"),
        "post_yield_ratio": spec.get("post_yield_ratio"),
        "file": file,
        "prefix": prefix,
        "bw_exponent": spec.get("bw_exponent"),
    }
    if model == "sdof":
        allowed = {"model", "period_s", "mass_kg", "damping_ratio", "height_m", "hysteresis",
                   "yield_disp_m", "post_yield_ratio", "bw_exponent"}  # fmt: skip
        _unknown(spec, allowed, file=file, prefix=prefix)
        for key in ("period_s", "mass_kg"):
            if key not in spec:
                raise InputError("is required for model = 'sdof'", file=file, key=prefix + key)
        return sdof(
            spec["period_s"],
            spec["mass_kg"],
            spec.get("damping_ratio", 0.05),
            spec.get("height_m"),
            yield_disp_m=spec.get("yield_disp_m"),
            **common,
        )
    if model == "shear":
        allowed = {
            "model",
            "storey_mass_kg",
            "storey_stiffness_N_per_m",
            "storey_height_m",
            "damping_ratio",
            "hysteresis",
            "storey_yield_disp_m",
            "post_yield_ratio",
            "bw_exponent",
        }
        _unknown(spec, allowed, file=file, prefix=prefix)
        for key in ("storey_mass_kg", "storey_stiffness_N_per_m", "storey_height_m"):
            if key not in spec:
                raise InputError("is required for model = 'shear'", file=file, key=prefix + key)
        return shear_building(
            spec["storey_mass_kg"],
            spec["storey_stiffness_N_per_m"],
            spec["storey_height_m"],
            spec.get("damping_ratio", 0.05),
            storey_yield_disp_m=spec.get("storey_yield_disp_m"),
            **common,
        )
    raise InputError(
        f"unknown model {model!r}; allowed: 'sdof', 'shear'", file=file, key=prefix + "model"
    )


def _unknown(spec: dict, allowed: set, *, file, prefix: str) -> None:
    extra = sorted(set(spec) - allowed)
    if extra:
        raise InputError(
            f"unknown key(s) {', '.join(extra)}{did_you_mean(extra[0], allowed)}; allowed: "
            f"{', '.join(sorted(allowed))}",
            file=file,
            key=prefix + extra[0],
        )


@dataclass(frozen=True)
class Contact:
    """One pair of floors that can pound.

    Attributes
    ----------
    left_floor, right_floor : int
        Floor indices (0 = first floor above ground).
    elevation_m : float or None
        Height of the contact [m] (``None`` for an SDOF pair without heights).
    m_left, m_right : float
        Masses that meet [kg]; on a column, its effective mass ``1 / sum(w_k^2 / m_k)`` (the
        mass a point whose displacement is ``sum(w_k x_k)`` opposes to an impulse).
    left_at, right_at : tuple
        Where a floor of one building meets the other's column: ``((floor, weight), ...)``,
        the floors (0-based, -1 the ground) whose displacements, so weighted, are the column's
        at the contact height (linear between the floors below and above); empty for a floor.
        ``left_floor`` / ``right_floor`` then name the floor below (-1: the ground).
    """

    left_floor: int
    right_floor: int
    elevation_m: float | None
    m_left: float
    m_right: float
    left_at: tuple = ()
    right_at: tuple = ()
    #: In a row of buildings, the index of the pair's left building (0: the first two).
    pair: int = 0

    @property
    def kind(self) -> str:
        """``"floor"`` (floor against floor) or ``"column"`` (a floor against a column)."""
        return "column" if self.left_at or self.right_at else "floor"

    def weights(self, side: str, n_floors: int) -> np.ndarray:
        """Weights of ``side``'s floors (``"left"`` / ``"right"``) in the contact's displacement."""
        w = np.zeros(n_floors)
        at = self.left_at if side == "left" else self.right_at
        floor = self.left_floor if side == "left" else self.right_floor
        for f, wf in at or ((floor, 1.0),):
            if f >= 0:
                w[f] += wf
        return w

    @property
    def m_eff(self) -> float:
        """Effective mass ``m1 m2 / (m1 + m2)`` [kg] (``m1`` against a wall's infinite mass)."""
        if math.isinf(self.m_right):
            return float(self.m_left)
        return self.m_left * self.m_right / (self.m_left + self.m_right)


def _column(z: float, building: Building, tol: float):
    """Where height ``z`` meets ``building``'s column: ``(floor below, at, effective mass)``.

    None unless ``z`` lies between two of its floors (below the first floor or above the roof,
    or within ``tol`` of a floor: a floor contact instead).
    """
    elev = building.elevation_m
    if z >= elev[-1] - tol or z <= elev[0] + tol:
        return None
    j = int(np.searchsorted(elev, z))  # first floor above z
    z_lo = elev[j - 1] if j > 0 else 0.0
    w = (z - z_lo) / (elev[j] - z_lo)
    at = ((j - 1, float(1.0 - w)), (j, float(w)))
    compliance = sum(wf * wf / building.storey_mass_kg[f] for f, wf in at if f >= 0)
    return j - 1, at, 1.0 / compliance


def contacts_between(
    left: Building, right: Building, *, file=None, level_tolerance_m: float = 0.0
) -> list[Contact]:
    """Pairs of floors that can pound: every pair at equal height (one for an SDOF pair).

    Against a wall (``right``): the left building's floors at or below the wall's height, or
    only its lowest floor where the wall has none.
    """
    if right.model == "wall":
        if left.model == "wall":
            raise InputError("a wall stands only on the right", file=file, key="left.model")
        mr = right.storey_mass_kg[0]
        if right.elevation_m is None or left.elevation_m is None:
            z = None if left.elevation_m is None else float(left.elevation_m[0])
            return [Contact(0, 0, z, left.storey_mass_kg[0], mr)]
        out = [
            Contact(i, 0, float(z), left.storey_mass_kg[i], mr)
            for i, z in enumerate(left.elevation_m)
            if z <= right.elevation_m[0] + HEIGHT_TOLERANCE_M
        ]
        if not out:
            raise InputError("the wall is lower than the building's first floor", file=file,
                             key="right.height_m")  # fmt: skip
        return out
    if (
        left.model == "sdof"
        and right.model == "sdof"
        and (left.elevation_m is None or right.elevation_m is None)
    ):
        return [Contact(0, 0, None, left.storey_mass_kg[0], right.storey_mass_kg[0])]
    for side, b in (("left", left), ("right", right)):
        if b.elevation_m is None:
            raise InputError(
                "an SDOF paired with a shear building needs height_m",
                file=file,
                key=f"{side}.height_m",
            )
    tol = max(float(level_tolerance_m), HEIGHT_TOLERANCE_M)
    out = []
    met_l, met_r = set(), set()
    for i, zl in enumerate(left.elevation_m):
        for j, zr in enumerate(right.elevation_m):
            if abs(zl - zr) <= tol:
                out.append(
                    Contact(i, j, float(zl), left.storey_mass_kg[i], right.storey_mass_kg[j])
                )
                met_l.add(i)
                met_r.add(j)
    # a floor between the other building's floors meets its column
    for i, zl in enumerate(left.elevation_m):
        col = None if i in met_l else _column(zl, right, tol)
        if col is not None:
            out.append(Contact(i, col[0], float(zl), left.storey_mass_kg[i], col[2],
                               right_at=col[1]))  # fmt: skip
    for j, zr in enumerate(right.elevation_m):
        col = None if j in met_r else _column(zr, left, tol)
        if col is not None:
            out.append(Contact(col[0], j, float(zr), col[2], right.storey_mass_kg[j],
                               left_at=col[1]))  # fmt: skip
    out.sort(key=lambda c: c.elevation_m)  # stable: floor contacts keep their order
    if not out:
        raise InputError(
            "no floors of the two buildings are at equal height, so they cannot pound",
            file=file,
            key="right.storey_height_m",
        )
    return out
