"""Step cost, size and variable count of each scene's FMU against the full FMU of its mode.

    .venv/bin/python benchmarks/bench_fmu_step.py [--steps N] [--repeats R] [--write]

For every scene (its first case) the scene's FMU and the full FMU of the same mode run
the same inputs through fmpy's FMU2Slave, call by call as a master does (setReal of the
inputs, doStep, getReal of the scene's outputs). Each of the N steps is timed in R fresh
runs; the cost per communication step is the mean over the steps of each step's fastest
run (the machine is shared: the minimum filters out the other processes). "model" is
the same model object called directly in Python (no FMI), timed between the scene FMU's
steps, to separate the FMI/pythonfmu overhead from the numerics.
``--write`` replaces the section "## FMU step cost" of docs/performance.md (the only
place the table lives; docs/fmu.md links to it).
"""

from __future__ import annotations

import datetime
import importlib
import sys
import time
from pathlib import Path

import fmpy
import numpy as np

import fmu_build
from contact_fmu.fmu.config import ModelConfig
from contact_fmu.scenario import discover, load, runner
from contact_fmu.scenario.instance import OK, Instance

if __package__:  # python -m benchmarks
    from . import harness
else:  # run as a script: benchmarks/ is first on sys.path
    import harness  # type: ignore[no-redef]

ROOT, OUT = harness.ROOT, harness.OUT
DOC = harness.PERFORMANCE
BLOCK = "bench_fmu_step.py"  # the marker block it writes
# Untimed runs before the timed ones: the first runs in a process are slower (caches,
# lazy imports), measured up to 1.8x for the model stepped outside the FMU.
WARMUP = 1


def time_fmu(
    path: Path, scene, case, n: int, repeats: int, with_model: bool = False
) -> tuple[float, float, dict[str, float]]:
    """Best mean seconds per step over fresh runs of the FMU and, with ``with_model``, of
    the scene's model object stepped directly (what the adapter calls per doStep),
    interleaved step by step so that both see the same machine speed (it drifts by up
    to 1.5x within a minute here); NaN without. Also the FMU's outputs after n steps."""
    table = runner.input_table(scene, case)
    names = {v.name for v in fmpy.read_model_description(str(path)).modelVariables}
    starts = {k: v for k, v in runner.start_values(scene, case).items() if k in names}
    rows = [{i: float(table[i][k]) for i in scene.inputs} for k in range(n)]
    times = np.full((2, WARMUP + repeats, n), np.inf)
    last: dict[str, float] = {}
    for r in range(WARMUP + repeats):
        model = _model(scene, case, rows[0]) if with_model else None
        with Instance(path, f"bench{r}", starts) as inst:
            refs = [inst.vars[k].valueReference for k in scene.inputs]
            outs = [inst.vars[k].valueReference for k in scene.outputs if k != "regime"]
            fmu = inst.fmu
            for k in range(n):
                t0 = time.perf_counter()
                fmu.setReal(refs, list(rows[k].values()))
                if inst.step(scene.step) != OK:
                    raise RuntimeError(f"{path.name}: {inst.messages[-1:]}")
                fmu.getReal(outs)
                times[0, r, k] = time.perf_counter() - t0
                if model is not None:
                    t0 = time.perf_counter()
                    model.step(scene.step, rows[k])
                    model.outputs()
                    times[1, r, k] = time.perf_counter() - t0
            last = {k: inst.get(k) for k in scene.outputs}
    t_fmu, t_model = np.mean(np.min(times[:, WARMUP:], axis=1), axis=1)
    return float(t_fmu), float(t_model) if with_model else float("nan"), last


# The cornering load of time_full_model: a lateral force and a yaw moment, in units of
# mu P and mu P Rx, that make Vy and Omega_z move (the law then marches its spin grid).
CORNERING = {"Fy_ex": 0.3, "Mz_ex": 0.002}


