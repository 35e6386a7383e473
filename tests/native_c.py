"""What the native FMU tests share: the C importers' input format, their compilation
(plain, with the sanitizers) and runs under valgrind's memcheck.

The importers (native_importer.c for FMI 2.0, native_importer3.c for FMI 3.0) read one
format: inputs, outputs, parameters, then for "run" one row per step.
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

from contact_fmu.scenario import runner
from fmu_build import native_fmu

HERE = Path(__file__).parent
IMPORTER2 = HERE / "native_importer.c"
IMPORTER3 = HERE / "native_importer3.c"
# AddressSanitizer and UBSan (float-to-int overflow included), no recovery: the first
# report ends the program with a non-zero status
SANITIZE = (
    "-fsanitize=address,undefined,float-cast-overflow",
    "-fno-sanitize-recover=all",
    "-fno-omit-frame-pointer",
    "-ffp-contract=off",
)
# memcheck: any invalid read or write, use of an undefined value or definite leak is an
# error; the exit status 99 says so
MEMCHECK = (
    "valgrind", "--error-exitcode=99", "--leak-check=full",
    "--errors-for-leak-kinds=definite", "--show-leak-kinds=definite", "-q",
)  # fmt: skip
HAS_VALGRIND = shutil.which("valgrind") is not None


def spec(md, scene, case, rows: bool = True) -> str:
    """The importers' input: the case's inputs per step (``rows``), its parameters."""
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


def compile_c(out: Path, *args: str) -> Path:
    """cc -O1 -g with the FMI headers (2.0 and 3.0) on the include path, -lm."""
    cmd = ["cc", "-O1", "-g", f"-I{native_fmu.fmi_headers()}", "-o", str(out), *args, "-lm"]
    subprocess.run(cmd, check=True, capture_output=True, text=True)
    return out


def sanitized(out: Path, importer: Path, unzip: Path) -> Path:
    """The importer and the extracted FMU's sources in one program under the
    sanitizers (-DLINKED: the importer calls the FMI functions directly)."""
    units = sorted(str(p) for p in (unzip / "sources").glob("*.c"))
    flags = (*SANITIZE, "-DLINKED", f"-I{unzip / 'sources'}")
    return compile_c(out, *flags, str(importer), *units)


def memcheck(*args: str, timeout: float = 600) -> str:
    """``args`` run under valgrind's memcheck; its stdout. Fails on any error it
    reports (exit status 99) or on the program's own failure."""
    proc = subprocess.run([*MEMCHECK, *args], capture_output=True, text=True, timeout=timeout)
    assert proc.returncode == 0, (proc.returncode, proc.stderr[-3000:])
    return proc.stdout
