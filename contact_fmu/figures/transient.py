"""The transient phase resolved (thin layers): Fig. 12 with the transient, Figs. 7-8
and 10-11 as snapshots of the traction field, and the duration of the transient.

Model: contact_fmu.dynamics.thin_layer_field (the traction field as a state, Eq. 15 with its time
derivative, coupled to Eqs. 8-11). Parameters: contact_fmu.examples, with the load
of the core's figures, Fx_ex = FX_FIG6_12_UNITS mu p0 a1 a2 (docs/model.md); the
durations are also measured at one force unit. Numbers quoted in docs/transient.md
come from ``durations`` (written to transient_durations.csv by make_figures).
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from scipy.integrate import quad
from scipy.optimize import brentq, fsolve

from .. import examples as ex
from ..dynamics.body import Lateral, Loads
from ..dynamics.integrator import RollingBody
from ..dynamics.thin_layer_field import TransientRollingBody
from ..laws.thin_layer import LayerContact, TractionField
from . import save

# Grid of the figures: 64 cells along 2 a1; an odd number of strips puts one on y = 0
# (the x-axis of Figs. 7-8, 10-11).
NX, NY = 64, 33
# Steps per transit time 2 a1/Vx: two per cell (the eta = 10.9 oscillation, 0.3
# contact lengths, gets about 40 steps per period; step error < 1e-3, see the docs).
STEPS_PER_TRANSIT = 128
# Settling band of the transient: 1 % of the quasistationary force.
SETTLE_TOL = 0.01
# Rolled distances (contact lengths 2 a1) of the field snapshots.
SNAPSHOTS = (0.25, 0.5, 1.0, 2.0, 4.0)
ETA_STYLE = {10.9: "-", 2.92: "--", 1.7: ":"}
ETA_COLOR = {10.9: "C0", 2.92: "C1", 1.7: "C2"}


@dataclass
class Run:
    """A time history: t (s), rolled distance s (contact lengths), Vx, vx (m/s), Tx, Ty
    (N); field snapshots keyed by the rolled distance at which they were taken."""

    t: np.ndarray
    s: np.ndarray
    Vx: np.ndarray
    vx: np.ndarray
    Tx: np.ndarray
    Ty: np.ndarray
    snaps: dict[float, TractionField] = field(default_factory=dict)
    final: TractionField | None = None


def _run(
    tb: TransientRollingBody,
    loads: Loads,
    transits: float,
    snapshots: tuple[float, ...] = (),
) -> Run:
    """Advance ``tb`` for ``transits`` contact lengths at STEPS_PER_TRANSIT steps per
    transit (the step follows the present speed), recording every step."""
    c = tb.law
    rec = [(tb.t, 0.0, tb.Vx, tb.vx, tb.out.Tx, tb.out.Ty)]
    s = 0.0
    pending = sorted(snapshots)
    snaps = {}
    while s < transits:
        h = 2.0 * c.a1 / abs(tb.Vx) / STEPS_PER_TRANSIT
        tb.advance(h, loads)
        s += tb.Vx * h / (2.0 * c.a1)  # the Vx of the step's end: a plotting axis only
        rec.append((tb.t, s, tb.Vx, tb.vx, tb.out.Tx, tb.out.Ty))
        while pending and s >= pending[0]:
            snaps[pending.pop(0)] = tb.traction_field()
    a = np.array(rec)
    return Run(*a.T, snaps=snaps, final=tb.traction_field())


def _body_at_rest_field(eta: float, vy_ratio: float, xi0: float = 0.0) -> TransientRollingBody:
    """The body at Vx(0) = Rx/T_c with the creepage vx/Vx = xi0, the field at rest."""
    b = ex.body(eta)
    V0 = ex.speed_unit()
    return TransientRollingBody(
        ex.contact(),
        b,
        Lateral(vy_ratio, 0.0),
        Vx0=V0,
        Omega_y0=V0 * (1.0 - xi0) / b.Rx,
        nx=NX,
        ny=NY,
    )


def steady_creepage(law: LayerContact, Tx: float, vy_ratio: float) -> float:
    """vx/Vx with Tx(vx/Vx, vy/Vx) = Tx on the steady law (Eqs. 40-42)."""
    return brentq(
        lambda xi: float(law.forces(xi, vy_ratio, 0.0, 1.0)[0]) - Tx, -0.05, 0.05, xtol=1e-16
    )


def settling_distance(run: Run, target: float, scale: float) -> float:
    """Rolled distance (contact lengths) after which |Tx - target| <= SETTLE_TOL scale."""
    bad = np.nonzero(np.abs(run.Tx - target) > SETTLE_TOL * abs(scale))[0]
    if bad.size == 0:
        return 0.0
    if bad[-1] + 1 >= run.s.size:
        return math.inf
    return float(run.s[bad[-1] + 1])


# ---- linear theory (docs/transient.md) -------------------------------------------------
def kernel_shape(q: np.ndarray) -> np.ndarray:
    """g(q) = (2/pi)(acos q - q sqrt(1 - q^2)), q = Vx s/(2 a1) in [0, 1]: the memory
    kernel G(s) = (pi a1 a2/k) g of the brush layer over the ellipse."""
    q = np.clip(q, 0.0, 1.0)
    return (2.0 / np.pi) * (np.arccos(q) - q * np.sqrt(1.0 - q * q))


def linear_root(Omega: float) -> complex:
    """Root z = lambda T (T = 2 a1/Vx) of z/Omega^2 + int_0^1 g(q) e^{-z q} dq = 0 near
    the undamped oscillation z = i Omega, Omega = T sqrt(pi a1 a2/(k m)): the slowest
    decaying mode of the linearised transient (no slip)."""

    def ghat(z: complex) -> complex:
        re = quad(
            lambda q: float(kernel_shape(q) * np.exp(-z.real * q) * np.cos(z.imag * q)),
            0,
            1,
            limit=200,
        )[0]
        im = quad(
            lambda q: float(-kernel_shape(q) * np.exp(-z.real * q) * np.sin(z.imag * q)),
            0,
            1,
            limit=200,
        )[0]
        return complex(re, im)

    def eq(v):
        z = complex(v[0], v[1])
        r = z / Omega**2 + ghat(z)
        return [r.real * Omega, r.imag * Omega]

    sol = fsolve(eq, [-0.5, Omega], xtol=1e-12)
    return complex(sol[0], sol[1])


def omega_transit(law: LayerContact, m: float, Vx: float) -> float:
    """Omega = (2 a1/Vx) sqrt(pi a1 a2/(k m)): the fast oscillation per transit (rad)."""
    return 2.0 * law.a1 / Vx * math.sqrt(math.pi * law.a1 * law.a2 / (law.k * m))


# ---- figures ------------------------------------------------------------------------------
def fig12(outdir: Path, runs: dict[float, Run]) -> Path:
    """vx(t) from the start of the motion, vy/Vx = 0.002: transient model against the
    steady-creep-law slip equation (Eq. 20, RollingBody "full") and Eq. (28)."""
    c = ex.contact()
    Tc, V0 = ex.time_unit(c), ex.speed_unit(c)
    Fx = ex.FX_FIG6_12_UNITS * ex.force_unit(c)
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7.5, 7), sharex=True)
    for eta, run in runs.items():
        b = ex.body(eta)
        col = ETA_COLOR[eta]
        ax1.plot(
            run.t / Tc,
            run.vx * 1e3,
            "-",
            color=col,
            lw=1.2,
            label=f"$\\eta$ = {eta}: transient field",
        )
        for method, ls in (("full", "--"), ("quasistationary", ":")):
            rb = RollingBody(c, b, Lateral(0.002, 0.0), method, Vx0=V0, Omega_y0=V0 / b.Rx)
            t, v = [0.0], [rb.vx]
            h = run.t[-1] / 400
            for _ in range(400):
                rb.advance(h, Loads(Fx_ex=Fx))
                t.append(rb.t)
                v.append(rb.vx)
            ax1.plot(np.array(t) / Tc, np.array(v) * 1e3, ls, color=col, lw=0.9)
        target = b.A2 * Fx
        ax2.plot(run.t / Tc, run.Tx / target, color=col, lw=1.0, label=f"$\\eta$ = {eta}")
    ax1.plot([], [], "k--", lw=0.9, label="slip equation, steady creep law (Eq. 20)")
    ax1.plot([], [], "k:", lw=0.9, label="quasistationary (Eq. 28)")
    ax1.set(ylabel="$v_x$ (mm/s)")
    ax1.legend(fontsize=7, ncol=2)
    ax2.axhspan(1 - SETTLE_TOL, 1 + SETTLE_TOL, color="0.85")
    ax2.set(xlabel="$t/T_c$", ylabel="$T_x / (A_2 F_x^{ex})$", ylim=(0, 2.2))
    ax2.legend(fontsize=8)
    eps = math.sqrt(c.a1 * c.a2) / c.Rx
    ax2.text(
        0.98,
        0.05,
        f"one contact length at $V_x(0)$ = {2 * c.a1 / V0 / Tc:.3f} $T_c$; $\\epsilon$ = {eps:.3f}",
        transform=ax2.transAxes,
        ha="right",
        fontsize=8,
    )
    fig.suptitle(
        f"Fig. 12, transient resolved: $F_x^{{ex}}$ = {ex.FX_FIG6_12_UNITS:g} "
        "$\\mu p_0 a_1 a_2$ from $\\tau$ = 0, $v_y/V_x$ = 0.002 (band: $\\pm$1 %)",
        fontsize=10,
    )
    return save(fig, outdir, "transient_fig12_slip_evolution")


def fig_snapshots(
    outdir: Path, runs: dict[float, Run], vy_ratio: float, comp: int, number: int
) -> Path:
    """tau_x (comp 0) or tau_y (comp 1) on y = 0 at rolled distances SNAPSHOTS, per eta,
    with the steady field (LayerContact.traction) of the final creepage."""
    c = ex.contact()
    fig, axes = plt.subplots(1, len(runs), figsize=(11, 3.6), sharey=True)
    name = ("x", "y")[comp]
    cmap = plt.get_cmap("viridis")
    for ax, (eta, run) in zip(axes, runs.items(), strict=True):
        for i, (s, tf) in enumerate(sorted(run.snaps.items())):
            j = int(np.argmin(np.abs(tf.y)))
            tau = (tf.tau_x, tf.tau_y)[comp][j]
            ins = tf.inside[j]
            ax.plot(
                tf.x[ins] / c.a1,
                tau[ins] / (c.mu * c.p0),
                color=cmap(i / len(SNAPSHOTS)),
                lw=1.0,
                label=f"{s:g} $\\cdot 2a_1$",
            )
        tf = run.final
        j = int(np.argmin(np.abs(tf.y)))
        ins = tf.inside[j]
        tau = (tf.tau_x, tf.tau_y)[comp][j]
        ax.plot(
            tf.x[ins] / c.a1,
            tau[ins] / (c.mu * c.p0),
            "k-",
            lw=1.6,
            label=f"{run.s[-1]:.0f} $\\cdot 2a_1$",
        )
        st = c.traction(run.vx[-1], vy_ratio * run.Vx[-1], run.Vx[-1], 161, 1)
        ax.plot(
            st.x / c.a1,
            (st.tau_x, st.tau_y)[comp][0] / (c.mu * c.p0),
            "r--",
            lw=0.9,
            label="steady (Eq. 36)",
        )
        cap = 1.0 - (st.x / c.a1) ** 2
        ax.plot(st.x / c.a1, cap, color="0.6", lw=0.6)
        ax.set(xlabel="$x/a_1$ (rolling towards +x)", title=f"$\\eta$ = {eta}")
    axes[0].set_ylabel(f"$\\tau_{name}/(\\mu p_0)$ on y = 0")
    axes[-1].legend(fontsize=7, title="rolled", title_fontsize=7)
    fig.suptitle(
        f"Fig. {number}, transient: $\\tau_{name}$ after the start from $\\tau$ = 0, "
        f"$v_y/V_x$ = {vy_ratio:g} (grey: $\\mu p$)",
        fontsize=10,
    )
    return save(fig, outdir, f"transient_fig{number:02d}_tau{name}_vy{vy_ratio:g}")


def fig_cattaneo(outdir: Path) -> Path:
    """Cattaneo start: a tangential shift at rest carrying A2 Fx_ex, then rolling from
    pure rolling under the constant Fx_ex (eta = 10.9, vy = 0, one force unit)."""
    c = ex.contact()
    eta = 10.9
    b = ex.body(eta)
    Fx = ex.force_unit(c)
    target = b.A2 * Fx
    tb = _body_at_rest_field(eta, 0.0)

    def excess(delta: float) -> float:
        tb.set_shift(delta)
        return tb.out.Tx - target

    brentq(excess, 0.0, c.k * c.mu * c.p0, xtol=1e-22)  # the shift carrying A2 Fx
    start = tb.traction_field()
    run = _run(tb, Loads(Fx_ex=Fx), 10.0, (0.25, 0.5, 1.0, 2.0))
    xi = steady_creepage(c, target, 0.0)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 3.8))
    ax1.plot(run.s, run.vx / run.Vx / xi, label="$v_x/V_x$ / steady creepage")
    ax1.plot(run.s, run.Tx / target, label="$T_x / (A_2 F_x^{ex})$")
    ax1.axhspan(1 - SETTLE_TOL, 1 + SETTLE_TOL, color="0.85")
    ax1.set(xlabel="rolled distance / $2a_1$", ylim=(-0.5, 2.5))
    ax1.legend(fontsize=8)
    cmap = plt.get_cmap("viridis")
    fields = [(0.0, start), *sorted(run.snaps.items()), (run.s[-1], run.final)]
    for i, (s_, tf) in enumerate(fields):
        j = int(np.argmin(np.abs(tf.y)))
        ins = tf.inside[j]
        ax2.plot(
            tf.x[ins] / c.a1,
            tf.tau_x[j][ins] / (c.mu * c.p0),
            color=cmap(i / len(fields)),
            label=f"{s_:.2g} $\\cdot 2a_1$",
        )
    x = np.linspace(-1, 1, 201)
    ax2.plot(x, 1 - x**2, color="0.6", lw=0.6)
    ax2.set(
        xlabel="$x/a_1$ (rolling towards +x)",
        ylabel="$\\tau_x/(\\mu p_0)$ on y = 0",
        ylim=(0, 0.35),
    )
    ax2.legend(fontsize=7, title="rolled", title_fontsize=7)
    fig.suptitle(
        "Cattaneo start: shift at rest carrying $A_2 F_x^{ex}$, then rolling under "
        "$F_x^{ex}$ = $\\mu p_0 a_1 a_2$, $\\eta$ = 10.9, $v_y$ = 0",
        fontsize=10,
    )
    return save(fig, outdir, "transient_cattaneo_start")


# ---- durations ------------------------------------------------------------------------
@dataclass
class Duration:
    eta: float
    case: str
    Fx_units: float
    s_settle: float  # contact lengths to within 1 % of the quasistationary force
    s_settle_jump: float  # ... within 1 % of the jump, around the drift-corrected force
    drift: float  # m xi* A1 (Fx + My/Rx)/M (N): the full model's O(epsilon) term m dvx/dt
    target: float  # Tx of Eq. (26) after the change (N)
    t_settle: float  # s
    Vx0: float
    Vx_settle: float
    vx_settle: float
    vx_eq22: float  # xi* Vx(0): the transient phase's Eq. (22)
    vx_eq26: float  # xi* Vx(t): the quasistationary Eq. (26)
    run: Run | None = None


def _step_case(eta: float, Fx_units: float, case: str, transits: float) -> Duration:
    """From the quasistationary state at Vx(0) = Rx/T_c under Fx_ex (steady field of the
    steady creepage, ``start_steady``), a sudden change of the loads at t = 0:
    "start": from tau = 0 (the field at rest) under Fx_ex;
    "Fx": Fx_ex -> 1.25 Fx_ex; "My": My_ex 0 -> -0.2 mu p0 Rx a1 a2 (Fig. 13's
    amplitude, in the direction that raises Tx)."""
    c = ex.contact()
    b = ex.body(eta)
    unit = ex.force_unit(c)
    Fx = Fx_units * unit
    if case == "start":
        tb = _body_at_rest_field(eta, 0.002)
        L1, T0 = Loads(Fx_ex=Fx), 0.0
    else:
        tb = _body_at_rest_field(eta, 0.002, steady_creepage(c, b.A2 * Fx, 0.002))
        tb.start_steady()
        T0 = b.A2 * Fx
        L1 = Loads(Fx_ex=1.25 * Fx) if case == "Fx" else Loads(Fx_ex=Fx, My_ex=-0.2 * unit * b.Rx)
    target = b.tx_demand(L1.Fx_ex, L1.My_ex)  # Eq. (26)
    xi = steady_creepage(c, target, 0.002)
    # On the quasistationary manifold vx = xi* Vx(t), so the full slip equation keeps
    # m dvx/dt = m xi* dVx/dt = m xi* A1 (Fx + My/Rx)/M, which Eq. (26) drops (O(eps)).
    drift = b.m_slip * xi * b.A1 * (L1.Fx_ex + L1.My_ex / b.Rx) / b.M
    Vx0 = tb.Vx
    run = _run(tb, L1, transits)
    s1 = settling_distance(run, target, target)
    s2 = settling_distance(run, target - drift, target - T0)
    i = int(np.searchsorted(run.s, s1)) if math.isfinite(s1) else -1
    return Duration(
        eta,
        case,
        Fx_units,
        s1,
        s2,
        drift,
        target,
        float(run.t[i]),
        Vx0,
        float(run.Vx[i]),
        float(run.vx[i]),
        xi * Vx0,
        xi * float(run.Vx[i]),
        run,
    )


def durations(transits: float = 16.0) -> list[Duration]:
    """The transient durations of docs/transient.md."""
    out = []
    for eta in ex.ETA_FIG6_12:
        out.append(_step_case(eta, 1.0, "start", transits))
        for case in ("start", "Fx", "My"):
            out.append(_step_case(eta, ex.FX_FIG6_12_UNITS, case, transits))
    return out


def fig_durations(outdir: Path, rows: list[Duration]) -> Path:
    fig, axes = plt.subplots(1, 3, figsize=(11, 3.6), sharey=True)
    for ax, case in zip(axes, ("start", "Fx", "My"), strict=True):
        for d in rows:
            if d.case != case or d.Fx_units != ex.FX_FIG6_12_UNITS:
                continue
            ax.semilogy(
                d.run.s,
                np.abs(d.run.Tx / d.target - 1.0),
                color=ETA_COLOR[d.eta],
                lw=0.9,
                label=f"$\\eta$ = {d.eta}: {d.s_settle:.1f}",
            )
        ax.axhline(SETTLE_TOL, color="k", lw=0.6)
        ax.set(
            xlabel="rolled distance / $2a_1$",
            ylim=(1e-5, 2),
            title={
                "start": "start from $\\tau$ = 0",
                "Fx": "$F_x^{ex} \\to 1.25 F_x^{ex}$",
                "My": "$M_y^{ex}$: 0 $\\to$ -0.2 $\\mu p_0 R_x a_1 a_2$",
            }[case],
        )
        ax.legend(fontsize=7, title="1 % reached at", title_fontsize=7)
    axes[0].set_ylabel("$|T_x / T_x^{qs} - 1|$ (Eq. 26)")
    fig.suptitle(
        f"Duration of the transient, $F_x^{{ex}}$ = {ex.FX_FIG6_12_UNITS:g} "
        "$\\mu p_0 a_1 a_2$, $v_y/V_x$ = 0.002",
        fontsize=10,
    )
    return save(fig, outdir, "transient_durations")


def write_durations(outdir: Path, rows: list[Duration]) -> Path:
    c = ex.contact()
    Tc = ex.time_unit(c)
    eps = math.sqrt(c.a1 * c.a2) / c.Rx
    path = outdir / "transient_durations.csv"
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(
            [
                "eta",
                "case",
                "Fx_ex [mu p0 a1 a2]",
                "s_1% [2a1]",
                "s_1%_of_jump [2a1]",
                "drift/Tx_qs",
                "t_1% [T_c]",
                "t_1%/epsilon [T_c]",
                "Omega",
                "linear e-fold [2a1]",
                "linear period [2a1]",
                "Vx(0) [m/s]",
                "Vx(t_1%) [m/s]",
                "vx(t_1%) [mm/s]",
                "vx Eq.22 [mm/s]",
                "vx Eq.26 [mm/s]",
            ]
        )
        for d in rows:
            Om = omega_transit(c, ex.body(d.eta).m_slip, d.Vx0)
            z = linear_root(Om)
            w.writerow(
                [
                    d.eta,
                    d.case,
                    d.Fx_units,
                    f"{d.s_settle:.2f}",
                    f"{d.s_settle_jump:.2f}",
                    f"{d.drift / d.target:.1e}",
                    f"{d.t_settle / Tc:.3f}",
                    f"{d.t_settle / Tc / eps:.2f}",
                    f"{Om:.2f}",
                    f"{-1.0 / z.real:.2f}",
                    f"{2 * math.pi / z.imag:.3f}",
                    f"{d.Vx0:.3f}",
                    f"{d.Vx_settle:.3f}",
                    f"{d.vx_settle * 1e3:.4f}",
                    f"{d.vx_eq22 * 1e3:.4f}",
                    f"{d.vx_eq26 * 1e3:.4f}",
                ]
            )
    return path


def make_figures(outdir: Path, durations_only: bool = False) -> list[Path]:
    paths = []
    if durations_only:
        rows = durations()
        return [fig_durations(outdir, rows), write_durations(outdir, rows)]
    Fx = ex.FX_FIG6_12_UNITS * ex.force_unit()
    for vy_ratio, first in ((0.002, 7), (0.006, 10)):
        runs = {}
        for eta in ex.ETA_FIG6_12:
            tb = _body_at_rest_field(eta, vy_ratio)
            runs[eta] = _run(tb, Loads(Fx_ex=Fx), 12.0, SNAPSHOTS)
        paths.append(fig_snapshots(outdir, runs, vy_ratio, 0, first))
        paths.append(fig_snapshots(outdir, runs, vy_ratio, 1, first + 1))
        if vy_ratio == 0.002:
            paths.append(fig12(outdir, runs))
    paths.append(fig_cattaneo(outdir))
    rows = durations()
    paths.append(fig_durations(outdir, rows))
    paths.append(write_durations(outdir, rows))
    return paths
