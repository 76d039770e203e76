"""Accuracy of the compiled integrators against independent solutions.

Independent references used here (none shares code with the compiled kernels):

* closed-form damped free vibration of an SDOF oscillator (Chopra, Dynamics of Structures,
  eq. 2.2.4);
* the matrix exponential of the physical first-order system augmented with the linearly
  interpolated ground acceleration (exact for a piecewise-linear record, physical floor
  coordinates, not modes);
* :func:`pound_mc.integrators.reference.reference_solution`: SciPy DOP853 at rtol 1e-11 in physical
  coordinates with the contact law written out and contact phases as terminal events.
"""

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.linalg import expm, sqrtm

from pound_mc.integrators import batch, kernel_settings, run_kernel
from pound_mc.integrators.outputs import (
    N_COUT,
    N_OUT,
    PEAK_FORCE,
    PRE_INTERVAL,
    PRE_RESUME,
    PRE_RESUME_PEAK,
    PRE_RUN_TO_CONTACT,
    STATUS,
    pre_size,
)
from pound_mc.integrators.reference import reference_solution
from pound_mc.motions import record_arrays
from pound_mc.scene import load_scene, scene_from_dict, simulate

ROOT = Path(__file__).resolve().parents[1]
B1_FILE = ROOT / "studies" / "scenes" / "b1.toml"


def rel(a, b):
    return abs(a - b) / abs(b)


# --------------------------------------------------------------------------- scene helpers


def sdof(period_s, mass_kg=1.0e6, damping_ratio=0.05):
    return {
        "model": "sdof",
        "period_s": period_s,
        "mass_kg": mass_kg,
        "damping_ratio": damping_ratio,
    }


def uniform_shear(n, mass_kg, period_s, storey_height_m=3.0, damping_ratio=0.05):
    """Uniform shear building with fundamental period ``period_s``.

    For n equal masses m and storey stiffnesses k (fixed base, free top),
    omega_1^2 = 4 (k/m) sin^2(pi / (2 (2n + 1))) (uniform chain eigenvalues).
    """
    w1 = 2.0 * math.pi / period_s
    k = mass_kg * w1**2 / (4.0 * math.sin(math.pi / (2 * (2 * n + 1))) ** 2)
    return {
        "model": "shear",
        "storey_mass_kg": [mass_kg] * n,
        "storey_stiffness_N_per_m": [k] * n,
        "storey_height_m": [storey_height_m] * n,
        "damping_ratio": damping_ratio,
    }


def make_scene(left, right, contact, record=None):
    return scene_from_dict(
        {
            "record": record or {"source": "builtin:elcentro", "duration_s": 10.0},
            "left": left,
            "right": right,
            "contact": contact,
        }
    )


NO_CONTACT = {"model": "jankowski", "gap_m": 10.0, "beta": 2.75e9, "xi": 0.35}


def sdof_pair_linear():
    return make_scene(sdof(0.5, 1.0e6, 0.05), sdof(1.0, 2.0e6, 0.02), NO_CONTACT)


def shear_pair_linear():
    return make_scene(uniform_shear(3, 1.0e6, 0.3), uniform_shear(5, 1.2e6, 0.6), NO_CONTACT)


def masses(scene):
    return np.r_[scene.left.storey_mass_kg, scene.right.storey_mass_kg]


def modal_state(scene, x, v):
    """Modal coordinates of floor displacements/velocities: q = phi^T M x (mass-normalised)."""
    phi = scene.modal_arrays()["phi"]
    mm = masses(scene)
    return phi.T @ (mm * np.asarray(x)), phi.T @ (mm * np.asarray(v))


def run_linear(scene, ag, dt, *, method="adaptive", dt_s, x0=None, v0=None):
    n = masses(scene).size
    q0, vq0 = modal_state(
        scene, np.zeros(n) if x0 is None else x0, np.zeros(n) if v0 is None else v0
    )
    out, _, hist, _ = run_kernel(
        ag,
        dt,
        **scene.modal_arrays(),
        method=method,
        dt_s=dt_s,
        q0=q0,
        v0=vq0,
        history=True,
    )
    return out, hist[0]


