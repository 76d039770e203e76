"""Layout of the kernels' outputs: names, slots and the end-of-run summary.

One simulation fills a vector of :data:`OUTPUTS` and a matrix with one row per contact and the
columns of :data:`CONTACT_OUTPUTS`.  Kernels write them through the slot constants below (the
only place that numbers them); :mod:`pound_mc.integrators.batch` turns them into named arrays.
"""

from __future__ import annotations

import math

import numpy as np

from pound_mc._jit import jit
from pound_mc.integrators.toolkit import mechanical_energy

#: Per-simulation outputs, in the order of the kernel's output vector.
OUTPUTS = (
    "peak_force",
    "impacts",
    "max_penetration",
    "peak_disp_left",
    "peak_disp_right",
    "impulse",
    "dissipated_energy",
    "energy_residual",
    "status",
    "input_energy",
    "steps",
    "peak_force_time",
    # inelastic buildings (NaN from the elastic kernels): DESIGN.md section 9
    "peak_ductility_left",
    "peak_ductility_right",
    "peak_drift_left",
    "peak_drift_right",
    "residual_drift_left",
    "residual_drift_right",
    "hysteretic_energy",
    "peak_floor_accel_left",
    "peak_floor_accel_right",
    # impact velocities and per-impact restitution: DESIGN.md section 9
    "max_impact_velocity",
    "median_impact_velocity",
    "peak_force_restitution",
)
N_OUT = len(OUTPUTS)
(
    PEAK_FORCE, IMPACTS, MAX_PENETRATION, PEAK_DISP_LEFT, PEAK_DISP_RIGHT, IMPULSE,
    DISSIPATED_ENERGY, ENERGY_RESIDUAL, STATUS, INPUT_ENERGY, STEPS, PEAK_FORCE_TIME,
) = range(12)  # fmt: skip
(
    PEAK_DUCTILITY_LEFT, PEAK_DUCTILITY_RIGHT, PEAK_DRIFT_LEFT, PEAK_DRIFT_RIGHT,
    RESIDUAL_DRIFT_LEFT, RESIDUAL_DRIFT_RIGHT, HYSTERETIC_ENERGY, PEAK_FLOOR_ACCEL_LEFT,
    PEAK_FLOOR_ACCEL_RIGHT,
) = range(12, 21)  # fmt: skip
#: Outputs of inelastic runs only (the storeys' responses), NaN from the elastic kernels.
INELASTIC_OUTPUTS = OUTPUTS[PEAK_DUCTILITY_LEFT : PEAK_FLOOR_ACCEL_RIGHT + 1]
MAX_IMPACT_VELOCITY, MEDIAN_IMPACT_VELOCITY, PEAK_FORCE_RESTITUTION = range(21, N_OUT)
#: Outputs that are NaN for a run that is not ok (no plain numbers to be taken for results).
_NAN_WHEN_FAILED = (
    PEAK_FORCE, MAX_PENETRATION, PEAK_DISP_LEFT, PEAK_DISP_RIGHT, IMPULSE, DISSIPATED_ENERGY,
    ENERGY_RESIDUAL,
)  # fmt: skip

#: Per-contact outputs (columns of the kernel's contact matrix).
CONTACT_OUTPUTS = ("peak_force", "impacts", "max_penetration", "impulse", "max_impact_velocity")
N_COUT = len(CONTACT_OUTPUTS)
C_PEAK_FORCE, C_IMPACTS, C_MAX_PENETRATION, C_IMPULSE, C_MAX_IMPACT_VELOCITY = range(N_COUT)

#: Status codes of a run.
STATUS_OK, STATUS_UNSTABLE, STATUS_NOT_CONVERGED = 0, 1, 2
#: (3, ``inaccurate``, is set after the kernels: :mod:`pound_mc.integrators.accuracy`.)

