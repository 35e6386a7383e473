"""Line contact: steady rolling of cylinders in plane strain (Carter 1926).

Two cylinders with parallel axes along y, rolling in +x, of combined radius R (1/R =
1/R_b + 1/R_s) pressed together by N (per unit length along y, N/m): the Hertz strip
of half width a, a^2 = 4 N R/(pi E*), and pressure p = p0 (1 - x^2/a^2)^(1/2), p0 =
2 N/(pi a) (Johnson 1985, Eq. 4.43-4.45). The tangential problem is the steady-rolling
problem of ``rolling`` on one row of elements with the plane-strain kernel
(``influence.plane_strain_operator``; Kalker's quasi-identity: the pressure coupling is
left out). Carter's closed form F/(mu N) = 2 kappa - kappa^2, kappa = R |xi|/(mu a)
<= 1 (references.md) is reproduced with a first-order error, 0.36 % on 100 elements
(tests/test_halfspace_line.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .._validate import count, finite, instance, positive
from .hertz import CombinedElastic, Material, traction_bound, within_scale
from .influence import Grid, plane_strain_operator
from .rolling import RollingPatch, RollingSolution, normalise_load, solve_rolling

# Elements across the contact strip (2 a); one more on each side is left free.
DEFAULT_LINE_N = 100


@dataclass(frozen=True)
class LineContact:
    """Cylinders in line contact, steady rolling in +x (plane strain).

    N: normal load per unit length (N/m); R: combined radius (m), 1/R = 1/R_b + 1/R_s
    (a flat substrate: R = R_b); body, substrate: materials (Kalker's combined G, nu,
    E*); mu: friction coefficient (-); n: elements across the contact strip.
    """

    N: float
    R: float
    body: Material
    substrate: Material
    mu: float
    n: int = DEFAULT_LINE_N

    def __post_init__(self) -> None:
        positive("N", self.N)
        positive("R", self.R)
        instance("body", self.body, Material, "a halfspace.Material")
        instance("substrate", self.substrate, Material, "a halfspace.Material")
        positive("mu", self.mu)
        count("n", self.n, 8)
        # the strip's scales within the solvers' range (hertz.SCALE_MIN .. SCALE_MAX)
        source = f" (the Hertz strip of N = {self.N:g} N/m, R = {self.R:g} m)"
        within_scale("a", self.a, "m", source)
        within_scale("p0", self.p0, "Pa", source)
        traction_bound(self.mu, self.p0)

    @cached_property
    def elastic(self) -> CombinedElastic:
        return CombinedElastic.of(self.body, self.substrate)

    @property
    def a(self) -> float:
        """Half width of the contact strip (m): a^2 = 4 N R/(pi E*)."""
        return math.sqrt(4.0 * self.N * self.R / (math.pi * self.elastic.Estar))

    @property
    def p0(self) -> float:
        """Peak pressure 2 N/(pi a) (Pa)."""
        return 2.0 * self.N / (math.pi * self.a)

    @cached_property
    def patch(self) -> RollingPatch:
        """One row of n + 2 elements of width 2 a/n, pressure scaled to sum p dx = N."""
        a, n = self.a, self.n
        dx = 2.0 * a / n
        grid = Grid(n + 2, 1, dx, 1.0, -a - dx, -0.5)
        X, _ = grid.mesh()
        p = self.p0 * np.sqrt(np.maximum(1.0 - (X / a) ** 2, 0.0))
        theta = np.where(p > 0.0, np.clip((a - X) / dx, np.finfo(float).tiny, 1.0), 1.0)
        e = self.elastic
        return RollingPatch(
            grid,
            normalise_load(p, grid, self.N),
            self.mu,
            e.G,
            e.nu,
            theta=theta,
            operator=plane_strain_operator(grid, e.G, e.nu),
        )

    def solve(self, xi: float) -> RollingSolution:
        """Steady rolling in +x at the creepage xi = vx/Vx (-): Tx is the force per unit
        length (N/m) on the substrate, along the slip."""
        return solve_rolling(self.patch, finite("xi", xi))

    def carter(self, xi: float) -> float:
        """Carter's force per unit length (N/m) at xi: mu N (2 kappa - kappa^2)
        sign(xi), kappa = R |xi|/(mu a), mu N beyond kappa = 1."""
        kappa = min(self.R * abs(finite("xi", xi)) / (self.mu * self.a), 1.0)
        return math.copysign(self.mu * self.N * (2.0 * kappa - kappa * kappa), xi)
