"""The thin-layer transient field compiled (contact_fmu/native/field.c) against its
Python reference, in one run.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_transient_field.py \
        [--steps 200] [--repeats 5] [--write]

Measured on the scene fig12_transient (32 x 16 cells, the thin-layer law of Section 4,
case eta = 2.92, half a cell per internal step), each path on its own model from the
same start, repeats interleaved path by path, the fastest repeat kept:

1. one field stage (LayerField.stage at a developed field: 40 half cells rolled near
   full slip), with and without the Jacobian the vector stage solve asks for;
2. one internal step of the body on the field (TransientRollingBody.advance: SDIRK2, two
   stage solves of 3-5 field stages each; compiled, the whole advance is one C call),
   over the first ``--steps`` communication steps;
3. one communication step of the FMU's body model (body_transient: two internal steps,
   the outputs with the field summary, the range check).

``--write`` replaces the block BLOCK of docs/performance.md.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse  # noqa: E402
import datetime  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

from contact_fmu.dynamics.body import Loads  # noqa: E402
from contact_fmu.dynamics.thin_layer_field import LayerField  # noqa: E402
from contact_fmu.fmu import body_transient  # noqa: E402
from contact_fmu.native import field as native_field  # noqa: E402
from contact_fmu.scenario import load  # noqa: E402

if __package__:  # python -m benchmarks
    from . import harness
else:  # run as a script: benchmarks/ is first on sys.path
    import harness  # type: ignore[no-redef]

ROOT = harness.ROOT
DOC = harness.PERFORMANCE
BLOCK = "bench_transient_field.py"  # the marker block it writes
SCENE = load(ROOT / "scenarios" / "fig12_transient.toml")
CASE = SCENE.cases[1]  # eta = 2.92: the longest transient
PATHS = ("compiled", "Python")


def _model(native_on: bool):
    params = {**SCENE.config.starts, **CASE.parameters, "field_file": "", "field_times": ""}
    inputs = {"P": SCENE.config.starts["P"], "Fx_ex": SCENE.config.starts["Fx_ex"]}
    model = body_transient.build(SCENE.config, params, inputs, 0.0)
    model.stepper.field.native = native_on
    model.stepper.field.__dict__.pop("_cf", None)
    return model, inputs


def stage_cost(repeats: int, n: int) -> dict[tuple[str, bool], float]:
    """us per field stage, by (path, jacobian)."""
    model, _ = _model(True)
    rb = model.stepper
    f = LayerField(rb.law, rb.field.nx, rb.field.ny)
    V, slip = rb.Vx, 0.6 * rb.law.creep_full_slip * rb.Vx
    for _ in range(40):
        f.roll(0.5 * f.dx / V, slip, 0.3 * slip, V, 2.0)
    base = f.begin()
    hat = (base.tau_x, base.tau_y)
    args = (0.3 * f.dx, 0.3 * f.dx / V, 0.09 * f.dx / V, slip, 0.3 * slip, 0.0, V)
    best: dict[tuple[str, bool], float] = {}
    for _ in range(repeats):
        for path in PATHS:
            f.native = path == "compiled"
            for jac in (False, True):
                reps = n if f.native else max(n // 10, 1)
                t0 = time.perf_counter()
                for _ in range(reps):
                    f.stage(base, hat, *args, jacobian=jac)
                us = (time.perf_counter() - t0) / reps * 1e6
                best[(path, jac)] = min(best.get((path, jac), us), us)
    return best


def step_cost(repeats: int, steps: int) -> dict[str, tuple[float, float, int]]:
    """(ms per internal step, ms per communication step, internal steps) by path: the
    stepper's advance alone, then the model's step on another model."""
    h = SCENE.config.experiment[2]
    best: dict[str, list[float]] = {}
    for _ in range(repeats):
        for path in PATHS:
            model, inputs = _model(path == "compiled")
            loads = Loads(Fx_ex=inputs["Fx_ex"])
            internal, spent = 0, 0.0
            for _ in range(steps):
                n = model.internal_steps(h)
                t0 = time.perf_counter()
                model.stepper.advance(h, loads, n)
                spent += time.perf_counter() - t0
                internal += n
            model, inputs = _model(path == "compiled")
            t0 = time.perf_counter()
            for _ in range(steps):
                model.step(h, inputs)
            comm = (time.perf_counter() - t0) / steps * 1e3
            row = [spent / internal * 1e3, comm, internal]
            old = best.setdefault(path, row)
            best[path] = [min(old[0], row[0]), min(old[1], row[1]), internal]
    return {k: (v[0], v[1], int(v[2])) for k, v in best.items()}


def report(stages: dict, steps: dict, args: argparse.Namespace) -> str:
    when = datetime.date.today().isoformat()
    lines = [
        "The thin-layer field of the transient phase (`thin_layer_field.LayerField`) runs its stage"
        " (re-indexing, loading, radial return, slip-aware weights, resultant and tangent) in"
        " C where the kernel library is there (`contact_fmu/native/field.c`), and so does the"
        " body's advance on it (`TransientRollingBody.advance`: the SDIRK2 steps, their"
        " stage solves) when vx is the only stage unknown (Vy and Omega_z held at ratios,"
        " loads held): the same arithmetic to rounding (tests/test_native_field.py). The"
        " Python code is the reference, taken with `CONTACT_FMU_NATIVE=0` or"
        " `LayerField.native = False`."
        " Scene fig12_transient, case eta = 2.92, 32 x 16 cells, both paths in one run"
        f" (`benchmarks/bench_transient_field.py --steps {args.steps} --repeats"
        f" {args.repeats} --write` on {when}, {harness.machine()}; fastest repeat):",
        "",
        "| measured | compiled | Python | ratio |",
        "|---|---|---|---|",
    ]
    for jac in (False, True):
        c, p = stages[("compiled", jac)], stages[("Python", jac)]
        what = "one field stage" + (" with its Jacobian" if jac else "")
        lines.append(f"| {what} (us) | {c:.1f} | {p:.0f} | {p / c:.1f} |")
    c, p = steps["compiled"], steps["Python"]
    lines.append(f"| one internal step of the body (ms) | {c[0]:.3f} | {p[0]:.2f} | "
                 f"{p[0] / c[0]:.1f} |")  # fmt: skip
    lines.append(f"| one communication step of the FMU's model (ms) | {c[1]:.3f} | "
                 f"{p[1]:.2f} | {p[1] / c[1]:.1f} |")  # fmt: skip
    lines += [
        "",
        f"Over the first {args.steps} communication steps ({c[2]} internal steps). An"
        " internal step is two stage solves of 3-5 field stages each, all in C on the"
        " compiled path (the stage rows include the binding's cost, the internal step"
        " does not pay it per stage). The communication step adds to its two internal"
        " steps the outputs (the field's summary compiled too: cf_field_summary) and the"
        " range check, in Python around one C call each.",
    ]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = harness.parser(__doc__)
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--stages", type=int, default=2000)
    args = ap.parse_args(argv)
    if native_field.library() is None:
        print("no compiled library (no C compiler, or CONTACT_FMU_NATIVE=0)", file=sys.stderr)
        return 1
    text = report(stage_cost(args.repeats, args.stages), step_cost(args.repeats, args.steps), args)
    harness.publish(text, args.write, DOC, BLOCK)
    return 0


if __name__ == "__main__":
    sys.exit(main())
