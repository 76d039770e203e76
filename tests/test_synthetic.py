import math

import numpy as np
import pytest
from scipy.integrate import quad

from pound_mc.errors import InputError
from pound_mc.motions import G, load_record, record_arrays, synthetic


def _binned_ratio(params, seeds, width_hz=1.0, band_hz=(0.5, 15.0), target_params=None):
    """Mean periodogram over realisations / target, averaged in frequency bins.

    The periodogram ``I(w) = dt / (2 pi N) |sum_n a_n exp(-i w t_n)|^2`` integrates over
    ``-pi/dt < w < pi/dt`` to the mean square of the record (Parseval), so it estimates the
    two-sided spectral density.  For ``a = e(t) x(t)`` with ``x`` stationary of spectrum
    ``S``, ``E[I(w)]`` is ``S`` convolved with the envelope's spectral window, whose area is
    ``mean(e^2)`` and whose width is about 1/duration; where ``S`` varies slowly on that scale,
    ``E[I(w)] = mean(e^2) S(w)``.  One periodogram ordinate scatters like an exponential
    variable (100 %), so we average over the realisations and over the ordinates of a
    1-Hz bin (40 of them for a 40-s record): the standard error is then about 1.5 %, and the
    10 % tolerance is several standard errors wide while a wrong level, shape or scale of the
    spectrum (checked below) misses it.
    """
    p = synthetic.validate_params(params)
    dt = p["dt_s"]
    acc = np.array([synthetic.generate(params, seed).data for seed in seeds])
    n = acc.shape[1]
    periodogram = dt / (2 * np.pi * n) * np.abs(np.fft.rfft(acc, axis=1)) ** 2
    mean = periodogram.mean(axis=0)
    f = np.fft.rfftfreq(n, dt)
    envelope = synthetic.jennings_envelope(np.arange(n) * dt, p["t1_s"], p["t2_s"], p["c_per_s"])
    tp = p if target_params is None else {**p, **target_params}
    filt = {k: tp[k] for k in ("omega_g", "zeta_g", "omega_f", "zeta_f", "S0")}
    target = synthetic.clough_penzien_psd(2 * np.pi * f, **filt) * np.mean(envelope**2)
    edges = np.arange(band_hz[0], band_hz[1] + 1e-9, width_hz)
    ratios = []
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        sel = (f >= lo) & (f < hi)
        ratios.append(mean[sel].mean() / target[sel].mean())
    return np.array(ratios)


def test_mean_periodogram_matches_clough_penzien_spectrum():
    params = {"duration_s": 40.0, "t2_s": 30.0}
    ratios = _binned_ratio(params, range(200))
    deviation = np.max(np.abs(ratios - 1.0))
    # measured: 0.025 (max over the 14 one-hertz bins between 0.5 and 15 Hz)
    assert deviation < 0.10, ratios
    # the check discriminates: the same motions against the medium-soil spectrum fail it
    wrong = _binned_ratio(params, range(200), target_params=synthetic.SOIL_PARAMETERS["medium"])
    assert np.max(np.abs(wrong - 1.0)) > 0.10


def _clough_penzien_written_out(w, wg, zg, wf, zf, s0):
    # Clough & Penzien (1975): S(w) = S0 (wg^4 + 4 zg^2 wg^2 w^2) / ((wg^2 - w^2)^2
    # + 4 zg^2 wg^2 w^2) * w^4 / ((wf^2 - w^2)^2 + 4 zf^2 wf^2 w^2), written out independently
    # of pound_mc.motions.synthetic.  Convention (pound_mc/synthetic.py module docstring and
    # clough_penzien_psd): w is angular frequency in rad/s and S is two-sided in w, i.e. the
    # variance is the integral of S over -inf < w < inf, so S0 is the two-sided intensity
    # [m^2/s^3]; no factor 2 or 2 pi enters.
    kanai_tajimi = (wg**4 + 4 * zg**2 * wg**2 * w**2) / (
        (wg**2 - w**2) ** 2 + 4 * zg**2 * wg**2 * w**2
    )
    high_pass = w**4 / ((wf**2 - w**2) ** 2 + 4 * zf**2 * wf**2 * w**2)
    return s0 * kanai_tajimi * high_pass


@pytest.mark.parametrize("soil", ["default", "medium"])
def test_psd_is_the_clough_penzien_formula(soil):
    w = np.concatenate([np.linspace(0.0, 120.0, 2401), [0.01, 1.5, 10.0, 15.0, 300.0, 3000.0]])
    if soil == "default":
        p = synthetic.DEFAULTS  # the function's keyword defaults must be these (firm soil)
        package = synthetic.clough_penzien_psd(w)
    else:
        p = {**synthetic.SOIL_PARAMETERS["medium"], "S0": 0.037}
        package = synthetic.clough_penzien_psd(w, **p)
    args = (p["omega_g"], p["zeta_g"], p["omega_f"], p["zeta_f"], p["S0"])
    expected = _clough_penzien_written_out(w, *args)
    np.testing.assert_allclose(package, expected, rtol=1e-12, atol=0.0)
    assert package[0] == 0.0 and np.all(package[1:] > 0)
    # the comparison discriminates the conventions: w read in Hz, or a one-sided S0, fail it
    f_hz = w / (2 * np.pi)
    assert not np.allclose(package, _clough_penzien_written_out(f_hz, *args), rtol=1e-12, atol=0)
    one_sided = _clough_penzien_written_out(w, *args[:4], args[4] / 2)
    assert not np.allclose(package, one_sided, rtol=1e-12, atol=0)


