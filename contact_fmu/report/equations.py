"""Eqs. (8)-(11) as a first-order system for scipy's solve_ivp, and the closed form of
the quasistationary phase (Eqs. 26, 28): the references of the work-precision report.

This is written from the paper's equations, not from the stepper: the state is
(Vx, vx[, Vy][, Omega_z]) and the right-hand side takes Eqs. (8) and (9) as printed
(with the corrected sign of Eq. 9, docs/model.md),

    M  dVx/dt      = -Tx + Fx_ex                                  (8)
    Iy dOmega_y/dt = +Rx Tx + My_ex                               (9)
    dvx/dt         = dVx/dt - Rx dOmega_y/dt                      (Eq. 3 at the centre)
    M  dVy/dt      = -Ty + Fy_ex                                  (10), or Vy = vy_ratio Vx
    Iz dOmega_z/dt = -Mz + Mz_ex                                  (11), or Omega_z = spin_ratio Vx

so the slip vx is integrated directly (integrating Omega_y instead would lose vx ~ 1e-4 Vx
to cancellation in Vx - Omega_y Rx). The contact law is the model's law; like the
stepper it is blended at |Vx| < V_STANDSTILL (integrator.forces_at_rest, the model's
definition at standstill).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..dynamics.body import Body, Lateral
from ..dynamics.integrator import forces_at_rest
from ..laws.thin_layer import LayerContact

FloatArray = NDArray[np.float64]
# Loads(t) -> (P, Fx_ex, Fy_ex, My_ex, Mz_ex) in N and N m
LoadFunction = Callable[[float], tuple[float, float, float, float, float]]


@dataclass(frozen=True)
class RollingEquations:
    """Eqs. (8)-(11) for one body on one contact law under loads(t)."""

    law: LayerContact
    body: Body
    lateral: Lateral
    loads: LoadFunction

    def __post_init__(self) -> None:
        if self.body.Iy == 0.0:
            raise ValueError("eta = inf (Iy = 0): Eq. (9) is algebraic; no ODE reference")
        if self.lateral.dynamic_spin and self.body.Iz is None:
            raise ValueError("Omega_z from Eq. (11) needs Iz")

    @property
    def size(self) -> int:
        return 2 + int(self.lateral.dynamic_vy) + int(self.lateral.dynamic_spin)

    def initial(self, Vx0: float, Omega_y0: float, Vy0: float = 0.0, Omega_z0: float = 0.0):
        """State (Vx, vx[, Vy][, Omega_z]) from the FMU's initial values."""
        y = [Vx0, Vx0 - Omega_y0 * self.body.Rx]
        if self.lateral.dynamic_vy:
            y.append(Vy0)
        if self.lateral.dynamic_spin:
            y.append(Omega_z0)
        return np.array(y, float)

    def kinematics(self, y: FloatArray) -> tuple[float, float, float, float]:
        """(Vx, vx, vy, Omega_z) of state y."""
        Vx, vx = float(y[0]), float(y[1])
        i = 2
        if self.lateral.dynamic_vy:
            vy, i = float(y[i]), i + 1
        else:
            vy = self.lateral.vy_ratio * Vx
        phi = float(y[i]) if self.lateral.dynamic_spin else self.lateral.spin_ratio * Vx
        return Vx, vx, vy, phi

    def forces(self, t: float, y: FloatArray) -> tuple[float, float, float]:
        """(Tx, Ty, Mz) of the law at state y and time t (the load P(t) sets the contact)."""
        Vx, vx, vy, phi = self.kinematics(y)
        P = self.loads(t)[0]
        law = self.law if P == self.law.P else self.law.with_load(P)
        return forces_at_rest(law, vx, vy, phi, Vx)

    def rhs(self, t: float, y: FloatArray) -> FloatArray:
        """dy/dt of Eqs. (8)-(11)."""
        _, Fx, Fy, My, Mzx = self.loads(t)
        Tx, Ty, Mz = self.forces(t, y)
        b = self.body
        dVx = (-Tx + Fx) / b.M
        dOy = (b.Rx * Tx + My) / b.Iy
        d = [dVx, dVx - b.Rx * dOy]
        if self.lateral.dynamic_vy:
            d.append((-Ty + Fy) / b.M)
        if self.lateral.dynamic_spin:
            d.append((-Mz + Mzx) / b.Iz)
        return np.array(d)


def quasistationary_force(body: Body, Fx: FloatArray, My: FloatArray) -> FloatArray:
    """Tx = A2 Fx_ex - A1 My_ex/Rx (N), Eq. (26) with A1, A2 of Eq. (23) from M, Rx, Iy."""
    eta_part = body.M * body.Rx**2
    A1 = eta_part / (eta_part + body.Iy)
    A2 = body.Iy / (eta_part + body.Iy)
    return A2 * np.asarray(Fx, float) - A1 * np.asarray(My, float) / body.Rx


def quasistationary_slip(law: LayerContact, Tx: float, Vx: float, xi_y: float) -> float:
    """vx = |Vx| T_x^-1(Tx) of Eq. (28) for a held lateral creepage xi_y = vy/Vx (m/s).

    The creep law depends on |v|/|Vx| and T points along v, so the slip that carries Tx
    has the sign of Tx whatever the direction of rolling.
    """
    return abs(Vx) * law.inverse_creep(Tx, xi_y=xi_y)