def time_full_model(
    scene, case, n: int, repeats: int, cornering: bool = False
) -> tuple[float, float]:
    """Best mean seconds per step of the full body FMU's model object stepped directly
    (no FMI), its stepper compiled (stepper.c's vector step, Eqs. 10-11 integrated) and
    in Python (RollingBody._lobatto_vector), interleaved step by step; NaN, NaN in
    contact mode (no stepper). ``cornering``: the scene's inputs plus CORNERING."""
    cfg = ModelConfig.full(scene.config.mode)
    if cfg.mode != "body":
        return float("nan"), float("nan")
    table = runner.input_table(scene, case)
    rows = [{i: float(table[i][k]) for i in scene.inputs} for k in range(n)]
    times = np.full((2, WARMUP + repeats, n), np.inf)
    for r in range(WARMUP + repeats):
        models = [_model(scene, case, rows[0], cfg) for _ in range(2)]
        models[1].stepper._kernel = None  # the Python stepper
        if cornering:
            law, Rx = models[0].stepper.law, models[0].stepper.body.Rx
            unit = {"Fy_ex": law.mu * law.P, "Mz_ex": law.mu * law.P * Rx}
            rows = [row | {k: v * unit[k] for k, v in CORNERING.items()} for row in rows]
        for k in range(n):
            for i, model in enumerate(models):
                t0 = time.perf_counter()
                model.step(scene.step, rows[k])
                model.outputs()
                times[i, r, k] = time.perf_counter() - t0
    compiled, python = np.mean(np.min(times[:, WARMUP:], axis=1), axis=1)
    return float(compiled), float(python)


def _model(scene, case, inputs: dict[str, float], cfg: ModelConfig | None = None):
    """The model object of the scene's FMU (or of ``cfg``'s) as the adapter builds it,
    outside any FMU."""
    cfg = cfg or scene.config
    module = importlib.import_module(f"contact_fmu.{cfg.model_module}")
    params = {v.name: cfg.start(v) for v in cfg.variables if v.causality[cfg.mode] == "parameter"}
    params.update(runner.start_values(scene, case))
    return module.build(cfg, params, inputs, 0.0)


