"""Kalker's creep coefficients of the linear theory: HalfSpaceContact.
creep_coefficients against the small-creepage slopes of full solves on the same grid
and against Kalker's published table.

Reference: Kalker (1990), Three-Dimensional Elastic Bodies in Rolling Contact, Table E3
(also Kalker 1967; Johnson 1985, Table 8.1), as tabulated in CONTACT's m_hertz.f90
(subroutine linrol); the rows a/b = 0.5, 1, 2 are those of references.md.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from contact_fmu.halfspace.contact import HalfSpaceContact
from contact_fmu.halfspace.hertz import Material
from contact_fmu.halfspace.railway import wheel_on_rail

# Kalker (1990), Table E3 (published data, kept once beside the validation page's script)
from contact_fmu.halfspace.validation import KALKER_E3, NUS

# Elements of the contact's bounding box: about 64 x 64 in all, square elements.
ELEMENTS = 64
# Measured errors against the table on these grids: at most 1.96 % (C22, a/b = 0.2,
# nu = 0.5), 1.65 % (C11, a/b = 0.5, nu = 0.5) elsewhere; on grids of 128 x 128 elements
# at most 1.04 %: the grid's part is below 0.8 % here, the rest is the table's three
# digits and Kalker's own truncation (it stays where the grid is refined). 2 %
# covers the 64 x 64 grid's measured error and nothing more.
KALKER_RTOL = 0.02


def contact(aob: float, nu: float, elements: int = ELEMENTS) -> HalfSpaceContact:
    """Hertz contact with c = 1 and a/b = aob on square elements, identical materials."""
    a1, a2 = math.sqrt(aob), 1.0 / math.sqrt(aob)
    n = (max(round(elements * math.sqrt(aob)), 10), max(round(elements / math.sqrt(aob)), 10))
    # dimensionless (G = 1, c = 1): no unit checks
    m = Material(2.0 * (1.0 + nu), nu, check_units=False)  # G = 1
    return HalfSpaceContact.from_ellipse(a1, a2, m, m, 0.3, P=1.0, n=n, check_units=False)


def test_c23_is_the_slope_of_full_solves_at_nu_0_28():
    """A bug once found: C23 loaded only the lateral part x phi of the spin's rigid
    slip and came out 4.4 % low at nu = 0.28. The coefficients now equal the slopes of
    full (Coulomb) solves at a creepage small enough for full adhesion (1e-6 of
    mu P/(G c^2)) on the same grid, to 1e-5 (Newton to 1e-12 of mu p, GMRES to 1e-10), and the
    spin moment from eta gives -C23 (reciprocity of the symmetric influence operator)."""
    c = wheel_on_rail(n=32)
    assert c.elastic.nu == pytest.approx(0.28)
    G, cc = c.elastic.G, c.c
    k = c.creep_coefficients()
    s = 1e-6 * c.mu * c.P / (G * cc * cc)
    zero = np.zeros((2, *c.patch.grid.shape))
    # Newton's tolerance is relative to mu p, and the tractions are 1e-6 of it here
    tol = 1e-12
    xi, eta = c.solve(s, tau0=zero, tol=tol), c.solve(0.0, s, tau0=zero, tol=tol)
    phi = c.solve(0.0, 0.0, s / cc, tau0=zero, tol=tol, check_units=False)
    assert min(xi.adhesion_fraction, eta.adhesion_fraction, phi.adhesion_fraction) == 1.0
    assert xi.Tx / (G * cc**2 * s) == pytest.approx(k.C11, rel=1e-5)
    assert eta.Ty / (G * cc**2 * s) == pytest.approx(k.C22, rel=1e-5)
    assert phi.Ty / (G * cc**2 * s) == pytest.approx(k.C23, rel=1e-5)
    assert phi.Mz / (G * cc**3 * s) == pytest.approx(k.C33, rel=1e-5)
    assert eta.Mz / (G * cc**3 * s) == pytest.approx(-k.C23, rel=1e-5)
    assert c.linear_coefficients() == (k.C11, k.C22, k.C23)
    # the lateral part alone is what the bug returned: 2.4 % below for this ellipse
    # (a/b = 1.3; 4.4 % at a/b = 1), where the slopes above agree to 1e-5
    patch = c.patch
    X, _ = patch.grid.mesh()
    W = np.zeros((2, *patch.grid.shape))
    W[1] = np.where(patch.contact, X * patch.grid.dx, 0.0)
    lateral = float(patch.solve_adhesion(W)[0][1].sum() * patch.grid.area) / (G * cc**3)
    assert lateral < 0.98 * k.C23


@pytest.mark.parametrize("aob", sorted(KALKER_E3))
def test_kalker_table_e3(aob):
    """C11, C22, C23 against Kalker's Table E3 for nu = 0, 0.25, 0.5 (tolerance:
    KALKER_RTOL, from the measured errors of the grid)."""
    for j, nu in enumerate(NUS):
        k = contact(aob, nu).creep_coefficients()
        ref = [KALKER_E3[aob][i][j] for i in range(3)]
        assert k.C11 == pytest.approx(ref[0], rel=KALKER_RTOL), ("C11", nu)
        assert k.C22 == pytest.approx(ref[1], rel=KALKER_RTOL), ("C22", nu)
        assert k.C23 == pytest.approx(ref[2], rel=KALKER_RTOL), ("C23", nu)


def test_small_a_over_b_limits():
    """Kalker's asymptotes for a/b -> 0 (references.md): C11 -> pi^2/(4 (1 - nu)),
    C22 -> pi^2/4. At a/b = 0.2 the table itself is still 5-8 % above them (2.59 vs
    2.47), so this checks the trend: C22 falls toward pi^2/4 as a/b falls and stays
    above it, C11 (1 - nu) likewise for every nu."""
    for nu in (0.0, 0.25):
        hi, lo = contact(0.5, nu).creep_coefficients(), contact(0.2, nu).creep_coefficients()
        for a, b in ((hi.C22, lo.C22), (hi.C11 * (1 - nu), lo.C11 * (1 - nu))):
            assert a > b > math.pi**2 / 4
