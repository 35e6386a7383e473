"""Reference solutions of a scene's case, computed outside the FMU to tight tolerance.

Each reference is produced for two readings of the inputs:

- *continuous*: the scene's input signals as functions of time, what the co-simulation
  approximates (its error includes the zero-order hold of the inputs over each
  communication step, first order in the step);
- *held*: the inputs sampled on the communication grid and held over each step, as the
  FMU receives them from fmpy (its error is the FMU's own time integration).

Sources, by model:

- body mode, ``method = "full"``: scipy's ``solve_ivp`` (Radau IIA, order 5, rtol
  RTOL) on Eqs. (8)-(11) (``equations.RollingEquations``), restarted at every jump or
  kink of the inputs (the signals' breakpoints; every grid point for held inputs);
- body mode, ``method = "quasistationary"``: the closed form, Tx of Eq. (26),
  Vx(t) = Vx(0) + (A1/M) int (Fx_ex + My_ex/Rx) dt and vx = |Vx| T_x^-1(Tx) of
  Eq. (28) (the integral by scipy's ``quad``, exact sums for held inputs);
- body mode, phase "transient": the thin-layer field of Eq. (15) with its time
  derivative, coupled with Eqs. (8)-(11) (``thin_layer_field.TransientRollingBody``, outside
  the FMU) on TRANSIENT_REFINE and 2 TRANSIENT_REFINE times the scene's grid (nx, ny)
  at its cells_per_step (the internal step refined with the cell), combined by
  Richardson's extrapolation for a second-order method, R = R_f + (R_f - R_c)/3
  (docs/transient.md: second order in the cell, 1.9-2.0 measured);
- contact mode, thin-layer law: the resultant of the traction of Eq. (36) (|tau| =
  min((l - x)|v| / (|Vx| k), mu p)) integrated by nested ``quad`` over the ellipse, at
  up to CONTACT_SAMPLES points per case: independent of the closed form H(beta) of
  Eqs. (40)-(43) that the FMU evaluates;
- contact mode, half-space law: direct solves of the steady-rolling problem
  (``HalfSpaceContact`` of the scene's [halfspace] declaration, on the solver grid of
  its table) at the same points, (Tx, Ty) mapped by the table's radial saturation
  (``halfspace.table.saturate``, the C1 cap at mu P): the law the table converges to
  as its nodes are refined, independent of its interpolation.

Values at a communication point are those at the end of the step that reaches it: the
left limit where an input jumps there.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy import integrate

from ..dynamics.body import Loads
from ..dynamics.kinematics import rigid_slip
from ..fmu.factory import initial_state, make_body, make_lateral, make_law, thin_layer_law
from ..laws.thin_layer import LayerContact
from ..scenario.schema import Case, Scene
from .equations import RollingEquations, quasistationary_force, quasistationary_slip

FloatArray = NDArray[np.float64]

# solve_ivp (Radau) relative tolerance, and absolute tolerances as fractions of the
# speed and of the slip scale: the reference's error is then below 1e-9 of the slip
# scale and mu P, far below the FMU errors the report resolves (>= 1e-8).
RTOL = 1e-11
ATOL_FRACTION = 1e-13
# Contact mode: reference points per case (each is a nested quadrature, ~10 ms).
CONTACT_SAMPLES = 41
# Nested quadrature tolerance (relative) of the contact-mode reference.
QUAD_RTOL = 1e-12
# Transient phase: the reference fields are on this factor and twice it times the
# scene's grid. Measured on fig12_transient (eta = 10.9, first ms, against the
# extrapolation from 128 x 64 and 256 x 128): the extrapolation from 64 x 32 and
# 128 x 64 is within 1.2e-4 of v_s in vx and 4.6e-5 of mu P in Tx, 128 x 64 alone
# within 7.5e-4 and 2.5e-4 (docs/performance.md).
TRANSIENT_REFINE = 2
LOAD_NAMES = ("P", "Fx_ex", "Fy_ex", "My_ex", "Mz_ex")
KINEMATICS = ("P", "Vx", "Vy", "Omega_y", "Omega_z")


class NoReferenceError(ValueError):
    """The setting has no reference here; the message says why."""


@dataclass(frozen=True)
class Solution:
    """Reference values on the times ``time`` (s): Tx (N), vx (m/s), Vx (m/s), and Ty (N)
    where the reference has it."""

    time: FloatArray
    Tx: FloatArray
    vx: FloatArray
    Vx: FloatArray
    Ty: FloatArray | None = None


# ---- case data ------------------------------------------------------------------------
# The law, the body, its lateral motion and its initial state are the FMU's (fmu.factory):
# the references integrate the model the FMU runs. What stays independent of the FMU on
# purpose is how they integrate it: equations.py writes Eqs. (8)-(11) and the closed forms
# of Eqs. (26), (28) from the paper for scipy, and traction_resultant integrates the
# traction of Eq. (36) by quadrature instead of the law's closed form H(beta).
def scene_law(scene: Scene, p: dict, P: float) -> Any:
    """The scene's contact law (a ContactLaw) under the load P (N); the half-space law as
    its FMU evaluates it: the creep-force table the build generates for the scene's
    [halfspace] declaration (fmu_build.tables, cached; the table's own accuracy is
    measured apart: docs/halfspace.md)."""
    table = None
    if scene.config.has_table:
        try:
            from fmu_build import tables

            table = tables.ensure(scene.config)
        except ImportError as e:
            raise NoReferenceError(f"{scene.name}: no half-space table outside the FMU: {e}") from e
    return make_law(scene.config, p, P, table=table)


def _require_steady(scene: Scene) -> None:
    if scene.config.phase != "steady":
        raise NoReferenceError(
            f"{scene.name}: no reference for phase = {scene.config.phase!r} (the references "
            "integrate the steady law)"
        )


def signal_values(case: Case, names: tuple[str, ...], t: FloatArray) -> dict[str, FloatArray]:
    """The case's inputs ``names`` at times t (0 where the case has no such input)."""
    return {n: case.inputs[n](t) if n in case.inputs else np.zeros_like(t) for n in names}


