"""Transient rolling on thin layers: the traction field as a state (Section 3b).

Field equation. The layers u^b = -kb tau, u^s = ks tau (Eq. 31) put the relative
displacement u^b - u^s = -k tau, k = kb + ks, into the slip of Eq. (2). In the
contact-fixed frame the material moves at -Vx, so d/dt of Eq. (2) is the material
derivative D/Dt = d/dt - Vx d/dx and

    s = v - k D(tau)/Dt,                     v(x, y) = (vx - Omega_z y, vy + Omega_z x)

(Eq. 15 with its time-derivative term, Eq. 3 for v). Adhesion (s = 0, Eq. 4) gives
k D(tau)/Dt = v; slip (Eq. 5) gives tau = mu p s/|s|. Along a material path this is
an elastic-perfectly-plastic law: the layer is loaded at the rate v/k and the traction
is capped by the disc |tau| <= mu p(x(t)), the slip being along tau. Material enters
unstressed at the leading edge and leaves at the trailing edge, where p = 0.

Discretisation. The field lives on a *material* grid: nx columns spaced dx = 2 a1/nx
that move with the material, at x_j = -X + (j + theta) dx in the contact frame, and ny
strips at fixed y. Rolling by a distance ds moves theta by -ds/dx; whole cells are
re-indexed (material leaving the grid is dropped, material entering is unstressed).
Transport is therefore exact for any step, any Vx(t) and any communication step: a
nodal value is never interpolated, and the scheme has no numerical diffusion. The
step "set by the grid" (Vx h = dx) is the special case where theta returns to the same
value every step; it is not required.

Along each material path the load rate v/k and the cap are integrated with the same
two-stage SDIRK method as the body (Alexander's: L-stable, stiffly accurate, order 2),
the cap being imposed at each stage by the radial return (closest point projection
onto the disc, the backward-Euler treatment of the slip rule). Material that entered
the contact during the step carries the displacement v t_in/k of the time t_in since
it crossed the leading edge. The resultant uses a slip-aware quadrature (see
``LayerField._weights``), exact along the strips for the steady and Cattaneo fields.

Coupling. The field and the body (Eqs. 8-11) are advanced together and implicitly:
each stage solves the body's stage equation for the slip velocity with the force
T = int tau dA of the stage's field, so the fast oscillation of the body's effective
mass M/(1 + eta) on the layer's tangential stiffness (pi a1 a2 / k) is integrated
by an L-stable method: stable for any step, and for steps much longer than the
transit time 2 a1/Vx the result is the steady field of the end-of-step slip (the
quasistationary limit, Eq. 26). docs/transient.md has the derivation, the linear
theory of the transient and the measured durations.

The half-space version (Kalker's transient rolling with influence coefficients) can
replace ``LayerField``: the body stepper needs of a field only ``begin``, ``stage``,
``to_base``, ``commit``, ``resultant`` and the export/state methods.

Compiled path: where the kernel library is there, the field's stage, weights and summary
and, when vx is the only stage unknown under held loads, the body's whole ``advance``
run in C (contact_fmu/native/field.c through native/field.py), agreeing with this code
to rounding (tests/test_native_field.py); this code is the reference and takes every
call the C declines.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import root

from .._validate import InputError, count, finite, positive
from ..laws.thin_layer import LayerContact, TractionField
from ..native import field as native_field
from .body import ROLLING_STRAIGHT, Body, Lateral, Loads
from .body_state import ContactOutputs
from .integrator import GAMMA, V_SCALE_FLOOR, EvalBudget, LoadInput, StageSolveError
from .solvers import SOLVE_RTOL, bracketed_newton
from .transient_body import TransientBody

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

# Alexander's two-stage SDIRK (L-stable, stiffly accurate, order 2; Hairer & Wanner,
# Solving ODEs II, IV.6): c = (gamma, 1), A = [[gamma, 0], [1 - gamma, gamma]]; gamma is
# the rolling body's (integrator.GAMMA).
A21 = 1.0 - GAMMA
STAGE_C = (GAMMA, 1.0)

# Default grid: cells along the contact length 2 a1 and strips across 2 a2. The
# steady force error of such grids against Eqs. (40)-(42) is a few 1e-6 (measured,
# docs/transient.md, section 3); the transient needs the cells to resolve the fast
# oscillation (about 0.3 contact lengths per period in the example).
DEFAULT_NX = 64
DEFAULT_NY = 32
# Layouts of the strips across the contact (LayerField).
STRIP_RULES = ("sine", "uniform")
# Smallest grids accepted: fewer cells cannot represent adhesion and slip in a strip.
MIN_NX = 4
MIN_NY = 2
# Entering material: its time in the contact is d_in/|Vx| (creepage form) unless the
# stage speed is below this fraction of the step's mean speed (Vx crossing 0).
MIN_SPEED_FRACTION = 0.1
# Iterations of the scalar stage solve (Newton in a bracket; typically 3 to 5).
MAX_STAGE_ITERATIONS = 200
# The most columns one stage may roll the lattice by: beyond, the loads or the step drive
# the body past what the field resolves (and the shift leaves a C long; field.c's limit).
SHIFT_MAX = 1e9


@dataclass(frozen=True)
class StepBase:
    """The field at the start of a step, in the grid's current column indexing."""

    theta: float
    tau_x: FloatArray
    tau_y: FloatArray
    inside: BoolArray


