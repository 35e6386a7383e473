"""The compiled stepper (contact_fmu/native) against the Python path it mirrors, and the
stage solver's stopping rule.

The kernel repeats the Python expressions in the same order without fused multiply-adds,
so where every hypot it evaluates has a zero argument (no lateral slip: hypot(x, 0) = |x|
exactly in both CPython and the C library) a step must give the same doubles. With a held
lateral ratio the two hypot implementations may differ by one unit in the last place;
the stage solves converge to SOLVE_RTOL = 1e-13 of their scale, so the paths agree to
that order.
"""

from __future__ import annotations

import itertools
import math
import os
import shutil
import sys
import sysconfig
from functools import partial
from pathlib import Path

import numpy as np
import pytest

from contact_fmu import examples as ex
from contact_fmu import native
from contact_fmu.dynamics import solvers
from contact_fmu.dynamics.body import ROLLING_STRAIGHT, Body, Lateral, Loads
from contact_fmu.dynamics.integrator import GAMMA, SCHEMES, RollingBody

pytestmark = pytest.mark.skipif(native.library() is None, reason="no C compiler")

CONTACT = ex.contact()
F = CONTACT.mu * CONTACT.P


def _pair(
    method: str, eta: float, V0: float, lateral: Lateral = ROLLING_STRAIGHT, scheme="lobatto3c"
):
    body = Body.from_eta(1.0, 0.05, eta)
    a, b = (
        RollingBody(CONTACT, body, lateral, method, V0, V0 / 0.05 * 0.999, scheme=scheme)
        for _ in range(2)
    )
    b._kernel = None  # the Python path
    assert a._kernel is not None
    return a, b


def _histories(rng, lateral: Lateral = ROLLING_STRAIGHT, scheme: str = "lobatto3c"):
    """Random load histories over the covered path: loads to 1.5 mu P (gross sliding),
    steps from 1e-8 to 10 s, 1-7 substeps, speeds from 5 m/s to rest and reversed,
    load changes; yields (a, b, advance args) for each step."""
    for method in ("full", "quasistationary"):
        for eta in (1.0, 3.0, 1e3, math.inf):
            for V0 in (5.0, 1e-3, 1e-8, 0.0, -2.0):
                a, b = _pair(method, eta, V0, lateral, scheme)
                for _ in range(60):
                    fx = rng.uniform(-1.5, 1.5) * F
                    L = Loads(fx, rng.uniform(-0.5, 0.5) * F * 0.05, 0.0, 0.0)
                    _change_load(rng, 0.05, CONTACT, a, b)
                    yield a, b, (10 ** rng.uniform(-8, 1), L, int(rng.integers(1, 8)))


def _change_load(rng, share: float, law, *bodies) -> None:
    """With probability ``share``, the same new normal load (0.5-1.5 of law.P) on each."""
    if rng.uniform() < share:
        P = law.P * rng.uniform(0.5, 1.5)
        for body in bodies:
            body.set_load(P)


def _advance(body, args):
    try:
        body.advance(*args)
    except Exception as e:  # both paths must fail alike
        return type(e).__name__, str(e)
    return None


def _counting(monkeypatch, kernel: type = native.Kernel) -> dict[str, int]:
    counts = {"kernel": 0, "python": 0}
    original = kernel.advance

    def counted(self, *args):
        result = original(self, *args)
        counts["kernel" if result else "python"] += 1
        return result

    monkeypatch.setattr(kernel, "advance", counted)
    return counts


@pytest.mark.parametrize("scheme", SCHEMES)
def test_kernel_gives_the_python_paths_doubles_without_lateral_slip(monkeypatch, scheme):
    """Lobatto IIIC (_lobatto_scalar) and SDIRK2 (_sdirk_scalar: its two stages in turn,
    each from its explicit part), both methods: the same doubles, step for step."""
    counts = _counting(monkeypatch)
    rng = np.random.default_rng(7)
    for a, b, args in _histories(rng, scheme=scheme):
        assert _advance(a, args) == _advance(b, args)
        assert np.array_equal(a.y, b.y) and a.t == b.t and a._dv == b._dv
        assert a.out == b.out and a.sliding == b.sliding
    # the kernel took the steps (a test of the fallback alone would pass vacuously)
    assert counts["kernel"] > 0.9 * (counts["kernel"] + counts["python"])


@pytest.mark.parametrize(
    ("vy_ratio", "spin_ratio", "scheme"),
    [
        (0.002, 0.0, "lobatto3c"),
        (-0.01, 0.0, "lobatto3c"),
        (0.3, 0.0, "lobatto3c"),
        (0.3, 0.0, "sdirk2"),
        (0.0, 1.0, "lobatto3c"),
        (0.002, -3.0, "sdirk2"),
    ],
)
def test_kernel_agrees_to_rounding_with_a_held_lateral_ratio(
    monkeypatch, vy_ratio, spin_ratio, scheme
):
    """A lateral slip and a spin held at ratios of Vx (Eqs. 10-11 left out): the kernel's
    scalar path (with spin, its slope by the same forward difference as the Python
    path's) agrees with the Python path step for step, to rounding in the stage solves'
    units; the kernel took the steps."""
    counts = _counting(monkeypatch)
    rng = np.random.default_rng(11)
    scale = F
    lateral = Lateral(vy_ratio=vy_ratio, spin_ratio=spin_ratio)
    for a, b, args in _histories(rng, lateral, scheme):
        assert _advance(a, args) == _advance(b, args)
        v = CONTACT.creep_full_slip * max(abs(b.y[0]), 1e-9)  # the stage solves' scale
        assert abs(a.y[0] - b.y[0]) <= 1e-12 * max(abs(b.y[0]), 1e-9)
        assert abs(a.y[1] - b.y[1]) <= 1e-11 * v
        assert abs(a.out.Tx - b.out.Tx) <= 1e-11 * scale
        assert abs(a.out.Ty - b.out.Ty) <= 1e-11 * scale
        assert a.sliding == b.sliding and a.t == b.t
    assert counts["kernel"] > 0.9 * (counts["kernel"] + counts["python"])


