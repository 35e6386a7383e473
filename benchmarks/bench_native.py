"""The native FMU's cost against the pythonfmu FMU and trivial FMUs, and its size.

    .venv/bin/python benchmarks/bench_native.py [--steps 300] [--repeats 5] [--write]

All in one process and one run (ratios, not absolute times, carry over to another
machine):

1. Step cost through fmpy's FMU2Slave, call by call as a master does (setReal of the
   inputs, doStep, getReal of the outputs; bench_cosim.Stepper) over the first steps of
   the Fig. 13 case eta = 3: the native FMU with the quasistationary method and with the
   full method, the pythonfmu FMU with both, a trivial pythonfmu FMU (one state, one
   input; bench_cosim.null_fmu) and a trivial native FMU (the same in C,
   benchmarks/trivial_fmu.c, built here). Repeats interleaved run by run; the cost is
   the mean over the steps of each step's fastest repeat.
2. From the C importer (tests/native_importer.c, no Python): communication steps per
   second of the native Fig. 13 FMU at the scene's step, both methods: the case eta = 3
   (its 320 steps, the scene's inputs) repeated from its start state (fmi2SetFMUstate)
   for N steps; the fastest of three runs. An importer that stops (any answer but
   fmi2OK) ends the benchmark with its message and a non-zero exit status.
3. FMU sizes.
4. The full body FMU (Eqs. 8-11 with the law's spin; stepper.c's vector step on both
   targets) through fmpy's FMU2Slave, native and pythonfmu, each scheme (the full
   method), as 1. with lateral loads swept, communication steps of 2.5e-4 s.

``--write`` replaces the blocks BLOCK (1-3) and FULL_BLOCK (4) of
docs/performance.md; ``--full-body-only`` measures and writes FULL_BLOCK alone.

    .venv/bin/python benchmarks/bench_native.py --spin [--steps 300] [--repeats 5] [--write]

measures instead the full contact FMU with a spin input (the law marching its spin grid
in every evaluation) as in 1.: the native FMU, the pythonfmu FMU with the compiled
library it carries (fmu_build.compiles) and the same pythonfmu FMU built without it
(numpy's march), in one run; ``--write`` replaces SPIN_BLOCK.

    .venv/bin/python benchmarks/bench_native.py --core [--steps 300] [--repeats 5] [--write]

measures instead the pythonfmu FMU delegating to the C core it carries against the same
FMU on its Python path (CONTACT_FMU_CORE=0 when each instance is made), with the native
FMU beside them, as in 1.: Fig. 13 with each method and the full body FMU (Lobatto
IIIC) as in 4.; ``--write`` replaces CORE_BLOCK.

    .venv/bin/python benchmarks/bench_native.py --transient [--steps N] [--repeats R]
        [--importer-steps M] [--write]

(``python -m benchmarks native_transient``: N = M = 350, the whole case, R = 5,
with --callgrind)

measures instead the communication step of fig12_transient (the body on the 32 x 16
thin-layer field, phase "transient"; its case eta = 2.92, the scene's inputs, steps of
20 us) in one run, the repeats interleaved run by run: through fmpy as 1. (setReal,
doStep, getReal of the scene's outputs; FMU2Slave, FMU3Slave for FMI 3.0) the pythonfmu
FMU (the field compiled, its fast path), the same pythonfmu FMU built without the
compiled library (all in Python), the native FMI 2.0 and FMI 3.0 FMUs; and from the C
importers without Python (tests/native_importer.c, native_importer3.c) the two native
FMUs, the case repeated from its start state for M steps, the fastest of three passes
(a whole pass: on a loaded machine it carries more of the other processes' time than
fmpy's rows, which take each step's fastest run). Each figure is
also given as a ratio to the pythonfmu FMU's step through fmpy, the baseline. With
``--callgrind`` the two native FMUs' steps from the C importers are also counted in
machine instructions (valgrind's callgrind, bench_front_ends.py's count: the bench run
of one case and of two, the difference over the 3 x 350 steps between them; the same
count whatever else the machine runs). ``--write`` replaces TRANSIENT_BLOCK.
"""

from __future__ import annotations

import datetime
import os
import platform
import subprocess
import sys
import tempfile
import time
import zipfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