def shear_matrices(building):
    """Mass, stiffness and damping matrices of a shear building from its data alone.

    Not the building's own matrices nor its modes (what the kernels run on): K assembled here
    from the storey stiffnesses (storey i joins floor i - 1, or the ground, to floor i), and
    classical damping with one ratio zeta in every mode in closed form,
    C = 2 zeta M^1/2 (M^-1/2 K M^-1/2)^1/2 M^1/2 (its modes are those of K and M, each damped
    2 zeta omega_i: Chopra, Dynamics of Structures, ch. 11), through a matrix square root
    (scipy.linalg.sqrtm), not an eigendecomposition.
    """
    mass = np.asarray(building.storey_mass_kg, dtype=float)
    ks = np.asarray(building.storey_stiffness_N_per_m, dtype=float)
    k = np.diag(ks + np.r_[ks[1:], 0.0]) - np.diag(ks[1:], 1) - np.diag(ks[1:], -1)
    root = np.sqrt(mass)
    sq = np.real(sqrtm(k / np.outer(root, root)))
    c = 2.0 * building.damping_ratio * sq * np.outer(root, root)
    return np.diag(mass), k, c


def exact_linear_history(scene, ag, dt, x0=None, v0=None):
    """Floor displacements at the samples: matrix exponential of the augmented system.

    State z = [x, v, a_g, a_g'] with M x'' + C x' + K x = -M 1 a_g, a_g'' = 0 inside a sample
    interval: exact for the linearly interpolated record.
    """
    nl = scene.left.storey_mass_kg.size
    blocks = [(scene.left, 0), (scene.right, nl)]
    n = masses(scene).size
    m = np.zeros((n, n))
    k = np.zeros((n, n))
    c = np.zeros((n, n))
    for b, o in blocks:
        s = slice(o, o + b.storey_mass_kg.size)
        m[s, s], k[s, s], c[s, s] = shear_matrices(b)
    minv = np.linalg.inv(m)
    a = np.zeros((2 * n + 2, 2 * n + 2))
    a[:n, n : 2 * n] = np.eye(n)
    a[n : 2 * n, :n] = -minv @ k
    a[n : 2 * n, n : 2 * n] = -minv @ c
    a[n : 2 * n, 2 * n] = -1.0
    a[2 * n, 2 * n + 1] = 1.0
    step = expm(a * dt)
    z = np.zeros(2 * n + 2)
    if x0 is not None:
        z[:n] = x0
    if v0 is not None:
        z[n : 2 * n] = v0
    out = [z[:n].copy()]
    for i in range(ag.size - 1):
        z[2 * n] = ag[i]
        z[2 * n + 1] = (ag[i + 1] - ag[i]) / dt
        z = step @ z
        out.append(z[:n].copy())
    return np.array(out)


def random_record(n=201, dt=0.02, seed=7):
    """A piecewise-linear record with a kink at every sample (seeded), starting at 0."""
    ag = np.random.default_rng(seed).normal(0.0, 2.0, n)
    ag[0] = 0.0
    return dt, ag


# --------------------------------------------------------------------------- a) linear


def free_vibration(x0, v0, w, z, t):
    """Damped free vibration, Chopra eq. 2.2.4: x(t) = e^{-z w t}(x0 cos + (v0+z w x0)/wd sin)."""
    wd = w * math.sqrt(1.0 - z * z)
    b = (v0 + z * w * x0) / wd
    return np.exp(-z * w * t) * (x0 * np.cos(wd * t) + b * np.sin(wd * t))


def free_vibration_peak(x0, v0, w, z, t_end):
    """max |x(t)| on [0, t_end], at the ends or where x'(t) = 0.

    x'(t) = 0 where tan(wd t) = (b wd - z w x0) / (x0 wd + z w b).
    """
    wd = w * math.sqrt(1.0 - z * z)
    b = (v0 + z * w * x0) / wd
    t0 = math.atan2(b * wd - z * w * x0, x0 * wd + z * w * b) / wd
    ts = t0 + np.arange(-1, int(t_end * wd / math.pi) + 2) * math.pi / wd
    ts = np.r_[0.0, t_end, ts[(ts > 0.0) & (ts < t_end)]]
    return float(np.max(np.abs(free_vibration(x0, v0, w, z, ts))))


