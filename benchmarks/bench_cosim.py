"""Co-simulation cost: scene FMUs against a trivial FMU, creep-law evaluations, fmpy throughput.

    .venv/bin/python benchmarks/bench_cosim.py [--steps 40] [--repeats 5] [--scenes NAME ...]
        [--write]

All in one process and one run, so that ratios are fair on a shared, noisy machine:

1. FMU step cost. A trivial pythonfmu FMU (one state x, one input u, dx/dt = u by
   explicit Euler; built here) and each scene's FMU (body scenes with both steppers)
   are stepped call by call through fmpy's FMU2Slave as a master does: setReal of the
   inputs, doStep, getReal of the outputs. Each step is timed in R fresh runs,
   interleaved with the trivial FMU's; the cost is the mean over the steps of each
   step's fastest run. *slave*: the FMU's class (ContactSlave) in this process, called
   as pythonfmu calls it (set_real, do_step, get_real) without FMI. *model*: the same
   model object stepped without FMI (its compiled step through ctypes, or Python).
2. Creep-law evaluations per second, vectorised: the thin-layer law (LayerContact.forces
   on arrays; without spin, the closed form; with spin, the strip march; compiled,
   stepper.c's cf_layer_forces, where the library is, else numpy) and, if the
   half-space package is present, its creep-force table (CreepTable.forces); the float
   fast path per call as a baseline.
3. fmpy throughput of the Fig. 12 and Fig. 13 scenes: fmpy.simulate_fmu of every case
   (fastest of R), steps per second and real-time factor (simulated time over wall
   time), against the trivial FMU simulated over the same grid.

``--write`` replaces the block BLOCK of docs/performance.md.
"""

from __future__ import annotations

import contextlib
import dataclasses
import datetime
import importlib
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import fmpy
import numpy as np

import fmu_build
from contact_fmu import examples as ex
from contact_fmu import native
from contact_fmu.scenario import discover, load, runner
from contact_fmu.scenario.instance import OK, Instance

if __package__:  # python -m benchmarks
    from . import harness
else:  # run as a script: benchmarks/ is first on sys.path
    import harness  # type: ignore[no-redef]

ROOT, OUT = harness.ROOT, harness.OUT
DOC = harness.PERFORMANCE
BLOCK = "bench_cosim.py"  # the marker block it writes
TARGET_RATIO = 1.5  # target: the thin-layer body FMU's step at most 1.5 x the trivial FMU's
TARGET_RATE = 1e6  # target: vectorised creep-law evaluations per second

NULL_FMU = '''"""Benchmark FMU without physics: inputs {inputs}, outputs {outputs}.

One state x with dx/dt = u (explicit Euler); every output reads x. With one input and
one output this is the trivial FMU (the baseline of the step cost); with a scene's
numbers of inputs and outputs it is that scene's interface floor (pythonfmu + fmpy
exchanging as many values).
"""

from pythonfmu import Fmi2Causality, Fmi2Initial, Fmi2Slave, Fmi2Variability, Real


class {name}(Fmi2Slave):
    author = "contact_fmu benchmarks"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.u = 0.0
        self.x = 0.0
        for name in {inputs}:
            setattr(self, name, 0.0)
            self.register_variable(Real(name, causality=Fmi2Causality.input,
                                        variability=Fmi2Variability.continuous))
        for name in {outputs}:
            self.register_variable(Real(name, causality=Fmi2Causality.output,
                                        variability=Fmi2Variability.continuous,
                                        initial=Fmi2Initial.exact, getter=lambda: self.x))

    def do_step(self, current_time, step_size):
        self.x += step_size * self.u
        return True
'''


