"""Rigid-body dynamics (Eqs. 8-11, 20-30) and the two time-stepping methods."""

from __future__ import annotations

import math

import numpy as np
import pytest

from contact_fmu import InputError
from contact_fmu import examples as ex
from contact_fmu.dynamics.body import Body, Lateral, Loads, load_utilisation
from contact_fmu.dynamics.integrator import RollingBody, StageSolveError
from contact_fmu.dynamics.simulate import load_history, simulate

C = ex.contact()
MU_P = C.mu * C.P
F = ex.force_unit()  # mu p0 a1 a2 (N)
TC = ex.time_unit()  # T_c of Eq. (13) (s)
V0 = ex.speed_unit()  # Rx / T_c (m/s)


def relaxation_time(body: Body, Vx: float) -> float:
    """Time constant of the slip equation (20) at small creep: M A2 Vx / (dT/d(v/Vx))."""
    return body.m_slip * Vx / C.creep_slope


def fig13_loads():
    """Fig. 13: Fx_ex = mu p0 a1 a2, My_ex = 0.2 mu p0 Rx a1 a2 sin(t/T_c)."""
    return load_history(Fx_ex=F, My_ex=lambda t: 0.2 * F * ex.Rx * math.sin(t / TC))


# ---- Eqs. (21), (23), (27) ---------------------------------------------------------------
def test_A1_A2_of_eq23():
    for eta in (1.0, 2.5, 10.0):
        b = ex.body(eta)
        assert b.eta == pytest.approx(eta, rel=1e-14)
        assert b.A1 == pytest.approx(eta / (1 + eta), rel=1e-14)
        assert b.A1 + b.A2 == pytest.approx(1.0, rel=1e-15)
    ring = ex.body(1.0)  # mass on a ring of radius Rx (Fig. 2)
    assert ring.A1 == ring.A2 == pytest.approx(0.5)
    axis = ex.body(math.inf)  # mass on the axis: Iy = 0
    assert (axis.Iy, axis.A1, axis.A2, axis.m_slip) == (0.0, 1.0, 0.0, 0.0)


def test_admissible_region_of_eq27_is_a_strip_and_an_ellipse():
    b = ex.body(2.5)
    # Fig. 3: |A2 Fx - A1 My/Rx| = mu P on two parallel lines in (Fx, My)
    My = np.linspace(-2, 2, 9) * MU_P * ex.Rx
    Fx_edge = (MU_P + b.A1 * My / ex.Rx) / b.A2
    np.testing.assert_allclose(load_utilisation(b, C.mu, C.P, Fx_edge, My), 1.0, rtol=1e-14)
    # Fig. 4: (A2 Fx)^2 + Fy^2 = (mu P)^2 for My = 0
    th = np.linspace(0, 2 * np.pi, 13)
    u = load_utilisation(b, C.mu, C.P, MU_P * np.cos(th) / b.A2, 0.0, MU_P * np.sin(th))
    np.testing.assert_allclose(u, 1.0, rtol=1e-14)


# ---- sign of Eq. (9) and energy ------------------------------------------------------------
@pytest.mark.parametrize("eta", [1.0, 2.5, 10.0])
def test_friction_reduces_the_slip_and_kinetic_energy_falls_by_the_friction_work(eta):
    # references.md: with no external loads the kinetic energy falls by exactly the
    # friction work int T.v dt >= 0. d/dt(M Vx^2/2 + Iy Omega_y^2/2) = -Tx (Vx - Omega_y Rx)
    # holds with Iy dOmega_y/dt = +Rx Tx (docs/model.md); with the printed -Rx Tx the
    # slip would grow for eta > 1.
    b = ex.body(eta)
    vx0 = 0.8 * C.creep_full_slip * V0
    tau = relaxation_time(b, V0)
    n = 400
    tr = simulate(
        C, b, Loads(), t_end=20 * tau, dt=20 * tau / n, Vx0=V0, Omega_y0=(V0 - vx0) / ex.Rx
    )
    assert np.all(np.diff(tr.vx) < 0) and 0 < tr.vx[-1] < 1e-6 * vx0
    assert np.all(tr.Tx * tr.vx >= 0)
    KE = 0.5 * b.M * tr.Vx**2 + 0.5 * b.Iy * tr.Omega_y**2
    P_fric = tr.Tx * tr.vx
    work = np.sum(0.5 * (P_fric[1:] + P_fric[:-1]) * np.diff(tr.t))
    # trapezoid over 400 steps of a decaying exponential (20 time constants): error
    # (dt/tau)^2/12 ~ 2e-4 relative to the work; the SDIRK2 energy error is smaller
    assert KE[0] - KE[-1] == pytest.approx(work, rel=5e-4)


