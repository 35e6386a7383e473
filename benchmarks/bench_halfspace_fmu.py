"""The half-space law in the FMU: the shipped table's error and the FMU's step cost.

    .venv/bin/python benchmarks/bench_halfspace_fmu.py [--points 200] [--steps 200]
        [--repeats 5] [--json out.json] [--spec-override KEY=VALUE ...] [--write]

1. Interpolation error of the creep-force table that the rail scenes' FMUs ship
   (scenarios/rail_creep.toml [halfspace]; the same table as rail_traction's), against
   direct solves on the table's own solver grid (HalfSpaceContact, the same
   declaration): at ``--points`` random points of the creepage plane the scenes use
   (|xi|, |eta| <= 0.98 of the box, no spin), and at the midpoints of the table's cells
   along the paths of the scenes (the xi sweeps at eta = 0 and eta = 0.002/(the table's
   xi_ref)), where cubic interpolation errs most. The table is read from the built FMU.
2. Step cost: the body-mode scene rail_traction's FMU and a thin-layer twin (the same
   scene with contact_law = "layer": k1 + k2 giving the Hertz a1 at 100 kN, Ry the
   rail head radius, kb + ks giving the table's onset of full slip), run alternately in
   one process through fmpy's FMU2Slave call by call (setReal, doStep, getReal), the
   fastest of ``--repeats`` runs per step; likewise the contact-mode scene rail_creep and
   its twin; and the two laws' scalar calls and RollingBody steps without FMI. Ratios
   are within one run on one machine.

--write replaces the block "bench_halfspace_fmu.py" of docs/halfspace.md (the table's
error) and "bench_halfspace_fmu.py step" of docs/performance.md (the step cost).

OPENBLAS_NUM_THREADS=1 is set before numpy is imported (the table's direct solves:
threaded BLAS slows GMRES down tenfold on the shared machine).
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import datetime  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402
import zipfile  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

import fmu_build  # noqa: E402
from contact_fmu.fmu.config import GENERATED_DATA, ModelConfig  # noqa: E402
from contact_fmu.halfspace.spec import TableSpec  # noqa: E402
from contact_fmu.scenario import load, runner  # noqa: E402
from contact_fmu.scenario.instance import OK, Instance  # noqa: E402

if __package__:  # python -m benchmarks
    from . import harness
else:  # run as a script: benchmarks/ is first on sys.path
    import harness  # type: ignore[no-redef]

ROOT, OUT = harness.ROOT, harness.OUT
SCENES = ROOT / "scenarios"


def shipped_table(built: fmu_build.Built, spec: TableSpec, dest: Path):
    """The TableLaw read from the FMU's own resources."""
    rel = f"resources/{built.package}/{GENERATED_DATA['halfspace']}"
    with zipfile.ZipFile(built.path) as z:
        dest.write_bytes(z.read(rel))
    return spec.load_law(dest)


def table_error(spec: TableSpec, law, points: int, seed: int = 1) -> dict:
    """Error of the table against direct solves (fractions of mu P, mu P c)."""
    contact = spec.contact()
    muP, c = contact.mu * contact.P, contact.c
    X = law.data.extent
    xr = law.xi_ref

    def err(x1: float, x2: float) -> list[float]:
        s = contact.solve(x1 * xr, x2 * xr, 0.0)
        Tx, Ty, Mz = law.forces(x1 * xr, x2 * xr, 0.0, 1.0)
        a = law.adhesion_fraction(x1 * xr, x2 * xr, 1.0)
        return [abs(Tx - s.Tx) / muP, abs(Ty - s.Ty) / muP, abs(Mz - s.Mz) / (muP * c),
                abs(a - s.adhesion_fraction)]  # fmt: skip

    rng = np.random.default_rng(seed)
    t0 = time.perf_counter()
    rand = np.array([err(*x) for x in rng.uniform(-0.98, 0.98, (points, 2)) * X[:2]])
    solve_s = (time.perf_counter() - t0) / points
    a1 = law.data.axes[0]
    mids = 0.5 * (a1[:-1] + a1[1:])
    mids = mids[np.abs(mids) <= 0.98 * X[0]]
    lines = {}
    for label, eta in (("eta = 0", 0.0), ("eta = 0.002", 0.002 / xr)):
        e = np.array([err(m, eta) for m in mids])
        lines[label] = {"max": e.max(axis=0).tolist(), "worst_x1": float(mids[np.argmax(e[:, 0])])}
    return {
        "random_points": points,
        "random_max": rand.max(axis=0).tolist(),
        "random_rms": np.sqrt((rand**2).mean(axis=0)).tolist(),
        "midpoints": len(mids),
        "lines": lines,
        "direct_solve_ms": solve_s * 1e3,
    }


