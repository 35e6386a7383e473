"""Kalker's FASTSIM (contact_fmu.halfspace.Fastsim): Kalker's coefficients, the linear
limit, full slip, the closed-form creep curve of the simplified theory, the traction
field of the march, and the exact solver beside it."""

from __future__ import annotations

import math

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from scipy.integrate import quad  # noqa: E402

from contact_fmu._validate import InputError  # noqa: E402
from contact_fmu.halfspace import (  # noqa: E402
    STEEL,
    Fastsim,
    HalfSpaceContact,
    kalker_coefficients,
    plot_creep_curves,
    wheel_on_rail,
)
from contact_fmu.halfspace.validation import KALKER_E3, NUS, kalker_contact  # noqa: E402

G, NU, MU, P = 8.0e10, 0.28, 0.3, 1.0e5
# Kalker (1990), Table E3, five rows as printed (a/b -> (C11, C22, C23), each for nu = 0,
# 0.25, 0.5): a transcription apart from the package's table, against its typing errors.
TABLE_E3_PRINTED = {
    0.2: ((2.59, 3.37, 4.81), (2.59, 2.63, 2.66), (0.483, 0.603, 0.809)),
    0.5: ((2.88, 3.62, 4.83), (2.88, 3.01, 3.14), (0.827, 0.929, 1.07)),
    1.0: ((3.40, 4.12, 5.20), (3.40, 3.67, 3.98), (1.33, 1.47, 1.63)),
    2.0: ((4.37, 5.10, 6.11), (4.37, 4.90, 5.56), (2.35, 2.62, 2.96)),
    5.0: ((6.96, 7.78, 8.82), (6.96, 8.14, 9.79), (5.72, 6.63, 7.89)),
}


def xref(f: Fastsim) -> float:
    """mu P/(G c^2): the creepage scale of the creep curves (-)."""
    return f.mu * f.P / (f.G * f.c**2)


def test_kalker_coefficients_at_the_table_nodes_are_kalkers_table_e3():
    """At five a/b of Kalker's Table E3 as printed and nu = 0, 0.25, 0.5 the
    interpolation returns the table's entries (rounding only), and the rows the
    validation uses (validation.KALKER_E3) are those entries."""
    assert KALKER_E3 == TABLE_E3_PRINTED
    for aob, table in TABLE_E3_PRINTED.items():
        for j, nu in enumerate(NUS):
            C = kalker_coefficients(aob, nu)
            np.testing.assert_allclose(C, [table[i][j] for i in range(3)], rtol=1e-12)
    # the row a/b = 0.8 (C23 = 1.13, 1.25, 1.40: increasing in nu as every row)
    np.testing.assert_allclose(kalker_coefficients(0.8, 0.25)[2], 1.25, rtol=1e-12)


@pytest.mark.parametrize("aob", [0.35, 1.0 / 0.45])
def test_kalker_coefficients_between_the_nodes_match_the_exact_solver(aob):
    """Between the table's rows (g = 0.35 and 0.45) and at nu = 0.28 (between its
    columns) the interpolated coefficients agree with the exact solver's full-adhesion
    coefficients on about 64 x 64 square elements within 3 %: the solver's own error at
    the table's nodes is at most 2.0 % on that grid (docs/validation.md), and linear
    interpolation in g errs by about a row's second difference over 8 (C23 at a/b =
    2.2: (3.24 - 2 x 2.62 + 2.23)/8 = 0.029, 1.0 %). Measured: 1.4 % (C22) and 1.5 % (C23)."""
    k = kalker_contact(aob, NU, 64).creep_coefficients()
    np.testing.assert_allclose((k.C11, k.C22, k.C23), kalker_coefficients(aob, NU), rtol=0.03)


