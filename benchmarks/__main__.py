"""Run the benchmarks: ``python -m benchmarks [NAME ...] [--write] [--quick] [--list]``
(``make bench``, with BENCH="NAME ... --write" for the arguments).

NAME: one of BENCHMARKS below (default: all of them; with --write, all that write a
block). Each runs in this process through its module's ``main(argv)``, one after the
other, with the arguments its docs block was made with; BLAS single-threaded (set here
before numpy is imported, as the half-space and study benchmarks set it on their own).

--write   replace each benchmark's marker blocks in docs/ (harness.write_block) with
          this run's numbers. Run it on a quiet machine: the blocks say which machine,
          load and command made them.
--quick   small sizes: a smoke test that every benchmark still runs (its numbers mean
          nothing, and --write is refused with it). tests/test_benchmarks.py runs the
          cheap ones.
--list    the benchmarks (name, whether --quick takes seconds, the blocks each writes,
          what each measures; tab-separated).

A failing benchmark is reported and the next one runs; the exit status is 1 if any
failed.
"""

from __future__ import annotations

import os

for _v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")  # before numpy is imported

import argparse  # noqa: E402
import contextlib  # noqa: E402
import importlib  # noqa: E402
import io  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import traceback  # noqa: E402
from collections.abc import Callable  # noqa: E402
from dataclasses import dataclass  # noqa: E402

from . import harness  # noqa: E402


@dataclass(frozen=True)
class Benchmark:
    """One entry of the runner: the module benchmarks.<module> and its ``main(argv)``."""

    name: str
    module: str
    about: str
    args: tuple[str, ...] = ()  # the arguments of a full run (those its blocks were made with)
    quick: tuple[str, ...] = ()  # instead with --quick: small sizes
    blocks: tuple[str, ...] = ()  # the marker blocks in docs/ that --write replaces
    cheap: bool = False  # its --quick takes seconds: tests/test_benchmarks.py runs it
    # a runner of its own in place of main(argv + ["--write"]): (argv, write) -> status
    call: Callable[[Benchmark, list[str], bool], int] | None = None

    def run(self, quick: bool, write: bool) -> int:
        argv = list(self.quick if quick else self.args)
        if self.call is not None:
            return self.call(self, argv, write)
        main = importlib.import_module(f"benchmarks.{self.module}").main
        return main(argv + (["--write"] if write and self.blocks else [])) or 0


def _small(bench: Benchmark, argv: list[str], write: bool) -> int:
    """bench_halfspace_small prints its table: the block is the table (and the creep
    curve's line) of what it printed, under the command's line."""
    from . import bench_halfspace_small

    out = io.StringIO()

    class Tee(io.TextIOBase):
        def write(self, s: str) -> int:
            out.write(s)
            return sys.__stdout__.write(s)

    with contextlib.redirect_stdout(Tee()):
        status = bench_halfspace_small.main(argv) or 0
    if write and status == 0:
        printed = out.getvalue().splitlines()
        table = [line for line in printed if line.startswith("|")]
        curve = [line.lstrip("# ") for line in printed if line.startswith("# 20-point")]
        cmd = f"python -m benchmarks {bench.name} --write"
        script = " ".join(["benchmarks/bench_halfspace_small.py", *argv])
        body = [harness.made_by(cmd, f"`{script}` printing the table"), "", *table]
        if curve:
            body += ["", "Creep curves of the same run (CPU time): " + "; ".join(curve) + "."]
        harness.write_block(harness.PERFORMANCE, bench.blocks[0], "\n".join(body))
    return status


def _report(bench: Benchmark, argv: list[str], write: bool) -> int:
    """``contact-fmu report``: the work-precision and stiff sections of
    docs/performance.md (and docs/accuracy.md), which the report writes with
    --write-docs (whole sections, by their headings, not marker blocks)."""
    from contact_fmu import cli

    return cli.main(["report", *argv, *(["--write-docs"] if write else [])])


