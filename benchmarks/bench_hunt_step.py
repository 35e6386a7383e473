"""Hunt for the slowest doStep: random hostile but legal calls per FMU kind, the slowest
kept with its inputs.

    .venv/bin/python benchmarks/bench_hunt_step.py [--instances 6] [--calls 30] [--seed 1]
        [--write]

Each FMU kind (the scenes fig13, rail_traction, cornering and fig12_transient and the full
body FMU, each as a pythonfmu FMU and, where it exists, a native one; fig12_transient also
as the native FMI 3.0 FMU, through harness.Instance3) is instantiated
``--instances`` times with parameters drawn within their declared ranges (mu down to
MU_MIN, M, Iy, Iz and Rx over many decades, h_max from 1e-9 to 1 s, the transient field's
grid; a start that is refused is drawn again), and each instance takes ``--calls``
doSteps: the load P from 0 (lift-off) or 1e-3 N to its declared maximum 1e9 N, Fx_ex and
My_ex / Rx up to the load limit 1e9 mu P with either sign, Fy_ex and Mz_ex / Rx likewise,
h from 1e-12 to 1e6 s, each call from the state the last one left or from the start
(fmi2SetFMUstate). max_work keeps its default: the budget under test. Every doStep is
timed (perf_counter); per kind the slowest is reported with its inputs and status. The
count of calls per kind stays in the hundreds: the machine is shared. The draws of a kind
come from a generator of its own, seeded by ``--seed`` and the kind's name: a kind's draws
do not depend on the kinds hunted before it, and its targets get the same parameters and
calls up to the first start that one refuses and the other takes (the native transient
FMU's grid is fixed at its build: a drawn nx or ny is refused there, drawn again).

``--write`` replaces the table between the markers of docs/reliability.md.
"""

from __future__ import annotations

import argparse
import datetime
import math
import time
import zlib
from pathlib import Path

import numpy as np
from fmpy.fmi1 import FMICallException

import fmu_build
from contact_fmu.fmu.config import ModelConfig
from contact_fmu.scenario import load
from fmu_build import native_fmu, native_fmu3

if __package__:  # python -m benchmarks
    from . import harness
else:  # run as a script: benchmarks/ is first on sys.path
    import harness  # type: ignore[no-redef]

ROOT, OUT = harness.ROOT, harness.OUT
DOC = harness.RELIABILITY
BLOCK = "bench_hunt_step.py"  # the marker block it writes
NAMES = {0: "OK", 1: "Warning", 2: "Discard", 3: "Error", 4: "Fatal"}
LOAD_LIMIT = 1e9  # integrator.LOAD_LIMIT


def kinds() -> list[tuple[str, str, Path]]:
    """(label, target, FMU) of every kind hunted."""
    cfgs = {n: load(ROOT / "scenarios" / f"{n}.toml").config
            for n in ("fig13", "rail_traction", "cornering", "fig12_transient")}  # fmt: skip
    cfgs["full body"] = ModelConfig.full("body")
    held = {
        "name": "full_body_held_spin",
        "vy": "ratio",
        "spin": "ratio",
        "inputs": ["P", "Fx_ex", "My_ex"],
        "starts": {"vy_ratio": 0.002, "spin_ratio": 1.0},
    }
    cfgs["full body, held spin"] = ModelConfig.from_dict(cfgs["full body"].to_dict() | held)
    out = []
    for name, cfg in cfgs.items():
        out.append((name, "pythonfmu", fmu_build.build(cfg, OUT).path))
        if native_fmu.unsupported(cfg) is None:
            out.append((name, "native", native_fmu.build(cfg, OUT).path))
        if name == "fig12_transient":  # the FMI 3.0 front end on the same core
            out.append((name, "native FMI 3.0", native_fmu3.build(cfg, OUT).path))
    return out


def log_uniform(rng: np.random.Generator, lo: float, hi: float) -> float:
    return float(10 ** rng.uniform(math.log10(lo), math.log10(hi)))


def parameters(rng: np.random.Generator, have: set[str]) -> dict[str, float]:
    """Parameters drawn within their declared ranges, each perturbed with probability
    one half (the scene's value otherwise)."""
    draws = {
        "mu": lambda: log_uniform(rng, 1e-9, 2.0),
        "M": lambda: log_uniform(rng, 1e-12, 1e6),
        "Iy": lambda: log_uniform(rng, 1e-12, 1e3) if rng.random() < 0.9 else 0.0,
        "Iz": lambda: log_uniform(rng, 1e-12, 1e3),
        "Rx": lambda: log_uniform(rng, 1e-6, 10.0),
        "h_max": lambda: log_uniform(rng, 1e-9, 1.0),
        "nx": lambda: int(rng.integers(4, 129)),
        "ny": lambda: int(rng.integers(2, 65)),
        "cells_per_step": lambda: log_uniform(rng, 1e-2, 1e2),
    }
    return {k: f() for k, f in draws.items() if k in have and rng.random() < 0.5}


