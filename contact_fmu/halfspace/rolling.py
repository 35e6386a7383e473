"""Steady rolling with the exact half-space theory (Kalker) plus the local layer terms.

Model (Spector & Batra 1995, Eqs. 2-7 and the Appendix; quasistationary phase, Eq. 15
without the time derivative). With u = u^s - u^b the slip is s = v + Vx du/dx and

    u = A tau + (kb + ks) tau + C p,

A the Cerruti operator of both half-spaces (influence.cerruti_kernels), C the pressure
coupling (zero for quasi-identical bodies). The solver works in the frame rolling in
+x (Vx > 0; contact.py mirrors Vx < 0): material enters at the leading edge x = +l(y).

Discretisation (Kalker 1990, Ch. 5; Vollebregt's CONTACT). Rectangular elements with
piecewise-constant traction; the derivative along the rolling direction is the upwind
difference over one element, so the slip per element, scaled by dx/Vx, is

    S_I = W_I - (U_I - U_I+),    W_I = w(x_I + dx/2, y_I) dx,    w = v/Vx,

I+ the element ahead of I. On a Toeplitz grid (U_I - U_I+) = (A dtau)_I exactly, with
the traction differences dtau_I = tau_I - tau_I+ (supported on the contact and on the
element behind each trailing edge): the steady-rolling operator is the symmetric
influence operator acting on differences, K tau = (A + k) D tau. One application costs
two FFTs per component (O(N log N)).

Leading edge. The element I0 of a row whose centre is the last inside the contact has
its forward neighbour outside, where the layer term vanishes but the half-space
displacement continues smoothly. With the edge at x_I0 + theta dx (0 < theta <= 1),
integrating the adhesion condition from the edge to x_I0 and interpolating A tau
linearly over the element gives (A dtau)_I0 + (k/theta) tau_I0 = w dx: the layer term
of that element is k/theta. This is exact for the thin layer (it reproduces the nodal
values of LayerContact.traction) and leaves Kalker's half-space scheme unchanged.

Coulomb conditions (4)-(5), with g = mu p, in the equivalent fixed-point form

    F(tau) = tau - Proj_{|.| <= g}(tau + r S(tau)) = 0,

(adhesion: S = 0, |tau| <= g; slip: |tau| = g, tau parallel to S with the same sense).
F is solved by a semismooth Newton method (Alart & Curnier 1991; Hintermueller, Ito &
Kunisch 2002): in adhesion elements the Newton rows are K dtau = S; in slip elements
the component along tau is local and the tangential one is (|z|/g - 1)/r dtau_t +
(K dtau)_t = -(|z|/g) tau_t/r, z = tau + r S. Each Newton system is solved by GMRES
(scipy) with a preconditioner that inverts the adhesion block: an FFT deconvolution
of (A + k) for the traction differences, an exact closure that makes them sum to zero
over each adhesion interval (a small dense system, one unknown per interval and
component), and the march from the leading edge that turns differences into
tractions. For the thin layer this preconditioner is the exact inverse (the march of
LayerContact.traction); for the half-space it is spectrally equivalent. Backtracking on
|F| globalises the iteration. Small contacts take dense direct Newton steps instead
(direct.py; DIRECT_MAX_ELEMENTS on a patch's first solve, DIRECT_REPEAT_MAX_ELEMENTS
on later ones).

Nested iteration: a patch from ellipse_patch carries its coarse levels (n/2, n/4, ...
elements per side over the same ellipse, down to NESTED_MIN_N); solve_rolling solves the
coarsest level from the calibrated FASTSIM guess and starts each finer level from the
prolonged coarse traction (``prolong``), so the fine grid's Newton count stays bounded
as the grid is refined (docs/halfspace.md, "Iteration counts").
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import cached_property, partial
from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.ndimage as ndi
from numpy.typing import NDArray
from scipy.linalg.lapack import dgetrf, dgetrs

from .._validate import (
    InputError,
    array,
    count,
    finite,
    instance,
    nonnegative,
    one_of,
    positive,
)
from . import direct
from .influence import (
    BlockConvolution,
    Grid,
    coupling_displacement,
    difference,
    tangential_operator,
)
from .krylov import gmres, gmres_right

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

# Newton convergence: max |F| <= NEWTON_TOL * max g. F is a traction (Pa); 1e-7 of the
# traction bound is far below the discretisation error (1e-3 and above).
NEWTON_TOL = 1e-7
# ... or, where the traction is far below its bound (small creepages), NEWTON_TOL times
# SMALL_TRACTION max |tau|, whichever is smaller (solve_rolling): the traction is then
# converged to NEWTON_TOL SMALL_TRACTION = 1e-4 of itself, ten times below the 0.1 % of
# the force asked of the solver (at xi = 1e-6 mu P/(G c^2) on 32 x 32 the bound max g
# alone left 0.015-0.08 % against the linear theory; tests/test_halfspace_curve.py).
# It binds only below max |tau| = 1e-3 max g: creep curves and tables cost the same.
SMALL_TRACTION = 1e3
# Newton iteration cap; observed counts are 2-12 (docs/halfspace.md).
NEWTON_MAXIT = 60
# Inexact Newton: the GMRES relative tolerance is min(GMRES_RTOL_MAX, ratio of the last two
# |F|) and at least GMRES_RTOL_MIN (Eisenstat & Walker 1996, choice 1 simplified).
GMRES_RTOL_MAX = 0.1
GMRES_RTOL_MIN = 1e-12
# ... but no smaller than OVERSOLVE times the reduction of max |F| still needed to reach
# the Newton tolerance (no oversolving in the last step; Kelley 1995, Sec. 6.3). Measured
# on the railway cases: 0-15 % fewer GMRES iterations, the same Newton counts.
OVERSOLVE = 0.1
# Preconditioner of the Newton systems: slip elements whose local coefficient
# (|z|/g - 1)/r is below SLIP_BLOCK_RATIO times their diagonal of K join the adhesion
# block (_newton_direction). Measured on the railway cases (16..128, four creepages):
# 0.3-0.7 all cut the fine grid's GMRES count by about 20 % (128 x 128: 25-30 %), 0.5
# the most; 1 and above less; all slip elements (inf) doubles it.
SLIP_BLOCK_RATIO = 0.5
# GMRES restart length and cap on the total number of inner iterations per Newton step.
GMRES_RESTART = 60
GMRES_MAXIT = 600
# Backtracking: sufficient decrease factor on |F|_2 and the smallest step fraction.
ARMIJO = 1e-4
MIN_STEP = 1.0 / 64.0
# Direct path (direct.py) for contacts of at most DIRECT_MAX_ELEMENTS elements on a
# patch's first solve, and of at most DIRECT_REPEAT_MAX_ELEMENTS on its later ones
# (solve_rolling, method "auto"; the rule in docs/halfspace.md, "Which path"). Measured
# on the railway wheel (CPU ms; first solve, second (it builds K^-1: 14.5 ms at 293
# elements), later ones): direct 8.9, 13.4, 3.3 and iterative 14.3, 7.3, 7.3 at 225
# elements; direct 13.9, 26.5, 7.7 and iterative 17.0, 8.6, 8.6 at 293; at 349 the
# iterative path is as fast on a first solve and faster on later ones. So a first solve
# is direct up to about 320 elements, and the n solves of one patch cost least on the
# direct path up to about 260 (at 225 from n = 2 on), but iteratively from the second
# solve on at 293 (direct only even again from n = 20).
DIRECT_MAX_ELEMENTS = 320
DIRECT_REPEAT_MAX_ELEMENTS = 260
# The start's calibration (RollingPatch.flexibilities) on an elliptic contact without
# layers: the patch's own linear theory (the LU of K) up to this many contact elements,
# Kalker's creep coefficients above; by the patch's size, never by the solves before it,
# so that a table built in chunks gives the serial build's doubles. Measured (CPU ms,
# median of 7, 11 x 11 of 79 elements, benchmarks/bench_halfspace_small.py): Kalker's
# start 1.91 first and 0.93 later cold solves longitudinal, 1.41 and 0.59 combined with
# spin; the exact start 1.80 and 0.67, 1.72 and 0.61 (Newton reuses one factorisation
# more often from it; its LU of 158 unknowns is cheap); on 19 x 19 (255 elements) the LU
# took a third of a first solve.
EXACT_START_MAX_ELEMENTS = 100
# Nested iteration (docs/halfspace.md): ellipse_patch grids of n elements per side get a
# coarse level of n/2 while n/2 >= NESTED_MIN_N, recursively. A 16 x 16 level costs
# about what it saves (measured: 32 x 32 15-20 % slower nested from 16 x 16, 64 x 64 no
# faster from 16 than from 32; the fine grid's counts are the same).
NESTED_MIN_N = 32
# Newton tolerance of the coarse levels, relative to max g like NEWTON_TOL: their
# solution is only the fine level's initial guess, whose error against the fine solution
# is the discretisation error of the coarse grid (1e-2 of mu p and above).
NESTED_TOL = 1e-4
# Continuation along a sequence of solves (``Continuation``): the next creepage is
# predicted from the last two solutions when it lies on their line (its distance from
# the line at most CONTINUATION_LINE times its distance from the last point) no farther
# than CONTINUATION_REACH of their spacings from the last; from the last alone, scaled,
# when it lies on the ray from zero through it (the linear theory's proportionality).
CONTINUATION_LINE = 0.1
CONTINUATION_REACH = 2.0
# Creepages far into full slip (``creepage_scale``): where the rigid slip W of every
# element exceeds the elastic displacement of the traction bound, max g/r, by more than
# SATURATION_RATIO, each element slips along W (up to terms of relative size
# 1/SATURATION_RATIO, below double rounding), so the tractions do not depend on the
# creepages' size: they are solved at this ratio, the slip scaled back. Without it the
# fixed-point variable tau + r S overflows from creepages of about 1e296 on (NaN
# tractions).
SATURATION_RATIO = 1e20
# Creepages within full adhesion (``creepage_scale``): where the rigid slip is below
# ADHESION_RATIO times that displacement, every element adheres and the solution is
# linear in the creepages (tau = K^-1 W), so it is solved at this ratio and scaled back
# (without it creepages of 1e-300 left the line contact's slip in subnormal numbers and
# its Newton iteration stalled). Without the pressure coupling only: its slip does not
# scale with the creepages.
ADHESION_RATIO = 1e-20


@dataclass(frozen=True)
class RollingSolution:
    """Steady-rolling traction on the grid (frame rolling in +x).

    tau (2, ny, nx) (Pa): traction the body exerts on the substrate; slip S (2, ny, nx)
    (m, the slip times dx/Vx); ``adhesion`` and ``slip`` masks (ny, nx); ``contact``
    mask; forces Tx, Ty (N) and the spin moment Mz = sum (x tau_y - y tau_x) dA (N m);
    Newton and total GMRES iteration counts on this grid. ``levels``: with nested
    iteration, (nx, ny, Newton, GMRES) per level from the coarsest to this grid (the last
    entry repeats the two counts above); empty for a single-level solve. ``error``:
    with ``HalfSpaceContact.solve(richardson=True)``, the estimated discretisation error
    (Tx, Ty, Mz) of this grid's forces, (F(r h) - F(h))/(r - 1) for the scheme's first
    order and elements r times larger (r = 2 on even grids), and ``extrapolated`` the
    Richardson values F(h) minus it; None otherwise. ``solves``:
    the steady-rolling solves that produced it (``HalfSpaceContact.creepages_for``: its
    whole search; 1 otherwise).
    """

    grid: Grid
    tau: FloatArray
    S: FloatArray
    contact: BoolArray
    adhesion: BoolArray
    slip: BoolArray
    Tx: float
    Ty: float
    Mz: float
    newton_iterations: int
    gmres_iterations: int
    levels: tuple[tuple[int, int, int, int], ...] = ()
    error: tuple[float, float, float] | None = None
    extrapolated: tuple[float, float, float] | None = None
    solves: int = 1

    @property
    def adhesion_fraction(self) -> float:
        """Adhesion area over contact area (-)."""
        n = int(self.contact.sum())
        return float(self.adhesion.sum()) / n if n else 0.0

    def plot(self, ax: Any = None, arrows: bool = True, title: bool = True) -> Any:
        """Traction arrows over contours of |tau|, adhesion and slip areas marked
        (matplotlib; ``plotting.plot_solution``). Returns the axes."""
        from .plotting import plot_solution  # matplotlib only when plotting

        return plot_solution(self, ax, arrows, title)

    @property
    def gmres_work(self) -> float:
        """GMRES iterations of all levels in units of this grid's (a coarse iteration
        weighted by its share of the elements): the total cost of the inner solves."""
        if not self.levels:
            return float(self.gmres_iterations)
        N = self.grid.nx * self.grid.ny
        return float(sum(g * nx * ny / N for nx, ny, _, g in self.levels))


@dataclass
class RollingPatch:
    """The discretised steady-rolling problem on one grid and pressure.

    grid: the potential contact area (it must leave at least one element outside the
    contact behind every trailing edge); p (ny, nx): normal pressure (Pa), the contact
    is p > 0; mu: friction coefficient (-); G, nu: Kalker's combined shear modulus (Pa)
    and Poisson's ratio (-); k: layer compliance kb + ks (m/Pa, Eqs. 6-7); theta (ny,
    nx): fraction of an element between its centre and the leading edge (1 inside,
    (0, 1] in the leading elements; None: 1); kappa: Kalker's difference parameter
    (pressure coupling, 0: quasi-identical bodies); backend "fft" or "dense" (the same
    solver with an explicit influence matrix, for benchmarks); ellipse: the semi-axes
    (a1, a2) (m) of the elliptic contact the pressure samples (``ellipse_patch``; the
    FASTSIM start's calibration by Kalker's creep coefficients, ``flexibilities``;
    None: any other contact); coarsen: builds the
    same problem on a grid of about half the elements per side over the same potential
    contact area, for the backend given (nested iteration, ``solve_rolling``; None:
    none, as for the coarsest level).
    Derived quantities are cached: treat a patch as immutable once built.
    """

    grid: Grid
    p: FloatArray
    mu: float
    G: float
    nu: float
    k: float = 0.0
    theta: FloatArray | None = None
    kappa: float = 0.0
    backend: str = "fft"
    use_closure: bool = False
    operator: BlockConvolution | None = None
    ellipse: tuple[float, float] | None = None
    coarsen: Callable[[str], RollingPatch] | None = field(default=None, repr=False, compare=False)
    solves: int = field(default=0, repr=False, compare=False)  # direct-path solves so far

    def __post_init__(self) -> None:
        instance("grid", self.grid, Grid, "an influence.Grid")
        self.p = array("p", self.p, self.grid.shape)
        if np.any(self.p < 0.0):
            raise InputError("p", "negative values", ">= 0")
        positive("mu", self.mu)
        positive("G", self.G)
        finite("nu", self.nu)
        nonnegative("k", self.k)
        finite("kappa", self.kappa)
        if self.backend not in ("fft", "dense"):
            raise InputError("backend", self.backend, '"fft" or "dense"')
        if np.any(self.contact[:, 0]):
            raise InputError(
                "grid", "contact in the first column", "one element behind each trailing edge"
            )
        th = np.ones(self.grid.shape) if self.theta is None else array("theta", self.theta)
        if th.shape != self.grid.shape or np.any(th <= 0.0) or np.any(th > 1.0):
            raise InputError("theta", "shape or range", f"shape {self.grid.shape}, in (0, 1]")
        self.theta = np.where(self.leading, th, 1.0)

    # ---- geometry ------------------------------------------------------------------
    @cached_property
    def contact(self) -> BoolArray:
        return self.p > 0.0

    @cached_property
    def leading(self) -> BoolArray:
        """Leading elements: in contact, forward neighbour (+x) outside."""
        C = self.contact
        ahead = np.zeros_like(C)
        ahead[:, :-1] = C[:, 1:]
        return C & ~ahead

    @cached_property
    def g(self) -> FloatArray:
        """Traction bound mu p (Pa)."""
        return self.mu * self.p

    @cached_property
    def coarse(self) -> RollingPatch | None:
        """The next coarser level (cached, with its own coarse levels), or None."""
        if self.coarsen is None:
            return None
        return self.coarsen(self.backend)

    @cached_property
    def op(self) -> BlockConvolution:
        """The operator A + k: supplied (e.g. plane strain) or the Cerruti block."""
        if self.operator is not None:
            return self.operator
        return tangential_operator(self.grid, self.G, self.nu, self.k)

    @cached_property
    def k_extra(self) -> FloatArray:
        """Extra layer coefficient k/theta - k of the leading elements (m/Pa)."""
        return self.k * (1.0 / self.theta - 1.0)

    @cached_property
    def r(self) -> float:
        """Scaling r of the fixed-point form: the inverse diagonal of K (Pa/m)."""
        d = self.op.self_coefficient
        return 1.0 / float(d[0, 0] - d[0, 1])

    @cached_property
    def creepage_units(self) -> tuple[float, float]:
        """The rigid slip per element of a unit creepage, dx, and of a unit spin, dx R (R:
        the largest |x|, |y| of the grid), over the elastic displacement of the traction
        bound, max g/r (``creepage_scale``)."""
        unit = self.grid.dx / (float(self.g.max()) / self.r)
        return unit, unit * self.grid.reach

    @cached_property
    def diag(self) -> FloatArray:
        """Diagonal of K per component (2, ny, nx) (m/Pa)."""
        d = self.op.self_coefficient
        out = np.empty((2, *self.grid.shape))
        for a in range(2):
            out[a] = d[a, 0] - d[a, 1]
            out[a, :, 0] = d[a, 0]  # no element behind the first column
        return out + self.k_extra

    @cached_property
    def pressure_slip(self) -> FloatArray:
        """-(U_p,I - U_p,I+): the slip (m) from the pressure coupling C p, (2, ny, nx)."""
        if self.kappa == 0.0:
            return np.zeros((2, *self.grid.shape))
        u = coupling_displacement(self.grid, self.p, self.G, self.kappa)
        du = u.copy()
        du[:, :, :-1] -= u[:, :, 1:]
        return -du

    @cached_property
    def _dense(self) -> tuple[FloatArray, BoolArray]:
        """Dense (A + k) restricted to rows C and columns C + trailing neighbours."""
        C = self.contact
        behind = np.zeros_like(C)
        behind[:, :-1] = C[:, 1:]
        cols = C | behind
        jj, ii = np.nonzero(cols)
        rows_in = C[jj, ii]
        full = self.op.dense(cols)
        keep = np.concatenate([rows_in, rows_in])
        return full[keep], cols

    @cached_property
    def direct(self) -> bool:
        """Whether this patch is in the direct path's range: contacts of at most
        DIRECT_MAX_ELEMENTS elements, FFT backend (its first ``solve_rolling(method=
        "auto")`` is direct, and so are later ones up to DIRECT_REPEAT_MAX_ELEMENTS; its
        full-adhesion solves use the dense K)."""
        return int(self.contact.sum()) <= DIRECT_MAX_ELEMENTS and self.backend == "fft"

    @cached_property
    def difference_kernel(self) -> direct.DifferenceKernel:
        """K's entries as shifted entries of one kernel (direct.py; small grids)."""
        return direct.DifferenceKernel(self.op, self.contact, self.k_extra)

    @cached_property
    def dense_contact_operator(self) -> FloatArray:
        """K on the contact as a dense (2 m, 2 m) matrix (direct.py; small grids)."""
        return direct.contact_operator(self)

    @cached_property
    def dense_contact_lu(self) -> tuple[FloatArray, NDArray[np.int32]]:
        """LU factors of K on the contact (the full-adhesion solves of a direct-path patch
        without its K^-1: a third of the inversion's cost)."""
        lu, piv, info = dgetrf(self.dense_contact_operator)
        if info != 0:
            raise RuntimeError(f"steady rolling: singular contact operator ({info})")
        return lu, piv

    @cached_property
    def dense_contact_inverse(self) -> FloatArray:
        """K^-1 on the contact (the slip form of the direct path's Newton steps, direct.py)."""
        return sla.inv(self.dense_contact_operator)

    # ---- operators ---------------------------------------------------------------------
    def apply_K(self, tau: FloatArray) -> FloatArray:
        """K tau = (A + k) D tau + (k/theta - k) D tau at the leading elements (m)."""
        dq = difference(tau)
        if self.backend == "fft":
            u = self.op.apply(dq)
        else:
            M, cols = self._dense
            v = np.concatenate([dq[0][cols], dq[1][cols]])
            w = M @ v
            m = int(self.contact.sum())
            u = np.zeros_like(dq)
            u[0][self.contact] = w[:m]
            u[1][self.contact] = w[m:]
        return u + self.k_extra * dq

    def rhs(self, xi: float, eta: float, phi: float) -> FloatArray:
        """W (2, ny, nx) (m): the creepage w = (xi - phi y, eta + phi x) at the element
        centre times dx (Kalker's collocation; it converges faster for spin than the
        midpoint of the travel, docs/halfspace.md), plus the pressure slip."""
        X, Y = self.grid.mesh()
        dx = self.grid.dx
        W = np.stack([(xi - phi * Y) * dx, (eta + phi * X) * dx])
        W = W + self.pressure_slip
        return np.where(self.contact, W, 0.0)

    # ---- preconditioner pieces ------------------------------------------------------------
    def _intervals(
        self, H: BoolArray
    ) -> tuple[NDArray[np.int_], NDArray[np.int_], NDArray[np.int_]]:
        """Maximal runs of H along x: (row, first column, last column); the closure element
        is first - 1."""
        Hp = np.zeros((H.shape[0], H.shape[1] + 2), bool)
        Hp[:, 1:-1] = H
        d = np.diff(Hp.astype(np.int8), axis=1)
        rs, cs = np.nonzero(d == 1)
        re, ce = np.nonzero(d == -1)
        # np.nonzero scans row-major, so starts and ends pair up in order
        return rs, cs, ce - 1

    def _closure(self, H: BoolArray):
        """Dense closure system for the adhesion intervals of H (factorised)."""
        rows, c0, c1 = self._intervals(H)
        n = len(rows)
        if n == 0 or not self.use_closure:
            return None
        ny, nx = self.grid.shape
        Kinv = self.op.inverse_offsets  # (2, 2, 2 ny - 1, 2 nx - 1)
        pref = np.concatenate([np.zeros((2, 2, 2 * ny - 1, 1)), np.cumsum(Kinv, axis=-1)], axis=-1)
        t = c0 - 1  # closure elements
        dyo = rows[:, None] - rows[None, :] + ny - 1
        hi = c1[:, None] - t[None, :] + nx - 1 + 1
        lo = t[:, None] - t[None, :] + nx - 1
        S = np.empty((2 * n, 2 * n))
        dth = self._theta_scale
        for a in range(2):
            for b in range(2):
                blk = pref[a, b][dyo, hi] - pref[a, b][dyo, lo]
                # leading-element scaling of the preconditioner (see _theta_scale)
                f = dth[rows, c1] - 1.0
                blk = blk + f[:, None] * Kinv[a, b][dyo, c1[:, None] - t[None, :] + nx - 1]
                S[a * n : (a + 1) * n, b * n : (b + 1) * n] = blk
        return sla.lu_factor(S), rows, t, c1

    @cached_property
    def _theta_scale(self) -> FloatArray:
        """Per-element factor on the deconvolution: (a0 + k)/(a0 + k/theta) (1 off the edge)."""
        a0 = float(self.op.self_coefficient[0, 0])
        return a0 / (a0 + self.k_extra)

    def _precondition_adhesion(
        self,
        res: FloatArray,
        H: BoolArray,
        clo,
        marcher: Callable[[FloatArray], FloatArray] | None = None,
    ) -> FloatArray:
        """Approximate K_HH^{-1} res (res (2, ny, nx) on H) -> dtau on H; marcher:
        ``march_plan(H)`` where the caller keeps it."""
        r0 = np.where(H, res, 0.0)
        q = self.op.solve_periodic(r0) * self._theta_scale
        if clo is not None:
            lu, rows, t, c1 = clo
            n = len(rows)
            # sums of q over interval + closure element per component
            cs = np.cumsum(q, axis=-1)
            tot = cs[:, rows, c1] - np.where(t > 0, cs[:, rows, np.maximum(t - 1, 0)], 0.0)
            mult = sla.lu_solve(lu, -np.concatenate([tot[0], tot[1]]))
            r1 = r0.copy()
            r1[0, rows, t] += mult[:n]
            r1[1, rows, t] += mult[n:]
            q = self.op.solve_periodic(r1) * self._theta_scale
        return march(q, H) if marcher is None else marcher(q)

    # ---- linear theory and the initial guess -----------------------------------------
    def solve_adhesion(self, W: FloatArray, rtol: float = 1e-10) -> tuple[FloatArray, int]:
        """Full adhesion (mu -> inf, Kalker's linear theory): K tau = W on the contact,
        by ``krylov.gmres_right`` to rtol of |W| (the true residual).

        Returns tau (2, ny, nx) (Pa) and the GMRES iteration count (0 for the contacts
        of the direct path, which use the dense K^-1 it keeps anyway)."""
        C = self.contact
        m = int(C.sum())
        if self.direct:
            return self._adhesion_dense([W])[0], 0
        clo = self._closure(C)

        iC = np.flatnonzero(C)
        iCC = np.concatenate([iC, C.size + iC])  # both components, flat
        shape = (2, *self.grid.shape)
        marcher = march_plan(C)

        def matvec(x):
            t = np.zeros(2 * C.size)
            t[iCC] = x
            return self.apply_K(t.reshape(shape)).ravel()[iCC], None

        def psolve(v):
            res = np.zeros(2 * C.size)
            res[iCC] = v
            return self._precondition_adhesion(res.reshape(shape), C, clo, marcher).ravel()[iCC]

        b = np.concatenate([W[0][C], W[1][C]])
        x, its, _ = gmres_right(matvec, b, psolve, rtol, GMRES_RESTART, GMRES_MAXIT)
        tau = np.zeros((2, *self.grid.shape))
        tau[0][C], tau[1][C] = x[:m], x[m:]
        return tau, its

    def _adhesion_dense(self, Ws: list[FloatArray]) -> list[FloatArray]:
        """Full adhesion K tau = W for several W at once by the dense K (direct path):
        K^-1 where built, else its LU factors."""
        C = self.contact
        m = int(C.sum())
        b = np.stack([np.concatenate([W[0][C], W[1][C]]) for W in Ws], axis=1)
        if "dense_contact_inverse" in self.__dict__:
            x = self.dense_contact_inverse @ b
        else:
            x, _ = dgetrs(*self.dense_contact_lu, b)
        out = []
        for j in range(len(Ws)):
            tau = np.zeros((2, *self.grid.shape))
            tau[0][C], tau[1][C] = x[:m, j], x[m:, j]
            out.append(tau)
        return out

    @cached_property
    def flexibilities(self) -> tuple[float, float, float]:
        """FASTSIM flexibilities (L_x, L_y, L_phi) (m/Pa) of the start's march tau_I =
        tau_I+ + W_I/L: the march's full-adhesion force per unit creepage (with L = 1)
        over the linear theory's. On an elliptic contact (``ellipse``) without layers of
        more than EXACT_START_MAX_ELEMENTS contact elements the linear theory is
        Kalker's, G c^2 C11, G c^2 C22, G c^3 C23 (Table E3 interpolated,
        ``kalker_coefficients``): no linear solve (it took a third of a first solve on
        19 x 19: an LU of K on the direct path, three GMRES solves on the iterative one).
        Otherwise the patch's own linear theory by three full-adhesion solves (products
        with K^-1 where the direct path has built it, else by the LU of K on the direct
        path, by GMRES on the iterative one). The two differ by the grid's
        discretisation error of the linear theory (2-7 % on 11 x 11, 1-3 % on 35 x 35);
        the start is only Newton's initial guess (the solutions agree to the Newton
        tolerance). Which one a patch uses depends on the patch alone, not on the solves
        before: a table built in chunks (Dask) gives the serial build's doubles."""
        C = self.contact
        dx = self.grid.dx
        ones, zero = np.where(C, dx, 0.0), np.zeros(self.grid.shape)
        X, Y = self.grid.mesh()
        # the spin load is the whole rigid slip phi (-y, x) (its -y part loads Ty too
        # for nu > 0); FASTSIM's march of the lateral part phi x carries Ty
        spin = np.stack([np.where(C, -Y * dx, 0.0), np.where(C, X * dx, 0.0)])
        loads = ((0, np.stack([ones, zero])), (1, np.stack([zero, ones])), (1, spin))
        fs = march(np.stack([W[a] for a, W in loads]), C).sum(axis=(1, 2))
        # Kalker's coefficients only where used (their interpolation is 3 % of an 11 x 11
        # first solve)
        coefficients = self.kalker_coefficients if int(C.sum()) > EXACT_START_MAX_ELEMENTS else None
        if coefficients is not None:
            # the linear theory's force sums tau over the elements: F/dA
            a1, a2 = self.ellipse  # type: ignore[misc]
            c2 = a1 * a2
            C11, C22, C23 = coefficients
            scale = self.G * c2 / self.grid.area
            exact = [scale * C11, scale * C22, scale * math.sqrt(c2) * C23]
        elif self.direct:  # the three solves at once by the dense LU, only their sums kept
            exact = [
                t[a].sum()
                for (a, _), t in zip(
                    loads, self._adhesion_dense([W for _, W in loads]), strict=True
                )
            ]
        else:
            exact = [self.solve_adhesion(W, rtol=1e-6)[0][a].sum() for a, W in loads]
        return tuple(float(f) / float(e) for f, e in zip(fs, exact, strict=True))

    @cached_property
    def kalker_coefficients(self) -> tuple[float, float, float] | None:
        """Kalker's (C11, C22, C23) (-) of this patch's ellipse (``flexibilities``), or
        None: no ellipse, layers (k > 0), or a/b or nu beyond Table E3."""
        if self.ellipse is None or self.k > 0.0:
            return None
        from .fastsim import AOB_MAX, AOB_MIN, kalker_coefficients  # fastsim imports rolling

        aob = self.ellipse[0] / self.ellipse[1]
        if not (AOB_MIN <= aob <= AOB_MAX and 0.0 <= self.nu <= 0.5):
            return None
        return kalker_coefficients(aob, self.nu)

    def fastsim_guess(self, xi: float, eta: float, phi: float) -> FloatArray:
        """Kalker's simplified theory on this grid with ``flexibilities``: the march from the
        leading edge projected on |tau| <= g (the initial guess of solve_rolling)."""
        Lx, Ly, Lp = self.flexibilities
        X, Y = self.grid.mesh()
        dx = self.grid.dx
        Wx = (xi / Lx - phi * Y / Lp) * dx + self.pressure_slip[0] / Lx
        Wy = (eta / Ly + phi * X / Lp) * dx + self.pressure_slip[1] / Ly
        # columns as contiguous rows, the load masked by the contact once: the march
        # runs a few ufuncs per column (it is a tenth of an 11 x 11 first solve)
        # (both components of a column at once: a handful of ufuncs per column)
        Cf = self.contact.T.astype(float)
        WT = np.stack([Wx.T * Cf, Wy.T * Cf], axis=1)  # (nx, 2, ny)
        gT = np.ascontiguousarray(self.g.T)
        # projection on |tau| <= g: the factor g/max(|tau|, g) (1 within the bound;
        # outside the contact 0/tiny, the traction there being zero anyway)
        gbound = np.maximum(gT, np.finfo(float).tiny)
        # the columns from the last with contact back to the first (the others carry
        # no traction; the run starts from zero beyond the last)
        cols = np.flatnonzero(Cf.any(axis=1))
        tauT = np.zeros((self.grid.nx, 2, self.grid.ny))
        t = np.zeros((2, self.grid.ny))
        for i in range(cols[-1], cols[0] - 1, -1) if len(cols) else ():
            t = np.add(t, WT[i], out=tauT[i])  # each column in place in the result
            t *= Cf[i]  # zero outside the contact: the run restarts
            t *= gT[i] / np.maximum(np.hypot(t[0], t[1]), gbound[i])
        return np.ascontiguousarray(tauT.transpose(1, 2, 0))


