"""The rolling body's kinematic state, shared by the steady and the transient steppers.

y = (Vx, vx, Vy, Omega_z) in m/s and rad/s, with vx = Vx - Omega_y Rx the longitudinal
rigid slip at the contact centre and vy = Vy (Eq. 3 at x = y = 0). Vy and Omega_z
either follow their own equations (10)-(11) or are held at ratios to Vx (``Lateral``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .._validate import InputError, finite
from .body import Body, Lateral

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class ContactOutputs:
    """The contact at the end of a step: Tx, Ty (N), Mz (N m) and whether the body
    slides grossly (no adhesion area)."""

    Tx: float = 0.0
    Ty: float = 0.0
    Mz: float = 0.0
    sliding: bool = False


class BodyState:
    """State vector, held lateral ratios and the unknowns of the stage solves."""

    def __init__(
        self,
        body: Body,
        lateral: Lateral,
        Vx0: float,
        Omega_y0: float,
        Vy0: float,
        Omega_z0: float,
        t0: float,
    ) -> None:
        if lateral.dynamic_spin and body.Iz is None:
            raise InputError("Iz", None, "given when Omega_z follows Eq. (11)")
        self.body = body
        self.lateral = lateral
        self.t = finite("t0", t0)
        Vx0 = finite("Vx0", Vx0)
        vx0 = Vx0 - finite("Omega_y0", Omega_y0) * body.Rx
        self.y = np.array([Vx0, vx0, finite("Vy0", Vy0), finite("Omega_z0", Omega_z0)])
        self._apply_ratios(self.y)
        # unknowns of the stage solves: indices into (Tx, Ty, Mz) and into y
        dyn = ((1, lateral.dynamic_vy), (2, lateral.dynamic_spin))
        self._act = [0] + [i for i, d in dyn if d]
        self._idx = [i + 1 for i in self._act]

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

    def kinematics(self) -> dict[str, float]:
        """Velocities and rigid slips (SI), the first keys of a stepper's outputs()."""
        Vx, vx, Vy, Omega_z = self.y.tolist()  # the properties' values, in one call
        return {
            "Vx": Vx,
            "Vy": Vy,
            "Omega_y": (Vx - vx) / self.body.Rx,
            "Omega_z": Omega_z,
            "vx": vx,
            "vy": Vy,
        }

    def _apply_ratios(self, y: FloatArray) -> FloatArray:
        """Impose the held ratios on state(s) y, shape (4,) or (4, k); returns y."""
        if self.lateral.vy_ratio is not None:
            y[2] = self.lateral.vy_ratio * y[0]
        if self.lateral.spin_ratio is not None:
            y[3] = self.lateral.spin_ratio * y[0]
        return y
