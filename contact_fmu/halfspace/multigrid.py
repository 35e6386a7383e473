"""Multigrid preconditioner for the Newton systems of steady rolling (rolling.py).

The semismooth Newton system of ``rolling._newton_direction``, written on fields. The
unknowns of an element e are coordinates along the columns of a basis Q_e (2 x k_e:
both traction components in adhesion, k_e = 2; the tangent t to the slip direction in
slip, k_e = 1; none outside the contact), and

    J x = Q^T (M K M Q x + Lam Q x),    K f = A * (D f) + kx (D f),

with M_e = Q_e Q_e^T, Lam_e = cS_e t t^T in slip (the local slip coefficient), A the
influence convolution plus the layer term (``RollingPatch.op``), D the upwind difference
along x and kx the leading-edge layer term (``RollingPatch.k_extra``).

Levels. Each coarser level aggregates 2 x 2 elements. The fine K is a convolution
acting on differences, and so is its piecewise-constant projection: with P0 the
injection of an aggregate into its four children, D P0 = E D_c (the differences of a
piecewise-constant field sit on the children in the odd columns, E injects there), so
P0^T K P0 = A_c * (D_c q) + kx_c D_c q with A_c(dR, dC) = sum over the children pairs of
A (``_coarsen_table``) and kx_c the sum of the odd-column children's kx. The coarse
operator is the Galerkin product P^T J P with each child's M replaced by the mean over
its aggregate (the "cheap" coarse operator of docs/halfspace.md, O(N) to form):
K_c = P0^T K P0 / 16, M_c and Lam_c the sums over the children, and Q_c the
eigenvectors of M_c whose eigenvalue exceeds AGGREGATE_MIN times the number of fine
elements per aggregate. The prolongation copies a coarse field to the children and
projects it on their unknowns; the restriction is its transpose.

Smoother: symmetric distributive Gauss-Seidel over the grid rows, lines along the
rolling direction (forward in y, then backward), each row's block banded to |column
offset| <= LINE_BAND and solved by banded LU. Distributive (Brandt's distributive
relaxation; Venner & Lubrecht's for the 1/r kernel of dry contact): the sweep relaxes
J C z = r and corrects x by C z, where C spreads a row's correction to the rows before
and after it with weight -SPREAD wherever both elements are in full adhesion (on a
coarse level: every child). Why: in adhesion D A is first-kind across the rows (for
fields smooth along x, A couples the rows like a logarithm of their distance), so the
plain sweep hardly damps fields alternating over a few rows, and the V-cycle's
contraction grew with the grid (0.07 -> 0.33 from 32 to 512 per side); C's symbol
1 - 2 SPREAD cos(theta_y) lifts those frequencies against the smooth ones (an
opposite-order factor of the first-kind coupling), and the contraction stays at
0.02-0.045 on 32..512 (docs/halfspace.md). The coupling of the rows already relaxed to
the others runs through the whole nonlocal kernel (with a lagged or truncated coupling
the count grows much faster, docs/halfspace.md): the rows 0 and 1 apart directly, the others in
bands of row distance: a row is final one row late (once the next row's spread has
reached it), and the final rows d + 1 apart, d in [s, 2 s) (s = 1, 2, 4, ...), act on
each other once a block of s final rows aligned to s is complete (``_Band``). The bands
s <= DIRECT_ROWS act by direct sums over the row pairs, on the rows transformed along x
once each; the others by one FFT convolution in y and x over the block's rows, on nodes
w columns apart, w dx <= s dy / FAR_RATIO (piecewise-linear anterpolation of the
sources, the kernel at the nodes' offsets, interpolation of the result: the kernel
between rows s or more apart is smooth on the scale s dy; w = 1, full resolution, where
that bound is below two columns). So each band costs O(N) plus its transforms on N/w
nodes, and a sweep O(N log N) (log2(ny) bands); with FAR_RATIO = None every band keeps
full resolution (exact, O(N log^2 N)). One V-cycle (one smoothing before and after the
coarse correction, dense LU on the coarsest level) is the preconditioner of GMRES
(krylov.fgmres): 3-4 iterations to 1e-6 on 32..512 per side.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.fft as sfft
import scipy.linalg as sla
from numpy.typing import NDArray
from scipy.linalg.lapack import dgbtrf, dgbtrs

from .influence import difference

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

# Half-width of the row blocks of the smoother in elements: the block of a row keeps the
# couplings |column offset| <= LINE_BAND. Measured on the railway cases (dense lab,
# docs/halfspace.md): 0 loses the bound (13 -> 67 iterations from 16 to 64 per side),
# 1 holds it with one or two more iterations than 3, 3 as good as the exact row block.
LINE_BAND = 3
# A coarse element keeps the directions of M_c whose eigenvalue exceeds AGGREGATE_MIN
# times the number of fine elements it aggregates (M_c sums their projections).
AGGREGATE_MIN = 0.05
# The coarsest level, solved by dense LU: at most COARSEST_UNKNOWNS unknowns, or a grid
# that cannot be halved again.
COARSEST_UNKNOWNS = 120
MIN_SIDE = 4
# ... and a coarsest level larger than COARSEST_MAX (a grid of few rows, which is not
# coarsened) is refused: its LU would cost more than the solve (the caller then takes
# the block preconditioner).
COARSEST_MAX = 2000
# Bands of the sweep up to DIRECT_ROWS rows sum over their row pairs directly (at full
# resolution along x): a forward and backward sweep measured 0-6 % faster with 4 than
# with 2, 8 or 16 on 64..256 per side (`bench_halfspace.py --sweep`'s system).
DIRECT_ROWS = 4
# The far bands' node spacing: w dx <= s dy / FAR_RATIO for rows s + 1..2 s apart.
# Measured on the railway cases (docs/halfspace.md): 4 gives the exact sweep's Newton /
# GMRES counts on 16..256 per side (nodes s/2 columns apart too, on 16..128) and keeps
# the sweep within 0.04-0.3 % of the exact one (relative, 32..512). None: every band at
# full resolution (exact).
FAR_RATIO: float | None = 4.0
# Distributive relaxation (module docstring): a row's correction is spread to the rows
# before and after it with weight -SPREAD, where both elements are in full adhesion.
# Measured (railway cases, docs/halfspace.md): 0.2-0.3 keep the V-cycle's contraction
# at 0.02-0.04 on 32..256 per side; 0.4 and 0.5 lose it (two-grid factors 0.12 and 0.86
# on 32 x 32; not by the row blocks' conditioning, which falls only 1.2-2 times from 0
# to 0.5); 0: the plain Gauss-Seidel sweep.
SPREAD = 0.25


@dataclass(frozen=True)
class KernelLevel:
    """The influence convolution A of one level (geometry only, reused by every solve).

    shape (ny, nx); table (2, 2, 2 Ry + 1, 2 Rx + 1): A at row/column offsets -Ry..Ry,
    -Rx..Rx (offset (0, 0) at [Ry, Rx]), field minus source, the local layer term
    included; Ry >= ny - 1 and Rx >= nx - 1; aspect: the element's dx/dy."""

    shape: tuple[int, int]
    table: FloatArray
    aspect: float = 1.0

    @property
    def R(self) -> tuple[int, int]:
        return (self.table.shape[2] - 1) // 2, (self.table.shape[3] - 1) // 2

    def _lookup(self, t: FloatArray, dr: NDArray[np.int_], dc: NDArray[np.int_]) -> FloatArray:
        Ry, Rx = self.R
        return t[:, :, np.clip(dr, -Ry, Ry) + Ry, np.clip(dc, -Rx, Rx) + Rx]

    def at(self, dr: NDArray[np.int_], dc: NDArray[np.int_]) -> FloatArray:
        """A at offsets (dr, dc) (arrays of the same shape): (2, 2, *dr.shape)."""
        return self._lookup(self.table, dr, dc)

    @cached_property
    def _difference_table(self) -> FloatArray:
        """A(dr, dc) - A(dr, dc + 1), the kernel of A D (same layout as ``table``)."""
        return difference(self.table)

    def at_difference(self, dr: NDArray[np.int_], dc: NDArray[np.int_]) -> FloatArray:
        """A(dr, dc) - A(dr, dc + 1) at offsets (dr, dc): (2, 2, *dr.shape) (a copy)."""
        return self._lookup(self._difference_table, dr, dc)

    @cached_property
    def row_symbols(self) -> NDArray[np.complex128]:
        """A's rows transformed along x: (2 ny - 1, 2, 2, Lx // 2 + 1) for the row offsets
        -(ny - 1)..ny - 1 (offset dr at index dr + ny - 1), zero-padded in x so that the
        products are linear convolutions along the rows."""
        ny, nx = self.shape
        Ry, Rx = self.R
        rows = np.arange(-(ny - 1), ny)
        cols = np.arange(-(nx - 1), nx)
        pad = np.zeros((rows.size, 2, 2, self.Lx))
        sub = self.table[:, :, rows[:, None] + Ry, cols[None, :] + Rx]  # (2, 2, r, c)
        pad[:, :, :, cols % self.Lx] = np.moveaxis(sub, 2, 0)
        return sfft.rfft(pad, axis=-1)

    @cached_property
    def Lx(self) -> int:
        return sfft.next_fast_len(2 * self.shape[1] - 1, real=True)

    @cached_property
    def symbol(self) -> NDArray[np.complex128]:
        """A's symbol on the level, zero-padded so that the circular convolution is the
        linear one: (2, 2, Ly, Lx // 2 + 1)."""
        ny, nx = self.shape
        Ry, Rx = self.R
        Ly = sfft.next_fast_len(2 * ny - 1, real=True)
        torus = np.zeros((2, 2, Ly, self.Lx))
        rows = np.arange(-(ny - 1), ny)
        cols = np.arange(-(nx - 1), nx)
        sub = self.table[:, :, rows[:, None] + Ry, cols[None, :] + Rx]
        torus[:, :, (rows % Ly)[:, None], (cols % self.Lx)[None, :]] = sub
        return sfft.rfft2(torus, axes=(-2, -1))

    def bands(self, forward: bool, ratio: float | None, direct_rows: int) -> list[_Band]:
        """The sweep's row-distance bands s = 1, 2, 4, ... < ny - 1 (module docstring), in
        the sweep's direction (forward: the field rows after the source rows)."""
        key = (forward, ratio, direct_rows)
        cache = self.__dict__.setdefault("_bands", {})
        if key not in cache:
            ny = self.shape[0]
            out, s = [], 1
            while s < ny - 1:
                w = 1 if ratio is None else max(1, int(s / (ratio * self.aspect)))
                out.append(_Band(self, s, w, 1 if forward else -1, s <= direct_rows))
                s *= 2
            cache[key] = out
        return cache[key]

    def convolve(self, q: FloatArray) -> FloatArray:
        """A * q for a field q (2, ny, nx) on the whole level."""
        ny, nx = self.shape
        S = self.symbol
        shape = (S.shape[2], self.Lx)
        fq = sfft.rfft2(q, s=shape, axes=(-2, -1))
        out = np.stack([S[a, 0] * fq[0] + S[a, 1] * fq[1] for a in range(2)])
        return sfft.irfft2(out, s=shape, axes=(-2, -1))[:, :ny, :nx]


