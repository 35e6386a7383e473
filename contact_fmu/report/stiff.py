"""Run the stiff and extreme cases through the body-mode FMU and check each one.

Checks (each with its measured quantity; see the constants for the tolerances):

- finite: every doStep answers fmi2OK and every output is finite;
- bound: |Tx| <= mu P to rounding;
- dissipation: the friction power Tx vx is never negative (to the stage-solve tolerance);
- oscillation: no step-to-step zig-zag above the solution's own variation
  (``metrics.oscillation``) in Tx or vx;
- convergence: the run repeated at h/2 and h/4 (same internal steps per communication
  step, inputs sampled on each grid): the differences d1 = |y(h) - y(h/2)| and
  d2 = |y(h/2) - y(h/4)| at the communication points of h fall at the observed order
  log2(d1/d2) >= P_MIN, or are at the rounding floor;
- memory: the number of memory blocks the interpreter holds (``sys.getallocatedblocks``
  after a garbage collection) grows by at most MEM_BLOCKS (and less than one block per
  step) over the second half of the longest run, and the resident set
  (``/proc/self/statm``) by at most MEM_RSS_BYTES (the lateral cases: on their long run
  only, StiffCase.memory).
"""

from __future__ import annotations

import dataclasses
import gc
import json
import math
import os
import shutil
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import fmpy
import numpy as np
from numpy.typing import NDArray

import fmu_build

from ..dynamics.integrator import V_STANDSTILL, standstill_weight
from ..dynamics.solvers import SOLVE_RTOL
from ..fmu.config import METHODS, SCHEMES, ModelConfig
from ..laws.thin_layer import SPIN_GRID, LayerContact
from ..scenario.instance import OK, Instance
from ..scenario.signals import parse
from ..study.engine import Engine, once, release
from .metrics import oscillation
from .stiff_cases import StiffCase, cases

FloatArray = NDArray[np.float64]

INPUTS = ("P", "Fx_ex", "My_ex")
OUTPUTS = ("Tx", "vx", "Vx", "regime")
# The lateral cases (StiffCase.lateral): Vy and Omega_z integrated (Eqs. 10-11), the law
# with spin; their inputs and outputs besides the above.
LATERAL_INPUTS = ("Fy_ex", "Mz_ex")
LATERAL_OUTPUTS = ("Ty", "vy", "Mz", "Omega_z")
# |Tx| <= mu P to rounding: the stepper rescales an implied force beyond the capacity
# onto it (a hypot, a quotient, a product: a few units in the last place); 16 of them.
BOUND_RTOL = 16 * np.finfo(float).eps
# The stage equations are solved to SOLVE_RTOL relative to the slip scale v_s (solvers):
# Tx vx can be negative by at most mu P x SOLVE_RTOL v_s (the force is bounded by mu P);
# the check allows 100 times that, in units of mu P v_s.
DISSIPATION_TOL = 100 * SOLVE_RTOL
# Noise of the outputs from the stage solves: vx to SOLVE_RTOL (v_s + |vx|), Tx to
# dT/dv times that, <= (32/(3 pi)) 2 SOLVE_RTOL mu P = 7 SOLVE_RTOL mu P in adhesion
# (h'(0) of Eq. 42; constant in full slip). Zig-zags below 100 SOLVE_RTOL of the scale
# are noise, not oscillation.
NOISE = 100 * SOLVE_RTOL
# Convergence: the ZOH of the inputs is first order in h, the schemes second order
# (Lobatto IIIC's stage order is 1: stiff order reduction towards 1, docs/model.md), so
# halving h must at least halve the differences, up to pre-asymptotic effects; P_MIN
# takes off a quarter of an order for them.
P_MIN = 0.75
# Differences below this (relative to mu P and v_s) are at the noise of the outputs
# summed over the steps compared: nothing left to converge.
CONV_FLOOR = 1e4 * SOLVE_RTOL
# Memory: the interpreter's free lists (tuples, floats, dicts, frames) keep freed
# objects allocated up to bounded sizes and fill slowly over a run: measured over the
# second half of the eta cases' 800-step runs (windows of 400 steps), the count moves by
# 65 to 126 blocks in repeated runs of eta = 1 in a fresh process, 143 once under the
# other CPU code path and 201 once in the test suite's process (eta = inf, whose earlier
# tests had filled other lists; 71-95 in a fresh one, 15-24 over windows of 800 to 3200
# steps: a fill, not a growth per step). A leak of one object per step adds at least as
# many blocks as the window has steps (256 to 500000 here): the limit lies between the
# two, MEM_LEAK_PER_STEP of the window's steps and at most MEM_BLOCKS (300 on the
# 400-step windows, 200 on the 256-step ones). The lateral path (the spin march, the
# adhesion output) fills them for about 1500 steps of a run (+287, +60, +30, +5, +5, +4,
# +5, +6, -5 blocks per 400 steps over 4000 steps of the lateral steps case; +161 and
# +185 over the second half of its 800-step runs): its cases measure memory on a run of
# 4000 steps. RSS: pymalloc arenas are 1 MiB; a leak of 8 bytes per step over the long
# run's measured 5e5 steps reaches 4 MiB.
MEM_BLOCKS = 300
MEM_LEAK_PER_STEP = 25 / 32
MEM_RSS_BYTES = 4 << 20
# The spin law's grid error is measured against a grid this many times finer each way
# (``spin_grid_roughness``): 128 x 96 against 64 x 48. The march is first order in the
# cell size (laws/thin_layer.py), so the difference is about half the 64 x 48 grid's own error:
# the floor errs on the strict side.
ROUGHNESS_REFINE = 2
ROUGHNESS_CHUNK = 64  # states per march: 2 x 64 fields of 128 x 96 complex, 25 MB
PAGE = os.sysconf("SC_PAGE_SIZE") if hasattr(os, "sysconf") else 4096


