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
from pathlib import Path

import numpy as np
import pytest

from contact_fmu import examples as ex
from contact_fmu import native, solvers
from contact_fmu.dynamics import ROLLING_STRAIGHT, Body, Lateral, Loads
from contact_fmu.integrator import RollingBody

pytestmark = pytest.mark.skipif(native.library() is None, reason="no C compiler")

CONTACT = ex.contact()
F = CONTACT.mu * CONTACT.P


def _pair(method: str, eta: float, V0: float, lateral: Lateral = ROLLING_STRAIGHT):
    body = Body.from_eta(1.0, 0.05, eta)
    a, b = (
        RollingBody(CONTACT, body, lateral, method=method, Vx0=V0, Omega_y0=V0 / 0.05 * 0.999)
        for _ in range(2)
    )
    b._kernel = None  # the Python path
    assert a._kernel is not None
    return a, b


def _histories(rng, lateral: Lateral = ROLLING_STRAIGHT):
    """Random load histories over the covered path: loads to 1.5 mu P (gross sliding),
    steps from 1e-8 to 10 s, 1-7 substeps, speeds from 5 m/s to rest and reversed,
    load changes; yields (a, b, advance args) for each step."""
    for method in ("full", "quasistationary"):
        for eta in (1.0, 3.0, 1e3, math.inf):
            for V0 in (5.0, 1e-3, 1e-8, 0.0, -2.0):
                a, b = _pair(method, eta, V0, lateral)
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


def test_kernel_gives_the_python_paths_doubles_without_lateral_slip(monkeypatch):
    counts = _counting(monkeypatch)
    rng = np.random.default_rng(7)
    for a, b, args in _histories(rng):
        assert _advance(a, args) == _advance(b, args)
        assert np.array_equal(a.y, b.y) and a.t == b.t and a._dv == b._dv
        assert a.out == b.out and a.sliding == b.sliding
    # the kernel took the steps (a test of the fallback alone would pass vacuously)
    assert counts["kernel"] > 0.9 * (counts["kernel"] + counts["python"])


@pytest.mark.parametrize("vy_ratio", [0.002, -0.01, 0.3])
def test_kernel_agrees_to_rounding_with_a_held_lateral_ratio(vy_ratio):
    rng = np.random.default_rng(11)
    scale = F
    for a, b, args in _histories(rng, Lateral(vy_ratio=vy_ratio)):
        assert _advance(a, args) == _advance(b, args)
        v = CONTACT.creep_full_slip * max(abs(b.y[0]), 1e-9)  # the stage solves' scale
        assert abs(a.y[0] - b.y[0]) <= 1e-12 * max(abs(b.y[0]), 1e-9)
        assert abs(a.y[1] - b.y[1]) <= 1e-11 * v
        assert abs(a.out.Tx - b.out.Tx) <= 1e-11 * scale
        assert abs(a.out.Ty - b.out.Ty) <= 1e-11 * scale
        assert a.sliding == b.sliding and a.t == b.t


def test_paths_the_kernel_leaves_out_step_in_python():
    body = Body.from_eta(1.0, 0.05, 3.0)
    dynamic_vy = Lateral(vy_ratio=None)
    assert RollingBody(CONTACT, body, scheme="sdirk2")._kernel is None
    assert RollingBody(CONTACT, body, Lateral(spin_ratio=1.0))._kernel is None
    assert RollingBody(CONTACT, body, dynamic_vy, scheme="sdirk2")._kernel is None
    for method in ("full", "quasistationary"):
        a = RollingBody(CONTACT, body, dynamic_vy, method=method)
        assert type(a._kernel) is native.VectorKernel


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
    import contact_fmu.integrator as integrator

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


def _vector_histories(law, rng, body_of, V0s, steps, method="full"):
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
    mu P / scale: 1e-12 of mu P (of mu P a1 for Mz). Returns the number of steps that
    completed."""
    cap = law.mu * law.P
    completed = 0
    for a, b, args in histories:
        ea, eb = _advance(a, args), _advance(b, args)
        if ea is not None and ea[0] == "StageSolveError" == eb[0]:
            # both fail alike; after "hybr:" scipy's diagnostic of its last iterate, which
            # differs where the states before the step differ by rounding
            ea, eb = ea[1].split(":")[0], eb[1].split(":")[0]
        assert ea == eb
        assert a.sliding == b.sliding  # the quasistationary regime
        v = law.creep_full_slip * max(abs(b.y[0]), 1e-9)  # the stage solves' scale
        assert abs(a.y[0] - b.y[0]) <= 1e-12 * max(abs(b.y[0]), 1e-9)
        for k, unit in ((1, v), (2, v), (3, v / law.a1)):
            assert abs(a.y[k] - b.y[k]) <= 1e-12 * (abs(b.y[k]) + unit)
        assert abs(a.out.Tx - b.out.Tx) <= 1e-12 * cap
        assert abs(a.out.Ty - b.out.Ty) <= 1e-12 * cap
        assert abs(a.out.Mz - b.out.Mz) <= 1e-12 * cap * law.a1
        assert a.out.sliding == b.out.sliding and a.t == b.t
        # _dv = (vx - vx_n)/dt of the last substep dt: the vx bound over dt, twice (a
        # step that raised left the _dv of the step before, checked with its own dt)
        dt = args[0] / args[2]
        assert ea is not None or abs(a._dv - b._dv) <= 2e-12 * (abs(b.y[1]) + v) / dt
        completed += ea is None
    return completed


@pytest.mark.parametrize("method", ["full", "quasistationary"])
def test_vector_kernel_agrees_with_the_python_path_on_the_thin_layer(monkeypatch, method):
    """Eqs. (8)-(11) with the thin-layer law and spin (the strip march in the stage
    residuals): the compiled Lobatto IIIC vector step (cf_advance_vector) against
    RollingBody._lobatto_vector; quasistationary: the algebraic stage T(u2) = F2 while
    rolling, the Lobatto stages in gross sliding (loads to 1.2 mu P), and the regime
    (RollingBody._step, _update_regime, advance's one step under held loads)."""
    counts = _counting(monkeypatch, native.VectorKernel)
    histories = _vector_histories(
        CONTACT,
        np.random.default_rng(3),
        lambda eta: Body.from_eta(1.0, 0.05, eta, Iz=2e-3),
        V0s=(5.0, 1e-3, -2.0),
        steps=12,
        method=method,
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


@pytest.mark.parametrize("method", ["full", "quasistationary"])
def test_vector_kernel_agrees_with_the_python_path_on_the_half_space_table(
    monkeypatch, table, method
):
    """The same on the creep-force table with spin (table_scalar with phi): the vector
    step of a railway wheel against RollingBody._lobatto_vector, both methods."""
    counts = _counting(monkeypatch, native.VectorKernel)
    histories = _vector_histories(
        table,
        np.random.default_rng(4),
        lambda eta: Body.from_eta(500.0, 0.46, eta, Iz=50.0),
        V0s=(20.0, -5.0),
        steps=10,
        method=method,
    )
    completed = _assert_vector_paths_agree(table, histories)
    assert counts["kernel"] == completed  # as on the thin layer


def test_kernel_agrees_to_rounding_on_the_half_space_table(monkeypatch, table):
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
                    RollingBody(table, body, lateral, method=method, Vx0=V0, Omega_y0=V0 / 0.46)
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
    from contact_fmu.layer import SPIN_GRID

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