class _Band:
    """The coupling of a block of s final rows [j0, j0 + s) to the rows s + 1..2 s after
    each of them in the sweep's order (sign: +1 forward, -1 backward), i.e. to the field
    rows [j0 + s + 1, j0 + 3 s): row distances d + 1 for d in [s, 2 s) (a row is final
    one row late, once the spread of the next row's correction has reached it; distances
    0 and 1 are the sweep's own). Near (w = 1, direct): sums over the row pairs of A's
    rows transformed along x. Otherwise: on nodes w columns apart (module docstring) by an
    FFT convolution over the block's s rows and the nodes."""

    def __init__(self, kern: KernelLevel, s: int, w: int, sign: int, direct: bool) -> None:
        ny, nx = kern.shape
        self.s, self.w = s, w
        self.direct = direct and w == 1
        lag_range = (s, min(2 * s, ny - 1))  # d: the row distances of this band, less 1
        if self.direct:
            # (field row t0 + a, source row j0 + b): d = s + a - b
            dist = s + np.arange(2 * s - 1)[:, None] - np.arange(s)[None, :]
            inside = (dist >= lag_range[0]) & (dist < lag_range[1])
            idx = np.clip(sign * (dist + 1), -(ny - 1), ny - 1) + ny - 1
            self.sym = kern.row_symbols[idx] * inside[..., None, None, None]
            return
        self.nodes = -(-(nx - 1) // w) + 1  # columns 0, w, ..., >= nx - 1
        self.Ly = sfft.next_fast_len(2 * s - 1, real=False)
        self.Lx = sfft.next_fast_len(2 * self.nodes - 1, real=True)
        dist = np.arange(*lag_range)
        C = np.arange(-(self.nodes - 1), self.nodes)
        torus = np.zeros((2, 2, self.Ly, self.Lx))
        dr = np.broadcast_to(sign * (dist[:, None] + 1), (dist.size, C.size))
        dc = np.broadcast_to(C[None, :] * w, (dist.size, C.size))
        torus[:, :, (dist - s)[:, None], (C % self.Lx)[None, :]] = kern.at(dr, dc)
        self.sym = sfft.rfft2(torus, axes=(-2, -1))
        self.t = np.arange(w) / w  # a column's position between its two nodes

    def near(self, F: NDArray[np.complex128], rows: int) -> NDArray[np.complex128]:
        """The coupling (transformed along x) on the first ``rows`` field rows from the
        block's rows transformed along x, F (s, 2, Lx // 2 + 1)."""
        return np.einsum("dsabk,sbk->dak", self.sym[:rows], F)

    def far(self, g: FloatArray, rows: int) -> FloatArray:
        """The coupling on the first ``rows`` field rows from the block's rows g (s, 2, nx)."""
        s, w, nx = self.s, self.w, g.shape[-1]
        if w > 1:  # anterpolation: column c w + t gives 1 - t/w to node c, t/w to c + 1
            pad = np.zeros((s, 2, self.nodes * w))
            pad[..., :nx] = g
            blocks = pad.reshape(s, 2, self.nodes, w)
            g = blocks @ (1.0 - self.t)
            g[..., 1:] += (blocks @ self.t)[..., :-1]
        shape = (self.Ly, self.Lx)
        fg = sfft.rfft2(g, s=shape, axes=(0, -1))
        S = self.sym
        prod = np.stack([S[a, 0] * fg[:, 0] + S[a, 1] * fg[:, 1] for a in range(2)], axis=1)
        u = sfft.irfft2(prod, s=shape, axes=(0, -1))[:rows, :, : self.nodes]
        if w == 1:
            return u[..., :nx]
        # interpolation, the transpose of the anterpolation
        nxt = np.concatenate([u[..., 1:], np.zeros((*u.shape[:2], 1))], axis=-1)
        fine = u[..., None] * (1.0 - self.t) + nxt[..., None] * self.t
        return fine.reshape(*u.shape[:2], self.nodes * w)[..., :nx]


Kernel = Callable[[FloatArray, FloatArray], tuple]


def fine_kernel(
    kernel: Kernel, dx: float, dy: float, local: float, shape: tuple[int, int], R: tuple[int, int]
) -> KernelLevel:
    """The fine level from the element kernel kernel(X, Y) (blocks at offsets X, Y in m,
    as BlockConvolution.kernel) plus the local term on the diagonal blocks."""
    Ry, Rx = R
    X, Y = np.meshgrid(np.arange(-Rx, Rx + 1) * dx, np.arange(-Ry, Ry + 1) * dy)
    table = np.array(kernel(X, Y), dtype=float)
    for a in range(2):
        table[a, a, Ry, Rx] += local
    return KernelLevel(tuple(shape), table, dx / dy)


def _coarsen_table(fine: KernelLevel, shape: tuple[int, int], R: tuple[int, int]) -> KernelLevel:
    """A_c(dR, dC) = sum_{t in 0, 1} [A(2dR - 1, c) + 2 A(2dR, c) + A(2dR + 1, c)] at
    c = 2 dC + t - 1 (module docstring), over |dR| <= R[0], |dC| <= R[1]."""
    dR = np.arange(-R[0], R[0] + 1)[:, None]
    dC = np.arange(-R[1], R[1] + 1)[None, :]
    acc = 0.0
    for t in (0, 1):
        c = 2 * dC + t - 1
        for s, wgt in ((-1, 1.0), (0, 2.0), (1, 1.0)):
            acc = acc + wgt * fine.at(np.broadcast_to(2 * dR + s, (dR.size, dC.size)), c + 0 * dR)
    return KernelLevel(tuple(shape), acc / 16.0, fine.aspect)


def kernel_levels(
    kernel: Kernel, dx: float, dy: float, local: float, shape: tuple[int, int]
) -> list[KernelLevel]:
    """The kernels of all levels for a fine grid of ``shape`` (cached by the caller)."""
    shapes = [tuple(shape)]
    while min(shapes[-1]) > MIN_SIDE:
        ny, nx = shapes[-1]
        shapes.append(((ny + 1) // 2, (nx + 1) // 2))
    # offset ranges: each level its own grid, and what the next coarser one needs
    R = [(s[0] - 1, s[1] - 1) for s in shapes]
    for k in range(len(shapes) - 2, -1, -1):
        R[k] = (max(R[k][0], 2 * R[k + 1][0] + 1), max(R[k][1], 2 * R[k + 1][1] + 1))
    levels = [fine_kernel(kernel, dx, dy, local, shapes[0], R[0])]
    for k in range(1, len(shapes)):
        levels.append(_coarsen_table(levels[-1], shapes[k], R[k]))
    return levels


class Level:
    """One level of the Newton system: kernel, per-element M, Lam (2, 2, ny, nx), kx
    (ny, nx), basis q (2 directions, 2 components, ny, nx) with ``active`` (2, ny, nx);
    the unknowns are the active (row, column, direction) in row-major order. children:
    the fine elements per element (M sums their projections); weight: the smoother's
    spread (None: SPREAD when the level is made; its coarser levels inherit it, and the
    row factors and the sweeps all read this one value)."""

    def __init__(
        self,
        kern: KernelLevel,
        M: FloatArray,
        Lam: FloatArray,
        kx: FloatArray,
        q: FloatArray,
        active: BoolArray,
        children: int = 1,
        weight: float | None = None,
    ) -> None:
        self.kern, self.M, self.Lam, self.kx, self.q = kern, M, Lam, kx, q
        self.children = children
        self.weight = SPREAD if weight is None else weight
        ny = kern.shape[0]
        r, c, d = np.nonzero(np.moveaxis(active, 0, -1))
        self.ur, self.uc, self.ud = r, c, d
        self.n = len(r)
        counts = np.bincount(r, minlength=ny)
        self.rowptr = np.concatenate([[0], np.cumsum(counts)])

    # ---- fields and unknowns -----------------------------------------------------------
    def to_field(self, x: FloatArray) -> FloatArray:
        """Q x as a field (2, ny, nx)."""
        coef = np.zeros((2, *self.kern.shape))
        coef[self.ud, self.ur, self.uc] = x
        return np.einsum("kaij,kij->aij", self.q, coef)

    def from_field(self, g: FloatArray) -> FloatArray:
        """Q^T g at the unknowns."""
        proj = np.einsum("kaij,aij->kij", self.q, g)
        return proj[self.ud, self.ur, self.uc]

    def mfield(self, f: FloatArray) -> FloatArray:
        """M f for a field f (2, ny, nx)."""
        return np.einsum("abij,bij->aij", self.M, f)

    def K(self, f: FloatArray) -> FloatArray:
        d = difference(f)
        return self.kern.convolve(d) + self.kx * d

    def apply(self, x: FloatArray) -> FloatArray:
        """J x (module docstring)."""
        d = self.to_field(x)
        g = self.mfield(self.K(self.mfield(d))) + np.einsum("abij,bij->aij", self.Lam, d)
        return self.from_field(g)

    # ---- dense and banded pieces ----------------------------------------------------------
    @cached_property
    def _unit(self) -> tuple[FloatArray, FloatArray]:
        """Per unknown: its basis vector q_u and M_u q_u, (2, n) each."""
        qu = self.q[self.ud, :, self.ur, self.uc].T
        mq = np.einsum("abn,bn->an", self.M[:, :, self.ur, self.uc], qu)
        return qu, mq

    def entries(self, u: NDArray[np.int_], v: NDArray[np.int_]) -> FloatArray:
        """Matrix entries J[u, v] for index arrays u, v (same shape)."""
        ru, cu, rv, cv = self.ur[u], self.uc[u], self.ur[v], self.uc[v]
        # K's kernel: A(I - J) - A(I - J + e_x) (the latter only if J has an element
        # behind it), plus kx_I at J = I and -kx_I at J = I + e_x
        dr, dc = ru - rv, cu - cv
        Kf = self.kern.at_difference(dr, dc)
        first = np.flatnonzero(cv == 0)
        if first.size:
            Kf[:, :, first] += self.kern.at(dr[first], dc[first] + 1)
        kx = self.kx[ru, cu] * ((dr == 0) * ((dc == 0) * 1.0 - (dc == -1)))
        Kf[0, 0] += kx
        Kf[1, 1] += kx
        qu, mq = self._unit
        a, b = mq[:, u], mq[:, v]
        out = a[0] * (Kf[0, 0] * b[0] + Kf[0, 1] * b[1])
        out += a[1] * (Kf[1, 0] * b[0] + Kf[1, 1] * b[1])
        same = np.flatnonzero((dr == 0) & (dc == 0))
        if same.size:
            us, vs = u[same], v[same]
            L = self.Lam[:, :, ru[same], cu[same]]
            qa, qb = qu[:, us], qu[:, vs]
            out[same] += qa[0] * (L[0, 0] * qb[0] + L[0, 1] * qb[1]) + qa[1] * (
                L[1, 0] * qb[0] + L[1, 1] * qb[1]
            )
        return out

    def dense(self) -> FloatArray:
        """The whole matrix (for the coarsest level and for tests)."""
        idx = np.arange(self.n)
        U, V = np.meshgrid(idx, idx, indexing="ij")
        return self.entries(U.ravel(), V.ravel()).reshape(self.n, self.n)

    @cached_property
    def band(self) -> int:
        return 2 * LINE_BAND + 1

    @cached_property
    def spread(self) -> tuple[BoolArray, BoolArray]:
        """The elements (ny, nx) in full adhesion (every child: M = children I) whose
        neighbour in the next row (row + 1), resp. the previous row, is too: there a row's
        correction is spread to the neighbour with weight -self.weight (module docstring)."""
        full = self.M[0, 0] + self.M[1, 1] > 2 * self.children - 0.5  # traces are integers
        nxt = np.zeros_like(full)
        nxt[:-1] = full[:-1] & full[1:]
        prv = np.zeros_like(full)
        prv[1:] = full[1:] & full[:-1]
        return nxt, prv

    @cached_property
    def row_factors(self) -> list:
        """Banded LU of each row's block of J C (|column offset| <= LINE_BAND; C the
        spread, module docstring): (lu, ipiv) or None."""
        kl = self.band
        out = []
        ny, nx = self.kern.shape
        # all pairs of unknowns in one row within the band
        us, vs = [], []
        for off in range(-kl, kl + 1):
            u = np.arange(max(0, -off), min(self.n, self.n - off))
            v = u + off
            keep = (self.ur[u] == self.ur[v]) & (np.abs(self.uc[u] - self.uc[v]) <= LINE_BAND)
            us.append(u[keep])
            vs.append(v[keep])
        u = np.concatenate(us)
        v = np.concatenate(vs)
        val = self.entries(u, v)
        # C's column of v: -weight times v's field (children q_v) on the neighbour, in its
        # unknowns (q_nb . q_v each: the neighbour's q is orthonormal, full adhesion)
        index = -np.ones((2, ny, nx), np.int_)
        index[self.ud, self.ur, self.uc] = np.arange(self.n)
        for mask, dr in zip(self.spread, (1, -1), strict=True) if self.weight else ():
            has = np.flatnonzero(mask[self.ur[v], self.uc[v]])
            rn, cn = self.ur[v[has]] + dr, self.uc[v[has]]
            for k in range(2):
                wgt = np.einsum("an,an->n", self.q[k][:, rn, cn], self._unit[0][:, v[has]])
                on = np.flatnonzero(wgt)  # (the bases are the identity on the fine level)
                nb = index[k, rn[on], cn[on]]
                val[has[on]] -= self.weight * wgt[on] * self.entries(u[has[on]], nb)
        ab = np.zeros((3 * kl + 1, self.n))
        ab[2 * kl + u - v, v] = val  # LAPACK band storage with room for the fill-in
        for i in range(ny):
            a, b = self.rowptr[i], self.rowptr[i + 1]
            if a == b:
                out.append(None)
                continue
            lu, piv, info = dgbtrf(ab[:, a:b], kl, kl)
            if info != 0:
                raise np.linalg.LinAlgError(f"multigrid: singular row block {i}")
            out.append((lu, piv))
        return out

    def solve_row(self, i: int, rhs: FloatArray) -> FloatArray:
        lu, piv = self.row_factors[i]
        x, info = dgbtrs(lu, self.band, self.band, rhs, piv)
        return x

    # ---- smoother ------------------------------------------------------------------------
    def _sweep(self, r: FloatArray, forward: bool) -> FloatArray:
        """C z with (B + L) z = r for J C (forward; L: rows below) or (B + U) z = r, the
        far rows' part of L (U) on the nodes of the bands (module docstring; FAR_RATIO
        None: exact)."""
        ny, nx = self.kern.shape
        Lx = self.kern.Lx
        z = np.zeros(self.n)
        # Row-major in the sweep's order (row, component, column or frequency):
        h = np.zeros((ny + 1, 2, nx))  # M Q C z located on the rows (row ny: none)
        near = np.zeros((ny, 2, Lx // 2 + 1), complex)  # coupling received, along x transformed
        far = np.zeros((ny, 2, nx))  # ... and in space
        g = np.zeros((ny, 2, nx))  # D h of the final rows
        F = np.zeros((ny, 2, Lx // 2 + 1), complex)  # the same, transformed along x
        bands = self.kern.bands(forward, FAR_RATIO, DIRECT_ROWS)
        # A's rows 0 and 1 apart in the sweep's direction (transformed along x)
        sym01 = self.kern.row_symbols[[ny - 1, ny - 1 + (1 if forward else -1)]]
        spilled = np.zeros(ny + 1, bool)  # rows the previous row spread onto
        ahead, behind = self.spread if forward else self.spread[::-1]
        rp = self.rowptr
        mq = self._unit[1]
        relaxed = np.zeros(ny + 1, np.int_)  # rows with unknowns among the first p
        for p, i in enumerate(range(ny) if forward else range(ny - 1, -1, -1)):
            a, b = rp[i], rp[i + 1]
            relaxed[p + 1] = relaxed[p] + (a < b)
            X = None  # row p - 1 transformed along x, while it stands unchanged
            if a < b:
                # received: the bands (final rows up to p - 2), row p - 1 as far as relaxed
                # (row distance 1), and what the previous row spread onto this one (0)
                src = ([p] if spilled[p] else []) + ([p - 1] if p else [])
                hat = near[p]
                if src:
                    Dh = difference(h[src])
                    X = sfft.rfft(Dh, Lx, axis=-1)
                    hat = hat + np.einsum("tabk,tbk->ak", sym01[[p - j for j in src]], X)
                coup = sfft.irfft(hat, Lx, axis=-1)[:, :nx] + far[p]
                if spilled[p]:
                    coup += self.kx[i] * Dh[0]
                cols, m = self.uc[a:b], mq[:, a:b]
                rhs = r[a:b] - (m[0] * coup[0, cols] + m[1] * coup[1, cols])
                d = self.solve_row(i, rhs)
                z[a:b] = d
                # M Q z on this row (Q^T M = (M Q)^T: the same vectors both ways)
                f = np.stack([np.bincount(cols, weights=m[c] * d, minlength=nx) for c in range(2)])
                h[p] += f
                if self.weight and ahead[i].any():
                    spilled[p + 1] = True
                    h[p + 1] -= self.weight * ahead[i] * f
                if self.weight and p and behind[i].any():
                    h[p - 1] -= self.weight * behind[i] * f
                    X = None  # row p - 1 changed since its transform above
            if p == 0:
                continue
            g[p - 1] = difference(h[p - 1])  # row p - 1 final now
            F[p - 1] = sfft.rfft(g[p - 1], Lx, axis=-1) if X is None else X[-1]
            for band in bands:  # the blocks that end with row p - 1 act on the rows after p
                s = band.s
                if p % s:
                    continue
                j0, rows = p - s, min(2 * s - 1, ny - p - 1)
                if rows <= 0 or relaxed[p] == relaxed[j0]:
                    continue  # no rows left, or no unknowns in the block
                if band.direct:
                    near[p + 1 : p + 1 + rows] += band.near(F[j0:p], rows)
                else:
                    far[p + 1 : p + 1 + rows] += band.far(g[j0:p], rows)
        return self._spread_correction(z)

    def _spread_correction(self, z: FloatArray) -> FloatArray:
        """C z: z plus, on the neighbours of each element in full adhesion, -weight times
        its field M Q z in their unknowns (Q^T / children there: M = children I)."""
        if not self.weight:
            return z
        f = self.mfield(self.to_field(z))
        nxt, prv = self.spread
        spill = np.zeros_like(f)
        spill[:, 1:] -= self.weight * nxt[:-1] * f[:, :-1]
        spill[:, :-1] -= self.weight * prv[1:] * f[:, 1:]
        return z + self.from_field(spill) / self.children

    def smooth(self, v: FloatArray, x: FloatArray | None) -> FloatArray:
        """One symmetric distributive Gauss-Seidel step from x (None: zero) for J x = v."""
        x = self._sweep(v, True) if x is None else x + self._sweep(v - self.apply(x), True)
        return x + self._sweep(v - self.apply(x), False)

    # ---- coarsening ----------------------------------------------------------------------
    def coarsen(self, kern: KernelLevel, children: int) -> Level:
        """The next level (module docstring); ``children``: fine elements per aggregate."""
        nyc, nxc = kern.shape

        def agg(a: FloatArray) -> FloatArray:
            ny, nx = a.shape[-2:]
            pad = np.zeros((*a.shape[:-2], 2 * nyc, 2 * nxc))
            pad[..., :ny, :nx] = a
            return pad.reshape(*a.shape[:-2], nyc, 2, nxc, 2).sum(axis=(-3, -1))

        Mc = agg(self.M)
        Lc = agg(self.Lam)
        ny, nx = self.kx.shape
        kxp = np.zeros((2 * nyc, 2 * nxc))
        kxp[:ny, :nx] = self.kx
        kxc = kxp.reshape(nyc, 2, nxc, 2)[:, :, :, 1].sum(axis=1) / 16.0
        w, V = np.linalg.eigh(np.moveaxis(Mc, (0, 1), (-2, -1)))  # (nyc, nxc, 2), (.., 2, 2)
        active = np.moveaxis(w > AGGREGATE_MIN * children, -1, 0)
        q = np.moveaxis(V, (-1, -2), (0, 1))  # q[k, a] = V[a, k]
        return Level(kern, Mc, Lc, kxc, q, active, children, self.weight)

    def prolong(self, coarse: Level, e: FloatArray) -> FloatArray:
        d = coarse.to_field(e)
        ny, nx = self.kern.shape
        f = np.repeat(np.repeat(d, 2, axis=1), 2, axis=2)[:, :ny, :nx]
        return self.from_field(f)

    def restrict(self, coarse: Level, r: FloatArray) -> FloatArray:
        f = self.to_field(r)
        nyc, nxc = coarse.kern.shape
        ny, nx = self.kern.shape
        pad = np.zeros((2, 2 * nyc, 2 * nxc))
        pad[:, :ny, :nx] = f
        return coarse.from_field(pad.reshape(2, nyc, 2, nxc, 2).sum(axis=(2, 4)))


class VCycle:
    """The multigrid V-cycle for the fine level ``fine`` over the kernels ``kernels``."""

    def __init__(self, fine: Level, kernels: list[KernelLevel]) -> None:
        self.levels = [fine]
        k = 1
        while k < len(kernels) and self.levels[-1].n > COARSEST_UNKNOWNS:
            self.levels.append(self.levels[-1].coarsen(kernels[k], 4**k))
            k += 1
        for lev in self.levels[:-1]:
            _ = lev.row_factors  # factorised here, so that a singular block fails now
        last = self.levels[-1]
        if last.n > COARSEST_MAX:
            raise np.linalg.LinAlgError(f"multigrid: {last.n} unknowns on the coarsest level")
        self.lu = sla.lu_factor(last.dense()) if last.n else None

    def _cycle(self, k: int, v: FloatArray) -> FloatArray:
        lev = self.levels[k]
        if k == len(self.levels) - 1:
            return sla.lu_solve(self.lu, v) if lev.n else v
        x = lev.smooth(v, None)
        coarse = self.levels[k + 1]
        e = self._cycle(k + 1, lev.restrict(coarse, v - lev.apply(x)))
        x = x + lev.prolong(coarse, e)
        return lev.smooth(v, x)

    def __call__(self, v: FloatArray) -> FloatArray:
        return self._cycle(0, v)


def newton_level(
    kern: KernelLevel, H: BoolArray, Sl: BoolArray, that: FloatArray, cS: FloatArray, kx: FloatArray
) -> Level:
    """The fine level of a Newton system: adhesion elements H (both components), slip
    elements Sl (the tangent ``that`` (2, ny, nx), local coefficient cS (ny, nx)), kx
    the leading-edge layer term (ny, nx)."""
    ny, nx = kern.shape
    q = np.zeros((2, 2, ny, nx))
    q[0, 0] = np.where(H, 1.0, np.where(Sl, that[0], 0.0))
    q[0, 1] = np.where(Sl, that[1], 0.0)
    q[1, 1] = np.where(H, 1.0, 0.0)
    active = np.stack([H | Sl, H])
    M = np.einsum("kaij,kbij->abij", q, q)
    Lam = np.where(Sl, cS, 0.0) * M
    return Level(kern, M, Lam, kx, q, active)
