"""The paper's Figs. 2, 3, 4, 5, 6-11, 12 and 13 from the model (thin layers, Section 4).

Parameters: contact_fmu.examples (recorded in docs/model.md). Forces in units of
mu p0 a1 a2, times in units of T_c (Eq. 13), as in the paper's figures.
"""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from .. import examples as ex
from ..dynamics.body import Lateral, load_utilisation
from ..dynamics.simulate import load_history, simulate
from . import save

ETA_STYLE = {10.9: "-", 2.92: "--", 1.7: ":", 1.5: ":", 3.0: "--", 10.0: "-"}


def fig2(outdir: Path) -> Path:
    """A1(eta), A2(eta) of Eq. (23) for 1 <= eta <= inf."""
    eta = np.logspace(0, 3, 200)
    fig, ax = plt.subplots(figsize=(5, 3.5))
    ax.semilogx(eta, eta / (1 + eta), label="$A_1 = \\eta/(1+\\eta)$")
    ax.semilogx(eta, 1 / (1 + eta), "--", label="$A_2 = 1/(1+\\eta)$")
    ax.axvline(2.5, color="0.7", lw=0.8)
    ax.text(2.6, 0.05, "homogeneous\nellipsoid", fontsize=8)
    ax.set(xlabel="$\\eta = M R_x^2 / I_y$", ylabel="$A_1, A_2$", ylim=(0, 1))
    ax.set_title("Fig. 2: $A_1 \\to 1$, $A_2 \\to 0$ as $\\eta \\to \\infty$", fontsize=10)
    ax.legend()
    return save(fig, outdir, "fig02_A1_A2")


def fig3(outdir: Path) -> Path:
    """Admissible (Fx_ex, My_ex), Eq. (27): |A2 Fx - A1 My/Rx| <= mu P."""
    c = ex.contact()
    f = np.linspace(-4, 4, 401)
    m = np.linspace(-2, 2, 401)
    F, Mm = np.meshgrid(f, m)
    fig, ax = plt.subplots(figsize=(5, 4))
    for eta, ls in ((1.0, ":"), (2.5, "--"), (math.inf, "-")):
        u = load_utilisation(ex.body(eta), c.mu, c.P, F * c.mu * c.P, Mm * c.mu * c.P * ex.Rx)
        ax.contour(F, Mm, u, levels=[1.0], linestyles=ls, colors="k")
        ax.plot([], [], ls, color="k", label=f"$\\eta$ = {eta:g}")
    ax.set(xlabel="$F_x^{ex}/\\mu P$", ylabel="$M_y^{ex}/(\\mu P R_x)$")
    ax.set_title("Fig. 3: admissible loads lie between the lines", fontsize=10)
    ax.legend()
    return save(fig, outdir, "fig03_admissible_Fx_My")


def fig4(outdir: Path) -> Path:
    """Admissible (Fx_ex, Fy_ex) for My_ex = Mz_ex = 0: (A2 Fx)^2 + Fy^2 <= (mu P)^2."""
    c = ex.contact()
    f = np.linspace(-4, 4, 401)
    g = np.linspace(-1.5, 1.5, 301)
    F, G = np.meshgrid(f, g)
    fig, ax = plt.subplots(figsize=(5, 3.5))
    for eta, ls in ((1.0, ":"), (2.5, "--"), (math.inf, "-")):
        u = load_utilisation(ex.body(eta), c.mu, c.P, F * c.mu * c.P, 0.0, G * c.mu * c.P)
        ax.contour(F, G, u, levels=[1.0], linestyles=ls, colors="k")
        ax.plot([], [], ls, color="k", label=f"$\\eta$ = {eta:g}")
    ax.set(xlabel="$F_x^{ex}/\\mu P$", ylabel="$F_y^{ex}/\\mu P$")
    ax.set_title("Fig. 4: admissible loads lie inside", fontsize=10)
    ax.legend(loc="upper right")
    return save(fig, outdir, "fig04_admissible_Fx_Fy")