def test_every_path_of_a_compiled_law_has_its_kernel():
    body = Body.from_eta(1.0, 0.05, 3.0)
    dynamic_vy = Lateral(vy_ratio=None)
    assert type(RollingBody(CONTACT, body, Lateral(spin_ratio=1.0))._kernel) is native.Kernel
    for method, scheme in itertools.product(("full", "quasistationary"), SCHEMES):
        a = RollingBody(CONTACT, body, dynamic_vy, method=method, scheme=scheme)
        assert type(a._kernel) is native.VectorKernel
        assert type(RollingBody(CONTACT, body, method=method, scheme=scheme)._kernel) is (
            native.Kernel
        )


def _steady_histories():
    """A co-simulation's use: a fixed communication step (1e-4 s, 2 substeps), loads
    varying smoothly (lateral force and spin moment swept), for each vector path and
    both methods (the quasistationary one's algebraic stage keeps its matrix too)."""
    cap = CONTACT.mu * CONTACT.P
    for lateral, method in itertools.product(VECTOR_PATHS, ("full", "quasistationary")):
        body = Body.from_eta(1.0, 0.05, 3.0, Iz=2e-3)
        a = RollingBody(CONTACT, body, lateral, method, Vx0=5.0, Omega_y0=5.0 / 0.05 * 0.999)
        for k in range(60):
            s = math.sin(k / 10)
            L = Loads(0.3 * cap, 0.4 * cap * s, 0.0, 0.05 * cap * CONTACT.a1 * s)
            yield a, None, (1e-4, L, 2)


def test_kept_newton_matrix_changes_the_vector_step_only_within_the_stage_tolerance(
    monkeypatch,
):
    """The vector step keeps its Newton matrix between steps of the same size
    (RollingBody._jac). Against the same histories stepped by Newton proper (a new
    matrix every iteration), states and forces agree to the stage tolerance (the bounds
    of _assert_vector_paths_agree), on random histories (load jumps, steps of 1e-8 to
    1 s) and on a co-simulation's smooth one (both methods), where the law is
    evaluated at most 0.6 times as often (measured: 0.55; on the random histories
    0.81)."""
    import contact_fmu.dynamics.integrator as integrator

    runs = {}
    for mode in ("kept", "newton"):
        if mode == "newton":  # the memo left out: a new matrix every iteration
            monkeypatch.setattr(
                integrator, "newton", lambda *a, f=solvers.newton, **kw: f(*a[:4], **kw)
            )
        inputs = [0]
        forces = RollingBody._forces

        def counted(self, Y, forces=forces, inputs=inputs):
            inputs[0] += Y.shape[0]
            return forces(self, Y)

        monkeypatch.setattr(RollingBody, "_forces", counted)
        random = _vector_histories(
            CONTACT,
            np.random.default_rng(8),
            lambda eta: Body.from_eta(1.0, 0.05, eta, Iz=2e-3),
            V0s=(5.0, -2.0),
            steps=12,
        )
        states = []
        for histories in (random, _steady_histories()):
            inputs[0] = 0  # the count of the last: the smooth history
            for a, _, args in histories:
                a._kernel = None
                states.append((_advance(a, args), a.y.copy(), a.out))
        runs[mode] = (states, inputs[0])
    cap = CONTACT.mu * CONTACT.P
    for (ea, ya, oa), (eb, yb, ob) in zip(runs["kept"][0], runs["newton"][0], strict=True):
        assert ea == eb
        v = CONTACT.creep_full_slip * max(abs(yb[0]), 1e-9)
        for k, unit in ((1, v), (2, v), (3, v / CONTACT.a1)):
            assert abs(ya[k] - yb[k]) <= 1e-12 * (abs(yb[k]) + unit)
        assert abs(oa.Tx - ob.Tx) <= 1e-12 * cap and abs(oa.Ty - ob.Ty) <= 1e-12 * cap
    assert runs["kept"][1] <= 0.6 * runs["newton"][1], (runs["kept"][1], runs["newton"][1])


# Eq. (10) and/or Eq. (11) integrated (the vector path), the other rate held at a ratio
VECTOR_PATHS = (
    Lateral(vy_ratio=None, spin_ratio=None),
    Lateral(vy_ratio=None, spin_ratio=2.0),
    Lateral(vy_ratio=0.01, spin_ratio=None),
)


def _vector_histories(law, rng, body_of, V0s, steps, method="full", scheme="lobatto3c"):
    """Random histories of all four loads (to 1.2 mu P: gross sliding; Fy_ex and Mz_ex
    drive Vy and Omega_z), steps of 1e-8 to 1 s in 1-4 substeps, load changes, for
    each vector path, eta (inf: no slip mass) and initial speed (reversed included)."""
    cap = law.mu * law.P
    for lateral in VECTOR_PATHS:
        for eta in (1.0, math.inf):
            for V0 in V0s:
                body = body_of(eta)
                a, b = (
                    RollingBody(
                        law,
                        body,
                        lateral,
                        method,
                        Vx0=V0,
                        Omega_y0=V0 / body.Rx * 0.999,
                        Vy0=0.01 * V0,
                        Omega_z0=0.3 * V0,
                        scheme=scheme,
                    )
                    for _ in range(2)
                )
                b._kernel = None
                for _ in range(steps):
                    L = Loads(
                        rng.uniform(-1.2, 1.2) * cap,
                        rng.uniform(-0.8, 0.8) * cap,
                        rng.uniform(-0.5, 0.5) * cap * body.Rx * 0.05,
                        rng.uniform(-1.0, 1.0) * cap * law.a1 * 0.1,
                    )
                    _change_load(rng, 0.1, law, a, b)
                    yield a, b, (10 ** rng.uniform(-8, 0), L, int(rng.integers(1, 5)))