def march(q: FloatArray, H: BoolArray) -> FloatArray:
    """Tractions from differences within each run of H: tau_I = q_I + tau_I+ (I+ in H),
    summed from the leading (+x) end of the run. q: (..., ny, nx)."""
    return march_plan(H)(q)


def march_plan(H: BoolArray) -> Callable[[FloatArray], FloatArray]:
    """``march`` over the runs of H as a function of q alone: the index arithmetic that
    locates each run's leading end is done once (a preconditioner marches over the same
    H in every GMRES iteration)."""
    ny, nx = H.shape
    # in the reversed rows, the last element outside H at or before each position: the
    # running sum there is what precedes the run (none: the run starts at the edge)
    outside = ~H[:, ::-1]
    last = np.maximum.accumulate(np.where(outside, np.arange(nx), -1), axis=-1)
    has = last >= 0
    at = (np.arange(ny)[:, None] * nx + np.maximum(last, 0)).ravel()

    def run(q: FloatArray) -> FloatArray:
        cs = np.cumsum(np.where(H, q, 0.0)[..., ::-1], axis=-1)
        base = cs.reshape(*cs.shape[:-2], ny * nx)[..., at].reshape(cs.shape)
        return np.where(H, (cs - np.where(has, base, 0.0))[..., ::-1], 0.0)

    return run


