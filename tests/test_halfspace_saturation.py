"""Creepages far into full slip, up to the largest double, rolling speeds down to the
smallest, and creepages down to the smallest: the half-space solvers answer the
full-slip forces, the sliding limit and the linear theory's, never NaN.

Beyond the onset of full slip every element slips along its slip S = W - K tau, and as
the rigid slip W grows the elastic term K tau (bounded by the traction bound) becomes
negligible: the tractions tend to g W/|W|, without spin |T| = mu P (the bound carries
sum g dA = mu P) along (xi, eta). The exact solver solves creepages whose rigid slip
exceeds rolling.SATURATION_RATIO = 1e20 times the elastic displacement of the bound at
that ratio (``rolling.creepage_scale``), FASTSIM and the transient field's step
(``transient.solve_coulomb``) likewise; before, the fixed-point variable tau + r S
overflowed from creepages of about 1e296 on: NaN tractions (steady) or zero ones
(transient). At the other end, creepages below rolling.ADHESION_RATIO of it leave every
element in adhesion, linear in the creepages: solved at that ratio and scaled back.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from contact_fmu.halfspace import Continuation, Fastsim, LineContact, wheel_on_rail
from contact_fmu.halfspace.railway import STEEL
from contact_fmu.halfspace.rolling import creepage_scale
from contact_fmu.halfspace.transient import HalfSpaceField

HUGE = (1e300, -1.7e308, 1.7976931348623157e308)


@pytest.fixture(scope="module")
def contact():
    return wheel_on_rail(n=16)


def _finite(sol) -> bool:
    return bool(
        np.all(np.isfinite(sol.tau))
        and np.all(np.isfinite(sol.S))
        and all(math.isfinite(v) for v in (sol.Tx, sol.Ty, sol.Mz))
    )


@pytest.mark.parametrize("value", HUGE)
def test_huge_creepages_give_mu_P_along_the_creepage(contact, value):
    """xi = eta = value (no spin), exact solver and FASTSIM: every contact element slips,
    tau and S are finite, |T| = mu P to 1e-12 and T along (xi, eta) (exact: the rigid
    slip; FASTSIM: (xi/L1, eta/L2), its slip direction) to 1e-12 of mu P."""
    muP = contact.mu * contact.P
    sign = math.copysign(1.0, value)
    exact = contact.solve(value, value)
    fast = contact.fastsim(value, value)
    L1, L2, _ = Fastsim.of(contact).flexibilities
    for sol, d in ((exact, (1.0, 1.0)), (fast, (1.0 / L1, 1.0 / L2))):
        assert _finite(sol)
        assert bool(np.all(sol.slip[sol.contact])) and sol.adhesion_fraction == 0.0
        assert math.hypot(sol.Tx, sol.Ty) == pytest.approx(muP, rel=1e-12)
        want = sign * muP * np.array(d) / math.hypot(*d)
        np.testing.assert_allclose([sol.Tx, sol.Ty], want, rtol=0.0, atol=1e-12 * muP)


@pytest.mark.parametrize("value", HUGE)
def test_a_huge_spin_gives_the_forces_of_the_largest_unscaled_spin(contact, value):
    """Spin phi = value: the same forces and moment (to 1e-12 of mu P and mu P c) as the
    spin at half the saturation ratio, which is solved as it is: beyond the ratio the
    solution does not depend on the creepages' size; the slip is the rigid slip's
    (S = phi (-y, x) dx to 1e-12 of its largest entry on the contact)."""
    muP = contact.mu * contact.P
    patch = contact.patch
    scale = creepage_scale(patch, 0.0, 0.0, value)
    assert scale < 1.0
    below = value * scale * 0.5
    assert creepage_scale(patch, 0.0, 0.0, below) == 1.0
    big, ref = contact.solve(0.0, 0.0, value), contact.solve(0.0, 0.0, below)
    assert _finite(big)
    np.testing.assert_allclose([big.Tx, big.Ty], [ref.Tx, ref.Ty], rtol=0.0, atol=1e-12 * muP)
    assert big.Mz == pytest.approx(ref.Mz, abs=1e-12 * muP * contact.c)
    X, Y = patch.grid.mesh()
    C = patch.contact
    rigid = np.stack([-Y, X]) * patch.grid.dx * value
    tol = 1e-12 * float(np.abs(rigid[:, C]).max())
    assert float(np.abs(big.S[:, C] - rigid[:, C]).max()) <= tol


@pytest.mark.parametrize("Vx", [5e-324, -5e-324, 1e-300])
def test_a_vanishing_rolling_speed_gives_the_sliding_forces(contact, Vx):
    """forces(vx, vy, phi, Vx) as Vx tends to 0 (creepages v/Vx up to beyond double
    range, where the division overflows): the forces of Vx = 0 (pure sliding, tau = g
    along the rigid slip velocity), to 1e-12 of mu P and mu P c, finite."""
    muP = contact.mu * contact.P
    v = (np.array([0.01, 1.7e308, 0.0]), np.array([0.003, 0.0, 0.0]), np.array([0.2, 1e308, 5.0]))
    got = np.array(contact.forces(*v, Vx))
    ref = np.array(contact.forces(*v, 0.0))
    assert np.all(np.isfinite(got))
    np.testing.assert_allclose(got[:2], ref[:2], rtol=0.0, atol=1e-12 * muP)
    np.testing.assert_allclose(got[2], ref[2], rtol=0.0, atol=1e-12 * muP * contact.c)


def test_a_continuation_through_a_huge_creepage_starts_the_next_point_cold(contact):
    """A creep curve whose points include one far into full slip (z = tau + r S beyond
    double range there): the next point is solved from a cold start and gives the cold
    solve's forces within the Newton tolerance (1e-7 of max mu p: 1e-6 of mu P here)."""
    muP = contact.mu * contact.P
    cont = Continuation(contact.patch)
    xref = muP / (contact.elastic.G * contact.c**2)
    for xi in (0.1 * xref, 0.2 * xref, 1e300, 0.3 * xref):
        last = cont.solve(xi)
    cold = contact.solve(0.3 * xref)
    assert _finite(last)
    assert abs(last.Tx - cold.Tx) <= 1e-6 * muP