FREE_X0 = np.array([0.001, -0.002])
FREE_V0 = np.array([0.2, -0.1])


def free_closed_form(scene, t):
    xs, peaks = [], []
    for b, j in ((scene.left, 0), (scene.right, 1)):
        # an SDOF: omega = sqrt(k / m) from its data (k = m (2 pi / T)^2), not its modes
        w = math.sqrt(b.storey_stiffness_N_per_m[0] / b.storey_mass_kg[0])
        z = b.damping_ratio
        xs.append(free_vibration(FREE_X0[j], FREE_V0[j], w, z, t))
        peaks.append(free_vibration_peak(FREE_X0[j], FREE_V0[j], w, z, t[-1]))
    return np.array(xs).T, peaks


@pytest.mark.nojit
@pytest.mark.parametrize("dt_s", [0.01, 0.003])
def test_adaptive_free_vibration_matches_closed_form(dt_s):
    scene = sdof_pair_linear()
    dt = 0.01
    ag = np.zeros(401)
    t = np.arange(ag.size) * dt
    x_exact, _ = free_closed_form(scene, t)
    out, hx = run_linear(scene, ag, dt, dt_s=dt_s, x0=FREE_X0, v0=FREE_V0)
    assert out["status"] == 0
    assert out["impacts"] == 0
    err = np.max(np.abs(hx - x_exact), axis=0) / np.max(np.abs(x_exact), axis=0)
    assert np.all(err < 1e-8), err


def test_reference_free_vibration_matches_closed_form():
    scene = sdof_pair_linear()
    dt = 0.01
    ag = np.zeros(401)
    t = np.arange(ag.size) * dt
    x_exact, peaks = free_closed_form(scene, t)
    ref = reference_solution(scene, (dt, ag), x0=FREE_X0, v0=FREE_V0)
    assert ref["impacts"] == 0
    np.testing.assert_allclose(ref["x_end"], x_exact[-1], rtol=0, atol=1e-9 * np.max(peaks))
    assert rel(ref["peak_disp_left"], peaks[0]) < 1e-9
    assert rel(ref["peak_disp_right"], peaks[1]) < 1e-9


@pytest.mark.nojit
@pytest.mark.parametrize("build", [sdof_pair_linear, shear_pair_linear], ids=["sdof", "shear"])
@pytest.mark.parametrize("dt_s", [0.02, 0.005, 0.007])
def test_adaptive_forced_linear_matches_matrix_exponential(build, dt_s):
    scene = build()
    dt, ag = random_record()
    x_exact = exact_linear_history(scene, ag, dt)
    out, hx = run_linear(scene, ag, dt, dt_s=dt_s)
    assert out["status"] == 0
    scale = np.max(np.abs(x_exact))
    assert np.max(np.abs(hx - x_exact)) < 1e-8 * scale


@pytest.mark.parametrize("build", [sdof_pair_linear, shear_pair_linear], ids=["sdof", "shear"])
def test_reference_forced_linear_matches_matrix_exponential(build):
    scene = build()
    dt, ag = random_record()
    x_exact = exact_linear_history(scene, ag, dt)
    ref = reference_solution(scene, (dt, ag))
    scale = np.max(np.abs(x_exact))
    assert np.max(np.abs(ref["x_end"] - x_exact[-1])) < 1e-9 * scale
    # the continuous maxima are at least the sampled ones and close to them
    nl = scene.left.n_floors
    for peak, cols in (
        (ref["peak_disp_left"], slice(0, nl)),
        (ref["peak_disp_right"], slice(nl, None)),
    ):
        sampled = np.max(np.abs(x_exact[:, cols]))
        assert sampled * (1 - 1e-10) <= peak < sampled * 1.01


@pytest.fixture(scope="module")
def linear_peaks():
    scene = sdof_pair_linear()
    dt, ag = random_record()
    return scene, (dt, ag), reference_solution(scene, (dt, ag))


