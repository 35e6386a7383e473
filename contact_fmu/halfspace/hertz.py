"""Hertz contact of two elastic bodies and the combined elastic constants.

Johnson (1985), Contact Mechanics, Sec. 4.2: the gap between two bodies with
principal radii aligned with x and y is h = A x^2 + B y^2 with the principal relative
curvatures

    A = (1/R_bx + 1/R_sx)/2,   B = (1/R_by + 1/R_sy)/2     (a flat substrate: 1/R_s = 0).

The pressure p = p0 (1 - x^2/a^2 - y^2/b^2)^(1/2) produces the displacement
w = (p0/E*)(L - M x^2 - N y^2) inside the ellipse (Johnson Eqs. 3.57-3.58 with the
semi-axis a >= b along the axis of smaller curvature, e^2 = 1 - b^2/a^2 and the
complete elliptic integrals K(e), E(e)):

    L = b K,   M = b (K - E)/(e^2 a^2),   N = b ((a/b)^2 E - K)/(e^2 a^2).

Matching w to delta - h gives A = p0 M/E*, B = p0 N/E*, delta = p0 L/E*, so

    B/A = ((a/b)^2 E - K)/(K - E),                       (solved for e)
    a^3 = 3 P (K - E)/(2 pi e^2 A E*),  p0 = 3 P/(2 pi a b).

scipy.special.ellipk/ellipe take the parameter m = e^2.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import brentq
from scipy.special import ellipe, ellipk

from .._validate import InputError, finite, positive, real

FloatArray = NDArray[np.float64]

# Curvature ratios within this relative distance of 1 are treated as a circle (e = 0):
# (K - E)/e^2 -> pi/4 there and the root finding for e would lose accuracy.
CIRCLE_RTOL = 1e-12
# Bracket of the eccentricity parameter m = e^2 for brentq; 1 - M_MAX corresponds to a
# semi-axis ratio b/a = 1e-6, far beyond any contact of practical interest.
M_MAX = 1.0 - 1e-12
# Below m = M_LINEAR (b/a > 0.9999995) N/M - 1 loses digits to cancellation and is
# linear in m to 1e-6 relative: Hertz.m interpolates there instead of root finding (a
# bracket down to m = 1e-14 failed for curvature ratios within 1e-7 of 1).
M_LINEAR = 1e-6


class UnitWarning(UserWarning):
    """An input that looks like it was given in another unit than SI (N/mm^2, mm, rad/mm:
    CONTACT's units). A warning, not an error: the value may be meant; silenced by the
    call's ``check_units=False``."""


# Plausibility bounds (SI): moduli below MODULUS_PLAUSIBLE Pa (1 MPa, soft rubber) look
# like N/mm^2 (steel's 210e3 MPa); contact semi-axes above SEMI_AXIS_PLAUSIBLE m look like
# mm (6.0 for 6 mm); spin creepages |phi| c (phi in 1/m, c the contact size) below
# SPIN_PLAUSIBLE but not zero look like rad/mm (CONTACT's unit, 1000 times smaller than
# 1/m; a tread's spin is 0.01-1 1/m, phi c = 1e-4-1e-2).
MODULUS_PLAUSIBLE = 1e6
SEMI_AXIS_PLAUSIBLE = 0.1
SPIN_PLAUSIBLE = 1e-5
# The range (SI) of the scales the solvers compute with: moduli, semi-axes, peak
# pressures and traction bounds mu p0 outside it are refused (InputError), so that the
# products and quotients of a few of them (G c^2, p0/E*, mu P/(G c^2), the influence
# coefficients dx/G) stay finite and normal doubles; outside it the arithmetic overflowed
# or divided by zero. Every physical contact lies tens of orders of magnitude inside.
SCALE_MIN, SCALE_MAX = 1e-100, 1e100
# Largest semi-axis ratio of a contact ellipse given by its semi-axes (Hertz's own
# bracket, M_MAX, ends there as well).
ASPECT_MAX = 1e6


def within_scale(name: str, value: float, unit: str, detail: str = "") -> float:
    """``value`` if within SCALE_MIN .. SCALE_MAX, else InputError naming ``name``
    (``detail``: what the value was derived from, for the message)."""
    if not SCALE_MIN <= value <= SCALE_MAX:
        raise InputError(name, value, f"within {SCALE_MIN:g} .. {SCALE_MAX:g} {unit}{detail}")
    return value


def semi_axes_within_aspect(a1: float, a2: float) -> None:
    """InputError naming a1/a2 when the semi-axes' ratio lies beyond ASPECT_MAX either
    way (1 - e^2 = (minor/major)^2 would lose its digits)."""
    if max(a1, a2) / min(a1, a2) > ASPECT_MAX:
        raise InputError(
            "a1/a2", a1 / a2, f"within {1.0 / ASPECT_MAX:g} .. {ASPECT_MAX:g} (a longer "
            "contact: LineContact)",
        )  # fmt: skip


def traction_bound(mu: float, p0: float) -> float:
    """mu p0 (Pa) if within SCALE_MIN .. SCALE_MAX, else InputError naming mu."""
    g = float(mu) * float(p0)  # Python floats: an overflow is inf, without a warning
    if not SCALE_MIN <= g <= SCALE_MAX:
        raise InputError(
            "mu", mu, f"such that the traction bound mu p0 lies within {SCALE_MIN:g} .. "
            f"{SCALE_MAX:g} Pa (p0 = {p0:g} Pa)",
        )  # fmt: skip
    return g


def unit_warning(name: str, value: float, looks_like: str, check_units: bool) -> None:
    """Warn (UnitWarning) that ``name`` = ``value`` looks like it is in ``looks_like``."""
    if check_units:
        warnings.warn(
            f"{name} = {value!r} looks like {looks_like}; the inputs are SI "
            "(check_units=False silences this)",
            UnitWarning,
            stacklevel=3,
        )


@dataclass(frozen=True, init=False)
class Material:
    """Isotropic elastic material: Young's modulus E (Pa), Poisson's ratio nu (-).

    ``Material(E, nu)``, ``Material(E=..., nu=...)`` or, as CONTACT users give it,
    ``Material(G=..., nu=...)`` with the shear modulus G (Pa) (E = 2 G (1 + nu)); exactly
    one of E and G. A modulus below MODULUS_PLAUSIBLE (1 MPa) warns (UnitWarning: it
    looks like N/mm^2) unless ``check_units=False``."""

    E: float
    nu: float

    def __init__(
        self,
        E: float | None = None,
        nu: float | None = None,
        *,
        G: float | None = None,
        check_units: bool = True,
    ) -> None:
        if nu is None:
            raise InputError("nu", nu, "given (Poisson's ratio, -)")
        nu = finite("nu", nu)
        if not -1.0 < nu <= 0.5:
            raise InputError("nu", nu, "in (-1, 0.5]")
        if (E is None) == (G is None):
            raise InputError("E, G", (E, G), "exactly one of them given (Pa)")
        if E is None:
            G = within_scale("G", positive("G", G), "Pa")
            if G < MODULUS_PLAUSIBLE:
                unit_warning("G", G, "N/mm^2 (MPa)", check_units)
            E = 2.0 * G * (1.0 + nu)
        else:
            E = within_scale("E", positive("E", E), "Pa")
            # G = E/(2 (1 + nu)) as well (nu near -1 makes it large)
            within_scale("E", E / (2.0 * (1.0 + nu)), "Pa", " as the shear modulus G")
            if E < MODULUS_PLAUSIBLE:
                unit_warning("E", E, "N/mm^2 (MPa)", check_units)
        object.__setattr__(self, "E", E)
        object.__setattr__(self, "nu", nu)

    @property
    def G(self) -> float:
        """Shear modulus (Pa)."""
        return self.E / (2.0 * (1.0 + self.nu))


@dataclass(frozen=True)
class CombinedElastic:
    """Kalker's combined constants of body (b) and substrate (s).

    G: 2/G = 1/G_b + 1/G_s (Pa); nu: nu/G = (nu_b/G_b + nu_s/G_s)/2 (-);
    Estar: 1/E* = (1 - nu_b^2)/E_b + (1 - nu_s^2)/E_s (Pa);
    kappa: the difference parameter (G/4)((1 - 2 nu_s)/G_s - (1 - 2 nu_b)/G_b) (-) that
    couples the pressure to the tangential displacement difference (zero for
    quasi-identical bodies).
    """

    G: float
    nu: float
    Estar: float
    kappa: float

    @classmethod
    def of(cls, body: Material, substrate: Material) -> CombinedElastic:
        Gb, Gs = body.G, substrate.G
        G = 2.0 / (1.0 / Gb + 1.0 / Gs)
        nu = 0.5 * G * (body.nu / Gb + substrate.nu / Gs)
        Estar = 1.0 / ((1.0 - body.nu**2) / body.E + (1.0 - substrate.nu**2) / substrate.E)
        kappa = 0.25 * G * ((1.0 - 2.0 * substrate.nu) / Gs - (1.0 - 2.0 * body.nu) / Gb)
        return cls(G, nu, Estar, kappa)

    @classmethod
    def identical(cls, G: float, nu: float) -> CombinedElastic:
        """Two bodies of the same material (shear modulus G, Poisson's ratio nu)."""
        return cls.of(Material(2.0 * G * (1.0 + nu), nu), Material(2.0 * G * (1.0 + nu), nu))


def _curvature(name: str, R: float) -> float:
    """1/R (1/m) for a radius R (m): inf is flat, a negative radius is concave."""
    R = real(name, R)
    if R == 0.0 or math.isnan(R):
        raise InputError(name, R, "non-zero (inf for a flat surface)")
    return 0.0 if math.isinf(R) else 1.0 / R


def relative_curvatures(
    Rx: float, Ry: float, Rsx: float = math.inf, Rsy: float = math.inf
) -> tuple[float, float]:
    """(A, B) in 1/m: A = (1/Rx + 1/Rsx)/2, B = (1/Ry + 1/Rsy)/2 (Johnson Eq. 4.3).

    Rx, Ry: principal radii of the body (m); Rsx, Rsy: of the substrate (m). inf is a
    flat direction, a negative radius a concave surface.
    """
    A = 0.5 * (_curvature("Rx", Rx) + _curvature("Rsx", Rsx))
    B = 0.5 * (_curvature("Ry", Ry) + _curvature("Rsy", Rsy))
    if A <= 0.0 or B <= 0.0:
        raise InputError("(A, B)", (A, B), "> 0 (the bodies must touch at a point)")
    return A, B


def _ratio(m: float) -> float:
    """N/M = ((a/b)^2 E - K)/(K - E) as a function of m = e^2 (a >= b)."""
    K, E = ellipk(m), ellipe(m)
    return (E / (1.0 - m) - K) / (K - E)


@dataclass(frozen=True)
class Hertz:
    """Hertzian contact ellipse under the normal load P (N).

    A, B: principal relative curvatures along x and y (1/m); Estar: combined modulus
    (Pa). Semi-axes a1 (along x, the rolling direction) and a2 (along y) (m), peak
    pressure p0 (Pa), approach delta (m).
    """

    P: float
    A: float
    B: float
    Estar: float

    def __post_init__(self) -> None:
        for name in ("P", "A", "B", "Estar"):
            positive(name, getattr(self, name))

    @cached_property
    def m(self) -> float:
        """e^2 = 1 - (minor/major)^2 of the contact ellipse (-)."""
        ratio = max(self.A, self.B) / min(self.A, self.B)
        if ratio - 1.0 <= CIRCLE_RTOL:
            return 0.0
        r_lo = _ratio(M_LINEAR)
        if ratio <= r_lo:  # nearly circular: N/M - 1 is linear in m below M_LINEAR
            return M_LINEAR * (ratio - 1.0) / (r_lo - 1.0)
        r_hi = _ratio(M_MAX)
        if ratio >= r_hi:  # beyond the bracket: a semi-axis ratio beyond 1e6
            raise InputError(
                "A/B", self.A / self.B,
                f"within {1.0 / r_hi:.4g} .. {r_hi:.4g} (an ellipse of semi-axis ratio up "
                "to 1e6; a longer contact: LineContact)",
            )  # fmt: skip
        return float(brentq(lambda m: _ratio(m) - ratio, M_LINEAR, M_MAX, xtol=1e-15, rtol=1e-15))

    @cached_property
    def _axes(self) -> tuple[float, float, float]:
        """(major, minor, delta) in m."""
        m = self.m
        Amin = min(self.A, self.B)  # the major axis lies along the smaller curvature
        K, E = ellipk(m), ellipe(m)
        kfac = math.pi / 4.0 if m == 0.0 else (K - E) / m
        major = (3.0 * self.P * kfac / (2.0 * math.pi * Amin * self.Estar)) ** (1.0 / 3.0)
        minor = major * math.sqrt(1.0 - m)
        p0 = 3.0 * self.P / (2.0 * math.pi * major * minor)
        delta = p0 * minor * K / self.Estar
        return major, minor, delta

    @property
    def a1(self) -> float:
        """Semi-axis along x (m)."""
        major, minor, _ = self._axes
        return major if self.A <= self.B else minor

    @property
    def a2(self) -> float:
        """Semi-axis along y (m)."""
        major, minor, _ = self._axes
        return minor if self.A <= self.B else major

    @property
    def p0(self) -> float:
        """Peak pressure 3 P/(2 pi a1 a2) (Pa)."""
        return 3.0 * self.P / (2.0 * math.pi * self.a1 * self.a2)

    @property
    def delta(self) -> float:
        """Approach of distant points of the two bodies (m)."""
        return self._axes[2]

    @property
    def c(self) -> float:
        """Kalker's mean radius (a1 a2)^(1/2) (m)."""
        return math.sqrt(self.a1 * self.a2)

    def pressure(self, x: ArrayLike, y: ArrayLike) -> FloatArray:
        """p(x, y) (Pa), zero outside the ellipse."""
        x, y = np.asarray(x, float), np.asarray(y, float)
        r = 1.0 - (x / self.a1) ** 2 - (y / self.a2) ** 2
        return self.p0 * np.sqrt(np.maximum(r, 0.0))

    def gap(self, x: ArrayLike, y: ArrayLike) -> FloatArray:
        """Undeformed gap A x^2 + B y^2 (m)."""
        x, y = np.asarray(x, float), np.asarray(y, float)
        return self.A * x * x + self.B * y * y

    def with_load(self, P: float) -> Hertz:
        return Hertz(P, self.A, self.B, self.Estar)


def ellipse_curvatures(
    a1: float, a2: float, Estar: float, P: float | None = None, delta: float | None = None
) -> tuple[float, float, float]:
    """The principal relative curvatures (A, B) (1/m) and the load P (N) of the Hertz
    contact with semi-axes a1 along x and a2 along y (m), given the load P or the
    approach delta (m) (exactly one): the module's relations read backwards,

        A, B = p0 (M, N)/E* (major axis first),  delta = p0 L/E*,  p0 = 3 P/(2 pi a b),

    L = b K, M = b (K - E)/(e^2 a^2), N = b ((a/b)^2 E - K)/(e^2 a^2), a >= b."""
    a1, a2, Estar = positive("a1", a1), positive("a2", a2), positive("Estar", Estar)
    if (P is None) == (delta is None):
        raise InputError("P, delta", (P, delta), "exactly one of them given")
    semi_axes_within_aspect(a1, a2)
    major, minor = max(a1, a2), min(a1, a2)
    m = 1.0 - (minor / major) ** 2
    K, E = float(ellipk(m)), float(ellipe(m))
    if m < 1e-8:  # circle: (K - E)/e^2 and ((a/b)^2 E - K)/e^2 both tend to pi/4
        fM = fN = math.pi / 4.0
    else:
        fM, fN = (K - E) / m, (E / (1.0 - m) - K) / m
    if P is not None:
        P = positive("P", P)
        p0 = 3.0 * P / (2.0 * math.pi * major * minor)
    else:
        p0 = positive("delta", delta) * Estar / (minor * K)
        P = 2.0 * math.pi * major * minor * p0 / 3.0
    k_major = p0 * minor * fM / (major * major * Estar)
    k_minor = p0 * minor * fN / (major * major * Estar)
    A, B = (k_major, k_minor) if a1 >= a2 else (k_minor, k_major)
    return A, B, P