@dataclass(frozen=True)
class StageField:
    """The field at a stage: columns shifted by ``shift`` with respect to the base.

    Column j of this stage holds the material of base column j - shift; ``x`` (nx,)
    are the column positions (m), ``weights`` (ny, nx) the quadrature weights (m^2).
    """

    theta: float
    shift: int
    ds: float
    x: FloatArray
    tau_x: FloatArray
    tau_y: FloatArray
    slip: BoolArray
    inside: BoolArray
    weights: FloatArray
    # d(int tau_x dA)/d(vx) at fixed geometry (N s/m): the tangent of the stage force
    dTx_dvx: float = 0.0
    # d(Tx, Ty, Mz)/d(vx, vy, Omega_z) at fixed geometry, (3, 3), when asked for
    jacobian: FloatArray | None = None
    # (Tx, Ty, Mz) over the field's strips, where the compiled stage computed it
    T: tuple[float, float, float] | None = None

    def resultant(self, y: FloatArray) -> tuple[float, float, float]:
        """(Tx, Ty, Mz) = int (tau_x, tau_y, x tau_y - y tau_x) dA (N, N, N m); ``y``:
        the strips of the field that made this stage."""
        if self.T is not None:
            return self.T
        w = self.weights
        Tx = float(np.sum(w * self.tau_x))
        Ty = float(np.sum(w * self.tau_y))
        wy = w * y[:, None]
        Mz = float(np.sum((w * self.x[None, :]) * self.tau_y) - np.sum(wy * self.tau_x))
        return Tx, Ty, Mz


def _gather(a: NDArray, idx: NDArray[np.intp], fill: float | bool = 0.0) -> NDArray:
    """a[:, idx] with ``fill`` where idx is outside the columns of a."""
    n = a.shape[1]
    valid = (idx >= 0) & (idx < n)
    out = a[:, np.clip(idx, 0, n - 1)]
    return np.where(valid[None, :], out, fill)