@pytest.mark.nojit
@pytest.mark.parametrize("dt_s,tol", [(0.02, 1e-5), (0.005, 1e-6)])
def test_adaptive_peak_displacement_within_hermite_bound(linear_peaks, dt_s, tol):
    # Bound of the cubic Hermite screen, O((omega h)^4 / 384) of the amplitude (3.7e-6 at
    # dt_s = 0.02, 6e-10 at 0.005 for T = 0.5 s); the kernel refines candidate peaks on the
    # exact solution, so it must do at least this well at every step size.
    scene, (dt, ag), ref = linear_peaks
    out, _ = run_linear(scene, ag, dt, dt_s=dt_s)
    assert rel(out["peak_disp_left"], ref["peak_disp_left"]) < tol
    assert rel(out["peak_disp_right"], ref["peak_disp_right"]) < tol


@pytest.mark.nojit
def test_adaptive_peak_displacement_exact_continuous_max(linear_peaks):
    # between linear steps the peak is found on the exact solution (not the Hermite cubic)
    scene, (dt, ag), ref = linear_peaks
    out, _ = run_linear(scene, ag, dt, dt_s=0.02)
    assert rel(out["peak_disp_left"], ref["peak_disp_left"]) < 1e-8
    assert rel(out["peak_disp_right"], ref["peak_disp_right"]) < 1e-8


@pytest.mark.nojit
def test_adaptive_free_vibration_peak():
    scene = sdof_pair_linear()
    dt = 0.01
    ag = np.zeros(401)
    _, peaks = free_closed_form(scene, np.arange(ag.size) * dt)
    out, _ = run_linear(scene, ag, dt, dt_s=0.002, x0=FREE_X0, v0=FREE_V0)
    # Hermite maximum at dt_s = 0.002: (omega h)^4 / 384 < 1e-8
    assert rel(out["peak_disp_left"], peaks[0]) < 1e-8
    assert rel(out["peak_disp_right"], peaks[1]) < 1e-8


# --------------------------------------------------------------------------- b) newmark order


def observed_orders(errors):
    return [math.log2(errors[i] / errors[i + 1]) for i in range(len(errors) - 1)]


@pytest.mark.nojit
def test_newmark_second_order_linear_forced():
    scene = sdof_pair_linear()
    dt, ag = random_record()
    x_exact = exact_linear_history(scene, ag, dt)
    errors = []
    for m in (2, 4, 8):
        _, hx = run_linear(scene, ag, dt, method="newmark", dt_s=dt / m)
        errors.append(np.max(np.abs(hx - x_exact)) / np.max(np.abs(x_exact)))
    orders = observed_orders(errors)
    assert all(1.8 <= p <= 2.2 for p in orders), (errors, orders)


@pytest.mark.nojit
def test_newmark_second_order_single_soft_impact():
    # one soft Hertz impact from initial velocities (smooth enough for order 2; the Jankowski
    # damping term ~ delta^0.25 delta_dot is not: measured orders 1.3-1.6 there)
    scene = make_scene(
        sdof(0.5, 1.0e6, 0.05),
        sdof(1.0, 2.0e6, 0.02),
        {"model": "hertz", "gap_m": 0.002, "beta": 1.0e8},
    )
    dt, ag = 0.01, np.zeros(51)
    x0, v0 = np.zeros(2), np.array([0.3, -0.2])
    ref = reference_solution(scene, (dt, ag), x0=x0, v0=v0)
    assert ref["impacts"] == 1
    errors = []
    for dt_s in (1e-3, 5e-4, 2.5e-4):
        out, hx = run_linear(scene, ag, dt, method="newmark", dt_s=dt_s, x0=x0, v0=v0)
        assert out["impacts"] == 1
        errors.append(np.max(np.abs(hx[-1] - ref["x_end"])) / np.max(np.abs(ref["x_end"])))
    orders = observed_orders(errors)
    assert all(1.8 <= p <= 2.2 for p in orders), (errors, orders)


# --------------------------------------------------------------------------- c) B1


@pytest.fixture(scope="module")
def b1():
    scene = load_scene(B1_FILE)
    record = record_arrays(scene.load_record())
    return scene, record, reference_solution(scene, record)


@pytest.mark.slow
def test_b1_reference_solution(b1):
    # DESIGN.md section 5: independent tight-tolerance SciPy solution, 22 impacts, 7.0259e6 N
    _, _, ref = b1
    assert ref["impacts"] == 22
    assert abs(ref["peak_force"] - 7.0259e6) <= 50.0  # half a unit of the 5th digit


