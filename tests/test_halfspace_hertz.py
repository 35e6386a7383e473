"""Hertz contact of elastic half-spaces and the numerical normal problem.

References independent of the code under test: the closed-form circular Hertz
solution (Johnson 1985, Eqs. 4.22-4.23), the Boussinesq potential of the Hertz
pressure integrated numerically with scipy (it must make the gap vanish over the
ellipse, Johnson Sec. 4.2), and quadrature of the point-load kernels.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate

from contact_fmu import InputError
from contact_fmu.halfspace.hertz import CombinedElastic, Hertz, Material, relative_curvatures
from contact_fmu.halfspace.influence import Grid
from contact_fmu.halfspace.normal import solve_normal
from contact_fmu.halfspace.railway import wheel_on_rail

STEEL = Material(210e9, 0.28)
ESTAR_STEEL = CombinedElastic.of(STEEL, STEEL).Estar


def test_hertz_circle_closed_form():
    """Equal curvatures: a^3 = 3 P R/(4 E*), p0 = 3P/(2 pi a^2), delta = a^2/R (Johnson 4.22)."""
    R, P = 0.02, 500.0
    A, B = relative_curvatures(R, R, R, R)  # two spheres of radius R: R_rel = R/2
    h = Hertz(P, A, B, ESTAR_STEEL)
    Rrel = R / 2.0
    a = (3.0 * P * Rrel / (4.0 * ESTAR_STEEL)) ** (1.0 / 3.0)
    # exact formulas: only round-off separates them (1e-12 relative)
    assert h.a1 == pytest.approx(a, rel=1e-12)
    assert h.a2 == pytest.approx(a, rel=1e-12)
    assert h.p0 == pytest.approx(3.0 * P / (2.0 * math.pi * a * a), rel=1e-12)
    assert h.delta == pytest.approx(a * a / Rrel, rel=1e-12)


def _boussinesq_w(h: Hertz, x: float, y: float) -> float:
    """w(x, y) = 1/(pi E*) int p/r dA in polar coordinates about (x, y).

    The 1/r of the kernel cancels the Jacobian. Along a ray, 1 - x^2/a^2 - y^2/b^2 is a
    quadratic q (r1 - r)(r - r0) with roots r0 < 0 < r1, so the radial integral of p is
    p0 q^(1/2) (pi R^2/4 + (m/2)(R^2 - m^2)^(1/2) + (R^2/2) asin(m/R)) with
    m = (r0 + r1)/2, R = (r1 - r0)/2; the angle is integrated by adaptive quadrature.
    """

    def radial(theta: float) -> float:
        c, s = math.cos(theta), math.sin(theta)
        qa = (c / h.a1) ** 2 + (s / h.a2) ** 2
        qb = 2.0 * (x * c / h.a1**2 + y * s / h.a2**2)
        qc = (x / h.a1) ** 2 + (y / h.a2) ** 2 - 1.0
        disc = math.sqrt(qb * qb - 4.0 * qa * qc)
        r0, r1 = (-qb - disc) / (2.0 * qa), (-qb + disc) / (2.0 * qa)
        m, R = 0.5 * (r0 + r1), 0.5 * (r1 - r0)
        area = (
            math.pi * R * R / 4.0
            + 0.5 * m * math.sqrt(R * R - m * m)
            + 0.5 * R * R * math.asin(m / R)
        )
        return h.p0 * math.sqrt(qa) * area

    return integrate.quad(radial, 0.0, 2.0 * math.pi, epsrel=1e-13, limit=200)[0] / (
        math.pi * h.Estar
    )


@pytest.mark.parametrize("ratio", [1.0, 1.53, 4.0])
def test_hertz_ellipse_closes_the_gap(ratio):
    """Johnson Sec. 4.2: the Hertz pressure's Boussinesq displacement plus the gap
    A x^2 + B y^2 equals the approach delta everywhere in the ellipse."""
    h = Hertz(1e5, 1.0, ratio, ESTAR_STEEL)
    for fx, fy in ((0.0, 0.0), (0.5, 0.0), (0.0, -0.6), (0.3, 0.4), (-0.7, 0.2)):
        x, y = fx * h.a1, fy * h.a2
        closure = _boussinesq_w(h, x, y) + float(h.gap(x, y))
        # smooth periodic integrand: quadrature to ~1e-13; 1e-10 covers the elliptic integrals
        assert closure == pytest.approx(h.delta, rel=1e-10)
    assert 2.0 * math.pi * h.a1 * h.a2 * h.p0 / 3.0 == pytest.approx(1e5, rel=1e-12)


def test_railway_wheel_on_rail_is_hertzian():
    """The railway set: wheel R = 0.46 m on a rail head of 0.3 m; the ellipse is longer
    along the track (smaller curvature) and closes the gap (as above)."""
    c = wheel_on_rail()
    h = c.hertz
    assert h.A == pytest.approx(0.5 / 0.46, rel=1e-15)
    assert h.B == pytest.approx(0.5 / 0.30, rel=1e-15)
    assert c.a1 > c.a2
    closure = _boussinesq_w(h, 0.4 * h.a1, 0.3 * h.a2) + float(h.gap(0.4 * h.a1, 0.3 * h.a2))
    assert closure == pytest.approx(h.delta, rel=1e-10)
    # quasi-identical bodies: no normal-tangential coupling
    assert c.elastic.kappa == 0.0


def test_numerical_normal_problem_matches_hertz():
    """Polonsky-Keer CG on a 64 x 64 grid reproduces Hertz: load exact, peak pressure
    and approach within 0.3 % (the measured discretisation error on 64 x 64 is 3e-4
    and 5e-5; docs/halfspace.md)."""
    h = Hertz(1e5, 0.5 / 0.46, 0.5 / 0.30, ESTAR_STEEL)
    L1, L2 = 1.25 * h.a1, 1.25 * h.a2
    g = Grid(64, 64, 2 * L1 / 64, 2 * L2 / 64, -L1, -L2)
    X, Y = g.mesh()
    sol = solve_normal(g, h.gap(X, Y), h.P, h.Estar)
    assert sol.load == pytest.approx(h.P, rel=1e-12)
    assert sol.p.max() == pytest.approx(h.p0, rel=3e-3)
    assert sol.delta == pytest.approx(h.delta, rel=3e-3)
    # contact area within the elements cut by the ellipse (perimeter x element size)
    area = sol.contact.sum() * g.area
    assert area == pytest.approx(math.pi * h.a1 * h.a2, rel=0.05)


def test_combined_constants_of_dissimilar_materials():
    """Kalker's combined constants: 2/G = 1/G1 + 1/G2, nu/G = (nu1/G1 + nu2/G2)/2 and
    the difference parameter; identical materials give kappa = 0."""
    m1, m2 = Material(210e9, 0.3), Material(70e9, 0.33)
    e = CombinedElastic.of(m1, m2)
    assert 2.0 / e.G == pytest.approx(1 / m1.G + 1 / m2.G, rel=1e-14)
    assert e.nu / e.G == pytest.approx(0.5 * (m1.nu / m1.G + m2.nu / m2.G), rel=1e-14)
    assert e.kappa == pytest.approx(
        0.25 * e.G * ((1 - 2 * m2.nu) / m2.G - (1 - 2 * m1.nu) / m1.G), rel=1e-14
    )
    assert CombinedElastic.of(m1, m1).kappa == 0.0


def test_inputs_are_checked():
    with pytest.raises(InputError):
        Material(210e9, 0.7)
    with pytest.raises(InputError):
        relative_curvatures(0.5, math.inf, math.inf, math.inf)  # line contact: B = 0
    with pytest.raises(InputError):
        solve_normal(Grid(4, 4, 1.0, 1.0, 0.0, 0.0), np.zeros((3, 3)), 1.0, 1.0)
