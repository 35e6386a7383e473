"""Root finders for the stage equations of the integrator (scipy underneath)."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import brentq, root

FloatArray = NDArray[np.float64]

# Relative tolerance of the stage solves, on the unknowns (in units of their scale).
SOLVE_RTOL = 1e-13
# Relative forward-difference step of the Newton Jacobian (about sqrt of the rounding).
FD_STEP = 1e-7
# ``newton``: iteration cap before scipy's hybrid method, smallest backtracking fraction.
NEWTON_ITERATIONS = 50
LINE_SEARCH_MIN = 1e-4
# ``newton`` with a kept Jacobian: the largest |r_new|/|r| of a full step it may take
# (beyond, the step is dropped and the Jacobian renewed) ...
CONTRACTION_MAX = 0.25
# ... and the largest after which it is kept: linear convergence at a slower rate would
# take more law evaluations than a new Jacobian.
CONTRACTION_FAST = 1e-2
# Bracket search: the step grows by this factor, at most this many times.
EXPAND = 4.0
MAX_EXPANSIONS = 60


class StageSolveError(RuntimeError):
    """A stage equation has no solution (e.g. loads beyond mu P with eta = inf)."""


def increasing_root(
    r: Callable[[float], float], u0: float, scale: float, max_step: float = np.inf
) -> float:
    """Root of an increasing function r, searched from the guess u0.

    The bracket grows from u0 in steps scale, EXPAND*scale, ... (the first one capped
    at max_step, a bound on the distance to the root when one is known), then scipy's
    brentq closes it to SOLVE_RTOL relative to the scale.
    """
    r0 = r(u0)
    if r0 == 0.0:
        return u0
    direction = -1.0 if r0 > 0.0 else 1.0
    step = min(scale, max_step)
    a = u0
    for _ in range(MAX_EXPANSIONS):
        b = a + direction * step
        if (r(b) > 0.0) != (r0 > 0.0):
            break
        a = b
        step *= EXPAND
    else:
        raise StageSolveError("no root: the stage residual keeps its sign (loads beyond mu P?)")
    lo, hi = (a, b) if a < b else (b, a)
    tol = SOLVE_RTOL * (scale + abs(lo) + abs(hi))
    return float(brentq(r, lo, hi, xtol=tol, rtol=4 * np.finfo(float).eps, maxiter=200))


def bracketed_newton(
    f: Callable[[float], tuple[float, float, Any]],
    u0: float,
    scale: float,
    rtol: float,
    max_iterations: int,
    failure: Callable[[], str],
    max_search: float = math.inf,
) -> tuple[float, Any]:
    """Root of a non-decreasing residual f(u) -> (r, dr/du, payload) from u0: Newton's
    method with the tangent given, kept inside the bracket its iterates build
    (bisection when a step leaves it; before a bracket exists, steps of 4 times the
    Newton step, a geometric search); where the slope vanishes (saturation: full slip)
    a step of ``scale`` toward the root. Converged when the Newton step, or the
    bracket, is below rtol (scale + |u|). Returns (u, payload) of the last evaluation.
    StageSolveError(failure()) after max_iterations evaluations, or once the search
    is max_search scales from u0 without a bracket (no root within any plausible u).
    The transient bodies' stage and step solves (field.c's solve_scalar mirrors it).
    """
    lo, hi = -math.inf, math.inf
    u = u0
    r, d, payload = f(u)
    for _ in range(max_iterations):
        if r == 0.0:
            return u, payload
        if r > 0.0:
            hi = u
        else:
            lo = u
        step = -r / d if d > 0.0 else math.copysign(scale, -r)
        tol = rtol * (scale + abs(u))
        if abs(step) <= tol:
            return u, payload
        bracketed = math.isfinite(lo) and math.isfinite(hi)
        if not bracketed and abs(u - u0) > max_search * scale:
            break
        un = u + step
        if not lo < un < hi:
            un = 0.5 * (lo + hi) if bracketed else u + 4.0 * step
        if bracketed and hi - lo <= tol:
            return u, payload
        u = un
        r, d, payload = f(u)
    raise StageSolveError(failure())


# Safeguarded Newton: at most this many iterations before the bracketing fallback.
MAX_NEWTON = 30


def newton_increasing(
    fdf: Callable[[float], tuple[float, float]], u0: float, scale: float
) -> float:
    """Root of an increasing function f from the guess u0, given f and f' (fdf(u)).

    Newton steps, kept inside the bracket [lo, hi] that the iterates establish (f < 0
    at lo, > 0 at hi); a step that leaves it, or a vanishing f', bisects (or, before a
    bracket exists, moves by a growing multiple of ``scale``). Converged when the step
    is below SOLVE_RTOL (scale + |u|); falls back to ``increasing_root`` otherwise.
    """
    lo, hi = -np.inf, np.inf
    u = u0
    jump = scale
    for _ in range(MAX_NEWTON):
        f, df = fdf(u)
        if f == 0.0:
            return u
        if f > 0.0:
            hi = u
        else:
            lo = u
        new = u - f / df if df > 0.0 else np.nan
        if abs(new - u) <= SOLVE_RTOL * (scale + abs(u)):
            # converged: tested before the bracket, which a step below the rounding of
            # u (new == u == lo) would "leave" and restart the search
            return new
        if not lo < new < hi:  # outside the bracket (or no slope): bisect or search
            if np.isfinite(lo) and np.isfinite(hi):
                new = 0.5 * (lo + hi)
            else:
                new = u + (jump if f < 0.0 else -jump)
                jump *= EXPAND
        if abs(new - u) <= SOLVE_RTOL * (scale + abs(u)):
            return new
        u = new
    return increasing_root(lambda v: fdf(v)[0], u0, scale)


def newton(
    residuals: Callable[[FloatArray], FloatArray],
    u0: FloatArray,
    scale: FloatArray,
    jacobian: Callable[[FloatArray, FloatArray], FloatArray] | None = None,
    memo: dict[str, FloatArray] | None = None,
    hybrid: bool = True,
) -> FloatArray:
    """Solve residuals(u) = 0, u of shape (n,).

    ``residuals`` takes a batch U (k, n) and returns (k, n), so that the
    forward-difference Jacobian costs one call. ``jacobian(u, du)``, if given, returns
    that Jacobian (n, n) for the steps du instead (a caller that knows which residuals
    an unknown moves evaluates fewer). Newton with backtracking on |r|; scipy's hybrid
    method if that stalls (``hybrid``; else StageSolveError, for a caller that tries
    another start first). A step along which the backtracking finds no decrease of |r|
    is a stall unless the full step is already within the stopping rule: on a
    saturated law (full slip: a flat residual) it would otherwise walk u off to
    1e200 and stop there on the relative step test.

    ``memo``: a Jacobian kept from an earlier solve (memo["J"]) and the one this solve
    forms last, written back. A kept Jacobian (and the last fresh one, in later
    iterations: simplified Newton, Hairer & Wanner IV.8) takes full steps while each
    shrinks |r| to at most CONTRACTION_MAX of its value; otherwise the step is dropped
    and the Jacobian formed anew at the current u, as it is after a kept step that left
    more than CONTRACTION_FAST of |r|. The contraction bound makes the error after the
    last step at most a third of that step, within the stopping rule.
    """
    n = len(u0)
    u = np.array(u0, float)
    r = residuals(u[None, :])[0]
    J = None if memo is None else memo.get("J")
    for _ in range(NEWTON_ITERATIONS):
        kept = J is not None
        if not kept:
            du = FD_STEP * (np.abs(u) + scale)
            J = (residuals(u + np.diag(du)) - r).T / du if jacobian is None else jacobian(u, du)
            if memo is not None:
                memo["J"] = J
        try:
            step = np.linalg.solve(J, -r)
        except np.linalg.LinAlgError:
            if not kept:
                break
            J = None
            continue
        lam, norm0 = 1.0, np.linalg.norm(r)
        while True:
            u_new = u + lam * step
            r_new = residuals(u_new[None, :])[0]
            norm = np.linalg.norm(r_new)
            if kept or norm < norm0 or lam < LINE_SEARCH_MIN:
                break
            lam *= 0.5
        if (
            not kept
            and not norm < norm0
            and not np.all(np.abs(step) <= SOLVE_RTOL * (np.abs(u) + scale))
        ):
            break  # no descent along a step that is not small: no root here (saturation)
        if kept and not norm <= CONTRACTION_MAX * norm0:
            J = None  # the step is dropped; a new Jacobian at u
            continue
        u, r = u_new, r_new
        if np.all(np.abs(lam * step) <= SOLVE_RTOL * (np.abs(u) + scale)):
            return u
        if memo is None or (kept and norm > CONTRACTION_FAST * norm0):
            J = None  # Newton; or a kept Jacobian that converges slowly, renewed
    if not hybrid:
        raise StageSolveError(f"stage solve: no convergence in {NEWTON_ITERATIONS} Newton steps")
    sol = root(lambda v: residuals(v[None, :])[0], u, method="hybr", options={"xtol": SOLVE_RTOL})
    if not sol.success:
        raise StageSolveError(f"stage solve failed after Newton and hybr: {sol.message}")
    return np.asarray(sol.x).reshape(n)
