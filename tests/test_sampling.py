import numpy as np
import pytest

from pound_mc.errors import InputError
from pound_mc.study import sampling


def _mean_error(method, n, seeds=24):
    e, _ = sampling.parse_variable("contact.e", {"material": "concrete"})
    b, _ = sampling.parse_variable("contact.beta", {"material": "concrete"})
    # exact means of the uniform ranges (Tables 2, 3, concrete): (0.4278+0.7840)/2, (3.9e9+13e9)/2
    true = np.array([(0.4278 + 0.7840) / 2, (3.9e9 + 13.0e9) / 2])
    errs = []
    for seed in range(seeds):
        d = sampling.draw([e, b], n, seed, method)
        errs.append((np.array([d["contact.e"].mean(), d["contact.beta"].mean()]) - true) / true)
    return np.sqrt(np.mean(np.square(errs), axis=0))


def test_sobol_and_lhs_means_converge_faster_than_random():
    random = [_mean_error("random", n) for n in (64, 1024)]
    for method in ("lhs", "sobol"):
        design = [_mean_error(method, n) for n in (64, 1024)]
        # at both sizes the design's RMS error of the mean is a fraction of plain random's,
        assert np.all(design[0] < 0.3 * random[0]) and np.all(design[1] < 0.1 * random[1])
        # and it falls faster than random's 1/sqrt(n) (factor 4 for 16x the samples)
        assert np.all(design[0] / design[1] > 2 * random[0] / random[1])


def test_random_stream_is_per_sample():
    # stream i depends only on (seed, i): the first 10 of 50 equal the 10 of a 10-sample draw
    a = sampling.design(50, 3, 7, "random")
    b = sampling.design(10, 3, 7, "random")
    assert np.array_equal(a[:10], b)
    assert not np.array_equal(sampling.design(10, 3, 8, "random"), b)


@pytest.mark.parametrize("method", ["random", "lhs", "sobol"])
def test_designs_reproducible_and_in_unit_cube(method):
    a = sampling.design(100, 2, 123, method)
    assert np.array_equal(a, sampling.design(100, 2, 123, method))
    assert a.shape == (100, 2) and a.min() >= 0 and a.max() < 1


def test_material_ranges_from_tables():
    e, _ = sampling.parse_variable("contact.e", {"material": "timber", "velocity_m_s": 1.0})
    assert (e.a, e.b) == (0.5334, 0.5797)  # Table 2, timber, 1.0 m/s
    b, _ = sampling.parse_variable("contact.beta", {"material": "steel"})
    assert (b.a, b.b) == (1.1e10, 6.6e10)  # Table 3, steel, all masses


def test_distributions():
    v, _ = sampling.parse_variable(
        "left.period_s", {"distribution": "lognormal", "median": 0.5, "sigma_ln": 0.1}
    )
    assert v.ppf(np.array([0.5]))[0] == pytest.approx(0.5)
    v, _ = sampling.parse_variable("left.period_s", {"distribution": "normal", "mean": 1, "std": 2})
    assert v.ppf(np.array([0.8413447460685429]))[0] == pytest.approx(3.0)  # Phi(1)


@pytest.mark.parametrize(
    ("key", "spec", "where"),
    [
        ("contact.e", {"material": "glass"}, "material"),
        ("left.period_s", {"material": "steel"}, "left.period_s"),
        ("left.period_s", {"distribution": "uniform", "low": 2, "high": 1}, "high"),
        ("left.period_s", {"distribution": "weibull"}, "distribution"),
        ("left.period_s", {"distribution": "normal", "mean": 1, "std": -1}, "std"),
        ("left.period_s", 3.0, "left.period_s"),
    ],
)
def test_bad_variables(key, spec, where):
    var, errors = sampling.parse_variable(key, spec, file="s.toml")
    assert var is None and errors
    assert where in errors[0].key and errors[0].file == "s.toml"


def test_unknown_method():
    with pytest.raises(InputError, match="sobol"):
        sampling.design(4, 1, 0, "halton")


def test_uniform_shorthand_is_the_uniform_distribution():
    # { uniform = [0, 1] } (issue 14's form for contact.e_quantile) is { distribution =
    # "uniform", low = 0, high = 1 }: the same variable, the same draws
    from pound_mc.study.sampling import draw, parse_variable

    short, errors = parse_variable("contact.e_quantile", {"uniform": [0, 1]})
    assert not errors
    long, _ = parse_variable(
        "contact.e_quantile", {"distribution": "uniform", "low": 0.0, "high": 1.0}
    )
    assert (short.kind, short.a, short.b) == (long.kind, long.a, long.b) == ("uniform", 0.0, 1.0)
    np.testing.assert_array_equal(
        draw([short], 16, 3, "sobol")["contact.e_quantile"],
        draw([long], 16, 3, "sobol")["contact.e_quantile"],
    )
    _, errors = parse_variable("contact.e_quantile", {"uniform": [0.5]})
    assert errors and "two numbers" in str(errors[0])
