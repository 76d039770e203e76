import json
import math

import pytest

from pound_mc.cli import main


def test_calibrate_json(capsys):
    assert main(["calibrate", "--e", "0.65", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    # seed eq. (2.9) at e = 0.65; it really rebounds with ~0.685 (DESIGN.md section 2)
    assert out["xi"] == pytest.approx(0.3161868221718613, rel=1e-12)
    assert out["e_effective"] == pytest.approx(0.685, abs=5e-4)
    assert out["relations"]["exact"]["e_effective"] == pytest.approx(0.65, abs=1e-6)
    assert out["relations"]["kelvin"]["e_effective"] == pytest.approx(0.65, abs=1e-6)


def test_calibrate_bad_e_exit_2(capsys):
    # every e outside the range each relation reaches names the option and that range
    for e in ("1.5", "0", "-0.2", "nan"):
        assert main(["calibrate", "--e", e]) == 2
        err = capsys.readouterr().err
        assert "--e:" in err and "must lie in [0.00878, 1]" in err, err


def test_materials_table_text(capsys):
    assert main(["materials", "--table", "2"]) == 0
    out = capsys.readouterr().out
    assert "0.4278" in out and "Table 2" in out


def test_droptest_writes_charts(tmp_path, capsys):
    assert main(["droptest", "--material", "timber", "--json", "--out", str(tmp_path)]) == 0
    out = json.loads(capsys.readouterr().out)
    # Table 2 timber at 1 m/s: e 0.5334-0.5797, mid 0.55655; eq 2.9 overshoots it (about +0.03)
    assert out["e_target"] == pytest.approx(0.55655)
    assert 0.55655 < out["restitution"] < 0.62
    for name in ("droptest.png", "restitution_relations.png", "restitution_table2.png"):
        data = (tmp_path / name).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000


def test_restitution_chart_plots_the_relations():
    from pound_mc.analysis.plot import restitution_chart
    from pound_mc.physics.relations import effective_restitution

    fig = restitution_chart(targets=[0.2, 0.5, 0.8])
    lines = {ln.get_label(): ln for ln in fig.axes[0].get_lines()}
    y = lines["Jankowski law, jankowski2008"].get_ydata()
    assert list(y) == list(effective_restitution([0.2, 0.5, 0.8], "jankowski2008"))
    assert lines["Kelvin law, kelvin"].get_ydata()[0] == pytest.approx(0.2, abs=1e-7)


# -- the command table ---------------------------------------------------------------------------


def _subcommands(parser, prefix=""):
    """Every leaf sub-command of ``parser`` and the handler name its defaults carry."""
    import argparse

    found = {}
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                found.update(_subcommands(sub, f"{prefix}{name} "))
    if not found and prefix:
        found[prefix.strip()] = parser.get_default("handler")
    return found


def test_every_subcommand_is_in_the_command_table():
    from pound_mc.cli import build_parser, command_function
    from pound_mc.cli.commands import COMMANDS

    leaves = _subcommands(build_parser())
    # DESIGN.md section 7 pins these names; the others are the package's own
    assert {"run", "check", "simulate", "calibrate", "materials", "bench"} <= set(leaves)
    assert leaves == {name: name for name in COMMANDS}
    for name in COMMANDS:
        assert callable(command_function(name)), name


def test_help_imports_no_command_module():
    import subprocess
    import sys

    code = (
        "import sys\n"
        "from pound_mc.cli import main\n"
        "try:\n    main(['--help'])\nexcept SystemExit:\n    pass\n"
        "print(sorted(m for m in sys.modules if m.startswith('pound_mc.cli.')))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    # only the parser's own module; the command modules (and the study engine, the
    # kernels' callers, matplotlib charts behind them) wait for their command
    assert out.strip().splitlines()[-1] == "['pound_mc.cli.commands']"


@pytest.mark.parametrize("argv", [["--e", "1e-9"], ["--e", "0.001", "--relation", "exact"]])
def test_calibrate_names_e_and_its_range(capsys, argv):
    """``calibrate`` blamed xi (the table's end) for an e below a relation's reach."""
    assert main(["calibrate", *argv]) == 2
    err = capsys.readouterr().err
    # jankowski2006 reaches xi = 71.17 (the exact table's end) at e = 0.008776, rounded up
    assert err.count("\n") == 1 and "--e:" in err and "[0.00878, 1]" in err, err
    assert main(["calibrate", "--e", "0.00878", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)["relations"]
    assert rows["exact"]["e_effective"] == pytest.approx(0.00878, abs=1e-6)


def test_lowest_e_of_each_relation_reaches_the_table_end():
    from pound_mc.physics.relations import RELATIONS, largest_xi, lowest_e

    # the exact table's last row: xi = 71.174474935359157, e = 0.0078499663098766138
    assert largest_xi() == pytest.approx(71.174474935359157, rel=1e-15)
    assert lowest_e("exact") == pytest.approx(0.0078499663098766138, rel=1e-15)
    # Jankowski (2008) eq. (2.9) solved for e at that xi: e = (-b + sqrt(b^2 + 4)) / 2 with
    # b = 2 pi xi / sqrt(5)
    b = 2 * math.pi * 71.174474935359157 / math.sqrt(5)
    assert lowest_e("jankowski2008") == pytest.approx((-b + math.sqrt(b * b + 4)) / 2, rel=1e-9)
    assert RELATIONS["jankowski2006"](lowest_e("jankowski2006")) == pytest.approx(71.1744749, 1e-9)
    assert lowest_e("kelvin") == 0.0


def test_droptest_elastic_law_takes_no_restitution(capsys):
    """``droptest --model hertz --e 0.5`` claimed the target e while it rebounded with e = 1."""
    assert main(["droptest", "--model", "hertz", "--e", "0.5"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--e:" in err and "'hertz' law has no damping" in err
    assert main(["droptest", "--model", "hertz", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["e_target"] is None
    assert out["restitution"] == pytest.approx(1.0, abs=1e-8)  # elastic: no energy lost


@pytest.mark.parametrize(
    ("model", "relation"),
    [
        ("jankowski", "jankowski2008"),
        ("kelvin", "kelvin"),
        ("hertzdamp", "ye2009"),
        ("hertz", None),
    ],
)
def test_droptest_names_the_relation_it_used(capsys, model, relation):
    """Each law's default xi-e relation (the droptest docstring; Ye et al. 2009 for
    Hertz-damp): ``--json`` gave ``"relation": null`` and the text said ``jankowski2008``
    whatever the law."""
    # the linear laws take their stiffness [N/m] given: Table 3's beta is N/m^1.5
    args = ["droptest", "--model", model, *(["--beta", "1e8"] if model == "kelvin" else [])]
    assert main([*args, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["relation"] == relation
    assert main(args) == 0
    text = capsys.readouterr().out
    assert (f"({relation})" in text) if relation else ("target e" not in text)
    assert ("jankowski2008" in text) == (relation == "jankowski2008")


@pytest.mark.parametrize("model", ["linear", "kelvin"])
def test_droptest_linear_laws_need_their_stiffness(capsys, model):
    """Table 3's beta [N/m^1.5] was taken as the linear law's stiffness [N/m] without a word."""
    assert main(["droptest", "--model", model]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--beta: " in err and "stiffness is in N/m;" in err
    assert main(["droptest", "--model", model, "--beta", "1e8", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["beta"] == 1e8


def test_droptest_refuses_what_a_scene_refuses(capsys):
    """An unknown law was blamed on ``--beta``; a target e below the Jankowski law's table
    (jankowski2008, eq. 2.9: xi = sqrt(5) (1 - e^2) / (2 pi e) = 88.97 at e = 0.004, beyond
    71.17) ran where a scene refuses it."""
    assert main(["droptest", "--model", "bogus"]) == 2
    assert "--model: unknown contact law 'bogus'" in capsys.readouterr().err
    assert main(["droptest", "--e", "0.004"]) == 2
    err = capsys.readouterr().err
    xi = math.sqrt(5) * (1 - 0.004**2) / (2 * math.pi * 0.004)
    assert err.count("\n") == 1 and f"--e: e = 0.004 gives xi = {xi:.4g} under jankowski2008" in err
