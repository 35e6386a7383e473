"""Creep curves by continuation and the solver's accuracy at small creepages.

``HalfSpaceContact.forces`` solves a sequence of creepages from the secant prediction
of ``rolling.Continuation`` instead of the cold start of ``solve``. The prediction is
only the initial guess of the same Newton iteration, converged to the same tolerance:
the forces must be the cold start's within what that tolerance allows. References: the
converged cold solves, and Kalker's linear theory (the grid's own creep coefficients,
``creep_coefficients``) at small creepage.
"""

from __future__ import annotations

import numpy as np
import pytest

from contact_fmu.halfspace.railway import wheel_on_rail
from contact_fmu.halfspace.rolling import NEWTON_TOL, Continuation, solve_rolling

# Forces of two solves converged to max |F| <= NEWTON_TOL max g from different starts:
# a residual of that size in every element moves the force by at most NEWTON_TOL max g
# times the contact area = 1.5 NEWTON_TOL mu P (Hertz: max p = 1.5 P/area) per unit gain
# of the inverse Jacobian; 1e-6 mu P allows a gain of 6 (measured: 7.9e-9 mu P).
SAME_FORCE = 1e-6


def reference_units(c):
    """mu P/(G c^2): the creepage unit of the curves."""
    return c.mu * c.P / (c.elastic.G * c.c**2)


def test_creep_curve_with_continuation_is_the_cold_one():
    """A 12-point longitudinal creep curve (xi = 0.125 .. 1.5 mu P/(G c^2), partial
    slip into full slip) and an 8-point combined one with spin and Vx < 0 (the mirrored
    frame), on 32 x 32 (the iterative path) and 19 x 19 (the direct path): forces with
    continuation equal the cold solves' within SAME_FORCE mu P (measured at most 7.9e-9
    mu P), and the warm longitudinal curve on 32 x 32 takes fewer Newton steps (measured
    48 against 57)."""
    for n in (32, (19, 19)):
        c = wheel_on_rail(n=n)
        xref = reference_units(c)
        muP = c.mu * c.P
        s = np.linspace(0.0, 1.5, 13)[1:]
        t = np.linspace(0.0, 1.5, 9)[1:]
        for vx, vy, phi, Vx in (
            (s * xref, 0.0 * s, 0.0 * s, 1.0),
            (-0.5 * t * xref, 0.3 * t * xref, 0.4 * t * xref / c.c, -1.0),
        ):
            if n == 32 and Vx > 0.0:
                continue  # below, by the solver directly, with its counts
            warm = np.array(c.forces(vx, vy, phi, Vx))
            cold = np.array(c.forces(vx, vy, phi, Vx, continuation=False))
            assert np.abs(warm[:2] - cold[:2]).max() <= SAME_FORCE * muP
            assert np.abs(warm[2] - cold[2]).max() <= SAME_FORCE * muP * c.c
            # the batch is single solves (the frame of Vx < 0 included)
            one = c.traction(vx[3], vy[3], phi[3], Vx)
            assert abs(one.Tx - warm[0, 3]) <= SAME_FORCE * muP
            assert abs(one.Ty - warm[1, 3]) <= SAME_FORCE * muP
    c = wheel_on_rail(n=32)
    p = c.patch
    cont = Continuation(p)
    warm = [cont.solve(x) for x in s * reference_units(c)]
    cold = [solve_rolling(p, x) for x in s * reference_units(c)]
    dT = max(max(abs(w.Tx - k.Tx), abs(w.Ty - k.Ty)) for w, k in zip(warm, cold, strict=True))
    assert dT <= SAME_FORCE * c.mu * c.P
    assert sum(w.newton_iterations for w in warm) < sum(k.newton_iterations for k in cold)


def test_continuation_predicts_only_along_a_line():
    """The secant prediction is made only for creepages on the line of the last two
    (here xi = 1, 2 -> 3: z_2 + (z_2 - z_1) of the fixed-point variable z = tau + r S,
    projected on |tau| <= g) and the scaled one on the ray of the last; a creepage off
    both gets no prediction (the cold start)."""
    c = wheel_on_rail(n=16)
    p = c.patch
    x = 0.1 * reference_units(c)

    def z(sol):
        return np.where(p.contact, sol.tau + p.r * sol.S, 0.0)

    def projected(v):
        mag = np.hypot(*v)
        return np.where(p.contact, v * np.minimum(1.0, p.g / np.where(mag > 0, mag, 1.0)), 0.0)

    cont = Continuation(p)
    assert cont.guess(x, 0.0, 0.0) is None
    z1 = z(cont.solve(x))
    # one point: the ray through it scales it (projected)
    assert np.abs(cont.guess(2.0 * x, 0.0, 0.0) - projected(2.0 * z1)).max() <= 1e-12 * p.g.max()
    assert cont.guess(x, x, 0.0) is None  # off the ray
    z2 = z(cont.solve(2.0 * x))
    line = cont.guess(3.0 * x, 0.0, 0.0)
    assert np.abs(line - projected(2.0 * z2 - z1)).max() <= 1e-12 * p.g.max()
    assert cont.guess(2.0 * x, x, 0.0) is None  # off the line and the ray


