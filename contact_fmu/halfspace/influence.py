"""Influence coefficients of rectangular elements and their FFT convolution.

The surface displacements of an elastic half-space under a traction that is constant
on a rectangle follow from integrating the point-load solutions (Boussinesq and
Cerruti; Love 1929; Johnson 1985, Contact Mechanics, Eqs. 3.19, 3.86) over the
rectangle. Every kernel needed here has a closed-form double antiderivative
(x, y = field point minus source point, r = (x^2 + y^2)^(1/2)):

    int int 1/r      = x asinh(y/|x|) + y asinh(x/|y|)
    int int x^2/r^3  = y asinh(x/|y|)
    int int y^2/r^3  = x asinh(y/|x|)
    int int x y/r^3  = -r
    int int x/r^2    = x atan(y/x) + (y/2) ln(r^2)
    int     ln|x|    = x ln|x| - x                       (plane strain, per unit width)

The terms x ln|x|, y ln|y| that the usual forms x ln(y + r) carry drop out of the
four-corner sum, which makes the asinh forms above exact and free of log(0).

Kernels (both bodies combined, the body receiving -tau and the substrate tau; the
Appendix of Spector & Batra 1995 with Kalker's combined constants, see docs/halfspace.md):

* tangential, u = u^s - u^b due to tau (Appendix, B(tau)):
  u_x = 1/(pi G) int [((1 - nu)/r + nu x^2/r^3) tau_x + nu x y/r^3 tau_y] dA,
  1/G = (1/G_b + 1/G_s)/2,  nu/G = (nu_b/G_b + nu_s/G_s)/2;
* normal, w = w^b + w^s due to p: w = 1/(pi E*) int p/r dA,
  1/E* = (1 - nu_b^2)/E_b + (1 - nu_s^2)/E_s;
* pressure-to-tangential coupling (Appendix, B(p)), u^s - u^b due to p:
  u_x = -(kappa/(pi G)) int x/r^2 p dA with Kalker's difference parameter
  kappa = (G/4) ((1 - 2 nu_s)/G_s - (1 - 2 nu_b)/G_b).

Grids are cell-centred, arrays are indexed [j, i] with x along axis 1 (shape (ny, nx)),
as in contact_fmu.laws.thin_layer.TractionField.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property, lru_cache

import numpy as np
import scipy.fft as sfft
from numpy.typing import NDArray

from .._validate import InputError, count, finite, positive

FloatArray = NDArray[np.float64]

# Reference Cerruti operators kept (``tangential_operator``): one per grid shape, element
# aspect ratio and nu, each (2 x 2 blocks of the padded grid, their symbols and inverse)
# about 0.2 MB on 32 x 32, 3 MB on 128 x 128.
KERNEL_CACHE = 64
# Smallest admissible eigenvalue of the circulant symbol, relative to its largest, for
# the FFT deconvolution preconditioner: the circulant embedding of a positive-definite
# Toeplitz kernel is not always positive definite; below this the symbol is clipped.
SYMBOL_FLOOR = 1e-10


@dataclass(frozen=True)
class Grid:
    """Uniform cell-centred grid: nx x ny elements of size dx x dy (m), lower-left corner
    (x0, y0) (m). Cell centres x_i = x0 + (i + 1/2) dx, y_j = y0 + (j + 1/2) dy."""

    nx: int
    ny: int
    dx: float
    dy: float
    x0: float
    y0: float

    def __post_init__(self) -> None:
        count("nx", self.nx, 1)
        count("ny", self.ny, 1)
        positive("dx", self.dx)
        positive("dy", self.dy)
        finite("x0", self.x0)
        finite("y0", self.y0)

    @property
    def shape(self) -> tuple[int, int]:
        return (self.ny, self.nx)

    @property
    def x(self) -> FloatArray:
        """Cell centres along x (m), shape (nx,)."""
        return self.x0 + (np.arange(self.nx) + 0.5) * self.dx

    @property
    def y(self) -> FloatArray:
        """Cell centres along y (m), shape (ny,)."""
        return self.y0 + (np.arange(self.ny) + 0.5) * self.dy

    @property
    def reach(self) -> float:
        """The largest |x|, |y| of the cell centres (m)."""
        return max(float(np.abs(self.x).max()), float(np.abs(self.y).max()))

    def mesh(self) -> tuple[FloatArray, FloatArray]:
        """(X, Y) of the cell centres, each of shape (ny, nx); built once per grid and
        read-only (a solve asks for it several times)."""
        return self._mesh

    @cached_property
    def _mesh(self) -> tuple[FloatArray, FloatArray]:
        # np.meshgrid's values, without its broadcasting machinery (a tenth of the cost)
        X, Y = np.empty(self.shape), np.empty(self.shape)
        X[...] = self.x
        Y[...] = self.y[:, None]
        X.flags.writeable = False
        Y.flags.writeable = False
        return X, Y

    @property
    def area(self) -> float:
        """Element area dx dy (m^2)."""
        return self.dx * self.dy


# ---- closed-form antiderivatives -------------------------------------------------
def _x_asinh_y_over_x(x: FloatArray, y: FloatArray) -> FloatArray:
    """x asinh(y/|x|), continuous with value 0 at x = 0."""
    ax = np.abs(x)
    safe = np.where(ax > 0.0, ax, 1.0)
    return np.where(ax > 0.0, x * np.arcsinh(y / safe), 0.0)


def _x_atan_y_over_x(x: FloatArray, y: FloatArray) -> FloatArray:
    """x atan(y/x), continuous with value 0 at x = 0."""
    safe = np.where(x != 0.0, x, 1.0)
    return np.where(x != 0.0, x * np.arctan(y / safe), 0.0)


def _y_log_r2(x: FloatArray, y: FloatArray) -> FloatArray:
    """(y/2) ln(x^2 + y^2), continuous with value 0 at y = 0."""
    r2 = x * x + y * y
    safe = np.where(r2 > 0.0, r2, 1.0)
    return np.where(y != 0.0, 0.5 * y * np.log(safe), 0.0)


def _corner_sum(F, X: FloatArray, Y: FloatArray, dx: float, dy: float) -> FloatArray:
    """int_{X-dx/2}^{X+dx/2} int_{Y-dy/2}^{Y+dy/2} f by the four corners of F (f = F_xy)."""
    hx, hy = 0.5 * dx, 0.5 * dy
    return F(X + hx, Y + hy) - F(X - hx, Y + hy) - F(X + hx, Y - hy) + F(X - hx, Y - hy)


def cerruti_kernels(
    X: FloatArray, Y: FloatArray, dx: float, dy: float, G: float, nu: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Tangential influence coefficients (m/Pa) of both half-spaces combined.

    X, Y: field-minus-source offsets (m) of element centres; dx, dy: element size (m).
    Returns (a_xx, a_yy, a_xy): u_x at the field element due to a unit tau_x (a_xx) or
    tau_y (a_xy) on the source element, the Appendix of Spector & Batra (1995)
    integrated over the source rectangle with Kalker's combined G (Pa) and nu (-).
    """
    i_yy = _corner_sum(_x_asinh_y_over_x, X, Y, dx, dy)  # int y^2/r^3
    i_xx = _corner_sum(lambda x, y: _x_asinh_y_over_x(y, x), X, Y, dx, dy)  # int x^2/r^3
    i_xy = _corner_sum(lambda x, y: -np.hypot(x, y), X, Y, dx, dy)  # int x y/r^3
    i_1 = i_xx + i_yy  # int 1/r
    c = 1.0 / (np.pi * G)
    a_xx = c * ((1.0 - nu) * i_1 + nu * i_xx)
    a_yy = c * ((1.0 - nu) * i_1 + nu * i_yy)
    a_xy = c * nu * i_xy
    return a_xx, a_yy, a_xy


