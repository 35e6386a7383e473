"""The wall time of one doStep whose internal steps reach the budget max_work
(fmu/body_model.py: its default, 10,000 work units), per kind of body FMU and target.

    python benchmarks/bench_worst_step.py [--repeat N] [--write]

Each FMU (the pythonfmu FMU, the native one where it exists, and for fig12_transient also
the native FMI 3.0 FMU) is loaded through fmpy (contact_fmu.scenario.instance.Instance;
harness.Instance3 for FMI 3.0), driven with loads that keep its degrees of
freedom moving (a lateral force and yaw moment where it integrates Eqs. 10-11), and one
doStep of h = 10 * MAX_WORK * h_max is timed (the fastest of the repeats); it answers
fmi2Warning (the budget lowered the accuracy), its note saying how many internal steps
it took. The Markdown table goes to stdout; ``--write`` replaces it between the markers
of docs/reliability.md.
"""

from __future__ import annotations

import datetime
import re
import time
from pathlib import Path

import fmu_build
from contact_fmu import examples as ex
from contact_fmu.fmu.body_model import MAX_WORK
from contact_fmu.fmu.config import ModelConfig
from contact_fmu.scenario import load
from fmu_build import native_fmu, native_fmu3

if __package__:  # python -m benchmarks
    from . import harness
else:  # run as a script: benchmarks/ is first on sys.path
    import harness  # type: ignore[no-redef]

ROOT, OUT = harness.ROOT, harness.OUT
DOC = harness.RELIABILITY
BLOCK = "bench_worst_step.py"  # the marker block it writes
MU_P = ex.mu * ex.P


def kinds() -> list[tuple[str, str, Path, dict, dict]]:
    """(label, target, FMU, start values, inputs)."""
    cfgs = {n: load(ROOT / "scenarios" / f"{n}.toml").config
            for n in ("fig13", "cornering", "rail_traction", "fig12_transient")}  # fmt: skip
    cfgs["full"] = ModelConfig.full("body")
    held = {"vy": "ratio", "spin": "ratio", "inputs": ["P", "Fx_ex", "My_ex"],
            "starts": {"vy_ratio": 0.002, "spin_ratio": 1.0}}  # fmt: skip
    cfgs["held"] = ModelConfig.from_dict(cfgs["full"].to_dict() | {"name": "full_body_held_spin"}
                                         | held)  # fmt: skip
    lateral = {"Fx_ex": 0.2 * MU_P, "Fy_ex": 0.3 * MU_P, "Mz_ex": 1e-3}
    cases = [
        ("fig13 (scalar step)", "fig13", {}, {}),
        ("rail_traction (creep-force table)", "rail_traction", {}, {}),
        ("full body, full method, Eqs. 10-11", "full", {"method": "full"}, lateral),
        ("full body, quasistationary, Eqs. 10-11", "full", {"method": "quasistationary"},
         lateral),
        ("cornering (spin law)", "cornering", {}, {}),
        ("full body, spin held at a ratio of Vx", "held", {}, {"Fx_ex": 0.2 * MU_P}),
        ("fig12_transient (field 32 x 16)", "fig12_transient", {}, {}),
    ]  # fmt: skip
    out = []
    for label, name, starts, inputs in cases:
        cfg = cfgs[name]
        out.append((label, "pythonfmu", fmu_build.build(cfg, OUT).path, starts, inputs))
        if native_fmu.unsupported(cfg) is None:
            out.append((label, "native", native_fmu.build(cfg, OUT).path, starts, inputs))
        if name == "fig12_transient":  # the FMI 3.0 front end on the same core
            path = native_fmu3.build(cfg, OUT).path
            out.append((label, "native FMI 3.0", path, starts, inputs))
    return out


def worst(path: Path, starts: dict, inputs: dict, repeat: int) -> tuple[float, float, int, str]:
    """(fastest wall time s, h s, status, internal steps taken) of one doStep from the
    start beyond the budget."""
    best, status, h, steps = float("inf"), -1, 0.0, "?"
    for _ in range(repeat):
        with harness.open_fmu(path, "worst", starts) as b:
            for n, v in inputs.items():
                b.set(n, v)
            h = 10.0 * MAX_WORK * b.get("h_max")
            t0 = time.perf_counter()
            status = harness.do_step(b, 0.0, h)
            best = min(best, time.perf_counter() - t0)
            note = re.search(r"taken in (\d+) steps", b.messages[-1][1] if b.messages else "")
            steps = note.group(1) if note else "-"
    return best, h, status, steps


def main(argv: list[str] | None = None) -> None:
    ap = harness.parser(__doc__, str(DOC.relative_to(ROOT)))
    ap.add_argument("--repeat", type=int, default=2)
    args = ap.parse_args(argv)
    lines = [
        f"Made by `python benchmarks/bench_worst_step.py --repeat {args.repeat} --write` on "
        f"{datetime.date.today()} ({harness.machine()}), max_work = {MAX_WORK}.",
        "",
        "| FMU | target | h (s) | status | internal steps taken | wall of one doStep (s) |",
        "|---|---|---|---|---|---|",
    ]
    print("\n".join(lines), flush=True)
    for label, target, path, starts, inputs in kinds():
        wall, h, status, steps = worst(path, starts, inputs, args.repeat)
        name = {0: "OK", 1: "Warning", 2: "Discard", 3: "Error"}.get(status, str(status))
        lines.append(f"| {label} | {target} | {h:g} | {name} | {steps} | {wall:.3g} |")
        print(lines[-1], flush=True)
    if args.write:
        harness.write_block(DOC, BLOCK, "\n".join(lines))


if __name__ == "__main__":
    main()
