"""Storey laws of yielding buildings as the error-controlled ``adaptive`` kernel steps them.

A yielding storey ``s`` (stiffness ``k``, yield drift ``u_y``, post-yield ratio ``alpha``)
resists its drift ``u`` with ``alpha k u + (1 - alpha) k z`` (``../shared/DESIGN.md`` section 9).
Its hysteretic drift ``z`` is one state variable of :mod:`pound_mc.integrators.adaptive_rk`,
with a rate ``z' = g(z, u') u'`` and a discrete state (the law's *branch*) that changes only at
located events, so that ``g`` is smooth inside every step:

* ``bilinear`` (kinematic hardening, ``z`` elastic-perfectly-plastic): branch 0 elastic
  (``z' = u'``), branch ``+1`` / ``-1`` yielding at ``z = +-u_y`` (``z' = 0``).  Events: elastic ->
  yielding where ``|z|`` reaches ``u_y``; yielding -> elastic where the drift rate turns
  (``branch u'`` from positive to negative).
* ``bouc-wen`` (exponent ``n``; the form of :func:`pound_mc.integrators.hysteretic.bouc_wen`):
  ``z' = u' (1 - |z / u_y|^n (1 if u' z > 0 else 0))``; the branch is the sign of ``u'``
  (``+-1``), and the event is the drift rate's turn, where the law switches between its
  loading and unloading forms.

Each law is the three functions below, switched on the storey's code (``LAW_BILINEAR``,
``LAW_BOUC_WEN``); a new storey law is a new code and its three functions, the kernel unchanged.
"""

from __future__ import annotations

import math

from pound_mc._jit import jit
from pound_mc.integrators.toolkit import hermite_max, hermite_root

__all__ = [
    "LAW_BILINEAR",
    "LAW_BOUC_WEN",
    "z_rate",
    "storey_event",
    "storey_switch",
    "settled_branch",
]

LAW_BILINEAR = 0
LAW_BOUC_WEN = 1
#: A yield event needs ``|z|`` beyond the yield drift by this fraction of it [-]: a storey that
#: has just unloaded at ``|z| = u_y`` does not yield again on round-off.
YIELD_TOL = 1e-13


@jit(inline=True)
def z_rate(law, branch, z, du, uy, n):
    """Rate of the hysteretic drift ``z`` [m/s] on a branch, at drift rate ``du`` [m/s]."""
    if law == LAW_BILINEAR:
        return du if branch == 0 else 0.0
    if z * branch > 0.0:  # loading away from z = 0 (the branch is the sign of du)
        return du * (1.0 - (abs(z) / uy) ** n)
    return du


@jit(inline=True)
def storey_event(law, branch, z0, z1, du0, du1, dda0, dda1, uy, h):
    """First switch of a storey's branch inside a step of length ``h`` [s], or inf.

    ``z``: hysteretic drift at both ends [m]; ``du, dda``: drift rate and its rate at both ends
    (the cubic Hermite interpolants of ``z`` with rate ``z'`` and of ``u'`` with rate ``u''``
    locate the switch).
    """
    if law == LAW_BILINEAR and branch == 0:
        lim = uy * (1.0 + YIELD_TOL)
        best = math.inf
        for sg in (1.0, -1.0):
            y0 = sg * z0 - lim
            y1 = sg * z1 - lim
            if y0 > 0.0:
                continue
            if y1 > 0.0:
                best = min(best, hermite_root(y0, sg * du0, y1, sg * du1, h))
            elif sg * du0 > 0.0 and sg * du1 < 0.0:
                hm, tm = hermite_max(y0, sg * du0, y1, sg * du1, h)
                if hm > 0.0:
                    best = min(best, hermite_root(y0, sg * du0, hm, 0.0, tm))
        return best
    # the drift rate turns against the branch (bilinear yielding, Bouc-Wen either), also where
    # it turns and turns back inside the step (both ends on the branch's side)
    b = float(branch)
    y0 = b * du0
    y1 = b * du1
    if y0 > 0.0 and y1 <= 0.0:
        return hermite_root(y0, b * dda0, y1, b * dda1, h)
    if y0 > 0.0 and y1 > 0.0 and b * dda0 < 0.0 and b * dda1 > 0.0:
        hm, tm = hermite_max(-y0, -b * dda0, -y1, -b * dda1, h)
        if hm > 0.0:  # the rate's least value is below 0: the first root before it
            return hermite_root(y0, b * dda0, -hm, 0.0, tm)
    return math.inf


@jit(inline=True)
def storey_switch(law, branch, z, du, uy):
    """The branch after a located switch and the hysteretic drift there (clamped at yield)."""
    if law == LAW_BILINEAR:
        if branch == 0:
            return (1 if z > 0.0 else -1), (uy if z > 0.0 else -uy)
        return 0, z
    return -branch, z


@jit(inline=True)
def settled_branch(law, branch, z, du, dda, uy, du_tol):
    """The branch a storey takes at a state where its branch may switch (start, events).

    ``du, dda``: drift rate and its rate; where ``|du| <= du_tol`` (at a located turn of the
    drift, within the root's round-off) the rate's rate decides the direction.  A bilinear
    storey yields only while its drift moves outwards beyond ``u_y`` (a yield located at the
    top of a grazing drift, where the drift turns at once, unloads there), and a Bouc-Wen
    storey's branch is its drift's direction.
    """
    out = du if abs(du) > du_tol else dda
    if law == LAW_BILINEAR:
        if branch != 0:
            return branch if branch * out > 0.0 else 0
        if abs(z) > uy * (1.0 + YIELD_TOL) and z * out > 0.0:
            return 1 if z > 0.0 else -1
        return 0
    if out == 0.0:
        return branch if branch != 0 else 1
    return 1 if out > 0.0 else -1
