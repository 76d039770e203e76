"""The scalar-state SDOF-pair ``adaptive`` kernel against the general modal kernel.

``run_kernel`` routes an SDOF pair (with or without history) to
``adaptive_pair.adaptive_pair``; the reference here is the general
``adaptive.adaptive`` called directly on the same arrays (itself held to independent solutions
by ``tests/test_integrators.py``).
"""

from pathlib import Path

import numpy as np
import pytest

from pound_mc.integrators import batch, kernel_settings, run_kernel, simulate_sdof_pairs
from pound_mc.integrators.accuracy import flag_inaccurate
from pound_mc.integrators.adaptive import adaptive
from pound_mc.integrators.outputs import (
    CONTACT_OUTPUTS,
    IMPACTS,
    N_COUT,
    N_OUT,
    ONSET_SIZE,
    OUTPUTS,
    PEAK_FORCE,
    PRE_INTERVAL,
    PRE_RESUME,
    PRE_RESUME_ONSET,
    PRE_RESUME_PEAK,
    PRE_RUN_TO_CONTACT,
    STATUS,
    pre_size,
)
from pound_mc.integrators.reference import reference_solution
from pound_mc.motions import record_arrays
from pound_mc.scene import load_scene, scene_from_dict, simulate

ROOT = Path(__file__).resolve().parents[1]
COMPARED = ("peak_force", "impacts", "max_penetration", "peak_disp_left", "peak_disp_right",
            "impulse", "dissipated_energy", "input_energy", "peak_force_time")  # fmt: skip
#: Same algorithm, scalar state; the pair kernel locates onset to 1e-12 of the step (general:
#: 1e-15) and refines a candidate peak by one Newton step (general: Newton to 1e-15), which
#: leaves laws other than Jankowski's equal to round-off (measured <= 2e-12, bound 1e-9).
RTOL = 1e-9
#: Jankowski: the pair kernel integrates the approach phase in ``u = v + psi D(delta)`` with
#: its own ramp and tail (adaptive_pair.py), a different discretisation of the same equations.
#: On B1 the pair kernel's peak force is +7e-6 from the SciPy reference and the general kernel's
#: +2.2e-5, both within the 3e-5 accuracy limit: the kernels are held to each other at that
#: limit (measured <= 1.6e-5 on these scenes).  The contact's dissipated energy is, in the
#: general kernel, a quadrature of the singular ``c0 delta^0.25 delta_dot^2``; the pair kernel
#: integrates it by parts and the elastic work exactly (1.9e-5 from the SciPy reference on B1,
#: the general kernel -4.4e-5; measured <= 6.4e-5 apart, bound 5e-4; energy residual <= 1.7e-5,
#: bound 2e-4).
RTOL_JANKOWSKI = 3e-5
RTOL_DISSIPATED = 5e-4
ATOL_RESIDUAL = 2e-4

KNET = {"source": "builtin:knet-akt013", "duration_s": 30.0, "pga_g": 0.3}
ELCENTRO = {"source": "builtin:elcentro", "duration_s": 12.0, "pga_g": 0.4}
JANKOWSKI = {"model": "jankowski", "gap_m": 0.01, "beta": 2.75e9, "xi": 0.35}
HERTZDAMP = {"model": "hertzdamp", "gap_m": 0.01, "beta": 2.75e9, "e": 0.6}
HERTZDAMP["relation"] = "muthukumar2006"


def sdof(period_s, mass_kg=1.0e6, damping_ratio=0.05):
    return {"model": "sdof", "period_s": period_s, "mass_kg": mass_kg,
            "damping_ratio": damping_ratio}  # fmt: skip


SCENES = {
    "zero-gap": (sdof(0.5), sdof(1.0), {**JANKOWSKI, "gap_m": 0.0}, KNET),
    "hertz": (sdof(0.5), sdof(1.0), {"model": "hertz", "gap_m": 0.01, "beta": 2.75e9}, KNET),
    "hertzdamp-muthukumar2006": (sdof(0.5), sdof(1.0), HERTZDAMP, KNET),
    "beta1e10-xi0.2": (sdof(0.5), sdof(1.0), {**JANKOWSKI, "beta": 1.0e10, "xi": 0.2}, KNET),
    "elcentro": (sdof(0.3, 5.0e5), sdof(0.8, 2.0e6, 0.02), JANKOWSKI, ELCENTRO),
    "linear": (sdof(0.5), sdof(1.0), {"model": "linear", "gap_m": 0.01, "k_N_per_m": 1e9}, KNET),
}


