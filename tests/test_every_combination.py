"""Every combination of structure, storey law, restitution and method against the reference.

The cases are :mod:`pound_mc.numerics.combinations`'s (5 structures x 4 storey laws x 2
restitutions x 4 methods = 160 runs, 3 s of El Centro 1940 at 0.5 g); the reference is
:func:`pound_mc.integrators.reference.reference_solution` (SciPy DOP853 at ``rtol = 1e-11``,
every switch located, no code shared with the kernels).  Each run must end ok with the
reference's impacts and every compared output within its method's tolerance
(:data:`~pound_mc.numerics.combinations.TOLERANCE`: ``adaptive`` 1e-5 at its defaults, the
fixed-step methods at 5e-5 s by their order).  ``docs/tables/combinations.md`` is the
table of the same runs (``python -m pound_mc.numerics.combinations``); the last test holds it
to the cases.
"""

from pathlib import Path

import pytest

from pound_mc.numerics import combinations as grid

ROOT = Path(__file__).resolve().parents[1]
CASES = [(s, law, r) for s in grid.STRUCTURES for law in grid.LAWS for r in grid.RESTITUTIONS]


@pytest.mark.slow
@pytest.mark.parametrize(("structure", "law", "restitution"), CASES,
                         ids=["-".join(c) for c in CASES])  # fmt: skip
def test_every_method_meets_the_reference(structure, law, restitution):
    ref = grid.reference(structure, law, restitution)
    assert ref["impacts"] > 0  # every case pounds
    if law != "elastic":  # the yielding building yields
        assert ref["peak_ductility_left"] > 1.0
    for method in grid.METHODS:
        got = grid.run(structure, law, restitution, method)
        assert got["status"] == 0 and got["impacts"] == ref["impacts"], method
        errors = grid.compare(got, ref)
        assert errors["largest"] <= grid.TOLERANCE[method], (method, errors)


def test_the_docs_table_lists_every_combination():
    # one line per structure, law and restitution, a column per method
    text = (ROOT / "docs" / "tables" / "combinations.md").read_text()
    lines = text.strip().splitlines()
    assert all(f"`{m}`" in lines[0] for m in grid.METHODS)
    rows = [[c.strip() for c in line.strip("|").split("|")] for line in lines[2:]]
    assert [tuple(r[:3]) for r in rows] == CASES
    for row in rows:  # every run ok and within its method's tolerance when the table was made
        for method, cell in zip(grid.METHODS, row[4:], strict=True):
            assert float(cell) <= grid.TOLERANCE[method], (row, method)
