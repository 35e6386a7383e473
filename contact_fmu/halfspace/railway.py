"""Railway wheel on rail: a parameter set for the half-space law.

Nominal values (SI): an S1002-like wheel of 920 mm diameter (rolling radius 0.46 m,
a conical tread with no transverse curvature) on a UIC60 rail, whose head crown has a
transverse radius of 0.3 m (the rail is straight along x). Both are steel, E = 210 GPa,
nu = 0.28; wheel load P = 100 kN (a 20 t axle); dry friction mu = 0.3. With these the
Hertz contact has a1 = 7.2 mm along the track, a2 = 5.4 mm across it and p0 = 1.23 GPa
(contact_fmu.halfspace.hertz; the numbers are checked in tests/test_halfspace_hertz.py).
The real S1002 and UIC60 profiles vary along the lateral position of the contact; a
single point of contact at the running circle is what this set describes.
"""

from __future__ import annotations

import math

from .contact import DEFAULT_N, HalfSpaceContact
from .hertz import Material

# Wheel rolling radius (m), wheel tread transverse radius (m, conical tread: flat)
WHEEL_RADIUS = 0.46
WHEEL_TRANSVERSE_RADIUS = math.inf
# Rail head crown transverse radius (m) of UIC60; the rail is straight along x
RAIL_HEAD_RADIUS = 0.30
# Steel (Pa, -)
STEEL = Material(E=210e9, nu=0.28)
# Wheel load (N) and friction coefficient (-)
WHEEL_LOAD = 100e3
MU_DRY = 0.3


def wheel_on_rail(
    P: float = WHEEL_LOAD, mu: float = MU_DRY, n: int = DEFAULT_N
) -> HalfSpaceContact:
    """Wheel (the rolling body) on rail (the substrate), Hertzian, no layers."""
    return HalfSpaceContact(
        P=P,
        Rx=WHEEL_RADIUS,
        Ry=WHEEL_TRANSVERSE_RADIUS,
        body=STEEL,
        substrate=STEEL,
        mu=mu,
        Rsx=math.inf,
        Rsy=RAIL_HEAD_RADIUS,
        n=n,
    )