# ---- quasistationary phase, Eqs. (26), (28) ------------------------------------------------
@pytest.mark.parametrize("eta", ex.ETA_FIG13)
def test_full_solution_approaches_eq26_with_the_first_order_lag(eta):
    # Fig. 13. The slip equation M A2 dvx/dt = -Tx + A2 Fx - A1 My/Rx (Eq. 20) is a
    # singular perturbation: after the transient, Tx = A2 Fx - A1 My/Rx - M A2 dv_qs/dt
    # + O((tau/T)^2), v_qs the quasistationary slip of Eq. (28). The remainder is of
    # relative order tau_r/T_c against the lag term (measured 1.2-1.5 tau_r/T_c; bound 3).
    b = ex.body(eta)
    kw = dict(t_end=4 * TC, dt=TC / 200, Vx0=V0)
    full = simulate(C, b, fig13_loads(), substeps=4, **kw)
    qs = simulate(C, b, fig13_loads(), method="quasistationary", **kw)
    target = b.tx_quasistationary(F, 0.2 * F * ex.Rx * np.sin(full.t / TC))
    # Eq. (26) exactly from the first step on (t = 0 is the given initial state)
    np.testing.assert_allclose(qs.Tx[1:], target[1:], rtol=0, atol=1e-13 * MU_P)
    tau = relaxation_time(b, V0)
    after = full.t > 30 * tau
    lag = -b.m_slip * np.gradient(qs.vx, qs.t)
    remainder = np.abs(full.Tx - target - lag)[after].max()
    assert remainder <= 3 * (tau / TC) * np.abs(lag[after]).max()
    # and Vx of both methods agree to O(tau_r/T_c)
    assert np.abs(full.Vx - qs.Vx).max() <= 3 * (tau / TC) * qs.Vx.max()


def test_quasistationary_speed_follows_eq28():
    # Eq. (28): M dVx/dt = A1 (Fx + My/Rx) in the quasistationary phase, so
    # Vx(t) = Vx(0) + A1/M int (Fx + My/Rx) dt; here in closed form for Fig. 13's loads
    b = ex.body(3.0)
    qs = simulate(C, b, fig13_loads(), 4 * TC, TC / 100, method="quasistationary", Vx0=V0)
    Vx = V0 + b.A1 / b.M * (F * qs.t + 0.2 * F * TC * (1 - np.cos(qs.t / TC)))
    # SDIRK2 quadrature of a smooth load, 400 steps: O(dt^2) ~ 1e-5 relative
    np.testing.assert_allclose(qs.Vx, Vx, rtol=1e-5)
    # the slip is the inverse creep law at the creepage of Eq. (26)
    np.testing.assert_allclose(C.force(qs.vx, 0.0, qs.Vx)[0], qs.Tx, rtol=1e-10)


