"""The worst-case wall time of one doStep: a communication step long enough that the
internal steps reach their cap (fmu/body_model.MAX_SUBSTEPS), per kind of body FMU.

    python benchmarks/bench_worst_step.py [--repeat N]

Each FMU is loaded through fmpy (contact_fmu.scenario.instance.Instance), driven with
loads that keep its degrees of freedom moving (a lateral force and yaw moment where it
integrates Eqs. 10-11), and one doStep of h = 10 * MAX_SUBSTEPS * h_max is timed (the
fastest of the repeats); it answers fmi2Warning (the cap lowered the accuracy). The
Markdown table goes to stdout (docs/reliability.md quotes it).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import fmu_build
from contact_fmu import examples as ex
from contact_fmu.fmu.body_model import MAX_SUBSTEPS
from contact_fmu.fmu.config import ModelConfig
from contact_fmu.scenario import load
from contact_fmu.scenario.instance import Instance

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "fmu"
MU_P = ex.mu * ex.P


def kinds() -> list[tuple[str, Path, dict, dict]]:
    """(label, FMU, start values, inputs)."""
    scene = {n: fmu_build.build(load(ROOT / "scenarios" / f"{n}.toml").config, OUT).path
             for n in ("fig13", "cornering", "rail_traction", "fig12_transient")}  # fmt: skip
    full = fmu_build.build(ModelConfig.full("body"), OUT).path
    lateral = {"Fx_ex": 0.2 * MU_P, "Fy_ex": 0.3 * MU_P, "Mz_ex": 1e-3}
    return [
        ("fig13 (compiled scalar step)", scene["fig13"], {}, {}),
        ("rail_traction (creep-force table)", scene["rail_traction"], {}, {}),
        ("full body, full method, Eqs. 10-11", full, {"method": "full"}, lateral),
        ("full body, quasistationary, Eqs. 10-11", full, {"method": "quasistationary"}, lateral),
        ("cornering (spin law)", scene["cornering"], {}, {}),
        ("fig12_transient (field 32 x 16)", scene["fig12_transient"], {}, {}),
    ]


def worst(path: Path, starts: dict, inputs: dict, repeat: int) -> tuple[float, float, int]:
    """(fastest wall time s, h s, status) of one capped doStep from the start."""
    best, status, h = float("inf"), -1, 0.0
    for _ in range(repeat):
        with Instance(path, "worst", starts) as b:
            for n, v in inputs.items():
                b.set(n, v)
            h = 10.0 * MAX_SUBSTEPS * b.get("h_max")
            t0 = time.perf_counter()
            status = b.fmu.fmi2DoStep(b.fmu.component, 0.0, h, 1)
            best = min(best, time.perf_counter() - t0)
    return best, h, status


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=2)
    args = ap.parse_args()
    print(f"| FMU | h (s) | status | wall of one doStep (s), {MAX_SUBSTEPS} internal steps |")
    print("|---|---|---|---|")
    for label, path, starts, inputs in kinds():
        wall, h, status = worst(path, starts, inputs, args.repeat)
        name = {0: "OK", 1: "Warning", 2: "Discard", 3: "Error"}.get(status, str(status))
        print(f"| {label} | {h:g} | {name} | {wall:.3g} |", flush=True)


if __name__ == "__main__":
    main()
