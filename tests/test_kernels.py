"""The SDOF-pair Newmark kernel against the general modal kernel it specialises."""

import numpy as np
import pytest

from pound_mc.integrators import run_kernel
from pound_mc.scene import scene_from_dict

# both Newmark kernels on one short record: also run with NUMBA_DISABLE_JIT=1
pytestmark = pytest.mark.nojit


def scene(**contact):
    return scene_from_dict(
        {
            "record": {"source": "builtin:knet-akt013", "duration_s": 8.0, "pga_g": 0.5},
            "left": {"model": "sdof", "period_s": 0.5, "damping_ratio": 0.05, "mass_kg": 1e6},
            "right": {"model": "sdof", "period_s": 1.0, "damping_ratio": 0.02, "mass_kg": 2e6},
            "contact": {
                k: v
                for k, v in {"gap_m": 0.002, "beta": 2.75e9, "xi": 0.35, **contact}.items()
                if v is not None
            },  # fmt: skip
        }
    )


@pytest.fixture(scope="module")
def record():
    from pound_mc.motions import record_arrays

    return record_arrays(scene().load_record())


@pytest.mark.parametrize("method", ["newmark", "newmark-explicit"])
@pytest.mark.parametrize("contact", [{}, {"model": "hertz", "xi": None}, {"gap_m": 0.0, "xi": 0.1}])
def test_pair_kernel_equals_general_kernel(record, method, contact):
    sc = scene(**contact)
    dt, acc = record
    arrays = sc.modal_arrays()
    kw = dict(model=sc.contact_model, method=method, dt_s=5e-4)
    fast, cf, *_ = run_kernel(acc, dt, **arrays, **kw)  # SDOF pair: the scalar kernel
    general, cg, *_ = run_kernel(acc, dt, **arrays, **kw, history=True)  # history: general
    assert fast["impacts"] == general["impacts"] > 0
    assert fast["status"] == general["status"] == 0
    for name in ("peak_force", "max_penetration", "peak_disp_left", "peak_disp_right",
                 "impulse", "dissipated_energy", "input_energy"):  # fmt: skip
        # same scheme and operation order; only Newton's stopping point may differ (1e-14)
        assert fast[name] == pytest.approx(general[name], rel=1e-9), name
    assert fast["energy_residual"] == pytest.approx(general["energy_residual"], abs=1e-9)
    for name in cf:
        np.testing.assert_allclose(cf[name], cg[name], rtol=1e-9, err_msg=name)


@pytest.mark.parametrize(
    "method", ["adaptive", "newmark", "newmark-explicit", "central-difference"]
)
def test_round_off_contact_is_no_impact(record, method):
    # identical buildings but for the last bit of a period (np.linspace's 0.9999999999999999
    # against 1.0) at gap 0 touch by 1e-16 m: no impact (outputs.IMPACT_MIN_PENETRATION_M,
    # 1e-9 m), as with exactly identical buildings
    dt, acc = record
    period = np.nextafter(1.0, 0.0)
    sc = scene_from_dict(
        {
            "record": {"source": "builtin:knet-akt013", "duration_s": 8.0, "pga_g": 0.5},
            "left": {"model": "sdof", "period_s": period, "damping_ratio": 0.05, "mass_kg": 1e6},
            "right": {"model": "sdof", "period_s": 1.0, "damping_ratio": 0.05, "mass_kg": 1e6},
            "contact": {"gap_m": 0.0, "beta": 2.75e9, "xi": 0.35},
        }
    )
    out, *_ = run_kernel(acc, dt, **sc.modal_arrays(), model="jankowski", method=method,
                           dt_s=1e-3 if method != "central-difference" else 1e-4)  # fmt: skip
    assert out["status"] == 0
    assert out["impacts"] == 0
    assert out["max_penetration"] == 0.0


def test_borrowed_view_reads_and_writes_its_owner():
    """toolkit.borrow: a view without an owner over the same memory (the kernels' loops use it)."""
    from pound_mc._jit import jit
    from pound_mc.integrators.toolkit import borrow

    @jit
    def double_through_view(a):
        b = borrow(a)
        for k in range(b.shape[0]):
            for j in range(b.shape[1]):
                b[k, j] *= 2.0
        return b[1, 2]

    a = np.arange(12.0).reshape(3, 4)
    assert double_through_view(a) == 12.0  # a[1, 2] = 6, doubled in place
    np.testing.assert_array_equal(a, 2.0 * np.arange(12.0).reshape(3, 4))