@pytest.mark.slow
def test_b1_adaptive_default_settings(b1):
    scene, record, ref = b1
    res = simulate(scene, record=record)
    o = res.outputs
    assert res.status == "ok"
    assert o["impacts"] == ref["impacts"] == 22
    assert rel(o["peak_force"], ref["peak_force"]) < 1e-4
    assert rel(o["peak_force"], 7.0259e6) < 1e-4  # DESIGN.md section 5
    assert rel(o["max_penetration"], ref["max_penetration"]) < 1e-4
    assert rel(o["peak_disp_left"], ref["peak_disp_left"]) < 1e-4
    assert rel(o["peak_disp_right"], ref["peak_disp_right"]) < 1e-4


@pytest.mark.slow
def test_record_ending_inside_an_episode_counts_it(b1):
    # B1 cut 10-20 ms after its first onset (14.405 s in the reference): the record ends in
    # the approach phase, 0.7-1.0 mm deep.  That episode is an impact (deeper than
    # IMPACT_MIN_PENETRATION_M) in the kernel and in the SciPy reference alike, and its
    # penetration so far is the deepest (the reference used to count impacts at the turn only:
    # 0 impacts and max_penetration 0 beside a peak force of 208 kN)
    scene, (dt, acc), ref = b1
    onset = ref["impact_times"][0]
    for extra in (0.005, 0.02):
        record = (dt, acc[: int(np.ceil((onset + extra) / dt)) + 1])
        cut = reference_solution(scene, record)
        o = simulate(scene, record=record).outputs
        assert cut["impacts"] == o["impacts"] == 1
        assert cut["max_penetration"] > 5e-4
        assert rel(o["max_penetration"], cut["max_penetration"]) < 1e-4
        assert rel(o["peak_force"], cut["peak_force"]) < 1e-4


# --------------------------------------------------------------------------- d) other scenes

ELCENTRO = {"source": "builtin:elcentro", "duration_s": 12.0, "pga_g": 0.4}
JANKOWSKI = {"model": "jankowski", "gap_m": 0.01, "beta": 2.75e9, "xi": 0.35}
SCENES = {
    "elcentro-at2": (sdof(0.5), sdof(1.0), JANKOWSKI, ELCENTRO),
    "periods-masses": (sdof(0.3, 5.0e5), sdof(0.8, 2.0e6), JANKOWSKI, ELCENTRO),
    "zero-gap": (sdof(0.5), sdof(1.0), {**JANKOWSKI, "gap_m": 0.0}, ELCENTRO),
    "beta1e10-xi0.2": (sdof(0.5), sdof(1.0), {**JANKOWSKI, "beta": 1.0e10, "xi": 0.2}, ELCENTRO),
    "hertz": (sdof(0.5), sdof(1.0), {"model": "hertz", "gap_m": 0.01, "beta": 2.75e9}, ELCENTRO),
}


@pytest.mark.slow
@pytest.mark.parametrize("name", list(SCENES))
def test_adaptive_matches_reference_on_scenes(name):
    scene = make_scene(*SCENES[name])
    record = record_arrays(scene.load_record())
    ref = reference_solution(scene, record)
    o = simulate(scene, record=record).outputs
    assert o["status"] == 0
    assert ref["impacts"] >= 10  # the scenes pound repeatedly
    assert o["impacts"] == ref["impacts"]
    for key in ("peak_force", "max_penetration", "peak_disp_left", "peak_disp_right"):
        assert rel(o[key], ref[key]) < 1e-4, key


# --------------------------------------------------------------------------- e) shear buildings


