"""Creep-force table of the half-space law for co-simulation (no dependency on pythonfmu).

A solve of the steady-rolling problem takes tens of milliseconds; the implicit
integrator calls the contact law tens of times per step. ``build_table`` therefore
precomputes the creep forces with the solver (contact.HalfSpaceContact) on a grid of
normalised creepages and normal loads, and ``CreepTable`` interpolates them.

Normalisation (Kalker's similarity for Hertzian contact): with c = (a1 a2)^(1/2),
xi_ref = mu P/(G c^2) and phi_ref = mu P/(G c^3),

    (Tx, Ty)/(mu P), Mz/(mu P c), adhesion fraction  =  f(xi/xi_ref, eta/xi_ref, phi/phi_ref),

which is exact for layer-free half-spaces (f then does not depend on P or mu, a1/a2
being fixed by the curvatures) and a smooth function of P otherwise. The table holds
f at load nodes P_k; with_load(P) interpolates along log P (cubic spline in the
weights, clamped to the node range: outside it the similarity is extrapolated).

Interpolation in the creepages: tricubic Hermite patches on a tensor grid of nodes,
denser near zero creepage (x = X sinh(beta u)/sinh(beta), u uniform), with nodal
derivatives from the modified Akima rule along each axis (scipy's makima; the cross
derivatives by applying it along the other axes). Any shared nodal derivative data
makes the patches C1 across cell faces; Akima's rule is local, so the kink of the
creep force where the adhesion area vanishes (pure spin: Ty peaks there) does not
ring through the table as it would with a global spline.

Invariants enforced by construction:
* odd symmetry T(-xi, -eta, -phi) = -T(xi, eta, phi) exactly: only half the nodes are
  solved, the other half is their negative, and the evaluation maps the argument to
  the half-space x1 > 0 (or x1 = 0, x2 > 0, ...) and negates;
* |T| <= mu P: the interpolated (fx, fy) is scaled radially by s(m)/m with
  s(m) = m for m <= 1 - d, 1 - d + d h((m - 1 + d)/d) with h(t) = t + t^2 - t^3 for
  1 - d < m < 1, and 1 for m >= 1 (d = SATURATION_WIDTH): C1, monotone, exactly mu P
  where the table is in full slip;
* outside the table (and for Vx = 0): direction-preserving clamping. The normalised
  creepage vector x is scaled by lambda = min(1, min_i X_i/|x_i|) onto the box
  |x_i| <= X_i, which keeps its direction; beyond full slip the force depends on the
  direction of the creepage only (up to the elastic part of the slip, which falls off
  like 1/|x|^2). Vx = 0 (pure sliding) is the limit |x| -> inf of this rule.
"""

from __future__ import annotations

import json
import math
import time
from bisect import bisect_right
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import cached_property, partial
from pathlib import Path
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.interpolate import Akima1DInterpolator, make_interp_spline

from .._validate import InputError, array, count, finite, instance, nonnegative, positive
from .contact import HalfSpaceContact
from .hertz import Hertz
from .rolling import Continuation

FloatArray = NDArray[np.float64]

TABLE_VERSION = 1
# Outputs per node: Tx/(mu P), Ty/(mu P), Mz/(mu P c), adhesion fraction.
OUTPUTS = ("fx", "fy", "mz", "adhesion")
# Width d of the C1 radial saturation below |T| = mu P (fraction of mu P): it changes
# interpolated forces above (1 - d) mu P by at most (4/27) d = 0.3 % of mu P.
SATURATION_WIDTH = 0.02
# Default node counts per creepage axis (odd: the node 0 is on every axis) and the
# default extent of the table in normalised creepage: about three times the onset of
# full slip of the railway contact (0.46) for xi and eta; the lateral force from pure
# spin peaks near 0.5 and falls slowly beyond, so spin gets twice that range.
DEFAULT_NODES = (17, 17, 13)
DEFAULT_EXTENT = (1.5, 1.5, 3.0)
# Node stretching beta of x = X sinh(beta u)/sinh(beta): the spacing at zero is
# beta/sinh(beta) = 0.55 of the uniform one, at the edge beta/tanh(beta) = 2.1 times it
# (the creep force curves bend most at small creepage, and are flat in full slip).
DEFAULT_STRETCH = 2.0
# Newton tolerance of the table's solves (fraction of max mu p): 1e-6 is far below the
# interpolation error (1e-3 and above) and saves about one Newton step per solve.
TABLE_TOL = 1e-6


