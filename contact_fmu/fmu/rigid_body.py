"""The rigid body of Eqs. (8)-(9) alone, driven by the contact force Tx of another FMU.

    M  dVx/dt      = Fx_ex - Tx
    Iy dOmega_y/dt = My_ex + Rx Tx      (the + sign of Eq. 9, see dynamics/body.py)

With the inputs held over a communication step the right-hand sides are constant, so
the update Vx += h (Fx_ex - Tx)/M, Omega_y += h (My_ex + Rx Tx)/Iy is exact. Coupled
to a contact-mode FMU through a master, the creep force is exchanged explicitly; that
is stable only for steps below the slip relaxation time (see tests/test_cosim*.py).

A step that would take Vx beyond SPEED_MAX or Omega_y beyond RATE_MAX (a huge Tx, Fx_ex
or My_ex, or one held too long) is refused with the body mode's check
(ranges.within_range), before the state changes: the adapter discards the step.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from .._validate import finite, positive
from .config import ModelConfig
from .factory import initial_state
from .ranges import within_range


class RigidBody:
    feedthrough = False

    def __init__(self, M: float, Rx: float, Iy: float, Vx0: float, Omega_y0: float) -> None:
        self.M = positive("M", M)
        self.Rx = positive("Rx", Rx)
        self.Iy = positive("Iy", Iy)
        within_range({"Vx": Vx0, "Omega_y": Omega_y0}, start=True)  # Rx may be tiny
        self.Vx = finite("Vx0", Vx0)
        self.Omega_y = finite("Omega_y0", Omega_y0)

    def step(self, h: float, inputs: Mapping[str, float]) -> str | None:
        Tx = inputs["Tx"]
        Vx = self.Vx + h * (inputs.get("Fx_ex", 0.0) - Tx) / self.M
        Omega_y = self.Omega_y + h * (inputs.get("My_ex", 0.0) + self.Rx * Tx) / self.Iy
        within_range({"Vx": Vx, "Omega_y": Omega_y})  # inf (overflow) is beyond too
        self.Vx, self.Omega_y = Vx, Omega_y
        return None

    def evaluate(self, inputs: Mapping[str, float]) -> None:  # no feedthrough
        return None

    def outputs(self) -> dict[str, float]:
        return {"Vx": self.Vx, "Omega_y": self.Omega_y}

    def snapshot(self) -> Any:
        return (self.Vx, self.Omega_y)

    def restore(self, snap: Any) -> None:
        self.Vx, self.Omega_y = snap


def build(
    cfg: ModelConfig,
    params: Mapping[str, Any],
    inputs: Mapping[str, float],
    t0: float,
    data_dir: Any = None,  # no contact law, no data
) -> RigidBody:
    p = params
    start = initial_state(p)
    return RigidBody(p["M"], p["Rx"], p["Iy"], start["Vx0"], start["Omega_y0"])