import fmu_build
from contact_fmu.fmu import slave_core
from contact_fmu.fmu.config import ModelConfig
from contact_fmu.scenario import load, runner
from fmu_build import c_importer, native_fmu, native_fmu3

if __package__:  # python -m benchmarks
    from . import harness
    from .bench_cosim import Stepper, null_fmu
    from .bench_front_ends import instructions_per_step
else:  # run as a script: benchmarks/ is first on sys.path
    import harness  # type: ignore[no-redef]
    from bench_cosim import Stepper, null_fmu  # type: ignore[no-redef]
    from bench_front_ends import instructions_per_step  # type: ignore[no-redef]

ROOT, OUT = harness.ROOT, harness.OUT
DOC = harness.PERFORMANCE
# the marker blocks it writes: step cost, importer rate, size; the full body FMU (also
# --full-body-only); the contact FMU with spin (--spin); the pythonfmu FMU's paths (--core)
BLOCK = "bench_native.py"
FULL_BLOCK = "bench_native.py full-body"
SPIN_BLOCK = "bench_native.py spin"
TRANSIENT_BLOCK = "bench_native.py transient"  # --transient: fig12_transient
CORE_BLOCK = "bench_native.py core"  # --core: the pythonfmu FMU's two paths
TRIVIAL_C = Path(__file__).with_name("trivial_fmu.c")


def _trivial_md(name: str, inputs: tuple, outputs: tuple) -> str:
    sv = [
        f'<ScalarVariable name="{n}" valueReference="{k}" causality="input" '
        f'variability="continuous"><Real start="0.0"/></ScalarVariable>'
        for k, n in enumerate(inputs)
    ] + [
        f'<ScalarVariable name="{n}" valueReference="{len(inputs) + k}" causality="output" '
        f'variability="continuous" initial="exact"><Real start="0.0"/></ScalarVariable>'
        for k, n in enumerate(outputs)
    ]
    idx = range(len(inputs) + 1, len(inputs) + len(outputs) + 1)
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        f'<fmiModelDescription fmiVersion="2.0" modelName="{name}" guid="{{{name}}}" '
        'generationTool="benchmarks/bench_native.py" variableNamingConvention="structured">'
        f'<CoSimulation modelIdentifier="{name}" needsExecutionTool="false" '
        'canHandleVariableCommunicationStepSize="true"/>'
        f"<ModelVariables>{''.join(sv)}</ModelVariables><ModelStructure><Outputs>"
        + "".join(f'<Unknown index="{i}" dependencies=""/>' for i in idx)
        + "</Outputs><InitialUnknowns>"
        + "".join(f'<Unknown index="{i}"/>' for i in idx)
        + "</InitialUnknowns></ModelStructure></fmiModelDescription>\n"
    )


def trivial_native(out: Path, n_in: int = 1, n_out: int = 1) -> tuple[Path, tuple, tuple]:
    """The trivial native FMU (benchmarks/trivial_fmu.c) with n_in inputs and n_out
    outputs, compiled like the native FMU; (path, input names, output names) as
    bench_cosim.null_fmu."""
    inputs = ("u", *(f"u{k}" for k in range(2, n_in + 1)))
    outputs = ("x", *(f"x{k}" for k in range(2, n_out + 1)))
    name = f"TrivialNative{n_in}x{n_out}"
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as work:
        lib = Path(work) / f"{name}.so"
        cmd = ["cc", *native_fmu.CFLAGS, f"-DNIN={n_in}", f"-DNOUT={n_out}",
               f"-I{native_fmu.fmi_headers()}", "-o", str(lib), str(TRIVIAL_C)]  # fmt: skip
        subprocess.run(cmd, check=True, capture_output=True)
        target = out / f"{name}.fmu"
        with zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as z:
            z.writestr("modelDescription.xml", _trivial_md(name, inputs, outputs))
            z.write(lib, f"binaries/linux64/{name}.so")
    return target, inputs, outputs


def fig13_configs():
    """The Fig. 13 scene's configuration with each method as its only one."""
    scene = load(ROOT / "scenarios" / "fig13.toml")
    d = scene.config.to_dict()
    methods = ("quasistationary", "full")
    return scene, {m: ModelConfig.from_dict(d | {"methods": [m]}) for m in methods}