def _assert_vector_paths_agree(law, histories):
    """Both paths run solvers.newton's iteration to SOLVE_RTOL = 1e-13 of (|u| + scale)
    on the same residuals; their Jacobians differ by rounding (another elimination
    order than LAPACK's), so the converged stage unknowns differ by about that
    tolerance, and the L-stable step does not amplify it from step to step: 1e-12 of
    the scale (measured: 5e-14). The forces are Lipschitz in u with constant about
    mu P / scale: 1e-12 of mu P (of mu P a1 for Mz). SDIRK2's forces close the last
    stage's balance, F - m (u - u_hat)/(h gamma) (integrator._sdirk_vector): they carry
    the unknowns' difference times m/(h gamma) besides, m the mass of each unknown
    (M A2, M, Iz) and h at most the substep dt. Returns the number of steps that
    completed."""
    cap = law.mu * law.P
    completed = 0
    for a, b, args in histories:
        dt = args[0] / args[2]
        ea, eb = _advance(a, args), _advance(b, args)
        if ea is not None and ea[0] == "StageSolveError" == eb[0]:
            # both fail alike; after "hybr:" scipy's diagnostic of its last iterate, which
            # differs where the states before the step differ by rounding
            ea, eb = ea[1].split(":")[0], eb[1].split(":")[0]
        assert ea == eb
        assert a.sliding == b.sliding  # the quasistationary regime
        v = law.creep_full_slip * max(abs(b.y[0]), 1e-9)  # the stage solves' scale
        assert abs(a.y[0] - b.y[0]) <= 1e-12 * max(abs(b.y[0]), 1e-9)
        balance = []
        masses = (b.body.m_slip, b.body.M, b.body.Iz)
        for k, unit, m in zip((1, 2, 3), (v, v, v / law.a1), masses, strict=True):
            assert abs(a.y[k] - b.y[k]) <= 1e-12 * (abs(b.y[k]) + unit)
            sdirk = b.scheme == "sdirk2"
            balance.append(sdirk * m / (dt * GAMMA) * 1e-12 * (abs(b.y[k]) + unit))
        assert abs(a.out.Tx - b.out.Tx) <= 1e-12 * cap + balance[0]
        assert abs(a.out.Ty - b.out.Ty) <= 1e-12 * cap + balance[1]
        assert abs(a.out.Mz - b.out.Mz) <= 1e-12 * cap * law.a1 + balance[2]
        assert a.out.sliding == b.out.sliding and a.t == b.t
        # _dv = (vx - vx_n)/dt of the last substep dt: the vx bound over dt, twice (a
        # step that raised left the _dv of the step before, checked with its own dt)
        assert ea is not None or abs(a._dv - b._dv) <= 2e-12 * (abs(b.y[1]) + v) / dt
        completed += ea is None
    return completed


@pytest.mark.parametrize("scheme", SCHEMES)
@pytest.mark.parametrize("method", ["full", "quasistationary"])
def test_vector_kernel_agrees_with_the_python_path_on_the_thin_layer(monkeypatch, method, scheme):
    """Eqs. (8)-(11) with the thin-layer law and spin (the strip march in the stage
    residuals): the compiled vector step (cf_advance_vector) against
    RollingBody._lobatto_vector and _sdirk_vector (its two stages in turn, Newton with a
    new matrix every iteration); quasistationary: the algebraic stages (T(u2) = F2 for
    Lobatto IIIC, SDIRK2's two with the masses zero) while rolling, the stages with the
    masses in gross sliding (loads to 1.2 mu P), and the regime (RollingBody._step,
    _update_regime, advance's one step under held loads)."""
    counts = _counting(monkeypatch, native.VectorKernel)
    histories = _vector_histories(
        CONTACT,
        np.random.default_rng(3),
        lambda eta: Body.from_eta(1.0, 0.05, eta, Iz=2e-3),
        V0s=(5.0, 1e-3, -2.0),
        steps=12,
        method=method,
        scheme=scheme,
    )
    sliding, completed = [], 0
    for a, b, args in histories:
        completed += _assert_vector_paths_agree(CONTACT, [(a, b, args)])
        sliding.append(b.sliding)
    # the kernel took every step that completed (its Newton from the same starts as
    # integrator._newton_from; 4 of these 432 steps need a further start), leaving to
    # Python only scipy's hybrid method, which none of them needs, and the steps that
    # raise (eta = inf with loads beyond mu P, full method), on both paths
    assert counts["kernel"] == completed
    if method == "quasistationary":  # both regimes were stepped
        assert 0 < sum(sliding) < len(sliding), sum(sliding)


def test_without_the_library_the_stepper_is_unchanged(monkeypatch):
    monkeypatch.setenv("CONTACT_FMU_NATIVE", "0")
    monkeypatch.setattr(native, "_LOADED", {})
    assert native.library() is None and native.fmi_module() is None
    rb = RollingBody(CONTACT, Body.from_eta(1.0, 0.05, 3.0), Vx0=5.0, Omega_y0=100.0)
    assert rb._kernel is None
    rb.advance(1e-4, Loads(0.5 * F, 0.0, 0.0, 0.0), 4)
    assert math.isfinite(rb.out.Tx)