def config(lateral: bool = False) -> ModelConfig:
    """The FMUs of the suite: body mode, both steppers and schemes; straight rolling, or
    (lateral) Vy and Omega_z from Eqs. (10)-(11)."""
    if lateral:
        return ModelConfig(
            name="stiff_lateral",
            mode="body",
            inputs=INPUTS + LATERAL_INPUTS,
            outputs=("Tx", "Ty", "Mz", "vx", "vy", "Vx", "Omega_z", "regime"),
            methods=METHODS,
            schemes=SCHEMES,
            vy="eq10",
            spin="eq11",
            description="Stiff and extreme cases with the lateral degrees of freedom",
        )
    return ModelConfig(
        name="stiff",
        mode="body",
        inputs=INPUTS,
        outputs=("Tx", "vx", "xi_x", "Vx", "Omega_y", "adhesion", "regime"),
        methods=METHODS,
        schemes=SCHEMES,
        description="Stiff and extreme cases",
    )


@dataclass
class Run:
    """Outputs at the communication points t_1..t_n of one run (t_0 = 0 not included)."""

    t: FloatArray
    values: dict[str, FloatArray]
    status: str | None = None  # the first non-OK doStep, if any
    blocks: tuple[int, int] = (0, 0)  # allocated blocks at half-way and at the end
    rss: tuple[int, int] = (0, 0)  # resident bytes at half-way and at the end
    wall: float = 0.0


def _rss() -> int:
    try:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * PAGE
    except OSError:  # pragma: no cover - not Linux
        return 0


def simulate(fmu_dir: Path, case: StiffCase, h: float, steps: int, memory: bool = False) -> Run:
    """``steps`` communication steps of h through the case's FMU, extracted under
    ``fmu_dir`` (``prepare``)."""
    inputs = INPUTS + (LATERAL_INPUTS if case.lateral else ())
    outputs = OUTPUTS[:-1] + (LATERAL_OUTPUTS if case.lateral else ()) + OUTPUTS[-1:]
    t = np.arange(steps + 1) * h
    u = {n: parse(n, case.inputs[n])(t) for n in inputs}
    vals = {n: np.full(steps, np.nan) for n in outputs}
    run = Run(t[1:], vals)
    t0 = time.perf_counter()
    folder = fmu_dir / config(case.lateral).name
    with Instance(folder, f"stiff-{case.name}", case.start_values(h), unzip_dir=folder) as inst:
        vin = [inst.vars[n].valueReference for n in inputs]
        vout = [inst.vars[n].valueReference for n in outputs if n != "regime"]
        vreg = [inst.vars["regime"].valueReference]
        fmu = inst.fmu
        half = steps // 2
        for k in range(steps):
            if memory and k == half:
                gc.collect()
                b1, r1 = sys.getallocatedblocks(), _rss()
            fmu.setReal(vin, [float(u[n][k]) for n in inputs])
            status = inst.step(h)
            if status != OK:
                msg = inst.messages[-1][1] if inst.messages else ""
                run.status = f"doStep {k + 1} at t = {t[k]:.6g} s: status {status} {msg}"
                break
            out = fmu.getReal(vout)
            for i, n in enumerate(outputs[:-1]):
                vals[n][k] = out[i]
            vals["regime"][k] = fmu.getInteger(vreg)[0]
        if memory and run.status is None:
            gc.collect()
            run.blocks = (b1, sys.getallocatedblocks())
            run.rss = (r1, _rss())
    run.wall = time.perf_counter() - t0
    return run


