"""Time stepping of the rolling body: the stiff slip equation and its quasistationary limit.

The state is y = (Vx, vx, Vy, Omega_z), with Omega_y = (Vx - vx)/Rx. In mass-matrix form
(Eqs. 8, 10, 11, 20)

    M       dVx/dt      = -Tx + Fx_ex
    M A2    dvx/dt      = -Tx + A2 Fx_ex - A1 My_ex/Rx
    M       dVy/dt      = -Ty + Fy_ex                 (or Vy = vy_ratio Vx)
    Iz      dOmega_z/dt = -Mz + Mz_ex                 (or Omega_z = spin_ratio Vx)

with T = T(vx, Vy, Omega_z, Vx) from the contact law. The slip equation is stiff: its
relaxation time tau_r = M A2 Vx / (dT/d(v/Vx)) is of order epsilon times the body's
time scale (Section 3b). Two implicit Runge-Kutta schemes, both order 2, L-stable and
stiffly accurate (Hairer & Wanner, Solving ODEs II, IV.3-6):

- "lobatto3c" (default), Lobatto IIIC with two stages: its stability function
  R(z) = 1/(1 - z + z^2/2) lies in (0, 1) for every z < 0, so the fast mode decays
  monotonically for any step: no overshoot, no step-to-step alternation;
- "sdirk2", Alexander's SDIRK2 (gamma = 1 - 1/sqrt 2): a quarter of Lobatto's error
  constant, but R(z) < 0 for z < -2.41 (minimum -0.21 at z = -8.5), so a step of a few
  tau_r after a load jump overshoots and the remnant alternates while it decays.

``method="quasistationary"`` applies the same scheme to the reduced system of
Section 3c (Eqs. 26, 28-30): the masses of the fast variables vx (and Vy, Omega_z) are
set to zero, so a stage solves the algebraic Eq. (26) by inverting the creep law, and
Vx follows the slow Eq. (8). eta = inf (Iy = 0) makes the slip equation algebraic in
the full method too; stiffly accurate schemes treat both as index-1 DAEs.

Each stage is reduced to the unknowns u = (vx[, Vy][, Omega_z]): eliminating T between
Eqs. (8) and (20) gives Vx explicitly,

    M (V_i - V_n) = h sum_j a_ij A1 (Fx_j + My_j/Rx) + M A2 (vx_i - vx_n),

so with one unknown every stage equation is one increasing scalar function (Lobatto's
two coupled stages included, see ``_lobatto_scalar``): bracketed root finding. With
several, ``_lobatto_vector``: Newton with a per-stage Jacobian kept from step to step
(simplified Newton, ``solvers.newton``'s memo; docs/model.md).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from .. import native
from .._validate import InputError, finite, positive
from ..laws.protocol import ContactLaw
from . import solvers
from .body import ROLLING_STRAIGHT, Body, Lateral, Loads
from .body_state import BodyState, ContactOutputs
from .kinematics import contact_quantities, is_full_slip
from .solvers import FD_STEP, StageSolveError, newton, newton_increasing

FloatArray = NDArray[np.float64]

SCHEMES = ("lobatto3c", "sdirk2")
# Alexander's SDIRK2: gamma = 1 - 1/sqrt(2); c = (gamma, 1); b = last row of A.
GAMMA = 1.0 - 0.5 * math.sqrt(2.0)
# Lobatto IIIC, two stages: A = [[1/2, -1/2], [1/2, 1/2]], c = (0, 1), b = last row.
STAGE_TIMES = {"sdirk2": (GAMMA, 1.0), "lobatto3c": (0.0, 1.0)}

# |Vx| (m/s) below which the contact law is the blend of its values at +-V_STANDSTILL
# (forces_at_rest): the creep law's Vx -> 0 limit is Coulomb's set-valued law; the
# floor keeps every stage equation single-valued and the blend continuous (at rest the
# body "creeps" at v ~ 1e-2 x 1e-9 m/s). docs/model.md.
V_STANDSTILL = 1e-9
# Floor of |Vx| (m/s) for the velocity scales of the stage solver (not the physics).
V_SCALE_FLOOR = 1e-9
# Lobatto IIIC with a vanishing slip mass: beyond this stiffness h dT/dv / (M A2) the
# stage is solved in its algebraic limit (relative difference 1/z, below rounding).
Z_ALGEBRAIC = 1e13
# Loads within this relative margin of the capacity mu P count as gross sliding in the
# quasistationary method (the inverse creep law runs to infinity there).
CAPACITY_MARGIN = 1e-9
# The key of RollingBody._jac for the algebraic stage (the quasistationary method in
# rolling: T(u) = F, no step size in it); Lobatto's coupled stages key theirs by h.
ALGEBRAIC = -1.0
# Largest |Fx_ex| and |My_ex|/Rx, in units of the capacity mu P. The steppers eliminate
# T and form Vx as V2b + (m/M) (v2 - vn) (Lobatto IIIC, Eq. 20), two terms of the size
# of the step's drive A1 (Fx_ex + My_ex/Rx) h / M that cancel to within mu P h / M; the
# momentum balance of Eqs. 8-9 then holds to about 11 eps (|Fx_ex| + |My_ex|/Rx)/(mu P)
# of mu P h / M (measured: 1e-2 at 5e12 mu P). At 1e9 mu P that is 3e-6: loads beyond,
# a billion times what the contact can transmit, are refused rather than integrated
# with a wrong balance.
LOAD_LIMIT = 1e9
# Load history: a function of time returning Loads, or constant Loads.
LoadInput = Loads | Callable[[float], Loads]

__all__ = [
    "ContactLaw",
    "ContactOutputs",
    "LoadInput",
    "RollingBody",
    "StageSolveError",
    "WorkBudgetError",
]


class WorkBudgetError(RuntimeError):
    """The evaluations of the contact law in one call of ``advance`` reached the
    stepper's ``eval_limit`` (the FMU's budget max_work, fmu/body_model.py): the stage
    solves of a hostile step can take hundreds of evaluations, ms each on a spin grid.
    Not a StageSolveError: no other start is tried."""

    def __init__(self, limit: int, why: str = "") -> None:
        self.limit = limit
        super().__init__(f"the stage solves need more than {limit} evaluations of the law{why}")


class EvalBudget:
    """Counts the law's evaluations of the stage solves against ``eval_limit`` (None:
    no limit), from 0 at each ``advance``."""

    eval_limit: int | None = None
    evals: int = 0

    def spend(self) -> None:
        self.evals += 1
        if self.eval_limit is not None and self.evals > self.eval_limit:
            raise WorkBudgetError(self.eval_limit)


class RollingBody(BodyState, EvalBudget):
    """The rolling body of Eqs. (8)-(11) on a contact law, advanced in time.

    ``method``: "full" (stiff slip equation, Eq. 20) or "quasistationary" (Eqs. 26,
    28-30, gross sliding handled by the full equations while it lasts). ``scheme``:
    "lobatto3c" or "sdirk2" (module docstring). Initial conditions Vx0 (m/s), Omega_y0
    (rad/s), Vy0 (m/s), Omega_z0 (rad/s); the held ratios of ``lateral`` override Vy0
    and Omega_z0.
    """

    def __init__(
        self,
        law: ContactLaw,
        body: Body,
        lateral: Lateral = ROLLING_STRAIGHT,
        method: str = "full",
        Vx0: float = 0.0,
        Omega_y0: float = 0.0,
        Vy0: float = 0.0,
        Omega_z0: float = 0.0,
        t0: float = 0.0,
        scheme: str = "lobatto3c",
    ) -> None:
        if method not in ("full", "quasistationary"):
            raise InputError("method", method, '"full" or "quasistationary"')
        if scheme not in SCHEMES:
            raise InputError("scheme", scheme, " or ".join(f'"{s}"' for s in SCHEMES))
        super().__init__(body, lateral, Vx0, Omega_y0, Vy0, Omega_z0, t0)
        self.law = law
        self.method = method
        self.scheme = scheme
        self.sliding = False
        self._dv = 0.0  # last step's dvx/dt (m/s^2): the predictor of the stage solves
        # (h or ALGEBRAIC, Newton matrix) of the last vector stage solve, kept for the
        # next one of the same kind (solvers.newton's memo)
        self._jac: tuple[float, FloatArray] | None = None
        T = self._forces(self.y[None, :])[0]
        self.out = ContactOutputs(*map(float, T), _saturated(law, self.y))
        self._kernel = self._native_kernel()

    # ---- public -----------------------------------------------------------------
    def outputs(self) -> dict[str, float]:
        """Everything a host reads after a step (SI): velocities, forces, contact state."""
        o = self.kinematics()
        o["Tx"], o["Ty"], o["Mz"] = self.out.Tx, self.out.Ty, self.out.Mz
        o.update(contact_quantities(self.law, o["Vx"], o["vx"], o["vy"], o["Omega_z"]))
        return o

    def snapshot(self) -> tuple:
        """The whole internal state, for FMU get/set state: restore(snapshot()) is exact."""
        return (self.y.copy(), self.t, self.sliding, self.out, self.law.P, self._dv, self._jac)

    def restore(self, snap: tuple) -> None:
        y, t, sliding, out, P, self._dv, self._jac = snap
        self.y, self.t, self.sliding, self.out = np.array(y, float), float(t), bool(sliding), out
        self.law = self.law.with_load(P)

    def set_load(self, P: float) -> None:
        """Change the normal load P (N): the contact ellipse follows (Eq. 34); P = 0 is
        lift-off (no contact, ``_free_step``)."""
        if not P >= 0.0:
            raise InputError("P", P, ">= 0 (lift-off, no contact, is P = 0)")
        self.law = self.law.with_load(finite("P", P))

    def set_mu(self, mu: float) -> None:
        """Change the coefficient of friction (takes effect from the next step; the
        state is kept: the slip relaxes to the new law, or saturates at the new mu P)."""
        self.law = self.law.with_mu(positive("mu", mu))

    def advance(self, h: float, loads: LoadInput, substeps: int = 1) -> None:
        """Advance by h (s) in ``substeps`` equal steps under the load history.

        Constant ``loads`` are held over the interval (zero-order hold, as a
        co-simulation master provides them); a callable is sampled at stage times.
        The quasistationary method under held, admissible loads takes one step for the
        whole interval: Vx is then linear in t and vx algebraic (Eq. 28), so substeps
        would change nothing but rounding; it substeps if that step ends in gross
        sliding. On error the state is left unchanged.
        """
        h = positive("h", h)
        if substeps < 1:
            raise InputError("substeps", substeps, ">= 1")
        self.evals = 0
        if self._kernel is not None and not callable(loads):
            L = self._bounded(_checked(loads))
            if self._kernel.advance(self, h, L, substeps):
                return  # else a case the kernel leaves to this code
        load_at = loads if callable(loads) else (lambda _t, L=loads: L)
        saved = (self.y.copy(), self.t, self.sliding, self.out, self._dv, self._jac)
        try:
            if substeps > 1 and self._exact_in_one_step(loads):
                self._step(saved[1], h, load_at)
                if not self.sliding:
                    self.t = saved[1] + h
                    return
                self.y, self.t, self.sliding, self.out, self._dv, self._jac = saved
            dt = h / substeps
            for k in range(substeps):
                self._step(saved[1] + k * dt, dt, load_at)
            self.t = saved[1] + h
        except Exception:
            self.y, self.t, self.sliding, self.out, self._dv, self._jac = saved
            raise

    def _native_kernel(self) -> native.Kernel | None:
        """The compiled twin of this stepper's path (contact_fmu/native), where it
        covers it: either scheme and a law with ``native_constants`` (thin layer,
        half-space table), and either vx the only unknown with vy and the spin held at
        ratios (``_lobatto_scalar``, ``_sdirk_scalar``: the Python path's doubles for the
        thin layer without lateral slip, the same to rounding else) or Vy and/or Omega_z
        as unknowns, either method (``_lobatto_vector``, ``_sdirk_vector`` and the
        quasistationary regime: the same to the stage tolerance)."""
        law_constants = getattr(type(self.law), "native_constants", None)
        if law_constants is None:
            return None
        scalar = len(self._idx) == 1 and self.lateral.vy_ratio is not None
        vector = len(self._idx) > 1
        lib = native.library() if scalar or vector else None
        if lib is None:
            return None
        constants = law_constants | {
            "v_standstill": V_STANDSTILL,
            "v_scale_floor": V_SCALE_FLOOR,
            "z_algebraic": Z_ALGEBRAIC,
            "capacity_margin": CAPACITY_MARGIN,
            "solve_rtol": solvers.SOLVE_RTOL,
            "expand": solvers.EXPAND,
            "max_newton": solvers.MAX_NEWTON,
            "fd_step": solvers.FD_STEP,
            "line_search_min": solvers.LINE_SEARCH_MIN,
            "contraction_max": solvers.CONTRACTION_MAX,
            "contraction_fast": solvers.CONTRACTION_FAST,
            "newton_iterations": solvers.NEWTON_ITERATIONS,
            "algebraic_key": ALGEBRAIC,
            "gamma": GAMMA,
            "sdirk": int(self.scheme == "sdirk2"),
        }
        if vector:
            return native.VectorKernel(lib, constants, self.method == "quasistationary")
        return native.Kernel(lib, constants, self.method == "quasistationary")

    def _exact_in_one_step(self, loads: LoadInput) -> bool:
        """Quasistationary rolling under held, admissible loads (see ``advance``)."""
        return (
            self.method == "quasistationary"
            and not callable(loads)
            and not self.sliding
            and self._admissible(_checked(loads))
        )

    # ---- one step ------------------------------------------------------------------
    def _step(self, t_n: float, h: float, load_at: Callable[[float], Loads]) -> None:
        c1, c2 = STAGE_TIMES[self.scheme]
        L1 = self._bounded(_checked(load_at(t_n + c1 * h)))
        L2 = self._bounded(_checked(load_at(t_n + c2 * h)))
        if self.law.P == 0.0:
            self._free_step(h, L1, L2)
            return
        admissible = self._admissible(L1) and self._admissible(L2)
        if self.method == "quasistationary" and not admissible:
            self.sliding = True
        elif self.body.m_slip == 0.0 and not admissible:
            raise StageSolveError(
                "eta = inf (Iy = 0) admits no gross sliding: |A2 Fx_ex - A1 My_ex/Rx| = "
                f"{abs(self._targets(L2)[0]):.6g} N reaches mu P = {self.law.mu * self.law.P:.6g} N"
            )
        algebraic = self.method == "quasistationary" and not self.sliding
        one = len(self._idx) == 1
        if self.scheme == "lobatto3c":
            step = self._lobatto_scalar if one else self._lobatto_vector
        else:
            step = self._sdirk_scalar if one else self._sdirk_vector
        vn = self.y[1]
        self.y, T = step(h, L1, L2, algebraic)
        self._dv = (self.y[1] - vn) / h
        cap = self.law.mu * self.law.P
        if math.hypot(T[0], T[1]) > cap:  # rounding of an implied force at mu P
            T[:2] *= cap / math.hypot(T[0], T[1])
        self.out = ContactOutputs(*map(float, T), _saturated(self.law, self.y))
        if self.method == "quasistationary":
            self._update_regime(L2)

    def _free_step(self, h: float, L1: Loads, L2: Loads) -> None:
        """A step without contact (P = 0, lift-off): Eqs. (8)-(11) with T = 0, the loads
        at the stages weighted as the scheme's quadrature (b = (1/2, 1/2) for Lobatto
        IIIC, (1 - gamma, gamma) for SDIRK2; exact for held loads): Vx += h Fx_ex/M,
        Omega_y += h My_ex/Iy, so the slip vx = Vx - Omega_y Rx moves by h (Fx_ex/M -
        Rx My_ex/Iy), Eq. (20) with T = 0 divided by M A2. The slip is carried: it is
        the body's kinematics, and it meets the contact when P returns (docs/model.md,
        "Lift-off"). Iy = 0 (eta = inf) takes no moment without contact (Omega_y would
        jump); with My_ex = 0 Omega_y is held, the Iy -> 0+ limit."""
        b = self.body
        w1, w2 = (0.5, 0.5) if self.scheme == "lobatto3c" else (1.0 - GAMMA, GAMMA)
        Fx = w1 * L1.Fx_ex + w2 * L2.Fx_ex
        My = w1 * L1.My_ex + w2 * L2.My_ex
        if b.Iy == 0.0 and (L1.My_ex != 0.0 or L2.My_ex != 0.0):
            raise StageSolveError(
                "eta = inf (Iy = 0) admits no gross sliding: |A2 Fx_ex - A1 My_ex/Rx| = "
                f"{abs(self._target_x(L2)):.6g} N reaches mu P = 0 N"
            )
        Vn, vn = float(self.y[0]), float(self.y[1])
        dV = h * Fx / b.M
        vx = vn + dV - (h * b.Rx * My / b.Iy if b.Iy > 0.0 else 0.0)
        y = self.y.copy()
        y[0], y[1] = Vn + dV, vx
        if self.lateral.dynamic_vy:
            y[2] += h * (w1 * L1.Fy_ex + w2 * L2.Fy_ex) / b.M
        if self.lateral.dynamic_spin:
            y[3] += h * (w1 * L1.Mz_ex + w2 * L2.Mz_ex) / b.Iz
        self.y = self._apply_ratios(y)
        self._dv = (vx - vn) / h
        self.out = ContactOutputs(0.0, 0.0, 0.0, _saturated(self.law, self.y))
        if self.method == "quasistationary":  # Eq. (26) has no root without contact
            self.sliding = True

    def _update_regime(self, L: Loads) -> None:
        """Quasistationary method: leave gross sliding when the slip law is unsaturated
        and the loads are admissible again (Eq. 27); enter it when they are not."""
        if self.sliding:
            if not _saturated(self.law, self.y) and self._admissible(L):
                self.sliding = False
        elif self.out.sliding:
            self.sliding = True

    def _bounded(self, L: Loads) -> Loads:
        """Loads within LOAD_LIMIT mu P (|Fx_ex|, |My_ex|/Rx), or InputError; any finite
        loads at P = 0 (the step without contact, ``_free_step``, is exact: no
        cancellation to bound)."""
        if self.law.P == 0.0:
            return L
        cap = LOAD_LIMIT * self.law.mu * self.law.P
        if abs(L.Fx_ex) > cap:
            raise InputError("Fx_ex", L.Fx_ex, f"<= {LOAD_LIMIT:g} mu P = {cap:.6g} N in magnitude")
        if abs(L.My_ex) > cap * self.body.Rx:
            raise InputError(
                "My_ex",
                L.My_ex,
                f"<= {LOAD_LIMIT:g} mu P Rx = {cap * self.body.Rx:.6g} N m in magnitude",
            )
        return L

    def _admissible(self, L: Loads) -> bool:
        """Eq. (27): the demanded force (Tx[, Ty]) is inside the capacity mu P."""
        Ty = L.Fy_ex if self.lateral.dynamic_vy else 0.0
        cap = self.law.mu * self.law.P * (1.0 - CAPACITY_MARGIN)
        return math.hypot(self._target_x(L), Ty) < cap

    def _targets(self, L: Loads) -> FloatArray:
        """Forces the stages balance: Eqs. (26), (29), (30) in the QS limit."""
        return np.array([self._target_x(L), L.Fy_ex, L.Mz_ex])[self._act]

    def _target_x(self, L: Loads) -> float:
        """Eq. (26)'s demand A2 Fx_ex - A1 My_ex/Rx (N), the first of ``_targets``."""
        return self.body.tx_demand(L.Fx_ex, L.My_ex)

    def _drive(self, L: Loads) -> float:
        """A1 (Fx_ex + My_ex/Rx): the force that accelerates Vx once T is eliminated."""
        b = self.body
        return b.A1 * (L.Fx_ex + L.My_ex / b.Rx)

    def _masses(self, algebraic: bool) -> FloatArray:
        if algebraic:
            return np.zeros(len(self._idx))
        b = self.body
        return np.array([b.m_slip, b.M, b.Iz if b.Iz is not None else 0.0])[self._act]

    def _law(self, vx: float, Vx: float) -> tuple:
        """The law at slip vx and speed Vx with the held lateral ratios (floats), at
        standstill as ``forces_at_rest``."""
        self.spend()  # one evaluation of a scalar step, against the budget
        ry, rz = self.lateral.vy_ratio, self.lateral.spin_ratio
        return forces_at_rest(self.law, vx, ry * Vx, rz * Vx, Vx)

    def _law_x(self, vx: float, Vx: float, k: float, scale: float) -> tuple[float, float]:
        """Tx and dTx/dvx along a stage path on which Vx moves by k per unit of vx
        (held ratios). The law's analytic slope (``tx_slope``) where it has one, else a
        forward difference."""
        ry, rz = self.lateral.vy_ratio, self.lateral.spin_ratio
        slope = getattr(self.law, "tx_slope", None)
        if slope is not None and rz == 0.0:
            self.spend()  # else _law's, twice
            if abs(Vx) >= V_STANDSTILL:
                T, d_vx, d_vy, d_V = slope(vx, ry * Vx, Vx)
                return T, d_vx + k * ry * d_vy + k * d_V
            # forces_at_rest's blend, and its slope: Vx, hence the weight, moves by k
            # per unit of vx
            w = standstill_weight(Vx)
            Tp, ap, bp, _ = slope(vx, ry * Vx, V_STANDSTILL)
            Tm, am, bm, _ = slope(vx, ry * Vx, -V_STANDSTILL)
            sp, sm = ap + k * ry * bp, am + k * ry * bm
            T = w * Tp + (1.0 - w) * Tm
            return T, w * sp + (1.0 - w) * sm + k * (Tp - Tm) / (2.0 * V_STANDSTILL)
        T = self._law(vx, Vx)[0]
        dv = FD_STEP * (abs(vx) + scale)
        return T, (self._law(vx + dv, Vx + k * dv)[0] - T) / dv

    def _forces(self, Y: FloatArray) -> FloatArray:
        """(Tx, Ty, Mz) at states Y (k, 4), shape (k, 3): one vectorised law call, with
        the law at standstill of ``forces_at_rest`` for |Vx| < V_STANDSTILL."""
        self.spend()
        k, Vx = Y.shape[0], Y[:, 0]
        near = np.flatnonzero(np.abs(Vx) < V_STANDSTILL)
        rows = np.concatenate([np.arange(k), near])  # near rows twice: at +V_s and -V_s
        V = np.concatenate([Vx, np.full(near.size, -V_STANDSTILL)])
        V[near] = V_STANDSTILL
        T = self.law.forces(Y[rows, 1], Y[rows, 2], Y[rows, 3], V)
        T = np.stack([np.broadcast_to(t, V.shape) for t in T], axis=1)
        w = standstill_weight(Vx[near])[:, None]
        T[near] = w * T[near] + (1.0 - w) * T[k:]
        return T[:k]

    def _scale(self, Vx: float) -> FloatArray:
        """Scales of the unknowns (vx, Vy, Omega_z) for the solvers."""
        v = self.law.creep_full_slip * max(abs(Vx), V_SCALE_FLOOR)
        return np.array([v, v, v / self.law.a1])[self._act]

    # ---- Lobatto IIIC ------------------------------------------------------------------
    def _lobatto_scalar(self, h: float, L1: Loads, L2: Loads, algebraic: bool):
        """Stages Y1, Y2 with one unknown (vx). With m = M A2 and a = Fe - T the stage
        forces, Lobatto IIIC reads m (v1 - vn) = h (a1 - a2)/2, m (v2 - vn) = h (a1 + a2)/2,
        i.e. T2 = Fe2 - m (v2 - v1)/h and T1 = Fe1 - m (v1 + v2 - 2 vn)/h. The first gives
        v1 explicitly from v2 (increasing in v2), so the second is one increasing
        function of v2. In the algebraic limit (m = 0) only T2 = Fe2 remains."""
        b = self.body
        Vn, vn = float(self.y[0]), float(self.y[1])
        G1, G2 = self._drive(L1), self._drive(L2)
        Fe1, Fe2 = self._target_x(L1), self._target_x(L2)
        V1b = Vn + 0.5 * h * (G1 - G2) / b.M
        V2b = Vn + 0.5 * h * (G1 + G2) / b.M
        scale = float(self._scale(V2b)[0])
        m = 0.0 if algebraic else b.m_slip
        k = m / b.M
        slope = self.law.mu * self.law.P / scale  # dT/dv at the saturation scale
        if m == 0.0 or h * slope / m > Z_ALGEBRAIC:
            # T(v2) = Fe2 with Vx = V2b + k (v2 - vn): the slip's mass m (v2 - v1)/h drops
            # out, not Eq. (8)'s share of the slip's change, k = M A2/M = A2 (a tiny M
            # makes k ~ 1 and the stage stiff: Vx, not Omega_y, takes up the slip's jump)
            v2 = newton_increasing(
                lambda v: _shift(self._law_x(v, V2b + k * (v - vn), k, scale), Fe2),
                vn + self._dv * h,
                scale,
            )
            V2 = V2b + k * (v2 - vn)
            T = self._law(v2, V2)
            return self._state(V2, v2), np.array([Fe2, float(T[1]), float(T[2])])

        def g(v2: float) -> tuple[float, float]:
            T2, d2 = self._law_x(v2, V2b + k * (v2 - vn), k, scale)
            v1 = v2 - h * (Fe2 - T2) / m
            dv1 = 1.0 + h * d2 / m  # v1 increases with v2
            T1, d1 = self._law_x(v1, V1b + k * (v1 - vn), k, scale)
            return T1 - Fe1 + m * (v1 + v2 - 2 * vn) / h, d1 * dv1 + m * (dv1 + 1.0) / h

        v2 = newton_increasing(g, vn + self._dv * h, scale)
        V2 = V2b + k * (v2 - vn)
        return self._state(V2, v2), np.array([float(t) for t in self._law(v2, V2)])

    def _lobatto_vector(self, h: float, L1: Loads, L2: Loads, algebraic: bool):
        """Lobatto IIIC with several unknowns u (vx, Vy and/or Omega_z): Newton on
        R1 = m (u1 + u2 - 2 un)/h + T(u1) - F1, R2 = m (u2 - u1)/h + T(u2) - F2."""
        b, n = self.body, len(self._idx)
        un = self.y[self._idx]
        F1, F2 = self._targets(L1), self._targets(L2)
        G1, G2 = self._drive(L1), self._drive(L2)
        m = self._masses(algebraic)
        Vb = self.y[0] + 0.5 * h * np.array([G1 - G2, G1 + G2]) / b.M
        scale = self._scale(Vb[1])

        def states(U: FloatArray, stage: int) -> FloatArray:
            Y = np.tile(self.y, (U.shape[0], 1))
            Y[:, self._idx] = U
            Y[:, 0] = Vb[stage] + (m[0] / b.M) * (U[:, 0] - un[0])
            return self._apply_ratios(Y.T).T

        if not np.any(m):  # algebraic: T(u2) = F2; its Jacobian kept under the key ALGEBRAIC
            key = ALGEBRAIC
            memo = {"J": self._jac[1]} if self._jac is not None and self._jac[0] == key else {}
            u0 = self._creep_start(un, Vb[1])

            def balance(U: FloatArray) -> FloatArray:
                return self._forces(states(U, 1))[:, self._act] - F2

            starts = (lambda: u0, lambda: self._no_slip(u0))
            u2, memo = _newton_from(balance, starts, scale, None, memo)
            self._jac = (key, memo["J"]) if "J" in memo else None
            Y2 = states(u2[None, :], 1)
            T = self._forces(Y2)[0]
            T[self._act] = F2
            return Y2[0], T

        last: dict[str, FloatArray] = {}  # the stage forces at the last single point

        def residuals(UU: FloatArray) -> FloatArray:
            U1, U2 = UU[:, :n], UU[:, n:]
            Y = np.concatenate([states(U1, 0), states(U2, 1)])
            T = self._forces(Y)[:, self._act]
            k = UU.shape[0]
            if k == 1:
                last["u"], last["T"] = UU[0].copy(), T
            R1 = m * (U1 + U2 - 2 * un) / h + T[:k] - F1
            R2 = m * (U2 - U1) / h + T[k:] - F2
            return np.concatenate([R1, R2], axis=1)

        def jacobian(u: FloatArray, du: FloatArray) -> FloatArray:
            """dR/du: the mass terms exactly, T(u_i) by forward differences in stage
            i's unknowns only (T(u1) does not move with u2: 2n law inputs, not 4n)."""
            T = last["T"] if np.array_equal(last.get("u"), u) else None
            U = u + np.diag(du)
            Y = [states(U[:n, :n], 0), states(U[n:, n:], 1)]
            if T is None:
                Y += [states(u[None, :n], 0), states(u[None, n:], 1)]
            Tp = self._forces(np.concatenate(Y))[:, self._act]
            if T is None:
                T = Tp[2 * n :]
            d1 = (Tp[:n] - T[0]).T / du[:n]
            d2 = (Tp[n : 2 * n] - T[1]).T / du[n:]
            D = np.diag(m / h)
            return np.block([[D + d1, D], [-D, D + d2]])

        memo = {"J": self._jac[1]} if self._jac is not None and self._jac[0] == h else {}
        # from the last state; where that fails (Vx changed much, or reversed, over a long
        # step), as the algebraic stage does
        starts = (
            lambda: np.concatenate([un, un]),
            lambda: np.concatenate([self._creep_start(un, Vb[0]), self._creep_start(un, Vb[1])]),
            lambda: np.tile(self._no_slip(self._creep_start(un, Vb[0])), 2),
        )
        UU, memo = _newton_from(residuals, starts, np.concatenate([scale, scale]), jacobian, memo)
        self._jac = (h, memo["J"]) if "J" in memo else None
        Y2 = states(UU[None, n:], 1)
        return Y2[0], self._forces(Y2)[0]

    def _creep_start(self, un: FloatArray, V: float, base: FloatArray | None = None) -> FloatArray:
        """A start for a stage's unknowns at the speed V: the last state's creepages
        (u/Vx: the law is a function of them, and Vx may change much in one step of
        Eq. 28, or reverse), with the slip (vx[, Vy]) pulled back to half the onset of
        full slip where it is beyond it (the law is flat in the slip's magnitude there,
        and Newton finds no direction). The algebraic stage's first start. ``base``: the
        state the unknowns un belong to (default the last state; SDIRK2's second stage
        gives its explicit part)."""
        base = self.y if base is None else base
        ratio = _signed(V) / _signed(base[0])
        u = un * ratio
        Y = base.copy()
        Y[0] = V
        Y[self._idx] = u
        Y = self._apply_ratios(Y)
        slip = math.hypot(Y[1], Y[2])
        onset = self.law.creep_full_slip * max(abs(V), V_SCALE_FLOOR)
        if slip >= onset and slip > 0.0:
            u[self._slip_unknowns] *= 0.5 * onset / slip
        return u

    def _no_slip(self, u: FloatArray) -> FloatArray:
        """u with the slip (vx[, Vy]) at zero, the spin kept: where the law is smooth and
        steepest, the last start of a stage solve."""
        u = u.copy()
        u[self._slip_unknowns] = 0.0
        return u

    @property
    def _slip_unknowns(self) -> list[int]:
        """Positions of vx and Vy among the stage unknowns (not the spin)."""
        return [i for i, a in enumerate(self._act) if a < 2]

    # ---- SDIRK2 ------------------------------------------------------------------------
    def _sdirk_scalar(self, h: float, L1: Loads, L2: Loads, algebraic: bool):
        """Two sequential stages m (v_i - v_hat_i)/(h gamma) + T(v_i) - Fe_i = 0, with
        v_hat_1 = vn, v_hat_2 = vn + (1 - gamma)/gamma (v1 - vn). The reported force
        closes the stage balance (Fe - m (v - v_hat)/(h gamma))."""
        b = self.body
        hg = h * GAMMA
        Vn, vn = float(self.y[0]), float(self.y[1])
        G1, G2 = self._drive(L1), self._drive(L2)
        m = 0.0 if algebraic else b.m_slip
        k = m / b.M
        v_hat, V_hat = vn, Vn
        for i, (L, G) in enumerate(((L1, G1), (L2, G2))):
            Fe = self._target_x(L)
            Vb = V_hat + hg * G / b.M

            scale = float(self._scale(Vb)[0])

            def r(v: float, Vb=Vb, Fe=Fe, v_hat=v_hat, scale=scale) -> tuple[float, float]:
                T, dT = self._law_x(v, Vb + k * (v - v_hat), k, scale)
                return m * (v - v_hat) / hg + T - Fe, m / hg + dT

            v = newton_increasing(r, v_hat + self._dv * hg, scale)
            V = Vb + k * (v - v_hat)
            if i == 0:  # the explicit part of stage 2 from stage 1's slope
                V_hat = Vn + (1 - GAMMA) / GAMMA * (V - Vn)
                v_hat = vn + (1 - GAMMA) / GAMMA * (v - vn) if m > 0 else v
        T = self._law(v, V)
        return self._state(V, v), np.array([Fe - m * (v - v_hat) / hg, float(T[1]), float(T[2])])

    def _sdirk_vector(self, h: float, L1: Loads, L2: Loads, algebraic: bool):
        """SDIRK2 stages with several unknowns, Newton on each stage in turn."""
        b = self.body
        hg = h * GAMMA
        m = self._masses(algebraic)
        y_hat = self.y.copy()
        for i, L in enumerate((L1, L2)):
            target = self._targets(L)
            Vb = y_hat[0] + hg * self._drive(L) / b.M
            u_hat = y_hat[self._idx]

            def states(U: FloatArray, y_hat=y_hat, Vb=Vb, u_hat=u_hat) -> FloatArray:
                Y = np.tile(y_hat, (U.shape[0], 1))
                Y[:, self._idx] = U
                Y[:, 0] = Vb + (m[0] / b.M) * (U[:, 0] - u_hat[0])
                return self._apply_ratios(Y.T).T

            def residuals(U: FloatArray, states=states, target=target, u_hat=u_hat):
                return m * (U - u_hat) / hg + self._forces(states(U))[:, self._act] - target

            # from the explicit part; where that fails (a start beyond full slip, where
            # the law is flat), from its creepages pulled back, then without slip (stepper.c's
            # sdirk_vstep tries the same)
            starts = (
                lambda u_hat=u_hat: u_hat,
                lambda u_hat=u_hat, Vb=Vb, y_hat=y_hat: self._creep_start(u_hat, Vb, y_hat),
                lambda u_hat=u_hat, Vb=Vb, y_hat=y_hat: self._no_slip(
                    self._creep_start(u_hat, Vb, y_hat)
                ),
            )
            u, _ = _newton_from(residuals, starts, self._scale(Vb), None, None)
            y = states(u[None, :])[0]
            if i == 0:
                y_hat = self.y + (1 - GAMMA) / GAMMA * (y - self.y)
                # no memory where an unknown has no mass (the QS limit; the slip of an
                # eta = inf body): its stage is algebraic, started from stage 1's root
                massless = [i for i, mass in zip(self._idx, m, strict=True) if mass == 0.0]
                y_hat[massless] = y[massless]
        T = self._forces(y[None, :])[0]
        T[self._act] = target - m * (u - u_hat) / hg
        return y, T

    def _state(self, Vx: float, vx: float) -> FloatArray:
        y = np.array([Vx, vx, 0.0, 0.0])
        return self._apply_ratios(y)