def step_costs(steps: int, repeats: int) -> dict[str, float]:
    scene, cfgs = fig13_configs()
    case = scene.case("eta = 3")
    table = runner.input_table(scene, case)
    starts = runner.start_values(scene, case)
    runs = {}
    for m, cfg in cfgs.items():
        io = (starts, scene.inputs, scene.outputs)
        runs[f"native {m}"] = (native_fmu.build(cfg, OUT).path, *io)
        runs[f"pythonfmu {m}"] = (fmu_build.build(cfg, OUT).path, *io)
    n_in, n_out = len(scene.inputs), len([o for o in scene.outputs if o != "regime"])
    trivial = {f"u{k}" if k > 1 else "u": np.full(steps + 1, 1.0) for k in range(1, n_in + 1)}
    for label, (a, b) in (("trivial", (1, 1)), (f"null {n_in}x{n_out}", (n_in, n_out))):
        path, ins, outs = null_fmu(OUT, a, b)
        runs[f"{label} pythonfmu"] = (path, {}, ins, outs)
        path, ins, outs = trivial_native(OUT, a, b)
        runs[f"{label} native"] = (path, {}, ins, outs)
    runs = {
        name: (path, st, ins, [o for o in outs if o != "regime"],
               trivial if name.startswith(("trivial", "null")) else table, scene.step)
        for name, (path, st, ins, outs) in runs.items()
    }  # fmt: skip
    return interleaved(runs, steps, repeats)


class Stepper3(Stepper):
    """bench_cosim.Stepper for an FMI 3.0 FMU (fmpy's FMU3Slave, harness.Instance3): step
    k sets the inputs (setFloat64), steps, reads the outputs (getFloat64)."""

    INSTANCE = harness.Instance3

    def step(self, k: int) -> float:
        inst, fmu = self.inst, self.inst.fmu
        t0 = time.perf_counter()
        fmu.setFloat64(self.vin, self.rows[k])
        status = inst.do_step(inst.time, self.h)
        fmu.getFloat64(self.vout)
        dt = time.perf_counter() - t0
        if status != 0:
            raise RuntimeError(f"fmi3DoStep answered {status}: {inst.messages[-1:]}")
        inst.time += self.h
        return dt


def _is_fmi3(path: Path) -> bool:
    import fmpy

    return fmpy.read_model_description(str(path)).fmiVersion.startswith("3")


class CoreOffStepper(Stepper):
    """bench_cosim.Stepper of a pythonfmu FMU on its Python path: its instance made with
    CONTACT_FMU_CORE=0 (fmu/slave_core.py), the C core it carries left unused."""

    def __init__(self, *args: Any) -> None:
        old = os.environ.get(slave_core.CORE_ENV)
        os.environ[slave_core.CORE_ENV] = "0"
        try:
            super().__init__(*args)
        finally:
            if old is None:
                del os.environ[slave_core.CORE_ENV]
            else:
                os.environ[slave_core.CORE_ENV] = old


PYTHON_PATH = "Python path"  # the runs of CoreOffStepper (by this in their name)


def interleaved(
    runs: dict, steps: int, repeats: int, between: Callable[[], None] | None = None
) -> dict[str, float]:
    """Seconds per step of each run (path, starts, inputs, outputs, input table, h; FMI
    2.0 or 3.0; a pythonfmu FMU on its Python path where the name says PYTHON_PATH): the
    repeats interleaved run by run, the mean over the steps of each step's fastest.
    ``between``: called after each round of runs (more candidates timed in the same
    rounds)."""
    times = {k: np.empty((repeats, steps)) for k in runs}
    kinds = {
        k: Stepper3 if _is_fmi3(run[0]) else CoreOffStepper if PYTHON_PATH in k else Stepper
        for k, run in runs.items()
    }
    for r in range(repeats):
        for name, (path, st, ins, outs, tab, h) in runs.items():
            s = kinds[name](path, name.replace(" ", "_"), st, ins, outs, tab, h)
            try:
                for k in range(steps):
                    times[name][r, k] = s.step(k)
            finally:
                s.close()
        if between is not None:
            between()
    return {k: float(np.mean(np.min(v, axis=0))) for k, v in times.items()}


FULL_BODY_H = 2.5e-4  # s: 3 internal steps of the default h_max (1e-4 s)