def fig5(outdir: Path) -> Path:
    """Tx / (mu p0 a1 a2) against |v|/Vx for vy/Vx = 0, 0.002, 0.006 (Eqs. 40-43)."""
    c = ex.contact()
    unit = ex.force_unit(c)
    fig, ax = plt.subplots(figsize=(5, 3.5))
    for xi_y, ls in zip(ex.VY_RATIOS, ("-", "--", ":"), strict=True):
        speed = np.linspace(xi_y, 0.025, 400)
        xi_x = np.sqrt(np.maximum(speed**2 - xi_y**2, 0.0))
        Tx, _ = c.force(xi_x, xi_y, 1.0)
        ax.plot(speed, Tx / unit, ls, label=f"$v_y/V_x$ = {xi_y:g}")
    ax.axhline(math.pi / 2, color="0.7", lw=0.8)
    ax.text(0.0005, math.pi / 2 - 0.12, "$\\mu P$", fontsize=8)
    ax.set(xlabel="$(v_x^2 + v_y^2)^{1/2}/V_x$", ylabel="$T_x/(\\mu p_0 a_1 a_2)$")
    ax.set_title("Fig. 5: creep-force law, corrected Eq. (42)", fontsize=10)
    ax.legend()
    return save(fig, outdir, "fig05_creep_force")


def _quasistationary_slip(eta: float, xi_y: float) -> float:
    """vx/Vx under Fx_ex alone in the quasistationary phase: Tx(vx) = A2 Fx_ex (Eq. 26)."""
    c = ex.contact()
    return c.inverse_creep(ex.body(eta).A2 * ex.FX_FIG6_12_UNITS * ex.force_unit(c), xi_y)


def fig_adhesion(outdir: Path, xi_y: float, number: int) -> Path:
    """Rear boundaries l_a(y) of the adhesion areas (Eq. 38), Figs. 6 and 9."""
    c = ex.contact()
    y = np.linspace(-c.a2, c.a2, 401)
    ell = c.a1 * np.sqrt(np.maximum(1 - (y / c.a2) ** 2, 0))
    fig, ax = plt.subplots(figsize=(5, 3.8))
    ax.plot(ell / c.a1, y / c.a2, color="0.6", lw=0.8)
    ax.plot(-ell / c.a1, y / c.a2, color="0.6", lw=0.8)
    for eta in ex.ETA_FIG6_12:
        xi_x = _quasistationary_slip(eta, xi_y)
        alpha = float(c.beta(xi_x, xi_y, 1.0)) * c.a1
        stick = ell > 0.5 * alpha
        ax.plot(
            (alpha - ell[stick]) / c.a1, y[stick] / c.a2, ETA_STYLE[eta], label=f"$\\eta$ = {eta}"
        )
    ax.set(xlabel="$x/a_1$ (rolling towards +x)", ylabel="$y/a_2$", aspect="equal")
    ax.set_title(
        f"Fig. {number}: adhesion areas (right of the curves), $v_y/V_x$ = {xi_y}", fontsize=9
    )
    ax.legend(fontsize=8, loc="lower left")
    return save(fig, outdir, f"fig{number:02d}_adhesion_vy{xi_y:g}")


def fig_traction(outdir: Path, xi_y: float, component: int, number: int) -> Path:
    """tau_x (component 0) or tau_y (1) along the x axis, Figs. 7-8 and 10-11."""
    c = ex.contact()
    fig, ax = plt.subplots(figsize=(5, 3.5))
    for eta in ex.ETA_FIG6_12:
        f = c.traction(_quasistationary_slip(eta, xi_y), xi_y, 1.0, nx=401, ny=1)
        tau = (f.tau_x, f.tau_y)[component][0]
        ax.plot(f.x / c.a1, tau / (c.mu * c.p0), ETA_STYLE[eta], label=f"$\\eta$ = {eta}")
    name = ("x", "y")[component]
    ax.set(xlabel="$x/a_1$ (y = 0)", ylabel=f"$\\tau_{name}/(\\mu p_0)$")
    ax.set_title(f"Fig. {number}: $\\tau_{name}$ along the x axis, $v_y/V_x$ = {xi_y}", fontsize=10)
    ax.legend(fontsize=8)
    return save(fig, outdir, f"fig{number:02d}_tau{name}_vy{xi_y:g}")


