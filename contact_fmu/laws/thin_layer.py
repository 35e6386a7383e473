"""Thin compliant layers: the example of Section 4 of Spector & Batra (1995).

Normal contact (Eqs. 32-34): Winkler layers, w^b = k1 p and w^s = -k2 p, give the
parabolic pressure p = p0 (1 - x^2/a1^2 - y^2/a2^2) on an ellipse.

Tangential contact (Eqs. 31, 35-43): the layers u^b = -kb tau, u^s = ks tau turn the
steady slip (Eq. 15 without its time derivative) into

    s = v + Vx (kb + ks) d(tau)/dx,

so in the adhesion area tau grows linearly from the leading edge, and in the slip
area |tau| = mu p. The closed form of the resultant (Eqs. 40-43) is implemented in
its corrected form: the printed H(beta) of Eq. (42) is half the integral, see
docs/model.md, section "Resultant frictional force".

Sign convention of Eq. (8): T is the force the body exerts on the substrate; the
body receives -T. T has the direction of the rigid slip v.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import brentq

from .. import native
from .._validate import InputError, finite, nonnegative, positive

FloatArray = NDArray[np.float64]

# beta = alpha / a1 (Eq. 43) at which the adhesion area vanishes: full slip.
BETA_FULL_SLIP = 2.0
# Smallest positive magnitude in the projection of the strip march (guards 0/0).
TINY = 1e-300
# Bound on the strip march's gain L vb/(|Vx| k) (_Grid.gain): increments stay finite.
INC_MAX = 1e300
# Default strip grid for the spin (Omega_z != 0) resultant, see LayerContact.forces.
SPIN_GRID = (64, 48)


def _H(b, sqrt, asin):
    """H(b) of Eq. (42), corrected, for 0 <= b <= 2 with the given sqrt/asin (math or numpy)."""
    m = sqrt(1.0 - 0.25 * b * b)
    return (
        (1.0 + b * b) * asin(0.5 * b) - 0.5 * math.pi * b * b + b * m * (13.0 / 6.0 + b * b / 12.0)
    )


def force_fraction(beta: ArrayLike) -> FloatArray:
    """|T| / (mu P) as a function of beta = alpha/a1 (Eqs. 40-43, corrected).

    h(beta) = (2/pi) H(beta) with the integral over the ellipse

        H(beta) = (1 + beta^2) asin(beta/2) - pi beta^2/2 + beta m (13/6 + beta^2/12),
        m = (1 - beta^2/4)^(1/2),

    for 0 <= beta <= 2 and h = 1 beyond. This is twice the printed Eq. (42) after
    asin(m) = pi/2 - asin(beta/2); the form used here has no cancellation at small
    beta (h ~ 16 beta / (3 pi)). h is C1 at beta = 2 (1 - h ~ (2 - beta)^3.5).
    """
    beta = np.asarray(beta, dtype=float)
    h = (2.0 / np.pi) * _H(np.minimum(beta, BETA_FULL_SLIP), np.sqrt, np.arcsin)
    # min(., 1): H(2) = pi/2 exactly; rounding must not lift |T| above mu P
    return np.where(beta >= BETA_FULL_SLIP, 1.0, np.minimum(h, 1.0))


def _force_fraction_scalar(beta: float) -> float:
    """force_fraction for one float (the integrator's inner loop): same formula, math."""
    if beta >= BETA_FULL_SLIP:
        return 1.0
    return min((2.0 / math.pi) * _H(beta, math.sqrt, math.asin), 1.0)


def _force_fraction_slope(beta: float) -> float:
    """dh/dbeta for one float: (2/pi) (m (8 + beta^2)/3 - 2 beta asin m), 0 beyond full slip.

    From differentiating H of ``force_fraction``; 16/(3 pi) at beta = 0, 0 at beta = 2.
    """
    if beta >= BETA_FULL_SLIP:
        return 0.0
    m = math.sqrt(1.0 - 0.25 * beta * beta)
    return max((2.0 / math.pi) * (m * (8.0 + beta * beta) / 3.0 - 2.0 * beta * math.asin(m)), 0.0)


# Below this beta, h/beta comes from its series 16/(3 pi) - beta + 2 beta^2/(3 pi)
# (next term beta^4/(120 pi): < 3e-19 relative here), not from the division.
BETA_SERIES = 1e-4


def _fraction_per_beta(beta: float) -> float:
    """h(beta)/beta for one float, finite as beta -> 0 (16/(3 pi) there)."""
    if beta < BETA_SERIES:
        return 16.0 / (3.0 * math.pi) - beta + 2.0 * beta * beta / (3.0 * math.pi)
    return _force_fraction_scalar(beta) / beta


def moment_fraction(beta: ArrayLike) -> FloatArray:
    """int x |tau| dA / (mu P a1) for rolling in +x (derived in docs/model.md).

    g(beta) = (beta/2) (h(beta) - 1) <= 0: the traction is centred behind the
    contact centre; g = 0 at full slip, g ~ -beta/2 at small beta.
    """
    beta = np.asarray(beta, dtype=float)
    b = np.minimum(beta, BETA_FULL_SLIP)
    return 0.5 * b * (force_fraction(b) - 1.0)


def adhesion_fraction(beta: ArrayLike) -> FloatArray:
    """Adhesion area / contact area pi a1 a2: (2 asin m - beta m)/pi, m = (1 - beta^2/4)^(1/2)."""
    beta = np.asarray(beta, dtype=float)
    b = np.minimum(beta, BETA_FULL_SLIP)
    m = np.sqrt(1.0 - 0.25 * b * b)
    return (2.0 * np.arcsin(m) - b * m) / np.pi


@dataclass(frozen=True)
class TractionField:
    """Tangential traction on a cell-centred grid over the contact ellipse.

    x (nx,), y (ny,) in m; tau_x, tau_y, p (ny, nx) in Pa, zero outside the contact;
    ``inside`` and ``slip`` (ny, nx) masks; ``la`` (ny,) the adhesion/slip boundary
    l_a(y) of Eq. (38) (equal to the leading edge where a strip fully slips).
    ``weights`` (ny, nx) are the quadrature weights (m^2) of the resultant.
    """

    x: FloatArray
    y: FloatArray
    tau_x: FloatArray
    tau_y: FloatArray
    p: FloatArray
    inside: NDArray[np.bool_]
    slip: NDArray[np.bool_]
    la: FloatArray
    weights: FloatArray = field(repr=False)

    def arrays(self) -> dict[str, FloatArray]:
        """The field as plain arrays, e.g. for ``numpy.savez``: x (nx,), y (ny,) in m;
        tau_x, tau_y, p (ny, nx) in Pa; slip, inside (ny, nx) as 0/1; weights m^2."""
        return {
            "x": self.x,
            "y": self.y,
            "tau_x": self.tau_x,
            "tau_y": self.tau_y,
            "p": self.p,
            "slip": self.slip.astype(np.int8),
            "inside": self.inside.astype(np.int8),
            "weights": self.weights,
        }

    def resultant(self) -> tuple[float, float, float]:
        """(Tx, Ty, Mz) = int (tau_x, tau_y, x tau_y - y tau_x) dA by the grid quadrature."""
        X, Y = np.meshgrid(self.x, self.y)
        w = self.weights
        Tx = float(np.sum(w * self.tau_x))
        Ty = float(np.sum(w * self.tau_y))
        Mz = float(np.sum(w * (X * self.tau_y - Y * self.tau_x)))
        return Tx, Ty, Mz


@dataclass(frozen=True)
class LayerContact:
    """Rolling/sliding contact through thin compliant layers (Section 4).

    Parameters (SI): P normal load (N); Rx, Ry radii of curvature of the body (m);
    k1, k2 normal compliances of the body's and the substrate's layer (m/Pa, Eq. 32);
    kb, ks tangential compliances (m/Pa, Eq. 31); mu friction coefficient (-).
    """

    P: float
    Rx: float
    Ry: float
    k1: float
    k2: float
    kb: float
    ks: float
    mu: float
    # The closed forms' constants for the compiled stepper (contact_fmu/native), which
    # covers this law without spin: its presence marks the law as covered.
    native_constants: ClassVar[dict[str, float]] = {
        "beta_full_slip": BETA_FULL_SLIP,
        "beta_series": BETA_SERIES,
    }

    @cached_property
    def _native_params(self) -> native.Params:
        """This law for stepper.c's layer functions (cf_layer_forces)."""
        p = native.Params()
        for k, v in (self.native_constants | self.native_fields()).items():
            setattr(p, k, v)
        return p

    def __getstate__(self) -> dict:
        """Pickle and deepcopy without the ctypes caches (rebuilt on use)."""
        return {k: v for k, v in self.__dict__.items() if k != "_native_params"}

    def native_strips(self) -> native.Strips:
        """The spin grid of ``forces`` as stepper.c's cf_strips (kept by this law)."""
        return self._grid(*SPIN_GRID).strips(self)

    def native_fields(self) -> dict[str, float]:
        """This law at its load for the compiled stepper (stepper.c, LAW_LAYER)."""
        return {
            "law": 0,
            "mu": self.mu,
            "P": self.P,
            "a1": self.a1,
            "creep_full_slip": self.creep_full_slip,
            "beta_per_creep": self._beta_per_creep,
        }

    def __post_init__(self) -> None:
        for name in ("Rx", "Ry", "mu"):
            positive(name, getattr(self, name))
        nonnegative("P", self.P)  # P = 0: lift-off, no contact (``lifted``)
        for name in ("k1", "k2", "kb", "ks"):
            nonnegative(name, getattr(self, name))
        if self.k1 + self.k2 <= 0.0:
            raise InputError("k1 + k2", self.k1 + self.k2, "> 0 (a Winkler layer carries the load)")
        if self.kb + self.ks <= 0.0:
            raise InputError("kb + ks", self.kb + self.ks, "> 0 (tangential layer compliance)")

    @property
    def lifted(self) -> bool:
        """P = 0: the body has lifted off, there is no contact and every force is zero
        (the P -> 0+ limit of Eqs. 34-43: T = mu P h(beta) v/|v| with |h| <= 1)."""
        return self.P == 0.0

    # ---- normal contact, Eqs. (32)-(34) -------------------------------------------
    @cached_property
    def delta(self) -> float:
        """Approach of the body and the substrate (m), Eq. (34)."""
        return math.sqrt(self.P * (self.k1 + self.k2) / math.pi) * (self.Rx * self.Ry) ** -0.25

    @cached_property
    def a1(self) -> float:
        """Semi-axis along the rolling direction (m), Eq. (34)."""
        return math.sqrt(2.0 * self.Rx * self.delta)

    @cached_property
    def a2(self) -> float:
        """Lateral semi-axis (m), Eq. (34)."""
        return math.sqrt(2.0 * self.Ry * self.delta)

    @cached_property
    def p0(self) -> float:
        """Peak pressure (Pa), Eq. (34); P = pi p0 a1 a2 / 2."""
        return self.delta / (self.k1 + self.k2)

    @property
    def k(self) -> float:
        """Tangential compliance of the layer pair kb + ks (m/Pa)."""
        return self.kb + self.ks

    @cached_property
    def creep_full_slip(self) -> float:
        """|v|/|Vx| at which full slip sets in (beta = 2): 2 mu p0 (kb + ks)/a1; 0 at
        P = 0, its limit (p0/a1 ~ P^(1/4), Eq. 34): any slip is full slip."""
        if self.lifted:
            return 0.0
        return BETA_FULL_SLIP * self.mu * self.p0 * self.k / self.a1

    @cached_property
    def creep_slope(self) -> float:
        """dT/d(v/Vx) at zero creep (N): (8/3) a1^2 a2 / (kb + ks), independent of mu."""
        return 8.0 * self.a1**2 * self.a2 / (3.0 * self.k)

    def pressure(self, x: ArrayLike, y: ArrayLike) -> FloatArray:
        """p(x, y) of Eq. (33) (Pa), zero outside the ellipse."""
        x, y = np.asarray(x, float), np.asarray(y, float)
        r = 1.0 - (x / self.a1) ** 2 - (y / self.a2) ** 2
        return self.p0 * np.maximum(r, 0.0)

    def with_load(self, P: float) -> LayerContact:
        """The same layers and body under another normal load P (N)."""
        if P == self.P:
            return self
        return LayerContact(P, self.Rx, self.Ry, self.k1, self.k2, self.kb, self.ks, self.mu)

    def with_mu(self, mu: float) -> LayerContact:
        """The same contact with another coefficient of friction (a wet or contaminated
        patch): the bound mu p of Eq. (35) and every force scale with it."""
        if mu == self.mu:
            return self
        return LayerContact(self.P, self.Rx, self.Ry, self.k1, self.k2, self.kb, self.ks, mu)

    # ---- tangential contact, Eqs. (35)-(43) ---------------------------------------
    def beta(self, vx: ArrayLike, vy: ArrayLike, Vx: ArrayLike) -> FloatArray:
        """beta = alpha/a1 (Eqs. 39, 43) = a1 |v| / (mu p0 (kb+ks) |Vx|); inf if Vx = 0 < |v|."""
        speed = np.hypot(vx, vy)
        aVx = np.abs(np.asarray(Vx, float))
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # inf: sliding
            b = speed * self._beta_per_creep / aVx
        return np.where(speed > 0.0, b, 0.0)

    def force(self, vx: ArrayLike, vy: ArrayLike, Vx: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Resultant frictional force (Tx, Ty) in N for rigid slip (vx, vy) and speed Vx (m/s).

        Eqs. (40)-(41), corrected: T = mu P h(beta) v/|v|. Vectorised over broadcastable
        arrays. Vx = 0 with v != 0 is pure sliding (|T| = mu P); v = 0 gives T = 0.
        """
        Tx, Ty, _ = self.forces(vx, vy, 0.0, Vx)
        return Tx, Ty

    def forces(
        self, vx: ArrayLike, vy: ArrayLike, phi: ArrayLike, Vx: ArrayLike
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """(Tx, Ty, Mz) for rigid slip (vx, vy) at the contact centre, spin phi = Omega_z.

        Without spin the closed forms hold: T of Eqs. (40)-(41) and Mz = int x tau_y dA
        = sign(Vx) mu P a1 g(beta) vy/|v| (docs/model.md). With spin the slip varies
        over the contact (Eq. 3) and the resultant comes from the strip solution of
        ``traction`` on a SPIN_GRID grid, corrected by the same grid's zero-spin error
        so that it is continuous at phi -> 0.
        """
        if isinstance(vx, float) and isinstance(vy, float) and isinstance(Vx, float) and phi == 0.0:
            return self._forces_scalar(vx, vy, Vx)
        if self.lifted:  # no contact: zero forces of the inputs' shape
            z = np.zeros(np.broadcast(*(np.asarray(a, float) for a in (vx, vy, phi, Vx))).shape)
            if z.ndim == 0:
                return 0.0, 0.0, 0.0
            return z, z.copy(), z.copy()
        v = (vx, vy, phi, Vx)
        scalar = all(np.ndim(a) == 0 for a in v)  # floats with spin: one input, floats out
        lib, args = _rolling_inputs(tuple(map(np.atleast_1d, v)) if scalar else v, Vx_at=3)
        if lib is not None:  # the same in C (stepper.c, cf_layer_forces), to rounding
            out = np.empty((args[0].size, 3))
            grid = self.native_strips()
            ptrs = (a.ctypes.data for a in args)
            lib.cf_layer_forces(self._native_params, grid, out.shape[0], *ptrs, out.ctypes.data)
            if scalar:
                return float(out[0, 0]), float(out[0, 1]), float(out[0, 2])
            Tx, Ty, Mz = out.T.copy()
            return Tx, Ty, Mz
        vx, vy, phi, Vx = np.broadcast_arrays(*(np.asarray(a, float) for a in (vx, vy, phi, Vx)))
        speed = np.hypot(vx, vy)
        beta = self.beta(vx, vy, Vx)
        scale = self.mu * self.P * force_fraction(beta)
        with np.errstate(divide="ignore", invalid="ignore"):
            ex = np.where(speed > 0.0, vx / speed, 0.0)
            ey = np.where(speed > 0.0, vy / speed, 0.0)
        Tx = np.array(scale * ex)
        Ty = np.array(scale * ey)
        Mz = np.array(np.sign(Vx) * self.mu * self.P * self.a1 * moment_fraction(beta) * ey)
        spinning = phi != 0.0
        if np.any(spinning):
            dTx, dTy, dMz = self.spin_correction(
                vx[spinning], vy[spinning], phi[spinning], Vx[spinning]
            )
            Tx[spinning] += dTx
            Ty[spinning] += dTy
            Mz[spinning] += dMz
        return Tx, Ty, Mz

    def spin_correction(
        self, vx: FloatArray, vy: FloatArray, phi: FloatArray, Vx: FloatArray,
        grid: tuple[int, int] = SPIN_GRID,
    ) -> tuple[FloatArray, FloatArray, FloatArray]:  # fmt: skip
        """What ``forces`` adds to the closed form for spin phi: the strip march's (Tx,
        Ty, Mz) with the spin less the same march without it, on an nx x ny ``grid``
        (1-D arrays of one length; one stacked march for both)."""
        n = len(vx)
        g = self._grid(*grid)
        v = (vx, vy, Vx)
        tau, _ = g.march(self, *(np.tile(a, 2) for a in v), np.r_[phi, np.zeros(n)])
        dT, dM = (r[:n] - r[n:] for r in g.resultants(tau, np.tile(np.sign(Vx), 2)))
        return dT.real, dT.imag, dM

    def _forces_scalar(self, vx: float, vy: float, Vx: float) -> tuple[float, float, float]:
        """``forces`` without spin for floats, in math instead of numpy (same formulas)."""
        speed = math.hypot(vx, vy)
        if speed == 0.0 or self.lifted:
            return 0.0, 0.0, 0.0
        beta = math.inf if Vx == 0.0 else speed * self._beta_per_creep / abs(Vx)
        h = _force_fraction_scalar(beta)
        muP = self.mu * self.P
        b = min(beta, BETA_FULL_SLIP)
        g = 0.5 * b * (h - 1.0)
        Mz = math.copysign(1.0, Vx) * muP * self.a1 * g * vy / speed if Vx != 0.0 else 0.0
        return muP * h * vx / speed, muP * h * vy / speed, Mz

    def tx_slope(self, vx: float, vy: float, Vx: float) -> tuple[float, float, float, float]:
        """Tx and its partial derivatives (dTx/dvx, dTx/dvy, dTx/dVx) for floats, no spin.

        With s = |v|, e = v/s, beta = c s/|Vx| (c = a1/(mu p0 k)) and Tx = mu P h(beta) e_x:
        dTx/dvx = mu P (h' c e_x^2/|Vx| + (h/s) e_y^2),
        dTx/dvy = mu P e_x e_y (h' c/|Vx| - h/s), dTx/dVx = -mu P h' beta e_x/Vx,
        with h/s = (h/beta) c/|Vx| from a series at small beta (no underflow as s -> 0).
        For the integrator's Newton iterations; Vx != 0. At P = 0 (no contact) all zero.
        """
        if self.lifted:
            return 0.0, 0.0, 0.0, 0.0
        muP, c = self.mu * self.P, self._beta_per_creep
        aV = abs(Vx)
        s = math.hypot(vx, vy)
        if s == 0.0:  # h ~ h'(0) beta: Tx ~ mu P h'(0) c vx/|Vx|
            return 0.0, muP * _force_fraction_slope(0.0) * c / aV, 0.0, 0.0
        ex, ey = vx / s, vy / s
        beta = s * c / aV
        h, dh = _force_fraction_scalar(beta), _force_fraction_slope(beta)
        h_per_s = _fraction_per_beta(beta) * c / aV
        Tx = muP * h * ex
        d_vx = muP * (dh * c * ex * ex / aV + h_per_s * ey * ey)
        d_vy = muP * ex * ey * (dh * c / aV - h_per_s)
        d_V = -muP * dh * beta * ex / Vx
        return Tx, d_vx, d_vy, d_V

    @cached_property
    def _beta_per_creep(self) -> float:
        """beta per unit creepage |v|/|Vx|: a1 / (mu p0 (kb + ks)); inf at P = 0 (its
        limit, ~ P^(-1/4))."""
        if self.lifted:
            return math.inf
        return BETA_FULL_SLIP / self.creep_full_slip

    def inverse_creep(self, Tx: float, xi_y: float = 0.0) -> float:
        """Longitudinal creepage xi_x = vx/Vx with Tx(xi_x Vx, xi_y Vx, Vx) = Tx (N).

        The inverse T_x^{-1} of Eq. (28), for a held lateral creepage xi_y = vy/Vx.
        |Tx| must be below the capacity (mu P; reached only asymptotically when
        xi_y != 0).
        """
        Tx, xi_y = finite("Tx", Tx), finite("xi_y", xi_y)
        cap = self.mu * self.P
        if abs(Tx) >= cap * (1.0 if xi_y == 0.0 else 1.0 - 1e-15):
            raise InputError("Tx", Tx, f"|Tx| < mu P = {cap:.6g} N")
        if Tx == 0.0:
            return 0.0
        sign = math.copysign(1.0, Tx)

        def gap(xi: float) -> float:
            return float(self.force(sign * xi, xi_y, 1.0)[0]) * sign - abs(Tx)

        hi = self.creep_full_slip
        while gap(hi) <= 0.0:  # beyond full slip only with lateral creep
            hi *= 2.0
        return sign * brentq(gap, 0.0, hi, xtol=1e-15 * hi, rtol=4 * np.finfo(float).eps)

    def adhesion_fraction(
        self, vx: ArrayLike, vy: ArrayLike, Vx: ArrayLike, phi: float = 0.0
    ) -> FloatArray:
        """Adhesion area over contact area (-). Closed form without spin; with spin
        phi = Omega_z (rad/s), the area of the non-slipping nodes of the strip solution
        on the SPIN_GRID grid (first order in the cell size). 0 at P = 0: no contact,
        nothing adheres (the limit at any slip: full slip)."""
        if self.lifted:
            z = np.zeros(np.broadcast(*(np.asarray(a, float) for a in (vx, vy, Vx))).shape)
            return 0.0 if z.ndim == 0 else z
        if phi != 0.0:
            f = self.traction(float(vx), float(vy), float(Vx), *SPIN_GRID, phi=float(phi))
            stuck = f.inside & ~f.slip
            return float(np.sum(f.weights * stuck) / np.sum(f.weights * f.inside))
        if isinstance(vx, float) and isinstance(vy, float) and isinstance(Vx, float):
            s = math.hypot(vx, vy)  # float path: (2 asin m - beta m)/pi in math
            if s == 0.0:
                return 1.0
            if Vx == 0.0 or s * self._beta_per_creep >= BETA_FULL_SLIP * abs(Vx):
                return 0.0
            b = s * self._beta_per_creep / abs(Vx)
            m = math.sqrt(1.0 - 0.25 * b * b)
            return (2.0 * math.asin(m) - b * m) / math.pi
        return adhesion_fraction(self.beta(vx, vy, Vx))

    def traction(
        self, vx: float, vy: float, Vx: float, nx: int = 81, ny: int = 61, phi: float = 0.0
    ) -> TractionField:
        """Traction field tau(x, y) (Eqs. 36-37) and adhesion boundary l_a(y) (Eq. 38).

        The field is computed strip by strip (y fixed) from the leading edge, where the
        material enters unstressed, as tau <- proj_{|tau| <= mu p}(tau + v dx/(|Vx| k)):
        the discrete form of Eq. (35) capped by the Coulomb conditions (4)-(5). Without
        spin the slip direction is constant and the nodal values are exact (Eq. 36);
        with spin (phi = Omega_z, rad/s; v of Eq. 3 varies over the contact) it is the
        first-order strip scheme of Kalker's FASTSIM with flexibility kb + ks.
        """
        for name, val in (("vx", vx), ("vy", vy), ("Vx", Vx), ("phi", phi)):
            finite(name, val)
        if self.lifted:
            raise InputError("P", self.P, "> 0 for a traction field (P = 0: no contact)")
        grid = self._grid(nx, ny)
        tau, slip = grid.march(self, *(np.array([float(a)]) for a in (vx, vy, Vx, phi)))
        s = math.copysign(1.0, Vx) if Vx != 0.0 else 0.0
        tau, slip = tau[0], slip[0]
        if s > 0:  # the march runs against x: back to column order
            tau, slip = tau[:, ::-1], slip[:, ::-1]
        ell = grid.ell
        alpha = float(self.beta(vx, vy, Vx)) * self.a1
        la = np.where(ell > 0.5 * alpha, s * (alpha - ell), s * ell) if s else -ell
        return TractionField(
            grid.x,
            grid.y,
            tau.real.copy(),
            tau.imag.copy(),
            grid.p,
            grid.inside,
            slip,
            la,
            grid.weights,
        )

    def _grid(self, nx: int, ny: int) -> _Grid:
        if self.lifted:
            raise InputError("P", self.P, "> 0 for a strip grid (P = 0: no contact)")
        nx, ny = int(nx), int(ny)
        if nx < 2 or ny < 1:
            raise InputError("nx, ny", (nx, ny), "nx >= 2 and ny >= 1")
        cache = self.__dict__.setdefault("_grids", {})  # frozen dataclass: cache by hand
        if (nx, ny) not in cache:
            cache[(nx, ny)] = _Grid.build(self, nx, ny)
        return cache[(nx, ny)]


@dataclass(frozen=True)
class _Grid:
    """Cell-centred grid over the contact ellipse, in the order of the strip march.

    The grid is symmetric in x, so a march from the leading edge x = +l(y) (Vx > 0)
    visits at step j the node -x[j], one from x = -l(y) (Vx < 0) the node x[j]:
    ``dist`` (the distance marched, from the leading edge for a strip's first node)
    and ``mid`` (the midpoints, for Vx < 0) serve both directions.
    """

    x: FloatArray
    y: FloatArray
    ell: FloatArray
    inside: NDArray[np.bool_]
    p: FloatArray
    weights: FloatArray
    dist: FloatArray
    mid: FloatArray

    @classmethod
    def build(cls, c: LayerContact, nx: int, ny: int) -> _Grid:
        a1, a2 = c.a1, c.a2
        # cell centres, exactly antisymmetric (x[nx-1-j] = -x[j]): the march reads the
        # grid backwards for Vx > 0
        x = (2.0 * np.arange(nx) + 1.0 - nx) * (a1 / nx)
        y = (2.0 * np.arange(ny) + 1.0 - ny) * (a2 / ny)
        ell = a1 * np.sqrt(np.maximum(1.0 - (y / a2) ** 2, 0.0))  # Eq. (37)
        X, Y = np.meshgrid(x, y)
        inside = np.abs(X) < ell[:, None]
        prev = np.where(inside, X, np.nan)
        # previous position on the strip: the node before, or the edge -l for the first
        prev = np.concatenate([np.full((ny, 1), np.nan), prev[:, :-1]], axis=1)
        prev = np.where(np.isnan(prev), -ell[:, None], prev)
        dist = np.where(inside, X - prev, 0.0)
        mid = np.where(inside, 0.5 * (X + prev), 0.0)
        weights = _strip_weights(x, ell, inside) * (2.0 * a2 / ny)
        return cls(x, y, ell, inside, c.pressure(X, Y), weights, dist, mid)

    def march(self, c: LayerContact, vx, vy, Vx, phi) -> tuple[NDArray, NDArray]:
        """Traction (complex tau_x + i tau_y) and slip mask, shape (n, ny, nx), march order.

        tau <- proj_{|tau| <= mu p}(tau + v dx / (|Vx| (kb + ks))) along each strip from
        the leading edge (Eqs. 35, 4-5); Vx = 0 slides everywhere: tau = mu p v/|v|.
        Rolling inputs run compiled where the library is (native, cf_strip_march).
        """
        compiled = self._compiled(c, vx, vy, Vx, phi)
        if compiled is not None:
            lib, st, args = compiled
            n, ny, nx = args[0].size, self.y.size, self.x.size
            tau = np.empty((n, ny, nx), complex)
            slip = np.empty((n, ny, nx), bool)
            lib.cf_strip_march(st, n, *(a.ctypes.data for a in args), tau.ctypes.data,
                               slip.ctypes.data)  # fmt: skip
            return tau, slip & self.inside
        return self._march_numpy(c, vx, vy, Vx, phi)

    def gain(self, c: LayerContact, vx, vy, Vx, phi) -> FloatArray:
        """The march's gain 1/(|Vx| k), bounded so that its increments stay finite.

        With L = 2|x0| + |y0| (>= every |y|, |mid| and dist of the grid, nx >= 2) and
        vb = max(|vx|, |vy|, |phi| L), an increment gain dist (slip of Eq. 3) is below
        4 gain L vb. Where gain L vb would pass INC_MAX (or is NaN: gain inf without
        slip), the gain is INC_MAX/(L vb) (0 without slip): the min of the two, so the
        march stays continuous in Vx, and every node with slip |v| > 1e-280 vb then
        slides along it (mu p/|inc| < 1e-280): the |Vx| -> 0+ limit (docs/model.md).
        stepper.c's march_gain, the same doubles.
        """
        L = 2.0 * abs(float(self.x[0])) + abs(float(self.y[0]))
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            g = 1.0 / (np.abs(Vx) * c.k)
            vb = np.maximum(np.maximum(np.abs(vx), np.abs(vy)), np.abs(phi) * L)
            free = g * L * vb <= INC_MAX
            bounded = np.where(vb > 0.0, INC_MAX / (L * vb), 0.0)
        return np.where(free, g, bounded)

    def _march_numpy(self, c: LayerContact, vx, vy, Vx, phi) -> tuple[NDArray, NDArray]:
        """``march`` in numpy, for every input (standstill included)."""
        vx, vy, Vx, phi = (np.asarray(a, float)[:, None, None] for a in (vx, vy, Vx, phi))
        # homogeneous of degree 0 in the velocities: scaled by the power of two that brings
        # the largest into [0.5, 1) (exact; stepper.c's march_scale, the same doubles), so
        # that no gain overflows (Vx = 1e-300 with a spin of 1e-300 rad/s gave NaN)
        m = np.maximum(np.maximum(np.abs(vx), np.abs(vy)), np.maximum(np.abs(Vx), np.abs(phi)))
        usable = (m > 0.0) & np.isfinite(m)
        e = np.where(usable, -np.frexp(np.where(usable, m, 1.0))[1], 0)
        # up from below 0.5, down only from above 2^512 (as stepper.c: down from smaller
        # sizes would round subnormals away)
        e = np.where((e > 0) | (e < -512), e, 0)
        vx, vy, Vx, phi = (np.ldexp(a, e) for a in (vx, vy, Vx, phi))
        s = np.sign(Vx)
        X = -np.where(s == 0, -1.0, s) * self.x  # node positions in march order
        Y = self.y[:, None]
        cap = c.mu * self.p
        rolling = s != 0
        gain = np.where(rolling, self.gain(c, vx, vy, Vx, phi), 0.0)
        # slip of Eq. (3) at the midpoints, times the distance marched
        inc = gain * self.dist * ((vx - phi * Y) + 1j * (vy - s * phi * self.mid))
        n, ny, nx = inc.shape[0], self.y.size, self.x.size
        tau = np.zeros((n, ny, nx), complex)
        slip = np.zeros((n, ny, nx), bool)
        t = np.zeros((n, ny), complex)
        for j in range(nx):
            trial = t + inc[:, :, j]
            mag = np.abs(trial)
            cj = cap[:, j]
            slip[:, :, j] = mag > cj
            # projection on |tau| <= mu p; TINY keeps 0/0 (outside the contact) at 0
            t = trial * np.minimum(1.0, cj / np.maximum(mag, TINY))
            tau[:, :, j] = t
        if not np.all(rolling):  # no rolling: every point slides (Eq. 5)
            v = (vx - phi * Y) + 1j * (vy + phi * X)
            mag = np.abs(v)
            sliding = np.divide(cap * v, mag, where=mag > 0, out=np.zeros_like(v))
            tau = np.where(rolling, tau, sliding)
            slip = np.where(rolling, slip, mag > 0)
        return tau, slip & self.inside

    def resultants(self, tau: NDArray, s: FloatArray) -> tuple[NDArray, FloatArray]:
        """(Tx + i Ty, Mz) of march-ordered fields: int tau dA, int (x tau_y - y tau_x) dA."""
        w = self.weights  # symmetric in x: valid in march order
        X = -np.where(s == 0, -1.0, s)[:, None, None] * self.x
        Y = self.y[:, None]
        T = np.sum(w * tau, axis=(1, 2))
        Mz = np.sum(w * (X * tau.imag - Y * tau.real), axis=(1, 2))
        return T, Mz

    def _compiled(self, c: LayerContact, *v) -> tuple | None:
        """(library, its grid struct, the inputs as contiguous float arrays) where the march
        of these inputs runs compiled: the library is there and every input rolls (Vx != 0;
        standstill slides, in numpy). The struct points into arrays kept with it, built
        for the contact's mu and k."""
        lib, args = _rolling_inputs(v, Vx_at=2)
        return None if lib is None else (lib, self.strips(c), args)

    def __getstate__(self) -> dict:
        """Pickle and deepcopy without the ctypes struct (rebuilt on use)."""
        return {k: v for k, v in self.__dict__.items() if k != "_strips"}

    def strips(self, c: LayerContact) -> native.Strips:
        """This grid as stepper.c's cf_strips for the contact c (cached; it points into
        arrays kept with it, built for c's mu and k)."""
        cache = self.__dict__.get("_strips")  # frozen dataclass: cache by hand
        if cache is None or cache[1][6:] != (c.mu, c.k):
            arrays = tuple(
                np.ascontiguousarray(a, float)
                for a in (self.x, self.y, self.dist, self.mid, c.mu * self.p, self.weights)
            )
            st = native.Strips(
                self.y.size, self.x.size, *(a.ctypes.data for a in arrays), c.k, TINY
            )
            cache = self.__dict__["_strips"] = (st, (*arrays, c.mu, c.k))
        return cache[0]


def _rolling_inputs(v: tuple, Vx_at: int) -> tuple:
    """(library, the inputs v as contiguous 1-D float arrays) where they can run compiled:
    the library is there and every speed v[Vx_at] is nonzero (standstill slides, in
    numpy); (None, None) otherwise."""
    lib = native.library()
    if lib is None:
        return None, None
    b = np.broadcast_arrays(*(np.asarray(a, float) for a in v))
    if b[0].ndim != 1 or not np.all(b[Vx_at] != 0.0):  # (ascontiguousarray makes 0-d 1-d)
        return None, None
    return lib, [np.ascontiguousarray(a) for a in b]


def _strip_weights(x: FloatArray, ell: FloatArray, inside: NDArray[np.bool_]) -> FloatArray:
    """Trapezoid weights along each strip with tau = 0 at both edges x = -ell, +ell."""
    dx = x[1] - x[0]
    w = np.where(inside, dx, 0.0)
    rows = np.nonzero(inside.any(axis=1))[0]
    for i in rows:
        js = np.nonzero(inside[i])[0]
        j0, j1 = js[0], js[-1]
        if j0 == j1:
            w[i, j0] = ell[i]  # one node: two half-segments to the edges
            continue
        w[i, j0] = 0.5 * dx + 0.5 * (x[j0] + ell[i])
        w[i, j1] = 0.5 * dx + 0.5 * (ell[i] - x[j1])
    return w
