"""FASTSIM (contact_fmu.halfspace.Fastsim) against the exact half-space solver: the creep
curves' differences and the time per solve.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_halfspace_fastsim.py \\
        [--grid 66] [--points 12] [--repeat 7] [--write]

Contacts: steel on steel (nu = 0.28), mu = 0.3, a circle (a/b = 1, 5 mm, 50 kN) and the
railway wheel on rail (a/b = 1.33, ``wheel_on_rail``), both on (grid, grid) elements.
FASTSIM runs on the same grid (``Fastsim.of``) with Kalker's coefficients (his Table E3,
``kalker_coefficients``), parabolic and elliptic bounds. Creep curves in units of
xref = mu P/(G c^2) (spin in xref/c), --points points each: longitudinal xi = 0 .. 1.5,
lateral eta = 0 .. 1.5, spin phi = 0 .. 3, and combined xi = eta = 0 .. 1 with phi =
0.3. Listed: the largest |T_fastsim - T_exact| over each curve in % of mu P (Tx, Ty; the
larger), with the creepage where it occurs; the exact solver's own discretisation
error on this grid is about 0.5 % of mu P (docs/halfspace.md, grid convergence).

Times: CPU time of the process (time.process_time), median of --repeat, for one
``Fastsim.solve`` (fields and masks included; the patch built beforehand), one point of
a batched ``Fastsim.forces`` curve of 100 points, and one exact ``HalfSpaceContact.solve``
(after a first solve that builds its operators), on 12 x 12, 32 x 32 and (grid, grid).

--write replaces the block "bench_halfspace_fastsim.py" of docs/halfspace.md (FASTSIM
beside the exact solver) with both tables.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import platform  # noqa: E402

import numpy as np  # noqa: E402

from contact_fmu.halfspace import STEEL, Fastsim, HalfSpaceContact, wheel_on_rail  # noqa: E402

if __package__:  # python -m benchmarks
    from . import harness
else:  # run as a script: benchmarks/ is first on sys.path
    import harness  # type: ignore[no-redef]

# name: (creepages (xi, eta, phi) at the curve parameter s in (0, 1], the label of s's
# creepage in the table)
CURVES = {
    "longitudinal": (lambda s: (1.5 * s, 0.0, 0.0), lambda s: f"xi = {1.5 * s:.2f}"),
    "lateral": (lambda s: (0.0, 1.5 * s, 0.0), lambda s: f"eta = {1.5 * s:.2f}"),
    "spin": (lambda s: (0.0, 0.0, 3.0 * s), lambda s: f"phi = {3.0 * s:.2f}"),
    "combined + spin 0.3": (lambda s: (s, s, 0.3), lambda s: f"xi = eta = {s:.2f}"),
}


def contacts(m: int) -> dict[str, HalfSpaceContact]:
    return {
        "a/b = 1": HalfSpaceContact.from_ellipse(5e-3, 5e-3, STEEL, STEEL, 0.3, P=5e4, n=(m, m)),
        "railway a/b = 1.33": wheel_on_rail(n=(m, m)),
    }


def cpu(f, repeat: int) -> float:
    """Median CPU seconds of ``repeat`` calls of ``f``."""
    return harness.repeated(f, repeat, harness.cpu_time).median


def main(argv: list[str] | None = None) -> None:
    ap = harness.parser(__doc__, "docs/halfspace.md")
    ap.add_argument("--grid", type=int, default=66)
    ap.add_argument("--points", type=int, default=12)
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args(argv)
    lines: list[str] = []

    def out(line: str = "") -> None:
        lines.append(line)
        print(line, flush=True)

    print(f"# {platform.processor() or platform.machine()}, python {platform.python_version()}")
    out(
        f"Largest abs(T_fastsim - T_exact) (Tx, Ty) over each curve in % of mu P, and where; "
        f"both solvers on {args.grid} x {args.grid} elements, {args.points} points per curve:"
    )
    out()
    out("| contact | curve | parabolic bound | elliptic bound |")
    out("|---|---|---|---|")
    steps = np.linspace(1.0 / args.points, 1.0, args.points)
    for name, c in contacts(args.grid).items():
        muP = c.mu * c.P
        xref = muP / (c.elastic.G * c.c**2)
        fs = {b: Fastsim.of(c, bound=b) for b in ("parabolic", "elliptic")}
        for curve, (w, label) in CURVES.items():
            worst = {b: (0.0, 0.0) for b in fs}
            for s in steps:
                xi, eta, phi = w(s)
                args_ = (xi * xref, eta * xref, phi * xref / c.c)
                e = c.solve(*args_, check_units=False)
                for b, f in fs.items():
                    r = f.solve(*args_, check_units=False)
                    d = max(abs(r.Tx - e.Tx), abs(r.Ty - e.Ty)) / muP
                    if d > worst[b][0]:
                        worst[b] = (d, s)
            cells = [f"{100 * worst[b][0]:.1f} ({label(worst[b][1])})" for b in fs]
            out(f"| {name} | {curve} | {cells[0]} | {cells[1]} |")
    out()
    out(
        "Cost (CPU time, median): one `Fastsim.solve` (tractions, masks and forces; the patch "
        "built once) and one point of a 100-point `forces` curve, against one exact solve of "
        "the railway case (xi = eta = 0.2, phi = 0.3):"
    )
    out()
    out(
        "| grid | contact elements | Fastsim.solve (ms) | forces per point (ms) "
        "| exact solve (ms) | exact/FASTSIM |"
    )
    out("|---|---|---|---|---|---|")
    for m in (12, 32, args.grid):
        c = wheel_on_rail(n=(m, m))
        xref = c.mu * c.P / (c.elastic.G * c.c**2)
        w = (0.2 * xref, 0.2 * xref, 0.3 * xref / c.c)
        f = Fastsim.of(c)
        f.solve(*w)  # the patch and the flexibilities
        t_fs = cpu(lambda f=f, w=w: f.solve(*w), 5 * args.repeat)
        xs = np.linspace(0.0, 1.5, 100) * xref
        t_curve = cpu(lambda f=f, xs=xs, w=w: f.forces(xs, 0.5 * xs, w[2]), args.repeat) / 100
        c.solve(*w)  # operators
        t_ex = cpu(lambda c=c, w=w: c.solve(*w), args.repeat)
        n_c = int(f.patch.contact.sum())
        out(
            f"| {m} x {m} | {n_c} | {t_fs * 1e3:.2f} | {t_curve * 1e3:.3f} | {t_ex * 1e3:.1f} "
            f"| {t_ex / t_fs:.0f} |"
        )
    if args.write:
        command = " ".join(
            ["benchmarks/bench_halfspace_fastsim.py", "--grid", str(args.grid), "--points",
             str(args.points), "--repeat", str(args.repeat), "--write"]
        )  # fmt: skip
        body = "\n".join([harness.made_by(command), "", *lines])
        harness.write_block(harness.DOCS / "halfspace.md", "bench_halfspace_fastsim.py", body)


if __name__ == "__main__":
    main()