def solve_rolling(
    patch: RollingPatch,
    xi: float,
    eta: float = 0.0,
    phi: float = 0.0,
    tau0: FloatArray | None = None,
    tol: float = NEWTON_TOL,
    maxit: int = NEWTON_MAXIT,
    method: str = "auto",
) -> RollingSolution:
    """Steady rolling for the creepages xi = vx/Vx, eta = vy/Vx (-) and spin phi =
    Omega_z/Vx (1/m), rolling in +x. tau0: initial traction (2, ny, nx) (warm start).

    method: "iterative" (GMRES Newton steps, below), "direct" (dense Newton steps,
    direct.py), "auto": with the FFT backend direct for contacts of at most
    DIRECT_MAX_ELEMENTS elements on the patch's first direct solve and of at most
    DIRECT_REPEAT_MAX_ELEMENTS on later ones (the measured costs of one and of many
    solves), iterative otherwise.

    Initial guess without tau0: nested iteration where the patch has a coarse level
    (``RollingPatch.coarse``; ellipse_patch grids of 64 and more elements per side): the
    same problem solved on the coarse level (recursively, to NESTED_TOL) and prolonged by
    ``prolong``; otherwise, and should a coarse solve fail, the calibrated FASTSIM march
    (``RollingPatch.fastsim_guess``). Either way Newton then solves this grid's problem
    to ``tol``: the converged solution does not depend on the guess beyond ``tol``."""
    instance("patch", patch, RollingPatch, "a RollingPatch")
    xi, eta, phi = finite("xi", xi), finite("eta", eta), finite("phi", phi)
    tol = positive("tol", tol)
    maxit = count("maxit", maxit, 1)
    if tau0 is not None:
        tau0 = array("tau0", tau0, (2, *patch.grid.shape))
    one_of("method", method, ("auto", "iterative", "direct"))
    scale = creepage_scale(patch, xi, eta, phi)
    if scale < 1.0:  # far into full slip: solved at SATURATION_RATIO, the slip scaled back
        sol = solve_rolling(patch, xi * scale, eta * scale, phi * scale, tau0, tol, maxit, method)
        return replace(sol, S=sol.S / scale)
    if scale > 1.0:  # within full adhesion, linear: solved at ADHESION_RATIO, scaled back
        # from the cold start (tau0 is dropped: a warm start scaled up would overshoot
        # the bound, and the cold start of a full-adhesion solve converges at once)
        sol = solve_rolling(patch, xi * scale, eta * scale, phi * scale, None, tol, maxit, method)
        return replace(
            sol, tau=sol.tau / scale, S=sol.S / scale,
            Tx=sol.Tx / scale, Ty=sol.Ty / scale, Mz=sol.Mz / scale,
        )  # fmt: skip
    C = patch.contact
    W = patch.rhs(xi, eta, phi)
    auto_direct = patch.direct and (patch.solves == 0 or int(C.sum()) <= DIRECT_REPEAT_MAX_ELEMENTS)
    if method == "direct" or (method == "auto" and auto_direct):
        guess = tau0 if tau0 is not None else patch.fastsim_guess(xi, eta, phi)
        tau, S, slip, newton = direct.newton(patch, W, guess, tol, maxit, SMALL_TRACTION)
        return _solution(patch, tau, S, slip, newton, 0, ())
    levels: tuple[tuple[int, int, int, int], ...] = ()
    tau = None
    if tau0 is not None:
        tau = np.where(C, tau0, 0.0)
    elif patch.coarse is not None:
        cp = patch.coarse
        try:
            cs = solve_rolling(cp, xi, eta, phi, tol=max(tol, NESTED_TOL), maxit=maxit)
        except RuntimeError:
            pass
        else:
            tau = prolong(cs.tau, cp, patch)
            gc = cp.grid
            levels = cs.levels or ((gc.nx, gc.ny, cs.newton_iterations, cs.gmres_iterations),)
    if tau is None:
        tau = patch.fastsim_guess(xi, eta, phi)
    tau, S, slip, _, _, newton, inner = coulomb_newton(
        patch,
        W,
        tau,
        tol,
        maxit,
        "steady rolling",
        slip_block=SLIP_BLOCK_RATIO,
        oversolve=OVERSOLVE,
        right=True,
        traction_scale=SMALL_TRACTION,
    )
    if levels:
        levels = (*levels, (patch.grid.nx, patch.grid.ny, newton, inner))
    return _solution(patch, tau, S, slip, newton, inner, levels)