def breakpoints(case: Case, t_end: float) -> list[float]:
    """Times in (0, t_end) where an input jumps or has a kink."""
    pts = {b for s in case.inputs.values() for b in s.breakpoints}
    return sorted(b for b in pts if 0.0 < b < t_end)


def _inside(a: float, b: float) -> Callable[[float], float]:
    """Clip times into the open segment (a, b): inputs are taken from inside it, so a jump
    at an end counts for the segment on its side."""
    lo, hi = np.nextafter(a, b), np.nextafter(b, a)
    return lambda t: min(max(t, lo), hi)


# ---- body mode: Eqs. (8)-(11) by Radau -----------------------------------------------------
def _loads_of(case: Case, clip: Callable[[float], float]):
    sig = [case.inputs.get(n) for n in LOAD_NAMES]

    def loads(t: float) -> tuple[float, float, float, float, float]:
        tt = np.array([clip(t)])
        return tuple(float(s(tt)[0]) if s is not None else 0.0 for s in sig)  # type: ignore[return-value]

    return loads


def _constant_loads(values: tuple[float, ...]):
    return lambda _t: values


def _integrate(
    scene: Scene,
    case: Case,
    segments: list[tuple[float, float, Callable]],
    times: FloatArray,
) -> Solution:
    """Radau over consecutive segments (a, b, loads); outputs at ``times`` in (a, b] of
    each segment (the left limit at b), and the initial state at t = 0."""
    p = case.parameters
    P0 = segments[0][2](0.0)[0]
    lateral = make_lateral(scene.config, p)
    base = RollingEquations(scene_law(scene, p, P0), make_body(p), lateral, segments[0][2])
    y = base.initial(**initial_state(p))
    v_scale = base.law.creep_full_slip * max(abs(p["Vx0"]), 1e-3)
    atol = np.full(base.size, ATOL_FRACTION * v_scale)
    atol[0] = ATOL_FRACTION * max(abs(p["Vx0"]), 1e-3)
    out = np.empty((times.size, 4))  # Vx, vx, Tx, Ty
    k = 0
    while k < times.size and times[k] <= 0.0:
        out[k] = (y[0], y[1], *base.forces(0.0, y)[:2])
        k += 1
    for a, b, loads in segments:
        eq = RollingEquations(base.law, base.body, base.lateral, loads)
        stop = int(np.searchsorted(times, b, side="right"))
        t_eval = times[k:stop]
        # the segment's end is always evaluated: the next segment starts from it
        ends = t_eval.size > 0 and t_eval[-1] == b
        t_all = t_eval if ends else np.append(t_eval, b)
        sol = integrate.solve_ivp(
            eq.rhs, (a, b), y, method="Radau", rtol=RTOL, atol=atol, t_eval=t_all
        )
        if sol.status != 0:
            raise RuntimeError(
                f"{scene.name}/{case.name}: Radau failed on [{a}, {b}]: {sol.message}"
            )
        for j, t in enumerate(t_eval):
            yj = sol.y[:, j]
            out[k + j] = (yj[0], yj[1], *eq.forces(t, yj)[:2])
        k = stop
        y = sol.y[:, -1]
    return Solution(times.copy(), out[:, 2], out[:, 1], out[:, 0], out[:, 3])