def test_shear_buildings_pound_at_common_floors():
    scene = make_scene(
        uniform_shear(3, 1.0e6, 0.3),
        uniform_shear(5, 1.0e6, 0.6),
        JANKOWSKI,
        {"source": "builtin:elcentro", "duration_s": 10.0, "pga_g": 0.4},
    )
    assert scene.left.periods_s[0] == pytest.approx(0.3, rel=1e-12)
    assert scene.right.periods_s[0] == pytest.approx(0.6, rel=1e-12)
    assert len(scene.contacts) == 3
    for k, ct in enumerate(scene.contacts):
        assert (ct.left_floor, ct.right_floor) == (k, k)
        assert ct.elevation_m == pytest.approx(3.0 * (k + 1))
        assert ct.m_eff == pytest.approx(0.5e6)
    record = record_arrays(scene.load_record())
    ref = reference_solution(scene, record)
    res = simulate(scene, record=record)
    o = res.outputs
    assert o["status"] == 0
    assert ref["impacts"] >= 10
    assert o["impacts"] == ref["impacts"]
    np.testing.assert_array_equal(res.contacts["impacts"], ref["contact_impacts"])
    np.testing.assert_allclose(res.contacts["peak_force"], ref["contact_peak_force"], rtol=1e-3)
    for key in ("peak_force", "max_penetration", "peak_disp_left", "peak_disp_right"):
        assert rel(o[key], ref[key]) < 1e-3, key


def test_shear_batch_shares_the_linear_response_and_peak_only_run():
    # a scene batch runs the linear response up to the first contact once per gap and step
    # (pre mode 1) and resumes every simulation from it (mode 2): every output bitwise that of
    # a run from rest.  The accuracy check's finer run resumes in mode 3: no energies, no floor
    # peaks, which never move the state, so its peak force is bitwise a full run's; every
    # other output NaN.  3 + 5 storeys, gaps 0 to 0.02 m, soft to stiff contacts
    scene = make_scene(
        uniform_shear(3, 1.0e6, 0.3), uniform_shear(5, 1.0e6, 0.6), JANKOWSKI,
        {"source": "builtin:elcentro", "duration_s": 10.0, "pga_g": 0.4},
    )  # fmt: skip
    dt_rec, acc = record_arrays(scene.load_record())
    a = scene.modal_arrays()
    nsim, nc = 6, a["gap"].size
    gap = np.repeat([0.0, 0.01, 0.02], 2)[:, None] * np.ones(nc)
    beta = np.array([1.0e9, 2.75e9, 1.0e10, 2.75e9, 2.75e9, 1.0e9])
    xi = np.array([0.35, 0.2, 0.35, 0.6, 0.35, 0.2])
    settings = kernel_settings("jankowski", "adaptive", substeps=16)
    pair = [acc, dt_rec, *(a[k] for k in ("omega", "zeta", "gamma", "phi", "side", "psi", "meff"))]
    every = np.arange(nsim, dtype=np.int64)
    size = pre_size(a["omega"].size, a["phi"].shape[0])
    rest = np.zeros((nsim, size))  # interval 0, at rest, no energy: a run from rest
    first, group = np.array([0, 2, 4]), np.repeat([0, 1, 2], 2)
    shared = np.zeros((3, size))

    def run(mode, pre, index, grp):
        o, c = np.empty((nsim, N_OUT)), np.empty((nsim, nc, N_COUT))
        batch._scene_adaptive(*pair, gap, beta, xi, np.full(nsim, 0.01), settings, o, c, index,
                              grp, pre, mode, 0, index.size)  # fmt: skip
        return o, c

    full, cfull = run(PRE_RESUME, rest, every, every)
    run(PRE_RUN_TO_CONTACT, shared, first, group)
    # at zero gap the buildings touch at once; at 0.01 and 0.02 m first near 1.9 s
    assert shared[0, PRE_INTERVAL] == 0 and (shared[1:, PRE_INTERVAL] > 100).all()
    resumed, cresumed = run(PRE_RESUME, shared, every, group)
    np.testing.assert_array_equal(resumed, full)
    np.testing.assert_array_equal(cresumed, cfull)
    peak, _ = run(PRE_RESUME_PEAK, shared, every, group)
    assert (full[:, STATUS] == 0).all() and (full[:, PEAK_FORCE] > 0.0).all()
    np.testing.assert_array_equal(peak[:, PEAK_FORCE], full[:, PEAK_FORCE])
    np.testing.assert_array_equal(peak[:, STATUS], full[:, STATUS])
    assert np.isnan(np.delete(peak, [PEAK_FORCE, STATUS], axis=1)).all()
