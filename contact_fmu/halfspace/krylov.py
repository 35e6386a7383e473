"""GMRES for the Newton systems of the half-space solvers: scipy's (restarted, the
preconditioner on the left) with its iteration count, as the block preconditioner
uses it."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.sparse.linalg as spla
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


def gmres(
    matvec: Callable[[FloatArray], FloatArray],
    b: FloatArray,
    psolve: Callable[[FloatArray], FloatArray],
    rtol: float,
    restart: int,
    maxit: int,
) -> tuple[FloatArray, int]:
    """scipy.sparse.linalg.gmres from x0 = 0 to rtol (atol 0), restarted every ``restart``
    and stopped after ``maxit`` iterations in all; returns x and the iteration count."""
    N = len(b)
    count = [0]
    x, _ = spla.gmres(
        spla.LinearOperator((N, N), matvec=matvec, dtype=float),
        b,
        M=spla.LinearOperator((N, N), matvec=psolve, dtype=float),
        rtol=rtol,
        atol=0.0,
        restart=restart,
        maxiter=maxit // restart,
        callback=lambda _: count.__setitem__(0, count[0] + 1),
        callback_type="pr_norm",
    )
    return x, count[0]