def full_continuous(scene: Scene, case: Case, times: FloatArray) -> Solution:
    """Eqs. (8)-(11) under the continuous input signals, at ``times`` (sorted, from 0)."""
    _require_full(scene, case)
    t_end = float(times[-1])
    edges = [0.0, *breakpoints(case, t_end), t_end]
    segments = [
        (a, b, _loads_of(case, _inside(a, b))) for a, b in zip(edges, edges[1:], strict=False)
    ]
    return _integrate(scene, case, segments, times)


def full_held(scene: Scene, case: Case, grid: FloatArray) -> Solution:
    """Eqs. (8)-(11) with the inputs sampled on ``grid`` and held over each step."""
    _require_full(scene, case)
    u = signal_values(case, LOAD_NAMES, grid)
    segments = [
        (
            float(grid[k]),
            float(grid[k + 1]),
            _constant_loads(tuple(float(u[n][k]) for n in LOAD_NAMES)),
        )
        for k in range(grid.size - 1)
    ]
    return _integrate(scene, case, segments, grid)


def _require_full(scene: Scene, case: Case) -> None:
    _require_steady(scene)
    if scene.config.mode != "body":
        raise NoReferenceError(f"{scene.name}: Eqs. (8)-(11) are the body mode's")
    if case.parameters["Iy"] == 0.0:
        raise NoReferenceError(f"{scene.name}/{case.name}: eta = inf (Iy = 0) has no ODE reference")


# ---- body mode, phase "transient": the field on finer grids, extrapolated ------------------------
def _require_transient(scene: Scene) -> None:
    cfg = scene.config
    if cfg.mode != "body" or cfg.phase != "transient" or cfg.contact_law != "layer":
        raise NoReferenceError(f"{scene.name}: the field reference is the transient thin layer's")


def transient_grids(case: Case) -> tuple[tuple[int, int], tuple[int, int]]:
    """The (nx, ny) of the two reference fields: TRANSIENT_REFINE and twice that times
    the case's grid."""
    from ..dynamics.thin_layer_field import DEFAULT_NX, DEFAULT_NY

    p = case.parameters
    nx, ny = int(p.get("nx", DEFAULT_NX)), int(p.get("ny", DEFAULT_NY))
    return (TRANSIENT_REFINE * nx, TRANSIENT_REFINE * ny), (
        2 * TRANSIENT_REFINE * nx,
        2 * TRANSIENT_REFINE * ny,
    )


def _transient_run(
    scene: Scene, case: Case, times: FloatArray, nx: int, ny: int, continuous: bool
) -> Solution:
    """Eqs. (8)-(11) on the thin-layer field of Eq. (15) (TransientRollingBody) on an
    nx x ny grid, stepped over the communication steps of ``times`` as the FMU steps
    them: max(ceil(h/h_max), steps of cells_per_step cells) internal steps, the load P
    of the step's start. The other loads held over each step, or (``continuous``) the
    signals sampled at the stage times."""
    from ..dynamics.thin_layer_field import TransientRollingBody
    from ..fmu.body_model import substeps

    p = case.parameters
    u = signal_values(case, LOAD_NAMES, times)
    if continuous and np.ptp(u["P"]) != 0.0:
        raise NoReferenceError(
            f"{scene.name}/{case.name}: the transient field takes P per step (no continuous P)"
        )
    tb = TransientRollingBody(
        scene_law(scene, p, float(u["P"][0])), make_body(p), make_lateral(scene.config, p),
        **initial_state(p), nx=nx, ny=ny,
    )  # fmt: skip
    cells = float(p.get("cells_per_step", 0.5))
    out = np.empty((times.size, 4))  # Tx, Ty, vx, Vx

    def record(k: int) -> None:
        o = tb.outputs()
        out[k] = (o["Tx"], o["Ty"], o["vx"], o["Vx"])

    record(0)
    for k in range(times.size - 1):
        h = float(times[k + 1] - times[k])
        if u["P"][k] != tb.law.P:
            tb.set_load(float(u["P"][k]))
        n = max(substeps(h, p["h_max"]), tb.substeps_for(h, cells))
        if continuous:
            t0 = float(times[k])
            loads = _loads_of(case, _inside(t0, t0 + h))
            tb.advance(h, lambda t, f=loads: Loads(*f(t)[1:]), n)
        else:
            tb.advance(h, Loads(*(float(u[m][k]) for m in LOAD_NAMES[1:])), n)
        record(k + 1)
    return Solution(times.copy(), out[:, 0], out[:, 2], out[:, 3], out[:, 1])