def full_body_run(steps: int) -> tuple[ModelConfig, dict[str, Any], list[str]]:
    """The full body FMU's configuration, input table and Real outputs for ``steps``
    steps (the full method): Fx_ex = 0.3 mu P, Fy_ex = 0.3 mu P sin(k/20), Mz_ex = 5e-5
    mu P sin(k/20) (N m; mu P = 300 N at the defaults)."""
    cfg = ModelConfig.full("body")
    s = np.sin(np.arange(steps + 1) / 20.0)
    table = {"P": np.full(steps + 1, 1000.0), "Fx_ex": np.full(steps + 1, 90.0),
             "Fy_ex": 90.0 * s, "My_ex": np.zeros(steps + 1), "Mz_ex": 0.015 * s}  # fmt: skip
    outputs = [v.name for v in cfg.variables if v.causality["body"] == "output"]
    return cfg, table, [o for o in outputs if o != "regime"]


def full_body_costs(steps: int, repeats: int) -> dict[str, float]:
    """Seconds per step of the full body FMU (full_body_run), native and pythonfmu, per
    scheme, interleaved as step_costs."""
    cfg, table, outputs = full_body_run(steps)
    paths = {"native": native_fmu.build(cfg, OUT).path, "pythonfmu": fmu_build.build(cfg, OUT).path}
    runs = {f"{t} {sch}": (p, {"scheme": sch}, list(table), outputs, table, FULL_BODY_H)
            for sch in ("lobatto3c", "sdirk2") for t, p in paths.items()}  # fmt: skip
    return interleaved(runs, steps, repeats)


def core_costs(steps: int, repeats: int) -> dict[str, float]:
    """Seconds per step of the pythonfmu FMU delegating to its C core (fmu/slave_core.py,
    fmi.c's CoreBinding) and of the same FMU on its Python path (CONTACT_FMU_CORE=0: the
    adapter's Python calls around the compiled step, slave_fast.py and fmi.c's Binding),
    with the native FMU beside them: Fig. 13 (case eta = 3) with each method and the full
    body FMU (Lobatto IIIC, full_body_run), interleaved as step_costs."""
    scene, cfgs = fig13_configs()
    case = scene.case("eta = 3")
    table = runner.input_table(scene, case)
    io = (runner.start_values(scene, case), scene.inputs,
          [o for o in scene.outputs if o != "regime"], table, scene.step)  # fmt: skip
    runs = {}
    for m, cfg in cfgs.items():
        python = fmu_build.build(cfg, OUT).path
        runs[f"fig13 {m}: pythonfmu, C core"] = (python, *io)
        runs[f"fig13 {m}: pythonfmu, {PYTHON_PATH}"] = (python, *io)
        runs[f"fig13 {m}: native"] = (native_fmu.build(cfg, OUT).path, *io)
    cfg, full, outputs = full_body_run(steps)
    io = ({"scheme": "lobatto3c"}, list(full), outputs, full, FULL_BODY_H)
    python = fmu_build.build(cfg, OUT).path
    runs["full body: pythonfmu, C core"] = (python, *io)
    runs[f"full body: pythonfmu, {PYTHON_PATH}"] = (python, *io)
    runs["full body: native"] = (native_fmu.build(cfg, OUT).path, *io)
    return interleaved(runs, steps, repeats)


def core_report(cost: dict[str, float], args) -> str:
    lines = [
        f"Made by `benchmarks/bench_native.py --core --steps {args.steps} --repeats "
        f"{args.repeats} --write` on {datetime.date.today()} ({harness.machine()}; the "
        "ratios are the result).",
        "",
        "The pythonfmu FMU delegating every FMI call to the C core it carries "
        "(fmu/slave_core.py; doStep, setReal and getReal through fmi.c's CoreBinding) "
        "against the same FMU on its Python path (CONTACT_FMU_CORE=0: the adapter's calls "
        "around the compiled step), and the native FMU, through fmpy's FMU2Slave (setReal, "
        f"doStep, getReal): Fig. 13, case eta = 3, and the full body FMU (Lobatto IIIC, "
        f"loads swept, steps of {FULL_BODY_H:.1e} s), the first {args.steps} steps, mean of "
        f"each step's fastest of {args.repeats} interleaved runs:",
        "",
        "| FMU | us per step | / Python path | / native |",
        "|---|---|---|---|",
    ]
    for k, v in cost.items():
        model = k.split(":")[0]
        py, nat = cost[f"{model}: pythonfmu, {PYTHON_PATH}"], cost[f"{model}: native"]
        lines.append(f"| {k} | {1e6 * v:.2f} | {v / py:.2f} | {v / nat:.2f} |")
    return "\n".join(lines) + "\n"