def null_fmu(out: Path, n_in: int = 1, n_out: int = 1) -> tuple[Path, tuple, tuple]:
    """A physics-free pythonfmu FMU with n_in inputs (u, u2, ...) and n_out outputs (x,
    x2, ...), built with pythonfmu's command line (cached by its source); (1, 1) is the
    trivial FMU. Returns (path, input names, output names)."""
    inputs = ("u", *(f"u{k}" for k in range(2, n_in + 1)))
    outputs = ("x", *(f"x{k}" for k in range(2, n_out + 1)))
    name = "TrivialBench" if (n_in, n_out) == (1, 1) else f"NullBench{n_in}x{n_out}"
    src = NULL_FMU.format(name=name, inputs=inputs, outputs=outputs)
    target, stamp = out / f"{name}.fmu", out / f"{name}.src"
    if target.is_file() and stamp.is_file() and stamp.read_text() == src:
        return target, inputs, outputs
    out.mkdir(parents=True, exist_ok=True)
    work = Path(tempfile.mkdtemp(prefix="nullfmu-"))
    try:
        script = work / f"{name.lower()}.py"
        script.write_text(src)
        cmd = [sys.executable, "-m", "pythonfmu", "build", "-f", str(script), "-d", str(work)]
        subprocess.run(cmd, check=True, capture_output=True, cwd=work)
        shutil.copyfile(work / f"{name}.fmu", target)
        stamp.write_text(src)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return target, inputs, outputs


def build_trivial(out: Path) -> Path:
    """The trivial FMU, the step-cost baseline: one state x, one input u, dx/dt = u."""
    return null_fmu(out)[0]


# ---- 1. step cost ------------------------------------------------------------------------
class Stepper:
    """A call-by-call FMU run: step k sets the inputs, steps, reads the outputs."""

    INSTANCE = Instance  # the FMI driver (an FMI 3.0 one in bench_native.Stepper3)

    def __init__(self, path: Path, name: str, starts, inputs, outputs, table, h):
        self.inst = self.INSTANCE(path, name, starts)
        self.vin = [self.inst.vars[n].valueReference for n in inputs]
        self.vout = [self.inst.vars[n].valueReference for n in outputs]
        nrows = len(table[inputs[0]])
        self.rows = [[float(table[n][k]) for n in inputs] for k in range(nrows)]
        self.h = h

    def step(self, k: int) -> float:
        fmu = self.inst.fmu
        t0 = time.perf_counter()
        fmu.setReal(self.vin, self.rows[k])
        status = self.inst.step(self.h)
        fmu.getReal(self.vout)
        dt = time.perf_counter() - t0
        if status != OK:
            raise RuntimeError(f"doStep failed: {self.inst.messages[-1:]}")
        return dt

    def close(self) -> None:
        self.inst.close()


class ModelStepper:
    """The scene's model object stepped directly (what the adapter calls per doStep)."""

    def __init__(self, scene, case) -> None:
        cfg = scene.config
        module = importlib.import_module(f"contact_fmu.{cfg.model_module}")
        table = runner.input_table(scene, case)
        params = {v.name: cfg.start(v) for v in cfg.variables
                  if v.causality[cfg.mode] == "parameter"}  # fmt: skip
        params.update(runner.start_values(scene, case))
        self.rows = [{i: float(table[i][k]) for i in scene.inputs} for k in range(len(table))]
        self.model = module.build(cfg, params, self.rows[0], 0.0)
        self.h = scene.step
        # the compiled step where the FMU uses it (BodyModel.fast): what its doStep runs
        self.fast = getattr(self.model, "fast", lambda: None)()
        if self.fast is not None:
            self.fast.push()

    def step(self, k: int) -> float:
        row, fast = self.rows[k], self.fast
        t0 = time.perf_counter()
        if fast is not None:
            for name in fast.INPUTS:
                if name in row:
                    setattr(fast.io, name, row[name])
            if fast.step(self.h):
                return time.perf_counter() - t0
            fast.pull()
        self.model.step(self.h, row)
        self.model.outputs()
        if fast is not None:
            fast.push()
        return time.perf_counter() - t0


