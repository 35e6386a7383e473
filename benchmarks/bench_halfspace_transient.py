"""Kalker's transient rolling on the half-space: cost per step and measured durations.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_halfspace_transient.py \
        [--grids 16 24 32] [--skip-coupled] [--json out.json] [--write]

Prints markdown tables (docs/halfspace.md, "Transient rolling"; the first is its block):

1. cost: steps of one element at constant creepage (the field alone) and the body on
   the field (railway wheel, Fx_ex with My_ex = -Fx_ex Rx), per grid: ms per step,
   Newton / GMRES iterations per step, seconds per contact length rolled;
2. durations under a sudden creepage (Kalker's 1970 problem, prescribed kinematics):
   contact lengths rolled until Tx stays within 1 % of the steady value, for the
   railway half-space, the layered half-space and the thin-layer model at the same
   force fractions;
3. the ripple of Tx as the lattice moves past the contact edges (steps that are not
   whole elements), per grid;
4. the coupled transient of the railway wheel from rest under a sudden Fx_ex (with
   --skip-coupled left out).

--write replaces the block "bench_halfspace_transient.py" of docs/halfspace.md (the cost
table, 1.) with this run's.

Threaded BLAS is switched off before numpy is imported (see bench_halfspace.py).
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

from contact_fmu import examples as ex  # noqa: E402
from contact_fmu.dynamics.body import Body, Loads  # noqa: E402
from contact_fmu.dynamics.thin_layer_field import LayerField  # noqa: E402
from contact_fmu.halfspace.railway import wheel_on_rail  # noqa: E402
from contact_fmu.halfspace.rolling import solve_rolling  # noqa: E402
from contact_fmu.halfspace.transient import HalfSpaceField, TransientHalfSpaceBody  # noqa: E402

if __package__:  # python -m benchmarks
    from . import harness
else:  # run as a script: benchmarks/ is first on sys.path
    import harness  # type: ignore[no-redef]

V_RAIL = 30.0  # m/s
# creepages of the duration table in units of mu P/(G c^2) (railway: Tx = 0.10, 0.41,
# 0.70, 0.86 mu P) and the steady-to-steady changes
LEVELS = (0.02, 0.1, 0.2, 0.3)
CHANGES = ((0.1, 0.2), (0.2, 0.1))
LENGTHS = 8  # contact lengths rolled per duration run


def settled(values: np.ndarray, ref: float, frac: float = 0.01) -> int:
    """Index after which |values - ref| <= frac |ref| for good."""
    bad = np.nonzero(np.abs(values - ref) > frac * abs(ref))[0]
    return int(bad[-1]) + 1 if bad.size else 0


def xref(c) -> float:
    return c.mu * c.P / (c.elastic.G * c.c**2)


def cost(n: int) -> dict:
    """ms per step of the field alone and of the body, iterations per step."""
    c = wheel_on_rail(n=n)
    x = xref(c)
    f = HalfSpaceField(c, n)
    cells = n - 2
    for _ in range(cells):  # past the start
        f.roll(f.dx / V_RAIL, 0.1 * x * V_RAIL, 0.0, V_RAIL)
    t0, newton, gm = time.perf_counter(), 0, 0
    for _ in range(cells):
        r = f.roll(f.dx / V_RAIL, 0.1 * x * V_RAIL, 0.0, V_RAIL)
        newton += r.solution.newton_iterations
        gm += r.solution.gmres_iterations
    field_ms = (time.perf_counter() - t0) / cells * 1e3
    wheel = Body.from_eta(600.0, 0.46, 2.0)
    b = TransientHalfSpaceBody(c, wheel, Vx0=V_RAIL, Omega_y0=V_RAIL / 0.46, n=n)
    Fx = 0.4 * c.mu * c.P
    L = Loads(Fx_ex=Fx, My_ex=-Fx * 0.46)
    b.advance(cells * b.cell_time(), L, cells)
    t0, counts = time.perf_counter(), np.zeros(3)
    for _ in range(cells):
        b.advance(b.cell_time(), L)
        counts += b.counts
    body_ms = (time.perf_counter() - t0) / cells * 1e3
    return {
        "n": n,
        "elements_in_contact": int(f.in_contact.sum()),
        "field_ms": field_ms,
        "field_newton": newton / cells,
        "field_gmres": gm / cells,
        "body_ms": body_ms,
        "body_evaluations": counts[0] / cells,
        "body_newton": counts[1] / cells,
        "body_gmres": counts[2] / cells,
        "cells_per_length": cells,
    }


def durations_halfspace(c, n: int, label: str) -> list[dict]:
    """Kalker's problem on the half-space contact c: settling distance of Tx."""
    x = xref(c)
    out = []
    cells = n - 2
    cases = [(0.0, q) for q in LEVELS] + list(CHANGES)
    for q0, q in cases:
        f = HalfSpaceField(c, n)
        st = solve_rolling(f.steady_patch(), q * x, 0.0, 0.0)
        if q0:
            f.set_steady(q0 * x, 0.0, 0.0)
        Tx = []
        for _ in range(LENGTHS * cells):
            Tx.append(f.roll(f.dx / V_RAIL, q * x * V_RAIL, 0.0, V_RAIL).Tx)
        Tx = np.array(Tx)
        one = Tx[cells - 1] / st.Tx
        out.append(
            {
                "model": label,
                "n": n,
                "from": q0,
                "to": q,
                "T_over_muP": st.Tx / (c.mu * c.P),
                "s1": settled(Tx, st.Tx) / cells,
                "T_after_one_length": one,
            }
        )
    return out