@dataclass(frozen=True)
class TableData:
    """Everything a CreepTable is made of (what the .npz file holds).

    axes: the node coordinates of the three normalised creepages (each symmetric about
    0, increasing; the box half-widths X_i are the last nodes); P (nP,): load nodes (N);
    values (nP, N1, N2, N3, 4): the OUTPUTS at the nodes;
    onset (nP,): normalised creepage magnitude at the onset of full slip (min of the
    longitudinal and lateral directions); A, B (1/m), Estar, G (Pa), nu, mu, k (m/Pa):
    the contact; n: the solver grid (``HalfSpaceContact.n``: an int n is (n, n)); meta:
    free text (JSON).
    """

    axes: tuple[FloatArray, FloatArray, FloatArray]
    P: FloatArray
    values: FloatArray
    onset: FloatArray
    A: float
    B: float
    Estar: float
    G: float
    nu: float
    mu: float
    k: float
    n: int | tuple[int, int]
    meta: str = "{}"

    @property
    def extent(self) -> FloatArray:
        """Half-widths X_i of the normalised creepage box (3,)."""
        return np.array([float(a[-1]) for a in self.axes])

    @property
    def nodes(self) -> tuple[int, int, int]:
        return tuple(len(a) for a in self.axes)

    @cached_property
    def patches(self) -> list[FloatArray]:
        """Hermite patch coefficients of each load node (see _patches); cached."""
        return [_patches(self.axes, v) for v in self.values]

    def save(self, path: str | Path) -> Path:
        path = Path(path)
        np.savez_compressed(
            path,
            version=np.array(TABLE_VERSION),
            x1=self.axes[0],
            x2=self.axes[1],
            x3=self.axes[2],
            P=self.P,
            values=self.values,
            onset=self.onset,
            scalars=np.array([self.A, self.B, self.Estar, self.G, self.nu, self.mu, self.k]),
            n=np.array(self.n),
            meta=np.array(self.meta),
        )
        return path if path.suffix == ".npz" else path.with_suffix(path.suffix + ".npz")

    @classmethod
    def load(cls, path: str | Path) -> TableData:
        with np.load(Path(path), allow_pickle=False) as f:
            version = int(f["version"])
            if version != TABLE_VERSION:
                raise InputError("table version", version, f"{TABLE_VERSION}")
            A, B, Estar, G, nu, mu, k = (float(v) for v in f["scalars"])
            return cls(
                tuple(np.array(f[k], float) for k in ("x1", "x2", "x3")),
                np.array(f["P"], float),
                np.array(f["values"], float),
                np.array(f["onset"], float),
                A,
                B,
                Estar,
                G,
                nu,
                mu,
                k,
                _grid(f["n"]),
                str(f["meta"]),
            )


def _grid(n: NDArray) -> int | tuple[int, int]:
    """The stored solver grid: an int, or the pair (mx, my)."""
    return int(n) if n.ndim == 0 else (int(n[0]), int(n[1]))


# ---- tricubic Hermite patches ---------------------------------------------------------
# Power-basis coefficients of the cubic Hermite basis on [0, 1]: rows H00, H10, H01,
# H11 (value at 0, slope at 0 times h, value at 1, slope at 1 times h), columns t^0..t^3.
_HERMITE = np.array(
    [[1.0, 0.0, -3.0, 2.0], [0.0, 1.0, -2.0, 1.0], [0.0, 0.0, 3.0, -2.0], [0.0, 0.0, -1.0, 1.0]]
)


def _nodal_derivative(x: FloatArray, data: FloatArray, axis: int) -> FloatArray:
    """d data/dx at the nodes x along ``axis`` by the modified Akima rule (scipy makima);
    two nodes: the chord slope."""
    if len(x) == 2:
        d = np.diff(data, axis=axis) / (x[1] - x[0])
        return np.concatenate([d, d], axis=axis)
    return Akima1DInterpolator(x, data, axis=axis, method="makima").derivative()(x)


def _patches(axes, data: FloatArray) -> FloatArray:
    """Power coefficients (N1-1, N2-1, N3-1, 4, 4, 4, nout) of the tricubic Hermite
    patches of ``data`` (N1, N2, N3, nout): on cell (i, j, k) with local coordinates
    t_a = (x_a - x_a,i)/h_a,i in [0, 1], f = sum C[i, j, k, p, q, r] t1^p t2^q t3^r."""
    d = {}
    for o1 in (0, 1):
        a1 = _nodal_derivative(axes[0], data, 0) if o1 else data
        for o2 in (0, 1):
            a2 = _nodal_derivative(axes[1], a1, 1) if o2 else a1
            for o3 in (0, 1):
                d[(o1, o2, o3)] = _nodal_derivative(axes[2], a2, 2) if o3 else a2
    h = [np.diff(x) for x in axes]
    shape = tuple(len(x) - 1 for x in axes)
    G = np.empty((*shape, 4, 4, 4, data.shape[-1]))
    for a in range(4):
        c1, o1 = divmod(a, 2)
        for b in range(4):
            c2, o2 = divmod(b, 2)
            for c in range(4):
                c3, o3 = divmod(c, 2)
                arr = d[(o1, o2, o3)][c1 : c1 + shape[0], c2 : c2 + shape[1], c3 : c3 + shape[2]]
                # derivative data scaled by the cell widths (Hermite basis on [0, 1])
                scale = (
                    (h[0] if o1 else np.ones(shape[0]))[:, None, None]
                    * (h[1] if o2 else np.ones(shape[1]))[None, :, None]
                    * (h[2] if o3 else np.ones(shape[2]))[None, None, :]
                )
                G[:, :, :, a, b, c] = arr * scale[..., None]
    # one axis at a time (a single four-operand einsum is 50 times slower)
    G = np.einsum("...abco,ap->...pbco", G, _HERMITE)
    G = np.einsum("...pbco,bq->...pqco", G, _HERMITE)
    return np.einsum("...pqco,cr->...pqro", G, _HERMITE)