class SlaveStepper:
    """The scene FMU's adapter class in this process, called as pythonfmu calls it: what
    the project's code costs per step, without pythonfmu's and fmpy's transport."""

    def __init__(self, scene, case, outputs) -> None:
        from contact_fmu.fmu.slave import ContactSlave

        cls = type("Bench", (ContactSlave,), {"CONFIG": scene.config.to_dict()})
        self.s = s = cls(instance_name="bench")
        vr = {v.name: k for k, v in s.vars.items()}
        s.setup_experiment(0.0)
        s.enter_initialization_mode()
        setters = {"Real": s.set_real, "Integer": s.set_integer, "String": s.set_string}
        for name, value in runner.start_values(scene, case).items():
            kind = type(s.vars[vr[name]]).__name__
            setters[kind]([vr[name]], [int(value) if kind == "Integer" else value])
        s.exit_initialization_mode()
        if s._model is None:
            raise RuntimeError([m.msg for m in s.log_queue][-1:])
        table = runner.input_table(scene, case)
        self.vin = [vr[n] for n in scene.inputs]
        self.vout = [vr[n] for n in outputs]
        self.rows = [[float(table[n][k]) for n in scene.inputs] for k in range(len(table))]
        self.h, self.t = scene.step, 0.0

    def step(self, k: int) -> float:
        s = self.s
        t0 = time.perf_counter()
        s.set_real(self.vin, self.rows[k])
        ok = s.do_step(self.t, self.h)
        s.get_real(self.vout)
        dt = time.perf_counter() - t0
        if not ok:
            raise RuntimeError("do_step failed")
        self.t += self.h
        return dt


def _slave(scene, case, outputs) -> SlaveStepper | None:
    try:
        return SlaveStepper(scene, case, outputs)
    except Exception as e:  # e.g. a law whose data only the built FMU carries
        print(f"{scene.name}: adapter not timed outside the FMU: {e}", file=sys.stderr)
        return None


def _model(scene, case) -> ModelStepper | None:
    try:
        return ModelStepper(scene, case)
    except Exception as e:  # e.g. a law whose data only the built FMU carries
        print(f"{scene.name}: model not timed outside the FMU: {e}", file=sys.stderr)
        return None


def step_costs(trivial: Path, steps: int, repeats: int, only=None) -> list[dict]:
    rows = []
    out = trivial.parent
    for path in discover(ROOT / "scenarios"):
        scene = load(path)
        if only and scene.name not in only:
            continue
        steady_body = scene.config.mode == "body" and scene.config.phase == "steady"
        methods = ("full", "quasistationary") if steady_body else (None,)
        cfg = scene.config
        if steady_body:  # both steppers in one FMU (the transient phase has its own)
            cfg = dataclasses.replace(cfg, methods=("full", "quasistationary"))
        built = fmu_build.build(cfg, OUT)
        sc = dataclasses.replace(scene, config=cfg)
        for method in methods:
            case = scene.cases[0]
            if method is not None:
                case = dataclasses.replace(case, method=method)
            n = min(steps, scene.n_steps)
            table = runner.input_table(sc, case)
            starts = runner.start_values(sc, case)
            kinds = ("scene", "trivial", "model", "floor", "slave")
            times = {k: np.full((repeats, n), np.inf) for k in kinds}
            outputs = [o for o in scene.outputs if o != "regime"]
            null, null_in, null_out = null_fmu(out, len(scene.inputs), len(outputs))
            null_table = {u: table[i] for u, i in zip(null_in, scene.inputs, strict=True)}
            for r in range(repeats):  # interleaved step by step: the same load on all four
                a = Stepper(built.path, f"s{r}", starts, scene.inputs, outputs, table, scene.step)
                b = Stepper(trivial, f"t{r}", {}, ("u",), ("x",), {"u": np.ones(n)}, scene.step)
                c = Stepper(null, f"n{r}", {}, null_in, null_out, null_table, scene.step)
                m = _model(sc, case)
                d = _slave(sc, case, outputs)
                for k in range(n):
                    times["trivial"][r, k] = b.step(k)
                    times["scene"][r, k] = a.step(k)
                    times["floor"][r, k] = c.step(k)
                    if m is not None:
                        times["model"][r, k] = m.step(k)
                    if d is not None:
                        times["slave"][r, k] = d.step(k)
                for stepper in (a, b, c):
                    stepper.close()
            cost = {k: float(np.mean(np.min(v, axis=0))) for k, v in times.items()}
            for k in ("model", "slave"):
                if not np.isfinite(cost[k]):
                    cost[k] = float("nan")
            rows.append({
                "scene": scene.name, "mode": scene.config.mode,
                "method": method or ("transient" if scene.config.phase != "steady" else "-"),
                "layer": scene.config.contact_law == "layer" and steady_body,
                "lateral": scene.config.vy == "eq10" or scene.config.spin == "eq11",
                "h": scene.step, "step": cost["scene"], "trivial": cost["trivial"],
                "model": cost["model"], "floor": cost["floor"], "slave": cost["slave"],
                "io": f"{len(scene.inputs)} in, {len(outputs)} out",
            })  # fmt: skip
            print(f"{scene.name} {method}: {cost['scene'] * 1e6:.0f} us vs trivial "
                  f"{cost['trivial'] * 1e6:.1f} us", file=sys.stderr)  # fmt: skip
    return rows


