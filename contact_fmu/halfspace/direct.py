"""The steady-rolling problem of small grids by dense direct Newton steps.

Below a few hundred unknowns the iterative path of ``rolling.coulomb_newton`` (GMRES
with the FFT block preconditioner) costs its Python overhead per iteration, not its
arithmetic. Here the steady-rolling operator K restricted to the contact (2 m x 2 m
for m contact elements, component-major) is formed once per patch by applying
``RollingPatch.apply_K`` to unit tractions, and every Newton step of the same
semismooth method (same fixed-point form, same backtracking, same convergence test)
solves its generalised Jacobian

    J = I - P (I - r K),   P = I (adhesion),  P = (g/|z|) (I - zhat zhat^T) (slip),

by LAPACK (dgetrf), in the smaller of two reduced forms (``_Jacobian``): the
unknowns the step couples (2 nH + nS for nH adhering and nS slipping elements), or,
when fewer than two thirds of the elements slip, the slip elements' components of
r K dtau through K^-1 (cached per patch; 2 nS). While the slip set stays the same the
last factorisation is reused (chord steps, accepted when they halve |F|; otherwise a
fresh step). The matrices are gathered into per-thread scratch memory. The initial
guess is the caller's (solve_rolling: the calibrated FASTSIM march, as on the
iterative path). Converged solutions agree with the iterative path to the Newton
tolerance (tests/test_halfspace_direct.py).
"""

from __future__ import annotations

import threading
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.linalg.lapack import dgetrf, dgetrs

FloatArray = NDArray[np.float64]

# Backtracking as in rolling.coulomb_newton.
ARMIJO = 1e-4
MIN_STEP = 1.0 / 64.0
# A chord step (the last factorisation reused while the slip set is unchanged) is taken
# when it reduces |F|_2 by at least this factor; otherwise a fresh Newton step follows.
# Measured on the railway wheel (40 random creepages and spins on 11, 19, 23 per side):
# 0.25-0.9 take the same time within the scatter, 24-54 % less than rejecting every
# chord step (docs/performance.md).
CHORD_DECREASE = 0.5


def contact_operator(patch: Any) -> FloatArray:
    """K on the contact: (2 m, 2 m) (m/Pa), gathered from the kernel blocks.

    K e_J for a unit traction at the contact element J applies (A + k) and the layer
    terms to its differences D e_J = e_J - e_J- (J- the element behind J, which exists:
    no contact in the first column). In the rows I of the contact the Toeplitz
    operator A gives A(I - J) - A(I - J-) = Ad(x_I - x_J), with the difference kernel
    Ad(d) = A(d) - A(d + dx e_x) taken once on the torus (offsets within the grid are
    their own minimum images there), so that each block is one indexed gather; the local
    terms (k + k_extra_I) (delta_IJ - delta_I,J-) add to the diagonal blocks. Equal to
    applying ``apply_K`` to unit tractions (2 m FFT convolutions) to rounding
    (tests/test_halfspace_direct.py), ``contact_operator_by_columns``."""
    C = patch.contact
    jj, ii = np.nonzero(C)
    m = len(jj)
    op = patch.op
    T = op.torus
    Ly, Lx = op.shape
    diff = T - np.roll(T, -1, axis=-1)  # Ad: A(d) - A(d + dx e_x) at every torus offset
    idx = ((jj[:, None] - jj[None, :]) % Ly) * Lx + (ii[:, None] - ii[None, :]) % Lx
    K = np.empty((2 * m, 2 * m))
    for a in range(2):
        for b in range(a, 2):
            blk = diff[a, b].ravel().take(idx)
            K[a * m : (a + 1) * m, b * m : (b + 1) * m] = blk
            if a != b:  # a_yx = a_xy: the y-x block is the x-y one
                K[b * m : (b + 1) * m, a * m : (a + 1) * m] = blk
    # local terms: row I gets (k + k_extra_I) at column I and minus it at column I+
    loc = op.local + patch.k_extra[C]
    if np.any(loc != 0.0):
        number = np.full(C.shape, -1)
        number[C] = np.arange(m)
        ahead = np.full(m, -1)
        fwd = ii + 1 < C.shape[1]
        ahead[fwd] = number[jj[fwd], ii[fwd] + 1]
        has = ahead >= 0
        rows = np.arange(m)
        for a in range(2):
            K[a * m + rows, a * m + rows] += loc
            K[a * m + rows[has], a * m + ahead[has]] -= loc[has]
    return K