def make(name):
    if name == "b1":
        return load_scene(ROOT / "studies" / "scenes" / "b1.toml")
    left, right, contact, record = SCENES[name]
    return scene_from_dict({"record": record, "left": left, "right": right, "contact": contact,
                            "integrator": {"dt_s": 0.01}})  # fmt: skip


def kwargs(scene):
    return dict(model=scene.contact_model, relation=scene.relation, dt_s=scene.dt_s,
                substeps=scene.substeps)  # fmt: skip


def general(acc, dt, arrays, scene, history=False):
    """The general modal kernel on the arrays ``run_kernel`` would pass: outputs by name."""
    f8 = np.float64
    a = {k: np.ascontiguousarray(x, dtype=np.int64 if k == "side" else f8)
         for k, x in arrays.items()}  # fmt: skip
    n, nc, nf = a["omega"].size, a["gap"].size, a["phi"].shape[0]
    out = np.empty(N_OUT)
    cout = np.empty((nc, N_COUT))
    nh = acc.size if history else 0
    hx, hd, hf = np.zeros((nh, nf)), np.zeros((nh, nc)), np.zeros((nh, nc))
    settings = kernel_settings(method="adaptive", **kwargs(scene))
    adaptive(np.ascontiguousarray(acc, dtype=f8), f8(dt), a["omega"], a["zeta"], a["gamma"],
             a["phi"], a["side"], a["psi"], a["gap"], a["meff"], a["beta"], a["xi"], settings,
             np.zeros(n), np.zeros(n), out, cout, hx, hd, hf, np.zeros(0))  # fmt: skip
    outputs = {name: float(out[k]) for k, name in enumerate(OUTPUTS)}
    contacts = {name: cout[:, k] for k, name in enumerate(CONTACT_OUTPUTS)}
    return outputs, contacts, (hx, hd, hf)


def close(a, b, rtol):
    return abs(a - b) <= rtol * abs(b)


@pytest.mark.parametrize("name", ["b1", *SCENES])
def test_pair_kernel_equals_general_kernel(name):
    scene = make(name)
    dt, acc = record_arrays(scene.load_record())
    arrays = scene.modal_arrays()
    fast, cf, *_ = run_kernel(acc, dt, **arrays, **kwargs(scene))
    ref, cg, _ = general(acc, dt, arrays, scene)
    assert fast["status"] == ref["status"] == 0
    assert fast["impacts"] == ref["impacts"] >= 10  # the scenes pound
    jankowski = scene.contact_model == "jankowski"
    rtol = RTOL_JANKOWSKI if jankowski else RTOL
    for key in COMPARED:
        tol = RTOL_DISSIPATED if jankowski and key == "dissipated_energy" else rtol
        assert close(fast[key], ref[key], tol), (key, fast[key], ref[key])
    res_tol = ATOL_RESIDUAL if jankowski else RTOL
    assert fast["energy_residual"] == pytest.approx(ref["energy_residual"], abs=res_tol)
    for key in CONTACT_OUTPUTS:
        np.testing.assert_allclose(cf[key], cg[key], rtol=rtol)


@pytest.mark.parametrize("name", ["b1", "beta1e10-xi0.2", "elcentro", "zero-gap"])
def test_dissipated_energy_matches_the_reference(name):
    # the contact's dissipated energy (its work less the energy it holds at the end) against the
    # SciPy reference, which integrates the contact work as a state of the ODE (DOP853, rtol
    # 1e-11; 1e-10 and 1e-12 give B1's within 1.3e-9).  Measured 1.9e-5, 2.3e-6, 1.4e-5 and
    # 1.9e-5; as a quadrature of the damping power (singular at onset, before) -2.7e-4, -1.9e-4,
    # -1.4e-4 and -2.3e-4
    scene = make(name)
    ref = reference_solution(scene, contact_work=True)
    out = simulate(scene).outputs
    assert close(out["dissipated_energy"], ref["dissipated_energy"], 5e-5)
    if name == "b1":  # no singular integrand left: the error falls fast with the sub-steps
        # (measured 8.7e-7 at 32, 1.5e-8 at 64)
        finer = simulate(scene, substeps=64).outputs
        assert close(finer["dissipated_energy"], ref["dissipated_energy"], 1e-7)