def layer_twin(scene_cfg: ModelConfig, spec: TableSpec, law) -> dict[str, float]:
    """Thin-layer parameters of the same contact: a1 at the first load node from k1 + k2
    (a1^2 = 2 Rx delta with delta from Eq. 33), Ry the substrate's lateral radius, and
    kb + ks scaled so that the thin-layer onset of full slip is the table's."""
    from contact_fmu.laws.thin_layer import LayerContact

    P, Rx, Ry, mu = spec.loads[0], spec.Rx, spec.substrate.Ry, spec.mu
    k12 = 5e-13
    base = LayerContact(P, Rx, Ry, k12 / 2, k12 / 2, 1e-13, 1e-13, mu)
    # a1 ~ k^(1/4) for the paraboloid layer contact (Eq. 34 with Eq. 33)
    k12 *= (law.a1 / base.a1) ** 4
    base = LayerContact(P, Rx, Ry, k12 / 2, k12 / 2, 1e-13, 1e-13, mu)
    kbs = 2e-13 * law.creep_full_slip / base.creep_full_slip  # onset ~ kb + ks
    twin = LayerContact(P, Rx, Ry, k12 / 2, k12 / 2, kbs / 2, kbs / 2, mu)
    out = {"Ry": Ry, "k1": twin.k1, "k2": twin.k2, "kb": twin.kb, "ks": twin.ks,
           "a1": twin.a1, "onset": twin.creep_full_slip}  # fmt: skip
    return {k: float(v) for k, v in out.items()}


def twin_config(cfg: ModelConfig, params: dict[str, float]) -> ModelConfig:
    d = cfg.to_dict()
    d.update(name=f"{cfg.name}_layer", contact_law="layer", law_spec={})
    d["starts"] = {**cfg.starts, **{k: params[k] for k in ("Ry", "k1", "k2", "kb", "ks")}}
    d["description"] = f"{cfg.description} (thin-layer twin for the benchmark)"
    return ModelConfig.from_dict(d)


def time_fmus(
    paths: dict[str, Path], starts: dict[str, dict], scene, case, n: int, repeats: int
) -> tuple[dict[str, float], dict[str, dict]]:
    """Seconds per communication step of each FMU (fastest of the repeats per step,
    averaged over the steps; the FMUs alternate run by run), and the last outputs."""
    table = runner.input_table(scene, case)
    n = min(n, scene.n_steps)
    times = {k: np.full((repeats, n), np.inf) for k in paths}
    last = {}
    for r in range(repeats):
        for key, path in paths.items():
            with Instance(path, f"{key}{r}", starts[key]) as inst:
                refs = [inst.vars[k].valueReference for k in scene.inputs]
                outs = [inst.vars[k].valueReference for k in scene.outputs if k != "regime"]
                fmu = inst.fmu
                for k in range(n):
                    t0 = time.perf_counter()
                    fmu.setReal(refs, [float(table[i][k]) for i in scene.inputs])
                    if inst.step(scene.step) != OK:
                        raise RuntimeError(f"{path.name}: {inst.messages[-1:]}")
                    fmu.getReal(outs)
                    times[key][r, k] = time.perf_counter() - t0
                last[key] = {k: inst.get(k) for k in scene.outputs}
    return {k: float(np.mean(np.min(v, axis=0))) for k, v in times.items()}, last


def law_calls(law, twin, reps: int = 3000) -> dict[str, float]:
    """Microseconds per scalar call of forces and tx_slope (partial slip, no spin)."""
    v = (0.5 * law.creep_full_slip * 30.0, 0.0, 0.0, 30.0)
    out = {}
    for name, lw in (("table", law), ("layer", twin)):
        for what, fn in (("forces", lambda lw=lw: lw.forces(*v)),
                         ("tx_slope", lambda lw=lw: lw.tx_slope(v[0], v[1], v[3]))):  # fmt: skip
            best = np.inf
            for _ in range(5):
                t0 = time.perf_counter()
                for _ in range(reps):
                    fn()
                best = min(best, (time.perf_counter() - t0) / reps)
            out[f"{name}_{what}_us"] = best * 1e6
    return out