class LayerField:
    """The transient traction field of the thin-layer contact on a material grid.

    ``law`` gives the contact (a1, a2, p0, mu, k = kb + ks); ``nx`` cells along the
    contact length 2 a1, ``ny`` strips across 2 a2. The field starts at rest (tau = 0)
    with the columns at the cell centres of ``LayerContact.traction``'s grid.

    ``strips``: "sine" (default) puts the strips at y = a2 sin(phi), phi at the
    midpoints of ny equal intervals of (-pi/2, pi/2), width a2 cos(phi) dphi: the
    midpoint rule in phi integrates the square-root ends of the ellipse (Eq. 37)
    without loss of order. "uniform": the strips of ``LayerContact.traction``
    (midpoint rule in y, order 1.5 for a field that does not vanish at y = +-a2).

    ``native``: the stage, the weights and the summary run compiled (and so does
    ``TransientRollingBody.advance`` on this field where vx is its only stage unknown;
    contact_fmu/native/field.c, the same arithmetic to rounding) where the kernel
    library is there; False keeps this object and its body on the Python path, the
    reference (as CONTACT_FMU_NATIVE=0 does for all).
    """

    def __init__(
        self,
        law: LayerContact,
        nx: int = DEFAULT_NX,
        ny: int = DEFAULT_NY,
        strips: str = "sine",
    ) -> None:
        if not isinstance(law, LayerContact):
            raise InputError("law", type(law).__name__, "a LayerContact")
        nx, ny = count("nx", nx, MIN_NX), count("ny", ny, MIN_NY)
        if strips not in STRIP_RULES:
            raise InputError("strips", strips, " or ".join(f'"{r}"' for r in STRIP_RULES))
        self.law = law
        self.strips = strips
        self.dx = 2.0 * law.a1 / nx
        self.X = law.a1  # half-extent of the column lattice (m)
        self.Y = law.a2  # half-extent covered by the strips (m)
        self.y, self.dy = _strips(strips, ny, law.a2)
        self.theta = 0.5
        # sign of the distance rolled in the last step: +1 the material moves towards -x
        # (Vx > 0, leading edge at +l(y)), -1 the reverse, 0 no rolling (Vx = 0).
        self.direction = 0.0
        self.tau_x = np.zeros((ny, nx))
        self.tau_y = np.zeros((ny, nx))
        self.slip = np.zeros((ny, nx), dtype=bool)
        self.native = True
        self._update_contact()

    def __getstate__(self) -> dict:
        """Pickle and deepcopy without the compiled stage's ctypes struct (rebuilt on use)."""
        return {k: v for k, v in self.__dict__.items() if k != "_cf"}

    def _compiled(self) -> native_field.CompiledField | None:
        """field.c for this grid and law, or None (``native`` off, or no library)."""
        if not getattr(self, "native", True):  # (absent in a field pickled before it)
            return None
        c = self.__dict__.get("_cf")
        if c is not None and c.matches(self):
            return c
        lib = native_field.library()
        if lib is None:
            return None
        c = self._cf = native_field.CompiledField(lib, self, MIN_SPEED_FRACTION)
        return c

    # ---- geometry ------------------------------------------------------------------
    @property
    def nx(self) -> int:
        return self.tau_x.shape[1]

    @property
    def ny(self) -> int:
        return self.tau_x.shape[0]

    def positions(self, theta: float | None = None) -> FloatArray:
        """Column positions x_j = -X + (j + theta) dx (m), (nx,)."""
        theta = self.theta if theta is None else theta
        return -self.X + (np.arange(self.nx) + theta) * self.dx

    def _update_contact(self) -> None:
        law = self.law
        self.ell = law.a1 * np.sqrt(np.maximum(1.0 - (self.y / law.a2) ** 2, 0.0))  # Eq. (37)
        self._p_strip = law.p0 * (1.0 - (self.y / law.a2) ** 2)  # p at x = 0 (may be < 0)
        # The strips' widths scaled so that the rule integrates the pressure exactly:
        # int p dx along a strip is (4/3) p0 l^3/a1^2 (Eq. 33), and the sum over the
        # strips is P exactly for strips laid over this a2 (the sine rule), but not
        # once the load has moved the ellipse across them (a full-slip resultant
        # reached 1.008 mu P after P fell from 1000 to 10 N). Scaled, the capacity
        # sum w mu p is mu P, so abs(T) <= mu P holds for every field.
        along = (4.0 / 3.0) * law.p0 * self.ell**3 / law.a1**2
        held = float(np.dot(self.dy, along))
        self._dy_w = self.dy * (law.P / held if held > 0.0 else 1.0)

    def _geometry(self, x: FloatArray) -> tuple[BoolArray, FloatArray]:
        """inside (ny, nx) and the cap mu p (Pa) at column positions x (nx,)."""
        law = self.law
        inside = np.abs(x)[None, :] < self.ell[:, None]
        p = self._p_strip[:, None] - law.p0 * (x / law.a1)[None, :] ** 2
        cap = law.mu * np.where(inside, np.maximum(p, 0.0), 0.0)
        return inside, cap

    def _weights(
        self,
        x: FloatArray,
        inside: BoolArray,
        tau_x: FloatArray | None,
        tau_y: FloatArray | None,
        sign: float,
        slip: BoolArray | None = None,
    ) -> FloatArray:
        """Quadrature weights (m^2), (ny, nx), of the resultant int tau dA.

        Along a strip the magnitude |tau| is integrated piecewise between the nodes,
        each node's contribution taken along its own tau, with a rule for each kind
        of interval (A: adhering node, S: slipping node, |tau| = mu p):
        - A-A: trapezoid (tau linear, as in steady adhesion, Eq. 36);
        - S-S: the cap itself, int mu p dx (Eq. 5), shared equally;
        - A-S and S-A: min(L, mu p), L the adhesion profile extended from the
          adhering side (slope from its other neighbour if that one adheres, else the
          chord), so a slip zone narrower than a cell at the edge of an adhesion
          zone is integrated exactly for linear adhesion;
        - end segments to the strip ends x = +-l(y): a slipping end node, the cap;
          else at the leading edge (``sign`` > 0: +l; < 0: -l) a ramp to 0 (material
          enters unstressed), at the trailing edge (both ends when ``sign`` = 0, Vx =
          0) min(L, mu p) with L extended from the inner neighbour.
        This is exact along x for the steady field without spin and for the Cattaneo
        field; the weights depend on tau. Across strips: midpoint rule.
        ``tau_x = None``: area weights (each interval shared equally, the end
        segments to the end nodes). Compiled where the library is (field.c).
        """
        c = self._compiled()
        if c is not None:
            w = c.weights(x, inside, tau_x, tau_y, slip, sign)
            if w is not None:
                return w
        dx = self.dx
        pair = inside[:, :-1] & inside[:, 1:]
        w = np.zeros(inside.shape)
        has = inside.any(axis=1)
        rows = np.nonzero(has)[0]
        nx = inside.shape[1]
        j_lo = np.argmax(inside[rows], axis=1)
        j_hi = nx - 1 - np.argmax(inside[rows, ::-1], axis=1)
        ell = self.ell[rows]
        if tau_x is None:
            w[:, :-1] += 0.5 * dx * pair
            w[:, 1:] += 0.5 * dx * pair
            w[rows, j_lo] += x[j_lo] + ell
            w[rows, j_hi] += ell - x[j_hi]
            return w * self._dy_w[:, None]
        law = self.law
        c0 = law.mu * law.p0 / law.a1**2
        l2 = (self.ell**2)[:, None]
        m = np.hypot(tau_x, tau_y)
        sl = (np.zeros_like(inside) if slip is None else slip) & inside
        with np.errstate(divide="ignore", invalid="ignore"):
            inv_m = np.where(m > 0.0, 1.0 / m, 0.0)
        s0, s1 = sl[:, :-1], sl[:, 1:]
        aa = pair & ~s0 & ~s1
        w[:, :-1] += 0.5 * dx * aa
        w[:, 1:] += 0.5 * dx * aa
        ss = pair & s0 & s1
        cap_at = c0 * (l2 * x[None, :] - x[None, :] ** 3 / 3.0)  # antiderivative of mu p
        half_cap = np.where(ss, 0.5 * (cap_at[:, 1:] - cap_at[:, :-1]), 0.0)
        w[:, :-1] += half_cap * inv_m[:, :-1]
        w[:, 1:] += half_cap * inv_m[:, 1:]
        # transitions: adhering node a, slipping neighbour on the side sd (+1: j + 1)
        adh = inside & ~sl
        for mask, sd in ((pair & ~s0 & s1, 1), (pair & s0 & ~s1, -1)):
            i, j0 = np.nonzero(mask)
            if i.size == 0:
                continue
            a = j0 if sd > 0 else j0 + 1
            back = a - sd
            back_c = np.clip(back, 0, nx - 1)
            ok = (back >= 0) & (back < nx) & adh[i, back_c]
            slope = np.where(ok, (m[i, a] - m[i, back_c]) / dx, (m[i, a + sd] - m[i, a]) / dx)
            lo = np.minimum(x[a], x[a + sd])
            seg = _capped_linear(c0, l2[i, 0], x[a], m[i, a], sd * slope, lo, lo + dx)
            to_a = m[i, a] > 0.0
            w[i, a] += np.where(to_a, seg * inv_m[i, a], 0.0)
            w[i, a + sd] += np.where(to_a, 0.0, seg * inv_m[i, a + sd])
        # end segments
        for j, side, is_lead in ((j_lo, -1, sign < 0.0), (j_hi, 1, sign > 0.0)):
            e = ell - side * x[j]
            lo = np.where(side > 0, x[j], x[j] - e)
            mj = m[rows, j]
            cap_int = c0 * (l2[rows, 0] * (lo + e) - (lo + e) ** 3 / 3.0) - c0 * (
                l2[rows, 0] * lo - lo**3 / 3.0
            )
            inner = j - side
            inner_c = np.clip(inner, 0, nx - 1)
            ok = (inner >= 0) & (inner < nx) & adh[rows, inner_c]
            slope = np.where(ok, (mj - m[rows, inner_c]) / dx, 0.0)
            slope = np.maximum(slope, np.where(e > 0.0, -mj / e, 0.0))  # L >= 0 on the segment
            trail = _capped_linear(c0, l2[rows, 0], x[j], mj, side * slope, lo, lo + e)
            seg = np.where(sl[rows, j], cap_int, 0.5 * e * mj if is_lead else trail)
            w[rows, j] += np.where(mj > 0.0, seg * inv_m[rows, j], e)
        return w * self._dy_w[:, None]

    def set_load(self, P: float) -> None:
        """New normal load P (N): new ellipse and pressure (Eq. 34); the field is kept.

        The column spacing is kept; if the contact outgrows the lattice, unstressed
        columns are added (exact). If it outgrows the strips, the strips are laid out
        again over the new a2 and the field is carried over by linear interpolation
        across y (along the strips nothing is interpolated). Material outside the new
        contact is released (tau = 0) at the next step by the cap mu p = 0.
        """
        self.law = self.law.with_load(positive("P", P))
        grow_x = max(0, math.ceil((self.law.a1 - self.X) / self.dx - 1e-12))
        if grow_x:
            pad = ((0, 0), (grow_x, grow_x))
            self.tau_x = np.pad(self.tau_x, pad)
            self.tau_y = np.pad(self.tau_y, pad)
            self.slip = np.pad(self.slip, pad)
            self.X += grow_x * self.dx
        if self.law.a2 > self.Y:
            y_new, dy_new = _strips(self.strips, self.ny, self.law.a2)

            def remap(a: FloatArray) -> FloatArray:
                return np.array([np.interp(y_new, self.y, col, 0.0, 0.0) for col in a.T]).T

            self.tau_x, self.tau_y = remap(self.tau_x), remap(self.tau_y)
            self.slip = np.zeros_like(self.tau_x, dtype=bool)
            self.y, self.dy, self.Y = y_new, dy_new, self.law.a2
        self._update_contact()

    # ---- stepping --------------------------------------------------------------------
    def begin(self) -> StepBase:
        """The field at the start of a step."""
        inside, _ = self._geometry(self.positions())
        return StepBase(self.theta, self.tau_x, self.tau_y, inside)

    def stage(
        self,
        base: StepBase,
        tau_hat: tuple[FloatArray, FloatArray],
        ds: float,
        elapsed: float,
        h_own: float,
        vx: float,
        vy: float,
        phi: float,
        Vx: float,
        memo: dict | None = None,
        midpath: bool = False,
        jacobian: bool = False,
    ) -> StageField:
        """The field at a stage of the step.

        ``tau_hat`` (base indexing): the explicit part of the stage for material that
        was in the contact at the start of the step; ``ds`` (m): distance rolled since
        the start of the step (the material moves by -ds); ``elapsed`` (s): time since
        the start of the step; ``h_own`` (s): the stage's own weight h gamma; (vx, vy)
        rigid slip at the contact centre (m/s), phi = Omega_z (rad/s), Eq. (3); Vx
        (m/s) the rolling speed at the stage.

        Material in the contact at the start: tau = proj(tau_hat + h_own v/k). Material
        that entered since: tau = proj(v t_in/k), t_in = d_in/|Vx| the time since it
        crossed the leading edge (d_in its distance from it) at the stage's creepage
        v/Vx, so that a step longer than the transit gives the steady field of the
        stage's creepage (the quasistationary limit); where Vx vanishes at the stage,
        t_in = elapsed d_in/|ds|. proj is the radial return onto |tau| <= mu p at the
        stage position (Eqs. 4-5).
        ``memo``: a dict private to one (base, tau_hat) pair that keeps the re-indexed
        arrays between calls (a stage solve calls this at nearly the same ds).
        ``midpath``: evaluate the x-dependent part of v (spin) at the middle of each
        node's path in this stage instead of at its end (exact for one stage under
        constant kinematics, used by ``roll``). ``jacobian``: also return the tangent
        d(Tx, Ty, Mz)/d(vx, vy, Omega_z) of the stage force at fixed positions.
        Compiled where the library is (field.c, cf_field_stage; this code where it
        declines).
        """
        c = self._compiled()
        if c is not None:
            args = (ds, elapsed, h_own, vx, vy, phi, Vx)
            r = c.stage(base.theta, base.inside, *tau_hat, args, midpath, jacobian)
            if r is not None:
                theta, shift, x, tx, ty, slip, inside, w, T, dT, J = r
                return StageField(theta, shift, ds, x, tx, ty, slip, inside, w, dT, J, T)
        k = self.law.k
        u = base.theta - ds / self.dx
        if not (math.isfinite(u) and abs(math.floor(u)) <= SHIFT_MAX):  # as field.c
            raise FloatingPointError(
                f"the step would roll the traction field's lattice by more than {SHIFT_MAX:g} "
                "columns (the loads or the step drive the body beyond what the field resolves)"
            )
        shift = math.floor(u)
        theta = u - shift
        x = -self.X + (np.arange(self.nx) + theta) * self.dx
        inside, cap = self._geometry(x)
        if memo is not None and shift in memo:
            was_inside, hx, hy = memo[shift]
        else:
            src = np.arange(self.nx) - shift
            was_inside = _gather(base.inside, src, False)
            hx = _gather(tau_hat[0], src)
            hy = _gather(tau_hat[1], src)
            if memo is not None:
                memo[shift] = (was_inside, hx, hy)
        entered = inside & ~was_inside
        d_in = self.ell[:, None] - np.sign(ds) * x[None, :]  # distance from the leading edge
        # rigid slip of Eq. (3) at the nodes
        rvx = (vx - phi * self.y)[:, None]
        if midpath and phi != 0.0:
            back = 0.5 * np.sign(ds) * np.where(entered, d_in, abs(ds))
            rvy = vy + phi * (x[None, :] + back)
        else:
            rvy = vy + phi * x[None, :]
        if ds != 0.0 and np.any(entered):
            if abs(Vx) * elapsed > MIN_SPEED_FRACTION * abs(ds):
                t_in = np.maximum(d_in, 0.0) / abs(Vx)
            else:
                t_in = np.clip(elapsed * d_in / abs(ds), 0.0, elapsed)
            t_eff = np.where(entered, t_in, h_own)
            hx = np.where(entered, 0.0, hx)
            hy = np.where(entered, 0.0, hy)
        else:
            t_eff = h_own
        tx = hx + rvx * (t_eff / k)
        ty = hy + rvy * (t_eff / k)
        mag = np.hypot(tx, ty)
        slip = mag > cap
        with np.errstate(divide="ignore", invalid="ignore"):
            f = np.where(slip, cap / mag, 1.0)
            # tangent of the radial return: I in adhesion, (cap/|t|)(I - n n^T) on the cap
            nx_ = np.where(slip, tx / np.where(slip, mag, 1.0), 0.0)
            ny_ = np.where(slip, ty / np.where(slip, mag, 1.0), 0.0)
        Dxx = f * (1.0 - nx_ * nx_)
        tx, ty = tx * f, ty * f
        w = self._weights(x, inside, tx, ty, float(np.sign(ds)), slip)
        g = w * t_eff / k  # d(force of a node)/d(trial) per unit slip velocity (N s/m)
        dT = float(np.sum(g * Dxx))
        J = None
        if jacobian:
            Dxy = -f * nx_ * ny_
            Dyy = f * (1.0 - ny_ * ny_)
            X = np.broadcast_to(x[None, :], g.shape)
            Y = np.broadcast_to(self.y[:, None], g.shape)
            # columns: d/dvx -> (Dxx, Dxy); d/dvy -> (Dxy, Dyy); d/dphi -> D (-y, x)
            cols = [(Dxx, Dxy), (Dxy, Dyy), (-Y * Dxx + X * Dxy, -Y * Dxy + X * Dyy)]
            J = np.array(
                [
                    [
                        float(np.sum(g * cx)),
                        float(np.sum(g * cy)),
                        float(np.sum(g * (X * cy - Y * cx))),
                    ]
                    for cx, cy in cols
                ]
            ).T
        return StageField(theta, shift, ds, x, tx, ty, slip & inside, inside, w, dT, J)

    def to_base(self, st: StageField, base: StepBase) -> tuple[FloatArray, FloatArray]:
        """A stage's field in base indexing (material that had not entered: base value)."""
        idx = np.arange(self.nx) + st.shift
        return (
            np.where(base.inside, _gather(st.tau_x, idx), base.tau_x),
            np.where(base.inside, _gather(st.tau_y, idx), base.tau_y),
        )

    def commit(self, st: StageField) -> None:
        """Make a stage the field at the end of the step."""
        self.theta = st.theta
        self.tau_x = st.tau_x
        self.tau_y = st.tau_y
        self.slip = st.slip
        self.direction = float(np.sign(st.ds))

    def roll(self, h: float, vx: float, vy: float, Vx: float, phi: float = 0.0) -> None:
        """Advance the field alone by h (s) under constant kinematics (the transient
        contact problem with prescribed rigid slip, as in Kalker 1970).

        With v and Vx constant the load is exact along each material path: the
        material moves by Vx h and is loaded by the integral of v/k along its path (v
        at the middle of the path, Eq. 3 being linear in x), capped at the end
        position (one backward-Euler stage of the slip rule).
        """
        h = positive("h", h)
        for name, val in (("vx", vx), ("vy", vy), ("Vx", Vx), ("phi", phi)):
            finite(name, val)
        base = self.begin()
        st = self.stage(base, (base.tau_x, base.tau_y), Vx * h, h, h, vx, vy, phi, Vx, midpath=True)
        self.commit(st)

    def set_shift(self, delta_x: float, delta_y: float = 0.0) -> None:
        """The field after a static tangential shift (delta_x, delta_y) (m) of the body
        relative to the substrate at Vx = 0 from rest: tau = proj(delta/k) (Cattaneo)."""
        dxs, dys = finite("delta_x", delta_x), finite("delta_y", delta_y)
        inside, cap = self._geometry(self.positions())
        tx = np.full(inside.shape, dxs / self.law.k)
        ty = np.full(inside.shape, dys / self.law.k)
        mag = np.hypot(tx, ty)
        slip = mag > cap
        with np.errstate(divide="ignore", invalid="ignore"):
            f = np.where(slip, cap / mag, 1.0)
        self.tau_x, self.tau_y, self.slip = tx * f, ty * f, slip & inside

    # ---- read-out ----------------------------------------------------------------------
    def current(self) -> StageField:
        """The present field as a stage record (positions, weights, masks)."""
        x = self.positions()
        inside, _ = self._geometry(x)
        w = self._weights(x, inside, self.tau_x, self.tau_y, self.direction, self.slip)
        ds = self.direction  # only its sign is used by the weights
        return StageField(self.theta, 0, ds, x, self.tau_x, self.tau_y, self.slip, inside, w)

    def resultant(self) -> tuple[float, float, float]:
        """(Tx, Ty, Mz) of the present field (N, N, N m): the force used by the body."""
        return self.current().resultant(self.y)

    def traction_field(self) -> TractionField:
        """The present field on its grid, in the record of ``LayerContact.traction``.

        ``la`` is the rear end of the adhesion zone that starts at the leading edge
        (the leading edge itself where the first node slips): the transient analogue
        of l_a(y) of Eq. (38); further adhesion zones behind a slip zone (after a
        Cattaneo start, for instance) are in ``slip``.
        """
        st = self.current()
        X, Y = np.meshgrid(st.x, self.y)
        p = self.law.pressure(X, Y)
        return TractionField(
            x=st.x.copy(),
            y=self.y.copy(),
            tau_x=np.where(st.inside, st.tau_x, 0.0),
            tau_y=np.where(st.inside, st.tau_y, 0.0),
            p=p,
            inside=st.inside.copy(),
            slip=st.slip.copy(),
            la=self._adhesion_boundary(st),
            weights=st.weights.copy(),
        )

    def _adhesion_boundary(self, st: StageField) -> FloatArray:
        ell = self.ell
        la = np.empty(self.ny)
        forward = self.direction >= 0.0
        order = slice(None, None, -1) if forward else slice(None)
        for i in range(self.ny):
            js = np.nonzero(st.inside[i])[0]
            if js.size == 0:
                la[i] = 0.0
                continue
            js = js[order]
            lead = ell[i] if forward else -ell[i]
            sl = st.slip[i, js]
            if sl[0]:
                la[i] = lead
            elif not sl.any():
                la[i] = -lead
            else:
                first = int(np.argmax(sl))
                la[i] = 0.5 * (st.x[js[first]] + st.x[js[first - 1]])
        return la

    def summary(self) -> dict[str, float]:
        """Adhesion fraction (-), slip-area centroid (m; 0 without slip) and peak |tau| (Pa).

        Areas are measured with the quadrature weights: adhesion = sum of the weights
        of non-slipping nodes / sum over the contact. Compiled where the library is
        (field.c, cf_field_summary).
        """
        c = self._compiled()
        if c is not None:
            r = c.summary(self.theta, self.tau_x, self.tau_y, self.slip)
            if r is not None:
                keys = ("adhesion", "slip_centroid_x", "slip_centroid_y", "tau_peak")
                return dict(zip(keys, r, strict=True))
        st = self.current()
        w = self._weights(st.x, st.inside, None, None, 0.0)  # areas
        total = float(np.sum(w))
        ws = np.where(st.slip, w, 0.0)
        slip_area = float(np.sum(ws))
        if slip_area > 0.0:
            cx = float(np.sum(ws * st.x[None, :])) / slip_area
            cy = float(np.sum(ws * self.y[:, None])) / slip_area
        else:
            cx = cy = 0.0
        peak = float(np.max(np.hypot(st.tau_x, st.tau_y), initial=0.0))
        return {
            "adhesion": (total - slip_area) / total if total > 0.0 else 0.0,
            "slip_centroid_x": cx,
            "slip_centroid_y": cy,
            "tau_peak": peak,
        }

    def arrays(self) -> dict[str, FloatArray]:
        """The present field as plain arrays (``TractionField.arrays``: for
        ``numpy.savez``)."""
        return self.traction_field().arrays()

    # ---- state -------------------------------------------------------------------------
    def state(self) -> tuple:
        """Everything that evolves (copies): restore with ``set_state``."""
        return (
            self.theta,
            self.direction,
            self.tau_x.copy(),
            self.tau_y.copy(),
            self.slip.copy(),
            self.X,
            self.Y,
            self.y.copy(),
            self.dy.copy(),
            self.law.P,
        )

    def set_state(self, s: tuple) -> None:
        theta, direction, tx, ty, slip, X, Y, y, dy, P = s
        self.law = self.law.with_load(P)
        self.theta, self.direction = float(theta), float(direction)
        self.X, self.Y = float(X), float(Y)
        self.tau_x, self.tau_y = np.array(tx, float), np.array(ty, float)
        self.slip, self.y, self.dy = np.array(slip, bool), np.array(y, float), np.array(dy, float)
        self._update_contact()


