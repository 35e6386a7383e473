"""Small grids against CONTACT's published steady-rolling times: first solve (patch,
kernels and dense operator built in the call) and repeat solve, today's solver against
a previous revision's, alternately in one run.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_halfspace_small.py \\
        [--repeat 11] [--grids 11 19 23 35] [--baseline cc7bca5] [--curve 32] [--curve-repeat 5] \\
        [--crossover 19 21 23 25 27]

The railway wheel on rail (contact_fmu.halfspace.railway) on m x m elements over the
potential contact area (``HalfSpaceContact(n=(m, m))``, CONTACT's meaning of the grid),
two cases: longitudinal creepage (xi = 0.3 mu P/(G c^2)) and combined creepage with
spin (xi = eta = 0.2, phi = 0.3 in the same units).

*first*: a fresh contact solved once, the whole call timed (Hertz pressure on the grid,
influence kernels, the dense operator, the FASTSIM calibration, the Newton iteration);
the kernel cache of each solver (where it has one) is emptied before each, so that no
call reuses another's kernels. *repeat*: the median of four more solves of the same contact (cold
starts, no warm start; the first of them builds K^-1 on the direct path): what a creep
curve or a table pays per point. CPU time of the process
(time.process_time; wall clock on a shared machine carries other processes' time),
median and best of --repeat, today's and the previous solver alternately.

Previous solver: the package contact_fmu of git revision --baseline, extracted by
``git archive`` into a temporary folder and imported as contact_fmu_prev (its modules
import each other relatively), called the same way. max dT: the largest difference of
Tx, Ty between the two, relative to mu P (both converged to the Newton tolerance).

--curve m: a 20-point creep curve (xi = 0.075 .. 1.5 mu P/(G c^2), no spin) on the
int grid ``HalfSpaceContact(n=m)`` of a fresh contact, ``c.forces(xs, 0, 0, 1)``: the
previous solver, today's with every point solved cold (``continuation=False``) and
today's default (each point from the secant prediction of the last two,
``rolling.Continuation``), alternately, --curve-repeat times; median and best CPU time.
Pass --grids with --repeat 0 for the curve alone.

--crossover m ...: today's solver by either path (``solve_rolling(method="direct")``
and ``"iterative"``) on m x m, first and repeat solves: the measurement behind
``rolling.DIRECT_MAX_ELEMENTS``.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse  # noqa: E402
import importlib  # noqa: E402
import platform  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from contact_fmu.halfspace import influence  # noqa: E402
from contact_fmu.halfspace.railway import wheel_on_rail  # noqa: E402

CASES = {"longitudinal": (0.3, 0.0, 0.0), "combined+spin": (0.2, 0.2, 0.3)}
# CONTACT's published steady-rolling times (its documentation; 2016 hardware, one thread)
CONTACT_PUBLISHED = {11: 1.9e-3, 19: 9.7e-3, 35: 0.134}


def previous_package(rev: str, where: Path):
    """contact_fmu of git revision ``rev`` imported as contact_fmu_prev; its railway module."""
    root = Path(__file__).resolve().parents[1]
    tar = subprocess.run(
        ["git", "archive", rev, "contact_fmu"], cwd=root, check=True, capture_output=True
    ).stdout
    subprocess.run(["tar", "-x", "-C", str(where)], input=tar, check=True)
    (where / "contact_fmu").rename(where / "contact_fmu_prev")
    sys.path.insert(0, str(where))
    return importlib.import_module("contact_fmu_prev.halfspace.railway")


def cpu(f):
    t = time.process_time()
    out = f()
    return time.process_time() - t, out


def fresh_new(m):
    influence._cerruti_reference.cache_clear()
    return wheel_on_rail(n=(m, m))


def fresh_old(old, m, n=None):
    """A fresh contact of the previous solver, its kernel cache (where it has one)
    emptied like today's."""
    prev = importlib.import_module("contact_fmu_prev.halfspace.influence")
    cache = getattr(prev, "_cerruti_reference", None)
    if cache is not None:
        cache.cache_clear()
    # the previous revision's int m is today's (m, m): before the one grid rule a pair
    # spared an element in y as well, a grid of other elements
    return old.wheel_on_rail(n=m if n is None else n)


