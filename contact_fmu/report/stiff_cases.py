"""The stiff and extreme cases: the example of contact_fmu.examples pushed to its edges.

Every case runs the body-mode FMU (full rigid-body dynamics, Eqs. 8-9, straight rolling)
call by call. Inputs are scene signals (``scenario.signals``, data): P, Fx_ex, My_ex.
Loads are written in units of the capacity mu P; with Fx_ex = -My_ex/Rx the drive
A1 (Fx_ex + My_ex/Rx) of Eq. (8) vanishes, Vx stays constant and Eq. (26) gives
Tx = A2 Fx_ex - A1 My_ex/Rx = Fx_ex for every eta: the demanded force, independent of
the body.

epsilon = a1/Rx is set through the layers at fixed load (the law stays the thin-layer
law of Eqs. 32-43 with the example's P, Rx, Ry): the approach delta = epsilon^2 Rx/2
(Eq. 34: a1 = (2 Rx delta)^(1/2)) needs k1 + k2 = pi delta^2 (Rx Ry)^(1/2)/P, and the
tangential compliance keeps the example's ratio kb + ks = 0.64 (k1 + k2). Then the
creepage at the onset of full slip is 2 mu p0 (kb + ks)/a1 = 0.64 mu epsilon, and the
slip relaxation time tau_r = M A2 |Vx| / (dT/dxi) scales with epsilon: the stiffness
ratio T_c/tau_r grows as 1/epsilon (Section 3b of the paper).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from .. import examples as ex

# Tangential over normal layer compliance of the example: (kb + ks)/(k1 + k2).
TANGENTIAL_RATIO = (ex.kb + ex.ks) / (ex.k1 + ex.k2)
MU_P = ex.mu * ex.P
SPEED = ex.speed_unit()  # Rx / T_c, the example's initial speed (m/s)


@dataclass(frozen=True)
class StiffCase:
    """One stiff or extreme case.

    ``params``: every FMU parameter (SI); ``inputs``: signals (scene syntax) of P,
    Fx_ex, My_ex; ``h``: communication step (s); ``steps``: communication steps of the
    run; ``substeps``: internal steps per communication step (h_max = h/substeps);
    ``conv_steps``: communication steps compared in the convergence check (the first
    ones; default all), run again at h/2 and h/4 with the same substeps. Every case
    runs the body-mode FMU through fmpy, the long run too.
    """

    name: str
    group: str
    what: str
    params: dict[str, float]
    inputs: dict[str, Any]
    h: float
    steps: int
    substeps: int = 4
    method: str = "full"
    scheme: str = "lobatto3c"
    conv_steps: int | None = None
    tags: tuple[str, ...] = field(default=())
    # Vy and Omega_z integrated (Eqs. 10-11): inputs Fy_ex, Mz_ex besides, params Iz
    lateral: bool = False
    # the memory check on this case's longest run; the lateral cases leave it to their
    # long run (stiff.MEM_BLOCKS: their first thousand steps fill free lists and caches)
    memory: bool = True

    @property
    def mu_P(self) -> float:
        return self.params["mu"] * float(self.inputs["P"])

    def start_values(self, h: float | None = None) -> dict[str, Any]:
        h = self.h if h is None else h
        return {
            **self.params,
            "h_max": h / self.substeps,
            "method": self.method,
            "scheme": self.scheme,
        }


def params(
    eta: float = 3.0,
    mu: float = ex.mu,
    epsilon: float | None = None,
    k_scale: float = 1.0,
    Vx0: float = SPEED,
) -> dict[str, float]:
    """FMU parameters of the example with the given changes (see the module docstring)."""
    k1, k2, kb, ks = ex.k1, ex.k2, ex.kb, ex.ks
    if epsilon is not None:
        delta = epsilon**2 * ex.Rx / 2.0
        k12 = math.pi * delta**2 * math.sqrt(ex.Rx * ex.Ry) / ex.P
        k1 = k2 = k12 / 2.0
        kb = ks = TANGENTIAL_RATIO * k12 / 2.0
    return {
        "mu": mu, "Rx": ex.Rx, "Ry": ex.Ry, "k1": k1, "k2": k2,
        "kb": kb * k_scale, "ks": ks * k_scale, "M": ex.M,
        "Iy": 0.0 if math.isinf(eta) else ex.M * ex.Rx**2 / eta,
        "Vx0": Vx0, "vx0": 0.0,
    }  # fmt: skip


def steady_sine(mu: float, T: float, mean: float = 0.6, amp: float = 0.3) -> dict[str, Any]:
    """Fx_ex = mean mu P, My_ex = (-mean + amp sin(2 pi t/T)) mu P Rx: by Eq. (26)
    Tx = (mean - A1 amp sin(2 pi t/T)) mu P, and the drive A1 amp mu P sin moves Vx by
    A1 amp mu P T / (2 pi M) at most (0.04 m/s for the example with T = 4 ms)."""
    muP = mu * ex.P
    return {
        "P": ex.P,
        "Fx_ex": mean * muP,
        "My_ex": [-mean * muP * ex.Rx, {"sine": {"amplitude": amp * muP * ex.Rx, "period": T}}],
    }


def held_demand(u: float, ramp: float) -> dict[str, Any]:
    """Tx -> u mu P over a ramp of ``ramp`` s, then held, Vx constant (Fx = -My/Rx)."""
    return {
        "P": ex.P,
        "Fx_ex": {"ramp": {"start": 0.0, "duration": ramp, "height": u * MU_P}},
        "My_ex": {"ramp": {"start": 0.0, "duration": ramp, "height": -u * MU_P * ex.Rx}},
    }


def cases() -> list[StiffCase]:
    out: list[StiffCase] = []
    T = 4e-3  # period of the sine loads (s): 200 steps of 2e-5 s
    for eta in (1.0, 2.5, 10.0, 1e3, math.inf):
        out.append(StiffCase(
            f"eta={eta:g}", "eta", f"eta = {eta:g}; Tx = (0.6 - 0.3 A1 sin) mu P",
            params(eta=eta), steady_sine(ex.mu, T), 2e-5, 200,
        ))  # fmt: skip
    for eps in (1e-1, 1e-2, 1e-3, 1e-4, 1e-5):
        out.append(StiffCase(
            f"epsilon={eps:g}", "epsilon",
            f"a1/Rx = {eps:g} via the layers (creepage at full slip {0.64 * ex.mu * eps:.2g})",
            params(epsilon=eps), steady_sine(ex.mu, T), 2e-5, 200,
        ))  # fmt: skip
    for u in (0.9, 0.99, 0.999):
        out.append(StiffCase(
            f"load={u:g}", "load", f"Tx ramped to {u:g} mu P in 1 ms and held (eta = 2)",
            params(eta=2.0), held_demand(u, 1e-3), 2e-5, 200,
        ))  # fmt: skip
    # no load: an initial slip of 1e-3 Vx decays geometrically (R(z) ~ 0.07 per step of
    # 1e-4 s for Lobatto IIIC) through the whole floating-point range towards zero
    out.append(StiffCase(
        "slip decay", "load", "no load; an initial slip of 1e-3 Vx decays to zero (eta = 2)",
        {**params(eta=2.0), "vx0": SPEED * 1e-3},
        {"P": ex.P, "Fx_ex": 0.0, "My_ex": 0.0}, 1e-4, 200, substeps=1,
    ))  # fmt: skip
    beyond = {
        "P": ex.P,
        "Fx_ex": [{"step": {"time": 5e-4, "height": 1.5 * MU_P}},
                  {"step": {"time": 2.5e-3, "height": -1.5 * MU_P}}],
        "My_ex": [{"step": {"time": 5e-4, "height": -1.5 * MU_P * ex.Rx}},
                  {"step": {"time": 2.5e-3, "height": 1.5 * MU_P * ex.Rx}}],
    }  # fmt: skip
    for method in ("full", "quasistationary"):
        out.append(StiffCase(
            f"load=1.5 {method}", "load",
            f"1.5 mu P from 0.5 to 2.5 ms: gross sliding, then rolling again ({method})",
            params(eta=2.0), beyond, 2.5e-5, 200, method=method,
        ))  # fmt: skip
    # SDIRK2 (R(z) < 0 for z < -2.41) on the smooth loads and on the jumps into and out
    # of gross sliding
    out.append(StiffCase(
        "sdirk2 eta=3", "scheme", "SDIRK2; Tx = (0.6 - 0.3 A1 sin) mu P",
        params(), steady_sine(ex.mu, T), 2e-5, 200, scheme="sdirk2",
    ))  # fmt: skip
    out.append(StiffCase(
        "sdirk2 load=1.5", "scheme", "SDIRK2; 1.5 mu P from 0.5 to 2.5 ms, then rolling again",
        params(eta=2.0), beyond, 2.5e-5, 200, scheme="sdirk2",
    ))  # fmt: skip
    for mu in (1e-3, 1e-2, 1e-1, 1.0):
        out.append(StiffCase(
            f"mu={mu:g}", "mu", f"mu = {mu:g}; Tx = (0.6 - 0.3 A1 sin) mu P",
            params(mu=mu), steady_sine(mu, T), 2e-5, 200,
        ))  # fmt: skip
    # Vx through zero: Fx_ex = -1.5 mu P/2 with eta = 2 (A1 = 2/3, A2 = 1/3) gives
    # Tx = A2 Fx_ex = -0.25 mu P and dVx/dt = A1 Fx_ex / M = -150 m/s^2: from 0.3 m/s
    # through zero at 2 ms to -0.3 m/s at 4 ms.
    through = {"P": ex.P, "Fx_ex": -0.75 * MU_P, "My_ex": 0.0}
    for method in ("full", "quasistationary"):
        out.append(StiffCase(
            f"reversal {method}", "reversal",
            f"Vx from 0.3 m/s through 0 to -0.3 m/s under constant braking ({method})",
            params(eta=2.0, Vx0=0.3), through, 2e-5, 200, method=method,
        ))  # fmt: skip
    # Vx falling to zero and resting: Fx_ex = -F0 (1 - t/t1) until t1, then 0, from
    # Vx0 = A1 F0 t1 / (2 M): Vx reaches 0 at t1 with zero slope and stays.
    F0, t1 = 0.75 * MU_P, 2e-3
    to_rest = {"P": ex.P, "Fx_ex": [-F0, {"ramp": {"start": 0.0, "duration": t1, "height": F0}}],
               "My_ex": 0.0}  # fmt: skip
    out.append(StiffCase(
        "to rest", "reversal", "Vx falls to zero at 2 ms with zero slope and rests",
        params(eta=2.0, Vx0=(2.0 / 3.0) * F0 * t1 / (2.0 * ex.M)), to_rest, 2e-5, 200,
    ))  # fmt: skip
    for k in (1e-9, 1e-4, 10.0, 30.0):
        out.append(StiffCase(
            f"kb+ks x{k:g}", "layer",
            f"tangential compliance x {k:g} (creepage at full slip {k * 0.0099:.2g})",
            params(k_scale=k), steady_sine(ex.mu, T), 2e-5, 200,
        ))  # fmt: skip
    for h in (1e-7, 1e-5, 1e-3, 1e-1, 10.0):
        n = 128
        Tr = n * h
        A1 = 0.75  # eta = 3
        # drive amplitude that moves Vx by at most 0.5 Vx0 over the run
        amp = min(0.2, 0.5 * SPEED * ex.M * 2 * math.pi / (A1 * Tr) / MU_P)
        inputs = {"P": ex.P, "Fx_ex": 0.6 * MU_P, "My_ex": [
            -0.6 * MU_P * ex.Rx, {"sine": {"amplitude": amp * MU_P * ex.Rx, "period": Tr,
                                           "phase": math.pi / 2}}]}  # fmt: skip
        out.append(StiffCase(
            f"h={h:g}", "step", f"communication step {h:g} s, {n} steps, h_max = h/4",
            params(), inputs, h, n,
        ))  # fmt: skip
    out += lateral_cases()
    out.append(StiffCase(
        "long run", "long",
        "1e6 steps of 1e-4 s of the FMU (quasistationary: one stage "
        "solve per held-load step), Tx = (0.6 - 0.3 A1 sin) mu P with a period of 0.2 s",
        params(), steady_sine(ex.mu, 0.2), 1e-4, 1_000_000, substeps=1,
        method="quasistationary", conv_steps=200, tags=("long",),
    ))  # fmt: skip
    return out


def lateral_inputs(Fy: Any = 0.0, Mz: Any = 0.0, Fx: Any = 0.0, My: Any = 0.0) -> dict[str, Any]:
    """The scene signals of a lateral case (P of the example)."""
    return {"P": ex.P, "Fx_ex": Fx, "My_ex": My, "Fy_ex": Fy, "Mz_ex": Mz}


def lateral_cases() -> list[StiffCase]:
    """Vy and Omega_z from Eqs. (10)-(11), the law with spin (its strip march): lateral
    force steps, demands at 0.99 mu P and beyond, yaw moments, Vx through zero under a
    lateral force, eta = inf, a small epsilon and a long step; both methods where the
    quasistationary one has its own path (algebraic stage, gross sliding)."""
    Iz = 0.4 * ex.M * ex.Rx**2  # a solid sphere's, as the cornering scene
    a1 = ex.contact().a1
    out: list[StiffCase] = []

    def add(name: str, what: str, inputs: dict, p: dict, h: float = 2e-5, n: int = 200,
            methods: tuple[str, ...] = ("full", "quasistationary"), **kw: Any) -> None:  # fmt: skip
        for method in methods:
            out.append(StiffCase(
                f"{name} {method}" if len(methods) > 1 else name, "lateral",
                f"{what} ({method})", {**p, "Iz": Iz}, inputs, h, n, method=method,
                lateral=True, **{"memory": False, **kw},
            ))  # fmt: skip

    steps = [{"step": {"time": 5e-4, "height": 0.6 * MU_P}},
             {"step": {"time": 2.5e-3, "height": -1.2 * MU_P}}]  # fmt: skip
    add("lateral steps", "Fy_ex = 0.6 mu P at 0.5 ms, reversed at 2.5 ms",
        lateral_inputs(Fy=steps), params(eta=2.0))  # fmt: skip
    # Near the capacity the quasistationary slip is the inverse creep law, whose slope
    # grows like (1 - |T|/(mu P))^(-2/3) (Eq. 42): the runs at h, h/2, h/4 converge at
    # first order only once a step's change of the demand is below the distance to the
    # capacity, 0.01 mu P here. Ramped over 3 ms, a step of 2e-5 s changes it by
    # 0.0047 mu P (expected order 0.92 from the cube root; over 1 ms: 0.014 mu P, 0.72,
    # measured 0.63 for the slip).
    ramp = {"ramp": {"start": 0.0, "duration": 3e-3, "height": 0.7 * MU_P}}
    ramp_my = {"ramp": {"start": 0.0, "duration": 3e-3, "height": -0.7 * MU_P * ex.Rx}}
    add("lateral 0.99", "Tx and Fy_ex ramped to 0.7 mu P each in 3 ms (abs(T) = 0.99 mu P)",
        lateral_inputs(Fy=ramp, Fx=ramp, My=ramp_my), params(eta=2.0))  # fmt: skip
    beyond = [{"step": {"time": 5e-4, "height": 1.2 * MU_P}},
              {"step": {"time": 2.5e-3, "height": -1.2 * MU_P}}]  # fmt: skip
    add("lateral 1.2", "Fy_ex = 1.2 mu P from 0.5 to 2.5 ms: gross sliding sideways",
        lateral_inputs(Fy=beyond), params(eta=2.0))  # fmt: skip
    yaw = [0.05 * MU_P * a1, {"step": {"time": 2e-3, "height": -0.15 * MU_P * a1}}]
    add("yaw", "Fy_ex = 0.3 mu P, Mz_ex = 0.05 mu P a1 stepped to -0.1 mu P a1 at 2 ms",
        lateral_inputs(Fy=0.3 * MU_P, Mz=yaw), params(eta=2.0))  # fmt: skip
    # as the straight reversal (Tx = -0.25 mu P, Vx from 0.3 m/s through 0 at 2 ms)
    add("lateral reversal", "Vx from 0.3 m/s through 0 to -0.3 m/s, Fy_ex = 0.2 mu P",
        lateral_inputs(Fy=0.2 * MU_P, Fx=-0.75 * MU_P), params(eta=2.0, Vx0=0.3))  # fmt: skip
    sine = {"sine": {"amplitude": 0.5 * MU_P, "period": 4e-3}}
    add("lateral eta=inf", "eta = inf; Fy_ex = 0.5 mu P sin, Tx = 0.3 mu P",
        lateral_inputs(Fy=sine, Fx=0.3 * MU_P, My=-0.3 * MU_P * ex.Rx),
        params(eta=math.inf), methods=("full",))  # fmt: skip
    add("lateral epsilon=0.001", "a1/Rx = 1e-3 via the layers; Fy_ex steps of 0.6 mu P",
        lateral_inputs(Fy=steps), params(eta=2.0, epsilon=1e-3), methods=("full",))  # fmt: skip
    add("lateral h=0.1", "communication step 0.1 s, Fy_ex = 0.5 mu P sin (period 12.8 s)",
        lateral_inputs(Fy={"sine": {"amplitude": 0.5 * MU_P, "period": 12.8}}),
        params(eta=2.0), h=0.1, n=128, methods=("full",))  # fmt: skip
    # memory: 4000 steps, measured over the second half (a leak of one object per step:
    # 2000 blocks; the caches' fill, +300 to +400 blocks over the first 1500 steps, is
    # behind); the lateral force and the yaw moment swept, so that the law marches its
    # spin grid in every evaluation
    add("lateral long run", "4000 steps of 2e-5 s, Fy_ex = 0.5 mu P sin, Mz_ex = 0.05 mu "
        "P a1 cos (period 0.02 s)",
        lateral_inputs(Fy={"sine": {"amplitude": 0.5 * MU_P, "period": 0.02}},
                       Mz={"sine": {"amplitude": 0.05 * MU_P * a1, "period": 0.02,
                                    "phase": math.pi / 2}}),
        params(eta=2.0), n=4000, methods=("full",), memory=True, conv_steps=200,
        tags=("long",))  # fmt: skip
    return out