def saturate(m: FloatArray, width: float = SATURATION_WIDTH) -> FloatArray:
    """The C1 radial saturation s(m) <= 1 of the module docstring (m >= 0)."""
    t = np.clip((m - (1.0 - width)) / width, 0.0, 1.0)
    s = 1.0 - width + width * (t + t * t - t**3)
    return np.where(m <= 1.0 - width, m, np.where(m >= 1.0, 1.0, s))


@dataclass(frozen=True)
class CreepTable:
    """Table-based half-space contact law at the normal load P (N): the ContactLaw
    protocol of contact_fmu.laws.protocol.

    forces(vx, vy, phi, Vx) -> (Tx, Ty, Mz) (N, N, N m) for rigid slip (vx, vy) (m/s),
    spin phi = Omega_z (rad/s) and rolling speed Vx (m/s), vectorised over broadcast
    arrays; adhesion_fraction(vx, vy, Vx, phi=0); with_load(P). Attributes P, mu, a1,
    a2, p0 (Hertz at P), c, creep_full_slip (|v|/|Vx| at the onset of full slip, the
    smaller of the longitudinal and lateral onsets).
    """

    data: TableData
    P: float
    _coef: FloatArray = field(repr=False, compare=False, default=None)
    # the compiled stepper (contact_fmu/native) covers this law without spin (LAW_TABLE)
    native_constants: ClassVar[dict[str, float]] = {"saturation_width": SATURATION_WIDTH}

    def native_fields(self) -> dict[str, float]:
        """This table at its load for the compiled stepper: addresses of its patch
        coefficients and axes (kept alive by this object), sizes, box and units."""
        coef, axes = self._coef_flat, self._native_axes
        return {
            "law": 1,
            "mu": self.mu,
            "P": self.P,
            "a1": self.a1,
            "creep_full_slip": self.creep_full_slip,
            "coef": coef.ctypes.data,
            **{f"ax{i + 1}": a.ctypes.data for i, a in enumerate(axes)},
            **{f"n{i + 1}": len(a) for i, a in enumerate(axes)},
            **{f"ext{i + 1}": x for i, x in enumerate(self._extent)},
            "xi_ref": self.xi_ref,
            "phi_ref": self.phi_ref,
            "c": self.c,
        }

    @cached_property
    def _native_axes(self) -> tuple[FloatArray, ...]:
        return tuple(np.ascontiguousarray(a, dtype=float) for a in self.data.axes)

    def __post_init__(self) -> None:
        nonnegative("P", self.P)  # P = 0: lift-off, no contact (``lifted``)
        if self._coef is None:
            object.__setattr__(self, "_coef", self._coefficients_at(self.P))

    # ---- construction ------------------------------------------------------------------
    @classmethod
    def load(cls, path: str | Path, P: float | None = None) -> CreepTable:
        """Read a table written by save (or TableData.save); P defaults to the first node."""
        data = TableData.load(path)
        return cls(data, float(data.P[0]) if P is None else P)

    def save(self, path: str | Path) -> Path:
        return self.data.save(path)

    def with_load(self, P: float) -> CreepTable:
        if P == self.P:
            return self
        return replace(self, P=nonnegative("P", P), _coef=None)

    @property
    def lifted(self) -> bool:
        """P = 0: lift-off, no contact; every force, the contact ellipse and the
        adhesion are zero (the limit P -> 0+: |T| <= mu P)."""
        return self.P == 0.0

    def _weights(self, P: float) -> FloatArray:
        """Interpolation weights of the load nodes at P (log P, clamped to the nodes)."""
        nodes = np.log(self.data.P)
        if len(nodes) == 1:
            return np.ones(1)
        lp = float(np.clip(math.log(P), nodes[0], nodes[-1])) if P > 0.0 else float(nodes[0])
        spl = make_interp_spline(nodes, np.eye(len(nodes)), k=min(3, len(nodes) - 1))
        return np.asarray(spl(lp), float)

    def _coefficients_at(self, P: float) -> FloatArray:
        """Patch coefficients at the load P: the weighted sum of the load nodes' patches
        (computed once per table and shared by with_load)."""
        patches = self.data.patches
        if len(patches) == 1:
            return patches[0]
        w = self._weights(P)
        return sum(wk * pk for wk, pk in zip(w, patches, strict=True))

    # ---- contact geometry at P -----------------------------------------------------------
    @cached_property
    def hertz(self) -> Hertz:
        return Hertz(self.P, self.data.A, self.data.B, self.data.Estar)

    @property
    def mu(self) -> float:
        return self.data.mu

    @property
    def a1(self) -> float:
        return 0.0 if self.lifted else self.hertz.a1

    @property
    def a2(self) -> float:
        return 0.0 if self.lifted else self.hertz.a2

    @property
    def p0(self) -> float:
        return 0.0 if self.lifted else self.hertz.p0

    @property
    def c(self) -> float:
        return 0.0 if self.lifted else self.hertz.c

    @cached_property
    def xi_ref(self) -> float:
        """mu P/(G c^2) (-): the unit of the normalised creepages (0 at P = 0)."""
        if self.lifted:
            return 0.0
        return self.mu * self.P / (self.data.G * self.c**2)

    @cached_property
    def phi_ref(self) -> float:
        """mu P/(G c^3) (1/m): the unit of the normalised spin (0 at P = 0)."""
        if self.lifted:
            return 0.0
        return self.xi_ref / self.c

    @cached_property
    def creep_full_slip(self) -> float:
        w = self._weights(self.P)
        return float(np.dot(w, self.data.onset)) * self.xi_ref

    # ---- evaluation ------------------------------------------------------------------------
    def _normalised(self, vx, vy, phi, Vx):
        """Normalised creepages in the frame rolling in +x and the mirror sign of Vx."""
        vx, vy, phi, Vx = np.broadcast_arrays(*(np.asarray(a, float) for a in (vx, vy, phi, Vx)))
        sV = np.where(Vx < 0.0, -1.0, 1.0)
        aV = np.abs(Vx)
        X = self.data.extent
        with np.errstate(over="ignore"):
            d = np.stack([sV * vx / self.xi_ref, vy / self.xi_ref, sV * phi / self.phi_ref])
        big = ~np.all(np.isfinite(d), axis=0)
        if np.any(big):  # slips beyond double range in table units: as _scalar
            m = np.where(big, np.maximum(np.maximum(np.abs(vx), np.abs(vy)), np.abs(phi)), 1.0)
            aV = aV / m
            d = np.stack([sV * (vx / m) / self.xi_ref, (vy / m) / self.xi_ref,
                          sV * (phi / m) / self.phi_ref])  # fmt: skip
        # direction-preserving clamp onto the box, as _scalar: inside it x = d/|Vx|, else
        # x = d lam on its face (Vx = 0: the limit; no product lam |Vx| that underflows)
        Xb = X.reshape((3,) + (1,) * (d.ndim - 1))
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            lam = np.min(np.where(np.abs(d) > 0.0, Xb / np.abs(d), np.inf), axis=0)
            inside = (aV > 0.0) & (lam * aV >= 1.0) & np.isfinite(lam)
            face = np.where(np.isfinite(lam), lam, 0.0)
            x = np.where(inside, d / np.where(inside, aV, 1.0), d * face)
        return x, sV

    def _evaluate(self, x: FloatArray) -> FloatArray:
        """Interpolated OUTPUTS (..., 4) at normalised creepages x (3, ...) inside the box."""
        shape = x.shape[1:]
        x = x.reshape(3, -1)
        # odd symmetry: map to the half-space x1 > 0 or (x1 = 0, x2 > 0) or (0, 0, x3 >= 0)
        neg = (x[0] < 0) | ((x[0] == 0) & ((x[1] < 0) | ((x[1] == 0) & (x[2] < 0))))
        sg = np.where(neg, -1.0, 1.0)
        y = x * sg
        idx = np.empty(y.shape, dtype=int)
        t = np.empty(y.shape)
        for a, ax in enumerate(self.data.axes):
            i = np.clip(np.searchsorted(ax, y[a], side="right") - 1, 0, len(ax) - 2)
            idx[a] = i
            t[a] = (y[a] - ax[i]) / (ax[i + 1] - ax[i])
        C = self._coef[idx[0], idx[1], idx[2]]  # (M, 4, 4, 4, 4)
        T = [np.stack([np.ones_like(ti), ti, ti * ti, ti * ti * ti], axis=-1) for ti in t]
        r = np.einsum("mpqro,mr->mpqo", C, T[2])
        r = np.einsum("mpqo,mq->mpo", r, T[1])
        f = np.einsum("mpo,mp->mo", r, T[0])
        f[:, :3] *= sg[:, None]
        return f.reshape(*shape, 4)

    def normalised_forces(self, x1: ArrayLike, x2: ArrayLike, x3: ArrayLike) -> FloatArray:
        """(fx, fy, mz, adhesion) (..., 4) at normalised creepages (clamped, saturated)."""
        x = np.stack(np.broadcast_arrays(*(np.asarray(a, float) for a in (x1, x2, x3))))
        X = self.data.extent.reshape((3,) + (1,) * x[0].ndim)
        with np.errstate(divide="ignore", invalid="ignore"):
            ratios = np.where(np.abs(x) > 0.0, X / np.abs(x), np.inf)
        x = x * np.minimum(np.min(ratios, axis=0), 1.0)
        return self._finish(self._evaluate(x))

    @staticmethod
    def _finish(f: FloatArray) -> FloatArray:
        m = np.hypot(f[..., 0], f[..., 1])
        scale = np.where(m > 0.0, saturate(m) / np.where(m > 0.0, m, 1.0), 1.0)
        out = f.copy()
        out[..., 0] *= scale
        out[..., 1] *= scale
        out[..., 3] = np.clip(out[..., 3], 0.0, 1.0)
        return out

    @cached_property
    def _coef_flat(self) -> FloatArray:
        """Patch coefficients as (N1-1, N2-1, N3-1, 64, 4) for the scalar path."""
        c = self._coef
        return np.ascontiguousarray(c.reshape(*c.shape[:3], 64, c.shape[-1]))

    def _scalar(self, vx: float, vy: float, phi: float, Vx: float) -> tuple[float, ...]:
        """The same rules as the array path, for scalar arguments (math + one dot)."""
        if self.lifted:  # no contact
            return 0.0, 0.0, 0.0, 0.0
        sV = -1.0 if Vx < 0.0 else 1.0
        aV = abs(Vx)
        d1, d2, d3 = sV * vx / self.xi_ref, vy / self.xi_ref, sV * phi / self.phi_ref
        if not (math.isfinite(d1) and math.isfinite(d2) and math.isfinite(d3)):
            # slips beyond double range in table units: v and Vx over their largest
            # (the same creepages, a direction within range)
            m = max(abs(vx), abs(vy), abs(phi))
            aV = aV / m
            d1, d2, d3 = (
                sV * (vx / m) / self.xi_ref,
                (vy / m) / self.xi_ref,
                sV * (phi / m) / self.phi_ref,
            )
        X1, X2, X3 = self._extent
        lam = math.inf
        for d, Xi in ((d1, X1), (d2, X2), (d3, X3)):
            if d != 0.0:
                lam = min(lam, Xi / abs(d))
        if lam == math.inf:  # no slip at all
            lam = 0.0
        elif aV > 0.0 and lam * aV >= 1.0:  # inside the box: x = d/|Vx|
            lam = 1.0 / aV
        # else on the box's face, x = d lam, whatever Vx (lam |Vx| may underflow: no
        # product with it; Vx = 0 is the limit)
        x1, x2, x3 = d1 * lam, d2 * lam, d3 * lam
        sg = 1.0
        if x1 < 0.0 or (x1 == 0.0 and (x2 < 0.0 or (x2 == 0.0 and x3 < 0.0))):
            sg, x1, x2, x3 = -1.0, -x1, -x2, -x3
        (A1, A2, A3) = self._axes_lists
        i1 = min(max(bisect_right(A1, x1) - 1, 0), len(A1) - 2)
        i2 = min(max(bisect_right(A2, x2) - 1, 0), len(A2) - 2)
        i3 = min(max(bisect_right(A3, x3) - 1, 0), len(A3) - 2)
        t1 = (x1 - A1[i1]) / (A1[i1 + 1] - A1[i1])
        t2 = (x2 - A2[i2]) / (A2[i2 + 1] - A2[i2])
        t3 = (x3 - A3[i3]) / (A3[i3 + 1] - A3[i3])
        w = np.multiply.outer(
            np.multiply.outer((1.0, t1, t1 * t1, t1 * t1 * t1), (1.0, t2, t2 * t2, t2 * t2 * t2)),
            (1.0, t3, t3 * t3, t3 * t3 * t3),
        ).ravel()
        fx, fy, mz, adh = (float(v) for v in w @ self._coef_flat[i1, i2, i3])
        fx, fy, mz = sg * fx, sg * fy, sg * mz
        m = math.hypot(fx, fy)
        if m > 1.0 - SATURATION_WIDTH:
            s = float(saturate(np.array(m)))
            fx, fy = fx * s / m, fy * s / m
        muP = self.mu * self.P
        return sV * muP * fx, muP * fy, sV * muP * self.c * mz, min(max(adh, 0.0), 1.0)

    def tx_slope(self, vx: float, vy: float, Vx: float) -> tuple[float, float, float, float]:
        """Tx (N) and its partial derivatives (dTx/dvx, dTx/dvy, dTx/dVx) for floats, no
        spin: the optional slope the integrator's Newton iterations use (cf.
        LayerContact.tx_slope). Exact derivatives of the Hermite patch, the radial
        saturation and the clamp; on a cell face or the box face the one-sided value of
        the cell the point falls in. Vx != 0."""
        if self.lifted:
            return 0.0, 0.0, 0.0, 0.0
        vx, vy, Vx = float(vx), float(vy), float(Vx)
        if Vx == 0.0:
            raise InputError("Vx", Vx, "!= 0 for the slope")
        sV = -1.0 if Vx < 0.0 else 1.0
        aV = abs(Vx)
        xr = self.xi_ref
        d = (sV * vx / xr, vy / xr)
        ext = self._extent
        lam, j = math.inf, -1
        for i in (0, 1):
            if d[i] != 0.0 and ext[i] / abs(d[i]) < lam:
                lam, j = ext[i] / abs(d[i]), i
        dd = (sV / xr, 1.0 / xr)  # d d_i / d(vx, vy)_i
        if j < 0 or lam * aV >= 1.0:  # inside the box: x = d/|Vx|
            x = (d[0] / aV, d[1] / aV)
            J = ((dd[0] / aV, 0.0, -x[0] * sV / aV), (0.0, dd[1] / aV, -x[1] * sV / aV))
        else:  # clamped onto the face of axis j: x = d X_j/|d_j|, independent of Vx
            x = (d[0] * lam, d[1] * lam)
            J = tuple(
                tuple(lam * ((i == k) - (d[i] / d[j] if k == j else 0.0)) * dd[k] for k in (0, 1))
                + (0.0,)
                for i in (0, 1)
            )
        x1, x2 = x
        sg = 1.0
        if x1 < 0.0 or (x1 == 0.0 and x2 < 0.0):
            sg, x1, x2 = -1.0, -x1, -x2
        A1, A2, A3 = self._axes_lists
        i1 = min(max(bisect_right(A1, x1) - 1, 0), len(A1) - 2)
        i2 = min(max(bisect_right(A2, x2) - 1, 0), len(A2) - 2)
        i3 = min(max(bisect_right(A3, 0.0) - 1, 0), len(A3) - 2)
        h1, h2 = A1[i1 + 1] - A1[i1], A2[i2 + 1] - A2[i2]
        t1, t2 = (x1 - A1[i1]) / h1, (x2 - A2[i2]) / h2
        t3 = (0.0 - A3[i3]) / (A3[i3 + 1] - A3[i3])
        T1, dT1 = (1.0, t1, t1 * t1, t1**3), (0.0, 1.0, 2.0 * t1, 3.0 * t1 * t1)
        T2, dT2 = (1.0, t2, t2 * t2, t2**3), (0.0, 1.0, 2.0 * t2, 3.0 * t2 * t2)
        T3 = (1.0, t3, t3 * t3, t3**3)
        C = self._coef_flat[i1, i2, i3][:, :2]  # (64, 2): fx, fy
        f = np.multiply.outer(np.multiply.outer(T1, T2), T3).ravel() @ C
        g1 = np.multiply.outer(np.multiply.outer(dT1, T2), T3).ravel() @ C / h1
        g2 = np.multiply.outer(np.multiply.outer(T1, dT2), T3).ravel() @ C / h2
        # f(x) = sg F(sg x): the value changes sign, the gradient does not
        fx, fy = sg * float(f[0]), sg * float(f[1])
        dfx = (float(g1[0]), float(g2[0]))
        dfy = (float(g1[1]), float(g2[1]))
        m = math.hypot(fx, fy)
        w = SATURATION_WIDTH
        if m > 1.0 - w:
            tt = min((m - (1.0 - w)) / w, 1.0)
            s = 1.0 - w + w * (tt + tt * tt - tt**3) if m < 1.0 else 1.0
            ds = 1.0 + 2.0 * tt - 3.0 * tt * tt if m < 1.0 else 0.0
            S, dS = s / m, (ds * m - s) / (m * m)
            dox = (S + fx * dS * fx / m, fx * dS * fy / m)  # d out_x/d(fx, fy)
            out = fx * S
        else:
            dox, out = (1.0, 0.0), fx
        dx_out = [dox[0] * dfx[a] + dox[1] * dfy[a] for a in (0, 1)]  # d out_x/d x_a
        muP = self.mu * self.P
        grad = [sV * muP * (dx_out[0] * J[0][k] + dx_out[1] * J[1][k]) for k in range(3)]
        return sV * muP * out, grad[0], grad[1], grad[2]

    @cached_property
    def _extent(self) -> tuple[float, float, float]:
        return tuple(float(v) for v in self.data.extent)

    @cached_property
    def _axes_lists(self) -> tuple[list[float], list[float], list[float]]:
        return tuple([float(v) for v in ax] for ax in self.data.axes)

    def forces(
        self, vx: ArrayLike, vy: ArrayLike, phi: ArrayLike, Vx: ArrayLike
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """(Tx, Ty, Mz) (N, N, N m) in the convention of Eq. (8), see the class docstring.

        Scalar arguments take a fast path (floats out); arrays broadcast."""
        if all(
            isinstance(a, (float, int)) or (isinstance(a, np.generic)) for a in (vx, vy, phi, Vx)
        ):
            Tx, Ty, Mz, _ = self._scalar(float(vx), float(vy), float(phi), float(Vx))
            return Tx, Ty, Mz
        if self.lifted:
            z = np.zeros(np.broadcast(*(np.asarray(a, float) for a in (vx, vy, phi, Vx))).shape)
            return z, z.copy(), z.copy()
        x, sV = self._normalised(vx, vy, phi, Vx)
        f = self._finish(self._evaluate(x))
        muP = self.mu * self.P
        Tx = sV * muP * f[..., 0]
        Ty = muP * f[..., 1]
        Mz = sV * muP * self.c * f[..., 2]
        return Tx, Ty, Mz

    def adhesion_fraction(
        self, vx: ArrayLike, vy: ArrayLike, Vx: ArrayLike, phi: ArrayLike = 0.0
    ) -> FloatArray:
        """Adhesion area over contact area (-), interpolated."""
        if all(
            isinstance(a, (float, int)) or (isinstance(a, np.generic)) for a in (vx, vy, phi, Vx)
        ):
            return self._scalar(float(vx), float(vy), float(phi), float(Vx))[3]
        if self.lifted:
            return np.zeros(np.broadcast(*(np.asarray(a, float) for a in (vx, vy, phi, Vx))).shape)
        x, _ = self._normalised(vx, vy, phi, Vx)
        return self._finish(self._evaluate(x))[..., 3]


# ---- building ------------------------------------------------------------------------------
def _table_task(contacts, axes, task) -> FloatArray | float:
    """One task of a build: (load index, nodes of one line of x1 from its centre out)
    -> the OUTPUTS at those nodes (len, 4), each solve started from the secant
    prediction of the last two (``rolling.Continuation``);
    (load index, None) -> the normalised onset of full slip at that load."""
    ip, line = task
    ck = contacts[ip]
    xref = ck.mu * ck.P / (ck.elastic.G * ck.c**2)
    if line is None:
        return min(ck.onset(0.0), ck.onset(0.5 * math.pi)) / xref
    pref = xref / ck.c
    muP, c = ck.mu * ck.P, ck.c
    out = np.empty((len(line), 4))
    cont = Continuation(ck.patch)  # the nodes of a line lie on it: secant predictions
    for i, (k1, k2, k3) in enumerate(line):
        s = cont.solve(axes[0][k1] * xref, axes[1][k2] * xref, axes[2][k3] * pref, TABLE_TOL)
        out[i] = (s.Tx / muP, s.Ty / muP, s.Mz / (muP * c), s.adhesion_fraction)
    return out


def _half_nodes(N: tuple[int, int, int]) -> list[tuple[int, int, int]]:
    """Node indices with x > 0 in the order (x1, then x2, then x3) of odd symmetry, plus
    the centre; each line of x1 is listed from its centre outwards (warm starts)."""
    c = [n // 2 for n in N]
    out = []
    for k3 in range(N[2]):
        for k2 in range(N[1]):
            for k1 in range(c[0], N[0]):
                if k1 == c[0] and (k2 < c[1] or (k2 == c[1] and k3 < c[2])):
                    continue
                out.append((k1, k2, k3))
    return out


def build_table(
    contact: HalfSpaceContact,
    loads: ArrayLike | None = None,
    xi_max: float | None = None,
    eta_max: float | None = None,
    phi_max: float | None = None,
    nodes: tuple[int, int, int] = DEFAULT_NODES,
    stretch: float = DEFAULT_STRETCH,
    progress: Callable[[int, int], None] | None = None,
    map_tasks: Callable[[Callable, list], list] | None = None,
) -> CreepTable:
    """Creep-force table of ``contact`` (direct solves on its n x n grid).

    loads: load nodes (N), default [contact.P]; with layers (kb + ks > 0) the
    similarity in P is only approximate, so give at least two nodes spanning the loads
    of the scene. xi_max, eta_max (-), phi_max (1/m): the creepage range to cover at the
    smallest load (the normalised box is the same for all loads, so larger loads are
    covered too); default DEFAULT_EXTENT in normalised units. nodes: odd node counts per
    axis; stretch: beta of the node distribution (0: uniform). Cost: about prod(nodes)/2
    solves per load node plus two bisections for the onset of full slip, see
    docs/halfspace.md.
    Coupling B(p) is switched off (quasi-identity) so that T is odd in the creepages.
    map_tasks(fn, tasks) -> [fn(t) for t in tasks] runs the independent solves elsewhere
    (contact_fmu.study.engine); the table is the same as the serial build's.
    progress(done, total) (serial build): solves done.
    """
    instance("contact", contact, HalfSpaceContact, "a HalfSpaceContact")
    contact = replace(contact, coupling=False)
    loads = array("loads", [contact.P] if loads is None else loads).ravel()
    loads.sort()
    if np.any(loads <= 0.0) or len(np.unique(loads)) != len(loads):
        raise InputError("loads", loads.tolist(), "distinct and > 0")
    if contact.k > 0.0 and len(loads) < 2:
        raise InputError("loads", loads.tolist(), "at least two nodes when kb + ks > 0")
    if isinstance(nodes, str | bytes) or not hasattr(nodes, "__len__") or len(nodes) != 3:
        raise InputError("nodes", nodes, "three odd integers >= 3")
    nodes = tuple(count("nodes", n, 3) for n in nodes)
    if any(n % 2 == 0 for n in nodes):
        raise InputError("nodes", nodes, "odd and >= 3 per axis")
    c0 = contact.with_load(float(loads[0]))
    xref0 = c0.mu * c0.P / (c0.elastic.G * c0.c**2)
    pref0 = xref0 / c0.c
    extent = np.array(DEFAULT_EXTENT, float)
    for i, (val, ref) in enumerate(((xi_max, xref0), (eta_max, xref0), (phi_max, pref0))):
        if val is not None:
            name = ("xi_max", "eta_max", "phi_max")[i]
            extent[i] = positive(name, abs(finite(name, val))) / ref
    beta = nonnegative("stretch", stretch)
    u = [np.linspace(-1.0, 1.0, n) for n in nodes]
    if beta > 0.0:
        axes = [X * np.sinh(beta * ui) / math.sinh(beta) for X, ui in zip(extent, u, strict=True)]
    else:
        axes = [X * ui for X, ui in zip(extent, u, strict=True)]
    for a in axes:  # exact symmetry of the nodes about 0
        a[:] = 0.5 * (a - a[::-1])
    half = _half_nodes(nodes)
    total = len(half) * len(loads)
    contacts = [contact.with_load(float(P)) for P in loads]
    # Independent tasks: each line of x1 (its solves warm-started along it, as in one
    # sequence) and each load's onset of full slip; ``map_tasks`` may run them anywhere.
    lines: dict[tuple[int, int], list[tuple[int, int, int]]] = {}
    for node in half:
        lines.setdefault((node[1], node[2]), []).append(node)
    tasks = [(ip, tuple(line)) for ip in range(len(loads)) for line in lines.values()]
    tasks += [(ip, None) for ip in range(len(loads))]
    work = partial(_table_task, tuple(contacts), tuple(axes))
    t0 = time.perf_counter()
    if map_tasks is None:
        results, done = [], 0
        for task in tasks:
            results.append(work(task))
            done += len(task[1] or ())
            if progress is not None and task[1] is not None:
                progress(done, total)
    else:
        results = map_tasks(work, tasks)
    values = np.zeros((len(loads), *nodes, 4))
    onset = np.zeros(len(loads))
    for (ip, line), res in zip(tasks, results, strict=True):
        if line is None:
            onset[ip] = res
            continue
        for (k1, k2, k3), v in zip(line, res, strict=True):
            values[ip, k1, k2, k3] = v
            m = (nodes[0] - 1 - k1, nodes[1] - 1 - k2, nodes[2] - 1 - k3)
            values[ip, m[0], m[1], m[2]] = (-v[0], -v[1], -v[2], v[3])
    e = contact.elastic
    meta = json.dumps(
        {
            "solves": total,
            "seconds": round(time.perf_counter() - t0, 3),
            "grid": contact.n,
            "Rx": contact.Rx,
            "Ry": contact.Ry,
            "Rsx": contact.Rsx,
            "Rsy": contact.Rsy,
        },
        default=str,
    )
    data = TableData(
        tuple(axes),
        loads,
        values,
        onset,
        contact.hertz.A,
        contact.hertz.B,
        e.Estar,
        e.G,
        e.nu,
        contact.mu,
        contact.k,
        contact.n,
        meta,
    )
    return CreepTable(data, contact.P)
