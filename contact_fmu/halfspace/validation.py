"""python -m contact_fmu.halfspace.validation [OUT.md] [FIGDIR]

Writes docs/validation.md (default) and its convergence figure (docs/figures): every
published result the half-space and thin-layer solvers are checked against, with the
grid, the value, the reference and the error. The tests (tests/test_halfspace_*.py)
assert the same comparisons with tolerances; this page lists the numbers. About one to
two minutes on one core.
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import numpy as np

from .. import examples as ex
from .contact import HalfSpaceContact
from .fastsim import KALKER_NUS, KALKER_TABLE
from .hertz import Hertz, Material
from .influence import Grid
from .line import LineContact
from .normal import solve_normal
from .railway import STEEL, wheel_on_rail
from .rolling import ellipse_patch, solve_rolling
from .transient import HalfSpaceField

COMMAND = "python -m contact_fmu.halfspace.validation"


def _kalker_row(aob: float) -> tuple[tuple[float, ...], ...]:
    """Kalker (1990), Table E3 at one of its nodes a/b = 0.1 k or b/a = 0.1 k (fastsim's
    copy of the table): (C11, C22, C23), each for nu = 0, 0.25, 0.5."""
    case, g = (0, aob) if aob <= 1.0 else (1, 1.0 / aob)
    row = KALKER_TABLE[case, round(10.0 * g) - 1]
    return tuple(tuple(float(c) for c in coefficient) for coefficient in row)


# The validated rows: a/b -> (C11, C22, C23) for nu in NUS.
KALKER_E3 = {aob: _kalker_row(aob) for aob in (0.2, 0.5, 1.0, 2.0, 5.0)}
NUS = KALKER_NUS
# The convergence cases: elements per side.
GRIDS = (16, 32, 64, 128)
# The spin case: ellipse a/b = 2 (7 x 3.5 mm, steel, 50 kN), eta = -6e-4, phi = 0.6
# rad/m, mu = 0.3 (a railway user's kind of case); the creepage case: the railway wheel,
# xi = 0.3 mu P/(G c^2).
SPIN_CASE = dict(a1=7e-3, a2=3.5e-3, P=5e4, w=(0.0, -6e-4, 0.6))


def square_grid(aob: float, elements: int) -> tuple[int, int]:
    """(mx, my) of about elements^2 elements, about square (dx = 2 a1/(mx - 2), dy = 2
    a2/my), on an ellipse of ratio a/b."""
    r = math.sqrt(aob)
    return max(round(elements * r), 10), max(round(elements / r), 10)


def kalker_contact(aob: float, nu: float, elements: int) -> HalfSpaceContact:
    # dimensionless (G = 1, c = 1): no unit checks
    m = Material(2.0 * (1.0 + nu), nu, check_units=False)
    a1, a2 = math.sqrt(aob), 1.0 / math.sqrt(aob)
    n = square_grid(aob, elements)
    return HalfSpaceContact.from_ellipse(a1, a2, m, m, 0.3, P=1.0, n=n, check_units=False)


def pct(x: float) -> str:
    return f"{100.0 * x:+.2f} %"


# ---- the comparisons ------------------------------------------------------------------
def hertz_rows() -> list[list[str]]:
    """Polonsky-Keer on 64 x 64 (1.25 times the ellipse) against Hertz (railway)."""
    h = Hertz(1e5, 0.5 / 0.46, 0.5 / 0.30, wheel_on_rail().elastic.Estar)
    L1, L2 = 1.25 * h.a1, 1.25 * h.a2
    g = Grid(64, 64, 2 * L1 / 64, 2 * L2 / 64, -L1, -L2)
    X, Y = g.mesh()
    s = solve_normal(g, h.gap(X, Y), h.P, h.Estar)
    area = float(s.contact.sum() * g.area)
    return [
        [
            "peak pressure p0 (MPa)",
            "64 x 64",
            f"{s.p.max() / 1e6:.2f}",
            f"{h.p0 / 1e6:.2f}",
            pct(s.p.max() / h.p0 - 1),
        ],
        [
            "approach delta (um)",
            "64 x 64",
            f"{s.delta * 1e6:.3f}",
            f"{h.delta * 1e6:.3f}",
            pct(s.delta / h.delta - 1),
        ],
        [
            "contact area (mm^2)",
            "64 x 64",
            f"{area * 1e6:.2f}",
            f"{math.pi * h.a1 * h.a2 * 1e6:.2f}",
            pct(area / (math.pi * h.a1 * h.a2) - 1),
        ],
    ]


def carter_rows() -> list[list[str]]:
    """LineContact against F/(mu N) = 2 kappa - kappa^2 (Carter 1926)."""
    rows = []
    for n in (50, 100, 200):
        lc = LineContact(1e6, 0.1, STEEL, STEEL, 0.3, n=n)
        xi1 = lc.mu * lc.a / lc.R
        for kappa in (0.1, 0.5, 0.9):
            F, ref = lc.solve(kappa * xi1).Tx, lc.carter(kappa * xi1)
            rows.append(
                [
                    f"kappa = {kappa}",
                    f"{n} elements",
                    f"{F / (lc.mu * lc.N):.5f}",
                    f"{ref / (lc.mu * lc.N):.5f}",
                    pct(F / ref - 1),
                ]
            )
    return rows


def kalker_rows(elements: int) -> tuple[list[list[str]], float]:
    rows, worst = [], 0.0
    for aob, table in KALKER_E3.items():
        for j, nu in enumerate(NUS):
            c = kalker_contact(aob, nu, elements)
            k = c.creep_coefficients()
            cells = []
            for i, v in enumerate((k.C11, k.C22, k.C23)):
                ref = table[i][j]
                worst = max(worst, abs(v / ref - 1))
                cells.append(f"{v:.3f} ({ref}) {pct(v / ref - 1)}")
            mx, my = c.elements
            rows.append([f"{aob:g}", f"{nu:g}", f"{mx} x {my}", *cells, f"{k.C33:.3f}"])
    return rows, worst


def transient_rows() -> list[list[str]]:
    rows = []
    # Cattaneo-Mindlin at a given force (Johnson Eq. 7.42)
    for nu in (0.0, 0.3):
        m = Material(2 * (1 + nu) * 80e9, nu)
        c = HalfSpaceContact.from_ellipse(1e-3, 1e-3, m, m, 0.3, P=1000.0)
        G, a, muP = c.elastic.G, c.a1, c.mu * c.P
        for n in (24, 32):
            f = HalfSpaceField(c, n)
            for q in (0.3, 0.9):
                dx, _, _ = f.shift_for_force(q * muP)
                ref = 3 * muP * (2 - nu) / (8 * G * a) * (1 - (1 - q) ** (2 / 3))
                rows.append(
                    [
                        f"Cattaneo-Mindlin shift, nu = {nu}, Q = {q} mu P",
                        f"{n} x {n}",
                        f"{dx * 1e6:.4f} um",
                        f"{ref * 1e6:.4f} um",
                        pct(dx / ref - 1),
                    ]
                )
    # Kalker (1970): rolling from rest at constant creepage reaches steady rolling
    c = wheel_on_rail(n=16)
    xref = c.mu * c.P / (c.elastic.G * c.c**2)
    xi, eta, V = 0.1 * xref, 0.05 * xref, 30.0
    for n in (16, 24):
        f = HalfSpaceField(c, n)
        steady = solve_rolling(f.steady_patch(), xi, eta, 0.0)
        cells = n - 2
        Tx = [f.roll(f.dx / V, xi * V, eta * V, V).Tx for _ in range(6 * cells)]
        off = np.abs(np.array(Tx) / steady.Tx - 1.0) > 0.01
        settled = (int(np.flatnonzero(off)[-1]) + 1) / cells if off.any() else 0.0
        rows.append(
            [
                "steady rolling reached (Tx within 1 %), wheel on rail",
                f"{n} x {n}",
                f"{settled:.2f} contact lengths",
                "one to a few (Kalker 1970)",
                "-",
            ]
        )
        rows.append(
            [
                "stationary state = steady solution, after 6 contact lengths",
                f"{n} x {n}",
                f"{Tx[-1] / (c.mu * c.P):.6f} mu P",
                f"{steady.Tx / (c.mu * c.P):.6f} mu P",
                f"{Tx[-1] / steady.Tx - 1:+.1e}",
            ]
        )
    return rows


def layer_rows() -> list[list[str]]:
    """The layer-dominated half-space against LayerContact's closed form (Eqs. 40-43)."""
    lc = ex.contact()
    rows = []
    for n in (24, 32):
        patch = ellipse_patch(
            lc.a1,
            lc.a2,
            n,
            lambda X, Y: lc.pressure(X, Y),
            lc.mu,
            1e4 * lc.a1 / lc.k,
            0.3,
            k=lc.k,
            P=lc.P,
        )
        for frac in (0.3, 0.7, 0.95):
            v = frac * lc.creep_full_slip
            s = solve_rolling(patch, v)
            ref = float(lc.force(v, 0.0, 1.0)[0])
            rows.append(
                [
                    f"xi = {frac} of full slip",
                    f"{n} x {n}",
                    f"{s.Tx / (lc.mu * lc.P):.5f}",
                    f"{ref / (lc.mu * lc.P):.5f}",
                    pct(s.Tx / ref - 1),
                ]
            )
    return rows