def test_history_runs_the_pair_kernel():
    # history=True reruns the kernel of the study (the pair kernel): same outputs bit for bit,
    # and histories at the record's samples as the general kernel writes them
    scene = make("b1")
    dt, acc = record_arrays(scene.load_record())
    arrays = scene.modal_arrays()
    plain, *_ = run_kernel(acc, dt, **arrays, **kwargs(scene))
    fast, _, (hx, hd, hf), _ = run_kernel(acc, dt, **arrays, **kwargs(scene), history=True)
    for key in OUTPUTS:  # NaN where an output does not apply (the inelastic ones)
        np.testing.assert_array_equal(fast[key], plain[key], err_msg=key)
    _, _, (gx, gd, gf) = general(acc, dt, arrays, scene, history=True)
    assert hx.shape == gx.shape == (acc.size, 2)
    assert np.count_nonzero(hf) == np.count_nonzero(gf) > 0  # contact at some samples
    tol = RTOL_JANKOWSKI
    np.testing.assert_allclose(hx, gx, rtol=0, atol=tol * np.abs(gx).max())
    np.testing.assert_allclose(hd, gd, rtol=0, atol=tol * np.abs(gd).max())
    # a force sampled inside a contact moves by its rate (~ peak / contact duration) times the
    # kernels' difference in contact timing: measured 4.0e-5 of the peak, bound 1e-4
    np.testing.assert_allclose(hf, gf, rtol=0, atol=1e-4 * np.abs(gf).max())


def test_shared_linear_response_in_batches():
    # simulations differing only in contact parameters share the linear response up to the
    # first contact (pre protocol, modes 1 and 2): each must equal its own general run
    scene = make("b1")
    dt, acc = record_arrays(scene.load_record())
    beta = np.array([1.0e9, 2.75e9, 1.0e10, 2.75e9])
    xi = np.array([0.35, 0.2, 0.35, 0.5])
    res = simulate_sdof_pairs(
        acc, dt, left_period_s=0.5, left_damping_ratio=0.05, left_mass_kg=1.0e6,
        right_period_s=1.0, right_damping_ratio=0.05, right_mass_kg=1.0e6, gap_m=0.01,
        beta=beta, xi=xi, dt_s=0.01,
    )  # fmt: skip
    arrays = scene.modal_arrays()
    for k in range(beta.size):
        arrays["beta"] = np.full(1, beta[k])
        arrays["xi"] = np.full(1, xi[k])
        ref, _, _ = general(acc, dt, arrays, scene)
        assert res["status"][k] == ref["status"] == 0
        for key in COMPARED:
            tol = RTOL_DISSIPATED if key == "dissipated_energy" else RTOL_JANKOWSKI
            assert close(res[key][k], ref[key], tol), (k, key)


#: Argument names of ``simulate_sdof_pairs`` in the order of ``batch._sdof_adaptive``'s arrays.
PAIR_ARRAYS = ("left_period_s", "left_damping_ratio", "left_mass_kg", "right_period_s",
               "right_damping_ratio", "right_mass_kg", "gap_m", "beta", "xi", "dt_s")  # fmt: skip


def b1_like_pairs(left_periods, gaps):
    """B1-like SDOF pairs (``PAIR_ARRAYS``): four contacts per left period, soft to stiff,
    lightly to heavily damped, with ``gaps`` [m] in turn."""
    k = len(left_periods)
    n = 4 * k
    return [
        np.repeat(left_periods, 4).astype(float), np.full(n, 0.05), np.full(n, 1.0e6),
        np.full(n, 1.0), np.full(n, 0.05), np.full(n, 1.0e6), np.tile(gaps, k).astype(float),
        np.tile([1.0e9, 2.75e9, 1.0e10, 2.75e9], k), np.tile([0.35, 0.2, 0.35, 0.6], k),
        np.full(n, 0.01),
    ]  # fmt: skip


