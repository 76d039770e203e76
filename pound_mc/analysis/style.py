"""One look for every chart: colours, markers, units, labels and legends.

Every chart of :mod:`pound_mc.analysis` takes its line styles, its axis labels and its legend
placement from here, so that charts read alike:

- colours from the Okabe-Ito palette (safe for the common colour-vision deficiencies), each line
  with its own marker, and a new line style every seven lines, so no two lines look alike;
- one choice of units in charts: lengths (gaps, displacements, penetrations) in mm, forces in
  MN, intensities in g, everything else in the dataset's own units;
- units stated once, in brackets after the name (``"initial separation gap [mm]"``);
- legends outside the data (right of the axes, or below panels that share their lines), tick
  labels turned when there are many.
"""

from __future__ import annotations

import contextvars
import textwrap
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.layout_engine import ConstrainedLayoutEngine

from pound_mc._docstring import fill
from pound_mc.analysis.labels import (  # noqa: F401  (charts take the names from here too)
    UNITS,
    chart_units,
    coord_text,
    coords_text,
    intensity_name,
    name_and_units,
    value_text,
)
from pound_mc.errors import InputError, OutputError
from pound_mc.study.files import temporary_beside

__all__ = [
    "PALETTE",
    "MARKERS",
    "line_style",
    "axis_label",
    "caption",
    "take_caption",
    "legend_outside",
    "fit_tick_labels",
    "new_axes",
    "save",
    "legend_below",
    "output_path",
    "no_values",
    "require_simulations",
    "note_left_out",
]

#: Okabe & Ito (2008) colour-blind-safe colours (yellow left out: too pale on white).
PALETTE = ("#0072B2", "#E69F00", "#009E73", "#D55E00", "#CC79A7", "#56B4E9", "#000000")
#: Markers, one per line in turn.
MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*")
_DASHES = ("-", "--", ":")


