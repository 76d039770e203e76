"""Shared docstring blocks (:mod:`pound_mc._docstring`): filled in place, nothing left over."""

import importlib
import inspect
import pkgutil

import pytest

import pound_mc
from pound_mc._docstring import _PLACEHOLDER, fill
from pound_mc.analysis.distribution_chart import distribution_chart
from pound_mc.analysis.plot import probability_chart
from pound_mc.physics.structures import sdof, shear_building


def test_block_takes_the_placeholders_indentation():
    @fill(x="x : float\n    The x [m].")
    def f():
        """Title, 5 % of it.

        Parameters
        ----------
        %(x)s
        """

    # the docstring as it would read with the block written out in place
    assert f.__doc__ == (
        "Title, 5 % of it.\n\n        Parameters\n        ----------\n"
        "        x : float\n            The x [m].\n        "
    )


def test_placeholder_without_a_block_fails():
    with pytest.raises(KeyError, match="y"):

        @fill(x="x : float")
        def f():
            """Title.

            %(y)s
            """


def test_charts_and_buildings_read_as_before():
    # the texts these docstrings had before their shared blocks were written once
    for func in (probability_chart, distribution_chart):
        assert (
            "    ds : xarray.Dataset\n        A study dataset.\n"
            "    path : str or Path, optional\n        Where to write the PNG.\n"
        ) in func.__doc__
        assert (
            "    record : int or str, optional\n"
            "        Which record (index or name); default all records pooled.\n"
        ) in func.__doc__
    for func in (sdof, shear_building):
        bw = "    bw_exponent : float, optional\n        Bouc-Wen exponent ``n`` [-] (default 2).\n"
        assert bw in func.__doc__


def test_no_placeholder_left_in_the_package():
    left = []
    for info in pkgutil.walk_packages(pound_mc.__path__, "pound_mc."):
        if info.name.endswith(("__main__", "generate_exact_table")):
            continue
        module = importlib.import_module(info.name)
        for name, obj in vars(module).items():
            if inspect.isfunction(obj) and _PLACEHOLDER.search(obj.__doc__ or ""):
                left.append(f"{info.name}.{name}")
    assert not left, left