@pytest.mark.parametrize("bound", ["parabolic", "elliptic"])
@pytest.mark.parametrize(
    ("a1", "a2", "n"), [(6e-3, 4e-3, 32), (3e-3, 6e-3, (20, 36)), (5e-3, 5e-3, 17)]
)
def test_small_creepage_is_kalkers_linear_theory_to_rounding(bound, a1, a2, n):
    """Linear theory (Kalker 1967): Tx = G c^2 C11 xi, Ty = G c^2 (C22 eta + c C23 phi)
    (the force on the substrate, along the creepage), with the flexibilities of the grid,
    to rounding on every grid and for both bounds (the whole contact adheres)."""
    f = Fastsim(a1, a2, G, NU, MU, P=P, bound=bound, n=n)
    C11, C22, C23 = f.C
    c, x = f.c, 1e-4 * xref(f)
    s = f.solve(x, check_units=False)
    assert s.adhesion.sum() == s.contact.sum()
    assert s.Tx == pytest.approx(G * c * c * C11 * x, rel=1e-12)
    assert abs(s.Ty) < 1e-12 * abs(s.Tx)
    s = f.solve(0.0, x, 0.0, check_units=False)
    assert s.Ty == pytest.approx(G * c * c * C22 * x, rel=1e-12)
    s = f.solve(0.0, 0.0, x / c, check_units=False)
    assert s.Ty == pytest.approx(G * c**3 * C23 * x / c, rel=1e-12)
    # Kalker's flexibilities of the continuous theory, and the grid's within the error of
    # its quadrature of the cut ellipse (first order, jittering with the cut: measured
    # 0.3-3 % on 16-33 elements per side, 0.3 % on 64, 7e-5 on 128)
    L = f.kalker_flexibilities
    assert L[0] == pytest.approx(8 * a1 / (3 * C11 * G), rel=1e-14)
    assert L[2] == pytest.approx(math.pi * a1 * math.sqrt(a1 / a2) / (4 * C23 * G), rel=1e-14)
    np.testing.assert_allclose(f.flexibilities, L, rtol=0.035)


@pytest.mark.parametrize("bound", ["parabolic", "elliptic"])
def test_full_sliding_gives_mu_P(bound):
    """Large creepage (100 mu P/(G c^2)): every element slips and |T| = mu P exactly (the
    bound carries sum p dA = P). FASTSIM's slip direction is that of (xi/L1, eta/L2), not
    of the creepage, when L1 != L2 (its known defect at combined creepage)."""
    f = Fastsim(6e-3, 4e-3, G, NU, MU, P=P, bound=bound, n=24)
    L1, L2, _ = f.flexibilities
    for xi, eta in ((100.0, 0.0), (0.0, -100.0), (60.0, 80.0)):
        s = f.solve(xi * xref(f), eta * xref(f))
        assert s.adhesion_fraction == 0.0
        assert math.hypot(s.Tx, s.Ty) == pytest.approx(MU * P, rel=1e-12)
        d = np.array([xi / L1, eta / L2])
        np.testing.assert_allclose([s.Tx, s.Ty], MU * P * d / np.hypot(*d), atol=1e-12 * MU * P)


def simplified_theory(kappa: float) -> float:
    """Tx/(mu P) of Kalker's simplified theory, parabolic bound, pure longitudinal
    creepage, kappa = xi a/(L1 mu p'), p' = 2 P/(pi a b) (derived strip by strip: with
    lambda = l(y)/a, adhesion from the leading edge to x = (kappa - lambda) a, the bound
    behind it; a strip carries mu p' a (2 kappa lambda^2 - kappa^2 lambda + kappa^3/6)
    while kappa < 2 lambda, (4/3) mu p' a lambda^3 beyond)."""

    def strip(s: float) -> float:
        lam = math.sqrt(max(1.0 - s * s, 0.0))
        if kappa >= 2.0 * lam:
            return 4.0 / 3.0 * lam**3
        return 2.0 * kappa * lam**2 - kappa**2 * lam + kappa**3 / 6.0

    s0 = math.sqrt(max(1.0 - kappa**2 / 4.0, 0.0))
    total = quad(strip, 0.0, s0)[0] + quad(strip, s0, 1.0)[0]
    return 4.0 / math.pi * total