def _cubic_system():
    """r(u) = A u + 0.1 u^3 - b (batched), its root and exact Jacobian there."""
    A = np.array([[4.0, 1.0, 0.0], [1.0, 3.0, 0.5], [0.0, 0.5, 2.0]])
    b = np.array([1.0, -2.0, 0.5])

    def residuals(U):
        return U @ A.T + 0.1 * U**3 - b

    root = solvers.newton(residuals, np.zeros(3), np.ones(3))
    return residuals, root, A + np.diag(0.3 * root**2)


def test_simplified_newton_keeps_a_jacobian_only_while_it_contracts():
    """solvers.newton with a memo (Hairer & Wanner IV.8): a kept Jacobian that makes
    every full step contract by CONTRACTION_FAST is used without forming a new one; a
    wrong one (here of the opposite sign: |r| grows) is dropped at its first step and
    replaced; either way the root is Newton's to the stopping rule (SOLVE_RTOL)."""
    residuals, root, J_root = _cubic_system()
    formed = [0]

    def counted(U):
        formed[0] += U.shape[0] > 1  # a forward-difference Jacobian: a batch of n
        return residuals(U)

    start = root + np.array([1e-3, -2e-3, 1e-3])
    for J0, new in ((J_root, 0), (-J_root, 1)):
        memo = {"J": J0}
        formed[0] = 0
        u = solvers.newton(counted, start, np.ones(3), memo=memo)
        assert np.all(np.abs(u - root) <= 1e-12)
        assert formed[0] == new
        assert (memo["J"] is J0) == (new == 0)


def test_newton_stops_at_a_step_below_the_rounding_of_u():
    """Converged Newton iterates of a smooth increasing function: the last step f/f' is
    rounding noise, often below half an ulp of u (u - f/f' == u). That is convergence,
    not a step outside the bracket (which restarted the search and ended in brentq
    after 30 iterations in 19 % of these cases). Newton from 0 on u^3 + u = c, c <= 50,
    needs at most 13 evaluations."""
    rng = np.random.default_rng(0)
    worst = 0
    for c in rng.uniform(0.5, 50.0, 500):
        calls = [0]

        def fdf(u, c=c, calls=calls):
            calls[0] += 1
            return u**3 + u - c, 3.0 * u * u + 1.0

        u = solvers.newton_increasing(fdf, 0.0, 1.0)
        assert abs(u**3 + u - c) <= 1e-12 * c
        worst = max(worst, calls[0])
    assert worst <= 13


@pytest.fixture(scope="module")
def table():
    """A small creep-force table of the railway wheel (8 x 8 solver grid)."""
    from contact_fmu.halfspace.railway import wheel_on_rail
    from contact_fmu.halfspace.table import build_table

    return build_table(wheel_on_rail(n=8), nodes=(9, 9, 5))


@pytest.mark.parametrize("scheme", SCHEMES)
@pytest.mark.parametrize("method", ["full", "quasistationary"])
def test_vector_kernel_agrees_with_the_python_path_on_the_half_space_table(
    monkeypatch, table, method, scheme
):
    """The same on the creep-force table with spin (table_scalar with phi): the vector
    step of a railway wheel against RollingBody._lobatto_vector and _sdirk_vector, both
    methods."""
    counts = _counting(monkeypatch, native.VectorKernel)
    histories = _vector_histories(
        table,
        np.random.default_rng(4),
        lambda eta: Body.from_eta(500.0, 0.46, eta, Iz=50.0),
        V0s=(20.0, -5.0),
        steps=10,
        method=method,
        scheme=scheme,
    )
    completed = _assert_vector_paths_agree(table, histories)
    assert counts["kernel"] == completed  # as on the thin layer


@pytest.mark.parametrize("scheme", SCHEMES)
def test_kernel_agrees_to_rounding_on_the_half_space_table(monkeypatch, table, scheme):
    """The half-space creep-force table (CreepTable, LAW_TABLE in stepper.c): the same
    Hermite patches, clamp and saturation, summed in another order than numpy's, so the
    two paths agree to rounding: states and forces within 1e-12 of their scales over
    random histories (loads beyond mu P, eta to inf, a held lateral ratio, reversal)."""
    counts = _counting(monkeypatch)
    cap = table.mu * table.P
    rng = np.random.default_rng(5)
    for method in ("full", "quasistationary"):
        for eta in (1.0, math.inf):
            for ry, V0 in ((0.0, 20.0), (0.002, 1e-3), (0.0, -5.0)):
                body, lateral = Body.from_eta(500.0, 0.46, eta), Lateral(vy_ratio=ry)
                a, b = (
                    RollingBody(table, body, lateral, method, V0, V0 / 0.46, scheme=scheme)
                    for _ in range(2)
                )
                b._kernel = None
                for _ in range(40):
                    L = Loads(
                        rng.uniform(-1.3, 1.3) * cap, rng.uniform(-0.3, 0.3) * cap * 0.46, 0, 0
                    )
                    args = (10 ** rng.uniform(-6, -1), L, int(rng.integers(1, 6)))
                    assert _advance(a, args) == _advance(b, args)
                    v = table.creep_full_slip * max(abs(b.y[0]), 1e-9)
                    assert abs(a.y[0] - b.y[0]) <= 1e-12 * max(abs(b.y[0]), 1e-9)
                    assert abs(a.y[1] - b.y[1]) <= 1e-12 * v
                    assert abs(a.out.Tx - b.out.Tx) <= 1e-12 * cap
                    assert abs(a.out.Ty - b.out.Ty) <= 1e-12 * cap
                    assert a.sliding == b.sliding
    assert counts["kernel"] > 0.9 * (counts["kernel"] + counts["python"])