def measure(steps: int, repeats: int) -> list[dict]:
    rows = []
    full = {m: fmu_build.build(ModelConfig.full(m), OUT) for m in ("body", "contact")}
    for path in discover(ROOT / "scenarios"):
        scene = load(path)
        if scene.config.contact_law != "layer":  # the full FMUs hold the layer law; the
            continue  # half-space FMUs' cost: benchmarks/bench_halfspace_fmu.py
        if scene.config.phase != "steady":  # the full FMU has the steady phase only; the
            continue  # field's cost: bench_cosim.py, docs/performance.md
        case = scene.cases[0]
        n = min(steps, scene.n_steps)
        own = fmu_build.build(scene.config, OUT)
        big = full[scene.config.mode]
        t_own, t_model, out_own = time_fmu(own.path, scene, case, n, repeats, with_model=True)
        t_full, _, out_full = time_fmu(big.path, scene, case, n, max(2, repeats // 2))
        t_full_c, t_full_py = time_full_model(scene, case, n, max(2, repeats // 2))
        corner = time_full_model(scene, case, n, max(2, repeats // 2), cornering=True)
        rows.append(
            {
                "scene": scene.name,
                "mode": scene.config.mode,
                "vars": len(scene.config.variables),
                "vars_full": len(ModelConfig.full(scene.config.mode).variables),
                "size": own.path.stat().st_size,
                "size_full": big.path.stat().st_size,
                "files": len(own.modules),
                "files_full": len(big.modules),
                "step": t_own,
                "step_full": t_full,
                "model": t_model,
                "full_model": t_full_c,
                "full_model_py": t_full_py,
                "cornering": corner,
                "dTx": abs(out_own["Tx"] - out_full["Tx"]),
                "n": n,
                "lateral": scene.config.vy == "ratio",  # a held ratio: the footnote
            }
        )
        print(f"{scene.name}: {t_own * 1e6:.0f} us vs {t_full * 1e6:.0f} us", file=sys.stderr)
    return rows


def table(rows: list[dict]) -> str:
    """The step-cost table with its footnote (Markdown)."""
    lines = [
        "| scene | mode | variables (full) | FMU size KiB (full) | modules (full) "
        "| step ms | full FMU step ms | model ms | full model ms: compiled / Python "
        "| abs(Tx - Tx_full) N |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        note = " (*)" if r["lateral"] else ""
        c, py = r["full_model"], r["full_model_py"]
        full_model = "-" if np.isnan(c) else f"{c * 1e3:.3f} / {py * 1e3:.3f} ({py / c:.1f}x)"
        lines.append(
            f"| {r['scene']} | {r['mode']} | {r['vars']} ({r['vars_full']}) "
            f"| {r['size'] / 1024:.0f} ({r['size_full'] / 1024:.0f}) "
            f"| {r['files']} ({r['files_full']}) | {r['step'] * 1e3:.3f} "
            f"| {r['step_full'] * 1e3:.3f} | {r['model'] * 1e3:.3f} | {full_model} "
            f"| {r['dTx']:.1e}{note} |"
        )
    lines += [
        "",
        "(*) Fig. 12 holds vy/Vx = 0.002; the full FMU has no held ratio and integrates "
        "Eq. (10) from Vy = 0 instead, so its Tx differs by the lateral creep.",
    ]
    return "\n".join(lines)


def markdown(rows: list[dict], steps: int, repeats: int) -> str:
    """The body of the docs section: how it was measured, then the table."""
    today = datetime.date.today().isoformat()
    return (
        f"Measured by `benchmarks/bench_fmu_step.py --write` on {today} ({harness.machine()}; "
        f"{steps} steps; each step the fastest of "
        f"{repeats} runs after {WARMUP} untimed, full FMU {max(2, repeats // 2)}). Per "
        "communication step: setReal of the inputs, doStep, getReal of the scene's outputs "
        "through fmpy's FMU2Slave. The full FMU of a mode holds every variable and model "
        "part (Eqs. 10-11 integrated, both steppers); it runs the scene's inputs with its "
        "extra inputs at 0. *model*: the scene's model object stepped in Python without "
        "FMI, timed step by step between the scene FMU's steps. *full model*: the full "
        "FMU's model object stepped the same way, its stepper compiled (stepper.c's "
        "vector step) and in Python, interleaved step by step (fastest of "
        f"{max(2, repeats // 2)} runs each).\n\n" + table(rows) + "\n" + cornering(rows)
    )


def cornering(rows: list[dict]) -> str:
    """The full model's cost when its lateral degrees of freedom move (Markdown)."""
    body = [r for r in rows if not np.isnan(r["cornering"][0])]
    if not body:
        return ""
    cells = "; ".join(
        f"{r['scene']} {r['cornering'][0] * 1e3:.3f} / {r['cornering'][1] * 1e3:.3f} ms "
        f"({r['cornering'][1] / r['cornering'][0]:.1f}x)"
        for r in body
    )
    return (
        "\nCornering: the full model with Fy_ex = "
        f"{CORNERING['Fy_ex']} mu P and Mz_ex = {CORNERING['Mz_ex']} mu P Rx added to "
        "the scene's inputs, so that Vy and Omega_z move and the law marches its spin "
        f"grid (thin_layer.SPIN_GRID) in every evaluation, compiled / Python: {cells}.\n"
    )


def main(argv: list[str] | None = None) -> None:
    ap = harness.parser(__doc__, str(DOC.relative_to(ROOT)))
    ap.add_argument("--steps", type=int, default=40)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    rows = measure(args.steps, args.repeats)
    section = markdown(rows, args.steps, args.repeats)
    print(section)
    if args.write:
        harness.write_block(DOC, BLOCK, section)


if __name__ == "__main__":
    main()
