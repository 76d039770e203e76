import re

import numpy as np
import pytest

from pound_mc.cli import main
from pound_mc.errors import InputErrors
from pound_mc.study.definition import study_from_text
from studies import study_text

GOOD = study_text(
    study={"name": "tiny", "seed": 7},
    record={"source": "builtin:knet-akt013", "duration_s": 5.0},
    grid={"left.period_s": {"start": 0.3, "stop": 0.6, "num": 2}},
    sampling={"n": 4},
)


def test_good_study_parses():
    study = study_from_text(GOOD, file="good.toml")
    assert study.shape == (1, 2, 2, 4)
    assert study.n_simulations == 16
    assert np.allclose(study.grid["left.period_s"], [0.3, 0.6])
    draws = study.draw()
    assert draws["contact.e"].min() >= 0.4278 and draws["contact.e"].max() <= 0.7840


def _replace(old, new):
    assert old in GOOD, old
    return GOOD.replace(old, new, 1)


# (case id, study text, key the message must name)
MALFORMED = [
    ("unknown-table", GOOD + "\n[colour]\nred = 1\n", "colour"),
    ("unknown-study-key", _replace('seed = 7', 'seed = 7\ncolour = "red"'), "study.colour"),
    ("name-with-space", _replace('name = "tiny"', 'name = "my study"'), "study.name"),
    ("seed-negative", _replace("seed = 7", "seed = -1"), "study.seed"),
    ("seed-string", _replace("seed = 7", 'seed = "seven"'), "study.seed"),
    ("chunk-size-zero", _replace("seed = 7", "seed = 7\nchunk_size = 0"), "study.chunk_size"),
    ("n-zero", _replace("n = 4", "n = 0"), "sampling.n"),
    ("n-negative", _replace("n = 4", "n = -5"), "sampling.n"),
    ("n-float", _replace("n = 4", "n = 2.5"), "sampling.n"),
    ("method-unknown", _replace('method = "sobol"', 'method = "halton"'), "sampling.method"),
    ("sampling-unknown-key", _replace("n = 4", "n = 4\nsize = 3"), "sampling.size"),
    ("vary-bad-material", _replace('"contact.e" = { material = "concrete" }',
                                   '"contact.e" = { material = "glass" }'), "material"),
    ("vary-non-numeric", _replace('"contact.beta" = { material = "concrete" }',
                                  '"contact.beta" = { material = "concrete" }\n'
                                  '"contact.model" = {distribution = "uniform", low = 0, high = 1}'
                                  ),
     "sampling.vary.contact.model"),
    ("vary-also-grid", _replace('"contact.beta" = { material = "concrete" }',
                                '"contact.beta" = { material = "concrete" }\n'
                                '"contact.gap_m" = { distribution = "uniform", low = 0, high = 1 }'
                                ),
     "sampling.vary.contact.gap_m"),
    ("grid-non-numeric", GOOD.replace("[grid]", '[grid]\n"contact.model" = ["hertz"]'),
     "grid.contact.model"),
    ("grid-num-zero", _replace("num = 2", "num = 0"), "grid.left.period_s.num"),
    ("grid-empty", _replace('"contact.gap_m" = [0.0, 0.002]', '"contact.gap_m" = []'),
     "grid.contact.gap_m"),
    ("grid-strings", _replace('"contact.gap_m" = [0.0, 0.002]', '"contact.gap_m" = ["a", "b"]'),
     "grid.contact.gap_m"),
    ("grid-negative-period", _replace("start = 0.3", "start = -0.3"), "grid.left.period_s"),
    ("period-negative", _replace("period_s = 1.0", "period_s = -1.0"), "right.period_s"),
    ("damping-string", _replace("damping_ratio = 0.05\nmass_kg = 1.0e6\n\n[right]",
                                'damping_ratio = "low"\nmass_kg = 1.0e6\n\n[right]'),
     "left.damping_ratio"),
    ("mass-zero", _replace("mass_kg = 1.0e6\n\n[contact]", "mass_kg = 0.0\n\n[contact]"),
     "right.mass_kg"),
    ("e-above-one", _replace("e = 0.65", "e = 1.5"), "contact.e"),
    ("e-zero", _replace("e = 0.65", "e = 0.0"), "contact.e"),
    ("gap-negative", _replace("gap_m = 0.002", "gap_m = -0.01"), "contact.gap_m"),
    ("beta-string", _replace("beta = 2.75e9", 'beta = "stiff"'), "contact.beta"),
    ("contact-model", _replace('model = "jankowski"', 'model = "glue"'), "contact.model"),
    ("integrator-method", _replace('method = "adaptive"', 'method = "euler"'),
     "integrator.method"),
    ("dt-zero", _replace("dt_s = 0.01", "dt_s = 0.0"), "integrator.dt_s"),
    ("record-missing-file", _replace('source = "builtin:knet-akt013"',
                                     'source = "records/nope.AT2"'), "record.source"),
    ("record-unknown-builtin", _replace('source = "builtin:knet-akt013"',
                                        'source = "builtin:atlantis"'), "record.source"),
    ("pga-negative", _replace("pga_g = 0.3", "pga_g = -0.3"), "record.pga_g"),
    ("left-unknown-key", _replace("period_s = 0.5", "period_s = 0.5\nwidth_m = 3.0"),
     "left.width_m"),
    ("no-record", GOOD.replace('[record]\nsource = "builtin:knet-akt013"\nduration_s = 5.0\n'
                               'pga_g = 0.3\n', ""), "record"),
    ("bad-toml", GOOD.replace("[grid]", "[grid"), None),
    ("shear-structural-axis", _replace('model = "sdof"\nperiod_s = 0.5\ndamping_ratio = 0.05\n'
                             'mass_kg = 1.0e6', 'model = "shear"\nstorey_mass_kg = [1.0e6]\n'
                             'storey_stiffness_N_per_m = [1.0e8]\nstorey_height_m = [3.0]'),
     "grid.left.period_s"),
    ("building-model-unknown", _replace('model = "sdof"', 'model = "frame"'), "left.model"),
    ("vary-e-normal-outside", _replace('"contact.e" = { material = "concrete" }',
                                       '"contact.e" = {distribution = "normal", mean = 0.9, '
                                       'std = 0.5}'), "sampling.vary.contact.e"),
    ("vary-bad-distribution", _replace('"contact.e" = { material = "concrete" }',
                                       '"contact.e" = { distribution = "weibull" }'),
     "sampling.vary.contact.e.distribution"),
    ("grid-e-above-one", GOOD.replace("[grid]", '[grid]\n"contact.e" = [0.5, 1.2]').replace(
        '"contact.e" = { material = "concrete" }', ""), "grid.contact.e"),
    # below the Jankowski law's restitution table (jankowski2008: xi = 356 at e = 0.001)
    ("grid-e-below-table", GOOD.replace("[grid]", '[grid]\n"contact.e" = [0.001, 0.5]').replace(
        '"contact.e" = { material = "concrete" }', ""), "grid.contact.e"),
    ("grid-spec-extra-key", _replace("num = 2", "num = 2, step = 0.1"), "grid.left.period_s"),
    ("grid-not-table", _replace("[grid]\n", 'grid = 3\n[nogrid]\n'), "grid"),
    ("record-and-records", GOOD + '\n[[records]]\nsource = "builtin:elcentro"\n', "records"),
    ("records-missing-file", GOOD.replace('[record]', '[[records]]').replace(
        '"builtin:knet-akt013"', '"missing.at2"'), "records[0].source"),
    ("description-number", _replace("seed = 7", "seed = 7\ndescription = 3"),
     "study.description"),
    ("sampling-seed-negative", _replace("n = 4", "n = 4\nseed = -3"), "sampling.seed"),
    ("substeps-too-few", _replace("dt_s = 0.01", "dt_s = 0.01\nsubsteps = 1"),
     "integrator.substeps"),
    ("relation-unknown", _replace("e = 0.65", 'e = 0.65\nrelation = "newton"'),
     "contact.relation"),
    ("xi-and-e", _replace("e = 0.65", "e = 0.65\nxi = 0.3"), "contact.xi"),
    ("duration-negative", _replace("duration_s = 5.0", "duration_s = -5.0"), "record.duration_s"),
]  # fmt: skip