def _capped_linear(
    c0: float,
    l2: FloatArray,
    xa: FloatArray,
    ma: FloatArray,
    bs: FloatArray,
    lo: FloatArray,
    hi: FloatArray,
) -> FloatArray:
    """int_lo^hi min(L, mu p) dx with L(x) = ma + bs (x - xa) >= 0 on [lo, hi] and
    mu p = c0 (l^2 - x^2) along a strip (Eq. 33, c0 = mu p0/a1^2), elementwise."""

    def cap_int(z):
        return c0 * (l2 * z - z**3 / 3.0)

    def lin_int(z):
        return ma * z + 0.5 * bs * (z - xa) ** 2

    # L < mu p between the roots of c0 x^2 + bs x - (c0 l^2 - ma + bs xa) = 0
    disc = bs * bs + 4.0 * c0 * (c0 * l2 - ma + bs * xa)
    sq = np.sqrt(np.maximum(disc, 0.0))
    r1 = (-bs - sq) / (2.0 * c0)
    r2 = (-bs + sq) / (2.0 * c0)
    o_lo = np.maximum(lo, r1)
    o_hi = np.maximum(np.minimum(hi, r2), o_lo)
    o_hi = np.where(disc > 0.0, o_hi, o_lo)
    below = (cap_int(o_hi) - cap_int(o_lo)) - (lin_int(o_hi) - lin_int(o_lo))
    return cap_int(hi) - cap_int(lo) - below