def test_peak_only_pass_gives_the_full_runs_peak_force():
    # the accuracy check's finer run resumes in pre mode 3: no energies, no floor peaks, which
    # never move the state, so its peak force is bitwise a full run's; every other output NaN.
    # Left periods 0.3 (two contact sub-steps per record sample), 0.5, 0.7 s; gaps 0 to
    # 0.02 m; soft to stiff, lightly to heavily damped contacts
    dt, acc = record_arrays(make("b1").load_record())
    arrays = b1_like_pairs([0.3, 0.5, 0.7], [0.0, 0.01, 0.01, 0.02])
    n = arrays[0].size
    settings = kernel_settings("jankowski", "adaptive", substeps=32)
    every = np.arange(n, dtype=np.int64)
    shared = np.zeros((n, pre_size(2, 2)))
    runs = {}
    for mode in (PRE_RUN_TO_CONTACT, PRE_RESUME, PRE_RESUME_PEAK):
        runs[mode] = np.empty((n, N_OUT))
        batch._sdof_adaptive(acc, dt, *arrays, settings, runs[mode], every, every, shared, mode,
                             0, n)  # fmt: skip
    full, peak = runs[PRE_RESUME], runs[PRE_RESUME_PEAK]
    assert (full[:, STATUS] == 0).all() and (full[:, PEAK_FORCE] > 0.0).all()
    np.testing.assert_array_equal(peak[:, PEAK_FORCE], full[:, PEAK_FORCE])
    np.testing.assert_array_equal(peak[:, STATUS], full[:, STATUS])
    assert np.isnan(np.delete(peak, [PEAK_FORCE, STATUS], axis=1)).all()


@pytest.fixture(scope="module")
def runs_8_16():
    """B1-like pairs (left 0.3, 0.4 and 0.7 s, gap 0.01 m) run at 8 and 16 sub-steps, each
    with the ``same`` slot and the check's start past its outputs; the shared linear response.
    """
    dt, acc = record_arrays(make("b1").load_record())
    arrays = b1_like_pairs([0.3, 0.4, 0.7], [0.01] * 4)
    n = arrays[0].size
    every = np.arange(n, dtype=np.int64)
    runs = {}
    shared = np.zeros((n, pre_size(2, 2)))
    for substeps in (8, 16):
        settings = kernel_settings("jankowski", "adaptive", substeps=substeps)
        runs[substeps] = np.zeros((n, N_OUT + 1 + ONSET_SIZE))
        for mode in (PRE_RUN_TO_CONTACT, PRE_RESUME):
            batch._sdof_adaptive(acc, dt, *arrays, settings, runs[substeps], every, every,
                                 shared, mode, 0, n)  # fmt: skip
    return dt, acc, arrays, runs, shared


def test_check_is_skipped_only_where_its_run_would_be_the_same(runs_8_16):
    # the run says whether the accuracy check's run (twice the sub-steps) would take its very
    # sub-steps (no bound set by ``substeps`` binding at the finer setting); the batch skips the
    # check there.  Held to running the finer run anyway: its peak force is bitwise the run's
    # wherever the run says so.  B1-like pairs at 8 sub-steps: left 0.3 and 0.4 s (contact
    # sub-steps at most 1/50 of the period, 5 ms, under duration / 16 for the softer contacts),
    # 0.7 s (the record's 10 ms, over duration / 16 = 8.75 ms on B1)
    dt, acc, arrays, runs, _ = runs_8_16
    run, finer = runs[8], runs[16]
    same = run[:, N_OUT] == 1.0
    assert same.any() and not same.all()  # both kinds among these pairs
    np.testing.assert_array_equal(finer[same, PEAK_FORCE], run[same, PEAK_FORCE])
    # the batch flags what running every check flags
    out = simulate_sdof_pairs(acc, dt, **dict(zip(PAIR_ARRAYS, arrays, strict=True)), substeps=8)
    want = flag_inaccurate(run[:, STATUS], run[:, IMPACTS], np.inf, 0.0, run[:, PEAK_FORCE],
                           finer[:, PEAK_FORCE])  # fmt: skip
    np.testing.assert_array_equal(out["status"], want)
    np.testing.assert_array_equal(out["peak_force"], run[:, PEAK_FORCE])


