"""Lift-off (P = 0) in the numerics: the law's limit and the step without contact.

docs/model.md, "Lift-off": as P -> 0+ the contact ellipse shrinks (a1 ~ P^(1/4)), the
onset of full slip 2 mu p0 k/a1 ~ P^(1/4) goes to 0, so any slip is full slip and
T = mu P v/|v| -> 0; the slip's relaxation time M A2 Vx/(dT/dxi) ~ P^(-3/4) grows
without bound, so the slip is no longer fast: at P = 0 it follows Eqs. (8)-(9) with
T = 0, in both methods, and is carried into the next contact.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from contact_fmu import examples as ex
from contact_fmu import native
from contact_fmu.dynamics.body import Body, Lateral, Loads
from contact_fmu.dynamics.integrator import RollingBody
from contact_fmu.laws.thin_layer import LayerContact


def law(P: float) -> LayerContact:
    return LayerContact(P, ex.Rx, ex.Ry, ex.k1, ex.k2, ex.kb, ex.ks, ex.mu)


def test_law_at_zero_load_is_the_limit_of_a_vanishing_load():
    """Eq. (34): a1, p0/a1 scale as P^(1/4), so creep_full_slip(P)/creep_full_slip(1000 N)
    = (P/1000)^(1/4) (to rounding) and tends to 0; the force at a fixed slip is mu P
    (full slip) and tends to 0. P = 0 gives those limits exactly: zero everywhere."""
    ref = law(ex.P)
    for P in (1e-4, 1e-12):
        small = law(P)
        assert small.creep_full_slip / ref.creep_full_slip == pytest.approx(
            (P / ex.P) ** 0.25, rel=1e-12
        )
        Tx, Ty, Mz = small.forces(0.01, 0.002, 0.0, 5.0)
        assert math.hypot(Tx, Ty) == pytest.approx(ex.mu * P, rel=1e-12)  # full slip
    zero = law(0.0)
    assert (zero.a1, zero.a2, zero.p0, zero.creep_full_slip) == (0.0, 0.0, 0.0, 0.0)
    assert zero.forces(0.01, 0.002, 0.0, 5.0) == (0.0, 0.0, 0.0)
    assert zero.forces(0.01, 0.002, 3.0, 5.0) == (0.0, 0.0, 0.0)  # with spin
    Tx, Ty, Mz = zero.forces(np.array([0.01, -1.0]), 0.0, 0.0, np.array([5.0, 0.0]))
    assert not np.any(Tx) and not np.any(Ty) and not np.any(Mz)
    assert zero.tx_slope(0.01, 0.0, 5.0) == (0.0, 0.0, 0.0, 0.0)
    assert zero.adhesion_fraction(0.01, 0.0, 5.0) == 0.0


def run(monkeypatch, compiled: bool, method: str, scheme: str, lateral: Lateral, Iy: float):
    """A body that lifts off, moves in the air and lands again; the states after each step."""
    if not compiled:
        monkeypatch.setattr(native, "library", lambda: None)
    b = RollingBody(
        law(ex.P), Body(ex.M, ex.Rx, Iy, 1e-3), lateral, method, Vx0=5.0, Omega_y0=99.0,
        scheme=scheme,
    )  # fmt: skip
    assert (b._kernel is not None) == compiled
    # eta = inf (Iy = 0) admits no gross sliding: no moment, no lateral force for it
    L = Loads(40.0, 5.0, -3.0, 1e-5) if Iy > 0 else Loads(40.0, 0.0, 0.0, 1e-5)
    states = []
    for P in (ex.P, 0.0, 0.0, 1.0, ex.P):
        b.set_load(P)
        y0 = b.y.copy()
        b.advance(2e-4, L, 3)
        states.append((y0, b.y.copy(), b.out))
        assert math.hypot(b.out.Tx, b.out.Ty) <= ex.mu * P * (1 + 1e-12)
    return states, L


LATERAL = (Lateral(0.0, 0.0), Lateral(None, 0.0), Lateral(None, None))


@pytest.mark.parametrize("lateral", LATERAL)
@pytest.mark.parametrize("method", ("full", "quasistationary"))
@pytest.mark.parametrize("scheme", ("lobatto3c", "sdirk2"))
@pytest.mark.parametrize("Iy", (ex.M * ex.Rx**2 / 3.0, 0.0))
def test_without_contact_the_body_moves_under_the_external_loads(
    monkeypatch, lateral, method, scheme, Iy
):
    """At P = 0, Eqs. (8)-(11) with T = 0: M dVx = Fx_ex h, Iy dOmega_y = My_ex h (Omega_y
    held for Iy = 0 without a moment), M dVy = Fy_ex h, Iz dOmega_z = Mz_ex h, to the
    rounding of the speeds (1e-13 of the change); no force. Compiled and Python paths:
    the same doubles where the compiled one covers the path (scalar: bit for bit)."""
    h = 2e-4
    got = {}
    for compiled in (False, True):
        states, L = run(monkeypatch, compiled, method, scheme, lateral, Iy)
        got[compiled] = states
        for y0, y1, out in states[1:3]:
            assert (out.Tx, out.Ty, out.Mz) == (0.0, 0.0, 0.0)
            dV = y1[0] - y0[0]
            assert ex.M * dV == pytest.approx(L.Fx_ex * h, rel=1e-12)
            dO = ((y1[0] - y1[1]) - (y0[0] - y0[1])) / ex.Rx
            assert abs(Iy * dO - L.My_ex * h) <= 1e-12 * abs(L.My_ex * h) + 1e-15 * abs(dO)
            if Iy == 0.0:
                assert abs(dO) <= 1e-12
            if lateral.dynamic_vy:
                assert ex.M * (y1[2] - y0[2]) == pytest.approx(L.Fy_ex * h, rel=1e-12)
            if lateral.dynamic_spin:
                assert 1e-3 * (y1[3] - y0[3]) == pytest.approx(L.Mz_ex * h, rel=1e-9)
        monkeypatch.undo()
    if lateral == LATERAL[0]:  # the scalar kernel: bit for bit
        for a, b in zip(got[False], got[True], strict=True):
            assert np.array_equal(a[1], b[1]) and a[2] == b[2]
    else:  # the vector kernel: to the stage tolerance
        for a, b in zip(got[False], got[True], strict=True):
            assert np.allclose(a[1], b[1], rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("compiled", (False, True))
def test_eta_infinity_takes_no_moment_without_contact(monkeypatch, compiled):
    """Iy = 0 in the air with My_ex != 0 would spin up instantly: the step is refused
    (StageSolveError, as beyond mu P in contact), the state unchanged."""
    from contact_fmu.dynamics.integrator import StageSolveError

    if not compiled:
        monkeypatch.setattr(native, "library", lambda: None)
    b = RollingBody(law(0.0), Body(ex.M, ex.Rx, 0.0), Vx0=5.0, Omega_y0=100.0)
    y = b.y.copy()
    with pytest.raises(StageSolveError, match="reaches mu P = 0 N"):
        b.advance(1e-4, Loads(My_ex=1.0))
    assert np.array_equal(b.y, y)


@pytest.mark.parametrize("compiled", (False, True))
def test_a_vanishing_mass_keeps_the_angular_momentum_balance(monkeypatch, compiled):
    """M = 1e-300 (eta ~ 1e-300): after Fx_ex jumps, a Lobatto step of 1e-12 s is stiff
    enough (h dT/dv/(M A2) > 1e13) to be solved in its algebraic limit. The slip jumps
    to the new creep force; with a massless translation Vx must take that jump (k =
    A2 = 1), not Omega_y: Iy dOmega_y = (My_ex + Rx Tx) h, abs(Tx) <= mu P. It took it
    into Omega_y (a jump of 0.34 rad/s against the 1.8e-8 rad/s allowed)."""
    if not compiled:
        monkeypatch.setattr(native, "library", lambda: None)
    Iy = 8.333333333333335e-4
    b = RollingBody(law(ex.P), Body(1e-300, ex.Rx, Iy), Vx0=5.64, Omega_y0=5.64 / ex.Rx)
    assert (b._kernel is not None) == compiled
    b.advance(1.75e-4, Loads(Fx_ex=190.0), 4)
    O0 = b.Omega_y
    h = 1e-12
    b.advance(h, Loads(Fx_ex=-38.2284))
    assert b.out.Tx == pytest.approx(-38.2284, rel=1e-12)  # Eq. (26): A2 = 1
    cap = ex.mu * ex.P * ex.Rx * h
    assert abs(Iy * (b.Omega_y - O0)) <= cap + Iy * 4 * math.ulp(O0)


@pytest.mark.parametrize("compiled", (False, True))
def test_sdirk2_with_eta_infinity_keeps_the_algebraic_slip_on_its_root(monkeypatch, compiled):
    """eta = inf (Iy = 0): Eq. (26) asks Tx = A2 Fx_ex - A1 My_ex/Rx = -My_ex/Rx = 0 of
    the contact (A2 = 0, A1 = 1), and Eq. (29) Ty = Fy_ex = 0, so the slip sits at the
    law's root vx = vy = 0 whatever Fx_ex (here 40 N). SDIRK2 with Vy as an unknown must
    start the massless slip of its second stage from the first stage's root, not from
    the (1 - gamma)/gamma extrapolation (which diverged to vx = -3.7e213 with T = 0)."""
    if not compiled:
        monkeypatch.setattr(native, "library", lambda: None)
    b = RollingBody(law(ex.P), Body(ex.M, ex.Rx, 0.0, 1e-3), Lateral(None, 0.0), "full",
                    Vx0=5.0, Omega_y0=99.0, scheme="sdirk2")  # fmt: skip
    b.advance(2e-4, Loads(40.0, 0.0, 0.0, 1e-5), 3)
    scale = b.law.creep_full_slip * 5.0  # the slip at the onset of full slip (m/s)
    assert abs(b.y[1]) <= 1e-12 * scale and abs(b.y[2]) <= 1e-12 * scale
    assert abs(b.out.Tx) <= 1e-12 * ex.mu * ex.P and abs(b.out.Ty) <= 1e-12 * ex.mu * ex.P
    assert b.y[0] == pytest.approx(5.0 + 40.0 * 2e-4 / ex.M, rel=1e-12)  # Eq. (8), T = 0