# ---- 2. creep-law evaluations ------------------------------------------------------------
def _rate(fn, n: int, repeats: int) -> float:
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return n / best


@contextlib.contextmanager
def _numpy_only(on: bool):
    """With ``on``, the law runs as without the compiled library (its numpy path)."""
    saved = dict(native._LOADED)
    if on:
        native._LOADED["stepper"] = None
    try:
        yield
    finally:
        native._LOADED.clear()
        native._LOADED.update(saved)


def law_rates(repeats: int) -> list[dict]:
    rng = np.random.default_rng(1)
    c = ex.contact()
    V = 5.0
    rows = []
    compiled = native.library() is not None
    for n in (10_000, 1_000_000):
        vx = rng.uniform(-2, 2, n) * c.creep_full_slip * V
        vy = rng.uniform(-1, 1, n) * c.creep_full_slip * V
        for numpy in (False, True) if compiled and n == 10_000 else (not compiled,):
            with _numpy_only(numpy):
                rate = _rate(lambda vx=vx, vy=vy: c.forces(vx, vy, 0.0, V), n, repeats)
            law = "thin layer, vectorised (Eqs. 40-43)"
            rows.append({"law": f"{law}, {'numpy' if numpy else 'C'}", "n": n, "rate": rate})
    n = 200
    vx = rng.uniform(-2, 2, n) * c.creep_full_slip * V
    phi = rng.uniform(0.1, 1.0, n)
    for numpy in (False, True) if compiled else (True,):
        with _numpy_only(numpy):
            rate = _rate(lambda: c.forces(vx, 0.0 * vx, phi, V), n, repeats)
        law = "thin layer with spin, vectorised (strip march 64 x 48)"
        rows.append({"law": f"{law}, {'numpy' if numpy else 'C'}", "n": n, "rate": rate})
    pts = [(float(a), 0.0, V) for a in rng.uniform(-2, 2, 20_000) * c.creep_full_slip * V]

    def scalar() -> None:
        for a, b, v in pts:
            c.forces(a, b, 0.0, v)

    rows.append(
        {
            "law": "thin layer, one float call at a time",
            "n": len(pts),
            "rate": _rate(scalar, len(pts), repeats),
        }
    )
    rows += _halfspace_rates(repeats, rng)
    return rows


def _halfspace_rates(repeats: int, rng) -> list[dict]:
    """The half-space creep-force table, if present: a small table of the
    railway contact (12 x 12 elements, 13 x 13 x 9 nodes, as its tests build it)."""
    try:
        from contact_fmu.halfspace.railway import wheel_on_rail
        from contact_fmu.halfspace.table import build_table
    except ImportError:
        return []
    t0 = time.perf_counter()
    table = build_table(wheel_on_rail(n=12), nodes=(13, 13, 9))
    built = time.perf_counter() - t0
    V = 20.0
    rows = []
    for n in (10_000, 1_000_000):
        x = rng.uniform(-2, 2, (3, n)) * np.array([[1.0], [1.0], [0.0]]) * table.creep_full_slip * V
        rate = _rate(lambda x=x: table.forces(x[0], x[1], 0.0, V), n, repeats)
        rows.append(
            {"law": f"half-space table, vectorised (built in {built:.0f} s)", "n": n, "rate": rate}
        )
    return rows