#: A run whose energy balance is broken by more than this fraction of the energy put in
#: (energy created by the integrator) is flagged unstable.
UNSTABLE_ENERGY_FRACTION = 0.5
#: A displacement beyond this [m] is a diverging run.
DIVERGENCE_LIMIT_M = 1.0e3
#: A contact episode counts as an impact only once its penetration exceeds this [m]: far above
#: the round-off of floor displacements (1e-16 of metres), far below any physical contact
#: (B1's impacts reach 1e-4 m).  Episodes of identical buildings that differ in the last bit
#: of a period (6e-17 m) are no impacts.
IMPACT_MIN_PENETRATION_M = 1.0e-9

# Shared linear response before the first contact (``pre`` of the adaptive kernel): slots of
# the run mode, the record interval reached, input and damping energy, steps and initial
# energy, then ``q`` (n), ``v`` (n) and the floors' peaks (nf).  Mode 1: run linearly to the
# first contact onset and leave the state at the start of that interval; mode 2: resume;
# mode 3 (``adaptive``, both kernels): resume for the peak force alone (the accuracy check's
# finer run): no energies, floor peaks or other outputs, the same trajectory and peak force.
PRE_MODE, PRE_INTERVAL, PRE_E_IN, PRE_E_D, PRE_STEPS, PRE_E0, PRE_STATE = range(7)
PRE_RUN_TO_CONTACT, PRE_RESUME, PRE_RESUME_PEAK = 1, 2, 3


def pre_size(n_modes: int, n_floors: int) -> int:
    """Length of a shared-state vector for ``n_modes`` modes and ``n_floors`` floors."""
    return PRE_STATE + 2 * n_modes + n_floors


# Mode 4 (SDOF-pair ``adaptive``): resume for the peak force and the floors' peaks (no
# energies; the peaks so far in the floors' slots of the state), from the start of
# the linear step in which a contact began: the last onset before which the accuracy check's
# finer run takes the run's very sub-steps, so that the two runs are bitwise the same up to
# there.  The slots of a pair's ``pre`` are followed by the step's start within its interval,
# its grid index, the peak force so far and the force law's damping constants (c0 and the
# episode's damping ratio); the run writes them past its outputs' ``same`` slot.
PRE_RESUME_ONSET = 4
ONSET_S, ONSET_GRID, ONSET_PEAK, ONSET_CD, ONSET_ZHD = range(pre_size(2, 2), pre_size(2, 2) + 5)
ONSET_SIZE = ONSET_ZHD + 1


@jit
def reset_contacts(cout):
    """Initial per-contact outputs: no force, no impact, no penetration yet, no impulse."""
    for c in range(cout.shape[0]):
        cout[c, C_PEAK_FORCE] = 0.0
        cout[c, C_IMPACTS] = 0.0
        cout[c, C_MAX_PENETRATION] = -np.inf
        cout[c, C_IMPULSE] = 0.0
        cout[c, C_MAX_IMPACT_VELOCITY] = 0.0


@jit
def snapshot(pre, i, e_in, e_d, steps, e0, q, v, peaks):
    """Store the state of a run at the start of record interval ``i`` in ``pre``."""
    n = q.size
    pre[PRE_INTERVAL] = i
    pre[PRE_E_IN] = e_in
    pre[PRE_E_D] = e_d
    pre[PRE_STEPS] = steps
    pre[PRE_E0] = e0
    for j in range(n):
        pre[PRE_STATE + j] = q[j]
        pre[PRE_STATE + n + j] = v[j]
    for f in range(peaks.size):
        pre[PRE_STATE + 2 * n + f] = peaks[f]


@jit
def fail(out, cout, status):
    """Outputs of a run that could not start (NaN, no impact, no step) with ``status``."""
    for k in range(out.size):
        out[k] = np.nan
    out[IMPACTS] = 0.0
    out[STATUS] = status
    out[STEPS] = 0.0
    for c in range(cout.shape[0]):
        for k in range(cout.shape[1]):
            cout[c, k] = np.nan


#: Codes of the floors' buildings (the kernels' ``side``): the first building of a pair or a
#: row (``left``) and the last (``right``); from 2 on, the other buildings of a row and a wall
#: that closes one (:meth:`pound_mc.scene.Scene.side_codes`).  The ``*_left`` / ``*_right``
#: outputs are the first's and the last's; with codes past 1, ``out`` may hold each code's
#: peak displacement past :data:`N_OUT` (:func:`finish`).
SIDE_FIRST, SIDE_LAST = 0, 1


