"""The command table: every sub-command's arguments and the function that runs it.

Building the parser imports no command's code: :data:`COMMANDS` names, for each sub-command, the
module and function that run it, and :func:`pound_mc.cli.main` imports that one module when
the command is dispatched, so ``pound-mc --help`` stays fast.
"""

from __future__ import annotations

import argparse

from pound_mc.physics.materials import MATERIALS
from pound_mc.physics.names import RELATION_NAMES

__all__ = ["COMMANDS", "KINDS", "HelpFormatter", "add_commands"]

#: Sub-command -> (module, function) that runs it, called with the parsed arguments.
COMMANDS: dict[str, tuple[str, str]] = {
    "materials": ("pound_mc.cli.physics", "materials_command"),
    "calibrate": ("pound_mc.cli.physics", "calibrate_command"),
    "droptest": ("pound_mc.cli.physics", "droptest_command"),
    "records list": ("pound_mc.cli.records", "list_command"),
    "records info": ("pound_mc.cli.records", "info_command"),
    "simulate": ("pound_mc.cli.scene", "simulate_command"),
    "bench": ("pound_mc.cli.scene", "bench_command"),
    "stability": ("pound_mc.cli.scene", "stability_command"),
    "run": ("pound_mc.cli.gate", "run_command"),
    "check": ("pound_mc.cli.gate", "check_command"),
    "compile": ("pound_mc.cli.study", "compile_command"),
    "plot": ("pound_mc.cli.analysis", "plot_command"),
    "report": ("pound_mc.cli.analysis", "report_command"),
    "fragility": ("pound_mc.cli.analysis", "fragility_command"),
    "risk": ("pound_mc.cli.site", "risk_command"),
    "required-gap": ("pound_mc.cli.site", "required_gap_command"),
    "sensitivity": ("pound_mc.cli.sensitivity", "sensitivity_command"),
    "init": ("pound_mc.cli.study", "init_command"),
    "validate": ("pound_mc.cli.validate", "validate_command"),
}

#: Chart kinds of ``pound-mc plot``.
KINDS = (
    "spectrum",
    "probability",
    "distribution",
    "restitution",
    "work-precision",
    "stability",
    "history",
    "fragility",
    "required-gap",
    "contacts",
    "drift",
    "ductility",
)

PLOT_DESCRIPTION = """\
Draw one chart. What FILE is depends on the kind:

  spectrum        a study dataset (the .nc of pound-mc run): median peak force against a
                  grid axis and its 5-95 % band, records and samples pooled (--record N for
                  one, --record each for one line per record, --record median for the median
                  of each record's quantiles)
  probability     a study dataset: pounding probability against the gap (or the first
                  grid axis)
  distribution    a study dataset: peak force box plots and histograms per value of --by
  restitution     a study dataset (its sampled e marked) or nothing: -
  work-precision  the CSV of pound-mc bench (outputs/bench.csv)
  stability       the CSV of pound-mc stability (outputs/stability.csv)
  history         a scene file (.toml), or a study dataset with --sel/--sample: that
                  simulation is rebuilt from the dataset's study text and run again
  fragility       a study dataset with an intensity axis (or --im DIM); --event
  required-gap    a study dataset with the gap on its grid; --probability
  contacts        a shear-building study dataset: peak force at each contact over height
  drift           a study dataset with inelastic buildings: peak storey drift profiles
  ductility       a study dataset with inelastic buildings: peak ductility profiles

A kind that does not apply to the file says so in one line (exit status 2), as does an
option the kind does not read (--im with spectrum, --by with fragility).
"""

COMPILE_DESCRIPTION = (
    "Compile the numba kernels of the given methods and contact laws, for SDOF pairs "
    "and shear buildings, into the user cache (POUND_MC_CACHE_DIR, else "
    "NUMBA_CACHE_DIR/pound-mc, else XDG_CACHE_HOME/pound-mc, else ~/.cache/pound-mc). "
    "Later runs of the same source load them instead of compiling; any edit of the "
    "compiled sources compiles again."
)

VALIDATE_DESCRIPTION = (
    "Run the validation cases on this machine and print one row per compared quantity: the "
    "tool's value, the reference and where it comes from (closed forms, Chopra's El Centro "
    "examples, the seed's Tables 2 and 3, the project's SciPy reference, OpenSees where "
    "openseespy is installed), the relative error, the tolerance and the verdict.  Exit "
    "status 1 when any case fails, 0 otherwise; a case that cannot run is listed with its "
    "reason and is no failure.  docs/validation.md explains every reference and tolerance."
)