def full_report(full: dict[str, float], args) -> str:
    lines = [
        f"Made by `benchmarks/bench_native.py --steps {args.steps} --repeats {args.repeats}"
        f" --full-body-only --write` on {datetime.date.today()} ({harness.machine()}; the "
        "ratios are the result).",
        "",
        "The full body FMU (`--full body`: Eqs. 8-11 with the law's spin, stepper.c's vector "
        "step on both targets) through fmpy's FMU2Slave, the full method: Fx_ex = 0.3 mu P, "
        f"Fy_ex and Mz_ex swept; the first {args.steps} steps of {FULL_BODY_H:.1e} s (3 "
        f"internal steps each), mean of each step's fastest of {args.repeats} interleaved runs:",
        "",
        "| FMU, scheme | us per step | native / pythonfmu | / Lobatto IIIC |",
        "|---|---|---|---|",
    ]
    for k, v in full.items():
        target, scheme = k.split()
        a, b = v / full[f"pythonfmu {scheme}"], v / full[f"{target} lobatto3c"]
        lines.append(f"| {k} | {1e6 * v:.2f} | {a:.2f} | {b:.2f} |")
    lines += [
        "",
        "SDIRK2's stages are solved in turn by Newton with a new matrix every iteration "
        "(integrator._sdirk_vector, mirrored in C: the same iteration), Lobatto IIIC's "
        "coupled pair keeps its matrix from step to step (simplified Newton).",
    ]
    return "\n".join(lines) + "\n"


def spin_costs(steps: int, repeats: int) -> dict[str, float]:
    """The full contact FMU, every step new kinematics with spin (rolling at Rx/T_c,
    creepages and spin creepage phi a1/Vx uniform within +-0.6 of the onset of full slip:
    partial slip), the load held: native; pythonfmu with its compiled march; the same
    pythonfmu FMU built without the library (numpy's march)."""
    from contact_fmu import examples as ex

    cfg = ModelConfig.full("contact")
    law, V = ex.contact(), ex.speed_unit()
    rng = np.random.default_rng(1)
    xi = rng.uniform(-0.6, 0.6, (3, steps + 1)) * law.creep_full_slip
    table = {"P": np.full(steps + 1, ex.P), "Vx": np.full(steps + 1, V), "Vy": xi[1] * V,
             "Omega_y": (V - xi[0] * V) / ex.Rx, "Omega_z": xi[2] * V / law.a1}  # fmt: skip
    outs = [n for n in cfg.outputs if n != "regime"]
    compiles = fmu_build.compiles
    fmu_build.compiles = lambda c: False  # the FMU as built before it carried the library
    try:
        numpy_path = fmu_build.build(cfg, OUT / "numpy_march").path
    finally:
        fmu_build.compiles = compiles
    io = ({}, tuple(table), outs, table, 1e-3)
    runs = {
        "native": (native_fmu.build(cfg, OUT).path, *io),
        "pythonfmu, compiled march": (fmu_build.build(cfg, OUT).path, *io),
        "pythonfmu, numpy march": (numpy_path, *io),
    }
    return interleaved(runs, steps, repeats)


def spin_report(cost: dict[str, float], args) -> str:
    us = {k: 1e6 * v for k, v in cost.items()}
    lines = [
        f"Made by `benchmarks/bench_native.py --spin --steps {args.steps} --repeats "
        f"{args.repeats} --write` on {datetime.date.today()} ({harness.machine()}; the ratios "
        "are the result).",
        "",
        "The full contact FMU (`python -m fmu_build --full contact`, and `--native`) with "
        "new kinematics and spin every step (partial slip, the load held), through fmpy's "
        "FMU2Slave (setReal of the 5 inputs, doStep, getReal of the 12 Real outputs; mean "
        f"of each step's fastest of {args.repeats} interleaved runs of {args.steps} steps). "
        "The pythonfmu FMU carries the compiled strip march (fmu_build.compiles); built "
        "without it, it marches in numpy:",
        "",
        "| FMU | us per step | / native |",
        "|---|---|---|",
    ]
    for k, v in us.items():
        lines.append(f"| {k} | {v:.1f} | {v / us['native']:.2f} |")
    c, n = us["pythonfmu, compiled march"], us["pythonfmu, numpy march"]
    lines += ["", f"The compiled march makes the pythonfmu FMU's step {n / c:.1f} times faster."]
    return "\n".join(lines) + "\n"


