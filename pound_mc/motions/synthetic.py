"""Stochastic ground motions: Clough-Penzien filtered white noise with a Jennings envelope.

The motion is ``a(t) = e(t) x(t)``: ``x`` a stationary Gaussian process whose two-sided power
spectral density is the Clough-Penzien spectrum (Kanai-Tajimi soil filter followed by the
Clough-Penzien high-pass that removes the spurious low-frequency content), ``e`` the
Jennings-Housner-Tsai envelope.

Conventions
-----------
``S(omega)`` is two-sided in angular frequency: ``E[x^2] = integral of S over -inf < omega <
inf`` [m^2/s^4], so ``S0`` is in m^2/s^3.  The expected periodogram of ``a`` is then about
``mean(e^2) * S(omega)`` wherever ``S`` varies slowly over the envelope's bandwidth (about
1/duration), which is what the tests check.

Generation (spectral representation with Gaussian amplitudes, Shinozuka & Deodatis 1991):
``x(t) = sum_k sqrt(2 S(omega_k) d_omega) (A_k cos omega_k t + B_k sin omega_k t)`` with
``A_k, B_k`` independent standard normals, evaluated by one inverse real FFT over twice the
record length (so the first and last samples are not correlated by the FFT's periodicity);
``omega_k = k d_omega``, the zero and Nyquist frequencies left out.  The random numbers come
from ``numpy.random.default_rng(numpy.random.SeedSequence(seed))``, all ``A`` then all ``B``:
one seed, one motion.

References
----------
Kanai, K. (1957). Semi-empirical formula for the seismic characteristics of the ground.
Bull. Earthq. Res. Inst. Univ. Tokyo 35, 309-325.
Tajimi, H. (1960). A statistical method of determining the maximum response of a building
structure during an earthquake. Proc. 2nd World Conf. Earthq. Eng., Tokyo, 781-798.
Clough, R. W., Penzien, J. (1975). Dynamics of Structures. McGraw-Hill (2nd ed. 1993).
Jennings, P. C., Housner, G. W., Tsai, N. C. (1968). Simulated earthquake motions. Report,
Earthquake Engineering Research Laboratory, California Institute of Technology.
Der Kiureghian, A., Neuenhofer, A. (1992). Response spectrum method for multi-support seismic
excitations. Earthq. Eng. Struct. Dyn. 21(8), 713-740.
Shinozuka, M., Deodatis, G. (1991). Simulation of stochastic processes by spectral
representation. Appl. Mech. Rev. 44(4), 191-204.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from pound_mc.errors import InputError
from pound_mc.motions.traces import G, make_trace

__all__ = [
    "SOIL_PARAMETERS",
    "DEFAULTS",
    "SYNTHETIC_MODELS",
    "clough_penzien_psd",
    "jennings_envelope",
    "validate_params",
    "generate",
]

#: Clough-Penzien filter parameters for three site classes, Der Kiureghian & Neuenhofer
#: (1992), Table 1: omega_g [rad/s], zeta_g [-], omega_f [rad/s], zeta_f [-].
SOIL_PARAMETERS: dict[str, dict[str, float]] = {
    "firm": {"omega_g": 15.0, "zeta_g": 0.6, "omega_f": 1.5, "zeta_f": 0.6},
    "medium": {"omega_g": 10.0, "zeta_g": 0.4, "omega_f": 1.0, "zeta_f": 0.6},
    "soft": {"omega_g": 5.0, "zeta_g": 0.2, "omega_f": 0.5, "zeta_f": 0.6},
}

#: Default parameters of ``synthetic:clough-penzien``.  The filter is the firm-soil set above.
#: The envelope has the shape of Jennings et al. (1968) (quadratic rise, constant strong phase,
#: exponential decay); its times are this package's choice for a moderate event of about 20 s:
#: strong phase 2-10 s, decay c = 0.3 1/s so that e(20 s) = exp(-3) = 0.05.  S0 = 0.01 m^2/s^3
#: gives a root-mean-square acceleration of about 0.98 m/s^2 in the strong phase.
DEFAULTS: dict[str, Any] = {
    "soil": "firm",
    **SOIL_PARAMETERS["firm"],
    "S0": 0.01,  # [m^2/s^3], two-sided
    "pga_g": None,  # [g] if given: each realisation scaled to this peak instead of using S0
    "duration_s": 20.0,  # [s]
    "dt_s": 0.01,  # [s]
    "t1_s": 2.0,  # [s] end of the quadratic rise
    "t2_s": 10.0,  # [s] end of the strong phase
    "c_per_s": 0.3,  # [1/s] decay rate after t2_s
}


def clough_penzien_psd(
    omega,
    *,
    omega_g: float = 15.0,
    zeta_g: float = 0.6,
    omega_f: float = 1.5,
    zeta_f: float = 0.6,
    S0: float = 0.01,
):
    """Clough-Penzien power spectral density of ground acceleration (two-sided).

    ``S(w) = S0 * (wg^4 + 4 zg^2 wg^2 w^2) / ((wg^2 - w^2)^2 + 4 zg^2 wg^2 w^2)
    * w^4 / ((wf^2 - w^2)^2 + 4 zf^2 wf^2 w^2)``: the Kanai-Tajimi soil filter (Kanai 1957,
    Tajimi 1960) times the Clough-Penzien high-pass (Clough & Penzien 1975).

    Parameters
    ----------
    omega : array_like
        Angular frequency [rad/s].
    omega_g, zeta_g : float
        Soil filter frequency [rad/s] and damping ratio [-] (firm soil: 15.0, 0.6).
    omega_f, zeta_f : float
        High-pass filter frequency [rad/s] and damping ratio [-] (firm soil: 1.5, 0.6).
    S0 : float
        Two-sided intensity of the bedrock white noise [m^2/s^3].

    Returns
    -------
    numpy.ndarray
        ``S(omega)`` [m^2/s^3]; ``integral S d(omega)`` over the whole line is the variance.
    """
    w2 = np.square(np.asarray(omega, dtype=np.float64))
    wg2, wf2 = omega_g**2, omega_f**2
    kanai_tajimi = (wg2**2 + 4 * zeta_g**2 * wg2 * w2) / (
        (wg2 - w2) ** 2 + 4 * zeta_g**2 * wg2 * w2
    )
    high_pass = w2**2 / ((wf2 - w2) ** 2 + 4 * zeta_f**2 * wf2 * w2)
    return S0 * kanai_tajimi * high_pass


def jennings_envelope(t, t1_s: float = 2.0, t2_s: float = 10.0, c_per_s: float = 0.3):
    """Jennings-Housner-Tsai amplitude envelope (Jennings et al. 1968).

    ``e = (t/t1)^2`` for ``t < t1``, ``1`` for ``t1 <= t <= t2``, ``exp(-c (t - t2))`` after.

    Parameters
    ----------
    t : array_like
        Time from the start of the motion [s].
    t1_s : float
        End of the quadratic rise [s] (0 for an instantaneous rise).
    t2_s : float
        End of the strong phase [s], ``>= t1_s``.
    c_per_s : float
        Decay rate of the tail [1/s].

    Returns
    -------
    numpy.ndarray
        Envelope [-], between 0 and 1.
    """
    t = np.asarray(t, dtype=np.float64)
    rise = np.square(t / t1_s) if t1_s > 0 else np.ones_like(t)
    tail = np.exp(-c_per_s * np.maximum(t - t2_s, 0.0))
    return np.where(t < t1_s, rise, np.where(t <= t2_s, 1.0, tail))


#: The most samples a synthetic motion may have (80 MB of float64; a day at 100 Hz).
MAX_SAMPLES = 1.0e7


def _number(params, name, *, minimum=0.0, inclusive=False) -> float:
    value = params[name]
    if isinstance(value, bool) or not isinstance(value, int | float | np.number):
        raise InputError(f"must be a number, got {value!r}", key=f"params.{name}")
    x = float(value)
    ok = math.isfinite(x) and (x >= minimum if inclusive else x > minimum)
    if not ok:
        relation = ">=" if inclusive else ">"
        raise InputError(
            f"must be finite and {relation} {minimum:g}, got {value!r}", key=f"params.{name}"
        )
    return x


def validate_params(params: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """Complete ``params`` with :data:`DEFAULTS` and check every value.

    ``soil`` picks a row of :data:`SOIL_PARAMETERS`; filter values given explicitly override it.
    ``S0`` and ``pga_g`` exclude each other.

    Raises
    ------
    InputError
        Unknown key, non-numeric or out-of-range value; the key is ``params.NAME``.
    """
    params = dict(params or {})
    unknown = sorted(set(params) - set(DEFAULTS))
    if unknown:
        raise InputError(
            f"unknown parameter(s) {', '.join(unknown)}; allowed: {', '.join(DEFAULTS)}",
            key=f"params.{unknown[0]}",
        )
    if params.get("S0") is not None and params.get("pga_g") is not None:
        raise InputError("give S0 or pga_g, not both", key="params.pga_g")
    soil = params.get("soil", DEFAULTS["soil"])
    if soil not in SOIL_PARAMETERS:
        raise InputError(
            f"unknown soil {soil!r}; choose one of {', '.join(SOIL_PARAMETERS)}", key="params.soil"
        )
    p = {**DEFAULTS, **SOIL_PARAMETERS[soil], **params, "soil": soil}
    for name in ("omega_g", "zeta_g", "omega_f", "zeta_f", "S0", "duration_s", "dt_s", "c_per_s"):
        p[name] = _number(p, name)
    for name in ("t1_s", "t2_s"):
        p[name] = _number(p, name, inclusive=True)
    if p["pga_g"] is not None:
        p["pga_g"] = _number(p, "pga_g")
    if p["t1_s"] > p["t2_s"]:
        raise InputError(
            f"t1_s = {p['t1_s']:g} s must not exceed t2_s = {p['t2_s']:g} s", key="params.t1_s"
        )
    if p["dt_s"] > p["duration_s"]:
        raise InputError(
            f"dt_s = {p['dt_s']:g} s is longer than duration_s = {p['duration_s']:g} s",
            key="params.dt_s",
        )
    if p["duration_s"] / p["dt_s"] > MAX_SAMPLES:
        raise InputError(
            f"duration_s / dt_s = {p['duration_s'] / p['dt_s']:.3g} samples, more than "
            f"{MAX_SAMPLES:.0e} (memory): give a shorter duration_s or a longer dt_s",
            key="params.duration_s",
        )
    nyquist = math.pi / p["dt_s"]
    if nyquist <= 2.0 * p["omega_g"]:
        raise InputError(
            f"dt_s = {p['dt_s']:g} s is too coarse for omega_g = {p['omega_g']:g} rad/s: the "
            f"Nyquist frequency pi/dt_s = {nyquist:.4g} rad/s must exceed 2 omega_g",
            key="params.dt_s",
        )
    return p


def _seed_sequence(seed) -> np.random.SeedSequence:
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise InputError(f"a synthetic motion needs an integer seed >= 0, got {seed!r}", key="seed")
    return np.random.SeedSequence(int(seed))


def generate(params: Mapping[str, Any] | None, seed: int):
    """One realisation of the enveloped Clough-Penzien process.

    Parameters
    ----------
    params : dict or None
        Parameters (see :data:`DEFAULTS`; missing ones take the defaults).
    seed : int
        Fixes the realisation: ``numpy.random.default_rng(numpy.random.SeedSequence(seed))``.

    Returns
    -------
    obspy.Trace
        Acceleration [m/s^2] at ``dt_s`` from 0 to ``duration_s``; parameters and seed in
        ``stats.pound``.

    Raises
    ------
    InputError
        Bad parameter or seed.
    """
    p = validate_params(params)
    rng = np.random.default_rng(_seed_sequence(seed))
    dt = p["dt_s"]
    n = int(round(p["duration_s"] / dt)) + 1
    m = 2 * n  # even FFT length, twice the record: no wrap-around correlation
    d_omega = 2.0 * math.pi / (m * dt)
    k = np.arange(1, m // 2)
    omega = k * d_omega
    filt = {key: p[key] for key in ("omega_g", "zeta_g", "omega_f", "zeta_f", "S0")}
    amplitude = np.sqrt(2.0 * clough_penzien_psd(omega, **filt) * d_omega)
    a_k = rng.standard_normal(k.size)
    b_k = rng.standard_normal(k.size)
    spectrum = np.zeros(m // 2 + 1, dtype=np.complex128)
    spectrum[1 : m // 2] = 0.5 * m * amplitude * (a_k - 1j * b_k)
    stationary = np.fft.irfft(spectrum, n=m)[:n]
    t = np.arange(n) * dt
    acc = jennings_envelope(t, p["t1_s"], p["t2_s"], p["c_per_s"]) * stationary
    if p["pga_g"] is not None:
        acc *= p["pga_g"] * G / np.max(np.abs(acc))
    return make_trace(
        acc,
        dt,
        source="synthetic:clough-penzien",
        format="synthetic",
        event=f"Clough-Penzien synthetic motion, seed {int(seed)}",
        station="SYNTH",
        component="H",
        source_units="m/s^2",
        seed=int(seed),
        params=dict(p),
    )


#: Synthetic models by name (``synthetic:NAME``).
SYNTHETIC_MODELS = {"clough-penzien": generate}