# ---- the stiff integrator ---------------------------------------------------------------------
@pytest.mark.parametrize("scheme", ["lobatto3c", "sdirk2"])
def test_scheme_converges_at_second_order(scheme):
    # Both schemes are second order. Steps of 0.4 to 0.1 relaxation times: below
    # h ~ tau_r, where Lobatto IIIC (stage order 1) shows the stiff order reduction
    # (observed 1.35 -> 1.9 from 6 tau_r down). The reference at 8x the finest step
    # leaves 1/64 of the finest error in the observed order (< 0.03).
    b = ex.body(3.0)
    kw = dict(t_end=TC / 4, dt=TC / 80, Vx0=V0, scheme=scheme)
    ref = simulate(C, b, fig13_loads(), substeps=640, **kw)
    errs = [
        np.abs(simulate(C, b, fig13_loads(), substeps=n, **kw).vx - ref.vx).max()
        for n in (20, 40, 80)
    ]
    orders = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all((orders > 1.8) & (orders < 2.2)), orders


def _stability(scheme: str, z: float) -> float:
    """Stability function R(z) of the scheme (docs/model.md, Time integration)."""
    if scheme == "lobatto3c":
        return 1.0 / (1.0 - z + 0.5 * z * z)
    g = 1 - 0.5 * math.sqrt(2)
    return (1 + (1 - 2 * g) * z) / (1 - g * z) ** 2


@pytest.mark.parametrize("scheme", ["lobatto3c", "sdirk2"])
@pytest.mark.parametrize("ratio", [1e2, 1e4, 1e8])
def test_any_step_size_is_stable_and_damps_the_fast_mode(scheme, ratio):
    # L-stability. Per step the deviation from the slow manifold is multiplied by the
    # scheme's R(z), z = -h/tau_r: Lobatto IIIC's 1/(1 - z + z^2/2) ~ 2/z^2 (positive),
    # SDIRK2's ~ -4.8/|z| (alternating). tau_r grows with Vx: the bound uses tau_r at
    # the step's end, with 20 % for the nonlinearity of the law. The reference is the
    # same run with 256 substeps (its own remnant < 1e-12).
    b = ex.body(3.0)
    dt = ratio * relaxation_time(b, V0)
    kw = dict(t_end=6 * dt, dt=dt, Vx0=V0, scheme=scheme)
    coarse = simulate(C, b, Loads(Fx_ex=F), **kw)
    fine = simulate(C, b, Loads(Fx_ex=F), substeps=256, **kw)
    creep = fine.vx / fine.Vx
    dev = coarse.vx / coarse.Vx - creep
    dev[0] = -creep[1]  # the start: pure rolling, off the slow manifold by the creepage
    for n in range(len(dev) - 1):
        z = -dt / relaxation_time(b, coarse.Vx[n + 1])
        bound = 1.2 * abs(_stability(scheme, z) * dev[n]) + 8 * np.finfo(float).eps
        assert abs(dev[n + 1]) <= bound, (n, dev)
    assert np.all(np.isfinite(coarse.Tx)) and np.all(np.abs(coarse.Tx) <= MU_P)


@pytest.mark.parametrize("ratio", [0.3, 3.0, 8.5, 30.0, 1e3, 1e6])
def test_lobatto_never_overshoots_a_load_step(ratio):
    # The default scheme's R(z) is in (0, 1): after a sudden load the force rises
    # monotonically to Eq. (26)'s value and never passes it, whatever the step (8.5
    # tau_r is where SDIRK2 overshoots most, by 21 %). Constant Fx_ex: Tx = A2 Fx_ex
    # up to the lag M A2 dv/dt < 0 (the slip grows with Vx), so Tx stays below it.
    b = ex.body(3.0)
    dt = ratio * relaxation_time(b, V0)
    tr = simulate(C, b, Loads(Fx_ex=F), t_end=40 * dt, dt=dt, Vx0=V0)
    target = b.A2 * F
    # noise floor: the stage solve fixes vx to 1e-13 of the creep scale, and the force
    # moves by about mu P/Tx = 6 times that relative: 1e-11 of Tx bounds it
    assert np.all(np.diff(tr.Tx) >= -1e-11 * target)
    assert np.all(tr.Tx <= target * (1 + 1e-11))
    assert tr.Tx[-1] == pytest.approx(target, rel=1e-2)


