"""Small grids against CONTACT's published steady-rolling times: the direct path
(contact_fmu.halfspace.direct, ``solve_rolling(method="auto")``) against the previous
direct path and the iterative path (``method="iterative"``, GMRES Newton steps), in one
run.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_halfspace_small.py \\
        [--repeat 21] [--grids 11 19 23 35] [--baseline a6f0032] [--force-direct]

The railway wheel on rail (contact_fmu.halfspace.railway) on mx x my elements over the
potential contact area (``HalfSpaceContact(n=(m, m))``, CONTACT's meaning of the grid),
two cases: longitudinal creepage (xi = 0.3 mu P/(G c^2)) and combined creepage with
spin (xi = eta = 0.2, phi = 0.3 in the same units). Times: median and best of --repeat
cold solves (no warm start), the three solvers alternately, CPU time of the process
(time.process_time; wall clock on a shared machine carries other processes' time). The
patch (kernels, the dense operator, its inverse, the FASTSIM calibration) is built once
per grid and timed apart ("setup"), as CONTACT's influence coefficients would be reused
over a table build.

Baseline ("previous"): the default path of the git revision --baseline: for contacts
within that revision's DIRECT_MAX_ELEMENTS its contact_fmu/halfspace/direct.py (read by
``git show``), called the way its solve_rolling called it (``patch.rhs``, its
``newton`` from the projected full-adhesion guess, the same ``_solution``) on the same
patch; above, the iterative path. --force-direct: "new" takes the direct path on every
grid (the crossover with the iterative path, which sets DIRECT_MAX_ELEMENTS). The
table's last column: max |dTx|, |dTy| of new against previous, relative to mu P (both
converged to the Newton tolerance).
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse  # noqa: E402
import platform  # noqa: E402
import re  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import time  # noqa: E402
import types  # noqa: E402
from collections.abc import Callable  # noqa: E402
from pathlib import Path  # noqa: E402

import scipy.linalg as sla  # noqa: E402

from contact_fmu.halfspace.railway import wheel_on_rail  # noqa: E402
from contact_fmu.halfspace.rolling import (  # noqa: E402
    DIRECT_MAX_ELEMENTS,
    NEWTON_MAXIT,
    NEWTON_TOL,
    RollingPatch,
    RollingSolution,
    _solution,
    solve_rolling,
)

CASES = {"longitudinal": (0.3, 0.0, 0.0), "combined+spin": (0.2, 0.2, 0.3)}
# CONTACT's published steady-rolling times (references.md; 2016 hardware, one thread)
CONTACT_PUBLISHED = {11: 1.9e-3, 19: 9.7e-3, 35: 0.134}
ROLLING = "contact_fmu/halfspace/rolling.py"


def git_show(rev: str, path: str) -> str:
    root = Path(__file__).resolve().parents[1]
    cmd = ["git", "show", f"{rev}:{path}"]
    return subprocess.run(cmd, cwd=root, check=True, capture_output=True, text=True).stdout


def previous_direct(rev: str) -> tuple[types.ModuleType, int]:
    """direct.py of git revision ``rev`` as a module, and that revision's
    DIRECT_MAX_ELEMENTS (rolling.py)."""
    mod = types.ModuleType(f"direct_{rev}")
    src = git_show(rev, "contact_fmu/halfspace/direct.py")
    exec(compile(src, f"{rev}:direct.py", "exec"), mod.__dict__)
    limit = re.search(r"^DIRECT_MAX_ELEMENTS = (\d+)", git_show(rev, ROLLING), re.M)
    return mod, int(limit.group(1))


def cpu(f: Callable[[], RollingSolution]) -> tuple[float, RollingSolution]:
    t = time.process_time()
    out = f()
    return time.process_time() - t, out


def time_case(
    p: RollingPatch,
    a: tuple[float, float, float],
    old: types.ModuleType | None,
    repeat: int,
    method: str,
) -> tuple[list[list[float]], RollingSolution, RollingSolution]:
    """CPU times of the iterative path, the previous solver (its direct path if ``old``,
    else its iterative path) and today's default, alternately; the last solutions of the
    previous and today's."""

    def previous() -> RollingSolution:
        if old is None:
            return solve_rolling(p, *a, method="iterative")
        tau, S, slip, it = old.newton(p, p.rhs(*a), None, NEWTON_TOL, NEWTON_MAXIT)
        return _solution(p, tau, S, slip, it, 0, ())

    times: list[list[float]] = [[], [], []]
    for _ in range(repeat):
        times[0].append(cpu(lambda: solve_rolling(p, *a, method="iterative"))[0])
        dt, so = cpu(previous)
        times[1].append(dt)
        dt, s = cpu(lambda: solve_rolling(p, *a, method=method))
        times[2].append(dt)
    return times, so, s


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=21)
    ap.add_argument("--grids", type=int, nargs="+", default=[11, 19, 23, 35])
    ap.add_argument("--baseline", default="a6f0032", help="git revision of the previous path")
    ap.add_argument(
        "--force-direct",
        action="store_true",
        help='"new" with method="direct" on every grid (the crossover with the iterative path)',
    )
    args = ap.parse_args()
    method = "direct" if args.force_direct else "auto"
    old, old_limit = previous_direct(args.baseline)
    print(f"# {platform.processor() or platform.machine()}, python {platform.python_version()}")
    print(f"# direct path for contacts of at most {DIRECT_MAX_ELEMENTS} elements; new: {method}")
    print(f"# previous: {args.baseline}, its direct path for at most {old_limit} elements")
    print(f"# load average before: {os.getloadavg()[0]:.2f}")
    print(
        "| grid | contact elements | case | setup (ms) | path: previous, new "
        "| Newton steps: previous, new | CPU median: iterative, previous, new (ms) "
        "| best: iterative, previous, new (ms) | previous/new | CONTACT published (ms) "
        "| new/CONTACT | max dT/(mu P) |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for m in args.grids:
        c = wheel_on_rail(n=(m, m))
        t0 = time.perf_counter()
        p = c.patch
        n_c = int(p.contact.sum())
        xref = c.mu * c.P / (c.elastic.G * c.c**2)
        # build what each path caches: FASTSIM calibration, dense operator, its inverse
        solve_rolling(p, xref, method="iterative")
        if n_c <= DIRECT_MAX_ELEMENTS or args.force_direct:
            solve_rolling(p, xref, method="direct")
            _ = p.dense_contact_inverse
        if n_c <= old_limit:  # what the previous path cached on the patch besides
            p.dense_contact_lu = sla.lu_factor(p.dense_contact_operator)
        setup = time.perf_counter() - t0
        ref = CONTACT_PUBLISHED.get(m)
        for name, w in CASES.items():
            a = (w[0] * xref, w[1] * xref, w[2] * xref / c.c)
            times, so, s = time_case(p, a, old if n_c <= old_limit else None, args.repeat, method)
            med = [statistics.median(t) * 1e3 for t in times]
            best = [min(t) * 1e3 for t in times]
            paths = ", ".join("direct" if x.gmres_iterations == 0 else "iterative" for x in (so, s))
            dT = max(abs(s.Tx - so.Tx), abs(s.Ty - so.Ty)) / (c.mu * c.P)
            cref = f"{ref * 1e3:.1f}" if ref else "-"
            vs = f"{med[2] * 1e-3 / ref:.2f}" if ref else "-"
            print(
                f"| {m} x {m} | {n_c} | {name} | {setup * 1e3:.0f} | {paths} | "
                f"{so.newton_iterations}, {s.newton_iterations} | "
                f"{', '.join(f'{x:.2f}' for x in med)} | {', '.join(f'{x:.2f}' for x in best)} | "
                f"{med[1] / med[2]:.2f} | {cref} | {vs} | {dT:.1e} |",
                flush=True,
            )
    print(f"# load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