def _g(x: float) -> str:
    """Two significant digits, as the docs' tables print them."""
    return f"{x:.2g}"


def error_block(report: dict, command: str) -> str:
    """The block of docs/halfspace.md: the shipped table's error against direct solves."""
    e, tab = report["error"], report["table"]
    n = e["random_points"]
    eta_label = f"eta = {0.002 / report['xi_ref']:.2f} xi_ref"
    pct = [100.0, 100.0, 100.0, 1.0]  # Tx, Ty, Mz in %; the adhesion fraction as it is
    rows = [
        (f"{n} random, max", e["random_max"]),
        (f"{n} random, rms", e["random_rms"]),
        ("cell midpoints, eta = 0, max", e["lines"]["eta = 0"]["max"]),
        (f"cell midpoints, {eta_label}, max", e["lines"]["eta = 0.002"]["max"]),
    ]
    lines = [
        harness.made_by(command),
        "",
        f"The table: {tab['solves']} solves, {tab['bytes'] / 1024:.0f} KiB.",
        "",
        "| points | Tx (% of mu P) | Ty (% of mu P) | Mz (% of mu P c) | adhesion fraction |",
        "|---|---|---|---|---|",
    ]
    for label, values in rows:
        cells = " | ".join(_g(v * s) for v, s in zip(values, pct, strict=True))
        lines.append(f"| {label} | {cells} |")
    return "\n".join(lines)