def creepage_scale(patch: RollingPatch, xi: float, eta: float, phi: float) -> float:
    """The factor the creepages (xi, eta, phi) are solved at: below 1 where a bound of
    the rigid slip per element, (|xi| + |eta| + |phi| R) dx (R: the largest |x|, |y| of
    the grid), exceeds SATURATION_RATIO times the elastic displacement of the traction
    bound, max g/r (it brings the bound down to that ratio: full slip along the rigid
    slip); above 1 where it is below ADHESION_RATIO times it and not zero, without the
    pressure coupling (it brings it up to that ratio: full adhesion, linear in the
    creepages); 1 otherwise."""
    unit, spin = patch.creepage_units
    ratio = abs(xi) * unit + abs(eta) * unit + abs(phi) * spin  # inf where it overflows
    if ratio > SATURATION_RATIO:
        # the terms over SATURATION_RATIO before the sum: finite for every finite
        # creepage unless the contact's own scales are extreme (InputError then)
        u, w = unit / SATURATION_RATIO, spin / SATURATION_RATIO
        over = abs(xi) * u + abs(eta) * u + abs(phi) * w
        if not math.isfinite(over):
            raise InputError(
                "xi, eta, phi", (xi, eta, phi),
                f"creepages of a rigid slip within double range on this contact "
                f"(below {SATURATION_RATIO * 1.7e308 / unit:.3g} in sum)",
            )  # fmt: skip
        return 1.0 / over
    if patch.kappa != 0.0:  # the pressure slip does not scale with the creepages
        return 1.0
    return ADHESION_RATIO / ratio if 0.0 < ratio < ADHESION_RATIO else 1.0


