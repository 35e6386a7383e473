"""Kalker's transient rolling on the elastic half-space (with layers), and the body on it.

Field equation (Spector & Batra 1995, Eq. 2, i.e. Eq. 15 with its time derivative).
With u = u^s - u^b the relative surface displacement, u = A tau + k tau (Eqs. 6-7:
A the Cerruti operator of both half-spaces, k = kb + ks the layers), and the material
moving at -Vx through the contact-fixed frame, the slip is

    s = v - Du/Dt,        D/Dt = d/dt - Vx d/dx,        v = (vx - Omega_z y, vy + Omega_z x)

(v the rigid slip of Eq. 3). Over a time step h along a material path this reads

    S = s h = W - (U^(n+1) - U'),    W = int v dt,    U' = U^n of the same material,

and the Coulomb conditions (4)-(5) hold for S (adhesion: S = 0, |tau| <= mu p; slip:
tau = mu p S/|S|). This is Kalker's transient rolling in contact-fixed coordinates
(Kalker 1970, J. Appl. Mech. 37, 677; Kalker 1990, Three-Dimensional Elastic Bodies
in Rolling Contact, Ch. 5; CONTACT's "T = 1" problems), in which the previous
displacement field is carried along with the material. Without the time derivative
(steady state) it is the problem of ``rolling.solve_rolling``.

Discretisation. Elements of the half-space solver (rectangles dx x dy with constant
traction, dx = 2 a1/(n - 2) as on the steady solver's n x ny grid) on a *material*
lattice of n + 2 columns (two to spare on each side of the contact): the columns move
with the material, x_j = -X + (j + theta) dx, X = a1 + 2 dx.
A step that rolls ds moves theta by -ds/dx and re-indexes whole columns (the material
of column j + 1 is in column j after rolling one cell). Because the influence
coefficients depend only on offsets, U^n = (A + k) tau^n evaluated on the lattice is
the displacement of the same material after the shift: U' is the previous displacement
field shifted by the rolled distance, exactly. The usual choice, rolling one element
per step (ds = dx, theta constant), is Kalker's scheme on the fixed grid; its
stationary state is exactly the steady solution of ``solve_rolling`` on the same grid
(module docs/halfspace.md, "Transient rolling"). Other steps (a master's communication
step, a speed that changes) move theta and the contact ellipse over the lattice; the
pressure is sampled at the element centres and scaled to sum p dA = P every step.

Each step is one static contact problem on the elements in contact,

    (A + k + k_e) tau = W + U' - S,   Coulomb conditions for (tau, S),

solved by the semismooth Newton method and preconditioned GMRES of ``rolling``
(``rolling._newton_direction``). Material that entered the contact during the step
has had its layer loaded only since it crossed the leading edge: k_e = k (|ds|/d - 1)
for it, d its distance from the edge (the k/theta rule of the steady solver, which it
reproduces for ds = dx).

Coupling with the body (Eqs. 8-11, Eq. 9 as Iy dOmega_y/dt = +Rx Tx + My_ex): one
implicit solve per step with the weights theta at the step's end and 1 - theta at its
start on the whole system, W = h (theta v^(n+1) + (1 - theta) v^n) and

    M (Vx^(n+1) - Vx^n) = h [Fx_theta - (theta Tx^(n+1) + (1 - theta) Tx^n)],
    m (vx^(n+1) - vx^n) = h [F_theta - (theta Tx^(n+1) + (1 - theta) Tx^n)],

F = A2 Fx - A1 My/Rx, m = M/(1 + eta). theta = 1/2 (the trapezoidal rule, second
order, no numerical damping of the body's oscillation on the contact) while that
oscillation is resolved, z = h (K/m)^(1/2) <= 2 (K the contact's stiffness in full
adhesion), and 1 - 1/z beyond, which tends to backward Euler (L-stable; eta = inf, m = 0,
makes Eq. 20 algebraic and theta = 1). With constant kinematics W = v h for any
theta, so the stationary state is the steady solution whatever the weights.
Eliminating Tx gives Vx^(n+1) in vx^(n+1) explicitly, and the slip equation is one
increasing function of vx^(n+1) (the map from W to the traction is monotone, tau =
(K + N_C)^(-1)(W + U')): a Newton iteration with the exact tangent dTx/dvx (one linear
solve on the converged active set) inside the bracket its iterates build. The lattice
moves by the distance predicted with the last step's slip rate; the difference to the
distance the body actually rolls (of order h^2 d(vx)/dt A2 per step) is carried to the
next step, so it never accumulates. Vy/Vx and Omega_z/Vx are held (``Lateral``
ratios); dynamic Vy and Omega_z (Eqs. 10-11) are not implemented for this stepper.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import root

from .._validate import InputError, count, finite, positive
from ..dynamics.body import ROLLING_STRAIGHT, Body, Lateral, Loads
from ..dynamics.body_state import ContactOutputs
from ..dynamics.integrator import V_SCALE_FLOOR, LoadInput
from ..dynamics.solvers import StageSolveError, bracketed_newton
from ..dynamics.transient_body import TransientBody
from ..laws.thin_layer import LayerContact, TractionField
from .contact import HalfSpaceContact
from .influence import BlockConvolution, Grid, tangential_operator
from .krylov import gmres
from .rolling import (
    GMRES_MAXIT,
    GMRES_RESTART,
    SATURATION_RATIO,
    RollingPatch,
    coulomb_newton,
    normalise_load,
    solve_rolling,
)

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

# Elements along the rolling direction (the contact length 2 a1 spans n - 2 of them)
# and across (ny); the steady solver's 32 x 32 has about 1 % error in the force
# (docs/halfspace.md), 24 x 24 about 1.5 %.
DEFAULT_N = 24
MIN_N = 6
MIN_NY = 2
# Newton tolerance of the contact problem of a step: max |F| <= FIELD_TOL max(mu p).
# Tighter than the steady solver's 1e-7 because the transient starts from small
# tractions (the first step from rest loads the layer by v h/k, about 1e-3 mu p0).
FIELD_TOL = 1e-10
NEWTON_MAXIT = 60
# shift_for_force: the largest force residual accepted (of mu P).
SHIFT_FORCE_TOL = 1e-7
# Relative GMRES tolerance of the tangent solve dtau/dvx (its error only slows the
# outer Newton iteration, which is safeguarded by its bracket).
TANGENT_RTOL = 1e-8
# Outer (slip velocity) iteration: relative tolerance on vx in units of its scale, and
# the iteration cap (typically 2 to 4 iterations).
OUTER_RTOL = 1e-11
MAX_OUTER = 100
# Columns to spare on each side of the contact, and the most cells a step may roll (the
# material in the contact after a step must have been on the lattice before it). Two
# let a step of one cell at a speed that grows within the step go without splitting it:
# split steps move the lattice offset by half cells, and the force's ripple with the
# offset (docs/halfspace.md) then feeds back on the speed.
SPARE = 2
MAX_CELLS_PER_STEP = 2.0
# Rounding allowance on the cells rolled in a step (a step of exactly one cell).
CELL_SLACK = 1e-9
# The outer solve gives up when no bracket has formed this many velocity scales from the
# start (the scale is the slip that carries the contact to full slip within one step).
MAX_SEARCH = 1e6
# Time weight: the trapezoidal rule while z = h (K/m)^(1/2) <= THETA_Z (the oscillation
# of the slip mass on the contact's stiffness K resolved by at least pi steps per
# period), 1 - 1/z beyond (tending to backward Euler, L-stable). docs/halfspace.md.
THETA_Z = 2.0


# ---- the contact problem of one step ---------------------------------------------------
class StepPatch:
    """The static contact problem of one step, in the interface of ``RollingPatch``
    that ``rolling._newton_direction`` uses: K tau = (A + k) tau + k_e tau on the
    elements in contact (no traction differences: the rolling enters through U').

    op: the lattice's operator A + k; contact (ny, nx): elements in contact; g (ny, nx):
    the traction bound mu p (Pa); k_extra (ny, nx): k_e of the elements that entered
    during the step (m/Pa).
    """

    def __init__(
        self, op: BlockConvolution, contact: BoolArray, g: FloatArray, k_extra: FloatArray
    ) -> None:
        self.op = op
        self.grid = op.grid
        self.contact = contact
        self.g = g
        self.k_extra = k_extra
        d0 = op.self_coefficient
        self.diag = np.stack([d0[0, 0] + k_extra, d0[1, 0] + k_extra])
        # scaling r of the fixed point, per element: the inverse diagonal of K. A single r
        # (the steady solver's) cycles where an element that just entered has k_e >> k
        # (its cap is tiny and its diagonal large): measured, Newton stalled at 7e-4 g.
        self.r = 1.0 / self.diag[0]
        self._scale = float(d0[0, 0]) / (float(d0[0, 0]) + k_extra)

    def apply_K(self, tau: FloatArray) -> FloatArray:
        """(A + k + k_e) tau (m), tau (2, ny, nx) (Pa) zero outside the contact."""
        return self.op.apply(tau) + self.k_extra * tau

    def _closure(self, H: BoolArray) -> None:
        return None

    def _precondition_adhesion(self, res: FloatArray, H: BoolArray, clo: None) -> FloatArray:
        """Approximate inverse of K on the adhesion elements H: the deconvolution of
        A + k on the padded torus, scaled for k_e (exact for the layer alone)."""
        q = self.op.solve_periodic(np.where(H, res, 0.0)) * self._scale
        return np.where(H, q, 0.0)


@dataclass(frozen=True)
class CoulombSolution:
    """Solution of one step's contact problem.

    tau (2, ny, nx) (Pa); S (2, ny, nx) the slip over the step (m); slip, contact masks;
    z, nz: the fixed-point variable tau + r S and its norm (for the tangent); Newton and
    GMRES iteration counts.
    """

    tau: FloatArray
    S: FloatArray
    contact: BoolArray
    slip: BoolArray
    z: FloatArray
    nz: FloatArray
    newton_iterations: int
    gmres_iterations: int


def solve_coulomb(
    patch: StepPatch, b: FloatArray, tau0: FloatArray, tol: float = FIELD_TOL
) -> CoulombSolution:
    """K tau = b - S with the Coulomb conditions (4)-(5) on the contact of ``patch``:
    F(tau) = tau - Proj_{|.| <= g}(tau + r S) = 0, S = b - K tau, by the semismooth
    Newton method of ``rolling.solve_rolling`` (same direction, GMRES forcing and
    backtracking), from tau0. b (2, ny, nx) (m)."""
    C = patch.contact
    if not np.any(C):
        z = np.zeros_like(b)
        return CoulombSolution(z, z.copy(), C, np.zeros_like(C), z.copy(), z[0].copy(), 0, 0)
    b = np.where(C, b, 0.0)
    # far into full slip (rolling.SATURATION_RATIO; the rigid slip of a step at 1e300
    # m/s overflowed tau + r S and gave zero tractions): b brought down to the ratio, the
    # slip scaled back; z and nz stay the scaled problem's (the tangent's coefficients
    # (|z|/g - 1)/r then 1e20 instead of more: a zero response either way)
    elastic = SATURATION_RATIO * float((patch.g / patch.r)[C].max())
    ratio = float(np.abs(b).max()) / elastic if elastic > 0.0 else 0.0
    scale = 1.0 / ratio if ratio > 1.0 else 1.0
    tau, S, slip, z, nz, newton, inner = coulomb_newton(
        patch,
        b * scale,
        np.where(C, tau0, 0.0),
        tol,
        NEWTON_MAXIT,
        "transient contact problem",
        error=StageSolveError,
    )
    tau = np.where(C, tau, 0.0)
    return CoulombSolution(tau, S / scale, C, slip, z, nz, newton, inner)


def linear_response(
    patch: StepPatch, sol: CoulombSolution, d: FloatArray, rtol: float = TANGENT_RTOL
) -> tuple[FloatArray, int]:
    """dtau for a change d (2, ny, nx) (m) of the right-hand side b at the converged
    active set of ``sol``: the tangent of the Coulomb solution map. Adhesion elements:
    K dtau = d; slip elements: dtau along the tangent t of the traction circle with
    (|z|/g - 1)/r dtau_t + (K dtau)_t = d_t (the linearised projection). Returns dtau
    and the GMRES iteration count."""
    C, g, r = patch.contact, patch.g, patch.r
    Sl = sol.slip
    H = C & ~Sl
    zhat = np.where(Sl, sol.z / np.where(Sl, sol.nz, 1.0), 0.0)
    that = np.stack([-zhat[1], zhat[0]])
    cS = (np.where(Sl, sol.nz / np.where(C, g, 1.0), 1.0) - 1.0) / r
    nH, nS = int(H.sum()), int(Sl.sum())
    shape = d.shape

    def to_field(x: FloatArray) -> FloatArray:
        out = np.zeros(shape)
        out[0][H] = x[:nH]
        out[1][H] = x[nH : 2 * nH]
        out[:, Sl] += x[2 * nH :] * that[:, Sl]
        return out

    def matvec(x: FloatArray) -> FloatArray:
        Kd = patch.apply_K(to_field(x))
        out_S = cS[Sl] * x[2 * nH :] + (that[0] * Kd[0] + that[1] * Kd[1])[Sl]
        return np.concatenate([Kd[0][H], Kd[1][H], out_S])

    dS = (cS + that[0] ** 2 * patch.diag[0] + that[1] ** 2 * patch.diag[1])[Sl]

    def psolve(v: FloatArray) -> FloatArray:
        res = np.zeros(shape)
        res[0][H] = v[:nH]
        res[1][H] = v[nH : 2 * nH]
        dH = patch._precondition_adhesion(res, H, None)
        return np.concatenate([dH[0][H], dH[1][H], v[2 * nH :] / dS])

    N = 2 * nH + nS
    if N == 0:
        return np.zeros(shape), 0
    b = np.concatenate([d[0][H], d[1][H], (that[0] * d[0] + that[1] * d[1])[Sl]])
    x, its = gmres(matvec, b, psolve, rtol, GMRES_RESTART, GMRES_MAXIT)
    return to_field(x), its


# ---- the field -----------------------------------------------------------------------
@dataclass(frozen=True)
class StepGeometry:
    """The lattice after rolling ``ds`` (m) from the committed field (the material moves
    by -ds). Column j holds the material of the committed column j - ``shift``.

    theta: lattice offset after the step; x (nx,): column positions (m); p (ny, nx):
    pressure (Pa) scaled to sum p dA = P; contact: p > 0; entered: in contact now, not at
    the start of the step; k_extra (m/Pa): k_e of the entered elements; U_prev (2, ny,
    nx): the displacement (A + k) tau^n of the same material (m); tau_prev: its traction
    (Pa), zero outside the contact (the initial guess)."""

    ds: float
    shift: int
    theta: float
    x: FloatArray
    p: FloatArray
    contact: BoolArray
    entered: BoolArray
    k_extra: FloatArray
    U_prev: FloatArray
    tau_prev: FloatArray
    patch: StepPatch


@dataclass(frozen=True)
class StepResult:
    """A solved step: the geometry, the Coulomb solution and the resultant (Tx, Ty, Mz)
    (N, N, N m) of the traction the body exerts on the substrate (Eq. 8 convention)."""

    geometry: StepGeometry
    solution: CoulombSolution
    Tx: float
    Ty: float
    Mz: float


def _gather(a: NDArray, idx: NDArray[np.intp], fill: float | bool = 0.0) -> NDArray:
    """a[..., idx] along the last axis with ``fill`` where idx is outside."""
    n = a.shape[-1]
    valid = (idx >= 0) & (idx < n)
    out = a[..., np.clip(idx, 0, n - 1)]
    return np.where(valid, out, fill)


def contact_pressure(contact: HalfSpaceContact | LayerContact) -> Callable:
    """p(x, y) (Pa) of the contact: Hertz (half-space) or Eq. (33) (Winkler layers)."""
    if isinstance(contact, HalfSpaceContact):
        return contact.hertz.pressure
    return contact.pressure


class HalfSpaceField:
    """The transient traction field of Kalker's transient rolling on a material lattice.

    ``contact``: a ``HalfSpaceContact`` (Hertz pressure, Kalker's combined G and nu, layers
    k = kb + ks; the pressure coupling must vanish: quasi-identical bodies or
    ``coupling=False``) or a ``LayerContact`` (the thin-layer contact of Eqs. 31-34:
    parabolic pressure, layers k) on half-spaces of combined shear modulus ``G`` (Pa)
    and Poisson's ratio ``nu`` (-), which must then be given. ``n`` elements along x (the
    contact length spans n - 2), ``ny`` across (default n). ``tol``: Newton tolerance of
    the step problems (of max mu p). ``scale_load``: scale the pressure sampled at the
    element centres to sum p dA = P (default, the load invariant: full slip gives mu P
    exactly); False keeps the sampled values (the caps of ``transient.LayerField``).
    The field starts at rest.
    """

    def __init__(
        self,
        contact: HalfSpaceContact | LayerContact,
        n: int = DEFAULT_N,
        ny: int | None = None,
        G: float | None = None,
        nu: float | None = None,
        tol: float = FIELD_TOL,
        scale_load: bool = True,
    ) -> None:
        if isinstance(contact, HalfSpaceContact):
            if G is not None or nu is not None:
                raise InputError("G, nu", (G, nu), "None for a HalfSpaceContact (its materials)")
            e = contact.elastic
            if contact.coupling and e.kappa != 0.0:
                raise InputError(
                    "coupling",
                    f"kappa = {e.kappa:.3g}",
                    "off (coupling=False) or quasi-identical bodies: the transient field "
                    "does not carry the pressure coupling B(p)",
                )
            G, nu = e.G, e.nu
        elif isinstance(contact, LayerContact):
            if G is None or nu is None:
                raise InputError("G, nu", (G, nu), "given for a LayerContact (the half-spaces)")
            G = positive("G", G)
            nu = finite("nu", nu)
            if not -1.0 < nu <= 0.5:
                raise InputError("nu", nu, "in (-1, 0.5]")
        else:
            raise InputError(
                "contact", type(contact).__name__, "a HalfSpaceContact or LayerContact"
            )
        n = count("n", n, MIN_N)
        ny = n if ny is None else count("ny", ny, MIN_NY)
        self.contact = contact
        self.G, self.nu = float(G), float(nu)
        self.tol = positive("tol", tol)
        self.scale_load = bool(scale_load)
        self.dx = 2.0 * contact.a1 / (n - 2)
        self.dy = 2.0 * contact.a2 / ny
        self.X = contact.a1 + SPARE * self.dx  # the lattice spans (-X, X) along x
        self.y = -contact.a2 + (np.arange(ny) + 0.5) * self.dy
        self.theta = 0.5
        self.direction = 0.0  # sign of the last step's ds (+1: the material moves to -x)
        nx = n - 2 + 2 * SPARE
        self.tau = np.zeros((2, ny, nx))
        self.S = np.zeros((2, ny, nx))
        self.slip = np.zeros((ny, nx), dtype=bool)
        self._operators: dict[tuple[int, int], BlockConvolution] = {}
        self._refresh()

    # ---- geometry ----------------------------------------------------------------------
    @property
    def nx(self) -> int:
        return self.tau.shape[2]

    @property
    def ny(self) -> int:
        return self.tau.shape[1]

    @property
    def P(self) -> float:
        return self.contact.P

    @property
    def k(self) -> float:
        """Layer compliance kb + ks (m/Pa)."""
        return self.contact.k

    @property
    def area(self) -> float:
        """Element area dx dy (m^2)."""
        return self.dx * self.dy

    @property
    def op(self) -> BlockConvolution:
        """A + k on the lattice (cached per lattice shape)."""
        key = (self.ny, self.nx)
        if key not in self._operators:
            grid = Grid(
                self.nx, self.ny, self.dx, self.dy, -self.X, float(self.y[0]) - 0.5 * self.dy
            )
            self._operators[key] = tangential_operator(grid, self.G, self.nu, self.k)
        return self._operators[key]

    def positions(self, theta: float | None = None) -> FloatArray:
        """Column positions x_j = -X + (j + theta) dx (m), (nx,)."""
        theta = self.theta if theta is None else theta
        return -self.X + (np.arange(self.nx) + theta) * self.dx

    def _pressure(self, x: FloatArray) -> FloatArray:
        """Pressure at the element centres (Pa), scaled so that sum p dA = P exactly."""
        X, Y = np.meshgrid(x, self.y)
        p = np.maximum(np.asarray(contact_pressure(self.contact)(X, Y), float), 0.0)
        if not self.scale_load:
            return p
        grid = Grid(self.nx, self.ny, self.dx, self.dy, 0.0, 0.0)
        return normalise_load(p, grid, self.P)

    def _refresh(self) -> None:
        """Pressure and contact of the committed lattice."""
        self.p = self._pressure(self.positions())
        self.in_contact = self.p > 0.0

    @cached_property
    def _ell(self) -> FloatArray:
        """Half length l(y) of the contact ellipse at the rows (m), (ny,)."""
        return self.contact.a1 * np.sqrt(np.maximum(1.0 - (self.y / self.contact.a2) ** 2, 0.0))

    def geometry(self, ds: float) -> StepGeometry:
        """The step that rolls ds (m): re-indexing, contact, entered material, U'."""
        ds = finite("ds", ds)
        if abs(ds) > (MAX_CELLS_PER_STEP + CELL_SLACK) * self.dx:
            raise InputError("ds", ds, f"at most {MAX_CELLS_PER_STEP} cells ({self.dx:.6g} m each)")
        u = self.theta - ds / self.dx
        shift = math.floor(u)
        theta = u - shift
        x = self.positions(theta)
        src = np.arange(self.nx) - shift
        p = self._pressure(x)
        C = p > 0.0
        if np.any(C & ~((src >= 0) & (src < self.nx))[None, :]):
            raise InputError("ds", ds, "a step that keeps the contact inside the lattice")
        was = _gather(self.in_contact, src, False)
        entered = C & ~was
        d_in = self._ell[:, None] - math.copysign(1.0, ds) * x[None, :]
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = abs(ds) / np.maximum(d_in, np.finfo(float).tiny)
        k_extra = np.where(entered & (ds != 0.0), self.k * np.maximum(ratio - 1.0, 0.0), 0.0)
        U_prev = _gather(self.op.apply(self.tau), src)
        tau_prev = np.where(C, _gather(self.tau, src), 0.0)
        patch = StepPatch(self.op, C, self.contact.mu * p, k_extra)
        return StepGeometry(ds, shift, theta, x, p, C, entered, k_extra, U_prev, tau_prev, patch)

    def rigid_slip(self, geom: StepGeometry, vx: float, vy: float, phi: float) -> FloatArray:
        """v of Eq. (3) at the element centres after the step (m/s), (2, ny, nx)."""
        X, Y = np.meshgrid(geom.x, self.y)
        return np.stack([vx - phi * Y, vy + phi * X])

    def solve(
        self, geom: StepGeometry, W: FloatArray, tau0: FloatArray | None = None
    ) -> StepResult:
        """The traction after the step for the rigid-slip integral W = int v dt (m),
        (2, ny, nx); tau0: initial guess (default: the previous traction)."""
        b = W + geom.U_prev
        sol = solve_coulomb(geom.patch, b, geom.tau_prev if tau0 is None else tau0, self.tol)
        return StepResult(geom, sol, *self._resultant(geom.x, sol.tau))

    def _resultant(self, x: FloatArray, tau: FloatArray) -> tuple[float, float, float]:
        X, Y = np.meshgrid(x, self.y)
        dA = self.area
        Tx = float(tau[0].sum() * dA)
        Ty = float(tau[1].sum() * dA)
        Mz = float(np.sum(X * tau[1] - Y * tau[0]) * dA)
        return Tx, Ty, Mz

    def commit(self, res: StepResult) -> None:
        """Make a solved step the committed field."""
        g = res.geometry
        self.theta = g.theta
        self.direction = float(np.sign(g.ds)) if g.ds != 0.0 else self.direction
        self.tau = res.solution.tau
        self.S = res.solution.S
        self.slip = res.solution.slip.copy()
        self.p = g.p
        self.in_contact = g.contact

    # ---- prescribed kinematics -----------------------------------------------------------
    def roll(self, h: float, vx: float, vy: float, Vx: float, phi: float = 0.0) -> StepResult:
        """One step of h (s) at constant rigid slip (vx, vy) (m/s), spin phi = Omega_z
        (rad/s) and speed Vx (m/s): the transient contact problem with prescribed
        kinematics (Kalker 1970). Rolls Vx h, at most MAX_CELLS_PER_STEP cells."""
        h = positive("h", h)
        for name, val in (("vx", vx), ("vy", vy), ("Vx", Vx), ("phi", phi)):
            finite(name, val)
        geom = self.geometry(Vx * h)
        res = self.solve(geom, h * self.rigid_slip(geom, vx, vy, phi))
        self.commit(res)
        return res

    def set_shift(self, delta_x: float, delta_y: float = 0.0) -> StepResult:
        """Replace the field by the one after a static tangential shift (delta_x,
        delta_y) (m) of the body against the substrate from rest, at Vx = 0
        (Cattaneo-Mindlin): one step with W = delta and no rolling."""
        dxs, dys = finite("delta_x", delta_x), finite("delta_y", delta_y)
        self.tau = np.zeros_like(self.tau)
        geom = self.geometry(0.0)
        W = np.stack([np.full(geom.p.shape, dxs), np.full(geom.p.shape, dys)])
        res = self.solve(geom, W)
        self.commit(res)
        return res

    def shift_for_force(self, Fx: float, Fy: float = 0.0) -> tuple[float, float, StepResult]:
        """Cattaneo at a given tangential force: the static shift (delta_x, delta_y) (m)
        from rest whose field carries (Tx, Ty) = (Fx, Fy) (N), set as by ``set_shift``.
        scipy.optimize.root from the adhesion stiffness's shift; |F| < mu P. A force
        it does not reach within SHIFT_FORCE_TOL of mu P answers InputError naming it,
        with the closest force reached."""
        Fx, Fy = finite("Fx", Fx), finite("Fy", Fy)
        muP = self.contact.mu * self.P
        if math.hypot(Fx, Fy) >= muP:
            raise InputError("Fx, Fy", (Fx, Fy), f"of magnitude below mu P = {muP:.6g} N")
        k = self.adhesion_stiffness()
        scale = muP / k

        def residual(u: FloatArray) -> FloatArray:
            res = self.set_shift(float(u[0]) * scale, float(u[1]) * scale)
            return np.array([res.Tx - Fx, res.Ty - Fy]) / muP

        u = root(residual, np.array([Fx, Fy]) / muP, method="hybr", options={"xtol": 1e-10}).x
        dx, dy = float(u[0]) * scale, float(u[1]) * scale
        res = self.set_shift(dx, dy)  # the field at the solution
        miss = max(abs(res.Tx - Fx), abs(res.Ty - Fy)) / muP
        if miss > SHIFT_FORCE_TOL:
            raise InputError(
                "Fx, Fy",
                (Fx, Fy),
                f"attainable by a static shift (closest: {res.Tx:.6g}, {res.Ty:.6g} N, "
                f"{miss:.3g} of mu P off)",
            )
        return dx, dy, res

    def steady_patch(self) -> RollingPatch:
        """The steady-rolling problem (``rolling.RollingPatch``) on the committed lattice:
        same elements, pressure and layers (leading fractions from the ellipse)."""
        x = self.positions()
        grid = Grid(
            self.nx,
            self.ny,
            self.dx,
            self.dy,
            x[0] - 0.5 * self.dx,
            float(self.y[0]) - 0.5 * self.dy,
        )
        X, _ = grid.mesh()
        theta = np.clip((self._ell[:, None] - X) / self.dx, np.finfo(float).tiny, 1.0)
        return RollingPatch(
            grid,
            self.p,
            self.contact.mu,
            self.G,
            self.nu,
            self.k,
            np.where(self.in_contact, theta, 1.0),
            operator=self.op,
        )

    def set_steady(self, xi: float, eta: float, phi: float) -> None:
        """Replace the field by the steady rolling solution (rolling in +x) for creepages
        xi, eta (-) and spin phi = Omega_z/Vx (1/m) on the committed lattice: the
        stationary state of steps of one cell."""
        sol = solve_rolling(self.steady_patch(), xi, eta, phi)
        self.tau = np.where(self.in_contact, sol.tau, 0.0)
        self.S = sol.S
        self.slip = sol.slip & self.in_contact
        self.direction = 1.0

    # ---- read-out ------------------------------------------------------------------------
    def resultant(self) -> tuple[float, float, float]:
        """(Tx, Ty, Mz) of the committed field (N, N, N m)."""
        return self._resultant(self.positions(), np.where(self.in_contact, self.tau, 0.0))

    def summary(self) -> dict[str, float]:
        """Adhesion fraction (-), slip-area centroid (m; 0 without slip), peak |tau| (Pa)."""
        C = self.in_contact
        n_c = int(C.sum())
        sl = self.slip & C
        n_s = int(sl.sum())
        if n_s:
            X, Y = np.meshgrid(self.positions(), self.y)
            cx, cy = float(X[sl].mean()), float(Y[sl].mean())
        else:
            cx = cy = 0.0
        peak = float(np.max(np.hypot(self.tau[0], self.tau[1]) * C, initial=0.0))
        return {
            "adhesion": (n_c - n_s) / n_c if n_c else 0.0,
            "slip_centroid_x": cx,
            "slip_centroid_y": cy,
            "tau_peak": peak,
        }

    def traction_field(self) -> TractionField:
        """The committed field in the record of ``LayerContact.traction`` (weights dA)."""
        x = self.positions()
        C = self.in_contact
        return TractionField(
            x=x,
            y=self.y.copy(),
            tau_x=np.where(C, self.tau[0], 0.0),
            tau_y=np.where(C, self.tau[1], 0.0),
            p=self.p.copy(),
            inside=C.copy(),
            slip=(self.slip & C).copy(),
            la=self._adhesion_boundary(x),
            weights=np.where(C, self.area, 0.0),
        )

    def _adhesion_boundary(self, x: FloatArray) -> FloatArray:
        """Rear end of the adhesion zone that starts at the leading edge, per row (m)."""
        forward = self.direction >= 0.0
        la = np.zeros(self.ny)
        for i in range(self.ny):
            js = np.nonzero(self.in_contact[i])[0]
            if js.size == 0:
                continue
            js = js[::-1] if forward else js
            lead = self._ell[i] if forward else -self._ell[i]
            sl = self.slip[i, js]
            if sl[0]:
                la[i] = lead
            elif not sl.any():
                la[i] = -lead
            else:
                first = int(np.argmax(sl))
                la[i] = 0.5 * (x[js[first]] + x[js[first - 1]])
        return la

    def arrays(self) -> dict[str, FloatArray]:
        """The present field as plain arrays (``TractionField.arrays``: for
        ``numpy.savez``)."""
        return self.traction_field().arrays()

    def displacement(self) -> FloatArray:
        """U = (A + k) tau of the committed field (m), (2, ny, nx)."""
        return self.op.apply(np.where(self.in_contact, self.tau, 0.0))

    def elastic_energy(self) -> float:
        """Energy stored by the tangential traction, (1/2) sum tau . U dA (J)."""
        tau = np.where(self.in_contact, self.tau, 0.0)
        return 0.5 * float(np.sum(tau * self.op.apply(tau))) * self.area

    def adhesion_stiffness(self) -> float:
        """Tangential stiffness of the contact in full adhesion (N/m): Tx per uniform
        static shift (the slope of Cattaneo's curve at zero), on the lattice at theta = 1/2
        (a function of the load and the grid only, not of the state)."""
        x = self.positions(0.5)
        p = self._pressure(x)
        C = p > 0.0
        patch = StepPatch(self.op, C, np.full(p.shape, np.inf), np.zeros(p.shape))
        W = np.zeros((2, self.ny, self.nx))
        W[0] = np.where(C, 1.0, 0.0)
        z = np.zeros_like(W)
        sol = CoulombSolution(z, z, C, np.zeros_like(C), z, z[0], 0, 0)
        dtau, _ = linear_response(patch, sol, W, rtol=1e-10)
        return float(dtau[0].sum()) * self.area

    # ---- load and state ------------------------------------------------------------------
    def set_load(self, P: float) -> None:
        """New normal load P (N): the contact ellipse and pressure follow (Hertz or Eq. 34)
        on the same lattice spacing; the lattice grows by unstressed columns and rows if
        the contact outgrows it (exact). Material outside the new contact is released at
        the next step."""
        self.contact = self.contact.with_load(positive("P", P))
        self.__dict__.pop("_ell", None)
        a1, a2 = self.contact.a1, self.contact.a2
        grow_x = max(0, math.ceil((a1 + SPARE * self.dx - self.X) / self.dx - 1e-12))
        grow_y = max(0, math.ceil((a2 - (-float(self.y[0]) + 0.5 * self.dy)) / self.dy - 1e-12))
        if grow_x or grow_y:
            pad = ((0, 0), (grow_y, grow_y), (grow_x, grow_x))
            self.tau = np.pad(self.tau, pad)
            self.S = np.pad(self.S, pad)
            self.slip = np.pad(self.slip, pad[1:])
            self.X += grow_x * self.dx
            y0 = float(self.y[0]) - grow_y * self.dy
            self.y = y0 + np.arange(self.ny) * self.dy
            self.__dict__.pop("_ell", None)
        self._refresh()

    def state(self) -> tuple:
        """Everything that evolves (copies): restore with ``set_state``."""
        return (
            self.theta,
            self.direction,
            self.tau.copy(),
            self.S.copy(),
            self.slip.copy(),
            self.X,
            self.y.copy(),
            self.contact.P,
        )

    def set_state(self, s: tuple) -> None:
        theta, direction, tau, S, slip, X, y, P = s
        self.contact = self.contact.with_load(P)
        self.theta, self.direction, self.X = float(theta), float(direction), float(X)
        self.tau, self.S = np.array(tau, float), np.array(S, float)
        self.slip, self.y = np.array(slip, bool), np.array(y, float)
        self.__dict__.pop("_ell", None)
        self._refresh()


