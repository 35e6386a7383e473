"""The Dask engine (contact_fmu.study) against serial runs in one process.

    .venv/bin/python benchmarks/bench_study.py [--workers 2] [--repeats 3] [--write]

Three measurements, each serial and on a LocalCluster of ``--workers`` worker processes
in the same run (the cluster started once, before; its start-up is reported apart):

- the 64-run sweep of scenarios/studies/fig13_peak.toml (Fig. 13's scene, 8 x 8 values),
  with the engine's default batches (about four tasks per worker) and with one task per
  run;
- a creep-force table build (wheel on rail, 12 x 12 solver grid, 13 x 13 x 9 nodes:
  TABLE_NODES), its independent solves as tasks;
- the engine's cost per task: a task that does nothing, one task per item (throughput
  over TRIVIAL tasks on all workers, and the round trip of a single task), against the
  run time of one sweep task (one fig13 run) and one table task (a line of nodes).

Each timing is the fastest of ``--repeats`` (the sweeps: SWEEP_REPEATS times as many;
the machine is shared; the minimum filters the other processes out), serial and Dask
repeats interleaved so that both see the same machine. BLAS is single-threaded in this
process as in the workers (threaded BLAS slows the solver's small GMRES operations down,
docs/performance.md). The Dask runs are checked to give the serial rows and table.
``--write`` replaces the block BLOCK of docs/performance.md.
"""

from __future__ import annotations

import os

for _v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"  # before numpy is imported: as in the Dask workers

import datetime  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from contact_fmu.halfspace.railway import wheel_on_rail  # noqa: E402
from contact_fmu.halfspace.table import build_table  # noqa: E402
from contact_fmu.scenario import load  # noqa: E402
from contact_fmu.study import sweep  # noqa: E402
from contact_fmu.study.engine import Engine  # noqa: E402

if __package__:  # python -m benchmarks
    from . import harness
else:  # run as a script: benchmarks/ is first on sys.path
    import harness  # type: ignore[no-redef]

ROOT, OUT = harness.ROOT, harness.OUT
DOC = harness.PERFORMANCE
BLOCK = "bench_study.py"  # the marker block it writes
STUDY = ROOT / "scenarios" / "studies" / "fig13_peak.toml"
TABLE_GRID = 12
TABLE_NODES = (13, 13, 9)
TRIVIAL = 200
# The sweeps take seconds: repeated this many times more than the table builds (their
# best is the noisier on a shared machine).
SWEEP_REPEATS = 3


def _noop(shared, item):
    return item