@dataclass
class Check:
    name: str
    ok: bool
    value: float
    limit: float
    note: str = ""


@dataclass
class Result:
    case: StiffCase
    checks: list[Check] = field(default_factory=list)
    wall: float = 0.0
    # observed orders of convergence, the lowest of the forces' and of the slips' whose
    # differences are above CONV_FLOOR (NaN: all at the floor)
    order_force: float = math.nan
    order_slip: float = math.nan

    @property
    def ok(self) -> bool:
        return all(c.ok for c in self.checks)

    def check(self, name: str) -> Check:
        return next(c for c in self.checks if c.name == name)


def _law(case: StiffCase) -> LayerContact:
    p = case.params
    return LayerContact(
        float(case.inputs["P"]), p["Rx"], p["Ry"], p["k1"], p["k2"], p["kb"], p["ks"], p["mu"]
    )


def _slip_scale(case: StiffCase, Vx: FloatArray) -> FloatArray:
    """v_s = (creepage at the onset of full slip) x max(|Vx|, 1e-9 m/s) at each point."""
    return _law(case).creep_full_slip * np.maximum(np.abs(Vx), 1e-9)


def spin_grid_roughness(case: StiffCase, values: dict[str, FloatArray]) -> FloatArray:
    """The step-to-step change of the spin law's grid error along a run's states (N),
    per zig-zag: r_k = max |E_j+1 - E_j| over the differences j = k-1, k, k+1 (those of
    the zig-zag centred on difference k, metrics.oscillation), for Tx and Ty (2, n - 1);
    E = the strip march's spin correction on SPIN_GRID less the same on a grid
    ROUGHNESS_REFINE times finer each way, at the run's (vx, Vy, Omega_z, Vx) (the blend
    of integrator.forces_at_rest at standstill).

    The forces are the law at the states. With spin the law is a sum over the grid's
    nodes, piecewise smooth: as the states move, nodes cross the stick-slip boundary and
    the resultant's error against the law's limit changes unevenly from step to step.
    Along states free of oscillation the forces' differences are a smooth part plus the
    differences of that error; where the smooth part is monotone over three differences
    and the forces still alternate, the error's differences flipped two of them, so
    their smallest magnitude is at most r_k. A zig-zag of the forces below r_k is the
    law's resolution, not the stepper's: the floor of the forces' oscillation check in
    the lateral cases, whose states are checked at NOISE."""
    law = _law(case)
    vx, Vy, Oz, Vx = (np.asarray(values[n], float) for n in ("vx", "vy", "Omega_z", "Vx"))
    fine = (SPIN_GRID[0] * ROUGHNESS_REFINE, SPIN_GRID[1] * ROUGHNESS_REFINE)

    def error(V: FloatArray) -> FloatArray:
        out = np.empty((2, V.size))
        for i in range(0, V.size, ROUGHNESS_CHUNK):  # the march keeps whole fields
            j = slice(i, i + ROUGHNESS_CHUNK)
            a = law.spin_correction(vx[j], Vy[j], Oz[j], V[j])
            b = law.spin_correction(vx[j], Vy[j], Oz[j], V[j], fine)
            out[:, j] = np.array(a[:2]) - np.array(b[:2])
        return out

    E = error(np.where(np.abs(Vx) < V_STANDSTILL, V_STANDSTILL, Vx))
    near = np.abs(Vx) < V_STANDSTILL
    if np.any(near):  # forces_at_rest: the blend of +V_STANDSTILL and -V_STANDSTILL
        w = standstill_weight(Vx)
        E = np.where(near, w * E + (1.0 - w) * error(np.full_like(Vx, -V_STANDSTILL)), E)
    E = np.where(Oz != 0.0, E, 0.0)  # no spin: the closed form alone
    dE = np.abs(np.diff(E, axis=1))
    pad = np.pad(dE, ((0, 0), (1, 1)))
    return np.maximum(np.maximum(pad[:, :-2], pad[:, 1:-1]), pad[:, 2:])