INIT_DESCRIPTION = (
    "Write a shipped study file NAME.toml, and the scene files it reads, into the "
    "current folder (or --dir), ready for pound-mc check and pound-mc run. Without "
    "NAME, list the shipped studies. With --new NAME, write a new study NAME.toml from a "
    "commented template to edit: every table with its common keys and what they take."
)

#: Sub-commands with a description for their ``--help`` (the others show their help line).
DESCRIPTIONS = {"plot": PLOT_DESCRIPTION, "compile": COMPILE_DESCRIPTION, "init": INIT_DESCRIPTION,
                "validate": VALIDATE_DESCRIPTION}  # fmt: skip

#: Arguments that several sub-commands share, declared once: name -> (flag, keywords of
#: ``add_argument``); a sub-command adds them with :func:`_shared`.
SHARED_ARGUMENTS: dict[str, tuple[str, dict]] = {
    "study": ("study", dict(metavar="STUDY.toml")),
    "chunk-size": ("--chunk-size", dict(type=int, metavar="N", help="simulations per chunk file")),
    "table-json": ("--json", dict(action="store_true", help="print the table as JSON records")),
    "table-out": ("--out", dict(default="outputs", metavar="DIR", help="folder for CSV and PNG")),
    "im": ("--im", dict(metavar="DIM",
                        help="intensity dimension of the fragility (default sa_g or pga_g)")),
    "event": ("--event", dict(default="pounding",
                              help="pounding (default), peak_force>N (newtons), ductility>X or "
                              "drift>X (drift ratio)")),
}  # fmt: skip


class HelpFormatter(argparse.RawDescriptionHelpFormatter):
    """Descriptions kept as written; every option's default shown unless its help says it."""

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        default = action.default
        if (
            "default" in text
            or "%(default)" in text
            or default in (None, False, [], argparse.SUPPRESS)
            or not action.option_strings
        ):
            return text
        return text + " (default: %(default)s)"


def _code_options(parser: argparse.ArgumentParser) -> None:
    """The code-gap factors of ``risk`` and ``required-gap`` (ASCE 7-22, EN 1998-1)."""
    parser.add_argument("--asce", metavar="R,CD,IE", help="ASCE/SEI 7-22 12.12.2 separation "
                        "with these R, Cd and Ie")  # fmt: skip
    parser.add_argument("--ec8", metavar="Q[,QD]", help="EN 1998-1:2004 4.4.2.7 separation "
                        "with this behaviour factor q (and qd, default q)")  # fmt: skip
    parser.add_argument(
        "--same-levels",
        action="store_true",
        help="floors at the same elevations (EN 1998-1's factor 0.7)",
    )


def _site_options(parser: argparse.ArgumentParser, required: bool) -> None:
    """The IM, event, hazard and target of ``risk`` (and of ``report``'s risk section)."""
    _shared(parser, "im", "event")
    hazard = parser.add_mutually_exclusive_group(required=required)
    hazard.add_argument(
        "--hazard", metavar="FILE.csv", help="hazard curve: columns im [g] and annual_rate [1/year]"
    )
    hazard.add_argument(
        "--hazard-power", metavar="K0,K", help="hazard curve annual_rate = K0 im^-K"
    )
    parser.add_argument("--target-rate", type=float, metavar="R",
                        help="target annual rate [1/year]")  # fmt: skip
    parser.add_argument(
        "--target-probability",
        type=float,
        metavar="P",
        help="target probability of the event in --years years",
    )
    parser.add_argument("--years", type=float, metavar="Y", help="years of --target-probability")


def _json_and_plot(parser: argparse.ArgumentParser, plot_help: str) -> None:
    """The ``--json`` and ``--plot FILE.png`` options of a command that prints one result."""
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--plot", metavar="FILE.png", help=plot_help)