class Continuation:
    """Initial guesses for a sequence of solves on one patch (a creep curve, a line of a
    table, a bisection along a ray): the secant predictor from the last two converged
    solutions,

        z = z_2 + s (z_2 - z_1),   s = (w - w_2).(w_2 - w_1)/|w_2 - w_1|^2,   tau = Proj(z),

    of the fixed-point variable z = tau + r S (tau = Proj_{|.| <= g}(z) at a solution;
    z is smooth where tau has a kink at the stick-slip boundary, so its secant also
    predicts the moving boundary: 5-10 % fewer Newton steps than the secant of tau on
    the railway curves), w = (xi, eta, phi l) the creepages (l: the radius of a circle
    of the contact's area, so that spin weighs like creepage); with one solution on the
    ray from zero through w, z_2 scaled by |w|/|w_2| and projected; otherwise none (the
    cold start of ``solve_rolling``). The predictor is only the initial guess: the
    solution is converged to the same tolerance from it, so it agrees with a cold
    start's within that tolerance (tests/test_halfspace_curve.py). Should Newton fail
    from the prediction, the point is solved cold."""

    def __init__(self, patch: RollingPatch) -> None:
        self.patch = patch
        C = patch.contact
        self.length = math.sqrt(float(C.sum()) * patch.grid.area / math.pi)
        self.points: list[tuple[FloatArray, FloatArray]] = []

    def guess(self, xi: float, eta: float, phi: float) -> FloatArray | None:
        """The predicted traction (2, ny, nx) (Pa) at (xi, eta, phi), or None."""
        if not self.points:
            return None
        # far into full slip (creepage_scale) the products may overflow: the
        # prediction is then not finite and _bounded answers None (a cold start)
        with np.errstate(over="ignore", invalid="ignore"):
            w = np.array([xi, eta, phi * self.length])
            w2, z2 = self.points[-1]
            step = float(np.linalg.norm(w - w2))
            if len(self.points) == 2:
                w1, z1 = self.points[0]
                d = w2 - w1
                dd = float(d @ d)
                if dd > 0.0:
                    s = float((w - w2) @ d) / dd
                    off = float(np.linalg.norm(w - w2 - s * d))
                    if off <= CONTINUATION_LINE * step and abs(s) <= CONTINUATION_REACH:
                        return self._bounded(z2 + s * (z2 - z1))
            ww = float(w2 @ w2)
            if ww > 0.0:
                s = float(w @ w2) / ww
                if s > 0.0 and float(np.linalg.norm(w - s * w2)) <= CONTINUATION_LINE * step:
                    return self._bounded(s * z2)
            return None

    def _bounded(self, tau: FloatArray) -> FloatArray | None:
        """tau (a predicted z) projected on |tau| <= g, zero off the contact; None where
        the prediction is not finite (it overflowed: the cold start instead)."""
        if not np.all(np.isfinite(tau)):
            return None
        g = self.patch.g
        mag = np.hypot(tau[0], tau[1])
        f = np.where(mag > g, g / np.where(mag > 0.0, mag, 1.0), 1.0)
        return np.where(self.patch.contact, tau * f, 0.0)

    def solve(
        self, xi: float, eta: float = 0.0, phi: float = 0.0, tol: float = NEWTON_TOL
    ) -> RollingSolution:
        """``solve_rolling`` from the predicted traction (cold without one, or should
        Newton fail from it); the solution joins the history."""
        tau0 = self.guess(xi, eta, phi)
        try:
            sol = solve_rolling(self.patch, xi, eta, phi, tau0=tau0, tol=tol)
        except RuntimeError:
            if tau0 is None:
                raise
            sol = solve_rolling(self.patch, xi, eta, phi, tol=tol)
        w = np.array([xi, eta, phi * self.length])
        with np.errstate(over="ignore", invalid="ignore"):
            z = np.where(self.patch.contact, sol.tau + self.patch.r * sol.S, 0.0)
        if not (np.all(np.isfinite(z)) and np.all(np.isfinite(w))):
            # far into full slip (creepage_scale), z beyond double range: no
            # history, the next point starts cold
            self.points = []
        elif self.points and float(np.linalg.norm(w - self.points[-1][0])) == 0.0:
            self.points[-1] = (w, z)  # a repeated point: no line through it
        else:
            self.points = [*self.points[-1:], (w, z)]
        return sol


