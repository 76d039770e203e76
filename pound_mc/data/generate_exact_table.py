"""Write the restitution tables: what one free impact really rebounds with.

``restitution_exact.csv``: the Jankowski law, per ``xi``; ``restitution_hertzdamp.csv``: the
Hertz-damp law, per target ``e`` under each of its relations
(:func:`pound_mc.physics.relations.single_impact_restitution_hertzdamp`, DOP853, rtol 1e-13).

Run from the repository root: ``python pound_mc/data/generate_exact_table.py``.

The grid of ``xi`` is eq. (2.9) of Jankowski (2008) evaluated at evenly spaced targets
``e`` (log-spaced 0.005-0.2, then evenly to 1), which spaces the tabulated restitutions
roughly like the targets.  Each row is one
high-accuracy integration of the dimensionless single impact
(:func:`pound_mc.physics.relations.single_impact_restitution`, DOP853, rtol 1e-13).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from pound_mc.physics.relations import (
    HERTZDAMP_RELATIONS,
    single_impact_restitution,
    single_impact_restitution_hertzdamp,
)

HERE = Path(__file__).resolve().parent


def main() -> None:
    """Compute the table and write it next to this script."""
    targets = np.unique(np.concatenate([np.geomspace(0.005, 0.2, 240), np.linspace(0.2, 1.0, 321)]))
    xi = math.sqrt(5.0) * (1.0 - targets**2) / (2.0 * math.pi * targets)
    xi[-1] = 0.0
    e = np.array([single_impact_restitution(x) for x in xi])
    lines = [
        "# Restitution of one free impact of the Jankowski (2008) non-linear viscoelastic law",
        "# as a function of the impact damping ratio xi (dimensionless single impact",
        "# u'' = -u^1.5 - 2 xi u^0.25 u', DOP853 rtol 1e-13). Made by generate_exact_table.py.",
        "xi,e",
    ]
    lines += [f"{x:.17g},{r:.17g}" for x, r in sorted(zip(xi, e, strict=True))]
    (HERE / "restitution_exact.csv").write_text("\n".join(lines) + "\n")
    rebound = {rel: [single_impact_restitution_hertzdamp(t, rel) for t in targets]
               for rel in HERTZDAMP_RELATIONS}  # fmt: skip
    lines = [
        "# Restitution of one free impact of the Hertz-damp law F = beta delta^1.5 (1 + zeta",
        "# delta'), clipped at 0, with zeta from the target e by each relation (dimensionless",
        "# u'' = -max(u^1.5 (1 + f(e) u'), 0), DOP853 rtol 1e-13).",
        "# Made by generate_exact_table.py.",
        "e," + ",".join(HERTZDAMP_RELATIONS),
    ]
    lines += [f"{t:.17g}," + ",".join(f"{rebound[r][k]:.17g}" for r in HERTZDAMP_RELATIONS)
              for k, t in enumerate(targets)]  # fmt: skip
    (HERE / "restitution_hertzdamp.csv").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
