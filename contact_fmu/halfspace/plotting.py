"""Plots of a steady-rolling solution (``RollingSolution.plot``): the traction on the
grid as arrows over contours of its magnitude, with the adhesion and slip areas marked.

Matplotlib is imported here only, on the first plot: the solver modules import numpy
and scipy alone.
"""

from __future__ import annotations

from typing import Any

import numpy as np

# Lengths in mm and tractions in MPa on the axes (the solver's SI values scaled).
MM = 1e3
MPA = 1e-6


def plot_solution(sol: Any, ax: Any = None, arrows: bool = True, title: bool = True) -> Any:
    """Draw ``sol`` (a RollingSolution) on ``ax`` (a new figure's when None) and return
    the axes: filled contours of |tau| (MPa) over the contact (colour bar), the traction
    tau (the body's on the substrate) as one arrow per contact element (``arrows``),
    adhesion elements as dots and slip elements as crosses (legend), the boundary of the
    adhesion area as a black line, x (the rolling direction, material entering at +x)
    and y in mm, equal scales; ``title``: the forces Tx, Ty (N) and Mz (N m)."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(6.0, 4.5))
    X, Y = (a * MM for a in sol.grid.mesh())
    C = sol.contact
    mag = np.where(C, np.hypot(sol.tau[0], sol.tau[1]), np.nan) * MPA
    if np.isfinite(mag).any() and np.nanmax(mag) > 0.0:
        cs = ax.contourf(X, Y, mag, levels=12, cmap="viridis")
        ax.figure.colorbar(cs, ax=ax, label="|tau| (MPa)")
    if arrows and C.any():
        ax.quiver(X[C], Y[C], sol.tau[0][C] * MPA, sol.tau[1][C] * MPA, color="white", label="tau")
    A, S = sol.adhesion, sol.slip
    ax.plot(X[A], Y[A], "o", ms=2.5, color="tab:blue", label=f"adhesion ({int(A.sum())})")
    ax.plot(X[S], Y[S], "x", ms=3.0, color="tab:red", label=f"slip ({int(S.sum())})")
    if A.any() and S.any():
        ax.contour(X, Y, A.astype(float), levels=[0.5], colors="black", linewidths=1.0)
    ax.set_xlabel("x (mm), rolling direction")
    ax.set_ylabel("y (mm)")
    ax.set_aspect("equal")
    ax.legend(loc="upper right", fontsize="small")
    if title:
        ax.set_title(
            f"Tx = {sol.Tx:.4g} N, Ty = {sol.Ty:.4g} N, Mz = {sol.Mz:.4g} N m", fontsize="small"
        )
    return ax