def test_eta_infinity_is_the_algebraic_limit():
    # Iy = 0 (Fig. 2, eta = inf): Eq. (9) becomes Rx Tx + My = 0, so Tx = -My/Rx
    b = ex.body(math.inf)
    for method in ("full", "quasistationary"):
        tr = simulate(C, b, fig13_loads(), 2 * TC, TC / 50, method=method, Vx0=V0)
        np.testing.assert_allclose(tr.Tx, -0.2 * F * np.sin(tr.t / TC), atol=1e-12 * MU_P)


def test_eta_infinity_rejects_loads_beyond_mu_P():
    rb = RollingBody(C, ex.body(math.inf), Vx0=V0, Omega_y0=V0 / ex.Rx)
    with pytest.raises(StageSolveError, match="eta = inf"):
        rb.advance(TC / 10, Loads(My_ex=-1.5 * MU_P * ex.Rx))
    assert rb.t == 0.0 and rb.Vx == V0  # state unchanged


# ---- gross sliding --------------------------------------------------------------------------
@pytest.mark.parametrize("method", ["full", "quasistationary"])
def test_gross_sliding_in_and_out_without_chattering(method):
    # A brake beyond mu P (Tx demanded 1.5 mu P) from Tc to 2Tc, then 0.5 mu P. During
    # sliding |Tx| = mu P against the slip, and the slip grows at (1.5 - 1) mu P / (M A2);
    # after release it shrinks at the same rate, so rolling resumes near t = 3 Tc.
    b = ex.body(2.5)

    def brake(t: float) -> float:
        return -(1.5 if TC <= t < 2 * TC else 0.5) * MU_P * ex.Rx / b.A1

    dt = TC / 100
    tr = simulate(C, b, load_history(My_ex=brake), 4 * TC, dt, method=method, Vx0=V0)
    sl = tr.sliding
    t_in, t_out = tr.t[np.argmax(sl)], tr.t[len(sl) - 1 - np.argmax(sl[::-1])]
    assert t_in == pytest.approx(TC, abs=2 * dt)
    # the end moves by the change of the saturation slip creep_full |Vx|: within 3 %
    assert t_out == pytest.approx(3 * TC, abs=0.03 * TC)
    assert np.all(sl[(tr.t > TC + 2 * dt) & (tr.t < 3 * TC - 0.03 * TC)])
    np.testing.assert_allclose(tr.Tx[sl], MU_P, rtol=1e-12)  # |T| = mu P, one sign
    # back to rolling: Tx returns to the demand 0.5 mu P (full: within the lag)
    assert tr.Tx[-1] == pytest.approx(0.5 * MU_P, rel=1e-3)
    assert np.all(np.isfinite(tr.vx)) and np.all(np.abs(tr.Tx) <= MU_P)


def test_speed_through_zero_and_reversal():
    # the constant brake of 0.5 mu P stops the body and drives it backwards: Vx crosses
    # zero, where the creep law becomes Coulomb's; no NaN, |T| <= mu P, T continuous
    b = ex.body(2.5)
    tr = simulate(C, b, Loads(My_ex=-0.5 * MU_P * ex.Rx / b.A1), 8 * TC, TC / 200, Vx0=V0)
    assert tr.Vx[0] > 0 > tr.Vx[-1]
    assert np.all(np.isfinite(tr.Tx)) and np.all(np.abs(tr.Tx) <= MU_P)
    # after the start-up transient (5 steps = 15 relaxation times) the force moves by
    # less than 1e-3 mu P per step, also where Vx passes zero (measured 3e-4)
    jumps = np.abs(np.diff(tr.Tx))[5:]
    assert jumps.max() < 1e-3 * MU_P