def _best(fn, repeats: int) -> tuple[float, object]:
    best, out = np.inf, None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main(argv: list[str] | None = None) -> int:
    ap = harness.parser(__doc__, "docs/performance.md")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)

    scene = load(STUDY)
    vary = scene.sweep.vary
    contact = wheel_on_rail(n=TABLE_GRID)
    serial = Engine(workers=0, progress=False)
    load_before = os.getloadavg()[0]
    t0 = time.perf_counter()
    dask = Engine(workers=args.workers, progress=False).__enter__()
    startup = time.perf_counter() - t0
    try:
        # warm-up: the workers import the package and extract the FMU once
        sweep.sweep(scene, vary, dask, OUT)
        sweep.sweep(scene, vary, serial, OUT)
        times: dict[str, float] = {}
        for _ in range(SWEEP_REPEATS * args.repeats):  # interleaved: the same machine
            for label, eng, batch in (("serial", serial, None), ("dask", dask, None),
                                      ("dask1", dask, 1)):  # fmt: skip
                t, rows = _best(lambda e=eng, b=batch: _sweep(scene, vary, e, b), 1)
                times[f"sweep_{label}"] = min(times.get(f"sweep_{label}", np.inf), t)
                if label == "serial":
                    ref_rows = rows
                else:
                    np.testing.assert_equal(rows, ref_rows)
        n_runs = len(ref_rows)
        tables = {}
        for _ in range(args.repeats):
            for label, mapper in (("serial", None), ("dask", dask.mapper("table"))):
                t0 = time.perf_counter()
                tab = build_table(contact, nodes=TABLE_NODES, map_tasks=mapper)
                t = time.perf_counter() - t0
                times[f"table_{label}"] = min(times.get(f"table_{label}", np.inf), t)
                tables[label] = tab
        assert np.array_equal(tables["serial"].data.values, tables["dask"].data.values)
        n_solves = tables["serial"].data.values[..., 0].size // 2 + 1
        n_lines = len({(k2, k3) for k2 in range(TABLE_NODES[1]) for k3 in range(TABLE_NODES[2])})
        items = list(range(TRIVIAL))
        times["trivial"], _ = _best(lambda: dask.map(_noop, items, batch=1), args.repeats)
        times["single"], _ = _best(lambda: dask.map(_noop, [0], batch=1), 5 * args.repeats)
    finally:
        dask.__exit__(None, None, None)
        serial.__exit__(None, None, None)

    load_after = os.getloadavg()[0]
    run_time = times["sweep_serial"] / n_runs
    line_time = times["table_serial"] / (n_lines + 1)
    per_task = times["trivial"] / TRIVIAL
    rows = [
        ("64-run sweep, fig13_peak (default batches)", times["sweep_serial"],
         times["sweep_dask"]),
        ("64-run sweep, fig13_peak (one task per run)", times["sweep_serial"],
         times["sweep_dask1"]),
        (f"creep-force table {'x'.join(map(str, TABLE_NODES))}, {TABLE_GRID}x{TABLE_GRID} grid "
         f"({n_solves} solves, {n_lines + 1} tasks)", times["table_serial"], times["table_dask"]),
    ]  # fmt: skip
    lines = [
        f"| work | serial (s) | {args.workers} workers (s) | speed-up |",
        "|---|---|---|---|",
    ]
    for name, s, d in rows:
        lines.append(f"| {name} | {s:.2f} | {d:.2f} | {s / d:.2f} |")
    table = "\n".join(lines)
    overhead = "\n".join(
        [
            "| per task | seconds | against one fig13 run | against one table line |",
            "|---|---|---|---|",
            f"| engine, throughput ({TRIVIAL} empty tasks on {args.workers} workers) | "
            f"{per_task:.2e} | {per_task / run_time:.3f} | {per_task / line_time:.4f} |",
            f"| engine, round trip of one empty task | {times['single']:.2e} | "
            f"{times['single'] / run_time:.3f} | {times['single'] / line_time:.4f} |",
            f"| one fig13 run (serial sweep / {n_runs}) | {run_time:.2e} | 1 | |",
            f"| one table line ({TABLE_NODES[0] // 2 + 1} solves; serial build / "
            f"{n_lines + 1} tasks) | {line_time:.2e} | | 1 |",
        ]
    )
    print(table)
    print()
    print(overhead)
    print(f"\nLocalCluster start-up: {startup:.1f} s; load average {load_before:.1f} before, "
          f"{load_after:.1f} after")  # fmt: skip
    if args.write:
        when = datetime.date.today().isoformat()
        body = "\n\n".join(
            [
                f"Measured by `benchmarks/bench_study.py --workers {args.workers} --repeats "
                f"{args.repeats} --write` ({when}, {harness.machine()}; 1-minute load "
                f"average {load_before:.1f} before and {load_after:.1f} after: the numbers "
                "vary with the load, each is the fastest of the repeats (sweeps "
                f"{SWEEP_REPEATS * args.repeats}, tables {args.repeats}), serial and Dask "
                "interleaved). Serial: every task in this process, in order; Dask: a "
                "LocalCluster of worker processes (one thread each, BLAS single-threaded "
                "in both), started once before the timings (its start-up, "
                f"{startup:.1f} s, and the workers' first extraction of the FMU are not "
                "counted). The Dask runs give the serial rows and table exactly (checked).",
                table,
                "Cost of the engine per task (a task that returns its argument, one per "
                "item) against the run time of one task of each kind; the round trip of a "
                "map of one item includes the two tasks that hold the function and the "
                "shared value for the workers:",
                overhead,
                "A sweep's default batches hold about a quarter of each worker's runs per "
                "task (8 tasks of 8 fig13 runs here), so the engine's cost per task is paid "
                "8 times, not 64; the table build's tasks (a line of nodes, a load's onset "
                "of full slip) are one each. With more runnable processes than cores (the "
                "load above), two worker processes get less than two cores: the speed-ups "
                "here depend on that load, and an idle machine is the place to rerun it.",
            ]
        )
        harness.write_block(DOC, BLOCK, body)
    return 0


def _sweep(scene, vary, eng, batch):
    return sweep.sweep(scene, vary, eng, OUT, batch=batch)


if __name__ == "__main__":
    raise SystemExit(main())