def test_small_creepage_is_the_linear_theory():
    """At xi (eta, phi c) = 1e-6 mu P/(G c^2) the slip area is vanishingly small and the
    forces are Kalker's linear theory on the same grid (``creep_coefficients``; the
    exact solution departs from it at second order, about 1e-6 relative here): Tx =
    G c^2 C11 xi, Ty = G c^2 (C22 eta + c C23 phi), within 0.1 % of the force with the
    default tolerance, on the iterative path (32 x 32; the bound max g alone left up to
    0.08 % there, now measured at most 2.6e-5), with nested iteration (64 x 64: 0.02 %
    before, now 3.7e-6) and on the direct path (19 x 19: exact to rounding)."""
    for n in (32, 64, (19, 19)):
        c = wheel_on_rail(n=n)
        k = c.creep_coefficients()
        G, cc = c.elastic.G, c.c
        x = 1e-6 * reference_units(c)
        for xi, eta, phi in ((x, 0.0, 0.0), (0.0, x, 0.0), (0.0, 0.0, x / cc)):
            s = c.solve(xi, eta, phi, check_units=False)
            Tx = G * cc**2 * k.C11 * xi
            Ty = G * cc**2 * (k.C22 * eta + cc * k.C23 * phi)
            scale = max(abs(Tx), abs(Ty))
            assert s.Tx == pytest.approx(Tx, abs=1e-3 * scale)
            assert s.Ty == pytest.approx(Ty, abs=1e-3 * scale)
            assert s.adhesion_fraction == 1.0


def test_convergence_bound_scales_with_small_tractions():
    """The Newton bound is NEWTON_TOL max g while max |tau| >= 1e-3 max g (creep
    curves and tables unchanged) and NEWTON_TOL 1e3 max |tau| below."""
    from contact_fmu.halfspace.rolling import SMALL_TRACTION, convergence_bound

    tau = np.zeros((2, 3, 3))
    tau[0, 1, 1] = 2e-4
    assert convergence_bound(tau, NEWTON_TOL, 1.0, SMALL_TRACTION) == pytest.approx(
        NEWTON_TOL * 0.2, rel=1e-12
    )
    tau[0, 1, 1] = 0.5
    assert convergence_bound(tau, NEWTON_TOL, 1.0, SMALL_TRACTION) == NEWTON_TOL
    assert convergence_bound(tau, NEWTON_TOL, 1.0, 0.0) == NEWTON_TOL


def test_right_preconditioned_gmres_with_restarts():
    """krylov.gmres_right, the Krylov solver of the Newton steps: on a nonsymmetric,
    diagonally dominant system of 60 unknowns with a Jacobi preconditioner, restarted
    every 5 iterations (the restart path of the Newton systems, which rarely need it),
    the true residual ends below rtol |b| = 1e-10 |b| (its stopping test, by the
    Arnoldi recurrence: 1e-3 of slack for its rounding; measured 4.5e-11 after 25
    iterations), and the side product (here the full product A z doubled) combines like
    the solution: 2 A x to rounding (measured 3.6e-15). b = 0: x = 0, no iteration."""
    from contact_fmu.halfspace.krylov import gmres_right

    rng = np.random.default_rng(7)
    n = 60
    A = rng.standard_normal((n, n)) / np.sqrt(n) + np.diag(2.0 + rng.random(n))
    b = rng.standard_normal(n)
    d = np.diag(A).copy()
    x, its, side = gmres_right(lambda z: (A @ z, 2.0 * (A @ z)), b, lambda v: v / d, 1e-10, 5, 500)
    assert np.linalg.norm(b - A @ x) <= 1.001e-10 * np.linalg.norm(b)
    assert its > 5  # it restarted
    assert np.abs(side - 2.0 * (A @ x)).max() <= 1e-12 * np.abs(b).max() * 2.0 * n
    x0, its0, side0 = gmres_right(lambda z: (A @ z, None), np.zeros(n), lambda v: v, 0.1, 5, 50)
    assert its0 == 0 and side0 is None and not x0.any()


def test_continuation_falls_back_to_a_cold_start(monkeypatch):
    """Should Newton fail from the prediction (here: every warm-started solve raises,
    as after NEWTON_MAXIT steps), the point is solved cold: the solution of
    ``solve_rolling`` without a guess, within SAME_FORCE mu P (the same start; the
    direct path's Newton steps may take another reduced form once K^-1 exists)."""
    from contact_fmu.halfspace import rolling

    c = wheel_on_rail(n=16)
    p = c.patch
    x = 0.2 * reference_units(c)
    real = rolling.solve_rolling

    def failing(patch, xi, eta=0.0, phi=0.0, tau0=None, **kw):
        if tau0 is not None:
            raise RuntimeError("steady rolling: no convergence (test)")
        return real(patch, xi, eta, phi, **kw)

    cont = Continuation(p)
    cont.solve(x)
    monkeypatch.setattr(rolling, "solve_rolling", failing)
    assert cont.guess(2.0 * x, 0.0, 0.0) is not None
    sol = cont.solve(2.0 * x)
    ref = real(p, 2.0 * x)
    assert abs(sol.Tx - ref.Tx) <= SAME_FORCE * c.mu * c.P
    assert sol.levels == ref.levels and sol.newton_iterations > 0
