"""Rigid-body dynamics of the rolling body, Eqs. (8)-(11), (20)-(23), (27).

Sign conventions (Fig. 1, z up): v_x = Vx - Omega_y Rx - Omega_z y, v_y = Vy + Omega_z x
(Eq. 3); the body receives -T at the contact point (0, 0, -Rx). Its moment about y
is (-Rx e_z) x (-Tx e_x) = +Rx Tx e_y, so Eq. (9) reads

    Iy dOmega_y/dt = +Rx Tx + My_ex.

The printed Eq. (9) has -Rx Tx; only the + sign gives the paper's Eq. (20) and
A1, A2 of Eq. (23) (docs/model.md, "Sign of Eq. (9)"). Eliminating Omega_y with
vx = Vx - Omega_y Rx gives the slip-velocity equation (Eq. 20, dimensional):

    (M / (1 + eta)) dvx/dt = -Tx + A2 Fx_ex - A1 My_ex / Rx,    eta = M Rx^2 / Iy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validate import InputError, finite, nonnegative, positive


class Loads(NamedTuple):
    """External loads on the body (Eqs. 8-11): forces in N, moments in N m."""

    Fx_ex: float = 0.0
    Fy_ex: float = 0.0
    My_ex: float = 0.0
    Mz_ex: float = 0.0


@dataclass(frozen=True)
class Body:
    """Inertial properties of the rolling body.

    M mass (kg); Rx rolling radius (m); Iy moment of inertia about the axle (kg m^2),
    Iy = 0 is the limit eta = inf (Fig. 2); Iz moment of inertia about the vertical
    (kg m^2), needed only when Omega_z follows Eq. (11).
    """

    M: float
    Rx: float
    Iy: float
    Iz: float | None = None

    def __post_init__(self) -> None:
        positive("M", self.M)
        positive("Rx", self.Rx)
        nonnegative("Iy", self.Iy)
        if self.Iz is not None:
            positive("Iz", self.Iz)
        # A1, A2 (Eq. 23) divide by M Rx^2 + Iy: it must neither underflow to 0 nor
        # overflow (each value alone admissible, e.g. Rx = 5e-324 with Iy = 0)
        inertia = self.M * self.Rx**2 + self.Iy
        if not (0.0 < self.M * self.Rx**2 < math.inf and inertia < math.inf):
            raise InputError(
                "M Rx^2 + Iy",
                inertia,
                f"positive and finite with M Rx^2 > 0 (M = {self.M!r}, Rx = {self.Rx!r}, "
                f"Iy = {self.Iy!r})",
            )

    @classmethod
    def from_eta(cls, M: float, Rx: float, eta: float, Iz: float | None = None) -> Body:
        """Body with eta = M Rx^2 / Iy (Eq. 21); eta = inf gives Iy = 0."""
        eta = float(eta)
        if not eta > 0.0:  # also rejects NaN
            raise InputError("eta", eta, "> 0 (or inf)")
        Iy = 0.0 if math.isinf(eta) else M * Rx**2 / eta
        return cls(M, Rx, Iy, Iz)

    @property
    def eta(self) -> float:
        """eta = M Rx^2 / Iy (Eq. 21), inf for Iy = 0."""
        return math.inf if self.Iy == 0.0 else self.M * self.Rx**2 / self.Iy

    @property
    def A1(self) -> float:
        """A1 = eta / (1 + eta) (Eq. 23); 1 for eta = inf."""
        return 1.0 if self.Iy == 0.0 else self.M * self.Rx**2 / (self.M * self.Rx**2 + self.Iy)

    @property
    def A2(self) -> float:
        """A2 = 1 / (1 + eta) (Eq. 23); 0 for eta = inf."""
        return self.Iy / (self.M * self.Rx**2 + self.Iy)

    @property
    def m_slip(self) -> float:
        """Effective mass M/(1 + eta) = M A2 (kg) of the slip equation (Eq. 20)."""
        return self.M * self.A2

    def tx_demand(self, Fx_ex: float, My_ex: float) -> float:
        """Tx = A2 Fx_ex - A1 My_ex / Rx (N): the force Eq. (26) asks of the contact, the
        right-hand side of the slip equation's stages (Eq. 20); floats in, float out."""
        return self.A2 * Fx_ex - self.A1 * My_ex / self.Rx

    def tx_quasistationary(self, Fx_ex: ArrayLike, My_ex: ArrayLike) -> NDArray[np.float64]:
        """Tx = A2 Fx_ex - A1 My_ex / Rx (N), Eq. (26) in dimensional form (arrays)."""
        return self.tx_demand(np.asarray(Fx_ex, float), np.asarray(My_ex, float))


def load_utilisation(
    body: Body, mu: float, P: float, Fx_ex: ArrayLike, My_ex: ArrayLike, Fy_ex: ArrayLike = 0.0
) -> NDArray[np.float64]:
    """|(A2 Fx - A1 My/Rx, Fy)| / (mu P): the loads are admissible (Eq. 27) where < 1.

    With My_ex = 0 this is Fig. 4's ellipse in (Fx, Fy) (Eqs. 26, 29); with Fy_ex = 0,
    Fig. 3's strip in (Fx, My) (Eqs. 26, 27).
    """
    positive("mu", mu)
    positive("P", P)
    Tx = body.tx_quasistationary(Fx_ex, My_ex)
    return np.hypot(Tx, np.asarray(Fy_ex, float)) / (mu * P)


@dataclass(frozen=True)
class Lateral:
    """How Vy and Omega_z are determined (Section 2).

    ``vy_ratio``: Vy/Vx held fixed (-), or None for Eq. (10).
    ``spin_ratio``: Omega_z/Vx held fixed (1/m; the paper's Omega_z l / Vx divided by
    l), or None for Eq. (11).
    """

    vy_ratio: float | None = 0.0
    spin_ratio: float | None = 0.0

    def __post_init__(self) -> None:
        if self.vy_ratio is not None:
            finite("vy_ratio", self.vy_ratio)
        if self.spin_ratio is not None:
            finite("spin_ratio", self.spin_ratio)

    @property
    def dynamic_vy(self) -> bool:
        return self.vy_ratio is None

    @property
    def dynamic_spin(self) -> bool:
        return self.spin_ratio is None


# No lateral slip and no spin: the paper's example with v_y = 0 (Section 4).
ROLLING_STRAIGHT = Lateral(vy_ratio=0.0, spin_ratio=0.0)
