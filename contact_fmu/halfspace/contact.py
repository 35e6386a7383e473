"""The half-space contact law by direct solves: Hertz pressure plus steady rolling.

HalfSpaceContact has the attributes and methods of the ContactLaw protocol of
contact_fmu.integrator (P, mu, a1, a2, p0, creep_full_slip; forces, adhesion_fraction,
with_load), but every call solves the tangential problem (rolling.solve_rolling), a
few tens of milliseconds on a 32 x 32 grid: it is the reference from which
table.CreepTable is built, not a law for time stepping.

Conventions (Spector & Batra 1995): T is the force the body exerts on the substrate
(the body receives -T), in the direction of the rigid slip v = (vx - Omega_z y,
vy + Omega_z x) of Eq. (3). The solver works in the frame rolling in +x; for Vx < 0
the problem is mirrored (x -> -x: vx, Omega_z and Tx, Mz change sign, the Hertz
pressure is even in x). Vx = 0 with v != 0 is pure sliding: every element slides,
tau = mu p v/|v| with the local rigid slip (Eq. 5), the elastic term Vx du/dx of Eq. (2)
being zero.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validate import InputError, finite, nonnegative, positive
from .hertz import CombinedElastic, Hertz, Material, relative_curvatures
from .rolling import (
    NEWTON_TOL,
    RollingPatch,
    RollingSolution,
    ellipse_patch,
    solve_rolling,
)

FloatArray = NDArray[np.float64]

# Default elements of the potential contact area per direction (docs/halfspace.md:
# about 1 % discretisation error of the creep forces on 32 x 32).
DEFAULT_N = 32
# Adhesion fraction at or below which a solution counts as full slip: none of the
# elements adheres (the bisection for the onset resolves one element).
FULL_SLIP_ADHESION = 0.0
# Relative bracket tolerance of the bisection for the onset of full slip (-).
ONSET_RTOL = 1e-4


@dataclass(frozen=True)
class HalfSpaceContact:
    """Elastic body on an elastic substrate, exact half-space theory with layers.

    P: normal load (N); Rx, Ry: principal radii of the body at the contact (m, inf for
    a flat direction); body, substrate: their materials; mu: friction coefficient (-);
    Rsx, Rsy: radii of the substrate (m, default flat); kb, ks: tangential layer
    compliances of Eqs. (6)-(7) (m/Pa); n: elements per direction of the potential
    contact area; coupling: include the pressure-to-tangential coupling B(p) of the
    Appendix (zero for quasi-identical bodies; it breaks the odd symmetry of T).
    """

    P: float
    Rx: float
    Ry: float
    body: Material
    substrate: Material
    mu: float
    Rsx: float = math.inf
    Rsy: float = math.inf
    kb: float = 0.0
    ks: float = 0.0
    n: int = DEFAULT_N
    coupling: bool = True

    def __post_init__(self) -> None:
        positive("P", self.P)
        positive("mu", self.mu)
        nonnegative("kb", self.kb)
        nonnegative("ks", self.ks)
        if int(self.n) != self.n or self.n < 8:
            raise InputError("n", self.n, "an integer >= 8")
        relative_curvatures(self.Rx, self.Ry, self.Rsx, self.Rsy)

    # ---- normal contact ------------------------------------------------------------
    @cached_property
    def elastic(self) -> CombinedElastic:
        return CombinedElastic.of(self.body, self.substrate)

    @cached_property
    def hertz(self) -> Hertz:
        A, B = relative_curvatures(self.Rx, self.Ry, self.Rsx, self.Rsy)
        return Hertz(self.P, A, B, self.elastic.Estar)

    @property
    def a1(self) -> float:
        """Semi-axis along the rolling direction (m)."""
        return self.hertz.a1

    @property
    def a2(self) -> float:
        """Lateral semi-axis (m)."""
        return self.hertz.a2

    @property
    def p0(self) -> float:
        """Hertz peak pressure (Pa)."""
        return self.hertz.p0

    @property
    def c(self) -> float:
        """(a1 a2)^(1/2) (m)."""
        return self.hertz.c

    @property
    def k(self) -> float:
        """kb + ks (m/Pa)."""
        return self.kb + self.ks

    @cached_property
    def patch(self) -> RollingPatch:
        """Hertz pressure on the n x n grid, scaled so that sum p dA = P exactly."""
        e = self.elastic
        patch = ellipse_patch(
            self.a1,
            self.a2,
            self.n,
            self.hertz.pressure,
            self.mu,
            e.G,
            e.nu,
            k=self.k,
            kappa=e.kappa if self.coupling else 0.0,
            P=self.P,
        )
        return patch

    def with_load(self, P: float) -> HalfSpaceContact:
        return self if P == self.P else replace(self, P=positive("P", P))

    # ---- tangential contact ----------------------------------------------------------
    def solve(
        self,
        xi: float,
        eta: float = 0.0,
        phi: float = 0.0,
        tau0: FloatArray | None = None,
        tol: float = NEWTON_TOL,
    ) -> RollingSolution:
        """Steady rolling in +x for creepages xi, eta (-) and spin phi (1/m)."""
        return solve_rolling(self.patch, xi, eta, phi, tau0=tau0, tol=tol)

    def traction(self, vx: float, vy: float, phi: float, Vx: float) -> RollingSolution:
        """The solution for rigid slip (vx, vy) (m/s), Omega_z = phi (rad/s), speed Vx (m/s),
        in the frame of the contact (x along +x of the body frame for every sign of Vx)."""
        vx, vy, phi, Vx = (
            finite(n, v) for n, v in zip(("vx", "vy", "phi", "Vx"), (vx, vy, phi, Vx), strict=True)
        )
        if Vx == 0.0:
            return self._sliding(vx, vy, phi)
        aV = abs(Vx)
        if Vx > 0.0:
            return self.solve(vx / aV, vy / aV, phi / aV)
        sol = self.solve(-vx / aV, vy / aV, -phi / aV)
        return _mirror(sol)

    def forces(
        self, vx: ArrayLike, vy: ArrayLike, phi: ArrayLike, Vx: ArrayLike
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """(Tx, Ty, Mz) in N, N m (Eq. 8 convention), one solve per element of the
        broadcast inputs."""
        vx, vy, phi, Vx = np.broadcast_arrays(*(np.asarray(a, float) for a in (vx, vy, phi, Vx)))
        out = np.zeros((3, *vx.shape))
        for idx in np.ndindex(vx.shape):
            s = self.traction(vx[idx], vy[idx], phi[idx], Vx[idx])
            out[:, *idx] = (s.Tx, s.Ty, s.Mz)
        return out[0], out[1], out[2]

    def adhesion_fraction(self, vx: ArrayLike, vy: ArrayLike, Vx: ArrayLike, phi: ArrayLike = 0.0):
        """Adhesion area over contact area (-)."""
        vx, vy, phi, Vx = np.broadcast_arrays(*(np.asarray(a, float) for a in (vx, vy, phi, Vx)))
        out = np.zeros(vx.shape)
        for idx in np.ndindex(vx.shape):
            out[idx] = self.traction(vx[idx], vy[idx], phi[idx], Vx[idx]).adhesion_fraction
        return out

    @cached_property
    def creep_full_slip(self) -> float:
        """|v|/|Vx| at the onset of full slip (-): the smaller of the longitudinal and the
        lateral onsets (bisection on the adhesion area, to ONSET_RTOL)."""
        return min(self.onset(0.0), self.onset(0.5 * math.pi))

    def onset(self, angle: float) -> float:
        """Creepage magnitude at which the adhesion area vanishes for the creepage
        direction (cos angle, sin angle), no spin (-)."""
        ca, sa = math.cos(angle), math.sin(angle)

        def adh(s: float) -> float:
            return self.solve(s * ca, s * sa).adhesion_fraction

        lo, hi = 0.0, 3.0 * self.mu * self.P / (self.elastic.G * self.c**2)
        while adh(hi) > FULL_SLIP_ADHESION:
            lo, hi = hi, 2.0 * hi
        while hi - lo > ONSET_RTOL * hi:
            mid = 0.5 * (lo + hi)
            if adh(mid) > FULL_SLIP_ADHESION:
                lo = mid
            else:
                hi = mid
        return hi

    def _sliding(self, vx: float, vy: float, phi: float) -> RollingSolution:
        """No rolling: tau = mu p v/|v| at every element with v of Eq. (3)."""
        patch = self.patch
        X, Y = patch.grid.mesh()
        wx, wy = vx - phi * Y, vy + phi * X
        mag = np.hypot(wx, wy)
        C = patch.contact
        moving = C & (mag > 0.0)
        safe = np.where(moving, mag, 1.0)
        tau = np.where(moving, patch.g * np.stack([wx, wy]) / safe, 0.0)
        dA = patch.grid.area
        Tx, Ty = float(tau[0].sum() * dA), float(tau[1].sum() * dA)
        Mz = float(np.sum(X * tau[1] - Y * tau[0]) * dA)
        S = np.stack([wx, wy])
        return RollingSolution(patch.grid, tau, S, C, C & ~moving, moving, Tx, Ty, Mz, 0, 0)

    def linear_coefficients(self) -> tuple[float, float, float]:
        """Kalker's C11, C22, C23 (-) of this patch from full-adhesion solves:
        Tx = G c^2 C11 xi, Ty = G c^2 (C22 eta + c C23 phi) (force on the substrate)."""
        patch = self.patch
        C = patch.contact
        X, _ = patch.grid.mesh()
        dx, dA = patch.grid.dx, patch.grid.area
        out = []
        for a, w in (
            (0, np.where(C, dx, 0.0)),
            (1, np.where(C, dx, 0.0)),
            (1, np.where(C, X * dx, 0.0)),
        ):
            W = np.zeros((2, *patch.grid.shape))
            W[a] = w
            tau, _ = patch.solve_adhesion(W)
            out.append(float(tau[a].sum() * dA))
        G, c = self.elastic.G, self.c
        return out[0] / (G * c * c), out[1] / (G * c * c), out[2] / (G * c**3)


def _mirror(sol: RollingSolution) -> RollingSolution:
    """The solution of the problem mirrored in x (x -> -x): tau_x, S_x, Tx, Mz change sign."""

    def flip(a):
        return a[..., ::-1]

    tau = flip(sol.tau).copy()
    tau[0] *= -1.0
    S = flip(sol.S).copy()
    S[0] *= -1.0
    return RollingSolution(
        sol.grid,
        tau,
        S,
        flip(sol.contact),
        flip(sol.adhesion),
        flip(sol.slip),
        -sol.Tx,
        sol.Ty,
        -sol.Mz,
        sol.newton_iterations,
        sol.gmres_iterations,
        sol.levels,
    )
