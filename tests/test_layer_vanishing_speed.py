"""The strip march of the thin-layer law with spin at a vanishing rolling speed: its gain
1/(|Vx| k) is bounded (thin_layer._Grid.gain, stepper.c march_gain; docs/model.md) so that
for |Vx| down to the smallest subnormal the increments stay finite and every node slides
along the slip of Eq. (3) at its midpoint, the |Vx| -> 0+ limit of Eqs. (35), (4)-(5)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from contact_fmu import examples as ex
from contact_fmu import native
from contact_fmu.laws.thin_layer import SPIN_GRID

LAW = ex.contact()
MU_P = LAW.mu * LAW.P
SPEEDS = (1e-300, -1e-300, 5e-324, -5e-324, 1e-200, -1e-200)
# rigid slip (vx, vy) and spin phi: pure spin, spin with longitudinal and lateral slip
# (creepage-sized slips: phi a1 of the size of |v|)
SLIPS = ((0.0, 0.0, 1.0), (1e-3, 2e-3, 1.0 / LAW.a1 * 1e-3), (2e-3, -1e-3, -3e-3 / LAW.a1))


@pytest.fixture(params=["compiled", "numpy"])
def path(request, monkeypatch):
    if request.param == "compiled":
        if native.library() is None:
            pytest.skip("no compiled library")
    else:
        monkeypatch.setattr(native, "_LOADED", {"stepper": None})
    return request.param


def _a(v: float) -> np.ndarray:
    return np.array([v])


@pytest.mark.parametrize("Vx", SPEEDS)
def test_forces_at_a_vanishing_speed_are_finite_and_within_coulomb(path, Vx):
    """Where 1/(|Vx| k) dist |slip| overflowed (|Vx| below about 1e-296 m/s) into
    inf/inf = NaN: finite (Tx, Ty, Mz) with |T| <= mu P (Eq. 35 over the contact: every
    node's |tau| <= mu p; 1e-12 for the rounding of the sums) and |Mz| <= mu P max(a1,
    a2), on the compiled and the numpy march."""
    for vx, vy, phi in SLIPS:
        F = LAW.forces(vx, vy, phi, Vx)
        assert all(math.isfinite(f) for f in F), (vx, vy, phi, Vx, F)
        assert math.hypot(F[0], F[1]) <= MU_P * (1 + 1e-12)
        assert abs(F[2]) <= MU_P * max(LAW.a1, LAW.a2)


@pytest.mark.parametrize("Vx", (1e-300, -5e-324))
def test_the_march_at_a_vanishing_speed_is_the_sliding_field_at_its_midpoints(path, Vx):
    """As |Vx| -> 0+ the increments dist v/(|Vx| k) outgrow the cap mu p at every node,
    and the projection leaves tau = mu p v/|v| with v = (vx - phi y) + i (vy - s phi
    mid), the slip of Eq. (3) where the march samples it (the midpoint of the step).
    With the bounded gain |inc| >= 1e300 dist |v|/(L vb), so tau differs from that
    field by mu p/|inc|, below 1e-280 of the cap at these slips (|v| >= 1e-6 vb): the
    field within 1e-12 of the cap (rounding of the projection's division)."""
    g = LAW._grid(*SPIN_GRID)
    s = math.copysign(1.0, Vx)
    for vx, vy, phi in SLIPS:
        tau, slip = g.march(LAW, _a(vx), _a(vy), _a(Vx), _a(phi))
        v = (vx - phi * g.y[:, None]) + 1j * (vy - s * phi * g.mid)
        cap = LAW.mu * g.p
        want = np.where(g.inside, cap * v / np.abs(v), 0.0)
        assert np.max(np.abs(tau[0] - want)) <= 1e-12 * np.max(cap)
        assert np.array_equal(slip[0], g.inside)


def test_the_bounded_gain_has_no_jump_below_the_rolling_speeds(path):
    """The bound is the min of 1/(|Vx| k) and INC_MAX/(L vb): continuous in Vx. From
    1e-30 m/s (the plain gain, gain L vb about 1e39: every node slides, its direction
    off the limit's by mu p/|inc| = O(|Vx|), below 1e-20) to 1e-100, 1e-300 and 5e-324
    (the bound) the forces are one field: equal within 1e-12 mu P (rounding of the
    sums; at 1e-12 m/s the O(|Vx|) term is still 1e-11 for pure spin, whose slip
    vanishes at the centre)."""
    for vx, vy, phi in SLIPS:
        ref = np.array(LAW.forces(vx, vy, phi, 1e-30))
        for Vx in (1e-100, 1e-300, 5e-324):
            F = np.array(LAW.forces(vx, vy, phi, Vx))
            assert np.max(np.abs(F - ref)[:2]) <= 1e-12 * MU_P, (vx, vy, phi, Vx)
            assert abs(F[2] - ref[2]) <= 1e-12 * MU_P * LAW.a1


def test_vanishing_speed_meets_standstill_to_first_order_in_the_grid(path):
    """At Vx = 0 (standstill) every node slides along the slip at the node itself; the
    march as |Vx| -> 0+ along the slip at the step's midpoint, half a cell behind it
    (first test). The resultants differ by O(dx): for pure spin the midpoint's lateral
    slip phi dx/2 tilts every node the same way, Ty = 1.21 mu P/nx (measured at nx = 32
    to 256). Asserted: the gap within 1.5 mu P/nx at nx = 64 and halving (0.5 +- 0.05)
    from nx = 64 to 128: a discretisation jump of the grid, not of the physics."""
    gaps = []
    for nx, ny in ((64, 48), (128, 96)):
        g = LAW._grid(nx, ny)
        gap = 0.0
        for vx, vy, phi in SLIPS:
            t0, _ = g.march(LAW, _a(vx), _a(vy), _a(0.0), _a(phi))
            T0, _ = g.resultants(t0, _a(0.0))
            t1, _ = g.march(LAW, _a(vx), _a(vy), _a(1e-300), _a(phi))
            T1, _ = g.resultants(t1, _a(1.0))
            gap = max(gap, abs(T1[0] - T0[0]))
        gaps.append(gap)
        assert gap <= 1.5 * MU_P / nx
    assert abs(gaps[1] / gaps[0] - 0.5) <= 0.05


def test_compiled_and_numpy_marches_agree_at_a_vanishing_speed():
    """The same bound in C (march_gain) and numpy (_Grid.gain), the same doubles
    deciding it: the fields within the bound of test_strip_march_of_the_spin_law_agrees
    _to_rounding (7e-13 of mu P per node's cap)."""
    if native.library() is None:
        pytest.skip("no compiled library")
    g = LAW._grid(*SPIN_GRID)
    cap = np.max(LAW.mu * g.p)
    for Vx in SPEEDS:
        for vx, vy, phi in SLIPS:
            v = (_a(vx), _a(vy), _a(Vx), _a(phi))
            tc, sc = g.march(LAW, *v)
            tn, sn = g._march_numpy(LAW, *v)
            assert np.max(np.abs(tc - tn)) <= 7e-13 * cap and np.array_equal(sc, sn)


def _jacobian(lib, g, v: tuple[float, float, float, float]) -> np.ndarray:
    """stepper.c's cf_march_jacobian: d(Tx, Ty, Mz)/d(vx, vy, Vx, phi) of the march."""
    import ctypes

    f = lib.cf_march_jacobian
    f.argtypes = [ctypes.POINTER(native.Strips)] + [ctypes.c_double] * 4 + [ctypes.c_void_p]
    f.restype = None
    D = np.zeros(12)
    f(g.strips(LAW), *v, D.ctypes.data)
    return D.reshape(3, 4)


def test_the_march_derivative_at_a_vanishing_speed_is_finite_and_its_slope():
    """cf_march_jacobian (behind the native FMU's directional derivatives) with the
    bounded gain: at Vx = 1e-200 (plain gain) and 1e-300, 5e-324 (bounded) finite, and
    d/d(vx, vy, phi) the central differences of the compiled march's resultants (step
    1e-9 of the input's scale u: 1e-3 m/s, 1e-3/a1 rad/s; truncation of the smooth
    sliding field below 1e-15, rounding sqrt(3072) eps mu P/(2e-9 u) = 6e-6 mu P/u,
    bound 2e-5 mu P/u, Mz with a1). d/dVx, the sliding field's limit slope (the part of
    the carried traction across a node's direction, divided by Vx), is the same from
    1e-20 to 1e-200 m/s (1e-9 of mu P/1e-3 m/s: the rounding of the projection; it was
    computed as lam |inc| less its part along the direction, 1e85 of rounding at 1e-100),
    and 0 where the gain is bounded (no Vx left in it)."""
    lib = native.library()
    if lib is None:
        pytest.skip("no compiled library")
    g = LAW._grid(*SPIN_GRID)
    unit = (1e-3, 1e-3, None, 1e-3 / LAW.a1)
    scale = np.array([MU_P, MU_P, MU_P * LAW.a1])

    def R(v):
        tau, _ = g.march(LAW, *(_a(x) for x in v))
        T, M = g.resultants(tau, _a(math.copysign(1.0, v[2])))
        return np.array([T[0].real, T[0].imag, M[0]])

    for vx, vy, phi in SLIPS[1:]:
        ref = _jacobian(lib, g, (vx, vy, 1e-20, phi))[:, 2]
        for Vx in (1e-200, 1e-300, 5e-324):
            v = [vx, vy, Vx, phi]
            D = _jacobian(lib, g, tuple(v))
            assert np.all(np.isfinite(D))
            for k in (0, 1, 3):
                d = 1e-9 * unit[k]
                up, dn = list(v), list(v)
                up[k] += d
                dn[k] -= d
                fd = (R(up) - R(dn)) / (2 * d)
                assert np.all(np.abs(D[:, k] - fd) <= 2e-5 * scale / unit[k] + 1e-6 * np.abs(fd))
            want = ref if Vx == 1e-200 else 0.0
            assert np.all(np.abs(D[:, 2] - want) <= 1e-9 * scale / 1e-3), (Vx, D[:, 2], ref)


@pytest.mark.parametrize("scale", [1e-300, 1e-250, 1e300])
def test_tiny_and_huge_velocities_of_one_creepage_give_its_forces(path, scale):
    """The law is homogeneous of degree 0 in (vx, vy, phi, Vx): every slip, spin and
    rolling speed times 1e-300, 1e-250 or 1e300 gives the forces of the
    creepages themselves, to 1e-12 of mu P (mu P a1 for Mz). The march scales them by a
    power of two first (stepper.c march_scale: exact); before, 1/(|Vx| k) overflowed and
    a spin at Vx = 1e-300 gave NaN."""
    for vx, vy, phi in SLIPS:
        ref = LAW.forces(_a(vx), _a(vy), _a(phi), _a(1.0))
        got = LAW.forces(_a(vx * scale), _a(vy * scale), _a(phi * scale), _a(scale))
        assert all(np.all(np.isfinite(g)) for g in got)
        for k, unit in ((0, MU_P), (1, MU_P), (2, MU_P * LAW.a1)):
            assert abs(float(got[k][0]) - float(ref[k][0])) <= 1e-12 * unit, (vx, vy, phi, k)