def _order(d1: float, d2: float) -> float:
    if d2 == 0.0:
        return math.inf if d1 > 0.0 else math.nan
    return math.log2(d1 / d2) if d1 > 0.0 else -math.inf


def evaluate(case: StiffCase, runs: list[Run], memory_run: Run | None) -> Result:
    """The checks of one case from its run at h (first), h/2 and h/4; the memory check
    from ``memory_run`` (None: not measured on this case, StiffCase.memory)."""
    res = Result(case)
    main = runs[0]
    failed = [r.status for r in runs if r.status]
    finite = all(np.all(np.isfinite(v)) for r in runs for v in r.values.values())
    res.checks.append(
        Check("finite", not failed and finite, float(len(failed)), 0.0, failed[0] if failed else "")
    )
    if failed:
        return res
    muP = case.mu_P
    Tx, vx, Vx = (main.values[n] for n in ("Tx", "vx", "Vx"))
    zero = np.zeros_like(Tx)
    Ty, vy, Mz, Oz = (main.values.get(n, zero) for n in LATERAL_OUTPUTS)
    vs = _slip_scale(case, Vx)
    bound = float(np.max(np.hypot(Tx, Ty))) / muP
    res.checks.append(Check("bound", bound <= 1.0 + BOUND_RTOL, bound, 1.0 + BOUND_RTOL))
    # the power of the creep forces on the rigid slip of Eq. (3) (straight: Tx vx)
    power = float(np.min((Tx * vx + Ty * vy + Mz * Oz) / (muP * vs)))
    res.checks.append(Check("dissipation", power >= -DISSIPATION_TOL, power, -DISSIPATION_TOL))
    forces = ("Tx", "Ty") if case.lateral else ("Tx",)
    slips = ("vx", "vy", "Omega_z") if case.lateral else ("vx",)
    a1 = _law(case).a1  # the spin's scale is v_s / a1 (the stage solver's)
    rough: dict[str, FloatArray] = {}  # the spin law's, measured where a force zig-zags
    worst, where = -math.inf, ""
    for var in forces + slips:
        y = main.values[var]
        if var in forces:
            unit, floor = muP, NOISE * muP
        else:  # the stage solver's scales: v_s, and v_s / a1 for the spin
            scale = vs / a1 if var == "Omega_z" else vs
            unit, floor = float(np.max(scale)), NOISE * float(np.max(scale + np.abs(y)))
        o, k = oscillation(y, floor)
        if o > 0.0 and case.lateral and var in forces:
            if not rough:
                rough.update(zip(forces, spin_grid_roughness(case, main.values), strict=True))
            o, k = oscillation(y, floor + rough[var])
        if o / unit > worst:
            worst, where = o / unit, f"{var} at step {k}"
    res.checks.append(Check("oscillation", worst <= 0.0, worst, 0.0, where))
    # convergence at the communication points of h (the first conv_steps of them)
    m = case.conv_steps or case.steps
    vsmax = float(np.max(vs[:m]))
    orders, ok, note = {}, True, []
    spin_scale = vsmax / a1
    scales = [(f, muP) for f in forces] + [(v, spin_scale if v == "Omega_z" else vsmax)
                                           for v in slips]  # fmt: skip
    above = {}  # the orders of the variables whose differences are above the floor
    for var, scale in scales:
        y = [r.values[var][(2**i) - 1 :: 2**i][:m] for i, r in enumerate(runs)]
        d1 = float(np.max(np.abs(y[0] - y[1]))) / scale
        d2 = float(np.max(np.abs(y[1] - y[2]))) / scale
        orders[var] = _order(d1, d2)
        good = d2 <= CONV_FLOOR or orders[var] >= P_MIN
        ok &= good
        if d2 > CONV_FLOOR:
            above[var] = orders[var]
        note.append(f"{var}: d1 {d1:.1e} d2 {d2:.1e}")
    res.order_force = min((above[v] for v in forces if v in above), default=math.nan)
    res.order_slip = min((above[v] for v in slips if v in above), default=math.nan)
    low = min(o for o in orders.values() if not math.isnan(o)) if orders else math.nan
    res.checks.append(Check("convergence", ok, low, P_MIN, "; ".join(note)))
    if memory_run is None:
        return res
    b1, b2 = memory_run.blocks
    r1, r2 = memory_run.rss
    grow = b2 - b1
    rss = r2 - r1
    window = len(memory_run.t) - len(memory_run.t) // 2
    limit = min(MEM_BLOCKS, MEM_LEAK_PER_STEP * window)
    res.checks.append(
        Check(
            "memory",
            grow <= limit and rss <= MEM_RSS_BYTES,
            float(grow),
            float(limit),
            f"RSS {rss / 1024:+.0f} KiB over {window} steps",
        )
    )
    return res