def test_check_run_starts_at_the_last_onset_it_shares_with_the_run(runs_8_16):
    # the run stores its state at each contact onset up to which the check's run (twice the
    # sub-steps) takes its very sub-steps; the check's run starts from the last one (pre mode
    # 4) and must give the peak force of a finer run from the shared linear response, to the
    # bit.  The pairs of the test above (some diverge from the check's run at the first
    # impact, some later, some never)
    dt, acc, arrays, runs, shared = runs_8_16
    n = arrays[0].size
    every = np.arange(n, dtype=np.int64)
    run, finer = runs[8], runs[16]
    starts = run[:, N_OUT + 1 :]
    assert (run[:, PEAK_FORCE] > 0.0).all()
    # the first onset is in the shared interval; some runs start the check's run later
    assert (starts[:, PRE_INTERVAL] >= shared[:, PRE_INTERVAL]).all()
    assert (starts[:, PRE_INTERVAL] > shared[:, PRE_INTERVAL]).any()
    resumed = np.empty((n, N_OUT))
    batch._sdof_adaptive(acc, dt, *arrays, kernel_settings("jankowski", "adaptive", substeps=16),
                         resumed, every, every, starts, PRE_RESUME_ONSET, 0, n)  # fmt: skip
    np.testing.assert_array_equal(resumed[:, PEAK_FORCE], finer[:, PEAK_FORCE])
    np.testing.assert_array_equal(resumed[:, STATUS], finer[:, STATUS])


def test_no_contact_pair():
    # a gap never closed: the pair kernel's linear path alone, equal to the general kernel
    scene = scene_from_dict({"record": ELCENTRO, "left": sdof(0.5), "right": sdof(1.0),
                             "contact": {**JANKOWSKI, "gap_m": 10.0}})  # fmt: skip
    dt, acc = record_arrays(scene.load_record())
    arrays = scene.modal_arrays()
    fast, *_ = run_kernel(acc, dt, **arrays, **kwargs(scene))
    ref, _, _ = general(acc, dt, arrays, scene)
    assert fast["impacts"] == ref["impacts"] == 0
    for key in ("peak_disp_left", "peak_disp_right", "input_energy", "steps"):
        assert close(fast[key], ref[key], 1e-12), key


@pytest.mark.parametrize("lean", [False, True])
def test_jankowski_bound_screen_never_changes_a_sub_step(lean):
    # the screen of bounds.contact_bound skips Jankowski's local bounds below a
    # penetration where they can neither bind nor be tight at the check's finer setting: its
    # sub-step and tightness must be those of the full evaluation, bit for bit, over a wide
    # random set of states and contacts and right at the screen's thresholds; a lean run's
    # screen (share 1: the bounds themselves, whose tightness that run does not use) must
    # keep the sub-step
    from pound_mc.integrators import bounds as ap

    law = ap._JANKOWSKI
    bound = ap.contact_bound.py_func
    rng = np.random.default_rng(11)
    screened = 0
    n = 4000
    for k in range(n):
        b = 10.0 ** rng.uniform(6.0, 13.0)
        me = 10.0 ** rng.uniform(1.0, 7.0)
        cd = 2.0 * rng.choice([0.0, 1e-6, 0.05, 0.35, 1.5, 5.8]) * np.sqrt(b * me)
        substeps = int(rng.choice([4, 8, 16, 32]))
        loc_k = ap.LOCAL_PERIOD_SHARE * np.sqrt(me) / substeps
        loc_c = ap.LOCAL_DAMPING_SHARE * me / substeps
        share = 1.0 if lean else ap.FINE
        kp4 = ap.period_screen(law, b, loc_k, share)
        kc4 = ap.damping_screen(law, b, cd, loc_c, share)
        hs = 10.0 ** rng.uniform(-6.0, -1.5)
        phase = int(rng.integers(0, 3))
        dd = rng.uniform(-1.0, 1.0) if k % 3 else 0.0
        d = 10.0 ** rng.uniform(-14.0, -0.5)
        if k % 4 == 0:  # at a threshold, within rounding of it
            edge = min(kp4, kc4 if phase == 1 else np.inf) / hs**4
            d = edge * (1.0 + rng.choice([-1.0, 1.0]) * 10.0 ** rng.uniform(-16.0, -5.0))
            d -= max(dd, 0.0) * hs
        full = bound(hs, d, dd, law, b, cd, 0.0, phase, loc_k, loc_c, -1.0, -1.0)
        fast = bound(hs, d, dd, law, b, cd, 0.0, phase, loc_k, loc_c, kp4, kc4)
        assert (fast[0] if lean else fast) == (full[0] if lean else full), (
            b, me, cd, substeps, hs, phase, d, dd)  # fmt: skip
        h4 = hs**4
        screened += (d + max(dd, 0.0) * hs) * h4 <= min(kp4, kc4 if phase == 1 else np.inf)
    assert screened > n // 4  # the screen is exercised, not only the full evaluation