def cerruti_grid_kernels(
    ox: FloatArray, oy: FloatArray, dx: float, dy: float, G: float, nu: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``cerruti_kernels`` at the offsets X, Y = meshgrid(ox, oy) (m), (len(oy), len(ox)),
    for offsets that are whole multiples of the element size dx, dy (in any order, e.g.
    a torus's fftfreq order): each antiderivative is evaluated once per element corner
    (four elements share one) rather than at the four corners of every element, a
    quarter of the transcendental functions (the kernels' cost when a contact is set
    up). The same four-corner sums in the same order: equal to ``cerruti_kernels`` to
    rounding (1e-14 of the largest entry; the corners' positions are rounded once
    instead of per element)."""
    kx = np.rint(np.asarray(ox) / dx).astype(np.intp)
    ky = np.rint(np.asarray(oy) / dy).astype(np.intp)
    x0, y0 = int(kx.min()), int(ky.min())
    # the corners x_k - dx/2 for k = x0 .. max + 1, likewise in y
    xc = (np.arange(x0, int(kx.max()) + 2) - 0.5) * dx
    yc = (np.arange(y0, int(ky.max()) + 2) - 0.5) * dy
    # the corners as a row and a column: each antiderivative broadcasts to the corner
    # grid (the same values as on np.meshgrid's arrays)
    Xc, Yc = xc[None, :], yc[:, None]
    Fc = np.stack(
        [
            _x_asinh_y_over_x(Xc, Yc),  # int y^2/r^3
            _x_asinh_y_over_x(Yc, Xc),  # int x^2/r^3
            -np.hypot(Xc, Yc),  # int x y/r^3
        ]
    )
    # the three corner sums at once, F(X + hx, Y + hy) - F(X - hx, Y + hy) - F(X + hx,
    # Y - hy) + F(X - hx, Y - hy), at the offsets asked for
    s = Fc[:, 1:, 1:] - Fc[:, 1:, :-1] - Fc[:, :-1, 1:] + Fc[:, :-1, :-1]
    i_yy, i_xx, i_xy = s.take(ky - y0, axis=1).take(kx - x0, axis=2)
    i_1 = i_xx + i_yy
    c = 1.0 / (np.pi * G)
    a_xx = c * ((1.0 - nu) * i_1 + nu * i_xx)
    a_yy = c * ((1.0 - nu) * i_1 + nu * i_yy)
    a_xy = c * nu * i_xy
    return a_xx, a_yy, a_xy


def boussinesq_kernel(
    X: FloatArray, Y: FloatArray, dx: float, dy: float, Estar: float
) -> FloatArray:
    """Normal influence coefficients (m/Pa): w = 1/(pi E*) int p/r over each element."""
    i_yy = _corner_sum(_x_asinh_y_over_x, X, Y, dx, dy)
    i_xx = _corner_sum(lambda x, y: _x_asinh_y_over_x(y, x), X, Y, dx, dy)
    return (i_xx + i_yy) / (np.pi * Estar)


def coupling_kernels(
    X: FloatArray, Y: FloatArray, dx: float, dy: float, G: float, kappa: float
) -> tuple[FloatArray, FloatArray]:
    """Pressure-to-tangential coefficients (m/Pa), u^s - u^b = -(kappa/(pi G)) int (x, y)/r^2 p.

    Zero for quasi-identical bodies (kappa = 0)."""

    def Fx(x, y):  # int int x/r^2
        return _x_atan_y_over_x(x, y) + _y_log_r2(x, y)

    c = -kappa / (np.pi * G)
    cx = c * _corner_sum(Fx, X, Y, dx, dy)
    cy = c * _corner_sum(lambda x, y: Fx(y, x), X, Y, dx, dy)
    return cx, cy


def plane_strain_kernel(X: FloatArray, dx: float, G: float, nu: float, L: float) -> FloatArray:
    """Plane-strain tangential coefficients (m/Pa) along a row (2-D, per unit width).

    u_x = -(2 (1 - nu)/(pi G)) int tau_x ln(|x|/L) dx' for two equal half-planes. The
    length L is arbitrary: it adds a constant displacement, and the steady-rolling
    operator acts on traction differences whose sum over a row vanishes. Choose L
    larger than the largest offset so that the kernel is positive.
    """

    def F(s):  # int ln(|s|/L) ds
        a = np.abs(s)
        safe = np.where(a > 0.0, a, 1.0)
        return np.where(a > 0.0, s * np.log(safe / L), 0.0) - s

    h = 0.5 * dx
    return -(2.0 * (1.0 - nu) / (np.pi * G)) * (F(X + h) - F(X - h))


# ---- FFT convolution ----------------------------------------------------------------
KernelFunction = Callable[[FloatArray, FloatArray], tuple[tuple[FloatArray, ...], ...]]


def difference(q: NDArray[np.float64]) -> NDArray[np.float64]:
    """D q: q_I - q_I+ along x (axis -1; the forward neighbour of the last column is 0),
    the upwind difference of steady rolling (rolling.py)."""
    d = q.copy()
    d[..., :-1] -= q[..., 1:]
    return d


@dataclass(frozen=True)
class BlockConvolution:
    """u_a = sum_b K_ab * q_b for a block of kernels (ncomp x ncomp), by FFT.

    ``kernel(X, Y)`` returns the blocks (rows of arrays) at field-minus-source offsets
    X, Y (m). They are evaluated on the zero-padded grid (>= 2n - 1 per direction) at
    the minimum-image offsets: the linear convolution on the grid uses only offsets up
    to n - 1, and filling the rest of the torus with the kernel itself (rather than
    zeros) keeps the circulant symbol positive definite, which the deconvolution
    preconditioner needs (with zero padding it is indefinite for nu = 0.5 or elongated
    elements). ``local`` (m/Pa) is added on the diagonal of every diagonal block (the
    layer terms kb + ks of Eqs. 6-7). ``on_grid(ox, oy)``, where given, returns the same
    blocks from the offsets along x and along y (for kernels that share work between
    neighbouring offsets, ``cerruti_grid_kernels``). ``apply`` costs O(N log N) for
    N = nx ny.
    """

    grid: Grid
    kernel: KernelFunction
    local: float = 0.0
    even: bool = True
    reference: BlockConvolution | None = field(default=None, repr=False, compare=False)
    scale: float = 1.0
    on_grid: KernelFunction | None = field(default=None, repr=False, compare=False)

    @cached_property
    def shape(self) -> tuple[int, int]:
        """Zero-padded FFT shape (Ly, Lx)."""
        return (
            sfft.next_fast_len(2 * self.grid.ny - 1, real=True),
            sfft.next_fast_len(2 * self.grid.nx - 1, real=True),
        )

    @cached_property
    def torus(self) -> NDArray[np.float64]:
        """Kernel blocks at the minimum-image offsets of the padded grid (n, n, Ly, Lx)."""
        if self.reference is not None:
            return self.scale * self.reference.torus
        Ly, Lx = self.shape
        oy = np.fft.fftfreq(Ly, 1.0 / Ly) * self.grid.dy
        ox = np.fft.fftfreq(Lx, 1.0 / Lx) * self.grid.dx
        if self.on_grid is not None:
            return np.array(self.on_grid(ox, oy), dtype=float)
        X, Y = np.meshgrid(ox, oy)
        return np.array(self.kernel(X, Y), dtype=float)

    @property
    def ncomp(self) -> int:
        return self.torus.shape[0]

    def offsets(self, arr: NDArray[np.float64]) -> NDArray[np.float64]:
        """Restrict a torus array (..., Ly, Lx) to offsets -(n-1)..(n-1): (..., 2ny-1, 2nx-1);
        offset (0, 0) sits at [ny - 1, nx - 1]."""
        ny, nx = self.grid.ny, self.grid.nx
        oy = np.arange(-(ny - 1), ny) % self.shape[0]
        ox = np.arange(-(nx - 1), nx) % self.shape[1]
        return arr[..., oy[:, None], ox[None, :]]

    @cached_property
    def symbols(self) -> NDArray:
        """Symbols of the blocks, (ncomp, ncomp, Ly, Lx//2+1): real for kernels even under
        (x, y) -> (-x, -y) (``even``, all but the pressure coupling), complex otherwise."""
        if self.reference is not None:
            return self.scale * self.reference.symbols
        S = sfft.rfft2(self.torus, axes=(-2, -1))
        return S.real if self.even else S

    @cached_property
    def self_coefficient(self) -> NDArray[np.float64]:
        """Diagonal-block coefficients at offsets (0, 0) and (dx, 0): (ncomp, 2) in m/Pa,
        the local term included on the (0, 0) entry."""
        out = np.empty((self.ncomp, 2))
        for a in range(self.ncomp):
            out[a, 0] = self.torus[a, a, 0, 0] + self.local
            out[a, 1] = self.torus[a, a, 0, 1] if self.grid.nx > 1 else 0.0
        return out

    def _convolve(self, S: NDArray[np.float64], q: FloatArray) -> FloatArray:
        """The block convolution of q (ncomp, ny, nx) with the symbols S on the padded
        torus, restricted to the grid. The 2-D transforms are taken one axis at a time,
        so that the padding rows are never transformed along x (forward) and only the
        grid's rows are transformed back along x (inverse): the same result as rfft2 and
        irfft2 of the padded arrays for about half their cost on the grids in use
        (per-call overhead included; 32 x 32 on 64 x 64: 0.09 ms against 0.16 ms)."""
        n = self.ncomp
        Ly, Lx = self.shape
        fq = sfft.fft(sfft.rfft(q, n=Lx, axis=-1), n=Ly, axis=-2, overwrite_x=True)
        out = np.empty_like(fq)
        for a in range(n):
            np.multiply(S[a, 0], fq[0], out=out[a])
            for b in range(1, n):
                out[a] += S[a, b] * fq[b]
        half = sfft.ifft(out, axis=-2, overwrite_x=True)[:, : self.grid.ny]
        return sfft.irfft(half, n=Lx, axis=-1)[:, :, : self.grid.nx]

    def apply(self, q: FloatArray) -> FloatArray:
        """Displacements (ncomp, ny, nx) (m) due to tractions q (ncomp, ny, nx) (Pa)."""
        u = self._convolve(self.symbols, q)
        if self.local:
            u = u + self.local * q
        return u

    @cached_property
    def inverse_symbols(self) -> NDArray[np.float64]:
        """Per-frequency inverse of (symbols + local I): (ncomp, ncomp, Ly, Lx//2+1)."""
        if self.reference is not None and self.local == 0.0 and self.reference.local == 0.0:
            return self.reference.inverse_symbols / self.scale  # the floor is relative
        S = np.moveaxis(self.symbols, (0, 1), (-2, -1)).copy()
        n = self.ncomp
        S[..., range(n), range(n)] += self.local
        w, V = np.linalg.eigh(S)
        w = np.maximum(w, SYMBOL_FLOOR * float(w.max()))
        inv = np.einsum("...ik,...k,...jk->...ij", V, 1.0 / w, V)
        return np.moveaxis(inv, (-2, -1), (0, 1))

    def solve_periodic(self, r: FloatArray) -> FloatArray:
        """Approximate inverse of ``apply``: deconvolution on the padded periodic grid.

        Exact for the pure layer (local) operator; for the half-space it inverts the
        circulant on the whole padded grid, a spectrally equivalent preconditioner for the
        operator restricted to the contact (Vollebregt 2014, J. Comput. Phys. 257, 333).
        """
        return self._convolve(self.inverse_symbols, r)

    @cached_property
    def inverse_offsets(self) -> NDArray[np.float64]:
        """Kernel of ``solve_periodic`` over offsets: (ncomp, ncomp, 2 ny - 1, 2 nx - 1)."""
        full = sfft.irfft2(self.inverse_symbols, s=self.shape, axes=(-2, -1))
        return self.offsets(full)

    def dense(self, mask: NDArray[np.bool_]) -> FloatArray:
        """Dense influence matrix restricted to ``mask`` (rows and columns), component-major:
        shape (ncomp m, ncomp m) for m = mask.sum(). Memory 8 (ncomp m)^2 bytes."""
        jj, ii = np.nonzero(mask)
        Ly, Lx = self.shape
        dj = (jj[:, None] - jj[None, :]) % Ly
        di = (ii[:, None] - ii[None, :]) % Lx
        n, m = self.ncomp, len(jj)
        M = np.empty((n * m, n * m))
        for a in range(n):
            for b in range(n):
                blk = self.torus[a, b][dj, di]
                if a == b and self.local:
                    blk = blk + self.local * np.eye(m)
                M[a * m : (a + 1) * m, b * m : (b + 1) * m] = blk
        return M


def tangential_operator(grid: Grid, G: float, nu: float, k: float = 0.0) -> BlockConvolution:
    """2 x 2 Cerruti block (tau_x, tau_y) -> (u_x, u_y) plus the layer term k (m/Pa).

    The coefficients are homogeneous: those of elements dx x dy and modulus G are dx/G
    times those of elements 1 x dy/dx and modulus 1 (every integral of 1/r, x^2/r^3,
    x y/r^3 over an element scales with its length). The operator therefore takes its
    kernel blocks, symbols and (without layer) inverse symbols from a reference operator
    kept per grid shape, aspect ratio dy/dx and nu (``_cerruti_reference``, at most
    KERNEL_CACHE of them), scaled: a load change (the ellipse scales, its aspect ratio
    stays), a creep curve or a table over loads evaluates no kernel again. The scaled
    coefficients equal directly evaluated ones to 1e-12 (the ratio is kept to 12 digits;
    tests/test_halfspace_influence.py).
    """
    # the aspect ratio to 12 digits: a load change scales dx and dy alike, but their
    # ratio from Hertz's semi-axes may differ in the last bits (the reference's kernel
    # then differs by 1e-12 relative, far below the solver's tolerance)
    ratio = float(f"{grid.dy / grid.dx:.12e}")
    ref = _cerruti_reference(grid.nx, grid.ny, ratio, float(nu))
    dx, dy = grid.dx, grid.dy

    def kern(X, Y):
        axx, ayy, axy = cerruti_kernels(X, Y, dx, dy, G, nu)
        return ((axx, axy), (axy, ayy))

    return BlockConvolution(grid, kern, local=k, reference=ref, scale=dx / G)


@lru_cache(maxsize=KERNEL_CACHE)
def _cerruti_reference(nx: int, ny: int, ratio: float, nu: float) -> BlockConvolution:
    """The Cerruti block of an nx x ny grid of elements 1 x ratio, modulus 1, Poisson's
    ratio nu (dimensionless), with its kernel blocks evaluated once; read-only arrays."""
    grid = Grid(nx, ny, 1.0, ratio, 0.0, 0.0)

    def kern(X, Y):
        axx, ayy, axy = cerruti_kernels(X, Y, 1.0, ratio, 1.0, nu)
        return ((axx, axy), (axy, ayy))

    def on_grid(ox, oy):
        axx, ayy, axy = cerruti_grid_kernels(ox, oy, 1.0, ratio, 1.0, nu)
        return ((axx, axy), (axy, ayy))

    op = BlockConvolution(grid, kern, on_grid=on_grid)
    op.torus.flags.writeable = False
    return op


def normal_operator(grid: Grid, Estar: float, k: float = 0.0) -> BlockConvolution:
    """1 x 1 Boussinesq block p -> w plus the Winkler layers k = k1 + k2 (m/Pa)."""
    dx, dy = grid.dx, grid.dy
    return BlockConvolution(
        grid, lambda X, Y: ((boussinesq_kernel(X, Y, dx, dy, Estar),),), local=k
    )


def coupling_displacement(grid: Grid, p: FloatArray, G: float, kappa: float) -> FloatArray:
    """u^s - u^b (2, ny, nx) (m) due to the pressure p (ny, nx) (Pa) (Appendix, B(p))."""
    dx, dy = grid.dx, grid.dy
    out = []
    for comp in range(2):
        op = BlockConvolution(
            grid,
            lambda X, Y, c=comp: ((coupling_kernels(X, Y, dx, dy, G, kappa)[c],),),
            even=False,  # x/r^2 and y/r^2 are odd: complex symbols
        )
        out.append(op.apply(p[None])[0])
    return np.stack(out)


def plane_strain_operator(grid: Grid, G: float, nu: float, k: float = 0.0) -> BlockConvolution:
    """Plane strain on a one-row grid: 2 x 2 block with the ln kernel on the diagonal and
    no coupling (only the x component carries load in a 2-D rolling problem)."""
    if grid.ny != 1:
        raise InputError("ny", grid.ny, "1 for plane strain")
    dx = grid.dx
    L = 4.0 * np.e * grid.nx * dx  # beyond every offset of the padded grid: kernel > 0

    def kern(X, Y):
        a = plane_strain_kernel(X, dx, G, nu, L)
        return ((a, np.zeros_like(a)), (np.zeros_like(a), a))

    return BlockConvolution(grid, kern, local=k)
