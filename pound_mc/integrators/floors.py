"""Floor displacements from the modes of their own building, penetrations as their differences.

Each building's modes move only its own floors: row ``f`` of ``phi`` is zero outside the
columns of its building's modes, so a floor's displacement is a dot product over those columns
only (:func:`floor_blocks`), the same sum in the same order as over the whole row less terms
that are exactly zero.  A contact's weights are ``psi_c = phi[left floor] - phi[right floor]``
(:meth:`pound_mc.scene.Scene.modal_arrays`), so its penetration is the difference of two floor
displacements less the gap: one subtraction once the floors are known instead of a dot product
over every mode (:func:`contact_floors` finds the two floors of each contact from ``psi``).
For an SDOF pair both forms give the same bits.
"""

from __future__ import annotations

import numpy as np

from pound_mc._jit import jit
from pound_mc.integrators.toolkit import hermite_max, rowdot


@jit
def floor_blocks(phi):
    """First and one-past-last column with a nonzero weight in each floor's row of ``phi``."""
    nf, n = phi.shape
    lo = np.zeros(nf, dtype=np.int64)
    hi = np.zeros(nf, dtype=np.int64)
    for f in range(nf):
        first = n
        last = -1
        for j in range(n):
            if phi[f, j] != 0.0:
                if first == n:
                    first = j
                last = j
        if last >= 0:
            lo[f] = first
            hi[f] = last + 1
    return lo, hi


@jit
def contact_floors(phi, psi, lo, hi):
    """Floors ``(left, right)`` of each contact with ``psi_c = phi[left] - phi[right]``.

    ``-1`` where no pair of floors gives ``psi_c`` exactly (the contact's penetration is then
    its dot product with the modal state).
    """
    nc, n = psi.shape
    nf = phi.shape[0]
    left = np.full(nc, -1, dtype=np.int64)
    right = np.full(nc, -1, dtype=np.int64)
    for c in range(nc):
        for f in range(nf):
            for sign in range(2):
                match = hi[f] > lo[f]
                for j in range(lo[f], hi[f]):
                    w = phi[f, j] if sign == 0 else -phi[f, j]
                    if psi[c, j] != w:
                        match = False
                        break
                if match:
                    if sign == 0 and left[c] < 0:
                        left[c] = f
                    elif sign == 1 and right[c] < 0:
                        right[c] = f
        if left[c] >= 0 and right[c] >= 0:
            # the two floors' columns must hold every nonzero weight of psi_c
            for j in range(n):
                inside = (lo[left[c]] <= j < hi[left[c]]) or (lo[right[c]] <= j < hi[right[c]])
                if psi[c, j] != 0.0 and not inside:
                    left[c] = -1
        if left[c] < 0 or right[c] < 0:
            left[c] = -1
            right[c] = -1
    return left, right


@jit(inline=True)
def blockdot(phi, f, lo, hi, x):
    """Displacement (or velocity) of floor ``f``: row ``f`` of ``phi`` dotted with ``x``."""
    acc = 0.0
    for j in range(lo[f], hi[f]):
        acc += phi[f, j] * x[j]
    return acc


@jit(inline=True)
def floor_values(phi, lo, hi, q, v, xf, xfd):
    """Every floor's displacement and velocity into ``xf, xfd``."""
    for f in range(phi.shape[0]):
        xf[f] = blockdot(phi, f, lo, hi, q)
        xfd[f] = blockdot(phi, f, lo, hi, v)


@jit(inline=True)
def penetrations(xf, xfd, q, v, psi, gap, left, right, dc, ddc):
    """Every contact's penetration and its rate into ``dc, ddc`` from the floors' values."""
    for c in range(gap.size):
        if left[c] >= 0:
            dc[c] = xf[left[c]] - xf[right[c]] - gap[c]
            ddc[c] = xfd[left[c]] - xfd[right[c]]
        else:
            dc[c] = rowdot(psi, c, q) - gap[c]
            ddc[c] = rowdot(psi, c, v)


@jit
def track_floor_blocks(phi, lo, hi, q0, v0, q1, v1, h, peaks):
    """Update the continuous-time peak |x| of every floor over a step (Hermite)."""
    for f in range(phi.shape[0]):
        x0 = blockdot(phi, f, lo, hi, q0)
        x1 = blockdot(phi, f, lo, hi, q1)
        m = abs(x1)
        if m > peaks[f]:
            peaks[f] = m
        xd0 = blockdot(phi, f, lo, hi, v0)
        xd1 = blockdot(phi, f, lo, hi, v1)
        if (xd0 > 0.0) != (xd1 > 0.0):
            hm, _ = hermite_max(x0, xd0, x1, xd1, h)
            if hm > peaks[f]:
                peaks[f] = hm
            hm, _ = hermite_max(-x0, -xd0, -x1, -xd1, h)
            if hm > peaks[f]:
                peaks[f] = hm