@pytest.mark.parametrize("n", [16, 32, 64, (34, 34)])
def test_creep_curve_is_the_simplified_theorys_closed_form(n):
    """Kalker's simplified theory with the parabolic bound for pure longitudinal creepage
    (Kalker 1973, 1982): the creep curve in closed form along each strip
    (``simplified_theory``; Tx = G c^2 C11 xi at small kappa, mu P from kappa = 2, i.e.
    xi = 32 mu P/(3 pi C11 G c^2)). The march agrees within 0.4 % of mu P: its nodal
    tractions are exact in adhesion, and the force is the first-order sum over the
    elements cut by the ellipse (measured 0.19 %, 0.12 %, 0.13 %, 0.16 %)."""
    f = Fastsim(6e-3, 4e-3, G, NU, MU, P=P, n=n)
    L1 = f.kalker_flexibilities[0]
    pbar = 2.0 * P / (math.pi * f.a1 * f.a2)
    kappa = np.linspace(0.05, 2.5, 50)
    Tx, _, _ = f.forces(kappa * MU * pbar * L1 / f.a1)
    ref = np.array([simplified_theory(k) for k in kappa])
    np.testing.assert_allclose(Tx / (MU * P), ref, atol=0.004)
    # full slip from kappa = 2 on, exactly mu P; at 0.9 of it the leading edges of the
    # long strips still adhere (on the grid: while kappa < 2 - (l - x_lead)/a)
    onset = 32.0 / (3.0 * math.pi * f.C[0]) * xref(f)
    s = f.solve(onset)
    assert s.Tx == pytest.approx(MU * P, rel=1e-12) and s.adhesion_fraction == 0.0
    s = f.solve(0.9 * onset)
    assert s.adhesion_fraction > 0.0 and s.Tx < MU * P


def test_traction_field_is_the_march_of_the_simplified_theory():
    """Pure longitudinal creepage: in adhesion tau_x = xi (l(y) - x)/L1 at the element
    centres (the exact integral from the leading edge), and an element slips exactly
    where that value exceeds the bound mu p (the parabolic bound falls towards the
    trailing edge, so a strip adheres from the leading edge and slips behind): Carter's
    picture strip by strip. The slip S is along tau, zero in adhesion."""
    f = Fastsim(6e-3, 4e-3, G, NU, MU, P=P, n=32)
    x = 0.4 * xref(f)
    s = f.solve(x)
    X, Y = s.grid.mesh()
    C = s.contact
    ell = f.a1 * np.sqrt(np.maximum(1.0 - (Y / f.a2) ** 2, 0.0))
    elastic = x * (ell - X) / f.flexibilities[0]
    g = f.patch.g
    assert s.adhesion.any() and s.slip.any()
    np.testing.assert_array_equal(s.slip, C & (elastic > g))
    A = s.adhesion
    np.testing.assert_allclose(s.tau[0][A], elastic[A], rtol=1e-12)
    np.testing.assert_allclose(s.tau[0][s.slip], g[s.slip], rtol=1e-12)
    assert np.all(s.S[0][A] == 0.0) and np.all(s.S[0][s.slip] > 0.0)
    assert np.all(s.tau[1] == 0.0)


@pytest.mark.parametrize("bound", ["parabolic", "elliptic"])
def test_reversing_the_creepages_reverses_the_forces(bound):
    """Symmetry: (xi, eta, phi) -> -(xi, eta, phi) reverses (Tx, Ty, Mz)."""
    f = Fastsim(6e-3, 4e-3, G, NU, MU, P=P, bound=bound, n=24)
    w = np.array([0.2, -0.3, 0.5 / f.c]) * xref(f)
    a, b = f.solve(*w), f.solve(*(-w))
    np.testing.assert_allclose([b.Tx, b.Ty, b.Mz], [-a.Tx, -a.Ty, -a.Mz], rtol=1e-12)