def test_slip_decays_to_zero_through_underflow():
    # no loads, initial slip 1e-3 Vx: the slip decays geometrically by R(z) per step
    # (here 1e-110 after 80 steps) down to zero; the Newton slopes must stay finite
    # where |v|^3 underflows (a stiff-suite case found a division by zero there)
    b = ex.body(2.0)
    tr = simulate(C, b, Loads(), 0.02, 1e-4, Vx0=V0, Omega_y0=V0 / ex.Rx * (1 - 1e-3))
    assert np.all(np.isfinite(tr.vx)) and np.all(np.diff(np.abs(tr.vx)) <= 0)
    assert abs(tr.vx[-1]) < 1e-200 * V0 and abs(tr.Tx[-1]) < 1e-190 * MU_P


def test_law_at_standstill_is_continuous_through_zero_speed():
    """Below V_STANDSTILL the stage solves see the blend of the law at +V_STANDSTILL and
    -V_STANDSTILL (integrator.forces_at_rest): with lateral slip and spin the two sides
    differ by a finite amount (Mz flips with the rolling direction, the spin march runs
    the other way), which the blend turns into a ramp of slope jump/(2 V_STANDSTILL),
    continuous at 0 and at +-V_STANDSTILL: across 2e-3 V_STANDSTILL about each of these
    points the forces move by at most 1e-3 of the jump (1.1e-3 with the law's own
    variation outside)."""
    from contact_fmu.dynamics.integrator import V_STANDSTILL

    b = Body(ex.M, ex.Rx, ex.M * ex.Rx**2 / 3, Iz=0.4 * ex.M * ex.Rx**2)
    rb = RollingBody(C, b, Lateral(vy_ratio=None, spin_ratio=None))
    Vs, d = V_STANDSTILL, 1e-3
    Vx = np.array([p + o * Vs for p in (-Vs, 0.0, Vs) for o in (-d, d)])
    Y = np.stack([Vx, np.full(6, 2e-4), np.full(6, 3e-4), np.full(6, 2.0)], axis=1)
    jump = np.abs(np.subtract(*rb._forces(np.array([[Vs, 2e-4, 3e-4, 2.0],
                                                     [-Vs, 2e-4, 3e-4, 2.0]]))))  # fmt: skip
    assert jump.max() > 1e-3 * MU_P  # the two sides differ: the floor alone would jump
    T = rb._forces(Y)
    for i in (0, 2, 4):
        assert np.all(np.abs(T[i + 1] - T[i]) <= 1.1e-3 * jump), np.abs(T[i + 1] - T[i]) / jump


@pytest.mark.parametrize("h", [1e-5, 1.2e-5, 2.5e-5])
def test_lateral_dynamics_through_zero_speed(h):
    """Eqs. (8)-(11) under braking and a lateral force: Vx passes zero (at 2 ms, a step
    boundary for h = 1e-5 and 2.5e-5) and reverses, the lateral slip and the spin with it.
    Every stage solve converges (before the blend at standstill the residual jumped
    where Vx crossed zero and h = 1e-5 failed), |T| <= mu P, the run ends backwards at
    the speed of Eq. (8) with Tx = -A2 0.75 mu P (Eq. 26), and the compiled step
    (stepper.c, the same blend) ends where the Python one does, to the bound of
    tests/test_native.py's vector-path comparisons (1e-12 of mu P; measured 1e-15)."""
    b = Body(ex.M, ex.Rx, ex.M * ex.Rx**2 / 2.0, Iz=0.4 * ex.M * ex.Rx**2)
    lat = Lateral(vy_ratio=None, spin_ratio=None)
    bodies = [RollingBody(C, b, lat, Vx0=0.3, Omega_y0=0.3 / ex.Rx) for _ in range(2)]
    bodies[1]._kernel = None  # the Python path
    L = Loads(Fx_ex=-0.75 * MU_P, Fy_ex=0.2 * MU_P)
    for rb in bodies:
        for _ in range(round(4e-3 / h)):
            rb.advance(h, L, 4)
            assert math.hypot(rb.out.Tx, rb.out.Ty) <= MU_P * (1 + 1e-12)
        assert rb.y[0] == pytest.approx(0.3 - b.A1 * 0.75 * MU_P / b.M * rb.t, rel=1e-2)
        assert rb.out.Tx == pytest.approx(-b.A2 * 0.75 * MU_P, rel=1e-3)
    a, p = (np.array([rb.out.Tx, rb.out.Ty, rb.out.Mz / C.a1]) for rb in bodies)
    assert np.abs(a - p).max() <= 1e-12 * MU_P