def run_case(case: StiffCase, fmu_dir: Path) -> Result:
    """The case at h, h/2 and h/4; memory measured on the longest run (if case.memory)."""
    t0 = time.perf_counter()
    m = case.conv_steps or case.steps
    runs = []
    for i in range(3):
        h = case.h / 2**i
        steps = case.steps * 2**i if m == case.steps else m * 2**i
        memory = case.memory and i == 2 and m == case.steps
        runs.append(simulate(fmu_dir, case, h, steps, memory=memory))
    memory_run = runs[2] if case.memory else None
    if m != case.steps:  # the long run: the full length at h, memory measured there
        full = simulate(fmu_dir, case, case.h, case.steps, memory=case.memory)
        runs[0] = dataclasses.replace(full)
        memory_run = full if case.memory else None
    res = evaluate(case, runs, memory_run)
    res.wall = time.perf_counter() - t0
    return res


def fmu_files(out_dir: Path) -> dict[str, str]:
    """Build (or take from the cache) the suite's FMUs: {configuration name: FMU file}."""
    out = {}
    for lateral in (False, True):
        cfg = config(lateral)
        out[cfg.name] = str(fmu_build.build(cfg, out_dir).path)
    return out


def _extract(fmus: dict[str, str]) -> Path:
    tmp = Path(tempfile.mkdtemp(prefix="stiff-"))
    for name, path in fmus.items():
        fmpy.extract(path, str(tmp / name))
    return tmp


def prepare(out_dir: Path) -> Path:
    """Build (or take from the cache) the suite's FMUs and extract each into a folder of
    its name under the returned one."""
    return _extract(fmu_files(out_dir))


def _extracted(fmus: dict[str, str]) -> Path:
    """``_extract`` once in this process (removed when released: run_all, the engine)."""
    key = "stiff:" + json.dumps(fmus, sort_keys=True)
    return once(key, lambda: _extract(fmus), lambda d: shutil.rmtree(d, True))


def _run_task(fmus: dict[str, str], case: StiffCase) -> Result:
    return run_case(case, _extracted(fmus))


def run_all(
    out_dir: Path,
    selected: list[StiffCase] | None = None,
    log: Callable[[str], None] = print,
    engine: Engine | None = None,
) -> list[Result]:
    """Every selected case, each a task of ``engine`` (default: in this process)."""
    engine = engine or Engine(workers=0)
    fmus = fmu_files(out_dir)
    try:
        results = engine.map(_run_task, list(selected or cases()), shared=fmus,
                             desc="stiff cases", batch=1)  # fmt: skip
    finally:
        release("stiff:")  # this process's copies (a worker's: at the engine's end)
    for r in results:
        log(row_text(r))
    return results


def row_text(r: Result) -> str:
    flags = " ".join(f"{c.name}={'ok' if c.ok else 'FAIL'}" for c in r.checks)
    return f"  {r.case.name:22s} {'PASS' if r.ok else 'FAIL'}  {r.wall:6.1f} s  {flags}"