BENCHMARKS = [
    Benchmark(
        "fmu_step", "bench_fmu_step", "pythonfmu FMU step cost per scene, full FMUs, models",
        quick=("--steps", "3", "--repeats", "1"), blocks=("bench_fmu_step.py",),
    ),
    Benchmark(
        "halfspace_fmu", "bench_halfspace_fmu",
        "the rail table's error; half-space FMUs against thin-layer twins",
        quick=("--points", "5", "--steps", "5", "--repeats", "1"),
        blocks=("bench_halfspace_fmu.py", "bench_halfspace_fmu.py step"),
    ),
    Benchmark(
        "halfspace", "bench_halfspace", "steady-rolling half-space solver, 16 .. 128 per side",
        args=("--repeat", "5"), quick=("--grids", "16", "--repeat", "1"),
        blocks=("bench_halfspace.py", "bench_halfspace.py iterations"), cheap=True,
    ),
    Benchmark(
        "halfspace_small", "bench_halfspace_small",
        "small grids, first and repeat solves, against a previous revision and CONTACT",
        args=("--repeat", "7", "--baseline", "091ab49", "--curve", "32", "--crossover", "21",
              "23", "25"),
        quick=("--grids", "11", "--repeat", "1", "--curve", "0"),
        blocks=("bench_halfspace_small.py",), cheap=True, call=_small,
    ),
    Benchmark(
        "halfspace_fastsim", "bench_halfspace_fastsim",
        "FASTSIM against the exact solver: accuracy and cost",
        quick=("--grid", "16", "--points", "2", "--repeat", "1"),
        blocks=("bench_halfspace_fastsim.py",), cheap=True,
    ),
    Benchmark(
        "halfspace_transient", "bench_halfspace_transient",
        "transient half-space field and body: cost per step, durations",
        args=("--skip-coupled",), quick=("--grids", "8", "--skip-coupled"),
        blocks=("bench_halfspace_transient.py",),
    ),
    Benchmark(
        "report", "",
        "contact-fmu report: work-precision, stiff cases (whole sections; also docs/accuracy.md)",
        quick=("--quick",), call=_report,
        # whole sections by heading (contact_fmu/report/command.py), not marker blocks
    ),
    Benchmark(
        "cosim", "bench_cosim", "step cost against a trivial FMU, law evaluations, fmpy",
        quick=("--steps", "3", "--repeats", "1", "--scenes", "fig13"),
        blocks=("bench_cosim.py",),
    ),
    Benchmark(
        "transient_field", "bench_transient_field", "the thin-layer field's compiled stage",
        quick=("--steps", "3", "--repeats", "1", "--stages", "20"),
        blocks=("bench_transient_field.py",), cheap=True,
    ),
    Benchmark(
        "native", "bench_native", "native FMU step cost, C importer rate, size; full body",
        quick=("--steps", "5", "--repeats", "1", "--importer-steps", "1000"),
        blocks=("bench_native.py", "bench_native.py full-body"),
    ),
    Benchmark(
        "native_core", "bench_native",
        "pythonfmu FMU on its C core against its Python path (and native): fig13, full body",
        args=("--core",), quick=("--core", "--steps", "3", "--repeats", "1"),
        blocks=("bench_native.py core",),
    ),
    Benchmark(
        "native_spin", "bench_native", "contact FMU with spin, native and pythonfmu",
        args=("--spin",), quick=("--spin", "--steps", "3", "--repeats", "1"),
        blocks=("bench_native.py spin",),
    ),
    Benchmark(
        "native_transient", "bench_native",
        "fig12_transient: pythonfmu (compiled, Python) and native FMI 2.0 / 3.0 FMUs",
        args=("--transient", "--steps", "350", "--repeats", "5", "--importer-steps", "350",
              "--callgrind"),
        quick=("--transient", "--steps", "3", "--repeats", "1", "--importer-steps", "20"),
        blocks=("bench_native.py transient",), cheap=True,
    ),
    Benchmark(
        "front_ends", "bench_front_ends",
        "FMI 2.0 and 3.0 front ends of the C core against a revision (callgrind)",
        args=("--base", "cc7bca5", "--repeats", "3", "--callgrind"),
        quick=("--steps", "50", "--importer-steps", "500", "--repeats", "1"),
        blocks=("bench_front_ends.py",),
    ),
    Benchmark(
        "study", "bench_study", "parameter studies on Dask against serial",
        quick=("--workers", "1", "--repeats", "1"), blocks=("bench_study.py",),
    ),
    Benchmark(
        "fmu_states", "bench_fmu_states", "native FMU: FMU states held at once",
        quick=("--held", "10", "100"), blocks=("bench_fmu_states.py",), cheap=True,
    ),
    Benchmark(
        "worst_step", "bench_worst_step", "worst-case time of one doStep (docs/reliability.md)",
        args=("--repeat", "1"), quick=("--repeat", "1"), blocks=("bench_worst_step.py",),
    ),
    Benchmark(
        "hunt_step", "bench_hunt_step", "slowest doStep of random hostile calls (reliability)",
        quick=("--instances", "1", "--calls", "2"), blocks=("bench_hunt_step.py",),
    ),
]  # fmt: skip
BY_NAME = {b.name: b for b in BENCHMARKS}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="python -m benchmarks",
        description=__doc__.split("\n")[0],
        epilog="benchmarks: " + ", ".join(BY_NAME),
    )
    ap.add_argument("names", nargs="*", metavar="NAME", help="default: all")
    ap.add_argument("--write", action="store_true", help="replace the blocks in docs/")
    ap.add_argument("--quick", action="store_true", help="small sizes: a smoke test")
    ap.add_argument("--list", action="store_true", help="list the benchmarks and their blocks")
    args = ap.parse_args(argv)
    unknown = [n for n in args.names if n not in BY_NAME]
    if unknown:
        ap.error(f"unknown benchmark {', '.join(map(repr, unknown))}; known: {', '.join(BY_NAME)}")
    if args.write and args.quick:
        ap.error("--quick with --write: a smoke test's numbers do not belong in the docs")
    if args.list:
        for b in BENCHMARKS:  # tab-separated: tests/test_benchmarks.py reads it
            blocks = "; ".join(b.blocks) or "-"
            quick = "quick: seconds" if b.cheap else "quick: minutes"
            print(f"{b.name}\t{quick}\tblocks: {blocks}\t{b.about}")
        return 0
    chosen = [BY_NAME[n] for n in args.names] or [
        b for b in BENCHMARKS if not args.write or b.blocks or b.call is _report
    ]
    print(harness.machine(), flush=True)
    failed, took = [], {}
    for b in chosen:
        print(f"\n=== {b.name} ({b.about})", flush=True)
        t0 = time.perf_counter()
        try:
            status = b.run(args.quick, args.write)
        except SystemExit as e:  # a benchmark's argparse or its own exit
            status = e.code if isinstance(e.code, int) else int(e.code is not None)
        except Exception:
            traceback.print_exc()
            status = 1
        took[b.name] = time.perf_counter() - t0
        if status:
            failed.append(b.name)
            print(f"=== {b.name} failed (status {status})", file=sys.stderr, flush=True)
    print("\n" + "; ".join(f"{k} {v:.1f} s" for k, v in took.items()))
    if failed:
        print(f"failed: {', '.join(failed)}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    # as contact_fmu.cli.entry: no interpreter finalisation after the run (pythonfmu's
    # wrapper can corrupt the heap when its libraries are torn down at exit)
    try:
        status = main()
    except SystemExit as e:
        status = e.code if isinstance(e.code, int) else (print(e.code, file=sys.stderr) or 2)
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(status)