# ---- lateral dynamics, Eqs. (10)-(11), (29)-(30) ------------------------------------------
def test_lateral_force_balances_the_load_eq29():
    b = Body(ex.M, ex.Rx, ex.M * ex.Rx**2 / 3)
    loads = Loads(Fx_ex=0.5 * F, Fy_ex=0.3 * F)
    lat = Lateral(vy_ratio=None, spin_ratio=0.0)
    full = simulate(C, b, loads, TC, TC / 50, lateral=lat, Vx0=V0)
    qs = simulate(C, b, loads, TC, TC / 50, lateral=lat, Vx0=V0, method="quasistationary")
    assert qs.Ty[-1] == pytest.approx(0.3 * F, rel=1e-12)  # Eq. (29)
    assert qs.Tx[-1] == pytest.approx(b.A2 * 0.5 * F, rel=1e-12)  # Eq. (26)
    # full: lateral relaxation time M Vx / (dT/d(v/Vx)) ~ 3e-3 T_c: within 1e-3 at 1 T_c
    assert full.Ty[-1] == pytest.approx(0.3 * F, rel=1e-3)
    assert full.Vy[-1] == pytest.approx(qs.Vy[-1], rel=2e-3)


def test_spin_moment_balances_the_load_eq30():
    # Omega_z from Eq. (11). The spin mode is slow: Iz ~ M Rx^2 against a spin stiffness
    # of order a^4/k gives a time constant of about 2 T_c here (measured), so the full
    # method settles over ~12 T_c at constant Vx (Fx_ex = 0); the QS method has Mz = Mz_ex.
    b = Body(ex.M, ex.Rx, ex.M * ex.Rx**2 / 3, Iz=0.4 * ex.M * ex.Rx**2)
    loads = Loads(Fy_ex=0.3 * F, Mz_ex=0.0)
    lat = Lateral(vy_ratio=None, spin_ratio=None)
    qs = simulate(C, b, loads, TC, TC / 4, lateral=lat, Vx0=V0, method="quasistationary")
    assert abs(qs.Mz[-1]) < 1e-12 * MU_P * C.a1
    assert qs.Ty[-1] == pytest.approx(0.3 * F, rel=1e-10)
    full = simulate(C, b, loads, 12 * TC, TC / 2, lateral=lat, Vx0=V0)
    # exp(-12/2.1) ~ 3e-3 of the aligning moment is left
    assert abs(full.Mz[-1]) < 1e-2 * abs(full.Mz[1])
    assert full.Omega_z[-1] == pytest.approx(qs.Omega_z[-1], rel=1e-2)
    assert full.Ty[-1] == pytest.approx(0.3 * F, rel=1e-4)


def test_held_lateral_creepage_gives_Ty_over_Tx_equal_vy_over_vx():
    # Fig. 12's setting: Vy/Vx = 0.002 held; the law gives Ty/Tx = vy/vx (Eq. 37)
    b = ex.body(2.92)
    tr = simulate(C, b, Loads(Fx_ex=F), TC, TC / 50, lateral=Lateral(vy_ratio=0.002), Vx0=V0)
    np.testing.assert_allclose(tr.Vy, 0.002 * tr.Vx, rtol=1e-15)
    np.testing.assert_allclose(tr.Ty[1:] / tr.Tx[1:], tr.vy[1:] / tr.vx[1:], rtol=1e-9)