CHECK_NAMES = ("finite", "bound", "dissipation", "oscillation", "convergence", "memory")
NOTE = (
    "Each case runs the body-mode FMU through fmpy call by call at its communication "
    "step h, and again at h/2 and h/4 "
    "(same internal steps per communication step). "
    "The lateral cases integrate Vy and Omega_z (Eqs. 10-11) with the law with spin. "
    "Checks: every doStep fmi2OK and every output finite; max |T|/(mu P) <= 1 + 16 eps "
    "(|T| = hypot(Tx, Ty)); min (Tx vx + Ty vy + Mz Omega_z)/(mu P v_s) >= -1e-11 "
    "(friction power on the rigid slip never negative; v_s = creepage at full slip x "
    "|Vx|); no step-to-step oscillation of Tx, vx (lateral: also Ty, vy, Omega_z): a "
    "zig-zag (three successive differences of alternating sign) must not exceed the "
    "solution's own change per step over the four steps around it, where a step-to-step "
    "alternation cancels (excess <= 0; noise floor 1e-11 of the scale; for the lateral "
    "forces plus the change of the spin law's grid error over the same three steps, "
    "measured against a grid twice as fine); convergence: the differences between the "
    "runs at h, h/2 and h/4 fall at an observed order >= 0.75 (first order expected: "
    "zero-order hold of the inputs), or are below 1e-9 of the scale; memory: interpreter "
    "memory blocks "
    "grow by <= 300 (<= 25/32 of the measured steps on shorter windows: less than a leak of "
    "one object per step) and the resident set by <= 4 MiB over the second half of the longest "
    "run (the lateral cases: a run of 4000 steps of their own). Column order T, v: the "
    "lowest observed order of the forces and of the slips (and the spin rate) whose "
    "differences are above that floor; -: all at it."
)


def failures(results: list[Result]) -> str:
    """The failing cases with the first failed check's measurement (empty if none)."""
    lines = []
    for r in results:
        for c in r.checks:
            if not c.ok:
                lines.append(f"- {r.case.name}: {c.name}: {c.note or c.value}")
                break
    return ("Failing:\n\n" + "\n".join(lines) + "\n") if lines else ""


def short_markdown(results: list[Result]) -> str:
    """A compact table (docs/accuracy.md): case, what, result, bound, order, wall time."""
    rows = [
        "| case | what | result | max abs(T)/(mu P) | order T, v | wall (s) |",
        "|---|---|---|---|---|---|",
    ]
    for r in results:
        names = {k.name: k for k in r.checks}
        failed = [k.name for k in r.checks if not k.ok]
        result = "pass" if r.ok else "**FAIL** (" + ", ".join(failed) + ")"
        bound = f"{names['bound'].value:.6f}" if "bound" in names else "-"
        rows.append(
            f"| {r.case.name} | {r.case.what} | {result} | {bound} "
            f"| {_o(r.order_force)}, {_o(r.order_slip)} | {r.wall:.1f} |"
        )
    return "\n".join(rows) + "\n"


def markdown(results: list[Result]) -> str:
    """The table of the cases: pass/fail and the measured quantities."""
    head = (
        "| case | group | method, scheme | h (s) x steps (substeps) | result | max abs(T)/(mu P) "
        "| min T.v/(mu P v_s) | oscillation excess | order T, v | memory blocks, RSS "
        "| wall (s) |\n|---|---|---|---|---|---|---|---|---|---|---|"
    )
    rows = [head]
    for r in results:
        c = r.case
        names = {k.name: k for k in r.checks}
        failed = [k.name for k in r.checks if not k.ok]
        result = "pass" if r.ok else "FAIL: " + ", ".join(failed)
        if "bound" not in names:
            rows.append(
                f"| {c.name} | {c.group} | {c.method}, {c.scheme} | {c.h:g} x {c.steps} "
                f"({c.substeps}) | {result}: {names['finite'].note} | | | | | | {r.wall:.1f} |"
            )
            continue
        mem = names.get("memory")
        memory = "-"
        if mem is not None:
            rss = mem.note.split(" over")[0].removeprefix("RSS ")
            memory = f"{mem.value:+.0f}, {rss}"
        rows.append(
            f"| {c.name} | {c.group} | {c.method}, {c.scheme} | {c.h:g} x {c.steps} "
            f"({c.substeps}) | {result} | {names['bound'].value:.15f} "
            f"| {names['dissipation'].value:.1e} | {names['oscillation'].value:.1e} "
            f"| {_o(r.order_force)}, {_o(r.order_slip)} | {memory} | {r.wall:.1f} |"
        )
    return "\n".join(rows) + "\n"


def _o(x: float) -> str:
    return "-" if math.isnan(x) else ("inf" if math.isinf(x) and x > 0 else f"{x:.2f}")