@pytest.mark.parametrize("value", HUGE)
def test_transient_steps_far_into_full_slip_give_mu_P(contact, value):
    """The transient field (HalfSpaceField): a rolling step at slip velocity vx = value and
    a static shift of value metres put every element of the contact into slip along x:
    Tx = mu P sign(value) to 1e-12, Ty within 1e-12 of mu P of zero, finite tau and S
    (before: tau + r S overflowed and the step answered zero tractions)."""
    muP = contact.mu * contact.P
    for step in (
        lambda f: f.roll(1e-4, value, 0.0, 10.0),
        lambda f: f.set_shift(value, 0.0),
    ):
        res = step(HalfSpaceField(contact, n=16))
        sol = res.solution
        assert np.all(np.isfinite(sol.tau)) and np.all(np.isfinite(sol.S))
        assert bool(np.all(sol.slip[sol.contact]))
        assert res.Tx == pytest.approx(math.copysign(muP, value), rel=1e-12)
        assert abs(res.Ty) <= 1e-12 * muP


@pytest.mark.parametrize("xi", [1e-300, -1e-200])
def test_tiny_creepages_keep_the_linear_theorys_slope(contact, xi):
    """Creepages far below the onset of slip (rigid slip below ADHESION_RATIO of the
    bound's elastic displacement): every element adheres and the forces are linear in
    the creepages, so T/xi equals that of xi = 1e-12 (solved as it is) to 1e-12 relative,
    on the railway contact and on Carter's line contact, also from a warm start (before:
    the line contact's Newton iteration stalled in subnormal slips, RuntimeError)."""
    line = LineContact(N=1e5, R=0.06, body=STEEL, substrate=STEEL, mu=0.3)
    assert creepage_scale(contact.patch, 1e-12, 0.0, 0.0) == 1.0
    assert creepage_scale(contact.patch, xi, 0.0, 0.0) > 1.0
    for solve in (
        lambda x: contact.solve(x, 0.5 * x, 0.0),
        lambda x: line.solve(x),
    ):
        tiny, ref = solve(xi), solve(1e-12)
        assert tiny.adhesion_fraction == 1.0
        assert tiny.Tx / xi == pytest.approx(ref.Tx / 1e-12, rel=1e-12)
        assert tiny.Ty / xi == pytest.approx(
            ref.Ty / 1e-12, rel=1e-12, abs=1e-12 * abs(ref.Tx) / 1e-12
        )
    # a warm start from a solution in slip is dropped there (scaled up it would overshoot
    # the bound): the same operations as the cold solve, the same doubles
    warm = contact.solve(xi, 0.5 * xi, 0.0, tau0=contact.solve(1e-3).tau)
    assert warm.Tx == contact.solve(xi, 0.5 * xi, 0.0).Tx
