"""Kalker's FASTSIM: the simplified theory of steady rolling on an elliptic Hertz contact.

Simplified theory (Kalker 1973; Kalker 1982, "A fast algorithm for the simplified theory
of rolling contact", Vehicle System Dynamics 11, 1-13; Kalker 1990, Sec. 3.3). The
surface displacement difference is proportional to the local traction, u = L tau, one
flexibility L per load: L1 for the longitudinal creepage xi, L2 for the lateral creepage
eta, L3 for the spin phi. Steady rolling in +x (material enters at the leading edge
x = l(y) = a (1 - y^2/b^2)^(1/2)) with the slip s = v + Vx du/dx of the exact solver
(rolling.py) gives in adhesion du/dx = -w, w = (xi - phi y, eta + phi x), so that

    tau_x(x, y) = int_x^l (xi/L1 - phi y/L3) dx',   tau_y(x, y) = int_x^l (eta/L2 + phi x'/L3) dx',

projected on the traction bound |tau| <= g wherever it exceeds it (slip; Coulomb's law
with tau along the slip). Along each strip y = const the tractions follow from the
leading edge by a march: the FASTSIM algorithm.

Flexibilities (Kalker 1982). In full adhesion the march gives Tx = 8 a^2 b xi/(3 L1),
Ty = 8 a^2 b eta/(3 L2) + pi a^3 b phi/(4 L3) (int (l - x) dx = 2 l^2 and int (l^2 -
x^2)/2 dx = 2 l^3/3 along a strip, int l^2 dy = 4 a^2 b/3 and int l^3 dy = 3 pi a^3 b/8
over the ellipse). Equating them with Kalker's linear theory Tx = G c^2 C11 xi, Ty =
G c^2 (C22 eta + c C23 phi), c^2 = a b:

    L1 = 8 a/(3 C11 G),   L2 = 8 a/(3 C22 G),   L3 = pi a (a/b)^(1/2)/(4 C23 G)

(the same in CONTACT's m_hertz.f90, simpflex). C11, C22, C23 default to Kalker's Table
E3 (``kalker_coefficients``).

Discretisation. The grid of the exact solver (``ellipse_patch``: uniform elements
dx x dy over the ellipse's bounding box, the same grid as ``HalfSpaceContact(n=...)``);
the tractions at the element centres. The increment of an element is the exact integral
of w over its travel: w at the midpoint of [x_I, x_I + dx] (linear in x), and for the
element next to the leading edge over [x_I, l(y)] alone. In adhesion the nodal
tractions are therefore those of the continuous theory. The forces are sums tau dA
over the elements; their full-adhesion values differ from the integrals above by the
quadrature of the cut ellipse (0.1 % on 32 x 32), so the flexibilities of the grid are
L scaled by that quadrature's ratio (``flexibilities``): the small-creepage forces are
the linear theory's to rounding on every grid.

Traction bound g = mu p, p sampled at the element centres and scaled so that sum p dA =
P (full sliding in one direction gives exactly mu P):

* ``bound="parabolic"``: p = (2 P/(pi a b)) (1 - x^2/a^2 - y^2/b^2), Kalker's
  choice for the simplified theory (the classic FASTSIM);
* ``bound="elliptic"``: the Hertz pressure p0 (1 - x^2/a^2 - y^2/b^2)^(1/2), p0 =
  3 P/(2 pi a b), as in CONTACT's FASTSIM with the elliptical traction bound (B-digit 2
  of CONTACT, Vollebregt's user guide). The linear limit is the same; the creep curve
  bends later and approaches mu P only slowly: the bound rises like the square root of
  the distance from the leading edge, so adhesion persists there (docs/halfspace.md).

The march is vectorised over the strips (one numpy step per column of the grid) and
over a batch of creepages (``forces``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validate import InputError, array, count, counts, finite, flag, one_of, positive
from .hertz import (
    MODULUS_PLAUSIBLE,
    SEMI_AXIS_PLAUSIBLE,
    SPIN_PLAUSIBLE,
    semi_axes_within_aspect,
    traction_bound,
    unit_warning,
    within_scale,
)
from .rolling import SATURATION_RATIO, RollingPatch, RollingSolution, ellipse_patch

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

# Default grid: as HalfSpaceContact's, so that the two solvers compare element by element.
DEFAULT_N = 32
MIN_N = 4
BOUNDS = ("parabolic", "elliptic")
# ``forces`` marches its creepages in batches of at most this many increments per
# component (cases x elements of the grid): 16 MB per array.
BATCH_ELEMENTS = 2_000_000

# Kalker (1990), Table E3: rows g = 0.1, 0.2, ..., 1.0 with g = a/b (a <= b) and g = b/a
# (a >= b); per row (C11, C22, C23), each for nu = 0, 0.25, 0.5. As stored in CONTACT's
# m_hertz.f90 (linrol; Apache-2.0). The copy in CONTACT's usetab_table program carries
# 1.15 for C23 at a/b = 0.8, nu = 0.25, a misprint of 1.25 (C23 grows with nu in every row).
_TABLE_A_LT_B = (
    ((2.51, 3.31, 4.85), (2.51, 2.52, 2.53), (0.334, 0.473, 0.731)),
    ((2.59, 3.37, 4.81), (2.59, 2.63, 2.66), (0.483, 0.603, 0.809)),
    ((2.68, 3.44, 4.80), (2.68, 2.75, 2.81), (0.607, 0.715, 0.889)),
    ((2.78, 3.53, 4.82), (2.78, 2.88, 2.98), (0.720, 0.823, 0.977)),
    ((2.88, 3.62, 4.83), (2.88, 3.01, 3.14), (0.827, 0.929, 1.07)),
    ((2.98, 3.72, 4.91), (2.98, 3.14, 3.31), (0.930, 1.03, 1.18)),
    ((3.09, 3.81, 4.97), (3.09, 3.28, 3.48), (1.03, 1.14, 1.29)),
    ((3.19, 3.91, 5.05), (3.19, 3.41, 3.65), (1.13, 1.25, 1.40)),
    ((3.29, 4.01, 5.12), (3.29, 3.54, 3.82), (1.23, 1.36, 1.51)),
    ((3.40, 4.12, 5.20), (3.40, 3.67, 3.98), (1.33, 1.47, 1.63)),
)
_TABLE_A_GT_B = (
    ((10.7, 11.7, 12.9), (10.7, 12.8, 16.0), (12.2, 14.6, 18.0)),
    ((6.96, 7.78, 8.82), (6.96, 8.14, 9.79), (5.72, 6.63, 7.89)),
    ((5.57, 6.34, 7.34), (5.57, 6.40, 7.51), (3.79, 4.32, 5.01)),
    ((4.84, 5.57, 6.57), (4.84, 5.48, 6.31), (2.88, 3.24, 3.70)),
    ((4.37, 5.10, 6.11), (4.37, 4.90, 5.56), (2.35, 2.62, 2.96)),
    ((4.06, 4.78, 5.80), (4.06, 4.50, 5.04), (2.01, 2.23, 2.50)),
    ((3.82, 4.54, 5.58), (3.82, 4.21, 4.67), (1.76, 1.95, 2.18)),
    ((3.65, 4.36, 5.42), (3.65, 3.99, 4.39), (1.58, 1.75, 1.94)),
    ((3.51, 4.22, 5.30), (3.51, 3.81, 4.16), (1.44, 1.59, 1.77)),
    ((3.40, 4.12, 5.20), (3.40, 3.67, 3.98), (1.33, 1.47, 1.63)),
)
KALKER_TABLE = np.array([_TABLE_A_LT_B, _TABLE_A_GT_B])  # (case, row, coefficient, nu)
KALKER_NUS = (0.0, 0.25, 0.5)
# The table's range: 0.1 <= a/b <= 10.
AOB_MIN, AOB_MAX = 0.1, 10.0


def kalker_coefficients(a_over_b: float, nu: float) -> tuple[float, float, float]:
    """Kalker's creep coefficients (C11, C22, C23) (-) of the linear theory for an
    ellipse of semi-axis ratio a/b (a along the rolling direction) and Poisson's ratio
    nu: Table E3 of Kalker (1990), linear in g = min(a/b, b/a) between its rows and
    quadratic in 1/C through nu = 0, 0.25, 0.5 (CONTACT's linrol). 0.1 <= a/b <= 10 and
    0 <= nu <= 0.5: the table's range (beyond it, give the coefficients to ``Fastsim(C=
    ...)``)."""
    aob = positive("a1/a2", a_over_b)
    if not AOB_MIN * (1.0 - 1e-12) <= aob <= AOB_MAX * (1.0 + 1e-12):
        raise InputError("a1/a2", aob, f"in [{AOB_MIN}, {AOB_MAX}] (Kalker's table; else give C)")
    nu = finite("nu", nu)
    if not 0.0 <= nu <= 0.5:
        raise InputError("nu", nu, "in [0, 0.5] (Kalker's table; else give C)")
    case, g = (0, aob) if aob <= 1.0 else (1, 1.0 / aob)
    # rows at g = 0.1 (index 0) ... 1.0 (index 9)
    t = min(max(10.0 * g - 1.0, 0.0), 9.0)
    i = min(int(t), 8)
    f = t - i
    rows = (1.0 - f) * KALKER_TABLE[case, i] + f * KALKER_TABLE[case, i + 1]  # (coef, nu)
    # Lagrange weights of the parabola through nu = 0, 0.25, 0.5, applied to 1/C
    w = (
        8.0 * (nu - 0.25) * (nu - 0.5),
        -16.0 * nu * (nu - 0.5),
        8.0 * nu * (nu - 0.25),
    )
    inv = sum(wk / rows[:, k] for k, wk in enumerate(w))
    C11, C22, C23 = (float(v) for v in 1.0 / inv)
    return C11, C22, C23


@dataclass(frozen=True)
class Fastsim:
    """Kalker's FASTSIM on the elliptic Hertz contact of semi-axes a1 along x (the
    rolling direction) and a2 along y (m).

    G, nu: Kalker's combined shear modulus (Pa) and Poisson's ratio (-)
    (``CombinedElastic``); mu: friction coefficient (-); the normal load P (N) or the
    Hertz peak pressure p0 = 3 P/(2 pi a1 a2) (Pa), exactly one (both are set after
    construction). bound: the traction bound, "parabolic" (Kalker's FASTSIM) or
    "elliptic" (the Hertz pressure; module docstring). n: the grid, as for
    ``HalfSpaceContact`` ((mx, my): mx x my elements, one to spare on each side along x;
    an int n: (n, n)). C: (C11, C22, C23) of the linear theory
    that fixes the flexibilities (default: ``kalker_coefficients(a1/a2, nu)``; e.g.
    ``HalfSpaceContact.linear_coefficients()`` for those of a grid). A semi-axis above
    0.1 m or a G below 1 MPa warns (UnitWarning) unless ``check_units=False``.

    ``solve`` returns the RollingSolution of the exact solver (traction field, adhesion
    and slip areas, forces, ``plot()``); ``forces`` is the batched march for creep
    curves.
    """

    a1: float
    a2: float
    G: float
    nu: float
    mu: float
    P: float | None = None
    p0: float | None = None
    bound: str = "parabolic"
    n: int | tuple[int, int] = DEFAULT_N
    C: tuple[float, float, float] | None = None
    check_units: bool = True

    def __post_init__(self) -> None:
        check = flag("check_units", self.check_units)
        for name in ("a1", "a2"):
            if positive(name, getattr(self, name)) > SEMI_AXIS_PLAUSIBLE:
                unit_warning(name, getattr(self, name), "mm", check)
        if positive("G", self.G) < MODULUS_PLAUSIBLE:
            unit_warning("G", self.G, "N/mm^2 (MPa)", check)
        within_scale("G", self.G, "Pa")
        for name in ("a1", "a2"):
            within_scale(name, getattr(self, name), "m")
        semi_axes_within_aspect(self.a1, self.a2)
        finite("nu", self.nu)
        if not -1.0 < self.nu <= 0.5:
            raise InputError("nu", self.nu, "in (-1, 0.5]")
        positive("mu", self.mu)
        if (self.P is None) == (self.p0 is None):
            raise InputError("P, p0", (self.P, self.p0), "exactly one of them given")
        area = math.pi * self.a1 * self.a2
        if self.P is not None:
            object.__setattr__(self, "p0", 1.5 * positive("P", self.P) / area)
        else:
            object.__setattr__(self, "P", area * positive("p0", self.p0) / 1.5)
        within_scale("p0", self.p0, "Pa", f" (P = {self.P:g} N over pi a1 a2)")
        traction_bound(self.mu, self.p0)
        one_of("bound", self.bound, BOUNDS)
        if isinstance(self.n, int | np.integer) and not isinstance(self.n, bool):
            count("n", self.n, MIN_N)
        else:
            object.__setattr__(self, "n", counts("n", self.n, MIN_N))
        if self.C is None:
            object.__setattr__(self, "C", kalker_coefficients(self.a1 / self.a2, self.nu))
        else:
            Cs = array("C", self.C, (3,))
            if np.any(Cs <= 0.0):
                raise InputError("C", self.C, "(C11, C22, C23), each > 0")
            object.__setattr__(self, "C", tuple(float(v) for v in Cs))

    @classmethod
    def of(cls, contact, bound: str = "parabolic", C: ArrayLike | None = None) -> Fastsim:
        """FASTSIM on the Hertz contact and the grid of a ``HalfSpaceContact`` (its a1,
        a2, combined G and nu, mu, P and n). Layers (kb + ks > 0) are refused; the
        pressure coupling (kappa) is left out, as Kalker's simplified theory does."""
        from .contact import HalfSpaceContact

        if not isinstance(contact, HalfSpaceContact):
            raise InputError("contact", type(contact).__name__, "a HalfSpaceContact")
        if contact.k > 0.0:
            raise InputError("kb + ks", contact.k, "0 for FASTSIM (half-space flexibilities)")
        e = contact.elastic
        return cls(
            contact.a1,
            contact.a2,
            e.G,
            e.nu,
            contact.mu,
            P=contact.P,
            bound=bound,
            n=contact.n,
            C=C,
            check_units=False,
        )

    # ---- discretisation --------------------------------------------------------------
    @property
    def c(self) -> float:
        """(a1 a2)^(1/2) (m)."""
        return math.sqrt(self.a1 * self.a2)

    @property
    def elements(self) -> tuple[int, int]:
        """(mx, my): elements of the grid along x and y."""
        return self.n if isinstance(self.n, tuple) else (int(self.n), int(self.n))

    def pressure(self, x: ArrayLike, y: ArrayLike) -> FloatArray:
        """The pressure p(x, y) (Pa) of the traction bound g = mu p: parabolic, 2 P/(pi a
        b) (1 - x^2/a^2 - y^2/b^2), or the Hertz pressure; zero outside the ellipse."""
        x, y = np.asarray(x, float), np.asarray(y, float)
        r = 1.0 - (x / self.a1) ** 2 - (y / self.a2) ** 2
        if self.bound == "parabolic":
            return (4.0 / 3.0) * self.p0 * np.maximum(r, 0.0)
        return self.p0 * np.sqrt(np.maximum(r, 0.0))

    @cached_property
    def patch(self) -> RollingPatch:
        """Grid, contact and traction bound (sum p dA = P) of ``ellipse_patch``."""
        mx, my = self.elements
        return ellipse_patch(
            self.a1,
            self.a2,
            mx,
            self.pressure,
            self.mu,
            self.G,
            self.nu,
            P=self.P,
            ny=my,
        )

    @cached_property
    def _geometry(self) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """(X, Y, length, xm): element centres, the travel of each contact element
        (dx; l(y) - x_I next to the leading edge; 0 outside) and its midpoint (m)."""
        patch = self.patch
        X, Y = patch.grid.mesh()
        C = patch.contact
        ell = self.a1 * np.sqrt(np.maximum(1.0 - (Y / self.a2) ** 2, 0.0))
        length = np.where(C, np.where(patch.leading, ell - X, patch.grid.dx), 0.0)
        return X, Y, length, X + 0.5 * length

    @cached_property
    def flexibilities(self) -> tuple[float, float, float]:
        """(L1, L2, L3) (m/Pa) of this grid: Kalker's 8 a/(3 C11 G), 8 a/(3 C22 G), pi a
        (a/b)^(1/2)/(4 C23 G), each times the ratio of the grid's full-adhesion force to
        the ellipse's integral (module docstring), so that the small-creepage forces are
        the linear theory's exactly."""
        q = self._quadrature
        return tuple(L * f for L, f in zip(self.kalker_flexibilities, q, strict=True))

    @property
    def kalker_flexibilities(self) -> tuple[float, float, float]:
        """Kalker's (L1, L2, L3) (m/Pa) of the continuous theory (module docstring)."""
        a, b, G = self.a1, self.a2, self.G
        C11, C22, C23 = self.C
        return (
            8.0 * a / (3.0 * C11 * G),
            8.0 * a / (3.0 * C22 * G),
            math.pi * a * math.sqrt(a / b) / (4.0 * C23 * G),
        )

    @cached_property
    def _quadrature(self) -> tuple[float, float, float]:
        """Full-adhesion forces of the grid over the ellipse's integrals 8 a^2 b/3 (xi,
        eta) and pi a^3 b/4 (spin), from the march itself with unit flexibilities."""
        X, Y, length, xm = self._geometry
        unit = np.zeros((X.shape[1], 1, X.shape[0]))
        # unit creepage: increments = travel; unit spin (lateral part): x_mid times travel
        free = np.full(X.shape, np.inf)
        Tx, Ty, _ = self._march(length.T[:, None, :], unit, free)[:3]
        _, Ts, _ = self._march(unit, (xm * length).T[:, None, :], free)[:3]
        a, b = self.a1, self.a2
        q1 = float(Tx[0]) / (8.0 * a * a * b / 3.0)
        q3 = float(Ts[0]) / (math.pi * a**3 * b / 4.0)
        return q1, q1, q3

    # ---- the march -------------------------------------------------------------------------
    def _march(
        self, inc_x: FloatArray, inc_y: FloatArray, g: FloatArray, fields: bool = False
    ) -> tuple:
        """The strip march for a batch: increments inc (nx, B, ny) (Pa; column first, so
        that a column's slice is contiguous), bound g (ny, nx).

        From the trailing column's neighbour ahead to the trailing edge, one column at a
        time for all strips and cases: predictor tau_H = tau_I+ + inc_I (zero ahead of the
        leading edge), projected on |tau| <= g. Returns (Tx, Ty, Mz) (B,) and, with
        ``fields``, tau and tau_H (B, 2, ny, nx) and the slip mask (B, ny, nx)."""
        patch = self.patch
        C = patch.contact
        X, Y = patch.grid.mesh()
        dA = patch.grid.area
        nx, B, ny = inc_x.shape
        tx, ty = np.zeros((B, ny)), np.zeros((B, ny))
        Tx, Ty, Mz = np.zeros(B), np.zeros(B), np.zeros(B)
        if fields:
            tau, tauH = np.zeros((B, 2, ny, nx)), np.zeros((B, 2, ny, nx))
            slip = np.zeros((B, ny, nx), bool)
        for i in range(nx - 1, -1, -1):
            ins = C[:, i]
            if not ins.any():
                tx[:], ty[:] = 0.0, 0.0
                continue
            hx = np.where(ins, tx + inc_x[i], 0.0)
            hy = np.where(ins, ty + inc_y[i], 0.0)
            mag = np.hypot(hx, hy)
            gi = g[:, i]
            over = mag > gi
            scale = np.where(over, gi / np.where(over, mag, 1.0), 1.0)
            tx, ty = hx * scale, hy * scale
            Tx += tx.sum(axis=1)
            Ty += ty.sum(axis=1)
            Mz += (X[:, i] * ty - Y[:, i] * tx).sum(axis=1)
            if fields:
                tau[:, 0, :, i], tau[:, 1, :, i] = tx, ty
                tauH[:, 0, :, i], tauH[:, 1, :, i] = hx, hy
                slip[:, :, i] = over & ins
        out = (Tx * dA, Ty * dA, Mz * dA)
        return (*out, tau, tauH, slip) if fields else out

    def _increments(
        self, xi: FloatArray, eta: FloatArray, phi: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Traction increments (nx, B, ny) (Pa) of the creepages (B,): the integral of
        w/L over each element's travel; and the factor (B,) <= 1 the creepages were
        scaled by. Creepages whose increments would exceed SATURATION_RATIO times the
        traction bound (rolling.creepage_scale) are brought down to it: every element
        then slips along its increment to rounding, at any larger size alike, and the
        increments stay finite (from creepages of about 1e300 on they overflowed: NaN
        tractions)."""
        X, Y, length, xm = (a.T[:, None, :] for a in self._geometry)
        L1, L2, L3 = self.flexibilities
        # a bound of |increment| / (SATURATION_RATIO max g), each term divided first
        unit = float(length.max()) / (SATURATION_RATIO * float(self.patch.g.max()))
        reach = max(float(np.abs(X).max()), float(np.abs(xm).max()), float(np.abs(Y).max()))
        ratio = (
            np.abs(xi) * (unit / L1) + np.abs(eta) * (unit / L2) + np.abs(phi) * (reach * unit / L3)
        )
        scale = np.where(ratio > 1.0, 1.0 / np.maximum(ratio, 1.0), 1.0)
        xi, eta, phi = (v[None, :, None] * scale[None, :, None] for v in (xi, eta, phi))
        inc_x = (xi / L1 - phi * Y / L3) * length
        inc_y = (eta / L2 + phi * xm / L3) * length
        return inc_x, inc_y, scale

    # ---- public solves ---------------------------------------------------------------------
    def solve(
        self, xi: float, eta: float = 0.0, phi: float = 0.0, check_units: bool = True
    ) -> RollingSolution:
        """FASTSIM for the creepages xi, eta (-) and spin phi (1/m), rolling in +x: the
        RollingSolution of the exact solver (tau, the slip S = L (tau_H - tau) per element
        in m (L1 along x, L2 along y; zero in adhesion), contact, adhesion and slip masks,
        Tx, Ty, Mz as the body's on the substrate; no Newton or GMRES iterations). A spin
        |phi| c below 1e-5 but not zero warns (UnitWarning: rad/mm) unless
        ``check_units=False``."""
        xi, eta, phi = finite("xi", xi), finite("eta", eta), finite("phi", phi)
        if 0.0 < abs(phi) * self.c < SPIN_PLAUSIBLE:
            unit_warning("phi", phi, "rad/mm (here 1/m)", flag("check_units", check_units))
        *inc, scale = self._increments(np.array([xi]), np.array([eta]), np.array([phi]))
        Tx, Ty, Mz, tau, tauH, slip = self._march(*inc, self.patch.g, fields=True)
        L1, L2, _ = self.flexibilities
        S = np.stack([L1 * (tauH[0, 0] - tau[0, 0]), L2 * (tauH[0, 1] - tau[0, 1])])
        S /= scale[0]  # the slip of the creepages asked for
        C = self.patch.contact
        return RollingSolution(
            self.patch.grid,
            tau[0],
            S,
            C,
            C & ~slip[0],
            slip[0],
            float(Tx[0]),
            float(Ty[0]),
            float(Mz[0]),
            0,
            0,
        )

    def forces(
        self, xi: ArrayLike, eta: ArrayLike = 0.0, phi: ArrayLike = 0.0
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """(Tx, Ty, Mz) (N, N m) for creepages broadcast together, one march for all (in
        batches of BATCH_ELEMENTS): a creep curve of 100 points costs about four solves."""
        from .contact import _broadcast

        xi, eta, phi = _broadcast(xi=xi, eta=eta, phi=phi)
        shape = xi.shape
        w = [v.ravel() for v in (xi, eta, phi)]
        out = np.zeros((3, w[0].size))
        # batches of at most BATCH_ELEMENTS increments per component (16 MB)
        step = max(1, BATCH_ELEMENTS // (self.patch.grid.nx * self.patch.grid.ny))
        for k in range(0, w[0].size, step):
            *inc, _ = self._increments(*(v[k : k + step] for v in w))
            out[:, k : k + step] = self._march(*inc, self.patch.g)
        return out[0].reshape(shape), out[1].reshape(shape), out[2].reshape(shape)