# ---- 3. fmpy throughput ------------------------------------------------------------------
def throughput(trivial: Path, repeats: int) -> list[dict]:
    rows = []
    for name in ("fig12", "fig13"):
        scene = load(ROOT / "scenarios" / f"{name}.toml")
        built = fmu_build.build(scene.config, OUT)
        tmp = Path(tempfile.mkdtemp(prefix=f"bench-{name}-"))
        ttmp = Path(tempfile.mkdtemp(prefix="bench-trivial-"))
        try:
            fmpy.extract(str(built.path), str(tmp))
            fmpy.extract(str(trivial), str(ttmp))
            wall = 0.0
            for case in scene.cases:
                best = np.inf
                for _ in range(repeats):
                    t0 = time.perf_counter()
                    res = runner.simulate_case(tmp, scene, case)
                    best = min(best, time.perf_counter() - t0)
                    if res.error:
                        raise RuntimeError(f"{name}/{case.name}: {res.error}")
                wall += best
            u = np.zeros(scene.n_steps + 1, dtype=[("time", float), ("u", float)])
            u["time"] = scene.grid
            u["u"] = 1.0
            best_t = np.inf
            for _ in range(repeats):
                t0 = time.perf_counter()
                fmpy.simulate_fmu(
                    str(ttmp),
                    input=u,
                    output=["x"],
                    stop_time=scene.stop_time,
                    output_interval=scene.step,
                )
                best_t = min(best_t, time.perf_counter() - t0)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
            shutil.rmtree(ttmp, ignore_errors=True)
        ncase = len(scene.cases)
        steps = scene.n_steps * ncase
        rows.append(
            {
                "scene": name,
                "cases": ncase,
                "steps": steps,
                "h": scene.step,
                "substeps": int(round(scene.step / scene.cases[0].parameters["h_max"])),
                "wall": wall,
                "sim": scene.stop_time * ncase,
                "trivial": best_t * ncase,
            }
        )
    return rows


