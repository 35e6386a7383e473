"""Thin-layer contact law (Section 4): normal contact, resultant, field, invariants.

References are independent of the code under test: numerical quadrature (scipy) of
the traction written out here from Eqs. (33)-(37), and the invariants of
references.md.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate
from scipy.optimize import brentq

from contact_fmu import InputError, LayerContact
from contact_fmu import examples as ex
from contact_fmu.laws.thin_layer import force_fraction, moment_fraction

C = ex.contact()
MU_P = C.mu * C.P
VX = 5.0  # rolling speed (m/s) of the point checks
# creepages |v|/Vx spanning partial slip (creep_full_slip ~ 0.01) and full slip
CREEPS = (1e-6, 1e-3, 4e-3, 8e-3, 0.0099, 0.02)


def tau_magnitude(c: LayerContact, x: float, y: float, speed: float, Vx: float) -> float:
    """|tau| of Eq. (36), written independently: the adhesion line capped by mu p.

    In adhesion |tau| = (l(y) - x)|v|/(Vx k) grows from the leading edge; behind the
    point where it reaches mu p the strip slips with |tau| = mu p (Eqs. 4-5, 35).
    """
    ell = c.a1 * math.sqrt(max(1.0 - (y / c.a2) ** 2, 0.0))
    p = c.p0 * max(1.0 - (x / c.a1) ** 2 - (y / c.a2) ** 2, 0.0)
    return min((ell - x) * speed / (Vx * c.k), c.mu * p)


def integrate_over_ellipse(c: LayerContact, f, x_break=None, epsabs: float = 0.0) -> float:
    """int f(x, y) dA over the contact ellipse: quad along x inside quad along y.

    ``x_break(y)`` is a breakpoint hint for the inner quadrature (the kink of the
    integrand at the slip boundary); it steers accuracy only, not the integrand.
    """

    def strip(y: float) -> float:
        ell = c.a1 * math.sqrt(max(1 - (y / c.a2) ** 2, 0))
        pts = None
        if x_break is not None and -ell < x_break(y, ell) < ell:
            pts = [x_break(y, ell)]
        return integrate.quad(
            lambda x: f(x, y), -ell, ell, points=pts, epsabs=epsabs / c.a2, epsrel=1e-13
        )[0]

    return integrate.quad(strip, -c.a2, c.a2, epsabs=epsabs, epsrel=1e-12, limit=200)[0]


def slip_break(c: LayerContact, speed: float, Vx: float):
    """Where the adhesion line meets mu p on a strip (a quadrature hint)."""
    alpha = float(c.beta(speed, 0.0, Vx)) * c.a1
    return lambda y, ell: alpha - ell


# ---- normal contact, Eqs. (32)-(34) --------------------------------------------------
def test_normal_load_equals_integral_of_pressure():
    # invariant: P = int p dA; quadrature to 1e-10, so 1e-9 is the bound
    P_num = integrate_over_ellipse(C, lambda x, y: float(C.pressure(x, y)))
    assert P_num == pytest.approx(C.P, rel=1e-9)


@pytest.mark.parametrize("P", [1.0, 1e3, 1e6])
def test_winkler_layers_fill_the_gap(P):
    # Eq. (32): (k1 + k2) p = delta - x^2/(2 Rx) - y^2/(2 Ry) inside the ellipse, and the
    # gap closes exactly on its boundary: a1^2/(2 Rx) = a2^2/(2 Ry) = delta
    c = C.with_load(P)
    rng = np.random.default_rng(1)
    x = rng.uniform(-0.7, 0.7, 50) * c.a1
    y = rng.uniform(-0.7, 0.7, 50) * c.a2
    inside = (x / c.a1) ** 2 + (y / c.a2) ** 2 < 1
    lhs = (c.k1 + c.k2) * c.pressure(x, y)[inside]
    rhs = (c.delta - x**2 / (2 * c.Rx) - y**2 / (2 * c.Ry))[inside]
    np.testing.assert_allclose(lhs, rhs, rtol=1e-12, atol=1e-14 * c.delta)
    assert c.a1**2 / (2 * c.Rx) == pytest.approx(c.delta, rel=1e-14)
    assert c.a2**2 / (2 * c.Ry) == pytest.approx(c.delta, rel=1e-14)


# ---- resultant, Eqs. (40)-(43) ---------------------------------------------------------
@pytest.mark.parametrize("creep", CREEPS)
def test_resultant_equals_integral_of_traction(creep):
    # Eqs. (40)-(41) against the quadrature of Eq. (36)
    speed = creep * VX
    T_num = integrate_over_ellipse(
        C, lambda x, y: tau_magnitude(C, x, y, speed, VX), slip_break(C, speed, VX)
    )
    Tx, Ty = C.force(speed, 0.0, VX)
    # nested quad at rel 1e-12..1e-13 with the kink as a breakpoint
    assert float(Tx) == pytest.approx(T_num, rel=1e-11)
    assert float(Ty) == 0.0


def test_printed_eq42_is_half_the_integral():
    # Departure from the printed paper (docs/model.md): Eq. (40) with Eq. (42) as
    # printed gives half the integral of Eq. (36) for every beta, e.g. mu P/2 at full
    # slip. The printed H is evaluated here as printed.
    for beta in (0.3, 1.0, 1.7, 2.0):
        m = math.sqrt(1 - 0.25 * beta**2)
        H_printed = (
            math.pi / 4 + beta * m / 12 * (13 + 0.5 * beta**2) - 0.5 * (1 + beta**2) * math.asin(m)
        )
        T_printed = C.mu * C.p0 * C.a1 * C.a2 * H_printed
        speed = beta * C.creep_full_slip / 2 * VX
        assert float(C.force(speed, 0.0, VX)[0]) == pytest.approx(2 * T_printed, rel=1e-12)


@pytest.mark.parametrize("direction", [0.0, 0.7, 2.0, math.pi])
def test_full_slip_force_is_mu_P_against_the_slip(direction):
    # references.md: full slip |T| = mu P exactly, along v (the body receives -T)
    speed = 3 * C.creep_full_slip * VX
    vx, vy = speed * math.cos(direction), speed * math.sin(direction)
    Tx, Ty = C.force(vx, vy, VX)
    assert math.hypot(Tx, Ty) == pytest.approx(MU_P, rel=1e-14)
    assert Tx * vx + Ty * vy == pytest.approx(MU_P * speed, rel=1e-14)


def test_sliding_without_rolling_is_coulomb():
    # Vx = 0: no leading edge, every point slides: |T| = mu P for any |v| > 0
    for vx in (1e-12, 1e-3, 10.0):
        assert float(C.force(vx, 0.0, 0.0)[0]) == pytest.approx(MU_P, rel=1e-14)
    assert C.force(0.0, 0.0, 0.0) == (0.0, 0.0)


def test_pure_rolling_transmits_no_force():
    assert C.force(0.0, 0.0, VX) == (0.0, 0.0)


@pytest.mark.parametrize("mu", [0.05, 0.3, 1.0])
def test_small_creep_slope_follows_from_adhesion_alone(mu):
    # references.md: dT/d(v/Vx) at zero creep from the adhesion solution alone (no mu):
    # int (l(y) - x) dA / k = (8/3) a1^2 a2 / (kb + ks). The O(beta) correction is
    # -(3 pi / 16) beta relative, so at creep 1e-9 of full slip the bound is 1e-8.
    c = LayerContact(C.P, C.Rx, C.Ry, C.k1, C.k2, C.kb, C.ks, mu)
    creep = 1e-9 * c.creep_full_slip
    slope = float(c.force(creep * VX, 0.0, VX)[0]) / creep
    assert slope == pytest.approx(8 * c.a1**2 * c.a2 / (3 * c.k), rel=1e-8)


def test_force_is_continuous_and_C1_at_the_onset_of_full_slip():
    # references.md: C1 at beta = 2 for the thin layers: h(2) = 1 and h'(2-) = 0.
    # Here 1 - h ~ 0.1 (2 - beta)^3.5, so the one-sided slope over d = 1e-2 is ~1e-6.
    assert float(force_fraction(2.0)) == 1.0
    d = 1e-2
    slope_left = (1.0 - float(force_fraction(2.0 - d))) / d
    assert 0.0 <= slope_left < 2e-6
    # and the approach is monotone: no overshoot of mu P anywhere
    beta = np.linspace(0, 3, 30001)
    h = force_fraction(beta)
    assert np.all(np.diff(h) >= 0) and h.max() <= 1.0


def test_lateral_over_longitudinal_force_equals_slip_ratio():
    # Eqs. (36)-(37): tau_y = (vy/vx) tau_x everywhere, so Ty/Tx = vy/vx
    for vy_ratio in (0.002, 0.006, 1.0, -3.0):
        vx = 0.004 * VX
        Tx, Ty = C.force(vx, vy_ratio * vx, VX)
        assert Ty / Tx == pytest.approx(vy_ratio, rel=1e-14)


def test_lateral_slip_alone_gives_a_lateral_force():
    # vx = 0, vy != 0: the same law turned by 90 degrees
    Tx, Ty = C.force(0.0, 0.004 * VX, VX)
    assert float(Tx) == 0.0
    assert float(Ty) == pytest.approx(float(C.force(0.004 * VX, 0.0, VX)[0]), rel=1e-14)


def test_reversing_the_slip_reverses_the_force_and_mirror_symmetry():
    rng = np.random.default_rng(2)
    vx, vy = rng.normal(size=(2, 200)) * 0.01 * VX
    Vx = rng.uniform(0.1, 10, 200)
    Tx, Ty, Mz = C.forces(vx, vy, 0.0, Vx)
    Tx2, Ty2, Mz2 = C.forces(-vx, -vy, 0.0, Vx)
    np.testing.assert_array_equal(Tx2, -Tx)
    np.testing.assert_array_equal(Ty2, -Ty)
    np.testing.assert_array_equal(Mz2, -Mz)
    # mirror y -> -y: Ty and Mz change sign, Tx does not
    Tx3, Ty3, Mz3 = C.forces(vx, -vy, 0.0, Vx)
    np.testing.assert_array_equal(Tx3, Tx)
    np.testing.assert_array_equal(Ty3, -Ty)
    np.testing.assert_array_equal(Mz3, -Mz)
    # rolling backwards mirrors x -> -x: the same force, the moment changes sign
    Tx4, Ty4, Mz4 = C.forces(vx, vy, 0.0, -Vx)
    np.testing.assert_array_equal(Tx4, Tx)
    np.testing.assert_array_equal(Mz4, -Mz)


def test_friction_power_is_never_negative():
    # references.md: the friction force does negative work on the relative motion
    rng = np.random.default_rng(3)
    vx, vy = rng.normal(size=(2, 1000)) * 10.0 ** rng.uniform(-8, 0, (2, 1000))
    Vx = rng.uniform(-20, 20, 1000)
    Tx, Ty = C.force(vx, vy, Vx)
    assert np.all(Tx * vx + Ty * vy >= 0.0)
    # |T| <= mu P to rounding: T = mu P h v/|v| with h <= 1
    assert np.all(np.hypot(Tx, Ty) <= MU_P * (1 + 4 * np.finfo(float).eps))


def test_analytic_slope_matches_the_force_law():
    # tx_slope (the integrator's Newton derivative) against central differences of
    # force(); the difference error is ~1e-8 of the slope scale mu P/(creep_full Vx)
    rng = np.random.default_rng(5)
    for _ in range(300):
        vx, vy = rng.normal(size=2) * 10.0 ** rng.uniform(-5, -1)
        Vx = float(rng.choice([-1, 1]) * 10.0 ** rng.uniform(-1, 1.3))
        T, d_vx, d_vy, d_V = C.tx_slope(float(vx), float(vy), Vx)
        assert T == pytest.approx(float(C.force(vx, vy, Vx)[0]), rel=1e-13, abs=1e-13 * MU_P)
        scale = MU_P / (C.creep_full_slip * abs(Vx))
        for i, d in enumerate((d_vx, d_vy, d_V)):
            args = np.array([vx, vy, Vx])
            e = 1e-6 * max(abs(args[i]), 1e-3 * C.creep_full_slip * abs(Vx))
            up, down = args.copy(), args.copy()
            up[i] += e
            down[i] -= e
            fd = (float(C.force(*up)[0]) - float(C.force(*down)[0])) / (2 * e)
            assert d == pytest.approx(fd, abs=1e-5 * scale)


def test_scalar_and_vector_paths_agree():
    # the integrator's float path and the numpy path implement the same formulas
    rng = np.random.default_rng(4)
    for _ in range(200):
        vx, vy = rng.normal(size=2) * 10.0 ** rng.uniform(-6, 0)
        Vx = float(rng.choice([-1, 1]) * 10.0 ** rng.uniform(-3, 2))
        scalar = C.forces(float(vx), float(vy), 0.0, Vx)
        vector = C.forces(np.array([vx]), np.array([vy]), 0.0, np.array([Vx]))
        for s, v in zip(scalar, vector, strict=True):
            assert s == pytest.approx(float(v[0]), rel=1e-13, abs=1e-13 * MU_P)
        af = C.adhesion_fraction(float(vx), float(vy), Vx)
        assert af == pytest.approx(float(C.adhesion_fraction(vx, vy, np.array(Vx))), abs=1e-14)


@pytest.mark.parametrize("creep", [1e-3, 4e-3, 0.0099])
def test_aligning_moment_equals_integral_of_x_tau_y(creep):
    # Mz = int (x tau_y - y tau_x) dA; the y tau_x part vanishes by symmetry. Closed form
    # mu P a1 g(beta) (docs/model.md) against quadrature of x |tau| along y.
    speed = creep * VX
    M_num = integrate_over_ellipse(
        C,
        lambda x, y: x * tau_magnitude(C, x, y, speed, VX),
        slip_break(C, speed, VX),
        epsabs=1e-14 * MU_P * C.a1,  # the integrand changes sign: an absolute floor
    )
    _, _, Mz = C.forces(0.0, speed, 0.0, VX)
    # near full slip Mz -> 0 (g ~ (2 - beta)^3.5): relative 1e-9, absolute 1e-12 mu P a1
    assert float(Mz) == pytest.approx(M_num, rel=1e-9, abs=1e-12 * MU_P * C.a1)
    assert float(Mz) < 0  # traction centred behind the contact centre
    beta = float(C.beta(0.0, speed, VX))
    assert float(moment_fraction(beta)) == pytest.approx(M_num / (MU_P * C.a1), rel=1e-9, abs=1e-12)


@pytest.mark.parametrize("creep", [1e-3, 5e-3, 0.009])
def test_adhesion_fraction_equals_area_of_adhesion(creep):
    # adhesion on a strip from the leading edge l(y) back to where the adhesion line
    # (l - x)|v|/(Vx k) meets mu p; its length integrated over y, over pi a1 a2
    speed = creep * VX
    g = speed / (VX * C.k)

    def adhesion_length(y: float) -> float:
        ell = C.a1 * math.sqrt(max(1 - (y / C.a2) ** 2, 0))
        if ell == 0.0:
            return 0.0
        # mu p on the strip, mu p0 (l^2 - x^2)/a1^2, against the adhesion line (l - x) g
        gap = lambda x: (ell - x) * g - C.mu * C.p0 * (ell**2 - x**2) / C.a1**2  # noqa: E731
        front = ell * (1 - 1e-9)
        if gap(front) >= 0.0:  # the line is above mu p right at the leading edge: full slip
            return 0.0
        # gap(-l) = 2 l g > 0 at the rear; the root is the adhesion/slip boundary
        return ell - brentq(gap, -ell, front, xtol=1e-15 * C.a1, rtol=1e-15)

    area = integrate.quad(adhesion_length, -C.a2, C.a2, epsabs=0, epsrel=1e-10, limit=200)[0]
    expected = float(C.adhesion_fraction(speed, 0.0, VX))
    assert area / (math.pi * C.a1 * C.a2) == pytest.approx(expected, rel=1e-8)


# ---- traction field, Figs. 6-11 ---------------------------------------------------------
def test_traction_field_is_exact_at_the_nodes_without_spin():
    speed = 0.004 * VX
    f = C.traction(0.8 * speed, 0.6 * speed, VX, 61, 41)
    X, Y = np.meshgrid(f.x, f.y)
    expected = np.vectorize(lambda x, y: tau_magnitude(C, x, y, speed, VX))(X, Y)
    expected = np.where(f.inside, expected, 0.0)
    np.testing.assert_allclose(np.hypot(f.tau_x, f.tau_y), expected, rtol=1e-12, atol=1e-9 * C.p0)
    np.testing.assert_allclose(f.tau_y[f.inside], 0.75 * f.tau_x[f.inside], rtol=1e-12)
    assert np.all(np.hypot(f.tau_x, f.tau_y) <= C.mu * f.p * (1 + 4 * np.finfo(float).eps))


def test_slip_mask_matches_the_adhesion_boundary_of_eq_38():
    # Eq. (38): l_a(y) = alpha - l(y), the slip area lies behind it
    speed = 0.005 * VX
    f = C.traction(speed, 0.0, VX, 201, 51)
    X = np.broadcast_to(f.x, f.slip.shape)
    dx = f.x[1] - f.x[0]
    behind = X < f.la[:, None] - dx
    ahead = X > f.la[:, None] + dx
    assert np.all(f.slip[behind & f.inside])
    assert not np.any(f.slip[ahead & f.inside])


def test_grid_resultant_converges_to_the_closed_form():
    speed = 0.004 * VX
    T = float(C.force(speed, 0.0, VX)[0])
    errs = [abs(C.traction(speed, 0.0, VX, n, n).resultant()[0] / T - 1) for n in (40, 80, 160)]
    # trapezoid in x with exact edges, midpoint in y: at least first order observed
    assert errs[2] < errs[1] < errs[0] < 1e-2
    assert math.log2(errs[0] / errs[1]) > 1.0 and math.log2(errs[1] / errs[2]) > 1.0


# ---- spin (Eq. 3 with Omega_z) ---------------------------------------------------------
def test_spin_force_is_continuous_bounded_and_odd():
    base = np.array([float(t) for t in C.forces(0.004 * VX, 0.001 * VX, 0.0, VX)])
    tiny = np.array([float(t) for t in C.forces(0.004 * VX, 0.001 * VX, 1e-9, VX)])
    np.testing.assert_allclose(tiny, base, rtol=1e-6, atol=1e-9 * MU_P * C.a1)
    for phi in (1.0, 30.0, 1e3):
        Tx, Ty, Mz = (float(t) for t in C.forces(0.004 * VX, 0.001 * VX, phi, VX))
        Tx2, Ty2, Mz2 = (float(t) for t in C.forces(-0.004 * VX, -0.001 * VX, -phi, VX))
        assert math.hypot(Tx, Ty) <= MU_P * (1 + 1e-12)
        assert (Tx2, Ty2, Mz2) == pytest.approx((-Tx, -Ty, -Mz), rel=1e-12, abs=1e-12)


def test_pure_spin_at_standstill_gives_the_coulomb_moment():
    # Vx = 0, v = 0, Omega_z != 0: tau = mu p e_theta, Mz = int mu p r dA; for a circle
    # (Rx = Ry) and the parabolic pressure of Eq. (33) that is (8/15) mu P a.
    # Grid quadrature (201^2 cells) of a field with a kink at the centre: 1 %.
    c = LayerContact(C.P, 0.05, 0.05, C.k1, C.k2, C.kb, C.ks, C.mu)
    _, _, Mz = c.traction(0.0, 0.0, 0.0, 201, 201, phi=2.0).resultant()
    assert Mz == pytest.approx(8 / 15 * c.mu * c.P * c.a1, rel=1e-2)


def test_inverse_creep_law_of_eq28():
    # T_x^{-1}: the creepage whose force is the given Tx, with and without lateral creep
    for xi_y in (0.0, 0.002, 0.006):
        for frac in (-0.9, -0.3, 1e-6, 0.5, 0.99):
            Tx = frac * MU_P
            xi = C.inverse_creep(Tx, xi_y)
            assert float(C.force(xi * VX, xi_y * VX, VX)[0]) == pytest.approx(Tx, rel=1e-12)
    with pytest.raises(InputError, match="Tx"):
        C.inverse_creep(1.01 * MU_P)


def test_adhesion_fraction_with_spin_is_continuous_symmetric_and_vanishes():
    # at phi -> 0 the grid's area tends to the closed form (first order in the 64-cell
    # grid: 2 %); phi -> -phi mirrors y -> -y for a longitudinal slip, so the area is
    # even in phi; a spin slip far beyond the longitudinal one leaves adhesion only
    # near the spin pole (a few % of the contact)
    speed = 0.004 * VX
    closed = float(C.adhesion_fraction(speed, 0.0, VX))
    assert C.adhesion_fraction(speed, 0.0, VX, phi=1e-9) == pytest.approx(closed, abs=2e-2)
    for phi in (3.0, 30.0):
        plus = C.adhesion_fraction(speed, 0.0, VX, phi=phi)
        assert C.adhesion_fraction(speed, 0.0, VX, phi=-phi) == pytest.approx(plus, abs=1e-12)
    assert C.adhesion_fraction(speed, 0.0, VX, phi=1e3) < 0.05


# ---- bad input --------------------------------------------------------------------------
@pytest.mark.parametrize(
    "name,value",
    [("P", -5e-324), ("P", -1.0), ("mu", 0.0), ("Rx", math.nan), ("k1", -1e-12), ("ks", math.inf)],
)
def test_bad_parameters_name_the_variable(name, value):
    kw = dict(P=C.P, Rx=C.Rx, Ry=C.Ry, k1=C.k1, k2=C.k2, kb=C.kb, ks=C.ks, mu=C.mu)
    kw[name] = value
    with pytest.raises(InputError) as err:
        LayerContact(**kw)
    assert err.value.name == name and name in str(err.value)


def test_zero_layer_compliance_is_rejected():
    with pytest.raises(InputError, match="kb \\+ ks"):
        LayerContact(C.P, C.Rx, C.Ry, C.k1, C.k2, 0.0, 0.0, C.mu)