def test_strip_march_of_the_spin_law_agrees_to_rounding(monkeypatch):
    """The thin-layer law with spin (LayerContact.forces, Eqs. 35 and 3-5 marched strip by
    strip): the compiled law and march (cf_layer_forces, its march without spin by the
    magnitude alone, march_straight; cf_strip_march) against numpy on random rolling
    inputs (both directions) in partial slip and gross sliding, an eighth of them
    without spin (the closed form of Eqs. 40-43). |tau| in C is sqrt(a^2 +
    b^2), within two roundings of numpy's complex abs, and the projection on |tau| <=
    mu p does not expand a difference, so along a strip of 64 nodes the tractions differ
    by at most about 128 roundings: 2e-14 of mu p0. The resultants are summed strip by
    strip in C, pairwise in numpy: each differs by at most 3072 roundings of sum w |tau|
    <= mu P (times max(a1, a2) for Mz), and forces takes the difference of two: 7e-13."""
    from contact_fmu.laws.thin_layer import SPIN_GRID

    grid = CONTACT._grid(*SPIN_GRID)
    rng = np.random.default_rng(11)
    n = 400
    Vx = rng.choice([-1.0, 1.0], n) * 10 ** rng.uniform(-2, 1.5, n)
    cs = CONTACT.creep_full_slip
    vx, vy = (rng.uniform(-0.6, 0.6, n) * cs * np.abs(Vx) for _ in range(2))
    phi = rng.uniform(-1.0, 1.0, n) * cs / CONTACT.a1 * np.abs(Vx)
    phi[: n // 8] = 0.0
    assert grid._compiled(CONTACT, vx, vy, Vx, phi) is not None  # the C path is taken
    tau_c, slip_c = grid.march(CONTACT, vx, vy, Vx, phi)
    forces_c = CONTACT.forces(vx, vy, phi, Vx)
    monkeypatch.setattr(native, "_LOADED", {"stepper": None})
    tau_p, slip_p = grid.march(CONTACT, vx, vy, Vx, phi)
    forces_p = CONTACT.forces(vx, vy, phi, Vx)
    g = CONTACT.mu * CONTACT.p0
    # adhesion and slip areas, and inputs in gross sliding, are all covered
    share = slip_p[:, grid.inside].mean(axis=1)
    assert 0.2 < share.mean() < 0.8 and np.any(share == 1.0) and np.any(share < 0.5)
    assert np.abs(tau_c - tau_p).max() <= 2e-14 * g
    assert np.array_equal(slip_c, slip_p)
    F = CONTACT.mu * CONTACT.P
    for a, b, scale in zip(
        forces_c, forces_p, (F, F, F * max(CONTACT.a1, CONTACT.a2)), strict=True
    ):
        assert np.abs(a - b).max() <= 7e-13 * scale


def test_spin_law_for_floats_runs_compiled_and_returns_floats(monkeypatch):
    """LayerContact.forces with float inputs and spin (the scalar stage solves with a
    held spin ratio, the report's reference equations): the compiled law for one input,
    floats out, the same doubles as for a one-element array, and numpy's to the bounds
    of the strip-march test (7e-13 of mu P)."""
    v = (0.01, 0.002, 0.5, -5.0)
    got = CONTACT.forces(*v)
    assert all(type(t) is float for t in got)
    assert got == tuple(float(t[0]) for t in CONTACT.forces(*(np.array([a]) for a in v)))
    monkeypatch.setattr(native, "_LOADED", {"stepper": None})
    ref = CONTACT.forces(*v)
    scale = (F, F, F * max(CONTACT.a1, CONTACT.a2))
    assert all(abs(a - float(b)) <= 7e-13 * s for a, b, s in zip(got, ref, scale, strict=True))


def test_a_law_that_ran_compiled_pickles_and_copies():
    """The compiled law keeps ctypes structs (parameters, the spin grid) on the law and
    its grid; pickle and deepcopy (a host's parallel sweep, an FMU state) leave them out
    and the copy rebuilds them: its forces equal the original's."""
    import copy
    import pickle

    law = ex.contact()
    args = (
        np.array([1e-3, -2e-3]),
        np.array([0.0, 1e-3]),
        np.array([0.5, 0.0]),
        np.array([5.0, -3.0]),
    )
    before = law.forces(*args)
    for twin in (pickle.loads(pickle.dumps(law)), copy.deepcopy(law)):
        assert np.array_equal(np.array(twin.forces(*args)), np.array(before))


def test_both_libraries_build_where_a_compiler_and_python_headers_are():
    """Not a skip in disguise: with cc and Python.h on the machine (CI has both), the
    stepper and the FMI calls' extension must compile and load, or the tests that skip
    without them would pass vacuously."""
    headers = Path(sysconfig.get_paths()["include"], "Python.h").is_file()
    if os.environ.get("CONTACT_FMU_NATIVE") == "0":
        pytest.skip("disabled by CONTACT_FMU_NATIVE=0")
    if shutil.which("cc") is None or not headers or not sys.platform.startswith("linux"):
        pytest.skip("no C compiler or Python headers")
    assert native.library() is not None
    assert native.fmi_module() is not None


# ---- every exported function of stepper.c on extreme doubles ------------------------------
EXTREME = (6e306, 1.2e308, -1.7e308, math.inf, -math.inf, math.nan, 0.0, 5e-324)


def _raw():
    """A second handle on the stepper: the same code, with cf_layer_forces and
    cf_strip_march answering their status (the package's handle ignores it)."""
    import ctypes

    lib = ctypes.CDLL(native.library()._name)
    for name in ("cf_layer_forces", "cf_strip_march"):
        getattr(lib, name).argtypes = getattr(native.library(), name).argtypes
        getattr(lib, name).restype = ctypes.c_int
    for name in ("cf_advance", "cf_body_step", "cf_advance_vector"):
        getattr(lib, name).argtypes = getattr(native.library(), name).argtypes
        getattr(lib, name).restype = ctypes.c_int
    return lib


def _scalar_kernel(method, scheme="lobatto3c"):
    a, _ = _pair(method, 3.0, 5.0, scheme=scheme)
    a._kernel.write(a)
    return a


def test_compiled_step_answers_not_ok_for_extreme_loads_and_steps():
    """A load or step beyond what a double step can hold (My_ex = 6e306 made the drive
    2 A1 My_ex/Rx overflow; with the state at inf the zero spin 0 * Vx became NaN and the
    scalar path marched a spin grid it does not have: a segfault) or a non-finite one:
    cf_advance answers CF_FALLBACK with the state untouched, or OK with a finite state."""
    import ctypes

    lib = _raw()
    for method, scheme in itertools.product(("full", "quasistationary"), SCHEMES):
        a = _scalar_kernel(method, scheme)
        k = a._kernel
        before = bytes(k._state)
        for Fx, My, h in itertools.product(EXTREME, EXTREME, (*EXTREME, -1e-4, 1e-4)):
            for n in (0, -3, 1, 4):
                rc = lib.cf_advance(ctypes.byref(k._params), ctypes.byref(k._state), h, Fx, My, n)
                s = k._state
                if rc == native.OK:
                    assert all(math.isfinite(v) for v in (s.Vx, s.vx, s.t, s.dv, s.Tx, s.Ty, s.Mz))
                    assert h > 0 and n >= 1
                else:
                    assert rc == 1 and bytes(s) == before
                ctypes.memmove(ctypes.byref(s), before, len(before))


def test_compiled_body_step_answers_not_ok_for_extreme_inputs_and_states():
    """cf_body_step (the pythonfmu FMU's doStep in C) with every input of the body FMU
    and every state double extreme: CF_FALLBACK and nothing changed, or OK and finite
    outputs."""
    import ctypes

    lib = _raw()
    model = BodyModelFor(_scalar_kernel("full"))
    fb = model.fast()
    fb.push()
    ptrs = fb._pointers
    state, io = fb._kernel._state, fb.io
    io.P, io.Fx_ex, io.My_ex = CONTACT.P, 0.2 * F, 0.0
    assert lib.cf_body_step(*ptrs, 1e-4) == native.OK  # the covered path
    saved = bytes(state), bytes(io)
    fields = [(io, n) for n in ("P", "Fx_ex", "My_ex", "h_max")] + [
        (state, n) for n in ("Vx", "vx", "t", "dv", "Tx")
    ]
    for (obj, name), x, h in itertools.product(fields, EXTREME, (1e-4, 0.0, -1e-4, math.nan)):
        setattr(obj, name, x)
        mid = bytes(state), bytes(io)
        rc = lib.cf_body_step(*ptrs, h)
        if rc == native.OK:
            assert all(math.isfinite(v) for v in io.out)
        else:
            assert rc == 1 and (bytes(state), bytes(io)) == mid
        ctypes.memmove(ctypes.byref(state), saved[0], len(saved[0]))
        ctypes.memmove(ctypes.byref(io), saved[1], len(saved[1]))
    assert lib.cf_body_step(*ptrs, 1e-4) == native.OK  # usable after all that


def BodyModelFor(rb):
    from contact_fmu.fmu.body_model import BodyModel

    return BodyModel(rb, 2.5e-5, rb.law.P)


@pytest.mark.parametrize("scheme", SCHEMES)
@pytest.mark.parametrize("lateral", VECTOR_PATHS)
def test_compiled_vector_step_answers_not_ok_for_extreme_loads(lateral, scheme):
    """cf_advance_vector (Vy and/or Omega_z as unknowns, the spin law's march) with
    extreme loads, steps and states: CF_FALLBACK with the state untouched, or OK and
    finite."""
    import ctypes

    lib = _raw()
    body = Body.from_eta(1.0, 0.05, 3.0, Iz=2e-3)
    rb = RollingBody(CONTACT, body, lateral, "full", 5.0, 5.0 / 0.05 * 0.999, scheme=scheme)
    k = rb._kernel
    k.write(rb)
    before = bytes(k._state)
    L = (ctypes.c_double * 4)()
    rng = np.random.default_rng(5)
    for _ in range(300):
        L[:] = [float(rng.choice(EXTREME)) if rng.uniform() < 0.5 else 0.1 * F for _ in range(4)]
        field = str(rng.choice(["Vx", "vx", "Vy", "Oz", "dv"]))
        setattr(k._state, field, float(rng.choice(EXTREME)))
        mid = bytes(k._state)
        h = float(rng.choice((*EXTREME, 1e-4)))
        rc = lib.cf_advance_vector(ctypes.byref(k._params), ctypes.byref(k._state), h, L, 2)
        s = k._state
        if rc == native.OK:
            assert all(math.isfinite(v) for v in (s.Vx, s.vx, s.Vy, s.Oz, s.Tx, s.Ty, s.Mz))
        else:
            assert rc == 1 and bytes(s) == mid
        ctypes.memmove(ctypes.byref(s), before, len(before))


def test_compiled_layer_law_and_march_answer_not_ok_for_extreme_inputs():
    """cf_layer_forces and cf_strip_march (spin included) on every combination of
    extreme inputs: no crash, and either finite results or CF_FALLBACK."""
    from contact_fmu.laws.thin_layer import SPIN_GRID

    lib = _raw()
    law = ex.contact()
    law.forces(np.array([1e-3]), np.array([0.0]), np.array([0.5]), np.array([5.0]))  # params
    strips = law.native_strips()
    grid = law._grid(*SPIN_GRID)
    field = grid.y.size * grid.x.size
    vals = (*EXTREME, 1e-3, -2.0)
    combos = np.array(list(itertools.product(vals, repeat=4)))
    vx, vy, phi, Vx = (np.ascontiguousarray(combos[:, i]) for i in range(4))
    n = vx.size
    out = np.empty((n, 3))
    rc = lib.cf_layer_forces(
        law._native_params, strips, n, *(a.ctypes.data for a in (vx, vy, phi, Vx)), out.ctypes.data
    )
    good = np.isfinite(combos).all(axis=1) & (Vx != 0.0)
    assert rc == 1  # some inputs are not finite
    assert np.isnan(out[~good]).all()
    # finite inputs: finite forces (|T| <= mu P), or NaN where a march overflowed; with
    # subnormal slips the direction v/|v| rounds off the unit circle (in Python's
    # _forces_scalar alike): the bound only for zero or normal inputs
    normal = ((combos == 0.0) | (np.abs(combos) >= 2.2250738585072014e-308)).all(axis=1)
    ok = good & normal & np.isfinite(out).all(axis=1)
    assert np.all(np.hypot(out[ok, 0], out[ok, 1]) <= F * (1 + 1e-12))
    for row in range(0, n, 97):  # the march field by field, a sample of the combinations
        one = [np.ascontiguousarray(a[row : row + 1]) for a in (vx, vy, Vx, phi)]
        tau = np.empty(2 * field)
        slip = np.empty(field, np.uint8)
        rc = lib.cf_strip_march(strips, 1, *(a.ctypes.data for a in one), tau.ctypes.data,
                                slip.ctypes.data)  # fmt: skip
        assert rc == 1 or np.isfinite(tau).all()
        assert rc in (0, 1)


def glibc_needed(path) -> tuple[int, ...]:
    """The newest GLIBC_x.y symbol version the shared library at ``path`` needs
    (``objdump -T``), as a tuple; () if none."""
    import re
    import subprocess

    text = subprocess.run(["objdump", "-T", str(path)], capture_output=True, text=True, check=True)
    found = {tuple(map(int, v.split("."))) for v in re.findall(r"GLIBC_([0-9.]+)\)", text.stdout)}
    return max(found, default=())


# manylinux2014's floor (CentOS 7); RHEL/Rocky 8 have 2.28, 9 has 2.34
GLIBC_FLOOR = (2, 17)


@pytest.mark.skipif(shutil.which("objdump") is None, reason="no objdump")
def test_shipped_libraries_need_no_c_library_newer_than_2_17():
    """The stepper and the FMI calls' extension (both shipped in every pythonfmu FMU)
    load on hosts with glibc 2.17: hypot and pow are bound to their old symbol versions
    (stepper.c), which compute the same values."""
    paths = [native.library()._name]
    if native.fmi_module() is not None:
        paths.append(native.fmi_module().__file__)
    for path in paths:
        need = glibc_needed(path)
        assert (2, 2) <= need <= GLIBC_FLOOR, (path, need)


@pytest.mark.parametrize("scheme", SCHEMES)
def test_c_bracket_fallback_gives_the_python_paths_doubles(monkeypatch, scheme):
    """Where the stage's safeguarded Newton iteration does not converge (78 of the 2400
    steps of the random histories: steps to 10 s, speeds to rest), Python brackets the
    root and calls scipy's brentq (solvers.increasing_root); with ``bracket`` set (the
    native FMU) the kernel does the same in C (stepper.c: increasing_root, brentq with
    the operations of scipy's brentq.c) and gives the Python path's doubles there too:
    it takes every step that the Python path takes."""
    counts = _counting(monkeypatch)
    rng = np.random.default_rng(7)
    taken_by_python = 0
    for a, b, args in _histories(rng, scheme=scheme):
        if not a._kernel._params.bracket:
            a._kernel.params(a)
            a._kernel._params.bracket = 1
            a._kernel._params.max_expansions = solvers.MAX_EXPANSIONS
        before = counts["python"]
        error = _advance(a, args)
        assert error == _advance(b, args)
        assert np.array_equal(a.y, b.y) and a.t == b.t and a._dv == b._dv
        assert a.out == b.out and a.sliding == b.sliding
        taken_by_python += counts["python"] > before and error is None
    # left to Python: only the steps that fail there too (no root: eta = inf beyond mu P)
    assert taken_by_python == 0 and counts["kernel"] > 2000, counts


# ---- SDIRK2 on the compiled path: its order and its L-stability ---------------------------
def _sdirk2_run(lateral: Lateral, loads, dt: float, steps: int, n: int) -> np.ndarray:
    """The states (Vx, vx, Vy, Omega_z) of the Fig. 13 body (eta = 3) from pure rolling
    at the speed unit, SDIRK2 in n substeps per step dt under loads(t) held over each."""
    V0 = ex.speed_unit()
    rb = RollingBody(CONTACT, ex.body(3.0), lateral, "full", V0, V0 / ex.Rx, scheme="sdirk2")
    ys = [rb.y.copy()]
    for k in range(steps):
        rb.advance(dt, loads(k * dt), n)
        ys.append(rb.y.copy())
    return np.array(ys)


SDIRK2_PATHS = (ROLLING_STRAIGHT, Lateral(vy_ratio=None))  # cf_advance, cf_advance_vector


@pytest.mark.parametrize("lateral", SDIRK2_PATHS)
def test_compiled_sdirk2_converges_at_second_order(monkeypatch, lateral):
    """SDIRK2 is second order (Hairer & Wanner IV.6; Alexander 1977). Fig. 13's loads
    (Fx_ex = F, My_ex = 0.2 F Rx sin(t/T_c), on the vector path Fy_ex = 0.3 F sin(t/T_c))
    held over communication steps of T_c/80, a quarter of T_c, in 20, 40 and 80 substeps
    (0.4 to 0.1 relaxation times); the reference takes 640. Each communication interval
    is smooth and the grid holds its ends, so the slip's error falls by 4 per halving:
    observed order 2 +- 0.2 in vx (and Vy), measured 2.02-2.03. Every step compiled."""
    counts = _counting(monkeypatch, native.Kernel)
    counts_v = _counting(monkeypatch, native.VectorKernel)
    F_unit, TC = ex.force_unit(), ex.time_unit()

    def loads(t):
        s = math.sin(t / TC)
        return Loads(F_unit, 0.3 * F_unit * s * lateral.dynamic_vy, 0.2 * F_unit * ex.Rx * s, 0)

    run = partial(_sdirk2_run, lateral, loads, TC / 80, 20)
    ref = run(640)
    unknowns = [1, 2] if lateral.dynamic_vy else [1]
    errs = np.array(
        [np.abs(run(n)[:, unknowns] - ref[:, unknowns]).max(axis=0) for n in (20, 40, 80)]
    )
    orders = np.log2(errs[:-1] / errs[1:])
    assert np.all((orders > 1.8) & (orders < 2.2)), orders
    assert counts["python"] == counts_v["python"] == 0
    assert counts["kernel"] + counts_v["kernel"] == 4 * 20


@pytest.mark.parametrize("lateral", SDIRK2_PATHS)
@pytest.mark.parametrize("ratio", [1e2, 1e4, 1e8])
def test_compiled_sdirk2_damps_the_fast_mode_at_any_step(monkeypatch, lateral, ratio):
    """L-stability: under a held load (Fx_ex = F; on the vector path Fy_ex = 0.3 F too)
    six steps of h = ratio tau_r, one substep each, against the same run in 256
    substeps. Per step the deviation of the creepages (vx/Vx[, Vy/Vx]) from the slow
    manifold is multiplied by SDIRK2's R(z) = (1 + (1 - 2 gamma) z)/(1 - gamma z)^2,
    z = -h/tau, tau the slowest fast mode's time at the step's end: the slip's M A2 Vx /
    (dTx/dxi) alone, on the vector path the lateral one, M Vx / (dTy/dxi) (the thin
    layer is isotropic: the same slope), with 20 % for the law's nonlinearity and 8 eps
    of rounding. The forces stay within mu P. Every step compiled."""
    counts = _counting(monkeypatch, native.Kernel)
    counts_v = _counting(monkeypatch, native.VectorKernel)
    F_unit, V0 = ex.force_unit(), ex.speed_unit()
    body = ex.body(3.0)
    dt = ratio * body.m_slip * V0 / CONTACT.creep_slope
    L = Loads(F_unit, 0.3 * F_unit * lateral.dynamic_vy, 0.0, 0.0)
    coarse = _sdirk2_run(lateral, lambda t: L, dt, 6, 1)
    fine = _sdirk2_run(lateral, lambda t: L, dt, 6, 256)
    dev = np.hypot(*((coarse[:, k] - fine[:, k]) / coarse[:, 0] for k in (1, 2)))
    dev[0] = np.hypot(fine[1, 1], fine[1, 2]) / fine[1, 0]  # pure rolling at the start
    mass = body.M if lateral.dynamic_vy else body.m_slip
    g = 1.0 - 0.5 * math.sqrt(2.0)
    for k in range(6):
        z = -dt * CONTACT.creep_slope / (mass * coarse[k + 1, 0])
        R = (1.0 + (1.0 - 2.0 * g) * z) / (1.0 - g * z) ** 2
        assert dev[k + 1] <= 1.2 * abs(R) * dev[k] + 8 * np.finfo(float).eps, (k, dev)
    assert counts["python"] == counts_v["python"] == 0
    assert counts["kernel"] + counts_v["kernel"] == 12


def test_c_sources_compile_without_warnings(tmp_path):
    """stepper.c, fmi.c and the native FMU's C files (with the generated headers of the
    body FMU with Eqs. 10-11, of the half-space table's and of the full contact FMU: the
    model parts the header switches on) under -Wall -Wextra -Werror and the flags they ship with: a
    warning there is a defect left for a user's compiler to find."""
    import subprocess

    from contact_fmu.fmu.config import ModelConfig
    from contact_fmu.scenario import load
    from fmu_build import native_fmu

    strict = ("-Wall", "-Wextra", "-Werror")
    cc = os.environ.get("CC", "cc")
    runs = [[*native.KERNEL_FLAGS, *strict, "-o", str(tmp_path / "s.so"), str(native.SOURCE)]]
    if Path(sysconfig.get_paths()["include"], "Python.h").is_file():
        runs.append([*native._fmi_flags(), *strict, "-o", str(tmp_path / "f.so"),
                     str(native.SOURCE_FMI)])  # fmt: skip
    scenes = Path(__file__).resolve().parents[1] / "scenarios"
    cfgs = {s: load(scenes / f"{s}.toml").config for s in ("cornering", "rail_traction")}
    for name, cfg in (cfgs | {"contact": ModelConfig.full("contact")}).items():
        src = tmp_path / name
        src.mkdir()
        for source in native_fmu.SOURCES:
            shutil.copyfile(native_fmu.NATIVE_DIR / source, src / source)
        (src / native_fmu.HEADER).write_text(native_fmu.header(cfg, "{}"))
        units = [str(src / n) for n in native_fmu.c_files()]
        runs.append([*native_fmu.CFLAGS, *strict, f"-I{src}", f"-I{native_fmu.fmi_headers()}",
                     "-o", str(src / "m.so"), *units])  # fmt: skip
    for args in runs:
        proc = subprocess.run([cc, *args, "-lm"], capture_output=True, text=True)
        assert proc.returncode == 0, proc.stderr[-3000:]
