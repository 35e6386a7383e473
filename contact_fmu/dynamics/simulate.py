"""Simulate the rolling body under given load histories on a uniform time grid."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .._validate import InputError, finite, positive
from ..laws.protocol import ContactLaw
from .body import ROLLING_STRAIGHT, Body, Lateral, Loads
from .integrator import LoadInput, RollingBody

FloatArray = NDArray[np.float64]
Signal = float | Callable[[float], float]


def load_history(
    Fx_ex: Signal = 0.0, Fy_ex: Signal = 0.0, My_ex: Signal = 0.0, Mz_ex: Signal = 0.0
) -> Callable[[float], Loads]:
    """Loads(t) from constants or functions of time t (s): forces in N, moments in N m."""
    parts = [f if callable(f) else (lambda _t, c=float(f): c) for f in (Fx_ex, Fy_ex, My_ex, Mz_ex)]
    return lambda t: Loads(*(float(f(t)) for f in parts))


@dataclass(frozen=True)
class Trajectory:
    """Results on the time grid t (s): velocities (m/s, rad/s), forces (N), moment (N m)."""

    t: FloatArray
    Vx: FloatArray
    Omega_y: FloatArray
    Vy: FloatArray
    Omega_z: FloatArray
    vx: FloatArray
    vy: FloatArray
    Tx: FloatArray
    Ty: FloatArray
    Mz: FloatArray
    sliding: NDArray[np.bool_]


def simulate(
    law: ContactLaw,
    body: Body,
    loads: LoadInput,
    t_end: float,
    dt: float,
    method: str = "full",
    lateral: Lateral = ROLLING_STRAIGHT,
    Vx0: float = 1.0,
    Omega_y0: float | None = None,
    Vy0: float = 0.0,
    Omega_z0: float = 0.0,
    substeps: int = 1,
    scheme: str = "lobatto3c",
) -> Trajectory:
    """Integrate Eqs. (8)-(11) from t = 0 to t_end with output step dt.

    ``method="full"``: the stiff slip equation (Eq. 20) with the creep law of ``law``;
    ``"quasistationary"``: Eqs. (26), (28)-(30). ``loads`` is Loads or a function of t
    returning Loads (see ``load_history``). Omega_y0 defaults to pure rolling, Vx0/Rx.
    ``substeps`` steps of ``scheme`` ("lobatto3c" or "sdirk2", see integrator) are taken
    per output step.
    """
    t_end = positive("t_end", t_end)
    dt = positive("dt", dt)
    n = int(round(t_end / dt))
    if n < 1 or abs(n * dt - t_end) > 1e-9 * t_end:
        raise InputError("t_end/dt", t_end / dt, "a whole number >= 1")
    Omega_y0 = finite("Vx0", Vx0) / body.Rx if Omega_y0 is None else Omega_y0
    rb = RollingBody(law, body, lateral, method, Vx0, Omega_y0, Vy0, Omega_z0, scheme=scheme)
    names = ("Vx", "Omega_y", "Vy", "Omega_z", "vx", "vy", "Tx", "Ty", "Mz")
    rec = {k: np.empty(n + 1) for k in names}
    sliding = np.zeros(n + 1, dtype=bool)

    def record(i: int) -> None:
        vals = (rb.Vx, rb.Omega_y, rb.Vy, rb.Omega_z, rb.vx, rb.vy, rb.out.Tx, rb.out.Ty, rb.out.Mz)
        for k, v in zip(names, vals, strict=True):
            rec[k][i] = v
        sliding[i] = rb.out.sliding

    record(0)
    for i in range(1, n + 1):
        rb.advance(dt, loads, substeps)
        record(i)
    return Trajectory(t=np.linspace(0.0, n * dt, n + 1), sliding=sliding, **rec)