TRANSIENT_CASE = "eta = 2.92"
PYTHONFMU = "pythonfmu, compiled (fmpy)"  # the baseline of the transient report


def transient_costs(
    steps: int, repeats: int, importer_steps: int, callgrind: bool = False
) -> tuple[dict[str, float], dict[str, float]]:
    """Seconds per communication step of fig12_transient's case TRANSIENT_CASE: through
    fmpy the pythonfmu FMU (compiled), the same built without the library (Python), the
    native FMI 2.0 and FMI 3.0 FMUs (their first ``steps`` steps, interleaved as
    step_costs); from the C importers the two native FMUs (1 / their steps per second,
    the fastest of their passes in all rounds, which run between step_costs'). With
    ``callgrind`` also the importers' instructions per
    step (else an empty dict)."""
    import fmpy

    scene = load(ROOT / "scenarios" / "fig12_transient.toml")
    case = scene.case(TRANSIENT_CASE)
    cfg = scene.config
    compiles = fmu_build.compiles
    fmu_build.compiles = lambda c: False  # the FMU without contact_fmu/native's library
    try:
        python_path = fmu_build.build(cfg, OUT / "python_path").path
    finally:
        fmu_build.compiles = compiles
    native = {"2": native_fmu.build(cfg, OUT).path, "3": native_fmu3.build(cfg, OUT).path}
    io = (runner.start_values(scene, case), scene.inputs,
          [o for o in scene.outputs if o != "regime"], runner.input_table(scene, case),
          scene.step)  # fmt: skip
    runs = {
        PYTHONFMU: (fmu_build.build(cfg, OUT).path, *io),
        "pythonfmu, Python (fmpy)": (python_path, *io),
        "native FMI 2.0 (fmpy)": (native["2"], *io),
        "native FMI 3.0 (fmpy)": (native["3"], *io),
    }
    steps = min(steps, scene.n_steps)
    rates: dict[str, list[float]] = {}
    with tempfile.TemporaryDirectory() as work:
        work = Path(work)
        argv = {}
        for v, path in native.items():
            unzip = work / f"fmi{v}"
            fmpy.extract(str(path), str(unzip))
            md = fmpy.read_model_description(str(unzip))
            spec = work / f"fmi{v}.txt"
            spec.write_text(_float_parameters_only(c_importer.spec(md, scene, case), md))
            ident = md.coSimulation.modelIdentifier
            folder = f"{platform.machine()}-linux" if v == "3" else "linux64"
            lib = str(unzip / "binaries" / folder / f"{ident}.so")
            exe = str(harness.compile_importer(work, fmi3=v == "3"))
            head = [exe, lib, md.guid] + ([ident] if v == "2" else [])
            argv[f"native FMI {v}.0 (C importer)"] = [*head, "bench", str(spec),
                                                      str(importer_steps)]  # fmt: skip

        def importers() -> None:
            for name, args in argv.items():
                rates.setdefault(name, []).append(harness.importer_rate(args))

        cost = interleaved(runs, steps, repeats, between=importers)
        n = scene.n_steps  # one case against two: 3 x n steps between the counts
        counts = {}
        if callgrind:
            counts = {k: instructions_per_step(a, work, n, 2 * n) for k, a in argv.items()}
    return cost | {name: 1.0 / max(r) for name, r in rates.items()}, counts


def _float_parameters_only(text: str, md) -> str:
    """The importers' input with only the Real (Float64) parameters: they set doubles;
    the grid nx, ny is an integer at its fixed start, the strings stay at theirs."""
    real = {v.valueReference for v in md.modelVariables if v.type in ("Real", "Float64")}
    lines = text.split("\n")
    pairs = lines[2].split()[1:]
    kept = [(a, b) for a, b in zip(pairs[::2], pairs[1::2], strict=True) if int(a) in real]
    lines[2] = f"{len(kept)} " + " ".join(f"{a} {b}" for a, b in kept)
    return "\n".join(lines)