def contact_operator_by_columns(patch: Any) -> FloatArray:
    """K on the contact by applying ``apply_K`` to unit tractions (2 m FFT convolutions):
    the reference for ``contact_operator``."""
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
    patch: Any,
    W: FloatArray,
    tau0: FloatArray,
    tol: float,
    maxit: int,
    traction_scale: float = 0.0,
) -> tuple[FloatArray, FloatArray, NDArray[np.bool_], int]:
    """Semismooth Newton on the contact with dense Jacobians from tau0 (2, ny, nx) (Pa),
    converged when max |F| <= tol max g, or with traction_scale > 0 tol min(max g,
    traction_scale max |tau|) (rolling.convergence_bound). Returns tau, S (2, ny, nx),
    the slip mask and the Newton count; RuntimeError after ``maxit`` steps."""
    C, r = patch.contact, patch.r
    K = patch.dense_contact_operator
    # K^-1 (the slip form) costs about three Newton factorisations (2 (2m)^3 flops): built
    # from a patch's second solve on, when its cost spreads over the solves that reuse it
    Kinv = patch.dense_contact_inverse if patch.solves > 0 else None
    patch.solves += 1
    m = K.shape[0] // 2
    g = patch.g[C]
    gmax = float(g.max())
    w = np.concatenate([W[0][C], W[1][C]])

    def residual(t: FloatArray):
        s = w - K @ t
        z = t + r * s
        zx, zy = z[:m], z[m:]
        nz = np.hypot(zx, zy)
        slip = nz > g
        scale = np.where(slip, g / np.where(slip, nz, 1.0), 1.0)
        F = t - z * np.tile(scale, 2)
        return F, s, zx, zy, nz, slip

    t = np.concatenate([tau0[0][C], tau0[1][C]])
    F, s, zx, zy, nz, slip = residual(t)
    fnorm = float(np.sqrt(F @ F))
    it = 0
    jac: _Jacobian | None = None
    while float(np.abs(F).max()) > _bound(t, tol, gmax, traction_scale):
        if it >= maxit:
            raise RuntimeError(
                f"steady rolling (direct): no convergence in {maxit} Newton steps "
                f"(max |F| / max g = {float(np.abs(F).max()) / gmax:.3g})"
            )
        it += 1
        if jac is not None and np.array_equal(slip, jac.slip):
            # the slip set has settled: try the last factorisation (a chord step)
            trial = t + jac.direction(F)
            Ft, st, zxt, zyt, nzt, slipt = residual(trial)
            fn = float(np.sqrt(Ft @ Ft))
            if fn <= CHORD_DECREASE * fnorm:
                t, F, s, zx, zy, nz, slip, fnorm = trial, Ft, st, zxt, zyt, nzt, slipt, fn
                continue
        jac = _Jacobian(K, Kinv, r, zx, zy, nz, g, slip)
        dt = jac.direction(F)
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


def _bound(t: FloatArray, tol: float, gmax: float, traction_scale: float) -> float:
    """rolling.convergence_bound on the contact's unknowns t."""
    if traction_scale <= 0.0:
        return tol * gmax
    return tol * min(gmax, traction_scale * float(np.abs(t).max(initial=0.0)))


_WORKSPACE = threading.local()
# Scratch vectors are kept between solves up to this many floats each (8 MiB; contacts
# of up to 512 elements); larger ones (method="direct" forced on a big grid) are freed.
WORKSPACE_KEEP = 4 * 512 * 512


