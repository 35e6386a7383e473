"""What the benchmarks share: clocks, best-of and interleaved timing, the machine line of
a generated block, and the writer of the blocks between marker comments in docs/.

A generated block of a docs page sits between two marker lines named after the
benchmark that writes it (the file name, and a label where one script writes several)::

    <!-- bench_fmu_step.py: table -->
    Made by `...` on DATE (machine) ...
    | ... |
    <!-- bench_fmu_step.py: end -->

``write_block`` replaces what lies between them and nothing else: the prose around a
block is the page's own. ``python -m benchmarks --write`` runs every benchmark that
writes one (benchmarks/__main__.py lists them).
"""

from __future__ import annotations

import argparse
import datetime
import math
import os
import platform
import re
import statistics
import subprocess
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from contact_fmu.scenario.instance import Instance3

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "fmu"  # where the benchmarks build their FMUs
DOCS = ROOT / "docs"
PERFORMANCE = DOCS / "performance.md"
RELIABILITY = DOCS / "reliability.md"

BEGIN = "<!-- {}: table -->"
END = "<!-- {}: end -->"
# a marker line of either kind; group 1: the block's name, group 2: table or end
MARKER = re.compile(r"^<!-- (.+): (table|end) -->$")


# --- clocks ---------------------------------------------------------------------------


def cpu_time(f: Callable[[], Any]) -> tuple[float, Any]:
    """CPU seconds of this process spent in ``f()`` (time.process_time: on a shared
    machine the wall clock also carries other processes' time), and its result."""
    t = time.process_time()
    out = f()
    return time.process_time() - t, out


def wall_time(f: Callable[[], Any]) -> tuple[float, Any]:
    """Wall-clock seconds of ``f()`` (time.perf_counter), and its result."""
    t = time.perf_counter()
    out = f()
    return time.perf_counter() - t, out


@dataclass
class Timed:
    """Seconds of each call of one candidate, and the result of its last call."""

    times: list[float] = field(default_factory=list)
    result: Any = None

    @property
    def best(self) -> float:
        return min(self.times)

    @property
    def median(self) -> float:
        return statistics.median(self.times)


def repeated(f: Callable[[], Any], repeats: int, clock=wall_time) -> Timed:
    """``f`` called ``repeats`` times (at least once), each call timed by ``clock``."""
    out = Timed()
    for _ in range(max(1, repeats)):
        t, out.result = clock(f)
        out.times.append(t)
    return out


def best_of(f: Callable[[], Any], repeats: int, clock=wall_time) -> tuple[float, Any]:
    """The fastest of ``repeats`` calls of ``f`` by ``clock``, and the last result."""
    t = repeated(f, repeats, clock)
    return t.best, t.result


def interleaved(
    candidates: dict[str, Callable[[], Any]], repeats: int, clock=wall_time
) -> dict[str, Timed]:
    """Each candidate timed ``repeats`` times, round-robin (A B C A B C ...), so that a
    change of the machine's load falls on all of them alike: the baseline of a
    comparison runs in the same run as what it is compared with."""
    out = {k: Timed() for k in candidates}
    for _ in range(max(1, repeats)):
        for k, f in candidates.items():
            t, out[k].result = clock(f)
            out[k].times.append(t)
    return out


# --- the machine ----------------------------------------------------------------------


def cpu_model() -> str:
    """The CPU's model name from /proc/cpuinfo (platform.machine() where there is none)."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def blas() -> str:
    """numpy's BLAS library and version, as numpy was built with it."""
    import numpy as np

    try:
        dep = np.show_config(mode="dicts")["Build Dependencies"]["blas"]
        return f"{dep['name']} {dep['version']}"
    except Exception:  # older numpy without mode="dicts": say so rather than guess
        return "BLAS unknown"


def machine() -> str:
    """One line for a generated block: CPU model, cores, Python, numpy and its BLAS, the
    BLAS threads, the 1-minute load average when the line is made."""
    import numpy as np

    threads = os.environ.get("OPENBLAS_NUM_THREADS", "default")
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    return (
        f"{cpu_model()} ({platform.machine()}), {os.cpu_count()} cores, load {load:.1f}; "
        f"Python {platform.python_version()}, numpy {np.__version__} with {blas()} "
        f"(BLAS threads: {threads})"
    )


def made_by(command: str, how: str = "") -> str:
    """The first sentence of a generated block: the command (and ``how`` it made the
    block, in parentheses), the date, the machine."""
    how = f" ({how})" if how else ""
    return f"Made by `{command}`{how} on {datetime.date.today()} ({machine()})."


# --- marker blocks --------------------------------------------------------------------