def test_batched_forces_equal_single_solves_and_p0_gives_the_same_contact():
    """``forces`` marches a batch of creepages at once: the same forces as ``solve`` one
    by one; p0 = 3 P/(2 pi a b) (Hertz) gives the same contact as P."""
    f = Fastsim(6e-3, 4e-3, G, NU, MU, P=P, n=24)
    xs = np.array([0.05, 0.3, 0.9]) * xref(f)
    Tx, Ty, Mz = f.forces(xs, 0.5 * xs, 0.2 / f.c * xref(f))
    for i, x in enumerate(xs):
        s = f.solve(x, 0.5 * x, 0.2 / f.c * xref(f))
        np.testing.assert_allclose([Tx[i], Ty[i], Mz[i]], [s.Tx, s.Ty, s.Mz], rtol=1e-12)
    q = Fastsim(6e-3, 4e-3, G, NU, MU, p0=f.p0, n=24)
    assert q.P == pytest.approx(P, rel=1e-14)
    assert f.p0 == pytest.approx(3 * P / (2 * math.pi * 6e-3 * 4e-3), rel=1e-14)


def test_fastsim_beside_the_exact_solver():
    """The same contact and grid (railway wheel on rail, 34 x 34) in one line each:
    ``c.solve`` and ``c.fastsim`` share the grid and the contact. At small creepage they
    agree within the exact solver's own coefficient error on this grid (about 1.5 %,
    docs/halfspace.md); over the creep curves FASTSIM with the parabolic bound is within
    6 % of mu P for pure creepage and 13 % for pure spin (the theory's difference
    measured on 66 x 66: 3.6 % and 9.6 %, benchmarks/bench_halfspace_fastsim.py, plus
    the exact solver's discretisation error on 34 x 34, 1-1.5 % for creepage and up to
    3 % with spin); it is not the exact theory: the spin curve is at least 5 % off."""
    c = wheel_on_rail(n=(34, 34))
    muP = c.mu * c.P
    x0 = muP / (c.elastic.G * c.c**2)
    e, f = c.solve(0.01 * x0), c.fastsim(0.01 * x0)
    assert f.grid == e.grid and np.array_equal(f.contact, e.contact)
    assert f.Tx == pytest.approx(e.Tx, rel=0.03)
    worst = {"creepage": 0.0, "spin": 0.0}
    for s in np.linspace(0.125, 1.0, 8):
        for kind, w in (("creepage", (1.5 * s, 0.0, 0.0)), ("creepage", (0.0, 1.5 * s, 0.0))):
            a = tuple(v * x0 for v in w)
            e, f = c.solve(*a), c.fastsim(*a)
            worst[kind] = max(worst[kind], abs(f.Tx - e.Tx) / muP, abs(f.Ty - e.Ty) / muP)
        a = (0.0, 0.0, 3.0 * s * x0 / c.c)
        e, f = c.solve(*a), c.fastsim(*a)
        worst["spin"] = max(worst["spin"], abs(f.Ty - e.Ty) / muP)
    assert worst["creepage"] < 0.06
    assert 0.05 < worst["spin"] < 0.13