def _transient(scene: Scene, case: Case, times: FloatArray, continuous: bool) -> Solution:
    """Richardson's extrapolation of the fields on the two grids of ``transient_grids``
    (second order): R = R_f + (R_f - R_c)/3."""
    _require_transient(scene)
    (nc, mc), (nf, mf) = transient_grids(case)
    coarse = _transient_run(scene, case, times, nc, mc, continuous)
    fine = _transient_run(scene, case, times, nf, mf, continuous)

    def extrapolate(name: str) -> FloatArray:
        f, c = getattr(fine, name), getattr(coarse, name)
        return f + (f - c) / 3.0

    return Solution(
        times.copy(),
        extrapolate("Tx"),
        extrapolate("vx"),
        extrapolate("Vx"),
        extrapolate("Ty"),
    )


def transient_continuous(scene: Scene, case: Case, times: FloatArray) -> Solution:
    """The transient field under the continuous load signals (constant P), at ``times``."""
    return _transient(scene, case, times, continuous=True)


def transient_held(scene: Scene, case: Case, grid: FloatArray) -> Solution:
    """The transient field with the loads sampled on ``grid`` and held over each step."""
    return _transient(scene, case, grid, continuous=False)


# ---- body mode: the quasistationary closed form ------------------------------------------------
def quasistationary_allowed(scene: Scene, case: Case, times: FloatArray) -> str | None:
    """None if Eqs. (26), (28) describe the case: rolling straight or at a held lateral
    ratio without spin, loads inside the admissible region (Eq. 27) at every sample of
    ``times`` and the breakpoints; else the reason."""
    cfg = scene.config
    if cfg.mode != "body":
        return "contact mode has no stepper"
    if cfg.phase != "steady" or cfg.contact_law != "layer":
        return "the closed form (inverse creep law) is the steady thin-layer law's"
    if cfg.vy == "eq10" or cfg.spin != "zero":
        return "no closed form with Eq. (10), Eq. (11) or spin"
    p = case.parameters
    t = np.union1d(times, breakpoints(case, float(times[-1])))
    u = signal_values(case, LOAD_NAMES, t)
    b = make_body(p)
    Tx = quasistationary_force(b, u["Fx_ex"], u["My_ex"])
    utilisation = np.abs(Tx) / (p["mu"] * u["P"])
    if np.any(utilisation >= 1.0):
        i = int(np.argmax(utilisation))
        return (
            f"loads beyond mu P (Eq. 27: {utilisation[i]:.3g} at t = {t[i]:.6g} s): gross sliding"
        )
    return None


def _quasistationary(scene: Scene, case: Case, times: FloatArray, Tx, P, Vx) -> Solution:
    p = case.parameters
    ratio = p.get("vy_ratio", 0.0) if scene.config.vy == "ratio" else 0.0
    base = thin_layer_law(p, float(P[0]))
    vx = np.empty(times.size)
    for k in range(times.size):
        lk = base if P[k] == base.P else base.with_load(float(P[k]))
        xi_y = ratio * math.copysign(1.0, Vx[k]) if Vx[k] != 0.0 else 0.0
        vx[k] = quasistationary_slip(lk, float(Tx[k]), float(Vx[k]), xi_y)
    return Solution(times.copy(), np.asarray(Tx, float), vx, np.asarray(Vx, float))