# ---- the body on the field -----------------------------------------------------------------
class TransientHalfSpaceBody(TransientBody):
    """The rolling body of Eqs. (8)-(9) on Kalker's transient half-space field.

    RollingBody's interface (advance, set_load, outputs, snapshot/restore) with the
    traction field as part of the state, plus ``traction_field``, ``field_arrays``,
    ``set_shift`` (Cattaneo start), ``start_steady``, ``substeps_for`` and ``cell_time``.
    ``contact``, ``n``, ``ny``, ``G``, ``nu``: the field's (``HalfSpaceField``). Vy/Vx and
    Omega_z/Vx are held at the ratios of ``lateral`` (Eqs. 10-11 are not integrated by
    this stepper). Each step rolls at most two elements; ``advance`` splits its
    substeps further where needed.
    """

    def __init__(
        self,
        contact: HalfSpaceContact | LayerContact,
        body: Body,
        lateral: Lateral = ROLLING_STRAIGHT,
        Vx0: float = 0.0,
        Omega_y0: float = 0.0,
        Vy0: float = 0.0,
        Omega_z0: float = 0.0,
        t0: float = 0.0,
        n: int = DEFAULT_N,
        ny: int | None = None,
        G: float | None = None,
        nu: float | None = None,
    ) -> None:
        if not isinstance(body, Body):
            raise InputError("body", type(body).__name__, "a Body")
        if lateral.dynamic_vy or lateral.dynamic_spin:
            raise InputError(
                "lateral",
                lateral,
                "held ratios vy_ratio and spin_ratio (Eqs. 10-11 are not integrated on the "
                "transient half-space field)",
            )
        super().__init__(body, lateral, Vx0, Omega_y0, Vy0, Omega_z0, t0)
        self.field = HalfSpaceField(contact, n, ny, G, nu)
        # contact impulse int T dt of the scheme since t0 (N s, N s, N m s)
        self.impulse = np.zeros(3)
        # distance the body has rolled beyond the lattice (m): carried to the next step
        self.lag = 0.0
        # last step's counts: outer iterations, Newton iterations, GMRES iterations
        self.counts = (0, 0, 0)
        self._dv = 0.0  # last step's dvx/dt (m/s^2): the predictor of the slip solve
        self.out = self._outputs_now()

    # ---- public ------------------------------------------------------------------------
    @property
    def law(self) -> HalfSpaceContact | LayerContact:
        return self.field.contact

    @cached_property
    def stiffness(self) -> float:
        """Tangential stiffness of the contact in full adhesion (N/m), see
        ``HalfSpaceField.adhesion_stiffness``; cached per load."""
        return self.field.adhesion_stiffness()

    def start_steady(self) -> None:
        """Replace the field by the steady rolling field of the present rigid slip: the
        stationary state of steps of one element (``rolling.solve_rolling``)."""
        if self.Vx == 0.0:
            raise InputError("Vx", self.Vx, "!= 0 (no steady rolling field at standstill)")
        aV = abs(self.Vx)
        if self.Vx < 0.0:
            raise InputError("Vx", self.Vx, "> 0 for start_steady")
        self.field.set_steady(self.vx / aV, self.vy / aV, self.Omega_z / aV)
        self.out = self._outputs_now()

    def snapshot(self) -> tuple:
        """The whole internal state, field included: restore(snapshot()) is exact."""
        return (
            self.y.copy(),
            self.t,
            self.out,
            self.impulse.copy(),
            self.lag,
            self._dv,
            self.field.state(),
        )

    def restore(self, snap: tuple) -> None:
        y, t, out, impulse, lag, dv, fstate = snap
        self.y, self.t, self.out = np.array(y, float), float(t), out
        self.impulse, self.lag, self._dv = np.array(impulse, float), float(lag), float(dv)
        P_before = self.field.P
        self.field.set_state(fstate)
        if self.field.P != P_before:
            self.__dict__.pop("stiffness", None)

    def set_load(self, P: float) -> None:
        """Change the normal load P (N): the contact follows, the field is kept."""
        self.field.set_load(P)
        self.__dict__.pop("stiffness", None)

    def advance(self, h: float, loads: LoadInput, substeps: int = 1) -> None:
        """Advance by h (s) in at least ``substeps`` equal steps, each rolling at most two
        element, under the load history (constant: zero-order hold; callable: sampled at
        the step ends). On error the state is left unchanged."""
        h = positive("h", h)
        if isinstance(substeps, bool) or not isinstance(substeps, (int, np.integer)):
            raise InputError("substeps", substeps, "an integer >= 1")
        if substeps < 1:
            raise InputError("substeps", substeps, ">= 1")
        load_at = loads if callable(loads) else (lambda _t, L=loads: L)
        saved = self.snapshot()
        try:
            t0 = self.t
            dt = h / substeps
            for k in range(substeps):
                self._interval(t0 + k * dt, dt, load_at)
            self.t = t0 + h
        except Exception:
            self.restore(saved)
            raise

    # ---- stepping ------------------------------------------------------------------------
    def _interval(self, t_n: float, h: float, load_at: Callable[[float], Loads]) -> None:
        """Advance from t_n by h in as many equal steps as keep each within
        MAX_CELLS_PER_STEP cells."""
        most = MAX_CELLS_PER_STEP * self.field.dx
        parts = max(1, math.ceil(abs(self._predicted_ds(t_n, h, load_at)) / most - 1e-9))
        dt = h / parts
        for k in range(parts):
            tk = t_n + k * dt
            if abs(self._predicted_ds(tk, dt, load_at)) > most * (1.0 + CELL_SLACK):
                self._interval(tk, dt, load_at)  # the speed grew: split this step again
            else:
                self._step(tk, dt, load_at)
            self.t = tk + dt

    def _drive(self, L: Loads) -> float:
        """A1 (Fx_ex + My_ex/Rx) (N): the force that accelerates Vx once T is eliminated."""
        b = self.body
        return b.A1 * (L.Fx_ex + L.My_ex / b.Rx)

    def _target(self, L: Loads) -> float:
        """A2 Fx_ex - A1 My_ex/Rx (N): the force of Eq. (26)."""
        return self.body.tx_demand(L.Fx_ex, L.My_ex)

    def theta_weight(self, h: float) -> float:
        """Weight of the step's end in the time integration (-): 1/2 (the trapezoidal
        rule, second order) while the oscillation of the slip mass on the contact's
        stiffness is resolved, z = h (K/m)^(1/2) <= 2, else 1 - 1/z, which tends to
        backward Euler (L-stable) as z grows; 1 for m = 0 (eta = inf: Eq. 20 is
        algebraic)."""
        m = self.body.m_slip
        if m == 0.0:
            return 1.0
        z = h * math.sqrt(self.stiffness / m)
        return 0.5 if z <= THETA_Z else 1.0 - 1.0 / z

    def _predicted_ds(self, t_n: float, h: float, load_at) -> float:
        """Distance the step of h will roll, plus the lag: Vx^(n+1) from the exact
        relation M dVx - m dvx = h A1 (Fx + My/Rx) with dvx from the last step's slope."""
        L0, L1 = _checked(load_at(t_n)), _checked(load_at(t_n + h))
        th = self.theta_weight(h)
        drive = th * self._drive(L1) + (1.0 - th) * self._drive(L0)
        Vp = self.Vx + h * drive / self.body.M + self.body.A2 * h * self._dv
        return h * (th * Vp + (1.0 - th) * self.Vx) + self.lag

    def _step(self, t_n: float, h: float, load_at: Callable[[float], Loads]) -> None:
        """One step of the field and the body, weights theta at the end and 1 - theta at
        the start (``theta_weight``; the module docstring has the trapezoidal case)."""
        b, f = self.body, self.field
        L0, L1 = _checked(load_at(t_n)), _checked(load_at(t_n + h))
        th = self.theta_weight(h)
        Vn, vn = self.Vx, self.vx
        ry, rz = self.lateral.vy_ratio, self.lateral.spin_ratio
        T_n = self.out.Tx
        target = th * self._target(L1) + (1.0 - th) * self._target(L0)
        Vx_base = Vn + h * (th * self._drive(L1) + (1.0 - th) * self._drive(L0)) / b.M
        ds = self._predicted_ds(t_n, h, load_at)
        geom = f.geometry(ds)
        v_n = f.rigid_slip(geom, vn, ry * Vn, rz * Vn)
        X, Y = np.meshgrid(geom.x, f.y)
        dW = th * h * np.stack([1.0 - rz * b.A2 * Y, (ry + rz * X) * b.A2])  # dW/dvx
        dW = np.where(geom.contact, dW, 0.0)
        m_h = b.m_slip / h
        guess = [geom.tau_prev]
        counts = [0, 0, 0]

        def evaluate(vx: float) -> tuple[float, float, StepResult]:
            Vx = Vx_base + b.A2 * (vx - vn)
            W = h * (th * f.rigid_slip(geom, vx, ry * Vx, rz * Vx) + (1.0 - th) * v_n)
            res = f.solve(geom, W, guess[0])
            guess[0] = res.solution.tau
            dtau, its = linear_response(geom.patch, res.solution, dW)
            counts[0] += 1
            counts[1] += res.solution.newton_iterations
            counts[2] += res.solution.gmres_iterations + its
            slope = float(dtau[0].sum()) * f.area
            r = m_h * (vx - vn) + th * res.Tx + (1.0 - th) * T_n - target
            return r, m_h + th * slope, res

        vscale = self._velocity_scale(h)
        cap = self.law.mu * self.law.P

        def failure() -> str:
            return (
                f"no slip velocity satisfies the step equation (target force {target:.6g} N "
                f"against mu P = {cap:.6g} N)"
            )

        vx, res = bracketed_newton(
            evaluate, vn + h * self._dv, vscale, OUTER_RTOL, MAX_OUTER, failure, MAX_SEARCH
        )
        self._dv = (vx - vn) / h
        Vx = Vx_base + b.A2 * (vx - vn)
        f.commit(res)
        # rolled by the body minus rolled by the lattice (ds includes the previous lag)
        self.lag += h * (th * Vx + (1.0 - th) * Vn) - ds
        self.y = self._apply_ratios(np.array([Vx, vx, 0.0, 0.0]))
        T1 = np.array([res.Tx, res.Ty, res.Mz])
        T0 = np.array([T_n, self.out.Ty, self.out.Mz])
        self.impulse += h * (th * T1 + (1.0 - th) * T0)
        self.out = ContactOutputs(res.Tx, res.Ty, res.Mz, _no_adhesion(res.solution))
        self.counts = (counts[0], counts[1], counts[2])

    def _velocity_scale(self, h: float) -> float:
        """Slip velocity (m/s) that would carry the contact to full slip: mu P over the
        stiffness, per transit time plus per step (the outer solve's scale)."""
        law = self.law
        shift = law.mu * law.P / self.stiffness
        return shift * (max(abs(self.Vx), V_SCALE_FLOOR) / (2.0 * law.a1) + 1.0 / h)

    def _outputs_now(self) -> ContactOutputs:
        Tx, Ty, Mz = self.field.resultant()
        C = self.field.in_contact
        sliding = bool(np.any(C)) and not np.any(C & ~self.field.slip)
        return ContactOutputs(Tx, Ty, Mz, sliding)


def _no_adhesion(sol: CoulombSolution) -> bool:
    return bool(np.any(sol.contact)) and not np.any(sol.contact & ~sol.slip)


def _checked(L: Loads) -> Loads:
    for name, val in zip(Loads._fields, L, strict=True):
        finite(name, val)
    return L


__all__ = [
    "CoulombSolution",
    "HalfSpaceField",
    "StepGeometry",
    "StepPatch",
    "StepResult",
    "TransientHalfSpaceBody",
    "linear_response",
    "solve_coulomb",
]
