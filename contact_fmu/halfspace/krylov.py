"""GMRES for the Newton systems of the half-space solvers.

``gmres`` is scipy's (restarted, the preconditioner on the left) with its iteration
count, as the block preconditioner uses it; ``fgmres`` is right-preconditioned GMRES
for an expensive preconditioner (the multigrid V-cycle):

scipy.sparse.linalg.gmres preconditions on the left and applies the preconditioner
twice more per solve than it iterates (5 applications for 2 iterations, measured with
scipy 1.17), and gcrotmk once more; with a V-cycle that costs as much as 15 to 35
influence products and a solve that needs 1 to 2 iterations, that triples the cost.
Here the preconditioner runs once per iteration (Saad 2003, Iterative Methods for
Sparse Linear Systems, Alg. 9.5, flexible form: the preconditioned vectors are kept,
so the preconditioner may change between iterations), and the stopping test is on the
true residual |b - A x| <= rtol |b| from the Givens-rotated Hessenberg system.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.linalg as sla
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


def fgmres(
    matvec: Callable[[FloatArray], FloatArray],
    b: FloatArray,
    psolve: Callable[[FloatArray], FloatArray],
    rtol: float,
    maxit: int,
) -> tuple[FloatArray, int]:
    """x with |b - A x| <= rtol |b| from x0 = 0 in at most maxit iterations (no restart);
    returns x and the iteration count (the last iterate if maxit is reached)."""
    beta = float(np.linalg.norm(b))
    x = np.zeros_like(b)
    if beta == 0.0 or maxit <= 0:
        return x, 0
    V = [b / beta]
    Z: list[FloatArray] = []
    R = np.zeros((maxit, maxit))  # the Hessenberg matrix, rotated to triangular
    cs, sn = np.zeros(maxit), np.zeros(maxit)
    g = np.zeros(maxit + 1)  # the rotated right-hand side beta e1
    g[0] = beta
    k = 0
    for j in range(maxit):
        z = psolve(V[j])
        w = matvec(z)
        h = np.empty(j + 2)
        for i in range(j + 1):  # modified Gram-Schmidt
            h[i] = float(w @ V[i])
            w = w - h[i] * V[i]
        h[j + 1] = float(np.linalg.norm(w))
        for i in range(j):  # the earlier rotations on the new column
            h[i], h[i + 1] = cs[i] * h[i] + sn[i] * h[i + 1], -sn[i] * h[i] + cs[i] * h[i + 1]
        den = float(np.hypot(h[j], h[j + 1]))
        if den == 0.0:  # A z = 0 within the Krylov space: no progress possible
            break
        cs[j], sn[j] = h[j] / den, h[j + 1] / den
        R[: j + 1, j] = h[: j + 1]
        R[j, j] = den
        g[j + 1] = -sn[j] * g[j]
        g[j] = cs[j] * g[j]
        Z.append(z)
        k = j + 1
        if abs(g[j + 1]) <= rtol * beta or h[j + 1] == 0.0:
            break
        V.append(w / h[j + 1])
    if k:
        y = sla.solve_triangular(R[:k, :k], g[:k])
        x = np.asarray(Z).T @ y
    return x, k
