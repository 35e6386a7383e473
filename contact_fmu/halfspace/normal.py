"""Numerical normal contact on a grid: the conjugate-gradient method of Polonsky & Keer.

Polonsky & Keer (1999), Wear 231, 206-219: find p >= 0 on the grid with total load
P = sum p dA and the gap

    g = h + w(p) - delta,   w = A p (+ (k1 + k2) p for Winkler layers, Eq. 32)

zero where p > 0 and non-negative where p = 0. The approach delta is the mean of
h + w over the contact set and need not be given. w = A p is the Boussinesq
convolution (influence.boussinesq_kernel), evaluated with FFTs, so one iteration costs
O(N log N). Used to check the Hertz solution (hertz.Hertz) on the grid of the
tangential problem.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .._validate import array, count, instance, nonnegative, positive
from .influence import Grid, normal_operator

FloatArray = NDArray[np.float64]

# Convergence: relative change of the pressure, sum |p_new - p_old| / sum p (-), the
# criterion of Polonsky & Keer; 1e-10 is far below the discretisation error.
NORMAL_TOL = 1e-10
# Iteration cap of the CG loop; the observed count is 20-60 on 16..128 grids.
NORMAL_MAXIT = 2000


@dataclass(frozen=True)
class NormalSolution:
    """Pressure p (ny, nx) (Pa), contact mask, approach delta (m), iterations."""

    grid: Grid
    p: FloatArray
    contact: NDArray[np.bool_]
    delta: float
    iterations: int

    @property
    def load(self) -> float:
        """sum p dA (N)."""
        return float(self.p.sum() * self.grid.area)


def solve_normal(
    grid: Grid,
    h: FloatArray,
    P: float,
    Estar: float,
    k_layers: float = 0.0,
    tol: float = NORMAL_TOL,
    maxit: int = NORMAL_MAXIT,
) -> NormalSolution:
    """Polonsky-Keer CG for the load P (N) and undeformed gap h (ny, nx) (m).

    Estar: combined modulus (Pa); k_layers = k1 + k2 (m/Pa), the Winkler layers of
    Eq. (32) added on the diagonal.
    """
    positive("P", P)
    positive("Estar", Estar)
    nonnegative("k_layers", k_layers)
    instance("grid", grid, Grid, "an influence.Grid")
    h = array("h", h, grid.shape)
    tol = positive("tol", tol)
    maxit = count("maxit", maxit, 1)
    op = normal_operator(grid, Estar, k_layers)
    dA = grid.area
    p = np.full(grid.shape, P / (grid.nx * grid.ny * dA))
    t = np.zeros(grid.shape)
    G_old = 1.0
    delta_cg = 0.0
    it = 0
    while it < maxit:
        it += 1
        u = op.apply(p[None])[0]
        g = u + h
        Ic = p > 0.0
        g_mean = float(g[Ic].mean())
        g = g - g_mean
        G = float(np.sum(g[Ic] ** 2))
        t = np.where(Ic, g + delta_cg * (G / G_old) * t, 0.0)
        G_old = G
        r = op.apply(t[None])[0]
        r = r - float(r[Ic].mean())
        denom = float(np.sum(r[Ic] * t[Ic]))
        step = float(np.sum(g[Ic] * t[Ic])) / denom if denom != 0.0 else 0.0
        p_old = p.copy()
        p = np.where(Ic, p - step * t, p)
        p = np.maximum(p, 0.0)
        overlap = (p == 0.0) & (g < 0.0)
        if np.any(overlap):
            delta_cg = 0.0
            p = np.where(overlap, p - step * g, p)
        else:
            delta_cg = 1.0
        p *= P / (float(p.sum()) * dA)
        err = float(np.abs(p - p_old).sum() / p.sum())
        if err < tol:
            break
    contact = p > 0.0
    u = op.apply(p[None])[0]
    delta = float(np.mean((u + h)[contact]))
    return NormalSolution(grid, p, contact, delta, it)
