"""The steady-rolling problem of small grids by dense direct Newton steps.

Below a few hundred unknowns the iterative path of ``rolling.coulomb_newton`` (GMRES
with the FFT block preconditioner) costs its Python overhead per iteration, not its
arithmetic. Here every entry of the steady-rolling operator K restricted to the
contact (2 m x 2 m for m contact elements, component-major) is read from one
difference kernel (``DifferenceKernel``): K itself (``contact_operator``, once per
patch) and every Newton matrix. Each Newton step of the same semismooth method (same
fixed-point form, same backtracking, same convergence test) solves its generalised
Jacobian

    J = I - P (I - r K),   P = I (adhesion),  P = (g/|z|) (I - zhat zhat^T) (slip),

by LAPACK, in the smaller of two reduced forms (``_Jacobian``): the unknowns the step
couples (2 nH + nS for nH adhering and nS slipping elements; from SINGLE_MIN unknowns
on factorised in single precision and refined in double), or, when fewer than two
thirds of the elements slip, the slip elements' components of r K dtau through K^-1
(cached per patch from its second solve on; 2 nS). While the slip set stays the same
the last factorisation is reused (chord steps, accepted when they halve |F|;
otherwise a fresh step). The matrices are gathered into per-thread scratch memory.
The initial guess is the caller's (solve_rolling: the calibrated FASTSIM march, as on
the iterative path). Converged solutions agree with the iterative path to the Newton
tolerance (tests/test_halfspace_direct.py).
"""

from __future__ import annotations

import threading
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.linalg.lapack import dgetrf, dgetrs, sgetrf, sgetrs

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


# Newton matrices (reduced form, gathered from the difference kernel) of at least this many
# unknowns are factorised in single precision (LAPACK sgetrf, 1.5-1.7 times faster than
# dgetrf at 250-510 unknowns on one core) and their solutions refined in double until
# the next correction is estimated below REFINE_TOL of the solution (at most REFINE_MAXIT
# corrections; ``_Jacobian._solve``).
SINGLE_MIN = 200
REFINE_TOL = 1e-12
REFINE_MAXIT = 6


def contact_operator(patch: Any) -> FloatArray:
    """K on the contact: (2 m, 2 m) (m/Pa), gathered from the kernel blocks.

    K e_J for a unit traction at the contact element J applies (A + k) and the layer
    terms to its differences D e_J = e_J - e_J- (J- the element behind J, which exists:
    no contact in the first column). In the rows I of the contact the Toeplitz
    operator A + k gives (A + k)(I - J) - (A + k)(I - J-) = Ad(x_I - x_J), with the
    difference kernel Ad taken once (``DifferenceKernel``), so that each block is one
    indexed gather; the leading elements' k_extra_I adds to the diagonal. Equal to
    applying ``apply_K`` to unit tractions (2 m FFT convolutions) to rounding
    (tests/test_halfspace_direct.py), ``contact_operator_by_columns``."""
    kern = patch.difference_kernel
    D = kern.D
    m = len(kern.source)
    idx = kern.field[:, None] - kern.source[None, :]
    K = np.empty((2 * m, 2 * m))
    for a in range(2):
        for b in range(a, 2):
            blk = D[a + b].take(idx)
            K[a * m : (a + 1) * m, b * m : (b + 1) * m] = blk
            if a != b:  # a_yx = a_xy: the y-x block is the x-y one
                K[b * m : (b + 1) * m, a * m : (a + 1) * m] = blk
    if np.any(kern.extra != 0.0):  # the leading elements' k/theta - k
        d = np.arange(2 * m)
        K[d, d] += np.tile(kern.extra, 2)
    return K


