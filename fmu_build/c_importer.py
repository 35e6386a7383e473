"""The C importers that drive a native FMU without Python (tests/native_importer.c for
FMI 2.0, tests/native_importer3.c for FMI 3.0): their input file and their compilation
against the FMI headers. The tests (tests/native_c.py) and the benchmarks that time a
native FMU from C (benchmarks/bench_native.py and the benchmarks built on it) share it.

The input is one format for both importers: inputs, outputs, parameters, then for the
modes that step one row per communication step. Not part of an FMU: the build key of a
pythonfmu FMU leaves this module out.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

from contact_fmu.scenario import runner
from fmu_build import native_fmu


def spec(md, scene, case, rows: bool = True) -> str:
    """The importers' input: the value references of the scene's inputs and Real
    outputs, the case's parameters (hexadecimal floats: exact), and, with ``rows``, the
    case's inputs per communication step (t, h, inputs)."""
    vr = {v.name: v.valueReference for v in md.modelVariables}
    reals = [o for o in scene.outputs if o != "regime"]
    params = runner.start_values(scene, case)
    lines = [
        f"{len(scene.inputs)} " + " ".join(str(vr[n]) for n in scene.inputs),
        f"{len(reals)} " + " ".join(str(vr[n]) for n in reals),
        f"{len(params)} " + " ".join(f"{vr[k]} {float(v).hex()}" for k, v in params.items()),
    ]
    if rows:
        table = runner.input_table(scene, case)
        for k in range(scene.grid.size - 1):
            u = " ".join(float(table[n][k]).hex() for n in scene.inputs)
            lines.append(f"{float(scene.grid[k]).hex()} {scene.step.hex()} {u}")
    return "\n".join(lines) + "\n"


def compile_c(out: Path, *args: str, opt: tuple[str, ...] = ("-O1", "-g")) -> Path:
    """cc ``opt`` with the FMI headers (2.0 and 3.0) on the include path, ``args``, -lm;
    the executable ``out``. The tests build with -O1 -g (and the sanitizers), the
    benchmarks with -O2."""
    cmd = ["cc", *opt, f"-I{native_fmu.fmi_headers()}", "-o", str(out), *args, "-lm"]
    subprocess.run(cmd, check=True, capture_output=True, text=True)
    return out