def _workspace(size: int) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Three scratch vectors of at least ``size`` floats, kept per thread: the Newton
    matrices of one patch reuse the same memory instead of fresh allocations, whose page
    faults cost as much as the gathering itself (measured on 19 x 19)."""
    ws = getattr(_WORKSPACE, "buffers", None)
    if ws is None or ws[0].size < size:
        ws = (np.empty(size), np.empty(size), np.empty(size))
        if size <= WORKSPACE_KEEP:
            _WORKSPACE.buffers = ws
    return ws


class _Jacobian:
    """The generalised Jacobian J = I - P (I - r K) of one Newton iterate, factorised
    (LAPACK dgetrf) in the smaller of two reduced forms, so that ``direction`` solves
    J dtau = -F for any F (the chord steps of ``newton`` reuse it).

    Reduced form (2 nH + nS unknowns): in a slip element the row along zhat is local
    (zhat^T P = 0: dtau_n = -F_n), so the system keeps both components of the adhesion
    elements and the tangential one (that = (-zhat_y, zhat_x)) of the slip elements,
    whose row is (1 - f) that^T + f r that^T K, f = g/|z|.

    Slip form (2 nS unknowns, when few elements slip): in u = r K dtau the adhesion
    rows read u_H = -F_H, so with M = (r K)^-1 (K^-1 cached per patch) only the
    components of u in the slip elements remain, from their rows (I - P) M u + P u = -F:
    along zhat, zhat^T (M u) = -zhat^T F; across, (1 - f) that^T (M u) + f that^T u =
    -that^T F; unknowns in the same local basis (u = u_n zhat + u_t that), so that the
    matrix is diagonally dominant like K^-1; dtau = M u.

    Both matrices are gathered rows first (whole rows of K or K^-1), then columns."""

    def __init__(
        self,
        K: FloatArray,
        Kinv: FloatArray | None,
        r: float,
        zx: FloatArray,
        zy: FloatArray,
        nz: FloatArray,
        g: FloatArray,
        slip: NDArray[np.bool_],
    ) -> None:
        m = len(g)
        self.K, self.Kinv, self.r, self.m, self.slip = K, Kinv, r, m, slip
        iS = np.flatnonzero(slip)
        k = len(iS)
        nzS = nz[iS]
        hx, hy = zx[iS] / nzS, zy[iS] / nzS  # zhat of the slip elements
        f = g[iS] / nzS
        self.iS, self.hx, self.hy, self.f = iS, hx, hy, f
        tx, ty = -hy, hx
        self.slip_form = Kinv is not None and 2 * k <= 2 * m - k  # the smaller system
        bR, bT, bA = _workspace(4 * m * m)
        if self.slip_form:
            n = 2 * k
            R = bR[: n * 2 * m].reshape(n, 2 * m)  # rows along zhat, then (1 - f) that
            Tx, Ty = bT[: n * 2 * m].reshape(2, k, 2 * m)
            np.take(Kinv, iS, axis=0, out=Tx)
            np.take(Kinv, m + iS, axis=0, out=Ty)
            np.multiply(Tx, hx[:, None], out=R[:k])
            R[:k] += Ty * hy[:, None]
            np.multiply(Tx, ((1.0 - f) * tx)[:, None], out=R[k:])
            np.multiply(Ty, ((1.0 - f) * ty)[:, None], out=Ty)
            R[k:] += Ty
            Cx, Cy = bT[: 2 * n * k].reshape(2, n, k)
            np.take(R, iS, axis=1, out=Cx)
            np.take(R, m + iS, axis=1, out=Cy)
            A = bA[: n * n].reshape(n, n, order="F")
            np.multiply(Cx, hx, out=A[:, :k])
            A[:, :k] += Cy * hy
            np.multiply(Cx, tx, out=A[:, k:])
            np.multiply(Cy, ty, out=Cy)
            A[:, k:] += Cy
            A[k + np.arange(k), k + np.arange(k)] += r * f
            self.S = np.concatenate([iS, m + iS])
        else:
            iH = np.flatnonzero(~slip)
            H = np.concatenate([iH, m + iH])
            nH2 = len(H)
            n = nH2 + k
            R = bR[: n * 2 * m].reshape(n, 2 * m)  # adhesion rows, then f that^T K
            Tx = bT[: k * 2 * m].reshape(k, 2 * m)
            np.take(K, H, axis=0, out=R[:nH2])
            np.take(K, iS, axis=0, out=Tx)
            np.multiply(Tx, (f * tx)[:, None], out=R[nH2:])
            np.take(K, m + iS, axis=0, out=Tx)
            np.multiply(Tx, (f * ty)[:, None], out=Tx)
            R[nH2:] += Tx
            A = bA[: n * n].reshape(n, n, order="F")
            np.take(R, H, axis=1, out=A[:, :nH2])
            Cx = bT[: n * k].reshape(n, k)
            np.take(R, iS, axis=1, out=Cx)
            np.multiply(Cx, tx, out=A[:, nH2:])
            np.take(R, m + iS, axis=1, out=Cx)
            np.multiply(Cx, ty, out=Cx)
            A[:, nH2:] += Cx
            A[nH2 + np.arange(k), nH2 + np.arange(k)] += (1.0 - f) / r
            self.H = H
        if n == 0:  # full adhesion in the slip form: dtau = -(r K)^-1 F
            self.lu = self.piv = None
            return
        lu, piv, info = dgetrf(A, overwrite_a=1)
        if info != 0:
            raise RuntimeError(f"steady rolling (direct): singular Newton matrix ({info})")
        self.lu, self.piv = lu, piv

    def _solve(self, b: FloatArray) -> FloatArray:
        x, info = dgetrs(self.lu, self.piv, b, overwrite_b=1)
        if info != 0:  # only for an illegal argument
            raise RuntimeError(f"steady rolling (direct): dgetrs failed ({info})")
        return x

    def direction(self, F: FloatArray) -> FloatArray:
        """dtau with J dtau = -F."""
        m, r, iS, hx, hy, f = self.m, self.r, self.iS, self.hx, self.hy, self.f
        tx, ty = -hy, hx
        k = len(iS)
        Fx, Fy = F[iS], F[m + iS]
        if self.slip_form:
            u = -F
            if k == 0:
                return (self.Kinv @ u) / r
            u[self.S] = 0.0
            v = self.Kinv @ u  # K^-1 u_H
            vx, vy = v[iS], v[m + iS]
            rhs = np.concatenate(
                [
                    -r * (hx * Fx + hy * Fy) - (hx * vx + hy * vy),
                    -r * (tx * Fx + ty * Fy) - (1.0 - f) * (tx * vx + ty * vy),
                ]
            )
            x = self._solve(rhs)
            u[iS] = hx * x[:k] + tx * x[k:]
            u[m + iS] = hy * x[:k] + ty * x[k:]
            return (self.Kinv @ u) / r
        H = self.H
        nH2 = len(H)
        # dtau = d0 + (adhesion x, adhesion y, slip tangential); d0 = -F_n zhat
        Fn = hx * Fx + hy * Fy
        d0 = np.zeros(2 * m)
        d0[iS], d0[m + iS] = -Fn * hx, -Fn * hy
        Kd0 = self.K @ d0
        rhs = np.concatenate(
            [
                -F[H] / r - Kd0[H],
                -(tx * Fx + ty * Fy) / r - f * (tx * Kd0[iS] + ty * Kd0[m + iS]),
            ]
        )
        x = self._solve(rhs)
        dt = d0
        dt[H] += x[:nH2]
        dt[iS] += x[nH2:] * tx
        dt[m + iS] += x[nH2:] * ty
        return dt
