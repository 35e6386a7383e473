"""GMRES for the Newton systems of the half-space solvers: scipy's (restarted, the
preconditioner on the left) with its iteration count (the transient solver), and
``gmres_right`` (the preconditioner on the right, with a side product; steady rolling
and its full-adhesion solves), as the block preconditioner uses them."""

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


def gmres_right(
    matvec: Callable[[FloatArray], tuple[FloatArray, FloatArray]],
    b: FloatArray,
    psolve: Callable[[FloatArray], FloatArray],
    rtol: float,
    restart: int,
    maxit: int,
) -> tuple[FloatArray, int, FloatArray | None]:
    """Restarted GMRES with the preconditioner on the right (Saad 2003, Alg. 9.5) from
    x0 = 0, stopped when the true residual |b - A x| is at most rtol |b| (the measure
    of the inexact-Newton forcing terms) or after ``maxit`` iterations in all.

    matvec(z) returns (A z, a side product linear in z), e.g. the full field of which
    A z is a restriction: the side products of the iterations combine with the same
    coefficients as x, so that the caller gets the side product of x without another
    application of the operator. Unlike scipy's gmres, no matvec or preconditioner
    solve is spent on the initial or the final residual (the Arnoldi recurrence gives
    its norm). Returns x, the iteration count and the side product of x (None for
    b = 0)."""
    N = len(b)
    x = np.zeros(N)
    side: FloatArray | None = None
    beta0 = float(np.linalg.norm(b))
    if beta0 == 0.0:
        return x, 0, side
    target = rtol * beta0
    r = b
    Ax = np.zeros(N)
    its = 0
    while True:
        beta = float(np.linalg.norm(r))
        V = np.empty((restart + 1, N))
        V[0] = r / beta
        Hm = np.zeros((restart + 1, restart))
        cs, sn = np.zeros(restart), np.zeros(restart)
        g = np.zeros(restart + 1)
        g[0] = beta
        Z, AZ, sides = [], [], []
        k = 0
        while k < restart and its < maxit:
            z = psolve(V[k])
            w, s = matvec(z)
            Z.append(z)
            AZ.append(w.copy())
            sides.append(s)
            # classical Gram-Schmidt applied twice (as stable as modified, in two
            # matrix products)
            h = V[: k + 1] @ w
            w = w - h @ V[: k + 1]
            h2 = V[: k + 1] @ w
            w -= h2 @ V[: k + 1]
            h += h2
            hn = float(np.linalg.norm(w))
            col = np.append(h, hn)
            for i in range(k):  # the earlier Givens rotations
                col[i], col[i + 1] = (
                    cs[i] * col[i] + sn[i] * col[i + 1],
                    (-sn[i] * col[i] + cs[i] * col[i + 1]),
                )
            d = float(np.hypot(col[k], col[k + 1]))
            cs[k], sn[k] = (col[k] / d, col[k + 1] / d) if d > 0.0 else (1.0, 0.0)
            col[k], col[k + 1] = d, 0.0
            g[k], g[k + 1] = cs[k] * g[k], -sn[k] * g[k]
            Hm[: k + 2, k] = col
            its += 1
            k += 1
            if abs(g[k]) <= target or hn <= 1e-14 * beta0:
                break
            V[k] = w / hn
        y = np.linalg.solve(np.triu(Hm[:k, :k]), g[:k]) if k else np.zeros(0)
        for i in range(k):
            x += y[i] * Z[i]
            Ax += y[i] * AZ[i]
            if sides[i] is not None:
                side = y[i] * sides[i] if side is None else side + y[i] * sides[i]
        if abs(g[k]) <= target or its >= maxit or hn <= 1e-14 * beta0:
            return x, its, side
        r = b - Ax
