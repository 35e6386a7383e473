"""Benchmark of the steady-rolling half-space solver: FFT against a dense influence matrix.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_halfspace.py [--grids 16 32 64 128]
        [--repeat 3] [--dense-limit-mb 1500] [--json out.json] [--write]
    ... bench_halfspace.py --table N N1 N2 N3 [--points 60]       (``table_report``)

Steady rolling of the railway wheel on rail (contact_fmu.halfspace.railway, Hertz,
steel, nu = 0.28) on n x n elements, two cases: longitudinal creepage in partial slip
(xi = 0.3 mu P/(G c^2), about 90 % of mu P) and combined creepage with spin
(xi = eta = 0.2, phi = 0.3 in the same units). The same solver (semismooth Newton,
GMRES with the FFT preconditioner) runs with the influence sums as FFT convolutions
and as products with an explicit dense influence matrix, in the same process, so the
ratio is a fair measure on a noisy machine. Dense is skipped where its matrix would
exceed --dense-limit-mb. Times are the median of --repeat cold solves (no warm
start; the patch, i.e. kernels, symbols and the FASTSIM calibration of the initial
guess, is built once per grid and timed separately as "setup").

The solver's default is nested iteration (coarse levels of n/2, n/4, ... down to 16
elements per side give the initial guess, docs/halfspace.md); "single-level" is the
same solver started from the calibrated FASTSIM guess on the fine grid
(``replace(patch, coarsen=None)``), and "previous" the solver as it was before nested
iteration (single level, slip rows preconditioned by their diagonal alone, no
oversolving guard), all three timed alternately. Newton and GMRES counts are the fine
grid's; "GMRES all levels" weights each coarse level's iterations by its share of the
elements.

``--write`` replaces the blocks BLOCK (times) and ITERATIONS_BLOCK (Newton and GMRES
counts) of docs/performance.md.

Threaded BLAS is switched off (the environment variables below are set before numpy
is imported): on the shared 2-core machine OpenBLAS threads contend with the other
process and slow GMRES's vector operations down by an order of magnitude.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import json  # noqa: E402
import math  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402
from dataclasses import replace  # noqa: E402

import numpy as np  # noqa: E402

from contact_fmu.halfspace import rolling  # noqa: E402
from contact_fmu.halfspace.railway import wheel_on_rail  # noqa: E402
from contact_fmu.halfspace.rolling import solve_rolling  # noqa: E402

if __package__:  # python -m benchmarks
    from . import harness
else:  # run as a script: benchmarks/ is first on sys.path
    import harness  # type: ignore[no-redef]

DOC = harness.PERFORMANCE
BLOCK = "bench_halfspace.py"  # the marker blocks it writes
ITERATIONS_BLOCK = "bench_halfspace.py iterations"

CASES = {"longitudinal": (0.3, 0.0, 0.0), "combined+spin": (0.2, 0.2, 0.3)}
# CONTACT's published steady-rolling timings, Hertzian cases (its documentation; 2016
# hardware, one thread): elements per side -> seconds
CONTACT_PUBLISHED = {11: 1.9e-3, 19: 9.7e-3, 35: 0.134}


def _previous(patch, *args):
    """The solver as it was before nested iteration (2026-11-22): on a single-level patch,
    the slip rows preconditioned by their diagonal alone and no oversolving guard."""
    saved = rolling.OVERSOLVE, rolling.SLIP_BLOCK_RATIO
    rolling.OVERSOLVE, rolling.SLIP_BLOCK_RATIO = 0.0, 0.0
    try:
        return solve_rolling(patch, *args, method="iterative")
    finally:
        rolling.OVERSOLVE, rolling.SLIP_BLOCK_RATIO = saved


def _levels(patch) -> list:
    """The patch and its coarse levels, finest first."""
    out = [patch]
    while out[-1].coarse is not None:
        out.append(out[-1].coarse)
    return out


def run(grids: list[int], repeat: int, dense_limit_mb: float) -> dict:
    results = {"grids": grids, "cases": {}, "setup": {}, "machine": platform.platform()}
    for n in grids:
        contact = wheel_on_rail(n=n)
        xref = contact.mu * contact.P / (contact.elastic.G * contact.c**2)
        t0 = time.perf_counter()
        patch = contact.patch
        levels = _levels(patch)
        for lev in levels:
            _ = lev.op.symbols, lev.op.inverse_symbols, lev.op.inverse_offsets
        _ = levels[-1].flexibilities
        setup = time.perf_counter() - t0
        # the single-level solver (FASTSIM guess on the fine grid, no coarse levels)
        single = replace(patch, coarsen=None)
        t0 = time.perf_counter()
        _ = single.op.symbols, single.op.inverse_symbols, single.op.inverse_offsets
        _ = single.flexibilities
        single_setup = time.perf_counter() - t0
        m = int(patch.contact.sum())
        dense_mb = 8.0 * (2 * m) * (2 * (m + patch.grid.ny)) / 1e6
        dense_patch = None
        dense_setup = math.nan
        if dense_mb <= dense_limit_mb:
            dense_patch = replace(patch, backend="dense")
            t0 = time.perf_counter()
            for lev in _levels(dense_patch):
                _ = lev._dense
            coarsest = _levels(dense_patch)[-1]
            coarsest.__dict__["flexibilities"] = levels[-1].flexibilities  # same guess
            dense_setup = time.perf_counter() - t0
        results["setup"][n] = {
            "elements_in_contact": m,
            "fft_setup_s": setup,
            "single_setup_s": single_setup,
            "dense_matrix_MB": dense_mb,
            "dense_setup_s": dense_setup,
        }
        for name, w in CASES.items():
            args = (w[0] * xref, w[1] * xref, w[2] * xref / contact.c)
            timed = harness.interleaved(  # median of each, the same machine load for each
                {
                    "fft": lambda a=args, p=patch: solve_rolling(p, *a, method="iterative"),
                    "single": lambda a=args, p=single: solve_rolling(p, *a, method="iterative"),
                    "previous": lambda a=args, p=single: _previous(p, *a),
                },
                repeat,
            )
            (t_fft, sol), (t_single, s1), (t_prev, s0) = (
                (timed[k].median, timed[k].result) for k in ("fft", "single", "previous")
            )
            g = float(patch.g.max())
            entry = {
                "fft_s": t_fft,
                "newton": sol.newton_iterations,
                "gmres": sol.gmres_iterations,
                "levels": [list(lv) for lv in sol.levels],
                "gmres_work": sol.gmres_work,
                "single_s": t_single,
                "single_newton": s1.newton_iterations,
                "single_gmres": s1.gmres_iterations,
                "max_dtau_single_over_g": float(np.abs(s1.tau - sol.tau).max() / g),
                "previous_s": t_prev,
                "previous_newton": s0.newton_iterations,
                "previous_gmres": s0.gmres_iterations,
                "max_dtau_previous_over_g": float(np.abs(s0.tau - sol.tau).max() / g),
                "Tx/muP": sol.Tx / (contact.mu * contact.P),
                "Ty/muP": sol.Ty / (contact.mu * contact.P),
                "adhesion": sol.adhesion_fraction,
            }
            if dense_patch is not None:
                dense = harness.repeated(lambda a=args, p=dense_patch: solve_rolling(p, *a), repeat)
                t_dense, sd = dense.median, dense.result
                entry["dense_s"] = t_dense
                entry["dense_over_fft"] = t_dense / t_fft
                entry["max_dtau_over_g"] = float(np.abs(sd.tau - sol.tau).max() / patch.g.max())
            else:
                entry["dense_s"] = None
            results["cases"].setdefault(name, {})[n] = entry
            print(
                f"n={n:4d} {name:14s} fft {t_fft:8.4f} s  single-level {t_single:8.4f} s  "
                f"previous {t_prev:8.4f} s  dense "
                f"{entry['dense_s'] if entry['dense_s'] is not None else float('nan'):8.4f} s  "
                f"Newton {sol.newton_iterations:2d} (single {s1.newton_iterations:2d}, "
                f"previous {s0.newton_iterations:2d})  "
                f"GMRES {sol.gmres_iterations:4d} (single {s1.gmres_iterations:4d}, "
                f"previous {s0.gmres_iterations:4d}, "
                f"all levels {sol.gmres_work:.0f} fine-equivalent)  levels {sol.levels}",
                flush=True,
            )
    return results


def exponents(res: dict, key: str, case: str) -> list[tuple[int, int, float]]:
    """Observed exponent p of time ~ N^p between successive grids (N = n^2)."""
    out = []
    ns = [n for n in res["grids"] if res["cases"][case][n].get(key)]
    for a, b in zip(ns[:-1], ns[1:], strict=True):
        ta, tb = res["cases"][case][a][key], res["cases"][case][b][key]
        out.append((a, b, math.log(tb / ta) / math.log((b * b) / (a * a))))
    return out


def markdown(res: dict) -> str:
    lines = []
    for case in CASES:
        lines.append(
            f"\n**{case}** (railway wheel on rail, {CASES[case]} in units of mu P/(G c^2))\n"
        )
        lines.append(
            "| grid | elements in contact | FFT (s) | single-level (s) | previous (s) | dense (s) "
            "| dense/FFT | Newton (single, previous) | GMRES (single, previous) | GMRES/Newton "
            "| GMRES all levels | coarse levels Newton/GMRES |"
        )
        lines.append("|---|---|---|---|---|---|---|---|---|---|---|---|")
        for n in res["grids"]:
            e = res["cases"][case][n]
            s = res["setup"][n]
            d = e.get("dense_s")
            coarse = ", ".join(f"{lv[0]}: {lv[2]}/{lv[3]}" for lv in e["levels"][:-1]) or "-"
            lines.append(
                f"| {n}x{n} | {s['elements_in_contact']} | {e['fft_s']:.4f} "
                f"| {e['single_s']:.4f} | {e['previous_s']:.4f} | "
                + (f"{d:.4f} | {e['dense_over_fft']:.1f}" if d else "skipped (memory) | -")
                + f" | {e['newton']} ({e['single_newton']}, {e['previous_newton']})"
                f" | {e['gmres']} ({e['single_gmres']}, {e['previous_gmres']})"
                f" | {e['gmres'] / max(e['newton'], 1):.1f} | {e['gmres_work']:.0f} | {coarse} |"
            )
        fx = ", ".join(f"{a}->{b}: {p:.2f}" for a, b, p in exponents(res, "fft_s", case))
        dx = ", ".join(f"{a}->{b}: {p:.2f}" for a, b, p in exponents(res, "dense_s", case))
        lines.append(
            f"\nScaling exponent p of time ~ N^p (N = n^2 elements): FFT {fx}; dense {dx}."
        )
    lines.append(
        "\n| grid | FFT setup, all levels (s) "
        "| single-level setup (s) | dense matrix (MB) | dense setup (s) |"
    )
    lines.append("|---|---|---|---|---|")
    for n in res["grids"]:
        s = res["setup"][n]
        lines.append(
            f"| {n}x{n} | {s['fft_setup_s']:.3f} | {s['single_setup_s']:.3f} "
            f"| {s['dense_matrix_MB']:.0f} | {s['dense_setup_s']:.3f} |"
        )
    return "\n".join(lines)


def _s(t: float | None) -> str:
    return "skipped" if t is None else f"{t:.3g}"


def doc_tables(res: dict, command: str) -> tuple[str, str]:
    """The blocks of docs/performance.md: the times per grid (FFT, single-level,
    baseline, dense; both cases side by side) and the fine-grid Newton / GMRES counts of
    the default against the baseline."""
    long, comb = (res["cases"][k] for k in CASES)
    head = "| grid | elements in contact | longitudinal: FFT (s) | single-level (s) | baseline (s) "
    head += "| dense (s) | combined + spin: FFT (s) | single-level (s) | baseline (s) | dense (s) |"
    times = [harness.made_by(command), "", head, "|---|---|---|---|---|---|---|---|---|---|"]
    counts = [
        f"Made by the same run (`{command}`).",
        "",
        "| grid | longitudinal | baseline | combined + spin | baseline |",
        "|---|---|---|---|---|",
    ]
    for n in res["grids"]:
        cells = [f"{n} x {n}", str(res["setup"][n]["elements_in_contact"])]
        its = [f"{n} x {n}"]
        for e in (long[n], comb[n]):
            cells += [_s(e[k]) for k in ("fft_s", "single_s", "previous_s")]
            cells.append(_s(e.get("dense_s")))
            its += [
                f"{e['newton']} / {e['gmres']}",
                f"{e['previous_newton']} / {e['previous_gmres']}",
            ]
        times.append("| " + " | ".join(cells) + " |")
        counts.append("| " + " | ".join(its) + " |")
    return "\n".join(times), "\n".join(counts)


def table_report(n: int, nodes: tuple[int, int, int], points: int, seed: int = 1) -> dict:
    """Build the railway creep-force table on an n x n solver grid and measure its
    interpolation error against direct solves at random points of the table box."""
    from contact_fmu.halfspace.table import build_table

    contact = wheel_on_rail(n=n)
    t0 = time.perf_counter()
    table = build_table(contact, nodes=nodes)
    build_s = time.perf_counter() - t0
    rng = np.random.default_rng(seed)
    X = table.data.extent
    muP = contact.mu * contact.P
    err = []
    for x in rng.uniform(-0.98, 0.98, (points, 3)) * X:
        a = (x[0] * table.xi_ref, x[1] * table.xi_ref, x[2] * table.phi_ref)
        s = contact.solve(*a)
        T = table.forces(*a, 1.0)
        err.append(
            [abs(T[0] - s.Tx) / muP, abs(T[1] - s.Ty) / muP, abs(T[2] - s.Mz) / (muP * contact.c)]
        )
    err = np.array(err)
    from contact_fmu.laws.thin_layer import LayerContact

    lc = LayerContact(1e5, 0.46, 0.3, 5e-13, 5e-13, 3.2e-13, 3.2e-13, 0.3)
    calls = {}
    for label, v in (("no_spin", (1e-3, 5e-4, 0.0, 20.0)), ("spin", (1e-3, 5e-4, 0.1, 20.0))):
        for name, law in (("table", table), ("layer", lc)):
            reps = 2000 if name == "table" or label == "no_spin" else 50
            t0 = time.perf_counter()
            for _ in range(reps):
                law.forces(*v)
            calls[f"{name}_{label}_us"] = (time.perf_counter() - t0) / reps * 1e6
    vec = np.linspace(-0.01, 0.01, 10000)
    t0 = time.perf_counter()
    table.forces(vec, 0.0, 0.0, 20.0)
    vec_us = (time.perf_counter() - t0) / len(vec) * 1e6
    return {
        "n": n,
        "nodes": nodes,
        "solves": json.loads(table.data.meta)["solves"],
        "build_s": build_s,
        "max_err": err.max(axis=0).tolist(),
        "rms_err": np.sqrt((err**2).mean(axis=0)).tolist(),
        "scalar_calls": calls,
        "vector_us_per_point": vec_us,
    }


def main(argv: list[str] | None = None) -> None:
    ap = harness.parser(__doc__, "docs/performance.md")
    ap.add_argument("--grids", type=int, nargs="+", default=None, help="default 16 32 64 128")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--dense-limit-mb", type=float, default=1500.0)
    ap.add_argument("--json", type=str, default=None)
    ap.add_argument(
        "--table",
        type=int,
        nargs=4,
        metavar=("N", "N1", "N2", "N3"),
        default=None,
        help="instead: build the railway table on an N x N grid with N1 x N2 x N3 nodes "
        "and report its cost and interpolation error",
    )
    ap.add_argument("--points", type=int, default=60, help="random points for --table")
    args = ap.parse_args(argv)
    if args.table:
        rep = table_report(args.table[0], tuple(args.table[1:]), args.points)
        print(json.dumps(rep, indent=1))
        if args.json:
            with open(args.json, "w") as f:
                json.dump(rep, f, indent=1)
        return
    grids = args.grids or [16, 32, 64, 128]
    res = run(grids, args.repeat, args.dense_limit_mb)
    print(markdown(res))
    if args.write:
        cmd = "python benchmarks/bench_halfspace.py"
        cmd += f" --grids {' '.join(map(str, grids))}" if args.grids else ""
        times, counts = doc_tables(res, f"{cmd} --repeat {args.repeat} --write")
        harness.write_block(DOC, BLOCK, times)
        harness.write_block(DOC, ITERATIONS_BLOCK, counts)
    print("\nCONTACT (published, 2016 hardware, one thread):", CONTACT_PUBLISHED)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(res, f, indent=1, default=str)


if __name__ == "__main__":
    main()