def convergence() -> dict[str, list[float]]:
    """Ty of the spin case and Tx of the creepage case (units mu P) on GRIDS."""
    out: dict[str, list[float]] = {"spin": [], "creep": []}
    a1, a2, P, w = SPIN_CASE["a1"], SPIN_CASE["a2"], SPIN_CASE["P"], SPIN_CASE["w"]
    for n in GRIDS:
        c = HalfSpaceContact.from_ellipse(a1, a2, STEEL, STEEL, 0.3, P=P, n=n)
        out["spin"].append(c.solve(*w).Ty / (c.mu * c.P))
        r = wheel_on_rail(n=n)
        xref = r.mu * r.P / (r.elastic.G * r.c**2)
        out["creep"].append(r.solve(0.3 * xref).Tx / (r.mu * r.P))
    return out


def plot(conv: dict[str, list[float]], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.5, 4))
    n = np.array(GRIDS, float)
    for key, label in (("creep", "creepage: wheel on rail, Tx"), ("spin", "spin + lateral, Ty")):
        F = np.array(conv[key])
        ref = 2 * F[-1] - F[-2]  # Richardson, first order, from the two finest grids
        ax.loglog(n[:-1], np.abs(F[:-1] - ref), "o-", label=label)
    ax.loglog(n, 0.3 * n[0] / n * abs(conv["spin"][0] - conv["spin"][-1]), "k:", label="1/n")
    ax.set_xlabel("elements per side")
    ax.set_ylabel("|F - F_extrapolated| / (mu P)")
    ax.set_title("Grid convergence of the steady half-space solver")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def table(head: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    out = Path(argv[0] if argv else "docs/validation.md")
    figdir = Path(argv[1] if len(argv) > 1 else out.parent / "figures")
    figdir.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    head5 = ["quantity", "grid", "value", "reference", "error"]
    kal64, worst64 = kalker_rows(64)
    kal128, worst128 = kalker_rows(128)
    conv = convergence()
    fig = figdir / "validation_convergence.png"
    plot(conv, fig)
    conv_rows = []
    for key in ("creep", "spin"):
        F = conv[key]
        rich = [2 * F[i + 1] - F[i] for i in range(len(F) - 1)]
        conv_rows.append([key, *(f"{v:.5f}" for v in F), *(f"{v:.5f}" for v in rich)])
    text = f"""# Validation of the half-space and thin-layer solvers

Generated by `{COMMAND}` (this page and `figures/{fig.name}`); the tests
(`tests/test_halfspace_*.py`) assert the same comparisons with tolerances justified by
the errors below. Errors are relative to the reference unless a unit is given.

## Hertz (Johnson 1985, Sec. 4.2): the numerical normal problem

Polonsky-Keer conjugate gradients (`normal.solve_normal`) on the railway contact
(wheel R 0.46 m on rail head R 0.3 m, steel, 100 kN), the grid spanning 1.25 times
the Hertz ellipse; the load is exact by construction.

{table(head5, hertz_rows())}

## Carter (1926): 2-D rolling, `LineContact`

Steel cylinders, R = 0.1 m, N = 1 MN/m, mu = 0.3; force in mu N. First order in the
element size.

{table(head5, carter_rows())}

## Kalker's creep coefficients over a/b and nu (Kalker 1990, Table E3)

`HalfSpaceContact.creep_coefficients()` (full-adhesion solves) on grids of square
elements, about 64 x 64 and 128 x 128 in all; cells: value (Kalker) error. C33 is
listed without a reference (Table E3 as stored here has C11, C22, C23 only).
Worst error: {100 * worst64:.2f} % on 64 x 64, {100 * worst128:.2f} % on 128 x 128.

{table(["a/b", "nu", "grid", "C11", "C22", "C23", "C33"], kal64 + kal128)}

## Transient rolling (Kalker 1970) and Cattaneo-Mindlin (Johnson 1985, Eq. 7.42)

`HalfSpaceField`: the static shift at a given tangential force (two equal spheres,
a = 1 mm) and rolling from rest at constant creepage (railway, xi = 0.1, eta = 0.05
mu P/(G c^2)).

{table(head5, transient_rows())}

## The layer limit (Eqs. 40-43, corrected: `contact_fmu.laws.thin_layer.LayerContact`)

Half-spaces 1e4 times stiffer than the layers (G = 1e4 a1/(kb + ks)), the thin-layer
example's parabolic pressure; force in mu P.

{table(head5, layer_rows())}

## Grid convergence: one creepage case and one spin case

Creepage: the railway wheel, xi = 0.3 mu P/(G c^2), Tx/(mu P). Spin: ellipse 7 x 3.5 mm
(a/b = 2), steel, 50 kN, mu = 0.3, eta = -6e-4, phi = 0.6 rad/m, Ty/(mu P). Both on
n x n elements (dx = 2 a1/(n - 2), dy = 2 a2/n). Richardson: 2 F(2n) - F(n) (first
order).

{table(["case", *(f"{n}" for n in GRIDS), *(f"R({n}, {2 * n})" for n in GRIDS[:-1])], conv_rows)}

![convergence](figures/{fig.name})

Generated in {time.perf_counter() - t0:.0f} s.
"""
    out.write_text(text)
    print(out, fig)
    return 0


if __name__ == "__main__":
    sys.exit(main())