@pytest.mark.parametrize("vy_ratio", [0.0, 0.002])
def test_quasistationary_takes_held_loads_in_one_step(vy_ratio):
    # Under held loads Eq. (28) makes Vx linear in t and vx algebraic: one step over the
    # interval equals eight substeps up to rounding (relative 1e-13: 8 additions)
    lat = Lateral(vy_ratio=vy_ratio)
    kw = dict(method="quasistationary", Vx0=V0, Omega_y0=V0 / ex.Rx)
    one, many = (RollingBody(C, ex.body(3.0), lat, **kw) for _ in range(2))
    for k in range(50):
        L = Loads(Fx_ex=F, My_ex=0.2 * F * ex.Rx * math.sin(k / 10))
        one.advance(TC / 20, L, substeps=8)
        for _ in range(8):
            many.advance(TC / 160, L)
    a, b = one.outputs(), many.outputs()
    for key in a:
        assert a[key] == pytest.approx(b[key], rel=1e-13, abs=1e-300), key


@pytest.mark.parametrize("native", [True, False])
def test_quasistationary_lateral_state_does_not_depend_on_the_slip_before(native):
    """Section 3c: with the masses of vx, Vy, Omega_z dropped, Eqs. (26), (29), (30) fix
    the slip from the loads (T = F) and Vx (Eq. 28), whatever it was before the step. From
    rest, from slip in the other direction, from slip beyond the onset of full slip (a
    flat law), from slip along the demand, and over a step in which Vx falls from 4.6 m/s
    through zero (eta = inf: the last state's slip velocities at the new speed are
    creepages 20 times too large): the same state, to the stage solve's tolerance
    (SOLVE_RTOL = 1e-13 of u + scale; 1e-12 allowed). The second and third starts of the
    first case and the second of the second raised StageSolveError when Newton started
    from the last slip velocities (RollingBody._creep_start, _no_slip)."""
    lat = Lateral(vy_ratio=None, spin_ratio=None)
    cases = [  # (body eta, Vx0, step, loads, previous slips (vx, Vy, Omega_z))
        (1.0, 5.0, 6.8e-5, Loads(-298.33, -126.33, 0.226, 0.0128),
         [(0.0, 0.0, 0.0), (0.005, 0.03, 0.0), (0.005, 0.05, 1.5), (-0.001, -0.01, -0.5)]),
        (math.inf, 4.59658177, 0.0264938, Loads(-185.37, 50.22, 0.173, -0.0317),
         [(0.0, 0.0, 0.0), (-1.84e-4, 1.096e-2, 0.894)]),
    ]  # fmt: skip
    for eta, V, h, L, slips in cases:
        body = Body.from_eta(1.0, 0.05, eta, Iz=2e-3)
        ends = []
        for vx, Vy, Oz in slips:
            rb = RollingBody(C, body, lat, "quasistationary", Vx0=V, Omega_y0=(V - vx) / 0.05,
                             Vy0=Vy, Omega_z0=Oz)  # fmt: skip
            if not native:
                rb._kernel = None
            rb.advance(h, L, 1)
            ends.append(rb.y.copy())
            assert rb.out.Ty == pytest.approx(L.Fy_ex, rel=1e-12)  # Eq. (29)
            assert rb.out.Mz == pytest.approx(L.Mz_ex, rel=1e-12)  # Eq. (30), QS
        v = C.creep_full_slip * abs(ends[0][0])
        for y in ends[1:]:
            assert y[0] == ends[0][0]  # Eq. (28): Vx does not depend on the slip
            for k, unit in ((1, v), (2, v), (3, v / C.a1)):
                assert abs(y[k] - ends[0][k]) <= 1e-12 * (abs(ends[0][k]) + unit)