def test_plot_draws_the_fastsim_solution():
    """``solution.plot()`` of a FASTSIM solution: one arrow per contact element, the
    adhesion and slip elements marked (the exact solver's plot)."""
    f = Fastsim(6e-3, 4e-3, G, NU, MU, P=P, n=16)
    s = f.solve(0.3 * xref(f), 0.1 * xref(f), 0.2 / f.c * xref(f))
    ax = s.plot()
    (q,) = [x for x in ax.collections if hasattr(x, "U")]
    assert q.N == int(s.contact.sum())
    labels = [ln.get_label() for ln in ax.get_lines()]
    assert f"adhesion ({int(s.adhesion.sum())})" in labels
    assert f"slip ({int(s.slip.sum())})" in labels
    plt.close(ax.figure)


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"a1": -1e-3}, "a1"),
        ({"G": float("nan")}, "G"),
        ({"nu": 0.7}, "nu"),
        ({"nu": -0.1}, "nu"),  # outside Kalker's table, no C given
        ({"a2": 0.5e-3}, "a1/a2"),  # a/b = 12, outside the table
        ({"mu": 0.0}, "mu"),
        ({"P": None}, "P, p0"),
        ({"p0": 1e9}, "P, p0"),
        ({"bound": "hertz"}, "bound"),
        ({"n": 2}, "n"),
        ({"n": (8, "x")}, "n"),
        ({"C": (3.0, 3.0)}, "C.shape"),
        ({"C": (3.0, -1.0, 1.0)}, "C"),
        ({"check_units": 1}, "check_units"),
    ],
)
def test_bad_input_names_the_variable(kwargs, name):
    args = {"a1": 6e-3, "a2": 4e-3, "G": G, "nu": NU, "mu": MU, "P": P} | kwargs
    with pytest.raises(InputError) as e:
        Fastsim(**args)
    assert e.value.name == name


def test_bad_solve_inputs_name_the_variable():
    f = Fastsim(6e-3, 4e-3, G, NU, MU, P=P, n=16)
    for call, name in (
        (lambda: f.solve(float("nan")), "xi"),
        (lambda: f.solve(0.0, "1"), "eta"),
        (lambda: f.solve(0.0, 0.0, float("inf")), "phi"),
        (lambda: f.forces([1e-3, 2e-3], [0.0, 0.0, 0.0]), "xi, eta, phi"),
        (lambda: Fastsim.of("wheel"), "contact"),
        (lambda: kalker_coefficients(0.05, 0.3), "a1/a2"),
    ):
        with pytest.raises(InputError) as e:
            call()
        assert e.value.name == name
    layered = HalfSpaceContact.from_ellipse(6e-3, 4e-3, STEEL, STEEL, MU, P=P, kb=1e-12, n=16)
    with pytest.raises(InputError) as e:
        layered.fastsim(1e-3)
    assert e.value.name == "kb + ks"
    # given coefficients lift the table's range
    assert Fastsim(6e-3, 0.5e-3, G, NU, MU, P=P, C=(15.0, 18.0, 20.0)).C == (15.0, 18.0, 20.0)


def test_creep_curve_plot_draws_exact_and_fastsim_together():
    """``plot_creep_curves``: Tx/(mu P) of the exact solver (circles) and of FASTSIM with
    both bounds (lines) against the creepage in mu P/(G c^2), each curve the solvers'
    own forces at those creepages; Ty is left out where it is zero (pure xi)."""
    c = wheel_on_rail(n=12)
    ax = plot_creep_curves(c, (1.0, 0.0, 0.0), s_max=1.0, points=4)
    lines = {ln.get_label(): ln for ln in ax.get_lines() if not ln.get_label().startswith("_")}
    assert set(lines) == {"exact Tx", "FASTSIM parabolic Tx", "FASTSIM elliptic Tx"}
    muP = c.mu * c.P
    x0 = muP / (c.elastic.G * c.c**2)
    s = lines["exact Tx"].get_xdata()
    np.testing.assert_allclose(s, [0.25, 0.5, 0.75, 1.0], rtol=1e-15)
    np.testing.assert_allclose(
        lines["FASTSIM elliptic Tx"].get_ydata()[1],
        c.fastsim(0.5 * x0, bound="elliptic").Tx / muP,
        rtol=1e-12,
    )
    np.testing.assert_allclose(lines["exact Tx"].get_ydata()[3], c.solve(x0).Tx / muP, rtol=1e-9)
    plt.close(ax.figure)
    with pytest.raises(InputError) as e:
        plot_creep_curves(c, (0.0, 0.0, 0.0))
    assert e.value.name == "direction"