def crossover(m: int) -> None:
    """Today's solver on m x m by either path (solve_rolling(method=...)): first solve
    of a fresh contact (patch and kernels built in the call) and the median of four
    repeat solves after one more, medians of three runs, each case."""
    from contact_fmu.halfspace.rolling import solve_rolling

    for name, w in CASES.items():
        res: dict[str, list[tuple[float, float]]] = {"direct": [], "iterative": []}
        for _ in range(3):
            for meth in res:
                c = fresh_new(m)
                xref = c.mu * c.P / (c.elastic.G * c.c**2)
                a = (w[0] * xref, w[1] * xref, w[2] * xref / c.c)

                def one(c=c, a=a, meth=meth):
                    return solve_rolling(c.patch, *a, method=meth)

                first, _ = cpu(one)
                again = [cpu(one)[0] for _ in range(5)][1:]
                res[meth].append((first, statistics.median(again)))
        n_c = int(c.patch.contact.sum())
        cols = [
            f"{statistics.median(f for f, _ in v) * 1e3:.1f}, "
            f"{statistics.median(r for _, r in v) * 1e3:.1f}"
            for v in res.values()
        ]
        print(
            f"# crossover {m} x {m} ({n_c} elements), {name}: first, repeat (ms): "
            f"direct {cols[0]}; iterative {cols[1]}",
            flush=True,
        )


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=11)
    ap.add_argument("--grids", type=int, nargs="+", default=[11, 19, 23, 35])
    ap.add_argument("--baseline", default="cc7bca5", help="git revision of the previous solver")
    ap.add_argument("--curve", type=int, default=32, help="grid of the creep curve (0: none)")
    ap.add_argument("--curve-repeat", type=int, default=5, help="runs of each creep curve")
    ap.add_argument(
        "--crossover", type=int, nargs="*", default=[], help="grids of the path crossover"
    )
    args = ap.parse_args(argv)
    tmp = tempfile.TemporaryDirectory()
    old = previous_package(args.baseline, Path(tmp.name))
    print(f"# {platform.processor() or platform.machine()}, python {platform.python_version()}")
    print(f"# previous: {args.baseline}; load average before: {os.getloadavg()[0]:.2f}")
    print(
        "| grid | contact elements | case | first: previous, new (ms) | best first: previous, "
        "new | repeat: previous, new (ms) | best repeat: previous, new | first previous/new "
        "| CONTACT published (ms) | new first/CONTACT | max dT/(mu P) |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for m in args.grids:
        probe = wheel_on_rail(n=(m, m))
        n_c = int(probe.patch.contact.sum())
        xref = probe.mu * probe.P / (probe.elastic.G * probe.c**2)
        a_of = {k: (w[0] * xref, w[1] * xref, w[2] * xref / probe.c) for k, w in CASES.items()}
        for name, a in a_of.items():
            if args.repeat == 0:
                continue
            # one untimed solve of each solver first: the process's one-time costs (lazy
            # imports, LAPACK lookups, the per-thread scratch memory) are no contact's
            fresh_old(old, m).solve(*a)
            fresh_new(m).solve(*a)
            first: list[list[float]] = [[], []]
            again: list[list[float]] = [[], []]
            for _ in range(args.repeat):
                for i in range(2):
                    c = fresh_old(old, m) if i == 0 else fresh_new(m)
                    dt, s = cpu(lambda c=c, a=a: c.solve(*a))
                    first[i].append(dt)
                    # later solves: the first of them builds K^-1 (direct path); their
                    # median is what a creep curve or a table pays per point
                    later = [cpu(lambda c=c, a=a: c.solve(*a)) for _ in range(4)]
                    again[i].append(statistics.median(t for t, _ in later))
                    s = later[-1][1]
                    if i == 0:
                        so = s
            med_f = [statistics.median(t) * 1e3 for t in first]
            med_r = [statistics.median(t) * 1e3 for t in again]
            best_f = [min(t) * 1e3 for t in first]
            best_r = [min(t) * 1e3 for t in again]
            ref = CONTACT_PUBLISHED.get(m)
            cref = f"{ref * 1e3:.1f}" if ref else "-"
            vs = f"{med_f[1] * 1e-3 / ref:.2f}" if ref else "-"
            muP = probe.mu * probe.P
            dT = max(abs(s.Tx - so.Tx), abs(s.Ty - so.Ty)) / muP
            print(
                f"| {m} x {m} | {n_c} | {name} | {med_f[0]:.2f}, {med_f[1]:.2f} | "
                f"{best_f[0]:.2f}, {best_f[1]:.2f} | {med_r[0]:.2f}, {med_r[1]:.2f} | "
                f"{best_r[0]:.2f}, {best_r[1]:.2f} | {med_f[0] / med_f[1]:.1f} | {cref} | "
                f"{vs} | {dT:.1e} |",
                flush=True,
            )
    if args.curve:
        m = args.curve
        # alternately: the previous solver, today's without continuation (every point
        # cold, continuation=False) and today's default (continuation)
        labels = ("previous", "new, cold points", "new, continuation")
        times: dict[str, list[float]] = {k: [] for k in labels}
        curves = {}
        for _ in range(args.curve_repeat):
            for label in labels:
                if label == "previous":
                    c = fresh_old(old, m, m)
                else:
                    influence._cerruti_reference.cache_clear()
                    c = wheel_on_rail(n=m)
                xref = c.mu * c.P / (c.elastic.G * c.c**2)
                xs = np.linspace(0.0, 1.5, 21)[1:] * xref
                kw = {} if label == "previous" else {"continuation": label.endswith("ion")}
                dt, T = cpu(lambda c=c, xs=xs, kw=kw: c.forces(xs, 0.0, 0.0, 1.0, **kw))
                times[label].append(dt)
                curves[label] = np.array(T[:2]) / (c.mu * c.P)
        base = statistics.median(times["previous"])
        for label in labels:
            med = statistics.median(times[label])
            dT = float(np.abs(curves[label] - curves["previous"]).max())
            print(
                f"# 20-point creep curve on {m} x {m}, {label}: median {med:.3f} s CPU, "
                f"best {min(times[label]):.3f} s (previous/this {base / med:.2f}; "
                f"max dT/(mu P) against previous {dT:.1e})"
            )
    for m in args.crossover:
        crossover(m)
    print(f"# load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