class DifferenceKernel:
    """Every entry of K on a patch's contact as a shifted entry of one kernel.

    In the rows I of the contact, K e_J (J in the contact) is (A + k)(x_I - x_J) - (A +
    k)(x_I - x_J-) plus the leading elements' extra layer term (``contact_operator``):
    the difference kernel Ad(d) = (A + k)(d) - (A + k)(d + dx e_x) at the offset d = x_I
    - x_J, plus k_extra_I where I = J (the element ahead of a leading element is outside
    the contact, so its -k_extra_I never enters). ``D`` holds Ad at the offsets within
    the grid, flat, for the blocks xx, xy (= yx) and yy: (3, (2 ny - 1) (2 nx - 1)),
    from the torus of the Cerruti block (A(d + dx e_x) at the last offset column is its
    minimum image, as for the FFT operator; no contact in the first column keeps a
    contact's offsets within nx - 2 of each other, so that entry is never read). With the
    position a = j (2 nx - 1) + i of each contact element, the entry (I, J) is D at
    ``field``_I - ``source``_J (field = source + the position of offset (0, 0)): one
    subtraction and one gather per entry, from an array that stays in cache, for K
    and for every Newton matrix (``_Jacobian``) alike. ``extra``: k_extra of the contact
    elements (m/Pa), in the order of np.nonzero(contact)."""

    def __init__(self, op: Any, contact: NDArray[np.bool_], k_extra: FloatArray) -> None:
        T = op.torus[(0, 0, 1), (0, 1, 1)]  # the blocks xx, xy, yy (a copy)
        if op.local:
            T[0, 0, 0] += op.local
            T[2, 0, 0] += op.local
        # at the offsets within the grid (``op.offsets``), minus the torus one element
        # ahead (np.roll by -1 along x, read only there)
        ny, nx = op.grid.ny, op.grid.nx
        Ly, Lx = T.shape[-2:]
        oy = (np.arange(-(ny - 1), ny) % Ly)[:, None]
        ox = np.arange(-(nx - 1), nx) % Lx
        self.D = (T[:, oy, ox] - T[:, oy, (ox + 1) % Lx]).reshape(3, -1)
        jj, ii = np.nonzero(contact)
        w = 2 * nx - 1
        self.source = jj * w + ii
        self.field = self.source + ((ny - 1) * w + nx - 1)
        self.extra = k_extra[contact]
        # 1/Ad(0) of the xx block (Pa/m): the single-precision matrices are scaled by it
        self.unit = 1.0 / float(self.D[0, self.field[0] - self.source[0]]) if len(jj) else 1.0

    @cached_property
    def D32(self) -> NDArray[np.float32]:
        """``D`` times ``unit`` in single precision (the Newton matrices of ``SINGLE_MIN``
        and more unknowns): entries of order one, far from float32's underflow (K's own
        are 1e-15 m/Pa and less; products of two in the factorisation would be
        subnormal, and subnormal arithmetic is many times slower on x86)."""
        return (self.D * self.unit).astype(np.float32)

    def index(self, rows: NDArray[np.int_], cols: NDArray[np.int_]) -> NDArray[np.int_]:
        """Flat kernel indices of the entries (cols, rows) (transposed: the matrix built
        in C order as its transpose is the Fortran-ordered one LAPACK factorises) for
        contact element numbers ``rows`` (field) and ``cols`` (source)."""
        return self.field[rows][None, :] - self.source[cols][:, None]


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
    kernel = patch.difference_kernel
    # K^-1 (the slip form) costs about three Newton factorisations (2 (2m)^3 flops): built
    # from a patch's second solve on, when its cost spreads over the solves that reuse it
    Kinv = inverse(patch)
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
        # g/|z| in slip, exactly 1 (g/g, g > 0 on the contact) in adhesion
        scale = g / np.maximum(nz, g)
        F = (t.reshape(2, m) - z.reshape(2, m) * scale).reshape(2 * m)
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
        jac = _Jacobian(K, Kinv, r, zx, zy, nz, g, slip, kernel)
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