def line_style(k: int) -> dict:
    """Colour, marker and line style of the ``k``-th line of a chart (all distinct up to 21).

    Returns
    -------
    dict
        ``color``, ``marker`` and ``linestyle``, as :meth:`matplotlib.axes.Axes.plot` takes them.
    """
    n = len(PALETTE)
    return {
        "color": PALETTE[k % n],
        "marker": MARKERS[k % len(MARKERS)],
        "linestyle": _DASHES[(k // n) % len(_DASHES)],
    }


def axis_label(ds: xr.Dataset, name: str) -> str:
    """``"long name [chart units]"`` of variable or coordinate ``name`` of ``ds``.

    The intensity axes read as people write them, with the period of Sa:
    ``"PGA [g]"``, ``"Sa(T = 1.0 s) [g]"``.
    """
    if name in ("pga_g", "sa_g"):
        return f"{intensity_name(ds, name)} [g]"
    long_name, units = name_and_units(ds[name].attrs, name)
    if name == "contact_material":  # names, not numbers: no units
        return long_name
    shown, _ = chart_units(units)
    return f"{long_name} [{shown}]"


def scale_of(ds: xr.Dataset, name: str) -> float:
    """Factor from ``ds[name]``'s stored units to its chart units."""
    return chart_units(name_and_units(ds[name].attrs, name)[1])[1]


def legend_outside(ax: Axes, *, title: str | None = None, size: float = 8, **kwargs) -> None:
    """Legend to the right of the axes, outside the data (nothing drawn if no labels)."""
    handles, labels = ax.get_legend_handles_labels()
    if not handles:
        return
    ax.legend(
        loc="upper left",
        bbox_to_anchor=(1.02, 1.0),
        borderaxespad=0.0,
        fontsize=size,
        title=title,
        title_fontsize=size,
        frameon=False,
        **kwargs,
    )


def legend_below(
    fig: Figure,
    ax: Axes,
    *,
    title: str | None = None,
    size: float = 8,
    handles: Sequence | None = None,
    labels: Sequence[str] | None = None,
    ncols: int = 3,
) -> None:
    """One legend of ``ax``'s lines below every panel of ``fig`` (panels sharing their lines).

    Below rather than beside, so that long labels do not narrow the panels; ``fig`` needs the
    constrained layout (:func:`new_axes`), which keeps room for it above the caption
    (:func:`caption`).  ``handles`` and ``labels``: the entries, when not ``ax``'s.  Nothing is
    drawn if no line has a label.
    """
    if handles is None or labels is None:
        handles, labels = ax.get_legend_handles_labels()
    if not handles:
        return
    ncols = min(len(handles), ncols)
    legend = fig.legend(
        handles,
        labels,
        loc="lower center",
        bbox_to_anchor=(0.5, 0.0),
        bbox_transform=fig.transFigure,
        ncols=ncols,
        fontsize=size,
        title=title,
        title_fontsize=size,
        frameon=False,
    )
    lines = 0  # text lines of the legend: per row its tallest label, and the title's
    for row in range(0, len(labels), ncols):
        lines += max(str(text).count("\n") + 1 for text in labels[row : row + ncols])
    lines += title.count("\n") + 1 if title else 0
    fig._pound_legend = (legend, (lines * size * 1.45 + size) / 72.0)
    _layout_foot(fig)


def fit_tick_labels(ax: Axes, n: int, *, axis: str = "x", most: int = 6) -> None:
    """Turn the tick labels of ``axis`` by 45 degrees when there are more than ``most``."""
    if n > most:
        ax.tick_params(axis=axis, labelrotation=45)
        for label in ax.get_xticklabels() if axis == "x" else ax.get_yticklabels():
            label.set_horizontalalignment("right")
            label.set_rotation_mode("anchor")


#: Whether new figures are pyplot's (the ``ds.pound.plot`` charts drawn for a person: shown by
#: a notebook and by ``plt.show()``) or detached (files: no pyplot state, safe in threads).
_PYPLOT: contextvars.ContextVar[bool | None] = contextvars.ContextVar(
    "pound_mc_pyplot_figures", default=None
)


@contextmanager
def pyplot_figures(on: bool = True, *, unless_set: bool = False) -> Iterator[None]:
    """Inside the block, :func:`new_figure` makes pyplot figures (``on``), else detached ones.

    ``unless_set``: leave the choice of an enclosing block as it is (the report draws the
    accessor's charts into its page, never into pyplot).
    """
    if unless_set and _PYPLOT.get() is not None:
        yield
        return
    token = _PYPLOT.set(on)
    try:
        yield
    finally:
        _PYPLOT.reset(token)


def new_figure(figsize: tuple[float, float]) -> Figure:
    """A new figure with constrained layout: pyplot's inside :func:`pyplot_figures`."""
    if _PYPLOT.get():
        return plt.figure(figsize=figsize, layout="constrained")
    return Figure(figsize=figsize, layout="constrained")


def new_axes(
    ax: Axes | Sequence[Axes] | None,
    figsize: tuple[float, float],
    *,
    nrows: int = 1,
    ncols: int = 1,
    spare: bool = False,
) -> tuple[Figure, np.ndarray]:
    """The figure and axes a chart draws on: ``ax`` given, or a new figure's.

    Parameters
    ----------
    ax : matplotlib.axes.Axes, sequence of Axes, or None
        Where to draw: one Axes per panel of the chart (``nrows * ncols``).
    figsize : tuple of float
        Size of a new figure [in].
    nrows, ncols : int
        Panels of a new figure.
    spare : bool
        Take a given ``ax`` with more Axes than panels (a grid), hiding the spare ones.

    Returns
    -------
    fig : matplotlib.figure.Figure
    axes : numpy.ndarray of Axes
        Flat, ``nrows * ncols`` long.
    """
    if ax is None:
        fig = new_figure(figsize)
        axes = np.asarray(fig.subplots(nrows, ncols, squeeze=False), dtype=object).ravel()
        return fig, axes
    axes = np.asarray([ax] if isinstance(ax, Axes) else list(ax), dtype=object).ravel()
    wanted = nrows * ncols
    if axes.size != wanted and not (spare and axes.size > wanted):
        raise ValueError(f"this chart draws {wanted} panel(s); got {axes.size} Axes")
    for extra in axes[wanted:]:  # a grid of Axes larger than the panels: the rest hidden
        extra.set_visible(False)
    return axes[0].figure, axes[:wanted]


def output_path(path: str | Path, *, key: str | None = None, suffix: str | None = None) -> Path:
    """``path`` as a :class:`~pathlib.Path`, after checking a file can be written there.

    Checked before anything is drawn, so a bad path costs nothing and leaves nothing behind.

    Parameters
    ----------
    path : str or Path
        The file to write (its folders are made when it is written).
    key : str, optional
        The option that gave it (``"--plot"``), named in the error.
    suffix : str, optional
        The file type required (``".png"``), case aside.

    Raises
    ------
    InputError
        ``path`` does not end in ``suffix``.
    OutputError
        ``path`` is a folder, or one of its parents is a file.
    """
    path = Path(path)
    if suffix is not None and path.suffix.lower() != suffix:
        kind = suffix.lstrip(".").upper()
        raise InputError(
            f"the chart is written as {kind}; give a {suffix} file, got {str(path)!r}", key=key
        )
    if path.is_dir():
        raise OutputError("is a folder; give a file name", file=str(path), key=key)
    parent = next((p for p in path.parents if p.exists()), None)
    if parent is not None and not parent.is_dir():
        raise OutputError(f"{parent} is a file, not a folder", file=str(path), key=key)
    return path


def write_atomically(path: str | Path, write) -> Path:
    """Call ``write(tmp)`` on a new temporary file beside ``path``, then move it to ``path``.

    The folders of ``path`` are made first.  ``tmp`` is in a new private folder
    (:func:`pound_mc.study.files.temporary_beside`), so nothing can be planted at it, and
    the rename replaces a link at ``path`` rather than writing through it.  On failure the
    temporary file is removed and an :class:`~pound_mc.errors.OutputError` names ``path``
    (never the temporary file).
    """
    path = output_path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with temporary_beside(path) as tmp:
            write(tmp)
    except OSError as exc:
        raise OutputError(f"cannot be written: {exc.strerror or exc}", file=str(path)) from None
    return path


def no_values(ds: xr.Dataset, values: xr.DataArray) -> bool:
    """Whether ``values`` (a variable of ``ds``, or a part of one) is NaN where status is ok.

    Nothing a chart could draw: the drift of SDOF buildings without ``height_m``, the
    ductility of a building that cannot yield.
    """
    return bool(values.where(ds["status"] == 0).isnull().all())


def require_simulations(ds: xr.Dataset, file: str | None = None) -> None:
    """Refuse a study dataset with an empty dimension (no simulation to chart or report)."""
    empty = [d for d, n in ds["peak_force"].sizes.items() if n == 0]
    if empty:
        raise InputError(f"has no simulations: its dimension {empty[0]!r} is empty", file=file)


def note_left_out(fig: Figure, counted, why: str) -> None:
    """Say in the figure's caption how many simulations a chart leaves out, where any are.

    ``counted``: the mask of the simulations the chart counts; ``why``: which statuses those
    left out have.  No analysis leaves runs out silently.
    """
    mask = np.asarray(counted, dtype=bool)
    n_out = int(mask.size - mask.sum())
    if n_out:
        caption(fig, f"{n_out:,} of {mask.size:,} simulations left out ({why}).")


#: Caption text size [pt].
CAPTION_SIZE = 7.0


def caption(fig: Figure, text: str) -> None:
    """Add ``text`` to the caption at the foot of ``fig``: how the chart was made.

    A chart's title says its answer; its method (what the lines, bands and marks are, what
    was pooled, what was left out) goes here, in small grey text under the axes.  Each text
    is added once (panels drawn by one chart on one figure share it); a figure with the
    constrained layout (:func:`new_figure`) keeps room for it under its axes.
    :func:`take_caption` removes it again (the HTML report writes it under the picture).
    """
    texts = fig.__dict__.setdefault("_pound_caption", [])
    if text in texts:
        return
    texts.append(text)
    _draw_caption(fig)


def _draw_caption(fig: Figure) -> None:
    old = fig.__dict__.pop("_pound_caption_artist", None)
    if old is not None:
        old.remove()
    texts = fig.__dict__.get("_pound_caption", [])
    if texts:
        chars = max(40, int(fig.get_figwidth() * 72 / (CAPTION_SIZE * 0.55)))
        text = textwrap.fill(" ".join(texts), chars)
        fig._pound_caption_artist = fig.text(
            0.005, 0.005, text, fontsize=CAPTION_SIZE, color="dimgray", ha="left", va="bottom"
        )
    _layout_foot(fig)


def _layout_foot(fig: Figure) -> None:
    """Room at the foot of ``fig`` for its caption and, above it, its legend below the panels."""
    caption = fig.__dict__.get("_pound_caption_artist")
    lines = caption.get_text().count("\n") + 1 if caption is not None else 0
    height = (lines * CAPTION_SIZE * 1.3 + 4.0) / 72.0 if lines else 0.0  # [in]
    legend, legend_height = fig.__dict__.get("_pound_legend", (None, 0.0))
    if legend is not None:
        legend.set_bbox_to_anchor((0.5, height / fig.get_figheight()), fig.transFigure)
    engine = fig.get_layout_engine()
    if isinstance(engine, ConstrainedLayoutEngine):
        bottom = (height + legend_height) / fig.get_figheight()
        engine.set(rect=(0.0, bottom, 1.0, 1.0 - bottom))


def take_caption(fig: Figure) -> str:
    """Remove the caption of ``fig`` (:func:`caption`) and return its text (empty if none)."""
    texts = fig.__dict__.pop("_pound_caption", [])
    _draw_caption(fig)
    return " ".join(texts)


def save(fig: Figure, path: str | Path | None) -> Figure:
    """Write ``fig`` as PNG to ``path`` (parent folders created, atomically) and return it."""
    if path is not None:
        write_atomically(path, lambda tmp: fig.savefig(tmp, dpi=130, format="png"))
    return fig


#: Parameter descriptions several charts share, by name (a chart's docstring names one as
#: ``%(name)s`` on a line of its own and is decorated with ``chart_doc``).
CHART_PARAMETERS = {
    "ds": "ds : xarray.Dataset\n    A study dataset.",
    "path": "path : str or Path, optional\n    Where to write the PNG.",
    "record": "record : int or str, optional\n"
    "    Which record (index or name); default all records pooled.",
}
#: Decorator filling a chart's docstring's ``%(name)s`` lines from ``CHART_PARAMETERS``.
chart_doc = fill(**CHART_PARAMETERS)