def quasistationary_continuous(scene: Scene, case: Case, times: FloatArray) -> Solution:
    """Eqs. (26), (28) under the continuous signals (left limits at the grid points)."""
    why = quasistationary_allowed(scene, case, times)
    if why:
        raise NoReferenceError(f"{scene.name}/{case.name}: {why}")
    p = case.parameters
    b = make_body(p)
    left = np.array([np.nextafter(t, -np.inf) if t > 0 else t for t in times])
    u = signal_values(case, LOAD_NAMES, left)
    Tx = quasistationary_force(b, u["Fx_ex"], u["My_ex"])
    A1 = b.M * b.Rx**2 / (b.M * b.Rx**2 + b.Iy)
    sF, sM = case.inputs.get("Fx_ex"), case.inputs.get("My_ex")

    def drive(t: float) -> float:
        tt = np.array([t])
        F = float(sF(tt)[0]) if sF is not None else 0.0
        M = float(sM(tt)[0]) if sM is not None else 0.0
        return F + M / b.Rx

    breaks = breakpoints(case, float(times[-1]))
    Vx = np.empty(times.size)
    Vx[0] = p["Vx0"]
    for k in range(1, times.size):
        a, c = float(times[k - 1]), float(times[k])
        inner = [x for x in breaks if a < x < c]
        val = integrate.quad(drive, a, c, points=inner or None, epsabs=0.0, epsrel=1e-13, limit=200)
        Vx[k] = Vx[k - 1] + A1 / b.M * val[0]
    P = u["P"]
    # at t = 0 the FMU reports its initial state (pure rolling), not the slow manifold
    Tx[0] = np.nan
    sol = _quasistationary(scene, case, times[1:], Tx[1:], P[1:], Vx[1:])
    return _prepend_nan(sol, times)


def quasistationary_held(scene: Scene, case: Case, grid: FloatArray) -> Solution:
    """Eqs. (26), (28) with the inputs sampled on ``grid`` and held over each step: Tx at
    t_k from the inputs at t_k-1; Vx the exact integral of the held drive."""
    why = quasistationary_allowed(scene, case, grid)
    if why:
        raise NoReferenceError(f"{scene.name}/{case.name}: {why}")
    p = case.parameters
    b = make_body(p)
    u = signal_values(case, LOAD_NAMES, grid)
    A1 = b.M * b.Rx**2 / (b.M * b.Rx**2 + b.Iy)
    h = np.diff(grid)
    drive = u["Fx_ex"][:-1] + u["My_ex"][:-1] / b.Rx
    Vx = p["Vx0"] + A1 / b.M * np.concatenate([[0.0], np.cumsum(h * drive)])
    Tx = quasistationary_force(b, u["Fx_ex"][:-1], u["My_ex"][:-1])
    sol = _quasistationary(scene, case, grid[1:], Tx, u["P"][:-1], Vx[1:])
    return _prepend_nan(sol, grid)


def _prepend_nan(sol: Solution, times: FloatArray) -> Solution:
    """The solution with t = 0 marked as not compared (NaN)."""
    pad = np.array([np.nan])
    return Solution(
        times.copy(),
        np.concatenate([pad, sol.Tx]),
        np.concatenate([pad, sol.vx]),
        np.concatenate([pad, sol.Vx]),
    )


# ---- contact mode: quadrature of the traction -------------------------------------------------
def traction_resultant(c: LayerContact, vx: float, vy: float, Vx: float) -> tuple[float, float]:
    """(Tx, Ty) = int tau dA with |tau| = min((l - x)|v|/(|Vx| k), mu p) along v (Eq. 36),
    by nested scipy quad; x measured from the leading edge l(y) (Eq. 37)."""
    speed = math.hypot(vx, vy)
    if speed == 0.0:
        return 0.0, 0.0
    if Vx == 0.0:
        return c.mu * c.P * vx / speed, c.mu * c.P * vy / speed
    gain = speed / (abs(Vx) * c.k)

    def strip(y: float) -> float:
        ell = c.a1 * math.sqrt(max(1.0 - (y / c.a2) ** 2, 0.0))
        if ell == 0.0:
            return 0.0

        def tau(x: float) -> float:
            p = c.p0 * max(1.0 - (x / c.a1) ** 2 - (y / c.a2) ** 2, 0.0)
            return min((ell - x) * gain, c.mu * p)

        # the adhesion line meets mu p at x = alpha - l (a hint for quad, Eq. 38)
        alpha = c.a1**2 * gain / (c.mu * c.p0)
        hint = [alpha - ell] if -ell < alpha - ell < ell else None
        return integrate.quad(tau, -ell, ell, points=hint, epsabs=0.0, epsrel=QUAD_RTOL, limit=200)[
            0
        ]

    beta = c.a1 * gain / (c.mu * c.p0)
    m = math.sqrt(max(1.0 - beta * beta / 4.0, 0.0))
    kinks = [-m * c.a2, m * c.a2] if 0.0 < m < 1.0 else None
    total = integrate.quad(
        strip, -c.a2, c.a2, points=kinks, epsabs=0.0, epsrel=QUAD_RTOL, limit=200
    )[0]
    return total * vx / speed, total * vy / speed


