"""The parameter set chosen for the paper's example (Section 4, Figs. 2-13).

The paper gives the shapes of its figures but not all parameter values. The values
here are chosen so that its lateral creepages vy/Vx = 0.002 and 0.006 are a fifth
and three fifths of the creepage at full slip (about 0.01), and epsilon = a1/Rx is
about 0.05. Times are in units of the characteristic time T_c of Eq. (13) with
p_c = p0 and l^2 = a1 a2, forces in units of mu p0 a1 a2, as in the paper's figures.
See docs/model.md, "Parameters of the figures".
"""

from __future__ import annotations

import math

from .dynamics.body import Body
from .laws.thin_layer import LayerContact

# Normal load (N), radii of the ellipsoid of revolution (m), friction coefficient (-)
P = 1000.0
Rx = 0.05
Ry = 0.10
mu = 0.3
# Layer compliances (m/Pa): Winkler layers on body and substrate (Eqs. 31-32)
k1 = k2 = 5.0e-13
kb = ks = 3.2e-13
# Mass of the body (kg); Iy follows from eta = M Rx^2 / Iy (Eq. 21)
M = 1.0

# eta of the figures: Fig. 2-4 (1, 5/2, inf), Figs. 6-12 (10.9, 2.92, 1.7), Fig. 13 (1.5, 3, 10)
ETA_FIG3 = (1.0, 2.5, math.inf)
ETA_FIG6_12 = (10.9, 2.92, 1.7)
ETA_FIG13 = (1.5, 3.0, 10.0)
VY_RATIOS = (0.0, 0.002, 0.006)
# Figs. 6-12 load the body by Fx_ex alone; the paper does not say how much. Three force
# units (Tx = A2 Fx_ex = 0.16, 0.49, 0.71 mu P for eta = 10.9, 2.92, 1.7) separate the
# three bodies' adhesion areas as clearly as the paper's figures do.
FX_FIG6_12_UNITS = 3.0
# Fig. 13: Fx_ex = 1 force unit, My_ex = 0.2 force units x Rx x sin(t / T_c)
FX_FIG13_UNITS = 1.0
MY_FIG13_UNITS = 0.2


def contact() -> LayerContact:
    """The thin-layer contact of the example."""
    return LayerContact(P=P, Rx=Rx, Ry=Ry, k1=k1, k2=k2, kb=kb, ks=ks, mu=mu)


def body(eta: float) -> Body:
    """The body of mass M with the given eta (Iy = M Rx^2 / eta)."""
    return Body.from_eta(M, Rx, eta)


def force_unit(c: LayerContact | None = None) -> float:
    """mu p0 a1 a2 (N): the force unit of Figs. 5 and 13 (mu P = pi/2 of it)."""
    c = c or contact()
    return c.mu * c.p0 * c.a1 * c.a2


def time_unit(c: LayerContact | None = None) -> float:
    """T_c = (M Rx / (p_c l^2))^(1/2) of Eq. (13) with p_c l^2 = p0 a1 a2 (s)."""
    c = c or contact()
    return math.sqrt(M * Rx / (c.p0 * c.a1 * c.a2))


def speed_unit(c: LayerContact | None = None) -> float:
    """Rx / T_c (m/s): the unit of Vx in Eq. (12)."""
    return Rx / time_unit(c)
