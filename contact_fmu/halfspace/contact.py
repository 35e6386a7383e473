"""The half-space contact law by direct solves: Hertz pressure plus steady rolling.

HalfSpaceContact has the attributes and methods of the ContactLaw protocol of
contact_fmu.laws.protocol (P, mu, a1, a2, p0, creep_full_slip; forces, adhesion_fraction,
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
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validate import (
    InputError,
    array,
    count,
    counts,
    finite,
    flag,
    instance,
    nonnegative,
    positive,
)
from .hertz import (
    SCALE_MAX,
    SEMI_AXIS_PLAUSIBLE,
    SPIN_PLAUSIBLE,
    CombinedElastic,
    Hertz,
    Material,
    ellipse_curvatures,
    relative_curvatures,
    traction_bound,
    unit_warning,
    within_scale,
)
from .rolling import (
    NEWTON_TOL,
    Continuation,
    RollingPatch,
    RollingSolution,
    ellipse_patch,
    solve_rolling,
)

FloatArray = NDArray[np.float64]

# Default elements of the potential contact area per direction (docs/halfspace.md:
# about 1 % discretisation error of the creep forces on 32 x 32).
DEFAULT_N = 32
# creepages_for (Newton on the forces): convergence on max |T - F| in units of mu P;
# the tolerance of its solves (relative to max g, as NEWTON_TOL), so that the forces'
# solver noise (about this of mu P) stays 1e-4 of the difference quotients of step
# FORCE_FD_STEP (in units of mu P/(G c^2), at least that of the creepage) even at 0.99 mu
# P, where dT/dxi is a tenth of its linear value; Newton iteration cap; backtracking
# (sufficient decrease on |r| and the smallest step fraction).
FORCE_RTOL = 1e-8
FORCE_SOLVE_TOL = 1e-9
FORCE_FD_STEP = 1e-4
FORCE_MAXIT = 30
FORCE_ARMIJO = 1e-4
FORCE_MIN_STEP = 1.0 / 64.0
# Fewest elements per direction of a grid.
MIN_N = 8
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
    compliances of Eqs. (6)-(7) (m/Pa); coupling: include the pressure-to-tangential
    coupling B(p) of the Appendix (zero for quasi-identical bodies; it breaks the odd
    symmetry of T).

    n: the grid, ``(mx, my)``: mx elements along x and my along y over the potential
    contact area, the Hertz ellipse's bounding box with one element to spare on each
    side along x (the rolling direction) and none along y (``rolling.ellipse_patch``):
    dx = 2 a1/(mx - 2), dy = 2 a2/my. An int n is the grid (n, n).

    Other ways in: ``from_ellipse`` (semi-axes and the load or the approach),
    ``from_curvatures`` (the relative curvatures A, B).
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
    n: int | tuple[int, int] = DEFAULT_N
    coupling: bool = True

    def __post_init__(self) -> None:
        positive("P", self.P)
        instance("body", self.body, Material, "a halfspace.Material")
        instance("substrate", self.substrate, Material, "a halfspace.Material")
        positive("mu", self.mu)
        nonnegative("kb", self.kb)
        nonnegative("ks", self.ks)
        if isinstance(self.n, int | np.integer) and not isinstance(self.n, bool):
            count("n", self.n, MIN_N)
        else:
            object.__setattr__(self, "n", counts("n", self.n, MIN_N))
        flag("coupling", self.coupling)
        relative_curvatures(self.Rx, self.Ry, self.Rsx, self.Rsy)
        # the contact's scales within the solvers' range (hertz.SCALE_MIN .. SCALE_MAX)
        h = self.hertz
        source = f" (the Hertz contact of P = {self.P:g} N, Rx = {self.Rx:g} m, Ry = {self.Ry:g} m)"
        within_scale("a1", h.a1, "m", source)
        within_scale("a2", h.a2, "m", source)
        within_scale("p0", h.p0, "Pa", source)
        traction_bound(self.mu, h.p0)
        if self.k * float(h.p0) > SCALE_MAX:  # the layers' displacement under p0, in m
            raise InputError(
                "kb + ks",
                self.k,
                f"such that (kb + ks) p0 is at most {SCALE_MAX:g} m (p0 = {h.p0:g} Pa)",
            )

    @classmethod
    def from_curvatures(
        cls, A: float, B: float, body: Material, substrate: Material, mu: float, P: float, **kw
    ) -> HalfSpaceContact:
        """The contact of the principal relative curvatures A along x and B along y
        (1/m; the gap is A x^2 + B y^2, Johnson Eq. 4.3) at the load P (N). ``kw``: the
        other fields (kb, ks, n, coupling)."""
        A, B = positive("A", A), positive("B", B)
        _no_radii(kw)
        return cls(P, 0.5 / A, 0.5 / B, body, substrate, mu, **kw)

    @classmethod
    def from_ellipse(
        cls,
        a1: float,
        a2: float,
        body: Material,
        substrate: Material,
        mu: float,
        P: float | None = None,
        delta: float | None = None,
        check_units: bool = True,
        **kw,
    ) -> HalfSpaceContact:
        """The Hertz contact with semi-axes a1 along x (rolling) and a2 along y (m),
        given its normal load P (N) or its approach delta (m) (one of the two): the
        curvatures follow from ``hertz.ellipse_curvatures``, and ``a1``, ``a2`` of the
        result reproduce the given ones (to 1e-12, 1e-9 within 1e-6 of a circle).
        ``kw``: the other fields (kb, ks, n, coupling). A semi-axis above
        SEMI_AXIS_PLAUSIBLE (0.1 m) warns (UnitWarning: it looks like mm) unless
        ``check_units=False``."""
        _no_radii(kw)
        for name, a in (("a1", a1), ("a2", a2)):
            if positive(name, a) > SEMI_AXIS_PLAUSIBLE:
                unit_warning(name, a, "mm", flag("check_units", check_units))
        Estar = CombinedElastic.of(
            instance("body", body, Material, "a halfspace.Material"),
            instance("substrate", substrate, Material, "a halfspace.Material"),
        ).Estar
        A, B, P = ellipse_curvatures(a1, a2, Estar, P, delta)
        return cls.from_curvatures(A, B, body, substrate, mu, P, **kw)

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

    @property
    def elements(self) -> tuple[int, int]:
        """(mx, my): elements of the grid along x and y."""
        return self.n if isinstance(self.n, tuple) else (int(self.n), int(self.n))

    @cached_property
    def patch(self) -> RollingPatch:
        """Hertz pressure on the grid ``n``, scaled so that sum p dA = P exactly."""
        e = self.elastic
        mx, my = self.elements
        patch = ellipse_patch(
            self.a1,
            self.a2,
            mx,
            self.hertz.pressure,
            self.mu,
            e.G,
            e.nu,
            k=self.k,
            kappa=e.kappa if self.coupling else 0.0,
            P=self.P,
            ny=my,
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
        richardson: bool = False,
        check_units: bool = True,
    ) -> RollingSolution:
        """Steady rolling in +x for creepages xi, eta (-) and spin phi (1/m).

        A spin creepage |phi| c below SPIN_PLAUSIBLE (1e-5) but not zero warns
        (UnitWarning: phi looks like rad/mm, CONTACT's unit) unless ``check_units=False``.

        richardson: also solve on the grid of twice the element size over the same
        ellipse (``richardson_grids``: its box of half the elements; ratio r = 2 exactly
        when mx and my are even) and return, with this grid's solution, the error
        estimate (F(r h) - F(h))/(r - 1) of F(h) and the extrapolated forces F(h) minus
        it (``error``, ``extrapolated`` of RollingSolution; the scheme is first order,
        docs/validation.md). The coarse solve costs about a quarter of the fine one."""
        phi = finite("phi", phi)
        if 0.0 < abs(phi) * self.c < SPIN_PLAUSIBLE:
            unit_warning("phi", phi, "rad/mm (here 1/m)", flag("check_units", check_units))
        sol = solve_rolling(self.patch, xi, eta, phi, tau0=tau0, tol=tol)
        if not flag("richardson", richardson):
            return sol
        (bx, by), (cx, cy), r = self.richardson_grids()
        coarse = replace(self, n=(cx + 2, cy)).solve(xi, eta, phi, tol=tol, check_units=False)
        fine = np.array([sol.Tx, sol.Ty, sol.Mz])
        # first order: F(h) = F + C h, so F(h) - F = (F(r h) - F(h))/(r - 1)
        err = (np.array([coarse.Tx, coarse.Ty, coarse.Mz]) - fine) / (r - 1.0)
        return replace(
            sol, error=tuple(map(float, err)), extrapolated=tuple(map(float, fine - err))
        )

    def fastsim(
        self,
        xi: float,
        eta: float = 0.0,
        phi: float = 0.0,
        bound: str = "parabolic",
        C: ArrayLike | None = None,
        check_units: bool = True,
    ) -> RollingSolution:
        """Kalker's FASTSIM on this contact and grid (``fastsim.Fastsim.of``): the same
        RollingSolution as ``solve``, for a one-line comparison. bound: "parabolic"
        (Kalker's) or "elliptic" (the Hertz pressure); C: (C11, C22, C23), default
        Kalker's table (``linear_coefficients()`` gives this grid's). No layers."""
        from .fastsim import Fastsim  # the exact solver does not need it

        return Fastsim.of(self, bound=bound, C=C).solve(xi, eta, phi, check_units=check_units)

    def richardson_grids(self) -> tuple[tuple[int, int], tuple[int, int], float]:
        """The grids of ``solve(richardson=True)``: the elements (bx, by) = (mx - 2, my)
        of this grid's bounding box of the ellipse, those (cx, cy) of the coarse grid's
        (half of them, rounded up; the coarse grid is ``n=(cx + 2, cy)``) and the ratio r
        of the element sizes, coarse over fine: exactly 2 for an even box (mx and my
        even), (bx/cx + by/cy)/2 otherwise (within 1/b of 2)."""
        mx, my = self.elements
        bx, by = mx - 2, my
        cx, cy = (bx + 1) // 2, (by + 1) // 2
        if cx + 2 < MIN_N or cy < MIN_N:
            raise InputError(
                "n",
                self.n,
                f"(mx, my) with mx >= {2 * MIN_N - 3}, my >= {2 * MIN_N - 1} for richardson=True",
            )
        return (bx, by), (cx, cy), 0.5 * (bx / cx + by / cy)

    def traction(self, vx: float, vy: float, phi: float, Vx: float) -> RollingSolution:
        """The solution for rigid slip (vx, vy) (m/s), Omega_z = phi (rad/s), speed Vx (m/s),
        in the frame of the contact (x along +x of the body frame for every sign of Vx)."""
        return self._traction(vx, vy, phi, Vx, None)

    def _traction(
        self, vx: float, vy: float, phi: float, Vx: float, cont: Continuation | None
    ) -> RollingSolution:
        """``traction``, solved from the continuation's prediction where one is given (its
        history is kept in the rolling frame, after the mirroring of Vx < 0)."""
        vx, vy, phi, Vx = (
            finite(n, v) for n, v in zip(("vx", "vy", "phi", "Vx"), (vx, vy, phi, Vx), strict=True)
        )
        if Vx == 0.0:
            return self._sliding(vx, vy, phi)
        aV = abs(Vx)
        sign = 1.0 if Vx > 0.0 else -1.0
        xi, eta, ph = sign * vx / aV, vy / aV, sign * phi / aV
        if not (math.isfinite(xi) and math.isfinite(eta) and math.isfinite(ph)):
            # creepages beyond double range (|v| > 1.8e308 |Vx|): the sliding limit, which
            # full slip along the rigid slip tends to (solve_rolling's saturation)
            return self._sliding(vx, vy, phi)
        # Omega_z of a simulation, not a user's spin: no unit check
        if cont is None:
            sol = self.solve(xi, eta, ph, check_units=False)
        else:
            sol = cont.solve(xi, eta, ph)
        return sol if Vx > 0.0 else _mirror(sol)

    def forces(
        self,
        vx: ArrayLike,
        vy: ArrayLike,
        phi: ArrayLike,
        Vx: ArrayLike,
        continuation: bool = True,
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """(Tx, Ty, Mz) in N, N m (Eq. 8 convention), one solve per element of the
        broadcast inputs, in their order (C order).

        continuation: each solve starts from the prediction of ``rolling.Continuation``
        (the secant through the last two solutions where the creepages lie on their
        line, as along a creep curve; otherwise a cold start), not from the cold start
        of ``solve``; the forces agree within the Newton tolerance (a 20-point creep
        curve on 32 x 32: 76 Newton steps instead of 94, 0.18 s CPU instead of 0.22 s;
        docs/halfspace.md, "Creep curves and tables: continuation")."""
        vx, vy, phi, Vx = _broadcast(vx=vx, vy=vy, phi=phi, Vx=Vx)
        cont = Continuation(self.patch) if flag("continuation", continuation) else None
        out = np.zeros((3, *vx.shape))
        for idx in np.ndindex(vx.shape):
            s = self._traction(vx[idx], vy[idx], phi[idx], Vx[idx], cont)
            out[:, *idx] = (s.Tx, s.Ty, s.Mz)
        return out[0], out[1], out[2]

    def adhesion_fraction(
        self,
        vx: ArrayLike,
        vy: ArrayLike,
        Vx: ArrayLike,
        phi: ArrayLike = 0.0,
        continuation: bool = True,
    ):
        """Adhesion area over contact area (-); continuation as in ``forces``."""
        vx, vy, phi, Vx = _broadcast(vx=vx, vy=vy, phi=phi, Vx=Vx)
        cont = Continuation(self.patch) if flag("continuation", continuation) else None
        out = np.zeros(vx.shape)
        for idx in np.ndindex(vx.shape):
            out[idx] = self._traction(vx[idx], vy[idx], phi[idx], Vx[idx], cont).adhesion_fraction
        return out

    @cached_property
    def creep_full_slip(self) -> float:
        """|v|/|Vx| at the onset of full slip (-): the smaller of the longitudinal and the
        lateral onsets (bisection on the adhesion area, to ONSET_RTOL)."""
        return min(self.onset(0.0), self.onset(0.5 * math.pi))

    def onset(self, angle: float) -> float:
        """Creepage magnitude at which the adhesion area vanishes for the creepage
        direction (cos angle, sin angle), no spin (-)."""
        angle = finite("angle", angle)
        ca, sa = math.cos(angle), math.sin(angle)
        # the bisection's creepages lie on one ray: each solve starts from the secant
        # through the last two (the same converged solutions as cold starts)
        cont = Continuation(self.patch)

        def adh(s: float) -> float:
            return cont.solve(s * ca, s * sa).adhesion_fraction

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
        # the direction from velocities divided by their largest first (no overflow)
        m = max(abs(vx), abs(vy), abs(phi) * patch.grid.reach)
        m = m if 0.0 < m < math.inf else 1.0
        wx, wy = vx / m - (phi / m) * Y, vy / m + (phi / m) * X
        mag = np.hypot(wx, wy)
        C = patch.contact
        moving = C & (mag > 0.0)
        safe = np.where(moving, mag, 1.0)
        tau = np.where(moving, patch.g * np.stack([wx, wy]) / safe, 0.0)
        dA = patch.grid.area
        Tx, Ty = float(tau[0].sum() * dA), float(tau[1].sum() * dA)
        Mz = float(np.sum(X * tau[1] - Y * tau[0]) * dA)
        with np.errstate(over="ignore"):  # a slip velocity beyond double range is inf
            S = np.stack([wx, wy]) * m
        return RollingSolution(patch.grid, tau, S, C, C & ~moving, moving, Tx, Ty, Mz, 0, 0)

    def creepages_for(
        self,
        Fx: float,
        Fy: float,
        phi: float = 0.0,
        rtol: float = FORCE_RTOL,
        check_units: bool = True,
    ) -> tuple[float, float, RollingSolution]:
        """The creepages (xi, eta) (-) of steady rolling in +x at spin phi (1/m) whose
        force on the substrate is (Tx, Ty) = (Fx, Fy) (N), and the solution there.

        Newton's method on the forces in units of mu P, r(u) = (T(u) - F)/(mu P) with u the
        creepages in units of mu P/(G c^2): the Jacobian by one-sided differences of
        FORCE_FD_STEP (two solves warm-started from the iterate, each converged to
        FORCE_SOLVE_TOL of max g, so that the difference quotient carries 1e-4 of its
        value in solver noise), updated by Broyden's rank-one formula after each step
        and evaluated afresh when a step fails to halve |r|. Steps are backtracked on
        |r| (Armijo). The creep curve is concave (the slope falls tenfold at 0.99 mu P and
        again at the onset of full slip, beyond which |T| still rises towards mu P as the
        slip directions align), so that full steps approach the target from below.
        Start: the linear theory stretched by Carter's inverse 1 - (1 - f)^(1/2) (f =
        |F|/(mu P)). Converged
        when max |r| <= rtol. Measured on the railway wheel (16 and 24 per side): 6-10
        solves up to |F| = 0.999 mu P, 14 with spin in full slip, 18-31 from 0.9999 to
        0.999999 mu P (full slip, creepages 3-30 times the onset's); ``solution.solves``
        counts them (tests/test_halfspace_api.py).

        |(Fx, Fy)| must be below mu P; a force the spin leaves out of reach answers
        InputError naming it, with the closest force reached. phi: as in ``solve``
        (``check_units``)."""
        Fx, Fy, phi = finite("Fx", Fx), finite("Fy", Fy), finite("phi", phi)
        rtol = positive("rtol", rtol)
        if 0.0 < abs(phi) * self.c < SPIN_PLAUSIBLE:
            unit_warning("phi", phi, "rad/mm (here 1/m)", flag("check_units", check_units))
        muP = self.mu * self.P
        f = math.hypot(Fx, Fy) / muP
        if f >= 1.0:
            raise InputError("Fx, Fy", (Fx, Fy), f"of magnitude below mu P = {muP:.6g} N")
        G, c = self.elastic.G, self.c
        k = self._coefficients
        stretch = 2.0 * (1.0 - math.sqrt(1.0 - f)) / f if f > 0.0 else 1.0
        xref = muP / (G * c * c)
        u = (
            stretch
            * np.array([Fx / (G * c * c * k.C11), (Fy / (G * c * c) - c * k.C23 * phi) / k.C22])
            / xref
        )
        target = np.array([Fx, Fy]) / muP
        tol = min(NEWTON_TOL, FORCE_SOLVE_TOL)
        solves = 0

        def evaluate(v: FloatArray, tau0: FloatArray | None) -> tuple[RollingSolution, FloatArray]:
            nonlocal solves
            solves += 1
            s = self.solve(
                float(v[0]) * xref, float(v[1]) * xref, phi, tau0=tau0, tol=tol, check_units=False
            )
            return s, np.array([s.Tx, s.Ty]) / muP - target

        sol, r = evaluate(u, None)
        J: FloatArray | None = None
        fresh = False
        for _ in range(FORCE_MAXIT):
            if float(np.abs(r).max()) <= rtol:
                break
            fresh = J is None
            if fresh:
                J = np.empty((2, 2))
                for i in range(2):
                    e = np.zeros(2)
                    e[i] = FORCE_FD_STEP * max(1.0, float(np.abs(u).max()))
                    _, ri = evaluate(u + e, sol.tau)
                    J[:, i] = (ri - r) / e[i]
            du = np.linalg.lstsq(J, -r, rcond=None)[0]
            rn = float(np.hypot(*r))
            step = 1.0
            while True:
                s_t, r_t = evaluate(u + step * du, sol.tau)
                rn_t = float(np.hypot(*r_t))
                if rn_t <= (1.0 - FORCE_ARMIJO * step) * rn or step <= FORCE_MIN_STEP:
                    break
                step *= 0.5
            if rn_t >= rn:
                if step <= FORCE_MIN_STEP and fresh:
                    break  # no progress even along a fresh difference Jacobian
                J = None
                continue
            d = step * du
            # Broyden's update keeps J consistent with the step taken; a step that did not
            # halve |r| asks for a fresh difference Jacobian instead
            J = J + np.outer(r_t - r - J @ d, d) / float(d @ d) if rn_t <= 0.5 * rn else None
            u, sol, r = u + d, s_t, r_t
        if float(np.abs(r).max()) > rtol:
            T = (r + target) * muP
            raise InputError(
                "Fx, Fy",
                (Fx, Fy),
                f"attainable at phi = {phi:.6g} 1/m (closest: {T[0]:.6g}, {T[1]:.6g} N)",
            )
        return float(u[0]) * xref, float(u[1]) * xref, replace(sol, solves=solves)

    @cached_property
    def _coefficients(self) -> CreepCoefficients:
        return self.creep_coefficients()

    def creep_coefficients(self) -> CreepCoefficients:
        """Kalker's C11, C22, C23, C33 (-) of this patch from full-adhesion solves (the
        linear theory; Kalker 1967, Johnson 1985 Sec. 8.4), force on the substrate:

            Tx = G c^2 C11 xi,  Ty = G c^2 (C22 eta + c C23 phi),
            Mz = G c^3 (-C23 eta + c C33 phi).

        The spin load is the whole rigid slip of the spin, w = phi (-y, x): with nu > 0
        its longitudinal part -phi y also loads Ty (C23 at nu = 0.28 is 4 % larger than
        from the lateral part phi x alone). Mz from eta gives -C23 again (reciprocity of
        the symmetric influence operator, tested)."""
        patch = self.patch
        C = patch.contact
        X, Y = patch.grid.mesh()
        dx, dA = patch.grid.dx, patch.grid.area
        ones, zero = np.where(C, dx, 0.0), np.zeros(patch.grid.shape)
        spin = np.stack([np.where(C, -Y * dx, 0.0), np.where(C, X * dx, 0.0)])
        (t_xi, _), (t_eta, _), (t_phi, _) = (
            patch.solve_adhesion(W) for W in (np.stack([ones, zero]), np.stack([zero, ones]), spin)
        )
        G, c = self.elastic.G, self.c
        return CreepCoefficients(
            C11=float(t_xi[0].sum() * dA) / (G * c * c),
            C22=float(t_eta[1].sum() * dA) / (G * c * c),
            C23=float(t_phi[1].sum() * dA) / (G * c**3),
            C33=float(np.sum(X * t_phi[1] - Y * t_phi[0]) * dA) / (G * c**4),
        )

    def linear_coefficients(self) -> tuple[float, float, float]:
        """(C11, C22, C23) of ``creep_coefficients``."""
        k = self.creep_coefficients()
        return k.C11, k.C22, k.C23


class CreepCoefficients(NamedTuple):
    """Kalker's creep coefficients of the linear theory (-), ``creep_coefficients``."""

    C11: float
    C22: float
    C23: float
    C33: float


def _broadcast(**arrays: ArrayLike) -> list[FloatArray]:
    """The named inputs as finite float arrays broadcast together (InputError naming the
    first bad one, or all of them when their shapes do not broadcast)."""
    checked = [array(name, a) for name, a in arrays.items()]
    try:
        return np.broadcast_arrays(*checked)
    except ValueError:
        shapes = tuple(a.shape for a in checked)
        raise InputError(", ".join(arrays), shapes, "shapes that broadcast") from None


def _no_radii(kw: dict) -> None:
    for name in ("Rx", "Ry", "Rsx", "Rsy"):
        if name in kw:
            raise InputError(name, kw[name], "not given: the curvatures or the ellipse fix it")


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
        None if sol.error is None else (-sol.error[0], sol.error[1], -sol.error[2]),
        None if sol.extrapolated is None else _flip_x(sol.extrapolated),
        sol.solves,
    )


def _flip_x(F: tuple[float, float, float]) -> tuple[float, float, float]:
    return (-F[0], F[1], -F[2])