def inverse(patch: Any) -> FloatArray | None:
    """K^-1 on the contact from a patch's second direct solve on (None on its first)."""
    return patch.dense_contact_inverse if patch.solves > 0 else None


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
    (LAPACK) in the smaller of two reduced forms, so that ``direction`` solves J dtau =
    -F for any F (the chord steps of ``newton`` reuse it).

    Reduced form (2 nH + nS unknowns): in a slip element the row along zhat is local
    (zhat^T P = 0: dtau_n = -F_n), so the system keeps both components of the adhesion
    elements and the tangential one (that = (-zhat_y, zhat_x)) of the slip elements,
    whose row is (1 - f) that^T + f r that^T K, f = g/|z|. Its matrix is gathered
    from the difference kernel (``_gather``); from SINGLE_MIN unknowns on it is
    factorised in single precision and its solves refined in double (``_solve``).

    Slip form (2 nS unknowns, when few elements slip): in u = r K dtau the adhesion
    rows read u_H = -F_H, so with M = (r K)^-1 (K^-1 cached per patch) only the
    components of u in the slip elements remain, from their rows (I - P) M u + P u = -F:
    along zhat, zhat^T (M u) = -zhat^T F; across, (1 - f) that^T (M u) + f that^T u =
    -that^T F; unknowns in the same local basis (u = u_n zhat + u_t that), so that the
    matrix is diagonally dominant like K^-1; dtau = M u.

    Its matrix is gathered rows first (whole rows of K^-1), then columns."""

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
        kernel: DifferenceKernel,
    ) -> None:
        m = len(g)
        self.K, self.Kinv, self.r, self.m, self.slip = K, Kinv, r, m, slip
        self.single = False
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
            self.H = np.concatenate([iH, m + iH])
            n = 2 * len(iH) + k
            self.single = n >= SINGLE_MIN
            self.unit = kernel.unit if self.single else 1.0  # the matrix's scale
            if self.single:
                A = self._gather(kernel, iH, iS, tx, ty, f, r, bA)
            else:
                A = self._from_K(iS, tx, ty, f, bA, bT)
        if n == 0:  # full adhesion in the slip form: dtau = -(r K)^-1 F
            self.lu = self.piv = None
            return
        lu, piv, info = (sgetrf if self.single else dgetrf)(A, overwrite_a=1)
        if info != 0:
            raise RuntimeError(f"steady rolling (direct): singular Newton matrix ({info})")
        self.lu, self.piv = lu, piv

    def _gather(
        self,
        kern: DifferenceKernel,
        iH: NDArray[np.int_],
        iS: NDArray[np.int_],
        tx: FloatArray,
        ty: FloatArray,
        f: FloatArray,
        r: float,
        buffer: FloatArray,
    ) -> FloatArray:
        """The reduced-form matrix (class docstring) gathered from the difference kernel,
        (n, n) Fortran-ordered in ``buffer`` (single precision where ``single``): its
        entries are kernel entries (``DifferenceKernel``), combined with the slip
        elements' tangents where a slip element's row or column is one, so that no row
        or column of K is copied first. Built as its transpose in C order."""
        nH, k = len(iH), len(iS)
        nH2 = 2 * nH
        n = nH2 + k
        D = kern.D32 if self.single else kern.D
        dt = D.dtype
        AT = buffer.view(dt)[: n * n].reshape(n, n)  # AT[J, I] = A[I, J]
        Dxx, Dxy, Dyy = D
        tx_, ty_ = tx.astype(dt)[:, None], ty.astype(dt)[:, None]
        ftx, fty = (f * tx).astype(dt), (f * ty).astype(dt)
        if nH:
            # adhesion rows and columns: the blocks of K (K_yx = K_xy)
            t = kern.index(iH, iH)
            np.take(Dxx, t, mode="clip", out=AT[:nH, :nH])
            np.take(Dxy, t, mode="clip", out=AT[:nH, nH:nH2])
            AT[nH:nH2, :nH] = AT[:nH, nH:nH2]
            np.take(Dyy, t, mode="clip", out=AT[nH:nH2, nH:nH2])
        if k:
            if nH:
                # slip columns (tangential unknowns), adhesion rows: K_aS t
                t = kern.index(iH, iS)
                xx, xy, yy = Dxx.take(t), Dxy.take(t), Dyy.take(t)
                np.multiply(xx, tx_, out=AT[nH2:, :nH])
                AT[nH2:, :nH] += xy * ty_
                np.multiply(xy, tx_, out=AT[nH2:, nH:nH2])
                AT[nH2:, nH:nH2] += yy * ty_
                # slip rows f that^T K, adhesion columns
                t = kern.index(iS, iH)
                xx, xy, yy = Dxx.take(t), Dxy.take(t), Dyy.take(t)
                np.multiply(xx, ftx, out=AT[:nH, nH2:])
                AT[:nH, nH2:] += xy * fty
                np.multiply(xy, ftx, out=AT[nH:nH2, nH2:])
                AT[nH:nH2, nH2:] += yy * fty
            # slip rows and columns: f_I that_I^T K_IJ that_J
            t = kern.index(iS, iS)
            xx, xy, yy = Dxx.take(t), Dxy.take(t), Dyy.take(t)
            xx *= tx_
            xx += xy * ty_  # (K_xx t_x + K_xy t_y) by column J
            xy *= tx_
            xy += yy * ty_  # (K_yx t_x + K_yy t_y)
            np.multiply(xx, ftx, out=AT[nH2:, nH2:])
            AT[nH2:, nH2:] += xy * fty
        # the diagonal: the leading elements' extra layer term, and in the slip rows
        # (1 - f)/r (f that^T that k_extra for the layer term)
        d = np.arange(n)
        diag = np.concatenate([kern.extra[iH], kern.extra[iH], f * kern.extra[iS] + (1.0 - f) / r])
        AT[d, d] += (diag * self.unit).astype(dt)
        return AT.T

    def _from_K(
        self,
        iS: NDArray[np.int_],
        tx: FloatArray,
        ty: FloatArray,
        f: FloatArray,
        buffer: FloatArray,
        scratch: FloatArray,
    ) -> FloatArray:
        """The reduced-form matrix (class docstring) in double precision from the dense
        K, (n, n) Fortran-ordered in ``buffer``: the unknowns' columns K E (whole
        columns of K: the adhesion elements' two, the slip elements' K_x t_x + K_y t_y),
        then their rows (the adhesion elements' two, the slip elements' f (t_x (K E)_x
        + t_y (K E)_y)), and (1 - f)/r on the slip rows' diagonal. The same products
        in the same order as ``_gather``: equal to it entry by entry without layers (to
        rounding with them: K's diagonal holds the layer term). A dozen array operations
        instead of its two dozen: at a hundred unknowns (double precision, below
        SINGLE_MIN) their overhead is what the matrix costs."""
        K, m, H = self.K, self.m, self.H
        nH2 = len(H)
        n = nH2 + len(iS)
        KE = scratch[: 2 * m * n].reshape(2 * m, n)
        K.take(H, axis=1, out=KE[:, :nH2])
        np.multiply(K.take(iS, axis=1), tx, out=KE[:, nH2:])
        KE[:, nH2:] += K.take(m + iS, axis=1) * ty
        A = buffer[: n * n].reshape(n, n, order="F")
        KE.take(H, axis=0, out=A[:nH2])
        np.multiply(KE.take(iS, axis=0), (f * tx)[:, None], out=A[nH2:])
        A[nH2:] += KE.take(m + iS, axis=0) * (f * ty)[:, None]
        # the slip rows' diagonal (1 - f)/r (K's diagonal holds the leading elements'
        # extra layer term already: f that^T that k_extra in the slip rows)
        d = np.arange(nH2, n)
        A[d, d] += (1.0 - f) / self.r
        return A

    def _reduced(self, x: FloatArray) -> FloatArray:
        """The reduced-form matrix times x, in double precision from K (the residual of
        ``_solve``'s refinement)."""
        m, iS, H = self.m, self.iS, self.H
        nH2 = len(H)
        tx, ty = -self.hy, self.hx
        d = np.zeros(2 * m)
        d[H] = x[:nH2]
        xs = x[nH2:]
        d[iS] = xs * tx
        d[m + iS] = xs * ty
        Kd = self.K @ d
        out = Kd[H]
        slip = self.f * (tx * Kd[iS] + ty * Kd[m + iS]) + (1.0 - self.f) / self.r * xs
        return np.concatenate([out, slip])

    def _solve(self, b: FloatArray) -> FloatArray:
        if not self.single:
            x, info = dgetrs(self.lu, self.piv, b, overwrite_b=1)
            if info != 0:  # only for an illegal argument
                raise RuntimeError(f"steady rolling (direct): dgetrs failed ({info})")
            return x
        # single-precision factors: iterative refinement with residuals in double
        # (Wilkinson 1963; Moler 1967). Each correction shrinks by the same factor (about
        # 1e-7 here: the condition number times float32's epsilon), so the next one is
        # estimated from the last two; done when that is below REFINE_TOL of x (after
        # two corrections, measured on 19 x 19: within 2e-13 of the double-precision step)
        x = np.zeros_like(b)
        res = b
        last = 1.0
        for _ in range(REFINE_MAXIT):
            dx, info = sgetrs(self.lu, self.piv, (res * self.unit).astype(np.float32))
            if info != 0:  # only for an illegal argument
                raise RuntimeError(f"steady rolling (direct): sgetrs failed ({info})")
            x += dx
            size = float(np.abs(x).max())
            step = float(np.abs(dx).max()) / size if size > 0.0 else 0.0
            if step * min(step / last, 1.0) <= REFINE_TOL:
                break
            last = step
            res = b - self._reduced(x)
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