def durations_layer(fractions: list[tuple[float, float]], nx: int = 64) -> list[dict]:
    """The thin-layer field (example contact) at the same force fractions: creepages
    from the closed form's inverse."""
    C = ex.contact()
    V = ex.speed_unit()
    out = []
    for f0, f1 in fractions:
        v1 = C.inverse_creep(f1 * C.mu * C.P) * V
        lf = LayerField(C, nx, 32)
        if f0:
            v0 = C.inverse_creep(f0 * C.mu * C.P) * V
            for _ in range(nx + 2):
                lf.roll(lf.dx / V, v0, 0.0, V)
        Tref = float(C.force(v1, 0.0, V)[0])
        Tx = []
        for _ in range(LENGTHS * nx // 4):
            lf.roll(lf.dx / V, v1, 0.0, V)
            Tx.append(lf.resultant()[0])
        out.append(
            {
                "model": "thin layer (64 cells)",
                "from": f0,
                "to": f1,
                "s1": settled(np.array(Tx), Tref) / nx,
            }
        )
    return out


def ripple(n: int) -> dict:
    """Tx over the last contact length of steps of 0.9 element at constant creepage,
    started on the steady field: (max - min)/mean."""
    c = wheel_on_rail(n=n)
    x = xref(c)
    f = HalfSpaceField(c, n)
    f.set_steady(0.1 * x, 0.0, 0.0)
    cells = n - 2
    Tx = [f.roll(0.9 * f.dx / V_RAIL, 0.1 * x * V_RAIL, 0.0, V_RAIL).Tx for _ in range(4 * cells)]
    last = np.array(Tx[-cells:])
    return {"n": n, "ripple": float((last.max() - last.min()) / last.mean())}


def coupled(n: int, lengths: int) -> list[dict]:
    """The railway wheel (M = 600 kg) from rest under Fx_ex = 0.4 mu P with
    My_ex = -Fx_ex Rx (Vx constant, Eq. 26 demands Tx = Fx_ex): settling distance
    (``lengths`` if it has not settled), period and e-folding length of the oscillation
    of Tx (from its successive extrema)."""
    c = wheel_on_rail(n=n)
    out = []
    cells = n - 2
    for V, eta in ((10.0, 2.0), (10.0, 24.0), (30.0, 2.0)):
        body = Body.from_eta(600.0, 0.46, eta)
        b = TransientHalfSpaceBody(c, body, Vx0=V, Omega_y0=V / 0.46, n=n)
        Fx = 0.4 * c.mu * c.P
        L = Loads(Fx_ex=Fx, My_ex=-Fx * 0.46)
        Tx = []
        t0 = time.perf_counter()
        for _ in range(lengths * cells):
            b.advance(b.cell_time(), L)
            Tx.append(b.out.Tx)
        omega = math.sqrt(b.stiffness / body.m_slip)
        dev = np.array(Tx) / Fx - 1.0
        ext = [i for i in range(1, dev.size - 1) if abs(dev[i]) >= abs(dev[i - 1])
               and abs(dev[i]) >= abs(dev[i + 1]) and abs(dev[i]) > 1e-3]  # fmt: skip
        ext = ext[1:]  # skip the first swing (the start)
        period = efold = math.nan
        if len(ext) >= 3:
            period = 2.0 * float(np.mean(np.diff(ext))) / cells
            amp = np.log(np.abs(dev[ext]))
            efold = -1.0 / float(np.polyfit(np.array(ext) / cells, amp, 1)[0])
        out.append(
            {
                "V": V,
                "eta": eta,
                "Omega": omega * 2 * c.a1 / V,
                "s1": settled(np.array(Tx), Fx) / cells,
                "period": period,
                "efold": efold,
                "seconds": time.perf_counter() - t0,
            }
        )
    return out


def main(argv: list[str] | None = None) -> None:
    ap = harness.parser(__doc__)
    ap.add_argument("--grids", type=int, nargs="+", default=[16, 24, 32])
    ap.add_argument("--skip-coupled", action="store_true")
    ap.add_argument("--only-coupled", action="store_true")
    ap.add_argument("--coupled-lengths", type=int, default=30)
    ap.add_argument("--json", default=None)
    a = ap.parse_args(argv)
    res: dict = {"machine": platform.platform()}
    if a.only_coupled:
        res["coupled"] = coupled(16, a.coupled_lengths)
        _print_coupled(res["coupled"])
        return
    res["cost"] = [cost(n) for n in a.grids]
    table = [
        "| grid | elements in contact | field: ms per step | Newton / GMRES per step "
        "| body: ms per step | evaluations / Newton / GMRES per step "
        "| body: s per contact length |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in res["cost"]:
        table.append(
            f"| {r['n']} x {r['n']} | {r['elements_in_contact']} | {r['field_ms']:.1f} | "
            f"{r['field_newton']:.1f} / {r['field_gmres']:.0f} | {r['body_ms']:.1f} | "
            f"{r['body_evaluations']:.1f} / {r['body_newton']:.1f} / {r['body_gmres']:.0f} | "
            f"{r['body_ms'] * r['cells_per_length'] / 1e3:.2f} |"
        )
    print("\n".join(table), flush=True)
    if a.write:
        grids = " ".join(map(str, a.grids))
        command = f"benchmarks/bench_halfspace_transient.py --grids {grids} --skip-coupled --write"
        harness.write_block(
            harness.DOCS / "halfspace.md", "bench_halfspace_transient.py",
            "\n".join([harness.made_by(command), "", *table]),
        )  # fmt: skip
    rail = wheel_on_rail(n=24)
    layered = replace(rail, kb=1.0 / (rail.elastic.G / (2 * rail.a1)))  # k ~ A's scale
    dur = durations_halfspace(rail, 24, "half-space (railway)")
    dur += durations_halfspace(replace(layered, n=24), 24, "half-space + layer")
    fr = [(0.0, d["T_over_muP"]) for d in dur[: len(LEVELS)]]
    fr += [
        (dur[LEVELS.index(q0)]["T_over_muP"], dur[LEVELS.index(q)]["T_over_muP"])
        for q0, q in CHANGES
    ]
    lay = durations_layer(fr)
    res["durations"] = dur + lay
    print()
    print(
        "| model | from | to | Tx/(mu P) | s_1% (contact lengths) | Tx/Tx_steady after 1 length |"
    )
    print("|---|---|---|---|---|---|")
    for d in dur:
        print(
            f"| {d['model']} | {d['from']} | {d['to']} | {d['T_over_muP']:.3f} | {d['s1']:.2f} | "
            f"{d['T_after_one_length']:.3f} |"
        )
    for d in lay:
        print(
            f"| {d['model']} | {d['from']:.3f} | {d['to']:.3f} | {d['to']:.3f} | {d['s1']:.2f} | |"
        )
    res["ripple"] = [ripple(n) for n in a.grids]
    print()
    print("| grid | ripple of Tx, (max - min)/mean |")
    print("|---|---|")
    for r in res["ripple"]:
        print(f"| {r['n']} x {r['n']} | {r['ripple']:.2e} |")
    if not a.skip_coupled:
        res["coupled"] = coupled(16, a.coupled_lengths)
        print()
        print("| V (m/s) | eta | Omega | s_1% (contact lengths) | run (s) |")
        print("|---|---|---|---|---|")
        for r in res["coupled"]:
            print(
                f"| {r['V']} | {r['eta']} | {r['Omega']:.2f} | {r['s1']:.2f} | {r['seconds']:.0f} |"
            )
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(res, fh, indent=1)


def _print_coupled(rows: list[dict]) -> None:
    print()
    print("| V (m/s) | eta | Omega | s_1% (contact lengths) | period | e-folding | run (s) |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        print(
            f"| {r['V']} | {r['eta']} | {r['Omega']:.2f} | {r['s1']:.2f} | {r['period']:.2f} | "
            f"{r['efold']:.2f} | {r['seconds']:.0f} |"
        )


if __name__ == "__main__":
    main()