def test_psd_integrates_to_kanai_tajimi_variance():
    # With the high-pass corner far below omega_g, the Clough-Penzien spectrum tends to the
    # Kanai-Tajimi one, whose variance is pi S0 omega_g (1 + 4 zeta_g^2) / (2 zeta_g)
    # (closed form of the integral of the rational spectrum over the whole line).
    wg, zg, s0 = 15.0, 0.6, 0.02
    kw = dict(omega_g=wg, zeta_g=zg, omega_f=1e-4, zeta_f=0.6, S0=s0)
    half, _ = quad(lambda w: synthetic.clough_penzien_psd(w, **kw), 0, np.inf, limit=400)
    exact = math.pi * s0 * wg * (1 + 4 * zg**2) / (2 * zg)
    assert 2 * half == pytest.approx(exact, rel=1e-4)


def test_envelope_shape():
    t = np.array([0.0, 1.0, 2.0, 6.0, 10.0, 11.0, 20.0])
    e = synthetic.jennings_envelope(t, t1_s=2.0, t2_s=10.0, c_per_s=0.3)
    expected = [0.0, 0.25, 1.0, 1.0, 1.0, math.exp(-0.3), math.exp(-3.0)]
    np.testing.assert_allclose(e, expected, rtol=1e-15)
    # instantaneous rise
    assert synthetic.jennings_envelope(0.0, t1_s=0.0, t2_s=1.0) == 1.0


def test_same_seed_same_motion_and_different_seeds_differ():
    a = synthetic.generate({}, 42).data
    b = synthetic.generate({}, 42).data
    c = synthetic.generate({}, 43).data
    np.testing.assert_array_equal(a, b)
    assert not np.allclose(a, c)
    # through load_record: the seed fixes the realisation
    d = load_record("synthetic:clough-penzien", seed=42, demean=False)
    np.testing.assert_array_equal(record_arrays(d)[1], a)


def test_default_motion_size_and_metadata():
    tr = synthetic.generate(None, 0)
    assert tr.stats.npts == 2001 and tr.stats.delta == 0.01
    assert tr.stats.pound.seed == 0
    assert tr.stats.pound.params["omega_g"] == 15.0
    # the envelope starts at zero
    assert tr.data[0] == 0.0


def test_pga_scaling():
    tr = load_record("synthetic:clough-penzien", seed=5, params={"pga_g": 0.3}, demean=False)
    assert np.max(np.abs(tr.data)) == pytest.approx(0.3 * G, rel=1e-12)


def test_soil_presets_and_override():
    p = synthetic.validate_params({"soil": "soft", "zeta_g": 0.3})
    assert p["omega_g"] == 5.0 and p["zeta_g"] == 0.3


@pytest.mark.parametrize(
    ("params", "key", "text"),
    [
        ({"omega_gg": 1.0}, "params.omega_gg", "unknown parameter"),
        ({"omega_g": -1.0}, "params.omega_g", "must be finite and > 0"),
        ({"zeta_g": "high"}, "params.zeta_g", "must be a number"),
        ({"S0": float("nan")}, "params.S0", "must be finite"),
        ({"t1_s": 5.0, "t2_s": 3.0}, "params.t1_s", "must not exceed t2_s"),
        ({"S0": 0.01, "pga_g": 0.3}, "params.pga_g", "not both"),
        ({"soil": "rock"}, "params.soil", "firm, medium, soft"),
        ({"dt_s": 0.5}, "params.dt_s", "too coarse"),
        ({"dt_s": 0.0}, "params.dt_s", "> 0"),
    ],
)
def test_bad_parameters(params, key, text):
    with pytest.raises(InputError) as err:
        synthetic.generate(params, 1)
    assert err.value.key == key
    assert text in err.value.message
    # through load_record the message names the source and the record key
    with pytest.raises(InputError) as err:
        load_record("synthetic:clough-penzien", seed=1, params=params)
    assert err.value.file == "synthetic:clough-penzien"
    assert err.value.key == f"record.{key}"


@pytest.mark.parametrize("seed", [None, -1, 1.5, "7", True])
def test_bad_seed(seed):
    with pytest.raises(InputError, match="integer seed"):
        load_record("synthetic:clough-penzien", seed=seed)


def test_unknown_model_and_inapplicable_options():
    with pytest.raises(InputError, match="unknown synthetic model 'kanai'.*clough-penzien"):
        load_record("synthetic:kanai", seed=1)
    with pytest.raises(InputError, match="units does not apply"):
        load_record("synthetic:clough-penzien", seed=1, units="g")