def transient_report(cost: dict[str, float], counts: dict[str, float], args) -> str:
    scene = load(ROOT / "scenarios" / "fig12_transient.toml")
    h, n = scene.step, min(args.steps, scene.n_steps)
    base = cost[PYTHONFMU]
    lines = [
        f"Made by `benchmarks/bench_native.py --transient --steps {args.steps} --repeats "
        f"{args.repeats} --importer-steps {args.importer_steps}"
        f"{' --callgrind' if counts else ''} --write` on "
        f"{datetime.date.today()} ({harness.machine()}; the ratios are the result).",
        "",
        f"fig12_transient, case {TRANSIENT_CASE} (the body on the 32 x 16 field, steps of "
        f"{h:g} s: two internal SDIRK2 steps each). Through fmpy (setReal of the "
        f"{len(scene.inputs)} inputs, doStep, getReal of the Real outputs): the first {n} "
        f"steps, mean of each step's fastest of {args.repeats} interleaved runs. From the C "
        f"importers (no Python): the case repeated from its start state for "
        f"{args.importer_steps} steps, the fastest of three passes in each of {args.repeats} "
        "rounds run between those of fmpy: a whole pass, where fmpy's figure takes each "
        "step's fastest run, so on a loaded machine the importers' rows can come out slower; "
        "the instruction counts below compare their front ends exactly. *Python*: the "
        "pythonfmu FMU built without the "
        "compiled library (fmu_build.compiles), the adapter and the field in Python.",
        "",
        "| FMU (driven by) | us per step | wall s per simulated s | / pythonfmu, compiled |",
        "|---|---|---|---|",
    ]
    for k, v in cost.items():
        lines.append(f"| {k} | {1e6 * v:.1f} | {v / h:.1f} | {v / base:.3f} |")
    if counts:
        ref = counts["native FMI 2.0 (C importer)"]
        lines += [
            "",
            "Instructions per step from the C importers (callgrind; setReal, doStep, getReal, "
            "the case's 350 steps): "
            + ", ".join(
                f"{k.split(' (')[0]} {v:.4g} (ratio {v / ref:.4f})" for k, v in counts.items()
            )  # fmt: skip
            + ".",
        ]
    return "\n".join(lines) + "\n"


def importer_rates(n: int) -> dict[str, float]:
    """Steps per second of the native Fig. 13 FMU from the C importer, per method: the
    case eta = 3 repeated from its start state for n steps."""
    import fmpy

    scene, cfgs = fig13_configs()
    case = scene.case("eta = 3")
    rates = {}
    with tempfile.TemporaryDirectory() as work:
        work = Path(work)
        exe = harness.compile_importer(work)
        for m, cfg in cfgs.items():
            unzip = work / m
            fmpy.extract(str(native_fmu.build(cfg, OUT).path), str(unzip))
            md = fmpy.read_model_description(str(unzip))
            spec = work / f"{m}.txt"
            spec.write_text(c_importer.spec(md, scene, case))
            ident = md.coSimulation.modelIdentifier
            lib = unzip / "binaries" / "linux64" / f"{ident}.so"
            try:
                rates[m] = harness.importer_rate([str(exe), str(lib), md.guid, ident, "bench",
                                          str(spec), str(n)])  # fmt: skip
            except harness.ImporterError as e:
                raise harness.ImporterError(f"native Fig. 13 FMU, {m} method: {e}") from None
    return rates


def scene_steps() -> int:
    """Communication steps of one run of the Fig. 13 scene."""
    scene, _ = fig13_configs()
    return scene.grid.size - 1


def sizes() -> dict[str, int]:
    scene, cfgs = fig13_configs()
    cfg = cfgs["full"]
    return {
        "native": native_fmu.build(cfg, OUT).path.stat().st_size,
        "pythonfmu": fmu_build.build(cfg, OUT).path.stat().st_size,
    }