def _shift(f_df: tuple[float, float], target: float) -> tuple[float, float]:
    """(f - target, f') for the root finder."""
    return f_df[0] - target, f_df[1]


def _newton_from(residuals, starts, scale, jacobian, memo) -> tuple[FloatArray, dict | None]:
    """solvers.newton from each start (a function forming it, called only when the one
    before has failed) in turn until one converges: the first with the kept matrix
    ``memo``, the others with a new one (memo None: no matrix kept at all, Newton's own
    at every iterate, as the SDIRK2 stages solve); scipy's hybrid method only from the
    last (the compiled step tries the same Newton starts before it leaves a step to
    this code). Returns u and the memo of the solve that converged; StageSolveError if
    none does."""
    for start in starts[:-1]:
        try:
            return newton(residuals, start(), scale, jacobian, memo, hybrid=False), memo
        except StageSolveError:
            memo = None if memo is None else {}
    return newton(residuals, starts[-1](), scale, jacobian, memo), memo


def _signed(V: float) -> float:
    """V with its magnitude at least V_SCALE_FLOOR (0 taken as positive)."""
    return max(abs(V), V_SCALE_FLOOR) if V >= 0.0 else -max(abs(V), V_SCALE_FLOOR)


def standstill_weight(Vx: FloatArray | float) -> FloatArray | float:
    """Weight of the law at +V_STANDSTILL (against -V_STANDSTILL) for |Vx| below it."""
    return 0.5 * (1.0 + Vx / V_STANDSTILL)


