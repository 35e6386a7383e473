"""The dense direct path of small grids (contact_fmu.halfspace.direct): the same
semismooth Newton method as the iterative path, so the same converged solution to the
Newton tolerance (1e-7 of max mu p; compared at 1e-6)."""

from __future__ import annotations

import numpy as np
import pytest

from contact_fmu import examples as ex
from contact_fmu.halfspace import HalfSpaceContact, Material, direct
from contact_fmu.halfspace.railway import wheel_on_rail
from contact_fmu.halfspace.rolling import (
    DIRECT_MAX_ELEMENTS,
    DIRECT_REPEAT_MAX_ELEMENTS,
    ellipse_patch,
    solve_rolling,
)


def _patches():
    w = wheel_on_rail(n=(11, 11))
    w19 = wheel_on_rail(n=(19, 19))  # 255 elements: near the limit of repeated direct solves
    lc = ex.contact()
    layer = ellipse_patch(lc.a1, lc.a2, 12, lc.pressure, lc.mu, lc.a1 / lc.k, 0.3, k=lc.k, P=lc.P)
    # 176 elements: Newton matrices of 200 and more unknowns, single precision with layers
    layer16 = ellipse_patch(lc.a1, lc.a2, 16, lc.pressure, lc.mu, lc.a1 / lc.k, 0.3, k=lc.k, P=lc.P)
    steel, alu = Material(210e9, 0.3), Material(70e9, 0.33)
    dissimilar = HalfSpaceContact(1000.0, 0.02, 0.02, steel, alu, 0.3, n=12)
    return {"railway 11 x 11": (w.patch, w), "railway 19 x 19": (w19.patch, w19),
            "layers": (layer, None), "layers 16 x 16": (layer16, None),
            "dissimilar": (dissimilar.patch, dissimilar)}  # fmt: skip


@pytest.mark.parametrize(
    "name", ["railway 11 x 11", "railway 19 x 19", "layers", "layers 16 x 16", "dissimilar"]
)
def test_direct_and_iterative_paths_agree(name):
    patch, c = _patches()[name]
    # "auto" takes the direct path on every solve
    assert int(patch.contact.sum()) <= DIRECT_REPEAT_MAX_ELEMENTS
    if c is not None:
        s = c.mu * c.P / (c.elastic.G * c.c**2)
        cases = [(0.1 * s, 0, 0), (0.3 * s, 0, 0), (0.2 * s, 0.2 * s, 0.3 * s / c.c),
                 (0, 0, 1.5 * s / c.c), (2.0 * s, 1.0 * s, 0)]  # fmt: skip
    else:
        cases = [(1e-4, 0, 0), (1e-3, 5e-4, 0), (1e-2, 0, 0)]
    for w in cases:
        a = solve_rolling(patch, *w, method="iterative")
        b = solve_rolling(patch, *w)
        assert b.gmres_iterations == 0  # the direct path ran
        assert np.abs(a.tau - b.tau).max() < 1e-6 * float(patch.g.max()), w
        assert np.array_equal(a.slip, b.slip), w
        assert b.newton_iterations <= 10


def test_path_rule_for_one_and_for_many_solves():
    """solve_rolling(method="auto") by the measured costs (rolling.DIRECT_MAX_ELEMENTS,
    DIRECT_REPEAT_MAX_ELEMENTS: 320 and 260 contact elements, docs/halfspace.md "Which
    path: the rule"): a patch of 315 elements (21 x 21) takes the direct path on its
    first solve and the iterative one after it; 255 elements (19 x 19) stay direct; 383
    (23 x 23) are iterative from the first. The solutions of the two paths agree to the
    Newton tolerance (compared at 1e-6 of max mu p)."""
    for m, first, later in ((19, True, True), (21, True, False), (23, False, False)):
        c = wheel_on_rail(n=(m, m))
        p = c.patch
        n = int(p.contact.sum())
        assert (n <= DIRECT_MAX_ELEMENTS, n <= DIRECT_REPEAT_MAX_ELEMENTS) == (first, later)
        x = 0.3 * c.mu * c.P / (c.elastic.G * c.c**2)
        one, two, three = (solve_rolling(p, x) for _ in range(3))
        assert (one.gmres_iterations == 0, two.gmres_iterations == 0) == (first, later)
        assert (three.gmres_iterations == 0) == later
        assert np.abs(one.tau - two.tau).max() < 1e-6 * float(p.g.max())


