"""The steady-rolling problem of small grids by dense direct Newton steps.

Below a few hundred unknowns the iterative path of ``rolling.coulomb_newton`` (GMRES
with the FFT block preconditioner) costs its Python overhead per iteration, not its
arithmetic. Here the steady-rolling operator K restricted to the contact (2 m x 2 m
for m contact elements, component-major) is formed once per patch by applying
``RollingPatch.apply_K`` to unit tractions, and every Newton step of the same
semismooth method (same fixed-point form, same backtracking, same convergence test)
solves its generalised Jacobian

    J = I - P (I - r K),   P = I (adhesion),  P = (g/|z|) (I - zhat zhat^T) (slip),

by LAPACK (numpy.linalg.solve). The initial guess is the full-adhesion solution
K^-1 W (LU cached per patch) projected on |tau| <= g. Converged solutions agree with
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
    top, bottom = rK[:m], rK[m:]
    idx = np.arange(m)
    J = np.empty_like(K)
    while float(np.abs(F).max()) > tol * gmax:
        if it >= maxit:
            raise RuntimeError(
                f"steady rolling (direct): no convergence in {maxit} Newton steps "
                f"(max |F| / max g = {float(np.abs(F).max()) / gmax:.3g})"
            )
        it += 1
        # P as 2 x 2 blocks per element: identity in adhesion, the scaled tangential
        # projector in slip
        f = np.where(slip, g / np.where(slip, nz, 1.0), 1.0)
        hx = np.where(slip, zx / np.where(slip, nz, 1.0), 0.0)
        hy = np.where(slip, zy / np.where(slip, nz, 1.0), 0.0)
        pxx, pxy, pyy = f * (1.0 - hx * hx), -f * hx * hy, f * (1.0 - hy * hy)
        # J = I - P + P r K, row blocks written in place
        np.multiply(pxx[:, None], top, out=J[:m])
        J[:m] += pxy[:, None] * bottom
        np.multiply(pxy[:, None], top, out=J[m:])
        J[m:] += pyy[:, None] * bottom
        J[idx, idx] += 1.0 - pxx
        J[m + idx, m + idx] += 1.0 - pyy
        J[idx, m + idx] -= pxy
        J[m + idx, idx] -= pxy
        _, _, dt, info = dgesv(J, -F, overwrite_a=1, overwrite_b=1)  # LAPACK, no checks
        if info != 0:
            raise RuntimeError(f"steady rolling (direct): singular Newton matrix ({info})")
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
