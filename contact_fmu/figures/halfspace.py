"""Half-space law: creep-force curves and adhesion areas of the railway wheel
on rail, and the grid convergence of the solver.

Model: contact_fmu.halfspace (exact half-space theory, steady rolling; Hertz pressure;
parameters contact_fmu.halfspace.railway). Creepages are shown in Kalker's units
mu P/(G c^2) (spin: mu P/(G c^3)), forces in mu P. The dashed lines are the linear
theory of the same grid (Kalker's C11, C22, C23 from full-adhesion solves). The numbers
quoted in docs/halfspace.md come from halfspace_curves.csv written here.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from ..halfspace.contact import HalfSpaceContact
from ..halfspace.plotting import plot_creep_curves
from ..halfspace.railway import wheel_on_rail

# Solver grid of the figures (elements per direction; ~1 % discretisation error).
N_FIG = 32
# Normalised creepages of the curves (units mu P/(G c^2), spin mu P/(G c^3)).
CREEPS = np.linspace(0.0, 1.2, 41)
SPINS = np.linspace(0.0, 3.0, 41)
# Creepage states of the traction maps: (xi, eta, phi) in the same units.
STATES = ((0.1, 0.0, 0.0), (0.3, 0.0, 0.0), (0.2, 0.2, 0.3), (0.0, 0.0, 1.0))
# The state of RollingSolution.plot()'s picture (same units), and the direction (xi, eta,
# phi c) and grid of plot_creep_curves' exact and FASTSIM curves.
SOLUTION_PLOT_STATE = (0.08, 0.04, 0.1)
FASTSIM_DIRECTION = (1.0, 0.3, 0.5)
N_FASTSIM = 24


def _units(c: HalfSpaceContact) -> tuple[float, float]:
    xref = c.mu * c.P / (c.elastic.G * c.c**2)
    return xref, xref / c.c


def curves(c: HalfSpaceContact) -> dict[str, np.ndarray]:
    """Tx(xi), Ty(eta), Ty and Mz (phi) and the adhesion fractions, warm-started sweeps."""
    xref, pref = _units(c)
    muP = c.mu * c.P
    out = {"creep": CREEPS, "spin": SPINS}
    for key, comp, make in (
        ("xi", 0, lambda s: (s * xref, 0.0, 0.0)),
        ("eta", 1, lambda s: (0.0, s * xref, 0.0)),
        ("phi", 1, lambda s: (0.0, 0.0, s * pref)),
    ):
        grid = SPINS if key == "phi" else CREEPS
        F, M, A = [], [], []
        tau = None
        for s in grid:
            sol = c.solve(*make(s), tau0=tau)
            tau = sol.tau
            F.append((sol.Tx, sol.Ty)[comp] / muP)
            M.append(sol.Mz / (muP * c.c))
            A.append(sol.adhesion_fraction)
        out[f"F_{key}"], out[f"Mz_{key}"], out[f"adh_{key}"] = map(np.array, (F, M, A))
    return out


def make_figures(outdir: Path) -> list[Path]:
    outdir = Path(outdir)
    c = wheel_on_rail(n=N_FIG)
    C11, C22, C23 = c.linear_coefficients()
    data = curves(c)
    paths = []

    # creep-force curves
    fig, axs = plt.subplots(1, 2, figsize=(10, 4))
    ax = axs[0]
    ax.plot(CREEPS, data["F_xi"], "C0-", label=r"$T_x$ vs $\xi$")
    ax.plot(CREEPS, data["F_eta"], "C1-", label=r"$T_y$ vs $\eta$")
    ax.plot(CREEPS, C11 * CREEPS, "C0--", lw=0.8, label=f"linear, C11 = {C11:.2f}")
    ax.plot(CREEPS, C22 * CREEPS, "C1--", lw=0.8, label=f"linear, C22 = {C22:.2f}")
    ax.plot(CREEPS, data["adh_xi"], "C0:", label="adhesion fraction ($\\xi$)")
    ax.set_ylim(0, 1.1)
    ax.set_xlabel(r"creepage / ($\mu P/(G c^2)$)")
    ax.set_ylabel(r"force / $\mu P$")
    ax.set_title("Wheel on rail: creep forces (exact half-space)")
    ax.legend(fontsize=8)
    ax = axs[1]
    ax.plot(SPINS, data["F_phi"], "C2-", label=r"$T_y$ vs spin $\phi$")
    ax.plot(SPINS, data["Mz_phi"], "C3-", label=r"$M_z/(\mu P c)$ vs $\phi$")
    ax.plot(SPINS, C23 * SPINS, "C2--", lw=0.8, label=f"linear, C23 = {C23:.2f}")
    ax.plot(SPINS, data["adh_phi"], "C2:", label="adhesion fraction")
    ax.set_ylim(0, 1.1)
    ax.set_xlabel(r"spin / ($\mu P/(G c^3)$)")
    ax.set_title("Pure spin")
    ax.legend(fontsize=8)
    fig.tight_layout()
    p = outdir / "halfspace_creep_curves.png"
    fig.savefig(p, dpi=120)
    plt.close(fig)
    paths.append(p)

    # adhesion areas and traction maps
    xref, pref = _units(c)
    fig, axs = plt.subplots(1, len(STATES), figsize=(3.2 * len(STATES), 3.4), layout="constrained")
    for ax, (a, b, s) in zip(axs, STATES, strict=True):
        sol = c.solve(a * xref, b * xref, s * pref)
        X, Y = sol.grid.mesh()
        g = c.patch.g
        ratio = np.where(sol.contact, np.hypot(*sol.tau) / np.where(g > 0, g, 1.0), np.nan)
        im = ax.pcolormesh(X * 1e3, Y * 1e3, ratio, vmin=0, vmax=1, cmap="viridis", shading="auto")
        ax.contour(X * 1e3, Y * 1e3, sol.adhesion.astype(float), levels=[0.5], colors="w")
        t = np.linspace(0, 2 * math.pi, 200)
        ax.plot(c.a1 * 1e3 * np.cos(t), c.a2 * 1e3 * np.sin(t), "k-", lw=0.6)
        step = max(1, sol.grid.nx // 12)
        ax.quiver(
            X[::step, ::step] * 1e3,
            Y[::step, ::step] * 1e3,
            sol.tau[0][::step, ::step],
            sol.tau[1][::step, ::step],
            color="w",
            scale=12 * float(g.max()),
            width=0.004,
        )
        ax.set_aspect("equal")
        ax.set_title(
            f"xi={a}, eta={b}, phi={s}\nT=({sol.Tx / (c.mu * c.P):.2f}, "
            f"{sol.Ty / (c.mu * c.P):.2f}) mu P, adh {sol.adhesion_fraction:.2f}",
            fontsize=8,
        )
        ax.set_xlabel("x (mm), rolling +x")
    axs[0].set_ylabel("y (mm)")
    fig.colorbar(im, ax=axs, label=r"$|\tau|/(\mu p)$ (adhesion inside the white line)")
    p = outdir / "halfspace_adhesion_areas.png"
    fig.savefig(p, dpi=120)
    plt.close(fig)
    paths.append(p)

    # the solution's own picture and the creep curves beside FASTSIM's: what
    # RollingSolution.plot() and plot_creep_curves draw (docs/halfspace.md shows both)
    a, b, s = SOLUTION_PLOT_STATE
    ax = c.solve(a * xref, b * xref, s * pref).plot()
    p = outdir / "halfspace_solution_plot.png"
    ax.figure.savefig(p, dpi=100, bbox_inches="tight")
    plt.close(ax.figure)
    paths.append(p)
    ax = plot_creep_curves(wheel_on_rail(n=N_FASTSIM), direction=FASTSIM_DIRECTION)
    p = outdir / "halfspace_exact_fastsim.png"
    ax.figure.savefig(p, dpi=100, bbox_inches="tight")
    plt.close(ax.figure)
    paths.append(p)

    # the numbers behind the curves
    p = outdir / "halfspace_curves.csv"
    with open(p, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["# wheel on rail, n =", N_FIG, "C11 C22 C23 =", C11, C22, C23])
        w.writerow(["creep", "Tx_xi", "adh_xi", "Ty_eta", "adh_eta", "spin", "Ty_phi", "Mz_phi"])
        for i in range(len(CREEPS)):
            w.writerow(
                [
                    f"{CREEPS[i]:.4f}",
                    f"{data['F_xi'][i]:.6f}",
                    f"{data['adh_xi'][i]:.4f}",
                    f"{data['F_eta'][i]:.6f}",
                    f"{data['adh_eta'][i]:.4f}",
                    f"{SPINS[i]:.4f}",
                    f"{data['F_phi'][i]:.6f}",
                    f"{data['Mz_phi'][i]:.6f}",
                ]
            )
    paths.append(p)
    return paths
