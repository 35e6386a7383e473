"""The contact-law protocol: what the steppers, the FMU and the outputs need of a law.

Implemented by ``thin_layer.LayerContact`` (thin layers, Section 4) and
``halfspace.table.CreepTable`` (the exact half-space theory, tabulated).
"""

from __future__ import annotations

from typing import Protocol


class ContactLaw(Protocol):
    """A steady creep-force law under the normal load P.

    forces(vx, vy, phi, Vx) -> (Tx, Ty, Mz) in N and N m for rigid slip (vx, vy) at the
    contact centre (m/s), spin phi = Omega_z (rad/s) and rolling speed Vx (m/s), in the
    sign convention of Eq. (8): the body receives -T. Floats in, floats out must work
    (the integrator's inner loop); arrays in, arrays out too. creep_full_slip is |v|/|Vx|
    at the onset of full slip; a1, a2 (m) and p0 (Pa) describe the contact ellipse.
    Optional: tx_slope(vx, vy, Vx) -> (Tx, dTx/dvx, dTx/dvy, dTx/dVx) for floats, used
    by the stage solves when present.
    """

    P: float
    mu: float
    a1: float
    a2: float
    p0: float
    creep_full_slip: float

    def forces(self, vx, vy, phi, Vx) -> tuple: ...

    def adhesion_fraction(self, vx, vy, Vx, phi=0.0): ...  # adhesion area / contact area

    def with_load(self, P: float) -> ContactLaw: ...