def test_long_lobatto_step_that_reverses_vx_converges(monkeypatch):
    """The full method with Vy and Omega_z as unknowns over one long step (4.6 ms) in
    which the drive takes Vx from 1e-3 m/s through zero to -0.62 m/s: the Lobatto IIIC
    stage system is solvable (its stiff limit is the quasistationary state), but Newton
    from the last slip velocities, hundreds of times too small for the new speed, found
    no solution (StageSolveError after scipy's hybr; this and one more of 216 random
    steps of tests/test_native.py). Now the stage is solved from the further starts
    (RollingBody._creep_start, _no_slip): the step completes with finite outputs,
    |T| <= mu P and non-negative friction power on the rigid slip (Tx vx + Ty vy + Mz
    Omega_z), and the first start still fails (so the further ones were needed)."""
    import contact_fmu.dynamics.integrator as integrator

    failed = []
    newton = integrator.newton

    def counted(*args, **kw):
        try:
            return newton(*args, **kw)
        except StageSolveError:
            failed.append(1)
            raise

    monkeypatch.setattr(integrator, "newton", counted)
    lat = Lateral(vy_ratio=None, spin_ratio=None)
    cases = [(1.0, 0.004625494463879148, Loads(-268.736, -97.556, -0.00536, 0.0543))]
    for eta, h, L in cases:  # (eta, step, loads)
        body = Body.from_eta(1.0, 0.05, eta, Iz=2e-3)
        rb = RollingBody(C, body, lat, Vx0=1e-3, Omega_y0=1e-3 / 0.05 * 0.999, Vy0=1e-5,
                         Omega_z0=3e-4)  # fmt: skip
        rb._kernel = None  # the compiled step leaves a failed stage solve to this path
        n = len(failed)
        rb.advance(h, L, 1)
        assert len(failed) > n
        o = rb.out
        assert all(math.isfinite(v) for v in (*rb.y, o.Tx, o.Ty, o.Mz))
        # Eq. (8): Vx moves with the drive A1 (Fx_ex + My_ex/Rx), hundreds of times its start
        assert abs(rb.y[0]) > 0.5 and np.sign(rb.y[0]) == np.sign(L.Fx_ex + L.My_ex / 0.05)
        assert math.hypot(o.Tx, o.Ty) <= MU_P * (1 + 16 * np.finfo(float).eps)
        power = o.Tx * rb.y[1] + o.Ty * rb.y[2] + o.Mz * rb.y[3]
        assert power >= -1e-11 * MU_P * C.creep_full_slip * abs(rb.y[0])


# ---- state handling ---------------------------------------------------------------------------
@pytest.mark.parametrize("dynamic", [False, True])
def test_snapshot_and_restore_are_exact(dynamic):
    """Also with Eqs. (10)-(11) integrated, whose stage solves keep their Newton matrix
    from step to step (RollingBody._jac, part of the snapshot)."""
    lat = Lateral(vy_ratio=None, spin_ratio=None) if dynamic else Lateral()
    b = Body(ex.M, ex.Rx, ex.M * ex.Rx**2 / 3, Iz=0.4 * ex.M * ex.Rx**2)
    rb = RollingBody(C, b, lat, Vx0=V0, Omega_y0=V0 / ex.Rx)
    rb.advance(TC / 10, Loads(Fx_ex=F, Fy_ex=0.2 * F), 3)  # the substeps that follow
    snap = rb.snapshot()
    later = Loads(Fx_ex=F, Fy_ex=-0.2 * F, My_ex=0.1 * F * ex.Rx)
    rb.advance(TC / 10, later, 3)
    first = rb.outputs()
    rb.restore(snap)
    rb.advance(TC / 10, later, 3)
    assert rb.outputs() == first


@pytest.mark.parametrize("name", ["Fx_ex", "My_ex"])
def test_bad_loads_name_the_variable_and_leave_the_state_unchanged(name):
    rb = RollingBody(C, ex.body(3.0), Vx0=V0, Omega_y0=V0 / ex.Rx)
    before = rb.outputs()
    with pytest.raises(InputError) as err:
        rb.advance(TC / 10, Loads(**{name: math.nan}))
    assert err.value.name == name
    assert rb.outputs() == before and rb.t == 0.0
    with pytest.raises(InputError, match="h = -1"):
        rb.advance(-1.0, Loads())
