"""Small grids against CONTACT's published steady-rolling times: the direct path
(contact_fmu.halfspace.direct, ``solve_rolling(method="auto")``) against the iterative
path (``method="iterative"``, GMRES Newton steps), in one run.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_halfspace_small.py [--repeat 15]

The railway wheel on rail (contact_fmu.halfspace.railway) on mx x my = 11 x 11, 19 x 19
and 35 x 35 elements over the potential contact area (``HalfSpaceContact(n=(m, m))``,
CONTACT's meaning of the grid), two cases: longitudinal creepage (xi = 0.3 mu P/(G c^2))
and combined creepage with spin (xi = eta = 0.2, phi = 0.3 in the same units). Times:
median of --repeat cold solves (no warm start), the two paths alternately, wall clock
(and, on a shared machine, the process's CPU time, time.process_time); the patch
(kernels, the dense operator and its LU of the direct path, the FASTSIM calibration of
the iterative path) is built once per grid and timed apart ("setup"), as CONTACT's
influence coefficients would be reused over a table build.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse  # noqa: E402
import platform  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

from contact_fmu.halfspace.railway import wheel_on_rail  # noqa: E402
from contact_fmu.halfspace.rolling import DIRECT_MAX_ELEMENTS, solve_rolling  # noqa: E402

CASES = {"longitudinal": (0.3, 0.0, 0.0), "combined+spin": (0.2, 0.2, 0.3)}
# CONTACT's published steady-rolling times (references.md; 2016 hardware, one thread)
CONTACT_PUBLISHED = {11: 1.9e-3, 19: 9.7e-3, 35: 0.134}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=15)
    args = ap.parse_args()
    print(f"# {platform.processor() or platform.machine()}, python {platform.python_version()}")
    print(f"# direct path for contacts of at most {DIRECT_MAX_ELEMENTS} elements")
    print(f"# load average before: {os.getloadavg()[0]:.2f}")
    print(
        "| grid | contact elements | case | setup (ms) | iterative (ms) | auto (ms) | path "
        "| iterative/auto | best of: iterative, auto (ms) | CPU time: iterative, auto (ms) "
        "| CONTACT published (ms) |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for m, ref in CONTACT_PUBLISHED.items():
        c = wheel_on_rail(n=(m, m))
        t0 = time.perf_counter()
        p = c.patch
        n_c = int(p.contact.sum())
        xref = c.mu * c.P / (c.elastic.G * c.c**2)
        # build what each path caches: FASTSIM calibration, dense operator and LU
        solve_rolling(p, xref, method="iterative")
        if n_c <= DIRECT_MAX_ELEMENTS:
            solve_rolling(p, xref)
        setup = time.perf_counter() - t0
        for name, w in CASES.items():
            a = (w[0] * xref, w[1] * xref, w[2] * xref / c.c)
            ti, ta, ci, ca = [], [], [], []
            for _ in range(args.repeat):
                t, c0 = time.perf_counter(), time.process_time()
                solve_rolling(p, *a, method="iterative")
                ti.append(time.perf_counter() - t)
                ci.append(time.process_time() - c0)
                t, c0 = time.perf_counter(), time.process_time()
                s = solve_rolling(p, *a)
                ta.append(time.perf_counter() - t)
                ca.append(time.process_time() - c0)
            mi, ma = statistics.median(ti), statistics.median(ta)
            cpu = f"{statistics.median(ci) * 1e3:.2f}, {statistics.median(ca) * 1e3:.2f}"
            path = "direct" if s.gmres_iterations == 0 else "iterative"
            best = f"{min(ti) * 1e3:.2f}, {min(ta) * 1e3:.2f}"
            print(
                f"| {m} x {m} | {n_c} | {name} | {setup * 1e3:.0f} | {mi * 1e3:.2f} | "
                f"{ma * 1e3:.2f} | {path} | {mi / ma:.1f} | {best} | {cpu} | {ref * 1e3:.1f} |",
                flush=True,
            )
    print(f"# load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
