"""Explicit coupling of a contact force element with a rigid body: the step it needs.

A co-simulation master that connects a contact-mode FMU (Tx out) with a rigid-body FMU
(Tx in, Eqs. 8-9) exchanges Tx once per communication step, so the slip equation
(Eq. 20) M A2 dvx/dt = -Tx(vx) + A2 Fx_ex - A1 My_ex/Rx is integrated explicitly with
a delay of one step. Linearised, Tx = (dTx/dxi) vx/|Vx|, the slip relaxes with the time

    tau = M A2 |Vx| / (dTx/dxi at xi = 0),

and the delayed explicit update x_{n+1} = x_n - a x_{n-1}, a = h/tau, is stable only
for a < 1 (both roots of z^2 - z + a inside the unit circle); its error is first order
in a (tests/test_cosim_libcosim.py).
"""

from __future__ import annotations

from ..laws.protocol import ContactLaw
from .body import Body

# creepage of the central difference where a law gives no closed-form slope
FD_CREEP = 1e-10


def creep_slope(law: ContactLaw, Vx: float) -> float:
    """dTx/dxi at zero creep (N): the law's own (``creep_slope``, the thin layers'
    closed form) or a central difference of ``forces`` at xi = +-FD_CREEP."""
    own = getattr(law, "creep_slope", None)
    if own is not None:
        return float(own)
    v = FD_CREEP * abs(Vx)
    plus = float(law.forces(v, 0.0, 0.0, Vx)[0])
    minus = float(law.forces(-v, 0.0, 0.0, Vx)[0])
    return (plus - minus) / (2.0 * FD_CREEP)


def relaxation_time(law: ContactLaw, body: Body, Vx: float) -> float:
    """tau = M A2 |Vx| / (dTx/dxi) (s): the slip's relaxation time at speed Vx (m/s);
    0 at Vx = 0 or for eta = inf (A2 = 0), where explicit coupling has no stable step."""
    if Vx == 0.0 or body.A2 == 0.0:
        return 0.0
    return body.M * body.A2 * abs(Vx) / creep_slope(law, Vx)
