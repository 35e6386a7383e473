"""CONTACT's conventions: the mapping of contact_fmu.halfspace.conventions
reproduces Kalker's linear theory written in CONTACT's units and signs (references.md:
Fx = -G c^2 C11 xi, Fy = -G c^2 (C22 eta + c C23 phi), force on body 1, mm and N,
spin in rad/mm)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from contact_fmu.halfspace import conventions as cv
from contact_fmu.halfspace.railway import wheel_on_rail


def test_linear_theory_in_contact_units():
    c = wheel_on_rail(n=24)
    k = c.creep_coefficients()
    G_mm, c_mm = cv.modulus_to_contact(c.elastic.G), cv.length_to_contact(c.c)
    s = 1e-6 * c.mu * c.P / (c.elastic.G * c.c**2)
    zero = np.zeros((2, *c.patch.grid.shape))
    for xi, eta, phi in ((s, 0.0, 0.0), (0.0, s, 0.0), (0.0, 0.0, s / c.c)):
        # the linear theory's tiny spin (phi c = 1e-8) is meant: no unit warning
        sol = c.solve(xi, eta, phi, tau0=zero, tol=1e-12, check_units=False)
        cksi, ceta, cphi = cv.creepages_to_contact(xi, eta, phi)
        Fx, Fy, Mz = cv.forces_to_contact(sol.Tx, sol.Ty, sol.Mz)
        scale = G_mm * c_mm**2 * s
        assert Fx == pytest.approx(-G_mm * c_mm**2 * k.C11 * cksi, abs=1e-5 * scale)
        assert Fy == pytest.approx(
            -G_mm * c_mm**2 * (k.C22 * ceta + c_mm * k.C23 * cphi), abs=1e-5 * scale
        )
        # Kalker: Mz = -G c^3 (-C23 eta + c C33 phi) on body 1, N mm
        assert Mz == pytest.approx(
            -G_mm * c_mm**3 * (-k.C23 * ceta + c_mm * k.C33 * cphi), abs=1e-5 * scale * c_mm
        )


def test_round_trips():
    a = (0.3e-3, -1.2e-3, 0.7)
    assert cv.creepages_from_contact(*cv.creepages_to_contact(*a)) == pytest.approx(a)
    f = (1.5e3, -2.0e3, 4.0)
    assert cv.forces_from_contact(*cv.forces_to_contact(*f)) == pytest.approx(f)
    assert cv.creepages_to_contact(0.0, 0.0, 1.0)[2] == 1e-3  # 1 rad/m = 1e-3 rad/mm
    assert math.isclose(cv.forces_to_contact(0.0, 0.0, 1.0)[2], -1e3)  # N m -> N mm