def _command(sub: argparse._SubParsersAction, command: str, **keywords) -> argparse.ArgumentParser:
    """Add the parser of ``command`` (a key of :data:`COMMANDS`; its last word names the parser).

    ``keywords`` go to ``add_parser`` (with the command's :data:`DESCRIPTIONS` entry); the parsed
    arguments carry ``handler=command``, the key :func:`pound_mc.cli.main` dispatches on.
    """
    keywords.setdefault("description", DESCRIPTIONS.get(command))
    parser = sub.add_parser(command.split()[-1], **keywords)
    parser.set_defaults(handler=command, command_parser=parser)  # its own usage in errors
    return parser


def _shared(parser: argparse.ArgumentParser, *names: str) -> None:
    """Add the :data:`SHARED_ARGUMENTS` ``names`` to ``parser``, in that order."""
    for name in names:
        flag, keywords = SHARED_ARGUMENTS[name]
        parser.add_argument(flag, **keywords)


def add_commands(sub: argparse._SubParsersAction) -> None:
    """Add every sub-command to the ``pound-mc`` parser, in the order of ``--help``."""
    for group in (_study, _analysis, _physics, _records, _scene, _validate):
        group(sub)
    _use_formatter(sub)


def _use_formatter(sub: argparse._SubParsersAction) -> None:
    """Give every sub-command's parser (nested ones too) :class:`HelpFormatter`."""
    for parser in sub.choices.values():
        parser.formatter_class = HelpFormatter
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                _use_formatter(action)


def _physics(sub: argparse._SubParsersAction) -> None:
    """The physics sub-commands: ``materials``, ``calibrate``, ``droptest``."""
    p = _command(sub, "materials", help="the seed paper's Tables 1-3 (measured e and beta)")
    p.add_argument("--table", type=int, choices=(1, 2, 3), help="only this table")
    p.add_argument("--json", action="store_true", help="print the tables as JSON")
    p.add_argument("--plot", metavar="FILE.png", help="chart of Table 2 against impact velocity")

    p = _command(sub, "calibrate", help="impact damping ratio xi for a restitution e")
    p.add_argument(
        "--e",
        type=float,
        required=True,
        help="coefficient of restitution, 0.00878 to 1 (below it a relation's xi leaves the "
        "Jankowski law's restitution table)",
    )
    p.add_argument(
        "--relation",
        default="jankowski2008",
        help=f"relation for 'xi' in --json ({', '.join(RELATION_NAMES)}; default jankowski2008)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")

    p = _command(sub, "droptest", help="virtual drop test of the seed's experiment")
    p.add_argument("--material", default="concrete", choices=MATERIALS, help="ball material")
    p.add_argument("--mass", type=float, help="ball mass [kg] (default: middle ball of Table 1)")
    p.add_argument("--velocity", type=float, default=1.0, help="impact velocity [m/s]")
    p.add_argument("--beta", type=float, help="impact stiffness (default: Table 3 mean)")
    group = p.add_mutually_exclusive_group()
    group.add_argument("--e", type=float, help="target restitution (default: Table 2 mid-range)")
    group.add_argument("--xi", type=float, help="impact damping ratio")
    p.add_argument("--relation", default=None, help="xi-e relation (default jankowski2008)")
    p.add_argument("--model", default="jankowski", help="contact law (default jankowski)")
    _json_and_plot(p, "write the force time history chart")
    p.add_argument(
        "--out",
        metavar="DIR",
        help="write the drop-test, relations and Table 2 charts into DIR",
    )


def _records(sub: argparse._SubParsersAction) -> None:
    """``records list`` and ``records info``."""
    p = sub.add_parser("records", help="ground motions: the built-in catalogue, record summaries")
    actions = p.add_subparsers(dest="records_command", metavar="ACTION")
    actions.required = True

    q = _command(
        actions, "records list", help="the built-in records (builtin:NAME) and record suites"
    )
    q.add_argument("--json", action="store_true", help="print the catalogue as JSON")

    q = _command(actions, "records info", help="PGA, duration and step of a record")
    q.add_argument(
        "source",
        metavar="NAME|PATH",
        help="builtin:NAME, synthetic:MODEL, a bare builtin name or a file",
    )
    _json_and_plot(q, "acceleration and 5%%-damped PSA chart")
    q.add_argument(
        "--units",
        help="units of the file's values, overriding the header: g, gal, m/s^2, mm/s^2, in/s^2, "
        "ft/s^2, kilogal (the spellings of the record units key)",
    )
    q.add_argument("--component", help="component of a multi-trace file")
    q.add_argument("--seed", type=int, default=0, help="realisation of a synthetic motion")
    q.add_argument(
        "--raw",
        action="store_true",
        help="keep the record's mean (default: demeaned as in studies)",
    )


