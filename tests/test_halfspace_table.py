"""The creep-force table: accuracy against direct solves, the invariants it
enforces by construction, smoothness, the .npz round trip, and its use as a
ContactLaw in the integrator (Eqs. 26 and 29).

The table here is small (solver grid 12 x 12, 13 x 13 x 9 nodes, about 760 solves)
to keep the test fast; docs/halfspace.md reports the errors of larger tables.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from contact_fmu.dynamics.body import Body, Lateral, Loads
from contact_fmu.dynamics.simulate import simulate
from contact_fmu.halfspace.railway import wheel_on_rail
from contact_fmu.halfspace.table import CreepTable, build_table, saturate

NODES = (13, 13, 9)
GRID = 12


@pytest.fixture(scope="module")
def contact():
    return wheel_on_rail(n=GRID)


@pytest.fixture(scope="module")
def table(contact):
    return build_table(contact, nodes=NODES)


def _direct(contact, table, x):
    """Direct solve at normalised creepages x: (Tx/(mu P), Ty/(mu P), Mz/(mu P c))."""
    s = contact.solve(x[0] * table.xi_ref, x[1] * table.xi_ref, x[2] * table.phi_ref)
    muP = contact.mu * contact.P
    return np.array([s.Tx / muP, s.Ty / muP, s.Mz / (muP * contact.c)])


def _table(table, x):
    T = table.forces(x[0] * table.xi_ref, x[1] * table.xi_ref, x[2] * table.phi_ref, 1.0)
    muP = table.mu * table.P
    return np.array([T[0] / muP, T[1] / muP, T[2] / (muP * table.c)])


def test_table_reproduces_the_solver_at_its_nodes(contact, table):
    """At the nodes the Hermite patches take the nodal values: the table equals direct
    solves there (to the Newton tolerance of the solver, 1e-6 of mu P)."""
    ax = table.data.axes
    for i, j, k in ((7, 6, 4), (9, 3, 6), (12, 12, 8), (4, 10, 1), (6, 6, 4)):
        x = (ax[0][i], ax[1][j], ax[2][k])
        np.testing.assert_allclose(_table(table, x), _direct(contact, table, x), atol=1e-6)


def test_table_interpolation_error_is_bounded(contact, table):
    """Between the nodes: the error against direct solves on 30 random points of the
    box (Tx, Ty in mu P, Mz in mu P c). Measured for this 13 x 13 x 9 table: 2.4 % max,
    0.69 % rms; the bounds 3.5 % and 1 % leave room for round-off-level changes of the
    solves only (the computation is deterministic). Larger tables: docs/halfspace.md
    (21 x 21 x 21 nodes: 0.37 % max, 0.1 % rms)."""
    rng = np.random.default_rng(11)
    X = table.data.extent
    err = np.array(
        [
            np.abs(_table(table, x) - _direct(contact, table, x))
            for x in rng.uniform(-0.98, 0.98, (30, 3)) * X
        ]
    )
    assert err.max() < 0.035
    assert np.sqrt(np.mean(err**2)) < 0.01


def _random_inputs(n: int, seed: int):
    rng = np.random.default_rng(seed)
    v = rng.normal(0.0, 0.01, (n, 3)) * (1.0, 1.0, 100.0)  # creepages up to 3 %, spin 3 1/m
    big = rng.random(n) < 0.2
    v[big] *= 30.0  # far outside the table
    Vx = rng.choice([-20.0, -1.0, 0.0, 1.0, 20.0], n)
    return v[:, 0] * np.abs(Vx), v[:, 1] * np.abs(Vx), v[:, 2] * np.abs(Vx), Vx


def test_odd_symmetry_is_exact(table):
    """Symmetry (references.md): reversing the slip reverses the force, exactly (bit
    for bit), inside and outside the table and for Vx = 0."""
    vx, vy, phi, Vx = _random_inputs(400, 1)
    vx[:3] = vy[:3] = 0.0  # the symmetry planes themselves
    a = table.forces(vx, vy, phi, Vx)
    b = table.forces(-vx, -vy, -phi, Vx)
    for k in range(3):
        assert np.array_equal(a[k], -b[k])
    for i in range(20):  # the scalar path obeys the same rule
        s1 = table.forces(float(vx[i]), float(vy[i]), float(phi[i]), float(Vx[i]))
        s2 = table.forces(-float(vx[i]), -float(vy[i]), -float(phi[i]), float(Vx[i]))
        assert s1 == tuple(-t for t in s2)


def test_force_never_exceeds_mu_P(table):
    """|T| <= mu P for any input (the radial saturation of the table), up to the
    round-off of scaling (fx, fy) by s(m)/m and of hypot (a few units of 1e-16)."""
    vx, vy, phi, Vx = _random_inputs(2000, 2)
    Tx, Ty, _ = table.forces(vx, vy, phi, Vx)
    assert np.max(np.hypot(Tx, Ty)) <= table.mu * table.P * (1.0 + 1e-15)


def test_scalar_and_array_paths_agree(table):
    vx, vy, phi, Vx = _random_inputs(200, 3)
    arr = table.forces(vx, vy, phi, Vx)
    for i in range(len(vx)):
        s = table.forces(float(vx[i]), float(vy[i]), float(phi[i]), float(Vx[i]))
        # the same arithmetic in a different order: round-off only
        assert np.allclose(s, [arr[k][i] for k in range(3)], rtol=1e-12, atol=1e-9)


def test_table_is_C1_across_cells_and_symmetry_planes(table):
    """The integrator's root finding needs a C1 law: one-sided difference quotients at
    a cell face, at the symmetry plane xi = 0 and at the saturation band agree to
    O(h) (h = 1e-7 of the box; the second derivative bounds the gap by 1e-4 here)."""
    ax = table.data.axes
    ref = table.xi_ref
    h = 1e-7 * ax[0][-1]

    def grad_gap(x):
        g = []
        for sgn in (+1.0, -1.0):
            f0 = np.array(_table(table, x))
            f1 = np.array(_table(table, (x[0] + sgn * h, x[1], x[2])))
            g.append((f1 - f0) / (sgn * h))
        return np.abs(g[0] - g[1]).max(), np.abs(g[0]).max()

    for x in ((ax[0][8], 0.31 * ax[1][-1], 0.2 * ax[2][-1]), (0.0, 0.2, 0.3), (0.0, -0.4, 1.0)):
        gap, scale = grad_gap(x)
        assert gap < 1e-4 * max(scale, 1.0)
    # the saturation s(m) is C1 at both ends of its band
    d = 0.02
    for m in (1.0 - d, 1.0):
        left = (saturate(np.array(m)) - saturate(np.array(m - 1e-8))) / 1e-8
        right = (saturate(np.array(m + 1e-8)) - saturate(np.array(m))) / 1e-8
        assert abs(left - right) < 1e-6
    assert ref > 0.0


def test_tx_slope_matches_difference_quotients(table):
    """The analytic slope offered to the integrator (tx_slope) agrees with central
    differences of forces: inside the table, in the saturation band, outside the box
    (clamped) and rolling backwards (cubic patches: the difference error is O(h^2),
    1e-6 of the slope's scale with h = 1e-6 of the creepage scale)."""
    xr = table.xi_ref
    V = 7.0
    for vx, vy, Vx in (
        (0.1 * xr * V, 0.05 * xr * V, V),
        (0.35 * xr * V, -0.2 * xr * V, V),
        (-0.3 * xr * V, 0.4 * xr * V, -V),
        (3.0 * xr * V, 1.0 * xr * V, V),
        (0.02 * xr * V, 2.5 * xr * V, -V),
    ):
        T, dvx, dvy, dV = table.tx_slope(vx, vy, Vx)
        assert T == pytest.approx(table.forces(vx, vy, 0.0, Vx)[0], rel=1e-13, abs=1e-9)
        h = 1e-6 * xr * V
        fd = [
            (table.forces(vx + h, vy, 0.0, Vx)[0] - table.forces(vx - h, vy, 0.0, Vx)[0]) / (2 * h),
            (table.forces(vx, vy + h, 0.0, Vx)[0] - table.forces(vx, vy - h, 0.0, Vx)[0]) / (2 * h),
            (table.forces(vx, vy, 0.0, Vx + h)[0] - table.forces(vx, vy, 0.0, Vx - h)[0]) / (2 * h),
        ]
        scale = table.mu * table.P / (xr * V)
        for a, b in zip((dvx, dvy, dV), fd, strict=True):
            assert abs(a - b) < 1e-6 * scale


def test_saturation_outside_the_table_keeps_the_direction(table):
    """Beyond the box the normalised creepage is scaled back onto it along its own
    direction: twice and ten times the largest creepage give the same force, and Vx = 0
    (pure sliding) is the limit of that rule."""
    X = table.data.extent
    d = np.array([0.7, -0.3, 0.2]) * X / 0.7  # leaves the box through the xi face
    v = d * (table.xi_ref, table.xi_ref, table.phi_ref)
    T2 = table.forces(*(2.0 * v), 1.0)
    T10 = table.forces(*(10.0 * v), 1.0)
    T0 = table.forces(*v, 0.0)
    # the same point of the table up to the round-off of the clamp factor
    np.testing.assert_allclose(T10, T2, rtol=1e-14)
    np.testing.assert_allclose(T0, T2, rtol=1e-12)
    T1 = table.forces(*v, 1.0)  # on the face itself
    np.testing.assert_allclose(T1, T2, rtol=1e-12)


def test_npz_round_trip_is_exact(table, tmp_path):
    path = table.save(tmp_path / "railway_table.npz")
    loaded = CreepTable.load(path, P=table.P)
    vx, vy, phi, Vx = _random_inputs(100, 4)
    a = table.forces(vx, vy, phi, Vx)
    b = loaded.forces(vx, vy, phi, Vx)
    for k in range(3):
        assert np.array_equal(a[k], b[k])
    assert loaded.creep_full_slip == table.creep_full_slip


def test_table_of_the_pair_grid_is_the_int_grids(table, tmp_path):
    """One grid rule: the table of n = (12, 12) is that of n = 12 (the same grid, the
    same solves: equal bit for bit, here on 3 x 3 x 3 nodes), and a table keeps the
    pair grid (mx, my) through its .npz file."""
    small = build_table(wheel_on_rail(n=GRID), nodes=(3, 3, 3))
    pair = build_table(wheel_on_rail(n=(GRID, GRID)), nodes=(3, 3, 3))
    assert np.array_equal(small.data.values, pair.data.values)
    assert np.array_equal(small.data.onset, pair.data.onset)
    loaded = CreepTable.load(pair.save(tmp_path / "pair.npz"))
    assert loaded.data.n == (GRID, GRID) and table.data.n == GRID
    assert np.array_equal(loaded.data.values, pair.data.values)


def test_with_load_uses_hertz_similarity(contact, table):
    """Kalker's similarity: for layer-free Hertz contact T/(mu P) depends on the
    creepages only through xi G c^2/(mu P); a table at one load gives another load's
    forces at a node to the solver tolerance."""
    t2 = table.with_load(2.0 * table.P)
    c2 = contact.with_load(2.0 * contact.P)
    ax = table.data.axes
    x = (ax[0][8], ax[1][5], ax[2][6])
    s = c2.solve(x[0] * t2.xi_ref, x[1] * t2.xi_ref, x[2] * t2.phi_ref)
    T = t2.forces(x[0] * t2.xi_ref, x[1] * t2.xi_ref, x[2] * t2.phi_ref, 1.0)
    muP = c2.mu * c2.P
    assert abs(T[0] - s.Tx) < 1e-6 * muP
    assert abs(T[1] - s.Ty) < 1e-6 * muP
    assert t2.a1 == pytest.approx(c2.a1, rel=1e-14)
    assert t2.creep_full_slip == pytest.approx(table.creep_full_slip * (2.0 ** (1 / 3)), rel=1e-12)


def test_table_drives_the_integrator_to_eqs_26_and_29(table):
    """The table as the ContactLaw of the stepper: a wheel under a constant driving
    force and lateral load settles in the quasistationary method on Tx = A2 Fx_ex
    (Eq. 26) and Ty = Fy_ex (Eq. 29), the stage equations inverting the table."""
    body = Body(M=1000.0, Rx=0.46, Iy=1000.0 * 0.46**2 / 2.0)
    muP = table.mu * table.P
    loads = Loads(Fx_ex=0.4 * muP, Fy_ex=0.25 * muP)
    # held spin creepage 0.1 1/m, or none; Vy from Eq. (10)
    for spin in (0.1, 0.0):
        lat = Lateral(vy_ratio=None, spin_ratio=spin)
        tr = simulate(
            table, body, loads, 0.5, 0.05, method="quasistationary", lateral=lat, Vx0=20.0
        )
        assert tr.Tx[-1] == pytest.approx(body.A2 * 0.4 * muP, rel=1e-9)
        assert tr.Ty[-1] == pytest.approx(0.25 * muP, rel=1e-9)
        assert not tr.sliding[-1]
        assert math.isfinite(tr.vx[-1]) and math.isfinite(tr.Vy[-1])
    # held lateral creepage, no spin: the scalar stage solve uses the table's tx_slope
    lat = Lateral(vy_ratio=0.001, spin_ratio=0.0)
    tr = simulate(table, body, loads, 0.5, 0.05, method="quasistationary", lateral=lat, Vx0=20.0)
    assert tr.Tx[-1] == pytest.approx(body.A2 * 0.4 * muP, rel=1e-9)


def test_slips_beyond_double_range_and_vanishing_speeds_give_the_sliding_forces(table):
    """Slip velocities whose table units overflow (1.7e308 m/s) and rolling speeds whose
    product with the clamp underflows (Vx = 5e-324): the forces of pure sliding (Vx = 0)
    along the same direction, bit for bit, finite, scalar and array paths alike (the
    slips are taken over their largest first, the clamp onto the box is d lam without
    |Vx|). Before: NaN, and zero forces with full adhesion."""
    for path in (float, lambda v: np.array([v])):
        big = table.forces(*(path(v) for v in (1.7e308, -1.7e308, 1.7e308, 1.0)))
        unit = table.forces(*(path(v) for v in (1.0, -1.0, 1.0, 0.0)))
        slow = table.forces(*(path(v) for v in (0.3, 0.1, 0.0, 5e-324)))
        still = table.forces(*(path(v) for v in (0.3, 0.1, 0.0, 0.0)))
        for a, b in ((big, unit), (slow, still)):
            assert [float(np.ravel(x)[0]) for x in a] == [float(np.ravel(x)[0]) for x in b]
        assert all(math.isfinite(float(np.ravel(x)[0])) for x in big)
        assert (
            math.hypot(float(np.ravel(slow[0])[0]), float(np.ravel(slow[1])[0]))
            > 0.99 * table.mu * table.P
        )
