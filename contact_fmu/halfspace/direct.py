"""The steady-rolling problem of small grids by dense direct Newton steps.

Below a few hundred unknowns the iterative path of ``rolling.coulomb_newton`` (GMRES
with the FFT block preconditioner) costs its Python overhead per iteration, not its
arithmetic. Here the steady-rolling operator K restricted to the contact (2 m x 2 m
for m contact elements, component-major) is formed once per patch by applying
``RollingPatch.apply_K`` to unit tractions, and every Newton step of the same
semismooth method (same fixed-point form, same backtracking, same convergence test)
solves its generalised Jacobian

    J = I - P (I - r K),   P = I (adhesion),  P = (g/|z|) (I - zhat zhat^T) (slip),

by LAPACK (dgesv), reduced to the unknowns it couples (``_direction``). The initial
guess is the full-adhesion solution K^-1 W (LU cached per patch) projected on
|tau| <= g. Converged solutions agree with
the iterative path to the Newton tolerance (tests/test_halfspace_direct.py).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.linalg as sla
from numpy.typing import NDArray
from scipy.linalg.lapack import dgesv

FloatArray = NDArray[np.float64]

# Backtracking as in rolling.coulomb_newton.
ARMIJO = 1e-4
MIN_STEP = 1.0 / 64.0


def contact_operator(patch: Any) -> FloatArray:
    """K on the contact: (2 m, 2 m), columns K e_j for unit tractions e_j (m/Pa)."""
    C = patch.contact
    jj, ii = np.nonzero(C)
    m = len(jj)
    K = np.empty((2 * m, 2 * m))
    unit = np.zeros((2, *patch.grid.shape))
    for a in range(2):
        for e in range(m):
            unit[a, jj[e], ii[e]] = 1.0
            Ke = patch.apply_K(unit)
            unit[a, jj[e], ii[e]] = 0.0
            K[:m, a * m + e] = Ke[0][C]
            K[m:, a * m + e] = Ke[1][C]
    return K


def newton(
    patch: Any, W: FloatArray, tau0: FloatArray | None, tol: float, maxit: int
) -> tuple[FloatArray, FloatArray, NDArray[np.bool_], int]:
    """Semismooth Newton on the contact with dense Jacobians. Returns tau, S (2, ny, nx),
    the slip mask and the Newton count; RuntimeError after ``maxit`` steps."""
    C, r = patch.contact, patch.r
    K = patch.dense_contact_operator
    m = K.shape[0] // 2
    g = patch.g[C]
    gmax = float(g.max())
    w = np.concatenate([W[0][C], W[1][C]])
    if tau0 is None:
        t = sla.lu_solve(patch.dense_contact_lu, w)
        mag = np.hypot(t[:m], t[m:])
        over = mag > g
        t = t * np.tile(np.where(over, g / np.where(over, mag, 1.0), 1.0), 2)
    else:
        t = np.concatenate([tau0[0][C], tau0[1][C]])

    def residual(t: FloatArray):
        s = w - K @ t
        z = t + r * s
        zx, zy = z[:m], z[m:]
        nz = np.hypot(zx, zy)
        slip = nz > g
        scale = np.where(slip, g / np.where(slip, nz, 1.0), 1.0)
        F = t - z * np.tile(scale, 2)
        return F, s, zx, zy, nz, slip

    F, s, zx, zy, nz, slip = residual(t)
    fnorm = float(np.sqrt(F @ F))
    it = 0
    rK = r * K
    while float(np.abs(F).max()) > tol * gmax:
        if it >= maxit:
            raise RuntimeError(
                f"steady rolling (direct): no convergence in {maxit} Newton steps "
                f"(max |F| / max g = {float(np.abs(F).max()) / gmax:.3g})"
            )
        it += 1
        nS = int(slip.sum())
        if 8 * nS * nS * m < (2 * m - nS) ** 3 // 2:  # Woodbury's cost below the LU's
            dt = _woodbury(rK, patch.dense_contact_inverse / r, F, zx, zy, nz, g, slip)
        else:
            dt = _direction(rK, F, zx, zy, nz, g, slip)
        step = 1.0
        while True:
            trial = t + step * dt
            Ft, st, zxt, zyt, nzt, slipt = residual(trial)
            fn = float(np.sqrt(Ft @ Ft))
            if fn <= (1.0 - ARMIJO * step) * fnorm or step <= MIN_STEP:
                break
            step *= 0.5
        t, F, s, zx, zy, nz, slip, fnorm = trial, Ft, st, zxt, zyt, nzt, slipt, fn
    tau = np.zeros((2, *patch.grid.shape))
    tau[0][C], tau[1][C] = t[:m], t[m:]
    S = np.zeros_like(tau)
    S[0][C], S[1][C] = s[:m], s[m:]
    mask = np.zeros(patch.grid.shape, dtype=bool)
    mask[C] = slip
    return tau, S, mask, it


def _direction(
    rK: FloatArray,
    F: FloatArray,
    zx: FloatArray,
    zy: FloatArray,
    nz: FloatArray,
    g: FloatArray,
    slip: NDArray[np.bool_],
) -> FloatArray:
    """The Newton step J dtau = -F, J = I - P (I - r K), reduced to its coupled unknowns:
    in a slip element the row along zhat is local (zhat^T P = 0: dtau_n = -F_n), so the
    system keeps both components of the adhesion elements and the tangential one
    (that = (-zhat_y, zhat_x)) of the slip elements, whose row is (1 - f) that^T +
    f r that^T K, f = g/|z|. One LU of 2 nH + nS unknowns (up to a third fewer than 2 m)."""
    m = len(g)
    iH, iS = np.flatnonzero(~slip), np.flatnonzero(slip)
    nzS = nz[iS]
    hx, hy = zx[iS] / nzS, zy[iS] / nzS  # zhat of the slip elements
    tx, ty = -hy, hx
    f = g[iS] / nzS
    # dtau = B u + d0: u = (adhesion x, adhesion y, slip tangential); d0 = -F_n zhat
    Fn = hx * F[iS] + hy * F[m + iS]
    d0 = np.zeros(2 * m)
    d0[iS], d0[m + iS] = -Fn * hx, -Fn * hy
    cols = np.concatenate([iH, m + iH])
    rKB = np.concatenate([rK[:, cols], tx * rK[:, iS] + ty * rK[:, m + iS]], axis=1)
    rKd0 = rK @ d0
    nH2 = len(cols)
    # rows: adhesion (J = r K), slip tangential
    A = np.empty((nH2 + len(iS), rKB.shape[1]))
    A[:nH2] = rKB[cols]
    A[nH2:] = f[:, None] * (tx[:, None] * rKB[iS] + ty[:, None] * rKB[m + iS])
    A[nH2 + np.arange(len(iS)), nH2 + np.arange(len(iS))] += 1.0 - f
    rhs = np.concatenate(
        [
            -F[cols] - rKd0[cols],
            -(tx * F[iS] + ty * F[m + iS]) - f * (tx * rKd0[iS] + ty * rKd0[m + iS]),
        ]
    )
    u = _solve(A, rhs)
    dt = d0
    dt[cols] += u[:nH2]
    dt[iS] += u[nH2:] * tx
    dt[m + iS] += u[nH2:] * ty
    return dt


def _woodbury(
    rK: FloatArray,
    rKinv: FloatArray,
    F: FloatArray,
    zx: FloatArray,
    zy: FloatArray,
    nz: FloatArray,
    g: FloatArray,
    slip: NDArray[np.bool_],
) -> FloatArray:
    """The same Newton step when few elements slip: J = r K + U V differs from r K (the
    adhesion Jacobian, inverted once per patch) only in the 2 nS rows of the slip
    elements, V = (I - P)(I - r K) there, so the Sherman-Morrison-Woodbury formula needs
    one dense system of 2 nS unknowns: dtau = y - (rK)^-1 U C^-1 V y, y = -(rK)^-1 F,
    C = I + V (rK)^-1 U."""
    m = len(g)
    iS = np.flatnonzero(slip)
    rows = np.concatenate([iS, m + iS])
    y = -(rKinv @ F)
    if len(iS) == 0:
        return y
    nzS = nz[iS]
    hx, hy = zx[iS] / nzS, zy[iS] / nzS
    f = g[iS] / nzS
    # I - P = (1 - f) I + f zhat zhat^T per slip element
    qxx, qxy, qyy = (1.0 - f) + f * hx * hx, f * hx * hy, (1.0 - f) + f * hy * hy
    D = -rK[rows]  # (I - r K) on the slip rows
    k = len(iS)
    D[np.arange(k), iS] += 1.0
    D[k + np.arange(k), m + iS] += 1.0
    V = np.concatenate(
        [qxx[:, None] * D[:k] + qxy[:, None] * D[k:], qxy[:, None] * D[:k] + qyy[:, None] * D[k:]]
    )
    KU = rKinv[:, rows]
    Cap = V @ KU
    Cap[np.arange(2 * k), np.arange(2 * k)] += 1.0
    return y - KU @ _solve(Cap, V @ y)


def _solve(A: FloatArray, b: FloatArray) -> FloatArray:
    """x with A x = b by LAPACK's dgesv (no scipy checks; A and b overwritten)."""
    _, _, x, info = dgesv(A, b, overwrite_a=1, overwrite_b=1)
    if info != 0:
        raise RuntimeError(f"steady rolling (direct): singular Newton matrix ({info})")
    return x