@pytest.mark.parametrize(("case", "text", "key"), MALFORMED, ids=[m[0] for m in MALFORMED])
def test_malformed_study_exit_2_names_file_and_key(case, text, key, tmp_path, capsys):
    path = tmp_path / f"{case}.toml"
    path.write_text(text)
    out = tmp_path / "outputs"
    assert main(["run", str(path), "--out", str(out), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert str(path) in err
    if key is not None:
        assert re.search(re.escape(key), err), err
    assert "Traceback" not in err
    assert not out.exists()  # nothing written


def test_all_problems_reported_at_once():
    text = _replace("n = 4", "n = 0").replace("seed = 7", "seed = -1").replace("e = 0.65", "e = 2")
    with pytest.raises(InputErrors) as info:
        study_from_text(text, file="multi.toml")
    keys = {e.key for e in info.value.errors}
    assert {"sampling.n", "study.seed", "contact.e"} <= keys


def _refused(tmp_path, capsys, text: str, name: str = "bad") -> str:
    """``pound-mc run`` on ``text``: exit 2, one line, nothing written; the message after the
    program's prefix, with the study path written as ``STUDY``."""
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    out = tmp_path / "outputs"
    assert main(["run", str(path), "--out", str(out), "--no-progress", "--no-plot"]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and err.count("\n") == 1, err
    assert not out.exists()  # nothing written: no .part file, no chunk
    return err.removeprefix("pound-mc run: error: ").rstrip("\n").replace(str(path), "STUDY")


@pytest.mark.parametrize("table", ["study", "sampling"])
def test_seed_the_dataset_cannot_store_is_refused(tmp_path, capsys, table):
    # the seeds are netCDF attributes: unsigned 64-bit at most (2^64 - 1 was written and
    # read back; 2^64 failed writing the dataset after every simulation had run)
    text = _replace("seed = 7", "seed = 18446744073709551616") if table == "study" else (
        _replace("n = 4", "n = 4\nseed = 18446744073709551616"))  # fmt: skip
    assert _refused(tmp_path, capsys, text) == (
        f"STUDY: {table}.seed: must be an integer in [0, 18446744073709551615], got "
        "18446744073709551616"
    )
    assert study_from_text(_replace("seed = 7", "seed = 18446744073709551615")).seed == 2**64 - 1


def test_misspelt_keys_get_a_hint(tmp_path, capsys):
    # close to an allowed key: named with it; a sampled variable's key: the key is blamed,
    # not the missing 'distribution' ("needs 'material' or 'distribution' ..., got None")
    text = _replace("damping_ratio = 0.05\nmass_kg = 1.0e6\n\n[right]",
                    "damping_ration = 0.05\nmass_kg = 1.0e6\n\n[right]")  # fmt: skip
    assert _refused(tmp_path, capsys, text).startswith(
        "STUDY: left.damping_ration: unknown key (did you mean 'damping_ratio'?); allowed: "
    )
    text = _replace('"contact.beta" = { material = "concrete" }',
                    '"contact.beta" = { dist = "uniform", low = 1e9, high = 2e9 }')  # fmt: skip
    assert _refused(tmp_path, capsys, text) == (
        "STUDY: sampling.vary.contact.beta.dist: unknown key; a sampled variable takes "
        "'material' or 'distribution'"
    )
    text = _replace('"contact.beta" = { material = "concrete" }',
                    '"contact.beta" = { distrib = "uniform", low = 1e9, high = 2e9 }')  # fmt: skip
    assert "contact.beta.distrib: unknown key (did you mean 'distribution'?)" in _refused(
        tmp_path, capsys, text
    )


def test_a_relation_given_to_a_law_without_damping_says_so(tmp_path, capsys):
    # the message listed the law's relations: "unknown value 'jankowski2008'; allowed: "
    text = (
        _replace('model = "jankowski"', 'model = "hertz"')
        .replace("e = 0.65", 'relation = "jankowski2008"')
        .replace('"contact.e" = { material = "concrete" }\n', "")
    )
    assert _refused(tmp_path, capsys, text) == (
        "STUDY: contact.relation: the 'hertz' law has no damping and takes no relation; remove it"
    )


def test_sampled_values_out_of_bounds_are_blamed_on_the_sampled_key_once(tmp_path, capsys):
    # beta uniform over [-2e9, 1e9] on a two-value gap axis: its draws were reported as
    # grid.contact.gap_m's, once per gap.  Sobol (seed 7) draws -1.14e9 first, < 0.
    vary = ('"contact.beta" = { material = "concrete" }',
            '"contact.beta" = { distribution = "uniform", low = -2e9, high = 1e9 }')  # fmt: skip
    err = _refused(tmp_path, capsys, _replace(*vary))
    assert re.fullmatch(
        r"STUDY: sampling\.vary\.contact\.beta: uniform \(low -2e\+09, high 1e\+09\) draws "
        r"values outside the key's bounds: must be > 0, got -[0-9.e+]+",
        err,
    ), err


@pytest.mark.parametrize("table", ["grid", "sampling.vary"])
def test_unquoted_dotted_key_says_to_quote_it(tmp_path, capsys, table):
    # TOML reads `contact.gap_m = [...]` as the table contact = { gap_m = [...] }
    if table == "grid":
        text = _replace('"contact.gap_m" = [0.0, 0.002]', "contact.gap_m = [0.0, 0.002]")
    else:
        text = _replace('"contact.beta" = { material = "concrete" }',
                        'contact.beta = { material = "concrete" }')  # fmt: skip
    leaf = "gap_m" if table == "grid" else "beta"
    err = _refused(tmp_path, capsys, text)
    assert err.startswith(
        f"STUDY: {table}.contact: not a numeric scene key (a dotted key must be quoted: "
        f'"contact.{leaf}" = ...); '
    ), err


@pytest.mark.parametrize("where", ["grid", "sampling.vary"])
def test_varied_xi_with_a_fixed_e_is_refused(tmp_path, capsys, where):
    # the study dropped [contact] e = 0.65 without a word; a scene refuses e and xi together
    if where == "grid":
        text = GOOD.replace("[grid]", '[grid]\n"contact.xi" = [0.1, 0.3]')
    else:
        xi = '"contact.xi" = { distribution = "uniform", low = 0.1, high = 0.3 }'
        text = _replace('"contact.e" = { material = "concrete" }', xi)
    assert _refused(tmp_path, capsys, text) == (
        f"STUDY: {where}.contact.xi: varies contact.xi while [contact] gives e = 0.65 "
        "(contact.e): give either xi or e, not both; remove e from [contact]"
    )