@jit
def _row_peaks(out, peaks, side, n_codes):
    """Peak displacement of each building code, at ``out[N_OUT + code]``."""
    for k in range(n_codes):
        out[N_OUT + k] = 0.0
    for f in range(peaks.size):
        out[N_OUT + side[f]] = max(out[N_OUT + side[f]], peaks[f])


@jit
def finish(out, cout, peaks, side, phase, q, v, omega, e0, e_in, e_d, w_c, stored, peak_f,
           peak_t, steps, status):  # fmt: skip
    """Fill the output vector at the end of a run: maxima, energy balance and status.

    A row (``side`` codes past :data:`SIDE_LAST`) whose ``out`` has a slot per code past
    :data:`N_OUT` gets each code's peak displacement there.
    """
    nc = cout.shape[0]
    e_mech = mechanical_energy(q, v, omega)
    scale = abs(e_in) + e0
    if scale <= 0.0:
        scale = 1e-300
    residual = (e0 + e_in - e_mech - e_d - w_c) / scale
    pl = 0.0
    pr = 0.0
    n_row = 0  # codes of a row's buildings past the first and last (0: a pair)
    for f in range(peaks.size):
        if side[f] == SIDE_FIRST:
            pl = max(pl, peaks[f])
        elif side[f] == SIDE_LAST:
            pr = max(pr, peaks[f])
        else:
            n_row = max(n_row, side[f] + 1)
        if peaks[f] > DIVERGENCE_LIMIT_M:
            status = STATUS_UNSTABLE
    if n_row > 0 and out.size >= N_OUT + n_row:
        _row_peaks(out, peaks, side, n_row)
    if status == STATUS_OK and not math.isfinite(residual):
        status = STATUS_UNSTABLE
    if status == STATUS_OK and abs(residual) > UNSTABLE_ENERGY_FRACTION:
        status = STATUS_UNSTABLE
    impacts = 0.0
    maxpen = -np.inf
    impulse = 0.0
    for c in range(nc):
        impacts += cout[c, C_IMPACTS]
        maxpen = max(maxpen, cout[c, C_MAX_PENETRATION])
        impulse += cout[c, C_IMPULSE]
    out[PEAK_FORCE] = peak_f
    out[IMPACTS] = impacts
    out[MAX_PENETRATION] = maxpen if impacts > 0 else 0.0
    out[PEAK_DISP_LEFT] = pl
    out[PEAK_DISP_RIGHT] = pr
    out[IMPULSE] = impulse
    out[DISSIPATED_ENERGY] = w_c - stored
    out[ENERGY_RESIDUAL] = residual
    out[STATUS] = status
    out[INPUT_ENERGY] = e_in
    out[STEPS] = steps
    out[PEAK_FORCE_TIME] = peak_t
    for k in range(PEAK_DUCTILITY_LEFT, PEAK_FLOOR_ACCEL_RIGHT + 1):
        out[k] = np.nan  # filled by the inelastic kernel after this
    if status != STATUS_OK:
        # unstable or not converged: no plain numbers that could be taken for results
        for k in _NAN_WHEN_FAILED:
            out[k] = np.nan
        if n_row > 0 and out.size >= N_OUT + n_row:
            for k in range(n_row):
                out[N_OUT + k] = np.nan
        for c in range(nc):
            cout[c, C_PEAK_FORCE] = np.nan
            cout[c, C_MAX_PENETRATION] = np.nan
            cout[c, C_IMPULSE] = np.nan
    else:
        for c in range(nc):
            if cout[c, C_IMPACTS] == 0.0:
                cout[c, C_MAX_PENETRATION] = 0.0