def block_spans(text: str) -> dict[str, tuple[int, int]]:
    """The marker blocks of a page: name -> (line of its table marker, line of its end
    marker), counted from 0. A marker without its partner, a block inside another or a
    name used twice is an error."""
    found: dict[str, tuple[int, int]] = {}
    open_name, start = None, 0
    for i, line in enumerate(text.split("\n")):
        m = MARKER.match(line)
        if not m:
            continue
        name, kind = m.groups()
        if kind == "table":
            if open_name is not None:
                raise ValueError(f"marker block {name!r} opens inside {open_name!r}")
            if name in found:
                raise ValueError(f"marker block {name!r} appears twice")
            open_name, start = name, i
        else:
            if name != open_name:
                raise ValueError(f"end marker of {name!r} without its table marker")
            found[name] = (start, i)
            open_name = None
    if open_name is not None:
        raise ValueError(f"marker block {open_name!r} has no end marker")
    return found


def blocks(text: str) -> dict[str, str]:
    """The marker blocks of a page: name -> the text between its two markers
    (``block_spans``' errors)."""
    lines = text.split("\n")
    return {name: "\n".join(lines[a + 1 : b]) for name, (a, b) in block_spans(text).items()}


def replace_block(text: str, name: str, body: str) -> str:
    """``text`` with the block ``name`` replaced by ``body`` (prose paragraphs wrapped to
    88 columns, tables and code kept as they are)."""
    from contact_fmu.report.output import wrap_prose

    present = blocks(text)
    if name not in present:
        raise ValueError(f"no marker block {name!r}: the page lacks {BEGIN.format(name)}")
    begin, end = BEGIN.format(name), END.format(name)
    head, rest = text.split(begin + "\n", 1)
    _, tail = rest.split(end, 1)
    return head + begin + "\n" + wrap_prose(body.strip("\n")) + "\n" + end + tail


def parser(doc: str, pages: str = "docs/") -> argparse.ArgumentParser:
    """A benchmark's argument parser: its module docstring as the help's description and
    ``--write`` (replace its marker blocks in ``pages``)."""
    ap = argparse.ArgumentParser(
        description=doc, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--write", action="store_true", help=f"replace its tables in {pages}")
    return ap


def publish(text: str, write: bool, doc: Path, name: str) -> None:
    """Print a benchmark's table; with ``write`` (its --write) also make it the block
    ``name`` of the page ``doc``."""
    print(text)
    if write:
        write_block(doc, name, text)


def write_block(doc: Path, name: str, body: str) -> None:
    """Replace the block ``name`` of the page ``doc`` by ``body`` (see replace_block)."""
    doc.write_text(replace_block(doc.read_text(), name, body))
    print(f"wrote the block {name!r} of {doc}")


# --- the C importer -------------------------------------------------------------------

# the C importers of the tests, which drive a native FMU without Python; their input is
# fmu_build.c_importer.spec's
IMPORTER2 = ROOT / "tests" / "native_importer.c"
IMPORTER3 = ROOT / "tests" / "native_importer3.c"


class ImporterError(RuntimeError):
    """The C importer did not finish its run: no rate to report."""


def compile_importer(work: Path, fmi3: bool = False) -> Path:
    """tests/native_importer.c (native_importer3.c: ``fmi3``) compiled with -O2 into
    ``work`` (it dlopens the FMU's binary)."""
    from fmu_build import c_importer

    exe = work / ("importer3" if fmi3 else "importer")
    source = IMPORTER3 if fmi3 else IMPORTER2
    return c_importer.compile_c(exe, str(source), "-ldl", opt=("-O2",))


def importer_rate(args: list[str]) -> float:
    """Steps per second that the C importer's bench run ``args`` prints; ImporterError
    (with the importer's message: the call, the step, the FMU's last message) if it
    stops or prints no positive rate."""
    proc = subprocess.run(args, capture_output=True, text=True)
    words = proc.stdout.split()
    try:
        rate = float(words[-1]) if proc.returncode == 0 and words else math.nan
    except ValueError:
        rate = math.nan
    if not (math.isfinite(rate) and rate > 0.0):
        raise ImporterError(
            f"the C importer stopped (exit status {proc.returncode}): "
            f"{(proc.stderr.strip() or proc.stdout.strip() or 'no output')[-2000:]}"
        )
    return rate


# --- FMI 3.0 ---------------------------------------------------------------------------


def open_fmu(
    path: str | Path, name: str, start_values: dict[str, Any] | None = None, initialise: bool = True
):
    """An initialised instance of the FMU at ``path`` (FMI 2.0: scenario.Instance, FMI
    3.0: Instance3), its start values set (``initialise``: initialisation ended)."""
    import fmpy

    from contact_fmu.scenario.instance import Instance

    if fmpy.read_model_description(str(path)).fmiVersion.startswith("3"):
        return Instance3(path, name, start_values, initialise=initialise)
    return Instance(path, name, start_values, initialise=initialise)


def do_step(inst: Any, t: float, h: float) -> int:
    """One doStep of an instance of ``open_fmu`` from t by h: the FMI status, Warning
    included (fmpy raises only above it), the instance's time not moved."""
    if isinstance(inst, Instance3):
        return inst.do_step(t, h)
    from fmpy.fmi1 import FMICallException

    try:
        return int(inst.fmu.fmi2DoStep(inst.fmu.component, t, h, 1))
    except FMICallException as e:
        return int(e.status)
