"""Line contact: the public plane-strain call reproduces Carter (1926)."""

from __future__ import annotations

import math

import pytest

from contact_fmu.halfspace.hertz import Material
from contact_fmu.halfspace.line import LineContact


def test_carter_through_the_public_call():
    """Steel cylinders (R = 0.1 m, 1 MN/m, mu = 0.3): F = mu N (2 kappa - kappa^2)
    for kappa = R xi/(mu a) <= 1 within 1 % on 100 elements (first-order error, 0.36 %
    measured in tests/test_halfspace_rolling.py's Carter test of the same scheme); full
    slip beyond kappa = 1 gives mu N to 1e-12; odd in xi; a^2 = 4 N R/(pi E*)."""
    steel = Material(210e9, 0.3)
    lc = LineContact(1e6, 0.1, steel, steel, 0.3)
    Estar = 210e9 / (2 * (1 - 0.09))
    assert lc.a == pytest.approx(math.sqrt(4 * 1e6 * 0.1 / (math.pi * Estar)), rel=1e-12)
    xi1 = lc.mu * lc.a / lc.R  # kappa = 1
    for kappa in (0.1, 0.4, 0.8):
        s = lc.solve(kappa * xi1)
        assert s.Tx == pytest.approx(lc.carter(kappa * xi1), rel=0.01)
        assert lc.solve(-kappa * xi1).Tx == pytest.approx(-s.Tx, rel=1e-9)
    assert lc.solve(1.5 * xi1).Tx == pytest.approx(lc.mu * lc.N, rel=1e-12)