def _solution(
    patch: RollingPatch,
    tau: FloatArray,
    S: FloatArray,
    slip: BoolArray,
    newton: int,
    inner: int,
    levels: tuple[tuple[int, int, int, int], ...],
) -> RollingSolution:
    """The RollingSolution of a converged traction: forces and masks on the contact."""
    C = patch.contact
    tau = np.where(C, tau, 0.0)
    X, Y = patch.grid.mesh()
    dA = patch.grid.area
    Tx = float(tau[0].sum() * dA)
    Ty = float(tau[1].sum() * dA)
    Mz = float(np.sum(X * tau[1] - Y * tau[0]) * dA)
    adhesion = C & ~slip
    return RollingSolution(patch.grid, tau, S, C, adhesion, slip, Tx, Ty, Mz, newton, inner, levels)


def coulomb_newton(
    patch: Any,
    W: FloatArray,
    tau: FloatArray,
    tol: float,
    maxit: int,
    what: str,
    slip_block: float = 0.0,
    oversolve: float = 0.0,
    error: type[RuntimeError] = RuntimeError,
    right: bool = False,
    traction_scale: float = 0.0,
) -> tuple[FloatArray, FloatArray, BoolArray, FloatArray, FloatArray, int, int]:
    """F(tau) = tau - Proj_{|.| <= g}(tau + r S) = 0 with S = W - K tau on the contact of
    ``patch`` (a RollingPatch, or the transient's step patch), by the semismooth Newton
    method of the module docstring from tau (2, ny, nx) (Pa): GMRES directions with the
    block preconditioner (``_newton_direction``, ``slip_block``), forcing terms after
    Eisenstat & Walker, no smaller than ``oversolve`` times the reduction still needed
    (0: no such bound), backtracking on |F|. Converged when max |F| <= tol max g, or
    with ``traction_scale`` > 0 when max |F| <= tol min(max g, traction_scale max
    |tau|) (``convergence_bound``); after ``maxit`` steps raises ``error`` naming
    ``what``. Returns tau, S, slip, z, |z| and the Newton and GMRES iteration counts.

    right: GMRES preconditioned on the right (``krylov.gmres_right``: the forcing terms
    bound the true residual, and neither the initial nor the final residual costs an
    operator application), which also returns K dtau, so that the slip of a trial
    step is S - step K dtau without applying K again; otherwise scipy's gmres (left
    preconditioning) and the slip of each trial from K tau."""
    C, g, r = patch.contact, patch.g, patch.r
    gmax = float(g.max())

    def residual(t: FloatArray, S: FloatArray | None = None):
        if S is None:
            S = np.where(C, W - patch.apply_K(t), 0.0)
        z = t + r * S
        nz = np.hypot(z[0], z[1])
        slip = C & (nz > g)
        scale = np.where(slip, g / np.where(slip, nz, 1.0), 1.0)
        F = np.where(C, t - z * scale, 0.0)
        return F, S, z, nz, slip

    F, S, z, nz, slip = residual(tau)
    fnorm = float(np.sqrt(np.sum(F * F)))
    newton = inner = 0
    prev_ratio = GMRES_RTOL_MAX
    while float(np.abs(F).max()) > (bound := convergence_bound(tau, tol, gmax, traction_scale)):
        if newton >= maxit:
            raise error(
                f"{what}: no convergence in {maxit} Newton steps "
                f"(max |F| / max g = {float(np.abs(F).max()) / gmax:.3g})"
            )
        newton += 1
        rtol = min(GMRES_RTOL_MAX, max(prev_ratio, GMRES_RTOL_MIN))
        rtol = min(GMRES_RTOL_MAX, max(rtol, oversolve * bound / float(np.abs(F).max())))
        dtau, its, Kd = _newton_direction(
            patch, tau, F, S, z, nz, slip, rtol, slip_block=slip_block, right=right
        )
        inner += its
        step = 1.0
        while True:
            trial = tau + step * dtau
            S_t = None if Kd is None else np.where(C, S - step * Kd, 0.0)
            F_t, S_t, z_t, nz_t, slip_t = residual(trial, S_t)
            fn_t = float(np.sqrt(np.sum(F_t * F_t)))
            if fn_t <= (1.0 - ARMIJO * step) * fnorm or step <= MIN_STEP:
                break
            step *= 0.5
        prev_ratio = fn_t / fnorm if fnorm > 0 else GMRES_RTOL_MIN
        tau, F, S, z, nz, slip = trial, F_t, S_t, z_t, nz_t, slip_t
        fnorm = fn_t
    return tau, S, slip, z, nz, newton, inner


