"""Plots of a steady-rolling solution (``RollingSolution.plot``): the traction on the
grid as arrows over contours of its magnitude, with the adhesion and slip areas marked;
and the creep curves of the exact solver and FASTSIM together (``plot_creep_curves``).

Matplotlib is imported here only, on the first plot: the solver modules import numpy
and scipy alone.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._validate import InputError, array, count, positive

# Lengths in mm and tractions in MPa on the axes (the solver's SI values scaled).
MM = 1e3
MPA = 1e-6
# A creep curve whose force stays below this (in units of mu P) along the whole curve is
# zero up to the solver's rounding (Ty of pure xi) and is left out.
ZERO_FORCE = 1e-9


def plot_solution(sol: Any, ax: Any = None, arrows: bool = True, title: bool = True) -> Any:
    """Draw ``sol`` (a RollingSolution) on ``ax`` (a new figure's when None) and return
    the axes: filled contours of |tau| (MPa) over the contact (colour bar), the traction
    tau (the body's on the substrate) as one arrow per contact element (``arrows``),
    adhesion elements as dots and slip elements as crosses (legend below the axes), the
    boundary of the adhesion area as a black line, x (the rolling direction, material
    entering at +x) and y in mm, equal scales; ``title``: the forces Tx, Ty (N) and Mz
    (N m)."""
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
    # below the axes, in one row: inside, it covered the contact's corner elements
    ax.legend(
        loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=3, fontsize="small", facecolor="0.8"
    )
    if title:
        ax.set_title(
            f"Tx = {sol.Tx:.4g} N, Ty = {sol.Ty:.4g} N, Mz = {sol.Mz:.4g} N m", fontsize="small"
        )
    return ax


def plot_creep_curves(
    contact: Any,
    direction: tuple[float, float, float] = (1.0, 0.0, 0.0),
    s_max: float = 1.5,
    points: int = 16,
    bounds: tuple[str, ...] = ("parabolic", "elliptic"),
    ax: Any = None,
) -> Any:
    """Creep curves of the exact solver and of FASTSIM together on ``ax`` (a new
    figure's when None); returns the axes.

    contact: a HalfSpaceContact (no layers). The creepages run along ``direction`` =
    (xi, eta, phi c) in units of mu P/(G c^2): (xi, eta, phi) = s (d_xi, d_eta, d_phi/c)
    mu P/(G c^2) for ``points`` values of s in (0, s_max]. Drawn against s: Tx/(mu P)
    and Ty/(mu P) unless below ZERO_FORCE along the whole curve, the exact solver's
    (``contact.solve``, circles) and FASTSIM's on the same grid for each of ``bounds``
    (``contact.fastsim``, lines), labelled "<solver> Tx" etc."""
    import matplotlib.pyplot as plt

    d = tuple(float(v) for v in array("direction", direction, (3,)))
    if not any(d):
        raise InputError("direction", direction, "(xi, eta, phi c), not all zero")
    s = np.linspace(0.0, positive("s_max", s_max), count("points", points, 2) + 1)[1:]
    if ax is None:
        _, ax = plt.subplots(figsize=(6.0, 4.5))
    muP = contact.mu * contact.P
    xref = muP / (contact.elastic.G * contact.c**2)
    w = [(v * d[0] * xref, v * d[1] * xref, v * d[2] * xref / contact.c) for v in s]
    curves = {"exact": [contact.solve(*a, check_units=False) for a in w]}
    for b in bounds:
        curves[f"FASTSIM {b}"] = [contact.fastsim(*a, bound=b, check_units=False) for a in w]
    for k, (name, sols) in enumerate(curves.items()):
        for comp, style in (("Tx", "-"), ("Ty", "--")):
            T = np.array([getattr(x, comp) for x in sols]) / muP
            if np.abs(T).max() < ZERO_FORCE:
                continue
            colour = f"C{k}"
            if name == "exact":
                ax.plot(s, T, "o", ms=4, color=colour, ls=style, lw=0.8, label=f"{name} {comp}")
            else:
                ax.plot(s, T, color=colour, ls=style, label=f"{name} {comp}")
    ax.axhline(0.0, color="grey", lw=0.5)
    ax.set_xlabel(f"creepage s along (xi, eta, phi c) = {d} (mu P/(G c^2))")
    ax.set_ylabel("T/(mu P)")
    ax.legend(loc="best", fontsize="small")
    return ax