def fig12(outdir: Path) -> Path:
    """Rigid slip vx(t) from the start of the motion (Eq. 20), vy/Vx = 0.002."""
    c = ex.contact()
    Tc, V0 = ex.time_unit(c), ex.speed_unit(c)
    Fx = ex.FX_FIG6_12_UNITS * ex.force_unit(c)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(8, 3.5))
    for eta in ex.ETA_FIG6_12:
        b = ex.body(eta)
        lat = Lateral(vy_ratio=0.002)
        short = simulate(c, b, load_history(Fx_ex=Fx), 0.02 * Tc, 2e-4 * Tc, lateral=lat, Vx0=V0)
        long = simulate(c, b, load_history(Fx_ex=Fx), 2 * Tc, 0.01 * Tc, lateral=lat, Vx0=V0)
        for ax, tr in ((ax1, short), (ax2, long)):
            ax.plot(tr.t / Tc, tr.vx * 1e3, ETA_STYLE[eta], label=f"$\\eta$ = {eta}")
    ax1.set(xlabel="$t/T_c$", ylabel="$v_x$ (mm/s)", title="transient (t ~ $\\epsilon$)")
    ax2.set(xlabel="$t/T_c$", title="quasistationary: $v_x \\propto V_x(t)$")
    ax1.legend(fontsize=8)
    fig.suptitle(
        f"Fig. 12: rigid slip under $F_x^{{ex}}$ = {ex.FX_FIG6_12_UNITS:g} "
        "$\\mu p_0 a_1 a_2$, $v_y/V_x$ = 0.002",
        fontsize=10,
    )
    return save(fig, outdir, "fig12_slip_evolution")


def fig13(outdir: Path) -> Path:
    """Tx(t) under Fx_ex = mu p0 a1 a2, My_ex = 0.2 mu p0 Rx a1 a2 sin(t/T_c)."""
    c = ex.contact()
    Tc, V0, unit = ex.time_unit(c), ex.speed_unit(c), ex.force_unit(c)
    Fx, My = ex.FX_FIG13_UNITS * unit, ex.MY_FIG13_UNITS * unit * ex.Rx
    loads = load_history(Fx_ex=Fx, My_ex=lambda t: My * math.sin(t / Tc))
    fig, ax = plt.subplots(figsize=(5.5, 3.5))
    for eta in ex.ETA_FIG13:
        b = ex.body(eta)
        # 8 substeps resolve the start-up transient (tau_r ~ 2.5e-3 T_c at eta = 1.5)
        tr = simulate(c, b, loads, 4 * math.pi * Tc, 4 * math.pi * Tc / 600, Vx0=V0, substeps=8)
        ax.plot(tr.t / Tc, tr.Tx / unit, ETA_STYLE[eta], label=f"$\\eta$ = {eta:g}")
        qs = b.tx_quasistationary(Fx, My * np.sin(tr.t / Tc)) / unit
        ax.plot(tr.t / Tc, qs, color="0.6", lw=0.6)
    ax.set(xlabel="$t/T_c$", ylabel="$T_x/(\\mu p_0 a_1 a_2)$")
    ax.set_title("Fig. 13: full model (black) on Eq. (26) (grey)", fontsize=10)
    ax.legend(fontsize=8)
    return save(fig, outdir, "fig13_Tx_time_moment")


def make_figures(outdir: Path) -> list[Path]:
    paths = [fig2(outdir), fig3(outdir), fig4(outdir), fig5(outdir)]
    for xi_y, first in ((0.002, 6), (0.006, 9)):
        paths.append(fig_adhesion(outdir, xi_y, first))
        paths.append(fig_traction(outdir, xi_y, 0, first + 1))
        paths.append(fig_traction(outdir, xi_y, 1, first + 2))
    paths += [fig12(outdir), fig13(outdir)]
    return paths