@jit(inline=True)
def peak_only(out, cout, peak_f, status):
    """The outputs of a run for its peak force alone (``PRE_RESUME_PEAK``): that and the status.

    Every other output is NaN; the peak force too unless the run is ok.
    """
    out[:] = np.nan
    cout[:] = np.nan
    out[PEAK_FORCE] = peak_f if status == STATUS_OK else np.nan
    out[STATUS] = status


# Impact velocities (the relative velocity at contact onset, the prior-impact velocity of the
# seed's Table 2) and the restitution of each episode: ``episodes`` has a row per contact with
# the onset velocity [m/s] and the restitution [-] of its current episode (NaN: fixed
# restitution); ``log`` collects the onset velocity of every impact; ``peak_e`` (one value) the
# restitution of the episode that holds the peak force.
EP_V0, EP_E = 0, 1


# Element loops instead of numpy's fill, slice copy and reductions: their compiled
# implementations cost seconds of every first run's compile for a handful of values.


@jit
def impact_log(nc):
    """Empty episode table, impact-velocity log and peak-force restitution of a run."""
    ep = np.empty((nc, 2))
    for c in range(nc):
        ep[c, EP_V0] = np.nan
        ep[c, EP_E] = np.nan
    peak_e = np.empty(1)
    peak_e[0] = np.nan
    return ep, np.zeros(16), peak_e


@jit
def log_impact_in(box, count, v0):
    """Append ``v0`` to the log ``box[0]`` (doubled when full); returns the new count.

    ``box`` is a list of one log, for a kernel's hot loop: an array variable that the loop
    reassigns (the log, when it grows) has its reference count changed, atomically, at every
    join of the loop's blocks (numba's SSA copies), while a list that is never reassigned has
    none (the SDOF-pair ``adaptive``: 29 % of its time in those counts, B1-like pairs).
    """
    log = box[0]
    if count == log.size:
        grown = np.empty(2 * log.size)
        for k in range(count):
            grown[k] = log[k]
        box[0] = grown
        log = grown
    log[count] = v0
    return count + 1


@jit
def log_max(log, count):
    """Largest of the first ``count`` values of ``log`` (0 when there are none)."""
    top = 0.0
    for k in range(count):
        if k == 0 or log[k] > top:
            top = log[k]
    return top


@jit
def _sorted(log, count):
    """The first ``count`` values of ``log`` in ascending order (Shell sort, Knuth's gaps).

    Instead of ``np.sort``, whose compiled quicksort costs seconds of the first run's compile
    for the few impact velocities of a run (O(n^1.5): 10,000 impacts sort in about 1e6 steps).
    """
    vals = np.empty(count)
    for k in range(count):
        vals[k] = log[k]
    gap = 1
    while 3 * gap + 1 < count:
        gap = 3 * gap + 1
    while gap >= 1:
        for k in range(gap, count):
            x = vals[k]
            j = k - gap
            while j >= 0 and vals[j] > x:
                vals[j + gap] = vals[j]
                j -= gap
            vals[j + gap] = x
        gap //= 3
    return vals


@jit
def finish_impacts(out, cout, log, count, peak_e):
    """Impact-velocity outputs (max, median), per-contact maxima and the peak-force ``e``.

    Called after :func:`finish`; a run that is not ok reports NaN, one without impacts 0
    velocities and NaN restitution.
    """
    vmax = 0.0
    med = 0.0
    if count > 0:
        vals = _sorted(log, count)
        vmax = vals[count - 1]
        mid = count // 2
        med = vals[mid] if count % 2 == 1 else 0.5 * (vals[mid - 1] + vals[mid])
    out[MAX_IMPACT_VELOCITY] = vmax
    out[MEDIAN_IMPACT_VELOCITY] = med
    out[PEAK_FORCE_RESTITUTION] = peak_e if count > 0 else np.nan
    if out[STATUS] != STATUS_OK:
        out[MAX_IMPACT_VELOCITY] = np.nan
        out[MEDIAN_IMPACT_VELOCITY] = np.nan
        out[PEAK_FORCE_RESTITUTION] = np.nan
        for c in range(cout.shape[0]):
            cout[c, C_MAX_IMPACT_VELOCITY] = np.nan