def _strips(rule: str, ny: int, a2: float) -> tuple[FloatArray, FloatArray]:
    """Strip centres y (m) and widths dy (m), (ny,), over (-a2, a2)."""
    if rule == "uniform":
        dy = 2.0 * a2 / ny
        return -a2 + (np.arange(ny) + 0.5) * dy, np.full(ny, dy)
    dphi = math.pi / ny
    phi = -0.5 * math.pi + (np.arange(ny) + 0.5) * dphi
    return a2 * np.sin(phi), a2 * np.cos(phi) * dphi


class TransientRollingBody(TransientBody, EvalBudget):
    """The rolling body of Eqs. (8)-(11) on the transient thin-layer field.

    The same interface as ``integrator.RollingBody`` (advance, set_load, outputs,
    snapshot/restore), with the traction field as part of the state: phase
    "transient". ``nx``, ``ny``: the field's grid (cells along 2 a1, strips across
    2 a2). Initial conditions Vx0 (m/s), Omega_y0 (rad/s), Vy0 (m/s), Omega_z0
    (rad/s); the field starts at rest (tau = 0), or after a tangential shift with
    ``set_shift``. The held ratios of ``lateral`` override Vy0 and Omega_z0.
    ``strips``: the strip layout of ``LayerField``.
    """

    def __init__(
        self,
        law: LayerContact,
        body: Body,
        lateral: Lateral = ROLLING_STRAIGHT,
        Vx0: float = 0.0,
        Omega_y0: float = 0.0,
        Vy0: float = 0.0,
        Omega_z0: float = 0.0,
        t0: float = 0.0,
        nx: int = DEFAULT_NX,
        ny: int = DEFAULT_NY,
        strips: str = "sine",
    ) -> None:
        if not isinstance(body, Body):
            raise InputError("body", type(body).__name__, "a Body")
        self.field = LayerField(law, nx, ny, strips)
        super().__init__(body, lateral, Vx0, Omega_y0, Vy0, Omega_z0, t0)
        # contact impulse int T dt of the scheme since t0 (N s, N s, N m s)
        self.impulse = np.zeros(3)
        self.out = self._outputs_now()

    # ---- public ------------------------------------------------------------------
    @property
    def law(self) -> LayerContact:
        return self.field.law

    def start_steady(self) -> None:
        """Replace the field by the steady field of the present rigid slip (Eqs. 36-38):
        the field after rolling one contact length (plus two cells) at constant
        kinematics, exact on the grid (see ``LayerField.roll``). With vx on the steady
        law for the loads, the body starts on the quasistationary state (Eq. 26)."""
        if self.Vx == 0.0:
            raise InputError("Vx", self.Vx, "!= 0 (no steady rolling field at standstill)")
        f = self.field
        h = f.dx / abs(self.Vx)
        for _ in range(f.nx + 2):
            f.roll(h, self.vx, self.vy, self.Vx, self.Omega_z)
        self.out = self._outputs_now()

    def snapshot(self) -> tuple:
        """The whole internal state, field included: restore(snapshot()) is exact."""
        return (self.y.copy(), self.t, self.out, self.impulse.copy(), self.field.state())

    def restore(self, snap: tuple) -> None:
        y, t, out, impulse, fstate = snap
        self.y, self.t, self.out = np.array(y, float), float(t), out
        self.impulse = np.array(impulse, float)
        self.field.set_state(fstate)

    def set_load(self, P: float) -> None:
        """Change the normal load P (N): the ellipse follows (Eq. 34), the field is kept
        (material outside the new contact is released at the next step)."""
        self.field.set_load(P)

    def set_mu(self, mu: float) -> None:
        """Change the coefficient of friction: the field is kept; tractions above the new
        bound mu p are capped at the next step (as after a load drop)."""
        self.field.law = self.field.law.with_mu(positive("mu", mu))

    def advance(self, h: float, loads: LoadInput, substeps: int = 1) -> None:
        """Advance by h (s) in ``substeps`` equal steps under the load history.

        Constant ``loads`` are held over the interval (zero-order hold); a callable is
        sampled at the stage times. On error the state is left unchanged. Compiled
        where vx is the only stage unknown and the loads are held (cf_field_advance).
        """
        h = positive("h", h)
        if isinstance(substeps, bool) or not isinstance(substeps, (int, np.integer)):
            raise InputError("substeps", substeps, "an integer >= 1")
        if substeps < 1:
            raise InputError("substeps", substeps, ">= 1")
        load_at = loads if callable(loads) else (lambda _t, L=loads: L)
        if not callable(loads) and self._advance_compiled(h, loads, int(substeps)):
            return
        saved = self.snapshot()
        self.evals = 0
        try:
            dt = h / substeps
            t0 = self.t
            for k in range(substeps):
                t_n = t0 + k * dt
                self._step(t_n, dt, load_at)
                self.t = t_n + dt
            self.t = t0 + h
        except Exception:
            self.restore(saved)
            raise

    def _advance_compiled(self, h: float, loads: Loads, substeps: int) -> bool:
        """``advance`` under held loads in one C call (field.c, cf_field_advance: this
        class's _step, _stage and _solve_scalar with the field's stage) where vx is the
        only stage unknown and the field runs compiled; False (nothing changed) where
        the Python steps must take it, which then word any error."""
        if len(self._idx) != 1:
            return False
        c = self.field._compiled()
        if c is None:
            return False
        b, law = self.body, self.law
        body = {"M": b.M, "Rx": b.Rx, "A1": b.A1, "A2": b.A2, "m_slip": b.m_slip,
                "ry": self.lateral.vy_ratio, "rz": self.lateral.spin_ratio,
                "creep_full_slip": law.creep_full_slip, "gamma": GAMMA, "a21": A21,
                "solve_rtol": SOLVE_RTOL, "v_scale_floor": V_SCALE_FLOOR,
                "max_iterations": MAX_STAGE_ITERATIONS}  # fmt: skip
        f = self.field
        r = c.advance(body, self.y, self.t, self.impulse, (f.theta, f.tau_x, f.tau_y, f.slip),
                      h, tuple(loads), substeps)  # fmt: skip
        if r is None:
            return False
        self.y, self.t, self.impulse, fstate, T, sliding = r
        f.theta, f.direction, f.tau_x, f.tau_y, f.slip = fstate
        self.out = ContactOutputs(*T, sliding=sliding)
        return True

    # ---- one SDIRK2 step -----------------------------------------------------------
    def _step(self, t_n: float, h: float, load_at: Callable[[float], Loads]) -> None:
        y_n = self.y
        hg = h * GAMMA
        L1 = load_at(t_n + STAGE_C[0] * h)
        L2 = load_at(t_n + h)
        base = self.field.begin()
        tau_n = (base.tau_x, base.tau_y)
        y1, st1, T1 = self._stage(y_n.copy(), hg, L1, base, tau_n, lambda Vx: hg * Vx, hg)
        k1 = (y1 - y_n) / hg
        y_hat = y_n + h * A21 * k1
        b1 = self.field.to_base(st1, base)
        c = A21 / GAMMA
        tau_hat = (tau_n[0] + c * (b1[0] - tau_n[0]), tau_n[1] + c * (b1[1] - tau_n[1]))
        ds1 = h * A21 * y1[0]
        y2, st2, T2 = self._stage(y_hat, hg, L2, base, tau_hat, lambda Vx: ds1 + hg * Vx, h)
        self.y = y2  # stiffly accurate: the last stage is the step's result
        self.field.commit(st2)
        self.impulse += h * (A21 * T1 + GAMMA * T2)
        self.out = ContactOutputs(*(float(v) for v in T2), sliding=self._no_adhesion(st2))

    @staticmethod
    def _no_adhesion(st: StageField) -> bool:
        return bool(np.any(st.inside)) and not np.any(st.inside & ~st.slip)

    def _targets(self, L: Loads) -> FloatArray:
        """Right-hand sides of the stage equations: Eq. (20) (A2 Fx - A1 My/Rx), Eqs.
        (10)-(11) where dynamic (N, N m)."""
        t = [self.body.tx_demand(L.Fx_ex, L.My_ex)]
        if self.lateral.dynamic_vy:
            t.append(L.Fy_ex)
        if self.lateral.dynamic_spin:
            t.append(L.Mz_ex)
        return np.array(t)

    def _masses(self) -> FloatArray:
        b = self.body
        full = np.array([b.M, b.m_slip, b.M, b.Iz if b.Iz is not None else 0.0])
        return full[self._idx]

    def _stage(
        self,
        y_hat: FloatArray,
        hg: float,
        L: Loads,
        base: StepBase,
        tau_hat: tuple[FloatArray, FloatArray],
        ds_of: Callable[[float], float],
        elapsed: float,
    ) -> tuple[FloatArray, StageField, FloatArray]:
        """Solve the stage: m (u - u_hat)/(h gamma) + T(u) = target, T from the field.

        u = (vx[, Vy][, Omega_z]); Vx follows from vx exactly (T eliminated between
        Eqs. 8 and 20): Vx = Vx_hat + h gamma A1 (Fx + My/Rx)/M + A2 (vx - vx_hat).
        """
        b = self.body
        for name, val in zip(Loads._fields, L, strict=True):
            finite(name, val)
        target = self._targets(L)
        m = self._masses()
        Vx_base = y_hat[0] + hg * b.A1 * (L.Fx_ex + L.My_ex / b.Rx) / b.M
        u_hat = y_hat[self._idx]
        idx, act = self._idx, self._act
        field = self.field
        y_ax = field.y

        def state(u: FloatArray) -> FloatArray:
            yy = y_hat.copy()
            yy[idx] = u
            yy[0] = Vx_base + (b.m_slip / b.M) * (u[0] - u_hat[0])
            return self._apply_ratios(yy)

        memo: dict = {}

        def evaluate(u: FloatArray) -> tuple[FloatArray, StageField, FloatArray]:
            self.spend()  # the field's evaluations, against the budget
            yy = state(u)
            ds = ds_of(yy[0])
            st = field.stage(base, tau_hat, ds, elapsed, hg, yy[1], yy[2], yy[3], yy[0], memo)
            return yy, st, np.array(st.resultant(y_ax))

        def residual(u: FloatArray) -> FloatArray:
            return m * (u - u_hat) / hg + evaluate(u)[2][act] - target

        # unknown u[i] -> column of the field's Jacobian (vx, vy = Vy, Omega_z)
        cols = (
            [0]
            + ([1] if self.lateral.dynamic_vy else [])
            + ([2] if self.lateral.dynamic_spin else [])
        )

        def vector(u: FloatArray) -> tuple[FloatArray, FloatArray, tuple]:
            self.spend()
            yy = state(u)
            ds = ds_of(yy[0])
            st = field.stage(
                base, tau_hat, ds, elapsed, hg, yy[1], yy[2], yy[3], yy[0], memo, jacobian=True
            )
            T = np.array(st.resultant(y_ax))
            r = m * (u - u_hat) / hg + T[act] - target
            J = np.diag(m / hg) + st.jacobian[np.ix_(act, cols)]
            return r, J, (yy, st, T)

        vscale = self.law.creep_full_slip * max(abs(Vx_base), V_SCALE_FLOOR)
        if len(idx) == 1:
            m_h = float(m[0]) / hg

            def scalar(s: float) -> tuple[float, float, tuple]:
                ev = evaluate(np.array([s]))
                r = m_h * (s - u_hat[0]) + ev[2][0] - target[0]
                return float(r), m_h + ev[1].dTx_dvx, ev

            return self._solve_scalar(scalar, float(u_hat[0]), float(target[0]), vscale)
        scale = np.array([vscale, vscale, vscale / self.law.a1])[: len(idx)]
        return self._solve_vector(vector, residual, u_hat.copy(), scale, evaluate)

    def _solve_scalar(self, f, u0: float, target: float, scale: float) -> tuple:
        """Root of the non-decreasing stage residual (``solvers.bracketed_newton`` with
        the field's tangent ``StageField.dTx_dvx``): the evaluation at the root.

        f(u) -> (r, dr/du, payload). Converged when the Newton correction is below
        SOLVE_RTOL (scale + |u|).
        """
        cap = self.law.mu * self.law.P

        def failure() -> str:
            return (
                f"no slip velocity satisfies the stage equation (target force {target:.6g} "
                f"N against mu P = {cap:.6g} N)"
            )

        return bracketed_newton(f, u0, scale, SOLVE_RTOL, MAX_STAGE_ITERATIONS, failure)[1]

    def _solve_vector(self, f, residual, u0: FloatArray, scale: FloatArray, evaluate) -> tuple:
        """Stage solve with dynamic Vy and/or Omega_z: Newton's method with the field's
        Jacobian and a backtracking line search on the scaled residual; scipy's hybrid
        method if that stalls. Converged when every Newton correction is below
        SOLVE_RTOL (scale_i + |u_i|)."""
        u = u0.copy()
        r, J, ev = f(u)
        for _ in range(MAX_STAGE_ITERATIONS):
            try:
                step = np.linalg.solve(J, -r)
            except np.linalg.LinAlgError:
                break
            if np.all(np.abs(step) <= SOLVE_RTOL * (scale + np.abs(u))):
                return ev
            norm0 = float(np.linalg.norm(r))
            lam = 1.0
            while True:
                r_new, J_new, ev_new = f(u + lam * step)
                if float(np.linalg.norm(r_new)) < norm0 or lam < 1e-6:
                    break
                lam *= 0.5
            if lam < 1e-6:
                break
            u, r, J, ev = u + lam * step, r_new, J_new, ev_new
        sol = root(
            lambda z: residual(u + z * scale),
            np.zeros_like(u),
            method="hybr",
            options={"xtol": SOLVE_RTOL},
        )
        if not sol.success:
            raise StageSolveError(f"stage solve failed: {sol.message}")
        return evaluate(u + np.asarray(sol.x) * scale)

    def _outputs_now(self) -> ContactOutputs:
        Tx, Ty, Mz = self.field.resultant()
        return ContactOutputs(Tx, Ty, Mz, self._no_adhesion(self.field.current()))