def inputs(rng: np.random.Generator, have: set[str], mu: float, Rx: float, transient: bool):
    """P and loads up to the load limit (1e9 mu P), random signs."""
    P = 0.0 if (not transient and rng.random() < 0.1) else log_uniform(rng, 1e-3, 1e9)
    cap = LOAD_LIMIT * mu * max(P, 1e-3)

    def load() -> float:
        return float(rng.choice([-1.0, 1.0])) * log_uniform(rng, 1e-9 * cap, cap)

    values = {"P": P, "Fx_ex": load(), "My_ex": load() * Rx, "Fy_ex": load(),
              "Mz_ex": load() * Rx}  # fmt: skip
    return {k: v for k, v in values.items() if k in have}


def hunt(path: Path, instances: int, calls: int, rng: np.random.Generator) -> dict:
    """The slowest doStep over the random calls: wall (s), status, t, h, parameters,
    inputs; and the count of calls and of their statuses."""
    worst = {"wall": -1.0}
    count: dict[str, int] = {}
    made = 0
    for _ in range(4 * instances):
        if made == instances:
            break
        with harness.open_fmu(path, "hunt", initialise=False) as b:
            have = set(b.vars)
            params = parameters(rng, have)
            try:
                for k, v in params.items():
                    b.set(k, v)
                b.initialise()
            except FMICallException:
                continue  # a start refused (Error, named): drawn again
            made += 1
            mu, Rx = b.get("mu"), b.get("Rx")
            start = b.get_state()
            for _ in range(calls):
                if rng.random() < 0.5:
                    b.set_state(start)
                ins = inputs(rng, have, mu, Rx, "nx" in have)
                for k, v in ins.items():
                    b.set(k, v)
                h = log_uniform(rng, 1e-12, 1e6)
                t = b.time
                t0 = time.perf_counter()
                status = harness.do_step(b, t, h)
                wall = time.perf_counter() - t0
                if status <= 1:
                    b.time = t + h
                name = NAMES.get(status, str(status))
                count[name] = count.get(name, 0) + 1
                if wall > worst["wall"]:
                    worst = {"wall": wall, "status": name, "t": t, "h": h,
                             "params": params, "inputs": ins}  # fmt: skip
            b.free_state(start)
    worst["count"] = count
    return worst


def _g(x: float) -> str:
    return f"{x:.4g}"


def table(rows: list[tuple[str, str, dict]], args: argparse.Namespace) -> str:
    lines = [
        f"Made by `python benchmarks/bench_hunt_step.py --instances {args.instances} "
        f"--calls {args.calls} --seed {args.seed} --write` on {datetime.date.today()} "
        f"({harness.machine()}), max_work at its default 10,000.",
        "",
        "| FMU | target | calls (OK/Warning/Discard) | slowest doStep (s) | its status | its t, h "
        "(s) | its parameters and inputs |",
        "|---|---|---|---|---|---|---|",
    ]
    for label, target, w in rows:
        c = w["count"]
        calls = sum(c.values())
        split = "/".join(str(c.get(k, 0)) for k in ("OK", "Warning", "Discard"))
        values = {**w["params"], **w["inputs"]}
        text = ", ".join(f"{k} = {_g(v)}" for k, v in values.items())
        lines.append(
            f"| {label} | {target} | {calls} ({split}) | {w['wall']:.3g} | {w['status']} | "
            f"{_g(w['t'])}, {_g(w['h'])} | {text} |"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    ap = harness.parser(__doc__, str(DOC.relative_to(ROOT)))
    ap.add_argument("--instances", type=int, default=6)
    ap.add_argument("--calls", type=int, default=30)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args(argv)
    rows = []
    for label, target, path in kinds():
        rng = np.random.default_rng([args.seed, zlib.crc32(label.encode())])
        w = hunt(path, args.instances, args.calls, rng)
        rows.append((label, target, w))
        print(f"{label} ({target}): slowest {w['wall']:.3g} s, {w['status']}, "
              f"{w['count']}", flush=True)  # fmt: skip
    text = table(rows, args)
    harness.publish(text, args.write, DOC, BLOCK)


if __name__ == "__main__":
    main()