def _scene(sub: argparse._SubParsersAction) -> None:
    """Single scenes and the numerics: ``simulate``, ``bench``, ``stability``."""
    p = _command(sub, "simulate", help="run one scene (TOML) and print its results")
    p.add_argument("scene", metavar="SCENE.toml")
    _json_and_plot(p, "chart of displacements, penetration, force")
    p.add_argument("--method", help="override [integrator] method")
    p.add_argument("--dt", type=float, metavar="S", help="override [integrator] dt_s")

    p = _command(
        sub,
        "bench",
        help="speed against accuracy: B1 head to head (ratios), then every method's sweep",
    )
    _shared(p, "table-json", "table-out")
    p.add_argument("--repeats", type=int, default=7, help="timed runs per point (median)")
    p.add_argument("--methods", nargs="+", metavar="METHOD", help="methods to run (all)")
    p.add_argument(
        "--scenes",
        nargs="+",
        metavar="SCENE",
        default=["B1", "shear-3-5"],
        help="benchmark scenes (default: B1 shear-3-5)",
    )
    p.add_argument(
        "--head-to-head-only",
        action="store_true",
        help="only the interleaved B1 comparison and its ratios (no work-precision sweep)",
    )
    p.add_argument(
        "--peers",
        action="store_true",
        help="only B1 in OpenSees (JankowskiImpact, dt 1e-3 and 1e-4 s; needs the extra "
        "'validation') and in adaptive, interleaved, with both errors",
    )

    p = _command(sub, "stability", help="map the largest stable step against contact stiffness")
    _shared(p, "table-out", "table-json")


def _validate(sub: argparse._SubParsersAction) -> None:
    """``validate``: the tool against closed forms, textbook values, tables and references."""
    p = _command(sub, "validate", help="rerun the validation cases: closed forms, Chopra, the "
                 "seed's tables, the SciPy reference (and OpenSees)")  # fmt: skip
    p.add_argument("--json", action="store_true", help="print a list of case objects")
    p.add_argument("--quick", action="store_true", help="only the quick cases (under a minute)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")


def _study(sub: argparse._SubParsersAction) -> None:
    """Studies: ``run`` and ``check``."""
    p = _command(sub, "run", help="run a study and write <out>/<name>.nc and its charts")
    _shared(p, "study")
    p.add_argument("--out", default="outputs", metavar="DIR", help="output folder")
    p.add_argument("--threads", type=int, metavar="N", help="numba threads (in-process run)")
    p.add_argument(
        "--workers",
        type=int,
        metavar="N",
        help="run on a local Dask cluster of N worker processes (one thread each)",
    )
    p.add_argument(
        "--scheduler", metavar="ADDRESS", help="run on the Dask cluster of this scheduler"
    )
    p.add_argument("--fresh", action="store_true", help="discard earlier results of this study")
    _shared(p, "chunk-size")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--no-plot", action="store_true", help="do not draw the study's charts")
    p.add_argument(
        "--dask-timeout",
        type=float,
        default=600.0,
        metavar="S",
        help="Dask: give up when the scheduler does not answer or no chunk finishes for S s (600)",
    )

    p = _command(sub, "check", help="validate a study and print its plan; writes nothing")
    _shared(p, "study")
    p.add_argument("--threads", type=int, metavar="N", help="threads for the estimate")
    _shared(p, "chunk-size")
    p.add_argument(
        "--calibrate",
        type=int,
        metavar="N",
        help="simulations timed for the estimate (default: at least 64, and enough for 1 s)",
    )
    p.add_argument(
        "--out", default="outputs", metavar="DIR", help="output folder of the disk estimate"
    )

    p = _command(
        sub,
        "compile",
        help="compile the kernels into the on-disk cache (cluster images, Dask workers)",
    )
    p.add_argument("--methods", nargs="+", metavar="METHOD", help="methods (default all)")
    p.add_argument("--laws", nargs="+", metavar="LAW", help="contact laws (default all)")
    p.add_argument(
        "--structures",
        nargs="+",
        choices=("sdof", "shear", "yielding"),
        default=["sdof", "shear", "yielding"],
        help="building pairs (default all three; yielding: bilinear shear buildings)",
    )

    p = _command(
        sub, "init", help="write a shipped study (and its scene files) into the current folder"
    )
    p.add_argument("name", nargs="?", metavar="NAME", help="shipped study (e.g. quickstart)")
    p.add_argument("--new", metavar="NAME", help="write a commented template study NAME.toml")
    p.add_argument("--dir", default=".", metavar="DIR", help="folder to write into")
    p.add_argument("--force", action="store_true", help="overwrite files that exist")


