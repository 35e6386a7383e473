"""What the native FMU tests share: the C importers' input format and their compilation
(fmu_build.c_importer, which the benchmarks use too), the importers built with the
sanitizers, runs under valgrind's memcheck.

The importers (native_importer.c for FMI 2.0, native_importer3.c for FMI 3.0) read one
format: inputs, outputs, parameters, then for "run" one row per step.
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

from fmu_build.c_importer import compile_c, spec  # noqa: F401 (the tests take spec here)

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