def _contact(scene: Scene, case: Case, times: FloatArray, u: dict[str, FloatArray]) -> Solution:
    if scene.config.mode != "contact":
        raise NoReferenceError(f"{scene.name}: the traction quadrature is the contact mode's")
    _require_steady(scene)
    if scene.config.contact_law == "halfspace":
        return _halfspace_contact(scene, case, times, u)
    if scene.config.contact_law != "layer":
        raise NoReferenceError(f"{scene.name}: the quadrature of Eq. (36) is the layer law's")
    p = case.parameters
    Tx = np.empty(times.size)
    Ty = np.empty(times.size)
    vx = np.empty(times.size)
    for k in range(times.size):
        if u["Omega_z"][k] != 0.0:
            raise NoReferenceError(f"{scene.name}/{case.name}: no quadrature reference with spin")
        vx[k] = u["Vx"][k] - u["Omega_y"][k] * p["Rx"]
        c = thin_layer_law(p, float(u["P"][k]))
        Tx[k], Ty[k] = traction_resultant(c, vx[k], u["Vy"][k], u["Vx"][k])
    return Solution(times.copy(), Tx, vx, u["Vx"].copy(), Ty)


def _halfspace_contact(
    scene: Scene, case: Case, times: FloatArray, u: dict[str, FloatArray]
) -> Solution:
    """Direct solves of the steady-rolling half-space problem (the scene's declaration on
    its table's solver grid, the case's mu) at the kinematics ``u``, (Tx, Ty) scaled
    radially by s(m)/m with m = |T|/(mu P), the table's saturation: what the table
    interpolates, up to its nodes' tolerance (TABLE_TOL, 1e-6)."""
    from ..halfspace.table import saturate

    spec = scene.config.table_spec
    p = case.parameters
    mu, Rx = p.get("mu", spec.mu), p.get("Rx", spec.Rx)
    contacts: dict[float, Any] = {}
    Tx, Ty, vx = np.empty(times.size), np.empty(times.size), np.empty(times.size)
    for k in range(times.size):
        P = float(u["P"][k])
        if P not in contacts:
            contacts[P] = spec.contact(P=P, mu=mu)
        vx[k], vy = rigid_slip(u["Vx"][k], u["Omega_y"][k], u["Vy"][k], Rx)
        s = contacts[P].traction(vx[k], vy, u["Omega_z"][k], u["Vx"][k])
        m = math.hypot(s.Tx, s.Ty) / (mu * P)
        scale = float(saturate(np.array(m))) / m if m > 0.0 else 1.0
        Tx[k], Ty[k] = s.Tx * scale, s.Ty * scale
    return Solution(times.copy(), Tx, vx, u["Vx"].copy(), Ty)


def contact_samples(grid: FloatArray) -> FloatArray:
    """Indices of the grid points where the contact reference is computed."""
    n = min(CONTACT_SAMPLES, grid.size - 1)
    return np.unique(np.round(np.linspace(1, grid.size - 1, n)).astype(int))


def contact_continuous(scene: Scene, case: Case, times: FloatArray) -> Solution:
    left = np.array([np.nextafter(t, -np.inf) if t > 0 else t for t in times])
    return _contact(scene, case, times, signal_values(case, KINEMATICS, left))


def contact_held(scene: Scene, case: Case, grid: FloatArray, idx: NDArray[np.int_]) -> Solution:
    """At grid[idx], the kinematics of the previous communication point grid[idx - 1]
    (what the force element holds over the step that ends there)."""
    before = grid[np.maximum(idx - 1, 0)]
    return _contact(scene, case, grid[idx], signal_values(case, KINEMATICS, before))