def _analysis(sub: argparse._SubParsersAction) -> None:
    """Results: ``plot``, ``fragility``, ``sensitivity`` and ``report``."""
    p = _command(
        sub,
        "plot",
        help="draw a chart of a study dataset, a bench/stability CSV or a scene",
        formatter_class=HelpFormatter,
    )
    p.add_argument("file", metavar="FILE", help="RESULT.nc, bench.csv, stability.csv or SCENE.toml")
    p.add_argument("--kind", required=True, choices=KINDS, help="which chart")
    p.add_argument("--out", metavar="FILE.png", help="PNG to write (default next to FILE)")
    p.add_argument(
        "--sel",
        action="append",
        default=[],
        metavar="DIM=VALUE",
        help="hold a grid dimension (or its study key, left.period_s) at a value (nearest; a "
        "material by name); repeatable",
    )
    p.add_argument(
        "--record",
        metavar="N|NAME",
        help="record index or name; spectrum: also 'each' or 'median' (default: all records "
        "pooled)",
    )
    p.add_argument("--sample", type=int, metavar="N", help="sample index (history; default 0)")
    p.add_argument(
        "--line",
        metavar="DIM",
        help="grid dimension (or its study key) drawn as one line per value",
    )
    p.add_argument(
        "--by", metavar="DIM", help="grid dimension (or its study key) of the distribution's groups"
    )
    _shared(p, "im", "event")
    p.set_defaults(event=None)  # pounding; None tells an option given from one left out
    p.add_argument(
        "--probability", type=float, help="target probability (required-gap; default 0.1)"
    )

    p = _command(sub, "fragility", help="fit lognormal fragility curves to a study dataset")
    p.add_argument("file", metavar="RESULT.nc")
    _shared(p, "im", "event")
    p.add_argument("--n-boot", type=int, default=1000, metavar="N", help="bootstrap replicates")
    p.add_argument("--json", action="store_true", help="print one JSON object")

    p = _command(sub, "risk", help="annual rate of an event per gap at a site, and the gap that "
                 "meets a target")  # fmt: skip
    p.add_argument("file", metavar="RESULT.nc")
    _site_options(p, required=True)
    p.add_argument(
        "--method",
        default="fragility",
        choices=("fragility", "stripes"),
        help="integrate the fitted fragility or the stripes themselves",
    )
    _code_options(p)
    p.add_argument("--n-boot", type=int, default=1000, metavar="N", help="bootstrap replicates")
    _json_and_plot(p, "chart of the annual rate against the gap")

    p = _command(sub, "required-gap", help="the gap that keeps the pounding probability under "
                 "P, per intensity, beside the rules' and codes' gaps")  # fmt: skip
    p.add_argument("file", metavar="RESULT.nc")
    p.add_argument(
        "--probability",
        type=float,
        default=0.1,
        metavar="P",
        help="target probability of pounding at each intensity",
    )
    _code_options(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")

    p = _command(
        sub,
        "sensitivity",
        help="Sobol' first- and total-order indices of a saltelli study's output",
    )
    p.add_argument("file", metavar="RESULT.nc")
    p.add_argument(
        "--output",
        default="peak_force",
        metavar="VAR",
        help="peak_force (default), pounding, ductility or a per-simulation variable",
    )
    p.add_argument("--n-boot", type=int, default=1000, metavar="N", help="bootstrap resamples")
    _json_and_plot(p, "bar chart of S1 and ST per sampled key, with their intervals")

    p = _command(sub, "report", help="write a self-contained HTML results page of a study")
    p.add_argument("file", metavar="RESULT.nc")
    p.add_argument("--out", metavar="FILE.html", help="page to write (default next to RESULT.nc)")
    # a risk section where a hazard is given (as pound-mc risk, the fitted fragility)
    _site_options(p, required=False)
    _code_options(p)