# ---- markdown ----------------------------------------------------------------------------
def markdown(steps_rows, law_rows, tp_rows, steps: int, repeats: int, scenes=None) -> str:
    today = datetime.date.today().isoformat()
    only = f" --scenes {' '.join(scenes)}" if scenes else ""
    out = [
        f"Measured by `.venv/bin/python benchmarks/bench_cosim.py --steps {steps} --repeats "
        f"{repeats}{only} --write` on {today} ({harness.machine()}; all numbers of one run, in one "
        "process). Absolute times move with "
        "the machine's load by up to 2x; the ratios, measured side by side, much less.",
        "",
        "### FMU step cost against a trivial FMU",
        "",
        "Per communication step (setReal of the scene's inputs, doStep, getReal of its "
        "outputs through fmpy's FMU2Slave; each step the fastest of "
        f"{repeats} runs, interleaved with the trivial FMU's). Trivial FMU: pythonfmu, one "
        "state and one input (dx/dt = u, explicit Euler), built by the benchmark. "
        "*floor*: the same physics-free FMU with the scene's numbers of inputs and outputs "
        "(what pythonfmu and fmpy cost to exchange that many values). *slave*: the FMU's "
        "class (contact_fmu/fmu/slave.py) in this process, called as pythonfmu calls it "
        "(set_real, do_step, get_real) without FMI: the project's code per step, adapter "
        "and model (with native/fmi.c in place of the adapter's methods where the "
        "compiled step runs). *model*: the scene's model stepped without FMI: its "
        "compiled step through ctypes (inputs into the struct, one call; BodyModel.fast; "
        "ctypes' own call cost included, which the FMU calling it from fmi.c does not "
        "pay) where it has one, else the Python model (step and outputs). Target: the "
        f"thin-layer body FMU at most {TARGET_RATIO} x the trivial FMU.",
        "",
        "| scene | mode | stepper | h (s) | values | step us | trivial us | ratio "
        "| floor us | floor / trivial | slave us | model us |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in steps_rows:
        out.append(
            f"| {r['scene']} | {r['mode']} | {r['method']} | {r['h']:g} | {r['io']} "
            f"| {r['step'] * 1e6:.0f} | {r['trivial'] * 1e6:.1f} "
            f"| {r['step'] / r['trivial']:.2f} | {r['floor'] * 1e6:.1f} "
            f"| {r['floor'] / r['trivial']:.2f} | {r['slave'] * 1e6:.1f} "
            f"| {r['model'] * 1e6:.1f} |"
        )
    # the target's FMUs: straight rolling or held lateral ratios (the compiled doStep);
    # with Eqs. (10)-(11) integrated the law marches its spin grid (reported apart)
    body = [r for r in steps_rows if r["mode"] == "body" and r["layer"] and not r["lateral"]]
    lateral = [r for r in steps_rows if r["mode"] == "body" and r["layer"] and r["lateral"]]
    if body:

        def span(key) -> str:
            v = [key(r) / r["trivial"] for r in body]
            return f"{min(v):.2f} to {max(v):.2f}"

        ratios = [r["step"] / r["trivial"] for r in body]
        met = "met" if max(ratios) <= TARGET_RATIO else "**not met**"
        out += [
            "",
            f"The {TARGET_RATIO}x target is {met} for the thin-layer body FMUs without "
            "Eqs. (10)-(11) (steady phase, both steppers): a step costs "
            f"{min(ratios):.2f} to {max(ratios):.2f} "
            "times the trivial FMU's. In trivial steps: exchanging their values with no "
            f"adapter and no physics costs {span(lambda r: r['floor'])}; the project's "
            f"code, adapter and model called in process, {span(lambda r: r['slave'])}. "
            "The whole doStep of these FMUs runs compiled (contact_fmu/native/stepper.c: "
            "internal steps, stage solves, outputs and their check in one call), the "
            "state staying in the kernel's struct, and pythonfmu's setReal, doStep and "
            "getReal reach it without a Python frame (native/fmi.c: the adapter's input "
            "range checks, step checks and output reads in C). Python takes a step only "
            "for what the kernel leaves out (a new load P, a bad input, the cap on "
            "internal steps, FMU state).",
        ]
    if lateral:
        out += [
            "",
            "With Vy and Omega_z integrated (Eqs. 10-11: "
            + ", ".join(f"{r['scene']} {r['method']}" for r in lateral)
            + ") a step costs "
            + ", ".join(f"{r['step'] / r['trivial']:.0f}" for r in lateral)
            + " trivial steps: the adapter in Python around the compiled vector step "
            "(stepper.c, cf_advance_vector; for the quasistationary method its algebraic "
            "stage, one Newton system of n unknowns instead of Lobatto's 2n), whose law "
            "marches its spin grid in every evaluation.",
        ]
    out += [
        "",
        "### Creep-law evaluations per second",
        "",
        f"Best of {repeats}; random creepages up to twice the onset of full slip. Target: "
        f"at least {TARGET_RATE:.0e} vectorised evaluations per second for the "
        "thin-layer law. C: the law compiled (stepper.c, cf_layer_forces; where the "
        "library is); numpy: the same law without the library, in the same run.",
        "",
        "| law | evaluations per call | evaluations/s |",
        "|---|---|---|",
    ]
    out += [f"| {r['law']} | {r['n']:,} | {r['rate']:.3g} |" for r in law_rows]
    out += [
        "",
        "### fmpy throughput, Figs. 12 and 13",
        "",
        "`fmpy.simulate_fmu` of every case of the scene (instantiation to termination, "
        f"fastest of {repeats}); the trivial FMU over the same grid as a baseline.",
        "",
        "| scene | cases x steps | h (s) | internal steps per step | wall (s) | steps/s "
        "| real-time factor | trivial FMU steps/s | slowdown |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in tp_rows:
        sps = r["steps"] / r["wall"]
        tps = r["steps"] / r["trivial"]
        out.append(
            f"| {r['scene']} | {r['cases']} x {r['steps'] // r['cases']} | {r['h']:g} "
            f"| {r['substeps']} | {r['wall']:.2f} | {sps:.0f} | {r['sim'] / r['wall']:.3g} "
            f"| {tps:.0f} | {tps / sps:.1f} |"
        )
    out += [
        "",
        "Real-time factor: simulated seconds per wall-clock second (below 1: slower than "
        "real time). The scenes' steps resolve the slip relaxation (microseconds), so "
        "they run slower than real time; a coarser h_max trades accuracy for speed "
        "(see the work-precision section).",
        "",
    ]
    return "\n".join(out)


def main(argv: list[str] | None = None) -> None:
    ap = harness.parser(__doc__, str(DOC.relative_to(ROOT)))
    ap.add_argument("--steps", type=int, default=40)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--scenes", nargs="*", help="step cost of these scenes only")
    args = ap.parse_args(argv)
    trivial = build_trivial(ROOT / "out" / "bench")
    s = step_costs(trivial, args.steps, args.repeats, args.scenes)
    law = law_rates(args.repeats)
    tp = throughput(trivial, max(2, args.repeats // 2))
    text = markdown(s, law, tp, args.steps, args.repeats, args.scenes)
    harness.publish(text, args.write, DOC, BLOCK)


if __name__ == "__main__":
    main()