def step_block(report: dict, command: str) -> str:
    """The block of docs/performance.md: the half-space FMUs' step cost against their
    thin-layer twins."""
    steps, body, calls = report["fmu_step"], report["rolling_body_step"], report["law_calls"]
    tr, cr = steps["rail_traction"], steps["rail_creep"]
    dTx = abs(tr["Tx_last"]["halfspace"] - tr["Tx_last"]["layer"])

    def row(label: str, table: float, layer: float) -> str:
        return f"| {label} | {_g(table)} | {_g(layer)} | {_g(table / layer)} |"

    return "\n".join([
        harness.made_by(command),
        "",
        "The rail scenes' half-space FMUs against thin-layer twins of the same scenes (k1 +"
        " k2 giving the Hertz a1, kb + ks the table's onset of full slip), run alternately in"
        " one process through fmpy's FMU2Slave, fastest of the repeats per step; both laws"
        f" evaluated by the compiled stepper in body mode. The body FMUs end within {dTx:.2g} N"
        " of each other in Tx.",
        "",
        "| | half-space (table) | thin layer | ratio |",
        "|---|---|---|---|",
        row("body FMU (rail_traction), ms per communication step (5 internal steps)",
            tr["step_ms"]["halfspace"], tr["step_ms"]["layer"]),
        row("contact FMU (rail_creep), ms per step", cr["step_ms"]["halfspace"],
            cr["step_ms"]["layer"]),
        row("RollingBody without FMI (compiled stages), ms per communication step",
            body["table_ms"], body["layer_ms"]),
        row("Python law call `forces`, us", calls["table_forces_us"], calls["layer_forces_us"]),
        row("Python law call `tx_slope` (the Newton slope), us", calls["table_tx_slope_us"],
            calls["layer_tx_slope_us"]),
        "",
        f"A direct solve on the table's grid costs {_g(report['error']['direct_solve_ms'])} ms"
        " in the same run: a table call is over a thousand times cheaper than solving in the"
        " step.",
    ])  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    ap = harness.parser(__doc__)
    ap.add_argument("--points", type=int, default=200, help="random points of the plane")
    ap.add_argument("--steps", type=int, default=200, help="communication steps timed")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--json", type=str, default=None)
    ap.add_argument("--no-timing", action="store_true", help="only the table's error")
    ap.add_argument("--spec-override", nargs="*", default=[], metavar="KEY=JSON",
                    help="measure a variant of the declaration (e.g. stretch=3.0)")  # fmt: skip
    args = ap.parse_args(argv)

    creep, traction = load(SCENES / "rail_creep.toml"), load(SCENES / "rail_traction.toml")
    cfg = creep.config
    if args.spec_override:
        d = dict(cfg.law_spec)
        for item in args.spec_override:
            k, v = item.split("=", 1)
            d[k] = json.loads(v)
        cfg = ModelConfig.from_dict({**cfg.to_dict(), "law_spec": d})
    spec = cfg.table_spec
    t0 = time.perf_counter()
    built = fmu_build.build(cfg, OUT)
    build_s = time.perf_counter() - t0
    tmp = OUT / f".bench-table-{built.key[:12]}.npz"
    law = shipped_table(built, spec, tmp)
    tmp.unlink()
    meta = json.loads(law.data.meta)
    report = {
        "date": datetime.date.today().isoformat(),
        "machine": f"{platform.machine()}, Python {platform.python_version()}",
        "spec": spec.to_dict(),
        "table": {
            "solves": meta["solves"],
            "build_s": meta["seconds"],
            "fmu_build_s (incl. table unless cached)": build_s,
            "bytes": os.path.getsize(fmu_build.tables.ensure(cfg)),
        },  # fmt: skip
        "xi_ref": law.xi_ref,
        "onset": law.creep_full_slip,
        "error": table_error(spec, law, args.points),
    }
    if not args.no_timing:
        from contact_fmu.dynamics.body import Body, Loads
        from contact_fmu.dynamics.integrator import RollingBody
        from contact_fmu.laws.thin_layer import LayerContact

        params = layer_twin(cfg, spec, law)
        report["layer_twin"] = params
        twin = LayerContact(spec.loads[0], spec.Rx, params["Ry"], params["k1"], params["k2"],
                            params["kb"], params["ks"], spec.mu)  # fmt: skip
        report["law_calls"] = law_calls(law, twin)
        steps = {}
        for scene in (traction, creep):
            twin_cfg = twin_config(scene.config, params)
            paths = {"halfspace": fmu_build.build(scene.config, OUT).path,
                     "layer": fmu_build.build(twin_cfg, OUT).path}  # fmt: skip
            case = scene.cases[0]
            own = runner.start_values(scene, case)
            twin_starts = {**own, **{k: params[k] for k in ("Ry", "k1", "k2", "kb", "ks")}}
            starts = {"halfspace": own, "layer": twin_starts}
            per_step, last = time_fmus(paths, starts, scene, case, args.steps, args.repeats)
            steps[scene.name] = {"step_ms": {k: v * 1e3 for k, v in per_step.items()},
                                 "ratio": per_step["halfspace"] / per_step["layer"],
                                 "Tx_last": {k: v["Tx"] for k, v in last.items()}}  # fmt: skip
        report["fmu_step"] = steps
        # RollingBody steps without FMI: the scene's first case, 5 internal steps of 1 ms
        case = traction.cases[0]
        p = case.parameters
        body = Body(p["M"], p["Rx"], p["Iy"])
        My = float(np.max(case.inputs["My_ex"](traction.grid)))
        model = {}
        for name, lw in (("table", law), ("layer", twin)):
            best = np.inf
            for _ in range(args.repeats):
                rb = RollingBody(lw, body, Vx0=p["Vx0"], Omega_y0=p["Vx0"] / p["Rx"])  # vx0 = 0
                t0 = time.perf_counter()
                for _ in range(args.steps):
                    rb.advance(traction.step, Loads(My_ex=My), 5)
                best = min(best, (time.perf_counter() - t0) / args.steps)
            model[f"{name}_ms"] = best * 1e3
        model["ratio"] = model["table_ms"] / model["layer_ms"]
        report["rolling_body_step"] = model
    print(json.dumps(report, indent=1))
    if args.json:
        Path(args.json).write_text(json.dumps(report, indent=1))
    if args.write:
        if args.spec_override or args.no_timing:
            ap.error("--write measures the shipped table with timing: no --spec-override, "
                     "--no-timing")  # fmt: skip
        command = (f"benchmarks/bench_halfspace_fmu.py --points {args.points} --steps "
                   f"{args.steps} --repeats {args.repeats} --write")  # fmt: skip
        harness.write_block(harness.DOCS / "halfspace.md", "bench_halfspace_fmu.py",
                            error_block(report, command))  # fmt: skip
        harness.write_block(harness.PERFORMANCE, "bench_halfspace_fmu.py step",
                            step_block(report, command))  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
