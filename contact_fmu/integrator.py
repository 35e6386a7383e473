"""Time stepping of the rolling body: the stiff slip equation and its quasistationary limit.

The state is y = (Vx, vx, Vy, Omega_z), with Omega_y = (Vx - vx)/Rx. In mass-matrix form
(Eqs. 8, 10, 11, 20)

    M       dVx/dt      = -Tx + Fx_ex
    M A2    dvx/dt      = -Tx + A2 Fx_ex - A1 My_ex/Rx
    M       dVy/dt      = -Ty + Fy_ex                 (or Vy = vy_ratio Vx)
    Iz      dOmega_z/dt = -Mz + Mz_ex                 (or Omega_z = spin_ratio Vx)

with T = T(vx, Vy, Omega_z, Vx) from the contact law. The slip equation is stiff: its
relaxation time M A2 Vx / (dT/d(v/Vx)) is of order epsilon times the body's time
scale (Section 3b). It is integrated with Alexander's two-stage SDIRK method, L-stable
and stiffly accurate, order 2 (Hairer & Wanner, Solving ODEs II, IV.6): stable for
any step, no oscillation of the fast mode, and exact on the slow manifold.

``method="quasistationary"`` is the same scheme applied to the reduced system of
Section 3c (Eqs. 26, 28-30): the masses of the fast variables vx (and Vy, Omega_z)
are set to zero, so every stage solves the algebraic Eq. (26) for the slip by
inverting the creep law, and Vx follows the slow Eq. (8). eta = inf (Iy = 0) makes
the slip equation algebraic in the full method too; the stiffly accurate scheme
handles both as index-1 DAEs.

Each stage is reduced to the unknowns u = (vx[, Vy][, Omega_z]): eliminating T
between the Vx and vx equations gives Vx explicitly in vx, so the stage equation is
r(u) = m (u - u_hat)/(h gamma) + T_active(u) - target = 0, monotone in u. One
unknown: bracketed root finding (scipy's brentq); more: Newton with a finite-
difference Jacobian and backtracking, scipy's hybrid method as fallback.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import brentq, root

from ._validate import InputError, finite, positive
from .dynamics import ROLLING_STRAIGHT, Body, Lateral, Loads
from .kinematics import contact_quantities, is_full_slip

FloatArray = NDArray[np.float64]

# Alexander's SDIRK2: gamma = 1 - 1/sqrt(2); c = (gamma, 1); b = last row of A.
GAMMA = 1.0 - 0.5 * math.sqrt(2.0)
A21 = 1.0 - GAMMA
STAGE_C = (GAMMA, 1.0)

# Relative tolerance of the stage solves, on the unknowns (in units of their scale).
SOLVE_RTOL = 1e-13
# Relative forward-difference step of the stage Jacobian (about sqrt of the rounding).
FD_STEP = 1e-7
# Floor of |Vx| (m/s) for the velocity scales of the stage solver (not the physics).
V_SCALE_FLOOR = 1e-9
# Loads within this relative margin of the capacity mu P count as gross sliding in the
# quasistationary method (the inverse creep law runs to infinity there).
CAPACITY_MARGIN = 1e-9
# Load history: a function of time returning Loads, or constant Loads.
LoadInput = Loads | Callable[[float], Loads]


class ContactLaw(Protocol):
    """What the integrator needs of a contact law (LayerContact, the half-space table).

    forces(vx, vy, phi, Vx) -> (Tx, Ty, Mz) in N and N m for rigid slip (vx, vy) at the
    contact centre (m/s), spin phi = Omega_z (rad/s) and rolling speed Vx (m/s), in the
    sign convention of Eq. (8): the body receives -T. creep_full_slip is |v|/|Vx| at the
    onset of full slip; a1, a2, p0 describe the contact ellipse and peak pressure.
    """

    P: float
    mu: float
    a1: float
    a2: float
    p0: float
    creep_full_slip: float

    def forces(self, vx, vy, phi, Vx) -> tuple: ...

    def adhesion_fraction(self, vx, vy, Vx): ...

    def with_load(self, P: float) -> ContactLaw: ...


class StageSolveError(RuntimeError):
    """A stage equation has no solution (loads beyond mu P with eta = inf)."""


@dataclass
class ContactOutputs:
    """Contact quantities at the end of a step (SI)."""

    Tx: float = 0.0
    Ty: float = 0.0
    Mz: float = 0.0
    sliding: bool = False


class RollingBody:
    """The rolling body of Eqs. (8)-(11) on a contact law, advanced in time.

    ``method``: "full" (stiff slip equation, Eq. 20) or "quasistationary" (Eqs. 26,
    28-30 with gross sliding handled by the full equations while it lasts).
    Initial conditions Vx0 (m/s), Omega_y0 (rad/s), Vy0 (m/s), Omega_z0 (rad/s); the
    held ratios of ``lateral`` override Vy0 and Omega_z0.
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
    ) -> None:
        if method not in ("full", "quasistationary"):
            raise InputError("method", method, '"full" or "quasistationary"')
        if lateral.dynamic_spin and body.Iz is None:
            raise InputError("Iz", None, "given when Omega_z follows Eq. (11)")
        self.law = law
        self.body = body
        self.lateral = lateral
        self.method = method
        self.t = finite("t0", t0)
        Vx0 = finite("Vx0", Vx0)
        vx0 = Vx0 - finite("Omega_y0", Omega_y0) * body.Rx
        self.y = np.array([Vx0, vx0, finite("Vy0", Vy0), finite("Omega_z0", Omega_z0)])
        self._apply_ratios(self.y)
        # unknowns of the stage solve: indices into y
        self._idx = (
            [1] + ([2] if lateral.dynamic_vy else []) + ([3] if lateral.dynamic_spin else [])
        )
        self.sliding = False
        self.out = self._contact_at(self.y)

    # ---- public -----------------------------------------------------------------
    @property
    def Vx(self) -> float:
        return float(self.y[0])

    @property
    def vx(self) -> float:
        return float(self.y[1])

    @property
    def Vy(self) -> float:
        return float(self.y[2])

    @property
    def Omega_z(self) -> float:
        return float(self.y[3])

    @property
    def Omega_y(self) -> float:
        return (self.Vx - self.vx) / self.body.Rx

    @property
    def vy(self) -> float:
        """Lateral rigid slip at the contact centre, Eq. (3) at x = 0: Vy."""
        return self.Vy

    def outputs(self) -> dict[str, float]:
        """Everything a host reads after a step (SI): velocities, forces, contact state."""
        o = {
            "Vx": self.Vx,
            "Vy": self.Vy,
            "Omega_y": self.Omega_y,
            "Omega_z": self.Omega_z,
            "vx": self.vx,
            "vy": self.vy,
            "Tx": self.out.Tx,
            "Ty": self.out.Ty,
            "Mz": self.out.Mz,
        }
        o.update(contact_quantities(self.law, self.Vx, self.vx, self.vy, self.Omega_z))
        return o

    def snapshot(self) -> tuple:
        """The whole internal state, for FMU get/set state: restore(snapshot()) is exact."""
        return (self.y.copy(), self.t, self.sliding, self.out, self.law.P)

    def restore(self, snap: tuple) -> None:
        y, t, sliding, out, P = snap
        self.y, self.t, self.sliding, self.out = np.array(y, float), float(t), bool(sliding), out
        self.law = self.law.with_load(P)

    def set_load(self, P: float) -> None:
        """Change the normal load P (N): the contact ellipse follows (Eq. 34)."""
        self.law = self.law.with_load(positive("P", P))

    def advance(self, h: float, loads: LoadInput, substeps: int = 1) -> None:
        """Advance by h (s) in ``substeps`` equal SDIRK steps under the load history.

        Constant ``loads`` are held over the interval (zero-order hold, as a
        co-simulation master provides them); a callable is sampled at stage times.
        On error the state is left unchanged.
        """
        h = positive("h", h)
        if substeps < 1:
            raise InputError("substeps", substeps, ">= 1")
        load_at = loads if callable(loads) else (lambda _t, L=loads: L)
        saved = (self.y.copy(), self.t, self.sliding, self.out)
        try:
            dt = h / substeps
            for k in range(substeps):
                t_n = saved[1] + k * dt
                self._step(t_n, dt, load_at)
                self.t = t_n + dt
            self.t = saved[1] + h
        except Exception:
            self.y, self.t, self.sliding, self.out = saved
            raise

    # ---- one SDIRK2 step ---------------------------------------------------------
    def _step(self, t_n: float, h: float, load_at: Callable[[float], Loads]) -> None:
        y_n = self.y
        hg = h * GAMMA
        L1 = _checked(load_at(t_n + STAGE_C[0] * h))
        L2 = _checked(load_at(t_n + h))
        admissible = self._admissible(L1) and self._admissible(L2)
        if self.method == "quasistationary" and not admissible:
            self.sliding = True
        elif self.body.m_slip == 0.0 and not admissible:
            raise StageSolveError(
                "eta = inf (Iy = 0) admits no gross sliding: |A2 Fx_ex - A1 My_ex/Rx| = "
                f"{abs(self._targets(L2)[0]):.6g} N reaches mu P = {self.law.mu * self.law.P:.6g} N"
            )
        qs = self.method == "quasistationary" and not self.sliding
        stage = self._stage_scalar if len(self._idx) == 1 else self._stage_vector
        y1, _ = stage(y_n, hg, L1, qs)
        k1 = (y1 - y_n) / hg
        y_hat = y_n + h * A21 * k1
        if qs:
            y_hat[self._idx] = y1[self._idx]  # fast variables carry no memory in the QS limit
        y2, out2 = stage(y_hat, hg, L2, qs)
        self.y = y2  # stiffly accurate: y_{n+1} is the last stage
        self.out = out2
        if self.method == "quasistationary":
            self._update_regime(L2)

    def _update_regime(self, L: Loads) -> None:
        """Quasistationary method: leave gross sliding when the slip law is unsaturated
        and the loads are admissible again (Eq. 27); enter it when they are not."""
        if self.sliding:
            beta_ok = not _saturated(self.law, self.y)
            if beta_ok and self._admissible(L):
                self.sliding = False
        elif self.out.sliding:
            self.sliding = True

    def _admissible(self, L: Loads) -> bool:
        """Eq. (27): the demanded force (Tx[, Ty]) is inside the capacity mu P."""
        b = self.body
        Tx = b.A2 * L.Fx_ex - b.A1 * L.My_ex / b.Rx
        Ty = L.Fy_ex if self.lateral.dynamic_vy else 0.0
        return math.hypot(Tx, Ty) < self.law.mu * self.law.P * (1.0 - CAPACITY_MARGIN)

    def _targets(self, L: Loads) -> FloatArray:
        """Forces the stage balances demand: Eqs. (26), (29), (30) in the QS limit."""
        b = self.body
        t = [b.A2 * L.Fx_ex - b.A1 * L.My_ex / b.Rx]
        if self.lateral.dynamic_vy:
            t.append(L.Fy_ex)
        if self.lateral.dynamic_spin:
            t.append(L.Mz_ex)
        return np.array(t)

    def _masses(self, algebraic: bool) -> FloatArray:
        if algebraic:
            return np.zeros(len(self._idx))
        b = self.body
        full = np.array([b.M, b.m_slip, b.M, b.Iz if b.Iz is not None else 0.0])
        return full[self._idx]

    def _apply_ratios(self, y: FloatArray) -> FloatArray:
        """Impose the held ratios on state(s) y, shape (4,) or (4, k); returns y."""
        if self.lateral.vy_ratio is not None:
            y[2] = self.lateral.vy_ratio * y[0]
        if self.lateral.spin_ratio is not None:
            y[3] = self.lateral.spin_ratio * y[0]
        return y

    def _stage_scalar(
        self, y_hat: FloatArray, hg: float, L: Loads, algebraic: bool
    ) -> tuple[FloatArray, ContactOutputs]:
        """Stage with one unknown, vx (Vy and Omega_z held): plain floats, as this is
        the inner loop of every co-simulation step. See ``_stage_vector``."""
        b, law = self.body, self.law
        ry, rz = self.lateral.vy_ratio, self.lateral.spin_ratio
        target = b.A2 * L.Fx_ex - b.A1 * L.My_ex / b.Rx
        m = 0.0 if algebraic else b.m_slip
        v_hat = float(y_hat[1])
        # Vx in terms of vx, T eliminated between Eqs. (8) and (20)
        Vb = float(y_hat[0]) + hg * b.A1 * (L.Fx_ex + L.My_ex / b.Rx) / b.M
        k = m / b.M

        def r(vx: float) -> float:
            Vx = Vb + k * (vx - v_hat)
            return m * (vx - v_hat) / hg + law.forces(vx, ry * Vx, rz * Vx, Vx)[0] - target

        scale = law.creep_full_slip * max(abs(Vb), V_SCALE_FLOOR)
        vx = self._solve_scalar(r, v_hat, m, hg, target, scale)
        Vx = Vb + k * (vx - v_hat)
        _, Ty, Mz = law.forces(vx, ry * Vx, rz * Vx, Vx)
        # the force that closes the stage balance (see _stage_vector), |Tx| <= mu P
        cap = law.mu * law.P
        Tx = min(max(target - m * (vx - v_hat) / hg, -cap), cap)
        y = np.array([Vx, vx, ry * Vx, rz * Vx])
        return y, ContactOutputs(Tx, float(Ty), float(Mz), _saturated(law, y))

    def _stage_vector(
        self, y_hat: FloatArray, hg: float, L: Loads, algebraic: bool
    ) -> tuple[FloatArray, ContactOutputs]:
        """Solve M (y - y_hat) = hg (B T(y) + F) for the stage value y."""
        b = self.body
        target = self._targets(L)
        m = self._masses(algebraic)
        # Vx in terms of vx, T eliminated between Eqs. (8) and (20):
        m_vx = 0.0 if algebraic else b.m_slip
        Vx_base = y_hat[0] + hg * b.A1 * (L.Fx_ex + L.My_ex / b.Rx) / b.M
        u_hat = y_hat[self._idx]
        idx = self._idx

        def states(U: FloatArray) -> FloatArray:
            """Stage states (k, 4) for unknowns U (k, n)."""
            Y = np.tile(y_hat, (U.shape[0], 1))
            Y[:, idx] = U
            Y[:, 0] = Vx_base + (m_vx / b.M) * (U[:, 0] - u_hat[0])
            return self._apply_ratios(Y.T).T

        def forces(Y: FloatArray) -> FloatArray:
            """(Tx, Ty, Mz) for each stage state, (k, 3): one vectorised law call."""
            T = self.law.forces(Y[:, 1], Y[:, 2], Y[:, 3], Y[:, 0])
            return np.stack([np.broadcast_to(t, Y.shape[:1]) for t in T], axis=1)

        act = [0] + [
            i for i, dyn in ((1, self.lateral.dynamic_vy), (2, self.lateral.dynamic_spin)) if dyn
        ]

        def residuals(U: FloatArray) -> FloatArray:
            return m * (U - u_hat) / hg + forces(states(U))[:, act] - target

        scale = self._scales(y_hat[0])[: len(idx)]
        u = self._solve_vector(residuals, u_hat.copy(), scale)
        y = states(u[None, :])[0]
        T = forces(y[None, :])[0]
        # The force that closes the stage balance: equal to T(y) where the law is
        # smooth, and the right value where it is set-valued (Vx = 0, stick). Its
        # magnitude is mu P at most; the clip removes the rounding of the difference.
        T[act] = target - m * (u - u_hat) / hg
        cap = self.law.mu * self.law.P
        if math.hypot(T[0], T[1]) > cap:
            T[:2] *= cap / math.hypot(T[0], T[1])
        sliding = _saturated(self.law, y)
        return y, ContactOutputs(float(T[0]), float(T[1]), float(T[2]), sliding)

    def _scales(self, Vx: float) -> FloatArray:
        v = self.law.creep_full_slip * max(abs(Vx), V_SCALE_FLOOR)
        return np.array([v, v, v / self.law.a1])

    def _solve_scalar(
        self, r, u0: float, m: float, hg: float, target: float, scale: float
    ) -> float:
        r0 = r(u0)
        if r0 == 0.0:
            return u0
        cap = self.law.mu * self.law.P
        direction = -1.0 if r0 > 0 else 1.0
        # r is increasing in u; the mass term bounds the root when m > 0
        step = scale
        if m > 0.0:
            step = min(step, hg * (cap + abs(target)) / m * (1.0 + 1e-12) + 1e-300)
        a = u0
        for _ in range(60):
            b = a + direction * step
            rb = r(b)
            if (rb > 0.0) != (r0 > 0.0):
                break
            a = b
            step *= 4.0
        else:
            raise StageSolveError(
                f"no slip velocity satisfies the stage equation (target force {target:.6g} N "
                f"against mu P = {cap:.6g} N)"
            )
        lo, hi = (a, b) if a < b else (b, a)
        tol = SOLVE_RTOL * (scale + abs(lo) + abs(hi))
        return float(brentq(r, lo, hi, xtol=tol, rtol=4 * np.finfo(float).eps, maxiter=200))

    def _solve_vector(self, residuals, u0: FloatArray, scale: FloatArray) -> FloatArray:
        """Newton with a forward-difference Jacobian (one batched residual call per
        iteration) and backtracking; scipy's hybrid method if that stalls."""
        n = len(u0)
        u = u0.copy()
        r = residuals(u[None, :])[0]
        for _ in range(50):
            du = FD_STEP * (np.abs(u) + scale)
            R = residuals(u + np.diag(du))
            J = (R - r).T / du
            try:
                step = np.linalg.solve(J, -r)
            except np.linalg.LinAlgError:
                break
            lam, norm0 = 1.0, np.linalg.norm(r)
            while True:
                u_new = u + lam * step
                r_new = residuals(u_new[None, :])[0]
                if np.linalg.norm(r_new) < norm0 or lam < 1e-4:
                    break
                lam *= 0.5
            u, r = u_new, r_new
            if np.all(np.abs(lam * step) <= SOLVE_RTOL * (np.abs(u) + scale)):
                return u
        sol = root(
            lambda v: residuals(v[None, :])[0], u, method="hybr", options={"xtol": SOLVE_RTOL}
        )
        if not sol.success:
            raise StageSolveError(f"stage solve failed after Newton and hybr: {sol.message}")
        return np.asarray(sol.x).reshape(n)

    def _contact_at(self, y: FloatArray) -> ContactOutputs:
        T = self.law.forces(y[1], y[2], y[3], y[0])
        return ContactOutputs(float(T[0]), float(T[1]), float(T[2]), _saturated(self.law, y))


def _checked(L: Loads) -> Loads:
    """Loads with finite values, or InputError naming the first bad one."""
    if not math.isfinite(sum(L)):
        for name, val in zip(Loads._fields, L, strict=True):
            finite(name, val)
    return L


def _saturated(law: ContactLaw, y: FloatArray) -> bool:
    """Gross sliding at state y: the slip is at or beyond the onset of full slip."""
    return is_full_slip(law, y[1], y[2], y[0])