def test_direct_path_warm_start_and_full_adhesion():
    """A warm start from the converged traction needs no Newton step; at a creepage of
    1e-6 mu P/(G c^2) the whole contact adheres and the direct path returns the linear
    theory (Kalker's C11 of this grid) to 1e-6."""
    c = wheel_on_rail(n=(11, 11))
    s = c.mu * c.P / (c.elastic.G * c.c**2)
    sol = c.solve(0.3 * s)
    again = c.solve(0.3 * s, tau0=sol.tau)
    assert again.newton_iterations == 0
    lin = c.solve(1e-6 * s, tol=1e-12)
    assert lin.adhesion_fraction == 1.0
    C11 = c.creep_coefficients().C11
    assert lin.Tx / (c.elastic.G * c.c**2 * 1e-6 * s) == pytest.approx(C11, rel=1e-6)


@pytest.mark.parametrize(
    "m, x, form",
    [(11, 0.1, "slip"), (11, 0.25, "kernel"), (19, 0.25, "single")],
)
def test_reduced_newton_steps_solve_the_full_jacobian(m, x, form):
    """Both reduced forms of a direct Newton step (the adhesion and slip-tangential
    unknowns, or the slip elements' components through K^-1) solve the full generalised
    Jacobian J dtau = -F, J = I - P (I - r K), to round-off, on partial-slip states (a
    perturbed iterate; few elements slipping selects the slip form, most the reduced
    one). The reduced form's matrix is gathered from the difference kernel, from 200
    unknowns on factorised in single precision and refined in double ("single": 19 x
    19 elements, 255 in contact). J is well conditioned here (cond 9 and 17): LAPACK
    in double leaves about 1e-15 of the step's largest component, the refinement stops
    once the next correction is estimated below direct.REFINE_TOL = 1e-12 of it
    (measured 2e-13); 1e-11 covers both."""
    from contact_fmu.halfspace import direct

    c = wheel_on_rail(n=(m, m))
    p, C = c.patch, c.patch.contact
    s = c.mu * c.P / (c.elastic.G * c.c**2)
    w = (x * s, 0.5 * x * s, x * s / c.c)
    sol = solve_rolling(p, *w, method="iterative", tol=1e-3)
    n = int(C.sum())
    t = np.concatenate([sol.tau[0][C], sol.tau[1][C]]) * 1.01
    K, Kinv, r, g = p.dense_contact_operator, p.dense_contact_inverse, p.r, p.g[C]
    W = p.rhs(*w)
    z = t + r * (np.concatenate([W[0][C], W[1][C]]) - K @ t)
    nz = np.hypot(z[:n], z[n:])
    slip = nz > g
    assert 0.05 < slip.mean() < 0.95
    F = t - z * np.tile(np.where(slip, g / nz, 1.0), 2)
    # the slip form through K^-1 (later solves), or the first solve's reduced form
    Kinv = Kinv if form == "slip" else None
    jac = direct._Jacobian(K, Kinv, r, z[:n], z[n:], nz, g, slip, p.difference_kernel)
    assert jac.slip_form == (form == "slip")
    assert jac.single == (form == "single")
    # the full J: P = f (I - zhat zhat^T) in the slip elements, I in the adhesion ones
    P = np.eye(2 * n)
    for e in np.flatnonzero(slip):
        h = np.array([z[e], z[n + e]]) / nz[e]
        ix = np.ix_([e, n + e], [e, n + e])
        P[ix] = g[e] / nz[e] * (np.eye(2) - np.outer(h, h))
    ref = np.linalg.solve(np.eye(2 * n) - P @ (np.eye(2 * n) - r * K), -F)
    assert np.abs(jac.direction(F) - ref).max() < 1e-11 * np.abs(ref).max()


def test_gathered_operator_equals_the_convolution_one():
    """The dense steady-rolling operator K on the contact, gathered from the difference
    kernel (direct.contact_operator), equals K applied to unit tractions by FFT
    convolution (2 m convolutions) to rounding: 1e-13 of its largest entry (measured
    6e-16; the FFT's rounding is about 1e-15), on the railway wheel, an elliptic
    contact of dissimilar materials with layers (the leading-edge terms k/theta) and a
    rectangular grid."""
    cases = (
        wheel_on_rail(n=(19, 19)),
        wheel_on_rail(n=12),
        HalfSpaceContact.from_ellipse(
            3e-3,
            5e-3,
            Material(210e9, 0.3),
            Material(70e9, 0.33),
            0.3,
            P=1e4,
            n=(14, 12),
            kb=1e-12,
            ks=2e-12,
        ),
    )
    for c in cases:
        p = c.patch
        K = direct.contact_operator(p)
        ref = direct.contact_operator_by_columns(p)
        assert np.abs(K - ref).max() <= 1e-13 * np.abs(ref).max()