def convergence_bound(tau: FloatArray, tol: float, gmax: float, traction_scale: float) -> float:
    """The Newton convergence bound on max |F| (Pa): tol max g, or with traction_scale > 0
    tol min(max g, traction_scale max |tau|) (SMALL_TRACTION: tractions far below their
    bound converged relative to themselves)."""
    if traction_scale <= 0.0:
        return tol * gmax
    return tol * min(gmax, traction_scale * float(np.abs(tau).max(initial=0.0)))


def prolong(tau_c: FloatArray, coarse: RollingPatch, fine: RollingPatch) -> FloatArray:
    """A coarse-level traction (2, nyc, nxc) (Pa) as the initial guess on the fine level.

    The traction relative to its bound, f = tau/g (|f| <= 1; |f| = 1 in slip, f along
    the slip), is extended from the coarse contact to its surroundings by the nearest
    contact element, interpolated bilinearly from the coarse to the fine element centres
    (constant beyond the outermost centres), projected on |f| <= 1 and multiplied by the
    fine bound g. The slip area and the slip directions thus carry over, and the guess
    satisfies |tau| <= g on the fine contact (zero outside it).
    """
    C = coarse.contact
    tau = np.zeros((2, *fine.grid.shape))
    if not C.any() or not fine.contact.any():
        return tau
    f = np.where(C, tau_c / np.where(C, coarse.g, 1.0), 0.0)
    gc, gf = coarse.grid, fine.grid
    if not C.all():
        _, (jj, ii) = ndi.distance_transform_edt(~C, sampling=(gc.dy, gc.dx), return_indices=True)
        f = f[:, jj, ii]
    Px = _interpolation_matrix(gc.x, gf.x)
    Py = _interpolation_matrix(gc.y, gf.y)
    f = np.stack([Py @ f[0] @ Px.T, Py @ f[1] @ Px.T])
    mag = np.hypot(f[0], f[1])
    f = f / np.maximum(mag, 1.0)
    return np.where(fine.contact, fine.g * f, 0.0)


def _interpolation_matrix(xc: FloatArray, xf: FloatArray) -> FloatArray:
    """Linear interpolation from the points xc to xf (constant beyond the ends):
    (len(xf), len(xc))."""
    return np.stack([np.interp(xf, xc, e) for e in np.eye(len(xc))], axis=1)


