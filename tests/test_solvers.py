"""solvers.bracketed_newton, the transient bodies' stage and step solver, on residuals
whose roots are known in closed form."""

from __future__ import annotations

import math

import pytest

from contact_fmu.dynamics.solvers import StageSolveError, bracketed_newton


def test_newton_converges_to_the_root_of_an_increasing_cubic():
    """r(u) = u^3 + u - 10 has its one real root at u = 2: from u0 = -50, far outside,
    the geometric search brackets it and Newton closes to rtol (scale + |u|)."""
    calls = []

    def f(u):
        calls.append(u)
        return u**3 + u - 10.0, 3.0 * u**2 + 1.0, u

    u, payload = bracketed_newton(f, -50.0, 1.0, 1e-13, 200, lambda: "no root")
    assert abs(u - 2.0) <= 1e-12 * (1.0 + 2.0) and payload == u
    assert len(calls) < 40


def test_a_saturated_residual_is_crossed_by_steps_of_the_scale():
    """r = tanh(u - 3) with its slope reported as 0 where |u - 3| > 1 (a full-slip
    plateau): steps of the scale reach the slope, then Newton the root u = 3."""

    def f(u):
        x = u - 3.0
        return math.tanh(x), (1.0 - math.tanh(x) ** 2 if abs(x) <= 1.0 else 0.0), None

    u, _ = bracketed_newton(f, -20.0, 0.5, 1e-13, 500, lambda: "no root")
    assert abs(u - 3.0) <= 1e-12 * (0.5 + 3.0)


def test_no_root_within_the_search_is_a_stage_solve_error():
    """r = 1 + exp(u) > 0 everywhere: the search stops at max_search scales from u0 and
    raises StageSolveError with the caller's words."""

    def f(u):
        return 1.0 + math.exp(min(u, 700.0)), math.exp(min(u, 700.0)), None

    with pytest.raises(StageSolveError, match="loads beyond mu P"):
        bracketed_newton(f, 0.0, 1.0, 1e-13, 10_000, lambda: "loads beyond mu P", 1e3)