def forces_at_rest(law: ContactLaw, vx: float, vy: float, phi: float, Vx: float) -> tuple:
    """(Tx, Ty, Mz) at the state's speed Vx; for |Vx| < V_STANDSTILL, where the creep
    law tends to Coulomb's set-valued law, the linear blend of the law at +V_STANDSTILL
    and at -V_STANDSTILL (standstill_weight). The two differ (Mz flips with the rolling
    direction, the spin march runs the other way), so evaluating at the nearer of them
    would make the stage residuals jump where Vx crosses zero; the blend keeps them
    continuous (docs/model.md, "Standstill")."""
    if abs(Vx) >= V_STANDSTILL:
        return tuple(float(t) for t in law.forces(vx, vy, phi, Vx))
    w = standstill_weight(Vx)
    plus = law.forces(vx, vy, phi, V_STANDSTILL)
    minus = law.forces(vx, vy, phi, -V_STANDSTILL)
    return tuple(float(w * a + (1.0 - w) * b) for a, b in zip(plus, minus, strict=True))


def _checked(L: Loads) -> Loads:
    """Loads with finite values, or InputError naming the first bad one."""
    if not math.isfinite(sum(L)):
        for name, val in zip(Loads._fields, L, strict=True):
            finite(name, val)
    return L


def _saturated(law: ContactLaw, y: FloatArray) -> bool:
    """Gross sliding at state y: the slip is at or beyond the onset of full slip."""
    return is_full_slip(law, y[1], y[2], y[0])