def _newton_direction(
    patch: RollingPatch,
    tau: FloatArray,
    F: FloatArray,
    S: FloatArray,
    z: FloatArray,
    nz: FloatArray,
    slip: BoolArray,
    rtol: float,
    slip_block: float = 0.0,
    right: bool = False,
) -> tuple[FloatArray, int, FloatArray | None]:
    """The semismooth Newton step dtau for F(tau) = 0 (module docstring) by GMRES with
    the block preconditioner; returns dtau (2, ny, nx), the GMRES iteration count and,
    with ``right`` (``krylov.gmres_right``), K dtau (None otherwise).

    slip_block: slip elements whose local coefficient (|z|/g - 1)/r is below slip_block
    times their diagonal of K (those next to the adhesion area, where |z| is close to g)
    join the adhesion block of the preconditioner with their tangential component; the
    others are preconditioned by their diagonal (0: all of them, as transient.py uses it).
    """
    C, g, r = patch.contact, patch.g, patch.r
    H = C & ~slip
    Sl = slip
    zhat = np.where(Sl, z / np.where(Sl, nz, 1.0), 0.0)
    that = np.stack([-zhat[1], zhat[0]])
    ratio = np.where(Sl, nz / np.where(C, g, 1.0), 1.0)
    cS = (ratio - 1.0) / r
    # slip elements: the component along z is local, dtau_n = -F_n
    dn = np.where(Sl, -(F[0] * zhat[0] + F[1] * zhat[1]), 0.0)
    tau_t = tau[0] * that[0] + tau[1] * that[1]
    nH = int(H.sum())
    Kn = patch.apply_K(dn * zhat)
    bH = (S - Kn)[:, H]
    bS = (-(ratio * tau_t) / r - (that[0] * Kn[0] + that[1] * Kn[1]))[Sl]
    b = np.concatenate([bH[0], bH[1], bS])
    shape = (2, *patch.grid.shape)
    # flat indices of the unknowns' elements: gathers and scatters by index are several
    # times cheaper than by boolean mask, and they run twice per GMRES iteration
    n = H.size
    iH, iS = np.flatnonzero(H), np.flatnonzero(Sl)
    iHH = np.concatenate([iH, n + iH])  # both components of the adhesion elements
    t_S, cS_S = that.reshape(2, n)[:, iS], cS.ravel()[iS]

    def to_field(x: FloatArray) -> FloatArray:
        d = np.zeros(2 * n)
        d[iHH] = x[: 2 * nH]
        d = d.reshape(2, n)
        d[:, iS] += x[2 * nH :] * t_S
        return d.reshape(shape)

    def matvec(x: FloatArray) -> FloatArray:
        Kd = patch.apply_K(to_field(x)).reshape(2, n)
        out_S = cS_S * x[2 * nH :] + (t_S[0] * Kd[0, iS] + t_S[1] * Kd[1, iS])
        return np.concatenate([Kd.ravel()[iHH], out_S])

    unknowns = _Unknowns(H, Sl, that, cS, iH, iS)
    psolve = _block_psolve(patch, unknowns, slip_block)
    if not right:
        x, its = gmres(matvec, b, psolve, rtol, GMRES_RESTART, GMRES_MAXIT)
        return to_field(x) + dn * zhat, its, None

    def matvec_field(x: FloatArray) -> tuple[FloatArray, FloatArray]:
        # the rows of the unknowns and, as side product, the whole field K d
        Kd = patch.apply_K(to_field(x)).reshape(2, n)
        out_S = cS_S * x[2 * nH :] + (t_S[0] * Kd[0, iS] + t_S[1] * Kd[1, iS])
        return np.concatenate([Kd.ravel()[iHH], out_S]), Kd

    x, its, Kx = gmres_right(matvec_field, b, psolve, rtol, GMRES_RESTART, GMRES_MAXIT)
    Kd = Kn if Kx is None else Kx.reshape(shape) + Kn
    return to_field(x) + dn * zhat, its, Kd


@dataclass(frozen=True)
class _Unknowns:
    """The unknowns of a Newton system (``_newton_direction``): the adhesion elements H
    (both components; flat indices iH) and the slip elements Sl (the component along
    the tangent ``that`` (2, ny, nx); flat indices iS) with their local coefficient cS."""

    H: BoolArray
    Sl: BoolArray
    that: FloatArray
    cS: FloatArray
    iH: NDArray[np.int_]
    iS: NDArray[np.int_]


def _block_psolve(
    patch: RollingPatch, u: _Unknowns, slip_block: float
) -> Callable[[FloatArray], FloatArray]:
    """The block preconditioner of the Newton system (``_newton_direction``)."""
    H, Sl, that, cS, iH, iS = u.H, u.Sl, u.that, u.cS, u.iH, u.iS
    n = H.size
    nH = len(iH)
    iHH = np.concatenate([iH, n + iH])
    t_S = that.reshape(2, n)[:, iS]
    shape = (2, *patch.grid.shape)
    Ktt = that[0] ** 2 * patch.diag[0] + that[1] ** 2 * patch.diag[1]
    dS = np.where(Sl, cS + Ktt, 1.0)
    # slip elements preconditioned with the adhesion block (see the docstring)
    Sb = Sl & (cS < slip_block * Ktt)
    B = H | Sb
    clo = patch._closure(B)
    precondition = patch._precondition_adhesion
    if isinstance(patch, RollingPatch):  # the march over B planned once for all iterations
        precondition = partial(precondition, marcher=march_plan(B))

    in_block = Sb.ravel()[iS]  # of the slip unknowns, those in the block
    iSb, vS_b = iS[in_block], np.flatnonzero(in_block)
    t_Sb, dS_S = t_S[:, in_block], dS.ravel()[iS]

    def psolve(v: FloatArray) -> FloatArray:
        # block preconditioner: the adhesion block (with the slip elements Sb, tangential
        # component) inverted approximately (FFT deconvolution, closure, march), the
        # other slip rows by their diagonal
        vs = v[2 * nH :]
        res = np.zeros(2 * n)
        res[iHH] = v[: 2 * nH]
        res = res.reshape(2, n)
        res[:, iSb] = vs[vS_b] * t_Sb
        d = precondition(res.reshape(shape), B, clo).reshape(2, n)
        xs = np.where(in_block, t_S[0] * d[0, iS] + t_S[1] * d[1, iS], vs / dS_S)
        return np.concatenate([d.ravel()[iHH], xs])

    return psolve


def ellipse_patch(
    a1: float,
    a2: float,
    n: int,
    pressure,
    mu: float,
    G: float,
    nu: float,
    k: float = 0.0,
    kappa: float = 0.0,
    ny: int | None = None,
    backend: str = "fft",
    P: float | None = None,
) -> RollingPatch:
    """Patch on an ellipse x^2/a1^2 + y^2/a2^2 < 1 with n x ny elements (ny = n default).

    The potential contact area is the ellipse's bounding box with one element to spare
    on each side along x, the rolling direction (the difference du/dx of an element at
    the leading edge reads the element ahead of it), and none along y (a row beyond the
    ellipse carries no traction and changes no solution): dx = 2 a1/(n - 2), dy = 2
    a2/ny, the box (n - 2) x ny elements, its edges element edges. pressure(X, Y) gives
    p (Pa) at the centres, scaled so that sum p dA = P (N) when P is given (the load
    invariant); theta follows from the exact leading edge l(y) = a1 (1 - y^2/a2^2)^(1/2).
    """
    a1, a2 = positive("a1", a1), positive("a2", a2)
    if not callable(pressure):
        raise InputError("pressure", type(pressure).__name__, "a function p(X, Y) (Pa)")
    n = count("n", n, 4)
    ny = n if ny is None else count("ny", ny, 1)
    dx = 2.0 * a1 / (n - 2)
    dy = 2.0 * a2 / ny
    grid = Grid(n, ny, dx, dy, -a1 - dx, -a2)
    X, Y = grid.mesh()
    inside = (X / a1) ** 2 + (Y / a2) ** 2 < 1.0
    p = np.where(inside, pressure(X, Y), 0.0)
    p = np.where(p > 0.0, p, 0.0)
    if P is not None:
        p = normalise_load(p, grid, positive("P", P))
    ell = a1 * np.sqrt(np.maximum(1.0 - (Y / a2) ** 2, 0.0))
    theta = np.clip((ell - X) / dx, np.finfo(float).tiny, 1.0)
    theta = np.where(inside, theta, 1.0)
    coarsen = None
    if n // 2 >= NESTED_MIN_N and ny // 2 >= NESTED_MIN_N:

        def coarsen(bk: str) -> RollingPatch:
            return ellipse_patch(a1, a2, n // 2, pressure, mu, G, nu, k, kappa, ny // 2, bk, P)

    return RollingPatch(
        grid, p, mu, G, nu, k, theta, kappa, backend, ellipse=(a1, a2), coarsen=coarsen
    )


def normalise_load(p: FloatArray, grid: Grid, P: float) -> FloatArray:
    """Scale a sampled pressure so that sum p dA = P exactly (the load invariant)."""
    tot = float(p.sum()) * grid.area
    if tot <= 0.0 or not math.isfinite(tot):
        raise InputError("p", "sum <= 0", "a positive pressure on the grid")
    return p * (P / tot)
