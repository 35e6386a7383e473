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


def fuzz(exe: Path, md, spec_file: Path, seeds: int, calls: int, env=None) -> dict[str, int]:
    """The importer ``exe`` (a sanitized build) making ``calls`` random calls for each of
    ``seeds`` seeds; the counts of each answer it prints. Fails on a sanitizer report or
    the importer's own failure."""
    counts: dict[str, int] = {}
    for seed in range(seeds):
        args = [str(exe), "-", md.guid, "fuzz", "fuzz", str(spec_file), str(seed), str(calls)]
        proc = subprocess.run(args, capture_output=True, text=True, timeout=600, env=env)
        assert proc.returncode == 0, proc.stderr[-3000:]
        assert "runtime error" not in proc.stderr and "Sanitizer" not in proc.stderr
        for k, v in dict(zip(*[iter(proc.stdout.split())] * 2, strict=True)).items():
            counts[k] = counts.get(k, 0) + int(v)
    return counts


def fuzz_spec(unzip: Path, tmp_path: Path):
    """The extracted FMU's model description and the importer's spec: every input, every
    Real output, no parameter."""
    import fmpy

    md = fmpy.read_model_description(str(unzip))
    ins = [v.valueReference for v in md.modelVariables if v.causality == "input"]
    outs = [v.valueReference for v in md.modelVariables
            if v.causality == "output" and v.type == "Real"]  # fmt: skip
    spec_file = tmp_path / "spec.txt"
    spec_file.write_text(f"{len(ins)} {' '.join(map(str, ins))}\n{len(outs)} "
                    f"{' '.join(map(str, outs))}\n0\n")  # fmt: skip
    return md, spec_file


def sanitized_fuzz(fmu: Path, tmp_path: Path, calls: int, resources: bool = False):
    """An FMI 2.0 FMU's sources with the importer under the sanitizers, ``calls`` random
    calls on every input (seed 0); the answers' counts. Skips the test where gcc has no
    sanitizer runtime. ``resources``: FMU_RESOURCES names the extracted resources/."""
    import os

    import fmpy
    import pytest

    unzip = tmp_path / "fmu"
    fmpy.extract(str(fmu), str(unzip))
    md, spec_file = fuzz_spec(unzip, tmp_path)
    try:
        exe = sanitized(tmp_path / "importer_asan", IMPORTER2, unzip)
    except subprocess.CalledProcessError as e:  # pragma: no cover - gcc without libasan
        pytest.skip(f"no sanitizer runtime: {e.stderr[-300:]}")
    env = {**os.environ, "FMU_RESOURCES": (unzip / "resources").as_uri()} if resources else None
    return fuzz(exe, md, spec_file, 1, calls, env)


def memcheck(*args: str, timeout: float = 600) -> str:
    """``args`` run under valgrind's memcheck; its stdout. Fails on any error it
    reports (exit status 99) or on the program's own failure."""
    proc = subprocess.run([*MEMCHECK, *args], capture_output=True, text=True, timeout=timeout)
    assert proc.returncode == 0, (proc.returncode, proc.stderr[-3000:])
    return proc.stdout
