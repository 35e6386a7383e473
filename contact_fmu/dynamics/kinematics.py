"""Rigid slip (Eq. 3) and the contact quantities reported at given kinematics."""

from __future__ import annotations

import math

from ..laws.protocol import ContactLaw

# |Vx| floor (m/s) of the reported creepages v/|Vx|: below it the body is at rest in
# practice and the creepage would be meaningless; the contact law itself has no floor.
V_CREEP_FLOOR = 1e-6

# Regime indicator values of the outputs.
ROLLING = 0.0  # rolling with partial slip (an adhesion area exists)
SLIDING = 1.0  # gross sliding (|T| = mu P, no adhesion)


def rigid_slip(Vx: float, Omega_y: float, Vy: float, Rx: float) -> tuple[float, float]:
    """(vx, vy) at the contact centre, Eq. (3) at x = y = 0 (m/s)."""
    return Vx - Omega_y * Rx, Vy


def spin_for_slip(Vx: float, vx: float, Rx: float) -> float:
    """Omega_y (rad/s) at which the body moving at Vx has the rigid slip vx at the contact
    centre: Eq. (3) solved, (Vx - vx)/Rx; vx = 0 is pure rolling."""
    return (Vx - vx) / Rx


def creepage(v: float, Vx: float) -> float:
    """v / |Vx| with |Vx| floored at V_CREEP_FLOOR (-)."""
    return v / max(abs(Vx), V_CREEP_FLOOR)


def is_full_slip(law: ContactLaw, vx: float, vy: float, Vx: float) -> bool:
    """Gross sliding: |v| at or beyond the onset of full slip, |v| >= creep_full_slip |Vx|."""
    speed = math.hypot(vx, vy)
    return speed > 0.0 and speed >= law.creep_full_slip * abs(Vx)


def contact_quantities(
    law: ContactLaw, Vx: float, vx: float, vy: float, Omega_z: float
) -> dict[str, float]:
    """Creepages, contact ellipse, adhesion fraction and regime at the given slip (SI)."""
    V = max(abs(Vx), V_CREEP_FLOOR)  # creepage's denominator, once
    return {
        "xi_x": vx / V,
        "xi_y": vy / V,
        "xi_sp": Omega_z / V,
        "a1": law.a1,
        "a2": law.a2,
        "p0": law.p0,
        "adhesion": float(law.adhesion_fraction(vx, vy, Vx, Omega_z)),
        "regime": SLIDING if is_full_slip(law, vx, vy, Vx) else ROLLING,
    }
