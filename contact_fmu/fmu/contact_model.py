"""Contact mode: a force element for a host that owns the dynamics.

Inputs are the kinematics (Vx, Vy, Omega_y, Omega_z) and the normal load P; the
outputs (Tx, Ty, Mz and the contact quantities) follow directly from them through the
contact law, with the rigid slip of Eq. (3) at the contact centre. There is no state:
a step only holds the inputs.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ..dynamics.kinematics import ROLLING, SLIDING, contact_quantities, rigid_slip
from .config import ModelConfig
from .factory import make_law


class ContactElement:
    """T(Vx, Vy, Omega_y, Omega_z; P) of the configured contact law."""

    feedthrough = True

    def __init__(self, law: Any, Rx: float, inputs: Mapping[str, float]) -> None:
        self.law = law
        self.Rx = Rx
        self._out: dict[str, float] = {}
        self.evaluate(inputs)

    def evaluate(self, inputs: Mapping[str, float]) -> None:
        P = inputs["P"]
        law = self.law if P == self.law.P else self.law.with_load(P)
        Vx, Omega_y = inputs["Vx"], inputs["Omega_y"]
        Vy, Omega_z = inputs.get("Vy", 0.0), inputs.get("Omega_z", 0.0)
        vx, vy = rigid_slip(Vx, Omega_y, Vy, self.Rx)
        Tx, Ty, Mz = law.forces(vx, vy, Omega_z, Vx)
        out = {"vx": vx, "vy": vy, "Tx": float(Tx), "Ty": float(Ty), "Mz": float(Mz)}
        out.update(contact_quantities(law, Vx, vx, vy, Omega_z))
        if Omega_z != 0.0:  # with spin the creepage alone does not tell gross sliding:
            out["regime"] = ROLLING if out["adhesion"] > 0.0 else SLIDING  # no area left
        self.law, self._out = law, out

    def tune(self, params: Mapping[str, Any]) -> None:
        """mu for the next evaluation (the adapter recomputes the outputs)."""
        if "mu" in params:
            self.law = self.law.with_mu(params["mu"])

    @property
    def P(self) -> float:
        """The normal load (N) of the current outputs."""
        return self.law.P

    def step(self, h: float, inputs: Mapping[str, float]) -> str | None:
        self.evaluate(inputs)
        return None

    def outputs(self) -> dict[str, float]:
        return dict(self._out)

    def snapshot(self) -> Any:
        # the load, not the law: the law at a load is a function of it (a half-space
        # law holds its whole creep-force table, megabytes to copy and serialize)
        return (self.law.P, dict(self._out))

    def restore(self, snap: Any) -> None:
        P, out = snap
        self.law = self.law if P == self.law.P else self.law.with_load(P)
        self._out = dict(out)


def build(
    cfg: ModelConfig,
    params: Mapping[str, Any],
    inputs: Mapping[str, float],
    t0: float,
    data_dir: Path | None = None,
) -> ContactElement:
    law = make_law(cfg, params, inputs["P"], data_dir)
    return ContactElement(law, params["Rx"], inputs)