def report(cost: dict[str, float], rates: dict[str, float], size: dict[str, int], args) -> str:
    us = {k: 1e6 * v for k, v in cost.items()}
    q = us["native quasistationary"]
    lines = [
        f"Made by `benchmarks/bench_native.py --steps {args.steps} --repeats {args.repeats}"
        f" --write` on {datetime.date.today()} ({harness.machine()}; the ratios are the "
        "result).",
        "",
        "Step cost through fmpy's FMU2Slave (setReal, doStep, getReal; Fig. 13, eta = 3, "
        f"the first {args.steps} steps of 1.75e-4 s; mean of each step's fastest of "
        f"{args.repeats} interleaved runs):",
        "",
        "| FMU | us per step | / trivial pythonfmu | / trivial native |",
        "|---|---|---|---|",
    ]
    for k, v in us.items():
        a, b = v / us["trivial pythonfmu"], v / us["trivial native"]
        lines.append(f"| {k} | {v:.2f} | {a:.2f} | {b:.2f} |")
    null = [k for k in us if k.startswith("null") and k.endswith("native")][0]
    lines += [
        "",
        f"The native Fig. 13 FMU with the quasistationary method costs "
        f"{q / us['trivial pythonfmu']:.2f} of the trivial pythonfmu FMU's step (target <= 0.8) "
        f"and {q / us['trivial native']:.2f} of the trivial native FMU's (target <= 1.3). "
        f"The trivial FMUs exchange one value each way, Fig. 13 three inputs and six outputs: "
        f"against a native FMU without physics exchanging as many ({null}), the native "
        f"Fig. 13 step costs {q / us[null]:.2f} of it; the rest is fmpy's cost per value. "
        "The C importer below measures the FMU without a Python master.",
        "",
        f"From the C importer (tests/native_importer.c, no Python; the case eta = 3, its "
        f"{scene_steps()} steps of 1.75e-4 s with the scene's inputs, repeated from its start "
        f"state for {args.importer_steps} steps; fastest of three runs): "
        + ", ".join(f"{m} {r:.3g} steps/s" for m, r in rates.items())
        + " (target >= 2e5).",
        "",
        f"Size of the Fig. 13 FMU: native {size['native'] / 1024:.0f} KiB (binary, C sources), "
        f"pythonfmu {size['pythonfmu'] / 1024:.0f} KiB "
        f"({size['native'] / size['pythonfmu']:.2f} of it).",
    ]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = harness.parser(__doc__)
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--importer-steps", type=int, default=200_000)
    ap.add_argument("--full-body-only", action="store_true")
    ap.add_argument("--spin", action="store_true", help="the contact FMU with spin only")
    ap.add_argument("--transient", action="store_true", help="fig12_transient's FMUs only")
    ap.add_argument("--callgrind", action="store_true", help="with --transient: instructions")
    ap.add_argument("--core", action="store_true", help="the pythonfmu FMU's two paths only")
    args = ap.parse_args(argv)
    if args.callgrind and not args.transient:
        ap.error("--callgrind is an option of --transient")
    if args.transient:
        try:
            cost, counts = transient_costs(
                args.steps, args.repeats, args.importer_steps, args.callgrind
            )
        except harness.ImporterError as e:
            print(f"bench_native: fig12_transient: {e}", file=sys.stderr)
            return 1
        text = transient_report(cost, counts, args)
        harness.publish(text, args.write, DOC, TRANSIENT_BLOCK)
        return 0
    if args.core:
        text = core_report(core_costs(args.steps, args.repeats), args)
        harness.publish(text, args.write, DOC, CORE_BLOCK)
        return 0
    if args.spin:
        text = spin_report(spin_costs(args.steps, args.repeats), args)
        harness.publish(text, args.write, DOC, SPIN_BLOCK)
        return 0
    if not args.full_body_only:
        try:
            rates = importer_rates(args.importer_steps)
        except harness.ImporterError as e:
            print(f"bench_native: {e}", file=sys.stderr)
            return 1
        text = report(step_costs(args.steps, args.repeats), rates, sizes(), args)
        harness.publish(text, args.write, DOC, BLOCK)
    text = full_report(full_body_costs(args.steps, args.repeats), args)
    harness.publish(text, args.write, DOC, FULL_BLOCK)
    return 0


if __name__ == "__main__":
    sys.exit(main())
